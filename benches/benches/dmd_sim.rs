//! Time per event of the `dmd-sim` event loop, each model and scheduler on the same footing.
//!
//! Every benchmark builds an equilibrated fluid once (outside the measurement) and then times
//! batches of 10⁴ events of the continuing run, so the figure is the steady-state cost of one
//! event (pair events and shell crossings together; `summary.json` splits them). Systems:
//!
//! - hard spheres at ρσ³ = 0.8 (N = 4000) on the three schedulers (bounded queue, heap,
//!   tournament tree): the baseline;
//! - the square well λ = 1.5 at ρσ³ = 0.5, kT = 1.5 (N = 4000): stored pair levels;
//! - the stepped Lennard-Jones fluid of `scenes/stepped-lj.toml` (24 steps, N = 4000).
//!
//! Skins are those the default rule of `dmd run` picks (0.25, 0.15 and 0.157).
//!
//! Throughput against N (10³ … 10⁶) is measured by the `throughput` example instead: a criterion
//! sample of a 10⁶-body system would take minutes to set up.
//!
//! Rods (group `dmd_sim_rods`): the paper's 512 rods of `scenes/rods-paper.toml` (ΔV = kT/2),
//! equilibrated once, then batches of 0.05 ps of simulated time (about 2400 pair events, and
//! virtual events in proportion) on the bounded queue (the baseline) and the heap, with virtual
//! events and without (a search runs to its root or the end of its bracket in one call). Time
//! per batch compares the variants at equal physics; events are not, since virtual events
//! differ.

use std::hint::black_box;

use collide::Particle;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dmd_sim::init::maxwell_boltzmann;
use dmd_sim::model::{HardSpheres, PairModel, Stepped};
use dmd_sim::potential::Potentials;
use dmd_sim::schedule::Scheduler;
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use event_queue::{BoundedQueue, HeapQueue, LazyQueue, Ticket, TournamentTree};
use glam::DVec3;

const BATCH: u64 = 10_000;

/// An fcc lattice of 4 k³ sites at density `rho` (box length, positions).
fn fcc(k: usize, rho: f64) -> (f64, Vec<DVec3>) {
    let n = 4 * k * k * k;
    let l = (n as f64 / rho).cbrt();
    let a = l / k as f64;
    let basis = [
        [0.25, 0.25, 0.25],
        [0.75, 0.75, 0.25],
        [0.75, 0.25, 0.75],
        [0.25, 0.75, 0.75],
    ];
    let mut r = Vec::with_capacity(n);
    for x in 0..k {
        for y in 0..k {
            for z in 0..k {
                for b in basis {
                    r.push(DVec3::new(x as f64 + b[0], y as f64 + b[1], z as f64 + b[2]) * a);
                }
            }
        }
    }
    (l, r)
}

fn system<M: PairModel, S: Scheduler>(
    model: M,
    rho: f64,
    temperature: f64,
    skin: f64,
) -> Simulation<M, S> {
    let (l, r) = fcc(10, rho);
    let n = r.len();
    let v = maxwell_boltzmann(&vec![1.0; n], temperature, 7);
    let settings = LoopSettings {
        rebase_events: 400_000,
        seed: 1,
        debug_check_events: 0,
        skin,
        start_time: 0.0,
    };
    let mut sim = Simulation::new(DVec3::splat(l), &r, &v, &vec![0; n], model, settings)
        .expect("a valid lattice");
    // Melt and equilibrate.
    sim.run(Stop::Events(200 * n as u64), &mut NoSampler, &mut |_| {})
        .expect("runs");
    sim
}

fn bench_system<M: PairModel, S: Scheduler>(
    c: &mut Criterion,
    name: &str,
    mut sim: Simulation<M, S>,
) {
    let mut g = c.benchmark_group("dmd_sim");
    g.throughput(Throughput::Elements(BATCH));
    g.sample_size(30);
    g.bench_function(name, |b| {
        b.iter(|| {
            sim.run(Stop::Events(BATCH), &mut NoSampler, &mut |_| {})
                .expect("runs");
            black_box(sim.counters().events)
        })
    });
    g.finish();
}

fn pots(steps: Vec<[f64; 2]>) -> Potentials {
    Potentials::from_tables(1, &[((0, 0), steps)])
}

