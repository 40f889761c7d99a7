#!/usr/bin/env python3
"""Rewrite Colonne_PR's imposed-velocity file so that the shaking starts at t = 0.

    python3 colonne_shake_from_t0.py DATBOX

The example (gen_sample.py) drives the foundation brick along y (DRV_DOF.DAT: dof 2, evolution vx.dat)
with v(t) = 0 for t <= 0.1 s, then 0.16 sin(2 pi 2 (t - 0.1)) m/s, sampled at 10000 instants over
[0, 10] s. Our imposed velocities are harmonics `mean + A cos(2 pi f t - phi)` from t = 0, which
cannot hold still for 0.1 s first; so both codes run the same law without the 0.1 s of rest:
v(t) = 0.16 sin(2 pi 2 t) = 0.16 cos(2 pi 2 t - pi/2), sampled here at 100001 instants (LMGC90
interpolates linearly between them: at most 3e-8 m/s from the sine).
"""

import os
import sys

import numpy as np

d = sys.argv[1]
t = np.linspace(0.0, 10.0, 100001)
v = 0.16 * np.sin(2 * np.pi * 2.0 * t)
with open(os.path.join(d, "vx.dat"), "w") as f:
    for a, b in zip(t, v):
        f.write(f" {a:.10E}  {b:.10E}\n")
print(f"wrote {os.path.join(d, 'vx.dat')}: 0.16 sin(4 pi t) on [0, 10] s")
