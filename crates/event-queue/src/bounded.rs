//! G. Paul's bounded priority queue (J. Comput. Phys. 221, 615, 2007): O(1) per event.
//!
//! Time is cut into buckets of width Δ. A window of `n` buckets starting at `start` holds
//! unsorted lists; only the bucket being consumed is fine-sorted, in a small binary heap (Paul's
//! "binary tree"). Events beyond the window wait, unsorted, in an overflow list. When the window
//! is used up, the next one starts at the earliest overflow event and the overflow is dealt out
//! again (the wrap-around). A push is one multiply and one vector push; a pop is a pop from a
//! heap of a few events; the bucket scan and the redistribution are paid once per window and
//! amortise to O(1) per event when the window holds a fair share of the queue.
//!
//! **Tuning.** With [`Tuning::Auto`] (the default) Δ and `n` are chosen afresh at every
//! wrap-around from the events then waiting, all of which sit in the overflow: Δ so that the
//! earliest quarter of them falls about [`DEFAULT_EVENTS_PER_BUCKET`] to a bucket (Paul sizes Δ by
//! the population of the tree), and `n` so that the window reaches several times as far as those
//! events (Paul sizes `n` by how far ahead of the last pop new events land). Both adapt as the
//! simulation's event rate or queue size changes. [`Tuning::Fixed`] pins them, as in the paper.
//!
//! Events at `+∞` wait in a list of their own and pop, first in first out, once no finite event
//! is left; events at `−∞`, or earlier than the bucket being consumed, go straight to the heap.
//!
//! **Order.** Which bucket an event goes to is a monotone function of its time, so the queue pops
//! in exactly the same order as [`HeapQueue`](crate::HeapQueue), ties included.

use crate::heap::MinHeap;
use crate::order::Entry;
use crate::{Event, EventQueue, QueueError, check_time};

/// Events per bucket that [`Tuning::Auto`] aims for near the front of the queue.
pub const DEFAULT_EVENTS_PER_BUCKET: f64 = 2.0;

/// Fewest buckets an automatically tuned window has.
const MIN_BUCKETS: usize = 16;
/// Most buckets an automatically tuned window has (memory: 24 bytes per bucket, plus entries).
const MAX_BUCKETS: usize = 1 << 28;
/// Most fine buckets in one block: a block's lists and entries must stay in a core's L2 cache.
const MAX_FINE: usize = 1 << 12;
/// Waiting times sampled to choose Δ at a wrap-around.
const TUNING_SAMPLE: usize = 4096;
/// How far an automatically tuned window reaches, in units of the span the waiting events
/// would fill at the density of the front of the queue.
const WINDOW_REACH: f64 = 8.0;
/// A heap this many times the target bucket population (and at least [`MIN_HEAP_LIMIT`])
/// tells an automatically tuned queue that its layout is far off: it re-spreads at once rather
/// than waiting for the next wrap-around, which a long window may put millions of events away.
const HEAP_LIMIT_FACTOR: f64 = 8.0;
const MIN_HEAP_LIMIT: usize = 16;

/// How the bucket width and count are chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tuning {
    /// Re-chosen at every wrap-around from the waiting events, aiming for
    /// `events_per_bucket` events per bucket near the front of the queue.
    Auto {
        /// Target bucket population (> 0); small values mean more, emptier buckets.
        events_per_bucket: f64,
    },
    /// Fixed width and count, never changed: Paul's setting, for simulations whose events are
    /// never scheduled more than about `buckets × width` ahead of the last pop. Events beyond
    /// the window wait unsorted and every wrap-around scans them, so times spread over many
    /// window lengths cost O(n) per wrap; [`Tuning::Auto`] has no such limit.
    Fixed(Layout),
}

impl Default for Tuning {
    fn default() -> Self {
        Tuning::Auto {
            events_per_bucket: DEFAULT_EVENTS_PER_BUCKET,
        }
    }
}

/// Bucket width Δ and number of buckets in the window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layout {
    /// Δ, the time span of one bucket (finite, > 0, not subnormal).
    pub width: f64,
    /// Number of buckets in the window (≥ 1; rounded up to a power of two).
    pub buckets: usize,
}

