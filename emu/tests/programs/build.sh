#!/usr/bin/env bash
# build.sh - build the differential test programs for the emulated H8/3052F.
#
# For every program <name>.c listed in PROGRAMS below:
#   target: h8300-hms-gcc -mh -mint32 -O2 -nostdlib with crt0.S, firmware/runtime.S,
#           console.c and the linker script h8-3052f.ld, then
#           h8300-hms-objcopy -O srec  ->  <name>.mot
#   host:   gcc -O2 with console.c mapped to stdio, run  ->  <name>.expected
#           (the run must exit with status 0, as the emulated run must)
#
# and for every program stack/<name>.c listed in STACK_PROGRAMS (the stack guard's test
# programs, which overflow their stack on purpose and have no host run):
#   target: as above  ->  stack/<name>.mot, and h8300-hms-nm -n  ->  stack/<name>.sym
#
# and for every program chip/<name>.c listed in CHIP_PROGRAMS (the chip's test programs: the
# watchdog, the IRQ inputs, registers the emulator does not model, a call structure for the
# profile; they use the hardware and have no host run), with chip/crt0.S, whose vector table
# points vectors 12, 20 and 24 at the program's handlers:
#   target: as above  ->  chip/<name>.mot, and h8300-hms-nm -n  ->  chip/<name>.sym
#
# Usage:
#   ./build.sh            build into this folder (commit the .mot and .expected files)
#   ./build.sh --check    rebuild into a temporary folder and fail, listing the
#                         files, if any committed .mot or .expected differs
#   ./build.sh --ubsan    build and run the host programs with -fsanitize=undefined
#                         (a development check that the C has no undefined behaviour)
#   ./build.sh --listing DIR   also write <name>.lst (objdump -d of .text), <name>.map and
#                         <name>.coff (the linked image with symbols) into DIR
#
# Environment: H8_PREFIX (default h8300-hms-), HOST_CC (default gcc).
#
# Reproducible by construction: sources are compiled with relative paths from
# this folder, and objcopy runs inside the output folder with a bare file name,
# so the S0 header record always holds just "<name>.mot"; S-records carry no
# timestamps. The .expected files depend only on the C sources.
set -euo pipefail
export LC_ALL=C

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"

PROGRAMS=(arith shifts muldiv bitops structs recursion funcptr switch q15learn crcmacdiv)
STACK_PROGRAMS=(stack_deep stack_after stack_close)
CHIP_PROGRAMS=(wdt idle_wdt unmodelled callstack irq irq_board minibot)
SUPPORT_C=(console.c)

H8_PREFIX="${H8_PREFIX:-h8300-hms-}"
HOST_CC="${HOST_CC:-gcc}"
TARGET_CFLAGS=(-mh -mint32 -O2 -nostdlib -Wall -Wextra -Werror -I.)
# -funsigned-char: plain char is unsigned on the H8 target (GCC defines
# __CHAR_UNSIGNED__ there); the programs never rely on it, this is a safety net.
# No -Werror on the host: a newer host GCC may warn about more; the target
# compiler is fixed (GCC 3.4.6) and builds with -Werror.
HOST_CFLAGS=(-O2 -funsigned-char -Wall -Wextra -I.)

mode=build
listing_dir=""
case "${1:-}" in
  "") ;;
  --check) mode=check ;;
  --ubsan) mode=ubsan ;;
  --listing)
    listing_dir="${2:?--listing needs a folder}"
    mkdir -p "$listing_dir"
    listing_dir="$(cd "$listing_dir" && pwd)"
    ;;
  *)
    echo "build.sh: unknown argument '$1' (valid: none, --check, --ubsan, --listing DIR)" >&2
    exit 2
    ;;
esac

