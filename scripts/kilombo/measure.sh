#!/usr/bin/env bash
# Time Kilombo's headless disperse example (1 000 robots) N times and print
# wall seconds, simulated seconds and real-time factor per run, then min/median/max.
#
#   KILOMBO=/path/to/kilombo scripts/kilombo/measure.sh [-n RUNS] [-c CONFIG.json]
#     KILOMBO    a checkout of github.com/JIC-CSB/kilombo outside this repository (built
#                here with cmake -DCMAKE_C_FLAGS=-fcommon and make headless if it is not)
#     -n RUNS    number of runs (default 3)
#     -c CONFIG  Kilombo parameter file (default scripts/kilombo/kilombo.json;
#                scripts/kilombo/kilombo-dense.json is the dense variant)
#
# Wall time: date +%s.%N taken just before the process starts and just after it
# exits (the whole process: parameter parsing, placing the bots, the steps,
# writing endstate.json), with /usr/bin/time -f giving user/sys CPU and max RSS.
# CPU time (user+sys) and sim/CPU are printed too: on a shared machine wall
# time includes waiting for a core, CPU time mostly does not.
# Simulated time: the KILOMBO_REPORT line the example prints at exit. Bot 0's
# loop repeats runsim.c's own `time += simparams->timeStep` once per step, so
# sim_seconds is the time Kilombo's loop reached; it is cross-checked against
# Kilombo's kilo_ticks (= time * 31) and steps x timeStep.
set -euo pipefail

KILOMBO=$(readlink -f "${KILOMBO:?set KILOMBO to a Kilombo checkout outside this repository}")
EX=$(dirname "$(readlink -f "$0")")
RUNS=3
CONFIG=$EX/kilombo.json
while getopts "n:c:h" opt; do
  case $opt in
    n) RUNS=$OPTARG ;;
    c) CONFIG=$(readlink -f "$OPTARG") ;;
    *) sed -n '2,9p' "$0"; exit 2 ;;
  esac
done
[[ $RUNS =~ ^[1-9][0-9]*$ ]] || { echo "runs must be a positive integer" >&2; exit 2; }
[[ -f $CONFIG ]] || { echo "no config $CONFIG" >&2; exit 2; }

# Build if needed (library: cmake + make headless; example: its Makefile).
if [[ ! -f $KILOMBO/build/src/libheadless.a ]]; then
  mkdir -p "$KILOMBO/build"
  (cd "$KILOMBO/build" && nice -n 5 cmake .. -DCMAKE_C_FLAGS=-fcommon >/dev/null && nice -n 5 make headless >/dev/null)
fi
OBJ=$KILOMBO/build/h8swarm-disperse
nice -n 5 make -s -C "$EX" KILOMBO="$KILOMBO" BUILD="$OBJ" headless >/dev/null
BIN=$OBJ/disperse

flags=$(sed -n 's/^C_FLAGS = //p' "$KILOMBO/build/src/CMakeFiles/headless.dir/flags.make")
defs=$(sed -n 's/^C_DEFINES = //p' "$KILOMBO/build/src/CMakeFiles/headless.dir/flags.make")
exflags=$(make -s -n -B -C "$EX" KILOMBO="$KILOMBO" BUILD="$OBJ" "$OBJ/disperse.o" | grep -m1 '^gcc')
echo "kilombo commit : $(git -C "$KILOMBO" rev-parse HEAD)"
echo "compiler       : $(gcc --version | head -1)"
echo "libheadless.a  : $defs $flags"
echo "disperse       : $exflags"
echo "config         : $CONFIG (sha256 $(sha256sum "$CONFIG" | cut -c1-16))"
echo "machine        : $(nproc) CPUs, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "load before    : $(cut -d' ' -f1-3 /proc/loadavg)"
echo

work=$(mktemp -d /tmp/kilombo-measure.XXXXXX)
trap 'rm -rf "$work"' EXIT
cp "$CONFIG" "$work/kilombo.json"

