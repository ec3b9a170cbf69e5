//! Rigid rods on terraced potentials through the event loop: conservation, the sphere limit,
//! virtual events, extreme starts.

use collide::Particle;
use dmd_sim::model::{PairModel, Stepped};
use dmd_sim::potential::Potentials;
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use dmd_sim::terraced::{RodSpecies, SearchSettings, Terraced, radial_steps};
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
        vec![((0, 0), pot, map)],
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
    let st = sim.model().search_stats().unwrap();
    eprintln!("{c:?}\n{st:?}\n{:?} E {e0} -> {e1}", sim.anomalies());
    assert!((e1 - e0).abs() < 1e-10 * e0.abs().max(1.0));
    assert!((p1 - p0).length() < 1e-12);
    assert!(c.step_in > 100 && c.step_out > 100 && c.virtual_ > 100);
    sim.check().unwrap();
}
