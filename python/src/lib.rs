//! `_dmdsim`, the compiled half of the Python package `dmdsim`: a thin layer over `dmd-sim`.
//!
//! `Simulation` holds the event loop of a scene (built by `dmd_sim::run::build_simulation`
//! exactly as `dmd run` starts it) behind an object-safe `Engine`, so one Python class
//! serves every model and queue. `run_json` runs a whole scene as `dmd run` does and returns
//! its summary as JSON. `ensemble_start`, `ensemble_job` and `ensemble_aggregate` are the
//! steps of an ensemble whose jobs run as tasks of a Dask cluster (`dmdsim/ensemble.py`), each
//! `dmd_sim::chains`'s own code. The engine runs with the GIL released; every 16384 events it takes the
//! GIL back briefly (at most every 0.1 s) to look for a signal, and a `KeyboardInterrupt` raises
//! the cancel flag of the loop, which stops between two events. The pure-Python half
//! (`dmdsim/__init__.py`) reads scene files, dicts and text, and turns JSON into dicts.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use dmd_sim::checkpoint::{self, Checkpoint, Left, SceneSource, Stage};
use dmd_sim::model::PairModel;
use dmd_sim::run::{
    Built, Halt, ObservableTable, Reporter, RunError as DmdRunError, RunOptions, StagedRun,
    Summary, UseRun,
};
use dmd_sim::scene::Scene;
use dmd_sim::schedule::Scheduler;
use dmd_sim::simulation::{Counters, Progress, SimError, Simulation as Loop, Stop};
use dmd_sim::smd_engine::Engine as EngineKind;
use glam::{DQuat, DVec3};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::{PyException, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

pyo3::create_exception!(
    dmdsim,
    DmdError,
    PyException,
    "Base class of every error of the dmd engine."
);
pyo3::create_exception!(
    dmdsim,
    SceneError,
    DmdError,
    "A scene (file, dict or override) that dmd refuses; the message is the `dmd` command's."
);
pyo3::create_exception!(
    dmdsim,
    RunError,
    DmdError,
    "A run that could not go on (the simulation, an output, a job of an ensemble)."
);
pyo3::create_exception!(
    dmdsim,
    CheckpointError,
    RunError,
    "A checkpoint that cannot be written, read or resumed."
);

/// How often the engine looks for a pending signal (it can only look every 16384 events).
const SIGNAL_CHECK: Duration = Duration::from_millis(100);

/// A Python exception of `dmd-sim`'s error, with its message (the `dmd` command's).
fn to_py(e: DmdRunError) -> PyErr {
    let message = e.to_string();
    match e {
        DmdRunError::Scene(_) => SceneError::new_err(message),
        DmdRunError::Checkpoint(_) => CheckpointError::new_err(message),
        _ => RunError::new_err(message),
    }
}

/// Looks for signals while the engine runs: [`Watch::look`] is called from the loop
/// (GIL released) and takes the GIL back to run Python's signal handlers; an exception they
/// raise (`KeyboardInterrupt`) is kept and the loop's cancel flag raised.
struct Watch {
    flag: Arc<AtomicBool>,
    last: Instant,
    raised: Option<PyErr>,
}

impl Watch {
    fn new() -> Self {
        Watch {
            flag: Arc::new(AtomicBool::new(false)),
            last: Instant::now(),
            raised: None,
        }
    }

    fn look(&mut self) {
        if self.raised.is_some() || self.last.elapsed() < SIGNAL_CHECK {
            return;
        }
        self.last = Instant::now();
        if let Err(e) = Python::attach(|py| py.check_signals()) {
            self.raised = Some(e);
            self.flag.store(true, Ordering::Relaxed);
        }
    }

    /// The exception for a run that ended with `result`: the signal's if it was cancelled.
    fn finish<T>(self, result: Result<T, DmdRunError>) -> PyResult<T> {
        match (result, self.raised) {
            (Err(DmdRunError::Sim(SimError::Cancelled)), Some(e)) => Err(e),
            (Err(e), _) => Err(to_py(e)),
            // A run that cannot be cancelled (the smd engine) ends first; the signal's
            // exception still arrives.
            (Ok(_), Some(e)) => Err(e),
            (Ok(x), None) => Ok(x),
        }
    }
}

impl Reporter for Watch {
    fn progress(&mut self, _p: Progress) {
        self.look();
    }
    fn cancel_flag(&self) -> Option<Arc<AtomicBool>> {
        Some(Arc::clone(&self.flag))
    }
}

/// What the Python class needs of a run, whatever its model and queue.
trait Engine: Send {
    fn advance(&mut self, budget: Option<Stop>, watch: &mut Watch) -> Result<Halt, DmdRunError>;
    fn n(&self) -> usize;
    fn time(&self) -> f64;
    fn counters(&self) -> Counters;
    fn lengths(&self) -> DVec3;
    fn positions(&self) -> Vec<DVec3>;
    fn unwrapped_positions(&self) -> Vec<DVec3>;
    fn velocities(&self) -> Vec<DVec3>;
    fn species(&self) -> Vec<u32>;
    fn attitudes(&self) -> Vec<Option<DQuat>>;
    fn spins(&self) -> Vec<DVec3>;
    fn energies(&self) -> (f64, f64, f64);
    fn built(&self) -> &Built;
    fn stage_name(&self) -> &'static str;
    fn stage(&self) -> Option<Stage>;
    fn summary(&self) -> Option<Summary>;
    fn tables(&mut self) -> Result<Vec<ObservableTable>, DmdRunError>;
    /// The ended run's summary, its files written (with an output folder).
    fn finish(&mut self) -> Result<Summary, DmdRunError>;
    /// Re-bases the time origin (where a state is exact) and returns the checkpoint of it.
    fn checkpoint(&mut self, source: SceneSource) -> Result<Checkpoint, DmdRunError>;
}

struct Held<M: PairModel, Q: Scheduler> {
    run: StagedRun<M, Q>,
}

impl<M: PairModel + Send, Q: Scheduler + Send> Held<M, Q> {
    fn sim(&self) -> &Loop<M, Q> {
        self.run.simulation()
    }
}

impl<M: PairModel + Send, Q: Scheduler + Send> Engine for Held<M, Q> {
    fn advance(&mut self, budget: Option<Stop>, watch: &mut Watch) -> Result<Halt, DmdRunError> {
        self.run.advance(budget, watch)
    }
    fn n(&self) -> usize {
        self.sim().bodies().len()
    }
    fn time(&self) -> f64 {
        self.sim().time()
    }
    fn counters(&self) -> Counters {
        self.sim().counters()
    }
    fn lengths(&self) -> DVec3 {
        self.sim().lengths()
    }
    fn positions(&self) -> Vec<DVec3> {
        // The loop wraps a body when it crosses into a cell across the box face, so a stored
        // position can lie a little outside the box; the array is wrapped into [0, L).
        let l = self.sim().lengths();
        let wrap = |x: f64, l: f64| {
            let y = x.rem_euclid(l);
            if y < l { y } else { 0.0 }
        };
        self.sim()
            .positions()
            .iter()
            .map(|r| DVec3::new(wrap(r.x, l.x), wrap(r.y, l.y), wrap(r.z, l.z)))
            .collect()
    }
    fn unwrapped_positions(&self) -> Vec<DVec3> {
        let sim = self.sim();
        let l = sim.lengths();
        sim.positions()
            .iter()
            .zip(sim.images())
            .map(|(r, im)| *r + DVec3::new(im[0] as f64, im[1] as f64, im[2] as f64) * l)
            .collect()
    }
    fn velocities(&self) -> Vec<DVec3> {
        self.sim().bodies().iter().map(|b| b.v).collect()
    }
    fn species(&self) -> Vec<u32> {
        self.sim().bodies().iter().map(|b| b.species).collect()
    }
    fn attitudes(&self) -> Vec<Option<DQuat>> {
        let sim = self.sim();
        let now = sim.now();
        (0..self.n() as u32)
            .map(|i| sim.model().attitude(i, now))
            .collect()
    }
    fn spins(&self) -> Vec<DVec3> {
        let sim = self.sim();
        let model = sim.model();
        sim.bodies()
            .iter()
            .enumerate()
            .map(|(i, b)| model.spin(i as u32, b.species))
            .collect()
    }
    fn energies(&self) -> (f64, f64, f64) {
        let sim = self.sim();
        (sim.kinetic_energy(), sim.potential_energy(), sim.dof())
    }
    fn built(&self) -> &Built {
        self.run.built()
    }
    fn stage_name(&self) -> &'static str {
        self.run.stage_name()
    }
    fn stage(&self) -> Option<Stage> {
        self.run.stage()
    }
    fn summary(&self) -> Option<Summary> {
        self.run.summary()
    }
    fn tables(&mut self) -> Result<Vec<ObservableTable>, DmdRunError> {
        Ok(self.run.tables()?)
    }
    fn finish(&mut self) -> Result<Summary, DmdRunError> {
        self.run.finish()
    }
    fn checkpoint(&mut self, source: SceneSource) -> Result<Checkpoint, DmdRunError> {
        self.run.checkpoint(source)
    }
}

