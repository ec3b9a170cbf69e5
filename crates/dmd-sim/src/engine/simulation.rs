//! The event loop: local clocks, neighbour lists built on cells, per-body event lists, lazy
//! invalidation, re-based time origin.
//!
//! [`Simulation`] is generic over the interaction model `M` and the scheduler `S`; a scene
//! picks both once, so the loop is compiled for each pairing with no dynamic dispatch on the
//! hot path. Each body keeps the events it predicted in its own list
//! ([`EventLists`]); the scheduler holds only each body's earliest. One step takes the
//! earliest body from the scheduler and looks at the front of its list:
//!
//! - an event whose partner has changed since it was predicted (the partner's generation
//!   moved on) is dropped, and the body is rescheduled at its next event — no rescan;
//! - **pair event** `(i, j)`: bring both bodies to the event time (their local clocks), apply
//!   the model's rule, bump both generations (every event others predicted with them becomes
//!   stale), clear both lists and predict their new events with the bodies of their
//!   neighbour lists;
//! - **shell crossing** of `i` (it has moved the skin `δ` away from its list centre): wrap it
//!   into the box, move its centre (and cell) to where it is, rebuild its neighbour list from
//!   the 27 cells around it and update its neighbours' lists; its velocity did not change, so
//!   its events stay valid and only pairs that just came into the list are predicted;
//! - **system events** (the scheduler's last participant): sampling, trajectory frames,
//!   Andersen thermostat collisions, the end of a phase.
//!
//! Every `rebase_events` events the time origin moves to the present: all bodies are brought to
//! `now` and their clocks set to zero, and every event is predicted afresh (about 1 % of the run
//! time at the default interval of 100 N events), so event times never grow large enough to
//! lose digits however long the run (the total time is kept in a compensated sum). Counters and
//! generations are `u64`.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use event_queue::QueueError;
use glam::{DQuat, DVec3};
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::engine::body::Body;
use crate::engine::cell::CellGrid;
use crate::engine::event::{Boundary, Event, EventLists, Kind, SystemEvent};
use crate::engine::fault::Blindfold;
use crate::engine::model::{Executed, Pair, PairClass, PairModel, PairSetupError};
use crate::engine::neighbour::{self, NeighbourLists};
use crate::engine::schedule::Scheduler;
use crate::engine::sum::Compensated;

// Hybrid Monte Carlo segments and checkpoints: saving and restoring the state at a
// re-basing of the time origin, pausing there, and the energy of a configuration from its
// distances. A child module, so that it reaches the loop's private state.
mod state;
pub use state::{BodyRecord, SimState, StateError, TrueEnergy};

/// Most events between re-basings: generations are `u32` and every event list is rebuilt at a
/// re-basing, so no generation can wrap round while an event predicted with it waits.
pub const MAX_REBASE_EVENTS: u64 = 1 << 31;

/// Largest box crossings of a body each way that a state may hold (image counters are `i32`;
/// no run crosses a box 10⁹ times): start files and checkpoints beyond it are refused.
pub const MAX_IMAGE: u32 = 1_000_000_000;

/// Why a simulation could not go on.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The impulse rule refused the state of a pair (non-finite velocities: a broken invariant).
    #[error("impulse rule failed for bodies {i} and {j} at time {time}: {source}")]
    Collide {
        /// First body.
        i: u32,
        /// Second body.
        j: u32,
        /// Simulated time.
        time: f64,
        /// The rule's error.
        source: collide::CollideError,
    },
    /// An event time came out NaN (non-finite positions or velocities).
    #[error("an event time of body {0} is not a number: its state is not finite")]
    NanTime(u32),
    /// An output reached its size limit (`output.max_bytes`).
    #[error("{0}")]
    OutputLimit(Box<str>),
    /// Nothing will ever happen again (every body at rest), but the run asks for more events.
    #[error(
        "no events are left (the bodies neither move nor meet), {0} events short of the run length"
    )]
    NoEvents(u64),
    /// The flag of [`Simulation::set_cancel`] was raised; the state is whole and the run can
    /// go on with another call.
    #[error("cancelled by the caller")]
    Cancelled,
}

/// Why a simulation could not be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SetupError {
    /// Two bodies overlap hard cores.
    #[error(
        "bodies {i} and {j} overlap: their distance {distance:.6} is less than the hard-core diameter {core}"
    )]
    Overlap {
        /// First body.
        i: u32,
        /// Second body.
        j: u32,
        /// Their distance.
        distance: f64,
        /// The hard-core diameter of the pair.
        core: f64,
    },
    /// The box is too small for two cells of the interaction reach along an axis.
    #[error(
        "the box side {length} along {axis} is less than 2 × (the interaction range {reach} + twice \
         the skin {skin}) = {need}: the cell list needs at least two cells along each axis; use \
         more bodies, a lower density or a smaller run.skin"
    )]
    BoxTooSmall {
        /// `x`, `y` or `z`.
        axis: char,
        /// The side.
        length: f64,
        /// The reach.
        reach: f64,
        /// The neighbour-list skin.
        skin: f64,
        /// 3 × (reach + 2 skin).
        need: f64,
    },
    /// Two bodies start inside the hard core of their terraced potential.
    #[error(
        "bodies {i} and {j} overlap: their pair energy {energy:.6} is at or above the hard-core level {core} of the terraces"
    )]
    InsideCore {
        /// First body.
        i: u32,
        /// Second body.
        j: u32,
        /// Their pair energy `U`.
        energy: f64,
        /// The hard-core level.
        core: f64,
    },
    /// A position, velocity or box length is not finite.
    #[error("the initial state is not finite (body {0})")]
    NotFinite(u32),
}

/// When a phase of the run ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stop {
    /// After this many events (pair events, cell crossings, thermostat collisions).
    Events(u64),
    /// After this much simulated time.
    Time(f64),
}

/// Events executed, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Counters {
    /// All counted events (the sum of the kinds below, sampling excluded).
    pub events: u64,
    /// Reflections at a hard core.
    pub core: u64,
    /// Finite steps crossed inwards.
    pub step_in: u64,
    /// Finite steps crossed outwards.
    pub step_out: u64,
    /// Reflections at a finite step.
    pub step_reflect: u64,
    /// Shell crossings (neighbour-list rebuilds).
    pub shell: u64,
    /// Andersen thermostat collisions.
    pub thermostat: u64,
    /// Virtual events (000 §III.B): a root search resumed (or started) where its window or the
    /// bracket put it; no impulse.
    pub virtual_: u64,
    /// Samples of the observables and trajectory frames (not counted in `events`).
    pub samples: u64,
    /// Re-basings of the time origin (not counted in `events`).
    pub rebases: u64,
}

impl Counters {
    /// Pair events of all kinds.
    pub fn pair_events(&self) -> u64 {
        self.core + self.step_in + self.step_out + self.step_reflect
    }
}

/// Things that should not happen, counted instead of crashing (release builds; debug builds
/// also check the invariants periodically and stop at the first violation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Anomalies {
    /// Events popped with a time before the present.
    pub negative_time: u64,
    /// Hard-core events found overlapping by more than round-off (relative 10⁻⁹ in r²).
    pub overlap: u64,
    /// Pair events found moving away from their boundary (grazing, decided by round-off); no
    /// impulse applied.
    pub receding: u64,
}

impl Anomalies {
    /// All anomalies.
    pub fn total(&self) -> u64 {
        self.negative_time + self.overlap + self.receding
    }
}

/// What a sampler sees at a sampling event.
pub struct View<'a> {
    /// Time in the current frame (bodies' positions are `r + v (now − t)`).
    pub now: f64,
    /// Simulated time since the start of the phase.
    pub elapsed: f64,
    /// The bodies.
    pub bodies: &'a [Body],
    /// Box crossings of each body (for unwrapped positions).
    pub images: &'a [[i32; 3]],
    /// Box edge lengths.
    pub lengths: DVec3,
    /// Mass of each species.
    pub masses: &'a [f64],
    /// Kinetic energy now.
    pub kinetic: f64,
    /// Potential energy now.
    pub potential: f64,
    /// Collision virial `Σ r_ij·Δp_i` accumulated since the start of the phase.
    pub virial: f64,
    /// `∫ K dt` since the start of the phase.
    pub kinetic_integral: f64,
    /// Degrees of freedom of the kinetic temperature.
    pub dof: f64,
    /// The unit long axis of every body now (empty for bodies without orientation).
    pub axes: Vec<DVec3>,
    /// Rotational kinetic energy now (0 for spheres).
    pub rotational_kinetic: f64,
    /// Rotational degrees of freedom (included in `dof`; 0 for spheres).
    pub rotational_dof: f64,
    /// Events of the current phase so far.
    pub events: u64,
    /// The attitude of every body now ([`PairModel::attitude`]: body → lab unit
    /// quaternions), in a frame's view, and in every view when the run asks for them
    /// ([`Simulation::set_sample_attitudes`]); empty otherwise and for models without
    /// attitudes.
    pub attitudes: Vec<DQuat>,
    /// The spin angular momentum `I ω` of every body with an attitude, lab frame
    /// ([`PairModel::spin`]), in a frame's view only.
    pub spins: Vec<DVec3>,
    /// The atoms of every body without a rigid attitude ([`PairModel::atoms`]: lab positions
    /// relative to the centre, lab velocities relative to the centre's), in a frame's view
    /// only; empty for other models, shorter than `bodies` if the model could not give them.
    pub atoms: Vec<(Vec<DVec3>, Vec<DVec3>)>,
}

