//! Starting from a written frame (`init.file` of `output.gsd` or `output.trajectory`): a run
//! whose last frame is read back as the start of another run begins in the same state, for
//! rods, SSD/E water (also on the standard-MD engine), rigid benzene-like molecules and
//! semi-flexible chains (and water from the standard-MD engine's frame back to the event-driven
//! one): the second run's first frame is the first run's last one, positions,
//! attitudes, velocities and angular momenta to the round-off of the file (single precision in
//! GSD, ten decimals in XYZ).

use std::path::{Path, PathBuf};
use std::process::Command;

use dmd_sim::run::{Quiet, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::smd_engine::{self, Engine};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dmd-gsd-start-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn shipped(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    std::fs::read_to_string(path).unwrap()
}

/// Runs `text` with `overrides` on `engine`, writing GSD and XYZ frames every `interval` into
/// `out`, without equilibration (no thermostat acts).
fn run(text: &str, overrides: &[String], interval: f64, engine: Engine, out: &Path) {
    let mut o = vec![
        "output=".to_owned(),
        format!("output.trajectory={{ interval = {interval} }}"),
        "run.equilibration_time=0.0".to_owned(),
    ];
    if engine == Engine::Dmd {
        o.push(format!("output.gsd={{ interval = {interval} }}"));
    }
    o.extend(overrides.iter().cloned());
    let mut scene = Scene::from_str_with(text, &o).unwrap_or_else(|e| panic!("{e}"));
    match engine {
        Engine::Dmd => {
            run_scene(&scene, Path::new("."), Some(out), &mut Quiet)
                .unwrap_or_else(|e| panic!("{e}"));
        }
        Engine::Smd => {
            scene.engine = Engine::Smd;
            smd_engine::run(&scene, Path::new("."), Some(out)).unwrap_or_else(|e| panic!("{e}"));
        }
    }
}

/// The overrides that start a run from the last frame of `file`.
fn start_from(file: &Path, attitudes: bool) -> Vec<String> {
    let mut o = vec![
        "init.positions=\"file\"".to_owned(),
        format!("init.file={:?}", file.display().to_string()),
        "init.frame=-1".to_owned(),
        "init.velocities=\"file\"".to_owned(),
    ];
    if attitudes {
        o.push("init.orientations=\"file\"".to_owned());
    }
    o
}

fn last_gsd(path: &Path) -> gsd::Frame {
    let mut r = gsd::Reader::open(path).unwrap();
    assert!(r.frames() >= 2, "{} frames", r.frames());
    r.read_frame(r.frames() - 1).unwrap()
}

fn first_gsd(path: &Path) -> gsd::Frame {
    gsd::Reader::open(path).unwrap().read_frame(0).unwrap()
}

/// The largest difference between two GSD frames' states, each part relative to its largest
/// magnitude (positions to the box edge, at the same periodic image).
fn gsd_difference(a: &gsd::Frame, b: &gsd::Frame) -> f64 {
    assert_eq!(a.n(), b.n());
    assert_eq!(a.typeid, b.typeid);
    assert_eq!(a.types, b.types);
    assert_eq!(a.sim_box, b.sim_box);
    assert_eq!(a.image, b.image, "periodic images");
    let l = a.sim_box.lx.max(a.sim_box.ly).max(a.sim_box.lz);
    let rel = |x: &[f32], y: &[f32], scale: f32| -> f64 {
        x.iter()
            .zip(y)
            .map(|(p, q)| f64::from((p - q).abs() / scale))
            .fold(0.0, f64::max)
    };
    let flat3 = |v: &[[f32; 3]]| v.iter().flatten().copied().collect::<Vec<f32>>();
    let flat4 = |v: &[[f32; 4]]| v.iter().flatten().copied().collect::<Vec<f32>>();
    let top = |v: &[f32]| v.iter().fold(f32::MIN_POSITIVE, |m, x| m.max(x.abs()));
    let mut worst = rel(&flat3(&a.position), &flat3(&b.position), l);
    let (va, vb) = (
        flat3(a.velocity.as_ref().unwrap()),
        flat3(b.velocity.as_ref().unwrap()),
    );
    worst = worst.max(rel(&va, &vb, top(&va)));
    worst = worst.max(rel(
        &flat4(a.orientation.as_ref().unwrap()),
        &flat4(b.orientation.as_ref().unwrap()),
        1.0,
    ));
    match (&a.angmom, &b.angmom) {
        (Some(x), Some(y)) => {
            let (x, y) = (flat4(x), flat4(y));
            worst = worst.max(rel(&x, &y, top(&x)));
        }
        (None, None) => {}
        _ => panic!("one frame has angular momenta, the other none"),
    }
    worst
}

/// The frames of a `trajectory.xyz`: per frame its rows, split into words.
fn xyz_frames(path: &Path) -> Vec<Vec<Vec<String>>> {
    let text = std::fs::read_to_string(path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut frames = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let n: usize = lines[k].trim().parse().unwrap();
        frames.push(
            lines[k + 2..k + 2 + n]
                .iter()
                .map(|l| l.split_whitespace().map(str::to_owned).collect())
                .collect(),
        );
        k += n + 2;
    }
    frames
}

/// The largest difference of two XYZ frames, column by column relative to the column's
/// largest magnitude (words that are not numbers must be equal).
fn xyz_difference(a: &[Vec<String>], b: &[Vec<String>]) -> f64 {
    xyz_columns_difference(a, b, 0..a[0].len())
}

/// [`xyz_difference`] over the columns `columns` only.
fn xyz_columns_difference(
    a: &[Vec<String>],
    b: &[Vec<String>],
    columns: std::ops::Range<usize>,
) -> f64 {
    assert_eq!(a.len(), b.len());
    let mut worst: f64 = 0.0;
    for c in columns {
        let col = |f: &[Vec<String>]| -> Vec<Option<f64>> {
            f.iter().map(|r| r[c].parse::<f64>().ok()).collect()
        };
        let (x, y) = (col(a), col(b));
        let scale = x.iter().flatten().fold(1e-300_f64, |m, v| m.max(v.abs()));
        for (i, (p, q)) in x.iter().zip(&y).enumerate() {
            match (p, q) {
                (Some(p), Some(q)) => worst = worst.max((p - q).abs() / scale),
                _ => assert_eq!(a[i][c], b[i][c], "row {i}, column {c}"),
            }
        }
    }
    worst
}

/// Runs `text` (`first` overrides), then runs it again from the first run's last GSD frame
/// and from its last XYZ frame, and checks that each second run's first frame is that frame:
/// to `gsd_tol` (relative) in GSD and `xyz_tol` in XYZ. Returns the first run's folder.
fn round_trip(
    name: &str,
    text: &str,
    first: &[String],
    interval: f64,
    attitudes: bool,
    (gsd_tol, xyz_tol): (f64, f64),
) -> PathBuf {
    let a = dir(&format!("{name}-a"));
    run(text, first, interval, Engine::Dmd, &a);
    // The second run is judged by its first frame, written as it starts: a tenth of an interval
    // beyond it shows that it runs on from the frame, at a tenth of the cost.
    let short = format!("run.time={}", interval / 10.0);
    for (file, tol) in [("trajectory.gsd", gsd_tol), ("trajectory.xyz", xyz_tol)] {
        let b = dir(&format!("{name}-b"));
        let mut o = first.to_vec();
        o.extend(start_from(&a.join(file), attitudes));
        o.push(short.clone());
        run(text, &o, interval, Engine::Dmd, &b);
        let gsd = gsd_difference(
            &last_gsd(&a.join("trajectory.gsd")),
            &first_gsd(&b.join("trajectory.gsd")),
        );
        let xyz_a = xyz_frames(&a.join("trajectory.xyz"));
        let xyz_b = xyz_frames(&b.join("trajectory.xyz"));
        let xyz = xyz_difference(xyz_a.last().unwrap(), &xyz_b[0]);
        eprintln!("{name} from {file}: GSD frames differ by {gsd:e}, XYZ frames by {xyz:e}");
        assert!(
            gsd <= gsd_tol,
            "{name} from {file}: GSD frames differ by {gsd:e}"
        );
        assert!(
            xyz <= tol.max(xyz_tol),
            "{name} from {file}: XYZ frames differ by {xyz:e}"
        );
        let _ = std::fs::remove_dir_all(&b);
    }
    a
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| (*s).to_owned()).collect()
}

