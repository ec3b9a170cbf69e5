//! The estimators of the continuous model along a terraced trajectory (the smooth potential's
//! energy and pressure at every sample), and production starting at the bath temperature.

use std::path::Path;
use std::sync::LazyLock;

use dmd_sim::scene::Scene;
use dmd_sim::search::SearchSettings;
use dmd_sim::simulation::{LoopSettings, Sampler, Simulation, Stop, View};
use dmd_sim::smooth::{Estimator, Evaluate};
use dmd_sim::terraced::{PairTerraces, RodSpecies, Terraced};
use event_queue::{BoundedQueue, LazyQueue, Ticket};
use glam::DVec3;
use potential::{LjRod, PairGeometry, PairPotential, Smoothed, TerraceMap, TerraceOptions};

use crate::support::{REDUCED_RODS, run_with as run};

type Queue = LazyQueue<BoundedQueue<Ticket>>;

/// The rods of `support`, sampled every 0.01 τ.
static RODS: LazyLock<String> =
    LazyLock::new(|| format!("{REDUCED_RODS}[output]\nsample_interval = 0.01\n"));

#[test]
fn production_starts_at_the_bath_temperature() {
    let s = run(&RODS, &[]);
    let t = 1.4;
    assert!(
        (s.temperature_start - t).abs() <= 1e-10 * t,
        "production starts at {} instead of {t}",
        s.temperature_start
    );
    // The rescaling re-predicted every event: production is as exact as ever.
    assert!(
        s.relative_energy_drift <= 1e-12,
        "drift {}",
        s.relative_energy_drift
    );
    assert!(s.momentum_drift < 1e-12, "{}", s.momentum_drift);
    assert_eq!(s.anomalies, 0, "{:?}", s.anomalies_by_kind);
    assert_eq!(s.detected_misses, 0);
    assert!(s.terrace_crossings > 0);
    // The mean over production comes with its blocking error.
    let err = s.temperature_error.expect("sampled");
    assert!(err.is_finite() && err > 0.0 && err < 0.2, "{err}");

    // Without the rescaling, production starts wherever the stochastic thermostat left it
    // (125 rods: a few per cent off), and still conserves energy.
    let off = run(&RODS, &["thermostat.rescale_at_end=false"]);
    assert!(
        (off.temperature_start - t).abs() > 1e-6 * t,
        "{}",
        off.temperature_start
    );
    assert!(off.relative_energy_drift <= 1e-12);
    // The same equilibration: only the factor differs.
    assert_eq!(off.equilibration_events, s.equilibration_events);
}

#[test]
fn the_smooth_estimators_are_reported_beside_the_terraced_values() {
    // At every sample: this short run has too few samples at the default stride for errors.
    let s = run(&RODS, &["output.smooth_every=1"]);
    let u = s.potential_energy_per_body_smooth.expect("on by default");
    let p = s.pressure_smooth.expect("on by default");
    let (ue, pe) = (
        s.potential_energy_per_body_smooth_error.unwrap(),
        s.pressure_smooth_error.unwrap(),
    );
    // A liquid of attracting rods: negative energy near the terraced one, finite errors.
    assert!(
        u < -1.0 && (u - s.potential_energy_per_body).abs() < 1.0,
        "{u} vs {s:?}"
    );
    assert!(p.is_finite() && ue > 0.0 && pe > 0.0, "{p} {ue} {pe}");
    assert!(s.pressure_error.unwrap() > 0.0);
    assert!(s.potential_energy_per_body_error.unwrap() > 0.0);
    // Switched off: the same trajectory, no smooth keys.
    let off = run(&RODS, &["output.smooth_estimators=false"]);
    assert_eq!(off.potential_energy_per_body_smooth, None);
    assert_eq!(off.pressure_smooth, None);
    assert_eq!(off.events, s.events);
    assert_eq!(off.energy_total_end, s.energy_total_end);
    // No sampling interval: nothing sampled, nothing estimated.
    let text = RODS.replace("[output]\nsample_interval = 0.01\n", "");
    let none = run(&text, &[]);
    assert_eq!(none.pressure_smooth, None);
    assert_eq!(none.temperature_error, None);
}

