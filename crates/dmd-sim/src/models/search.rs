//! The root-search driver shared by the models whose event times are roots of a smooth function
//! of time (terraced bodies, site molecules, flexible molecules): the accuracy and cost knobs,
//! the counters every search keeps, and the window in which two centres are within a reach.

use glam::DVec3;
use root_search::{Adaptive, Grid, SearchError};

use crate::engine::hash::mix;
use crate::engine::model::Report;
use crate::engine::saved::{StateReader, push_count};

/// How the event times of a pair are searched.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SearchMethod {
    /// The adaptive search with cubic Hermite interpolation of 003 §III (maximum step
    /// [`SearchSettings::max_step`]).
    Adaptive,
    /// The uniform grid of 000 §III.A with spacing [`SearchSettings::max_step`]; extrema are
    /// examined where `|g|` at a grid point is below `threshold` (energy units).
    Grid {
        /// The grazing threshold.
        threshold: f64,
    },
}

/// The accuracy and cost knobs of the root searches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchSettings {
    /// Adaptive or grid search.
    pub method: SearchMethod,
    /// The maximum step of the adaptive search, or the grid spacing (003 §V.A: 4 fs).
    pub max_step: f64,
    /// How far one search call may go before it stops and schedules a virtual event (003 §V.A:
    /// 4 fs); `+∞` searches each bracket to its end in one call (no virtual events).
    pub window: f64,
    /// Each search call shortens its step by a random fraction in `[0, jitter)`, so that
    /// virtual events of different pairs do not coincide (003 §V.A).
    pub jitter: f64,
    /// Validation mode: every search interval is searched again on a uniform grid of this
    /// spacing that examines every extremum (`None`: off).
    pub verify_step: Option<f64>,
    /// Each call's maximum step is also at most this fraction of the terrace's width divided
    /// by `|U̇|` at the call's first sample (never below 1 % of `max_step`): steps follow the
    /// speed of `U`, so an excursion across a level and back within one maximum step is still
    /// sampled. (The indicator's own slope cannot size the step: it vanishes mid-terrace.)
    /// `+∞`: off, the paper's search.
    pub max_change: f64,
    /// Certified prediction (`potential::certify`): before each search call, jump the
    /// stretch of free flight in which a Taylor model of the potential's effective coordinate
    /// proves that `U` stays inside its band, up to this far ahead; a pair still safe there
    /// gets a virtual event at that time, having evaluated nothing, and a pair the models stop
    /// short of it gets one at the end of the proven stretch, where its root search starts.
    /// 0: off (and for potentials without a Taylor model, whatever its value).
    pub horizon: f64,
}

impl SearchSettings {
    /// The paper's settings (003 §V.A) with maximum step `max_step` (4 fs there): the adaptive
    /// search, a window equal to the step, 1 % jitter, no verification.
    pub fn paper(max_step: f64) -> Self {
        SearchSettings {
            method: SearchMethod::Adaptive,
            max_step,
            window: max_step,
            jitter: 0.01,
            verify_step: None,
            max_change: f64::INFINITY,
            horizon: 0.0,
        }
    }
}

/// Counters of the root searches of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SearchStats {
    /// Search calls (started or resumed).
    pub searches: u64,
    /// Evaluations of `U`, force and torques inside searches.
    pub evaluations: u64,
    /// Searches that ended at a root.
    pub roots: u64,
    /// Searches that stopped at the end of their window (a virtual event scheduled).
    pub suspended: u64,
    /// Virtual events scheduled for the moment a pair comes within reach (no evaluation).
    pub deferred: u64,
    /// Searches that started with the pair's `U` off its stored terrace by more than round-off:
    /// the trace of an event missed earlier.
    pub off_terrace: u64,
    /// Executed events whose `U` was not at the predicted level beyond round-off.
    pub misfits: u64,
    /// Searches that failed (a non-finite indicator: a broken invariant); the pair got no event.
    pub failures: u64,
    /// Searches checked against the fine grid (validation mode).
    pub verified: u64,
    /// Searches in whose interval the fine grid found an earlier root (missed events).
    pub verify_misses: u64,
    /// Taylor models of certified prediction evaluated (each proves a stretch or stops).
    #[serde(default)]
    pub taylor_models: u64,
    /// Search calls that jumped a proven-safe stretch.
    #[serde(default)]
    pub certified_jumps: u64,
}

impl SearchStats {
    /// The counts since `earlier` (a snapshot of the same run).
    pub fn since(&self, earlier: &SearchStats) -> SearchStats {
        SearchStats {
            searches: self.searches - earlier.searches,
            evaluations: self.evaluations - earlier.evaluations,
            roots: self.roots - earlier.roots,
            suspended: self.suspended - earlier.suspended,
            deferred: self.deferred - earlier.deferred,
            off_terrace: self.off_terrace - earlier.off_terrace,
            misfits: self.misfits - earlier.misfits,
            failures: self.failures - earlier.failures,
            verified: self.verified - earlier.verified,
            verify_misses: self.verify_misses - earlier.verify_misses,
            taylor_models: self.taylor_models - earlier.taylor_models,
            certified_jumps: self.certified_jumps - earlier.certified_jumps,
        }
    }
}

