//! Uniform rotation about a fixed axis: the spherical rotor, steady spin about a principal axis,
//! and the linear rotor with its decoupled spin left out (free-rigid-body.md §(a)).
//!
//! `ω` is constant in the body and in the lab and `A(t) = exp(−t W(ω)) A(0)`: the orientation
//! turns by `|ω| t` about the fixed lab axis `ω_lab/|ω|`.

use crate::attitude::LabRotation;
use glam::{DMat3, DVec3};

/// Rotation at constant angular velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniformRotation {
    rotation: LabRotation,
    rate: f64,
    omega: DVec3,
}

impl UniformRotation {
    /// From the orientation `r0 = A(0)ᵀ` and the (non-zero) body-frame angular velocity.
    pub(crate) fn new(r0: DMat3, omega: DVec3) -> Self {
        let rate = omega.length();
        Self {
            rotation: LabRotation::new(r0 * omega / rate, r0),
            rate,
            omega,
        }
    }

    /// The constant body-frame angular velocity.
    #[inline]
    pub fn omega(&self) -> DVec3 {
        self.omega
    }

    /// Orientation `R(t) = A(t)ᵀ`.
    #[inline]
    pub(crate) fn orientation(&self, t: f64) -> DMat3 {
        let (s, c) = crate::trig::sin_cos(self.rate * t);
        self.rotation.apply(s, c)
    }
}