/// Boxes the run `build_run` hands over.
struct Hold;

impl UseRun for Hold {
    type Output = Box<dyn Engine>;
    fn use_run<M: PairModel + Send + 'static, Q: Scheduler + Send + 'static>(
        self,
        run: StagedRun<M, Q>,
    ) -> Box<dyn Engine> {
        Box::new(Held { run })
    }
}

/// `n × 3` float64 array of vectors.
fn vectors<'py>(py: Python<'py>, v: &[DVec3]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = v.iter().flat_map(|x| x.to_array()).collect();
    Array2::from_shape_vec((v.len(), 3), flat)
        .expect("3 numbers per vector")
        .into_pyarray(py)
}

/// The run of one scene, advanced through its stages by events or simulated time (see the
/// stubs, `dmdsim/_dmdsim.pyi`, for the Python documentation).
#[pyclass(module = "dmdsim._dmdsim")]
struct Simulation {
    engine: std::sync::Mutex<Box<dyn Engine>>,
    source: SceneSource,
    /// The run's files were written (it ended).
    finished: AtomicBool,
}

impl Simulation {
    /// The run, unless another Python thread is advancing it (waiting for it here, with the
    /// GIL held, would deadlock: the running loop takes the GIL to look for signals).
    fn engine(&self) -> PyResult<std::sync::MutexGuard<'_, Box<dyn Engine>>> {
        match self.engine.try_lock() {
            Ok(g) => Ok(g),
            // A panic in the engine poisons the lock; reading the state is still safe.
            Err(std::sync::TryLockError::Poisoned(p)) => Ok(p.into_inner()),
            Err(std::sync::TryLockError::WouldBlock) => Err(PyRuntimeError::new_err(
                "the simulation is running in another thread",
            )),
        }
    }

    fn check_staged(scene: &Scene) -> PyResult<()> {
        let refuse = |what: &str| {
            Err(SceneError::new_err(format!(
                "a Simulation runs one scene of the event-driven engine; this scene has {what}: \
                 run it whole with {}",
                if what.starts_with("engine") {
                    "dmdsim.run"
                } else {
                    "dmdsim.run or dmdsim.run_ensemble"
                }
            )))
        };
        if scene.engine == EngineKind::Smd {
            return refuse("engine = \"smd\"");
        }
        if scene.chains.is_some() || scene.sweep.is_some() {
            return refuse("an ensemble ([chains] or [sweep])");
        }
        Ok(())
    }

    fn build(
        py: Python<'_>,
        scene: &Scene,
        source: SceneSource,
        out: Option<PathBuf>,
        force: bool,
        resume: Option<(PathBuf, Checkpoint)>,
    ) -> PyResult<Self> {
        Simulation::check_staged(scene)?;
        if let Some(dir) = &out {
            dmd_sim::outdir::prepare(dir, force).map_err(|e| RunError::new_err(e.to_string()))?;
        }
        let engine = py
            .detach(|| dmd_sim::run::build_run(scene, &source.base, out.as_deref(), resume, Hold))
            .map_err(to_py)?;
        Ok(Simulation {
            engine: std::sync::Mutex::new(engine),
            source,
            finished: AtomicBool::new(false),
        })
    }
}

