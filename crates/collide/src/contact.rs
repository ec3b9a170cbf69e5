//! The contact-point rule (000 §IV.B): an impulse along a line through a point of each body.
//!
//! When site `α` of rigid body `i` and site `β` of body `j` collide (a hard core or the edge of a
//! square well between sites), the impulse `S n` acts on `i` at the site, `−S n` on `j`, along
//! the line `n` joining the two sites. With `d_i = r_iα − R_i` the arm from the centre of mass:
//!
//! ```text
//! Δv_i =  S n / M_i      Δω_i =  S I_i⁻¹ (d_i × n)
//! Δv_j = −S n / M_j      Δω_j = −S I_j⁻¹ (d_j × n)
//! ```
//!
//! which is the terrace rule (003 Eq. 21) with `F = n`, `τ_ij = d_i × n`, `τ_ji = −d_j × n`; its
//! quadratic has `a = ½[1/M_i + 1/M_j + (d_i×n)·I_i⁻¹(d_i×n) + (d_j×n)·I_j⁻¹(d_j×n)]` and
//! `b = n·(u_i − u_j)`, `u = v + ω × d` the velocities of the two sites. The torques balance
//! (003 Eq. 6) whenever the sites lie on the line of action, `(r_iα − r_jβ) × n = 0`, so angular
//! momentum is conserved.
//!
//! The same rule serves bodies touching at one point (the arms then end at the common contact
//! point and `n` is the surface normal).

use glam::DVec3;

use crate::{Body, CollideError, Collision, PairForce, Velocity, terrace};

/// Where and along which line the impulse acts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Line of the impulse, pointing from `j` towards `i` (for sites, `r_iα − r_jβ`). Any
    /// nonzero length: the impulse on `i` is `S·normal`, so with a unit normal `S` is the
    /// magnitude of the impulse.
    pub normal: DVec3,
    /// From the centre of mass of `i` to the point of application on `i` (lab frame). Zero for
    /// a [`Particle`](crate::Particle).
    pub arm_i: DVec3,
    /// From the centre of mass of `j` to the point of application on `j` (lab frame).
    pub arm_j: DVec3,
}

impl Contact {
    /// A contact along `normal` (from `j` towards `i`) at arms `arm_i`, `arm_j`.
    #[inline]
    pub const fn new(normal: DVec3, arm_i: DVec3, arm_j: DVec3) -> Self {
        Self {
            normal,
            arm_i,
            arm_j,
        }
    }

    /// The force and torques of a unit push along the normal: the impulse directions of
    /// 003 Eq. 21.
    #[inline(always)]
    pub fn pair_force(&self) -> PairForce {
        PairForce {
            force: self.normal,
            torque_i: self.arm_i.cross(self.normal),
            torque_j: self.normal.cross(self.arm_j),
        }
    }
}

/// Applies the contact-point rule (000 §IV.B) to bodies `i` and `j`; `delta_v` is the
/// potential-energy change of crossing (`+∞` for a hard core, `−ε` entering a square well of
/// depth `ε`, `+ε` leaving it).
///
/// ```
/// use collide::{Contact, Outcome, RigidBody, Velocity, contact};
/// use glam::{DQuat, DVec3};
///
/// // A dumbbell-like body hit at the end of its long axis by a heavier one.
/// let i = RigidBody::from_principal(1.0, DVec3::new(0.1, 1.0, 1.0), DQuat::IDENTITY)?;
/// let j = RigidBody::from_principal(4.0, DVec3::new(2.0, 2.0, 2.0), DQuat::IDENTITY)?;
/// // Centres at R_i = (2, 0, 0) and R_j = 0; the colliding sites at R + arm are (1, 0.5, 0) and
/// // (0.6, 0.5, 0), so the line joining them is along x.
/// let arm_i = DVec3::new(-1.0, 0.5, 0.0);
/// let arm_j = DVec3::new(0.6, 0.5, 0.0);
/// let hit = Contact::new(DVec3::X, arm_i, arm_j);
/// let vi = Velocity::new(DVec3::new(-1.0, 0.0, 0.0), DVec3::ZERO);
/// let vj = Velocity::new(DVec3::ZERO, DVec3::new(0.0, 0.0, 0.3));
/// let out = contact(&i, &j, vi, vj, &hit, f64::INFINITY)?; // hard core
/// assert_eq!(out.impulse.outcome, Outcome::Reflected);
/// assert!(out.impulse.s > 0.0);          // pushes i away from j
/// assert!(out.i.angular.z != 0.0);       // and spins it: the arm is off the line
/// # Ok::<(), collide::CollideError>(())
/// ```
///
/// # Errors
/// As [`terrace`]; [`CollideError::NoImpulse`] for a zero normal, and
/// [`CollideError::TorqueOnParticle`] for a nonzero arm on a particle.
#[inline]
pub fn contact<A: Body, B: Body>(
    body_i: &A,
    body_j: &B,
    vel_i: Velocity,
    vel_j: Velocity,
    at: &Contact,
    delta_v: f64,
) -> Result<Collision<Velocity>, CollideError> {
    terrace(body_i, body_j, vel_i, vel_j, &at.pair_force(), delta_v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LinearBody, Outcome, Particle, RigidBody};
    use glam::DQuat;

    #[test]
    fn site_velocities_along_the_normal_reverse_on_a_hard_core() {
        // A hard-core reflection reverses the normal component of the relative velocity of
        // the two contact points, whatever the bodies.
        let i =
            RigidBody::from_principal(1.3, DVec3::new(0.4, 0.9, 1.1), DQuat::from_rotation_x(0.4))
                .unwrap();
        let j = LinearBody::new(0.7, 0.3, DVec3::new(1.0, 1.0, 0.0)).unwrap();
        let at = Contact::new(
            DVec3::new(0.6, -0.8, 0.0),
            DVec3::new(0.1, 0.5, -0.2),
            DVec3::new(-0.5, -0.5, 0.0),
        );
        let vi = Velocity::new(DVec3::new(-1.0, 0.3, 0.2), DVec3::new(0.3, -0.2, 0.8));
        let vj = Velocity::new(DVec3::new(0.2, 0.1, 0.0), DVec3::new(0.4, -0.4, 0.1));
        let site = |v: Velocity, d: DVec3| v.linear + v.angular.cross(d);
        let before = at.normal.dot(site(vi, at.arm_i) - site(vj, at.arm_j));
        let out = contact(&i, &j, vi, vj, &at, f64::INFINITY).unwrap();
        let after = at.normal.dot(site(out.i, at.arm_i) - site(out.j, at.arm_j));
        assert_eq!(out.impulse.outcome, Outcome::Reflected);
        assert!(
            (after + before).abs() < 1e-14 * before.abs(),
            "{before} {after}"
        );
    }

    #[test]
    fn arms_on_particles_are_refused() {
        let p = Particle::new(1.0).unwrap();
        let v = Velocity::default();
        let at = Contact::new(DVec3::X, DVec3::Y, DVec3::ZERO);
        assert!(matches!(
            contact(&p, &p, v, v, &at, 1.0),
            Err(CollideError::TorqueOnParticle(_))
        ));
        let zero = Contact::new(DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        assert!(matches!(
            contact(&p, &p, v, v, &zero, 1.0),
            Err(CollideError::NoImpulse(_))
        ));
    }
}
