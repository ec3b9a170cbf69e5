//! `dmd tune`: which accuracy setting of a scene buys a target error cheapest.
//!
//! For each accuracy knob the scene uses (the terrace step ΔV of every terraced pair, the
//! search step of a root-searched model, the smd engine's time step), short probe runs of the
//! scene at the knob's value times 2, 1, ½ and ¼, the other knobs at the scene's values. Each
//! probe is an ordinary run ([`run_scene`] or [`smd_engine::run`]) with `--set` overrides for
//! the knob and a shortened length. The level rule of a terraced pair (its terrace energies)
//! is a knob of choices: each other rule at the scene's ΔV against the scene's rule at the
//! finest ΔV. The error of a probe is its difference from the finest
//! probe of the same knob in the potential energy per body and the pressure, relative to a
//! scale (|U/N| of the finest probe; for P the larger of |P| and ρkT, since P may be near
//! zero), with the uncertainty of that difference from the two runs' own block-average errors
//! (`_error` of the summary) in quadrature. A setting qualifies when `error + uncertainty` is
//! within the target, and a probe that missed events (`detected_misses` of its runs, and the
//! verified misses when the scene verifies its searches) never qualifies, whatever its
//! averages say. The recommended value of each knob is its cheapest qualifying one, by CPU
//! seconds of production per unit of simulated time; a quantity too noisy at this probe length
//! to be shown within the target is named as not certified and left out of the judgement, and
//! when no coarser probe meets the target in U/N and P together, the cheapest that meets it in
//! one of them (U/N first) is recommended for that one, the other named as not certified with
//! why (really off, too noisy, or not decided at this length).
//!
//! After this first pass, the probes whose noise alone keeps a knob from certifying U/N and P
//! are lengthened ([`lengthening`]: the knob's cheapest coarser probe that is within the
//! target or could be, with its reference), in up to [`MAX_ROUNDS`] rounds, while the
//! estimate of their wall time fits in the budget ([`TuneOptions::wall_budget`], default
//! [`WALL_BUDGET`]). A lengthening is an independent run (its own seed and equilibration) of
//! the missing production, pooled with the probe's runs ([`Probe::pooled`]); the knobs are
//! then judged on the pooled probes. Knobs are judged one at a time; whether their
//! recommended values together meet the target is what `cargo xtask validate --only tune`
//! checks on the shipped scenes.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::analysis::output::{Line, OutputError, Plot, write_atomically, write_plot};
use crate::config::scene::{Scene, SceneError, ThermostatKind, ThermostatPhase};
use crate::config::units::UnitNames;
use crate::driver::reporting::{Quiet, RunError};
use crate::driver::run::run_scene;
use crate::driver::smd_engine::{self, Engine};

/// The multiples of a knob's scene value that are probed, coarsest first; the last is the
/// reference.
pub const FACTORS: [f64; 4] = [2.0, 1.0, 0.5, 0.25];

/// Default probe production length, as a fraction of the scene's.
pub const PRODUCTION_FRACTION: f64 = 0.5;

/// Default probe equilibration length, as a fraction of the scene's.
pub const EQUILIBRATION_FRACTION: f64 = 0.5;

/// Default wall-clock budget of a tune (seconds): the first pass always runs whole; probes
/// are lengthened only while their estimated wall time fits in what is left of it.
pub const WALL_BUDGET: f64 = 540.0;

/// The most a probe's production is lengthened by in one round of lengthening.
pub const MAX_LENGTHENING: f64 = 16.0;

/// Rounds of lengthening after the first pass at most.
pub const MAX_ROUNDS: usize = 3;

/// Why `dmd tune` cannot run.
#[derive(Debug, thiserror::Error)]
pub enum TuneError {
    /// The scene (with its overrides) is not acceptable.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A command-line value is not acceptable.
    #[error("{option}: {problem}")]
    Option {
        /// The option (`--target`).
        option: &'static str,
        /// What is wrong.
        problem: String,
    },
    /// The scene has no accuracy knob that `dmd tune` varies.
    #[error("nothing to tune: {0}")]
    NoKnob(String),
    /// A reference probe (the finest setting of a knob) failed.
    #[error("the reference probe {setting} failed: {source}")]
    Reference {
        /// The `--set` line of the probe.
        setting: String,
        /// Why.
        source: RunError,
    },
    /// The table or the plot could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl TuneError {
    /// Whether the user's input is at fault (exit status 2), not the run.
    pub fn is_input(&self) -> bool {
        matches!(
            self,
            TuneError::Scene(_) | TuneError::Option { .. } | TuneError::NoKnob(_)
        ) || matches!(
            self,
            TuneError::Reference {
                source: RunError::Scene(_),
                ..
            }
        )
    }
}

/// What `dmd tune` is asked.
#[derive(Clone, Debug, Default)]
pub struct TuneOptions {
    /// Target relative error (0.02 = 2 %).
    pub target: f64,
    /// The user's `--set` overrides (and `engine=…`), applied before the probes' own.
    pub overrides: Vec<String>,
    /// Probe production time (the scene's time unit); default half the scene's
    /// production.
    pub time: Option<f64>,
    /// Or: probe production events.
    pub events: Option<f64>,
    /// Wall-clock seconds the whole tune may take ([`WALL_BUDGET`] if none): the first pass
    /// runs whole, and its probes are lengthened while the estimate of what that takes fits
    /// in what is left.
    pub wall_budget: Option<f64>,
}

/// A wall-clock duration given as seconds (`540`, `540s`), minutes (`9m`) or hours (`1h`).
///
/// # Errors
/// What is wrong with `text`.
pub fn parse_wall(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let (number, unit) = match t.char_indices().last() {
        Some((k, 's')) => (&t[..k], 1.0),
        Some((k, 'm')) => (&t[..k], 60.0),
        Some((k, 'h')) => (&t[..k], 3600.0),
        _ => (t, 1.0),
    };
    match number.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x * unit),
        _ => Err(format!(
            "`{text}` is not a wall-clock time: give seconds (540, 540s), minutes (9m) or \
             hours (1h)"
        )),
    }
}

/// One accuracy knob of a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Knob {
    /// The scene key varied (`pair.0.terraces.step_kt`).
    pub key: String,
    /// Keys set to the same value with it (the search window when it equals the step).
    pub linked: Vec<String>,
    /// What it is, for people (`ΔV of pair 0`).
    pub label: String,
    /// Its unit (`kT`, `ps`).
    pub unit: String,
    /// The scene's value (0 for a rule knob).
    pub value: f64,
    /// A knob of rules rather than of a number (the level rule of a terraced pair): the
    /// settings probed, the last one the reference. Empty for a numeric knob, whose values
    /// are the scene's times [`FACTORS`]. A row of a rule knob carries the index of its
    /// choice as its value.
    pub choices: Vec<Choice>,
}

/// One setting of a rule knob.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    /// What it is, for people and the table (`step_energy=virial`).
    pub label: String,
    /// The `--set` lines of its probe.
    pub sets: Vec<String>,
    /// The `--set` lines to recommend when it is chosen (empty for the reference, which is
    /// the scene's own rule at a finer ΔV: choosing it keeps the scene's rule, and the ΔV
    /// knob says which step).
    pub recommend: Vec<String>,
}

impl Knob {
    /// The values probed, coarsest first; the last is the reference.
    pub fn values(&self) -> Vec<f64> {
        if self.choices.is_empty() {
            FACTORS.iter().map(|f| self.value * f).collect()
        } else {
            (0..self.choices.len()).map(|k| k as f64).collect()
        }
    }

    /// The `--set` lines that give the knob `value` (for a rule knob, the index of a choice:
    /// its probe's lines).
    pub fn sets(&self, value: f64) -> Vec<String> {
        if let Some(c) = self.choice(value) {
            return c.sets.clone();
        }
        std::iter::once(&self.key)
            .chain(&self.linked)
            .map(|k| format!("{k}={value}"))
            .collect()
    }

    /// The `--set` lines to paste for `value` (for a rule knob, those of its choice; none
    /// for the reference, which keeps the scene's rule).
    pub fn recommend(&self, value: f64) -> Vec<String> {
        match self.choice(value) {
            Some(c) => c.recommend.clone(),
            None => self.sets(value),
        }
    }

    /// The `--set` lines of a setting finer than any probed: half the finest value of a
    /// numeric knob; for a rule knob none (the scene's rule, at the finer ΔV the ΔV knob
    /// gives).
    pub fn finer_sets(&self) -> Vec<String> {
        if self.choices.is_empty() {
            self.sets(0.5 * self.value * FACTORS[FACTORS.len() - 1])
        } else {
            Vec::new()
        }
    }

    /// `value` for people: the number with its unit, or the choice's label.
    pub fn show(&self, value: f64) -> String {
        match self.choice(value) {
            Some(c) => c.label.clone(),
            None => format!("{} {}", short(value), self.unit),
        }
    }

    fn choice(&self, value: f64) -> Option<&Choice> {
        if self.choices.is_empty() {
            None
        } else {
            self.choices.get(value as usize)
        }
    }
}

/// A mean with its standard error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// The mean.
    pub value: f64,
    /// Its standard error (NaN when the run gave none).
    pub error: f64,
}

/// What one probe run measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Probe {
    /// Potential energy per body (energy unit).
    pub energy: Measured,
    /// Pressure (pressure unit).
    pub pressure: Measured,
    /// ρkT of the run (pressure unit): the scale of pressure errors when |P| is smaller.
    pub pressure_ideal: f64,
    /// Self-diffusion coefficient from the MSD, if the scene measures it (shown, not used to
    /// select: short probes leave it too noisy).
    pub diffusion: Option<Measured>,
    /// CPU seconds of production per unit of simulated time.
    pub cost: f64,
    /// Simulated time of production (time unit), over all its runs.
    pub length: f64,
    /// Wall-clock seconds of production, over all its runs.
    pub wall: f64,
    /// Independent runs pooled into it (1, and one more for each lengthening).
    pub runs: usize,
    /// Events its runs missed, as the run detects them (a pair found off its stored terrace,
    /// an event not at its level: `detected_misses`), over all its runs; 0 for smd. A setting
    /// that misses events is never within the target, whatever its averages say.
    pub misses: u64,
}

