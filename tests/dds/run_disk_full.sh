#!/usr/bin/env bash
# Recording onto a full disk (issue 6 point 8): fake MCU (pty) ⇄ fcc-bridge --record BAG on a
# tiny filesystem (a 384 KiB tmpfs in a private mount namespace; if mounting is not possible, a
# 384 KiB file-size limit with SIGXFSZ ignored) ⇄ the independent Cyclone DDS peer. Expected:
# one clear one-line error on stderr and on /rosout, the bridge keeps running and publishing,
# and the bag written up to the error is readable by an independent MCAP reader.
#   usage: tests/dds/run_disk_full.sh [PYTHON]   (PYTHON with cyclonedds, mcap, mcap-ros2-support)
# Needs: cargo build --release -p fcc_bridge. Runs itself under netns-run if not inside one.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
py="${1:-${FCC_DDS_PYTHON:-python3}}"
. "$root/tests/lib/loopback_only.sh"
loopback_only "$0" "$py"
# A private mount namespace for the tiny tmpfs (nothing is mounted on the host).
# (FCC_DISK_FULL_MODE=rlimit skips it, to test the fallback.)
if [ -z "${FCC_IN_MNTNS:-}" ] && [ "${FCC_DISK_FULL_MODE:-}" != rlimit ] && unshare -m true 2>/dev/null; then
  exec env FCC_IN_MNTNS=1 unshare -m --propagation private "$0" "$py"
fi
bin="${FCC_BIN_DIR:-$root/target/release}"
tmp="$(mktemp -d)"
full="$tmp/full"
mkdir -p "$full"
mode="file-size limit (ulimit -f 384, SIGXFSZ ignored)"
if [ "${FCC_IN_MNTNS:-}" = 1 ] && mount -t tmpfs -o size=384k tmpfs "$full" 2>/dev/null; then
  mode="384 KiB tmpfs"
fi
cleanup() {
  kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true
  umount "$full" 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT
echo "disk full by: $mode"
"$bin/fcc-fake-mcu" --duration 60 > "$tmp/fake.out" 2> "$tmp/fake.err" &
for _ in $(seq 50); do grep -q '^PTY' "$tmp/fake.out" 2>/dev/null && break; sleep 0.1; done
pty="$(awk '/^PTY/{print $2}' "$tmp/fake.out")"
bag="$full/flight.mcap"
(
  trap '' XFSZ
  [ "$mode" = "384 KiB tmpfs" ] || ulimit -f 384
  exec "$bin/fcc-bridge" --device "$pty" --record "$bag" --ros-args -r __ns:=/fcc -p record_compression:=none
) > "$tmp/bridge.out" 2> "$tmp/bridge.err" &
bridge=$!
rc=0
set +e
PYTHONPATH="$here:$root/tests/mcap" "$py" "$here/disk_full_peer.py" --seconds 25
prc=$?
set -e
[ $prc -eq 0 ] || rc=1
if kill -0 "$bridge" 2>/dev/null; then
  echo "PASS bridge still running after the write error"
else
  echo "FAIL bridge died"; rc=1
fi
# While running (before the exit summary, which repeats the outcome): exactly one error line.
errs="$(grep -c 'recording to .* stopped' "$tmp/bridge.err" || true)"
line="$(grep -m1 'recording to .* stopped' "$tmp/bridge.err")"
if [ "$errs" = 1 ] && echo "$line" | grep -qE 'No space left on device|File too large'; then
  echo "PASS one error line on stderr, naming the cause: $line"
else
  echo "FAIL stderr: $errs error line(s) naming the recording (want 1, with the OS cause); stderr tail:"
  tail -5 "$tmp/bridge.err"; rc=1
fi
kill -INT "$bridge"; set +e; wait "$bridge"; brc=$?; set -e
[ "$brc" = 0 ] && echo "PASS bridge exits 0 on SIGINT after the error" || { echo "FAIL bridge exit $brc on SIGINT"; rc=1; }
ls -l "$bag" 2>/dev/null | awk '{print "bag on the full filesystem: " $5 " bytes"}' || true
if ! "$py" -c "import mcap, mcap_ros2.decoder" 2>/dev/null; then
  if [ "${FCC_REQUIRE_DDS_PEER:-}" = 1 ]; then echo "FAIL $py cannot import mcap, mcap_ros2"; rc=1
  else echo "SKIPPED the bag check: $py lacks mcap / mcap-ros2-support"; fi
  echo "disk-full: $( [ $rc -eq 0 ] && echo all passed || echo FAILED )"
  exit $rc
fi
set +e
PYTHONPATH="$root/tests/mcap" "$py" - "$bag" <<'PY'
import sys
from check_bag import read_truncated
counts, last, err = read_truncated(sys.argv[1])
n = sum(counts.values())
print(f"bag up to the error: {n} messages on {len(counts)} topics decoded by mcap + mcap_ros2 "
      f"(stream reader stopped at: {err})")
print(("PASS" if n > 100 and "/fcc/imu/data_raw" in counts else "FAIL") + " the bag up to the error is readable")
sys.exit(0 if n > 100 else 1)
PY
[ $? -eq 0 ] || rc=1
set -e
echo "disk-full: $( [ $rc -eq 0 ] && echo all passed || echo FAILED )"
exit $rc
