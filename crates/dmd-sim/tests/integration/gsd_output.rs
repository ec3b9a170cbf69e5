//! `output.gsd` and the attitudes in `output.trajectory`, for every body model: the GSD file
//! read back with the `gsd` crate (and Python's `gsd.hoomd` when installed) agrees frame by
//! frame with `trajectory.xyz`, its quaternions are unit and body → lab, and a run halted after
//! a checkpoint and resumed writes the same bytes as a straight one.

use std::path::{Path, PathBuf};
use std::process::Command;

use dmd_sim::checkpoint::{self, Every, SceneSource};
use dmd_sim::model::PairModel;
use dmd_sim::run::{Quiet, RunError, RunOptions, Summary, run_scene_with};
use dmd_sim::scene::Scene;
use dmd_sim::search::{SearchMethod, SearchSettings};
use dmd_sim::sites::{ImpulseRule, Sites, molecules, random_orientations};
use glam::{DQuat, DVec3};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dmd-gsd-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A shipped scene's text with `edits` (text replacements) applied.
fn shipped(name: &str, edits: &[(&str, &str)]) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    let mut text = std::fs::read_to_string(&path).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{name}: no `{from}`");
        text = text.replace(from, to);
    }
    text
}

fn options(text: &str, overrides: &[String], every: Option<Every>, halt: bool) -> RunOptions {
    RunOptions {
        checkpoint_every: every,
        source: Some(SceneSource {
            text: text.to_owned(),
            overrides: overrides.to_vec(),
            base: PathBuf::from("."),
            file: PathBuf::from("test.toml"),
        }),
        resume: None,
        halt_after_checkpoint: halt,
    }
}

fn run(
    text: &str,
    overrides: &[String],
    out: &Path,
    opts: &RunOptions,
) -> Result<Summary, RunError> {
    let scene = Scene::from_str_with(text, overrides).unwrap();
    run_scene_with(&scene, Path::new("."), Some(out), &mut Quiet, opts)
}

/// One frame of `trajectory.xyz`: the time, box edges, property names and the rows.
struct XyzFrame {
    time: f64,
    lattice: [f64; 3],
    props: String,
    rows: Vec<Vec<String>>,
}

fn read_xyz(path: &Path) -> Vec<XyzFrame> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let mut frames = Vec::new();
    while let Some(count) = lines.next() {
        let n: usize = count.trim().parse().unwrap();
        let comment = lines.next().unwrap();
        let field = |key: &str| {
            let start = comment.find(key).unwrap() + key.len();
            comment[start..]
                .split_whitespace()
                .next()
                .unwrap()
                .to_owned()
        };
        let lat = comment.split('"').nth(1).unwrap();
        let l: Vec<f64> = lat.split_whitespace().map(|x| x.parse().unwrap()).collect();
        frames.push(XyzFrame {
            time: field("Time=").parse().unwrap(),
            lattice: [l[0], l[4], l[8]],
            props: field("Properties="),
            rows: (0..n)
                .map(|_| {
                    lines
                        .next()
                        .unwrap()
                        .split_whitespace()
                        .map(str::to_owned)
                        .collect()
                })
                .collect(),
        });
    }
    frames
}

fn num(s: &str) -> f64 {
    s.parse().unwrap()
}

