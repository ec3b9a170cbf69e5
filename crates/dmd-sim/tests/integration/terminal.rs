//! What `dmd` prints for a person: the header before the run, a summary in the scene's units
//! within 100 columns, no notes about what is normal, `--help` in the user's words; and the
//! files a newcomer opens first (`summary.json`'s event rate under an honest name, a
//! `series.csv` with a number in every cell).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dmd-terminal-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn dmd(args: &[&str], out: &Path) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_dmd"))
        .current_dir(root())
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// Every line within 100 columns (characters, as a terminal counts them).
fn assert_narrow(text: &str) {
    for l in text.lines() {
        assert!(
            l.chars().count() <= 100,
            "{} columns: {l}",
            l.chars().count()
        );
    }
}

/// The first data row of `series.csv`, checked to be finite numbers in every column, and its
/// time.
fn first_series_row(out: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(out.join("series.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let row: Vec<f64> = lines
        .next()
        .expect("a row")
        .split(',')
        .map(|x| x.trim().parse::<f64>().unwrap())
        .collect();
    assert_eq!(row.len(), header.split(',').count(), "{text}");
    assert!(row.iter().all(|x| x.is_finite()), "{header}\n{row:?}");
    row
}

#[test]
fn the_rods_run_says_what_runs_first_and_sums_up_in_molecular_units() {
    let out = dir("rods");
    let o = dmd(
        &[
            "run",
            "scenes/rods-paper.toml",
            "--set",
            "run.equilibration_time=0.05",
            "--set",
            "run.time=0.1",
            "--set",
            "output.msd.max_lag=0.05",
            "--set",
            "output.vacf.max_lag=0.05",
            "--set",
            "output.orientation_acf.max_lag=0.05",
        ],
        &out,
    );
    let text = String::from_utf8_lossy(&o.stdout);
    let header = text
        .find("dmd: running scenes/rods-paper.toml")
        .expect(&text);
    let done = text.find("dmd: done").expect(&text);
    assert!(header < done, "{text}");
    let (head, tail) = text.split_at(done);
    for what in [
        "512 bodies (rigid rods, terraced potential)",
        "ρ = 0.01789 Å⁻³",
        "T = 505.1 K",
        "molecular units",
        "event-driven",
        "equilibration 0.05 ps (Andersen thermostat at 505.1 K)",
        "production 0.1 ps (NVE)",
    ] {
        assert!(head.contains(what), "{what}:\n{text}");
    }
    // The summary names the unit of its numbers, the equilibration included.
    for what in [
        "equilibration  0.05 ps,",
        "ended at T = ",
        " K (production started at ",
        " bar, Z = ",
        " kJ/mol (the terraced potential)",
        "smooth model   U/N ",
        " ps between pair events",
        " pair events per ps",
        " Å²/ps (MSD)",
        "anomalies 0",
        "missed events detected",
        " ± ",
    ] {
        assert!(tail.contains(what), "{what}:\n{text}");
    }
    assert_narrow(&text);
    // The scene's [smd] table is for the other engine: nothing to say about it.
    assert!(!text.contains("[smd]") && !text.contains("note"), "{text}");
    let json = summary(&out);
    assert!(json["events_per_ps"].as_f64().unwrap() > 0.0, "{json}");
    assert!(json.get("events_per_time_unit").is_none(), "{json}");
    // The series starts at the end of the first sampling interval (0.005 ps).
    let row = first_series_row(&out);
    assert!((row[0] - 0.005).abs() < 1e-12, "{row:?}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_reduced_unit_run_reports_its_event_rate_per_time_unit() {
    let out = dir("reduced");
    let o = dmd(
        &[
            "run",
            "scenes/square-well.toml",
            "--set",
            "species.0.count=500",
            "--set",
            "run.equilibration_events=2000",
            "--set",
            "run.events=20000",
            "--set",
            "output.plots=false",
        ],
        &out,
    );
    let text = String::from_utf8_lossy(&o.stdout);
    for what in [
        "reduced units",
        "σ⁻³",
        "equilibration 2,000 events",
        "production 20,000 events",
        " pair events per τ",
        " ε/σ³, Z = ",
    ] {
        assert!(text.contains(what), "{what}:\n{text}");
    }
    assert_narrow(&text);
    let json = summary(&out);
    assert!(json.get("events_per_ps").is_none(), "{json}");
    assert!(
        json["events_per_time_unit"].as_f64().unwrap() > 0.0,
        "{json}"
    );
    // The series starts at the end of the first sampling interval (0.05 τ).
    let row = first_series_row(&out);
    assert!((row[0] - 0.05).abs() < 1e-12, "{row:?}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn the_smd_engine_says_what_runs_and_its_series_starts_with_numbers() {
    let out = dir("smd");
    let o = dmd(
        &[
            "run",
            "scenes/rods-paper.toml",
            "--engine",
            "smd",
            "--set",
            "run.equilibration_time=0.09",
            "--set",
            "run.time=0.09",
        ],
        &out,
    );
    let text = String::from_utf8_lossy(&o.stdout);
    let header = text
        .find("dmd: running scenes/rods-paper.toml")
        .expect(&text);
    let done = text.find("dmd: done (engine smd").expect(&text);
    assert!(header < done, "{text}");
    for what in [
        "standard MD, dt = 0.0018 ps",
        "equilibration 0.09 ps (velocity rescaling to 505.1 K)",
        "ended at T = ",
        " bar, Z = ",
        " kJ/mol (the smooth model)",
        "ignored (event-driven only): pair[0].terraces, search",
    ] {
        assert!(text.contains(what), "{what}:\n{text}");
    }
    assert_narrow(&text);
    let row = first_series_row(&out);
    assert!((row[0] - 0.0054).abs() < 1e-9, "{row:?}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn the_help_speaks_the_users_words() {
    let help = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_dmd"))
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success());
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let top = help(&["--help"]);
    for what in [
        "hard spheres",
        "rods",
        "SSD/E water",
        "SPC/E water",
        "spherocylinders",
        "site molecules",
        "semi-flexible molecules",
        "--engine smd",
        "docs/USER-GUIDE.md",
    ] {
        assert!(top.contains(what), "{what}:\n{top}");
    }
    for args in [&["--help"][..], &["run", "--help"], &["resume", "--help"]] {
        let text = help(args);
        for jargon in ["issue", "lazy invalidation", "re-basing"] {
            assert!(!text.contains(jargon), "{jargon}:\n{text}");
        }
    }
    assert!(help(&["run", "--help"]).contains("summary"));
    assert!(help(&["check", "--help"]).contains("without running it"));
}
