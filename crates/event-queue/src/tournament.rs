//! A complete binary tree with one leaf per participant: the scheduler of choice when every
//! participant has exactly one pending event (its earliest), as in many hard-sphere codes.
//!
//! Each leaf holds a participant's next event time; each inner node holds the participant that
//! wins (has the earliest time) in its subtree, so the root names the next event. Changing a
//! participant's time replays the matches on its path to the root, O(log n), stopping early
//! once a match's winner is unchanged and is someone else. There are no stale events, nothing
//! to invalidate, and memory stays at `n` leaves; payloads live with the simulator, indexed by
//! participant.
//!
//! Ties go to the lower participant index, so runs are reproducible. `+∞` means "no event".
//!
//! ```
//! use event_queue::TournamentTree;
//!
//! let mut tree = TournamentTree::new(4); // every participant starts at +∞ (no event)
//! tree.set(2, 1.5)?;
//! tree.set(0, 0.5)?;
//! assert_eq!(tree.min(), Some((0, 0.5)));
//! tree.set(0, f64::INFINITY)?; // participant 0's event happened; it has none now
//! assert_eq!(tree.min(), Some((2, 1.5)));
//! # Ok::<(), event_queue::QueueError>(())
//! ```

use crate::{QueueError, check_time};

/// A tournament (winner) tree over participants `0..n`.
#[derive(Clone, Debug)]
pub struct TournamentTree {
    n: usize,
    /// Event time of each leaf; leaves `n..` are padding at `+∞`.
    times: Vec<f64>,
    /// Winner of each inner node, heap-ordered: node 1 is the root, node `k` has children `2k`
    /// and `2k + 1`, and node `leaves + i` is leaf `i`. Slot 0 is unused.
    winner: Vec<u32>,
    /// Number of leaves: a power of two ≥ n.
    leaves: usize,
}

impl TournamentTree {
    /// A tree for participants `0..n`, all at `+∞` (no event).
    ///
    /// # Panics
    /// If `n` is 2³² or more.
    pub fn new(n: usize) -> Self {
        assert!(n < u32::MAX as usize, "at most 2^32 - 2 participants");
        let leaves = n.max(1).next_power_of_two();
        let mut tree = Self {
            n,
            times: vec![f64::INFINITY; leaves],
            winner: vec![0; leaves],
            leaves,
        };
        for k in (1..leaves).rev() {
            tree.winner[k] = tree.play(k);
        }
        tree
    }

    /// Number of participants.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the tree has no participant.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Participant `i`'s event time (`+∞`: none).
    ///
    /// # Panics
    /// If `i` is not a participant.
    pub fn get(&self, i: usize) -> f64 {
        assert!(i < self.n, "participant {i} of {}", self.n);
        self.times[i]
    }

    /// The participant with the earliest event and its time; `None` if nobody has an event.
    #[inline]
    pub fn min(&self) -> Option<(usize, f64)> {
        let w = if self.leaves == 1 {
            0
        } else {
            self.winner[1] as usize
        };
        let t = self.times[w];
        (t < f64::INFINITY && w < self.n).then_some((w, t))
    }

    /// Sets participant `i`'s event time (`+∞` to clear it).
    ///
    /// # Errors
    /// [`QueueError::NanTime`] if `time` is NaN; the tree is unchanged.
    ///
    /// # Panics
    /// If `i` is not a participant.
    #[inline]
    pub fn set(&mut self, i: usize, time: f64) -> Result<(), QueueError> {
        check_time(time)?;
        assert!(i < self.n, "participant {i} of {}", self.n);
        self.times[i] = time;
        let me = i as u32;
        let mut k = (self.leaves + i) / 2;
        while k >= 1 {
            let old = self.winner[k];
            let new = self.play(k);
            self.winner[k] = new;
            if new == old && new != me {
                break; // this subtree's winner and its time are unchanged: so is every ancestor
            }
            k /= 2;
        }
        Ok(())
    }

    /// The winner of the match at inner node `k`.
    #[inline(always)]
    fn play(&self, k: usize) -> u32 {
        let side = |c: usize| {
            if c >= self.leaves {
                (c - self.leaves) as u32
            } else {
                self.winner[c]
            }
        };
        let (a, b) = (side(2 * k), side(2 * k + 1));
        let (ta, tb) = (self.times[a as usize], self.times[b as usize]);
        // `a` is the left (lower-index) side: it keeps ties.
        if tb < ta { b } else { a }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follows_a_brute_force_minimum() {
        for n in [1usize, 2, 3, 5, 8, 100, 1000] {
            let mut tree = TournamentTree::new(n);
            let mut times = vec![f64::INFINITY; n];
            let mut x = 12_345u64;
            for step in 0..20 * n {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                let i = (x % n as u64) as usize;
                // Few distinct values so that ties are common; some +∞ to clear events.
                let t = match x % 11 {
                    0 => f64::INFINITY,
                    r => (r % 4) as f64,
                };
                tree.set(i, t).unwrap();
                times[i] = t;
                let expected = times
                    .iter()
                    .enumerate()
                    .filter(|(_, t)| t.is_finite())
                    .min_by(|a, b| a.1.partial_cmp(b.1).unwrap().then(a.0.cmp(&b.0)))
                    .map(|(i, &t)| (i, t));
                assert_eq!(tree.min(), expected, "n = {n}, step {step}");
            }
        }
    }

    #[test]
    fn refuses_nan_and_handles_empty() {
        let mut tree = TournamentTree::new(3);
        tree.set(1, 2.0).unwrap();
        assert_eq!(tree.set(1, f64::NAN), Err(QueueError::NanTime));
        assert_eq!(tree.min(), Some((1, 2.0)));
        assert_eq!(tree.get(1), 2.0);
        let empty = TournamentTree::new(0);
        assert!(empty.is_empty() && empty.min().is_none());
        tree.set(2, f64::NEG_INFINITY).unwrap();
        assert_eq!(tree.min(), Some((2, f64::NEG_INFINITY)));
    }
}
