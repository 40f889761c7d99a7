#!/usr/bin/env python3
"""Convert an LMGC90 3D rigid DATBOX (RBDY3 + POLYR/PLANx) to a ballast 3D NSCD scene (TOML).

    python3 datbox_to_toml.py DATBOX_DIR -o scene.toml --dt 1e-3 --steps 5000 \
        --theta 0.5 --criterion strict --tolerance 1e-4 --max-iterations 5000

What is mapped (docs/lmgc90-3d.md has the table):
- POLYR contactor -> `polyhedron = { vertices }`: the vertices of BODIES.DAT (body frame), moved so
  that the frame origin is the volume centroid of LMGC90's triangulation (ours takes the hull's
  centroid too), `position = cooref + X + F c`, `orientation = { quaternion }` of DOF.INI's frame F;
- PLANx contactor -> `plane = { normal = F e3 }` through `cooref + X + axe3 * normal` (LMGC90's
  contact surface), fixed: our plane is an infinite half-space, LMGC90's a finite rectangle;
- bulk behaviour (BULK_BEHAV `Umas`) -> `[[material]] density`; one material per (behaviour,
  contactor type, colour), since LMGC90 keys its contact laws on colours and contactor types and we
  key them on materials;
- see tables + IQS_CLB / RST_CLB ... laws (TACT_BEHAV) -> `[[contact]] friction` between the
  materials they match; the alert distance is one number here (default: the largest of the see
  tables', `--alert` to set it);
- DRV_DOF.DAT vlocy: all six dofs imposed 0 -> `fixed = true`; otherwise `imposed = { vx, vy, vz,
  spin }` with LMGC90's `[CT + AMP cos(OMEGA t + PHI)] * [RAMPI + RAMP t]` (RAMP = 0) written as our
  harmonic table (mean CT*RAMPI, amplitude AMP*RAMPI, frequency OMEGA/2pi, phase -PHI), and an
  `evolution` file fitted by a harmonic (refused if the fit is not exact to 1e-6);
- `$gravy` -> gravity; DOF.INI velocities -> velocity, spin (V(4:6) is in the body frame: F V).
Not converted: periodicity, source points, invisible bodies (command-script features, not DATBOX).
"""

from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import datbox as dbx  # noqa: E402


def fmt(x: float) -> str:
    return repr(float(x))


def vec(v) -> str:
    return "[" + ", ".join(fmt(x) for x in v) + "]"


def harmonic_toml(h: dict) -> str:
    if set(h) == {"mean"}:
        return fmt(h["mean"])
    return "{ " + ", ".join(f"{k} = {fmt(v)}" for k, v in h.items()) + " }"


def driven_value(spec, datbox_dir: str, where: str) -> dict:
    if spec[0] == "const":
        ct, amp, omega, phi, rampi, ramp = spec[1:]
        if ramp != 0.0:
            raise SystemExit(f"{where}: a ramp (RAMP = {ramp}) has no equivalent harmonic")
        if amp == 0.0 or omega == 0.0:
            return {"mean": (ct + amp * math.cos(phi)) * rampi}
        return {"mean": ct * rampi, "amplitude": amp * rampi, "frequency": omega / (2 * math.pi), "phase": -phi}
    t, y = dbx.read_evolution(os.path.join(datbox_dir, spec[1]))
    h, res = dbx.fit_harmonic(t, y)
    scale = max(np.max(np.abs(y)), 1e-300)
    if res > 1e-6 * scale:
        raise SystemExit(
            f"{where}: evolution file {spec[1]} is not a harmonic (best fit {h}, residual {res:.3g}); "
            "ours imposes mean + A cos(2 pi f t - phi) only"
        )
    return {k: (round(v, 12) if k != "phase" else v) for k, v in h.items()}


