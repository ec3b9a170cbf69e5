//! The classic *hold* model for benchmarking event queues.
//!
//! A queue is filled with `n` events; then each *hold* pops the earliest event and pushes a new
//! one at that time plus a random increment. The queue size stays `n`, and the time per hold
//! measures the queue at that size (Jones 1986; Brown's calendar-queue paper; Paul 2007 Fig. 2).
//! Increments are exponential (the inter-event times of a simulator's many independent pairs)
//! or uniform.
//!
//! [`StdHeap`] wraps `std::collections::BinaryHeap` in the [`EventQueue`] trait so the standard
//! library's heap runs the very same workload as the queues of this crate.
//!
//! [`PairHold`] is the variant for schedulers that keep one event per participant: each step
//! executes the earliest event and gives its participant and a random partner new events, as a
//! collision does. It runs on a [`TournamentTree`] or on a [`LazyQueue`] (where the partner's
//! old event is left behind, stale).
//!
//! ```
//! use event_queue::hold::{Increment, Hold, StdHeap};
//! use event_queue::BoundedQueue;
//!
//! let mut a = Hold::new(BoundedQueue::new(), 1_000, Increment::Exponential, 7);
//! let mut b = Hold::new(StdHeap::new(), 1_000, Increment::Exponential, 7);
//! // Same seed, same increments: both queues must pop the same times.
//! assert_eq!(a.run(10_000), b.run(10_000));
//! ```

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::{Event, EventQueue, LazyQueue, QueueError, Ticket, TournamentTree};

/// Distribution of the increment added to the popped time, with mean 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Increment {
    /// Exponential with mean 1.
    Exponential,
    /// Uniform on [0, 2).
    Uniform,
}

/// SplitMix64: tiny, fast, and value-stable, which is all a benchmark workload needs.
#[derive(Clone, Debug)]
struct SplitMix64(u64);

