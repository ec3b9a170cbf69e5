//! An indexed calendar queue: one pending time per participant, each in an unsorted bucket of a
//! time window, linked in place so that changing a participant's time is O(1).
//!
//! This is G. Paul's bucket idea (J. Comput. Phys. 221, 615, 2007) for the case a
//! [`TournamentTree`](crate::TournamentTree) serves: every participant has exactly one pending
//! time, its earliest event. Time is cut into buckets of width Δ over a window; each bucket is a
//! doubly-linked list threaded through the participants' own records, and times beyond the
//! window wait in an overflow list. Setting a time unlinks the participant from its bucket and
//! links it into the new one, both O(1): there are no stale entries, no tickets and no sweeps.
//! Taking the earliest scans the first non-empty bucket, which holds about two entries when
//! Δ fits the events.
//!
//! Δ and the window are chosen from the pending times whenever the window is used up (and the
//! overflow is dealt into a new window): Δ so that the front of the queue holds about
//! [`CALENDAR_EVENTS_PER_BUCKET`] times per bucket, the window several times the span the
//! pending times would fill at that density. A bucket found much fuller than that (the times
//! bunched since the last choice) re-chooses at once, at most once per `len` pops, so the work
//! stays O(1) amortised per operation.
//!
//! The order is the time, then the lower participant index among equal times, as the
//! tournament tree's. `+∞` means "no event"; NaN is refused.
//!
//! ```
//! use event_queue::Calendar;
//!
//! let mut cal = Calendar::new(4); // nobody has an event yet
//! cal.set(2, 1.5)?;
//! cal.set(0, 0.5)?;
//! cal.set(3, 0.7)?;
//! cal.set(3, 2.0)?; // participant 3 changed its mind: its 0.7 is gone, in O(1)
//! assert_eq!(cal.pop(), Some((0, 0.5)));
//! assert_eq!(cal.pop(), Some((2, 1.5)));
//! assert_eq!(cal.pop(), Some((3, 2.0)));
//! assert_eq!(cal.pop(), None);
//! # Ok::<(), event_queue::QueueError>(())
//! ```

use crate::{QueueError, check_time};

/// Times per bucket that the calendar aims for at the front of the queue.
pub const CALENDAR_EVENTS_PER_BUCKET: f64 = 2.0;

/// The window covers this many times the span that the pending times would fill at the
/// density of the front of the queue.
const WINDOW_REACH: f64 = 4.0;
/// Fewest and most buckets in a window.
const MIN_BUCKETS: usize = 16;
const MAX_BUCKETS: usize = 1 << 26;
/// A bucket scan longer than this (with more pending times than [`MIN_LEN_RETUNE`]) re-chooses
/// the layout, once the scans since the last choice have visited `4 len` entries (so the
/// choice, O(len), costs at most what the scans did).
const LONG_SCAN: usize = 32;
const MIN_LEN_RETUNE: usize = 256;

/// No participant / not in any list.
const NIL: u32 = u32::MAX;

/// One participant's record: its pending time and its links in the bucket it sits in.
#[derive(Clone, Copy, Debug)]
struct Node {
    time: f64,
    next: u32,
    prev: u32,
    /// The bucket (`0..buckets`), the overflow list (`buckets`), or [`NIL`] (no pending time).
    bucket: u32,
}

/// An indexed calendar queue over participants `0..n`.
#[derive(Clone, Debug)]
pub struct Calendar {
    nodes: Vec<Node>,
    /// Head of each bucket's list; the last slot heads the overflow list.
    heads: Vec<u32>,
    /// Start of bucket 0, bucket width Δ and its inverse.
    base: f64,
    width: f64,
    inv_width: f64,
    /// The bucket being consumed: every bucket before it is empty.
    current: usize,
    /// Participants with a pending time.
    len: usize,
    /// Entries visited by bucket scans since the layout was last chosen.
    scan_work: usize,
    /// Times of the pending participants while a layout is chosen (kept to reuse memory).
    scratch: Vec<f64>,
    layouts: u64,
}

