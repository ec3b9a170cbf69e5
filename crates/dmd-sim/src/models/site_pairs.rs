//! What rigid and flexible site molecules share: the atoms of a molecule, the band of a site
//! pair's level in squared distance, the state a site pair's search has come to, and the
//! [`SiteTable`]: everything of a site-molecule model but how its molecules move and how an
//! impulse acts on them (000 §III: searches of every site pair of two molecules, bracketed
//! by bounding spheres, resumed by virtual events).

use collide::Outcome;
use glam::DVec3;
use root_search::{Adaptive, Crossing, Grid, Method, SearchState};

use crate::engine::event::{Boundary, Kind};
use crate::engine::hash::mix;
use crate::engine::model::{Pair, PairClass, PairSetupError};
use crate::engine::pair_state::{SavedSearches, SiteLevels};
use crate::engine::potential::{Level, Potentials};
use crate::engine::saved::StateReader;
use crate::models::search::{SearchMethod, SearchSettings, SearchStats, bracket, jitter_factor};

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

/// What a prediction left for a pair of site molecules.
#[derive(Clone, Debug, PartialEq)]
pub enum Pending {
    /// The molecules come within reach at the event: set up every site pair then.
    Later,
    /// Per site pair, in the order of the pair's site-pair table.
    Sites(Vec<SiteSearch>),
    /// The pair event is for site pair `k` at the boundary.
    Fire(u32, Boundary),
    /// A molecule's motion could not be computed (a failed RATTLE step of a semi-flexible
    /// molecule): the event is due at once and stops the run.
    Broken,
}

/// One site pair of a pair of molecule types.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SitePair {
    /// The site of the first molecule.
    pub a: u16,
    /// The site of the second.
    pub b: u16,
    /// Index of their potential in the [`Potentials`] table.
    pub potential: u32,
    /// `ρ_α + ρ_β`: the bounding radii of the two sites about their centres.
    pub arms: f64,
}

/// The site pairs of one ordered pair of molecule types.
#[derive(Clone, Debug, PartialEq)]
struct TypePair {
    pairs: Vec<SitePair>,
    /// Largest centre distance at which any site pair interacts.
    reach: f64,
}

/// Where two molecules' sites are: what a site pair's indicator needs from a model. Rigid
/// molecules answer from their free motion, semi-flexible ones from their RATTLE trajectory.
pub trait SiteDistance {
    /// `d²` of site `a` of the first molecule and site `b` of the second at `t`, and its rate
    /// `2 r·u` (NaN when the motion cannot be computed, which the search reports as a failure).
    fn distance2(&mut self, a: usize, b: usize, t: f64) -> (f64, f64);
}

/// How an event's site pair stands at the event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Firing {
    /// The site pair's index in the pair's table.
    pub k: usize,
    /// The site of the first molecule.
    pub a: usize,
    /// The site of the second.
    pub b: usize,
    /// Index of the site pair's potential.
    pub potential: usize,
    /// Its stored level.
    pub level: u16,
    /// The boundary the search found.
    pub boundary: Boundary,
}

/// What the site-pair bookkeeping says about an event before the impulse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Judged {
    /// The energy step at the boundary (`+∞` for a hard core).
    pub step: f64,
    /// The pair moves through the boundary the way the search found it (else nothing happens).
    pub right_way: bool,
    /// Inside a hard core by more than round-off.
    pub overlap: bool,
}

