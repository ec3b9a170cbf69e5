//! Scenes: the only reader of TOML. The keys (`scene`), units, initial configurations, the
//! limits that keep a run's time and memory bounded, one module per body kind with its
//! checks and construction, and `load`, the one place that branches on the body kind.

pub mod flexible_scene;
pub mod init;
pub mod kinds;
pub mod limits;
pub(crate) mod load;
pub mod plan;
pub mod rods;
pub mod scene;
pub mod site_scene;
pub mod smd_spec;
pub mod spherocylinder_scene;
pub mod units;
