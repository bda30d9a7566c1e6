#!/usr/bin/env bash
# Soak test (not in CI): 10 robots x STEPS steps (default 10^6) in the arena, learning
# condition only (scenarios/arena-learning-only.toml; SCENARIO=... for another), with the
# firmware and with the model, each run twice (1 and 2 threads); the four runs go at once.
# Checks that every run ends with status 0, that its resident memory stays flat (sampled every
# 5 s: the largest sample of the last half may exceed the largest of the first half by at most
# 10 %; a run keeps no per-step history, see swarm/src/experiment/metrics.rs), and that the two runs of each
# controller write byte-identical metrics.csv and summary.json. Then the fuzz suite with many
# cases.
#
#   scripts/soak.sh [STEPS] [FUZZ_CASES]    (defaults 1000000 and 100000; OUT=dir keeps results)
#
# About 40 min (model) and 2 h (firmware) of CPU per run at the defaults on this 2-core machine;
# `scripts/soak.sh 20000 5000` takes minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
steps=${1:-1000000}
fuzz_cases=${2:-100000}
scenario=${SCENARIO:-scenarios/arena-learning-only.toml}
out=${OUT:-$(mktemp -d /tmp/h8swarm-soak.XXXXXX)}
mkdir -p "$out"
cargo build --release --quiet
bin=${CARGO_TARGET_DIR:-target}/release/h8swarm
fail() { echo "soak: FAILED: $*"; exit 1; }

rss_kb() { awk '/^VmRSS:/ { print $2 }' "/proc/$1/status" 2>/dev/null || echo 0; }

# One run with its memory sampled every 5 s into $dir.rss ("seconds KB" lines).
soak_one() {
    local controller=$1 threads=$2 dir=$out/$1-t$2
    local log=$dir.rss started pid status
    : > "$log"
    started=$(date +%s)
    "$bin" run "$scenario" --robots 10 --steps "$steps" --repeats 1 --threads "$threads" \
        --controller "$controller" --out "$dir" > "$dir.txt" 2>&1 &
    pid=$!
    while kill -0 "$pid" 2>/dev/null; do
        echo "$(($(date +%s) - started)) $(rss_kb "$pid")" >> "$log"
        sleep 5
    done
    status=0
    wait "$pid" || status=$?
    echo "$status $(($(date +%s) - started))" > "$dir.status"
}

pids=()
for controller in model firmware; do
    for threads in 1 2; do
        soak_one "$controller" "$threads" &
        pids+=($!)
    done
done
for p in "${pids[@]}"; do wait "$p"; done

for controller in model firmware; do
    for threads in 1 2; do
        dir=$out/$controller-t$threads
        read -r status secs < "$dir.status"
        [ "$status" = 0 ] || fail "$controller on $threads threads: status $status ($(tail -n 1 "$dir.txt"))"
        python3 - "$dir.rss" "$controller $threads" <<'EOF'
import sys
rows = [tuple(map(int, l.split())) for l in open(sys.argv[1]) if l.strip()]
rows = [r for r in rows if r[1] > 0]
if len(rows) < 4:
    print(f"soak: {sys.argv[2]}: too short to judge the memory ({len(rows)} samples)")
    sys.exit(0)
half = len(rows) // 2
first = max(r[1] for r in rows[:half])
last = max(r[1] for r in rows[half:])
tenths = [rows[min(len(rows) - 1, i * len(rows) // 10)] for i in range(10)] + [rows[-1]]
curve = ", ".join(f"{t} s {kb // 1024} MB" for t, kb in tenths)
print(f"soak: {sys.argv[2]}: peak RSS first half {first} KB, second half {last} KB; curve: {curve}")
if last > first * 1.10:
    print("soak: FAILED: memory grows")
    sys.exit(1)
EOF
        echo "soak: $controller on $threads threads: $secs s, $(grep '^wall' "$dir.txt")"
    done
    for f in metrics.csv summary.json; do
        cmp -s "$out/$controller-t1/$f" "$out/$controller-t2/$f" \
            || fail "$controller: $f differs between 1 and 2 threads"
    done
    echo "soak: $controller: metrics.csv and summary.json identical for 1 and 2 threads"
done

H8SWARM_FUZZ_CASES=$fuzz_cases cargo test --release --test fuzz
echo "soak: passed ($out)"
