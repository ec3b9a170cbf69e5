//! `dmd`: run event-driven molecular dynamics scenes.
//!
//! `dmd run SCENE.toml --out DIR [--set KEY=VALUE]...` runs a scene, shows a progress bar on a
//! terminal, prints a summary and writes `DIR/summary.json` plus the outputs the scene asks
//! for. `dmd check SCENE.toml` only reads and checks the scene. `dmd run --checkpoint-every`
//! saves `DIR/checkpoint.dmd` from time to time, and `dmd resume CHECKPOINT` continues such a
//! run bit for bit; a scene with `[chains]` or `[sweep]` runs its jobs in parallel (issue 9).
//! Every argument and the output folder are checked before the run (exit status 2); a folder
//! holding another run's files needs `--force`.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use dmd_sim::checkpoint::{self, Every, SceneSource};
use dmd_sim::run::{Reporter, RunOptions, Summary, run_scene_with};
use dmd_sim::scene::Scene;
use dmd_sim::simulation::{Progress, Stop};
use dmd_sim::smd_engine::{self, Engine, SmdSummary};
use indicatif::{ProgressBar, ProgressStyle};

/// The `dmd` command.
#[derive(Parser)]
#[command(
    name = "dmd",
    version,
    about = "Event-driven (discontinuous) molecular dynamics: hard and stepped spheres, rods and \
             rigid bodies of any shape on terraced smooth potentials (SSD/E water among them), \
             rigid and semi-flexible site molecules; standard MD on the same smooth potentials \
             with --engine smd. Scenes are TOML files, described key by key in \
             docs/USER-GUIDE.md."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write DIR/summary.json and the requested outputs.
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
        /// No progress bar and no summary on the terminal.
        #[arg(long, short)]
        quiet: bool,
        /// Save DIR/checkpoint.dmd this often: a number of events (1e7) or a wall-clock time
        /// (90s, 10m, 2h); saved at the next re-basing of the time origin (HMC: between
        /// segments). `dmd resume` continues the run.
        #[arg(long, value_name = "EVENTS|TIME")]
        checkpoint_every: Option<String>,
        /// Threads for the jobs of a scene with `[chains]` or `[sweep]` (default: all cores).
        /// Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
        /// Replace the files of a previous run in the output folder (only files dmd writes
        /// are removed); without it such a folder is refused.
        #[arg(long)]
        force: bool,
        /// Stop right after the first checkpoint, as a crash would (tests of `dmd resume`).
        #[arg(long, hide = true)]
        halt_after_checkpoint: bool,
    },
    /// Continue a run from its checkpoint (written by `dmd run --checkpoint-every`), or finish
    /// the chains or sweep whose output folder is given.
    Resume {
        /// The checkpoint file, or the output folder of a scene with `[chains]` or `[sweep]`.
        checkpoint: PathBuf,
        /// Output folder (default: the checkpoint's folder).
        #[arg(long, short)]
        out: Option<PathBuf>,
        /// No progress bar and no summary on the terminal.
        #[arg(long, short)]
        quiet: bool,
        /// Change the checkpoint interval (default: the saved one).
        #[arg(long, value_name = "EVENTS|TIME")]
        checkpoint_every: Option<String>,
        /// Threads for the jobs of chains or a sweep (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Read and check a scene (with overrides) without running it.
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

/// A progress bar on a terminal; nothing otherwise.
struct Bar {
    bar: Option<ProgressBar>,
    length: Option<Stop>,
}

impl Reporter for Bar {
    fn phase(&mut self, name: &str, length: Stop) {
        self.length = Some(length);
        if !std::io::stderr().is_terminal() {
            return;
        }
        let total = match length {
            Stop::Events(n) => n,
            Stop::Time(_) => 1000,
        };
        let bar = ProgressBar::new(total);
        let unit = match length {
            // HMC phases count segments (issue 9).
            Stop::Events(_) if name.starts_with("hmc") => "segments",
            Stop::Events(_) => "events",
            Stop::Time(_) => "‰ of the time",
        };
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{{prefix:>13}} [{{bar:40}}] {{human_pos}}/{{human_len}} {unit} ({{rate}}, eta {{eta}})"
            ))
            .expect("a valid template")
            .with_key(
                "rate",
                |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                    let _ = write!(w, "{:.3e}/s", state.per_sec());
                },
            )
            .progress_chars("=> "),
        );
        bar.set_prefix(name.to_owned());
        self.bar = Some(bar);
    }

    fn progress(&mut self, p: Progress) {
        if let (Some(bar), Some(length)) = (&self.bar, self.length) {
            match length {
                Stop::Events(_) => bar.set_position(p.events),
                Stop::Time(t) => bar.set_position(((p.elapsed / t) * 1000.0) as u64),
            }
        }
    }

    fn done(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

fn print_summary(s: &Summary, out: &std::path::Path) {
    println!(
        "dmd: {} bodies ({}), density {:.6}, queue {}",
        s.n_bodies, s.model, s.density, s.queue
    );
    println!(
        "  events        {} in {:.3} s: {:.4e} events/s, {:.4e} pair events/s",
        s.events, s.wall_seconds, s.events_per_second, s.pair_events_per_second
    );
    let kinds: Vec<String> = s
        .events_by_kind
        .iter()
        .filter(|(_, v)| **v > 0)
        .map(|(k, v)| format!("{k} {v}"))
        .collect();
    println!("  by kind       {}", kinds.join(", "));
    println!(
        "  sim time      {:.6}   mean free time {:.6e}",
        s.sim_time, s.mean_free_time
    );
    println!(
        "  temperature   {:.6}   pressure {:.6} (Z = {:.6})",
        s.temperature, s.pressure, s.compressibility
    );
    println!(
        "  energy        {:.12e} -> {:.12e} (relative drift {:.2e}), U/N {:.6}",
        s.energy_total_start,
        s.energy_total_end,
        s.relative_energy_drift,
        s.potential_energy_per_body
    );
    println!(
        "  momentum drift {:.2e}   anomalies {}",
        s.momentum_drift, s.anomalies
    );
    print_estimates(s);
    if let Some(d) = s.diffusion_msd {
        println!("  diffusion (MSD) {d:.6}");
    }
    if let Some(d) = s.diffusion_vacf {
        println!("  diffusion (VACF) {d:.6}");
    }
    if let Some(h) = &s.hmc {
        println!(
            "  hmc           {} τ = {}, {} segments, acceptance {:.4} (rejected: overlap {}, energy {}, non-finite {}), segments with a miss {}",
            h.ensemble,
            h.segment_time,
            h.segments,
            h.acceptance_rate,
            h.rejected_by_cause.get("overlap").copied().unwrap_or(0),
            h.rejected_by_cause.get("energy").copied().unwrap_or(0),
            h.rejected_by_cause.get("non_finite").copied().unwrap_or(0),
            h.segments_with_misses
        );
        println!(
            "  chain U/N     {:.6} ± {:.6} (block averages), <exp(-βΔH)> {:.6}",
            h.potential_energy_per_body.mean,
            h.potential_energy_per_body.error,
            h.exp_minus_beta_delta_h
        );
    }
    println!(
        "  wrote {}/summary.json{}",
        out.display(),
        if s.files.is_empty() {
            String::new()
        } else {
            format!(" and {}", s.files.join(", "))
        }
    );
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
            Ok((s, _)) => {
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
            if s.smd.is_some() && !quiet {
                println!(
                    "dmd: note: the event-driven engine uses only [smd] smoothing (for the smooth \
                     estimators)"
                );
            }
            let source = SceneSource {
                text: std::fs::read_to_string(&scene).unwrap_or_default(),
                overrides: set,
                base: base.clone(),
                file: scene.clone(),
            };
            if s.chains.is_some() || s.sweep.is_some() {
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
            let mut bar = Bar {
                bar: None,
                length: None,
            };
            let result = if quiet {
                run_scene_with(&s, &base, Some(&out), &mut dmd_sim::run::Quiet, &options)
            } else {
                run_scene_with(&s, &base, Some(&out), &mut bar, &options)
            };
            match result {
                Ok(summary) => finished(&summary, &out, quiet),
                Err(e) => {
                    eprintln!("dmd: {}: {e}", scene.display());
                    exit_code(&e)
                }
            }
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

/// `dmd run` of a scene with `engine = "smd"`.
fn run_smd(
    scene: &std::path::Path,
    s: &Scene,
    base: &std::path::Path,
    out: &std::path::Path,
    quiet: bool,
) -> ExitCode {
    let mut bar = Bar {
        bar: None,
        length: None,
    };
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
        smd_engine::run_named(s, base, Some(out), &mut bar, name.as_deref())
    };
    match result {
        Ok(summary) => {
            if !quiet {
                print_smd_summary(&summary, out);
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

/// Production temperature and the smooth estimators with error bars and units (lines printed
/// only for what the run measured).
fn print_estimates(s: &Summary) {
    let [_, _, e, t, p] = dmd_sim::run::unit_names(&s.units);
    let pm = |x: Option<f64>| x.map_or(String::new(), |x| format!(" ± {x:.3}"));
    println!(
        "  production    T {:.3}{} {t} (started at {:.6} {t}), U/N {:.4}{} {e}, P {:.3}{} {p}",
        s.temperature,
        pm(s.temperature_error),
        s.temperature_start,
        s.potential_energy_per_body,
        pm(s.potential_energy_per_body_error),
        s.pressure,
        pm(s.pressure_error)
    );
    if let (Some(u), Some(pr)) = (s.potential_energy_per_body_smooth, s.pressure_smooth) {
        println!(
            "  smooth model  U/N {u:.4}{} {e}, P {pr:.3}{} {p} (the continuous potential at the samples)",
            pm(s.potential_energy_per_body_smooth_error),
            pm(s.pressure_smooth_error)
        );
    }
}

fn print_smd_summary(s: &SmdSummary, out: &std::path::Path) {
    println!(
        "dmd (engine smd): {} bodies ({}), density {:.6}",
        s.n_bodies, s.model, s.density
    );
    println!(
        "  steps         {} of dt = {:.6e} ({} equilibration) in {:.3} s: {:.1} ns per particle-step",
        s.steps, s.dt, s.equilibration_steps, s.cpu_seconds, s.ns_per_particle_step
    );
    println!(
        "  sim time      {:.6}   neighbour lists {} ({:.1} steps each, skin {:.4}), smoothing {:?}",
        s.sim_time, s.neighbour_list_builds, s.steps_per_build, s.skin, s.smoothing
    );
    println!(
        "  temperature   {:.6} ± {:.6}   pressure {:.6} ± {:.6} (Z = {:.6})",
        s.temperature, s.temperature_error, s.pressure, s.pressure_error, s.compressibility
    );
    let [_, _, e, t, p] = dmd_sim::run::unit_names(&s.units);
    println!(
        "  production    started at T {:.6} {t}; U/N {:.4} ± {:.4} {e}, P {:.3} ± {:.3} {p} (the smooth model)",
        s.temperature_start,
        s.potential_energy_per_body_smooth,
        s.potential_energy_per_body_smooth_error,
        s.pressure_smooth,
        s.pressure_smooth_error
    );
    println!(
        "  energy        {:.12e} -> {:.12e} (relative drift {:.2e}), U/N {:.6}",
        s.energy_total_start,
        s.energy_total_end,
        s.relative_energy_drift,
        s.potential_energy_per_body
    );
    println!(
        "  energy drift  {:.3e} per body per unit time, std {:.3e} ({:.3} of std U)",
        s.energy_drift_per_body, s.energy_total_std, s.energy_fluctuation_over_potential_std
    );
    if let Some(d) = s.diffusion_msd {
        println!("  diffusion (MSD) {d:.6}");
    }
    if let Some(d) = s.diffusion_vacf {
        println!("  diffusion (VACF) {d:.6}");
    }
    if !s.ignored_keys.is_empty() {
        println!(
            "  ignored (event-driven only): {}",
            s.ignored_keys.join(", ")
        );
    }
    for n in &s.notes {
        println!("  note: {n}");
    }
    println!(
        "  wrote {}/summary.json{}",
        out.display(),
        if s.files.is_empty() {
            String::new()
        } else {
            format!(" and {}", s.files.join(", "))
        }
    );
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
            .map(std::path::Path::to_owned)
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
    let mut bar = Bar {
        bar: None,
        length: None,
    };
    let result = if quiet {
        run_scene_with(
            &scene,
            &base,
            Some(&out),
            &mut dmd_sim::run::Quiet,
            &options,
        )
    } else {
        run_scene_with(&scene, &base, Some(&out), &mut bar, &options)
    };
    match result {
        Ok(summary) => finished(&summary, &out, quiet),
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

/// SIGINT, SIGTERM and SIGHUP stop the run at its next re-basing with a checkpoint; a second
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

/// The end of a run that completed: the summary on the terminal, and exit status 1 if the
/// state became non-finite (its outputs are written, for the post-mortem), 0 otherwise.
fn finished(s: &Summary, out: &std::path::Path, quiet: bool) -> ExitCode {
    if !quiet {
        print_summary(s, out);
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
fn resume_ensemble(dir: &std::path::Path, threads: Option<usize>, quiet: bool) -> ExitCode {
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
    scene: &std::path::Path,
    s: &Scene,
    source: SceneSource,
    out: &std::path::Path,
    every: Option<Every>,
    threads: Option<usize>,
    quiet: bool,
) -> ExitCode {
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

fn print_ensemble(e: &dmd_sim::chains::Ensemble, out: &std::path::Path) {
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
            match q.error {
                Some(err) => println!("    {name:<36} {:.6} ± {err:.6}", q.mean),
                None => println!("    {name:<36} {:.6}", q.mean),
            }
        }
    }
    println!(
        "  wrote {}/ensemble.json, ensemble.csv and one folder per job",
        out.display()
    );
}
