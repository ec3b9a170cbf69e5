//! Running a scene end to end: set-up, equilibration, production, summary and outputs.
//!
//! [`run_scene`] picks the interaction model (hard spheres, stepped, or terraced rods) and the
//! queue once and hands over to a loop compiled for that pair; everything scene-specific
//! happens here, around the loop, never inside it. Scenes in molecular units are converted to
//! the internal units first and the summary back ([`units`](crate::config::units)).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use event_queue::{BoundedQueue, Calendar, HeapQueue, LazyQueue, Ticket, TournamentTree};
use glam::DVec3;
use serde::Serialize;

use crate::analysis::observable::{Correlations, Observers, Rdf, Series};
use crate::analysis::output::{
    GsdTrajectory, Layout, OutputError, Trajectory, element_of, write_atomically, write_csv,
};
use crate::analysis::site_rdf::MoleculeSites;
use crate::config::init::{
    Configuration, ase_momentum_unit, lattice, maxwell_boltzmann, read_motion, read_xyz,
};
use crate::config::plan::{Drawings, ModelStart, Plan, UseModel};
use crate::config::scene::{
    AcceptKind, EnsembleKind, MeasureKind, Positions, QueueKind, Scene, SceneError, ThermostatKind,
    ThermostatPhase, Velocities,
};
use crate::config::units::Units;
use crate::driver::checkpoint::{
    Checkpoint, CheckpointError, Every, Left, ObserverState, Problem, RunRecord, Saver,
    SceneSource, Stage,
};
use crate::driver::hmc::{Acceptance, Chain, Ensemble, HmcSettings, HmcSummary, Measure};
pub use crate::driver::reporting::{
    ObservableTable, PhaseEnd, Quiet, Reporter, RunError, RunPlan, thread_cpu_seconds,
};
use crate::driver::reporting::{PlotInfo, observable_tables, terrace_step, write_observables};
use crate::engine::model::PairModel;
use crate::engine::schedule::Scheduler;
use crate::engine::simulation::MAX_REBASE_EVENTS;

/// How far (relative to the energy scale) a resumed state's tracked energies may be from the
/// ones its velocities and pair levels give: the tolerance of the loop's own debug check.
const RESUME_ENERGY_TOLERANCE: f64 = 1e-9;
/// How far (relative) a resumed plain production run's energy may be from its recorded start.
const RESUME_DRIFT: f64 = 1e-2;

use crate::analysis::output::short;
use crate::engine::simulation::{Andersen, LoopSettings, Progress, SetupError, Simulation, Stop};
use crate::models::search::SearchStats;

/// What a run does besides the scene: checkpoints, and resuming from one.
#[derive(Debug, Default)]
pub struct RunOptions {
    /// Write `DIR/checkpoint.dmd` this often (needs `source` and an output folder).
    pub checkpoint_every: Option<Every>,
    /// The scene's text and overrides, stored in checkpoints.
    pub source: Option<SceneSource>,
    /// Continue the run saved in this checkpoint (its file, and its contents).
    pub resume: Option<(std::path::PathBuf, Checkpoint)>,
    /// Stop right after the first checkpoint is written, outputs unfinished, as a crash then
    /// would (tests of `dmd resume`).
    pub halt_after_checkpoint: bool,
}

/// Energies, momentum and counters of a run, as written to `summary.json`. Units are the
/// scene's (reduced, σ = m = kT = 1 by default; in molecular units energies in kJ/mol,
/// temperatures in K, pressures in bar, times in ps, lengths in Å); all averages are over
/// production.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// `dmd` (the standard-MD engine writes `smd`).
    pub engine: String,
    /// Events of production (pair events, cell crossings, thermostat collisions).
    pub events: u64,
    /// Production events by kind, plus bookkeeping counts (`samples`, `rebases`).
    pub events_by_kind: BTreeMap<String, u64>,
    /// Events of equilibration.
    pub equilibration_events: u64,
    /// Wall-clock seconds of production.
    pub wall_seconds: f64,
    /// CPU seconds of production (the thread's run time; Linux only, else equal to the wall
    /// time). On a shared machine this is the steadier measure of cost.
    pub cpu_seconds: f64,
    /// Production events per wall-clock second.
    pub events_per_second: f64,
    /// Production events per CPU second.
    pub events_per_cpu_second: f64,
    /// Pair events (collisions and step crossings) per wall-clock second.
    pub pair_events_per_second: f64,
    /// Simulated time of production.
    pub sim_time: f64,
    /// Number of bodies.
    pub n_bodies: u64,
    /// Number density N/V.
    pub density: f64,
    /// Box edge lengths.
    pub box_lengths: [f64; 3],
    /// Time-averaged kinetic temperature, `2⟨K⟩ / dof`.
    pub temperature: f64,
    /// Block-average error of the mean kinetic temperature, from the instantaneous one at
    /// every sample (Flyvbjerg–Petersen, [`block_average`](crate::analysis::block::block_average);
    /// `null` without `output.sample_interval` or with fewer than 16 samples).
    pub temperature_error: Option<f64>,
    /// Kinetic temperature `2K/dof` at the start of production: the bath temperature exactly
    /// when a thermostatted equilibration ended with `thermostat.rescale_at_end` (default).
    pub temperature_start: f64,
    /// Degrees of freedom of the temperature (3N − 3 in NVE, 3N with a thermostat).
    pub degrees_of_freedom: f64,
    /// Pressure from the collision virial: `(N kT + Σ r_ij·Δp_i / 3t) / V`.
    pub pressure: f64,
    /// Ideal part of the pressure, `N kT / V`.
    pub pressure_ideal: f64,
    /// Excess (virial) part of the pressure.
    pub pressure_excess: f64,
    /// Block-average error of `pressure`, from its mean over each sampling interval.
    pub pressure_error: Option<f64>,
    /// Compressibility factor `Z = P V / (N kT)`.
    pub compressibility: f64,
    /// Mean time between pair events of a body, `N t / (2 × pair events)`.
    pub mean_free_time: f64,
    /// Pair events per body per unit time, `2 × pair events / (N t)`.
    pub collision_rate: f64,
    /// Kinetic energy at the end.
    pub energy_kinetic: f64,
    /// Potential energy at the end (from the stored pair levels).
    pub energy_potential: f64,
    /// Time-averaged potential energy per body.
    pub potential_energy_per_body: f64,
    /// Block-average error of `potential_energy_per_body`, from the samples.
    pub potential_energy_per_body_error: Option<f64>,
    /// Mean over the samples of the smooth potential energy per body (terraced rods and
    /// Gay–Berne: the continuous potential, cut and switched as by the smd engine, evaluated
    /// at the sampled configurations; `output.smooth_estimators`).
    pub potential_energy_per_body_smooth: Option<f64>,
    /// Its block-average error.
    pub potential_energy_per_body_smooth_error: Option<f64>,
    /// Mean over the samples of the smooth potential's pressure `(N kT_t + W/3)/V`, `W` its
    /// molecular virial and `kT_t` the instantaneous translational temperature (the smd
    /// engine's formula).
    pub pressure_smooth: Option<f64>,
    /// Its block-average error.
    pub pressure_smooth_error: Option<f64>,
    /// Total energy at the start of production.
    pub energy_total_start: f64,
    /// Total energy at the end.
    pub energy_total_end: f64,
    /// `|E_end − E_start|` relative to `max(|E_start|, K_start)`.
    pub relative_energy_drift: f64,
    /// `|P_end − P_start|` relative to `Σ m|v|` at the start.
    pub momentum_drift: f64,
    /// Anomalies counted (negative event times, overlaps, receding pairs); 0 in a healthy run.
    pub anomalies: u64,
    /// Anomalies by kind.
    pub anomalies_by_kind: BTreeMap<String, u64>,
    /// Interaction model used (`hard-spheres`, `stepped`, `terraced-rods`,
    /// `terraced-gay-berne`, `rigid-sites`).
    pub model: String,
    /// The unit system of the numbers (`reduced` or `molecular`).
    pub units: String,
    /// Pair events (terrace crossings and reflections) per ps of simulated time, in molecular
    /// units only (003 §V.B reports 4.7·10⁴ for its rods at ΔV = kT/2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub events_per_ps: Option<f64>,
    /// The same per unit of simulated time, in reduced units only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub events_per_time_unit: Option<f64>,
    /// Pair events per CPU second.
    pub pair_events_per_cpu_second: f64,
    /// Virtual events (root searches resumed at the end of their window, or started when a
    /// pair comes within reach).
    pub virtual_events: u64,
    /// Terrace (or step) crossings, up and down.
    pub terrace_crossings: u64,
    /// Reflections, at finite steps and at the hard core.
    pub reflections: u64,
    /// Missed events detected during the run (rods): searches that found their pair off its
    /// stored terrace, and events whose `U` was not at the predicted level beyond round-off.
    pub detected_misses: u64,
    /// Misses found by re-searching every interval on a fine grid (`search.verify_step`).
    pub verified_misses: Option<u64>,
    /// Counters of the root searches (rods).
    pub search: Option<SearchStats>,
    /// Translational temperature `2⟨K_trans⟩/(3N − 3)` (rods; equal to `temperature` for
    /// spheres).
    pub translational_temperature: f64,
    /// Block-average error of `translational_temperature`, from the instantaneous one at every
    /// sample (as `temperature_error`).
    pub translational_temperature_error: Option<f64>,
    /// Rotational temperature `⟨K_rot⟩/N` of rods (two degrees of freedom each).
    pub rotational_temperature: Option<f64>,
    /// Block-average error of `rotational_temperature`, from the instantaneous one at every
    /// sample.
    pub rotational_temperature_error: Option<f64>,
    /// Queue used.
    pub queue: String,
    /// Entries pushed into the scheduler (each body's earliest event, re-set at every change).
    pub queue_pushed: u64,
    /// Superseded scheduler entries dropped when popped (queues).
    pub queue_stale_dropped: u64,
    /// Superseded scheduler entries removed by sweeps (queues).
    pub queue_stale_swept: u64,
    /// Bodies rescheduled from their own event list because the partner of their earliest
    /// event had changed (no rescan needed).
    pub requeued: u64,
    /// Self-diffusion coefficient from the MSD slope (when `output.msd` is on).
    pub diffusion_msd: Option<f64>,
    /// Its error: each time origin's own `D` (the same fit on that origin's MSD alone),
    /// block-averaged over the origins in their order (`null` with fewer than 16 origins that
    /// reached the last lag).
    pub diffusion_msd_error: Option<f64>,
    /// Self-diffusion coefficient from the Green–Kubo VACF integral (when `output.vacf` is on).
    pub diffusion_vacf: Option<f64>,
    /// Its error, as `diffusion_msd_error`.
    pub diffusion_vacf_error: Option<f64>,
    /// The `_error` keys whose blocking found no plateau (`block::plateau`): the run is
    /// shorter than a few correlation times of those quantities, and their errors are lower
    /// bounds; run longer.
    pub errors_without_plateau: Vec<String>,
    /// The seed.
    pub seed: u64,
    /// Files written besides `summary.json`.
    pub files: Vec<String>,
    /// Hybrid Monte Carlo statistics (only with `[hmc]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hmc: Option<HmcSummary>,
    /// Largest relative bond-length error of the semi-flexible molecules at the end (at their
    /// last event and interpolated to the end time; only with `bonds`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bond_error: Option<f64>,
    /// What the RATTLE integration did (only with `bonds`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rattle: Option<crate::models::flexible::FlexStats>,
    /// Every count the body model keeps, over production, by name (`search.*`,
    /// `rattle.*`, `spherocylinders.*`, …): the model's whole report, whichever model it is.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub model_counts: BTreeMap<String, u64>,
    /// Every real-valued figure the body model keeps, at the end, by name.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub model_figures: BTreeMap<String, f64>,
}