#[test]
fn the_smd_engine_reports_its_own_values_under_the_smooth_names() {
    let o: Vec<String> = ["engine=\"smd\"", "smd.dt=0.001"]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    let scene = Scene::from_str_with(&RODS, &o).unwrap();
    let s = dmd_sim::smd_engine::run(&scene, Path::new("."), None).unwrap();
    assert_eq!(
        s.potential_energy_per_body_smooth,
        s.potential_energy_per_body
    );
    assert_eq!(s.pressure_smooth, s.pressure);
    assert_eq!(
        s.potential_energy_per_body_smooth_error,
        s.potential_energy_per_body_error
    );
    assert!(s.pressure_smooth_error > 0.0 && s.potential_energy_per_body_error > 0.0);
    // Its last velocity rescaling puts production at the bath temperature too.
    assert!(
        (s.temperature_start - 1.4).abs() <= 1e-10 * 1.4,
        "{}",
        s.temperature_start
    );
}

/// At ΔV = kT/4 the terraced trajectory's estimate of the continuous model's energy is closer
/// to standard MD on the smoothed potential than the terraced energy itself (which misses the
/// tail beyond the outermost level and the energy within each terrace).
#[test]
fn at_a_quarter_kt_the_smooth_estimate_is_closer_to_standard_md_than_the_terraces() {
    let dmd = run(&RODS, &["pair.0.terraces.step_kt=0.25", "run.time=1"]);
    let o: Vec<String> = ["engine=\"smd\"", "run.time=1"]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    let scene = Scene::from_str_with(&RODS, &o).unwrap();
    let smd = dmd_sim::smd_engine::run(&scene, Path::new("."), None).unwrap();
    let reference = smd.potential_energy_per_body;
    let smooth = dmd.potential_energy_per_body_smooth.unwrap();
    let terraced = dmd.potential_energy_per_body;
    eprintln!(
        "U/N: smd {reference} ± {}, dmd smooth {smooth} ± {:?}, dmd terraced {terraced} ± {:?}",
        smd.potential_energy_per_body_error,
        dmd.potential_energy_per_body_smooth_error,
        dmd.potential_energy_per_body_error
    );
    assert!(
        (smooth - reference).abs() < (terraced - reference).abs(),
        "smooth {smooth}, terraced {terraced}, smd {reference}"
    );
    assert!(dmd.relative_energy_drift <= 1e-12);
}

/// Lennard-Jones spheres on terraces run as radial steps; their summary carries the smooth
/// estimators too, and at ΔV = kT/4 those are within 3 % of standard MD on the smoothed
/// potential in U/N (two short NVE runs, each at its own temperature), where the terraced
/// energy is off by more than 10 %.
#[test]
fn lennard_jones_spheres_on_terraces_carry_the_smooth_estimators() {
    const SPHERES: &str = r#"
version = 1
seed = 5
[box]
density = 0.6
[[species]]
name = "LJ"
count = 256
[[pair]]
species = ["LJ", "LJ"]
potential = { kind = "lennard-jones", epsilon = 1.0, sigma = 1.0 }
terraces = { step_kt = 0.25 }
[init]
positions = "fcc"
temperature = 1.5
[thermostat]
kind = "andersen"
rate = 1.0
[run]
equilibration_time = 1.0
time = 4.0
[output]
sample_interval = 0.02
"#;
    let dmd = run(SPHERES, &[]);
    assert_eq!(dmd.model, "stepped");
    let scene = Scene::from_str_with(SPHERES, &["engine=\"smd\"".to_owned()]).unwrap();
    let smd = dmd_sim::smd_engine::run(&scene, Path::new("."), None).unwrap();
    let reference = smd.potential_energy_per_body;
    let smooth = dmd.potential_energy_per_body_smooth.unwrap();
    let terraced = dmd.potential_energy_per_body;
    eprintln!("U/N: smd {reference}, dmd smooth {smooth}, dmd terraced {terraced}");
    assert!(
        ((smooth - reference) / reference).abs() < 0.03,
        "smooth {smooth}, smd {reference}"
    );
    assert!(
        ((terraced - reference) / reference).abs() > 0.1,
        "terraced {terraced}, smd {reference}"
    );
    assert!(dmd.pressure_smooth.is_some_and(f64::is_finite));
    // Explicit steps have no smooth potential: no estimate.
    let steps = run(
        SPHERES,
        &[
            "pair.0.potential=",
            "pair.0.terraces=",
            "pair.0.steps=[[1.0, inf]]",
        ],
    );
    assert!(steps.potential_energy_per_body_smooth.is_none());
}

