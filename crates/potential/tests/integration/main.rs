//! The integration tests of this crate, gathered into one test binary: one link instead of one
//! per file, which is most of a fresh build's time.

mod certify;
mod common;
mod extremes;
mod forces;
mod gay_berne_reference;
mod rigid_water;
mod site_water;
mod terraces;
