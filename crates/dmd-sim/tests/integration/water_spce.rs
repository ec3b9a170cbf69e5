//! SPC/E water (`scenes/water-spce.toml`, `kind = "spc-e"`): three-site rigid molecules with
//! site–site Lennard-Jones and damped shifted force Coulomb terms, run by both engines through
//! the library as `dmd run` runs them, a few hundred events or a few tens of femtoseconds.

use std::path::Path;

use dmd_sim::run::{Quiet, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::smd_engine::{self, Engine};

use crate::support::scratch;

/// The shipped scene with `overrides`, without its own lengths of run and outputs.
fn water(overrides: &[&str]) -> Scene {
    let text = crate::support::shipped_text("water-spce.toml");
    let mut o: Vec<String> = ["run.equilibration_time=", "run.time=", "output="]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    o.extend(overrides.iter().map(|s| (*s).to_owned()));
    Scene::from_str_with(&text, &o).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn terraced_spc_e_conserves_energy_and_misses_nothing() {
    let dir = scratch("spce-dmd");
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
    let dir = scratch("spce-smd");
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
    let text = crate::support::shipped_text("water-spce.toml");
    for (set, key) in [
        ("pair.0.potential.r_cut=3.0", "pair[0].potential.r_cut"),
        ("pair.0.potential.alpha=-0.1", "pair[0].potential.alpha"),
    ] {
        let e = Scene::from_str_with(&text, &[set.to_owned()]).unwrap_err();
        assert!(e.to_string().contains(key), "{set}: {e}");
    }
}

/// The header and rows of a CSV file.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines
        .next()
        .expect("a header")
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().expect("a number")).collect())
        .collect();
    (header, rows)
}

/// The column `name` of a table.
fn column(header: &[String], rows: &[Vec<f64>], name: &str) -> Vec<f64> {
    let k = header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"));
    rows.iter().map(|r| r[k]).collect()
}

/// The site–site g(r) of a short run: the columns of every pair of site types with their
/// errors, its plot, and no O–H or H–H pair at the intramolecular distances (1 Å, 1.63 Å
/// would fill the bins below 1.2 Å and at 1.6 Å: the nearest intermolecular pairs are
/// hydrogen bonds, H···O near 1.8 Å), while rdf.csv keeps the centres alone.
fn check_site_columns(dir: &Path) -> Vec<String> {
    let (header, rows) = read_csv(&dir.join("rdf-sites.csv"));
    assert_eq!(
        header,
        [
            "r",
            "g_O_O",
            "g_O_O_error",
            "g_O_H",
            "g_O_H_error",
            "g_H_H",
            "g_H_H_error"
        ]
    );
    assert_eq!(rows.len(), 100);
    assert!(dir.join("rdf-sites.svg").exists());
    let r = column(&header, &rows, "r");
    for name in ["g_O_O", "g_O_H", "g_H_H"] {
        let g = column(&header, &rows, name);
        assert!(g.iter().any(|&x| x > 0.5), "{name} is empty: {g:?}");
        for (&r, &g) in r.iter().zip(&g) {
            if r < 1.2 {
                assert_eq!(g, 0.0, "{name}({r}) = {g}");
            }
        }
    }
    let (centres, _) = read_csv(&dir.join("rdf.csv"));
    assert_eq!(centres, ["r", "g", "g_error"]);
    header
}

