//! `dmd-sim`: an event-driven ("discontinuous") molecular dynamics simulator for spheres, rigid
//! bodies on terraced smooth potentials, and rigid and semi-flexible site molecules.
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
//! Rigid bodies ([`terraced`], seed 003) — rods, or bodies of any shape such as SSD/E or SPC/E water
//! molecules, whose rotation is a [`rotor::Rotor`] — interact through a smooth
//! orientation-dependent pair potential mapped onto energy terraces; they rotate exactly between
//! events, their event times are found by root searches with virtual events, and the impulse
//! follows the smooth force and torques.
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

// The layers, each importing only those before it (checked by `tests/integration/layers.rs`): engine ←
// models ← analysis ← config ← driver ← the `dmd` binary.
mod analysis;
mod config;
mod driver;
mod engine;
mod models;

pub use analysis::{block, observable, output, reference, site_rdf, smooth};
pub use config::{
    flexible_scene, init, kinds, limits, plan, rods, scene, site_scene, smd_spec,
    spherocylinder_scene, units,
};
pub use driver::{chains, checkpoint, hmc, interrupt, outdir, run, smd_engine, tune};
pub use engine::{
    body, cell, event, model, neighbour, pair_state, potential, saved, schedule, simulation, sum,
};
pub use models::{flexible, molecule, rotor, search, site_pairs, sites, spherocylinders, terraced};

/// The README's example, compiled and run as a doctest so it cannot go stale.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
