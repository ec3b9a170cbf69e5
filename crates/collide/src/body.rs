//! The participants of an event, seen only through how they respond to an impulse.
//!
//! An impulse `S·F` on the centre of mass and an angular impulse `S·τ` change a body's velocity
//! by `S·F/m` and its angular velocity by `S·I⁻¹τ` (000 §IV.B, 003 Eqs. 16–19). That is all a
//! rule needs to know about a body: its inverse mass and the action of its inverse lab-frame
//! inertia tensor on a torque. [`Body`] says exactly that, and each kind of body pays only for
//! what it has:
//!
//! - [`Particle`]: a mass and no rotation (spheres, atoms);
//! - [`LinearBody`]: a rod, whose moment about its own axis is zero, so that its angular
//!   velocity stays perpendicular to the axis and it accepts only perpendicular torques;
//! - [`RigidBody`]: a full, positive definite inertia tensor, given in the lab frame or as
//!   principal moments and an attitude.

use glam::{DMat3, DQuat, DVec3};

use crate::CollideError;

/// The velocity of a body at the instant of an event.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Velocity {
    /// Velocity of the centre of mass (lab frame).
    pub linear: DVec3,
    /// Angular velocity (lab frame). Ignored for a [`Particle`].
    pub angular: DVec3,
}

impl Velocity {
    /// A velocity from its linear and angular parts.
    #[inline]
    pub const fn new(linear: DVec3, angular: DVec3) -> Self {
        Self { linear, angular }
    }
}

/// How a body responds to an impulse: its inverse mass and inverse inertia.
///
/// Implementations must describe a physical body: a positive finite inverse mass, and an
/// `angular_response` that is a symmetric positive semi-definite linear map (the inverse, or on
/// a linear body the pseudo-inverse, of the lab-frame inertia tensor). The rules are generic over
/// this trait, so each pair of body kinds is compiled to its own code with no dynamic dispatch.
pub trait Body {
    /// `1/m`.
    fn inv_mass(&self) -> f64;

    /// `I⁻¹τ` in the lab frame: the change of angular velocity per unit angular impulse `τ`.
    ///
    /// # Errors
    /// When the body cannot take this torque: any nonzero torque on a [`Particle`], a torque along
    /// the axis of a [`LinearBody`].
    fn angular_response(&self, torque: DVec3) -> Result<DVec3, CollideError>;
}

fn check_mass(mass: f64) -> Result<f64, CollideError> {
    if mass.is_finite() && mass > 0.0 {
        Ok(1.0 / mass)
    } else {
        Err(CollideError::Mass(mass))
    }
}

/// A point mass, or a sphere whose interactions act through its centre: no rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    inv_mass: f64,
}

impl Particle {
    /// A particle of mass `mass`.
    ///
    /// # Errors
    /// [`CollideError::Mass`] unless `mass` is positive and finite.
    pub fn new(mass: f64) -> Result<Self, CollideError> {
        Ok(Self {
            inv_mass: check_mass(mass)?,
        })
    }

    /// The mass.
    pub fn mass(&self) -> f64 {
        1.0 / self.inv_mass
    }
}

impl Body for Particle {
    #[inline(always)]
    fn inv_mass(&self) -> f64 {
        self.inv_mass
    }

    #[inline(always)]
    fn angular_response(&self, torque: DVec3) -> Result<DVec3, CollideError> {
        if torque == DVec3::ZERO {
            Ok(DVec3::ZERO)
        } else {
            Err(CollideError::TorqueOnParticle(torque.to_array()))
        }
    }
}

/// Largest component of a torque along the axis of a linear body, relative to the torque's
/// magnitude, that is taken for round-off and removed. Torques of a potential that depends on
/// the axis `s` alone are `s × (…)` and have no such component; anything larger than this is a
/// modelling error and is refused rather than silently dropped (it would break angular-momentum
/// conservation).
pub const AXIAL_TORQUE_TOLERANCE: f64 = 1e-9;

