//! Rigid site-based molecules through the event loop (issue 10): conservation laws, the two
//! impulse rules against each other, search settings, extreme molecules.

use dmd_sim::model::PairModel;
use dmd_sim::potential::Potentials;
use dmd_sim::search::{SearchMethod, SearchSettings};
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use dmd_sim::site_pairs::SiteAtom;
use dmd_sim::sites::{ImpulseRule, MoleculeType, Sites, random_orientations};
use event_queue::{BoundedQueue, LazyQueue, Ticket};
use glam::DVec3;

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

fn atom(x: f64, y: f64, z: f64, mass: f64, species: u32) -> SiteAtom {
    SiteAtom {
        position: DVec3::new(x, y, z),
        mass,
        species,
    }
}

/// A hard dumbbell of two unit-diameter sites at separation `elongation`.
fn dumbbell(elongation: f64) -> MoleculeType {
    MoleculeType::new(&[
        atom(0.0, 0.0, -0.5 * elongation, 1.0, 0),
        atom(0.0, 0.0, 0.5 * elongation, 1.0, 0),
    ])
    .unwrap()
}

/// An asymmetric top: a bent triatomic with unequal masses and two site species.
fn bent() -> MoleculeType {
    MoleculeType::new(&[
        atom(0.0, 0.0, 0.0, 3.0, 0),
        atom(0.6, 0.2, 0.0, 1.0, 1),
        atom(-0.3, 0.5, 0.25, 2.0, 1),
    ])
    .unwrap()
}

/// A simple cubic lattice of `k³` molecules at number density `rho`.
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

fn search(method: SearchMethod, step: f64, window: f64) -> SearchSettings {
    SearchSettings {
        method,
        max_step: step,
        window,
        jitter: 0.0,
        verify_step: None,
        max_change: f64::INFINITY,
        horizon: 0.0,
    }
}

/// The smallest simple cubic lattice of at least `k³` molecules at density `rho` whose box fits
/// the cell list of a model of reach `reach` (skin 0.2).
fn lattice_for(k: usize, rho: f64, reach: f64) -> (f64, Vec<DVec3>) {
    let need = 3.0 * (reach + 0.4) * 1.01;
    let k = k.max((rho * need.powi(3)).cbrt().ceil() as usize);
    lattice(k, rho)
}

#[allow(clippy::too_many_arguments)]
fn system(
    ty: MoleculeType,
    pot: Potentials,
    k: usize,
    rho: f64,
    kt: f64,
    s: SearchSettings,
    rule: ImpulseRule,
    seed: u64,
) -> Simulation<Sites, Queue> {
    let types = vec![ty];
    let probe = Sites::new(
        types.clone(),
        pot.clone(),
        &[],
        &[],
        &[],
        0.0,
        s,
        rule,
        seed,
    )
    .unwrap();
    let (l, r) = lattice_for(k, rho, probe.reach());
    let n = r.len();
    let kinds = vec![0u32; n];
    let (q, w) = random_orientations(&types, &kinds, kt, seed);
    let mass = types[0].mass();
    let v = dmd_sim::init::maxwell_boltzmann(&vec![mass; n], kt, seed + 1);
    let model = Sites::new(types, pot, &kinds, &q, &w, 0.0, s, rule, seed).unwrap();
    Simulation::new(DVec3::splat(l), &r, &v, &kinds, model, settings(0.2)).unwrap()
}

fn hard(sigma: f64) -> Potentials {
    Potentials::from_tables(1, &[((0, 0), vec![[sigma, f64::INFINITY]])])
}

/// Two site species: hard cores with square wells of two depths, and a two-step well.
fn wells() -> Potentials {
    Potentials::from_tables(
        2,
        &[
            ((0, 0), vec![[1.0, f64::INFINITY], [1.3, -1.0]]),
            (
                (0, 1),
                vec![[0.8, f64::INFINITY], [1.0, -0.5], [1.25, -0.25]],
            ),
            ((1, 1), vec![[0.6, f64::INFINITY], [0.9, 0.3]]),
        ],
    )
}

fn energy(sim: &Simulation<Sites, Queue>) -> f64 {
    sim.kinetic_energy() + sim.potential_energy()
}

