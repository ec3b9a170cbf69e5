//! Hard spherocylinders against a known result: at low density the compressibility factor of
//! the collision virial is `Z = 1 + B₂ρ + B₃ρ² + …` with Onsager's exact second virial
//! coefficient of spherocylinders of segment length `L` and diameter `D`,
//! `B₂ = 2πD³/3 + πD²L + πDL²/4` (half the orientation-averaged excluded volume, whose
//! `⟨|sin γ|⟩ = π/4` gives the last term). `B₃` of convex hard bodies lies between 0 and the
//! hard-sphere ratio `B₃/B₂² = 5/8`, which bounds the rest at the density chosen.

use std::f64::consts::PI;

use crate::support::run_shipped;

#[test]
fn low_density_pressure_follows_onsagers_second_virial_coefficient() {
    let (l, d) = (3.0, 1.0);
    let b2 = 2.0 * PI * d * d * d / 3.0 + PI * d * d * l + PI * d * l * l / 4.0;
    // B₂ρ = 0.1: the B₃ term is at most 0.00625.
    let rho = 0.1 / b2;
    let density = format!("box.density={rho}");
    let s = run_shipped(
        "hard-spherocylinders.toml",
        &[
            density.as_str(),
            "run.equilibration_events=20000",
            "run.events=300000",
            "output.sample_interval=2.0",
        ],
        None,
    );
    assert_eq!(s.model, "hard-spherocylinders");
    assert_eq!(s.anomalies, 0, "{:?}", s.anomalies_by_kind);
    // The model's own counters reach the summary, over production: a prediction per pair
    // event at least.
    let predictions = s.model_counts["spherocylinders.predictions"];
    assert!(
        predictions >= s.events - s.virtual_events && predictions < 100 * s.events,
        "{predictions} predictions for {} events: {:?}",
        s.events,
        s.model_counts
    );
    let sigma = s.pressure_error.expect("sampled") / s.pressure_ideal;
    let excess = s.compressibility - 1.0;
    assert!(
        sigma < 0.003,
        "the run is too short to test B₂: σ(Z) = {sigma}"
    );
    let (lo, hi) = (0.1 - 4.0 * sigma, 0.1 + 0.625 * 0.01 + 4.0 * sigma);
    assert!(
        (lo..=hi).contains(&excess),
        "Z − 1 = {excess} ± {sigma}, expected B₂ρ + B₃ρ² in [0.1, 0.10625]"
    );
}
