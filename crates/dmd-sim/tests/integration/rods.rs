//! Rigid rods on terraced potentials through the event loop: conservation, the sphere limit,
//! virtual events, extreme starts.

use collide::Particle;
use dmd_sim::model::{Pair, PairModel, Stepped};
use dmd_sim::potential::Potentials;
use dmd_sim::search::SearchSettings;
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use dmd_sim::terraced::{PairTerraces, RodSpecies, Terraced, radial_steps};
use event_queue::{BoundedQueue, LazyQueue, Ticket};
use glam::DVec3;
use potential::{LennardJones, LjRod, PairPotential, TerraceMap, TerraceOptions, profile};

type Queue = LazyQueue<BoundedQueue<Ticket>>;

fn settings(skin: f64) -> LoopSettings {
    LoopSettings {
        rebase_events: 1_000_000,
        seed: 3,
        debug_check_events: 500,
        skin,
        start_time: 0.0,
    }
}

/// A simple cubic lattice of `k³` sites at number density `rho`.
fn lattice(k: usize, rho: f64) -> (f64, Vec<DVec3>) {
    let n = k * k * k;
    let l = (n as f64 / rho).cbrt();
    let a = l / k as f64;
    let mut r = Vec::new();
    for x in 0..k {
        for y in 0..k {
            for z in 0..k {
                r.push((DVec3::new(x as f64, y as f64, z as f64) + 0.5) * a);
            }
        }
    }
    (l, r)
}

fn rods_model<P: PairPotential>(
    pot: P,
    map: TerraceMap,
    axes: &[DVec3],
    omegas: &[DVec3],
    search: SearchSettings,
) -> Terraced<P> {
    let n = axes.len();
    Terraced::new(
        vec![RodSpecies {
            mass: 1.0,
            inertia: 0.1,
        }],
        vec![((0, 0), PairTerraces::new(pot, map).unwrap())],
        &vec![0; n],
        axes,
        omegas,
        0.0,
        search,
        9,
    )
    .unwrap()
}

#[test]
fn smoke_rods_conserve_energy_and_momentum() {
    let rod = LjRod::new(1.0, 1.0, 0.3).unwrap();
    let map = TerraceMap::evenly_spaced(&rod, 0.5, &TerraceOptions::default()).unwrap();
    let (l, r) = lattice(5, 0.3);
    let n = r.len();
    let v = dmd_sim::init::maxwell_boltzmann(&vec![1.0; n], 1.5, 4);
    let axes: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new((i as f64).sin(), (1.3 * i as f64).cos(), 0.4).normalize())
        .collect();
    let omegas: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new(0.3 * (i as f64).cos(), 1.0, -0.5) * 2.0)
        .collect();
    let model = rods_model(rod, map, &axes, &omegas, SearchSettings::paper(0.02));
    let mut sim: Simulation<_, Queue> =
        Simulation::new(DVec3::splat(l), &r, &v, &vec![0; n], model, settings(0.2)).unwrap();
    let e0 = sim.kinetic_energy() + sim.potential_energy();
    let (p0, _) = sim.momentum_and_mass();
    sim.run(Stop::Events(20_000), &mut NoSampler, &mut |_| {})
        .unwrap();
    let e1 = sim.kinetic_energy() + sim.potential_energy();
    let (p1, _) = sim.momentum_and_mass();
    let c = sim.counters();
    let st = sim.model().search_stats();
    eprintln!("{c:?}\n{st:?}\n{:?} E {e0} -> {e1}", sim.anomalies());
    assert!((e1 - e0).abs() < 1e-10 * e0.abs().max(1.0));
    assert!((p1 - p0).length() < 1e-12);
    assert!(c.step_in > 100 && c.step_out > 100 && c.virtual_ > 100);
    sim.check().unwrap();
}

