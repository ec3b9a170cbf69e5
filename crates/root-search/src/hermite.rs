//! The cubic Hermite interpolant of two samples (003 Eqs. 13–15).
//!
//! Two evaluations `(f₁, f₁')` at `t₁` and `(f₂, f₂')` at `t₂ = t₁ + h` determine a unique
//! cubic `f_c(τ) = f₁ + f₁' τ + α τ² + β τ³` (003 Eq. 13) with
//! `α = [3(f₂ − f₁) − (2f₁' + f₂') h] / h²` (Eq. 14) and
//! `β = [2(f₁ − f₂) + (f₁' + f₂') h] / h³` (Eq. 15).
//! Its error is `O(h⁴)`, so it predicts well where the extrema of `f` lie in the interval and
//! how deep they are: that is what lets the adaptive search take long steps and still see a
//! grazing dip.
//!
//! The cubic is kept in the unit variable `u = τ/h ∈ [0, 1]`,
//! `f_c = f₁ + D u + A u² + B u³` with `D = f₁' h`, `A = α h²`, `B = β h³`, which avoids
//! dividing by powers of a small `h`.

use crate::indicator::Sample;

/// The interpolant on `[t₁, t₁ + h]`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hermite {
    t1: f64,
    h: f64,
    f1: f64,
    d: f64,
    a: f64,
    b: f64,
}

/// A critical point of the interpolant strictly inside the interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Extremum {
    /// Where (absolute time).
    pub(crate) t: f64,
    /// The interpolant's value there.
    pub(crate) value: f64,
    /// Whether it is a minimum (else a maximum).
    pub(crate) is_min: bool,
}

impl Hermite {
    /// The cubic through `p` and `q` (`q.t > p.t`) with their derivatives.
    #[inline]
    pub(crate) fn new(p: &Sample, q: &Sample) -> Self {
        let h = q.t - p.t;
        let d = p.df * h;
        let e = q.df * h;
        let df = q.f - p.f;
        // 003 Eqs. 14–15 scaled by h² and h³.
        let a = 3.0 * df - 2.0 * d - e;
        let b = -2.0 * df + d + e;
        Self {
            t1: p.t,
            h,
            f1: p.f,
            d,
            a,
            b,
        }
    }

    /// The interpolant at unit position `u`.
    #[inline]
    fn value_u(&self, u: f64) -> f64 {
        self.f1 + u * (self.d + u * (self.a + u * self.b))
    }

    /// Its `u`-derivative at `u`.
    #[inline]
    fn slope_u(&self, u: f64) -> f64 {
        self.d + u * (2.0 * self.a + 3.0 * self.b * u)
    }

    /// The interpolant at absolute time `t`.
    #[cfg(test)]
    pub(crate) fn value(&self, t: f64) -> f64 {
        self.value_u((t - self.t1) / self.h)
    }

    /// Whether the interpolant may have a critical point inside the interval: a cheap test (no
    /// square root, no division) that lets most steps skip [`extrema`](Self::extrema).
    ///
    /// The slope `3B u² + 2A u + D` is `D` at `u = 0` and `E = D + 2A + 3B` at `u = 1`. If they
    /// differ in sign there is a critical point inside; if they agree, there are two only when
    /// the parabola's vertex `−A/3B` lies in `(0, 1)` and its discriminant `A² − 3BD` is positive.
    #[inline]
    pub(crate) fn may_turn(&self) -> bool {
        let e = self.d + 2.0 * self.a + 3.0 * self.b;
        if self.d * e <= 0.0 {
            return true;
        }
        let vertex_inside = -self.a * self.b > 0.0 && self.a.abs() < 3.0 * self.b.abs();
        vertex_inside && self.a * self.a - 3.0 * self.b * self.d > 0.0
    }

    /// A bound on how far the interpolant strays from its value at the start of the interval:
    /// `|f_c − f₁| ≤ |D| + |A| + |B|` for `u ∈ [0, 1]`.
    #[inline]
    pub(crate) fn reach(&self) -> f64 {
        self.d.abs() + self.a.abs() + self.b.abs()
    }