fn hard_spheres(c: &mut Criterion) {
    let p = pots(vec![[1.0, f64::INFINITY]]);
    let part = vec![Particle::new(1.0).unwrap()];
    bench_system(
        c,
        "hard_spheres_rho0.8/bounded",
        system::<_, LazyQueue<BoundedQueue<Ticket>>>(
            HardSpheres::new(p.clone(), part.clone()),
            0.8,
            1.0,
            0.25,
        ),
    );
    bench_system(
        c,
        "hard_spheres_rho0.8/heap",
        system::<_, LazyQueue<HeapQueue<Ticket>>>(
            HardSpheres::new(p.clone(), part.clone()),
            0.8,
            1.0,
            0.25,
        ),
    );
    bench_system(
        c,
        "hard_spheres_rho0.8/tournament",
        system::<_, TournamentTree>(HardSpheres::new(p.clone(), part.clone()), 0.8, 1.0, 0.25),
    );
    // The general stepped model running a bare hard core: the price of its level look-ups.
    bench_system(
        c,
        "hard_spheres_rho0.8/as_stepped",
        system::<_, LazyQueue<BoundedQueue<Ticket>>>(Stepped::new(p, part, 4000), 0.8, 1.0, 0.25),
    );
}

fn stepped(c: &mut Criterion) {
    let part = vec![Particle::new(1.0).unwrap()];
    let sw = pots(vec![[1.0, f64::INFINITY], [1.5, -1.0]]);
    bench_system(
        c,
        "square_well_rho0.5",
        system::<_, LazyQueue<BoundedQueue<Ticket>>>(
            Stepped::new(sw, part.clone(), 4000),
            0.5,
            1.5,
            0.15,
        ),
    );
    // The table of scenes/stepped-lj.toml (ΔV = ε/2, hard core at U = 10ε).
    let scene = dmd_sim::scene::Scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/stepped-lj.toml"),
        &[],
    )
    .expect("the shipped scene reads")
    .0;
    let lj = pots(scene.pair[0].steps.clone());
    bench_system(
        c,
        "stepped_lj_rho0.5",
        system::<_, LazyQueue<BoundedQueue<Ticket>>>(Stepped::new(lj, part, 4000), 0.5, 1.5, 0.157),
    );
}

/// The paper's rods, equilibrated, on scheduler `S`, with the search window `window` (ps).
fn paper_rods<S: Scheduler>(
    window: f64,
) -> Simulation<dmd_sim::terraced::Terraced<potential::LjRod>, S> {
    use dmd_sim::plan::Plan;
    use dmd_sim::rods::{equipartitioned_omegas, random_axes, rod_species, search_settings};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/rods-paper.toml");
    let scene = dmd_sim::scene::Scene::load(&path, &[])
        .expect("the shipped scene reads")
        .0
        .internal();
    let Ok(Plan::Terraced(plan)) = Plan::of(&scene) else {
        panic!("the paper's scene is a rods scene")
    };
    let tables = plan.take::<dmd_sim::scene::LjRodsSpec>();
    let config = dmd_sim::init::lattice(&scene, 0.0).expect("a lattice");
    let n = config.positions.len();
    let kt = scene.init.temperature;
    let v = maxwell_boltzmann(&vec![18.0; n], kt, 7);
    let axes = random_axes(n, 7);
    let omegas = equipartitioned_omegas(&axes, &vec![1.154; n], kt, 7);
    let mut search = search_settings(&scene);
    search.window = window;
    let model = dmd_sim::terraced::Terraced::new(
        rod_species(&scene),
        tables,
        &config.species,
        &axes,
        &omegas,
        0.0,
        search,
        7,
    )
    .expect("a valid model");
    let settings = LoopSettings {
        rebase_events: 4_000_000,
        seed: 1,
        debug_check_events: 0,
        skin: 0.5,
        start_time: 0.0,
    };
    let mut sim = Simulation::new(
        config.lengths,
        &config.positions,
        &v,
        &config.species,
        model,
        settings,
    )
    .expect("a valid lattice");
    sim.run(Stop::Time(2.0), &mut NoSampler, &mut |_| {})
        .expect("runs");
    sim
}

fn rods(c: &mut Criterion) {
    let mut g = c.benchmark_group("dmd_sim_rods");
    g.sample_size(20);
    let mut bench = |name: &str, run: &mut dyn FnMut()| {
        g.bench_function(name, |b| b.iter(&mut *run));
    };
    let mut a = paper_rods::<LazyQueue<BoundedQueue<Ticket>>>(0.004);
    bench("paper/bounded", &mut || {
        a.run(Stop::Time(0.05), &mut NoSampler, &mut |_| {})
            .expect("runs");
    });
    let mut b = paper_rods::<LazyQueue<HeapQueue<Ticket>>>(0.004);
    bench("paper/heap", &mut || {
        b.run(Stop::Time(0.05), &mut NoSampler, &mut |_| {})
            .expect("runs");
    });
    let mut c2 = paper_rods::<LazyQueue<BoundedQueue<Ticket>>>(f64::INFINITY);
    bench("paper/bounded_no_virtual", &mut || {
        c2.run(Stop::Time(0.05), &mut NoSampler, &mut |_| {})
            .expect("runs");
    });
    g.finish();
}

criterion_group!(benches, hard_spheres, stepped, rods);
criterion_main!(benches);
