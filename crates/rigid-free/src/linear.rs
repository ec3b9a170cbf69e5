//! The linear rotor of seed 003 §V: a rod whose only rotational state is its unit axis `s` and
//! the angular velocity `ω ⊥ s` (its spin about `s` is decoupled and left out).
//!
//! With a zero moment along `s` and equal moments `I` across it, `L = I ω` is constant, so `ω`
//! is constant and the axis turns uniformly about it: `s(t) = cos(|ω|t) s + sin(|ω|t) ω̂ × s`.
//! One sine and cosine per evaluation; no attitude matrix is formed.

use crate::FreeError;
use crate::attitude::check_vector;
use glam::DVec3;

/// Free motion of a rod: the lab axis `s(t)` and the constant lab angular velocity.
///
/// ```
/// use glam::DVec3;
/// use rigid_free::LinearRotor;
/// let rod = LinearRotor::new(DVec3::X, DVec3::new(0.0, 0.0, 2.0))?;
/// let quarter = std::f64::consts::FRAC_PI_4; // |ω| t = π/2
/// assert!((rod.axis(quarter) - DVec3::Y).length() < 1e-15);
/// assert!((rod.axis_velocity(0.0) - DVec3::new(0.0, 2.0, 0.0)).length() < 1e-15);
/// # Ok::<(), rigid_free::FreeError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearRotor {
    s0: DVec3,
    /// `ω̂ × s0` (zero at rest).
    v0: DVec3,
    rate: f64,
    omega: DVec3,
}

impl LinearRotor {
    /// From the lab axis (normalised here) and the lab angular velocity. The component of `ω`
    /// along the axis is the decoupled spin: it carries no energy or angular momentum of a
    /// rod and is dropped.
    ///
    /// # Errors
    /// [`FreeError::NonFiniteVector`] for a NaN or infinite input, [`FreeError::ZeroAxis`] for a
    /// zero axis.
    pub fn new(axis: DVec3, omega: DVec3) -> Result<Self, FreeError> {
        check_vector(axis, "rod axis")?;
        check_vector(omega, "angular velocity")?;
        let s0 = axis.try_normalize().ok_or(FreeError::ZeroAxis)?;
        let omega = omega - s0 * s0.dot(omega);
        let rate = omega.length();
        let v0 = if rate > 0.0 {
            (omega / rate).cross(s0)
        } else {
            DVec3::ZERO
        };
        Ok(Self {
            s0,
            v0,
            rate,
            omega,
        })
    }

    /// The same rod turning the other way (`ω → −ω`, the axis at the rotor's time origin
    /// unchanged): `axis(t)` of the reversed rotor is exactly `axis(−t)` of this one, which is
    /// what a reversal of the momenta at the time origin needs (hybrid Monte Carlo).
    #[must_use]
    pub fn reversed(&self) -> Self {
        Self {
            s0: self.s0,
            v0: -self.v0,
            rate: self.rate,
            omega: -self.omega,
        }
    }

    /// The rotor's numbers `[s0, ω̂ × s0, |ω|, ω]` (10 of them), from which
    /// [`from_parts`](Self::from_parts) rebuilds the same rotor bit for bit (saved states).
    pub fn to_parts(&self) -> [f64; 10] {
        let (s, v, w) = (self.s0, self.v0, self.omega);
        [s.x, s.y, s.z, v.x, v.y, v.z, self.rate, w.x, w.y, w.z]
    }

    /// The rotor of [`to_parts`](Self::to_parts), as it was (nothing is normalised again).
    ///
    /// # Errors
    /// [`FreeError::NonFiniteVector`] for a number that is not finite, [`FreeError::ZeroAxis`]
    /// for an axis that is not a unit vector to round-off.
    pub fn from_parts(p: [f64; 10]) -> Result<Self, FreeError> {
        let s0 = check_vector(DVec3::new(p[0], p[1], p[2]), "rod axis")?;
        let v0 = check_vector(DVec3::new(p[3], p[4], p[5]), "rod axis velocity")?;
        let omega = check_vector(DVec3::new(p[7], p[8], p[9]), "angular velocity")?;
        if !p[6].is_finite() {
            return Err(FreeError::NonFiniteVector {
                what: "rotation rate",
            });
        }
        if (s0.length() - 1.0).abs() > 1e-9 {
            return Err(FreeError::ZeroAxis);
        }
        Ok(Self {
            s0,
            v0,
            rate: p[6],
            omega,
        })
    }

