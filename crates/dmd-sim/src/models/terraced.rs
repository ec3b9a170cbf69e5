//! Rigid rods on terraced potentials (seed 003): any smooth pair potential
//! `U_ij(r_ij, s_i, s_j)` mapped onto energy terraces (003 Eq. 7) and simulated exactly between
//! events.
//!
//! [`Terraced`] is the [`PairModel`] of such a scene. It keeps, indexed like the loop's bodies:
//!
//! - the free rotation of every rod, a [`LinearRotor`] set up at the rod's last change with the
//!   time of that change (the rod's rotational clock); a rod carries no spin about its axis
//!   (the torques of a uniaxial potential are perpendicular to it, 003 §V);
//! - the terrace of every pair off the zero terrace ([`PairStates`], the terrace index stored
//!   and changed only by executed events, never recomputed from `U` at a level);
//! - the saved root searches of its virtual events (000 §III.B, 003 §V.A), keyed by the owner
//!   of the event and its partner.
//!
//! **Event times.** A pair on terrace `k` (`U_k ≤ U < U_{k+1}`) has its next event when `U(t)`
//! leaves that band, at either level. One root search finds the earlier of the two: the
//! indicator is
//!
//! ```text
//! g(t) = (U(t) − U_k)(U_{k+1} − U(t)) / (U_{k+1} − U_k)          (U_{k+1} − U(t) on terrace 0)
//! ```
//!
//! positive inside the band, zero at either level (where it behaves like `±(U − U_level)`, the
//! indicator of 003 Eq. 8), negative outside; its derivative follows from `U̇` (003 Eq. 12) at the
//! cost of a multiplication, so both levels are watched for the price of one search. The search
//! asks for a falling crossing of `g` and is bracketed by the times the centres spend within the
//! band's reach (the forms of `root_search::sphere_window`; the reach of the outermost levels is
//! 003 Eq. 25 for the rods). Each call's step is also limited by the speed of `U` at its first
//! sample ([`SearchSettings::max_change`]). A pair not yet within reach gets a virtual event at
//! the moment it enters (nothing is evaluated before), and a search that reaches the end of its
//! window gets one at its last sample, from which it resumes if neither body has changed by
//! then. With certified prediction ([`SearchSettings::horizon`]) each call first jumps the
//! stretch the potential's Taylor model proves free of crossings and ends with a virtual event
//! there: certified again from there if the jump reached the horizon, the root search started
//! there if it stopped short (a crossing may be near). Many predictions are thrown away before
//! their event (either body changes first), so a deferred search is often a search saved.
//!
//! **Impulses.** At the event the force and torques of the smooth potential give the direction
//! of the impulse and `collide::terrace` (003 Eq. 21) its size; the pair crosses to the next
//! terrace or is reflected (always at the hard core above the top terrace).
//!
//! **Checks.** Every executed event verifies that `U` is at the level it was predicted for
//! (beyond round-off: a *misfit*), every search that starts checks that the pair's `U` lies on
//! its stored terrace (a pair found *off terrace* is the trace of a missed event), and with
//! [`SearchSettings::verify_step`] every search interval is searched again on a fine uniform
//! grid that examines every extremum, counting the roots the search stepped over.

use collide::{Outcome, PairForce, Velocity, terrace};
use glam::{DQuat, DVec3};
use potential::{
    FreeFlight, PairEval, PairGeometry, PairPotential, PotentialError, RigidFlight, RigidGeometry,
    RigidPairPotential, TaylorModel, TerraceMap, certify::Proof,
};
use rand_xoshiro::Xoshiro256PlusPlus;
use rigid_free::LinearRotor;
use root_search::{Adaptive, Crossing, Grid, Method, SearchError, SearchState, taylor_root};

use crate::engine::event::{Boundary, Kind};
use crate::engine::hash::mix;
use crate::engine::model::{Executed, Pair, PairClass, PairModel, PairSetupError, Report};
use crate::engine::pair_state::{PairStates, SavedSearches};
use crate::engine::saved::{StateReader, push_count};
use crate::models::rotor::{Anchored, Rotations, Rotor, Top};
use crate::models::search::{SearchMethod, SearchSettings, SearchStats, bracket, jitter_factor};

/// A smooth pair potential as the terraced model reads it: energy, force and torques for two
/// bodies' poses, its minimum and reaches, and optionally a certified Taylor model along the
/// free flight (`potential::certify`). Every uniaxial [`PairPotential`] is one, on rods
/// ([`LinearRotor`]); a [`RigidPairPotential`] becomes one on [`Top`]s through [`Rigid`].
pub trait TerracedPotential {
    /// The rotation of the bodies this potential acts between.
    type Rotor: Rotor;

    /// `U`, force on `i` and both torques for separation `r = r_i − r_j` and poses `a`, `b`.
    ///
    /// # Errors
    /// As [`PairPotential::evaluate`].
    fn evaluate(
        &self,
        r: DVec3,
        a: &Pose<Self>,
        b: &Pose<Self>,
    ) -> Result<PairEval, PotentialError>;

    /// `U` alone (`+∞` inside the core).
    fn energy(&self, r: DVec3, a: &Pose<Self>, b: &Pose<Self>) -> f64;

    /// A lower bound on `U` (exact where the potential knows it).
    fn minimum(&self) -> f64;

    /// An upper bound on the centre distance at which `U` can reach level `u`.
    ///
    /// # Errors
    /// As [`PairPotential::reach`].
    fn reach(&self, u: f64) -> Result<f64, PotentialError>;

    /// The band `[lo, hi)` of `U` in the potential's effective coordinate (empty: none).
    fn coordinate_intervals(&self, lo: f64, hi: f64) -> Vec<(f64, f64)> {
        let _ = (lo, hi);
        Vec::new()
    }

    /// A Taylor model over `h` of the effective coordinate for centres at `r` moving apart at
    /// `v` and the rotations `a`, `b` each `dt` after its anchor (none: no certified jumps).
    fn taylor_model(
        &self,
        r: DVec3,
        v: DVec3,
        a: (&Self::Rotor, f64),
        b: (&Self::Rotor, f64),
        h: f64,
    ) -> Option<TaylorModel> {
        let _ = (r, v, a, b, h);
        None
    }
}

/// The pose type of a terraced potential's bodies.
pub type Pose<P> = <<P as TerracedPotential>::Rotor as Rotor>::Pose;

impl<P: PairPotential> TerracedPotential for P {
    type Rotor = LinearRotor;

    #[inline(always)]
    fn evaluate(&self, r: DVec3, a: &DVec3, b: &DVec3) -> Result<PairEval, PotentialError> {
        PairPotential::evaluate(self, &PairGeometry::new(r, *a, *b))
    }

    #[inline(always)]
    fn energy(&self, r: DVec3, a: &DVec3, b: &DVec3) -> f64 {
        PairPotential::energy(self, &PairGeometry::new(r, *a, *b))
    }

    fn minimum(&self) -> f64 {
        PairPotential::minimum(self)
    }

    fn reach(&self, u: f64) -> Result<f64, PotentialError> {
        PairPotential::reach(self, u)
    }

    fn coordinate_intervals(&self, lo: f64, hi: f64) -> Vec<(f64, f64)> {
        PairPotential::coordinate_intervals(self, lo, hi)
    }

    #[inline(always)]
    fn taylor_model(
        &self,
        r: DVec3,
        v: DVec3,
        (ri, ti): (&LinearRotor, f64),
        (rj, tj): (&LinearRotor, f64),
        h: f64,
    ) -> Option<TaylorModel> {
        let ((s_i, ds_i), (s_j, ds_j)) = (ri.axis_and_velocity(ti), rj.axis_and_velocity(tj));
        let flight = FreeFlight {
            r,
            v,
            s_i,
            w_i: ri.omega(),
            s_j,
            w_j: rj.omega(),
            ds_i,
            ds_j,
            dds_i: s_i * -(ri.rate() * ri.rate()),
            dds_j: s_j * -(rj.rate() * rj.rate()),
            spin: ri.rate() + rj.rate(),
        };
        PairPotential::taylor_model(self, &flight, h)
    }
}

