//! `kind = "spc-e"`: SPC/E water (Berendsen, Grigera and Straatsma, J. Phys. Chem. 91, 6269
//! (1987)) as a rigid molecule of three sites between rigid tops: site–site Lennard-Jones on
//! the oxygens and damped shifted force Coulomb between all charges (Fennell and Gezelter,
//! J. Chem. Phys. 124, 234104 (2006)), both shifted to vanish with their force at the site
//! cut-off (`potential::site_site`). The keys are the Coulomb term's damping `alpha` (1/Å,
//! default 0.2) and the site cut-off `r_cut` (Å, default 9); the molecular pair energy is zero
//! beyond `r_cut` plus twice the hydrogens' arm (10.93 Å by default).

use potential::site_site::{COULOMB, Dsf, spc_e_sites};
use potential::{RigidPairPotential, SiteSite};

use super::Kind;
use crate::analysis::output::Drawing;
use crate::analysis::site_rdf::MoleculeSites;
use crate::config::rods::{pair_terraces, plain_terrace_map, potential_error};
use crate::config::scene::{
    Body, Describe, PotentialSpec, SceneError, SpcESpec, TerraceSpec, UnitSystem, non_negative,
    positive,
};
use crate::models::terraced::{PairTerraces, Rigid};

/// The standard-MD time step of SPC/E water: 2 fs (in ps), SSD/E's step for a molecule of
/// nearly the same moments of inertia; on `scenes/water-spce.toml` after 8 ps of
/// equilibration, 4 ps of NVE production keep std(E)/std(U) at 0.82 %, within the 1 % of
/// docs/PERFORMANCE.md's criterion (docs/VALIDATION.md, SPC/E water).
const SPC_E_DT: f64 = 0.002;

impl SpcESpec {
    /// The DSF parameters: given, or FG06's `α = 0.2 Å⁻¹`, `R_c = 9 Å`.
    fn dsf(&self) -> Dsf {
        Dsf {
            alpha: self.alpha.unwrap_or(Dsf::FG06.alpha),
            r_cut: self.r_cut.unwrap_or(Dsf::FG06.r_cut),
        }
    }

    /// SPC/E with its energies in internal units: `ε` and the Coulomb constant scaled.
    ///
    /// # Errors
    /// What [`SiteSite::new`] refuses.
    pub fn potential(&self) -> Result<SiteSite, potential::PotentialError> {
        let u = self.energy_unit;
        let sites = spc_e_sites().map(|s| potential::Site {
            epsilon: s.epsilon * u,
            ..s
        });
        SiteSite::new(&sites, COULOMB * u, self.dsf())
    }

    /// The longest arm of a site (the hydrogens').
    fn arm() -> f64 {
        spc_e_sites()
            .iter()
            .map(|s| s.position.length())
            .fold(0.0, f64::max)
    }
}

impl Describe for SpcESpec {
    fn name(&self) -> &'static str {
        "spc-e"
    }
    fn body(&self) -> Body {
        Body::Top
    }
    fn check(&self, key: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
        let d = self.dsf();
        non_negative(&key("alpha"), d.alpha)?;
        positive(&key("r_cut"), d.r_cut)?;
        let well = 2f64.powf(1.0 / 6.0) * spc_e_sites()[0].sigma;
        if d.r_cut <= well {
            return Err(SceneError::invalid(
                key("r_cut"),
                format!(
                    "{} Å is inside the oxygens' Lennard-Jones well at {well:.4} Å: the cut-off \
                     must lie beyond it (9 to 12 Å are usual)",
                    d.r_cut
                ),
            ));
        }
        Ok(())
    }
    fn scale_energy(&mut self, e: f64) {
        self.energy_unit *= e;
    }
    /// The oxygens' Lennard-Jones well, the smallest of its energies.
    fn well_depth(&self) -> f64 {
        self.energy_unit * spc_e_sites()[0].epsilon
    }
    /// The oxygens' σ, and the longest contact distance `σ + 2 arm`.
    fn lengths(&self) -> (f64, f64) {
        let sigma = spc_e_sites()[0].sigma;
        (sigma, sigma + 2.0 * Self::arm())
    }
    /// The oxygen (1.0 Å) and two hydrogens (0.6 Å) at the model's geometry.
    fn drawing(&self) -> Drawing {
        let sites = spc_e_sites();
        Drawing::Sites {
            centres: sites.iter().map(|s| s.position).collect(),
            diameters: vec![1.0, 0.6, 0.6],
        }
    }
    /// The site cut-off acts on molecule pairs between `R_c − 2 arm` and `R_c + 2 arm`, and
    /// the pair energy is zero beyond: the window is the potential's own.
    fn own_window(&self) -> Option<(f64, f64)> {
        let r_cut = self.dsf().r_cut;
        let arms = 2.0 * Self::arm();
        Some((r_cut - arms, r_cut + arms))
    }
    fn smd_dt(&self) -> Option<f64> {
        Some(SPC_E_DT)
    }
    /// The oxygen and the two hydrogens at the model's geometry, in the body frame of
    /// [`spc_e_sites`].
    fn sites(&self) -> Option<MoleculeSites> {
        Some(MoleculeSites {
            names: ["O", "H", "H"].map(str::to_owned).to_vec(),
            offsets: spc_e_sites().iter().map(|s| s.position).collect(),
        })
    }
    fn units(&self) -> Option<UnitSystem> {
        Some(UnitSystem::Molecular)
    }
}

