//! The asymmetric top: Jacobi elliptic functions for `ω(t)`, a theta series for the rotation
//! about `L` (free-rigid-body.md §(c), after R. van Zon and J. Schofield, J. Comput. Phys. 225,
//! 145 (2007); seed 000 §II.B), with the robustness fixes of the sheet:
//!
//! - the axis order and `m_c` come from the same cancellation-free `Δ2 = L² − 2E I2`, so
//!   `m_c ≥ 0` always, and `m_c` is computed directly (never as `1 − m`) and handed to the
//!   elliptic routines;
//! - `η` comes from a Carlson form of `F(ψ0 | m_c)` that does not cancel as `m → 0`;
//! - the secular rate `A2` comes from the closed form with `Π(n|m)/K`, evaluated by an AGM that
//!   shares the table of sn/cn/dn, so it stays cheap and exact near the separatrix where the
//!   `coth`/`q`-series needs hundreds of terms.

use crate::axes::{AxisOrder, to_invariant_frame};
use crate::elliptic::{Jacobi, pi_over_k, rf};
use crate::exact::Dd;
use crate::theta::ThetaSeries;
use crate::trig::sin_cos;
use glam::{DMat3, DVec3};

/// The invariants of an ordered state (axis 2 intermediate, axis 3 circled by `L`), computed on
/// an angular velocity scaled by a power of two so that no square under- or overflows.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Invariants {
    /// `L² − 2E I_k`, `k = 1, 2, 3`, of the scaled angular velocity.
    pub(crate) delta: [f64; 3],
    /// The power of two the angular velocity was multiplied by.
    pub(crate) scale: f64,
    /// The scaled ordered angular velocity.
    pub(crate) w: DVec3,
}

impl Invariants {
    /// `Δ_k` of `i` (ordered moments) and `omega` (ordered, not all zero), cancellation-free:
    /// `Δ1 = I2ω2²(I2 − I1) + I3ω3²(I3 − I1)` and cyclically (free-rigid-body.md, **[fix]**).
    /// `Δ1`, `Δ3` are sums of like-signed terms; `Δ2`, whose terms cancel near the separatrix,
    /// is evaluated in double-double ([`delta_mid`](Self::delta_mid)).
    /// `delta2` is [`delta_mid`](Self::delta_mid) of the same ordered state, computed by the
    /// caller to decide the ordering.
    pub(crate) fn new(i: DVec3, omega: DVec3, delta2: f64) -> Self {
        let scale = pow2_scale(omega);
        let w = omega * scale;
        let q = i * w * w; // I_k ω_k²
        Self {
            delta: [
                q.y * (i.y - i.x) + q.z * (i.z - i.x),
                delta2,
                q.x * (i.x - i.z) + q.y * (i.y - i.z),
            ],
            scale,
            w,
        }
    }

    /// `Δ2 = I_a ω_a² (I_a − I_mid) + I_c ω_c² (I_c − I_mid)` of the angular velocity scaled as in
    /// [`Invariants::new`], for any axis order (intermediate moment on `mid`), in double-double
    /// so that its sign (which decides the ordering) and its value (which gives `m_c`) are those
    /// of the exact inputs.
    pub(crate) fn delta_mid(i: DVec3, omega: DVec3, a: usize, mid: usize, c: usize) -> f64 {
        let w = omega * pow2_scale(omega);
        let (ta, tc) = (
            i[a] * w[a] * w[a] * (i[a] - i[mid]),
            i[c] * w[c] * w[c] * (i[c] - i[mid]),
        );
        let plain = ta + tc;
        // Far from the separatrix the terms do not cancel (|Δ2| ≥ ½ of their magnitudes) and
        // binary64 is within a few ulp; only a cancelling sum needs the exact evaluation.
        if plain.abs() >= 0.5 * (ta.abs() + tc.abs()) {
            return plain;
        }
        let term = |k: usize| {
            Dd::prod(w[k], w[k])
                .mul_f64(i[k])
                .mul(Dd::diff(i[k], i[mid]))
        };
        term(a).add(term(c)).value()
    }
}

