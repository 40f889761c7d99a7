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
from typing import Any, Dict, Optional, Sequence, Tuple, Union

from . import _ballast
from ._ballast import Simulation
from ._ensemble import ensemble
from ._sample import Sample, text_of
from ._table import table

__all__ = ["sample", "load", "settle", "convergence", "compare", "PAPER_POLICIES"]

#: The convergence policies and tolerances of the table of §3.2, as ``(policy, tolerance)``.
PAPER_POLICIES = list(_ballast.PAPER_POLICIES)


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


def _sample_path(sample: Sample, out: Union[str, "os.PathLike[str]"]) -> str:
    """The path of ``sample``'s scene file: a Simulation's state is written to ``out/sample.toml``."""
    if isinstance(sample, Simulation):
        os.makedirs(out, exist_ok=True)
        path = os.path.join(os.fspath(out), "sample.toml")
        with open(path, "w", encoding="utf-8") as f:
            f.write(sample.to_toml())
        return path
    return os.fspath(sample)


def _study_result(path: str, failed: Any, out: Union[str, "os.PathLike[str]"]) -> Dict[str, Any]:
    return {"table": table(path), "path": path, "failed": failed, "out": os.fspath(out)}


def convergence(
    sample: Sample,
    out: Union[str, "os.PathLike[str]"],
    policies: Optional[Sequence[Tuple[str, float]]] = None,
    reference: Optional[Tuple[str, float]] = None,
    replicas: int = 1,
    perturbation: float = _ballast.DEFAULT_PERTURBATION_M,
    perturbation_seed: int = _ballast.DEFAULT_PERTURB_SEED,
    seating_cycles: int = _ballast.DEFAULT_SEATING_CYCLES,
    jobs: Optional[int] = None,
    resume: bool = False,
    checkpoint_every: float = 300.0,
    cycles: int = 100,
    **loading: Any,
) -> Dict[str, Any]:
    """§3.2 (``ballast saussine convergence``): the loaded sample under each ``(policy, tolerance)`` of
    ``policies`` (``None``: the paper's table, ``PAPER_POLICIES``), ``replicas`` runs each, ``jobs`` at a time
    on this machine, compared with ``reference`` (``None``: the tightest ``strict`` run). Writes
    ``out/convergence.csv`` and the figures (cumulated interpenetration, iterations against tolerance, the
    settlement ensembles). Returns ``table`` (``convergence.csv`` as ``ballast.table`` reads it), ``path``,
    ``failed`` and ``out``."""
    path = _sample_path(sample, out)
    reps = (replicas, perturbation, perturbation_seed, seating_cycles)
    args = {"cycles": cycles, **loading}
    done, failed = _ballast.saussine_convergence(
        path, os.fspath(out), list(policies or []), reference, reps, jobs, resume, checkpoint_every, args
    )
    return _study_result(done, failed, out)


def compare(
    sample: Sample,
    out: Union[str, "os.PathLike[str]"],
    overlaps: Sequence[float] = (1e-2, 1e-3, 1e-4),
    model: str = "linear",
    dt_fraction: Optional[float] = None,
    replicas: int = 1,
    perturbation: float = _ballast.DEFAULT_PERTURBATION_M,
    perturbation_seed: int = _ballast.DEFAULT_PERTURB_SEED,
    seating_cycles: int = _ballast.DEFAULT_SEATING_CYCLES,
    jobs: Optional[int] = None,
    resume: bool = False,
    checkpoint_every: float = 300.0,
    cycles: int = 100,
    **loading: Any,
) -> Dict[str, Any]:
    """``ballast compare``: the loaded sample (or a loaded 2D scene with a followed body) on NSCD and on the
    planar MD engine at each ``[soft] max_overlap_ratio`` of ``overlaps`` (contact ``model`` ``linear`` or
    ``hertz``), ``replicas`` runs each, ``jobs`` at a time. Writes ``out/compare.csv`` (one row per run and
    cycle: settlement, overlaps, coordination, wall time) and its figure. Returns ``table``, ``path``,
    ``failed`` and ``out``."""
    path = _sample_path(sample, out)
    reps = (replicas, perturbation, perturbation_seed, seating_cycles)
    args = {"cycles": cycles, **loading}
    done, failed = _ballast.compare(
        path, os.fspath(out), list(overlaps), model, dt_fraction, reps, jobs, resume, checkpoint_every, args
    )
    return _study_result(done, failed, out)
