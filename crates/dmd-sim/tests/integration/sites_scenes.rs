//! Scenes of rigid site molecules through `run_scene`, as `dmd run` runs them (issue 10): the
//! three shipped scenes shortened, their molecules and tables against `sites::molecules`, the
//! constrained rule, aligned starts, outputs, units and determinism.

use std::path::Path;

use dmd_sim::potential::Potentials;
use dmd_sim::run::{Quiet, Summary, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::site_scene::SitesPlan;
use dmd_sim::sites::molecules;

use crate::support;
use crate::support::{run_shipped as run, shipped};

/// The same step tables (the derived levels hold NaN for absent steps, so no `==`).
fn assert_same_tables(a: &Potentials, b: &Potentials) {
    assert_eq!(a.n_species(), b.n_species());
    for x in 0..a.n_species() as u32 {
        for y in 0..a.n_species() as u32 {
            assert_eq!(a.get(x, y).radii(), b.get(x, y).radii(), "{x} {y}");
            assert_eq!(a.get(x, y).steps(), b.get(x, y).steps(), "{x} {y}");
        }
    }
}

fn assert_healthy(s: &Summary, what: &str) {
    assert_eq!(s.model, "rigid-sites", "{what}");
    support::assert_conserved(s, what, 1e-11);
    assert!(s.reflections > 0, "{what}: no collision");
    assert!(s.virtual_events > 0, "{what}: no virtual event");
}

#[test]
fn the_hard_dumbbells_scene_runs_and_its_pressure_is_that_of_dumbbells() {
    let dir = std::env::temp_dir().join(format!("dmd-dumbbells-{}", std::process::id()));
    let s = run(
        "hard-dumbbells.toml",
        &[
            "run.equilibration_time=1.0",
            "run.time=2.0",
            "output.rdf.every=1",
        ],
        Some(&dir),
    );
    assert_healthy(&s, "hard dumbbells");
    assert_eq!(s.n_bodies, 256);
    // Two rotational degrees of freedom per linear molecule.
    assert_eq!(s.degrees_of_freedom, 5.0 * 256.0 - 3.0);
    assert_eq!(s.terrace_crossings, 0, "hard cores only");
    // kT = 1 at the start, no potential energy: the temperature stays 1 up to the noise of
    // 1277 degrees of freedom, shared evenly by translation and rotation.
    assert!((s.temperature - 1.0).abs() < 0.1, "{}", s.temperature);
    let rot = s.rotational_temperature.unwrap();
    assert!((rot - s.translational_temperature).abs() < 0.15, "{rot}");
    // η = 0.4, L* = 0.6: Tildesley–Streett Z = 8.20; hard spheres at the same η would give
    // 6.93 (Carnahan–Starling), spheres at the same number density 2.3. A short run: 5 %.
    assert!(
        (s.compressibility - 8.20).abs() < 0.05 * 8.20,
        "{}",
        s.compressibility
    );
    for f in ["rdf.csv", "msd.csv", "oacf.csv", "series.csv"] {
        assert!(s.files.iter().any(|x| x == f), "{f} missing: {:?}", s.files);
    }
    // The molecular axis decorrelates: the first-rank orientation ACF starts at 1 and falls.
    let text = std::fs::read_to_string(dir.join("oacf.csv")).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.trim().parse().unwrap()).collect())
        .collect();
    assert!((rows[0][1] - 1.0).abs() < 1e-9, "{:?}", rows[0]);
    assert!(rows.last().unwrap()[1] < 0.9, "{:?}", rows.last());
    // The site–site g(r) of the sites of kind A: no pair of sites of two molecules inside the
    // hard core (σ = 1, the bins of 0.02 below it), the molecule's own pair at 0.6 σ left
    // out, and the contact peak in the first bin beyond it.
    let text = std::fs::read_to_string(dir.join("rdf-sites.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("r,g_A_A,g_A_A_error"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.trim().parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 150);
    for r in rows.iter().filter(|r| r[0] + 0.01 < 0.999) {
        assert_eq!(r[1], 0.0, "{r:?}");
    }
    let contact = rows.iter().find(|r| r[0] > 1.0).unwrap();
    assert!(contact[1] > 1.5, "{contact:?}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_methane_scene_spells_out_the_shipped_molecule_and_runs() {
    let (scene, _) = shipped("methane-like.toml", &[]);
    let plan = SitesPlan::of(&scene.internal()).unwrap();
    let (t, pot) = molecules::methane_like();
    assert_eq!(plan.kinds, ["C", "H"]);
    assert_eq!(plan.types[0].mass(), t.mass());
    assert_eq!(scene.species[0].mass, 16.0);
    let dm = (plan.types[0].moments() - t.moments()).abs().max_element();
    assert!(dm < 1e-12 * t.moments().max_element(), "{dm}");
    assert_same_tables(&plan.potentials, &pot);
    let s = run(
        "methane-like.toml",
        &["run.equilibration_time=0.5", "run.time=0.5"],
        None,
    );
    assert_healthy(&s, "methane-like");
    assert_eq!(s.degrees_of_freedom, 6.0 * 256.0 - 3.0);
    assert!(s.terrace_crossings > s.reflections, "{s:?}");
    assert!(s.potential_energy_per_body < 0.0);
}

#[test]
fn the_benzene_scene_uses_the_shipped_tables_and_runs() {
    let (scene, _) = shipped("benzene-like.toml", &[]);
    let plan = SitesPlan::of(&scene.internal()).unwrap();
    let (t, pot) = molecules::benzene_like();
    assert_same_tables(&plan.potentials, &pot);
    assert_eq!(plan.types[0].mass(), t.mass());
    let dm = (plan.types[0].moments() - t.moments()).abs().max_element();
    assert!(dm < 1e-12 * t.moments().max_element(), "{dm}");
    let s = run(
        "benzene-like.toml",
        &[
            "species.0.count=64",
            "run.equilibration_time=0.2",
            "run.time=0.2",
        ],
        None,
    );
    assert_healthy(&s, "benzene-like");
    assert_eq!(s.degrees_of_freedom, 6.0 * 64.0 - 3.0);
}

#[test]
fn the_constrained_rule_runs_dumbbells_like_the_contact_rule() {
    let o = [
        "species.0.count=108",
        "run.equilibration_time=0",
        "run.time=1.0",
        "output=",
    ];
    let a = run("hard-dumbbells.toml", &o, None);
    let mut oc: Vec<&str> = o.to_vec();
    oc.push("impulse.rule=constrained");
    let b = run("hard-dumbbells.toml", &oc, None);
    assert_healthy(&a, "contact");
    assert_healthy(&b, "constrained");
    // Same physics, different round-off: the trajectories part after a while, the
    // collision counts of the first unit of time stay close.
    let (ra, rb) = (a.reflections as f64, b.reflections as f64);
    assert!((ra - rb).abs() < 0.1 * ra, "{ra} {rb}");
}

#[test]
fn runs_are_deterministic_and_seeds_matter() {
    let o = [
        "species.0.count=32",
        "box.density=0.2",
        "run.equilibration_time=0",
        "run.time=0.5",
        "output=",
    ];
    let a = run("hard-dumbbells.toml", &o, None);
    let b = run("hard-dumbbells.toml", &o, None);
    assert_eq!(a.events, b.events);
    assert_eq!(a.energy_total_end, b.energy_total_end);
    let mut o2 = o.to_vec();
    o2.push("seed=11");
    let c = run("hard-dumbbells.toml", &o2, None);
    assert_ne!(a.energy_total_end, c.energy_total_end);
}

#[test]
fn aligned_starts_trajectories_and_molecular_units() {
    // Aligned along z on an fcc lattice at η = 0.4 with L* = 1 (tangent spheres): random
    // orientations could not be placed, aligned ones fit.
    let dir = std::env::temp_dir().join(format!("dmd-dumbbells-xyz-{}", std::process::id()));
    let o = [
        "species.0.count=108",
        "species.0.molecule.elongation=1.0",
        "box.density=0.382",
        "init.orientations=aligned",
        "init.axis=[0, 0, 1]",
        "run.equilibration_time=0",
        "run.time=0.3",
        "output.trajectory.interval=0.1",
    ];
    let s = run("hard-dumbbells.toml", &o, Some(&dir));
    assert_healthy(&s, "aligned");
    let xyz = std::fs::read_to_string(dir.join("trajectory.xyz")).unwrap();
    assert!(xyz.contains("orientation:R:4"));
    std::fs::remove_dir_all(&dir).ok();
    // The same molecules in Å, g/mol and kJ/mol: σ = 3.4 Å, site mass 1 g/mol, 300 K, at the
    // scene's ρσ³ = 0.42631.
    let m = [
        "units=molecular",
        "species.0.count=108",
        "box.density=0.010846",
        "species.0.molecule.elongation=2.04",
        "site_pair.0.steps=[[3.4, inf]]",
        "init.temperature=300",
        "run.equilibration_time=0",
        "run.time=0.5",
        "output=",
    ];
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/hard-dumbbells.toml"),
    )
    .unwrap();
    let scene = Scene::from_str_with(&text, &m.map(str::to_owned)).unwrap();
    let s = run_scene(&scene, Path::new("."), None, &mut Quiet).unwrap();
    assert_healthy(&s, "molecular units");
    assert_eq!(s.units, "molecular");
    assert!((s.temperature - 300.0).abs() < 40.0, "{}", s.temperature);
}
