//! Error bars on every averaged output: the `_error` twins in `summary.json` and the error
//! columns of the observables' CSV files, from a short rods run.

use std::path::Path;

use dmd_sim::run::{Quiet, run_scene};
use dmd_sim::scene::Scene;

use crate::support::{REDUCED_RODS, scratch};

/// The rods of `support` with seed 5, 0.3 τ of thermostatted equilibration and 0.6 τ of NVE
/// production: more than 16 time origins of the correlations.
const OVERRIDES: [&str; 9] = [
    "seed=5",
    "run.equilibration_time=0.3",
    "run.time=0.6",
    "output.sample_interval=0.01",
    "output.rdf={ bins = 20, r_max = 2.0, every = 1 }",
    "output.msd={ max_lag = 0.05 }",
    "output.vacf={ max_lag = 0.05 }",
    "output.orientation_acf={ max_lag = 0.05 }",
    "output.plots=false",
];

/// A CSV file's header and rows.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{e}"));
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn every_average_has_a_finite_positive_error_and_every_table_an_error_column() {
    let dir = scratch("errors");
    let scene = Scene::from_str_with(REDUCED_RODS, &OVERRIDES.map(String::from)).unwrap();
    let s = run_scene(&scene, Path::new("."), Some(&dir), &mut Quiet).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    for key in [
        "temperature",
        "translational_temperature",
        "rotational_temperature",
        "pressure",
        "potential_energy_per_body",
        "diffusion_msd",
        "diffusion_vacf",
    ] {
        let value = json[key].as_f64();
        let error = json[format!("{key}_error")].as_f64();
        assert!(value.is_some_and(f64::is_finite), "{key}: {value:?}");
        assert!(
            error.is_some_and(|e| e.is_finite() && e > 0.0),
            "{key}_error: {error:?}"
        );
        // An error bar, not a second value: well below the rods' temperatures, and D is
        // known to better than itself.
        let (v, e) = (value.unwrap(), error.unwrap());
        if key.contains("temperature") || key.starts_with("diffusion") {
            assert!(e < 0.5 * v.abs(), "{key}: {v} ± {e}");
        }
    }
    assert_eq!(
        s.translational_temperature_error,
        json["translational_temperature_error"].as_f64()
    );

    let (header, rows) = read_csv(&dir.join("rdf.csv"));
    assert_eq!(header, ["r", "g", "g_error"]);
    assert!(rows.iter().all(|r| r[2].is_finite() && r[2] >= 0.0));
    // Where pairs were counted the error is positive, and small against a peak.
    assert!(
        rows.iter()
            .filter(|r| r[1] > 0.5)
            .all(|r| r[2] > 0.0 && r[2] < 0.5 * r[1])
    );
    // Inside the hard core nothing is ever counted: g = 0 with no spread.
    assert!(rows.iter().filter(|r| r[1] == 0.0).all(|r| r[2] == 0.0));

    let (header, rows) = read_csv(&dir.join("msd.csv"));
    assert_eq!(header, ["t", "msd", "msd_error"]);
    assert_eq!(rows[0][2], 0.0, "no displacement at lag 0");
    assert!(
        rows[1..].iter().all(|r| r[2] > 0.0 && r[2] < r[1]),
        "{rows:?}"
    );
    let (header, rows) = read_csv(&dir.join("vacf.csv"));
    assert_eq!(
        header,
        [
            "t",
            "vacf",
            "vacf_error",
            "vacf_normalised",
            "vacf_normalised_error"
        ]
    );
    assert!(rows.iter().all(|r| r[2] > 0.0 && r[4] > 0.0), "{rows:?}");
    let (header, rows) = read_csv(&dir.join("oacf.csv"));
    assert_eq!(
        header,
        ["t", "s0_dot_st", "s0_dot_st_error", "p2", "p2_error"]
    );
    assert!(
        rows[1..].iter().all(|r| r[2] > 0.0 && r[4] > 0.0),
        "{rows:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
