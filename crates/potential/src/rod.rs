//! The modified Lennard-Jones rods of 003 §V (Eqs. 22–25).

use crate::certify::{FreeFlight, TaylorModel};
use crate::error::{non_negative, positive};
use crate::lennard_jones::{energy_and_virial, energy_from_s2, lj_intervals, lj_reach};
use crate::pair::overlap;
use crate::{PairEval, PairGeometry, PairPotential, PotentialError};

/// Rods interacting through a Lennard-Jones potential of an orientation-dependent effective
/// distance (003 Eqs. 22–23):
///
/// ```text
/// U = 4ε[(σ/r_e)¹² − (σ/r_e)⁶],   r_e = |r_ij| + ζ(½ − (s_i·s_j)²).
/// ```
///
/// Perpendicular rods (`r_e = r + ζ/2`) sit further out than parallel ones (`r_e = r − ζ/2`),
/// so adjacent rods prefer to be perpendicular (crossed). Force and torques (003 Eq. 24):
///
/// ```text
/// F_ij = −dU/dr_e r̂_ij,   τ_ij = 2ζ(s_i·s_j) dU/dr_e s_i × s_j = −τ_ji,
/// dU/dr_e = −(24ε/r_e)[2(σ/r_e)¹² − (σ/r_e)⁶].
/// ```
///
/// `τ_ij` is perpendicular to `s_i`, so the spin about the long axis is conserved and a rod
/// can be propagated as a linear rotor. The minimum over all configurations is `−ε`, at
/// `r_e = 2^{1/6} σ` for every orientation.
///
/// Overlap: `r = 0` (centres coincide) and `r_e ≤ 0` (possible for near-parallel rods when
/// `r ≤ ζ/2`) give `U = +∞` and an [`PotentialError::Overlap`] from `evaluate`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LjRod {
    epsilon: f64,
    sigma: f64,
    zeta: f64,
    four_eps: f64,
    sigma2: f64,
}

impl LjRod {
    /// Well depth `ε`, diameter `σ` and orientation shift `ζ ≥ 0` (`ζ = 0` is Lennard-Jones
    /// spheres; [`LennardJones`](crate::LennardJones) is the cheaper type for those).
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] unless `ε`, `σ` are finite and positive and `ζ` finite
    /// and non-negative.
    pub fn new(epsilon: f64, sigma: f64, zeta: f64) -> Result<Self, PotentialError> {
        let epsilon = positive("epsilon", epsilon)?;
        let sigma = positive("sigma", sigma)?;
        let zeta = non_negative("zeta", zeta)?;
        Ok(Self {
            epsilon,
            sigma,
            zeta,
            four_eps: 4.0 * epsilon,
            sigma2: sigma * sigma,
        })
    }

    /// The paper's rods (003 §V): `ε = 3.0 kJ/mol`, `σ = 3.035 Å`, `ζ = 1 Å` (units kJ/mol and
    /// Å).
    pub fn paper() -> Self {
        Self {
            epsilon: 3.0,
            sigma: 3.035,
            zeta: 1.0,
            four_eps: 12.0,
            sigma2: 3.035 * 3.035,
        }
    }

    /// `ε`.
    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }

    /// `σ`.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// `ζ`.
    pub fn zeta(&self) -> f64 {
        self.zeta
    }

    /// The effective distance `r_e = r + ζ(½ − c²)` (003 Eq. 23) for centre distance `r` and
    /// `c = s_i·s_j`.
    #[inline]
    pub fn effective_distance(&self, r: f64, c: f64) -> f64 {
        r + self.zeta * (0.5 - c * c)
    }

    /// `U` as a function of the effective distance alone (`+∞` for `r_e ≤ 0`): the
    /// orientation-free part of the potential, a Lennard-Jones function of `r_e`.
    #[inline]
    pub fn energy_of_effective(&self, r_e: f64) -> f64 {
        if r_e > 0.0 {
            energy_from_s2(self.four_eps, self.sigma2 / (r_e * r_e))
        } else {
            f64::INFINITY
        }
    }

    /// The reach of a level in closed form (003 Eq. 25, generalised to any level): the
    /// Lennard-Jones distance at which `U = u_k`, plus `ζ/2`, the largest shift `r − r_e`
    /// (parallel rods, `c² = 1`). For the paper's outermost level `u_k = −ΔV/2` this is
    /// `r_m = ζ/2 + σ / (½[1 − √(1 − ΔV/2ε)])^{1/6}`.
    ///
    /// # Errors
    /// As [`PairPotential::reach`].
    pub fn reach_closed_form(&self, u_k: f64) -> Result<f64, PotentialError> {
        let r_e = lj_reach(self.epsilon, self.sigma, u_k)?;
        Ok(if r_e > 0.0 {
            r_e + 0.5 * self.zeta
        } else {
            0.0
        })
    }
}

