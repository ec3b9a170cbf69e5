//! Files a run writes: `summary.json`, observables as CSV with an SVG plot each, and an
//! extended XYZ trajectory. Every file is written to a temporary name in the output folder and
//! renamed into place when complete, so a crash never leaves a half-written result behind.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::engine::simulation::View;

/// Bytes of one row of `series.csv` (six numbers in full precision; also more than its 48
/// bytes in memory).
pub const SERIES_ROW_BYTES: f64 = 150.0;

/// Bytes of one lag of the correlation buffers (MSD, VACF, two orientational ACFs, count).
pub const LAG_BYTES: f64 = 40.0;

/// Bytes per body of one trajectory frame: species name, position and velocity with ten
/// decimals and the id; rods add a quaternion with twelve and the shape.
pub fn trajectory_line_bytes(rods: bool) -> f64 {
    if rods { 190.0 } else { 110.0 }
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
        let cells: Vec<String> = row.iter().map(|x| format!("{x:e}")).collect();
        text.push_str(&cells.join(","));
        text.push('\n');
    }
    write_atomically(path, text.as_bytes())
}

/// One curve of a plot.
pub struct Curve<'a> {
    /// Legend.
    pub label: &'a str,
    /// Points.
    pub points: Vec<(f64, f64)>,
}

/// Draws curves into an SVG file (written atomically).
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
    use plotters::prelude::*;
    let tmp = temporary(path);
    let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let all: Vec<(f64, f64)> = curves
        .iter()
        .flat_map(|c| c.points.iter().filter(finite).copied())
        .collect();
    if all.is_empty() {
        return Ok(());
    }
    let (mut x0, mut x1, mut y0, mut y1) = all.iter().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), p| (a.min(p.0), b.max(p.0), c.min(p.1), d.max(p.1)),
    );
    if x1 <= x0 {
        x1 = x0 + 1.0;
        x0 -= 1.0;
    }
    let pad = 0.05 * (y1 - y0).abs().max(1e-12 * y1.abs()).max(1e-300);
    y0 -= pad;
    y1 += pad;
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::new(&tmp, (720, 420)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .draw()?;
        let colors = [BLUE, RED, BLACK, GREEN, MAGENTA, CYAN];
        for (k, c) in curves.iter().enumerate() {
            let color = colors[k % colors.len()];
            let pts: Vec<(f64, f64)> = c.points.iter().filter(finite).copied().collect();
            chart
                .draw_series(LineSeries::new(pts, color.stroke_width(2)))?
                .label(c.label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color));
        }
        if curves.len() > 1 {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()?;
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| io_err(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| io_err(path, e))
}

/// An extended XYZ trajectory (readable by OVITO): per frame the body count, a comment line
/// with `Lattice`, `Properties=species:S:1:pos:R:3:velo:R:3:id:I:1` and `Time`, and one line per
/// body. Rods add `orientation:R:4` (unit quaternion, scalar last) and `aspherical_shape:R:3`
/// before the id. Written to `trajectory.xyz.partial` and renamed when the run ends.
#[derive(Debug)]
pub struct Trajectory {
    path: PathBuf,
    tmp: PathBuf,
    out: BufWriter<File>,
    names: Vec<String>,
    error: Option<String>,
    frames: u64,
    shape: [f64; 3],
}

/// Semi-axes of the ellipsoid a rod is drawn as, unless [`Trajectory::with_shape`] says
/// otherwise.
const ROD_SHAPE: [f64; 3] = [0.5, 0.5, 1.5];

/// The unit quaternion (shortest arc) that turns `z` into `axis`.
pub fn axis_quaternion(axis: glam::DVec3) -> glam::DQuat {
    glam::DQuat::from_rotation_arc(glam::DVec3::Z, axis.normalize())
}

impl Trajectory {
    /// Opens `path` (as a temporary file) for species `names`.
    ///
    /// # Errors
    /// [`OutputError`].
    pub fn create(path: &Path, names: Vec<String>) -> Result<Self, OutputError> {
        let tmp = temporary(path);
        let f = File::create(&tmp).map_err(|e| io_err(&tmp, e))?;
        Ok(Trajectory {
            path: path.to_owned(),
            tmp,
            out: BufWriter::new(f),
            names,
            error: None,
            frames: 0,
            shape: ROD_SHAPE,
        })
    }

