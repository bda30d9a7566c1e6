#!/usr/bin/env bash
# gdb-h8300.sh - build GDB for h8300-elf from Debian's gdb-source package into
# target/gdb-h8300/ and run a scripted session against h8swarm's GDB stub (docs/debugging.md:
# "A GDB for the H8/300"). Debian's gdb-multiarch has no H8/300 support, hence the build. Not part of CI.
#
# Usage:
#   scripts/gdb-h8300.sh            build GDB unless built, then run the session
#   scripts/gdb-h8300.sh build      only build GDB (about 35 min of CPU on one core)
#   scripts/gdb-h8300.sh session    only run the session (GDB built before)
#
# The session: `h8swarm emu firmware/robot.mot --gdb 127.0.0.1:0` (the stub prints the port it
# listens on), GDB connects, reads the registers, breaks at learner_forward (address from
# firmware/robot.sym: the image carries no debug information), continues to it, single-steps,
# reads the clock (`monitor clock`), the network's shape and its weights (net_w), continues to
# the next step's forward pass, reads them again, and detaches (the emulator runs on to its
# --max-states). The transcript goes to
# standard output and to target/gdb-h8300/session.log.
#
# Environment: JOBS (make -j; default: the number of CPUs), NICE (niceness of the build;
# default 10), H8SWARM (an h8swarm binary to use; default: cargo build --release, in
# CARGO_TARGET_DIR or target/).
set -euo pipefail
export LC_ALL=C

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
out="$root/target/gdb-h8300"
gdb_bin="$out/build/gdb/gdb"
JOBS="${JOBS:-$(nproc)}"
NICE="${NICE:-10}"

mode="${1:-all}"
case "$mode" in
  all | build | session) ;;
  *)
    echo "gdb-h8300.sh: unknown argument '$mode' (valid: none, build, session)" >&2
    exit 2
    ;;
esac

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

build_gdb() {
  local tarball
  tarball="$(ls /usr/src/gdb.tar.* 2>/dev/null | head -n 1 || true)"
  if [ -z "$tarball" ] || ! dpkg -s g++ make libgmp-dev libexpat1-dev >/dev/null 2>&1; then
    echo "== installing gdb-source and the build dependencies (apt)"
    as_root apt-get update -qq
    DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq gdb-source g++ make \
      libgmp-dev libexpat1-dev >/dev/null
    tarball="$(ls /usr/src/gdb.tar.* | head -n 1)"
  fi
  echo "== unpacking $tarball into $out/src"
  rm -rf "$out/src" "$out/build"
  mkdir -p "$out/src" "$out/build"
  tar xf "$tarball" -C "$out/src" --strip-components=1
  echo "== configuring for h8300-elf"
  cd "$out/build"
  # GDB alone: no simulator, no gdbserver, no binutils; XML target descriptions (expat) so
  # that the stub's description names the architecture; no Python, no docs (MAKEINFO=true:
  # Debian's source package leaves the manual out).
  nice -n "$NICE" "$out/src/configure" --target=h8300-elf --prefix="$out/install" \
    --disable-nls --disable-werror --disable-sim --disable-gdbserver --disable-binutils \
    --disable-ld --disable-gas --disable-gprof --disable-gold --disable-libctf \
    --disable-sframe --with-expat --without-python --without-guile --without-debuginfod \
    --without-babeltrace --without-intel-pt --without-xxhash >"$out/configure.log" 2>&1 || {
    tail -n 30 "$out/configure.log" >&2
    exit 1
  }
  echo "== building (make -j$JOBS all-gdb; log: $out/make.log)"
  local t0=$SECONDS
  nice -n "$NICE" make -j"$JOBS" all-gdb MAKEINFO=true >"$out/make.log" 2>&1 || {
    tail -n 40 "$out/make.log" >&2
    exit 1
  }
  echo "== built $gdb_bin in $((SECONDS - t0)) s"
  cd "$root"
}

# The address of a symbol in firmware/robot.sym (nm -n output), as 0x...
sym() {
  local a
  a="$(awk -v n="_$1" '$3 == n { print $1; exit }' firmware/robot.sym)"
  if [ -z "$a" ]; then
    echo "gdb-h8300.sh: symbol '$1' not in firmware/robot.sym" >&2
    exit 1
  fi
  printf '0x%x' "$((16#$a))"
}

session() {
  if [ ! -x "$gdb_bin" ]; then
    echo "gdb-h8300.sh: $gdb_bin not built; run 'scripts/gdb-h8300.sh build' first" >&2
    exit 2
  fi
  local h8swarm="${H8SWARM:-}"
  if [ -z "$h8swarm" ]; then
    echo "== building h8swarm (release)"
    cargo build --release --locked --bin h8swarm >/dev/null
    h8swarm="${CARGO_TARGET_DIR:-$root/target}/release/h8swarm"
  fi
  local forward net_w n_in n_out steps
  forward="$(sym learner_forward)"
  net_w="$(sym net_w)"
  n_in="$(sym net_n_in)"
  n_out="$(sym net_n_out)"
  steps="$(sym steps)"
  local stub_err="$out/stub.err"
  mkdir -p "$out"
  # 10 s of emulated time: the session needs 0.5 s; after the detach the rest runs freely.
  "$h8swarm" emu firmware/robot.mot --max-states 250000000 --gdb 127.0.0.1:0 \
    >"$out/stub.out" 2>"$stub_err" &
  local stub_pid=$!
  local port=""
  for _ in $(seq 1 100); do
    port="$(sed -n 's/.*GDB stub listening on 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$stub_err")"
    [ -n "$port" ] && break
    sleep 0.1
  done
  if [ -z "$port" ]; then
    echo "gdb-h8300.sh: the stub did not start:" >&2
    cat "$stub_err" >&2
    kill "$stub_pid" 2>/dev/null || true
    exit 1
  fi
  cat >"$out/session.gdb" <<EOF
set pagination off
set confirm off
set height 0
set architecture h8300h
echo \n--- connect\n
target remote 127.0.0.1:$port
info registers
monitor clock
echo \n--- break at learner_forward ($forward) and continue\n
hbreak *$forward
continue
info registers pc sp
monitor clock
echo \n--- two single steps\n
x/3i \$pc
stepi
info registers pc
stepi
info registers pc
echo \n--- the network: N inputs, M outputs, the weights (M rows of N Q15 values)\n
set \$w = *(unsigned long *) $net_w
set \$n = *(unsigned short *) $n_in
set \$m = *(unsigned char *) $n_out
printf "N = %d, M = %d, net_w = 0x%06lx\n", \$n, \$m, \$w
eval "x/%ddh 0x%lx", \$n * \$m, \$w
echo \n--- continue to the next step's forward pass\n
continue
monitor clock
printf "steps done = %d\n", *(unsigned long *) $steps
eval "x/%ddh 0x%lx", \$n * \$m, \$w
echo \n--- detach: the firmware runs on to --max-states\n
detach
EOF
  echo "== GDB session (port $port)"
  local status=0
  timeout 300 "$gdb_bin" -nx -batch -data-directory "$out/build/gdb/data-directory" \
    -x "$out/session.gdb" 2>&1 | tee "$out/session.log" || status=$?
  wait "$stub_pid" || true
  echo "== stub's standard error:"
  cat "$stub_err"
  return "$status"
}

if [ "$mode" = all ] || [ "$mode" = build ]; then
  if [ "$mode" = build ] || [ ! -x "$gdb_bin" ]; then
    build_gdb
  fi
fi
if [ "$mode" = all ] || [ "$mode" = session ]; then
  session
fi
