//! Model-based property tests: for random interleavings of push, pop, invalidate and sweep,
//! every queue pops exactly what a sorted reference pops, in the same order, ties included.

use std::collections::BTreeMap;

use event_queue::{
    BoundedQueue, Cleanup, EventQueue, HeapQueue, Layout, LazyQueue, QueueError, StampBook,
    Stamped, Ticket, Tuning,
};
use proptest::prelude::*;

/// The reference: a map ordered by (time, sequence), popped from its least key. Times enter
/// the key through their IEEE bits mapped to an order-preserving integer, with −0.0 taken as
/// +0.0 (they compare equal, so they tie and go by sequence); NaN is refused before. An
/// ordered map keeps the reference obviously right and O(log n) per operation, so the
/// thousands of events of a case cost no quadratic scan.
#[derive(Default)]
struct Reference<P> {
    items: BTreeMap<(u64, u64), (f64, P)>,
    seq: u64,
}

/// `t` as an integer of the same order (for every t that is not NaN).
fn order_key(t: f64) -> u64 {
    let bits = if t == 0.0 { 0 } else { t.to_bits() };
    if bits >> 63 == 1 {
        !bits
    } else {
        bits | 1 << 63
    }
}

impl<P> EventQueue for Reference<P> {
    type Payload = P;
    fn push(&mut self, time: f64, payload: P) -> Result<(), QueueError> {
        if time.is_nan() {
            return Err(QueueError::NanTime);
        }
        self.items
            .insert((order_key(time), self.seq), (time, payload));
        self.seq += 1;
        Ok(())
    }
    fn pop(&mut self) -> Option<event_queue::Event<P>> {
        let (_, (time, payload)) = self.items.pop_first()?;
        Some(event_queue::Event { time, payload })
    }
    fn peek(&self) -> Option<(f64, &P)> {
        self.items.first_key_value().map(|(_, (t, p))| (*t, p))
    }
    fn len(&self) -> usize {
        self.items.len()
    }
    fn clear(&mut self) {
        self.items.clear();
    }
    fn retain(&mut self, keep: &mut dyn FnMut(&P) -> bool) -> usize {
        let before = self.items.len();
        self.items.retain(|_, (_, p)| keep(p));
        before - self.items.len()
    }
}

#[derive(Clone, Debug)]
enum Op {
    /// Push at a time relative to the last popped time (or absolute, for special values).
    Push(TimeSpec),
    Pop,
    Peek,
    /// Remove payloads divisible by the given number (retain).
    Retain(u8),
}

#[derive(Clone, Debug)]
enum TimeSpec {
    After(f64),
    Exactly(f64),
}

fn time_spec() -> impl Strategy<Value = TimeSpec> {
    prop_oneof![
        // Typical: a little after the last pop, on several scales.
        6 => (0.0..10.0f64).prop_map(TimeSpec::After),
        2 => (0.0..1e-3f64).prop_map(TimeSpec::After),
        1 => (0.0..1e6f64).prop_map(TimeSpec::After),
        // Ties: a few exact values shared by many events.
        3 => (0u8..4).prop_map(|k| TimeSpec::Exactly(f64::from(k))),
        // Round-off in simulators: slightly before the last pop.
        1 => (-1e-9..0.0f64).prop_map(TimeSpec::After),
        // Extremes.
        1 => Just(TimeSpec::Exactly(f64::INFINITY)),
        1 => Just(TimeSpec::Exactly(f64::NEG_INFINITY)),
        1 => Just(TimeSpec::Exactly(-0.0)),
        // Subnormal times: a tuned width must never become subnormal (1/Δ = ∞).
        1 => (0u64..16).prop_map(|k| TimeSpec::Exactly(f64::from_bits(k))),
        1 => Just(TimeSpec::Exactly(f64::NAN)),
    ]
}

fn ops(max: usize) -> impl Strategy<Value = Vec<Op>> {
    prop::collection::vec(
        prop_oneof![
            8 => time_spec().prop_map(Op::Push),
            5 => Just(Op::Pop),
            1 => Just(Op::Peek),
            1 => (2u8..5).prop_map(Op::Retain),
        ],
        0..max,
    )
}