/// A [`RigidPairPotential`] between [`Top`]s: bodies of any shape on terraces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rigid<P>(pub P);

impl<P: RigidPairPotential> TerracedPotential for Rigid<P> {
    type Rotor = Top;

    #[inline]
    fn evaluate(&self, r: DVec3, a: &DQuat, b: &DQuat) -> Result<PairEval, PotentialError> {
        self.0.evaluate(&RigidGeometry::new(r, *a, *b))
    }

    #[inline]
    fn energy(&self, r: DVec3, a: &DQuat, b: &DQuat) -> f64 {
        self.0.energy(&RigidGeometry::new(r, *a, *b))
    }

    fn minimum(&self) -> f64 {
        self.0.minimum()
    }

    fn reach(&self, u: f64) -> Result<f64, PotentialError> {
        self.0.reach(u)
    }

    /// The coordinate of a rigid potential's model is `U` itself: the band is the terrace.
    fn coordinate_intervals(&self, lo: f64, hi: f64) -> Vec<(f64, f64)> {
        if self.0.certifies() {
            vec![(lo, hi)]
        } else {
            Vec::new()
        }
    }

    #[inline]
    fn taylor_model(
        &self,
        r: DVec3,
        v: DVec3,
        (ri, ti): (&Top, f64),
        (rj, tj): (&Top, f64),
        h: f64,
    ) -> Option<TaylorModel> {
        if !self.0.certifies() {
            return None;
        }
        let ((q_i, w_i), (q_j, w_j)) = (ri.pose_omega(ti), rj.pose_omega(tj));
        // |ω(τ)| ≤ min(W, |ω(0)| + Ẇτ): the bound over all time, or the start's spin grown
        // at the fastest turning over the window, whichever is smaller.
        let ((spin_i, turn_i), (spin_j, turn_j)) = (ri.spin_bounds(), rj.spin_bounds());
        let spin_i = spin_i.min(w_i.length() + turn_i * h);
        let spin_j = spin_j.min(w_j.length() + turn_j * h);
        self.0.taylor_model(
            &RigidFlight {
                r,
                v,
                q_i,
                q_j,
                w_i,
                w_j,
                spin_i,
                spin_j,
                turn_i,
                turn_j,
            },
            h,
        )
    }
}

/// The band of one terrace: the two levels around it and what crossing them costs.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Band {
    /// The level below (`−∞` for terrace 0).
    lo: f64,
    /// The level above (the hard core for the top terrace).
    hi: f64,
    /// `1 / (hi − lo)`, 0 for terrace 0.
    inv_width: f64,
    /// The range of `U` on the terrace (`hi − U_min` for terrace 0).
    width: f64,
    /// The largest centre distance at which `U` can reach either level.
    reach: f64,
    /// `ΔV` of crossing up (`+∞` into the core).
    up: f64,
    /// `ΔV` of crossing down (NaN for terrace 0).
    down: f64,
    /// The band in the potential's effective coordinate, for certified prediction (at most two
    /// intervals, the flanks of a well; unused slots are empty and never hold a pair).
    coordinate: [(f64, f64); 2],
}

impl Band {
    /// The indicator `g` and `ġ` from `U` and `U̇` (module documentation).
    #[inline(always)]
    fn indicator(&self, u: f64, du: f64) -> (f64, f64) {
        if self.inv_width == 0.0 {
            (self.hi - u, -du)
        } else {
            (
                (u - self.lo) * (self.hi - u) * self.inv_width,
                du * (self.hi + self.lo - 2.0 * u) * self.inv_width,
            )
        }
    }

    fn width(&self) -> f64 {
        self.width
    }
}

/// The terraced potential of one pair of species, ready for the event loop.
#[derive(Clone, Debug)]
pub struct PairTerraces<P> {
    potential: P,
    map: TerraceMap,
    bands: Vec<Band>,
    zero: u16,
    terraces: u16,
    reach: f64,
    reach2: f64,
    /// `U` is clamped here inside searches (deep inside the core it may overflow).
    clamp: f64,
}

/// Most terraces of one pair (stored per pair in 16 bits).
pub const MAX_TERRACES: usize = u16::MAX as usize;

/// Why a terraced model could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// The reach of a level could not be found.
    #[error("the reach of the terraces cannot be found: {0}")]
    Reach(PotentialError),
    /// More terraces than a pair can store.
    #[error(
        "{0} terraces: at most {MAX_TERRACES} are possible (raise the step ΔV or lower the core)"
    )]
    TooManyTerraces(usize),
    /// A search setting is out of range.
    #[error("bad search setting: {0}")]
    Search(SearchError),
    /// A rod's axis or angular velocity is not usable.
    #[error("body {body}: {problem}")]
    Rotor {
        /// The body.
        body: usize,
        /// What is wrong.
        problem: String,
    },
    /// A species pair has no table, or a table names a missing species.
    #[error("species pair ({0}, {1}) has no terraced potential")]
    MissingPair(usize, usize),
    /// A mass or moment of inertia is not positive and finite.
    #[error("species {species}: {what} {value} must be positive and finite")]
    Species {
        /// The species.
        species: usize,
        /// `mass` or `inertia`.
        what: &'static str,
        /// The value.
        value: f64,
    },
}

impl<P: TerracedPotential> PairTerraces<P> {
    /// The terraces of `map` on `potential`, with the reach of every band (so that a pair
    /// deep in the well is bracketed by the reach of its own terrace's levels).
    ///
    /// # Errors
    /// [`ModelError::Reach`], [`ModelError::TooManyTerraces`].
    pub fn new(potential: P, map: TerraceMap) -> Result<Self, ModelError> {
        Self::build(potential, map, true)
    }

    /// As [`new`](Self::new), but every band bracketed by the outermost reach: two reaches
    /// instead of one per level, for potentials whose reach is found numerically (Gay–Berne:
    /// about 0.1 s per level); the brackets of inner terraces are looser, the events the same.
    ///
    /// # Errors
    /// As [`new`](Self::new).
    pub fn with_outer_reach(potential: P, map: TerraceMap) -> Result<Self, ModelError> {
        Self::build(potential, map, false)
    }

    fn build(potential: P, map: TerraceMap, per_level: bool) -> Result<Self, ModelError> {
        let n = map.terraces();
        if n > MAX_TERRACES {
            return Err(ModelError::TooManyTerraces(n));
        }
        let levels = map.levels().to_vec();
        let core = map.core();
        // The reach of the outermost levels around the zero terrace (as `TerraceMap::reach`).
        let zero = map.zero_terrace();
        let above = levels.get(zero).copied().unwrap_or(core);
        let mut outer = potential.reach(above).map_err(ModelError::Reach)?;
        if let Some(&u) = levels[..zero].last() {
            outer = outer.max(potential.reach(u).map_err(ModelError::Reach)?);
        }
        let outer = outer * (1.0 + 1e-12);
        // Reach of every level, and of the core; a tiny pad covers round-off of the bracket.
        let mut level_reach = Vec::with_capacity(levels.len() + 1);
        for &u in levels.iter().chain(std::iter::once(&core)) {
            level_reach.push(if per_level {
                potential.reach(u).map_err(ModelError::Reach)? * (1.0 + 1e-12)
            } else {
                outer
            });
        }
        let energies = map.energies();
        let bands: Vec<Band> = (0..n)
            .map(|k| {
                let (lo, reach_lo) = if k == 0 {
                    (f64::NEG_INFINITY, 0.0)
                } else {
                    (levels[k - 1], level_reach[k - 1])
                };
                let hi = if k < levels.len() { levels[k] } else { core };
                Band {
                    lo,
                    hi,
                    inv_width: if k == 0 { 0.0 } else { 1.0 / (hi - lo) },
                    width: if k == 0 {
                        hi - potential.minimum()
                    } else {
                        hi - lo
                    },
                    reach: reach_lo.max(level_reach[k]),
                    up: energies
                        .get(k + 1)
                        .map_or(f64::INFINITY, |v| v - energies[k]),
                    down: if k == 0 {
                        f64::NAN
                    } else {
                        energies[k - 1] - energies[k]
                    },
                    coordinate: {
                        let mut c = [(f64::NAN, f64::NAN); 2];
                        for (slot, part) in c.iter_mut().zip(potential.coordinate_intervals(lo, hi))
                        {
                            *slot = part;
                        }
                        c
                    },
                }
            })
            .collect();
        let reach = outer;
        Ok(PairTerraces {
            clamp: 1e3 * core.abs().max(1.0),
            potential,
            zero: map.zero_terrace() as u16,
            terraces: n as u16,
            map,
            bands,
            reach,
            reach2: reach * reach,
        })
    }

