//! A signal at a random moment of a long run, and `dmd resume` of the checkpoint it leaves,
//! against the same run never stopped: every file of the output folder and the summary
//! (timings excepted) must be the same byte for byte.
//!
//! For each case (hard spheres and the paper's rods, with every output they have streamed as
//! the run goes) the production length is first calibrated to about `--cpu` seconds of CPU
//! (30 by default, 2 with `--quick`) from a short run; the run is then made once without a
//! stop, and `--trials` times (4; 2 with `--quick`) it is started and sent SIGTERM once it has
//! used a CPU time drawn uniformly over 5–85 % of the straight run's production CPU time (so
//! that the moment is a point of the run whatever the load of the machine, which changes its
//! wall-clock time), and resumed; every second trial stops its resumed run again at a CPU
//! time drawn over 5–50 % of what was left, before resuming it to the end. The moments come
//! from the clock, so they differ between runs of this check; they are printed with the
//! results.
//!
//! It runs the `dmd` command that `cargo build --release -p dmd-sim --features validation`
//! builds next to this example (it builds it first). Prints a Markdown report on stdout and
//! exits non-zero if a resumed run differs from the straight one, if a stopped run does not
//! exit with the interrupted status 130, or if fewer than all but one of the trials of a case
//! were stopped before their end (a signal that comes after the end stops nothing). `--figures
//! DIR` is accepted for symmetry with the other validations (no figure is written).

use rand::{Rng, SeedableRng};
use rand_xoshiro::SplitMix64;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::time::Duration;

/// One scene of the check.
struct Case {
    title: &'static str,
    /// The scene, without `[run]`'s production length (`events = {EVENTS}` is filled in).
    text: &'static str,
}

const SPHERES: &str = r#"version = 1
seed = 31
[box]
density = 0.8
[[species]]
name = "A"
count = 4000
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf]]
[init]
positions = "fcc"
temperature = 1.0
[run]
equilibration_events = 4e5
events = {EVENTS}
# As for the rods below: a signal stops a run at its next re-basing, and the quick check's
# production (about 10⁶ events) may hold none at the default interval.
rebase_events = 1e5
[output]
sample_interval = 0.05
series = true
rdf = { bins = 100, r_max = 4.0, every = 10 }
msd = { max_lag = 2.0 }
vacf = { max_lag = 0.5 }
trajectory = { interval = 20.0 }
"#;

const RODS: &str = r#"version = 1
seed = 2008
units = "molecular"
[box]
density = 0.0178853806
[[species]]
name = "rod"
count = 512
mass = 18.0
inertia = 1.154
[[pair]]
species = ["rod", "rod"]
potential = { kind = "rods", epsilon = 3.0, sigma = 3.035, zeta = 1.0 }
terraces = { step_kt = 0.5 }
[init]
positions = "sc"
orientations = "random"
temperature = 505.144
[thermostat]
kind = "andersen"
rate = 2.0
[search]
method = "adaptive"
max_step = 0.004
window = 0.004
jitter = 0.01
[run]
equilibration_time = 2.0
events = {EVENTS}
# A signal stops a run at its next re-basing: at the default (10⁶ events) the quick check's
# production (about 6·10⁵ events) may hold none, and the stopped run then ends normally.
rebase_events = 1e5
[output]
sample_interval = 0.005
rdf = { bins = 200, r_max = 12.0, every = 20 }
msd = { max_lag = 5.0 }
vacf = { max_lag = 1.0 }
orientation_acf = { max_lag = 1.0 }
series = true
trajectory = { interval = 2.0 }
"#;

const CASES: &[Case] = &[
    Case {
        title: "hard spheres, N = 4000, ρσ³ = 0.8 (series, g(r), MSD, VACF, trajectory)",
        text: SPHERES,
    },
    Case {
        title: "rods of the paper, N = 512, ρ* = 0.5, T* = 1.4 (series, g(r), MSD, VACF, OACF, trajectory)",
        text: RODS,
    },
];

/// The status of a run stopped by a signal (the user guide's exit-code contract).
const INTERRUPTED: i32 = 130;

struct Options {
    cpu: f64,
    trials: usize,
    quick: bool,
}

