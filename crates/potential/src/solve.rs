//! One-dimensional root and minimum finding for set-up code (reaches, profile radii).
//!
//! Brent's zero finder (R. P. Brent, *Algorithms for Minimization without Derivatives*, 1973,
//! ch. 4): inverse quadratic interpolation or secant steps, accepted only while they shrink the
//! bracket fast enough, bisection otherwise. A non-finite function value (an overlapping pair
//! gives `U = +∞`) forces bisection, so the bracket never fills with NaN.

/// A root of `f` in `[a, b]`, where `f(a)` and `f(b)` have opposite signs or one is zero, to an
/// absolute width `tol + 4ε|x|`. `fa`, `fb` are the values at the ends (either may be `±∞`).
pub(crate) fn brent_root(
    f: &mut impl FnMut(f64) -> f64,
    mut a: f64,
    mut b: f64,
    mut fa: f64,
    mut fb: f64,
    tol: f64,
) -> f64 {
    if fa == 0.0 {
        return a;
    }
    if fb == 0.0 {
        return b;
    }
    debug_assert!((fa < 0.0) != (fb < 0.0), "brent_root needs a sign change");
    // `b` is the best estimate, `a` the previous one, `c` the far end of the bracket.
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    for _ in 0..200 {
        if (fb > 0.0) == (fc > 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() || !fb.is_finite() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol1 = 4.0 * f64::EPSILON * b.abs() + 0.5 * tol;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol1 || fb == 0.0 {
            return b;
        }
        let finite = fa.is_finite() && fb.is_finite() && fc.is_finite();
        if finite && e.abs() >= tol1 && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qa = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qa * (qa - r) - (b - a) * (r - 1.0));
                q = (qa - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            }
            p = p.abs();
            let min1 = 3.0 * xm * q - (tol1 * q).abs();
            let min2 = (e * q).abs();
            if 2.0 * p < min1.min(min2) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol1 { d } else { tol1.copysign(xm) };
        fb = f(b);
        if fb.is_nan() {
            // Treat NaN like the side of `c`'s opposite: bisect towards `c`.
            fb = f64::INFINITY.copysign(-fc);
        }
    }
    b
}

/// The minimiser of a unimodal `f` on `[a, b]` by golden-section search, to a relative width
/// of about `1e-9` (enough for the value, which is quadratic in the error).
pub(crate) fn golden_min(f: &mut impl FnMut(f64) -> f64, mut a: f64, mut b: f64) -> (f64, f64) {
    const G: f64 = 0.381_966_011_250_105_2; // (3 − √5)/2
    let mut x1 = a + G * (b - a);
    let mut x2 = b - G * (b - a);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..200 {
        if (b - a).abs() <= 1e-9 * (a.abs() + b.abs()) {
            break;
        }
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = a + G * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = b - G * (b - a);
            f2 = f(x2);
        }
    }
    if f1 <= f2 { (x1, f1) } else { (x2, f2) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brent_finds_roots_to_full_precision() {
        let mut calls = 0;
        let mut f = |x: f64| {
            calls += 1;
            x * x * x - 2.0
        };
        let (fa, fb) = (f(0.0), f(3.0));
        let x = brent_root(&mut f, 0.0, 3.0, fa, fb, 0.0);
        assert!((x - 2f64.cbrt()).abs() <= 4.0 * f64::EPSILON * x);
        assert!(calls < 30, "{calls}");
    }

    #[test]
    fn brent_survives_infinite_values() {
        // An overlap region with U = +∞ at the left end and beyond x < 0.5.
        let mut f = |x: f64| {
            if x < 0.5 {
                f64::INFINITY
            } else {
                1.0 / (x * x) - 1.0
            }
        };
        let f4 = f(4.0);
        let x = brent_root(&mut f, 0.1, 4.0, f64::INFINITY, f4, 0.0);
        assert!((x - 1.0).abs() < 1e-15);
    }

    #[test]
    fn golden_section_finds_the_well() {
        let (x, fx) = golden_min(&mut |x: f64| (x - 1.3).powi(2) - 2.0, 0.0, 5.0);
        // x only to ~√ε (the values near the bottom are equal in binary64), the value exactly.
        assert!((x - 1.3).abs() < 1e-7 && (fx + 2.0).abs() < 1e-15);
    }
}
