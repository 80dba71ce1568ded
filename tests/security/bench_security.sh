#!/usr/bin/env bash
# Benchmark (not a test): what ROS 2 security costs the bridge (issue 19), security off vs on in
# the same run. fcc-fake-mcu (pty, the firmware's default rates, IMU at N Hz) → fcc-bridge →
# Debian's Cyclone DDS 0.10 through its Python binding (.venv-sec, scripts/security-setup.sh),
# the latency peer of row 4 (tests/dds/latency_peer.py), all in ONE loopback-only namespace.
# "on": ROS_SECURITY_ENABLE=true, Enforce, the bridge in enclave /fcc/fcc_bridge and the peer in
# /ground_station of a fresh `fcc-keystore create` (governance: discovery and data encrypted
# with AES-GCM, RTPS signed; a peer with security receives only from an authenticated bridge, one
# without only from a bridge without). "off": the same binaries and peer without security. Runs are
# interleaved (off, on, off, on at 500 Hz, then at 200 Hz) so load drifts hit both alike.
# Prints human lines and `ROW|4d|…`, `ROW|4e|…` for scripts/bench.sh.
#   usage: tests/security/bench_security.sh   (~2 min)
# Needs: cargo build --release -p fcc_bridge (fcc-bridge, fcc-fake-mcu, fcc-keystore).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="$root/.venv-sec/bin/python"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0"
bin="${FCC_BIN_DIR:-$root/target/release}"
warm="${FCC_BENCH_WARMUP:-3}"
secs="${FCC_BENCH_SECONDS:-10}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
export PYTHONPATH="$root/tests/dds:$here"
ks="$tmp/keystore"
"$bin/fcc-keystore" create "$ks" > /dev/null
peer_xml=$("$py" -c 'import sys; from keystore_peer import security_xml; print(security_xml(sys.argv[1]))' \
  "$ks/enclaves/ground_station")

# run LABEL SECURITY(on|off) IMU_HZ → $tmp/LABEL.json (the peer's RESULT)
run() {
  local label=$1 sec=$2 hz=$3
  local dur; dur=$(awk -v w="$warm" -v s="$secs" 'BEGIN{print w + s + 20}')
  "$bin/fcc-fake-mcu" --firmware-rates --imu-counter --imu-hz "$hz" --duration "$dur" \
    > "$tmp/$label.pty" 2> "$tmp/$label.fake" &
  local fake=$!
  for _ in $(seq 50); do grep -qs '^PTY' "$tmp/$label.pty" && break; sleep 0.1; done
  local pty; pty="$(awk '/^PTY/{print $2}' "$tmp/$label.pty")"
  local -a env_b=(env -u ROS_SECURITY_ENABLE) env_p=(env -u CYCLONEDDS_URI)
  if [ "$sec" = on ]; then
    env_b=(env ROS_SECURITY_ENABLE=true ROS_SECURITY_STRATEGY=Enforce ROS_SECURITY_KEYSTORE="$ks")
    env_p=(env CYCLONEDDS_URI="$peer_xml")
  fi
  "${env_b[@]}" "$bin/fcc-bridge" --device "$pty" --ros-args -r __ns:=/fcc \
    --enclave /fcc/fcc_bridge -p clock_source:=sync > "$tmp/$label.bridge" 2>&1 &
  local bridge=$!
  "${env_p[@]}" "$py" "$root/tests/dds/latency_peer.py" --rate "$hz" --warmup "$warm" \
    --seconds "$secs" --bridge-pid "$bridge" --wait 40 > "$tmp/$label.peer" 2>&1 || true
  kill -TERM "$bridge" 2>/dev/null || true; wait "$bridge" 2>/dev/null || true
  kill -TERM "$fake" 2>/dev/null || true; wait "$fake" 2>/dev/null || true
  sed -n 's/^RESULT //p' "$tmp/$label.peer" > "$tmp/$label.json"
  if [ ! -s "$tmp/$label.json" ]; then
    echo "{\"error\": \"peer printed no result\"}" > "$tmp/$label.json"
    echo "--- $label: peer output"; tail -5 "$tmp/$label.peer"
    echo "--- bridge log"; tail -5 "$tmp/$label.bridge"
  fi
  echo "$label (security $sec, IMU $hz Hz, ${secs} s): $(cat "$tmp/$label.json")"
}

