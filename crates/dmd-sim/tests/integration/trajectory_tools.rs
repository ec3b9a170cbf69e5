//! Trajectories other tools read, and runs that continue from any frame they hold:
//! `trajectory.xyz` read by ASE (`ase.io.read(path, index=":")`) and by OVITO's Python module
//! agrees with `trajectory.gsd` written at the same moments, for every body kind ASE types each
//! line, gives the box and understands the velocities; a run started from a frame (`init.velocities = "file"`) starts
//! with that frame's kinetic energy, and its rows go to the bodies their ids name.
//!
//! The Python checks need `python3` with `ase`, `ovito`, `gsd` and `numpy` (`python3 -m pip
//! install ase ovito gsd numpy`); without them they print why they skip and pass, unless the
//! environment variable `CI` is set, where they fail.

use std::path::{Path, PathBuf};
use std::process::Command;

use dmd_sim::output::ASE_VELOCITY_IN_A_PER_PS;
use dmd_sim::run::{Quiet, Summary, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::smd_engine::{self, Engine};
use glam::{DQuat, DVec3};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dmd-traj-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A shipped scene with `overrides`.
fn shipped(name: &str, overrides: &[String]) -> Scene {
    let text = crate::support::shipped_text(name);
    Scene::from_str_with(&text, overrides).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Runs the shipped scene `name` with `overrides`, writing into `out`.
fn run_into(name: &str, overrides: &[String], out: &Path) -> Summary {
    run_scene(
        &shipped(name, overrides),
        Path::new("."),
        Some(out),
        &mut Quiet,
    )
    .unwrap()
}

fn strings(xs: &[&str]) -> Vec<String> {
    xs.iter().map(|s| (*s).to_owned()).collect()
}

/// 125 of the paper's rods (molecular units) for 0.3 ps from a simple cubic lattice, with both
/// trajectories every 0.1 ps and the energy series.
fn rods(extra: &[&str]) -> Scene {
    let mut o = strings(&[
        "species.0.count=125",
        "thermostat=",
        "run.equilibration_time=0",
        "run.time=0.3",
        "output=",
        "output.series=true",
        "output.sample_interval=0.01",
        "output.trajectory={ interval = 0.1 }",
        "output.gsd={ interval = 0.1 }",
    ]);
    o.extend(strings(extra));
    shipped("rods-paper.toml", &o)
}

/// Whether `python3 -c "import {modules}"` works; without it, fails under CI and skips
/// otherwise.
fn python_ready(test: &str, modules: &str) -> bool {
    let ok = Command::new("python3")
        .args(["-c", &format!("import {modules}")])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        let why = format!(
            "python3 cannot `import {modules}` (install them with `python3 -m pip install ase \
             ovito gsd numpy`)"
        );
        assert!(std::env::var_os("CI").is_none(), "{test}: {why}");
        eprintln!("SKIPPED {test}: {why}");
    }
    ok
}

/// Whether ASE, gsd and numpy import ([`python_ready`]).
fn ase_ready(test: &str) -> bool {
    python_ready(test, "ase.io, gsd.hoomd, numpy")
}

/// Runs a Python script with arguments; its standard output.
fn python(script: &str, args: &[String]) -> String {
    let out = Command::new("python3")
        .args(["-c", script])
        .args(args)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "python failed:\nstdout: {}\nstderr: {}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().to_owned()
}

/// ASE's frames of `trajectory.xyz` against `trajectory.gsd`, frame by frame: the box as the
/// cell with periodic boundaries, the unwrapped positions (`pos + map_shift · L` against GSD's
/// `position + image · L`), ASE's velocities (in its own units: × `unit` gives Å/ps) against
/// GSD's and the `velo` column, the attitudes, the time, the rods' shape `(a, a, c)`, the lab
/// angular velocities against GSD's angular momenta (`I ω = L`), elements and masses.
const ASE_AGAINST_GSD: &str = r#"
import sys, numpy as np, ase.io, gsd.hoomd
xyz, gsd_path = sys.argv[1], sys.argv[2]
unit, inertia, a, c, mass = map(float, sys.argv[3:8])
frames = ase.io.read(xyz, index=":")
def qmul(p, q):
    w1, x1, y1, z1 = p.T
    w2, x2, y2, z2 = q.T
    return np.stack([w1*w2 - x1*x2 - y1*y2 - z1*z2, w1*x2 + x1*w2 + y1*z2 - z1*y2,
                     w1*y2 - x1*z2 + y1*w2 + z1*x2, w1*z2 + x1*y2 - y1*x2 + z1*w2], axis=1)
with gsd.hoomd.open(gsd_path, "r") as t:
    assert len(frames) == len(t) >= 3, (len(frames), len(t))
    for k, (at, f) in enumerate(zip(frames, t)):
        L = np.array(f.configuration.box[:3], dtype=float)
        assert len(at) == f.particles.N, k
        assert np.allclose(at.cell.array, np.diag(L), rtol=1e-6), (k, at.cell)
        assert at.pbc.all(), k
        assert abs(at.info["Time"] - float(f.log["dmd/time"][0])) < 1e-12, k
        assert ((at.positions >= 0) & (at.positions < L)).all(), k
        u = at.positions + at.arrays["map_shift"] * L
        ug = f.particles.position + f.particles.image * L
        assert np.abs(u - ug).max() < 1e-5 * L.max(), (k, np.abs(u - ug).max())
        v = at.get_velocities() * unit
        assert np.allclose(v, at.arrays["velo"], rtol=1e-8, atol=1e-9), k
        assert np.allclose(v, f.particles.velocity, rtol=1e-5, atol=1e-5), k
        q = at.arrays["orientation"][:, [3, 0, 1, 2]]
        assert np.abs(q - f.particles.orientation).max() < 1e-6, k
        assert np.allclose(at.arrays["aspherical_shape"], [a, a, c], rtol=1e-12), k
        conj = f.particles.orientation * np.array([1, -1, -1, -1])
        lab = qmul(f.particles.angmom.astype(float), conj.astype(float))[:, 1:] / 2
        assert np.allclose(at.arrays["omega"] * inertia, lab, rtol=1e-4, atol=1e-4), k
        assert (at.numbers == 0).all() and np.allclose(at.get_masses(), mass), k
print(len(frames))
"#;

#[test]
fn ase_reads_a_rods_trajectory_as_the_gsd_file_has_it() {
    let d = dir("ase-rods");
    let s = run_scene(&rods(&[]), Path::new("."), Some(&d), &mut Quiet).unwrap();
    assert!(
        s.files.iter().any(|f| f == "trajectory.xyz"),
        "{:?}",
        s.files
    );
    // The header a person reads: rods carry their attitude, shape, spin and ASE's columns.
    let text = std::fs::read_to_string(d.join("trajectory.xyz")).unwrap();
    let header = text.lines().nth(1).unwrap();
    assert!(
        header.contains(
            "Properties=species:S:1:pos:R:3:velo:R:3:orientation:R:4:aspherical_shape:R:3:\
             omega:R:3:map_shift:I:3:Z:I:1:masses:R:1:momenta:R:3:id:I:1 "
        ),
        "{header}"
    );
    if !ase_ready("ase_reads_a_rods_trajectory_as_the_gsd_file_has_it") {
        return;
    }
    // σ = 3.035 Å, ζ = 1 Å: width σ − ζ/2, length σ + ζ/2.
    let (sigma, zeta) = (3.035, 1.0);
    let args = [
        d.join("trajectory.xyz").display().to_string(),
        d.join("trajectory.gsd").display().to_string(),
        format!("{ASE_VELOCITY_IN_A_PER_PS:e}"),
        "1.154".to_owned(),
        format!("{:e}", 0.5 * (sigma - 0.5 * zeta)),
        format!("{:e}", 0.5 * (sigma + 0.5 * zeta)),
        "18".to_owned(),
    ];
    let frames: u32 = python(ASE_AGAINST_GSD, &args).parse().unwrap();
    assert!(frames >= 3, "{frames} frames");
    let _ = std::fs::remove_dir_all(&d);
}

/// OVITO's Python module reads `trajectory.xyz` (first argument) as the GSD file (second) has
/// it, frame by frame: box, ids, unwrapped positions (wrapped position plus `Periodic Image`),
/// velocities, attitudes (OVITO's quaternions are x, y, z, w), the rods' semi-axes (`a a c`) and
/// time (OVITO keeps shapes in single precision). Prints the number of frames.
const OVITO_AGAINST_GSD: &str = r#"
import sys, numpy as np, gsd.hoomd
from ovito.io import import_file
xyz, gsd_path = sys.argv[1], sys.argv[2]
a, c = float(sys.argv[3]), float(sys.argv[4])
pipeline = import_file(xyz)
with gsd.hoomd.open(gsd_path, "r") as t:
    assert pipeline.source.num_frames == len(t) >= 3, (pipeline.source.num_frames, len(t))
    for k, f in enumerate(t):
        d = pipeline.compute(k)
        L = np.array(f.configuration.box[:3], dtype=float)
        assert np.allclose(d.cell[:, :3], np.diag(L), rtol=1e-6), (k, d.cell[...])
        assert d.cell.pbc == (True, True, True), k
        assert abs(d.attributes["Time"] - float(f.log["dmd/time"][0])) < 1e-12, k
        p = d.particles
        assert p.count == f.particles.N, k
        assert (np.asarray(p["Particle Identifier"]) == np.arange(p.count)).all(), k
        u = np.asarray(p.positions) + np.asarray(p["Periodic Image"]) * L
        ug = f.particles.position + f.particles.image * L
        assert np.abs(u - ug).max() < 1e-5 * L.max(), (k, np.abs(u - ug).max())
        assert np.allclose(p["Velocity"], f.particles.velocity, rtol=1e-5, atol=1e-5), k
        q = np.asarray(p["Orientation"])[:, [3, 0, 1, 2]]
        assert np.abs(q - f.particles.orientation).max() < 1e-6, k
        assert np.allclose(p["Aspherical Shape"], [a, a, c], rtol=1e-6), k
print(pipeline.source.num_frames)
"#;

/// OVITO's Python module (`pip install ovito`) reads a rods trajectory with its box, velocities,
/// attitudes, shapes and image counters. Skips where the module does not import, except under
/// CI, whose Python packages include it.
#[test]
fn ovito_reads_a_rods_trajectory_as_the_gsd_file_has_it() {
    let test = "ovito_reads_a_rods_trajectory_as_the_gsd_file_has_it";
    if !python_ready(test, "ovito.io, gsd.hoomd, numpy") {
        return;
    }
    let d = dir("ovito-rods");
    run_scene(&rods(&[]), Path::new("."), Some(&d), &mut Quiet).unwrap();
    let (sigma, zeta) = (3.035, 1.0);
    let args = [
        d.join("trajectory.xyz").display().to_string(),
        d.join("trajectory.gsd").display().to_string(),
        format!("{:e}", 0.5 * (sigma - 0.5 * zeta)),
        format!("{:e}", 0.5 * (sigma + 0.5 * zeta)),
    ];
    let frames: u32 = python(OVITO_AGAINST_GSD, &args).parse().unwrap();
    assert!(frames >= 3, "{frames} frames");
    let _ = std::fs::remove_dir_all(&d);
}

/// For each frame: atom count, box, elements and `get_velocities()` × `unit` against `velo`.
const ASE_READS: &str = r#"
import sys, json, numpy as np, ase.io
path, n, unit, numbers = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), json.loads(sys.argv[4])
frames = ase.io.read(path, index=":")
for at in frames:
    assert len(at) == n, len(at)
    assert at.pbc.all() and at.cell.rank == 3, at.cell
    assert sorted(set(at.numbers.tolist())) == numbers, sorted(set(at.numbers.tolist()))
    v = at.get_velocities() * unit
    assert np.allclose(v, at.arrays["velo"], rtol=1e-8, atol=1e-9)
    assert (at.arrays["id"] == np.arange(n)).all()
