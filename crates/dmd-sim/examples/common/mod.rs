//! What the rods validations share (`validate_compare`, `validate_frontier`, `validate_rods`): the
//! paper's scene and its gas, scene runs, CSV reading, the integrated difference of two curves,
//! cost at matched error, and log–log plots of error against cost.
//!
//! Each example uses a subset.
#![allow(dead_code)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use dmd_sim::run::{Quiet, Summary, run_scene};
use dmd_sim::scene::Scene;
use potential::LjRod;
use smd::units;

/// The paper's rods (003 §V.B): ρ* = 0.5, T* = 1.4, N = 512, ΔV = kT/2.
pub(crate) const PAPER: &str = include_str!("../../../../scenes/rods-paper.toml");
/// T* = 1.4 with ε = 3 kJ/mol, in kelvin (the scene's `init.temperature`).
pub(crate) const T_KELVIN: f64 = 505.144;

/// Scene overrides that turn [`PAPER`] into the paper's gas, T* = 10 and ρ* = 0.01 (N = 512,
/// box 113 Å).
pub(crate) fn gas_overrides() -> Vec<String> {
    let t_star = 10.0;
    vec![
        format!("init.temperature={}", t_star / 1.4 * T_KELVIN),
        // ρ* = 0.01: 0.01 / σ³ per Å³.
        format!(
            "box.density={}",
            units::density_from_reduced(0.01, LjRod::paper().sigma())
        ),
    ]
}

/// The command line of a validation example: `--quick` (the CI subset), `--figures DIR` and
/// `--case TEXT` (only the cases whose name contains `TEXT`, for examples with several cases:
/// `validate_tune`).
pub(crate) struct Args {
    pub(crate) quick: bool,
    pub(crate) figures: PathBuf,
    pub(crate) case: Option<String>,
}

fn parse() -> Result<Args, String> {
    let mut quick = false;
    let mut figures = PathBuf::from("target/validate-figures");
    let mut case = None;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--figures" => figures = PathBuf::from(it.next().ok_or("--figures needs a folder")?),
            "--case" => case = Some(it.next().ok_or("--case needs a name")?),
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    Ok(Args {
        quick,
        figures,
        case,
    })
}

/// The `main` of a validation example `name`: parses the arguments, runs `validate` in a
/// scratch folder (removed afterwards), prints its Markdown and exits non-zero when a check
/// failed or `validate` returned an error (2 for a bad argument).
pub(crate) fn main_of(
    name: &str,
    validate: impl FnOnce(&Args, &Path, &mut Report, &mut String) -> Result<(), String>,
) -> ExitCode {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{name}: {e}");
            return ExitCode::from(2);
        }
    };
    let _ = std::fs::create_dir_all(&args.figures);
    let work = std::env::temp_dir().join(format!("dmd-{name}-{}", std::process::id()));
    let mut r = Report { ok: true };
    let mut text = String::new();
    if let Err(e) = validate(&args, &work, &mut r, &mut text) {
        eprintln!("{name}: {e}");
        r.ok = false;
        let _ = writeln!(text, "\n**Error:** {e}");
    }
    let _ = std::fs::remove_dir_all(&work);
    print!("{text}");
    if r.ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// Pass/fail bookkeeping of a report: `check` records a failure and returns the word to print.
pub(crate) struct Report {
    pub(crate) ok: bool,
}

impl Report {
    pub(crate) fn check(&mut self, ok: bool) -> &'static str {
        self.ok &= ok;
        if ok { "pass" } else { "**FAIL**" }
    }
}

/// The rows of a CSV file after its header (unparsable cells are NaN; a missing file is empty).
pub(crate) fn csv(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

/// Rows `(x, y)` of the columns named `x` and `y` of a CSV file with a header (empty if the
/// file or a column is missing): columns by name, as `dmd` documents them, not by position.
pub(crate) fn csv_pairs(path: &Path, x: &str, y: &str) -> Vec<(f64, f64)> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let (Some(i), Some(j)) = (
        header.iter().position(|h| *h == x),
        header.iter().position(|h| *h == y),
    ) else {
        return Vec::new();
    };
    lines
        .map(|l| {
            let row: Vec<f64> = l
                .split(',')
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect();
            (row[i], row[j])
        })
        .collect()
}

/// Runs the event-driven engine on scene `text` with `--set` style `overrides`, writing its
/// outputs to `dir` (emptied first) if given.
pub(crate) fn scene_run(
    text: &str,
    overrides: &[String],
    dir: Option<&Path>,
) -> Result<Summary, String> {
    let scene = Scene::from_str_with(text, overrides).map_err(|e| e.to_string())?;
    if let Some(d) = dir {
        let _ = std::fs::remove_dir_all(d);
    }
    run_scene(&scene, Path::new("."), dir, &mut Quiet).map_err(|e| e.to_string())
}

