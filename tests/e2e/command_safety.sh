#!/usr/bin/env bash
# Command safety and parameter envelopes through the real pty + bridge (issue 14, points 1 and 2),
# in ONE loopback-only network namespace: fcc-sitl --link-pty ⇄ fcc-bridge ⇄ an independent Cyclone
# DDS peer (command_safety.py) that flies a hover at ~5 m and, while airborne, sends cmd/arm false,
# cmd/mode "disarm" and cmd/arm toggled at 100 Hz: the simulator's CSV truth must show the vehicle
# still flying (true altitude within ±0.5 m of the hold height), every refusal counted on `status`
# (command_rejects, last_reject not_landed); then cmd/kill with a wrong text is refused and "KILL"
# stops the motors (failsafe emergency_kill, disarmed). Also: SetParameters with ttl_ms=65535,
# max_speed_mps=-0.0 / 5e-324 / inf, max_stamp_age_ms=-0.0 / 5e-324 refused with the range; and
# use_sim_time set at run time on a second bridge (clock_source:=sync, fcc-fake-mcu) moves the
# IMU stamps onto the peer's /clock and back.
# Simulated time runs at FCC_SAFETY_SPEED (default 2) × real time; ROS time = the MCU's.
#   usage: tests/e2e/command_safety.sh [PYTHON]   (PYTHON must import cyclonedds)
# Needs: release builds of fcc-sitl, fcc-bridge and fcc-fake-mcu (FCC_BIN_DIR). Takes ~25 s.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
t0=$(date +%s)
rc=0
PYTHONPATH="$root/tests/dds:$here" "$py" "$here/command_safety.py" --speed "${FCC_SAFETY_SPEED:-2}" || rc=1
echo "=== command safety: exit $rc, $(( $(date +%s) - t0 )) s wall"
exit $rc
