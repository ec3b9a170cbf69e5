//! Why a system could not be built or a run could not go on.

use std::path::PathBuf;

use potential::PotentialError;
use rigid_free::FreeError;
use thiserror::Error;

/// A bad input, or an integration that broke down. Every variant says what and where; no
/// function of this crate hands back NaN in place of one of these.
#[derive(Clone, Debug, PartialEq, Error)]
#[non_exhaustive]
pub enum SmdError {
    /// A number outside its domain (a mass, a density, a time step, …).
    #[error("parameter {name} = {value} is invalid: it must be {why}")]
    Parameter {
        /// Name of the parameter, as in the documentation of the function that took it.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        why: &'static str,
    },
    /// A count outside its domain (bodies, steps, bins, …).
    #[error("{name} = {value} is invalid: it must be {why}")]
    Count {
        /// Name of the count.
        name: &'static str,
        /// The value given.
        value: u64,
        /// What it must be.
        why: &'static str,
    },
    /// Lists of per-body data whose lengths disagree, or data that does not fit the body model.
    #[error("{0}")]
    Inconsistent(String),
    /// The periodic box is too small for the minimum-image convention with this list radius.
    #[error(
        "box side {side} is not larger than twice the neighbour-list radius {radius} (cut-off \
         r_u plus skin): a body would interact with two images of another; use a bigger box, \
         more bodies, or a thinner skin"
    )]
    BoxTooSmall {
        /// The shortest box edge.
        side: f64,
        /// The neighbour-list radius.
        radius: f64,
    },
    /// A rigid-body input rigid-free refused (moments, attitude, angular velocity).
    #[error("rigid body: {0}")]
    Body(#[from] FreeError),
    /// A potential parameter refused by dmd-potential.
    #[error("potential: {0}")]
    Potential(#[from] PotentialError),
    /// Two bodies came so close that the potential has no finite force: the time step is far
    /// too large, or the initial state overlaps.
    #[error(
        "step {step} (t = {time}): bodies {i} and {j} overlap: {source}; the time step is too \
         large for this state, or the initial configuration overlaps"
    )]
    Overlap {
        /// Steps completed before the failed force evaluation.
        step: u64,
        /// Simulated time of the failed evaluation.
        time: f64,
        /// First body.
        i: usize,
        /// Second body.
        j: usize,
        /// What the potential reported.
        source: PotentialError,
    },
    /// The integration blew up: a non-finite quantity, or the total energy moved further from
    /// its reference than the stability guard allows.
    #[error(
        "step {step} (t = {time}): the integration is unstable: {what}; reduce the time step \
         (or widen Settings::guard if the change is intended)"
    )]
    Unstable {
        /// Steps completed when the failure was detected.
        step: u64,
        /// Simulated time.
        time: f64,
        /// What went wrong, with the numbers.
        what: String,
    },
    /// An output file could not be written.
    #[error("cannot write {path}: {message}")]
    Output {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// `Ok(value)` if `value` is finite and strictly positive.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, SmdError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SmdError::Parameter {
            name,
            value,
            why: "finite and > 0",
        })
    }
}

/// `Ok(value)` if `value` is finite and not negative.
pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64, SmdError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(SmdError::Parameter {
            name,
            value,
            why: "finite and >= 0",
        })
    }
}