/// Runs a scene. `base` is the folder relative paths of the scene are read from; with
/// `out = Some(dir)` the summary and every requested output are written there.
///
/// # Errors
/// [`RunError`].
pub fn run_scene(
    scene: &Scene,
    base: &Path,
    out: Option<&Path>,
    reporter: &mut dyn Reporter,
) -> Result<Summary, RunError> {
    run_scene_with(scene, base, out, reporter, &RunOptions::default())
}

/// [`run_scene`] with checkpoints, or continuing from one (`options.resume`: the scene must be
/// the checkpoint's own).
///
/// # Errors
/// [`RunError`].
pub fn run_scene_with(
    scene: &Scene,
    base: &Path,
    out: Option<&Path>,
    reporter: &mut dyn Reporter,
    options: &RunOptions,
) -> Result<Summary, RunError> {
    let fault = scene.hmc.as_ref().is_some_and(|h| h.fault_fraction > 0.0);
    let mut summary = set_up(scene, base, out, options, false, Running { reporter })?;
    if fault {
        summary.model = "stepped (fault injection)".to_owned();
    }
    Ok(summary)
}

/// Everything `dmd run` checks of a scene before its first event, for `dmd check`: the scene's
/// set-up (lattice or start file, box against the cut-off, skin, overlaps, the body model and
/// its tables, the observables' sizes) is built and dropped, nothing runs and nothing is
/// written. A scene of `[chains]` or `[sweep]` is set up point by point; a scene for the smd
/// engine is left to its engine.
///
/// # Errors
/// The [`RunError`] `dmd run` would stop with before its first event.
pub fn check_setup(
    scene: &Scene,
    base: &Path,
    text: &str,
    overrides: &[String],
) -> Result<(), RunError> {
    if scene.engine == crate::driver::smd_engine::Engine::Smd {
        return crate::driver::smd_engine::check_setup(scene, base);
    }
    let points = scene.sweep.as_ref().map_or(1, |s| s.values.len());
    for k in 0..points {
        let point = if scene.sweep.is_some() {
            scene.sweep_point(text, overrides, k)?
        } else {
            scene.clone()
        };
        let quiet = Running {
            reporter: &mut Quiet,
        };
        match set_up(&point, base, None, &RunOptions::default(), true, quiet) {
            Err(RunError::SetUpOnly) | Ok(_) => {}
            Err(RunError::Scene(e)) if scene.sweep.is_some() => {
                // Named as a point's error is when the point does not read.
                let sw = scene.sweep.as_ref().expect("a sweep");
                return Err(SceneError::invalid(
                    format!("sweep.values[{k}]"),
                    format!("with {} = {}: {e}", sw.key, sw.values[k]),
                )
                .into());
            }
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// What a scene's run is built with besides its state ([`build_run`]).
#[derive(Clone, Debug)]
pub struct Built {
    /// The scene's unit system (the simulation computes in internal units: lengths, masses
    /// and times pass unchanged, energies and temperatures are converted).
    pub units: Units,
    /// The interaction model (as the summary's `model`).
    pub model: &'static str,
    /// The names of the species, by index.
    pub species: Vec<String>,
    /// The principal moments of inertia of each species' body frame (rods `[I, I, 0]` with the
    /// axis along z; empty for spheres and semi-flexible molecules).
    pub moments: Vec<[f64; 3]>,
}

/// Something done with the run of a scene, whatever its model and scheduler ([`build_run`]).
pub trait UseRun {
    /// What it gives.
    type Output;
    /// Takes the run.
    fn use_run<M: PairModel + Send + 'static, Q: Scheduler + Send + 'static>(
        self,
        run: StagedRun<M, Q>,
    ) -> Self::Output;
}

/// Sets up the run of `scene` as [`run_scene`] does (the same configuration, velocities,
/// model, queue, loop settings and thermostat), or continues the one saved in a checkpoint
/// (`resume`: its file and contents; the scene must be the checkpoint's), and hands it to
/// `user` before its first event. For code that advances a run in pieces (the Python
/// package). With `out`, the run's files are written there by [`StagedRun::finish`] (the
/// trajectories as it goes).
///
/// # Errors
/// [`RunError`] as [`run_scene`] for a scene or checkpoint it refuses.
pub fn build_run<U: UseRun>(
    scene: &Scene,
    base: &Path,
    out: Option<&Path>,
    resume: Option<(std::path::PathBuf, Checkpoint)>,
    user: U,
) -> Result<U::Output, RunError> {
    let options = RunOptions {
        resume,
        ..RunOptions::default()
    };
    set_up(scene, base, out, &options, false, Building(user))
}

/// What [`set_up`] does with the model and queue it picked.
trait Go {
    type Out;
    fn go<M: PairModel + Send + 'static, Q: Scheduler + Send + 'static>(
        self,
        ctx: &Context<'_>,
        model: M,
    ) -> Result<Self::Out, RunError>;
}

/// Runs the scene ([`run_scene_with`]).
struct Running<'r> {
    reporter: &'r mut dyn Reporter,
}

impl Go for Running<'_> {
    type Out = Summary;
    fn go<M: PairModel + Send + 'static, Q: Scheduler + Send + 'static>(
        self,
        ctx: &Context<'_>,
        model: M,
    ) -> Result<Summary, RunError> {
        ctx.go::<M, Q>(model, self.reporter)
    }
}

/// Hands the run over ([`build_run`]).
struct Building<U>(U);

impl<U: UseRun> Go for Building<U> {
    type Out = U::Output;
    fn go<M: PairModel + Send + 'static, Q: Scheduler + Send + 'static>(
        self,
        ctx: &Context<'_>,
        model: M,
    ) -> Result<U::Output, RunError> {
        let run = ctx.start::<M, Q>(model, &mut Quiet)?;
        Ok(self.0.use_run(run))
    }
}

fn go_any_queue<G: Go, M: PairModel + Send + 'static>(
    ctx: &Context<'_>,
    g: G,
    model: M,
) -> Result<G::Out, RunError> {
    match ctx.scene.run.queue {
        QueueKind::Bounded => g.go::<_, LazyQueue<BoundedQueue<Ticket>>>(ctx, model),
        QueueKind::Heap => g.go::<_, LazyQueue<HeapQueue<Ticket>>>(ctx, model),
        QueueKind::Tournament => g.go::<_, TournamentTree>(ctx, model),
        QueueKind::Calendar => g.go::<_, Calendar>(ctx, model),
    }
}

