//! `dmd`: run event-driven molecular dynamics scenes.
//!
//! `dmd run SCENE.toml --out DIR [--set KEY=VALUE]...` runs a scene, shows a progress bar on a
//! terminal, prints a summary and writes `DIR/summary.json` plus the outputs the scene asks
//! for. `dmd check SCENE.toml` only reads and checks the scene.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use dmd_sim::run::{Reporter, Summary, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::simulation::{Progress, Stop};
use indicatif::{ProgressBar, ProgressStyle};

/// Event-driven molecular dynamics of spheres with hard cores, square wells and stepped
/// potentials.
#[derive(Parser)]
#[command(name = "dmd", version, about)]
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
        /// No progress bar and no summary on the terminal.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Read and check a scene (with overrides) without running it.
    Check {
        /// The scene file.
        scene: PathBuf,
        /// Override a scene key (as for `run`).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
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
    if let Some(d) = s.diffusion_msd {
        println!("  diffusion (MSD) {d:.6}");
    }
    if let Some(d) = s.diffusion_vacf {
        println!("  diffusion (VACF) {d:.6}");
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
        Command::Check { scene, set } => match Scene::load(&scene, &set) {
            Ok((s, _)) => {
                println!(
                    "{}: a valid scene of {} bodies",
                    scene.display(),
                    s.n_bodies()
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
            set,
            quiet,
        } => {
            let (s, base) = match Scene::load(&scene, &set) {
                Ok(x) => x,
                Err(e) => {
                    eprintln!("dmd: {}: {e}", scene.display());
                    return ExitCode::from(2);
                }
            };
            let mut bar = Bar {
                bar: None,
                length: None,
            };
            let result = if quiet {
                run_scene(&s, &base, Some(&out), &mut dmd_sim::run::Quiet)
            } else {
                run_scene(&s, &base, Some(&out), &mut bar)
            };
            match result {
                Ok(summary) => {
                    if !quiet {
                        print_summary(&summary, &out);
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("dmd: {}: {e}", scene.display());
                    ExitCode::FAILURE
                }
            }
        }
    }
}
