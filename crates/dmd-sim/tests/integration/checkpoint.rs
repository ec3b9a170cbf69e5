//! Checkpoint and restart (issue 9): a run saved mid-way and resumed gives the same bits as a
//! run that never stopped; damaged checkpoints are refused with a clear message and nothing
//! is overwritten.

use std::path::PathBuf;
use std::process::Command;

use dmd_sim::checkpoint::{self, CODE_VERSION, Every, Problem, SceneSource};
use dmd_sim::run::RunError;

use crate::support;
use crate::support::{options, physics, resume, run_text as run, same_files};

/// A square well with every output, re-based every 1500 events so that checkpoints fall
/// mid-run, an Andersen thermostat in equilibration (its generator is saved too).
const SW: &str = r#"
version = 1
seed = 17
[box]
density = 0.5
[[species]]
name = "A"
count = 108
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf], [1.5, -1.0]]
[init]
positions = "fcc"
temperature = 1.5
[thermostat]
kind = "andersen"
rate = 1.0
[run]
equilibration_events = 4000
events = 20000
rebase_events = 1500
[output]
sample_interval = 0.05
rdf = { bins = 50, every = 2 }
msd = { max_lag = 0.5 }
vacf = { max_lag = 0.5 }
series = true
trajectory = { interval = 0.2 }
plots = false
"#;

const HMC: &str = r#"
version = 1
seed = 23
[box]
density = 0.3
[[species]]
name = "A"
count = 64
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf], [1.5, -1.0]]
[init]
positions = "sc"
temperature = 1.5
[run]
equilibration_events = 2000
[hmc]
segment_time = 0.3
segments = 40
equilibration_segments = 5
fault_fraction = 0.01
series = true
"#;

fn dir(name: &str) -> PathBuf {
    support::scratch(&format!("ckpt-{name}"))
}

#[test]
fn a_resumed_run_is_bit_identical_to_a_straight_one() {
    // Checkpoints in equilibration and in production (the interval counts events of both).
    for (name, every) in [("eq", 2000), ("prod", 12000)] {
        let straight = dir(&format!("straight-{name}"));
        let a = run(SW, &[], &straight, &options(SW, &[], None, false)).unwrap();
        // A run with checkpoints that never stops gives the same bits.
        let saved = dir(&format!("saved-{name}"));
        let b = run(
            SW,
            &[],
            &saved,
            &options(SW, &[], Some(Every::Events(every)), false),
        )
        .unwrap();
        assert_eq!(physics(&a), physics(&b), "checkpoints changed the run");
        // Halted after its first checkpoint, as a crash would leave it, then resumed.
        let crashed = dir(&format!("crashed-{name}"));
        let e = run(
            SW,
            &[],
            &crashed,
            &options(SW, &[], Some(Every::Events(every)), true),
        )
        .unwrap_err();
        assert!(matches!(e, RunError::Halted));
        assert!(!crashed.join("summary.json").exists());
        let c = checkpoint::read(&crashed.join(checkpoint::FILE_NAME)).unwrap();
        let in_production = matches!(c.stage, checkpoint::Stage::Production(_));
        assert_eq!(in_production, name == "prod", "{:?}", c.stage);
        let r = resume(&crashed.join(checkpoint::FILE_NAME));
        assert_eq!(physics(&a), physics(&r), "resumed in {name}");
        same_files(
            &straight,
            &crashed,
            &[
                "summary.json",
                "rdf.csv",
                "msd.csv",
                "vacf.csv",
                "series.csv",
                "trajectory.xyz",
            ]
            .into_iter()
            .filter(|n| *n != "summary.json")
            .collect::<Vec<_>>(),
        );
        for d in [straight, saved, crashed] {
            let _ = std::fs::remove_dir_all(d);
        }
    }
}

#[test]
fn a_resumed_hmc_chain_is_bit_identical() {
    let straight = dir("hmc-straight");
    let a = run(HMC, &[], &straight, &options(HMC, &[], None, false)).unwrap();
    let crashed = dir("hmc-crashed");
    // Due after 3000 events: a few production segments in.
    let e = run(
        HMC,
        &[],
        &crashed,
        &options(HMC, &[], Some(Every::Events(3000)), true),
    )
    .unwrap_err();
    assert!(matches!(e, RunError::Halted));
    let r = resume(&crashed.join(checkpoint::FILE_NAME));
    let h = a.hmc.as_ref().unwrap();
    assert_eq!(h.segments, 40);
    assert_eq!(physics(&a), physics(&r));
    same_files(&straight, &crashed, &["hmc.csv"]);
    let _ = std::fs::remove_dir_all(straight);
    let _ = std::fs::remove_dir_all(crashed);
}

