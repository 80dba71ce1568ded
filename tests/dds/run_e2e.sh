#!/usr/bin/env bash
# End-to-end: fake MCU (pty) ⇄ fcc-bridge ⇄ Cyclone DDS peer, all in ONE loopback-only network
# namespace (processes must share it to discover each other).
#   usage: tests/dds/run_e2e.sh [PYTHON]     (PYTHON must have `cyclonedds`; default python3)
# Needs: cargo build --release -p fcc_bridge. Runs itself under netns-run if not inside one.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
bin="${FCC_BIN_DIR:-$root/target/release}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
"$bin/fcc-fake-mcu" --duration 40 --log "$tmp/mcu.jsonl" > "$tmp/fake.out" 2> "$tmp/fake.err" &
for _ in $(seq 50); do grep -q '^PTY' "$tmp/fake.out" && break; sleep 0.1; done
pty="$(awk '/^PTY/{print $2}' "$tmp/fake.out")"
RUST_LOG=info "$bin/fcc-bridge" --device "$pty" --ros-args -r __ns:=/fcc > "$tmp/bridge.log" 2>&1 &
bridge=$!
set +e
PYTHONPATH="$here" "$py" "$here/peer.py" --mcu-log "$tmp/mcu.jsonl" --seconds 6
rc=$?
set -e
if ! kill -0 "$bridge" 2>/dev/null; then echo "fcc-bridge died:"; cat "$tmp/bridge.log"; rc=1; fi
if [ $rc -ne 0 ]; then echo "--- bridge log"; tail -30 "$tmp/bridge.log"; fi

# Handshake mismatch: the bridge must exit 2 with one readable line.
"$bin/fcc-fake-mcu" --duration 10 --schema-hash 0xdeadbeef > "$tmp/fake2.out" 2>/dev/null &
for _ in $(seq 50); do grep -q '^PTY' "$tmp/fake2.out" && break; sleep 0.1; done
pty2="$(awk '/^PTY/{print $2}' "$tmp/fake2.out")"
set +e
timeout 10 "$bin/fcc-bridge" --device "$pty2" > "$tmp/bridge2.log" 2>&1
rc2=$?
set -e
msg="$(grep '^fcc-bridge:' "$tmp/bridge2.log" || true)"
if [ $rc2 -eq 2 ] && echo "$msg" | grep -q 'schema mismatch'; then
  echo "PASS schema mismatch → exit 2: $msg"
else
  echo "FAIL schema mismatch: exit $rc2, '$msg'"; cat "$tmp/bridge2.log"; rc=1
fi
exit $rc
