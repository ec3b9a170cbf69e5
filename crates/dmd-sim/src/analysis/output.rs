//! Files a run writes: `summary.json`, observables as CSV with an SVG plot each, an extended
//! XYZ trajectory and a GSD trajectory. Every file but the GSD trajectory is written to a
//! temporary name in the output folder and renamed into place when complete, so a crash never
//! leaves a half-written result behind; the GSD file is complete after every frame (its writer
//! commits each frame), so it is written in place and can be watched while the run goes on.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};

use crate::engine::simulation::View;

/// Bytes of one row of `series.csv` (six numbers in full precision; also more than its 48
/// bytes in memory).
pub const SERIES_ROW_BYTES: f64 = 150.0;

/// Bytes of one lag of the correlation buffers (MSD, VACF, two orientational ACFs, count).
pub const LAG_BYTES: f64 = 40.0;

/// Bytes of one line of a `trajectory.xyz` frame: species name, position and velocity with
/// ten decimals, image, element, mass, momentum in eleven digits and the id; a body with an
/// attitude adds a quaternion with twelve decimals, the shape and the angular velocity, an atom
/// of a semi-flexible molecule its molecule's id.
pub fn trajectory_line_bytes(oriented: bool, atom: bool) -> f64 {
    match (oriented, atom) {
        (true, _) => 300.0,
        (false, true) => 190.0,
        (false, false) => 180.0,
    }
}

/// Bytes of one particle of a `trajectory.gsd` frame: position, orientation, velocity, image
/// and angular momentum (17 numbers of 4 bytes).
pub const GSD_PARTICLE_BYTES: f64 = 68.0;

/// Bytes of a `trajectory.gsd` frame beyond its particles: step, the time and energies in
/// `log/`, index entries (with the index's growth by doubling) and, once, the types and shapes.
pub const GSD_FRAME_BYTES: f64 = 1024.0;

/// A number as a scene gave it, for messages: the shortest digits that read back as the same
/// number, in exponent form outside `1e-4 ≤ |x| < 1e15` (`1e20`, `-1e300`, `2.5`, `1e-9`),
/// never the hundreds of digits Rust's plain `{}` spells out for `1e300`.
pub fn given(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A number in short form: `8e15`, `2.8e9`, `0.001`, `150`.
pub fn short(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e6).contains(&x.abs()) {
        let s = format!("{x:.2e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        format!("{m}e{e}")
    } else {
        let s = format!("{x:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    }
}

/// An output could not be written.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {message}")]
pub struct OutputError {
    /// The file.
    pub path: PathBuf,
    /// Why.
    pub message: String,
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError {
        path: path.to_owned(),
        message: e.to_string(),
    }
}

/// The temporary name of `path` while it is being written.
fn temporary(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    path.with_file_name(name)
}

/// Writes `bytes` to `path` atomically (temporary file, then rename).
///
/// # Errors
/// [`OutputError`] naming the file.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let tmp = temporary(path);
    let mut f = File::create(&tmp).map_err(|e| io_err(&tmp, e))?;
    f.write_all(bytes).map_err(|e| io_err(&tmp, e))?;
    f.sync_all().map_err(|e| io_err(&tmp, e))?;
    drop(f);
    std::fs::rename(&tmp, path).map_err(|e| io_err(path, e))
}

/// Writes a CSV table with a header line.
///
/// # Errors
/// [`OutputError`].
pub fn write_csv(path: &Path, header: &[&str], rows: &[Vec<f64>]) -> Result<(), OutputError> {
    let mut text = header.join(",");
    text.push('\n');
    for row in rows {
        // `{:e}`: the shortest digits that read back to the same f64 (`1.25e-1`, `3e0`).
        text.push_str(&csv_line(row));
    }
    write_atomically(path, text.as_bytes())
}

/// The line of a CSV row as [`write_csv`] writes it: `{:e}` (the shortest digits that read
/// back to the same f64) separated by commas.
fn csv_line(row: &[f64]) -> String {
    let cells: Vec<String> = row.iter().map(|x| format!("{x:e}")).collect();
    let mut line = cells.join(",");
    line.push('\n');
    line
}

/// A CSV table written row by row as a run produces it (a temporary file renamed when
/// finished), so that its rows are never held in memory; the finished file is byte for byte
/// what [`write_csv`] writes for the same rows.
#[derive(Debug)]
pub struct CsvStream {
    path: PathBuf,
    tmp: PathBuf,
    out: BufWriter<File>,
    error: Option<String>,
}

/// The temporary file `tmp` of an interrupted `what` (a table, a trajectory) cut to the `len`
/// bytes a checkpoint recorded, for appending at its end.
///
/// # Errors
/// [`OutputError`] if the file is missing or shorter than `len`.
fn cut_to(tmp: &Path, len: u64, what: &str) -> Result<BufWriter<File>, OutputError> {
    let f = std::fs::OpenOptions::new()
        .write(true)
        .open(tmp)
        .map_err(|e| io_err(tmp, format!("cannot continue the {what}: {e}")))?;
    let have = f.metadata().map_err(|e| io_err(tmp, e))?.len();
    if have < len {
        return Err(io_err(
            tmp,
            format!(
                "cannot continue the {what}: it has {have} bytes, the checkpoint recorded {len}"
            ),
        ));
    }
    f.set_len(len).map_err(|e| io_err(tmp, e))?;
    let mut out = BufWriter::new(f);
    std::io::Seek::seek(&mut out, std::io::SeekFrom::End(0)).map_err(|e| io_err(tmp, e))?;
    Ok(out)
}

impl CsvStream {
    /// The temporary file the rows go to until [`finish`](Self::finish).
    pub fn temporary_path(&self) -> &Path {
        &self.tmp
    }

    /// Opens `path` (as a temporary file) and writes the header line.
    ///
    /// # Errors
    /// [`OutputError`].
    pub fn create(path: &Path, header: &[&str]) -> Result<Self, OutputError> {
        let tmp = temporary(path);
        let f = File::create(&tmp).map_err(|e| io_err(&tmp, e))?;
        let mut out = BufWriter::new(f);
        writeln!(out, "{}", header.join(",")).map_err(|e| io_err(&tmp, e))?;
        Ok(CsvStream {
            path: path.to_owned(),
            tmp,
            out,
            error: None,
        })
    }

    /// Reopens the temporary file of a table interrupted after `len` bytes (a resumed run):
    /// rows written after that point are cut off and new ones appended.
    ///
    /// # Errors
    /// [`OutputError`] if the temporary file is missing or shorter than `len`.
    pub fn reopen(path: &Path, len: u64) -> Result<Self, OutputError> {
        let tmp = temporary(path);
        let out = cut_to(&tmp, len, "table")?;
        Ok(CsvStream {
            path: path.to_owned(),
            tmp,
            out,
            error: None,
        })
    }

    /// Appends a row (an error is kept and reported by [`mark`](Self::mark) and
    /// [`finish`](Self::finish)).
    pub fn write_row(&mut self, row: &[f64]) {
        if self.error.is_none()
            && let Err(e) = self.out.write_all(csv_line(row).as_bytes())
        {
            self.error = Some(e.to_string());
        }
    }

    /// Flushes and gives the bytes written so far (for a checkpoint).
    ///
    /// # Errors
    /// [`OutputError`].
    pub fn mark(&mut self) -> Result<u64, OutputError> {
        if let Some(e) = &self.error {
            return Err(io_err(&self.tmp, e));
        }
        self.out.flush().map_err(|e| io_err(&self.tmp, e))?;
        Ok(self
            .out
            .get_ref()
            .metadata()
            .map_err(|e| io_err(&self.tmp, e))?
            .len())
    }

    /// Flushes, syncs and renames the table to its name; gives its path.
    ///
    /// # Errors
    /// [`OutputError`].
    pub fn finish(mut self) -> Result<PathBuf, OutputError> {
        if let Some(e) = self.error.take() {
            return Err(io_err(&self.tmp, e));
        }
        self.out.flush().map_err(|e| io_err(&self.tmp, e))?;
        self.out
            .get_ref()
            .sync_all()
            .map_err(|e| io_err(&self.tmp, e))?;
        std::fs::rename(&self.tmp, &self.path).map_err(|e| io_err(&self.path, e))?;
        Ok(self.path)
    }
}

/// The rows of a CSV file this module wrote (its header skipped), back as the numbers written.
///
/// # Errors
/// [`OutputError`] if the file cannot be read or holds a cell that is not a number.
pub fn read_csv_rows(path: &Path) -> Result<Vec<Vec<f64>>, OutputError> {
    let bad = |e: &dyn std::fmt::Display| OutputError {
        path: path.to_owned(),
        message: format!("cannot read the table back: {e}"),
    };
    let text = std::fs::read_to_string(path).map_err(|e| bad(&e))?;
    text.lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(str::parse)
                .collect::<Result<Vec<f64>, _>>()
                .map_err(|e| bad(&e))
        })
        .collect()
}