#[test]
fn rods_start_from_their_last_frame() {
    let o = strings(&["species.0.count=216", "run.time=0.02"]);
    let text = shipped("rods-paper.toml");
    let a = round_trip("rods", &text, &o, 0.01, true, (1e-6, 1e-8));
    // The standard-MD engine starts from the same GSD frame.
    let c = dir("rods-smd");
    let mut s = o.clone();
    s.extend(start_from(&a.join("trajectory.gsd"), true));
    s.push("run.time=0.01".to_owned());
    run(&text, &s, 0.01, Engine::Smd, &c);
    let xyz_a = xyz_frames(&a.join("trajectory.xyz"));
    let xyz_c = xyz_frames(&c.join("trajectory.xyz"));
    let d = xyz_difference(xyz_a.last().unwrap(), &xyz_c[0]);
    eprintln!("rods on smd from trajectory.gsd: XYZ frames differ by {d:e}");
    assert!(d <= 1e-6, "the smd engine's first frame differs by {d:e}");
    for p in [a, c] {
        let _ = std::fs::remove_dir_all(p);
    }
}

#[test]
fn water_starts_from_its_last_frame_on_both_engines() {
    let text = shipped("water-ssd.toml");
    // 8³ molecules: a 24.9 Å box, two cells of the 8.3 Å range and the skin along each side.
    // A water event costs about half a millisecond of CPU in a test build: the first run is
    // one interval long (two frames), the event-driven runs after it a tenth of one (their
    // first frame is what is checked), the standard-MD ones a step (the shortest it takes).
    let o = strings(&[
        "species.0.count=512",
        "run.time=0.002",
        "output.sample_interval=0.002",
    ]);
    let a = round_trip("water", &text, &o, 0.002, false, (1e-6, 1e-8));
    // The standard-MD engine reads the same GSD frame: its first XYZ frame is the frame the
    // event-driven run wrote last.
    let c = dir("water-smd");
    let mut s = o.clone();
    s.extend(start_from(&a.join("trajectory.gsd"), false));
    s.push("run.time=0.002".to_owned());
    run(&text, &s, 0.002, Engine::Smd, &c);
    let xyz_a = xyz_frames(&a.join("trajectory.xyz"));
    let xyz_c = xyz_frames(&c.join("trajectory.xyz"));
    let d = xyz_difference(xyz_a.last().unwrap(), &xyz_c[0]);
    eprintln!("water on smd from trajectory.gsd: XYZ frames differ by {d:e}");
    assert!(d <= 1e-6, "the smd engine's first frame differs by {d:e}");
    // And back: the event-driven engine starts from the standard-MD run's last XYZ frame.
    let e = dir("water-from-smd");
    let mut s = o.clone();
    s.extend(start_from(&c.join("trajectory.xyz"), false));
    s.push("run.time=0.0002".to_owned());
    run(&text, &s, 0.002, Engine::Dmd, &e);
    let xyz_c = xyz_frames(&c.join("trajectory.xyz"));
    let xyz_e = xyz_frames(&e.join("trajectory.xyz"));
    let d = xyz_difference(xyz_c.last().unwrap(), &xyz_e[0]);
    eprintln!("water on dmd from the smd run's trajectory.xyz: XYZ frames differ by {d:e}");
    assert!(d <= 1e-8, "the dmd engine's first frame differs by {d:e}");
    // Tops take their whole attitudes alone (`orientations = "file"`) on either engine.
    let gsd = a.join("trajectory.gsd");
    let xyz = a.join("trajectory.xyz");
    for (engine, time) in [(Engine::Smd, "0.002"), (Engine::Dmd, "0.0002")] {
        let mut s = o.clone();
        s.push(format!("run.time={time}"));
        let d = attitudes_only(&text, &s, (&gsd, &xyz), 0.002, engine);
        eprintln!("water on {engine:?}, attitudes from trajectory.gsd: differ by {d:e}");
        assert!(d <= 1e-6, "{d:e}");
    }
    for p in [a, c, e] {
        let _ = std::fs::remove_dir_all(p);
    }
}

