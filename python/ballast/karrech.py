"""The experiments of Karrech et al. (2007): a sample of Hertz-Mindlin spheres (Table 1) deposited under
gravity in a box, then loaded by a plate (the settlement driver's Fig. 10 on MD)."""

import os
from typing import Optional, Union

from . import _ballast
from ._ballast import Simulation

__all__ = ["deposit"]


def deposit(
    out: Union[str, "os.PathLike[str]"],
    spheres: int = 850,
    seed: int = 1,
    dt: float = 1e-7,
    duration: float = 2.0,
    young: float = 46.9e9,
    every: int = 1000,
    resume: bool = False,
    threads: Optional[int] = None,
) -> Simulation:
    """Deposits the Table 1 sample (``ballast karrech deposit``) into ``out``: ``spheres`` spheres (850: the
    paper's quarter sample) with radii and loose positions from ``seed``, Young's modulus ``young`` (Pa), time
    step ``dt`` (s), until E_c/E_p <= 1e-6 or ``duration`` (s); a row of ``series.csv`` every ``every`` steps and
    the figures of the paper's Fig. 3. Returns the deposited state as a Simulation."""
    path = _ballast.karrech_deposit(os.fspath(out), spheres, seed, dt, duration, young, every, resume, threads)
    return _ballast.load(path)