/// Compares the estimator with an all-pairs sum at every sample.
struct BruteForce {
    estimator: Estimator<LjRod>,
    smooth: Smoothed<LjRod>,
    samples: usize,
    pairs_in_range: usize,
}

impl Sampler for BruteForce {
    fn sample(&mut self, view: &View<'_>) {
        let got = self.estimator.evaluate(view);
        let l = view.lengths;
        let r_u = self.smooth.window().1;
        let (mut u, mut w, mut w_abs) = (0.0, 0.0, 0.0);
        let n = view.bodies.len();
        for i in 0..n {
            for j in i + 1..n {
                let mut d = view.position(i) - view.position(j);
                d -= l * (d / l).round();
                if d.length_squared() >= r_u * r_u {
                    continue;
                }
                self.pairs_in_range += 1;
                let ev = self
                    .smooth
                    .evaluate(&PairGeometry::new(d, view.axes[i], view.axes[j]))
                    .unwrap();
                u += ev.energy;
                w += d.dot(ev.force);
                w_abs += d.dot(ev.force).abs();
            }
        }
        assert!(
            (got.energy - u).abs() <= 1e-12 * u.abs(),
            "U: estimator {} brute force {u}",
            got.energy
        );
        // The virial sums terms of both signs: relative to the sum of their sizes.
        assert!(
            (got.virial - w).abs() <= 1e-12 * w_abs,
            "W: estimator {} brute force {w} (Σ|w| {w_abs})",
            got.virial
        );
        self.samples += 1;
    }
}

#[test]
fn the_estimator_is_the_all_pairs_sum_at_every_sample() {
    // 216 rods at ρ = 0.5 (box 7.56) with the switch between 1.6 and 2.2: three cells of the
    // cut-off fit along each axis, so the estimator's cell search is what is compared.
    let rod = LjRod::new(1.0, 1.0, 0.33).unwrap();
    let map = TerraceMap::evenly_spaced(&rod, 0.5, &TerraceOptions::default()).unwrap();
    let k = 6;
    let n = k * k * k;
    let l = (n as f64 / 0.5_f64).cbrt();
    let a = l / k as f64;
    let mut r = Vec::new();
    for x in 0..k {
        for y in 0..k {
            for z in 0..k {
                r.push((DVec3::new(x as f64, y as f64, z as f64) + 0.5) * a);
            }
        }
    }
    let v = dmd_sim::init::maxwell_boltzmann(&vec![1.0; n], 1.4, 5);
    let axes = dmd_sim::rods::random_axes(n, 5);
    let omegas = dmd_sim::rods::equipartitioned_omegas(&axes, &vec![0.007; n], 1.4, 5);
    let model = Terraced::new(
        vec![RodSpecies {
            mass: 1.0,
            inertia: 0.007,
        }],
        vec![((0, 0), PairTerraces::new(rod, map).unwrap())],
        &vec![0; n],
        &axes,
        &omegas,
        0.0,
        SearchSettings::paper(0.01),
        9,
    )
    .unwrap();
    let settings = LoopSettings {
        rebase_events: 1_000_000,
        seed: 3,
        debug_check_events: 0,
        skin: 0.15,
        start_time: 0.0,
    };
    let mut sim: Simulation<_, Queue> =
        Simulation::new(DVec3::splat(l), &r, &v, &vec![0; n], model, settings).unwrap();
    let (r_l, r_u) = (1.6, 2.2);
    assert!(l / r_u >= 3.0);
    let smooth = Smoothed::new(rod, r_l, r_u).unwrap();
    let mut check = BruteForce {
        estimator: Estimator::new(1, vec![((0, 0), smooth)]),
        smooth,
        samples: 0,
        pairs_in_range: 0,
    };
    sim.begin_phase(false, Some(0.02), None);
    sim.run(Stop::Time(0.3), &mut check, &mut |_| {}).unwrap();
    assert!(check.samples >= 15, "{} samples", check.samples);
    assert!(check.pairs_in_range > 10 * n, "{}", check.pairs_in_range);
    assert!(sim.counters().pair_events() > 100);
}
