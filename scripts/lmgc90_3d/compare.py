#!/usr/bin/env python3
"""Read an LMGC90 run (run_lmgc90.py's OUT/steps.csv, OUT/final.json) and ours (`ballast run`'s
series.csv, final.json, summary.json, and the scene for the vertices) and write a markdown table.

    python3 compare.py --title "Colonne_PR" --scene colonne.toml \
        --lmgc90 runs/colonne/lmgc90 [--lmgc90 runs/colonne/lmgc90_check10 --lmgc90-label "..."] \
        --ours runs/colonne/ours > table.md

Heights: the top of the highest grain (largest z over the vertices of the non-fixed polyhedra) and the
mean height of their centres, both at the last step. Contacts: LMGC90's PRPRx + PRPLx interactions of
the step (one per contact point, up to 4 per pair with Cundall's detection and more with the
face-to-face one), those with R_N > 0, and the distinct body pairs; ours: `contacts` (points within
the alert distance) and `active_contacts` (points carrying load) of series.csv.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import tomllib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import datbox as dbx  # noqa: E402


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def initial_state(scene):
    """Initial centre and rotation of every scene body (the converter centres the vertices on the
    centroid, so `position` is the centre; the orientation is DOF.INI's frame)."""
    out = {}
    for b in scene["body"]:
        q = b.get("orientation", {}).get("quaternion", [1.0, 0.0, 0.0, 0.0])
        out[b["name"]] = (np.array(b["position"], float), dbx.quaternion_to_matrix(q))
    return out


def motion(init, finals):
    """Largest horizontal displacement of a centre (m) and largest rotation (deg) from the start."""
    dmax, amax = 0.0, 0.0
    for name, (x, R) in finals.items():
        x0, R0 = init[name]
        dmax = max(dmax, float(np.hypot(*(x - x0)[:2])))
        c = (np.trace(R @ R0.T) - 1.0) / 2.0
        amax = max(amax, float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))))
    return dmax, amax


def lmgc90_stats(d, mobile_idx, init):
    rows = read_csv(os.path.join(d, "steps.csv"))
    fin = json.load(open(os.path.join(d, "final.json")))
    f = lambda k: np.array([float(r[k]) for r in rows])  # noqa: E731
    nint = f("prprx") + f("prplx")
    centres = {b["index"]: np.array(b["centre"]) for b in fin["bodies"]}
    tops = []
    for body, v in zip(fin["polyr_bodies"], fin["polyr_vertices_TT"]):
        if body in mobile_idx:
            tops.append(np.array(v)[:, 2].max())
    cz = [centres[i][2] for i in mobile_idx]
    frames = {b["index"]: np.array(b["frame"]) for b in fin["bodies"]}
    dmax, amax = motion(init, {f"b{i}": (centres[i], frames[i]) for i in mobile_idx})
    sweeps = f("sweeps")
    cap = fin["gs_it1"] * fin["gs_it2"]
    return {
        "steps": len(rows),
        "top": max(tops),
        "mean_z": float(np.mean(cz)),
        "median_z": float(np.median(cz)),
        "dxy_max": dmax,
        "rot_max": amax,
        "contacts_end": int(nint[-1]),
        "contacts_mean": float(nint.mean()),
        "active_end": int(f("active")[-1]),
        "active_mean": float(f("active").mean()),
        "pairs_end": int(f("pairs")[-1]),
        "sweeps_mean": float(sweeps.mean()),
        "sweeps_mean_with_contacts": float(sweeps[nint > 0].mean()) if np.any(nint > 0) else 0.0,
        "sweeps_max": int(sweeps.max()),
        "unconverged": int(np.sum((sweeps >= cap) & (nint > 0))),
        "wall_ms": 1e3 * float(f("wall_s").sum()) / len(rows),
        "cpu_ms": 1e3 * float(f("cpu_s").sum()) / len(rows) if "cpu_s" in rows[0] else None,
        "ke_end": float(f("kinetic_energy_J")[-1]),
        "ke_mean": float(f("kinetic_energy_J").mean()),
        "note": f"NLGS check every {fin['gs_it1']} sweeps, at most {fin['gs_it2']} checks",
    }