/// Everything of a run before its phases: the configuration, velocities, model and queue,
/// handed to `g`; with `set_up_only`, the run stops with [`RunError::SetUpOnly`] once its
/// outputs are set up too ([`check_setup`]).
fn set_up<G: Go>(
    scene: &Scene,
    base: &Path,
    out: Option<&Path>,
    options: &RunOptions,
    set_up_only: bool,
    g: G,
) -> Result<G::Out, RunError> {
    if scene.engine == crate::driver::smd_engine::Engine::Smd {
        // Never run an smd scene event-driven behind the caller's back.
        return Err(SceneError::invalid(
            "engine",
            "this scene asks for the smd engine: run it with smd_engine::run (as `dmd run` does)",
        )
        .into());
    }
    let units = Units::of(scene.units);
    let scene = &scene.internal();
    let plan = Plan::of(scene)?;
    // A lattice denser than the smallest hard core allows can hold no species; pairs of larger
    // cores that end up too close are reported by the set-up.
    let smallest_core = plan.smallest_core();
    if let Some((path, c)) = &options.resume {
        check_checkpoint_scene(scene, path, c)?;
    }
    let layout = layout_of(scene, &plan, &units);
    let sites = plan.sites(scene);
    let start_file = base.join(scene.init.file.as_deref().unwrap_or(Path::new("")));
    // Semi-flexible molecules start from a file of their atoms (or of their centres).
    let molecules = match (&options.resume, scene.init.positions) {
        (None, Positions::File) => plan.read_molecules(scene, &start_file)?,
        _ => None,
    };
    let config = match (&options.resume, scene.init.positions) {
        // A resumed run takes its configuration from the checkpoint.
        (Some((_, c)), _) => Configuration {
            lengths: c.sim.lengths,
            positions: c.sim.bodies.iter().map(|b| b.r).collect(),
            species: c.sim.bodies.iter().map(|b| b.species).collect(),
            lattice_spacing: None,
        },
        (None, Positions::Fcc | Positions::Sc) => lattice(scene, smallest_core)?,
        (None, Positions::File) => match &molecules {
            Some(m) => m.config.clone(),
            None => read_xyz(scene, &start_file)?,
        },
    };
    let masses: Vec<f64> = config
        .species
        .iter()
        .map(|&s| scene.species[s as usize].mass)
        .collect();
    // A start file's own velocities (and angular velocities of rods, tops and site
    // molecules), or Maxwell–Boltzmann ones; a resumed run takes its state from the checkpoint.
    let rotating = plan.rotates();
    let moments: Vec<[f64; 3]> = if rotating {
        config
            .species
            .iter()
            .map(|&s| layout.moments[s as usize])
            .collect()
    } else {
        Vec::new()
    };
    let motion = match (&options.resume, scene.init.velocities) {
        (None, Velocities::File) => match &molecules {
            Some(m) => m.motion.clone(),
            None => Some(read_motion(
                scene,
                &start_file,
                &masses,
                rotating.then_some(moments.as_slice()),
            )?),
        },
        _ => None,
    };
    let velocities = match &motion {
        Some(m) => m.velocities.clone(),
        None => maxwell_boltzmann(&masses, scene.init.temperature, scene.seed),
    };
    let images = motion
        .as_ref()
        .and_then(|m| m.images.as_deref())
        .map(|im| crate::config::init::wrapped_images(im, &config.positions, config.lengths));
    let omegas = motion.and_then(|m| m.omegas);
    let n = config.positions.len();
    let hard = plan.is_hard_spheres();
    let skin = match &options.resume {
        Some((_, c)) => c.sim.settings.3,
        None => choose_skin(scene, plan.reach(), hard, &config)?,
    };
    let mut settings = LoopSettings {
        rebase_events: scene.run.rebase_events.unwrap_or_else(|| {
            (100 * n as u64).clamp(plan.fewest_rebase_events(), MAX_REBASE_EVENTS)
        }),
        seed: scene.seed.wrapping_add(0x7e57_0000_0000_0001),
        debug_check_events: (n as u64).max(1000),
        skin,
        start_time: 0.0,
    };
    if let Some((path, c)) = &options.resume {
        // The loop's settings are the scene's: an edited scene or state would not continue
        // the run it claims to.
        let fresh = choose_skin(scene, plan.reach(), hard, &config).ok();
        let (rebase, seed, _, _, _) = c.sim.settings;
        let problem = if fresh != Some(skin) {
            Some(format!(
                "its neighbour-list skin {} is not the one the scene gives ({})",
                short(skin),
                fresh.map_or_else(|| "none".to_owned(), short)
            ))
        } else if rebase != settings.rebase_events || seed != settings.seed {
            Some("its re-basing interval or seed is not the scene's".to_owned())
        } else {
            None
        };
        if let Some(m) = problem {
            return Err(CheckpointError {
                path: path.clone(),
                problem: Problem::Inconsistent(
                    crate::engine::simulation::StateError(m).to_string(),
                ),
            }
            .into());
        }
    }
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).map_err(|e| OutputError {
            path: dir.to_owned(),
            message: e.to_string(),
        })?;
    }
    type Heap = LazyQueue<HeapQueue<Ticket>>;
    // HMC fault injection (a validation tool) runs on the general stepped model; missed
    // events break the loop's invariants on purpose, so the debug checks are off.
    let fault = scene.hmc.as_ref().map_or(0.0, |h| h.fault_fraction);
    if fault > 0.0 {
        settings.debug_check_events = 0;
    }
    let ctx = Context {
        scene,
        config: &config,
        velocities: &velocities,
        images,
        settings,
        out,
        units,
        model_name: plan.name(),
        options,
        smooth: std::cell::Cell::new(None),
        layout,
        sites,
        set_up_only,
    };
    if fault > 0.0 {
        // Checked with the scene: fault injection is for sphere scenes.
        let (model, smooth) = plan.fault_model(scene, &config)?;
        ctx.smooth.set(smooth);
        return g.go::<_, Heap>(&ctx, model);
    }
    let start = ModelStart {
        scene,
        base,
        config: &config,
        resumed: options.resume.is_some(),
        start_file: &start_file,
        omegas,
        molecules,
    };
    plan.build(start, Start { ctx: &ctx, g })?
}

/// Runs `g` on the model a plan built, on the scene's queue.
struct Start<'a, G> {
    ctx: &'a Context<'a>,
    g: G,
}

impl<G: Go> UseModel for Start<'_, G> {
    type Out = Result<G::Out, RunError>;

    fn use_model<M: PairModel + Send + 'static>(
        self,
        model: M,
        smooth: Option<Box<dyn crate::analysis::smooth::Evaluate>>,
    ) -> Self::Out {
        self.ctx.smooth.set(smooth);
        go_any_queue(self.ctx, self.g, model)
    }
}

/// How trajectory frames draw each species of a scene ([`Plan::drawings`]), with each species'
/// element, its moments of inertia and the unit of the momenta (`units`: the scene's system).
fn layout_of(scene: &Scene, plan: &Plan, units: &Units) -> Layout {
    let species: Vec<String> = scene.species.iter().map(|s| s.name.clone()).collect();
    let Drawings {
        species: drawings,
        kinds,
        moments,
    } = plan.drawings(scene);
    let mut layout = Layout::new(species, drawings);
    layout.elements = scene
        .species
        .iter()
        .map(|s| element_of(&s.name, s.element.as_deref()))
        .collect();
    layout.kind_elements = kinds
        .iter()
        .map(|(name, _): &(String, f64)| element_of(name, None))
        .collect();
    layout.kinds = kinds;
    layout.moments = moments;
    layout.momentum_unit = ase_momentum_unit(units.system);
    layout
}

struct Context<'a> {
    scene: &'a Scene,
    config: &'a Configuration,
    velocities: &'a [DVec3],
    /// A start file's image counters (`map_shift`), which the run continues.
    images: Option<Vec<[i32; 3]>>,
    settings: LoopSettings,
    out: Option<&'a Path>,
    units: Units,
    model_name: &'static str,
    options: &'a RunOptions,
    /// The smooth estimator of a terraced scene, taken by the run.
    smooth: std::cell::Cell<Option<Box<dyn crate::analysis::smooth::Evaluate>>>,
    /// How trajectory frames draw each species.
    layout: Layout,
    /// The named sites of each species, for the site–site g(r) ([`Plan::sites`]).
    sites: Option<Vec<MoleculeSites>>,
    /// Stop with [`RunError::SetUpOnly`] once the simulation and its outputs' sizes are set up.
    set_up_only: bool,
}