/// The power of two that brings the largest component of `v` (non-zero) near 1, so that no
/// square under- or overflows.
fn pow2_scale(v: DVec3) -> f64 {
    let big = v.abs().max_element();
    // The binary exponent from the bits (subnormals count as 2⁻¹⁰²²).
    let e = (((big.to_bits() >> 52) & 0x7ff) as i64 - 1023).clamp(-1000, 1000);
    f64::from_bits(((1023 - e) as u64) << 52)
}

/// `AGM(1, b)` by the plain iteration (quadratic convergence).
fn agm(mut a: f64, mut b: f64) -> f64 {
    for _ in 0..64 {
        if a - b <= f64::EPSILON * a {
            break;
        }
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    0.5 * (a + b)
}

/// Free motion of an asymmetric top off the separatrix (`0 < m_c ≤ 1`, `m > 0`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AsymmetricTop {
    order: AxisOrder,
    /// Ordered moments.
    i: DVec3,
    /// Amplitudes `(ω1m, ω2m, ω3m)`: `ω = (ω1m cn, ω2m sn, ω3m dn)(ω_p t + ε)`.
    amp: DVec3,
    omega_p: f64,
    eps: f64,
    jacobi: Jacobi,
    theta: ThetaSeries,
    a1: f64,
    a2: f64,
    inv_l: f64,
    /// `Gᵀ = R0 Πᵀ T(L_b(0))ᵀ`: the invariant frame's axes in the lab.
    h: DMat3,
}

impl AsymmetricTop {
    /// Set-up from the ordered moments and state. `inv` are the invariants of `omega`, with
    /// `Δ2 > 0` (the sign the ordering guarantees) and `Δ3 ≠ 0`.
    pub(crate) fn new(
        order: AxisOrder,
        i: DVec3,
        omega: DVec3,
        inv: &Invariants,
        r0: DMat3,
    ) -> Self {
        let [d1, d2, d3] = inv.delta;
        let w = inv.w;
        let unscale = 1.0 / inv.scale;
        let (i1, i2, i3) = (i.x, i.y, i.z);
        // free-rigid-body.md §(c): m, m_c directly from the Δ's.
        let m = (d3 * (i2 - i1) / (d1 * (i2 - i3))).clamp(0.0, 1.0);
        let m_c = (d2 * (i3 - i1) / (d1 * (i3 - i2))).clamp(0.0, 1.0);
        let s1 = if w.x < 0.0 { -1.0 } else { 1.0 };
        let s3 = if w.z < 0.0 { -1.0 } else { 1.0 };
        let amp_s = DVec3::new(
            s1 * (d3 / (i1 * (i1 - i3))).sqrt(),
            -s1 * (d3 / (i2 * (i2 - i3))).sqrt(),
            s3 * (d1 / (i3 * (i3 - i1))).sqrt(),
        );
        // The factor I2 − I3 carries the sign of ω_p in both orderings.
        let omega_p_s = s3 * (i2 - i3) * (d1 / (i1 * i2 * i3 * (i3 - i2))).sqrt();
        let jacobi = Jacobi::new_unchecked(m_c);
        let agm_m = jacobi.agm(); // π/(2K)

        // Phase: sn0, cn0 ≥ 0, dn0 of the initial state; ε = F(atan2(sn0, cn0) | m) by
        // DLMF 19.25.5, sn0 · R_F(cn0², dn0², 1).
        let (cn0, sn0, dn0) = (w.x / amp_s.x, w.y / amp_s.y, w.z / amp_s.z);
        let eps = sn0 * rf(cn0 * cn0, dn0 * dn0, 1.0);

        // Nome q = exp(−πK'/K) = exp(−2 AGM(1,√m_c) K'), K' = π/(2 AGM(1, √m)).
        let k_prime = std::f64::consts::FRAC_PI_2 / agm(1.0, m.sqrt());
        let q = (-2.0 * agm_m * k_prime).exp();
        // η = s3 (π/2K) F(ψ0 | m_c), tan ψ0 = √(I1(I3−I2)/(I3(I2−I1))), in the Carlson form
        // √α R_F(β, β + mα, α + β) that does not cancel as m → 0 (free-rigid-body.md **[fix]**).
        let alpha = (i1 * (i3 - i2)).abs();
        let beta = (i3 * (i2 - i1)).abs();
        let gamma = (i2 * (i3 - i1)).abs();
        let f_psi0 = alpha.sqrt() * rf(beta, beta + m * alpha, gamma);
        let theta = ThetaSeries::new(q, s3 * agm_m * f_psi0);
        let (s0, c0) = sin_cos(agm_m * eps);
        let (r0_, i0_) = theta.eval(s0, c0);
        let a1 = i0_.atan2(r0_);

        // L and the secular rate (closed form, free-rigid-body.md **[derived]**):
        // A2 = L/I3 + L(I3−I1)/(I1 I3) Π(n|m)/K − sgn(I3−I1) π|ω_p|/(2K),
        // n = −I3(I2−I1)/(I1(I3−I2)).
        let l = (i * omega).length();
        let l_s = (i * w).length();
        let n = -i3 * (i2 - i1) / (i1 * (i3 - i2));
        let a2_s = l_s / i3 + l_s * (i3 - i1) / (i1 * i3) * pi_over_k(&jacobi, n)
            - (i3 - i1).signum() * omega_p_s.abs() * agm_m;

        let t0 = to_invariant_frame(i * omega, 1.0 / l);
        let h = r0 * order.matrix().transpose() * t0.transpose();
        Self {
            order,
            i,
            amp: amp_s * unscale,
            omega_p: omega_p_s * unscale,
            eps,
            jacobi,
            theta,
            a1,
            a2: a2_s * unscale,
            inv_l: 1.0 / l,
            h,
        }
    }

