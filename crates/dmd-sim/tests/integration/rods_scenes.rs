//! Rods scenes through `run_scene`, as `dmd run` runs them: the shipped paper scene, units,
//! extreme state points and terrace choices, determinism, trajectories with orientations read
//! back, the thermostat, and the verification grid catching misses of a coarse search.

use std::path::Path;

use dmd_sim::run::{Quiet, Summary, run_scene};
use dmd_sim::scene::Scene;

use crate::support::{REDUCED_RODS as RODS, run_with as run};

fn assert_healthy(s: &Summary, what: &str) {
    assert!(
        s.relative_energy_drift < 1e-12,
        "{what}: drift {}",
        s.relative_energy_drift
    );
    assert!(s.momentum_drift < 1e-12, "{what}: {}", s.momentum_drift);
    assert_eq!(s.anomalies, 0, "{what}: {:?}", s.anomalies_by_kind);
    assert_eq!(s.detected_misses, 0, "{what}: {:?}", s.search);
    assert!(s.terrace_crossings > 0, "{what}");
    // The generic report of the model's counters says what the decoded one says.
    let search = s.search.expect("rods search");
    assert_eq!(s.model_counts["search.searches"], search.searches, "{what}");
    assert_eq!(s.model_counts["search.roots"], search.roots, "{what}");
}

#[test]
fn the_shipped_paper_scene_runs_in_molecular_units() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/rods-paper.toml");
    let o: Vec<String> = [
        "run.equilibration_time=0.3",
        "run.time=0.2",
        "output.rdf.every=1",
    ]
    .iter()
    .map(|s| (*s).to_owned())
    .collect();
    let (scene, base) = Scene::load(&path, &o).unwrap();
    let dir = std::env::temp_dir().join(format!("dmd-rods-paper-{}", std::process::id()));
    let s = run_scene(&scene, &base, Some(&dir), &mut Quiet).unwrap();
    assert_healthy(&s, "paper scene");
    assert_eq!(
        (s.model.as_str(), s.units.as_str()),
        ("terraced-rods", "molecular")
    );
    assert_eq!(s.n_bodies, 512);
    // 2 × 512 rods' degrees of freedom besides translation.
    assert_eq!(s.degrees_of_freedom, 5.0 * 512.0 - 3.0);
    // Kelvin, around the scene's 505 K after a short equilibration.
    assert!((s.temperature - 505.0).abs() < 60.0, "{}", s.temperature);
    let rot = s.rotational_temperature.unwrap();
    assert!((rot - 505.0).abs() < 80.0 && (s.translational_temperature - 505.0).abs() < 80.0);
    // The paper's rate at ΔV = kT/2 is 4.7e4 per ps; a short run lands within 30 %.
    assert!(
        (s.pair_event_rate() - 4.7e4).abs() < 0.3 * 4.7e4,
        "{} events per ps",
        s.pair_event_rate()
    );
    assert!(s.virtual_events > 0);
    for f in ["rdf.csv", "msd.csv", "vacf.csv", "oacf.csv", "series.csv"] {
        assert!(s.files.iter().any(|x| x == f), "{f} missing: {:?}", s.files);
    }
    // The orientational autocorrelation starts at 1 and decays.
    let oacf = std::fs::read_to_string(dir.join("oacf.csv")).unwrap();
    let rows: Vec<Vec<f64>> = oacf
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert!((rows[0][1] - 1.0).abs() < 1e-12 && (rows[0][3] - 1.0).abs() < 1e-12);
    assert!(rows.last().unwrap()[1] < 0.9, "{:?}", rows.last());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn runs_are_deterministic_and_queue_independent() {
    let strip = |s: Summary| {
        (
            s.events,
            s.energy_total_end,
            s.terrace_crossings,
            s.reflections,
            s.virtual_events,
            s.temperature,
            s.pressure,
        )
    };
    let a = strip(run(RODS, &[]));
    assert_eq!(a, strip(run(RODS, &[])));
    assert_eq!(a, strip(run(RODS, &["run.queue=bounded"])));
    assert_ne!(a, strip(run(RODS, &["seed=4"])));
}

