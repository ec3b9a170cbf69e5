//! SVG line and point plots for the validation report (plotters, SVG backend only).

use std::path::Path;

use plotters::prelude::*;

/// One curve: a label and its points.
pub(crate) struct Curve {
    pub(crate) label: String,
    pub(crate) points: Vec<(f64, f64)>,
}

/// Axis kind.
#[derive(Clone, Copy)]
pub(crate) enum Axis {
    Linear,
    Log,
}

const COLORS: [RGBColor; 6] = [
    RGBColor(200, 30, 30),
    RGBColor(30, 80, 200),
    RGBColor(20, 150, 60),
    RGBColor(170, 60, 170),
    RGBColor(230, 140, 0),
    RGBColor(0, 0, 0),
];

/// A tick label: plain decimals for ordinary magnitudes, exponents otherwise.
fn tick(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if (1e-2..1e4).contains(&a) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        format!("{v:.1e}")
    }
}

fn range(values: impl Iterator<Item = f64>, axis: Axis) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (matches!(axis, Axis::Linear) || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    match axis {
        Axis::Linear => {
            let pad = 0.05 * (hi - lo).max(1e-12 * hi.abs()).max(1e-300);
            (lo - pad, hi + pad)
        }
        Axis::Log => (lo / 1.5, hi * 1.5),
    }
}

/// Draws `curves` as lines (`markers`: also a circle at every point) into `path`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    curves: &[Curve],
    x_axis: Axis,
    y_axis: Axis,
    markers: bool,
) -> Result<(), String> {
    let xs = range(
        curves.iter().flat_map(|c| c.points.iter().map(|p| p.0)),
        x_axis,
    );
    let ys = range(
        curves.iter().flat_map(|c| c.points.iter().map(|p| p.1)),
        y_axis,
    );
    let root = SVGBackend::new(path, (760, 460)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70);
    macro_rules! draw {
        ($chart:expr) => {{
            let mut chart = $chart.map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc(x_label)
                .y_desc(y_label)
                .x_label_formatter(&|v| tick(*v))
                .y_label_formatter(&|v| tick(*v))
                .draw()
                .map_err(|e| e.to_string())?;
            for (k, c) in curves.iter().enumerate() {
                let col = COLORS[k % COLORS.len()];
                let pts: Vec<(f64, f64)> = c
                    .points
                    .iter()
                    .copied()
                    .filter(|p| {
                        p.0.is_finite()
                            && p.1.is_finite()
                            && (matches!(x_axis, Axis::Linear) || p.0 > 0.0)
                            && (matches!(y_axis, Axis::Linear) || p.1 > 0.0)
                    })
                    .collect();
                chart
                    .draw_series(LineSeries::new(pts.iter().copied(), col.stroke_width(2)))
                    .map_err(|e| e.to_string())?
                    .label(c.label.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2))
                    });
                if markers {
                    chart
                        .draw_series(pts.iter().map(|p| Circle::new(*p, 4, col.filled())))
                        .map_err(|e| e.to_string())?;
                }
            }
            chart
                .configure_series_labels()
                .border_style(BLACK)
                .background_style(WHITE.mix(0.9))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| e.to_string())?;
        }};
    }
    match (x_axis, y_axis) {
        (Axis::Linear, Axis::Linear) => draw!(builder.build_cartesian_2d(xs.0..xs.1, ys.0..ys.1)),
        (Axis::Log, Axis::Linear) => {
            draw!(builder.build_cartesian_2d((xs.0..xs.1).log_scale(), ys.0..ys.1))
        }
        (Axis::Linear, Axis::Log) => {
            draw!(builder.build_cartesian_2d(xs.0..xs.1, (ys.0..ys.1).log_scale()))
        }
        (Axis::Log, Axis::Log) => {
            draw!(builder.build_cartesian_2d((xs.0..xs.1).log_scale(), (ys.0..ys.1).log_scale()))
        }
    }
    root.present().map_err(|e| e.to_string())
}
