"""The experiments of Saussine et al. (2006): a 2D sample of pentagons deposited on a viscoelastic sublayer
(stage 1), loaded by a sleeper under F = A + B cos(2 pi f t - phi) (§4), settled over cycles, with replicas.

The loading arguments (``**loading``) are the fields of the library's ``LoadingSpec`` (SI units):
``cycles``, ``sleeper_width``, ``sleeper_height``, ``sleeper_density``, ``bar_size``, ``bars``, ``mean`` (A, N),
``amplitude`` (B, N), ``frequency`` (Hz), ``phase`` (rad), ``inclination`` (degrees), ``guide``
(``vertical``, ``level``, ``free``), ``stiffness_factor``, ``dt`` (s), ``criterion``, ``tolerance``,
``min_iterations``, ``max_iterations``, ``output_every``; absent ones are the paper's (A = -1000 N,
B = -500 N, f = 20 Hz, dt = 2e-4 s, 100 cycles), and a sample scaled to fewer grains gets the sleeper's
width and load scaled alike (the same pressure).
"""

import os
from typing import Any, Dict, Optional, Union

from . import _ballast
from ._ballast import Simulation
from ._ensemble import ensemble
from ._sample import Sample, text_of

__all__ = ["sample", "load", "settle"]


def sample(
    out: Union[str, "os.PathLike[str]"],
    grains: Optional[int] = None,
    seed: int = 1,
    dt: Optional[float] = None,
    bank: bool = False,
    resume: bool = False,
    threads: Optional[int] = None,
) -> Simulation:
    """Deposits the sample (``ballast saussine sample``) into ``out``: ``grains`` pentagons (``None``: the
    paper's 724; fewer scale the box's width alike, at least 16), random grading order, angles and start
    velocities from ``seed``, deposited under gravity with time step ``dt`` (s; default 2e-4) until
    equilibrium; with ``bank``, the mould removed and the banks settled. Writes ``out/sample.toml`` and
    ``out/sample.json`` (balance, solid fraction, coordination); ``resume`` continues an interrupted deposit.
    Returns the deposited sample as a Simulation."""
    path = _ballast.saussine_sample(os.fspath(out), grains, seed, dt, bank, resume, threads)
    return _ballast.load(path)


def load(sample: Sample, cycles: int = 100, **loading: Any) -> Simulation:
    """The sample ``sample`` (a path to a ``sample.toml``, or a Simulation: the state it holds) under the
    sleeper (``ballast saussine load``): a Simulation of the loaded scene, ready to ``run`` (its cycles in
    ``cycles.csv``) or ``settle`` (with ``accelerate``)."""
    text, name = text_of(sample)
    loaded = _ballast.saussine_loaded(text, name, {"cycles": cycles, **loading})
    return _ballast.from_toml(loaded, name="loaded.toml")


def settle(
    sample: Sample,
    out: Union[str, "os.PathLike[str]"],
    cycles: int = 100,
    replicas: int = 1,
    executor: Any = None,
    perturbation: float = _ballast.DEFAULT_PERTURBATION_M,
    perturbation_seed: int = _ballast.DEFAULT_PERTURB_SEED,
    seating_cycles: int = _ballast.DEFAULT_SEATING_CYCLES,
    resume: bool = False,
    **loading: Any,
) -> Dict[str, Any]:
    """§4 with replicas (``ballast saussine settle --replicas``): the loaded sample from ``replicas`` starts
    (replica 0 as it is, replica r moved by at most ``perturbation`` m, stream r of ``perturbation_seed``), each
    run in ``out/runs/replica-<r>/`` on ``executor`` (see ``ballast.ensemble``), and the ensemble's settlement
    per cycle with its 95 % intervals in ``out/settlement_ensemble.csv``. Returns ``ensemble``'s dict."""
    return ensemble(
        sample,
        replicas=replicas,
        out=out,
        executor=executor,
        perturbation=perturbation,
        perturbation_seed=perturbation_seed,
        seating_cycles=seating_cycles,
        resume=resume,
        cycles=cycles,
        **loading,
    )
