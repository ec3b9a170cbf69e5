//! Scenes of semi-flexible molecules (species with `bonds`) through `run_scene`, as `dmd run`
//! runs them: the shipped chains shortened (energy, bonds, anomalies, degrees of freedom), the
//! defaults of `[rattle]`, a molecule the bonds hold rigid, and determinism.

use std::path::Path;

use dmd_sim::flexible_scene::{FlexiblePlan, STEP_BOND_FRACTION, rattle_settings};
use dmd_sim::run::{Quiet, Summary, run_scene};
use dmd_sim::scene::Scene;

use crate::support;
use crate::support::{run_shipped as run, shipped};

fn assert_healthy(s: &Summary, what: &str) {
    assert_eq!(s.model, "semi-flexible", "{what}");
    support::assert_conserved(s, what, 1e-10);
    let bond = s
        .bond_error
        .expect("semi-flexible runs report their bond error");
    assert!(bond < 1e-5, "{what}: bond error {bond}");
    let r = s
        .rattle
        .expect("semi-flexible runs report RATTLE statistics");
    assert_eq!(r.failures, 0, "{what}");
    assert!(r.steps > 0 && r.restarts > 0, "{what}: {r:?}");
    assert!(s.reflections > 0, "{what}: no collision");
    assert!(s.terrace_crossings > 0, "{what}: no well entered");
}