/// Lennard-Jones spheres through the root-search path agree with the same terraces as radial
/// steps with analytic event times (the ζ = 0 case of 003 Eq. 22): every event at the same
/// time, to the root tolerance, until chaos separates the runs.
#[test]
fn isotropic_terraces_match_the_analytic_stepped_path() {
    let lj = LennardJones::new(1.0, 1.0).unwrap();
    let map = TerraceMap::evenly_spaced(&lj, 0.3, &TerraceOptions::default()).unwrap();
    let steps = radial_steps(&profile::lennard_jones(&lj).unwrap(), &map).unwrap();
    let (l, r) = lattice(5, 0.4);
    let n = r.len();
    let v = dmd_sim::init::maxwell_boltzmann(&vec![1.0; n], 1.2, 8);
    let axes = vec![DVec3::Z; n];
    let rods = rods_model(
        lj,
        map,
        &axes,
        &vec![DVec3::ZERO; n],
        SearchSettings::paper(0.01),
    );
    let stepped = Stepped::new(
        Potentials::from_tables(1, &[((0, 0), steps)]),
        vec![Particle::new(1.0).unwrap()],
        n,
    );
    let mut a: Simulation<_, Queue> =
        Simulation::new(DVec3::splat(l), &r, &v, &vec![0; n], rods, settings(0.2)).unwrap();
    let mut b: Simulation<_, Queue> =
        Simulation::new(DVec3::splat(l), &r, &v, &vec![0; n], stepped, settings(0.2)).unwrap();
    assert_eq!(a.potential_energy(), b.potential_energy());
    a.run(Stop::Time(0.3), &mut NoSampler, &mut |_| {}).unwrap();
    b.run(Stop::Time(0.3), &mut NoSampler, &mut |_| {}).unwrap();
    let (ca, cb) = (a.counters(), b.counters());
    assert!(cb.pair_events() > 300, "{cb:?}");
    // (Radially inwards is down in U on the attractive branch: the terraced model counts
    // crossings up and down in U, the stepped one inwards and outwards, so only sums compare.)
    assert_eq!(
        (ca.core, ca.step_in + ca.step_out, ca.step_reflect),
        (cb.core, cb.step_in + cb.step_out, cb.step_reflect)
    );
    let worst = a
        .positions()
        .iter()
        .zip(b.positions())
        .map(|(p, q)| (*p - q).length())
        .fold(0.0, f64::max);
    assert!(worst < 1e-7, "positions differ by {worst}");
    assert_eq!(a.potential_energy(), b.potential_energy());
}

/// A cluster of rods far from the box walls: total angular momentum (orbital and spin) is
/// conserved through thousands of impulses (003 Eq. 6 holds for the rods' torques).
#[test]
fn a_free_cluster_conserves_angular_momentum() {
    let rod = LjRod::new(1.0, 1.0, 0.3).unwrap();
    let map = TerraceMap::evenly_spaced(&rod, 0.25, &TerraceOptions::default()).unwrap();
    let mut r = Vec::new();
    for x in 0..3 {
        for y in 0..3 {
            for z in 0..3 {
                r.push(DVec3::new(x as f64, y as f64, z as f64) * 1.15 + 14.0);
            }
        }
    }
    let n = r.len();
    let v = dmd_sim::init::maxwell_boltzmann(&vec![1.0; n], 0.4, 2);
    let axes: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new((2.0 * i as f64).sin(), (i as f64).cos(), 0.7).normalize())
        .collect();
    let omegas: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new(1.0, (i as f64).sin(), -0.3))
        .collect();
    let model = rods_model(rod, map, &axes, &omegas, SearchSettings::paper(0.01));
    let mut sim: Simulation<_, Queue> = Simulation::new(
        DVec3::splat(30.0),
        &r,
        &v,
        &vec![0; n],
        model,
        settings(0.3),
    )
    .unwrap();
    let l0 = sim.angular_momentum();
    let e0 = sim.kinetic_energy() + sim.potential_energy();
    sim.run(Stop::Events(20_000), &mut NoSampler, &mut |_| {})
        .unwrap();
    let l1 = sim.angular_momentum();
    let e1 = sim.kinetic_energy() + sim.potential_energy();
    let c = sim.counters();
    assert!(c.pair_events() > 2000, "{c:?}");
    // Scale: Σ m |r||v| of the cluster.
    let scale: f64 = sim
        .positions()
        .iter()
        .zip(sim.bodies())
        .map(|(p, b)| p.length() * b.v.length())
        .sum();
    assert!(
        (l1 - l0).length() < 1e-12 * scale,
        "L {l0} -> {l1} (scale {scale})"
    );
    assert!((e1 - e0).abs() < 1e-12 * e0.abs().max(1.0), "{e0} {e1}");
    // The spins took part: the rods' angular velocities changed.
    let moved = (0..n as u32)
        .filter(|&i| (sim.model().omega(i) - omegas[i as usize]).length() > 1e-3)
        .count();
    assert!(moved > n / 2);
}