printf '%4s %9s %9s %8s %10s %7s %7s %8s %7s %6s %7s %8s\n' \
  run wall_s sim_s rtf steps user_s sys_s cpu_rtf rss_MB load1 moving contacts
results=()
for ((i = 1; i <= RUNS; i++)); do
  load1=$(cut -d' ' -f1 /proc/loadavg)
  t0=$(date +%s.%N)
  (cd "$work" && /usr/bin/time -f 'TIME user=%U sys=%S rss_kb=%M' -o "$work/time.$i" \
     "$BIN" -p kilombo.json >"$work/out.$i" 2>"$work/err.$i")
  t1=$(date +%s.%N)
  rep=$(grep '^KILOMBO_REPORT' "$work/out.$i") || { echo "run $i: no KILOMBO_REPORT" >&2; cat "$work/err.$i" >&2; exit 1; }
  get() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<<" $rep"; }
  tim() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<<" $(cat "$work/time.$i")"; }
  sim=$(get sim_seconds); steps=$(get steps); ts=$(get timeStep)
  kt=$(get kilo_ticks); ktc=$(get kilo_ticks_check)
  [[ $kt == "$ktc" ]] || { echo "run $i: kilo_ticks $kt != floor(sim_seconds*31) $ktc" >&2; exit 1; }
  awk -v s="$sim" -v n="$steps" -v t="$ts" 'BEGIN { d = s - n * t; if (d < 0) d = -d; exit !(d < 1e-3) }' \
    || { echo "run $i: sim_seconds $sim != steps*timeStep" >&2; exit 1; }
  wall=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }')
  rtf=$(awk -v s="$sim" -v w="$wall" 'BEGIN { printf "%.1f", s / w }')
  cpu=$(awk -v u="$(tim user)" -v y="$(tim sys)" 'BEGIN { printf "%.2f", u + y }')
  crtf=$(awk -v s="$sim" -v c="$cpu" 'BEGIN { printf "%.1f", (c > 0 ? s / c : 0) }')
  printf '%4d %9s %9.3f %8s %10s %7s %7s %8s %7.1f %6s %7s %8s\n' "$i" "$wall" "$sim" "$rtf" "$steps" \
    "$(tim user)" "$(tim sys)" "$crtf" "$(awk -v k="$(tim rss_kb)" 'BEGIN{print k/1024}')" "$load1" \
    "$(get moving)" "$(get contacts)"
  results+=("$wall $rtf $cpu $crtf")
done

echo
printf '%s\n' "${results[@]}" | awk -v n="$RUNS" '
  { w[NR] = $1; r[NR] = $2; c[NR] = $3; q[NR] = $4 }
  function sort(a, m,   i, j, t) { for (i = 2; i <= m; i++) for (j = i; j > 1 && a[j-1] > a[j]; j--) { t = a[j]; a[j] = a[j-1]; a[j-1] = t } }
  function med(a, m) { return m % 2 ? a[(m+1)/2] : (a[m/2] + a[m/2+1]) / 2 }
  END {
    sort(w, n); sort(r, n); sort(c, n); sort(q, n)
    printf "wall s             min %.3f  median %.3f  max %.3f\n", w[1], med(w, n), w[n]
    printf "real-time x (wall) min %.1f  median %.1f  max %.1f\n", r[1], med(r, n), r[n]
    printf "CPU s (user+sys)   min %.2f  median %.2f  max %.2f\n", c[1], med(c, n), c[n]
    printf "real-time x (CPU)  min %.1f  median %.1f  max %.1f\n", q[1], med(q, n), q[n]
  }'
echo "load after     : $(cut -d' ' -f1-3 /proc/loadavg)"
echo "samples (last run, every sampleEvery simulated s):"
grep '^KILOMBO_SAMPLE' "$work/out.$RUNS" | sed 's/^/  /'
