//! The crate used the way an event-driven simulator uses it: point masses on a ring colliding
//! elastically with their neighbours, one participant per particle, lazy invalidation.
//!
//! Checks: energy and momentum conserved to round-off, particles never pass each other, stale
//! events are dropped rather than executed, and the bounded queue and the binary heap produce
//! bit-identical trajectories (same events, same order, same numbers).

use event_queue::{BoundedQueue, EventQueue, HeapQueue, LazyQueue, StampBook, Stamped, Ticket};

/// A collision between particle `left` and its right neighbour.
#[derive(Clone, Copy, Debug)]
struct Collision {
    left: u32,
    ticket: Ticket,
}

impl Stamped for Collision {
    fn is_current(&self, book: &StampBook) -> bool {
        self.ticket.is_current(book)
    }
}

struct Ring<Q: EventQueue<Payload = Collision>> {
    length: f64,
    /// Position, velocity and local clock of each particle (positions unwrapped: x_{i+1} ≥ x_i
    /// except across the seam, where the gap is taken modulo the ring length).
    x: Vec<f64>,
    v: Vec<f64>,
    clock: Vec<f64>,
    mass: Vec<f64>,
    queue: LazyQueue<Q>,
    now: f64,
}

impl<Q: EventQueue<Payload = Collision>> Ring<Q> {
    fn new(queue: Q, n: usize, seed: u64) -> Self {
        let mut s = seed;
        let mut unit = move || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        let length = n as f64;
        let x = (0..n).map(|i| i as f64 + 0.5 * unit()).collect();
        let v = (0..n).map(|_| 2.0 * unit() - 1.0).collect();
        let mass = (0..n).map(|_| 0.5 + 4.5 * unit()).collect();
        let mut ring = Ring {
            length,
            x,
            v,
            clock: vec![0.0; n],
            mass,
            queue: LazyQueue::new(queue, n),
            now: 0.0,
        };
        for i in 0..n {
            ring.schedule(i);
        }
        ring
    }

    fn n(&self) -> usize {
        self.x.len()
    }

    fn right(&self, i: usize) -> usize {
        (i + 1) % self.n()
    }

    /// Position of `i` at the current time (local clocks: nothing else is ever advanced).
    fn position(&self, i: usize) -> f64 {
        self.x[i] + self.v[i] * (self.now - self.clock[i])
    }

    /// Schedules the collision of `i` with its right neighbour, if they approach.
    fn schedule(&mut self, i: usize) {
        let j = self.right(i);
        let closing = self.v[i] - self.v[j];
        if closing <= 0.0 {
            return;
        }
        let gap = (self.position(j) - self.position(i)).rem_euclid(self.length);
        let ticket = self.queue.book().ticket2(i as u32, j as u32);
        self.queue
            .schedule(
                self.now + gap / closing,
                Collision {
                    left: i as u32,
                    ticket,
                },
            )
            .unwrap();
    }

    fn step(&mut self) -> bool {
        let Some(ev) = self.queue.pop() else {
            return false;
        };
        assert!(ev.time >= self.now - 1e-12, "time went backwards");
        self.now = self.now.max(ev.time);
        let i = ev.payload.left as usize;
        let j = self.right(i);
        for k in [i, j] {
            self.x[k] = self.position(k);
            self.clock[k] = self.now;
        }
        let (mi, mj, vi, vj) = (self.mass[i], self.mass[j], self.v[i], self.v[j]);
        let m = mi + mj;
        self.v[i] = ((mi - mj) * vi + 2.0 * mj * vj) / m;
        self.v[j] = ((mj - mi) * vj + 2.0 * mi * vi) / m;
        self.queue.invalidate(i as u32);
        self.queue.invalidate(j as u32);
        let left = (i + self.n() - 1) % self.n();
        self.schedule(left);
        self.schedule(j);
        true
    }

    fn energy(&self) -> f64 {
        self.v
            .iter()
            .zip(&self.mass)
            .map(|(v, m)| 0.5 * m * v * v)
            .sum()
    }

    fn momentum(&self) -> f64 {
        self.v.iter().zip(&self.mass).map(|(v, m)| m * v).sum()
    }
}

fn run<Q: EventQueue<Payload = Collision>>(queue: Q, events: usize) -> (Vec<u64>, Ring<Q>) {
    let mut ring = Ring::new(queue, 500, 3);
    let (e0, p0) = (ring.energy(), ring.momentum());
    for _ in 0..events {
        assert!(ring.step(), "the ring ran out of events");
    }
    let e1 = ring.energy();
    assert!((e1 - e0).abs() <= 1e-12 * e0, "energy {e0} -> {e1}");
    assert!(
        (ring.momentum() - p0).abs() <= 1e-12 * e0.sqrt(),
        "momentum drifted"
    );
    // Particles keep their cyclic order: every gap stays within one ring length.
    let xs: Vec<f64> = (0..ring.n()).map(|i| ring.position(i)).collect();
    let gaps: f64 = (0..ring.n())
        .map(|i| (xs[ring.right(i)] - xs[i]).rem_euclid(ring.length))
        .sum();
    assert!(
        (gaps - ring.length).abs() < 1e-6,
        "particles passed each other"
    );
    let bits = xs.iter().chain(&ring.v).map(|f| f.to_bits()).collect();
    (bits, ring)
}

#[test]
fn ring_gas_is_identical_on_both_queues_and_conserves() {
    let events = 200_000;
    let (heap_bits, heap_ring) = run(HeapQueue::new(), events);
    let (bounded_bits, bounded_ring) = run(BoundedQueue::new(), events);
    assert_eq!(heap_bits, bounded_bits, "trajectories differ");
    assert_eq!(heap_ring.now.to_bits(), bounded_ring.now.to_bits());
    let s = bounded_ring.queue.stats();
    assert_eq!(s.popped, events as u64);
    // Every collision obsoletes the pending event of the particle on the far side.
    assert!(s.dropped_stale + s.swept > events as u64 / 4, "{s:?}");
    assert_eq!(s, heap_ring.queue.stats());
}