/// Counters describing how the queue has been working, for tuning and reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BoundedStats {
    /// Wrap-arounds: windows used up and restarted from the overflow.
    pub wraps: u64,
    /// Re-spreads: the fine-sorted heap grew too large and every event was dealt out afresh.
    pub respreads: u64,
    /// Events moved out of the overflow list into a window.
    pub overflow_moves: u64,
    /// Events dealt from a block's list into its fine buckets.
    pub block_moves: u64,
    /// Buckets emptied into the fine-sorted heap.
    pub buckets_consumed: u64,
    /// Events those buckets held, in total.
    pub bucket_events: u64,
}

/// Entries per chunk of a block list (6 KiB for 24-byte entries).
const CHUNK: usize = 256;

/// An unsorted list of entries kept in fixed-capacity chunks, so that appending never
/// reallocates or copies: a block's list grows by thousands of events while it waits to be
/// dealt, and with a plain `Vec` the copies of its doubling were a tenth of all the work at 10⁶
/// events. Chunks come from and go back to a shared pool, last in first out, so a recycled chunk
/// is usually still in cache.
#[derive(Clone, Debug)]
struct ChunkList<P> {
    /// The chunk being filled: capacity exactly [`CHUNK`], or 0 before the first push.
    tail: Vec<Entry<P>>,
    /// Full chunks.
    full: Vec<Vec<Entry<P>>>,
}

impl<P> ChunkList<P> {
    const fn new() -> Self {
        Self {
            tail: Vec::new(),
            full: Vec::new(),
        }
    }

    fn is_empty(&self) -> bool {
        self.tail.is_empty() && self.full.is_empty()
    }

    #[inline(always)]
    fn push(&mut self, e: Entry<P>, pool: &mut Vec<Vec<Entry<P>>>) {
        if self.tail.len() == self.tail.capacity() {
            self.next_chunk(pool);
        }
        self.tail.push(e);
    }

    #[cold]
    fn next_chunk(&mut self, pool: &mut Vec<Vec<Entry<P>>>) {
        let fresh = pool.pop().unwrap_or_else(|| Vec::with_capacity(CHUNK));
        let old = std::mem::replace(&mut self.tail, fresh);
        if !old.is_empty() {
            self.full.push(old);
        }
    }

    /// Hands every entry to `f`, leaving the list empty and its full chunks in `pool`.
    fn drain_into(&mut self, pool: &mut Vec<Vec<Entry<P>>>, mut f: impl FnMut(Entry<P>)) {
        for mut chunk in self.full.drain(..) {
            chunk.drain(..).for_each(&mut f);
            pool.push(chunk);
        }
        self.tail.drain(..).for_each(f);
    }

    fn retain(&mut self, keep: &mut dyn FnMut(&P) -> bool) -> usize {
        let mut removed = 0;
        for chunk in self.full.iter_mut().chain(std::iter::once(&mut self.tail)) {
            let before = chunk.len();
            chunk.retain(|e| keep(&e.payload));
            removed += before - chunk.len();
        }
        removed
    }

    fn clear(&mut self, pool: &mut Vec<Vec<Entry<P>>>) {
        self.drain_into(pool, drop);
    }
}

