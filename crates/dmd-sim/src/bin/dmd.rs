//! `dmd`: run event-driven molecular dynamics scenes.
//!
//! `dmd run SCENE.toml --out DIR [--set KEY=VALUE]...` runs a scene: it says what runs, shows a
//! progress bar on a terminal, prints a summary in the scene's units and writes
//! `DIR/summary.json` plus the outputs the scene asks for. `dmd check SCENE.toml` only reads and
//! checks the scene. `dmd run --checkpoint-every` saves `DIR/checkpoint.dmd` from time to time,
//! and `dmd resume CHECKPOINT` continues such a run bit for bit; a scene with `[chains]` or
//! `[sweep]` runs its jobs in parallel. Every argument and the output folder are checked before
//! the run (exit status 2); a folder holding another run's files needs `--force`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand};
use dmd_sim::checkpoint::{self, Every, SceneSource};
use dmd_sim::run::{PhaseEnd, Reporter, RunOptions, RunPlan, Summary, run_scene_with};
use dmd_sim::scene::{Scene, UnitSystem};
use dmd_sim::simulation::{Progress, Stop};
use dmd_sim::smd_engine::{self, Engine, SmdSummary};
use dmd_sim::units::UnitNames;
use indicatif::{ProgressBar, ProgressStyle};

/// Large arrays (bodies, event and neighbour lists of large systems) on 2 MiB pages: their
/// accesses come in random order and 4 KiB pages would cost a page-table walk on most of them.
#[global_allocator]
static ALLOCATOR: memory_hints::LargePages = memory_hints::LargePages;

/// The `dmd` command.
#[derive(Parser)]
#[command(
    name = "dmd",
    version,
    about = "Event-driven molecular dynamics: bodies move freely between events, and at an event \
             a pair reaching a step of its potential exchanges momentum and energy exactly.",
    long_about = "Event-driven molecular dynamics: bodies move freely between events, and at \
                  an event a pair reaching a step of its potential exchanges momentum and \
                  energy exactly.\n\n\
                  It runs hard spheres, square-well and stepped spheres (mixtures too); hard \
                  spherocylinders; rigid rods, Gay-Berne ellipsoids and rigid tops such as SSD/E \
                  water and SPC/E water, whose smooth potential is mapped onto energy terraces; \
                  rigid site molecules; and semi-flexible molecules with bonds held by RATTLE, \
                  their own atoms interacting if asked. With --engine smd the \
                  same scene runs with standard (time-step) molecular dynamics on the smooth \
                  potential.\n\n\
                  A scene is a TOML file; docs/USER-GUIDE.md describes every key, the units \
                  and every output. Start with: dmd run scenes/hard-spheres.toml --out out/hs"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene (equilibration, then production): prints what runs, a progress bar and a
    /// summary, and writes DIR/summary.json and the files the scene asks for.
    Run {
        /// The scene file (TOML; every key is described in docs/USER-GUIDE.md).
        scene: PathBuf,
        /// Output folder (created if missing).
        #[arg(long, short)]
        out: PathBuf,
        /// Override a scene key: dotted path = TOML value (repeatable), e.g.
        /// `--set run.events=1e6 --set box.density=0.8 --set species.0.count=4000`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// The engine, overriding the scene's `engine` key: `dmd` (event-driven) or `smd`
        /// (standard MD on the smoothed potential).
        #[arg(long, value_parser = ["dmd", "smd"])]
        engine: Option<String>,
        /// Print nothing but errors and warnings (no header, progress bar or summary).
        #[arg(long, short)]
        quiet: bool,
        /// Save DIR/checkpoint.dmd this often: a number of events (1e7) or a wall-clock time
        /// (90s, 10m, 2h), so that `dmd resume` can continue the run after a crash or a
        /// stop. Saved at the next moment the state can be saved exactly (at most
        /// run.rebase_events events later; HMC: between segments).
        #[arg(long, value_name = "EVENTS|TIME")]
        checkpoint_every: Option<String>,
        /// Threads for the jobs of a scene with `[chains]` or `[sweep]` (default: all cores).
        /// Results do not depend on it.
        #[arg(long, value_parser = threads_count)]
        threads: Option<usize>,
        /// Replace the files of a previous run in the output folder (only files dmd writes
        /// are removed); without it such a folder is refused.
        #[arg(long)]
        force: bool,
        /// Stop right after the first checkpoint, as a crash would (tests of `dmd resume`).
        #[arg(long, hide = true)]
        halt_after_checkpoint: bool,
    },
    /// Continue a stopped run from its checkpoint (written by `dmd run --checkpoint-every` or
    /// when a signal stopped it), or finish the chains or sweep of an output folder.
    Resume {
        /// The checkpoint file, or the output folder of a scene with `[chains]` or `[sweep]`.
        checkpoint: PathBuf,
        /// Output folder (default: the checkpoint's folder).
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// Print nothing but errors and warnings (no header, progress bar or summary).
        #[arg(long, short)]
        quiet: bool,
        /// Change the checkpoint interval (default: the saved one).
        #[arg(long, value_name = "EVENTS|TIME")]
        checkpoint_every: Option<String>,
        /// Threads for the jobs of chains or a sweep (default: all cores).
        #[arg(long, value_parser = threads_count)]
        threads: Option<usize>,
    },
    /// Find the cheapest accuracy setting of a scene within a target error: short probe runs
    /// at 2, 1, ½ and ¼ times each accuracy knob the scene uses (terrace step ΔV, search step,
    /// smd time step), errors of U/N and P against the finest with their error bars, cost in
    /// CPU s per simulated time; prints a table and the `--set` lines to use, and writes
    /// DIR/tune.csv and DIR/tune.svg.
    Tune {
        /// The scene file.
        scene: PathBuf,
        /// Target relative error of U/N and P (0.02 = 2 %).
        #[arg(long, allow_hyphen_values = true)]
        target: f64,
        /// Output folder for tune.csv and tune.svg (created if missing).
        #[arg(long, short)]
        out: PathBuf,
        /// Override a scene key (as for `run`), before the probes' own settings.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// The engine (as for `run`).
        #[arg(long, value_parser = ["dmd", "smd"])]
        engine: Option<String>,
        /// Production time of each probe, in the scene's time unit (default: half the
        /// scene's production; equilibration is half the scene's).
        #[arg(long)]
        time: Option<f64>,
        /// Or: production events of each probe.
        #[arg(long, conflicts_with = "time")]
        events: Option<f64>,
        /// Wall-clock budget of the whole tune: seconds (540, 540s), minutes (9m) or hours
        /// (1h); default 9m. The first pass of probes always runs; probes whose noise keeps a
        /// knob from certifying U/N and P are then lengthened while the estimate fits.
        #[arg(long, allow_hyphen_values = true, value_parser = dmd_sim::tune::parse_wall)]
        budget: Option<f64>,
    },
    /// Read and check a scene (with its overrides) without running it, and say how many bodies
    /// it has.
    Check {
        /// The scene file.
        scene: PathBuf,
        /// Override a scene key (as for `run`).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Check for this engine (as for `run`).
        #[arg(long, value_parser = ["dmd", "smd"])]
        engine: Option<String>,
    },
}