def convert(d: str, args) -> str:
    bodies, gravity, dens, laws, sees = dbx.read_datbox(d)
    out = []
    w = out.append
    w(f"# Converted from the LMGC90 DATBOX {os.path.abspath(d)} by scripts/lmgc90_3d/datbox_to_toml.py")
    w(f"# {len(bodies)} bodies; body names are 'b<LMGC90 index>' (1-based order of BODIES.DAT).")
    w("")
    w("[simulation]")
    w('engine = "nscd"')
    w("dimension = 3")
    w(f"dt = {fmt(args.dt)}")
    w(f"duration = {fmt(args.steps * args.dt)}   # {args.steps} steps (round(duration / dt))")
    w(f"gravity = {vec(gravity)}")
    w("")
    alert = args.alert if args.alert is not None else max(s.alert for s in sees)
    w("[nscd]")
    w(f"theta = {fmt(args.theta)}")
    w(f'criterion = "{args.criterion}"')
    w(f"tolerance = {fmt(args.tolerance)}")
    w(f"max_iterations = {args.max_iterations}")
    w(f"alert_distance = {fmt(alert)}   # LMGC90 see tables: " + ", ".join(
        f"{s.cdtac}/{s.cdcol}-{s.antac}/{s.ancol} {s.alert:g}" for s in sees))
    w("")
    w("[output]")
    w(f"every = {args.every}")
    w("")

    # materials: one per (behaviour, contactor type, colour)
    mats = {}
    for b in bodies:
        if len(b.contactors) != 1:
            raise SystemExit(f"body {b.index}: {len(b.contactors)} contactors; only one per body is converted")
        c = b.contactors[0]
        key = (b.behav, c.kind, c.color)
        mats.setdefault(key, f"{b.behav}_{c.kind}_{c.color}")
    for (behav, kind, color), name in mats.items():
        w("[[material]]")
        w(f'name = "{name}"')
        w(f"density = {fmt(dens[behav])}   # BULK_BEHAV {behav} Umas")
        w("")
    pairs = {}
    for s in sees:
        law, params = laws[s.behav]
        if law not in ("IQS_CLB", "RST_CLB", "GAP_SGR_CLB", "VEL_SGR_CLB"):
            raise SystemExit(f"TACT_BEHAV {s.behav}: law {law} not converted")
        for (b1, k1, c1), n1 in mats.items():
            for (b2, k2, c2), n2 in mats.items():
                if (k1, c1) == (s.cdtac, s.cdcol) and (k2, c2) == (s.antac, s.ancol):
                    key = tuple(sorted((n1, n2)))
                    entry = {"friction": params.get("fric", 0.0)}
                    if law == "RST_CLB":
                        entry["restitution"] = params.get("rstn", 0.0)
                        entry["tangential_restitution"] = params.get("rstt", 0.0)
                    if key in pairs and pairs[key] != entry:
                        raise SystemExit(f"materials {key}: two different laws from the see tables")
                    pairs[key] = (entry, f"{s.behav} {law} ({s.cdtac} {s.cdcol} -> {s.antac} {s.ancol})")
    for (n1, n2), (entry, why) in pairs.items():
        w("[[contact]]")
        w(f'between = ["{n1}", "{n2}"]   # {why}')
        for k, v in entry.items():
            w(f"{k} = {fmt(v)}")
        w("")

    for b in bodies:
        c = b.contactors[0]
        F = b.frame
        name = f"b{b.index}"
        mat = mats[(b.behav, c.kind, c.color)]
        fixed = len(b.driven) == 6 and all(s[0] == "const" and s[1] == 0.0 and s[2] == 0.0 for s in b.driven.values())
        w("[[body]]")
        w(f'name = "{name}"')
        w(f'material = "{mat}"')
        if c.kind == "POLYR":
            cen, vol = dbx.polyhedron_centroid(c.vertices, c.faces)
            verts = c.vertices - cen
            pos = b.cooref + b.X[:3] + F @ cen
            w("polyhedron = { vertices = [" + ", ".join(vec(v) for v in verts) + "] }")
            w(f"position = {vec(pos)}")
            q = dbx.frame_to_quaternion(F)
            if q != [1.0, 0.0, 0.0, 0.0]:
                w(f"orientation = {{ quaternion = {vec(q)} }}")
        elif c.kind == "PLANx":
            n = F[:, 2] / np.linalg.norm(F[:, 2])
            pos = b.cooref + b.X[:3] + c.axes[2] * n
            w(f"plane = {{ normal = {vec(n)} }}   # LMGC90 PLANx half sizes {vec(c.axes)}")
            w(f"position = {vec(pos)}")
            if not fixed:
                if not args.fix_planes:
                    raise SystemExit(f"body {b.index}: a PLANx with imposed motion; ours are fixed half-spaces "
                                     "(--fix-planes to fix it)")
                print(f"warning: body {b.index} (PLANx) had driven dofs {sorted(b.driven)}: fixed here",
                      file=sys.stderr)
            fixed = True
        else:
            raise SystemExit(f"body {b.index}: contactor {c.kind} not converted")
        if fixed:
            w("fixed = true")
        else:
            if np.any(b.V[:3] != 0.0):
                w(f"velocity = {vec(b.V[:3])}")
            if np.any(b.V[3:] != 0.0):
                w(f"spin = {vec(F @ b.V[3:])}")
            if b.driven:
                parts = []
                for dof, key in ((1, "vx"), (2, "vy"), (3, "vz")):
                    if dof in b.driven:
                        parts.append(f"{key} = " + harmonic_toml(driven_value(b.driven[dof], d, f"body {b.index} dof {dof}")))
                rot = [k for k in (4, 5, 6) if k in b.driven]
                if rot:
                    if len(rot) != 3:
                        raise SystemExit(f"body {b.index}: ours imposes the spin as a whole, LMGC90 imposes dofs {rot}")
                    vals = [driven_value(b.driven[k], d, f"body {b.index} dof {k}") for k in rot]
                    if any(set(v) != {"mean"} for v in vals):
                        raise SystemExit(f"body {b.index}: only a constant imposed spin is converted")
                    parts.append(f"spin = {vec(F @ np.array([v['mean'] for v in vals]))}")
                w("imposed = { " + ", ".join(parts) + " }")
        w("")
    return "\n".join(out)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("datbox")
    p.add_argument("-o", "--out", required=True)
    p.add_argument("--dt", type=float, required=True)
    p.add_argument("--steps", type=int, required=True)
    p.add_argument("--theta", type=float, default=0.5)
    p.add_argument("--criterion", default="strict", help="LMGC90 'Maxm ' = strict, 'Quad ' = quad, 'QM/16' = quad_max")
    p.add_argument("--tolerance", type=float, required=True)
    p.add_argument("--max-iterations", type=int, required=True, help="LMGC90 gs_it1 * gs_it2")
    p.add_argument("--alert", type=float, default=None)
    p.add_argument("--every", type=int, default=1)
    p.add_argument("--fix-planes", action="store_true", help="fix PLANx bodies that LMGC90 drives")
    args = p.parse_args(argv)
    text = convert(args.datbox, args)
    with open(args.out, "w") as f:
        f.write(text + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
