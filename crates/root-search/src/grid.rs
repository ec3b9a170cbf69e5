//! The uniform grid search of 000 §III.A.
//!
//! The bracket is sampled every `Δt`. A sign change between two grid points is refined by
//! Newton–Raphson with its safeguard ([`refine`](crate::refine)). Where `f` keeps its sign but
//! `f'` turns towards zero and `|f|` at one of the two grid points is below a threshold, the
//! extremum in between is searched and decides whether a grazing event hides there. The
//! threshold is the method's second accuracy knob: 000 sets it by trial and error until missed
//! grazing events are rare enough. Intervals holding two extrema (an `f'` that ends with the
//! sign it started with) are not examined: that is what a step too coarse for the function
//! misses, and what the adaptive search was made for.

use crate::error::{SearchError, positive};
use crate::grazing::{Limits, Verdict, examine, touches};
use crate::indicator::{Counted, Crossing, Indicator, Sample, Side};
use crate::refine::refine;
use crate::search::{self, Method, Report, SearchState, Stepper};
use crate::tolerance::Tolerances;

/// Uniform grid search with grazing detection below a threshold (000 §III.A).
///
/// ```
/// use root_search::{Crossing, Grid, Method};
///
/// // cos t falls through zero at π/2.
/// let grid = Grid::new(0.1, 0.05)?;
/// let report = grid.start(&mut |t: f64| (t.cos(), -t.sin()), 0.0, 3.0, Crossing::Falling, f64::INFINITY)?;
/// assert!((report.root().unwrap() - std::f64::consts::FRAC_PI_2).abs() < 1e-10);
/// # Ok::<(), root_search::SearchError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    step: f64,
    threshold: f64,
    tol: Tolerances,
}

impl Grid {
    /// A grid of spacing `step`; extrema are examined where `|f|` at a grid point is below
    /// `threshold` (0 turns grazing detection off, `f64::INFINITY` examines every extremum).
    /// Tolerances default to [`Tolerances::relative_to`]`(step)`.
    ///
    /// # Errors
    /// [`SearchError::BadSetting`] if `step` is not finite and positive or `threshold` is
    /// negative or NaN.
    pub fn new(step: f64, threshold: f64) -> Result<Self, SearchError> {
        positive("grid step", step)?;
        if threshold.is_nan() || threshold < 0.0 {
            return Err(SearchError::BadSetting {
                name: "grazing threshold",
                value: threshold,
                why: ">= 0",
            });
        }
        Ok(Self {
            step,
            threshold,
            tol: Tolerances::relative_to(step),
        })
    }

    /// The same grid with other tolerances.
    ///
    /// # Errors
    /// See [`Tolerances::validated`].
    pub fn with_tolerances(self, tol: Tolerances) -> Result<Self, SearchError> {
        Ok(Self {
            tol: tol.validated()?,
            ..self
        })
    }

    /// The grid spacing.
    pub fn step(&self) -> f64 {
        self.step
    }

    /// The grazing threshold on `|f|`.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// The tolerances.
    pub fn tolerances(&self) -> Tolerances {
        self.tol
    }
}

impl Stepper for Grid {
    fn limits(&self, seek: Crossing) -> Limits {
        Limits {
            root_tol: self.tol.root,
            extremum_tol: self.tol.extremum,
            touch: self.tol.touch,
            seek,
        }
    }

    #[inline]
    fn next_time(&self, p: &Sample, _side: Side) -> f64 {
        p.t + self.step
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
        if !p.strictly_on(side) {
            // A start at zero: only the interpolant can tell where f first goes.
            return examine(ind, p, q, side, lim);
        }
        let q_side = Side::of(q.f, q.df, side);
        if q_side != side {
            let dir = side.leaving();
            return Ok(if lim.seek.accepts(dir) {
                Verdict::Root(refine(ind, p, q, side, lim.root_tol)?, dir)
            } else {
                Verdict::Passed(q_side)
            });
        }
        if touches(&q, side, lim) {
            return Ok(Verdict::Root(q.t, side.leaving()));
        }
        // f' turns towards zero: a minimum above zero or a maximum below it.
        let turns = match side {
            Side::Pos => p.df < 0.0 && q.df > 0.0,
            Side::Neg => p.df > 0.0 && q.df < 0.0,
        };
        if turns && p.f.abs().min(q.f.abs()) < self.threshold {
            return examine(ind, p, q, side, lim);
        }
        Ok(Verdict::Passed(side))
    }
}

impl Method for Grid {
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
