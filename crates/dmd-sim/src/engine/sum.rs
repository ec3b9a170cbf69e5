//! Compensated summation for long-running accumulators (time origin, virial, energy integrals).

/// A Neumaier-compensated sum: the error stays at a few ulps of the total after 10⁹ terms,
/// where a plain `f64` sum can lose 10⁻⁷ relative.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Compensated {
    sum: f64,
    carry: f64,
}

impl Compensated {
    /// Zero.
    pub const ZERO: Compensated = Compensated {
        sum: 0.0,
        carry: 0.0,
    };

    /// Adds `x`.
    #[inline(always)]
    pub fn add(&mut self, x: f64) {
        let t = self.sum + x;
        if self.sum.abs() >= x.abs() {
            self.carry += (self.sum - t) + x;
        } else {
            self.carry += (x - t) + self.sum;
        }
        self.sum = t;
    }

    /// The total.
    #[inline(always)]
    pub fn value(&self) -> f64 {
        self.sum + self.carry
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_small_terms_next_to_a_large_total() {
        let mut c = Compensated::ZERO;
        let mut plain = 0.0;
        c.add(1e16);
        plain += 1e16;
        for _ in 0..1000 {
            c.add(1.0);
            plain += 1.0;
        }
        assert_eq!(c.value(), 1e16 + 1000.0);
        assert_ne!(plain, 1e16 + 1000.0);
    }
}
