//! Running a scene end to end: set-up, equilibration, production, summary and outputs.
//!
//! [`run_scene`] picks the interaction model (hard spheres, stepped, or terraced rods) and the
//! queue once and hands over to a loop compiled for that pair; everything scene-specific
//! happens here, around the loop, never inside it. Scenes in molecular units are converted to
//! the internal units first and the summary back ([`units`](crate::units)).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use collide::Particle;
use event_queue::{BoundedQueue, HeapQueue, LazyQueue, Ticket, TournamentTree};
use glam::DVec3;
use serde::Serialize;

use crate::init::{Configuration, lattice, maxwell_boltzmann, read_orientations, read_xyz};
use crate::model::{HardSpheres, PairModel, Stepped};
use crate::observable::{Correlations, Observers, Rdf, Series};
use crate::output::{Curve, OutputError, Trajectory, plot_svg, write_atomically, write_csv};
use crate::rods::{Plan, equipartitioned_omegas, random_axes, rod_species, search_settings};
use crate::scene::{
    Orientations, Positions, QueueKind, Scene, SceneError, ThermostatKind, ThermostatPhase,
};
use crate::schedule::Scheduler;
use crate::simulation::{Andersen, LoopSettings, Progress, SetupError, SimError, Simulation, Stop};
use crate::terraced::{PairTable, SearchStats, Terraced};
use crate::units::Units;

/// Most events between re-basings: generations are `u32` and every event list is rebuilt at a
/// re-basing, so no generation can wrap round while an event predicted with it waits.
pub const MAX_REBASE_EVENTS: u64 = 1 << 31;

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scene is not acceptable.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The simulation could not go on.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// An output could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// Receives progress reports (the `dmd` command draws a progress bar).
pub trait Reporter {
    /// A phase (`equilibration` or `production`) starts with this length.
    fn phase(&mut self, _name: &str, _length: Stop) {}
    /// Progress within the phase.
    fn progress(&mut self, _p: Progress) {}
    /// The phase ended.
    fn done(&mut self) {}
}

/// A reporter that reports nothing.
pub struct Quiet;
impl Reporter for Quiet {}

