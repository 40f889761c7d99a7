"""The extension module of ``ballast`` (re-exported by the package): scenes opened on their engine, the
experiments' building blocks. SI units throughout: m, s, kg, rad, N, J.
"""

from os import PathLike
from typing import Any, Callable, Optional, Union

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

    def run(
        self,
        out: Union[str, PathLike[str], None] = None,
        steps: Optional[int] = None,
        checkpoint_every: Optional[float] = None,
        resume: bool = False,
        progress: Optional[Callable[[dict[str, Any]], Any]] = None,
        stop_after: Optional[int] = None,
        vtk_every: int = 0,
        figures: bool = False,
        threads: Optional[int] = None,
        change_solver: bool = False,
        extend: bool = False,
        keep_checkpoint: bool = False,
    ) -> dict[str, Any]:
        """Runs through the library's run loop into ``out`` (None: a temporary folder) from the state held,
        ``steps`` steps (None: the scene's duration), and keeps the state reached. ``progress`` gets a dict at
        the first step, every 20 ms and at the last; ``False`` from it stops the run (a checkpoint). Ctrl-C stops
        it between two steps with a checkpoint and raises KeyboardInterrupt; ``resume=True`` continues the run
        in ``out``, and with ``change_solver=True`` from a scene whose ``[nscd]`` solver keys differ;
        ``extend=True`` continues it past its end to ``steps`` (a finished run keeps the checkpoint to extend
        from when it ran with ``keep_checkpoint=True``). Returns
        ``status``, ``step``, ``end_step``, ``time`` (s), ``kinetic_energy`` (J), ``elapsed_s``, ``out``,
        ``report`` (``summary.json``), ``solver_changes`` (what ``change_solver`` changed)."""
    def settle(
        self,
        cycles: Optional[int] = None,
        accelerate: Optional[tuple[int, int, int]] = None,
        law: Optional[str] = None,
        body: Optional[str] = None,
        settings: Optional[dict[str, Any]] = None,
        out: Union[str, PathLike[str], None] = None,
        progress: Optional[Callable[[dict[str, Any]], Any]] = None,
        resume: bool = False,
        checkpoint_every: Optional[float] = None,
        stop_after: Optional[int] = None,
        figures: bool = False,
        threads: Optional[int] = None,
    ) -> dict[str, Any]:
        """The settlement-acceleration procedure of Karrech et al. (2007, Fig. 10) to ``cycles`` cycles, with
        the scene's ``[settlement]`` table or ``accelerate = (k_i, k, h)``, ``law``, ``body``, ``settings``
        in place of its keys. Returns the run's summary (``summary.json``) with ``out``."""
    def to_toml(self) -> str:
        """The state held as a scene (TOML text)."""

def load(path: Union[str, PathLike[str]], engine: Optional[str] = None) -> Simulation:
    """Opens a scene file on its engine, or on ``engine`` (``nscd``, ``md2d``, ``md``)."""

def from_toml(text: str, engine: Optional[str] = None, name: str = "scene.toml") -> Simulation:
    """Opens a scene given as TOML text."""

def table(path: str) -> dict[str, Union[npt.NDArray[np.int64], npt.NDArray[np.float64], list[str]]]: ...
def saussine_sample(
    out: str, grains: Optional[int] = None, seed: int = 1, dt: Optional[float] = None, bank: bool = False,
    resume: bool = False, threads: Optional[int] = None,
) -> str: ...
def saussine_loaded(sample: str, name: str, loading: Optional[dict[str, Any]] = None) -> str: ...
def karrech_deposit(
    out: str, spheres: int, seed: int, dt: float, duration: float, young: float, every: int, resume: bool,
    threads: Optional[int],
) -> str: ...
def luding_box(spheres: int, friction: float, seed: int, duration: float, every: int) -> str: ...
def replica_starts(
    sample: str, name: str, out: str, replicas: int, perturbation: float, perturbation_seed: int,
    seating_cycles: int, resume: bool, loading: Optional[dict[str, Any]] = None,
) -> tuple[int, int]: ...
def replica_run(
    out: str, r: int, threads: int = 1, resume: bool = False, checkpoint_every: float = 300.0,
    snapshot_every: int = 0,
) -> Optional[str]: ...
def replica_finish(out: str, failures: list[Optional[str]], seating: int) -> tuple[str, list[tuple[str, str]]]: ...

DEFAULT_PERTURBATION_M: float
DEFAULT_PERTURB_SEED: int
DEFAULT_SEATING_CYCLES: int
PAPER_POLICIES: list[tuple[str, float]]
def saussine_convergence(
    sample: str, out: str, policies: list[tuple[str, float]], reference: Optional[tuple[str, float]],
    replicas: tuple[int, float, int, int], jobs: Optional[int], resume: bool, checkpoint_every: float,
    loading: Optional[dict[str, Any]] = None,
) -> tuple[str, list[tuple[str, str]]]: ...
def compare(
    sample: str, out: str, overlaps: list[float], model: str, dt_fraction: Optional[float],
    replicas: tuple[int, float, int, int], jobs: Optional[int], resume: bool, checkpoint_every: float,
    loading: Optional[dict[str, Any]] = None,
) -> tuple[str, list[tuple[str, str]]]: ...