/// Checks `trajectory.gsd` against `trajectory.xyz` in `dir`: frame count, N, box, times,
/// unit quaternions, and the last frame's positions, velocities and orientations. Returns the
/// GSD reader.
fn compare(dir: &Path, oriented: bool) -> gsd::Reader {
    let xyz = read_xyz(&dir.join("trajectory.xyz"));
    let mut r = gsd::Reader::open(dir.join("trajectory.gsd")).unwrap();
    assert!(xyz.len() >= 3, "{} frames", xyz.len());
    assert_eq!(r.frames(), xyz.len() as u64, "frame counts");
    assert_eq!(
        xyz[0].props.contains("orientation:R:4"),
        oriented,
        "{}",
        xyz[0].props
    );
    let mut last_step = None;
    for (k, x) in xyz.iter().enumerate() {
        let f = r.read_frame(k as u64).unwrap();
        assert_eq!(f.n(), x.rows.len(), "frame {k}: N");
        let b = f.sim_box;
        assert_eq!(
            [b.lx, b.ly, b.lz],
            x.lattice.map(|l| l as f32),
            "frame {k}: box"
        );
        assert_eq!((b.xy, b.xz, b.yz), (0.0, 0.0, 0.0));
        let time = f.log["dmd/time"].as_scalar::<f64>().unwrap();
        assert_eq!(time, x.time, "frame {k}: time");
        // Events so far: no frame has fewer than the one before.
        assert!(last_step <= Some(f.step), "frame {k}: step {}", f.step);
        last_step = Some(f.step);
        let q = f.orientation.as_ref().unwrap();
        for (i, q) in q.iter().enumerate() {
            let norm = q.iter().map(|x| x * x).sum::<f32>().sqrt();
            assert!((norm - 1.0).abs() < 1e-6, "frame {k}, {i}: |q| = {norm}");
        }
        for (i, p) in f.position.iter().enumerate() {
            for c in 0..3 {
                let half = 0.5 * x.lattice[c] as f32;
                assert!(-half <= p[c] && p[c] < half, "frame {k}, {i}: {p:?}");
            }
        }
        let names: Vec<&str> = f
            .typeid
            .iter()
            .map(|&t| f.types[t as usize].as_str())
            .collect();
        let species: Vec<&str> = x.rows.iter().map(|row| row[0].as_str()).collect();
        assert_eq!(names, species, "frame {k}: types");
    }
    assert!(
        last_step > Some(r.read_frame(0).unwrap().step),
        "no event between frames"
    );
    // The last frame, particle by particle: positions agree up to a box length (GSD's box is
    // centred), orientations as (w, x, y, z) against OVITO's (x, y, z, w).
    let last = xyz.last().unwrap();
    let f = r.read_frame(xyz.len() as u64 - 1).unwrap();
    let image = f.image.as_ref().unwrap();
    for (i, row) in last.rows.iter().enumerate() {
        for c in 0..3 {
            let l = last.lattice[c];
            let d = f.position[i][c] as f64 - num(&row[1 + c]);
            let off = d - l * (d / l).round();
            assert!(off.abs() < 1e-5 * l, "{i}: position {c} off by {off}");
            let v = f.velocity.as_ref().unwrap()[i][c] as f64;
            let vx = num(&row[4 + c]);
            assert!(
                (v - vx).abs() <= 1e-6 * (1.0 + vx.abs()),
                "{i}: velocity {v} {vx}"
            );
            assert!(image[i][c].abs() < 1000, "{i}: image {:?}", image[i]);
        }
        let q = f.orientation.as_ref().unwrap()[i];
        if oriented {
            let qx = [num(&row[10]), num(&row[7]), num(&row[8]), num(&row[9])];
            for c in 0..4 {
                assert!(
                    (q[c] as f64 - qx[c]).abs() < 1e-6,
                    "{i}: {q:?} against {qx:?}"
                );
            }
        } else {
            assert_eq!(q, [1.0, 0.0, 0.0, 0.0], "{i}");
        }
    }
    r
}

/// Reads the file with Python's `gsd.hoomd` too: frame count, N and unit quaternions. Skipped
/// with a message when the package is missing, failing then under `CI`.
fn python_agrees(path: &Path, frames: u64, n: usize) {
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
    let script = "import sys, gsd.hoomd, numpy\n\
        with gsd.hoomd.open(sys.argv[1], 'r') as t:\n\
        \x20   last = t[len(t) - 1]\n\
        \x20   q = numpy.linalg.norm(last.particles.orientation, axis=1)\n\
        \x20   assert numpy.all(abs(q - 1) < 1e-6), q\n\
        \x20   print(len(t), last.particles.N, last.configuration.step > t[0].configuration.step,\n\
        \x20         float(last.log['dmd/time'][0]) > 0)\n";
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
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        format!("{frames} {n} True True")
    );
}

fn both(interval: f64) -> [String; 3] {
    [
        "output=".to_owned(),
        format!("output.trajectory={{ interval = {interval} }}"),
        format!("output.gsd={{ interval = {interval} }}"),
    ]
}

fn run_and_compare(name: &str, text: &str, overrides: &[String], oriented: bool) -> gsd::Reader {
    let d = dir(name);
    let s = run(text, overrides, &d, &options(text, overrides, None, false)).unwrap();
    assert!(
        s.files.iter().any(|f| f == "trajectory.gsd"),
        "{:?}",
        s.files
    );
    let r = compare(&d, oriented);
    let f = gsd::Reader::open(d.join("trajectory.gsd"))
        .unwrap()
        .read_frame(0)
        .unwrap();
    python_agrees(&d.join("trajectory.gsd"), r.frames(), f.n());
    let _ = std::fs::remove_dir_all(&d);
    r
}

#[test]
fn hard_spheres_write_spheres_of_their_diameter() {
    let text = shipped(
        "hard-spheres.toml",
        &[
            ("count = 10976", "count = 108"),
            ("equilibration_events = 8e6", "equilibration_events = 0"),
            ("events = 1.2e7", "time = 1.0"),
        ],
    );
    let mut r = run_and_compare("spheres", &text, &both(0.25), false);
    let f = r.read_frame(0).unwrap();
    assert_eq!(f.types, ["A"]);
    assert_eq!(f.type_shapes, [gsd::Shape::Sphere { diameter: 1.0 }]);
    assert!(f.angmom.is_none());
}

