"""Event-driven molecular dynamics of rigid bodies (the ``dmd`` engine) from Python.

A scene is a TOML file, TOML text or a dict of the same keys (``docs/USER-GUIDE.md``), with
overrides as ``dmd run --set`` takes them::

    import dmdsim

    sim = dmdsim.load("scenes/hard-spheres.toml", set={"species.0.count": 500})
    sim.advance(events=100_000)   # through the scene's stages: equilibration, production
    sim.positions          # (N, 3) float64, in the box, in the scene's length unit
    sim.state()            # time, events, energies, temperature
    sim.advance()          # to the end of the run
    sim.summary()          # dmd run's summary.json, error bars included
    sim.observables()["rdf"]["g"]   # g(r), MSD, ... as [output] asks, numpy arrays

    summary = dmdsim.run("scenes/rods-paper.toml", out="out/rods", set=["run.time=2"])

    # the jobs of [chains] and [sweep] as tasks on a Dask cluster (a LocalCluster by default)
    aggregate = dmdsim.run_ensemble("sweep.toml", out="out/sweep", client="tcp://head:8786")

Numbers are in the scene's units (reduced, or Å, ps, kJ/mol, K and bar in molecular units).
Errors of the engine are raised as :class:`SceneError`, :class:`RunError` and
:class:`CheckpointError` (all :class:`DmdError`) with the ``dmd`` command's messages.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _dmdsim
from ._dmdsim import CheckpointError, DmdError, RunError, SceneError, Simulation

__all__ = [
    "CheckpointError",
    "DmdError",
    "RunError",
    "SceneError",
    "Simulation",
    "load",
    "read_observables",
    "resume",
    "run",
    "resume_ensemble",
    "run_ensemble",
]

__version__ = "0.1.0"

SceneLike = Union[str, "os.PathLike[str]", Mapping[str, Any]]
Overrides = Union[None, Sequence[str], Mapping[str, Any]]


def _toml_value(v: Any) -> str:
    """A Python value as the TOML text of an override's VALUE (``None``: none, which removes
    the key as ``--set KEY=`` does)."""
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        x = float(v)
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return repr(x)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise SceneError(f"override value {v!r}: a {type(v).__name__} has no TOML form")


def _overrides(set: Overrides) -> list:
    """``KEY=VALUE`` strings, as ``dmd run --set`` takes them."""
    if set is None:
        return []
    if isinstance(set, Mapping):
        return [f"{k}={_toml_value(v)}" for k, v in set.items()]
    if isinstance(set, str):
        return [set]
    return [str(s) for s in set]


def _is_file(scene: Union[str, "os.PathLike[str]"]) -> bool:
    if isinstance(scene, os.PathLike):
        return True
    return "\n" not in scene and "=" not in scene


def _source(scene: SceneLike) -> Tuple[str, str, str]:
    """The scene's TOML text, base folder and file (empty for text and dicts)."""
    if isinstance(scene, Mapping):
        return _dmdsim.dict_to_toml(dict(scene)), os.getcwd(), ""
    if _is_file(scene):
        text, base = _dmdsim.read_scene(os.fspath(scene))
        return text, base, os.fspath(scene)
    return str(scene), os.getcwd(), ""


def load(
    scene: SceneLike,
    set: Overrides = None,
    out: Union[None, str, "os.PathLike[str]"] = None,
    force: bool = False,
) -> Simulation:
    """The run of ``scene`` before its first event, set up as ``dmd run`` sets it up.

    ``scene`` is a path to a TOML file, TOML text or a dict; ``set`` overrides keys like
    ``dmd run --set`` (a list of ``"KEY=VALUE"`` or a dict ``{"KEY": value}``, where the value
    ``None`` removes the key). :meth:`Simulation.advance` runs the scene's stages in order
    (equilibration with its thermostat, HMC segments, production with the observables of
    ``[output]``); with ``out`` the run's files (``summary.json``, the observables' CSV files,
    trajectories) are written into that folder as ``dmd run --out`` writes them, when the run
    ends (``force`` empties a folder holding another run's files). Raises
    :class:`SceneError` with the ``dmd`` command's message for a scene it refuses.
    """
    text, base, file = _source(scene)
    out_path = None if out is None else os.fspath(out)
    return Simulation(text, _overrides(set), base, file, out_path, force)


