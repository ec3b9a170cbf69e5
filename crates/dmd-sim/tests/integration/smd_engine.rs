//! The standard-MD engine on scene files (issue 8): `engine = "smd"` and `dmd run --engine
//! smd` write the event-driven engine's files and a summary of their own; small N, short times.

use std::path::{Path, PathBuf};
use std::process::Command;

use dmd_sim::run::{Quiet, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::smd_engine::{self, SmdSummary};

/// 216 of the paper's rods (6³ on a simple cubic lattice, the smallest sc box whose half side
/// exceeds r_u + skin = 3σ + 0.6σ), molecular units, with the event-driven engine's keys.
const RODS: &str = r#"
version = 1
seed = 11
units = "molecular"
engine = "smd"
[box]
density = 0.0178853806
[[species]]
name = "rod"
count = 216
mass = 18.0
inertia = 1.154
[[pair]]
species = ["rod", "rod"]
potential = { kind = "rods", epsilon = 3.0, sigma = 3.035, zeta = 1.0 }
terraces = { step_kt = 0.5 }
[init]
positions = "sc"
temperature = 505.144
[thermostat]
kind = "andersen"
rate = 20.0
[search]
max_step = 0.004
[run]
equilibration_time = 0.6
time = 0.3
[smd]
dt = 0.0018
[output]
sample_interval = 0.009
rdf = { bins = 50, r_max = 11.0, every = 2 }
msd = { max_lag = 0.09 }
vacf = { max_lag = 0.09 }
orientation_acf = { max_lag = 0.09 }
series = true
trajectory = { interval = 0.1 }
"#;

/// 256 Lennard-Jones spheres, reduced units, ρ* = 0.5, T* = 2 (no terraces: smd needs none).
const LJ: &str = r#"
version = 1
engine = "smd"
[box]
density = 0.5
[[species]]
name = "A"
count = 256
[[pair]]
species = ["A", "A"]
potential = { kind = "lennard-jones", epsilon = 1.0, sigma = 1.0 }
[init]
positions = "fcc"
temperature = 2.0
[run]
equilibration_time = 0.2
time = 0.4
[smd]
dt = 0.002
"#;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dmd-smd-engine-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn run(text: &str, overrides: &[&str], out: Option<&Path>) -> SmdSummary {
    let o: Vec<String> = overrides.iter().map(|s| (*s).to_owned()).collect();
    let scene = Scene::from_str_with(text, &o).unwrap_or_else(|e| panic!("{e}"));
    smd_engine::run(&scene, Path::new("."), out).unwrap_or_else(|e| panic!("{e}"))
}

fn header(path: &Path) -> String {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .next()
        .unwrap_or("")
        .to_owned()
}

