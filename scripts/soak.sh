#!/usr/bin/env bash
# Soak test (issue 13; not in CI): 10 robots x STEPS steps (default 10^6) in the arena, with the
# firmware and with the model, each run twice (1 and 2 threads). Checks that every run ends
# with status 0, that its resident memory stays flat (sampled every 5 s: the largest sample of
# the last half may exceed the largest of the first half by at most 10 %; the metrics held per
# step grow by ~128 B a step and are counted in), and that the two runs of each controller
# write byte-identical metrics.csv and summary.json. Then the fuzz suite with many cases.
#
#   scripts/soak.sh [STEPS] [FUZZ_CASES]    (defaults 1000000 and 100000; OUT=dir keeps results)
#
# Hours on a 2-core machine at the defaults; `scripts/soak.sh 20000 5000` takes minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
steps=${1:-1000000}
fuzz_cases=${2:-100000}
out=${OUT:-$(mktemp -d /tmp/h8swarm-soak.XXXXXX)}
mkdir -p "$out"
cargo build --release --quiet
bin=${CARGO_TARGET_DIR:-target}/release/h8swarm
fail() { echo "soak: FAILED: $*"; exit 1; }

rss_kb() { awk '/^VmRSS:/ { print $2 }' "/proc/$1/status" 2>/dev/null || echo 0; }

for controller in model firmware; do
    for threads in 1 2; do
        dir=$out/$controller-t$threads
        log=$dir.rss
        : > "$log"
        started=$(date +%s)
        "$bin" run arena --robots 10 --steps "$steps" --repeats 1 --threads "$threads" \
            --controller "$controller" --out "$dir" > "$dir.txt" 2>&1 &
        pid=$!
        while kill -0 "$pid" 2>/dev/null; do
            echo "$(($(date +%s) - started)) $(rss_kb "$pid")" >> "$log"
            sleep 5
        done
        wait "$pid" || fail "$controller on $threads threads: status $? ($(tail -n 1 "$dir.txt"))"
        # Memory flat: the largest sample of the second half against that of the first half,
        # less the metrics held (3 runs x steps done x 128 B, grown linearly over the run).
        python3 - "$log" "$steps" "$controller $threads" <<'EOF'
import sys
rows = [tuple(map(int, l.split())) for l in open(sys.argv[1]) if l.strip()]
rows = [r for r in rows if r[1] > 0]
if len(rows) < 4:
    print(f"soak: {sys.argv[3]}: too short to judge the memory ({len(rows)} samples)")
    sys.exit(0)
half = len(rows) // 2
first = max(r[1] for r in rows[:half])
last = max(r[1] for r in rows[half:])
metrics_kb = 3 * int(sys.argv[2]) * 128 / 1024 / 2
print(f"soak: {sys.argv[3]}: peak RSS first half {first} KB, second half {last} KB over {rows[-1][0]} s")
if last > first * 1.10 + metrics_kb:
    print("soak: FAILED: memory grows")
    sys.exit(1)
EOF
        echo "soak: $controller on $threads threads: $(($(date +%s) - started)) s, $(grep '^wall' "$dir.txt")"
    done
    for f in metrics.csv summary.json; do
        cmp -s "$out/$controller-t1/$f" "$out/$controller-t2/$f" \
            || fail "$controller: $f differs between 1 and 2 threads"
    done
    echo "soak: $controller: metrics.csv and summary.json identical for 1 and 2 threads"
done

H8SWARM_FUZZ_CASES=$fuzz_cases cargo test --release --test fuzz
echo "soak: passed ($out)"
