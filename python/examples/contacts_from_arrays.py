"""A scene built from numpy arrays, its contact forces read back: a column of square blocks stacked on a
floor (NSCD), stepped to rest; the floor carries the column's weight, and each interface the weight above it.

    python python/examples/contacts_from_arrays.py
"""

import numpy as np

import ballast

n, side, density, g = 5, 0.05, 2000.0, 9.81
# The blocks' centres, with a 0.1 mm gap between neighbours: an (n, 2) array.
centres = np.column_stack([np.zeros(n), side / 2 + np.arange(n) * (side + 1e-4) + 1e-4])
square = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * side / 2

blocks = "\n".join(
    f'[[body]]\nname = "block{i}"\nmaterial = "stone"\npolygon = {square.tolist()}\nposition = {c.tolist()}\n'
    for i, c in enumerate(centres)
)
scene = f"""
[simulation]
engine = "nscd"
dt = 1.0e-3
duration = 1.0
gravity = [0.0, -{g}]

[[material]]
name = "stone"
density = {density}

[[contact]]
between = ["stone", "stone"]
friction = 0.5

[[body]]
name = "floor"
material = "stone"
polygon = [[-0.2, -0.05], [0.2, -0.05], [0.2, 0.0], [-0.2, 0.0]]
position = [0.0, 0.0]
fixed = true

{blocks}
"""

sim = ballast.from_toml(scene)
sim.step(300)
c = sim.contacts()
mass = density * side * side  # per metre of thickness
for k in range(n):
    # Contacts whose first body is block k and other body the one below (the floor for k = 0).
    below = 0 if k == 0 else k  # body indices: 0 is the floor, block i is body i + 1
    rows = (c["bodies"][:, 0] == k + 1) & (c["bodies"][:, 1] == below)
    rows |= (c["bodies"][:, 1] == k + 1) & (c["bodies"][:, 0] == below)
    carried = c["normal_forces"][rows].sum()
    expected = (n - k) * mass * g
    print(f"under block {k}: {carried:9.4f} N carried, weight above {expected:9.4f} N")
    assert abs(carried - expected) < 1e-3 * expected, (carried, expected)
print("positions (x, y, angle):")
print(sim.positions[1:])