/// All rods exactly parallel (u_i × u_j = 0: no torque at all), at rest in rotation: the run
/// advances (no livelock of virtual events at t = 0), and rotation starts once... never: with
/// parallel axes and no angular velocity the torques stay zero, so the rods stay parallel.
#[test]
fn exactly_parallel_rods_run() {
    let rod = LjRod::new(1.0, 1.0, 0.3).unwrap();
    let map = TerraceMap::evenly_spaced(&rod, 0.5, &TerraceOptions::default()).unwrap();
    let (l, r) = lattice(5, 0.5);
    let n = r.len();
    let v = dmd_sim::init::maxwell_boltzmann(&vec![1.0; n], 1.4, 5);
    let model = rods_model(
        rod,
        map,
        &vec![DVec3::Z; n],
        &vec![DVec3::ZERO; n],
        SearchSettings::paper(0.01),
    );
    let mut sim: Simulation<_, Queue> =
        Simulation::new(DVec3::splat(l), &r, &v, &vec![0; n], model, settings(0.15)).unwrap();
    sim.run(Stop::Events(5_000), &mut NoSampler, &mut |_| {})
        .unwrap();
    assert!(sim.time() > 0.05, "time {}", sim.time());
    assert!(sim.counters().pair_events() > 1000);
    for i in 0..n as u32 {
        assert_eq!(sim.model().axis(i, sim.now()), Some(DVec3::Z));
    }
    // Now with angular velocities: parallel at the start, torques appear as they turn.
    let omegas: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new((i as f64).cos(), (i as f64).sin(), 0.0) * 3.0)
        .collect();
    let model = rods_model(
        rod,
        TerraceMap::evenly_spaced(&rod, 0.5, &TerraceOptions::default()).unwrap(),
        &vec![DVec3::Z; n],
        &omegas,
        SearchSettings::paper(0.01),
    );
    let mut sim: Simulation<_, Queue> =
        Simulation::new(DVec3::splat(l), &r, &v, &vec![0; n], model, settings(0.15)).unwrap();
    let e0 = sim.kinetic_energy() + sim.potential_energy();
    sim.run(Stop::Events(5_000), &mut NoSampler, &mut |_| {})
        .unwrap();
    let e1 = sim.kinetic_energy() + sim.potential_energy();
    assert!(sim.time() > 0.05);
    assert!((e1 - e0).abs() < 1e-12 * e0.abs());
}

/// Two rods far apart in a large box, `b` apart sideways, meeting at speed `speed` (equal
/// masses, opposite velocities along x).
fn two_rods(
    rod: LjRod,
    step: f64,
    b: f64,
    axes: [DVec3; 2],
    omegas: [DVec3; 2],
    speed: f64,
) -> Simulation<Terraced<LjRod>, Queue> {
    let map = TerraceMap::evenly_spaced(&rod, step, &TerraceOptions::default()).unwrap();
    let pos = [
        DVec3::new(5.0, 10.0, 10.0),
        DVec3::new(15.0, 10.0 + b, 10.0),
    ];
    let vel = [DVec3::X * speed, -DVec3::X * speed];
    let model = rods_model(rod, map, &axes, &omegas, SearchSettings::paper(0.01));
    Simulation::new(
        DVec3::splat(20.0),
        &pos,
        &vel,
        &[0, 0],
        model,
        settings(0.3),
    )
    .unwrap()
}

/// A head-on encounter: in through the terraces, reflected or across the well, and out again
/// with the kinetic energy it came with (translation and rotation together) and the pair back
/// on the zero terrace.
#[test]
fn head_on_encounter_comes_out_as_it_went_in() {
    let rod = LjRod::new(1.0, 1.0, 0.3).unwrap();
    for (speed, axes) in [
        (1.0, [DVec3::Z, DVec3::Y]),
        (3.0, [DVec3::Z, DVec3::new(0.0, 0.6, 0.8)]),
        (0.3, [DVec3::Z, DVec3::Z]),
    ] {
        let mut sim = two_rods(rod, 0.2, 0.0, axes, [DVec3::ZERO; 2], speed);
        let k0 = sim.kinetic_energy();
        sim.run(Stop::Time(12.0 / speed), &mut NoSampler, &mut |_| {})
            .unwrap();
        let c = sim.counters();
        assert!(c.step_in + c.step_reflect > 5, "{speed}: {c:?}");
        assert_eq!(
            sim.potential_energy(),
            0.0,
            "{speed}: the pair is apart again"
        );
        let k1 = sim.kinetic_energy();
        assert!((k1 - k0).abs() < 1e-12 * k0, "{speed}: {k0} -> {k1}");
        let (p, _) = sim.momentum_and_mass();
        assert!(p.length() < 1e-14);
        assert_eq!(sim.model().search_stats().misfits, 0);
        assert_eq!(sim.anomalies().total(), 0);
    }
}

