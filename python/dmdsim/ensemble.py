"""Ensembles (``[chains]`` and ``[sweep]``) run as tasks on a Dask cluster.

Every job of the scene is one task. The task runs, resumes or reads back its job through the
engine's own code (``dmd_sim::chains``): a finished job's ``summary.json`` is read back, an
interrupted one continues bit for bit from the checkpoint in its folder, one never started runs
from its start. When a worker is lost, Dask's scheduler gives its task to another worker, which
therefore continues the job from its last checkpoint. Once every job is done, the aggregate
(``ensemble.json``, ``ensemble.csv``) is written by the same function that ``dmd run`` uses,
from the same per-job seeds, so it equals the one ``dmd run`` writes on one machine.

Workers must import the same build of ``dmdsim`` (checkpoints are continued only by the
``dmd`` version that wrote them) and see ``out`` at the same path (a shared file system on a
cluster).
"""

from __future__ import annotations

import json
import os
import uuid
from typing import Any, Dict, List, Optional, Union

from . import _dmdsim

#: The topic of the events the tasks log on the scheduler (``client.get_events(EVENT_TOPIC)``).
EVENT_TOPIC = "dmdsim.ensemble"


def _job(out: str, k: int, folder: str) -> Dict[str, Any]:
    """The task of job ``k`` (in ``out/folder``): runs, resumes or reads it back and returns,
    and logs as an event of :data:`EVENT_TOPIC`, how it found the job."""
    # The summary stays in the job's folder, where the aggregate reads it from.
    _, start = _dmdsim.ensemble_job(out, k)
    record: Dict[str, Any] = {"out": out, "job": folder, "start": start, "pid": os.getpid()}
    try:
        from distributed import get_worker

        worker = get_worker()
    except (ImportError, ValueError):
        return record
    record["worker"] = worker.address
    worker.log_event(EVENT_TOPIC, record)
    return record


def run_ensemble(
    text: str,
    overrides: list,
    base: str,
    file: str,
    out: Union[str, "os.PathLike[str]"],
    client: Any = None,
    checkpoint_every: Optional[str] = "10m",
    force: bool = False,
) -> Dict[str, Any]:
    """See :func:`dmdsim.run_ensemble`."""
    _distributed()
    out = os.path.abspath(os.fspath(out))
    jobs = _dmdsim.ensemble_start(
        text, list(overrides), os.fspath(base), os.fspath(file), out, checkpoint_every, force
    )
    return _run_jobs(out, jobs, client)


def resume_ensemble(out: Union[str, "os.PathLike[str]"], client: Any = None) -> Dict[str, Any]:
    """See :func:`dmdsim.resume_ensemble`."""
    _distributed()
    out = os.path.abspath(os.fspath(out))
    return _run_jobs(out, _dmdsim.ensemble_jobs(out), client)


def _distributed():
    try:
        import distributed
    except ImportError as e:  # depends on the environment
        raise ImportError(
            "dmdsim's Dask ensembles need Dask's distributed scheduler: "
            "pip install dask distributed"
        ) from e
    return distributed


def _run_jobs(out: str, jobs: List[str], client: Any) -> Dict[str, Any]:
    """Runs every job of the ensemble recorded in ``out`` as a task on ``client``'s cluster
    and writes the aggregate."""
    distributed = _distributed()
    own_cluster = None
    own_client = None
    if client is None:
        # One thread per worker process: a job is single-threaded and holds no GIL while it
        # runs, and a lost process costs one job.
        own_cluster = distributed.LocalCluster(threads_per_worker=1, processes=True)
        own_client = distributed.Client(own_cluster)
        client = own_client
    elif not isinstance(client, distributed.Client):
        # A scheduler address ("tcp://host:8786") or a cluster object (LocalCluster,
        # dask-jobqueue's SLURMCluster or PBSCluster, ...).
        own_client = distributed.Client(client)
        client = own_client
    try:
        # Keys end with the job's folder (they show in Dask's dashboard); the tag keeps two
        # ensembles on one scheduler apart.
        tag = uuid.uuid4().hex[:8]
        futures = [
            client.submit(_job, out, k, d, key=f"dmdsim-{tag}-{k}-{d}", pure=False)
            for k, d in enumerate(jobs)
        ]
        client.gather(futures)
    finally:
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()
    return json.loads(_dmdsim.ensemble_aggregate(out))
