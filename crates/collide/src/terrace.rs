//! The impulse rule for terraced potentials (003 §IV, Eq. 21), for unequal masses and full
//! inertia tensors.
//!
//! At the instant a pair's continuous potential `U_ij` reaches a terrace value `U_k`, the pair
//! receives an impulse along the force and torques the continuous potential would exert there
//! (003 Eqs. 18–19), all scaled by one scalar `S` (003 Eq. 20):
//!
//! ```text
//! v_i' = v_i + S F_ij / m_i        ω_i' = ω_i + S I_i⁻¹ τ_ij
//! v_j' = v_j − S F_ij / m_j        ω_j' = ω_j + S I_j⁻¹ τ_ji
//! ```
//!
//! and energy conservation gives 003 Eq. 21 generalised to unequal masses and tensors:
//!
//! ```text
//! ½ [ (1/m_i + 1/m_j) F·F + τ_ij·I_i⁻¹τ_ij + τ_ji·I_j⁻¹τ_ji ] S²
//!   + (F·v_ij + τ_ij·ω_i + τ_ji·ω_j) S + ΔV = 0
//! ```
//!
//! (for `m_i = m_j = m` the first term is the paper's `F·F/m`). The linear coefficient is
//! `−U̇_ij` (003 Eq. 12); [`energy::solve`](crate::energy::solve) picks the root.
//!
//! Linear momentum is conserved by construction. Angular momentum about any fixed point is
//! conserved exactly when the force and torques satisfy 003 Eq. 6,
//! `r_ij × F_ij + τ_ij + τ_ji = 0`, which holds for any rotationally invariant pair potential
//! (003 Eqs. 4–5); [`PairForce::torque_imbalance`] measures it.

use glam::DVec3;

use crate::{Body, CollideError, Collision, Velocity, energy};

/// The continuous force and torques of a pair at the instant of the event: the directions of the
/// impulse (003 Eqs. 4–5, 18–19). Only their directions and relative sizes matter; any common
/// scale is absorbed by `S`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairForce {
    /// `F_ij`: force on body `i` (body `j` receives `−F_ij`).
    pub force: DVec3,
    /// `τ_ij`: torque on body `i` about its centre of mass.
    pub torque_i: DVec3,
    /// `τ_ji`: torque on body `j` about its centre of mass.
    pub torque_j: DVec3,
}

impl PairForce {
    /// The force and torques.
    #[inline]
    pub const fn new(force: DVec3, torque_i: DVec3, torque_j: DVec3) -> Self {
        Self {
            force,
            torque_i,
            torque_j,
        }
    }

    /// How far the torques are from balancing the force's moment (003 Eq. 6):
    /// `|r_ij × F + τ_ij + τ_ji|` relative to `|r_ij||F| + |τ_ij| + |τ_ji|`, with
    /// `r_ij = r_i − r_j` the separation of the centres of mass. Zero (to round-off) is required
    /// for the rule to conserve angular momentum; use it to check a potential's torques.
    pub fn torque_imbalance(&self, r_ij: DVec3) -> f64 {
        let sum = r_ij.cross(self.force) + self.torque_i + self.torque_j;
        let scale =
            r_ij.length() * self.force.length() + self.torque_i.length() + self.torque_j.length();
        if scale == 0.0 {
            0.0
        } else {
            sum.length() / scale
        }
    }
}

