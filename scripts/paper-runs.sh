#!/usr/bin/env bash
# The paper's two settings (arena, corridor) with their controls, seeds 1-5 x 20 repeats each,
# for both sensor mountings (the default 8 cm set-back and the body surface), then the claims
# table over the seeds (scripts/claims-table.py; docs/claims.md says how claims are judged).
#
#   scripts/paper-runs.sh [OUT] [THREADS] [SOLVER]
#
# (default OUT: out/paper, THREADS: 2, SOLVER: each scenario's own, the capped contact solver;
# `converged` or `newton` runs every setting with that world.solver: docs/claims.md, "Under the
# converged solver". The scenario files run are written into OUT/scenarios.)
#
# About 10 minutes on this 2-core machine (shared with other jobs) with model robots.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/paper}
threads=${2:-2}
solver=${3:-}
case "$solver" in
    "" | capped | converged | newton) ;;
    *) echo "paper-runs.sh: SOLVER is capped, converged or newton, not \`$solver\`" >&2; exit 2 ;;
esac
cargo build --release --quiet
bin=${CARGO_TARGET_DIR:-target}/release/h8swarm
[ -z "$solver" ] || mkdir -p "$out/scenarios"
for scenario in arena corridor scenarios/arena-surface.toml scenarios/corridor-surface.toml; do
    name=$(basename "$scenario" .toml)
    file=$scenario
    if [ -n "$solver" ]; then
        # The setting with the solver named (a built-in becomes a file based on it; the two
        # files end in their [world] table, so the key lands in it).
        file=$out/scenarios/$name.toml
        if [ -f "$scenario" ]; then
            text=$(cat "$scenario")
        else
            text=$(printf 'base = "%s"\n\n[world]' "$scenario")
        fi
        text=$(printf '%s\nsolver = "%s"' "$text" "$solver")
        # A file of the same name that this script did not write (a user's own) is kept.
        if [ -e "$file" ] && [ "$(cat "$file")" != "$text" ]; then
            echo "paper-runs.sh: $file exists and is not this script's: give another OUT" >&2
            exit 2
        fi
        printf '%s\n' "$text" >"$file"
    fi
    for seed in 1 2 3 4 5; do
        echo "## $name seed $seed"
        "$bin" run "$file" --repeats 20 --seed "$seed" --threads "$threads" \
            --out "$out/$name-seed$seed" | grep -E "^(wall|contact|HOLDS|UNSURE|FAILS|UNDECIDED)"
    done
done
python3 scripts/claims-table.py "$out"