impl Kind for SpcESpec {
    const MODEL: &'static str = "terraced-tops";
    type Terraced = Rigid<SiteSite>;
    type Smd = smd::Rigid<SiteSite>;

    fn select(spec: &PotentialSpec) -> Option<Self> {
        match spec {
            PotentialSpec::SpcE(k) => Some(*k),
            _ => None,
        }
    }

    fn terraces(
        &self,
        k: usize,
        t: &TerraceSpec,
        kt: f64,
        scale: f64,
    ) -> Result<PairTerraces<Rigid<SiteSite>>, SceneError> {
        let p = self.potential().map_err(|e| potential_error(k, e))?;
        let map = plain_terrace_map(k, p.minimum(), t, kt, scale)?;
        // The minimum holds for pairs that never crossed the barrier of the lower bound
        // (`potential::site_site`): the hard core must stop them before it.
        if map.core() >= p.barrier() {
            return Err(SceneError::invalid(
                format!("pair[{k}].terraces.core"),
                format!(
                    "the hard core {} kJ/mol is at or above {} kJ/mol, the barrier behind which \
                     a hydrogen can fall onto another molecule's oxygen without limit: lower it",
                    map.core() / scale,
                    p.barrier() / scale
                ),
            ));
        }
        pair_terraces(k, PairTerraces::new(Rigid(p), map))
    }

    fn smd(&self, _: (f64, f64)) -> Result<smd::Rigid<SiteSite>, SceneError> {
        let p = self.potential().map_err(|e| potential_error(0, e))?;
        let cutoff = p.cutoff();
        smd::Rigid::new(p, cutoff)
            .map_err(|e| SceneError::invalid("pair[0].potential", e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn internal_units_scale_every_energy() {
        let spec = |u: f64| SpcESpec {
            alpha: None,
            r_cut: None,
            energy_unit: u,
        };
        let (a, b) = (
            spec(1.0).potential().unwrap(),
            spec(100.0).potential().unwrap(),
        );
        let g = potential::RigidGeometry::new(
            glam::DVec3::new(2.9, 0.4, -0.3),
            glam::DQuat::from_rotation_y(0.8),
            glam::DQuat::from_rotation_x(-1.3),
        );
        let (ea, eb) = (a.evaluate(&g).unwrap(), b.evaluate(&g).unwrap());
        assert!((eb.energy - 100.0 * ea.energy).abs() < 1e-11 * eb.energy.abs());
        assert!((b.minimum() - 100.0 * a.minimum()).abs() < 1e-6 * b.minimum().abs());
        assert_eq!(a.cutoff(), b.cutoff());
        // The scene's moments are the model's, from its site masses.
        let t = potential::site_site::inertia_tensor(&spc_e_sites());
        for (k, m) in potential::site_site::SPC_E_MOMENTS.iter().enumerate() {
            assert!((t[k][k] - m).abs() < 5e-5 * m);
        }
        let (lo, hi) = spec(1.0).own_window().unwrap();
        assert!((hi - a.cutoff()).abs() < 1e-12 && lo < 9.0);
    }
}
