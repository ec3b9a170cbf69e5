//! Jacobi elliptic functions sn, cn, dn by the descending Gauss (Landen) transformation.
//!
//! The arithmetic-geometric mean of `a₀ = 1`, `b₀ = √m_c` (DLMF 22.20(ii)) gives the moduli of
//! a chain of Gauss transformations `k_{n+1} = (a_n − b_n)/(a_n + b_n)` that fall quadratically
//! to zero. At the last level `sn ≈ sin`, `cn ≈ cos`, `dn ≈ 1` to within one ulp, and the
//! transformation (DLMF 22.7.1–22.7.3) carries the three functions back up to `m`. Written for
//! the ratio `cs = cn/sn` in homogeneous form `(C, S)`, one step back is
//!
//! ```text
//! C_n = C_{n+1} · dn_{n+1} · a_{n+1},          S_n = S_{n+1} · a_n,
//! dn_n = (a_{n+1} C² + b_n S²) / (a_{n+1} C² + a_n S²)      (C, S of level n + 1)
//! ```
//!
//! with only positive terms, so no step cancels; at the end `sn = S/√(S²+C²)`, `cn = C/√(S²+C²)`.
//! The argument at the last level is `u·M` with `M = AGM(1, √m_c) = π/(2K)`, which makes the
//! approximation `sn ≈ sin` uniform in `u` (the period is exact) instead of growing with `u`.
//! The table depends on `m_c` only, so it is built once per parameter and each evaluation costs
//! one sine and cosine plus a few multiplications and one division per level.

use crate::FreeError;
use std::f64::consts::FRAC_PI_2;

/// Most levels the table holds: `m_c` = the smallest subnormal needs 14.
const MAX_LEVELS: usize = 16;

/// sn, cn and dn of one argument.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnCnDn {
    /// sn(u | m).
    pub sn: f64,
    /// cn(u | m).
    pub cn: f64,
    /// dn(u | m).
    pub dn: f64,
}

/// The Gauss-transformation table of one parameter: evaluates sn, cn, dn at any argument.
///
/// Takes the complementary parameter `m_c = 1 − m` so that parameters close to 1 (near the
/// separatrix of a rigid body) keep their full precision.
///
/// ```
/// use rigid_free::elliptic::Jacobi;
/// let j = Jacobi::new(0.5)?; // m = 0.5
/// let f = j.sn_cn_dn(1.0);
/// assert!((f.sn - 0.80300182489564389).abs() < 1e-15);
/// assert!((f.sn * f.sn + f.cn * f.cn - 1.0).abs() < 1e-15);
/// # Ok::<(), rigid_free::FreeError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jacobi {
    m_c: f64,
    levels: usize,
    a: [f64; MAX_LEVELS],
    b: [f64; MAX_LEVELS],
    /// `AGM(1, √m_c) = π/(2K)`; 0 on the separatrix `m_c = 0`.
    agm: f64,
}

impl Jacobi {
    /// Builds the table for parameter `m = 1 − m_c`, `0 ≤ m_c ≤ 1`.
    ///
    /// # Errors
    /// [`FreeError::ParameterOutOfRange`] if `m_c` is NaN or outside `[0, 1]`.
    pub fn new(m_c: f64) -> Result<Self, FreeError> {
        if !(0.0..=1.0).contains(&m_c) {
            return Err(FreeError::ParameterOutOfRange {
                function: "Jacobi::new",
                name: "m_c",
                value: m_c,
            });
        }
        Ok(Self::new_unchecked(m_c))
    }

    /// [`Jacobi::new`] for an `m_c` the caller has already checked to lie in `[0, 1]`.
    pub(crate) fn new_unchecked(m_c: f64) -> Self {
        let mut t = Self {
            m_c,
            levels: 0,
            a: [0.0; MAX_LEVELS],
            b: [0.0; MAX_LEVELS],
            agm: 0.0,
        };
        if m_c == 0.0 {
            return t;
        }
        let (mut a, mut b) = (1.0_f64, m_c.sqrt());
        let mut n = 0;
        // Stop once a − b ≤ 2⁻⁵² a: then k² ≈ 2(a − b)/a of the last level is below one ulp and
        // sn, dn of that level equal sin, 1 to rounding.
        while a - b > f64::EPSILON * a && n + 1 < MAX_LEVELS {
            t.a[n] = a;
            t.b[n] = b;
            let next = 0.5 * (a + b);
            b = (a * b).sqrt();
            a = next;
            n += 1;
        }
        t.a[n] = a;
        t.b[n] = b;
        t.levels = n;
        t.agm = 0.5 * (a + b);
        t
    }

    /// The complementary parameter `m_c = 1 − m` the table was built for.
    #[inline]
    pub fn m_c(&self) -> f64 {
        self.m_c
    }

    /// The number of Gauss transformations an evaluation applies.
    #[inline]
    pub fn levels(&self) -> usize {
        self.levels
    }

    /// `AGM(1, √m_c) = π / (2K)`, the factor that turns `u` into the phase `x = πu/(2K)` of the
    /// theta functions (0 on the separatrix, where `K = ∞`).
    #[inline]
    pub fn agm(&self) -> f64 {
        self.agm
    }

    /// The quarter period `K(m) = π/(2·AGM(1, √m_c))` (DLMF 19.8.5); `+∞` when `m_c = 0`.
    #[inline]
    pub fn quarter_period(&self) -> f64 {
        if self.m_c == 0.0 {
            f64::INFINITY
        } else {
            FRAC_PI_2 / self.agm
        }
    }

