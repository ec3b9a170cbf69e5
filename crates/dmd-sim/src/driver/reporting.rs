//! What every engine's run shares: why a run failed, the progress reporter, CPU time, the
//! names of the summary's units, and the observable files with their plots.

use std::path::Path;

use crate::analysis::observable::Observers;
use crate::analysis::output::{Curve, OutputError, plot_svg, write_csv};
use crate::config::scene::{SceneError, UnitSystem};
use crate::config::units::Units;
use crate::driver::checkpoint::CheckpointError;
use crate::engine::simulation::{Progress, SimError, Stop};

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scene is not acceptable.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The simulation could not go on.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// An output could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A checkpoint cannot be resumed (issue 9).
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// The standard-MD engine could not go on (issue 8).
    #[error("smd: {0}")]
    Smd(#[from] smd::SmdError),
    /// Stopped after a checkpoint, as `RunOptions::halt_after_checkpoint` asked.
    #[error("halted after writing a checkpoint, as asked")]
    Halted,
    /// Stopped by a signal ([`crate::driver::interrupt`]) at a re-basing, after saving this checkpoint
    /// (none for a run without an output folder).
    #[error("stopped by a signal{}", match .checkpoint {
        Some(p) => format!(" after saving {}", p.display()),
        None => " (no output folder: nothing saved)".to_owned(),
    })]
    Interrupted {
        /// The checkpoint written.
        checkpoint: Option<std::path::PathBuf>,
    },
    /// A job of an ensemble of chains or sweep points failed (issue 9).
    #[error("job {job}: {source}")]
    Job {
        /// The job's folder.
        job: String,
        /// Why.
        source: Box<RunError>,
    },
}

