#!/usr/bin/env bash
# Acceptance through the full stack, all in ONE loopback-only network namespace:
#   (a) fcc-launch flies the square (fcc-sitl --link-pty ⇄ fcc-bridge ⇄ fcc-mission) while the
#       independent Cyclone DDS peer subscribes to every topic; after the run the peer checks
#       rates, frames and values against the simulator's CSV truth;
#   (b) fcc-sitl --link-pty ⇄ fcc-bridge, and the peer flies the vehicle itself (cmd/arm,
#       reliable TwistStamped setpoints, cmd/mode hold/land); the CSV truth must show it.
#       The peer also checks the VALUES on altitude and altitude/ground (issue 4) against the
#       CSV's ground_m / true_agl_m / ground_source / laser_m / sonar_m at the same sim times.
# FCC_E2E_KEEP=DIR keeps (a)'s CSV and the received altitude messages (altitude.json) there;
# `stack_peer.py check-altitude --csv DIR/square_stack.csv --dump DIR/altitude.json` re-checks.
# Simulated time runs at FCC_E2E_SPEED (default 2) × real time; ROS time is the MCU's
# (fcc-bridge -p clock_source:=mcu, /clock) so the checks do not depend on the speed. (a) gives
# fcc-launch `speed:=2` alone: the launch config's rule must choose that clock.
#   usage: tests/e2e/run_stack.sh [PYTHON]   (PYTHON must import cyclonedds; default python3)
# Needs: release builds of fcc-sitl, fcc-bridge, fcc-mission and fcc-launch (FCC_BIN_DIR).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
speed="${FCC_E2E_SPEED:-2}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
export PYTHONPATH="$root/tests/dds"
rc=0

echo "=== (a) square mission through the full stack, peer observing (speed $speed)"
t0=$(date +%s)
"$py" "$here/stack_peer.py" observe --csv "$tmp/square_stack.csv" --until-file "$tmp/done" \
  --dump "$tmp/altitude.json" > "$tmp/peer_a.log" 2>&1 &
peer=$!
sleep 2   # the peer's readers exist before the nodes start (discovery info is seen from the start)
set +e
# At any speed but 1, `speed:=N` alone must do (issue 16): the config's `when` rule makes ROS time
# the simulator's (clock_source:=mcu, use_sim_time:=true). At speed 1 they are given here.
clock=(); [ "$speed" = 1 ] && clock=(clock_source:=mcu use_sim_time:=true)
"$bin/fcc-launch" "$root/launch_configs/square_flight.yaml" BIN:="$bin" out:="$tmp" speed:="$speed" \
  "${clock[@]}" > "$tmp/launch.log" 2>&1
lrc=$?
if [ "$speed" != 1 ] && ! grep -q "^fcc-launch: clock_source:=mcu (because speed is $speed)" "$tmp/launch.log"; then
  echo "(a) FAIL: speed:=$speed alone did not select the simulator's clock"; lrc=1
fi
touch "$tmp/done"
wait $peer
prc=$?
set -e
grep -E '^\[mission\] fcc-mission: mission complete|^== |^leg |^all |^armed ' "$tmp/launch.log" || true
cat "$tmp/peer_a.log"
echo "(a) launcher exit $lrc, peer exit $prc, $(( $(date +%s) - t0 )) s wall"
if [ -n "${FCC_E2E_KEEP:-}" ]; then  # keep the truth log and the altitude messages (check-altitude)
  mkdir -p "$FCC_E2E_KEEP"; cp "$tmp/square_stack.csv" "$tmp/altitude.json" "$tmp/launch.log" "$FCC_E2E_KEEP/" 2>/dev/null || true
fi
if [ $lrc -ne 0 ] || [ $prc -ne 0 ]; then echo "--- launch log (tail)"; tail -40 "$tmp/launch.log"; rc=1; fi

echo "=== (b) the peer flies the vehicle through fcc-bridge (speed $speed)"
t0=$(date +%s)
"$bin/fcc-sitl" --scenario "$root/launch_configs/scenarios/square.yaml" --link-pty --pty-link "$tmp/link.tty" \
  --speed "$speed" --csv "$tmp/fly.csv" > "$tmp/sitl_b.log" 2>&1 &
sitl=$!
for _ in $(seq 100); do [ -e "$tmp/link.tty" ] && break; sleep 0.05; done
"$bin/fcc-bridge" --device "$tmp/link.tty" --ros-args -r __ns:=/fcc -p clock_source:=mcu > "$tmp/bridge_b.log" 2>&1 &
bridge=$!
set +e
"$py" "$here/stack_peer.py" fly --events "$tmp/events.json"
frc=$?
kill -TERM $bridge; kill -TERM $sitl; wait $sitl; wait $bridge 2>/dev/null
"$py" "$here/stack_peer.py" check-fly --csv "$tmp/fly.csv" --events "$tmp/events.json"
crc=$?
set -e
echo "(b) peer flight exit $frc, truth check exit $crc, $(( $(date +%s) - t0 )) s wall"
if [ $frc -ne 0 ] || [ $crc -ne 0 ]; then echo "--- bridge log (tail)"; tail -20 "$tmp/bridge_b.log"; rc=1; fi
exit $rc
