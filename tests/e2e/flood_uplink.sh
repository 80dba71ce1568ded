#!/usr/bin/env bash
# Uplink budget under a setpoint flood (issue 14), in ONE loopback-only network namespace:
# fake MCU (pty, logs what it receives with CLOCK_MONOTONIC times) ⇄ fcc-wire-fault --baud 921600
# (a 921600-baud line: each direction at most 92,160 B/s; what does not fit waits in the pty)
# ⇄ fcc-bridge ⇄ a Cyclone DDS peer (flood_uplink.py) that publishes valid setpoints at 10 kHz
# for 6 s and a cmd/mode land/hold every 0.5 s during it. Goals: every land/hold at the MCU
# ≤ 100 ms after the peer's write (monotonic stamps of both processes, the one time limit of
# the test), uplink ≤ 25 % of the line with ≤ 1 KB waiting, ≤ 101 setpoints/s at the MCU.
#   usage: tests/e2e/flood_uplink.sh [PYTHON]   (PYTHON with cyclonedds)
# Needs: cargo build --release -p fcc_bridge -p fcc_tests --bins. Takes ~20 s.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
bridge_bin="${FCC_FLOOD_BRIDGE:-$bin/fcc-bridge}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
"$bin/fcc-fake-mcu" --duration 120 --log "$tmp/mcu.jsonl" > "$tmp/fake.out" 2> "$tmp/fake.err" &
for _ in $(seq 50); do grep -q '^PTY' "$tmp/fake.out" && break; sleep 0.1; done
pty="$(awk '/^PTY/{print $2}' "$tmp/fake.out")"
"$bin/fcc-wire-fault" --mcu "$pty" --link "$tmp/link.tty" --ber 0 --baud 921600 \
  --stats "$tmp/relay.jsonl" > "$tmp/relay.out" 2>&1 &
relay=$!
for _ in $(seq 50); do [ -e "$tmp/link.tty" ] && break; sleep 0.1; done
"$bridge_bin" --device "$tmp/link.tty" --ros-args -r __ns:=/fcc > "$tmp/bridge.log" 2>&1 &
bridge=$!
rc=0
PYTHONPATH="$root/tests/dds" "$py" "$here/flood_uplink.py" --mcu-log "$tmp/mcu.jsonl" \
  --relay-stats "$tmp/relay.jsonl" ${FCC_FLOOD_ARGS:-} || rc=1
kill -INT "$bridge" 2>/dev/null || true; wait "$bridge" 2>/dev/null || true
kill -TERM "$relay" 2>/dev/null || true; wait "$relay" 2>/dev/null || true
grep '^wire-fault:' "$tmp/relay.out" || true
if [ $rc -ne 0 ]; then echo "--- bridge log (last 20 lines, cut)"; tail -20 "$tmp/bridge.log" | cut -c1-300; fi
exit $rc
