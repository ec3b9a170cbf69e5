//! The scene's second engine: standard molecular dynamics of the `smd` crate on the
//! same scene files, observables and output files as the event-driven engine.
//!
//! A scene says `engine = "smd"` (or `dmd run --engine smd`), and an optional `[smd]` table
//! gives the time step, the neighbour-list skin and the smoothing window of 003 Eq. 26. The
//! mapping, all of it here:
//!
//! - the potential of `[[pair]]` (`rods`, `lennard-jones`, `gay-berne`) is smoothed to zero
//!   between `r_l` and `r_u` (003 Eq. 26; default 2.5σ and 3σ, for Gay–Berne measured from
//!   the end-to-end contact κσ₀) and integrated with the splitting of [`smd::Integrator`];
//!   its terraces are not used; a kind between rigid tops that vanishes beyond a cut-off of
//!   its own (`ssd-e` water switched off at 9 Å, `spc-e` water whose site terms end at 9 Å,
//!   `biaxial-gay-berne`) is integrated as it is ([`smd::Rigid`]), the bodies rigid tops;
//! - the initial state is the event-driven engine's own (lattice or file, Maxwell–Boltzmann
//!   velocities, orientations or attitudes and equipartitioned angular velocities from the
//!   same seed);
//! - equilibration: with an Andersen thermostat, velocity rescaling to the bath temperature
//!   once per mean Andersen collision time `1/rate` (a deterministic thermostat in place of a
//!   stochastic one: both only prepare the state; production is NVE in both engines);
//!   without one, plain NVE steps;
//! - times (`run.time`, `run.equilibration_time`, `output.sample_interval`, the trajectory
//!   interval) are rounded to whole steps; the summary reports the times actually simulated;
//! - the observables are the event-driven engine's ([`Observers`]), fed from the integrator's
//!   state, so the files (`rdf.csv`, `msd.csv`, `vacf.csv`, `oacf.csv`, `series.csv`,
//!   `trajectory.xyz`, the SVG plots) are the same in name, columns and units.
//!
//! Keys only the event-driven engine uses (terraces, `[search]`, the queue, its skin) are
//! ignored and listed in `summary.json`; keys this engine cannot honour (stepped potentials,
//! HMC, chains, sweeps, several species, run lengths in events, a thermostat in production)
//! are refused when the scene is read ([`check`]).

use std::path::Path;

use glam::{DMat3, DQuat, DVec3};
use serde::Serialize;
use smd::{BodyModel, Integrator, Interaction, Observer, Settings, SmdError, Snapshot, System};

use crate::analysis::observable::{Correlations, Observers, Rdf, Series};
use crate::analysis::output::{
    Drawing, Layout, OutputError, Trajectory, axis_quaternion, element_of, write_atomically,
};
use crate::config::init::{
    Configuration, ase_momentum_unit, lattice, maxwell_boltzmann, read_attitudes, read_motion,
    read_orientations, read_xyz, rod_semi_axes,
};
use crate::config::kinds::{Kind, Visit};
use crate::config::rods::{equipartitioned_omegas, random_axes, rotor_omegas, tops_start};
pub use crate::config::scene::{Engine, SmdSpec, SmoothingSpec};
use crate::config::scene::{
    Orientations, Positions, Scene, SceneError, ThermostatKind, UnitSystem, Velocities,
};
use crate::config::smd_spec::{check, default_dt, ignored_keys, list_skin, window};
use crate::config::units::Units;
use crate::driver::reporting::{PhaseEnd, Quiet, Reporter, RunError, RunPlan, thread_cpu_seconds};
use crate::engine::body::Body;
use crate::engine::simulation::{Progress, Sampler, Stop, View};
use crate::models::rotor::TopInertia;

