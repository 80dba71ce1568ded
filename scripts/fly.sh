#!/usr/bin/env bash
# The main job: fly paper A's and paper B's flights in the software-in-the-loop simulator and leave a summary
# and 50 Hz flight logs in out/:
#   1. the lockstep scenario runs (faster than real time, in-process mission computer);
#   2. the 20 m square through the full stack — simulated MCU serving its UART on a pty ⇄
#      fcc-bridge (ROS 2) ⇄ fcc-mission (ROS 2) — started by fcc-launch from
#      launch_configs/square_flight.yaml, in a loopback-only network namespace (DDS never
#      leaves the machine), in real time (FCC_SPEED=2 to halve it); the bridge records every
#      topic to out/square.mcap (MCAP, rosbag2-compatible);
#   3. fcc-report turns that bag into out/report/ (PNG plots, report.html, summary.txt) and its
#      summary is appended to out/summary.txt.
#   usage: scripts/fly.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out}
speed=${FCC_SPEED:-1}
mkdir -p "$out"
cargo build --release --locked -p fcc_firmware --bin fcc-sitl
cargo build --release --locked -p fcc_bridge --bin fcc-bridge
cargo build --release --locked -p fcc_mission --features ros --bin fcc-mission --bin fcc-launch
cargo build --release --locked -p fcc_report --bin fcc-report
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
clock=(); [ "$speed" != 1 ] && clock=(clock_source:=mcu use_sim_time:=true)
bag="$out/square.mcap"
rm -f "$bag" "$bag".counts.json
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

echo "summary: $summary"
