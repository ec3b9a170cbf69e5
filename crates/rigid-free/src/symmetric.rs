//! The symmetric top, trigonometric (free-rigid-body.md §(b); seed 000 §II.B).
//!
//! With symmetry axis `e_s` (moment `I_s`) and the other two moments `I⊥`, the body-frame
//! angular velocity precesses about `e_s` at `ω_p = (1 − I_s/I⊥) ω_s(0)`, and
//! `A(t) = R_s(ω_p t) · exp(−(t/I⊥) W(L_b(0))) · A(0)`: a uniform rotation about the lab-fixed
//! `L` at the rate `|L|/I⊥`, followed by a body rotation about `e_s`. Two sines and cosines per
//! evaluation, no elliptic functions.

use crate::attitude::LabRotation;
use glam::{DMat3, DVec3};

/// Free motion of a symmetric top.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SymmetricTop {
    /// Symmetry axis j and the two others, (j, k, l) cyclic.
    axes: [usize; 3],
    omega_p: f64,
    /// `|L|/I⊥`.
    rate: f64,
    rotation: LabRotation,
    omega0: DVec3,
}

impl SymmetricTop {
    /// From the symmetry axis, the moments, `r0 = A(0)ᵀ` and the non-zero body `ω(0)`.
    pub(crate) fn new(axis: usize, moments: [f64; 3], r0: DMat3, omega: DVec3) -> Self {
        let axes = [axis, (axis + 1) % 3, (axis + 2) % 3];
        let (i_s, i_perp) = (moments[axis], moments[axes[1]]);
        let l_body = DVec3::from(moments) * omega;
        let l = l_body.length();
        Self {
            axes,
            omega_p: (1.0 - i_s / i_perp) * omega[axis],
            rate: l / i_perp,
            rotation: LabRotation::new(r0 * l_body / l, r0),
            omega0: omega,
        }
    }

    /// The precession rate of `ω` about the symmetry axis in the body frame.
    pub fn precession_rate(&self) -> f64 {
        self.omega_p
    }

    #[inline]
    fn rotate_body(&self, v: DVec3, s: f64, c: f64) -> DVec3 {
        let [_, k, l] = self.axes;
        let mut out = v;
        out[k] = c * v[k] + s * v[l];
        out[l] = c * v[l] - s * v[k];
        out
    }

    /// Body-frame angular velocity at time `t`: `R_s(ω_p t) ω(0)`.
    #[inline]
    pub fn omega(&self, t: f64) -> DVec3 {
        let (s, c) = crate::trig::sin_cos(self.omega_p * t);
        self.rotate_body(self.omega0, s, c)
    }

    /// Orientation `R(t) = A(t)ᵀ` and body-frame angular velocity at time `t`.
    #[inline]
    pub(crate) fn orientation_omega(&self, t: f64) -> (DMat3, DVec3) {
        let (s1, c1) = crate::trig::sin_cos(self.rate * t);
        let b = self.rotation.apply(s1, c1);
        let (s, c) = crate::trig::sin_cos(self.omega_p * t);
        // R(t) = B(t)ᵀ R_s(φ)ᵀ mixes columns k and l of B(t)ᵀ = exp((t/I⊥) W(L_lab)) R0.
        let [_, k, l] = self.axes;
        let mut r = b;
        *r.col_mut(k) = b.col(k) * c + b.col(l) * s;
        *r.col_mut(l) = b.col(l) * c - b.col(k) * s;
        (r, self.rotate_body(self.omega0, s, c))
    }
}
