//! The plots `dmd run` writes: axis labels with the scene's units, a caption naming the
//! system, means with error bands, partial g(r) for mixtures, and no plot that shows nothing.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::support::{WELL_FLUID, scenes_dir, scratch};

/// Runs `dmd run scenes/<scene> --out <dir> --set …` (quietly) and returns the summary.
fn dmd_run(scene: &str, dir: &Path, extra: &[&str], sets: &[&str]) -> serde_json::Value {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dmd"));
    c.arg("run")
        .arg(scenes_dir().join(scene))
        .arg("--out")
        .arg(dir)
        .arg("--quiet")
        .args(extra);
    for s in sets {
        c.args(["--set", s]);
    }
    let out = c.output().unwrap();
    assert!(
        out.status.success(),
        "{scene}: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// The contents of the `<text>` elements of an SVG file, unescaped.
fn svg_texts(path: &Path) -> Vec<String> {
    let svg = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut texts = Vec::new();
    let mut rest = svg.as_str();
    while let Some(start) = rest.find("<text") {
        rest = &rest[start..];
        let open = rest.find('>').expect("a text element closes its tag");
        let close = rest.find("</text>").expect("a text element ends");
        let inner = &rest[open + 1..close];
        texts.push(
            inner
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&quot;", "\"")
                .replace("&apos;", "'")
                .replace("&amp;", "&")
                .trim()
                .to_owned(),
        );
        rest = &rest[close + 7..];
    }
    texts
}

/// Whether some text of `texts` contains `what`.
fn has(texts: &[String], what: &str) -> bool {
    texts.iter().any(|t| t.contains(what))
}

/// The number after `key` in the first text that holds it (`T = 530.5 K` → 530.5).
fn number_after(texts: &[String], key: &str) -> f64 {
    let t = texts
        .iter()
        .find(|t| t.contains(key))
        .unwrap_or_else(|| panic!("no text with {key:?} in {texts:?}"));
    let tail = &t[t.find(key).unwrap() + key.len()..];
    let num: String = tail
        .chars()
        .take_while(|c| c.is_ascii_digit() || matches!(c, '.' | '-' | 'e' | '+'))
        .collect();
    num.parse()
        .unwrap_or_else(|e| panic!("{key:?} in {t:?}: {num:?}: {e}"))
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

/// Every plot of a rods run in molecular units: axis labels in Å, ps, Å², kJ/mol and bar, a
/// caption naming the scene with N, T and ρ, the pressure's mean and error from the summary.
fn check_rods_plots(dir: &Path, s: &serde_json::Value, engine: &str) {
    let t = s["temperature"].as_f64().unwrap();
    let n = s["n_bodies"].as_u64().unwrap();
    let rho = s["density"].as_f64().unwrap();
    let svgs = [
        "rdf",
        "msd",
        "vacf",
        "oacf",
        "series-energy",
        "series-pressure",
    ];
    for name in &svgs {
        let texts = svg_texts(&dir.join(format!("{name}.svg")));
        let what = format!("{engine} {name}.svg: {texts:?}");
        assert!(has(&texts, "rods-paper: "), "{what}");
        assert!(has(&texts, &format!("N = {n},")), "{what}");
        // The caption's T and ρ are the summary's, to the four digits shown, with units.
        assert!(close(number_after(&texts, "T = "), t, 1e-3), "{what}");
        assert!(has(&texts, " K, ρ = "), "{what}");
        assert!(close(number_after(&texts, "ρ = "), rho, 1e-3), "{what}");
        assert!(has(&texts, " Å⁻³"), "{what}");
        if *name != "rdf" {
            assert!(texts.iter().any(|x| x == "t (ps)"), "{what}");
        }
    }
    let rdf = svg_texts(&dir.join("rdf.svg"));
    assert!(
        rdf.iter().any(|x| x == "r (Å)") && has(&rdf, "g(r)"),
        "{rdf:?}"
    );
    let msd = svg_texts(&dir.join("msd.svg"));
    assert!(msd.iter().any(|x| x == "MSD (Å²)"), "{msd:?}");
    // The fit's D, in Å²/ps, is the summary's diffusion_msd.
    let d = s["diffusion_msd"].as_f64().unwrap();
    assert!(has(&msd, " Å²/ps"), "{msd:?}");
    assert!(
        close(number_after(&msd, "D = "), d, 1e-3),
        "{msd:?} vs D = {d}"
    );
    let vacf = svg_texts(&dir.join("vacf.svg"));
    assert!(
        has(&vacf, "Å²/ps²") && has(&vacf, "(dimensionless)"),
        "{vacf:?}"
    );
    let energy = svg_texts(&dir.join("series-energy.svg"));
    assert!(has(&energy, "energy per body (kJ/mol)"), "{energy:?}");
    for curve in ["K/N", "U/N", "E/N"] {
        let entry = format!("{curve}: mean ");
        assert!(
            energy.iter().any(|x| x.starts_with(&entry)),
            "{curve}: {energy:?}"
        );
    }
    // U/N's mean line is the summary's potential energy per body.
    let u = s["potential_energy_per_body"].as_f64().unwrap();
    let means: Vec<f64> = energy
        .iter()
        .filter(|x| x.contains(": mean "))
        .map(|x| number_after(std::slice::from_ref(x), "mean "))
        .collect();
    assert_eq!(means.len(), 3, "{energy:?}");
    // Means are shown to the decimals of their error's two digits: within 5 % of the error.
    let du = s["potential_energy_per_body_error"].as_f64().unwrap();
    assert!(
        means
            .iter()
            .any(|&m| (m - u).abs() <= 0.05 * du + 1e-3 * u.abs()),
        "{means:?} vs U/N {u} ± {du}"
    );
    // Per body: K/N of rods is 5/2 kT per body, about 10.5 kJ/mol at 505 K (totals would be
    // 512 times that).
    let kt = 8.314_462_618e-3 * t;
    assert!(
        means.iter().any(|&m| close(m, 2.5 * kt, 0.01)),
        "{means:?} vs 5kT/2 = {}",
        2.5 * kt
    );
    let pressure = svg_texts(&dir.join("series-pressure.svg"));
    assert!(pressure.iter().any(|x| x == "P (bar)"), "{pressure:?}");
    let p = s["pressure"].as_f64().unwrap();
    let dp = s["pressure_error"].as_f64().unwrap();
    let shown = number_after(&pressure, "mean ");
    assert!(
        (shown - p).abs() <= 0.05 * dp + 1e-3 * p.abs(),
        "{pressure:?} vs {p}"
    );
    // The error to two significant digits.
    assert!(
        close(number_after(&pressure, " ± "), dp, 0.05),
        "{pressure:?} vs {dp}"
    );
    assert!(has(&pressure, " bar"), "{pressure:?}");
    // The error band: a translucent rectangle across the plot, as tall as ± the error.
    let svg = std::fs::read_to_string(dir.join("series-pressure.svg")).unwrap();
    let band = svg.lines().any(|l| {
        let attr = |name: &str| -> Option<f64> {
            let start = l.find(&format!(" {name}=\""))? + name.len() + 3;
            l[start..].split('"').next()?.parse().ok()
        };
        l.starts_with("<rect")
            && attr("opacity") == Some(0.22)
            && attr("width").is_some_and(|w| w > 500.0)
            && attr("height").is_some_and(|h| h >= 1.0)
    });
    assert!(band, "no error band in series-pressure.svg");
}

#[test]
fn rods_plots_carry_units_and_name_the_system() {
    let dir = scratch("plots-rods");
    let s = dmd_run(
        "rods-paper.toml",
        &dir,
        &[],
        &["run.equilibration_time=0.2", "run.time=0.3"],
    );
    check_rods_plots(&dir, &s, "dmd");
    // Terraced rods: the caption gives the terrace step, kT/2 = 2.100 kJ/mol at 505.144 K.
    let texts = svg_texts(&dir.join("rdf.svg"));
    let dv = number_after(&texts, "ΔV = ");
    assert!(close(dv, 0.5 * 8.314_462_618e-3 * 505.144, 1e-3), "{dv}");
    assert!(has(&texts, " kJ/mol"), "{texts:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The correlation functions and g(r) carry their block-average errors as translucent bands
/// around the curves (where a point has an error: 16 time origins or configurations).
#[test]
fn correlation_and_rdf_plots_draw_their_error_bands() {
    let fluid = format!(
        "{WELL_FLUID}[run]\ntime = 20.0\n[output]\nsample_interval = 0.05\n\
         rdf = {{ bins = 30, r_max = 2.5, every = 1 }}\nmsd = {{ max_lag = 0.5 }}\n\
         vacf = {{ max_lag = 0.5 }}\n"
    );
    let dir = scratch("plots-bands");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("fluid.toml");
    std::fs::write(&file, fluid).unwrap();
    let out = dir.join("out");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_dmd"))
        .args(["run", "--quiet", "--out"])
        .arg(&out)
        .arg(&file)
        .status()
        .unwrap();
    assert!(status.success());
    for (file, csv) in [
        ("msd", "msd_error"),
        ("vacf", "vacf_error"),
        ("rdf", "g_error"),
    ] {
        let (header, rows) = read_csv(&out.join(format!("{file}.csv")));
        let col = header.iter().position(|h| h == csv).unwrap();
        assert!(
            rows.iter().any(|r| r[col].is_finite() && r[col] > 0.0),
            "{file}: no errors"
        );
        let svg = std::fs::read_to_string(out.join(format!("{file}.svg"))).unwrap();
        assert!(
            svg.lines()
                .any(|l| l.starts_with("<polygon") && l.contains("opacity=\"0.2\"")),
            "no error band in {file}.svg"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn smd_rods_plots_carry_units_and_name_the_system() {
    let dir = scratch("plots-rods-smd");
    let s = dmd_run(
        "rods-paper.toml",
        &dir,
        &["--engine", "smd"],
        &["run.equilibration_time=0.09", "run.time=0.18"],
    );
    check_rods_plots(&dir, &s, "smd");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The columns of a CSV file: header names and rows.
fn read_csv(path: &PathBuf) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn a_mixture_writes_partial_rdfs_whose_weighted_sum_is_the_total() {
    let dir = scratch("plots-mixture");
    let (ns, nl) = (200.0f64, 56.0f64);
    let s = dmd_run(
        "mixture.toml",
        &dir,
        &[],
        &[
            "species.0.count=200",
            "species.1.count=56",
            // Dilute enough for a simple lattice of 256 to keep the large cores apart.
            "box.density=0.15",
            "run.equilibration_events=5e3",
            "run.events=2e4",
            "output.sample_interval=0.05",
            "output.rdf.every=1",
            "output.trajectory.interval=1e3",
        ],
    );
    assert_eq!(s["n_bodies"].as_u64(), Some(256));
    let (header, rows) = read_csv(&dir.join("rdf.csv"));
    assert_eq!(
        header,
        [
            "r",
            "g",
            "g_error",
            "g_S_S",
            "g_S_S_error",
            "g_S_L",
            "g_S_L_error",
            "g_L_L",
            "g_L_L_error"
        ]
    );
    let n = ns + nl;
    let w = [
        ns * (ns - 1.0) / (n * (n - 1.0)),
        2.0 * ns * nl / (n * (n - 1.0)),
        nl * (nl - 1.0) / (n * (n - 1.0)),
    ];
    let mut seen = 0;
    for row in &rows {
        let partials = [row[3], row[5], row[7]];
        let sum: f64 = w.iter().zip(&partials).map(|(w, g)| w * g).sum();
        // Each partial's error is there wherever its g is (the blocks of 400 samples).
        for e in [row[4], row[6], row[8]] {
            assert!(e.is_finite() && e >= 0.0, "{row:?}");
        }
        assert!(
            (sum - row[1]).abs() <= 1e-12 * row[1].max(1.0),
            "{row:?}: {sum}"
        );
        seen += usize::from(row[1] > 0.0);
    }
    assert!(seen > rows.len() / 2, "g(r) is mostly empty: {rows:?}");
    // The hard cores: no S–S pair closer than 1, no S–L closer than 1.3, no L–L than 1.6.
    for row in &rows {
        let r = row[0];
        let width = rows[1][0] - rows[0][0];
        for (k, core) in [1.0, 1.3, 1.6].into_iter().enumerate() {
            if r + 0.5 * width < core {
                assert_eq!(row[3 + 2 * k], 0.0, "{} at r = {r}", header[3 + 2 * k]);
                assert_eq!(row[4 + 2 * k], 0.0, "{} at r = {r}", header[4 + 2 * k]);
            }
        }
    }
    let texts = svg_texts(&dir.join("rdf.svg"));
    for label in ["g(r), all pairs", "g S–S", "g S–L", "g L–L"] {
        assert!(texts.iter().any(|x| x == label), "{label}: {texts:?}");
    }
    // Reduced units: σ on the axis, and the caption says so.
    assert!(texts.iter().any(|x| x == "r (σ)"), "{texts:?}");
    assert!(has(&texts, "mixture: N = 256, T = ") && has(&texts, "(reduced units)"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_hard_sphere_run_writes_no_flat_energy_plot() {
    let dir = scratch("plots-hard-spheres");
    let s = dmd_run(
        "hard-spheres.toml",
        &dir,
        &[],
        &[
            "species.0.count=500",
            "run.equilibration_events=5e3",
            "run.events=2e4",
            "output.sample_interval=0.01",
        ],
    );
    let files: Vec<&str> = s["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    // The series is there, with no potential energy and a constant kinetic energy …
    let (header, rows) = read_csv(&dir.join("series.csv"));
    assert_eq!(header[1..4], ["kinetic", "potential", "total"]);
    assert!(rows.len() > 16, "{} rows", rows.len());
    assert!(rows.iter().all(|r| r[2] == 0.0));
    let k0 = rows[0][1];
    assert!(rows.iter().all(|r| (r[1] - k0).abs() <= 1e-9 * k0));
    // … so no energy plot (it would be a flat line), but the pressure plot, in reduced units.
    assert!(!dir.join("series-energy.svg").exists(), "{files:?}");
    assert!(!files.contains(&"series-energy.svg"), "{files:?}");
    assert!(files.contains(&"series-pressure.svg"), "{files:?}");
    let texts = svg_texts(&dir.join("series-pressure.svg"));
    assert!(texts.iter().any(|x| x == "P (ε/σ³)"), "{texts:?}");
    assert!(texts.iter().any(|x| x == "t (τ)"), "{texts:?}");
    assert!(has(&texts, "hard-spheres: N = 500, ") && has(&texts, "σ⁻³ (reduced units)"));
    let _ = std::fs::remove_dir_all(&dir);
}