impl Probe {
    /// This probe pooled with an independent run of the same setting (`other`): every mean
    /// weighted by its run's simulated time, as one run of both lengths would weigh its
    /// samples; standard errors combined as those of independent means,
    /// `√(Σ wᵢ² σᵢ²) / Σ wᵢ`; cost as total CPU over total simulated time.
    pub fn pooled(&self, other: &Probe) -> Probe {
        let (a, b) = (self.length, other.length);
        let w = a + b;
        let mean = |x: Measured, y: Measured| Measured {
            value: (a * x.value + b * y.value) / w,
            error: (a * x.error).hypot(b * y.error) / w,
        };
        Probe {
            energy: mean(self.energy, other.energy),
            pressure: mean(self.pressure, other.pressure),
            pressure_ideal: (a * self.pressure_ideal + b * other.pressure_ideal) / w,
            diffusion: match (self.diffusion, other.diffusion) {
                (Some(x), Some(y)) => Some(mean(x, y)),
                _ => None,
            },
            cost: (a * self.cost + b * other.cost) / w,
            length: w,
            wall: self.wall + other.wall,
            runs: self.runs + other.runs,
            misses: self.misses + other.misses,
        }
    }
}

/// The error of a probe against its knob's reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deviation {
    /// `|x − x_ref| / scale`.
    pub error: f64,
    /// The standard error of that difference, `√(σ² + σ_ref²) / scale`.
    pub uncertainty: f64,
}

impl Deviation {
    /// The deviation of `x` from `reference` relative to `scale`; zero for the reference
    /// itself.
    pub fn of(x: Measured, reference: Measured, scale: f64, is_reference: bool) -> Self {
        if is_reference {
            return Deviation {
                error: 0.0,
                uncertainty: 0.0,
            };
        }
        Deviation {
            error: (x.value - reference.value).abs() / scale,
            uncertainty: x.error.hypot(reference.error) / scale,
        }
    }

    /// The error bound `error + uncertainty` (NaN when unknown).
    pub fn bound(&self) -> f64 {
        self.error + self.uncertainty
    }

    /// How many times longer the runs behind this deviation would have to be for its bound to
    /// fall within `budget`, if its difference alone is within it (errors shrink as the square
    /// root of the length): 1 when the bound is within already; `None` when the difference is
    /// not within `budget` or the uncertainty is unknown.
    pub fn longer(&self, budget: f64) -> Option<f64> {
        if self.bound() <= budget {
            return Some(1.0);
        }
        if self.error >= budget || self.uncertainty.is_nan() {
            return None;
        }
        Some((self.uncertainty / (budget - self.error)).powi(2))
    }
}

/// One row of the table: a knob at one value.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Index of the knob in [`Tuning::knobs`].
    pub knob: usize,
    /// The value probed.
    pub value: f64,
    /// The measurement, or why the probe failed.
    pub probe: Result<Probe, String>,
    /// Deviation of U/N and of P from the knob's reference (none for a failed probe).
    pub deviations: Option<[Deviation; 2]>,
}

impl Row {
    /// The largest error bound of the selecting observables (infinite for a failed probe).
    pub fn bound(&self) -> f64 {
        self.bound_of([true, true])
    }

    /// The largest error bound of the observables `which` selects (U/N, P); infinite for a
    /// failed probe and for one that missed events.
    pub fn bound_of(&self, which: [bool; 2]) -> f64 {
        if self.probe.as_ref().is_ok_and(|p| p.misses > 0) {
            return f64::INFINITY;
        }
        // `f64::max` would drop a NaN: an unknown bound must disqualify.
        self.deviations.map_or(f64::INFINITY, |d| {
            d.iter()
                .zip(which)
                .filter(|(_, w)| *w)
                .map(|(d, _)| d.bound())
                .map(|b| if b.is_nan() { f64::INFINITY } else { b })
                .fold(0.0, f64::max)
        })
    }

    /// CPU seconds per unit of simulated time (infinite for a failed probe).
    pub fn cost(&self) -> f64 {
        self.probe.as_ref().map_or(f64::INFINITY, |p| p.cost)
    }
}

/// The result of `dmd tune`.
#[derive(Clone, Debug)]
pub struct Tuning {
    /// The knobs, in the order of the table.
    pub knobs: Vec<Knob>,
    /// Every probe, knob by knob, coarsest first.
    pub rows: Vec<Row>,
    /// The target relative error.
    pub target: f64,
    /// What each knob's error bound may be: the target (knobs are probed one at a time, each
    /// with the others at the scene's values).
    pub budget: f64,
    /// The recommended row of each knob (index into `rows`), none if no probe qualified.
    pub recommended: Vec<Option<usize>>,
    /// For each knob, whether its recommendation certifies U/N and P within the target (both
    /// false when it recommends its finest probe, whose own error is not known).
    pub certified: Vec<[bool; 2]>,
    /// Unit names of the scene.
    pub units: &'static UnitNames,
    /// The probe length, for people (`5 ps of production after 5 ps of equilibration`).
    pub length: String,
    /// Whether U/N and P are the smooth estimators' (the continuous model along the terraced
    /// run, `potential_energy_per_body_smooth`, `pressure_smooth`) rather than the terraced
    /// potential's own.
    pub smooth: bool,
    /// The wall-clock budget (s).
    pub wall_budget: f64,
    /// The wall-clock seconds the tune took.
    pub wall_seconds: f64,
    /// Each lengthening of a probe, for people (`round 2: pair.0.terraces.step_kt=0.25:
    /// 10 → 43 ps`).
    pub lengthened: Vec<String>,
}

/// The cheapest row (by [`Row::cost`]) among `rows` whose bound is within `budget`; among
/// equally cheap rows the first. `None` if none qualifies.
pub fn cheapest_within(rows: &[&Row], budget: f64) -> Option<usize> {
    cheapest_within_of(rows, budget, [true, true])
}

/// [`cheapest_within`] judging only the observables `which` selects (U/N, P); `None` when it
/// selects none.
pub fn cheapest_within_of(rows: &[&Row], budget: f64, which: [bool; 2]) -> Option<usize> {
    if which == [false, false] {
        return None;
    }
    rows.iter()
        .enumerate()
        .filter(|(_, r)| r.bound_of(which) <= budget && r.cost().is_finite())
        .min_by(|a, b| a.1.cost().total_cmp(&b.1.cost()))
        .map(|(k, _)| k)
}

/// Which of U/N and P the probes of one knob (`rows`, the reference last, judged) can show
/// within `budget`: those whose difference from the reference has a standard error within it
/// at one coarser probe at least. A quantity noisier than that at this probe length can never
/// be shown within the target, however close the settings are: the tune names it as not
/// certified instead of recommending by it.
pub fn certifiable(rows: &[&Row], budget: f64) -> [bool; 2] {
    let mut out = [false; 2];
    for r in &rows[..rows.len().saturating_sub(1)] {
        if let (Ok(_), Some(d)) = (&r.probe, r.deviations) {
            for q in 0..2 {
                out[q] |= d[q].uncertainty <= budget;
            }
        }
    }
    out
}

/// The smallest standard error of the difference from the reference of observable `q` (0:
/// U/N, 1: P) among the coarser probes of one knob (`rows`, the reference last).
fn best_uncertainty(rows: &[Row], q: usize) -> f64 {
    rows[..rows.len().saturating_sub(1)]
        .iter()
        .filter_map(|r| r.deviations.map(|d| d[q].uncertainty))
        .filter(|u| u.is_finite())
        .fold(f64::INFINITY, f64::min)
}

/// The accuracy knobs of a scene that `dmd tune` varies.
///
/// # Errors
/// [`TuneError::NoKnob`] saying why there is none.
pub fn knobs(scene: &Scene) -> Result<Vec<Knob>, TuneError> {
    let names = UnitNames::of(scene.units);
    let mut knobs = Vec::new();
    if scene.engine == Engine::Smd {
        let dt = scene.smd.as_ref().and_then(|s| s.dt).ok_or_else(|| {
            TuneError::NoKnob(
                "the smd engine's time step is tuned from the scene's `smd.dt`: give it".to_owned(),
            )
        })?;
        knobs.push(Knob {
            key: "smd.dt".to_owned(),
            linked: Vec::new(),
            label: "smd time step".to_owned(),
            unit: names.time.to_owned(),
            value: dt,
            choices: Vec::new(),
        });
        return Ok(knobs);
    }
    let mut stepped = Vec::new();
    for (k, p) in scene.pair.iter().enumerate() {
        match (&p.potential, &p.terraces) {
            (Some(_), Some(t)) => {
                let (key, unit, value) = match (t.step_kt, t.step) {
                    (Some(v), _) => ("step_kt", "kT".to_owned(), v),
                    (None, Some(v)) => ("step", names.energy.to_owned(), v),
                    // Explicit levels: no single step to scale.
                    (None, None) => continue,
                };
                let step = Knob {
                    key: format!("pair.{k}.terraces.{key}"),
                    linked: Vec::new(),
                    label: format!("ΔV of pair {k}"),
                    unit,
                    value,
                    choices: Vec::new(),
                };
                let rules = level_rules(scene, k, &step);
                knobs.push(step);
                knobs.extend(rules);
            }
            _ if !p.steps.is_empty() && p.steps.iter().any(|s| s[1].is_finite()) => {
                stepped.push(k);
            }
            _ => {}
        }
    }
    // Root searches: terraced anisotropic bodies, rigid site molecules and semi-flexible ones.
    let searched = scene.has_sites()
        || scene.has_bonds()
        || scene
            .pair
            .iter()
            .any(|p| p.potential.is_some_and(|q| q.is_anisotropic()));
    if let Some(s) = scene.search.as_ref().filter(|_| searched)
        && let Some(step) = s.max_step
    {
        knobs.push(Knob {
            key: "search.max_step".to_owned(),
            linked: if s.window == Some(step) {
                vec!["search.window".to_owned()]
            } else {
                Vec::new()
            },
            label: "search step".to_owned(),
            unit: names.time.to_owned(),
            value: step,
            choices: Vec::new(),
        });
    }
    if scene.has_bonds() {
        // The RATTLE step of the internal motion between events: the scene's, or its default.
        let internal = scene.internal();
        let plan = crate::config::flexible_scene::FlexiblePlan::of(&internal)?;
        let step = crate::config::flexible_scene::rattle_settings(&internal, &plan).step;
        knobs.push(Knob {
            key: "rattle.step".to_owned(),
            linked: Vec::new(),
            label: "RATTLE step".to_owned(),
            unit: names.time.to_owned(),
            value: step,
            choices: Vec::new(),
        });
    }
    if knobs.is_empty() {
        let why = if let Some(k) = stepped.first() {
            format!(
                "pair[{k}] is an explicit step table (`steps`), which has no step to refine; give \
                 the smooth potential and its terraces instead (`pair.{k}.potential`, \
                 `pair.{k}.terraces`; `dmd tune` varies `terraces.step_kt` or `terraces.step`)"
            )
        } else {
            "the scene has no terraced potential (`pair.K.terraces.step_kt` or `step`), no \
             `search.max_step` of a searched potential and no smd `smd.dt`: its dynamics have no \
             discretisation error to trade against cost"
                .to_owned()
        };
        return Err(TuneError::NoKnob(why));
    }
    Ok(knobs)
}

