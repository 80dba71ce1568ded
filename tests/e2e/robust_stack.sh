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
if [ -z "${FCC_IN_NETNS:-}" ]; then
  for c in "$root/../shared/tools/netns-run" /work/shared/tools/netns-run; do
    if [ -x "$c" ]; then exec env FCC_IN_NETNS=1 "$c" "$0" "$py" "$@"; fi
  done
  echo "robust_stack.sh: netns-run not found; refusing to run DDS outside a loopback-only namespace" >&2
  exit 3
fi
if ip -o link show | awk -F': ' '{print $2}' | grep -qv '^lo$'; then
  echo "robust_stack.sh: not in a loopback-only namespace; refusing" >&2; exit 3
fi
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