#[test]
fn a_rods_scene_with_smd_writes_the_event_driven_files_and_holds_its_temperature() {
    let dir = tmp("rods");
    let s = run(RODS, &[], Some(&dir));
    for f in [
        "summary.json",
        "rdf.csv",
        "rdf.svg",
        "msd.csv",
        "vacf.csv",
        "oacf.csv",
        "series.csv",
        "series-energy.svg",
        "series-pressure.svg",
        "trajectory.xyz",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing; wrote {:?}", s.files);
    }
    // The same columns as the event-driven engine writes.
    assert_eq!(
        header(&dir.join("series.csv")),
        "t,kinetic,potential,total,temperature,pressure"
    );
    assert_eq!(
        header(&dir.join("oacf.csv")),
        "t,s0_dot_st,s0_dot_st_error,p2,p2_error"
    );
    assert_eq!(
        header(&dir.join("vacf.csv")),
        "t,vacf,vacf_error,vacf_normalised,vacf_normalised_error"
    );
    // 0.3 ps of 1.8 fs steps (rounded to 167); the trajectory every 0.1 ps = 56 steps from
    // t = 0: frames at steps 0, 56 and 112, with the rods' orientation columns.
    assert_eq!((s.steps, s.equilibration_steps), (167, 333));
    assert!(
        (s.sim_time - 167.0 * 0.0018).abs() < 1e-12,
        "{}",
        s.sim_time
    );
    let xyz = std::fs::read_to_string(dir.join("trajectory.xyz")).unwrap();
    let frames: Vec<&str> = xyz.lines().filter(|l| l.starts_with("Lattice=")).collect();
    assert_eq!(frames.len(), 3, "{}", frames.len());
    assert!(frames[0].contains("orientation:R:4"));
    // Equilibrated by rescaling to 505 K; NVE production keeps it within a few per cent.
    assert!(
        (s.temperature - 505.144).abs() < 0.06 * 505.144,
        "T = {} K",
        s.temperature
    );
    let rot = s.rotational_temperature.expect("rods rotate");
    assert!((rot - 505.144).abs() < 0.15 * 505.144, "T_rot = {rot} K");
    // Every average carries its error, as the event-driven engine's does.
    for (what, e) in [
        ("T_trans", Some(s.translational_temperature_error)),
        ("T_rot", s.rotational_temperature_error),
        ("D (MSD)", s.diffusion_msd_error),
        ("D (VACF)", s.diffusion_vacf_error),
    ] {
        assert!(e.is_some_and(|e| e.is_finite() && e > 0.0), "{what}: {e:?}");
    }
    // A liquid: the potential energy per rod is negative, a few ε (ε = 3 kJ/mol).
    assert!(
        s.potential_energy_per_body < -3.0 && s.potential_energy_per_body > -20.0,
        "U/N = {} kJ/mol",
        s.potential_energy_per_body
    );
    assert_eq!(s.model, "smd-rods");
    assert_eq!(s.smoothing, [2.5 * 3.035, 3.0 * 3.035]);
    assert!(
        s.ignored_keys.contains(&"pair[0].terraces".to_owned()),
        "{:?}",
        s.ignored_keys
    );
    assert!(
        s.ignored_keys.contains(&"search".to_owned()),
        "{:?}",
        s.ignored_keys
    );
    assert!(s.neighbour_list_builds > 0 && s.ns_per_particle_step > 0.0);
    // summary.json has the common fields under the event-driven engine's names.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["engine"], "smd");
    for key in [
        "n_bodies",
        "sim_time",
        "temperature",
        "potential_energy_per_body",
        "pressure",
        "cpu_seconds",
        "wall_seconds",
        "dt",
        "steps",
        "ns_per_particle_step",
        "energy_drift_per_body",
        "energy_total_std",
        "neighbour_list_builds",
    ] {
        assert!(json[key].is_number(), "summary.json lacks {key}: {json}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_engine_flag_runs_the_shipped_paper_scene() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = tmp("flag");
    let out = Command::new(env!("CARGO_BIN_EXE_dmd"))
        .current_dir(&root)
        .args(["run", "scenes/rods-paper.toml", "--engine", "smd", "--out"])
        .arg(&dir)
        .args([
            "--set",
            "run.equilibration_time=0.09",
            "--set",
            "run.time=0.09",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("engine smd"), "{stdout}");
    assert!(
        stdout.contains("ignored (event-driven only): pair[0].terraces, search"),
        "{stdout}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["engine"], "smd");
    assert_eq!(json["n_bodies"], 512);
    assert_eq!(json["steps"], 50);
    assert_eq!(json["dt"], 0.0018);
    // `dmd check --engine smd` checks for that engine: run lengths in events are refused.
    let check = Command::new(env!("CARGO_BIN_EXE_dmd"))
        .current_dir(&root)
        .args([
            "check",
            "scenes/rods-paper.toml",
            "--engine",
            "smd",
            "--set",
            "run.time=",
            "--set",
            "run.events=1000",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&check.stderr);
    assert_eq!(check.status.code(), Some(2), "{err}");
    assert!(
        err.contains("scene key `run.events`: not available with engine = \"smd\""),
        "{err}"
    );
    // Checkpoints are the event-driven engine's: refused, exit status 2.
    let ck = Command::new(env!("CARGO_BIN_EXE_dmd"))
        .current_dir(&root)
        .args([
            "run",
            "scenes/rods-paper.toml",
            "--engine",
            "smd",
            "--checkpoint-every",
            "1m",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&ck.stderr);
    assert_eq!(ck.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--checkpoint-every is not available with engine = \"smd\""),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_lennard_jones_scene_runs_and_the_event_driven_runner_refuses_it() {
    let s = run(LJ, &[], None);
    assert_eq!(s.model, "smd-lennard-jones");
    assert_eq!((s.steps, s.equilibration_steps), (200, 100));
    // NVE equilibration (no thermostat) from the lattice: the liquid's temperature is below
    // the initial 2.0 and stays within reach of it.
    assert!(
        s.temperature > 1.2 && s.temperature < 2.2,
        "T = {}",
        s.temperature
    );
    // Smoothed Lennard-Jones at ρ* = 0.5: U/N ≈ −3 for the full potential.
    assert!(
        s.potential_energy_per_body < -2.0 && s.potential_energy_per_body > -4.0,
        "U/N = {}",
        s.potential_energy_per_body
    );
    assert_eq!(s.rotational_temperature, None);
    // A cut-off beyond half the box (L = 8 here) is refused when the scene is read, so
    // `dmd check` catches it too.
    let e = Scene::from_str_with(LJ, &["smd.smoothing.r_u=4.0".to_owned()]).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("scene key `smd.smoothing.r_u`: the cut-off 4 reaches half"),
        "{e}"
    );
    // The event-driven runner never runs an smd scene silently.
    let scene = Scene::from_str_with(LJ, &[]).unwrap();
    let e = run_scene(&scene, Path::new("."), None, &mut Quiet).unwrap_err();
    assert!(e.to_string().starts_with("scene key `engine`"), "{e}");
}

#[test]
fn the_energy_drift_is_small_and_the_fluctuation_grows_as_dt_squared() {
    let fine = run(LJ, &["smd.dt=0.001", "run.time=0.2"], None);
    let coarse = run(LJ, &["smd.dt=0.002", "run.time=0.2"], None);
    assert!(
        fine.relative_energy_drift < 1e-5,
        "drift {}",
        fine.relative_energy_drift
    );
    assert!(
        fine.energy_fluctuation_over_potential_std < 1e-3,
        "{}",
        fine.energy_fluctuation_over_potential_std
    );
    // A second-order integrator: halving dt divides the fluctuation of E by about 4.
    let ratio = coarse.energy_total_std / fine.energy_total_std;
    assert!(ratio > 2.8 && ratio < 5.5, "ratio {ratio}");
}

#[test]
fn gay_berne_rods_run_with_the_window_shifted_to_the_end_to_end_contact() {
    // GB(1.5, 5, 2, 1) at ρσ₀³ = 0.1: on the sc lattice (spacing 2.15σ₀) no two rods touch.
    let text = r#"
version = 1
engine = "smd"
[box]
density = 0.1
[[species]]
name = "gb"
count = 512
inertia = 0.1
[[pair]]
species = ["gb", "gb"]
potential = { kind = "gay-berne", sigma0 = 1.0, epsilon0 = 1.0, kappa = 1.5 }
[init]
positions = "sc"
temperature = 1.5
[run]
time = 0.2
"#;
    let s = run(text, &[], None);
    assert_eq!(s.model, "smd-gay-berne");
    // 003 Eq. 26's 2.5σ and 3σ beyond σ, from the end-to-end contact κσ₀ = 1.5.
    assert_eq!(s.smoothing, [3.0, 3.5]);
    // The default step, min(0.0028 σ √(m/kT), √(I/kT)/30) at kT = 1.5, and no blow-up.
    assert!(
        (s.dt - 0.0028 / 1.5f64.sqrt()).abs() < 1e-15,
        "dt = {}",
        s.dt
    );
    assert!(
        s.relative_energy_drift < 1e-3,
        "{}",
        s.relative_energy_drift
    );
    assert!(s.rotational_temperature.is_some());
}

#[test]
fn a_trajectory_frame_starts_a_run_from_a_file_with_its_orientations() {
    // The first frame of an smd trajectory (positions, and the rods' orientation column) is a
    // valid `init.file` for the next run: the mapping reads files as the event-driven engine.
    let dir = tmp("file");
    run(
        RODS,
        &[
            "run.equilibration_time=0.018",
            "run.time=0.018",
            "output.trajectory.interval=0.009",
        ],
        Some(&dir),
    );
    let xyz = std::fs::read_to_string(dir.join("trajectory.xyz")).unwrap();
    let first: Vec<&str> = xyz.lines().take(2 + 216).collect();
    let file = dir.join("start.xyz");
    std::fs::write(&file, first.join("\n") + "\n").unwrap();
    let o = [
        "init.positions=file".to_owned(),
        "init.orientations=file".to_owned(),
        format!("init.file=\"{}\"", file.display()),
        "box.density=".to_owned(),
        "run.equilibration_time=0".to_owned(),
        "run.time=0.018".to_owned(),
        "output=".to_owned(),
    ];
    let scene = Scene::from_str_with(RODS, &o).unwrap_or_else(|e| panic!("{e}"));
    let s = smd_engine::run(&scene, Path::new("."), None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((s.n_bodies, s.steps, s.equilibration_steps), (216, 10, 0));
    assert!(s.rotational_temperature.is_some_and(|t| t > 0.0));
    // A missing file is an error naming the key, not a panic.
    let o2: Vec<String> = o
        .iter()
        .map(|x| {
            if x.starts_with("init.file") {
                format!("init.file=\"{}\"", dir.join("none.xyz").display())
            } else {
                x.clone()
            }
        })
        .collect();
    let scene = Scene::from_str_with(RODS, &o2).unwrap();
    let e = smd_engine::run(&scene, Path::new("."), None).unwrap_err();
    assert!(e.to_string().starts_with("scene key `init.file`"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