/// The checkpoint of a short HMC run halted early, and its output folder with a good summary
/// from an earlier run.
fn damaged_setup(name: &str) -> (PathBuf, Vec<u8>, Vec<u8>) {
    let d = dir(name);
    let _ = run(
        HMC,
        &["hmc.fault_fraction=0".into()],
        &d,
        &options(
            HMC,
            &["hmc.fault_fraction=0".into()],
            Some(Every::Events(1)),
            true,
        ),
    );
    let good = b"{\"a good summary\": true}".to_vec();
    std::fs::write(d.join("summary.json"), &good).unwrap();
    let bytes = std::fs::read(d.join(checkpoint::FILE_NAME)).unwrap();
    (d, bytes, good)
}

#[test]
fn damaged_checkpoints_get_clear_errors_and_overwrite_nothing() {
    let (d, bytes, good) = damaged_setup("damaged");
    let c = checkpoint::decode(&bytes).unwrap();
    let mut other_format = bytes.clone();
    let other = checkpoint::FORMAT_VERSION + 1;
    other_format[8..12].copy_from_slice(&other.to_le_bytes());
    let mut flipped = bytes.clone();
    let k = bytes.len() - 100;
    flipped[k] ^= 0x10;
    let cases: Vec<(&str, Vec<u8>, String)> = vec![
        (
            "truncated",
            bytes[..bytes.len() / 2].to_vec(),
            format!(
                "truncated: {} bytes, the header announces {}",
                bytes.len() / 2,
                bytes.len()
            ),
        ),
        (
            "corrupted",
            flipped,
            "corrupted: its CRC-32 does not match its contents".into(),
        ),
        (
            "other-version",
            checkpoint::encode_with_version(&c, "9.9.9"),
            format!(
                "written by dmd 9.9.9, this is dmd {CODE_VERSION}: another version would not \
                 continue the run bit for bit; resume it with dmd 9.9.9"
            ),
        ),
        (
            "other-format",
            other_format,
            format!(
                "format version {other}, this dmd reads version {}",
                checkpoint::FORMAT_VERSION
            ),
        ),
        (
            "not-a-checkpoint",
            b"version = 1\n".to_vec(),
            "not a dmd checkpoint (it does not start with the checkpoint signature)".into(),
        ),
        (
            "empty",
            Vec::new(),
            "not a dmd checkpoint (it does not start with the checkpoint signature)".into(),
        ),
    ];
    let exe = env!("CARGO_BIN_EXE_dmd");
    for (name, data, message) in cases {
        let path = d.join(format!("{name}.dmd"));
        std::fs::write(&path, &data).unwrap();
        let e = checkpoint::read(&path).unwrap_err();
        assert_eq!(e.problem.to_string(), message, "{name}");
        // The command refuses it with the message, exit status 2, and writes nothing.
        let o = Command::new(exe)
            .args(["resume", "--quiet"])
            .arg(&path)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{name}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(
            err.trim(),
            format!("dmd: checkpoint {}: {message}", path.display()),
            "{name}"
        );
        assert_eq!(std::fs::read(d.join("summary.json")).unwrap(), good);
        assert_eq!(std::fs::read(&path).unwrap(), data, "{name} was rewritten");
    }
    // A checkpoint whose state does not fit its scene (edited by hand or by a bug).
    let mut bad = c.clone();
    bad.sim.bodies.pop();
    let path = d.join("misfit.dmd");
    std::fs::write(&path, checkpoint::encode_with_version(&bad, CODE_VERSION)).unwrap();
    let o = Command::new(exe)
        .args(["resume", "--quiet"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("the saved state does not fit the scene: it has 63 bodies, the scene 64"),
        "{err}"
    );
    assert_eq!(std::fs::read(d.join("summary.json")).unwrap(), good);
    // A stage its scene does not have, and a chain missing: refused, no panic.
    for (name, bad) in [
        ("stage", {
            let mut b = c.clone();
            b.stage = checkpoint::Stage::Production(checkpoint::Left::Events(10));
            b
        }),
        ("chain", {
            let mut b = c.clone();
            b.chain = None;
            b
        }),
    ] {
        let path = d.join(format!("misfit-{name}.dmd"));
        std::fs::write(&path, checkpoint::encode_with_version(&bad, CODE_VERSION)).unwrap();
        let o = Command::new(exe)
            .args(["resume", "--quiet"])
            .arg(&path)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{name}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("the saved state does not fit the scene"),
            "{err}"
        );
    }
    assert!(matches!(
        checkpoint::decode(&bytes[..20]),
        Err(Problem::Truncated { .. })
    ));
    let _ = std::fs::remove_dir_all(d);
}

