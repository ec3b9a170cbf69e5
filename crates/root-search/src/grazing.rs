//! Grazing events: the earliest crossing inside one interval between two samples.
//!
//! Two samples on the same side of zero do not prove that `f` stayed there: it may dip across
//! zero and back between them (a *grazing* event, 000 §III.A). Near such a dip `f` has an
//! extremum, so both seeds look for extrema and decide by the sign of `f` there: 000 when `f'`
//! changes sign between grid points and `|f|` is below a threshold, 003 §III wherever the cubic
//! Hermite interpolant of the two samples (003 Eqs. 13–15) predicts an extremum.
//!
//! [`examine`] does this for both methods. It reads the interpolant of the interval:
//!
//! - no predicted extremum: `f` is taken as monotone; a sign change is one crossing, refined by
//!   [`refine`](crate::refine) if it goes the requested way;
//! - a predicted extremum that turns *towards* zero (a minimum above zero, a maximum below):
//!   the interval is split there with one evaluation and both halves are examined in time order.
//!   This is an extremum search guided by the interpolant (it uses `f'` as well as `f`, in the
//!   spirit of Brent's minimiser with derivatives), safeguarded by keeping every split at least
//!   a tenth of the interval away from its ends;
//! - a sign change with predicted extrema: split at the first one, so the refined bracket holds
//!   the *earliest* crossing only.
//!
//! The extremum search stops as soon as the sign of the extremum is settled. A sample beyond
//! zero brackets a root. Where the interpolant is convex over an interval that brackets a
//! minimum (`f'` from negative to positive), the tangents of `f` at the two ends lie below a
//! convex `f`, so their intersection is a lower bound of the minimum: when it is above zero
//! (by more than `touch`) the dip is ruled out without another evaluation; a maximum below zero
//! likewise. With one end of the bracket at a distance `δ` from a minimum of curvature `2k` and
//! the other at `H`, the bound is `f_min − kδH`, which the splits drive to `f_min` fast (each
//! split near an end shortens the bracket tenfold). Otherwise the search goes on until the
//! interval is narrower than the extremum tolerance; an extremum that ends within `touch` of
//! zero counts as a root (a double root, `f` touching zero).

use crate::SearchError;
use crate::hermite::{Extremum, Hermite};
use crate::indicator::{Counted, Crossing, Direction, Indicator, Sample, Side};
use crate::refine::refine;

/// Splits stay this fraction of the interval away from its ends, so every split removes at
/// least that much and the search cannot stall at an end.
const SPLIT_MARGIN: f64 = 0.1;
/// Nested splits pending at once; at 10 % shrinkage per level this is far below any tolerance.
const DEPTH: usize = 48;
/// A predicted extremum farther from zero than this many times the variation of `f` over its
/// interval is not searched (see [`plan`]).
const RESOLVED: f64 = 8.0;
/// Splits allowed in one call of [`examine`]: a safety net against a function whose
/// interpolants keep predicting extrema near zero; past it the interval counts as monotone.
const BUDGET: u32 = 400;

/// What the search settles for inside an interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Verdict {
    /// The earliest accepted crossing.
    Root(f64, Direction),
    /// No accepted crossing; the side `f` is on at the end of the interval.
    Passed(Side),
}

/// The tolerances and the requested direction, as [`examine`] needs them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    pub(crate) root_tol: f64,
    pub(crate) extremum_tol: f64,
    pub(crate) touch: f64,
    pub(crate) seek: Crossing,
}

