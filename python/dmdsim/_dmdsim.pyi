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
    """The run of one scene (build it with :func:`dmdsim.load`), advanced through its stages.

    It starts as ``dmd run`` starts (lattice or file, Maxwell–Boltzmann velocities and random or
    given orientations from the scene's seed) and runs the stages the scene gives, in order:
    equilibration (``run.equilibration_events`` or ``run.equilibration_time``, with the
    ``[thermostat]``), HMC equilibration segments (``hmc.equilibration_segments``), then
    production (``run.events``, ``run.time`` or ``hmc.segments``) with the thermostat of
    ``thermostat.during`` and the observables of ``[output]``. Advanced to its end it gives the
    numbers of ``dmd run`` for the same scene and seed (:meth:`summary`, :meth:`observables`).
    Scenes with ``[chains]``, ``[sweep]`` or ``engine = "smd"`` are refused (run them with
    :func:`dmdsim.run` or :func:`dmdsim.run_ensemble`). Arrays are new float64 (species int64)
    numpy arrays in the scene's units: lengths in σ or Å, times in the time unit or ps.
    """

    def __init__(
        self,
        text: str,
        overrides: List[str],
        base: str,
        file: str,
        out: Optional[str] = None,
        force: bool = False,
    ) -> None: ...
    @staticmethod
    def resume(path: str, out: Optional[str] = None, force: bool = False) -> "Simulation":
        """The run saved in ``path`` by :meth:`checkpoint`, at its stage, with its thermostat and
        observables; it continues bit for bit as the run that saved it."""
    def advance(self, events: Optional[int] = None, time: Optional[float] = None) -> None:
        """Runs the scene's stages for ``events`` more events or ``time`` more simulated time,
        or, with neither, to the end of the run.

        The budget carries over from one stage into the next while their lengths are in the
        same unit; a stage whose length is in the other unit (``run.time`` against ``events=``)
        raises ``ValueError`` naming its key, and an HMC stage runs whole segments while the
        budget lasts. A run stops at its end (an ended run raises :class:`RunError`); with an
        output folder its files are written then. Advancing in pieces runs the same events as
        running whole; only the time integrals are summed piece by piece (round-off), and each
        piece of a stage measured in time adds one scheduler entry (the summary's
        ``queue_pushed`` and ``queue_stale_dropped``).

        The GIL is released while the engine runs; Ctrl-C raises ``KeyboardInterrupt`` within
        16384 events, leaving the state whole (it can be advanced again).
        """
    def run(self) -> Dict[str, Any]:
        """Advances to the end of the run and returns its summary (:meth:`summary`)."""
    def summary(self) -> Optional[Dict[str, Any]]:
        """The summary of production so far, the keys and units of ``dmd run``'s
        ``summary.json`` (temperature, pressure, potential energy with their block-average
        ``_error`` bars, diffusion coefficients, event counts, ...); the whole production's,
        equal to the command's, once the run has ended. ``None`` before production."""
    def observables(self) -> Dict[str, Dict[str, npt.NDArray[np.float64]]]:
        """The observables of production so far that ``[output]`` asks for, as
        ``{name: {column: array}}`` with the names and columns of ``dmd run``'s CSV files:
        ``rdf`` (``r``, ``g``, ``g_error``, partials), ``msd`` (``t``, ``msd``, ``msd_error``),
        ``vacf``, ``oacf`` and ``series``. Empty before production."""
    @property
    def stage(self) -> str:
        """``"equilibration"``, ``"hmc equilibration"``, ``"production"``,
        ``"hmc production"``, or ``"ended"``."""
    @property
    def stage_left(self) -> Optional[Tuple[str, float]]:
        """What is left of the current stage: ``("events", n)``, ``("time", t)`` or
        ``("segments", n)``; ``None`` once the run has ended."""
    def checkpoint(self, path: str) -> None:
        """Writes the run to ``path`` (dmd's checkpoint format: state, stage, thermostat,
        observables) for :meth:`resume`.

        The time origin is re-based first (the loop's exact state is saved at a re-basing), so
        this run and a resumed one continue identically from here.
        """
    @property
    def n(self) -> int:
        """Number of bodies."""
    @property
    def time(self) -> float:
        """Simulated time since the start of the run (equilibration included)."""
    @property
    def events(self) -> int:
        """Events of the current stage (pair events, cell crossings, thermostat collisions);
        production counts from its own start, as the summary's ``events``."""
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
