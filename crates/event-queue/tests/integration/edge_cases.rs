//! Edge cases every queue must handle: empty queues, NaN and infinite times, times earlier than
//! the last pop, long runs of equal times, time windows far from zero, and ten million events.

use event_queue::hold::StdHeap;
use event_queue::{BoundedQueue, EventQueue, HeapQueue, Layout, QueueError, Tuning};

/// Runs `check` on every queue implementation.
fn each_queue(check: impl Fn(&mut dyn EventQueue<Payload = u32>, &str)) {
    check(&mut HeapQueue::new(), "HeapQueue");
    check(&mut BoundedQueue::new(), "BoundedQueue auto");
    let fixed = Tuning::Fixed(Layout {
        width: 0.25,
        buckets: 8,
    });
    check(
        &mut BoundedQueue::with_tuning(fixed).unwrap(),
        "BoundedQueue fixed",
    );
    check(&mut StdHeap::new(), "std BinaryHeap");
}

fn drain(q: &mut dyn EventQueue<Payload = u32>) -> Vec<(f64, u32)> {
    std::iter::from_fn(|| q.pop().map(|e| (e.time, e.payload))).collect()
}

#[test]
fn empty_queue() {
    each_queue(|q, name| {
        assert!(q.pop().is_none(), "{name}");
        assert!(q.peek().is_none() && q.peek_time().is_none(), "{name}");
        assert_eq!(q.len(), 0, "{name}");
        assert!(q.is_empty(), "{name}");
        assert_eq!(q.retain(&mut |_| false), 0, "{name}");
        q.clear();
        q.push(1.0, 7).unwrap();
        q.clear();
        assert!(q.pop().is_none(), "{name}: clear must empty the queue");
    });
}

#[test]
fn nan_is_refused_and_leaves_the_queue_intact() {
    each_queue(|q, name| {
        q.push(2.0, 1).unwrap();
        q.push(1.0, 0).unwrap();
        assert_eq!(q.push(f64::NAN, 9), Err(QueueError::NanTime), "{name}");
        assert_eq!(q.push(-f64::NAN, 9), Err(QueueError::NanTime), "{name}");
        assert_eq!(q.len(), 2, "{name}");
        assert_eq!(drain(q), vec![(1.0, 0), (2.0, 1)], "{name}");
    });
    assert!(QueueError::NanTime.to_string().contains("NaN"));
}

#[test]
fn infinities_pop_first_and_last_in_arrival_order() {
    each_queue(|q, name| {
        q.push(f64::INFINITY, 0).unwrap();
        q.push(5.0, 1).unwrap();
        q.push(f64::NEG_INFINITY, 2).unwrap();
        q.push(f64::INFINITY, 3).unwrap();
        q.push(f64::NEG_INFINITY, 4).unwrap();
        q.push(f64::MAX, 5).unwrap();
        q.push(f64::MIN, 6).unwrap();
        let order: Vec<u32> = drain(q).into_iter().map(|(_, p)| p).collect();
        assert_eq!(order, vec![2, 4, 6, 1, 5, 0, 3], "{name}");
    });
}

#[test]
fn times_earlier_than_the_last_pop_come_next() {
    each_queue(|q, name| {
        for i in 0..100u32 {
            q.push(f64::from(i), i).unwrap();
        }
        for _ in 0..50 {
            q.pop().unwrap();
        }
        // Round-off in a simulator: an event computed a hair before "now" (49.0).
        q.push(49.0 - 1e-13, 1000).unwrap();
        q.push(10.0, 1001).unwrap();
        assert_eq!(q.pop().unwrap().payload, 1001, "{name}");
        assert_eq!(q.pop().unwrap().payload, 1000, "{name}");
        assert_eq!(q.pop().unwrap().time, 50.0, "{name}");
    });
}

#[test]
fn equal_times_pop_first_in_first_out() {
    each_queue(|q, name| {
        for i in 0..10_000u32 {
            let t = if i % 2 == 0 { 3.0 } else { 1.0 };
            q.push(t, i).unwrap();
        }
        let got = drain(q);
        let odd = got[..5_000].iter().map(|&(_, p)| p);
        assert!(odd.eq((1..10_000).step_by(2)), "{name}");
        let even = got[5_000..].iter().map(|&(_, p)| p);
        assert!(even.eq((0..10_000).step_by(2)), "{name}");
    });
}

#[test]
fn windows_far_from_zero_and_extreme_magnitudes() {
    for origin in [1e15f64, -1e15, 1e300, 0.0] {
        each_queue(|q, name| {
            // Spacing of a few ulps of the origin: the queue must still separate the times.
            let ulp = if origin == 0.0 {
                f64::from_bits(1) // subnormals
            } else {
                origin.abs() * f64::EPSILON
            };
            let times: Vec<f64> = (0..2_000u32)
                .map(|i| origin + f64::from((i * 7_919) % 2_000) * ulp)
                .collect();
            for (i, &t) in times.iter().enumerate() {
                q.push(t, i as u32).unwrap();
            }
            let got = drain(q);
            assert_eq!(got.len(), times.len(), "{name} at {origin}");
            for w in got.windows(2) {
                assert!(
                    w[0].0 < w[1].0 || (w[0].0 == w[1].0 && w[0].1 < w[1].1),
                    "{name} at {origin}: {w:?}"
                );
            }
        });
    }
}

#[test]
fn ten_million_events() {
    // Push 10⁷ events (a hold-like spread with many exact ties), pop them all, check the order
    // and a checksum. The bounded queue is the one whose layout logic meets its largest inputs
    // here; the release-mode validation runs every queue at this size against a full sort.
    let n = 10_000_000u32;
    let mut q = BoundedQueue::new();
    let mut x = 88_172_645_463_325_252u64;
    let mut sum_in = 0.0f64;
    for i in 0..n {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let t = ((x >> 40) % 100_000) as f64 * 1e-3; // 10⁵ distinct times, ~100 events each
        sum_in += t;
        q.push(t, i).unwrap();
    }
    assert_eq!(q.len(), n as usize);
    let (mut last_t, mut last_p, mut count, mut sum_out) = (f64::NEG_INFINITY, 0u32, 0u32, 0.0f64);
    while let Some(e) = q.pop() {
        assert!(
            e.time > last_t || (e.time == last_t && e.payload > last_p),
            "out of order at pop {count}"
        );
        (last_t, last_p) = (e.time, e.payload);
        sum_out += e.time;
        count += 1;
    }
    assert_eq!(count, n);
    assert!((sum_in - sum_out).abs() <= 1e-9 * sum_in);
}
