//! Fault injection, a validation tool of hybrid Monte Carlo: in each HMC segment the loop hides
//! a fixed, freshly drawn fraction of the pairs from every event prediction, so the dynamics
//! miss their events on purpose and the accept/reject step has something to correct. It sits
//! in the loop, not in a model, so it serves every model without a wrapper; while it is off
//! (every ordinary run, and HMC before its first segment) it costs one predictable branch per
//! prediction.

use crate::engine::hash::mix;

/// Which pairs the predictions skip in the present segment (none while inactive).
#[derive(Clone, Debug, Default)]
pub(crate) struct Blindfold {
    threshold: u64,
    salt: u64,
    key: u64,
    active: bool,
}

impl Blindfold {
    /// Hides about `fraction` (in `[0, 1)`) of the pairs per segment, chosen from `seed`, once
    /// the first segment begins.
    pub(crate) fn new(fraction: f64, seed: u64) -> Self {
        let threshold = (fraction.clamp(0.0, 1.0) * 18_446_744_073_709_551_616.0) as u64;
        Blindfold {
            threshold,
            salt: mix(seed ^ 0xfa17_0000_0000_0009),
            key: 0,
            active: false,
        }
    }

    /// Segment number `segment` begins: the hidden pairs are drawn afresh (a function of the
    /// seed and the segment number alone, so a resumed chain hides the same pairs).
    pub(crate) fn begin_segment(&mut self, segment: u64) {
        self.key = mix(self.salt ^ segment);
        self.active = self.threshold > 0;
    }

    /// Whether any pair is hidden in the present segment.
    #[inline(always)]
    pub(crate) fn is_active(&self) -> bool {
        self.active
    }

    /// Whether pair `(i, j)` is hidden in the present segment.
    #[inline(always)]
    pub(crate) fn hides(&self, i: u32, j: u32) -> bool {
        self.active && self.hides_active(i, j)
    }

    #[inline(never)]
    fn hides_active(&self, i: u32, j: u32) -> bool {
        let (a, b) = if i < j { (i, j) } else { (j, i) };
        mix(self.key ^ (u64::from(a) << 32 | u64::from(b))) < self.threshold
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hidden_pairs_are_symmetric_near_the_fraction_and_fresh_per_segment() {
        let mut f = Blindfold::new(0.1, 7);
        assert!(!f.hides(1, 2), "nothing is hidden before the first segment");
        f.begin_segment(3);
        let mut hidden = 0;
        for i in 0..200 {
            for j in 0..i {
                assert_eq!(f.hides(i, j), f.hides(j, i));
                hidden += u32::from(f.hides(i, j));
            }
        }
        // 19 900 pairs, binomial(0.1): σ ≈ 42.
        assert!((f64::from(hidden) - 1990.0).abs() < 250.0, "{hidden}");
        let before: Vec<bool> = (0..50).map(|j| f.hides(100, j)).collect();
        f.begin_segment(4);
        let after: Vec<bool> = (0..50).map(|j| f.hides(100, j)).collect();
        assert_ne!(before, after, "the hidden set is drawn afresh per segment");
        let mut none = Blindfold::new(0.0, 7);
        none.begin_segment(3);
        assert!((0..50).all(|j| !none.hides(100, j)));
    }
}
