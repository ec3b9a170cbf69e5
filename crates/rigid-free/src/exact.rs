//! Double-double arithmetic (error-free transformations, Dekker 1971 / Knuth) for the one
//! quantity whose cancellation binary64 cannot absorb: `Δ2 = L² − 2E I2` near the separatrix.
//!
//! Written as `I1ω1²(I1 − I2) + I3ω3²(I3 − I2)` it has no `L² − 2E I` cancellation, but its two
//! terms have opposite signs and cancel to the distance from the separatrix: at `m_c = 3e-14`
//! one rounding of `ω1²` already moves `m_c` by 0.4 % and the period by 1e-4. Evaluated in
//! double-double, `Δ2` is exact to ~1e-32 of its terms, so `m_c` is as exact as the inputs.

/// `a + b` as an unevaluated sum `hi + lo`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Dd {
    hi: f64,
    lo: f64,
}

/// Veltkamp's split of `a` into two 26-bit halves.
#[inline]
fn split(a: f64) -> (f64, f64) {
    const C: f64 = 134_217_729.0; // 2^27 + 1
    let t = C * a;
    let hi = t - (t - a);
    (hi, a - hi)
}

/// `a·b = p + e` exactly (Dekker), without relying on a hardware fused multiply-add.
#[inline]
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    (p, e)
}

/// `a + b = s + e` exactly (Knuth).
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

impl Dd {
    /// `a − b`, exactly.
    pub(crate) fn diff(a: f64, b: f64) -> Self {
        let (hi, lo) = two_sum(a, -b);
        Self { hi, lo }
    }

    /// `a · b`, exactly.
    pub(crate) fn prod(a: f64, b: f64) -> Self {
        let (hi, lo) = two_prod(a, b);
        Self { hi, lo }
    }

    /// `self · other` to double-double precision.
    pub(crate) fn mul(self, o: Self) -> Self {
        let (p, e) = two_prod(self.hi, o.hi);
        let e = e + (self.hi * o.lo + self.lo * o.hi);
        let (hi, lo) = two_sum(p, e);
        Self { hi, lo }
    }

    /// `self · b` to double-double precision.
    pub(crate) fn mul_f64(self, b: f64) -> Self {
        let (p, e) = two_prod(self.hi, b);
        let (hi, lo) = two_sum(p, e + self.lo * b);
        Self { hi, lo }
    }

    /// `self + other` to double-double precision.
    pub(crate) fn add(self, o: Self) -> Self {
        let (s, e) = two_sum(self.hi, o.hi);
        let (hi, lo) = two_sum(s, e + self.lo + o.lo);
        Self { hi, lo }
    }

    /// The nearest binary64.
    pub(crate) fn value(self) -> f64 {
        self.hi + self.lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cancellation_is_exact() {
        // (1 + 2⁻³⁰)² − 1 − 2⁻²⁹ = 2⁻⁶⁰, lost entirely in binary64.
        let a = 1.0 + 2f64.powi(-30);
        let sq = Dd::prod(a, a);
        let r = sq.add(Dd::diff(-1.0, 2f64.powi(-29))).value();
        assert_eq!(r, 2f64.powi(-60));
        assert_eq!(a * a - 1.0 - 2f64.powi(-29), 0.0);
        // A product chain: 3 · (1 + 2⁻⁴⁰)·(1 − 2⁻⁴⁰) − 3 = −3·2⁻⁸⁰.
        let x = Dd::prod(1.0 + 2f64.powi(-40), 1.0 - 2f64.powi(-40)).mul_f64(3.0);
        assert_eq!(x.add(Dd::diff(0.0, 3.0)).value(), -3.0 * 2f64.powi(-80));
        // (1 + 2⁻³⁰)(1 + 2⁻⁵⁰) − 1 − 2⁻³⁰ − 2⁻⁵⁰ = 2⁻⁸⁰ (a product of two double-doubles).
        let y = Dd::diff(1.0, -(2f64.powi(-30))).mul(Dd::diff(1.0, -(2f64.powi(-50))));
        let z = y
            .add(Dd::diff(-1.0, 2f64.powi(-30)))
            .add(Dd::diff(0.0, 2f64.powi(-50)));
        assert_eq!(z.value(), 2f64.powi(-80));
    }
}
