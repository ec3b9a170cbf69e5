//! The one total order every queue in this crate pops in.
//!
//! Events are ordered by time, compared with IEEE `<` (so `-0.0` and `+0.0` are the same time),
//! and then by the sequence number the queue gave them when they were pushed. The sequence makes
//! equal times pop first-in, first-out, so a run is reproducible whatever the queue, and it is
//! why two implementations can be checked against each other event by event. NaN never enters
//! a queue (push rejects it), which is what makes the order total.

/// An event as stored: when, in which order it arrived, and what it carries.
#[derive(Clone, Debug)]
pub(crate) struct Entry<P> {
    pub(crate) time: f64,
    pub(crate) seq: u64,
    pub(crate) payload: P,
}

impl<P> Entry<P> {
    /// Whether `self` pops strictly before `other`.
    #[inline(always)]
    pub(crate) fn before(&self, other: &Self) -> bool {
        self.time < other.time || (self.time == other.time && self.seq < other.seq)
    }
}