/// A linear body (a rod): principal moments `(I, I, 0)` about its centre of mass.
///
/// Its moment about its own axis `s` is zero, so its angular velocity is perpendicular to `s`
/// and only the perpendicular part of a torque can change it: `Δω = S·τ/I` for `τ ⊥ s`. The
/// inertia tensor `I(1 − s sᵀ)` is singular; the rule uses its pseudo-inverse, which is exact on
/// the torques a linear body can receive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearBody {
    inv_mass: f64,
    inv_moment: f64,
    axis: DVec3,
}

impl LinearBody {
    /// A linear body of mass `mass`, moment `moment` about any axis through its centre
    /// perpendicular to its own, and axis direction `axis` (normalised here).
    ///
    /// # Errors
    /// [`CollideError::Mass`], [`CollideError::Moment`] (moment not positive and finite),
    /// [`CollideError::Axis`] (zero or non-finite axis).
    pub fn new(mass: f64, moment: f64, axis: DVec3) -> Result<Self, CollideError> {
        let inv_mass = check_mass(mass)?;
        if !(moment.is_finite() && moment > 0.0) {
            return Err(CollideError::Moment([moment, moment, 0.0]));
        }
        let len = axis.length();
        if !(len.is_finite() && len > 0.0) {
            return Err(CollideError::Axis(axis.to_array()));
        }
        Ok(Self {
            inv_mass,
            inv_moment: 1.0 / moment,
            axis: axis / len,
        })
    }

    /// The unit axis.
    pub fn axis(&self) -> DVec3 {
        self.axis
    }
}

impl Body for LinearBody {
    #[inline(always)]
    fn inv_mass(&self) -> f64 {
        self.inv_mass
    }

    #[inline]
    fn angular_response(&self, torque: DVec3) -> Result<DVec3, CollideError> {
        let along = torque.dot(self.axis);
        let t2 = torque.length_squared();
        // Compared squared: no square root on the hot path.
        if along * along > AXIAL_TORQUE_TOLERANCE * AXIAL_TORQUE_TOLERANCE * t2 {
            return Err(CollideError::AxialTorque {
                along,
                magnitude: t2.sqrt(),
            });
        }
        Ok((torque - along * self.axis) * self.inv_moment)
    }
}

/// Relative tolerance of the checks on inertia tensors (symmetry, triangle inequality): room
/// for the round-off of a tensor computed from a mass distribution or rotated to the lab frame.
const INERTIA_TOLERANCE: f64 = 1e-10;

/// A rigid body with a positive definite inertia tensor (all three principal moments nonzero).
///
/// Holds the inverse mass and the inverse lab-frame inertia tensor at the instant of the event:
/// build it from the body's current attitude for each event (cheap: no allocation, a few dozen
/// flops).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidBody {
    inv_mass: f64,
    inv_inertia: DMat3,
}

impl RigidBody {
    /// A body of mass `mass` with principal moments `moments` about its centre of mass and
    /// attitude `attitude`, the rotation that takes body-frame vectors to the lab frame
    /// (`a_lab = attitude * a_body`, i.e. the transpose of the paper's matrix `A`). Then
    /// `I_lab⁻¹ = R diag(1/I₁, 1/I₂, 1/I₃) Rᵀ` with `R` the rotation matrix of `attitude`.
    ///
    /// # Errors
    /// [`CollideError::Mass`]; [`CollideError::ZeroMoment`] if a moment is zero (use
    /// [`LinearBody`]); [`CollideError::Moment`] if one is negative or not finite;
    /// [`CollideError::ImpossibleMoments`] if they violate `I_a ≤ I_b + I_c`;
    /// [`CollideError::Attitude`] if `attitude` is not within 1e−6 of unit length.
    pub fn from_principal(
        mass: f64,
        moments: DVec3,
        attitude: DQuat,
    ) -> Result<Self, CollideError> {
        let inv_mass = check_mass(mass)?;
        let m = moments.to_array();
        if !moments.is_finite() || moments.min_element() < 0.0 {
            return Err(CollideError::Moment(m));
        }
        if moments.min_element() == 0.0 {
            return Err(CollideError::ZeroMoment(m));
        }
        let sum = moments.element_sum();
        if 2.0 * moments.max_element() > sum * (1.0 + INERTIA_TOLERANCE) {
            return Err(CollideError::ImpossibleMoments(m));
        }
        let len = attitude.length();
        if !(len.is_finite() && (len - 1.0).abs() <= 1e-6) {
            return Err(CollideError::Attitude(len));
        }
        let r = DMat3::from_quat(attitude / len);
        let w = moments.recip();
        let scaled = DMat3::from_cols(r.x_axis * w.x, r.y_axis * w.y, r.z_axis * w.z);
        Ok(Self {
            inv_mass,
            inv_inertia: scaled * r.transpose(),
        })
    }

