#!/usr/bin/env bash
# Soak benchmark of the whole stack (issue 14 point 4): fcc-sitl --link-pty (square, then a long
# hover in HOLD) ⇄ fcc-wire-fault (light bit-error rate, 1e-6) ⇄ fcc-bridge (recording a bag)
# ⇄ fcc-mission, plus a Cyclone DDS peer; the bridge is SIGKILLed and restarted once (half-way).
# Samples every process's RSS every 5 s and prints the least-squares RSS slope after warm-up
# (20 % of the soak, ≥ 60 s) in MB/h per process (goal ≤ 1 MB/h each) and the messages lost
# outside the kill window. Exit 0 when every goal holds.
#   usage: scripts/soak.sh [MINUTES] [soak_stack.py options]   (default 30 minutes; see
#          tests/e2e/soak_stack.py: --speed, --ber, --kill-at, --warmup-s, --keep DIR,
#          --bridge-param NAME:=VALUE, e.g. record_split_s:=300)
# Needs release builds of fcc-sitl, fcc-wire-fault, fcc-bridge and fcc-mission (feature ros),
# and .venv-dds (scripts/test.sh makes both). Runs in a loopback-only network namespace.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
minutes="${1:-30}"
shift || true
py="${FCC_DDS_PYTHON:-$root/.venv-dds/bin/python}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$minutes" "$@"
bin="${FCC_BIN_DIR:-$root/target/release}"
for b in fcc-sitl fcc-wire-fault fcc-bridge fcc-mission; do
  if [ ! -x "$bin/$b" ]; then
    echo "soak.sh: $bin/$b missing: cargo build --release -p fcc_sim -p fcc_bridge -p fcc_tests --bins && cargo build --release -p fcc_mission --features ros --bin fcc-mission" >&2
    exit 2
  fi
done
PYTHONPATH="$root/tests/dds" exec "$py" "$root/tests/e2e/soak_stack.py" "$minutes" --bin "$bin" "$@"
