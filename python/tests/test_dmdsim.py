"""Tests of the dmdsim package: run with `python3 -m pytest python/tests` after installing it."""

import contextlib
import json
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import dmdsim

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


def hard_spheres(count=256, events=20_000, time=None):
    """Hard spheres at ρσ³ = 0.5 on an fcc lattice (4 n³ bodies), NVE production of `events`
    events (or of simulated `time`)."""
    run = {"equilibration_events": 0, "events": events}
    if time is not None:
        run = {"equilibration_events": 0, "time": time}
    return {
        "version": 1,
        "seed": 7,
        "box": {"density": 0.5},
        "species": [{"name": "A", "count": count}],
        "pair": [{"species": ["A", "A"], "steps": [[1.0, float("inf")]]}],
        "init": {"positions": "fcc", "temperature": 1.0},
        "run": run,
    }


def test_arrays_have_the_documented_shapes_and_dtypes():
    sim = dmdsim.load(hard_spheres())
    n = 256
    assert sim.n == n
    assert sim.model == "hard-spheres"
    assert sim.units == "reduced"
    assert sim.species_names == ["A"]
    for name, shape, dtype in [
        ("positions", (n, 3), np.float64),
        ("unwrapped_positions", (n, 3), np.float64),
        ("velocities", (n, 3), np.float64),
        ("quaternions", (n, 4), np.float64),
        ("angular_velocities", (n, 3), np.float64),
        ("species", (n,), np.int64),
        ("box_lengths", (3,), np.float64),
    ]:
        a = getattr(sim, name)
        assert isinstance(a, np.ndarray), name
        assert a.shape == shape, name
        assert a.dtype == dtype, name
    # Spheres have no attitude: identity quaternions, no angular velocity.
    np.testing.assert_array_equal(sim.quaternions, np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)))
    assert not sim.angular_velocities.any()
    # ρ = N / V.
    assert np.prod(sim.box_lengths) == pytest.approx(n / 0.5, rel=1e-12)


def test_advance_by_events_conserves_energy_and_stays_in_the_box():
    sim = dmdsim.load(hard_spheres())
    before = sim.state()
    assert before["events"] == 0 and before["time"] == 0.0
    # Maxwell–Boltzmann velocities at kT = 1 with zero total momentum.
    assert np.abs(sim.velocities.sum(axis=0)).max() < 1e-12
    p0 = sim.positions.copy()
    sim.advance(events=20_000)
    after = sim.state()
    assert sim.events == after["events"] == 20_000
    assert after["time"] > 0.0
    assert after["potential_energy"] == 0.0
    assert after["total_energy"] == pytest.approx(before["total_energy"], rel=1e-12)
    pos = sim.positions
    assert not np.array_equal(pos, p0)
    assert (pos >= 0.0).all() and (pos < sim.box_lengths).all()
    # Unwrapped positions differ from them by whole box lengths.
    shift = (sim.unwrapped_positions - pos) / sim.box_lengths
    np.testing.assert_allclose(shift, np.round(shift), atol=1e-9)
    assert np.abs(sim.velocities.sum(axis=0)).max() < 1e-10
    assert after["events_by_kind"]["core"] > 0


def test_advance_by_time_ends_at_that_time():
    sim = dmdsim.load(hard_spheres(time=10.0))
    sim.advance(time=0.25)
    assert sim.time == pytest.approx(0.25, abs=1e-12)
    sim.advance(time=0.25)
    assert sim.time == pytest.approx(0.5, abs=1e-12)
    assert sim.stage == "production"
    assert sim.stage_left[0] == "time"
    assert sim.stage_left[1] == pytest.approx(9.5, abs=1e-12)
    with pytest.raises(ValueError):
        sim.advance(events=10, time=1.0)
    with pytest.raises(ValueError):
        sim.advance(time=-1.0)
    # Production is measured in time (run.time): an events budget is refused, naming the key.
    with pytest.raises(ValueError, match="run.time"):
        sim.advance(events=10)


