//! Set-up shared by the integration tests: the shipped scenes, scratch folders, runs with
//! checkpoints and their comparison. Each test binary uses a part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use dmd_sim::checkpoint::{self, Every, SceneSource};
use dmd_sim::run::{Quiet, RunError, RunOptions, Summary, run_scene, run_scene_with};
use dmd_sim::scene::Scene;

/// The folder of the shipped scenes.
pub(crate) fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// Every shipped scene file, sorted by name.
pub(crate) fn shipped_scenes() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

/// A shipped scene with `overrides` (as `--set`) and the folder its paths are relative to.
pub(crate) fn shipped(name: &str, overrides: &[&str]) -> (Scene, PathBuf) {
    let o: Vec<String> = overrides.iter().map(|s| (*s).to_owned()).collect();
    Scene::load(&scenes_dir().join(name), &o).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Runs a shipped scene with `overrides`, writing into `out` if given.
pub(crate) fn run_shipped(name: &str, overrides: &[&str], out: Option<&Path>) -> Summary {
    let (scene, base) = shipped(name, overrides);
    run_scene(&scene, &base, out, &mut Quiet).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// An empty scratch folder of this test process.
pub(crate) fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dmd-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Run options carrying the scene's source (so that its checkpoints can be resumed), with
/// checkpoints `every` and, with `halt`, a stop right after the first one (as a crash).
pub(crate) fn options(
    text: &str,
    overrides: &[String],
    every: Option<Every>,
    halt: bool,
) -> RunOptions {
    RunOptions {
        checkpoint_every: every,
        source: Some(SceneSource {
            text: text.to_owned(),
            overrides: overrides.to_vec(),
            base: scenes_dir(),
            file: PathBuf::from("test.toml"),
        }),
        resume: None,
        halt_after_checkpoint: halt,
    }
}

/// Runs the scene `text` with `overrides` into `out`.
///
/// # Errors
/// The run's.
pub(crate) fn run_text(
    text: &str,
    overrides: &[String],
    out: &Path,
    opts: &RunOptions,
) -> Result<Summary, RunError> {
    let scene = Scene::from_str_with(text, overrides).unwrap();
    run_scene_with(&scene, &scenes_dir(), Some(out), &mut Quiet, opts)
}

/// Resumes the checkpoint at `path` into its folder.
pub(crate) fn resume(path: &Path) -> Summary {
    let c = checkpoint::read(path).unwrap();
    let scene = Scene::from_str_with(&c.source.text, &c.source.overrides).unwrap();
    let out = path.parent().unwrap().to_owned();
    let opts = RunOptions {
        resume: Some((path.to_owned(), c)),
        ..RunOptions::default()
    };
    run_scene_with(&scene, &scenes_dir(), Some(&out), &mut Quiet, &opts).unwrap()
}

/// The summary without what depends on the machine or on the scheduler's bookkeeping.
pub(crate) fn physics(s: &Summary) -> serde_json::Value {
    let mut v = serde_json::to_value(s).unwrap();
    let o = v.as_object_mut().unwrap();
    for k in [
        "wall_seconds",
        "cpu_seconds",
        "events_per_second",
        "events_per_cpu_second",
        "pair_events_per_second",
        "pair_events_per_cpu_second",
        "queue_pushed",
        "queue_stale_dropped",
        "queue_stale_swept",
        "requeued",
    ] {
        o.remove(k);
    }
    v
}

/// Asserts that the files `names` are byte for byte the same in folders `a` and `b`.
pub(crate) fn same_files(a: &Path, b: &Path, names: &[&str]) {
    for n in names {
        let x = std::fs::read(a.join(n)).unwrap_or_else(|e| panic!("{n}: {e}"));
        let y = std::fs::read(b.join(n)).unwrap_or_else(|e| panic!("{n}: {e}"));
        assert!(
            x == y,
            "{n} differs between the straight and the resumed run"
        );
    }
}

/// Asserts what every event-driven run keeps: energy to `drift` (relative), momentum, no
/// anomaly and no detected miss.
pub(crate) fn assert_conserved(s: &Summary, what: &str, drift: f64) {
    assert!(
        s.relative_energy_drift < drift,
        "{what}: drift {}",
        s.relative_energy_drift
    );
    assert!(s.momentum_drift < 1e-11, "{what}: {}", s.momentum_drift);
    assert_eq!(s.anomalies, 0, "{what}: {:?}", s.anomalies_by_kind);
    assert_eq!(s.detected_misses, 0, "{what}: {:?}", s.search);
}

/// Reduced units: σ = ε = m = 1, rods with ζ = 0.33 σ and I = 0.0069 m σ² (the paper's rods:
/// ζ/σ = 1/3.035, I/(mσ²) = 1.154/(18 · 3.035²)).
/// 125 of them at ρσ³ = 0.5 and kT = 1.4 ε, Andersen-equilibrated for 0.5 τ, then 0.5 τ NVE.
pub(crate) const REDUCED_RODS: &str = r#"
version = 1
seed = 3
[box]
density = 0.5
[[species]]
name = "rod"
count = 125
mass = 1.0
inertia = 0.00696
[[pair]]
species = ["rod", "rod"]
potential = { kind = "rods", epsilon = 1.0, sigma = 1.0, zeta = 0.3295 }
terraces = { step_kt = 0.5 }
[init]
positions = "sc"
temperature = 1.4
[thermostat]
kind = "andersen"
rate = 2.0
[run]
equilibration_time = 0.5
time = 0.5
"#;

/// Runs scene `text` with `overrides` (no output folder).
pub(crate) fn run_with(text: &str, overrides: &[&str]) -> Summary {
    let o: Vec<String> = overrides.iter().map(|s| (*s).to_owned()).collect();
    let scene = Scene::from_str_with(text, &o).unwrap_or_else(|e| panic!("{e}"));
    run_scene(&scene, Path::new("."), None, &mut Quiet).unwrap_or_else(|e| panic!("{e}"))
}
