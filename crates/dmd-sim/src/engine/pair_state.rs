//! Stored pair state: which level (terrace, well) each interacting pair is on
//! ([`PairStates`]; per site pair of molecules: [`SiteLevels`]), and what the pending virtual
//! event of a pair will continue ([`SavedSearches`]).
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

use std::collections::HashMap;

use crate::engine::saved::StateReader;

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

/// Site-pair levels of molecule pairs (site molecules, rigid or semi-flexible): for each
/// molecule pair `(lo, hi)`, `lo ≤ hi` (`lo = hi`: the site pairs of one molecule), with a
/// site pair off level 0, the levels of all its site pairs, `α`-major for `lo` (`sizes` below
/// are the two molecules' site counts).
#[derive(Clone, Debug, Default)]
pub struct SiteLevels {
    map: HashMap<(u32, u32), Box<[u16]>>,
}

impl SiteLevels {
    /// Key and index of site pair (`a` of `i`, `b` of `j`); `sizes` = site counts of `i`, `j`.
    #[inline]
    fn index(i: u32, j: u32, a: usize, b: usize, sizes: (usize, usize)) -> ((u32, u32), usize) {
        if i <= j {
            ((i, j), a * sizes.1 + b)
        } else {
            ((j, i), b * sizes.0 + a)
        }
    }

    /// The level of site `a` of `i` with site `b` of `j`.
    pub fn get(&self, i: u32, j: u32, a: usize, b: usize, sizes: (usize, usize)) -> u16 {
        let (key, idx) = Self::index(i, j, a, b, sizes);
        self.map.get(&key).map_or(0, |l| l[idx])
    }

    /// Sets the level of site `a` of `i` with site `b` of `j`; a molecule pair whose site
    /// pairs are all back on level 0 is dropped.
    pub fn set(&mut self, i: u32, j: u32, a: usize, b: usize, sizes: (usize, usize), level: u16) {
        let (key, idx) = Self::index(i, j, a, b, sizes);
        let entry = self
            .map
            .entry(key)
            .or_insert_with(|| vec![0; sizes.0 * sizes.1].into_boxed_slice());
        entry[idx] = level;
        if level == 0 && entry.iter().all(|&l| l == 0) {
            self.map.remove(&key);
        }
    }

    /// All site-pair levels of `(i, j)`, `α`-major for `i` (zeros if none is stored).
    pub fn pair(&self, i: u32, j: u32, sizes: (usize, usize)) -> Vec<u16> {
        let (ni, nj) = sizes;
        let mut out = vec![0; ni * nj];
        if let Some(l) = self.stored(i, j) {
            for a in 0..ni {
                for b in 0..nj {
                    out[a * nj + b] = if i <= j { l[a * nj + b] } else { l[b * ni + a] };
                }
            }
        }
        out
    }

    /// The stored levels of `(i, j)` in the order of the lower index (`None`: all on 0).
    pub fn stored(&self, i: u32, j: u32) -> Option<&[u16]> {
        self.map.get(&(i.min(j), i.max(j))).map(|l| &l[..])
    }

    /// Number of molecule pairs stored.
    pub fn len(&self) -> usize {
        self.map.len()
    }