fn main() -> ExitCode {
    let mut o = Options {
        cpu: 30.0,
        trials: 4,
        quick: false,
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut k = 0;
    while k < args.len() {
        match args[k].as_str() {
            "--quick" => {
                o.quick = true;
                o.cpu = 2.0;
                o.trials = 2;
            }
            "--cpu" => {
                k += 1;
                o.cpu = args[k].parse().expect("--cpu SECONDS");
            }
            "--trials" => {
                k += 1;
                o.trials = args[k].parse().expect("--trials N");
            }
            "--figures" => k += 1,
            other => {
                eprintln!("validate_signals: unknown argument `{other}`");
                return ExitCode::FAILURE;
            }
        }
        k += 1;
    }
    let dmd = match build_dmd() {
        Ok(p) => p,
        Err(e) => {
            eprintln!("validate_signals: {e}");
            return ExitCode::FAILURE;
        }
    };
    let work = std::env::temp_dir().join(format!("dmd-validate-signals-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).expect("a temporary folder");
    // The moments' generator, seeded from the clock: every run of the check draws new ones.
    let seed = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(1, |d| d.as_nanos() as u64)
        | 1;
    let mut rng = SplitMix64::seed_from_u64(seed);
    let mut report = String::new();
    let _ = writeln!(
        report,
        "Each case's production is calibrated to about {} s of CPU; the run is made once \
         without a stop and {} times stopped by SIGTERM once it has used a CPU time drawn \
         uniformly over 5–85 % of the straight run's production CPU time (every second trial \
         stopped again in its resumed run, over 5–50 % of what was left), then resumed with \
         `dmd resume` to its end. \
         Every file of the output folder and the summary (timings excepted) are compared \
         with the straight run's byte for byte. Moments drawn from seed {seed:#x}.\n",
        short(o.cpu),
        o.trials
    );
    let mut ok = true;
    for (c, case) in CASES.iter().enumerate() {
        let dir = work.join(format!("case{c}"));
        std::fs::create_dir_all(&dir).expect("a temporary folder");
        match run_case(&dmd, case, &dir, &o, &mut rng) {
            Ok((text, passed)) => {
                ok &= passed;
                let _ = writeln!(report, "### {}\n\n{text}", case.title);
            }
            Err(e) => {
                ok = false;
                let _ = writeln!(report, "### {}\n\nFAILED: {e}\n", case.title);
            }
        }
    }
    let _ = writeln!(
        report,
        "Result: {}.",
        if ok {
            "every stopped run resumed to the straight run's files and summary, bit for bit"
        } else {
            "FAILED"
        }
    );
    print!("{report}");
    let _ = std::fs::remove_dir_all(&work);
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// Builds `dmd` with this example's profile and features (so that cargo reuses the library it
/// already built) and gives its path, next to this example's folder.
fn build_dmd() -> Result<PathBuf, String> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = Command::new(cargo)
        .args([
            "build",
            "--quiet",
            "--release",
            "-p",
            "dmd-sim",
            "--features",
            "validation",
            "--bin",
            "dmd",
        ])
        .stdout(Stdio::null())
        .status()
        .map_err(|e| format!("cannot start cargo: {e}"))?;
    if !status.success() {
        return Err("cargo could not build dmd".into());
    }
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let path = exe
        .parent()
        .and_then(Path::parent)
        .map(|d| d.join("dmd"))
        .ok_or("no folder above this example")?;
    if path.exists() {
        Ok(path)
    } else {
        Err(format!("{} was not built", path.display()))
    }
}

/// A uniform draw in `[a, b)` from the moments' generator (SplitMix64: portable, so the
/// moments are the same on every machine).
fn between(rng: &mut SplitMix64, a: f64, b: f64) -> f64 {
    a + (b - a) * ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
}

/// `summary.json` of `dir` without its timings, or `None` without one.
fn summary_without_timings(dir: &Path) -> Option<serde_json::Value> {
    let mut v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).ok()?).ok()?;
    let o = v.as_object_mut()?;
    for k in [
        "wall_seconds",
        "cpu_seconds",
        "events_per_second",
        "events_per_cpu_second",
        "pair_events_per_second",
        "pair_events_per_cpu_second",
    ] {
        o.remove(k);
    }
    Some(v)
}

/// Runs `dmd ARGS` to its end; its exit status and standard error.
fn run(dmd: &Path, args: &[&std::ffi::OsStr]) -> Result<(Option<i32>, String), String> {
    let o = Command::new(dmd)
        .args(args)
        .stdout(Stdio::null())
        .output()
        .map_err(|e| format!("cannot start dmd: {e}"))?;
    Ok((
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    ))
}

/// CPU seconds (user and system) the process `pid` has used, from `/proc/PID/stat` (`None`
/// once it has ended).
fn cpu_seconds(pid: u32, ticks: f64) -> Option<f64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The fields after the command name, which is in parentheses and may hold spaces.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the line, 12 and 13 after the name.
    let (u, s) = (
        f.get(11)?.parse::<f64>().ok()?,
        f.get(12)?.parse::<f64>().ok()?,
    );
    Some((u + s) / ticks)
}