/// Runs `ops` on `q` and returns the log of everything observable.
fn run<Q: EventQueue<Payload = u32>>(q: &mut Q, ops: &[Op], origin: f64) -> Vec<String> {
    let mut log = Vec::new();
    let mut last = origin;
    let mut next = 0u32;
    for op in ops {
        match op {
            Op::Push(spec) => {
                let t = match *spec {
                    TimeSpec::After(d) => last + d,
                    TimeSpec::Exactly(t) => origin + t,
                };
                let r = q.push(t, next);
                log.push(format!("push {t:?} {next} -> {r:?}"));
                next += 1;
            }
            Op::Pop => {
                let e = q.pop();
                if let Some(e) = e.as_ref().filter(|e| e.time.is_finite()) {
                    last = e.time;
                }
                log.push(format!("pop {:?}", e.map(|e| (e.time, e.payload))));
            }
            Op::Peek => log.push(format!("peek {:?}", q.peek().map(|(t, p)| (t, *p)))),
            Op::Retain(k) => {
                let k = u32::from(*k);
                let removed = q.retain(&mut |p| p % k != 0);
                log.push(format!("retain {k} removed {removed}"));
            }
        }
        log.push(format!("len {}", q.len()));
    }
    while let Some(e) = q.pop() {
        log.push(format!("drain {:?} {}", e.time, e.payload));
    }
    log
}

fn tiny_window() -> BoundedQueue<u32> {
    BoundedQueue::with_tuning(Tuning::Fixed(Layout {
        width: 0.5,
        buckets: 3,
    }))
    .unwrap()
}

/// 2^14 buckets of width 0.01: four blocks, so block lists are dealt and the window wraps.
fn blocked_window() -> BoundedQueue<u32> {
    BoundedQueue::with_tuning(Tuning::Fixed(Layout {
        width: 0.01,
        buckets: 1 << 14,
    }))
    .unwrap()
}

fn sparse_auto() -> BoundedQueue<u32> {
    BoundedQueue::with_tuning(Tuning::Auto {
        events_per_bucket: 0.25,
    })
    .unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn every_queue_pops_what_the_reference_pops(ops in ops(400), far in prop::bool::ANY) {
        // Half the cases run in a time window far from zero, where Δ is tiny next to |t|.
        let origin = if far { 1.0e9 } else { 0.0 };
        let expected = run(&mut Reference::default(), &ops, origin);
        prop_assert_eq!(&run(&mut HeapQueue::new(), &ops, origin), &expected, "heap");
        prop_assert_eq!(&run(&mut BoundedQueue::new(), &ops, origin), &expected, "bounded auto");
        prop_assert_eq!(&run(&mut sparse_auto(), &ops, origin), &expected, "bounded sparse");
        prop_assert_eq!(&run(&mut tiny_window(), &ops, origin), &expected, "bounded tiny window");
        prop_assert_eq!(&run(&mut blocked_window(), &ops, origin), &expected, "bounded blocks");
    }

    #[test]
    fn many_events_force_respreads_and_wraps(times in prop::collection::vec(0.0..1.0f64, 300..3000),
                                              scale in prop_oneof![Just(1e-12), Just(1.0), Just(1e12)]) {
        // Bulk pushes before any pop: the first layout is far off and must re-spread.
        let ops: Vec<Op> = times.iter().map(|&t| Op::Push(TimeSpec::Exactly(t * scale)))
            .chain(std::iter::repeat_n(Op::Pop, times.len() / 2))
            .chain(times.iter().map(|&t| Op::Push(TimeSpec::After(t * scale))))
            .collect();
        let expected = run(&mut Reference::default(), &ops, 0.0);
        let mut q = BoundedQueue::new();
        prop_assert_eq!(&run(&mut q, &ops, 0.0), &expected);
        prop_assert!(q.stats().wraps + q.stats().respreads > 0);
        // A sparse target spreads the same events over many blocks of fine buckets.
        let mut q = BoundedQueue::with_tuning(Tuning::Auto { events_per_bucket: 0.1 }).unwrap();
        prop_assert_eq!(&run(&mut q, &ops, 0.0), &expected);
    }
}

/// A payload for the lazy-invalidation model: a ticket plus an id to compare logs by.
#[derive(Clone, Copy, Debug)]
struct Ev {
    id: u32,
    ticket: Ticket,
}

impl Stamped for Ev {
    fn is_current(&self, book: &StampBook) -> bool {
        self.ticket.is_current(book)
    }
}

#[derive(Clone, Debug)]
enum LazyOp {
    Schedule { dt: f64, a: u32, b: Option<u32> },
    Invalidate(u32),
    Pop,
    Peek,
    Sweep,
}

fn lazy_ops() -> impl Strategy<Value = Vec<LazyOp>> {
    const N: u32 = 6;
    prop::collection::vec(
        prop_oneof![
            6 => (0.0..5.0f64, 0..N, prop::option::of(0..N))
                .prop_map(|(dt, a, b)| LazyOp::Schedule { dt, a, b }),
            3 => (0..N).prop_map(LazyOp::Invalidate),
            4 => Just(LazyOp::Pop),
            1 => Just(LazyOp::Peek),
            1 => Just(LazyOp::Sweep),
        ],
        0..300,
    )
}