/// What an smd run wrote to `summary.json`. The fields it shares with the event-driven
/// engine's `Summary` (module `run`) have the same names, meanings and units (the
/// scene's: in molecular units kJ/mol, K, bar, ps, Å); averages are over production.
#[derive(Clone, Debug, Serialize)]
pub struct SmdSummary {
    /// `smd`.
    pub engine: String,
    /// Interaction model (`smd-` and the kind: `smd-rods`, `smd-lennard-jones`, `smd-ssd-e`, …).
    pub model: String,
    /// `reduced` or `molecular`.
    pub units: String,
    /// Number of bodies.
    pub n_bodies: u64,
    /// Number density N/V.
    pub density: f64,
    /// Box edge lengths.
    pub box_lengths: [f64; 3],
    /// Simulated time of production (whole steps).
    pub sim_time: f64,
    /// Simulated time of equilibration (whole steps).
    pub equilibration_time: f64,
    /// Mean kinetic temperature over all degrees of freedom (`3N − 3` translational).
    pub temperature: f64,
    /// Its block-average error (Flyvbjerg–Petersen, as the event-driven engine's).
    pub temperature_error: f64,
    /// Kinetic temperature at the start of production: the bath temperature exactly after a
    /// thermostatted equilibration (its last velocity rescaling), as in the event-driven
    /// engine with `thermostat.rescale_at_end` (default).
    pub temperature_start: f64,
    /// Mean translational temperature.
    pub translational_temperature: f64,
    /// Its block-average error.
    pub translational_temperature_error: f64,
    /// Mean rotational temperature (rods and tops).
    pub rotational_temperature: Option<f64>,
    /// Its block-average error.
    pub rotational_temperature_error: Option<f64>,
    /// Mean virial pressure `(N kT_t + W/3)/V` of the smoothed potential.
    pub pressure: f64,
    /// Its block-average error.
    pub pressure_error: f64,
    /// `pressure` again, under the name the event-driven engine gives its estimate of the
    /// smooth potential's pressure, so that scripts compare one key across engines.
    pub pressure_smooth: f64,
    /// Its block-average error.
    pub pressure_smooth_error: f64,
    /// Compressibility factor `P V / (N kT)`.
    pub compressibility: f64,
    /// Mean potential energy per body.
    pub potential_energy_per_body: f64,
    /// Its block-average error.
    pub potential_energy_per_body_error: f64,
    /// `potential_energy_per_body` again, under the event-driven engine's name for its
    /// estimate of the smooth potential energy.
    pub potential_energy_per_body_smooth: f64,
    /// Its block-average error.
    pub potential_energy_per_body_smooth_error: f64,
    /// Kinetic energy at the end.
    pub energy_kinetic: f64,
    /// Potential energy at the end.
    pub energy_potential: f64,
    /// Total energy at the start of production.
    pub energy_total_start: f64,
    /// Total energy at the end.
    pub energy_total_end: f64,
    /// `|E_end − E_start|` relative to `max(|E_start|, K_start)` (as the event-driven engine).
    pub relative_energy_drift: f64,
    /// Least-squares slope of the total energy per body, per unit time.
    pub energy_drift_per_body: f64,
    /// Standard deviation of the total energy about its least-squares line.
    pub energy_total_std: f64,
    /// That standard deviation over the standard deviation of the potential energy (003 §V.B
    /// reports about 1 % at 1.8 fs for its rods).
    pub energy_fluctuation_over_potential_std: f64,
    /// Wall-clock seconds of production.
    pub wall_seconds: f64,
    /// CPU seconds of production (the thread's; else the wall time).
    pub cpu_seconds: f64,
    /// Time step.
    pub dt: f64,
    /// Steps of production.
    pub steps: u64,
    /// Steps of equilibration.
    pub equilibration_steps: u64,
    /// Steps between velocity rescalings in equilibration (0: NVE equilibration).
    pub rescale_every: u64,
    /// CPU nanoseconds per body per production step (observables included).
    pub ns_per_particle_step: f64,
    /// Neighbour-list builds in production.
    pub neighbour_list_builds: u64,
    /// Mean production steps per neighbour-list build.
    pub steps_per_build: f64,
    /// The Verlet-list skin.
    pub skin: f64,
    /// The smoothing window `[r_l, r_u]` (003 Eq. 26); for a kind with a cut-off of its own
    /// (rigid tops) its own window, from where the cut-off starts to act to where the pair
    /// energy ends.
    pub smoothing: [f64; 2],
    /// Self-diffusion coefficient from the MSD slope (when `output.msd` is on).
    pub diffusion_msd: Option<f64>,
    /// Its error, from the time origins blocked (as the event-driven engine's).
    pub diffusion_msd_error: Option<f64>,
    /// Self-diffusion coefficient from the Green–Kubo VACF integral (when `output.vacf` is on).
    pub diffusion_vacf: Option<f64>,
    /// Its error, as `diffusion_msd_error`.
    pub diffusion_vacf_error: Option<f64>,
    /// The `_error` keys whose blocking found no plateau, as the event-driven engine's.
    pub errors_without_plateau: Vec<String>,
    /// The seed.
    pub seed: u64,
    /// Scene keys this engine ignored (they belong to the event-driven engine).
    pub ignored_keys: Vec<String>,
    /// How the scene's times were rounded to steps, and other mapping notes.
    pub notes: Vec<String>,
    /// Files written besides `summary.json`.
    pub files: Vec<String>,
}

fn smd_error(e: SmdError) -> RunError {
    RunError::Smd(e)
}

/// Runs a scene with `engine = "smd"`; with `out = Some(dir)` writes `summary.json` and the
/// outputs the scene asks for. `base` is the folder relative paths are read from.
///
/// # Errors
/// [`RunError::Scene`] for a scene this engine cannot run (naming the key), [`RunError::Smd`]
/// if the integration fails, [`RunError::Output`] if a file cannot be written.
pub fn run(scene: &Scene, base: &Path, out: Option<&Path>) -> Result<SmdSummary, RunError> {
    run_with(scene, base, out, &mut Quiet)
}

