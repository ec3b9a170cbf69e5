//! What every engine's run shares: why a run failed, the progress reporter, CPU time, the
//! names of the summary's units, and the observable files with their plots.

use std::path::Path;

use crate::analysis::observable::{Observers, msd_fit};
use crate::analysis::output::{Line, Mean, OutputError, Plot, write_csv, write_plot};
use crate::config::scene::{SceneError, UnitSystem};
use crate::config::units::{UnitNames, Units};
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
    /// A checkpoint cannot be resumed.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// The standard-MD engine could not go on.
    #[error("smd: {0}")]
    Smd(#[from] smd::SmdError),
    /// Stopped after a checkpoint, as `RunOptions::halt_after_checkpoint` asked.
    #[error("halted after writing a checkpoint, as asked")]
    Halted,
    /// Stopped after the set-up, as the set-up check of `dmd check` asks (nothing ran).
    #[error("stopped after the set-up, as asked")]
    SetUpOnly,
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
    /// A job of an ensemble of chains or sweep points failed.
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
    /// A flag that stops the run when raised (from [`Reporter::progress`] or another thread):
    /// the run then ends with `RunError::Sim(SimError::Cancelled)` between two events, nothing
    /// saved. `None` (the default): only the end of the run or a signal stops it.
    fn cancel_flag(&self) -> Option<std::sync::Arc<std::sync::atomic::AtomicBool>> {
        None
    }
}

/// A reporter that reports nothing.
pub struct Quiet;
impl Reporter for Quiet {}

/// CPU time of the calling thread, from `/proc/thread-self/schedstat` (Linux).
pub fn thread_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// What the plots of a run say besides their data: the system named in every caption, and the
/// production means with their block-average errors drawn over the series. Numbers are in the
/// scene's units (as the summary's).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct PlotInfo {
    /// The scene's name (its file's stem), when the run knows it.
    pub scene: Option<String>,
    /// Bodies.
    pub n: u64,
    /// Mean kinetic temperature of production.
    pub temperature: f64,
    /// Number density N/V (per length³).
    pub density: f64,
    /// The terrace step ΔV (energy) of a terraced run whose pairs share one.
    pub terrace_step: Option<f64>,
    /// Species names, in the scene's order.
    pub species: Vec<String>,
    /// Mean pressure of production and its error.
    pub pressure: (f64, Option<f64>),
    /// Mean potential energy per body of production and its error.
    pub potential_per_body: (f64, Option<f64>),
}

impl PlotInfo {
    /// The system, with its scene and the units in `names`: `rods-paper: N = 512, T = 530.5 K,
    /// ρ = 0.01789 Å⁻³, ΔV = 2.1 kJ/mol`.
    fn caption(&self, names: &UnitNames) -> String {
        let mut text = match &self.scene {
            Some(s) => format!("{s}: "),
            None => String::new(),
        };
        text.push_str(&format!(
            "N = {}, T = {} {}, ρ = {} {}",
            self.n,
            sig(self.temperature),
            names.temperature,
            sig(self.density),
            names.density
        ));
        if let Some(dv) = self.terrace_step {
            text.push_str(&format!(", ΔV = {} {}", sig(dv), names.energy));
        }
        if names.reduced {
            text.push_str(" (reduced units)");
        }
        text
    }
}

/// The terrace step ΔV (scene energy unit) of a scene in internal units whose terraced pairs
/// all have the same evenly spaced terraces (`step` or `step_kt`); none otherwise.
pub(crate) fn terrace_step(scene: &crate::config::scene::Scene, units: &Units) -> Option<f64> {
    let kt = scene.init.temperature;
    let mut steps = scene
        .pair
        .iter()
        .filter_map(|p| p.terraces.as_ref())
        .map(|t| t.step.or(t.step_kt.map(|x| x * kt)));
    let first = steps.next()??;
    steps
        .all(|s| s == Some(first))
        .then(|| units.energy_out(first))
}

/// `x` with four significant digits (`530.5`, `0.01789`, `1312`), in e-notation when very
/// large or small.
fn sig(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    // Rounded to four digits first, so that 0.99999 is `1.000`, not `1.0000`.
    let x: f64 = format!("{x:.3e}").parse().unwrap_or(x);
    let mag = x.abs().log10().floor();
    if !(-4.0..6.0).contains(&mag) {
        return format!("{x:.3e}");
    }
    let decimals = (3.0 - mag).max(0.0) as usize;
    format!("{x:.decimals$}")
}

