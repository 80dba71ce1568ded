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
# The bag readers of the recorder tests (Foxglove's mcap + mcap-ros2-support, rosbags).
if ! .venv-dds/bin/python -c 'import mcap, mcap_ros2.decoder, rosbags.highlevel' 2>/dev/null; then
  .venv-dds/bin/pip install -q --disable-pip-version-check mcap mcap-ros2-support rosbags
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
# Every program the end-to-end tests start (fcc-sitl, fcc-bridge, fcc-fake-mcu, fcc-mission,
# fcc-launch, fcc-wire-fault, fcc-report, the recorder's mission driver), built before the tests.
run cargo build --offline --locked --release --workspace --bins --examples
run cargo build --offline --locked --release -p fcc_mission --features ros --bin fcc-mission --bin fcc-launch
# Unit tests beside the code, the scenario tests in tests/ (optimised: whole flights), the DDS
# peer and recorder tests.
run cargo test --offline --locked --workspace --release
# The full stack (fcc-sitl --link-pty ⇄ fcc-bridge ⇄ fcc-mission, started by fcc-launch) against
# the independent Cyclone DDS peer; the script puts everything in ONE loopback-only namespace.
tests/e2e/run_stack.sh "$FCC_DDS_PYTHON"
# Robustness through the real pty + bridge (issue 6): bad configuration, a noisy wire under the
# square mission, the mission node killed mid-leg, the bridge and the serial device lost and back.
tests/e2e/robust_stack.sh "$FCC_DDS_PYTHON"
