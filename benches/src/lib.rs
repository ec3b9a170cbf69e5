//! Criterion benchmarks of the `dmd` workspace, one file per crate in `benches/benches/`.
//!
//! Run them with `cargo xtask bench` (all) or `cargo xtask bench --only NAME`. Timings on shared
//! machines are noisy: every benchmark measures its baseline in the same run, and the numbers
//! quoted in `docs/PERFORMANCE.md` are medians and ratios to that baseline.
//!
//! This library holds the workload generators the benchmark files share.
