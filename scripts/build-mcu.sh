#!/usr/bin/env bash
# Cross-build the flight-control image for the TM4C1294 (Cortex-M4F, thumbv7em-none-eabihf) and
# check it fits: 1024 KB flash, 256 KB RAM.
#   usage: scripts/build-mcu.sh            (installs what it needs with apt-get when missing)
# Toolchain: rustup's target when present (`rustup target add thumbv7em-none-eabihf`), else
# Debian's rustc-web/cargo-web 1.96 with the std sources, building core with -Zbuild-std.
# Env: MCU_SKIP_INSTALL=1 to never call apt-get; MCU_OFFLINE=1 to build with --offline.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
BOARD=$ROOT/fcc_firmware/board
TARGET=thumbv7em-none-eabihf
FLASH_KB=1024
RAM_KB=256
# Reserve for the main stack when checking RAM (cortex-m-rt puts it at the top of RAM).
STACK_RESERVE_KB=${MCU_STACK_RESERVE_KB:-32}

need_pkgs=()
[ -x /usr/bin/rustc ] && /usr/bin/rustc --print target-list 2>/dev/null | grep -qx $TARGET || need_pkgs+=(rustc-web)
[ -d /usr/lib/rustlib/src/rust/library/core ] || need_pkgs+=(rust-web-src)
[ -x /usr/bin/cargo ] || need_pkgs+=(cargo-web)
command -v arm-none-eabi-ld >/dev/null || need_pkgs+=(binutils-arm-none-eabi)
if [ "${MCU_WITH_QEMU:-0}" = 1 ]; then command -v qemu-system-arm >/dev/null || need_pkgs+=(qemu-system-arm); fi
if [ ${#need_pkgs[@]} -gt 0 ]; then
  if [ "${MCU_SKIP_INSTALL:-0}" = 1 ]; then echo "build-mcu.sh: missing ${need_pkgs[*]}" >&2; exit 1; fi
  echo "build-mcu.sh: installing ${need_pkgs[*]}" >&2
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO=sudo
  $SUDO apt-get update -qq >/dev/null
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${need_pkgs[@]}" >/dev/null
fi

export RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1
CARGO=/usr/bin/cargo
offline=(); [ "${MCU_OFFLINE:-0}" = 1 ] && offline=(--offline)
xbuild() { (cd "$BOARD" && $CARGO build "${offline[@]}" --release -Zbuild-std=core --target $TARGET "$@"); }

echo "build-mcu.sh: building fcc-board for $TARGET ($($RUSTC -V))" >&2
xbuild --features tm4c --bin fcc-board
ELF=$BOARD/target/$TARGET/release/fcc-board

# Size: flash = vectors + text + rodata + initialised data image; RAM = data + bss (+ stack).
read -r text data bss _ < <(arm-none-eabi-size "$ELF" | awk 'NR==2{print $1, $2, $3, $4}')
flash=$((text + data)); ram=$((data + bss))
ram_with_stack=$((ram + STACK_RESERVE_KB * 1024))
pct() { awk -v a="$1" -v b="$2" 'BEGIN{printf "%.1f", 100*a/(b*1024)}'; }
arm-none-eabi-size -A "$ELF" | awk '$1 ~ /^\./ && $2 > 0 {printf "  %-14s %8d B\n", $1, $2}'
echo "image: $ELF"
echo "flash: $flash B of ${FLASH_KB} KB ($(pct $flash $FLASH_KB)%)  [TM4C1294NCPDT]"
echo "RAM:   $ram B static + ${STACK_RESERVE_KB} KB stack reserve = $ram_with_stack B of ${RAM_KB} KB ($(pct $ram_with_stack $RAM_KB)%)"

# f64 on a single-precision FPU is software: list the image's functions that call the EABI
# double-precision helpers (lat/lon geodesy is the allowed user).
objdump=arm-none-eabi-objdump
if command -v $objdump >/dev/null; then
  $objdump -d --no-show-raw-insn -C "$ELF" > "$BOARD/target/fcc-board.dis"
  echo "functions calling software double-precision helpers (__aeabi_d*, f64):"
  awk '/^[0-9a-f]+ <.*>:$/ {fn=$0; sub(/^[0-9a-f]+ </,"",fn); sub(/>:$/,"",fn)}
       /bl.*<__aeabi_(d|l2d|ul2d|i2d|ui2d|f2d|d2f)/ && fn !~ /^__aeabi|^compiler_builtins/ {print "  " fn}' \
    "$BOARD/target/fcc-board.dis" | sort | uniq -c | sort -rn | head -20
  echo "functions calling core::panicking (panic paths left in the image):"
  awk '/^[0-9a-f]+ <.*>:$/ {fn=$0; sub(/^[0-9a-f]+ </,"",fn); sub(/>:$/,"",fn)}
       /bl.*<core::panicking|bl.*<core::option::unwrap_failed|bl.*<core::slice::index/ {print "  " fn}' \
    "$BOARD/target/fcc-board.dis" | sort | uniq -c | sort -rn | head -20
fi

if [ $flash -gt $((FLASH_KB * 1024)) ] || [ $ram_with_stack -gt $((RAM_KB * 1024)) ]; then
  echo "build-mcu.sh: OVER BUDGET" >&2
  exit 1
fi
echo "build-mcu.sh: within budget"