/// The issue's extreme and stiff cases, each conserving energy with no miss detected.
#[test]
fn extreme_state_points_and_terraces() {
    for (what, overrides) in [
        ("ΔV = 5 kT", vec!["pair.0.terraces.step_kt=5"]),
        (
            "ΔV = kT/20",
            vec![
                "pair.0.terraces.step_kt=0.05",
                "species.0.count=343",
                "run.time=0.05",
                "run.equilibration_time=0.05",
            ],
        ),
        ("T* = 10", vec!["init.temperature=10"]),
        (
            "gas T* = 10, ρ* = 0.01",
            vec![
                "init.temperature=10",
                "box.density=0.01",
                "run.time=5",
                "run.equilibration_time=2",
            ],
        ),
        (
            "aligned start",
            vec!["init.orientations=aligned", "init.axis=[0, 0, 1]"],
        ),
        (
            "equal-volume levels, B2-matched energies",
            vec![
                "pair.0.terraces.placement=equal-volume",
                "pair.0.terraces.step_energy=virial",
            ],
        ),
        (
            "grid search",
            vec!["search.method=grid", "search.max_step=0.002"],
        ),
        ("no virtual events", vec!["search.window=inf"]),
    ] {
        let s = run(RODS, &overrides);
        assert_healthy(&s, what);
    }
}

/// A level within 1e-9 of the potential's minimum is refused with the reason, or shifted.
#[test]
fn a_level_on_the_minimum_is_refused_or_shifted() {
    // Levels (k − ½)ΔV with ΔV = 2/3 put one on U_min = −1 (within round-off).
    let bad = [
        "pair.0.terraces.step_kt=",
        "pair.0.terraces.step=0.6666666666666666",
    ];
    let scene = Scene::from_str_with(
        RODS,
        &bad.iter().map(|s| (*s).to_owned()).collect::<Vec<_>>(),
    )
    .unwrap();
    let e = run_scene(&scene, Path::new("."), None, &mut Quiet).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("scene key `pair[0].terraces`: level -1 lies on the potential's minimum"),
        "{e}"
    );
    let mut shifted = bad.to_vec();
    shifted.push("pair.0.terraces.near_minimum=shift");
    assert_healthy(&run(RODS, &shifted), "shifted level");
}

#[test]
fn trajectories_carry_orientations_that_read_back() {
    let dir = std::env::temp_dir().join(format!("dmd-rods-traj-{}", std::process::id()));
    let scene =
        Scene::from_str_with(RODS, &["output.trajectory={ interval = 0.25 }".to_owned()]).unwrap();
    let s = run_scene(&scene, Path::new("."), Some(&dir), &mut Quiet).unwrap();
    assert!(s.files.iter().any(|f| f == "trajectory.xyz"));
    let text = std::fs::read_to_string(dir.join("trajectory.xyz")).unwrap();
    let header = text.lines().nth(1).unwrap();
    assert!(header.contains("orientation:R:4"), "{header}");
    // Unit quaternions, scalar last.
    for line in text.lines().skip(2).take(125) {
        let v: Vec<f64> = line
            .split_whitespace()
            .skip(7)
            .take(4)
            .map(|x| x.parse().unwrap())
            .collect();
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-9, "{line}");
    }
    // The last frame starts a new run with its positions and orientations.
    let frames: Vec<&str> = text.lines().collect();
    let last = frames[frames.len() - 127..].join("\n");
    std::fs::write(dir.join("last.xyz"), &last).unwrap();
    let restart = RODS.replace(
        "positions = \"sc\"",
        "positions = \"file\"\nfile = \"last.xyz\"\norientations = \"file\"",
    );
    let scene = Scene::from_str_with(
        &restart,
        &[
            "box.density=".to_owned(),
            "run.equilibration_time=0".to_owned(),
        ],
    )
    .unwrap();
    let s = run_scene(&scene, &dir, None, &mut Quiet).unwrap();
    assert_healthy(&s, "restart from a trajectory frame");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_thermostat_holds_both_temperatures() {
    let s = run(
        RODS,
        &[
            "thermostat.during=always",
            "run.time=2",
            "init.temperature=2.0",
        ],
    );
    assert!(
        (s.translational_temperature - 2.0).abs() < 0.2,
        "{}",
        s.translational_temperature
    );
    let rot = s.rotational_temperature.unwrap();
    assert!((rot - 2.0).abs() < 0.2, "{rot}");
    assert_eq!(s.anomalies, 0);
}

