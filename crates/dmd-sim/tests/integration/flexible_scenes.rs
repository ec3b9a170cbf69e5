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

/// Eight trimers far apart (heavy ends on a light centre, unit bonds) whose two ends, two bonds
/// apart, keep a hard core of 1.2 between them (`interact_beyond_bonds = 1`): the bend angle
/// θ at the centre cannot close below `2 asin 0.6 = 73.7°`. Andersen collisions throughout
/// make the dynamics sample its canonical measure.
const CORED_TRIMERS: &str = r#"version = 1
seed = 5
[box]
density = 0.001
[[species]]
name = "trimer"
count = 8
sites = [
  { kind = "E", mass = 10.0, position = [1.0, 0.0, 0.0] },
  { kind = "M", mass = 1.0, position = [0.0, 0.0, 0.0] },
  { kind = "E", mass = 10.0, position = [0.0, 1.0, 0.0] },
]
bonds = [[0, 1], [1, 2]]
interact_beyond_bonds = 1
[[site_pair]]
sites = ["E", "E"]
steps = [[1.2, inf], [1.5, -0.5]]
[[site_pair]]
sites = ["E", "M"]
steps = [[0.05, inf]]
[[site_pair]]
sites = ["M", "M"]
steps = [[0.05, inf]]
[init]
positions = "sc"
temperature = 1.0
[thermostat]
kind = "andersen"
rate = 1.0
during = "always"
[run]
equilibration_time = 5.0
time = 1000.0
[output]
trajectory = { interval = 0.5 }
"#;

/// `cos²θ` of the bend angle of every trimer in every frame of `trajectory.xyz` (three atoms
/// per molecule, in order), and the smallest distance between two ends of one trimer.
fn bend_angles(xyz: &str) -> (Vec<f64>, f64) {
    let mut lines = xyz.lines();
    let (mut c2, mut closest) = (Vec::new(), f64::INFINITY);
    while let Some(n) = lines.next() {
        let n: usize = n.trim().parse().unwrap();
        let comment = lines.next().unwrap();
        let lattice = comment.split("Lattice=\"").nth(1).unwrap();
        let l: Vec<f64> = lattice
            .split('"')
            .next()
            .unwrap()
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        let atoms: Vec<[f64; 3]> = (0..n)
            .map(|_| {
                let f: Vec<f64> = lines
                    .next()
                    .unwrap()
                    .split_whitespace()
                    .skip(1)
                    .take(3)
                    .map(|x| x.parse().unwrap())
                    .collect();
                [f[0], f[1], f[2]]
            })
            .collect();
        // Minimum image in the cubic box.
        let d = |a: [f64; 3], b: [f64; 3]| -> [f64; 3] {
            let mut r = [0.0; 3];
            for k in 0..3 {
                let x = a[k] - b[k];
                r[k] = x - l[4 * k] * (x / l[4 * k]).round();
            }
            r
        };
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for m in atoms.chunks(3) {
            let (u, w) = (d(m[0], m[1]), d(m[2], m[1]));
            let c = dot(u, w) / (dot(u, u) * dot(w, w)).sqrt();
            c2.push(c * c);
            let e = d(m[0], m[2]);
            closest = closest.min(dot(e, e).sqrt());
        }
    }
    (c2, closest)
}