/// The part of a site-molecule model that does not depend on how molecules move (rigid or
/// semi-flexible): the site-pair tables of each pair of molecule types, the site-pair levels
/// of molecule pairs, the saved searches, the bracketing and root search of site pairs and the
/// choice of a pair's next event, the bookkeeping of an executed event, and the pair checks.
/// A model supplies the sites' positions ([`SiteDistance`] for the searches, lab arms from
/// the centres elsewhere) and its impulse rule.
#[derive(Debug)]
pub struct SiteTable {
    potentials: Potentials,
    type_pairs: Vec<TypePair>,
    n_types: usize,
    /// Site count of each molecule type.
    site_counts: Vec<usize>,
    /// The molecule type of each body.
    pub body_type: Vec<u32>,
    /// Per molecule type, the site pairs of one molecule that interact with each other (`a <
    /// b`; empty: none, the default), searched as the pair `(i, i)`.
    own: Vec<TypePair>,
    levels: SiteLevels,
    pending: SavedSearches<Pending>,
    settings: SearchSettings,
    /// The key of the search steps' jitter ([`jitter_factor`]).
    jitter_key: u64,
    /// Counters of the root searches.
    pub stats: SearchStats,
    reach: f64,
}

impl SiteTable {
    /// The table for molecule types with sites of `species` at bounding radii `radii` (one
    /// pair of slices per type) and site–site `potentials`, bodies of types `body_type`,
    /// searches with `settings` and jitter key `jitter_key`.
    pub fn new<'a>(
        types: impl Iterator<Item = (&'a [u32], &'a [f64])> + Clone,
        potentials: Potentials,
        body_type: &[u32],
        settings: SearchSettings,
        jitter_key: u64,
    ) -> Self {
        let mut type_pairs = Vec::new();
        for (si, ri) in types.clone() {
            for (sj, rj) in types.clone() {
                let mut pairs = Vec::new();
                let mut reach: f64 = 0.0;
                for (a, (&sa, &ra)) in si.iter().zip(ri).enumerate() {
                    for (b, (&sb, &rb)) in sj.iter().zip(rj).enumerate() {
                        let k = potentials.index(sa, sb);
                        reach = reach.max(potentials.all()[k].reach() + ra + rb);
                        pairs.push(SitePair {
                            a: a as u16,
                            b: b as u16,
                            potential: k as u32,
                            arms: ra + rb,
                        });
                    }
                }
                type_pairs.push(TypePair {
                    pairs,
                    reach: reach * (1.0 + 1e-12),
                });
            }
        }
        let reach = type_pairs.iter().map(|p| p.reach).fold(0.0, f64::max);
        let site_counts: Vec<usize> = types.map(|(s, _)| s.len()).collect();
        SiteTable {
            potentials,
            type_pairs,
            n_types: site_counts.len(),
            own: vec![
                TypePair {
                    pairs: Vec::new(),
                    reach: 0.0
                };
                site_counts.len()
            ],
            site_counts,
            body_type: body_type.to_vec(),
            levels: SiteLevels::default(),
            pending: SavedSearches::new(body_type.len()),
            settings,
            jitter_key,
            stats: SearchStats::default(),
            reach,
        }
    }

    /// The table with the site pairs `own[t]` (`a < b`) of each molecule of type `t`
    /// interacting with each other through their site species' potential: the pair `(i, i)`
    /// of a molecule that [`has_own_pairs`](Self::has_own_pairs).
    pub fn with_own_pairs(mut self, own: &[Vec<(u16, u16)>], species: &[&[u32]]) -> Self {
        for (t, list) in own.iter().enumerate() {
            let pairs = list
                .iter()
                .map(|&(a, b)| {
                    debug_assert!(a < b);
                    SitePair {
                        a,
                        b,
                        potential: self
                            .potentials
                            .index(species[t][a as usize], species[t][b as usize])
                            as u32,
                        // Both sites move with the molecule: no bounding sphere brackets them.
                        arms: f64::INFINITY,
                    }
                })
                .collect();
            self.own[t] = TypePair { pairs, reach: 0.0 };
        }
        self
    }

    /// Whether molecules of type `t` have site pairs of their own that interact.
    #[inline]
    pub fn has_own_pairs(&self, t: usize) -> bool {
        !self.own[t].pairs.is_empty()
    }

    /// Largest centre distance at which two molecules interact.
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// The site–site potentials.
    pub fn potentials(&self) -> &Potentials {
        &self.potentials
    }

    /// The search settings.
    pub fn settings(&self) -> &SearchSettings {
        &self.settings
    }

    /// Number of molecule pairs with a site pair off level 0.
    pub fn stored_pairs(&self) -> usize {
        self.levels.len()
    }

    /// The molecule type of body `i`.
    #[inline]
    pub fn type_of(&self, i: u32) -> usize {
        self.body_type[i as usize] as usize
    }

    /// The site pairs of molecules `i` and `j`, `α`-major for `i` (of one molecule with
    /// itself for `i == j`).
    #[inline]
    pub fn pairs(&self, i: u32, j: u32) -> &[SitePair] {
        if i == j {
            return &self.own[self.type_of(i)].pairs;
        }
        &self.type_pairs[self.type_of(i) * self.n_types + self.type_of(j)].pairs
    }

    /// Where the level of site pair `sp` of `(i, j)` sits in [`SiteLevels::pair`]'s order.
    #[inline]
    fn slot(&self, i: u32, j: u32, sp: &SitePair) -> usize {
        sp.a as usize * self.sizes(i, j).1 + sp.b as usize
    }

    /// The site counts of `i` and `j`.
    #[inline]
    fn sizes(&self, i: u32, j: u32) -> (usize, usize) {
        (
            self.site_counts[self.type_of(i)],
            self.site_counts[self.type_of(j)],
        )
    }

    /// The stored level of site `a` of `i` with site `b` of `j`.
    pub fn site_level(&self, i: u32, j: u32, a: usize, b: usize) -> u16 {
        self.levels.get(i, j, a, b, self.sizes(i, j))
    }

    fn set_level(&mut self, i: u32, j: u32, a: usize, b: usize, level: u16) {
        let sizes = self.sizes(i, j);
        self.levels.set(i, j, a, b, sizes, level);
    }

    /// The level band of site pair `sp` on `level`.
    #[inline]
    fn level(&self, sp: &SitePair, level: u16) -> Level {
        self.potentials.all()[sp.potential as usize].levels()[level as usize]
    }

    /// Stores the levels of the site pairs of `(i, j)` at separation `dr` from the sites' lab
    /// arms from their centres (a new pair: every stored level is 0).
    ///
    /// # Errors
    /// Two sites inside a hard core.
    pub fn setup(
        &mut self,
        i: u32,
        j: u32,
        dr: DVec3,
        arms_i: &[DVec3],
        arms_j: &[DVec3],
    ) -> Result<(), PairSetupError> {
        for k in 0..self.pairs(i, j).len() {
            let sp = self.pairs(i, j)[k];
            let pot = &self.potentials.all()[sp.potential as usize];
            let d = (dr + arms_i[sp.a as usize] - arms_j[sp.b as usize]).length();
            if let Some(core) = pot.core()
                && d < core
            {
                return Err(PairSetupError::Overlap { distance: d, core });
            }
            let level = pot.level_at(d);
            if level > 0 {
                self.set_level(i, j, sp.a as usize, sp.b as usize, level as u16);
            }
        }
        Ok(())
    }

    /// The first step of a prediction: `Err(answer)` when the molecules are not within reach
    /// now (no event, or a virtual event when they arrive, saved as [`Pending::Later`]);
    /// `Ok(())` when the site pairs must be searched now.
    fn approach(&mut self, pair: &Pair) -> Result<(), Option<(f64, Kind)>> {
        let Pair {
            i, j, now, dr, dv, ..
        } = *pair;
        if i == j {
            // A molecule's own sites are always within reach of each other.
            return Ok(());
        }
        let reach = self.type_pairs[self.type_of(i) * self.n_types + self.type_of(j)].reach;
        let Some((start, _)) = bracket(dr, dv, reach * reach) else {
            return Err(None);
        };
        if start.is_nan() {
            self.stats.failures += 1;
            return Err(None);
        }
        if start > 0.0 {
            self.stats.deferred += 1;
            self.pending.set(i, j, now + start, Pending::Later);
            return Err(Some((start, Kind::Virtual)));
        }
        Ok(())
    }

    /// Predicts the next event of a pair: none, a virtual event when the molecules come
    /// within reach, or the outcome of `search` on every site pair's bracket (the model runs
    /// the searches due on its own motion, [`search_due`](Self::search_due), then
    /// [`choose`](Self::choose)s; its last argument is `fresh`).
    pub fn predict(
        &mut self,
        pair: &Pair,
        search: impl FnOnce(&mut Self, Vec<SiteSearch>, bool) -> Option<(f64, Kind)>,
    ) -> Option<(f64, Kind)> {
        if let Err(answer) = self.approach(pair) {
            return answer;
        }
        let sites = self.brackets(pair.i, pair.j, pair.now, pair.dr, pair.dv);
        search(self, sites, true)
    }

    /// Continues what the prediction of a pair saved, at its virtual event (as
    /// [`predict`](Self::predict)).
    pub fn resume(
        &mut self,
        pair: &Pair,
        search: impl FnOnce(&mut Self, Vec<SiteSearch>, bool) -> Option<(f64, Kind)>,
    ) -> Option<(f64, Kind)> {
        match self.take(pair.i, pair.j, pair.now)? {
            Pending::Later => {
                let sites = self.brackets(pair.i, pair.j, pair.now, pair.dr, pair.dv);
                search(self, sites, true)
            }
            Pending::Sites(sites) => search(self, sites, false),
            Pending::Fire(..) | Pending::Broken => None,
        }
    }

    /// Takes what the event of `i` with `j` due at `now` continues.
    fn take(&mut self, i: u32, j: u32, now: f64) -> Option<Pending> {
        self.pending.take(i, j, now)
    }

    /// Saves `what` for the event of `i` with `j` at `at`.
    pub fn save(&mut self, i: u32, j: u32, at: f64, what: Pending) {
        self.pending.set(i, j, at, what);
    }

    /// Forgets what body `i` saved (it changed).
    pub fn forget(&mut self, i: u32) {
        self.pending.clear(i);
    }

    /// Brackets every site pair of `(i, j)` at `now` by the bounding spheres around the
    /// centres: the pair can be at a radius `R` of its band only while the centres are within
    /// `R + ρ_α + ρ_β`.
    fn brackets(&mut self, i: u32, j: u32, now: f64, dr: DVec3, dv: DVec3) -> Vec<SiteSearch> {
        let levels = self.levels.pair(i, j, self.sizes(i, j));
        let n = self.pairs(i, j).len();
        let mut sites = Vec::with_capacity(n);
        for k in 0..n {
            let sp = self.pairs(i, j)[k];
            let lv = self.level(&sp, levels[self.slot(i, j, &sp)]);
            // The band's largest radius: the outer one, or the inner one on level 0.
            let radius = if lv.outer2 < f64::INFINITY {
                lv.outer2.sqrt()
            } else {
                lv.inner2.sqrt()
            };
            let r = (radius + sp.arms) * (1.0 + 1e-12);
            sites.push(match bracket(dr, dv, r * r) {
                None => SiteSearch::Done,
                Some((a, b)) if a.is_nan() || b.is_nan() => {
                    self.stats.failures += 1;
                    SiteSearch::Done
                }
                Some((a, b)) => SiteSearch::Deferred {
                    at: now + a,
                    end: now + b,
                },
            });
        }
        sites
    }

    /// Runs every site pair of `(i, j)` whose search is due at `now` up to `now + window`
    /// (with `fresh`, a stopped search continues only if it stopped by now; a virtual event
    /// continues them all).
    pub fn search_due<G: SiteDistance>(
        &mut self,
        geo: &mut G,
        (i, j): (u32, u32),
        now: f64,
        sites: &mut [SiteSearch],
        fresh: bool,
    ) {
        let levels = self.levels.pair(i, j, self.sizes(i, j));
        let until = now + self.settings.window;
        for (k, site) in sites.iter_mut().enumerate() {
            let due = match *site {
                SiteSearch::Deferred { at, .. } => at <= now,
                SiteSearch::Suspended(s) => s.time() <= now || !fresh,
                _ => false,
            };
            if !due {
                continue;
            }
            let sp = self.pairs(i, j)[k];
            let band = Band::of(&self.level(&sp, levels[self.slot(i, j, &sp)]));
            *site = self.search_site(
                geo,
                (i, j, k as u32),
                (sp.a as usize, sp.b as usize),
                band,
                now,
                *site,
                until,
            );
        }
    }

    /// Starts or continues the search of site pair `k` of `(i, j)` (sites `a`, `b`) on `band`
    /// up to `until`.
    #[allow(clippy::too_many_arguments)]
    fn search_site<G: SiteDistance>(
        &mut self,
        geo: &mut G,
        (i, j, k): (u32, u32, u32),
        (a, b): (usize, usize),
        band: Band,
        now: f64,
        from: SiteSearch,
        until: f64,
    ) -> SiteSearch {
        let (t0, end) = match from {
            SiteSearch::Deferred { at, end } => (at.max(now), end),
            SiteSearch::Suspended(s) => (s.time(), s.end()),
            other => return other,
        };
        if let SiteSearch::Deferred { .. } = from {
            // A search that starts with its pair off the stored level has missed an event.
            let (d2, rate) = geo.distance2(a, b, t0);
            let tol = 1e-7 * band.scale;
            if d2 < band.lo - tol || d2 > band.hi + tol {
                self.stats.off_terrace += 1;
            }
            if let Some(boundary) = band.leaving(d2, rate) {
                self.stats.roots += 1;
                return SiteSearch::Root(t0, boundary);
            }
        }
        let key = mix(self.jitter_key ^ u64::from(k));
        let jitter = jitter_factor(self.settings.jitter, key, i, j, t0);
        let step = self.settings.max_step * jitter;
        // A bracket without end (no relative motion: only rotation changes d) needs a window.
        let horizon = if until == f64::INFINITY && end == f64::INFINITY {
            t0 + 1e4 * self.settings.max_step
        } else {
            until
        };
        let window = (horizon - t0).max(f64::MIN_POSITIVE);
        let mut evals = 0u32;
        let mut indicator = |t: f64| -> (f64, f64) {
            evals += 1;
            let (d2, rate) = geo.distance2(a, b, t);
            band.indicator(d2, rate)
        };
        let result = match (self.settings.method, from) {
            (SearchMethod::Adaptive, SiteSearch::Suspended(s)) => {
                Adaptive::new(step).and_then(|m| m.resume(&mut indicator, s, window))
            }
            (SearchMethod::Adaptive, _) => Adaptive::new(step)
                .and_then(|m| m.start(&mut indicator, t0, end, Crossing::Falling, window)),
            (SearchMethod::Grid { threshold }, SiteSearch::Suspended(s)) => {
                Grid::new(step, threshold).and_then(|m| m.resume(&mut indicator, s, window))
            }
            (SearchMethod::Grid { threshold }, _) => Grid::new(step, threshold)
                .and_then(|m| m.start(&mut indicator, t0, end, Crossing::Falling, window)),
        };
        self.stats.searches += 1;
        self.stats.evaluations += u64::from(evals);
        let Ok(report) = result else {
            self.stats.failures += 1;
            return SiteSearch::Done;
        };
        let checked_to = match report.outcome {
            root_search::Outcome::Root(r) => r.t,
            root_search::Outcome::Suspended(s) => s.time(),
            root_search::Outcome::NoRoot => end,
        };
        if let Some(fine) = self.settings.verify_step {
            self.stats.verified += 1;
            let mut reference = |t: f64| -> (f64, f64) {
                let (d2, rate) = geo.distance2(a, b, t);
                band.indicator(d2, rate)
            };
            let found = Grid::new(fine, f64::INFINITY).and_then(|g| {
                g.start(
                    &mut reference,
                    t0,
                    checked_to.min(t0 + 1e4 * self.settings.max_step),
                    Crossing::Falling,
                    f64::INFINITY,
                )
            });
            if let Ok(rep) = found
                && let Some(tg) = rep.root()
                && tg < checked_to - 1e-6 * self.settings.max_step
            {
                self.stats.verify_misses += 1;
            }
        }
        match report.outcome {
            root_search::Outcome::Root(r) => {
                self.stats.roots += 1;
                let (d2, _) = geo.distance2(a, b, r.t);
                let boundary = if band.hi == f64::INFINITY
                    || (band.lo > 0.0 && (d2 - band.lo).abs() < (band.hi - d2).abs())
                {
                    Boundary::Inner
                } else {
                    Boundary::Outer
                };
                SiteSearch::Root(r.t, boundary)
            }
            root_search::Outcome::Suspended(s) => {
                self.stats.suspended += 1;
                SiteSearch::Suspended(s)
            }
            root_search::Outcome::NoRoot => SiteSearch::Done,
        }
    }

    /// Picks the pair's next event from its site pairs' searches: the earliest root if no
    /// stopped or deferred search lies before it, else a virtual event at the earliest of
    /// those (which resumes them).
    pub fn choose(
        &mut self,
        i: u32,
        j: u32,
        now: f64,
        sites: Vec<SiteSearch>,
    ) -> Option<(f64, Kind)> {
        let mut root = (f64::INFINITY, 0usize, Boundary::Inner);
        let mut wait = f64::INFINITY;
        for (k, s) in sites.iter().enumerate() {
            match *s {
                SiteSearch::Root(t, b) if t < root.0 => root = (t, k, b),
                SiteSearch::Suspended(st) => wait = wait.min(st.time()),
                SiteSearch::Deferred { at, .. } => wait = wait.min(at),
                _ => {}
            }
        }
        if root.0 <= wait && root.0 < f64::INFINITY {
            let dt = root.0 - now;
            self.pending
                .set(i, j, now + dt, Pending::Fire(root.1 as u32, root.2));
            return Some((dt, Kind::Pair(root.2)));
        }
        if wait < f64::INFINITY {
            let dt = (wait - now).max(0.0);
            self.pending.set(i, j, now + dt, Pending::Sites(sites));
            return Some((dt, Kind::Virtual));
        }
        None
    }

    /// The site pair an event of `(i, j)` due at `now` is for, from what its prediction saved:
    /// `Ok(None)` for a stale event (nothing happens), `Err(())` for a broken motion.
    #[allow(clippy::result_unit_err)]
    pub fn fire(&mut self, i: u32, j: u32, now: f64) -> Result<Option<Firing>, ()> {
        let (k, boundary) = match self.pending.take(i, j, now) {
            Some(Pending::Fire(k, boundary)) => (k as usize, boundary),
            Some(Pending::Broken) => return Err(()),
            _ => return Ok(None),
        };
        let sp = self.pairs(i, j)[k];
        let (a, b) = (sp.a as usize, sp.b as usize);
        Ok(Some(Firing {
            k,
            a,
            b,
            potential: sp.potential as usize,
            level: self.site_level(i, j, a, b),
            boundary,
        }))
    }

    /// Judges the event `f` with the site pair at separation `n` and `rate = n·u`: the energy
    /// step, the direction, and an overlap; an event whose site distance is not at the
    /// boundary (to the root tolerance, 1e-10 of the step in time, and round-off) counts a
    /// misfit.
    pub fn judge(&mut self, f: &Firing, n: DVec3, rate: f64) -> Judged {
        let lv = self.potentials.all()[f.potential].levels()[f.level as usize];
        let (radius2, step, right_way) = match f.boundary {
            Boundary::Inner => (lv.inner2, lv.dv_in, rate < 0.0),
            Boundary::Outer => (lv.outer2, lv.dv_out, rate > 0.0),
        };
        let d2 = n.length_squared();
        let tol = 1e-9 * radius2 + 2.0 * 8.0 * rate.abs() * 1e-10 * self.settings.max_step;
        if (d2 - radius2).abs() > tol || d2.is_nan() {
            self.stats.misfits += 1;
        }
        Judged {
            step,
            right_way,
            overlap: step == f64::INFINITY && d2 < radius2 * (1.0 - SITE_OVERLAP_TOLERANCE),
        }
    }

    /// Books the impulse's `outcome` of event `f` of `(i, j)` (energy step `step`): the new
    /// level of a crossing, and the class of the event.
    pub fn settle(&mut self, i: u32, j: u32, f: &Firing, outcome: Outcome, step: f64) -> PairClass {
        match (outcome, f.boundary) {
            (Outcome::Reflected, _) if step == f64::INFINITY => PairClass::Core,
            (Outcome::Reflected, _) => PairClass::StepReflect,
            (Outcome::Crossed, Boundary::Inner) => {
                self.set_level(i, j, f.a, f.b, f.level + 1);
                PairClass::StepIn
            }
            (Outcome::Crossed, Boundary::Outer) => {
                self.set_level(i, j, f.a, f.b, f.level - 1);
                PairClass::StepOut
            }
        }
    }

    /// The potential energy of `(i, j)` judged from the site distances (at separation `dr`,
    /// lab arms `arms_i`, `arms_j`): each site pair on the level its distance says, the stored
    /// one at a boundary.
    pub fn configured_energy(
        &self,
        i: u32,
        j: u32,
        dr: DVec3,
        arms_i: &[DVec3],
        arms_j: &[DVec3],
    ) -> f64 {
        let mut e = 0.0;
        for sp in self.pairs(i, j) {
            let pot = &self.potentials.all()[sp.potential as usize];
            let d = (dr + arms_i[sp.a as usize] - arms_j[sp.b as usize]).length();
            let held = self.site_level(i, j, sp.a as usize, sp.b as usize) as usize;
            e += pot.levels()[pot.true_level(held, d)].energy;
        }
        e
    }

    /// The potential energy of `(i, j)` on its stored site levels.
    pub fn pair_energy(&self, i: u32, j: u32) -> f64 {
        let Some(l) = self.levels.stored(i, j) else {
            return 0.0;
        };
        let (lo, hi) = (i.min(j), i.max(j));
        let mut e = 0.0;
        for sp in self.pairs(lo, hi) {
            let level = l[self.slot(lo, hi, sp)];
            if level != 0 {
                e += self.potentials.all()[sp.potential as usize].levels()[level as usize].energy;
            }
        }
        e
    }

    /// Checks the stored site levels of `(i, j)` against the geometry (separation `dr`, lab
    /// arms), no overlapping hard cores, and that an interacting pair is `listed`.
    ///
    /// # Errors
    /// A description of the violation.
    pub fn check(
        &self,
        (i, j): (u32, u32),
        dr: DVec3,
        arms_i: &[DVec3],
        arms_j: &[DVec3],
        listed: bool,
    ) -> Result<(), String> {
        for sp in self.pairs(i, j) {
            let pot = &self.potentials.all()[sp.potential as usize];
            let (a, b) = (sp.a as usize, sp.b as usize);
            let d = (dr + arms_i[a] - arms_j[b]).length();
            if d < pot.reach() && !listed {
                return Err(format!(
                    "sites {a} of {i} and {b} of {j} interact at {d} but the pair is not listed"
                ));
            }
            if let Some(core) = pot.core()
                && d * d < core * core * (1.0 - SITE_OVERLAP_TOLERANCE)
            {
                return Err(format!(
                    "site {a} of {i} and site {b} of {j} overlap: distance {d} < {core}"
                ));
            }
            let stored = self.site_level(i, j, a, b) as usize;
            let expected = pot.level_at(d);
            if stored != expected {
                let n = pot.radii().len();
                let at = pot.radii()[n - stored.max(expected)];
                if stored.abs_diff(expected) > 1 || (d - at).abs() > 1e-7 * at {
                    return Err(format!(
                        "sites {a} of {i} and {b} of {j} at distance {d} are stored on level \
                         {stored}, their distance says {expected}"
                    ));
                }
            }
        }
        Ok(())
    }

    /// Appends the site levels and the search counters to a saved state.
    pub fn write_numbers(&self, x: &mut Vec<f64>) {
        self.levels.write_numbers(x);
        self.stats.write_numbers(x);
    }

    /// Reads what [`write_numbers`](Self::write_numbers) wrote and takes it (only once the
    /// model's own part has been read too: `commit`).
    ///
    /// # Errors
    /// Levels or counters that do not fit the scene.
    pub fn read_numbers(&self, r: &mut StateReader) -> Result<(SiteLevels, SearchStats), String> {
        let n = self.body_type.len() as u32;
        let levels = SiteLevels::read_numbers(
            r,
            n,
            |i, j| {
                let (ni, nj) = self.sizes(i, j);
                ni * nj
            },
            |i, j, k| {
                // The site pair whose level sits at `k` (none: only level 0 is possible).
                self.pairs(i, j)
                    .iter()
                    .find(|sp| self.slot(i, j, sp) == k)
                    .map_or(1, |sp| {
                        self.potentials.all()[sp.potential as usize].levels().len()
                    })
            },
        )?;
        Ok((levels, SearchStats::read_numbers(r)?))
    }

    /// Takes a state read by [`read_numbers`](Self::read_numbers).
    pub fn commit(&mut self, (levels, stats): (SiteLevels, SearchStats)) {
        self.levels = levels;
        self.stats = stats;
    }
}

