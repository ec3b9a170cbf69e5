//! What rigid and flexible site molecules share: the atoms of a molecule, the band of a site
//! pair's level in squared distance, and the state a site pair's search has come to.

use glam::DVec3;
use root_search::SearchState;

use crate::engine::event::Boundary;
use crate::engine::potential::Level;

/// Relative tolerance on squared site distances below which an overlap counts as round-off.
pub const SITE_OVERLAP_TOLERANCE: f64 = 1e-9;

/// One atom of a molecule type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SiteAtom {
    /// Position in the frame the molecule is described in (any origin, any orientation).
    pub position: DVec3,
    /// Mass.
    pub mass: f64,
    /// Site species (indexes the site–site potential table).
    pub species: u32,
}

/// The band of a site pair's level in squared distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// `r_in²` (`−1`: none).
    pub lo: f64,
    /// `r_out²` (`+∞`: none).
    pub hi: f64,
    /// `1 / (hi − lo)` when both exist, else 0.
    inv: f64,
    /// A squared length for tolerances.
    pub scale: f64,
}

impl Band {
    /// The band of level `l`.
    pub fn of(l: &Level) -> Band {
        let both = l.inner2 > 0.0 && l.outer2 < f64::INFINITY;
        Band {
            lo: l.inner2,
            hi: l.outer2,
            inv: if both {
                1.0 / (l.outer2 - l.inner2)
            } else {
                0.0
            },
            scale: if l.outer2 < f64::INFINITY {
                l.outer2
            } else {
                l.inner2
            },
        }
    }

    /// The boundary a pair at `d²` with rate `ḋ²` is leaving through right now: on it (within
    /// round-off, `1e-10` of the band's scale) and moving out. A fresh search never reports a
    /// crossing at its start (right after an event the pair sits on the boundary it crossed,
    /// moving in); a pair whose velocities were redrawn there (HMC's refresh at the end of an
    /// equilibration stopped by an event count) may move out at once, and this says so.
    #[inline]
    pub fn leaving(&self, d2: f64, rate: f64) -> Option<Boundary> {
        let margin = 1e-10 * self.scale;
        if self.lo > 0.0 && rate < 0.0 && (d2 - self.lo).abs() <= margin {
            Some(Boundary::Inner)
        } else if self.hi < f64::INFINITY && rate > 0.0 && (self.hi - d2).abs() <= margin {
            Some(Boundary::Outer)
        } else {
            None
        }
    }

    /// `g` and `ġ` (module documentation) from `d²` and its rate.
    #[inline(always)]
    pub fn indicator(&self, d2: f64, rate: f64) -> (f64, f64) {
        if self.inv > 0.0 {
            (
                (d2 - self.lo) * (self.hi - d2) * self.inv,
                rate * (self.hi + self.lo - 2.0 * d2) * self.inv,
            )
        } else if self.hi == f64::INFINITY {
            (d2 - self.lo, rate)
        } else {
            (self.hi - d2, -rate)
        }
    }
}

/// What one site pair's search has come to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SiteSearch {
    /// Nothing can happen in its bracket.
    Done,
    /// Its event.
    Root(f64, Boundary),
    /// Stopped at the end of its window.
    Suspended(SearchState),
    /// Its bracket starts at `at` and ends at `end`.
    Deferred {
        /// Where the bracket starts.
        at: f64,
        /// Where it ends.
        end: f64,
    },
}
