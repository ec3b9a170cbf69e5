//! `kind = "ssd-e"`: soft sticky dipole water, SSD/E (Fennell and Gezelter, J. Chem. Phys.
//! 120, 9175 (2004)), between rigid tops, with its published parameters.

use potential::{SoftStickyDipole, SsdParameters};

use super::Kind;
use crate::analysis::output::Drawing;
use crate::config::rods::{Water, pair_terraces, plain_terrace_map, potential_error};
use crate::config::scene::{
    Body, Describe, PotentialSpec, SceneError, SsdESpec, TerraceSpec, UnitSystem,
};
use crate::models::terraced::{PairTerraces, Rigid};

impl SsdESpec {
    /// SSD/E with its energies in internal units: `ε`, `ν₀`, `ν₀'` scaled, the dipole by
    /// `√energy_unit` (the dipolar energy goes as `μ²`).
    pub fn potential(&self) -> Result<SoftStickyDipole, potential::PotentialError> {
        let p = SsdParameters::SSD_E;
        let u = self.energy_unit;
        SoftStickyDipole::new(SsdParameters {
            epsilon: p.epsilon * u,
            nu0: p.nu0 * u,
            nu0_prime: p.nu0_prime * u,
            dipole: p.dipole * u.sqrt(),
            ..p
        })
    }
}

impl Describe for SsdESpec {
    fn name(&self) -> &'static str {
        "ssd-e"
    }
    fn body(&self) -> Body {
        Body::Top
    }
    fn check(&self, _: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
        Ok(())
    }
    fn scale_energy(&mut self, e: f64) {
        self.energy_unit *= e;
    }
    /// The Lennard-Jones well, the smallest of its energies.
    fn well_depth(&self) -> f64 {
        self.energy_unit * SsdParameters::SSD_E.epsilon
    }
    fn lengths(&self) -> (f64, f64) {
        let sigma = SsdParameters::SSD_E.sigma;
        (sigma, sigma)
    }
    /// The oxygen and two hydrogens ([`water_drawing`](crate::config::rods::water_drawing)).
    fn drawing(&self) -> Drawing {
        let (centres, diameters) = crate::config::rods::water_drawing();
        Drawing::Sites { centres, diameters }
    }
    /// SSD/E switches itself off (zero beyond its cut-off, 9 Å): its window is its own.
    fn own_window(&self) -> Option<(f64, f64)> {
        let s = SsdParameters::SSD_E;
        Some((s.r_switch, s.r_cut))
    }
    fn smd_dt(&self) -> Option<f64> {
        Some(crate::config::smd_spec::SSD_E_DT)
    }
    fn units(&self) -> Option<UnitSystem> {
        Some(UnitSystem::Molecular)
    }
}

impl Kind for SsdESpec {
    const MODEL: &'static str = "terraced-tops";
    type Terraced = Water;
    type Smd = smd::Rigid<SoftStickyDipole>;

    fn select(spec: &PotentialSpec) -> Option<Self> {
        match spec {
            PotentialSpec::SsdE(k) => Some(*k),
            _ => None,
        }
    }

    fn terraces(
        &self,
        k: usize,
        t: &TerraceSpec,
        kt: f64,
        scale: f64,
    ) -> Result<PairTerraces<Water>, SceneError> {
        let water = Rigid(self.potential().map_err(|e| potential_error(k, e))?);
        let minimum = potential::RigidPairPotential::minimum(&water.0);
        let map = plain_terrace_map(k, minimum, t, kt, scale)?;
        pair_terraces(k, PairTerraces::new(water, map))
    }

    fn smd(&self, _: (f64, f64)) -> Result<smd::Rigid<SoftStickyDipole>, SceneError> {
        let p = self.potential().map_err(|e| potential_error(0, e))?;
        smd::Rigid::new(p, p.cutoff())
            .map_err(|e| SceneError::invalid("pair[0].potential", e.to_string()))
    }
}