/// Parallel rods passing each other at impact parameter `b` around the reach `r_m`
/// (003 Eq. 25, the distance at which parallel rods reach the outermost level): a grazing
/// encounter crosses the level in and out when `b` is below it by one part in a million, and
/// never when it is above by as much.
#[test]
fn grazing_encounters_at_the_reach() {
    let rod = LjRod::new(1.0, 1.0, 0.3).unwrap();
    let step = 0.3;
    let map = TerraceMap::evenly_spaced(&rod, step, &TerraceOptions::default()).unwrap();
    let r_m = map.reach(&rod).unwrap();
    for (scale, crossings) in [(1.0 - 1e-6, 2), (1.0 + 1e-6, 0), (1.0 - 1e-12, 2)] {
        let mut sim = two_rods(
            rod,
            step,
            r_m * scale,
            [DVec3::Z, DVec3::Z],
            [DVec3::ZERO; 2],
            1.0,
        );
        sim.run(Stop::Time(12.0), &mut NoSampler, &mut |_| {})
            .unwrap();
        let c = sim.counters();
        assert_eq!(c.step_in + c.step_out, crossings, "b = {scale} r_m: {c:?}");
        assert_eq!(sim.potential_energy(), 0.0);
    }
}

/// Rods nearly parallel and nearly perpendicular, spinning: the torque `∝ (s_i·s_j) s_i × s_j`
/// is tiny at both, and energy and momentum are conserved through the encounter.
#[test]
fn nearly_parallel_and_nearly_perpendicular_encounters() {
    let rod = LjRod::new(1.0, 1.0, 0.3).unwrap();
    let tilt = 1e-7;
    for axes in [
        [DVec3::Z, DVec3::new(tilt, 0.0, 1.0).normalize()],
        [DVec3::Z, DVec3::new(0.0, 1.0, tilt).normalize()],
    ] {
        let omegas = [DVec3::X * 1e-6, DVec3::Y * 2.0];
        let mut sim = two_rods(rod, 0.25, 0.3, axes, omegas, 1.2);
        let k0 = sim.kinetic_energy();
        sim.run(Stop::Time(12.0), &mut NoSampler, &mut |_| {})
            .unwrap();
        assert!(sim.counters().pair_events() > 4);
        let k1 = sim.kinetic_energy() + sim.potential_energy();
        assert!((k1 - k0).abs() < 1e-12 * k0, "{k0} -> {k1}");
        assert_eq!(sim.anomalies().total(), 0);
    }
}

/// The fine-grid verification counts the events a coarse grid search steps over (a grid of 0.03
/// with no grazing detection), and none of the default adaptive search's. (Misses break the
/// loop's debug invariant that stored terraces match U, so the checks are off here.)
#[test]
fn verification_catches_the_misses_of_a_coarse_grid() {
    let rod = LjRod::new(1.0, 1.0, 0.33).unwrap();
    let (l, r) = lattice(5, 0.5);
    let n = r.len();
    let v = dmd_sim::init::maxwell_boltzmann(&vec![1.0; n], 1.4, 6);
    let axes: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new((i as f64).sin(), (2.3 * i as f64).cos(), 0.2).normalize())
        .collect();
    let omegas: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new((i as f64).cos(), -1.0, 0.5) * 8.0)
        .collect();
    let mut misses = Vec::new();
    for search in [
        SearchSettings {
            method: dmd_sim::search::SearchMethod::Grid { threshold: 0.0 },
            max_step: 0.03,
            verify_step: Some(0.0005),
            ..SearchSettings::paper(0.03)
        },
        SearchSettings {
            verify_step: Some(0.0005),
            ..SearchSettings::paper(0.005)
        },
    ] {
        let map = TerraceMap::evenly_spaced(&rod, 0.7, &TerraceOptions::default()).unwrap();
        let model = rods_model(rod, map, &axes, &omegas, search);
        let mut s = settings(0.2);
        s.debug_check_events = 0;
        let mut sim: Simulation<_, Queue> =
            Simulation::new(DVec3::splat(l), &r, &v, &vec![0; n], model, s).unwrap();
        sim.run(Stop::Events(30_000), &mut NoSampler, &mut |_| {})
            .unwrap();
        let st = sim.model().search_stats();
        assert_eq!(st.verified, st.searches);
        misses.push(st.verify_misses);
    }
    assert!(misses[0] > 10, "coarse grid: {misses:?}");
    assert_eq!(misses[1], 0, "adaptive: {misses:?}");
}