/// The earliest accepted crossing in `(p.t, q.t]`, `f` being on `side` just after `p`.
pub(crate) fn examine<I: Indicator + ?Sized>(
    ind: &mut Counted<'_, I>,
    p: Sample,
    q: Sample,
    side: Side,
    lim: &Limits,
) -> Result<Verdict, SearchError> {
    // Right ends of the intervals still to examine, latest split on top; made on the first
    // split only, since most intervals need none and the array is not free to fill.
    let mut stack: Option<[Sample; DEPTH]> = None;
    let mut depth = 0;
    let mut splits = 0;
    let (mut a, mut b, mut side) = (p, q, side);
    loop {
        let b_side = Side::of(b.f, b.df, side);
        let h = b.t - a.t;
        let split = if h <= lim.extremum_tol || depth == DEPTH {
            if b_side == side
                && let Some(v) = tiny_interval(ind, &a, &b, side, lim)?
            {
                return Ok(v);
            }
            None
        } else {
            plan(&a, &b, side, b_side, lim)
        };
        if let Some(t) = split.filter(|_| splits < BUDGET) {
            splits += 1;
            let m = ind.at(t)?;
            stack.get_or_insert([q; DEPTH])[depth] = b;
            depth += 1;
            b = m;
            continue;
        }
        // f is monotone on [a, b] as far as the interpolant can tell.
        if b_side != side {
            let dir = side.leaving();
            // A start on zero whose f' promised `side` but whose f never got strictly there
            // within the extremum tolerance: it did not leave zero that way, so there is no
            // crossing to report, only the side it is really on.
            if lim.seek.accepts(dir) && a.strictly_on(side) {
                let t = refine(ind, a, b, side, lim.root_tol)?;
                return Ok(Verdict::Root(t, dir));
            }
            side = b_side;
        } else if touches(&b, side, lim) {
            return Ok(Verdict::Root(b.t, side.leaving()));
        }
        if depth == 0 {
            return Ok(Verdict::Passed(side));
        }
        depth -= 1;
        a = b;
        b = stack.as_ref().map_or(q, |s| s[depth]);
    }
}

/// Whether sample `b`, on `side`, is a touch: within the touch margin of zero with `f'` turned
/// away from it (a sample that is merely close to zero on its way across is not one).
#[inline]
pub(crate) fn touches(b: &Sample, side: Side, lim: &Limits) -> bool {
    side.sign() * b.f <= lim.touch && side.sign() * b.df >= 0.0 && lim.seek.accepts(side.leaving())
}

/// Where to split `[a, b]`, or `None` when the interval can be treated as monotone.
fn plan(a: &Sample, b: &Sample, side: Side, b_side: Side, lim: &Limits) -> Option<f64> {
    let h = b.t - a.t;
    let clamp = |t: f64| t.clamp(a.t + SPLIT_MARGIN * h, b.t - SPLIT_MARGIN * h);
    let cubic = Hermite::new(a, b);
    if b_side != side {
        // One crossing or three: cut at the first extremum so the bracket keeps only the first.
        // A start at zero (or within the touch margin of it, on the far side) must first move
        // off it before a bracket exists.
        let (ext, n) = if cubic.may_turn() {
            cubic.extrema()
        } else {
            ([Extremum::NONE; 2], 0)
        };
        return if n > 0 {
            Some(clamp(ext[0].t))
        } else if !a.strictly_on(side) {
            Some(a.t + 0.5 * h)
        } else {
            None
        };
    }
    // Most steps end here: the interpolant is monotone.
    if !cubic.may_turn() {
        return None;
    }
    let toward_min = side == Side::Pos;
    let (rising, falling) = (a.df < 0.0 && b.df > 0.0, a.df > 0.0 && b.df < 0.0);
    if rising || falling {
        // Exactly one extremum inside, of known kind: one turning away from zero is harmless.
        if rising != toward_min {
            return None;
        }
        // It turns towards zero and the interpolant bends one way all along: the tangents at
        // the ends bound it (below a minimum, above a maximum) at no cost.
        if cubic.bends(toward_min) {
            let u = (b.f - a.f - b.df * h) / (a.df - b.df);
            let bound = a.f + a.df * u;
            if side.sign() * bound > lim.touch {
                return None;
            }
        }
    }
    // The same test as below on a cheap bound: the interpolant stays within `reach` of f(a).
    let s = side.sign();
    let reach = cubic.reach();
    let spread = reach + (a.f - b.f).abs();
    if s * a.f - reach - lim.touch > RESOLVED * spread {
        return None;
    }
    let (ext, n) = cubic.extrema();
    let toward = ext[..n].iter().find(|e| e.is_min == toward_min)?;
    // An extremum predicted far from zero compared with how much f varies over the interval
    // would need the interpolant to be wrong by many times that variation: a feature the step
    // does not resolve, which no sampling would see. (It also keeps round-off noise in the
    // slopes of a flat f from being chased as extrema.)
    let distance = s * toward.value - lim.touch;
    let variation = (s * a.f).min(s * b.f) - s * toward.value + (a.f - b.f).abs();
    if distance > RESOLVED * variation.max(0.0) {
        return None;
    }
    Some(clamp(toward.t))
}

