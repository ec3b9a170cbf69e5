//! The event loop against an independent brute-force simulator.
//!
//! The reference below knows nothing of cells, neighbour lists, event lists, schedulers or time
//! origins: at every step it computes the next event of *every* pair (O(N²), minimum image,
//! levels kept per pair in a plain matrix), executes the earliest with `collide::spheres`, and
//! moves every body to the event time. Starting both from the same state, the positions and
//! velocities after a few hundred events must agree to round-off (the dynamics is chaotic, so
//! runs are kept short enough for round-off not to grow visibly), and so must the number of
//! pair events of each kind. A missed or spurious event changes everything after it.

use collide::{Outcome, Particle, spheres};
use dmd_sim::event::Boundary;
use dmd_sim::model::{HardSpheres, PairModel, Stepped};
use dmd_sim::potential::Potentials;
use dmd_sim::schedule::Scheduler;
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use event_queue::{BoundedQueue, HeapQueue, LazyQueue, Ticket, TournamentTree};
use glam::DVec3;

struct Reference {
    l: DVec3,
    r: Vec<DVec3>,
    v: Vec<DVec3>,
    species: Vec<usize>,
    particles: Vec<Particle>,
    pots: Potentials,
    level: Vec<Vec<usize>>,
    pair_events: [u64; 4],
}

impl Reference {
    fn min_image(&self, mut d: DVec3) -> DVec3 {
        for a in 0..3 {
            d[a] -= self.l[a] * (d[a] / self.l[a]).round();
        }
        d
    }

    fn next_event(&self, i: usize, j: usize) -> Option<(f64, Boundary)> {
        let dr = self.min_image(self.r[i] - self.r[j]);
        let dv = self.v[i] - self.v[j];
        let (r2, b, v2) = (dr.length_squared(), dr.dot(dv), dv.length_squared());
        let lv = self
            .pots
            .get(self.species[i] as u32, self.species[j] as u32)
            .levels()[self.level[i][j]];
        // Textbook roots, written independently of the simulator's.
        if lv.inner2 > 0.0 && b < 0.0 {
            let disc = b * b - v2 * (r2 - lv.inner2);
            if disc > 0.0 {
                return Some((((-b - disc.sqrt()) / v2).max(0.0), Boundary::Inner));
            }
        }
        if lv.outer2.is_finite() && v2 > 0.0 {
            let disc = (b * b - v2 * (r2 - lv.outer2)).max(0.0);
            return Some((((-b + disc.sqrt()) / v2).max(0.0), Boundary::Outer));
        }
        None
    }

    /// Time to the next event, without executing it.
    fn peek(&self) -> f64 {
        let n = self.r.len();
        let mut best = f64::INFINITY;
        for i in 0..n {
            for j in i + 1..n {
                if let Some((t, _)) = self.next_event(i, j) {
                    best = best.min(t);
                }
            }
        }
        best
    }

    fn step(&mut self) -> f64 {
        let n = self.r.len();
        let mut best = (f64::INFINITY, 0, 0, Boundary::Inner);
        for i in 0..n {
            for j in i + 1..n {
                if let Some((t, b)) = self.next_event(i, j)
                    && t < best.0
                {
                    best = (t, i, j, b);
                }
            }
        }
        let (t, i, j, boundary) = best;
        for k in 0..n {
            self.r[k] += self.v[k] * t;
        }
        let dr = self.min_image(self.r[i] - self.r[j]);
        let lv = self
            .pots
            .get(self.species[i] as u32, self.species[j] as u32)
            .levels()[self.level[i][j]];
        let step = match boundary {
            Boundary::Inner => lv.dv_in,
            Boundary::Outer => lv.dv_out,
        };
        let out = spheres(
            &self.particles[self.species[i]],
            &self.particles[self.species[j]],
            self.v[i],
            self.v[j],
            dr,
            step,
        )
        .unwrap();
        self.v[i] = out.i;
        self.v[j] = out.j;
        let kind = match (out.impulse.outcome, boundary) {
            (Outcome::Reflected, _) if step == f64::INFINITY => 0,
            (Outcome::Reflected, _) => 3,
            (Outcome::Crossed, Boundary::Inner) => {
                self.level[i][j] += 1;
                self.level[j][i] += 1;
                1
            }
            (Outcome::Crossed, Boundary::Outer) => {
                self.level[i][j] -= 1;
                self.level[j][i] -= 1;
                2
            }
        };
        self.pair_events[kind] += 1;
        t
    }
}

/// A random non-overlapping start: bodies on a jittered simple cubic lattice.
fn start(
    per_side: usize,
    spacing: f64,
    seed: u64,
    masses: &[f64],
) -> (DVec3, Vec<DVec3>, Vec<DVec3>, Vec<usize>) {
    let mut s = seed;
    let mut unit = move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let l = DVec3::splat(per_side as f64 * spacing);
    let mut r = Vec::new();
    let mut v = Vec::new();
    let mut species = Vec::new();
    for x in 0..per_side {
        for y in 0..per_side {
            for z in 0..per_side {
                let jitter = DVec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5) * 0.1 * spacing;
                r.push((DVec3::new(x as f64, y as f64, z as f64) + 0.5) * spacing + jitter);
                let s = r.len() % masses.len();
                species.push(s);
                let scale = 1.0 / masses[s].sqrt();
                v.push(DVec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5) * 3.0 * scale);
            }
        }
    }
    (l, r, v, species)
}

fn settings(skin: f64) -> LoopSettings {
    LoopSettings {
        rebase_events: 50,
        seed: 3,
        debug_check_events: 1,
        skin,
        start_time: 0.0,
    }
}

