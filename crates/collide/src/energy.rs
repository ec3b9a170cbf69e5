//! Energy conservation fixes the size of the impulse: the quadratic for `S`.
//!
//! Every rule of this crate moves the participants' momenta along one fixed direction in
//! velocity space, scaled by an unknown scalar `S` (003 Eqs. 18–20; 000 §IV.A, §IV.B). The
//! kinetic energy then changes by `a S² + b S`, where
//!
//! - `a = ½ Σ (impulse direction)·M⁻¹·(impulse direction) > 0` (the inverse effective mass along
//!   the impulse), and
//! - `b` = the generalised velocity along the impulse direction; for the terrace rule
//!   `b = F·v_ij + τ_ij·ω_i + τ_ji·ω_j = −U̇_ij` (003 Eqs. 12 and 21).
//!
//! Energy conservation with a potential-energy change `ΔV` is the quadratic
//! `a S² + b S + ΔV = 0` (003 Eq. 21; the quadratic of 000 §IV.A). After the event the
//! generalised velocity is `b' = b + 2aS`.
//!
//! - **Crossed**: real roots exist and the physical one is the root that vanishes as `ΔV → 0`,
//!   the positive branch if `U̇ < 0` (`b > 0`) and the negative one if `U̇ > 0` (`b < 0`), as both
//!   papers prescribe. Then `b' = sign(b)·√(b² − 4aΔV)`: the pair keeps going the way it went.
//! - **Reflected**: no real root, not enough kinetic energy to climb the step. The pair
//!   stays on its terrace, `ΔV = 0`, and `S` is the nonzero root `−b/a`: `b' = −b`. A hard core
//!   is `ΔV = +∞` and always reflects.
//!
//! # Numerics
//!
//! The root is taken in the form `S = −2ΔV / (b + sign(b)·√D)`, `D = b² − 4aΔV`, whose
//! denominator adds two numbers of the same sign: no cancellation, so `S` is accurate to a few
//! ulps when `ΔV` is tiny next to the kinetic energy or the approach `b` is slow. The
//! discriminant itself is evaluated with Kahan's fused-multiply-add correction, so that `D` is
//! nearly exact in `a`, `b`, `ΔV` even when `b² ≈ 4aΔV`.
//!
//! When `D` is within round-off of zero (the kinetic energy along the impulse equals the step
//! to within [`THRESHOLD_ULPS`] ulps) the event is a **reflection**: crossing would leave the pair
//! exactly on the step with `U̇ = 0`, where the next root search has no sign to follow, while a
//! reflection sends it cleanly back with `b' = −b`. Both conserve energy; the tie goes to the one
//! that keeps the simulation well posed. `b = ±0` (an exactly grazing event) takes the sign of
//! its zero.

use crate::CollideError;

/// What an event did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Outcome {
    /// The pair crossed the step: potential energy `ΔV` was exchanged with kinetic energy.
    Crossed,
    /// The pair bounced off the step: no potential energy was exchanged (always, for a hard
    /// core).
    Reflected,
}

/// The solution of the energy equation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Impulse {
    /// What happened.
    pub outcome: Outcome,
    /// The scalar `S` multiplying the impulse direction the rule was given.
    pub s: f64,
    /// Potential energy gained by the pair: `ΔV` if it crossed, `0` if it was reflected. The
    /// kinetic energy changed by exactly minus this.
    pub delta_v: f64,
}

/// A discriminant within this many ulps (relative to `b² + 4|aΔV|`) of zero counts as zero, and
/// the event is a reflection. The coefficients `a` and `b` carry a few ulps of round-off each from
/// the dot products that formed them; a crossing this close to the threshold is not resolved by
/// the inputs anyway.
pub const THRESHOLD_ULPS: f64 = 16.0;

/// Solves `a S² + b S + ΔV = 0` for the physical root (see the [module docs](self)).
///
/// `delta_v = +∞` is a hard core (always a reflection).
///
/// # Errors
/// - [`CollideError::NoImpulse`] if `a` is zero (the impulse direction moves nothing);
/// - [`CollideError::NotFinite`] if `a` or `b` is NaN or infinite (a bad velocity, force,
///   torque or mass upstream);
/// - [`CollideError::PotentialChange`] if `delta_v` is NaN or `−∞`;
/// - [`CollideError::Overflow`] if `S` overflows.
#[inline]
pub fn solve(a: f64, b: f64, delta_v: f64) -> Result<Impulse, CollideError> {
    if !(a > 0.0 && a < f64::INFINITY && b.is_finite()) {
        return Err(bad_coefficients(a));
    }
    if delta_v == f64::INFINITY {
        // A hard core: the common case of hard-body simulations, kept on the fast path.
        return finite(reflect(a, b), a, b, delta_v);
    }
    if !delta_v.is_finite() {
        return Err(CollideError::PotentialChange(delta_v));
    }
    let d = discriminant(a, b, delta_v);
    if d.is_nan() || d == f64::INFINITY {
        // b² or 4aΔV overflowed (or both, giving NaN); -∞ alone is an effectively infinite
        // barrier and reflects correctly below.
        return Err(CollideError::Overflow { a, b, delta_v });
    }
    let tolerance = THRESHOLD_ULPS * f64::EPSILON * (b * b + 4.0 * (a * delta_v).abs());
    let impulse = if d > tolerance {
        // b + sign(b)√D never cancels; sign(±0) = ±1 picks a branch for an exactly grazing event.
        let s = -2.0 * delta_v / (b + d.sqrt().copysign(b));
        Impulse {
            outcome: Outcome::Crossed,
            s,
            delta_v,
        }
    } else {
        reflect(a, b)
    };
    finite(impulse, a, b, delta_v)
}

