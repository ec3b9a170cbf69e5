//! Events per second against system size, for docs/PERFORMANCE.md.
//!
//! ```sh
//! cargo run --release -p dmd-sim --example throughput -- [--sizes 1,2,4,9] [--per-body 100] \
//!     [--repeats 3] [--queue bounded] [--skin S]
//! ```
//!
//! A base system of 1372 hard spheres at packing fraction 0.49 (ρσ³ = 0.9357) is melted from
//! an fcc lattice and equilibrated; larger systems are k × k × k copies of it (N = 1372 k³:
//! 1372, 10 976, 87 808, 1 000 188 for k = 1, 2, 4, 9), so every size starts as an equilibrated
//! fluid (the copies decorrelate within a few collisions per body; the collision rate per body
//! is that of the fluid from the start). Each size then runs `per-body × N` events after a
//! warm-up of 20 events per body, `repeats` times; the table gives the median collisions per
//! second (wall and CPU), and the ratio to the smallest size.

use std::path::{Path, PathBuf};

use dmd_sim::run::{Quiet, Summary, run_scene};
use dmd_sim::scene::Scene;

const BASE: &str = r#"
version = 1
seed = 4
[box]
density = 0.9357
[[species]]
name = "A"
count = 1372
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf]]
[init]
positions = "fcc"
temperature = 1.0
[run]
equilibration_events = 2e6
time = 30
[output]
trajectory = { interval = 30 }
plots = false
"#;

fn main() {
    let mut sizes = vec![1u32, 2, 4, 9];
    let mut per_body = 100.0;
    let mut repeats = 3;
    let mut queue = "bounded".to_owned();
    let mut skin: Option<String> = None;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let v = it.next().unwrap_or_default();
        match a.as_str() {
            "--sizes" => sizes = v.split(',').filter_map(|x| x.parse().ok()).collect(),
            "--per-body" => per_body = v.parse().expect("--per-body NUMBER"),
            "--repeats" => repeats = v.parse().expect("--repeats NUMBER"),
            "--queue" => queue = v,
            "--skin" => skin = Some(v),
            _ => panic!("unknown argument {a}"),
        }
    }
    let work = std::env::temp_dir().join(format!("dmd-throughput-{}", std::process::id()));
    std::fs::create_dir_all(&work).unwrap();
    eprintln!("equilibrating the base system ...");
    let base = run(BASE, &[], &work.join("base"));
    let frame = last_frame(&work.join("base/trajectory.xyz"));
    let l0 = base.box_lengths[0];
    println!(
        "| N | events | collisions/s (wall) | collisions/CPU-s | events/CPU-s | vs smallest | Z |"
    );
    println!("|---|---|---|---|---|---|---|");
    let mut first = None;
    for &k in &sizes {
        let file = work.join(format!("tiled-{k}.xyz"));
        let n = tile(&frame, l0, k, &file);
        let events = (per_body * n as f64).round();
        let mut o = vec![
            format!("species.0.count={n}"),
            "init.positions=\"file\"".to_owned(),
            format!("init.file=\"{}\"", file.display()),
            "box.density=".to_owned(),
            format!("run.equilibration_events={}", 20 * n),
            "run.time=".to_owned(),
            format!("run.events={events}"),
            "output.trajectory=".to_owned(),
            format!("run.queue=\"{queue}\""),
        ];
        if let Some(s) = &skin {
            o.push(format!("run.skin={s}"));
        }
        let mut wall = Vec::new();
        let mut cpu = Vec::new();
        let mut ev_cpu = Vec::new();
        let mut z = 0.0;
        for r in 0..repeats {
            let mut o = o.clone();
            o.push(format!("seed={}", 10 + r));
            let s = run(BASE, &o, &work.join(format!("run-{k}-{r}")));
            let coll = s.events_by_kind["core"] as f64;
            wall.push(coll / s.wall_seconds);
            cpu.push(coll / s.cpu_seconds);
            ev_cpu.push(s.events as f64 / s.cpu_seconds);
            z = s.compressibility;
        }
        let (w, c, e) = (median(&mut wall), median(&mut cpu), median(&mut ev_cpu));
        let f = *first.get_or_insert(c);
        println!(
            "| {n} | {events:.0} | {w:.3e} | {c:.3e} | {e:.3e} | {:.2} | {z:.3} |",
            c / f
        );
    }
    let _ = std::fs::remove_dir_all(&work);
}

fn run(text: &str, overrides: &[String], dir: &Path) -> Summary {
    let scene = Scene::from_str_with(text, overrides).unwrap_or_else(|e| panic!("{e}"));
    run_scene(&scene, Path::new("."), Some(dir), &mut Quiet).unwrap_or_else(|e| panic!("{e}"))
}

fn median(x: &mut [f64]) -> f64 {
    x.sort_by(f64::total_cmp);
    x[x.len() / 2]
}

/// Positions of the last frame of an extended XYZ file.
fn last_frame(path: &PathBuf) -> Vec<[f64; 3]> {
    let text = std::fs::read_to_string(path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let n: usize = lines[0].trim().parse().unwrap();
    let start = lines.len() - n;
    lines[start..]
        .iter()
        .map(|l| {
            let f: Vec<f64> = l
                .split_whitespace()
                .skip(1)
                .take(3)
                .map(|x| x.parse().unwrap())
                .collect();
            [f[0], f[1], f[2]]
        })
        .collect()
}

/// Writes `k³` copies of the base frame (box `l0`) as an XYZ file; returns the body count.
fn tile(frame: &[[f64; 3]], l0: f64, k: u32, path: &Path) -> usize {
    use std::io::Write;
    let n = frame.len() * (k * k * k) as usize;
    let l = l0 * f64::from(k);
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    writeln!(out, "{n}").unwrap();
    writeln!(out, "Lattice=\"{l} 0 0 0 {l} 0 0 0 {l}\"").unwrap();
    for a in 0..k {
        for b in 0..k {
            for c in 0..k {
                let off = [f64::from(a) * l0, f64::from(b) * l0, f64::from(c) * l0];
                for p in frame {
                    writeln!(
                        out,
                        "A {} {} {}",
                        p[0] + off[0],
                        p[1] + off[1],
                        p[2] + off[2]
                    )
                    .unwrap();
                }
            }
        }
    }
    n
}