/// A horizontal line at a curve's mean, with a shaded band of ± its error.
#[derive(Clone, Debug, PartialEq)]
pub struct Mean {
    /// Legend of the line, with its value and unit (`mean 1312 ± 45 bar`).
    pub label: String,
    /// The mean (the curve's unit).
    pub value: f64,
    /// Its error, the band's half-width (none: the line alone).
    pub error: Option<f64>,
}

/// One curve of a [`Plot`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Line {
    /// Legend.
    pub label: String,
    /// Points.
    pub points: Vec<(f64, f64)>,
    /// Drawn dashed (a fit or a reference line) instead of solid.
    pub dashed: bool,
    /// A line at the curve's mean with its error band, in the curve's colour.
    pub mean: Option<Mean>,
    /// The error of each point (empty: none), drawn as a shaded band of ± it around the curve.
    pub errors: Vec<f64>,
}

impl Line {
    /// A solid line without a mean.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Line {
            label: label.into(),
            points,
            dashed: false,
            mean: None,
            errors: Vec::new(),
        }
    }

    /// The same line with a shaded band of ± `errors` (one per point; non-finite ones leave
    /// a gap).
    pub fn with_errors(mut self, errors: Vec<f64>) -> Self {
        self.errors = errors;
        self
    }

    /// The band's stretches of consecutive points with a finite point and error, each as
    /// `(x, y − e, y + e)`.
    fn band(&self) -> Vec<Vec<(f64, f64, f64)>> {
        let mut out: Vec<Vec<(f64, f64, f64)>> = Vec::new();
        let mut run = Vec::new();
        for (&(x, y), &e) in self.points.iter().zip(&self.errors) {
            if x.is_finite() && y.is_finite() && e.is_finite() {
                run.push((x, y - e.abs(), y + e.abs()));
            } else if !run.is_empty() {
                out.push(std::mem::take(&mut run));
            }
        }
        if !run.is_empty() {
            out.push(run);
        }
        out
    }
}

/// What a plot shows: a title, a caption naming the system, axis labels with their units,
/// and the curves.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Plot {
    /// What is plotted (`Radial distribution function`).
    pub title: String,
    /// The system, under the title (`rods-paper: N = 512, T = 530.5 K, …`).
    pub caption: String,
    /// The x axis with its unit (`t (ps)`).
    pub x_label: String,
    /// The y axis with its unit (`P (bar)`).
    pub y_label: String,
    /// The curves; a legend lists those with a label, and the means.
    pub lines: Vec<Line>,
}

/// The range `(x0, x1, y0, y1)` of the finite points and mean bands of `curves`, padded in y;
/// none without a finite point.
fn plot_range(curves: &[Line]) -> Option<(f64, f64, f64, f64)> {
    let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let mut any = false;
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for c in curves {
        for p in c.points.iter().filter(finite) {
            any = true;
            (x0, x1, y0, y1) = (x0.min(p.0), x1.max(p.0), y0.min(p.1), y1.max(p.1));
        }
        if let Some(m) = c.mean.as_ref().filter(|m| m.value.is_finite()) {
            let e = m.error.filter(|e| e.is_finite()).unwrap_or(0.0).abs();
            (y0, y1) = (y0.min(m.value - e), y1.max(m.value + e));
        }
        for &(_, lo, hi) in c.band().iter().flatten() {
            (y0, y1) = (y0.min(lo), y1.max(hi));
        }
    }
    if !any {
        return None;
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
        x0 -= 1.0;
    }
    let pad = 0.05 * (y1 - y0).abs().max(1e-12 * y1.abs()).max(1e-300);
    Some((x0, x1, y0 - pad, y1 + pad))
}

/// Where the legend goes: the place, of the nine plotters offers, whose box (`w` × `h`, as
/// fractions of the plotting area) covers the fewest points of the curves and mean lines
/// (sampled along their segments), the upper right first among equals. Returns the place as
/// `(column, row)`, each 0, 1 or 2 (left/top, middle, right/bottom), and the points it covers.
fn legend_place(
    curves: &[Line],
    (x0, x1, y0, y1): (f64, f64, f64, f64),
    w: f64,
    h: f64,
) -> ((usize, usize), usize) {
    let norm = |(x, y): (f64, f64)| ((x - x0) / (x1 - x0), (y - y0) / (y1 - y0));
    let mut samples: Vec<(f64, f64)> = Vec::new();
    let mut trace = |pts: &mut dyn Iterator<Item = (f64, f64)>| {
        let mut last: Option<(f64, f64)> = None;
        for p in pts.filter(|p| p.0.is_finite() && p.1.is_finite()).map(norm) {
            if let Some(q) = last {
                let n = (((p.0 - q.0).abs() + (p.1 - q.1).abs()) * 100.0)
                    .ceil()
                    .clamp(1.0, 200.0);
                for k in 1..=n as usize {
                    let f = k as f64 / n;
                    samples.push((q.0 + f * (p.0 - q.0), q.1 + f * (p.1 - q.1)));
                }
            } else {
                samples.push(p);
            }
            last = Some(p);
        }
    };
    for c in curves {
        trace(&mut c.points.iter().copied());
        if let Some(m) = &c.mean {
            let e = m.error.filter(|e| e.is_finite()).unwrap_or(0.0);
            for y in [m.value - e, m.value, m.value + e] {
                trace(&mut [(x0, y), (x1, y)].into_iter());
            }
        }
    }
    let span = |k: usize, size: f64| match k {
        0 => (0.0, size),
        1 => (0.5 - 0.5 * size, 0.5 + 0.5 * size),
        _ => (1.0 - size, 1.0),
    };
    let places = [
        (2, 0),
        (0, 0),
        (2, 2),
        (0, 2),
        (2, 1),
        (1, 0),
        (1, 2),
        (0, 1),
        (1, 1),
    ];
    places
        .into_iter()
        .map(|(col, row)| {
            let (a, b) = span(col, w);
            // Rows count from the top, y from the bottom.
            let (c, d) = span(2 - row, h);
            let covered = samples
                .iter()
                .filter(|p| (a..=b).contains(&p.0) && (c..=d).contains(&p.1))
                .count();
            ((col, row), covered)
        })
        .min_by_key(|&(_, covered)| covered)
        .unwrap_or(((2, 0), 0))
}

