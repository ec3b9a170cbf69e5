//! The adaptive search with cubic Hermite interpolation of 003 §III (Fig. 2).
//!
//! From the last sample `(t, f, f')` the linear extrapolation `f + f' τ` (003 §III) predicts
//! when `f` reaches zero; the next sample goes a little beyond it, at `t + τ' + δt`, so that a
//! sign change is likely to be bracketed, but never further than the maximum step `Δt`, and at
//! `t + Δt` when `f` moves away from zero. Between every two samples the cubic Hermite
//! interpolant (003 Eqs. 13–15) predicts the extrema; one that turns towards zero is searched
//! and decides whether a grazing event hides there (see [`grazing`](crate::grazing)); a sign
//! change is refined once bracketed.
//!
//! Where 000's grid has to be fine everywhere to catch the rare rapid change, this search pays
//! for resolution only where the function comes near zero or turns: the maximum step only has
//! to be short against the time over which `f` itself changes shape.

use crate::error::{SearchError, positive};
use crate::grazing::{Limits, Verdict, examine};
use crate::indicator::{Counted, Crossing, Indicator, Sample, Side};
use crate::search::{self, Method, Report, SearchState, Stepper};
use crate::tolerance::Tolerances;

/// Default overshoot `δt` past the extrapolated root, as a fraction of the maximum step.
pub const DEFAULT_OVERSHOOT: f64 = 1.0 / 8.0;

/// Adaptive search with cubic Hermite interpolation (003 §III).
///
/// ```
/// use root_search::{Adaptive, Crossing, Grid, Method};
///
/// // A dip 0.1 % below zero, 0.05 wide, between samples 0.04 apart.
/// let mut f = |t: f64| {
///     let x = (t - 0.5137) / 0.05;
///     let g = 1.001 * (-x * x).exp();
///     (1.0 - g, 2.0 * x / 0.05 * g)
/// };
/// let root = 0.5137 - 0.05 * 1.001f64.ln().sqrt();
///
/// let report = Adaptive::new(0.04)?.start(&mut f, 0.0, 1.0, Crossing::Falling, f64::INFINITY)?;
/// assert!((report.root().unwrap() - root).abs() < 1e-10);
///
/// // A grid of the same step without grazing detection steps over it.
/// let grid = Grid::new(0.04, 0.0)?.start(&mut f, 0.0, 1.0, Crossing::Falling, f64::INFINITY)?;
/// assert_eq!(grid.root(), None);
/// # Ok::<(), root_search::SearchError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    max_step: f64,
    overshoot: f64,
    tol: Tolerances,
}

impl Adaptive {
    /// A search with maximum step `max_step`, overshoot [`DEFAULT_OVERSHOOT`]` · max_step` and
    /// tolerances [`Tolerances::relative_to`]`(max_step)`.
    ///
    /// # Errors
    /// [`SearchError::BadSetting`] if `max_step` is not finite and positive.
    pub fn new(max_step: f64) -> Result<Self, SearchError> {
        positive("maximum step", max_step)?;
        Ok(Self {
            max_step,
            overshoot: DEFAULT_OVERSHOOT * max_step,
            tol: Tolerances::relative_to(max_step),
        })
    }

    /// The same search with another maximum step, everything else kept: for the small random
    /// jitter a simulator puts on the step so that virtual events do not coincide (003 §V.A).
    ///
    /// # Errors
    /// [`SearchError::BadSetting`] if `max_step` is not finite and positive.
    pub fn with_max_step(self, max_step: f64) -> Result<Self, SearchError> {
        Ok(Self {
            max_step: positive("maximum step", max_step)?,
            ..self
        })
    }

    /// The same search with overshoot `δt` past the extrapolated root (003 §III).
    ///
    /// # Errors
    /// [`SearchError::BadSetting`] if `overshoot` is not finite and positive.
    pub fn with_overshoot(self, overshoot: f64) -> Result<Self, SearchError> {
        Ok(Self {
            overshoot: positive("overshoot", overshoot)?,
            ..self
        })
    }

    /// The same search with other tolerances.
    ///
    /// # Errors
    /// See [`Tolerances::validated`].
    pub fn with_tolerances(self, tol: Tolerances) -> Result<Self, SearchError> {
        Ok(Self {
            tol: tol.validated()?,
            ..self
        })
    }

    /// The maximum step.
    pub fn max_step(&self) -> f64 {
        self.max_step
    }

    /// The overshoot past the extrapolated root.
    pub fn overshoot(&self) -> f64 {
        self.overshoot
    }

    /// The tolerances.
    pub fn tolerances(&self) -> Tolerances {
        self.tol
    }
}

impl Stepper for Adaptive {
    fn limits(&self, seek: Crossing) -> Limits {
        Limits {
            root_tol: self.tol.root,
            extremum_tol: self.tol.extremum,
            touch: self.tol.touch,
            seek,
        }
    }

    #[inline]
    fn next_time(&self, p: &Sample, side: Side) -> f64 {
        // 003 §III: solve the linear extrapolation f + f' τ = 0 when it heads for zero.
        let heading = match side {
            Side::Pos => p.df < 0.0,
            Side::Neg => p.df > 0.0,
        };
        let step = if heading {
            (p.f / p.df).abs() + self.overshoot
        } else {
            self.max_step
        };
        p.t + step.min(self.max_step)
    }

    #[inline]
    fn examine<I: Indicator + ?Sized>(
        &self,
        ind: &mut Counted<'_, I>,
        p: Sample,
        q: Sample,
        side: Side,
        lim: &Limits,
    ) -> Result<Verdict, SearchError> {
        examine(ind, p, q, side, lim)
    }
}

impl Method for Adaptive {
    fn start<I: Indicator + ?Sized>(
        &self,
        f: &mut I,
        t0: f64,
        end: f64,
        seek: Crossing,
        window: f64,
    ) -> Result<Report, SearchError> {
        search::start(self, f, t0, end, seek, window)
    }

    fn resume<I: Indicator + ?Sized>(
        &self,
        f: &mut I,
        state: SearchState,
        window: f64,
    ) -> Result<Report, SearchError> {
        search::resume(self, f, state, window)
    }
}