/// The widest line of the header and the summary (the progress bar fits the terminal).
const COLUMNS: usize = 100;

/// `x` to `digits` significant digits: plain between 10⁻³ and 10⁶, else in scientific notation.
/// `--threads`: a whole number of at least 1 (rayon would read 0 as "all cores").
fn threads_count(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err("expected a whole number of threads, at least 1".to_owned()),
    }
}

fn sig(x: f64, digits: usize) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let magnitude = x.abs().log10().floor() as i32;
    if (-3..(digits as i32).max(1)).contains(&magnitude) {
        let decimals = (digits as i32 - 1 - magnitude).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.*e}", digits.saturating_sub(1))
    }
}

/// `x` to `digits` significant digits as [`sig`], trailing zeros dropped: `0.05`, `20`, `1.8e-3`.
fn trimmed(x: f64, digits: usize) -> String {
    let s = sig(x, digits);
    match s.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
        }
        None if s.contains('.') => s.trim_end_matches('0').trim_end_matches('.').to_owned(),
        _ => s,
    }
}

/// A length or time as given in a scene: up to 6 significant digits, trailing zeros dropped.
fn plain(x: f64) -> String {
    trimmed(x, 6)
}

/// A mean with its error: the error to two significant digits and the mean to the same decimal
/// place; without an error, the mean to `digits` significant digits.
fn pm(x: f64, error: Option<f64>, digits: usize) -> String {
    match error.filter(|e| e.is_finite() && *e > 0.0) {
        // An error below a millionth of the mean would print a dozen meaningless digits.
        Some(e)
            if x.is_finite()
                && (x == 0.0 || (1e-3..1e6).contains(&x.abs()) && e > 1e-6 * x.abs()) =>
        {
            let decimals = (1 - e.log10().floor() as i32).max(0) as usize;
            format!("{x:.decimals$} ± {e:.decimals$}")
        }
        Some(e) => format!("{} ± {}", sig(x, digits), sig(e, 2)),
        None => sig(x, digits),
    }
}