impl View<'_> {
    /// Position of body `i` now, in the box.
    #[inline]
    pub fn position(&self, i: usize) -> DVec3 {
        self.bodies[i].position_at(self.now)
    }

    /// Unwrapped position of body `i` now (continuous across box faces).
    #[inline]
    pub fn unwrapped(&self, i: usize) -> DVec3 {
        let im = self.images[i];
        self.position(i) + DVec3::new(im[0] as f64, im[1] as f64, im[2] as f64) * self.lengths
    }
}

/// Streams of trajectory frames the loop schedules, each with its own interval (the driver
/// gives stream 0 to `trajectory.xyz` and stream 1 to `trajectory.gsd`).
pub const FRAME_STREAMS: usize = 2;

/// Receives sampling events (observables, trajectory).
pub trait Sampler {
    /// Samples the observables.
    fn sample(&mut self, _view: &View<'_>) {}
    /// Writes a trajectory frame of stream `stream` (`< FRAME_STREAMS`).
    fn frame(&mut self, _stream: usize, _view: &View<'_>) {}
    /// Why the outputs cannot grow any further (checked after each sample and frame: the
    /// loop then stops with [`SimError::OutputLimit`]).
    fn over_budget(&self) -> Option<String> {
        None
    }
}

/// A sampler that does nothing.
pub struct NoSampler;
impl Sampler for NoSampler {}

/// Where the run stands, for a progress display.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Events of the current phase so far.
    pub events: u64,
    /// Simulated time of the current phase so far.
    pub elapsed: f64,
}

/// Settings of the loop that are not physics.
#[derive(Clone, Copy, Debug)]
pub struct LoopSettings {
    /// Events between re-basings of the time origin.
    pub rebase_events: u64,
    /// Seed of the thermostat's random numbers.
    pub seed: u64,
    /// Events between full invariant checks in debug builds (0: never).
    pub debug_check_events: u64,
    /// Neighbour-list skin `δ` (a body rebuilds its list when it is `δ` from its centre).
    pub skin: f64,
    /// Time of the first frame (0 normally; tests start far from zero to show what re-basing
    /// the time origin protects against).
    pub start_time: f64,
}

/// An Andersen thermostat.
#[derive(Clone, Copy, Debug)]
pub struct Andersen {
    /// Collisions per body per unit time.
    pub rate: f64,
    /// Bath temperature.
    pub temperature: f64,
}

#[derive(Clone, Copy, Debug)]
enum Skip {
    Nobody,
    One(u32),
    Lower,
}

/// Accumulators of the current phase.
#[derive(Clone, Copy, Debug, Default)]
struct Phase {
    start: f64,
    virial: Compensated,
    kinetic_integral: Compensated,
    translational_integral: Compensated,
    potential_integral: Compensated,
    last_change: f64,
}

/// Scheduler statistics of the run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ScheduleStats {
    /// Entries pushed into the scheduler.
    pub pushed: u64,
    /// Superseded entries dropped when popped (queues).
    pub stale_dropped: u64,
    /// Superseded entries removed by sweeps (queues).
    pub stale_swept: u64,
    /// Bodies rescheduled because the front of their list had gone stale (partner changed).
    pub requeued: u64,
}

/// The working set above which the loop loads records ahead of use: a 1 MiB L2 cache.
const PREFETCH_ABOVE_BYTES: usize = 1 << 20;

/// Bytes per body besides its neighbour and event lists: the 64-byte record, list centre,
/// image, cell, marks and the scheduler's entries.
const BODY_BYTES: usize = 164;

/// An event-driven simulation of spheres in a periodic box.
pub struct Simulation<M, S> {
    bodies: Vec<Body>,
    /// Packed cell coordinates of each body's list centre.
    cell_of: Vec<u32>,
    images: Vec<[i32; 3]>,
    masses: Vec<f64>,
    cells: CellGrid,
    /// Neighbour-list centre of each body (same periodic image as its stored position).
    centres: Vec<DVec3>,
    nbrs: NeighbourLists,
    /// Displacement of each image code (see [`neighbour`]).
    shifts: [DVec3; 32],
    skin2: f64,
    list2: f64,
    scratch_old: Vec<u32>,
    scratch_new: Vec<u32>,
    /// Per-body marks for merging neighbour lists (see `shell_event`).
    marks: Vec<u32>,
    mark_epoch: u32,
    lists: EventLists,
    model: M,
    sched: S,
    /// Statistics of schedulers replaced by re-basing.
    old_stats: (u64, u64, u64),
    requeued: u64,
    system: u32,
    now: f64,
    epoch: Compensated,
    lengths: DVec3,
    half: DVec3,
    counters: Counters,
    anomalies: Anomalies,
    kinetic: f64,
    translational: f64,
    potential: f64,
    phase: Phase,
    thermostat: Option<Andersen>,
    rng: Xoshiro256PlusPlus,
    /// Pairs hidden from the predictions (HMC fault injection; inactive otherwise).
    blindfold: Blindfold,
    /// Whether samples' views carry the attitudes ([`Simulation::set_sample_attitudes`]).
    sample_attitudes: bool,
    next_thermostat: f64,
    sample_dt: Option<f64>,
    next_sample: f64,
    /// Interval and next time of each stream of trajectory frames.
    frame_dt: [Option<f64>; FRAME_STREAMS],
    next_frame: [f64; FRAME_STREAMS],
    end: f64,
    settings: LoopSettings,
    since_rebase: u64,
    since_check: u64,
    nan: Option<u32>,
    // `run` returns at a re-basing when asked (a checkpoint can be taken there), and
    // momenta are refreshed by HMC (3N degrees of freedom).
    pause_at_rebase: bool,
    paused: bool,
    refreshed_momenta: bool,
    /// Set by another thread to stop [`Simulation::run`] early ([`Simulation::set_cancel`]).
    cancel: Option<Arc<AtomicBool>>,
    /// A stop asked from outside and how long to wait for a scheduled re-basing
    /// ([`Simulation::set_stop_request`]), and when the loop first saw it.
    stop_request: Option<(Arc<AtomicBool>, Duration)>,
    stop_seen: Option<Instant>,
}

