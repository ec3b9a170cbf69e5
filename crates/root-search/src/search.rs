//! A search from start to finish: the bracket, the window, and the state a virtual event keeps.
//!
//! Both methods share one loop: from the last sample, the method picks the next time, the
//! indicator is evaluated there, and the interval between the two samples is examined for the
//! earliest accepted crossing. The loop ends at a root, at the bracket end (no root), or when
//! the next step would leave the call's window: then it returns the last sample as a
//! [`SearchState`], from which [`Method::resume`] continues exactly as if it had never stopped
//! (000 §III.B: the simulator keeps it in a *virtual event* at [`SearchState::time`], which is
//! only resumed if neither body has had an event before).

use crate::error::SearchError;
use crate::grazing::{Limits, Verdict};
use crate::indicator::{Counted, Crossing, Direction, Indicator, Sample, Side};

/// What a search call returns: its outcome and how many times it evaluated the indicator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Report {
    /// Root, no root, or a suspended search.
    pub outcome: Outcome,
    /// Evaluations of the indicator made by this call.
    pub evals: u32,
}

impl Report {
    /// The root's time, if one was found.
    pub fn root(&self) -> Option<f64> {
        match self.outcome {
            Outcome::Root(r) => Some(r.t),
            _ => None,
        }
    }
}

/// How a search call ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// The earliest accepted crossing after the start.
    Root(Root),
    /// No accepted crossing up to and including the bracket end.
    NoRoot,
    /// The window ran out first; resume from this state to continue.
    Suspended(SearchState),
}

/// A crossing that was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Root {
    /// When `f` crosses (or touches) zero, to within the root tolerance.
    pub t: f64,
    /// Which way it crosses.
    pub direction: Direction,
}

/// Where a suspended search stands: the last sample, the bracket end and the requested
/// direction (40 bytes, `Copy`: it fits in an event payload).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchState {
    t: f64,
    f: f64,
    df: f64,
    end: f64,
    side: Side,
    seek: Crossing,
}

impl SearchState {
    /// Time of the last sample: when the virtual event is due.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// `f` at [`time`](Self::time).
    pub fn value(&self) -> f64 {
        self.f
    }

    /// `f'` at [`time`](Self::time).
    pub fn slope(&self) -> f64 {
        self.df
    }

    /// End of the bracket being searched.
    pub fn end(&self) -> f64 {
        self.end
    }

    /// The crossings being looked for.
    pub fn seek(&self) -> Crossing {
        self.seek
    }

    /// The same state with the time origin moved to `origin` (times become `t − origin`), for
    /// simulators that re-base their clock to keep long runs precise.
    ///
    /// # Errors
    /// [`SearchError::BadTime`] if `origin` is not finite.
    pub fn rebased(self, origin: f64) -> Result<Self, SearchError> {
        if !origin.is_finite() {
            return Err(SearchError::BadTime {
                what: "new time origin",
                value: origin,
            });
        }
        Ok(Self {
            t: self.t - origin,
            end: self.end - origin,
            ..self
        })
    }
}

/// A root-search method: start a search, or resume a suspended one.
///
/// Generic over the indicator, so a search is compiled for each indicator type and the
/// evaluation is inlined (no dynamic dispatch on the hot path).
pub trait Method {
    /// Searches `(t0, end]` for the earliest crossing accepted by `seek`, evaluating `f` first
    /// at `t0`. `end` may be `f64::INFINITY` if `window` is finite.
    ///
    /// `window` limits the call: it always takes one step past `t0` and then stops before any
    /// step that would end after `t0 + window`, returning [`Outcome::Suspended`]. Pass
    /// `f64::INFINITY` to search to the end in one call.
    ///
    /// A start at zero (`|f(t0)|` within the touch tolerance, as after an event) is on the side
    /// `f'(t0)` points to, so the event just executed is not found again.
    ///
    /// # Errors
    /// A NaN or infinite `t0`, a NaN `end`, `end < t0`, a NaN or non-positive `window`, an
    /// unbounded search, a non-finite indicator value, or a step too small to change `t`.
    fn start<I: Indicator + ?Sized>(
        &self,
        f: &mut I,
        t0: f64,
        end: f64,
        seek: Crossing,
        window: f64,
    ) -> Result<Report, SearchError>;

    /// Continues a suspended search from `state` with a new `window`, without evaluating `f`
    /// at the state's time again. With the same method and settings, the sequence of samples
    /// and the root are bit for bit those of a search that was never suspended.
    ///
    /// # Errors
    /// As for [`start`](Self::start).
    fn resume<I: Indicator + ?Sized>(
        &self,
        f: &mut I,
        state: SearchState,
        window: f64,
    ) -> Result<Report, SearchError>;
}

