//! Why a rule refused its input.

use thiserror::Error;

/// A bad input to a body constructor or an impulse rule. Every variant names the offending
/// quantity; no rule returns NaN velocities instead of one of these.
#[derive(Clone, Debug, PartialEq, Error)]
#[non_exhaustive]
pub enum CollideError {
    /// A mass that is zero, negative, infinite or NaN.
    #[error("mass must be positive and finite, got {0}")]
    Mass(f64),
    /// The mass of one atom of a molecule is zero, negative, infinite or NaN.
    #[error("mass of atom {index} must be positive and finite, got {mass}")]
    AtomMass {
        /// Index of the atom in its molecule.
        index: usize,
        /// The mass given.
        mass: f64,
    },
    /// A principal moment of inertia that is negative, infinite or NaN.
    #[error("principal moments of inertia must be positive and finite, got {0:?}")]
    Moment([f64; 3]),
    /// A principal moment of inertia is zero: the body is linear.
    #[error(
        "a principal moment of inertia is zero ({0:?}): the body is linear; describe it with \
         LinearBody::new(mass, perpendicular_moment, axis)"
    )]
    ZeroMoment([f64; 3]),
    /// Principal moments that no distribution of mass can have (`I_a > I_b + I_c`).
    #[error(
        "principal moments {0:?} violate the triangle inequality I_a <= I_b + I_c: no body has them"
    )]
    ImpossibleMoments([f64; 3]),
    /// An attitude quaternion that is zero, not finite, or far from unit length.
    #[error("attitude must be a unit quaternion, got one of length {0}")]
    Attitude(f64),
    /// A lab-frame inertia tensor that is not symmetric, not finite, not positive definite, or
    /// not the tensor of any mass distribution.
    #[error("lab-frame inertia tensor is {0}")]
    Inertia(&'static str),
    /// The axis of a linear body is zero or not finite.
    #[error("axis of a linear body must be a finite nonzero vector, got {0:?}")]
    Axis([f64; 3]),
    /// A torque on a linear body has a component along its axis, about which the body has no
    /// moment of inertia: no finite impulse can deliver it.
    #[error(
        "torque on a linear body has a component {along} along its axis (magnitude {magnitude}): \
         a linear body takes only torques perpendicular to its axis"
    )]
    AxialTorque {
        /// Component of the torque along the axis.
        along: f64,
        /// Magnitude of the torque.
        magnitude: f64,
    },
    /// A nonzero torque on a body described without rotational inertia.
    #[error("torque {0:?} on a particle, which has no rotational inertia")]
    TorqueOnParticle([f64; 3]),
    /// The impulse direction moves nothing: force and torques vanish, the contact direction is
    /// zero, or the colliding atoms cannot move relative to each other.
    #[error(
        "the impulse has no effect on the participants ({0}); there is no collision to resolve"
    )]
    NoImpulse(&'static str),
    /// An input that must be a finite number is NaN or infinite.
    #[error("{0} is not finite")]
    NotFinite(&'static str),
    /// A model that integrates the free motion numerically could not continue it to the event
    /// (a semi-flexible molecule whose RATTLE step is too long for its motion).
    #[error("the free motion could not be integrated to the event: {0}")]
    FreeMotion(&'static str),
    /// The potential-energy change is NaN or −∞.
    #[error(
        "potential-energy change must be finite or +infinity (a hard core), got {0}; \
         -infinity would release unbounded energy"
    )]
    PotentialChange(f64),
    /// The impulse scalar overflowed (inputs of extreme magnitude).
    #[error("the impulse scalar overflowed; rescale the inputs (a = {a}, b = {b}, dV = {delta_v})")]
    Overflow {
        /// Coefficient of `S²`.
        a: f64,
        /// Coefficient of `S`.
        b: f64,
        /// Potential-energy change.
        delta_v: f64,
    },
    /// Slices describing one molecule have different lengths.
    #[error("molecule has {masses} masses, {positions} positions and {velocities} velocities")]
    Lengths {
        /// Number of masses.
        masses: usize,
        /// Number of positions.
        positions: usize,
        /// Number of velocities.
        velocities: usize,
    },
    /// An atom index (of a constraint or of a colliding atom) outside the molecule.
    #[error("atom index {index} is out of range for a molecule of {count} atoms")]
    AtomIndex {
        /// The index given.
        index: usize,
        /// Number of atoms in the molecule.
        count: usize,
    },
    /// A distance constraint or a collision that joins an atom to itself, or atoms at the same
    /// position.
    #[error("atoms {0} and {1} coincide or are the same atom; their distance has no direction")]
    Coincident(usize, usize),
    /// The distance constraints are redundant or singular (`Z` is not positive definite).
    #[error(
        "the distance constraints are redundant or singular: constraint {index} adds a pivot of \
         relative size {pivot:e} to the Z matrix (independent constraints need more than {tolerance:e})"
    )]
    DependentConstraints {
        /// Index of the first constraint found dependent on the ones before it.
        index: usize,
        /// Its pivot relative to its diagonal entry of `Z`.
        pivot: f64,
        /// The smallest relative pivot accepted.
        tolerance: f64,
    },
}
