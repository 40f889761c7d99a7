"""The cyclic triaxial box of David, Garcia-Rojo, Herrmann & Luding (2005): polydisperse frictional spheres
between six walls, compressed isotropically, then cycled."""

from . import _ballast
from ._ballast import Simulation

__all__ = ["box"]


def box(
    spheres: int = 1728, friction: float = 0.1, seed: int = 1, duration: float = 10.0, every: int = 1000
) -> Simulation:
    """The box's isotropic compression (the scene of ``ballast luding compress``): ``spheres`` spheres (343,
    1000, 1728, 3375 in the paper) with radii from ``seed``, friction coefficient ``friction``, the walls
    servo-controlled to the paper's pressure; it runs until equilibrium or ``duration`` (s), a row of
    ``series.csv`` every ``every`` steps. Returns it as a Simulation (not yet run)."""
    return _ballast.from_toml(_ballast.luding_box(spheres, friction, seed, duration, every), name="compress.toml")
