//! Root refinement in a bracket: Newton–Raphson with a safeguard, falling back on the
//! van Wijngaarden–Dekker–Brent method (000 §III.A).
//!
//! Once a sign change is bracketed in `[a, b]`, Newton's method converges in a couple of steps
//! because `f'` is available at every point. It is started from the earliest root of the cubic
//! Hermite interpolant of the bracket (003 Eqs. 13–15), which is already accurate to `O(h⁴)`.
//! 000 demands that a Newton result lie inside the bracket and that `f'` have the sign of the
//! crossing being refined; every iterate is checked that way, the bracket is shrunk with each
//! evaluation, and on the first violation Brent's method takes over the shrunken bracket, where
//! it is guaranteed to converge.

use crate::SearchError;
use crate::hermite::Hermite;
use crate::indicator::{Counted, Indicator, Sample, Side};

/// Newton steps before Brent takes over: from the cubic's root two or three suffice, so more
/// means the function is not behaving like its interpolant.
const NEWTON_STEPS: usize = 8;
/// Brent halves the bracket at worst every other step; this bounds any sane bracket.
const BRENT_STEPS: usize = 400;

/// The root in `[lo.t, hi.t]`, to within `tol` (absolute time) plus round-off of `t`.
///
/// `lo` must be strictly on side `from` (`lo.f ≠ 0`); `hi` on the other side or exactly zero.
pub(crate) fn refine<I: Indicator + ?Sized>(
    ind: &mut Counted<'_, I>,
    lo: Sample,
    hi: Sample,
    from: Side,
    tol: f64,
) -> Result<f64, SearchError> {
    debug_assert!(lo.f != 0.0 && Side::of(lo.f, lo.df, from) == from);
    if hi.f == 0.0 {
        return Ok(hi.t);
    }
    let (mut lo, mut hi) = (lo, hi);
    let mut x = Hermite::new(&lo, &hi).first_root();
    for _ in 0..NEWTON_STEPS {
        if !(x > lo.t && x < hi.t) {
            break;
        }
        let m = ind.at(x)?;
        if m.f == 0.0 {
            return Ok(x);
        }
        if (m.f > 0.0) == (from == Side::Pos) {
            lo = m;
        } else {
            hi = m;
        }
        // 000 §III.A: the slope must carry f across zero in the direction being refined.
        if m.df * from.sign() >= 0.0 {
            break;
        }
        let step = -m.f / m.df;
        if step.abs() <= tol + 2.0 * f64::EPSILON * x.abs() {
            let next = x + step;
            return Ok(if next >= lo.t && next <= hi.t {
                next
            } else {
                x
            });
        }
        x += step;
    }
    brent(ind, lo, hi, tol)
}