/// [`run`] reporting the phases and their progress to `reporter` (the `dmd` command's
/// progress bar), in simulated time.
///
/// # Errors
/// As [`run`].
pub fn run_with(
    scene: &Scene,
    base: &Path,
    out: Option<&Path>,
    reporter: &mut dyn Reporter,
) -> Result<SmdSummary, RunError> {
    run_named(scene, base, out, reporter, None)
}

/// [`run_with`] for a scene called `name` (its file's stem), which the captions of the plots
/// name.
///
/// # Errors
/// As [`run`].
pub fn run_named(
    scene: &Scene,
    base: &Path,
    out: Option<&Path>,
    reporter: &mut dyn Reporter,
    name: Option<&str>,
) -> Result<SmdSummary, RunError> {
    go(scene, base, out, reporter, name, false)
}

/// Sets a scene with `engine = "smd"` up exactly as [`run`] does (start state, time step,
/// neighbour list, initial forces, outputs' sizes) and stops before the first step: everything
/// `dmd run` refuses before its first step is refused here, with the same error.
///
/// # Errors
/// As [`run`]; never [`RunError::Smd`] from the integration itself.
pub fn check_setup(scene: &Scene, base: &Path) -> Result<(), RunError> {
    match go(scene, base, None, &mut Quiet, None, true) {
        Err(RunError::SetUpOnly) | Ok(_) => Ok(()),
        Err(e) => Err(e),
    }
}