/// The level rules a rule knob compares: the terrace energies of the paper's levels (equal
/// steps ΔV, 003 Eq. 7), B₂-matched at the scene temperature, the middle of each terrace's
/// range of `U`, and its shell average. All keep the levels, hence the reach and about the
/// cost; on the stepped Lennard-Jones fluid at ΔV = ε/2 the B₂-matched energies take the
/// smooth pressure from 16 % to 2 % of standard MD's (docs/VALIDATION.md, "Convergence of
/// terraced thermodynamics with ΔV"). Moving the outermost level out to the smooth
/// potential's switching window was measured too, and is not offered: it costs four times as
/// much at ε/2 and moves the smooth pressure further away. `(label, step_energy)`.
const LEVEL_RULES: [(&str, &str); 4] = [
    ("paper", "equal"),
    ("B2-matched", "virial"),
    ("midpoint", "midpoint"),
    ("shell-averaged", "volume-average"),
];

/// The rule knob of terraced pair `k` (whose ΔV knob is `step`): every terrace-energy rule of
/// [`LEVEL_RULES`] other than the scene's, at the scene's ΔV and levels, against the scene's
/// rule at the finest ΔV probed (the ΔV knob's reference, the same probe). Only for the
/// Lennard-Jones spheres and rods, whose radial profile the rules other than equal steps
/// need; none for a scene that gives its levels.
fn level_rules(scene: &Scene, k: usize, step: &Knob) -> Option<Knob> {
    use crate::config::scene::StepEnergySpec;
    let p = &scene.pair[k];
    let (pot, t) = (p.potential?, p.terraces.as_ref()?);
    // The rules other than equal steps need the potential's radial profile.
    if !pot.describe().has_profile() || t.levels.is_some() {
        return None;
    }
    let scene_rule = match t.step_energy {
        StepEnergySpec::Equal => "equal",
        StepEnergySpec::Midpoint => "midpoint",
        StepEnergySpec::VolumeAverage => "volume-average",
        StepEnergySpec::Virial => "virial",
    };
    let key = format!("pair.{k}.terraces.step_energy");
    let mut choices: Vec<Choice> = LEVEL_RULES
        .iter()
        .filter(|(_, energy)| *energy != scene_rule)
        .map(|(label, energy)| {
            let sets = vec![format!("{key}=\"{energy}\"")];
            Choice {
                label: format!("{key}={energy} ({label})"),
                recommend: sets.clone(),
                sets,
            }
        })
        .collect();
    let finest = step.values()[FACTORS.len() - 1];
    choices.push(Choice {
        label: format!("scene's rule at {}={}", step.key, short(finest)),
        sets: step.sets(finest),
        recommend: Vec::new(),
    });
    Some(Knob {
        key: format!("pair.{k}.terraces.step_energy"),
        linked: Vec::new(),
        label: format!("level rule of pair {k}"),
        unit: String::new(),
        value: 0.0,
        choices,
    })
}

/// The `--set` lines that shorten a probe: `options.time` or `events`, else a fraction of the
/// scene's lengths; outputs a probe does not use (trajectories, g(r), correlations other
/// than the MSD, the series) are dropped.
fn probe_overrides(
    given: &dyn Fn(&str) -> bool,
    scene: &Scene,
    options: &TuneOptions,
) -> (Vec<String>, String, Production) {
    let names = UnitNames::of(scene.units);
    let mut sets = Vec::new();
    let mut unit = Production::Scene;
    let production = match (
        options.time,
        options.events,
        scene.run.time,
        scene.run.events,
    ) {
        (Some(t), _, _, _) => {
            if given("run.events") {
                sets.push("run.events=".to_owned());
            }
            sets.push(format!("run.time={t}"));
            unit = Production::Time(t);
            format!("{t} {}", names.time)
        }
        (None, Some(n), _, _) => {
            if given("run.time") {
                sets.push("run.time=".to_owned());
            }
            sets.push(format!("run.events={}", n.round()));
            unit = Production::Events(n.round());
            format!("{n:.3e} events")
        }
        (None, None, Some(t), _) => {
            let t = t * PRODUCTION_FRACTION;
            sets.push(format!("run.time={t}"));
            unit = Production::Time(t);
            format!("{t} {}", names.time)
        }
        (None, None, None, Some(n)) => {
            let n = (n as f64 * PRODUCTION_FRACTION).round();
            sets.push(format!("run.events={n}"));
            unit = Production::Events(n);
            format!("{n:.3e} events")
        }
        (None, None, None, None) => "the scene's length".to_owned(),
    };
    let equilibration = if let Some(t) = scene.run.equilibration_time {
        let t = t * EQUILIBRATION_FRACTION;
        sets.push(format!("run.equilibration_time={t}"));
        format!("{t} {}", names.time)
    } else if scene.run.equilibration_events > 0 {
        let n = (scene.run.equilibration_events as f64 * EQUILIBRATION_FRACTION).round();
        sets.push(format!("run.equilibration_events={n}"));
        format!("{n:.3e} events")
    } else {
        "none".to_owned()
    };
    for k in ["trajectory", "gsd", "rdf", "vacf", "orientation_acf"] {
        if given(&format!("output.{k}")) {
            sets.push(format!("output.{k}="));
        }
    }
    if given("output.series") {
        sets.push("output.series=false".to_owned());
    }
    (
        sets,
        format!(
            "probes of {production} of production (first pass) after {equilibration} of \
             equilibration"
        ),
        unit,
    )
}

/// How a probe's production length is given: the production run of a lengthening is given
/// the same way.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Production {
    /// `run.time`, in the scene's time unit.
    Time(f64),
    /// `run.events`.
    Events(f64),
    /// The scene's own length, which the tune does not know how to scale.
    Scene,
}

impl Production {
    /// The `--set` line of a production `factor` times this one; `None` for the scene's.
    fn times(self, factor: f64) -> Option<String> {
        match self {
            Production::Time(t) => Some(format!("run.time={}", t * factor)),
            Production::Events(n) => Some(format!("run.events={}", (n * factor).round())),
            Production::Scene => None,
        }
    }
}

/// The `--set` lines that keep the scene's Andersen thermostat on in production
/// (`thermostat.during = "always"`), so that every probe samples the same temperature: in NVE
/// production each run keeps the energy it ended equilibration with, and its temperature
/// drifts from the bath's by a different few kelvin as U/N relaxes, which moves P by more
/// than its error bar (the differences between probes would then measure the runs, not the
/// knob). Empty for the smd engine (which thermostats during equilibration only) and for
/// scenes without an Andersen thermostat or already thermostatted throughout.
pub fn canonical_sets(scene: &Scene) -> Vec<String> {
    let t = &scene.thermostat;
    if scene.engine != Engine::Smd
        && t.kind == ThermostatKind::Andersen
        && t.during == ThermostatPhase::Equilibration
    {
        vec!["thermostat.during=always".to_owned()]
    } else {
        Vec::new()
    }
}

/// Runs one probe of `text` (the scene file's text) with `overrides`.
fn probe(text: &str, base: &Path, overrides: &[String], smooth: bool) -> Result<Probe, RunError> {
    let scene = Scene::from_str_with(text, overrides)?;
    let m = |value: f64, error: Option<f64>| Measured {
        value,
        error: error.unwrap_or(f64::NAN),
    };
    if scene.engine == Engine::Smd {
        let s = smd_engine::run(&scene, base, None)?;
        let ideal = if s.compressibility != 0.0 {
            s.pressure / s.compressibility
        } else {
            f64::NAN
        };
        return Ok(Probe {
            energy: m(
                s.potential_energy_per_body,
                Some(s.potential_energy_per_body_error),
            ),
            pressure: m(s.pressure, Some(s.pressure_error)),
            pressure_ideal: ideal,
            diffusion: s.diffusion_msd.map(|d| m(d, s.diffusion_msd_error)),
            cost: s.cpu_seconds / s.sim_time,
            length: s.sim_time,
            wall: s.wall_seconds,
            runs: 1,
            misses: 0,
        });
    }
    let s = run_scene(&scene, base, None, &mut Quiet)?;
    let (energy, pressure) = if smooth {
        match (s.potential_energy_per_body_smooth, s.pressure_smooth) {
            (Some(u), Some(p)) => (
                m(u, s.potential_energy_per_body_smooth_error),
                m(p, s.pressure_smooth_error),
            ),
            _ => {
                return Err(SceneError::invalid(
                    "output.smooth_estimators",
                    "a probe ran without the smooth estimators that dmd tune judges terraced \
                     scenes by (their cut-off must fit in half the box); set \
                     output.smooth_estimators = false to tune the terraced values",
                )
                .into());
            }
        }
    } else {
        (
            m(
                s.potential_energy_per_body,
                s.potential_energy_per_body_error,
            ),
            m(s.pressure, s.pressure_error),
        )
    };
    Ok(Probe {
        energy,
        pressure,
        pressure_ideal: s.pressure_ideal,
        diffusion: s.diffusion_msd.map(|d| m(d, s.diffusion_msd_error)),
        cost: s.cpu_seconds / s.sim_time,
        length: s.sim_time,
        wall: s.wall_seconds,
        runs: 1,
        misses: s.detected_misses + s.verified_misses.unwrap_or(0),
    })
}

/// Fills in the deviations of the rows of one knob (its last row is the reference) from
/// the reference.
fn deviations(rows: &mut [Row]) {
    let Some(Ok(reference)) = rows.last().map(|r| r.probe.clone()) else {
        return;
    };
    let n = rows.len();
    for (k, row) in rows.iter_mut().enumerate() {
        row.deviations = None;
        if let Ok(p) = &row.probe {
            let is_ref = k + 1 == n;
            let u_scale = reference.energy.value.abs();
            let p_scale = reference
                .pressure
                .value
                .abs()
                .max(reference.pressure_ideal.abs());
            row.deviations = Some([
                Deviation::of(p.energy, reference.energy, u_scale, is_ref),
                Deviation::of(p.pressure, reference.pressure, p_scale, is_ref),
            ]);
        }
    }
}