/// A count with thousands separated: `433,887`.
fn count(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (k, c) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// A wall-clock duration: `0.82 s`, `12.3 s`, `4 min 05 s`, `2 h 07 min`.
fn duration(seconds: f64) -> String {
    if !seconds.is_finite() {
        return "?".to_owned();
    }
    if seconds < 60.0 {
        return format!("{} s", sig(seconds, 3));
    }
    let s = seconds.round() as u64;
    if s < 3600 {
        format!("{} min {:02} s", s / 60, s % 60)
    } else {
        format!("{} h {:02} min", s / 3600, (s % 3600) / 60)
    }
}

/// The length of a phase: simulated time with its unit, events, or HMC segments.
fn span(name: &str, length: Stop, time: &str) -> String {
    match length {
        Stop::Time(t) => format!("{} {time}", plain(t)),
        Stop::Events(n) if name.starts_with("hmc") => format!("{} segments", count(n)),
        Stop::Events(n) => format!("{} events", count(n)),
    }
}

/// What the bodies are, from the interaction model.
fn kind(model: &str) -> &str {
    match model {
        "hard-spheres" => "hard spheres",
        "stepped" => "spheres with stepped potentials",
        "stepped (fault injection)" => "spheres with stepped potentials, fault injection",
        "terraced-rods" => "rigid rods, terraced potential",
        "terraced-gay-berne" => "Gay-Berne ellipsoids, terraced potential",
        "terraced-tops" => "rigid tops, terraced potential",
        "rigid-sites" => "rigid site molecules",
        "semi-flexible" => "semi-flexible molecules",
        "smd-rods" => "rigid rods, smooth potential",
        "smd-lennard-jones" => "Lennard-Jones spheres",
        "smd-gay-berne" => "Gay-Berne ellipsoids, smooth potential",
        "smd-ssd-e" => "SSD/E water",
        "smd-spc-e" => "SPC/E water",
        other => other,
    }
}

/// A summary line: a label in a column of 15, then the text.
fn line(label: &str, text: &str) {
    println!("  {label:<14} {text}");
}

/// A labelled list, wrapped at [`COLUMNS`] with its items aligned.
fn list(label: &str, items: &[String]) {
    wrap(&format!("  {label:<14} "), 17, items);
}

/// Items joined by commas after `first`, wrapped at [`COLUMNS`] onto lines indented by
/// `indent`.
fn wrap(first: &str, indent: usize, items: &[String]) {
    let mut current = first.to_owned();
    for (k, item) in items.iter().enumerate() {
        if k == 0 {
            current.push_str(item);
        } else if current.chars().count() + 2 + item.chars().count() > COLUMNS {
            println!("{current},");
            current = format!("{:indent$}{item}", "");
        } else {
            current.push_str(", ");
            current.push_str(item);
        }
    }
    println!("{current}");
}

/// The terminal side of a run: the header once the run is set up, a progress bar per phase on
/// standard error when it is a terminal, and what the summary needs of the equilibration.
struct Terminal {
    scene: PathBuf,
    out: PathBuf,
    units: UnitSystem,
    engine: &'static str,
    bar: Option<ProgressBar>,
    /// The phase under way: its name, length and wall-clock start.
    phase: Option<(String, Stop, Instant)>,
    /// How equilibration ended, and its wall-clock seconds.
    equilibration: Option<(PhaseEnd, f64)>,
    /// Wall-clock seconds of the last phase that ended.
    last_wall: f64,
}

impl Terminal {
    fn new(scene: &Path, out: &Path) -> Self {
        Terminal {
            scene: scene.to_owned(),
            out: out.to_owned(),
            units: UnitSystem::Reduced,
            engine: "dmd",
            bar: None,
            phase: None,
            equilibration: None,
            last_wall: 0.0,
        }
    }

    /// The progress text: done of total, the time left, and the rates (the time left first,
    /// so that a narrow terminal keeps it).
    fn message(&self, p: Progress) -> Option<(u64, String)> {
        let (name, length, started) = self.phase.as_ref()?;
        let wall = started.elapsed().as_secs_f64().max(1e-9);
        let time = UnitNames::of(self.units).time;
        let per_hour = format!("{} {time}/h", sig(p.elapsed / wall * 3600.0, 3));
        let what = if self.engine == "smd" {
            "steps"
        } else {
            "events"
        };
        let per_second = format!("{} {what}/s", sig(p.events as f64 / wall, 3));
        let (position, fraction, done, rates) = match *length {
            Stop::Time(t) => {
                let f = if t > 0.0 { p.elapsed / t } else { 1.0 };
                (
                    (f * 1000.0) as u64,
                    f,
                    format!("{} of {} {time}", sig(p.elapsed, 3), plain(t)),
                    format!("{per_hour}, {per_second}"),
                )
            }
            Stop::Events(n) if name.starts_with("hmc") => (
                p.events,
                p.events as f64 / n.max(1) as f64,
                format!("{} of {} segments", count(p.events), count(n)),
                format!("{} segments/s", sig(p.events as f64 / wall, 3)),
            ),
            Stop::Events(n) => (
                p.events,
                p.events as f64 / n.max(1) as f64,
                format!("{} of {} events", count(p.events), count(n)),
                format!("{per_second}, {per_hour}"),
            ),
        };
        let eta = if fraction > 0.0 {
            duration(wall * (1.0 - fraction).max(0.0) / fraction)
        } else {
            "?".to_owned()
        };
        Some((position, format!("{done}, eta {eta}, {rates}")))
    }
}

impl Reporter for Terminal {
    fn start(&mut self, plan: &RunPlan) {
        self.units = plan.units;
        self.engine = plan.engine;
        let u = UnitNames::of(plan.units);
        println!(
            "dmd: {} {}, output in {}",
            if plan.resumed_in.is_some() {
                "resuming"
            } else {
                "running"
            },
            self.scene.display(),
            self.out.display()
        );
        let bodies = if plan.species.len() > 1 {
            let parts: Vec<String> = plan
                .species
                .iter()
                .map(|(name, n)| format!("{} {name}", count(*n)))
                .collect();
            format!(
                "{} bodies ({}: {})",
                count(plan.n_bodies),
                kind(&plan.model),
                parts.join(", ")
            )
        } else {
            format!("{} bodies ({})", count(plan.n_bodies), kind(&plan.model))
        };
        let l = plan.box_lengths;
        let edges = if l[0] == l[1] && l[1] == l[2] {
            format!("box {} {}", sig(l[0], 4), u.length)
        } else {
            format!(
                "box {} × {} × {} {}",
                sig(l[0], 4),
                sig(l[1], 4),
                sig(l[2], 4),
                u.length
            )
        };
        wrap(
            "  ",
            2,
            &[
                bodies,
                format!("ρ = {} {}", sig(plan.density, 4), u.density),
                edges,
                format!("T = {} {}", sig(plan.temperature, 4), u.temperature),
                u.system.to_owned(),
            ],
        );
        let engine = match plan.dt {
            Some(dt) => format!("standard MD, dt = {} {}", plain(dt), u.time),
            None => "event-driven".to_owned(),
        };
        let mut phases: Vec<String> = plan
            .phases
            .iter()
            .map(|(name, length)| {
                let bath = match (plan.thermostat, *name) {
                    (Some((t, _)), "equilibration") if plan.engine == "smd" => {
                        format!(" (velocity rescaling to {} {})", sig(t, 4), u.temperature)
                    }
                    (Some((t, _)), "equilibration") => {
                        format!(" (Andersen thermostat at {} {})", sig(t, 4), u.temperature)
                    }
                    (Some((t, "always")), "production") => {
                        format!(" (Andersen thermostat at {} {})", sig(t, 4), u.temperature)
                    }
                    (_, "production") => " (NVE)".to_owned(),
                    _ => String::new(),
                };
                format!("{name} {}{bath}", span(name, *length, u.time))
            })
            .collect();
        if let Some(phase) = plan.resumed_in {
            phases.push(format!("continuing in {phase}"));
        }
        let mut items = vec![engine];
        items.extend(phases);
        wrap("  ", 2, &items);
    }

    fn phase(&mut self, name: &str, length: Stop) {
        self.phase = Some((name.to_owned(), length, Instant::now()));
        if !std::io::stderr().is_terminal() {
            return;
        }
        let total = match length {
            Stop::Events(n) => n,
            Stop::Time(_) => 1000,
        };
        let bar = ProgressBar::new(total);
        bar.set_style(
            ProgressStyle::with_template("{prefix:>13} [{bar:16}] {wide_msg}")
                .expect("a valid template")
                .progress_chars("=> "),
        );
        bar.set_prefix(name.to_owned());
        self.bar = Some(bar);
    }

    fn progress(&mut self, p: Progress) {
        if self.bar.is_none() {
            return;
        }
        if let (Some(bar), Some((position, message))) = (&self.bar, self.message(p)) {
            bar.set_position(position);
            bar.set_message(message);
        }
    }

    fn done(&mut self) {
        if let Some((_, _, started)) = self.phase.take() {
            self.last_wall = started.elapsed().as_secs_f64();
        }
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }

    fn equilibrated(&mut self, end: PhaseEnd) {
        self.equilibration = Some((end, self.last_wall));
    }
}

/// The equilibration line of a summary: its length, cost and end temperature.
fn print_equilibration(terminal: Option<&Terminal>, events: u64, what: &str, u: &UnitNames) {
    match terminal.and_then(|t| t.equilibration) {
        Some((end, wall)) => line(
            "equilibration",
            &format!(
                "{} {}, {} {what} in {}; ended at T = {} {}",
                trimmed(end.elapsed, 4),
                u.time,
                count(end.events),
                duration(wall),
                sig(end.temperature, 4),
                u.temperature
            ),
        ),
        None if events > 0 => line(
            "equilibration",
            &format!("{} {what} (before the checkpoint)", count(events)),
        ),
        None => line("equilibration", "none"),
    }
}

fn print_summary(s: &Summary, out: &Path, terminal: Option<&Terminal>) {
    let u = UnitNames::of_summary(&s.units);
    println!(
        "dmd: done: {} bodies ({}), ρ = {} {}",
        count(s.n_bodies),
        kind(&s.model),
        sig(s.density, 4),
        u.density
    );
    print_equilibration(terminal, s.equilibration_events, "events", u);
    line(
        "production",
        &format!(
            "{} {}, {} events in {} ({} CPU s, {} queue)",
            trimmed(s.sim_time, 4),
            u.time,
            count(s.events),
            duration(s.wall_seconds),
            sig(s.cpu_seconds, 3),
            s.queue
        ),
    );
    line(
        "speed",
        &format!(
            "{} events/s, {} pair events/s, {} pair events per {}",
            sig(s.events_per_second, 3),
            sig(s.pair_events_per_second, 3),
            sig(s.pair_event_rate(), 3),
            u.time
        ),
    );
    let kinds: Vec<String> = s
        .events_by_kind
        .iter()
        .filter(|(_, v)| **v > 0)
        .map(|(k, v)| format!("{k} {}", count(*v)))
        .collect();
    list("by kind", &kinds);
    line(
        "mean free time",
        &format!(
            "{} {} between pair events of a body",
            sig(s.mean_free_time, 4),
            u.time
        ),
    );
    print_thermodynamics(
        &Thermo {
            temperature: (s.temperature, s.temperature_error),
            start: s.temperature_start,
            translational: (
                s.translational_temperature,
                s.translational_temperature_error,
            ),
            rotational: s
                .rotational_temperature
                .map(|t| (t, s.rotational_temperature_error)),
            pressure: (s.pressure, s.pressure_error),
            compressibility: s.compressibility,
            of: "",
        },
        u,
    );
    line(
        "U/N",
        &format!(
            "{} {}{}",
            pm(
                s.potential_energy_per_body,
                s.potential_energy_per_body_error,
                5
            ),
            u.energy,
            if s.model.starts_with("terraced") {
                " (the terraced potential)"
            } else {
                ""
            }
        ),
    );
    if let (Some(e), Some(p)) = (s.potential_energy_per_body_smooth, s.pressure_smooth) {
        line(
            "smooth model",
            &format!(
                "U/N {} {}, P {} {} (continuous potential)",
                pm(e, s.potential_energy_per_body_smooth_error, 5),
                u.energy,
                pm(p, s.pressure_smooth_error, 5),
                u.pressure
            ),
        );
    }
    line(
        "energy",
        &format!(
            "{} → {} {} (total), relative drift {:.1e}",
            sig(s.energy_total_start, 10),
            sig(s.energy_total_end, 10),
            u.energy,
            s.relative_energy_drift
        ),
    );
    let mut checks = vec![
        format!("momentum drift {:.1e}", s.momentum_drift),
        format!("anomalies {}", count(s.anomalies)),
    ];
    if s.search.is_some() {
        checks.push(format!(
            "missed events detected {}",
            count(s.detected_misses)
        ));
    }
    if let Some(m) = s.verified_misses {
        checks.push(format!("found by the verification grid {}", count(m)));
    }
    if let Some(b) = s.bond_error {
        checks.push(format!("largest relative bond error {b:.1e}"));
    }
    list("checks", &checks);
    print_diffusion(
        (s.diffusion_msd, s.diffusion_msd_error),
        (s.diffusion_vacf, s.diffusion_vacf_error),
        u,
    );
    print_without_plateau(&s.errors_without_plateau);
    if let Some(h) = &s.hmc {
        line(
            "hmc",
            &format!(
                "{} chain{}, segments of {} {}: {} segments, acceptance {}",
                h.ensemble,
                if h.measure == "stiff-bonds" {
                    " (stiff-bond measure)"
                } else {
                    ""
                },
                plain(h.segment_time),
                u.time,
                count(h.segments),
                sig(h.acceptance_rate, 4)
            ),
        );
        let rejected = |k: &str| h.rejected_by_cause.get(k).copied().unwrap_or(0);
        line(
            "",
            &format!(
                "rejected: overlap {}, energy {}, non-finite {}; segments with a miss {}",
                count(rejected("overlap")),
                count(rejected("energy")),
                count(rejected("non_finite")),
                count(h.segments_with_misses)
            ),
        );
        line(
            "chain U/N",
            &format!(
                "{} {} (block averages), <exp(-βΔH)> = {}",
                pm(
                    h.potential_energy_per_body.mean,
                    Some(h.potential_energy_per_body.error),
                    5
                ),
                u.energy,
                sig(h.exp_minus_beta_delta_h, 6)
            ),
        );
    }
    print_wrote(out, &s.files);
}

/// The temperatures and pressure both engines report, each with its block-average error.
struct Thermo {
    temperature: (f64, Option<f64>),
    /// The temperature at the start of production.
    start: f64,
    translational: (f64, Option<f64>),
    /// Of bodies that rotate.
    rotational: Option<(f64, Option<f64>)>,
    pressure: (f64, Option<f64>),
    compressibility: f64,
    /// What the pressure is of, after its line (`" (the smooth model)"` for standard MD).
    of: &'static str,
}

/// The `temperature` and `pressure` lines of a summary.
fn print_thermodynamics(t: &Thermo, u: &UnitNames) {
    let mut temperature = vec![format!(
        "{} {} (production started at {} {})",
        pm(t.temperature.0, t.temperature.1, 5),
        u.temperature,
        sig(t.start, 5),
        u.temperature
    )];
    if let Some((rot, rot_error)) = t.rotational {
        temperature.push(format!(
            "translational {} {}",
            pm(t.translational.0, t.translational.1, 5),
            u.temperature
        ));
        temperature.push(format!(
            "rotational {} {}",
            pm(rot, rot_error, 5),
            u.temperature
        ));
    }
    list("temperature", &temperature);
    line(
        "pressure",
        &format!(
            "{} {}, Z = PV/NkT = {}{}",
            pm(t.pressure.0, t.pressure.1, 5),
            u.pressure,
            sig(t.compressibility, 4),
            t.of
        ),
    );
}

/// The diffusion coefficients a run measured.
fn print_diffusion(
    msd: (Option<f64>, Option<f64>),
    vacf: (Option<f64>, Option<f64>),
    u: &UnitNames,
) {
    let mut d = Vec::new();
    if let (Some(x), e) = msd {
        d.push(format!("{} {} (MSD)", pm(x, e, 4), u.diffusion));
    }
    if let (Some(x), e) = vacf {
        d.push(format!("{} {} (VACF)", pm(x, e, 4), u.diffusion));
    }
    if !d.is_empty() {
        list("diffusion", &d);
    }
}

/// The error bars whose blocking found no plateau: the run is shorter than a few correlation
/// times of those quantities, so their errors are lower bounds.
fn print_without_plateau(keys: &[String]) {
    if !keys.is_empty() {
        let mut items = keys.to_vec();
        items[0] = format!("lower bounds, run longer: {}", items[0]);
        list("no plateau", &items);
    }
}

/// The files written.
fn print_wrote(out: &Path, files: &[String]) {
    let mut items = vec![format!("{}/summary.json", out.display())];
    items.extend(files.iter().cloned());
    list("wrote", &items);
}

fn print_smd_summary(s: &SmdSummary, out: &Path, terminal: Option<&Terminal>) {
    let u = UnitNames::of_summary(&s.units);
    println!(
        "dmd: done (engine smd, standard MD): {} bodies ({}), ρ = {} {}",
        count(s.n_bodies),
        kind(&s.model),
        sig(s.density, 4),
        u.density
    );
    print_equilibration(terminal, s.equilibration_steps, "steps", u);
    line(
        "production",
        &format!(
            "{} {}, {} steps of dt = {} {} in {} CPU s: {} ns per body-step",
            trimmed(s.sim_time, 4),
            u.time,
            count(s.steps),
            plain(s.dt),
            u.time,
            sig(s.cpu_seconds, 3),
            sig(s.ns_per_particle_step, 3)
        ),
    );
    list(
        "neighbours",
        &[
            format!(
                "{} list builds ({} steps each)",
                count(s.neighbour_list_builds),
                sig(s.steps_per_build, 3)
            ),
            format!("skin {} {}", sig(s.skin, 4), u.length),
            format!(
                "smoothing {} to {} {}",
                sig(s.smoothing[0], 4),
                sig(s.smoothing[1], 4),
                u.length
            ),
        ],
    );
    print_thermodynamics(
        &Thermo {
            temperature: (s.temperature, Some(s.temperature_error)),
            start: s.temperature_start,
            translational: (
                s.translational_temperature,
                Some(s.translational_temperature_error),
            ),
            rotational: s
                .rotational_temperature
                .map(|t| (t, s.rotational_temperature_error)),
            pressure: (s.pressure, Some(s.pressure_error)),
            compressibility: s.compressibility,
            of: " (the smooth model)",
        },
        u,
    );
    line(
        "U/N",
        &format!(
            "{} {} (the smooth model)",
            pm(
                s.potential_energy_per_body,
                Some(s.potential_energy_per_body_error),
                5
            ),
            u.energy
        ),
    );
    line(
        "energy",
        &format!(
            "{} → {} {} (total), relative drift {:.1e}",
            sig(s.energy_total_start, 10),
            sig(s.energy_total_end, 10),
            u.energy,
            s.relative_energy_drift
        ),
    );
    list(
        "",
        &[
            format!(
                "drift {:.2e} {} per body per {}",
                s.energy_drift_per_body, u.energy, u.time
            ),
            format!("std {:.2e} {}", s.energy_total_std, u.energy),
            format!(
                "{} % of std U",
                sig(100.0 * s.energy_fluctuation_over_potential_std, 3)
            ),
        ],
    );
    print_diffusion(
        (s.diffusion_msd, s.diffusion_msd_error),
        (s.diffusion_vacf, s.diffusion_vacf_error),
        u,
    );
    print_without_plateau(&s.errors_without_plateau);
    if !s.ignored_keys.is_empty() {
        let mut keys = vec![format!(
            "ignored (event-driven only): {}",
            s.ignored_keys[0]
        )];
        keys.extend(s.ignored_keys[1..].iter().cloned());
        wrap("  ", 4, &keys);
    }
    for n in &s.notes {
        let words: Vec<&str> = n.split(' ').collect();
        let mut current = "  note:".to_owned();
        for w in words {
            if current.chars().count() + 1 + w.chars().count() > COLUMNS {
                println!("{current}");
                current = "       ".to_owned();
            }
            current.push(' ');
            current.push_str(w);
        }
        println!("{current}");
    }
    print_wrote(out, &s.files);
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check {
            scene,
            mut set,
            engine,
        } => match Scene::load(&scene, {
            set.extend(engine.map(|e| format!("engine={e}")));
            &set
        }) {
            // Everything `dmd run` refuses before its first event is refused here too.
            Ok((s, base)) => {
                let text = std::fs::read_to_string(&scene).unwrap_or_default();
                if let Err(e) = dmd_sim::run::check_setup(&s, &base, &text, &set) {
                    eprintln!("dmd: {}: {e}", scene.display());
                    return exit_code(&e);
                }
                println!(
                    "{}: a valid scene of {} bodies{}",
                    scene.display(),
                    s.n_bodies(),
                    if s.engine == Engine::Smd {
                        " for the smd engine"
                    } else {
                        ""
                    }
                );
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("dmd: {}: {e}", scene.display());
                ExitCode::from(2)
            }
        },
        Command::Run {
            scene,
            out,
            mut set,
            engine,
            quiet,
            checkpoint_every,
            threads,
            force,
            halt_after_checkpoint,
        } => {
            // The flag is the last override, so it wins over the scene's key.
            set.extend(engine.map(|e| format!("engine={e}")));
            let (s, base) = match Scene::load(&scene, &set) {
                Ok(x) => x,
                Err(e) => {
                    eprintln!("dmd: {}: {e}", scene.display());
                    return ExitCode::from(2);
                }
            };
            if s.engine == Engine::Smd && checkpoint_every.is_some() {
                eprintln!(
                    "dmd: {}: --checkpoint-every is not available with engine = \"smd\"",
                    scene.display()
                );
                return ExitCode::from(2);
            }
            let every = match checkpoint_every.as_deref().map(Every::parse).transpose() {
                Ok(e) => e,
                Err(e) => {
                    eprintln!("dmd: --checkpoint-every: {e}");
                    return ExitCode::from(2);
                }
            };
            // Every argument is checked; the folder is made ready before any work is done.
            match dmd_sim::outdir::prepare(&out, force) {
                Ok(removed) => {
                    if !removed.is_empty() && !quiet {
                        println!(
                            "dmd: removed {} file(s) of a previous run from {}",
                            removed.len(),
                            out.display()
                        );
                    }
                }
                Err(e) => {
                    eprintln!("dmd: {e}");
                    return ExitCode::from(2);
                }
            }
            if s.engine == Engine::Smd {
                return run_smd(&scene, &s, &base, &out, quiet);
            }
            let source = SceneSource {
                text: std::fs::read_to_string(&scene).unwrap_or_default(),
                overrides: set,
                base: base.clone(),
                file: scene.clone(),
            };
            if s.chains.is_some() || s.sweep.is_some() {
                // Every point is set up before the first job runs (as `dmd check` does).
                if let Err(e) =
                    dmd_sim::run::check_setup(&s, &base, &source.text, &source.overrides)
                {
                    eprintln!("dmd: {}: {e}", scene.display());
                    return exit_code(&e);
                }
                return run_ensemble(&scene, &s, source, &out, every, threads, quiet);
            }
            let options = RunOptions {
                checkpoint_every: every,
                source: Some(source),
                resume: None,
                halt_after_checkpoint,
            };
            if let Err(code) = install_signal_handlers() {
                return code;
            }
            let mut terminal = Terminal::new(&scene, &out);
            let result = if quiet {
                run_scene_with(&s, &base, Some(&out), &mut dmd_sim::run::Quiet, &options)
            } else {
                run_scene_with(&s, &base, Some(&out), &mut terminal, &options)
            };
            match result {
                Ok(summary) => finished(&summary, &out, (!quiet).then_some(&terminal)),
                Err(e) => {
                    eprintln!("dmd: {}: {e}", scene.display());
                    exit_code(&e)
                }
            }
        }
        Command::Tune {
            scene,
            target,
            out,
            mut set,
            engine,
            time,
            events,
            budget,
        } => {
            set.extend(engine.map(|e| format!("engine={e}")));
            let options = dmd_sim::tune::TuneOptions {
                target,
                overrides: set,
                time,
                events,
                wall_budget: budget,
            };
            tune(&scene, &out, &options)
        }
        Command::Resume {
            checkpoint,
            out,
            quiet,
            checkpoint_every,
            threads,
        } => {
            if checkpoint.is_dir() {
                resume_ensemble(&checkpoint, threads, quiet)
            } else {
                resume(checkpoint, out, quiet, checkpoint_every)
            }
        }
    }
}

