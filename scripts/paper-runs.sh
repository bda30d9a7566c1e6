#!/usr/bin/env bash
# Reproduces every figure of the README's "The swarm experiment": the paper's two settings with
# the defaults (5 repeats), the arena with 10 and 100 robots, both settings with 20 repeats, and
# the change that makes the arena's claims hold. Each run's folder holds metrics.csv,
# summary.json, the plots and fit.json; the claims and window means are printed.
#
#   scripts/paper-runs.sh [OUT]      (default OUT: out/paper; about 2 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/paper}
cargo build --release --quiet
run() {
    local name=$1
    shift
    echo "## $name: h8swarm run $*"
    cargo run --release --quiet -- run "$@" --out "$out/$name" | sed -n '/^wall/p;/^condition/,/^fit:/p'
    echo
}
run arena arena
run corridor corridor
run arena-10 arena --robots 10
run arena-100 arena --robots 100
run arena-20rep arena --repeats 20
run corridor-20rep corridor --repeats 20
run arena-history0-20rep scenarios/arena-history0.toml --repeats 20