impl Calendar {
    /// A calendar for participants `0..n`, none with a pending time.
    ///
    /// # Panics
    /// If `n` is 2³² − 1 or more.
    pub fn new(n: usize) -> Self {
        assert!(n < NIL as usize, "at most 2^32 - 2 participants");
        let buckets = MIN_BUCKETS;
        Calendar {
            nodes: vec![
                Node {
                    time: f64::INFINITY,
                    next: NIL,
                    prev: NIL,
                    bucket: NIL,
                };
                n
            ],
            heads: vec![NIL; buckets + 1],
            base: 0.0,
            width: 0.0,
            inv_width: 0.0,
            // No layout yet: everything waits in the overflow until the first pop chooses one.
            current: buckets,
            len: 0,
            scan_work: 0,
            scratch: Vec::new(),
            layouts: 0,
        }
    }

    /// Number of participants with a pending time.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no participant has a pending time.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Participant `p`'s pending time (`+∞`: none).
    ///
    /// # Panics
    /// If `p` is not a participant.
    pub fn get(&self, p: usize) -> f64 {
        self.nodes[p].time
    }

    /// How many times the layout (Δ and the window) has been chosen.
    pub fn layouts(&self) -> u64 {
        self.layouts
    }

    /// The bucket width Δ of the present layout (0 before the first pop).
    pub fn width(&self) -> f64 {
        self.width
    }

    fn buckets(&self) -> usize {
        self.heads.len() - 1
    }

    /// Sets participant `p`'s pending time, replacing its previous one (`+∞`: none).
    ///
    /// # Errors
    /// [`QueueError::NanTime`] for a NaN time; the calendar is left unchanged.
    ///
    /// # Panics
    /// If `p` is not a participant.
    #[inline]
    pub fn set(&mut self, p: usize, time: f64) -> Result<(), QueueError> {
        check_time(time)?;
        self.unlink(p);
        self.nodes[p].time = time;
        if time < f64::INFINITY {
            let b = self.bucket_of(time);
            self.link(p, b);
            self.len += 1;
        }
        Ok(())
    }

    /// The bucket for `time` in the present layout: never before the current one, and the
    /// overflow beyond the window. Monotone in `time`, so buckets keep the time order.
    #[inline(always)]
    fn bucket_of(&self, time: f64) -> usize {
        let buckets = self.buckets();
        let x = (time - self.base) * self.inv_width;
        if x < self.current as f64 {
            // `current` is the overflow itself while no window is laid out.
            self.current
        } else if x < buckets as f64 {
            x as usize
        } else {
            buckets
        }
    }

    #[inline(always)]
    fn link(&mut self, p: usize, b: usize) {
        let head = self.heads[b];
        self.nodes[p].next = head;
        self.nodes[p].prev = NIL;
        self.nodes[p].bucket = b as u32;
        if head != NIL {
            self.nodes[head as usize].prev = p as u32;
        }
        self.heads[b] = p as u32;
    }

    #[inline(always)]
    fn unlink(&mut self, p: usize) {
        let Node {
            next, prev, bucket, ..
        } = self.nodes[p];
        if bucket == NIL {
            return;
        }
        if prev == NIL {
            self.heads[bucket as usize] = next;
        } else {
            self.nodes[prev as usize].next = next;
        }
        if next != NIL {
            self.nodes[next as usize].prev = prev;
        }
        self.nodes[p].bucket = NIL;
        self.len -= 1;
    }

    /// The participant with the earliest pending time and its time (ties: the lower index);
    /// `None` if nobody has one. Moves the window on past empty buckets.
    #[inline]
    pub fn peek(&mut self) -> Option<(usize, f64)> {
        if self.len == 0 {
            return None;
        }
        loop {
            let buckets = self.buckets();
            while self.current < buckets && self.heads[self.current] == NIL {
                self.current += 1;
            }
            if self.current == buckets {
                self.choose_layout();
                continue;
            }
            let (p, t, scanned) = self.scan(self.current);
            self.scan_work += scanned;
            if scanned > LONG_SCAN && self.len > MIN_LEN_RETUNE && self.scan_work >= 4 * self.len {
                self.choose_layout();
                continue;
            }
            return Some((p, t));
        }
    }