#[test]
fn rods_write_their_axis_as_body_z() {
    let text = shipped(
        "rods-paper.toml",
        &[
            ("count = 512", "count = 216"),
            ("equilibration_time = 10.0", "equilibration_time = 0.0"),
            ("time = 20.0 ", "time = 0.02 "),
        ],
    );
    let mut r = run_and_compare("rods", &text, &both(0.005), true);
    let f = r.read_frame(r.frames() - 1).unwrap();
    assert!(matches!(f.type_shapes[0], gsd::Shape::Ellipsoid { c, a, .. } if c > a));
    // A rod's angular momentum is perpendicular to its axis: L_body has no z component, and
    // HOOMD's p = 2 q ⊗ (0, L_body) gives L_body = ½ (q* ⊗ p).
    for (q, p) in f.orientation.unwrap().iter().zip(f.angmom.unwrap()) {
        let q = DQuat::from_xyzw(q[1] as f64, q[2] as f64, q[3] as f64, q[0] as f64);
        let p = DQuat::from_xyzw(p[1] as f64, p[2] as f64, p[3] as f64, p[0] as f64);
        let l = (q.conjugate() * p) * 0.5;
        assert!(l.z.abs() <= 1e-5 * (l.x.hypot(l.y) + 1e-30), "{l:?}");
        assert!(l.w.abs() <= 1e-5 * l.length(), "{l:?}");
    }
}

/// Lab sites of every molecule of frame `f`: position + q · (body-frame site), the sites read
/// from the frame's `SphereUnion` shape.
fn lab_sites(f: &gsd::Frame) -> Vec<Vec<DVec3>> {
    let gsd::Shape::Other(json) = &f.type_shapes[0] else {
        panic!("{:?}", f.type_shapes[0]);
    };
    assert!(json.contains("\"SphereUnion\""), "{json}");
    let centers = json
        .split("\"centers\":[")
        .nth(1)
        .unwrap()
        .split("],\"diameters\"")
        .next()
        .unwrap();
    let body: Vec<DVec3> = centers
        .trim_matches(|c| c == '[' || c == ']')
        .split("],[")
        .map(|t| {
            let v: Vec<f64> = t.split(',').map(num).collect();
            DVec3::new(v[0], v[1], v[2])
        })
        .collect();
    let orientation = f.orientation.as_ref().unwrap();
    f.position
        .iter()
        .zip(orientation)
        .map(|(p, q)| {
            let q = DQuat::from_xyzw(q[1] as f64, q[2] as f64, q[3] as f64, q[0] as f64);
            let p = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            body.iter().map(|&s| p + q * s).collect()
        })
        .collect()
}

#[test]
fn methane_like_molecules_write_their_whole_attitude() {
    let text = shipped(
        "methane-like.toml",
        &[
            ("count = 256", "count = 108"),
            ("equilibration_time = 5.0", "equilibration_time = 0.5"),
            ("time = 5.0", "time = 0.4"),
        ],
    );
    let mut r = run_and_compare("methane", &text, &both(0.1), true);
    let f = r.read_frame(r.frames() - 1).unwrap();
    assert!(f.angmom.is_some());
    // The sites the attitude puts in the lab: every C–H distance the body's, and no two
    // molecules' sites inside their hard cores (C–C 1, C–H 0.75, H–H 0.55 σ), at the
    // minimum image. A quaternion applied the wrong way round would still keep distances
    // within a molecule, but not the molecules apart.
    let sites = lab_sites(&f);
    let l = f.sim_box.lx as f64;
    let core = |a: usize, b: usize| match (a == 0, b == 0) {
        (true, true) => 1.0,
        (true, false) | (false, true) => 0.75,
        (false, false) => 0.55,
    };
    for m in &sites {
        for h in &m[1..] {
            let d = (*h - m[0]).length();
            assert!((d - 0.32).abs() < 1e-3, "C–H {d}");
        }
    }
    let mut closest = f64::INFINITY;
    for (i, a) in sites.iter().enumerate() {
        for b in &sites[i + 1..] {
            for (x, &sa) in a.iter().enumerate() {
                for (y, &sb) in b.iter().enumerate() {
                    let mut d = sa - sb;
                    d -= l * (d / l).round();
                    let ratio = d.length() / core(x, y);
                    closest = closest.min(ratio);
                }
            }
        }
    }
    assert!(closest > 1.0 - 1e-4, "sites overlap: {closest}");
}

