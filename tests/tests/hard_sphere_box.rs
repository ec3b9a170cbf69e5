//! The crates working together as a simulator uses them: a gas of hard spheres in a box with
//! hard walls, events scheduled in an `event_queue::LazyQueue`, collisions resolved by
//! `collide::spheres`. Every body keeps a local clock; nothing moves the whole system per event.
//!
//! Checks: kinetic energy conserved to round-off over tens of thousands of collisions, no two
//! spheres ever overlap beyond round-off, every executed event is a real contact, and the run
//! is bit-identical on the bounded queue and on the binary heap.

use collide::{Outcome, Particle, spheres};
use event_queue::{BoundedQueue, EventQueue, HeapQueue, LazyQueue, StampBook, Stamped, Ticket};
use glam::DVec3;

const SIGMA: f64 = 1.0;

#[derive(Clone, Copy, Debug)]
enum Kind {
    Pair(u32, u32),
    Wall(u32, usize),
}

#[derive(Clone, Copy, Debug)]
struct Ev {
    kind: Kind,
    ticket: Ticket,
}

impl Stamped for Ev {
    fn is_current(&self, book: &StampBook) -> bool {
        self.ticket.is_current(book)
    }
}

struct Gas<Q: EventQueue<Payload = Ev>> {
    side: f64,
    r: Vec<DVec3>,
    v: Vec<DVec3>,
    clock: Vec<f64>,
    particles: Vec<Particle>,
    queue: LazyQueue<Q>,
    now: f64,
    collisions: u64,
}

/// Earliest t ≥ 0 at which |dr + dv t| = σ for an approaching pair (the stable quadratic root).
fn contact_time(dr: DVec3, dv: DVec3) -> Option<f64> {
    let b = dr.dot(dv);
    if b >= 0.0 {
        return None;
    }
    let a = dv.length_squared();
    let c = dr.length_squared() - SIGMA * SIGMA;
    let disc = b * b - a * c;
    if disc <= 0.0 {
        return None;
    }
    // t = c / (−b + √disc): no cancellation between −b > 0 and √disc.
    Some((c / (-b + disc.sqrt())).max(0.0))
}