#[test]
fn both_engines_write_the_site_site_g_of_r() {
    let rdf = "output.rdf={ bins = 100, r_max = 6.0, every = 1 }";
    let dir = scratch("spce-sites-dmd");
    let scene = water(&[
        "run.equilibration_events=100",
        "run.events=400",
        "output.sample_interval=0.0005",
        rdf,
    ]);
    run_scene(&scene, Path::new("."), Some(&dir), &mut Quiet).unwrap_or_else(|e| panic!("{e}"));
    let dmd = check_site_columns(&dir);
    let _ = std::fs::remove_dir_all(&dir);

    let dir = scratch("spce-sites-smd");
    let mut scene = water(&[
        "species.0.count=512",
        "run.equilibration_time=0.01",
        "run.time=0.01",
        "output.sample_interval=0.002",
        rdf,
    ]);
    scene.engine = Engine::Smd;
    smd_engine::run(&scene, Path::new("."), Some(&dir)).unwrap_or_else(|e| panic!("{e}"));
    let smd = check_site_columns(&dir);
    assert_eq!(dmd, smd);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Liquid SPC/E by standard MD from the simple cubic lattice (O–O 3.1 Å): within a few
/// tenths of a picosecond the hydrogen bonds pull the oxygens' first peak in to about
/// 2.75 Å, and the O–H peak of the hydrogen bond sits near 1.8 Å, which also places the
/// sites by the right attitudes (a wrong body frame would put the hydrogens elsewhere).
#[test]
fn standard_md_spc_e_oxygens_peak_near_2_75_angstrom() {
    let dir = scratch("spce-peak-smd");
    let mut scene = water(&[
        "species.0.count=512",
        "thermostat.rate=50",
        "run.equilibration_time=1.0",
        "run.time=0.4",
        "output.sample_interval=0.01",
        "output.rdf={ bins = 100, r_max = 6.0, every = 1 }",
    ]);
    scene.engine = Engine::Smd;
    smd_engine::run(&scene, Path::new("."), Some(&dir)).unwrap_or_else(|e| panic!("{e}"));
    let (header, rows) = read_csv(&dir.join("rdf-sites.csv"));
    let r = column(&header, &rows, "r");
    let peak = |name: &str, below: f64| {
        let g = column(&header, &rows, name);
        r.iter()
            .zip(&g)
            .filter(|(r, _)| **r < below)
            .fold((0.0, 0.0), |m, (&r, &g)| if g > m.1 { (r, g) } else { m })
    };
    let (r_oo, g_oo) = peak("g_O_O", 3.5);
    assert!(
        (2.6..3.0).contains(&r_oo) && g_oo > 2.0,
        "O–O peak {g_oo} at {r_oo} Å"
    );
    let (r_oh, g_oh) = peak("g_O_H", 2.5);
    assert!(
        (1.6..2.0).contains(&r_oh) && g_oh > 0.5,
        "O–H peak {g_oh} at {r_oh} Å"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run halted after its first checkpoint and resumed writes the site–site g(r) of the
/// straight run bit for bit: the checkpoint keeps the site counts and their blocks, and the
/// resumed production samples the attitudes again.
#[test]
fn a_resumed_run_writes_the_same_site_site_g_of_r() {
    use crate::support::{options, resume, run_text, same_files};
    use dmd_sim::checkpoint::{self, Every};
    let text = crate::support::shipped_text("water-spce.toml");
    let ov: Vec<String> = [
        "run.equilibration_time=",
        "run.time=",
        "output=",
        "run.equilibration_events=100",
        "run.events=600",
        "run.rebase_events=200",
        "output.sample_interval=0.00002",
        "output.plots=false",
        "output.rdf={ bins = 60, r_max = 6.0, every = 1 }",
    ]
    .map(str::to_owned)
    .to_vec();
    let dir_a = scratch("spce-sites-straight");
    run_text(&text, &ov, &dir_a, &options(&text, &ov, None, false))
        .unwrap_or_else(|e| panic!("{e}"));
    let dir_b = scratch("spce-sites-crashed");
    let e = run_text(
        &text,
        &ov,
        &dir_b,
        &options(&text, &ov, Some(Every::Events(300)), true),
    )
    .unwrap_err();
    assert!(matches!(e, dmd_sim::run::RunError::Halted), "{e}");
    resume(&dir_b.join(checkpoint::FILE_NAME));
    let (_, rows) = read_csv(&dir_a.join("rdf-sites.csv"));
    assert!(rows.iter().any(|r| r[1] > 0.0), "no O–O pair: {rows:?}");
    same_files(&dir_a, &dir_b, &["rdf-sites.csv", "rdf.csv"]);
    for d in [dir_a, dir_b] {
        let _ = std::fs::remove_dir_all(d);
    }
}
