"""Reader of LMGC90 3D rigid DATBOX files (RBDY3 bodies with POLYR / PLANx contactors).

Only what the converter needs: BODIES.DAT (node coordinates, bulk behaviour, contactors),
DOF.INI (displacements, velocities, local frames), BULK_BEHAV.DAT (gravity, densities),
TACT_BEHAV.DAT (contact laws and see tables) and DRV_DOF.DAT (imposed velocities).
Both the files written by `pylmgc90.pre.writeDatbox` and the older hand-written ones
(100_PR_PerioBox) are read: the parser goes by keywords and `name= value` pairs, not columns.

LMGC90 conventions used (from src/Core/rigid_3D/mod_RBDY3.f90 and contact_3D/mod_PRPLx.f90):
- a body's world position is `cooref + X(1:3)`, `cooref` the `$nodty` coordinates of BODIES.DAT
  and `X` the displacement of DOF.INI (0 for a body absent from DOF.INI);
- the three frame lines of DOF.INI (alpha/beta/gamma, or a/b/c in old files) are the columns of
  the body's local frame F (body axes in world coordinates), so a vertex `v` of a POLYR given in
  the body frame is at `cooref + X + F v` (identity when the body has no DOF.INI entry);
- a PLANx contactor is a rectangle of half sizes axe1, axe2 and half thickness axe3 about its
  centre, its outward normal the third axis of the frame: the contact surface is at
  `centre + axe3 n` (PRPLx: `dist = n.(x - centre) - axe(3)`), finite (|t1.(x-c)| <= axe1, ...).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field

import numpy as np

_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[dDeE][-+]?\d+)?"


def fnum(s: str) -> float:
    return float(s.replace("D", "E").replace("d", "e"))


def numbers_after_eq(line: str) -> list[float]:
    """Values of the `name= value` pairs of a line, in order."""
    return [fnum(m) for m in re.findall(r"=\s*(" + _NUM + ")", line)]


@dataclass
class Contactor:
    kind: str  # POLYR, PLANx, SPHER, ...
    color: str
    vertices: np.ndarray | None = None  # (n, 3) body frame
    faces: np.ndarray | None = None  # (m, 3) 0-based
    axes: np.ndarray | None = None  # PLANx half sizes (a1, a2, a3)
    data: list[float] = field(default_factory=list)


@dataclass
class Body:
    index: int  # 1-based, order of BODIES.DAT (LMGC90's numbering)
    behav: str
    cooref: np.ndarray
    contactors: list[Contactor]
    X: np.ndarray = field(default_factory=lambda: np.zeros(6))
    V: np.ndarray = field(default_factory=lambda: np.zeros(6))
    frame: np.ndarray = field(default_factory=lambda: np.eye(3))
    driven: dict = field(default_factory=dict)  # dof (1..6) -> ('const', ct, amp, omega, phi, rampi, ramp) | ('evolution', path)


def _blocks(path: str) -> list[list[str]]:
    """Lines of each `$bdyty` block (up to `$$$$$$`)."""
    out, cur = [], None
    with open(path, encoding="latin-1") as f:
        for line in f:
            line = line.rstrip("\n")
            if line.startswith("$bdyty"):
                cur = []
                continue
            if cur is None:
                continue
            if line.startswith("$$$$$$"):
                out.append(cur)
                cur = None
                continue
            cur.append(line)
    return out


def read_bodies(path: str) -> list[Body]:
    bodies = []
    for n, blk in enumerate(_blocks(path), start=1):
        behav, cooref, contactors = None, None, []
        i = 0
        section = None
        while i < len(blk):
            line = blk[i]
            s = line.strip()
            if s.startswith("$blmty"):
                section = "blmty"
            elif s.startswith("$nodty"):
                section = "nodty"
            elif s.startswith("$tacty"):
                section = "tacty"
            elif section == "blmty" and "behav" in s:
                toks = s.split()
                behav = toks[toks.index("behav") + 1]
            elif section == "nodty" and s.startswith("NO"):
                vals = numbers_after_eq(line)
                cooref = np.array(vals[:3])
            elif section == "tacty" and re.match(r"^[A-Z][A-Za-z0-9]{4}\s", s):
                toks = s.split()
                kind, color = toks[0], toks[toks.index("color") + 1]
                c = Contactor(kind, color)
                if kind == "POLYR":
                    nv = int(re.search(r"nb_vertex=\s*(\d+)", s).group(1))
                    nf = int(re.search(r"nb_faces=\s*(\d+)", s).group(1))
                    verts = [numbers_after_eq(blk[i + 1 + k])[:3] for k in range(nv)]
                    faces = [[int(v) - 1 for v in numbers_after_eq(blk[i + 1 + nv + k])[:3]] for k in range(nf)]
                    c.vertices, c.faces = np.array(verts), np.array(faces, dtype=int)
                    i += nv + nf
                elif kind == "PLANx":
                    c.axes = np.array(numbers_after_eq(line)[:3])
                else:
                    c.data = numbers_after_eq(line)
                contactors.append(c)
            i += 1
        if cooref is None:
            raise ValueError(f"{path}: body {n} has no $nodty coordinates")
        bodies.append(Body(n, behav, cooref, contactors))
    return bodies


def read_dof_ini(path: str, bodies: list[Body]) -> None:
    if not os.path.exists(path):
        return
    for blk in _blocks(path):
        idx = int(blk[0].split()[1])
        vals = []
        on = False
        for line in blk:
            if line.strip().startswith("NO6xx"):
                on = True
            if on:
                vals += numbers_after_eq(line)
        b = bodies[idx - 1]
        b.X = np.array(vals[0:6])
        b.V = np.array(vals[6:12])
        if len(vals) >= 21:
            b.frame = np.array(vals[12:21]).reshape(3, 3).T  # lines are the columns


def read_drv_dof(path: str, bodies: list[Body]) -> None:
    if not os.path.exists(path):
        return
    for blk in _blocks(path):
        idx = int(blk[0].split()[1])
        for line in blk:
            s = line.split()
            if s and s[0] in ("vlocy", "force"):
                if s[0] != "vlocy":
                    raise ValueError(f"DRV_DOF: body {idx}: only vlocy is converted, got {s[0]}")
                dof = int(s[1])
                if s[2] == "evolution":
                    bodies[idx - 1].driven[dof] = ("evolution", s[3])
                else:
                    bodies[idx - 1].driven[dof] = ("const",) + tuple(fnum(x) for x in s[2:8])


def read_bulk(path: str) -> tuple[np.ndarray, dict[str, float]]:
    gravity, dens = np.array([0.0, 0.0, -9.81]), {}
    lines = open(path, encoding="latin-1").read().splitlines()
    for i, line in enumerate(lines):
        if line.startswith("$gravy"):
            gravity = np.array(numbers_after_eq(lines[i + 1])[:3])
        m = re.match(r"^\s*(\S{5})\s+RIGID\b", line)
        if m:
            vals = numbers_after_eq(line) + (numbers_after_eq(lines[i + 1]) if i + 1 < len(lines) else [])
            um = re.search(r"Umas=\s*(" + _NUM + ")", line + " " + (lines[i + 1] if i + 1 < len(lines) else ""))
            dens[m.group(1)] = fnum(um.group(1)) if um else vals[0]
    return gravity, dens


@dataclass
class SeeTable:
    cdbdy: str
    cdtac: str
    cdcol: str
    behav: str
    anbdy: str
    antac: str
    ancol: str
    alert: float


def read_tact(path: str) -> tuple[dict[str, tuple[str, dict]], list[SeeTable]]:
    laws, sees = {}, []
    lines = open(path, encoding="latin-1").read().splitlines()
    for i, line in enumerate(lines):
        if line.startswith("$behav"):
            toks = lines[i + 1].split()
            params = dict((k, fnum(v)) for k, v in re.findall(r"(\w+)=\s*(" + _NUM + ")", lines[i + 1]))
            laws[toks[0]] = (toks[1], params)
        if line.startswith("$seety"):
            toks = lines[i + 2].split()
            sees.append(SeeTable(*toks[:7], fnum(toks[7])))
    return laws, sees


def read_evolution(path: str) -> tuple[np.ndarray, np.ndarray]:
    data = np.loadtxt(path)
    return data[:, 0], data[:, 1]


def fit_harmonic(t: np.ndarray, y: np.ndarray) -> tuple[dict, float]:
    """Least-squares fit of `mean + A cos(2 pi f t - phi)`; returns the table and the largest residual."""
    if np.ptp(y) == 0.0:
        return {"mean": float(y[0])}, 0.0

    def solve(f):
        w = 2 * math.pi * f
        M = np.column_stack([np.ones_like(t), np.cos(w * t), np.sin(w * t)])
        coef, *_ = np.linalg.lstsq(M, y, rcond=None)
        r = M @ coef - y
        return coef, float(np.max(np.abs(r))), float(np.dot(r, r))

    # frequency guess from the mean-crossings, a scan of the squared residual on a grid finer than
    # 1/(record length), then a golden-section refinement within one grid step
    yc = y - np.mean(y)
    crossings = np.sum(np.diff(yc >= 0) != 0)
    f0 = max(crossings / 2.0 / (t[-1] - t[0]), 1e-6)
    grid = np.linspace(0.7 * f0, 1.3 * f0, 2001)
    best = int(np.argmin([solve(f)[2] for f in grid]))
    step = grid[1] - grid[0]
    a, b = grid[best] - step, grid[best] + step
    g = (math.sqrt(5) - 1) / 2
    for _ in range(100):
        c, d = b - g * (b - a), a + g * (b - a)
        if solve(c)[2] < solve(d)[2]:
            b = d
        else:
            a = c
    f = (a + b) / 2
    (m, ca, sa), res, _ = solve(f)
    amp = math.hypot(ca, sa)
    phase = math.atan2(sa, ca)  # A cos(wt - phi) = A cos(phi) cos(wt) + A sin(phi) sin(wt)
    return {"mean": float(m), "amplitude": float(amp), "frequency": float(f), "phase": float(phase)}, res


def polyhedron_centroid(v: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, float]:
    """Volume centroid of a closed triangulated convex surface: tetrahedra from the vertex mean, an
    inside point, taken with their absolute volume (LMGC90 files do not orient their triangles
    consistently)."""
    o = v.mean(axis=0)
    vol, cen = 0.0, np.zeros(3)
    for f in faces:
        a, b, c = v[f[0]] - o, v[f[1]] - o, v[f[2]] - o
        dv = abs(np.dot(a, np.cross(b, c))) / 6.0
        vol += dv
        cen += dv * (a + b + c) / 4.0
    return o + cen / vol, vol


def frame_to_quaternion(F: np.ndarray) -> list[float]:
    """[w, x, y, z] of the rotation matrix F (columns = body axes in world)."""
    # orthonormalise (DATBOX frames have 7 digits)
    u, _, vt = np.linalg.svd(F)
    R = u @ vt
    if np.linalg.det(R) < 0:
        raise ValueError("local frame is not a rotation (det < 0)")
    tr = np.trace(R)
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        w, x, y, z = 0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2]) * 2
        w, x, y, z = (R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s
    elif R[1, 1] > R[2, 2]:
        s = math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2]) * 2
        w, x, y, z = (R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s
    else:
        s = math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1]) * 2
        w, x, y, z = (R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s
    q = np.array([w, x, y, z])
    q /= np.linalg.norm(q)
    if q[0] < 0:
        q = -q
    return [float(c) for c in q]


def quaternion_to_matrix(q) -> np.ndarray:
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def read_datbox(d: str):
    bodies = read_bodies(os.path.join(d, "BODIES.DAT"))
    read_dof_ini(os.path.join(d, "DOF.INI"), bodies)
    read_drv_dof(os.path.join(d, "DRV_DOF.DAT"), bodies)
    gravity, dens = read_bulk(os.path.join(d, "BULK_BEHAV.DAT"))
    laws, sees = read_tact(os.path.join(d, "TACT_BEHAV.DAT"))
    return bodies, gravity, dens, laws, sees
