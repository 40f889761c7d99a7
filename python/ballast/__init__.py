"""Granular mechanics under cyclic loading: the NSCD and MD engines of railway ballast settlement.

SI units throughout: m, s, kg, rad, N, J.

- ``load(path)``, ``from_toml(text)``: a scene opened on its engine as a ``Simulation`` (step, run, settle; its
  state as numpy arrays).
- ``saussine``, ``karrech``, ``luding``: the papers' experiments (samples, loaded scenes, studies).
- ``ensemble``: replicas of a settlement run on any ``concurrent.futures``-style executor.
- ``table(path)``: a CSV table the runs and studies write, as numpy arrays.
"""

from ._ballast import (
    CheckpointError,
    DivergedError,
    SceneError,
    Simulation,
    StalledError,
    __version__,
    from_toml,
    load,
)
from ._table import table
from ._ensemble import ensemble
from . import karrech, luding, saussine

__all__ = [
    "CheckpointError",
    "DivergedError",
    "SceneError",
    "Simulation",
    "StalledError",
    "__version__",
    "ensemble",
    "from_toml",
    "karrech",
    "load",
    "luding",
    "saussine",
    "table",
]