/// [`run_named`]; with `set_up_only`, stops with [`RunError::SetUpOnly`] once the integrator
/// holds the start state and the outputs are sized, before anything is written.
fn go(
    scene: &Scene,
    base: &Path,
    out: Option<&Path>,
    reporter: &mut dyn Reporter,
    name: Option<&str>,
    set_up_only: bool,
) -> Result<SmdSummary, RunError> {
    let units = Units::of(scene.units);
    let ignored = ignored_keys(scene);
    let scene = &scene.internal();
    let mut s = scene.clone();
    s.engine = Engine::Smd;
    check(&s)?;
    let pot = scene.pair[0]
        .potential
        .expect("checked: smd needs a potential");
    let species = &scene.species[0];
    let kt = scene.init.temperature;
    let config = match scene.init.positions {
        Positions::Fcc | Positions::Sc => lattice(scene, 0.0)?,
        Positions::File => read_xyz(
            scene,
            &base.join(scene.init.file.as_ref().expect("checked")),
        )?,
    };
    let n = config.positions.len();
    let spec = scene.smd.clone().unwrap_or_default();
    let (r_l, r_u) = window(scene, &pot);
    let skin = list_skin(&pot, (r_l, r_u), spec.skin, config.lengths)?;
    let dt = spec
        .dt
        .unwrap_or_else(|| default_dt(&pot, species.mass, species.inertia, kt));
    let mut settings = Settings::new(dt, skin);
    if let Some(g) = spec.guard {
        settings.guard = g;
    }
    let mut notes = Vec::new();
    if spec.dt.is_none() {
        notes.push(format!("smd.dt not given: default {dt:.6e}"));
    }
    let steps_of = |key: &str, t: f64, notes: &mut Vec<String>| -> Result<u64, SceneError> {
        let k = (t / dt).round();
        if k < 1.0 && t > 0.0 {
            return Err(SceneError::invalid(
                key,
                format!("{t} is shorter than half the time step smd.dt = {dt}"),
            ));
        }
        let k = k as u64;
        let actual = k as f64 * dt;
        if (actual - t).abs() > 1e-9 * t.abs() {
            notes.push(format!("{key} = {t} rounded to {k} steps = {actual:.6e}"));
        }
        Ok(k)
    };
    let production_steps = steps_of("run.time", scene.run.time.expect("checked"), &mut notes)?;
    let eq_steps = match scene.run.equilibration_time {
        Some(t) => steps_of("run.equilibration_time", t, &mut notes)?,
        None => 0,
    };
    let o = &scene.output;
    let sample_every = match o.sample_interval {
        Some(t) => steps_of("output.sample_interval", t, &mut notes)?,
        None => 0,
    };
    let frame_every = match &o.trajectory {
        Some(tr) if out.is_some() || set_up_only => {
            steps_of("output.trajectory.interval", tr.interval, &mut notes)?
        }
        _ => 0,
    };

    // The event-driven engine's initial state, from the same seed.
    let masses = vec![species.mass; n];
    let rods = pot.is_anisotropic();
    // A start file's own velocities and angular velocities (`init.velocities = "file"`).
    let start_file = base.join(scene.init.file.as_deref().unwrap_or(Path::new("")));
    // The principal moments of each body, for the angular momenta of a GSD file: a rod's
    // two equal ones about its short axes, a top's about its principal axes.
    let moments: Option<[f64; 3]> = if pot.is_rigid() {
        let m = species.moments.expect("checked: tops have moments");
        Some(
            TopInertia::new(DVec3::from(m))
                .map_err(|e| SceneError::invalid("species.moments", e))?
                .principal()
                .to_array(),
        )
    } else if rods {
        let i = species.inertia.expect("checked: rods have inertia");
        Some([i, i, 0.0])
    } else {
        None
    };
    let moments = moments.map(|m| vec![m; n]);
    let motion = match scene.init.velocities {
        Velocities::File => Some(read_motion(
            scene,
            &start_file,
            &masses,
            moments.as_deref(),
        )?),
        Velocities::MaxwellBoltzmann => None,
    };
    let velocities = match &motion {
        Some(m) => m.velocities.clone(),
        None => maxwell_boltzmann(&masses, kt, scene.seed),
    };
    let file_images = motion.as_ref().and_then(|m| m.images.clone());
    let file_omegas = motion.and_then(|m| m.omegas);
    let (body, orientations, ang_mom) = if pot.is_rigid() {
        let moments = species.moments.expect("checked: tops have moments");
        let inertia = TopInertia::new(DVec3::from(moments))
            .map_err(|e| SceneError::invalid("species.moments", e))?;
        let (poses, omegas) = match (file_omegas, scene.init.orientations) {
            (Some(w), _) => (read_attitudes(scene, &start_file, n, "init.velocities")?, w),
            (None, Orientations::File) => {
                let q = read_attitudes(scene, &start_file, n, "init.orientations")?;
                tops_start(scene, &[inertia], &vec![0; n], Some(q))
            }
            (None, _) => tops_start(scene, &[inertia], &vec![0; n], None),
        };
        let principal = inertia.principal();
        // L = R (I ∘ ω_body), with ω_body = R⁻¹ ω.
        let l = poses
            .iter()
            .zip(&omegas)
            .map(|(&q, &w)| q * (principal * (q.inverse() * w)))
            .collect();
        (
            // The body frame is the principal frame the potential reads; its z (the water
            // models' dipole) is the axis the orientational correlations follow, as in the
            // event-driven engine.
            BodyModel::rigid(species.mass, principal.to_array(), DVec3::Z).map_err(smd_error)?,
            smd::Orientations::Rotations(poses.iter().map(|&q| DMat3::from_quat(q)).collect()),
            l,
        )
    } else if rods {
        let inertia = species.inertia.expect("checked: rods have inertia");
        let axes = match scene.init.orientations {
            Orientations::Random => random_axes(n, scene.seed),
            Orientations::Aligned => {
                vec![DVec3::from(scene.init.axis.expect("checked")).normalize(); n]
            }
            Orientations::File => read_orientations(scene, &start_file, n)?,
        };
        let omegas = match file_omegas {
            // A linear rotor spins about no axis but its short ones.
            Some(w) => rotor_omegas(scene, &w, &axes)?,
            None => equipartitioned_omegas(&axes, &vec![inertia; n], kt, scene.seed),
        };
        let l = omegas.iter().map(|w| *w * inertia).collect();
        (
            BodyModel::linear_rotor(species.mass, inertia).map_err(smd_error)?,
            smd::Orientations::Axes(axes),
            l,
        )
    } else {
        (
            BodyModel::sphere(species.mass).map_err(smd_error)?,
            smd::Orientations::None,
            Vec::new(),
        )
    };
    let mut system = System::from_parts(
        config.lengths,
        body,
        config.positions.clone(),
        velocities,
        orientations,
        ang_mom,
    )
    .map_err(smd_error)?;
    // smd wraps the file's positions itself, counting the crossing in the images.
    if let Some(images) = file_images {
        system.set_images(&images).map_err(smd_error)?;
    }
    if let Some(dir) = out.filter(|_| !set_up_only) {
        std::fs::create_dir_all(dir).map_err(|e| OutputError {
            path: dir.to_owned(),
            message: e.to_string(),
        })?;
    }
    let job = Job {
        scene,
        config: &config,
        units,
        out,
        settings,
        window: (r_l, r_u),
        eq_steps,
        production_steps,
        sample_every,
        frame_every,
        ignored,
        notes,
        reporter,
        name: name.map(str::to_owned),
        set_up_only,
    };
    pot.visit(SmdGo { job, system })
}

/// Runs a job on kind `K`'s force field: the force loop is compiled for each kind.
struct SmdGo<'a> {
    job: Job<'a>,
    system: System,
}

impl Visit for SmdGo<'_> {
    type Out = Result<SmdSummary, RunError>;

    fn visit<K: Kind>(self, kind: &K) -> Self::Out {
        let field = kind.smd(self.job.window)?;
        let model = format!("smd-{}", kind.name());
        self.job.integrate(self.system, field, &model)
    }
}