def ours_cpu_ms(d, steps):
    """User + system time of the whole `ballast run` per step, from the `time` report that run_all.sh
    leaves in ours.log next to the output folder (setup and output writing included: an upper bound)."""
    log = os.path.join(os.path.dirname(os.path.abspath(d)), os.path.basename(os.path.abspath(d)) + ".log")
    if not os.path.exists(log):
        return None
    tot = 0.0
    found = 0
    for line in open(log):
        p = line.split()
        if len(p) == 2 and p[0] in ("user", "sys") and p[1].endswith("s") and "m" in p[1]:
            m, s = p[1][:-1].split("m")
            tot += 60 * float(m) + float(s)
            found += 1
    return 1e3 * tot / steps if found == 2 else None


def ours_pairs(d):
    """Distinct body pairs among the last step's contact points (contacts.csv)."""
    path = os.path.join(d, "contacts.csv")
    if not os.path.exists(path):
        return None
    return len({(min(int(r["a"]), int(r["b"])), max(int(r["a"]), int(r["b"]))) for r in read_csv(path)})


def ours_stats(d, scene, init):
    rows = read_csv(os.path.join(d, "series.csv"))
    fin = json.load(open(os.path.join(d, "final.json")))
    summ = json.load(open(os.path.join(d, "summary.json")))
    f = lambda k: np.array([float(r[k]) for r in rows])  # noqa: E731
    by_name = {b["name"]: b for b in scene["body"]}
    tops, cz, finals = [], [], {}
    for b in fin["bodies"]:
        sb = by_name[b["name"]]
        if sb.get("fixed") or "imposed" in sb or "polyhedron" not in sb:
            continue
        R = dbx.quaternion_to_matrix(b["orientation"])
        v = np.array(sb["polyhedron"]["vertices"])
        # the scene's vertices are centred on the polyhedron's centroid (datbox_to_toml.py), so the
        # frame origin is the centre of mass that final.json gives
        w = np.array(b["position"]) + v @ R.T
        tops.append(w[:, 2].max())
        cz.append(b["position"][2])
        finals[b["name"]] = (np.array(b["position"]), R)
    dmax, amax = motion(init, finals)
    it = f("iterations")
    conv = [r["converged"].strip().lower() in ("true", "1") for r in rows]
    nc = f("contacts")
    return {
        "steps": int(summ["steps"]),
        "top": max(tops),
        "mean_z": float(np.mean(cz)),
        "median_z": float(np.median(cz)),
        "dxy_max": dmax,
        "rot_max": amax,
        "contacts_end": int(nc[-1]),
        "contacts_mean": float(nc.mean()),
        "active_end": int(f("active_contacts")[-1]),
        "active_mean": float(f("active_contacts").mean()),
        "pairs_end": ours_pairs(d),
        "sweeps_mean": float(it.mean()),
        "sweeps_mean_with_contacts": float(it[nc > 0].mean()) if np.any(nc > 0) else 0.0,
        "sweeps_max": int(it.max()),
        "unconverged": int(sum(1 for c, n in zip(conv, nc) if not c and n > 0)),
        "wall_ms": 1e3 * float(summ["wall_time_per_step_s"]),
        "cpu_ms": ours_cpu_ms(d, int(summ["steps"])),
        "ke_end": float(f("kinetic_energy_J")[-1]),
        "ke_mean": float(f("kinetic_energy_J").mean()),
        "note": f"threads {summ.get('threads')}; max overlap {summ.get('max_overlap_m', float('nan')):.3g} m",
    }


def series(kind, d):
    """Per-step (contacts, loaded contacts, sweeps, kinetic energy) of either code."""
    if kind == "ours":
        rows = read_csv(os.path.join(d, "series.csv"))
        return np.array([[float(r["contacts"]), float(r["active_contacts"]), float(r["iterations"]),
                          float(r["kinetic_energy_J"])] for r in rows])
    rows = read_csv(os.path.join(d, "steps.csv"))
    return np.array([[float(r["prprx"]) + float(r["prplx"]), float(r["active"]), float(r["sweeps"]),
                      float(r["kinetic_energy_J"])] for r in rows])


