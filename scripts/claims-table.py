#!/usr/bin/env python3
"""The claims of the paper over seeds: reads OUT/<name>-seed<k>/summary.json (as written by
scripts/paper-runs.sh) and prints, per setting and claim, the two means of every seed, how many
seeds the claim holds in (means) and in how many the 95 % intervals are apart, and the window
means (mean over seeds of the per-seed means over 20 repeats) of every condition.

    python3 scripts/claims-table.py OUT
"""
import json
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
    return f"{v:.3g}" if abs(v) < 10 else f"{v:.0f}"


for name, seeds in runs.items():
    ks = sorted(seeds)
    print(f"### {name} (seeds {', '.join(map(str, ks))}, "
          f"{seeds[ks[0]]['conditions'][0]['first']['mean_d']['n']} repeats each)")
    print()
    print("| condition | window | mean D | collisions/robot | contact time | stuck | moved/step | gap CV |")
    print("|---|---|---|---|---|---|---|---|")
    conds = [c["condition"] for c in seeds[ks[0]]["conditions"]]
    for ci, cname in enumerate(conds):
        for w in ("first", "last"):
            def avg(key, scale=1.0):
                vals = [seeds[k]["conditions"][ci][w].get(key) for k in ks]
                if any(v is None for v in vals):
                    return "–"
                return fmt(sum(v["mean"] for v in vals) / len(vals) * scale)
            print(f"| {cname} | {w} | {avg('mean_d')} | {avg('collisions_per_robot')} | "
                  f"{avg('contact_fraction', 100)} % | {avg('stuck_fraction', 100)} % | "
                  f"{avg('moved_m', 1000)} mm | {avg('gap_cv')} |")
    print()
    print("| the paper's claim | " + " | ".join(f"seed {k}" for k in ks) + " | holds (means) | apart |")
    print("|---|" + "---|" * len(ks) + "---|---|")
    claims = [c["claim"] for c in seeds[ks[0]]["claims"]]
    for qi, q in enumerate(claims):
        cells, holds, apart = [], 0, 0
        for k in ks:
            c = seeds[k]["claims"][qi]
            holds += c["holds"]
            apart += c["holds"] and c["apart"]
            mark = "✓" if c["holds"] else "✗"
            mark += " apart" if c["apart"] else ""
            cells.append(f"{fmt(c['values'][0])} vs {fmt(c['values'][1])} {mark}")
        print(f"| {q} | " + " | ".join(cells) + f" | {holds}/{len(ks)} | {apart}/{len(ks)} |")
    print()