def resume(
    path: Union[str, "os.PathLike[str]"],
    out: Union[None, str, "os.PathLike[str]"] = None,
    force: bool = False,
) -> Simulation:
    """The run saved by :meth:`Simulation.checkpoint` in ``path``, continuing at its stage
    (``out`` and ``force`` as for :func:`load`)."""
    out_path = None if out is None else os.fspath(out)
    return Simulation.resume(os.fspath(path), out_path, force)


def run(
    scene: SceneLike,
    out: Union[None, str, "os.PathLike[str]"] = None,
    set: Overrides = None,
    checkpoint_every: Optional[str] = None,
    force: bool = False,
) -> Dict[str, Any]:
    """Runs a whole scene as ``dmd run`` does and returns its summary (``summary.json``).

    Equilibration, thermostat, production, observables and, with ``out``, every file of the
    run are the command's; ``engine = "smd"`` scenes run with the standard-MD engine, and
    scenes with ``[chains]`` or ``[sweep]`` run their jobs in parallel into ``out`` (required)
    and return the ensemble's aggregate (``ensemble.json``). ``checkpoint_every`` is
    ``--checkpoint-every`` (``"1e6"`` events or ``"10m"`` of wall time); ``force`` empties an
    ``out`` folder holding another run's files. Ctrl-C stops the run between two events with
    ``KeyboardInterrupt`` (ensembles and the smd engine stop when they end).
    """
    text, base, file = _source(scene)
    out_path = None if out is None else os.fspath(out)
    summary = _dmdsim.run_json(
        text, _overrides(set), base, file, out_path, checkpoint_every, force
    )
    return json.loads(summary)


def read_observables(out: Union[str, "os.PathLike[str]"]) -> Dict[str, Dict[str, np.ndarray]]:
    """The CSV files of a run's folder as ``{stem: {column: float64 array}}``.

    For example ``read_observables("out/rods")["rdf"]`` holds the columns of ``rdf.csv``
    (``r`` and ``g``). Units are the scene's, as in the files.
    """
    tables: Dict[str, Dict[str, np.ndarray]] = {}
    for path in sorted(Path(out).glob("*.csv")):
        with open(path, encoding="utf-8") as f:
            header = f.readline().strip().split(",")
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2, dtype=np.float64)
        if data.size == 0:
            data = np.empty((0, len(header)))
        tables[path.stem] = {name: data[:, k].copy() for k, name in enumerate(header)}
    return tables


def run_ensemble(
    scene: SceneLike,
    out: Union[str, "os.PathLike[str]"],
    set: Overrides = None,
    client: Any = None,
    checkpoint_every: Optional[str] = "10m",
    force: bool = False,
) -> Dict[str, Any]:
    """Runs the jobs of a scene's ``[chains]`` and ``[sweep]`` as tasks on a Dask cluster and
    returns their aggregate (``ensemble.json``), equal to the one ``dmd run`` writes.

    ``client`` is a ``distributed.Client``, a scheduler address (``"tcp://host:8786"``) or a
    cluster object (``distributed.LocalCluster``, dask-jobqueue's ``SLURMCluster`` or
    ``PBSCluster``); ``None`` starts a ``LocalCluster`` of one single-threaded worker process
    per core for the call. Each job writes its own folder under ``out`` (which the workers must
    see at the same path) with a checkpoint every ``checkpoint_every`` (``"10m"`` of wall time,
    ``"1e6"`` events; ``None``: none). A job whose worker is lost is given to another worker by
    Dask and continues from its last checkpoint, bit for bit. ``set`` and ``force`` are those
    of :func:`run`. Needs the ``dask`` and ``distributed`` packages.
    """
    from . import ensemble

    text, base, file = _source(scene)
    return ensemble.run_ensemble(
        text, _overrides(set), base, file, out, client, checkpoint_every, force
    )


def resume_ensemble(out: Union[str, "os.PathLike[str]"], client: Any = None) -> Dict[str, Any]:
    """Finishes the ensemble in ``out`` (started by :func:`run_ensemble` or ``dmd run``) on a
    Dask cluster and returns its aggregate: finished jobs are read back, interrupted ones
    continue from their checkpoints, the others run. ``client`` as for :func:`run_ensemble`.
    """
    from . import ensemble

    return ensemble.resume_ensemble(out, client)