/// G. Paul's O(1) priority queue of timed events: buckets of width Δ over a time window, a
/// small heap for the bucket being consumed, an overflow list, automatic tuning ([`Tuning`]).
///
/// ```
/// use event_queue::{BoundedQueue, EventQueue};
///
/// let mut q = BoundedQueue::new();
/// for (i, t) in [0.3, 7.5, 0.1, 1e6, 2.0].into_iter().enumerate() {
///     q.push(t, i)?;
/// }
/// let order: Vec<usize> = std::iter::from_fn(|| q.pop().map(|e| e.payload)).collect();
/// assert_eq!(order, [2, 0, 4, 1, 3]);
/// # Ok::<(), event_queue::QueueError>(())
/// ```
#[derive(Clone, Debug)]
pub struct BoundedQueue<P> {
    /// Sequence number of the next push. Kept away from `len`: adjacent, the two are updated
    /// by one 16-byte load and store in `push` that cannot take its value from `pop`'s 8-byte
    /// store to `len` (a store-forwarding stall that cost ~40 % of a push at 10⁶ events).
    next_seq: u64,
    /// Start of bucket 0 of the current window (always finite).
    start: f64,
    width: f64,
    inv_width: f64,
    /// Buckets per block are `1 << shift`.
    shift: u32,
    /// Buckets in the window, as a float for the comparison in [`place`](Self::place).
    window: f64,
    /// The unsorted lists of the block being consumed; window bucket `i` of that block is
    /// `fine[i & mask]` and spans `[start + iΔ, start + (i+1)Δ)`.
    fine: Vec<Vec<Entry<P>>>,
    /// One unsorted list per block; block `b` holds window buckets `b << shift ..` until it is
    /// dealt into `fine`. `coarse[0]` is never used: block 0 starts out dealt. Never shrinks, so
    /// a retune that changes the number of blocks keeps the lists (and their tail chunks).
    coarse: Vec<ChunkList<P>>,
    /// Empty chunks for the block lists.
    pool: Vec<Vec<Entry<P>>>,
    /// The window bucket whose events are in `current`; buckets `≤ cur` go to `current`.
    cur: u64,
    /// Fine-sorted events of bucket `cur` and anything pushed earlier than it.
    /// Invariant: empty only when no finite event is left.
    current: MinHeap<P>,
    /// Finite events at or beyond the end of the window, unsorted.
    overflow: Vec<Entry<P>>,
    /// Events at `+∞`, in arrival (= pop) order; they pop only when no finite event is left.
    at_infinity: std::collections::VecDeque<Entry<P>>,
    /// Reused allocation for dealing a list out again.
    spare: Vec<Entry<P>>,
    /// Reused allocation for the time quantiles of auto-tuning.
    scratch: Vec<f64>,
    len: usize,
    tuning: Tuning,
    /// With auto-tuning, a heap larger than this triggers [`BoundedQueue::respread`]. Raised to
    /// twice the heap size after each re-spread or wrap, so that a pile of equal times that no
    /// layout can spread does not trigger one re-spread after another.
    heap_limit: usize,
    /// Pushes and pops since the last re-spread. A re-spread (O(len)) waits until this reaches
    /// `len / 2`, which bounds its amortised cost by O(1) per operation whatever the times.
    ops_since_respread: usize,
    stats: BoundedStats,
}

impl<P> Default for BoundedQueue<P> {
    fn default() -> Self {
        Self::new()
    }
}

impl<P> BoundedQueue<P> {
    /// An empty queue with automatic tuning.
    pub fn new() -> Self {
        let layout = Layout {
            width: 1.0,
            buckets: MIN_BUCKETS,
        };
        Self::build(layout, Tuning::default())
    }

    /// An empty queue with the given tuning.
    ///
    /// # Errors
    /// [`QueueError::InvalidLayout`] for a width that is not positive, finite and normal, zero or more than
    /// 2²⁸ buckets, or a target bucket population that is not finite and positive.
    pub fn with_tuning(tuning: Tuning) -> Result<Self, QueueError> {
        let layout = match tuning {
            Tuning::Auto { events_per_bucket } => {
                if !(events_per_bucket.is_finite() && events_per_bucket > 0.0) {
                    return Err(QueueError::InvalidLayout(
                        "events per bucket must be finite and positive",
                    ));
                }
                Layout {
                    width: 1.0,
                    buckets: MIN_BUCKETS,
                }
            }
            Tuning::Fixed(layout) => {
                if !(layout.width.is_finite() && (1.0 / layout.width).is_finite())
                    || layout.width <= 0.0
                {
                    return Err(QueueError::InvalidLayout(
                        "bucket width must be positive, finite, and not subnormal",
                    ));
                }
                if layout.buckets == 0 || layout.buckets > MAX_BUCKETS {
                    return Err(QueueError::InvalidLayout(
                        "a window needs between 1 and 2^28 buckets",
                    ));
                }
                layout
            }
        };
        Ok(Self::build(layout, tuning))
    }

    fn build(layout: Layout, tuning: Tuning) -> Self {
        let mut q = Self {
            start: 0.0,
            width: 1.0,
            inv_width: 1.0,
            shift: 0,
            window: 1.0,
            fine: Vec::new(),
            coarse: Vec::new(),
            pool: Vec::new(),
            cur: 0,
            current: MinHeap::new(),
            overflow: Vec::new(),
            at_infinity: std::collections::VecDeque::new(),
            spare: Vec::new(),
            scratch: Vec::new(),
            len: 0,
            next_seq: 0,
            tuning,
            heap_limit: MIN_HEAP_LIMIT,
            ops_since_respread: 0,
            stats: BoundedStats::default(),
        };
        q.set_layout(layout.width, layout.buckets);
        q.heap_limit = q.heap_limit_floor();
        q
    }