/// The recommended row of one knob's judged rows (the reference last) with the observables
/// (U/N, P) it certifies within the budget: the cheapest row within it in every certifiable
/// observable ([`certifiable`]); failing that, the cheapest coarser row within it in one of
/// them, U/N before P, the other then named as not certified (a user who asked for 2 % gets
/// the setting that meets it in U/N, and is told that P is not shown at that setting, rather
/// than the finest probe with no claim at all); the reference, certifying nothing, when no
/// observable is certifiable or no coarser row qualifies in any. `None` when the reference
/// gave no value.
fn decide(rows: &[&Row], budget: f64) -> Option<(usize, [bool; 2])> {
    let n = rows.len();
    if !matches!(rows.last().map(|r| &r.probe), Some(Ok(_))) {
        return None;
    }
    let which = certifiable(rows, budget);
    let tries = [which, [which[0], false], [false, which[1]]];
    tries
        .into_iter()
        .find_map(|w| match cheapest_within_of(rows, budget, w) {
            Some(r) if r + 1 < n => Some((r, w)),
            _ => None,
        })
        .or(Some((n - 1, [false, false])))
}

/// Fills in the deviations of the rows of one knob (its last row is the reference) and
/// returns its recommendation ([`decide`]).
fn judge(rows: &mut [Row], budget: f64) -> Option<(usize, [bool; 2])> {
    deviations(rows);
    let refs: Vec<&Row> = rows.iter().collect();
    decide(&refs, budget)
}

/// Which probe of one knob's judged rows (the reference last) to lengthen, together with the
/// reference, so that the knob may certify U/N and P both, and by what factor of their
/// production; `None` when the knob certifies both already or no lengthening can help.
///
/// A candidate is a coarser row, cheaper than the reference, that is within the budget in
/// each observable or could be: its difference minus twice its standard error is within
/// it (the difference may be noise), and its standard error is more than half the budget
/// (more length shrinks it). The cheapest candidate is lengthened; the factor aims the
/// standard error of its difference at `max(0.8 (budget − difference), budget / 2)`
/// (errors shrink as the square root of the length), at most [`MAX_LENGTHENING`]. Whether
/// it then qualifies is measured, not assumed: a difference that was noise shrinks, one
/// that is real stays.
pub fn lengthening(rows: &[&Row], budget: f64) -> Option<(usize, f64)> {
    let n = rows.len();
    let (_, certified) = decide(rows, budget)?;
    if certified == [true, true] {
        return None;
    }
    let reference_cost = rows[n - 1].cost();
    let mut best: Option<(usize, f64)> = None;
    for (k, r) in rows[..n - 1].iter().enumerate() {
        let Some(d) = r.deviations.filter(|_| r.cost() < reference_cost) else {
            continue;
        };
        let mut factor: f64 = 1.0;
        let mut possible = true;
        for d in d {
            if d.bound() <= budget {
                continue;
            }
            let (e, u) = (d.error, d.uncertainty);
            if !(u.is_finite() && u > 0.5 * budget && e - 2.0 * u < budget) {
                possible = false;
                break;
            }
            let aim = (0.8 * (budget - e)).max(0.5 * budget);
            factor = factor.max((u / aim).powi(2));
        }
        if possible && factor > 1.0 && best.is_none_or(|(b, _)| r.cost() < rows[b].cost()) {
            best = Some((k, factor.min(MAX_LENGTHENING)));
        }
    }
    best
}

/// Tunes the scene at `path`: runs the probes (reporting each through `progress` as
/// `(done, total, what)` before it starts) and judges them.
///
/// # Errors
/// [`TuneError`]: bad options or scene, no knob, a failed reference probe.
pub fn tune(
    path: &Path,
    options: &TuneOptions,
    progress: &mut dyn FnMut(usize, usize, &str),
) -> Result<Tuning, TuneError> {
    if !(options.target.is_finite() && options.target > 0.0) {
        return Err(TuneError::Option {
            option: "--target",
            problem: format!(
                "{} is not a relative error: give a positive number such as 0.02 (2 %)",
                options.target
            ),
        });
    }
    for (option, v) in [("--time", options.time), ("--events", options.events)] {
        if let Some(v) = v
            && !(v.is_finite() && v > 0.0)
        {
            return Err(TuneError::Option {
                option,
                problem: format!("{v} is not a positive length"),
            });
        }
    }
    if let Some(b) = options.wall_budget
        && !(b.is_finite() && b >= 0.0)
    {
        return Err(TuneError::Option {
            option: "--budget",
            problem: format!("{b} s is not a wall-clock budget: give a duration such as 9m"),
        });
    }
    let started = std::time::Instant::now();
    let (scene, base) = Scene::load(path, &options.overrides)?;
    if scene.chains.is_some() || scene.sweep.is_some() || scene.hmc.is_some() {
        return Err(TuneError::NoKnob(
            "scenes of `[chains]`, `[sweep]` or `[hmc]` are not tuned: tune the plain scene"
                .to_owned(),
        ));
    }
    let knobs = knobs(&scene)?;
    // A terraced scene's own U/N and P converge to the continuous model only as ΔV^½ (the cut
    // of the attractive tail, docs/VALIDATION.md); its smooth estimators measure the continuous
    // model along the run, which is what the terraces approximate: they are judged instead.
    let smooth = scene.engine != Engine::Smd && scene.wants_smooth_estimators();
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_owned(),
        source,
    })?;
    const ASKED: [&str; 8] = [
        "run.events",
        "run.time",
        "output.trajectory",
        "output.gsd",
        "output.rdf",
        "output.vacf",
        "output.orientation_acf",
        "output.series",
    ];
    let present = Scene::given_keys(&text, &options.overrides, &ASKED)?;
    let given = |key: &str| ASKED.iter().zip(&present).any(|(k, &p)| p && *k == key);
    let (mut shorten, mut length, production) = probe_overrides(&given, &scene, options);
    let canonical = canonical_sets(&scene);
    if !canonical.is_empty() {
        shorten.extend(canonical.iter().cloned());
        length.push_str(
            ", the Andersen thermostat on in production too (every probe at the bath temperature)",
        );
    }
    if smooth {
        // Every sample, so that short probes have enough for an error bar; the estimator's
        // cost per simulated time is the same for every probe and keeps their order of cost.
        shorten.push("output.smooth_every=1".to_owned());
    }
    // Every probe's scene is checked before the first runs.
    let mut plan: Vec<(usize, f64, Vec<String>)> = Vec::new();
    for (k, knob) in knobs.iter().enumerate() {
        for value in knob.values() {
            let mut sets = options.overrides.clone();
            sets.extend(shorten.iter().cloned());
            sets.extend(knob.sets(value));
            Scene::from_str_with(&text, &sets)?;
            plan.push((k, value, sets));
        }
    }
    // The scene's own setting is the same probe for every numeric knob, and a rule knob's
    // reference is its ΔV knob's: each distinct probe runs once.
    let is_scene = |k: usize, value: f64| {
        let knob: &Knob = &knobs[k];
        knob.choices.is_empty() && (value - knob.value).abs() <= 1e-12 * knob.value.abs()
    };
    let key_of = |k: usize, value: f64, sets: &[String]| {
        if is_scene(k, value) {
            Vec::new()
        } else {
            sets.to_vec()
        }
    };
    let mut distinct: Vec<Distinct> = Vec::new();
    // For each row, its distinct probe.
    let mut of_row = Vec::new();
    for (k, value, sets) in &plan {
        let key = key_of(*k, *value, sets);
        let d = match distinct.iter().position(|d| d.key == key) {
            Some(d) => d,
            None => {
                distinct.push(Distinct {
                    key,
                    sets: sets.clone(),
                    what: format!("{} = {}", knobs[*k].key, knobs[*k].show(*value)),
                    is_reference: false,
                    result: Err(String::new()),
                    equilibration_wall: 0.0,
                    first_length: f64::NAN,
                });
                distinct.len() - 1
            }
        };
        distinct[d].is_reference |= knobs[*k].values().last() == Some(value);
        of_row.push(d);
    }
    let mut total = distinct.len();
    let mut done = 0;
    for d in &mut distinct {
        progress(done, total, &d.what);
        let started = std::time::Instant::now();
        let r = probe(&text, &base, &d.sets, smooth);
        let wall = started.elapsed().as_secs_f64();
        d.result = match r {
            Err(e) if d.is_reference => {
                return Err(TuneError::Reference {
                    setting: d.what.clone(),
                    source: e,
                });
            }
            r => r.map_err(|e| e.to_string()),
        };
        if let Ok(p) = &d.result {
            d.equilibration_wall = (wall - p.wall).max(0.0);
            d.first_length = p.length;
        }
        done += 1;
    }
    let mut rows: Vec<Row> = plan
        .iter()
        .zip(&of_row)
        .map(|((k, value, _), &d)| Row {
            knob: *k,
            value: *value,
            probe: distinct[d].result.clone(),
            deviations: None,
        })
        .collect();
    let budget = options.target;
    let spans = |rows: &[Row]| -> Vec<std::ops::Range<usize>> {
        (0..knobs.len())
            .map(|k| {
                let a = rows.iter().position(|r| r.knob == k).unwrap_or(0);
                let n = rows[a..].iter().take_while(|r| r.knob == k).count();
                a..a + n
            })
            .collect()
    };
    let spans = spans(&rows);
    for span in &spans {
        deviations(&mut rows[span.clone()]);
    }
    // Rounds of lengthening: the probes whose noise keeps a knob from certifying U/N and P,
    // each pooled with an independent run of the missing length (its own seed and
    // equilibration), while the estimate of its wall time fits in the budget.
    let wall_budget = options.wall_budget.unwrap_or(WALL_BUDGET);
    let mut lengthened = Vec::new();
    for round in 2..=MAX_ROUNDS + 1 {
        // (distinct probe, factor of its production) wanted, knob by knob.
        let mut wanted: Vec<(usize, f64)> = Vec::new();
        for span in &spans {
            let refs: Vec<&Row> = rows[span.clone()].iter().collect();
            if let Some((r, factor)) = lengthening(&refs, budget) {
                let ds = [of_row[span.start + r], of_row[span.end - 1]];
                // The two probes at their longest wanted factor, or a smaller one that the
                // budget allows (not below 1.5: the error bar would shrink by less than a
                // fifth).
                let mut factor = factor;
                while factor >= 1.5 {
                    let mut plan = wanted.clone();
                    for d in ds {
                        match plan.iter_mut().find(|(w, _)| *w == d) {
                            Some((_, f)) => *f = f.max(factor),
                            None => plan.push((d, factor)),
                        }
                    }
                    let estimate: f64 = plan.iter().map(|&(d, f)| distinct[d].estimate(f)).sum();
                    if started.elapsed().as_secs_f64() + estimate <= wall_budget {
                        wanted = plan;
                        break;
                    }
                    factor = 1.0 + 0.7 * (factor - 1.0);
                }
            }
        }
        if wanted.is_empty() {
            break;
        }
        total += wanted.len();
        for (d, factor) in wanted {
            let probe_d = &distinct[d];
            let Ok(before) = probe_d.result.clone() else {
                continue;
            };
            // The missing production, in the unit the probe was given in; its simulated
            // time may differ from the plan's when it is counted in events.
            let Some(extra) =
                production.times((factor - 1.0) * before.length / probe_d.first_length)
            else {
                done += 1;
                continue;
            };
            let what = format!(
                "round {round}: {}, ×{factor:.1} the production ({} in all)",
                probe_d.what,
                before.runs + 1
            );
            progress(done, total, &what);
            let mut sets = probe_d.sets.clone();
            sets.push(extra);
            // An independent run: the scene's seed moved by a large odd stride per run.
            sets.push(format!(
                "seed={}",
                scene
                    .seed
                    .wrapping_add(1_000_003u64.wrapping_mul(before.runs as u64))
            ));
            let started_run = std::time::Instant::now();
            let r = probe(&text, &base, &sets, smooth);
            let wall = started_run.elapsed().as_secs_f64();
            let d_mut = &mut distinct[d];
            match r {
                Ok(more) => {
                    d_mut.equilibration_wall = (wall - more.wall).max(0.0);
                    let pooled = before.pooled(&more);
                    lengthened.push(format!(
                        "round {round}: {}: {} → {} {} of production ({} runs)",
                        d_mut.what,
                        short(before.length),
                        short(pooled.length),
                        UnitNames::of(scene.units).time,
                        pooled.runs
                    ));
                    d_mut.result = Ok(pooled);
                }
                Err(e) => lengthened.push(format!(
                    "round {round}: {}: the lengthening run failed ({e}); its first runs are kept",
                    d_mut.what
                )),
            }
            done += 1;
        }
        for (row, &d) in rows.iter_mut().zip(&of_row) {
            row.probe = distinct[d].result.clone();
        }
        for span in &spans {
            deviations(&mut rows[span.clone()]);
        }
    }
    progress(total, total, "done");
    let mut recommended = Vec::new();
    let mut certified = Vec::new();
    for span in &spans {
        let judged = judge(&mut rows[span.clone()], budget);
        recommended.push(judged.map(|(r, _)| span.start + r));
        certified.push(judged.map_or([false, false], |(_, c)| c));
    }
    Ok(Tuning {
        knobs,
        rows,
        target: options.target,
        budget,
        recommended,
        certified,
        units: UnitNames::of(scene.units),
        length,
        smooth,
        wall_budget,
        wall_seconds: started.elapsed().as_secs_f64(),
        lengthened,
    })
}

