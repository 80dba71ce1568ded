# Sourced by the test scripts that start DDS: `. "$root/tests/lib/loopback_only.sh"` then
# `loopback_only "$0" ARGS...` as the script's first action. Outside a private network namespace
# it re-executes the script (with ARGS) under ../shared/tools/netns-run (loopback only), so DDS
# discovery never leaves the machine; inside, it refuses to go on if any interface but `lo`
# exists. Needs `$root` (the repository root). Exit 3 when neither holds.
loopback_only() {
  local me
  me="$(basename "$1")"
  if [ -z "${FCC_IN_NETNS:-}" ]; then
    local c
    for c in "$root/../shared/tools/netns-run" /work/shared/tools/netns-run; do
      if [ -x "$c" ]; then exec env FCC_IN_NETNS=1 "$c" "$@"; fi
    done
    echo "$me: netns-run not found; refusing to run DDS outside a loopback-only namespace" >&2
    exit 3
  fi
  if ip -o link show | awk -F': ' '{print $2}' | grep -qv '^lo$'; then
    echo "$me: not in a loopback-only namespace; refusing" >&2
    exit 3
  fi
}