def test_a_resumed_checkpoint_continues_bit_for_bit(tmp_path):
    path = tmp_path / "state.dmd"
    a = dmdsim.load(hard_spheres(), set={"seed": 11})
    a.advance(events=7_000)
    a.checkpoint(path)
    b = dmdsim.resume(path)
    assert b.events == a.events
    np.testing.assert_array_equal(b.positions, a.positions)
    a.advance(events=9_000)
    b.advance(events=9_000)
    assert a.events == b.events == 16_000
    assert a.time == b.time
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.velocities, b.velocities)
    assert a.state() == b.state()


def test_a_checkpoint_that_is_not_one_raises(tmp_path):
    bad = tmp_path / "junk.dmd"
    bad.write_bytes(b"not a checkpoint")
    with pytest.raises(dmdsim.CheckpointError):
        dmdsim.resume(bad)


def dmd_command():
    """The `dmd` command of this clone's build, if it is built."""
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return next(
        (p for p in [target / "debug" / "dmd", target / "release" / "dmd"] if p.exists()), None
    )


def test_a_bad_key_raises_scene_error_with_the_commands_message(tmp_path):
    scene = hard_spheres()
    scene["box"] = {"densty": 0.5}
    with pytest.raises(dmdsim.SceneError) as e:
        dmdsim.load(scene)
    assert isinstance(e.value, dmdsim.DmdError)
    assert "densty" in str(e.value)
    # The same text as `dmd run` prints after `dmd: FILE: `, when the command is built.
    dmd = dmd_command()
    if dmd is None:
        pytest.skip("the dmd command is not built")
    file = tmp_path / "bad.toml"
    file.write_text((SCENES / "hard-spheres.toml").read_text())
    with pytest.raises(dmdsim.SceneError) as from_file:
        dmdsim.load(file, set=["box.densty=0.5"])
    cli = subprocess.run(
        [str(dmd), "run", str(file), "--set", "box.densty=0.5", "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
    )
    assert cli.returncode == 2
    assert cli.stderr.strip() == f"dmd: {file}: {from_file.value}"


def test_overrides_as_list_or_dict_and_scene_as_text():
    text = (SCENES / "hard-spheres.toml").read_text()
    a = dmdsim.load(text, set=["species.0.count=108", "box.density=0.4"])
    b = dmdsim.load(SCENES / "hard-spheres.toml", set={"species.0.count": 108, "box.density": 0.4})
    assert a.n == b.n == 108
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.velocities, b.velocities)
    with pytest.raises(dmdsim.SceneError):
        dmdsim.load(SCENES / "no-such-scene.toml")


def test_run_returns_the_summary_and_writes_the_commands_files(tmp_path):
    scene = hard_spheres(events=30_000)
    scene["run"]["equilibration_events"] = 5_000
    scene["output"] = {"sample_interval": 0.05, "rdf": {"bins": 50, "r_max": 2.5}}
    summary = dmdsim.run(scene, out=tmp_path / "run")
    assert summary["events"] == 30_000
    assert summary["equilibration_events"] == 5_000
    assert summary["n_bodies"] == 256
    assert summary["relative_energy_drift"] < 1e-12
    assert 2.5 < summary["compressibility"] < 4.5
    on_disk = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert on_disk == summary
    obs = dmdsim.read_observables(tmp_path / "run")
    rdf = obs["rdf"]
    r, g = rdf[list(rdf)[0]], rdf[list(rdf)[1]]
    assert r.dtype == np.float64 and len(r) == 50
    # No pair closer than the hard core; the contact peak is above 1.
    assert (g[r < 0.95] == 0).all()
    assert g.max() > 1.2
    # The same scene again gives the same physics (the seed fixes everything).
    again = dmdsim.run(scene)
    for key in ["events", "sim_time", "pressure", "energy_total_end"]:
        assert again[key] == summary[key]


TIMINGS = {
    "wall_seconds",
    "cpu_seconds",
    "events_per_second",
    "events_per_cpu_second",
    "pair_events_per_second",
    "pair_events_per_cpu_second",
}


