#!/usr/bin/env bash
# The main flight on Zenoh by one launcher argument, and its bag replayed on Zenoh (issue 18,
# scope 1), in one loopback-only namespace:
#  1. `fcc-launch launch_configs/square_flight.yaml rmw:=rmw_zenoh_cpp speed:=4 hover_s:=0
#     record:=…`: the launcher sets RMW_IMPLEMENTATION for every process and, the config starting
#     no router, starts fcc-zenoh-router first; the bridge and the mission node log that they run
#     on Zenoh, the square completes (the mission node flies it on the bridge's odometry and its
#     setpoints reach the MCU only over Zenoh: no DDS participant exists), the bag is written.
#  2. `RMW_IMPLEMENTATION=rmw_zenoh_cpp fcc-replay BAG --rate 4 --ns-prefix /replay` beside an
#     fcc-zenoh-router: the independent peer (tests/zenoh/replay_sub.py: eclipse-zenoh, the bag
#     read with Foxglove's mcap) receives /replay/fcc/state/odom byte for byte as the bag holds
#     it, on the type's REP-2016 key, with rmw_zenoh's attachment; the replay takes the bag's
#     span / 4; a TRANSIENT_LOCAL subscription to /replay/tf_static declared 4 s late (an
#     AdvancedSubscriber with history, as rmw_zenoh's) still gets the bag's /tf_static.
#   usage: tests/zenoh/launch_replay.sh [PYTHON]   (PYTHON imports zenoh, rosbags and mcap)
# Needs release builds of fcc-sitl, fcc-bridge, fcc-mission, fcc-launch, fcc-replay and
# fcc-zenoh-router (FCC_BIN_DIR). ~40 s.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
"$py" -c 'import zenoh, rosbags, mcap' || { echo "launch_replay.sh: $py cannot import zenoh, rosbags and mcap" >&2; exit 2; }
rc=0
pass() { echo "PASS $1"; }
fail() { echo "FAIL $1"; rc=1; }

echo "=== 1. the square on Zenoh: fcc-launch launch_configs/square_flight.yaml rmw:=rmw_zenoh_cpp (speed 4)"
t0=$(date +%s.%N)
set +e
timeout 180 "$bin/fcc-launch" "$root/launch_configs/square_flight.yaml" BIN:="$bin" rmw:=rmw_zenoh_cpp \
  speed:=4 hover_s:=0 out:="$tmp" record:="$tmp/square.mcap" > "$tmp/launch.log" 2>&1
lrc=$?
set -e
echo "fcc-launch exit $lrc, $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.1f", b-a}') s wall"
grep -E '^fcc-launch: (RMW_IMPLEMENTATION|the config starts no Zenoh router|starting zenoh_router)|^\[zenoh_router\] fcc-zenoh-router: listening|fcc-mission: mission complete' "$tmp/launch.log" || true
[ $lrc = 0 ] && pass "fcc-launch rmw:=rmw_zenoh_cpp: exit 0" || { fail "fcc-launch rmw:=rmw_zenoh_cpp: exit $lrc"; tail -30 "$tmp/launch.log"; }
grep -q '^fcc-launch: RMW_IMPLEMENTATION=rmw_zenoh_cpp for 3 of 3 processes' "$tmp/launch.log" \
  && grep -q '^\[zenoh_router\] fcc-zenoh-router: listening on' "$tmp/launch.log" \
  && pass "the launcher set RMW_IMPLEMENTATION for sitl, bridge, mission and started fcc-zenoh-router first" \
  || fail "the launcher's rmw lines or the router's start are missing"
# Each node's first log line names its middleware.
for n in bridge mission; do
  if grep -E "^\[$n\] .*Zenoh domain" "$tmp/launch.log" > /dev/null; then pass "$n runs on Zenoh (its start-up line)"
  else fail "$n: no start-up line naming Zenoh: $(grep -m1 "^\[$n\]" "$tmp/launch.log")"; fi
done
grep -q '^\[mission\] .*mission complete' "$tmp/launch.log" && pass "the square flown on Zenoh: mission complete" \
  || fail "the mission did not complete"
[ -s "$tmp/square.mcap" ] && pass "the bag written ($(stat -c %s "$tmp/square.mcap") bytes)" || fail "no bag"

echo "=== 2. fcc-replay on Zenoh (rate 4, under /replay) to the independent peer"
if [ -s "$tmp/square.mcap" ]; then
  "$bin/fcc-zenoh-router" > "$tmp/router.log" 2>&1 &
  for _ in $(seq 100); do (exec 3<>/dev/tcp/127.0.0.1/7447) 2>/dev/null && break; sleep 0.1; done
  span=$("$py" -c "
from mcap.reader import make_reader
import sys
s = make_reader(open(sys.argv[1], 'rb')).get_summary().statistics
print((s.message_end_time - s.message_start_time) / 1e9)" "$tmp/square.mcap")
  secs=$(awk -v s="$span" 'BEGIN{printf "%.0f", s / 4 + 8}')
  PYTHONPATH="$here${PYTHONPATH:+:$PYTHONPATH}" timeout -k 5 $((secs + 120)) "$py" "$here/replay_sub.py" "$tmp/square.mcap" /fcc/state/odom "$secs" \
    --prefix /replay --late-transient /tf_static --ready-file "$tmp/sub_ready" > "$tmp/sub.log" 2>&1 &
  sub=$!
  for _ in $(seq 200); do [ -e "$tmp/sub_ready" ] && break; sleep 0.05; done
  if RMW_IMPLEMENTATION=rmw_zenoh_cpp timeout 120 "$bin/fcc-replay" "$tmp/square.mcap" --rate 4 --ns-prefix /replay \
       2> "$tmp/replay.err"; then
    took=$(grep -o 'in [0-9.]* s' "$tmp/replay.err" | tail -1 | awk '{print $2}')
    grep -q '^fcc-replay: on Zenoh' "$tmp/replay.err" && pass "fcc-replay on Zenoh (RMW_IMPLEMENTATION=rmw_zenoh_cpp)" \
      || fail "fcc-replay did not say Zenoh: $(head -2 "$tmp/replay.err")"
    if awk -v t="$took" -v s="$span" 'BEGIN{exit !(t >= 0.9 * s / 4 && t <= 1.2 * s / 4 + 1)}'; then
      pass "fcc-replay --rate 4: $(tail -1 "$tmp/replay.err") (the bag spans $(printf '%.2f' "$span") s, / 4 = $(awk -v s="$span" 'BEGIN{printf "%.2f", s/4}') s)"
    else
      fail "fcc-replay --rate 4 took $took s for a span of $span s"
    fi
  else
    fail "fcc-replay on Zenoh failed: $(tail -3 "$tmp/replay.err")"
  fi
  set +e; wait $sub; src=$?; set -e
  cat "$tmp/sub.log"
  [ $src = 0 ] && pass "the Zenoh peer's checks of the replayed odometry" || fail "the Zenoh peer's checks (exit $src)"
fi
echo "launch_replay: $([ $rc = 0 ] && echo PASS || echo FAIL)"
exit $rc
