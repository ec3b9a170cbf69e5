//! The special functions of the free rigid body, written for binary64 and for parameters close
//! to 1: every routine takes the complementary parameter `m_c = 1 − m`.
//!
//! - [`Jacobi`]: sn, cn, dn by the descending Gauss transformation (DLMF 22.20(ii));
//! - [`complete_k`], [`incomplete_f`], [`complete_pi`]: Legendre's integrals from Carlson's
//!   symmetric forms ([`carlson_rf`], [`carlson_rj`], [`carlson_rc`]).

mod carlson;
mod jacobi;
mod legendre;

pub(crate) use carlson::rf;
pub use jacobi::{Jacobi, SnCnDn};
pub(crate) use legendre::pi_over_k;
pub use legendre::{complete_k, complete_pi, incomplete_f};

use crate::FreeError;

fn nonneg(function: &'static str, name: &'static str, v: f64) -> Result<(), FreeError> {
    if v >= 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(FreeError::ParameterOutOfRange {
            function,
            name,
            value: v,
        })
    }
}

fn at_most_one_zero(function: &'static str, x: f64, y: f64, z: f64) -> Result<(), FreeError> {
    let zeros = [x, y, z].iter().filter(|v| **v == 0.0).count();
    if zeros > 1 {
        Err(FreeError::ParameterOutOfRange {
            function,
            name: "number of zero arguments",
            value: zeros as f64,
        })
    } else {
        Ok(())
    }
}

/// Carlson's symmetric integral of the first kind `R_F(x, y, z)` (DLMF 19.16.1).
///
/// # Errors
/// [`FreeError::ParameterOutOfRange`] if an argument is negative or not finite, or more than one
/// is zero.
pub fn carlson_rf(x: f64, y: f64, z: f64) -> Result<f64, FreeError> {
    nonneg("carlson_rf", "x", x)?;
    nonneg("carlson_rf", "y", y)?;
    nonneg("carlson_rf", "z", z)?;
    at_most_one_zero("carlson_rf", x, y, z)?;
    Ok(carlson::rf(x, y, z))
}

/// Carlson's symmetric integral of the third kind `R_J(x, y, z, p)` (DLMF 19.16.2), `p > 0`.
///
/// # Errors
/// [`FreeError::ParameterOutOfRange`] if `x, y, z` are negative or not finite or more than one
/// is zero, or `p` is not positive and finite.
pub fn carlson_rj(x: f64, y: f64, z: f64, p: f64) -> Result<f64, FreeError> {
    nonneg("carlson_rj", "x", x)?;
    nonneg("carlson_rj", "y", y)?;
    nonneg("carlson_rj", "z", z)?;
    at_most_one_zero("carlson_rj", x, y, z)?;
    if !(p > 0.0 && p.is_finite()) {
        return Err(FreeError::ParameterOutOfRange {
            function: "carlson_rj",
            name: "p",
            value: p,
        });
    }
    Ok(carlson::rj(x, y, z, p))
}

/// Carlson's degenerate integral `R_C(x, y) = R_F(x, y, y)` (DLMF 19.2.17), `y > 0`.
///
/// # Errors
/// [`FreeError::ParameterOutOfRange`] if `x` is negative or `y` not positive (or either is not
/// finite).
pub fn carlson_rc(x: f64, y: f64) -> Result<f64, FreeError> {
    nonneg("carlson_rc", "x", x)?;
    if !(y > 0.0 && y.is_finite()) {
        return Err(FreeError::ParameterOutOfRange {
            function: "carlson_rc",
            name: "y",
            value: y,
        });
    }
    Ok(carlson::rc(x, y))
}