#[inline(always)]
fn finite(impulse: Impulse, a: f64, b: f64, delta_v: f64) -> Result<Impulse, CollideError> {
    if impulse.s.is_finite() {
        Ok(impulse)
    } else {
        Err(CollideError::Overflow { a, b, delta_v })
    }
}

/// The reflection root of `a S² + b S = 0`: `S = −b/a`.
#[inline(always)]
fn reflect(a: f64, b: f64) -> Impulse {
    Impulse {
        outcome: Outcome::Reflected,
        s: -b / a,
        delta_v: 0.0,
    }
}

/// Names what is wrong with coefficients that failed the fast check.
#[cold]
#[inline(never)]
fn bad_coefficients(a: f64) -> CollideError {
    if a.is_nan() || a == f64::INFINITY {
        CollideError::NotFinite(
            "the inverse effective mass along the impulse (a mass, force, torque or direction)",
        )
    } else if a <= 0.0 {
        CollideError::NoImpulse("zero effective inverse mass along the impulse")
    } else {
        CollideError::NotFinite(
            "the approach rate b = -dU/dt (a velocity, angular velocity, force or torque)",
        )
    }
}

/// `b² − 4ac` with Kahan's correction: when the two products nearly cancel, their rounding
/// errors (recovered exactly by fused multiply-adds) are added back, so the result is accurate
/// to a few ulps of `b²` rather than of the (possibly much smaller) difference.
#[inline(always)]
fn discriminant(a: f64, b: f64, c: f64) -> f64 {
    let p = b * b;
    let q = 4.0 * a * c;
    let d = p - q;
    if 3.0 * d.abs() >= p + q.abs() {
        // Less than a factor of 3 of cancellation: the plain difference is good enough.
        return d;
    }
    let dp = b.mul_add(b, -p);
    let dq = (4.0 * a).mul_add(c, -q);
    d + (dp - dq)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn residual(a: f64, b: f64, i: &Impulse) -> f64 {
        (a * i.s * i.s + b * i.s + i.delta_v).abs()
    }

    #[test]
    fn crossing_keeps_direction_reflection_reverses_it() {
        // Slow approach onto a barrier too high: reflected, b' = -b.
        let r = solve(1.0, -1.0, 1.0).unwrap();
        assert_eq!(r.outcome, Outcome::Reflected);
        assert_eq!(r.s, 1.0);
        assert_eq!(-1.0 + 2.0 * 1.0 * r.s, 1.0);
        // Enough energy: crossed, b' keeps the sign of b and |b'| = sqrt(b² - 4aΔV).
        let c = solve(1.0, -3.0, 2.0).unwrap();
        assert_eq!(c.outcome, Outcome::Crossed);
        let b_after = -3.0 + 2.0 * c.s;
        assert!((b_after - (-1.0)).abs() < 1e-15, "{b_after}");
        // Into a well from either side.
        for b in [-2.0, 2.0] {
            let w = solve(0.5, b, -1.5).unwrap();
            assert_eq!(w.outcome, Outcome::Crossed);
            let b_after = b + 2.0 * 0.5 * w.s;
            assert_eq!(b_after.signum(), b.signum());
            assert!(residual(0.5, b, &w) < 1e-15);
        }
    }

    #[test]
    fn hard_core_always_reflects() {
        for b in [-1e-300, -1.0, -1e300, 0.0, 1.0] {
            let r = solve(2.0, b, f64::INFINITY).unwrap();
            assert_eq!(r.outcome, Outcome::Reflected);
            assert_eq!(r.s, -b / 2.0);
            assert_eq!(r.delta_v, 0.0);
        }
    }

    #[test]
    fn tiny_step_has_no_cancellation() {
        // The textbook (-b + sqrt(b² - 4ac)) / 2a loses every digit here; the stable form keeps
        // S = -c/b (1 + O(ac/b²)) to full precision.
        let (a, b, c) = (1.0, 1.0, 1e-20);
        let r = solve(a, b, c).unwrap();
        assert_eq!(r.outcome, Outcome::Crossed);
        let textbook = (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
        assert_eq!(textbook, 0.0);
        assert!((r.s - (-1e-20)).abs() <= 1e-35, "{}", r.s);
    }

    #[test]
    fn slow_approach_into_a_well() {
        // b → 0 with a well: S → ±sqrt(-ΔV/a), no loss of precision.
        let r = solve(2.0, -1e-12, -8.0).unwrap();
        assert_eq!(r.outcome, Outcome::Crossed);
        assert!((r.s + 2.0).abs() < 1e-12);
        assert!(residual(2.0, -1e-12, &r) < 1e-14);
    }

    #[test]
    fn exactly_grazing_takes_the_sign_of_zero() {
        let plus = solve(1.0, 0.0, -1.0).unwrap();
        let minus = solve(1.0, -0.0, -1.0).unwrap();
        assert_eq!(
            (plus.outcome, minus.outcome),
            (Outcome::Crossed, Outcome::Crossed)
        );
        assert_eq!(plus.s, 1.0);
        assert_eq!(minus.s, -1.0);
        // Grazing a barrier: a reflection with zero impulse, nothing changes.
        let graze = solve(1.0, 0.0, 1.0).unwrap();
        assert_eq!(graze.outcome, Outcome::Reflected);
        assert_eq!(graze.s, 0.0);
    }

    #[test]
    fn energy_exactly_at_the_barrier_reflects() {
        // b² = 4aΔV exactly.
        let r = solve(0.5, -2.0, 2.0).unwrap();
        assert_eq!(r.outcome, Outcome::Reflected);
        assert_eq!(r.s, 4.0);
        // A hair above the barrier in energy (ΔV one part in 10⁹ lower) still crosses, and ends
        // with the small remaining approach rate.
        let c = solve(0.5, -2.0, 2.0 * (1.0 - 1e-9)).unwrap();
        assert_eq!(c.outcome, Outcome::Crossed);
        let b_after = -2.0 + 2.0 * 0.5 * c.s;
        let expected = -(4.0f64 * 1e-9).sqrt();
        assert!(
            (b_after / expected - 1.0).abs() < 1e-6,
            "{b_after} vs {expected}"
        );
        // Within round-off of the barrier: reflected.
        let t = solve(0.5, -2.0, 2.0 * (1.0 - 2.0 * f64::EPSILON)).unwrap();
        assert_eq!(t.outcome, Outcome::Reflected);
    }

    #[test]
    fn discriminant_is_accurate_under_cancellation() {
        // b² and 4ac agree to 1e-16 relative: the naive difference is 0 or one ulp of b².
        let b = 1.0 + f64::EPSILON;
        let (a, c) = (0.25, 1.0);
        // Exact: (1+e)² - 1 = 2e + e².
        let exact = 2.0 * f64::EPSILON + f64::EPSILON * f64::EPSILON;
        assert_eq!(discriminant(a, b, c), exact);
    }

    #[test]
    fn huge_steps() {
        // A barrier 1e30 times the kinetic energy: reflected; a well as deep: crossed with
        // kinetic energy 1e30 after.
        let r = solve(1.0, -1.0, 1e30).unwrap();
        assert_eq!(r.outcome, Outcome::Reflected);
        let w = solve(1.0, -1.0, -1e30).unwrap();
        assert_eq!(w.outcome, Outcome::Crossed);
        assert!(residual(1.0, -1.0, &w) <= 1e30 * 4.0 * f64::EPSILON);
    }

    #[test]
    fn bad_inputs_are_named() {
        assert!(matches!(
            solve(0.0, 1.0, 1.0),
            Err(CollideError::NoImpulse(_))
        ));
        assert!(matches!(
            solve(-1.0, 1.0, 1.0),
            Err(CollideError::NoImpulse(_))
        ));
        assert!(matches!(
            solve(f64::NAN, 1.0, 1.0),
            Err(CollideError::NotFinite(_))
        ));
        assert!(matches!(
            solve(1.0, f64::NAN, 1.0),
            Err(CollideError::NotFinite(_))
        ));
        assert!(matches!(
            solve(1.0, f64::INFINITY, 1.0),
            Err(CollideError::NotFinite(_))
        ));
        assert!(matches!(
            solve(1.0, 1.0, f64::NAN),
            Err(CollideError::PotentialChange(_))
        ));
        assert!(matches!(
            solve(1.0, 1.0, f64::NEG_INFINITY),
            Err(CollideError::PotentialChange(_))
        ));
        assert!(matches!(
            solve(1e-300, 1e300, 1.0),
            Err(CollideError::Overflow { .. })
        ));
        assert!(matches!(
            solve(1.0, 1e200, 1.0),
            Err(CollideError::Overflow { .. })
        ));
        // A barrier so high that 4aΔV overflows is still just a reflection.
        assert_eq!(solve(4.0, -1.0, 1e308).unwrap().outcome, Outcome::Reflected);
    }
}