    /// Sets Δ and the bucket count (rounded up to a power of two) and splits the window into
    /// blocks of at most [`MAX_FINE`] buckets. Only while every list is empty.
    fn set_layout(&mut self, width: f64, buckets: usize) {
        let total = buckets.next_power_of_two();
        let fine = total.min(MAX_FINE);
        self.width = width;
        self.inv_width = 1.0 / width;
        self.shift = fine.trailing_zeros();
        self.window = total as f64;
        self.fine.resize_with(fine, Vec::new);
        let blocks = total / fine;
        if self.coarse.len() < blocks {
            self.coarse.resize_with(blocks, ChunkList::new);
        }
    }

    /// The bucket width and count in use now.
    pub fn layout(&self) -> Layout {
        Layout {
            width: self.width,
            buckets: self.window as usize,
        }
    }

    /// How the queue has been working so far.
    pub fn stats(&self) -> BoundedStats {
        self.stats
    }

    /// Window bucket of a time, as a float: monotone in time for NaN-free times, so every
    /// decision taken from it keeps the events in order.
    #[inline(always)]
    fn index(&self, time: f64) -> f64 {
        (time - self.start) * self.inv_width
    }

    /// Puts an entry where it belongs: the heap if its bucket has been reached, a fine bucket if
    /// it falls in the block being consumed, its block's list if further in the window, the
    /// overflow otherwise.
    #[inline(always)]
    fn place(&mut self, e: Entry<P>) {
        let x = self.index(e.time);
        debug_assert!(!x.is_nan(), "bucket index of {} is NaN", e.time);
        if x < (self.cur + 1) as f64 {
            self.current.push(e);
        } else if x < self.window {
            let i = x as u64;
            let block = i >> self.shift;
            if block == self.cur >> self.shift {
                let mask = self.fine.len() as u64 - 1;
                self.fine[(i & mask) as usize].push(e);
            } else {
                self.coarse[block as usize].push(e, &mut self.pool);
            }
        } else {
            self.overflow.push(e);
        }
    }

    /// Whether finite events wait outside `current`.
    #[inline(always)]
    fn finite_waiting(&self) -> bool {
        self.len > self.current.len() + self.at_infinity.len()
    }

    /// Refills `current` from the next non-empty bucket, dealing out the next block's list and
    /// wrapping around as needed. Called only when `current` is empty and finite events wait
    /// elsewhere.
    fn advance(&mut self) {
        debug_assert!(self.current.is_empty() && self.finite_waiting());
        let mask = self.fine.len() as u64 - 1;
        loop {
            let next = self.cur + 1;
            if next as f64 >= self.window {
                self.wrap();
                if !self.current.is_empty() {
                    return;
                }
                continue;
            }
            if next & mask == 0 {
                self.deal_block((next >> self.shift) as usize);
            }
            self.cur = next;
            let bucket = &mut self.fine[(next & mask) as usize];
            if !bucket.is_empty() {
                self.stats.buckets_consumed += 1;
                self.stats.bucket_events += bucket.len() as u64;
                self.current.extend(bucket);
                return;
            }
        }
    }

    /// Deals block `b`'s list into the fine buckets (all of which are empty).
    fn deal_block(&mut self, b: usize) {
        let (start, inv_width, shift) = (self.start, self.inv_width, self.shift);
        let mask = self.fine.len() as u64 - 1;
        let fine = &mut self.fine;
        let mut moved = 0u64;
        self.coarse[b].drain_into(&mut self.pool, |e| {
            // The same float expression as `index`, so the same bucket as at push time.
            let i = ((e.time - start) * inv_width) as u64;
            debug_assert_eq!(i >> shift, b as u64);
            fine[(i & mask) as usize].push(e);
            moved += 1;
        });
        self.stats.block_moves += moved;
    }

