//! Generation stamps for lazy invalidation; the user-facing description is on [`StampBook`].

/// The generation of one participant at some moment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Stamp(u32);

/// Index of a participant in a [`StampBook`].
pub type ParticipantId = u32;

/// One generation counter per participant: lazy invalidation without searching the queue.
///
/// Every participant (a body, a cell, a machine …) has a generation counter. An event records
/// the counters of its participants when it is scheduled, in a [`Ticket`]. Whenever something
/// happens to a participant that makes its pending events obsolete, the simulator calls
/// [`StampBook::invalidate`], which bumps the counter. A popped event whose ticket no longer
/// matches the book is stale and is simply dropped. Nothing ever has to find an event inside the
/// queue to cancel it (seed 003 §V.A measured this at ~15 % less total run time).
///
/// The scheme needs no queue: a `StampBook` and [`Ticket`]s work with any container;
/// [`LazyQueue`](crate::LazyQueue) is the ready-made combination.
///
/// Counters are `u32` and wrap. A stale ticket could only be mistaken for a current one if its
/// participant were invalidated a multiple of 2³² times while the ticket waited in the queue.
/// `LazyQueue` rules that out by sweeping stale events at least once every 2³¹ invalidations;
/// users of a bare `StampBook` get [`StampBook::invalidations`] to do the same.
#[derive(Clone, Debug, Default)]
pub struct StampBook {
    stamps: Vec<u32>,
    invalidations: u64,
}

impl StampBook {
    /// A book for participants `0..n`, all at generation zero.
    pub fn new(n: usize) -> Self {
        assert!(
            n < ParticipantId::MAX as usize,
            "at most {} participants can be stamped",
            ParticipantId::MAX - 1
        );
        Self {
            stamps: vec![0; n],
            invalidations: 0,
        }
    }

    /// Adds a participant and returns its id.
    pub fn add(&mut self) -> ParticipantId {
        let id = self.stamps.len();
        assert!(
            id < (ParticipantId::MAX - 1) as usize,
            "participant ids are exhausted"
        );
        self.stamps.push(0);
        id as ParticipantId
    }

    /// Number of participants.
    pub fn len(&self) -> usize {
        self.stamps.len()
    }

    /// Whether the book has no participants.
    pub fn is_empty(&self) -> bool {
        self.stamps.is_empty()
    }

    /// The current generation of `id`.
    ///
    /// # Panics
    /// If `id` is not a participant of this book.
    #[inline]
    pub fn current(&self, id: ParticipantId) -> Stamp {
        Stamp(self.stamps[id as usize])
    }

    /// Whether `stamp` is still the current generation of `id`.
    #[inline]
    pub fn is_current(&self, id: ParticipantId, stamp: Stamp) -> bool {
        self.stamps[id as usize] == stamp.0
    }

    /// Makes every event scheduled so far for `id` stale.
    #[inline]
    pub fn invalidate(&mut self, id: ParticipantId) {
        let s = &mut self.stamps[id as usize];
        *s = s.wrapping_add(1);
        self.invalidations += 1;
    }

    /// Total number of [`invalidate`](Self::invalidate) calls since the book was made.
    pub fn invalidations(&self) -> u64 {
        self.invalidations
    }

    /// A ticket for an event with one participant.
    #[inline]
    pub fn ticket1(&self, a: ParticipantId) -> Ticket {
        Ticket {
            ids: [a, NOBODY],
            stamps: [self.stamps[a as usize], 0],
        }
    }

    /// A ticket for an event with two participants (`a` may equal `b`).
    #[inline]
    pub fn ticket2(&self, a: ParticipantId, b: ParticipantId) -> Ticket {
        Ticket {
            ids: [a, b],
            stamps: [self.stamps[a as usize], self.stamps[b as usize]],
        }
    }
}

/// Marks the unused second slot of a one-participant ticket.
const NOBODY: ParticipantId = ParticipantId::MAX;

/// The stamps of an event's one or two participants at the time it was scheduled (16 bytes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Ticket {
    ids: [ParticipantId; 2],
    stamps: [u32; 2],
}

impl Ticket {
    /// The first participant.
    pub fn first(&self) -> ParticipantId {
        self.ids[0]
    }

    /// The second participant, if the event has two.
    pub fn second(&self) -> Option<ParticipantId> {
        (self.ids[1] != NOBODY).then_some(self.ids[1])
    }

    /// Whether no participant has been invalidated since the ticket was issued.
    #[inline]
    pub fn is_current(&self, book: &StampBook) -> bool {
        book.stamps[self.ids[0] as usize] == self.stamps[0]
            && (self.ids[1] == NOBODY || book.stamps[self.ids[1] as usize] == self.stamps[1])
    }
}

/// A payload that can tell whether it is still current.
///
/// Implement it for your event type by delegating to the [`Ticket`] it carries; [`Ticket`]
/// itself implements it, so a bare ticket works as a payload.
pub trait Stamped {
    /// Whether the event is still valid according to `book`.
    fn is_current(&self, book: &StampBook) -> bool;
}

impl Stamped for Ticket {
    #[inline]
    fn is_current(&self, book: &StampBook) -> bool {
        Ticket::is_current(self, book)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalidation_makes_tickets_stale_for_that_participant_only() {
        let mut book = StampBook::new(3);
        let t01 = book.ticket2(0, 1);
        let t2 = book.ticket1(2);
        assert!(t01.is_current(&book) && t2.is_current(&book));
        book.invalidate(1);
        assert!(!t01.is_current(&book));
        assert!(t2.is_current(&book));
        let fresh = book.ticket2(0, 1);
        assert!(fresh.is_current(&book));
        assert_eq!(fresh.second(), Some(1));
        assert_eq!(t2.second(), None);
        assert_eq!(book.invalidations(), 1);
    }

    #[test]
    fn self_pair_and_added_participants() {
        let mut book = StampBook::new(0);
        assert!(book.is_empty());
        let a = book.add();
        let t = book.ticket2(a, a);
        assert!(t.is_current(&book));
        book.invalidate(a);
        assert!(!t.is_current(&book));
        assert_eq!(book.len(), 1);
    }

    #[test]
    fn counters_wrap_instead_of_overflowing() {
        let mut book = StampBook::new(1);
        book.stamps[0] = u32::MAX;
        let t = book.ticket1(0);
        book.invalidate(0);
        assert_eq!(book.current(0), Stamp(0));
        assert!(!t.is_current(&book));
    }
}
