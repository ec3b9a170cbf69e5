//! Events: what each body has predicted, kept in its own short list.
//!
//! Every body owns a list of the events it predicted at its last change (one per partner it
//! will meet, plus the time it leaves its neighbour-list skin). The global queue holds only each body's earliest
//! event (see [`schedule`](crate::engine::schedule)), so a collision pushes two entries into the queue,
//! not one per predicted pair, and the queue stays at N entries.
//!
//! Validity is lazy at both levels. A list entry records the generation of its partner; a
//! body's generation is bumped whenever its velocity changes, and an entry whose partner has
//! moved on is dropped when it reaches the front of its list. A body's own change clears its
//! list. Nothing is ever searched for to be cancelled.
//!
//! Rigid bodies add one kind, [`Kind::Virtual`] (000 §III.B, 003 §V.A): a root search that
//! reached the end of its window without finding the pair's next event. The saved search state
//! stays with the interaction model (keyed by the owner and the partner, see
//! the `terraced` model), so the entry keeps its 16 bytes; when the event comes due and
//! is still current, the model resumes the search from it.

/// Which boundary of its current level a pair event is for.
///
/// For stepped radial potentials the boundaries are radii. For terraced potentials of rigid
/// bodies (003 Eq. 7) they are the two levels around the pair's terrace: `Inner` is the level
/// above (`U` rising towards the hard core, terrace `k → k + 1`), `Outer` the level below
/// (`k → k − 1`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boundary {
    /// The inner boundary (a hard core, or the next step inwards; the level above a terrace).
    Inner,
    /// The outer boundary (leaving the level outwards; the level below a terrace).
    Outer,
}

/// What a body's event is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// The pair (owner, partner) reaches a boundary of its level.
    Pair(Boundary),
    /// The owner leaves the skin sphere around its neighbour-list centre: it rebuilds its
    /// list (see [`neighbour`](crate::engine::neighbour)).
    Shell,
    /// The root search of the pair (owner, partner) reached the end of its window, or the pair
    /// reaches the bracket where a search must start: resume (or start) it then.
    Virtual,
}

/// One predicted event in a body's list (16 bytes): its time, and a tag packing the kind with
/// the partner and the partner's generation when the event was predicted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    /// When it happens (in the current time frame).
    pub time: f64,
    /// Kind in the top 3 bits, partner in the low 27 (see [`neighbour::MAX_BODIES`](crate::engine::neighbour::MAX_BODIES)).
    tag: u32,
    /// The partner's generation at prediction.
    generation: u32,
}

const PARTNER_BITS: u32 = 27;
const PARTNER_MASK: u32 = (1 << PARTNER_BITS) - 1;
const INNER: u32 = 0;
const OUTER: u32 = 1;
const SHELL: u32 = 2;
const VIRTUAL: u32 = 3;

impl Event {
    /// A pair event with `partner` (at generation `generation`) at `boundary`.
    #[inline(always)]
    pub fn pair(time: f64, partner: u32, generation: u32, boundary: Boundary) -> Self {
        let kind = match boundary {
            Boundary::Inner => INNER,
            Boundary::Outer => OUTER,
        };
        Event {
            time,
            tag: (kind << PARTNER_BITS) | partner,
            generation,
        }
    }

    /// A pair event (`Kind::Pair`) or a virtual event (`Kind::Virtual`) with `partner` (at
    /// generation `generation`).
    ///
    /// # Panics
    /// For `Kind::Shell`, which has no partner (a bug of the caller).
    #[inline(always)]
    pub fn with_partner(time: f64, partner: u32, generation: u32, kind: Kind) -> Self {
        let kind = match kind {
            Kind::Pair(Boundary::Inner) => INNER,
            Kind::Pair(Boundary::Outer) => OUTER,
            Kind::Virtual => VIRTUAL,
            Kind::Shell => panic!("a shell crossing has no partner"),
        };
        Event {
            time,
            tag: (kind << PARTNER_BITS) | partner,
            generation,
        }
    }

    /// A shell crossing.
    #[inline(always)]
    pub fn shell(time: f64) -> Self {
        Event {
            time,
            tag: SHELL << PARTNER_BITS,
            generation: 0,
        }
    }

    /// What happens.
    #[inline(always)]
    pub fn kind(&self) -> Kind {
        match self.tag >> PARTNER_BITS {
            INNER => Kind::Pair(Boundary::Inner),
            OUTER => Kind::Pair(Boundary::Outer),
            VIRTUAL => Kind::Virtual,
            _ => Kind::Shell,
        }
    }

