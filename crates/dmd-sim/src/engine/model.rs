//! Interaction models: how a pair's next event is predicted and executed.
//!
//! A scene picks its model once and the event loop is compiled for it ([`PairModel`] is a
//! generic parameter of the event loop's `Simulation`, never a trait object):
//!
//! - [`HardSpheres`]: every pair table is one infinite step. Nothing is stored per pair; the
//!   prediction is one quadratic, the execution one reflection.
//! - [`Stepped`]: general staircases (square wells, stepped Lennard-Jones, soft steps, mixtures).
//!   The level of every interacting pair is stored ([`PairStates`]); a prediction solves the
//!   quadratic of the one or two boundaries of the pair's level.
//!
//! Both give **analytic** event times: the relative centre moves on a straight line between
//! events, so reaching radius `R` solves `v² t² + 2 b t + (r² − R²) = 0`, `b = r·v`. Each root is
//! taken in the form without cancellation (`c / (−b + √D)` entering, `−c / (b + √D)` leaving
//! while receding), as in `root_search::sphere_window`, which the tests use as the reference.
//! A rigid-body model implements the same trait with root searches bracketed by the
//! reach sphere, and may return virtual events.

use collide::{Outcome, Particle, spheres};
use glam::{DQuat, DVec3};

use crate::engine::event::{Boundary, Kind};
use crate::engine::pair_state::PairStates;
use crate::engine::potential::{Level, Potentials, StepPotential};

/// What executing a pair event did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairClass {
    /// Reflection at a hard core.
    Core,
    /// Crossed a finite step inwards.
    StepIn,
    /// Crossed a finite step outwards.
    StepOut,
    /// Reflected by a finite step (not enough kinetic energy to climb it).
    StepReflect,
    /// Nothing done: the pair was found moving away from the boundary it was to cross (a
    /// grazing event decided by round-off). Counted as an anomaly.
    Skipped,
}

/// The result of a pair event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Executed {
    /// What happened.
    pub class: PairClass,
    /// Potential energy gained by the pair.
    pub delta_u: f64,
    /// `r_ij · Δp_i`: the pair's contribution to the collision virial.
    pub virial: f64,
    /// The pair was inside a hard core by more than round-off.
    pub overlap: bool,
}

/// Relative tolerance on squared distances below which an overlap counts as round-off.
pub const OVERLAP_TOLERANCE: f64 = 1e-9;

/// Why a pair cannot start where it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PairSetupError {
    /// The centres are closer than the hard-core diameter.
    Overlap {
        /// Their distance.
        distance: f64,
        /// The hard-core diameter.
        core: f64,
    },
    /// The smooth pair potential is at or above the hard-core level of the terrace map (the
    /// bodies overlap more than the terraced potential allows).
    InsideCore {
        /// `U` of the pair.
        energy: f64,
        /// The hard-core level.
        core: f64,
    },
}

/// One pair as the loop hands it to a model at time `now`: the bodies `i`, `j`, their species
/// `si`, `sj`, their separation `dr = r_i − r_j` at the minimum image and relative velocity
/// `dv = v_i − v_j` (both at `now`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// The first body.
    pub i: u32,
    /// The second body.
    pub j: u32,
    /// Species of `i`.
    pub si: u32,
    /// Species of `j`.
    pub sj: u32,
    /// The loop's time.
    pub now: f64,
    /// `r_i − r_j` at `now`, minimum image.
    pub dr: DVec3,
    /// `v_i − v_j`.
    pub dv: DVec3,
}

impl Pair {
    /// Body `i` (of species `s`) with itself at `now` ([`PairModel::self_pairs`]).
    #[inline]
    pub fn own(i: u32, s: u32, now: f64) -> Pair {
        Pair {
            i,
            j: i,
            si: s,
            sj: s,
            now,
            dr: DVec3::ZERO,
            dv: DVec3::ZERO,
        }
    }
}

/// An interaction model for the event loop.
///
/// The loop knows bodies only by their translational record ([`Body`](crate::engine::body::Body));
/// everything else a model needs (stored pair levels, orientations, saved searches) it keeps
/// itself, indexed like the bodies. The rotation hooks have do-nothing defaults, so spheres pay
/// nothing for them: the loop is compiled per model and the calls vanish.
pub trait PairModel {
    /// The largest distance at which two bodies interact (the smallest cell side).
    fn reach(&self) -> f64;

    /// Number of species.
    fn n_species(&self) -> usize;

    /// The mass of species `s`.
    fn mass(&self, s: u32) -> f64;

    /// Sets up the stored state of pair `(i, j)`, of species `(si, sj)`, at separation
    /// `dr = r_i − r_j` (initial configuration; called once per pair within the neighbour-list
    /// radius).
    ///
    /// # Errors
    /// The pair overlaps a hard core.
    fn setup_pair(&mut self, pair: &Pair) -> Result<(), PairSetupError>;

