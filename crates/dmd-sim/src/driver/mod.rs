//! Runs: the phases of a run of either engine, hybrid Monte Carlo chains, checkpoints,
//! ensembles of chains and sweeps, signals and output folders.

pub mod chains;
pub mod checkpoint;
pub mod hmc;
pub mod interrupt;
pub mod outdir;
pub(crate) mod reporting;
pub mod run;
pub mod smd_engine;
pub mod tune;