impl<M, S> Simulation<M, S>
where
    M: PairModel,
    S: Scheduler,
{
    /// Sets up a simulation: bodies at `positions` (wrapped into the box) with `velocities`
    /// and `species`, pair levels from the initial distances, neighbour lists, and the first
    /// events.
    ///
    /// # Errors
    /// [`SetupError`] for overlapping hard cores, a box too small for the cell list, or a
    /// non-finite state.
    pub fn new(
        lengths: DVec3,
        positions: &[DVec3],
        velocities: &[DVec3],
        species: &[u32],
        mut model: M,
        settings: LoopSettings,
    ) -> Result<Self, SetupError> {
        let n = positions.len();
        assert_eq!(n, velocities.len());
        assert_eq!(n, species.len());
        let reach = model.reach();
        let skin = settings.skin;
        let list_radius = reach + 2.0 * skin;
        let mut cells =
            CellGrid::new(lengths, list_radius, n).map_err(|a| SetupError::BoxTooSmall {
                axis: ['x', 'y', 'z'][a],
                length: lengths[a],
                reach,
                skin,
                need: 2.0 * list_radius,
            })?;
        let mut bodies = Vec::with_capacity(n);
        let mut cell_of = Vec::with_capacity(n);
        for i in 0..n {
            let (p, v) = (positions[i], velocities[i]);
            if !(p.is_finite() && v.is_finite()) {
                return Err(SetupError::NotFinite(i as u32));
            }
            let r = DVec3::new(
                p.x.rem_euclid(lengths.x),
                p.y.rem_euclid(lengths.y),
                p.z.rem_euclid(lengths.z),
            );
            let cell = cells.locate(r);
            cells.insert(i as u32, cell);
            cell_of.push(cell);
            bodies.push(Body {
                r,
                t: settings.start_time,
                v,
                species: species[i],
                generation: 0,
            });
        }
        let n_species = model.n_species();
        let masses: Vec<f64> = (0..n_species as u32).map(|s| model.mass(s)).collect();
        let shifts = neighbour::shift_table(lengths);
        // Neighbour lists, initial pair levels, and overlaps of hard cores.
        let list2 = list_radius * list_radius;
        let mut nbrs = NeighbourLists::new(n);
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n];
        for i in 0..n as u32 {
            let bi = bodies[i as usize];
            let mut found = Ok(());
            cells.for_each_neighbour_cell(cell_of[i as usize], |cell, shift| {
                for &j in cells.bodies(cell) {
                    if j <= i || found.is_err() {
                        continue;
                    }
                    let bj = &bodies[j as usize];
                    let d2 = (bi.r - (bj.r + shift)).length_squared();
                    if d2 >= list2 {
                        continue;
                    }
                    let code = image_code(shift, lengths);
                    lists[i as usize].push(neighbour::entry(j, code));
                    lists[j as usize].push(neighbour::entry(i, neighbour::opposite(code)));
                    let dr = bi.r - (bj.r + shift);
                    match model.setup_pair(&Pair {
                        i,
                        j,
                        si: bi.species,
                        sj: bj.species,
                        now: 0.0,
                        dr,
                        dv: bi.v - bj.v,
                    }) {
                        Ok(()) => {}
                        Err(PairSetupError::Overlap { distance, core }) => {
                            found = Err(SetupError::Overlap {
                                i,
                                j,
                                distance,
                                core,
                            });
                        }
                        Err(PairSetupError::InsideCore { energy, core }) => {
                            found = Err(SetupError::InsideCore { i, j, energy, core });
                        }
                    }
                }
            });
            found?;
        }
        for (i, b) in bodies.iter().enumerate() {
            if !(M::SELF_PAIRS && model.self_pairs(b.species)) {
                continue;
            }
            let i = i as u32;
            match model.setup_pair(&Pair::own(i, b.species, 0.0)) {
                Ok(()) => {}
                Err(PairSetupError::Overlap { distance, core }) => {
                    return Err(SetupError::Overlap {
                        i,
                        j: i,
                        distance,
                        core,
                    });
                }
                Err(PairSetupError::InsideCore { energy, core }) => {
                    return Err(SetupError::InsideCore {
                        i,
                        j: i,
                        energy,
                        core,
                    });
                }
            }
        }
        for (i, l) in lists.iter().enumerate() {
            nbrs.replace(i as u32, l);
        }
        let centres = bodies.iter().map(|b| b.r).collect();
        let system = n as u32;
        let mut sim = Simulation {
            bodies,
            cell_of,
            images: vec![[0; 3]; n],
            masses,
            cells,
            centres,
            nbrs,
            shifts,
            skin2: skin * skin,
            list2,
            scratch_old: Vec::with_capacity(64),
            scratch_new: Vec::with_capacity(64),
            marks: vec![0; n],
            mark_epoch: 0,
            lists: EventLists::new(n),
            model,
            sched: S::with_participants(n + 1),
            old_stats: (0, 0, 0),
            requeued: 0,
            system,
            now: settings.start_time,
            epoch: Compensated::ZERO,
            lengths,
            half: lengths * 0.5,
            counters: Counters::default(),
            anomalies: Anomalies::default(),
            kinetic: 0.0,
            translational: 0.0,
            potential: 0.0,
            phase: Phase {
                start: settings.start_time,
                last_change: settings.start_time,
                ..Phase::default()
            },
            thermostat: None,
            rng: Xoshiro256PlusPlus::seed_from_u64(settings.seed),
            blindfold: Blindfold::default(),
            sample_attitudes: false,
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
        sim.kinetic = sim.kinetic_energy();
        sim.translational = sim.translational_kinetic();
        sim.potential = sim.potential_energy();
        sim.predict_all();
        Ok(sim)
    }

    // ----- the loop ------------------------------------------------------------------------------

    /// Runs until `stop`, calling `sampler` at sampling events and `progress` every 16384
    /// events.
    ///
    /// # Errors
    /// [`SimError`] if the state became non-finite or no event is left.
    pub fn run(
        &mut self,
        stop: Stop,
        sampler: &mut dyn Sampler,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), SimError> {
        self.paused = false;
        if let Stop::Time(d) = stop {
            self.end = self.now + d;
            self.schedule_system();
        }
        let target = match stop {
            Stop::Events(n) => self.counters.events.saturating_add(n),
            Stop::Time(_) => u64::MAX,
        };
        let mut cancelled = false;
        while self.counters.events < target {
            if self.step(sampler)? {
                break;
            }
            if self.since_rebase >= self.settings.rebase_events {
                self.rebase();
                // A checkpoint can be taken here (see `state`).
                if self.pause_at_rebase {
                    self.paused = true;
                    break;
                }
            }
            // A requested stop waits for the scheduled re-basing (where a checkpoint continues
            // exactly as if never stopped) only as long as its grace: a re-basing of rigid
            // tops can be minutes of events away, and a batch system's SIGKILL follows its
            // SIGTERM within seconds.
            if self.counters.events & 0xff == 0 && self.pause_at_rebase && self.stop_overdue() {
                self.rebase();
                self.paused = true;
                break;
            }
            if self.counters.events & 0x3fff == 0 {
                progress(Progress {
                    events: self.counters.events,
                    elapsed: self.now - self.phase.start,
                });
                if self
                    .cancel
                    .as_ref()
                    .is_some_and(|c| c.load(Ordering::Relaxed))
                {
                    cancelled = true;
                    break;
                }
            }
            #[cfg(debug_assertions)]
            if self.settings.debug_check_events > 0
                && self.since_check >= self.settings.debug_check_events
            {
                self.since_check = 0;
                if let Err(e) = self.check() {
                    panic!(
                        "invariant broken after {} events: {e}",
                        self.counters.events
                    );
                }
            }
        }
        if self.paused {
            // Paused at a re-basing; `end` stays for the continuation.
            return Ok(());
        }
        if self.end < f64::INFINITY {
            self.end = f64::INFINITY;
            self.schedule_system();
        }
        self.flush_integrals();
        progress(Progress {
            events: self.counters.events,
            elapsed: self.now - self.phase.start,
        });
        if cancelled {
            return Err(SimError::Cancelled);
        }
        if let Stop::Events(_) = stop
            && self.counters.events < target
        {
            return Err(SimError::NoEvents(target - self.counters.events));
        }
        Ok(())
    }

    /// Executes the next event; returns whether the phase ended (or nothing is left).
    #[inline]
    fn step(&mut self, sampler: &mut dyn Sampler) -> Result<bool, SimError> {
        let Some((p, t)) = self.sched.next() else {
            return Ok(true);
        };
        if t < self.now {
            self.anomalies.negative_time += 1;
        } else {
            self.now = t;
        }
        if p == self.system {
            return self.system_event(sampler);
        }
        // The next body's record and lists are needed next step: ask for them now, while this
        // event runs (it usually stays the next). Only where the records no longer fit in cache.
        if self.prefetches()
            && let Some(q) = self.sched.peek()
            && q != self.system
        {
            self.lists.prefetch(q);
            self.nbrs.prefetch(q);
            memory_hints::prefetch(&self.bodies[q as usize]);
        }
        let Some((k, e)) = self.lists.earliest(p, &self.bodies) else {
            // Every event of the body had gone stale: it waits for a partner to find it.
            self.requeued += 1;
            return Ok(false);
        };
        if e.time > t {
            // Its earliest event had gone stale (the partner changed): reschedule.
            self.requeued += 1;
            self.set(p, e.time);
            return Ok(false);
        }
        match (e.kind(), e.partner()) {
            // A pair event clears both lists: no need to remove its entry first.
            (Kind::Pair(boundary), Some(j)) => self.pair_event(p, j, boundary)?,
            (Kind::Virtual, Some(j)) => {
                self.lists.remove(p, k);
                self.virtual_event(p, j);
            }
            _ => {
                self.lists.remove(p, k);
                self.shell_event(p);
            }
        }
        if let Some(i) = self.nan {
            return Err(SimError::NanTime(i));
        }
        self.counters.events += 1;
        self.since_rebase += 1;
        self.since_check += 1;
        Ok(false)
    }

    #[inline(always)]
    fn set(&mut self, p: u32, time: f64) {
        if let Err(QueueError::NanTime) = self.sched.set(p, time) {
            self.nan = Some(p);
        }
    }

    /// Reschedules body `i` at the earliest event of its list.
    #[inline]
    fn reschedule(&mut self, i: u32) {
        let t = self
            .lists
            .earliest(i, &self.bodies)
            .map_or(f64::INFINITY, |(_, e)| e.time);
        self.set(i, t);
    }

    fn pair_event(&mut self, i: u32, j: u32, boundary: Boundary) -> Result<(), SimError> {
        // A body with itself ([`PairModel::self_pairs`]).
        let own = M::SELF_PAIRS && i == j;
        if self.prefetches() {
            self.prefetch_partners(i);
            self.prefetch_partners(j);
        }
        let now = self.now;
        let (iu, ju) = (i as usize, j as usize);
        self.bodies[iu].sync(now);
        self.bodies[ju].sync(now);
        let (bi, bj) = (self.bodies[iu], self.bodies[ju]);
        let dr = self.min_image(bi.r - bj.r);
        let (mut vi, mut vj) = (bi.v, bj.v);
        let ex: Executed = self
            .model
            .execute(
                &Pair {
                    i,
                    j,
                    si: bi.species,
                    sj: bj.species,
                    now,
                    dr,
                    dv: vi - vj,
                },
                boundary,
                &mut vi,
                &mut vj,
            )
            .map_err(|source| SimError::Collide {
                i,
                j,
                time: self.epoch.value() + now,
                source,
            })?;
        // Within one body (`own`) the impulses sum to zero: the model keeps `vj = vi`.
        self.bodies[iu].v = vi;
        self.bodies[ju].v = vj;
        if ex.overlap {
            self.anomalies.overlap += 1;
        }
        match ex.class {
            PairClass::Core => self.counters.core += 1,
            PairClass::StepIn => self.counters.step_in += 1,
            PairClass::StepOut => self.counters.step_out += 1,
            PairClass::StepReflect => self.counters.step_reflect += 1,
            PairClass::Skipped => self.anomalies.receding += 1,
        }
        if self.model.rotational_dof() > 0.0 {
            // Impulses share kinetic energy between translation and rotation: track the
            // translational part for the two temperatures.
            let (mi, mj) = (
                self.masses[bi.species as usize],
                self.masses[bj.species as usize],
            );
            let mut dkt = 0.5 * mi * (vi.length_squared() - bi.v.length_squared());
            if !own {
                dkt += 0.5 * mj * (vj.length_squared() - bj.v.length_squared());
            }
            self.energy_changes(-ex.delta_u, ex.delta_u, dkt);
        } else if ex.delta_u != 0.0 {
            self.energy_changes(-ex.delta_u, ex.delta_u, -ex.delta_u);
        }
        let numerical = self.model.take_kinetic_error();
        if numerical != 0.0 {
            // The free motion's integration error (RATTLE) that the event brought in.
            self.energy_changes(numerical, 0.0, 0.0);
        }
        self.phase.virial.add(ex.virial);
        self.bodies[iu].generation = self.bodies[iu].generation.wrapping_add(1);
        self.lists.clear(i);
        self.model.forget(i);
        if !own {
            self.bodies[ju].generation = self.bodies[ju].generation.wrapping_add(1);
            self.lists.clear(j);
            self.model.forget(j);
        }
        let ti = self.predict(i, Skip::Nobody);
        self.set(i, ti);
        if !own {
            let tj = self.predict(j, Skip::One(i));
            self.set(j, tj);
        }
        Ok(())
    }

    /// A virtual event of owner `i` with partner `j` (both unchanged since it was scheduled):
    /// the model continues the pair's root search from where it stopped, and whatever it finds
    /// (a pair event, or the next virtual event) joins `i`'s list.
    fn virtual_event(&mut self, i: u32, j: u32) {
        let now = self.now;
        let (bi, bj) = (&self.bodies[i as usize], &self.bodies[j as usize]);
        let dr = self.min_image(bi.position_at(now) - bj.position_at(now));
        let dv = bi.v - bj.v;
        let (si, sj, gj) = (bi.species, bj.species, bj.generation);
        if self.blindfold.hides(i, j) {
            self.counters.virtual_ += 1;
            self.reschedule(i);
            return;
        }
        if let Some((dt, kind)) = self.model.resume(&Pair {
            i,
            j,
            si,
            sj,
            now,
            dr,
            dv,
        }) {
            self.lists
                .push(i, Event::with_partner(now + dt, j, gj, kind));
        }
        self.counters.virtual_ += 1;
        self.reschedule(i);
    }

    /// Body `i` has moved the skin away from its list centre: wrap it into the box, move its
    /// centre (and cell) to where it is now, rebuild its list and its neighbours' entries for
    /// it, and predict its events with the bodies that came into its list.
    fn shell_event(&mut self, i: u32) {
        let iu = i as usize;
        let now = self.now;
        self.bodies[iu].sync(now);
        let mut r = self.bodies[iu].r;
        for a in 0..3 {
            let l = self.lengths[a];
            if r[a] < 0.0 {
                r[a] += l;
                self.images[iu][a] -= 1;
            } else if r[a] >= l {
                r[a] -= l;
                self.images[iu][a] += 1;
            }
        }
        self.bodies[iu].r = r;
        self.centres[iu] = r;
        let old_cell = self.cell_of[iu];
        let cell = self.cells.locate(r);
        if cell != old_cell {
            self.cells.remove(i, old_cell);
            self.cells.insert(i, cell);
            self.cell_of[iu] = cell;
        }
        // The new list, from the 27 cells around the centre.
        let mut new = std::mem::take(&mut self.scratch_new);
        new.clear();
        {
            let (cells, centres, lengths, list2) =
                (&self.cells, &self.centres, self.lengths, self.list2);
            cells.for_each_neighbour_cell(cell, |c, shift| {
                for &j in cells.bodies(c) {
                    if j != i && (r - (centres[j as usize] + shift)).length_squared() < list2 {
                        new.push(neighbour::entry(j, image_code(shift, lengths)));
                    }
                }
            });
        }
        let mut old = std::mem::take(&mut self.scratch_old);
        old.clear();
        old.extend_from_slice(self.nbrs.of(i));
        // Merge the old and new lists in linear time with a mark per body:
        // `epoch << 6 | seen-in-new << 5 | old image code`.
        self.mark_epoch += 1;
        if self.mark_epoch >= 1 << 25 {
            self.marks.fill(0);
            self.mark_epoch = 1;
        }
        let epoch = self.mark_epoch;
        for &o in &old {
            self.marks[neighbour::partner(o) as usize] = (epoch << 6) | neighbour::code(o);
        }
        for &e in &new {
            let (j, code) = (neighbour::partner(e), neighbour::code(e));
            let m = self.marks[j as usize];
            if m >> 6 == epoch {
                self.marks[j as usize] = m | 32;
                if m & 31 == code {
                    continue; // Same partner, same image: nothing changes for this pair.
                }
                self.nbrs.upsert(j, i, neighbour::opposite(code));
            } else {
                self.nbrs.upsert(j, i, neighbour::opposite(code));
                if !M::PRUNES {
                    self.predict_pair(i, j, code);
                }
            }
        }
        for &o in &old {
            let j = neighbour::partner(o);
            if self.marks[j as usize] & 32 == 0 {
                self.nbrs.remove(j, i);
            }
        }
        self.nbrs.replace(i, &new);
        self.scratch_new = new;
        self.scratch_old = old;
        self.counters.shell += 1;
        if M::PRUNES {
            // The list held no event beyond this crossing: predict every pair afresh (the
            // events of unchanged pairs come out the same).
            self.lists.clear(i);
            let t = self.predict(i, Skip::Nobody);
            self.set(i, t);
        } else {
            self.predict_shell(i);
            self.reschedule(i);
        }
    }

    /// Predicts the event of pair `(i, j)` (`j`'s image `code`) into `i`'s list.
    fn predict_pair(&mut self, i: u32, j: u32, code: u32) {
        let now = self.now;
        let (bi, bj) = (&self.bodies[i as usize], &self.bodies[j as usize]);
        let dr = bi.position_at(now) - (bj.position_at(now) + self.shifts[code as usize]);
        let dv = bi.v - bj.v;
        let (si, sj, gj) = (bi.species, bj.species, bj.generation);
        if self.blindfold.hides(i, j) {
            return;
        }
        if let Some((dt, kind)) = self.model.predict(&Pair {
            i,
            j,
            si,
            sj,
            now,
            dr,
            dv,
        }) {
            self.lists
                .push(i, Event::with_partner(now + dt, j, gj, kind));
        }
    }

    /// The next system event: the earliest of sampling, frame, thermostat and end.
    fn system_time(&self) -> f64 {
        let mut t = self.end;
        if self.sample_dt.is_some() {
            t = t.min(self.next_sample);
        }
        for (dt, next) in self.frame_dt.iter().zip(self.next_frame) {
            if dt.is_some() {
                t = t.min(next);
            }
        }
        if self.thermostat.is_some() {
            t = t.min(self.next_thermostat);
        }
        t
    }

    fn schedule_system(&mut self) {
        let t = self.system_time();
        self.sched
            .set(self.system, t)
            .expect("system event times are not NaN");
    }

    #[inline(never)]
    fn system_event(&mut self, sampler: &mut dyn Sampler) -> Result<bool, SimError> {
        let t = self.now;
        // In a fixed order when several are due at once: the end comes last.
        let what = if self.thermostat.is_some() && self.next_thermostat <= t {
            SystemEvent::Thermostat
        } else if self.sample_dt.is_some() && self.next_sample <= t {
            SystemEvent::Sample
        } else if let Some(k) =
            (0..FRAME_STREAMS).find(|&k| self.frame_dt[k].is_some() && self.next_frame[k] <= t)
        {
            SystemEvent::Frame(k)
        } else {
            SystemEvent::End
        };
        match what {
            SystemEvent::End => {
                self.now = self.end;
                return Ok(true);
            }
            SystemEvent::Sample => {
                self.flush_integrals();
                sampler.sample(&self.view());
                self.counters.samples += 1;
                self.next_sample += self.sample_dt.unwrap_or(f64::INFINITY);
            }
            SystemEvent::Frame(k) => {
                sampler.frame(k, &self.frame_view());
                self.counters.samples += 1;
                self.next_frame[k] += self.frame_dt[k].unwrap_or(f64::INFINITY);
            }
            SystemEvent::Thermostat => {
                self.thermostat_collision();
                self.counters.thermostat += 1;
                self.counters.events += 1;
                self.since_rebase += 1;
                self.since_check += 1;
            }
        }
        self.schedule_system();
        if let Some(problem) = sampler.over_budget() {
            return Err(SimError::OutputLimit(problem.into()));
        }
        Ok(false)
    }

    fn thermostat_collision(&mut self) {
        let Some(th) = self.thermostat else {
            return;
        };
        let n = self.system;
        let i = self.rng.random_range(0..n);
        let iu = i as usize;
        self.bodies[iu].sync(self.now);
        let m = self.masses[self.bodies[iu].species as usize];
        let scale = (th.temperature / m).sqrt();
        let v = DVec3::new(
            StandardNormal.sample(&mut self.rng),
            StandardNormal.sample(&mut self.rng),
            StandardNormal.sample(&mut self.rng),
        ) * scale;
        let dkt = 0.5 * m * (v.length_squared() - self.bodies[iu].v.length_squared());
        self.bodies[iu].v = v;
        let species = self.bodies[iu].species;
        let dk = dkt
            + self
                .model
                .thermalize(i, species, self.now, th.temperature, &mut self.rng);
        self.energy_changes(dk, 0.0, dkt);
        self.bodies[iu].generation = self.bodies[iu].generation.wrapping_add(1);
        self.lists.clear(i);
        self.model.forget(i);
        let t = self.predict(i, Skip::Nobody);
        self.set(i, t);
        let u: f64 = self.rng.random();
        self.next_thermostat = self.now - (1.0 - u).ln() / (th.rate * f64::from(n));
    }

    /// Records a change of kinetic energy `dk` (of which `dkt` translational) and potential
    /// energy `du` now (for the time integrals).
    #[inline]
    fn energy_changes(&mut self, dk: f64, du: f64, dkt: f64) {
        self.flush_integrals();
        self.kinetic += dk;
        self.potential += du;
        self.translational += dkt;
    }

    fn flush_integrals(&mut self) {
        let dt = self.now - self.phase.last_change;
        if dt != 0.0 {
            self.phase.kinetic_integral.add(self.kinetic * dt);
            self.phase
                .translational_integral
                .add(self.translational * dt);
            self.phase.potential_integral.add(self.potential * dt);
            self.phase.last_change = self.now;
        }
    }

    // ----- prediction ----------------------------------------------------------------------------

    /// Whether the loop prefetches ([`prefetch_partners`](Self::prefetch_partners), the next
    /// body's record and lists): while the working set (records, neighbour lists, event lists)
    /// fits in L2 the prefetches only cost instructions (hard spheres at N = 1372: 1.08 of the CPU time with them);
    /// beyond it they hide the misses (stepped fluids at N = 4000 with their longer lists, and
    /// every larger system).
    #[inline(always)]
    fn prefetches(&self) -> bool {
        let per_body = BODY_BYTES
            + self.nbrs.capacity() * std::mem::size_of::<u32>()
            + self.lists.capacity() * std::mem::size_of::<Event>();
        self.bodies.len() * per_body > PREFETCH_ABOVE_BYTES
    }

    /// Prefetches every record body `i`'s next prediction will need (its partners' records,
    /// its event list): they are all in flight at once (with 10⁵ bodies the records are rarely
    /// in L2), and the prediction then finds them in L1. Prefetches rather than loads, because
    /// a load that misses holds up every instruction after it until it arrives (0.87 of the
    /// CPU time at N = 87 808 against reading a word of each record).
    #[inline(always)]
    fn prefetch_partners(&self, i: u32) {
        self.lists.prefetch(i);
        for &e in self.nbrs.of(i) {
            memory_hints::prefetch(&self.bodies[neighbour::partner(e) as usize]);
        }
    }

    /// Predicts every pair event of body `i` with its neighbours (except `skip`) and the
    /// time it leaves its skin into `i`'s list, and its event with itself if it has one;
    /// returns the earliest time.
    #[inline(always)]
    fn predict(&mut self, i: u32, skip: Skip) -> f64 {
        // Two copies of the partner loop: without fault injection (every ordinary run) the
        // loop has no test for hidden pairs at all, whose never-taken call would otherwise
        // keep the loop's vectors out of registers (measured: +3 % instructions per event on
        // hard spheres).
        let t = if self.blindfold.is_active() {
            self.predict_partners::<true>(i, skip)
        } else {
            self.predict_partners::<false>(i, skip)
        };
        if M::SELF_PAIRS && self.model.self_pairs(self.bodies[i as usize].species) {
            t.min(self.predict_own(i))
        } else {
            t
        }
    }

    /// Predicts the event of body `i` with itself ([`PairModel::self_pairs`]) into its list;
    /// returns its time (`+∞`: none). Out of line: the loops of models without such pairs
    /// stay as they were.
    #[inline(never)]
    fn predict_own(&mut self, i: u32) -> f64 {
        let b = &self.bodies[i as usize];
        let (s, g) = (b.species, b.generation);
        if self.blindfold.hides(i, i) {
            return f64::INFINITY;
        }
        let now = self.now;
        match self.model.predict(&Pair::own(i, s, now)) {
            Some((dt, kind)) => {
                self.lists
                    .push(i, Event::with_partner(now + dt, i, g, kind));
                now + dt
            }
            None => f64::INFINITY,
        }
    }

    /// [`predict`](Self::predict), hiding the blindfolded pairs if `HIDE`.
    #[inline(always)]
    fn predict_partners<const HIDE: bool>(&mut self, i: u32, skip: Skip) -> f64 {
        let now = self.now;
        let bi = self.bodies[i as usize];
        let ri = bi.position_at(now);
        let (other, lower) = match skip {
            Skip::Nobody => (i, false),
            Skip::One(o) => (o, false),
            Skip::Lower => (i, true),
        };
        // The skin exit first: with a pruning model no pair event after it is kept (the
        // shell crossing predicts every pair afresh).
        let shell = self.predict_shell(i);
        let (nbrs, bodies, model, lists, shifts, blindfold) = (
            &self.nbrs,
            &self.bodies,
            &mut self.model,
            &mut self.lists,
            &self.shifts,
            &self.blindfold,
        );
        let horizon = shell - now;
        let mut earliest = shell;
        for &e in nbrs.of(i) {
            let j = neighbour::partner(e);
            if j == other || (lower && j < i) || (HIDE && blindfold.hides(i, j)) {
                continue;
            }
            let bj = &bodies[j as usize];
            let dr = (ri - shifts[neighbour::code(e) as usize]) - bj.position_at(now);
            let dv = bi.v - bj.v;
            let pair = Pair {
                i,
                j,
                si: bi.species,
                sj: bj.species,
                now,
                dr,
                dv,
            };
            let predicted = if M::PRUNES {
                model.predict_before(&pair, horizon)
            } else {
                model.predict(&pair)
            };
            if let Some((dt, kind)) = predicted {
                let time = now + dt;
                earliest = earliest.min(time);
                lists.push(i, Event::with_partner(time, j, bj.generation, kind));
            }
        }
        earliest
    }

    /// Predicts when body `i` leaves the skin sphere around its list centre (analytic: linear
    /// motion out of a sphere) into its list; returns the time (`+∞` at rest).
    #[inline]
    fn predict_shell(&mut self, i: u32) -> f64 {
        let b = self.bodies[i as usize];
        let d = b.r - self.centres[i as usize];
        let v2 = b.v.length_squared();
        if v2 == 0.0 {
            return f64::INFINITY;
        }
        let c = d.length_squared() - self.skin2;
        let bb = d.dot(b.v);
        let disc = (bb * bb - v2 * c).max(0.0);
        let dt = if bb > 0.0 {
            -c / (bb + disc.sqrt())
        } else {
            (-bb + disc.sqrt()) / v2
        };
        let time = (b.t + dt.max(0.0)).max(self.now);
        if time.is_nan() {
            self.nan = Some(i);
            return f64::INFINITY;
        }
        self.lists.push(i, Event::shell(time));
        time
    }

    /// Forgets every prediction and predicts all events afresh (after a change of every
    /// velocity).
    fn predict_all(&mut self) {
        for i in 0..self.bodies.len() as u32 {
            let b = &mut self.bodies[i as usize];
            b.generation = b.generation.wrapping_add(1);
            self.lists.clear(i);
            self.model.forget(i);
        }
        for i in 0..self.bodies.len() as u32 {
            self.predict(i, Skip::Lower);
        }
        self.rebuild_schedule();
    }

    /// A fresh scheduler holding the earliest event of every list and the system's.
    fn rebuild_schedule(&mut self) {
        let (a, b, c) = self.sched.stats();
        self.old_stats = (
            self.old_stats.0 + a,
            self.old_stats.1 + b,
            self.old_stats.2 + c,
        );
        self.sched = S::with_participants(self.bodies.len() + 1);
        for i in 0..self.bodies.len() as u32 {
            self.reschedule(i);
        }
        self.schedule_system();
    }

    /// Moves the time origin to the present: bodies brought to `now` with their clocks at
    /// zero, and every event predicted afresh in the new frame (a prediction made far from
    /// the origin carries that frame's round-off; shifting it would keep the error).
    pub fn rebase(&mut self) {
        self.flush_integrals();
        let t0 = self.now;
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
        self.counters.rebases += 1;
        self.predict_all();
    }

    // ----- phases --------------------------------------------------------------------------------

    /// A flag that stops [`run`](Self::run) with [`SimError::Cancelled`] when raised (from
    /// another thread, or from its `progress` callback); it is read every 16384 events, where
    /// the state is whole. `None` (the default) never stops.
    pub fn set_cancel(&mut self, flag: Option<Arc<AtomicBool>>) {
        self.cancel = flag;
    }

    /// A flag (set by a signal handler) that asks [`run`](Self::run) to pause at a re-basing
    /// when [`set_pause_at_rebase`](Self::set_pause_at_rebase) is on: at the scheduled one if
    /// it comes within `grace` of wall time after the loop first sees the flag (read every
    /// 256 events), otherwise at a re-basing made then. The state there is whole and can be
    /// saved exactly either way; only an early re-basing makes the continuation differ from a
    /// run never stopped, by the rounding of moving the time origin.
    pub fn set_stop_request(&mut self, flag: Option<Arc<AtomicBool>>, grace: Duration) {
        self.stop_request = flag.map(|f| (f, grace));
        self.stop_seen = None;
    }

    /// Whether a stop was requested longer than its grace ago.
    fn stop_overdue(&mut self) -> bool {
        let Some((flag, grace)) = &self.stop_request else {
            return false;
        };
        if !flag.load(Ordering::Relaxed) {
            return false;
        }
        self.stop_seen.get_or_insert_with(Instant::now).elapsed() >= *grace
    }

    /// Switches the Andersen thermostat on (or off with `None`).
    pub fn set_thermostat(&mut self, thermostat: Option<Andersen>) {
        self.thermostat = thermostat;
        match thermostat {
            Some(th) => {
                let u: f64 = self.rng.random();
                self.next_thermostat =
                    self.now - (1.0 - u).ln() / (th.rate * f64::from(self.system));
            }
            None => self.next_thermostat = f64::INFINITY,
        }
        self.schedule_system();
    }

    /// Starts a new phase: resets the counters and accumulators, optionally removes the total
    /// momentum (after a thermostat), and schedules sampling every `sample_dt` and trajectory
    /// frames every `frame_dt` from now on (frame stream 0; the other streams off).
    pub fn begin_phase(
        &mut self,
        zero_momentum: bool,
        sample_dt: Option<f64>,
        frame_dt: Option<f64>,
    ) {
        let mut frames = [None; FRAME_STREAMS];
        frames[0] = frame_dt;
        self.begin_phase_with_frames(zero_momentum, sample_dt, frames);
    }

    /// [`begin_phase`](Self::begin_phase) with every stream of trajectory frames: stream `k`
    /// every `frames[k]` from now on ([`Sampler::frame`] tells the sampler which stream is
    /// due).
    pub fn begin_phase_with_frames(
        &mut self,
        zero_momentum: bool,
        sample_dt: Option<f64>,
        frames: [Option<f64>; FRAME_STREAMS],
    ) {
        let now = self.now;
        if zero_momentum {
            for b in &mut self.bodies {
                b.sync(now);
            }
            let (p, m) = self.momentum_and_mass();
            let u = p / m;
            for b in &mut self.bodies {
                b.v -= u;
            }
            self.predict_all();
        }
        self.kinetic = self.kinetic_energy();
        self.translational = self.translational_kinetic();
        self.potential = self.potential_energy();
        self.counters = Counters::default();
        self.anomalies = Anomalies::default();
        self.phase = Phase {
            start: now,
            last_change: now,
            ..Phase::default()
        };
        self.sample_dt = sample_dt;
        self.next_sample = now;
        self.frame_dt = frames;
        self.next_frame = [now; FRAME_STREAMS];
        self.schedule_system();
    }

    /// Scales every velocity so that the kinetic temperature `2K/dof` is `kt` (the end of a
    /// thermostatted equilibration): rotations by the model
    /// ([`PairModel::scale_rotations`]) and translations by one factor `√(kt dof / 2K)`,
    /// the translational one then adjusted by round-off so that the total is `kt` exactly
    /// whatever the model's rotors made of theirs. Every event is predicted afresh (the
    /// momentum refresh of hybrid Monte Carlo). Returns the factor.
    pub fn rescale_to_temperature(&mut self, kt: f64) -> f64 {
        let target = 0.5 * self.dof() * kt;
        let k = self.kinetic_energy();
        if !(k > 0.0 && target > 0.0) {
            return 1.0;
        }
        let f = (target / k).sqrt();
        self.refresh_momenta(|bodies, now, masses, model| {
            model.scale_rotations(now, f);
            let rotational = model.rotational_kinetic();
            let mut translational = Compensated::ZERO;
            for b in bodies.iter() {
                translational.add(0.5 * masses[b.species as usize] * b.v.length_squared());
            }
            let translational = translational.value();
            let g = if translational > 0.0 && target > rotational {
                ((target - rotational) / translational).sqrt()
            } else {
                f
            };
            for b in bodies {
                b.v *= g;
            }
        });
        f
    }

    // ----- measurements --------------------------------------------------------------------------

    fn view(&self) -> View<'_> {
        View {
            now: self.now,
            elapsed: self.now - self.phase.start,
            bodies: &self.bodies,
            images: &self.images,
            lengths: self.lengths,
            masses: &self.masses,
            kinetic: self.kinetic,
            potential: self.potential,
            virial: self.phase.virial.value(),
            kinetic_integral: self.phase.kinetic_integral.value(),
            dof: self.dof(),
            axes: (0..self.bodies.len() as u32)
                .map_while(|i| self.model.axis(i, self.now))
                .collect(),
            rotational_kinetic: self.model.rotational_kinetic(),
            rotational_dof: self.model.rotational_dof(),
            events: self.counters.events,
            attitudes: if self.sample_attitudes {
                (0..self.bodies.len() as u32)
                    .map_while(|i| self.model.attitude(i, self.now))
                    .collect()
            } else {
                Vec::new()
            },
            spins: Vec::new(),
            atoms: Vec::new(),
        }
    }

    /// Whether every view (samples too, not only trajectory frames) carries the bodies'
    /// attitudes: the smooth estimators of full-attitude potentials read them.
    pub fn set_sample_attitudes(&mut self, yes: bool) {
        self.sample_attitudes = yes;
    }

    /// The view of a trajectory frame: [`view`](Self::view) with the attitudes, spins and
    /// atoms that only frames need.
    fn frame_view(&self) -> View<'_> {
        let n = self.bodies.len() as u32;
        let attitudes: Vec<DQuat> = (0..n)
            .map_while(|i| self.model.attitude(i, self.now))
            .collect();
        let spins = if attitudes.is_empty() {
            Vec::new()
        } else {
            (0..n)
                .map(|i| self.model.spin(i, self.bodies[i as usize].species))
                .collect()
        };
        View {
            atoms: (0..n)
                .map_while(|i| self.model.atoms(i, self.now))
                .collect(),
            attitudes,
            spins,
            ..self.view()
        }
    }

    /// Degrees of freedom of the kinetic temperature: 3N − 3 when momentum is conserved, 3N
    /// with a thermostat acting (or HMC momenta refreshed from the Gaussian distribution), plus
    /// the rotational ones (2 per rod).
    pub fn dof(&self) -> f64 {
        let n = self.bodies.len() as f64;
        let rotation = self.model.rotational_dof();
        if self.thermostat.is_some() || self.refreshed_momenta {
            3.0 * n + rotation
        } else {
            3.0 * n - 3.0 + rotation
        }
    }

    /// Kinetic energy (translational and rotational), recomputed from the velocities.
    pub fn kinetic_energy(&self) -> f64 {
        self.translational_kinetic() + self.model.rotational_kinetic()
    }

    /// Translational kinetic energy, recomputed from the velocities.
    pub fn translational_kinetic(&self) -> f64 {
        let mut k = Compensated::ZERO;
        for b in &self.bodies {
            k.add(0.5 * self.masses[b.species as usize] * b.v.length_squared());
        }
        k.value()
    }

    /// Total angular momentum about the origin, `Σ m r × v + I ω`, with unwrapped positions
    /// (meaningful for a cluster that never interacts with its periodic images: periodic
    /// boundaries conserve linear momentum, not angular momentum).
    pub fn angular_momentum(&self) -> DVec3 {
        let mut l = [Compensated::ZERO; 3];
        for (i, b) in self.bodies.iter().enumerate() {
            let im = self.images[i];
            let r = b.position_at(self.now)
                + DVec3::new(f64::from(im[0]), f64::from(im[1]), f64::from(im[2])) * self.lengths;
            let li = self.masses[b.species as usize] * r.cross(b.v)
                + self.model.spin(i as u32, b.species);
            for (a, la) in l.iter_mut().enumerate() {
                la.add(li[a]);
            }
        }
        DVec3::new(l[0].value(), l[1].value(), l[2].value())
    }

    /// Potential energy, recomputed from the stored pair levels.
    pub fn potential_energy(&self) -> f64 {
        let mut u = Compensated::ZERO;
        for i in 0..self.bodies.len() as u32 {
            let bi = &self.bodies[i as usize];
            self.cells
                .for_each_distinct_neighbour_cell(self.cell_of[i as usize], |cell| {
                    for &j in self.cells.bodies(cell) {
                        if j > i {
                            let bj = &self.bodies[j as usize];
                            let e = self.model.pair_energy(i, j, bi.species, bj.species);
                            if e != 0.0 {
                                u.add(e);
                            }
                        }
                    }
                });
            if M::SELF_PAIRS && self.model.self_pairs(bi.species) {
                let e = self.model.pair_energy(i, i, bi.species, bi.species);
                if e != 0.0 {
                    u.add(e);
                }
            }
        }
        u.value()
    }

    /// Total momentum and total mass.
    pub fn momentum_and_mass(&self) -> (DVec3, f64) {
        let mut p = [Compensated::ZERO; 3];
        let mut m = Compensated::ZERO;
        for b in &self.bodies {
            let mi = self.masses[b.species as usize];
            for (a, pa) in p.iter_mut().enumerate() {
                pa.add(mi * b.v[a]);
            }
            m.add(mi);
        }
        (
            DVec3::new(p[0].value(), p[1].value(), p[2].value()),
            m.value(),
        )
    }

    /// `Σ m_i |v_i|`: the scale against which momentum drift is measured.
    pub fn momentum_scale(&self) -> f64 {
        let mut s = Compensated::ZERO;
        for b in &self.bodies {
            s.add(self.masses[b.species as usize] * b.v.length());
        }
        s.value()
    }

    /// Kinetic energy tracked through the events (compare with [`kinetic_energy`](Self::kinetic_energy)).
    pub fn tracked_kinetic(&self) -> f64 {
        self.kinetic
    }

    /// Potential energy tracked through the events.
    pub fn tracked_potential(&self) -> f64 {
        self.potential
    }

    /// Simulated time since the start of the phase.
    pub fn phase_elapsed(&self) -> f64 {
        self.now - self.phase.start
    }

    /// Simulated time since the start of the run.
    pub fn time(&self) -> f64 {
        self.epoch.value() + self.now
    }

    /// Time in the current frame (since the last re-basing).
    pub fn now(&self) -> f64 {
        self.now
    }

    /// `Σ r_ij·Δp_i` of the phase.
    pub fn virial(&self) -> f64 {
        self.phase.virial.value()
    }

    /// `∫ K dt` of the phase.
    pub fn kinetic_integral(&self) -> f64 {
        self.phase.kinetic_integral.value()
    }

    /// `∫ K_rot dt` of the phase (rotational kinetic energy; 0 for spheres).
    pub fn rotational_kinetic_integral(&self) -> f64 {
        self.phase.kinetic_integral.value() - self.phase.translational_integral.value()
    }

    /// `∫ U dt` of the phase.
    pub fn potential_integral(&self) -> f64 {
        self.phase.potential_integral.value()
    }

    /// Counters of the phase.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Anomalies of the phase.
    pub fn anomalies(&self) -> Anomalies {
        self.anomalies
    }

    /// Scheduler statistics over the whole run.
    pub fn schedule_stats(&self) -> ScheduleStats {
        let (a, b, c) = self.sched.stats();
        ScheduleStats {
            pushed: a + self.old_stats.0,
            stale_dropped: b + self.old_stats.1,
            stale_swept: c + self.old_stats.2,
            requeued: self.requeued,
        }
    }

    /// The per-body event lists.
    pub fn event_lists(&self) -> &EventLists {
        &self.lists
    }

    /// The bodies (state at their local clocks).
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// Box crossings per body.
    pub fn images(&self) -> &[[i32; 3]] {
        &self.images
    }

    /// Sets the box crossings per body, for a run that continues another's unwrapped
    /// positions. Panics unless there is one per body.
    pub fn set_images(&mut self, images: Vec<[i32; 3]>) {
        assert_eq!(images.len(), self.images.len(), "one image per body");
        self.images = images;
    }

    /// Masses per species.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// The box.
    pub fn lengths(&self) -> DVec3 {
        self.lengths
    }

    /// The cell grid.
    pub fn cells(&self) -> &CellGrid {
        &self.cells
    }

    /// Hides about `fraction` of the pairs from every event prediction in each HMC segment,
    /// drawn afresh per segment from `seed` (fault injection, a validation tool of HMC; see
    /// the `engine::fault` module). Nothing is hidden before the first [`begin_segment`](Self::begin_segment).
    pub fn set_fault_fraction(&mut self, fraction: f64, seed: u64) {
        self.blindfold = Blindfold::new(fraction, seed);
    }

    /// HMC begins segment number `segment`: the fault injection, if any, draws its hidden
    /// pairs afresh.
    pub fn begin_segment(&mut self, segment: u64) {
        self.blindfold.begin_segment(segment);
    }

    /// The interaction model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// Positions of all bodies now.
    pub fn positions(&self) -> Vec<DVec3> {
        self.bodies
            .iter()
            .map(|b| b.position_at(self.now))
            .collect()
    }

    #[inline(always)]
    fn min_image(&self, mut d: DVec3) -> DVec3 {
        for a in 0..3 {
            if d[a] > self.half[a] {
                d[a] -= self.lengths[a];
            } else if d[a] < -self.half[a] {
                d[a] += self.lengths[a];
            }
        }
        d
    }

    /// Checks the invariants of the present state: every body within the skin of its list
    /// centre and in the cell of that centre, neighbour lists exactly the pairs of centres
    /// closer than `reach + 2δ` (up to round-off at that distance) with matching image codes
    /// on both sides, no hard cores overlapping, every stored pair level matching the distance
    /// (a pair within round-off of a boundary may be on either side), and the tracked energies
    /// matching the recomputed ones. O(N · neighbours).
    ///
    /// # Errors
    /// A description of the first violation.
    pub fn check(&self) -> Result<(), String> {
        self.check_within(1e-9)
    }

    /// [`check`](Self::check) with the tracked energies allowed to differ from the recomputed
    /// ones by `energy_tolerance` of the energy scale (a resumed checkpoint allows the round-off
    /// of a long run's sums); also every list centre inside the box.
    ///
    /// # Errors
    /// A description of the first violation.
    pub fn check_within(&self, energy_tolerance: f64) -> Result<(), String> {
        let skin = self.skin2.sqrt();
        for (i, c) in self.centres.iter().enumerate() {
            if (0..3).any(|a| !(0.0..=self.lengths[a]).contains(&c[a])) {
                return Err(format!(
                    "body {i} has its list centre {c} outside the box {}",
                    self.lengths
                ));
            }
        }
        for (i, b) in self.bodies.iter().enumerate() {
            let r = b.position_at(self.now);
            let off = (r - self.centres[i]).length();
            if off > skin * (1.0 + 1e-9) + 1e-12 {
                return Err(format!(
                    "body {i} is {off} from its list centre, beyond the skin {skin}"
                ));
            }
            if self.cells.locate(self.centres[i]) != self.cell_of[i] {
                return Err(format!("body {i} is not in the cell of its list centre"));
            }
        }
        let list_r = self.list2.sqrt();
        for i in 0..self.bodies.len() as u32 {
            let bi = self.bodies[i as usize];
            let ri = bi.position_at(self.now);
            let ci = self.centres[i as usize];
            let mut err = Ok(());
            self.cells
                .for_each_neighbour_cell(self.cell_of[i as usize], |cell, shift| {
                    for &j in self.cells.bodies(cell) {
                        if j == i || err.is_err() {
                            continue;
                        }
                        let code = image_code(shift, self.lengths);
                        let dc = (ci - (self.centres[j as usize] + shift)).length();
                        let listed = self.nbrs.of(i).contains(&neighbour::entry(j, code));
                        let back = self
                            .nbrs
                            .of(j)
                            .contains(&neighbour::entry(i, neighbour::opposite(code)));
                        let near_edge = (dc - list_r).abs() <= 1e-9 * list_r;
                        if listed != back || (listed != (dc < list_r) && !near_edge) {
                            err = Err(format!(
                                "pair ({i}, {j}) with centres {dc} apart (list radius {list_r}): \
                             listed by {i}: {listed}, by {j}: {back}"
                            ));
                            return;
                        }
                        if j < i {
                            continue;
                        }
                        // Along an axis of two cells `j`'s cell comes twice, one box length
                        // apart: a pair listed under the other image is checked there.
                        if !listed && self.nbrs.of(i).iter().any(|&e| neighbour::partner(e) == j) {
                            continue;
                        }
                        let bj = &self.bodies[j as usize];
                        let dr = ri - (bj.position_at(self.now) + shift);
                        if let Err(e) = self.model.check_pair(
                            &Pair {
                                i,
                                j,
                                si: bi.species,
                                sj: bj.species,
                                now: self.now,
                                dr,
                                dv: bi.v - bj.v,
                            },
                            listed,
                        ) {
                            err = Err(e);
                            return;
                        }
                    }
                });
            err?;
            if M::SELF_PAIRS && self.model.self_pairs(bi.species) {
                self.model
                    .check_pair(&Pair::own(i, bi.species, self.now), true)?;
            }
        }
        let k = self.kinetic_energy();
        if (k - self.kinetic).abs() > energy_tolerance * k.abs().max(1.0) {
            return Err(format!(
                "tracked kinetic energy {} differs from the velocities' {k}",
                self.kinetic
            ));
        }
        let kt = self.translational_kinetic();
        if (kt - self.translational).abs() > energy_tolerance * k.abs().max(1.0) {
            return Err(format!(
                "tracked translational kinetic energy {} differs from the velocities' {kt}",
                self.translational
            ));
        }
        let u = self.potential_energy();
        let scale = k.abs().max(self.potential.abs()).max(1.0);
        if (u - self.potential).abs() > energy_tolerance * scale {
            return Err(format!(
                "tracked potential energy {} differs from the stored levels' {u}",
                self.potential
            ));
        }
        Ok(())
    }

    /// The neighbour lists.
    pub fn neighbour_lists(&self) -> &NeighbourLists {
        &self.nbrs
    }

    /// The neighbour-list skin.
    pub fn skin(&self) -> f64 {
        self.skin2.sqrt()
    }
}