def test_run_gives_the_summary_of_the_command(tmp_path):
    dmd = dmd_command()
    if dmd is None:
        pytest.skip("the dmd command is not built")
    scene = SCENES / "square-well.toml"
    overrides = ["species.0.count=256", "run.equilibration_events=2000", "run.events=10000"]
    summary = dmdsim.run(scene, out=tmp_path / "py", set=overrides)
    args = [str(dmd), "run", str(scene), "--quiet", "--out", str(tmp_path / "cli")]
    for o in overrides:
        args += ["--set", o]
    subprocess.run(args, check=True, capture_output=True)
    cli = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert summary.keys() == cli.keys()
    for key in summary.keys() - TIMINGS:
        assert summary[key] == cli[key], key


@contextlib.contextmanager
def ctrl_c_after(seconds):
    """Sends this process SIGINT after `seconds`, with Python's own handler in place: a
    process started in the background by a shell without job control inherits SIGINT
    ignored, and Python then installs no handler, so the signal would never arrive."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)


def test_ctrl_c_stops_a_whole_run():
    started = time.monotonic()
    with ctrl_c_after(0.5), pytest.raises(KeyboardInterrupt):
        dmdsim.run(hard_spheres(count=500, events=10**12))
    assert time.monotonic() - started < 30.0


def test_run_refuses_a_folder_holding_another_run(tmp_path):
    scene = hard_spheres(events=2_000)
    dmdsim.run(scene, out=tmp_path)
    with pytest.raises(dmdsim.RunError):
        dmdsim.run(scene, out=tmp_path)
    assert dmdsim.run(scene, out=tmp_path, force=True)["events"] == 2_000


def test_rods_have_unit_quaternions_and_the_kinetic_energy_of_their_motion():
    sim = dmdsim.load(SCENES / "rods-paper.toml")
    assert sim.model == "terraced-rods"
    assert sim.units == "molecular"
    assert sim.stage == "equilibration"
    sim.advance(time=0.05)  # ps, within equilibration (thermostatted)
    assert sim.stage == "equilibration"
    q = sim.quaternions
    assert q.shape == (512, 4)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    assert np.abs(q[:, 0]).max() < 1.0  # not identities: the rods point every way
    # The axis is the body z rotated into the lab frame; a linear rotor turns across it.
    w, x, y, z = q.T
    axis = np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=1)
    omega = sim.angular_velocities
    assert np.abs((omega * axis).sum(axis=1)).max() < 1e-9 * np.abs(omega).max()
    # ½ m v² + ½ I ω² in g/mol·Å²/ps² (10 J/mol) is the engine's kinetic energy in kJ/mol.
    mass, inertia = 18.0, 1.154
    kinetic = 0.5 * mass * (sim.velocities**2).sum() + 0.5 * inertia * (omega**2).sum()
    assert kinetic / 100.0 == pytest.approx(sim.state()["kinetic_energy"], rel=1e-10)


def test_rods_load_from_the_last_frame_of_their_gsd_trajectory(tmp_path):
    hoomd = pytest.importorskip("gsd.hoomd")
    short = {
        "species.0.count": 216,
        "run.equilibration_time": 0.0,
        "run.time": 0.01,
        "output": None,
        "output.gsd": {"interval": 0.005},
    }
    dmdsim.run(SCENES / "rods-paper.toml", out=tmp_path / "a", set=short)
    path = tmp_path / "a" / "trajectory.gsd"
    start = {
        "species.0.count": 216,
        "init.positions": "file",
        "init.file": str(path),
        "init.frame": -1,
        "init.orientations": "file",
        "init.velocities": "file",
        "output": None,
    }
    sim = dmdsim.load(SCENES / "rods-paper.toml", set=start)
    with hoomd.open(str(path), "r") as t:
        last = t[len(t) - 1]
    # The state of the frame, to its single precision: positions (GSD's box is centred, the
    # engine's starts at 0), quaternions (w, x, y, z both) and velocities (Å/ps).
    box = sim.box_lengths
    d = sim.positions - last.particles.position
    d -= box * np.round(d / box)
    assert np.abs(d).max() < 1e-6 * box.max()
    np.testing.assert_allclose(sim.quaternions, last.particles.orientation, atol=1e-6)
    v = last.particles.velocity
    assert np.abs(sim.velocities - v).max() < 1e-6 * np.abs(v).max()


def test_ctrl_c_stops_the_engine_and_leaves_it_usable():
    sim = dmdsim.load(hard_spheres(count=500, events=10**12))
    started = time.monotonic()
    with ctrl_c_after(0.5), pytest.raises(KeyboardInterrupt):
        sim.advance(events=10**12)
    # The timer thread ran while the engine did: the GIL was released.
    assert time.monotonic() - started < 30.0
    stopped = sim.events
    assert 0 < stopped < 10**12
    sim.advance(events=1_000)
    assert sim.events == stopped + 1_000


def test_dicts_that_have_no_toml_form_raise_scene_error():
    scene = hard_spheres()
    scene["init"]["temperature"] = object()
    with pytest.raises(dmdsim.SceneError, match="init.temperature"):
        dmdsim.load(scene)


def test_the_example_script_parses():
    source = (ROOT / "python" / "examples" / "rods_gr.py").read_text()
    compile(source, "rods_gr.py", "exec")


def cli_summary(dmd, scene, overrides, out):
    """`dmd run SCENE --set ...`'s summary.json and observables, written into `out`."""
    args = [str(dmd), "run", str(scene), "--quiet", "--out", str(out)]
    for o in overrides:
        args += ["--set", o]
    subprocess.run(args, check=True, capture_output=True)
    return json.loads((out / "summary.json").read_text()), dmdsim.read_observables(out)


