#!/usr/bin/env python3
"""Write a replica of a 3D scene: every non-fixed body's position moved by at most DIST (m), uniform in the ball.

    python3 perturb_scene.py SRC.toml DST.toml SEED DIST

Seed 0 copies the scene unchanged (replica 0). The scene is edited line by line (the `position = [x, y, z]`
line of each `[[body]]` without `fixed = true`), so the rest of the file is kept byte for byte. The library's
own replicas (`ballast track3d settle --replicas`, `perturb_scene3`) start from a deposited sample; this
starts from any loaded state, such as a run's `final_scene.toml`.
"""
import random, re, sys
src, dst, seed, dist = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
rng = random.Random(seed)
lines = open(src).read().split("\n")
# find body blocks
blocks = []
cur = None
for k, l in enumerate(lines):
    if l.startswith("[["):
        cur = {"kind": l, "start": k, "fixed": False, "pos": None}
        blocks.append(cur)
    elif cur is not None:
        if l.startswith("fixed = true"):
            cur["fixed"] = True
        if l.startswith("position = "):
            cur["pos"] = k
moved = 0
for b in blocks:
    if b["kind"] != "[[body]]" or b["fixed"] or b["pos"] is None or seed == 0:
        continue
    while True:
        d = [rng.uniform(-1, 1) for _ in range(3)]
        if sum(x * x for x in d) <= 1:
            break
    m = re.match(r"position = \[(.*)\]", lines[b["pos"]])
    xyz = [float(v) for v in m.group(1).split(",")]
    xyz = [x + dist * e for x, e in zip(xyz, d)]
    lines[b["pos"]] = "position = [%r, %r, %r]" % tuple(xyz)
    moved += 1
open(dst, "w").write("\n".join(lines))
print(dst, "moved", moved)
