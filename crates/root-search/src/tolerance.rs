//! The accuracy settings every search shares.

use crate::error::{SearchError, non_negative, positive};

/// How precisely roots and extrema are located, and when an extremum counts as touching zero.
///
/// Times are absolute, in the caller's unit. [`Tolerances::relative_to`] gives the defaults
/// scaled to a method's step, which is the natural time scale of a search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    /// A returned root lies within this time of the true crossing (plus round-off of `t`).
    pub root: f64,
    /// An extremum search stops once its interval is narrower than this (it usually stops far
    /// earlier, as soon as the sign of the extremum is settled).
    pub extremum: f64,
    /// An extremum within this distance of zero (in units of `f`) counts as a root: a double
    /// root where `f` touches zero and turns back. Zero counts only extrema that reach zero.
    pub touch: f64,
}

impl Tolerances {
    /// Root to `1e-10 step`, extrema to `1e-7 step`, no touch margin.
    pub fn relative_to(step: f64) -> Self {
        Self {
            root: 1e-10 * step,
            extremum: 1e-7 * step,
            touch: 0.0,
        }
    }

    /// Checks the settings.
    ///
    /// # Errors
    /// [`SearchError::BadSetting`] naming the first one that is not finite and positive
    /// (`touch` may be zero).
    pub fn validated(self) -> Result<Self, SearchError> {
        positive("root tolerance", self.root)?;
        positive("extremum tolerance", self.extremum)?;
        non_negative("touch tolerance", self.touch)?;
        Ok(self)
    }
}
