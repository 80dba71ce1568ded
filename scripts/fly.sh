#!/usr/bin/env bash
# The main job: fly paper A's flights in the software-in-the-loop simulator (lockstep, faster
# than real time) and leave a summary and 50 Hz flight logs in out/.
#   usage: scripts/fly.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out}
mkdir -p "$out"
cargo build --release --locked -p fcc_firmware --bin fcc-sitl
summary="$out/summary.txt"
: > "$summary"
for s in hover square elevator yaw_disturbance; do
  echo "== $s" | tee -a "$summary"
  ./target/release/fcc-sitl --scenario "launch_configs/scenarios/$s.yaml" --csv "$out/$s.csv" | tee -a "$summary"
done
echo "summary: $summary"