/// One distinct probe of a tune (the scene's own setting is shared by its numeric knobs, a
/// rule knob's reference is its ΔV knob's).
struct Distinct {
    /// What identifies it (empty for the scene's own setting).
    key: Vec<String>,
    /// Its `--set` lines.
    sets: Vec<String>,
    /// For the progress line.
    what: String,
    /// Whether it is a knob's reference (whose failure stops the tune).
    is_reference: bool,
    /// Its measurement, pooled over its runs.
    result: Result<Probe, String>,
    /// Wall-clock seconds of its last run's equilibration and set-up.
    equilibration_wall: f64,
    /// Simulated production time of its first run (the unit of its `--set` length).
    first_length: f64,
}

impl Distinct {
    /// Estimated wall-clock seconds of lengthening it to `factor` times its production: one
    /// more run of the missing production after its own equilibration, at the wall time per
    /// simulated time its runs took.
    fn estimate(&self, factor: f64) -> f64 {
        match &self.result {
            Ok(p) if p.length > 0.0 => self.equilibration_wall + (factor - 1.0).max(0.0) * p.wall,
            _ => f64::INFINITY,
        }
    }
}

/// How many times longer the probes of `row` and its reference would have to be for its
/// error bound to fall within `budget`, if its difference alone is within it (errors shrink as
/// the square root of the length); `None` if it already qualifies or its difference does not.
pub fn longer(row: &Row, budget: f64) -> Option<f64> {
    let [u, p] = row.deviations?;
    let factor = u.longer(budget)?.max(p.longer(budget)?);
    (factor > 1.0).then_some(factor)
}

/// `x` with up to 4 significant digits, as a scene would give it.
fn short(x: f64) -> String {
    let s = format!("{x:.4e}");
    match s.parse::<f64>() {
        Ok(v) if (1e-3..1e5).contains(&v.abs()) => {
            let t = format!("{v:.6}");
            t.trim_end_matches('0').trim_end_matches('.').to_owned()
        }
        Ok(v) => format!("{v:e}"),
        Err(_) => s,
    }
}

/// `m ± e` with the error to two significant digits.
fn pm(m: Measured) -> String {
    if m.error.is_finite() && m.error > 0.0 {
        let d = (1 - m.error.log10().floor() as i32).max(0) as usize;
        format!("{:.d$} ± {:.d$}", m.value, m.error)
    } else {
        format!("{:.4}", m.value)
    }
}

/// A relative deviation in per cent, `e ± u %`.
fn percent(d: Deviation) -> String {
    format!("{:.2} ± {:.2}", 100.0 * d.error, 100.0 * d.uncertainty)
}

