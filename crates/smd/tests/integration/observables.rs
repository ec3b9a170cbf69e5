//! Observables against exact results: free flight (no pair within reach) and an ideal gas.

use glam::DVec3;
use potential::{LjRod, Smoothed};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use smd::observe::{Correlations, Observables, Rdf};
use smd::{BodyModel, Integrator, Orientations, Settings, System};

/// Eight rods 20 apart in a box of 40 with a potential that reaches 0.3: they never interact
/// over the run, so each moves freely: `MSD = ⟨v²⟩ t²`, the VACF stays 1 and
/// `⟨s(0)·s(t)⟩ = ⟨cos |ω| t⟩`, exactly.
#[test]
fn free_flight_correlations_are_exact() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(4);
    let mut pos = Vec::new();
    for x in 0..2 {
        for y in 0..2 {
            for z in 0..2 {
                pos.push(DVec3::new(x as f64, y as f64, z as f64) * 20.0 + 5.0);
            }
        }
    }
    let r = |rng: &mut Xoshiro256PlusPlus| {
        DVec3::new(rng.random(), rng.random(), rng.random()) * 2.0 - 1.0
    };
    let vel: Vec<DVec3> = (0..8).map(|_| r(&mut rng)).collect();
    let axes: Vec<DVec3> = (0..8).map(|_| r(&mut rng).normalize()).collect();
    let inertia = 0.7;
    let l: Vec<DVec3> = axes.iter().map(|s| s.cross(r(&mut rng)) * 3.0).collect();
    let sys = System::from_parts(
        DVec3::splat(40.0),
        BodyModel::linear_rotor(1.0, inertia).unwrap(),
        pos,
        vel.clone(),
        Orientations::Axes(axes),
        l.clone(),
    )
    .unwrap();
    let rod = LjRod::new(1.0, 0.1, 0.05).unwrap();
    let mut md = Integrator::new(
        sys,
        Smoothed::new(rod, 0.25, 0.3).unwrap(),
        Settings::new(0.01, 0.5),
    )
    .unwrap();
    let mut obs = Observables {
        correlations: Some(Correlations::new(0.05, 40, 5).unwrap()),
        ..Observables::default()
    };
    md.run(1000, 5, &mut obs).unwrap();
    let c = obs.correlations.as_ref().unwrap();
    let v2 = vel.iter().map(|v| v.length_squared()).sum::<f64>() / 8.0;
    for (t, m) in c.msd() {
        assert!(
            (m - v2 * t * t).abs() < 1e-10 * (1.0 + m),
            "MSD at {t}: {m}"
        );
    }
    for (t, v) in c.vacf_normalised() {
        assert!((v - 1.0).abs() < 1e-12, "VACF at {t}: {v}");
    }
    let omega: Vec<f64> = l.iter().map(|l| l.length() / inertia).collect();
    for (t, p1) in c.orientation_p1() {
        let want = omega.iter().map(|w| (w * t).cos()).sum::<f64>() / 8.0;
        assert!((p1 - want).abs() < 1e-10, "P1 at {t}: {p1} vs {want}");
    }
    assert_eq!(c.msd().len(), 41);
    // Energies: no potential energy, the kinetic energy constant.
    for row in &obs.series {
        assert_eq!(row.potential, 0.0);
        assert!((row.total - obs.series[0].total).abs() < 1e-12 * row.total);
    }
}

/// Uniformly scattered points (an ideal gas) have g(r) = 1 within counting noise.
#[test]
fn ideal_gas_rdf_is_one() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(8);
    let n = 4000;
    let l = 20.0;
    let pos: Vec<DVec3> = (0..n)
        .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) * l)
        .collect();
    let sys = System::from_parts(
        DVec3::splat(l),
        BodyModel::sphere(1.0).unwrap(),
        pos,
        vec![DVec3::ZERO; n],
        Orientations::None,
        Vec::new(),
    )
    .unwrap();
    // Cells (r_max 5 < L/3) and all pairs (r_max 9 > L/3) agree on the same points.
    let mut cells = Rdf::new(10, 5.0, 1).unwrap();
    let mut all = Rdf::new(18, 9.0, 1).unwrap();
    cells.add(&sys);
    all.add(&sys);
    for (r, g) in cells.table().into_iter().skip(2) {
        assert!((g - 1.0).abs() < 0.08, "cells: g({r}) = {g}");
    }
    for (r, g) in all.table().into_iter().skip(2) {
        assert!((g - 1.0).abs() < 0.08, "all pairs: g({r}) = {g}");
    }
    let (a, b) = (cells.table(), all.table());
    for k in 0..10 {
        assert!(
            (a[k].1 - b[k].1).abs() < 1e-12,
            "bin {k}: {} {}",
            a[k].1,
            b[k].1
        );
    }
}

#[test]
fn csv_files_have_headers_and_one_row_per_sample() {
    let body = BodyModel::paper_rod();
    let sys = System::new(&smd::Setup::new(256, 0.5 / 3.035f64.powi(3), body, 4.2)).unwrap();
    let rod = LjRod::paper();
    let mut md = Integrator::new(
        sys,
        Smoothed::paper(rod, rod.sigma()).unwrap(),
        Settings::new(0.018, 1.0),
    )
    .unwrap();
    let mut obs = Observables {
        rdf: Some(Rdf::new(50, 10.0, 2).unwrap()),
        correlations: Some(Correlations::new(0.09, 10, 2).unwrap()),
        ..Observables::default()
    };
    md.run(100, 5, &mut obs).unwrap();
    let dir = std::env::temp_dir().join(format!("smd-csv-test-{}", std::process::id()));
    let files = obs.write_csv(&dir).unwrap();
    assert_eq!(
        files,
        [
            "rdf.csv",
            "msd.csv",
            "vacf.csv",
            "orientation.csv",
            "series.csv"
        ]
    );
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    let series = read("series.csv");
    let mut lines = series.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t,kinetic,kinetic_translational,kinetic_rotational,potential,total,temperature,pressure"
    );
    assert_eq!(lines.count(), 21);
    assert!(read("rdf.csv").starts_with("r,g\n"));
    assert!(read("vacf.csv").starts_with("t,vacf,vacf_normalised\n"));
    assert!(read("orientation.csv").starts_with("t,p1,p2\n"));
    assert_eq!(obs.rdf.as_ref().unwrap().samples(), 11);
    std::fs::remove_dir_all(&dir).unwrap();
}