impl Context<'_> {
    /// What the run is about to do, for the reporter.
    fn plan(&self, andersen: Option<Andersen>, eq: Stop, hmc_eq: u64, production: Stop) -> RunPlan {
        let scene = self.scene;
        let u = &self.units;
        let l = self.config.lengths;
        let n = self.config.positions.len() as u64;
        let mut phases = Vec::new();
        if !matches!(eq, Stop::Events(0) | Stop::Time(0.0)) {
            phases.push(("equilibration", eq));
        }
        if hmc_eq > 0 {
            phases.push(("hmc equilibration", Stop::Events(hmc_eq)));
        }
        phases.push(if scene.hmc.is_some() {
            ("hmc production", production)
        } else {
            ("production", production)
        });
        RunPlan {
            engine: "dmd",
            model: self.model_name.to_owned(),
            species: scene
                .species
                .iter()
                .map(|s| (s.name.clone(), s.count))
                .collect(),
            n_bodies: n,
            density: n as f64 / (l.x * l.y * l.z),
            box_lengths: l.to_array(),
            temperature: u.temperature_out(scene.init.temperature),
            thermostat: andersen.map(|a| {
                (
                    u.temperature_out(a.temperature),
                    match scene.thermostat.during {
                        ThermostatPhase::Always => "always",
                        ThermostatPhase::Equilibration => "equilibration",
                    },
                )
            }),
            units: scene.units,
            phases,
            dt: None,
            resumed_in: self.options.resume.as_ref().map(|(_, c)| match c.stage {
                Stage::Equilibration(Left::Segments(_)) => "hmc equilibration",
                Stage::Equilibration(_) => "equilibration",
                Stage::Production(_) if scene.hmc.is_some() => "hmc production",
                Stage::Production(_) => "production",
            }),
        }
    }

    /// The checks of a state restored from a checkpoint that need the built simulation.
    fn check_resumed_state<M: PairModel, Q: Scheduler>(
        &self,
        sim: &Simulation<M, Q>,
        c: &Checkpoint,
        faults: bool,
    ) -> Result<(), String> {
        if !sim.at_origin() {
            return Err("it was not saved at a re-basing (its clocks are not all 0)".into());
        }
        if !faults {
            sim.check_within(RESUME_ENERGY_TOLERANCE)?;
        }
        // A plain production run without a thermostat conserves energy: the state's energy
        // is its start's within any drift a run can have.
        if let (Stage::Production(_), None, None, Some((_, e0, _, _))) =
            (c.stage, &self.scene.hmc, c.sim.thermostat, c.record.start)
        {
            let (k, u) = (sim.tracked_kinetic(), sim.tracked_potential());
            let scale = k.abs().max(u.abs()).max(e0.abs()).max(f64::MIN_POSITIVE);
            let drift = (k + u - e0).abs();
            if drift.is_nan() || drift > RESUME_DRIFT * scale {
                return Err(format!(
                    "its energy {} differs from the {} it recorded at the start of production \
                     by more than any run drifts",
                    short(k + u),
                    short(e0)
                ));
            }
        }
        Ok(())
    }

    /// The loop in its initial state, or in the checkpoint's.
    fn simulation<M: PairModel, Q: Scheduler>(
        &self,
        model: M,
    ) -> Result<Simulation<M, Q>, RunError> {
        let mut sim = match &self.options.resume {
            Some((path, c)) => {
                let sim = Simulation::from_state(model, &c.sim).map_err(|e| CheckpointError {
                    path: path.clone(),
                    problem: Problem::Inconsistent(e.to_string()),
                })?;
                // The restored state must be a state of this scene's physics: lists, cells,
                // levels against distances, no overlap, tracked energies (fault injection, a
                // validation tool, leaves missed events in its states on purpose).
                let fault = self
                    .scene
                    .hmc
                    .as_ref()
                    .is_some_and(|h| h.fault_fraction > 0.0);
                self.check_resumed_state(&sim, c, fault)
                    .map_err(|m| CheckpointError {
                        path: path.clone(),
                        problem: Problem::Inconsistent(
                            crate::engine::simulation::StateError(m).to_string(),
                        ),
                    })?;
                sim
            }
            None => Simulation::new(
                self.config.lengths,
                &self.config.positions,
                self.velocities,
                &self.config.species,
                model,
                self.settings,
            )
            .map_err(|e| setup_error(self.scene, self.config, &self.units, e))?,
        };
        if let (None, Some(images)) = (&self.options.resume, &self.images) {
            sim.set_images(images.clone());
        }
        Ok(sim)
    }

    fn go<M: PairModel, Q: Scheduler>(
        &self,
        model: M,
        reporter: &mut dyn Reporter,
    ) -> Result<Summary, RunError> {
        let mut run = self.start::<M, Q>(model, reporter)?;
        run.advance(None, reporter)?;
        run.finish()
    }

    /// The run set up to its first event (or to the checkpoint's stage): the loop, the
    /// scene's thermostat for equilibration, and production's observers when the run starts
    /// in production.
    fn start<M: PairModel, Q: Scheduler>(
        &self,
        model: M,
        reporter: &mut dyn Reporter,
    ) -> Result<StagedRun<M, Q>, RunError> {
        let scene = self.scene;
        // A resumed run starts from its checkpoint's state and stage.
        let resume = self.options.resume.as_ref();
        let mut sim: Simulation<M, Q> = self.simulation(model)?;
        let fault = scene.hmc.as_ref().map_or(0.0, |h| h.fault_fraction);
        if fault > 0.0 {
            sim.set_fault_fraction(fault, scene.seed);
        }
        let every = resume.map_or(self.options.checkpoint_every, |(_, c)| {
            self.options.checkpoint_every.or(c.every)
        });
        let source = resume
            .map(|(_, c)| c.source.clone())
            .or_else(|| self.options.source.clone());
        let mut driver = Driver {
            saver: Saver::new(every, self.out, source),
            record: resume.map(|(_, c)| c.record.clone()).unwrap_or_default(),
            chain: resume.and_then(|(_, c)| c.chain.clone()).or_else(|| {
                scene
                    .hmc
                    .as_ref()
                    .map(|h| Chain::new(hmc_settings(scene), h.series))
            }),
            started: None,
            events: 0,
            halt: self.options.halt_after_checkpoint,
        };
        // With signal handlers installed every re-basing is a chance to stop (saved exactly).
        let interruptible = crate::driver::interrupt::installed() && driver.saver.can_save();
        sim.set_pause_at_rebase((driver.saver.active() || interruptible) && scene.hmc.is_none());
        if interruptible {
            use crate::driver::interrupt;
            sim.set_stop_request(interrupt::flag(), interrupt::GRACE);
        }

        // Equilibration.
        let andersen = (scene.thermostat.kind == ThermostatKind::Andersen).then(|| Andersen {
            rate: scene.thermostat.rate.expect("checked"),
            temperature: scene
                .thermostat
                .temperature
                .unwrap_or(scene.init.temperature),
        });
        let eq_stop = match scene.run.equilibration_time {
            Some(t) => Stop::Time(t),
            None => Stop::Events(scene.run.equilibration_events),
        };
        let equilibrate = !matches!(eq_stop, Stop::Events(0) | Stop::Time(0.0));
        let hmc_eq = scene.hmc.as_ref().map_or(0, |h| h.equilibration_segments);
        let stage = match resume {
            Some((_, c)) => c.stage,
            None if equilibrate => Stage::Equilibration(left_of(eq_stop)),
            None if hmc_eq > 0 => Stage::Equilibration(Left::Segments(hmc_eq)),
            None => Stage::Production(Left::Events(0)),
        };
        let stop = match (scene.run.events, scene.run.time, &scene.hmc) {
            (_, _, Some(h)) => Stop::Events(h.segments),
            (Some(e), _, _) => Stop::Events(e),
            (None, Some(t), _) => Stop::Time(t),
            (None, None, None) => unreachable!("checked"),
        };
        // Refused before equilibration, not after it.
        if scene.output.rdf.is_some() {
            rdf_r_max(scene, self.config.lengths)?;
        }
        if self.set_up_only {
            return Err(RunError::SetUpOnly);
        }
        reporter.start(&self.plan(andersen, eq_stop, hmc_eq, stop));
        if resume.is_none() && equilibrate {
            driver.record.had_thermostat = andersen.is_some();
            if andersen.is_some() {
                sim.set_thermostat(andersen);
            }
        }
        let resumed_production = match resume {
            Some((path, c)) if matches!(c.stage, Stage::Production(_)) => {
                Some((path.clone(), c.observers.clone()))
            }
            _ => None,
        };
        let mut run = StagedRun {
            fresh_production: resumed_production.is_none(),
            sim,
            scene: scene.clone(),
            built: Built {
                units: self.units,
                model: self.model_name,
                species: scene.species.iter().map(|s| s.name.clone()).collect(),
                moments: self.layout.moments.clone(),
            },
            layout: self.layout.clone(),
            sites: self.sites.clone(),
            lengths: self.config.lengths,
            body_species: self.config.species.clone(),
            out: self.out.map(Path::to_owned),
            scene_name: scene_name(self.options),
            smooth: self.smooth.take(),
            driver,
            andersen,
            eq_stop,
            hmc_eq,
            stop,
            stage,
            open: false,
            switched: false,
            production: false,
            ended: false,
            observers: Observers::default(),
            files: Vec::new(),
            resumed_production,
        };
        run.settle(reporter)?;
        Ok(run)
    }
}

/// Where [`StagedRun::advance`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Halt {
    /// The budget it was given is spent.
    Budget,
    /// The run is over (production ended).
    Ended,
    /// The current stage's length is in another unit than the budget (events against
    /// simulated time); the stage is left where it was.
    OtherUnit,
}

/// A scene's run in progress, stage by stage as `dmd run` runs it: equilibration (with the
/// scene's thermostat), HMC equilibration segments, then production with the thermostat of
/// `thermostat.during` and the observers of `[output]`. [`run_scene`] is [`build_run`] and
/// one [`StagedRun::advance`] to the end; advancing in pieces runs the same stages.
pub struct StagedRun<M: PairModel, Q: Scheduler> {
    sim: Simulation<M, Q>,
    scene: Scene,
    built: Built,
    layout: Layout,
    /// The named sites of each species, for the site–site g(r) ([`Plan::sites`]).
    sites: Option<Vec<MoleculeSites>>,
    lengths: DVec3,
    body_species: Vec<u32>,
    out: Option<std::path::PathBuf>,
    scene_name: Option<String>,
    /// The smooth estimator, until production's observers take it.
    smooth: Option<Box<dyn crate::analysis::smooth::Evaluate>>,
    driver: Driver,
    andersen: Option<Andersen>,
    eq_stop: Stop,
    hmc_eq: u64,
    /// Production's length.
    stop: Stop,
    stage: Stage,
    /// The reporter was told that the current stage started.
    open: bool,
    /// Production's thermostat is set (it follows equilibration's).
    switched: bool,
    /// Production's observers are set up.
    production: bool,
    ended: bool,
    /// Production did not start in a checkpoint this run continues.
    fresh_production: bool,
    observers: Observers,
    /// The files [`StagedRun::finish`] wrote.
    files: Vec<String>,
    /// A checkpoint's file and observers, when it was saved in production.
    resumed_production: Option<(std::path::PathBuf, ObserverState)>,
}

impl<M: PairModel, Q: Scheduler> StagedRun<M, Q> {
    /// The loop.
    pub fn simulation(&self) -> &Simulation<M, Q> {
        &self.sim
    }

    /// What the run was built with.
    pub fn built(&self) -> &Built {
        &self.built
    }

    /// The current stage and what is left of it; `None` once the run is over.
    pub fn stage(&self) -> Option<Stage> {
        (!self.ended).then_some(self.stage)
    }

