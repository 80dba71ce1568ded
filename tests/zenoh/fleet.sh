#!/usr/bin/env bash
# A fleet on Zenoh through two linked routers (issue 18), in one loopback-only namespace:
#  1. fcc-launch flies launch_configs/zenoh_fleet.yaml — router A (uav1, uav2), router B (uav3,
#     uav4) linked to A, every node a Zenoh client of its site's router (RMW_IMPLEMENTATION=
#     rmw_zenoh_cpp) — while the independent peer (tests/zenoh/fleet_peer.py: eclipse-zenoh,
#     rosbags' CDR decoder), a client of router B only, reads every vehicle's tokens and topics,
#     checks them against each vehicle's own CSV truth, and flies uav1 (site A) from site B by a
#     FollowWaypoints action goal to uav1's mission node (no mission file; rmw_zenoh's service
#     protocol, tests/zenoh/action_flight.py). uav2 … uav4 fly their missions with fcc-mission
#     (exit 0, "mission complete").
#  2. The same two sites NOT linked (router B's --connect points at a port nothing listens on):
#     a vehicle at site A is heard by a control peer at site A and not at all at site B.
#   usage: tests/zenoh/fleet.sh [PYTHON]   (PYTHON must import zenoh (eclipse-zenoh) and rosbags)
# FCC_E2E_KEEP=DIR keeps the CSVs and logs. Needs release builds of fcc-sitl, fcc-bridge,
# fcc-mission, fcc-launch and fcc-zenoh-router (FCC_BIN_DIR).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
speed="${FCC_E2E_SPEED:-1}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
"$py" -c 'import zenoh, rosbags' || { echo "fleet.sh: $py cannot import zenoh and rosbags" >&2; exit 2; }
rc=0

# Waits until a TCP port on 127.0.0.1 accepts connections (a router is up).
wait_port() {
  for _ in $(seq 100); do (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null && return 0; sleep 0.1; done
  echo "fleet.sh: nothing listens on port $1" >&2; return 1
}

echo "=== 1. four vehicles, two sites, routers linked; the ground station at site B (speed $speed)"
t0=$(date +%s.%N)
# Every long-running step has a hang guard (timeout: exit 124, the step fails with its log),
# far beyond its ~75 s: a hang must fail the test command, not stall it.
timeout -k 5 400 "$bin/fcc-launch" "$root/launch_configs/zenoh_fleet.yaml" BIN:="$bin" out:="$tmp" speed:="$speed" \
  > "$tmp/launch.log" 2>&1 &
launch=$!
wait_port 7448
timeout -k 5 260 "$py" "$here/fleet_peer.py" --connect tcp/127.0.0.1:7448 --timeout 200 --until-file "$tmp/done" --csv-dir "$tmp" \
  --scenarios-dir "$root/launch_configs/scenarios" > "$tmp/peer.log" 2>&1 &
peer=$!
set +e
wait $launch
lrc=$?
touch "$tmp/done"
wait $peer
prc=$?
set -e
t1=$(date +%s.%N)
grep -E '^\[mission[0-9]\] fcc-mission: mission complete|^fcc-launch: (all|mission[0-9]) .*exited|^== ' \
  "$tmp/launch.log" || true
cat "$tmp/peer.log"
for n in 2 3 4; do
  if grep -q "^\[mission$n\] fcc-mission: mission complete" "$tmp/launch.log"; then
    echo "PASS /uav$n: fcc-mission on Zenoh: \"mission complete\""
  else
    echo "FAIL /uav$n: fcc-mission did not complete its mission"; rc=1
  fi
done
if grep -qE 'panicked|ERROR' "$tmp/launch.log"; then
  echo "FAIL no panic or ERROR line from the stack:"; grep -E 'panicked|ERROR' "$tmp/launch.log" | head -5; rc=1
else
  echo "PASS no panic or ERROR line from the stack"
fi
wall=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')
echo "fleet: launcher exit $lrc, peer exit $prc, $wall s wall"
if [ $lrc -ne 0 ] || [ $prc -ne 0 ]; then echo "--- launch log (tail)"; tail -30 "$tmp/launch.log"; rc=1; fi

echo "=== 2. the same sites NOT linked: nothing of site A reaches site B"
"$bin/fcc-zenoh-router" --listen tcp/127.0.0.1:7457 > "$tmp/ra.log" 2>&1 &
"$bin/fcc-zenoh-router" --listen tcp/127.0.0.1:7458 --connect tcp/127.0.0.1:9 > "$tmp/rb.log" 2>&1 &
wait_port 7457; wait_port 7458
"$bin/fcc-sitl" --scenario "$root/launch_configs/scenarios/uav1.yaml" --link-pty \
  --pty-link "$tmp/s1.tty" --speed "$speed" > "$tmp/s1.log" 2>&1 &
for _ in $(seq 100); do [ -e "$tmp/s1.tty" ] && break; sleep 0.1; done
RMW_IMPLEMENTATION=rmw_zenoh_cpp \
ZENOH_CONFIG_OVERRIDE='mode="client";connect/endpoints=["tcp/127.0.0.1:7457"];scouting/multicast/enabled=false' \
  "$bin/fcc-bridge" --device "$tmp/s1.tty" --ros-args -r __ns:=/uav1 > "$tmp/b1.log" 2>&1 &
set +e
timeout -k 5 90 "$py" "$here/fleet_peer.py" --connect tcp/127.0.0.1:7458 --control-connect tcp/127.0.0.1:7457 \
  --expect-silence 1 --listen-s 6
src=$?
set -e
[ $src -eq 0 ] || rc=1
if [ -n "${FCC_E2E_KEEP:-}" ]; then
  mkdir -p "$FCC_E2E_KEEP"; cp "$tmp"/*.csv "$tmp"/*.log "$FCC_E2E_KEEP/" 2>/dev/null || true
fi
if [ $rc -eq 0 ]; then echo "zenoh fleet: PASS"; else echo "zenoh fleet: FAIL"; fi
exit $rc