/// The image code of a cell shift (each component 0 or ±L).
#[inline]
fn image_code(shift: DVec3, lengths: DVec3) -> u32 {
    let s = |a: usize| {
        if shift[a] > 0.5 * lengths[a] {
            1
        } else if shift[a] < -0.5 * lengths[a] {
            -1
        } else {
            0
        }
    };
    neighbour::code_of([s(0), s(1), s(2)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::model::HardSpheres;
    use crate::engine::potential::{Potentials, StepPotential};
    use collide::Particle;
    use event_queue::{HeapQueue, LazyQueue, Ticket};

    fn hs_potentials() -> Potentials {
        let scene = crate::config::scene::Scene::from_str_with(
            r#"
version = 1
[box]
density = 0.5
[[species]]
name = "A"
count = 2
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf]]
[init]
positions = "sc"
temperature = 1.0
[run]
events = 10
"#,
            &[],
        )
        .unwrap();
        Potentials::from_scene(&scene)
    }

    fn settings() -> LoopSettings {
        LoopSettings {
            rebase_events: 1_000_000,
            seed: 1,
            debug_check_events: 1,
            skin: 0.2,
            start_time: 0.0,
        }
    }

    #[test]
    fn head_on_pair_collides_at_contact_and_crosses_cells() {
        let pots = hs_potentials();
        assert!(pots.all_hard_spheres());
        let model = HardSpheres::new(pots, vec![Particle::new(1.0).unwrap()]);
        let l = DVec3::splat(10.0);
        let pos = [DVec3::new(2.0, 5.0, 5.0), DVec3::new(6.0, 5.0, 5.0)];
        let vel = [DVec3::new(1.0, 0.0, 0.0), DVec3::new(-1.0, 0.0, 0.0)];
        let mut sim: Simulation<_, LazyQueue<HeapQueue<Ticket>>> =
            Simulation::new(l, &pos, &vel, &[0, 0], model, settings()).unwrap();
        // Contact at distance 1: each moves 1.5, at t = 1.5; cell crossings happen on the way.
        let mut events = 0;
        while sim.counters().core == 0 {
            sim.run(Stop::Events(1), &mut NoSampler, &mut |_| {})
                .unwrap();
            events += 1;
            assert!(events < 20);
        }
        assert!((sim.time() - 1.5).abs() < 1e-14, "{}", sim.time());
        assert!(sim.counters().shell >= 1);
        let b = sim.bodies();
        assert_eq!(b[0].v, DVec3::new(-1.0, 0.0, 0.0));
        assert_eq!(b[1].v, DVec3::new(1.0, 0.0, 0.0));
        sim.check().unwrap();
        let _ = StepPotential::new(&[[1.0, f64::INFINITY]]);
    }

    /// Two spheres on parallel courses whose centres pass `b` apart: a collision if and only if
    /// `b < σ`, however close to σ; the grazing impulse is tiny and exact.
    #[test]
    fn grazing_collisions_are_decided_by_the_impact_parameter() {
        for (b, hits) in [
            (1.0 - 1e-12, true),
            (1.0 - 1e-15, true),
            (1.0 + 1e-12, false),
        ] {
            let model = HardSpheres::new(hs_potentials(), vec![Particle::new(1.0).unwrap()]);
            let pos = [DVec3::new(2.0, 5.0, 5.0), DVec3::new(6.0, 5.0 + b, 5.0)];
            let vel = [DVec3::new(1.0, 0.0, 0.0), DVec3::new(-1.0, 0.0, 0.0)];
            let mut sim: Simulation<_, LazyQueue<HeapQueue<Ticket>>> =
                Simulation::new(DVec3::splat(10.0), &pos, &vel, &[0, 0], model, settings())
                    .unwrap();
            sim.run(Stop::Time(3.0), &mut NoSampler, &mut |_| {})
                .unwrap();
            assert_eq!(sim.counters().core == 1, hits, "b = {b}");
            assert_eq!(sim.anomalies().total(), 0);
            let k = sim.kinetic_energy();
            assert!((k - 1.0).abs() < 1e-15, "b = {b}: K = {k}");
            sim.check().unwrap();
            if hits {
                // The impulse is along the nearly perpendicular line of centres: tiny.
                let v0 = sim.bodies()[0].v;
                assert!(v0.x < 1.0 && v0.x > 0.999_99 && v0.y.abs() < 1e-5, "{v0}");
            }
        }
    }

    /// Generations are u32 and wrap; a wrap must not make stale events look current.
    #[test]
    fn generations_wrap_safely() {
        let model = HardSpheres::new(hs_potentials(), vec![Particle::new(1.0).unwrap()]);
        let mut pos = Vec::new();
        for x in 0..4 {
            for y in 0..4 {
                for z in 0..4 {
                    pos.push(DVec3::new(f64::from(x), f64::from(y), f64::from(z)) * 1.6 + 0.5);
                }
            }
        }
        let vel = crate::config::init::maxwell_boltzmann(&vec![1.0; pos.len()], 1.0, 9);
        let mut sim: Simulation<_, LazyQueue<HeapQueue<Ticket>>> = Simulation::new(
            DVec3::splat(6.4),
            &pos,
            &vel,
            &vec![0; pos.len()],
            model,
            settings(),
        )
        .unwrap();
        for b in &mut sim.bodies {
            b.generation = u32::MAX - 3;
        }
        sim.predict_all();
        sim.run(Stop::Events(5000), &mut NoSampler, &mut |_| {})
            .unwrap();
        assert!(
            sim.bodies.iter().any(|b| b.generation < 100),
            "no generation wrapped"
        );
        assert_eq!(sim.anomalies().total(), 0);
        sim.check().unwrap();
    }

    /// A start written at a collision and read back from text has pairs inside the core by
    /// round-off: they start at contact (and part at once if they approach); a real overlap is
    /// still refused.
    #[test]
    fn a_start_inside_the_core_by_round_off_is_at_contact() {
        for (d, accepted) in [
            (1.0 - 1e-13, true),
            (1.0 - 1e-11, true),
            (1.0 - 1e-7, false),
        ] {
            let model = HardSpheres::new(hs_potentials(), vec![Particle::new(1.0).unwrap()]);
            let pos = [DVec3::new(4.0, 5.0, 5.0), DVec3::new(4.0 + d, 5.0, 5.0)];
            let vel = [DVec3::new(1.0, 0.0, 0.0), DVec3::new(-1.0, 0.0, 0.0)];
            let r: Result<Simulation<_, LazyQueue<HeapQueue<Ticket>>>, _> =
                Simulation::new(DVec3::splat(10.0), &pos, &vel, &[0, 0], model, settings());
            let Ok(mut sim) = r else {
                assert!(!accepted, "refused at distance {d}");
                assert!(matches!(r, Err(SetupError::Overlap { i: 0, j: 1, .. })));
                continue;
            };
            assert!(accepted, "accepted at distance {d}");
            sim.run(Stop::Events(1), &mut NoSampler, &mut |_| {})
                .unwrap();
            assert_eq!(sim.counters().core, 1);
            assert_eq!(sim.time(), 0.0);
            assert_eq!(sim.bodies()[0].v, DVec3::new(-1.0, 0.0, 0.0));
            sim.check().unwrap();
        }
    }

    #[test]
    fn overlapping_start_and_small_box_are_refused() {
        let model = HardSpheres::new(hs_potentials(), vec![Particle::new(1.0).unwrap()]);
        let pos = [DVec3::new(0.2, 5.0, 5.0), DVec3::new(9.7, 5.0, 5.0)];
        let r: Result<Simulation<_, LazyQueue<HeapQueue<Ticket>>>, _> = Simulation::new(
            DVec3::splat(10.0),
            &pos,
            &[DVec3::ZERO; 2],
            &[0, 0],
            model.clone(),
            settings(),
        );
        assert!(matches!(r, Err(SetupError::Overlap { i: 0, j: 1, .. })));
        let r: Result<Simulation<_, LazyQueue<HeapQueue<Ticket>>>, _> = Simulation::new(
            // Cells of 1 + 2 × 0.2: two fit along y = 2.8, not along 2.7.
            DVec3::new(10.0, 2.7, 10.0),
            &[DVec3::ZERO, DVec3::splat(1.2)],
            &[DVec3::ZERO; 2],
            &[0, 0],
            model,
            settings(),
        );
        assert!(matches!(r, Err(SetupError::BoxTooSmall { axis: 'y', .. })));
    }
}