print(len(frames))
"#;

#[test]
fn ase_reads_every_body_kind() {
    if !ase_ready("ase_reads_every_body_kind") {
        return;
    }
    let frames = |interval: &str| {
        strings(&[
            "output=",
            &format!("output.trajectory={{ interval = {interval} }}"),
        ])
    };
    let d = dir("ase-kinds");
    // (scene, overrides, lines per frame, ASE velocity unit, elements by atomic number): a
    // mixture of spheres named `S` (sulfur for ASE) and `L` (no element); dumbbells, one
    // line each; chains written as their atoms of kinds `A` and `B` (boron); water, tops in
    // molecular units, given the element O.
    let cases: [(&str, Vec<String>, usize, f64, &str); 4] = [
        (
            "mixture.toml",
            [
                strings(&[
                    "species.0.count=200",
                    "species.1.count=56",
                    "box.density=0.2",
                    "run.equilibration_events=0",
                    "run.events=",
                    "run.time=1.0",
                ]),
                frames("0.5"),
            ]
            .concat(),
            256,
            1.0,
            "[0, 16]",
        ),
        (
            "hard-dumbbells.toml",
            [
                strings(&[
                    "species.0.count=108",
                    "run.equilibration_time=0",
                    "run.time=0.2",
                ]),
                frames("0.1"),
            ]
            .concat(),
            108,
            1.0,
            "[0]",
        ),
        (
            "flexible-chains.toml",
            [
                strings(&[
                    "species.0.count=64",
                    "thermostat=",
                    "run.equilibration_time=0",
                    "run.time=0.2",
                ]),
                frames("0.1"),
            ]
            .concat(),
            256,
            1.0,
            "[0, 5]",
        ),
        (
            "water-ssd.toml",
            [
                strings(&[
                    "species.0.count=729",
                    "species.0.element=\"O\"",
                    "thermostat=",
                    "run.equilibration_time=0",
                    // Three frames (a water event costs half a millisecond of CPU here).
                    "run.time=0.0004",
                ]),
                frames("0.0002"),
            ]
            .concat(),
            729,
            ASE_VELOCITY_IN_A_PER_PS,
            "[8]",
        ),
    ];
    for (name, o, n, unit, numbers) in cases {
        let out = d.join(name);
        let scene = shipped(name, &o);
        run_scene(&scene, Path::new("."), Some(&out), &mut Quiet)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let args = [
            out.join("trajectory.xyz").display().to_string(),
            n.to_string(),
            format!("{unit:e}"),
            numbers.to_owned(),
        ];
        let got = python(ASE_READS, &args);
        assert!(got.parse::<u32>().unwrap() >= 2, "{name}: {got} frames");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// The rows of the last frame of `path`, and its comment line.
fn last_frame(path: &Path) -> (String, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut at = 0;
    let mut last = 0;
    while at < lines.len() {
        last = at;
        at += lines[at].trim().parse::<usize>().unwrap() + 2;
    }
    let n: usize = lines[last].trim().parse().unwrap();
    let rows = lines[last + 2..last + 2 + n]
        .iter()
        .map(|l| l.split_whitespace().map(str::to_owned).collect())
        .collect();
    (lines[last + 1].to_owned(), rows)
}

/// The comment line and the rows, split into words, of the first frame of `path`.
fn first_frame(path: &Path) -> (String, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let n: usize = text.lines().next().unwrap().trim().parse().unwrap();
    let comment = text.lines().nth(1).unwrap().to_owned();
    let rows = text
        .lines()
        .skip(2)
        .take(n)
        .map(|l| l.split_whitespace().map(str::to_owned).collect())
        .collect();
    (comment, rows)
}

/// The `map_shift` image counters of a frame's rows.
fn images(comment: &str, rows: &[Vec<String>]) -> Vec<[i64; 3]> {
    let at = column(comment, "map_shift");
    rows.iter()
        .map(|r| std::array::from_fn(|k| r[at + k].parse().unwrap()))
        .collect()
}

/// The first word of column `name` in a comment line's `Properties`.
fn column(comment: &str, name: &str) -> usize {
    let props = comment
        .split_whitespace()
        .find_map(|w| w.strip_prefix("Properties="))
        .unwrap();
    let f: Vec<&str> = props.split(':').collect();
    let mut at = 0;
    for c in f.chunks(3) {
        if c[0] == name {
            return at;
        }
        at += c[2].parse::<usize>().unwrap();
    }
    panic!("no {name} in {props}")
}

fn vec3(row: &[String], at: usize) -> DVec3 {
    DVec3::new(
        row[at].parse().unwrap(),
        row[at + 1].parse().unwrap(),
        row[at + 2].parse().unwrap(),
    )
}

/// The kinetic energy (internal units) of the last frame of `path` from its columns: `½ m v²`
/// with the `masses` column, plus `½ Σ I_k ω_k²` in the body frame of each `orientation` for
/// principal moments `moments` (a rod's `(I, I, 0)`).
fn frame_kinetic(path: &Path, moments: Option<DVec3>) -> f64 {
    let (comment, rows) = last_frame(path);
    let (m, v) = (column(&comment, "masses"), column(&comment, "velo"));
    let mut k = 0.0;
    for row in &rows {
        let mass: f64 = row[m].parse().unwrap();
        k += 0.5 * mass * vec3(row, v).length_squared();
        if let Some(i) = moments {
            let q = column(&comment, "orientation");
            let q = DQuat::from_xyzw(
                row[q].parse().unwrap(),
                row[q + 1].parse().unwrap(),
                row[q + 2].parse().unwrap(),
                row[q + 3].parse().unwrap(),
            )
            .normalize();
            let w = q.inverse() * vec3(row, column(&comment, "omega"));
            k += 0.5 * (i * w * w).element_sum();
        }
    }
    k
}

/// The kinetic energy at the start of the run in `dir` (the scene's unit): the summary's
/// `temperature_start` times the ratio of kinetic energy to temperature of a `series.csv` row
/// (the series starts one sampling interval later; the ratio is fixed by the degrees of freedom).
fn first_kinetic(dir: &Path) -> f64 {
    let text = std::fs::read_to_string(dir.join("series.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = |name: &str| header.iter().position(|&h| h == name).unwrap();
    let row: Vec<f64> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let start = summary["temperature_start"].as_f64().unwrap();
    start * row[at("kinetic")] / row[at("temperature")]
}

/// Overrides that start a scene from the last frame of `file`, in a box of the frame's edges
/// (scenes with a `box.aspect` drop it too).
fn from_last_frame(file: &Path, lengths: DVec3) -> Vec<String> {
    vec![
        "init.positions=file".to_owned(),
        format!("init.file=\"{}\"", file.display()),
        "init.frame=-1".to_owned(),
        "init.velocities=file".to_owned(),
        "box.density=".to_owned(),
        format!(
            "box.lengths=[{:?}, {:?}, {:?}]",
            lengths.x, lengths.y, lengths.z
        ),
    ]
}

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-9 * a.abs().max(b.abs()),
        "{what}: {a} against {b}"
    );
}

#[test]
fn a_run_of_spheres_continues_from_its_last_frame() {
    let d = dir("restart-spheres");
    let o = strings(&[
        "species.0.count=200",
        "species.1.count=56",
        "box.density=0.2",
        "run.equilibration_events=0",
        "run.events=",
        "run.time=1.0",
        "output=",
        "output.series=true",
        "output.sample_interval=0.1",
        "output.trajectory={ interval = 0.4 }",
    ]);
    let first = d.join("first");
    let s: Summary = run_into("mixture.toml", &o, &first);
    let xyz = first.join("trajectory.xyz");
    let k = frame_kinetic(&xyz, None);
    let mut o2 = o.clone();
    o2.extend(from_last_frame(&xyz, DVec3::from(s.box_lengths)));
    o2.push("box.aspect=".to_owned());
    let second = d.join("second");
    run_into("mixture.toml", &o2, &second);
    close(first_kinetic(&second), k, "kinetic energy at t = 0");
    // Drawn velocities at init.temperature would give (3N − 3)/2 kT.
    assert!((k - 0.5 * (3.0 * 256.0 - 3.0)).abs() > 1e-3 * k, "{k}");
    // The image counters go on from the frame's: unwrapped positions continue.
    let (c1, a) = last_frame(&xyz);
    let (c2, b) = first_frame(&second.join("trajectory.xyz"));
    let (was, now) = (images(&c1, &a), images(&c2, &b));
    assert!(was.iter().any(|m| *m != [0; 3]), "no body crossed the box");
    assert_eq!(was, now);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_run_of_rods_continues_from_its_last_frame_on_both_engines() {
    let d = dir("restart-rods");
    let first = d.join("first");
    let s = run_scene(&rods(&[]), Path::new("."), Some(&first), &mut Quiet).unwrap();
    let xyz = first.join("trajectory.xyz");
    // Internal energy units (10 J/mol) to the series' kJ/mol.
    let k = frame_kinetic(&xyz, Some(DVec3::new(1.154, 1.154, 0.0))) / 100.0;
    let mut o = from_last_frame(&xyz, DVec3::from(s.box_lengths));
    o.push("init.orientations=file".to_owned());
    let refs: Vec<&str> = o.iter().map(String::as_str).collect();
    let second = d.join("second");
    let s2 = run_scene(&rods(&refs), Path::new("."), Some(&second), &mut Quiet).unwrap();
    close(first_kinetic(&second), k, "kinetic energy at t = 0");
    // The frame's attitudes and images too: the second run's first frame is the first run's
    // last.
    let (c1, a) = last_frame(&xyz);
    let (c2, b) = first_frame(&second.join("trajectory.xyz"));
    assert_eq!(images(&c1, &a), images(&c2, &b));
    let q = column(&c1, "orientation");
    for (x, y) in a.iter().zip(&b) {
        for c in 0..4 {
            let (u, w): (f64, f64) = (x[q + c].parse().unwrap(), y[q + c].parse().unwrap());
            assert!((u - w).abs() < 1e-10, "{x:?} against {y:?}");
        }
    }
    assert!(
        s2.relative_energy_drift < 1e-9,
        "{}",
        s2.relative_energy_drift
    );
    // The standard-MD engine starts from the same frame with the same kinetic energy.
    let mut scene = rods(&[refs, vec!["output.gsd="]].concat());
    scene.engine = Engine::Smd;
    let third = d.join("smd");
    smd_engine::run(&scene, Path::new("."), Some(&third)).unwrap_or_else(|e| panic!("{e}"));
    close(first_kinetic(&third), k, "smd: kinetic energy at t = 0");
    let (c3, b3) = first_frame(&third.join("trajectory.xyz"));
    assert_eq!(images(&c1, &a), images(&c3, &b3), "smd: image counters");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_run_of_water_continues_from_its_last_frame() {
    let d = dir("restart-water");
    let o = strings(&[
        "species.0.count=729",
        "thermostat=",
        "run.equilibration_time=0",
        // A few hundred events each (a water event costs half a millisecond of CPU in a test
        // build): the check is the kinetic energy at the start of the second run.
        "run.time=0.0004",
        "output=",
        "output.series=true",
        "output.sample_interval=0.0002",
        "output.trajectory={ interval = 0.0004 }",
    ]);
    let first = d.join("first");
    let s = run_into("water-ssd.toml", &o, &first);
    let xyz = first.join("trajectory.xyz");
    // The moments the model takes: water's published 1.7696 rounded to the planar 1.7695.
    let moments = DVec3::new(0.6145 + 1.1550, 0.6145, 1.1550);
    let k = frame_kinetic(&xyz, Some(moments)) / 100.0;
    let mut o2 = o.clone();
    o2.extend(from_last_frame(&xyz, DVec3::from(s.box_lengths)));
    let second = d.join("second");
    run_into("water-ssd.toml", &o2, &second);
    close(first_kinetic(&second), k, "kinetic energy at t = 0");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn rows_go_to_the_bodies_their_ids_name() {
    let d = dir("ids");
    let o = strings(&[
        "species.0.count=200",
        "species.1.count=56",
        "box.density=0.2",
        "run.equilibration_events=0",
        "run.events=",
        "run.time=0.5",
        "output=",
        "output.trajectory={ interval = 0.5 }",
    ]);
    let first = d.join("first");
    let s = run_into("mixture.toml", &o, &first);
    // The last frame as written, and with its rows reversed.
    let (comment, rows) = last_frame(&first.join("trajectory.xyz"));
    let write = |name: &str, comment: &str, rows: &[Vec<String>]| {
        let mut text = format!("{}\n{comment}\n", rows.len());
        for r in rows {
            text.push_str(&r.join(" "));
            text.push('\n');
        }
        let path = d.join(name);
        std::fs::write(&path, text).unwrap();
        path
    };
    let ordered = write("ordered.xyz", &comment, &rows);
    let reversed: Vec<Vec<String>> = rows.iter().rev().cloned().collect();
    let reversed = write("reversed.xyz", &comment, &reversed);
    // Each start file's run: its first frame, species and positions per body (the first run's
    // last frame, body by body, when the rows went to the bodies their ids name).
    let run = |file: &Path| {
        let mut o2 = strings(&[
            "run.time=0.1",
            "output=",
            "output.trajectory={ interval = 1 }",
        ]);
        o2.extend(from_last_frame(file, DVec3::from(s.box_lengths)));
        o2.push("box.aspect=".to_owned());
        let o2: Vec<String> = [o[..5].to_vec(), o2].concat();
        let out = d.join(file.file_stem().unwrap());
        run_into("mixture.toml", &o2, &out);
        let (_, rows) = last_frame(&out.join("trajectory.xyz"));
        rows.into_iter()
            .map(|r| r[..4].join(" "))
            .collect::<Vec<_>>()
    };
    let written: Vec<String> = rows.iter().map(|r| r[..4].join(" ")).collect();
    assert_eq!(run(&ordered), written);
    assert_eq!(run(&reversed), written);
    // Without the id column the reversed rows are taken as they stand: other bodies.
    let unnamed = write(
        "unnamed.xyz",
        &comment.replace(":id:I:1", ":index:I:1"),
        &rows.iter().rev().cloned().collect::<Vec<_>>(),
    );
    let c = run(&unnamed);
    assert_ne!(c, written);
    assert_eq!(c[0], written[written.len() - 1]);
    let _ = std::fs::remove_dir_all(&d);
}