/// The last look at an interval narrower than the extremum tolerance with both ends on one
/// side: an extremum the interpolant puts within `touch` of zero or beyond is evaluated.
fn tiny_interval<I: Indicator + ?Sized>(
    ind: &mut Counted<'_, I>,
    a: &Sample,
    b: &Sample,
    side: Side,
    lim: &Limits,
) -> Result<Option<Verdict>, SearchError> {
    let cubic = Hermite::new(a, b);
    let (ext, n) = cubic.extrema();
    let Some(e) = ext[..n].iter().find(|e| e.is_min == (side == Side::Pos)) else {
        return Ok(None);
    };
    if side.sign() * e.value > lim.touch {
        return Ok(None);
    }
    if !a.strictly_on(side) {
        return Ok(None);
    }
    let m = ind.at(e.t)?;
    let m_side = Side::of(m.f, m.df, side);
    if m_side != side {
        // Two crossings inside the interval; which one is wanted depends on the direction.
        let first = side.leaving();
        if lim.seek.accepts(first) {
            let t = refine(ind, *a, m, side, lim.root_tol)?;
            return Ok(Some(Verdict::Root(t, first)));
        }
        let t = if m.f == 0.0 {
            m.t
        } else {
            refine(ind, m, *b, m_side, lim.root_tol)?
        };
        return Ok(Some(Verdict::Root(t, m_side.leaving())));
    }
    // A touch needs a real extremum in the interval: f' turning from towards zero to away.
    let turns = side.sign() * a.df <= 0.0 && side.sign() * b.df >= 0.0;
    if turns && side.sign() * m.f <= lim.touch && lim.seek.accepts(side.leaving()) {
        return Ok(Some(Verdict::Root(m.t, side.leaving())));
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lim(seek: Crossing) -> Limits {
        Limits {
            root_tol: 1e-13,
            extremum_tol: 1e-10,
            touch: 0.0,
            seek,
        }
    }

    fn run(
        f: &mut impl FnMut(f64) -> (f64, f64),
        t0: f64,
        t1: f64,
        seek: Crossing,
    ) -> (Verdict, u32) {
        run_with(f, t0, t1, &lim(seek))
    }

    fn run_with(
        f: &mut impl FnMut(f64) -> (f64, f64),
        t0: f64,
        t1: f64,
        lim: &Limits,
    ) -> (Verdict, u32) {
        let (f0, d0) = f(t0);
        let (f1, d1) = f(t1);
        let p = Sample {
            t: t0,
            f: f0,
            df: d0,
        };
        let q = Sample {
            t: t1,
            f: f1,
            df: d1,
        };
        let side = Side::of(f0, d0, Side::Pos);
        let mut c = Counted::new(f);
        let v = examine(&mut c, p, q, side, lim).unwrap();
        (v, c.evals)
    }

    /// A Gaussian dip of depth `1 + d` below a level of 1: it crosses zero iff `d > 0`, at
    /// `c ± w √ln(1 + d)`.
    fn dip(c: f64, w: f64, d: f64) -> impl FnMut(f64) -> (f64, f64) {
        move |t: f64| {
            let x = (t - c) / w;
            let g = (1.0 + d) * (-x * x).exp();
            (1.0 - g, 2.0 * x / w * g)
        }
    }

    #[test]
    fn finds_a_dip_barely_below_zero_between_two_samples() {
        let (c, w, d) = (0.4137, 0.05, 1e-9);
        let (v, evals) = run(&mut dip(c, w, d), 0.35, 0.5, Crossing::Falling);
        let expect = c - w * d.ln_1p().sqrt();
        match v {
            Verdict::Root(t, Direction::Falling) => assert!((t - expect).abs() < 1e-11),
            other => panic!("{other:?}"),
        }
        assert!(evals < 30, "{evals}");
    }

    #[test]
    fn rules_out_a_dip_barely_above_zero_cheaply_when_far_and_surely_when_close() {
        let (v, _) = run(&mut dip(0.4137, 0.05, -1e-9), 0.35, 0.5, Crossing::Falling);
        assert_eq!(v, Verdict::Passed(Side::Pos));
        // A shallow dip far above zero costs very few evaluations.
        let (v, evals) = run(&mut dip(0.4137, 0.05, -0.5), 0.35, 0.5, Crossing::Falling);
        assert_eq!(v, Verdict::Passed(Side::Pos));
        assert!(evals <= 3, "{evals}");
    }

    #[test]
    fn wrong_direction_pair_yields_its_second_crossing() {
        // Below zero, a bump crossing above and back: a Falling search wants the way back.
        let (c, w, d) = (0.4137, 0.05, 1e-3);
        let mut bump = move |t: f64| {
            let (v, dv) = dip(c, w, d)(t);
            (-v, -dv)
        };
        let (v, _) = run(&mut bump, 0.35, 0.5, Crossing::Falling);
        let expect = c + w * d.ln_1p().sqrt();
        match v {
            Verdict::Root(t, Direction::Falling) => assert!((t - expect).abs() < 1e-11, "{t}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn three_crossings_in_one_interval_give_the_first() {
        let f = |t: f64| ((t - 1.0) * (t - 1.1) * (t - 1.2), 0.0);
        let mut g = |t: f64| (f(t).0, 3.0 * t * t - 6.6 * t + 3.62);
        let (v, _) = run(&mut g, 0.9, 1.3, Crossing::Either);
        match v {
            Verdict::Root(t, Direction::Rising) => assert!((t - 1.0).abs() < 1e-12, "{t}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn exact_tangency_counts_as_a_touch() {
        // f = 4 (t − 0.3)² touches zero at 0.3; with a round-off touch margin it is an event.
        let mut f = |t: f64| (4.0 * (t - 0.3) * (t - 0.3), 8.0 * (t - 0.3));
        let touchy = Limits {
            touch: 1e-12,
            ..lim(Crossing::Falling)
        };
        let (v, _) = run_with(&mut f, 0.0, 1.0, &touchy);
        match v {
            Verdict::Root(t, Direction::Falling) => assert!((t - 0.3).abs() < 1e-6, "{t}"),
            other => panic!("{other:?}"),
        }
        // Not a rising event.
        let rising = Limits {
            seek: Crossing::Rising,
            ..touchy
        };
        assert_eq!(
            run_with(&mut f, 0.0, 1.0, &rising).0,
            Verdict::Passed(Side::Pos)
        );
        // Without the margin, f must land exactly on zero to count: either outcome is
        // acceptable, but never a root elsewhere.
        match run(&mut f, 0.0, 1.0, Crossing::Falling).0 {
            Verdict::Root(t, _) => assert!((t - 0.3).abs() < 1e-6),
            Verdict::Passed(side) => assert_eq!(side, Side::Pos),
        }
    }
}
