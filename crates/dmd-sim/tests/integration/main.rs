//! The integration tests of this crate, gathered into one test binary: one link instead of one
//! per file, which is most of a fresh build's time.

mod chains;
mod checkpoint;
mod cli_robust;
mod errors;
mod every_scene;
mod flexible;
mod flexible_scenes;
mod fuzz;
mod gsd_output;
mod gsd_start;
mod hmc;
mod layers;
mod mixed_scenes;
mod physics;
mod plots;
mod reference;
mod rods;
mod rods_scenes;
mod scene_errors;
mod sites;
mod sites_scenes;
mod smd_engine;
mod smooth;
mod spherocylinders;
mod support;
mod terminal;
mod tops;
mod trajectory_tools;
mod tune;
mod water_smd;
mod water_spce;