impl Tuning {
    /// The table, for a terminal.
    pub fn table(&self) -> String {
        let u = self.units;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{:<34} {:>20} {:>18} {:>16} {:>16} {:>18} {:>14} {:>12}  within",
            "setting",
            format!(
                "U/N{} ({})",
                if self.smooth { " smooth" } else { "" },
                u.energy
            ),
            format!(
                "P{} ({})",
                if self.smooth { " smooth" } else { "" },
                u.pressure
            ),
            "err U/N (%)",
            "err P (%)",
            format!("D ({})", u.diffusion),
            format!("CPU s/{}", u.time),
            format!("prod ({})", u.time),
        );
        for (k, row) in self.rows.iter().enumerate() {
            let knob = &self.knobs[row.knob];
            let mut setting = if knob.choices.is_empty() {
                format!("{}={}", knob.key, short(row.value))
            } else {
                knob.show(row.value)
            };
            if k + 1 == self.rows.len() || self.rows[k + 1].knob != row.knob {
                setting.push_str(" (ref)");
            }
            match &row.probe {
                Ok(p) => {
                    let d = row.deviations.expect("judged");
                    let mark = if self.recommended[row.knob] == Some(k) {
                        "yes  <- recommended".to_owned()
                    } else if p.misses > 0 {
                        format!("no: {} missed events", p.misses)
                    } else if row.bound() <= self.budget {
                        "yes".to_owned()
                    } else {
                        "no".to_owned()
                    };
                    let _ = writeln!(
                        out,
                        "{setting:<34} {:>20} {:>18} {:>16} {:>16} {:>18} {:>14.4} {:>12}  {mark}",
                        pm(p.energy),
                        pm(p.pressure),
                        percent(d[0]),
                        percent(d[1]),
                        p.diffusion.map_or("-".to_owned(), pm),
                        p.cost,
                        if p.runs > 1 {
                            format!("{} ({} runs)", short(p.length), p.runs)
                        } else {
                            short(p.length)
                        },
                    );
                }
                Err(e) => {
                    let _ = writeln!(out, "{setting:<34} failed: {e}");
                }
            }
        }
        out
    }

    /// The recommendation: the `--set` lines, or why there is none.
    pub fn recommendation(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "Error = |difference from the finest setting| + its standard error, relative to |U/N| \
             and to max(|P|, ρkT), within {:.3} % for each knob (probed one at a time){}.",
            100.0 * self.target,
            if self.smooth {
                "; U/N and P of the smooth estimators (the continuous model along the terraced \
                 run)"
            } else {
                ""
            }
        );
        let _ = writeln!(
            out,
            "The tune took {:.0} s of wall time against a budget of {:.0} s; {}",
            self.wall_seconds,
            self.wall_budget,
            if self.lengthened.is_empty() {
                "no probe was lengthened (none whose noise alone kept a knob from certifying \
                 U/N and P, or none that fitted in the budget)."
                    .to_owned()
            } else {
                format!(
                    "lengthened, each pooled with independent runs, where noise kept a knob \
                     from certifying U/N and P:\n{}",
                    self.lengthened
                        .iter()
                        .map(|l| format!("#   {l}"))
                        .collect::<Vec<_>>()
                        .join("\n")
                )
            }
        );
        for (k, knob) in self.knobs.iter().enumerate() {
            let finest = self
                .rows
                .iter()
                .rposition(|r| r.knob == k)
                .expect("every knob has rows");
            if let Ok(p) = &self.rows[finest].probe
                && p.misses > 0
            {
                let _ = writeln!(
                    out,
                    "# {}: the finest probe missed {} events: it is no reference; refine the \
                     search (a smaller search.max_step) before trusting this knob.",
                    knob.label, p.misses
                );
            }
            match self.recommended[k] {
                Some(r) if r == finest => {
                    let next = &self.rows[finest - 1];
                    let _ = writeln!(
                        out,
                        "# {}: {} (the next coarser differs from it by {}).{}",
                        knob.label,
                        if knob.choices.is_empty() {
                            "no coarser setting is within the target at this probe length; the \
                             finest probed is recommended, and its own error is not known"
                        } else {
                            "no other rule at the scene's ΔV is within the target of the scene's \
                             rule at the finest ΔV at this probe length: keep the scene's rule"
                        },
                        next.deviations.map_or("?".to_owned(), |d| {
                            let w = if d[0].bound() >= d[1].bound() {
                                d[0]
                            } else {
                                d[1]
                            };
                            format!("{} %", percent(w))
                        }),
                        match longer(next, self.budget) {
                            Some(f) => format!(
                                " Its difference is within the target but not its error bar: \
                                 probes about {f:.0} times longer would tell (a larger \
                                 --budget, or --time)."
                            ),
                            None => String::new(),
                        }
                    );
                    for s in knob.recommend(self.rows[r].value) {
                        let _ = writeln!(out, "--set {s}");
                    }
                }
                Some(r) => {
                    let row = &self.rows[r];
                    let which = self.certified[k];
                    let first = self
                        .rows
                        .iter()
                        .position(|r| r.knob == k)
                        .expect("every knob has rows");
                    for (q, name) in ["U/N", "P"].iter().enumerate() {
                        if which[q] {
                            continue;
                        }
                        let rows = &self.rows[first..=finest];
                        let u = best_uncertainty(rows, q);
                        let other = ["U/N", "P"][1 - q];
                        // The smallest the difference of a coarser probe could be, at two
                        // standard errors.
                        let reach = rows[..rows.len() - 1]
                            .iter()
                            .filter_map(|r| {
                                r.deviations.map(|d| d[q].error - 2.0 * d[q].uncertainty)
                            })
                            .filter(|x| x.is_finite())
                            .fold(f64::INFINITY, f64::min);
                        // A rule knob's other probes are the other rules at the scene's ΔV,
                        // judged against the scene's rule at the finest ΔV.
                        let others = if knob.choices.is_empty() {
                            "coarser probe"
                        } else {
                            "other rule"
                        };
                        // The coarser probe closest to the target in this quantity (smallest
                        // bound).
                        let closest = rows[..rows.len() - 1]
                            .iter()
                            .filter_map(|r| r.deviations.map(|d| d[q]))
                            .filter(|d| d.bound().is_finite())
                            .min_by(|a, b| a.bound().total_cmp(&b.bound()));
                        let why = if reach >= self.budget {
                            format!(
                                "every {others} differs from the reference by more than the \
                                 target (at two standard errors, by {:.2} % at least), so longer \
                                 probes would not qualify one; a finer setting than the tune \
                                 probes (tune again from a finer scene value) would be needed \
                                 for {name} within the target",
                                100.0 * reach.max(0.0),
                            )
                        } else if u > self.budget {
                            format!(
                                "the standard error of its difference from the reference is at \
                                 best {:.2} % at this probe length, above the target, so no \
                                 setting can be shown within it (probes about {:.0} times longer \
                                 would tell: a larger --budget, or --time)",
                                100.0 * u,
                                (u / self.budget).powi(2).ceil().max(2.0),
                            )
                        } else if let Some(d) = closest.filter(|d| d.bound() <= self.budget) {
                            // Another probe meets the target in this quantity, but none meets
                            // it in both, and the recommendation went by the other.
                            format!(
                                "it is within the target only at another {others} (by {} %), \
                                 which is not within it in {other}",
                                percent(d)
                            )
                        } else {
                            // Precise enough to judge, and no other probe shown within: the
                            // closest says how far, and how much longer probes would have to
                            // be if its difference is within.
                            format!(
                                "no {others} is shown within the target in it at this probe \
                                 length (the closest differs from the reference by {} %, and \
                                 may be within only if that is noise){}",
                                closest.map_or("?".to_owned(), percent),
                                match closest.and_then(|d| d.longer(self.budget)) {
                                    Some(f) => format!(
                                        "; probes about {:.0} times longer would tell (a larger \
                                         --budget, or --time)",
                                        f.ceil().max(2.0)
                                    ),
                                    None => String::new(),
                                }
                            )
                        };
                        let _ = writeln!(
                            out,
                            "# {}: {name} is not certified: {why}. The recommendation rests on \
                             {other} alone; at the recommended setting {name} differs from the \
                             reference by {} %.",
                            knob.label,
                            row.deviations.map_or("?".to_owned(), |d| percent(d[q])),
                        );
                    }
                    let sets = knob.recommend(row.value);
                    if sets.is_empty() {
                        let _ = writeln!(out, "# {}: keep the scene's", knob.label);
                    }
                    for s in sets {
                        let _ = writeln!(
                            out,
                            "--set {s}    # {} {}: error ≤ {:.2} % in {}, {:.4} CPU s per {}",
                            knob.label,
                            knob.show(row.value),
                            100.0 * row.bound_of(which),
                            match which {
                                [true, true] => "U/N and P",
                                [true, false] => "U/N",
                                _ => "P",
                            },
                            row.cost(),
                            self.units.time
                        );
                    }
                }
                None => {
                    let _ = writeln!(
                        out,
                        "# {}: no setting could be judged (the reference probe gave no value)",
                        knob.label
                    );
                }
            }
        }
        out
    }

    /// Whether the recommended settings together are certified in U/N and in P: every knob's
    /// recommendation that changes the scene certifies it (a rule knob that keeps the
    /// scene's rule adds no setting, and takes no claim away).
    pub fn certified_all(&self) -> [bool; 2] {
        let mut all = [true; 2];
        for ((knob, c), r) in self
            .knobs
            .iter()
            .zip(&self.certified)
            .zip(&self.recommended)
        {
            let keeps = r.is_some_and(|r| knob.recommend(self.rows[r].value).is_empty());
            if !knob.choices.is_empty() && keeps {
                continue;
            }
            all[0] &= c[0];
            all[1] &= c[1];
        }
        all
    }

    /// The `--set` lines of the recommended settings.
    pub fn recommended_sets(&self) -> Vec<String> {
        self.knobs
            .iter()
            .zip(&self.recommended)
            .filter_map(|(knob, r)| r.map(|r| knob.recommend(self.rows[r].value)))
            .flatten()
            .collect()
    }

    /// The `--set` lines of every knob's finest setting (the references).
    pub fn reference_sets(&self) -> Vec<String> {
        self.knobs
            .iter()
            .flat_map(|k| {
                let v = k.values();
                k.recommend(v[v.len() - 1])
            })
            .collect()
    }

    /// Writes `tune.csv` (one row per probe, units in the header) and `tune.svg` (error
    /// bound against cost, one curve per knob, the target dashed) into `dir`; returns their
    /// paths.
    ///
    /// # Errors
    /// [`OutputError`].
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, OutputError> {
        std::fs::create_dir_all(dir).map_err(|e| OutputError {
            path: dir.to_owned(),
            message: e.to_string(),
        })?;
        let u = self.units;
        let mut csv = format!(
            "key,value,U_per_body{x} ({e}),U_per_body{x}_error ({e}),P{x} ({p}),P{x}_error ({p}),\
             D ({d}),D_error ({d}),cpu_seconds_per_{t} (s/{t}),production ({t}),runs,missed_events,U_rel_error,\
             U_rel_uncertainty,P_rel_error,P_rel_uncertainty,bound,within_target,recommended\n",
            x = if self.smooth { "_smooth" } else { "" },
            e = u.energy,
            p = u.pressure,
            d = u.diffusion,
            t = u.time
        );
        for (k, row) in self.rows.iter().enumerate() {
            let knob = &self.knobs[row.knob];
            let nan = Measured {
                value: f64::NAN,
                error: f64::NAN,
            };
            let (p, d) = match &row.probe {
                Ok(p) => (p.clone(), row.deviations.expect("judged")),
                Err(_) => (
                    Probe {
                        energy: nan,
                        pressure: nan,
                        pressure_ideal: f64::NAN,
                        diffusion: None,
                        cost: f64::NAN,
                        length: f64::NAN,
                        wall: f64::NAN,
                        runs: 0,
                        misses: 0,
                    },
                    [Deviation {
                        error: f64::NAN,
                        uncertainty: f64::NAN,
                    }; 2],
                ),
            };
            let diff = p.diffusion.unwrap_or(nan);
            let cells = [
                p.energy.value,
                p.energy.error,
                p.pressure.value,
                p.pressure.error,
                diff.value,
                diff.error,
                p.cost,
                p.length,
                p.runs as f64,
                p.misses as f64,
                d[0].error,
                d[0].uncertainty,
                d[1].error,
                d[1].uncertainty,
                row.bound(),
            ];
            if knob.choices.is_empty() {
                let _ = write!(csv, "{},{:e}", knob.key, row.value);
            } else {
                // A rule: its label (`pair.0.terraces.step_energy=virial`) and its index.
                let _ = write!(csv, "{},{:e}", knob.show(row.value), row.value);
            }
            for c in cells {
                let _ = write!(csv, ",{c:e}");
            }
            let _ = writeln!(
                csv,
                ",{},{}",
                row.bound() <= self.budget,
                self.recommended[row.knob] == Some(k)
            );
        }
        let csv_path = dir.join("tune.csv");
        write_atomically(&csv_path, csv.as_bytes())?;
        let mut lines: Vec<Line> = self
            .knobs
            .iter()
            .enumerate()
            .map(|(k, knob)| {
                let v = knob.values();
                Line::new(
                    format!(
                        "{} ({} … {})",
                        knob.label,
                        knob.show(v[0]),
                        knob.show(v[v.len() - 1])
                    ),
                    self.rows
                        .iter()
                        .filter(|r| r.knob == k && r.cost().is_finite())
                        // The reference's bound is 0 by definition: it is drawn at its cost.
                        .map(|r| (r.cost(), 100.0 * r.bound()))
                        .collect(),
                )
            })
            .collect();
        let costs: Vec<f64> = self
            .rows
            .iter()
            .map(Row::cost)
            .filter(|c| c.is_finite())
            .collect();
        let (lo, hi) = costs
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &c| (a.min(c), b.max(c)));
        if lo.is_finite() {
            let mut target = Line::new(
                format!("target, {:.3} %", 100.0 * self.budget),
                vec![(lo, 100.0 * self.budget), (hi, 100.0 * self.budget)],
            );
            target.dashed = true;
            lines.push(target);
        }
        let svg_path = dir.join("tune.svg");
        write_plot(
            &svg_path,
            &Plot {
                title: "Error against cost of each accuracy knob".to_owned(),
                caption: self.length.clone(),
                x_label: format!("CPU s per {}", u.time),
                y_label: "error bound vs finest setting (%)".to_owned(),
                lines,
            },
        )?;
        Ok(vec![csv_path, svg_path])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(knob: usize, value: f64, cost: f64, error: f64, uncertainty: f64) -> Row {
        let m = Measured {
            value: 1.0,
            error: 0.0,
        };
        Row {
            knob,
            value,
            probe: Ok(Probe {
                energy: m,
                pressure: m,
                pressure_ideal: 1.0,
                diffusion: None,
                cost,
                length: 1.0,
                wall: 1.0,
                runs: 1,
                misses: 0,
            }),
            deviations: Some([
                Deviation { error, uncertainty },
                Deviation {
                    error: 0.0,
                    uncertainty: 0.0,
                },
            ]),
        }
    }

    #[test]
    fn the_cheapest_row_within_the_budget_is_chosen() {
        // Coarse and cheap but off; the second cheapest qualifies only with its uncertainty
        // counted below the budget; the finest qualifies and costs most.
        let rows = [
            row(0, 2.0, 1.0, 0.05, 0.001),
            row(0, 1.0, 2.0, 0.008, 0.001),
            row(0, 0.5, 4.0, 0.002, 0.001),
            row(0, 0.25, 8.0, 0.0, 0.0),
        ];
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(cheapest_within(&refs, 0.01), Some(1));
        // The uncertainty counts: 0.008 + 0.001 exceeds 0.0085.
        assert_eq!(cheapest_within(&refs, 0.0085), Some(2));
        assert_eq!(cheapest_within(&refs, 0.1), Some(0));
        // A failed probe is never chosen, however cheap.
        let mut failed = row(0, 4.0, 0.1, 0.0, 0.0);
        failed.probe = Err("unstable".to_owned());
        failed.deviations = None;
        let refs: Vec<&Row> = std::iter::once(&failed).chain(rows.iter()).collect();
        assert_eq!(cheapest_within(&refs, 0.1), Some(1));
        // An unknown uncertainty (NaN) disqualifies.
        let unknown = row(0, 3.0, 0.5, 0.0, f64::NAN);
        let refs: Vec<&Row> = std::iter::once(&unknown).chain(rows.iter()).collect();
        assert_eq!(cheapest_within(&refs, 0.1), Some(1));
    }

    #[test]
    fn a_probe_that_missed_events_is_never_within_the_target() {
        // The cheapest row is within the budget on its averages but missed events: the next
        // cheapest is chosen, and pooling with a clean run keeps the misses.
        let mut missing = row(0, 2.0, 1.0, 0.001, 0.001);
        let rows = [row(0, 1.0, 2.0, 0.001, 0.001), row(0, 0.5, 4.0, 0.0, 0.0)];
        let refs: Vec<&Row> = std::iter::once(&missing).chain(rows.iter()).collect();
        assert_eq!(cheapest_within(&refs, 0.01), Some(0));
        if let Ok(p) = &mut missing.probe {
            p.misses = 3;
        }
        assert_eq!(missing.bound(), f64::INFINITY);
        let refs: Vec<&Row> = std::iter::once(&missing).chain(rows.iter()).collect();
        assert_eq!(cheapest_within(&refs, 0.01), Some(1));
        assert_eq!(decide(&refs, 0.01), Some((1, [true, true])));
        let clean = rows[0].probe.clone().unwrap();
        let pooled = missing.probe.as_ref().unwrap().pooled(&clean);
        assert_eq!((pooled.misses, pooled.runs), (3, 2));
    }

    /// A probe of U/N `u ± 0.001` and P `p ± p_err` at `cost`.
    fn probe_row(value: f64, u: f64, p: f64, p_err: f64, cost: f64) -> Row {
        Row {
            knob: 0,
            value,
            probe: Ok(Probe {
                energy: Measured {
                    value: u,
                    error: 0.001,
                },
                pressure: Measured {
                    value: p,
                    error: p_err,
                },
                pressure_ideal: 0.5,
                diffusion: None,
                cost,
                length: 1.0,
                wall: 1.0,
                runs: 1,
                misses: 0,
            }),
            deviations: None,
        }
    }

    #[test]
    fn a_quantity_too_noisy_for_the_target_is_not_certified_and_not_judged() {
        // P carries 2 % errors against a 1 % target: no setting can be shown within it in P.
        // U/N is certified, and the cheapest setting within 1 % in U/N is recommended.
        let mut rows = vec![
            probe_row(1.0, -3.20, 0.40, 0.01, 1.0),
            probe_row(0.5, -3.145, 0.42, 0.01, 2.0),
            probe_row(0.25, -3.125, 0.53, 0.01, 4.0),
            probe_row(0.125, -3.12, 0.53, 0.01, 8.0),
        ];
        assert_eq!(judge(&mut rows, 0.01), Some((1, [true, false])));
        // Every quantity precise enough: both judged, and P's 20 % keeps the coarse rows out.
        for r in &mut rows {
            if let Ok(p) = &mut r.probe {
                p.pressure.error = 0.0001;
            }
        }
        assert_eq!(judge(&mut rows, 0.01), Some((2, [true, true])));
        // Nothing certifiable: the finest probe, certifying nothing.
        for r in &mut rows {
            if let Ok(p) = &mut r.probe {
                p.pressure.error = 0.01;
                p.energy.error = 0.1;
            }
        }
        assert_eq!(judge(&mut rows, 0.01), Some((3, [false, false])));
    }

    /// The ΔV knob of pair 0 at 0.5 ε, as `knobs` gives it for a terraced scene.
    fn delta_v_knob() -> Knob {
        Knob {
            key: "pair.0.terraces.step".to_owned(),
            linked: Vec::new(),
            label: "ΔV of pair 0".to_owned(),
            unit: "ε".to_owned(),
            value: 0.5,
            choices: Vec::new(),
        }
    }

    #[test]
    fn a_rule_knob_that_keeps_the_scene_rule_takes_no_claim_away() {
        let step = delta_v_knob();
        let choice = |sets: Vec<String>| Choice {
            label: "rule".to_owned(),
            recommend: sets.clone(),
            sets,
        };
        let mut keep = choice(step.sets(0.125));
        keep.recommend = Vec::new();
        let rule = Knob {
            key: "pair.0.terraces.step_energy".to_owned(),
            linked: Vec::new(),
            label: "level rule of pair 0".to_owned(),
            unit: String::new(),
            value: 0.0,
            choices: vec![
                choice(vec!["pair.0.terraces.step_energy=\"virial\"".to_owned()]),
                choice(vec!["pair.0.terraces.step_energy=\"midpoint\"".to_owned()]),
                choice(vec![
                    "pair.0.terraces.step_energy=\"volume-average\"".to_owned(),
                ]),
                keep,
            ],
        };
        let rows: Vec<Row> = (0..8)
            .map(|k| {
                let mut r = row(k / 4, (k % 4) as f64, 1.0, 0.0, 0.0);
                if k < 4 {
                    r.value = 0.5 * FACTORS[k];
                }
                r
            })
            .collect();
        let mut t = tuning(
            vec![step, rule],
            rows,
            0.01,
            vec![Some(2), Some(7)],
            vec![[true, false], [false, false]],
        );
        // The ΔV knob's claim stands: the rule knob keeps the scene's rule.
        assert_eq!(t.certified_all(), [true, false]);
        assert_eq!(t.recommended_sets(), ["pair.0.terraces.step=0.25"]);
        // A rule that changes the scene without a claim of its own voids the claim.
        t.recommended[1] = Some(4);
        assert_eq!(t.certified_all(), [false, false]);
    }

    #[test]
    fn longer_probes_are_asked_for_only_when_the_difference_alone_is_within() {
        // 1 % off with a 2 % error bar against a 2 % target: (2 / (2 − 1))² = 4 times longer.
        let r = row(0, 1.0, 1.0, 0.01, 0.02);
        assert!((longer(&r, 0.02).unwrap() - 4.0).abs() < 1e-12);
        // Already within, or off by more than the target: no such advice.
        assert_eq!(longer(&row(0, 1.0, 1.0, 0.01, 0.005), 0.02), None);
        assert_eq!(longer(&row(0, 1.0, 1.0, 0.03, 0.001), 0.02), None);
    }

    #[test]
    fn deviations_are_relative_with_both_errors_in_quadrature() {
        let x = Measured {
            value: -9.0,
            error: 0.03,
        };
        let r = Measured {
            value: -10.0,
            error: 0.04,
        };
        let d = Deviation::of(x, r, 10.0, false);
        assert!((d.error - 0.1).abs() < 1e-15);
        assert!((d.uncertainty - 0.005).abs() < 1e-15);
        assert!((d.bound() - 0.105).abs() < 1e-15);
        assert_eq!(Deviation::of(x, r, 10.0, true).bound(), 0.0);
    }

    #[test]
    fn judging_scales_the_pressure_by_rho_kt_when_it_is_small() {
        let probe = |u: f64, p: f64| Probe {
            energy: Measured {
                value: u,
                error: 0.0,
            },
            pressure: Measured {
                value: p,
                error: 0.0,
            },
            pressure_ideal: 2.0,
            diffusion: None,
            cost: 1.0,
            length: 1.0,
            wall: 1.0,
            runs: 1,
            misses: 0,
        };
        let mut rows: Vec<Row> = [(-4.1, 0.2), (-4.0, 0.1)]
            .iter()
            .map(|&(u, p)| Row {
                knob: 0,
                value: 1.0,
                probe: Ok(probe(u, p)),
                deviations: None,
            })
            .collect();
        judge(&mut rows, 0.1);
        let d = rows[0].deviations.unwrap();
        assert!((d[0].error - 0.025).abs() < 1e-12);
        // P differs by 0.1 with |P_ref| = 0.1 < ρkT = 2: 5 %, not 100 %.
        assert!((d[1].error - 0.05).abs() < 1e-12);
    }

    /// Rows of one knob (the reference last) whose U/N is exact and whose P differs from the
    /// reference by `p[k] ± u[k]` (relative), at costs 1, 2, 4, 8.
    fn p_rows(p: [f64; 3], u: [f64; 3]) -> Vec<Row> {
        let mut rows: Vec<Row> = (0..3)
            .map(|k| row(0, k as f64, (1 << k) as f64, 0.0, 0.0))
            .collect();
        for (k, r) in rows.iter_mut().enumerate() {
            let d = r.deviations.as_mut().unwrap();
            d[1] = Deviation {
                error: p[k],
                uncertainty: u[k],
            };
        }
        rows.push(row(0, 3.0, 8.0, 0.0, 0.0));
        rows
    }

    #[test]
    fn lengthening_picks_the_cheapest_probe_that_noise_alone_keeps_out() {
        let b = 0.02;
        // P of the coarsest is off by far more than its noise (10 ± 1 %): never lengthened.
        // The second, 3.7 ± 2.1 %, may be within 2 % (3.7 − 4.2 < 2): lengthened until its
        // error bar is b/2, (2.1 / 1)² = 4.41 times. The third is within already (0.5 ± 1).
        let rows = p_rows([0.10, 0.037, 0.005], [0.01, 0.021, 0.01]);
        let refs: Vec<&Row> = rows.iter().collect();
        // The third row certifies both: nothing to lengthen.
        assert_eq!(lengthening(&refs, b), None);
        // Without it (its P 5 ± 1 %: off), the second is the candidate.
        let rows = p_rows([0.10, 0.037, 0.05], [0.01, 0.021, 0.01]);
        let refs: Vec<&Row> = rows.iter().collect();
        let (r, f) = lengthening(&refs, b).unwrap();
        assert_eq!(r, 1);
        assert!((f - 4.41).abs() < 1e-9, "{f}");
        // A difference within the target aims at 0.8 (b − e): 0.5 ± 3 % → (3 / 1.2)².
        let rows = p_rows([0.10, 0.005, 0.05], [0.01, 0.03, 0.01]);
        let refs: Vec<&Row> = rows.iter().collect();
        let (r, f) = lengthening(&refs, b).unwrap();
        assert_eq!(r, 1);
        assert!((f - 6.25).abs() < 1e-9, "{f}");
        // At most MAX_LENGTHENING.
        let rows = p_rows([0.10, 0.005, 0.05], [0.01, 0.2, 0.01]);
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(lengthening(&refs, b), Some((1, MAX_LENGTHENING)));
        // Every coarser probe off at two standard errors, or already precise (2.5 ± 0.4 %:
        // more length would not bring it in): nothing.
        let rows = p_rows([0.10, 0.09, 0.025], [0.01, 0.02, 0.004]);
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(lengthening(&refs, b), None);
        // The cheapest of two candidates.
        let rows = p_rows([0.03, 0.01, 0.05], [0.02, 0.02, 0.01]);
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(lengthening(&refs, b).map(|x| x.0), Some(0));
        // A candidate no cheaper than the reference is not worth lengthening.
        let mut rows = p_rows([0.10, 0.10, 0.01], [0.01, 0.01, 0.02]);
        if let Ok(p) = &mut rows[2].probe {
            p.cost = 8.0;
        }
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(lengthening(&refs, b), None);
    }

    #[test]
    fn pooled_probes_weigh_by_length_and_add_errors_as_independent_means() {
        let probe = |u: f64, e: f64, length: f64, cost: f64| Probe {
            energy: Measured { value: u, error: e },
            pressure: Measured {
                value: 2.0 * u,
                error: 2.0 * e,
            },
            pressure_ideal: 1.0,
            diffusion: None,
            cost,
            length,
            wall: length * cost,
            runs: 1,
            misses: 0,
        };
        // A run of 10 and one of 30: weights ¼ and ¾.
        let a = probe(-3.0, 0.02, 10.0, 1.0);
        let b = probe(-3.4, 0.01, 30.0, 3.0);
        let p = a.pooled(&b);
        assert!((p.energy.value - -3.3).abs() < 1e-12);
        assert!((p.pressure.value - -6.6).abs() < 1e-12);
        let e = (0.25f64 * 0.02).hypot(0.75 * 0.01);
        assert!((p.energy.error - e).abs() < 1e-15);
        assert!((p.pressure.error - 2.0 * e).abs() < 1e-15);
        // Cost: 100 CPU s over 40 time units.
        assert!((p.cost - 2.5).abs() < 1e-12);
        assert_eq!((p.length, p.runs), (40.0, 2));
        // Two equal runs: the error falls by √2.
        let q = a.pooled(&a);
        assert!((q.energy.error - 0.02 / 2f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn wall_budgets_read_seconds_minutes_and_hours() {
        assert_eq!(parse_wall("540"), Ok(540.0));
        assert_eq!(parse_wall("540s"), Ok(540.0));
        assert_eq!(parse_wall("9m"), Ok(540.0));
        assert_eq!(parse_wall("1.5h"), Ok(5400.0));
        assert!(parse_wall("9 minutes").is_err());
        assert!(parse_wall("-1").is_err());
        assert!(parse_wall("").is_err());
    }

    #[test]
    fn a_production_given_in_time_or_events_is_scaled_in_its_own_unit() {
        assert_eq!(
            Production::Time(10.0).times(3.3).as_deref(),
            Some("run.time=33")
        );
        assert_eq!(
            Production::Events(1e6).times(0.5).as_deref(),
            Some("run.events=500000")
        );
        assert_eq!(Production::Scene.times(2.0), None);
    }

    /// A tuning of `knobs` with `rows` at `target`, recommending `recommended` certified in
    /// `certified` (knob by knob), in reduced units.
    fn tuning(
        knobs: Vec<Knob>,
        rows: Vec<Row>,
        target: f64,
        recommended: Vec<Option<usize>>,
        certified: Vec<[bool; 2]>,
    ) -> Tuning {
        Tuning {
            knobs,
            rows,
            target,
            budget: target,
            recommended,
            certified,
            units: UnitNames::of(crate::config::scene::UnitSystem::Reduced),
            length: String::new(),
            smooth: true,
            wall_budget: WALL_BUDGET,
            wall_seconds: 0.0,
            lengthened: Vec::new(),
        }
    }

    /// The recommendation text of one ΔV knob (`delta_v_knob`) with `rows`, judged at
    /// `target`, recommending row `r` certified in `which`.
    fn recommendation_of(rows: Vec<Row>, target: f64, r: usize, which: [bool; 2]) -> String {
        tuning(
            vec![delta_v_knob()],
            rows,
            target,
            vec![Some(r)],
            vec![which],
        )
        .recommendation()
    }

    #[test]
    fn an_uncertified_quantity_is_named_with_why_noise_or_a_real_difference() {
        // P 0.5 ± 1.5 % at the two coarse probes: noise (the difference could be within 1 %).
        let noisy = p_rows([0.005, 0.005, 0.005], [0.015, 0.015, 0.015]);
        // P 5.8 ± 1.2 %: off at two standard errors, whatever the length.
        let off = p_rows([0.10, 0.07, 0.058], [0.012, 0.012, 0.012]);
        for (rows, noise) in [(noisy, true), (off, false)] {
            let refs: Vec<&Row> = rows.iter().collect();
            // U/N alone is judged: the cheapest probe is recommended in U/N.
            let (r, which) = decide(&refs, 0.01).unwrap();
            assert_eq!((r, which), (0, [true, false]));
            let text = recommendation_of(rows, 0.01, r, which);
            assert!(text.contains("P is not certified"), "{text}");
            assert_eq!(text.contains("times longer would tell"), noise, "{text}");
            assert_eq!(
                text.contains("longer probes would not qualify one"),
                !noise,
                "{text}"
            );
            assert!(text.contains("--set pair.0.terraces.step=0"), "{text}");
        }
    }

    #[test]
    fn a_quantity_precise_but_not_shown_within_leaves_the_other_to_recommend() {
        let text_of = |rows, r, which| recommendation_of(rows, 0.02, r, which);
        // P 1.5 ± 0.8 % at every coarser probe against 2 %: precise enough to judge (so P is
        // certifiable), none shown within (bound 2.3 %), none shown off (1.5 − 1.6 < 2). U/N
        // alone recommends the cheapest; P is named undecided, with the length that would tell:
        // (0.8 / (2 − 1.5))² = 2.56, so 3 times.
        let rows = p_rows([0.015, 0.015, 0.015], [0.008, 0.008, 0.008]);
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(certifiable(&refs, 0.02), [true, true]);
        assert_eq!(decide(&refs, 0.02), Some((0, [true, false])));
        let text = text_of(rows, 0, [true, false]);
        assert!(
            text.contains("P is not certified: no coarser probe is shown within"),
            "{text}"
        );
        assert!(text.contains("1.50 ± 0.80 %"), "{text}");
        assert!(text.contains("about 3 times longer would tell"), "{text}");
        assert!(
            text.contains(
                "at the recommended setting P differs from the reference by 1.50 ± 0.80 %"
            ),
            "{text}"
        );
        assert!(text.contains("error ≤ 0.00 % in U/N,"), "{text}");
        // 3.5 ± 0.8 %: within only if noise, and no length would show it within.
        let rows = p_rows([0.035, 0.035, 0.035], [0.008, 0.008, 0.008]);
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(decide(&refs, 0.02), Some((0, [true, false])));
        let text = text_of(rows, 0, [true, false]);
        assert!(
            text.contains("may be within only if that is noise)."),
            "{text}"
        );
        assert!(!text.contains("times longer"), "{text}");
        // U/N off everywhere and P within at the second probe: P alone recommends it.
        let mut rows = p_rows([0.03, 0.01, 0.03], [0.002, 0.002, 0.002]);
        for r in &mut rows[..3] {
            r.deviations.as_mut().unwrap()[0] = Deviation {
                error: 0.05,
                uncertainty: 0.002,
            };
        }
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(decide(&refs, 0.02), Some((1, [false, true])));
        // U/N within at the first probe only, P at the second only: U/N recommends the first,
        // and P is said to be within at another probe, not at the recommended one.
        let mut both = p_rows([0.05, 0.01, 0.05], [0.002, 0.002, 0.002]);
        both[1].deviations.as_mut().unwrap()[0].error = 0.05;
        both[2].deviations.as_mut().unwrap()[0].error = 0.05;
        let refs: Vec<&Row> = both.iter().collect();
        assert_eq!(decide(&refs, 0.02), Some((0, [true, false])));
        let text = text_of(both, 0, [true, false]);
        assert!(
            text.contains(
                "P is not certified: it is within the target only at another coarser probe \
                 (by 1.00 ± 0.20 %), which is not within it in U/N"
            ),
            "{text}"
        );
        assert!(!text.contains("times longer"), "{text}");
        // Neither within at any coarser probe: the finest, certifying nothing.
        for r in &mut rows[..3] {
            r.deviations.as_mut().unwrap()[1].error = 0.05;
        }
        let refs: Vec<&Row> = rows.iter().collect();
        assert_eq!(decide(&refs, 0.02), Some((3, [false, false])));
    }
}
