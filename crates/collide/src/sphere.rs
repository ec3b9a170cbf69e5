//! Spheres: the hard-sphere and square-well rule, the cheapest special case.
//!
//! For bodies that interact through their centres the contact rule (000 §IV.B) loses its
//! torques: with `r = r_i − r_j`, the impulse `S r` on `i` and `−S r` on `j` solves
//! `a S² + b S + ΔV = 0` with `a = ½(1/m_i + 1/m_j) r·r` and `b = r·(v_i − v_j)`. The direction
//! is left unnormalised (its length is absorbed by `S`), so a hard-sphere reflection,
//! `S = −b/a`, costs no square root at all and a square-well crossing one.

use glam::DVec3;

use crate::{CollideError, Collision, Particle, energy};

/// Applies the sphere rule to particles `i` and `j` with velocities `v_i`, `v_j` at separation
/// `r_ij = r_i − r_j` (centre to centre; any nonzero length along that line). `delta_v` is the
/// potential-energy change of crossing: `+∞` for a hard core, `−ε` entering a square well,
/// `+ε` leaving it. The impulse on `i` is `s·r_ij`.
///
/// ```
/// use collide::{Outcome, Particle, spheres};
/// use glam::DVec3;
///
/// let (light, heavy) = (Particle::new(1.0)?, Particle::new(3.0)?);
/// let r_ij = DVec3::new(1.0, 0.0, 0.0);
/// // Head-on hard-sphere collision: the textbook result.
/// let out = spheres(&light, &heavy, DVec3::new(-2.0, 0.0, 0.0), DVec3::ZERO, r_ij, f64::INFINITY)?;
/// assert_eq!(out.impulse.outcome, Outcome::Reflected);
/// assert_eq!(out.i, DVec3::new(1.0, 0.0, 0.0));
/// assert_eq!(out.j, DVec3::new(-1.0, 0.0, 0.0));
/// // Leaving a square well of depth 1 needs more than that: reflected back inside ...
/// let slow = spheres(&light, &heavy, DVec3::new(0.5, 0.0, 0.0), DVec3::ZERO, r_ij, 1.0)?;
/// assert_eq!(slow.impulse.outcome, Outcome::Reflected);
/// // ... while a fast pair escapes, slower by exactly the well depth.
/// let fast = spheres(&light, &heavy, DVec3::new(4.0, 0.0, 0.0), DVec3::ZERO, r_ij, 1.0)?;
/// assert_eq!(fast.impulse.outcome, Outcome::Crossed);
/// let kinetic = 0.5 * fast.i.length_squared() + 1.5 * fast.j.length_squared();
/// assert!((kinetic - (8.0 - 1.0)).abs() < 1e-14);
/// # Ok::<(), collide::CollideError>(())
/// ```
///
/// # Errors
/// [`CollideError::NoImpulse`] if `r_ij` is zero; the errors of [`energy::solve`].
#[inline]
pub fn spheres(
    p_i: &Particle,
    p_j: &Particle,
    v_i: DVec3,
    v_j: DVec3,
    r_ij: DVec3,
    delta_v: f64,
) -> Result<Collision<DVec3>, CollideError> {
    use crate::Body;
    let (w_i, w_j) = (p_i.inv_mass(), p_j.inv_mass());
    let a = 0.5 * (w_i + w_j) * r_ij.length_squared();
    let b = r_ij.dot(v_i - v_j);
    let impulse = energy::solve(a, b, delta_v)?;
    let s = impulse.s;
    Ok(Collision {
        impulse,
        i: v_i + (s * w_i) * r_ij,
        j: v_j - (s * w_j) * r_ij,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Contact, Outcome, Velocity, contact};

    #[test]
    fn agrees_with_the_general_contact_rule() {
        let (pi, pj) = (Particle::new(0.3).unwrap(), Particle::new(7.0).unwrap());
        let (vi, vj) = (DVec3::new(0.3, -1.0, 2.0), DVec3::new(-0.4, 0.2, 0.1));
        let r = DVec3::new(0.2, 0.9, -0.3);
        for dv in [f64::INFINITY, 0.05, -0.7, 0.0] {
            let fast = spheres(&pi, &pj, vi, vj, r, dv).unwrap();
            let general = contact(
                &pi,
                &pj,
                Velocity::new(vi, DVec3::ZERO),
                Velocity::new(vj, DVec3::ZERO),
                &Contact::new(r, DVec3::ZERO, DVec3::ZERO),
                dv,
            )
            .unwrap();
            assert_eq!(fast.impulse, general.impulse);
            assert_eq!(fast.i, general.i.linear);
            assert_eq!(fast.j, general.j.linear);
        }
    }

    #[test]
    fn square_well_capture_accelerates_inwards() {
        let p = Particle::new(1.0).unwrap();
        let r = DVec3::X;
        // Approaching (b < 0) the outer edge of a well of depth 1: captured, faster.
        let out = spheres(&p, &p, DVec3::new(-0.5, 0.0, 0.0), DVec3::ZERO, r, -1.0).unwrap();
        assert_eq!(out.impulse.outcome, Outcome::Crossed);
        assert!(out.impulse.s < 0.0);
        assert!((out.i - out.j).x < -0.5);
        assert_eq!(out.impulse.delta_v, -1.0);
    }

    #[test]
    fn coincident_centres_are_refused() {
        let p = Particle::new(1.0).unwrap();
        assert!(matches!(
            spheres(&p, &p, DVec3::X, DVec3::ZERO, DVec3::ZERO, 1.0),
            Err(CollideError::NoImpulse(_))
        ));
    }
}
