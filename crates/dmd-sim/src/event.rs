//! Events: what each body has predicted, kept in its own short list.
//!
//! Every body owns a list of the events it predicted at its last change (one per partner it
//! will meet, plus the time it leaves its neighbour-list skin). The global queue holds only each body's earliest
//! event (see [`schedule`](crate::schedule)), so a collision pushes two entries into the queue,
//! not one per predicted pair, and the queue stays at N entries.
//!
//! Validity is lazy at both levels. A list entry records the generation of its partner; a
//! body's generation is bumped whenever its velocity changes, and an entry whose partner has
//! moved on is dropped when it reaches the front of its list. A body's own change clears its
//! list. Nothing is ever searched for to be cancelled.
//!
//! Rigid bodies (issue 7) add one kind: `Virtual { slot }`, a root search that reached the end
//! of its window without finding the pair's next event; `slot` indexes the saved search state
//! in the pair's stored entry, and when the event comes due the search resumes from it.

/// Which boundary of its current level a pair event is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// The inner boundary (a hard core, or the next step inwards).
    Inner,
    /// The outer boundary (leaving the level outwards).
    Outer,
}

/// What a body's event is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// The pair (owner, partner) reaches a boundary of its level.
    Pair(Boundary),
    /// The owner leaves the skin sphere around its neighbour-list centre: it rebuilds its
    /// list (see [`neighbour`](crate::neighbour)).
    Shell,
}

/// No partner (shell crossings).
pub const NOBODY: u32 = u32::MAX;

/// One predicted event in a body's list (24 bytes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    /// When it happens (in the current time frame).
    pub time: f64,
    /// The partner's generation when the event was predicted.
    pub partner_gen: u64,
    /// The partner ([`NOBODY`] for a shell crossing).
    pub partner: u32,
    /// What happens.
    pub kind: Kind,
}

/// Events that belong to the system as a whole (the queue's extra participant).
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

/// The event lists of all bodies, in fixed-stride storage (body `i`'s events are
/// `events[i·cap .. i·cap + len[i]]`); the stride doubles when a list overflows.
#[derive(Clone, Debug)]
pub struct EventLists {
    cap: usize,
    len: Vec<u32>,
    events: Vec<Event>,
}

const EMPTY: Event = Event {
    time: f64::INFINITY,
    partner_gen: 0,
    partner: NOBODY,
    kind: Kind::Shell,
};

impl EventLists {
    /// Empty lists for `n` bodies.
    pub fn new(n: usize) -> Self {
        let cap = 8;
        EventLists {
            cap,
            len: vec![0; n],
            events: vec![EMPTY; n * cap],
        }
    }

    /// Body `i`'s events.
    #[inline(always)]
    pub fn of(&self, i: u32) -> &[Event] {
        let base = i as usize * self.cap;
        &self.events[base..base + self.len[i as usize] as usize]
    }

    /// Empties body `i`'s list.
    #[inline(always)]
    pub fn clear(&mut self, i: u32) {
        self.len[i as usize] = 0;
    }

    /// Adds an event to body `i`'s list.
    #[inline(always)]
    pub fn push(&mut self, i: u32, e: Event) {
        let n = self.len[i as usize] as usize;
        if n == self.cap {
            self.grow();
        }
        self.events[i as usize * self.cap + n] = e;
        self.len[i as usize] += 1;
    }

    /// Removes entry `k` of body `i`'s list (the last entry takes its place).
    #[inline(always)]
    pub fn remove(&mut self, i: u32, k: usize) {
        let base = i as usize * self.cap;
        let last = self.len[i as usize] as usize - 1;
        self.events[base + k] = self.events[base + last];
        self.len[i as usize] -= 1;
    }

    /// The earliest event of body `i` whose partner is still at the generation it was
    /// predicted with (`gens`), dropping stale ones on the way; its index in the list.
    #[inline]
    pub fn earliest(&mut self, i: u32, gens: &[u64]) -> Option<(usize, Event)> {
        loop {
            let mut best: Option<(usize, Event)> = None;
            for (k, e) in self.of(i).iter().enumerate() {
                if best.is_none_or(|(_, b)| e.time < b.time) {
                    best = Some((k, *e));
                }
            }
            let (k, e) = best?;
            if e.partner == NOBODY || gens[e.partner as usize] == e.partner_gen {
                return Some((k, e));
            }
            self.remove(i, k);
        }
    }

    /// Slots per body (grows on overflow).
    pub fn capacity(&self) -> usize {
        self.cap
    }

    #[cold]
    fn grow(&mut self) {
        let cap = self.cap * 2;
        let n = self.len.len();
        let mut events = vec![EMPTY; n * cap];
        for i in 0..n {
            let len = self.len[i] as usize;
            events[i * cap..i * cap + len]
                .copy_from_slice(&self.events[i * self.cap..i * self.cap + len]);
        }
        self.events = events;
        self.cap = cap;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(time: f64, partner: u32, partner_gen: u64) -> Event {
        Event {
            time,
            partner_gen,
            partner,
            kind: Kind::Pair(Boundary::Inner),
        }
    }

    #[test]
    fn entries_are_small() {
        assert_eq!(std::mem::size_of::<Event>(), 24);
    }

    #[test]
    fn earliest_skips_stale_partners_and_lists_grow() {
        let mut l = EventLists::new(3);
        let mut gens = vec![0u64; 3];
        for k in 0..20 {
            l.push(0, ev(10.0 + f64::from(k), 2, 0));
        }
        l.push(0, ev(3.0, 1, 0));
        l.push(0, ev(5.0, NOBODY, 0));
        assert!(l.capacity() >= 22);
        assert_eq!(l.earliest(0, &gens).unwrap().1.time, 3.0);
        gens[1] = 1; // partner 1 changed: its event is stale
        let (k, e) = l.earliest(0, &gens).unwrap();
        assert_eq!(e.time, 5.0);
        assert_eq!(l.of(0).len(), 21);
        l.remove(0, k);
        gens[2] = 7;
        assert!(l.earliest(0, &gens).is_none());
        assert!(l.of(0).is_empty());
        l.push(1, ev(1.0, 0, 0));
        assert_eq!(l.of(1)[0].time, 1.0);
        l.clear(1);
        assert!(l.of(1).is_empty());
    }
}
