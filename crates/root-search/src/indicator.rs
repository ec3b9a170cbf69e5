//! The indicator function `f(t)` and the direction of its crossings.
//!
//! In an event-driven simulation of terraced potentials, a pair of bodies changes terrace when
//! its smooth potential `U(t)` reaches a terrace value `U_k`: the event is a root of
//! `f(t) = U(t) − U_k` (003 Eq. 8). Its time derivative comes almost for free from the forces
//! and torques already computed for `U` (003 Eq. 12), so an indicator always returns both.

use crate::SearchError;

/// A smooth function of time whose earliest root is sought, evaluated with its derivative.
///
/// Searches are generic over it (static dispatch), so an implementation is inlined into the
/// search loop. Closures `FnMut(f64) -> (f64, f64)` are indicators.
pub trait Indicator {
    /// `(f(t), f'(t))`.
    ///
    /// Both must be finite: a search stops with [`SearchError::NonFiniteIndicator`] otherwise.
    fn eval(&mut self, t: f64) -> (f64, f64);
}

impl<F: FnMut(f64) -> (f64, f64)> Indicator for F {
    #[inline(always)]
    fn eval(&mut self, t: f64) -> (f64, f64) {
        self(t)
    }
}

/// Which crossings of zero a search looks for.
///
/// After an event at `t0` where `f` crossed zero, `f(t0)` is zero up to round-off and may sit
/// on either side of it. Searching for a *direction* makes that harmless: a spurious crossing
/// right after `t0` goes the wrong way and is skipped (see the crate documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Crossing {
    /// `f` goes from negative to zero or above (`U` climbs onto terrace `U_k`).
    Rising,
    /// `f` goes from positive to zero or below (`U` drops below `U_k`).
    Falling,
    /// Either of the two.
    Either,
}

/// The direction of a crossing that was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Direction {
    /// From negative to non-negative.
    Rising,
    /// From positive to non-positive.
    Falling,
}

impl Crossing {
    /// Whether a crossing in direction `d` is one this search looks for.
    #[inline]
    pub fn accepts(self, d: Direction) -> bool {
        match self {
            Crossing::Either => true,
            Crossing::Rising => d == Direction::Rising,
            Crossing::Falling => d == Direction::Falling,
        }
    }
}

/// The side of zero the function is on just after a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Side {
    Pos,
    Neg,
}

impl Side {
    /// The side of a sample `(f, f')`: the sign of `f`, or where `f'` takes it when `f` is zero
    /// (a function that is zero at `t` is on the side it moves to), or `prev` when both vanish.
    #[inline]
    pub(crate) fn of(f: f64, df: f64, prev: Side) -> Side {
        if f > 0.0 {
            Side::Pos
        } else if f < 0.0 {
            Side::Neg
        } else if df > 0.0 {
            Side::Pos
        } else if df < 0.0 {
            Side::Neg
        } else {
            prev
        }
    }

    /// +1 or −1.
    #[inline]
    pub(crate) fn sign(self) -> f64 {
        match self {
            Side::Pos => 1.0,
            Side::Neg => -1.0,
        }
    }

    /// The direction of a crossing that leaves this side.
    #[inline]
    pub(crate) fn leaving(self) -> Direction {
        match self {
            Side::Pos => Direction::Falling,
            Side::Neg => Direction::Rising,
        }
    }

    #[inline]
    pub(crate) fn flip(self) -> Side {
        match self {
            Side::Pos => Side::Neg,
            Side::Neg => Side::Pos,
        }
    }
}

/// One evaluation of the indicator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Sample {
    pub(crate) t: f64,
    pub(crate) f: f64,
    pub(crate) df: f64,
}

impl Sample {
    /// Whether `f` is strictly on `side` here (not zero, not across it): only a start on zero,
    /// or within the touch margin of it, is not.
    #[inline]
    pub(crate) fn strictly_on(&self, side: Side) -> bool {
        side.sign() * self.f > 0.0
    }
}

/// An indicator together with the count of its evaluations and the finiteness check every
/// evaluation must pass (a NaN must never steer a search silently).
pub(crate) struct Counted<'a, I: ?Sized> {
    inner: &'a mut I,
    pub(crate) evals: u32,
}

impl<'a, I: Indicator + ?Sized> Counted<'a, I> {
    pub(crate) fn new(inner: &'a mut I) -> Self {
        Self { inner, evals: 0 }
    }

    #[inline(always)]
    pub(crate) fn at(&mut self, t: f64) -> Result<Sample, SearchError> {
        let (f, df) = self.inner.eval(t);
        self.evals += 1;
        if f.is_finite() && df.is_finite() {
            Ok(Sample { t, f, df })
        } else {
            Err(SearchError::NonFiniteIndicator { t, f, df })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn side_of_zero_follows_the_derivative_then_the_previous_side() {
        assert_eq!(Side::of(1e-300, -5.0, Side::Neg), Side::Pos);
        assert_eq!(Side::of(-0.0, -5.0, Side::Pos), Side::Neg);
        assert_eq!(Side::of(0.0, 2.0, Side::Neg), Side::Pos);
        assert_eq!(Side::of(0.0, 0.0, Side::Neg), Side::Neg);
        assert_eq!(Side::of(0.0, 0.0, Side::Pos), Side::Pos);
    }

    #[test]
    fn crossing_filter() {
        assert!(Crossing::Either.accepts(Direction::Rising));
        assert!(Crossing::Either.accepts(Direction::Falling));
        assert!(Crossing::Rising.accepts(Direction::Rising));
        assert!(!Crossing::Rising.accepts(Direction::Falling));
        assert!(!Crossing::Falling.accepts(Direction::Rising));
        assert_eq!(Side::Pos.leaving(), Direction::Falling);
        assert_eq!(Side::Neg.flip(), Side::Pos);
    }

    #[test]
    fn counted_rejects_nan_and_counts() {
        let mut f = |t: f64| if t < 1.0 { (t, 1.0) } else { (f64::NAN, 1.0) };
        let mut c = Counted::new(&mut f);
        assert!(c.at(0.5).is_ok());
        let e = c.at(2.0).unwrap_err();
        assert!(matches!(e, SearchError::NonFiniteIndicator { t, .. } if t == 2.0));
        assert_eq!(c.evals, 2);
    }
}