struct Job<'a> {
    scene: &'a Scene,
    config: &'a Configuration,
    units: Units,
    out: Option<&'a Path>,
    settings: Settings,
    window: (f64, f64),
    eq_steps: u64,
    production_steps: u64,
    sample_every: u64,
    frame_every: u64,
    ignored: Vec<String>,
    notes: Vec<String>,
    reporter: &'a mut dyn Reporter,
    /// The scene's name, for the plots' captions.
    name: Option<String>,
    /// Stop with [`RunError::SetUpOnly`] before the first step (`dmd check`).
    set_up_only: bool,
}

/// Progress reports per phase (and equilibration chunks).
const REPORTS: u64 = 200;

impl Job<'_> {
    fn integrate<F: Interaction>(
        mut self,
        system: System,
        pot: F,
        model: &str,
    ) -> Result<SmdSummary, RunError> {
        let scene = self.scene;
        let n = system.n();
        let mut md = Integrator::new(system, pot, self.settings).map_err(|e| match e {
            SmdError::Overlap { i, j, source, .. } => RunError::Scene(SceneError::invalid(
                match scene.init.positions {
                    Positions::File => "init.file",
                    _ => "box.density",
                },
                format!(
                    "bodies {i} and {j} start without a finite force ({source}): the initial \
                     configuration overlaps"
                ),
            )),
            e => smd_error(e),
        })?;

        // The outputs' sizes are refused before any step is taken.
        let half = 0.5 * self.config.lengths.min_element();
        let rdf_r_max = scene
            .output
            .rdf
            .as_ref()
            .map_or(half, |rdf| rdf.r_max.unwrap_or(half.min(5.0)));
        if rdf_r_max > half {
            return Err(SceneError::invalid(
                "output.rdf.r_max",
                format!("{rdf_r_max} exceeds half the smallest box side ({half})"),
            )
            .into());
        }
        if self.set_up_only {
            return Err(RunError::SetUpOnly);
        }

        // Equilibration: velocity rescaling in place of the Andersen thermostat, else NVE.
        let t = &scene.thermostat;
        let mut rescale_every = 0;
        let dt = self.settings.dt;
        let u = self.units;
        let lengths = self.config.lengths;
        let mut phases = Vec::new();
        if self.eq_steps > 0 {
            phases.push(("equilibration", Stop::Time(self.eq_steps as f64 * dt)));
        }
        phases.push(("production", Stop::Time(self.production_steps as f64 * dt)));
        self.reporter.start(&RunPlan {
            engine: "smd",
            model: model.to_owned(),
            species: scene
                .species
                .iter()
                .map(|s| (s.name.clone(), s.count))
                .collect(),
            n_bodies: n as u64,
            density: n as f64 / (lengths.x * lengths.y * lengths.z),
            box_lengths: lengths.to_array(),
            temperature: u.temperature_out(scene.init.temperature),
            thermostat: (t.kind == ThermostatKind::Andersen && self.eq_steps > 0).then(|| {
                (
                    u.temperature_out(t.temperature.unwrap_or(scene.init.temperature)),
                    "equilibration",
                )
            }),
            units: scene.units,
            phases,
            dt: Some(dt),
            resumed_in: None,
        });
        if self.eq_steps > 0 {
            let bath = (t.kind == ThermostatKind::Andersen).then(|| {
                let rate = t.rate.expect("checked: andersen has a rate");
                rescale_every = ((1.0 / (rate * dt)).round() as u64).max(1);
                t.temperature.unwrap_or(scene.init.temperature)
            });
            // In chunks for the progress report; a chunk is a whole number of rescaling
            // intervals, so the rescalings fall where one call would put them (the extra one
            // at a chunk's start repeats the previous chunk's last: a factor 1 up to round-off).
            let unit = rescale_every.max(1);
            let chunk = (self.eq_steps / REPORTS).div_ceil(unit).max(1) * unit;
            self.reporter
                .phase("equilibration", Stop::Time(self.eq_steps as f64 * dt));
            let mut done = 0;
            while done < self.eq_steps {
                let k = chunk.min(self.eq_steps - done);
                match bath {
                    Some(kt) => md.equilibrate(k, rescale_every, kt),
                    None => md.run(k, k, &mut ()),
                }
                .map_err(smd_error)?;
                done += k;
                self.reporter.progress(Progress {
                    events: done,
                    elapsed: done as f64 * dt,
                });
            }
            self.reporter.done();
            self.reporter.equilibrated(PhaseEnd {
                events: self.eq_steps,
                elapsed: self.eq_steps as f64 * dt,
                temperature: u.temperature_out(md.snapshot().temperature()),
            });
            if bath.is_some() {
                self.notes.push(format!(
                    "equilibration: velocity rescaling every {rescale_every} steps (1/rate) in \
                     place of the Andersen thermostat"
                ));
            }
        }

        // Production, NVE.
        let o = &scene.output;
        let mut observers = Observers::default();
        let lengths = self.config.lengths;
        if let Some(rdf) = &o.rdf {
            let g = Rdf::new(rdf.bins as usize, rdf_r_max, rdf.every);
            // One species: the sites of the potential's kind, as the event-driven engine's
            // plan gives them.
            let sites = scene.pair[0]
                .potential
                .as_ref()
                .and_then(|p| p.describe().sites());
            observers.rdf = Some(match sites {
                Some(s) => g.with_sites(vec![s]),
                None => g,
            });
        }
        let interval = self.sample_every as f64 * self.settings.dt;
        if o.msd.is_some() || o.vacf.is_some() || o.orientation_acf.is_some() {
            let lag = o
                .msd
                .iter()
                .chain(o.vacf.iter())
                .chain(o.orientation_acf.iter())
                .map(|c| c.max_lag)
                .fold(0.0, f64::max);
            observers.correlations = Some(Correlations::with_orientations(
                interval,
                lag,
                o.msd.is_some(),
                o.vacf.is_some(),
                o.orientation_acf.is_some(),
            ));
        }
        if o.series {
            observers.series = Some(match self.out {
                Some(dir) => Series::streamed(&dir.join("series.csv"), self.units.series())?,
                None => Series::default(),
            });
        }
        if let (Some(_), Some(dir)) = (&o.trajectory, self.out) {
            // Drawn as the event-driven engine draws the same scene.
            let names: Vec<String> = scene.species.iter().map(|s| s.name.clone()).collect();
            let sp = &scene.species[0];
            let pot = scene.pair[0].potential.as_ref();
            let (drawing, moments) = match md.system().body() {
                BodyModel::Rigid { .. } => {
                    let (centres, diameters) = crate::config::rods::water_drawing();
                    // As the model takes them (a rounded planar body made planar).
                    let moments = sp.moments.map_or([0.0; 3], |m| {
                        TopInertia::new(DVec3::from(m)).map_or(m, |t| t.principal().to_array())
                    });
                    (Drawing::Sites { centres, diameters }, vec![moments])
                }
                _ if sp.inertia.is_some() => {
                    let i = sp.inertia.unwrap_or(0.0);
                    let semi_axes = pot.and_then(rod_semi_axes).unwrap_or([0.5; 3]);
                    (Drawing::Rod { semi_axes }, vec![[i, i, 0.0]])
                }
                _ => {
                    let sigma = pot.map_or(1.0, |p| p.describe().lengths().0);
                    (Drawing::Sphere { diameter: sigma }, Vec::new())
                }
            };
            let mut layout = Layout::new(names, vec![drawing]);
            layout.elements = vec![element_of(&sp.name, sp.element.as_deref())];
            layout.moments = moments;
            layout.momentum_unit = ase_momentum_unit(scene.units);
            observers.trajectory = Some(Trajectory::create(&dir.join("trajectory.xyz"), layout)?);
        }
        // About 10⁴ rows of the energy series for the summary's means, drift and fluctuation.
        let stride = (self.production_steps / 10_000).max(1);
        let mut bridge = Bridge {
            observers,
            sample_every: self.sample_every,
            frame_every: self.frame_every,
            stride,
            mass: [scene.species[0].mass],
            steps: 0,
            t0: md.time(),
            last: None,
            virial_integral: 0.0,
            kinetic_integral: 0.0,
            rows: Vec::new(),
            bodies: Vec::new(),
            images: Vec::new(),
            reporter: &mut *self.reporter,
            report_every: (self.production_steps / REPORTS).max(1),
            dt,
        };
        bridge
            .reporter
            .phase("production", Stop::Time(self.production_steps as f64 * dt));
        let e0 = md.energy();
        let kt_start = md.snapshot().temperature();
        let wall = std::time::Instant::now();
        let cpu0 = thread_cpu_seconds();
        // Sampled every step: the series pressure averages the virial over each sampling
        // interval, as the event-driven engine's does, and needs the virial of every step.
        let stats = md
            .run(self.production_steps, 1, &mut bridge)
            .map_err(smd_error)?;
        bridge.reporter.done();
        let wall_seconds = wall.elapsed().as_secs_f64();
        let cpu_seconds = match (cpu0, thread_cpu_seconds()) {
            (Some(a), Some(b)) => b - a,
            _ => wall_seconds,
        };

        // Summary.
        let u = self.units;
        let sm = smd::observe::Summary::of(&bridge.rows, n);
        // The errors by the event-driven engine's blocking, so that the engines' error bars
        // mean the same; the keys of those without a plateau are listed.
        let mut without_plateau: Vec<String> = Vec::new();
        let mut blocked_by = |key: &str, x: Vec<f64>| {
            let b = crate::analysis::block::block_average(&x);
            if !b.converged {
                without_plateau.push(key.to_owned());
            }
            b.error
        };
        let nb = n as f64;
        let column = |f: fn(&smd::observe::SeriesRow) -> f64| -> Vec<f64> {
            bridge.rows.iter().map(f).collect()
        };
        let temperature_error = blocked_by("temperature_error", column(|r| r.temperature));
        let translational_error = blocked_by(
            "translational_temperature_error",
            column(|r| r.temperature_translational),
        );
        let potential_error = u.energy_out(blocked_by(
            "potential_energy_per_body_error",
            bridge.rows.iter().map(|r| r.potential / nb).collect(),
        ));
        let pressure_error = u.pressure_out(blocked_by("pressure_error", column(|r| r.pressure)));
        let s = md.system();
        let nf = n as f64;
        let volume = s.volume();
        let e1 = md.energy();
        let rot_dof = s.dof_rotational();
        let mean_t_rot = if rot_dof > 0.0 {
            let dof = s.dof_translational() + rot_dof;
            Some(
                (sm.temperature.mean * dof
                    - sm.temperature_translational.mean * s.dof_translational())
                    / rot_dof,
            )
        } else {
            None
        };
        let rot_error = (rot_dof > 0.0).then(|| {
            let (dof_t, dof) = (s.dof_translational(), s.dof_translational() + rot_dof);
            let t_rot: Vec<f64> = bridge
                .rows
                .iter()
                .map(|r| (r.temperature * dof - r.temperature_translational * dof_t) / rot_dof)
                .collect();
            u.temperature_out(blocked_by("rotational_temperature_error", t_rot))
        });
        let mut observers = bridge.observers;
        let diffusion = Correlations::diffusions(observers.correlations.as_ref());
        let mut summary = SmdSummary {
            engine: "smd".to_owned(),
            model: model.to_owned(),
            units: match scene.units {
                UnitSystem::Reduced => "reduced",
                UnitSystem::Molecular => "molecular",
            }
            .to_owned(),
            n_bodies: n as u64,
            density: nf / volume,
            box_lengths: lengths.to_array(),
            sim_time: stats.simulated_time,
            equilibration_time: self.eq_steps as f64 * self.settings.dt,
            temperature: u.temperature_out(sm.temperature.mean),
            temperature_error: u.temperature_out(temperature_error),
            temperature_start: u.temperature_out(kt_start),
            translational_temperature: u.temperature_out(sm.temperature_translational.mean),
            translational_temperature_error: u.temperature_out(translational_error),
            rotational_temperature: mean_t_rot.map(|t| u.temperature_out(t)),
            rotational_temperature_error: rot_error,
            pressure: u.pressure_out(sm.pressure.mean),
            pressure_error,
            pressure_smooth: u.pressure_out(sm.pressure.mean),
            pressure_smooth_error: pressure_error,
            compressibility: sm.pressure.mean * volume / (nf * sm.temperature.mean),
            potential_energy_per_body: u.energy_out(sm.potential_per_body.mean),
            potential_energy_per_body_error: potential_error,
            potential_energy_per_body_smooth: u.energy_out(sm.potential_per_body.mean),
            potential_energy_per_body_smooth_error: potential_error,
            energy_kinetic: u.energy_out(e1.kinetic()),
            energy_potential: u.energy_out(e1.potential),
            energy_total_start: u.energy_out(e0.total()),
            energy_total_end: u.energy_out(e1.total()),
            relative_energy_drift: (e1.total() - e0.total()).abs()
                / e0.total().abs().max(e0.kinetic()),
            energy_drift_per_body: u.energy_out(sm.drift_per_body),
            energy_total_std: u.energy_out(sm.total_detrended_std),
            energy_fluctuation_over_potential_std: sm.fluctuation_over_potential_std,
            wall_seconds,
            cpu_seconds,
            dt: self.settings.dt,
            steps: stats.steps,
            equilibration_steps: self.eq_steps,
            rescale_every,
            ns_per_particle_step: cpu_seconds * 1e9 / (nf * stats.steps.max(1) as f64),
            neighbour_list_builds: stats.builds,
            steps_per_build: stats.steps_per_build(),
            skin: self.settings.skin,
            smoothing: [self.window.0, self.window.1],
            diffusion_msd: diffusion.msd,
            diffusion_vacf: diffusion.vacf,
            diffusion_msd_error: diffusion.msd_error,
            diffusion_vacf_error: diffusion.vacf_error,
            errors_without_plateau: without_plateau
                .into_iter()
                .chain(diffusion.without_plateau.iter().map(|k| (*k).to_owned()))
                .collect(),
            seed: scene.seed,
            ignored_keys: self.ignored,
            notes: self.notes,
            files: Vec::new(),
        };
        if let Some(dir) = self.out {
            let info = crate::driver::reporting::PlotInfo {
                scene: self.name.clone(),
                n: summary.n_bodies,
                temperature: summary.temperature,
                density: summary.density,
                terrace_step: None,
                species: scene.species.iter().map(|s| s.name.clone()).collect(),
                pressure: (summary.pressure, Some(summary.pressure_error)),
                potential_per_body: (
                    summary.potential_energy_per_body,
                    Some(summary.potential_energy_per_body_error),
                ),
            };
            summary.files = crate::driver::reporting::write_observables(
                dir,
                &mut observers,
                o.plots,
                &self.units,
                &info,
            )?;
            let json = serde_json::to_string_pretty(&summary).expect("a summary serialises");
            write_atomically(&dir.join("summary.json"), json.as_bytes())?;
        }
        Ok(summary)
    }
}