/// A summary as a Python dict (its JSON, as `summary.json` holds it).
fn summary_dict<'py>(py: Python<'py>, s: &Summary) -> PyResult<Bound<'py, PyAny>> {
    let json = serde_json::to_string(s)
        .map_err(|e| RunError::new_err(format!("the summary does not serialise: {e}")))?;
    py.import("json")?.call_method1("loads", (json,))
}

#[pymethods]
impl Simulation {
    /// The run of a scene's TOML text with `--set` overrides (use `dmdsim.load`).
    #[new]
    #[pyo3(signature = (text, overrides, base, file, out=None, force=false))]
    fn new(
        py: Python<'_>,
        text: String,
        overrides: Vec<String>,
        base: PathBuf,
        file: PathBuf,
        out: Option<PathBuf>,
        force: bool,
    ) -> PyResult<Self> {
        let scene = Scene::from_str_with(&text, &overrides)
            .map_err(|e| SceneError::new_err(e.to_string()))?;
        let source = SceneSource {
            text,
            overrides,
            base,
            file,
        };
        Simulation::build(py, &scene, source, out, force, None)
    }

    /// The run saved by `checkpoint` in `path`; continues it bit for bit.
    #[staticmethod]
    #[pyo3(signature = (path, out=None, force=false))]
    fn resume(py: Python<'_>, path: PathBuf, out: Option<PathBuf>, force: bool) -> PyResult<Self> {
        let c = checkpoint::read(&path).map_err(|e| CheckpointError::new_err(e.to_string()))?;
        let scene = Scene::from_str_with(&c.source.text, &c.source.overrides).map_err(|e| {
            CheckpointError::new_err(format!(
                "checkpoint {}: its scene ({}) no longer reads: {e}",
                path.display(),
                c.source.file.display()
            ))
        })?;
        let source = c.source.clone();
        Simulation::build(py, &scene, source, out, force, Some((path, c)))
    }