/// Energies, momentum and counters of a run, as written to `summary.json`. Units are the
/// scene's (reduced, σ = m = kT = 1 by default; in molecular units energies in kJ/mol,
/// temperatures in K, pressures in bar, times in ps, lengths in Å); all averages are over
/// production.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
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
    /// Degrees of freedom of the temperature (3N − 3 in NVE, 3N with a thermostat).
    pub degrees_of_freedom: f64,
    /// Pressure from the collision virial: `(N kT + Σ r_ij·Δp_i / 3t) / V`.
    pub pressure: f64,
    /// Ideal part of the pressure, `N kT / V`.
    pub pressure_ideal: f64,
    /// Excess (virial) part of the pressure.
    pub pressure_excess: f64,
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
    /// `terraced-gay-berne`).
    pub model: String,
    /// The unit system of the numbers (`reduced` or `molecular`).
    pub units: String,
    /// Pair events (terrace crossings and reflections) per unit of simulated time: per ps in
    /// molecular units (003 §V.B reports 4.7·10⁴ for its rods at ΔV = kT/2).
    pub events_per_ps: f64,
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
    /// Rotational temperature `⟨K_rot⟩/N` of rods (two degrees of freedom each).
    pub rotational_temperature: Option<f64>,
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
    /// Self-diffusion coefficient from the Green–Kubo VACF integral (when `output.vacf` is on).
    pub diffusion_vacf: Option<f64>,
    /// The seed.
    pub seed: u64,
    /// Files written besides `summary.json`.
    pub files: Vec<String>,
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
    let units = Units::of(scene.units);
    let scene = &scene.internal();
    let plan = Plan::of(scene)?;
    // A lattice denser than the smallest hard core allows can hold no species; pairs of larger
    // cores that end up too close are reported by the set-up.
    let smallest_core = match &plan {
        Plan::Spheres(potentials) => potentials
            .all()
            .iter()
            .filter_map(|p| p.core())
            .fold(f64::INFINITY, f64::min),
        _ => 0.0,
    };
    let smallest_core = if smallest_core.is_finite() {
        smallest_core
    } else {
        0.0
    };
    let config = match scene.init.positions {
        Positions::Fcc | Positions::Sc => lattice(scene, smallest_core)?,
        Positions::File => {
            let file = scene.init.file.as_ref().expect("checked");
            read_xyz(scene, &base.join(file))?
        }
    };
    let masses: Vec<f64> = config
        .species
        .iter()
        .map(|&s| scene.species[s as usize].mass)
        .collect();
    let velocities = maxwell_boltzmann(&masses, scene.init.temperature, scene.seed);
    let n = config.positions.len();
    let hard = matches!(&plan, Plan::Spheres(p) if p.all_hard_spheres());
    let skin = choose_skin(scene, plan.reach(), hard, &config)?;
    let settings = LoopSettings {
        rebase_events: scene
            .run
            .rebase_events
            .unwrap_or_else(|| (100 * n as u64).clamp(1_000_000, MAX_REBASE_EVENTS)),
        seed: scene.seed.wrapping_add(0x7e57_0000_0000_0001),
        debug_check_events: (n as u64).max(1000),
        skin,
        start_time: 0.0,
    };
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).map_err(|e| OutputError {
            path: dir.to_owned(),
            message: e.to_string(),
        })?;
    }
    let ctx = Context {
        scene,
        config: &config,
        velocities: &velocities,
        settings,
        out,
        units,
        model_name: plan.name(),
    };
    type Bounded = LazyQueue<BoundedQueue<Ticket>>;
    type Heap = LazyQueue<HeapQueue<Ticket>>;
    match plan {
        Plan::Spheres(potentials) => {
            let particles: Vec<Particle> = scene
                .species
                .iter()
                .map(|s| Particle::new(s.mass).expect("masses are checked"))
                .collect();
            match (hard, scene.run.queue) {
                (true, QueueKind::Bounded) => {
                    ctx.go::<_, Bounded>(HardSpheres::new(potentials, particles), reporter)
                }
                (true, QueueKind::Heap) => {
                    ctx.go::<_, Heap>(HardSpheres::new(potentials, particles), reporter)
                }
                (true, QueueKind::Tournament) => {
                    ctx.go::<_, TournamentTree>(HardSpheres::new(potentials, particles), reporter)
                }
                (false, QueueKind::Bounded) => {
                    ctx.go::<_, Bounded>(Stepped::new(potentials, particles, n), reporter)
                }
                (false, QueueKind::Heap) => {
                    ctx.go::<_, Heap>(Stepped::new(potentials, particles, n), reporter)
                }
                (false, QueueKind::Tournament) => {
                    ctx.go::<_, TournamentTree>(Stepped::new(potentials, particles, n), reporter)
                }
            }
        }
        Plan::Rods(tables) => {
            let model = terraced_model(scene, base, &config, tables)?;
            ctx.go_any_queue(model, reporter)
        }
        Plan::GayBerne(tables) => {
            let model = terraced_model(scene, base, &config, tables)?;
            ctx.go_any_queue(model, reporter)
        }
    }
}

/// The terraced model of a rods scene: orientations and equipartitioned angular velocities.
fn terraced_model<P: potential::PairPotential>(
    scene: &Scene,
    base: &Path,
    config: &Configuration,
    tables: Vec<PairTable<P>>,
) -> Result<Terraced<P>, RunError> {
    let n = config.positions.len();
    let axes = match scene.init.orientations {
        Orientations::Random => random_axes(n, scene.seed),
        Orientations::Aligned => {
            let a = glam::DVec3::from(scene.init.axis.expect("checked")).normalize();
            vec![a; n]
        }
        Orientations::File => {
            let file = scene.init.file.as_ref().expect("checked");
            read_orientations(&base.join(file), n)?
        }
    };
    let species = rod_species(scene);
    let inertia: Vec<f64> = config
        .species
        .iter()
        .map(|&s| species[s as usize].inertia)
        .collect();
    let omegas = equipartitioned_omegas(&axes, &inertia, scene.init.temperature, scene.seed);
    Terraced::new(
        species,
        tables,
        &config.species,
        &axes,
        &omegas,
        0.0,
        search_settings(scene),
        scene.seed ^ 0x5ea2_c400_0000_0007,
    )
    .map_err(|e| SceneError::invalid("search", e.to_string()).into())
}

struct Context<'a> {
    scene: &'a Scene,
    config: &'a Configuration,
    velocities: &'a [DVec3],
    settings: LoopSettings,
    out: Option<&'a Path>,
    units: Units,
    model_name: &'static str,
}