/// Clock ticks per second of `/proc`'s times.
fn clock_ticks() -> f64 {
    Command::new("getconf")
        .arg("CLK_TCK")
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .and_then(|t| t.trim().parse().ok())
        .unwrap_or(100.0)
}

/// Runs `dmd ARGS` and sends it SIGTERM once it has used `cpu` seconds of CPU (a moment that
/// means the same point of the run whatever the machine's load); its exit status and standard
/// error.
fn run_and_stop(
    dmd: &Path,
    args: &[&std::ffi::OsStr],
    cpu: f64,
) -> Result<(Option<i32>, String), String> {
    let ticks = clock_ticks();
    let mut child = Command::new(dmd)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start dmd: {e}"))?;
    let pid = child.id();
    loop {
        if child.try_wait().map_err(|e| e.to_string())?.is_some() {
            break;
        }
        if cpu_seconds(pid, ticks).is_some_and(|c| c >= cpu) {
            let k = Command::new("kill")
                .args(["-TERM", &pid.to_string()])
                .status()
                .map_err(|e| format!("cannot start kill: {e}"))?;
            if !k.success() {
                return Err("kill -TERM failed".into());
            }
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let o = child.wait_with_output().map_err(|e| e.to_string())?;
    Ok((
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    ))
}

/// The files of `a` (the stopped and resumed run) that differ from `b`'s (the straight run),
/// or exist in one only; `summary.json` is compared without timings and `checkpoint.dmd` (the
/// stopped run's) is left out.
fn differences(a: &Path, b: &Path) -> Vec<String> {
    let names = |d: &Path| -> std::collections::BTreeSet<String> {
        std::fs::read_dir(d)
            .map(|r| {
                r.filter_map(Result::ok)
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|n| n != "checkpoint.dmd")
                    .collect()
            })
            .unwrap_or_default()
    };
    let (na, nb) = (names(a), names(b));
    let mut out: Vec<String> = na
        .symmetric_difference(&nb)
        .map(|n| format!("{n} (in one folder only)"))
        .collect();
    for n in na.intersection(&nb) {
        let same = if n == "summary.json" {
            summary_without_timings(a) == summary_without_timings(b)
        } else {
            std::fs::read(a.join(n)).ok() == std::fs::read(b.join(n)).ok()
        };
        if !same {
            out.push(n.clone());
        }
    }
    out
}

fn short(x: f64) -> String {
    if x >= 100.0 {
        format!("{x:.0}")
    } else {
        format!("{x:.2}")
    }
}

/// One case: calibration, the straight run and the trials; the report and whether it passed.
fn run_case(
    dmd: &Path,
    case: &Case,
    dir: &Path,
    o: &Options,
    rng: &mut SplitMix64,
) -> Result<(String, bool), String> {
    let os = |p: &Path| p.as_os_str().to_owned();
    let scene_with = |events: u64, name: &str| -> Result<PathBuf, String> {
        let p = dir.join(name);
        std::fs::write(&p, case.text.replace("{EVENTS}", &events.to_string()))
            .map_err(|e| e.to_string())?;
        Ok(p)
    };
    let straight_run = |scene: &Path, out: &Path| -> Result<serde_json::Value, String> {
        let (code, err) = run(
            dmd,
            &[
                "run".as_ref(),
                "--quiet".as_ref(),
                &os(scene),
                "--out".as_ref(),
                &os(out),
            ],
        )?;
        if code != Some(0) {
            return Err(format!("dmd run exited with {code:?}: {err}"));
        }
        std::fs::read(out.join("summary.json"))
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
            .ok_or_else(|| "no summary".to_owned())
    };
    // Calibration: CPU seconds of production per event.
    let probe_events = 200_000u64;
    let probe = straight_run(&scene_with(probe_events, "probe.toml")?, &dir.join("probe"))?;
    let cpu_per_event = probe["cpu_seconds"].as_f64().unwrap_or(f64::NAN) / probe_events as f64;
    if !(cpu_per_event.is_finite() && cpu_per_event > 0.0) {
        return Err("the calibration run reports no CPU time".into());
    }
    let events = ((o.cpu / cpu_per_event) as u64).max(probe_events);
    let scene = scene_with(events, "scene.toml")?;
    let straight = dir.join("straight");
    let s = straight_run(&scene, &straight)?;
    let (cpu, wall) = (
        s["cpu_seconds"].as_f64().unwrap_or(f64::NAN),
        s["wall_seconds"].as_f64().unwrap_or(f64::NAN),
    );
    let mut files: Vec<String> = std::fs::read_dir(&straight)
        .map_err(|e| e.to_string())?
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let mut text = format!(
        "{events} events of production: {} s of CPU, {} s of wall-clock time in the straight \
         run; files compared: {}.\n\n\
         | trial | first stop (CPU s into the run) | exit | second stop (CPU s into the resumed run) | exit | resumed to the end | files and summary |\n\
         |---|---|---|---|---|---|---|\n",
        short(cpu),
        short(wall),
        files.join(", ")
    );
    let mut passed = true;
    let mut stopped = 0;
    for t in 0..o.trials {
        let out = dir.join(format!("trial{t}"));
        let ck = out.join("checkpoint.dmd");
        let first = between(rng, 0.05, 0.85) * cpu;
        let (code, err) = run_and_stop(
            dmd,
            &[
                "run".as_ref(),
                "--quiet".as_ref(),
                &os(&scene),
                "--out".as_ref(),
                &os(&out),
            ],
            first,
        )?;
        let mut row = format!("| {} | {} | {} |", t + 1, short(first), exit_text(code));
        let mut trial_ok = match code {
            Some(INTERRUPTED) => {
                stopped += 1;
                true
            }
            // The signal came after the end: nothing to resume, the run is the straight one.
            Some(0) => true,
            _ => {
                row.push_str(&format!(" ({})", err.lines().next().unwrap_or("")));
                false
            }
        };
        let mut second_text = ("–".to_owned(), "–".to_owned());
        if trial_ok && code == Some(INTERRUPTED) {
            if t % 2 == 1 {
                let second = between(rng, 0.05, 0.5) * (cpu - first).max(0.0);
                let (code2, err2) = run_and_stop(
                    dmd,
                    &["resume".as_ref(), "--quiet".as_ref(), &os(&ck)],
                    second,
                )?;
                second_text = (short(second), exit_text(code2));
                if !matches!(code2, Some(INTERRUPTED) | Some(0)) {
                    trial_ok = false;
                    second_text.1 = format!("{} ({})", second_text.1, first_line(&err2));
                }
            }
            if trial_ok && !out.join("summary.json").exists() {
                let (code3, err3) = run(dmd, &["resume".as_ref(), "--quiet".as_ref(), &os(&ck)])?;
                if code3 != Some(0) {
                    trial_ok = false;
                    row.push_str(&format!(" resume: {}", first_line(&err3)));
                }
                row.push_str(&format!(
                    " {} | {} | {} |",
                    second_text.0,
                    second_text.1,
                    exit_text(code3)
                ));
            } else {
                row.push_str(&format!(" {} | {} | – |", second_text.0, second_text.1));
            }
        } else {
            row.push_str(" – | – | – |");
        }
        let diff = if trial_ok {
            differences(&out, &straight)
        } else {
            vec!["not compared".to_owned()]
        };
        if diff.is_empty() {
            row.push_str(" identical |");
        } else {
            trial_ok = false;
            row.push_str(&format!(" DIFFER: {} |", diff.join(", ")));
        }
        passed &= trial_ok;
        let _ = writeln!(text, "{row}");
        let _ = std::fs::remove_dir_all(&out);
    }
    if stopped + 1 < o.trials {
        passed = false;
        let _ = writeln!(
            text,
            "\nOnly {stopped} of {} trials were stopped before their end.",
            o.trials
        );
    }
    let _ = std::fs::remove_dir_all(&straight);
    Ok((text, passed))
}

fn exit_text(code: Option<i32>) -> String {
    code.map_or_else(|| "killed".to_owned(), |c| c.to_string())
}

fn first_line(s: &str) -> &str {
    s.lines().next().unwrap_or("")
}