/// Starts `text` on `engine` from the positions and attitudes of the last frame of `file`
/// with Maxwell–Boltzmann velocities, and returns how far its first XYZ frame's positions and
/// orientations (columns 1–3 and 7–10) are from that frame's (`xyz`).
fn attitudes_only(
    text: &str,
    first: &[String],
    (file, xyz): (&Path, &Path),
    interval: f64,
    engine: Engine,
) -> f64 {
    let b = dir("attitudes-only");
    let mut o = first.to_vec();
    o.extend(start_from(file, true));
    o.retain(|s| s != "init.velocities=\"file\"");
    run(text, &o, interval, engine, &b);
    let a = xyz_frames(xyz);
    let b_frames = xyz_frames(&b.join("trajectory.xyz"));
    let (a, b0) = (a.last().unwrap(), &b_frames[0]);
    let d = xyz_columns_difference(a, b0, 1..4).max(xyz_columns_difference(a, b0, 7..11));
    let _ = std::fs::remove_dir_all(&b);
    d
}

#[test]
fn benzene_like_molecules_start_from_their_last_frame() {
    let text = shipped("benzene-like.toml");
    let o = strings(&["run.time=0.2"]);
    let a = round_trip("benzene", &text, &o, 0.1, true, (1e-6, 1e-8));
    // Attitudes alone (`orientations = "file"`, Maxwell–Boltzmann velocities).
    let gsd = a.join("trajectory.gsd");
    let xyz = a.join("trajectory.xyz");
    let short = strings(&["run.time=0.01"]);
    let d = attitudes_only(&text, &short, (&gsd, &xyz), 0.1, Engine::Dmd);
    eprintln!("benzene, attitudes from trajectory.gsd: positions and orientations differ by {d:e}");
    assert!(d <= 1e-6, "{d:e}");
    python_reads(&a.join("trajectory.gsd"), "SphereUnion", true);
    let _ = std::fs::remove_dir_all(a);
}