    /// Runs the scene's stages for `events` more events or `time` more simulated time (at
    /// most one; neither: to the end of the run), GIL released; Ctrl-C raises
    /// `KeyboardInterrupt` and leaves the state whole.
    #[pyo3(signature = (events=None, time=None))]
    fn advance(&self, py: Python<'_>, events: Option<u64>, time: Option<f64>) -> PyResult<()> {
        let budget = match (events, time) {
            (Some(n), None) => Some(Stop::Events(n)),
            (None, Some(t)) if t.is_finite() && t >= 0.0 => Some(Stop::Time(t)),
            (None, Some(t)) => {
                return Err(PyValueError::new_err(format!(
                    "time must be finite and not negative, got {t}"
                )));
            }
            (None, None) => None,
            _ => {
                return Err(PyValueError::new_err(
                    "give at most one of events= and time=",
                ));
            }
        };
        let mut guard = self.engine()?;
        let engine: &mut Box<dyn Engine> = &mut guard;
        if engine.stage().is_none() {
            let done = engine
                .summary()
                .map_or((0, 0.0), |s| (s.events, s.sim_time));
            return Err(RunError::new_err(format!(
                "the run has ended ({} events, time {} of production); load the scene with a \
                 longer run.events, run.time or hmc.segments to run further",
                done.0, done.1
            )));
        }
        let mut watch = Watch::new();
        let result = py.detach(|| {
            let halt = engine.advance(budget, &mut watch)?;
            if halt == Halt::Ended && !self.finished.swap(true, Ordering::Relaxed) {
                engine.finish()?;
            }
            Ok(halt)
        });
        match watch.finish(result)? {
            Halt::OtherUnit => {
                let (key, unit, kw) = match engine.stage() {
                    Some(Stage::Equilibration(Left::Time(_))) => {
                        ("run.equilibration_time", "simulated time", "time")
                    }
                    Some(Stage::Equilibration(_)) => {
                        ("run.equilibration_events", "events", "events")
                    }
                    Some(Stage::Production(Left::Time(_))) => {
                        ("run.time", "simulated time", "time")
                    }
                    _ => ("run.events", "events", "events"),
                };
                Err(PyValueError::new_err(format!(
                    "the {} stage is measured in {unit} ({key}): advance it with {kw}= or to \
                     the end of the run with advance()",
                    engine.stage_name()
                )))
            }
            Halt::Budget | Halt::Ended => Ok(()),
        }
    }