need() {
  if ! command -v "$1" >/dev/null 2>&1; then
    echo "build.sh: '$1' not found; install Debian's gcc-h8300-hms and binutils-h8300-hms (and gcc)" >&2
    exit 2
  fi
}
need "${H8_PREFIX}gcc"
need "${H8_PREFIX}objcopy"
need "${H8_PREFIX}nm"
need "$HOST_CC"

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# build_all OUT_DIR [extra host flags...]
build_all() {
  local out="$1"
  shift
  local host_extra=("$@")
  local obj="$work/obj"
  mkdir -p "$obj" "$out"

  # The .S files use no preprocessor directives: assemble them as they are.
  "${H8_PREFIX}gcc" "${TARGET_CFLAGS[@]}" -x assembler -c crt0.S -o "$obj/crt0.o"
  # The runtime helpers have one source for every H8 program of the project: the firmware's.
  "${H8_PREFIX}gcc" "${TARGET_CFLAGS[@]}" -x assembler -c ../../../firmware/runtime.S -o "$obj/runtime.o"
  local support_objs=()
  local c
  for c in "${SUPPORT_C[@]}"; do
    "${H8_PREFIX}gcc" "${TARGET_CFLAGS[@]}" -c "$c" -o "$obj/${c%.c}.o"
    support_objs+=("$obj/${c%.c}.o")
  done

  local name
  for name in "${PROGRAMS[@]}"; do
    # Target image. crt0.o first: its .text starts with the vector table.
    "${H8_PREFIX}gcc" "${TARGET_CFLAGS[@]}" -c "$name.c" -o "$obj/$name.o"
    "${H8_PREFIX}gcc" "${TARGET_CFLAGS[@]}" -T h8-3052f.ld -Wl,-Map,"$obj/$name.map" \
      "$obj/crt0.o" "$obj/$name.o" "${support_objs[@]}" "$obj/runtime.o" \
      -o "$obj/$name.coff"
    (cd "$obj" && "${H8_PREFIX}objcopy" -O srec "$name.coff" "$name.mot")
    cp "$obj/$name.mot" "$out/$name.mot"
    chmod 644 "$out/$name.mot"
    if [[ -n "$listing_dir" ]]; then
      "${H8_PREFIX}objdump" -d -j .text "$obj/$name.coff" > "$listing_dir/$name.lst"
      cp "$obj/$name.map" "$obj/$name.coff" "$listing_dir/"
    fi

    # Host reference run.
    "$HOST_CC" "${HOST_CFLAGS[@]}" "${host_extra[@]}" "$name.c" "${SUPPORT_C[@]}" -o "$obj/$name.host"
    local status=0
    "$obj/$name.host" > "$out/$name.expected" || status=$?
    if [[ $status -ne 0 ]]; then
      echo "build.sh: host run of $name exited with status $status (expected 0); see $out/$name.expected" >&2
      exit 1
    fi
  done

  # The stack guard's programs: target only, with their symbol tables.
  mkdir -p "$out/stack"
  for name in "${STACK_PROGRAMS[@]}"; do
    "${H8_PREFIX}gcc" "${TARGET_CFLAGS[@]}" -c "stack/$name.c" -o "$obj/$name.o"
    "${H8_PREFIX}gcc" "${TARGET_CFLAGS[@]}" -T h8-3052f.ld -Wl,-Map,"$obj/$name.map" \
      "$obj/crt0.o" "$obj/$name.o" "${support_objs[@]}" "$obj/runtime.o" \
      -o "$obj/$name.coff"
    (cd "$obj" && "${H8_PREFIX}objcopy" -O srec "$name.coff" "$name.mot")
    "${H8_PREFIX}nm" -n "$obj/$name.coff" > "$obj/$name.sym"
    cp "$obj/$name.mot" "$obj/$name.sym" "$out/stack/"
    chmod 644 "$out/stack/$name.mot" "$out/stack/$name.sym"
    if [[ -n "$listing_dir" ]]; then
      "${H8_PREFIX}objdump" -d -j .text "$obj/$name.coff" > "$listing_dir/$name.lst"
      cp "$obj/$name.map" "$obj/$name.coff" "$listing_dir/"
    fi
  done
  # The chip's programs: their own crt0, target only, with their symbol tables.
  "${H8_PREFIX}gcc" "${TARGET_CFLAGS[@]}" -x assembler -c chip/crt0.S -o "$obj/chip_crt0.o"
  mkdir -p "$out/chip" "$obj/chip"
  for name in "${CHIP_PROGRAMS[@]}"; do
    "${H8_PREFIX}gcc" "${TARGET_CFLAGS[@]}" -Ichip -c "chip/$name.c" -o "$obj/chip/$name.o"
    # The linker script puts *crt0.o(.text) first: the chip crt0 is linked as chip/crt0.o.
    cp "$obj/chip_crt0.o" "$obj/chip/crt0.o"
    "${H8_PREFIX}gcc" "${TARGET_CFLAGS[@]}" -T h8-3052f.ld -Wl,-Map,"$obj/chip/$name.map" \
      "$obj/chip/crt0.o" "$obj/chip/$name.o" "${support_objs[@]}" "$obj/runtime.o" \
      -o "$obj/chip/$name.coff"
    (cd "$obj/chip" && "${H8_PREFIX}objcopy" -O srec "$name.coff" "$name.mot")
    "${H8_PREFIX}nm" -n "$obj/chip/$name.coff" > "$obj/chip/$name.sym"
    cp "$obj/chip/$name.mot" "$obj/chip/$name.sym" "$out/chip/"
    chmod 644 "$out/chip/$name.mot" "$out/chip/$name.sym"
    if [[ -n "$listing_dir" ]]; then
      "${H8_PREFIX}objdump" -d -j .text "$obj/chip/$name.coff" > "$listing_dir/chip_$name.lst"
    fi
  done
}