/// What a run is about to do, told to its [`Reporter`] once it is set up and before any
/// simulated time passes. Numbers are in the scene's units.
#[derive(Clone, Debug, PartialEq)]
pub struct RunPlan {
    /// `dmd` (event-driven) or `smd` (standard MD).
    pub engine: &'static str,
    /// The interaction model, as the summary's `model`.
    pub model: String,
    /// Bodies per species: name and count.
    pub species: Vec<(String, u64)>,
    /// Number of bodies.
    pub n_bodies: u64,
    /// Number density N/V.
    pub density: f64,
    /// Box edge lengths.
    pub box_lengths: [f64; 3],
    /// The temperature of the initial velocities.
    pub temperature: f64,
    /// The thermostat's temperature and the phases it acts in (`equilibration` or
    /// `always`), if the scene has one.
    pub thermostat: Option<(f64, &'static str)>,
    /// The unit system.
    pub units: UnitSystem,
    /// The phases in order, named as [`Reporter::phase`] names them (`equilibration`,
    /// `hmc equilibration`, `production`, `hmc production`), with their lengths (HMC phases
    /// count segments in `Stop::Events`).
    pub phases: Vec<(&'static str, Stop)>,
    /// The time step of the standard-MD engine.
    pub dt: Option<f64>,
    /// The run continues from a checkpoint, in this phase.
    pub resumed_in: Option<&'static str>,
}

/// How a phase ended: its length and the state it left.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseEnd {
    /// Events of the phase (steps for the standard-MD engine).
    pub events: u64,
    /// Simulated time of the phase.
    pub elapsed: f64,
    /// The kinetic temperature at its end, in the scene's unit.
    pub temperature: f64,
}

/// Receives progress reports (the `dmd` command prints what runs and draws a progress bar).
pub trait Reporter {
    /// The run is set up and about to start.
    fn start(&mut self, _plan: &RunPlan) {}
    /// A phase (`equilibration` or `production`) starts with this length.
    fn phase(&mut self, _name: &str, _length: Stop) {}
    /// Progress within the phase.
    fn progress(&mut self, _p: Progress) {}
    /// The phase ended.
    fn done(&mut self) {}
    /// The equilibration phase ended in this state (reported after [`Reporter::done`]).
    fn equilibrated(&mut self, _end: PhaseEnd) {}
}

/// A reporter that reports nothing.
pub struct Quiet;
impl Reporter for Quiet {}

/// Names of the units of a summary's `units` (`reduced` or `molecular`): `(length, time,
/// energy, temperature, pressure)`, as [`Units::names`].
pub fn unit_names(units: &str) -> [&'static str; 5] {
    let system = if units == "molecular" {
        crate::config::scene::UnitSystem::Molecular
    } else {
        crate::config::scene::UnitSystem::Reduced
    };
    Units::of(system).names()
}

/// CPU time of the calling thread, from `/proc/thread-self/schedstat` (Linux).
pub fn thread_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

pub(crate) fn write_observables(
    dir: &Path,
    obs: &mut Observers,
    plots: bool,
    units: &Units,
) -> Result<Vec<String>, OutputError> {
    let mut files = Vec::new();
    let mut table = |name: &str,
                     header: &[&str],
                     rows: Vec<Vec<f64>>,
                     plot: Option<(&str, &str, &str, Vec<Curve<'_>>)>|
     -> Result<(), OutputError> {
        let csv = format!("{name}.csv");
        write_csv(&dir.join(&csv), header, &rows)?;
        files.push(csv);
        if let (true, Some((title, xl, yl, curves))) = (plots, plot) {
            let svg = format!("{name}.svg");
            plot_svg(&dir.join(&svg), title, xl, yl, &curves)?;
            files.push(svg);
        }
        Ok(())
    };
    if let Some(rdf) = &obs.rdf {
        let t = rdf.table();
        table(
            "rdf",
            &["r", "g"],
            t.iter().map(|&(r, g)| vec![r, g]).collect(),
            Some((
                "Radial distribution function",
                "r",
                "g(r)",
                vec![Curve {
                    label: "g(r)",
                    points: t,
                }],
            )),
        )?;
    }
    if let Some(c) = &obs.correlations {
        if c.wants_msd() {
            let t = c.msd_table();
            table(
                "msd",
                &["t", "msd"],
                t.iter().map(|&(x, y)| vec![x, y]).collect(),
                Some((
                    "Mean-square displacement",
                    "t",
                    "<|r(t) - r(0)|^2>",
                    vec![Curve {
                        label: "MSD",
                        points: t,
                    }],
                )),
            )?;
        }
        if c.wants_vacf() {
            let t = c.vacf_table();
            let c0 = t.first().map(|p| p.1).unwrap_or(1.0);
            table(
                "vacf",
                &["t", "vacf", "vacf_normalised"],
                t.iter().map(|&(x, y)| vec![x, y, y / c0]).collect(),
                Some((
                    "Velocity autocorrelation (normalised)",
                    "t",
                    "<v(0).v(t)> / <v^2>",
                    vec![Curve {
                        label: "VACF",
                        points: t.iter().map(|&(x, y)| (x, y / c0)).collect(),
                    }],
                )),
            )?;
        }
        if c.wants_oacf() {
            let t = c.oacf_table();
            table(
                "oacf",
                &["t", "s0_dot_st", "p2"],
                t.iter().map(|&(x, a, b)| vec![x, a, b]).collect(),
                Some((
                    "Long-axis orientational autocorrelation",
                    "t",
                    "<s(0).s(t)>, <P2(s(0).s(t))>",
                    vec![
                        Curve {
                            label: "<s(0).s(t)>",
                            points: t.iter().map(|&(x, a, _)| (x, a)).collect(),
                        },
                        Curve {
                            label: "<P2>",
                            points: t.iter().map(|&(x, _, b)| (x, b)).collect(),
                        },
                    ],
                )),
            )?;
        }
    }
    if let Some(s) = &obs.series {
        let rows: Vec<crate::analysis::observable::SeriesRow> = s
            .rows()
            .iter()
            .map(|r| crate::analysis::observable::SeriesRow {
                time: r.time,
                kinetic: units.energy_out(r.kinetic),
                potential: units.energy_out(r.potential),
                total: units.energy_out(r.total),
                temperature: units.temperature_out(r.temperature),
                pressure: units.pressure_out(r.pressure),
            })
            .collect();
        table(
            "series",
            &[
                "t",
                "kinetic",
                "potential",
                "total",
                "temperature",
                "pressure",
            ],
            rows.iter()
                .map(|r| {
                    vec![
                        r.time,
                        r.kinetic,
                        r.potential,
                        r.total,
                        r.temperature,
                        r.pressure,
                    ]
                })
                .collect(),
            None,
        )?;
        if plots {
            let pts = |f: fn(&crate::analysis::observable::SeriesRow) -> f64| -> Vec<(f64, f64)> {
                rows.iter().map(|r| (r.time, f(r))).collect()
            };
            plot_svg(
                &dir.join("series-energy.svg"),
                "Energy",
                "t",
                "energy",
                &[
                    Curve {
                        label: "kinetic",
                        points: pts(|r| r.kinetic),
                    },
                    Curve {
                        label: "potential",
                        points: pts(|r| r.potential),
                    },
                    Curve {
                        label: "total",
                        points: pts(|r| r.total),
                    },
                ],
            )?;
            plot_svg(
                &dir.join("series-pressure.svg"),
                "Pressure (averaged over each sampling interval)",
                "t",
                "P",
                &[Curve {
                    label: "pressure",
                    points: pts(|r| r.pressure),
                }],
            )?;
            files.push("series-energy.svg".into());
            files.push("series-pressure.svg".into());
        }
    }
    if let Some(t) = obs.trajectory.take() {
        t.finish()?;
        files.push("trajectory.xyz".into());
    }
    if let Some(g) = obs.gsd.take() {
        g.finish()?;
        files.push("trajectory.gsd".into());
    }
    Ok(files)
}