#[test]
fn the_command_resumes_a_halted_run() {
    let d = dir("cli");
    let scene = d.join("scene.toml");
    std::fs::write(&scene, HMC).unwrap();
    let exe = env!("CARGO_BIN_EXE_dmd");
    let o = Command::new(exe)
        .args([
            "run",
            "--quiet",
            "--checkpoint-every",
            "2000",
            "--halt-after-checkpoint",
        ])
        .arg(&scene)
        .arg("--out")
        .arg(d.join("out"))
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = Command::new(exe)
        .args(["resume", "--quiet"])
        .arg(d.join("out").join(checkpoint::FILE_NAME))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("out/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["hmc"]["segments"], 40);
    let o = Command::new(exe)
        .args(["run", "--quiet", "--checkpoint-every", "5d"])
        .arg(&scene)
        .arg("--out")
        .arg(d.join("out2"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("`5d` is not an interval"));
    let _ = std::fs::remove_dir_all(d);
}

/// The loop-level tests' system: 125 spheres on a 5³ lattice of spacing 1.5 in a box of 7.5,
/// a core at 1, a shoulder of 0.5 to 1.2 and a well of −1 to 1.5, at kT = 2.
mod small {
    use collide::Particle;
    use dmd_sim::model::Stepped;
    use dmd_sim::potential::Potentials;
    use dmd_sim::simulation::{LoopSettings, Simulation};
    use event_queue::{BoundedQueue, LazyQueue, Ticket};
    use glam::DVec3;

    pub(crate) type Sim = Simulation<Stepped, LazyQueue<BoundedQueue<Ticket>>>;

    pub(crate) fn model() -> Stepped {
        let pots = Potentials::from_tables(
            1,
            &[((0, 0), vec![[1.0, f64::INFINITY], [1.2, 0.5], [1.5, -1.0]])],
        );
        Stepped::new(pots, vec![Particle::new(1.0).unwrap()], 125)
    }

    /// A fresh simulation of the system, re-based every `rebase_events`, with the debug
    /// invariant check every `debug_check_events` (0: never).
    pub(crate) fn new(rebase_events: u64, debug_check_events: u64) -> Sim {
        let pos: Vec<DVec3> = (0..125)
            .map(|i| {
                DVec3::new(f64::from(i / 25), f64::from(i / 5 % 5), f64::from(i % 5)) * 1.5 + 0.3
            })
            .collect();
        let vel = dmd_sim::init::maxwell_boltzmann(&[1.0; 125], 2.0, 4);
        let settings = LoopSettings {
            rebase_events,
            seed: 3,
            debug_check_events,
            skin: 0.2,
            start_time: 0.0,
        };
        Simulation::new(DVec3::splat(7.5), &pos, &vel, &[0; 125], model(), settings).unwrap()
    }

    /// The same bits in the counters, the clock and every body's position and velocity.
    pub(crate) fn assert_same(a: &Sim, b: &Sim) {
        assert_eq!(a.counters(), b.counters());
        assert_eq!(a.now().to_bits(), b.now().to_bits());
        for (x, y) in a.bodies().iter().zip(b.bodies()) {
            assert_eq!(x, y, "a body differs");
            assert_eq!(
                x.r.to_array().map(f64::to_bits),
                y.r.to_array().map(f64::to_bits)
            );
            assert_eq!(
                x.v.to_array().map(f64::to_bits),
                y.v.to_array().map(f64::to_bits)
            );
        }
    }
}

/// The issue's test, at the level of the loop: 2N events straight, or N events, a checkpoint
/// (through the file encoding), a fresh simulation built from it, and N more events: the same
/// bits in every body's position, clock, velocity and generation, and in the time.
#[test]
fn two_n_events_straight_or_n_plus_checkpoint_plus_n_give_the_same_bits() {
    use dmd_sim::simulation::{NoSampler, Stop};

    let n = 20_000;
    let new = || small::new(997, 500);
    let mut straight = new();
    straight
        .run(Stop::Events(2 * n), &mut NoSampler, &mut |_| {})
        .unwrap();

    // N events (to the first re-basing after them), then a checkpoint through its bytes.
    let mut first = new();
    first.set_pause_at_rebase(true);
    let mut left = 2 * n;
    loop {
        let before = first.counters().events;
        first
            .run(Stop::Events(left), &mut NoSampler, &mut |_| {})
            .unwrap();
        assert!(first.take_paused());
        left -= first.counters().events - before;
        if first.counters().events >= n {
            break;
        }
    }
    let c = checkpoint::Checkpoint {
        source: SceneSource {
            text: String::new(),
            overrides: Vec::new(),
            base: PathBuf::new(),
            file: PathBuf::new(),
        },
        every: None,
        stage: checkpoint::Stage::Production(checkpoint::Left::Events(left)),
        sim: first.save_state(),
        record: checkpoint::RunRecord::default(),
        observers: checkpoint::ObserverState::default(),
        chain: None,
    };
    drop(first);
    let bytes = checkpoint::encode_with_version(&c, CODE_VERSION);
    let c = checkpoint::decode(&bytes).unwrap();
    let mut resumed = small::Sim::from_state(small::model(), &c.sim).unwrap();
    resumed
        .run(Stop::Events(left), &mut NoSampler, &mut |_| {})
        .unwrap();

    small::assert_same(&resumed, &straight);
    assert_eq!(resumed.time().to_bits(), straight.time().to_bits());
    assert_eq!(resumed.images(), straight.images());
    assert_eq!(
        resumed.tracked_potential().to_bits(),
        straight.tracked_potential().to_bits()
    );
    assert!(straight.counters().step_in > 100, "the steps took part");
}

/// A stop requested (a signal's flag) far from the scheduled re-basing: within its grace the
/// loop runs on towards the scheduled one; past it the loop re-bases at once and pauses there,
/// and a checkpoint taken there continues bit for bit as the paused simulation does.
#[test]
fn a_stop_past_its_grace_re_bases_early_and_its_checkpoint_continues_exactly() {
    use dmd_sim::simulation::{NoSampler, Stop};
    use std::sync::Arc;
    use std::sync::atomic::AtomicBool;
    use std::time::Duration;

    let new = || small::new(1_000_000, 0);
    let raised = Arc::new(AtomicBool::new(true));

    // A long grace: the 30 000 events hold no scheduled re-basing, so the run is not stopped.
    let mut patient = new();
    patient.set_pause_at_rebase(true);
    patient.set_stop_request(Some(Arc::clone(&raised)), Duration::from_secs(3600));
    patient
        .run(Stop::Events(30_000), &mut NoSampler, &mut |_| {})
        .unwrap();
    assert!(!patient.take_paused());
    assert_eq!(patient.counters().events, 30_000);
    assert_eq!(patient.counters().rebases, 0);

    // No grace: the loop re-bases and pauses at its next look at the flag (every 256 events).
    let mut stopped = new();
    stopped.set_pause_at_rebase(true);
    stopped.set_stop_request(Some(Arc::clone(&raised)), Duration::ZERO);
    stopped
        .run(Stop::Events(30_000), &mut NoSampler, &mut |_| {})
        .unwrap();
    assert!(stopped.take_paused());
    let at = stopped.counters().events;
    assert!(at > 0 && at <= 256, "paused after {at} events");
    assert_eq!(stopped.counters().rebases, 1);

    // Saved there and resumed, against the paused simulation itself going on.
    let mut resumed = small::Sim::from_state(small::model(), &stopped.save_state()).unwrap();
    stopped.set_stop_request(None, Duration::ZERO);
    stopped
        .run(Stop::Events(30_000 - at), &mut NoSampler, &mut |_| {})
        .unwrap();
    resumed
        .run(Stop::Events(30_000 - at), &mut NoSampler, &mut |_| {})
        .unwrap();
    small::assert_same(&resumed, &stopped);
    assert!(stopped.counters().step_in > 100, "the steps took part");
}

/// Rods on terraced potentials (issue 7) with every output, re-based every 700 events so that
/// checkpoints fall mid-run: the rotors, the search counters and the predictions rebuilt from
/// them must continue bit for bit.
const RODS: &str = r#"
version = 1
seed = 5
[box]
density = 0.3
[[species]]
name = "rod"
count = 64
mass = 1.0
inertia = 0.00696
[[pair]]
species = ["rod", "rod"]
potential = { kind = "rods", epsilon = 1.0, sigma = 1.0, zeta = 0.3295 }
terraces = { step_kt = 0.5 }
[init]
positions = "sc"
temperature = 1.4
[thermostat]
kind = "andersen"
rate = 2.0
[run]
equilibration_events = 1500
events = 4000
rebase_events = 700
[output]
sample_interval = 0.02
msd = { max_lag = 0.1 }
orientation_acf = { max_lag = 0.1 }
series = true
trajectory = { interval = 0.05 }
plots = false
"#;

/// With certified prediction (jumps and located crossings, no root search) and without it
/// (root searches suspended and resumed by virtual events).
#[test]
fn a_resumed_rods_run_is_bit_identical() {
    resumed_rods_run_is_bit_identical(RODS, "rods", |s| s.certified_jumps > 0 && s.roots > 0);
    let searched = format!("{RODS}\n[search]\nhorizon = 0\n");
    resumed_rods_run_is_bit_identical(&searched, "rods-searched", |s| {
        s.searches > 0 && s.suspended > 0
    });
}

fn resumed_rods_run_is_bit_identical(
    text: &str,
    name: &str,
    used: impl Fn(&dmd_sim::search::SearchStats) -> bool,
) {
    let straight = dir(&format!("{name}-straight"));
    let a = run(text, &[], &straight, &options(text, &[], None, false)).unwrap();
    assert!(a.search.as_ref().is_some_and(&used), "{:?}", a.search);
    assert!(a.terrace_crossings > 100, "{}", a.terrace_crossings);
    let crashed = dir(&format!("{name}-crashed"));
    let e = run(
        text,
        &[],
        &crashed,
        &options(text, &[], Some(Every::Events(3000)), true),
    )
    .unwrap_err();
    assert!(matches!(e, RunError::Halted));
    let c = checkpoint::read(&crashed.join(checkpoint::FILE_NAME)).unwrap();
    assert!(matches!(c.stage, checkpoint::Stage::Production(_)));
    assert!(!c.sim.model_extra.is_empty(), "the rotors are saved");
    let r = resume(&crashed.join(checkpoint::FILE_NAME));
    assert_eq!(physics(&a), physics(&r));
    same_files(
        &straight,
        &crashed,
        &["msd.csv", "oacf.csv", "series.csv", "trajectory.xyz"],
    );
    let _ = std::fs::remove_dir_all(straight);
    let _ = std::fs::remove_dir_all(crashed);
}

/// HMC on rods: canonical segments redraw the angular velocities; the chain and its rotors
/// are saved and resumed bit for bit, and with exact dynamics every segment is accepted.
#[test]
fn a_resumed_hmc_chain_of_rods_is_bit_identical_and_accepts_exact_segments() {
    let text = RODS
        .replace("[thermostat]\nkind = \"andersen\"\nrate = 2.0\n", "")
        .replace("events = 4000\n", "")
        .split("[output]")
        .next()
        .unwrap()
        .to_owned()
        + "[hmc]\nsegment_time = 0.05\nsegments = 12\nequilibration_segments = 2\nseries = true\n";
    let straight = dir("rods-hmc-straight");
    let a = run(&text, &[], &straight, &options(&text, &[], None, false)).unwrap();
    let h = a.hmc.as_ref().unwrap();
    assert_eq!(h.segments, 12);
    // Terrace crossings conserve K + U exactly (up to round-off), and the energy of a chain
    // state from the attitudes agrees with the stored terraces: nothing is rejected.
    assert_eq!(h.accepted, 12, "{h:?}");
    assert_eq!(h.segments_with_misses, 0, "{h:?}");
    assert!(h.delta_h_max_abs < 1e-8, "{h:?}");
    let crashed = dir("rods-hmc-crashed");
    let e = run(
        &text,
        &[],
        &crashed,
        &options(&text, &[], Some(Every::Events(2500)), true),
    )
    .unwrap_err();
    assert!(matches!(e, RunError::Halted));
    let r = resume(&crashed.join(checkpoint::FILE_NAME));
    assert_eq!(physics(&a), physics(&r));
    same_files(&straight, &crashed, &["hmc.csv"]);
    let _ = std::fs::remove_dir_all(straight);
    let _ = std::fs::remove_dir_all(crashed);
}

/// `dmd resume` of `bytes` (written as `NAME.dmd` in `d`) exits with status 2 and a message
/// that contains `expected`, and writes nothing.
fn refused(d: &std::path::Path, name: &str, bytes: &[u8], expected: &str) {
    let path = d.join(format!("{name}.dmd"));
    std::fs::write(&path, bytes).unwrap();
    let before: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    let o = Command::new(env!("CARGO_BIN_EXE_dmd"))
        .args(["resume", "--quiet"])
        .arg(&path)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{name}: {err}");
    assert!(err.contains(expected), "{name}: {err}");
    assert_eq!(err.lines().count(), 1, "{name}: {err}");
    let after: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(before, after, "{name}: files were written");
}

/// Checkpoints edited and sealed again with a valid CRC, as a forger (or a bug writing a wrong
/// state) would make them: each check of the state against its scene refuses its edit with a
/// message naming what is wrong, exit status 2, and no panic or run with wrong physics.
#[test]
fn forged_checkpoints_with_valid_crcs_are_refused_as_states() {
    let d = dir("forged");
    // A plain square well halted in production (no thermostat there), and a rods run.
    let sw = SW.replace("rate = 1.0\n", "rate = 1.0\nduring = \"equilibration\"\n");
    let e = run(
        &sw,
        &[],
        &d,
        &options(&sw, &[], Some(Every::Events(12000)), true),
    )
    .unwrap_err();
    assert!(matches!(e, RunError::Halted));
    let bytes = std::fs::read(d.join(checkpoint::FILE_NAME)).unwrap();
    std::fs::remove_file(d.join(checkpoint::FILE_NAME)).unwrap();
    let c = checkpoint::decode(&bytes).unwrap();
    assert!(matches!(c.stage, checkpoint::Stage::Production(_)));
    assert!(c.sim.thermostat.is_none() && !c.sim.levels.is_empty());
    let seal = |c: &checkpoint::Checkpoint| checkpoint::encode_with_version(c, CODE_VERSION);
    let edit = |f: &dyn Fn(&mut checkpoint::Checkpoint)| {
        let mut b = c.clone();
        f(&mut b);
        seal(&b)
    };
    let n = c.sim.bodies.len();
    assert!(c.observers.samples.as_ref().is_some_and(|s| s.count() > 40));
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "nan-velocity",
            edit(&|b| b.sim.bodies[3].v.y = f64::NAN),
            "body 3 has a non-finite state",
        ),
        (
            "centre-outside-box",
            edit(&|b| {
                let l = b.sim.lengths.x;
                b.sim.bodies[5].r.x += 3.0 * l;
                b.sim.centres[5].x += 3.0 * l;
            }),
            "body 5 has its list centre",
        ),
        (
            "image-counter-at-its-limit",
            edit(&|b| b.sim.images[4][2] = i32::MIN),
            "-2147483648] times, more than any run (at most 1000000000 each way)",
        ),
        (
            "body-off-its-centre",
            edit(&|b| b.sim.bodies[7].r.z += 0.9),
            "from its list centre, beyond the skin",
        ),
        (
            "level-dropped",
            edit(&|b| {
                b.sim.levels.remove(0);
            }),
            "is stored on level 0, its distance says level 1",
        ),
        (
            "neighbour-list-emptied",
            edit(&|b| {
                b.sim.nbr_entries.clear();
                b.sim.nbr_len = vec![0; n];
            }),
            "(list radius 1.8): listed by 0: false",
        ),
        (
            "hard-core-grown-in-the-scene",
            edit(&|b| {
                b.source.text = b
                    .source
                    .text
                    .replace("[[1.0, inf], [1.5, -1.0]]", "[[1.3, inf], [1.5, -1.0]]");
            }),
            "overlap: distance",
        ),
        (
            "density-edited-in-the-scene",
            edit(&|b| b.source.text = b.source.text.replace("density = 0.5", "density = 0.49")),
            "its box is",
        ),
        (
            "thermostat-edited-in-the-scene",
            edit(&|b| {
                b.source.text = b.source.text.replace("during = \"equilibration\"\n", "");
                b.sim.thermostat = Some((1.0, 2.0));
            }),
            "its thermostat (rate 1, temperature 2) is not the scene's",
        ),
        (
            "kinetic-energy",
            edit(&|b| b.sim.kinetic *= 1.5),
            "tracked kinetic energy",
        ),
        (
            "potential-energy",
            edit(&|b| b.sim.potential -= 1e3),
            "tracked potential energy",
        ),
        (
            "start-energy",
            edit(&|b| {
                if let Some(s) = &mut b.record.start {
                    s.1 += 2e7;
                }
            }),
            "it recorded at the start of production by more than any run drifts",
        ),
        (
            "endless-stage",
            edit(&|b| b.stage = checkpoint::Stage::Production(checkpoint::Left::Events(u64::MAX))),
            "has more left than the scene's run",
        ),
        (
            "thin-skin",
            edit(&|b| b.sim.settings.3 = 1e-300),
            "its neighbour-list skin 1e-300 is not the one the scene gives",
        ),
        (
            "seed",
            edit(&|b| b.sim.settings.1 ^= 1),
            "its re-basing interval or seed is not the scene's",
        ),
        (
            "infinite-record",
            edit(&|b| b.record.seconds.0 = f64::INFINITY),
            "its record of the time spent is not finite",
        ),
        (
            "not-at-a-rebasing",
            edit(&|b| b.sim.bodies[0].t = 0.25),
            "it was not saved at a re-basing",
        ),
        (
            "rdf-bins",
            edit(&|b| {
                b.observers.rdf = c.observers.rdf.clone().map(|r| {
                    let mut v = serde_json::to_value(&r).unwrap();
                    v["counts"].as_array_mut().unwrap().pop();
                    serde_json::from_value(v).unwrap()
                });
            }),
            "its g(r) does not fit",
        ),
        (
            "correlation-origin-in-the-future",
            edit(&|b| {
                b.observers.correlations = c.observers.correlations.clone().map(|r| {
                    let mut v = serde_json::to_value(&r).unwrap();
                    v["origins"][0]["sample"] = serde_json::json!(u64::MAX);
                    serde_json::from_value(v).unwrap()
                });
            }),
            "its correlations do not fit",
        ),
        (
            "sample-count-beyond-its-accumulators",
            edit(&|b| {
                b.observers.samples = c.observers.samples.clone().map(|r| {
                    let mut v = serde_json::to_value(&r).unwrap();
                    v["count"] = serde_json::json!(v["count"].as_u64().unwrap() + 1);
                    serde_json::from_value(v).unwrap()
                });
            }),
            "its per-sample accumulators do not fit its",
        ),
        (
            "blocking-level-forged",
            edit(&|b| {
                b.observers.samples = c.observers.samples.clone().map(|r| {
                    let mut v = serde_json::to_value(&r).unwrap();
                    v["pressure"]["levels"][1]["count"] = serde_json::json!(1_000_000u64);
                    serde_json::from_value(v).unwrap()
                });
            }),
            "its blocking level 1 (1000000 values) is not one that sampling gives",
        ),
        (
            "length-field-wraps-around",
            {
                let mut x = bytes.clone();
                x[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
                let crc = checkpoint::crc32(&x[16..]);
                x[12..16].copy_from_slice(&crc.to_le_bytes());
                x
            },
            "its header announces a payload of 18446744073709551615 bytes, more than any file \
             holds",
        ),
    ];
    for (name, data, expected) in cases {
        refused(&d, name, &data, expected);
    }
    // The unedited checkpoint still resumes.
    std::fs::write(d.join(checkpoint::FILE_NAME), &bytes).unwrap();
    resume(&d.join(checkpoint::FILE_NAME));

    // A rod's axis that is not a unit vector.
    let d = dir("forged-rods");
    let e = run(
        RODS,
        &[],
        &d,
        &options(RODS, &[], Some(Every::Events(3000)), true),
    )
    .unwrap_err();
    assert!(matches!(e, RunError::Halted));
    let c = checkpoint::read(&d.join(checkpoint::FILE_NAME)).unwrap();
    let mut b = c.clone();
    b.sim.model_extra[0] *= 2.0;
    refused(&d, "rod-axis", &seal(&b), "body 0 cannot be restored");
    // A rod spinning about its own axis: ω given a component along the axis (parts 7..10 are
    // ω, 0..3 the axis), which no linear rotor has.
    let mut b = c.clone();
    let axis = glam::DVec3::from_slice(&b.sim.model_extra[..3]);
    for (k, a) in axis.to_array().iter().enumerate() {
        b.sim.model_extra[7 + k] += 0.5 * a;
    }
    refused(
        &d,
        "rod-spinning-about-its-axis",
        &seal(&b),
        "body 0 cannot be restored: its angular velocity",
    );
    refused(
        &d,
        "rod-spinning-about-its-axis-why",
        &seal(&b),
        "along the rod's axis: a rod turns only about its short axes, so its angular velocity \
         must be perpendicular to its axis",
    );
    let _ = std::fs::remove_dir_all(d);

    // An HMC chain whose ΔH histogram lost a bin, or whose counts disagree.
    let (d, bytes, _) = damaged_setup("forged-hmc");
    std::fs::remove_file(d.join(checkpoint::FILE_NAME)).unwrap();
    let c = checkpoint::decode(&bytes).unwrap();
    let mut b = c.clone();
    b.chain.as_mut().unwrap().stats.histogram.pop();
    refused(&d, "hmc-histogram", &seal(&b), "its ΔH histogram has");
    let mut b = c.clone();
    b.chain.as_mut().unwrap().stats.accepted += 1;
    refused(&d, "hmc-counts", &seal(&b), "its HMC counts do not agree");
    let _ = std::fs::remove_dir_all(d);
}

/// `series.csv` is written as the run goes, not held: a run halted at its production
/// checkpoint has the rows so far on disk (the checkpoint records their count and the file's
/// length), and a resume after a crash that left rows beyond the checkpoint cuts them off and
/// continues, giving the straight run's file: no row doubled, none missing.
#[test]
fn the_series_is_streamed_and_a_resume_continues_it_without_duplicates_or_gaps() {
    let straight = dir("series-straight");
    run(SW, &[], &straight, &options(SW, &[], None, false)).unwrap();
    let crashed = dir("series-crashed");
    let e = run(
        SW,
        &[],
        &crashed,
        &options(SW, &[], Some(Every::Events(12000)), true),
    )
    .unwrap_err();
    assert!(matches!(e, RunError::Halted));
    let c = checkpoint::read(&crashed.join(checkpoint::FILE_NAME)).unwrap();
    assert!(matches!(c.stage, checkpoint::Stage::Production(_)));
    let state = c.observers.series.clone().expect("the series is saved");
    let partial = crashed.join("series.csv.partial");
    let text = std::fs::read_to_string(&partial).unwrap();
    assert_eq!(text.len() as u64, state.bytes);
    assert_eq!(
        text.lines().count() as u64,
        state.rows + 1,
        "header and rows"
    );
    assert!(state.rows > 10, "{state:?}");
    let whole = std::fs::read_to_string(straight.join("series.csv")).unwrap();
    assert!(
        whole.starts_with(&text),
        "the rows so far are the straight run's"
    );
    // Rows a crashed run wrote after its checkpoint.
    let mut f = std::fs::OpenOptions::new()
        .append(true)
        .open(&partial)
        .unwrap();
    std::io::Write::write_all(&mut f, b"1e0,2e0,3e0,5e0,1e0,1e0\n").unwrap();
    drop(f);
    resume(&crashed.join(checkpoint::FILE_NAME));
    same_files(&straight, &crashed, &["series.csv"]);
    assert!(!partial.exists());
    let _ = std::fs::remove_dir_all(straight);
    let _ = std::fs::remove_dir_all(crashed);
}
