//! The global schedule: each body's earliest event, and one slot for the system's.
//!
//! A [`Scheduler`] holds at most one pending time per participant (body or system) and hands
//! out the earliest. Setting a participant's time replaces its previous one. Two kinds
//! implement it, chosen once per scene (`run.queue`):
//!
//! - [`LazyQueue`] over a [`BoundedQueue`](event_queue::BoundedQueue) (G. Paul's O(1) queue,
//!   the default) or a [`HeapQueue`](event_queue::HeapQueue): a new time is pushed with a fresh
//!   ticket and the participant's previous entry becomes stale through its generation stamp —
//!   lazy invalidation, never a search. Both queues pop in one total order (time, then first
//!   in, first out), so a run is bit-identical on either.
//! - [`Calendar`]: one entry per participant in buckets linked through the participants'
//!   records, moved in O(1) when its time changes (no stale entries); ties go to the lower
//!   index, as in the tree.
//! - [`TournamentTree`]: one leaf per participant, updated in place (no stale entries); ties go
//!   to the lower index, so its order can differ from the queues' only between events at
//!   exactly the same time.

use event_queue::{Calendar, EventQueue, LazyQueue, QueueError, Ticket, TournamentTree};

/// One pending time per participant; the earliest comes out first.
pub trait Scheduler {
    /// A schedule for participants `0..n`, none with a pending time.
    fn with_participants(n: usize) -> Self;

    /// Sets participant `p`'s pending time, replacing any previous one (`+∞`: none).
    ///
    /// # Errors
    /// [`QueueError::NanTime`] for a NaN time.
    fn set(&mut self, p: u32, time: f64) -> Result<(), QueueError>;

    /// Removes and returns the earliest pending time and its participant.
    fn next(&mut self) -> Option<(u32, f64)>;

    /// The participant that [`next`](Self::next) would return now (stale queue entries in
    /// front of it are dropped).
    fn peek(&mut self) -> Option<u32>;

    /// Entries held (stale ones included, for queues).
    fn held(&self) -> usize;

    /// Entries pushed, stale entries dropped on pop, stale entries swept (queues only).
    fn stats(&self) -> (u64, u64, u64) {
        (0, 0, 0)
    }
}

impl<Q> Scheduler for LazyQueue<Q>
where
    Q: EventQueue<Payload = Ticket> + Default,
{
    fn with_participants(n: usize) -> Self {
        LazyQueue::new(Q::default(), n)
    }

    #[inline(always)]
    fn set(&mut self, p: u32, time: f64) -> Result<(), QueueError> {
        if time.is_nan() {
            return Err(QueueError::NanTime);
        }
        self.invalidate(p);
        if time < f64::INFINITY {
            let ticket = self.book().ticket1(p);
            self.schedule(time, ticket)?;
        }
        Ok(())
    }

    #[inline(always)]
    fn next(&mut self) -> Option<(u32, f64)> {
        self.pop().map(|e| (e.payload.first(), e.time))
    }

    #[inline(always)]
    fn peek(&mut self) -> Option<u32> {
        LazyQueue::peek(self).map(|(_, t)| t.first())
    }

    fn held(&self) -> usize {
        self.len()
    }

    fn stats(&self) -> (u64, u64, u64) {
        let s = LazyQueue::stats(self);
        (s.scheduled, s.dropped_stale, s.swept)
    }
}

impl Scheduler for TournamentTree {
    fn with_participants(n: usize) -> Self {
        TournamentTree::new(n)
    }

    #[inline(always)]
    fn set(&mut self, p: u32, time: f64) -> Result<(), QueueError> {
        TournamentTree::set(self, p as usize, time)
    }

    #[inline(always)]
    fn next(&mut self) -> Option<(u32, f64)> {
        let (p, t) = self.min()?;
        if t == f64::INFINITY {
            return None;
        }
        TournamentTree::set(self, p, f64::INFINITY).expect("+∞ is a valid time");
        Some((p as u32, t))
    }

    #[inline(always)]
    fn peek(&mut self) -> Option<u32> {
        self.min()
            .filter(|&(_, t)| t < f64::INFINITY)
            .map(|(p, _)| p as u32)
    }

    fn held(&self) -> usize {
        self.len()
    }
}

impl Scheduler for Calendar {
    fn with_participants(n: usize) -> Self {
        Calendar::new(n)
    }

    #[inline(always)]
    fn set(&mut self, p: u32, time: f64) -> Result<(), QueueError> {
        Calendar::set(self, p as usize, time)
    }

    #[inline(always)]
    fn next(&mut self) -> Option<(u32, f64)> {
        self.pop().map(|(p, t)| (p as u32, t))
    }

    #[inline(always)]
    fn peek(&mut self) -> Option<u32> {
        Calendar::peek(self).map(|(p, _)| p as u32)
    }

    fn held(&self) -> usize {
        self.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use event_queue::{BoundedQueue, HeapQueue};

    fn exercise<S: Scheduler>() -> Vec<(u32, f64)> {
        let mut s = S::with_participants(4);
        s.set(0, 5.0).unwrap();
        s.set(1, 2.0).unwrap();
        s.set(2, 7.0).unwrap();
        s.set(1, 6.0).unwrap(); // replaces 2.0
        s.set(3, 1.0).unwrap();
        s.set(3, f64::INFINITY).unwrap(); // withdrawn
        assert!(s.set(2, f64::NAN).is_err());
        assert_eq!(s.peek(), Some(0));
        std::iter::from_fn(|| s.next()).collect()
    }

    #[test]
    fn every_scheduler_replaces_and_orders() {
        let expect = vec![(0, 5.0), (1, 6.0), (2, 7.0)];
        assert_eq!(exercise::<LazyQueue<BoundedQueue<Ticket>>>(), expect);
        assert_eq!(exercise::<LazyQueue<HeapQueue<Ticket>>>(), expect);
        assert_eq!(exercise::<TournamentTree>(), expect);
        assert_eq!(exercise::<Calendar>(), expect);
    }
}
