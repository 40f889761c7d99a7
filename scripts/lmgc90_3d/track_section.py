#!/usr/bin/env python3
"""Our 3D track section (a scene TOML of ours: planes, boxes, polyhedra, a loaded sleeper, sprung pads) in LMGC90.

    # 1. the DATBOX (and TRACK.json: what the run loop needs that a DATBOX cannot hold)
    PYTHONPATH=$LMGC/build python3 track_section.py convert <scene> OUT_DIR [--alert 1e-3]
    # 2. the run, one thread, from OUT_DIR (prints the mass / inertia check first)
    cd OUT_DIR && OMP_NUM_THREADS=1 PYTHONPATH=$LMGC/build python3 track_section.py run --steps 50 --out lmgc90
    # 0. the check that RBDY3_PutBodyVector('Fext_') adds to gravity (a free box under a constant force)
    PYTHONPATH=$LMGC/build python3 track_section.py fext-test DIR

**Bodies** (one RBDY3 each, in the scene's order: RBDY3 number = scene index + 1):
- `polyhedron = { vertices }`: the vertices are in the body's scene frame (`docs/scene-format.md`: world point =
  `position + R v`, `R` the `orientation` quaternion [w, x, y, z]); the body is their convex hull. The POLYR is
  built by `pre.rigidPolyhedron(generation_type='full')` from the hull's vertices in world coordinates and its
  triangles (scipy `ConvexHull`, each turned outwards); `pre` computes the centre, volume, inertia and principal
  frame from that triangulation.
- `box = { half }` (pads, sleeper): the same, from the 8 corners (12 triangles).
- `plane = { normal }` (fixed): a PLANx whose contact surface is the plane through `position` (normal along the
  PLANx's third axis), 0.5 m half sizes; only axis-aligned normals are handled.
- `velocity` is the velocity of the scene frame's origin and `spin` is in world axes (`src/scene/d3/build.rs`,
  `world_state`): LMGC90's initial V is the centre's, `v + ω × R c` (`c` the centroid in the scene frame), and its
  dofs 4–6 are in the body's inertia frame: `Fᵀ ω`, `F` the principal frame `pre` computed (its columns the
  axes in world coordinates).
- `imposed = { vx = 0, vy = 0, spin = [0,0,0] }` → DRV_DOF `vlocy` 0 on dofs 1, 2, 4, 5, 6 (the only imposed
  form handled: constants 0).
**Materials**: one per `[[material]]` (name and colour: its first 5 letters upper case), its `density`.
**Laws**: one IQS_CLB per `[[contact]]` (its `friction`; restitution must be 0), a see table for each pair the
scene allows (POLYR–POLYR, POLYR–PLANx), every alert distance the scene's `nscd.alert_distance`.
**What a DATBOX cannot hold** (applied by the run loop as external forces, `RBDY3_PutBodyVector('Fext_')`, which
adds to the gravity `ComputeFext` put there; the `fext-test` checks it):
- the sleeper `load` (force `mean + amplitude cos(2π f t − phase)` along `direction`) at
  `t_m = t_n + (1 − θ) h`, as ours (`src/nscd/d3/system.rs`): the same force for the step;
- the `[[spring]]`s to a world anchor (law (17): `ε = (L − L0)/L0 − ε0`, `R = −k_N ε − ν U_N / L0`, clamped at 0
  if compression-only): LMGC90 has no such element for RBDY3, so the force is computed **explicitly** from the
  body's state at the start of the step (`Coorb`, `Vbeg_`), the end point moved to `t_m` by the start
  velocity, and applied for the step (with its moment about the centre). Ours solves it as an implicit row of the
  contact problem: the one deliberate difference, O(h).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from run_lmgc90 import ex_solver  # noqa: E402

try:
    import tomllib
except ImportError:  # Python < 3.11
    sys.exit("track_section.py needs Python >= 3.11 (tomllib)")


# ---------------------------------------------------------------------------------------------------------------
# geometry (ours' definitions: the convex hull, exact mass properties)

def quat_matrix(q):
    w, x, y, z = (float(a) for a in q)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def hull(points):
    """The convex hull of `points`: (its vertices, triangles turned outwards indexing them)."""
    from scipy.spatial import ConvexHull
    h = ConvexHull(points)
    idx = np.unique(h.simplices)
    remap = {int(o): k for k, o in enumerate(idx)}
    verts = points[idx]
    inside = verts.mean(axis=0)
    tris = []
    for s in h.simplices:
        a, b, c = (remap[int(i)] for i in s)
        n = np.cross(verts[b] - verts[a], verts[c] - verts[a])
        if np.dot(n, verts[a] - inside) < 0:
            b, c = c, b
        tris.append((a, b, c))
    return verts, np.array(tris, dtype=int)


def mass_properties(verts, tris):
    """Volume, centroid, inertia tensor about the centroid per unit density (closed outward triangulation)."""
    p0 = verts.mean(axis=0)
    vol, first, second = 0.0, np.zeros(3), np.zeros((3, 3))
    for a, b, c in tris:
        v1, v2, v3 = verts[a] - p0, verts[b] - p0, verts[c] - p0
        d = float(np.dot(v1, np.cross(v2, v3)))
        vol += d / 6.0
        s = v1 + v2 + v3
        first += d / 24.0 * s
        second += d / 120.0 * (np.outer(v1, v1) + np.outer(v2, v2) + np.outer(v3, v3) + np.outer(s, s))
    c = first / vol
    second_c = second - vol * np.outer(c, c)
    inertia = np.trace(second_c) * np.eye(3) - second_c
    return vol, p0 + c, inertia


def box_vertices(half):
    hx, hy, hz = half
    return np.array([[sx * hx, sy * hy, sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)


def read_scene(path):
    with open(path, "rb") as f:
        return tomllib.load(f)


def body_geometry(b):
    """Scene-frame vertices of a solid body (None for a plane)."""
    if "polyhedron" in b:
        return np.array(b["polyhedron"]["vertices"], float)
    if "box" in b:
        return box_vertices(b["box"]["half"])
    if "plane" in b:
        return None
    raise SystemExit(f"body {b.get('name')}: only polyhedron, box and plane are converted")


def orientation(b):
    o = b.get("orientation")
    if o is None:
        return np.eye(3)
    if "quaternion" in o:
        return quat_matrix(o["quaternion"])
    raise SystemExit(f"body {b.get('name')}: orientation must be a quaternion")


def five(name):
    return (name.upper() + "xxxxx")[:5]


# ---------------------------------------------------------------------------------------------------------------
# convert

def convert(args):
    from pylmgc90 import pre

    sc = read_scene(args.scene)
    sim, nscd = sc["simulation"], sc["nscd"]
    assert sim.get("dimension") == 3 and sim.get("engine") == "nscd", "a 3D NSCD scene"
    alert = args.alert if args.alert is not None else nscd["alert_distance"]
    os.makedirs(args.out, exist_ok=True)
    cwd = os.getcwd()
    os.chdir(args.out)

    mats, mods, avatars, svs, tacts = pre.materials(), pre.models(), pre.avatars(), pre.see_tables(), pre.tact_behavs()
    mod = pre.model(name="rigid", physics="MECAx", element="Rxx3D", dimension=3)
    mods.addModel(mod)
    lm = {}
    for m in sc["material"]:
        code = five(m["name"])
        lm[m["name"]] = pre.material(name=code, materialType="RIGID", density=float(m["density"]))
        mats.addMaterial(lm[m["name"]])

    T = 0.01  # PLANx half thickness
    kinds, bodies_json = {}, []
    for i, b in enumerate(sc["body"]):
        mat = b["material"]
        col = five(mat)
        verts = body_geometry(b)
        if verts is None:  # a fixed plane
            assert b.get("fixed", False), f"{b['name']}: a plane must be fixed"
            n = np.array(b["plane"]["normal"], float)
            n /= np.linalg.norm(n)
            p = np.array(b["position"], float)
            centre = p - T * n
            H = 0.5
            axis_rot = {(1, 0, 0): ([0., 1., 0.], math.pi / 2), (-1, 0, 0): ([0., 1., 0.], -math.pi / 2),
                        (0, 1, 0): ([1., 0., 0.], -math.pi / 2), (0, -1, 0): ([1., 0., 0.], math.pi / 2),
                        (0, 0, 1): (None, 0.0), (0, 0, -1): ([1., 0., 0.], math.pi)}
            key = tuple(int(round(x)) for x in n)
            assert key in axis_rot and np.allclose(n, key), f"{b['name']}: only axis-aligned planes"
            body = pre.rigidPlan(axe1=H, axe2=H, axe3=T, center=centre, model=mod, material=lm[mat], color=col)
            ax, alpha = axis_rot[key]
            if ax is not None:
                body.rotate(description="axis", alpha=alpha, axis=ax, center=centre)
            body.imposeDrivenDof(component=[1, 2, 3, 4, 5, 6], dofty="vlocy")
            avatars.addAvatar(body)
            kinds.setdefault(mat, set()).add("PLANx")
            bodies_json.append({"name": b.get("name", ""), "kind": "plane"})
            continue
        R = orientation(b)
        pos = np.array(b.get("position", [0, 0, 0]), float)
        hv, tris = hull(verts)
        vol, c_scene, _ = mass_properties(hv, tris)
        world = pos + hv @ R.T
        centre = pos + R @ c_scene
        split = args.split.get(b.get("name"))
        if split is None:
            body = pre.rigidPolyhedron(model=mod, material=lm[mat], center=centre.copy(), color=col,
                                       generation_type="full", vertices=world.copy(), faces=tris + 1)
        else:
            # a box cut into nx × ny × nz POLYR contactors of one RBDY3 (same volume, mass and inertia): LMGC90's
            # Cundall common plane starts from the centre-to-centre direction and turns it by at most 5° per
            # iteration, so a grain under the edge of a 0.3 × 0.39 × 0.2 m box got the box's side face as its
            # common plane (a horizontal normal, gaps of −5 to −12 cm); smaller contactors give it a good start
            assert "box" in b, "--split: boxes only"
            half = np.array(b["box"]["half"], float)
            n3 = np.array(split, int)
            body = pre.avatar(dimension=3)
            body.addBulk(pre.rigid3d())
            body.addNode(pre.node(coor=np.zeros(3), number=1))
            body.defineGroups()
            body.defineModel(model=mod)
            body.defineMaterial(material=lm[mat])
            sub = half / n3
            for ix in range(n3[0]):
                for iy in range(n3[1]):
                    for iz in range(n3[2]):
                        c = -half + sub * (2 * np.array([ix, iy, iz]) + 1)
                        sv, st = hull(box_vertices(sub) + c)
                        body.addContactors(shape="POLYR", color=col, nb_vertices=len(sv), vertices=pos + sv @ R.T,
                                           nb_faces=len(st), connectivity=st + 1)
            body.computeRigidProperties()
        if b.get("fixed", False):
            body.imposeDrivenDof(component=[1, 2, 3, 4, 5, 6], dofty="vlocy")
        else:
            v = np.array(b.get("velocity", [0, 0, 0]), float)
            w = np.array(b.get("spin", [0, 0, 0]), float)
            vc = v + np.cross(w, R @ c_scene)
            # DOF.INI gets the centre's velocity and the world spin; the run loop puts Fᵀ ω (LMGC90's principal
            # frame, read back with chipy) into V and Vbegin before the first step: `pre` does not expose the
            # frame it writes
            body.imposeInitValue(component=[1, 2, 3, 4, 5, 6], value=[float(x) for x in (*vc, *w)])
            imp = b.get("imposed")
            if imp:
                ok = set(imp) <= {"vx", "vy", "vz", "spin"}
                comps = [k + 1 for k, key in enumerate(("vx", "vy", "vz")) if key in imp]
                vals = [imp[key] for key in ("vx", "vy", "vz") if key in imp]
                if "spin" in imp:
                    comps += [4, 5, 6]
                    vals += list(imp["spin"])
                assert ok and all(isinstance(x, (int, float)) and x == 0 for x in vals), \
                    f"{b['name']}: only imposed components at 0 are converted"
                body.imposeDrivenDof(component=comps, dofty="vlocy")
        avatars.addAvatar(body)
        kinds.setdefault(mat, set()).add("POLYR")
        bodies_json.append({"name": b.get("name", ""), "kind": "box" if "box" in b else "polyhedron",
                            "velocity_centre": vc.tolist() if not b.get("fixed", False) else [0.0] * 3,
                            "spin_world": list(map(float, b.get("spin", [0, 0, 0]))),
                            "guided": bool(b.get("imposed")) and all(k in b["imposed"] for k in ("vx", "vy", "spin")),
                            "material": mat, "density": next(float(m["density"]) for m in sc["material"] if m["name"] == mat),
                            "scene_centroid": c_scene.tolist(), "rotation0": R.tolist(), "volume": vol,
                            "centre": centre.tolist(),
                            "fixed": bool(b.get("fixed", False)), "load": b.get("load")})

    # Every pair of materials: a [[contact]] entry's friction, or frictionless (ours: "pairs of materials
    # without a [[contact]] entry are frictionless"). Except pairs whose both sides can only move along z (a
    # material whose every body is guided: vx, vy, spin imposed, like the pads and the sleeper; or planes with
    # horizontal normals): a contact between them with a horizontal normal (pad-pad, pad-wall, sleeper-wall)
    # has its normal and both tangents blocked, W = diag(0, 0, w), and LMGC90's local solver stops on it
    # ("A.W+B is not inversible"); it cannot carry anything in either code (ours lists such points, always
    # with f_n = 0). The only such pair that could carry load, with a vertical normal, is a guided body on
    # another (pad-sleeper): the converter says which pairs it left out, check they never meet.
    mat_names = [m["name"] for m in sc["material"]]
    guided_only = {m: any(bj.get("material") == m for bj in bodies_json)
                   and all(bj.get("guided") for bj in bodies_json if bj.get("material") == m) for m in mat_names}
    vertical_planes = {m: any("plane" in b and b["material"] == m for b in sc["body"])
                       and all(abs(b["plane"]["normal"][2]) < 1e-12 for b in sc["body"] if "plane" in b and b["material"] == m)
                       for m in mat_names}
    z_only = {m: guided_only[m] or vertical_planes[m] for m in mat_names}
    listed = {frozenset(c["between"]): c for c in sc.get("contact", [])}
    skipped = []
    for k, (a, bb) in enumerate([(a, b) for i, a in enumerate(mat_names) for b in mat_names[i:]]):
        c = listed.get(frozenset((a, bb)), {"friction": 0.0})
        assert float(c.get("restitution", 0.0)) == 0.0, "restitution must be 0 (IQS_CLB)"
        if not kinds.get(a) or not kinds.get(bb):
            continue
        if z_only[a] and z_only[bb]:
            skipped.append(f"{a}-{bb}")
            continue
        law = None
        for ta in sorted(kinds[a]):
            for tb in sorted(kinds[bb]):
                if ta == "PLANx" and tb == "PLANx":
                    continue
                if law is None:
                    law = pre.tact_behav(name=f"iqs{k:02d}", law="IQS_CLB", fric=float(c["friction"]))
                    tacts += law
                # POLYR candidate, PLANx antagonist (PRPLx); LMGC90's see tables are symmetric (get_isee)
                cd, an, ccd, can = (a, bb, ta, tb) if ta != "PLANx" else (bb, a, tb, ta)
                svs += pre.see_table(CorpsCandidat="RBDY3", candidat=ccd, colorCandidat=five(cd), behav=law,
                                     CorpsAntagoniste="RBDY3", antagoniste=can, colorAntagoniste=five(an), alert=alert)
    pre.writeDatbox(3, mats, mods, avatars, tacts, svs, gravy=list(map(float, sim.get("gravity", [0, 0, -9.81]))))

    springs = []
    names = {b.get("name"): i for i, b in enumerate(sc["body"])}
    for s in sc.get("spring", []):
        assert "anchor" in s and "other" not in s, "only springs to a world anchor"
        i = names[s["body"]]
        bj = bodies_json[i]
        R0 = np.array(bj["rotation0"])
        springs.append({"body": i, "r0": (R0 @ (np.array(s.get("point", [0, 0, 0]), float) - np.array(bj["scene_centroid"]))).tolist(),
                        "anchor": s["anchor"], "k_n": s["k_n"], "nu": s.get("nu", 0.0), "rest_length": s["rest_length"],
                        "prestrain": s.get("prestrain", 0.0), "compression_only": s.get("compression_only", False)})
    loads = [{"body": i, **b["load"]} for i, b in enumerate(sc["body"]) if "load" in b]
    for b in sc["body"]:
        assert "torque" not in b, "torques are not converted"
    json.dump({"scene": os.path.basename(args.scene), "dt": sim["dt"], "theta": nscd.get("theta", 0.5),
               "criterion": nscd.get("criterion"), "tolerance": nscd.get("tolerance"),
               "max_iterations": nscd.get("max_iterations"), "alert": alert, "gravity": sim.get("gravity"),
               "bodies": bodies_json, "skipped_pairs": skipped, "springs": springs, "loads": loads},
              open("TRACK.json", "w"))
    os.chdir(cwd)
    npoly = sum(1 for b in bodies_json if b["kind"] != "plane")
    print(f"{len(bodies_json)} bodies ({npoly} POLYR, {len(bodies_json) - npoly} PLANx), {len(springs)} springs, "
          f"{len(loads)} loads, alert {alert} -> {args.out}/DATBOX, {args.out}/TRACK.json; "
          f"no see table for the pairs that can only move along z {skipped}")


# ---------------------------------------------------------------------------------------------------------------
# run

def harmonic(ld, t):
    return ld["mean"] + ld.get("amplitude", 0.0) * math.cos(2 * math.pi * ld.get("frequency", 0.0) * t - ld.get("phase", 0.0))


def frame(chipy, ib):
    """LMGC90's principal frame of body `ib`, its columns the axes in world coordinates (`RBDY3_GetBodyMatrix
    ('IF___')` returns the axes as rows: checked by `mass_check`, Gᵀ I G diagonal)."""
    return np.array(chipy.RBDY3_GetBodyMatrix("IF___", ib)).T


def mass_check(chipy, tr):
    """LMGC90's mass, principal inertia and centre against ours (hull, exact), per solid body."""
    worst = {"mass": 0.0, "inertia": 0.0, "centre_m": 0.0, "frame": 0.0}
    for i, bj in enumerate(tr["bodies"]):
        if bj["kind"] == "plane":
            continue
        rho = bj["density"]
        # ours: the scene-frame hull rotated to the world
        m_l = chipy.RBDY3_GetMass(i + 1)
        I_l = np.array(chipy.RBDY3_GetBodyInertia(i + 1))[:3]
        c_l = np.array(chipy.RBDY3_GetBodyVector("Coor_", i + 1))[:3]
        m_o = rho * bj["volume"]
        I_o = np.array(bj["inertia_principal"]) * rho
        worst["mass"] = max(worst["mass"], abs(m_l - m_o) / m_o)
        worst["inertia"] = max(worst["inertia"], float(np.max(np.abs(np.sort(I_l) - np.sort(I_o)) / np.max(I_o))))
        worst["centre_m"] = max(worst["centre_m"], float(np.linalg.norm(c_l - np.array(bj["centre"]))))
        # LMGC90's frame diagonalises our inertia tensor with its moments
        G = frame(chipy, i + 1)
        Iw = np.array(bj["inertia_world"]) * rho
        worst["frame"] = max(worst["frame"], float(np.max(np.abs(G.T @ Iw @ G - np.diag(I_l))) / np.max(I_o)))
    return worst


def run(args):
    tr = json.load(open("TRACK.json"))
    # ours' inertia, recomputed from LMGC90's own vertices' world hull is not needed: from the scene (convert)
    sc = None
    if args.scene:
        sc = read_scene(args.scene)
    dt, theta = tr["dt"], tr["theta"]
    steps = args.steps
    os.makedirs(args.out, exist_ok=True)

    from pylmgc90 import chipy

    chipy.Initialize()
    chipy.checkDirectories()
    chipy.utilities_DisableLogMes()
    chipy.SetDimension(3, 0)
    if args.detection == "cundall":
        chipy.PRPRx_UseCpCundallDetection(args.cundall_iter)
    elif args.detection == "f2f":
        chipy.PRPRx_UseCpF2fExplicitDetection(1e-2)
    chipy.PRPRx_LowSizeArrayPolyr(args.low_size)
    chipy.TimeEvolution_SetTimeStep(dt)
    chipy.Integrator_InitTheta(theta)
    chipy.ReadDatbox(deformable=False)
    chipy.RBDY3_NewRotationScheme()
    chipy.ComputeMass()
    nb = chipy.RBDY3_GetNbRBDY3()
    assert nb == len(tr["bodies"]), (nb, len(tr["bodies"]))

    if sc is not None:  # the mass / inertia check
        for i, (b, bj) in enumerate(zip(sc["body"], tr["bodies"])):
            if bj["kind"] == "plane":
                continue
            hv, tris = hull(body_geometry(b))
            _, _, I = mass_properties(hv, tris)
            R = np.array(bj["rotation0"])
            Iw = R @ I @ R.T
            bj["inertia_world"] = Iw.tolist()
            bj["inertia_principal"] = np.linalg.eigvalsh(Iw).tolist()
        w = mass_check(chipy, tr)
        print("mass/inertia check, LMGC90 against ours (hull, exact), worst over the bodies: "
              f"mass {w['mass']:.2e} (relative), principal moments {w['inertia']:.2e} (relative), "
              f"centre {w['centre_m']:.2e} m, Fᵀ I F − diag(I_LMGC90) {w['frame']:.2e} (relative)", flush=True)
        json.dump(w, open(os.path.join(args.out, "mass_check.json"), "w"))

    # initial velocities: the centre's, and the spin in LMGC90's principal frame
    for i, bj in enumerate(tr["bodies"]):
        if bj["kind"] == "plane" or bj["fixed"]:
            continue
        G = frame(chipy, i + 1)
        v = np.array([*bj["velocity_centre"], *(G.T @ np.array(bj["spin_world"]))])
        chipy.RBDY3_PutBodyVector("Vbeg_", i + 1, v)
        chipy.RBDY3_PutBodyVector("V____", i + 1, v)

    springs, loads = tr["springs"], tr["loads"]
    frames0 = {s["body"]: frame(chipy, s["body"] + 1) for s in springs}
    sleeper = loads[0]["body"] if loads else None
    z0 = chipy.RBDY3_GetBodyVector("Coor_", sleeper + 1)[2] if sleeper is not None else 0.0
    spring_log = []

    rows, total = [], 0.0
    for k in range(steps):
        t0, c0 = time.perf_counter(), time.process_time()
        chipy.IncrementStep()
        chipy.ComputeFext()
        t_end = chipy.TimeEvolution_GetTime()
        t_m = t_end - theta * dt  # = t_n + (1 - θ) h
        for ld in loads:
            d = np.array(ld["direction"], float)
            d /= np.linalg.norm(d)
            f = harmonic(ld, t_m) * d
            chipy.RBDY3_PutBodyVector("Fext_", ld["body"] + 1, np.array([f[0], f[1], f[2], 0.0, 0.0, 0.0]))
        fsum = 0.0
        for s in springs:
            ib = s["body"] + 1
            xb = np.array(chipy.RBDY3_GetBodyVector("Coorb", ib))[:3]
            vb = np.array(chipy.RBDY3_GetBodyVector("Vbeg_", ib))
            F = frame(chipy, ib)
            r = F @ frames0[s["body"]].T @ np.array(s["r0"])  # lever arm (world) at the start of the step
            w = F @ vb[3:6]
            vp = vb[:3] + np.cross(w, r)
            end = xb + r + (1.0 - theta) * dt * vp  # the end point moved to t_m
            dvec = end - np.array(s["anchor"], float)
            L = float(np.linalg.norm(dvec))
            n = dvec / L if L > 0 else np.array([0.0, 0.0, 1.0])
            eps = (L - s["rest_length"]) / s["rest_length"] - s["prestrain"]
            R_n = -s["k_n"] * eps - s["nu"] * float(np.dot(n, vp)) / s["rest_length"]
            if s["compression_only"]:
                R_n = max(R_n, 0.0)
            f = R_n * n
            m = F.T @ np.cross(r, f)  # moment in the inertia frame
            chipy.RBDY3_PutBodyVector("Fext_", ib, np.array([f[0], f[1], f[2], m[0], m[1], m[2]]))
            fsum += R_n
        chipy.ComputeBulk()
        chipy.ComputeFreeVelocity()
        chipy.SelectProxTactors()
        chipy.RecupRloc(args.rloc_tol)
        sweeps, iconv = ex_solver(chipy, args.storage.ljust(30), args.norm, args.tol, args.relax,
                                  args.check_every, args.blocks)
        chipy.UpdateTactBehav()
        chipy.StockRloc()
        chipy.ComputeDof()
        chipy.UpdateStep()
        dt_wall = time.perf_counter() - t0
        dt_cpu = time.process_time() - c0
        total += dt_wall

        n_prpr = chipy.inter_handler_3D_tgetNb(chipy.PRPRx_ID)
        n_prpl = chipy.inter_handler_3D_tgetNb(chipy.PRPLx_ID)
        active, s_pts, s_loaded, s_fn = 0, 0, 0, 0.0
        for iid in (chipy.PRPRx_ID, chipy.PRPLx_ID):
            for j in range(chipy.inter_handler_3D_tgetNb(iid)):
                d = chipy.inter_handler_3D_tgetRData(iid, j + 1)  # coor, t, n, s (12), rlt, rln, rls, …
                if d[13] > 0.0:
                    active += 1
                if sleeper is not None and sleeper + 1 in (int(x) for x in chipy.inter_handler_3D_tgetIdBodies(iid, j + 1)):
                    s_pts += 1
                    s_loaded += d[13] > 0.0
                    s_fn += d[13] / dt  # R_N as a force (LMGC90's rln is an impulse over the step)
        conv = chipy.nlgs_3D_GetAllConvergenceNorms() if hasattr(chipy, "nlgs_3D_GetAllConvergenceNorms") else None
        zs = chipy.RBDY3_GetBodyVector("Coor_", sleeper + 1)[2] if sleeper is not None else 0.0
        rows.append((k + 1, chipy.TimeEvolution_GetTime(), n_prpr, n_prpl, active, sweeps,
                     int(iconv == 0) if iconv is not None else 1, dt_wall, dt_cpu, zs - z0, fsum,
                     s_pts, s_loaded, s_fn))
        if args.verbose:
            print(rows[-1], conv, flush=True)
        if args.max_wall and total > args.max_wall:
            print(f"stopping after {k + 1} steps: {total:.0f} s > --max-wall", flush=True)
            break

    with open(os.path.join(args.out, "steps.csv"), "w") as f:
        f.write("step,time_s,prprx,prplx,active,sweeps,converged,wall_s,cpu_s,sleeper_dz_m,spring_force_sum_N,sleeper_points,sleeper_loaded,sleeper_fn_sum_N\n")
        for r in rows:
            f.write(",".join(repr(x) for x in r) + "\n")
    final = []
    for i in range(nb):
        final.append({"centre": list(chipy.RBDY3_GetBodyVector("Coor_", i + 1)[:3]),
                      "v": list(chipy.RBDY3_GetBodyVector("V____", i + 1))})
    json.dump({"steps": len(rows), "dt": dt, "check_every": args.check_every, "blocks": args.blocks,
               "norm": args.norm, "tol": args.tol, "detection": args.detection, "wall_s_loop": total,
               "bodies": final}, open(os.path.join(args.out, "final.json"), "w"))
    chipy.Finalize()
    print(f"{len(rows)} steps, {total:.2f} s in the loop, {1e3 * total / max(len(rows), 1):.1f} ms/step")


# ---------------------------------------------------------------------------------------------------------------
# fext-test: a free box under gravity and a constant force P along x and z

def fext_test(args):
    from pylmgc90 import pre
    os.makedirs(args.dir, exist_ok=True)
    os.chdir(args.dir)
    mats, mods, avatars, svs, tacts = pre.materials(), pre.models(), pre.avatars(), pre.see_tables(), pre.tact_behavs()
    mod = pre.model(name="rigid", physics="MECAx", element="Rxx3D", dimension=3)
    mods.addModel(mod)
    mat = pre.material(name="STONE", materialType="RIGID", density=1000.0)
    mats.addMaterial(mat)
    hv, tris = hull(box_vertices([0.1, 0.2, 0.3]))
    body = pre.rigidPolyhedron(model=mod, material=mat, center=np.zeros(3), color="BLUEx", generation_type="full",
                               vertices=hv, faces=tris + 1)
    avatars.addAvatar(body)
    law = pre.tact_behav(name="iqs00", law="IQS_CLB", fric=0.5)
    tacts += law
    svs += pre.see_table(CorpsCandidat="RBDY3", candidat="POLYR", colorCandidat="BLUEx", behav=law,
                         CorpsAntagoniste="RBDY3", antagoniste="POLYR", colorAntagoniste="BLUEx", alert=1e-3)
    g = -9.81
    pre.writeDatbox(3, mats, mods, avatars, tacts, svs, gravy=[0.0, 0.0, g])
    from pylmgc90 import chipy
    chipy.Initialize()
    chipy.checkDirectories()
    chipy.utilities_DisableLogMes()
    chipy.SetDimension(3, 0)
    h, n = 1e-3, 100
    chipy.TimeEvolution_SetTimeStep(h)
    chipy.Integrator_InitTheta(0.5)
    chipy.ReadDatbox(deformable=False)
    chipy.ComputeMass()
    m = chipy.RBDY3_GetMass(1)
    P = np.array([3.0, 0.0, 50.0])
    x0 = np.array(chipy.RBDY3_GetBodyVector("Coor_", 1))[:3]
    for k in range(n):
        chipy.IncrementStep()
        chipy.ComputeFext()
        chipy.RBDY3_PutBodyVector("Fext_", 1, np.array([P[0], P[1], P[2], 0.0, 0.0, 0.0]))
        chipy.ComputeBulk()
        chipy.ComputeFreeVelocity()
        chipy.SelectProxTactors()
        chipy.ComputeDof()
        chipy.UpdateStep()
    t = chipy.TimeEvolution_GetTime()
    x = np.array(chipy.RBDY3_GetBodyVector("Coor_", 1))[:3] - x0
    v = np.array(chipy.RBDY3_GetBodyVector("V____", 1))[:3]
    a = P / m + np.array([0.0, 0.0, g])
    chipy.Finalize()
    print(f"free box, m = {m:.6g} kg, force {P.tolist()} N + gravity, {n} steps of {h} s (t = {t:.6g} s):")
    print(f"  v = {v.tolist()}  closed form a t = {(a * t).tolist()}")
    print(f"  x = {x.tolist()}  closed form a t²/2 = {(0.5 * a * t * t).tolist()}")
    ok = np.allclose(v, a * t, rtol=1e-9, atol=1e-12) and np.allclose(x, 0.5 * a * t * t, rtol=1e-9, atol=1e-12)
    print("  Fext_ adds to gravity:", "yes" if ok else "NO")
    return 0 if ok else 1


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("convert")
    c.add_argument("scene")
    c.add_argument("out")
    c.add_argument("--alert", type=float, default=None)
    c.add_argument("--split", action="append", default=[], metavar="NAME=NX,NY,NZ",
                   help="cut box body NAME into NX×NY×NZ POLYR contactors (see convert)")
    r = sub.add_parser("run")
    r.add_argument("--steps", type=int, default=50)
    r.add_argument("--out", default="lmgc90")
    r.add_argument("--scene", default=None, help="our scene, for the mass / inertia check")
    r.add_argument("--norm", default="Quad ")
    r.add_argument("--tol", type=float, default=1e-4)
    r.add_argument("--relax", type=float, default=1.0)
    r.add_argument("--check-every", type=int, default=10)
    r.add_argument("--blocks", type=int, default=200)
    r.add_argument("--storage", default="Stored_Delassus_Loops         ")
    r.add_argument("--rloc-tol", type=float, default=5e-2)
    r.add_argument("--detection", choices=("cundall", "f2f"), default="cundall")
    r.add_argument("--cundall-iter", type=int, default=100)
    r.add_argument("--low-size", type=int, default=70)
    r.add_argument("--max-wall", type=float, default=0.0, help="stop after this many seconds in the loop")
    r.add_argument("--verbose", action="store_true")
    t = sub.add_parser("fext-test")
    t.add_argument("dir")
    a = p.parse_args()
    if a.cmd == "convert":
        a.split = {k: [int(x) for x in v.split(",")] for k, v in (x.split("=") for x in a.split)}
        convert(a)
    elif a.cmd == "run":
        run(a)
    else:
        sys.exit(fext_test(a))


if __name__ == "__main__":
    main()
