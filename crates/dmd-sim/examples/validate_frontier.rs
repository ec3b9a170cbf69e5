//! `cargo xtask frontier` (= `cargo xtask validate --only frontier`): the error-against-cost
//! frontier of event-driven MD (DMD, terraced potential) and standard MD (SMD, smoothed
//! continuous potential) on the paper's rods (003 §V.B).
//!
//! Prints a Markdown report on stdout and exits non-zero if a check fails. `--quick` runs the
//! reduced CI subset; `--figures DIR` is where the SVG figures go.
//!
//! Four state points: the paper's dense fluid (ρ* = 0.5, T* = 1.4) and its gas (ρ* = 0.01,
//! T* = 10), N = 512, and water, SSD/E (`scenes/water-ssd.toml`) and SPC/E
//! (`scenes/water-spce.toml`), 512 rigid asymmetric tops each, every run from one frame of SMD
//! (their terraced equilibration from a lattice would cost hours); `--case
//! dense|gas|water|spce` runs one. At each: DMD at several ΔV with the paper's levels and, at one ΔV, other
//! level distributions (placement, terrace energies, outermost level); SMD at several time
//! steps; all against an SMD reference at a small step, whose own noise is measured by further
//! reference runs with other seeds. Observables: potential energy per body, pressure,
//! self-diffusion coefficient (MSD slope) and g(r). Cost: CPU seconds per simulated ps of
//! production, `cpu_seconds / sim_time` of the run's summary, the same measure for both
//! engines (thread CPU time of production, with the same observables sampled at the same
//! interval). Runs go two at a time (the machine has two cores); the measure is per thread.

use std::fmt::Write as _;
use std::path::Path;
use std::process::ExitCode;

use dmd_sim::run::Summary;
use dmd_sim::scene::Scene;
use dmd_sim::smd_engine::{self, SmdSummary};
use rayon::prelude::*;

mod common;
use common::{
    Args, Bound, PAPER, Report, Series, bound_mark, csv, draw_panel, gas_overrides,
    integrated_difference, kt_label, matched_cost, matched_ratio, ratio, scene_run,
};

/// SSD/E water (Fennell and Gezelter 2004), 512 molecules at 298.15 K and 0.997 g/cm³.
const WATER: &str = include_str!("../../../scenes/water-ssd.toml");
/// SPC/E water (three sites, damped shifted force Coulomb), 1000 molecules at the same state.
const SPCE: &str = include_str!("../../../scenes/water-spce.toml");
/// Grid spacing of the verification runs (ps): every search interval searched again.
const VERIFY_STEP: f64 = 0.0002;
/// Largest relative energy drift of a DMD production run of the rods (their energy is
/// conserved to round-off: the loop's sums are compensated).
const DRIFT_MAX: f64 = 1e-12;
/// The same in water, the bound for it: at kT/16 its 512 molecules make 7·10⁶ pair
/// events per ps, each adding its round-off (1.3·10⁻¹² measured over 1.3 ps).
const DRIFT_MAX_WATER: f64 = 1e-10;
/// How many noise levels the comparison SMD run may be from the reference.
const SANITY: f64 = 5.0;
/// The gas's SMD step: the largest with detrended std(E)/std(U) at most this.
const FLUCTUATION_MAX: f64 = 0.01;

/// The observables whose errors are measured, with their units.
const OBSERVABLES: [(&str, &str); 4] = [
    ("U/N", "kJ/mol"),
    ("P", "bar"),
    ("D", "Å²/ps"),
    ("g(r)", "Å"),
];

fn main() -> ExitCode {
    common::main_of("validate_frontier", validate)
}

// ---- What is run ------------------------------------------------------------------------------

/// A terrace-level distribution at one ΔV (`pair.0.terraces`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Levels {
    /// ΔV / kT.
    step_kt: f64,
    placement: &'static str,
    energy: &'static str,
    /// The outermost level (kJ/mol); `None`: the paper's −ΔV/2.
    outermost: Option<f64>,
}

impl Levels {
    /// The paper's levels `U_k = (k − ½)ΔV` with equal steps.
    const fn paper(step_kt: f64) -> Self {
        Levels {
            step_kt,
            placement: "equal-energy",
            energy: "equal",
            outermost: None,
        }
    }

    const fn rule(step_kt: f64, placement: &'static str, energy: &'static str) -> Self {
        Levels {
            step_kt,
            placement,
            energy,
            outermost: None,
        }
    }

    fn is_paper(&self) -> bool {
        self.placement == "equal-energy" && self.energy == "equal" && self.outermost.is_none()
    }

    fn label(&self) -> String {
        let mut parts = vec![format!("ΔV = {}", kt_label(self.step_kt))];
        if self.placement != "equal-energy" {
            parts.push(self.placement.to_owned());
        }
        if self.energy != "equal" {
            parts.push(format!("{} energies", self.energy));
        }
        if let Some(x) = self.outermost {
            parts.push(format!("outermost {x} kJ/mol"));
        }
        parts.join(", ")
    }

    /// Short text beside the point in the plot.
    fn tag(&self) -> String {
        if self.is_paper() {
            return kt_label(self.step_kt);
        }
        let mut parts = Vec::new();
        match self.placement {
            "equal-distance" => parts.push("dist"),
            "equal-volume" => parts.push("vol"),
            _ => {}
        }
        match self.energy {
            "midpoint" => parts.push("mid"),
            "virial" => parts.push("vir"),
            "volume-average" => parts.push("vavg"),
            _ => {}
        }
        if self.outermost.is_some() {
            parts.push("out");
        }
        parts.join("+")
    }

