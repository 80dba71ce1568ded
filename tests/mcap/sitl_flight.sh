#!/usr/bin/env bash
# A real SITL flight recorded by the bridge: fcc-sitl (square, --link-pty, 2× real time) ⇄
# fcc-bridge --record ⇄ a mission driver (fcc_mission's follower over ROS; after the square a
# hover of FCC_HOVER_S (default 30) s of sim time in the MCU's HOLD mode, then land), all in ONE
# loopback-only network namespace. Leaves the bag, the sidecar counts, the 50 Hz truth CSV and
# fcc-sitl's own summary in OUT_DIR, checks the bag with independent readers, runs fcc-report
# and compares its cross-track figures, hover box and observer ratio with the flight core's
# own log of the same flight (compare_csv.py).
#   usage: tests/mcap/sitl_flight.sh OUT_DIR [PYTHON]
# Needs: cargo build --release -p fcc_bridge --bins --examples; -p fcc_sim --bin fcc-sitl.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$(mkdir -p "$1" && cd "$1" && pwd)"
py="${2:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$out" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
hover_s="${FCC_HOVER_S:-30}"   # HOLD after the square (paper A Fig. 16), s of sim time
cd "$root"
rm -f "$out"/flight.mcap* "$out"/flight.csv
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true' EXIT
"$bin/fcc-sitl" --scenario launch_configs/scenarios/square.yaml --link-pty --pty-link "$out/sitl.tty" \
  --speed 2 --csv "$out/flight.csv" > "$out/sitl.out" 2> "$out/sitl.err" &
sitl=$!
for _ in $(seq 100); do [ -e "$out/sitl.tty" ] && break; sleep 0.1; done
"$bin/fcc-bridge" --device "$out/sitl.tty" --record "$out/flight.mcap" \
  --ros-args -p clock_source:=mcu > "$out/bridge.log" 2>&1 &
bridge=$!
set +e
timeout 200 "$bin/examples/fly_mission" launch_configs/missions/square.yaml --timeout 190 --hover-s "$hover_s" > "$out/mission.log" 2>&1
rc=$?
set -e
sleep 1
kill -INT "$bridge"; wait "$bridge" || true
kill -INT "$sitl"; wait "$sitl" || true
if [ $rc -ne 0 ]; then echo "mission driver failed ($rc):"; tail -5 "$out/mission.log"; tail -20 "$out/bridge.log"; exit 1; fi
grep -E "^fcc-bridge (counts|: recorded)" "$out/bridge.log" | cut -c1-300
"$py" "$here/check_bag.py" "$out/flight.mcap" --counts "$out/flight.mcap.counts.json" --min-seconds 60
# The report on the same flight, and its cross-track figures vs the flight core's own log.
"$bin/fcc-report" "$out/flight.mcap" --out "$out/report" --mission launch_configs/missions/square.yaml
"$py" "$here/compare_csv.py" "$out/report/summary.json" "$out/flight.csv" --sitl-out "$out/sitl.out"
