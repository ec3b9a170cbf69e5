//! [`LazyQueue`]: a queue and a stamp book together, the way an event loop drives them.

use crate::{Event, EventQueue, ParticipantId, QueueError, StampBook, Stamped};

/// When [`LazyQueue`] sweeps stale events out of its queue.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cleanup {
    /// Sweep when the queue holds more than `growth` times the events it held after the last
    /// sweep (≥ 1; `f64::INFINITY` never sweeps for size).
    pub growth: f64,
    /// Never sweep for size below this many events.
    pub min_len: usize,
}

impl Default for Cleanup {
    fn default() -> Self {
        Cleanup {
            growth: 4.0,
            min_len: 1024,
        }
    }
}

/// Invalidations between forced sweeps: less than the 2³² period of a wrapping `u32` stamp, so
/// a stale ticket can never come back to life (see [`StampBook`]).
/// The length above which a queue swept down to `len` is swept again: at least
/// `cleanup.min_len` and more than `cleanup.growth × len` (`len > ⌊g·l⌋` is `len > g·l` for a
/// whole `len`).
fn sweep_above(cleanup: Cleanup, len: usize) -> usize {
    let grown = (cleanup.growth * len as f64).floor();
    // A float-to-integer `as` saturates (and takes NaN to 0).
    (grown as usize).max(cleanup.min_len.saturating_sub(1))
}

const SWEEP_EVERY_INVALIDATIONS: u64 = 1 << 31;

/// What a [`LazyQueue`] has done so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LazyStats {
    /// Events scheduled.
    pub scheduled: u64,
    /// Current events handed out by [`LazyQueue::pop`].
    pub popped: u64,
    /// Stale events dropped on pop.
    pub dropped_stale: u64,
    /// Bulk sweeps performed.
    pub sweeps: u64,
    /// Stale events removed by sweeps.
    pub swept: u64,
}

/// An event queue with lazy invalidation by generation stamps.
///
/// `LazyQueue` owns a queue and a [`StampBook`]. Events are scheduled with the ticket of their
/// participants; [`LazyQueue::invalidate`] makes all pending events of a participant stale in
/// O(1); [`LazyQueue::pop`] returns the earliest event that is still current, dropping stale ones
/// on the way. Stale events are removed in bulk ("swept") only when the queue has grown to
/// [`Cleanup::growth`] times its size after the previous sweep, which costs O(1) amortised per
/// event and keeps memory bounded (seed 003 §V.A: "a relatively fast and infrequent cleanup of
/// invalid events from the lists").
///
/// This is how a simulator drives the crate: one participant per body, events carrying a
/// [`Ticket`](crate::Ticket), invalidate on every change, pop the next current event.
///
/// ```
/// use event_queue::{BoundedQueue, LazyQueue, Stamped, StampBook, Ticket};
///
/// // The simulator's own event type: what happens, and the ticket of who is involved.
/// #[derive(Debug)]
/// enum Kind { Collision { a: u32, b: u32 }, Wall { a: u32 } }
/// struct Ev { kind: Kind, ticket: Ticket }
/// impl Stamped for Ev {
///     fn is_current(&self, book: &StampBook) -> bool { self.ticket.is_current(book) }
/// }
///
/// let mut q = LazyQueue::new(BoundedQueue::new(), 3);
/// let t = q.book().ticket2(0, 1);
/// q.schedule(2.0, Ev { kind: Kind::Collision { a: 0, b: 1 }, ticket: t })?;
/// let t = q.book().ticket1(1);
/// q.schedule(1.0, Ev { kind: Kind::Wall { a: 1 }, ticket: t })?;
///
/// // Body 1 hits the wall first; its velocity changes, so its pending events are obsolete.
/// let ev = q.pop().unwrap();
/// assert!(matches!(ev.payload.kind, Kind::Wall { a: 1 }));
/// q.invalidate(1);
/// // ... the simulator would now compute and schedule body 1's new events ...
/// assert!(q.pop().is_none()); // the stale collision is dropped, never returned
/// assert_eq!(q.stats().dropped_stale, 1);
/// # Ok::<(), event_queue::QueueError>(())
/// ```
#[derive(Clone, Debug)]
pub struct LazyQueue<Q> {
    queue: Q,
    book: StampBook,
    cleanup: Cleanup,
    /// Sweep once the queue holds more than this (from the cleanup policy and the length
    /// after the last sweep).
    sweep_above: usize,
    invalidations_since_sweep: u64,
    stats: LazyStats,
}