/// An event of the lazy model: time, sequence, id, participants and their generations.
type ModelEvent = (f64, u64, u32, Vec<u32>, Vec<u64>);

/// The lazy model: the reference queue holding every event, with staleness decided at pop time
/// by an independent record of which participants were invalidated after each event was made.
fn run_lazy_reference(ops: &[LazyOp]) -> Vec<String> {
    let mut items: Vec<ModelEvent> = Vec::new();
    let mut gens = [0u64; 6];
    let (mut seq, mut next, mut now) = (0u64, 0u32, 0.0f64);
    let mut log = Vec::new();
    let current = |it: &ModelEvent, gens: &[u64; 6]| {
        it.3.iter().zip(&it.4).all(|(&p, &g)| gens[p as usize] == g)
    };
    let earliest = |items: &[ModelEvent]| {
        (0..items.len()).reduce(|a, b| {
            if items[b].0 < items[a].0 || (items[b].0 == items[a].0 && items[b].1 < items[a].1) {
                b
            } else {
                a
            }
        })
    };
    for op in ops {
        match *op {
            LazyOp::Schedule { dt, a, b } => {
                let who: Vec<u32> = std::iter::once(a).chain(b).collect();
                let g = who.iter().map(|&p| gens[p as usize]).collect();
                items.push((now + dt, seq, next, who, g));
                seq += 1;
                next += 1;
            }
            LazyOp::Invalidate(p) => gens[p as usize] += 1,
            LazyOp::Pop | LazyOp::Peek => {
                let mut found = None;
                while let Some(i) = earliest(&items) {
                    if current(&items[i], &gens) {
                        found = Some(i);
                        break;
                    }
                    items.swap_remove(i);
                }
                let shown = found.map(|i| (items[i].0, items[i].2));
                if matches!(op, LazyOp::Pop) {
                    if let Some(i) = found {
                        now = items[i].0;
                        items.swap_remove(i);
                    }
                    log.push(format!("pop {shown:?}"));
                } else {
                    log.push(format!("peek {shown:?}"));
                }
            }
            LazyOp::Sweep => items.retain(|it| current(it, &gens)),
        }
    }
    log
}

fn run_lazy<Q: EventQueue<Payload = Ev>>(q: Q, ops: &[LazyOp], cleanup: Cleanup) -> Vec<String> {
    let mut q = LazyQueue::with_cleanup(q, 6, cleanup);
    let (mut next, mut now) = (0u32, 0.0f64);
    let mut log = Vec::new();
    for op in ops {
        match *op {
            LazyOp::Schedule { dt, a, b } => {
                let ticket = match b {
                    Some(b) => q.book().ticket2(a, b),
                    None => q.book().ticket1(a),
                };
                q.schedule(now + dt, Ev { id: next, ticket }).unwrap();
                next += 1;
            }
            LazyOp::Invalidate(p) => q.invalidate(p),
            LazyOp::Pop => {
                let e = q.pop();
                if let Some(e) = &e {
                    now = e.time;
                }
                log.push(format!("pop {:?}", e.map(|e| (e.time, e.payload.id))));
            }
            LazyOp::Peek => log.push(format!("peek {:?}", q.peek().map(|(t, e)| (t, e.id)))),
            LazyOp::Sweep => {
                q.sweep();
            }
        }
    }
    log
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn lazy_queues_pop_exactly_the_current_events(ops in lazy_ops()) {
        let expected = run_lazy_reference(&ops);
        let eager = Cleanup { growth: 1.0, min_len: 0 };
        let never = Cleanup { growth: f64::INFINITY, min_len: usize::MAX };
        for cleanup in [Cleanup::default(), eager, never] {
            prop_assert_eq!(&run_lazy(HeapQueue::new(), &ops, cleanup), &expected);
            prop_assert_eq!(&run_lazy(BoundedQueue::new(), &ops, cleanup), &expected);
            let tiny = BoundedQueue::with_tuning(Tuning::Fixed(Layout { width: 0.3, buckets: 2 })).unwrap();
            prop_assert_eq!(&run_lazy(tiny, &ops, cleanup), &expected);
            let blocks = BoundedQueue::with_tuning(Tuning::Fixed(Layout { width: 1e-3, buckets: 1 << 14 })).unwrap();
            prop_assert_eq!(&run_lazy(blocks, &ops, cleanup), &expected);
        }
    }
}