/// Feeds the event-driven engine's observers from the integrator: a [`View`] of the state at
/// every sample, with the virial and kinetic energy integrated over time as the event-driven
/// engine accumulates them.
struct Bridge<'r> {
    observers: Observers,
    sample_every: u64,
    frame_every: u64,
    stride: u64,
    mass: [f64; 1],
    steps: u64,
    t0: f64,
    /// Time, virial and kinetic energy of the previous step.
    last: Option<(f64, f64, f64)>,
    virial_integral: f64,
    kinetic_integral: f64,
    rows: Vec<smd::observe::SeriesRow>,
    bodies: Vec<Body>,
    images: Vec<[i32; 3]>,
    reporter: &'r mut dyn Reporter,
    report_every: u64,
    dt: f64,
}

impl Bridge<'_> {
    fn view<'a>(&'a mut self, s: &Snapshot<'_>) -> View<'a> {
        let sys = s.system;
        let elapsed = s.time - self.t0;
        self.bodies.clear();
        self.images.clear();
        for (i, (&r, &v)) in sys.positions().iter().zip(sys.velocities()).enumerate() {
            self.bodies.push(Body {
                r,
                t: elapsed,
                v,
                species: 0,
                generation: 0,
            });
            // The integral image counters of smd: unwrapped = r + image ∘ L.
            let im = (sys.unwrapped(i) - r) / sys.lengths();
            self.images.push([
                im.x.round() as i32,
                im.y.round() as i32,
                im.z.round() as i32,
            ]);
        }
        View {
            now: elapsed,
            elapsed,
            bodies: &self.bodies,
            images: &self.images,
            lengths: sys.lengths(),
            masses: &self.mass,
            kinetic: s.energy.kinetic(),
            potential: s.energy.potential,
            virial: self.virial_integral,
            kinetic_integral: self.kinetic_integral,
            dof: sys.dof_translational() + sys.dof_rotational(),
            axes: sys.axes().to_vec(),
            rotational_kinetic: s.energy.kinetic_rotational,
            rotational_dof: sys.dof_rotational(),
            events: self.steps,
            attitudes: Vec::new(),
            spins: Vec::new(),
            atoms: Vec::new(),
        }
    }
}

