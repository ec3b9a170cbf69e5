//! The integration tests of this crate, gathered into one test binary: one link instead of one
//! per file, which is most of a fresh build's time.

mod degenerate;
mod oracle_ellip;
mod propagate_cli;
mod properties;
mod reference;
mod special_functions;