#[test]
fn hard_dumbbells_conserve_energy_and_momentum() {
    let mut sim = system(
        dumbbell(0.6),
        hard(1.0),
        4,
        0.15,
        1.0,
        search(SearchMethod::Adaptive, 0.02, 0.1),
        ImpulseRule::ContactPoint,
        1,
    );
    let e0 = energy(&sim);
    let (p0, _) = sim.momentum_and_mass();
    sim.run(Stop::Events(20_000), &mut NoSampler, &mut |_| {})
        .unwrap();
    let c = sim.counters();
    let st = sim.model().search_stats();
    eprintln!("{c:?}\n{st:?}\n{:?}", sim.anomalies());
    let e1 = energy(&sim);
    let (p1, _) = sim.momentum_and_mass();
    assert!((e1 - e0).abs() < 1e-11 * e0, "E {e0} -> {e1}");
    assert!((p1 - p0).length() < 1e-11, "P {p0} -> {p1}");
    assert!(c.core > 1000 && c.virtual_ > 1000, "{c:?}");
    assert_eq!(sim.anomalies().overlap, 0);
    assert_eq!((st.off_terrace, st.failures), (0, 0), "{st:?}");
    // Rotation shared the energy: the rotational temperature is near the translational one.
    let (krot, dof) = (
        sim.model().rotational_kinetic(),
        sim.model().rotational_dof(),
    );
    assert_eq!(dof, 2.0 * sim.bodies().len() as f64);
    let t_rot = 2.0 * krot / dof;
    assert!(t_rot > 0.6 && t_rot < 1.5, "T_rot {t_rot}");
    sim.check().unwrap();
}

#[test]
fn asymmetric_tops_in_square_wells_conserve_energy_and_momentum() {
    let mut sim = system(
        bent(),
        wells(),
        4,
        0.2,
        1.5,
        search(SearchMethod::Adaptive, 0.02, 0.1),
        ImpulseRule::ContactPoint,
        2,
    );
    let ty = &sim.model().types()[0];
    assert!(ty.moments().x < ty.moments().y && ty.moments().y < ty.moments().z);
    let e0 = energy(&sim);
    let (p0, _) = sim.momentum_and_mass();
    sim.run(Stop::Events(20_000), &mut NoSampler, &mut |_| {})
        .unwrap();
    let c = sim.counters();
    let st = sim.model().search_stats();
    eprintln!("{c:?}\n{st:?}\n{:?}", sim.anomalies());
    let e1 = energy(&sim);
    let (p1, _) = sim.momentum_and_mass();
    assert!((e1 - e0).abs() < 1e-10 * e0.abs(), "E {e0} -> {e1}");
    assert!((p1 - p0).length() < 1e-11, "P {p0} -> {p1}");
    // Every kind of event happened, and the tracked energies agree with the recomputed ones.
    assert!(c.core > 100 && c.step_in > 500 && c.step_out > 500 && c.step_reflect > 10);
    assert!((sim.tracked_potential() - sim.potential_energy()).abs() < 1e-9);
    assert_eq!(st.failures, 0);
    sim.check().unwrap();
}

#[test]
fn a_free_cluster_conserves_angular_momentum() {
    // 27 asymmetric tops in a loose cluster far from the walls of a big box.
    let ty = bent();
    let types = vec![ty];
    let mut r = Vec::new();
    for x in 0..3 {
        for y in 0..3 {
            for z in 0..3 {
                r.push(DVec3::new(x as f64, y as f64, z as f64) * 1.9 + 58.0);
            }
        }
    }
    let n = r.len();
    let kinds = vec![0u32; n];
    let (q, w) = random_orientations(&types, &kinds, 1.0, 5);
    let v = dmd_sim::init::maxwell_boltzmann(&vec![types[0].mass(); n], 0.3, 6);
    let model = Sites::new(
        types,
        wells(),
        &kinds,
        &q,
        &w,
        0.0,
        search(SearchMethod::Adaptive, 0.02, 0.1),
        ImpulseRule::ContactPoint,
        7,
    )
    .unwrap();
    let mut sim: Simulation<_, Queue> =
        Simulation::new(DVec3::splat(120.0), &r, &v, &kinds, model, settings(0.3)).unwrap();
    let l0 = sim.angular_momentum();
    let e0 = energy(&sim);
    // Short enough that no molecule that leaves the cluster meets another across the periodic
    // boundary (which changes the angular momentum of the unwrapped system).
    sim.run(Stop::Events(6_000), &mut NoSampler, &mut |_| {})
        .unwrap();
    let c = sim.counters();
    assert!(c.pair_events() > 2000, "{c:?}");
    let l1 = sim.angular_momentum();
    let scale: f64 = sim
        .positions()
        .iter()
        .zip(sim.bodies())
        .map(|(p, b)| p.length() * b.v.length() * 6.0)
        .sum();
    assert!((l1 - l0).length() < 1e-12 * scale, "L {l0} -> {l1}");
    assert!((energy(&sim) - e0).abs() < 1e-11 * e0.abs());
}

