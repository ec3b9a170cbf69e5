//! The asymmetric top exactly on the separatrix, `m_c = 0` (`L² = 2E I2`): the elliptic
//! functions degenerate to hyperbolic ones and the theta series to a closed form
//! (free-rigid-body.md, "Exactly on the separatrix", **[derived]**):
//!
//! ```text
//! ω = (ω1m sech v, ω2m tanh v, ω3m sech v),   v = ω_p t + ε,
//! ψ = (L/I3) t + (L/I3)(2E I3 − L²)/ω_p · [G(v) − G(ε)],
//! G(v) = v/L² + a/(L² b) · atan(a tanh v / b),   a = I3 ω3m,  b = √(L² − a²).
//! ```

use crate::asymmetric::Invariants;
use crate::axes::{AxisOrder, to_invariant_frame};
use glam::{DMat3, DVec3};

/// Free motion of an asymmetric top on its separatrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeparatrixTop {
    order: AxisOrder,
    i: DVec3,
    amp: DVec3,
    omega_p: f64,
    eps: f64,
    /// `L/I3`, the uniform part of ψ.
    rate: f64,
    /// `(L/I3)(2E I3 − L²)/ω_p`, in the scaled units of `g_*`.
    coef: f64,
    /// `1/L²`, `a/(L² b)`, `a/b` in scaled units, and `G(ε)`.
    g_lin: f64,
    g_atan: f64,
    a_over_b: f64,
    g_eps: f64,
    inv_l: f64,
    h: DMat3,
}

impl SeparatrixTop {
    /// Set-up from the ordered moments and state with `Δ2 = 0` and `ω1 ≠ 0 ≠ ω3`.
    pub(crate) fn new(
        order: AxisOrder,
        i: DVec3,
        omega: DVec3,
        inv: &Invariants,
        r0: DMat3,
    ) -> Self {
        let [d1, _, d3] = inv.delta;
        let w = inv.w;
        let unscale = 1.0 / inv.scale;
        let (i1, i2, i3) = (i.x, i.y, i.z);
        let s1 = if w.x < 0.0 { -1.0 } else { 1.0 };
        let s3 = if w.z < 0.0 { -1.0 } else { 1.0 };
        let amp_s = DVec3::new(
            s1 * (d3 / (i1 * (i1 - i3))).sqrt(),
            -s1 * (d3 / (i2 * (i2 - i3))).sqrt(),
            s3 * (d1 / (i3 * (i3 - i1))).sqrt(),
        );
        let omega_p_s = s3 * (i2 - i3) * (d1 / (i1 * i2 * i3 * (i3 - i2))).sqrt();
        // sinh ε = tanh ε / sech ε = (ω2/ω2m)/(ω1/ω1m): no clamping of tanh ε to (−1, 1).
        let eps = ((w.y / amp_s.y) / (w.x / amp_s.x)).asinh();
        let l_s = (i * w).length();
        let a = i3 * amp_s.z.abs();
        let b = ((l_s - a) * (l_s + a)).sqrt();
        let g_lin = 1.0 / (l_s * l_s);
        let g_atan = a / (l_s * l_s * b);
        let a_over_b = a / b;
        let g_eps = eps * g_lin + g_atan * (a_over_b * eps.tanh()).atan();
        let l = (i * omega).length();
        let t0 = to_invariant_frame(i * omega, 1.0 / l);
        Self {
            order,
            i,
            amp: amp_s * unscale,
            omega_p: omega_p_s * unscale,
            eps,
            rate: l_s / i3 * unscale,
            // (L/I3)(2E I3 − L²)/ω_p = −(L/I3) Δ3/ω_p.
            coef: -(l_s / i3) * d3 / omega_p_s,
            g_lin,
            g_atan,
            a_over_b,
            g_eps,
            inv_l: 1.0 / l,
            h: r0 * order.matrix().transpose() * t0.transpose(),
        }
    }

    #[inline]
    fn omega_ordered(&self, v: f64) -> DVec3 {
        let sech = 1.0 / v.cosh();
        self.amp * DVec3::new(sech, v.tanh(), sech)
    }

    /// Body-frame angular velocity (caller's axes) at time `t`.
    #[inline]
    pub fn omega(&self, t: f64) -> DVec3 {
        self.order
            .unordered(self.omega_ordered(self.omega_p * t + self.eps))
    }

    /// Orientation `R(t) = A(t)ᵀ` and body-frame angular velocity at time `t`.
    #[inline]
    pub(crate) fn orientation_omega(&self, t: f64) -> (DMat3, DVec3) {
        let v = self.omega_p * t + self.eps;
        let w = self.omega_ordered(v);
        let g = v * self.g_lin + self.g_atan * (self.a_over_b * v.tanh()).atan();
        let psi = self.rate * t + self.coef * (g - self.g_eps);
        let (sp, cp) = crate::trig::sin_cos(psi);
        let t_now = to_invariant_frame(self.i * w, self.inv_l);
        let hr = DMat3::from_cols(
            self.h.x_axis * cp + self.h.y_axis * sp,
            self.h.y_axis * cp - self.h.x_axis * sp,
            self.h.z_axis,
        );
        (self.order.mul_right(hr * t_now), self.order.unordered(w))
    }
}