    /// Runs the scene to the end of its run and returns the summary (`dmd run`'s).
    fn run<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        if self.engine()?.stage().is_some() {
            self.advance(py, None, None)?;
        }
        let summary = self.engine()?.summary();
        summary_dict(py, &summary.expect("an ended run has a production"))
    }

    /// The summary of production so far, or None before production.
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let summary = self.engine()?.summary();
        summary.map(|s| summary_dict(py, &s)).transpose()
    }

    /// The observables of production so far: `{name: {column: array}}`.
    fn observables<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let tables = self.engine()?.tables().map_err(to_py)?;
        let d = PyDict::new(py);
        for t in tables {
            let columns = PyDict::new(py);
            for (k, name) in t.columns.iter().enumerate() {
                let col: Vec<f64> = t.rows.iter().map(|r| r[k]).collect();
                columns.set_item(name, Array1::from_vec(col).into_pyarray(py))?;
            }
            d.set_item(t.name, columns)?;
        }
        Ok(d)
    }

    /// The current stage's name, or `"ended"`.
    #[getter]
    fn stage(&self) -> PyResult<&'static str> {
        Ok(self.engine()?.stage_name())
    }

    /// What is left of the current stage: `("events", n)`, `("time", t)`, `("segments", n)`,
    /// or None once the run has ended.
    #[getter]
    fn stage_left(&self) -> PyResult<Option<(&'static str, f64)>> {
        Ok(self.engine()?.stage().map(|s| match s {
            Stage::Equilibration(l) | Stage::Production(l) => match l {
                Left::Events(n) => ("events", n as f64),
                Left::Time(t) => ("time", t),
                Left::Segments(n) => ("segments", n as f64),
            },
        }))
    }

    /// Re-bases the time origin and writes the run's state to `path` (dmd's checkpoint format).
    fn checkpoint(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let mut guard = self.engine()?;
        let engine: &mut Box<dyn Engine> = &mut guard;
        let source = self.source.clone();
        py.detach(|| {
            let c = engine.checkpoint(source).map_err(to_py)?;
            checkpoint::write(&path, &c).map_err(|e| CheckpointError::new_err(e.to_string()))
        })
    }

    /// Number of bodies.
    #[getter]
    fn n(&self) -> PyResult<usize> {
        Ok(self.engine()?.n())
    }

    /// Simulated time since the start (time unit or ps).
    #[getter]
    fn time(&self) -> PyResult<f64> {
        Ok(self.engine()?.time())
    }

    /// Events executed since the start.
    #[getter]
    fn events(&self) -> PyResult<u64> {
        Ok(self.engine()?.counters().events)
    }

    /// `"reduced"` or `"molecular"`.
    #[getter]
    fn units(&self) -> PyResult<&'static str> {
        Ok(match self.engine()?.built().units.system {
            dmd_sim::scene::UnitSystem::Reduced => "reduced",
            dmd_sim::scene::UnitSystem::Molecular => "molecular",
        })
    }

    /// The interaction model, as the summary's `model`.
    #[getter]
    fn model(&self) -> PyResult<&'static str> {
        Ok(self.engine()?.built().model)
    }

    /// Names of the species, indexed by `species`.
    #[getter]
    fn species_names(&self) -> PyResult<Vec<String>> {
        Ok(self.engine()?.built().species.clone())
    }

    /// Box edge lengths, shape (3,).
    #[getter]
    fn box_lengths<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let l = self.engine()?.lengths().to_array().to_vec();
        Ok(Array1::from_vec(l).into_pyarray(py))
    }

    /// Centres of mass now, wrapped into [0, L), shape (N, 3).
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(vectors(py, &self.engine()?.positions()))
    }

    /// Centres of mass now, continuous across box faces, shape (N, 3).
    #[getter]
    fn unwrapped_positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(vectors(py, &self.engine()?.unwrapped_positions()))
    }

    /// Centre-of-mass velocities, shape (N, 3).
    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(vectors(py, &self.engine()?.velocities()))
    }

    /// Species index of each body, shape (N,), int64.
    #[getter]
    fn species<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let s: Vec<i64> = self
            .engine()?
            .species()
            .into_iter()
            .map(i64::from)
            .collect();
        Ok(Array1::from_vec(s).into_pyarray(py))
    }

    /// Attitudes now, unit quaternions (w, x, y, z) from body to lab frame, shape (N, 4);
    /// identity for bodies without one (spheres, semi-flexible molecules).
    #[getter]
    fn quaternions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let q = self.engine()?.attitudes();
        let flat: Vec<f64> = q
            .iter()
            .flat_map(|q| {
                let q = q.unwrap_or(DQuat::IDENTITY);
                [q.w, q.x, q.y, q.z]
            })
            .collect();
        Ok(Array2::from_shape_vec((q.len(), 4), flat)
            .expect("4 numbers per quaternion")
            .into_pyarray(py))
    }

    /// Lab angular velocities now, shape (N, 3); zero for bodies without an attitude.
    #[getter]
    fn angular_velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let engine = self.engine()?;
        let moments = &engine.built().moments;
        let species = engine.species();
        let omegas: Vec<DVec3> = engine
            .attitudes()
            .iter()
            .zip(engine.spins())
            .zip(species)
            .map(|((q, l), s)| match (q, moments.get(s as usize)) {
                (Some(q), Some(m)) => {
                    // ω = A I⁻¹ Aᵀ L in the principal body frame; a zero moment (a rod's
                    // axis) carries no angular velocity.
                    let lb = q.inverse() * l;
                    let inv = |l: f64, i: f64| if i > 0.0 { l / i } else { 0.0 };
                    *q * DVec3::new(inv(lb.x, m[0]), inv(lb.y, m[1]), inv(lb.z, m[2]))
                }
                _ => DVec3::ZERO,
            })
            .collect();
        Ok(vectors(py, &omegas))
    }

    /// Time, events, energies and temperature now, in the scene's units.
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let engine = self.engine()?;
        let u = engine.built().units;
        let (k, p, dof) = engine.energies();
        let c = engine.counters();
        let d = PyDict::new(py);
        d.set_item("time", engine.time())?;
        d.set_item("events", c.events)?;
        d.set_item("kinetic_energy", u.energy_out(k))?;
        d.set_item("potential_energy", u.energy_out(p))?;
        d.set_item("total_energy", u.energy_out(k + p))?;
        d.set_item("temperature", u.temperature_out(2.0 * k / dof))?;
        d.set_item("degrees_of_freedom", dof)?;
        let by_kind = PyDict::new(py);
        for (name, v) in [
            ("core", c.core),
            ("step_in", c.step_in),
            ("step_out", c.step_out),
            ("step_reflect", c.step_reflect),
            ("shell_crossing", c.shell),
            ("thermostat", c.thermostat),
            ("virtual", c.virtual_),
            ("rebases", c.rebases),
        ] {
            by_kind.set_item(name, v)?;
        }
        d.set_item("events_by_kind", by_kind)?;
        Ok(d)
    }

    fn __repr__(&self) -> PyResult<String> {
        let engine = self.engine()?;
        Ok(format!(
            "<dmdsim.Simulation: {} bodies, {}, t = {}, {} events>",
            engine.n(),
            engine.built().model,
            engine.time(),
            engine.counters().events
        ))
    }
}

