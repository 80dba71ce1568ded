#!/usr/bin/env bash
# A recording cut by SIGKILL, recovered (issue 14, crash-safe bags for every reader):
#   fake MCU → fcc-bridge --record k.mcap; kill -9 the bridge after ~6 s;
#   fcc-bag-recover k.mcap -o k.recovered.mcap --killed-at-ns T (prints messages kept, loss);
#   check_recovered.py: Foxglove's mcap reader (summary, iter_messages, mcap_ros2 decoding) and
#   rosbags' AnyReader open the recovered bag, same counts; loss ≤ 1 s (printed).
# Runs in a loopback-only network namespace (the bridge starts DDS).
#   usage: tests/mcap/sigkill_recover.sh [PYTHON]   (PYTHON with mcap, mcap-ros2-support, rosbags)
# Needs: cargo build --release -p fcc_bridge.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
. "$root/tests/lib/fake_mcu.sh"
start_fake_mcu 30
"$bin/fcc-bridge" --device "$pty" --record "$tmp/k.mcap" > "$tmp/k.log" 2>&1 &
b=$!; sleep 6.3; kill -KILL $b; kill_ns=$(date +%s%N); wait $b 2>/dev/null || true
ls -l "$tmp/k.mcap" | awk '{print "killed bag: " $5 " B"}'
rc=0
"$bin/fcc-bag-recover" "$tmp/k.mcap" -o "$tmp/k.recovered.mcap" --killed-at-ns "$kill_ns" || rc=1
"$py" "$here/check_recovered.py" "$tmp/k.recovered.mcap" --kill-ns "$kill_ns" --raw "$tmp/k.mcap" || rc=1
# The input is left as it was; a second recovery of the recovered bag says it was complete.
"$bin/fcc-bag-recover" "$tmp/k.recovered.mcap" -o "$tmp/k2.mcap" > "$tmp/k2.out" || rc=1
grep -q 'the input was complete' "$tmp/k2.out" \
  && echo "PASS recovering a complete bag keeps it whole" || { echo "FAIL second recovery"; rc=1; }
exit $rc