load0=$(cut -d' ' -f1 /proc/loadavg)
echo "== security cost: fake MCU → fcc-bridge → Cyclone DDS 0.10 (Debian), security off vs on"
for i in 1 2; do
  run "off500_$i" off 500; run "on500_$i" on 500
done
for i in 1 2; do
  run "off200_$i" off 200; run "on200_$i" on 200
done
load1=$(cut -d' ' -f1 /proc/loadavg)
"$py" - "$tmp" "$load0" "$load1" "$(nproc)" <<'EOF'
import json, os, statistics, sys
tmp, load0, load1, ncpu = sys.argv[1:5]

def runs(prefix):
    out = []
    for i in (1, 2):
        try:
            r = json.load(open(os.path.join(tmp, f"{prefix}_{i}.json")))
        except Exception as e:  # noqa: BLE001
            r = {"error": str(e)}
        if "error" not in r and r.get("received", 0) > 0:
            out.append(r)
    return out

R = {k: runs(k) for k in ("off500", "on500", "off200", "on200")}
med = lambda rs, k: statistics.median(r[k] for r in rs)  # noqa: E731
if R["off500"] and R["on500"]:
    off, on = R["off500"], R["on500"]
    f = lambda rs: (f"p50 {med(rs, 'lat_p50_ms'):.2f} / p99 {med(rs, 'lat_p99_ms'):.2f} ms, "  # noqa: E731
                    f"{sum(r['missed'] for r in rs)} lost")
    ratio = med(on, "lat_p99_ms") / med(off, "lat_p99_ms")
    print(f"ROW|4d|Bridge with ROS 2 security (SROS2, AES-GCM) vs without: latency link frame → Debian Cyclone DDS 0.10 "
          f"peer at 500 Hz IMU, same run|on: {f(on)}|off: {f(off)}|p99 on/off {ratio:.2f}×|— (cost, for information)|info")
else:
    print(f"ROW|4d|Bridge with ROS 2 security vs without: latency|failed ({R})|—|—|—|not measured")
if R["off200"] and R["on200"]:
    off, on = R["off200"], R["on200"]
    c5 = ""
    if R["off500"] and R["on500"] and all(r.get("cpu_pct") is not None for r in R["off500"] + R["on500"]):
        c5 = f"; at 500 Hz IMU on {med(R['on500'], 'cpu_pct'):.1f} % vs off {med(R['off500'], 'cpu_pct'):.1f} %"
    print(f"ROW|4e|Bridge CPU with ROS 2 security vs without, default link rates (IMU 200 Hz), utime+stime / wall, "
          f"same run|on: {med(on, 'cpu_pct'):.1f} % of one core|off: {med(off, 'cpu_pct'):.1f} %|"
          f"on/off {med(on, 'cpu_pct') / med(off, 'cpu_pct'):.2f}×{c5}|— (cost, for information)|info")
else:
    print(f"ROW|4e|Bridge CPU with ROS 2 security vs without|failed|—|—|—|not measured")
print(f"NOTE|4d|Security off vs on, interleaved (off, on, off, on) at 500 Hz then 200 Hz, {len(R['on500'])}+"
      f"{len(R['on200'])} secure and {len(R['off500'])}+{len(R['off200'])} plain runs, medians; each run a fresh "
      f"bridge, fake MCU and peer, 3 s warm-up then a 10 s window; the peer is Debian's Cyclone DDS 0.10 with its "
      f"security plugins in enclave /ground_station. Load average {load0} → {load1} on {ncpu} cores. "
      f"Source: tests/security/bench_security.sh.")
EOF
