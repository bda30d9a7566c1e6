#!/usr/bin/env bash
# mutants.sh - mutation-test the learner (crate nn_q15) with cargo-mutants: each mutant of
# nn_q15/src is built and run against nn_q15's own tests and the proptests crate's; a mutant that
# no test catches is "missed". The missed mutants that docs/testing.md lists as equivalent (with
# the reason no test can tell them from the original) are accepted; any other fails the run.
#
# Usage:
#   scripts/mutants.sh                    every mutant of nn_q15
#   scripts/mutants.sh --last-change      only mutants on the lines that the last commit touching
#                                         nn_q15/src added (what CI runs; see docs/testing.md)
#   scripts/mutants.sh --in-diff FILE     only mutants on the lines a unified diff FILE adds
#   scripts/mutants.sh [...] -- ARGS      more cargo-mutants arguments (e.g. --file net.rs, --re X)
#
# Environment:
#   PROPTEST_CASES     cases per property (default here 1000; the tests' own default is 10000)
#   PROPTEST_RNG_SEED  proptest's seed (default here 1, so that a run can be repeated)
#   MUTANTS_JOBS       cargo-mutants jobs in parallel (default 1)
#   MUTANTS_CAP        wall-clock cap in seconds (default: none). When it is reached the run
#                      stops, the mutants tested so far are judged, and the report says the
#                      check was partial.
#   MUTANTS_OUT        folder for mutants.out (default target/mutants-out)
#
# Exit status: 0 no missed mutant other than the listed equivalent ones (or nothing to test),
# 1 a tool failure (cargo-mutants itself, or the tests failing on the unmutated tree),
# 2 bad arguments, 3 missed mutants that are not listed as equivalent (named on stderr).
set -euo pipefail
export LC_ALL=C
cd "$(dirname "$0")/.."

mode=all
diff_file=""
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --last-change) mode=last ;;
    --in-diff)
      [ $# -ge 2 ] || { echo "mutants.sh: --in-diff needs a diff file" >&2; exit 2; }
      mode=diff
      diff_file="$2"
      [ -r "$diff_file" ] || { echo "mutants.sh: cannot read diff file '$diff_file'" >&2; exit 2; }
      shift
      ;;
    --)
      shift
      extra=("$@")
      break
      ;;
    -h | --help)
      sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
      exit 0
      ;;
    *)
      echo "mutants.sh: unknown argument '$1' (valid: --last-change, --in-diff FILE, -- ARGS)" >&2
      exit 2
      ;;
  esac
  shift
done

if ! cargo mutants --version >/dev/null 2>&1; then
  echo "mutants.sh: cargo-mutants is not installed (cargo install --locked cargo-mutants@27.1.0)" >&2
  exit 1
fi

export PROPTEST_CASES="${PROPTEST_CASES:-1000}"
export PROPTEST_RNG_SEED="${PROPTEST_RNG_SEED:-1}"
jobs="${MUTANTS_JOBS:-1}"
out="${MUTANTS_OUT:-target/mutants-out}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"

if [ "$mode" = last ]; then
  # The last commit that changed nn_q15's source, and its own diff (a merge's against its first
  # parent). A change that touched only tests or docs has no mutants of its own; CI then checks
  # the last change that did touch the source, so the check always has a subject.
  rev="$(git log -1 --format=%H -- nn_q15/src)"
  if [ -z "$rev" ]; then
    echo "mutants.sh: no commit touches nn_q15/src in this clone: nothing to test"
    exit 0
  fi
  if ! git rev-parse -q --verify "$rev^" >/dev/null; then
    echo "mutants.sh: $rev has no parent in this clone (shallow?): cannot take its diff" >&2
    exit 1
  fi
  diff_file="$out/last-change.diff"
  git diff "$rev^" "$rev" -- nn_q15/src >"$diff_file"
  echo "mutants.sh: the last change to nn_q15/src is $(git log -1 --format='%h %s' "$rev" | cut -c1-100)"
fi

# A test run takes a few seconds on an idle machine; cargo-mutants would time a mutant out at
# 20 s, which a machine shared with other builds exceeds: at least 120 s before a timeout.
args=(mutants -p nn_q15 --test-package nn_q15,proptests --profile mutants --jobs "$jobs"
  --no-shuffle --colors never --output "$out" --minimum-test-timeout 120)
if [ -n "$diff_file" ]; then
  if ! grep -q '^+++ b/nn_q15/src/' "$diff_file"; then
    echo "mutants.sh: the diff adds nothing to nn_q15/src: nothing to test"
    exit 0
  fi
  args+=(--in-diff "$diff_file")
fi
args+=("${extra[@]}")

echo "mutants.sh: cargo ${args[*]} (PROPTEST_CASES=$PROPTEST_CASES, PROPTEST_RNG_SEED=$PROPTEST_RNG_SEED)"
status=0
start=$(date +%s)
if [ -n "${MUTANTS_CAP:-}" ]; then
  # SIGINT lets cargo-mutants write the outcomes so far; KILL 60 s later if it does not stop.
  timeout --signal=INT --kill-after=60 "$MUTANTS_CAP" cargo "${args[@]}" || status=$?
else
  cargo "${args[@]}" || status=$?
fi
elapsed=$(($(date +%s) - start))

partial=""
case "$status" in
  0 | 2 | 3) ;; # all caught / some missed / some timed out
  124 | 130 | 137)
    partial=yes
    echo "mutants.sh: the cap of ${MUTANTS_CAP}s was reached: judging the mutants tested so far"
    ;;
  4)
    echo "mutants.sh: the tests fail on the unmutated tree; fix that first" >&2
    exit 1
    ;;
  *)
    echo "mutants.sh: cargo-mutants failed with status $status" >&2
    exit 1
    ;;
esac

res="$out/mutants.out"
count() { if [ -f "$res/$1" ]; then grep -c . "$res/$1" || true; else echo 0; fi; }
caught=$(count caught.txt)
missed=$(count missed.txt)
timeouts=$(count timeout.txt)
unviable=$(count unviable.txt)

# The equivalent mutants: the first column of the table under "Equivalent mutants" in
# docs/testing.md, as `file: description` (cargo-mutants' name without line and column).
equivalent="$(awk '/^### Equivalent mutants/ {on = 1; next} /^#/ {on = 0} on' docs/testing.md |
  sed -n 's/^| `\([^`]*\)`.*/\1/p')"
unexplained=()
if [ -f "$res/missed.txt" ]; then
  while IFS= read -r m; do
    [ -n "$m" ] || continue
    key="$(printf '%s\n' "$m" | sed 's/^\([^:]*\):[0-9]*:[0-9]*: /\1: /')"
    if ! printf '%s\n' "$equivalent" | grep -qxF -- "$key"; then
      unexplained+=("$m")
    fi
  done <"$res/missed.txt"
fi

echo "mutants.sh: ${elapsed}s; caught $caught, missed $missed (listed as equivalent: $((missed - ${#unexplained[@]}))), timed out $timeouts, unviable $unviable${partial:+ (partial: cap reached)}"
echo "mutants.sh: outcomes in $res"
if [ "${#unexplained[@]}" -gt 0 ]; then
  echo "mutants.sh: missed mutants not listed as equivalent in docs/testing.md:" >&2
  printf '  %s\n' "${unexplained[@]}" >&2
  exit 3
fi
exit 0
