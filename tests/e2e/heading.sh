#!/usr/bin/env bash
# Heading and yaw-rate setpoints through the real pty + bridge (issue 17, part 3), in ONE
# loopback-only network namespace: fcc-sitl --link-pty ⇄ fcc-bridge ⇄ an independent Cyclone DDS
# peer (heading.py) that flies the vehicle: `twist.angular.z` +0.3 and −0.5 rad/s must turn it at
# the commanded rate ±10 % on the simulator's CSV truth, a `setpoint/heading` of east (NED 90°)
# must be held within 3° RMS during a 10 s leg flown north, and bad headings (non-unit, NaN,
# unknown frame) are refused and counted on /diagnostics; then fcc-mission flies a leg north with
# `yaw_deg: 90` (published on setpoint/heading): true heading within 3° RMS while cruising. ~50 s.
# Simulated time runs at FCC_HEADING_SPEED (default 2) × real time; ROS time = the MCU's.
#   usage: tests/e2e/heading.sh [PYTHON]   (PYTHON must import cyclonedds)
# Needs: release builds of fcc-sitl and fcc-bridge (FCC_BIN_DIR).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
t0=$(date +%s)
rc=0
PYTHONPATH="$root/tests/dds:$here" "$py" "$here/heading.py" --speed "${FCC_HEADING_SPEED:-2}" || rc=1
echo "=== heading: exit $rc, $(( $(date +%s) - t0 )) s wall"
exit $rc