    /// The name of the current stage (`equilibration`, `hmc equilibration`, `production`,
    /// `hmc production`), or `ended`.
    pub fn stage_name(&self) -> &'static str {
        match (self.ended, self.stage) {
            (true, _) => "ended",
            (false, Stage::Equilibration(Left::Segments(_))) => "hmc equilibration",
            (false, Stage::Equilibration(_)) => "equilibration",
            (false, Stage::Production(Left::Segments(_))) => "hmc production",
            (false, Stage::Production(_)) => "production",
        }
    }

    /// Starts what comes next without running an event: the reporter's phase, production's
    /// thermostat after equilibration, production's observers.
    fn settle(&mut self, reporter: &mut dyn Reporter) -> Result<(), RunError> {
        if let Stage::Equilibration(Left::Events(_) | Left::Time(_)) = self.stage {
            if !self.open {
                reporter.phase("equilibration", self.eq_stop);
                self.open = true;
            }
            return Ok(());
        }
        if !self.switched {
            self.switched = true;
            let production_thermostat = self
                .andersen
                .filter(|_| self.scene.thermostat.during == ThermostatPhase::Always);
            if self.fresh_production
                && self.driver.record.had_thermostat != production_thermostat.is_some()
            {
                self.sim.set_thermostat(production_thermostat);
            }
        }
        if let Stage::Equilibration(Left::Segments(_)) = self.stage {
            if !self.open {
                // HMC equilibration segments (not recorded).
                if !self.sim.at_origin() {
                    self.sim
                        .begin_phase(self.driver.record.had_thermostat, None, None);
                    self.sim.move_origin_here();
                }
                reporter.phase("hmc equilibration", Stop::Events(self.hmc_eq));
                self.open = true;
            }
            return Ok(());
        }
        if !self.production {
            self.enter_production(reporter)?;
        }
        Ok(())
    }

    /// Production's observers and start: fresh, or those of the checkpoint saved in it.
    fn enter_production(&mut self, reporter: &mut dyn Reporter) -> Result<(), RunError> {
        self.production = true;
        let scene = &self.scene;
        let o = &scene.output;
        let lengths = self.lengths;
        let mut observers = Observers::default();
        let resumed = self.resumed_production.take();
        if let Some(rdf) = &o.rdf {
            let r_max = rdf_r_max(scene, lengths)?;
            let g = Rdf::new(rdf.bins as usize, r_max, rdf.every);
            observers.rdf = Some(match &self.sites {
                Some(sites) => g.with_sites(sites.clone()),
                None => g,
            });
        }
        if o.msd.is_some() || o.vacf.is_some() || o.orientation_acf.is_some() {
            let lag = o
                .msd
                .iter()
                .chain(o.vacf.iter())
                .chain(o.orientation_acf.iter())
                .map(|c| c.max_lag)
                .fold(0.0, f64::max);
            observers.correlations = Some(Correlations::with_orientations(
                o.sample_interval.expect("checked"),
                lag,
                o.msd.is_some(),
                o.vacf.is_some(),
                o.orientation_acf.is_some(),
            ));
        }
        if o.series {
            // Written to series.csv as it grows; a resumed run continues the file where its
            // checkpoint left it (the rows after it, from the stopped run, are cut off).
            let path = self.out.as_deref().map(|dir| dir.join("series.csv"));
            let units = self.built.units.series();
            observers.series = Some(match &resumed {
                Some((_, c)) => Series::resumed(
                    path.as_deref(),
                    units,
                    &c.series.clone().unwrap_or_default(),
                )?,
                None => match &path {
                    Some(p) => Series::streamed(p, units)?,
                    None => Series::held(units),
                },
            });
        }
        if o.sample_interval.is_some() {
            observers.samples = Some(crate::analysis::smooth::Samples::default());
            observers.smooth = self.smooth.take();
            if observers
                .smooth
                .as_ref()
                .is_some_and(|e| e.needs_attitudes())
            {
                self.sim.set_sample_attitudes(true);
            }
            observers.smooth_every = o
                .smooth_every
                .unwrap_or(crate::config::scene::DEFAULT_SMOOTH_EVERY);
        }
        observers.max_bytes = Some(crate::config::limits::max_bytes(scene));
        let out = self.out.as_deref();
        if let (Some(_), Some(dir)) = (&o.trajectory, out) {
            let path = dir.join("trajectory.xyz");
            let layout = self.layout.clone();
            observers.trajectory = Some(match &resumed {
                Some((_, c)) => {
                    let (len, frames) = c.trajectory.unwrap_or((0, 0));
                    Trajectory::reopen(&path, layout, len, frames)?
                }
                None => Trajectory::create(&path, layout)?,
            });
        }
        if let (Some(_), Some(dir)) = (&o.gsd, out) {
            let path = dir.join("trajectory.gsd");
            let layout = self.layout.clone();
            observers.gsd = Some(match &resumed {
                Some((_, c)) => GsdTrajectory::reopen(&path, layout, c.gsd.unwrap_or(0))?,
                None => GsdTrajectory::create(&path, layout)?,
            });
        }
        match resumed {
            None => {
                let had_thermostat = self.driver.record.had_thermostat;
                let production_thermostat = self
                    .andersen
                    .filter(|_| scene.thermostat.during == ThermostatPhase::Always);
                let wants_samples = observers.rdf.is_some()
                    || observers.correlations.is_some()
                    || observers.series.is_some()
                    || observers.samples.is_some();
                let interval = |t: &Option<crate::config::scene::TrajectorySpec>| {
                    t.as_ref().filter(|_| out.is_some()).map(|t| t.interval)
                };
                let sim = &mut self.sim;
                sim.begin_phase_with_frames(
                    had_thermostat && production_thermostat.is_none(),
                    o.sample_interval.filter(|_| wants_samples),
                    [interval(&o.trajectory), interval(&o.gsd)],
                );
                if scene.hmc.is_some() {
                    sim.move_origin_here();
                }
                // NVE production starts at the bath temperature, not wherever the stochastic
                // thermostat left the kinetic energy (as the smd engine's last rescaling does).
                if had_thermostat
                    && scene.hmc.is_none()
                    && scene.thermostat.rescales_at_end()
                    && let Some(a) = self.andersen
                {
                    sim.rescale_to_temperature(a.temperature);
                }
                let (p0, _) = sim.momentum_and_mass();
                let k0 = sim.kinetic_energy();
                self.driver.record.start = Some((
                    k0,
                    k0 + sim.potential_energy(),
                    p0.to_array(),
                    sim.momentum_scale(),
                ));
                let report = sim.model().report();
                self.driver.record.search_start = SearchStats::from_report(&report);
                self.driver.record.counts_start = report
                    .counts()
                    .map(|(name, c)| (name.to_owned(), c))
                    .collect();
                self.stage = Stage::Production(match &scene.hmc {
                    Some(h) => Left::Segments(h.segments),
                    None => left_of(self.stop),
                });
            }
            Some((path, c)) => {
                let l = lengths;
                crate::driver::checkpoint::check_observers(
                    &c,
                    observers.rdf.as_ref(),
                    observers.correlations.as_ref(),
                    observers.samples.is_some(),
                    &self.body_species,
                    l.x * l.y * l.z,
                )
                .map_err(|m| CheckpointError {
                    path,
                    problem: Problem::Inconsistent(
                        crate::engine::simulation::StateError(m).to_string(),
                    ),
                })?;
                observers.rdf = c.rdf;
                observers.correlations = c.correlations;
                observers.samples = c.samples;
            }
        }
        if observers.rdf.as_ref().is_some_and(Rdf::needs_attitudes) {
            self.sim.set_sample_attitudes(true);
        }
        if let Some(c) = &mut self.driver.chain
            && scene.hmc.is_some()
        {
            c.recording = true;
        }
        self.observers = observers;
        reporter.phase(
            if self.scene.hmc.is_some() {
                "hmc production"
            } else {
                "production"
            },
            self.stop,
        );
        self.open = true;
        Ok(())
    }

    /// Runs the stages from where the run stands, for at most `budget` (events, or simulated
    /// time; `None`: to the end of the run). A stage of HMC segments runs whole segments while
    /// the budget lasts. Pieces of a stage run exactly as the whole stage would, except that
    /// the time integrals are summed piece by piece (round-off only).
    ///
    /// # Errors
    /// [`RunError`] as [`run_scene`] (a cancelled run: `RunError::Sim(SimError::Cancelled)`,
    /// the state whole).
    pub fn advance(
        &mut self,
        budget: Option<Stop>,
        reporter: &mut dyn Reporter,
    ) -> Result<Halt, RunError> {
        self.sim.set_cancel(reporter.cancel_flag());
        let mut budget = budget;
        loop {
            if self.ended {
                return Ok(Halt::Ended);
            }
            match budget {
                Some(Stop::Events(0)) => return Ok(Halt::Budget),
                Some(Stop::Time(t)) if t <= 0.0 => return Ok(Halt::Budget),
                _ => {}
            }
            let production = matches!(self.stage, Stage::Production(_));
            let (left, put): (Left, fn(Left) -> Stage) = match self.stage {
                Stage::Equilibration(l) => (l, Stage::Equilibration),
                Stage::Production(l) => (l, Stage::Production),
            };
            let (e0, t0) = (self.driver.events, self.sim.time());
            if production {
                self.driver.started = Some((Instant::now(), thread_cpu_seconds()));
            }
            let result = match left {
                Left::Segments(n) => {
                    let take = if budget.is_none() { n } else { n.min(1) };
                    self.driver
                        .segments(&mut self.sim, n, take, production, reporter)
                        .map(|()| Left::Segments(n - take))
                }
                _ => {
                    let (piece, rest) = match (left, budget) {
                        (l, None) => (l, None),
                        (Left::Events(n), Some(Stop::Events(b))) => {
                            (Left::Events(n.min(b)), Some(Left::Events(n - n.min(b))))
                        }
                        (Left::Time(t), Some(Stop::Time(b))) if b < t => {
                            (Left::Time(b), Some(Left::Time(t - b)))
                        }
                        (Left::Time(t), Some(Stop::Time(_))) => (Left::Time(t), None),
                        _ => return Ok(Halt::OtherUnit),
                    };
                    let mut none = Observers::default();
                    let observers = if production {
                        &mut self.observers
                    } else {
                        &mut none
                    };
                    self.driver
                        .plain(&mut self.sim, piece, production, observers, reporter)
                        .map(|()| match rest {
                            Some(Left::Events(0)) | None => Left::Events(0),
                            Some(l) => l,
                        })
                }
            };
            if production && let Some((wall, cpu0)) = self.driver.started.take() {
                let seconds = &mut self.driver.record.seconds;
                seconds.0 += wall.elapsed().as_secs_f64();
                seconds.1 += match (cpu0, thread_cpu_seconds()) {
                    (Some(a), Some(b)) => b - a,
                    _ => wall.elapsed().as_secs_f64(),
                };
            }
            let rest = result?;
            budget = match budget {
                Some(Stop::Events(b)) => {
                    Some(Stop::Events(b.saturating_sub(self.driver.events - e0)))
                }
                Some(Stop::Time(b)) => Some(Stop::Time(b - (self.sim.time() - t0))),
                None => None,
            };
            let over = matches!(rest, Left::Events(0) | Left::Segments(0));
            self.stage = put(rest);
            if over {
                self.end_stage(reporter)?;
            } else if matches!(left, Left::Time(_)) {
                // A piece of a stage in time ends at the budget's end exactly.
                budget = Some(Stop::Time(0.0));
            }
        }
    }

    /// The current stage ended: report it and start the next.
    fn end_stage(&mut self, reporter: &mut dyn Reporter) -> Result<(), RunError> {
        reporter.done();
        match self.stage {
            Stage::Production(_) => {
                self.ended = true;
                return Ok(());
            }
            Stage::Equilibration(Left::Segments(_)) => {
                self.stage = Stage::Production(Left::Events(0));
            }
            Stage::Equilibration(_) => {
                let sim = &self.sim;
                reporter.equilibrated(PhaseEnd {
                    events: sim.counters().events,
                    elapsed: sim.phase_elapsed(),
                    temperature: self
                        .built
                        .units
                        .temperature_out(2.0 * sim.kinetic_energy() / sim.dof()),
                });
                self.driver.record.equilibration_events = sim.counters().events;
                self.stage = if self.hmc_eq > 0 {
                    Stage::Equilibration(Left::Segments(self.hmc_eq))
                } else {
                    Stage::Production(Left::Events(0))
                };
            }
        }
        self.open = false;
        self.settle(reporter)
    }

    /// The checkpoint of the run as it stands (between two advances): the time origin is
    /// re-based first, so the run and one resumed from the file continue identically.
    ///
    /// # Errors
    /// [`RunError::Checkpoint`] or an output's error (marking the trajectories' ends).
    pub fn checkpoint(&mut self, source: SceneSource) -> Result<Checkpoint, RunError> {
        if !self.sim.at_origin() {
            self.sim.rebase();
        }
        let trajectory = match &mut self.observers.trajectory {
            Some(t) => Some(t.mark()?),
            None => None,
        };
        let gsd = match &mut self.observers.gsd {
            Some(g) => Some(g.mark()?),
            None => None,
        };
        let series = match &mut self.observers.series {
            Some(s) => Some(s.mark()?),
            None => None,
        };
        let observers = &self.observers;
        Ok(Checkpoint {
            source,
            every: None,
            stage: self.stage,
            sim: self.sim.save_state(),
            record: self.driver.record.clone(),
            observers: ObserverState {
                rdf: observers.rdf.clone(),
                correlations: observers.correlations.clone(),
                series,
                trajectory,
                gsd,
                samples: observers.samples.clone(),
            },
            chain: self.driver.chain.clone(),
        })
    }

    /// The summary of production so far (all of it once the run has ended), as `dmd run`
    /// writes it; `None` before production (in equilibration).
    pub fn summary(&self) -> Option<Summary> {
        if !self.production {
            return None;
        }
        let scene = &self.scene;
        let sim = &self.sim;
        let observers = &self.observers;
        let (wall_seconds, cpu_seconds) = self.driver.record.seconds;
        let (k0, e0, p0, p_scale) = self.driver.record.start?;
        let p0 = DVec3::from_array(p0);
        let search0 = self.driver.record.search_start;
        let lengths = self.lengths;
        let counters = sim.counters();
        let anomalies = sim.anomalies();
        let n = sim.bodies().len() as f64;
        let volume = lengths.x * lengths.y * lengths.z;
        let t = sim.phase_elapsed();
        let k1 = sim.kinetic_energy();
        let u1 = sim.potential_energy();
        let e1 = k1 + u1;
        let (p1, _) = sim.momentum_and_mass();
        let dof = sim.dof();
        let mean_k = if t > 0.0 {
            sim.kinetic_integral() / t
        } else {
            k1
        };
        let kt = 2.0 * mean_k / dof;
        let mean_rot = if t > 0.0 {
            sim.rotational_kinetic_integral() / t
        } else {
            sim.model().rotational_kinetic()
        };
        let rot_dof = sim.model().rotational_dof();
        let kt_trans = 2.0 * (mean_k - mean_rot) / (dof - rot_dof);
        let report = sim.model().report();
        let search = SearchStats::from_report(&report)
            .zip(search0)
            .map(|(a, b)| a.since(&b));
        let u = self.built.units;
        let excess = if t > 0.0 {
            sim.virial() / (3.0 * t * volume)
        } else {
            f64::NAN
        };
        let ideal = n * kt / volume;
        let pair_events = counters.pair_events();
        let by_kind: BTreeMap<String, u64> = [
            ("core", counters.core),
            ("step_in", counters.step_in),
            ("step_out", counters.step_out),
            ("step_reflect", counters.step_reflect),
            ("shell_crossing", counters.shell),
            ("thermostat", counters.thermostat),
            ("virtual", counters.virtual_),
            ("samples", counters.samples),
            ("rebases", counters.rebases),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_owned(), v))
        .collect();
        let anomalies_by_kind: BTreeMap<String, u64> = [
            ("negative_time", anomalies.negative_time),
            ("overlap", anomalies.overlap),
            ("receding", anomalies.receding),
            (
                "search_failures",
                search.map_or(0, |s: SearchStats| s.failures),
            ),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_owned(), v))
        .collect();
        let qs = sim.schedule_stats();
        let sampled = observers
            .samples
            .as_ref()
            .map(crate::analysis::smooth::Samples::summary);
        let diffusion = Correlations::diffusions(observers.correlations.as_ref());
        let summary = Summary {
            engine: "dmd".to_owned(),
            events: counters.events,
            events_by_kind: by_kind,
            equilibration_events: self.driver.record.equilibration_events,
            wall_seconds,
            cpu_seconds,
            events_per_second: counters.events as f64 / wall_seconds,
            events_per_cpu_second: counters.events as f64 / cpu_seconds,
            pair_events_per_second: pair_events as f64 / wall_seconds,
            sim_time: t,
            n_bodies: n as u64,
            density: n / volume,
            box_lengths: lengths.to_array(),
            temperature: u.temperature_out(kt),
            temperature_start: u.temperature_out(2.0 * k0 / dof),
            temperature_error: sampled.map(|s| u.temperature_out(s.temperature.error)),
            degrees_of_freedom: dof,
            pressure: u.pressure_out(ideal + excess),
            pressure_ideal: u.pressure_out(ideal),
            pressure_excess: u.pressure_out(excess),
            pressure_error: sampled.map(|s| u.pressure_out(s.pressure.error)),
            compressibility: (ideal + excess) * volume / (n * kt),
            mean_free_time: n * t / (2.0 * pair_events as f64),
            collision_rate: 2.0 * pair_events as f64 / (n * t),
            energy_kinetic: u.energy_out(k1),
            energy_potential: u.energy_out(u1),
            potential_energy_per_body: u.energy_out(if t > 0.0 {
                sim.potential_integral() / t / n
            } else {
                u1 / n
            }),
            potential_energy_per_body_error: sampled
                .map(|s| u.energy_out(s.potential_per_body.error)),
            potential_energy_per_body_smooth: sampled
                .and_then(|s| s.potential_smooth_per_body)
                .map(|b| u.energy_out(b.mean)),
            potential_energy_per_body_smooth_error: sampled
                .and_then(|s| s.potential_smooth_per_body)
                .map(|b| u.energy_out(b.error)),
            pressure_smooth: sampled
                .and_then(|s| s.pressure_smooth)
                .map(|b| u.pressure_out(b.mean)),
            pressure_smooth_error: sampled
                .and_then(|s| s.pressure_smooth)
                .map(|b| u.pressure_out(b.error)),
            energy_total_start: u.energy_out(e0),
            energy_total_end: u.energy_out(e1),
            relative_energy_drift: (e1 - e0).abs() / e0.abs().max(k0),
            momentum_drift: (p1 - p0).length() / p_scale,
            anomalies: anomalies.total() + search.map_or(0, |s| s.failures),
            anomalies_by_kind,
            model: self.built.model.to_owned(),
            units: match scene.units {
                crate::config::scene::UnitSystem::Reduced => "reduced",
                crate::config::scene::UnitSystem::Molecular => "molecular",
            }
            .to_owned(),
            events_per_ps: (scene.units == crate::config::scene::UnitSystem::Molecular)
                .then_some(pair_events as f64 / t),
            events_per_time_unit: (scene.units == crate::config::scene::UnitSystem::Reduced)
                .then_some(pair_events as f64 / t),
            pair_events_per_cpu_second: pair_events as f64 / cpu_seconds,
            virtual_events: counters.virtual_,
            terrace_crossings: counters.step_in + counters.step_out,
            reflections: counters.core + counters.step_reflect,
            detected_misses: search.map_or(0, |s| s.off_terrace + s.misfits),
            verified_misses: search.filter(|s| s.verified > 0).map(|s| s.verify_misses),
            search,
            translational_temperature: u.temperature_out(kt_trans),
            translational_temperature_error: sampled
                .map(|s| s.translational_temperature.error)
                .filter(|e| e.is_finite())
                .map(|e| u.temperature_out(e)),
            rotational_temperature: (rot_dof > 0.0)
                .then(|| u.temperature_out(2.0 * mean_rot / rot_dof)),
            rotational_temperature_error: sampled
                .and_then(|s| s.rotational_temperature)
                .map(|b| b.error)
                .filter(|e| e.is_finite())
                .map(|e| u.temperature_out(e)),
            queue: match scene.run.queue {
                QueueKind::Bounded => "bounded",
                QueueKind::Heap => "heap",
                QueueKind::Tournament => "tournament",
                QueueKind::Calendar => "calendar",
            }
            .to_owned(),
            queue_pushed: qs.pushed,
            queue_stale_dropped: qs.stale_dropped,
            queue_stale_swept: qs.stale_swept,
            requeued: qs.requeued,
            diffusion_msd: diffusion.msd,
            diffusion_vacf: diffusion.vacf,
            diffusion_msd_error: diffusion.msd_error,
            diffusion_vacf_error: diffusion.vacf_error,
            errors_without_plateau: sampled
                .map(|s| s.without_plateau())
                .unwrap_or_default()
                .into_iter()
                .chain(diffusion.without_plateau.iter().copied())
                .map(str::to_owned)
                .collect(),
            seed: scene.seed,
            files: self.files.clone(),
            hmc: self
                .driver
                .chain
                .as_ref()
                .map(|c| hmc_out(c.summary(n as usize), &u)),
            bond_error: sim.model().bond_error_at(sim.now()),
            rattle: crate::models::flexible::FlexStats::from_report(&sim.model().report()),
            model_counts: report
                .counts()
                .map(|(name, c)| {
                    let before = self.driver.record.counts_start.get(name).copied();
                    (name.to_owned(), c.saturating_sub(before.unwrap_or(0)))
                })
                .collect(),
            model_figures: report
                .reals()
                .map(|(name, x)| (name.to_owned(), x))
                .collect(),
        };
        Some(summary)
    }

    /// What the plots and tables of the run say besides their data.
    fn plot_info(&self, summary: &Summary) -> PlotInfo {
        PlotInfo {
            scene: self.scene_name.clone(),
            n: summary.n_bodies,
            temperature: summary.temperature,
            density: summary.density,
            terrace_step: terrace_step(&self.scene, &self.built.units),
            species: self.built.species.clone(),
            pressure: (summary.pressure, summary.pressure_error),
            potential_per_body: (
                summary.potential_energy_per_body,
                summary.potential_energy_per_body_error,
            ),
        }
    }

    /// The observables' tables of production so far (`rdf`, `msd`, `vacf`, `oacf`,
    /// `series`: the columns and numbers of their CSV files); empty before production. Once
    /// [`finish`](Self::finish) has closed `series.csv`, its rows are read from the folder.
    ///
    /// # Errors
    /// [`OutputError`] if the series cannot be read back.
    pub fn tables(&mut self) -> Result<Vec<ObservableTable>, OutputError> {
        let Some(summary) = self.summary() else {
            return Ok(Vec::new());
        };
        let info = self.plot_info(&summary);
        let mut tables = observable_tables(&mut self.observers, &self.built.units, &info)?;
        if let (true, None, Some(dir)) = (
            self.scene.output.series,
            &self.observers.series,
            self.out.as_deref(),
        ) {
            let path = dir.join("series.csv");
            tables.push(ObservableTable {
                name: "series".to_owned(),
                columns: crate::analysis::observable::SERIES_HEADER
                    .iter()
                    .map(|s| (*s).to_owned())
                    .collect(),
                rows: crate::analysis::output::read_csv_rows(&path)?,
            });
        }
        Ok(tables)
    }

    /// The summary of the ended run, with every file of `[output]` written into the run's
    /// folder (once: the trajectories are closed).
    ///
    /// # Errors
    /// An output's error.
    pub fn finish(&mut self) -> Result<Summary, RunError> {
        let mut summary = self
            .summary()
            .expect("a run that has ended has been in production");
        if let Some(dir) = self.out.clone() {
            let info = self.plot_info(&summary);
            let units = self.built.units;
            summary.files = write_observables(
                &dir,
                &mut self.observers,
                self.scene.output.plots,
                &units,
                &info,
            )?;
            if let Some(series) = self.driver.chain.as_ref().and_then(|c| c.series.as_ref()) {
                write_hmc_series(&dir.join("hmc.csv"), series, &units)?;
                summary.files.push("hmc.csv".to_owned());
            }
            self.files.clone_from(&summary.files);
            let json = serde_json::to_string_pretty(&summary).expect("a summary serialises");
            write_atomically(&dir.join("summary.json"), json.as_bytes())?;
        }
        Ok(summary)
    }
}