#[test]
fn the_flexible_chains_scene_runs_conserving_energy_and_bonds() {
    let dir = std::env::temp_dir().join(format!("dmd-flexible-chains-{}", std::process::id()));
    let s = run(
        "flexible-chains.toml",
        &["run.equilibration_time=1.0", "run.time=3.0"],
        Some(&dir),
    );
    assert_healthy(&s, "flexible chains");
    assert_eq!(s.n_bodies, 125);
    // Three translational and 3·4 − 3 − 3 = 6 internal degrees of freedom per chain, less the
    // conserved momentum in NVE.
    assert_eq!(s.degrees_of_freedom, 9.0 * 125.0 - 3.0);
    // Started at kT = 1.5 and thermostatted for a while: the temperature stays near it.
    assert!((s.temperature - 1.5).abs() < 0.3, "{}", s.temperature);
    for f in ["rdf.csv", "msd.csv", "vacf.csv", "series.csv"] {
        assert!(s.files.iter().any(|x| x == f), "{f} missing: {:?}", s.files);
        assert!(dir.join(f).exists(), "{f}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_rattle_defaults_follow_the_bonds_and_the_temperature() {
    let (scene, _) = shipped("flexible-chains.toml", &["rattle="]);
    let plan = FlexiblePlan::of(&scene).unwrap();
    let r = rattle_settings(&scene, &plan);
    // Shortest bond 0.6 (atoms 0–1), unit masses, kT = 1.5.
    let h = STEP_BOND_FRACTION * 0.6 / 1.5f64.sqrt();
    assert!((r.step - h).abs() < 1e-12 * h, "{} vs {h}", r.step);
    assert_eq!(r.tolerance, 1e-12);
    assert!(r.rescale);
    let (scene, _) = shipped(
        "flexible-chains.toml",
        &["rattle.rescale=false", "rattle.tolerance=1e-10"],
    );
    let r = rattle_settings(&scene, &FlexiblePlan::of(&scene).unwrap());
    assert_eq!((r.step, r.tolerance, r.rescale), (0.005, 1e-10, false));
}

#[test]
fn without_rescaling_the_energy_takes_the_interpolants_error() {
    let common = [
        "run.equilibration_time=0.0",
        "thermostat=",
        "run.time=2.0",
        "rattle.step=0.02",
        "output=",
    ];
    let mut on = common.to_vec();
    on.push("rattle.rescale=true");
    let mut off = common.to_vec();
    off.push("rattle.rescale=false");
    let kept = run("flexible-chains.toml", &on, None);
    let raw = run("flexible-chains.toml", &off, None);
    assert!(kept.relative_energy_drift < 1e-10, "{kept:?}");
    // O((ωh)²) per event at h = 0.02: far above round-off.
    assert!(
        raw.relative_energy_drift > 1e-6,
        "{}",
        raw.relative_energy_drift
    );
}

#[test]
fn a_molecule_held_rigid_by_its_bonds_still_runs_with_rattle() {
    // A dumbbell with its one bond: no internal freedom left but the rotation.
    let text = r#"
version = 1
seed = 3
[box]
density = 0.1
[[species]]
name = "dumbbell"
count = 64
sites = [
  { kind = "A", mass = 1.0, position = [0.0, 0.0, 0.0] },
  { kind = "A", mass = 1.0, position = [0.6, 0.0, 0.0] },
]
bonds = [[0, 1]]
[[site_pair]]
sites = ["A", "A"]
steps = [[1.0, inf], [1.3, -1.0]]
[init]
positions = "sc"
temperature = 1.5
[run]
time = 2.0
"#;
    let scene = Scene::from_str_with(text, &[]).unwrap();
    let a = run_scene(&scene, Path::new("."), None, &mut Quiet).unwrap();
    assert_eq!(a.model, "semi-flexible");
    // Two rotational degrees of freedom per dumbbell: 3 + 2 each, less the momentum.
    assert_eq!(a.degrees_of_freedom, 5.0 * 64.0 - 3.0);
    assert!(
        a.relative_energy_drift < 1e-10,
        "{}",
        a.relative_energy_drift
    );
    assert!(a.bond_error.unwrap() < 1e-5, "{:?}", a.bond_error);
    assert_eq!(a.anomalies, 0);
    // The same seed gives the same run.
    let b = run_scene(&scene, Path::new("."), None, &mut Quiet).unwrap();
    assert_eq!(a.events, b.events);
    assert_eq!(a.energy_total_end, b.energy_total_end);
}

/// 27 free trimers, heavy ends on a light centre, with tiny cores between molecules: the bonds'
/// metric `det Z = 1.21 − cos²θ` varies by a factor 5.8 with the bend angle θ.
const TRIMERS: &str = r#"version = 1
seed = 3
[box]
density = 0.05
[[species]]
name = "trimer"
count = 27
sites = [
  { kind = "E", mass = 10.0, position = [1.0, 0.0, 0.0] },
  { kind = "M", mass = 1.0, position = [0.0, 0.0, 0.0] },
  { kind = "E", mass = 10.0, position = [0.0, 1.0, 0.0] },
]
bonds = [[0, 1], [1, 2]]
[[site_pair]]
sites = ["E", "E"]
steps = [[0.05, inf]]
[[site_pair]]
sites = ["E", "M"]
steps = [[0.05, inf]]
[[site_pair]]
sites = ["M", "M"]
steps = [[0.05, inf]]
[init]
positions = "sc"
temperature = 1.0
[run]
equilibration_time = 1.0
[hmc]
segment_time = 1.0
segments = 12
"#;

#[test]
fn hmc_of_flexible_molecules_samples_the_dynamics_or_the_stiff_bond_measure() {
    // The dynamics' own measure: with the rescaled RATTLE interpolant H is conserved to
    // round-off, so every segment is accepted.
    let d = support::run_with(TRIMERS, &[]);
    let h = d.hmc.expect("an hmc summary");
    assert_eq!((h.segments, h.accepted), (12, 12), "{h:?}");
    assert!(h.delta_h_max_abs < 1e-9, "{h:?}");
    // Stiff bonds: the acceptance also weighs √(det Z₀/det Z₁), which rejects segments whose
    // ΔH is round-off. (The distributions are checked in `cargo xtask validate`.)
    let s = support::run_with(TRIMERS, &["hmc.measure=\"stiff-bonds\""]);
    let h = s.hmc.expect("an hmc summary");
    assert_eq!(h.measure, "stiff-bonds");
    let rejected = |cause: &str| h.rejected_by_cause.get(cause).copied().unwrap_or(0);
    assert!(h.accepted > 0 && rejected("energy") > 0, "{h:?}");
    assert_eq!(rejected("overlap") + rejected("non_finite"), 0, "{h:?}");
    assert!(h.delta_h_max_abs < 1e-9, "{h:?}");
}