    /// Starts a new window at the earliest overflow event and deals the overflow out again.
    fn wrap(&mut self) {
        debug_assert!(self.current.is_empty());
        debug_assert!(self.fine.iter().all(Vec::is_empty));
        debug_assert!(self.coarse.iter().all(ChunkList::is_empty));
        self.stats.wraps += 1;
        // −∞ (moved here by a re-spread) always lands in the heap; it cannot start a window.
        let t_min = self
            .overflow
            .iter()
            .map(|e| e.time)
            .filter(|t| t.is_finite())
            .fold(f64::INFINITY, f64::min);
        if t_min.is_finite() {
            if let Tuning::Auto { events_per_bucket } = self.tuning {
                self.retune(t_min, events_per_bucket);
            }
            self.start = t_min;
        }
        self.cur = 0;
        let mut waiting = std::mem::replace(&mut self.overflow, std::mem::take(&mut self.spare));
        self.stats.overflow_moves += waiting.len() as u64;
        for e in waiting.drain(..) {
            self.place(e);
        }
        // Give the overflow back its large allocation (it fills up again in this window).
        if waiting.capacity() > self.overflow.capacity() {
            waiting.append(&mut self.overflow);
            std::mem::swap(&mut waiting, &mut self.overflow);
        }
        self.spare = waiting;
        self.heap_limit = self.heap_limit_floor().max(2 * self.current.len());
    }

    fn heap_limit_floor(&self) -> usize {
        match self.tuning {
            Tuning::Auto { events_per_bucket } => {
                MIN_HEAP_LIMIT.max((HEAP_LIMIT_FACTOR * events_per_bucket) as usize)
            }
            Tuning::Fixed(_) => usize::MAX,
        }
    }

    /// Re-spreads if the heap shows the layout is far off and enough operations have passed
    /// since the last re-spread to pay for this one.
    #[inline(always)]
    fn check_layout(&mut self) {
        self.ops_since_respread += 1;
        if self.current.len() > self.heap_limit && 2 * self.ops_since_respread >= self.len {
            self.respread();
        }
    }

    /// Deals every event out afresh with a new layout: the heap has grown too large, so the
    /// layout no longer fits the events (auto-tuning only).
    #[cold]
    fn respread(&mut self) {
        self.stats.respreads += 1;
        self.ops_since_respread = 0;
        self.overflow.extend(self.current.drain());
        for list in &mut self.fine {
            self.overflow.append(list);
        }
        let overflow = &mut self.overflow;
        for list in &mut self.coarse {
            list.drain_into(&mut self.pool, |e| overflow.push(e));
        }
        self.wrap();
        if self.current.is_empty() && self.finite_waiting() {
            self.advance();
        }
    }

    /// Chooses Δ and the bucket count from the waiting events (all in the overflow), earliest
    /// at `t_min`.
    fn retune(&mut self, t_min: f64, events_per_bucket: f64) {
        let m = self.overflow.len();
        // A strided sample of the waiting times: the quantile below needs a few thousand
        // values, not all of them, which keeps a wrap at O(1) work beyond moving the events.
        let stride = (m / TUNING_SAMPLE).max(1);
        self.scratch.clear();
        self.scratch.extend(
            self.overflow
                .iter()
                .step_by(stride)
                .map(|e| e.time)
                .filter(|t| t.is_finite()),
        );
        let sample = self.scratch.len();
        // The earliest quarter sets the density near the front of the queue.
        let k = (sample / 4).max(1).min(sample.saturating_sub(1));
        if k == 0 {
            return; // a single finite event: nothing to measure, keep the layout
        }
        let (_, t_k, _) = self.scratch.select_nth_unstable_by(k, f64::total_cmp);
        let span = *t_k - t_min;
        // k sampled events stand for k·stride waiting ones.
        let width = events_per_bucket * span / (k * stride) as f64;
        // Δ below the resolution of the times themselves cannot separate events, and 1/Δ must
        // be finite (a subnormal Δ would make the bucket index ∞·0 = NaN).
        let resolution = t_min.abs().max(t_k.abs()) * 4.0 * f64::EPSILON;
        if !(width > resolution && (1.0 / width).is_finite() && width.is_finite()) {
            return; // a pile of (nearly) equal times: keep the layout that holds them
        }
        // The window reaches WINDOW_REACH times as far as the events now waiting would fill
        // at the front's density. Only one block of it is materialised as fine buckets, so a
        // long reach costs just one list per block, and it makes wrap-arounds (which move
        // every waiting event) rare.
        let want = (WINDOW_REACH * m as f64 / events_per_bucket).ceil() as usize;
        self.set_layout(width, want.clamp(MIN_BUCKETS, MAX_BUCKETS));
    }
}

