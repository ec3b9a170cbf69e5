//! SPC/E water (`scenes/water-spce.toml`, `kind = "spc-e"`): three-site rigid molecules with
//! site–site Lennard-Jones and damped shifted force Coulomb terms, run by both engines through
//! the library as `dmd run` runs them, a few hundred events or a few tens of femtoseconds.

use std::path::{Path, PathBuf};

use dmd_sim::run::{Quiet, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::smd_engine::{self, Engine};

fn scene_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/water-spce.toml")
}

/// The shipped scene with `overrides`, without its own lengths of run and outputs.
fn water(overrides: &[&str]) -> Scene {
    let text = std::fs::read_to_string(scene_path()).expect("the shipped scene");
    let mut o: Vec<String> = ["run.equilibration_time=", "run.time=", "output="]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    o.extend(overrides.iter().map(|s| (*s).to_owned()));
    Scene::from_str_with(&text, &o).unwrap_or_else(|e| panic!("{e}"))
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dmd-spce-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn terraced_spc_e_conserves_energy_and_misses_nothing() {
    let dir = scratch("dmd");
    let scene = water(&[
        "run.equilibration_events=300",
        "run.events=1500",
        "output.sample_interval=0.0005",
    ]);
    let s =
        run_scene(&scene, Path::new("."), Some(&dir), &mut Quiet).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.model, "terraced-tops");
    assert_eq!(s.n_bodies, 1000);
    assert_eq!(s.detected_misses, 0);
    assert!(
        s.relative_energy_drift <= 1e-10,
        "{}",
        s.relative_energy_drift
    );
    // A few hundred events into the melting of the lattice: the smooth estimator runs along
    // (the molecules still sit near their sites, U/N of order kJ/mol).
    let smooth = s
        .potential_energy_per_body_smooth
        .expect("smooth estimator");
    assert!((-60.0..20.0).contains(&smooth), "U/N = {smooth} kJ/mol");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn standard_md_runs_spc_e_as_rigid_tops() {
    let dir = scratch("smd");
    let mut scene = water(&[
        "species.0.count=512",
        "run.equilibration_time=0.02",
        "run.time=0.02",
        "output.sample_interval=0.002",
    ]);
    scene.engine = Engine::Smd;
    let s = smd_engine::run(&scene, Path::new("."), Some(&dir)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.model, "smd-spc-e");
    assert!(
        (-60.0..-5.0).contains(&s.potential_energy_per_body),
        "U/N = {} kJ/mol",
        s.potential_energy_per_body
    );
    assert!(
        s.relative_energy_drift < 1e-2,
        "{}",
        s.relative_energy_drift
    );
    // The window is the potential's own: site cut-off 9 Å ∓ twice the hydrogens' arm.
    assert!(
        (s.smoothing[1] - 10.928_283).abs() < 1e-5,
        "{:?}",
        s.smoothing
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_hard_core_above_the_barrier_is_refused_naming_the_key() {
    let scene = water(&["pair.0.terraces.core=1e6", "run.events=10"]);
    let e = run_scene(&scene, Path::new("."), None, &mut Quiet).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("pair[0].terraces.core") && msg.contains("barrier"),
        "{msg}"
    );
}

#[test]
fn bad_keys_of_the_kind_are_named() {
    let text = std::fs::read_to_string(scene_path()).unwrap();
    for (set, key) in [
        ("pair.0.potential.r_cut=3.0", "pair[0].potential.r_cut"),
        ("pair.0.potential.alpha=-0.1", "pair[0].potential.alpha"),
    ] {
        let e = Scene::from_str_with(&text, &[set.to_owned()]).unwrap_err();
        assert!(e.to_string().contains(key), "{set}: {e}");
    }
}