def windows(a, n):
    cols = [(a.lmgc90_label[k] if k < len(a.lmgc90_label) else "LMGC90", series("lmgc90", d))
            for k, d in enumerate(a.lmgc90)] + [("ours", series("ours", a.ours))]
    steps = min(len(c[1]) for c in cols)
    print("Means over windows of steps (contact points / loaded points / sweeps per step / kinetic energy J):\n")
    print("| steps | " + " | ".join(c[0] for c in cols) + " |")
    print("|---|" + "---|" * len(cols))
    for w in range(n):
        lo, hi = w * steps // n, (w + 1) * steps // n
        cells = []
        for _, s in cols:
            m = s[lo:hi].mean(axis=0)
            cells.append(f"{m[0]:.0f} / {m[1]:.0f} / {m[2]:.0f} / {m[3]:.3g}")
        print(f"| {lo + 1}–{hi} | " + " | ".join(cells) + " |")


ROWS = [
    ("steps", "steps run", "{}"),
    ("top", "top of the highest grain at the end (m)", "{:.4f}"),
    ("mean_z", "mean height of the grains' centres at the end (m)", "{:.4f}"),
    ("median_z", "median height of the grains' centres at the end (m)", "{:.4f}"),
    ("dxy_max", "largest horizontal displacement of a grain's centre from the start (m)", "{:.4f}"),
    ("rot_max", "largest rotation of a grain from the start (deg)", "{:.2f}"),
    ("contacts_end", "contact points at the last step (within the alert distance)", "{}"),
    ("contacts_mean", "contact points, mean over the steps", "{:.1f}"),
    ("active_end", "contact points carrying load (R_N > 0) at the last step", "{}"),
    ("active_mean", "contact points carrying load, mean over the steps", "{:.1f}"),
    ("pairs_end", "body pairs in contact at the last step", "{}"),
    ("sweeps_mean", "NLGS sweeps per step, mean over all steps", "{:.1f}"),
    ("sweeps_mean_with_contacts", "NLGS sweeps per step, mean over steps with contacts", "{:.1f}"),
    ("sweeps_max", "NLGS sweeps in a step, largest", "{}"),
    ("unconverged", "steps ending at the sweep cap", "{}"),
    ("wall_ms", "wall time per step, 1 thread (ms)", "{:.3f}"),
    ("cpu_ms", "CPU time per step (ms; LMGC90: the loop's process time; ours: user + sys of the whole run)", "{:.3f}"),
    ("ke_mean", "kinetic energy of all bodies, mean over the steps (J)", "{:.4g}"),
    ("ke_end", "kinetic energy of all bodies at the end (J)", "{:.4g}"),
]


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--title", required=True)
    p.add_argument("--scene", required=True)
    p.add_argument("--lmgc90", action="append", required=True)
    p.add_argument("--lmgc90-label", action="append", default=[])
    p.add_argument("--ours", required=True)
    p.add_argument("--json", default=None, help="also write the numbers here")
    p.add_argument("--windows", type=int, default=0, help="also a table over N equal windows of steps")
    a = p.parse_args()
    scene = tomllib.load(open(a.scene, "rb"))
    names = [b["name"] for b in scene["body"]]
    mobile = [i + 1 for i, b in enumerate(scene["body"])
              if not b.get("fixed") and "imposed" not in b and "polyhedron" in b]
    assert all(n == f"b{i + 1}" for i, n in enumerate(names)), "scene bodies must be b1..bn in LMGC90 order"
    init = initial_state(scene)
    cols = []
    for k, d in enumerate(a.lmgc90):
        label = a.lmgc90_label[k] if k < len(a.lmgc90_label) else "LMGC90"
        cols.append((label, lmgc90_stats(d, mobile, init)))
    cols.append(("ours (ballast)", ours_stats(a.ours, scene, init)))
    print(f"**{a.title}**\n")
    print("| quantity | " + " | ".join(c[0] for c in cols) + " |")
    print("|---|" + "---|" * len(cols))
    for key, label, fmt in ROWS:
        cells = []
        for _, s in cols:
            v = s.get(key)
            cells.append("n/a" if v is None else fmt.format(v))
        print(f"| {label} | " + " | ".join(cells) + " |")
    print("| notes | " + " | ".join(s["note"] for _, s in cols) + " |")
    if a.windows:
        print()
        windows(a, a.windows)
    if a.json:
        json.dump({c[0]: c[1] for c in cols}, open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