    /// The smooth potential.
    pub fn potential(&self) -> &P {
        &self.potential
    }

    /// The terrace map.
    pub fn map(&self) -> &TerraceMap {
        &self.map
    }

    /// The interaction reach (the reach of the outermost levels, 003 Eq. 25 for the rods).
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// Stored value of terrace `k` (0 for the zero terrace, which is not stored).
    #[inline(always)]
    fn stored(&self, k: u16) -> u16 {
        wrap(
            u32::from(k) + u32::from(self.terraces) - u32::from(self.zero),
            self.terraces,
        )
    }

    /// Terrace of stored value `v`.
    #[inline(always)]
    fn terrace(&self, v: u16) -> u16 {
        wrap(u32::from(v) + u32::from(self.zero), self.terraces)
    }
}

/// `x mod n` for `x < 2n` (a terrace or stored value shifted by less than `n`): one compare
/// instead of an integer division, which sat on every prediction's critical path.
#[inline(always)]
fn wrap(x: u32, n: u16) -> u16 {
    let n = u32::from(n);
    debug_assert!(x < 2 * n);
    (if x >= n { x - n } else { x }) as u16
}

/// What a virtual event resumes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Pending {
    /// Start the search (the pair has just come within reach) at `at`, bracket end `end`.
    Start { at: f64, end: f64 },
    /// Continue a suspended search; the speed `U̇` at its last sample.
    Resume(SearchState, f64),
    /// Start the root search at `at` without certified jumps: the Taylor models already
    /// stopped there (a crossing may be near), bracket end `end`.
    Search { at: f64, end: f64 },
}

/// Certified prediction from `t` towards `limit`: Taylor models of the potential's effective
/// coordinate along `flight`, each proving a stretch in which `U` stays inside `band`
/// (`potential::certify`), by the model's safe time or, where that proves little (on a level
/// just crossed, or a level ahead), by its monotone window, or at a turn by its convex one.
/// Stops at `limit`, at a crossing those windows locate (returned: it needs refinement, not a
/// search), when a model proves less than `min_jump` (a crossing may be near: the root search
/// takes over), or after 32 models. Returns the time reached (at a located crossing, the time
/// of the model that located it), the models evaluated (0 for a potential without a model) and
/// the located crossing, if any.
///
/// A model stops the jumps when it proves less than `1e-3·max_step`; a model of `U` itself
/// (a rigid potential's, [`TaylorModel::spread`] > 0) when it proves less than `max_step`:
/// it costs about one evaluation of `U`, as a step of the search does.
#[inline]
fn certified_jump(
    band: &Band,
    model_at: impl Fn(f64, f64) -> Option<TaylorModel>,
    mut t: f64,
    limit: f64,
    max_step: f64,
) -> (f64, u64, Option<potential::certify::Crossing>) {
    let min_jump = 1e-3 * max_step;
    let mut models = 0;
    let mut ends: Option<(f64, f64)> = None;
    while t < limit && models < 32 {
        let h = limit - t;
        let Some(m) = model_at(t, h) else {
            break;
        };
        models += 1;
        // The interval that holds the pair (none: off its band, so prove nothing).
        let Some((a, b)) =
            ends.or_else(|| potential::certify::interval_near(&band.coordinate, m.x))
        else {
            break;
        };
        ends = Some((a, b));
        let mut tau = m.safe_time(a, b, h);
        if tau < h {
            let mut proof = m.monotone(a, b, h);
            if matches!(proof, Proof::Safe(s) if tau.max(s) < min_jump) || proof == Proof::Unknown {
                // Turning (the monotone window ends at once): the curvature may prove more.
                proof = match m.convex(a, b, h) {
                    Proof::Unknown => proof,
                    other => other,
                };
            }
            match proof {
                Proof::Safe(s) => tau = tau.max(s),
                Proof::Crossing(c) => return (t, models, Some(c)),
                Proof::Unknown => {}
            }
        }
        if tau >= h {
            t = limit;
            break;
        }
        if tau < min_jump || (m.spread > 0.0 && tau < max_step) {
            break;
        }
        t += tau;
    }
    (t, models, None)
}

/// Which level of `band` a pair reaches at a root `t` (centres `r` apart then): the one its
/// energy there is nearer to.
#[inline]
fn boundary_at<P: TerracedPotential>(
    band: &Band,
    pot: &P,
    clamp: f64,
    (ri, rj): (&Anchored<P::Rotor>, &Anchored<P::Rotor>),
    r: DVec3,
    t: f64,
) -> Boundary {
    if band.inv_width == 0.0 {
        return Boundary::Inner;
    }
    let u = pot.energy(r, &ri.pose(t), &rj.pose(t)).min(clamp);
    if u > 0.5 * (band.lo + band.hi) {
        Boundary::Inner
    } else {
        Boundary::Outer
    }
}

/// Validation mode (a fine `grid` set): searches `[from, to]` of a pair on `band` again on the
/// grid (every extremum examined) and counts the check in `stats`. A root of the fine grid
/// before `to` by more than 10⁻⁶ of the search's `max_step` is an event the search (or a
/// certified jump) stepped over: a miss, counted, and described by `describe(root)` under
/// `DMD_DEBUG_MISSES` ([`debug_miss`]).
#[allow(clippy::too_many_arguments)]
fn verify_stretch(
    grid: Option<Grid>,
    max_step: f64,
    pair_at: &impl Fn(f64) -> (f64, f64),
    band: &Band,
    from: f64,
    to: f64,
    stats: &mut SearchStats,
    describe: impl FnOnce(f64) -> String,
) {
    let Some(grid) = grid else {
        return;
    };
    stats.verified += 1;
    let mut reference = |t: f64| -> (f64, f64) {
        let (u, du) = pair_at(t);
        band.indicator(u, du)
    };
    let tol = 1e-6 * max_step;
    let missed = grid
        .start(&mut reference, from, to, Crossing::Falling, f64::INFINITY)
        .ok()
        .and_then(|r| r.root())
        .filter(|&tg| tg < to - tol);
    if let Some(root) = missed {
        stats.verify_misses += 1;
        debug_miss(pair_at, from, to, || describe(root));
    }
}

/// With the environment variable `DMD_DEBUG_MISSES` set: prints what `message` says of a miss,
/// then `U` and `U̇` at 41 points of `[from, to]`.
fn debug_miss(
    pair_at: &impl Fn(f64) -> (f64, f64),
    from: f64,
    to: f64,
    message: impl FnOnce() -> String,
) {
    if std::env::var_os("DMD_DEBUG_MISSES").is_none() {
        return;
    }
    eprintln!("{}", message());
    for q in 0..=40 {
        let t = from + (to - from) * f64::from(q) / 40.0;
        let (u, du) = pair_at(t);
        eprintln!("  t {t:.9}  U {u:.9}  dU/dt {du:.6e}");
    }
}

/// Mass and rotational inertia of one species of terraced bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodySpecies<I> {
    /// Mass.
    pub mass: f64,
    /// The rotational inertia: a rod's moment `I₁ = I₂` about axes perpendicular to its own,
    /// a top's principal moments.
    pub inertia: I,
}

