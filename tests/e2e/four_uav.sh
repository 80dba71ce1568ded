#!/usr/bin/env bash
# Four vehicles on ONE DDS domain (issue 7, point 7), all in one loopback-only network namespace:
# fcc-launch flies launch_configs/four_uav_flight.yaml — per vehicle /uavN (N = 1…4) its own
# fcc-sitl --link-pty (own pty, seed, GPS home, CSV), fcc-bridge -r __ns:=/uavN (tf, tf_static,
# diagnostics and clock remapped into the namespace) and fcc-mission -r __ns:=/uavN with its own
# mission (squares in four quadrants, 8–14 m, at 4–7 m) — while the independent Cyclone DDS peer
# (four_uav_peer.py) subscribes to every vehicle's topics and afterwards checks that each
# vehicle's topics were all received and that no message crossed namespaces (every message
# against its own vehicle's CSV truth, GPS home, clock, device). All four mission nodes must
# exit 0 with "mission complete". Prints the CPU use of the whole run (user+sys of every
# process — per kind — over the wall time, % of one core).
# Simulated time runs at FCC_E2E_SPEED (default 2) × real time; ROS time is each vehicle's MCU
# time (clock_source:=mcu on /uavN/clock, use_sim_time), so the checks do not depend on the speed
# or on the machine keeping up.
#   usage: tests/e2e/four_uav.sh [PYTHON]   (PYTHON must import cyclonedds; default python3)
# FCC_FOUR_UAV_FAULT=swap  runs a broken configuration on purpose (the bridges of uav1 and uav2
#   swap namespaces): the test must FAIL. FCC_FOUR_UAV_FAULT=global-tf drops the tf remaps.
# FCC_E2E_KEEP=DIR keeps the CSVs and logs.
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
cfg="$root/launch_configs/four_uav_flight.yaml"
case "${FCC_FOUR_UAV_FAULT:-}" in
  "") ;;
  swap)       # bridge1 serves /uav2 and bridge2 /uav1: mission uavN then flies the other vehicle
    sed -e "s#\${CONFIG_DIR}#$root/launch_configs#g" \
        -e 's#"__ns:=/uav1", -r, "/tf:=tf"#"__ns:=/uavX", -r, "/tf:=tf"#' \
        -e 's#"__ns:=/uav2", -r, "/tf:=tf"#"__ns:=/uav1", -r, "/tf:=tf"#' \
        -e 's#"__ns:=/uavX", -r, "/tf:=tf"#"__ns:=/uav2", -r, "/tf:=tf"#' \
        "$cfg" > "$tmp/four_uav_flight.yaml"
    cfg="$tmp/four_uav_flight.yaml"; echo "FAULT INJECTED: bridges of uav1 and uav2 swap namespaces" ;;
  global-tf)  # the bridges publish on the global /tf and /tf_static
    sed -e "s#\${CONFIG_DIR}#$root/launch_configs#g" -e 's#-r, "/tf:=tf", -r, "/tf_static:=tf_static",##' \
        "$cfg" > "$tmp/four_uav_flight.yaml"
    cfg="$tmp/four_uav_flight.yaml"; echo "FAULT INJECTED: no tf remaps" ;;
  *) echo "four_uav.sh: unknown FCC_FOUR_UAV_FAULT '$FCC_FOUR_UAV_FAULT'" >&2; exit 2 ;;
esac
rc=0

echo "=== four vehicles (/uav1 … /uav4) on one DDS domain, peer observing (speed $speed)"
t0=$(date +%s.%N)
"$py" "$here/four_uav_peer.py" --until-file "$tmp/done" --csv-dir "$tmp" > "$tmp/peer.log" 2>&1 &
peer=$!
sleep 2   # the peer's readers exist before the nodes start
set +e
"$bin/fcc-launch" "$cfg" BIN:="$bin" out:="$tmp" speed:="$speed" clock_source:=mcu use_sim_time:=true \
  > "$tmp/launch.log" 2>&1
lrc=$?
touch "$tmp/done"
wait $peer
prc=$?
set -e
t1=$(date +%s.%N)
grep -E '^\[mission[0-9]\] fcc-mission: mission complete|^fcc-launch: (all|mission[0-9]) .*exited|^== |^all ' \
  "$tmp/launch.log" || true
cat "$tmp/peer.log"

echo "--- mission nodes"
for n in 1 2 3 4; do
  if grep -q "^\[mission$n\] fcc-mission: mission complete" "$tmp/launch.log" &&
     grep -qE "^fcc-launch: .*mission$n (exited with code 0|0[,)])" "$tmp/launch.log"; then
    echo "PASS /uav$n: fcc-mission exited 0 with \"mission complete\""
  else
    echo "FAIL /uav$n: fcc-mission did not complete its mission (exit 0 + \"mission complete\")"; rc=1
  fi
done

echo "--- CPU use of the whole run (user+sys, all processes; 100 % = one core)"
wall=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')
awk -v wall="$wall" '
  /^fcc-launch: cpu / && $3 != "fcc-launch" {
    k = $3; sub(/[0-9]+$/, "", k); u[k] += $5; s[k] += $8; n[k]++ }
  /^fcc-launch: cpu fcc-launch / { u["fcc-launch"] += $5; s["fcc-launch"] += $8; n["fcc-launch"] = 1 }
  /^fcc-launch: all .*exited after / { for (i = 1; i <= NF; i++) if ($i == "after") lw = $(i + 1) }
  /^peer cpu / { u["peer (python)"] += $4; s["peer (python)"] += $7; n["peer (python)"] = 1 }
  BEGIN { lw = "n/a" }
  END {
    for (k in u) { t = u[k] + s[k]; tot += t; if (k !~ /^peer/) stack += t
      printf "  %-14s x%d  user %6.2f s  sys %6.2f s  = %5.1f %% of one core\n", k, n[k], u[k], s[k], 100 * t / wall }
    printf "  flight stack (launcher, 4 × sitl, bridge, mission): %.2f s CPU = %.1f %% of one core\n", stack, 100 * stack / wall
    printf "  all processes incl. the peer: %.2f s CPU in %.1f s wall = %.1f %% of one core (flight: %s s of it)\n", tot, wall, 100 * tot / wall, lw
  }' "$tmp/launch.log" "$tmp/peer.log"
echo "four vehicles: launcher exit $lrc, peer exit $prc, $wall s wall"
if [ -n "${FCC_E2E_KEEP:-}" ]; then
  mkdir -p "$FCC_E2E_KEEP"; cp "$tmp"/uav*.csv "$tmp/launch.log" "$tmp/peer.log" "$FCC_E2E_KEEP/" 2>/dev/null || true
fi
if [ $lrc -ne 0 ] || [ $prc -ne 0 ]; then echo "--- launch log (tail)"; tail -30 "$tmp/launch.log"; rc=1; fi
if [ $rc -eq 0 ]; then echo "four_uav: PASS"; else echo "four_uav: FAIL"; fi
exit $rc
