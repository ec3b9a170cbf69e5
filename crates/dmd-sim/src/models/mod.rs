//! Body models plugged into the event loop: terraced rigid bodies on smooth potentials,
//! rigid site molecules, semi-flexible molecules. Each imports the engine and the shared
//! pieces here (`search`: the root-search driver; `site_pairs`: what site models share;
//! `molecule`: a rigid molecule type; `rotor`: the free rotation of a terraced body), never
//! another model.

pub mod flexible;
pub mod molecule;
pub mod rotor;
pub mod search;
pub mod site_pairs;
pub mod sites;
pub mod spherocylinders;
pub mod terraced;
