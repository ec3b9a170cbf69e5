//! Body storage: one 64-byte record per body, state kept at the body's own clock.
//!
//! A body's position is stored at its local time `t` (its last event); its position at a later
//! time is `r + v (t' − t)`. Nothing moves the whole system per event. Everything a pair
//! prediction reads of a partner (position, clock, velocity, species, cell) sits in one
//! cache-line-aligned record, so scanning a neighbourhood costs one cache line per partner.
//! Spheres carry no orientation: rigid bodies keep theirs in their model's own
//! arrays, indexed like these records, and leave this record unchanged.

use glam::DVec3;

/// One body's translational state at its local clock.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Body {
    /// Centre position at time `t` (inside the box up to round-off while in its cell).
    pub r: DVec3,
    /// The body's local clock (time since the last re-basing of the time origin).
    pub t: f64,
    /// Centre velocity.
    pub v: DVec3,
    /// Species index.
    pub species: u32,
    /// Generation: bumped (wrapping) whenever the velocity changes, so that events others
    /// predicted with this body can tell they are stale. It cannot wrap round to an old value
    /// while such an event waits: every list is rebuilt at each re-basing of the time origin,
    /// at most 2³¹ events apart.
    pub generation: u32,
}

impl Body {
    /// Position at time `now` (not stored).
    #[inline(always)]
    pub fn position_at(&self, now: f64) -> DVec3 {
        self.r + self.v * (now - self.t)
    }

    /// Brings the stored state to time `now`.
    #[inline(always)]
    pub fn sync(&mut self, now: f64) {
        self.r = self.position_at(now);
        self.t = now;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_cache_line_per_body() {
        assert_eq!(std::mem::size_of::<Body>(), 64);
        assert_eq!(std::mem::align_of::<Body>(), 64);
    }
}