impl SearchStats {
    /// The counters' names in a [`Report`] (prefix `search.`), in the order of
    /// [`counts`](Self::counts).
    pub const NAMES: [&'static str; 12] = [
        "search.searches",
        "search.evaluations",
        "search.roots",
        "search.suspended",
        "search.deferred",
        "search.off_terrace",
        "search.misfits",
        "search.failures",
        "search.verified",
        "search.verify_misses",
        "search.taylor_models",
        "search.certified_jumps",
    ];

    /// The counters in a fixed order (the order of [`SearchStats::NAMES`]).
    pub fn counts(&self) -> [u64; 12] {
        [
            self.searches,
            self.evaluations,
            self.roots,
            self.suspended,
            self.deferred,
            self.off_terrace,
            self.misfits,
            self.failures,
            self.verified,
            self.verify_misses,
            self.taylor_models,
            self.certified_jumps,
        ]
    }

    /// The counters from [`counts`](Self::counts).
    pub fn from_counts(c: [u64; 12]) -> SearchStats {
        SearchStats {
            searches: c[0],
            evaluations: c[1],
            roots: c[2],
            suspended: c[3],
            deferred: c[4],
            off_terrace: c[5],
            misfits: c[6],
            failures: c[7],
            verified: c[8],
            verify_misses: c[9],
            taylor_models: c[10],
            certified_jumps: c[11],
        }
    }

    /// Appends the counters to a model's saved state.
    pub fn write_numbers(&self, out: &mut Vec<f64>) {
        for c in self.counts() {
            push_count(out, c);
        }
    }

    /// Reads what [`write_numbers`](Self::write_numbers) wrote.
    ///
    /// # Errors
    /// A counter that is not a count.
    pub fn read_numbers(r: &mut StateReader) -> Result<SearchStats, String> {
        let mut c = [0u64; 12];
        for x in &mut c {
            *x = r.count("a search counter")?;
        }
        Ok(SearchStats::from_counts(c))
    }

    /// Adds the counters to a model's report.
    pub fn report_into(&self, report: &mut Report) {
        for (name, c) in Self::NAMES.iter().zip(self.counts()) {
            report.count(name, c);
        }
    }

    /// The counters of a model's report (`None` if the model does no root searches).
    pub fn from_report(report: &Report) -> Option<SearchStats> {
        let mut c = [0; 12];
        for (k, name) in Self::NAMES.iter().enumerate() {
            c[k] = report.get_count(name)?;
        }
        Some(SearchStats::from_counts(c))
    }
}

/// Checks search settings a site model cannot use.
///
/// # Errors
/// The first unusable setting.
pub fn check_settings(s: &SearchSettings) -> Result<(), SearchError> {
    Adaptive::new(s.max_step)?;
    if let SearchMethod::Grid { threshold } = s.method {
        Grid::new(s.max_step, threshold)?;
    }
    if s.window.is_nan() || s.window <= 0.0 {
        return Err(SearchError::BadSetting {
            name: "window",
            value: s.window,
            why: "> 0",
        });
    }
    if !(0.0..0.5).contains(&s.jitter) {
        return Err(SearchError::BadSetting {
            name: "jitter",
            value: s.jitter,
            why: "in [0, 0.5)",
        });
    }
    if let Some(v) = s.verify_step {
        Grid::new(v, f64::INFINITY)?;
    }
    Ok(())
}

/// The times `(enter, exit)` from now during which `|dr + dv t|² ≤ R²` (`enter = 0` for a pair
/// already inside), or `None` if the pair never comes within `R` from now on. Each root is
/// taken in the form without cancellation, as `root_search::sphere_window` (the tests compare
/// them), with a quick exit for receding pairs outside and no square root before it.
#[inline(always)]
pub fn bracket(dr: DVec3, dv: DVec3, radius2: f64) -> Option<(f64, f64)> {
    let r2 = dr.length_squared();
    let b = dr.dot(dv);
    let c = r2 - radius2;
    if c > 0.0 {
        if b >= 0.0 {
            return None;
        }
        let v2 = dv.length_squared();
        let disc = b * b - v2 * c;
        if disc <= 0.0 {
            return None;
        }
        let q = -b + disc.sqrt();
        Some((c / q, q / v2))
    } else {
        let v2 = dv.length_squared();
        if v2 == 0.0 {
            return Some((0.0, f64::INFINITY));
        }
        let sq = (b * b - v2 * c).max(0.0).sqrt();
        let exit = if b > 0.0 {
            -c / (b + sq)
        } else {
            (-b + sq) / v2
        };
        Some((0.0, exit))
    }
}

/// The factor `1 − jitter·u` by which one search call shortens its step, `u ∈ [0, 1)` a hash
/// of `key`, the pair `(i, j)` and the time `t0` the call starts from. A pure function, never
/// a generator's history: a prediction made again from the same state (a saved state
/// restored) is the same prediction, so checkpoints and HMC rollbacks stay bit for bit.
#[inline]
pub fn jitter_factor(jitter: f64, key: u64, i: u32, j: u32, t0: f64) -> f64 {
    if jitter > 0.0 {
        let h = mix(mix(key ^ (u64::from(i) << 32 | u64::from(j))) ^ t0.to_bits());
        1.0 - jitter * ((h >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0))
    } else {
        1.0
    }
}
