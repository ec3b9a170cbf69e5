//! `kind = "stockmayer"`: Stockmayer rods, Lennard-Jones spheres each carrying a point dipole
//! along its axis (Stockmayer, J. Chem. Phys. 9, 398 (1941)):
//!
//! ```text
//! U = 4ε[(σ/r)¹² − (σ/r)⁶] + μ² [c − 3 x_i x_j / r²] / r³,
//! ```
//!
//! with the invariants of `potential::pair` (`x_i = r_ij·s_i`, `x_j = r_ij·s_j`,
//! `c = s_i·s_j`). `μ²` is an energy times a volume in the scene's units (in reduced units
//! `μ*² = μ²/εσ³`; in molecular units 1 D² is 60.22 kJ/mol Å³). The bodies are linear rotors
//! (`species.inertia`); the dipole is unscreened, so the terraces' zero terrace and the
//! standard-MD engine's smoothing window end it (no Ewald sum).

use potential::{
    PairEval, PairGeometry, PairPotential, Partials, PotentialError, Smoothed, pair::assemble,
};

use super::Kind;
use crate::analysis::output::Drawing;
use crate::config::rods::{pair_terraces, plain_terrace_map, potential_error, smoothed};
use crate::config::scene::{
    Body, Describe, PotentialSpec, SceneError, StockmayerSpec, TerraceSpec, non_negative, positive,
};
use crate::models::terraced::PairTerraces;

/// The Stockmayer potential (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stockmayer {
    four_eps: f64,
    sigma2: f64,
    sigma: f64,
    mu2: f64,
    minimum: f64,
}

impl Stockmayer {
    /// Well depth `ε`, diameter `σ`, dipole `μ`.
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] unless `ε`, `σ` are finite and positive and `μ` finite
    /// and non-negative.
    pub fn new(epsilon: f64, sigma: f64, dipole: f64) -> Result<Self, PotentialError> {
        for (name, x, min) in [("epsilon", epsilon, 0.0), ("sigma", sigma, 0.0)] {
            if !(x.is_finite() && x > min) {
                return Err(PotentialError::Parameter {
                    name,
                    value: x,
                    why: "finite and > 0",
                });
            }
        }
        if !(dipole.is_finite() && dipole >= 0.0) {
            return Err(PotentialError::Parameter {
                name: "dipole",
                value: dipole,
                why: "finite and ≥ 0",
            });
        }
        let mut p = Self {
            four_eps: 4.0 * epsilon,
            sigma2: sigma * sigma,
            sigma,
            mu2: dipole * dipole,
            minimum: 0.0,
        };
        p.minimum = p.head_to_tail_minimum();
        Ok(p)
    }

    /// `U_LJ(r)` and `dU_LJ/dr`.
    #[inline]
    fn lj(&self, r2: f64, r: f64) -> (f64, f64) {
        let s6 = (self.sigma2 / r2).powi(3);
        let s12 = s6 * s6;
        (
            self.four_eps * (s12 - s6),
            -6.0 * self.four_eps * (2.0 * s12 - s6) / r,
        )
    }

    /// The global minimum: at each distance the dipolar term is lowest head to tail
    /// (`c = 1`, `x_i = x_j = r`: `−2μ²/r³`), so it is the minimum over `r` of
    /// `U_LJ(r) − 2μ²/r³`, whose slope changes sign once between `σ/2` (repulsion wins) and
    /// the Lennard-Jones minimum `2^{1/6}σ` (the dipole still pulls): bisection of the slope.
    fn head_to_tail_minimum(&self) -> f64 {
        let slope = |r: f64| self.lj(r * r, r).1 + 6.0 * self.mu2 / r.powi(4);
        let (mut lo, mut hi) = (0.5 * self.sigma, 2f64.powf(1.0 / 6.0) * self.sigma);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if slope(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let r = 0.5 * (lo + hi);
        self.lj(r * r, r).0 - 2.0 * self.mu2 / (r * r * r)
    }
}

impl PairPotential for Stockmayer {
    #[inline]
    fn energy(&self, g: &PairGeometry) -> f64 {
        let r2 = g.r_ij.length_squared();
        if r2 == 0.0 {
            return f64::INFINITY;
        }
        let r = r2.sqrt();
        let (x_i, x_j, c) = (g.r_ij.dot(g.s_i), g.r_ij.dot(g.s_j), g.s_i.dot(g.s_j));
        self.lj(r2, r).0 + self.mu2 * (c - 3.0 * x_i * x_j / r2) / (r2 * r)
    }

    #[inline]
    fn evaluate(&self, g: &PairGeometry) -> Result<PairEval, PotentialError> {
        let inv = g.invariants();
        let (r, r2) = (inv.r, inv.r * inv.r);
        let (u, du) = self.lj(r2, r);
        let r3 = r2 * r;
        let r5 = r3 * r2;
        let p = Partials {
            energy: u + self.mu2 * (inv.c - 3.0 * inv.x_i * inv.x_j / r2) / r3,
            d_r: du + self.mu2 * (-3.0 * inv.c / (r3 * r) + 15.0 * inv.x_i * inv.x_j / (r5 * r)),
            d_xi: -3.0 * self.mu2 * inv.x_j / r5,
            d_xj: -3.0 * self.mu2 * inv.x_i / r5,
            d_c: self.mu2 / r3,
        };
        assemble(g, &inv, &p)
    }

