//! Whole runs through the library, as `dmd run` does them: conservation, determinism, queue
//! independence, re-basing of the time origin, the thermostat, and the output files.
//! (Debug builds also check every invariant of the loop every N events during these runs.)

use std::path::Path;

use collide::Particle;
use dmd_sim::model::{HardSpheres, Stepped};
use dmd_sim::potential::Potentials;
use dmd_sim::run::{Quiet, Summary, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use event_queue::{BoundedQueue, LazyQueue, Ticket};
use glam::DVec3;

const HS: &str = r#"
version = 1
seed = 5
[box]
density = 0.8
[[species]]
name = "A"
count = 256
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf]]
[init]
positions = "fcc"
temperature = 1.0
[run]
equilibration_events = 20000
events = 100000
"#;

const SW: &str = r#"
version = 1
seed = 9
[box]
density = 0.5
[[species]]
name = "A"
count = 256
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf], [1.5, -1.0]]
[init]
positions = "fcc"
temperature = 1.5
[run]
equilibration_events = 20000
events = 100000
"#;

const MIXTURE: &str = r#"
version = 1
seed = 21
[box]
lengths = [12.0, 12.0, 15.0]
[[species]]
name = "small"
count = 200
mass = 1.0
[[species]]
name = "heavy"
count = 50
mass = 1.0e4
[[pair]]
species = ["small", "small"]
steps = [[0.8, inf], [1.0, 0.5], [1.3, -0.4]]
[[pair]]
species = ["small", "heavy"]
steps = [[1.2, inf], [1.5, -0.8]]
[[pair]]
species = ["heavy", "heavy"]
steps = [[1.6, inf]]
[init]
positions = "sc"
temperature = 2.0
[run]
equilibration_events = 10000
events = 100000
"#;

fn run(text: &str, overrides: &[&str]) -> Summary {
    let o: Vec<String> = overrides.iter().map(|s| (*s).to_owned()).collect();
    let scene = Scene::from_str_with(text, &o).unwrap();
    run_scene(&scene, Path::new("."), None, &mut Quiet).unwrap()
}

/// The physics fields of a summary (times and speeds excluded) as exact bit patterns.
fn physics(s: &Summary) -> String {
    let mut v = serde_json::to_value(s).unwrap();
    let o = v.as_object_mut().unwrap();
    for k in [
        "wall_seconds",
        "cpu_seconds",
        "events_per_second",
        "events_per_cpu_second",
        "pair_events_per_second",
        "pair_events_per_cpu_second",
        "queue",
        "queue_pushed",
        "queue_stale_dropped",
        "queue_stale_swept",
        "requeued",
    ] {
        o.remove(k);
    }
    // serde_json prints the shortest representation that reads back to the same f64.
    serde_json::to_string(&v).unwrap()
}

#[test]
fn hard_spheres_conserve_energy_and_momentum() {
    let s = run(HS, &[]);
    assert_eq!(s.events, 100_000);
    assert!(
        s.relative_energy_drift <= 1e-13,
        "{}",
        s.relative_energy_drift
    );
    assert!(s.momentum_drift <= 1e-13, "{}", s.momentum_drift);
    assert_eq!(s.anomalies, 0);
    assert_eq!(s.energy_potential, 0.0);
    // Short run, small system: only a loose check of the pressure (Z ≈ 7.77 at ρ = 0.8).
    assert!(
        (s.compressibility - 7.77).abs() < 0.4,
        "Z = {}",
        s.compressibility
    );
    assert!((s.temperature - 1.0).abs() < 1e-12);
}

#[test]
fn square_wells_conserve_total_energy() {
    let s = run(SW, &[]);
    let k = &s.events_by_kind;
    assert!(k["step_in"] > 1000 && k["step_out"] > 1000 && k["step_reflect"] > 100);
    assert!(
        s.relative_energy_drift <= 1e-12,
        "{}",
        s.relative_energy_drift
    );
    assert!(s.momentum_drift <= 1e-13, "{}", s.momentum_drift);
    assert_eq!(s.anomalies, 0);
    assert!(s.potential_energy_per_body < -1.0);
}