    /// The next event of pair `(i, j)`, of species `(si, sj)`, whose relative position and
    /// velocity are `dr = r_i − r_j` and `dv = v_i − v_j` at time `now`: the time from now and
    /// its kind ([`Kind::Pair`] or, for models with root searches, [`Kind::Virtual`]).
    fn predict(&mut self, pair: &Pair) -> Option<(f64, Kind)>;

    /// Whether [`predict_before`](Self::predict_before) drops events later than its horizon.
    /// A model that does is predicted with the time its body leaves the neighbour-list skin as
    /// the horizon, and a body's list is predicted afresh from all its neighbours when it
    /// rebuilds its neighbour list, so nothing dropped is ever missed.
    const PRUNES: bool = false;

    /// [`predict`](Self::predict), but a model with [`PRUNES`](Self::PRUNES) may return `None`
    /// for a pair whose next event is certainly later than `horizon` (time from now), without
    /// computing it.
    #[inline(always)]
    fn predict_before(&mut self, pair: &Pair, _horizon: f64) -> Option<(f64, Kind)> {
        self.predict(pair)
    }

    /// A virtual event of owner `i` with partner `j` has come due (both unchanged since it was
    /// scheduled): continue the pair's search. Models without virtual events never get one.
    fn resume(&mut self, _pair: &Pair) -> Option<(f64, Kind)> {
        None
    }

    /// Executes a pair event at time `now` and separation `dr = r_i − r_j`, updating the
    /// velocities and the stored pair state (and, for rigid bodies, the angular velocities the
    /// model keeps).
    ///
    /// # Errors
    /// The impulse rule's error for a non-finite state (a broken invariant upstream).
    fn execute(
        &mut self,
        pair: &Pair,
        boundary: Boundary,
        vi: &mut DVec3,
        vj: &mut DVec3,
    ) -> Result<Executed, collide::CollideError>;

    /// The potential energy of pair `(i, j)` on its stored level.
    fn pair_energy(&self, i: u32, j: u32, si: u32, sj: u32) -> f64;

    /// Checks the stored state of pair `(i, j)` at separation `dr` at time `now` against the
    /// geometry (debug invariant checks): the stored level matches the distance or potential
    /// (up to round-off at a boundary), no hard core overlaps, and a pair that interacts is
    /// `listed` in the neighbour lists.
    ///
    /// # Errors
    /// A description of the violation.
    fn check_pair(&self, pair: &Pair, listed: bool) -> Result<(), String>;

    /// Whether any body of this model may interact with itself ([`self_pairs`](Self::self_pairs));
    /// without, the loop carries no code for it.
    const SELF_PAIRS: bool = false;

    /// Whether a body of species `s` interacts with itself (sites of one semi-flexible
    /// molecule that its bonds leave free to meet; only asked when [`SELF_PAIRS`](Self::SELF_PAIRS)).
    /// The loop then treats the pair `(i, i)` as any other, with `dr = dv = 0`: it sets it
    /// up, predicts, executes and checks it, and counts its energy; an impulse within one body
    /// leaves its centre velocity unchanged.
    #[inline(always)]
    fn self_pairs(&self, _s: u32) -> bool {
        false
    }

    /// Body `i`'s event list was cleared: predictions saved for it may go.
    #[inline(always)]
    fn forget(&mut self, _i: u32) {}

    /// The time origin moves to `t0` (every body is brought to it first).
    #[inline(always)]
    fn rebase(&mut self, _t0: f64) {}

    // ----- Hybrid Monte Carlo and checkpoints ----------------------------------------------------
    // The stored pair levels are opaque numbers to the loop (0: not stored); only the model
    // knows what they mean. Hooks of the per-body state have defaults that do nothing, right
    // for spheres (no state beyond the `Body` record and the pair levels); the rigid model
    // keeps attitudes and angular velocities in its own arrays and implements them (see
    // docs/ARCHITECTURE.md, "Hybrid Monte Carlo").

    /// The stored level of pair `(i, j)` (0 when nothing is stored).
    fn level(&self, i: u32, j: u32) -> u16;

    /// Stores a level for pair `(i, j)` (a saved state, or HMC's repair of levels).
    fn set_level(&mut self, i: u32, j: u32, level: u16);

    /// Forgets every stored pair level (every pair back on level 0). HMC calls it before it
    /// sets the levels a configuration gives, after a segment with missed events.
    #[inline(always)]
    fn clear_levels(&mut self) {}

    /// Whether `level` is a level a pair of species `(si, sj)` can be stored on outside a hard
    /// core (checks of a saved state).
    fn storable_level(&self, si: u32, sj: u32, level: u16) -> bool;

