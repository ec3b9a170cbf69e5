//! Why a potential, a terrace map or a quadrature refused its input.

use thiserror::Error;

/// A bad input or an impossible request. Every variant names the offending quantity; no function
/// of this crate returns NaN in place of one of these.
#[derive(Clone, Debug, PartialEq, Error)]
#[non_exhaustive]
pub enum PotentialError {
    /// A parameter of a potential, a smoothing window or a rule outside its domain.
    #[error("parameter {name} = {value} is invalid: it must be {why}")]
    Parameter {
        /// Name of the parameter (as in the constructor's documentation).
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        why: &'static str,
    },
    /// The bodies overlap so deeply that the potential is infinite (centres coincide, the
    /// effective distance is zero or negative) or too large for binary64: there is no finite
    /// force or torque to return.
    #[error(
        "the bodies overlap at centre distance {r}: the potential is infinite or overflows \
         there ({what}), so force and torques are not defined"
    )]
    Overlap {
        /// Centre distance `|r_ij|`.
        r: f64,
        /// Which quantity is infinite (for example `effective distance r_e <= 0`).
        what: &'static str,
    },
    /// An input that must be a finite number is NaN or infinite.
    #[error("{0} is not finite")]
    NotFinite(&'static str),
    /// A terrace level within the tolerance of the potential's minimum: the terrace below it
    /// would have zero width (003 §V), which makes events pile up at a tangency.
    #[error(
        "level {level} lies within {tolerance:e} of the potential's minimum {minimum}: the \
         terrace below it would have zero width (003 §V); choose other levels or ask for \
         NearMinimum::Shift"
    )]
    LevelAtMinimum {
        /// The level.
        level: f64,
        /// The potential's minimum.
        minimum: f64,
        /// The absolute tolerance used.
        tolerance: f64,
    },
    /// A level below the potential's minimum: no pair can ever cross it.
    #[error("level {level} lies below the potential's minimum {minimum}: no pair can cross it")]
    LevelBelowMinimum {
        /// The level.
        level: f64,
        /// The potential's minimum.
        minimum: f64,
    },
    /// A level at `U = 0`: every potential that decays to zero crosses it at every distance, so
    /// the reach would be infinite and far-apart pairs would sit on it.
    #[error(
        "a level at U = {0} (zero): far-apart pairs would sit on it and the reach would be \
         infinite; offset the levels (the paper uses (k - 1/2) dV)"
    )]
    LevelAtZero(f64),
    /// Levels that are not strictly increasing.
    #[error("levels must increase strictly: level {index} = {value} follows {previous}")]
    UnsortedLevels {
        /// Index of the offending level.
        index: usize,
        /// Its value.
        value: f64,
        /// The level before it.
        previous: f64,
    },
    /// Two levels within round-off of each other: the terrace between them has no width.
    #[error("levels {index} and {} ({a} and {b}) are within round-off of each other", index + 1)]
    CoincidentLevels {
        /// Index of the first of the two levels.
        index: usize,
        /// The first level.
        a: f64,
        /// The second level.
        b: f64,
    },
    /// A level at or above the hard core.
    #[error("level {level} is not below the hard-core level {core}")]
    LevelAboveCore {
        /// The level.
        level: f64,
        /// The hard-core level.
        core: f64,
    },
    /// The lengths of parallel lists disagree (levels and their step energies).
    #[error("{what}: expected {expected} values, got {got}")]
    Length {
        /// Which list.
        what: &'static str,
        /// How many were expected.
        expected: usize,
        /// How many were given.
        got: usize,
    },
    /// More levels than the map accepts ([`MAX_LEVELS`](crate::MAX_LEVELS)).
    #[error("{0} levels requested; at most {max} are accepted (raise the step or lower the core)", max = crate::MAX_LEVELS)]
    TooManyLevels(usize),
    /// A value of `U` at or above the hard core: no terrace holds it.
    #[error("U = {u} is at or above the hard-core level {core}: the pair is inside the core")]
    InsideCore {
        /// The value asked about.
        u: f64,
        /// The hard-core level.
        core: f64,
    },
    /// A terrace index out of range.
    #[error("terrace {index} does not exist: the map has terraces 0..={last}")]
    TerraceIndex {
        /// The index given.
        index: usize,
        /// The highest valid index.
        last: usize,
    },
    /// The potential stays beyond the level out to the end of the numerical search: the reach
    /// is infinite or larger than the search range.
    #[error(
        "the potential still reaches level {level} at distance {searched_to}: the reach is \
         unbounded or beyond the search range"
    )]
    UnboundedReach {
        /// The level.
        level: f64,
        /// The largest distance examined.
        searched_to: f64,
    },
    /// A radial profile without the single well this crate's placement rules assume.
    #[error("radial profile: {0}")]
    Profile(&'static str),
    /// A quadrature that did not reach its tolerance within its subdivision budget.
    #[error(
        "quadrature did not converge: estimated error {error:e} above the tolerance {tolerance:e} \
         after {intervals} subintervals"
    )]
    Quadrature {
        /// The final error estimate.
        error: f64,
        /// The tolerance asked for.
        tolerance: f64,
        /// Subintervals used.
        intervals: usize,
    },
}

/// `Ok(value)` if `value` is finite and strictly positive.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, PotentialError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(PotentialError::Parameter {
            name,
            value,
            why: "finite and > 0",
        })
    }
}

/// `Ok(value)` if `value` is finite and not negative.
pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64, PotentialError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(PotentialError::Parameter {
            name,
            value,
            why: "finite and >= 0",
        })
    }
}
