//! Semi-flexible molecules through the event loop (issue 10, second half): RATTLE against the
//! exact rigid motion, conservation laws and bond lengths of a gas of chains, and a rigid
//! molecule run by the flexible engine against the rigid one (`sites`).

use collide::Bond;
use dmd_sim::flexible::{
    Constraints, Flexible, FlexibleType, RattleSettings, Trajectory, random_internal,
};
use dmd_sim::model::PairModel;
use dmd_sim::potential::Potentials;
use dmd_sim::search::{SearchMethod, SearchSettings};
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use dmd_sim::site_pairs::SiteAtom;
use dmd_sim::sites::{ImpulseRule, MoleculeType, Sites};
use event_queue::{BoundedQueue, LazyQueue, Ticket};
use glam::{DMat3, DQuat, DVec3};

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

fn search(step: f64, window: f64) -> SearchSettings {
    SearchSettings {
        method: SearchMethod::Adaptive,
        max_step: step,
        window,
        jitter: 0.0,
        verify_step: None,
        max_change: f64::INFINITY,
        horizon: 0.0,
    }
}

fn rattle(step: f64) -> RattleSettings {
    RattleSettings {
        step,
        tolerance: 1e-12,
        rescale: false,
    }
}

/// An asymmetric rigid triangle (unequal masses, two site species).
fn triangle_atoms() -> Vec<SiteAtom> {
    vec![
        atom(0.0, 0.0, 0.0, 3.0, 0),
        atom(0.6, 0.2, 0.0, 1.0, 1),
        atom(-0.3, 0.5, 0.0, 2.0, 1),
    ]
}

fn all_bonds3() -> Vec<Bond> {
    vec![Bond::new(0, 1), Bond::new(1, 2), Bond::new(0, 2)]
}

/// A 4-atom chain (bonds 0.6, free bond and torsion angles), sites of species 0, 1, 1, 0.
fn chain() -> FlexibleType {
    FlexibleType::new(
        &[
            atom(0.0, 0.0, 0.0, 1.0, 0),
            atom(0.6, 0.0, 0.0, 1.0, 1),
            atom(0.9, 0.52, 0.0, 1.0, 1),
            atom(1.5, 0.52, 0.05, 1.0, 0),
        ],
        &[Bond::new(0, 1), Bond::new(1, 2), Bond::new(2, 3)],
    )
    .unwrap()
}

/// Hard cores with square wells of two depths, and a repulsive shoulder.
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

