//! The potential smoothed to zero for standard molecular dynamics (003 §V.B, Eq. 26).

use crate::error::positive;
use crate::{PairEval, PairGeometry, PairPotential, PotentialError};

/// `U_smooth = g(r) U` with the cubic switch of 003 Eq. 26,
///
/// ```text
/// g(r) = 1                                            r < r_l
///        (r_u − r)² (r_u − 3r_l + 2r) / (r_u − r_l)³   r_l ≤ r ≤ r_u
///        0                                            r > r_u
/// ```
///
/// which takes `U` and its first derivative continuously to zero at `r_u` (`g(r_l) = 1`,
/// `g(r_u) = 0`, `g' = 0` at both ends). The paper uses `r_l = 2.5σ`, `r_u = 3σ`. Forces and
/// torques are exact for the product: the force gains `−U g'(r) r̂_ij`, with
/// `g'(r) = −6 (r_u − r)(r − r_l)/(r_u − r_l)³`, and both torques scale by `g`. Beyond `r_u`
/// the inner potential is not evaluated at all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Smoothed<P> {
    inner: P,
    r_l: f64,
    r_u: f64,
    inv_width3: f64,
}

impl<P: PairPotential> Smoothed<P> {
    /// `inner` switched off between `r_l` and `r_u`.
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] unless `0 < r_l < r_u` are finite.
    pub fn new(inner: P, r_l: f64, r_u: f64) -> Result<Self, PotentialError> {
        let r_l = positive("r_l", r_l)?;
        let r_u = positive("r_u", r_u)?;
        if r_u <= r_l {
            return Err(PotentialError::Parameter {
                name: "r_u",
                value: r_u,
                why: "larger than r_l",
            });
        }
        let w = r_u - r_l;
        Ok(Self {
            inner,
            r_l,
            r_u,
            inv_width3: 1.0 / (w * w * w),
        })
    }

    /// The paper's window `r_l = 2.5 s`, `r_u = 3 s` for a length `s` (`σ` of the rods).
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn paper(inner: P, sigma: f64) -> Result<Self, PotentialError> {
        Self::new(inner, 2.5 * sigma, 3.0 * sigma)
    }

    /// The unsmoothed potential.
    pub fn inner(&self) -> &P {
        &self.inner
    }

    /// `(r_l, r_u)`.
    pub fn window(&self) -> (f64, f64) {
        (self.r_l, self.r_u)
    }

    /// `(g(r), g'(r))`.
    #[inline]
    pub fn switch(&self, r: f64) -> (f64, f64) {
        if r <= self.r_l {
            (1.0, 0.0)
        } else if r >= self.r_u {
            (0.0, 0.0)
        } else {
            let (du, dl) = (self.r_u - r, r - self.r_l);
            (
                du * du * (self.r_u - 3.0 * self.r_l + 2.0 * r) * self.inv_width3,
                -6.0 * du * dl * self.inv_width3,
            )
        }
    }
}

impl<P: PairPotential> PairPotential for Smoothed<P> {
    #[inline]
    fn energy(&self, g: &PairGeometry) -> f64 {
        let r = g.r_ij.length();
        if r >= self.r_u {
            return 0.0;
        }
        let u = self.inner.energy(g);
        if r <= self.r_l {
            u
        } else {
            self.switch(r).0 * u
        }
    }

    // Always inlined: engines call it once per pair in their hot loop, and without the hint
    // LLVM kept it out of line there (a call and a `Result` through memory per pair: +30 %
    // per step for Lennard-Jones spheres in smd, measured).
    #[inline(always)]
    fn evaluate(&self, g: &PairGeometry) -> Result<PairEval, PotentialError> {
        let r = g.r_ij.length();
        if r >= self.r_u {
            return Ok(PairEval::default());
        }
        let e = self.inner.evaluate(g)?;
        if r <= self.r_l {
            return Ok(e);
        }
        let (s, ds) = self.switch(r);
        Ok(PairEval {
            energy: s * e.energy,
            force: s * e.force - (e.energy * ds / r) * g.r_ij,
            torque_i: s * e.torque_i,
            torque_j: s * e.torque_j,
        })
    }

    /// The inner potential's minimum: exact when the inner minimum lies inside `r_l` (as for
    /// every potential of this crate with the paper's window), otherwise a lower bound (the
    /// switch only makes a well shallower).
    fn minimum(&self) -> f64 {
        self.inner.minimum()
    }

    fn length_scale(&self) -> f64 {
        self.inner.length_scale()
    }

    fn depends_on_orientation(&self) -> bool {
        self.inner.depends_on_orientation()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LennardJones;
    use glam::DVec3;

    #[test]
    fn switch_is_c1_at_both_ends() {
        let s = Smoothed::paper(LennardJones::new(1.0, 1.0).unwrap(), 1.0).unwrap();
        assert_eq!(s.switch(2.5), (1.0, 0.0));
        assert_eq!(s.switch(3.0), (0.0, 0.0));
        let h = 1e-9;
        let (g_in, d_in) = s.switch(2.5 + h);
        assert!((g_in - 1.0).abs() < 1e-15 && d_in.abs() < 1e-7);
        let (g_out, d_out) = s.switch(3.0 - h);
        assert!(g_out.abs() < 1e-15 && d_out.abs() < 1e-7);
        // Midpoint of the window: g = ½, g' = −6 (¼ · ¼) / ⅛ = −3.
        let (g, d) = s.switch(2.75);
        assert!((g - 0.5).abs() < 1e-15 && (d + 3.0).abs() < 1e-14);
    }

    #[test]
    fn beyond_the_window_is_exactly_zero() {
        let s = Smoothed::paper(LennardJones::new(1.0, 1.0).unwrap(), 1.0).unwrap();
        let g = PairGeometry::spheres(DVec3::X * 3.5);
        assert_eq!(s.energy(&g), 0.0);
        assert_eq!(s.evaluate(&g).unwrap(), PairEval::default());
    }

    #[test]
    fn bad_windows_are_refused() {
        let lj = LennardJones::new(1.0, 1.0).unwrap();
        assert!(Smoothed::new(lj, 3.0, 2.5).is_err());
        assert!(Smoothed::new(lj, 0.0, 2.5).is_err());
        assert!(Smoothed::new(lj, 2.0, f64::INFINITY).is_err());
    }
}