/// Runs a whole scene as `dmd run` does (with `out`: writes its files there) and returns the
/// summary as JSON (an ensemble's aggregate for `[chains]`/`[sweep]`).
#[pyfunction]
#[pyo3(signature = (text, overrides, base, file, out=None, checkpoint_every=None, force=false))]
#[allow(clippy::too_many_arguments)]
fn run_json(
    py: Python<'_>,
    text: String,
    overrides: Vec<String>,
    base: PathBuf,
    file: PathBuf,
    out: Option<PathBuf>,
    checkpoint_every: Option<String>,
    force: bool,
) -> PyResult<String> {
    let scene =
        Scene::from_str_with(&text, &overrides).map_err(|e| SceneError::new_err(e.to_string()))?;
    let every = checkpoint_every
        .as_deref()
        .map(checkpoint::Every::parse)
        .transpose()
        .map_err(|e| SceneError::new_err(format!("checkpoint_every: {e}")))?;
    if every.is_some() && (out.is_none() || scene.engine == EngineKind::Smd) {
        return Err(SceneError::new_err(
            "checkpoint_every needs an output folder and the event-driven engine",
        ));
    }
    if let Some(dir) = &out {
        dmd_sim::outdir::prepare(dir, force).map_err(|e| RunError::new_err(e.to_string()))?;
    }
    let source = SceneSource {
        text,
        overrides,
        base: base.clone(),
        file: file.clone(),
    };
    let out = out.as_deref();
    let json = |v: Result<String, serde_json::Error>| {
        v.map_err(|e| RunError::new_err(format!("the summary does not serialise: {e}")))
    };
    if scene.engine == EngineKind::Smd {
        let name = file.file_stem().map(|s| s.to_string_lossy().into_owned());
        let mut watch = Watch::new();
        let result = py.detach(|| {
            dmd_sim::smd_engine::run_named(&scene, &base, out, &mut watch, name.as_deref())
        });
        return json(serde_json::to_string(&watch.finish(result)?));
    }
    if scene.chains.is_some() || scene.sweep.is_some() {
        let Some(out) = out else {
            return Err(SceneError::new_err(
                "an ensemble ([chains] or [sweep]) writes a folder per job: give out=",
            ));
        };
        let result = py.detach(|| {
            dmd_sim::chains::run_ensemble(&scene, &source, out, None, every, &|_, _| {})
        });
        return json(serde_json::to_string(&result.map_err(to_py)?));
    }
    let options = RunOptions {
        checkpoint_every: every,
        source: Some(source),
        ..RunOptions::default()
    };
    let mut watch = Watch::new();
    let result =
        py.detach(|| dmd_sim::run::run_scene_with(&scene, &base, out, &mut watch, &options));
    json(serde_json::to_string(&watch.finish(result)?))
}

