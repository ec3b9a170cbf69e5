//! The one error type of the crate: every bad input gets its own variant and message.

use std::fmt;

/// What was wrong with an input.
///
/// The crate never panics on user input and never returns NaN silently: a non-finite or
/// physically impossible input is refused with one of these.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum FreeError {
    /// A principal moment of inertia is NaN or infinite.
    NonFiniteMoment {
        /// Which moment (0, 1 or 2).
        axis: usize,
        /// Its value.
        value: f64,
    },
    /// A principal moment of inertia is negative.
    NegativeMoment {
        /// Which moment (0, 1 or 2).
        axis: usize,
        /// Its value.
        value: f64,
    },
    /// More than one principal moment is zero: no rigid body has that inertia.
    TooManyZeroMoments,
    /// One moment is zero but the other two differ: only a linear rotor (a rod) may have a zero
    /// moment, and then its other two moments are equal.
    ZeroMomentUnequalOthers {
        /// The two non-zero moments.
        others: [f64; 2],
    },
    /// The moments violate the triangle inequality `I_a ≤ I_b + I_c` that every mass
    /// distribution obeys.
    TriangleInequality {
        /// The three moments as given.
        moments: [f64; 3],
    },
    /// A vector argument (angular velocity, axis, body vector) has a NaN or infinite component.
    NonFiniteVector {
        /// Which argument.
        what: &'static str,
    },
    /// The attitude is not a proper rotation (not orthonormal to 1e-9, or det ≠ +1).
    NotARotation {
        /// The largest deviation of `AᵀA` from the identity, or of `det A` from 1.
        deviation: f64,
    },
    /// The axis of a linear rotor is the zero vector.
    ZeroAxis,
    /// An elliptic parameter is outside the range the function accepts.
    ParameterOutOfRange {
        /// The function.
        function: &'static str,
        /// The parameter's name.
        name: &'static str,
        /// Its value.
        value: f64,
    },
}

impl fmt::Display for FreeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NonFiniteMoment { axis, value } => {
                write!(
                    f,
                    "moment of inertia I{} = {value} is not a finite number",
                    axis + 1
                )
            }
            Self::NegativeMoment { axis, value } => {
                write!(f, "moment of inertia I{} = {value} is negative", axis + 1)
            }
            Self::TooManyZeroMoments => {
                write!(
                    f,
                    "at most one moment of inertia may be zero (a linear rotor)"
                )
            }
            Self::ZeroMomentUnequalOthers { others } => write!(
                f,
                "a zero moment of inertia means a linear rotor, whose other two moments must be \
                 equal, but they are {} and {}",
                others[0], others[1]
            ),
            Self::TriangleInequality { moments } => write!(
                f,
                "moments of inertia {}, {}, {} violate the triangle inequality (each must be at \
                 most the sum of the other two)",
                moments[0], moments[1], moments[2]
            ),
            Self::NonFiniteVector { what } => {
                write!(f, "{what} has a component that is not a finite number")
            }
            Self::NotARotation { deviation } => write!(
                f,
                "the attitude matrix is not a proper rotation (deviation {deviation:e} from \
                 orthonormal with det = +1)"
            ),
            Self::ZeroAxis => write!(f, "the axis of a linear rotor is the zero vector"),
            Self::ParameterOutOfRange {
                function,
                name,
                value,
            } => write!(f, "{function}: {name} = {value} is out of range"),
        }
    }
}

impl std::error::Error for FreeError {}
