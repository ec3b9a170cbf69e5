//! From parameters to results in one call: build the system, equilibrate with velocity
//! rescaling, run NVE production with the observables, summarise. This is the layer a driver
//! (the `dmd` command, a validation) maps its scene onto.

use potential::{PairPotential, Smoothed};

use crate::observe::{Correlations, Observables, Rdf, Summary};
use crate::{Integrator, RunStats, Settings, Setup, SmdError, System};

/// Radial distribution function settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RdfConfig {
    /// Number of bins.
    pub bins: usize,
    /// Largest distance (default: half the shortest box edge).
    pub r_max: Option<f64>,
    /// Histogram every `every`-th sample (one histogram costs about as much as a step).
    pub every: u64,
}

impl Default for RdfConfig {
    fn default() -> Self {
        Self {
            bins: 200,
            r_max: None,
            every: 10,
        }
    }
}

/// Time-correlation settings (MSD, VACF, orientational ACF).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CorrelationConfig {
    /// Longest lag, in simulated time (rounded to whole sampling intervals).
    pub max_lag: f64,
    /// A new time origin every this many samples.
    pub origin_every: u64,
}

/// A whole run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunConfig {
    /// The initial state (its `temperature` is also the equilibration target).
    pub setup: Setup,
    /// Time step, skin, guard.
    pub settings: Settings,
    /// Steps of equilibration (velocity rescaling to the setup's temperature).
    pub equilibration_steps: u64,
    /// Rescale every this many equilibration steps.
    pub rescale_every: u64,
    /// Steps of NVE production.
    pub production_steps: u64,
    /// Sample the observables every this many production steps.
    pub sample_every: u64,
    /// The radial distribution function, if wanted.
    pub rdf: Option<RdfConfig>,
    /// The time correlations, if wanted.
    pub correlations: Option<CorrelationConfig>,
}

/// What a run produced.
#[derive(Clone, Debug)]
pub struct RunOutput {
    /// The observables of production.
    pub observables: Observables,
    /// Their summary (means with block errors, drift, fluctuation).
    pub summary: Summary,
    /// Cost of equilibration.
    pub equilibration: RunStats,
    /// Cost of production (observables included).
    pub production: RunStats,
    /// The final state.
    pub system: System,
}

/// Runs `config` with `potential`.
///
/// # Errors
/// Any [`SmdError`] of building the system and the integrator, or of a step; a bad RDF range
/// ([`SmdError::Parameter`] if `r_max` exceeds half the shortest box edge).
pub fn run<P: PairPotential>(
    config: &RunConfig,
    potential: Smoothed<P>,
) -> Result<RunOutput, SmdError> {
    let system = System::new(&config.setup)?;
    let side = system.lengths().min_element();
    let mut md = Integrator::new(system, potential, config.settings)?;
    let equilibration = md.equilibrate(
        config.equilibration_steps,
        config.rescale_every,
        config.setup.temperature,
    )?;
    let mut observables = Observables::default();
    if let Some(r) = config.rdf {
        let r_max = r.r_max.unwrap_or(0.5 * side);
        if r_max > 0.5 * side {
            return Err(SmdError::Parameter {
                name: "rdf r_max",
                value: r_max,
                why: "at most half the shortest box edge",
            });
        }
        observables.rdf = Some(Rdf::new(r.bins, r_max, r.every)?);
    }
    if let Some(c) = config.correlations {
        let interval = config.settings.dt * config.sample_every.max(1) as f64;
        let lags = (c.max_lag / interval).round().max(1.0) as usize;
        observables.correlations = Some(Correlations::new(interval, lags, c.origin_every)?);
    }
    let production = md.run(
        config.production_steps,
        config.sample_every,
        &mut observables,
    )?;
    let summary = observables.summary(md.system().n());
    Ok(RunOutput {
        observables,
        summary,
        equilibration,
        production,
        system: md.into_system(),
    })
}
