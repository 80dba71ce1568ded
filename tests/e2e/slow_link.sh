#!/usr/bin/env bash
# The slow-link profile end to end (issue 20), in ONE loopback-only network namespace: fcc-launch
# flies the square (launch_configs/square_slow_link.yaml: fcc-sitl --link-pty ⇄ fcc-wire-fault,
# a UART of 115200 baud in simulated time ⇄ fcc-bridge on launch_configs/slow_link_115200.yaml
# ⇄ fcc-mission), recording a bag; slow_link.py checks the cross-track, the link utilisation
# (≤ 80 % after start-up), the profile's rates in the bag, no CRC error or lost frame, no
# failsafe on the CSV truth.
#   usage: tests/e2e/slow_link.sh [PYTHON]   (PYTHON with mcap + mcap-ros2-support)
# FCC_E2E_SPEED (default 2): the relay's line runs at 115200 × speed baud so that it carries
# 115200 baud's bytes per simulated second. Takes ~45 s at speed 2.
# Needs: release builds of fcc-sitl, fcc-wire-fault, fcc-bridge, fcc-mission, fcc-launch.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
. "$root/tests/lib/scratch.sh"
speed="${FCC_E2E_SPEED:-2}"
baud=115200
echo "=== the square over a $baud-baud UART, slow-link profile (speed $speed, relay at $((baud * speed)) baud)"
set +e
"$bin/fcc-launch" "$root/launch_configs/square_slow_link.yaml" BIN:="$bin" out:="$tmp" speed:="$speed" \
  baud:="$baud" line_baud:="$((baud * speed))" record:="$tmp/slow_link.mcap" > "$tmp/launch.log" 2>&1
lrc=$?
set -e
grep -E '^\[mission\] fcc-mission: mission complete|^== |^all |^armed |^\[uart\] wire-fault' "$tmp/launch.log" || true
rc=0
"$py" "$here/slow_link.py" --dir "$tmp" --baud "$baud" --speed "$speed" \
  --profile "$root/launch_configs/slow_link_115200.yaml" || rc=1
if [ $lrc -ne 0 ] || [ $rc -ne 0 ]; then echo "--- launch log (tail)"; tail -30 "$tmp/launch.log" | cut -c1-300; rc=1; fi
exit $rc
