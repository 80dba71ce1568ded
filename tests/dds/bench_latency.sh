#!/usr/bin/env bash
# Benchmark (not a test): the bridge's frame → peer latency, CPU use and loss-free frame rate.
#   fcc-fake-mcu (pty, the firmware's default link rates, IMU at N Hz) → fcc-bridge
#   (clock_source:=sync) → independent Cyclone DDS peer (tests/dds/latency_peer.py),
# all in ONE loopback-only network namespace. Latency = peer arrival (realtime clock) − header
# stamp (the fake's frame time, mapped to the realtime clock by the bridge's time sync). CPU =
# the bridge's utime+stime over the window / wall. Runs: default rates (IMU 200 Hz, for CPU),
# IMU 500 Hz (latency), then 1000, 2000, 4000 Hz (loss) — about 75 s.
# Prints human lines and `ROW|4|…`, `ROW|4b|…`, `ROW|4c|…`, `NOTE|4|…` for scripts/bench.sh.
#   usage: tests/dds/bench_latency.sh [PYTHON]   (PYTHON must import cyclonedds)
#   FCC_BENCH_ONLY_CPU=1: only the default and 500 Hz runs (rows 4 and 4b; 4c not measured).
#   FCC_BENCH_THREADS=1: also print the bridge's context switches and CPU per thread (from
#     /proc/PID/task/*, over 6 s starting warm-up + 2 s after the bridge starts) for each run.
# Needs: cargo build --release -p fcc_bridge (fcc-bridge, fcc-fake-mcu).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
warm="${FCC_BENCH_WARMUP:-3}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
export PYTHONPATH="$here"

# run LABEL IMU_HZ SECONDS → $tmp/LABEL.json (the peer's RESULT), $tmp/LABEL.fake (fake's stderr)
run() {
  local label=$1 hz=$2 secs=$3
  local dur; dur=$(awk -v w="$warm" -v s="$secs" 'BEGIN{print w + s + 15}')
  "$bin/fcc-fake-mcu" --firmware-rates --imu-counter --imu-hz "$hz" --duration "$dur" > "$tmp/$label.pty" 2> "$tmp/$label.fake" &
  local fake=$!
  for _ in $(seq 50); do grep -qs '^PTY' "$tmp/$label.pty" && break; sleep 0.1; done
  local pty; pty="$(awk '/^PTY/{print $2}' "$tmp/$label.pty")"
  "$bin/fcc-bridge" --device "$pty" --ros-args -r __ns:=/fcc -p clock_source:=sync > "$tmp/$label.bridge" 2>&1 &
  local bridge=$!
  local sampler=
  if [ -n "${FCC_BENCH_THREADS:-}" ]; then
    (sleep "$(awk -v w="$warm" 'BEGIN{print w + 2}')"; thread_stats "$bridge" 6 > "$tmp/$label.threads") &
    sampler=$!
  fi
  "$py" "$here/latency_peer.py" --rate "$hz" --warmup "$warm" --seconds "$secs" --bridge-pid "$bridge" \
    > "$tmp/$label.peer" 2>&1 || true
  if [ -n "$sampler" ]; then wait "$sampler" || true; fi
  kill -TERM "$bridge" 2>/dev/null || true; wait "$bridge" 2>/dev/null || true
  kill -TERM "$fake" 2>/dev/null || true; wait "$fake" 2>/dev/null || true
  sed -n 's/^RESULT //p' "$tmp/$label.peer" > "$tmp/$label.json"
  if [ ! -s "$tmp/$label.json" ]; then
    echo "{\"error\": \"peer printed no result\"}" > "$tmp/$label.json"
    echo "--- $label: peer output"; tail -5 "$tmp/$label.peer"; echo "--- bridge log"; tail -5 "$tmp/$label.bridge"
  fi
  echo "$label (IMU $hz Hz, ${secs} s): $(cat "$tmp/$label.json")"
  if [ -s "$tmp/$label.threads" ]; then cat "$tmp/$label.threads"; fi
}

# thread_stats PID SECONDS: per thread of PID, context switches per second (voluntary +
# involuntary) and CPU % of one core over SECONDS.
thread_stats() {
  local pid=$1 secs=$2
  snap() {
    local t
    for t in /proc/"$pid"/task/*; do
      awk -v tid="${t##*/}" '/^Name:/{n=$2} /^voluntary_ctxt_switches:/{v=$2}
        /^nonvoluntary_ctxt_switches:/{w=$2} END{printf "%s %s %s %s", tid, n, v, w}' "$t/status" 2>/dev/null
      awk '{s=$0; sub(/^.*\) /, "", s); split(s, f, " "); printf " %d\n", f[12] + f[13]}' "$t/stat" 2>/dev/null
    done
  }
  snap > "$tmp/snap0.$pid"; sleep "$secs"; snap > "$tmp/snap1.$pid"
  awk -v secs="$secs" -v tck="$(getconf CLK_TCK)" 'NR==FNR{v[$1]=$3; w[$1]=$4; c[$1]=$5; next}
    ($1 in v){dv=($3-v[$1])/secs; dw=($4-w[$1])/secs; dc=100*($5-c[$1])/tck/secs; tv+=dv; tw+=dw; tc+=dc
      if (dv+dw >= 1 || dc > 0) printf "  thread %-16s %7.0f vol/s %6.0f invol/s %5.1f %%\n", $2, dv, dw, dc}
    END{printf "  threads total      %7.0f vol/s %6.0f invol/s %5.1f %%\n", tv, tw, tc}' \
    "$tmp/snap0.$pid" "$tmp/snap1.$pid"
}