#[test]
fn sites_of_one_molecule_beyond_the_given_bonds_interact() {
    // NVE: the ends' own events conserve energy and bonds, and they happen.
    let nve = support::run_with(
        CORED_TRIMERS,
        &[
            "thermostat.during=\"equilibration\"",
            "run.time=100.0",
            "output.trajectory.interval=10.0",
        ],
    );
    assert_healthy(&nve, "trimers with cored ends");
    // The canonical bend-angle distribution: sin θ times the bonds' metric √det Z,
    // det Z = 1.21 − cos²θ (000 §II.A), times e^{−βU} of the ends' well (U = −0.5 below 1.5),
    // on the angles the core allows. In x = cos θ, the ends' distance is √(2 − 2x): the core
    // (1.2) allows x ≤ 0.28, the well holds x > −0.125.
    let density = |x: f64| {
        let boltzmann = if x > -0.125 { 0.5f64.exp() } else { 1.0 };
        boltzmann * (1.21 - x * x).sqrt()
    };
    let simpson = |f: &dyn Fn(f64) -> f64, a: f64, b: f64| {
        let n = 2000;
        let h = (b - a) / n as f64;
        let inner: f64 = (1..n)
            .map(|k| f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 })
            .sum();
        (f(a) + f(b) + inner) * h / 3.0
    };
    let moment = |p: i32| {
        simpson(&|x| x.powi(p) * density(x), -1.0, -0.125)
            + simpson(&|x| x.powi(p) * density(x), -0.125, 0.28)
    };
    let exact = moment(2) / moment(0);
    // Without the metric it would be 0.2242; without the ends' interaction 0.2763.
    assert!((exact - 0.1771).abs() < 1e-4, "{exact}");
    let d = support::scratch("cored-trimers");
    let s = support::run_text(
        CORED_TRIMERS,
        &[],
        &d,
        &support::options(CORED_TRIMERS, &[], None, false),
    )
    .unwrap();
    assert_eq!(s.anomalies, 0);
    let (c2, closest) = bend_angles(&std::fs::read_to_string(d.join("trajectory.xyz")).unwrap());
    assert!(
        closest >= 1.2 * (1.0 - 1e-6),
        "ends at {closest} inside their core"
    );
    // Blocks of 40 frames (20 τ, far beyond the angle's correlation time) per molecule.
    let per_frame: Vec<f64> = c2.chunks(8).map(|f| f.iter().sum::<f64>() / 8.0).collect();
    let blocks: Vec<f64> = per_frame
        .chunks(40)
        .map(|b| b.iter().sum::<f64>() / b.len() as f64)
        .collect();
    let n = blocks.len() as f64;
    let mean = blocks.iter().sum::<f64>() / n;
    let sd = (blocks.iter().map(|b| (b - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let err = sd / n.sqrt();
    assert!(err < 0.01, "error {err}: too short to tell");
    assert!(
        (mean - exact).abs() < 4.0 * err,
        "⟨cos²θ⟩ = {mean} ± {err}, exact {exact}"
    );
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn own_site_pairs_resume_bit_for_bit_and_run_under_hmc() {
    use dmd_sim::checkpoint::{self, Every};
    let nve = [
        "thermostat.during=\"equilibration\"".to_owned(),
        "run.time=40.0".to_owned(),
        "output.trajectory.interval=2.0".to_owned(),
    ];
    let straight = support::scratch("cored-straight");
    let a = support::run_text(
        CORED_TRIMERS,
        &nve,
        &straight,
        &support::options(CORED_TRIMERS, &nve, None, false),
    )
    .unwrap();
    assert!(a.reflections > 0 && a.terrace_crossings > 0, "{a:?}");
    let crashed = support::scratch("cored-crashed");
    let e = support::run_text(
        CORED_TRIMERS,
        &nve,
        &crashed,
        &support::options(CORED_TRIMERS, &nve, Some(Every::Events(20_000)), true),
    )
    .unwrap_err();
    assert!(matches!(e, dmd_sim::run::RunError::Halted), "{e}");
    let r = support::resume(&crashed.join(checkpoint::FILE_NAME));
    assert_eq!(support::physics(&a), support::physics(&r));
    support::same_files(&straight, &crashed, &["trajectory.xyz"]);
    // HMC: with the rescaled interpolant H is conserved to round-off through the ends' own
    // events, so every segment is accepted.
    let h = support::run_with(
        CORED_TRIMERS,
        &[
            "thermostat.during=\"equilibration\"",
            "run.time=",
            "output.trajectory=",
            "hmc.segment_time=5.0",
            "hmc.segments=8",
        ],
    )
    .hmc
    .expect("an hmc summary");
    assert_eq!((h.segments, h.accepted), (8, 8), "{h:?}");
    assert!(h.delta_h_max_abs < 1e-9, "{h:?}");
    let _ = std::fs::remove_dir_all(straight);
    let _ = std::fs::remove_dir_all(crashed);
}