/// An atom of site species 0 at `(x, y, z)`, for the tests of the site models.
#[cfg(test)]
pub(crate) fn atom(x: f64, y: f64, z: f64, mass: f64) -> SiteAtom {
    SiteAtom {
        position: DVec3::new(x, y, z),
        mass,
        species: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_indicator_watches_both_radii() {
        let b = Band::of(&Level {
            inner2: 1.0,
            outer2: 2.25,
            dv_in: f64::INFINITY,
            dv_out: 1.0,
            energy: -1.0,
        });
        assert!(b.indicator(1.5, 0.0).0 > 0.0);
        assert_eq!(b.indicator(1.0, -2.0), (0.0, -2.0));
        assert_eq!(b.indicator(2.25, 2.0), (0.0, -2.0));
        let b0 = Band::of(&Level {
            inner2: 2.25,
            outer2: f64::INFINITY,
            dv_in: -1.0,
            dv_out: f64::NAN,
            energy: 0.0,
        });
        assert_eq!(b0.indicator(3.0, -1.0), (0.75, -1.0));
        // On a boundary: leaving only when moving out; just crossed in (moving in), or
        // grazing, or inside, it is not leaving.
        assert_eq!(b.leaving(2.25, 0.5), Some(Boundary::Outer));
        assert_eq!(b.leaving(2.25 * (1.0 - 1e-13), 0.5), Some(Boundary::Outer));
        assert_eq!(b.leaving(1.0, -0.5), Some(Boundary::Inner));
        assert_eq!(b.leaving(2.25, -0.5), None);
        assert_eq!(b.leaving(2.25, 0.0), None);
        assert_eq!(b.leaving(1.0, 0.5), None);
        assert_eq!(b.leaving(2.2, 0.5), None);
        assert_eq!(b0.leaving(2.25, -0.1), Some(Boundary::Inner));
        assert_eq!(b0.leaving(2.25, 0.1), None);
    }
}