    /// No molecule pair stored.
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }

    /// Appends every stored pair to a saved state, in the order of the pairs (so that equal
    /// states give equal numbers): the count, then per pair `lo, hi, n`, and the `n` levels.
    pub fn write_numbers(&self, out: &mut Vec<f64>) {
        let mut keys: Vec<&(u32, u32)> = self.map.keys().collect();
        keys.sort_unstable();
        out.push(keys.len() as f64);
        for k in keys {
            let l = &self.map[k];
            out.extend_from_slice(&[f64::from(k.0), f64::from(k.1), l.len() as f64]);
            out.extend(l.iter().map(|&v| f64::from(v)));
        }
    }

    /// Reads what [`write_numbers`](Self::write_numbers) wrote, for `n` molecules whose pair
    /// `(lo, hi)` has `sizes(lo, hi)` site pairs and whose site pair `k` has `levels(lo, hi, k)`
    /// levels.
    ///
    /// # Errors
    /// A pair or level that does not fit the scene.
    pub fn read_numbers(
        r: &mut StateReader,
        n: u32,
        sizes: impl Fn(u32, u32) -> usize,
        levels: impl Fn(u32, u32, usize) -> usize,
    ) -> Result<Self, String> {
        let pairs = r.index("the number of stored site-pair levels", u64::from(u32::MAX))?;
        let mut map = HashMap::new();
        for _ in 0..pairs {
            let lo = r.index("a molecule of a stored pair", u64::from(n))? as u32;
            let hi = r.index("a molecule of a stored pair", u64::from(n))? as u32;
            if lo > hi {
                return Err(format!("the stored pair ({lo}, {hi}) is not ordered"));
            }
            let len = r.index("a pair's number of site pairs", 1 << 32)? as usize;
            if len != sizes(lo, hi) {
                return Err(format!(
                    "the pair ({lo}, {hi}) has {} site pairs, the state gives {len}",
                    sizes(lo, hi)
                ));
            }
            let mut l = Vec::with_capacity(len);
            for k in 0..len {
                l.push(r.index("a site-pair level", levels(lo, hi, k) as u64)? as u16);
            }
            if map.insert((lo, hi), l.into_boxed_slice()).is_some() {
                return Err(format!("the pair ({lo}, {hi}) is stored twice"));
            }
        }
        Ok(SiteLevels { map })
    }
}

/// What the pending virtual events of every owner will continue (a saved root search, a pair
/// to start searching …), per partner, tagged with the event's time as the loop computes it
/// (`now + dt`). The loop may hold two current events of one pair: a pair that left the
/// neighbour list and came back with neither body changing is predicted again while its first
/// event is still scheduled. The time tells them apart, so the stale one, when due, finds
/// nothing instead of consuming the live one's saved state.
#[derive(Clone, Debug)]
pub struct SavedSearches<P> {
    lists: Vec<Vec<(u32, f64, P)>>,
}

impl<P> SavedSearches<P> {
    /// Nothing saved, for `n` owners.
    pub fn new(n: usize) -> Self {
        SavedSearches {
            lists: (0..n).map(|_| Vec::new()).collect(),
        }
    }

    /// Saves `what` for the event of owner `i` with partner `j` at time `at` (replacing what
    /// an earlier prediction of the pair saved).
    pub fn set(&mut self, i: u32, j: u32, at: f64, what: P) {
        let list = &mut self.lists[i as usize];
        match list.iter_mut().find(|(p, _, _)| *p == j) {
            Some(e) => {
                e.1 = at;
                e.2 = what;
            }
            None => list.push((j, at, what)),
        }
    }

    /// Takes what the event of `i` with `j` due at `now` continues (`None` for a stale event).
    pub fn take(&mut self, i: u32, j: u32, now: f64) -> Option<P> {
        let list = &mut self.lists[i as usize];
        let k = list.iter().position(|(p, at, _)| *p == j && *at == now)?;
        Some(list.swap_remove(k).2)
    }

    /// Forgets everything owner `i` saved (its events are invalid: it changed).
    pub fn clear(&mut self, i: u32) {
        self.lists[i as usize].clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A site pair reads the same from either molecule, a pair's table is oriented from the
    /// asking molecule, and a molecule pair back on level 0 everywhere is dropped.
    #[test]
    fn site_levels_read_the_same_from_either_molecule() {
        let mut l = SiteLevels::default();
        // Molecule 5 has 3 sites, molecule 2 has 2.
        l.set(5, 2, 1, 0, (3, 2), 4);
        l.set(2, 5, 1, 2, (2, 3), 7);
        assert_eq!(l.get(2, 5, 0, 1, (2, 3)), 4);
        assert_eq!(l.get(5, 2, 2, 1, (3, 2)), 7);
        assert_eq!(l.pair(5, 2, (3, 2)), vec![0, 0, 4, 0, 0, 7]);
        assert_eq!(l.pair(2, 5, (2, 3)), vec![0, 4, 0, 0, 0, 7]);
        assert_eq!(l.len(), 1);
        l.set(5, 2, 1, 0, (3, 2), 0);
        assert_eq!(l.len(), 1);
        l.set(5, 2, 2, 1, (3, 2), 0);
        assert!(l.is_empty() && l.stored(2, 5).is_none());
    }

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