/// Prepares `out` for the jobs of an ensemble scene as `dmd run` does before running them
/// (every point set up, the folder prepared, the scene recorded) and returns the jobs' folders
/// in job order; nothing runs.
#[pyfunction]
#[pyo3(signature = (text, overrides, base, file, out, checkpoint_every=None, force=false))]
#[allow(clippy::too_many_arguments)]
fn ensemble_start(
    py: Python<'_>,
    text: String,
    overrides: Vec<String>,
    base: PathBuf,
    file: PathBuf,
    out: PathBuf,
    checkpoint_every: Option<String>,
    force: bool,
) -> PyResult<Vec<String>> {
    let scene =
        Scene::from_str_with(&text, &overrides).map_err(|e| SceneError::new_err(e.to_string()))?;
    if scene.chains.is_none() && scene.sweep.is_none() {
        return Err(SceneError::new_err(
            "run_ensemble runs the jobs of [chains] or [sweep]; this scene has neither: run it \
             with dmdsim.run",
        ));
    }
    if scene.engine == EngineKind::Smd {
        return Err(SceneError::new_err(
            "run_ensemble runs scenes of the event-driven engine; this one has engine = \"smd\"",
        ));
    }
    let every = checkpoint_every
        .as_deref()
        .map(checkpoint::Every::parse)
        .transpose()
        .map_err(|e| SceneError::new_err(format!("checkpoint_every: {e}")))?;
    let source = SceneSource {
        text,
        overrides,
        base,
        file,
    };
    // Every point is set up before anything is written (as `dmd run` does).
    py.detach(|| dmd_sim::run::check_setup(&scene, &source.base, &source.text, &source.overrides))
        .map_err(to_py)?;
    dmd_sim::outdir::prepare(&out, force).map_err(|e| RunError::new_err(e.to_string()))?;
    let jobs = dmd_sim::chains::start_ensemble(&scene, &source, &out, every).map_err(to_py)?;
    Ok(jobs
        .iter()
        .map(|j| j.dir.to_string_lossy().into_owned())
        .collect())
}