#[test]
fn the_attitude_of_a_site_molecule_rotates_its_body_sites_into_the_lab() {
    // Benzene-like (planar, three distinct moments: the asymmetric top) against the model's
    // own lab sites, over a free flight.
    let (ty, pot) = molecules::benzene_like();
    let types = vec![ty.clone()];
    let kinds = vec![0u32; 4];
    let (q, w) = random_orientations(&types, &kinds, 2.0, 7);
    let search = SearchSettings {
        method: SearchMethod::Adaptive,
        max_step: 0.01,
        window: 0.1,
        jitter: 0.0,
        verify_step: None,
        max_change: f64::INFINITY,
        horizon: 0.0,
    };
    let model = Sites::new(
        types,
        pot,
        &kinds,
        &q,
        &w,
        0.0,
        search,
        ImpulseRule::ContactPoint,
        7,
    )
    .unwrap();
    for i in 0..4 {
        for t in [0.0, 0.37, 2.9] {
            let q = model.attitude(i, t).unwrap();
            assert!((q.length() - 1.0).abs() < 1e-12);
            for (s, arm) in ty.sites().iter().zip(model.site_arms(i, t)) {
                assert!((q * *s - arm).length() < 1e-12, "{i} at {t}");
            }
        }
    }
}

#[test]
fn flexible_chains_write_their_atoms() {
    let text = shipped(
        "flexible-chains.toml",
        &[
            ("count = 125", "count = 64"),
            ("equilibration_time = 10.0", "equilibration_time = 0.5"),
            ("time = 20.0", "time = 0.4"),
        ],
    );
    let mut r = run_and_compare("flexible", &text, &both(0.1), false);
    let f = r.read_frame(r.frames() - 1).unwrap();
    assert_eq!(f.n(), 64 * 4);
    assert_eq!(f.types, ["A", "B"]);
    // The atoms of each chain, unwrapped with their images, are held at their bond lengths.
    let l = f.sim_box.lx as f64;
    let image = f.image.as_ref().unwrap();
    let unwrapped: Vec<DVec3> = f
        .position
        .iter()
        .zip(image)
        .map(|(p, im)| {
            DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
                + DVec3::new(im[0] as f64, im[1] as f64, im[2] as f64) * l
        })
        .collect();
    for chain in unwrapped.chunks(4) {
        for (a, b, len) in [(0, 1, 0.6), (1, 2, 0.6003), (2, 3, 0.6021)] {
            let d = (chain[a] - chain[b]).length();
            assert!((d - len).abs() < 2e-3, "bond {a}–{b}: {d}");
        }
    }
}

#[test]
fn a_resumed_run_writes_the_same_gsd_file() {
    let text = shipped(
        "methane-like.toml",
        &[
            ("count = 256", "count = 108"),
            ("equilibration_time = 5.0", "equilibration_time = 0.2"),
            ("time = 5.0", "time = 0.6"),
        ],
    );
    // Re-basings (where checkpoints are taken) every 500 events.
    let mut o = both(0.05).to_vec();
    o.push("run.rebase_events=500".to_owned());
    let straight = dir("straight");
    run(&text, &o, &straight, &options(&text, &o, None, false)).unwrap();
    let crashed = dir("crashed");
    let every = Some(Every::Events(700));
    let e = run(&text, &o, &crashed, &options(&text, &o, every, true)).unwrap_err();
    assert!(matches!(e, RunError::Halted), "{e}");
    let path = crashed.join(checkpoint::FILE_NAME);
    let c = checkpoint::read(&path).unwrap();
    assert!(
        matches!(c.stage, checkpoint::Stage::Production(_)),
        "{:?}",
        c.stage
    );
    let saved = c.observers.gsd.unwrap();
    let gsd_path = crashed.join("trajectory.gsd");
    assert_eq!(gsd::Reader::open(&gsd_path).unwrap().frames(), saved);
    assert!(saved > 1, "{saved} frames at the checkpoint");
    // A crash after the checkpoint leaves frames the checkpoint does not know of: the resumed
    // run must drop them.
    let mut late = gsd::Reader::open(&gsd_path)
        .unwrap()
        .read_frame(saved - 1)
        .unwrap();
    late.step += 1;
    let mut w = gsd::Writer::append_to(&gsd_path).unwrap();
    w.append(&late).unwrap();
    w.finish().unwrap();
    let scene = Scene::from_str_with(&c.source.text, &c.source.overrides).unwrap();
    let opts = RunOptions {
        resume: Some((path.clone(), c)),
        ..RunOptions::default()
    };
    run_scene_with(&scene, Path::new("."), Some(&crashed), &mut Quiet, &opts).unwrap();
    for name in ["trajectory.gsd", "trajectory.xyz"] {
        let a = std::fs::read(straight.join(name)).unwrap();
        let b = std::fs::read(crashed.join(name)).unwrap();
        assert!(
            a == b,
            "{name} differs between the straight and the resumed run"
        );
    }
    for d in [straight, crashed] {
        let _ = std::fs::remove_dir_all(d);
    }
}