#[test]
fn stepped_mixture_with_mass_ratio_ten_thousand_conserves() {
    let s = run(MIXTURE, &[]);
    assert!(
        s.relative_energy_drift <= 1e-12,
        "{}",
        s.relative_energy_drift
    );
    assert!(s.momentum_drift <= 1e-12, "{}", s.momentum_drift);
    assert_eq!(s.anomalies, 0);
}

#[test]
fn runs_are_bit_identical_across_repeats_and_queues() {
    let a = physics(&run(SW, &[]));
    assert_eq!(
        a,
        physics(&run(SW, &[])),
        "same scene and seed, different physics"
    );
    // The calendar (the default) and the tree order by (time, body), the lazy queues by
    // (time, arrival): they differ only at exactly equal times, which these runs never meet.
    for queue in ["bounded", "heap", "tournament"] {
        let set = format!("run.queue={queue}");
        assert_eq!(a, physics(&run(SW, &[&set])), "calendar vs {queue}");
    }
    assert_ne!(a, physics(&run(SW, &["seed=10"])), "the seed has no effect");
    let b = physics(&run(HS, &[]));
    assert_eq!(b, physics(&run(HS, &["run.queue=bounded"])));
}

#[test]
fn rebasing_often_changes_nothing_but_round_off() {
    let rare = run(SW, &[]);
    let often = run(SW, &["run.rebase_events=997"]);
    assert!(often.events_by_kind["rebases"] >= 100);
    assert!(often.relative_energy_drift <= 1e-12);
    assert_eq!(often.anomalies, 0);
    // Same statistics (the trajectories part ways at round-off level, then chaotically).
    assert!((often.potential_energy_per_body - rare.potential_energy_per_body).abs() < 0.1);
}

/// Starting the clock at 10¹² (as after a very long run) leaves about 10⁻⁴ of absolute time
/// resolution: without re-basing, collisions are found at the wrong places. Re-basing moves
/// the origin back to zero and the run is clean again.
#[test]
fn huge_times_need_the_rebased_origin() {
    let pots = Potentials::from_tables(1, &[((0, 0), vec![[1.0, f64::INFINITY]])]);
    let model = || HardSpheres::new(pots.clone(), vec![Particle::new(1.0).unwrap()]);
    let per_side = 5;
    let spacing = 1.4;
    let l = DVec3::splat(per_side as f64 * spacing);
    let mut r = Vec::new();
    for x in 0..per_side {
        for y in 0..per_side {
            for z in 0..per_side {
                r.push((DVec3::new(x as f64, y as f64, z as f64) + 0.5) * spacing);
            }
        }
    }
    let v = dmd_sim::init::maxwell_boltzmann(&vec![1.0; r.len()], 1.0, 4);
    let species = vec![0; r.len()];
    let go = |rebase: bool| {
        let settings = LoopSettings {
            rebase_events: if rebase { 1000 } else { u64::MAX },
            seed: 1,
            debug_check_events: 0,
            skin: 0.2,
            start_time: 1e12,
        };
        let mut sim: Simulation<_, LazyQueue<BoundedQueue<Ticket>>> =
            Simulation::new(l, &r, &v, &species, model(), settings).unwrap();
        if rebase {
            sim.rebase();
        }
        sim.run(Stop::Events(20_000), &mut NoSampler, &mut |_| {})
            .unwrap();
        let k = sim.kinetic_energy();
        (sim.anomalies().total(), sim.check().is_ok(), k, sim.time())
    };
    let (bad, bad_ok, _, _) = go(false);
    assert!(
        bad > 0 || !bad_ok,
        "without re-basing the run should break at t = 1e12"
    );
    let (good, good_ok, k, t) = go(true);
    assert_eq!(good, 0);
    assert!(good_ok);
    assert!((k - 1.5 * 124.0).abs() < 1e-9);
    assert!(t > 1e12);
}

