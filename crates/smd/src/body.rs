//! What the bodies are: their mass and how (whether) they rotate.

use glam::DVec3;
use rigid_free::{BodyKind, Moments};

use crate::SmdError;
use crate::error::positive;

/// The body model of a system (all bodies alike).
///
/// The pair potentials of `dmd-potential` see one unit axis per body (`s_i`, 003 §II), so
/// every rotating model says which body-fixed direction that axis is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BodyModel {
    /// A point mass: no orientation, no rotation, no torque is ever computed.
    Sphere {
        /// Mass.
        mass: f64,
    },
    /// A linear rotor (the rods of 003 §V): state is the unit axis `s` and the lab angular
    /// momentum `L = I ω` with `ω ⊥ s`; the spin about `s` is decoupled and left out. Torques
    /// of uniaxial potentials are perpendicular to `s`, so `ω` stays perpendicular to it.
    LinearRotor {
        /// Mass.
        mass: f64,
        /// Moment of inertia about any axis perpendicular to the rod.
        inertia: f64,
    },
    /// A general rigid body (symmetric or asymmetric top), rotated with the exact free motion
    /// of `rigid-free` ([`rigid_free::FreeMotion`]); the potential sees the body-fixed `axis`.
    Rigid {
        /// Mass.
        mass: f64,
        /// Principal moments of inertia (body frame).
        moments: Moments,
        /// The unit body-frame vector the potential sees as the body's axis.
        axis: DVec3,
    },
}

impl BodyModel {
    /// A point mass.
    ///
    /// # Errors
    /// [`SmdError::Parameter`] unless the mass is finite and positive.
    pub fn sphere(mass: f64) -> Result<Self, SmdError> {
        Ok(Self::Sphere {
            mass: positive("mass", mass)?,
        })
    }

    /// A linear rotor of `mass` and moment of inertia `inertia` about its perpendicular axes.
    ///
    /// # Errors
    /// [`SmdError::Parameter`] unless both are finite and positive.
    pub fn linear_rotor(mass: f64, inertia: f64) -> Result<Self, SmdError> {
        Ok(Self::LinearRotor {
            mass: positive("mass", mass)?,
            inertia: positive("inertia", inertia)?,
        })
    }

    /// The paper's rods (003 §V): `m = 18 g/mol`, `I₁ = I₂ = 1.154 g/mol·Å²`.
    pub fn paper_rod() -> Self {
        Self::LinearRotor {
            mass: 18.0,
            inertia: 1.154,
        }
    }

    /// A rigid body with principal moments `moments` whose potential axis is the body-frame
    /// direction `axis` (normalised here).
    ///
    /// # Errors
    /// [`SmdError::Parameter`] for a bad mass, [`SmdError::Body`] for moments rigid-free
    /// refuses, [`SmdError::Inconsistent`] for a zero or non-finite axis or for moments with a
    /// zero (a linear body: use [`BodyModel::linear_rotor`]).
    pub fn rigid(mass: f64, moments: [f64; 3], axis: DVec3) -> Result<Self, SmdError> {
        let mass = positive("mass", mass)?;
        let moments = Moments::new(moments)?;
        if let BodyKind::Linear { .. } = moments.kind() {
            return Err(SmdError::Inconsistent(format!(
                "moments {:?} have a zero: that is a linear body, use BodyModel::linear_rotor",
                moments.get()
            )));
        }
        let axis = if axis.is_finite() {
            axis.try_normalize()
        } else {
            None
        }
        .ok_or_else(|| {
            SmdError::Inconsistent(format!(
                "the body axis {axis} must be a finite non-zero vector"
            ))
        })?;
        Ok(Self::Rigid {
            mass,
            moments,
            axis,
        })
    }

    /// The mass.
    pub fn mass(&self) -> f64 {
        match *self {
            Self::Sphere { mass } | Self::LinearRotor { mass, .. } | Self::Rigid { mass, .. } => {
                mass
            }
        }
    }

    /// Rotational degrees of freedom per body: 0 (sphere), 2 (linear rotor), 3 (rigid).
    pub fn rotational_dof(&self) -> usize {
        match self {
            Self::Sphere { .. } => 0,
            Self::LinearRotor { .. } => 2,
            Self::Rigid { .. } => 3,
        }
    }

    /// Whether the bodies have an orientation at all.
    pub fn rotates(&self) -> bool {
        !matches!(self, Self::Sphere { .. })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_bodies_are_named() {
        assert!(
            BodyModel::sphere(0.0)
                .unwrap_err()
                .to_string()
                .contains("mass")
        );
        assert!(
            BodyModel::linear_rotor(1.0, f64::NAN)
                .unwrap_err()
                .to_string()
                .contains("inertia")
        );
        let e = BodyModel::rigid(1.0, [0.0, 1.0, 1.0], DVec3::X).unwrap_err();
        assert!(e.to_string().contains("linear_rotor"), "{e}");
        let e = BodyModel::rigid(1.0, [1.0, 2.0, 2.5], DVec3::ZERO).unwrap_err();
        assert!(e.to_string().contains("axis"), "{e}");
        assert!(BodyModel::rigid(1.0, [1.0, 1.0, 5.0], DVec3::Z).is_err());
        let b = BodyModel::rigid(2.0, [1.0, 2.0, 2.5], DVec3::new(0.0, 0.0, 3.0)).unwrap();
        assert!(matches!(b, BodyModel::Rigid { axis, .. } if axis == DVec3::Z));
        assert_eq!((b.mass(), b.rotational_dof()), (2.0, 3));
        assert_eq!(BodyModel::paper_rod().rotational_dof(), 2);
    }
}