/// ΔV in units of kT as text: `2kT`, `kT`, `kT/2`, …
pub(crate) fn kt_label(dv: f64) -> String {
    if dv == 1.0 {
        "kT".to_owned()
    } else if dv > 1.0 {
        format!("{dv}kT")
    } else {
        format!("kT/{}", (1.0 / dv).round())
    }
}

/// `∫ |f − g|` over the abscissae of `f` inside `g`'s range, `g` interpolated linearly
/// (trapezoids on |f − g|).
pub(crate) fn integrated_difference(f: &[(f64, f64)], g: &[(f64, f64)]) -> f64 {
    let at = |x: f64| -> Option<f64> {
        let k = g.partition_point(|p| p.0 < x);
        if k < g.len() && (g[k].0 - x).abs() <= 1e-9 * (1.0 + x.abs()) {
            return Some(g[k].1);
        }
        if k == 0 || k >= g.len() {
            return None;
        }
        let (a, b) = (g[k - 1], g[k]);
        Some(a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0))
    };
    let d: Vec<(f64, f64)> = f
        .iter()
        .filter_map(|&(x, y)| at(x).map(|z| (x, (y - z).abs())))
        .collect();
    d.windows(2)
        .map(|w| 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0))
        .sum()
}

/// How a matched cost relates to the true one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Bound {
    /// Interpolated between two runs.
    About,
    /// Even the cheapest run is as accurate: the matched cost is at most its cost.
    AtMost,
    /// No run is as accurate: the matched cost is at least the most accurate run's.
    AtLeast,
}

/// The CPU time per ps an engine with runs `pts` (cost, error) needs for error `err`: the
/// cheapest run at least as accurate, interpolated log–log towards the next cheaper one.
pub(crate) fn matched_cost(pts: &[(f64, f64)], err: f64) -> (Bound, f64) {
    // Cheapest first.
    let mut pts = pts.to_vec();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let Some(j) = pts.iter().position(|p| p.1 <= err) else {
        return (Bound::AtLeast, pts.last().map_or(f64::NAN, |p| p.0));
    };
    if j == 0 {
        return (Bound::AtMost, pts[0].0);
    }
    // The next cheaper run is less accurate: interpolate log–log between the two.
    let (a, b) = (pts[j - 1], pts[j]);
    let s = (err.ln() - a.1.ln()) / (b.1.ln() - a.1.ln());
    (Bound::About, (a.0.ln() + s * (b.0.ln() - a.0.ln())).exp())
}

/// SMD's CPU time per ps at error `err` (runs `smd`: cost, error), over `dmd_cost`, as text:
/// `≤`/`≥` for bounds, "(unresolved)" when `err` is at or below the noise `floor`.
pub(crate) fn matched_ratio(smd: &[(f64, f64)], err: f64, floor: f64, dmd_cost: f64) -> String {
    let below = if err <= floor { " (unresolved)" } else { "" };
    let (bound, cost) = matched_cost(smd, err);
    format!("{}{}{below}", bound_mark(bound), ratio(cost / dmd_cost))
}

/// A cost ratio as text: two decimals from 0.1 on, three significant digits below (water's
/// ratios are hundredths and thousandths).
pub(crate) fn ratio(x: f64) -> String {
    if !(x.is_finite() && x > 0.0) || x >= 0.1 {
        return format!("{x:.2}");
    }
    let digits = (2.0 - x.log10().floor()) as usize;
    format!("{x:.digits$}")
}

/// `≤ ` or `≥ ` before a bound, nothing before an interpolated value.
pub(crate) fn bound_mark(bound: Bound) -> &'static str {
    match bound {
        Bound::About => "",
        Bound::AtMost => "≤ ",
        Bound::AtLeast => "≥ ",
    }
}

// ---- Plots ------------------------------------------------------------------------------------

/// One set of points of a log–log panel.
pub(crate) struct Series {
    pub(crate) label: String,
    pub(crate) points: Vec<(f64, f64)>,
    /// A text beside each point (empty: none).
    pub(crate) tags: Vec<String>,
    /// Join the points by lines (in the given order).
    pub(crate) joined: bool,
}

