#!/usr/bin/env bash
# The paper's two settings (arena, corridor) with their controls, seeds 1-5 x 20 repeats each,
# for both sensor mountings (the default 8 cm set-back and the body surface), then the claims
# table over the seeds (scripts/claims-table.py; docs/claims.md says how claims are judged).
#
#   scripts/paper-runs.sh [OUT] [THREADS]   (default OUT: out/paper, THREADS: 2)
#
# About 10 minutes on this 2-core machine (shared with other jobs) with model robots.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/paper}
threads=${2:-2}
cargo build --release --quiet
bin=${CARGO_TARGET_DIR:-target}/release/h8swarm
for scenario in arena corridor scenarios/arena-surface.toml scenarios/corridor-surface.toml; do
    name=$(basename "$scenario" .toml)
    for seed in 1 2 3 4 5; do
        echo "## $name seed $seed"
        "$bin" run "$scenario" --repeats 20 --seed "$seed" --threads "$threads" \
            --out "$out/$name-seed$seed" | grep -E "^(wall|HOLDS|UNSURE|FAILS|UNDECIDED)"
    done
done
python3 scripts/claims-table.py "$out"