    /// The constant lab-frame angular velocity (perpendicular to the axis).
    #[inline]
    pub fn omega(&self) -> DVec3 {
        self.omega
    }

    /// The rotation rate `|ω|`.
    #[inline]
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// The unit axis at time `t`.
    #[inline(always)]
    pub fn axis(&self, t: f64) -> DVec3 {
        // At the rotor's own origin (a body that has just changed): no trigonometry. The same
        // value as the general formula, `s₀·1 + v₀·0`.
        if t == 0.0 {
            return self.s0;
        }
        let (s, c) = crate::trig::sin_cos(self.rate * t);
        self.s0 * c + self.v0 * s
    }

    /// The unit axis at time `t` and its velocity `ds/dt = ω × s(t)`, from one sine and cosine:
    /// with `ω ⟂ s`, `ω̂ × s(t) = v₀ cos ωt − s₀ sin ωt`. Certified prediction needs both (and
    /// `d²s/dt² = −|ω|² s`), without the cross products of the general rotation.
    #[inline(always)]
    pub fn axis_and_velocity(&self, t: f64) -> (DVec3, DVec3) {
        if t == 0.0 {
            return (self.s0, self.v0 * self.rate);
        }
        let (s, c) = crate::trig::sin_cos(self.rate * t);
        (
            self.s0 * c + self.v0 * s,
            (self.v0 * c - self.s0 * s) * self.rate,
        )
    }

    /// `ds/dt = ω × s(t)`.
    #[inline]
    pub fn axis_velocity(&self, t: f64) -> DVec3 {
        self.omega.cross(self.axis(t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_velocity_from_one_sine_matches_the_cross_product() {
        let rod = LinearRotor::new(DVec3::new(0.3, -0.5, 0.8), DVec3::new(2.0, 1.0, -0.7)).unwrap();
        for t in [0.0, 1e-9, 0.37, 5.0, -2.0] {
            let (s, ds) = rod.axis_and_velocity(t);
            assert_eq!(s, rod.axis(t));
            assert!(
                (ds - rod.axis_velocity(t)).length() < 1e-14 * rod.rate(),
                "{t}"
            );
        }
    }

    #[test]
    fn spin_is_dropped_and_axis_stays_unit() {
        let rod = LinearRotor::new(DVec3::new(0.0, 0.0, 3.0), DVec3::new(1.0, 0.0, 5.0)).unwrap();
        assert_eq!(rod.omega(), DVec3::new(1.0, 0.0, 0.0));
        for t in [0.0, 0.5, 1e3] {
            let s = rod.axis(t);
            assert!((s.length() - 1.0).abs() < 1e-15);
            assert!(s.dot(rod.omega()).abs() < 1e-15);
        }
        assert_eq!(
            LinearRotor::new(DVec3::ZERO, DVec3::X),
            Err(FreeError::ZeroAxis)
        );
        assert!(LinearRotor::new(DVec3::X, DVec3::new(f64::NAN, 0.0, 0.0)).is_err());
        let rest = LinearRotor::new(DVec3::X, DVec3::X).unwrap();
        assert_eq!(rest.axis(7.0), DVec3::X);
    }

    #[test]
    fn parts_round_trip_and_reversal_runs_backwards() {
        let rod = LinearRotor::new(DVec3::new(0.3, -1.0, 0.7), DVec3::new(1.3, 0.2, -0.4)).unwrap();
        let again = LinearRotor::from_parts(rod.to_parts()).unwrap();
        assert_eq!(again, rod);
        let back = rod.reversed();
        assert_eq!(back.omega(), -rod.omega());
        for t in [0.0, 0.3, 2.5] {
            assert_eq!(back.axis(t), rod.axis(-t));
        }
        let mut bad = rod.to_parts();
        bad[6] = f64::NAN;
        assert!(LinearRotor::from_parts(bad).is_err());
        bad = rod.to_parts();
        bad[0] *= 2.0;
        assert!(LinearRotor::from_parts(bad).is_err());
    }
}
