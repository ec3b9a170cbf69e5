//! Rigid asymmetric tops on a full-attitude terraced potential (SSD/E water) through the event
//! loop: conservation of energy, momentum and angular momentum through the impulses of 003
//! Eq. 21 with full inertia tensors, no missed event on a fine verification grid, tops near
//! the separatrix and spinning fast.
//!
//! The potential is used in its own units (kJ/mol, Å, g/mol), so the time unit of these runs
//! is 0.1 ps (`1 kJ/mol = 100 g/mol·Å²/ps²`).

use dmd_sim::model::PairModel;
use dmd_sim::rotor::{Rotor, Top, TopInertia};
use dmd_sim::search::SearchSettings;
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use dmd_sim::terraced::{BodySpecies, PairTerraces, Rigid, Terraced};
use event_queue::{BoundedQueue, LazyQueue, Ticket};
use glam::{DQuat, DVec3};
use potential::{
    LevelSet, RigidPairPotential, SoftStickyDipole, Steps, TerraceMap, TerraceOptions,
};

type Queue = LazyQueue<BoundedQueue<Ticket>>;
type Water = Rigid<SoftStickyDipole>;

/// kT of 298.15 K in kJ/mol.
const KT: f64 = 2.478_957;

fn settings(skin: f64) -> LoopSettings {
    LoopSettings {
        rebase_events: 1_000_000,
        seed: 3,
        debug_check_events: 200,
        skin,
        start_time: 0.0,
    }
}

fn inertia() -> TopInertia {
    TopInertia::new(SoftStickyDipole::INERTIA).unwrap()
}

/// The water model on evenly spaced terraces `step` apart, searched with `search`.
fn water(poses: &[DQuat], omegas: &[DVec3], step: f64, search: SearchSettings) -> Terraced<Water> {
    let ssd = SoftStickyDipole::ssd_e();
    let set = LevelSet::evenly_spaced(ssd.minimum(), step, &TerraceOptions::default()).unwrap();
    let map = TerraceMap::new(set, Steps::Uniform(step)).unwrap();
    let n = poses.len();
    Terraced::new(
        vec![BodySpecies {
            mass: SoftStickyDipole::MASS,
            inertia: inertia(),
        }],
        vec![((0, 0), PairTerraces::new(Rigid(ssd), map).unwrap())],
        &vec![0; n],
        poses,
        omegas,
        0.0,
        search,
        17,
    )
    .unwrap()
}

/// A 2 × 2 × 2 cluster of molecules `spacing` apart in the middle of a 40 Å box, attitudes
/// and angular velocities from `seed` (lab ω scaled by `spin` over thermal).
fn cluster(spacing: f64, spin: f64, seed: u64) -> (Vec<DVec3>, Vec<DVec3>, Vec<DQuat>, Vec<DVec3>) {
    use rand::SeedableRng;
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut r = Vec::new();
    for x in 0..2 {
        for y in 0..2 {
            for z in 0..2 {
                r.push(DVec3::new(x as f64, y as f64, z as f64) * spacing + 18.0);
            }
        }
    }
    let n = r.len();
    let v = dmd_sim::init::maxwell_boltzmann(&vec![SoftStickyDipole::MASS; n], 0.3 * KT, seed);
    let poses = dmd_sim::rods::random_attitudes(n, seed);
    let omegas = poses
        .iter()
        .map(|&q| spin * Top::draw(&inertia(), q, KT, &mut rng))
        .collect();
    (r, v, poses, omegas)
}

/// Total energy, linear momentum and angular momentum (orbital about the origin plus spins).
fn invariants(sim: &Simulation<Terraced<Water>, Queue>) -> Invariants {
    (
        sim.kinetic_energy() + sim.potential_energy(),
        sim.momentum_and_mass().0,
        sim.angular_momentum(),
    )
}

type Invariants = (f64, DVec3, DVec3);

/// Runs `model` for `events` from positions `r` and velocities `v` in a 40 Å box: the
/// simulation and its invariants before and after.
fn run_in_box(
    model: Terraced<Water>,
    r: &[DVec3],
    v: &[DVec3],
    events: u64,
) -> (Simulation<Terraced<Water>, Queue>, Invariants, Invariants) {
    let mut sim: Simulation<_, Queue> = Simulation::new(
        DVec3::splat(40.0),
        r,
        v,
        &vec![0; r.len()],
        model,
        settings(0.5),
    )
    .unwrap();
    let before = invariants(&sim);
    sim.run(Stop::Events(events), &mut NoSampler, &mut |_| {})
        .unwrap();
    let after = invariants(&sim);
    (sim, before, after)
}

