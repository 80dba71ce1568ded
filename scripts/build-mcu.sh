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
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -o DPkg::Lock::Timeout=600 -y -qq --no-install-recommends "${need_pkgs[@]}" >/dev/null
fi
# MCU_INSTALL_ONLY=1: the toolchain only (scripts/test.sh installs it first, then runs the builds
# beside its other steps).
[ "${MCU_INSTALL_ONLY:-0}" = 1 ] && exit 0

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

# f64 on a single-precision FPU is software (__aeabi_dmul, __aeabi_dadd, … from compiler-builtins).
# Find every call into a double-precision helper, or into a function that uses them (libm's f64
# routines), from code outside libm/compiler-builtins/core, and attribute it to the innermost
# source line of THIS repository in its inline chain (addr2line -i on the debug info). Only the
# sites in the allowlist below may use f64; anything else fails the build.
f64_ok=1
objdump=arm-none-eabi-objdump
if command -v $objdump >/dev/null; then
  DIS=$BOARD/target/fcc-board.dis
  $objdump -d --no-show-raw-insn -C "$ELF" > "$DIS"
  # Functions whose own body calls a double helper.
  mapfile -t f64fns < <(awk '/^[0-9a-f]+ <.*>:$/ {fn=$0; sub(/^[0-9a-f]+ </,"",fn); sub(/>:$/,"",fn)}
       /\t(bl|b|b\.w)\t[0-9a-f]+ <__aeabi_(d[a-z0-9]+|[a-z0-9]*2d|d2[a-z0-9]+)>/ {print fn}' "$DIS" | sort -u)
  # Call sites (address, callee) of double helpers or of those functions, in non-library code.
  awk -v list="$(printf '%s\n' "${f64fns[@]}")" '
       BEGIN { n = split(list, a, "\n"); for (i = 1; i <= n; i++) if (a[i] != "") f64[a[i]] = 1 }
       /^[0-9a-f]+ <.*>:$/ {fn=$0; sub(/^[0-9a-f]+ </,"",fn); sub(/>:$/,"",fn)}
       /\t(bl|b|b\.w)\t[0-9a-f]+ </ {
         callee = $0; sub(/.*\t(bl|b|b\.w)\t[0-9a-f]+ </, "", callee); sub(/>.*/, "", callee)
         if (fn ~ /^(__aeabi|compiler_builtins|libm::)/) next
         if (callee ~ /^__aeabi_(d[a-z0-9]+|[a-z0-9]*2d|d2[a-z0-9]+)$/ || (callee in f64)) {
           addr = $1; sub(/:$/, "", addr); print addr "\t" callee
         }
       }' "$DIS" > "$BOARD/target/f64-sites.txt"
  : > "$BOARD/target/f64-report.txt"
  while IFS=$'\t' read -r addr callee; do
    # Inline chain, innermost first: "function\nfile:line" pairs; keep the first frame in this repo.
    where=$(arm-none-eabi-addr2line -e "$ELF" -f -i -C "0x$addr" | paste - - |
      awk -F'\t' -v root="$ROOT/" 'index($2, root) == 1 && $2 !~ /\/target\// {
        fn = $1; sub(/^.*::/, "", fn); f = $2; sub(root, "", f); sub(/ \(discriminator [0-9]+\)/, "", f)
        if (!n++) { first = f; name = $1 } else { name = name " <- " fn; exit } }
        END { if (n) print first "\t" name }')
    [ -n "$where" ] || where=$'(outside this repository)\t?'
    printf '%s\t%s\n' "$where" "$callee" >> "$BOARD/target/f64-report.txt"
  done < "$BOARD/target/f64-sites.txt"
  echo "f64 (software double precision) in the image, by source file and function (calls into __aeabi_d* / libm f64):"
  # Allowlist: source file (and function / callee) → reason.
  awk -F'\t' '
    function reason(file, fn, callee) {
      if (file ~ /^msg\/src\/geodesy\.rs$/) return "allowed: WGS-84 lat/lon -> local NED (home: once; then per GPS fix, 5 Hz)"
      if (callee ~ /^(__aeabi_(f2d|d2f)|,)+$/) return "allowed: f32<->f64 conversion only (lat/lon and home fields are f64), no f64 arithmetic"
      if (file ~ /^fcc_nav\/src\/complementary\.rs$/ && fn ~ /CfGains>::discrete/) return "allowed: filter gain design, cached per dt (first IMU sample; again only if an IMU sample is missed)"
      if (file ~ /^fcc_firmware\/board\/src\/drivers\/.*(gps|ubx)/) return "allowed: lat/lon from the GPS receiver"
      return "NOT ALLOWED: f64 in the flight path"
    }
    { f = $1; sub(/:[0-9?]+$/, "", f); key = f "\t" $2
      if (!(key in n)) { keys++; c[key] = $3 } else if (index("," c[key] ",", "," $3 ",") == 0) c[key] = c[key] "," $3
      n[key]++ }
    END {
      bad = 0
      for (k in n) { split(k, p, "\t"); r = reason(p[1], p[2], c[k]); if (r ~ /^NOT/) bad = 1
        cs = c[k]; gsub(/libm::math::[a-z0-9_]+::/, "libm::", cs); gsub(/fcc_msgs::geodesy::/, "", cs)
        printf "  %s: %s — %d call(s) of %s  => %s\n", p[1], p[2], n[k], cs, r | "sort" }
      close("sort")
      if (keys == 0) print "  none"
      exit bad
    }' "$BOARD/target/f64-report.txt" || f64_ok=0
  echo "  (libm f64 routines in the image, reached only from the sites above: $(printf '%s\n' "${f64fns[@]}" | grep '^libm::' | sed 's/^libm::math::[a-z_0-9]*:://' | sort -u | tr '\n' ' '))"
  echo "square roots: $(grep -c 'vsqrt.f32' "$DIS") VSQRT.F32 instruction(s); software sqrtf in the image: $(grep -q '<libm::math::sqrt::sqrtf>:' "$DIS" && echo yes || echo no)"
  echo "functions calling core::panicking (panic paths left in the image):"
  awk '/^[0-9a-f]+ <.*>:$/ {fn=$0; sub(/^[0-9a-f]+ </,"",fn); sub(/>:$/,"",fn)}
       /bl.*<core::panicking|bl.*<core::option::unwrap_failed|bl.*<core::slice::index/ {print "  " fn}' \
    "$DIS" | sort | uniq -c | sort -rn | head -20
fi

if [ $flash -gt $((FLASH_KB * 1024)) ] || [ $ram_with_stack -gt $((RAM_KB * 1024)) ]; then
  echo "build-mcu.sh: OVER BUDGET" >&2
  exit 1
fi
if [ $f64_ok = 0 ]; then
  echo "build-mcu.sh: f64 arithmetic outside the allowed sites (see above)" >&2
  exit 1
fi
echo "build-mcu.sh: within budget"
