//! What the queue holds: event payloads with their lazy-invalidation tickets.
//!
//! A payload is a [`Ticket`] (the participants and their generation stamps when the event was
//! predicted) and a [`Kind`]. Pair events name the boundary they are for; cell crossings the
//! face; system events (sampling, thermostat, end of run) belong to one extra participant, the
//! "system", which is invalidated only when the whole schedule is rebuilt. The payload is 20
//! bytes, so a queue entry (time, sequence number, payload) is 40.
//!
//! Rigid bodies (issue 7) add one variant: `Virtual { slot }`, a root search that reached the
//! end of its window without finding the pair's next event; `slot` indexes the saved search
//! state in the pair's stored entry, and when the event comes due the search resumes from it.

use event_queue::{StampBook, Stamped, Ticket};

/// Which boundary of its current level a pair event is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// The inner boundary (a hard core, or the next step inwards).
    Inner,
    /// The outer boundary (leaving the level outwards).
    Outer,
}

/// Events that belong to the system as a whole.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SystemEvent {
    /// Sample the observables.
    Sample,
    /// Write a trajectory frame.
    Frame,
    /// An Andersen thermostat collision.
    Thermostat,
    /// The end of the current phase (a run length given in time).
    End,
}

/// What an event is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Pair `(ticket.first, ticket.second)` reaches a boundary of its level.
    Pair(Boundary),
    /// Body `ticket.first` leaves its cell through face `axis` (0, 1, 2), upwards if `up`.
    Cell {
        /// Axis of the face.
        axis: u8,
        /// Whether the body moves towards larger coordinates.
        up: bool,
    },
    /// A system event.
    System(SystemEvent),
}

/// A queued event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Event {
    /// Participants and their stamps at prediction time.
    pub ticket: Ticket,
    /// What happens.
    pub kind: Kind,
}

impl Stamped for Event {
    #[inline(always)]
    fn is_current(&self, book: &StampBook) -> bool {
        self.ticket.is_current(book)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payload_is_small() {
        assert!(std::mem::size_of::<Event>() <= 20);
    }
}
