//! Lennard-Jones spheres: the `ζ = 0` case of the rods of 003 Eq. 22, with no orientation work.

use glam::DVec3;

use crate::certify::{FreeFlight, TaylorModel};
use crate::error::positive;
use crate::pair::overlap;
use crate::{PairEval, PairGeometry, PairPotential, PotentialError};

/// The 12-6 Lennard-Jones potential `U = 4ε[(σ/r)¹² − (σ/r)⁶]` between spheres (003 Eq. 22
/// with `r_e = r`). Minimum `−ε` at `r = 2^{1/6} σ`; `+∞` at `r = 0`.
///
/// It computes everything from `r²` (no square root), returns zero torques and reports
/// [`depends_on_orientation`](PairPotential::depends_on_orientation) `false`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LennardJones {
    epsilon: f64,
    sigma: f64,
    four_eps: f64,
    sigma2: f64,
}

impl LennardJones {
    /// Well depth `ε` and diameter `σ` (where `U = 0`).
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] unless both are finite and positive.
    pub fn new(epsilon: f64, sigma: f64) -> Result<Self, PotentialError> {
        let epsilon = positive("epsilon", epsilon)?;
        let sigma = positive("sigma", sigma)?;
        Ok(Self {
            epsilon,
            sigma,
            four_eps: 4.0 * epsilon,
            sigma2: sigma * sigma,
        })
    }

    /// `ε`.
    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }

    /// `σ`.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// `U(r)` for a centre distance `r ≥ 0` (`+∞` at `r = 0`).
    #[inline]
    pub fn energy_at(&self, r: f64) -> f64 {
        energy_from_s2(self.four_eps, self.sigma2 / (r * r))
    }

    /// Where the potential sits at its minimum, `2^{1/6} σ`.
    pub fn minimum_distance(&self) -> f64 {
        2f64.powf(1.0 / 6.0) * self.sigma
    }
}

/// `4ε s⁶(s⁶ − 1)` with `s² = (σ/r)²`; written as a product so that an overflowing `s⁶` gives
/// `+∞`, never `∞ − ∞`.
#[inline]
pub(crate) fn energy_from_s2(four_eps: f64, s2: f64) -> f64 {
    let s6 = s2 * s2 * s2;
    four_eps * s6 * (s6 - 1.0)
}

/// `U` and `r dU/dr = −24ε s⁶(2s⁶ − 1)` (003 Eq. 24 times `r`) from `s² = (σ/r)²`.
#[inline]
pub(crate) fn energy_and_virial(four_eps: f64, s2: f64) -> (f64, f64) {
    let s6 = s2 * s2 * s2;
    (
        four_eps * s6 * (s6 - 1.0),
        -6.0 * four_eps * s6 * (2.0 * s6 - 1.0),
    )
}

/// The distances at which `4ε[(σ/r)¹² − (σ/r)⁶] = level`, `level ≥ −ε`, in a cancellation-free
/// form: with `x = (σ/r)⁶` the level is crossed where `x² − x − level/4ε = 0`, whose large root
/// `x₊ = ½(1 + √(1 + level/ε))` is the inner distance (on the repulsive flank) and whose small
/// root `x₋ = (−level/4ε)/x₊` the outer one (on the attractive flank, `+∞` for `level ≥ 0`,
/// which is crossed once). Levels below `−ε` are taken as `−ε`.
fn lj_preimages(epsilon: f64, sigma: f64, level: f64) -> (f64, f64) {
    let ratio = (level / epsilon).max(-1.0);
    let x_plus = 0.5 * (1.0 + (1.0 + ratio).sqrt());
    let outer = if level < 0.0 {
        sigma * ((-0.25 * ratio) / x_plus).powf(-1.0 / 6.0)
    } else {
        f64::INFINITY
    };
    (sigma * x_plus.powf(-1.0 / 6.0), outer)
}

/// The largest `r` at which `4ε[(σ/r)¹² − (σ/r)⁶]` is at or below `level < 0` (or at or above
/// `level > 0`): 003 Eq. 25 without its `ζ/2`, the outer preimage of a negative level and the
/// inner one of a positive level ([`lj_preimages`]).
pub(crate) fn lj_reach(epsilon: f64, sigma: f64, level: f64) -> Result<f64, PotentialError> {
    if !level.is_finite() {
        return Err(PotentialError::NotFinite("level"));
    }
    if level == 0.0 {
        return Err(PotentialError::LevelAtZero(level));
    }
    if level / epsilon < -1.0 {
        return Ok(0.0);
    }
    let (inner, outer) = lj_preimages(epsilon, sigma, level);
    Ok(if level < 0.0 { outer } else { inner })
}

/// The open intervals of `x` on which `lo < 4ε[(σ/x)¹² − (σ/x)⁶] < hi`: the band of a terrace
/// in the coordinate of certified prediction ([`crate::certify`]). The function falls on
/// `(0, x_m)` and rises on `(x_m, ∞)` towards 0, `x_m = 2^{1/6}σ`, so the band is one interval
/// around `x_m` when `lo` is below the minimum `−ε`, else up to two (one on each flank), whose
/// ends are the levels' inner (`x < x_m`) and outer preimages ([`lj_preimages`]).
pub(crate) fn lj_intervals(epsilon: f64, sigma: f64, lo: f64, hi: f64) -> Vec<(f64, f64)> {
    // An empty band: below the minimum, or not an interval.
    let band = hi > -epsilon && lo < hi;
    if !band {
        return Vec::new();
    }
    // The hard core's level may be +∞: its inner preimage is the origin.
    let (hi_in, hi_out) = if hi == f64::INFINITY {
        (0.0, f64::INFINITY)
    } else {
        lj_preimages(epsilon, sigma, hi)
    };
    let above_minimum = lo > -epsilon;
    if !above_minimum {
        // The lowest terrace: the well's bottom lies inside the band.
        return vec![(hi_in, hi_out)];
    }
    let (lo_in, lo_out) = lj_preimages(epsilon, sigma, lo);
    if lo < 0.0 {
        vec![(hi_in, lo_in), (lo_out, hi_out)]
    } else {
        // A level at or above 0 has no outer preimage: the band lies on the inner flank.
        vec![(hi_in, lo_in)]
    }
}

