//! Energy: fluctuation against the time step, drift at the paper's step.

use crate::common;
use crate::common::{energies, std_dev, with_dt};
use smd::units;

/// Ratio of std(E) at `dt` to std(E) at `dt/2` from the same state, sampled at the same
/// times over `span` (short enough that the two trajectories stay close, so that the ratio
/// measures the integrator and not the sampling of two diverging trajectories).
fn ratio<P: potential::PairPotential + Clone>(
    base: &smd::Integrator<potential::Smoothed<P>>,
    dt: f64,
    span: f64,
    every: f64,
) -> f64 {
    let steps = (span / dt).round() as u64;
    let mut a = with_dt(base, dt);
    let mut b = with_dt(base, 0.5 * dt);
    let ea = energies(&mut a, steps, (every / dt).round() as u64);
    let eb = energies(&mut b, 2 * steps, (every / (0.5 * dt)).round() as u64);
    assert_eq!(ea.len(), eb.len());
    std_dev(&ea) / std_dev(&eb)
}

/// The splitting is second order: its energy error (the distance to the shadow Hamiltonian it
/// conserves) scales as dt². Halving the step must divide the fluctuation of E by ≈ 4 (the
/// rods approach 4 from above as dt → 0: at 1.8 fs → 0.9 fs the ratio is ≈ 4.5-5, the
/// libration of these light rods in their neighbours' cage is fast; see VALIDATION.md).
#[test]
fn energy_fluctuation_shrinks_as_dt_squared() {
    let rods = common::rods(256, 300, 7);
    let r = ratio(
        &rods,
        units::from_fs(0.9),
        units::from_fs(180.0),
        units::from_fs(1.8),
    );
    eprintln!("rods, 0.9 fs / 0.45 fs: std(E) ratio {r:.3}");
    assert!((r - 4.0).abs() < 0.5, "rods: ratio {r}");
    let lj = common::lj(256, 300, 0.004);
    let r = ratio(&lj, 0.004, 0.4, 0.008);
    eprintln!("LJ, dt 0.004 / 0.002: std(E) ratio {r:.3}");
    assert!((r - 4.0).abs() < 0.5, "LJ: ratio {r}");
}

/// At the paper's 1.8 fs the energy fluctuates but does not drift: the least-squares slope
/// over 3.6 ps moves E by much less than its fluctuation, and the fluctuation itself is small
/// against the kinetic energy.
#[test]
fn no_drift_at_the_papers_time_step() {
    let mut md = common::rods(256, 300, 11);
    let every = 10;
    let e = energies(&mut md, 2000, every);
    let t: Vec<f64> = (0..e.len()).map(|k| k as f64).collect();
    let slope = smd::observe::slope(&t, &e);
    let change = slope * (e.len() - 1) as f64;
    let fluct = std_dev(&e);
    let kt = 1.4 * 3.0;
    eprintln!(
        "1.8 fs over 3.6 ps: fitted change {change:.3e}, std {fluct:.3e} kJ/mol (N kT = {})",
        256.0 * kt
    );
    assert!(
        change.abs() < fluct,
        "drift {change} against fluctuation {fluct}"
    );
    assert!(fluct < 1e-3 * 256.0 * kt, "fluctuation {fluct}");
}
