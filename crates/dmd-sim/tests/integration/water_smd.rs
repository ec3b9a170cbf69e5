//! The standard-MD engine on SSD/E water (`scenes/water-ssd.toml`): rigid asymmetric tops on a
//! full-attitude potential, run through the library as `dmd run --engine smd` runs them;
//! 343 molecules and a few tens of femtoseconds.

use std::path::Path;

use dmd_sim::run::{Quiet, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::smd_engine::{self, Engine};

use crate::support::scratch;

/// The water scene with `overrides`, shortened: 7³ molecules (a 21.7 Å box, whose half side
/// exceeds the 9 Å cut-off plus the skin), 0.03 ps of equilibration and of production.
fn water(overrides: &[&str]) -> Scene {
    let text = crate::support::shipped_text("water-ssd.toml");
    let mut o: Vec<String> = [
        "species.0.count=343",
        "run.equilibration_time=0.03",
        "run.time=0.03",
        "output.sample_interval=0.002",
        "output.msd.max_lag=0.01",
        "output.orientation_acf.max_lag=0.01",
    ]
    .iter()
    .map(|s| (*s).to_owned())
    .collect();
    o.extend(overrides.iter().map(|s| (*s).to_owned()));
    let mut scene = Scene::from_str_with(&text, &o).unwrap_or_else(|e| panic!("{e}"));
    scene.engine = Engine::Smd;
    scene
}

/// The frames of `dir/trajectory.xyz`, each as its count, comment and one line per molecule.
fn frames(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("trajectory.xyz")).expect("a trajectory");
    let lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let mut out = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let n: usize = lines[k].trim().parse().expect("a frame's count");
        out.push(lines[k..k + n + 2].to_vec());
        k += n + 2;
    }
    out
}

/// The attitude quaternion of each molecule of a frame (the `orientation:R:4` columns).
fn attitudes(frame: &[String]) -> Vec<[f64; 4]> {
    frame[2..]
        .iter()
        .map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .skip(7)
                .take(4)
                .map(|x| x.parse().unwrap())
                .collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

/// Distance of two unit quaternions up to sign (about half the angle between the attitudes).
fn turn(a: [f64; 4], b: [f64; 4]) -> f64 {
    let d = |s: f64| {
        (0..4)
            .map(|k| (a[k] - s * b[k]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    d(1.0).min(d(-1.0))
}

fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    x[x.len() / 2]
}

/// Both engines start from one state: positions, velocities and attitudes of the first frame
/// agree to the last digit written, and 0.02 fs later the attitudes still agree to
/// 1 % of how far the molecules turned (the spins agree: different spins would part the
/// attitudes as fast as they turn; the forces' part grows as the square of the time).
#[test]
fn both_engines_start_water_from_the_same_state() {
    // 512 molecules: a 24.9 Å box, two cells of the event-driven engine's reach and skin.
    let short = [
        "species.0.count=512",
        "run.equilibration_time=0",
        "run.time=0.00002",
        "smd.dt=0.00002",
        "output.trajectory={interval=0.00002}",
    ];
    let dirs = [scratch("water-start-smd"), scratch("water-start-dmd")];
    let smd = water(&short);
    smd_engine::run(&smd, Path::new("."), Some(&dirs[0])).unwrap_or_else(|e| panic!("{e}"));
    let mut dmd = water(&short);
    dmd.engine = Engine::Dmd;
    run_scene(&dmd, Path::new("."), Some(&dirs[1]), &mut Quiet).unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (frames(&dirs[0]), frames(&dirs[1]));
    assert_eq!((a.len(), b.len()), (2, 2));
    assert_eq!(a[0].len(), 514);
    for (k, (x, y)) in a[0].iter().zip(&b[0]).enumerate() {
        assert_eq!(x, y, "line {k} of frame 0");
    }
    let (q0, qa, qb) = (attitudes(&a[0]), attitudes(&a[1]), attitudes(&b[1]));
    let turned = median(q0.iter().zip(&qa).map(|(x, y)| turn(*x, *y)).collect());
    let apart = median(qa.iter().zip(&qb).map(|(x, y)| turn(*x, *y)).collect());
    assert!(turned > 1e-5, "the molecules turn: {turned}");
    assert!(
        apart < 0.01 * turned,
        "attitudes {apart} apart after turning {turned}"
    );
    for d in dirs {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn water_runs_with_the_smd_engine() {
    let dir = scratch("water-smd");
    let s =
        smd_engine::run(&water(&[]), Path::new("."), Some(&dir)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.model, "smd-ssd-e");
    assert_eq!(s.n_bodies, 343);
    for e in [
        s.energy_total_start,
        s.energy_total_end,
        s.energy_kinetic,
        s.energy_potential,
        s.potential_energy_per_body,
        s.temperature,
    ] {
        assert!(e.is_finite(), "{s:?}");
    }
    // Hydrogen-bonded liquid: tens of kJ/mol per molecule, bound.
    assert!(
        (-60.0..-10.0).contains(&s.potential_energy_per_body),
        "U/N = {} kJ/mol",
        s.potential_energy_per_body
    );
    // NVE production at the default step: the total energy stays put.
    // NVE production at the default step, right after the lattice melted (the largest forces
    // of the run): the total energy stays within a fraction of a per cent.
    assert!(
        s.relative_energy_drift < 1e-2,
        "drift {}",
        s.relative_energy_drift
    );
    assert!(
        s.energy_fluctuation_over_potential_std < 0.02,
        "std(E)/std(U) = {}",
        s.energy_fluctuation_over_potential_std
    );
    // Equilibration ends with a rescaling to the bath, all six degrees of freedom included.
    assert!(
        (s.temperature_start - 298.15).abs() < 1e-6,
        "{}",
        s.temperature_start
    );
    let t_rot = s.rotational_temperature.expect("tops rotate");
    assert!(t_rot.is_finite() && t_rot > 0.0, "T_rot = {t_rot} K");
    assert_eq!(s.smoothing, [7.65, 9.0]);
    for f in ["summary.json", "rdf.csv", "msd.csv", "oacf.csv"] {
        assert!(dir.join(f).is_file(), "{f} missing: {:?}", s.files);
    }
    let rdf = std::fs::read_to_string(dir.join("rdf.csv")).unwrap();
    assert!(rdf.lines().count() > 100, "rdf.csv has its bins");
    let json = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    assert!(json.contains("\"potential_energy_per_body\""));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn water_refuses_a_smoothing_window_with_the_reason() {
    let e = smd_engine::run(&water(&["smd.smoothing.r_l=7.0"]), Path::new("."), None).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("smd.smoothing") && msg.contains("`ssd-e`") && msg.contains("9 Å"),
        "{msg}"
    );
}

#[test]
fn water_in_a_box_too_small_for_the_cut_off_is_refused_naming_the_box() {
    let e = smd_engine::run(&water(&["species.0.count=125"]), Path::new("."), None).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("`box`") && msg.contains("cut-off 9"), "{msg}");
}