impl<P> EventQueue for BoundedQueue<P> {
    type Payload = P;

    #[inline]
    fn push(&mut self, time: f64, payload: P) -> Result<(), QueueError> {
        check_time(time)?;
        let seq = self.next_seq;
        self.next_seq += 1;
        self.len += 1;
        if time == f64::INFINITY {
            self.at_infinity.push_back(Entry { time, seq, payload });
            return Ok(());
        }
        self.place(Entry { time, seq, payload });
        if self.current.is_empty() {
            self.advance();
        }
        self.check_layout();
        Ok(())
    }

    #[inline]
    fn pop(&mut self) -> Option<Event<P>> {
        let Some(e) = self.current.pop() else {
            let e = self.at_infinity.pop_front()?;
            self.len -= 1;
            return Some(e.into());
        };
        self.len -= 1;
        if self.current.is_empty() && self.finite_waiting() {
            self.advance();
        }
        self.check_layout();
        Some(e.into())
    }

    fn peek(&self) -> Option<(f64, &P)> {
        self.current
            .peek()
            .or_else(|| self.at_infinity.front())
            .map(|e| (e.time, &e.payload))
    }

    fn len(&self) -> usize {
        self.len
    }

    fn clear(&mut self) {
        self.current.clear();
        for list in &mut self.fine {
            list.clear();
        }
        for list in &mut self.coarse {
            list.clear(&mut self.pool);
        }
        self.overflow.clear();
        self.at_infinity.clear();
        self.len = 0;
    }

    fn retain(&mut self, keep: &mut dyn FnMut(&P) -> bool) -> usize {
        let mut removed = self.current.retain(keep);
        for list in self
            .fine
            .iter_mut()
            .chain(std::iter::once(&mut self.overflow))
        {
            let before = list.len();
            list.retain(|e| keep(&e.payload));
            removed += before - list.len();
        }
        for list in &mut self.coarse {
            removed += list.retain(keep);
        }
        let before = self.at_infinity.len();
        self.at_infinity.retain(|e| keep(&e.payload));
        removed += before - self.at_infinity.len();
        self.len -= removed;
        if self.current.is_empty() && self.finite_waiting() {
            self.advance();
        }
        removed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drain<P>(q: &mut BoundedQueue<P>) -> Vec<(f64, P)> {
        std::iter::from_fn(|| q.pop().map(|e| (e.time, e.payload))).collect()
    }

    #[test]
    fn wraps_around_and_keeps_order() {
        let mut q = BoundedQueue::with_tuning(Tuning::Fixed(Layout {
            width: 1.0,
            buckets: 4,
        }))
        .unwrap();
        for (i, t) in [9.5, 0.5, 3.5, 4.0, 100.0, 2.0, 2.0]
            .into_iter()
            .enumerate()
        {
            q.push(t, i).unwrap();
        }
        let got: Vec<usize> = drain(&mut q).into_iter().map(|(_, p)| p).collect();
        assert_eq!(got, [1, 5, 6, 2, 3, 0, 4]);
        assert!(q.stats().wraps >= 2, "{:?}", q.stats());
    }

    #[test]
    fn layout_catches_up_with_a_queue_that_grew() {
        // Filling a queue from empty (no pops) tunes the layout for a fraction of the final
        // size at best; the first pops must notice crowded buckets and re-spread, instead of
        // running until the next wrap-around with dozens of events per bucket.
        let mut q = BoundedQueue::new();
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let n = 200_000u32;
        for i in 0..n {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let u = ((x >> 11) + 1) as f64 / (1u64 << 53) as f64;
            q.push(-u.ln(), i).unwrap();
        }
        let before = q.stats();
        for _ in 0..20_000 {
            q.pop().unwrap();
        }
        let s = q.stats();
        let per_bucket = (s.bucket_events - before.bucket_events) as f64
            / (s.buckets_consumed - before.buckets_consumed) as f64;
        assert!(
            per_bucket < 2.0 * DEFAULT_EVENTS_PER_BUCKET,
            "{per_bucket} per bucket, {s:?}"
        );
    }

    #[test]
    fn blocks_are_dealt_in_order() {
        // 2^14 buckets of width 1: four blocks of 4096; times spread over all of them.
        let mut q = BoundedQueue::with_tuning(Tuning::Fixed(Layout {
            width: 1.0,
            buckets: 1 << 14,
        }))
        .unwrap();
        let n = 50_000u64;
        for i in 0..n {
            // A permutation of 0..n scaled into [0, 16384): every block gets events.
            let k = (i * 7_919) % n;
            q.push(k as f64 * 16_384.0 / n as f64, k).unwrap();
        }
        let got = drain(&mut q);
        assert_eq!(got.len(), n as usize);
        assert!(got.iter().enumerate().all(|(i, &(_, k))| k == i as u64));
        let s = q.stats();
        assert!(s.block_moves > 3 * n / 4 - 100, "{s:?}");
        assert_eq!(q.layout().buckets, 1 << 14);
    }

    #[test]
    fn refuses_bad_layouts() {
        let bad = |width, buckets| {
            BoundedQueue::<()>::with_tuning(Tuning::Fixed(Layout { width, buckets })).is_err()
        };
        assert!(bad(0.0, 8) && bad(-1.0, 8) && bad(f64::NAN, 8) && bad(f64::INFINITY, 8));
        assert!(
            bad(f64::from_bits(1), 8),
            "a subnormal width has an infinite reciprocal"
        );
        assert!(bad(1.0, 0) && bad(1.0, (1 << 28) + 1));
        for e in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let t = Tuning::Auto {
                events_per_bucket: e,
            };
            assert!(BoundedQueue::<()>::with_tuning(t).is_err());
        }
    }

