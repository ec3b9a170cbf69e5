//! `cargo xtask validate --only tune`: `dmd tune` on the shipped scenes, and its
//! recommendation run for real.
//!
//! For each case, `tune::tune` with its default probes; then the recommended settings of all
//! knobs together and a finer reference (every knob at half its finest probed value, one step
//! beyond what the tune could see) are each run at the scene's full length, and the relative
//! differences of U/N and P (scaled as the tune scales them) are checked against the target.
//! `--case TEXT`: only the cases whose name contains `TEXT` (`stepped-lj`).
//! `--quick`: the reduced rods of the integration tests (N = 216, so that the finer reference's reach fits the box) with short probes and a loose target.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use dmd_sim::run::{Quiet, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::tune::{self, FACTORS, TuneOptions, WALL_BUDGET};

mod common;
use common::{Args, Report};

/// One tuned scene.
struct Case {
    name: &'static str,
    scene: PathBuf,
    overrides: Vec<String>,
    target: f64,
    /// Probe production length (`None`: the tune's default).
    time: Option<f64>,
    /// Overrides of the long runs' length (`[]`: the scene's).
    long: Vec<String>,
}

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// The explicit step table of `stepped-lj.toml` given as the Lennard-Jones potential on
/// terraces of the same ΔV = ε/2 and core at 10ε, so that `dmd tune` has a step to vary; and
/// its lengths in time (10 τ of equilibration, 40 τ of production) instead of events: a finer
/// ΔV makes more events per τ, so that runs of a fixed number of events would cover ever less
/// time (5·10⁶ events are 1.5 τ at ε/16, too few samples for an error bar) after an
/// equilibration too short to melt the fcc start.
fn stepped_lj_as_terraces() -> Vec<String> {
    vec![
        "pair.0.steps=".to_owned(),
        r#"pair.0.potential={kind="lennard-jones", epsilon=1.0, sigma=1.0}"#.to_owned(),
        "pair.0.terraces={step=0.5, core=10.0}".to_owned(),
        "run.events=".to_owned(),
        "run.equilibration_events=".to_owned(),
        "run.time=40".to_owned(),
        "run.equilibration_time=10".to_owned(),
    ]
}

fn cases(quick: bool, work: &Path) -> Result<Vec<Case>, String> {
    if quick {
        std::fs::create_dir_all(work).map_err(|e| e.to_string())?;
        let path = work.join("rods.toml");
        std::fs::write(&path, QUICK_RODS).map_err(|e| e.to_string())?;
        return Ok(vec![Case {
            name: "reduced rods (N = 216)",
            scene: path,
            overrides: Vec::new(),
            target: 0.5,
            time: Some(0.2),
            long: vec!["run.time=1.0".to_owned()],
        }]);
    }
    Ok(vec![
        Case {
            name: "scenes/rods-paper.toml",
            scene: scenes().join("rods-paper.toml"),
            overrides: Vec::new(),
            target: 0.02,
            time: None,
            // Three times the scene's production: at 20 ps the standard error of the two
            // runs' difference in P is 1.8 % of ρkT, as large as the target it checks.
            long: vec!["run.time=60".to_owned()],
        },
        Case {
            name: "scenes/stepped-lj.toml (as terraces)",
            scene: scenes().join("stepped-lj.toml"),
            overrides: stepped_lj_as_terraces(),
            target: 0.01,
            time: None,
            long: Vec::new(),
        },
    ])
}

/// The reduced rods of the integration tests, 216 of them, with a search step and sampling.
const QUICK_RODS: &str = r#"
version = 1
seed = 3
[box]
density = 0.5
[[species]]
name = "rod"
count = 216
mass = 1.0
inertia = 0.00696
[[pair]]
species = ["rod", "rod"]
potential = { kind = "rods", epsilon = 1.0, sigma = 1.0, zeta = 0.3295 }
terraces = { step_kt = 0.5 }
[init]
positions = "sc"
temperature = 1.4
[thermostat]
kind = "andersen"
rate = 2.0
[run]
equilibration_time = 0.5
time = 0.5
[search]
max_step = 0.01
window = 0.01
[output]
sample_interval = 0.01
"#;

/// U/N, P (with errors), ρkT and CPU seconds of a run of `scene` with `sets`.
fn long_run(case: &Case, sets: &[String]) -> Result<[f64; 6], String> {
    let mut all = case.overrides.clone();
    all.extend(case.long.iter().cloned());
    all.extend(sets.iter().cloned());
    // At the bath temperature throughout, as the tune's probes are.
    let (scene, _) = Scene::load(&case.scene, &all).map_err(|e| e.to_string())?;
    all.extend(tune::canonical_sets(&scene));
    // The smooth estimators at every sample, as in the probes, so that they carry an error.
    if scene.wants_smooth_estimators() {
        all.push("output.smooth_every=1".to_owned());
    }
    let (scene, base) = Scene::load(&case.scene, &all).map_err(|e| e.to_string())?;
    let s = run_scene(&scene, &base, None, &mut Quiet).map_err(|e| e.to_string())?;
    // As the tune judges them: the smooth estimators where the scene has them.
    let (u, u_err, p, p_err) = match (s.potential_energy_per_body_smooth, s.pressure_smooth) {
        (Some(u), Some(p)) => (
            u,
            s.potential_energy_per_body_smooth_error,
            p,
            s.pressure_smooth_error,
        ),
        _ => (
            s.potential_energy_per_body,
            s.potential_energy_per_body_error,
            s.pressure,
            s.pressure_error,
        ),
    };
    Ok([
        u,
        u_err.unwrap_or(f64::NAN),
        p,
        p_err.unwrap_or(f64::NAN),
        s.pressure_ideal,
        s.cpu_seconds,
    ])
}