    /// The parameter `m_c = 1 − m` of the elliptic functions.
    pub fn m_c(&self) -> f64 {
        self.jacobi.m_c()
    }

    /// The period of `ω(t)`, `4K/|ω_p|`.
    pub fn period(&self) -> f64 {
        4.0 * self.jacobi.quarter_period() / self.omega_p.abs()
    }

    /// How many Gauss transformations and theta terms an evaluation costs.
    pub fn cost(&self) -> (usize, u32) {
        (self.jacobi.levels(), self.theta.terms())
    }

    /// Body-frame angular velocity (caller's axes) at time `t`.
    #[inline]
    pub fn omega(&self, t: f64) -> DVec3 {
        let (sx, cx) = sin_cos((self.omega_p * t + self.eps) * self.jacobi.agm());
        let f = self.jacobi.at_phase(sx, cx);
        self.order
            .unordered(self.amp * DVec3::new(f.cn, f.sn, f.dn))
    }

    /// Orientation `R(t) = A(t)ᵀ` and body-frame angular velocity (caller's axes) at time `t`.
    #[inline]
    pub(crate) fn orientation_omega(&self, t: f64) -> (DMat3, DVec3) {
        // One phase x = πu/(2K) serves both the Jacobi functions and the theta series.
        let (sx, cx) = sin_cos((self.omega_p * t + self.eps) * self.jacobi.agm());
        let f = self.jacobi.at_phase(sx, cx);
        let w = self.amp * DVec3::new(f.cn, f.sn, f.dn);
        let (r, i) = self.theta.eval(sx, cx);
        let inv = 1.0 / (r * r + i * i).sqrt();
        let (s, c) = sin_cos(self.a1 + self.a2 * t);
        // ψ = A1 + A2 t − arg(r + i·i): cos ψ, sin ψ without forming the angle.
        let (cp, sp) = ((c * r + s * i) * inv, (s * r - c * i) * inv);
        let t_now = to_invariant_frame(self.i * w, self.inv_l);
        // R(t) = A(t)ᵀ = Gᵀ R3(ψ)ᵀ T(L_b(t)) Π with R3(ψ) = [[c, s, 0], [−s, c, 0], [0, 0, 1]].
        let hr = DMat3::from_cols(
            self.h.x_axis * cp + self.h.y_axis * sp,
            self.h.y_axis * cp - self.h.x_axis * sp,
            self.h.z_axis,
        );
        (self.order.mul_right(hr * t_now), self.order.unordered(w))
    }
}
