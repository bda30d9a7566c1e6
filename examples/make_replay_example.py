#!/usr/bin/env python3
"""Writes replay-arena.jsonl: a 13 x 4 arena network (eta 0.1 = 3277, T = 10) and 40 steps of
inputs and evaluations, for `h8swarm learn --replay` (docs/design.md §2.6). Deterministic: fixed seed."""
import json
import random

rng = random.Random(2008)
n_in, n_out = 13, 4
header = {
    "n_in": n_in,
    "n_out": n_out,
    "eta": 3277,
    "threshold": 10,
    "weights": [[rng.randint(-16384, 16384) for _ in range(n_in)] for _ in range(n_out)],
}
lines = [json.dumps(header)]
for step in range(40):
    x = [rng.randint(-128, 127) for _ in range(n_in)]
    # Mostly small evaluations (dead zone), some rewards and punishments, and the edges.
    e = rng.choice([0, 5, -5, 10, -10, 11, -11, 40, -40, rng.randint(-1020, 1020)])
    lines.append(json.dumps({"x": x, "e": e}))
with open("replay-arena.jsonl", "w") as f:
    f.write("\n".join(lines) + "\n")