impl PairPotential for LennardJones {
    #[inline]
    fn energy(&self, g: &PairGeometry) -> f64 {
        energy_from_s2(self.four_eps, self.sigma2 / g.r_ij.length_squared())
    }

    // Always inlined: engines call it once per pair in their hot loop, and without the hint
    // LLVM kept it out of line there (a call and a `Result` through memory per pair: +30 %
    // per step for Lennard-Jones spheres in smd, measured).
    #[inline(always)]
    fn evaluate(&self, g: &PairGeometry) -> Result<PairEval, PotentialError> {
        let r2 = g.r_ij.length_squared();
        let (energy, virial) = energy_and_virial(self.four_eps, self.sigma2 / r2);
        // F = −dU/dr r̂ = −(r dU/dr) r_ij / r².
        let force = (-virial / r2) * g.r_ij;
        let out = PairEval {
            energy,
            force,
            torque_i: DVec3::ZERO,
            torque_j: DVec3::ZERO,
        };
        if energy.is_finite() && force.is_finite() {
            Ok(out)
        } else {
            Err(overlap(g, r2.sqrt(), "(sigma/r)^12 overflows binary64"))
        }
    }

    fn minimum(&self) -> f64 {
        -self.epsilon
    }

    fn length_scale(&self) -> f64 {
        self.sigma
    }

    fn depends_on_orientation(&self) -> bool {
        false
    }

    fn reach(&self, u_k: f64) -> Result<f64, PotentialError> {
        lj_reach(self.epsilon, self.sigma, u_k)
    }

    /// `x = r`: `r⃛` bounded by the closest approach over the window.
    #[inline]
    fn taylor_model(&self, flight: &FreeFlight, h: f64) -> Option<TaylorModel> {
        let (x, dx, ddx) = flight.distance_derivatives();
        Some(TaylorModel {
            x,
            dx,
            ddx,
            third: flight.distance_third_bound(h),
            spread: 0.0,
        })
    }

    fn coordinate_intervals(&self, lo: f64, hi: f64) -> Vec<(f64, f64)> {
        lj_intervals(self.epsilon, self.sigma, lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn textbook_values() {
        let lj = LennardJones::new(2.0, 1.5).unwrap();
        assert_eq!(lj.energy_at(1.5), 0.0);
        let rm = lj.minimum_distance();
        assert!((lj.energy_at(rm) + 2.0).abs() < 1e-15);
        let e = lj
            .evaluate(&PairGeometry::spheres(DVec3::new(rm, 0.0, 0.0)))
            .unwrap();
        assert!(e.force.length() < 1e-13);
        // Repulsive inside the minimum, attractive outside: F·r̂_ij > 0 pushes i away from j.
        let inside = lj.evaluate(&PairGeometry::spheres(DVec3::X * 1.4)).unwrap();
        let outside = lj.evaluate(&PairGeometry::spheres(DVec3::X * 2.0)).unwrap();
        assert!(inside.force.x > 0.0 && outside.force.x < 0.0);
    }

    #[test]
    fn coincident_centres_are_infinite_not_nan() {
        let lj = LennardJones::new(1.0, 1.0).unwrap();
        let g = PairGeometry::spheres(DVec3::ZERO);
        assert_eq!(lj.energy(&g), f64::INFINITY);
        assert!(matches!(
            lj.evaluate(&g),
            Err(PotentialError::Overlap { .. })
        ));
        // Far inside but finite: the energy overflows to +∞, never NaN.
        let g = PairGeometry::spheres(DVec3::X * 1e-30);
        assert_eq!(lj.energy(&g), f64::INFINITY);
        assert!(lj.evaluate(&g).is_err());
        // Far outside: tiny and negative, force finite.
        let g = PairGeometry::spheres(DVec3::X * 1e30);
        assert!(lj.energy(&g) <= 0.0 && lj.evaluate(&g).is_ok());
    }

    #[test]
    fn bad_parameters_are_named() {
        let e = LennardJones::new(-1.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("epsilon"));
        assert!(LennardJones::new(1.0, 0.0).is_err());
        assert!(LennardJones::new(1.0, f64::NAN).is_err());
    }

    #[test]
    fn reach_solves_the_level_equation() {
        let lj = LennardJones::new(1.3, 0.9).unwrap();
        for level in [-1.3, -1.0, -0.5, -1e-3, -1e-12, 1e-3, 0.7, 50.0] {
            let r = lj.reach(level).unwrap();
            let u = lj.energy_at(r);
            // Relative to the level, plus the round-off of U near σ (|r U'| ~ 24ε).
            assert!(
                (u - level).abs() <= 1e-12 * level.abs() + 1e-14,
                "{level}: {u}"
            );
        }
        assert_eq!(lj.reach(-1.4).unwrap(), 0.0);
        assert!(lj.reach(0.0).is_err());
        assert!(lj.reach(f64::NAN).is_err());
    }
}