    /// The level and energy of pair `(i, j)` (species `si`, `sj`, separation `dr = r_i − r_j`
    /// at time `now`) judged from its configuration, not from its events: the stored level
    /// `stored` if the configuration is on it or within round-off of its boundary, else the
    /// level the configuration gives. Inside a hard core the energy is `+∞` and the level the
    /// one just outside the core (where HMC's repair puts such a pair, at contact). The `U`
    /// of HMC's `ΔH`. Spheres read the radial step potential of the species pair; the rigid
    /// model evaluates its terrace from the attitudes at `now`.
    fn configured_level(&self, pair: &Pair, stored: u16) -> (u16, f64);

    /// Rotational kinetic energy of all bodies (0 for spheres; part of the HMC Hamiltonian).
    #[inline(always)]
    fn rotational_kinetic(&self) -> f64 {
        0.0
    }

    /// Rotational degrees of freedom of all bodies together (0 for spheres, 2 per rod).
    #[inline(always)]
    fn rotational_dof(&self) -> f64 {
        0.0
    }

    /// A thermostat collision of body `i` (species `s`) at `now`: draws its angular velocity
    /// afresh at temperature `kt`; returns the change of rotational kinetic energy.
    #[inline(always)]
    fn thermalize(
        &mut self,
        _i: u32,
        _s: u32,
        _now: f64,
        _kt: f64,
        _rng: &mut rand_xoshiro::Xoshiro256PlusPlus,
    ) -> f64 {
        0.0
    }

    /// The spin angular momentum `I ω` of body `i` (species `s`) about its centre (lab frame).
    #[inline(always)]
    fn spin(&self, _i: u32, _s: u32) -> DVec3 {
        DVec3::ZERO
    }

    /// The lab angular velocity of body `i`.
    #[inline(always)]
    fn omega(&self, _i: u32) -> DVec3 {
        DVec3::ZERO
    }

    /// The unit long axis of body `i` at `now` (`None` for bodies without orientation).
    #[inline(always)]
    fn axis(&self, _i: u32, _now: f64) -> Option<DVec3> {
        None
    }

    /// The whole attitude of body `i` at `now`: the unit quaternion that rotates body-frame
    /// vectors into the lab frame (`None` for bodies without orientation, spheres, and for
    /// molecules without a rigid attitude). Each model documents its body frame. Called when a
    /// trajectory frame is written, never on the event path.
    fn attitude(&self, _i: u32, _now: f64) -> Option<DQuat> {
        None
    }

    /// The atoms of body `i` at `now` when the body has no rigid attitude and moves its atoms
    /// itself (semi-flexible molecules): their positions relative to the body's centre and
    /// their velocities relative to the centre's, both in the lab frame (`None` for every
    /// other body, and when the model cannot compute them). Called when a trajectory frame is
    /// written.
    fn atoms(&self, _i: u32, _now: f64) -> Option<(Vec<DVec3>, Vec<DVec3>)> {
        None
    }

    /// Kinetic energy changed by the model's own numerical integration of the free motion
    /// since the last call, beyond what the executed events' `delta_u` accounts for (taken:
    /// reported once). The loop adds it to its tracked kinetic energy after every event. Exact
    /// free motion changes nothing (0); semi-flexible molecules, whose internal motion is
    /// integrated by RATTLE, report the step's energy error as it enters at their events.
    #[inline(always)]
    fn take_kinetic_error(&mut self) -> f64 {
        0.0
    }

    /// Largest relative bond-length error of semi-flexible molecules at `now` (models with
    /// distance constraints only).
    fn bond_error_at(&self, _now: f64) -> Option<f64> {
        None
    }

    /// `ln` of the density, at time `now`, of the configuration measure that the model's free
    /// motion leaves invariant relative to the flat measure of its coordinates, up to a
    /// constant: `Σ ½ ln det Z` over molecules whose distance constraints leave internal
    /// freedom (000 §II.A), 0 for rigid bodies, whose measure is flat. HMC divides it out of
    /// the acceptance when asked to sample the stiff-spring (flexible) ensemble.
    fn log_metric(&self, _now: f64) -> f64 {
        0.0
    }

    /// Named counters of the model's own work (root searches, constraint integration): the
    /// loop and the driver read them by name, so a model adds counters without a new hook.
    fn report(&self) -> Report {
        Report::default()
    }

    /// Draws every body's angular velocity from its Gaussian (Maxwell–Boltzmann) distribution
    /// at `temperature` (the canonical HMC refresh, 000 §V), every body at time `now`. The loop
    /// re-predicts every event afterwards.
    #[inline(always)]
    fn draw_rotations(
        &mut self,
        _now: f64,
        _temperature: f64,
        _rng: &mut rand_xoshiro::Xoshiro256PlusPlus,
    ) {
    }

    /// Reverses every angular velocity (an HMC rejection reverses the momenta), every body at
    /// a re-basing of the time origin.
    #[inline(always)]
    fn reverse_rotations(&mut self) {}

