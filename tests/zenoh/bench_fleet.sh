#!/usr/bin/env bash
# Fleet scale benchmark on Zenoh (issue 18, BENCHMARKS.md row 7): N vehicles (default 12), each
# fcc-sitl --link-pty + fcc-bridge + fcc-mission on rmw_zenoh (Zenoh clients), alternately at
# site A (router A, odd N) and site B (router B, linked to A); the ground peer
# (tests/zenoh/bench_peer.py) is a client of router B. Prints per-vehicle CPU (sitl, bridge,
# mission: user+sys over the run's wall time, from fcc-launch), bytes/s per vehicle at default
# rates (payload + attachment of every sample the peer receives) and the end-to-end latency of
# imu/data_raw from the MCU sample (bridge stamp, Linux clock via time sync) to the ground peer,
# p50/p99, for the site-A vehicles: two routers in the path.
#   usage: tests/zenoh/bench_fleet.sh [N] [PYTHON]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
n="${1:-12}"
py="${2:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$n" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
cfg="$tmp/fleet.yaml"
za='mode="client";connect/endpoints=["tcp/127.0.0.1:7447"];scouting/multicast/enabled=false'
zb='mode="client";connect/endpoints=["tcp/127.0.0.1:7448"];scouting/multicast/enabled=false'
{
  echo "stop_timeout_s: 10"
  echo "processes:"
  echo "  - {name: router_a, cmd: [\"$bin/fcc-zenoh-router\", --listen, tcp/127.0.0.1:7447], delay_s: 0.5}"
  echo "  - {name: router_b, cmd: [\"$bin/fcc-zenoh-router\", --listen, tcp/127.0.0.1:7448, --connect, tcp/127.0.0.1:7447], delay_s: 0.5}"
  for i in $(seq 1 "$n"); do
    k=$(( (i - 1) % 4 + 1 )); z=$za; [ $((i % 2)) -eq 0 ] && z=$zb
    cat <<EOF
  - name: sitl$i
    group: uav$i
    cmd: ["$bin/fcc-sitl", --scenario, "$root/launch_configs/scenarios/uav$k.yaml", --link-pty, --pty-link, "$tmp/uav$i.tty", --speed, "1"]
    wait_for: "$tmp/uav$i.tty"
  - name: bridge$i
    group: uav$i
    env: {RMW_IMPLEMENTATION: rmw_zenoh_cpp, ZENOH_CONFIG_OVERRIDE: '$z'}
    cmd: ["$bin/fcc-bridge", --device, "$tmp/uav$i.tty", --ros-args, -r, "__ns:=/uav$i", -r, "/tf:=tf", -r, "/tf_static:=tf_static", -r, "/diagnostics:=diagnostics"]
  - name: mission$i
    group: uav$i
    env: {RMW_IMPLEMENTATION: rmw_zenoh_cpp, ZENOH_CONFIG_OVERRIDE: '$z'}
    cmd: ["$bin/fcc-mission", --mission, "$root/launch_configs/missions/uav$k.yaml", --ros-args, -r, "__ns:=/uav$i", -p, "hover_s:=20"]
    main: true
EOF
  done
} > "$cfg"
odd=$(seq -s, 1 2 "$n")
echo "=== $n vehicles on Zenoh, two linked routers, ground peer at site B"
t0=$(date +%s.%N)
"$bin/fcc-launch" "$cfg" > "$tmp/launch.log" 2>&1 &
launch=$!
for _ in $(seq 100); do (exec 3<>/dev/tcp/127.0.0.1/7448) 2>/dev/null && break; sleep 0.1; done
"$py" "$here/bench_peer.py" --connect tcp/127.0.0.1:7448 --warmup 15 --seconds 30 --latency-from "$odd" \
  > "$tmp/peer.json" 2> "$tmp/peer.err" || true
