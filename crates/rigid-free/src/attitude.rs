//! Attitudes as matrices and quaternions, and the small rotation algebra the propagators share.
//!
//! The attitude `A` maps lab to body components (`a_body = A · a_lab`, free-rigid-body.md): its
//! rows are the body axes in the lab frame. Its transpose `R = Aᵀ` is the orientation, the
//! rotation that carries body-fixed vectors into the lab (`s_lab = R · s̃`); that is what a unit
//! quaternion in a trajectory file (OVITO, extended XYZ) holds, and what the propagators compute
//! internally, since lab vectors of body-fixed points are then one matrix-vector product.

use crate::FreeError;
use glam::{DMat3, DQuat, DVec3};

/// The attitude matrix `A` (body = A·lab) of the orientation quaternion `q` (which rotates body
/// vectors into the lab). `q` need not be normalised; it must not be zero.
///
/// ```
/// use glam::{DQuat, DVec3};
/// use rigid_free::{attitude_from_quat, quat_from_attitude};
/// let q = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 2.0).normalize(), 0.7);
/// let a = attitude_from_quat(q);
/// // The body x axis, seen from the lab, is the first row of A.
/// assert!((q * DVec3::X - a.row(0)).length() < 1e-15);
/// assert!(quat_from_attitude(a).abs_diff_eq(q, 1e-15) || quat_from_attitude(a).abs_diff_eq(-q, 1e-15));
/// ```
pub fn attitude_from_quat(q: DQuat) -> DMat3 {
    DMat3::from_quat(q.normalize()).transpose()
}

/// The orientation quaternion (scalar part ≥ 0) of the attitude matrix `A`.
pub fn quat_from_attitude(a: DMat3) -> DQuat {
    let q = DQuat::from_mat3(&a.transpose()).normalize();
    if q.w < 0.0 { -q } else { q }
}

/// Checks that `a` is a proper rotation to 1e-9 and returns it.
pub(crate) fn check_rotation(a: DMat3) -> Result<DMat3, FreeError> {
    if !a.is_finite() {
        return Err(FreeError::NonFiniteVector { what: "attitude" });
    }
    // Frobenius norm of AᵀA − I (no branches), and det A − 1.
    let g = a.transpose() * a - DMat3::IDENTITY;
    let frob =
        (g.x_axis.length_squared() + g.y_axis.length_squared() + g.z_axis.length_squared()).sqrt();
    let dev = frob.max((a.determinant() - 1.0).abs());
    if dev > 1e-9 {
        return Err(FreeError::NotARotation { deviation: dev });
    }
    Ok(a)
}

/// Checks that a vector argument is finite.
pub(crate) fn check_vector(v: DVec3, what: &'static str) -> Result<DVec3, FreeError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(FreeError::NonFiniteVector { what })
    }
}

/// `W(n) M`: the cross product of `n` with every column of `M`.
#[inline]
pub(crate) fn cross_cols(n: DVec3, m: DMat3) -> DMat3 {
    DMat3::from_cols(n.cross(m.x_axis), n.cross(m.y_axis), n.cross(m.z_axis))
}

/// A rotation of the lab frame about a fixed unit axis `n` by the angle `θ` applied to an
/// orientation `R0`, `exp(θ W(n)) R0 = Z + cos θ (R0 − Z) + sin θ W(n) R0` with `Z = n nᵀ R0`
/// (Rodrigues): the three matrices are stored, an evaluation is one sine and cosine and
/// eighteen multiply-adds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LabRotation {
    z: DMat3,
    d: DMat3,
    y: DMat3,
}

impl LabRotation {
    /// For the unit axis `n` (lab frame) and the orientation `r0 = A(0)ᵀ`.
    pub(crate) fn new(n: DVec3, r0: DMat3) -> Self {
        let z = DMat3::from_cols(
            n * n.dot(r0.x_axis),
            n * n.dot(r0.y_axis),
            n * n.dot(r0.z_axis),
        );
        Self {
            z,
            d: r0 - z,
            y: cross_cols(n, r0),
        }
    }

    /// `exp(θ W(n)) R0` from `(sin θ, cos θ)`.
    #[inline]
    pub(crate) fn apply(&self, s: f64, c: f64) -> DMat3 {
        DMat3::from_cols(
            self.z.x_axis + self.d.x_axis * c + self.y.x_axis * s,
            self.z.y_axis + self.d.y_axis * c + self.y.y_axis * s,
            self.z.z_axis + self.d.z_axis * c + self.y.z_axis * s,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_check() {
        assert!(check_rotation(DMat3::IDENTITY).is_ok());
        assert!(check_rotation(DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0))).is_err());
        assert!(check_rotation(DMat3::from_diagonal(DVec3::new(1.0, 1.0, 1.1))).is_err());
        let mut bad = DMat3::IDENTITY;
        bad.x_axis.x = f64::NAN;
        assert!(check_rotation(bad).is_err());
    }

    #[test]
    fn lab_rotation_is_rodrigues() {
        let n = DVec3::new(1.0, -2.0, 0.5).normalize();
        let r0 = DMat3::from_quat(DQuat::from_rotation_y(0.3));
        let lr = LabRotation::new(n, r0);
        let (s, c) = 1.1f64.sin_cos();
        let want = DMat3::from_quat(DQuat::from_axis_angle(n, 1.1)) * r0;
        assert!(lr.apply(s, c).abs_diff_eq(want, 1e-15));
    }
}
