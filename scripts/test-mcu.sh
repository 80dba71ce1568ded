#!/usr/bin/env bash
# The flight core on an emulated Cortex-M4F: record a flight on the host (SITL physics + sensor
# models, host build of the core), replay its inputs through the same core cross-built for
# thumbv7em-none-eabihf in QEMU (mps2-an386, -icount shift=0: 1 instruction = 1 ns), compare the
# motor commands with the host build's, and print instructions per 500 Hz step and the share of
# the 240,000-cycle budget (120 MHz / 500 Hz).
#   usage: scripts/test-mcu.sh [SECONDS]   (default 16 s of flight = 8000 steps)
# Exit 0 only if every step's outputs match within MCU_TOLERANCE (default 1e-5).
# Cost on a fresh state (November 2026, this project's 2-core machine, shared: load average ~8):
# apt-get install of the cross toolchain + QEMU 36 s (with apt-get update ~45 s); then, with an
# empty fcc_firmware/board/target and an empty cargo registry, this script 567 s (crate
# downloads, -Zbuild-std cross builds of both images, the host SITL recorder, 1 s of QEMU);
# incremental re-runs ~30 s. scripts/test.sh runs it as its "MCU" step.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
BOARD=$ROOT/fcc_firmware/board
TARGET=thumbv7em-none-eabihf
SECONDS_FLOWN=${1:-16}
TOL=${MCU_TOLERANCE:-1e-5}
BUDGET=240000

# 1. Toolchain, QEMU, and the board image with its size check.
MCU_WITH_QEMU=1 scripts/build-mcu.sh

offline=(); [ "${MCU_OFFLINE:-0}" = 1 ] && offline=(--offline)
# 2. Record on the host (the host's default cargo/rustc; falls back to Debian's).
# The board crate's release profile is the image's (fat LTO, one codegen unit, full debug info);
# the host tools need none of it, and it made their build the longest part of this step. Rust
# neither contracts nor reorders f32 arithmetic, so they compute the same bits either way (the
# QEMU comparison below would tell).
HOST_CARGO=cargo; command -v cargo >/dev/null || HOST_CARGO=/usr/bin/cargo
host_profile=(CARGO_PROFILE_RELEASE_LTO=false CARGO_PROFILE_RELEASE_CODEGEN_UNITS=16 CARGO_PROFILE_RELEASE_DEBUG=line-tables-only)
(cd "$BOARD" && env -u RUSTC -u RUSTC_BOOTSTRAP "${host_profile[@]}" $HOST_CARGO run "${offline[@]}" -q --release --features host --bin record -- "$SECONDS_FLOWN" data)
(cd "$BOARD" && env -u RUSTC -u RUSTC_BOOTSTRAP "${host_profile[@]}" $HOST_CARGO build "${offline[@]}" -q --release --features std --bin compare)

# 3. The QEMU image (embeds data/inputs.bin and data/expected.bin).
(cd "$BOARD" && RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1 /usr/bin/cargo build "${offline[@]}" -q --release \
  -Zbuild-std=core --target $TARGET --features qemu --bin qemu-replay)
ELF=$BOARD/target/$TARGET/release/qemu-replay
echo "qemu-replay image (text/data/bss incl. $(stat -c %s "$BOARD/data/inputs.bin") B recording):"
arm-none-eabi-size "$ELF" | sed 's/^/  /'

# 4. Run it.
OUT=$BOARD/target/qemu-replay.out
t0=$(date +%s.%N)
timeout 600 qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -nographic -monitor none \
  -semihosting-config enable=on,target=native -icount shift=0 -kernel "$ELF" > "$OUT" 2>&1 \
  || { echo "test-mcu.sh: QEMU run failed"; grep -v '^M ' "$OUT" | tail -20; exit 1; }
t1=$(date +%s.%N)
grep -v '^M ' "$OUT" | sed 's/^/qemu: /'
echo "qemu wall time: $(awk -v a=$t0 -v b=$t1 'BEGIN{printf "%.1f s", b-a}')"

# 5. Figures and comparison.
awk -v B=$BUDGET '/^STEP/ {
  for (i = 1; i <= NF; i++) { if ($i == "mean") m[++k] = $(i+1); if ($i == "max") x[++j] = $(i+1) }
  printf "per 500 Hz step (all ticks):   mean %d insns (%.1f%% of %d cycles), max %d (%.1f%%)\n", m[1], 100*m[1]/B, B, x[1], 100*x[1]/B
  printf "per 500 Hz step (armed ticks): mean %d insns (%.1f%%), max %d (%.1f%%)\n", m[2], 100*m[2]/B, x[2], 100*x[2]/B
}
/^LINK/ {
  for (i = 1; i <= NF; i++) { if ($i == "mean") lm = $(i+1); if ($i == "max" && !lx) lx = $(i+1); if ($i == "bytes/tick;") lb = $(i-1) }
  tot = $NF; if (tot == "insns") tot = $(NF-1)
  printf "link TX after each step (poll_tx, %s B/tick): mean %d insns (%.1f%%), max %d; step + link worst tick %d insns (%.1f%%)\n", lb, lm, 100*lm/B, lx, tot, 100*tot/B
}
/^TICK/ {
  for (i = 1; i <= NF; i++) { if ($i == "mean") tm = $(i+1); if ($i == "max") tx = $(i+1) }
  printf "whole tick (FlightComputer::tick: link in, step, link out): mean %d insns (%.1f%%), max %d (%.1f%%)\n", tm, 100*tm/B, tx, 100*tx/B
}' "$OUT"
echo "(instructions, not cycles: on the TM4C129 at 120 MHz expect roughly 1.2-2 cycles per instruction with flash wait states)"
"$BOARD/target/release/compare" "$OUT" "$BOARD/data/expected.bin" "$TOL"