/// Applies the terrace rule (003 Eq. 21) to bodies `i` and `j` with velocities `vel_i`, `vel_j`,
/// the pair's continuous force and torques `push`, and the potential-energy change `delta_v` of
/// crossing the terrace (`+∞` for a hard core). Returns the new velocities and what happened.
///
/// ```
/// use collide::{LinearBody, Outcome, PairForce, Velocity, terrace};
/// use glam::DVec3;
///
/// // Two rods side by side, approaching; the potential pushes them apart and twists them.
/// let rod_i = LinearBody::new(1.0, 0.1, DVec3::Z)?;
/// let rod_j = LinearBody::new(1.0, 0.1, DVec3::X)?;
/// let (vi, vj) = (Velocity::new(DVec3::new(-1.0, 0.0, 0.0), DVec3::ZERO),
///                 Velocity::new(DVec3::new(1.0, 0.0, 0.0), DVec3::ZERO));
/// let r_ij = DVec3::new(1.0, 0.0, 0.0); // r_i − r_j
/// let push = PairForce::new(DVec3::X, DVec3::Y * 0.2, -DVec3::Y * 0.2);
/// assert!(push.torque_imbalance(r_ij) < 1e-15);
/// let hit = terrace(&rod_i, &rod_j, vi, vj, &push, 10.0)?; // a step too high to climb
/// assert_eq!(hit.impulse.outcome, Outcome::Reflected);
/// assert!(hit.i.linear.x > 0.0 && hit.j.linear.x < 0.0); // moving apart now
/// # Ok::<(), collide::CollideError>(())
/// ```
///
/// # Errors
/// A torque the body cannot take ([`CollideError::TorqueOnParticle`],
/// [`CollideError::AxialTorque`]); [`CollideError::NoImpulse`] if force and torques vanish; and
/// the errors of [`energy::solve`] (non-finite inputs, bad `delta_v`, overflow).
#[inline]
pub fn terrace<A: Body, B: Body>(
    body_i: &A,
    body_j: &B,
    vel_i: Velocity,
    vel_j: Velocity,
    push: &PairForce,
    delta_v: f64,
) -> Result<Collision<Velocity>, CollideError> {
    let k_i = body_i.angular_response(push.torque_i)?;
    let k_j = body_j.angular_response(push.torque_j)?;
    let w_i = body_i.inv_mass();
    let w_j = body_j.inv_mass();
    let f = push.force;
    // 003 Eq. 21, coefficient of S²: half the inverse effective mass along the impulse.
    let a =
        0.5 * ((w_i + w_j) * f.length_squared() + push.torque_i.dot(k_i) + push.torque_j.dot(k_j));
    // 003 Eq. 21, coefficient of S: −U̇_ij (003 Eq. 12). The relative velocity is formed first
    // so that a common drift of the pair cancels exactly.
    let b = f.dot(vel_i.linear - vel_j.linear)
        + push.torque_i.dot(vel_i.angular)
        + push.torque_j.dot(vel_j.angular);
    let impulse = energy::solve(a, b, delta_v)?;
    let s = impulse.s;
    Ok(Collision {
        impulse,
        i: Velocity {
            linear: vel_i.linear + (s * w_i) * f,
            angular: vel_i.angular + s * k_i,
        },
        j: Velocity {
            linear: vel_j.linear - (s * w_j) * f,
            angular: vel_j.angular + s * k_j,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Outcome, Particle, RigidBody};
    use glam::DQuat;

    #[test]
    fn equal_masses_reduce_to_the_papers_equation() {
        // 003 Eq. 21 as printed, with m_i = m_j = m.
        let m = 2.0;
        let moments = DVec3::new(1.0, 1.5, 2.0);
        let q = DQuat::from_rotation_y(0.3);
        let bi = RigidBody::from_principal(m, moments, q).unwrap();
        let bj = RigidBody::from_principal(m, moments, q.inverse()).unwrap();
        let push = PairForce::new(
            DVec3::new(1.0, 0.2, 0.0),
            DVec3::new(0.0, 0.3, 0.1),
            DVec3::new(0.1, 0.0, -0.2),
        );
        let vi = Velocity::new(DVec3::new(-1.0, 0.0, 0.5), DVec3::new(0.1, 0.2, 0.3));
        let vj = Velocity::new(DVec3::new(0.5, 0.1, 0.0), DVec3::new(-0.3, 0.0, 0.2));
        let dv = -0.4;
        let c = terrace(&bi, &bj, vi, vj, &push, dv).unwrap();
        let inv_i = bi.inv_inertia();
        let inv_j = bj.inv_inertia();
        let a = push.force.dot(push.force) / m
            + push.torque_i.dot(inv_i * push.torque_i) / 2.0
            + push.torque_j.dot(inv_j * push.torque_j) / 2.0;
        let b = (vi.linear - vj.linear).dot(push.force)
            + push.torque_i.dot(vi.angular)
            + push.torque_j.dot(vj.angular);
        let s = c.impulse.s;
        assert!((a * s * s + b * s + dv).abs() < 1e-15);
        assert_eq!(c.impulse.outcome, Outcome::Crossed);
        // b < 0 (U̇ > 0): the negative root branch of the paper.
        assert!(b < 0.0);
        assert!((s - (-b - (b * b - 4.0 * a * dv).sqrt()) / (2.0 * a)).abs() < 1e-14);
    }

    #[test]
    fn errors_name_the_problem() {
        let p = Particle::new(1.0).unwrap();
        let v = Velocity::default();
        let none = PairForce::default();
        assert!(matches!(
            terrace(&p, &p, v, v, &none, 1.0),
            Err(CollideError::NoImpulse(_))
        ));
        let twist = PairForce::new(DVec3::X, DVec3::Y, DVec3::ZERO);
        assert!(matches!(
            terrace(&p, &p, v, v, &twist, 1.0),
            Err(CollideError::TorqueOnParticle(_))
        ));
        let nan = Velocity::new(DVec3::new(f64::NAN, 0.0, 0.0), DVec3::ZERO);
        assert!(matches!(
            terrace(
                &p,
                &p,
                nan,
                v,
                &PairForce::new(DVec3::Y, DVec3::ZERO, DVec3::ZERO),
                1.0
            ),
            Err(CollideError::NotFinite(_))
        ));
    }

    #[test]
    fn torque_imbalance_of_a_central_force_is_zero() {
        let r = DVec3::new(1.0, 2.0, 3.0);
        let central = PairForce::new(r * 0.5, DVec3::ZERO, DVec3::ZERO);
        assert_eq!(central.torque_imbalance(r), 0.0);
        let off = PairForce::new(DVec3::X, DVec3::ZERO, DVec3::ZERO);
        assert!(off.torque_imbalance(r) > 0.1);
        assert_eq!(PairForce::default().torque_imbalance(r), 0.0);
    }
}
