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

    /// The constant lab-frame angular velocity (perpendicular to the axis).
    #[inline]
    pub fn omega(&self) -> DVec3 {
        self.omega
    }

    /// The unit axis at time `t`.
    #[inline]
    pub fn axis(&self, t: f64) -> DVec3 {
        let (s, c) = crate::trig::sin_cos(self.rate * t);
        self.s0 * c + self.v0 * s
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
}
