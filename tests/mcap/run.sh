#!/usr/bin/env bash
# Recorder tests with the fake MCU, in ONE loopback-only network namespace:
#  1. a bag from a clean SIGINT stop: independent readers decode every message; counts == the
#     bridge's own (0 lost); fcc-replay --decode-raw re-decodes the raw frames; fcc-replay
#     republishes the bag at rate 4 under /replay: it takes the bag's span / 4, and a Cyclone
#     subscriber receives the odometry equal to the bag's (replay_sub.py); at rate 1 with the
#     recorded QoS, a Cyclone subscriber that joins after /tf_static was published gets it
#     (transient local, late_tf_static.py).
#  2. SIGKILL mid-flight: the bag opens (streamed) and loses ≤ 1 s (printed).
#  3. A full disk (/dev/full): one clear error, the bridge keeps running.
#  4. Recorder options, three bridges at once (own namespaces): split by time with uncompressed
#     chunks, split by size (zstd), record only while armed (armed/disarmed twice over DDS by
#     a Cyclone publisher): every file complete and read by both readers, 0 lost across the
#     splits, one file per arm period (check_files.py).
#   usage: tests/mcap/run.sh [PYTHON]   (PYTHON with mcap, mcap-ros2-support, rosbags)
# Needs: cargo build --release -p fcc_bridge.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
fake() { # $1 = name, $2 = seconds → prints the pty
  "$bin/fcc-fake-mcu" --duration "$2" > "$tmp/$1.out" 2>/dev/null &
  for _ in $(seq 50); do grep -q '^PTY' "$tmp/$1.out" && break; sleep 0.1; done
  awk '/^PTY/{print $2}' "$tmp/$1.out"
}
rc=0
# 1. clean stop
pty=$(fake a 30)
"$bin/fcc-bridge" --device "$pty" --record "$tmp/a.mcap" > "$tmp/a.log" 2>&1 &
b=$!; sleep 8; kill -INT $b; wait $b || true
"$py" "$here/check_bag.py" "$tmp/a.mcap" --counts "$tmp/a.mcap.counts.json" --min-seconds 5 || rc=1
"$bin/fcc-replay" "$tmp/a.mcap" --decode-raw > "$tmp/raw.txt"; head -4 "$tmp/raw.txt"
grep -q "mcu→linux ImuRaw" "$tmp/raw.txt" && echo "PASS fcc-replay --decode-raw" || { echo "FAIL decode-raw"; rc=1; }
# replay at 4× under /replay: a Cyclone subscriber gets the bag's odometry unchanged, on time
"$py" "$here/replay_sub.py" "$tmp/a.mcap" /fcc/state/odom 7 --prefix /replay > "$tmp/replay_sub.out" 2>&1 &
sub=$!; sleep 1.5
if timeout 20 "$bin/fcc-replay" "$tmp/a.mcap" --rate 4 --ns-prefix /replay 2> "$tmp/replay.err"; then
  span=$("$py" -c "
from mcap.reader import make_reader
s = make_reader(open('$tmp/a.mcap','rb')).get_summary().statistics
print((s.message_end_time - s.message_start_time) / 1e9)")
  took=$(grep -o 'in [0-9.]* s' "$tmp/replay.err" | tail -1 | awk '{print $2}')
  if "$py" -c "import sys; s, t = $span / 4, $took; sys.exit(0 if s - 0.1 <= t <= s + 1.0 else 1)"; then
    echo "PASS fcc-replay --rate 4: $(tail -1 "$tmp/replay.err") (the bag spans $(awk "BEGIN{printf \"%.2f s, / 4 = %.2f\", $span, $span/4}") s)"
  else echo "FAIL fcc-replay --rate 4 took $took s for a $span s bag"; rc=1; fi