/// What distinguishes the methods: where the next sample goes and how an interval is examined.
pub(crate) trait Stepper {
    /// The tolerances and direction for [`examine`](Self::examine).
    fn limits(&self, seek: Crossing) -> Limits;

    /// The next sample time after `p` (before clipping at the bracket end).
    fn next_time(&self, p: &Sample, side: Side) -> f64;

    /// The earliest accepted crossing in `(p.t, q.t]`.
    fn examine<I: Indicator + ?Sized>(
        &self,
        ind: &mut Counted<'_, I>,
        p: Sample,
        q: Sample,
        side: Side,
        lim: &Limits,
    ) -> Result<Verdict, SearchError>;
}

fn check_window(window: f64) -> Result<(), SearchError> {
    if window > 0.0 {
        Ok(())
    } else {
        Err(SearchError::BadTime {
            what: "window",
            value: window,
        })
    }
}

/// [`Method::start`] for any stepper.
pub(crate) fn start<S: Stepper, I: Indicator + ?Sized>(
    s: &S,
    ind: &mut I,
    t0: f64,
    end: f64,
    seek: Crossing,
    window: f64,
) -> Result<Report, SearchError> {
    if !t0.is_finite() {
        return Err(SearchError::BadTime {
            what: "start",
            value: t0,
        });
    }
    if end.is_nan() {
        return Err(SearchError::BadTime {
            what: "end",
            value: end,
        });
    }
    if end < t0 {
        return Err(SearchError::ReversedBracket { start: t0, end });
    }
    check_window(window)?;
    if end == f64::INFINITY && window == f64::INFINITY {
        return Err(SearchError::Unbounded);
    }
    if end == t0 {
        return Ok(Report {
            outcome: Outcome::NoRoot,
            evals: 0,
        });
    }
    let mut c = Counted::new(ind);
    let p = c.at(t0)?;
    // Where neither f nor f' says which way f goes, assume the side from which a crossing
    // would be accepted is *not* where it is: a crossing right at t0 is then never reported.
    let fallback = match seek {
        Crossing::Falling => Side::Neg,
        Crossing::Rising | Crossing::Either => Side::Pos,
    };
    // Within the touch margin, f(t0) is zero as far as the search can tell (the event just
    // executed, up to round-off): f' alone says where f goes.
    let at_zero = p.f.abs() <= s.limits(seek).touch;
    let side = Side::of(if at_zero { 0.0 } else { p.f }, p.df, fallback);
    run(s, &mut c, p, side, end, seek, window)
}

/// [`Method::resume`] for any stepper.
pub(crate) fn resume<S: Stepper, I: Indicator + ?Sized>(
    s: &S,
    ind: &mut I,
    state: SearchState,
    window: f64,
) -> Result<Report, SearchError> {
    check_window(window)?;
    if state.end == f64::INFINITY && window == f64::INFINITY {
        return Err(SearchError::Unbounded);
    }
    if !state.t.is_finite() || state.end.is_nan() || state.end < state.t {
        return Err(SearchError::ReversedBracket {
            start: state.t,
            end: state.end,
        });
    }
    let p = Sample {
        t: state.t,
        f: state.f,
        df: state.df,
    };
    let mut c = Counted::new(ind);
    run(s, &mut c, p, state.side, state.end, state.seek, window)
}

fn run<S: Stepper, I: Indicator + ?Sized>(
    s: &S,
    c: &mut Counted<'_, I>,
    mut p: Sample,
    mut side: Side,
    end: f64,
    seek: Crossing,
    window: f64,
) -> Result<Report, SearchError> {
    let lim = s.limits(seek);
    let limit = p.t + window;
    let mut first = true;
    loop {
        if p.t >= end {
            return Ok(Report {
                outcome: Outcome::NoRoot,
                evals: c.evals,
            });
        }
        let t = s.next_time(&p, side).min(end);
        if t.is_nan() || t <= p.t {
            return Err(SearchError::StepBelowResolution {
                t: p.t,
                step: t - p.t,
            });
        }
        if !first && t > limit {
            return Ok(Report {
                outcome: Outcome::Suspended(SearchState {
                    t: p.t,
                    f: p.f,
                    df: p.df,
                    end,
                    side,
                    seek,
                }),
                evals: c.evals,
            });
        }
        first = false;
        let q = c.at(t)?;
        match s.examine(c, p, q, side, &lim)? {
            Verdict::Root(t, direction) => {
                return Ok(Report {
                    outcome: Outcome::Root(Root { t, direction }),
                    evals: c.evals,
                });
            }
            Verdict::Passed(next) => side = next,
        }
        p = q;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_fits_an_event_payload() {
        assert!(std::mem::size_of::<SearchState>() <= 40);
    }
}
