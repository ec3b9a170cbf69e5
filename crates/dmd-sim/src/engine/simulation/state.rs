//! The loop's state at a re-basing of the time origin, for hybrid Monte Carlo segments and
//! checkpoints, and the energy of a configuration from its distances.
//!
//! **Why at a re-basing.** Right after the time origin moved to the present, every body's
//! clock is zero and every event list and the schedule are a pure function of the stored
//! state: they are rebuilt by predicting, body by body in index order, from the bodies, their
//! neighbour lists (in their order) and the pair levels. So [`SimState`] holds only that stored
//! state (bodies, cells and neighbour lists in their order, pair levels, energies, accumulators,
//! timers, the thermostat's generator), and [`Simulation::from_state`] rebuilds the rest the
//! way a re-basing does: a run continued from a saved state is bit-identical to one that never
//! stopped. The loop pauses at a re-basing when asked ([`Simulation::set_pause_at_rebase`]);
//! that pause changes nothing of the trajectory (the end of a phase given in time is kept, and
//! the integrals have nothing to flush at a re-basing).
//!
//! **Energy from distances.** The loop trusts stored pair levels; a missed event leaves a level
//! that no longer matches its pair's distance (or two hard cores overlapping).
//! [`Simulation::true_energy`] evaluates the potential energy from the distances, keeping the
//! stored level only where the distance is within round-off of the boundary it was stored at
//! (as the debug check does), and `+∞` for a hard-core overlap: the `H` of HMC (000 §V).

use glam::DVec3;
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

use super::{Phase, Simulation, Skip};
use crate::engine::body::Body;
use crate::engine::cell::CellGrid;
use crate::engine::event::EventLists;
use crate::engine::fault::Blindfold;
use crate::engine::model::{Pair, PairModel};
use crate::engine::neighbour::{self, NeighbourLists};
use crate::engine::schedule::Scheduler;
use crate::engine::simulation::{Andersen, Anomalies, Counters, FRAME_STREAMS, LoopSettings};
use crate::engine::sum::Compensated;

/// One body's record.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyRecord {
    /// Position at the body's clock.
    pub r: DVec3,
    /// The clock (0 at a re-basing).
    pub t: f64,
    /// Velocity.
    pub v: DVec3,
    /// Species.
    pub species: u32,
    /// Generation (lazy invalidation).
    pub generation: u32,
}

/// The stored state of a simulation at a re-basing of the time origin (see the module
/// documentation): everything but the event lists and the schedule, which are rebuilt from it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimState {
    /// Box edge lengths.
    pub lengths: DVec3,
    /// Bodies.
    pub bodies: Vec<BodyRecord>,
    /// Box crossings per body.
    pub images: Vec<[i32; 3]>,
    /// Neighbour-list centres.
    pub centres: Vec<DVec3>,
    /// Packed cell of each body's centre.
    pub cell_of: Vec<u32>,
    /// Bodies per cell (linear cell index), then the bodies of every cell in their order.
    pub cell_len: Vec<u32>,
    /// See `cell_len`.
    pub cell_bodies: Vec<u32>,
    /// Entries per body, then every body's neighbour entries in their order.
    pub nbr_len: Vec<u32>,
    /// See `nbr_len`.
    pub nbr_entries: Vec<u32>,
    /// Pairs `(i, j, level)`, `i < j`, off level 0.
    pub levels: Vec<(u32, u32, u16)>,
    /// The model's own state ([`PairModel::extra_state`]).
    pub model_extra: Vec<f64>,
    /// Present time (0 at a re-basing).
    pub now: f64,
    /// Time of the origin since the start of the run.
    pub epoch: Compensated,
    /// Counters of the phase.
    pub counters: Counters,
    /// Anomalies of the phase.
    pub anomalies: Anomalies,
    /// Tracked kinetic energy (translational and rotational).
    pub kinetic: f64,
    /// Tracked translational kinetic energy.
    pub translational: f64,
    /// Tracked potential energy.
    pub potential: f64,
    /// Phase accumulators: start, last change, virial, `∫K dt`, `∫U dt`.
    pub phase: (f64, f64, Compensated, Compensated, Compensated),
    /// Phase accumulator `∫K_trans dt`.
    pub translational_integral: Compensated,
    /// Thermostat `(rate, temperature)`.
    pub thermostat: Option<(f64, f64)>,
    /// The thermostat's generator.
    pub rng: Xoshiro256PlusPlus,
    /// Timers: next thermostat collision, sample, frame of each stream, end.
    pub timers: (f64, f64, [f64; FRAME_STREAMS], f64),
    /// Sampling and frame intervals.
    pub sample_dt: Option<f64>,
    /// See `sample_dt`.
    pub frame_dt: [Option<f64>; FRAME_STREAMS],
    /// Loop settings: re-basing interval, seed, debug-check interval, skin, start time.
    pub settings: (u64, u64, u64, f64, f64),
    /// Events since the last debug check.
    pub since_check: u64,
    /// Scheduler statistics of replaced schedulers, and requeued bodies.
    pub sched_stats: (u64, u64, u64, u64),
    /// Momenta refreshed by HMC (3N degrees of freedom).
    pub refreshed_momenta: bool,
}

