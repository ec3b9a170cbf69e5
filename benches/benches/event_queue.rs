//! Hold-model throughput of the event queues against `std::collections::BinaryHeap`.
//!
//! `hold/*`: for each queue size n in 10³..10⁶ and each increment distribution, a queue is filled with n
//! events and warmed up with n holds; criterion then times holds on that same queue (one hold per
//! iteration, `iter_custom`), so only steady-state holds are measured. The baseline,
//! `std BinaryHeap`, runs in the same group: compare medians within a group.
//!
//! `pair_hold/*`: one event per participant, a step reschedules two participants (see
//! `event_queue::hold::PairHold`): `TournamentTree` against lazy invalidation.
//!
//! `cargo bench -p dmd-benches --bench event_queue` (or `cargo xtask bench --only event_queue`).

use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use event_queue::hold::{Hold, Increment, PairHold, PairScheduler, StdHeap};
use event_queue::{BoundedQueue, EventQueue, HeapQueue, LazyQueue, TournamentTree};

fn bench_queue<Q: EventQueue<Payload = u64>>(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    queue: Q,
    n: usize,
    inc: Increment,
) {
    let mut hold = Hold::new(queue, n, inc, 42);
    hold.run(n as u64);
    group.bench_function(BenchmarkId::new(name, n), |b| {
        b.iter_custom(|iters| {
            let start = Instant::now();
            std::hint::black_box(hold.run(iters));
            start.elapsed()
        })
    });
}

fn hold(c: &mut Criterion) {
    for (inc, label) in [
        (Increment::Exponential, "exp"),
        (Increment::Uniform, "uniform"),
    ] {
        let mut group = c.benchmark_group(format!("hold/{label}"));
        group.throughput(Throughput::Elements(1));
        group.sample_size(20);
        group.warm_up_time(Duration::from_millis(500));
        group.measurement_time(Duration::from_secs(2));
        for n in [1_000, 10_000, 100_000, 1_000_000] {
            bench_queue(&mut group, "std BinaryHeap", StdHeap::new(), n, inc);
            bench_queue(&mut group, "HeapQueue", HeapQueue::new(), n, inc);
            bench_queue(&mut group, "BoundedQueue", BoundedQueue::new(), n, inc);
        }
        group.finish();
    }
}

fn bench_scheduler<S: PairScheduler>(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    scheduler: S,
    n: u32,
) {
    let mut model = PairHold::new(scheduler, n, Increment::Exponential, 42);
    model.run(u64::from(n));
    group.bench_function(BenchmarkId::new(name, n), |b| {
        b.iter_custom(|iters| {
            let start = Instant::now();
            std::hint::black_box(model.run(iters));
            start.elapsed()
        })
    });
}

/// One event per participant, two participants rescheduled per step (a collision): the
/// tournament tree against lazy invalidation on the bounded queue and on the heap.
fn pair_hold(c: &mut Criterion) {
    let mut group = c.benchmark_group("pair_hold/exp");
    group.throughput(Throughput::Elements(1));
    group.sample_size(20);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(2));
    for n in [1_000u32, 10_000, 100_000, 1_000_000] {
        let lazy_heap = LazyQueue::new(HeapQueue::new(), n as usize);
        let lazy_bounded = LazyQueue::new(BoundedQueue::new(), n as usize);
        bench_scheduler(
            &mut group,
            "TournamentTree",
            TournamentTree::new(n as usize),
            n,
        );
        bench_scheduler(&mut group, "LazyQueue<HeapQueue>", lazy_heap, n);
        bench_scheduler(&mut group, "LazyQueue<BoundedQueue>", lazy_bounded, n);
    }
    group.finish();
}

criterion_group!(benches, hold, pair_hold);
criterion_main!(benches);