#[test]
fn andersen_thermostat_brings_the_temperature_to_the_bath() {
    let s = run(
        HS,
        &[
            "init.temperature=3.0",
            "thermostat.kind=andersen",
            "thermostat.rate=2.0",
            "thermostat.temperature=1.0",
            "run.equilibration_events=60000",
            "run.events=60000",
        ],
    );
    // Production is NVE from the thermostatted state: T near 1, energy conserved again.
    assert!((s.temperature - 1.0).abs() < 0.08, "T = {}", s.temperature);
    assert!(s.relative_energy_drift <= 1e-13);
    assert!(s.momentum_drift <= 1e-13);
    let always = run(
        HS,
        &[
            "thermostat.kind=andersen",
            "thermostat.rate=1.0",
            "thermostat.during=always",
            "run.equilibration_events=0",
        ],
    );
    assert!(always.events_by_kind["thermostat"] > 100);
    assert_eq!(always.degrees_of_freedom, 3.0 * 256.0);
}

#[test]
fn a_time_limited_run_ends_exactly_on_time() {
    let s = run(HS, &["run.events=", "run.time=1.25"]);
    assert_eq!(s.sim_time, 1.25);
    assert!(s.events > 1000);
}

#[test]
fn outputs_are_written_with_headers() {
    let dir = std::env::temp_dir().join(format!("dmd-physics-out-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scene = Scene::from_str_with(
        SW,
        &[
            "run.events=40000".into(),
            "output.sample_interval=0.05".into(),
            "output.rdf={ bins = 50, r_max = 3.0 }".into(),
            "output.msd={ max_lag = 0.5 }".into(),
            "output.vacf={ max_lag = 0.5 }".into(),
            "output.series=true".into(),
            "output.trajectory={ interval = 0.5 }".into(),
        ],
    )
    .unwrap();
    let s = run_scene(&scene, Path::new("."), Some(&dir), &mut Quiet).unwrap();
    for (file, header) in [
        ("rdf.csv", "r,g,g_error"),
        ("msd.csv", "t,msd,msd_error"),
        (
            "vacf.csv",
            "t,vacf,vacf_error,vacf_normalised,vacf_normalised_error",
        ),
        (
            "series.csv",
            "t,kinetic,potential,total,temperature,pressure",
        ),
    ] {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        assert_eq!(text.lines().next().unwrap(), header, "{file}");
        assert!(text.lines().count() > 5, "{file} is nearly empty");
    }
    for svg in [
        "rdf.svg",
        "msd.svg",
        "vacf.svg",
        "series-energy.svg",
        "series-pressure.svg",
    ] {
        let text = std::fs::read_to_string(dir.join(svg)).unwrap();
        assert!(text.starts_with("<svg"), "{svg}");
    }
    // g(r) is zero inside the core and peaks just outside it.
    let rdf: Vec<(f64, f64)> = std::fs::read_to_string(dir.join("rdf.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let mut f = l.split(',').map(|x| x.parse::<f64>().unwrap());
            (f.next().unwrap(), f.next().unwrap())
        })
        .collect();
    assert!(rdf.iter().filter(|p| p.0 < 0.95).all(|p| p.1 == 0.0));
    let peak = rdf
        .iter()
        .cloned()
        .fold((0.0, 0.0), |a, p| if p.1 > a.1 { p } else { a });
    assert!(
        peak.0 > 1.0 && peak.0 < 1.2 && peak.1 > 1.5,
        "peak {peak:?}"
    );
    // The extended XYZ trajectory: frames of N lines with the OVITO properties.
    let xyz = std::fs::read_to_string(dir.join("trajectory.xyz")).unwrap();
    let lines: Vec<&str> = xyz.lines().collect();
    assert_eq!(lines[0], "256");
    assert!(lines[1].contains(
        "Properties=species:S:1:pos:R:3:velo:R:3:map_shift:I:3:Z:I:1:masses:R:1:momenta:R:3:id:I:1"
    ));
    assert!(lines[1].starts_with("Lattice=\""));
    assert_eq!(lines[2].split_whitespace().count(), 16);
    assert!(lines.len() >= 2 * 258);
    // The summary mirrors the files and the diffusion estimates exist.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    for key in [
        "events",
        "events_by_kind",
        "wall_seconds",
        "events_per_second",
        "sim_time",
        "n_bodies",
        "density",
        "temperature",
        "pressure",
        "mean_free_time",
        "energy_kinetic",
        "energy_potential",
        "energy_total_start",
        "energy_total_end",
        "relative_energy_drift",
        "momentum_drift",
        "anomalies",
    ] {
        assert!(json.get(key).is_some(), "summary.json lacks {key}");
    }
    assert!(s.diffusion_msd.unwrap() > 0.0 && s.diffusion_vacf.unwrap() > 0.0);
    assert!(s.files.contains(&"trajectory.xyz".to_owned()));
    assert!(std::fs::read_dir(&dir).unwrap().all(|e| {
        !e.unwrap()
            .file_name()
            .to_string_lossy()
            .ends_with(".partial")
    }));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A box between two and three interaction reaches wide has two cells along each axis, so a
/// body's neighbourhood visits the other cell twice, one box length apart. The run must be the
/// run of the same bodies periodically repeated 2 × 2 × 2 times in a box twice as wide (four
/// cells along each axis, every neighbourhood distinct): the same positions of each body and
/// its first replica, eight times the collisions, energies and virial, and a stored potential
/// energy that its recomputation from the pair levels agrees with (each pair counted once).
#[test]
fn a_box_of_two_cells_runs_as_its_periodic_repeat_in_a_box_of_four() {
    let pots = Potentials::from_tables(1, &[((0, 0), vec![[1.0, f64::INFINITY], [1.5, -1.0]])]);
    let model = |n| Stepped::new(pots.clone(), vec![Particle::new(1.0).unwrap()], n);
    // fcc, 2 × 2 × 2 cells of side 2: 32 bodies in a box of 4, nearest neighbours √2 apart.
    let l = 4.0;
    let basis = [
        DVec3::ZERO,
        DVec3::new(0.5, 0.5, 0.0),
        DVec3::new(0.5, 0.0, 0.5),
        DVec3::new(0.0, 0.5, 0.5),
    ];
    let mut r = Vec::new();
    for x in 0..2 {
        for y in 0..2 {
            for z in 0..2 {
                for b in basis {
                    r.push((DVec3::new(x as f64, y as f64, z as f64) + b + 0.25) * 2.0);
                }
            }
        }
    }
    let v = dmd_sim::init::maxwell_boltzmann(&vec![1.0; r.len()], 1.5, 7);
    let (mut r8, mut v8) = (r.clone(), v.clone());
    for k in 1..8 {
        let shift = DVec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, (k >> 2) as f64) * l;
        r8.extend(r.iter().map(|&p| p + shift));
        v8.extend_from_slice(&v);
    }
    let settings = LoopSettings {
        rebase_events: u64::MAX,
        seed: 1,
        debug_check_events: 64,
        skin: 0.1,
        start_time: 0.0,
    };
    let go = |lengths: f64, r: &[DVec3], v: &[DVec3]| {
        let species = vec![0; r.len()];
        let mut sim: Simulation<_, LazyQueue<BoundedQueue<Ticket>>> = Simulation::new(
            DVec3::splat(lengths),
            r,
            v,
            &species,
            model(r.len()),
            settings,
        )
        .unwrap();
        sim.run(Stop::Time(2.0), &mut NoSampler, &mut |_| {})
            .unwrap();
        sim
    };
    let small = go(l, &r, &v);
    let big = go(2.0 * l, &r8, &v8);
    assert_eq!(small.cells().dims(), [2, 2, 2]);
    assert_eq!(big.cells().dims(), [4, 4, 4]);
    for sim in [&small, &big] {
        sim.check().unwrap();
        assert_eq!(sim.anomalies().total(), 0);
        let (stored, recomputed) = (sim.tracked_potential(), sim.potential_energy());
        assert!((stored - recomputed).abs() < 1e-9, "{stored} {recomputed}");
    }
    let (c1, c8) = (small.counters(), big.counters());
    assert!(c1.pair_events() > 200, "{c1:?}");
    assert_eq!(8 * c1.pair_events(), c8.pair_events(), "{c1:?} {c8:?}");
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1.0);
    assert!(close(
        8.0 * small.potential_energy(),
        big.potential_energy()
    ));
    assert!(close(8.0 * small.kinetic_energy(), big.kinetic_energy()));
    assert!(close(8.0 * small.virial(), big.virial()));
    let (p1, p8) = (small.positions(), big.positions());
    for i in 0..r.len() {
        let mut d = p1[i] - p8[i];
        d -= (d / l).round() * l;
        assert!(d.length() < 1e-9, "body {i}: {d}");
    }
}