    /// Whether the interpolant is convex (`up`) or concave (`!up`) over the whole interval: its
    /// second derivative is linear, so its signs at the two ends decide.
    #[inline]
    pub(crate) fn bends(&self, up: bool) -> bool {
        let (c0, c1) = (2.0 * self.a, 2.0 * self.a + 6.0 * self.b);
        if up {
            c0 >= 0.0 && c1 >= 0.0
        } else {
            c0 <= 0.0 && c1 <= 0.0
        }
    }

    /// The critical points strictly inside the interval, in time order (at most two).
    ///
    /// They are the roots of the quadratic `3B u² + 2A u + D = 0`, solved in the cancellation-free
    /// form; a double root (an inflection with zero slope) is not an extremum and is dropped.
    pub(crate) fn extrema(&self) -> ([Extremum; 2], usize) {
        let (qa, qb, qc) = (3.0 * self.b, 2.0 * self.a, self.d);
        let mut roots = [f64::NAN; 2];
        let scale = qa.abs().max(qb.abs()).max(qc.abs());
        if scale == 0.0 {
            return ([Extremum::NONE; 2], 0);
        }
        if qa.abs() <= 1e-14 * scale {
            // Practically a parabola (B ≈ 0): the slope is linear in u.
            if qb != 0.0 {
                roots[0] = -qc / qb;
            }
        } else {
            let disc = qb * qb - 4.0 * qa * qc;
            if disc > 0.0 {
                let q = -0.5 * (qb + disc.sqrt().copysign(qb));
                roots[0] = q / qa;
                roots[1] = if q != 0.0 { qc / q } else { f64::NAN };
            }
        }
        if roots[1] < roots[0] {
            roots.swap(0, 1);
        }
        let mut out = [Extremum::NONE; 2];
        let mut n = 0;
        for u in roots {
            if u > 0.0 && u < 1.0 {
                let curv = 2.0 * self.a + 6.0 * self.b * u;
                if curv != 0.0 {
                    out[n] = Extremum {
                        t: self.t1 + u * self.h,
                        value: self.value_u(u),
                        is_min: curv > 0.0,
                    };
                    n += 1;
                }
            }
        }
        (out, n)
    }

    /// The earliest root of the interpolant in the interval, assuming the ends have opposite
    /// signs (`f₁ ≠ 0`); used as the starting point of the root refinement.
    ///
    /// The interval is cut at the interpolant's extrema and the first piece with a sign change
    /// is searched by Newton's method on the cubic, safeguarded by bisection. No evaluation of
    /// the indicator is spent here.
    pub(crate) fn first_root(&self) -> f64 {
        let (ext, n) = self.extrema();
        let mut lo = 0.0;
        let s0 = self.f1 > 0.0;
        let mut hi = 1.0;
        for e in &ext[..n] {
            let u = (e.t - self.t1) / self.h;
            if (self.value_u(u) > 0.0) != s0 {
                hi = u;
                break;
            }
            lo = u;
        }
        // The piece [lo, hi] changes sign (or the interpolant is inaccurate and the secant
        // guess below is as good as any): Newton with bisection fallback.
        let (mut a, mut b) = (lo, hi);
        let mut u = 0.5 * (a + b);
        for _ in 0..40 {
            let v = self.value_u(u);
            if v == 0.0 {
                break;
            }
            if (v > 0.0) == s0 {
                a = u;
            } else {
                b = u;
            }
            let s = self.slope_u(u);
            let next = if s != 0.0 { u - v / s } else { f64::NAN };
            let nu = if next > a && next < b {
                next
            } else {
                0.5 * (a + b)
            };
            let done = (nu - u).abs() < 1e-15 || b - a < 1e-15;
            u = nu;
            if done {
                break;
            }
        }
        self.t1 + u.clamp(0.0, 1.0) * self.h
    }
}

