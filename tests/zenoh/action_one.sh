#!/usr/bin/env bash
# One vehicle flown by an action goal on Zenoh (issue 18), in one loopback-only namespace:
# fcc-zenoh-router, fcc-sitl --link-pty (launch_configs/scenarios/uav1.yaml, --csv), fcc-bridge
# (clock_source:=mcu) and fcc-mission WITHOUT --mission (it serves its actions), both Zenoh
# clients of the router (RMW_IMPLEMENTATION=rmw_zenoh_cpp), remaps as launch_configs/
# zenoh_fleet.yaml. The ground station (tests/zenoh/action_flight.py, eclipse-zenoh + rosbags)
# sends a FollowWaypoints goal to /uav1/mission/follow_waypoints and checks the acceptance, the
# feedback, the status, get_result (SUCCEEDED, outcome 0) and the simulator's truth.
#   usage: tests/zenoh/action_one.sh [PYTHON]   FCC_E2E_KEEP=DIR keeps the CSV and logs.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
zc='mode="client";connect/endpoints=["tcp/127.0.0.1:7447"];scouting/multicast/enabled=false'
t0=$(date +%s.%N)
"$bin/fcc-zenoh-router" --listen tcp/127.0.0.1:7447 > "$tmp/router.log" 2>&1 &
for _ in $(seq 100); do (exec 3<>/dev/tcp/127.0.0.1/7447) 2>/dev/null && break; sleep 0.1; done
"$bin/fcc-sitl" --scenario "$root/launch_configs/scenarios/uav1.yaml" --link-pty \
  --pty-link "$tmp/uav1.tty" --csv "$tmp/uav1.csv" > "$tmp/sitl.log" 2>&1 &
sitl=$!
for _ in $(seq 100); do [ -e "$tmp/uav1.tty" ] && break; sleep 0.1; done
export RMW_IMPLEMENTATION=rmw_zenoh_cpp ZENOH_CONFIG_OVERRIDE="$zc"
"$bin/fcc-bridge" --device "$tmp/uav1.tty" --ros-args -r __ns:=/uav1 -r /tf:=tf \
  -r /tf_static:=tf_static -r /diagnostics:=diagnostics -r /clock:=clock \
  -p clock_source:=mcu > "$tmp/bridge.log" 2>&1 &
"$bin/fcc-mission" --ros-args -r __ns:=/uav1 -r /clock:=clock -p use_sim_time:=true \
  > "$tmp/mission.log" 2>&1 &
unset RMW_IMPLEMENTATION ZENOH_CONFIG_OVERRIDE
"$py" "$here/action_flight.py" --connect tcp/127.0.0.1:7447 --vehicle 1 --csv "$tmp/uav1.csv" \
  --until-file "$tmp/stopped" > "$tmp/gs.log" 2>&1 &
gs=$!
# Once the ground station has its result, stop the simulator (its CSV is then complete).
for _ in $(seq 1200); do [ -e "$tmp/stopped.flown" ] || ! kill -0 $gs 2>/dev/null && break; sleep 0.1; done
sleep 1
kill $sitl 2>/dev/null || true
wait $sitl 2>/dev/null || true
touch "$tmp/stopped"
set +e
wait $gs
rc=$?
set -e
cat "$tmp/gs.log"
if grep -qE 'panicked|ERROR' "$tmp/bridge.log" "$tmp/mission.log"; then
  echo "FAIL no panic or ERROR line from the stack:"; grep -E 'panicked|ERROR' "$tmp"/*.log | head -5; rc=1
fi
echo "--- mission log (tail)"; tail -5 "$tmp/mission.log"
if [ -n "${FCC_E2E_KEEP:-}" ]; then mkdir -p "$FCC_E2E_KEEP"; cp "$tmp"/*.csv "$tmp"/*.log "$FCC_E2E_KEEP/"; fi
echo "action_one: $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }') s wall"
if [ $rc -eq 0 ]; then echo "zenoh action flight: PASS"; else echo "zenoh action flight: FAIL"; fi
exit $rc
