//! `kind = "gay-berne"`: Gay–Berne GB(κ, κ', μ, ν) rods.

use potential::{GayBerne, Smoothed};

use super::Kind;
use crate::analysis::output::Drawing;
use crate::config::rods::{pair_terraces, plain_terrace_map, potential_error, smoothed};
use crate::config::scene::{
    Body, Describe, GayBerneSpec, PotentialSpec, SceneError, TerraceSpec, non_negative, positive,
};
use crate::models::terraced::PairTerraces;

impl GayBerneSpec {
    fn potential(&self, k: usize) -> Result<GayBerne, SceneError> {
        GayBerne::new(
            self.sigma0,
            self.epsilon0,
            self.kappa,
            self.kappa_prime,
            self.mu,
            self.nu,
        )
        .map_err(|e| potential_error(k, e))
    }
}

impl Describe for GayBerneSpec {
    fn name(&self) -> &'static str {
        "gay-berne"
    }
    fn body(&self) -> Body {
        Body::Rod
    }
    fn check(&self, key: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
        positive(&key("sigma0"), self.sigma0)?;
        positive(&key("epsilon0"), self.epsilon0)?;
        positive(&key("kappa"), self.kappa)?;
        positive(&key("kappa_prime"), self.kappa_prime)?;
        positive(&key("mu"), self.mu)?;
        non_negative(&key("nu"), self.nu)
    }
    fn scale_energy(&mut self, e: f64) {
        self.epsilon0 *= e;
    }
    fn well_depth(&self) -> f64 {
        self.epsilon0
    }
    /// σ₀, and the end-to-end contact κσ₀.
    fn lengths(&self) -> (f64, f64) {
        (self.sigma0, self.sigma0 * self.kappa.max(1.0))
    }
    /// An ellipsoid of breadth σ₀ and length κσ₀.
    fn drawing(&self) -> Drawing {
        let a = 0.5 * self.sigma0;
        Drawing::Rod {
            semi_axes: [a, a, 0.5 * self.kappa * self.sigma0],
        }
    }
}

impl Kind for GayBerneSpec {
    const MODEL: &'static str = "terraced-gay-berne";
    type Terraced = GayBerne;
    type Smd = Smoothed<GayBerne>;

    fn select(spec: &PotentialSpec) -> Option<Self> {
        match spec {
            PotentialSpec::GayBerne(k) => Some(*k),
            _ => None,
        }
    }

    /// Evenly spaced or explicit levels (no radial profile); every band bracketed by the
    /// outermost reach, which Gay–Berne finds numerically (about 0.1 s per level).
    fn terraces(
        &self,
        k: usize,
        t: &TerraceSpec,
        kt: f64,
        scale: f64,
    ) -> Result<PairTerraces<GayBerne>, SceneError> {
        let gb = self.potential(k)?;
        let map = plain_terrace_map(k, potential::PairPotential::minimum(&gb), t, kt, scale)?;
        pair_terraces(k, PairTerraces::with_outer_reach(gb, map))
    }

    fn smd(&self, window: (f64, f64)) -> Result<Smoothed<GayBerne>, SceneError> {
        smoothed(self.potential(0)?, window)
    }
}
