"""Notebook-sized: deposit a small Saussine sample, load it with the sleeper, run 20 cycles, plot the
settlement per cycle (Saussine et al. 2006, §4; the 724-grain sample of the paper is grains=None).

    python python/examples/settlement.py [OUT]      # about 5 s; writes OUT/settlement.png (default out/py-settlement)
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import ballast

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/py-settlement")

# Stage 1: 50 pentagons deposited under gravity on the sublayer pads until equilibrium.
sample = ballast.saussine.sample(out / "sample", grains=50, seed=1, dt=5e-4)
print(f"deposited: {len(sample.names)} bodies")

# Stage 2: the sleeper on top under F = A + B cos(2 pi f t - phi), scaled to the sample's width.
loaded = ballast.saussine.load(sample, cycles=20)
result = loaded.run(out / "load", progress=lambda p: print(f"\rcycle {p['cycles'][0]}/{p['cycles'][1]}", end=""))
print(f"\n{result['status']} after {result['step']} steps ({result['elapsed_s']:.1f} s)")

cycles = ballast.table(out / "load" / "cycles.csv")
fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(cycles["cycle"], 1e3 * cycles["settlement_at_min_load_m"], marker="o")
ax.set_xlabel("cycle")
ax.set_ylabel("settlement at the load minimum (mm)")
ax.set_title("Sleeper on a 50-grain sample")
fig.tight_layout()
fig.savefig(out / "settlement.png", dpi=120)
print(f"settlement after {cycles['cycle'][-1]} cycles: {1e3 * cycles['settlement_at_min_load_m'][-1]:.3f} mm")
print(f"figure: {out / 'settlement.png'}")