load0=$(cut -d' ' -f1 /proc/loadavg)
echo "== bridge latency bench: fake MCU (firmware default rates) → fcc-bridge → Cyclone DDS peer"
run default 200 10
run r500 500 10
if [ -z "${FCC_BENCH_ONLY_CPU:-}" ]; then
  for hz in 1000 2000 4000; do run "r$hz" "$hz" 6; done
fi

load1=$(cut -d' ' -f1 /proc/loadavg)
"$py" - "$tmp" "$load0" "$load1" "$(nproc)" <<'EOF'
import json, os, sys
tmp, load0, load1, ncpu = sys.argv[1:5]
R = {}
for k in ("default", "r500", "r1000", "r2000", "r4000"):
    try:
        R[k] = json.load(open(os.path.join(tmp, k + ".json")))
    except Exception as e:  # noqa: BLE001
        R[k] = {"error": str(e)}

def ok(r):
    return "error" not in r and r.get("received", 0) > 0

r5, rd = R["r500"], R["default"]
if ok(r5):
    verdict = "met" if r5["lat_p99_ms"] <= 2.0 else "**missed**"
    ours = (f"p50 {r5['lat_p50_ms']:.2f} ms, p99 {r5['lat_p99_ms']:.2f} ms (max {r5['lat_max_ms']:.2f}); "
            f"{r5['received']} msgs, {r5['missed']} lost")
else:
    verdict, ours = "not measured", f"failed ({r5.get('error')})"
print(f"ROW|4|Bridge: latency link frame → independent DDS peer p50/p99 at 500 Hz IMU + 100 Hz state "
      f"(fake MCU on a pty → fcc-bridge → Cyclone DDS reliable reader)|{ours}|—|—|p99 ≤ 2 ms|{verdict}")
if ok(rd) and rd.get("cpu_pct") is not None:
    c5 = f"; {r5['cpu_pct']:.1f} % with the IMU at 500 Hz" if ok(r5) and r5.get("cpu_pct") is not None else ""
    # Issue 20's goal is at 500 Hz IMU (the busier case): both figures must be within it.
    worst = max(rd["cpu_pct"], r5["cpu_pct"] if c5 else float("inf"))
    verdict = "met" if worst <= 5.0 else "**missed**"
    print(f"ROW|4b|Bridge: CPU at the default link rates (IMU 200, nav 100, mag/baro/altitude 50, GPS/ranges/status 10, "
          f"battery 5 Hz) and with the IMU at 500 Hz, utime+stime / wall|{rd['cpu_pct']:.1f} % of one core{c5}|—|—|"
          f"≤ 5 % (both)|{verdict}")
else:
    print(f"ROW|4b|Bridge: CPU at the default link rates|failed ({rd.get('error')})|—|—|≤ 5 %|not measured")
if os.environ.get("FCC_BENCH_ONLY_CPU"):
    sys.exit(0)
tried = [(int(k[1:]), R[k]) for k in ("r500", "r1000", "r2000", "r4000")]
best = None
for hz, r in tried:
    if ok(r) and r["missed"] == 0 and r["rx_rate_hz"] > 0.97 * hz:
        best = hz
    else:
        break
desc = ", ".join(f"{hz} Hz: {r['missed']} lost of {r['missed'] + r['received']}, p99 {r['lat_p99_ms']:.2f} ms"
                 if ok(r) else f"{hz} Hz: failed" for hz, r in tried)
print(f"ROW|4c|Bridge: highest IMU frame rate with 0 loss (tried 500/1000/2000/4000 Hz, other streams at default rates)|"
      f"{('≥ ' + str(best) + ' Hz, the highest tried') if best == tried[-1][0] else (str(best) + ' Hz') if best else '< 500 Hz'} "
      f"({desc})|—|—|— (no goal; for information)|info")
if ok(r5):
    print(f"NOTE|4|Latency = peer arrival (CLOCK_REALTIME, right after the peer's WaitSet wakes) − header stamp; the "
          f"stamp is the fake MCU's frame time, taken just before it writes the frame to the pty, mapped to the "
          f"realtime clock by the bridge's ping/pong time sync (clock_source:=sync; error ≤ half the best round trip). "
          f"At 500 Hz, split by the DDS source timestamp: frame → bridge's write p50 {r5['bridge_p50_ms']:.3f} / "
          f"p99 {r5['bridge_p99_ms']:.3f} ms, DDS + Python peer p50 {r5['dds_peer_p50_ms']:.3f} / "
          f"p99 {r5['dds_peer_p99_ms']:.3f} ms. Reliable reader, {r5['window_s']:.0f} s windows after "
          f"a 3 s warm-up; loss counted from the IMU frame counter the fake puts in gyro x (--imu-counter). "
          f"Machine load while it ran: 1-min load average {load0} → {load1} on {ncpu} cores (fake MCU, bridge and "
          f"Python peer share them; concurrent work inflates the tails). Rates above ≈2 kHz exceed what a 921600-baud UART "
          f"carries (an IMU frame is ≈45 B); on the pty they test the bridge alone. Source: tests/dds/bench_latency.sh.")
EOF