    #[test]
    fn auto_tuning_follows_the_time_scale() {
        for scale in [1e-9, 1.0, 1e9] {
            let mut q = BoundedQueue::new();
            for i in 0..10_000u32 {
                q.push(f64::from(i) * scale, i).unwrap();
            }
            // Draining forces wrap-arounds that measure the density: ~2 events per bucket.
            let mut last = f64::NEG_INFINITY;
            for _ in 0..5_000 {
                let e = q.pop().unwrap();
                assert!(e.time >= last);
                last = e.time;
            }
            let w = q.layout().width / scale;
            assert!(
                (1.0..=4.0).contains(&w),
                "width/scale = {w} at scale {scale}"
            );
        }
    }

    #[test]
    fn respread_with_minus_infinity_and_earlier_times_in_the_heap() {
        let mut q = BoundedQueue::new();
        q.push(f64::NEG_INFINITY, u32::MAX).unwrap();
        q.push(f64::INFINITY, u32::MAX - 1).unwrap();
        // Far more events than the first layout's heap limit, all in its first bucket.
        for i in 0..5_000u32 {
            q.push(1e-6 * f64::from(i % 1000), i).unwrap();
        }
        assert!(q.stats().respreads > 0);
        let got = drain(&mut q);
        assert_eq!(got.len(), 5_002);
        assert_eq!(got[0], (f64::NEG_INFINITY, u32::MAX));
        assert_eq!(got[5_001], (f64::INFINITY, u32::MAX - 1));
        assert!(got.windows(2).all(|w| w[0].0 <= w[1].0));
        // Equal times keep their arrival order.
        assert!(
            got.windows(2)
                .filter(|w| w[0].0 == w[1].0 && w[0].0.is_finite())
                .all(|w| w[0].1 < w[1].1)
        );
    }

    #[test]
    fn retain_across_heap_buckets_and_overflow() {
        let mut q = BoundedQueue::with_tuning(Tuning::Fixed(Layout {
            width: 1.0,
            buckets: 8,
        }))
        .unwrap();
        for i in 0..100u32 {
            q.push(f64::from(i) * 0.25, i).unwrap();
        }
        assert_eq!(q.retain(&mut |p| p % 2 == 0), 50);
        assert_eq!(q.len(), 50);
        let got: Vec<u32> = drain(&mut q).into_iter().map(|(_, p)| p).collect();
        assert_eq!(got, (0..100).step_by(2).collect::<Vec<_>>());
        // Removing everything in the heap must move on to the next bucket.
        for i in 0..20u32 {
            q.push(f64::from(i), i).unwrap();
        }
        q.retain(&mut |p| *p >= 5);
        assert_eq!(q.peek_time(), Some(5.0));
    }
}
