#!/usr/bin/env bash
# build.sh - build the robot firmware (docs/design.md §8) into robot.mot and robot.sym.
#
#   h8300-hms-gcc -mh -mint32 -O2 -fomit-frame-pointer -fno-optimize-sibling-calls -nostdlib
#   crt0.S runtime.S robot.c learner.c config.c i2c.c record.c du_table.c, linked with
#   h8-3052f.ld; h8300-hms-objcopy -O srec -> robot.mot; h8300-hms-nm -n -> robot.sym.
#
# Usage:
#   ./build.sh               build into this folder (commit robot.mot and robot.sym)
#   ./build.sh --check       rebuild into a temporary folder; fail, naming the files, if the
#                            committed robot.mot or robot.sym differ
#   ./build.sh --listing D   also write robot.lst (objdump -d), robot.map and robot.coff into D
#
# Environment: H8_PREFIX (default h8300-hms-).
#
# Reproducible: sources are compiled by relative path from this folder, objcopy runs inside
# the output folder on a bare file name (the S0 record holds just "robot.mot"), S-records and
# nm output carry no timestamps.
set -euo pipefail
export LC_ALL=C

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"

H8_PREFIX="${H8_PREFIX:-h8300-hms-}"
# -fomit-frame-pointer frees ER6 for the loops; -fno-optimize-sibling-calls keeps every call a
# JSR/BSR with its RTS, so the emulator's profiler sees each phase's entry and return.
CFLAGS=(-mh -mint32 -O2 -fomit-frame-pointer -fno-optimize-sibling-calls -nostdlib
  -Wall -Wextra -Werror -I.)
SOURCES=(robot learner config i2c record du_table)

mode=build
listing_dir=""
case "${1:-}" in
  "") ;;
  --check) mode=check ;;
  --listing)
    listing_dir="${2:?--listing needs a folder}"
    mkdir -p "$listing_dir"
    listing_dir="$(cd "$listing_dir" && pwd)"
    ;;
  *)
    echo "build.sh: unknown argument '$1' (valid: none, --check, --listing DIR)" >&2
    exit 2
    ;;
esac

for tool in gcc objcopy nm objdump; do
  if ! command -v "${H8_PREFIX}$tool" >/dev/null 2>&1; then
    echo "build.sh: '${H8_PREFIX}$tool' not found; install Debian's gcc-h8300-hms and binutils-h8300-hms" >&2
    exit 2
  fi
done

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# build OUT_DIR
build() {
  local out="$1" obj="$work/obj"
  mkdir -p "$obj" "$out"
  "${H8_PREFIX}gcc" "${CFLAGS[@]}" -x assembler -c crt0.S -o "$obj/crt0.o"
  "${H8_PREFIX}gcc" "${CFLAGS[@]}" -x assembler -c runtime.S -o "$obj/runtime.o"
  local objs=("$obj/crt0.o") s
  for s in "${SOURCES[@]}"; do
    "${H8_PREFIX}gcc" "${CFLAGS[@]}" -c "$s.c" -o "$obj/$s.o"
    objs+=("$obj/$s.o")
  done
  objs+=("$obj/runtime.o")
  "${H8_PREFIX}gcc" "${CFLAGS[@]}" -T h8-3052f.ld -Wl,-Map,"$obj/robot.map" "${objs[@]}" \
    -o "$obj/robot.coff"
  (cd "$obj" && "${H8_PREFIX}objcopy" -O srec robot.coff robot.mot)
  "${H8_PREFIX}nm" -n "$obj/robot.coff" > "$obj/robot.sym"
  cp "$obj/robot.mot" "$obj/robot.sym" "$out/"
  chmod 644 "$out/robot.mot" "$out/robot.sym"
  if [[ -n "$listing_dir" ]]; then
    "${H8_PREFIX}objdump" -d "$obj/robot.coff" > "$listing_dir/robot.lst"
    cp "$obj/robot.map" "$obj/robot.coff" "$listing_dir/"
  fi
}

case "$mode" in
  build)
    build "$here"
    printf 'robot.mot %d bytes, robot.sym %d symbols\n' "$(wc -c < robot.mot)" "$(wc -l < robot.sym)"
    ;;
  check)
    build "$work/fresh"
    differ=()
    for f in robot.mot robot.sym; do
      if [[ ! -f "$f" ]] || ! cmp -s "$work/fresh/$f" "$f"; then
        differ+=("$f")
      fi
    done
    if [[ ${#differ[@]} -ne 0 ]]; then
      echo "build.sh --check: these files differ from a fresh build (run firmware/build.sh and commit):" >&2
      printf '  %s\n' "${differ[@]}" >&2
      exit 1
    fi
    echo "build.sh --check: robot.mot and robot.sym match a fresh build"
    ;;
esac