    /// A body of mass `mass` with lab-frame inertia tensor `inertia` (about its centre of mass).
    ///
    /// # Errors
    /// [`CollideError::Mass`]; [`CollideError::Inertia`] if the tensor is not finite, not
    /// symmetric (to 1e−10 relative), not positive definite, or not the tensor of any mass
    /// distribution (its principal moments violate the triangle inequality).
    pub fn from_lab_inertia(mass: f64, inertia: DMat3) -> Result<Self, CollideError> {
        let inv_mass = check_mass(mass)?;
        if !inertia.is_finite() {
            return Err(CollideError::Inertia("not finite"));
        }
        let trace = inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z;
        let asym = (inertia - inertia.transpose()).abs().to_cols_array();
        if asym.iter().any(|&d| d > INERTIA_TOLERANCE * trace.abs()) {
            return Err(CollideError::Inertia("not symmetric"));
        }
        let sym = (inertia + inertia.transpose()) * 0.5;
        if !positive_definite(&sym) {
            return Err(CollideError::Inertia("not positive definite"));
        }
        // I = tr(J)·1 − J with J = Σ m r rᵀ positive semi-definite, so a physical tensor has
        // tr(I)/2·1 − I ⪰ 0 (equivalently I_a ≤ I_b + I_c).
        let j = DMat3::from_diagonal(DVec3::splat(0.5 * trace)) - sym;
        if !positive_semidefinite(&j, INERTIA_TOLERANCE * trace) {
            return Err(CollideError::Inertia(
                "not the tensor of any mass distribution (I_a > I_b + I_c)",
            ));
        }
        Ok(Self {
            inv_mass,
            inv_inertia: sym.inverse(),
        })
    }

    /// The inverse lab-frame inertia tensor.
    pub fn inv_inertia(&self) -> DMat3 {
        self.inv_inertia
    }
}

impl Body for RigidBody {
    #[inline(always)]
    fn inv_mass(&self) -> f64 {
        self.inv_mass
    }

    #[inline(always)]
    fn angular_response(&self, torque: DVec3) -> Result<DVec3, CollideError> {
        Ok(self.inv_inertia * torque)
    }
}

/// Sylvester's criterion: all leading principal minors positive.
fn positive_definite(m: &DMat3) -> bool {
    let (a, b, c) = (m.x_axis, m.y_axis, m.z_axis);
    a.x > 0.0 && a.x * b.y - a.y * b.x > 0.0 && m.determinant() > 0.0 && c.z.is_finite()
}

