#!/usr/bin/env bash
# Faults of a fleet on Zenoh (issue 18), in one loopback-only namespace: two sites as in
# launch_configs/zenoh_fleet.yaml — router A (tcp/127.0.0.1:7447) with /uav2, router B (:7448)
# with /uav3 and the ground station — but router B reaches router A THROUGH a TCP relay
# (tests/zenoh/tcp_relay.py, :7449 → :7447), so killing the relay cuts the link between the
# sites without touching a router. Each vehicle is fcc-sitl --link-pty + fcc-bridge + fcc-mission
# exactly as in zenoh_fleet.yaml (RMW_IMPLEMENTATION=rmw_zenoh_cpp, Zenoh clients of their
# site's router, clock_source:=mcu, use_sim_time), uav2 with hover_s:=40. The ground station
# (tests/zenoh/fault_peer.py, eclipse-zenoh + rosbags), a client of router B, records the arrival
# of every /uav2 and /uav3 status and state/odom sample.
#   1. both vehicles armed and > 2 m up (as the peer sees them);
#   2. link cut: the relay killed for 5 s, then started again; the time from the restore to the
#      next /uav2 sample at site B is printed; /uav3 (site B) must not have a gap > 1 s;
#   3. router A killed (SIGKILL) for 5 s, then started again on its port: uav2's bridge and
#      mission node (both its clients) lose each other, the MCU's own failsafes hold then land;
#      the time from the restart to the next /uav2 sample at site B is printed; uav2's bridge is
#      the same process, still running (it reconnected by itself);
#   4. until uav2 has landed and disarmed and uav3's mission is complete; everything stopped
#      (SIGTERM: the simulators write their CSVs), then the peer checks the data and each
#      simulator's TRUTH: one ground contact (the final landing) per vehicle, touchdown ≤ 0.5 m/s
#      down and ≤ 0.3 m/s horizontal, no flyaway (≤ 3 m from the mission's path, uav2 ≤ 3 m from
#      where router A went down), landed and disarmed; uav2's mode/failsafe sequence is printed.
#   usage: tests/zenoh/faults.sh [PYTHON]   (PYTHON must import zenoh (eclipse-zenoh) and rosbags)
# FCC_E2E_KEEP=DIR keeps the CSVs and logs. Needs release builds of fcc-sitl, fcc-bridge,
# fcc-mission and fcc-zenoh-router (FCC_BIN_DIR). ≈ 70 s wall at speed 1.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
cfg="$root/launch_configs"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
"$py" -c 'import zenoh, rosbags' || { echo "faults.sh: $py cannot import zenoh and rosbags" >&2; exit 2; }
rc=0
port_a=7447 port_b=7448 port_relay=7449
fault_s=5
# The nodes' Zenoh settings: as launch_configs/zenoh_fleet.yaml's zenoh_a / zenoh_b.
zenoh_a="mode=\"client\";connect/endpoints=[\"tcp/127.0.0.1:$port_a\"];scouting/multicast/enabled=false"
zenoh_b="mode=\"client\";connect/endpoints=[\"tcp/127.0.0.1:$port_b\"];scouting/multicast/enabled=false"
t_start=$(date +%s.%N)