def assert_same_run(py_summary, py_tables, cli, cli_tables):
    """Every value of the summary (timings and the files written apart) and every number of
    every observable the same, to the last digit."""
    assert py_summary.keys() == cli.keys()
    for key in py_summary.keys() - TIMINGS - {"files"}:
        assert py_summary[key] == cli[key], key
    assert py_tables.keys() == cli_tables.keys()
    for name, columns in cli_tables.items():
        assert py_tables[name].keys() == columns.keys(), name
        for column, values in columns.items():
            np.testing.assert_array_equal(py_tables[name][column], values, err_msg=name)


ROD_RUN = [
    "species.0.count=216",
    "run.equilibration_time=0.1",
    "run.time=0.1",
    "output.sample_interval=0.002",
    "output.rdf.r_max=8.0",
    "output.msd.max_lag=0.02",
    "output.vacf.max_lag=0.02",
    "output.orientation_acf.max_lag=0.02",
]


def test_a_thermostatted_rods_run_gives_the_commands_numbers(tmp_path):
    dmd = dmd_command()
    if dmd is None:
        pytest.skip("the dmd command is not built")
    scene = SCENES / "rods-paper.toml"
    sim = dmdsim.load(scene, set=ROD_RUN, out=tmp_path / "py")
    assert sim.summary() is None  # no production yet
    # The Andersen thermostat acts in equilibration (thermostat collisions are events).
    sim.advance(time=0.05)
    assert sim.stage == "equilibration"
    assert sim.state()["events_by_kind"]["thermostat"] > 0
    sim.advance(time=0.05)
    assert sim.stage == "production"
    # Production counts its events from its own start, as the summary does.
    assert sim.summary()["equilibration_events"] > 0 and sim.events == 0
    summary = sim.run()
    assert sim.stage == "ended"
    cli, cli_tables = cli_summary(dmd, scene, ROD_RUN, tmp_path / "cli")
    # Run whole, every number is the command's.
    whole = dmdsim.load(scene, set=ROD_RUN)
    assert_same_run(whole.run(), whole.observables(), cli, cli_tables)
    # Run in pieces of time, too: each piece's end is one more entry in the scheduler (its
    # bookkeeping counters differ), the dynamics are the same.
    tables = sim.observables()
    assert {"rdf", "msd", "vacf", "oacf", "series"} <= tables.keys()
    bookkeeping = {"queue_pushed", "queue_stale_dropped"}
    assert_same_run(
        {k: v for k, v in summary.items() if k not in bookkeeping},
        tables,
        {k: v for k, v in cli.items() if k not in bookkeeping},
        cli_tables,
    )
    # The Python run's folder holds the command's files, the same summary among them.
    on_disk = json.loads((tmp_path / "py" / "summary.json").read_text())
    assert on_disk == summary
    assert summary["files"] == cli["files"]
    assert summary["temperature_error"] is not None
    with pytest.raises(dmdsim.RunError, match="ended"):
        sim.advance(time=0.01)


