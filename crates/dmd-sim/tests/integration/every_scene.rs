//! Every shipped scene, whatever its body model, gets every feature: each scene in `scenes/`
//! is shortened and run straight, halted after a checkpoint and resumed (the same bits and the
//! same files), checked for conservation, run as an HMC chain, and its trajectory read back. A
//! scene added to `scenes/` is covered without a change here.

use std::collections::BTreeMap;
use std::sync::Mutex;

use dmd_sim::checkpoint::{self, Every};
use dmd_sim::run::{RunError, Summary};
use dmd_sim::scene::Scene;

use crate::support::{
    assert_conserved, options, physics, resume, run_text, same_files, scratch, shipped_scenes,
};

/// Events of the shortened runs (equilibration, production) and between re-basings, so that
/// checkpoints (taken at re-basings) fall mid-production with re-basings before and after.
/// Water and benzene cost about half a millisecond of CPU per event in a test build.
const EQUILIBRATION: u64 = 500;
const PRODUCTION: u64 = 1_500;
const REBASE: u64 = 350;
const CHECKPOINT_EVERY: u64 = 1_000;

/// A shipped scene, shortened.
struct Short {
    name: String,
    text: String,
    /// Overrides making it short: one run (no chains or sweep), no outputs of its own.
    base: Vec<String>,
    hmc: bool,
    /// Atoms per frame of a scene of semi-flexible molecules (drawn atom by atom, rigid ones
    /// among them too).
    atoms: Option<u64>,
    thermostat: bool,
    /// The scene sets `run.events` itself.
    events: bool,
}

/// Whether the scene's TOML has the dotted `key`.
fn has(table: &toml::Table, key: &str) -> bool {
    let mut t = table;
    let mut parts = key.split('.').peekable();
    while let Some(p) = parts.next() {
        match t.get(p) {
            None => return false,
            Some(_) if parts.peek().is_none() => return true,
            Some(toml::Value::Table(inner)) => t = inner,
            Some(_) => return false,
        }
    }
    false
}

fn strings(x: &[&str]) -> Vec<String> {
    x.iter().map(|s| (*s).to_owned()).collect()
}

fn scenes() -> Vec<Short> {
    shipped_scenes()
        .into_iter()
        .map(|path| {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let text = std::fs::read_to_string(&path).unwrap();
            let scene = Scene::from_str_with(&text, &[]).unwrap();
            let hmc = scene.hmc.is_some();
            let atoms = scene.species.iter().any(|s| s.bonds.is_some()).then(|| {
                let n = |s: &dmd_sim::scene::SpeciesSpec| s.sites.as_ref().map_or(1, Vec::len);
                scene.species.iter().map(|s| s.count * n(s) as u64).sum()
            });
            let table: toml::Table = toml::from_str(&text).unwrap();
            let mut base: Vec<String> = [
                "chains",
                "sweep",
                "output",
                "run.equilibration_time",
                "run.time",
                "run.queue",
            ]
            .into_iter()
            .filter(|k| has(&table, k))
            .map(|k| format!("{k}="))
            .collect();
            base.push(format!("run.equilibration_events={EQUILIBRATION}"));
            base.push(format!("run.rebase_events={REBASE}"));
            if hmc {
                base.extend(strings(&["hmc.segments=6", "hmc.equilibration_segments=1"]));
            } else {
                base.push(format!("run.events={PRODUCTION}"));
            }
            let thermostat = has(&table, "thermostat");
            let events = has(&table, "run.events");
            Short {
                name,
                text,
                base,
                hmc,
                atoms,
                thermostat,
                events,
            }
        })
        .collect()
}

fn with(base: &[String], more: &[String]) -> Vec<String> {
    base.iter().chain(more).cloned().collect()
}

fn straight(s: &Short, ov: &[String], tag: &str) -> (Summary, std::path::PathBuf) {
    let dir = scratch(&format!("every-{tag}-{}", s.name));
    let sum = run_text(&s.text, ov, &dir, &options(&s.text, ov, None, false))
        .unwrap_or_else(|e| panic!("{}: {e}", s.name));
    (sum, dir)
}

/// The production's simulated time of the shortened scene (to place samples and frames),
/// from one probe run per scene shared by both tests (the lock is held through the probe, so
/// the other test waits for it instead of running it again).
fn production_time(s: &Short) -> f64 {
    static TIMES: Mutex<BTreeMap<String, f64>> = Mutex::new(BTreeMap::new());
    let mut times = TIMES.lock().unwrap();
    *times.entry(s.name.clone()).or_insert_with(|| {
        let (sum, dir) = straight(s, &s.base, "probe");
        let _ = std::fs::remove_dir_all(dir);
        assert!(sum.sim_time > 0.0, "{}: {}", s.name, sum.sim_time);
        sum.sim_time
    })
}

