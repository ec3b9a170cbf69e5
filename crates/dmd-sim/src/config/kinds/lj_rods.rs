//! `kind = "rods"`: the modified Lennard-Jones rods of 003 Eqs. 22–23.

use potential::{LjRod, Smoothed, profile};

use super::Kind;
use crate::analysis::output::Drawing;
use crate::config::rods::{pair_terraces, potential_error, smoothed, terrace_error, terrace_map};
use crate::config::scene::{
    Body, Describe, LennardJonesSpec, LjRodsSpec, PotentialSpec, SceneError, TerraceSpec,
    non_negative, positive,
};
use crate::models::terraced::PairTerraces;

impl LjRodsSpec {
    fn potential(&self, k: usize) -> Result<LjRod, SceneError> {
        LjRod::new(self.epsilon, self.sigma, self.zeta).map_err(|e| potential_error(k, e))
    }

    /// Rods with `ζ = 0`: Lennard-Jones spheres.
    pub fn as_spheres(&self) -> LennardJonesSpec {
        LennardJonesSpec {
            epsilon: self.epsilon,
            sigma: self.sigma,
        }
    }
}

impl Describe for LjRodsSpec {
    fn name(&self) -> &'static str {
        "rods"
    }
    fn body(&self) -> Body {
        if self.zeta > 0.0 {
            Body::Rod
        } else {
            Body::Sphere
        }
    }
    fn check(&self, key: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
        positive(&key("epsilon"), self.epsilon)?;
        positive(&key("sigma"), self.sigma)?;
        non_negative(&key("zeta"), self.zeta)
    }
    fn scale_energy(&mut self, e: f64) {
        self.epsilon *= e;
    }
    fn well_depth(&self) -> f64 {
        self.epsilon
    }
    fn lengths(&self) -> (f64, f64) {
        (self.sigma, self.sigma)
    }
    /// An ellipsoid of width `σ − ζ/2`, where two parallel rods' potential vanishes, and
    /// length `σ + ζ/2`, where two perpendicular rods' does.
    fn drawing(&self) -> Drawing {
        if self.zeta == 0.0 {
            return self.as_spheres().drawing();
        }
        let a = 0.5 * (self.sigma - 0.5 * self.zeta);
        Drawing::Rod {
            semi_axes: [a, a, 0.5 * (self.sigma + 0.5 * self.zeta)],
        }
    }
    fn has_profile(&self) -> bool {
        true
    }
}

impl Kind for LjRodsSpec {
    const MODEL: &'static str = "terraced-rods";
    type Terraced = LjRod;
    type Smd = Smoothed<LjRod>;

    fn select(spec: &PotentialSpec) -> Option<Self> {
        match spec {
            PotentialSpec::Rods(k) => Some(*k),
            _ => None,
        }
    }

    fn terraces(
        &self,
        k: usize,
        t: &TerraceSpec,
        kt: f64,
        scale: f64,
    ) -> Result<PairTerraces<LjRod>, SceneError> {
        let rod = self.potential(k)?;
        let prof = profile::rods(&rod).map_err(|e| terrace_error(k, e, scale))?;
        let map = terrace_map(k, &rod, Some(&prof), t, kt, scale)?;
        pair_terraces(k, PairTerraces::new(rod, map))
    }

    fn smd(&self, window: (f64, f64)) -> Result<Smoothed<LjRod>, SceneError> {
        smoothed(self.potential(0)?, window)
    }
}