    /// Multiplies every body's angular (or internal) velocity by `factor` at time `now`, each
    /// body's motion restarted there with the scaled velocity: the end of a thermostatted
    /// equilibration scales translation and rotation by one factor so that production starts
    /// at the bath temperature with the equipartition of the moment kept. The loop scales the
    /// translational velocities and re-predicts every event afterwards. Models without
    /// rotations do nothing (their rotational kinetic energy is 0); the loop reads the
    /// rotational kinetic energy back afterwards, so a model that could not scale a body
    /// leaves the loop to reach the target with the translational factor.
    #[inline(always)]
    fn scale_rotations(&mut self, _now: f64, _factor: f64) {}

    /// The model's state beyond the `Body` record and the pair levels (attitudes, angular
    /// velocities, counters), as numbers, at a re-basing of the time origin: HMC snapshots
    /// and checkpoints. Empty for spheres. What the model's predictions add (saved searches)
    /// is not part of it: the loop rebuilds every prediction from the state.
    fn extra_state(&self) -> Vec<f64> {
        Vec::new()
    }

    /// Restores what [`extra_state`](Self::extra_state) returned. The loop calls it before it
    /// rebuilds the predictions and once more after (so that counters of the model's own work
    /// end as they were saved, not counting the rebuilt predictions twice): it must not touch
    /// the predictions' saved searches.
    ///
    /// # Errors
    /// A description when `state` does not fit the model (a checkpoint of another scene).
    fn set_extra_state(&mut self, state: &[f64]) -> Result<(), String> {
        if state.is_empty() {
            Ok(())
        } else {
            Err(format!(
                "the model keeps no state beyond positions and velocities, but {} numbers were given",
                state.len()
            ))
        }
    }
}

/// Roots of `|dr + dv t|² = R²` for an approaching pair entering the sphere: the earliest
/// `t ≥ 0`, or `None` if the pair misses it.
#[inline(always)]
fn enter_time(r2: f64, b: f64, v2: f64, radius2: f64) -> Option<f64> {
    if b >= 0.0 {
        return None;
    }
    approach_time(r2, b, v2, radius2)
}

/// [`enter_time`] for a pair known to approach (`b < 0`), without testing it again (a test
/// the compiler would move before the caller's and branch on).
#[inline(always)]
fn approach_time(r2: f64, b: f64, v2: f64, radius2: f64) -> Option<f64> {
    let c = r2 - radius2;
    let disc = b * b - v2 * c;
    if disc <= 0.0 {
        return None;
    }
    Some((c / (-b + disc.sqrt())).max(0.0))
}

/// The time at which a pair inside a sphere of squared radius `radius2` leaves it.
#[inline(always)]
fn exit_time(r2: f64, b: f64, v2: f64, radius2: f64) -> Option<f64> {
    if v2 == 0.0 {
        return None;
    }
    let c = r2 - radius2;
    let disc = (b * b - v2 * c).max(0.0);
    let t = if b > 0.0 {
        -c / (b + disc.sqrt())
    } else {
        (-b + disc.sqrt()) / v2
    };
    Some(t.max(0.0))
}

/// The next boundary event of a pair on `level`.
#[inline(always)]
fn predict_level(level: &Level, r2: f64, b: f64, v2: f64) -> Option<(f64, Boundary)> {
    if level.inner2 > 0.0
        && let Some(t) = enter_time(r2, b, v2, level.inner2)
    {
        return Some((t, Boundary::Inner));
    }
    if level.outer2 < f64::INFINITY {
        return exit_time(r2, b, v2, level.outer2).map(|t| (t, Boundary::Outer));
    }
    None
}

/// Hard spheres (and hard-sphere mixtures): one infinite step per pair, nothing stored.
#[derive(Clone, Debug)]
pub struct HardSpheres {
    n_species: usize,
    /// Squared contact distance per species pair.
    sigma2: Vec<f64>,
    /// The squared contact distance of a one-species system (no table look-up per pair).
    sigma2_one: f64,
    particles: Vec<Particle>,
    potentials: Potentials,
}

impl HardSpheres {
    /// From the potentials (all bare hard cores) and the species masses.
    pub fn new(potentials: Potentials, particles: Vec<Particle>) -> Self {
        assert!(potentials.all_hard_spheres());
        let n = potentials.n_species();
        let sigma2 = (0..n * n)
            .map(|k| {
                let d = potentials
                    .get((k / n) as u32, (k % n) as u32)
                    .core()
                    .expect("hard core");
                d * d
            })
            .collect::<Vec<f64>>();
        HardSpheres {
            n_species: n,
            sigma2_one: sigma2[0],
            sigma2,
            particles,
            potentials,
        }
    }
}

impl HardSpheres {
    /// The squared contact distance of species `si` and `sj`.
    #[inline(always)]
    fn contact2(&self, si: u32, sj: u32) -> f64 {
        if self.n_species == 1 {
            self.sigma2_one
        } else {
            self.sigma2[si as usize * self.n_species + sj as usize]
        }
    }
}

