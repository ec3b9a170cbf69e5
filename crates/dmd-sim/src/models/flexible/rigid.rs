//! Rigid molecules among semi-flexible ones: a species without bonds in a scene with bonded
//! ones moves by the exact torque-free motion of its [`MoleculeType`] (000 §II.B), not by
//! RATTLE. To the model it answers the questions a RATTLE trajectory answers (where each atom
//! is and how fast it moves at time `t`, relative to the centre of mass) and is restarted at
//! events from its new angular velocity.
//!
//! A start given as atom positions (a random turn of the species' configuration, or a start
//! file) is fitted by the rotation that carries two body-frame arms onto the given ones (the
//! pair of arms farthest from parallel; one arm for a linear molecule); positions that are not
//! a rigid image of the molecule to [`START_TOLERANCE`](super::START_TOLERANCE) are refused.
//! Internal velocities become the rigid rotation of the same angular momentum,
//! `ω = I⁻¹ Σ m_k q_k × u_k`: the mass-weighted projection onto the rotations, so Gaussian atom
//! velocities give the Maxwell–Boltzmann distribution of `ω`.

use std::sync::Arc;

use glam::{DMat3, DQuat, DVec3};
use rigid_free::FreeMotion;

use crate::engine::saved::StateReader;
use crate::models::molecule::{MoleculeType, SiteBody};

/// One rigid molecule's free motion since its last change at time `t0`, with its atoms' arms
/// and velocities about the centre at `t0`.
#[derive(Clone, Debug)]
pub struct RigidMotion {
    ty: Arc<MoleculeType>,
    motion: FreeMotion,
    t0: f64,
    q0: Vec<DVec3>,
    u0: Vec<DVec3>,
}

impl RigidMotion {
    /// The motion of `ty` from `t0` with orientation `o` (body → lab) and lab angular velocity
    /// `w`.
    ///
    /// # Errors
    /// A non-finite orientation or angular velocity.
    pub fn new(ty: Arc<MoleculeType>, t0: f64, o: DMat3, w: DVec3) -> Result<Self, String> {
        let q = DQuat::from_mat3(&o).normalize();
        let wb = DMat3::from_quat(q).transpose() * w;
        let motion = FreeMotion::from_quat(&ty.moments, q, wb).map_err(|e| e.to_string())?;
        Ok(Self::anchored(ty, motion, t0))
    }

    fn anchored(ty: Arc<MoleculeType>, motion: FreeMotion, t0: f64) -> Self {
        let p = motion.initial_pose();
        let (o, w) = (p.orientation, p.omega_lab());
        let q0: Vec<DVec3> = ty.sites.iter().map(|&d| o * d).collect();
        let u0 = q0.iter().map(|&d| w.cross(d)).collect();
        RigidMotion {
            ty,
            motion,
            t0,
            q0,
            u0,
        }
    }

    /// The motion whose atoms are at `q` (about the centre, lab) at `t0` with the rigid
    /// rotation of the angular momentum of internal velocities `u` (module documentation).
    ///
    /// # Errors
    /// Positions that are not a rigid image of the molecule to `tolerance` (relative to its
    /// size), or not finite.
    pub fn fitted(
        ty: Arc<MoleculeType>,
        t0: f64,
        q: &[DVec3],
        u: &[DVec3],
        tolerance: f64,
    ) -> Result<Self, String> {
        let o = fit(&ty.sites, q, ty.is_linear())
            .ok_or_else(|| "the atom positions are degenerate".to_owned())?;
        let misfit = ty
            .sites
            .iter()
            .zip(q)
            .map(|(&d, &x)| (o * d - x).length())
            .fold(0.0, f64::max);
        if misfit.is_nan() || misfit > tolerance * ty.radius {
            return Err(format!(
                "the atoms are not a rigid image of the molecule: an atom is {misfit:e} away \
                 from the best fit (more than {tolerance} of the molecule's radius {})",
                ty.radius
            ));
        }
        let w = omega_of(&ty, o, q, u);
        Self::new(ty, t0, o, w)
    }

    /// Orientation (body → lab) and lab angular velocity at `t`.
    #[inline(always)]
    pub fn pose(&self, t: f64) -> (DMat3, DVec3) {
        let p = self.motion.pose(t - self.t0);
        (p.orientation, p.omega_lab())
    }

