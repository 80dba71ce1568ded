#!/usr/bin/env bash
# Participant churn against the bridge (issue 14), in ONE loopback-only network namespace:
# fake MCU (pty) ⇄ fcc-bridge ⇄ Cyclone DDS (churn.py): 40 cycles of 20 participants joining
# (readers and writers on the bridge's topics) and leaving; bridge RSS growth ≤ 20 MB and flat.
#   usage: tests/e2e/churn.sh [PYTHON]   (PYTHON with cyclonedds; FCC_CHURN_ARGS="--cycles 10")
# Needs: cargo build --release -p fcc_bridge.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
. "$root/tests/lib/fake_mcu.sh"
start_fake_mcu 600
${FCC_BRIDGE_ENV:-} "$bin/fcc-bridge" --device "$pty" --ros-args -r __ns:=/fcc > "$tmp/bridge.log" 2>&1 &
bridge=$!
rc=0
PYTHONPATH="$root/tests/dds" "$py" "$here/churn.py" --bridge-pid "$bridge" ${FCC_CHURN_ARGS:-} || rc=1
if [ $rc -ne 0 ]; then echo "--- bridge log (last 20 lines, cut)"; tail -20 "$tmp/bridge.log" | cut -c1-300; fi
kill -INT "$bridge" 2>/dev/null || true; wait "$bridge" 2>/dev/null || true
exit $rc