/// The legend of a mean: `mean 1207 ± 30 bar`, the error to two significant digits and the
/// mean to the same decimals (four significant digits when the error is below a millionth of
/// it, `mean 4.491 ± 1.2e-15 kJ/mol`).
fn mean_label(value: f64, error: Option<f64>, unit: &str) -> String {
    match error.filter(|e| e.is_finite() && *e > 0.0) {
        Some(e) if e < 1e-6 * value.abs() => format!("mean {} ± {e:.1e} {unit}", sig(value)),
        Some(e) => {
            let decimals = (1.0 - e.log10().floor()).clamp(0.0, 12.0) as usize;
            format!("mean {value:.decimals$} ± {e:.decimals$} {unit}")
        }
        None => format!("mean {} {unit}", sig(value)),
    }
}

/// The mean of the finite values of `x` and, with 16 or more, its block-average error.
fn block_mean(x: &[f64]) -> Option<(f64, Option<f64>)> {
    let finite: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return None;
    }
    let b = crate::analysis::block::block_average(&finite);
    Some((b.mean, b.error.is_finite().then_some(b.error)))
}

/// One observable's table, as its CSV file holds it: `rdf`, `rdf-sites`, `msd`, `vacf`, `oacf`
/// or `series`,
/// its column names and its rows (in the scene's units).
#[derive(Clone, Debug, PartialEq)]
pub struct ObservableTable {
    /// The file's stem (`rdf` for `rdf.csv`).
    pub name: String,
    /// The column names (the CSV header).
    pub columns: Vec<String>,
    /// The rows, one number per column.
    pub rows: Vec<Vec<f64>>,
}

/// Writes the observables' CSV files and, with `plots`, their SVG plots (axes in the units of
/// `units`, captions and means from `info`); returns the names of the files written.
pub(crate) fn write_observables(
    dir: &Path,
    obs: &mut Observers,
    plots: bool,
    units: &Units,
    info: &PlotInfo,
) -> Result<Vec<String>, OutputError> {
    observables(Some(dir), obs, plots, units, info, &mut Vec::new())
}

/// The observables' tables, the numbers [`write_observables`] writes, without writing anything.
///
/// # Errors
/// [`OutputError`] if the series' stream cannot be flushed or read back.
pub(crate) fn observable_tables(
    obs: &mut Observers,
    units: &Units,
    info: &PlotInfo,
) -> Result<Vec<ObservableTable>, OutputError> {
    let mut tables = Vec::new();
    observables(None, obs, false, units, info, &mut tables)?;
    Ok(tables)
}

