//! `kind = "lennard-jones"`: Lennard-Jones spheres, whose terraces are radial steps.

use potential::{LennardJones, Profile, Smoothed, TerraceMap, profile};

use super::Kind;
use crate::analysis::output::Drawing;
use crate::config::rods::{pair_terraces, potential_error, smoothed, terrace_error, terrace_map};
use crate::config::scene::{
    Body, Describe, LennardJonesSpec, PotentialSpec, SceneError, TerraceSpec, positive,
};
use crate::models::terraced::{PairTerraces, radial_steps};

/// A pair table's potential with its radial profile and terrace map.
struct Mapped<F> {
    lj: LennardJones,
    prof: Profile<F>,
    map: TerraceMap,
}

impl LennardJonesSpec {
    fn potential(&self, k: usize) -> Result<LennardJones, SceneError> {
        LennardJones::new(self.epsilon, self.sigma).map_err(|e| potential_error(k, e))
    }

    /// The potential of pair table `k`, its radial profile and its terrace map.
    fn mapped(
        &self,
        k: usize,
        t: &TerraceSpec,
        kt: f64,
        scale: f64,
    ) -> Result<Mapped<impl Fn(f64) -> f64 + use<>>, SceneError> {
        let lj = self.potential(k)?;
        let prof = profile::lennard_jones(&lj).map_err(|e| terrace_error(k, e, scale))?;
        let map = terrace_map(k, &lj, Some(&prof), t, kt, scale)?;
        Ok(Mapped { lj, prof, map })
    }
}

impl Describe for LennardJonesSpec {
    fn name(&self) -> &'static str {
        "lennard-jones"
    }
    fn body(&self) -> Body {
        Body::Sphere
    }
    fn check(&self, key: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
        positive(&key("epsilon"), self.epsilon)?;
        positive(&key("sigma"), self.sigma)
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
    fn drawing(&self) -> Drawing {
        Drawing::Sphere {
            diameter: self.sigma,
        }
    }
    fn has_profile(&self) -> bool {
        true
    }
}

impl Kind for LennardJonesSpec {
    const MODEL: &'static str = "stepped";
    type Terraced = LennardJones;
    type Smd = Smoothed<LennardJones>;

    /// Rods with `ζ = 0` too.
    fn select(spec: &PotentialSpec) -> Option<Self> {
        match spec {
            PotentialSpec::LennardJones(k) => Some(*k),
            PotentialSpec::Rods(k) if k.zeta == 0.0 => Some(k.as_spheres()),
            _ => None,
        }
    }

    fn radial_steps(
        &self,
        k: usize,
        t: &TerraceSpec,
        kt: f64,
        scale: f64,
    ) -> Option<Result<Vec<[f64; 2]>, SceneError>> {
        let steps = || {
            let m = self.mapped(k, t, kt, scale)?;
            radial_steps(&m.prof, &m.map).map_err(|e| terrace_error(k, e, scale))
        };
        Some(steps())
    }

    fn terraces(
        &self,
        k: usize,
        t: &TerraceSpec,
        kt: f64,
        scale: f64,
    ) -> Result<PairTerraces<LennardJones>, SceneError> {
        let m = self.mapped(k, t, kt, scale)?;
        pair_terraces(k, PairTerraces::new(m.lj, m.map))
    }

    fn smd(&self, window: (f64, f64)) -> Result<Smoothed<LennardJones>, SceneError> {
        smoothed(self.potential(0)?, window)
    }
}