    fn minimum(&self) -> f64 {
        self.minimum
    }

    fn length_scale(&self) -> f64 {
        self.sigma
    }

    fn depends_on_orientation(&self) -> bool {
        self.mu2 > 0.0
    }
}

impl StockmayerSpec {
    fn potential(&self, k: usize) -> Result<Stockmayer, SceneError> {
        Stockmayer::new(self.epsilon, self.sigma, self.dipole).map_err(|e| potential_error(k, e))
    }
}

impl Describe for StockmayerSpec {
    fn name(&self) -> &'static str {
        "stockmayer"
    }
    fn body(&self) -> Body {
        Body::Rod
    }
    fn check(&self, key: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
        positive(&key("epsilon"), self.epsilon)?;
        positive(&key("sigma"), self.sigma)?;
        non_negative(&key("dipole"), self.dipole)
    }
    /// `μ²` is an energy × volume.
    fn scale_energy(&mut self, e: f64) {
        self.epsilon *= e;
        self.dipole *= e.sqrt();
    }
    fn well_depth(&self) -> f64 {
        self.epsilon
    }
    fn lengths(&self) -> (f64, f64) {
        (self.sigma, self.sigma)
    }
    /// A sphere of diameter σ that turns with its dipole.
    fn drawing(&self) -> Drawing {
        Drawing::Rod {
            semi_axes: [0.5 * self.sigma; 3],
        }
    }
}

impl Kind for StockmayerSpec {
    const MODEL: &'static str = "terraced-stockmayer";
    type Terraced = Stockmayer;
    type Smd = Smoothed<Stockmayer>;

    fn select(spec: &PotentialSpec) -> Option<Self> {
        match spec {
            PotentialSpec::Stockmayer(k) => Some(*k),
            _ => None,
        }
    }

    fn terraces(
        &self,
        k: usize,
        t: &TerraceSpec,
        kt: f64,
        scale: f64,
    ) -> Result<PairTerraces<Stockmayer>, SceneError> {
        let p = self.potential(k)?;
        let map = plain_terrace_map(k, p.minimum(), t, kt, scale)?;
        // The reach is found numerically over orientations: once for the outermost levels,
        // not for each of the hundreds up to the core.
        pair_terraces(k, PairTerraces::with_outer_reach(p, map))
    }

    fn smd(&self, window: (f64, f64)) -> Result<Smoothed<Stockmayer>, SceneError> {
        smoothed(self.potential(0)?, window)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Force and torques against central differences of the energy (translation of `i`,
    /// rotation of each axis), and the head-to-tail minimum against a fine scan.
    #[test]
    fn forces_torques_and_minimum_match_the_energy() {
        let p = Stockmayer::new(1.0, 1.0, 1.2).unwrap();
        let g = PairGeometry::new(
            DVec3::new(0.9, 0.5, -0.4),
            DVec3::new(0.3, -0.2, 0.9).normalize(),
            DVec3::new(-0.6, 0.7, 0.1).normalize(),
        );
        let e = p.evaluate(&g).unwrap();
        assert_eq!(e.energy, p.energy(&g));
        let h = 1e-6;
        for k in 0..3 {
            let d = DVec3::AXES[k] * h;
            let at = |r: DVec3| p.energy(&PairGeometry::new(r, g.s_i, g.s_j));
            let f = -(at(g.r_ij + d) - at(g.r_ij - d)) / (2.0 * h);
            assert!(
                (f - e.force[k]).abs() < 1e-6,
                "force {k}: {f} vs {}",
                e.force[k]
            );
            // A small rotation about axis k of s_i (s_j): dU = −τ·dθ.
            let turn = |s: DVec3, a: f64| glam::DQuat::from_axis_angle(DVec3::AXES[k], a) * s;
            let ti = -(p.energy(&PairGeometry::new(g.r_ij, turn(g.s_i, h), g.s_j))
                - p.energy(&PairGeometry::new(g.r_ij, turn(g.s_i, -h), g.s_j)))
                / (2.0 * h);
            let tj = -(p.energy(&PairGeometry::new(g.r_ij, g.s_i, turn(g.s_j, h)))
                - p.energy(&PairGeometry::new(g.r_ij, g.s_i, turn(g.s_j, -h))))
                / (2.0 * h);
            assert!((ti - e.torque_i[k]).abs() < 1e-6, "torque_i {k}");
            assert!((tj - e.torque_j[k]).abs() < 1e-6, "torque_j {k}");
        }
        let scan = (1..40_000)
            .map(|n| {
                let r = 0.8 + n as f64 * 1e-5;
                p.energy(&PairGeometry::new(DVec3::Z * r, DVec3::Z, DVec3::Z))
            })
            .fold(f64::INFINITY, f64::min);
        // Not above its value at the Lennard-Jones minimum, −ε − 2μ²/√2σ³.
        assert!((p.minimum() - scan).abs() < 1e-8);
        assert!(p.minimum() <= -1.0 - 2.0 * 1.44 / 2f64.sqrt());
        // Side by side, antiparallel dipoles attract less than head to tail.
        let side = p.energy(&PairGeometry::new(DVec3::X * 1.1, DVec3::Z, -DVec3::Z));
        let line = p.energy(&PairGeometry::new(DVec3::Z * 1.1, DVec3::Z, DVec3::Z));
        assert!(line < side && side < 0.0);
    }
}