/// The constrained-Lagrangian rule (000 §IV.A) and the contact-point rule (000 §IV.B) give the
/// same impulse at every event of a long run: both are applied to the same state and compared.
#[test]
fn constrained_and_contact_rules_agree_event_by_event() {
    // A non-planar molecule (the bent triatomic is planar: three atoms always are), a
    // methane-like tetrahedron with unequal masses, in square wells.
    let s = 1.0 / 3f64.sqrt();
    let ty = MoleculeType::new(&[
        atom(0.0, 0.0, 0.0, 12.0, 0),
        atom(0.55 * s, 0.55 * s, 0.55 * s, 1.0, 1),
        atom(0.55 * s, -0.55 * s, -0.55 * s, 2.0, 1),
        atom(-0.55 * s, 0.55 * s, -0.55 * s, 1.0, 1),
        atom(-0.55 * s, -0.55 * s, 0.55 * s, 3.0, 1),
    ])
    .unwrap();
    for rule in [ImpulseRule::ContactPoint, ImpulseRule::Constrained] {
        let (l, r) = lattice_for(4, 0.15, 3.0);
        let n = r.len();
        let kinds = vec![0u32; n];
        let types = vec![ty.clone()];
        let (q, w) = random_orientations(&types, &kinds, 1.5, 11);
        let v = dmd_sim::init::maxwell_boltzmann(&vec![ty.mass(); n], 1.5, 12);
        let mut model = Sites::new(
            types,
            wells(),
            &kinds,
            &q,
            &w,
            0.0,
            search(SearchMethod::Adaptive, 0.02, 0.1),
            rule,
            11,
        )
        .unwrap();
        // The model runs the other rule on the same incoming state at every event.
        model.set_cross_check(true).unwrap();
        let mut sim =
            Simulation::<_, Queue>::new(DVec3::splat(l), &r, &v, &kinds, model, settings(0.2))
                .unwrap();
        let e0 = energy(&sim);
        sim.run(Stop::Events(15_000), &mut NoSampler, &mut |_| {})
            .unwrap();
        let cc = sim.model().cross_check().unwrap();
        let c = sim.counters();
        eprintln!("{rule:?}: {c:?}\n{cc:?}");
        assert!(cc.events > 3000, "{cc:?}");
        assert_eq!(cc.outcome_mismatches, 0);
        assert!(cc.impulse < 1e-10, "{cc:?}");
        assert!(cc.velocity < 1e-11, "{cc:?}");
        assert!((energy(&sim) - e0).abs() < 1e-10 * e0.abs());
        sim.check().unwrap();
    }
}

/// The grid and the adaptive search with the same (fine) step find the same events: the same
/// counts of every kind over a short run, and the same positions to the root tolerance.
#[test]
fn grid_and_adaptive_searches_agree() {
    let mk = |method| {
        system(
            bent(),
            wells(),
            3,
            0.12,
            1.5,
            search(method, 0.005, 0.05),
            ImpulseRule::ContactPoint,
            4,
        )
    };
    let mut a = mk(SearchMethod::Adaptive);
    let mut g = mk(SearchMethod::Grid { threshold: 0.05 });
    a.run(Stop::Time(1.0), &mut NoSampler, &mut |_| {}).unwrap();
    g.run(Stop::Time(1.0), &mut NoSampler, &mut |_| {}).unwrap();
    let (ca, cg) = (a.counters(), g.counters());
    assert!(ca.pair_events() > 200, "{ca:?}");
    assert_eq!(
        (ca.core, ca.step_in, ca.step_out, ca.step_reflect),
        (cg.core, cg.step_in, cg.step_out, cg.step_reflect)
    );
    let worst = a
        .positions()
        .iter()
        .zip(g.positions())
        .map(|(p, q)| (*p - q).length())
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "positions differ by {worst}");
}

/// Virtual events change nothing: a window of one step and no window at all give the same
/// trajectory (the suspended searches resume bit for bit).
#[test]
fn virtual_events_do_not_change_the_trajectory() {
    let mk = |window| {
        system(
            dumbbell(0.8),
            hard(1.0),
            3,
            0.12,
            1.0,
            search(SearchMethod::Adaptive, 0.02, window),
            ImpulseRule::ContactPoint,
            9,
        )
    };
    let mut a = mk(0.02);
    let mut b = mk(f64::INFINITY);
    a.run(Stop::Time(2.0), &mut NoSampler, &mut |_| {}).unwrap();
    b.run(Stop::Time(2.0), &mut NoSampler, &mut |_| {}).unwrap();
    let (ca, cb) = (a.counters(), b.counters());
    assert!(ca.virtual_ > 10 * cb.virtual_.max(1), "{ca:?} {cb:?}");
    assert_eq!(ca.core, cb.core);
    let worst = a
        .positions()
        .iter()
        .zip(b.positions())
        .map(|(p, q)| (*p - q).length())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "positions differ by {worst}");
}