/// The jobs' folders of the ensemble recorded in `out`, in job order.
#[pyfunction]
fn ensemble_jobs(out: PathBuf) -> PyResult<Vec<String>> {
    let r = dmd_sim::chains::read_ensemble(&out).map_err(to_py)?;
    Ok(r.jobs
        .iter()
        .map(|j| j.dir.to_string_lossy().into_owned())
        .collect())
}

/// Runs, resumes or reads back job `k` of the ensemble recorded in `out` (GIL released);
/// returns its summary as JSON and `"fresh"`, `"resumed"` or `"finished"`.
#[pyfunction]
fn ensemble_job(py: Python<'_>, out: PathBuf, k: usize) -> PyResult<(String, &'static str)> {
    let (summary, start) = py
        .detach(|| dmd_sim::chains::run_or_resume_job(&out, k))
        .map_err(to_py)?;
    let json = serde_json::to_string(&summary)
        .map_err(|e| RunError::new_err(format!("the summary does not serialise: {e}")))?;
    Ok((json, start.name()))
}

/// Aggregates the jobs' summaries of the ensemble in `out` into `ensemble.json` and
/// `ensemble.csv` (as `dmd run` does) and returns the aggregate as JSON.
#[pyfunction]
fn ensemble_aggregate(py: Python<'_>, out: PathBuf) -> PyResult<String> {
    let e = py
        .detach(|| dmd_sim::chains::write_aggregate(&out))
        .map_err(to_py)?;
    serde_json::to_string(&e)
        .map_err(|e| RunError::new_err(format!("the aggregate does not serialise: {e}")))
}

/// A Python value as TOML (dicts, lists, tuples, str, bool, int, float).
fn to_toml(v: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    let bad = || {
        SceneError::new_err(format!(
            "{key}: a {} has no TOML form (use dict, list, str, bool, int or float)",
            v.get_type()
                .name()
                .map_or_else(|_| "value".to_owned(), |n| n.to_string())
        ))
    };
    if let Ok(d) = v.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, x) in d.iter() {
            let k: String = k.extract().map_err(|_| bad())?;
            let path = if key.is_empty() {
                k.clone()
            } else {
                format!("{key}.{k}")
            };
            table.insert(k, to_toml(&x, &path)?);
        }
        return Ok(toml::Value::Table(table));
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract().map_err(|_| bad())?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = v.extract()?;
        let values = items
            .iter()
            .enumerate()
            .map(|(i, x)| to_toml(x, &format!("{key}[{i}]")))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(toml::Value::Array(values));
    }
    Err(bad())
}

/// The TOML text of a scene given as a dict.
#[pyfunction]
fn dict_to_toml(scene: &Bound<'_, PyDict>) -> PyResult<String> {
    match to_toml(scene.as_any(), "")? {
        toml::Value::Table(t) => {
            toml::to_string(&t).map_err(|e| SceneError::new_err(format!("scene dict: {e}")))
        }
        _ => unreachable!("a dict gives a table"),
    }
}

/// The base folder of a scene file (relative paths in the scene are read from it).
fn base_of(file: &Path) -> PathBuf {
    file.parent().map(Path::to_owned).unwrap_or_default()
}

/// Reads a scene file: its text and its base folder, with the `dmd` command's error.
#[pyfunction]
fn read_scene(file: PathBuf) -> PyResult<(String, PathBuf)> {
    let text = std::fs::read_to_string(&file).map_err(|source| {
        SceneError::new_err(
            dmd_sim::scene::SceneError::Io {
                path: file.clone(),
                source,
            }
            .to_string(),
        )
    })?;
    Ok((text, base_of(&file)))
}

/// The compiled module.
#[pymodule]
fn _dmdsim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("DmdError", py.get_type::<DmdError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("RunError", py.get_type::<RunError>())?;
    m.add("CheckpointError", py.get_type::<CheckpointError>())?;
    m.add_class::<Simulation>()?;
    m.add_function(wrap_pyfunction!(run_json, m)?)?;
    m.add_function(wrap_pyfunction!(dict_to_toml, m)?)?;
    m.add_function(wrap_pyfunction!(read_scene, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble_start, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble_jobs, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble_job, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble_aggregate, m)?)?;
    Ok(())
}