/// A species of rods.
pub type RodSpecies = BodySpecies<f64>;

/// The species of the bodies of terraced potential `P`.
pub type SpeciesOf<P> = BodySpecies<<<P as TerracedPotential>::Rotor as Rotor>::Inertia>;

/// A species-pair table: the two species and their terraced potential.
pub type PairTable<P> = ((usize, usize), PairTerraces<P>);

/// Rigid bodies on terraced pair potentials (module documentation).
#[derive(Clone, Debug)]
pub struct Terraced<P: TerracedPotential> {
    n_species: usize,
    table: Vec<u32>,
    pairs: Vec<PairTerraces<P>>,
    species: Vec<SpeciesOf<P>>,
    rot: Rotations<P::Rotor>,
    states: PairStates,
    pending: SavedSearches<Pending>,
    settings: SearchSettings,
    adaptive: Adaptive,
    verify: Option<Grid>,
    /// The key of the jitter of the search steps (a hash of it, the pair and the time).
    jitter_key: u64,
    stats: SearchStats,
    reach: f64,
}

impl<P: TerracedPotential> Terraced<P> {
    /// Counters of this model's root searches so far.
    pub fn search_stats(&self) -> SearchStats {
        self.stats
    }

    /// Rods of `species` with terraced pair potentials `pairs` (every unordered pair of
    /// species once); body `i` is of species `body_species[i]` (as the loop's bodies) with
    /// initial axis `axes[i]` and lab angular velocity `omegas[i]` (its component along the
    /// axis is dropped: rods have no spin) at time `t0`; searches with `settings`, the jitter
    /// a hash of `seed`, the pair and the time a search call starts from.
    ///
    /// # Errors
    /// [`ModelError`].
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        species: Vec<SpeciesOf<P>>,
        pairs: Vec<PairTable<P>>,
        body_species: &[u32],
        poses: &[Pose<P>],
        omegas: &[DVec3],
        t0: f64,
        settings: SearchSettings,
        seed: u64,
    ) -> Result<Self, ModelError> {
        let ns = species.len();
        for (k, s) in species.iter().enumerate() {
            let mass = if s.mass.is_finite() && s.mass > 0.0 {
                Ok(())
            } else {
                Err(("mass", s.mass))
            };
            if let Err((what, value)) = mass.and_then(|()| P::Rotor::check(&s.inertia)) {
                return Err(ModelError::Species {
                    species: k,
                    what,
                    value,
                });
            }
        }
        let mut table = vec![u32::MAX; ns * ns];
        let mut tables = Vec::with_capacity(pairs.len());
        for ((a, b), terraces) in pairs {
            if a >= ns || b >= ns {
                return Err(ModelError::MissingPair(a, b));
            }
            let k = tables.len() as u32;
            tables.push(terraces);
            table[a * ns + b] = k;
            table[b * ns + a] = k;
        }
        if let Some(k) = table.iter().position(|&t| t == u32::MAX) {
            return Err(ModelError::MissingPair(k / ns, k % ns));
        }
        let reach = tables.iter().map(|t| t.reach).fold(0.0, f64::max);
        if let Some((i, &s)) = body_species
            .iter()
            .enumerate()
            .find(|&(_, &s)| s as usize >= ns)
        {
            return Err(ModelError::Rotor {
                body: i,
                problem: format!("species {s} does not exist"),
            });
        }
        let rods = poses
            .iter()
            .zip(omegas)
            .zip(body_species)
            .enumerate()
            .map(|(i, ((&pose, &w), &s))| {
                P::Rotor::start(&species[s as usize].inertia, pose, w)
                    .map(|rotor| Anchored { rotor, t: t0 })
                    .map_err(|problem| ModelError::Rotor { body: i, problem })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let adaptive = Adaptive::new(settings.max_step).map_err(ModelError::Search)?;
        let threshold = match settings.method {
            SearchMethod::Grid { threshold } => threshold,
            SearchMethod::Adaptive => 0.0,
        };
        Grid::new(settings.max_step, threshold).map_err(ModelError::Search)?;
        assert_eq!(body_species.len(), rods.len(), "one species per body");
        if settings.window.is_nan() || settings.window <= 0.0 {
            return Err(ModelError::Search(SearchError::BadSetting {
                name: "window",
                value: settings.window,
                why: "> 0",
            }));
        }
        if settings.max_change.is_nan() || settings.max_change <= 0.0 {
            return Err(ModelError::Search(SearchError::BadSetting {
                name: "max_change",
                value: settings.max_change,
                why: "> 0 (inf: off)",
            }));
        }
        if settings.horizon.is_nan() || settings.horizon < 0.0 {
            return Err(ModelError::Search(SearchError::BadSetting {
                name: "horizon",
                value: settings.horizon,
                why: ">= 0 (0: off)",
            }));
        }
        if !(0.0..0.5).contains(&settings.jitter) {
            return Err(ModelError::Search(SearchError::BadSetting {
                name: "jitter",
                value: settings.jitter,
                why: "in [0, 0.5)",
            }));
        }
        let verify = settings
            .verify_step
            .map(|s| Grid::new(s, f64::INFINITY))
            .transpose()
            .map_err(ModelError::Search)?;
        let n = rods.len();
        let inertia = species.iter().map(|s| s.inertia).collect();
        Ok(Terraced {
            n_species: ns,
            table,
            pairs: tables,
            species,
            rot: Rotations::new(rods, body_species, inertia),
            states: PairStates::new(n),
            pending: SavedSearches::new(n),
            settings,
            adaptive,
            verify,
            jitter_key: mix(seed ^ 0x6a17_7e50_0000_0007),
            stats: SearchStats::default(),
            reach,
        })
    }

    /// The pair tables.
    pub fn pairs(&self) -> &[PairTerraces<P>] {
        &self.pairs
    }

    /// The terraces of species `a` and `b`.
    #[inline(always)]
    pub fn pair(&self, a: u32, b: u32) -> &PairTerraces<P> {
        &self.pairs[self.table[a as usize * self.n_species + b as usize] as usize]
    }

    /// The stored terrace of pair `(i, j)` of species `(si, sj)`.
    #[inline(always)]
    pub fn terrace(&self, i: u32, j: u32, si: u32, sj: u32) -> usize {
        let pt = self.pair(si, sj);
        pt.terrace(self.states.get(i, j)) as usize
    }

    /// The search settings.
    pub fn settings(&self) -> &SearchSettings {
        &self.settings
    }

    /// `U` of pair `(i, j)` at `now` and separation `dr` (tests and checks).
    pub fn energy(&self, i: u32, j: u32, si: u32, sj: u32, now: f64, dr: DVec3) -> f64 {
        let (a, b) = (
            self.rot.bodies[i as usize].pose(now),
            self.rot.bodies[j as usize].pose(now),
        );
        self.pair(si, sj).potential.energy(dr, &a, &b)
    }

    /// Runs (or continues) the search of pair `(i, j)` on terrace `k` from `from`.
    #[allow(clippy::too_many_arguments)]
    fn search(
        &mut self,
        i: u32,
        j: u32,
        si: u32,
        sj: u32,
        k: u16,
        now: f64,
        dr: DVec3,
        dv: DVec3,
        from: Pending,
    ) -> Option<(f64, Kind)> {
        let pt = &self.pairs[self.table[si as usize * self.n_species + sj as usize] as usize];
        let band = pt.bands[k as usize];
        let (ri, rj) = (&self.rot.bodies[i as usize], &self.rot.bodies[j as usize]);
        let pot = &pt.potential;
        let clamp = pt.clamp;
        // U and U̇ (003 Eq. 12) at time t, U clamped deep inside the core.
        let pair_at = |t: f64| -> (f64, f64) {
            let ((a, wi), (b, wj)) = (ri.pose_omega(t), rj.pose_omega(t));
            match pot.evaluate(dr + dv * (t - now), &a, &b) {
                Ok(e) if e.energy < clamp => (e.energy, e.rate(dv, wi, wj)),
                _ => (clamp, 0.0),
            }
        };
        // Certified prediction: jump the stretch the Taylor model proves free of crossings
        // (module documentation) and schedule a virtual event at its end.
        let certify = self.settings.horizon > 0.0 && !matches!(from, Pending::Search { .. });
        let from = match from {
            Pending::Search { at, end } => Pending::Start { at, end },
            other => other,
        };
        if certify {
            let (t_start, end) = match from {
                Pending::Start { at, end } | Pending::Search { at, end } => (at.max(now), end),
                Pending::Resume(s, _) => (s.time(), s.end()),
            };
            let limit = (t_start + self.settings.horizon).min(end);
            let model_at = |t: f64, h: f64| {
                pot.taylor_model(
                    dr + dv * (t - now),
                    dv,
                    (&ri.rotor, t - ri.t),
                    (&rj.rotor, t - rj.t),
                    h,
                )
            };
            let (t, models, located) =
                certified_jump(&band, model_at, t_start, limit, self.settings.max_step);
            self.stats.taylor_models += models;
            // One crossing, proven: refine it on the coordinate itself (a model at each
            // iterate, counted as one) instead of searching `U`, by the model's quadratic,
            // stopping on its own error bound (its third-derivative bound over the bracket).
            let root = located.map(|c| {
                let sign = if c.rising { 1.0 } else { -1.0 };
                let coordinate = |tau: f64| match model_at(t + tau, c.within) {
                    Some(m) => (sign * (m.x - c.end), sign * m.dx, sign * m.ddx, m.third),
                    None => (f64::NAN, f64::NAN, f64::NAN, f64::NAN),
                };
                let tol = 1e-10 * self.settings.max_step;
                let (tau, evaluations) = taylor_root(coordinate, c.from, c.within, c.guess, tol);
                self.stats.taylor_models += u64::from(evaluations);
                t + tau
            });
            let (proven_to, how) = match root {
                Some(r) => (r, "a located crossing"),
                None => (t, "a certified jump"),
            };
            if proven_to > t_start {
                self.stats.certified_jumps += 1;
            }
            if root.is_some() || t > t_start {
                // The proven stretch, searched on the fine grid like any search interval.
                verify_stretch(
                    self.verify,
                    self.settings.max_step,
                    &pair_at,
                    &band,
                    t_start,
                    proven_to,
                    &mut self.stats,
                    |tg| {
                        format!(
                            "missed by {how}: pair ({i}, {j}) terrace {k} {band:?} from \
                             {t_start} to {proven_to}, fine grid root at {tg}"
                        )
                    },
                );
            }
            if let Some(root) = root {
                self.stats.roots += 1;
                let boundary =
                    boundary_at(&band, pot, clamp, (ri, rj), dr + dv * (root - now), root);
                return Some((root - now, Kind::Pair(boundary)));
            }
            if t > t_start {
                if t >= end {
                    return None;
                }
                // Safe up to the horizon: certify again from there. Stopped short of it (a
                // crossing may be near): the root search waits for a virtual event at the end
                // of the proven stretch, so a prediction thrown away before then (either body
                // changes first, the fate of many) costs no search and no root refinement.
                let next = if t >= limit {
                    Pending::Start { at: t, end }
                } else {
                    Pending::Search { at: t, end }
                };
                // Saved under the event's time as the loop computes it (`now + dt`, which
                // need not equal `t` in binary64): under `t` a virtual event could miss its
                // saved state, and the pair would go unpredicted until one of the two changed.
                let dt = t - now;
                self.pending.set(i, j, now + dt, next);
                return Some((dt, Kind::Virtual));
            }
        }
        let (t0, end, speed) = match from {
            Pending::Start { at, end } | Pending::Search { at, end } => {
                (at.max(now), end, f64::NAN)
            }
            Pending::Resume(s, udot) => (s.time(), s.end(), udot.abs()),
        };
        // A start evaluates its first sample here: its U checks the stored terrace and its U̇
        // limits the steps. The search then finds that sample in the cache.
        let first = match from {
            Pending::Start { .. } | Pending::Search { .. } => Some(pair_at(t0)),
            Pending::Resume(..) => None,
        };
        let speed = first.map_or(speed, |(_, du)| du.abs());
        let mut last = (t0, speed);
        let mut indicator = |t: f64| -> (f64, f64) {
            let (u, du) = match first {
                Some(x) if t == t0 => x,
                _ => pair_at(t),
            };
            if t >= last.0 {
                last = (t, du.abs());
            }
            band.indicator(u, du)
        };
        let jitter = jitter_factor(self.settings.jitter, self.jitter_key, i, j, t0);
        // The step follows the speed of U: at most `max_change` of the terrace's width per
        // step at the speed of the call's first sample (never below 1 % of the maximum step).
        let mut step = self.settings.max_step * jitter;
        if self.settings.max_change < f64::INFINITY && speed > 0.0 {
            let limit = self.settings.max_change * band.width / speed;
            step = step.min(limit.max(0.01 * self.settings.max_step));
        }
        let window = self.settings.window;
        // A bracket without end (no relative motion: only rotation changes U) needs a window.
        let window = if end == f64::INFINITY && window == f64::INFINITY {
            1e4 * self.settings.max_step
        } else {
            window
        };
        let result = match (self.settings.method, from) {
            (SearchMethod::Adaptive, Pending::Start { .. } | Pending::Search { .. }) => self
                .adaptive
                .with_max_step(step)
                .and_then(|m| m.start(&mut indicator, t0, end, Crossing::Falling, window)),
            (SearchMethod::Adaptive, Pending::Resume(s, _)) => self
                .adaptive
                .with_max_step(step)
                .and_then(|m| m.resume(&mut indicator, s, window)),
            (SearchMethod::Grid { threshold }, Pending::Start { .. } | Pending::Search { .. }) => {
                Grid::new(step, threshold)
                    .and_then(|m| m.start(&mut indicator, t0, end, Crossing::Falling, window))
            }
            (SearchMethod::Grid { threshold }, Pending::Resume(s, _)) => {
                Grid::new(step, threshold).and_then(|m| m.resume(&mut indicator, s, window))
            }
        };
        self.stats.searches += 1;
        let report = match result {
            Ok(r) => r,
            Err(_) => {
                self.stats.failures += 1;
                return None;
            }
        };
        // The cached first sample was evaluated once, here.
        self.stats.evaluations += u64::from(report.evals.max(1));
        if let Some((u0, _)) = first {
            // A pair that starts a search off its terrace has missed an event before.
            let tol = 1e-6 * band.width;
            if u0 < band.lo - tol || u0 > band.hi + tol {
                self.stats.off_terrace += 1;
            }
        }
        let checked_to = match report.outcome {
            root_search::Outcome::Root(r) => r.t,
            root_search::Outcome::Suspended(s) => s.time(),
            root_search::Outcome::NoRoot => end,
        };
        // The same interval, searched again from where this call started.
        verify_stretch(
            self.verify,
            self.settings.max_step,
            &pair_at,
            &band,
            t0,
            checked_to,
            &mut self.stats,
            |tg| {
                format!(
                    "missed: pair ({i}, {j}) terrace {k} {band:?} search from {t0} to \
                     {checked_to} (resumed: {}), fine grid root at {tg}",
                    matches!(from, Pending::Resume(..))
                )
            },
        );
        match report.outcome {
            root_search::Outcome::Root(r) => {
                self.stats.roots += 1;
                let boundary = boundary_at(&band, pot, clamp, (ri, rj), dr + dv * (r.t - now), r.t);
                Some((r.t - now, Kind::Pair(boundary)))
            }
            root_search::Outcome::Suspended(s) => {
                self.stats.suspended += 1;
                // The last sample is the state's (the search never samples past it).
                let udot = if last.0 == s.time() { last.1 } else { f64::NAN };
                let dt = s.time() - now;
                self.pending.set(i, j, now + dt, Pending::Resume(s, udot));
                Some((dt, Kind::Virtual))
            }
            root_search::Outcome::NoRoot => None,
        }
    }
}

impl<P: TerracedPotential> PairModel for Terraced<P> {
    fn reach(&self) -> f64 {
        self.reach
    }

    fn n_species(&self) -> usize {
        self.n_species
    }

    fn mass(&self, s: u32) -> f64 {
        self.species[s as usize].mass
    }

    fn setup_pair(&mut self, pair: &Pair) -> Result<(), PairSetupError> {
        let Pair {
            i, j, si, sj, dr, ..
        } = *pair;
        let t = self.rot.bodies[i as usize].t;
        let u = self.energy(i, j, si, sj, t, dr);
        let pt = self.pair(si, sj);
        let k = pt
            .map
            .terrace_of(u)
            .map_err(|_| PairSetupError::InsideCore {
                energy: u,
                core: pt.map.core(),
            })?;
        let v = pt.stored(k as u16);
        if v != 0 {
            self.states.set(i, j, v);
        }
        Ok(())
    }

    #[inline]
    fn predict(&mut self, pair: &Pair) -> Option<(f64, Kind)> {
        let Pair {
            i,
            j,
            si,
            sj,
            now,
            dr,
            dv,
        } = *pair;
        let pt = self.pair(si, sj);
        let k = if dr.length_squared() > pt.reach2 {
            pt.zero
        } else {
            pt.terrace(self.states.get(i, j))
        };
        let band = pt.bands[k as usize];
        // The bracket: while the centres are within the band's reach.
        let (start, end) = bracket(dr, dv, band.reach * band.reach)?;
        if start.is_nan() || end.is_nan() {
            self.stats.failures += 1;
            return None;
        }
        let (start, end) = (now + start, now + end);
        if start > now {
            // Not yet within reach: start searching when the pair gets there.
            self.stats.deferred += 1;
            let dt = start - now;
            self.pending
                .set(i, j, now + dt, Pending::Start { at: start, end });
            return Some((dt, Kind::Virtual));
        }
        self.search(
            i,
            j,
            si,
            sj,
            k,
            now,
            dr,
            dv,
            Pending::Start { at: now, end },
        )
    }

    fn resume(&mut self, pair: &Pair) -> Option<(f64, Kind)> {
        let Pair {
            i,
            j,
            si,
            sj,
            now,
            dr,
            dv,
        } = *pair;
        let from = self.pending.take(i, j, now)?;
        let pt = self.pair(si, sj);
        let k = pt.terrace(self.states.get(i, j));
        self.search(i, j, si, sj, k, now, dr, dv, from)
    }

    fn execute(
        &mut self,
        pair: &Pair,
        boundary: Boundary,
        vi: &mut DVec3,
        vj: &mut DVec3,
    ) -> Result<Executed, collide::CollideError> {
        let Pair {
            i,
            j,
            si,
            sj,
            now,
            dr,
            ..
        } = *pair;
        let table = self.table[si as usize * self.n_species + sj as usize] as usize;
        let pt = &self.pairs[table];
        let v = self.states.get(i, j);
        let k = pt.terrace(v);
        let band = pt.bands[k as usize];
        let (ri, rj) = (self.rot.bodies[i as usize], self.rot.bodies[j as usize]);
        let ((ai, wi), (aj, wj)) = (ri.pose_omega(now), rj.pose_omega(now));
        let skipped = |overlap| Executed {
            class: PairClass::Skipped,
            delta_u: 0.0,
            virial: 0.0,
            overlap,
        };
        let Ok(e) = pt.potential.evaluate(dr, &ai, &aj) else {
            // Deep inside the core (beyond binary64): the terraces were stepped over.
            return Ok(skipped(true));
        };
        let udot = e.rate(*vi - *vj, wi, wj);
        let (level, step, right_way) = match boundary {
            Boundary::Inner => (band.hi, band.up, udot > 0.0),
            Boundary::Outer => (band.lo, band.down, udot < 0.0),
        };
        // U must be at the level up to the root tolerance (1e-10 of the step, in time) and
        // round-off; anything more is an event that was not where it was predicted.
        let root_tol = 1e-10 * self.settings.max_step;
        let tol = 1e-9 * (level.abs() + band.width()) + 8.0 * udot.abs() * root_tol;
        let off = (e.energy - level).abs();
        if off.is_nan() || off > tol {
            self.stats.misfits += 1;
        }
        if !right_way {
            return Ok(skipped(false));
        }
        let spi = self.species[si as usize];
        let spj = self.species[sj as usize];
        let bi = P::Rotor::body(spi.mass, &spi.inertia, &ai)?;
        let bj = P::Rotor::body(spj.mass, &spj.inertia, &aj)?;
        let out = terrace(
            &bi,
            &bj,
            Velocity::new(*vi, wi),
            Velocity::new(*vj, wj),
            &PairForce::new(e.force, e.torque_i, e.torque_j),
            step,
        )?;
        *vi = out.i.linear;
        *vj = out.j.linear;
        let unusable = |_| collide::CollideError::NotFinite("angular velocity after the impulse");
        self.rot
            .restart(i, ai, out.i.angular, now)
            .map_err(unusable)?;
        self.rot
            .restart(j, aj, out.j.angular, now)
            .map_err(unusable)?;
        let class = match (out.impulse.outcome, boundary) {
            (Outcome::Reflected, Boundary::Inner) if step == f64::INFINITY => PairClass::Core,
            (Outcome::Reflected, _) => PairClass::StepReflect,
            (Outcome::Crossed, Boundary::Inner) => {
                let pt = &self.pairs[table];
                self.states.set(i, j, pt.stored(k + 1));
                PairClass::StepIn
            }
            (Outcome::Crossed, Boundary::Outer) => {
                let pt = &self.pairs[table];
                self.states.set(i, j, pt.stored(k - 1));
                PairClass::StepOut
            }
        };
        Ok(Executed {
            class,
            delta_u: out.impulse.delta_v,
            virial: out.impulse.s * dr.dot(e.force),
            overlap: false,
        })
    }

    #[inline]
    fn pair_energy(&self, i: u32, j: u32, si: u32, sj: u32) -> f64 {
        let v = self.states.get(i, j);
        if v == 0 {
            return 0.0;
        }
        let pt = self.pair(si, sj);
        pt.map.energies()[pt.terrace(v) as usize]
    }

    fn check_pair(&self, pair: &Pair, listed: bool) -> Result<(), String> {
        let Pair {
            i,
            j,
            si,
            sj,
            now,
            dr,
            ..
        } = *pair;
        let pt = self.pair(si, sj);
        let d = dr.length();
        if d < pt.reach && !listed {
            return Err(format!(
                "pair ({i}, {j}) interacts at {d} but is not listed"
            ));
        }
        let u = self.energy(i, j, si, sj, now, dr);
        let stored = pt.terrace(self.states.get(i, j)) as usize;
        let expected = pt.map.terrace_of(u).map_err(|_| {
            format!(
                "pair ({i}, {j}) is inside the hard core: U = {u}, core {}",
                pt.map.core()
            )
        })?;
        if stored != expected {
            // Allowed only at the level between them, within round-off.
            let at = pt.map.levels()[stored.max(expected) - 1];
            let band = pt.bands[stored];
            if stored.abs_diff(expected) > 1 || (u - at).abs() > 1e-7 * band.width() {
                return Err(format!(
                    "pair ({i}, {j}) with U = {u} is stored on terrace {stored}, its energy says \
                     terrace {expected}"
                ));
            }
        }
        Ok(())
    }

    #[inline]
    fn forget(&mut self, i: u32) {
        self.pending.clear(i);
    }

    crate::models::rotor::rotation_hooks!(rot);

    fn report(&self) -> Report {
        let mut r = Report::default();
        self.stats.report_into(&mut r);
        r
    }

    // ----- hybrid Monte Carlo and checkpoints (009) -------------------------------------------

    #[inline]
    fn level(&self, i: u32, j: u32) -> u16 {
        self.states.get(i, j)
    }

    #[inline]
    fn set_level(&mut self, i: u32, j: u32, level: u16) {
        self.states.set(i, j, level);
    }

    fn clear_levels(&mut self) {
        self.states = PairStates::new(self.states.n_bodies());
    }

    fn storable_level(&self, si: u32, sj: u32, level: u16) -> bool {
        (si as usize) < self.n_species
            && (sj as usize) < self.n_species
            && level != 0
            && level < self.pair(si, sj).terraces
    }

    fn configured_level(&self, pair: &Pair, stored: u16) -> (u16, f64) {
        let Pair {
            i,
            j,
            si,
            sj,
            now,
            dr,
            ..
        } = *pair;
        let pt = self.pair(si, sj);
        let u = self.energy(i, j, si, sj, now, dr);
        let Ok(expected) = pt.map.terrace_of(u) else {
            // Inside the hard core (or U not a number): at contact, on the top terrace.
            return (pt.stored(pt.terraces - 1), f64::INFINITY);
        };
        let kept = pt.terrace(stored) as usize;
        // The stored terrace stands if U is on it, or beside it within round-off of the level
        // between them (an event executed there), as in `check_pair`.
        let k = if kept == expected
            || (kept.abs_diff(expected) == 1
                && (u - pt.map.levels()[kept.max(expected) - 1]).abs()
                    <= 1e-7 * pt.bands[kept].width())
        {
            kept
        } else {
            expected
        };
        let v = pt.stored(k as u16);
        let energy = if v == 0 { 0.0 } else { pt.map.energies()[k] };
        (v, energy)
    }

    fn extra_state(&self) -> Vec<f64> {
        let mut x = Vec::with_capacity(self.rot.numbers() + STATS_NUMBERS);
        self.rot.write(&mut x);
        for c in self.stats.counts() {
            push_count(&mut x, c);
        }
        x
    }

    fn set_extra_state(&mut self, state: &[f64]) -> Result<(), String> {
        let mut r = StateReader::new(state);
        let rotations = r.take(self.rot.numbers(), "the bodies' rotations")?;
        let mut c = [0u64; STATS_NUMBERS / 2];
        for x in &mut c {
            *x = r.count("a search counter")?;
        }
        r.finish()?;
        self.rot.read(rotations)?;
        self.stats = SearchStats::from_counts(c);
        Ok(())
    }
}

/// Numbers of the search counters in [`PairModel::extra_state`] (two per counter).
const STATS_NUMBERS: usize = 24;

/// A lab angular velocity for a rod with axis `axis` drawn from equipartition at `kt`: each of
/// the two components perpendicular to the axis Gaussian with variance `kT / I`.
pub fn draw_omega(axis: DVec3, inertia: f64, kt: f64, rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    <LinearRotor as Rotor>::draw(&inertia, axis, kt, rng)
}

/// The terraces of an isotropic potential as the radial steps of a stepped potential: the
/// equivalent `[radius, ΔU]` table of [`StepPotential`](crate::engine::potential::StepPotential),
/// whose event times are analytic (no root search), with the hard core where `U = U_core`.
///
/// A negative level `U_m` is crossed twice along `r`: on the attractive branch (outer radius,
/// inwards the pair falls from terrace `m + 1` to `m`) and on the repulsive branch (inner
/// radius, inwards it climbs back); a positive level only on the repulsive branch.
///
/// # Errors
/// The profile's errors (a level below the minimum, or never reached).
pub fn radial_steps<F: Fn(f64) -> f64>(
    profile: &potential::Profile<F>,
    map: &TerraceMap,
) -> Result<Vec<[f64; 2]>, PotentialError> {
    let v = map.energies();
    let mut steps = vec![[profile.inner_radius(map.core())?, f64::INFINITY]];
    for (m, &u) in map.levels().iter().enumerate() {
        let climb = v[m + 1] - v[m];
        steps.push([profile.inner_radius(u)?, climb]);
        if u < 0.0 {
            steps.push([profile.outer_radius(u)?, -climb]);
        }
    }
    steps.sort_by(|a, b| a[0].total_cmp(&b[0]));
    Ok(steps)
}

/// Checks the certified model of a rigid potential along the exact free motion of a pair
/// of tops: `|U(τ) − U − U̇τ| ≤ Kτ²/2` at 200 points of the window. Returns how much of the
/// bound the remainder used at most (`None` where the potential offers no model or the start
/// lies on the core). Shared by the property tests of every rigid potential with a model
/// (here and in `config::kinds`).
#[cfg(test)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn check_rigid_model<R: RigidPairPotential>(
    pot: &Rigid<R>,
    moments: DVec3,
    r: DVec3,
    v: DVec3,
    (qa, qb): (DQuat, DQuat),
    (wa, wb): (DVec3, DVec3),
    h: f64,
) -> Result<Option<f64>, proptest::test_runner::TestCaseError> {
    use crate::models::rotor::TopInertia;
    use proptest::prop_assert;
    let inertia = TopInertia::new(moments).unwrap();
    let ri = Top::start(&inertia, qa.normalize(), wa).unwrap();
    let rj = Top::start(&inertia, qb.normalize(), wb).unwrap();
    let Some(m) = pot.taylor_model(r, v, (&ri, 0.0), (&rj, 0.0), h) else {
        return Ok(None);
    };
    prop_assert!(m.ddx == 0.0 && m.third == 0.0 && m.spread >= 0.0);
    let energy = |tau: f64| pot.energy(r + v * tau, &ri.pose(tau), &rj.pose(tau));
    prop_assert!((energy(0.0) - m.x).abs() <= 1e-12 * (1.0 + m.x.abs()));
    if m.x.abs() >= 1e4 {
        return Ok(None);
    }
    let mut used = 0f64;
    for k in 1..=200 {
        let tau = h * f64::from(k) / 200.0;
        let rest = energy(tau) - m.x - m.dx * tau;
        let bound = 0.5 * m.spread * tau * tau;
        prop_assert!(
            rest.abs() <= bound + 1e-9 * (1.0 + m.x.abs()),
            "τ = {tau}: remainder {rest} beyond {bound} (K = {})",
            m.spread
        );
        if bound > 0.0 {
            used = used.max(rest.abs() / bound);
        }
    }
    Ok(Some(used))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use root_search::sphere_window;

    proptest! {
        /// The bracket agrees with the reference of `root_search`.
        #[test]
        fn bracket_matches_sphere_window(
            r in prop::array::uniform3(-3.0f64..3.0),
            v in prop::array::uniform3(-2.0f64..2.0),
            radius in 0.5f64..2.0,
        ) {
            let (dr, dv) = (DVec3::from(r), DVec3::from(v));
            prop_assume!(dv.length() > 1e-3);
            let ours = bracket(dr, dv, radius * radius);
            let reference = sphere_window(r, v, radius).unwrap().and_then(|w| w.after(0.0));
            match (ours, reference) {
                (Some((a, b)), Some((c, d))) => {
                    prop_assert!((a - c).abs() <= 1e-9 * (1.0 + c.abs()), "enter {a} vs {c}");
                    prop_assert!((b - d).abs() <= 1e-9 * (1.0 + d.abs()), "exit {b} vs {d}");
                }
                (None, None) => {}
                (x, y) => {
                    // Only a course tangent to within round-off may be judged differently.
                    let b = dr.dot(dv);
                    let closest = (dr - dv * (b / dv.length_squared())).length();
                    prop_assert!((closest - radius).abs() < 1e-7, "{x:?} vs {y:?}");
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(96))]
        /// The certified models of the rigid water potentials (SPC/E's sites, SSD/E's dipole
        /// and sticky terms; asymmetric tops) hold along the exact free motion, from contact
        /// to beyond the cut-off, at thermal and at ten times thermal spin.
        #[test]
        fn rigid_water_models_bound_the_exact_motion(
            dir in prop::array::uniform3(-1.0f64..1.0),
            dist in 2.4f64..11.5,
            v in prop::array::uniform3(-8.0f64..8.0),
            qa in prop::array::uniform4(-1.0f64..1.0),
            qb in prop::array::uniform4(-1.0f64..1.0),
            wa in prop::array::uniform3(-30.0f64..30.0),
            wb in prop::array::uniform3(-30.0f64..30.0),
            fast in prop::bool::ANY,
            h in 1e-4f64..2e-2,
        ) {
            let dir = DVec3::from(dir);
            prop_assume!(dir.length() > 0.1);
            let (qa, qb) = (DQuat::from_array(qa), DQuat::from_array(qb));
            prop_assume!(qa.length() > 0.1 && qb.length() > 0.1);
            let spin = if fast { 10.0 } else { 1.0 };
            let (r, v) = (dir.normalize() * dist, DVec3::from(v));
            let w = (DVec3::from(wa) * spin, DVec3::from(wb) * spin);
            check_rigid_model(
                &Rigid(potential::SiteSite::spc_e()),
                DVec3::from(potential::site_site::SPC_E_MOMENTS),
                r, v, (qa, qb), w, h,
            )?;
            check_rigid_model(
                &Rigid(potential::SoftStickyDipole::ssd_e()),
                potential::SoftStickyDipole::INERTIA,
                r, v, (qa, qb), w, h,
            )?;
        }
    }

    /// The stored value of the zero terrace is 0 (not stored), every terrace round-trips, and
    /// each band's reach covers both of its levels and never exceeds the outermost reach.
    #[test]
    fn terrace_storage_and_band_reaches() {
        let rod = potential::LjRod::new(1.0, 1.0, 0.3).unwrap();
        let map =
            TerraceMap::evenly_spaced(&rod, 0.3, &potential::TerraceOptions::default()).unwrap();
        let pt = PairTerraces::new(rod, map).unwrap();
        assert_eq!(pt.stored(pt.zero), 0);
        for k in 0..pt.terraces {
            assert_eq!(pt.terrace(pt.stored(k)), k);
        }
        for (k, b) in pt.bands.iter().enumerate() {
            assert!(b.reach <= pt.reach * (1.0 + 1e-12), "terrace {k}");
            for level in [b.lo, b.hi] {
                if level.is_finite() {
                    assert!(
                        PairPotential::reach(&rod, level).unwrap() <= b.reach,
                        "terrace {k}, level {level}"
                    );
                }
            }
        }
        // The zero terrace's reach is the outermost one (003 Eq. 25 for the rods).
        assert_eq!(pt.bands[pt.zero as usize].reach, pt.reach);
        let outer = PairTerraces::with_outer_reach(rod, pt.map.clone()).unwrap();
        assert!(outer.bands.iter().all(|b| b.reach == pt.reach));
    }

    /// Lennard-Jones terraces as radial steps: the energy at any distance is the terrace of
    /// U there, far pairs at 0, a hard core where U reaches the core.
    #[test]
    fn radial_steps_reproduce_the_terraces() {
        let lj = potential::LennardJones::new(1.0, 1.0).unwrap();
        let map =
            TerraceMap::evenly_spaced(&lj, 0.3, &potential::TerraceOptions::default()).unwrap();
        let prof = potential::profile::lennard_jones(&lj).unwrap();
        let steps = radial_steps(&prof, &map).unwrap();
        let stepped = crate::engine::potential::StepPotential::new(&steps);
        assert_eq!(stepped.core(), Some(steps[0][0]));
        for k in 1..400 {
            let r = 0.9 + 2.0 * f64::from(k) / 400.0;
            let u = lj.energy_at(r);
            let expected = map.value(u);
            assert!(
                (stepped.energy_at(r) - expected).abs() < 1e-12,
                "r = {r}: {} vs {expected}",
                stepped.energy_at(r)
            );
        }
    }

    /// Two current events of one pair (a pair that left the neighbour list and came back with
    /// neither body changing is predicted again): the stale one finds nothing when due, and
    /// the live one resumes its own saved search. Untagged, the stale event consumed the live
    /// one's saved state and continued it from the wrong time.
    #[test]
    fn a_stale_virtual_event_does_not_consume_the_live_ones_search() {
        let rod = potential::LjRod::new(1.0, 1.0, 0.3).unwrap();
        let map =
            TerraceMap::evenly_spaced(&rod, 0.3, &potential::TerraceOptions::default()).unwrap();
        let axes = [DVec3::X, DVec3::Y];
        let omegas = [DVec3::new(0.0, 0.0, 1.0), DVec3::new(1.0, 0.0, 0.0)];
        let species = RodSpecies {
            mass: 1.0,
            inertia: 0.1,
        };
        let mut settings = SearchSettings::paper(0.01);
        settings.jitter = 0.0;
        let mut model = Terraced::new(
            vec![species],
            vec![((0, 0), PairTerraces::new(rod, map).unwrap())],
            &[0, 0],
            &axes,
            &omegas,
            0.0,
            settings,
            1,
        )
        .unwrap();
        // Well within reach, slowly approaching: every call stops at its window.
        let (dr, dv) = (DVec3::new(1.6, 0.1, 0.0), DVec3::new(-0.05, 0.0, 0.0));
        let (dt1, k1) = model
            .predict(&Pair {
                i: 0,
                j: 1,
                si: 0,
                sj: 0,
                now: 0.0,
                dr,
                dv,
            })
            .unwrap();
        assert_eq!(k1, Kind::Virtual);
        let later = 0.25 * dt1;
        let (dt2, k2) = model
            .predict(&Pair {
                i: 0,
                j: 1,
                si: 0,
                sj: 0,
                now: later,
                dr: dr + dv * later,
                dv,
            })
            .unwrap();
        assert_eq!(k2, Kind::Virtual);
        let (t1, t2) = (dt1, later + dt2);
        assert!(t2 > t1, "{t1} {t2}");
        // The stale event is due first: nothing to continue.
        assert_eq!(
            model.resume(&Pair {
                i: 0,
                j: 1,
                si: 0,
                sj: 0,
                now: t1,
                dr: dr + dv * t1,
                dv
            }),
            None
        );
        // The live one continues its search from where the second call stopped.
        let (dt3, _) = model
            .resume(&Pair {
                i: 0,
                j: 1,
                si: 0,
                sj: 0,
                now: t2,
                dr: dr + dv * t2,
                dv,
            })
            .expect("the live virtual event resumes its search");
        assert!(dt3 > 0.0);
        // Taken once: the same event cannot be resumed twice.
        let t3 = t2 + dt3;
        assert_eq!(
            model.resume(&Pair {
                i: 0,
                j: 1,
                si: 0,
                sj: 0,
                now: t2,
                dr: dr + dv * t2,
                dv
            }),
            None
        );
        assert!(
            model
                .resume(&Pair {
                    i: 0,
                    j: 1,
                    si: 0,
                    sj: 0,
                    now: t3,
                    dr: dr + dv * t3,
                    dv
                })
                .is_some()
        );
    }

    #[test]
    fn bands_watch_both_levels() {
        let b = Band {
            lo: -1.0,
            hi: 0.5,
            inv_width: 1.0 / 1.5,
            width: 1.5,
            reach: 2.0,
            up: 0.5,
            down: -0.5,
            coordinate: [(f64::NAN, f64::NAN); 2],
        };
        // Positive inside, zero on either level, negative outside; slopes of ±U̇ at the levels.
        assert!(b.indicator(0.0, 1.0).0 > 0.0);
        assert_eq!(b.indicator(-1.0, 2.0), (0.0, 2.0));
        assert_eq!(b.indicator(0.5, 2.0), (0.0, -2.0));
        assert!(b.indicator(0.7, 0.0).0 < 0.0 && b.indicator(-1.2, 0.0).0 < 0.0);
        // Terrace 0: only the level above.
        let b0 = Band {
            lo: f64::NEG_INFINITY,
            inv_width: 0.0,
            ..b
        };
        assert_eq!(b0.indicator(0.25, 3.0), (0.25, -3.0));
    }
}