/// [`write_observables`] into `dir` (with `None`: no file, no plot, the trajectories left
/// open), handing every table to `tables` too.
fn observables(
    dir: Option<&Path>,
    obs: &mut Observers,
    plots: bool,
    units: &Units,
    info: &PlotInfo,
    tables: &mut Vec<ObservableTable>,
) -> Result<Vec<String>, OutputError> {
    let mut files = Vec::new();
    let au = units.names();
    let caption = info.caption(au);
    let plot = |title: &str, x: String, y: String, curves: Vec<Line>| Plot {
        title: title.to_owned(),
        caption: caption.clone(),
        x_label: x,
        y_label: y,
        lines: curves,
    };
    let mut table = |name: &str,
                     header: &[String],
                     rows: Vec<Vec<f64>>,
                     plot: Option<Plot>|
     -> Result<(), OutputError> {
        let Some(dir) = dir else {
            tables.push(ObservableTable {
                name: name.to_owned(),
                columns: header.to_vec(),
                rows,
            });
            return Ok(());
        };
        let csv = format!("{name}.csv");
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        write_csv(&dir.join(&csv), &header, &rows)?;
        files.push(csv);
        if let (true, Some(p)) = (plots, plot) {
            let svg = format!("{name}.svg");
            write_plot(&dir.join(&svg), &p)?;
            if dir.join(&svg).exists() {
                files.push(svg);
            }
        }
        Ok(())
    };
    let strings = |h: &[&str]| -> Vec<String> { h.iter().map(|s| (*s).to_owned()).collect() };
    if let Some(rdf) = &obs.rdf {
        let t = rdf.table();
        let partials = rdf.partials();
        let name = |k: usize| {
            info.species
                .get(k)
                .cloned()
                .unwrap_or_else(|| format!("species{k}"))
        };
        let mut header = strings(&["r", "g", "g_error"]);
        let mut rows: Vec<Vec<f64>> = t
            .iter()
            .zip(rdf.errors())
            .map(|(&(r, g), e)| vec![r, g, e])
            .collect();
        let mut curves = vec![
            Line::new(
                if partials.is_empty() {
                    String::new()
                } else {
                    "g(r), all pairs".to_owned()
                },
                t,
            )
            .with_errors(rdf.errors()),
        ];
        for p in partials {
            header.push(format!("g_{}_{}", name(p.a), name(p.b)));
            header.push(format!("g_{}_{}_error", name(p.a), name(p.b)));
            for ((row, &(_, g)), &e) in rows.iter_mut().zip(&p.rows).zip(&p.errors) {
                row.push(g);
                row.push(e);
            }
            curves.push(Line::new(format!("g {}–{}", name(p.a), name(p.b)), p.rows));
        }
        table(
            "rdf",
            &header,
            rows,
            Some(plot(
                "Radial distribution function",
                format!("r ({})", au.length),
                "g(r)".to_owned(),
                curves,
            )),
        )?;
        // The site–site g(r) of molecules with named sites, in a file of its own: rdf.csv
        // keeps the centres, and the sites' names cannot clash with its species' columns.
        if let Some(sites) = rdf.sites() {
            let partials = sites.partials();
            let mut header = strings(&["r"]);
            let mut rows: Vec<Vec<f64>> = partials
                .first()
                .map_or(&[][..], |p| &p.rows[..])
                .iter()
                .map(|&(r, _)| vec![r])
                .collect();
            let mut curves = Vec::new();
            for p in partials {
                header.push(format!("g_{}_{}", p.a, p.b));
                header.push(format!("g_{}_{}_error", p.a, p.b));
                for ((row, &(_, g)), &e) in rows.iter_mut().zip(&p.rows).zip(&p.errors) {
                    row.push(g);
                    row.push(e);
                }
                curves.push(Line::new(format!("g {}–{}", p.a, p.b), p.rows).with_errors(p.errors));
            }
            table(
                "rdf-sites",
                &header,
                rows,
                Some(plot(
                    "Site–site radial distribution functions",
                    format!("r ({})", au.length),
                    "g(r)".to_owned(),
                    curves,
                )),
            )?;
        }
    }
    if let Some(c) = &obs.correlations {
        if c.wants_msd() {
            let t = c.msd_table();
            let mut curves =
                vec![Line::new("⟨|r(t) − r(0)|²⟩", t.clone()).with_errors(c.msd_errors())];
            if let Some((a, b)) = msd_fit(&t) {
                let from = t[t.len() / 2].0;
                let to = t.last().map_or(from, |p| p.0);
                curves.push(Line {
                    label: format!("fit 6Dt + c: D = {} {}", sig(b / 6.0), au.diffusion),
                    points: vec![(from, a + b * from), (to, a + b * to)],
                    dashed: true,
                    mean: None,
                    errors: Vec::new(),
                });
            }
            table(
                "msd",
                &strings(&["t", "msd", "msd_error"]),
                t.iter()
                    .zip(c.msd_errors())
                    .map(|(&(x, y), e)| vec![x, y, e])
                    .collect(),
                Some(plot(
                    "Mean-square displacement",
                    format!("t ({})", au.time),
                    format!("MSD ({})", au.area),
                    curves,
                )),
            )?;
        }
        if c.wants_vacf() {
            let t = c.vacf_table();
            let c0 = t.first().map(|p| p.1).unwrap_or(1.0);
            table(
                "vacf",
                &strings(&[
                    "t",
                    "vacf",
                    "vacf_error",
                    "vacf_normalised",
                    "vacf_normalised_error",
                ]),
                t.iter()
                    .zip(c.vacf_errors())
                    .map(|(&(x, y), e)| vec![x, y, e, y / c0, e / c0])
                    .collect(),
                Some(plot(
                    "Velocity autocorrelation (normalised)",
                    format!("t ({})", au.time),
                    "⟨v(0)·v(t)⟩ / ⟨v²⟩ (dimensionless)".to_owned(),
                    vec![
                        Line::new(
                            match c.diffusion_from_vacf() {
                                Some(d) => format!(
                                    "⟨v²⟩ = {} {}, Green–Kubo D = {} {}",
                                    sig(c0),
                                    au.speed_squared,
                                    sig(d),
                                    au.diffusion
                                ),
                                None => format!("⟨v²⟩ = {} {}", sig(c0), au.speed_squared),
                            },
                            t.iter().map(|&(x, y)| (x, y / c0)).collect(),
                        )
                        .with_errors(c.vacf_errors().iter().map(|e| e / c0).collect()),
                    ],
                )),
            )?;
        }
        if c.wants_oacf() {
            let t = c.oacf_table();
            table(
                "oacf",
                &strings(&["t", "s0_dot_st", "s0_dot_st_error", "p2", "p2_error"]),
                t.iter()
                    .zip(c.oacf_errors())
                    .map(|(&(x, a, b), (ea, eb))| vec![x, a, ea, b, eb])
                    .collect(),
                Some(plot(
                    "Long-axis orientational autocorrelation",
                    format!("t ({})", au.time),
                    "correlation (dimensionless)".to_owned(),
                    {
                        let errors = c.oacf_errors();
                        vec![
                            Line::new("⟨s(0)·s(t)⟩", t.iter().map(|&(x, a, _)| (x, a)).collect())
                                .with_errors(errors.iter().map(|e| e.0).collect()),
                            Line::new(
                                "⟨P₂(s(0)·s(t))⟩",
                                t.iter().map(|&(x, _, b)| (x, b)).collect(),
                            )
                            .with_errors(errors.iter().map(|e| e.1).collect()),
                        ]
                    },
                )),
            )?;
        }
    }
    // Without a folder nothing is written: the series' rows (held, or read back from its
    // stream) are handed over as a table, and the trajectories are left open.
    let Some(dir) = dir else {
        if let Some(s) = obs.series.as_mut() {
            tables.push(ObservableTable {
                name: "series".to_owned(),
                columns: strings(&crate::analysis::observable::SERIES_HEADER),
                rows: s.table()?,
            });
        }
        return Ok(files);
    };
    // `series.csv` was written as the run went; the plots read it back.
    if let Some(path) = obs.series.take().map(|s| s.finish()).transpose()?.flatten() {
        files.push("series.csv".into());
        let rows = if plots {
            read_series(&path)?
        } else {
            Vec::new()
        };
        if plots {
            let x_label = format!("t ({})", au.time);
            if let Some(p) = energy_plot(&rows, info, au) {
                let p = plot(p.0, x_label.clone(), p.1, p.2);
                let path = dir.join("series-energy.svg");
                write_plot(&path, &p)?;
                if path.exists() {
                    files.push("series-energy.svg".into());
                }
            }
            let (mean, error) = info.pressure;
            let p = plot(
                "Pressure",
                x_label,
                format!("P ({})", au.pressure),
                vec![Line {
                    label: "P over each sampling interval".to_owned(),
                    points: rows.iter().map(|r| (r.time, r.pressure)).collect(),
                    dashed: false,
                    mean: Some(Mean {
                        label: mean_label(mean, error, au.pressure),
                        value: mean,
                        error,
                    }),
                    errors: Vec::new(),
                }],
            );
            let path = dir.join("series-pressure.svg");
            write_plot(&path, &p)?;
            if path.exists() {
                files.push("series-pressure.svg".into());
            }
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

/// The rows of a finished `series.csv` (numbers in the scene's units), for its plots: at most
/// [`PLOTTED_ROWS`], every k-th row of a longer series (a plot draws no more).
fn read_series(path: &Path) -> Result<Vec<crate::analysis::observable::SeriesRow>, OutputError> {
    use std::io::BufRead;
    let bad = |e: &dyn std::fmt::Display| OutputError {
        path: path.to_owned(),
        message: format!("cannot read back the series for its plots: {e}"),
    };
    let lines = || -> Result<_, OutputError> {
        let f = std::fs::File::open(path).map_err(|e| bad(&e))?;
        Ok(std::io::BufReader::new(f).lines().skip(1))
    };
    let count = lines()?.count();
    let stride = count.div_ceil(PLOTTED_ROWS).max(1);
    let mut rows = Vec::with_capacity(count.min(PLOTTED_ROWS));
    for line in lines()?.step_by(stride) {
        let line = line.map_err(|e| bad(&e))?;
        let x: Vec<f64> = line
            .split(',')
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|e| bad(&e))?;
        let [time, kinetic, potential, total, temperature, pressure] = x[..] else {
            return Err(bad(&format!("a row of {} numbers", x.len())));
        };
        rows.push(crate::analysis::observable::SeriesRow {
            time,
            kinetic,
            potential,
            total,
            temperature,
            pressure,
        });
    }
    Ok(rows)
}

/// The most rows of `series.csv` its plots draw.
const PLOTTED_ROWS: usize = 100_000;

/// The energy plot of a series (rows in the scene's units): `K/N`, `U/N` and `E/N` with their
/// production means and errors (`U/N`'s from `info`, the others block averages of the rows),
/// as `(title, y label, curves)`. A run whose potential energy is zero at every sample has
/// only `K/N` (then equal to `E/N`), and no plot at all when that is constant (hard spheres
/// without a thermostat in production: a flat line).
fn energy_plot(
    rows: &[crate::analysis::observable::SeriesRow],
    info: &PlotInfo,
    au: &UnitNames,
) -> Option<(&'static str, String, Vec<Line>)> {
    let n = info.n.max(1) as f64;
    let column = |f: fn(&crate::analysis::observable::SeriesRow) -> f64| -> Vec<f64> {
        rows.iter().map(|r| f(r) / n).collect()
    };
    let curve = |label: &str, values: Vec<f64>, mean: Option<(f64, Option<f64>)>| Line {
        label: label.to_owned(),
        points: rows.iter().map(|r| r.time).zip(values).collect(),
        dashed: false,
        mean: mean.map(|(value, error)| Mean {
            label: mean_label(value, error, au.energy),
            value,
            error,
        }),
        errors: Vec::new(),
    };
    let kinetic = column(|r| r.kinetic);
    let no_potential = rows.iter().all(|r| r.potential == 0.0);
    if no_potential {
        let (lo, hi) = kinetic
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let spread = hi - lo;
        if spread.is_nan() || spread <= 1e-9 * hi.abs().max(lo.abs()) {
            return None;
        }
        let mean = block_mean(&kinetic);
        return Some((
            "Kinetic energy per body (no potential energy)",
            format!("K/N ({})", au.energy),
            vec![curve("K/N", kinetic, mean)],
        ));
    }
    let potential = column(|r| r.potential);
    let total = column(|r| r.total);
    let (km, tm) = (block_mean(&kinetic), block_mean(&total));
    Some((
        "Energy per body",
        format!("energy per body ({})", au.energy),
        vec![
            curve("K/N", kinetic, km),
            curve("U/N", potential, Some(info.potential_per_body)),
            curve("E/N", total, tm),
        ],
    ))
}

#[cfg(test)]
mod plot_tests {
    use super::*;

    #[test]
    fn captions_and_legends_round_their_numbers() {
        assert_eq!(sig(530.539), "530.5");
        assert_eq!(sig(0.017_885_380_6), "0.01789");
        assert_eq!(sig(0.99999), "1.000");
        assert_eq!(sig(1312.07), "1312");
        assert_eq!(mean_label(1179.3, Some(25.4), "bar"), "mean 1179 ± 25 bar");
        assert_eq!(
            mean_label(10.4771, Some(0.01432), "kJ/mol"),
            "mean 10.477 ± 0.014 kJ/mol"
        );
        assert_eq!(
            mean_label(4.458, Some(2.8e-15), "kJ/mol"),
            "mean 4.458 ± 2.8e-15 kJ/mol"
        );
        assert_eq!(mean_label(8.7812, None, "ε/σ³"), "mean 8.781 ε/σ³");
    }

    #[test]
    fn the_msd_fit_recovers_the_slope_of_the_straight_tail() {
        // MSD = 6 D t + c with D = 0.25 beyond a ballistic start.
        let t: Vec<(f64, f64)> = (0..40)
            .map(|k| {
                let t = 0.1 * k as f64;
                (t, if t < 1.0 { 3.0 * t * t } else { 1.5 * t + 1.5 })
            })
            .collect();
        let (a, b) = msd_fit(&t).unwrap();
        assert!(
            (b / 6.0 - 0.25).abs() < 1e-12 && (a - 1.5).abs() < 1e-12,
            "{a} {b}"
        );
    }
}
