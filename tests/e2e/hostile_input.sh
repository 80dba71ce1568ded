#!/usr/bin/env bash
# Hostile input against the bridge (issue 14), in ONE loopback-only network namespace:
# fake MCU (pty) ⇄ fcc-bridge ⇄ a Cyclone DDS peer (hostile_input.py) that sends 600 setpoints
# with a 1 MB frame_id at 10 Hz (and 1 MB mode texts), then a NaN flood: bridge RSS growth
# ≤ 20 MB, log growth under the flood ≤ 64 KB, logs / /rosout / /diagnostics bounded and escaped.
#   usage: tests/e2e/hostile_input.sh [PYTHON]   (PYTHON with cyclonedds)
# Needs: cargo build --release -p fcc_bridge. Takes ~75 s.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
. "$root/tests/lib/fake_mcu.sh"
start_fake_mcu 200
${FCC_BRIDGE_ENV:-} "$bin/fcc-bridge" --device "$pty" --ros-args -r __ns:=/fcc > "$tmp/bridge.log" 2>&1 &
bridge=$!
rc=0
PYTHONPATH="$root/tests/dds" "$py" "$here/hostile_input.py" --bridge-pid "$bridge" \
  --bridge-log "$tmp/bridge.log" ${FCC_HOSTILE_ARGS:-} || rc=1
if [ $rc -ne 0 ]; then echo "--- bridge log (last 20 lines, cut)"; tail -20 "$tmp/bridge.log" | cut -c1-300; fi
kill -INT "$bridge" 2>/dev/null || true; wait "$bridge" 2>/dev/null || true
exit $rc
