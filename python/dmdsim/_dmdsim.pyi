"""Type stubs of the compiled half of dmdsim (``dmdsim._dmdsim``)."""

from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

class DmdError(Exception):
    """Base class of every error of the dmd engine."""

class SceneError(DmdError):
    """A scene (file, dict or override) that dmd refuses; the message is the ``dmd`` command's."""

class RunError(DmdError):
    """A run that could not go on (the simulation, an output, a job of an ensemble)."""

class CheckpointError(RunError):
    """A checkpoint that cannot be written, read or resumed."""

class Simulation:
    """The event loop of one scene (build it with :func:`dmdsim.load`).

    It starts in the scene's initial state (lattice or file, Maxwell–Boltzmann velocities and
    random or given orientations from the scene's seed), exactly as ``dmd run`` starts, and runs
    the plain microcanonical dynamics: no equilibration phase, thermostat or observables (those
    belong to :func:`dmdsim.run`). Scenes with ``[hmc]``, ``[chains]``, ``[sweep]`` or
    ``engine = "smd"`` are refused. Arrays are new float64 (species int64) numpy arrays in the
    scene's units: lengths in σ or Å, times in the time unit or ps.
    """

    def __init__(self, text: str, overrides: List[str], base: str, file: str) -> None: ...
    @staticmethod
    def resume(path: str) -> "Simulation":
        """The simulation saved in ``path`` by :meth:`checkpoint`; continues it bit for bit."""
    def advance(self, events: Optional[int] = None, time: Optional[float] = None) -> None:
        """Runs ``events`` more events, or ``time`` more simulated time (exactly one of them).

        The GIL is released while the engine runs; Ctrl-C raises ``KeyboardInterrupt`` within
        16384 events, leaving the state whole (it can be advanced again).
        """
    def checkpoint(self, path: str) -> None:
        """Writes the state to ``path`` (dmd's checkpoint format) for :meth:`resume`.

        The time origin is re-based first (the loop's exact state is saved at a re-basing), so
        this run and a resumed one continue identically from here.
        """
    @property
    def n(self) -> int:
        """Number of bodies."""
    @property
    def time(self) -> float:
        """Simulated time since the start."""
    @property
    def events(self) -> int:
        """Events executed since the start (pair events, cell crossings)."""
    @property
    def units(self) -> str:
        """``"reduced"`` or ``"molecular"``."""
    @property
    def model(self) -> str:
        """The interaction model (``hard-spheres``, ``stepped``, ``terraced-rods``, ...)."""
    @property
    def species_names(self) -> List[str]:
        """Names of the species, indexed by :attr:`species`."""
    @property
    def box_lengths(self) -> npt.NDArray[np.float64]:
        """Box edge lengths, shape (3,)."""
    @property
    def positions(self) -> npt.NDArray[np.float64]:
        """Centres of mass now, wrapped into the box ``[0, L)``, shape (N, 3)."""
    @property
    def unwrapped_positions(self) -> npt.NDArray[np.float64]:
        """Centres of mass now, continuous across box faces, shape (N, 3)."""
    @property
    def velocities(self) -> npt.NDArray[np.float64]:
        """Centre-of-mass velocities, shape (N, 3)."""
    @property
    def quaternions(self) -> npt.NDArray[np.float64]:
        """Attitudes now, unit quaternions ``(w, x, y, z)`` rotating body-frame vectors into the
        lab frame, shape (N, 4). A rod's body z is its axis; rigid bodies and site molecules use
        their principal frame. Spheres and semi-flexible molecules get ``(1, 0, 0, 0)``."""
    @property
    def angular_velocities(self) -> npt.NDArray[np.float64]:
        """Lab-frame angular velocities now (rad per time unit), shape (N, 3); zeros for
        spheres and semi-flexible molecules."""
    @property
    def species(self) -> npt.NDArray[np.int64]:
        """Species index of each body, shape (N,)."""
    def state(self) -> Dict[str, Any]:
        """``time``, ``events``, ``kinetic_energy``, ``potential_energy``, ``total_energy``,
        ``temperature`` (``2K / dof``), ``degrees_of_freedom`` and ``events_by_kind``."""

def run_json(
    text: str,
    overrides: List[str],
    base: str,
    file: str,
    out: Optional[str] = None,
    checkpoint_every: Optional[str] = None,
    force: bool = False,
) -> str: ...
def dict_to_toml(scene: Dict[str, Any]) -> str: ...
def read_scene(file: str) -> Tuple[str, str]: ...
def ensemble_start(
    text: str,
    overrides: List[str],
    base: str,
    file: str,
    out: str,
    checkpoint_every: Optional[str] = None,
    force: bool = False,
) -> List[str]:
    """Sets up every point of an ensemble scene (``[chains]``/``[sweep]``), prepares ``out``
    as ``dmd run`` does and records the scene in ``out/ensemble-source.json``; returns the
    jobs' folders (relative to ``out``) in job order. Nothing runs."""
def ensemble_jobs(out: str) -> List[str]:
    """The jobs' folders of the ensemble recorded in ``out``, in job order."""
def ensemble_job(out: str, k: int) -> Tuple[str, str]:
    """Runs job ``k`` of the ensemble recorded in ``out`` with the GIL released: a finished
    job's ``summary.json`` is read back, an interrupted one continues from its checkpoint, one
    never started runs. Returns its summary as JSON and ``"finished"``, ``"resumed"`` or
    ``"fresh"``."""
def ensemble_aggregate(out: str) -> str:
    """Aggregates the jobs' ``summary.json`` of the ensemble in ``out`` into ``ensemble.json``
    and ``ensemble.csv`` (``dmd run``'s code) and returns the aggregate as JSON."""
