#!/usr/bin/env python3
"""Summarise one-cycle runs of a loaded 3D scene per stopping rule (BENCHMARKS.md, docs/track3d.md).

    python3 summarize_cycle.py DIR REFERENCE SETTING...

DIR holds run folders SETTING-rK (K = replica) of `ballast run` (each with cycles.csv, series.csv,
summary.json). For each setting: the replicas' settlement of the cycle (mm, cycles.csv), mean with Student's
95 % interval; sweeps per step; steps at the cap; the growth of the summed overlap over the cycle (mm,
series.csv's total_overlap_m, last row − first row); and the difference of the mean settlement from the
reference's with Welch's 95 % interval. Standard library only.
"""

import csv
import json
import math
import os
import sys

# Student's t quantile (two-sided 95 %) for 1..30 degrees of freedom.
T95 = [12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145,
       2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048,
       2.045, 2.042]


def t95(dof):
    return T95[min(max(int(round(dof)), 1), 30) - 1]


def runs(root, setting):
    out = []
    k = 0
    while os.path.isdir(os.path.join(root, f"{setting}-r{k}")):
        d = os.path.join(root, f"{setting}-r{k}")
        k += 1
        if not os.path.exists(os.path.join(d, "summary.json")):
            continue
        cyc = list(csv.DictReader(open(os.path.join(d, "cycles.csv"))))
        ser = list(csv.DictReader(open(os.path.join(d, "series.csv"))))
        s = json.load(open(os.path.join(d, "summary.json")))
        out.append(dict(settlement=1e3 * float(cyc[-1]["settlement_m"]), sweeps=s["mean_iterations"],
                        capped=s["unconverged_steps"],
                        overlap=1e3 * (float(ser[-1]["total_overlap_m"]) - float(ser[0]["total_overlap_m"]))))
    return out


def mean_ci(x):
    n = len(x)
    m = sum(x) / n
    if n < 2:
        return m, float("nan"), float("nan")
    var = sum((v - m) ** 2 for v in x) / (n - 1)
    return m, t95(n - 1) * math.sqrt(var / n), var


def main():
    root, ref, settings = sys.argv[1], sys.argv[2], sys.argv[3:]
    ref_runs = runs(root, ref)
    rm, _, rv = mean_ci([r["settlement"] for r in ref_runs])
    print("| setting | replicas | sweeps per step | steps at the cap | settlement of the cycle (mm) | "
          "summed overlap growth (mm) | − reference (mm) |")
    print("|---|---|---|---|---|---|---|")
    for s in settings + ([ref] if ref not in settings else []):
        rs = runs(root, s)
        if not rs:
            continue
        x = [r["settlement"] for r in rs]
        m, h, v = mean_ci(x)
        sw = sum(r["sweeps"] for r in rs) / len(rs)
        lo, hi = min(r["capped"] for r in rs), max(r["capped"] for r in rs)
        caps = f"{lo}" if lo == hi else f"{lo}–{hi}"
        ov = sum(r["overlap"] for r in rs) / len(rs)
        diff = ""
        if s != ref and len(rs) > 1 and len(ref_runs) > 1:
            a, b = v / len(rs), rv / len(ref_runs)
            dof = (a + b) ** 2 / (a * a / (len(rs) - 1) + b * b / (len(ref_runs) - 1))
            d, w = m - rm, t95(dof) * math.sqrt(a + b)
            diff = f"{d:+.4f} [{d - w:+.4f}, {d + w:+.4f}]"
        elif s != ref and ref_runs:
            diff = f"{m - rm:+.4f} (one reference run)"
        ci = f"[{m - h:.4f}, {m + h:.4f}]" if len(rs) > 1 else ""
        print(f"| {s} | {len(rs)} | {sw:.0f} | {caps} | {m:.4f} {ci} | {ov:.2f} | {diff} |")


if __name__ == "__main__":
    main()