/// Certified prediction (`search.horizon`): the jumped stretches are searched again on the fine
/// grid and hold no event, stiff starts included (fast spin, dense); jumps really happen and
/// replace most evaluations; and the run follows the uncertified one event for event (the
/// same crossings and reflections, positions equal to round-off amplified by the dynamics).
#[test]
fn certified_prediction_misses_nothing_and_changes_no_event() {
    let rod = LjRod::new(1.0, 1.0, 0.33).unwrap();
    let (l, r) = lattice(5, 0.5);
    let n = r.len();
    let v = dmd_sim::init::maxwell_boltzmann(&vec![1.0; n], 1.4, 6);
    let axes: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new((i as f64).sin(), (2.3 * i as f64).cos(), 0.2).normalize())
        .collect();
    // Spins from slow to fast (up to ~40 radians per time unit).
    let omegas: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new((i as f64).cos(), -1.0, 0.5) * (1.0 + (i % 5) as f64 * 8.0))
        .collect();
    let run = |horizon: f64, stop: Stop| {
        // The scenes' default step limit by the speed of U (without it the adaptive search
        // itself steps over fast excursions through a level, certified or not).
        let search = SearchSettings {
            verify_step: Some(0.0005),
            horizon,
            max_change: 0.5,
            ..SearchSettings::paper(0.005)
        };
        let map = TerraceMap::evenly_spaced(&rod, 0.7, &TerraceOptions::default()).unwrap();
        let model = rods_model(rod, map, &axes, &omegas, search);
        let mut sim: Simulation<_, Queue> =
            Simulation::new(DVec3::splat(l), &r, &v, &vec![0; n], model, settings(0.2)).unwrap();
        let e0 = sim.kinetic_energy() + sim.potential_energy();
        sim.run(stop, &mut NoSampler, &mut |_| {}).unwrap();
        let e1 = sim.kinetic_energy() + sim.potential_energy();
        assert!((e1 - e0).abs() < 1e-12 * e0.abs(), "{e0} -> {e1}");
        assert_eq!(sim.anomalies().total(), 0);
        let st = sim.model().search_stats();
        (st, sim.counters(), sim.positions())
    };
    let (plain, _, _) = run(0.0, Stop::Time(1.5));
    let (cert, _, _) = run(0.02, Stop::Time(1.5));
    assert_eq!(plain.taylor_models, 0);
    assert_eq!(plain.verify_misses, 0, "{plain:?}");
    assert_eq!(cert.verify_misses, 0, "{cert:?}");
    assert_eq!(cert.off_terrace + cert.misfits, 0, "{cert:?}");
    assert!(cert.certified_jumps > 5_000, "{cert:?}");
    assert!(
        cert.evaluations < plain.evaluations / 2,
        "evaluations: {} certified, {} plain",
        cert.evaluations,
        plain.evaluations
    );
    // The same pair events over a stretch short enough for round-off not to grow.
    let (_, c_a, x_a) = run(0.0, Stop::Time(0.3));
    let (_, c_b, x_b) = run(0.02, Stop::Time(0.3));
    assert_eq!(c_a.pair_events(), c_b.pair_events());
    assert_eq!((c_a.step_in, c_a.step_out), (c_b.step_in, c_b.step_out));
    let worst = x_a
        .iter()
        .zip(&x_b)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "positions differ by {worst}");
}