impl<Q: EventQueue<Payload = Ev>> Gas<Q> {
    fn new(queue: Q, per_side: usize, seed: u64) -> Self {
        let mut s = seed;
        let mut unit = move || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        let spacing = 1.3 * SIGMA;
        let side = per_side as f64 * spacing;
        let n = per_side.pow(3);
        let mut r = Vec::with_capacity(n);
        for i in 0..per_side {
            for j in 0..per_side {
                for k in 0..per_side {
                    r.push((DVec3::new(i as f64, j as f64, k as f64) + 0.5) * spacing);
                }
            }
        }
        let v: Vec<DVec3> = (0..n)
            .map(|_| DVec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5) * 2.0)
            .collect();
        let particles = (0..n)
            .map(|i| Particle::new(if i % 3 == 0 { 1.0 } else { 2.5 }).unwrap())
            .collect();
        let mut gas = Gas {
            side,
            r,
            v,
            clock: vec![0.0; n],
            particles,
            queue: LazyQueue::new(queue, n),
            now: 0.0,
            collisions: 0,
        };
        for i in 0..n {
            gas.predict(i, None);
        }
        gas
    }

    fn position(&self, i: usize) -> DVec3 {
        self.r[i] + self.v[i] * (self.now - self.clock[i])
    }

    fn sync(&mut self, i: usize) {
        self.r[i] = self.position(i);
        self.clock[i] = self.now;
    }

    /// Schedules body `i`'s wall events and its collisions with every other body (except `skip`,
    /// whose events with `i` were just scheduled from the other side).
    fn predict(&mut self, i: usize, skip: Option<usize>) {
        let ri = self.position(i);
        for axis in 0..3 {
            let (x, vx) = (ri[axis], self.v[i][axis]);
            let t = if vx > 0.0 {
                (self.side - 0.5 * SIGMA - x) / vx
            } else if vx < 0.0 {
                (0.5 * SIGMA - x) / vx
            } else {
                continue;
            };
            let ticket = self.queue.book().ticket1(i as u32);
            let ev = Ev {
                kind: Kind::Wall(i as u32, axis),
                ticket,
            };
            self.queue.schedule(self.now + t.max(0.0), ev).unwrap();
        }
        for j in 0..self.r.len() {
            if j == i || Some(j) == skip {
                continue;
            }
            if let Some(t) = contact_time(ri - self.position(j), self.v[i] - self.v[j]) {
                let ticket = self.queue.book().ticket2(i as u32, j as u32);
                let ev = Ev {
                    kind: Kind::Pair(i as u32, j as u32),
                    ticket,
                };
                self.queue.schedule(self.now + t, ev).unwrap();
            }
        }
    }

    fn step(&mut self) {
        let ev = self.queue.pop().expect("a closed gas always has events");
        assert!(ev.time >= self.now - 1e-12, "time went backwards");
        self.now = self.now.max(ev.time);
        match ev.payload.kind {
            Kind::Wall(i, axis) => {
                let i = i as usize;
                self.sync(i);
                self.v[i][axis] = -self.v[i][axis];
                self.queue.invalidate(i as u32);
                self.predict(i, None);
            }
            Kind::Pair(i, j) => {
                let (i, j) = (i as usize, j as usize);
                self.sync(i);
                self.sync(j);
                let r_ij = self.r[i] - self.r[j];
                assert!(
                    (r_ij.length() - SIGMA).abs() < 1e-9,
                    "event at distance {} instead of contact",
                    r_ij.length()
                );
                let pi = &self.particles[i];
                let pj = &self.particles[j];
                let out = spheres(pi, pj, self.v[i], self.v[j], r_ij, f64::INFINITY).unwrap();
                assert_eq!(out.impulse.outcome, Outcome::Reflected);
                (self.v[i], self.v[j]) = (out.i, out.j);
                self.collisions += 1;
                self.queue.invalidate(i as u32);
                self.queue.invalidate(j as u32);
                self.predict(i, None);
                self.predict(j, Some(i));
            }
        }
    }

    fn kinetic_energy(&self) -> f64 {
        let m = |i: usize| 1.0 / collide::Body::inv_mass(&self.particles[i]);
        (0..self.v.len())
            .map(|i| 0.5 * m(i) * self.v[i].length_squared())
            .sum()
    }

    fn min_distance(&self) -> f64 {
        let pos: Vec<DVec3> = (0..self.r.len()).map(|i| self.position(i)).collect();
        let mut d = f64::INFINITY;
        for i in 0..pos.len() {
            for j in 0..i {
                d = d.min(pos[i].distance(pos[j]));
            }
        }
        d
    }
}

fn run<Q: EventQueue<Payload = Ev>>(queue: Q, events: usize) -> (Vec<u64>, u64) {
    let mut gas = Gas::new(queue, 5, 17);
    let e0 = gas.kinetic_energy();
    for k in 0..events {
        gas.step();
        if k % 5_000 == 0 {
            assert!(
                gas.min_distance() > SIGMA * (1.0 - 1e-9),
                "overlap after {k} events"
            );
        }
    }
    let e1 = gas.kinetic_energy();
    assert!((e1 - e0).abs() <= 1e-12 * e0, "kinetic energy {e0} -> {e1}");
    assert!(
        gas.collisions > events as u64 / 2,
        "too few pair collisions"
    );
    let bits = (0..gas.r.len())
        .flat_map(|i| {
            let p = gas.position(i);
            [p.x, p.y, p.z, gas.v[i].x, gas.v[i].y, gas.v[i].z]
        })
        .map(f64::to_bits)
        .collect();
    (bits, gas.collisions)
}

#[test]
fn hard_sphere_gas_conserves_energy_and_is_queue_independent() {
    let events = 30_000;
    let (heap, c1) = run(HeapQueue::new(), events);
    let (bounded, c2) = run(BoundedQueue::new(), events);
    assert_eq!(c1, c2);
    assert!(
        heap == bounded,
        "the two queues gave different trajectories"
    );
}
