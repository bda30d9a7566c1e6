#!/usr/bin/env python3
"""The claims of the paper over seeds: reads OUT/<name>-seed<k>/summary.json (as written by
scripts/paper-runs.sh) and prints, per setting, the window means of every condition (mean over
seeds of each seed's mean over its repeats), the robots ending held, and per claim each seed's
outcome (repeats for the claim of those with a value) with the outcome pooled over the seeds
(the repeats' counts added, the same one-sided sign test at p < 0.05).

    python3 scripts/claims-table.py OUT
"""
import json
import math
import pathlib
import re
import sys

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "out/paper")
runs = {}
for d in sorted(out.iterdir()):
    m = re.fullmatch(r"(.+)-seed(\d+)", d.name)
    if m and (d / "summary.json").exists():
        runs.setdefault(m.group(1), {})[int(m.group(2))] = json.loads(
            (d / "summary.json").read_text()
        )


def fmt(v):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return f"{v:.3g}" if abs(v) < 10 else f"{v:.0f}"


def sign_p(k, n):
    """P(X >= k), X ~ Binomial(n, 1/2)."""
    if k == 0:
        return 1.0
    return sum(math.comb(n, j) for j in range(k, n + 1)) / 2**n


def pooled(f, a):
    n = f + a
    if n == 0:
        return "undecided"
    if sign_p(f, n) < 0.05:
        return "holds"
    if sign_p(a, n) < 0.05:
        return "the opposite"
    return "unsure" if f > a else "fails"


for name, seeds in runs.items():
    ks = sorted(seeds)
    first = seeds[ks[0]]
    print(f"### {name} (seeds {', '.join(map(str, ks))}, "
          f"{first['conditions'][0]['first']['mean_d']['n']} repeats each)")
    print()
    print("| condition | window | D (du) | coll./robot | coll./net m | coll./path m | contact % | held % | shuttling % | exploring % | net mm/step | path mm/step | gap CV |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    conds = [c["condition"] for c in first["conditions"]]
    for ci, cname in enumerate(conds):
        for w in ("first", "last"):
            def avg(key):
                vals = [seeds[k]["conditions"][ci][w].get(key) for k in ks]
                vals = [v["mean"] for v in vals if v is not None and v["mean"] is not None]
                return fmt(sum(vals) / len(vals)) if vals else "–"
            print(f"| {cname} | {w} | {avg('mean_d')} | {avg('collisions_per_robot')} | "
                  f"{avg('collisions_per_net_m')} | {avg('collisions_per_m')} | "
                  f"{avg('contact_percent')} | {avg('held_percent')} | {avg('shuttling_percent')} | "
                  f"{avg('exploring_percent')} | {avg('net_mm')} | {avg('moved_mm')} | {avg('gap_cv')} |")
    print()
    print("| condition | robots ending the run held | with a lasting held spell |")
    print("|---|---|---|")
    for ci, cname in enumerate(conds):
        r = [seeds[k]["conditions"][ci]["robots"] for k in ks]
        n = sum(x["robots"] for x in r)
        print(f"| {cname} | {sum(x['ending_held'] for x in r)} of {n} | "
              f"{sum(x['with_lasting_held_spell'] for x in r)} of {n} |")
    print()
    print("| claim | " + " | ".join(f"seed {k}" for k in ks) + " | pooled over the seeds |")
    print("|---|" + "---|" * len(ks) + "---|")
    for qi, q in enumerate(first["claims"]):
        cells, f_all, a_all, n_all = [], 0, 0, 0
        for k in ks:
            c = seeds[k]["claims"][qi]
            r = c["repeats"]
            n = r["for"] + r["against"] + r["tied"]
            f_all += r["for"]
            a_all += r["against"]
            n_all += n
            cells.append(f"{c['outcome']} {r['for']}/{n}")
        tag = " (paper)" if q["paper"] else ""
        print(f"| {q['claim']}{tag} | " + " | ".join(cells)
              + f" | {pooled(f_all, a_all)} {f_all}/{n_all} |")
    print()
