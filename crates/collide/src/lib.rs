//! Impulse rules for event-driven ("discontinuous") molecular dynamics of rigid bodies.
//!
//! At an event two bodies (or two atoms) change terrace of their pair potential. This crate
//! takes the state of the participants at that instant and returns their new velocities,
//! conserving total energy (kinetic plus the potential step `ΔV`), linear momentum, angular
//! momentum and, for molecules, the velocity constraints. It knows nothing of scenes, cells or
//! time. The rules, after the seed papers:
//!
//! - [`spheres`]: hard spheres and square wells, the cheap special case;
//! - [`terrace`]: the impulse along the continuous force and torques of a terraced potential,
//!   one scalar `S` (003 §IV, Eq. 21), for unequal masses and full inertia tensors;
//! - [`contact`]: an impulse along the line joining two sites of two rigid bodies (000 §IV.B);
//! - [`ConstraintSolver`]: atoms held by distance constraints, with impulsive constraint forces
//!   from the `Z` matrix (000 §IV.A), for rigid and semi-flexible molecules.
//!
//! All of them end in the same quadratic for `S` ([`energy::solve`]): the pair crosses the step
//! ([`Outcome::Crossed`]) or, without the kinetic energy to climb it, is reflected
//! ([`Outcome::Reflected`]); a hard core is `ΔV = +∞`. Bodies are [`Particle`], [`LinearBody`]
//! (rods) and [`RigidBody`]; the rules are generic over [`Body`], so each pairing compiles to
//! its own code, and none of the rigid-body rules allocates.
//!
//! ```
//! use collide::{Outcome, Particle, spheres};
//! use glam::DVec3;
//!
//! // Two equal hard spheres meeting head on exchange their velocities.
//! let p = Particle::new(1.0)?;
//! let out = spheres(&p, &p, DVec3::new(1.0, 0.0, 0.0), DVec3::new(-1.0, 0.0, 0.0),
//!                   DVec3::new(-1.0, 0.0, 0.0), f64::INFINITY)?;
//! assert_eq!(out.impulse.outcome, Outcome::Reflected);
//! assert_eq!((out.i, out.j), (DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0)));
//! # Ok::<(), collide::CollideError>(())
//! ```

mod body;
mod constraint;
mod contact;
pub mod energy;
mod error;
mod sphere;
mod terrace;

pub use body::{AXIAL_TORQUE_TOLERANCE, Body, LinearBody, Particle, RigidBody, Velocity};
pub use constraint::{Bond, ConstraintSolver, MOBILITY_TOLERANCE, Molecule, PIVOT_TOLERANCE};
pub use contact::{Contact, contact};
pub use energy::{Impulse, Outcome};
pub use error::CollideError;
pub use sphere::spheres;
pub use terrace::{PairForce, terrace};

/// The result of a two-body rule: what happened and the new velocities of `i` and `j`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Collision<V> {
    /// The outcome, the scalar `S` and the potential energy exchanged.
    pub impulse: Impulse,
    /// New velocity of body `i`.
    pub i: V,
    /// New velocity of body `j`.
    pub j: V,
}
