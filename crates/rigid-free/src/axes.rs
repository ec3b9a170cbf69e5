//! The principal-axis ordering of an asymmetric top and the rotation that takes `L` to `+z`.
//!
//! The elliptic solution wants axis 2 to carry the intermediate moment and axis 3 to be the axis
//! that the angular momentum circles (free-rigid-body.md §(c)). [`AxisOrder`] is the proper
//! signed permutation `Π` from the caller's body axes to that order; [`to_invariant_frame`] is
//! `T(L)`, the rotation taking the body-frame `L` to `+z`.

use glam::{DMat3, DVec3};

/// A proper signed permutation `Π` of the body axes: ordered `v_k = sign_k · v[index_k]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct AxisOrder {
    index: [usize; 3],
    sign: [f64; 3],
}

impl AxisOrder {
    /// `index` lists the caller's axes that become ordered axes 1, 2, 3. An odd permutation
    /// gets axis 2 negated so that `Π` is a proper rotation (the sheet's `(x, y, z) → (z, −y, x)`).
    pub(crate) fn new(index: [usize; 3]) -> Self {
        let even = matches!(index, [0, 1, 2] | [1, 2, 0] | [2, 0, 1]);
        Self {
            index,
            sign: [1.0, if even { 1.0 } else { -1.0 }, 1.0],
        }
    }

    /// `Π v`.
    #[inline]
    pub(crate) fn ordered(self, v: DVec3) -> DVec3 {
        DVec3::new(
            self.sign[0] * v[self.index[0]],
            self.sign[1] * v[self.index[1]],
            self.sign[2] * v[self.index[2]],
        )
    }

    /// `Πᵀ v`.
    #[inline]
    pub(crate) fn unordered(self, v: DVec3) -> DVec3 {
        let mut out = DVec3::ZERO;
        for k in 0..3 {
            out[self.index[k]] = self.sign[k] * v[k];
        }
        out
    }

    /// `M Π`: column `index_k` of the result is `sign_k` times column `k` of `M`.
    #[inline]
    pub(crate) fn mul_right(self, m: DMat3) -> DMat3 {
        let mut out = DMat3::ZERO;
        for k in 0..3 {
            *out.col_mut(self.index[k]) = m.col(k) * self.sign[k];
        }
        out
    }

    /// The matrix `Π`.
    pub(crate) fn matrix(self) -> DMat3 {
        self.mul_right(DMat3::IDENTITY)
    }
}

/// `T(L)` (free-rigid-body.md §(c)): rows `(L1 L3, L2 L3, −L⊥²)/(L⊥ L)`, `(−L2, L1, 0)/L⊥`,
/// `L/|L|`. Takes the body-frame `L` to `+z`; needs `L⊥ = |(L1, L2)| > 0`. `inv_l = 1/|L|`.
#[inline]
pub(crate) fn to_invariant_frame(l: DVec3, inv_l: f64) -> DMat3 {
    let l_perp = (l.x * l.x + l.y * l.y).sqrt();
    let inv_perp = 1.0 / l_perp;
    let (cx, cy) = (l.x * inv_perp, l.y * inv_perp);
    let (z, p) = (l.z * inv_l, l_perp * inv_l);
    // Columns of T (glam is column-major): T = [[cx z, cy z, −p], [−cy, cx, 0], [l/|l|]].
    DMat3::from_cols(
        DVec3::new(cx * z, -cy, l.x * inv_l),
        DVec3::new(cy * z, cx, l.y * inv_l),
        DVec3::new(-p, 0.0, z),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_permutations_are_proper() {
        for index in [
            [0, 1, 2],
            [2, 1, 0],
            [1, 0, 2],
            [0, 2, 1],
            [1, 2, 0],
            [2, 0, 1],
        ] {
            let p = AxisOrder::new(index);
            let m = p.matrix();
            assert_eq!(m.determinant(), 1.0, "{index:?}");
            let v = DVec3::new(1.0, 2.0, 3.0);
            assert_eq!(p.ordered(v), m * v);
            assert_eq!(p.unordered(p.ordered(v)), v);
            let a = DMat3::from_cols_array(&[1., 2., 3., 4., 5., 6., 7., 8., 10.]);
            assert_eq!(p.mul_right(a), a * m);
        }
    }

    #[test]
    fn t_takes_l_to_z() {
        let l = DVec3::new(0.3, -1.2, 0.7);
        let t = to_invariant_frame(l, 1.0 / l.length());
        assert!((t * l - DVec3::new(0.0, 0.0, l.length())).length() < 1e-15);
        assert!((t.determinant() - 1.0).abs() < 1e-15);
        assert!((t.transpose() * t).abs_diff_eq(DMat3::IDENTITY, 1e-15));
    }
}
