"""Granular mechanics under cyclic loading: NSCD and MD engines for railway ballast settlement.

SI units throughout: m, s, kg, rad, N, J.
"""

from os import PathLike
from typing import Optional, Union

import numpy as np
import numpy.typing as npt

__version__: str

class SceneError(ValueError):
    """An invalid scene or argument."""

    key: Optional[str]
    """The scene key or argument the message names (``simulation.dt``, ``body[1].polygon``), or None."""

class CheckpointError(ValueError):
    """A checkpoint to resume from was refused or is missing."""

class DivergedError(RuntimeError):
    """A run blew up; the simulation keeps the state of the last good step."""

    step: int
    """The step being made."""
    body: int
    """The body, by its index in the scene."""
    name: str
    """The body's name."""

class StalledError(RuntimeError):
    """A step reached its sweep cap short of the tolerance under ``[nscd] on_stall = "stop"``."""

    step: int

class Simulation:
    """A scene opened on its engine: ``nscd`` or ``md2d`` (2D) or ``md`` (3D spheres)."""

    @property
    def engine(self) -> str:
        """``nscd``, ``md2d`` or ``md``."""
    @property
    def time(self) -> float:
        """Time (s)."""
    @property
    def steps_done(self) -> int:
        """Steps made."""
    @property
    def dt(self) -> float:
        """Time step (s)."""
    def step(self, n: int = 1) -> dict[str, Union[float, int, bool]]:
        """Makes ``n`` steps and returns the last one's statistics: ``time`` (s), ``kinetic_energy`` (J),
        ``contacts``, ``mean_overlap`` and ``max_overlap`` (m), ``iterations``, ``converged``, ``criterion``.
        Raises DivergedError (the state is the last good step's)."""
    @property
    def names(self) -> list[str]:
        """The bodies' names, in scene order."""
    @property
    def fixed(self) -> npt.NDArray[np.bool_]:
        """Which bodies are fixed (or have every velocity component imposed), shape (n,)."""
    @property
    def positions(self) -> npt.NDArray[np.float64]:
        """Shape (n, 3): x, y (m) and the angle (rad) in 2D; x, y, z (m) in 3D."""
    @property
    def velocities(self) -> npt.NDArray[np.float64]:
        """Shape (n, 3): v_x, v_y (m/s) and the spin (rad/s) in 2D; v_x, v_y, v_z (m/s) in 3D."""
    def set_positions(self, positions: npt.NDArray[np.float64]) -> None:
        """Writes the positions back (shape (n, 3), as ``positions`` gives them; fixed bodies' rows unchanged);
        velocities are zeroed."""
    def contacts(self) -> dict[str, Union[list[str], npt.NDArray[np.float64], npt.NDArray[np.int64]]]:
        """The contacts of the last step: ``kind``, ``bodies`` (m, 2), ``points`` and ``normals`` (m, dim),
        ``gaps`` (m), ``normal_forces`` (N), ``tangential_forces`` (m, dim) (N)."""

def load(path: Union[str, PathLike[str]], engine: Optional[str] = None) -> Simulation:
    """Opens a scene file on its engine, or on ``engine`` (``nscd``, ``md2d``, ``md``)."""

def from_toml(text: str, engine: Optional[str] = None, name: str = "scene.toml") -> Simulation:
    """Opens a scene given as TOML text."""