impl Extremum {
    /// A placeholder for an unused slot.
    pub(crate) const NONE: Extremum = Extremum {
        t: f64::NAN,
        value: f64::NAN,
        is_min: false,
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(t: f64, f: f64, df: f64) -> Sample {
        Sample { t, f, df }
    }

    #[test]
    fn reproduces_any_cubic_exactly() {
        // f = 2 − t + 0.5 t² − 0.25 t³ on [0.3, 1.7].
        let f = |t: f64| 2.0 - t + 0.5 * t * t - 0.25 * t * t * t;
        let df = |t: f64| -1.0 + t - 0.75 * t * t;
        let c = Hermite::new(&s(0.3, f(0.3), df(0.3)), &s(1.7, f(1.7), df(1.7)));
        for k in 0..=20 {
            let t = 0.3 + 1.4 * k as f64 / 20.0;
            assert!((c.value(t) - f(t)).abs() < 1e-13, "t = {t}");
        }
    }

    #[test]
    fn matches_003_eqs_14_15() {
        let (f1, d1, f2, d2, h) = (0.7, -1.3, 0.2, 0.4, 0.25);
        let alpha = (3.0 * (f2 - f1) - (2.0 * d1 + d2) * h) / (h * h);
        let beta = (2.0 * (f1 - f2) + (d1 + d2) * h) / (h * h * h);
        let c = Hermite::new(&s(1.0, f1, d1), &s(1.0 + h, f2, d2));
        for tau in [0.03, 0.1, 0.2] {
            let expect = f1 + d1 * tau + alpha * tau * tau + beta * tau * tau * tau;
            assert!((c.value(1.0 + tau) - expect).abs() < 1e-14);
        }
    }

    #[test]
    fn finds_both_extrema_in_order_with_their_kind() {
        // f = (t − 1)(t − 2)(t − 3): max at 2 − 1/√3, min at 2 + 1/√3.
        let f = |t: f64| (t - 1.0) * (t - 2.0) * (t - 3.0);
        let df = |t: f64| 3.0 * t * t - 12.0 * t + 11.0;
        let c = Hermite::new(&s(0.5, f(0.5), df(0.5)), &s(3.5, f(3.5), df(3.5)));
        let (e, n) = c.extrema();
        assert_eq!(n, 2);
        let r = 1.0 / 3f64.sqrt();
        assert!((e[0].t - (2.0 - r)).abs() < 1e-12 && !e[0].is_min);
        assert!((e[1].t - (2.0 + r)).abs() < 1e-12 && e[1].is_min);
        assert!((e[1].value - f(2.0 + r)).abs() < 1e-12);
    }

    #[test]
    fn parabola_and_flat_cases() {
        // A parabola: B = 0 exactly.
        let c = Hermite::new(&s(0.0, 1.0, -2.0), &s(2.0, 1.0, 2.0));
        let (e, n) = c.extrema();
        assert_eq!(n, 1);
        assert!((e[0].t - 1.0).abs() < 1e-15 && e[0].is_min && e[0].value.abs() < 1e-15);
        // Constant: no extrema, no panic.
        let c = Hermite::new(&s(0.0, 1.0, 0.0), &s(1.0, 1.0, 0.0));
        assert_eq!(c.extrema().1, 0);
        // Monotone: no extrema.
        let c = Hermite::new(&s(0.0, 0.0, 1.0), &s(1.0, 1.0, 1.0));
        assert_eq!(c.extrema().1, 0);
    }

    #[test]
    fn the_cheap_turn_test_agrees_with_the_extrema() {
        // Slopes sampled over a grid of end values: may_turn must be true whenever an interior
        // extremum exists (it may be true without one only when a slope vanishes at an end).
        let vals = [-2.0, -0.7, -0.1, 0.0, 0.3, 1.1, 2.5];
        for &f2 in &vals {
            for &d1 in &vals {
                for &d2 in &vals {
                    let c = Hermite::new(&s(0.0, 0.4, d1), &s(1.3, f2, d2));
                    if c.extrema().1 > 0 {
                        assert!(c.may_turn(), "f2 {f2} d1 {d1} d2 {d2}");
                    }
                }
            }
        }
    }

    #[test]
    fn first_root_is_the_earliest_of_three() {
        let f = |t: f64| (t - 1.0) * (t - 2.0) * (t - 3.0);
        let df = |t: f64| 3.0 * t * t - 12.0 * t + 11.0;
        let c = Hermite::new(&s(0.5, f(0.5), df(0.5)), &s(3.5, f(3.5), df(3.5)));
        assert!((c.first_root() - 1.0).abs() < 1e-12);
    }
}