impl PairPotential for LjRod {
    #[inline]
    fn energy(&self, g: &PairGeometry) -> f64 {
        let r2 = g.r_ij.length_squared();
        if r2 == 0.0 {
            return f64::INFINITY;
        }
        if self.zeta == 0.0 {
            // r_e = r: the Lennard-Jones arithmetic from r², bit for bit.
            return energy_from_s2(self.four_eps, self.sigma2 / r2);
        }
        self.energy_of_effective(self.effective_distance(r2.sqrt(), g.s_i.dot(g.s_j)))
    }

    // Always inlined: engines call it once per pair in their hot loop, and without the hint
    // LLVM kept it out of line there (a call and a `Result` through memory per pair: +30 %
    // per step for Lennard-Jones spheres in smd, measured).
    #[inline(always)]
    fn evaluate(&self, g: &PairGeometry) -> Result<PairEval, PotentialError> {
        let r2 = g.r_ij.length_squared();
        let r = r2.sqrt();
        let c = g.s_i.dot(g.s_j);
        let r_e = self.effective_distance(r, c);
        if !(r > 0.0 && r_e > 0.0) {
            return Err(overlap(
                g,
                r,
                "effective distance r_e = r + zeta (1/2 - c^2) <= 0 or r = 0",
            ));
        }
        // r_e² and r_e r; for ζ = 0 (r_e = r) exactly r², so that the arithmetic is that of
        // LennardJones bit for bit.
        let (re2, re_r) = if self.zeta == 0.0 {
            (r2, r2)
        } else {
            (r_e * r_e, r_e * r)
        };
        let (energy, virial) = energy_and_virial(self.four_eps, self.sigma2 / re2);
        let force = (-virial / re_r) * g.r_ij; // −dU/dr_e r̂ (003 Eq. 24)
        let du = virial / r_e; // dU/dr_e
        let torque_i = (2.0 * self.zeta * c * du) * g.s_i.cross(g.s_j);
        let out = PairEval {
            energy,
            force,
            torque_i,
            torque_j: -torque_i,
        };
        if out.is_finite() {
            Ok(out)
        } else {
            Err(overlap(g, r, "(sigma/r_e)^12 overflows binary64"))
        }
    }

    fn minimum(&self) -> f64 {
        -self.epsilon
    }

    fn length_scale(&self) -> f64 {
        self.sigma + 0.5 * self.zeta
    }

    fn depends_on_orientation(&self) -> bool {
        self.zeta > 0.0
    }

    fn reach(&self, u_k: f64) -> Result<f64, PotentialError> {
        self.reach_closed_form(u_k)
    }