impl PairModel for HardSpheres {
    fn reach(&self) -> f64 {
        self.potentials.reach()
    }

    fn n_species(&self) -> usize {
        self.n_species
    }

    fn mass(&self, s: u32) -> f64 {
        self.particles[s as usize].mass()
    }

    fn setup_pair(&mut self, pair: &Pair) -> Result<(), PairSetupError> {
        let Pair { si, sj, dr, .. } = *pair;
        setup_stepped(self.potentials.get(si, sj), dr).map(|_| ())
    }

    #[inline(always)]
    fn predict(&mut self, pair: &Pair) -> Option<(f64, Kind)> {
        let Pair { si, sj, dr, dv, .. } = *pair;
        let b = dr.dot(dv);
        if b >= 0.0 {
            return None;
        }
        let sigma2 = self.contact2(si, sj);
        approach_time(dr.length_squared(), b, dv.length_squared(), sigma2)
            .map(|t| (t, Kind::Pair(Boundary::Inner)))
    }

    const PRUNES: bool = true;

    /// Before the square root: with `a = σ² − r²` and `b = dr·dv < 0`,
    /// `|dr + dv t|² − σ² ≥ 2 b t − a > 0` for every `t ≤ horizon` once `2 b · horizon > a`,
    /// so the pair cannot touch before the horizon (Smallenburg's test).
    #[inline(always)]
    fn predict_before(&mut self, pair: &Pair, horizon: f64) -> Option<(f64, Kind)> {
        let Pair { si, sj, dr, dv, .. } = *pair;
        let b = dr.dot(dv);
        let sigma2 = self.contact2(si, sj);
        let r2 = dr.length_squared();
        // Kept only if approaching (`b < 0`) and able to touch before the horizon
        // (`2 b · horizon − a < 0`): one test of both sign bits, so one branch, where a test of
        // each (two branches) is mispredicted about once per two partners (half of them
        // recede, at random). `b + 0` turns `b = −0` into `+0` (receding); `2 b · horizon = a`
        // is a touch at the horizon at most (the shell crossing predicts afresh).
        let d = 2.0 * b * horizon - (sigma2 - r2);
        if ((b + 0.0).to_bits() & d.to_bits()) >> 63 == 0 {
            return None;
        }
        approach_time(r2, b, dv.length_squared(), sigma2).map(|t| (t, Kind::Pair(Boundary::Inner)))
    }

    #[inline(always)]
    fn execute(
        &mut self,
        pair: &Pair,
        boundary: Boundary,
        vi: &mut DVec3,
        vj: &mut DVec3,
    ) -> Result<Executed, collide::CollideError> {
        let Pair { si, sj, dr, .. } = *pair;
        debug_assert_eq!(boundary, Boundary::Inner);
        let r2 = dr.length_squared();
        let sigma2 = self.contact2(si, sj);
        let overlap = r2 < sigma2 * (1.0 - OVERLAP_TOLERANCE);
        if dr.dot(*vi - *vj) >= 0.0 {
            return Ok(Executed {
                class: PairClass::Skipped,
                delta_u: 0.0,
                virial: 0.0,
                overlap,
            });
        }
        let out = spheres(
            &self.particles[si as usize],
            &self.particles[sj as usize],
            *vi,
            *vj,
            dr,
            f64::INFINITY,
        )?;
        *vi = out.i;
        *vj = out.j;
        Ok(Executed {
            class: PairClass::Core,
            delta_u: 0.0,
            virial: out.impulse.s * r2,
            overlap,
        })
    }

    fn pair_energy(&self, _i: u32, _j: u32, _si: u32, _sj: u32) -> f64 {
        0.0
    }

    fn check_pair(&self, pair: &Pair, listed: bool) -> Result<(), String> {
        let Pair {
            i, j, si, sj, dr, ..
        } = *pair;
        check_stepped(self.potentials.get(si, sj), i, j, 0, dr.length(), listed)
    }

    #[inline(always)]
    fn level(&self, _i: u32, _j: u32) -> u16 {
        0
    }

    fn set_level(&mut self, _i: u32, _j: u32, level: u16) {
        debug_assert_eq!(level, 0, "hard spheres have no levels but 0");
    }

    fn storable_level(&self, _si: u32, _sj: u32, _level: u16) -> bool {
        false
    }

    fn configured_level(&self, pair: &Pair, stored: u16) -> (u16, f64) {
        let Pair { si, sj, dr, .. } = *pair;
        configured_step(self.potentials.get(si, sj), stored, dr)
    }
}