/// A simple cubic lattice of at least `k³` molecules at density `rho` whose box fits the cell
/// list of reach `reach` (skin 0.2).
fn lattice_for(k: usize, rho: f64, reach: f64) -> (f64, Vec<DVec3>) {
    let need = 3.0 * (reach + 0.4) * 1.01;
    let k = k.max((rho * need.powi(3)).cbrt().ceil() as usize);
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

/// A gas of chains at density `rho` and temperature `kt`.
fn chains(rho: f64, kt: f64, h: f64, rescale: bool, seed: u64) -> Simulation<Flexible, Queue> {
    chains_with(rho, kt, h, rescale, seed, search(0.02, 0.1))
}

fn chains_with(
    rho: f64,
    kt: f64,
    h: f64,
    rescale: bool,
    seed: u64,
    s: SearchSettings,
) -> Simulation<Flexible, Queue> {
    let types = vec![chain()];
    let rattle = RattleSettings {
        rescale,
        ..rattle(h)
    };
    let probe = Flexible::new(types.clone(), wells(), &[], &[], &[], 0.0, rattle, s, seed).unwrap();
    let (l, r) = lattice_for(3, rho, probe.reach());
    let n = r.len();
    let kinds = vec![0u32; n];
    let (q, u) = random_internal(&types, &kinds, kt, seed);
    let v = dmd_sim::init::maxwell_boltzmann(&vec![types[0].mass(); n], kt, seed + 1);
    let model = Flexible::new(types, wells(), &kinds, &q, &u, 0.0, rattle, s, seed).unwrap();
    Simulation::new(DVec3::splat(l), &r, &v, &kinds, model, settings(0.2)).unwrap()
}

fn energy<M: PairModel>(sim: &Simulation<M, Queue>) -> f64 {
    sim.kinetic_energy() + sim.potential_energy()
}

/// RATTLE on a fully constrained triangle follows the exact free rigid motion (`rigid_free`
/// through `sites`) to O(h²): the error shrinks about fourfold when h halves.
#[test]
fn rattle_on_a_rigid_triangle_converges_to_the_exact_motion_at_second_order() {
    let ty = MoleculeType::new(&triangle_atoms()).unwrap();
    let q0 = DQuat::from_rotation_y(0.4) * DQuat::from_rotation_x(-0.7);
    let w = DVec3::new(1.3, -0.4, 2.1);
    let exact = Sites::new(
        vec![ty.clone()],
        wells(),
        &[0],
        &[q0],
        &[w],
        0.0,
        search(0.01, 0.1),
        ImpulseRule::ContactPoint,
        1,
    )
    .unwrap();
    let arms = exact.site_arms(0, 0.0);
    let vel: Vec<DVec3> = arms.iter().map(|&d| w.cross(d)).collect();
    let bonds = all_bonds3();
    let lengths: Vec<f64> = bonds
        .iter()
        .map(|b| (arms[b.a] - arms[b.b]).length())
        .collect();
    let c = Constraints::new(ty.masses(), &bonds, &lengths, 1e-13);
    let t_end = 1.5;
    let error = |h: f64| {
        let mut traj = Trajectory::new(0.0, h, &arms, &vel);
        let mut worst: f64 = 0.0;
        // Sample grid points and points between them.
        for k in 1..=60 {
            let t = t_end * k as f64 / 60.0;
            let (q, _) = traj.state_at(&c, t).unwrap();
            let truth = exact.site_arms(0, t);
            for (a, b) in q.iter().zip(&truth) {
                worst = worst.max((*a - *b).length());
            }
        }
        worst
    };
    let (e1, e2, e3) = (error(0.02), error(0.01), error(0.005));
    eprintln!("errors {e1:e} {e2:e} {e3:e}");
    assert!(e1 < 1e-2, "{e1}");
    for (a, b) in [(e1, e2), (e2, e3)] {
        let ratio = a / b;
        assert!(ratio > 3.5 && ratio < 4.6, "ratio {ratio} ({a:e} / {b:e})");
    }
}

/// A gas of 4-atom chains in hard cores and square wells, internal kinetic energy kept at
/// events: momentum and energy to round-off, bonds to the interpolation error, no anomalies.
#[test]
fn a_gas_of_chains_conserves_momentum_energy_and_bonds() {
    let mut sim = chains(0.04, 1.5, 0.005, true, 2);
    let e0 = energy(&sim);
    let (p0, _) = sim.momentum_and_mass();
    sim.run(Stop::Events(15_000), &mut NoSampler, &mut |_| {})
        .unwrap();
    let c = sim.counters();
    let st = sim.model().search_stats();
    let fx = sim.model().flex_stats();
    eprintln!("{c:?}\n{st:?}\n{fx:?}\n{:?}", sim.anomalies());
    let e1 = energy(&sim);
    let (p1, _) = sim.momentum_and_mass();
    assert!((p1 - p0).length() < 1e-11, "P {p0} -> {p1}");
    let drift = (e1 - e0).abs() / e0.abs();
    assert!(drift < 1e-11, "E {e0} -> {e1}: {drift:e}");
    assert!(c.core > 200 && c.step_in > 500 && c.step_out > 500, "{c:?}");
    assert_eq!(sim.anomalies().total(), 0, "{:?}", sim.anomalies());
    assert_eq!(
        (st.off_terrace, st.failures, st.misfits, fx.failures),
        (0, 0, 0, 0)
    );
    assert!((sim.tracked_potential() - sim.potential_energy()).abs() < 1e-9);
    // The bounding radii hold every atom however the chain has flexed.
    let radii = sim.model().types()[0].radii().to_vec();
    for i in 0..sim.bodies().len() as u32 {
        let (q, _) = sim.model().internal_state(i, sim.now()).unwrap();
        for (x, r) in q.iter().zip(&radii) {
            assert!(x.length() <= *r, "molecule {i}: {} > {r}", x.length());
        }
    }
    // The bonds hold to the SHAKE tolerance at the RATTLE steps, to the interpolation error
    // (O(h³): a RATTLE step's local error) between them and at the starts.
    let bonds = sim.model().bond_error(sim.now());
    assert!(bonds < 2e-6, "bond error {bonds:e}");
    assert!(fx.interpolated_bond_error < 2e-6, "{fx:?}");
    // The chains flex: internal kinetic energy over 6 internal degrees of freedom per chain
    // shares the temperature of the centres.
    let n = sim.bodies().len() as f64;
    let t_int = 2.0 * sim.model().rotational_kinetic() / sim.model().rotational_dof();
    let t_com = 2.0 * sim.translational_kinetic() / (3.0 * n - 3.0);
    assert_eq!(sim.model().rotational_dof(), 6.0 * n);
    assert!(
        (t_int / t_com - 1.0).abs() < 0.35,
        "T_int {t_int} T_com {t_com}"
    );
    sim.check().unwrap();
}

/// Without the kinetic energy kept at events, the energy takes the RATTLE step's error at every
/// event: the drift over the same number of events shrinks about fourfold when h halves, and
/// the loop's tracked energy follows the recomputed one (the model reports the error).
#[test]
fn the_energy_error_shrinks_with_the_rattle_step() {
    let err = |h: f64| {
        let mut sim = chains(0.04, 1.5, h, false, 4);
        let e0 = energy(&sim);
        sim.run(Stop::Events(8_000), &mut NoSampler, &mut |_| {})
            .unwrap();
        let e1 = energy(&sim);
        let tracked = sim.tracked_kinetic() + sim.tracked_potential();
        assert!((tracked - e1).abs() < 1e-9 * e1.abs(), "{tracked} vs {e1}");
        sim.check().unwrap();
        (e1 - e0) / e0.abs()
    };
    let (a, b) = (err(0.01), err(0.005));
    eprintln!("energy drifts {a:e} (h = 0.01), {b:e} (h = 0.005)");
    assert!(a.abs() > 1e-5, "{a:e}");
    let ratio = a / b;
    assert!(ratio > 2.5 && ratio < 6.0, "{a:e} vs {b:e}: {ratio}");
}

/// A rigid triangle (all three distances bonded) run by the flexible engine and by the exact
/// rigid engine from the same start: the same events, the same centres to a tolerance that
/// shrinks with the RATTLE step.
#[test]
fn a_rigid_molecule_follows_the_rigid_engine() {
    let ty = MoleculeType::new(&triangle_atoms()).unwrap();
    let flex_type = FlexibleType::new(&triangle_atoms(), &all_bonds3()).unwrap();
    let pot = wells();
    let s = search(0.01, 0.05);
    let probe = Flexible::new(
        vec![flex_type.clone()],
        pot.clone(),
        &[],
        &[],
        &[],
        0.0,
        rattle(0.01),
        s,
        1,
    )
    .unwrap();
    let (l, r) = lattice_for(3, 0.1, probe.reach());
    let n = r.len();
    let kinds = vec![0u32; n];
    let (q, w) = dmd_sim::sites::random_orientations(std::slice::from_ref(&ty), &kinds, 1.0, 8);
    let v = dmd_sim::init::maxwell_boltzmann(&vec![ty.mass(); n], 1.0, 9);
    // Long enough for some hundred pair events, short enough that the chaos of the gas does not
    // amplify the O(h²) difference of the free motion beyond it.
    let t_end = 1.0;
    let mut rigid = {
        let model = Sites::new(
            vec![ty.clone()],
            pot.clone(),
            &kinds,
            &q,
            &w,
            0.0,
            s,
            ImpulseRule::ContactPoint,
            1,
        )
        .unwrap();
        Simulation::<_, Queue>::new(DVec3::splat(l), &r, &v, &kinds, model, settings(0.2)).unwrap()
    };
    rigid
        .run(Stop::Time(t_end), &mut NoSampler, &mut |_| {})
        .unwrap();
    let cr = rigid.counters();
    assert!(cr.pair_events() > 50, "{cr:?}");
    let run = |h: f64| {
        let (mut pos, mut vel) = (Vec::new(), Vec::new());
        for (qi, wi) in q.iter().zip(&w) {
            let o = DMat3::from_quat(*qi);
            let arms: Vec<DVec3> = ty.sites().iter().map(|&d| o * d).collect();
            vel.push(arms.iter().map(|&d| wi.cross(d)).collect());
            pos.push(arms);
        }
        let model = Flexible::new(
            vec![flex_type.clone()],
            pot.clone(),
            &kinds,
            &pos,
            &vel,
            0.0,
            rattle(h),
            s,
            1,
        )
        .unwrap();
        let mut sim =
            Simulation::<_, Queue>::new(DVec3::splat(l), &r, &v, &kinds, model, settings(0.2))
                .unwrap();
        sim.run(Stop::Time(t_end), &mut NoSampler, &mut |_| {})
            .unwrap();
        let c = sim.counters();
        let worst = sim
            .positions()
            .iter()
            .zip(rigid.positions())
            .map(|(a, b)| (*a - b).length())
            .fold(0.0, f64::max);
        (c, worst)
    };
    let (c1, d1) = run(0.01);
    let (c2, d2) = run(0.005);
    eprintln!("rigid {cr:?}\nh = 0.01: {c1:?} {d1:e}\nh = 0.005: {c2:?} {d2:e}");
    for c in [c1, c2] {
        assert_eq!(
            (c.core, c.step_in, c.step_out, c.step_reflect),
            (cr.core, cr.step_in, cr.step_out, cr.step_reflect)
        );
    }
    // Second order: 1.6e-3 and 4.4e-4 when written (and 9.6e-5 at h = 0.0025).
    assert!(d1 < 5e-3, "{d1:e}");
    assert!(d2 < 0.4 * d1, "{d2:e} vs {d1:e}");
}

/// Thermostat collisions draw the internal velocities from the constrained Maxwell–Boltzmann
/// distribution: the internal and centre temperatures both relax to the bath's.
#[test]
fn a_thermostat_brings_the_internal_motion_to_the_bath_temperature() {
    let mut sim = chains(0.04, 0.5, 0.005, true, 6);
    sim.set_thermostat(Some(dmd_sim::simulation::Andersen {
        rate: 10.0,
        temperature: 2.5,
    }));
    sim.run(Stop::Time(0.5), &mut NoSampler, &mut |_| {})
        .unwrap();
    let n = sim.bodies().len() as f64;
    let (mut t_int, mut t_com) = (0.0, 0.0);
    for k in 1..=20 {
        sim.run(
            Stop::Time(0.5 + 0.05 * k as f64),
            &mut NoSampler,
            &mut |_| {},
        )
        .unwrap();
        t_int += 2.0 * sim.model().rotational_kinetic() / sim.model().rotational_dof() / 20.0;
        t_com += 2.0 * sim.translational_kinetic() / (3.0 * n) / 20.0;
    }
    eprintln!("T_int {t_int}, T_com {t_com}, {:?}", sim.counters());
    assert!(sim.counters().thermostat > 1000);
    assert!((t_int / 2.5 - 1.0).abs() < 0.06, "T_int {t_int}");
    assert!((t_com / 2.5 - 1.0).abs() < 0.06, "T_com {t_com}");
    // The bookkeeping of the thermostat's energy follows the recomputed energy.
    let e = energy(&sim);
    let tracked = sim.tracked_kinetic() + sim.tracked_potential();
    assert!((tracked - e).abs() < 1e-9 * e.abs(), "{tracked} vs {e}");
    sim.check().unwrap();
}

/// A RATTLE step too long for the motion stops the run with an error naming it; it never runs
/// on with pairs that lost their events.
#[test]
fn a_failed_rattle_step_stops_the_run() {
    let mut sim = chains(0.04, 40.0, 0.06, true, 7);
    let err = sim
        .run(Stop::Time(20.0), &mut NoSampler, &mut |_| {})
        .unwrap_err();
    let text = format!("{err}");
    eprintln!("{text}");
    assert!(text.contains("RATTLE"), "{text}");
}

/// Virtual events change nothing (the suspended searches resume on the same RATTLE steps), and
/// the grid search with the same step finds the same events as the adaptive one.
#[test]
fn virtual_events_and_the_search_method_do_not_change_the_trajectory() {
    let run = |s: SearchSettings| {
        let mut sim = chains_with(0.04, 1.5, 0.005, true, 8, s);
        sim.run(Stop::Time(2.0), &mut NoSampler, &mut |_| {})
            .unwrap();
        (sim.counters(), sim.positions())
    };
    let (ca, pa) = run(search(0.01, 0.02));
    let (cb, pb) = run(search(0.01, f64::INFINITY));
    let grid = SearchSettings {
        method: SearchMethod::Grid { threshold: 0.05 },
        ..search(0.01, 0.02)
    };
    let (cg, pg) = run(grid);
    assert!(ca.virtual_ > 5 * cb.virtual_.max(1), "{ca:?} {cb:?}");
    assert!(ca.pair_events() > 300, "{ca:?}");
    for (c, p) in [(cb, &pb), (cg, &pg)] {
        assert_eq!(
            (ca.core, ca.step_in, ca.step_out, ca.step_reflect),
            (c.core, c.step_in, c.step_out, c.step_reflect)
        );
        let worst = pa
            .iter()
            .zip(p)
            .map(|(x, y)| (*x - *y).length())
            .fold(0.0, f64::max);
        assert!(worst < 1e-7, "positions differ by {worst}");
    }
}