/// A scene in molecular units is the same physics as its internal numbers in reduced units:
/// the same events, and the summary in kJ/mol and K.
#[test]
fn molecular_units_are_the_internal_numbers_scaled() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/rods-paper.toml");
    let paper = std::fs::read_to_string(path).unwrap();
    let short = [
        "run.equilibration_time=0.1",
        "run.time=0.1",
        "output.rdf=",
        "output.msd=",
        "output.vacf=",
        "output.orientation_acf=",
        "output.series=false",
    ];
    let molecular = run(&paper, &short);
    let kt = 505.144 * dmd_sim::units::GAS_CONSTANT;
    let mut reduced: Vec<String> = short.iter().map(|s| (*s).to_owned()).collect();
    reduced.extend([
        "units=reduced".to_owned(),
        format!("init.temperature={kt:e}"),
        "pair.0.potential={ kind = \"rods\", epsilon = 300.0, sigma = 3.035, zeta = 1.0 }"
            .to_owned(),
    ]);
    let reduced: Vec<&str> = reduced.iter().map(String::as_str).collect();
    let reduced = run(&paper, &reduced);
    assert_eq!(molecular.events, reduced.events);
    assert_eq!(molecular.terrace_crossings, reduced.terrace_crossings);
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(rel(molecular.energy_total_end * 100.0, reduced.energy_total_end) < 1e-12);
    assert!(
        rel(
            molecular.temperature * dmd_sim::units::GAS_CONSTANT,
            reduced.temperature
        ) < 1e-12
    );
    assert!(
        rel(
            molecular.pressure / dmd_sim::units::BAR_PER_UNIT,
            reduced.pressure
        ) < 1e-12
    );
    assert_eq!(molecular.sim_time, reduced.sim_time);
}

/// Gay–Berne rods (GB(3, 5, 2, 1)), the issue's second anisotropic potential, through the same
/// path: reaches found numerically, energy conserved, no miss detected.
#[test]
fn gay_berne_rods_run() {
    let gb = r#"
version = 1
seed = 5
[box]
density = 0.03
[[species]]
name = "gb"
count = 216
inertia = 0.5
[[pair]]
species = ["gb", "gb"]
potential = { kind = "gay-berne", sigma0 = 1.0, epsilon0 = 1.0 }
terraces = { step_kt = 0.5, core = 8.0 }
[init]
positions = "sc"
temperature = 2.0
orientations = "aligned"
axis = [0, 0, 1]
[run]
equilibration_time = 0.5
time = 2
"#;
    let s = run(gb, &[]);
    assert_eq!(s.model, "terraced-gay-berne");
    assert_healthy(&s, "Gay-Berne");
    assert!(s.rotational_temperature.unwrap() > 0.5);
}

/// The shipped biaxial Gay–Berne ellipsoids use their certified models only when asked: by
/// default no model is made (the search alone, as measured cheaper); with `search.horizon`
/// the models jump stretches, and the jumped stretches, searched again on a grid a hundred
/// times finer than the search step, hold no missed crossing.
#[test]
fn biaxial_ellipsoids_certify_only_when_asked_and_miss_nothing() {
    let short = [
        "run.equilibration_time=0.05",
        "run.time=0.1",
        "output.rdf=",
        "output.orientation_acf=",
        "search.verify_step=5e-5",
    ];
    let plain = crate::support::run_shipped("biaxial-gb.toml", &short, None);
    let mut asked = short.to_vec();
    asked.push("search.horizon=0.0052");
    let cert = crate::support::run_shipped("biaxial-gb.toml", &asked, None);
    for (s, what) in [(&plain, "default"), (&cert, "horizon")] {
        assert_healthy(s, what);
        let st = s.search.expect("terraced tops report their searches");
        assert_eq!(
            st.verify_misses + st.off_terrace + st.misfits,
            0,
            "{what}: {st:?}"
        );
        assert!(st.verified > 10_000, "{what}: {st:?}");
    }
    let (p, c) = (plain.search.unwrap(), cert.search.unwrap());
    assert_eq!(p.taylor_models + p.certified_jumps, 0, "{p:?}");
    assert!(
        c.certified_jumps > 1_000 && c.taylor_models > c.certified_jumps,
        "{c:?}"
    );
    assert!(c.evaluations < p.evaluations, "{c:?} against {p:?}");
}
