//! The event loop and what it is made of: bodies on straight lines, cells and neighbour lists,
//! the level of every pair, per-body event lists and the scheduler, stepped potentials, the
//! model contract ([`model::PairModel`]) and the loop generic over it
//! ([`simulation::Simulation`]). It knows nothing of scenes, files or any one body model beyond
//! the two built into the contract (hard spheres and radial steps).

pub mod body;
pub mod cell;
pub mod event;
pub(crate) mod fault;
pub(crate) mod hash;
pub mod model;
pub mod neighbour;
pub mod pair_state;
pub mod potential;
pub mod saved;
pub mod schedule;
pub mod simulation;
pub mod sum;
