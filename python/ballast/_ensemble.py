"""Ensembles of settlement runs on any executor in the ``concurrent.futures`` style.

Each replica is a task (``_run_replica``: a module-level function, so that process pools, Dask and mpi4py can
send it by reference) that runs one folder alone; its start depends on its index alone, and the summary is
written from the folders once every task is done, so it is the same, byte for byte, whichever executor ran the
tasks and in whatever order.
"""

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Dict, List, Optional, Sequence, Union

from . import _ballast
from ._sample import Sample, text_of
from ._table import table

__all__ = ["ensemble"]


def _run_replica(out: str, r: int, threads: int, resume: bool, checkpoint_every: float) -> Optional[str]:
    """Runs replica ``r`` of the study in ``out``: ``None``, or the one-line error of a run that failed (an
    invalid start or checkpoint raises)."""
    return _ballast.replica_run(out, r, threads, resume, checkpoint_every)


def ensemble(
    sample: Sample,
    replicas: int = 4,
    settings: Optional[Sequence[Dict[str, Any]]] = None,
    out: Union[str, "os.PathLike[str]", None] = None,
    executor: Any = None,
    perturbation: float = _ballast.DEFAULT_PERTURBATION_M,
    perturbation_seed: int = _ballast.DEFAULT_PERTURB_SEED,
    seating_cycles: int = _ballast.DEFAULT_SEATING_CYCLES,
    resume: bool = False,
    threads: int = 1,
    checkpoint_every: float = 300.0,
    **loading: Any,
) -> Dict[str, Any]:
    """Replicas of a settlement run, each a task on ``executor``, with the statistics of their ensemble.

    ``sample``: a deposited Saussine sample (a path to its ``sample.toml``, or a Simulation), loaded under
    ``**loading`` (``ballast.saussine``'s loading arguments), or a cyclic 2D scene (one with ``[output]
    cycles``) taken as it is. ``replicas`` R: replica 0 from the scene as it is, replica r from it with every
    mobile body moved by at most ``perturbation`` m (stream r of ``perturbation_seed``). ``settings``: a list of
    dicts of loading arguments, each with an optional ``name`` (default ``setting-<i>``), every one replicated;
    ``None``: one setting, ``**loading``.

    Results are written as ``ballast saussine settle --replicas`` writes them: with ``settings=None`` into
    ``out`` (``out/runs/replica-<r>/``, ``out/settlement_ensemble.csv`` and its figure), else into
    ``out/<name>/`` per setting. ``executor``: any object with ``submit`` returning futures with ``result()``
    (tested: ``concurrent.futures`` process and thread pools, a Dask ``Client``, mpi4py's ``MPIPoolExecutor``;
    submitit's executors have that interface, untried); ``None``: a local process pool, one process per core.
    Each run
    steps on ``threads`` threads (the numbers do not depend on them) and checkpoints every ``checkpoint_every``
    s; ``resume`` skips the finished replicas and resumes the checkpointed ones.

    Returns, for ``settings=None``, a dict: ``table`` (``settlement_ensemble.csv`` as ``ballast.table`` reads
    it: per cycle the mean settlement at the load minimum with its standard deviation and 95 % interval, and
    the settlement accrued since the seating cycle), ``path`` (the table's file), ``failed`` (``(replica,
    error)`` of the runs that failed) and ``out``; with settings, a dict of those by setting name.
    """
    if out is None:
        raise ValueError("out: the replicas write their runs into folders; give the folder")
    out = os.fspath(out)
    text, name = text_of(sample)
    plans = []
    for i, setting in enumerate([None] if settings is None else settings):
        if setting is None:
            label, folder, args = None, out, dict(loading)
        else:
            setting = dict(setting)
            label = str(setting.pop("name", f"setting-{i}"))
            folder, args = os.path.join(out, label), {**loading, **setting}
        count, seating = _ballast.replica_starts(
            text, name, folder, replicas, perturbation, perturbation_seed, seating_cycles, resume, args
        )
        plans.append((label, folder, count, seating))
    tasks = [(folder, r, threads, resume, checkpoint_every) for (_, folder, count, _) in plans for r in range(count)]
    own = executor is None
    if own:
        workers = max(1, min(os.cpu_count() or 1, len(tasks)))
        # spawn: a fresh interpreter per worker (a fork of a process with threads running is unsafe).
        executor = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    try:
        futures = [executor.submit(_run_replica, *task) for task in tasks]
        failures: List[Optional[str]] = [f.result() for f in futures]
    finally:
        if own:
            executor.shutdown()
    results: Dict[str, Any] = {}
    first = 0
    for label, folder, count, seating in plans:
        path, failed = _ballast.replica_finish(folder, failures[first : first + count], seating)
        first += count
        result = {"table": table(path), "path": path, "failed": failed, "out": folder}
        if label is None:
            return result
        results[label] = result
    return results