impl Context<'_> {
    fn go_any_queue<M: PairModel>(
        &self,
        model: M,
        reporter: &mut dyn Reporter,
    ) -> Result<Summary, RunError> {
        match self.scene.run.queue {
            QueueKind::Bounded => self.go::<_, LazyQueue<BoundedQueue<Ticket>>>(model, reporter),
            QueueKind::Heap => self.go::<_, LazyQueue<HeapQueue<Ticket>>>(model, reporter),
            QueueKind::Tournament => self.go::<_, TournamentTree>(model, reporter),
        }
    }

    fn go<M: PairModel, Q: Scheduler>(
        &self,
        model: M,
        reporter: &mut dyn Reporter,
    ) -> Result<Summary, RunError> {
        let scene = self.scene;
        let mut sim: Simulation<M, Q> = Simulation::new(
            self.config.lengths,
            &self.config.positions,
            self.velocities,
            &self.config.species,
            model,
            self.settings,
        )
        .map_err(|e| setup_error(scene, self.config, &self.units, e))?;

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
        let mut equilibration_events = 0;
        if equilibrate {
            if andersen.is_some() {
                sim.set_thermostat(andersen);
            }
            reporter.phase("equilibration", eq_stop);
            sim.run(eq_stop, &mut crate::simulation::NoSampler, &mut |p| {
                reporter.progress(p)
            })?;
            reporter.done();
            equilibration_events = sim.counters().events;
        }
        let production_thermostat =
            andersen.filter(|_| scene.thermostat.during == ThermostatPhase::Always);
        let had_thermostat = equilibrate && andersen.is_some();
        if had_thermostat != production_thermostat.is_some() {
            sim.set_thermostat(production_thermostat);
        }

        // Production.
        let o = &scene.output;
        let mut observers = Observers::default();
        let lengths = self.config.lengths;
        if let Some(rdf) = &o.rdf {
            let half = 0.5 * lengths.min_element();
            let r_max = rdf.r_max.unwrap_or(half.min(5.0));
            if r_max > half {
                return Err(SceneError::invalid(
                    "output.rdf.r_max",
                    format!("{r_max} exceeds half the smallest box side ({half})"),
                )
                .into());
            }
            observers.rdf = Some(Rdf::new(rdf.bins as usize, r_max, rdf.every));
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
            observers.series = Some(Series::default());
        }
        let out = self.out;
        if let (Some(_), Some(dir)) = (&o.trajectory, out) {
            observers.trajectory = Some(Trajectory::create(
                &dir.join("trajectory.xyz"),
                scene.species.iter().map(|s| s.name.clone()).collect(),
            )?);
        }
        let wants_samples = observers.rdf.is_some()
            || observers.correlations.is_some()
            || observers.series.is_some();
        sim.begin_phase(
            had_thermostat && production_thermostat.is_none(),
            o.sample_interval.filter(|_| wants_samples),
            o.trajectory
                .as_ref()
                .filter(|_| out.is_some())
                .map(|t| t.interval),
        );
        let k0 = sim.kinetic_energy();
        let e0 = k0 + sim.potential_energy();
        let (p0, _) = sim.momentum_and_mass();
        let p_scale = sim.momentum_scale();
        let stop = match (scene.run.events, scene.run.time) {
            (Some(e), _) => Stop::Events(e),
            (None, Some(t)) => Stop::Time(t),
            (None, None) => unreachable!("checked"),
        };
        reporter.phase("production", stop);
        let search0 = sim.model().search_stats();
        let wall = Instant::now();
        let cpu0 = thread_cpu_seconds();
        sim.run(stop, &mut observers, &mut |p| reporter.progress(p))?;
        let wall_seconds = wall.elapsed().as_secs_f64();
        let cpu_seconds = match (cpu0, thread_cpu_seconds()) {
            (Some(a), Some(b)) => b - a,
            _ => wall_seconds,
        };
        reporter.done();

        // Summary.
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
        let search = sim
            .model()
            .search_stats()
            .zip(search0)
            .map(|(a, b)| a.since(&b));
        let u = self.units;
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
        let mut summary = Summary {
            events: counters.events,
            events_by_kind: by_kind,
            equilibration_events,
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
            degrees_of_freedom: dof,
            pressure: u.pressure_out(ideal + excess),
            pressure_ideal: u.pressure_out(ideal),
            pressure_excess: u.pressure_out(excess),
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
            energy_total_start: u.energy_out(e0),
            energy_total_end: u.energy_out(e1),
            relative_energy_drift: (e1 - e0).abs() / e0.abs().max(k0),
            momentum_drift: (p1 - p0).length() / p_scale,
            anomalies: anomalies.total() + search.map_or(0, |s| s.failures),
            anomalies_by_kind,
            model: self.model_name.to_owned(),
            units: match scene.units {
                crate::scene::UnitSystem::Reduced => "reduced",
                crate::scene::UnitSystem::Molecular => "molecular",
            }
            .to_owned(),
            events_per_ps: pair_events as f64 / t,
            pair_events_per_cpu_second: pair_events as f64 / cpu_seconds,
            virtual_events: counters.virtual_,
            terrace_crossings: counters.step_in + counters.step_out,
            reflections: counters.core + counters.step_reflect,
            detected_misses: search.map_or(0, |s| s.off_terrace + s.misfits),
            verified_misses: search.filter(|s| s.verified > 0).map(|s| s.verify_misses),
            search,
            translational_temperature: u.temperature_out(kt_trans),
            rotational_temperature: (rot_dof > 0.0)
                .then(|| u.temperature_out(2.0 * mean_rot / rot_dof)),
            queue: match scene.run.queue {
                QueueKind::Bounded => "bounded",
                QueueKind::Heap => "heap",
                QueueKind::Tournament => "tournament",
            }
            .to_owned(),
            queue_pushed: qs.pushed,
            queue_stale_dropped: qs.stale_dropped,
            queue_stale_swept: qs.stale_swept,
            requeued: qs.requeued,
            diffusion_msd: observers
                .correlations
                .as_ref()
                .filter(|c| c.wants_msd())
                .and_then(Correlations::diffusion_from_msd),
            diffusion_vacf: observers
                .correlations
                .as_ref()
                .filter(|c| c.wants_vacf())
                .and_then(Correlations::diffusion_from_vacf),
            seed: scene.seed,
            files: Vec::new(),
        };
        if let Some(dir) = out {
            summary.files = write_observables(dir, &mut observers, o.plots, &self.units)?;
            let json = serde_json::to_string_pretty(&summary).expect("a summary serialises");
            write_atomically(&dir.join("summary.json"), json.as_bytes())?;
        }
        Ok(summary)
    }
}