/// The level of a pair at separation `dr` on a stepped potential, or its overlap. A pair
/// inside the core by round-off ([`OVERLAP_TOLERANCE`]) is at contact: a configuration written
/// at a collision and read back from text sits there, and the loop makes its event at once.
fn setup_stepped(pot: &StepPotential, dr: DVec3) -> Result<usize, PairSetupError> {
    let d = dr.length();
    if let Some(core) = pot.core()
        && d < core
    {
        if d * d < core * core * (1.0 - OVERLAP_TOLERANCE) {
            return Err(PairSetupError::Overlap { distance: d, core });
        }
        return Ok(pot.level_at(core));
    }
    Ok(pot.level_at(d))
}

/// The invariants of a pair on a stepped potential at distance `d`, stored on `stored`.
fn check_stepped(
    pot: &StepPotential,
    i: u32,
    j: u32,
    stored: usize,
    d: f64,
    listed: bool,
) -> Result<(), String> {
    if d < pot.reach() && !listed {
        return Err(format!(
            "pair ({i}, {j}) interacts at {d} but is not listed"
        ));
    }
    if let Some(core) = pot.core()
        && d * d < core * core * (1.0 - OVERLAP_TOLERANCE)
    {
        return Err(format!("bodies {i} and {j} overlap: distance {d} < {core}"));
    }
    let expected = pot.level_at(d);
    if stored != expected && !pot.is_hard_sphere() {
        // Allowed only at a boundary, within round-off.
        let n = pot.radii().len();
        let k = n - stored.max(expected);
        let at = pot.radii()[k];
        if (d - at).abs() > 1e-9 * at {
            return Err(format!(
                "pair ({i}, {j}) at distance {d} is stored on level {stored}, its distance \
                 says level {expected}"
            ));
        }
    }
    Ok(())
}

/// General stepped potentials with stored pair levels.
#[derive(Clone, Debug)]
pub struct Stepped {
    potentials: Potentials,
    particles: Vec<Particle>,
    states: PairStates,
}

impl Stepped {
    /// From the potentials and species masses, for `n` bodies (all pairs on level 0).
    pub fn new(potentials: Potentials, particles: Vec<Particle>, n: usize) -> Self {
        Stepped {
            potentials,
            particles,
            states: PairStates::new(n),
        }
    }

    /// The stored pair levels.
    pub fn states(&self) -> &PairStates {
        &self.states
    }
}

impl PairModel for Stepped {
    fn reach(&self) -> f64 {
        self.potentials.reach()
    }

    fn n_species(&self) -> usize {
        self.potentials.n_species()
    }

    fn mass(&self, s: u32) -> f64 {
        self.particles[s as usize].mass()
    }

    fn setup_pair(&mut self, pair: &Pair) -> Result<(), PairSetupError> {
        let Pair {
            i, j, si, sj, dr, ..
        } = *pair;
        let level = setup_stepped(self.potentials.get(si, sj), dr)?;
        if level > 0 {
            self.states.set(i, j, level as u16);
        }
        Ok(())
    }

    #[inline(always)]
    fn predict(&mut self, pair: &Pair) -> Option<(f64, Kind)> {
        let Pair {
            i,
            j,
            si,
            sj,
            dr,
            dv,
            ..
        } = *pair;
        let levels = self.potentials.get(si, sj).levels();
        let r2 = dr.length_squared();
        let b = dr.dot(dv);
        let reach2 = levels[0].inner2;
        // Beyond the reach (by more than round-off) a pair is on level 0: no look-up.
        let level = if r2 > reach2 * (1.0 + OVERLAP_TOLERANCE) {
            if b >= 0.0 {
                return None;
            }
            0
        } else {
            self.states.get(i, j) as usize
        };
        predict_level(&levels[level], r2, b, dv.length_squared()).map(|(t, b)| (t, Kind::Pair(b)))
    }

    fn execute(
        &mut self,
        pair: &Pair,
        boundary: Boundary,
        vi: &mut DVec3,
        vj: &mut DVec3,
    ) -> Result<Executed, collide::CollideError> {
        let Pair {
            i, j, si, sj, dr, ..
        } = *pair;
        let level = self.states.get(i, j);
        let l = self.potentials.get(si, sj).levels()[level as usize];
        let r2 = dr.length_squared();
        let b = dr.dot(*vi - *vj);
        let (step, moving_right_way) = match boundary {
            Boundary::Inner => (l.dv_in, b < 0.0),
            Boundary::Outer => (l.dv_out, b > 0.0),
        };
        let overlap = step == f64::INFINITY && r2 < l.inner2 * (1.0 - OVERLAP_TOLERANCE);
        if !moving_right_way {
            return Ok(Executed {
                class: PairClass::Skipped,
                delta_u: 0.0,
                virial: 0.0,
                overlap,
            });
        }
        let out = spheres(
            &self.particles[si as usize],
            &self.particles[sj as usize],
            *vi,
            *vj,
            dr,
            step,
        )?;
        *vi = out.i;
        *vj = out.j;
        let class = match (out.impulse.outcome, boundary) {
            (Outcome::Reflected, _) if step == f64::INFINITY => PairClass::Core,
            (Outcome::Reflected, _) => PairClass::StepReflect,
            (Outcome::Crossed, Boundary::Inner) => {
                self.states.set(i, j, level + 1);
                PairClass::StepIn
            }
            (Outcome::Crossed, Boundary::Outer) => {
                self.states.set(i, j, level - 1);
                PairClass::StepOut
            }
        };
        Ok(Executed {
            class,
            delta_u: out.impulse.delta_v,
            virial: out.impulse.s * r2,
            overlap,
        })
    }