    /// The AGM table `(a_n, b_n)`, level 0 first (level 0 is `(1, √m_c)`), shared with the
    /// complete integral of the third kind (DLMF 19.8.6).
    pub(crate) fn table(&self) -> (&[f64], &[f64]) {
        (&self.a[..=self.levels], &self.b[..=self.levels])
    }

    /// sn, cn, dn of `u`.
    #[inline]
    pub fn sn_cn_dn(&self, u: f64) -> SnCnDn {
        if self.m_c == 0.0 {
            // m = 1: sn = tanh, cn = dn = sech (DLMF 22.5.iv).
            let sech = 1.0 / u.cosh();
            return SnCnDn {
                sn: u.tanh(),
                cn: sech,
                dn: sech,
            };
        }
        let (s, c) = crate::trig::sin_cos(u * self.agm);
        if self.levels == 0 {
            // m ≤ 2⁻⁵² or so: sn = sin, cn = cos to rounding.
            return SnCnDn {
                sn: s,
                cn: c,
                dn: 1.0,
            };
        }
        self.at_phase(s, c)
    }

    /// sn, cn, dn from `sin x`, `cos x` of the phase `x = u·AGM(1, √m_c) = πu/(2K)`, for callers
    /// that need the same sine and cosine elsewhere (the theta series of the asymmetric top).
    /// Not for `m_c = 0`.
    #[inline]
    pub(crate) fn at_phase(&self, sin_x: f64, cos_x: f64) -> SnCnDn {
        let (mut s, mut c, mut d) = (sin_x, cos_x, 1.0_f64);
        let mut n = self.levels;
        while n > 0 {
            n -= 1;
            let (a0, b0, a1) = (self.a[n], self.b[n], self.a[n + 1]);
            let (c2, s2) = (c * c, s * s);
            let d_next = (a1 * c2 + b0 * s2) / (a1 * c2 + a0 * s2);
            c *= d * a1;
            s *= a0;
            d = d_next;
            // Both factors shrink |(C, S)| by at most a few orders of magnitude per level, which
            // only the most extreme parameters (m_c ≲ 1e-200) can underflow: rescale then.
            if s.abs() + c.abs() < 1e-100 {
                s *= 1e100;
                c *= 1e100;
            }
        }
        let r = 1.0 / (s * s + c * c).sqrt();
        SnCnDn {
            sn: s * r,
            cn: c * r,
            dn: d,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameter_range_is_checked() {
        assert!(Jacobi::new(-1e-300).is_err());
        assert!(Jacobi::new(1.0 + f64::EPSILON).is_err());
        assert!(Jacobi::new(f64::NAN).is_err());
        assert!(Jacobi::new(0.0).is_ok());
        assert!(Jacobi::new(1.0).is_ok());
    }

    #[test]
    fn m_zero_is_circular() {
        let j = Jacobi::new(1.0).unwrap();
        assert_eq!(j.levels(), 0);
        for u in [0.0, 0.3, -2.0, 100.0] {
            let f = j.sn_cn_dn(u);
            assert!((f.sn - u.sin()).abs() <= 2.3e-16 && (f.cn - u.cos()).abs() <= 2.3e-16);
            assert_eq!(f.dn, 1.0);
        }
    }

    #[test]
    fn separatrix_is_hyperbolic() {
        let j = Jacobi::new(0.0).unwrap();
        let f = j.sn_cn_dn(0.7);
        assert_eq!(f.sn, 0.7f64.tanh());
        assert!((f.cn - 1.0 / 0.7f64.cosh()).abs() < 1e-16);
        assert_eq!(j.quarter_period(), f64::INFINITY);
    }

    #[test]
    fn identities_hold_across_parameters() {
        for m_c in [
            1e-300,
            1e-30,
            1e-12,
            1e-6,
            0.01,
            0.3,
            0.5,
            0.99,
            1.0 - 1e-12,
        ] {
            let j = Jacobi::new(m_c).unwrap();
            assert!(
                j.levels() < MAX_LEVELS - 1,
                "m_c = {m_c}: {} levels",
                j.levels()
            );
            let m = 1.0 - m_c;
            for i in -40..=40 {
                let u = 0.37 * f64::from(i);
                let f = j.sn_cn_dn(u);
                let e1 = (f.sn * f.sn + f.cn * f.cn - 1.0).abs();
                let e2 = (f.dn * f.dn + m * f.sn * f.sn - 1.0).abs();
                assert!(e1 < 5e-16 && e2 < 5e-16, "m_c {m_c} u {u}: {e1:e} {e2:e}");
            }
            // sn(K) = 1, cn(K) = 0, dn(K) = √m_c.
            let k = j.quarter_period();
            let f = j.sn_cn_dn(k);
            assert!((f.sn - 1.0).abs() < 1e-15);
            assert!(f.cn.abs() < 1e-15 * k.max(1.0) * 4.0, "cn(K) = {}", f.cn);
            assert!((f.dn - m_c.sqrt()).abs() < 1e-15 * k.max(1.0) * 4.0);
        }
    }

    #[test]
    fn odd_and_even() {
        let j = Jacobi::new(0.2).unwrap();
        for u in [0.1, 1.3, 7.9] {
            let (p, n) = (j.sn_cn_dn(u), j.sn_cn_dn(-u));
            assert_eq!(p.sn, -n.sn);
            assert_eq!(p.cn, n.cn);
            assert_eq!(p.dn, n.dn);
        }
    }
}