HS_RUN = [
    "species.0.count=500",
    "run.equilibration_events=20000",
    "run.events=60000",
    "output.sample_interval=0.05",
    "output.rdf={bins = 100, r_max = 2.5}",
    "output.msd={max_lag = 0.5}",
    "thermostat.kind=\"andersen\"",
    "thermostat.rate=1.0",
    "thermostat.during=\"always\"",
]


def test_a_hard_sphere_run_in_pieces_gives_the_commands_numbers(tmp_path):
    dmd = dmd_command()
    if dmd is None:
        pytest.skip("the dmd command is not built")
    scene = SCENES / "hard-spheres.toml"
    cli, cli_tables = cli_summary(dmd, scene, HS_RUN, tmp_path / "cli")
    whole = dmdsim.load(scene, set=HS_RUN)
    assert_same_run(whole.run(), whole.observables(), cli, cli_tables)
    # In pieces of events that cross from equilibration into production: the same events;
    # the time integrals are summed piece by piece, so the averages agree to round-off.
    pieces = dmdsim.load(scene, set=HS_RUN)
    for _ in range(5):
        pieces.advance(events=13_000)
        assert pieces.state()["events_by_kind"]["thermostat"] > 0  # NVT throughout
    assert pieces.stage == "production"
    assert pieces.stage_left == ("events", 20_000 + 60_000 - 5 * 13_000.0)
    pieces.advance()
    summary = pieces.summary()
    for key in ["events", "equilibration_events", "sim_time", "energy_total_end", "seed"]:
        assert summary[key] == cli[key], key
    for key in ["temperature", "pressure", "potential_energy_per_body", "pressure_error"]:
        assert summary[key] == pytest.approx(cli[key], rel=1e-12), key
    np.testing.assert_array_equal(pieces.observables()["rdf"]["g"], cli_tables["rdf"]["g"])


def test_a_checkpoint_in_equilibration_resumes_into_the_same_production(tmp_path):
    scene = SCENES / "hard-spheres.toml"
    a = dmdsim.load(scene, set=HS_RUN)
    a.advance(events=12_000)
    a.checkpoint(tmp_path / "eq.dmd")
    b = dmdsim.resume(tmp_path / "eq.dmd", out=tmp_path / "b")
    assert b.stage == "equilibration" and b.stage_left == ("events", 8_000.0)
    # The thermostat, the stages and the observers carry on as in the run that saved it.
    ours, resumed = a.run(), b.run()
    for key in ours.keys() - TIMINGS - {"files"}:
        assert resumed[key] == ours[key], key
    np.testing.assert_array_equal(a.observables()["msd"]["msd"], b.observables()["msd"]["msd"])
    assert json.loads((tmp_path / "b" / "summary.json").read_text()) == resumed


def test_hmc_stages_run_as_the_scene_says():
    scene = SCENES / "square-well-hmc.toml"
    short = {
        "chains": None,
        "sweep": None,
        "species.0.count": 108,
        "run.equilibration_events": 2_000,
        "hmc.equilibration_segments": 3,
        "hmc.segments": 5,
        "hmc.segment_time": 0.2,
    }
    sim = dmdsim.load(scene, set=short)
    assert sim.stage == "equilibration"
    sim.advance(events=2_000)
    assert sim.stage == "hmc equilibration" and sim.stage_left == ("segments", 3.0)
    sim.advance()
    assert sim.stage == "ended"
    summary = sim.summary()
    assert summary["hmc"]["segments"] == 5
    assert summary["equilibration_events"] == 2_000
    assert "hmc" not in sim.observables()