/// The frames of an extended XYZ file: per frame the body count and the comment line.
fn xyz_frames(text: &str) -> Vec<(usize, String)> {
    let mut lines = text.lines();
    let mut frames = Vec::new();
    while let Some(n) = lines.next() {
        let n: usize = n
            .trim()
            .parse()
            .expect("a frame starts with its body count");
        let comment = lines.next().expect("a comment line").to_owned();
        for k in 0..n {
            let l = lines
                .next()
                .unwrap_or_else(|| panic!("frame cut at body {k}"));
            assert!(
                l.split_whitespace()
                    .skip(1)
                    .all(|x| x.parse::<f64>().is_ok_and(f64::is_finite)),
                "{l}"
            );
        }
        frames.push((n, comment));
    }
    frames
}

#[test]
fn every_scene_resumes_bit_for_bit_conserves_energy_and_writes_its_trajectory() {
    for s in scenes() {
        let t = production_time(&s);
        let outputs = if s.hmc {
            strings(&["hmc.series=true"])
        } else {
            vec![
                format!("output.sample_interval={}", t / 20.0),
                "output.series=true".to_owned(),
                "output.plots=false".to_owned(),
                format!("output.trajectory.interval={}", t / 4.0),
                format!("output.gsd.interval={}", t / 4.0),
            ]
        };
        let ov = with(&s.base, &outputs);
        let (a, dir_a) = straight(&s, &ov, "straight");
        if s.hmc {
            let h = a.hmc.as_ref().unwrap();
            assert_eq!(h.accepted, h.segments, "{}: {h:?}", s.name);
        } else {
            assert_conserved(&a, &s.name, 1e-10);
            // The trajectories: a frame at every interval of production, every body in each
            // (every atom of a flexible molecule), the same frames in both files.
            let text = std::fs::read_to_string(dir_a.join("trajectory.xyz"))
                .unwrap_or_else(|e| panic!("{}: {e}", s.name));
            let frames = xyz_frames(&text);
            assert!((4..=5).contains(&frames.len()), "{}: {frames:?}", s.name);
            for (n, comment) in &frames {
                let n = *n as u64;
                assert_eq!(n, s.atoms.unwrap_or(a.n_bodies), "{}", s.name);
                assert!(comment.contains("Lattice="), "{}: {comment}", s.name);
            }
            let mut gsd = gsd::Reader::open(dir_a.join("trajectory.gsd"))
                .unwrap_or_else(|e| panic!("{}: {e}", s.name));
            assert_eq!(gsd.frames(), frames.len() as u64, "{}", s.name);
            let last = gsd.read_frame(gsd.frames() - 1).unwrap();
            assert_eq!(last.n(), frames.last().unwrap().0, "{}", s.name);
        }
        // Halted after its first checkpoint, as a crash would leave it, then resumed.
        let dir_b = scratch(&format!("every-crashed-{}", s.name));
        let e = run_text(
            &s.text,
            &ov,
            &dir_b,
            &options(&s.text, &ov, Some(Every::Events(CHECKPOINT_EVERY)), true),
        )
        .unwrap_err();
        assert!(matches!(e, RunError::Halted), "{}: {e}", s.name);
        let r = resume(&dir_b.join(checkpoint::FILE_NAME));
        assert_eq!(physics(&a), physics(&r), "{}: resumed", s.name);
        let files: Vec<&str> = a
            .files
            .iter()
            .map(String::as_str)
            .filter(|f| *f != "summary.json")
            .collect();
        assert!(!files.is_empty(), "{}", s.name);
        same_files(&dir_a, &dir_b, &files);
        for d in [dir_a, dir_b] {
            let _ = std::fs::remove_dir_all(d);
        }
    }
}

#[test]
fn every_scene_runs_as_an_hmc_chain_that_accepts_its_exact_segments() {
    for s in scenes().into_iter().filter(|s| !s.hmc) {
        let t = production_time(&s);
        let ov = with(
            &s.base
                .iter()
                .filter(|o| !o.starts_with("run.events"))
                .cloned()
                .collect::<Vec<_>>(),
            &[
                s.thermostat.then(|| "thermostat=".to_owned()),
                s.events.then(|| "run.events=".to_owned()),
                Some(format!("hmc.segment_time={}", t / 8.0)),
                Some("hmc.segments=4".to_owned()),
                Some("hmc.equilibration_segments=1".to_owned()),
            ]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>(),
        );
        let dir = scratch(&format!("every-hmc-{}", s.name));
        let got = run_text(&s.text, &ov, &dir, &options(&s.text, &ov, None, false));
        let _ = std::fs::remove_dir_all(&dir);
        let a = got.unwrap_or_else(|e| panic!("{}: {e}", s.name));
        let h = a.hmc.as_ref().unwrap();
        assert_eq!(h.segments, 4, "{}", s.name);
        // Exact event-driven dynamics conserve H to round-off: every segment is accepted.
        assert_eq!(h.accepted, 4, "{}: {h:?}", s.name);
        assert_eq!(h.segments_with_misses, 0, "{}: {h:?}", s.name);
        assert!(
            h.delta_h_max_abs < 1e-8 * (1.0 + a.n_bodies as f64),
            "{}: {h:?}",
            s.name
        );
    }
}