else echo "FAIL fcc-replay"; cat "$tmp/replay.err"; rc=1; fi
wait $sub || rc=1; cat "$tmp/replay_sub.out"
# replay at 1×: the recorded QoS (offered_qos_profiles) — /tf_static transient local; a Cyclone
# subscriber that joins 1 s after the replay published it still gets it (late_tf_static.py)
"$bin/fcc-replay" "$tmp/a.mcap" --ns-prefix /late 2> "$tmp/late.err" &
rp=$!
for _ in $(seq 100); do grep -q '^fcc-replay: publishing' "$tmp/late.err" && break; sleep 0.1; done
sleep 1
"$py" "$here/late_tf_static.py" "$tmp/a.mcap" 4 --prefix /late || rc=1
wait $rp || { echo "FAIL fcc-replay (late joiner run)"; rc=1; }
grep -E '/tf_static:|QoS from the bag' "$tmp/late.err" | sed 's/^/  /'
grep -q 'QoS from the bag.* 0 without a usable profile' "$tmp/late.err" \
  && grep -q '/late/tf_static: reliable, transient local, keep last 1$' "$tmp/late.err" \
  && echo "PASS fcc-replay republishes the recorded QoS" || { echo "FAIL replay QoS"; cat "$tmp/late.err"; rc=1; }
# 2. SIGKILL
pty=$(fake k 30)
"$bin/fcc-bridge" --device "$pty" --record "$tmp/k.mcap" > "$tmp/k.log" 2>&1 &
b=$!; sleep 6.3; kill -KILL $b; kill_ns=$(date +%s%N); wait $b 2>/dev/null || true
"$py" "$here/check_bag.py" "$tmp/k.mcap" --truncated --kill-ns "$kill_ns" || rc=1
# 3. disk full
pty=$(fake f 30)
"$bin/fcc-bridge" --device "$pty" --record /dev/full > "$tmp/f.log" 2>&1 &
b=$!; sleep 3
n=$(grep -c "recording to /dev/full stopped" "$tmp/f.log" || true)
if kill -0 $b 2>/dev/null && [ "$n" = 1 ]; then
  echo "PASS disk full: one error ($(grep -m1 -o 'stopped: .*' "$tmp/f.log")), bridge still running"
else echo "FAIL disk full: alive=$(kill -0 $b 2>/dev/null && echo yes || echo no), errors=$n"; tail -5 "$tmp/f.log"; rc=1; fi
kill -INT $b; wait $b || true
# 4. recorder options
pty=$(fake s 30)
"$bin/fcc-bridge" --device "$pty" --record "$tmp/s.mcap" --ros-args -r __ns:=/split_s \
  -p record_split_s:=2 -p record_compression:=none > "$tmp/s.log" 2>&1 &
bs=$!
pty=$(fake m 30)
"$bin/fcc-bridge" --device "$pty" --record "$tmp/m.mcap" --ros-args -r __ns:=/split_mb \
  -p record_split_mb:=1 > "$tmp/m.log" 2>&1 &
bm=$!
pty=$(fake r 30)
"$bin/fcc-bridge" --device "$pty" --record "$tmp/r.mcap" --ros-args -p record_on_arm:=true > "$tmp/r.log" 2>&1 &
br=$!
"$py" "$here/arm_cycle.py" 2.5 4.5 5.5 7.5 || rc=1
sleep 0.5; kill -INT $bs $bm $br; wait $bs $bm $br || true
echo "record_split_s:=2, record_compression:=none"
"$py" "$here/check_files.py" "$tmp/s.mcap.counts.json" --min-files 3 --split-s 2 --compression none || rc=1
echo "record_split_mb:=1"
"$py" "$here/check_files.py" "$tmp/m.mcap.counts.json" --min-files 2 --split-mb 1 --compression zstd || rc=1
echo "record_on_arm:=true"
"$py" "$here/check_files.py" "$tmp/r.mcap.counts.json" --on-arm --arm-periods 2 --compression zstd || rc=1
exit $rc
