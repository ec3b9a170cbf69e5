//! The earliest root of an indicator function `f(t)`, with no grazing event missed.
//!
//! An event-driven simulation of bodies with terraced potentials needs, for every pair, the
//! first time `t > t0` at which `f(t) = U(t) − U_k` reaches zero (003 Eq. 8), knowing `f` and
//! `f'` (003 Eq. 12) at any time it asks for. Roots where `f` only dips across zero between two
//! samples (*grazing* events) are the hard part. This crate provides:
//!
//! - [`Indicator`], what a search evaluates: `(f(t), f'(t))` together;
//! - [`Grid`], the uniform grid search of 000 §III.A with Newton–Raphson refinement and
//!   grazing detection by extrema below a threshold;
//! - [`Adaptive`], the adaptive search of 003 §III: linear extrapolation to place samples, the
//!   cubic Hermite interpolant (003 Eqs. 13–15) to find extrema between them;
//! - resumable searches: a call limited to a window returns a [`SearchState`] (40 bytes,
//!   `Copy`) that a *virtual event* (000 §III.B) keeps until it resumes the search exactly;
//! - [`sphere_window`], the analytic times at which a linearly moving centre distance enters
//!   and leaves the interaction sphere, which bracket each search;
//! - [`monotone_root`], the root of a function proven monotone on a bracket (by a certificate
//!   from outside the crate), where refinement alone suffices, and [`taylor_root`], the same
//!   from a Taylor model's derivatives, which stops on the model's own error bound;
//! - [`corpus`], adversarial indicators with known roots that test any method.
//!
//! Every call reports how many times it evaluated the indicator. Searches ask for a crossing
//! [`Crossing::Rising`], [`Crossing::Falling`] or [`Crossing::Either`]. After an event `f(t0)`
//! is zero only up to round-off, and may sit on the wrong side of it: a start within the
//! [`Tolerances::touch`] margin counts as zero and goes the way `f'(t0)` points, and a search for
//! a direction skips a round-off crossing right after `t0` in any case, since it goes the wrong
//! way. Set `touch` to the round-off level of `f`.
//!
//! ```
//! use root_search::{sphere_window, Adaptive, Crossing, Method, Outcome};
//!
//! // A pair approaching head-on; f = U − U_k for a soft wall U = 1/r⁴ and a terrace U_k = 1.
//! let (r0, v) = (3.0, -0.8);
//! let mut f = |t: f64| {
//!     let r = r0 + v * t;
//!     (r.powi(-4) - 1.0, -4.0 * r.powi(-5) * v)
//! };
//! // Only while the centres are within the reach 2.5 can anything happen: the bracket.
//! let w = sphere_window([r0, 0.0, 0.0], [v, 0.0, 0.0], 2.5)?.unwrap();
//! let (start, end) = w.after(0.0).unwrap();
//!
//! // Search at most 0.25 time units per call, as a simulator with virtual events does.
//! let search = Adaptive::new(0.1)?;
//! let mut report = search.start(&mut f, start, end, Crossing::Rising, 0.25)?;
//! let mut calls = 1;
//! while let Outcome::Suspended(state) = report.outcome {
//!     // ... a virtual event at state.time() comes due ...
//!     report = search.resume(&mut f, state, 0.25)?;
//!     calls += 1;
//! }
//! let root = report.root().expect("the pair reaches r = 1 at t = 2.5");
//! assert!((root - 2.5).abs() < 1e-9);
//! assert!(calls > 1);
//! # Ok::<(), root_search::SearchError>(())
//! ```

mod adaptive;
mod bracket;
pub mod corpus;
mod error;
mod grazing;
mod grid;
mod hermite;
mod indicator;
mod refine;
mod search;
mod tolerance;

pub use adaptive::{Adaptive, DEFAULT_OVERSHOOT};
pub use bracket::{SphereWindow, sphere_window};
pub use error::SearchError;
pub use grid::Grid;
pub use indicator::{Crossing, Direction, Indicator};
pub use refine::{monotone_root, taylor_root};
pub use search::{Method, Outcome, Report, Root, SearchState};
pub use tolerance::Tolerances;

/// The README's example, compiled and run as a doctest so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
