#!/usr/bin/env python3
"""Write the walled variant of LMGC90's 100_PR_PerioBox as a DATBOX, with pylmgc90.pre.

    PYTHONPATH=$LMGC/build python3 gen_periobox_walled.py ORIGINAL_DATBOX OUT_DIR

The example (build_native/examples/RIGID_3D/100_PR_PerioBox) is periodic in x and y (period 25, the
domain [0, 25]^2: RBDY3 folds X into [0, period]) and feeds its 100 grains one by one through a source
point (RBDY3_SetSourcePointWithIni(2, 6, 12, 12, 12): a grain appears at (12, 12, 12) once the
previous one is 6 away from it), onto a PLANx floor driven at vz = -0.1 m/s, vx = vy = -0.08 sin(0.5 t).
Ours has no periodic boundaries in 3D, no source point and no moving half-space, so the variant run in
BOTH codes is:
- the same 100 POLYR grains (vertices, faces, density 5800 of PLEX1), at their BODIES.DAT reference
  positions: a zig-zag column from z = 4.2 to 761.4 m above the floor (what the DATBOX holds; the
  source point is a command-script feature). Released together at rest, they fall as one column and
  land one after another: a sequential deposit, fed by gravity instead of by the source point;
- the floor: the example's PLANx (centre (6.08, 6.36, -0.06), half sizes 25.3 x 25.7 x 0.06, top at
  z = 0), fixed instead of driven;
- four fixed PLANx walls on the faces of the period, x = 0, x = 25, y = 0, y = 25 (contact surface on
  the face, normal inwards, half thickness 0.06, 13 m half width and 400 m half height from z = -10);
- the example's laws: sico5 (IQS_CLB, friction 0.3, alert 0.3) grain-grain, sico6 (IQS_CLB, friction
  0.5, alert 0.1) grain-plane; gravity -9.81.
"""

from __future__ import annotations

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import datbox as dbx  # noqa: E402

L = 25.0  # the period
T = 0.06  # PLANx half thickness (the example's floor)


def main():
    src, out = sys.argv[1], sys.argv[2]
    from pylmgc90 import pre

    bodies, gravity, dens, laws, sees = dbx.read_datbox(src)
    os.makedirs(out, exist_ok=True)
    cwd = os.getcwd()
    os.chdir(out)

    avatars = pre.avatars()
    mats = pre.materials()
    mods = pre.models()
    svs = pre.see_tables()
    tacts = pre.tact_behavs()
    plex = pre.material(name="PLEX1", materialType="RIGID", density=dens["PLEX1"])
    plan = pre.material(name="PLAN1", materialType="RIGID", density=dens["PLAN1"])
    mats.addMaterial(plex, plan)
    mod = pre.model(name="rigid", physics="MECAx", element="Rxx3D", dimension=3)
    mods.addModel(mod)

    def plane(axe1, axe2, center, axis=None, alpha=0.0):
        b = pre.rigidPlan(axe1=axe1, axe2=axe2, axe3=T, center=np.array(center, float), model=mod,
                          material=plan, color="BLEUx")
        if axis is not None:
            b.rotate(description="axis", alpha=alpha, axis=axis, center=np.array(center, float))
        b.imposeDrivenDof(component=[1, 2, 3, 4, 5, 6], dofty="vlocy")
        avatars.addAvatar(b)

    floor = bodies[0]
    assert floor.contactors[0].kind == "PLANx"
    a = floor.contactors[0].axes
    plane(a[0], a[1], floor.cooref)  # top at cooref_z + axe3 = 0
    zc, hh, hw = 390.0, 400.0, 13.0
    # rigidPlan's normal is its local z; a rotation of +pi/2 about y takes z to +x, about x takes z to -y
    plane(hh, hw, [-T, L / 2, zc], axis=[0.0, 1.0, 0.0], alpha=np.pi / 2)       # x = 0, normal +x
    plane(hh, hw, [L + T, L / 2, zc], axis=[0.0, 1.0, 0.0], alpha=-np.pi / 2)   # x = L, normal -x
    plane(hw, hh, [L / 2, -T, zc], axis=[1.0, 0.0, 0.0], alpha=-np.pi / 2)      # y = 0, normal +y
    plane(hw, hh, [L / 2, L + T, zc], axis=[1.0, 0.0, 0.0], alpha=np.pi / 2)    # y = L, normal -y

    for b in bodies[1:]:
        c = b.contactors[0]
        assert c.kind == "POLYR"
        # generation_type="full" takes the vertices in world coordinates (it recomputes the centre)
        g = pre.rigidPolyhedron(model=mod, material=plex, center=b.cooref.copy(), color="BLEUx",
                                generation_type="full", vertices=c.vertices + b.cooref, faces=c.faces + 1)
        avatars.addAvatar(g)

    sico5 = pre.tact_behav(name="sico5", law="IQS_CLB", fric=laws["sico5"][1]["fric"])
    sico6 = pre.tact_behav(name="sico6", law="IQS_CLB", fric=laws["sico6"][1]["fric"])
    tacts += sico5
    tacts += sico6
    for s in sees:
        svs += pre.see_table(CorpsCandidat=s.cdbdy, candidat=s.cdtac, colorCandidat=s.cdcol,
                             behav=sico5 if s.behav == "sico5" else sico6,
                             CorpsAntagoniste=s.anbdy, antagoniste=s.antac, colorAntagoniste=s.ancol,
                             alert=s.alert)
    pre.writeDatbox(3, mats, mods, avatars, tacts, svs, gravy=list(gravity))
    os.chdir(cwd)


if __name__ == "__main__":
    main()
