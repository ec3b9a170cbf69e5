//! Reference standard molecular dynamics (SMD) of rigid bodies with continuous pair potentials:
//! the baseline the event-driven engine is judged against (seed 003 §V.B).
//!
//! - [`Integrator`]: a symplectic, time-reversible splitting (half kick with forces and
//!   torques, drift with the **exact** free rotation of `rigid-free`, half kick) for spheres,
//!   linear rotors (the paper's rods) and general rigid bodies ([`BodyModel`]);
//! - Verlet neighbour lists with a skin, built from cells and rebuilt when a body has moved
//!   half the skin; the potential smoothed to zero between `r_l` and `r_u` (003 Eq. 26,
//!   [`potential::Smoothed`]) and evaluated with the same `PairPotential::evaluate` as the
//!   event-driven engine, generic over the potential (static dispatch); rigid tops on a
//!   full-attitude [`potential::RigidPairPotential`] that vanishes beyond its own cut-off
//!   (SSD/E or SPC/E water) through [`Rigid`], with the forces and torques of
//!   `RigidPairPotential::evaluate` ([`Interaction`] is either kind);
//! - [`System`]: bodies in a periodic box from a lattice, random orientations and
//!   Maxwell–Boltzmann velocities ([`Setup`]), or from explicit state;
//! - [`observe`]: g(r), MSD, normalised VACF, orientational ACF, energy, temperature and
//!   pressure series, written as CSV; [`run`]: one call from parameters to results;
//! - [`units`]: kJ/mol, Å, g/mol make the time unit 0.1 ps; conversions to and from fs;
//! - [`reference`](mod@reference): the Kolafa–Nezbeda Lennard-Jones equation of state and the
//!   correction from the smoothed to the full potential, to check runs (SMD or terraced DMD)
//!   against.
//!
//! A run that blows up is an error ([`SmdError::Unstable`], [`SmdError::Overlap`]), never NaN.
//!
//! ```
//! use potential::{LjRod, Smoothed};
//! use smd::{BodyModel, Integrator, Lattice, Settings, Setup, System, units};
//!
//! // 256 of the paper's rods (kJ/mol, Å, g/mol) at ρ* = 0.5, T* = 1.4; dt = 1.8 fs.
//! let rod = LjRod::paper();
//! let kt = 1.4 * rod.epsilon();
//! let density = units::density_from_reduced(0.5, rod.sigma());
//! let setup = Setup { lattice: Lattice::Sc, ..Setup::new(256, density, BodyModel::paper_rod(), kt) };
//! let smoothed = Smoothed::paper(rod, rod.sigma())?; // 003 Eq. 26: r_l = 2.5σ, r_u = 3σ
//! let settings = Settings::new(units::from_fs(1.8), 1.0); // skin 1 Å
//! let mut md = Integrator::new(System::new(&setup)?, smoothed, settings)?;
//! let e0 = md.energy().total();
//! md.run(100, 10, &mut ())?;
//! // Linear rotors stay linear rotors: ω ⊥ s.
//! let s = md.system();
//! for (a, l) in s.axes().iter().zip(s.angular_momenta()) {
//!     assert!(a.dot(*l).abs() <= 1e-12 * l.length());
//! }
//! assert!((md.energy().total() - e0).abs() < 0.01 * 256.0 * kt);
//! # Ok::<(), smd::SmdError>(())
//! ```

mod body;
mod error;
mod forces;
mod integrator;
mod neighbour;
pub mod observe;
pub mod output;
pub mod reference;
pub mod run;
mod system;
pub mod timing;
pub mod units;

pub use body::BodyModel;
pub use error::SmdError;
pub use forces::{Interaction, Rigid};
pub use integrator::{DEFAULT_GUARD, Energy, Integrator, Observer, RunStats, Settings, Snapshot};
pub use neighbour::capped_cell_dims;
pub use system::{Lattice, MAX_BODIES, Orientations, Setup, System};

/// The README's example, compiled and run as a doctest so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
