//! The `dmd` command against a hostile but fair user ("Nothing lost, nothing crashes"): bad
//! command-line values and output folders are refused before the run with exit status 2, an
//! output that outgrows its limit during a run stops it with exit status 1, and a new run never
//! mixes its files with another run's.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::support::{WELL_FLUID, run_and_signal, signal_then_resume_is_bit_for_bit};

const SCENE: &str = r#"version = 1
[box]
density = 0.5
[[species]]
name = "A"
count = 108
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf]]
[init]
positions = "fcc"
temperature = 1.0
[run]
events = 10000
"#;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dmd-cli-robust-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn scene(d: &Path, extra: &str) -> PathBuf {
    let path = d.join("scene.toml");
    std::fs::write(&path, format!("{SCENE}{extra}")).unwrap();
    path
}

fn dmd(args: &[&str], paths: &[(&str, &Path)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dmd"));
    c.args(args);
    for (flag, p) in paths {
        if !flag.is_empty() {
            c.arg(flag);
        }
        c.arg(p);
    }
    c.output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_checkpoint_interval_beyond_a_duration_is_refused() {
    let d = dir("every");
    let s = scene(&d, "rebase_events = 1000\n");
    let out = d.join("out");
    // Before the fix this ran and panicked at the first re-basing (exit 101).
    for every in ["1e20s", "1e300h"] {
        let o = dmd(
            &["run", "--quiet", "--checkpoint-every", every],
            &[("", &s), ("--out", &out)],
        );
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(
            stderr(&o).starts_with(&format!(
                "dmd: --checkpoint-every: `{every}` is too long a wall-clock time: at most 1.84e19s"
            )),
            "{}",
            stderr(&o)
        );
        assert!(!out.join("summary.json").exists());
    }
    let o = dmd(
        &["resume", "--quiet", "--checkpoint-every", "1e300h"],
        &[("", &d.join("missing.dmd"))],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).starts_with("dmd: --checkpoint-every: `1e300h` is too long"),
        "{}",
        stderr(&o)
    );
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn an_unusable_output_folder_is_refused_before_the_run() {
    let d = dir("unwritable");
    let s = scene(&d, "");
    // A file where the folder should be.
    let file = d.join("a-file");
    std::fs::write(&file, "mine").unwrap();
    let o = dmd(&["run", "--quiet"], &[("", &s), ("--out", &file)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(
        stderr(&o).trim(),
        format!("dmd: --out {}: exists and is not a folder", file.display())
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    // A folder that cannot be created (inside that file): found before the run, not after it.
    let inside = file.join("out");
    let o = dmd(
        &["run", "--quiet", "--set", "run.events=1e9"],
        &[("", &s), ("--out", &inside)],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).starts_with(&format!(
            "dmd: --out {}: cannot create the folder:",
            inside.display()
        )),
        "{}",
        stderr(&o)
    );
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_new_run_does_not_mix_its_files_with_another_runs() {
    let d = dir("occupied");
    let out = d.join("out");
    let first = scene(
        &d,
        "[output]\nsample_interval = 0.1\nseries = true\ntrajectory = { interval = 0.5 }\n",
    );
    let o = dmd(
        &[
            "run",
            "--quiet",
            "--checkpoint-every",
            "1000",
            "--set",
            "run.rebase_events=1000",
        ],
        &[("", &first), ("--out", &out)],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "summary.json",
        "series.csv",
        "trajectory.xyz",
        "checkpoint.dmd",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let summary = std::fs::read(out.join("summary.json")).unwrap();
    // A second run into the same folder is refused and changes nothing. (Hard spheres in NVE
    // write no energy plot: it would be a flat line.)
    let second = scene(&d, "");
    let o = dmd(&["run", "--quiet"], &[("", &second), ("--out", &out)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).starts_with(&format!(
            "dmd: --out {}: holds the files of another run (checkpoint.dmd, \
             series-pressure.svg, series.csv, summary.json, and 1 more): use --force to \
             replace them, or `dmd resume` to continue that run",
            out.display()
        )),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), summary);
    // With --force the old run's files go (only dmd's), then the new run writes its own.
    let o = dmd(
        &["run", "--quiet", "--force"],
        &[("", &second), ("--out", &out)],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let mut left: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["notes.txt", "summary.json"]);
    // A stale temporary file of dmd is cleaned up at the start of a run (with --force here,
    // as the folder holds the last run's summary).
    std::fs::write(out.join("trajectory.xyz.partial"), "stale").unwrap();
    let o = dmd(
        &["run", "--quiet", "--force"],
        &[("", &second), ("--out", &out)],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.join("trajectory.xyz.partial").exists());
    assert!(out.join("notes.txt").exists());
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn zero_threads_are_refused() {
    // Zero would silently mean "all cores".
    let d = dir("threads");
    let s = scene(&d, "");
    let out = d.join("out");
    let o = dmd(
        &["run", "--quiet", "--threads", "0"],
        &[("", &s), ("--out", &out)],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--threads"), "{}", stderr(&o));
    assert!(!out.exists());
    let o = dmd(&["resume", "--threads", "0"], &[("", &d)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn samples_behind_the_error_bars_need_no_output_limit() {
    // The samples behind the summary's error bars are accumulated online (memory growing as
    // the logarithm of their number): a run sampling far more often than output.max_bytes
    // would allow for a stored series runs to its end and reports its errors.
    let d = dir("samples");
    let s = scene(&d, "[output]\nsample_interval = 1e-6\nmax_bytes = 1e3\n");
    let out = d.join("out");
    let o = dmd(&["run", "--quiet"], &[("", &s), ("--out", &out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let samples = summary["events_by_kind"]["samples"].as_u64().unwrap();
    assert!(samples > 1000, "{samples} samples");
    assert!(summary["pressure_error"].as_f64().unwrap() > 0.0);
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_series_that_outgrows_its_limit_stops_the_run() {
    // A run given in events cannot be estimated beforehand: the series is stopped when it
    // reaches output.max_bytes (exit status 1: a failure during the run).
    let d = dir("series");
    let s = scene(
        &d,
        "[output]\nsample_interval = 1e-6\nseries = true\nmax_bytes = 1e5\n",
    );
    let out = d.join("out");
    let o = dmd(&["run", "--quiet"], &[("", &s), ("--out", &out)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).starts_with(&format!(
            "dmd: {}: output.series: series.csv has reached 667 rows (about 100050 bytes), the \
             limit output.max_bytes = 100000",
            s.display()
        )),
        "{}",
        stderr(&o)
    );
    let _ = std::fs::remove_dir_all(d);
}

/// The fluid of `support` running 4·10⁶ events with a series, an MSD and a trajectory.
fn long() -> String {
    format!(
        "{WELL_FLUID}[run]\nevents = 4e6\n[output]\nsample_interval = 0.5\nseries = true\n\
         msd = {{ max_lag = 5 }}\ntrajectory = {{ interval = 20 }}\n"
    )
}

#[test]
fn a_signal_stops_the_run_with_a_checkpoint_that_resumes_bit_for_bit() {
    let d = dir("signal");
    // 1.5·10⁶ events: seconds of a run, of which the signal, 0.2 s into production, stops the
    // first part at a re-basing.
    let text = long().replace("events = 4e6\n", "events = 1.5e6\nrebase_events = 1e5\n");
    signal_then_resume_is_bit_for_bit(&d, &text, &["series.csv", "msd.csv", "trajectory.xyz"]);
    let _ = std::fs::remove_dir_all(d);
}

/// A run stopped by a signal, resumed, stopped again at another moment of the resumed run and
/// resumed to its end gives the files and summary of the run never stopped. The moments vary
/// from run to run (0.1–0.6 s into each part, from the clock); the result may not.
#[test]
fn a_run_stopped_twice_at_varying_moments_resumes_bit_for_bit() {
    let d = dir("signal-twice-resumed");
    let s = d.join("scene.toml");
    std::fs::write(
        &s,
        long().replace("events = 4e6\n", "events = 2e6\nrebase_events = 1e5\n"),
    )
    .unwrap();
    let moment = || {
        let ns = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .subsec_nanos();
        100 + u64::from(ns % 500)
    };
    let stopped = d.join("stopped");
    let ck = stopped.join("checkpoint.dmd");
    let run_args = [
        "run".as_ref(),
        "--quiet".as_ref(),
        s.as_os_str(),
        "--out".as_ref(),
        stopped.as_os_str(),
    ];
    let ready = stopped.join("trajectory.xyz.partial");
    let (o, _) = crate::support::signal_command(&run_args, &ready, moment(), 1);
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    let resume_args = ["resume".as_ref(), "--quiet".as_ref(), ck.as_os_str()];
    let (o, _) = crate::support::signal_command(&resume_args, &ready, moment(), 1);
    assert_eq!(
        o.status.code(),
        Some(130),
        "the resumed run: {}",
        stderr(&o)
    );
    assert!(
        stderr(&o).contains(&format!("dmd resume {}", ck.display())),
        "{}",
        stderr(&o)
    );
    let o = dmd(&["resume", "--quiet"], &[("", &ck)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let straight = d.join("straight");
    let o = dmd(&["run", "--quiet"], &[("", &s), ("--out", &straight)]);
    assert!(o.status.success(), "{}", stderr(&o));
    crate::support::same_files(
        &stopped,
        &straight,
        &["series.csv", "msd.csv", "trajectory.xyz"],
    );
    assert_eq!(
        crate::support::summary_without_timings(&stopped),
        crate::support::summary_without_timings(&straight)
    );
    let _ = std::fs::remove_dir_all(d);
}

/// Rigid dumbbells (site molecules) stop on a signal as spheres do: at the next re-basing,
/// by default within 10⁴ events (about a quarter of a second here), from which the resumed
/// run is bit for bit the run never stopped.
#[test]
fn a_signal_stops_a_run_of_site_molecules_that_resumes_bit_for_bit() {
    let d = dir("signal-sites");
    let text = r#"version = 1
seed = 10
[box]
density = 0.42631
[[species]]
name = "dumbbell"
count = 108
molecule = { kind = "dumbbell", elongation = 0.6 }
[[site_pair]]
sites = ["A", "A"]
steps = [[1.0, inf]]
[init]
positions = "fcc"
orientations = "random"
temperature = 1.0
[run]
time = 40.0
[output]
sample_interval = 0.5
series = true
msd = { max_lag = 5 }
orientation_acf = { max_lag = 3 }
trajectory = { interval = 2 }
"#;
    signal_then_resume_is_bit_for_bit(
        &d,
        text,
        &["series.csv", "msd.csv", "oacf.csv", "trajectory.xyz"],
    );
    let _ = std::fs::remove_dir_all(d);
}

/// Semi-flexible chains (RATTLE between events) stop on a signal at the next re-basing and
/// resume bit for bit.
#[test]
fn a_signal_stops_a_run_of_flexible_molecules_that_resumes_bit_for_bit() {
    let d = dir("signal-flexible");
    let text = r#"version = 1
seed = 21
[box]
density = 0.04
[[species]]
name = "chain"
count = 64
sites = [
  { kind = "A", mass = 1.0, position = [0.0, 0.0, 0.0] },
  { kind = "B", mass = 1.0, position = [0.6, 0.0, 0.0] },
  { kind = "B", mass = 1.0, position = [0.9, 0.52, 0.0] },
  { kind = "A", mass = 1.0, position = [1.5, 0.52, 0.05] },
]
bonds = [[0, 1], [1, 2], [2, 3]]
[[site_pair]]
sites = ["A", "A"]
steps = [[1.0, inf], [1.3, -1.0]]
[[site_pair]]
sites = ["A", "B"]
steps = [[0.8, inf], [1.0, -0.5], [1.25, -0.25]]
[[site_pair]]
sites = ["B", "B"]
steps = [[0.6, inf], [0.9, 0.3]]
[rattle]
step = 0.005
[search]
max_step = 0.02
window = 0.1
[init]
positions = "sc"
temperature = 1.5
[run]
time = 16.0
[output]
sample_interval = 0.5
series = true
msd = { max_lag = 4 }
trajectory = { interval = 1 }
"#;
    signal_then_resume_is_bit_for_bit(&d, text, &["series.csv", "msd.csv", "trajectory.xyz"]);
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn a_second_signal_stops_the_run_at_once() {
    // Re-basings 1e9 events apart: the first signal alone would wait for the end of the run.
    let d = dir("signal-twice");
    let s = d.join("scene.toml");
    let text = long().replace("events = 4e6\n", "events = 1e8\nrebase_events = 1e9\n");
    std::fs::write(&s, &text).unwrap();
    let out = d.join("out");
    let (o, took) = run_and_signal(&s, &out, 2);
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(took.as_secs() < 10, "{took:?}");
    assert!(!out.join("checkpoint.dmd").exists());
    let _ = std::fs::remove_dir_all(d);
}