fn run_cluster(spin: f64, seed: u64, verify: bool) -> Simulation<Terraced<Water>, Queue> {
    let (r, v, poses, omegas) = cluster(3.0, spin, seed);
    let n = r.len();
    let mut search = SearchSettings::paper(0.02 / spin.max(1.0));
    if verify {
        search.verify_step = Some(2e-4 / spin.max(1.0));
    }
    let model = water(&poses, &omegas, 0.5 * KT, search);
    let (sim, (e0, p0, l0), (e1, p1, l1)) = run_in_box(model, &r, &v, 6_000);
    let c = sim.counters();
    let st = sim.model().search_stats();
    assert!(c.pair_events() > 3000, "{c:?}");
    assert!(c.step_in > 100 && c.step_out > 100, "{c:?}");
    // Every event at its level, every search from its own terrace.
    assert_eq!(
        (st.misfits, st.off_terrace, st.failures),
        (0, 0, 0),
        "{st:?}"
    );
    let scale_e: f64 = sim.kinetic_energy();
    assert!((e1 - e0).abs() < 1e-12 * scale_e, "E {e0} -> {e1}");
    let scale_p: f64 =
        sim.bodies().iter().map(|b| b.v.length()).sum::<f64>() * SoftStickyDipole::MASS;
    assert!((p1 - p0).length() < 1e-13 * scale_p, "p {p0} -> {p1}");
    let scale_l: f64 = sim
        .positions()
        .iter()
        .zip(sim.bodies())
        .map(|(p, b)| p.length() * b.v.length() * SoftStickyDipole::MASS)
        .sum();
    assert!(
        (l1 - l0).length() < 1e-13 * scale_l,
        "L {l0} -> {l1} (scale {scale_l})"
    );
    // The tops took part: their angular velocities changed.
    let moved = (0..n as u32)
        .filter(|&i| (sim.model().omega(i) - omegas[i as usize]).length() > 1e-3)
        .count();
    assert!(moved > n / 2, "{moved}");
    sim
}

/// A bound cluster of water molecules far from the walls: energy, momentum and angular momentum
/// (orbital and spin) through thousands of terrace crossings and reflections.
#[test]
fn a_free_water_cluster_conserves_energy_momentum_and_angular_momentum() {
    let sim = run_cluster(1.0, 5, false);
    sim.check().unwrap();
}

/// The same, spinning ten times faster than thermal, every searched stretch searched again on
/// a grid a hundred times finer: no crossing stepped over.
#[test]
fn fast_spinning_tops_miss_no_event_on_the_verification_grid() {
    let sim = run_cluster(10.0, 7, true);
    let st = sim.model().search_stats();
    assert!(st.verified > 10_000, "{st:?}");
    assert_eq!(st.verify_misses, 0, "{st:?}");
}

/// Tops started on (or next to) the separatrix of the free asymmetric top: angular velocity
/// about the intermediate axis with a tiny perturbation, and exactly on it. The exact
/// propagator (hyperbolic case) carries them through the run with every invariant kept.
#[test]
fn tops_near_the_separatrix_conserve_the_invariants() {
    let (r, v, poses, _) = cluster(3.0, 1.0, 9);
    // Body y has the smallest moment, z the intermediate one (0.6145 < 1.1550 < 1.7696).
    let omegas: Vec<DVec3> = poses
        .iter()
        .enumerate()
        .map(|(i, &q)| {
            let eps = if i % 2 == 0 { 0.0 } else { 1e-9 };
            q * DVec3::new(eps, eps, 20.0)
        })
        .collect();
    let model = water(&poses, &omegas, 0.5 * KT, SearchSettings::paper(0.005));
    let (sim, (e0, p0, l0), (e1, p1, l1)) = run_in_box(model, &r, &v, 3_000);
    let k = sim.kinetic_energy();
    assert!((e1 - e0).abs() < 1e-12 * k, "E {e0} -> {e1}");
    assert!((p1 - p0).length() < 1e-9, "p {p0} -> {p1}");
    assert!(
        (l1 - l0).length() < 1e-9 * l0.length().max(1.0),
        "L {l0} -> {l1}"
    );
    let st = sim.model().search_stats();
    assert_eq!(
        (st.misfits, st.off_terrace, st.failures),
        (0, 0, 0),
        "{st:?}"
    );
    sim.check().unwrap();
}

/// Saved and restored, a top's rotation is the same bit for bit; the model's rotational
/// degrees of freedom are three per body.
#[test]
fn the_tops_state_round_trips_and_counts_three_rotations_per_body() {
    let (_, _, poses, omegas) = cluster(3.0, 1.0, 11);
    let mut a = water(&poses, &omegas, 0.5 * KT, SearchSettings::paper(0.02));
    assert_eq!(a.rotational_dof(), 3.0 * poses.len() as f64);
    let saved = a.extra_state();
    let b = {
        let mut b = water(&poses, &omegas, 0.5 * KT, SearchSettings::paper(0.02));
        a.scale_rotations(0.3, 1.7);
        b.set_extra_state(&saved).unwrap();
        b
    };
    a.set_extra_state(&saved).unwrap();
    for i in 0..poses.len() as u32 {
        assert_eq!(a.attitude(i, 0.123), b.attitude(i, 0.123));
        assert_eq!(a.omega(i), b.omega(i));
    }
    assert!(a.set_extra_state(&saved[1..]).is_err());
}