impl Summary {
    /// Pair events per unit of simulated time (`events_per_ps` in molecular units,
    /// `events_per_time_unit` in reduced ones).
    pub fn pair_event_rate(&self) -> f64 {
        self.events_per_ps
            .or(self.events_per_time_unit)
            .unwrap_or(f64::NAN)
    }
}

/// The stem of the scene file a run was read from (`rods-paper`), when the options say.
fn scene_name(options: &RunOptions) -> Option<String> {
    let file = match (&options.source, &options.resume) {
        (Some(s), _) => &s.file,
        (None, Some((_, c))) => &c.source.file,
        (None, None) => return None,
    };
    file.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
}

// ----- Checkpoints and HMC segments --------------------------------------------------------------

/// Runs the phases of a scene in pieces, saving checkpoints between them.
struct Driver {
    saver: Saver,
    record: RunRecord,
    chain: Option<Chain>,
    /// When production started in this process (wall clock, thread CPU seconds).
    started: Option<(Instant, Option<f64>)>,
    /// Events executed by this process (the checkpoint interval counts them).
    events: u64,
    /// Stop after the first checkpoint.
    halt: bool,
}

impl Driver {
    /// Runs plain dynamics for `left`, pausing at re-basings to save checkpoints when due.
    fn plain<M: PairModel, Q: Scheduler>(
        &mut self,
        sim: &mut Simulation<M, Q>,
        mut left: Left,
        production: bool,
        observers: &mut Observers,
        reporter: &mut dyn Reporter,
    ) -> Result<(), RunError> {
        loop {
            let stop = match left {
                Left::Events(n) => Stop::Events(n),
                Left::Time(t) => Stop::Time(t),
                Left::Segments(_) => unreachable!("segments are run by `segments`"),
            };
            let before = sim.counters().events;
            sim.run(stop, observers, &mut |p| reporter.progress(p))?;
            let done = sim.counters().events - before;
            self.events += done;
            if !sim.take_paused() {
                return Ok(());
            }
            left = match left {
                Left::Events(n) => Left::Events(n - done),
                _ => Left::Time(sim.remaining_time()),
            };
            let stage = if production {
                Stage::Production(left)
            } else {
                Stage::Equilibration(left)
            };
            self.checkpoint(sim, stage, observers)?;
        }
    }