    /// Removes and returns the participant with the earliest pending time and its time.
    #[inline]
    pub fn pop(&mut self) -> Option<(usize, f64)> {
        let (p, t) = self.peek()?;
        self.unlink(p);
        self.nodes[p].time = f64::INFINITY;
        Some((p, t))
    }

    /// The earliest entry of bucket `b` (not empty) and how many entries it holds.
    #[inline(always)]
    fn scan(&self, b: usize) -> (usize, f64, usize) {
        let mut p = self.heads[b] as usize;
        let (mut best, mut best_t) = (p, self.nodes[p].time);
        let mut n = 1;
        loop {
            let next = self.nodes[p].next;
            if next == NIL {
                return (best, best_t, n);
            }
            p = next as usize;
            n += 1;
            let t = self.nodes[p].time;
            if t < best_t || (t == best_t && p < best) {
                (best, best_t) = (p, t);
            }
        }
    }

    /// Chooses Δ and the window from the pending times and deals them all into it.
    #[cold]
    fn choose_layout(&mut self) {
        self.layouts += 1;
        self.scan_work = 0;
        // Every pending participant, out of whatever list it is in.
        let mut times = std::mem::take(&mut self.scratch);
        times.clear();
        let mut pending = Vec::with_capacity(self.len);
        for (p, node) in self.nodes.iter().enumerate() {
            if node.bucket != NIL {
                pending.push(p as u32);
                times.push(node.time);
            }
        }
        let (base, width) = layout_for(&mut times);
        let buckets = ((WINDOW_REACH * pending.len() as f64 / CALENDAR_EVENTS_PER_BUCKET).ceil()
            as usize)
            .clamp(MIN_BUCKETS, MAX_BUCKETS)
            .next_power_of_two();
        // Relinking overwrites every pending node's links; the count stays.
        self.heads.clear();
        self.heads.resize(buckets + 1, NIL);
        self.base = base;
        self.width = width;
        self.inv_width = 1.0 / width;
        self.current = 0;
        for &p in &pending {
            let b = self.bucket_of(self.nodes[p as usize].time);
            self.link(p as usize, b);
        }
        self.scratch = times;
    }
}

