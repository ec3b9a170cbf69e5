//! Priority queues of timed events for discrete-event simulators.
//!
//! A discrete-event simulator keeps its pending events in a priority queue keyed by time, pops
//! the earliest, executes it, and schedules what follows. This crate provides:
//!
//! - [`EventQueue`], the small trait such a queue implements;
//! - [`HeapQueue`], a binary heap (O(log n), the baseline);
//! - [`BoundedQueue`], G. Paul's bounded priority queue (O(1): buckets of width Δ over a time
//!   window, a small heap for the bucket being consumed, an overflow list, automatic tuning);
//! - lazy invalidation: a [`StampBook`] of per-participant generation counters and the
//!   [`Ticket`] an event carries, so that events made obsolete by an earlier event are recognised
//!   and dropped when popped instead of being searched for and cancelled; [`LazyQueue`] puts a
//!   queue and a book together the way an event loop uses them;
//! - [`Calendar`], an indexed calendar queue with one pending time per participant: buckets
//!   linked through the participants' records, so a change of time is O(1) with nothing stale;
//! - [`TournamentTree`], a complete binary tree with one leaf per participant, for schedulers
//!   that keep exactly one event per participant (no stale events at all);
//! - [`hold`], the classic hold model that benchmarks a queue (and a `std` heap adapter).
//!
//! Every queue pops in the same total order: by time, then first-in, first-out among equal
//! times. NaN times are refused with [`QueueError::NanTime`]; `±∞` are accepted (`+∞` pops after
//! every finite time, `−∞` before). A time earlier than the last one popped is accepted and pops
//! next: simulators produce such times by round-off.
//!
//! ```
//! use event_queue::{EventQueue, HeapQueue, StampBook};
//!
//! // Two participants; an event between them, and one for participant 1 alone.
//! let mut book = StampBook::new(2);
//! let mut queue = HeapQueue::new();
//! queue.push(1.5, book.ticket2(0, 1))?;
//! queue.push(0.5, book.ticket1(1))?;
//!
//! // The earlier event happens and changes participant 1: its other events become stale.
//! let first = queue.pop().unwrap();
//! assert_eq!(first.time, 0.5);
//! book.invalidate(1);
//! let second = queue.pop().unwrap();
//! assert!(!second.payload.is_current(&book)); // dropped without ever searching the queue
//! # Ok::<(), event_queue::QueueError>(())
//! ```

mod bounded;
mod calendar;
mod heap;
pub mod hold;
mod lazy;
mod order;
mod stamp;
mod tournament;

pub use bounded::{BoundedQueue, BoundedStats, DEFAULT_EVENTS_PER_BUCKET, Layout, Tuning};
pub use calendar::{CALENDAR_EVENTS_PER_BUCKET, Calendar};
pub use heap::HeapQueue;
pub use lazy::{Cleanup, LazyQueue, LazyStats};
pub use stamp::{ParticipantId, Stamp, StampBook, Stamped, Ticket};
pub use tournament::TournamentTree;

use order::Entry;

/// An event taken out of a queue.
#[derive(Clone, Debug, PartialEq)]
pub struct Event<P> {
    /// When it happens.
    pub time: f64,
    /// What the simulator attached to it.
    pub payload: P,
}

impl<P> From<Entry<P>> for Event<P> {
    #[inline]
    fn from(e: Entry<P>) -> Self {
        Event {
            time: e.time,
            payload: e.payload,
        }
    }
}

/// A priority queue of timed events with a payload.
///
/// Implementations pop in the crate's total order (time, then first-in, first-out) and never
/// search for an event: cancellation is left to lazy invalidation (see [`StampBook`]).
pub trait EventQueue {
    /// What an event carries.
    type Payload;

    /// Schedules `payload` at `time`.
    ///
    /// # Errors
    /// [`QueueError::NanTime`] if `time` is NaN; the queue is left unchanged.
    fn push(&mut self, time: f64, payload: Self::Payload) -> Result<(), QueueError>;

    /// Removes and returns the earliest event, stale or not.
    fn pop(&mut self) -> Option<Event<Self::Payload>>;

    /// The earliest event, without removing it.
    fn peek(&self) -> Option<(f64, &Self::Payload)>;

    /// The time of the earliest event.
    fn peek_time(&self) -> Option<f64> {
        self.peek().map(|(t, _)| t)
    }

    /// Number of events held, stale ones included.
    fn len(&self) -> usize;

    /// Whether the queue holds no event.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Removes every event.
    fn clear(&mut self);

    /// Keeps only the events whose payload passes `keep` (the bulk clean-up of stale events);
    /// returns how many were removed. O(n).
    fn retain(&mut self, keep: &mut dyn FnMut(&Self::Payload) -> bool) -> usize;
}

/// Why a queue refused an operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QueueError {
    /// An event time was NaN, which has no place in a time order.
    NanTime,
    /// A queue was configured with parameters it cannot work with; the text says which.
    InvalidLayout(&'static str),
}

impl std::fmt::Display for QueueError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            QueueError::NanTime => f.write_str("event time is NaN; it cannot be scheduled"),
            QueueError::InvalidLayout(why) => write!(f, "invalid queue layout: {why}"),
        }
    }
}

impl std::error::Error for QueueError {}

#[inline(always)]
fn check_time(time: f64) -> Result<(), QueueError> {
    if time.is_nan() {
        Err(QueueError::NanTime)
    } else {
        Ok(())
    }
}