    /// Runs `take` of the `left` HMC segments of a stage, saving checkpoints between them when
    /// due.
    fn segments<M: PairModel, Q: Scheduler>(
        &mut self,
        sim: &mut Simulation<M, Q>,
        left: u64,
        take: u64,
        production: bool,
        reporter: &mut dyn Reporter,
    ) -> Result<(), RunError> {
        for k in 0..take.min(left) {
            let chain = self.chain.as_mut().expect("a scene with [hmc] has a chain");
            let seg = chain.segment(sim)?;
            self.events += seg.events;
            reporter.progress(Progress {
                events: if production {
                    chain.stats.segments
                } else {
                    k + 1
                },
                elapsed: sim.phase_elapsed(),
            });
            let rest = left - k - 1;
            if rest > 0 {
                let stage = if production {
                    Stage::Production(Left::Segments(rest))
                } else {
                    Stage::Equilibration(Left::Segments(rest))
                };
                self.checkpoint(sim, stage, &mut Observers::default())?;
            }
        }
        Ok(())
    }

    /// Saves a checkpoint if one is due (the simulation is at a re-basing).
    fn checkpoint<M: PairModel, Q: Scheduler>(
        &mut self,
        sim: &Simulation<M, Q>,
        stage: Stage,
        observers: &mut Observers,
    ) -> Result<(), RunError> {
        let interrupted = crate::driver::interrupt::requested();
        if !interrupted && !self.saver.due(self.events) {
            return Ok(());
        }
        if interrupted && !self.saver.can_save() {
            return Err(RunError::Interrupted { checkpoint: None });
        }
        let mut record = self.record.clone();
        if let Some((wall, cpu0)) = self.started {
            record.seconds.0 += wall.elapsed().as_secs_f64();
            record.seconds.1 += match (cpu0, thread_cpu_seconds()) {
                (Some(a), Some(b)) => b - a,
                _ => wall.elapsed().as_secs_f64(),
            };
        }
        let trajectory = match &mut observers.trajectory {
            Some(t) => Some(t.mark()?),
            None => None,
        };
        let gsd = match &mut observers.gsd {
            Some(g) => Some(g.mark()?),
            None => None,
        };
        let series = match &mut observers.series {
            Some(s) => Some(s.mark()?),
            None => None,
        };
        let chain = &self.chain;
        self.saver.save(self.events, |source, every| {
            Ok(Checkpoint {
                source,
                every,
                stage,
                sim: sim.save_state(),
                record,
                observers: ObserverState {
                    rdf: observers.rdf.clone(),
                    correlations: observers.correlations.clone(),
                    series,
                    trajectory,
                    gsd,
                    samples: observers.samples.clone(),
                },
                chain: chain.clone(),
            })
        })?;
        if self.halt {
            return Err(RunError::Halted);
        }
        if interrupted {
            return Err(RunError::Interrupted {
                checkpoint: self.saver.path.clone(),
            });
        }
        Ok(())
    }
}

/// A checkpoint's bodies must be the scene's (count and species) before anything is built.
fn check_checkpoint_scene(
    scene: &Scene,
    path: &Path,
    c: &Checkpoint,
) -> Result<(), CheckpointError> {
    let bad = |m: String| CheckpointError {
        path: path.to_owned(),
        problem: Problem::Inconsistent(crate::engine::simulation::StateError(m).to_string()),
    };
    let n = scene.n_bodies();
    if c.sim.bodies.len() as u64 != n {
        return Err(bad(format!(
            "it has {} bodies, the scene {n}",
            c.sim.bodies.len()
        )));
    }
    for (s, sp) in scene.species.iter().enumerate() {
        let have = c
            .sim
            .bodies
            .iter()
            .filter(|b| b.species == s as u32)
            .count() as u64;
        if have != sp.count {
            return Err(bad(format!(
                "it has {have} bodies of species `{}`, the scene {}",
                sp.name, sp.count
            )));
        }
    }
    // The box, clocks and numbers of the state: the scene's box, every number finite.
    let l = c.sim.lengths;
    if !(l.is_finite() && l.min_element() > 0.0) {
        return Err(bad(format!("its box {l} is not a box")));
    }
    if let Some(box_) = crate::config::init::box_lengths(scene)
        && box_ != l
    {
        return Err(bad(format!("its box is {l}, the scene's {box_}")));
    }
    let finite = |x: f64| x.is_finite();
    let (p0, p1, p2, p3, p4) = &c.sim.phase;
    if !(finite(c.sim.epoch.value())
        && c.sim.epoch.value() >= 0.0
        && finite(c.sim.translational)
        && [
            *p0,
            *p1,
            p2.value(),
            p3.value(),
            p4.value(),
            c.sim.translational_integral.value(),
        ]
        .into_iter()
        .all(finite))
    {
        return Err(bad("its clock or phase sums are not finite".into()));
    }
    if let Some((k, e, p, scale)) = c.record.start
        && !([k, e, scale].into_iter().chain(p).all(finite) && k >= 0.0 && scale >= 0.0)
    {
        return Err(bad(
            "its record of the start of production is not finite".into()
        ));
    }
    let (wall, cpu) = c.record.seconds;
    if !(finite(wall) && finite(cpu) && wall >= 0.0 && cpu >= 0.0) {
        return Err(bad("its record of the time spent is not finite".into()));
    }
    // The thermostat and the sampling interval of the state are the scene's.
    if let Some((rate, temperature)) = c.sim.thermostat {
        let ok = scene.thermostat.kind == ThermostatKind::Andersen
            && scene.thermostat.rate == Some(rate)
            && scene
                .thermostat
                .temperature
                .unwrap_or(scene.init.temperature)
                == temperature;
        if !ok {
            return Err(bad(format!(
                "its thermostat (rate {}, temperature {}) is not the scene's",
                short(rate),
                short(temperature)
            )));
        }
    }
    if let Some(dt) = c.sim.sample_dt
        && scene.output.sample_interval != Some(dt)
    {
        return Err(bad(format!(
            "its sampling interval {} is not the scene's output.sample_interval",
            short(dt)
        )));
    }
    // What is left of the stage is at most the scene's phase.
    let too_long = match c.stage {
        // Between phases.
        Stage::Equilibration(Left::Events(0)) | Stage::Production(Left::Events(0)) => false,
        Stage::Equilibration(Left::Events(n)) => {
            scene.run.equilibration_time.is_some() || n > scene.run.equilibration_events
        }
        Stage::Equilibration(Left::Time(t)) => scene
            .run
            .equilibration_time
            .is_none_or(|e| t > e * (1.0 + 1e-9)),
        Stage::Equilibration(Left::Segments(n)) => scene
            .hmc
            .as_ref()
            .is_none_or(|h| n > h.equilibration_segments),
        Stage::Production(Left::Segments(n)) => scene.hmc.as_ref().is_none_or(|h| n > h.segments),
        Stage::Production(Left::Events(n)) => scene.run.events.is_none_or(|e| n > e),
        Stage::Production(Left::Time(t)) => {
            scene.run.events.is_some() || scene.run.time.is_none_or(|e| t > e * (1.0 + 1e-9))
        }
    };
    // The stage must be one this scene has (a hand-edited or foreign file must not reach a
    // broken invariant of the driver).
    let hmc = scene.hmc.is_some();
    if let Stage::Equilibration(Left::Time(t)) | Stage::Production(Left::Time(t)) = c.stage
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(bad(format!("the time left of its phase is {t}")));
    }
    let fits = match c.stage {
        Stage::Equilibration(Left::Segments(_)) | Stage::Production(Left::Segments(_)) => hmc,
        Stage::Production(_) => !hmc,
        Stage::Equilibration(_) => true,
    };
    if !fits {
        return Err(bad(format!(
            "its stage {:?} does not belong to a scene {} [hmc]",
            c.stage,
            if hmc { "with" } else { "without" }
        )));
    }
    if too_long {
        return Err(bad(format!(
            "its stage {:?} has more left than the scene's run",
            c.stage
        )));
    }
    if hmc != c.chain.is_some() {
        return Err(bad("its HMC chain does not match the scene's [hmc]".into()));
    }
    if let (Some(chain), Some(h)) = (&c.chain, &scene.hmc) {
        chain
            .check_fits(&hmc_settings(scene), h.series)
            .map_err(bad)?;
    }
    if matches!(c.stage, Stage::Production(_)) && c.record.start.is_none() {
        return Err(bad(
            "it is in production but has no record of its start".into()
        ));
    }
    Ok(())
}

