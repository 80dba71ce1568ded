#!/usr/bin/env bash
# Robustness tests through the real pty + bridge (issue 6: points 2, 4, 5, 6, 7), all in ONE
# loopback-only network namespace (the independent Cyclone DDS peer, the bridge and the mission
# node must discover each other; nothing may leave the machine):
#   (7) bad configuration: bad YAML and bad flags for every binary → exit 2, one line, no panic
#   (2) noisy wire: fcc-sitl ⇄ fcc-wire-fault (BER 1e-4, drop/dup 1e-4) ⇄ fcc-bridge ⇄ fcc-mission
#   (4) mission node SIGKILLed mid-leg → hold within the TTL, land, disarm; cause on `status`
#   (5) bridge SIGKILLed + restarted, serial device (relay pty) gone + back → MCU keeps hovering
#   (6) sensors: magnetic disturbance, laser dead, GPS lost in one hover → status, /diagnostics, /rosout
# Simulated time runs at FCC_ROBUST_SPEED (default 2) × real time; ROS time = MCU time.
#   usage: tests/e2e/robust_stack.sh [PYTHON] [TEST ...]   (PYTHON must import cyclonedds)
#          TEST: config noisy kill-mission reconnect sensors (default: all)
# Needs: release builds of fcc-sitl, fcc-bridge, fcc-mission, fcc-launch, fcc-wire-fault (FCC_BIN_DIR).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
shift || true
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py" "$@"
tests=("$@")
[ ${#tests[@]} -gt 0 ] || tests=(config noisy kill-mission reconnect sensors)
rc=0
declare -A res
t_all=$(date +%s)
for t in "${tests[@]}"; do
  t0=$(date +%s)
  set +e
  "$py" "$here/robust_stack.py" "$t"
  r=$?
  set -e
  res[$t]="exit $r, $(( $(date +%s) - t0 )) s wall"
  [ $r -eq 0 ] || rc=1
done
echo "=== robustness summary ($(( $(date +%s) - t_all )) s wall)"
for t in "${tests[@]}"; do echo "  $t: ${res[$t]}"; done
exit $rc