/// The start and bucket width for pending `times` (reordered in place): the window starts at
/// the earliest finite time, and Δ holds [`CALENDAR_EVENTS_PER_BUCKET`] times at the density of
/// the earliest eighth of them. Degenerate spreads (one time, all equal, or a span so small
/// that Δ would lose its digits against the times) fall back to a width the times can resolve;
/// `−∞` times take no part (they go to the first bucket).
fn layout_for(times: &mut Vec<f64>) -> (f64, f64) {
    times.retain(|t| t.is_finite());
    let Some(&first) = times.iter().min_by(|a, b| a.total_cmp(b)) else {
        return (0.0, 1.0);
    };
    let len = times.len();
    let k = (len / 8).max(1).min(len - 1);
    let mut width = if len > 1 {
        let (_, &mut tk, _) = times.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
        CALENDAR_EVENTS_PER_BUCKET * (tk - first) / k as f64
    } else {
        0.0
    };
    // Δ must be resolvable at the times' magnitude, and finite.
    let floor = (first.abs().max(f64::MIN_POSITIVE) * 1e-12).max(1e-300);
    if !(width.is_finite() && width > floor) {
        let last = times.iter().copied().fold(first, f64::max);
        width = ((last - first) / len as f64).max(floor);
        if !width.is_finite() {
            width = floor;
        }
    }
    (first, width)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Pops everything, checking the order against a sort by (time, index).
    fn drain(cal: &mut Calendar) -> Vec<(usize, f64)> {
        std::iter::from_fn(|| cal.pop()).collect()
    }

    #[test]
    fn replaces_withdraws_and_refuses_nan() {
        let mut c = Calendar::new(5);
        c.set(0, 5.0).unwrap();
        c.set(1, 2.0).unwrap();
        c.set(2, 7.0).unwrap();
        c.set(1, 6.0).unwrap();
        c.set(3, 1.0).unwrap();
        c.set(3, f64::INFINITY).unwrap();
        assert_eq!(c.set(2, f64::NAN), Err(QueueError::NanTime));
        assert_eq!(c.get(2), 7.0);
        assert_eq!(c.len(), 3);
        assert_eq!(c.peek(), Some((0, 5.0)));
        assert_eq!(drain(&mut c), vec![(0, 5.0), (1, 6.0), (2, 7.0)]);
        assert!(c.is_empty());
    }

    #[test]
    fn equal_times_go_to_the_lower_index_and_past_times_pop_next() {
        let mut c = Calendar::new(6);
        for p in [4, 1, 3] {
            c.set(p, 2.0).unwrap();
        }
        c.set(0, 10.0).unwrap();
        assert_eq!(c.pop(), Some((1, 2.0)));
        // Earlier than the last popped (round-off in a simulator): next out.
        c.set(5, 1.0).unwrap();
        assert_eq!(c.pop(), Some((5, 1.0)));
        assert_eq!(drain(&mut c), vec![(3, 2.0), (4, 2.0), (0, 10.0)]);
    }

    #[test]
    fn minus_infinity_pops_first() {
        let mut c = Calendar::new(3);
        c.set(1, 3.0).unwrap();
        c.set(0, f64::NEG_INFINITY).unwrap();
        assert_eq!(drain(&mut c), vec![(0, f64::NEG_INFINITY), (1, 3.0)]);
    }

    #[test]
    fn bunched_times_re_choose_the_layout() {
        // Spread first (a wide Δ), then every participant bunched into one bucket's span.
        let n = 4096;
        let mut c = Calendar::new(n);
        for p in 0..n {
            c.set(p, p as f64).unwrap();
        }
        c.pop();
        let width = c.width();
        for p in 0..n {
            c.set(p, 1.0 + p as f64 * 1e-9).unwrap();
        }
        for _ in 0..n {
            c.set(0, f64::INFINITY).unwrap();
            c.pop();
        }
        assert!(c.layouts() >= 2);
        assert!(c.width() < width * 1e-3, "{} against {width}", c.width());
    }

    /// One step of a random workload: set a participant's time, or pop.
    #[derive(Clone, Debug)]
    enum Op {
        Set(usize, f64),
        Withdraw(usize),
        Pop,
    }

    fn ops() -> impl Strategy<Value = Vec<Op>> {
        let op = prop_oneof![
            4 => (0..64usize, 0.0..50.0f64).prop_map(|(p, dt)| Op::Set(p, dt)),
            1 => (0..64usize).prop_map(Op::Withdraw),
            4 => Just(Op::Pop),
        ];
        proptest::collection::vec(op, 1..2000)
    }

    proptest! {
        /// Against a plain array of times: every pop is the earliest (ties to the lower
        /// index), times set relative to the last pop as a simulator sets them, some of them
        /// slightly in the past.
        #[test]
        fn pops_in_time_then_index_order(ops in ops(), tie in 0u8..4) {
            let n = 64;
            let mut c = Calendar::new(n);
            let mut model = vec![f64::INFINITY; n];
            let mut now = 0.0f64;
            for op in ops {
                match op {
                    Op::Set(p, dt) => {
                        // Quantised times make exact ties common.
                        let t = if tie == 0 { ((now + dt) * 4.0).floor() / 4.0 } else { now + dt - 0.01 };
                        c.set(p, t).unwrap();
                        model[p] = t;
                    }
                    Op::Withdraw(p) => {
                        c.set(p, f64::INFINITY).unwrap();
                        model[p] = f64::INFINITY;
                    }
                    Op::Pop => {
                        let want = model
                            .iter()
                            .enumerate()
                            .filter(|(_, t)| **t < f64::INFINITY)
                            .min_by(|a, b| a.1.total_cmp(b.1).then(a.0.cmp(&b.0)))
                            .map(|(p, t)| (p, *t));
                        prop_assert_eq!(c.pop(), want);
                        if let Some((p, t)) = want {
                            model[p] = f64::INFINITY;
                            now = now.max(t);
                        }
                    }
                }
                prop_assert_eq!(c.len(), model.iter().filter(|t| **t < f64::INFINITY).count());
            }
        }
    }
}
