#!/usr/bin/env bash
# The main job: fly paper A's and paper B's flights in the software-in-the-loop simulator and leave a summary
# and 50 Hz flight logs in out/:
#   1. the lockstep scenario runs (faster than real time, in-process mission computer);
#   2. the 20 m square through the full stack — simulated MCU serving its UART on a pty ⇄
#      fcc-bridge (ROS 2) ⇄ fcc-mission (ROS 2) — started by fcc-launch from
#      launch_configs/square_flight.yaml, in a loopback-only network namespace (DDS never
#      leaves the machine), in real time (FCC_SPEED=2 to halve it), ROS time = the MCU's time
#      (clock_source:=mcu use_sim_time:=true: /clock from the bridge, bag stamps = the
#      simulator CSV's t_s); after the square the mission node hovers FCC_HOVER_S (default 30) s
#      in the MCU's HOLD mode (paper A Fig. 16), then lands; the bridge records every topic to
#      out/square.mcap (MCAP, rosbag2-compatible);
#   3. fcc-report turns that bag into out/report/ (PNG plots, report.html, summary.txt) and its
#      summary is appended to out/summary.txt;
#   4. the bag is opened with independent readers (tests/mcap/check_bag.py: PyPI mcap +
#      mcap-ros2-support, rosbags; in .venv-dds, created if missing) and the report's figures
#      (cross-track per leg, hover box, observer ratio) are compared with the flight core's own
#      log of the same flight, out/square_stack.csv (tests/mcap/compare_csv.py), into
#      out/summary.txt. The script fails if any of these checks fails.
#   usage: scripts/fly.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out}
speed=${FCC_SPEED:-1}
hover_s=${FCC_HOVER_S:-30}
mkdir -p "$out"
# Python for the bag checks (same venv as scripts/test.sh; only the bag readers are needed here).
py=.venv-dds/bin/python
if [ ! -x "$py" ]; then
  python3 -m venv .venv-dds
fi
if ! "$py" -c 'import mcap, mcap_ros2.decoder, rosbags.highlevel' 2>/dev/null; then
  .venv-dds/bin/pip install -q --disable-pip-version-check mcap mcap-ros2-support rosbags
fi
cargo build --release --locked -p fcc_sim --bin fcc-sitl
cargo build --release --locked -p fcc_bridge --bin fcc-bridge
cargo build --release --locked -p fcc_mission --features ros --bin fcc-mission --bin fcc-launch
cargo build --release --locked -p fcc_bridge --bin fcc-report
summary="$out/summary.txt"
: > "$summary"
for s in hover square elevator yaw_disturbance ground_test roll_30 roll_45 landing_dark; do
  echo "== $s" | tee -a "$summary"
  ./target/release/fcc-sitl --scenario "launch_configs/scenarios/$s.yaml" --csv "$out/$s.csv" | tee -a "$summary"
done

netns=""
for c in ../shared/tools/netns-run /work/shared/tools/netns-run; do
  if [ -x "$c" ] && "$c" true 2>/dev/null; then netns=$c; break; fi
done
# ROS time = MCU time at any speed: the bag's stamps are the CSV's t_s (compare_csv.py needs it).
clock=(clock_source:=mcu use_sim_time:=true hover_s:="$hover_s")
bag="$out/square.mcap"
csv="$out/square_stack.csv"
rm -f "$bag" "$bag".counts.json "$csv"
if [ -n "$netns" ]; then
  "$netns" ./target/release/fcc-launch launch_configs/square_flight.yaml \
    out:="$out" speed:="$speed" record:="$bag" "${clock[@]}" | tee "$out/square_stack.log"
else
  # No namespace: the nodes still default to loopback-only DDS (ROS_LOCALHOST_ONLY semantics).
  echo "fly.sh: no network namespace available; running with loopback-only DDS" >&2
  ROS_LOCALHOST_ONLY=1 ./target/release/fcc-launch launch_configs/square_flight.yaml \
    out:="$out" speed:="$speed" record:="$bag" "${clock[@]}" | tee "$out/square_stack.log"
fi

# The flight's bag → plots and figures (reads the file only; no DDS).
echo "== flight report: fcc-report $bag --out $out/report" | tee -a "$summary"
./target/release/fcc-report "$bag" --out "$out/report" --mission launch_configs/missions/square.yaml \
  > "$out/report.log"
cat "$out/report/summary.txt" | tee -a "$summary"
echo "bag: $bag ($(du -h "$bag" | cut -f1)), report: $out/report/report.html" | tee -a "$summary"

# The bag with independent readers, then the report's figures vs the flight core's own log.
rc=0
echo "== bag check: tests/mcap/check_bag.py $bag (PyPI mcap + mcap-ros2-support, rosbags)" | tee -a "$summary"
"$py" tests/mcap/check_bag.py "$bag" --counts "$bag".counts.json --min-seconds 60 2>&1 | tee -a "$summary" \
  || rc=1
echo "== report (bag) vs flight core log: tests/mcap/compare_csv.py $out/report/summary.json $csv" \
  | tee -a "$summary"
"$py" tests/mcap/compare_csv.py "$out/report/summary.json" "$csv" --sitl-out "$out/square_stack.log" 2>&1 \
  | tee -a "$summary" || rc=1

echo "summary: $summary"
if [ $rc -ne 0 ]; then echo "fly.sh: a bag check FAILED (see $summary)" >&2; fi
exit $rc
