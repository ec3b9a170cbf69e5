//! Workspace-level integration tests: the `dmd` crates used together, the way a simulator uses
//! them. The tests live in `tests/tests/`; this library holds nothing but shared test helpers.
