//! What is measured and written: observables sampled from a read-only view of the state,
//! smooth estimators of terraced runs, block-average errors, output files and plots, and
//! reference equations of state. It reads the engine's view, never a scene.

pub mod block;
pub mod observable;
pub mod output;
pub(crate) mod pairs;
pub mod reference;
pub mod site_rdf;
pub mod smooth;