    #[inline]
    fn pair_energy(&self, i: u32, j: u32, si: u32, sj: u32) -> f64 {
        let level = self.states.get(i, j);
        if level == 0 {
            return 0.0;
        }
        self.potentials.get(si, sj).levels()[level as usize].energy
    }

    fn check_pair(&self, pair: &Pair, listed: bool) -> Result<(), String> {
        let Pair {
            i, j, si, sj, dr, ..
        } = *pair;
        let stored = self.states.get(i, j) as usize;
        check_stepped(
            self.potentials.get(si, sj),
            i,
            j,
            stored,
            dr.length(),
            listed,
        )
    }

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
        storable_step(self.potentials.get(si, sj), level)
    }

    fn configured_level(&self, pair: &Pair, stored: u16) -> (u16, f64) {
        let Pair { si, sj, dr, .. } = *pair;
        configured_step(self.potentials.get(si, sj), stored, dr)
    }
}

/// The level and energy of a pair of a radial step potential at separation `dr` whose stored
/// level is `stored` ([`PairModel::configured_level`]).
fn configured_step(pot: &StepPotential, stored: u16, dr: DVec3) -> (u16, f64) {
    let level = pot.true_level(stored as usize, dr.length());
    let energy = pot.levels()[level].energy;
    if energy == f64::INFINITY {
        // Inside the hard core: the level at contact (the core is the last level).
        (level.saturating_sub(1) as u16, energy)
    } else {
        (level as u16, energy)
    }
}

/// Whether a pair of `pot` can be stored on `level` outside its hard core.
fn storable_step(pot: &StepPotential, level: u16) -> bool {
    let top = pot.levels().len() - usize::from(pot.core().is_some());
    level > 0 && (level as usize) < top
}

impl Stepped {
    /// The stored level of pair `(i, j)` (0 when out of range).
    #[inline]
    pub fn level(&self, i: u32, j: u32) -> u16 {
        self.states.get(i, j)
    }

    /// The potentials.
    pub fn potentials(&self) -> &Potentials {
        &self.potentials
    }
}