/// A saved state that does not fit (a checkpoint of another scene, or a damaged one).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the saved state does not fit the scene: {0}")]
pub struct StateError(pub String);

/// The energy of the present configuration from its distances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrueEnergy {
    /// Kinetic energy (translational and the model's rotational).
    pub kinetic: f64,
    /// Potential energy from the distances (`+∞` if hard cores overlap).
    pub potential: f64,
    /// Pairs inside a hard core by more than round-off.
    pub overlaps: u64,
    /// Pairs whose stored level differs from the one their distance gives (missed step events).
    pub mismatched: u64,
}

impl TrueEnergy {
    /// `H = K + U`.
    pub fn total(&self) -> f64 {
        self.kinetic + self.potential
    }
}

impl<M, S> Simulation<M, S>
where
    M: PairModel,
    S: Scheduler,
{
    /// Asks [`run`](Self::run) to return at every re-basing of the time origin (a checkpoint
    /// can be saved there); [`take_paused`](Self::take_paused) says whether it did.
    pub fn set_pause_at_rebase(&mut self, on: bool) {
        self.pause_at_rebase = on;
    }

    /// Whether the last [`run`](Self::run) returned at a re-basing before its stop; clears it.
    pub fn take_paused(&mut self) -> bool {
        std::mem::take(&mut self.paused)
    }

    /// The simulated time left of a phase given in time, after a pause.
    pub fn remaining_time(&self) -> f64 {
        self.end - self.now
    }

    /// Whether the state is at a re-basing: present time 0 and every clock at 0.
    pub fn at_origin(&self) -> bool {
        self.now == 0.0 && self.bodies.iter().all(|b| b.t == 0.0)
    }

    /// The model, mutably (HMC refreshes rotations through it).
    pub fn model_mut(&mut self) -> &mut M {
        &mut self.model
    }

    /// The stored state; call it at a re-basing ([`at_origin`](Self::at_origin)).
    pub fn save_state(&self) -> SimState {
        debug_assert!(self.at_origin(), "a state is saved at a re-basing");
        let n = self.bodies.len() as u32;
        let mut cell_len = Vec::with_capacity(self.cells.n_cells());
        let mut cell_bodies = Vec::with_capacity(self.bodies.len());
        for c in 0..self.cells.n_cells() {
            let b = self.cells.bodies(c);
            cell_len.push(b.len() as u32);
            cell_bodies.extend_from_slice(b);
        }
        let mut nbr_len = Vec::with_capacity(self.bodies.len());
        let mut nbr_entries = Vec::new();
        let mut levels = Vec::new();
        for i in 0..n {
            let l = self.nbrs.of(i);
            nbr_len.push(l.len() as u32);
            nbr_entries.extend_from_slice(l);
            for &e in l {
                let j = neighbour::partner(e);
                if j > i {
                    let level = self.model.level(i, j);
                    if level > 0 {
                        levels.push((i, j, level));
                    }
                }
            }
        }
        let (a, b, c) = self.old_stats;
        SimState {
            lengths: self.lengths,
            bodies: self
                .bodies
                .iter()
                .map(|b| BodyRecord {
                    r: b.r,
                    t: b.t,
                    v: b.v,
                    species: b.species,
                    generation: b.generation,
                })
                .collect(),
            images: self.images.clone(),
            centres: self.centres.clone(),
            cell_of: self.cell_of.clone(),
            cell_len,
            cell_bodies,
            nbr_len,
            nbr_entries,
            levels,
            model_extra: self.model.extra_state(),
            now: self.now,
            epoch: self.epoch,
            counters: self.counters,
            anomalies: self.anomalies,
            kinetic: self.kinetic,
            translational: self.translational,
            potential: self.potential,
            phase: (
                self.phase.start,
                self.phase.last_change,
                self.phase.virial,
                self.phase.kinetic_integral,
                self.phase.potential_integral,
            ),
            translational_integral: self.phase.translational_integral,
            thermostat: self.thermostat.map(|t| (t.rate, t.temperature)),
            rng: self.rng.clone(),
            timers: (
                self.next_thermostat,
                self.next_sample,
                self.next_frame,
                self.end,
            ),
            sample_dt: self.sample_dt,
            frame_dt: self.frame_dt,
            settings: (
                self.settings.rebase_events,
                self.settings.seed,
                self.settings.debug_check_events,
                self.settings.skin,
                self.settings.start_time,
            ),
            since_check: self.since_check,
            sched_stats: (a, b, c, self.requeued),
            refreshed_momenta: self.refreshed_momenta,
        }
    }

    /// A simulation continuing from a saved state with `model` (built from the same scene):
    /// the event lists and the schedule are rebuilt as a re-basing builds them, so the run
    /// goes on bit for bit.
    ///
    /// # Errors
    /// [`StateError`] if the state does not fit the model (sizes, species, indices, levels).
    pub fn from_state(model: M, state: &SimState) -> Result<Self, StateError> {
        let n = state.bodies.len();
        let settings = LoopSettings {
            rebase_events: state.settings.0,
            seed: state.settings.1,
            debug_check_events: state.settings.2,
            skin: state.settings.3,
            start_time: state.settings.4,
        };
        let reach = model.reach();
        let list_radius = reach + 2.0 * settings.skin;
        let cells = CellGrid::new(state.lengths, list_radius, n).map_err(|a| {
            StateError(format!(
                "the box {} has fewer than 2 cells along axis {a}",
                state.lengths
            ))
        })?;
        let n_species = model.n_species() as u32;
        let masses: Vec<f64> = (0..n_species).map(|s| model.mass(s)).collect();
        let shifts = neighbour::shift_table(state.lengths);
        let mut sim = Simulation {
            blindfold: Blindfold::default(),
            sample_attitudes: false,
            bodies: Vec::new(),
            cell_of: Vec::new(),
            images: Vec::new(),
            masses,
            cells,
            centres: Vec::new(),
            nbrs: NeighbourLists::new(n),
            shifts,
            skin2: settings.skin * settings.skin,
            list2: list_radius * list_radius,
            scratch_old: Vec::with_capacity(64),
            scratch_new: Vec::with_capacity(64),
            marks: vec![0; n],
            mark_epoch: 0,
            lists: EventLists::new(n),
            model,
            sched: S::with_participants(n + 1),
            old_stats: (0, 0, 0),
            requeued: 0,
            system: n as u32,
            now: 0.0,
            epoch: Compensated::ZERO,
            lengths: state.lengths,
            half: state.lengths * 0.5,
            counters: Counters::default(),
            anomalies: Anomalies::default(),
            kinetic: 0.0,
            translational: 0.0,
            potential: 0.0,
            phase: Phase::default(),
            thermostat: None,
            rng: state.rng.clone(),
            next_thermostat: f64::INFINITY,
            sample_dt: None,
            next_sample: f64::INFINITY,
            frame_dt: [None; FRAME_STREAMS],
            next_frame: [f64::INFINITY; FRAME_STREAMS],
            end: f64::INFINITY,
            settings,
            since_rebase: 0,
            since_check: 0,
            nan: None,
            pause_at_rebase: false,
            paused: false,
            refreshed_momenta: false,
            cancel: None,
            stop_request: None,
            stop_seen: None,
        };
        sim.restore_state(state, true)?;
        Ok(sim)
    }

    /// Puts a saved state of this simulation back (an HMC rejection), and with `predict`
    /// rebuilds the event lists and the schedule (without, the caller must refresh the
    /// momenta, which predicts everything, before the loop runs again).
    ///
    /// # Errors
    /// [`StateError`] if the state does not fit (then nothing usable is left: the caller
    /// gives up).
    pub fn restore_state(&mut self, state: &SimState, predict: bool) -> Result<(), StateError> {
        let n = self.marks.len();
        if state.lengths != self.lengths {
            return Err(StateError(format!(
                "its box is {}, the scene's {}",
                state.lengths, self.lengths
            )));
        }
        check_fits(state, n, &self.model, &self.cells, self.settings.skin)?;
        self.bodies.clear();
        self.bodies.extend(state.bodies.iter().map(|b| Body {
            r: b.r,
            t: b.t,
            v: b.v,
            species: b.species,
            generation: b.generation,
        }));
        self.images.clone_from(&state.images);
        self.centres.clone_from(&state.centres);
        self.cell_of.clone_from(&state.cell_of);
        let list_radius = self.model.reach() + 2.0 * self.settings.skin;
        self.cells = CellGrid::new(self.lengths, list_radius, n)
            .map_err(|_| StateError("the box is too small for its cells".into()))?;
        let mut k = 0;
        for (c, &len) in state.cell_len.iter().enumerate() {
            for &i in &state.cell_bodies[k..k + len as usize] {
                if self.cells.linear(self.cell_of[i as usize]) != c {
                    return Err(StateError(format!(
                        "body {i} is listed in cell {c}, its centre is in another"
                    )));
                }
                self.cells.insert(i, self.cell_of[i as usize]);
            }
            k += len as usize;
        }
        let mut k = 0;
        for (i, &len) in state.nbr_len.iter().enumerate() {
            self.nbrs
                .replace(i as u32, &state.nbr_entries[k..k + len as usize]);
            k += len as usize;
        }
        self.model.clear_levels();
        for &(i, j, level) in &state.levels {
            self.model.set_level(i, j, level);
        }
        self.model
            .set_extra_state(&state.model_extra)
            .map_err(StateError)?;
        self.now = state.now;
        self.epoch = state.epoch;
        self.counters = state.counters;
        self.anomalies = state.anomalies;
        self.kinetic = state.kinetic;
        self.translational = state.translational;
        self.potential = state.potential;
        let (start, last_change, virial, kint, uint) = state.phase;
        self.phase = Phase {
            start,
            virial,
            kinetic_integral: kint,
            translational_integral: state.translational_integral,
            potential_integral: uint,
            last_change,
        };
        self.thermostat = state
            .thermostat
            .map(|(rate, temperature)| Andersen { rate, temperature });
        self.rng = state.rng.clone();
        (
            self.next_thermostat,
            self.next_sample,
            self.next_frame,
            self.end,
        ) = state.timers;
        self.sample_dt = state.sample_dt;
        self.frame_dt = state.frame_dt;
        self.since_rebase = 0;
        self.since_check = state.since_check;
        let (a, b, c, r) = state.sched_stats;
        self.refreshed_momenta = state.refreshed_momenta;
        for i in 0..n as u32 {
            self.lists.clear(i);
        }
        if predict {
            for i in 0..n as u32 {
                self.predict(i, Skip::Lower);
            }
            // The model's counters as saved, without the rebuilt predictions (see
            // `PairModel::set_extra_state`).
            self.model
                .set_extra_state(&state.model_extra)
                .map_err(StateError)?;
        }
        self.rebuild_schedule();
        // `rebuild_schedule` folded the statistics of the scheduler it replaced: put back the
        // saved totals (a re-basing leaves exactly these).
        self.old_stats = (a, b, c);
        self.requeued = r;
        Ok(())
    }

    /// Moves the time origin to the present like a re-basing, without predicting: every body
    /// brought to now with its clock at 0. The event lists and the schedule are stale until
    /// the momenta are refreshed ([`refresh_momenta`](Self::refresh_momenta)) or a saved state
    /// is restored with prediction.
    pub(crate) fn move_origin_here(&mut self) {
        self.flush_integrals();
        let t0 = self.now;
        // The model's per-body state (attitudes) comes along, as in `rebase`.
        for b in &mut self.bodies {
            b.sync(t0);
            b.t = 0.0;
        }
        self.model.rebase(t0);
        self.epoch.add(t0);
        self.now = 0.0;
        self.phase.start -= t0;
        self.phase.last_change -= t0;
        self.next_thermostat -= t0;
        self.next_sample -= t0;
        for next in &mut self.next_frame {
            *next -= t0;
        }
        self.end -= t0;
        self.since_rebase = 0;
    }

    /// Lets `refresh` change the velocities (every body at the present time `now`, its
    /// second argument, with the masses per species and the model for rotations), then
    /// predicts every event afresh (which makes the model forget its saved searches).
    pub(crate) fn refresh_momenta(
        &mut self,
        refresh: impl FnOnce(&mut [Body], f64, &[f64], &mut M),
    ) {
        self.flush_integrals();
        let now = self.now;
        for b in &mut self.bodies {
            b.sync(now);
        }
        refresh(&mut self.bodies, now, &self.masses, &mut self.model);
        self.kinetic = self.kinetic_energy();
        self.translational = self.translational_kinetic();
        self.predict_all();
    }

    /// Reverses every velocity (an HMC rejection, 000 §V); predictions are stale until the next
    /// refresh of the momenta.
    pub(crate) fn reverse_momenta(&mut self) {
        for b in &mut self.bodies {
            b.v = -b.v;
        }
        self.model.reverse_rotations();
    }

    /// Marks the momenta as refreshed from their Gaussian distribution by HMC (the kinetic
    /// temperature then counts 3N degrees of freedom).
    pub(crate) fn set_refreshed_momenta(&mut self, on: bool) {
        self.refreshed_momenta = on;
    }

    /// Kinetic and potential energy of the present configuration, the potential from the
    /// distances (see the module documentation). Every pair within the reach is in the
    /// neighbour lists whatever events were missed: shell crossings are never skipped.
    pub fn true_energy(&self) -> TrueEnergy {
        let mut u = Compensated::ZERO;
        let (mut overlaps, mut mismatched) = (0, 0);
        self.for_each_interacting_pair(|_, _, stored, level, e| {
            if level != stored || e == f64::INFINITY {
                mismatched += 1;
            }
            if e == f64::INFINITY {
                overlaps += 1;
            } else if e != 0.0 {
                u.add(e);
            }
        });
        TrueEnergy {
            kinetic: self.kinetic_energy(),
            potential: if overlaps > 0 {
                f64::INFINITY
            } else {
                u.value()
            },
            overlaps,
            mismatched,
        }
    }

    /// Stores the levels the distances give (keeping stored levels within round-off of their
    /// boundary), forgetting every other stored level: after an accepted HMC segment in which
    /// events were missed. The tracked potential energy is recomputed.
    pub(crate) fn repair_levels(&mut self) {
        let mut found = Vec::new();
        self.for_each_interacting_pair(|i, j, _, level, _| {
            // A pair left inside a hard core (only when every segment is accepted, a validation
            // comparison) is put at contact (the level `configured_level` gives it): the loop
            // then reflects it, counting an overlap.
            if level > 0 {
                found.push((i, j, level));
            }
        });
        self.model.clear_levels();
        for (i, j, level) in found {
            self.model.set_level(i, j, level);
        }
        self.flush_integrals();
        self.potential = self.potential_energy();
    }

    /// Calls `f(i, j, stored level, level, energy)` for every listed pair `i < j` that is
    /// stored off level 0 or closer than the reach, and every body with itself that
    /// [`PairModel::self_pairs`] says interacts, with the level and energy its configuration
    /// gives ([`PairModel::configured_level`]).
    fn for_each_interacting_pair(&self, mut f: impl FnMut(u32, u32, u16, u16, f64)) {
        let reach = self.model.reach();
        let now = self.now;
        for i in 0..self.bodies.len() as u32 {
            let bi = &self.bodies[i as usize];
            let ri = bi.position_at(now);
            for &e in self.nbrs.of(i) {
                let j = neighbour::partner(e);
                if j < i {
                    continue;
                }
                let bj = &self.bodies[j as usize];
                let dr = (ri - self.shifts[neighbour::code(e) as usize]) - bj.position_at(now);
                let stored = self.model.level(i, j);
                if stored == 0 && dr.length_squared() >= reach * reach {
                    continue;
                }
                let (level, energy) = self.model.configured_level(
                    &Pair {
                        i,
                        j,
                        si: bi.species,
                        sj: bj.species,
                        now,
                        dr,
                        dv: bi.v - bj.v,
                    },
                    stored,
                );
                f(i, j, stored, level, energy);
            }
            if M::SELF_PAIRS && self.model.self_pairs(bi.species) {
                let (level, energy) = self
                    .model
                    .configured_level(&Pair::own(i, bi.species, now), 0);
                f(i, i, 0, level, energy);
            }
        }
    }
}

