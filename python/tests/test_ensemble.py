"""Ensembles on a Dask cluster: `dmdsim.run_ensemble` with a lost worker gives `dmd run`'s
aggregate."""

import json
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest

import dmdsim

SKIP = "dmdsim.run_ensemble needs dask and distributed (pip install dask distributed)"
distributed = pytest.importorskip("distributed", reason=SKIP)
pytest.importorskip("dask", reason=SKIP)

ROOT = Path(__file__).resolve().parents[2]


def square_well(events):
    """Square-well fluid at two densities × two chains (four jobs); a re-basing, hence a
    chance to checkpoint, every 5000 events."""
    return {
        "version": 1,
        "seed": 5,
        "box": {"density": 0.4},
        "species": [{"name": "A", "count": 108}],
        "pair": [{"species": ["A", "A"], "steps": [[1.0, float("inf")], [1.5, -1.0]]}],
        "init": {"positions": "fcc", "temperature": 1.5},
        "run": {"equilibration_events": 2_000, "events": events, "rebase_events": 5_000},
        "chains": {"count": 2},
        "sweep": {"key": "box.density", "values": [0.3, 0.5]},
    }


def dmd_command():
    """The `dmd` command of this clone's build, if it is built."""
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return next(
        (p for p in [target / "debug" / "dmd", target / "release" / "dmd"] if p.exists()), None
    )


def assert_same_aggregate(a: Path, b: Path):
    """`ensemble.json` and `ensemble.csv` of two ensemble folders, value for value."""
    assert json.loads((a / "ensemble.json").read_text()) == json.loads(
        (b / "ensemble.json").read_text()
    )
    assert (a / "ensemble.json").read_bytes() == (b / "ensemble.json").read_bytes()
    assert (a / "ensemble.csv").read_bytes() == (b / "ensemble.csv").read_bytes()


def job_events():
    """Events that make a job last about a second on this build and machine (a
    dev build runs ~2.5·10⁵ events/s here, a release build several times more), so that a
    worker can be caught in the middle of a job: the engine's own rate on a short job."""
    probe = square_well(events=20_000)
    del probe["chains"], probe["sweep"]
    rate = dmdsim.run(probe)["events_per_second"]
    return int(min(max(rate, 150_000), 3_000_000))


def test_a_killed_worker_s_job_resumes_and_the_aggregate_is_dmd_run_s(tmp_path):
    scene = square_well(events=job_events())
    reference = tmp_path / "reference"
    expected = dmdsim.run(scene, out=reference)
    jobs = expected["jobs"]
    assert len(jobs) == 4

    out = tmp_path / "dask"
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    client = distributed.Client(cluster)
    try:
        pids = client.run(os.getpid)
        result = {}

        def run():
            try:
                result["aggregate"] = dmdsim.run_ensemble(
                    scene, out, client=client, checkpoint_every="1"
                )
            except BaseException as e:  # handed to the test's thread
                result["error"] = e

        runner = threading.Thread(target=run)
        runner.start()
        # Kill the worker of the first job seen with a checkpoint and no summary yet: it is
        # in the middle of its run.
        killed = None
        deadline = time.monotonic() + 120
        while killed is None and runner.is_alive() and time.monotonic() < deadline:
            for job in jobs:
                folder = out / job
                if (folder / "checkpoint.dmd").exists() and not (folder / "summary.json").exists():
                    running = {
                        w: keys
                        for w, keys in client.processing().items()
                        if any(str(k).endswith("-" + job) for k in keys)
                    }
                    if len(running) == 1:
                        (worker,) = running
                        os.kill(pids[worker], signal.SIGKILL)
                        killed = (job, pids[worker])
                        break
            time.sleep(0.01)
        runner.join(timeout=180)
        assert not runner.is_alive(), "the ensemble did not finish"
        assert "error" not in result, result.get("error")
        assert killed is not None, "no job was seen running with a checkpoint"
        # The killed job finished on another worker, continued from its checkpoint.
        events = [e for _, e in client.get_events(dmdsim.ensemble.EVENT_TOPIC)]
        done = {e["job"]: e for e in events if e["out"] == str(out)}
        assert sorted(done) == sorted(jobs)
        job, pid = killed
        assert done[job]["start"] == "resumed", done[job]
        assert done[job]["pid"] != pid
    finally:
        client.close()
        cluster.close()

    # The aggregate is dmd run's, value for value (the same code on the same per-job seeds).
    assert result["aggregate"] == expected
    assert_same_aggregate(out, reference)
    # And that of the command itself, when it is built.
    dmd = dmd_command()
    if dmd is not None:
        scene_file = tmp_path / "scene.toml"
        scene_file.write_text(dmdsim._dmdsim.dict_to_toml(scene))
        cli = tmp_path / "cli"
        subprocess.run(
            [str(dmd), "run", str(scene_file), "--quiet", "--out", str(cli)],
            check=True,
            capture_output=True,
        )
        assert_same_aggregate(out, cli)


def test_without_a_client_a_local_cluster_runs_the_jobs(tmp_path):
    scene = square_well(events=10_000)
    scene["sweep"]["values"] = [0.3]
    aggregate = dmdsim.run_ensemble(scene, tmp_path / "dask", checkpoint_every=None)
    expected = dmdsim.run(scene, out=tmp_path / "reference")
    assert aggregate == expected
    assert_same_aggregate(tmp_path / "dask", tmp_path / "reference")
    # A finished ensemble run again into its folder is refused, as by dmd run, unless forced.
    with pytest.raises(dmdsim.RunError):
        dmdsim.run_ensemble(scene, tmp_path / "dask")


def test_a_scene_without_chains_or_sweep_is_refused(tmp_path):
    scene = square_well(events=1_000)
    del scene["chains"], scene["sweep"]
    with pytest.raises(dmdsim.SceneError, match=r"\[chains\] or \[sweep\]"):
        dmdsim.run_ensemble(scene, tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_resume_ensemble_reads_back_finished_jobs_and_runs_the_rest(tmp_path):
    scene = square_well(events=10_000)
    out = tmp_path / "dask"
    text = dmdsim._dmdsim.dict_to_toml(scene)
    jobs = dmdsim._dmdsim.ensemble_start(text, [], str(tmp_path), "", str(out))
    assert jobs == ["point-0/chain-0", "point-0/chain-1", "point-1/chain-0", "point-1/chain-1"]
    # One job done before the client went away; nothing else ran.
    _, start = dmdsim._dmdsim.ensemble_job(str(out), 2)
    assert start == "fresh"
    # A cluster object as the client (threads: the jobs hold no GIL while they run).
    cluster = distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    )
    try:
        aggregate = dmdsim.resume_ensemble(out, client=cluster)
        with distributed.Client(cluster) as client:
            events = [e for _, e in client.get_events(dmdsim.ensemble.EVENT_TOPIC)]
    finally:
        cluster.close()
    starts = {e["job"]: e["start"] for e in events}
    assert starts == {j: "finished" if k == 2 else "fresh" for k, j in enumerate(jobs)}
    expected = dmdsim.run(scene, out=tmp_path / "reference")
    assert aggregate == expected
    assert_same_aggregate(out, tmp_path / "reference")