/// All principal minors non-negative (to `tol`, `tol` scaling like an entry of `m`).
fn positive_semidefinite(m: &DMat3, tol: f64) -> bool {
    let d = [m.x_axis.x, m.y_axis.y, m.z_axis.z];
    let minor = |p: usize, q: usize| d[p] * d[q] - m.col(q)[p] * m.col(q)[p];
    let scale = d.iter().map(|x| x.abs()).fold(0.0, f64::max) + tol;
    d.iter().all(|&x| x >= -tol)
        && minor(0, 1) >= -tol * scale
        && minor(0, 2) >= -tol * scale
        && minor(1, 2) >= -tol * scale
        && m.determinant() >= -tol * scale * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masses_must_be_positive_and_finite() {
        for m in [0.0, -1.0, f64::NAN, f64::INFINITY, -0.0] {
            assert!(
                matches!(Particle::new(m), Err(CollideError::Mass(_))),
                "{m}"
            );
            assert!(matches!(
                RigidBody::from_principal(m, DVec3::ONE, DQuat::IDENTITY),
                Err(CollideError::Mass(_))
            ));
            assert!(LinearBody::new(m, 1.0, DVec3::X).is_err());
        }
        assert_eq!(Particle::new(2.0).unwrap().mass(), 2.0);
    }

    #[test]
    fn principal_moments_are_checked() {
        let q = DQuat::IDENTITY;
        assert!(matches!(
            RigidBody::from_principal(1.0, DVec3::new(1.0, 1.0, 0.0), q),
            Err(CollideError::ZeroMoment(_))
        ));
        assert!(matches!(
            RigidBody::from_principal(1.0, DVec3::new(1.0, -1.0, 1.0), q),
            Err(CollideError::Moment(_))
        ));
        assert!(matches!(
            RigidBody::from_principal(1.0, DVec3::new(1.0, 1.0, 2.5), q),
            Err(CollideError::ImpossibleMoments(_))
        ));
        // A flat body sits exactly on the triangle inequality: accepted.
        assert!(RigidBody::from_principal(1.0, DVec3::new(1.0, 2.0, 3.0), q).is_ok());
        assert!(matches!(
            RigidBody::from_principal(1.0, DVec3::ONE, DQuat::from_xyzw(0.0, 0.0, 0.0, 2.0)),
            Err(CollideError::Attitude(_))
        ));
    }

    #[test]
    fn lab_tensor_agrees_with_principal_form() {
        let q = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7);
        let moments = DVec3::new(1.0, 2.0, 2.5);
        let r = DMat3::from_quat(q);
        let lab = r * DMat3::from_diagonal(moments) * r.transpose();
        let a = RigidBody::from_principal(3.0, moments, q).unwrap();
        let b = RigidBody::from_lab_inertia(3.0, lab).unwrap();
        assert!(a.inv_inertia().abs_diff_eq(b.inv_inertia(), 1e-14));
        let tau = DVec3::new(0.3, -1.0, 2.0);
        let w = a.angular_response(tau).unwrap();
        assert!((lab * w - tau).length() < 1e-14);
    }

    #[test]
    fn lab_tensors_are_checked() {
        let bad = DMat3::from_cols(
            DVec3::new(1.0, 0.5, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        );
        assert_eq!(
            RigidBody::from_lab_inertia(1.0, bad),
            Err(CollideError::Inertia("not symmetric"))
        );
        let indefinite = DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0));
        assert_eq!(
            RigidBody::from_lab_inertia(1.0, indefinite),
            Err(CollideError::Inertia("not positive definite"))
        );
        let impossible = DMat3::from_diagonal(DVec3::new(1.0, 1.0, 3.0));
        assert!(matches!(
            RigidBody::from_lab_inertia(1.0, impossible),
            Err(CollideError::Inertia(msg)) if msg.contains("mass distribution")
        ));
        let nan = DMat3::from_diagonal(DVec3::new(1.0, f64::NAN, 1.0));
        assert_eq!(
            RigidBody::from_lab_inertia(1.0, nan),
            Err(CollideError::Inertia("not finite"))
        );
    }

    #[test]
    fn linear_body_takes_only_perpendicular_torques() {
        let rod = LinearBody::new(2.0, 0.5, DVec3::new(0.0, 0.0, 3.0)).unwrap();
        assert_eq!(rod.axis(), DVec3::Z);
        assert_eq!(
            rod.angular_response(DVec3::new(1.0, 0.0, 0.0)).unwrap(),
            DVec3::new(2.0, 0.0, 0.0)
        );
        // Round-off along the axis is removed ...
        let w = rod.angular_response(DVec3::new(1.0, 0.0, 1e-14)).unwrap();
        assert_eq!(w.z, 0.0);
        // ... a real axial torque is refused.
        assert!(matches!(
            rod.angular_response(DVec3::new(1.0, 0.0, 1e-3)),
            Err(CollideError::AxialTorque { .. })
        ));
        assert!(matches!(
            LinearBody::new(1.0, 1.0, DVec3::ZERO),
            Err(CollideError::Axis(_))
        ));
        assert!(LinearBody::new(1.0, 0.0, DVec3::X).is_err());
    }

    #[test]
    fn particles_refuse_torques() {
        let p = Particle::new(1.0).unwrap();
        assert_eq!(p.angular_response(DVec3::ZERO).unwrap(), DVec3::ZERO);
        assert!(matches!(
            p.angular_response(DVec3::X),
            Err(CollideError::TorqueOnParticle(_))
        ));
    }
}
