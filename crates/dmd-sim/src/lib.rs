//! `dmd-sim`: an event-driven ("discontinuous") molecular dynamics simulator for spheres and
//! rigid rods.
//!
//! Bodies move freely and exactly between events; at an event a pair reaches a step of its
//! stepped radial potential (a hard core, the edge of a square well, a terrace of a stepped
//! Lennard-Jones potential) and the impulse rule of [`collide`] changes their velocities. The
//! event loop ([`simulation::Simulation`]) keeps a local clock per body, neighbour lists built on
//! cells, the level of every interacting pair, and its pending events in per-body lists, with
//! each body's earliest in an `event_queue` scheduler and lazy invalidation at both levels;
//! event times of spheres are analytic (a quadratic per boundary), and the time origin is
//! re-based periodically.
//!
//! Rigid rods ([`terraced`], seed 003) interact through a smooth orientation-dependent pair
//! potential mapped onto energy terraces; they rotate exactly between events, their event times
//! are found by root searches with virtual events, and the impulse follows the smooth force and
//! torques.
//!
//! The `dmd` command runs a scene file ([`scene`], documented key by key in
//! `docs/USER-GUIDE.md`) and writes `summary.json`, observables and trajectories
//! ([`run::run_scene`]).
//!
//! ```
//! use dmd_sim::scene::Scene;
//! use dmd_sim::run::{run_scene, Quiet};
//!
//! // 108 hard spheres at ρσ³ = 0.5 on an fcc lattice, 20 000 events.
//! let scene = Scene::from_str_with(r#"
//!     version = 1
//!     [box]
//!     density = 0.5
//!     [[species]]
//!     name = "A"
//!     count = 108
//!     [[pair]]
//!     species = ["A", "A"]
//!     steps = [[1.0, inf]]
//!     [init]
//!     positions = "fcc"
//!     temperature = 1.0
//!     [run]
//!     equilibration_events = 5000
//!     events = 20000
//! "#, &[])?;
//! let summary = run_scene(&scene, std::path::Path::new("."), None, &mut Quiet)?;
//! assert_eq!(summary.events, 20_000);
//! assert!(summary.relative_energy_drift < 1e-13);
//! assert!(summary.compressibility > 2.5 && summary.compressibility < 4.0); // Z ≈ 3.27
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod block;
pub mod body;
pub mod cell;
pub mod chains;
pub mod checkpoint;
pub mod event;
// Issue 10, second half: semi-flexible molecules (RATTLE between events).
pub mod flexible;
pub mod flexible_scene;
pub mod hmc;
pub mod init;
pub mod interrupt;
pub mod limits;
mod load;
pub mod model;
pub mod neighbour;
pub mod observable;
pub mod outdir;
pub mod output;
pub mod pair_state;
mod pairs;
pub mod potential;
pub mod reference;
mod reporting;
pub mod rods;
pub mod run;
pub mod scene;
pub mod search;
// Issue 10: rigid site-based molecules (seed 000).
pub mod schedule;
pub mod simulation;
pub mod site_pairs;
pub mod site_scene;
pub mod sites;
// Issue 8: the standard-MD engine on the same scenes.
pub mod smd_engine;
pub mod smd_spec;
pub mod smooth;
pub mod sum;
pub mod terraced;
pub mod units;

/// The README's example, compiled and run as a doctest so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