#[test]
fn flexible_chains_start_from_their_last_frame() {
    let text = shipped("flexible-chains.toml");
    let o = strings(&["species.0.count=64", "run.time=0.2"]);
    // The model puts the file's atoms back on their bonds (the frame's atoms lie on the
    // Hermite interpolant between RATTLE steps, about 1e-7 off).
    let a = round_trip("flexible", &text, &o, 0.1, false, (1e-5, 1e-5));
    python_reads(&a.join("trajectory.gsd"), "Sphere", false);
    let _ = std::fs::remove_dir_all(a);
}

/// Reads the last frame of `path` with Python's `gsd.hoomd`: unit quaternions, every type's
/// shape of kind `shape`, and (with `spun`) angular momenta. Skipped with a message when the
/// package is missing, failing then under `CI`.
fn python_reads(path: &Path, shape: &str, spun: bool) {
    let ok = Command::new("python3")
        .args(["-c", "import gsd.hoomd, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        let why = "python3 cannot `import gsd.hoomd, numpy` (install them with \
                   `python3 -m pip install gsd numpy`)";
        assert!(std::env::var_os("CI").is_none(), "{why}");
        eprintln!("SKIPPED the check with Python's gsd: {why}");
        return;
    }
    let script = "import sys, json, gsd.hoomd, numpy\n\
        with gsd.hoomd.open(sys.argv[1], 'r') as t:\n\
        \x20   f = t[len(t) - 1]\n\
        \x20   q = numpy.linalg.norm(f.particles.orientation, axis=1)\n\
        \x20   assert numpy.all(abs(q - 1) < 1e-6), q\n\
        \x20   kinds = {(s if isinstance(s, dict) else json.loads(s))['type'] for s in f.particles.type_shapes}\n\
        \x20   spun = bool(numpy.any(f.particles.angmom != 0))\n\
        \x20   print(len(f.particles.type_shapes) == len(f.particles.types), sorted(kinds), spun)\n";
    let out = Command::new("python3")
        .args(["-c", script])
        .arg(path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "python: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let py_spun = if spun { "True" } else { "False" };
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        format!("True ['{shape}'] {py_spun}")
    );
}
