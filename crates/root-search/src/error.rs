//! Why a search or a setting was refused.

use std::fmt;

/// Everything a search or a configuration can refuse, one variant per kind of bad input.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SearchError {
    /// A setting is out of its range (`name` says which, `why` what it must be).
    BadSetting {
        /// The setting's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What the value must be.
        why: &'static str,
    },
    /// A time argument (`what`: the start, the end, the window) is NaN, or infinite where a
    /// finite value is needed.
    BadTime {
        /// Which argument.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// The bracket ends before it starts.
    ReversedBracket {
        /// Start of the search.
        start: f64,
        /// End of the bracket.
        end: f64,
    },
    /// Neither the bracket end nor the window is finite: the search could run forever.
    Unbounded,
    /// The indicator returned a NaN or an infinity.
    NonFiniteIndicator {
        /// Where it was evaluated.
        t: f64,
        /// The value it returned.
        f: f64,
        /// The derivative it returned.
        df: f64,
    },
    /// A step is too small to move the time at this magnitude (`t + step == t`): the time
    /// origin should be re-based, or the step made larger.
    StepBelowResolution {
        /// Where the search stood.
        t: f64,
        /// The step that did not move it.
        step: f64,
    },
}

impl fmt::Display for SearchError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            SearchError::BadSetting { name, value, why } => {
                write!(f, "setting `{name}` = {value} is invalid: it must be {why}")
            }
            SearchError::BadTime { what, value } => {
                write!(
                    f,
                    "the {what} of the search is {value}; it must be a finite time"
                )
            }
            SearchError::ReversedBracket { start, end } => write!(
                f,
                "the bracket ends at t = {end}, before the search starts at t = {start}"
            ),
            SearchError::Unbounded => f.write_str(
                "both the bracket end and the window are infinite; give a finite end or a \
                 finite window so the search stops",
            ),
            SearchError::NonFiniteIndicator { t, f: v, df } => write!(
                f,
                "the indicator returned f = {v}, f' = {df} at t = {t}; both must be finite"
            ),
            SearchError::StepBelowResolution { t, step } => write!(
                f,
                "a step of {step} does not change t = {t} in double precision; re-base the \
                 time origin or use a larger step"
            ),
        }
    }
}

impl std::error::Error for SearchError {}

/// A setting that must be finite and strictly positive.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, SearchError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(SearchError::BadSetting {
            name,
            value,
            why: "finite and > 0",
        })
    }
}

/// A setting that must be finite and non-negative.
pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64, SearchError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(SearchError::BadSetting {
            name,
            value,
            why: "finite and >= 0",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_problem() {
        let e = positive("max_step", -1.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "setting `max_step` = -1 is invalid: it must be finite and > 0"
        );
        assert!(non_negative("threshold", f64::NAN).is_err());
        assert!(non_negative("threshold", 0.0).is_ok());
        assert!(
            SearchError::ReversedBracket {
                start: 2.0,
                end: 1.0
            }
            .to_string()
            .contains("before the search starts")
        );
    }
}