impl HardSpheres {
    /// The potentials.
    pub fn potentials(&self) -> &Potentials {
        &self.potentials
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use root_search::sphere_window;

    proptest! {
        /// The analytic times agree with the reference bracket of `root_search`.
        #[test]
        fn event_times_match_sphere_window(
            r in prop::array::uniform3(-3.0f64..3.0),
            v in prop::array::uniform3(-2.0f64..2.0),
            radius in 0.5f64..2.0,
        ) {
            let dr = DVec3::from(r);
            let dv = DVec3::from(v);
            prop_assume!(dv.length() > 1e-3);
            let (r2, b, v2) = (dr.length_squared(), dr.dot(dv), dv.length_squared());
            let w = sphere_window(r, v, radius).unwrap();
            if r2 > radius * radius {
                match (enter_time(r2, b, v2, radius * radius), w) {
                    (Some(t), Some(w)) => prop_assert!((t - w.enter).abs() <= 1e-9 * (1.0 + t)),
                    (None, Some(w)) => prop_assert!(w.exit < 0.0 || (w.exit - w.enter) < 1e-6),
                    (Some(t), None) => {
                        // Only a course tangent to within round-off may be judged differently.
                        let closest = (dr + dv * (-b / v2)).length();
                        prop_assert!((closest - radius).abs() < 1e-9, "entered at {t}, window empty");
                    }
                    (None, None) => {}
                }
            } else {
                let t = exit_time(r2, b, v2, radius * radius).unwrap();
                let w = w.unwrap();
                prop_assert!((t - w.exit).abs() <= 1e-9 * (1.0 + t));
            }
        }
    }

    proptest! {
        /// Pruning drops only events later than the horizon, and keeps the others exactly
        /// (one species and a mixture, whose contact distances come from the table).
        #[test]
        fn hard_spheres_prune_only_beyond_the_horizon(
            r in prop::array::uniform3(-2.5f64..2.5),
            v in prop::array::uniform3(-2.0f64..2.0),
            horizon in prop_oneof![0.0f64..2.0, Just(f64::INFINITY)],
            mixture in any::<bool>(),
        ) {
            let (n, tables) = if mixture {
                (2, vec![
                    ((0, 0), vec![[1.0, f64::INFINITY]]),
                    ((0, 1), vec![[0.8, f64::INFINITY]]),
                    ((1, 1), vec![[0.6, f64::INFINITY]]),
                ])
            } else {
                (1, vec![((0, 0), vec![[1.0, f64::INFINITY]])])
            };
            let particles = vec![Particle::new(1.0).unwrap(); n];
            let mut model = HardSpheres::new(Potentials::from_tables(n, &tables), particles);
            let pair = Pair {
                i: 0,
                j: 1,
                si: 0,
                sj: (n - 1) as u32,
                now: 0.0,
                dr: DVec3::from(r),
                dv: DVec3::from(v),
            };
            let sigma = if mixture { 0.8 } else { 1.0 };
            prop_assume!(pair.dr.length() > sigma);
            let full = model.predict(&pair);
            let pruned = model.predict_before(&pair, horizon);
            match (full, pruned) {
                (Some(a), Some(b)) => prop_assert_eq!(a, b),
                (Some((t, _)), None) => prop_assert!(t > horizon, "dropped {t} ≤ {horizon}"),
                (None, Some(b)) => prop_assert!(false, "pruned found {b:?}, full none"),
                (None, None) => {}
            }
        }
    }

    #[test]
    fn pruning_rejects_receding_pairs_with_a_negative_zero() {
        let mut model = HardSpheres::new(
            Potentials::from_tables(1, &[((0, 0), vec![[1.0, f64::INFINITY]])]),
            vec![Particle::new(1.0).unwrap()],
        );
        let pair = |dr: DVec3, dv: DVec3| Pair {
            i: 0,
            j: 1,
            si: 0,
            sj: 0,
            now: 0.0,
            dr,
            dv,
        };
        // b = dr·dv = −0 (every product −0): receding for the pruned test as for the full one,
        // also inside the core, where an approaching pair would collide at once.
        for x in [-1.5, -0.9] {
            let p = pair(DVec3::new(x, -0.0, -0.0), DVec3::new(0.0, 1.0, 0.0));
            assert!(p.dr.dot(p.dv).is_sign_negative() && p.dr.dot(p.dv) == 0.0);
            assert_eq!(model.predict(&p), None);
            assert_eq!(model.predict_before(&p, 1.0), None);
        }
        // Approaching and inside the core by round-off: the event is now, pruned or not.
        let p = pair(
            DVec3::new(1.0 - 1e-16, 0.0, 0.0),
            DVec3::new(-1.0, 0.0, 0.0),
        );
        assert_eq!(model.predict_before(&p, 1.0), model.predict(&p));
        assert_eq!(model.predict_before(&p, 1.0).map(|p| p.0), Some(0.0));
    }

    #[test]
    fn grazing_and_far_pairs() {
        // Exactly tangent course, r = (−2, 1, 0), v = (1, 0, 0), R = 1: no collision (D = 0).
        assert_eq!(enter_time(5.0, -2.0, 1.0, 1.0), None);
        // Receding pair never enters.
        assert_eq!(enter_time(4.0, 0.5, 1.0, 1.0), None);
        // Inside by round-off while approaching: the event is now.
        assert_eq!(enter_time(1.0 - 1e-16, -1.0, 1.0, 1.0), Some(0.0));
        // Leaving while approaching: the far side of the sphere.
        let t = exit_time(0.25, -0.5, 1.0, 2.25).unwrap();
        assert!((t - 2.0).abs() < 1e-15);
    }
}

/// Named counters and maxima of a model's own work, in the order the model wrote them.
///
/// Counts are exact integers; maxima and other real-valued figures are stored apart, so that
/// a count never passes through a float.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    counts: Vec<(&'static str, u64)>,
    reals: Vec<(&'static str, f64)>,
}

impl Report {
    /// Records count `name`.
    pub fn count(&mut self, name: &'static str, value: u64) {
        self.counts.push((name, value));
    }

    /// Records real-valued figure `name`.
    pub fn real(&mut self, name: &'static str, value: f64) {
        self.reals.push((name, value));
    }

    /// Count `name`, if the model keeps it.
    pub fn get_count(&self, name: &str) -> Option<u64> {
        self.counts
            .iter()
            .find(|(n, _)| *n == name)
            .map(|&(_, v)| v)
    }

    /// Real-valued figure `name`, if the model keeps it.
    pub fn get_real(&self, name: &str) -> Option<f64> {
        self.reals.iter().find(|(n, _)| *n == name).map(|&(_, v)| v)
    }

    /// Every count, in the order written.
    pub fn counts(&self) -> impl Iterator<Item = (&'static str, u64)> + '_ {
        self.counts.iter().copied()
    }

    /// Every real-valued figure, in the order written.
    pub fn reals(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        self.reals.iter().copied()
    }
}