    /// Arm and velocity of atom `a` about the centre at `t`.
    #[inline]
    pub fn atom_at(&self, t: f64, a: usize) -> (DVec3, DVec3) {
        let (o, w) = self.pose(t);
        let d = o * self.ty.sites[a];
        (d, w.cross(d))
    }

    /// Arms and velocities of every atom about the centre at `t`.
    pub fn state_at(&self, t: f64) -> (Vec<DVec3>, Vec<DVec3>) {
        let (o, w) = self.pose(t);
        let q: Vec<DVec3> = self.ty.sites.iter().map(|&d| o * d).collect();
        let u = q.iter().map(|&d| w.cross(d)).collect();
        (q, u)
    }

    /// Arms and velocities at the last change.
    pub fn initial(&self) -> (&[DVec3], &[DVec3]) {
        (&self.q0, &self.u0)
    }

    /// The molecule as an impulse rule sees it at `t`, with its lab angular velocity.
    ///
    /// # Errors
    /// An orientation `collide` refuses (not finite).
    pub fn body_at(&self, t: f64) -> Result<(SiteBody, DVec3), collide::CollideError> {
        let (o, w) = self.pose(t);
        Ok((self.ty.body(o)?, w))
    }

    /// The lab angular velocity of the rotation with the angular momentum of internal velocities
    /// `u` of atoms at `q` (at orientation `o`).
    pub fn omega_of_atoms(&self, o: DMat3, q: &[DVec3], u: &[DVec3]) -> DVec3 {
        omega_of(&self.ty, o, q, u)
    }

    /// The same motion anchored at `now` with lab angular velocity `w` (its orientation there
    /// kept).
    ///
    /// # Errors
    /// A non-finite angular velocity.
    pub fn restarted(&self, now: f64, w: DVec3) -> Result<Self, String> {
        let (o, _) = self.pose(now);
        Self::new(Arc::clone(&self.ty), now, o, w)
    }

    /// Moves the time origin to `t0` (a re-basing) by re-anchoring the motion there, as the
    /// rigid-sites model does: poses stay evaluated at short times.
    pub fn rebase(&mut self, t0: f64) {
        let p = self.motion.pose(t0 - self.t0);
        let q = DQuat::from_mat3(&p.orientation).normalize();
        match FreeMotion::from_quat(&self.ty.moments, q, p.omega) {
            Ok(motion) => *self = Self::anchored(Arc::clone(&self.ty), motion, 0.0),
            // Not finite (a broken invariant, reported elsewhere): keep the old anchor.
            Err(_) => self.t0 -= t0,
        }
    }

    /// Appends the motion as the state it is built from (exactly: rebuilding it gives the same
    /// motion bit for bit).
    pub fn write_numbers(&self, out: &mut Vec<f64>) {
        let p = self.motion.initial_pose();
        out.extend_from_slice(&p.orientation.to_cols_array());
        out.extend_from_slice(&p.omega.to_array());
        out.push(self.t0);
    }

    /// Reads what [`write_numbers`](Self::write_numbers) wrote.
    ///
    /// # Errors
    /// Missing or unusable numbers.
    pub fn read_numbers(r: &mut StateReader, ty: Arc<MoleculeType>) -> Result<Self, String> {
        let orientation = r.mat3("a rigid molecule's orientation")?;
        let omega = r.vec3("a rigid molecule's angular velocity")?;
        let t0 = r.real("a rigid molecule's clock")?;
        let motion = FreeMotion::new(&ty.moments, orientation.transpose(), omega)
            .map_err(|e| format!("a rigid molecule cannot be restored: {e}"))?;
        Ok(Self::anchored(ty, motion, t0))
    }
}

/// `ω = I⁻¹ L` (lab) for the angular momentum `L = Σ m q × u` of atoms at `q` (orientation `o`).
fn omega_of(ty: &MoleculeType, o: DMat3, q: &[DVec3], u: &[DVec3]) -> DVec3 {
    let l = ty
        .masses
        .iter()
        .zip(q.iter().zip(u))
        .fold(DVec3::ZERO, |s, (&m, (&x, &v))| s + m * x.cross(v));
    o * ty.omega_from_momentum(o, l)
}