/// The bodies' attitudes: tops' own; rods' as the terraced model gives them (body z along the
/// axis `axes`), so that both engines write the same orientation column.
fn attitudes_of(s: &Snapshot<'_>, axes: &[DVec3]) -> Vec<DQuat> {
    if s.system.orientations().is_empty() {
        axes.iter().map(|&a| axis_quaternion(a)).collect()
    } else {
        s.system
            .orientations()
            .iter()
            .map(|r| DQuat::from_mat3(r).normalize())
            .collect()
    }
}

impl Observer for Bridge<'_> {
    fn sample(&mut self, s: &Snapshot<'_>) {
        // Trapezoids of ∫W dt and ∫K dt: the event-driven engine's Σ r·Δp is ∫W dt.
        let (w, k) = (s.energy.virial, s.energy.kinetic());
        if let Some((t, w0, k0)) = self.last {
            let h = s.time - t;
            self.virial_integral += 0.5 * (w + w0) * h;
            self.kinetic_integral += 0.5 * (k + k0) * h;
        }
        self.last = Some((s.time, w, k));
        let step = self.steps;
        self.steps += 1;
        if step > 0 && step.is_multiple_of(self.report_every) {
            self.reporter.progress(Progress {
                events: step,
                elapsed: step as f64 * self.dt,
            });
        }
        if step.is_multiple_of(self.stride) {
            self.rows.push(smd::observe::SeriesRow::of(s));
        }
        let sample = self.sample_every > 0 && step.is_multiple_of(self.sample_every);
        let frame = self.frame_every > 0 && step.is_multiple_of(self.frame_every);
        if sample || frame {
            let mut observers = std::mem::take(&mut self.observers);
            let mut view = self.view(s);
            if sample {
                // The site–site g(r) places the sites by the attitudes.
                if observers.rdf.as_ref().is_some_and(Rdf::needs_attitudes) {
                    view.attitudes = attitudes_of(s, &view.axes);
                }
                observers.sample(&view);
            }
            if frame {
                let attitudes = if view.attitudes.is_empty() {
                    attitudes_of(s, &view.axes)
                } else {
                    std::mem::take(&mut view.attitudes)
                };
                let spins = s.system.angular_momenta().to_vec();
                observers.frame(
                    0,
                    &View {
                        attitudes,
                        spins,
                        ..view
                    },
                );
            }
            self.observers = observers;
        }
    }
}