/// `dmd tune`: the probes with a progress line on stderr, the table, the recommendation.
fn tune(scene: &Path, out: &Path, options: &dmd_sim::tune::TuneOptions) -> ExitCode {
    use dmd_sim::tune;
    eprintln!(
        "dmd tune: wall-clock budget {} (the first pass of probes always runs whole; then \
         probes are lengthened while they fit)",
        duration(options.wall_budget.unwrap_or(tune::WALL_BUDGET))
    );
    let started = std::time::Instant::now();
    let mut progress = |done: usize, total: usize, what: &str| {
        eprintln!(
            "dmd tune: [{done}/{total}] {} {what}",
            duration(started.elapsed().as_secs_f64())
        );
    };
    let result = tune::tune(scene, options, &mut progress).and_then(|t| {
        let files = t.write(out)?;
        Ok((t, files))
    });
    match result {
        Ok((t, files)) => {
            println!("dmd tune {}: {}", scene.display(), t.length);
            print!("{}", t.table());
            println!();
            print!("{}", t.recommendation());
            for f in files {
                println!("wrote {}", f.display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("dmd tune: {}: {e}", scene.display());
            if e.is_input() {
                ExitCode::from(2)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

/// `dmd run` of a scene with `engine = "smd"`.
fn run_smd(scene: &Path, s: &Scene, base: &Path, out: &Path, quiet: bool) -> ExitCode {
    let mut terminal = Terminal::new(scene, out);
    let name = scene.file_stem().map(|s| s.to_string_lossy().into_owned());
    let result = if quiet {
        smd_engine::run_named(
            s,
            base,
            Some(out),
            &mut dmd_sim::run::Quiet,
            name.as_deref(),
        )
    } else {
        smd_engine::run_named(s, base, Some(out), &mut terminal, name.as_deref())
    };
    match result {
        Ok(summary) => {
            if !quiet {
                print_smd_summary(&summary, out, Some(&terminal));
            }
            ExitCode::SUCCESS
        }
        Err(e @ dmd_sim::run::RunError::Scene(_)) => {
            eprintln!("dmd: {}: {e}", scene.display());
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("dmd: {}: {e}", scene.display());
            ExitCode::FAILURE
        }
    }
}

/// `dmd resume`: every check of the checkpoint passes before anything is written.
fn resume(path: PathBuf, out: Option<PathBuf>, quiet: bool, every: Option<String>) -> ExitCode {
    let every = match every.as_deref().map(Every::parse).transpose() {
        Ok(e) => e,
        Err(e) => {
            eprintln!("dmd: --checkpoint-every: {e}");
            return ExitCode::from(2);
        }
    };
    let c = match checkpoint::read(&path) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("dmd: {e}");
            return ExitCode::from(2);
        }
    };
    let scene = match Scene::from_str_with(&c.source.text, &c.source.overrides) {
        Ok(s) => s,
        Err(e) => {
            eprintln!(
                "dmd: checkpoint {}: its scene ({}) no longer reads: {e}",
                path.display(),
                c.source.file.display()
            );
            return ExitCode::from(2);
        }
    };
    let out = out.unwrap_or_else(|| {
        path.parent()
            .map(Path::to_owned)
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or_else(|| PathBuf::from("."))
    });
    if let Err(e) = dmd_sim::outdir::check_writable(&out) {
        eprintln!("dmd: {e}");
        return ExitCode::from(2);
    }
    let base = c.source.base.clone();
    let options = RunOptions {
        checkpoint_every: every,
        source: None,
        resume: Some((path.clone(), c)),
        halt_after_checkpoint: false,
    };
    if let Err(code) = install_signal_handlers() {
        return code;
    }
    let mut terminal = Terminal::new(&path, &out);
    let result = if quiet {
        run_scene_with(
            &scene,
            &base,
            Some(&out),
            &mut dmd_sim::run::Quiet,
            &options,
        )
    } else {
        run_scene_with(&scene, &base, Some(&out), &mut terminal, &options)
    };
    match result {
        Ok(summary) => finished(&summary, &out, (!quiet).then_some(&terminal)),
        Err(e @ dmd_sim::run::RunError::Checkpoint(_)) => {
            eprintln!("dmd: {e}");
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("dmd: {}: {e}", path.display());
            exit_code(&e)
        }
    }
}

/// SIGINT, SIGTERM and SIGHUP stop the run at a re-basing (within about 5 s) with a checkpoint; a second
/// signal ends it at once (`dmd_sim::interrupt`).
fn install_signal_handlers() -> Result<(), ExitCode> {
    dmd_sim::interrupt::install().map_err(|e| {
        eprintln!("dmd: cannot install the signal handlers: {e}");
        ExitCode::FAILURE
    })
}

/// The exit status of a failed run: 2 for what was wrong before the run started (the scene, a
/// checkpoint), 1 for a failure during the run, 130 for a run stopped by a signal
/// (docs/USER-GUIDE.md, Running).
fn exit_code(e: &dmd_sim::run::RunError) -> ExitCode {
    use dmd_sim::run::RunError;
    match e {
        RunError::Interrupted { checkpoint } => {
            if let Some(p) = checkpoint {
                eprintln!("dmd: continue the run with: dmd resume {}", p.display());
            }
            ExitCode::from(dmd_sim::interrupt::EXIT_STATUS as u8)
        }
        RunError::Scene(_) | RunError::Checkpoint(_) => ExitCode::from(2),
        RunError::Job { source, .. } => exit_code(source),
        _ => ExitCode::FAILURE,
    }
}

/// The end of a run that completed: the summary on the terminal (unless quiet, `terminal`
/// `None`), and exit status 1 if the state became non-finite (its outputs are written, for the
/// post-mortem), 0 otherwise.
fn finished(s: &Summary, out: &Path, terminal: Option<&Terminal>) -> ExitCode {
    if let Some(t) = terminal {
        print_summary(s, out, Some(t));
    }
    let energies = [
        ("energy_kinetic", s.energy_kinetic),
        ("energy_potential", s.energy_potential),
        ("energy_total_start", s.energy_total_start),
        ("energy_total_end", s.energy_total_end),
    ];
    if let Some((name, x)) = energies.iter().find(|(_, x)| !x.is_finite()) {
        eprintln!(
            "dmd: the run ended in a non-finite state: {name} = {x} (see {}/summary.json)",
            out.display()
        );
        return ExitCode::FAILURE;
    }
    if s.anomalies > 0 {
        eprintln!(
            "dmd: warning: {} anomalies (things that should not happen: {}); see anomalies in \
             docs/USER-GUIDE.md",
            s.anomalies,
            s.anomalies_by_kind
                .iter()
                .filter(|(_, n)| **n > 0)
                .map(|(k, n)| format!("{k} {n}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    ExitCode::SUCCESS
}

/// `dmd resume DIR` of chains or a sweep.
fn resume_ensemble(dir: &Path, threads: Option<usize>, quiet: bool) -> ExitCode {
    let done = |k: usize, n: usize| {
        if !quiet {
            eprintln!("dmd: {k} of {n} jobs done");
        }
    };
    match dmd_sim::chains::resume_ensemble(dir, threads, &done) {
        Ok(e) => {
            if !quiet {
                print_ensemble(&e, dir);
            }
            ExitCode::SUCCESS
        }
        Err(e @ dmd_sim::run::RunError::Checkpoint(_)) => {
            eprintln!("dmd: {e}");
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("dmd: {}: {e}", dir.display());
            ExitCode::FAILURE
        }
    }
}

/// `dmd run` of a scene with `[chains]` or `[sweep]`: the jobs in parallel, then the
/// aggregate.
fn run_ensemble(
    scene: &Path,
    s: &Scene,
    source: SceneSource,
    out: &Path,
    every: Option<Every>,
    threads: Option<usize>,
    quiet: bool,
) -> ExitCode {
    if !quiet {
        let chains = s.chains.as_ref().map_or(1, |c| c.count);
        let points = s.sweep.as_ref().map_or(1, |w| w.values.len() as u64);
        println!(
            "dmd: running {}, output in {}",
            scene.display(),
            out.display()
        );
        let sweep = s
            .sweep
            .as_ref()
            .map(|w| format!(", sweeping {} over {} values", w.key, w.values.len()))
            .unwrap_or_default();
        wrap(
            "  ",
            2,
            &[
                format!(
                    "{} jobs ({points} point(s) × {chains} chain(s)) of {} bodies{sweep}",
                    points * chains,
                    count(s.n_bodies())
                ),
                "run in parallel, each into its own folder".to_owned(),
            ],
        );
    }
    let done = |k: usize, n: usize| {
        if !quiet {
            eprintln!("dmd: {k} of {n} jobs done");
        }
    };
    match dmd_sim::chains::run_ensemble(s, &source, out, threads, every, &done) {
        Ok(e) => {
            if !quiet {
                print_ensemble(&e, out);
            }
            ExitCode::SUCCESS
        }
        Err(dmd_sim::run::RunError::Scene(e)) => {
            eprintln!("dmd: {}: {e}", scene.display());
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("dmd: {}: {e}", scene.display());
            ExitCode::FAILURE
        }
    }
}

fn print_ensemble(e: &dmd_sim::chains::Ensemble, out: &Path) {
    // The units of the jobs, from the first job's summary.
    let units = e
        .jobs
        .first()
        .and_then(|j| std::fs::read_to_string(out.join(j).join("summary.json")).ok())
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["units"].as_str().map(str::to_owned))
        .unwrap_or_default();
    let u = UnitNames::of_summary(&units);
    let rate = format!("per {}", u.time);
    println!(
        "dmd: {} point(s) × {} chain(s){}",
        e.points.len(),
        e.chains,
        e.key
            .as_ref()
            .map(|k| format!(", sweep over {k}"))
            .unwrap_or_default()
    );
    for p in &e.points {
        if let Some(v) = &p.value {
            println!("  {} = {v}", e.key.as_deref().unwrap_or("value"));
        }
        for (name, q) in &p.quantities {
            let unit = match name.as_str() {
                "temperature" => u.temperature,
                "pressure" => u.pressure,
                "potential_energy_per_body"
                | "hmc.potential_energy_per_body.mean"
                | "hmc.kinetic_energy_per_body.mean" => u.energy,
                "mean_free_time" => u.time,
                "collision_rate" => rate.as_str(),
                "diffusion_msd" | "diffusion_vacf" => u.diffusion,
                _ => "",
            };
            let line = format!("    {name:<36} {} {unit}", pm(q.mean, q.error, 6));
            println!("{}", line.trim_end());
        }
    }
    println!(
        "  wrote {}/ensemble.json, ensemble.csv and one folder per job",
        out.display()
    );
}