/// The neighbour-list skin: `run.skin`, or by default 0.3 × the Boltzmann mean free path
/// `1/(√2 π ρ R²)` at the largest reach `R`, kept between R/4 (hard spheres) or R/10 (stepped
/// potentials) and 2R, and reduced to fit three cells of `R + 2δ` along the shortest box side.
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
    let fit = (l.min_element() / 3.0 - reach) / 2.0;
    if fit < 0.01 * reach {
        let a = (0..3).min_by(|&a, &b| l[a].total_cmp(&l[b])).unwrap_or(0);
        return Err(SceneError::invalid(
            "box",
            format!(
                "the box side {:.6} along {} is less than 3 × the interaction range {reach} \
                 (= {:.6}) plus the neighbour-list skin: the cell list needs three cells along \
                 each axis; use more bodies or a lower density",
                l[a],
                ['x', 'y', 'z'][a],
                3.0 * reach
            ),
        ));
    }
    if let Some(skin) = scene.run.skin {
        if skin > fit {
            return Err(SceneError::invalid(
                "run.skin",
                format!(
                    "{skin} is too large for this box: three cells of reach + 2 skin must fit \
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
    Ok(skin.min(0.999 * fit))
}

/// CPU time of the calling thread, from `/proc/thread-self/schedstat` (Linux).
pub fn thread_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

fn setup_error(scene: &Scene, config: &Configuration, units: &Units, e: SetupError) -> RunError {
    let name = |k: &u32| &scene.species[config.species[*k as usize] as usize].name;
    let (key, problem) = match (&e, scene.init.positions) {
        (SetupError::BoxTooSmall { .. }, _) => ("box", e.to_string()),
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

fn write_observables(
    dir: &Path,
    obs: &mut Observers,
    plots: bool,
    units: &Units,
) -> Result<Vec<String>, OutputError> {
    let mut files = Vec::new();
    let mut table = |name: &str,
                     header: &[&str],
                     rows: Vec<Vec<f64>>,
                     plot: Option<(&str, &str, &str, Vec<Curve<'_>>)>|
     -> Result<(), OutputError> {
        let csv = format!("{name}.csv");
        write_csv(&dir.join(&csv), header, &rows)?;
        files.push(csv);
        if let (true, Some((title, xl, yl, curves))) = (plots, plot) {
            let svg = format!("{name}.svg");
            plot_svg(&dir.join(&svg), title, xl, yl, &curves)?;
            files.push(svg);
        }
        Ok(())
    };
    if let Some(rdf) = &obs.rdf {
        let t = rdf.table();
        table(
            "rdf",
            &["r", "g"],
            t.iter().map(|&(r, g)| vec![r, g]).collect(),
            Some((
                "Radial distribution function",
                "r",
                "g(r)",
                vec![Curve {
                    label: "g(r)",
                    points: t,
                }],
            )),
        )?;
    }
    if let Some(c) = &obs.correlations {
        if c.wants_msd() {
            let t = c.msd_table();
            table(
                "msd",
                &["t", "msd"],
                t.iter().map(|&(x, y)| vec![x, y]).collect(),
                Some((
                    "Mean-square displacement",
                    "t",
                    "<|r(t) - r(0)|^2>",
                    vec![Curve {
                        label: "MSD",
                        points: t,
                    }],
                )),
            )?;
        }
        if c.wants_vacf() {
            let t = c.vacf_table();
            let c0 = t.first().map(|p| p.1).unwrap_or(1.0);
            table(
                "vacf",
                &["t", "vacf", "vacf_normalised"],
                t.iter().map(|&(x, y)| vec![x, y, y / c0]).collect(),
                Some((
                    "Velocity autocorrelation (normalised)",
                    "t",
                    "<v(0).v(t)> / <v^2>",
                    vec![Curve {
                        label: "VACF",
                        points: t.iter().map(|&(x, y)| (x, y / c0)).collect(),
                    }],
                )),
            )?;
        }
        if c.wants_oacf() {
            let t = c.oacf_table();
            table(
                "oacf",
                &["t", "s0_dot_st", "p2"],
                t.iter().map(|&(x, a, b)| vec![x, a, b]).collect(),
                Some((
                    "Long-axis orientational autocorrelation",
                    "t",
                    "<s(0).s(t)>, <P2(s(0).s(t))>",
                    vec![
                        Curve {
                            label: "<s(0).s(t)>",
                            points: t.iter().map(|&(x, a, _)| (x, a)).collect(),
                        },
                        Curve {
                            label: "<P2>",
                            points: t.iter().map(|&(x, _, b)| (x, b)).collect(),
                        },
                    ],
                )),
            )?;
        }
    }
    if let Some(s) = &obs.series {
        let rows: Vec<crate::observable::SeriesRow> = s
            .rows()
            .iter()
            .map(|r| crate::observable::SeriesRow {
                time: r.time,
                kinetic: units.energy_out(r.kinetic),
                potential: units.energy_out(r.potential),
                total: units.energy_out(r.total),
                temperature: units.temperature_out(r.temperature),
                pressure: units.pressure_out(r.pressure),
            })
            .collect();
        table(
            "series",
            &[
                "t",
                "kinetic",
                "potential",
                "total",
                "temperature",
                "pressure",
            ],
            rows.iter()
                .map(|r| {
                    vec![
                        r.time,
                        r.kinetic,
                        r.potential,
                        r.total,
                        r.temperature,
                        r.pressure,
                    ]
                })
                .collect(),
            None,
        )?;
        if plots {
            let pts = |f: fn(&crate::observable::SeriesRow) -> f64| -> Vec<(f64, f64)> {
                rows.iter().map(|r| (r.time, f(r))).collect()
            };
            plot_svg(
                &dir.join("series-energy.svg"),
                "Energy",
                "t",
                "energy",
                &[
                    Curve {
                        label: "kinetic",
                        points: pts(|r| r.kinetic),
                    },
                    Curve {
                        label: "potential",
                        points: pts(|r| r.potential),
                    },
                    Curve {
                        label: "total",
                        points: pts(|r| r.total),
                    },
                ],
            )?;
            plot_svg(
                &dir.join("series-pressure.svg"),
                "Pressure (averaged over each sampling interval)",
                "t",
                "P",
                &[Curve {
                    label: "pressure",
                    points: pts(|r| r.pressure),
                }],
            )?;
            files.push("series-energy.svg".into());
            files.push("series-pressure.svg".into());
        }
    }
    if let Some(t) = obs.trajectory.take() {
        t.finish()?;
        files.push("trajectory.xyz".into());
    }
    Ok(files)
}