/// Log–log points joined by lines, with an optional dashed horizontal line at `floor`.
pub(crate) fn plot_points(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(String, Vec<(f64, f64)>)],
    floor: Option<f64>,
) -> Result<(), String> {
    use plotters::prelude::*;
    let series: Vec<Series> = series
        .iter()
        .map(|(label, points)| Series {
            label: label.clone(),
            points: points.clone(),
            tags: Vec::new(),
            joined: true,
        })
        .collect();
    let root = SVGBackend::new(path, (760, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    draw_panel(&root, title, x_label, y_label, &series, floor)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    root.present().map_err(|e| e.to_string())
}

/// Draws one log–log panel of `series` on `area` (see [`plot_points`]).
pub(crate) fn draw_panel(
    area: &plotters::drawing::DrawingArea<
        plotters::prelude::SVGBackend<'_>,
        plotters::coord::Shift,
    >,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    floor: Option<f64>,
) -> Result<(), String> {
    use plotters::prelude::*;
    let colours = [
        RGBColor(200, 30, 30),
        RGBColor(30, 80, 200),
        RGBColor(20, 150, 60),
        RGBColor(170, 60, 170),
    ];
    let ok = |p: &(f64, f64)| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite();
    let pts = || {
        series
            .iter()
            .flat_map(|s| s.points.iter().copied())
            .filter(ok)
    };
    let (x0, x1) = pts().fold((f64::INFINITY, 0.0f64), |a, p| (a.0.min(p.0), a.1.max(p.0)));
    let (mut y0, mut y1) = pts().fold((f64::INFINITY, 0.0f64), |a, p| (a.0.min(p.1), a.1.max(p.1)));
    if let Some(f) = floor.filter(|f| *f > 0.0) {
        y0 = y0.min(f);
        y1 = y1.max(f);
    }
    if !x0.is_finite() || !y0.is_finite() {
        return Err("nothing to plot".to_owned());
    }
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x0 / 1.5..x1 * 1.5).log_scale(),
            // Headroom above the data for the legend.
            (y0 / 1.5..y1 * 6.0).log_scale(),
        )
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&log_tick)
        .y_label_formatter(&log_tick)
        .draw()
        .map_err(|e| e.to_string())?;
    for (k, s) in series.iter().enumerate() {
        let c = colours[k % colours.len()];
        let kept: Vec<usize> = (0..s.points.len()).filter(|&i| ok(&s.points[i])).collect();
        let p: Vec<(f64, f64)> = kept.iter().map(|&i| s.points[i]).collect();
        let legend = move |(x, y): (i32, i32)| {
            PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
        };
        if s.joined {
            chart
                .draw_series(LineSeries::new(p.iter().copied(), c.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(s.label.clone())
                .legend(legend);
            chart
                .draw_series(p.iter().map(|q| Circle::new(*q, 4, c.filled())))
                .map_err(|e| e.to_string())?;
        } else {
            chart
                .draw_series(p.iter().map(|q| Circle::new(*q, 4, c.filled())))
                .map_err(|e| e.to_string())?
                .label(s.label.clone())
                .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
        }
        let tags = kept.iter().filter_map(|&i| {
            s.tags.get(i).filter(|t| !t.is_empty()).map(|t| {
                Text::new(
                    t.clone(),
                    s.points[i],
                    ("sans-serif", 11).into_font().color(&c),
                )
            })
        });
        chart.draw_series(tags).map_err(|e| e.to_string())?;
    }
    if let Some(f) = floor.filter(|f| *f > 0.0) {
        // Dashes as short segments (the SVG backend of this plotters has no dash style).
        let (a, b) = (x0 / 1.5, x1 * 1.5);
        let n = 40;
        let ratio = (b / a).powf(1.0 / f64::from(2 * n));
        let dashes = (0..n).map(|k| {
            let s = a * ratio.powi(2 * k);
            PathElement::new(vec![(s, f), (s * ratio, f)], BLACK.stroke_width(1))
        });
        chart
            .draw_series(dashes)
            .map_err(|e| e.to_string())?
            .label("noise floor")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(1)));
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())
}

/// A log axis's tick label at 1, 2 and 5 times a power of ten only (plotters offers a tick at
/// every integer mantissa, which overprint each other near the top of a decade).
fn log_tick(v: &f64) -> String {
    let e = v.log10().floor();
    let m = v / 10f64.powf(e);
    if [1.0, 2.0, 5.0].iter().any(|k| (m - k).abs() < 1e-6 * k) {
        let s = format!("{v:.6}");
        if (1e-3..1e4).contains(v) {
            s.trim_end_matches('0').trim_end_matches('.').to_owned()
        } else {
            format!("{v:.0e}")
        }
    } else {
        String::new()
    }
}