now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
event() { echo "$1 $(now)" >> "$tmp/events"; }
say() { echo "[faults $(since "$t_start") s] $*"; }
fail() { echo "FAIL $*"; rc=1; }
pass() { echo "PASS $*"; }
# Field N of vehicle V's line in the peer's state file (see fault_peer.py).
field() { awk -v u="uav$1" -v n="$2" '$1 == u { print $n }' "$tmp/state" 2>/dev/null; }
# Waits (at most $1 s) until the shell condition $2 holds; returns 1 on timeout.
wait_for() {
  local end=$(( $(date +%s) + $1 ))
  while [ "$(date +%s)" -le $end ]; do eval "$2" && return 0; sleep 0.1; done
  return 1
}
wait_port() {
  for _ in $(seq 100); do (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null && return 0; sleep 0.1; done
  echo "faults.sh: nothing listens on port $1" >&2; return 1
}
airborne() { [ "$(field "$1" 3)" = 1 ] && awk -v z="$(field "$1" 4)" 'BEGIN { exit !(z > 2.0) }'; }
heard_after() { awk -v l="$(field "$1" 2)" -v t="$2" 'BEGIN { exit !(l > t) }'; }
# Ends a process we started: SIGTERM, then SIGKILL after 10 s; its exit status in $stopped_rc.
stop() {
  local pid=$1
  kill -TERM "$pid" 2>/dev/null || true
  for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
  kill -KILL "$pid" 2>/dev/null && echo "faults.sh: pid $pid needed SIGKILL"
  set +e; wait "$pid"; stopped_rc=$?; set -e
}

start_relay() {
  "$py" "$here/tcp_relay.py" --listen "127.0.0.1:$port_relay" --to "127.0.0.1:$port_a" \
    >> "$tmp/relay.log" 2>&1 &
  relay=$!
  wait_port $port_relay
}
start_router_a() {
  "$bin/fcc-zenoh-router" --listen "tcp/127.0.0.1:$port_a" >> "$tmp/router_a.log" 2>&1 &
  router_a=$!
}
# vehicle N ZENOH_CONFIG MISSION_ARGS...: fcc-sitl, fcc-bridge, fcc-mission as zenoh_fleet.yaml.
start_vehicle() {
  local n=$1 zc=$2; shift 2
  "$bin/fcc-sitl" --scenario "$cfg/scenarios/uav$n.yaml" --link-pty --pty-link "$tmp/uav$n.tty" \
    --speed 1 --csv "$tmp/uav$n.csv" > "$tmp/sitl$n.log" 2>&1 &
  eval "sitl$n=$!"
  for _ in $(seq 100); do [ -e "$tmp/uav$n.tty" ] && break; sleep 0.1; done
  RMW_IMPLEMENTATION=rmw_zenoh_cpp ZENOH_CONFIG_OVERRIDE="$zc" \
    "$bin/fcc-bridge" --device "$tmp/uav$n.tty" --ros-args -r "__ns:=/uav$n" -r /tf:=tf \
    -r /tf_static:=tf_static -r /diagnostics:=diagnostics -r /clock:=clock \
    -p clock_source:=mcu > "$tmp/bridge$n.log" 2>&1 &
  eval "bridge$n=$!"
  RMW_IMPLEMENTATION=rmw_zenoh_cpp ZENOH_CONFIG_OVERRIDE="$zc" \
    "$bin/fcc-mission" --mission "$cfg/missions/uav$n.yaml" --ros-args -r "__ns:=/uav$n" \
    -r /clock:=clock -p use_sim_time:=true -p timeout_s:=400 "$@" > "$tmp/mission$n.log" 2>&1 &
  eval "mission$n=$!"
}

echo "=== Zenoh faults: site A (router A :$port_a, /uav2), site B (router B :$port_b, /uav3, the peer),"
echo "    router B → relay :$port_relay → router A; link cut ${fault_s} s, router A down ${fault_s} s"
start_router_a
wait_port $port_a
start_relay
"$bin/fcc-zenoh-router" --listen "tcp/127.0.0.1:$port_b" --connect "tcp/127.0.0.1:$port_relay" \
  > "$tmp/router_b.log" 2>&1 &
router_b=$!
wait_port $port_b
# Hang guard (exit 124: the peer's check fails), far beyond the test's ~70 s.
timeout -k 5 400 "$py" "$here/fault_peer.py" --connect "tcp/127.0.0.1:$port_b" --state-file "$tmp/state" \
  --until-file "$tmp/done" --events "$tmp/events" --csv-dir "$tmp" --missions-dir "$cfg/missions" \
  > "$tmp/peer.log" 2>&1 &
peer=$!
start_vehicle 2 "$zenoh_a" -p hover_s:=40
start_vehicle 3 "$zenoh_b"
bridge2_pid=$bridge2

# ---- 1. both airborne
if wait_for 60 'airborne 2 && airborne 3'; then
  event airborne
  say "both airborne: uav2 z $(field 2 4) m $(field 2 5), uav3 z $(field 3 4) m $(field 3 5)"
else
  fail "both vehicles armed and > 2 m up within 60 s (uav2: $(field 2 3) $(field 2 4) m, uav3: $(field 3 3) $(field 3 4) m)"
fi

if [ $rc -eq 0 ]; then
  # ---- 2. link cut
  kill -KILL "$relay"; set +e; wait "$relay" 2>/dev/null; set -e
  event cut
  say "link cut (relay killed); uav2 $(field 2 5)"
  sleep $fault_s
  start_relay
  event restore
  t_restore=$(awk '$1 == "restore" { print $2 }' "$tmp/events")
  if wait_for 20 "heard_after 2 $t_restore"; then
    say "link restored; /uav2 heard again at site B $(awk -v a="$t_restore" -v b="$(field 2 2)" 'BEGIN { printf "%.2f", b - a }') s after the restore"
  else
    fail "/uav2 not heard at site B within 20 s of the link's restore"
  fi
  # ---- 3. router A down
  say "killing router A; uav2 $(field 2 5) at z $(field 2 4) m"
  lines_b2=$(wc -l < "$tmp/bridge2.log") lines_m2=$(wc -l < "$tmp/mission2.log")
  kill -KILL "$router_a"; set +e; wait "$router_a" 2>/dev/null; set -e
  event kill_a
  sleep $fault_s
  start_router_a
  event restart_a
  t_restart=$(awk '$1 == "restart_a" { print $2 }' "$tmp/events")
  wait_port $port_a || fail "router A did not listen again on :$port_a (router_a.log: $(tail -2 "$tmp/router_a.log"))"
  if wait_for 20 "heard_after 2 $t_restart"; then
    say "router A restarted; /uav2 heard again at site B $(awk -v a="$t_restart" -v b="$(field 2 2)" 'BEGIN { printf "%.2f", b - a }') s after the restart ($(field 2 5), failsafe $(field 2 6))"
  else
    fail "/uav2 not heard at site B within 20 s of router A's restart"
  fi
  if kill -0 "$bridge2" 2>/dev/null && [ "$bridge2" = "$bridge2_pid" ]; then
    pass "uav2's bridge is the same process (pid $bridge2), still running after both faults"
  else
    fail "uav2's bridge (pid $bridge2_pid) is not running after the faults"
  fi
  # ---- 4. uav2 lands on its failsafes, uav3 completes its mission
  wait_for 60 '[ "$(field 2 3)" = 0 ] && [ "$(field 2 7)" = 1 ] && ! kill -0 $mission3 2>/dev/null' || true
  say "uav2: armed $(field 2 3) landed $(field 2 7) $(field 2 5)/$(field 2 6); mission3 $(kill -0 "$mission3" 2>/dev/null && echo running || echo exited)"
  if [ "$(field 2 3)" = 0 ] && [ "$(field 2 7)" = 1 ]; then
    pass "uav2 landed and disarmed (its status at site B: $(field 2 5), failsafe $(field 2 6))"
  else
    fail "uav2 not landed and disarmed (armed $(field 2 3), landed $(field 2 7), $(field 2 5))"
  fi
  sleep 1
fi
event stop

# ---- stop everything (missions, bridges, simulators: their CSVs; routers, relay)
for p in mission3 mission2; do
  pid=${!p}
  if kill -0 "$pid" 2>/dev/null; then stop "$pid"; eval "${p}_rc=stopped"; else
    set +e; wait "$pid"; eval "${p}_rc=$?"; set -e; fi
done
for p in bridge2 bridge3 sitl2 sitl3 router_a router_b relay; do stop "${!p}"; done
touch "$tmp/done"
set +e; wait $peer; prc=$?; set -e
t_end=$(date +%s.%N)

echo "--- fcc-mission"
for n in 2 3; do
  echo "  uav$n (exit $(eval echo \$mission${n}_rc)): $(grep -E 'mission complete|disarmed in flight|failsafe|Failed|error' "$tmp/mission$n.log" | tail -2 | tr '\n' ' ')"
done
if grep -q "mission complete" "$tmp/mission3.log" && [ "$mission3_rc" = 0 ]; then
  pass "/uav3: fcc-mission \"mission complete\", exit 0 (site B, through both faults)"
else
  fail "/uav3: fcc-mission did not complete its mission (exit $mission3_rc)"
fi
echo "--- uav2's bridge and mission node from router A's kill on (their own log lines)"
for f in bridge2:${lines_b2:-0} mission2:${lines_m2:-0}; do
  tail -n +$(( ${f#*:} + 1 )) "$tmp/${f%%:*}.log" | sed 's/\x1b\[[0-9;]*m//g' \
    | grep -vE '^fcc-bridge counts|command Arm|refused Arm' | head -8 | sed "s/^/  [${f%%:*}] /" || true
done
if grep -lE 'panicked|ERROR' "$tmp"/*.log >/dev/null 2>&1; then
  fail "no panic or ERROR line from the stack:"; grep -hE 'panicked|ERROR' "$tmp"/*.log | head -5; rc=1
else
  pass "no panic or ERROR line from the stack"
fi
echo "--- the ground station (site B)"
cat "$tmp/peer.log"
[ $prc -eq 0 ] || rc=1
echo "faults: peer exit $prc, $(since "$t_start") s wall"
if [ -n "${FCC_E2E_KEEP:-}" ]; then
  mkdir -p "$FCC_E2E_KEEP"; cp "$tmp"/*.csv "$tmp"/*.log "$tmp/events" "$FCC_E2E_KEEP/" 2>/dev/null || true
fi
if [ $rc -eq 0 ]; then echo "zenoh faults: PASS"; else echo "zenoh faults: FAIL"; fi
exit $rc