/// Tick labels for an axis from `lo` to `hi`: as many decimals as ticks about a tenth of the
/// range apart need (`2000`, `0.2`, `0.05`), e-notation for very large or small numbers.
fn tick_label(lo: f64, hi: f64) -> impl Fn(&f64) -> String {
    let range = (hi - lo).abs();
    let big = lo.abs().max(hi.abs());
    let scientific = big >= 1e6 || (range > 0.0 && range < 1e-3);
    let decimals = if range > 0.0 {
        (-(range / 10.0).log10().floor()).clamp(0.0, 6.0) as usize
    } else {
        3
    };
    move |x: &f64| {
        if scientific && *x != 0.0 {
            let s = format!("{x:.2e}");
            let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
            let m = m.trim_end_matches('0').trim_end_matches('.');
            format!("{m}e{e}")
        } else {
            // No `-0` for a tick at zero.
            let s = format!("{x:.decimals$}");
            if s.trim_start_matches('-')
                .chars()
                .all(|c| c == '0' || c == '.')
            {
                s.trim_start_matches('-').to_owned()
            } else {
                s
            }
        }
    }
}

/// Draws a plot into an SVG file (written atomically): the title, the caption under it, the
/// axes with their labels, each curve in its own colour (dashed if asked; lighter when it has
/// a mean, which is drawn over it as a line on a shaded band of ± its error), and a legend of
/// the labelled curves with their means where it covers the fewest points (above the curves,
/// the y axis lengthened, when it would cover some anywhere). Nothing is written when no curve has a finite point.
///
/// # Errors
/// [`OutputError`].
pub fn write_plot(path: &Path, plot: &Plot) -> Result<(), OutputError> {
    use plotters::prelude::*;
    let tmp = temporary(path);
    let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let Some((x0, x1, y0, mut y1)) = plot_range(&plot.lines) else {
        return Ok(());
    };
    // One legend entry per labelled curve; a curve with a mean has one entry for both, drawn
    // as the mean's line on its band.
    let entry = |c: &Line| -> Option<String> {
        match (&c.mean, c.label.is_empty()) {
            (Some(m), false) => Some(format!("{}: {}", c.label, m.label)),
            (Some(m), true) => Some(m.label.clone()),
            (None, false) => Some(c.label.clone()),
            (None, true) => None,
        }
    };
    let entries: Vec<String> = plot.lines.iter().filter_map(entry).collect();
    // The legend's box as a fraction of the plotting area (about 7 pixels a character, 19 a
    // line, in a plotting area of about 650 × 350 pixels). Where every place would cover a
    // curve, the y axis is lengthened to leave the top free for it.
    let chars = entries.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    let w = (40.0 + 7.0 * chars as f64) / 650.0;
    let h = (12.0 + 19.0 * entries.len() as f64) / 350.0;
    let (mut place, covered) = legend_place(&plot.lines, (x0, x1, y0, y1), w, h);
    if covered > 0 && h < 0.6 {
        y1 = y0 + (y1 - y0) / (1.0 - h - 0.03);
        place = (2, 0);
    }
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::new(&tmp, (760, 480)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut area = root.titled(&plot.title, ("sans-serif", 20))?;
        if !plot.caption.is_empty() {
            area = area.titled(&plot.caption, ("sans-serif", 14))?;
        }
        let mut chart = ChartBuilder::on(&area)
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(78)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc(plot.x_label.as_str())
            .y_desc(plot.y_label.as_str())
            .axis_desc_style(("sans-serif", 15))
            .x_label_formatter(&tick_label(x0, x1))
            .y_label_formatter(&tick_label(y0, y1))
            .draw()?;
        // Dark enough to read on white (plotters' GREEN and CYAN are not).
        let colors = [
            BLUE,
            RED,
            BLACK,
            RGBColor(0, 140, 0),
            MAGENTA,
            RGBColor(0, 140, 160),
        ];
        for (k, c) in plot.lines.iter().enumerate() {
            let color = colors[k % colors.len()];
            let mean = c.mean.as_ref().filter(|m| m.value.is_finite());
            // A curve with a mean is drawn lighter and thinner, its mean and band over it.
            let style = if mean.is_some() {
                color.mix(0.55).stroke_width(1)
            } else {
                color.stroke_width(2)
            };
            // The error band under the curve: the polygon along y + e and back along y − e.
            for stretch in c.band() {
                let outline: Vec<(f64, f64)> = stretch
                    .iter()
                    .map(|&(x, _, hi)| (x, hi))
                    .chain(stretch.iter().rev().map(|&(x, lo, _)| (x, lo)))
                    .collect();
                chart.draw_series(std::iter::once(Polygon::new(
                    outline,
                    color.mix(0.2).filled(),
                )))?;
            }
            let pts: Vec<(f64, f64)> = c.points.iter().filter(finite).copied().collect();
            let anno = if c.dashed {
                chart.draw_series(DashedLineSeries::new(pts, 8, 5, style))?
            } else {
                chart.draw_series(LineSeries::new(pts, style))?
            };
            let label = entry(c);
            if let (None, Some(label)) = (mean, &label) {
                anno.label(label.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
            }
            if let Some(m) = mean {
                let error = m.error.filter(|e| e.is_finite() && *e > 0.0);
                if let Some(e) = error {
                    chart.draw_series(std::iter::once(Rectangle::new(
                        [(x0, m.value - e), (x1, m.value + e)],
                        color.mix(0.22).filled(),
                    )))?;
                }
                let band = error.is_some();
                chart
                    .draw_series(LineSeries::new(
                        [(x0, m.value), (x1, m.value)],
                        color.stroke_width(2),
                    ))?
                    .label(label.unwrap_or_default())
                    .legend(move |(x, y)| {
                        let fill = if band {
                            color.mix(0.22)
                        } else {
                            WHITE.mix(0.0)
                        };
                        EmptyElement::at((x, y))
                            + Rectangle::new([(0, -5), (18, 5)], fill.filled())
                            + PathElement::new(vec![(0, 0), (18, 0)], color.stroke_width(2))
                    });
            }
        }
        if !entries.is_empty() {
            let position = match place {
                (0, 0) => SeriesLabelPosition::UpperLeft,
                (0, 1) => SeriesLabelPosition::MiddleLeft,
                (0, _) => SeriesLabelPosition::LowerLeft,
                (1, 0) => SeriesLabelPosition::UpperMiddle,
                (1, 1) => SeriesLabelPosition::MiddleMiddle,
                (1, _) => SeriesLabelPosition::LowerMiddle,
                (_, 0) => SeriesLabelPosition::UpperRight,
                (_, 1) => SeriesLabelPosition::MiddleRight,
                _ => SeriesLabelPosition::LowerRight,
            };
            chart
                .configure_series_labels()
                .position(position)
                .label_font(("sans-serif", 13))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()?;
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| io_err(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| io_err(path, e))
}

/// One curve of a plot drawn by [`plot_svg`].
pub struct Curve<'a> {
    /// Legend.
    pub label: &'a str,
    /// Points.
    pub points: Vec<(f64, f64)>,
}

/// Draws curves into an SVG file (written atomically) with [`write_plot`]: a title, axis
/// labels and, for more than one curve, a legend.
///
/// # Errors
/// [`OutputError`].
pub fn plot_svg(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    curves: &[Curve<'_>],
) -> Result<(), OutputError> {
    let legend = curves.len() > 1;
    write_plot(
        path,
        &Plot {
            title: title.to_owned(),
            caption: String::new(),
            x_label: x_label.to_owned(),
            y_label: y_label.to_owned(),
            lines: curves
                .iter()
                .map(|c| Line::new(if legend { c.label } else { "" }, c.points.clone()))
                .collect(),
        },
    )
}

/// How a trajectory frame draws the bodies of one species.
#[derive(Clone, Debug, PartialEq)]
pub enum Drawing {
    /// A sphere of `diameter` (length).
    Sphere {
        /// Diameter (length).
        diameter: f64,
    },
    /// A rod: an ellipsoid along its body z axis.
    Rod {
        /// Semi-axes (length), the third along the rod.
        semi_axes: [f64; 3],
    },
    /// A rigid site molecule: its sites in its body (principal) frame, relative to its centre
    /// (length), and their diameters (length).
    Sites {
        /// Site positions in the body frame (length).
        centres: Vec<DVec3>,
        /// Site diameters (length).
        diameters: Vec<f64>,
    },
    /// A semi-flexible molecule, drawn as its atoms: the site kind of each atom, an index into
    /// [`Layout::kinds`], and its mass.
    Atoms {
        /// Site kind of each atom.
        kinds: Vec<u32>,
        /// Mass of each atom.
        masses: Vec<f64>,
    },
}

impl Drawing {
    /// The semi-axes (length) of the ellipsoid an extended XYZ frame draws a body with an
    /// attitude as: for site molecules the extent of the sites along each body axis (`None`
    /// for semi-flexible molecules, written as their atoms).
    fn semi_axes(&self) -> Option<[f64; 3]> {
        match self {
            Drawing::Sphere { diameter } => Some([0.5 * diameter; 3]),
            Drawing::Rod { semi_axes } => Some(*semi_axes),
            Drawing::Atoms { .. } => None,
            Drawing::Sites { centres, diameters } => {
                let mut e = [0.0f64; 3];
                for (c, d) in centres.iter().zip(diameters) {
                    for (k, x) in c.to_array().into_iter().enumerate() {
                        e[k] = e[k].max(x.abs() + 0.5 * d);
                    }
                }
                // Six decimals: a drawing's size, not a measurement.
                Some(e.map(|x| (x * 1e6).round() / 1e6))
            }
        }
    }
}

/// The chemical symbols by atomic number (`X`, 0, for none).
const ELEMENTS: [&str; 119] = [
    "X", "H", "He", "Li", "Be", "B", "C", "N", "O", "F", "Ne", "Na", "Mg", "Al", "Si", "P", "S",
    "Cl", "Ar", "K", "Ca", "Sc", "Ti", "V", "Cr", "Mn", "Fe", "Co", "Ni", "Cu", "Zn", "Ga", "Ge",
    "As", "Se", "Br", "Kr", "Rb", "Sr", "Y", "Zr", "Nb", "Mo", "Tc", "Ru", "Rh", "Pd", "Ag", "Cd",
    "In", "Sn", "Sb", "Te", "I", "Xe", "Cs", "Ba", "La", "Ce", "Pr", "Nd", "Pm", "Sm", "Eu", "Gd",
    "Tb", "Dy", "Ho", "Er", "Tm", "Yb", "Lu", "Hf", "Ta", "W", "Re", "Os", "Ir", "Pt", "Au", "Hg",
    "Tl", "Pb", "Bi", "Po", "At", "Rn", "Fr", "Ra", "Ac", "Th", "Pa", "U", "Np", "Pu", "Am", "Cm",
    "Bk", "Cf", "Es", "Fm", "Md", "No", "Lr", "Rf", "Db", "Sg", "Bh", "Hs", "Mt", "Ds", "Rg", "Cn",
    "Nh", "Fl", "Mc", "Lv", "Ts", "Og",
];

/// The atomic number of a chemical symbol written as the periodic table writes it (`O`, `Ar`;
/// `X` is 0, no element); `None` for anything else.
pub fn atomic_number(symbol: &str) -> Option<u8> {
    ELEMENTS.iter().position(|&e| e == symbol).map(|z| z as u8)
}

/// The atomic number a species or site kind is written with: its `element`, else its name when
/// the name is a chemical symbol, else 0 (`X`).
pub fn element_of(name: &str, element: Option<&str>) -> u8 {
    element
        .and_then(atomic_number)
        .or_else(|| atomic_number(name))
        .unwrap_or(0)
}

/// ASE's unit of velocity, `Å / (Å·√(amu/eV))`, in Å/ps: `√(eV/amu) · 1 ps / 1 Å`
/// (CODATA 2018: e = 1.602176634·10⁻¹⁹ J, amu = 1.66053906660·10⁻²⁷ kg).
pub const ASE_VELOCITY_IN_A_PER_PS: f64 = 98.226_947_502_532_77;

/// What the trajectory writers know of a scene's bodies: names, drawings, elements and moments
/// of inertia per species, and the unit of the `momenta` column.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Species names.
    pub species: Vec<String>,
    /// How each species is drawn.
    pub drawings: Vec<Drawing>,
    /// Site kinds of semi-flexible molecules: name and diameter (length).
    pub kinds: Vec<(String, f64)>,
    /// The atomic number of each species ([`element_of`]), the `Z` column.
    pub elements: Vec<u8>,
    /// The atomic number of each site kind of semi-flexible molecules.
    pub kind_elements: Vec<u8>,
    /// The principal moments of inertia of each species about its body axes (mass·length²;
    /// a rod's `(I, I, 0)`), for the `omega` column; empty when the bodies do not rotate.
    pub moments: Vec<[f64; 3]>,
    /// The `momenta` column per internal momentum `m v`: 1 in reduced units, and in molecular
    /// units `1 / ASE_VELOCITY_IN_A_PER_PS`, so that the column is in ASE's units
    /// (amu·√(eV/amu)) and ASE's velocities in its own.
    pub momentum_unit: f64,
}

impl Layout {
    /// A layout of species `names` drawn as `drawings`, elements from the names, no site
    /// kinds, no rotation, momenta in the run's units.
    pub fn new(species: Vec<String>, drawings: Vec<Drawing>) -> Self {
        Layout {
            elements: species.iter().map(|n| element_of(n, None)).collect(),
            species,
            drawings,
            kinds: Vec::new(),
            kind_elements: Vec::new(),
            moments: Vec::new(),
            momentum_unit: 1.0,
        }
    }

    /// Whether the frames hold atoms (semi-flexible molecules) instead of bodies.
    pub fn atoms(&self) -> bool {
        self.drawings
            .iter()
            .any(|d| matches!(d, Drawing::Atoms { .. }))
    }
}

/// Why a frame of semi-flexible molecules has no atoms for a body.
fn missing_atoms(i: usize, now: f64) -> std::io::Error {
    std::io::Error::other(format!(
        "molecule {i} has no atom positions at time {now}: its RATTLE step failed"
    ))
}

/// `u` wrapped into `[0, L)` and the periodic image `n` with `u = wrapped + n L`.
fn wrap_with_image(u: DVec3, l: DVec3) -> (DVec3, [i64; 3]) {
    let mut p = DVec3::ZERO;
    let mut image = [0i64; 3];
    for k in 0..3 {
        let n = (u[k] / l[k]).floor();
        let mut w = u[k] - n * l[k];
        let mut n = n as i64;
        if w >= l[k] {
            w -= l[k];
            n += 1;
        } else if w < 0.0 {
            w += l[k];
            n -= 1;
        }
        p[k] = w;
        image[k] = n;
    }
    (p, image)
}

/// The lab angular velocity of a body of attitude `q` (body → lab), lab angular momentum `l`
/// and principal moments `moments` about its body axes (a zero moment: no rotation about that
/// axis, as a rod's about its own).
pub fn angular_velocity(q: DQuat, l: DVec3, moments: [f64; 3]) -> DVec3 {
    let lb = q.inverse() * l;
    let div = |x: f64, i: f64| if i > 0.0 { x / i } else { 0.0 };
    q * DVec3::new(
        div(lb.x, moments[0]),
        div(lb.y, moments[1]),
        div(lb.z, moments[2]),
    )
}

/// An extended XYZ trajectory, read by OVITO and by ASE (`ase.io.read(path, index=":")`):
/// per frame the line count, a comment line with `Lattice`, `Properties`, `Time` and `pbc`,
/// and one line per body with the columns
///
/// - `species:S:1`: the species name (OVITO's particle type);
/// - `pos:R:3`: the position wrapped into the box `[0, L)` (length);
/// - `velo:R:3`: the velocity (length/time);
/// - bodies with an attitude (rods, tops, site molecules): `orientation:R:4`, the attitude
///   (body → lab) as a unit quaternion with the scalar last (OVITO's Orientation.X/Y/Z/W);
///   `aspherical_shape:R:3`, the semi-axes of the ellipsoid it is drawn as (length); and
///   `omega:R:3`, the lab angular velocity (1/time);
/// - `map_shift:I:3`: the periodic image, so that `pos + map_shift · L` is the unwrapped
///   position (OVITO's Periodic Image);
/// - `Z:I:1`: the atomic number ([`element_of`]; ASE types atoms by it);
/// - `masses:R:1` and `momenta:R:3`: mass and `m v`, ASE's masses and momenta (in
///   molecular units amu and amu·√(eV/amu), so that ASE's `get_velocities()` is in its own
///   units; in reduced units mass and `m v` as they are);
/// - `id:I:1`: the body's index.
///
/// Semi-flexible molecules are written as their atoms, one line each (with the atom's kind,
/// mass and velocity), with `molecule:I:1` before the id. Written to
/// `trajectory.xyz.partial` and renamed when the run ends.
#[derive(Debug)]
pub struct Trajectory {
    path: PathBuf,
    tmp: PathBuf,
    out: BufWriter<File>,
    error: Option<String>,
    frames: u64,
    layout: Layout,
}

/// The unit quaternion (shortest arc) that turns `z` into `axis`.
pub fn axis_quaternion(axis: DVec3) -> DQuat {
    DQuat::from_rotation_arc(DVec3::Z, axis.normalize())
}

impl Trajectory {
    /// Opens `path` (as a temporary file) for bodies drawn as `layout` says.
    ///
    /// # Errors
    /// [`OutputError`].
    pub fn create(path: &Path, layout: Layout) -> Result<Self, OutputError> {
        let tmp = temporary(path);
        let f = File::create(&tmp).map_err(|e| io_err(&tmp, e))?;
        Ok(Trajectory {
            path: path.to_owned(),
            tmp,
            out: BufWriter::new(f),
            error: None,
            frames: 0,
            layout,
        })
    }

    /// Appends a frame (errors are kept and reported by [`finish`](Self::finish)).
    pub fn write_frame(&mut self, view: &View<'_>) {
        if self.error.is_some() {
            return;
        }
        match self.frame(view) {
            Ok(()) => self.frames += 1,
            Err(e) => self.error = Some(e.to_string()),
        }
    }

    fn frame(&mut self, view: &View<'_>) -> std::io::Result<()> {
        let l = view.lengths;
        let layout = &self.layout;
        let out = &mut self.out;
        let head = |out: &mut BufWriter<File>, lines: usize, props: &str| {
            writeln!(out, "{lines}")?;
            writeln!(
                out,
                "Lattice=\"{} 0 0 0 {} 0 0 0 {}\" Properties={props} Time={} pbc=\"T T T\"",
                l.x, l.y, l.z, view.elapsed
            )
        };
        // Position, velocity, …, then image, element, mass and ASE's momentum.
        let tail = |out: &mut BufWriter<File>, im: [i64; 3], z: u8, m: f64, v: DVec3| {
            let p = v * (m * layout.momentum_unit);
            write!(
                out,
                "{} {} {} {z} {m} {:.10e} {:.10e} {:.10e} ",
                im[0], im[1], im[2], p.x, p.y, p.z
            )
        };
        if layout.atoms() {
            if view.atoms.len() < view.bodies.len() {
                return Err(missing_atoms(view.atoms.len(), view.now));
            }
            let lines = view.atoms.iter().map(|(q, _)| q.len()).sum();
            head(
                out,
                lines,
                "species:S:1:pos:R:3:velo:R:3:map_shift:I:3:Z:I:1:masses:R:1:momenta:R:3:\
                 molecule:I:1:id:I:1",
            )?;
            let mut id = 0;
            for (i, (b, (q, u))) in view.bodies.iter().zip(&view.atoms).enumerate() {
                let (kinds, masses) = match &layout.drawings[b.species as usize] {
                    Drawing::Atoms { kinds, masses } => (kinds.as_slice(), masses.as_slice()),
                    _ => (&[][..], &[][..]),
                };
                let centre = view.unwrapped(i);
                for (a, (&qa, &ua)) in q.iter().zip(u).enumerate() {
                    let (p, im) = wrap_with_image(centre + qa, l);
                    let v = b.v + ua;
                    let (Some(&k), Some(&m)) = (kinds.get(a), masses.get(a)) else {
                        return Err(std::io::Error::other(format!(
                            "molecule {i} has more atoms than its species"
                        )));
                    };
                    let (kind, z) = (
                        &layout.kinds[k as usize].0,
                        layout.kind_elements[k as usize],
                    );
                    write!(
                        out,
                        "{kind} {:.10} {:.10} {:.10} {:.10} {:.10} {:.10} ",
                        p.x, p.y, p.z, v.x, v.y, v.z
                    )?;
                    tail(out, im, z, m, v)?;
                    writeln!(out, "{i} {id}")?;
                    id += 1;
                }
            }
            return Ok(());
        }
        let oriented = !view.attitudes.is_empty();
        let spun = oriented && view.spins.len() == view.bodies.len() && !layout.moments.is_empty();
        let props = match (oriented, spun) {
            (true, true) => {
                "species:S:1:pos:R:3:velo:R:3:orientation:R:4:aspherical_shape:R:3:omega:R:3:\
                 map_shift:I:3:Z:I:1:masses:R:1:momenta:R:3:id:I:1"
            }
            (true, false) => {
                "species:S:1:pos:R:3:velo:R:3:orientation:R:4:aspherical_shape:R:3:\
                 map_shift:I:3:Z:I:1:masses:R:1:momenta:R:3:id:I:1"
            }
            _ => "species:S:1:pos:R:3:velo:R:3:map_shift:I:3:Z:I:1:masses:R:1:momenta:R:3:id:I:1",
        };
        head(out, view.bodies.len(), props)?;
        for (i, b) in view.bodies.iter().enumerate() {
            let s = b.species as usize;
            let (p, im) = wrap_with_image(view.unwrapped(i), l);
            write!(
                out,
                "{} {:.10} {:.10} {:.10} {:.10} {:.10} {:.10} ",
                layout.species[s], p.x, p.y, p.z, b.v.x, b.v.y, b.v.z
            )?;
            if oriented {
                let q = view.attitudes[i];
                let e = layout
                    .drawings
                    .get(s)
                    .and_then(Drawing::semi_axes)
                    .ok_or_else(|| std::io::Error::other(format!("species {s} has no shape")))?;
                write!(
                    out,
                    "{:.12} {:.12} {:.12} {:.12} {} {} {} ",
                    q.x, q.y, q.z, q.w, e[0], e[1], e[2]
                )?;
                if spun {
                    let w = angular_velocity(q, view.spins[i], layout.moments[s]);
                    write!(out, "{:.10} {:.10} {:.10} ", w.x, w.y, w.z)?;
                }
            }
            tail(out, im, layout.elements[s], view.masses[s], b.v)?;
            writeln!(out, "{i}")?;
        }
        Ok(())
    }

    /// Frames written.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Flushes the frames written so far and returns the length of the temporary file and the
    /// frame count (a checkpoint records them).
    ///
    /// # Errors
    /// [`OutputError`] with the first write error of the run, if any.
    pub fn mark(&mut self) -> Result<(u64, u64), OutputError> {
        if let Some(e) = &self.error {
            return Err(io_err(&self.tmp, e));
        }
        self.out.flush().map_err(|e| io_err(&self.tmp, e))?;
        let len = self
            .out
            .get_ref()
            .metadata()
            .map_err(|e| io_err(&self.tmp, e))?
            .len();
        Ok((len, self.frames))
    }

    /// Reopens the temporary file of a trajectory interrupted after `len` bytes and `frames`
    /// frames (a resumed run): frames written after that point are cut off and new ones
    /// appended.
    ///
    /// # Errors
    /// [`OutputError`] if the temporary file is missing or shorter than `len`.
    pub fn reopen(path: &Path, layout: Layout, len: u64, frames: u64) -> Result<Self, OutputError> {
        let tmp = temporary(path);
        let out = cut_to(&tmp, len, "trajectory")?;
        Ok(Trajectory {
            path: path.to_owned(),
            tmp,
            out,
            error: None,
            frames,
            layout,
        })
    }

    /// Flushes and renames the file into place.
    ///
    /// # Errors
    /// [`OutputError`] with the first write error of the run, if any.
    pub fn finish(mut self) -> Result<(), OutputError> {
        if let Some(e) = self.error.take() {
            return Err(io_err(&self.tmp, e));
        }
        self.out.flush().map_err(|e| io_err(&self.tmp, e))?;
        self.out
            .get_ref()
            .sync_all()
            .map_err(|e| io_err(&self.tmp, e))?;
        std::fs::rename(&self.tmp, &self.path).map_err(|e| io_err(&self.path, e))
    }
}

/// A GSD trajectory (HOOMD-blue's format, read by OVITO, freud and Python's `gsd.hoomd`),
/// written to `trajectory.gsd` in place: the `gsd` writer commits each frame, so the file is
/// complete after every frame. Per frame:
///
/// - `configuration/step`: events of the production phase so far; `configuration/box`: the
///   box edges (length);
/// - `particles/position`: positions wrapped into the centred box `[-L/2, L/2)` (length), and
///   `particles/image` the periodic images, so that `position + image · L` is the unwrapped
///   position;
/// - `particles/orientation`: the attitude (body → lab) as `(w, x, y, z)`, the identity for
///   spheres and atoms;
/// - `particles/velocity` (length/time) and, for bodies with an attitude,
///   `particles/angmom`: HOOMD's `2 q ⊗ (0, L_body)` of the spin angular momentum
///   (mass·length²/time; the moments of inertia are not written);
/// - `particles/typeid`, `particles/types`: the species (for semi-flexible molecules, written
///   as their atoms, the site kinds), `particles/type_shapes`: a `Sphere` of the hard-core
///   diameter, a rod's `Ellipsoid` along its body z axis, a site molecule's `SphereUnion` of
///   its sites in its principal frame;
/// - `log/dmd/time`: the production time (time), `log/dmd/kinetic_energy` and
///   `log/dmd/potential_energy` (energy).
///
/// Units are the run's internal ones (those of `trajectory.xyz`); GSD records none.
#[derive(Debug)]
pub struct GsdTrajectory {
    path: PathBuf,
    writer: gsd::Writer,
    layout: Layout,
    error: Option<String>,
}

impl GsdTrajectory {
    /// Creates `path` (replacing any file there) for bodies drawn as `layout` says.
    ///
    /// # Errors
    /// [`OutputError`].
    pub fn create(path: &Path, layout: Layout) -> Result<Self, OutputError> {
        let writer = gsd::Writer::create(path, "dmd").map_err(|e| io_err(path, e))?;
        Ok(GsdTrajectory {
            path: path.to_owned(),
            writer,
            layout,
            error: None,
        })
    }

    /// Continues the trajectory of a resumed run at the `frames` frames a checkpoint recorded:
    /// frames written after that point are dropped. The file is rebuilt from its first
    /// `frames` frames (a GSD file's index and name list are rewritten in place as it grows,
    /// so cutting its bytes would not do), then appended to, which leaves exactly the bytes an
    /// uninterrupted run writes.
    ///
    /// # Errors
    /// [`OutputError`] if the file is missing, unreadable or holds fewer frames.
    pub fn reopen(path: &Path, layout: Layout, frames: u64) -> Result<Self, OutputError> {
        let fail = |e: &dyn std::fmt::Display| {
            io_err(path, format!("cannot continue the GSD trajectory: {e}"))
        };
        let mut reader = gsd::Reader::open(path).map_err(|e| fail(&e))?;
        if reader.frames() < frames {
            return Err(fail(&format!(
                "it has {} frames, the checkpoint recorded {frames}",
                reader.frames()
            )));
        }
        let tmp = temporary(path);
        let mut writer = gsd::Writer::create(&tmp, "dmd").map_err(|e| fail(&e))?;
        for k in 0..frames {
            let frame = reader.read_frame(k).map_err(|e| fail(&e))?;
            writer.append(&frame).map_err(|e| fail(&e))?;
        }
        writer.finish().map_err(|e| fail(&e))?;
        drop(reader);
        std::fs::rename(&tmp, path).map_err(|e| io_err(path, e))?;
        let writer = gsd::Writer::append_to(path).map_err(|e| fail(&e))?;
        Ok(GsdTrajectory {
            path: path.to_owned(),
            writer,
            layout,
            error: None,
        })
    }

    /// The type names and shapes of the frames.
    fn types(&self) -> Result<(Vec<String>, Vec<gsd::Shape>), String> {
        if self.layout.atoms() {
            let names = self.layout.kinds.iter().map(|(n, _)| n.clone()).collect();
            let shapes = self
                .layout
                .kinds
                .iter()
                .map(|&(_, d)| gsd::Shape::Sphere { diameter: d })
                .collect();
            return Ok((names, shapes));
        }
        let mut shapes = Vec::with_capacity(self.layout.drawings.len());
        for d in &self.layout.drawings {
            shapes.push(match d {
                Drawing::Sphere { diameter } => gsd::Shape::Sphere {
                    diameter: *diameter,
                },
                Drawing::Rod { semi_axes } => gsd::Shape::Ellipsoid {
                    a: semi_axes[0],
                    b: semi_axes[1],
                    c: semi_axes[2],
                },
                Drawing::Sites { centres, diameters } => {
                    // GSD's SphereUnion (OVITO draws it): the sites in the body frame.
                    let num = |x: f64| {
                        if x.is_finite() {
                            Ok(format!("{x:?}"))
                        } else {
                            Err(format!("a site of the drawing is at {x}"))
                        }
                    };
                    let mut cs = Vec::with_capacity(centres.len());
                    for c in centres {
                        cs.push(format!("[{},{},{}]", num(c.x)?, num(c.y)?, num(c.z)?));
                    }
                    let ds = diameters
                        .iter()
                        .map(|&d| num(d))
                        .collect::<Result<Vec<_>, _>>()?;
                    gsd::Shape::Other(format!(
                        r#"{{"type":"SphereUnion","centers":[{}],"diameters":[{}]}}"#,
                        cs.join(","),
                        ds.join(",")
                    ))
                }
                Drawing::Atoms { .. } => gsd::Shape::Undefined,
            });
        }
        Ok((self.layout.species.clone(), shapes))
    }

    /// The frame of `view`.
    fn frame_of(&self, view: &View<'_>) -> Result<gsd::Frame, String> {
        let l = view.lengths;
        // Wrapped into [-L/2, L/2) in single precision, with the image that restores the
        // unwrapped position; a coordinate that rounds up to +L/2 goes to −L/2 (same point).
        let wrap = |u: DVec3| -> ([f32; 3], [i32; 3]) {
            let mut p = [0.0f32; 3];
            let mut im = [0i32; 3];
            for k in 0..3 {
                let (x, len) = (u[k], l[k]);
                let n = ((x + 0.5 * len) / len).floor();
                let mut w = (x - n * len) as f32;
                let mut n = n as i32;
                let half = (0.5 * len) as f32;
                if w >= half {
                    w = -half;
                    n += 1;
                }
                p[k] = w;
                im[k] = n;
            }
            (p, im)
        };
        let f3 = |v: DVec3| v.as_vec3().to_array();
        let (types, type_shapes) = self.types()?;
        let mut frame = gsd::Frame {
            step: view.events,
            sim_box: gsd::SimBox::orthorhombic(l.x as f32, l.y as f32, l.z as f32),
            types,
            type_shapes,
            ..gsd::Frame::default()
        };
        let identity = [1.0f32, 0.0, 0.0, 0.0];
        let mut orientation = Vec::new();
        let mut velocity = Vec::new();
        let mut image = Vec::new();
        if self.layout.atoms() {
            if view.atoms.len() < view.bodies.len() {
                return Err(missing_atoms(view.atoms.len(), view.now).to_string());
            }
            for (i, (b, (q, u))) in view.bodies.iter().zip(&view.atoms).enumerate() {
                let kinds = match &self.layout.drawings[b.species as usize] {
                    Drawing::Atoms { kinds, .. } => kinds.as_slice(),
                    _ => &[],
                };
                let centre = view.unwrapped(i);
                for (a, (&qa, &ua)) in q.iter().zip(u).enumerate() {
                    let (p, im) = wrap(centre + qa);
                    frame.position.push(p);
                    image.push(im);
                    velocity.push(f3(b.v + ua));
                    orientation.push(identity);
                    frame.typeid.push(
                        *kinds.get(a).ok_or_else(|| {
                            format!("molecule {i} has more atoms than its species")
                        })?,
                    );
                }
            }
        } else {
            let oriented = view.attitudes.len() == view.bodies.len();
            let spun = oriented && view.spins.len() == view.bodies.len();
            let mut angmom = Vec::new();
            for (i, b) in view.bodies.iter().enumerate() {
                let (p, im) = wrap(view.unwrapped(i));
                frame.position.push(p);
                image.push(im);
                velocity.push(f3(b.v));
                frame.typeid.push(b.species);
                if oriented {
                    let q = view.attitudes[i];
                    orientation.push([q.w as f32, q.x as f32, q.y as f32, q.z as f32]);
                    if spun {
                        // HOOMD's conjugate momentum 2 q ⊗ (0, L_body) = 2 (0, L_lab) ⊗ q.
                        let s = view.spins[i];
                        let p = (DQuat::from_xyzw(s.x, s.y, s.z, 0.0) * q) * 2.0;
                        angmom.push([p.w as f32, p.x as f32, p.y as f32, p.z as f32]);
                    }
                } else {
                    orientation.push(identity);
                }
            }
            if spun {
                frame.angmom = Some(angmom);
            }
        }
        frame.orientation = Some(orientation);
        frame.velocity = Some(velocity);
        frame.image = Some(image);
        for (key, x) in [
            ("dmd/time", view.elapsed),
            ("dmd/kinetic_energy", view.kinetic),
            ("dmd/potential_energy", view.potential),
        ] {
            frame.log.insert(key.to_owned(), gsd::Chunk::scalar(x));
        }
        Ok(frame)
    }

    /// Appends and commits a frame (errors are kept and reported by
    /// [`finish`](Self::finish)).
    pub fn write_frame(&mut self, view: &View<'_>) {
        if self.error.is_some() {
            return;
        }
        let result = self
            .frame_of(view)
            .and_then(|frame| self.writer.append(&frame).map_err(|e| e.to_string()));
        if let Err(e) = result {
            self.error = Some(e);
        }
    }

    /// Frames in the file.
    pub fn frames(&self) -> u64 {
        self.writer.frames()
    }

    /// The frame count a checkpoint records, with the frames put on disk.
    ///
    /// # Errors
    /// [`OutputError`] with the first write error of the run, if any.
    pub fn mark(&mut self) -> Result<u64, OutputError> {
        if let Some(e) = &self.error {
            return Err(io_err(&self.path, e));
        }
        self.writer.flush().map_err(|e| io_err(&self.path, e))?;
        Ok(self.frames())
    }

    /// Puts the file on disk and closes it.
    ///
    /// # Errors
    /// [`OutputError`] with the first write error of the run, if any.
    pub fn finish(self) -> Result<(), OutputError> {
        if let Some(e) = &self.error {
            return Err(io_err(&self.path, e));
        }
        self.writer.finish().map_err(|e| io_err(&self.path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Numbers in messages are short and exact: what the scene said, read back unchanged.
    #[test]
    fn given_numbers_are_short_and_read_back_exactly() {
        for (x, text) in [
            (1e20, "1e20"),
            (-1e300, "-1e300"),
            (2.5, "2.5"),
            (1e-9, "1e-9"),
            (0.0, "0"),
            (150.0, "150"),
            (f64::INFINITY, "inf"),
            (123456789012345.0, "123456789012345"),
            (0.1 + 0.2, "0.30000000000000004"),
        ] {
            assert_eq!(given(x), text);
            assert_eq!(given(x).parse::<f64>().unwrap(), x);
        }
        for k in -320..309 {
            let x = 1.2345 * 10f64.powi(k);
            let s = given(x);
            assert!(s.len() <= 24, "{s}");
            assert_eq!(s.parse::<f64>().unwrap(), x);
        }
    }

    /// A streamed table is byte for byte the table written at once, also when it is cut at a
    /// mark and continued (a resumed run): no row lost or doubled.
    #[test]
    fn a_streamed_table_is_the_table_written_at_once_and_continues_at_its_mark() {
        let dir = std::env::temp_dir().join(format!("dmd-csv-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rows: Vec<Vec<f64>> = (0..50)
            .map(|k| {
                let x = k as f64;
                vec![0.1 * x, 1.0 / (x + 3.0), -x * 1e-300, 2e300 / (x + 1.0)]
            })
            .collect();
        let header = ["a", "b", "c", "d"];
        let whole = dir.join("whole.csv");
        write_csv(&whole, &header, &rows).unwrap();
        let streamed = dir.join("streamed.csv");
        let mut s = CsvStream::create(&streamed, &header).unwrap();
        for r in &rows[..20] {
            s.write_row(r);
        }
        let mark = s.mark().unwrap();
        // Rows the stopped run wrote after its checkpoint, then lost with it.
        for r in &rows[20..27] {
            s.write_row(r);
        }
        s.mark().unwrap();
        drop(s);
        assert!(
            !streamed.exists(),
            "only the temporary file exists until finished"
        );
        let mut s = CsvStream::reopen(&streamed, mark).unwrap();
        for r in &rows[20..] {
            s.write_row(r);
        }
        assert_eq!(s.finish().unwrap(), streamed);
        assert_eq!(
            std::fs::read(&streamed).unwrap(),
            std::fs::read(&whole).unwrap()
        );
        // A temporary file shorter than the mark is refused.
        let mut s = CsvStream::create(&streamed, &header).unwrap();
        s.write_row(&rows[0]);
        let short_mark = s.mark().unwrap();
        drop(s);
        let e = CsvStream::reopen(&streamed, short_mark + 1).unwrap_err();
        assert!(e.to_string().contains("the checkpoint recorded"), "{e}");
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn csv_numbers_read_back_to_the_same_bits() {
        let dir = std::env::temp_dir().join(format!("dmd-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.csv");
        let xs = [
            0.1,
            1.0 / 3.0,
            2.0f64.sqrt() * 1e-300,
            6.02214076e23,
            -123456.78901234567,
            f64::MIN_POSITIVE,
            f64::MAX,
            0.0,
        ];
        write_csv(
            &path,
            &["x"],
            &xs.iter().map(|&x| vec![x]).collect::<Vec<_>>(),
        )
        .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let back: Vec<f64> = text.lines().skip(1).map(|l| l.parse().unwrap()).collect();
        for (a, b) in xs.iter().zip(&back) {
            assert_eq!(a.to_bits(), b.to_bits(), "{a} wrote {b}");
        }
        // Short: 0.1 is written as 1e-1, not 1.0000000000e-1.
        assert_eq!(text.lines().nth(1), Some("1e-1"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn elements_by_symbol_name_or_none() {
        assert_eq!(atomic_number("O"), Some(8));
        assert_eq!(atomic_number("Og"), Some(118));
        assert_eq!(atomic_number("X"), Some(0));
        assert_eq!(atomic_number("o"), None);
        assert_eq!(element_of("Ar", None), 18);
        assert_eq!(element_of("rod", None), 0);
        assert_eq!(element_of("water", Some("O")), 8);
        assert_eq!(element_of("S", Some("X")), 0);
    }

    #[test]
    fn images_restore_the_unwrapped_position() {
        let l = DVec3::new(2.0, 3.0, 5.0);
        for u in [
            DVec3::new(-0.5, 7.25, 4.999),
            DVec3::new(2.0, -3.0, 0.0),
            DVec3::new(-1e-17, 1e6 + 0.1, -12.5),
        ] {
            let (p, n) = wrap_with_image(u, l);
            for k in 0..3 {
                assert!((0.0..l[k]).contains(&p[k]), "{u} → {p}");
                let back = p[k] + n[k] as f64 * l[k];
                assert!(
                    (back - u[k]).abs() <= 1e-9 * (1.0 + u[k].abs()),
                    "{u} → {p}, {n:?}"
                );
            }
        }
    }

    #[test]
    fn angular_velocity_from_momentum_and_moments() {
        // A rod along x (body z turned onto x) spinning about lab z: ω = L / I.
        let q = axis_quaternion(DVec3::X);
        let w = angular_velocity(q, DVec3::new(0.0, 0.0, 2.0), [0.5, 0.5, 0.0]);
        assert!((w - DVec3::new(0.0, 0.0, 4.0)).length() < 1e-12, "{w}");
        // An asymmetric top: ω_body = L_body / I component by component.
        let q = DQuat::from_euler(glam::EulerRot::ZYX, 0.3, -1.1, 2.0);
        let wb = DVec3::new(0.7, -1.3, 2.2);
        let i = [1.0, 2.0, 3.0];
        let l = q * (DVec3::from(i) * wb);
        assert!((angular_velocity(q, l, i) - q * wb).length() < 1e-12);
    }

    #[test]
    fn atomic_write_leaves_no_partial_file() {
        let dir = std::env::temp_dir().join(format!("dmd-out-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("t.csv");
        write_csv(&p, &["a", "b"], &[vec![1.0, 2.0]]).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.starts_with("a,b\n1e0,2e0"));
        assert!(!temporary(&p).exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
