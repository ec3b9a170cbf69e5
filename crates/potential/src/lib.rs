//! Smooth orientation-dependent pair potentials and the terrace map that turns them into
//! energy terraces, for event-driven ("discontinuous") and standard molecular dynamics of rigid
//! bodies.
//!
//! The seed paper (R. van Zon and J. Schofield, J. Chem. Phys. 128, 154119 (2008), "003")
//! simulates rigid bodies on a *terraced* version of a smooth pair potential `U`: the energy
//! changes only when `U` crosses one of a set of levels, and the impulse at such an event points
//! along the smooth potential's force and torques. Both the event-driven engine and a standard
//! MD reference use the same smooth potential, so it lives here:
//!
//! - [`PairPotential`]: energy, force and both torques of a pair of uniaxial bodies from the
//!   separation `r_ij` and the axes `s_i`, `s_j` (003 Eqs. 4–6), its minimum, and the reach of a
//!   level; [`pair::assemble`] builds force and torques from the partial derivatives of `U`,
//!   and [`PairEval::rate`] gives `U̇` along free motion (003 Eq. 12);
//! - [`LennardJones`] spheres, the modified Lennard-Jones rods [`LjRod`] of 003 Eqs. 22–25,
//!   and [`GayBerne`] (Gay and Berne 1981);
//! - [`Smoothed`]: any potential switched off between `r_l` and `r_u` for standard MD
//!   (003 Eq. 26);
//! - [`TerraceMap`]: the terraced potential of 003 Eq. 7 with a hard core, the paper's evenly
//!   spaced levels or explicit ones, and the placement and step-energy rules of stepped
//!   potentials on a radial [`Profile`] ([`Placement`], [`StepEnergy`]);
//! - [`certify`]: certified event prediction, a Taylor model with a rigorous remainder of an
//!   effective coordinate (`r`, or the rods' `r_e`) that proves stretches of free flight
//!   without a level crossing;
//! - [`RigidPairPotential`] (the [`rigid`] module): the same energy, force and both torques for
//!   bodies of any shape, from the separation and each body's whole attitude (a [`RigidGeometry`]
//!   with one `DQuat` per body; 003 Eqs. 4–6 generalised); [`Uniaxial`] makes every
//!   [`PairPotential`] one (axis = attitude · body `ẑ`), bit for bit;
//! - [`SoftStickyDipole`] (the [`water`] module): the single-site SSD/E water of Fennell and
//!   Gezelter (2004) in kJ/mol, Å, amu, ps, switched to zero at a 9 Å cut-off, with its inertia
//!   tensor and rigorous bounds (minimum, reach of a level) for the terrace map;
//! - [`SiteSite`] (the [`site_site`] module): rigid molecules of sites with site–site
//!   Lennard-Jones and damped shifted force Coulomb terms (Fennell and Gezelter 2006), forces
//!   and torques from the site forces, and SPC/E water;
//! - [`reach`], [`virial`], [`quadrature`]: the reach of a level for any potential, second virial
//!   coefficients of the smooth and terraced potentials, and the quadrature behind them.
//!
//! ```
//! use glam::DVec3;
//! use potential::{LjRod, PairGeometry, PairPotential, TerraceMap, TerraceOptions};
//!
//! // Two of the paper's rods (kJ/mol, Å), crossed, 4 Å apart.
//! let rod = LjRod::paper();
//! let g = PairGeometry::new(DVec3::new(4.0, 0.0, 0.0), DVec3::Z, DVec3::new(0.0, 0.6, 0.8));
//! let e = rod.evaluate(&g)?;
//! assert!(e.energy < 0.0);
//! assert!(e.torque_imbalance(g.r_ij) < 1e-15);       // 003 Eq. 6
//! assert!(e.torque_i.dot(g.s_i).abs() < 1e-15);      // no torque about the rod's axis
//!
//! // The paper's terraces with ΔV = kT/2 at T* = 1.4, and the cell size they need.
//! let kt = 1.4 * rod.epsilon();
//! let map = TerraceMap::evenly_spaced(&rod, kt / 2.0, &TerraceOptions::default())?;
//! let k = map.terrace_of(e.energy)?;
//! assert!(map.energy(k)? < 0.0);
//! let r_m = map.reach(&rod)?;
//! let dv = kt / 2.0; // 003 Eq. 25:
//! let eq25 = 0.5 * rod.zeta()
//!     + rod.sigma() / (0.5 * (1.0 - (1.0 - dv / (2.0 * rod.epsilon())).sqrt())).powf(1.0 / 6.0);
//! assert!((r_m - eq25).abs() < 1e-12 * eq25);
//! # Ok::<(), potential::PotentialError>(())
//! ```

pub mod certify;
mod error;
mod gay_berne;
mod lennard_jones;
pub mod pair;
mod placement;
pub mod profile;
pub mod quadrature;
pub mod reach;
pub mod rigid;
mod rod;
pub mod site_site;
mod smoothing;
mod solve;
mod terrace;
pub mod virial;
pub mod water;

pub use certify::{FreeFlight, Rates, RigidFlight, TaylorModel};
pub use error::PotentialError;
pub use gay_berne::GayBerne;
pub use lennard_jones::LennardJones;
pub use pair::{Invariants, PairEval, PairGeometry, PairPotential, Partials};
pub use placement::{Layout, Placement, StepEnergy};
pub use profile::{Profile, Shell};
pub use rigid::{RigidGeometry, RigidPairPotential, Uniaxial};
pub use rod::LjRod;
pub use site_site::{Dsf, Site, SiteSite};
pub use smoothing::Smoothed;
pub use terrace::{
    Bounds, DEFAULT_CORE_DEPTHS, DEFAULT_MINIMUM_TOLERANCE, LevelSet, MAX_LEVELS, NearMinimum,
    Steps, TerraceMap, TerraceOptions,
};
pub use water::{SoftStickyDipole, SsdParameters};

/// The README's example, compiled and run as a doctest so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
