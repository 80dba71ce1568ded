# Sourced by the test scripts after `loopback_only`: sets `bin` (the release binaries, or
# $FCC_BIN_DIR) and `tmp` (a scratch directory removed at exit, with every background job
# killed). Needs `$root`.
bin="${FCC_BIN_DIR:-$root/target/release}"
tmp="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$tmp"' EXIT