set +e
wait $launch
lrc=$?
set -e
t1=$(date +%s.%N)
wall=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')
completed=$(grep -c "fcc-mission: mission complete" "$tmp/launch.log" || true)
echo "missions complete: $completed of $n (launcher exit $lrc, $wall s wall)"
awk -v wall="$wall" -v n="$n" '
  /^fcc-launch: cpu / && $3 != "fcc-launch" { k = $3; if (k !~ /^router/) sub(/[0-9]+$/, "", k); t[k] += $5 + $8 }
  END { for (k in t) if (k !~ /^router/) printf "  %-9s %5.1f %% of one core per vehicle\n", k, 100 * t[k] / wall / n
        printf "  per vehicle (sitl + bridge + mission): %.1f %% of one core\n", 100 * (t["sitl"] + t["bridge"] + t["mission"]) / wall / n
        printf "  routers: A %.1f %%, B %.1f %% of one core (%d vehicles)\n", 100 * t["router_a"] / wall, 100 * t["router_b"] / wall, n
        printf "%.1f %.1f %.1f %.1f %.1f\n", 100 * t["bridge"] / wall / n, 100 * t["mission"] / wall / n, 100 * t["sitl"] / wall / n, 100 * t["router_a"] / wall, 100 * t["router_b"] / wall > cpuf }' \
  cpuf="$tmp/cpu.txt" "$tmp/launch.log"
"$py" - "$tmp/peer.json" "$n" "$tmp/cpu.txt" "$completed" <<'EOF'
import json, sys
d = json.loads(open(sys.argv[1]).read())
n = int(sys.argv[2])
bridge, mission, sitl, ra, rb = (float(x) for x in open(sys.argv[3]).read().split())
completed = int(sys.argv[4])
vs = d["vehicles"]
bps = sorted(v["bytes_per_s"] for v in vs.values())
print(f"  ground peer received {len(vs)} of {n} vehicles over {d['window_s']} s (peer CPU {d['peer_cpu_pct']} %)")
print(f"  bytes/s per vehicle (payload + attachment): median {bps[len(bps)//2]:,} (min {bps[0]:,}, max {bps[-1]:,}); "
      f"samples/s per vehicle median {sorted(v['samples_per_s'] for v in vs.values())[len(vs)//2]}")
for t, x in list(d["topics"].items())[:8]:
    print(f"    {t:18s} {x['hz']:6.1f} Hz  {x['bytes_per_sample']:5d} B/sample  {x['bytes_per_s']:7,} B/s per vehicle")
print(f"  imu/data_raw latency MCU sample → ground peer through two routers (site-A vehicles): "
      f"p50 {d['lat_p50_ms']} ms, p99 {d['lat_p99_ms']} ms")
ok = completed == n and len(vs) == n and n >= 12
print(f"ROW|7|Fleet on Zenoh: {n} vehicles (fcc-sitl + fcc-bridge + fcc-mission each, Zenoh clients) through two "
      f"linked fcc-zenoh-routers, ground peer (eclipse-zenoh) at the second site; default rates "
      f"(tests/zenoh/bench_fleet.sh)|{completed} of {n} missions completed, all {len(vs)} heard; per vehicle: bridge "
      f"{bridge:.1f} % + mission {mission:.1f} % of one core (simulator {sitl:.1f} %), "
      f"{bps[len(bps)//2] / 1000:.0f} kB/s; routers {ra:.1f} % and {rb:.1f} %; latency MCU sample → ground peer "
      f"through both routers p50 {d['lat_p50_ms']} ms, p99 {d['lat_p99_ms']} ms|—|—|≥ 12 vehicles on this 2-core "
      f"machine|{'met' if ok else '**missed**'}")
print("FLEET_BENCH " + json.dumps({"vehicles": n, "received": len(vs), "bytes_per_s_median": bps[len(bps)//2],
      "lat_p50_ms": d["lat_p50_ms"], "lat_p99_ms": d["lat_p99_ms"]}))
EOF
if [ -n "${FCC_E2E_KEEP:-}" ]; then mkdir -p "$FCC_E2E_KEEP"; cp "$tmp"/*.log "$tmp"/peer.* "$cfg" "$FCC_E2E_KEEP/" 2>/dev/null || true; fi