impl<Q> LazyQueue<Q>
where
    Q: EventQueue,
    Q::Payload: Stamped,
{
    /// Wraps `queue` (normally empty) with a stamp book for participants `0..participants`.
    pub fn new(queue: Q, participants: usize) -> Self {
        Self::with_cleanup(queue, participants, Cleanup::default())
    }

    /// As [`new`](Self::new), with an explicit sweep policy.
    pub fn with_cleanup(queue: Q, participants: usize, cleanup: Cleanup) -> Self {
        let len = queue.len();
        Self {
            queue,
            book: StampBook::new(participants),
            cleanup,
            sweep_above: sweep_above(cleanup, len),
            invalidations_since_sweep: 0,
            stats: LazyStats::default(),
        }
    }

    /// The stamp book, to issue tickets.
    pub fn book(&self) -> &StampBook {
        &self.book
    }

    /// Adds a participant (a body entering the simulation) and returns its id.
    pub fn add_participant(&mut self) -> ParticipantId {
        self.book.add()
    }

    /// Schedules an event.
    ///
    /// # Errors
    /// [`QueueError::NanTime`] if `time` is NaN; nothing is scheduled.
    #[inline]
    pub fn schedule(&mut self, time: f64, payload: Q::Payload) -> Result<(), QueueError> {
        self.queue.push(time, payload)?;
        self.stats.scheduled += 1;
        if self.queue.len() > self.sweep_above
            || self.invalidations_since_sweep >= SWEEP_EVERY_INVALIDATIONS
        {
            self.sweep();
        }
        Ok(())
    }

    /// Makes every pending event of `id` stale, in O(1).
    #[inline]
    pub fn invalidate(&mut self, id: ParticipantId) {
        self.book.invalidate(id);
        self.invalidations_since_sweep += 1;
    }

    /// The earliest current event, dropping stale ones before it.
    #[inline]
    pub fn pop(&mut self) -> Option<Event<Q::Payload>> {
        while let Some(e) = self.queue.pop() {
            if e.payload.is_current(&self.book) {
                self.stats.popped += 1;
                return Some(e);
            }
            self.stats.dropped_stale += 1;
        }
        None
    }

    /// The earliest current event, without removing it (stale events before it are dropped).
    pub fn peek(&mut self) -> Option<(f64, &Q::Payload)> {
        while !self.queue.peek()?.1.is_current(&self.book) {
            self.queue.pop();
            self.stats.dropped_stale += 1;
        }
        self.queue.peek()
    }

    /// Removes every stale event now; returns how many. O(len).
    pub fn sweep(&mut self) -> usize {
        let book = &self.book;
        let removed = self.queue.retain(&mut |p| p.is_current(book));
        self.stats.sweeps += 1;
        self.stats.swept += removed as u64;
        self.sweep_above = sweep_above(self.cleanup, self.queue.len());
        self.invalidations_since_sweep = 0;
        removed
    }

    /// Events held, stale ones included.
    pub fn len(&self) -> usize {
        self.queue.len()
    }

    /// Whether no event is held at all.
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }

    /// Counters of what the queue has done.
    pub fn stats(&self) -> LazyStats {
        self.stats
    }

    /// The underlying queue (for its own statistics).
    pub fn queue(&self) -> &Q {
        &self.queue
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::HeapQueue;

    #[test]
    fn sweeps_when_grown_and_keeps_current_events() {
        let cleanup = Cleanup {
            growth: 2.0,
            min_len: 8,
        };
        let mut q = LazyQueue::with_cleanup(HeapQueue::new(), 1, cleanup);
        // Every new event for participant 0 obsoletes the previous one, as in a simulator
        // that reschedules a body after each of its events.
        for i in 0..100 {
            q.invalidate(0);
            let t = q.book().ticket1(0);
            q.schedule(f64::from(i), t).unwrap();
            assert!(q.len() <= 16, "stale events piled up: {}", q.len());
        }
        assert!(q.stats().sweeps > 0);
        assert_eq!(q.peek().map(|(t, _)| t), Some(99.0));
        let e = q.pop().unwrap();
        assert_eq!(e.time, 99.0);
        assert!(q.pop().is_none());
        let s = q.stats();
        assert_eq!(s.scheduled, 100);
        assert_eq!(s.popped, 1);
        assert_eq!(s.swept + s.dropped_stale, 99);
    }

    #[test]
    fn forced_sweep_before_stamps_could_wrap() {
        let mut q = LazyQueue::new(HeapQueue::new(), 2);
        let stale = q.book().ticket1(0);
        q.schedule(1.0, stale).unwrap();
        q.invalidate(0);
        // Pretend 2^31 invalidations happened since the last sweep.
        q.invalidations_since_sweep = SWEEP_EVERY_INVALIDATIONS;
        let t = q.book().ticket1(1);
        q.schedule(2.0, t).unwrap();
        assert_eq!(q.stats().sweeps, 1);
        assert_eq!(q.len(), 1);
    }

    #[test]
    fn nan_is_refused_and_counts_nothing() {
        let mut q = LazyQueue::new(HeapQueue::new(), 1);
        let t = q.book().ticket1(0);
        assert_eq!(q.schedule(f64::NAN, t), Err(QueueError::NanTime));
        assert_eq!(q.stats().scheduled, 0);
        assert!(q.is_empty());
    }
}
