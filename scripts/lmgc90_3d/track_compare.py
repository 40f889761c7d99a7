#!/usr/bin/env python3
"""The markdown tables of the track-section comparison: LMGC90 runs of `track_section.py run` (OUT/steps.csv)
against ours (`ballast run` folders: series.csv, cycles.csv with one cycle per step, summary.json, and the
`/usr/bin/time -v` output of the run for its CPU time).

    python3 track_compare.py --lmgc90 LABEL=DIR [--lmgc90 ...] --ours LABEL=DIR:TIMEFILE [--ours ...] [--steps N]

Per step: LMGC90's wall and CPU time of the step (IncrementStep … UpdateStep), its sweeps, contact points
(PRPRx + PRPLx), loaded points (R_N > 0), the sleeper's vertical displacement from the start; ours' sweeps
(`iterations`), `contacts`, `active_contacts` and the sleeper's displacement (`−settlement_m` of cycles.csv,
one cycle per step). Ours writes no per-step time: its time per step is the run's mean (`wall_time_per_step_s`,
and user + sys of the whole run over the steps: an upper bound, the setup is in it).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import re

import numpy as np


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def lmgc90(d, steps):
    r = rows(os.path.join(d, "steps.csv"))[:steps]
    f = lambda k: np.array([float(x[k]) for x in r])  # noqa: E731
    return {"n": len(r), "wall": f("wall_s"), "cpu": f("cpu_s"), "sweeps": f("sweeps"),
            "contacts": f("prprx") + f("prplx"), "loaded": f("active"), "dz": f("sleeper_dz_m"),
            "converged": f("converged")}


def cpu_of(timefile):
    t = open(timefile).read()
    u = float(re.search(r"User time \(seconds\): ([0-9.]+)", t).group(1))
    s = float(re.search(r"System time \(seconds\): ([0-9.]+)", t).group(1))
    return u + s


def ours(spec, steps):
    d, timefile = spec.split(":")
    s = rows(os.path.join(d, "series.csv"))[:steps]
    c = rows(os.path.join(d, "cycles.csv"))[:steps]
    summ = json.load(open(os.path.join(d, "summary.json")))
    f = lambda k: np.array([float(x[k]) for x in s])  # noqa: E731
    n = len(s)
    assert len(c) == n, f"{d}: cycles.csv must have one row per step ({len(c)} rows, {n} steps)"
    cpu = cpu_of(timefile) / summ["steps"]
    return {"n": n, "wall_mean": summ["wall_time_per_step_s"], "cpu_mean": cpu, "sweeps": f("iterations"),
            "contacts": f("contacts"), "loaded": f("active_contacts"), "converged": f("converged"),
            "dz": -np.array([float(x["settlement_m"]) for x in c]), "unconverged": summ["unconverged_steps"]}


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--lmgc90", action="append", default=[], help="LABEL=DIR")
    p.add_argument("--ours", action="append", default=[], help="LABEL=DIR:TIMEFILE")
    p.add_argument("--steps", type=int, default=None)
    p.add_argument("--dt", type=float, default=2e-4)
    p.add_argument("--every", type=int, default=5, help="rows of the per-step table: every N-th step")
    a = p.parse_args()
    L = [(x.split("=", 1)[0], lmgc90(x.split("=", 1)[1], a.steps or 10**9)) for x in a.lmgc90]
    O = [(x.split("=", 1)[0], ours(x.split("=", 1)[1], a.steps or 10**9)) for x in a.ours]
    n = min([r["n"] for _, r in L] + [r["n"] for _, r in O])

    out = []
    out.append("| run | steps | wall ms/step | CPU ms/step | sweeps/step | steps at the 2000-sweep cap | "
               "contact points/step | loaded points/step | sleeper Δz at the end (µm) |")
    out.append("|---|---|---|---|---|---|---|---|---|")
    for lab, r in L:
        out.append(f"| LMGC90, {lab} | {n} | {1e3 * r['wall'][:n].mean():.0f} | {1e3 * r['cpu'][:n].mean():.0f} | "
                   f"{r['sweeps'][:n].mean():.0f} | {int((r['converged'][:n] == 0).sum())} | "
                   f"{r['contacts'][:n].mean():.0f} | {r['loaded'][:n].mean():.0f} | {1e6 * r['dz'][n - 1]:.2f} |")
    for lab, r in O:
        out.append(f"| ours, {lab} | {n} | {1e3 * r['wall_mean']:.0f} | {1e3 * r['cpu_mean']:.0f} (whole run) | "
                   f"{r['sweeps'][:n].mean():.0f} | {int((r['converged'][:n] == 0).sum())} | "
                   f"{r['contacts'][:n].mean():.0f} | {r['loaded'][:n].mean():.0f} | {1e6 * r['dz'][n - 1]:.2f} |")
    out.append("")
    if L and O:
        out.append("| ratio LMGC90 / ours | wall per step | CPU per step | CPU per sweep |")
        out.append("|---|---|---|---|")
        for la, lr in L:
            for lo, orr in O:
                w = lr["wall"][:n].mean() / orr["wall_mean"]
                c = lr["cpu"][:n].mean() / orr["cpu_mean"]
                cs = (lr["cpu"][:n].sum() / lr["sweeps"][:n].sum()) / (orr["cpu_mean"] * n / orr["sweeps"][:n].sum())
                out.append(f"| LMGC90 {la} / ours {lo} | {w:.2f} | {c:.2f} | {cs:.2f} |")
        out.append("")

    head = "| step | t (ms) |"
    sep = "|---|---|"
    for lab, _ in L:
        head += f" LMGC90 {lab}: wall / CPU ms, sweeps, points / loaded, Δz µm |"
        sep += "---|"
    for lab, _ in O:
        head += f" ours {lab}: sweeps, points / loaded, Δz µm |"
        sep += "---|"
    out.append(head)
    out.append(sep)
    for k in sorted(set(list(range(0, n, a.every)) + [0, 1, 2, n - 1])):
        line = f"| {k + 1} | {1e3 * a.dt * (k + 1):.1f} |"
        for _, r in L:
            line += (f" {1e3 * r['wall'][k]:.0f} / {1e3 * r['cpu'][k]:.0f}, {int(r['sweeps'][k])}, "
                     f"{int(r['contacts'][k])} / {int(r['loaded'][k])}, {1e6 * r['dz'][k]:.2f} |")
        for _, r in O:
            line += f" {int(r['sweeps'][k])}, {int(r['contacts'][k])} / {int(r['loaded'][k])}, {1e6 * r['dz'][k]:.2f} |"
        out.append(line)
    print("\n".join(out))


if __name__ == "__main__":
    main()