    fn overrides(&self) -> Vec<String> {
        let mut o = vec![format!("pair.0.terraces.step_kt={}", self.step_kt)];
        // The rules are keys of the uniaxial potentials' terraces only: the paper's levels are
        // the default, so they are left unsaid (a rigid top's terraces refuse the keys).
        if self.placement != "equal-energy" {
            o.push(format!("pair.0.terraces.placement={}", self.placement));
        }
        if self.energy != "equal" {
            o.push(format!("pair.0.terraces.step_energy={}", self.energy));
        }
        if let Some(x) = self.outermost {
            o.push(format!("pair.0.terraces.outermost={x}"));
        }
        o
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Setting {
    Dmd(Levels),
    /// dt in fs.
    Smd(f64),
}

impl Setting {
    fn engine(self) -> &'static str {
        match self {
            Setting::Dmd(_) => "DMD",
            Setting::Smd(_) => "SMD",
        }
    }

    fn label(self) -> String {
        match self {
            Setting::Dmd(l) => l.label(),
            Setting::Smd(dt) => format!("dt = {dt} fs"),
        }
    }

    fn tag(self) -> String {
        match self {
            Setting::Dmd(l) => l.tag(),
            Setting::Smd(dt) => format!("{dt} fs"),
        }
    }

    /// A guess of the CPU seconds per ps at the dense state, to start the dearest runs first.
    fn guess(self) -> f64 {
        match self {
            Setting::Dmd(l) => {
                let rule = if l.is_paper() { 1.0 } else { 2.5 };
                rule * 0.3 * (0.5 / l.step_kt).powf(1.3)
            }
            Setting::Smd(dt) => 0.35 * 0.9 / dt,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    /// The reference: SMD at the smallest step.
    Reference,
    /// Another seed of the reference's setting: its noise.
    Twin,
    /// A run on the frontier.
    Run,
    /// DMD's own seed-to-seed difference (another seed of a DMD run).
    Repeat,
    /// A short DMD run whose searches are checked on a fine grid (not timed).
    Verify,
}

/// Which SMD run the DMD runs are held against.
#[derive(Clone, Copy, Debug)]
enum Comparator {
    /// This step (fs), and why it: the paper's 1.8 fs at the dense state.
    Step(f64, &'static str),
    /// The largest step with detrended std(E)/std(U) at most [`FLUCTUATION_MAX`].
    Fluctuation,
}

/// One state point and what runs at it.
#[derive(Clone)]
struct StatePoint {
    key: &'static str,
    title: &'static str,
    /// The title of the plot panels.
    short: &'static str,
    /// The scene (TOML text) every run starts from.
    scene: &'static str,
    /// Scene overrides of the state (the gas's temperature and density).
    overrides: Vec<String>,
    /// Where the runs start: `None`, each from its own lattice; `Some(ps)`, every run from
    /// one frame of SMD equilibrated this long from the lattice, with velocities and angular
    /// velocities drawn from its own seed (for systems whose terraced equilibration from a
    /// lattice would cost hours, such as water).
    start_ps: Option<f64>,
    /// Overrides of the DMD runs' equilibration only (a stronger thermostat where the
    /// terraces take over a smooth-potential frame and release heat).
    dmd_equilibration: Vec<String>,
    eq_ps: f64,
    ps: f64,
    /// Sampling interval (ps), a multiple of every SMD step.
    sample_ps: f64,
    msd_lag_ps: f64,
    rdf_bins: usize,
    rdf_max: f64,
    rdf_every: u32,
    /// SMD's Verlet skin (Å); `None`: the engine's default.
    skin: Option<f64>,
    ref_dt: f64,
    /// Reference runs besides the reference itself.
    twins: usize,
    dts: Vec<f64>,
    dmd: Vec<Levels>,
    repeat: Option<Levels>,
    /// Equilibration and production (ps) of the verification runs.
    verify_ps: (f64, f64),
    /// Grid spacing of the verification runs (ps).
    verify_step: f64,
    /// Largest relative energy drift of a DMD run.
    drift_max: f64,
    comparator: Comparator,
    /// The ΔV / kT of the efficiency-ratio line, and what the paper says of it (empty: none).
    ratio_steps: Vec<f64>,
    ratio_note: &'static str,
}

impl StatePoint {
    fn dense(quick: bool) -> Self {
        let half = 0.5;
        let dmd = if quick {
            vec![
                Levels::paper(1.0),
                Levels::paper(half),
                Levels::rule(half, "equal-distance", "equal"),
            ]
        } else {
            vec![
                Levels::paper(2.0),
                Levels::paper(1.0),
                Levels::paper(half),
                Levels::paper(0.25),
                Levels::rule(half, "equal-distance", "equal"),
                Levels::rule(half, "equal-volume", "equal"),
                Levels::rule(half, "equal-energy", "midpoint"),
                Levels::rule(half, "equal-energy", "virial"),
                Levels {
                    outermost: Some(-0.1),
                    ..Levels::rule(half, "equal-energy", "virial")
                },
                Levels::rule(0.25, "equal-distance", "equal"),
            ]
        };
        StatePoint {
            key: "dense",
            title: "Dense fluid: ρ* = 0.5, T* = 1.4",
            short: "Dense rods",
            scene: PAPER,
            overrides: Vec::new(),
            start_ps: None,
            dmd_equilibration: Vec::new(),
            eq_ps: if quick { 1.5 } else { 10.0 },
            ps: if quick { 3.0 } else { 40.0 },
            sample_ps: 0.0072,
            msd_lag_ps: if quick { 1.0 } else { 4.0 },
            rdf_bins: 120,
            rdf_max: 12.0,
            rdf_every: 5,
            skin: Some(2.0),
            ref_dt: 0.45,
            twins: if quick { 3 } else { 4 },
            dts: if quick {
                vec![1.8, 0.9]
            } else {
                vec![3.6, 1.8, 0.9]
            },
            dmd,
            repeat: (!quick).then_some(Levels::paper(half)),
            verify_ps: if quick { (0.5, 0.1) } else { (2.0, 1.0) },
            verify_step: VERIFY_STEP,
            drift_max: DRIFT_MAX,
            comparator: Comparator::Step(1.8, "the paper's step"),
            ratio_steps: vec![half, 1.0],
            ratio_note: "003 §V.B: ≈ 1.7 at ΔV = kT … 2kT and 1.25 at kT/2",
        }
    }

    fn gas(quick: bool) -> Self {
        let dmd = if quick {
            vec![Levels::paper(0.5), Levels::paper(0.125)]
        } else {
            vec![
                Levels::paper(0.5),
                Levels::paper(0.25),
                Levels::paper(0.125),
                Levels::paper(0.0625),
                Levels::rule(0.125, "equal-distance", "equal"),
                Levels::rule(0.125, "equal-energy", "virial"),
                Levels {
                    outermost: Some(-0.1),
                    ..Levels::rule(0.125, "equal-energy", "virial")
                },
            ]
        };
        StatePoint {
            key: "gas",
            title: "Gas: ρ* = 0.01, T* = 10",
            short: "Gas",
            scene: PAPER,
            // The search defaults scale with the thermal speed: the paper's 4 fs at T* = 1.4,
            // 1.26 fs at T* = 10. With the paper's 4 fs kept in the gas, ΔV = kT/16 missed
            // events (2 detected in 400 ps, 1–2 verified in 10 ps).
            overrides: [
                gas_overrides(),
                vec!["search.max_step=".to_owned(), "search.window=".to_owned()],
            ]
            .concat(),
            start_ps: None,
            dmd_equilibration: Vec::new(),
            eq_ps: if quick { 5.0 } else { 20.0 },
            ps: if quick { 30.0 } else { 400.0 },
            sample_ps: 0.036,
            msd_lag_ps: if quick { 8.0 } else { 40.0 },
            rdf_bins: 150,
            rdf_max: 15.0,
            rdf_every: 1,
            skin: Some(4.0),
            ref_dt: 0.225,
            twins: if quick { 2 } else { 4 },
            dts: if quick {
                vec![0.9, 0.45]
            } else {
                vec![1.8, 0.9, 0.45]
            },
            dmd,
            repeat: None,
            verify_ps: if quick { (1.0, 1.0) } else { (5.0, 10.0) },
            verify_step: VERIFY_STEP,
            drift_max: DRIFT_MAX,
            comparator: Comparator::Fluctuation,
            ratio_steps: vec![0.5, 0.125],
            ratio_note: "003 §V.B: > 120 in the gas",
        }
    }

    fn water(quick: bool) -> Self {
        let dmd = if quick {
            vec![Levels::paper(0.5)]
        } else {
            vec![
                Levels::paper(0.5),
                Levels::paper(0.25),
                Levels::paper(0.125),
                Levels::paper(0.0625),
            ]
        };
        StatePoint {
            key: "water",
            title: "SSD/E water: 512 molecules, 298.15 K, 0.997 g/cm³",
            short: "SSD/E water",
            scene: WATER,
            overrides: Vec::new(),
            start_ps: Some(if quick { 2.0 } else { 10.0 }),
            // The terraced landscape releases heat as it takes over the smooth frame
            // (docs/VALIDATION.md, SSD/E): a thermostat ten times the scene's removes it.
            dmd_equilibration: vec!["thermostat.rate=20".to_owned()],
            eq_ps: if quick { 0.05 } else { 0.3 },
            ps: if quick { 0.1 } else { 1.0 },
            sample_ps: 0.004,
            msd_lag_ps: if quick { 0.05 } else { 0.5 },
            rdf_bins: 200,
            rdf_max: 10.0,
            rdf_every: 4,
            skin: None,
            ref_dt: 0.5,
            // Five reference runs in the quick check too: three set too narrow a noise.
            twins: 4,
            dts: if quick {
                vec![2.0]
            } else {
                vec![4.0, 2.0, 1.0]
            },
            dmd,
            repeat: None,
            // The grid of the water sections of docs/VALIDATION.md: 0.02 fs.
            verify_ps: if quick {
                (0.001, 0.002)
            } else {
                (0.002, 0.004)
            },
            verify_step: 2e-5,
            drift_max: DRIFT_MAX_WATER,
            comparator: Comparator::Step(2.0, "the scene's step"),
            ratio_steps: vec![0.5, 0.25, 0.125, 0.0625],
            ratio_note: "",
        }
    }

    /// SPC/E water at SSD/E's state point, 512 molecules (the scene's 1000 cost twice as much
    /// per ps).
    fn spce(quick: bool) -> Self {
        let dmd = if quick {
            vec![Levels::paper(0.5)]
        } else {
            vec![Levels::paper(0.5), Levels::paper(0.25)]
        };
        // SSD/E's protocol (start frame, thermostat, sampling, SMD steps, verification grid),
        // shorter runs.
        StatePoint {
            key: "spce",
            title: "SPC/E water: 512 molecules, 298.15 K, 0.997 g/cm³",
            short: "SPC/E water",
            scene: SPCE,
            overrides: vec!["species.0.count=512".to_owned()],
            eq_ps: if quick { 0.05 } else { 0.15 },
            ps: if quick { 0.1 } else { 0.8 },
            msd_lag_ps: if quick { 0.05 } else { 0.4 },
            dmd,
            ratio_steps: vec![0.5, 0.25],
            ..Self::water(quick)
        }
    }

    /// Overrides of every production run (times and observables).
    fn production(&self) -> Vec<String> {
        let mut o = self.overrides.clone();
        o.extend([
            format!("run.time={}", self.ps),
            format!("run.equilibration_time={}", self.eq_ps),
            format!("output.sample_interval={}", self.sample_ps),
            format!("output.rdf.bins={}", self.rdf_bins),
            format!("output.rdf.r_max={}", self.rdf_max),
            format!("output.rdf.every={}", self.rdf_every),
            format!("output.msd.max_lag={}", self.msd_lag_ps),
            "output.series=false".to_owned(),
            "output.plots=false".to_owned(),
        ]);
        o.extend(self.without(&["output.vacf", "output.orientation_acf"]));
        o
    }

    /// Overrides that remove those of `keys` the scene has (a removal of an absent key is
    /// refused).
    fn without(&self, keys: &[&str]) -> Vec<String> {
        keys.iter()
            .map(|k| format!("{k}="))
            .filter(|o| Scene::from_str_with(self.scene, std::slice::from_ref(o)).is_ok())
            .collect()
    }

    fn jobs(&self) -> Vec<(Setting, u64, Role)> {
        let mut jobs = vec![(Setting::Smd(self.ref_dt), 101, Role::Reference)];
        for k in 0..self.twins {
            jobs.push((Setting::Smd(self.ref_dt), 202 + 101 * k as u64, Role::Twin));
        }
        for (k, &dt) in self.dts.iter().enumerate() {
            jobs.push((Setting::Smd(dt), 1000 + k as u64, Role::Run));
        }
        for (k, &l) in self.dmd.iter().enumerate() {
            jobs.push((Setting::Dmd(l), 2000 + k as u64, Role::Run));
            jobs.push((Setting::Dmd(l), 3000 + k as u64, Role::Verify));
        }
        if let Some(l) = self.repeat {
            jobs.push((Setting::Dmd(l), 4000, Role::Repeat));
        }
        jobs
    }
}

// ---- Runs -------------------------------------------------------------------------------------

/// What one production run measured, in the scene's units (kJ/mol, bar, Å, ps, K).
#[derive(Clone, Debug)]
struct Measured {
    /// ⟨U⟩/N and P as compared: the continuous model's estimators where the engine has them.
    u: f64,
    p: f64,
    /// DMD: the terraced system's own ⟨V⟩/N and collision-virial P.
    terraced: Option<(f64, f64)>,
    /// Self-diffusion coefficient from the MSD slope.
    d: f64,
    temperature: f64,
    rdf: Vec<(f64, f64)>,
    /// CPU seconds per ps of production.
    cost: f64,
    /// DMD: pair events per ps; SMD: steps per ps.
    rate: f64,
    /// SMD: detrended std(E)/std(U) of production.
    fluctuation: Option<f64>,
    /// DMD: relative energy drift, detected misses, anomalies.
    drift: f64,
    detected: u64,
    anomalies: u64,
}

/// What a verification run found: verified misses, detected misses, anomalies, pair events.
#[derive(Clone, Copy, Debug)]
struct Verified {
    verified: Option<u64>,
    detected: u64,
    anomalies: u64,
    pair_events: f64,
    drift: f64,
}

enum Outcome {
    Measured(Box<Measured>),
    Verified(Verified),
}

/// DMD's potential energy per body (kJ/mol) and pressure (bar) as compared with SMD's: the
/// continuous model's estimators along the terraced trajectory (`potential_energy_per_body_smooth`,
/// `pressure_smooth`: the smooth potential, cut and switched as SMD's, at every 20th sample),
/// or the terraced system's own values where a run has none; the table lists the terraced
/// values beside them.
fn dmd_energy_pressure(s: &Summary) -> (f64, f64) {
    match (s.potential_energy_per_body_smooth, s.pressure_smooth) {
        (Some(u), Some(p)) => (u, p),
        _ => (s.potential_energy_per_body, s.pressure),
    }
}

fn rdf_of(dir: &Path) -> Vec<(f64, f64)> {
    csv(&dir.join("rdf.csv"))
        .iter()
        .map(|x| (x[0], x[1]))
        .collect()
}

fn dmd_run(sp: &StatePoint, l: Levels, seed: u64, dir: &Path) -> Result<Measured, String> {
    let mut o = sp.production();
    o.extend(l.overrides());
    o.extend(sp.dmd_equilibration.iter().cloned());
    o.push(format!("seed={seed}"));
    let s = scene_run(sp.scene, &o, Some(dir)).map_err(|e| format!("DMD {}: {e}", l.label()))?;
    let (u, p) = dmd_energy_pressure(&s);
    Ok(Measured {
        u,
        p,
        terraced: Some((s.potential_energy_per_body, s.pressure)),
        d: s.diffusion_msd.unwrap_or(f64::NAN),
        temperature: s.temperature,
        rdf: rdf_of(dir),
        cost: s.cpu_seconds / s.sim_time,
        rate: s.pair_event_rate(),
        fluctuation: None,
        drift: s.relative_energy_drift,
        detected: s.detected_misses,
        anomalies: s.anomalies,
    })
}

fn dmd_verify(sp: &StatePoint, l: Levels, seed: u64) -> Result<Verified, String> {
    let mut o = sp.overrides.clone();
    o.extend(l.overrides());
    o.extend(sp.dmd_equilibration.iter().cloned());
    o.extend([
        format!("seed={seed}"),
        format!("run.equilibration_time={}", sp.verify_ps.0),
        format!("run.time={}", sp.verify_ps.1),
        format!("search.verify_step={}", sp.verify_step),
        "output.series=false".to_owned(),
    ]);
    o.extend(sp.without(&[
        "output.rdf",
        "output.msd",
        "output.vacf",
        "output.orientation_acf",
    ]));
    let s =
        scene_run(sp.scene, &o, None).map_err(|e| format!("DMD {} (verified): {e}", l.label()))?;
    Ok(Verified {
        verified: s.verified_misses,
        detected: s.detected_misses,
        anomalies: s.anomalies,
        pair_events: (s.terrace_crossings + s.reflections) as f64,
        drift: s.relative_energy_drift,
    })
}

fn smd_run(sp: &StatePoint, dt: f64, seed: u64, dir: &Path) -> Result<Measured, String> {
    let mut o = sp.production();
    o.extend([
        format!("seed={seed}"),
        "engine=smd".to_owned(),
        format!("smd.dt={}", dt * 1e-3),
    ]);
    o.extend(sp.skin.map(|d| format!("smd.skin={d}")));
    let scene = Scene::from_str_with(sp.scene, &o).map_err(|e| e.to_string())?;
    let _ = std::fs::remove_dir_all(dir);
    let s: SmdSummary = smd_engine::run(&scene, Path::new("."), Some(dir))
        .map_err(|e| format!("SMD at {dt} fs: {e}"))?;
    Ok(Measured {
        u: s.potential_energy_per_body,
        p: s.pressure,
        terraced: None,
        d: s.diffusion_msd.unwrap_or(f64::NAN),
        temperature: s.temperature,
        rdf: rdf_of(dir),
        cost: s.cpu_seconds / s.sim_time,
        rate: 1000.0 / dt,
        fluctuation: Some(s.energy_fluctuation_over_potential_std),
        drift: s.relative_energy_drift,
        detected: 0,
        anomalies: 0,
    })
}

/// `sp` with its runs' start: where it starts from one SMD frame, that frame made (SMD from the
/// lattice for `start_ps`, its state at the start of a short production written by the
/// trajectory output) and every run pointed at it.
fn start_frame(sp: &StatePoint, work: &Path) -> Result<StatePoint, String> {
    let mut sp = sp.clone();
    let Some(ps) = sp.start_ps else {
        return Ok(sp);
    };
    let dir = work.join(format!("{}-start", sp.key));
    let _ = std::fs::remove_dir_all(&dir);
    let mut o = sp.overrides.clone();
    o.extend([
        "engine=smd".to_owned(),
        format!("run.equilibration_time={ps}"),
        format!("run.time={}", 2.0 * sp.sample_ps),
        format!("output.sample_interval={}", sp.sample_ps),
        "output.series=false".to_owned(),
        "output.plots=false".to_owned(),
        // One frame, at the start of production.
        "output.trajectory={interval=1000.0}".to_owned(),
    ]);
    o.extend(sp.without(&[
        "output.rdf",
        "output.msd",
        "output.vacf",
        "output.orientation_acf",
    ]));
    let scene = Scene::from_str_with(sp.scene, &o).map_err(|e| e.to_string())?;
    smd_engine::run(&scene, Path::new("."), Some(&dir))
        .map_err(|e| format!("SMD start frame of {}: {e}", sp.key))?;
    let frame = dir
        .join("trajectory.xyz")
        .canonicalize()
        .map_err(|e| format!("the start frame of {}: {e}", sp.key))?;
    sp.overrides.extend([
        "init.positions=file".to_owned(),
        format!("init.file={}", frame.display()),
        "init.orientations=file".to_owned(),
    ]);
    Ok(sp)
}

/// Runs every job of `sp`, two at a time, dearest first; results in job order.
fn run_all(
    sp: &StatePoint,
    jobs: &[(Setting, u64, Role)],
    work: &Path,
) -> Result<Vec<Result<Outcome, String>>, String> {
    let mut order: Vec<usize> = (0..jobs.len()).collect();
    let weight = |k: usize| {
        let (s, _, role) = jobs[k];
        if role == Role::Verify {
            // A verification costs about ten times its short production.
            10.0 * s.guess() * sp.verify_ps.1 + s.guess() * sp.verify_ps.0
        } else {
            s.guess() * (sp.eq_ps + sp.ps)
        }
    };
    order.sort_by(|&a, &b| weight(b).total_cmp(&weight(a)));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .map_err(|e| e.to_string())?;
    let mut done: Vec<(usize, Result<Outcome, String>)> = pool.install(|| {
        order
            .into_iter()
            .par_bridge()
            .map(|k| {
                let (setting, seed, role) = jobs[k];
                let dir = work.join(format!("{}-{k}", sp.key));
                let res = match (setting, role) {
                    (Setting::Dmd(l), Role::Verify) => {
                        dmd_verify(sp, l, seed).map(Outcome::Verified)
                    }
                    (Setting::Dmd(l), _) => {
                        dmd_run(sp, l, seed, &dir).map(|m| Outcome::Measured(Box::new(m)))
                    }
                    (Setting::Smd(dt), _) => {
                        smd_run(sp, dt, seed, &dir).map(|m| Outcome::Measured(Box::new(m)))
                    }
                };
                let _ = std::fs::remove_dir_all(&dir);
                eprintln!(
                    "  frontier {}: {} {} (seed {seed}) done",
                    sp.key,
                    setting.engine(),
                    setting.label()
                );
                (k, res)
            })
            .collect()
    });
    done.sort_by_key(|x| x.0);
    Ok(done.into_iter().map(|x| x.1).collect())
}

// ---- Errors -----------------------------------------------------------------------------------

/// |ΔU/N|, |ΔP|, |ΔD| and ∫|Δg| dr of `m` against `reference`.
fn errors(m: &Measured, reference: &Measured) -> [f64; 4] {
    [
        (m.u - reference.u).abs(),
        (m.p - reference.p).abs(),
        (m.d - reference.d).abs(),
        integrated_difference(&m.rdf, &reference.rdf),
    ]
}

/// The noise level of each error: the root mean square of the same error between every two
/// reference runs (independent seeds, the reference's step), i.e. the error a run has from
/// sampling alone.
fn noise(refs: &[&Measured]) -> [f64; 4] {
    let mut sum = [0.0; 4];
    let mut n = 0.0;
    for (i, a) in refs.iter().enumerate() {
        for b in &refs[i + 1..] {
            let e = errors(a, b);
            for k in 0..4 {
                sum[k] += e[k] * e[k];
            }
            n += 1.0;
        }
    }
    sum.map(|s| (s / n).sqrt())
}

/// One measured run on the frontier.
struct Row {
    setting: Setting,
    seed: u64,
    role: Role,
    m: Measured,
    err: [f64; 4],
}

// ---- Report -----------------------------------------------------------------------------------

fn validate(args: &Args, work: &Path, r: &mut Report, w: &mut String) -> Result<(), String> {
    writeln!(
        w,
        "The error-against-cost frontier of the two engines on the paper's rods \
         (`scenes/rods-paper.toml`, N = 512). DMD: the paper's scene (adaptive search, 4 fs \
         step and window, `max_change` 0.5), Andersen thermostat during equilibration, NVE \
         production (in the gas with the search's default step and window, which scale with \
         the thermal speed: 1.26 fs at T* = 10), at several ΔV with the paper's levels `U_k = (k − ½)ΔV` and, at one ΔV, \
         other level distributions (`placement`, `step_energy`, `outermost`; see \
         docs/USER-GUIDE.md). SMD: `dmd run --engine smd` on the same scene (the `smd` \
         crate's symplectic splitting with the exact free rotation, the potential smoothed to \
         zero between 2.5σ and 3σ), velocity rescaling during equilibration, NVE production. \
         Both engines sample the same observables at the same interval, so their costs are \
         the same measure: **CPU seconds per ps** = the summary's `cpu_seconds` (thread CPU \
         time of production, sampling included) over the simulated production time. Runs go \
         two at a time on a 2-core machine shared with other jobs: compare within a table.\n\n\
         Errors are against the reference run (SMD at the smallest step, seed 101): \
         ⟨U⟩/N (kJ/mol), the mean pressure P (bar), the self-diffusion coefficient D \
         (Å²/ps, slope of the MSD over the second half of its lags / 6) and ∫|g − g_ref| dr \
         (Å). The **noise** of each is the root mean square of the same error between every \
         two reference runs (independent seeds at the reference step): what a run's error is \
         from sampling alone. DMD's U/N and P are the estimators of the continuous model where \
         the summary has them (the smooth potential along the terraced trajectory) and \
         otherwise the terraced system's own ⟨V⟩/N and collision-virial P, listed beside \
         them (`dmd_energy_pressure` in `validate_frontier.rs` is where that is chosen); \
         the terraced system lacks the attraction beyond its outermost level, so its U/N \
         differs from the smooth potential's by construction. Both engines start production at \
         the bath temperature (rescaled at the end of equilibration); in NVE the mean still \
         moves by the seed-to-seed scatter of the equilibrated state, so DMD's own noise can \
         exceed the reference's (the repeat row measures it). Every DMD setting also \
         runs a short verification (`search.verify_step` = {} fs at the rods, 0.02 fs in water; \
         not timed).\n\n\
         The third state point is SSD/E water (`scenes/water-ssd.toml`: 512 rigid asymmetric \
         tops at 298.15 K and 0.997 g/cm³, a single site with Lennard-Jones, dipole and sticky \
         terms switched off between 7.65 and 9 Å), where both engines use the potential as it \
         is (SMD integrates the asymmetric tops exactly between kicks), DMD the scene's search \
         (2 fs steps and window, certified prediction) at ΔV = kT/2 and finer, and every run \
         starts from one equilibrated SMD frame. g(r) there is the molecular centres' (the \
         model's O–O g(r)). The fourth is SPC/E water (`scenes/water-spce.toml` with 512 \
         molecules, the same state: three charged sites, damped shifted force Coulomb and \
         oxygen Lennard-Jones terms cut at 9 Å), run the same way; its g(r) is that of the \
         centres of mass, 0.065 Å from the oxygens. {} run.\n",
        VERIFY_STEP * 1e3,
        if args.quick { "Quick (CI)" } else { "Full" }
    )
    .ok();
    let points = [
        StatePoint::dense(args.quick),
        StatePoint::gas(args.quick),
        StatePoint::water(args.quick),
        StatePoint::spce(args.quick),
    ];
    // `--case KEY` runs the state points whose key contains KEY (dense, gas, water, spce).
    for sp in points.iter().filter(|sp| {
        args.case
            .as_ref()
            .is_none_or(|c| sp.key.contains(c.as_str()))
    }) {
        state(sp, args, r, w, work)?;
    }
    Ok(())
}

#[allow(clippy::too_many_lines)]
fn state(
    sp: &StatePoint,
    args: &Args,
    r: &mut Report,
    w: &mut String,
    work: &Path,
) -> Result<(), String> {
    let started = std::time::Instant::now();
    let prepared = start_frame(sp, work)?;
    let sp = &prepared;
    let jobs = sp.jobs();
    let results = run_all(sp, &jobs, work)?;
    let wall = started.elapsed().as_secs_f64();

    // Sort the outcomes: an SMD run coarser than the reference may blow up (a result); any
    // other failure is an error.
    let mut reference = None;
    let mut twins: Vec<(u64, Measured)> = Vec::new();
    let mut rows: Vec<Row> = Vec::new();
    let mut unstable: Vec<(f64, String)> = Vec::new();
    let mut verified: Vec<(Levels, Verified)> = Vec::new();
    for (res, &(setting, seed, role)) in results.into_iter().zip(&jobs) {
        match (res, role, setting) {
            (Ok(Outcome::Verified(v)), _, Setting::Dmd(l)) => verified.push((l, v)),
            (Ok(Outcome::Measured(m)), Role::Reference, _) => reference = Some(*m),
            (Ok(Outcome::Measured(m)), Role::Twin, _) => twins.push((seed, *m)),
            (Ok(Outcome::Measured(m)), _, _) => rows.push(Row {
                setting,
                seed,
                role,
                m: *m,
                err: [f64::NAN; 4],
            }),
            (Err(e), Role::Run, Setting::Smd(dt)) if dt > sp.ref_dt => unstable.push((dt, e)),
            (Err(e), _, _) => return Err(e),
            (Ok(_), _, _) => return Err("a verification outcome of an SMD job".to_owned()),
        }
    }
    let reference = reference.ok_or("no reference run")?;
    let mut refs = vec![&reference];
    refs.extend(twins.iter().map(|t| &t.1));
    let noise = noise(&refs);
    // The first twin is an SMD run at the reference step like any other.
    if let Some((seed, m)) = twins.first() {
        rows.push(Row {
            setting: Setting::Smd(sp.ref_dt),
            seed: *seed,
            role: Role::Run,
            m: m.clone(),
            err: [f64::NAN; 4],
        });
    }
    for row in &mut rows {
        row.err = errors(&row.m, &reference);
    }
    // SMD by decreasing step, then DMD's paper levels by decreasing ΔV, then other rules.
    let key = |x: &Row| match x.setting {
        Setting::Smd(dt) => (0, -dt),
        Setting::Dmd(l) if x.role == Role::Repeat => (3, -l.step_kt),
        Setting::Dmd(l) if l.is_paper() => (1, -l.step_kt),
        Setting::Dmd(l) => (2, -l.step_kt),
    };
    rows.sort_by(|a, b| {
        let (ka, kb) = (key(a), key(b));
        ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
    });

    let start = match sp.start_ps {
        None => "Every run starts from its own seed (simple-cubic lattice, random axes)".to_owned(),
        Some(ps) => format!(
            "Every run starts from one frame, SMD equilibrated for {ps} ps from the lattice \
             (positions and attitudes), with velocities and angular velocities drawn from its \
             own seed at the bath temperature{}",
            if sp.dmd_equilibration.is_empty() {
                String::new()
            } else {
                format!(
                    " (DMD's equilibration with `{}`)",
                    sp.dmd_equilibration.join("`, `")
                )
            }
        ),
    };
    let skin = sp.skin.map_or("the engine's default skin".to_owned(), |d| {
        format!("skin {d} Å")
    });
    writeln!(
        w,
        "### {}\n\n\
         {start}, is \
         equilibrated for {} ps and produces {} ps of NVE, sampled every {} fs (g(r) once every \
         {} samples, {} bins to {} Å; MSD to {} ps). Reference: SMD at {} fs ({skin}) and \
         {} more seeds for the noise. Wall time of this state's runs: {wall:.0} s.\n\n\
         | engine | setting | seed | CPU s per ps | ΔU/N (kJ/mol) | ΔP (bar) | ΔD (Å²/ps) | \
         ∫\\|Δg\\| dr (Å) | errors / noise (U, P, D, g) | U/N (kJ/mol) | terraced ⟨V⟩/N \
         (kJ/mol) | P (bar) | terraced P (bar) | D (Å²/ps) | T (K) | events or steps per ps |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n\
         | SMD | dt = {} fs (**reference**) | 101 | {:.3} | – | – | – | – | – | {:.3} | – | \
         {:.1} | – | {:.4} | {:.1} | {:.0} steps |\n\
         | **noise** | {} reference runs | – | – | **{:.3}** | **{:.1}** | **{:.4}** | \
         **{:.3e}** | 1, 1, 1, 1 | – | – | – | – | – | – | – |",
        sp.title,
        sp.eq_ps,
        sp.ps,
        sp.sample_ps * 1e3,
        sp.rdf_every,
        sp.rdf_bins,
        sp.rdf_max,
        sp.msd_lag_ps,
        sp.ref_dt,
        sp.twins,
        sp.ref_dt,
        reference.cost,
        reference.u,
        reference.p,
        reference.d,
        reference.temperature,
        reference.rate,
        sp.twins + 1,
        noise[0],
        noise[1],
        noise[2],
        noise[3],
    )
    .ok();
    for row in &rows {
        let m = &row.m;
        let rate = match row.setting {
            Setting::Dmd(_) => format!("{:.3e} events", m.rate),
            Setting::Smd(_) => format!("{:.0} steps", m.rate),
        };
        let (vu, vp) = m
            .terraced
            .map_or(("–".to_owned(), "–".to_owned()), |(u, p)| {
                (format!("{u:.3}"), format!("{p:.1}"))
            });
        let label = match row.role {
            Role::Repeat => format!("{} (repeat: another seed)", row.setting.label()),
            _ => row.setting.label(),
        };
        writeln!(
            w,
            "| {} | {label} | {} | {:.3} | {:+.3} | {:+.1} | {:+.4} | {:.3e} | {} | {:.3} | {vu} | \
             {:.1} | {vp} | {:.4} | {:.1} | {rate} |",
            row.setting.engine(),
            row.seed,
            m.cost,
            m.u - reference.u,
            m.p - reference.p,
            m.d - reference.d,
            row.err[3],
            (0..4)
                .map(|k| format!("{:.1}", row.err[k] / noise[k]))
                .collect::<Vec<_>>()
                .join(", "),
            m.u,
            m.p,
            m.d,
            m.temperature,
        )
        .ok();
    }
    for (dt, _) in &unstable {
        writeln!(
            w,
            "| SMD | dt = {dt} fs | – | unstable | | | | | | | | | | | | |"
        )
        .ok();
    }
    for (dt, e) in &unstable {
        writeln!(w, "\nSMD at {dt} fs did not complete its production: {e}").ok();
    }

    // The comparison SMD run.
    let smd: Vec<&Row> = rows
        .iter()
        .filter(|x| matches!(x.setting, Setting::Smd(_)))
        .collect();
    let dmd: Vec<&Row> = rows
        .iter()
        .filter(|x| matches!(x.setting, Setting::Dmd(_)) && x.role == Role::Run)
        .collect();
    let fluct: Vec<String> = smd
        .iter()
        .filter_map(|x| match x.setting {
            Setting::Smd(dt) => x.m.fluctuation.map(|f| format!("{f:.2e} at {dt} fs")),
            Setting::Dmd(_) => None,
        })
        .collect();
    let comparator: Option<&Row> = match sp.comparator {
        Comparator::Step(dt, _) => smd.iter().copied().find(|x| x.setting == Setting::Smd(dt)),
        Comparator::Fluctuation => smd
            .iter()
            .copied()
            .filter(|x| x.m.fluctuation.is_some_and(|f| f <= FLUCTUATION_MAX))
            .max_by(|a, b| match (a.setting, b.setting) {
                (Setting::Smd(x), Setting::Smd(y)) => x.total_cmp(&y),
                _ => std::cmp::Ordering::Equal,
            }),
    };
    let why = match sp.comparator {
        Comparator::Step(dt, why) => format!("{why}, {dt} fs"),
        Comparator::Fluctuation => format!(
            "the largest step whose detrended std(E)/std(U) in NVE is at most {FLUCTUATION_MAX} \
             (003 §V.B's measure, about 1 % at 1.8 fs at the dense state)"
        ),
    };
    writeln!(
        w,
        "\nSMD's energy conservation, detrended std(E)/std(U) of NVE: {}. The SMD run the DMD \
         runs are held against: {why}: {}.\n",
        fluct.join(", "),
        comparator.map_or("none completed".to_owned(), |c| c.setting.label())
    )
    .ok();

    // Matched cost and the frontier in words.
    let smd_pts =
        |k: usize| -> Vec<(f64, f64)> { smd.iter().map(|x| (x.m.cost, x.err[k])).collect() };
    writeln!(
        w,
        "At matched error: the CPU time per ps SMD needs for the DMD run's error (the cheapest \
         SMD run at least as accurate, interpolated log–log towards the next cheaper one, the \
         SMD run at the reference step included: its error is the noise), over the DMD run's; \
         `≤` when even the cheapest SMD run is as accurate, `≥` when none is; \
         \"(unresolved)\" when the DMD error is within the noise. Above 1, DMD is the cheaper \
         way to that accuracy.\n\n\
         | DMD setting | CPU s per ps | SMD(comparison) / DMD | matched U/N | matched P | \
         matched D | matched g(r) |\n|---|---|---|---|---|---|---|"
    )
    .ok();
    let mut best: Option<(f64, Bound, &Row)> = None;
    for row in &dmd {
        let plain = comparator.map_or("–".to_owned(), |c| ratio(c.m.cost / row.m.cost));
        let matched: Vec<String> = (0..4)
            .map(|k| matched_ratio(&smd_pts(k), row.err[k], noise[k], row.m.cost))
            .collect();
        // The worse of U and D decides how far this setting is from SMD's frontier.
        let (ud, bound) = [0, 2]
            .iter()
            .map(|&k| {
                let (b, cost) = matched_cost(&smd_pts(k), row.err[k].max(noise[k]));
                (cost / row.m.cost, b)
            })
            .fold(
                (f64::INFINITY, Bound::About),
                |a, x| if x.0 < a.0 { x } else { a },
            );
        if best.is_none_or(|b| ud > b.0) {
            best = Some((ud, bound, row));
        }
        writeln!(
            w,
            "| {} | {:.3} | {plain} | {} | {} | {} | {} |",
            row.setting.label(),
            row.m.cost,
            matched[0],
            matched[1],
            matched[2],
            matched[3]
        )
        .ok();
    }
    if let Some(c) = comparator {
        // "As accurate": an error no larger than the comparison run's, or within the noise.
        let as_good = |row: &Row, k: usize| row.err[k] <= c.err[k].max(noise[k]);
        let winners: Vec<String> = dmd
            .iter()
            .filter(|x| as_good(x, 0) && as_good(x, 2) && x.m.cost < c.m.cost)
            .map(|x| format!("{} ({:.3} CPU s per ps)", x.setting.label(), x.m.cost))
            .collect();
        // The other direction: DMD's cost at the comparison run's error (the DMD runs with
        // the paper's levels, interpolated; a bound when none reaches it), over SMD's.
        let dmd_reach = |k: usize| -> String {
            let pts: Vec<(f64, f64)> = dmd
                .iter()
                .filter(|x| matches!(x.setting, Setting::Dmd(l) if l.is_paper()))
                .map(|x| (x.m.cost, x.err[k]))
                .collect();
            let (bound, cost) = matched_cost(&pts, c.err[k].max(noise[k]));
            format!("{}{}", bound_mark(bound), ratio(cost / c.m.cost))
        };
        let verdict = if winners.is_empty() {
            match best {
                Some((worst, bound, row)) => format!(
                    "none is. The cost ratio at matched error, DMD's CPU time per ps for the \
                     comparison run's error over SMD's (along the paper's levels, interpolated \
                     log–log; `≥` when no ΔV reaches it): U/N {}, D {}. The DMD run closest to \
                     SMD's frontier in U/N and D together, {} ({:.3} CPU s per ps), has a \
                     matched ratio SMD/DMD of {}{} in the worse of the two (the table \
                     above; below 1, SMD reaches that run's accuracy for less)",
                    dmd_reach(0),
                    dmd_reach(2),
                    row.setting.label(),
                    row.m.cost,
                    bound_mark(bound),
                    ratio(worst)
                ),
                None => "no DMD run completed".to_owned(),
            }
        } else {
            winners.join("; ")
        };
        writeln!(
            w,
            "\nThe frontier in words: the DMD settings at least as accurate as SMD at {} \
             ({:.3} CPU s per ps; errors U/N {:.3} kJ/mol, D {:.4} Å²/ps, i.e. {:.1} and {:.1} \
             noise levels) in U/N and D (an error no larger, or within the noise) and cheaper: \
             {verdict}.\n",
            c.setting.label(),
            c.m.cost,
            c.err[0],
            c.err[2],
            c.err[0] / noise[0],
            c.err[2] / noise[2]
        )
        .ok();
        let ratios: Vec<String> = sp
            .ratio_steps
            .iter()
            .filter_map(|&dv| {
                dmd.iter()
                    .find(|x| x.setting == Setting::Dmd(Levels::paper(dv)))
                    .map(|x| format!("ΔV = {}: {}", kt_label(dv), ratio(c.m.cost / x.m.cost)))
            })
            .collect();
        let note = if sp.ratio_note.is_empty() {
            String::new()
        } else {
            format!("; {}", sp.ratio_note)
        };
        writeln!(
            w,
            "Efficiency ratio, CPU per ps of SMD at {} over DMD's with the paper's levels (the \
             paper's measure{note}): {}.\n",
            c.setting.label(),
            ratios.join("; ")
        )
        .ok();
    }

    // Plot: one panel per observable.
    let file = format!("frontier-{}.svg", sp.key);
    plot(&args.figures.join(&file), sp, &rows, noise)?;
    writeln!(w, "![error against cost, {}](figures/{file})\n", sp.title).ok();

    // Checks.
    let dmd_clean = rows
        .iter()
        .filter(|x| matches!(x.setting, Setting::Dmd(_)))
        .all(|x| x.m.detected == 0 && x.m.anomalies == 0 && x.m.drift <= sp.drift_max);
    let worst_drift = rows
        .iter()
        .filter(|x| matches!(x.setting, Setting::Dmd(_)))
        .map(|x| x.m.drift)
        .fold(0.0f64, f64::max);
    let detected: u64 = rows.iter().map(|x| x.m.detected).sum();
    let verified_clean = !verified.is_empty()
        && verified.iter().all(|(_, v)| {
            v.verified == Some(0) && v.detected == 0 && v.anomalies == 0 && v.drift <= sp.drift_max
        });
    let verified_text: Vec<String> = verified
        .iter()
        .map(|(l, v)| {
            format!(
                "{}: {} in {:.2e} pair events",
                l.label(),
                v.verified
                    .map_or("not verified".to_owned(), |m| m.to_string()),
                v.pair_events
            )
        })
        .collect();
    let sane = comparator.is_some_and(|c| (0..4).all(|k| c.err[k] <= SANITY * noise[k]));
    writeln!(
        w,
        "Checks:\n\n\
         - every DMD production run: no detected miss, no anomaly, relative energy drift at \
         most {:.0e} (detected misses {detected}, largest drift {worst_drift:.1e}): {}\n\
         - every DMD setting's verification run finds no missed event (verified misses: {}): {}\n\
         - the reference is sane: the comparison SMD run ({}) is within {SANITY} noise levels of \
         it in every observable: {}\n",
        sp.drift_max,
        r.check(dmd_clean),
        verified_text.join("; "),
        r.check(verified_clean),
        comparator.map_or("none".to_owned(), |c| c.setting.label()),
        r.check(sane),
    )
    .ok();
    Ok(())
}

/// The four panels (U/N, P, D, g(r)) of error against cost at one state point.
fn plot(path: &Path, sp: &StatePoint, rows: &[Row], noise: [f64; 4]) -> Result<(), String> {
    use plotters::prelude::*;
    let root = SVGBackend::new(path, (1400, 1000)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let panels = root.split_evenly((2, 2));
    let pick = |f: &dyn Fn(&Row) -> bool| -> Vec<&Row> { rows.iter().filter(|x| f(x)).collect() };
    let paper =
        pick(&|x| matches!(x.setting, Setting::Dmd(l) if l.is_paper()) && x.role == Role::Run);
    let other =
        pick(&|x| matches!(x.setting, Setting::Dmd(l) if !l.is_paper()) && x.role == Role::Run);
    let smd = pick(&|x| matches!(x.setting, Setting::Smd(_)));
    for (k, area) in panels.iter().enumerate() {
        let (name, unit) = OBSERVABLES[k];
        let series = |label: &str, set: &[&Row], joined: bool| Series {
            label: label.to_owned(),
            points: set.iter().map(|x| (x.m.cost, x.err[k])).collect(),
            tags: set.iter().map(|x| x.setting.tag()).collect(),
            joined,
        };
        let all = [
            series("DMD, the paper's levels (ΔV)", &paper, true),
            series("DMD, other level rules", &other, false),
            series("SMD (dt)", &smd, true),
        ];
        let y = if k == 3 {
            format!("∫|Δg| dr ({unit})")
        } else {
            format!("|Δ{name}| ({unit})")
        };
        draw_panel(
            area,
            &format!("{}: error of {name} against cost", sp.short),
            "CPU s per ps",
            &y,
            &all,
            Some(noise[k]),
        )
        .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    root.present().map_err(|e| e.to_string())
}
