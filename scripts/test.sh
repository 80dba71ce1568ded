#!/usr/bin/env bash
# Run every test of the project. Installs what the tests need, then runs them with no network
# beyond loopback (DDS discovery must never leave the machine).
#   usage: scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."

# 1. Dependencies (needs the package registries): Rust crates, and the independent DDS peer
#    (PyPI cyclonedds, Cyclone DDS) that stands in for a ROS 2 node in the bridge tests.
cargo fetch --locked
if [ ! -x .venv-dds/bin/python ] || ! .venv-dds/bin/python -c 'import cyclonedds' 2>/dev/null; then
  python3 -m venv .venv-dds
  .venv-dds/bin/pip install -q --disable-pip-version-check cyclonedds
fi
export FCC_DDS_PYTHON="$PWD/.venv-dds/bin/python" FCC_REQUIRE_DDS_PEER=1

# 2. Everything that runs, in a private network namespace with loopback only when available.
netns=""
for c in ../shared/tools/netns-run /work/shared/tools/netns-run; do
  if [ -x "$c" ] && "$c" true 2>/dev/null; then netns=$c; break; fi
done
if [ -z "$netns" ]; then
  echo "test.sh: no network namespace available; running without one (no DDS test runs yet)" >&2
fi

run() { if [ -n "$netns" ]; then "$netns" "$@"; else "$@"; fi; }

# The MCU core must build without std (no heap, no OS).
run cargo build --offline --locked -p fcc_firmware --no-default-features
run cargo build --offline --locked -p fcc_msgs --no-default-features
# Unit tests beside the code and the scenario tests in tests/ (optimised: whole flights).
run cargo test --offline --locked --workspace --release