    /// The partner of a pair event.
    #[inline(always)]
    pub fn partner(&self) -> Option<u32> {
        (self.tag >> PARTNER_BITS != SHELL).then_some(self.tag & PARTNER_MASK)
    }

    /// Whether the event is still valid: a shell crossing always, a pair event while its
    /// partner is at the generation it was predicted with.
    #[inline(always)]
    pub fn is_current(&self, bodies: &[crate::engine::body::Body]) -> bool {
        match self.partner() {
            None => true,
            Some(j) => bodies[j as usize].generation == self.generation,
        }
    }
}

/// Events that belong to the system as a whole (the queue's extra participant).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SystemEvent {
    /// Sample the observables.
    Sample,
    /// Write a trajectory frame of the given stream.
    Frame(usize),
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
    tag: SHELL << PARTNER_BITS,
    generation: 0,
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

    /// Asks for the first line of body `i`'s list ahead of use. Its place is known without
    /// its length, so nothing waits for a load.
    #[inline(always)]
    pub fn prefetch(&self, i: u32) {
        memory_hints::prefetch(&self.events[i as usize * self.cap]);
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
    /// predicted with, dropping stale ones on the way; its index in the list.
    #[inline]
    pub fn earliest(
        &mut self,
        i: u32,
        bodies: &[crate::engine::body::Body],
    ) -> Option<(usize, Event)> {
        loop {
            let list = self.of(i);
            let first = list.first()?;
            // The first of the smallest times (index and time only: the entry is read once,
            // after the scan).
            let (mut k, mut t) = (0, first.time);
            for (m, e) in list.iter().enumerate().skip(1) {
                if e.time < t {
                    (k, t) = (m, e.time);
                }
            }
            let e = list[k];
            if e.is_current(bodies) {
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
    use crate::engine::body::Body;
    use glam::DVec3;

    fn bodies(n: usize) -> Vec<Body> {
        vec![
            Body {
                r: DVec3::ZERO,
                t: 0.0,
                v: DVec3::ZERO,
                species: 0,
                generation: 0,
            };
            n
        ]
    }

    #[test]
    fn entries_are_small_and_round_trip() {
        assert_eq!(std::mem::size_of::<Event>(), 16);
        let e = Event::pair(1.5, (1 << 27) - 1, u32::MAX, Boundary::Outer);
        assert_eq!(e.partner(), Some((1 << 27) - 1));
        assert_eq!(e.kind(), Kind::Pair(Boundary::Outer));
        let e = Event::pair(1.5, 0, 3, Boundary::Inner);
        assert_eq!(
            (e.partner(), e.kind()),
            (Some(0), Kind::Pair(Boundary::Inner))
        );
        let s = Event::shell(2.0);
        assert_eq!((s.partner(), s.kind()), (None, Kind::Shell));
        let v = Event::with_partner(0.5, 12, 9, Kind::Virtual);
        assert_eq!((v.partner(), v.kind()), (Some(12), Kind::Virtual));
        let p = Event::with_partner(0.5, 12, 9, Kind::Pair(Boundary::Outer));
        assert_eq!(p, Event::pair(0.5, 12, 9, Boundary::Outer));
    }

    #[test]
    fn earliest_skips_stale_partners_and_lists_grow() {
        let mut l = EventLists::new(3);
        let mut b = bodies(3);
        for k in 0..20 {
            l.push(0, Event::pair(10.0 + f64::from(k), 2, 0, Boundary::Inner));
        }
        l.push(0, Event::pair(3.0, 1, 0, Boundary::Inner));
        l.push(0, Event::shell(5.0));
        assert!(l.capacity() >= 22);
        assert_eq!(l.earliest(0, &b).unwrap().1.time, 3.0);
        b[1].generation = 1; // partner 1 changed: its event is stale
        let (k, e) = l.earliest(0, &b).unwrap();
        assert_eq!(e.time, 5.0);
        assert_eq!(l.of(0).len(), 21);
        l.remove(0, k);
        b[2].generation = 7;
        assert!(l.earliest(0, &b).is_none());
        assert!(l.of(0).is_empty());
        l.push(1, Event::pair(1.0, 0, 0, Boundary::Outer));
        assert_eq!(l.of(1)[0].time, 1.0);
        l.clear(1);
        assert!(l.of(1).is_empty());
    }
}