    /// The same trajectory drawing rods as ellipsoids of semi-axes `shape` (for OVITO's
    /// aspherical shape; the third is along the rod).
    pub fn with_shape(mut self, shape: [f64; 3]) -> Self {
        self.shape = shape;
        self
    }

    /// Appends a frame (errors are kept and reported by [`finish`](Self::finish)).
    pub fn write_frame(&mut self, view: &View<'_>) {
        if self.error.is_some() {
            return;
        }
        let l = view.lengths;
        let mut go = || -> std::io::Result<()> {
            writeln!(self.out, "{}", view.bodies.len())?;
            let rods = !view.axes.is_empty();
            let props = if rods {
                "species:S:1:pos:R:3:velo:R:3:orientation:R:4:aspherical_shape:R:3:id:I:1"
            } else {
                "species:S:1:pos:R:3:velo:R:3:id:I:1"
            };
            writeln!(
                self.out,
                "Lattice=\"{} 0 0 0 {} 0 0 0 {}\" Properties={props} Time={} pbc=\"T T T\"",
                l.x, l.y, l.z, view.elapsed
            )?;
            for (i, b) in view.bodies.iter().enumerate() {
                let p = view.position(i);
                let p = glam::DVec3::new(
                    p.x.rem_euclid(l.x),
                    p.y.rem_euclid(l.y),
                    p.z.rem_euclid(l.z),
                );
                write!(
                    self.out,
                    "{} {:.10} {:.10} {:.10} {:.10} {:.10} {:.10} ",
                    self.names[b.species as usize], p.x, p.y, p.z, b.v.x, b.v.y, b.v.z
                )?;
                if rods {
                    // The rotation taking the body's long axis z to the rod's axis, as a unit
                    // quaternion with the scalar last (OVITO's Orientation); the shape draws
                    // the rod as an ellipsoid three times as long as it is wide.
                    let q = axis_quaternion(view.axes[i]);
                    write!(
                        self.out,
                        "{:.12} {:.12} {:.12} {:.12} {} {} {} ",
                        q.x, q.y, q.z, q.w, self.shape[0], self.shape[1], self.shape[2]
                    )?;
                }
                writeln!(self.out, "{i}")?;
            }
            Ok(())
        };
        match go() {
            Ok(()) => self.frames += 1,
            Err(e) => self.error = Some(e.to_string()),
        }
    }

    /// Frames written.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Flushes the frames written so far and returns the length of the temporary file and the
    /// frame count (a checkpoint records them, issue 9).
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
    /// frames (a resumed run, issue 9): frames written after that point are cut off and new
    /// ones appended.
    ///
    /// # Errors
    /// [`OutputError`] if the temporary file is missing or shorter than `len`.
    pub fn reopen(
        path: &Path,
        names: Vec<String>,
        len: u64,
        frames: u64,
    ) -> Result<Self, OutputError> {
        let tmp = temporary(path);
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(&tmp)
            .map_err(|e| io_err(&tmp, format!("cannot continue the trajectory: {e}")))?;
        let have = f.metadata().map_err(|e| io_err(&tmp, e))?.len();
        if have < len {
            return Err(io_err(
                &tmp,
                format!(
                    "cannot continue the trajectory: it has {have} bytes, the checkpoint \
                     recorded {len}"
                ),
            ));
        }
        f.set_len(len).map_err(|e| io_err(&tmp, e))?;
        let mut out = BufWriter::new(f);
        std::io::Seek::seek(&mut out, std::io::SeekFrom::End(0)).map_err(|e| io_err(&tmp, e))?;
        Ok(Trajectory {
            path: path.to_owned(),
            tmp,
            out,
            names,
            error: None,
            frames,
            shape: ROD_SHAPE,
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

#[cfg(test)]
mod tests {
    use super::*;

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