/// The g(r) range of a scene with `output.rdf` in a box of `lengths`: at most half the box.
fn rdf_r_max(scene: &Scene, lengths: DVec3) -> Result<f64, SceneError> {
    let half = 0.5 * lengths.min_element();
    let r_max = scene
        .output
        .rdf
        .as_ref()
        .and_then(|r| r.r_max)
        .unwrap_or(half.min(5.0));
    if r_max > half {
        return Err(SceneError::invalid(
            "output.rdf.r_max",
            format!("{r_max} exceeds half the smallest box side ({half})"),
        ));
    }
    Ok(r_max)
}

fn left_of(stop: Stop) -> Left {
    match stop {
        Stop::Events(n) => Left::Events(n),
        Stop::Time(t) => Left::Time(t),
    }
}

/// The chain settings of a scene with `[hmc]`.
fn hmc_settings(scene: &Scene) -> HmcSettings {
    let h = scene.hmc.as_ref().expect("a scene with [hmc]");
    HmcSettings {
        ensemble: match h.ensemble {
            EnsembleKind::Canonical => Ensemble::Canonical,
            EnsembleKind::Microcanonical => Ensemble::Microcanonical,
        },
        segment_time: h.segment_time,
        temperature: h.temperature.unwrap_or(scene.init.temperature),
        exchanges: h.exchanges.unwrap_or_else(|| scene.n_bodies()),
        tolerance: h.tolerance,
        acceptance: match h.accept {
            AcceptKind::Metropolis => Acceptance::Metropolis,
            AcceptKind::Always => Acceptance::Always,
        },
        histogram_bins: h.histogram_bins as usize,
        histogram_range: h.histogram_range,
        seed: scene.seed,
        measure: match h.measure {
            MeasureKind::Dynamics => Measure::Dynamics,
            MeasureKind::StiffBonds => Measure::StiffBonds,
        },
    }
}

/// `hmc.csv`: one row per production segment (outcome: 0 accepted, 1 overlap, 2 energy,
/// 3 non-finite).
/// The HMC summary in the scene's units (energies and the temperature; `ΔH` histograms and
/// `e^{−βΔH}` are dimensionless or counts).
fn hmc_out(mut h: HmcSummary, u: &Units) -> HmcSummary {
    h.temperature = u.temperature_out(h.temperature);
    h.delta_h_mean = u.energy_out(h.delta_h_mean);
    h.delta_h_max_abs = u.energy_out(h.delta_h_max_abs);
    h.delta_h_histogram.low = u.energy_out(h.delta_h_histogram.low);
    h.delta_h_histogram.high = u.energy_out(h.delta_h_histogram.high);
    for b in [
        &mut h.potential_energy_per_body,
        &mut h.kinetic_energy_per_body,
    ] {
        b.mean = u.energy_out(b.mean);
        b.error = u.energy_out(b.error);
    }
    h
}

fn write_hmc_series(
    path: &Path,
    series: &[crate::driver::hmc::Segment],
    u: &Units,
) -> Result<(), OutputError> {
    use crate::driver::hmc::Outcome;
    let rows: Vec<Vec<f64>> = series
        .iter()
        .map(|s| {
            vec![
                s.index as f64,
                f64::from(u8::from(s.outcome == Outcome::Accepted)),
                match s.outcome {
                    Outcome::Accepted => 0.0,
                    Outcome::Overlap => 1.0,
                    Outcome::Energy => 2.0,
                    Outcome::NonFinite => 3.0,
                },
                u.energy_out(s.delta_h),
                u.energy_out(s.kinetic),
                u.energy_out(s.potential),
                s.events as f64,
                s.mismatched as f64,
                s.overlaps as f64,
            ]
        })
        .collect();
    write_csv(
        path,
        &[
            "segment",
            "accepted",
            "outcome",
            "delta_h",
            "kinetic",
            "potential",
            "events",
            "mismatched",
            "overlaps",
        ],
        &rows,
    )
}

/// The neighbour-list skin: `run.skin`, or by default 0.3 × the Boltzmann mean free path
/// `1/(√2 π ρ R²)` at the largest reach `R`, kept between R/4 (hard spheres) or R/10 (stepped
/// potentials) and 2R, and reduced to fit three cells of `R + 2δ` along the shortest box side,
/// or two where three do not fit even with a skin of 1 % of R.
/// (Measured optima with N = 4000: hard spheres δ ≈ 0.2–0.3 at ρ = 0.5–0.94, 0.5–1 at ρ = 0.1,
/// 1–2 at ρ = 0.01; square well λ = 1.5 at ρ = 0.5: 0.2; stepped Lennard-Jones at ρ = 0.5:
/// 0.1 or less; see docs/PERFORMANCE.md.)
fn choose_skin(
    scene: &Scene,
    reach: f64,
    hard: bool,
    config: &Configuration,
) -> Result<f64, SceneError> {
    let l = config.lengths;
    let fit = (l.min_element() / 2.0 - reach) / 2.0;
    if fit < 0.01 * reach {
        let a = (0..3).min_by(|&a, &b| l[a].total_cmp(&l[b])).unwrap_or(0);
        return Err(SceneError::invalid(
            "box",
            format!(
                "the box side {:.6} along {} is less than 2 × the interaction range {reach} \
                 (= {:.6}) plus the neighbour-list skin: the cell list needs two cells along \
                 each axis; use more bodies or a lower density",
                l[a],
                ['x', 'y', 'z'][a],
                2.0 * reach
            ),
        ));
    }
    if let Some(skin) = scene.run.skin {
        let least = crate::config::limits::MIN_SKIN_FRACTION * reach;
        if skin < least {
            return Err(SceneError::invalid(
                "run.skin",
                format!(
                    "{} is too thin: at least {} of the interaction reach {} (= {}), or every \
                     move across the reach costs more than a thousand list rebuilds; leave it \
                     out for the automatic skin",
                    crate::config::limits::short(skin),
                    crate::config::limits::short(crate::config::limits::MIN_SKIN_FRACTION),
                    crate::config::limits::short(reach),
                    crate::config::limits::short(least)
                ),
            ));
        }
        if skin > fit {
            return Err(SceneError::invalid(
                "run.skin",
                format!(
                    "{skin} is too large for this box: two cells of reach + 2 skin must fit \
                     along the shortest side {}, so the skin can be at most {fit:.6}",
                    l.min_element()
                ),
            ));
        }
        return Ok(skin);
    }
    let rho = config.positions.len() as f64 / (l.x * l.y * l.z);
    let mean_free_path =
        1.0 / (std::f64::consts::SQRT_2 * std::f64::consts::PI * rho * reach * reach);
    // Stepped potentials have many more pair events per unit of path than hard spheres, so
    // list rebuilds are relatively rarer and a thinner skin (fewer candidates) pays.
    let lower = if hard { 0.25 } else { 0.1 };
    let skin = (0.3 * mean_free_path).clamp(lower * reach, 2.0 * reach);
    // Where three cells fit with a skin of 1 % of the reach, the skin is kept within them (a
    // thinner skin and three cells scan fewer candidates than a thicker one and two).
    let fit3 = (l.min_element() / 3.0 - reach) / 2.0;
    let room = if fit3 >= 0.01 * reach { fit3 } else { fit };
    Ok(skin.min(0.999 * room))
}

fn setup_error(scene: &Scene, config: &Configuration, units: &Units, e: SetupError) -> RunError {
    let name = |k: &u32| &scene.species[config.species[*k as usize] as usize].name;
    let (key, problem) = match (&e, scene.init.positions) {
        (SetupError::BoxTooSmall { .. }, _) => ("box", e.to_string()),
        // A molecule with itself: two of its own sites that interact start inside their core.
        (
            SetupError::Overlap {
                i,
                j,
                distance,
                core,
            },
            positions,
        ) if i == j => {
            let s = config.species[*i as usize] as usize;
            let conformation = match positions {
                Positions::File => "the start file gives molecule",
                _ => "the species' `sites` give molecule",
            };
            return SceneError::invalid(
                format!("species[{s}].interact_beyond_bonds"),
                format!(
                    "{conformation} {i} ({}) two sites {distance:.6} apart that interact, less \
                     than their hard-core diameter {core}; give a conformation that keeps them \
                     apart, or count more bonds",
                    name(i)
                ),
            )
            .into();
        }
        (SetupError::InsideCore { i, j, energy, core }, positions) => {
            let what = format!(
                "bodies {i} ({}) and {j} ({}) start with pair energy {:.6}, at or above the \
                 hard-core level {} of the terraces",
                name(i),
                name(j),
                units.energy_out(*energy),
                units.energy_out(*core)
            );
            match positions {
                Positions::File => (
                    "init.file",
                    format!("overlapping initial configuration: {what}"),
                ),
                _ => (
                    "box.density",
                    format!(
                        "density too high for this lattice: {what}; lower the density or start \
                         from a file"
                    ),
                ),
            }
        }
        (SetupError::Overlap { .. }, Positions::File) => (
            "init.file",
            format!("overlapping initial configuration: {e}"),
        ),
        (
            SetupError::Overlap {
                i,
                j,
                distance,
                core,
            },
            _,
        ) => (
            "box.density",
            format!(
                "density too high for this lattice: it puts bodies {i} ({}) and {j} ({}) \
                     {distance:.6} apart, less than their hard-core diameter {core}; lower the \
                     density or start from a file",
                name(i),
                name(j)
            ),
        ),
        _ => ("init.positions", e.to_string()),
    };
    SceneError::invalid(key, problem).into()
}
