//! Stored pair state: which level (terrace, well) each interacting pair is on.
//!
//! Only pairs off level 0 (inside at least one step radius) are stored, in per-body lists with
//! a fixed stride: body `i`'s partners are `partners[i·cap .. i·cap + len[i]]`. A look-up scans
//! one body's short list (a few dozen bytes, usually one cache line), which stays local at any
//! system size, where a global hash table would miss the cache on every probe at 10⁶ bodies.
//! Each pair is kept in both bodies' lists. The stride doubles when a list overflows (rare:
//! the number of partners within the reach is bounded by packing when there is a hard core).
//!
//! The level is changed only by executed events; it is never recomputed from a distance during
//! a run (at a boundary the distance is the radius up to round-off, either side).

/// Levels of all interacting pairs.
#[derive(Clone, Debug)]
pub struct PairStates {
    cap: usize,
    len: Vec<u32>,
    partners: Vec<u32>,
    levels: Vec<u16>,
    stored: usize,
}

impl PairStates {
    /// No pair interacting yet, for `n` bodies.
    pub fn new(n: usize) -> Self {
        let cap = 8;
        PairStates {
            cap,
            len: vec![0; n],
            partners: vec![u32::MAX; n * cap],
            levels: vec![0; n * cap],
            stored: 0,
        }
    }

    /// The level of pair `(i, j)` (0 when not stored).
    #[inline(always)]
    pub fn get(&self, i: u32, j: u32) -> u16 {
        let base = i as usize * self.cap;
        let list = &self.partners[base..base + self.len[i as usize] as usize];
        match list.iter().position(|&p| p == j) {
            Some(k) => self.levels[base + k],
            None => 0,
        }
    }

    /// Sets the level of pair `(i, j)`, `i ≠ j`.
    pub fn set(&mut self, i: u32, j: u32, level: u16) {
        debug_assert_ne!(i, j);
        let had = self.set_one(i, j, level);
        let had_j = self.set_one(j, i, level);
        debug_assert_eq!(had, had_j, "pair lists of {i} and {j} disagree");
        match (had, level != 0) {
            (false, true) => self.stored += 1,
            (true, false) => self.stored -= 1,
            _ => {}
        }
    }

    /// Number of bodies.
    pub fn n_bodies(&self) -> usize {
        self.len.len()
    }

    /// Number of pairs off level 0.
    pub fn stored(&self) -> usize {
        self.stored
    }

    /// Partners and levels of body `i`.
    pub fn of(&self, i: u32) -> impl Iterator<Item = (u32, u16)> + '_ {
        let base = i as usize * self.cap;
        let n = self.len[i as usize] as usize;
        self.partners[base..base + n]
            .iter()
            .copied()
            .zip(self.levels[base..base + n].iter().copied())
    }

    /// Updates `i`'s list; returns whether the pair was stored before.
    fn set_one(&mut self, i: u32, j: u32, level: u16) -> bool {
        let base = i as usize * self.cap;
        let n = self.len[i as usize] as usize;
        let found = self.partners[base..base + n].iter().position(|&p| p == j);
        match (found, level) {
            (Some(k), 0) => {
                let last = base + n - 1;
                self.partners[base + k] = self.partners[last];
                self.levels[base + k] = self.levels[last];
                self.partners[last] = u32::MAX;
                self.len[i as usize] -= 1;
                true
            }
            (Some(k), l) => {
                self.levels[base + k] = l;
                true
            }
            (None, 0) => false,
            (None, l) => {
                if n == self.cap {
                    self.grow();
                }
                let base = i as usize * self.cap;
                self.partners[base + n] = j;
                self.levels[base + n] = l;
                self.len[i as usize] += 1;
                false
            }
        }
    }

    #[cold]
    fn grow(&mut self) {
        let cap = self.cap * 2;
        let n = self.len.len();
        let mut partners = vec![u32::MAX; n * cap];
        let mut levels = vec![0; n * cap];
        for i in 0..n {
            let len = self.len[i] as usize;
            partners[i * cap..i * cap + len]
                .copy_from_slice(&self.partners[i * self.cap..i * self.cap + len]);
            levels[i * cap..i * cap + len]
                .copy_from_slice(&self.levels[i * self.cap..i * self.cap + len]);
        }
        self.partners = partners;
        self.levels = levels;
        self.cap = cap;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_get_remove_symmetric_and_growing() {
        let mut s = PairStates::new(40);
        for j in 1..30 {
            s.set(0, j, (j % 3 + 1) as u16);
        }
        assert_eq!(s.stored(), 29);
        for j in 1..30 {
            assert_eq!(s.get(0, j), (j % 3 + 1) as u16);
            assert_eq!(s.get(j, 0), (j % 3 + 1) as u16);
        }
        s.set(0, 7, 0);
        s.set(4, 0, 9);
        assert_eq!(s.get(7, 0), 0);
        assert_eq!(s.get(0, 4), 9);
        assert_eq!(s.stored(), 28);
        assert_eq!(s.get(30, 31), 0);
        s.set(30, 31, 0);
        assert_eq!(s.stored(), 28);
        assert_eq!(s.of(0).count(), 28);
    }
}
