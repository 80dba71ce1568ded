# Sourced by the test scripts that run the bridge against the scripted fake MCU:
# `. "$root/tests/lib/fake_mcu.sh"` after `loopback_only`, then `start_fake_mcu SECONDS [ARGS…]`.
# Sets `bin` (the release binaries, or $FCC_BIN_DIR), `tmp` (a scratch directory removed at exit,
# with every background job killed) and `pty` (the fake MCU's serial device); the fake MCU's
# stdout is "$tmp/fake.out", its stderr "$tmp/fake.err". Needs `$root`.
. "$root/tests/lib/scratch.sh"
start_fake_mcu() {
  local secs="$1"; shift
  "$bin/fcc-fake-mcu" --duration "$secs" "$@" > "$tmp/fake.out" 2> "$tmp/fake.err" &
  for _ in $(seq 50); do grep -qs '^PTY' "$tmp/fake.out" && break; sleep 0.1; done
  pty="$(awk '/^PTY/{print $2}' "$tmp/fake.out")"
  [ -n "$pty" ] || { echo "fake MCU gave no PTY: $(head -c 300 "$tmp/fake.err")" >&2; exit 1; }
}
