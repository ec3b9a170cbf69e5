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

/// The text of the shipped scene `name`.
pub(crate) fn shipped_text(name: &str) -> String {
    std::fs::read_to_string(scenes_dir().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
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

/// 108 square-well spheres (core σ, well 1.5σ deep ε) at ρσ³ = 0.5 from an fcc lattice at
/// kT = 1.5ε, without `[run]` or `[output]`: tests add their own.
pub(crate) const WELL_FLUID: &str = r#"version = 1
[box]
density = 0.5
[[species]]
name = "A"
count = 108
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf], [1.5, -1.0]]
[init]
positions = "fcc"
temperature = 1.5
"#;

/// Runs scene `text` with `overrides` (no output folder).
pub(crate) fn run_with(text: &str, overrides: &[&str]) -> Summary {
    let o: Vec<String> = overrides.iter().map(|s| (*s).to_owned()).collect();
    let scene = Scene::from_str_with(text, &o).unwrap_or_else(|e| panic!("{e}"));
    run_scene(&scene, Path::new("."), None, &mut Quiet).unwrap_or_else(|e| panic!("{e}"))
}

/// Starts `dmd run --quiet SCENE --out OUT`, waits until production has started (its
/// trajectory is being written: the scene must ask for `output.trajectory`) and 0.2 s more,
/// and sends SIGTERM `signals` times, 20 ms apart. Gives the command's output and the time
/// from the first signal to its end.
pub(crate) fn run_and_signal(
    scene: &Path,
    out: &Path,
    signals: usize,
) -> (std::process::Output, std::time::Duration) {
    let args = [
        "run".as_ref(),
        "--quiet".as_ref(),
        scene.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    signal_command(&args, &out.join("trajectory.xyz.partial"), 200, signals)
}

/// Starts `dmd ARGS`, waits until `ready` exists and `delay_ms` more, and sends SIGTERM
/// `signals` times, 20 ms apart. Gives the command's output and the time from the first
/// signal to its end.
pub(crate) fn signal_command(
    args: &[&std::ffi::OsStr],
    ready: &Path,
    delay_ms: u64,
    signals: usize,
) -> (std::process::Output, std::time::Duration) {
    use std::time::{Duration, Instant};
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_dmd"))
        .args(args)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !ready.exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(delay_ms));
    let sent = Instant::now();
    for _ in 0..signals {
        let k = std::process::Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status()
            .unwrap();
        assert!(k.success());
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = child.wait_with_output().unwrap();
    (o, sent.elapsed())
}

/// `summary.json` of `dir` without its timings.
pub(crate) fn summary_without_timings(dir: &Path) -> serde_json::Value {
    let mut v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    for k in [
        "wall_seconds",
        "cpu_seconds",
        "events_per_second",
        "events_per_cpu_second",
        "pair_events_per_second",
        "pair_events_per_cpu_second",
    ] {
        v.as_object_mut().unwrap().remove(k);
    }
    v
}

/// The scene `text` (which asks for a trajectory) is run in `d` and stopped by SIGTERM in
/// production: the command says where it saved the checkpoint and how to resume, exits with
/// status 130 and writes no summary; `dmd resume` of that checkpoint then gives `files` and a
/// summary identical (timings excepted) to those of the same run never stopped.
pub(crate) fn signal_then_resume_is_bit_for_bit(d: &Path, text: &str, files: &[&str]) {
    let s = d.join("scene.toml");
    std::fs::write(&s, text).unwrap();
    let stopped = d.join("stopped");
    let (o, _) = run_and_signal(&s, &stopped, 1);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(130), "{err}");
    let ck = stopped.join("checkpoint.dmd");
    assert!(
        err.starts_with(&format!(
            "dmd: {}: stopped by a signal after saving {}",
            s.display(),
            ck.display()
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!("dmd resume {}", ck.display())),
        "{err}"
    );
    assert!(!stopped.join("summary.json").exists());
    let dmd = |args: &[&std::ffi::OsStr]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_dmd"))
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    dmd(&["resume".as_ref(), "--quiet".as_ref(), ck.as_os_str()]);
    let straight = d.join("straight");
    dmd(&[
        "run".as_ref(),
        "--quiet".as_ref(),
        s.as_os_str(),
        "--out".as_ref(),
        straight.as_os_str(),
    ]);
    same_files(&stopped, &straight, files);
    assert_eq!(
        summary_without_timings(&stopped),
        summary_without_timings(&straight)
    );
}