/// Runs the simulator and the reference for `events` pair events; compares states.
fn compare<M: PairModel, S: Scheduler>(
    model: M,
    pots: Potentials,
    masses: &[f64],
    per_side: usize,
    spacing: f64,
    events: usize,
    skin: f64,
) {
    let (l, r, v, species) = start(per_side, spacing, 11, masses);
    let particles: Vec<Particle> = masses.iter().map(|&m| Particle::new(m).unwrap()).collect();
    let n = r.len();
    let mut reference = Reference {
        l,
        r: r.clone(),
        v: v.clone(),
        species: species.clone(),
        particles,
        pots: pots.clone(),
        level: vec![vec![0; n]; n],
        pair_events: [0; 4],
    };
    for i in 0..n {
        for j in 0..n {
            if i != j {
                let d = reference.min_image(r[i] - r[j]).length();
                reference.level[i][j] = pots.get(species[i] as u32, species[j] as u32).level_at(d);
            }
        }
    }
    let mut time = 0.0;
    for _ in 0..events {
        time += reference.step();
    }
    // Compare half-way to the next event, away from any tie with the end of the run.
    let half = 0.5 * reference.peek();
    for k in 0..n {
        reference.r[k] += reference.v[k] * half;
    }
    time += half;
    let sp: Vec<u32> = species.iter().map(|&s| s as u32).collect();
    let mut sim: Simulation<M, S> = Simulation::new(l, &r, &v, &sp, model, settings(skin)).unwrap();
    sim.run(Stop::Time(time), &mut NoSampler, &mut |_| {})
        .unwrap();
    sim.check().unwrap();
    let c = sim.counters();
    assert_eq!(
        [c.core, c.step_in, c.step_out, c.step_reflect],
        reference.pair_events,
        "pair events by kind (core, in, out, reflect)"
    );
    assert_eq!(sim.anomalies().total(), 0);
    let pos = sim.positions();
    let mut worst: f64 = 0.0;
    for (i, p) in pos.iter().enumerate() {
        let d = reference.min_image(*p - reference.r[i]).length();
        let dv = (sim.bodies()[i].v - reference.v[i]).length();
        worst = worst.max(d).max(dv);
    }
    // Chaos amplifies round-off by about 10 per few hundred events at these densities.
    assert!(
        worst < 1e-6,
        "states differ by {worst} after {events} events"
    );
}

fn hs(masses: &[f64]) -> (Potentials, Vec<Particle>) {
    let n = masses.len();
    let mut tables = Vec::new();
    for a in 0..n {
        for b in a..n {
            tables.push(((a, b), vec![[0.9 + 0.1 * (a + b) as f64, f64::INFINITY]]));
        }
    }
    let pots = Potentials::from_tables(n, &tables);
    (
        pots,
        masses.iter().map(|&m| Particle::new(m).unwrap()).collect(),
    )
}

#[test]
fn hard_spheres_follow_the_brute_force_reference() {
    let (pots, parts) = hs(&[1.0]);
    compare::<_, LazyQueue<BoundedQueue<Ticket>>>(
        HardSpheres::new(pots.clone(), parts.clone()),
        pots.clone(),
        &[1.0],
        5,
        1.25,
        600,
        0.2,
    );
    compare::<_, LazyQueue<HeapQueue<Ticket>>>(
        HardSpheres::new(pots.clone(), parts.clone()),
        pots.clone(),
        &[1.0],
        5,
        1.25,
        600,
        0.05,
    );
    compare::<_, TournamentTree>(
        HardSpheres::new(pots.clone(), parts),
        pots,
        &[1.0],
        5,
        1.25,
        600,
        0.4,
    );
}

#[test]
fn hard_sphere_mixture_with_a_mass_ratio_of_1000_follows_the_reference() {
    let masses = [1.0, 1000.0];
    let (pots, parts) = hs(&masses);
    compare::<_, LazyQueue<BoundedQueue<Ticket>>>(
        HardSpheres::new(pots.clone(), parts),
        pots,
        &masses,
        5,
        1.3,
        500,
        0.15,
    );
}

#[test]
fn square_wells_and_soft_steps_follow_the_reference() {
    // Square well, λ = 1.5: captures, escapes and reflections at the well's edge.
    let sw = Potentials::from_tables(1, &[((0, 0), vec![[1.0, f64::INFINITY], [1.5, -1.0]])]);
    let parts = vec![Particle::new(1.0).unwrap()];
    compare::<_, LazyQueue<BoundedQueue<Ticket>>>(
        Stepped::new(sw.clone(), parts.clone(), 125),
        sw,
        &[1.0],
        5,
        1.6,
        600,
        0.1,
    );
    // A mixture with a penetrable soft core, a repulsive shoulder and an attractive step.
    let masses = [1.0, 3.0];
    let soft = Potentials::from_tables(
        2,
        &[
            ((0, 0), vec![[0.5, 3.0], [1.0, 1.0], [1.3, -0.5]]),
            ((0, 1), vec![[0.9, f64::INFINITY], [1.2, 0.7]]),
            (
                (1, 1),
                vec![[1.0, f64::INFINITY], [1.4, -0.3], [1.45, -0.2]],
            ),
        ],
    );
    let parts: Vec<Particle> = masses.iter().map(|&m| Particle::new(m).unwrap()).collect();
    compare::<_, LazyQueue<HeapQueue<Ticket>>>(
        Stepped::new(soft.clone(), parts, 125),
        soft,
        &masses,
        5,
        1.6,
        600,
        0.2,
    );
}