/// The rotation carrying body-frame arms `d` onto lab arms `q` (module documentation), `None`
/// for degenerate arms.
fn fit(d: &[DVec3], q: &[DVec3], linear: bool) -> Option<DMat3> {
    if d.len() != q.len() || !q.iter().all(|x| x.is_finite()) {
        return None;
    }
    let longest = (0..d.len()).max_by(|&x, &y| d[x].length().total_cmp(&d[y].length()))?;
    if linear {
        let (from, to) = (d[longest].try_normalize()?, q[longest].try_normalize()?);
        return Some(DMat3::from_quat(DQuat::from_rotation_arc(from, to)));
    }
    let mut best = (0, 0, 0.0);
    for x in 0..d.len() {
        for y in x + 1..d.len() {
            let area = d[x].cross(d[y]).length();
            if area > best.2 {
                best = (x, y, area);
            }
        }
    }
    let triad = |a: DVec3, b: DVec3| -> Option<DMat3> {
        let e1 = a.try_normalize()?;
        let e2 = (b - b.dot(e1) * e1).try_normalize()?;
        Some(DMat3::from_cols(e1, e2, e1.cross(e2)))
    };
    let (x, y, _) = best;
    let (td, tq) = (triad(d[x], d[y])?, triad(q[x], q[y])?);
    let o = tq * td.transpose();
    // Orthonormal to round-off; through the quaternion it is exactly a rotation.
    Some(DMat3::from_quat(DQuat::from_mat3(&o).normalize()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::site_pairs::atom;

    #[test]
    fn a_turned_molecule_is_fitted_and_keeps_its_angular_momentum() {
        let ty = Arc::new(
            MoleculeType::new(&[
                atom(0.0, 0.0, 0.0, 3.0),
                atom(0.7, 0.1, 0.0, 1.0),
                atom(-0.2, 0.6, 0.3, 2.0),
                atom(0.1, -0.3, 0.5, 1.5),
            ])
            .unwrap(),
        );
        let o = DMat3::from_quat(DQuat::from_axis_angle(
            DVec3::new(0.3, -1.0, 0.4).normalize(),
            2.1,
        ));
        let w = DVec3::new(0.4, -0.9, 1.3);
        let q: Vec<DVec3> = ty.sites.iter().map(|&d| o * d).collect();
        // Atom velocities of the rotation plus a part that is no rotation (a stretch).
        let u: Vec<DVec3> = q.iter().map(|&d| w.cross(d) + 0.3 * d).collect();
        let m = RigidMotion::fitted(Arc::clone(&ty), 2.0, &q, &u, 1e-9).unwrap();
        let (o_fit, w_fit) = m.pose(2.0);
        assert!((o_fit - o).to_cols_array().iter().all(|x| x.abs() < 1e-14));
        // A radial stretch carries no angular momentum: the rotation is recovered.
        assert!((w_fit - w).length() < 1e-13 * w.length(), "{w_fit} {w}");
        let (q1, u1) = m.state_at(2.5);
        let l = |q: &[DVec3], u: &[DVec3]| {
            ty.masses
                .iter()
                .zip(q.iter().zip(u))
                .fold(DVec3::ZERO, |s, (&m, (&x, &v))| s + m * x.cross(v))
        };
        let (l0, l1) = (l(m.initial().0, m.initial().1), l(&q1, &u1));
        assert!((l1 - l0).length() < 1e-13 * l0.length(), "{l0} {l1}");
        // A bent image is refused.
        let mut bent = q.clone();
        bent[1] *= 1.01;
        assert!(RigidMotion::fitted(ty, 0.0, &bent, &u, 1e-6).is_err());
    }

    #[test]
    fn the_saved_motion_restores_bit_for_bit() {
        let ty = Arc::new(
            MoleculeType::new(&[atom(0.0, 0.0, 0.0, 1.0), atom(0.0, 0.0, 0.8, 2.0)]).unwrap(),
        );
        let o = DMat3::from_quat(DQuat::from_rotation_y(0.7));
        let m = RigidMotion::new(Arc::clone(&ty), 0.25, o, o * DVec3::new(0.3, -1.2, 0.0)).unwrap();
        let mut x = Vec::new();
        m.write_numbers(&mut x);
        let back = RigidMotion::read_numbers(&mut StateReader::new(&x), ty).unwrap();
        for t in [0.25, 1.0, 7.5] {
            assert_eq!(back.state_at(t), m.state_at(t));
        }
    }
}