fn validate(args: &Args, work: &Path, r: &mut Report, out: &mut String) -> Result<(), String> {
    let _ = writeln!(
        out,
        "`dmd tune` with its default probes (the knob's scene value times {FACTORS:?}, probe \
         production half the scene's, equilibration half the scene's) and its default \
         wall-clock budget of {WALL_BUDGET} s, within which it lengthens the probes whose noise \
         keeps a knob from certifying U/N and P (each pooled with independent runs of its own \
         seed), then two long runs (the scene's production; 60 ps for the rods, whose P \
         otherwise carries a 1.8 % error bar against a 2 % target): every knob at its recommended value, and every knob at half its \
         finest probed value (a reference finer than any the tune saw; a level rule at the scene's). \
         Check: U/N and P of the recommended run, each where the tune claims it (every knob's \
         recommendation certifies it), within the target of the finer reference, relative to |U/N| and to \
         max(|P|, ρkT) as the tune measures them (for terraces of a smooth potential, those of \
         the smooth estimators: the continuous model along the run), both with the Andersen \
         thermostat on in production as the tune's probes are. `stepped-lj.toml` is tuned through \
         `--set pair.0.steps= --set 'pair.0.potential={{kind=\"lennard-jones\", epsilon=1.0, \
         sigma=1.0}}' --set 'pair.0.terraces={{step=0.5, core=10.0}}'` (the same ΔV = ε/2 and \
         core; an explicit step table has no step to vary), with its lengths in time \
         (`run.time=40 run.equilibration_time=10` for its 5·10⁶ and 10⁶ events: a fixed number \
         of events covers less time at every finer ΔV). Wall times on the shared 2-core \
         machine.{}\n",
        if args.quick {
            " Quick run."
        } else {
            " Full run."
        }
    );
    for case in cases(args.quick, work)?.into_iter().filter(|c| {
        args.case
            .as_ref()
            .is_none_or(|n| c.name.contains(n.as_str()))
    }) {
        let started = std::time::Instant::now();
        let options = TuneOptions {
            target: case.target,
            overrides: case.overrides.clone(),
            time: case.time,
            events: None,
            wall_budget: None,
        };
        let mut progress = |done: usize, total: usize, what: &str| {
            eprintln!(
                "validate_tune: {}: [{done}/{total}] {:.0} s {what}",
                case.name,
                started.elapsed().as_secs_f64()
            );
        };
        let t = tune::tune(&case.scene, &options, &mut progress).map_err(|e| e.to_string())?;
        let tune_wall = started.elapsed().as_secs_f64();
        let folder = format!("tune-{}", case.scene.file_stem().unwrap().to_string_lossy());
        t.write(&args.figures.join(&folder))
            .map_err(|e| e.to_string())?;
        let _ = writeln!(
            out,
            "### {}, target {} %\n\n{}; the tune took {:.0} s of wall time.\n\n```\n{}\n{}```\n\n\
             ![dmd tune: error bound against cost](figures/{folder}/tune.svg)\n",
            case.name,
            100.0 * case.target,
            t.length,
            tune_wall,
            t.table().trim_end(),
            t.recommendation()
        );
        let recommended = t.recommended_sets();
        let finer: Vec<String> = t.knobs.iter().flat_map(|k| k.finer_sets()).collect();
        eprintln!("validate_tune: {}: long runs", case.name);
        let a = long_run(&case, &recommended)?;
        let b = long_run(&case, &finer)?;
        let scales = [b[0].abs(), b[2].abs().max(b[4].abs())];
        let _ = writeln!(
            out,
            "Recommended (`{}`) against the finer reference (`{}`), full-length runs:\n\n\
             | quantity | recommended | finer reference | relative difference | target | check |\n\
             |---|---|---|---|---|---|",
            recommended.join(" "),
            finer.join(" ")
        );
        // The tune's claim: the quantities every knob's recommendation certifies.
        let claimed = t.certified_all();
        for (k, name) in [(0usize, "U/N"), (2, "P")] {
            let d = (a[k] - b[k]).abs() / scales[k / 2];
            let u = a[k + 1].hypot(b[k + 1]) / scales[k / 2];
            let check = if claimed[k / 2] {
                r.check(d <= case.target)
            } else {
                "not claimed by the tune (shown, not checked)"
            };
            let _ = writeln!(
                out,
                "| {name} | {:.4} ± {:.4} | {:.4} ± {:.4} | {:.2} ± {:.2} % | {} % | {check} |",
                a[k],
                a[k + 1],
                b[k],
                b[k + 1],
                100.0 * d,
                100.0 * u,
                100.0 * case.target,
            );
        }
        let _ = writeln!(
            out,
            "\nCPU s of production: recommended {:.1}, finer reference {:.1}.\n",
            a[5], b[5]
        );
    }
    Ok(())
}

fn main() -> ExitCode {
    common::main_of("validate_tune", validate)
}
