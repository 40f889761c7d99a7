"""A 4-replica ensemble on a Dask LocalCluster: the same loaded sample from 4 starts (replica 0 as it is,
replicas 1-3 with every grain moved by at most 1e-9 m), each replica a task on the cluster, and the mean
settlement per cycle with its 95 % confidence interval (Student's t over the replicas).

    pip install "dask[distributed]" matplotlib
    python python/examples/dask_ensemble.py [OUT]     # about 10 s; writes OUT/ensemble.png (default out/py-ensemble)
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from distributed import Client, LocalCluster

import ballast

if __name__ == "__main__":  # the cluster's worker processes import this file
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/py-ensemble")
    sample = ballast.saussine.sample(out / "sample", grains=50, seed=1, dt=5e-4)
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster, Client(cluster) as client:
        result = ballast.ensemble(sample, replicas=4, out=out / "ensemble", executor=client, cycles=10, dt=1e-3)
    t = result["table"]
    mm = 1e3
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.fill_between(t["cycle"], mm * t["settlement_ci95_low_m"], mm * t["settlement_ci95_high_m"], alpha=0.3,
                    label="95 % interval of the mean")
    ax.plot(t["cycle"], mm * t["settlement_mean_m"], marker="o", label=f"mean of {t['replicas'][0]} replicas")
    ax.set_xlabel("cycle")
    ax.set_ylabel("settlement at the load minimum (mm)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "ensemble.png", dpi=120)
    print(f"failed: {result['failed']}")
    print(f"summary: {result['path']}; figure: {out / 'ensemble.png'}")