impl SplitMix64 {
    #[inline(always)]
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform on (0, 1]: never 0, so the logarithm below is finite.
    #[inline(always)]
    fn unit(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

impl Increment {
    #[inline(always)]
    fn draw(self, rng: &mut SplitMix64) -> f64 {
        match self {
            Increment::Exponential => -rng.unit().ln(),
            Increment::Uniform => 2.0 * rng.unit(),
        }
    }
}

/// A queue in the hold model: filled with `n` events, ready for holds.
#[derive(Clone, Debug)]
pub struct Hold<Q> {
    queue: Q,
    increment: Increment,
    rng: SplitMix64,
    next_id: u64,
}

impl<Q: EventQueue<Payload = u64>> Hold<Q> {
    /// Fills `queue` with `n` events at increments from time zero, seeded by `seed`.
    pub fn new(mut queue: Q, n: usize, increment: Increment, seed: u64) -> Self {
        let mut rng = SplitMix64(seed);
        for id in 0..n as u64 {
            let t = increment.draw(&mut rng);
            queue.push(t, id).expect("increments are finite");
        }
        Self {
            queue,
            increment,
            rng,
            next_id: n as u64,
        }
    }

    /// Performs `holds` holds; returns the time of the last event popped (a checksum that also
    /// keeps the optimiser from discarding the work). `0.0` for an empty queue.
    #[inline(never)]
    pub fn run(&mut self, holds: u64) -> f64 {
        let mut last = 0.0;
        for _ in 0..holds {
            let Some(e) = self.queue.pop() else { break };
            last = e.time;
            let t = e.time + self.increment.draw(&mut self.rng);
            self.queue
                .push(t, self.next_id)
                .expect("increments are finite");
            self.next_id += 1;
        }
        last
    }

    /// The queue, for its statistics.
    pub fn queue(&self) -> &Q {
        &self.queue
    }
}

/// A scheduler that keeps one pending event per participant.
pub trait PairScheduler {
    /// The participant with the earliest event and its time. The event counts as executed: the
    /// caller must [`reschedule`](Self::reschedule) that participant before the next call.
    fn next(&mut self) -> Option<(u32, f64)>;
    /// Replaces participant `p`'s pending event (if any) by one at `time`.
    fn reschedule(&mut self, p: u32, time: f64);
}

impl PairScheduler for TournamentTree {
    #[inline]
    fn next(&mut self) -> Option<(u32, f64)> {
        // No need to clear the leaf: the caller overwrites it (one path update, not two).
        self.min().map(|(p, t)| (p as u32, t))
    }

    #[inline]
    fn reschedule(&mut self, p: u32, time: f64) {
        self.set(p as usize, time).expect("increments are finite");
    }
}

impl<Q: EventQueue<Payload = Ticket>> PairScheduler for LazyQueue<Q> {
    #[inline]
    fn next(&mut self) -> Option<(u32, f64)> {
        self.pop().map(|e| (e.payload.first(), e.time))
    }

    #[inline]
    fn reschedule(&mut self, p: u32, time: f64) {
        self.invalidate(p);
        let ticket = self.book().ticket1(p);
        self.schedule(time, ticket).expect("increments are finite");
    }
}

/// The pair-hold model: `n` participants with one event each; a step executes the earliest and
/// reschedules its participant and a partner drawn uniformly from the others.
#[derive(Clone, Debug)]
pub struct PairHold<S> {
    scheduler: S,
    n: u32,
    increment: Increment,
    rng: SplitMix64,
}

impl<S: PairScheduler> PairHold<S> {
    /// Gives each of `n ≥ 2` participants a first event at an increment from time zero.
    ///
    /// # Panics
    /// If `n < 2`.
    pub fn new(mut scheduler: S, n: u32, increment: Increment, seed: u64) -> Self {
        assert!(n >= 2, "the pair-hold model needs two participants");
        let mut rng = SplitMix64(seed);
        for p in 0..n {
            scheduler.reschedule(p, increment.draw(&mut rng));
        }
        Self {
            scheduler,
            n,
            increment,
            rng,
        }
    }

    /// Performs `steps` steps; returns the time of the last event executed.
    #[inline(never)]
    pub fn run(&mut self, steps: u64) -> f64 {
        let mut last = 0.0;
        for _ in 0..steps {
            let Some((p, t)) = self.scheduler.next() else {
                break;
            };
            last = t;
            let q = (p + 1 + (self.rng.next_u64() % u64::from(self.n - 1)) as u32) % self.n;
            let tp = t + self.increment.draw(&mut self.rng);
            let tq = t + self.increment.draw(&mut self.rng);
            self.scheduler.reschedule(p, tp);
            self.scheduler.reschedule(q, tq);
        }
        last
    }

    /// The scheduler, for its statistics.
    pub fn scheduler(&self) -> &S {
        &self.scheduler
    }
}

/// `std::collections::BinaryHeap` behind the [`EventQueue`] trait, with the crate's order.
#[derive(Clone, Debug, Default)]
pub struct StdHeap<P> {
    heap: BinaryHeap<Keyed<P>>,
    next_seq: u64,
}

impl<P> StdHeap<P> {
    /// An empty queue.
    pub fn new() -> Self {
        Self {
            heap: BinaryHeap::new(),
            next_seq: 0,
        }
    }
}

/// An entry ordered so that the max-heap yields the earliest (time, sequence) first.
#[derive(Clone, Debug)]
struct Keyed<P> {
    time: f64,
    seq: u64,
    payload: P,
}

impl<P> PartialEq for Keyed<P> {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl<P> Eq for Keyed<P> {}

impl<P> PartialOrd for Keyed<P> {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl<P> Ord for Keyed<P> {
    #[inline]
    fn cmp(&self, other: &Self) -> Ordering {
        // Reversed: the max-heap's top is the earliest. NaN never enters (push refuses it).
        other
            .time
            .partial_cmp(&self.time)
            .unwrap_or(Ordering::Equal)
            .then(other.seq.cmp(&self.seq))
    }
}

impl<P> EventQueue for StdHeap<P> {
    type Payload = P;

    #[inline]
    fn push(&mut self, time: f64, payload: P) -> Result<(), QueueError> {
        crate::check_time(time)?;
        let seq = self.next_seq;
        self.next_seq += 1;
        self.heap.push(Keyed { time, seq, payload });
        Ok(())
    }

    #[inline]
    fn pop(&mut self) -> Option<Event<P>> {
        self.heap.pop().map(|k| Event {
            time: k.time,
            payload: k.payload,
        })
    }

    fn peek(&self) -> Option<(f64, &P)> {
        self.heap.peek().map(|k| (k.time, &k.payload))
    }

    fn len(&self) -> usize {
        self.heap.len()
    }

    fn clear(&mut self) {
        self.heap.clear();
    }

    fn retain(&mut self, keep: &mut dyn FnMut(&P) -> bool) -> usize {
        let before = self.heap.len();
        self.heap.retain(|k| keep(&k.payload));
        before - self.heap.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BoundedQueue, HeapQueue};

    #[test]
    fn all_queues_agree_on_the_hold_sequence() {
        for inc in [Increment::Exponential, Increment::Uniform] {
            let a = Hold::new(HeapQueue::new(), 500, inc, 1).run(20_000);
            let b = Hold::new(BoundedQueue::new(), 500, inc, 1).run(20_000);
            let c = Hold::new(StdHeap::new(), 500, inc, 1).run(20_000);
            assert_eq!(a, b);
            assert_eq!(a, c);
            // Mean increment 1 and 500 events: time advances by ~1/500 per hold.
            assert!((20.0..60.0).contains(&a), "{a}");
        }
    }

    #[test]
    fn pair_hold_agrees_on_tree_and_lazy_queues() {
        let n = 300;
        let a = PairHold::new(
            TournamentTree::new(n as usize),
            n,
            Increment::Exponential,
            5,
        )
        .run(50_000);
        let bounded = LazyQueue::new(BoundedQueue::new(), n as usize);
        let b = PairHold::new(bounded, n, Increment::Exponential, 5).run(50_000);
        let heap = LazyQueue::new(HeapQueue::new(), n as usize);
        let mut c = PairHold::new(heap, n, Increment::Exponential, 5);
        assert_eq!(a, b);
        assert_eq!(a, c.run(50_000));
        // Each step leaves the partner's old event behind.
        let s = c.scheduler().stats();
        assert!(s.dropped_stale + s.swept > 40_000, "{s:?}");
    }

    #[test]
    fn increments_have_mean_one() {
        let mut rng = SplitMix64(3);
        for inc in [Increment::Exponential, Increment::Uniform] {
            let n = 200_000;
            let mean = (0..n).map(|_| inc.draw(&mut rng)).sum::<f64>() / f64::from(n);
            assert!((mean - 1.0).abs() < 0.01, "{inc:?}: {mean}");
        }
    }
}