    /// `x = r_e = r + ζ(½ − c²)`, `c = s_i·s_j` (003 Eq. 23): `ẋ = ṙ − 2ζcċ`,
    /// `ẍ = r̈ − 2ζ(ċ² + cc̈)`, and `x⃛ = r⃛ − 2ζ(cc⃛ + 3ċc̈)` with `|c⁽ⁿ⁾| ≤ Ωⁿ`, `|c| ≤ 1`:
    /// `|x⃛| ≤ (2/√3)|v|³/r_lo² + 8ζΩ³` (`Ω` the flight's [`spin`](FreeFlight::spin)).
    #[inline]
    fn taylor_model(&self, flight: &FreeFlight, h: f64) -> Option<TaylorModel> {
        let (r, rd, rdd) = flight.distance_derivatives();
        let (c, cd, cdd) = flight.alignment_derivatives();
        let w = flight.spin;
        let z = self.zeta;
        Some(TaylorModel {
            x: self.effective_distance(r, c),
            dx: rd - 2.0 * z * c * cd,
            ddx: rdd - 2.0 * z * (cd * cd + c * cdd),
            third: flight.distance_third_bound(h) + 8.0 * z * w * w * w,
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
    use glam::DVec3;

    #[test]
    fn perpendicular_rods_sit_further_out_than_parallel_ones() {
        let rod = LjRod::new(1.0, 1.0, 0.3).unwrap();
        let r = DVec3::X * 1.1;
        let parallel = rod.energy(&PairGeometry::new(r, DVec3::Z, DVec3::Z));
        let crossed = rod.energy(&PairGeometry::new(r, DVec3::Z, DVec3::Y));
        // r_e = 1.1 − 0.15 (parallel: repulsive), 1.1 + 0.15 (crossed: in the well).
        assert_eq!(rod.effective_distance(1.1, 1.0), 1.1 - 0.15);
        assert_eq!(rod.effective_distance(1.1, 0.0), 1.1 + 0.15);
        assert_eq!(parallel, rod.energy_of_effective(1.1 - 0.15));
        assert_eq!(crossed, rod.energy_of_effective(1.1 + 0.15));
        assert!(parallel > 0.0 && crossed < 0.0);
    }

    #[test]
    fn torque_is_zero_for_parallel_and_perpendicular_axes() {
        // c = 0 and s_i × s_j = 0 (exactly) both give zero torque; no NaN from either.
        let rod = LjRod::new(1.0, 1.0, 0.3).unwrap();
        for (si, sj) in [
            (DVec3::Z, DVec3::Z),
            (DVec3::Z, -DVec3::Z),
            (DVec3::Z, DVec3::Y),
        ] {
            let e = rod
                .evaluate(&PairGeometry::new(DVec3::X * 1.3, si, sj))
                .unwrap();
            assert_eq!(e.torque_i, DVec3::ZERO);
            assert_eq!(e.torque_j, DVec3::ZERO);
        }
    }

    #[test]
    fn deep_overlap_is_infinite() {
        let rod = LjRod::new(1.0, 1.0, 0.4).unwrap();
        // Parallel rods at r = 0.1 < ζ/2: r_e = 0.1 − 0.2 < 0.
        let g = PairGeometry::new(DVec3::X * 0.1, DVec3::Z, DVec3::Z);
        assert_eq!(rod.energy(&g), f64::INFINITY);
        assert!(matches!(
            rod.evaluate(&g),
            Err(PotentialError::Overlap { .. })
        ));
        // r_e = 0 exactly.
        let g = PairGeometry::new(DVec3::X * 0.2, DVec3::Z, DVec3::Z);
        assert_eq!(rod.energy(&g), f64::INFINITY);
        // Centres coincide (r_e would be ζ/2 > 0 for crossed rods, but the bodies overlap).
        let g = PairGeometry::new(DVec3::ZERO, DVec3::Z, DVec3::X);
        assert_eq!(rod.energy(&g), f64::INFINITY);
        assert!(rod.evaluate(&g).is_err());
    }

    #[test]
    fn eq_25_as_printed() {
        let rod = LjRod::paper();
        for dv in [0.1, 1.0, 2.0, 5.0] {
            let printed = 0.5 * rod.zeta()
                + rod.sigma()
                    / (0.5 * (1.0 - (1.0 - dv / (2.0 * rod.epsilon())).sqrt())).powf(1.0 / 6.0);
            let ours = rod.reach(-0.5 * dv).unwrap();
            assert!(
                (ours - printed).abs() <= 1e-13 * printed,
                "{dv}: {ours} {printed}"
            );
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        assert!(
            LjRod::new(1.0, 1.0, -0.1)
                .unwrap_err()
                .to_string()
                .contains("zeta")
        );
        assert!(LjRod::new(0.0, 1.0, 0.1).is_err());
    }
}
