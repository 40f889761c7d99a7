#!/usr/bin/env python3
"""Run one of LMGC90's RIGID_3D polyhedra examples with the parameters of its own script, and record
per step what the comparison needs.

    cd WORKDIR            # holds DATBOX/ (the example's, or the walled variant's)
    OMP_NUM_THREADS=1 PYTHONPATH=$LMGC/build python3 run_lmgc90.py --case colonne --steps 5000 --out lmgc90

The time loop is the example's (`command_for_dummies.py` for Colonne_PR, `command.py` for
100_PR_PerioBox): IncrementStep, ComputeFext, ComputeBulk, ComputeFreeVelocity, SelectProxTactors,
RecupRloc, the NLGS, UpdateTactBehav, StockRloc, ComputeDof, UpdateStep; with the same dt, theta,
Rloc_tol, norm, tolerance, relaxation, gs_it1, gs_it2, storage and detection options. Visualisation and
OUTBOX writes are left out of the loop (they are not part of the solve).

`chipy.ExSolver` is expanded into its wrapped parts (nlgs_3D_SetCheckType, ExPrep, ExIter(gs_it1),
AfterIterCheck, ExPost: the Fortran of wrap_nlgs_3D.f90's ExSolver, block for block) only to count the
sweeps it makes: LMGC90's ExSolver(…, gs_it1, gs_it2) makes gs_it1 sweeps between two convergence checks,
at most gs_it2 blocks, so its sweeps are a multiple of gs_it1. `--check-every N --blocks M` sets them
(the script's values by default).

Per step (`OUT/steps.csv`): time, PRPRx and PRPLx interactions (contact points) of the step, those with
a positive normal reaction, the distinct body pairs, sweeps, the wall time of the step (everything from
IncrementStep to UpdateStep, nothing else), its CPU time (process time: on a loaded machine the
fairer figure) and the kinetic energy of all bodies (the driven ones included, as ours). At the end `OUT/final.json`: every
body's centre, frame and the world coordinates of its POLYR vertices, and the total wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

CASES = {
    # examples/RIGID_3D/Colonne_PR/command_for_dummies.py
    "colonne": dict(dt=1e-3, steps=5000, theta=0.5, rloc_tol=5e-2, tol=1e-4, relax=1.0, norm="Maxm ",
                    gs_it1=500, gs_it2=10, storage="Stored_Delassus_Loops         "),
    # examples/RIGID_3D/100_PR_PerioBox/command.py
    "periobox": dict(dt=2e-3, steps=100000, theta=0.5, rloc_tol=5e-2, tol=1.666e-5, relax=1.0, norm="Maxm ",
                     gs_it1=400, gs_it2=10, storage="Stored_Delassus_Loops         "),
}


def ex_solver(chipy, storage, norm, tol, relax, gs_it1, gs_it2, quick_scramble=False):
    """`chipy.ExSolver(storage, norm, tol, relax, gs_it1, gs_it2)` expanded block for block (module doc), with
    LMGC90's quick scramble of the contact order before each block when asked; returns the sweeps made and the
    last check's code (0 converged, -1 a NaN, 1 not converged; None when nothing was checked)."""
    chipy.nlgs_3D_SetCheckType(norm, tol, relax)
    chipy.nlgs_3D_ExPrep(storage)
    sweeps, iconv = 0, None
    nint = sum(chipy.inter_handler_3D_tgetNb(i) for i in (chipy.PRPRx_ID, chipy.PRPLx_ID))
    for _ in range(gs_it2):
        if quick_scramble:
            chipy.nlgs_3D_QuickScrambleContactOrder()
        chipy.nlgs_3D_ExIter(gs_it1)
        sweeps += gs_it1
        if nint == 0:  # prep_check_nlgs finds nothing to check: ExSolver returns here
            break
        iconv = chipy.nlgs_3D_AfterIterCheck()
        if iconv in (0, -1):
            break
    if nint > 0:
        chipy.nlgs_3D_ExPost()
    return sweeps, iconv


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--case", choices=CASES, required=True)
    p.add_argument("--steps", type=int, default=None)
    p.add_argument("--out", default="lmgc90")
    p.add_argument("--check-every", type=int, default=None, help="gs_it1: sweeps between two checks")
    p.add_argument("--blocks", type=int, default=None, help="gs_it2: blocks of sweeps at most")
    p.add_argument("--periodic", action="store_true", help="periobox: the example's periodicity and source point")
    args = p.parse_args()
    c = dict(CASES[args.case])
    steps = args.steps or c["steps"]
    gs_it1 = args.check_every or c["gs_it1"]
    gs_it2 = args.blocks or c["gs_it2"]
    os.makedirs(args.out, exist_ok=True)

    from pylmgc90 import chipy

    chipy.Initialize()
    chipy.checkDirectories()
    chipy.utilities_DisableLogMes()
    chipy.SetDimension(3, 0)

    quick_scramble = False
    if args.case == "colonne":
        chipy.nlgs_3D_DiagonalResolution()
        chipy.nlgs_3D_SetWithQuickScramble()
        quick_scramble = True
        chipy.PRPRx_UseCpF2fExplicitDetection(1.e-2)
        chipy.PRPRx_ShrinkPolyrFaces(1e-2)
    else:
        chipy.PRPRx_UseCpCundallDetection(300)
        chipy.PRPRx_LowSizeArrayPolyr(70)

    chipy.TimeEvolution_SetTimeStep(c["dt"])
    chipy.Integrator_InitTheta(c["theta"])
    chipy.ReadDatbox(deformable=False)

    if args.case == "periobox":
        chipy.RBDY3_NewRotationScheme()
        if args.periodic:
            chipy.RBDY3_SetSourcePointWithIni(2, 6., 12., 12., 12.)
            chipy.SetPeriodicCondition(25.0, 25.0)

    chipy.ComputeMass()

    nb = chipy.RBDY3_GetNbRBDY3()
    masses = np.array([chipy.RBDY3_GetMass(i + 1) for i in range(nb)])
    inertia = [np.array(chipy.RBDY3_GetBodyInertia(i + 1)) for i in range(nb)]

    def kinetic():
        e = 0.0
        for i in range(nb):
            v = chipy.RBDY3_GetBodyVector("V____", i + 1)
            e += 0.5 * masses[i] * float(np.dot(v[:3], v[:3])) + 0.5 * float(np.dot(inertia[i][:3] * v[3:6], v[3:6]))
        return e

    rows = []
    total = 0.0
    for k in range(steps):
        t0, c0 = time.perf_counter(), time.process_time()
        chipy.IncrementStep()
        chipy.ComputeFext()
        chipy.ComputeBulk()
        chipy.ComputeFreeVelocity()
        chipy.SelectProxTactors()
        chipy.RecupRloc(c["rloc_tol"])
        sweeps, _ = ex_solver(chipy, c["storage"], c["norm"], c["tol"], c["relax"], gs_it1, gs_it2, quick_scramble)
        chipy.UpdateTactBehav()
        chipy.StockRloc()
        chipy.ComputeDof()
        chipy.UpdateStep()
        dt_wall = time.perf_counter() - t0
        dt_cpu = time.process_time() - c0
        total += dt_wall

        n_prpr = chipy.inter_handler_3D_tgetNb(chipy.PRPRx_ID)
        n_prpl = chipy.inter_handler_3D_tgetNb(chipy.PRPLx_ID)
        active, pairs = 0, set()
        for iid in (chipy.PRPRx_ID, chipy.PRPLx_ID):
            for j in range(chipy.inter_handler_3D_tgetNb(iid)):
                cd, an = (int(x) for x in chipy.inter_handler_3D_tgetIdBodies(iid, j + 1))
                pairs.add((min(cd, an), max(cd, an)))
                # tgetRData: local frame (12), rlt, rln, rls, vlt, vln, vls, gapTT
                if chipy.inter_handler_3D_tgetRData(iid, j + 1)[13] > 0.0:
                    active += 1
        rows.append((k + 1, chipy.TimeEvolution_GetTime(), n_prpr, n_prpl, active, len(pairs), sweeps, dt_wall, dt_cpu, kinetic()))

    with open(os.path.join(args.out, "steps.csv"), "w") as f:
        f.write("step,time_s,prprx,prplx,active,pairs,sweeps,wall_s,cpu_s,kinetic_energy_J\n")
        for r in rows:
            f.write(",".join(repr(x) for x in r) + "\n")

    bodies = []
    for i in range(nb):
        coor = np.array(chipy.RBDY3_GetBodyVector("Coor_", i + 1))[:3]
        F = np.array(chipy.RBDY3_GetBodyMatrix("IF___", i + 1))
        bodies.append({"index": i + 1, "centre": coor.tolist(), "frame": F.tolist()})
    npol = chipy.POLYR_GetNbPOLYR()
    chipy.POLYR_MoveToConfigurationTT()
    polyr = []
    polyr_bodies = [i + 1 for i in range(nb) if chipy.RBDY3_GetContactorType(i + 1, 1).strip() == "POLYR"]
    assert len(polyr_bodies) == npol
    for it in range(npol):
        v = np.array(chipy.POLYR_GetPtrVertexTT(it + 1)).reshape(-1, 3)
        polyr.append(v.tolist())
    json.dump({"case": args.case, "steps": steps, "dt": c["dt"], "gs_it1": gs_it1, "gs_it2": gs_it2,
               "norm": c["norm"], "tol": c["tol"], "wall_s_loop": total, "bodies": bodies,
               "polyr_vertices_TT": polyr, "polyr_bodies": polyr_bodies}, open(os.path.join(args.out, "final.json"), "w"))
    chipy.Finalize()
    print(f"{steps} steps, {total:.2f} s in the loop, {1e3 * total / steps:.3f} ms/step")


if __name__ == "__main__":
    main()