/// Brent's zero finder (inverse quadratic interpolation, secant, bisection) on a bracket with
/// opposite signs at its ends.
fn brent<I: Indicator + ?Sized>(
    ind: &mut Counted<'_, I>,
    lo: Sample,
    hi: Sample,
    tol: f64,
) -> Result<f64, SearchError> {
    let (mut a, mut fa) = (lo.t, lo.f);
    let (mut b, mut fb) = (hi.t, hi.f);
    let (mut c, mut fc) = (b, fb);
    let (mut d, mut e) = (b - a, b - a);
    for _ in 0..BRENT_STEPS {
        if (fb > 0.0) == (fc > 0.0) {
            // The root is between a and b: c takes a's place as the opposite end.
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            (a, b, c) = (b, c, b);
            (fa, fb, fc) = (fb, fc, fb);
        }
        let tol1 = 2.0 * f64::EPSILON * b.abs() + 0.5 * tol;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol1 || fb == 0.0 {
            return Ok(b);
        }
        if e.abs() >= tol1 && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                // Secant.
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                // Inverse quadratic interpolation.
                let qa = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qa * (qa - r) - (b - a) * (r - 1.0));
                q = (qa - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            }
            p = p.abs();
            if 2.0 * p < (3.0 * xm * q - (tol1 * q).abs()).min((e * q).abs()) {
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
        fb = ind.at(b)?.f;
    }
    Ok(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(f: &mut impl FnMut(f64) -> (f64, f64), t: f64) -> Sample {
        let (v, d) = f(t);
        Sample { t, f: v, df: d }
    }

    #[test]
    fn newton_converges_in_few_steps_on_a_smooth_root() {
        let mut f = |t: f64| (t.cos() - t, -t.sin() - 1.0);
        let (lo, hi) = (sample(&mut f, 0.0), sample(&mut f, 1.0));
        let mut c = Counted::new(&mut f);
        let r = refine(&mut c, lo, hi, Side::Pos, 1e-13).unwrap();
        assert!((r - 0.739_085_133_215_160_6).abs() < 1e-13);
        assert!(c.evals <= 3, "{} evaluations", c.evals);
    }

    #[test]
    fn a_triple_root_falls_back_to_brent_and_still_converges() {
        // f' vanishes at the root: Newton crawls; Brent takes over.
        let r0 = 0.3;
        let mut f = |t: f64| ((t - r0).powi(3), 3.0 * (t - r0).powi(2));
        let (lo, hi) = (sample(&mut f, 0.0), sample(&mut f, 1.0));
        let mut c = Counted::new(&mut f);
        let r = refine(&mut c, lo, hi, Side::Neg, 1e-12).unwrap();
        assert!((r - r0).abs() < 1e-5, "r = {r}"); // f = 1e-15 already below f's resolution
        assert!(c.evals < 120);
    }

    #[test]
    fn a_wrong_slope_sends_the_search_to_brent() {
        // A derivative that lies (points the wrong way): Newton must not be trusted.
        let mut f = |t: f64| (0.5 - t, 1.0);
        let (lo, hi) = (sample(&mut f, 0.0), sample(&mut f, 1.0));
        let mut c = Counted::new(&mut f);
        let r = refine(&mut c, lo, hi, Side::Pos, 1e-12).unwrap();
        assert!((r - 0.5).abs() < 1e-11);
    }

    #[test]
    fn exact_zero_at_the_far_end_is_returned_without_evaluation() {
        let mut f = |t: f64| (1.0 - t, -1.0);
        let (lo, hi) = (sample(&mut f, 0.0), sample(&mut f, 1.0));
        let mut c = Counted::new(&mut f);
        assert_eq!(refine(&mut c, lo, hi, Side::Pos, 1e-12).unwrap(), 1.0);
        assert_eq!(c.evals, 0);
    }

    #[test]
    fn brent_alone_finds_a_steep_root() {
        let mut f = |t: f64| {
            (
                (20.0 * (t - 0.123)).tanh(),
                20.0 / (20.0 * (t - 0.123)).cosh().powi(2),
            )
        };
        let (lo, hi) = (sample(&mut f, 0.0), sample(&mut f, 1.0));
        let mut c = Counted::new(&mut f);
        let r = brent(&mut c, lo, hi, 1e-13).unwrap();
        assert!((r - 0.123).abs() < 1e-12);
    }
}

/// The root of `g` in `[lo, hi]` when `g(lo) < 0 < g(hi)` and `g` is known to change sign
/// only once there (a certificate such as a Taylor model's monotone or convex window proves
/// it): then no grazing can hide another root, so no search is needed, only refinement. Newton–Raphson from `guess`, every iterate kept inside the
/// shrinking bracket (bisection when a step would leave it, as 000 §III.A demands of Newton
/// results), until a step is below `tol` plus round-off of `t`. `g` returns `(g(t), g'(t))`.
///
/// Returns the root and the number of evaluations of `g`.
pub fn monotone_root<G: FnMut(f64) -> (f64, f64)>(
    mut g: G,
    lo: f64,
    hi: f64,
    guess: f64,
    tol: f64,
) -> (f64, u32) {
    let (mut lo, mut hi) = (lo, hi);
    let mut t = start(lo, hi, guess);
    let mut evaluations = 0;
    // Each step at least halves the bracket or is a Newton step inside it: 200 bounds any
    // bracket of doubles.
    for _ in 0..200 {
        let (f, df) = g(t);
        evaluations += 1;
        if f == 0.0 {
            return (t, evaluations);
        }
        shrink(&mut lo, &mut hi, t, f);
        let (next, done) = safeguarded_newton(t, f, df, (lo, hi), tol);
        if done {
            return (next, evaluations);
        }
        t = next;
    }
    (t, evaluations)
}

/// Where refinement starts: `guess` if it lies inside `(lo, hi)`, else the middle.
fn start(lo: f64, hi: f64, guess: f64) -> f64 {
    if guess > lo && guess < hi {
        guess
    } else {
        0.5 * (lo + hi)
    }
}

/// Moves the end of the bracket on `f`'s side to `t` (`f < 0` below the root).
fn shrink(lo: &mut f64, hi: &mut f64, t: f64, f: f64) {
    if f < 0.0 {
        *lo = t;
    } else {
        *hi = t;
    }
}

/// The Newton step from `t`, kept inside the bracket `(lo, hi)` (bisection when it would leave
/// it, as 000 §III.A demands of Newton results), and whether it ends the refinement: the step
/// below `tol` plus round-off of `t`, or the bracket below `tol`; the point is then clamped
/// into the bracket.
fn safeguarded_newton(t: f64, f: f64, df: f64, (lo, hi): (f64, f64), tol: f64) -> (f64, bool) {
    let newton = t - f / df;
    let next = if df > 0.0 && newton > lo && newton < hi {
        newton
    } else {
        0.5 * (lo + hi)
    };
    if (next - t).abs() <= tol + 2.0 * f64::EPSILON * t.abs() || hi - lo <= tol {
        (next.clamp(lo, hi), true)
    } else {
        (next, false)
    }
}

/// [`monotone_root`] for a `g` whose second derivative and a bound on its third are known:
/// `g` returns `(g(t), g'(t), g''(t), c₃)` with `|g'''| ≤ c₃` near `t` (a Taylor model's data).
/// Each step goes to the nearer root of the local quadratic (cubic convergence), and the
/// iteration stops as soon as that quadratic's own error is below `tol`: at the step `δ` it
/// misses `g` by at most `c₃|δ|³/6`, which moves its root by at most that over the smallest
/// slope between (doubled here, for the bound's change over the step). From a guess some fs
/// off at molecular speeds two evaluations suffice where Newton needs three or four (the last
/// only to see that its step has become small). A quadratic without a real root, or a step that
/// would leave the bracket, falls back on Newton and then bisection, as in [`monotone_root`].
///
/// Returns the root and the number of evaluations of `g`.
pub fn taylor_root<G: FnMut(f64) -> (f64, f64, f64, f64)>(
    mut g: G,
    lo: f64,
    hi: f64,
    guess: f64,
    tol: f64,
) -> (f64, u32) {
    let (mut lo, mut hi) = (lo, hi);
    let mut t = start(lo, hi, guess);
    let mut evaluations = 0;
    for _ in 0..200 {
        let (f, df, ddf, c3) = g(t);
        evaluations += 1;
        if f == 0.0 {
            return (t, evaluations);
        }
        shrink(&mut lo, &mut hi, t, f);
        let floor = tol + 2.0 * f64::EPSILON * t.abs();
        // The nearer root of f + f'δ + f''δ²/2, cancellation-free: δ = −2f / (f' + √(f'² − 2ff'')).
        let disc = df * df - 2.0 * f * ddf;
        if df > 0.0 && disc >= 0.0 {
            let d = -2.0 * f / (df + disc.sqrt());
            let next = t + d;
            if next > lo && next < hi {
                let slope = df.min(df + ddf * d);
                let bound = c3 * d.abs().powi(3);
                if (slope > 0.0 && bound <= 3.0 * slope * floor) || d.abs() <= floor {
                    return (next, evaluations);
                }
                t = next;
                continue;
            }
        }
        let (next, done) = safeguarded_newton(t, f, df, (lo, hi), tol);
        if done {
            return (next, evaluations);
        }
        t = next;
    }
    (t, evaluations)
}

#[cfg(test)]
mod monotone_tests {
    use super::{monotone_root, taylor_root};
    use proptest::prelude::*;

    proptest! {
        /// Any strictly increasing function with a sign change in the bracket: the root is
        /// found to the tolerance, from any guess, in few evaluations when Newton applies.
        #[test]
        fn finds_the_one_root(
            root in -5.0f64..5.0,
            a in 0.1f64..10.0,
            c in 0.0f64..3.0,
            left in 1e-6f64..4.0,
            right in 1e-6f64..4.0,
            guess in -10.0f64..10.0,
        ) {
            // g = a·(t − r) + c·(t − r)³: increasing, one root at r.
            let g = |t: f64| {
                let d = t - root;
                (a * d + c * d * d * d, a + 3.0 * c * d * d)
            };
            let (t, n) = monotone_root(g, root - left, root + right, guess, 1e-12);
            prop_assert!((t - root).abs() <= 1e-9, "{t} against {root}");
            prop_assert!(n <= 200);
        }
    }

    proptest! {
        /// The same functions with their third-derivative bound: the root to the tolerance.
        #[test]
        fn taylor_root_finds_the_one_root(
            root in -5.0f64..5.0,
            a in 0.1f64..10.0,
            c in 0.0f64..3.0,
            left in 1e-6f64..4.0,
            right in 1e-6f64..4.0,
            guess in -10.0f64..10.0,
        ) {
            let g = |t: f64| {
                let d = t - root;
                (a * d + c * d * d * d, a + 3.0 * c * d * d, 6.0 * c * d, 6.0 * c)
            };
            let (t, n) = taylor_root(g, root - left, root + right, guess, 1e-12);
            prop_assert!((t - root).abs() <= 1e-9, "{t} against {root}");
            prop_assert!(n <= 200);
        }
    }

    #[test]
    fn taylor_root_stops_on_its_error_bound() {
        // e^t − 2 with |g'''| ≤ e on [0, 1]: from 0.7 (0.007 off) the quadratic step lands
        // within 1e-7, the next within round-off, and the bound says so: two evaluations,
        // where Newton takes more.
        let e = 1f64.exp();
        let g = |t: f64| (t.exp() - 2.0, t.exp(), t.exp(), e);
        let (t, n) = taylor_root(g, 0.0, 1.0, 0.7, 1e-14);
        assert!((t - 2f64.ln()).abs() < 1e-14);
        assert_eq!(n, 2);
        let (_, m) = monotone_root(|t: f64| (t.exp() - 2.0, t.exp()), 0.0, 1.0, 0.7, 1e-14);
        assert!(m > n, "Newton {m}, quadratic {n}");
        // The bound is what stops it: with c₃ = 0 (wrong) the first quadratic root is taken
        // as exact, and it is 1e-7 off.
        let wrong = |t: f64| (t.exp() - 2.0, t.exp(), t.exp(), 0.0);
        let (t0, n0) = taylor_root(wrong, 0.0, 1.0, 0.7, 1e-14);
        assert_eq!(n0, 1);
        assert!((t0 - 2f64.ln()).abs() > 1e-9);
    }

    #[test]
    fn newton_from_a_close_guess_takes_a_few_steps() {
        let g = |t: f64| (t.exp() - 2.0, t.exp());
        let (t, n) = monotone_root(g, 0.0, 1.0, 0.7, 1e-14);
        assert!((t - 2f64.ln()).abs() < 1e-14);
        assert!(n <= 4, "{n} evaluations");
    }

    #[test]
    fn a_flat_stretch_falls_back_on_bisection() {
        // g' = 0 on the left part: Newton cannot step, bisection still converges.
        let g = |t: f64| {
            if t < 0.5 {
                (-1.0, 0.0)
            } else {
                (t - 0.75, 1.0)
            }
        };
        let (t, _) = monotone_root(g, 0.0, 1.0, 0.1, 1e-13);
        assert!((t - 0.75).abs() < 1e-12);
    }
}
