//! Exact torque-free motion of rigid bodies, for event-driven simulators.
//!
//! Between events a rigid body moves freely, and its rotation has a closed form (seed 000 §II.B;
//! R. van Zon and J. Schofield, J. Comput. Phys. 225, 145 (2007)): uniform rotation for a
//! spherical rotor or a rod, trigonometric functions for a symmetric top, Jacobi elliptic
//! functions and a theta series for an asymmetric top. [`FreeMotion`] chooses the solution once
//! per state from the [`Moments`] and the angular velocity, does the set-up work then, and
//! evaluates the [`Pose`] at any later (or earlier) time cheaply: a root search asks for hundreds
//! of times per pair. [`LinearRotor`] is the rod of seed 003 §V, whose only state is its axis.
//! The special functions live in [`elliptic`].
//!
//! Conventions (free-rigid-body.md): the attitude `A` maps lab to body components; `ω` is in the
//! body frame; `dA/dt = −W(ω) A`; the propagator is `P(t) = A(t) A(0)ᵀ`.
//!
//! ```
//! use glam::{DMat3, DVec3};
//! use rigid_free::{FreeMotion, Moments};
//!
//! let moments = Moments::new([1.0, 1.7, 2.1])?;
//! let motion = FreeMotion::new(&moments, DMat3::IDENTITY, DVec3::new(0.3, -1.0, 0.8))?;
//! let tip = DVec3::new(0.5, 0.0, 0.0); // a body-fixed point
//! for t in [0.1, 0.2, 0.3] {
//!     let pose = motion.pose(t);
//!     let (r, v) = (pose.lab_vector(tip), pose.lab_velocity(tip));
//!     assert!((r.length() - 0.5).abs() < 1e-15 && r.dot(v).abs() < 1e-14);
//! }
//! # Ok::<(), rigid_free::FreeError>(())
//! ```

mod asymmetric;
mod attitude;
mod axes;
pub mod elliptic;
mod error;
mod exact;
mod linear;
mod moments;
mod motion;
mod separatrix;
mod symmetric;
mod theta;
mod trig;
mod uniform;

pub use asymmetric::AsymmetricTop;
pub use attitude::{attitude_from_quat, quat_from_attitude};
pub use error::FreeError;
pub use linear::LinearRotor;
pub use moments::{BodyKind, Moments};
pub use motion::{Case, FreeMotion, MotionKind, Pose};
pub use separatrix::SeparatrixTop;
pub use symmetric::SymmetricTop;
pub use uniform::UniformRotation;