case "$mode" in
  build)
    build_all "$here"
    for name in "${PROGRAMS[@]}"; do
      printf '%-10s %6d bytes .mot  %5d bytes .expected  %s\n' "$name" \
        "$(wc -c < "$name.mot")" "$(wc -c < "$name.expected")" "$(tail -n 1 "$name.expected")"
    done
    for name in "${STACK_PROGRAMS[@]}"; do
      printf 'stack/%-12s %6d bytes .mot  %5d lines .sym\n' "$name" \
        "$(wc -c < "stack/$name.mot")" "$(wc -l < "stack/$name.sym")"
    done
    for name in "${CHIP_PROGRAMS[@]}"; do
      printf 'chip/%-13s %6d bytes .mot  %5d lines .sym\n' "$name" \
        "$(wc -c < "chip/$name.mot")" "$(wc -l < "chip/$name.sym")"
    done
    ;;
  ubsan)
    build_all "$work/ubsan" -fsanitize=undefined -fno-sanitize-recover=undefined
    for name in "${PROGRAMS[@]}"; do
      if ! cmp -s "$work/ubsan/$name.expected" "$name.expected"; then
        echo "build.sh: $name.expected differs under -fsanitize=undefined" >&2
        exit 1
      fi
    done
    echo "ubsan: all host runs clean and identical"
    ;;
  check)
    build_all "$work/fresh"
    differ=()
    for name in "${PROGRAMS[@]}"; do
      for ext in mot expected; do
        if [[ ! -f "$name.$ext" ]] || ! cmp -s "$work/fresh/$name.$ext" "$name.$ext"; then
          differ+=("$name.$ext")
        fi
      done
    done
    for name in "${STACK_PROGRAMS[@]}"; do
      for ext in mot sym; do
        if [[ ! -f "stack/$name.$ext" ]] || ! cmp -s "$work/fresh/stack/$name.$ext" "stack/$name.$ext"; then
          differ+=("stack/$name.$ext")
        fi
      done
    done
    for name in "${CHIP_PROGRAMS[@]}"; do
      for ext in mot sym; do
        if [[ ! -f "chip/$name.$ext" ]] || ! cmp -s "$work/fresh/chip/$name.$ext" "chip/$name.$ext"; then
          differ+=("chip/$name.$ext")
        fi
      done
    done
    for f in chip/*.mot; do
      [[ -e "$f" ]] || continue
      name="$(basename "${f%.mot}")"
      if [[ ! " ${CHIP_PROGRAMS[*]} " == *" $name "* ]]; then
        differ+=("$f (not built by build.sh)")
      fi
    done
    for f in stack/*.mot; do
      [[ -e "$f" ]] || continue
      name="$(basename "${f%.mot}")"
      if [[ ! " ${STACK_PROGRAMS[*]} " == *" $name "* ]]; then
        differ+=("$f (not built by build.sh)")
      fi
    done
    # A committed image without a source in PROGRAMS would be run by the
    # differential test but never rebuilt: flag it too.
    for f in *.mot; do
      [[ -e "$f" ]] || continue
      name="${f%.mot}"
      if [[ ! " ${PROGRAMS[*]} " == *" $name "* ]]; then
        differ+=("$f (not built by build.sh)")
      fi
    done
    if [[ ${#differ[@]} -ne 0 ]]; then
      echo "build.sh --check: these files differ from a fresh build (run ./build.sh and commit):" >&2
      printf '  %s\n' "${differ[@]}" >&2
      exit 1
    fi
    echo "build.sh --check: all ${#PROGRAMS[@]} programs' .mot and .expected files, the ${#STACK_PROGRAMS[@]} stack programs' and the ${#CHIP_PROGRAMS[@]} chip programs' .mot and .sym files match a fresh build"
    ;;
esac