/// Checks that a saved state fits a simulation of `n` bodies with `model` (never a panic on a
/// damaged or foreign checkpoint).
fn check_fits<M: PairModel>(
    s: &SimState,
    n: usize,
    model: &M,
    cells: &CellGrid,
    skin: f64,
) -> Result<(), StateError> {
    let bad = |m: String| Err(StateError(m));
    if s.bodies.len() != n {
        return bad(format!("it has {} bodies, the scene {n}", s.bodies.len()));
    }
    let (a, b, c, d) = s.timers;
    if [a, b, d].iter().chain(&c).any(|t| t.is_nan())
        || s.sample_dt.is_some_and(|x| !(x.is_finite() && x > 0.0))
        || s.frame_dt
            .iter()
            .flatten()
            .any(|&x| !(x.is_finite() && x > 0.0))
        || !(s.now.is_finite() && s.kinetic.is_finite() && s.potential.is_finite())
        || s.settings.0 == 0
    {
        return bad("its timers, energies or settings are not valid numbers".into());
    }
    if s.settings.3 != skin {
        return bad(format!(
            "its neighbour-list skin is {}, the simulation's {skin}",
            s.settings.3
        ));
    }
    for (name, len) in [
        ("images", s.images.len()),
        ("centres", s.centres.len()),
        ("cells of bodies", s.cell_of.len()),
        ("neighbour lists", s.nbr_len.len()),
    ] {
        if len != n {
            return bad(format!("it has {len} {name} for {n} bodies"));
        }
    }
    if let Some((i, im)) = s
        .images
        .iter()
        .enumerate()
        .find(|(_, im)| im.iter().any(|k| k.unsigned_abs() > super::MAX_IMAGE))
    {
        return bad(format!(
            "body {i} has crossed the box {im:?} times, more than any run (at most {} each way)",
            super::MAX_IMAGE
        ));
    }
    if s.cell_len.len() != cells.n_cells() {
        return bad(format!(
            "it has {} cells, the box {}",
            s.cell_len.len(),
            cells.n_cells()
        ));
    }
    let n_species = model.n_species() as u32;
    for (i, b) in s.bodies.iter().enumerate() {
        if b.species >= n_species {
            return bad(format!(
                "body {i} has species {}, the scene {n_species} species",
                b.species
            ));
        }
        if !(b.r.is_finite() && b.v.is_finite() && b.t.is_finite()) {
            return bad(format!("body {i} has a non-finite state"));
        }
    }
    let cells_sum: u64 = s.cell_len.iter().map(|&x| u64::from(x)).sum();
    if cells_sum != n as u64
        || s.cell_bodies.len() != n
        || s.cell_bodies.iter().any(|&i| i as usize >= n)
    {
        return bad("its cells do not hold every body once".into());
    }
    let mut seen = vec![false; n];
    for &i in &s.cell_bodies {
        if std::mem::replace(&mut seen[i as usize], true) {
            return bad(format!("body {i} is in two cells"));
        }
    }
    let nbr_sum: u64 = s.nbr_len.iter().map(|&x| u64::from(x)).sum();
    if nbr_sum != s.nbr_entries.len() as u64
        || s.nbr_entries
            .iter()
            .any(|&e| neighbour::partner(e) as usize >= n || neighbour::code(e) >= 27)
    {
        return bad("its neighbour lists name bodies that do not exist".into());
    }
    for &(i, j, level) in &s.levels {
        if i >= j || j as usize >= n {
            return bad(format!("it stores a level for the pair ({i}, {j})"));
        }
        let (si, sj) = (s.bodies[i as usize].species, s.bodies[j as usize].species);
        if !model.storable_level(si, sj, level) {
            return bad(format!(
                "pair ({i}, {j}) is stored on level {level}, which its potential does not have \
                 outside a hard core"
            ));
        }
    }
    let dims = cells.dims();
    let grid_ok = |p: u32| {
        let c = crate::engine::cell::unpack(p);
        (0..3).all(|a| c[a] < dims[a])
    };
    if s.cell_of.iter().any(|&p| !grid_ok(p)) {
        return bad("a cell index is out of range".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::engine::potential::StepPotential;

    #[test]
    fn stored_levels_are_kept_only_within_round_off_of_their_boundary() {
        // Hard core 1, shoulder to 1.2, well to 1.5: levels 0 (out), 1 (1.2–1.5), 2 (1–1.2),
        // 3 (core).
        let pot = StepPotential::new(&[[1.0, f64::INFINITY], [1.2, 0.5], [1.5, -1.0]]);
        assert_eq!(pot.true_level(1, 1.3), 1);
        // Just outside 1.5 after an inward crossing executed there: still level 1.
        assert_eq!(pot.true_level(1, 1.5 * (1.0 + 1e-12)), 1);
        // Clearly outside: the distance wins (a missed outward step).
        assert_eq!(pot.true_level(1, 1.6), 0);
        // Two levels away is never round-off.
        assert_eq!(pot.true_level(0, 1.1), 2);
        // At contact by round-off: not an overlap.
        assert_eq!(pot.true_level(2, 1.0 - 1e-13), 2);
        // Inside the core by more: the core level (+∞ energy).
        assert_eq!(pot.true_level(2, 0.99), 3);
        assert_eq!(pot.levels()[3].energy, f64::INFINITY);
    }
}