/// The HMC hooks of the rods (issue 9): the canonical refresh draws `ω ⊥ axis` at the right
/// temperature, a reversal retraces the axes exactly, the extra state round-trips bit for bit
/// and refuses a foreign one, and the configured terrace agrees with the energy.
#[test]
fn hmc_hooks_of_the_rods() {
    use rand::SeedableRng;
    let rod = LjRod::new(1.0, 1.0, 0.3).unwrap();
    let map = TerraceMap::evenly_spaced(&rod, 0.5, &TerraceOptions::default()).unwrap();
    let n = 4000;
    let axes: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new((i as f64).sin(), (1.3 * i as f64).cos(), 0.4).normalize())
        .collect();
    let mut model = rods_model(
        rod,
        map,
        &axes,
        &vec![DVec3::ZERO; n],
        SearchSettings::paper(0.02),
    );
    assert_eq!(model.rotational_kinetic(), 0.0);
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(1);
    let kt = 1.7;
    model.draw_rotations(0.0, kt, &mut rng);
    // Two degrees of freedom per rod: ⟨K_rot⟩ = N kT (relative error ~ 1/√(2N) ≈ 1.1 %).
    let k = model.rotational_kinetic() / n as f64;
    assert!((k / kt - 1.0).abs() < 0.05, "K_rot/N = {k}, kT = {kt}");
    for i in 0..n as u32 {
        let s = model.axis(i, 0.0).unwrap();
        assert!(model.omega(i).dot(s).abs() < 1e-12 * model.omega(i).length().max(1.0));
    }

    // Reversal at the time origin: the axes retrace their path.
    let ahead: Vec<DVec3> = (0..n as u32).map(|i| model.axis(i, 0.3).unwrap()).collect();
    let saved = model.extra_state();
    model.reverse_rotations();
    for i in 0..n as u32 {
        assert_eq!(model.axis(i, -0.3).unwrap(), ahead[i as usize]);
        assert_eq!(model.axis(i, 0.0).unwrap(), axes_at_zero(&saved, i));
    }

    // The extra state round-trips exactly and a foreign one is refused.
    model.set_extra_state(&saved).unwrap();
    assert_eq!(model.extra_state(), saved);
    for i in 0..n as u32 {
        assert_eq!(model.axis(i, 0.3).unwrap(), ahead[i as usize]);
    }
    assert!(model.set_extra_state(&saved[1..]).is_err());
    assert!(model.set_extra_state(&[]).is_err());
    let mut bad = saved.clone();
    bad[0] = f64::NAN;
    assert!(model.set_extra_state(&bad).is_err());

    // The configured terrace: level 0 and no energy far apart; on the stored terrace while U is
    // on it; the terrace of U after a (missed) change; +∞ inside the core.
    let far = DVec3::new(0.0, 0.0, 5.0);
    assert_eq!(
        model.configured_level(
            &Pair {
                i: 0,
                j: 1,
                si: 0,
                sj: 0,
                now: 0.0,
                dr: far,
                dv: DVec3::ZERO
            },
            0
        ),
        (0, 0.0)
    );
    let mut seen_well = false;
    let mut seen_core = false;
    for k in 0..400 {
        let dr = DVec3::new(0.0, 0.3 + 0.004 * f64::from(k), 0.0);
        let u = model.energy(0, 1, 0, 0, 0.0, dr);
        let (level, e) = model.configured_level(
            &Pair {
                i: 0,
                j: 1,
                si: 0,
                sj: 0,
                now: 0.0,
                dr,
                dv: DVec3::ZERO,
            },
            0,
        );
        if e == f64::INFINITY {
            seen_core = true;
            assert!(model.storable_level(0, 0, level), "contact level {level}");
            continue;
        }
        // The terrace's energy is within a step of U (the map rounds U to its terraces).
        assert!(
            (e - u).abs() <= 0.5 + 1e-9 || level == 0,
            "U {u}, terrace energy {e}"
        );
        if level != 0 {
            seen_well = true;
            assert!(model.storable_level(0, 0, level));
            // Stored on it: it stands.
            assert_eq!(
                model.configured_level(
                    &Pair {
                        i: 0,
                        j: 1,
                        si: 0,
                        sj: 0,
                        now: 0.0,
                        dr,
                        dv: DVec3::ZERO
                    },
                    level
                ),
                (level, e)
            );
        }
    }
    assert!(seen_well && seen_core);
    assert!(!model.storable_level(0, 0, 0));
}

/// The axis of rod `i` at the time origin from a saved extra state (its rotor's `s0`).
fn axes_at_zero(state: &[f64], i: u32) -> DVec3 {
    let k = 11 * i as usize;
    DVec3::new(state[k], state[k + 1], state[k + 2])
}
