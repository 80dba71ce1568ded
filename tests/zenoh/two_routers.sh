#!/usr/bin/env bash
# Two linked fcc-zenoh-routers (A on 7447; B on 7448, connected to A) and the Python rmw_zenoh peer:
# its talker on B, its listener on A, so the message and the liveliness tokens cross the link.
# Run inside a private network namespace:
#   /work/shared/tools/netns-run tests/zenoh/two_routers.sh [ROUTER_BIN] [PYTHON]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
router=${1:-${CARGO_TARGET_DIR:-target}/release/fcc-zenoh-router}
python=${2:-python3}
log=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; }
trap cleanup EXIT

# Starts a router in the background; waits for its "listening" line.
start_router() {
  local name=$1; shift
  "$router" "$@" >"$log/$name.out" 2>"$log/$name.err" &
  pids+=($!)
  for _ in $(seq 100); do
    grep -q 'listening on' "$log/$name.out" && { echo "router $name: $(cat "$log/$name.out")"; return; }
    kill -0 "${pids[-1]}" 2>/dev/null || break
    sleep 0.1
  done
  echo "router $name did not start:"; cat "$log/$name.err"; exit 1
}

start_router A --listen tcp/127.0.0.1:7447
start_router B --listen tcp/127.0.0.1:7448 --connect tcp/127.0.0.1:7447
"$python" "$here/zenoh_ros.py" --selftest --connect tcp/127.0.0.1:7448 \
  --echo-connect tcp/127.0.0.1:7447
# Both routers stop on SIGTERM with exit 0.
for p in "${pids[@]}"; do kill -TERM "$p"; done
for p in "${pids[@]}"; do wait "$p"; done
pids=()
echo "routers stopped cleanly"
