//! Principal moments of inertia, checked once, and the kind of body they describe.

use crate::FreeError;

/// What the principal moments make of a body; decides which propagator its motion uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BodyKind {
    /// `I1 = I2 = I3 > 0`: a spherical rotor (also any body with cubic symmetry).
    Spherical,
    /// Exactly two equal moments: a symmetric top about body axis `axis` (0, 1 or 2).
    Symmetric {
        /// The symmetry axis (the one with the distinct moment).
        axis: usize,
    },
    /// Three different moments: an asymmetric top.
    Asymmetric,
    /// One zero moment, the other two equal: a linear rotor (a rod, 003 §V) along body axis
    /// `axis`. Its spin about that axis is decoupled and left out.
    Linear {
        /// The long axis (the one with the zero moment).
        axis: usize,
    },
}

/// Principal moments of inertia `(I1, I2, I3)` of a rigid body, in any order.
///
/// Checked once on construction: finite, non-negative, at most one zero (a linear rotor, whose
/// other two moments must then be equal), and the triangle inequality `I_a ≤ I_b + I_c` that
/// every mass distribution obeys. Equality of moments is exact: moments that differ by one ulp
/// make an asymmetric top, which the asymmetric propagator handles accurately.
///
/// ```
/// use rigid_free::{BodyKind, Moments};
/// assert_eq!(Moments::new([1.0, 2.0, 2.5])?.kind(), BodyKind::Asymmetric);
/// assert_eq!(Moments::new([0.0, 1.154, 1.154])?.kind(), BodyKind::Linear { axis: 0 });
/// assert!(Moments::new([1.0, 1.0, 3.0]).is_err()); // 3 > 1 + 1
/// # Ok::<(), rigid_free::FreeError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moments {
    i: [f64; 3],
    kind: BodyKind,
}

impl Moments {
    /// Checks the moments and classifies the body.
    ///
    /// # Errors
    /// [`FreeError::NonFiniteMoment`], [`FreeError::NegativeMoment`],
    /// [`FreeError::TooManyZeroMoments`], [`FreeError::ZeroMomentUnequalOthers`] or
    /// [`FreeError::TriangleInequality`].
    pub fn new(i: [f64; 3]) -> Result<Self, FreeError> {
        for (axis, &value) in i.iter().enumerate() {
            if !value.is_finite() {
                return Err(FreeError::NonFiniteMoment { axis, value });
            }
            if value < 0.0 {
                return Err(FreeError::NegativeMoment { axis, value });
            }
        }
        let zeros: Vec<usize> = (0..3).filter(|&k| i[k] == 0.0).collect();
        if zeros.len() > 1 {
            return Err(FreeError::TooManyZeroMoments);
        }
        if let Some(&axis) = zeros.first() {
            let others = [i[(axis + 1) % 3], i[(axis + 2) % 3]];
            if others[0] != others[1] {
                return Err(FreeError::ZeroMomentUnequalOthers { others });
            }
            return Ok(Self {
                i,
                kind: BodyKind::Linear { axis },
            });
        }
        for k in 0..3 {
            if i[k] > i[(k + 1) % 3] + i[(k + 2) % 3] {
                return Err(FreeError::TriangleInequality { moments: i });
            }
        }
        let kind = match (i[0] == i[1], i[1] == i[2], i[0] == i[2]) {
            (true, true, _) => BodyKind::Spherical,
            (true, false, _) => BodyKind::Symmetric { axis: 2 },
            (false, true, _) => BodyKind::Symmetric { axis: 0 },
            (false, false, true) => BodyKind::Symmetric { axis: 1 },
            (false, false, false) => BodyKind::Asymmetric,
        };
        Ok(Self { i, kind })
    }

    /// The moments as given.
    #[inline]
    pub fn get(&self) -> [f64; 3] {
        self.i
    }

    /// The kind of body.
    #[inline]
    pub fn kind(&self) -> BodyKind {
        self.kind
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bad_input_has_its_message() {
        let cases: [([f64; 3], &str); 6] = [
            ([f64::NAN, 1.0, 1.0], "I1 = NaN is not a finite number"),
            ([1.0, -2.0, 2.0], "I2 = -2 is negative"),
            ([0.0, 0.0, 1.0], "at most one moment"),
            (
                [1.0, 0.0, 2.0],
                "other two moments must be equal, but they are 2 and 1",
            ),
            ([1.0, 1.0, 2.5], "triangle inequality"),
            ([1.0, f64::INFINITY, 1.0], "I2 = inf is not a finite number"),
        ];
        for (i, want) in cases {
            let msg = Moments::new(i).unwrap_err().to_string();
            assert!(msg.contains(want), "{i:?}: {msg}");
        }
    }

    #[test]
    fn kinds() {
        let k = |i| Moments::new(i).unwrap().kind();
        assert_eq!(k([2.0, 2.0, 2.0]), BodyKind::Spherical);
        assert_eq!(k([1.0, 2.0, 2.0]), BodyKind::Symmetric { axis: 0 });
        assert_eq!(k([2.0, 1.0, 2.0]), BodyKind::Symmetric { axis: 1 });
        assert_eq!(k([2.0, 2.0, 1.0]), BodyKind::Symmetric { axis: 2 });
        assert_eq!(k([1.0, 1.5, 2.0]), BodyKind::Asymmetric);
        assert_eq!(k([1.0, 1.0, 0.0]), BodyKind::Linear { axis: 2 });
        // Flat bodies sit on the triangle inequality and are allowed.
        assert_eq!(k([1.0, 2.0, 3.0]), BodyKind::Asymmetric);
    }
}
