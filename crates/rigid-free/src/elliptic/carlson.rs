//! Carlson's symmetric elliptic integrals R_F, R_J and R_C by duplication (DLMF 19.36.1;
//! B. C. Carlson, Numer. Algorithms 10, 13 (1995)).
//!
//! Each duplication step replaces every argument `v` by `(v + λ)/4` with
//! `λ = √x√y + √y√z + √z√x`, which leaves the integral unchanged (up to a known sum for R_J) and
//! shrinks the spread of the arguments by 4. Once the spread is below `(3r)^{1/6}` of their mean
//! (`r` = 2⁻⁵³), a fifth-order Taylor expansion about the mean is exact to rounding.

/// `(3r)^(−1/6)` and `(r/4)^(−1/6)` for `r = 2⁻⁵³` (one rounding of binary64): Carlson's
/// stopping scales for R_F and R_J.
const RF_SCALE: f64 = 379.820_224_302_285_96;
const RJ_SCALE: f64 = 574.700_568_734_399;

/// Carlson's R_F(x, y, z) for `x, y, z ≥ 0`, at most one of them zero (unchecked).
pub(crate) fn rf(x: f64, y: f64, z: f64) -> f64 {
    let (mut x, mut y, mut z) = (x, y, z);
    let a0 = (x + y + z) / 3.0;
    // (3r)^(-1/6) · largest distance from the mean: the stopping scale of DLMF 19.36.1.
    let q = RF_SCALE * (a0 - x).abs().max((a0 - y).abs()).max((a0 - z).abs());
    let (x0, y0) = (x, y);
    let mut a = a0;
    let mut pow4 = 1.0_f64; // 4^m
    while q >= pow4 * a.abs() {
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lambda = sx * sy + sy * sz + sz * sx;
        a = 0.25 * (a + lambda);
        x = 0.25 * (x + lambda);
        y = 0.25 * (y + lambda);
        z = 0.25 * (z + lambda);
        pow4 *= 4.0;
    }
    let inv = 1.0 / (pow4 * a);
    let xx = (a0 - x0) * inv;
    let yy = (a0 - y0) * inv;
    let zz = -(xx + yy);
    let e2 = xx * yy - zz * zz;
    let e3 = xx * yy * zz;
    // Carlson (1995) Eq. (2.2), the terms of total degree ≤ 5 (reciprocal constants: one
    // division instead of five).
    (1.0 - e2 * (1.0 / 10.0) + e3 * (1.0 / 14.0) + e2 * e2 * (1.0 / 24.0) - e2 * e3 * (3.0 / 44.0))
        / a.sqrt()
}

/// `R_C(1, 1 + e)` for `e > −1`, the degenerate integral R_J needs (DLMF 19.2.17–19.2.19):
/// `atan(√e)/√e` for `e > 0` and, for `e < 0`, `atanh(s)/s = ln((1 + s)/√(1 + e))/s` with
/// `s = √−e`, evaluated as `ln_1p` so that it keeps full precision both as `s → 0` and as
/// `s → 1` (where `atanh(s)` would inherit the rounding of `1 − s`).
fn rc_one(e: f64) -> f64 {
    if e.abs() < 1e-3 {
        // Σ (−e)^k / (2k + 1); the next term is below 1e-16.
        1.0 - e * (1.0 / 3.0 - e * (1.0 / 5.0 - e * (1.0 / 7.0 - e * (1.0 / 9.0 - e / 11.0))))
    } else if e > 0.0 {
        let s = e.sqrt();
        s.atan() / s
    } else {
        // (1 + s)/t − 1 = (s − e/(1 + t))/t with t = √(1 + e), so ln_1p sees no cancellation.
        let s = (-e).sqrt();
        let t = (1.0 + e).sqrt();
        ((s - e / (1.0 + t)) / t).ln_1p() / s
    }
}

/// Carlson's R_C(x, y) for `x ≥ 0`, `y > 0` (unchecked), DLMF 19.2.17–19.2.18.
pub(crate) fn rc(x: f64, y: f64) -> f64 {
    if x == 0.0 {
        return std::f64::consts::FRAC_PI_2 / y.sqrt();
    }
    let e = y / x - 1.0;
    if e < -1e-3 {
        // ln((√x + √(x − y))/√y)/√(x − y) (DLMF 19.2.19), no 1 − y/x formed: with
        // √x + d = √y + (√x − √y) + d and √x − √y = (x − y)/(√x + √y), as ln_1p.
        let (sx, sy) = (x.sqrt(), y.sqrt());
        let d = (x - y).sqrt();
        return ((d * d / (sx + sy) + d) / sy).ln_1p() / d;
    }
    rc_one(e) / x.sqrt()
}

/// Carlson's R_J(x, y, z, p) for `x, y, z ≥ 0` (at most one zero) and `p > 0` (unchecked).
pub(crate) fn rj(x: f64, y: f64, z: f64, p: f64) -> f64 {
    let (mut x, mut y, mut z, mut p) = (x, y, z, p);
    let a0 = (x + y + z + 2.0 * p) / 5.0;
    let delta = (p - x) * (p - y) * (p - z);
    let q = RJ_SCALE
        * (a0 - x)
            .abs()
            .max((a0 - y).abs())
            .max((a0 - z).abs())
            .max((a0 - p).abs());
    let (x0, y0, z0) = (x, y, z);
    let mut a = a0;
    let mut pow4 = 1.0_f64; // 4^m
    let mut sum = 0.0;
    while q >= pow4 * a.abs() {
        let (sx, sy, sz, sp) = (x.sqrt(), y.sqrt(), z.sqrt(), p.sqrt());
        let lambda = sx * sy + sy * sz + sz * sx;
        let d = (sp + sx) * (sp + sy) * (sp + sz);
        let e = delta / (pow4 * pow4 * pow4 * d * d);
        sum += rc_one(e) / (pow4 * d);
        a = 0.25 * (a + lambda);
        x = 0.25 * (x + lambda);
        y = 0.25 * (y + lambda);
        z = 0.25 * (z + lambda);
        p = 0.25 * (p + lambda);
        pow4 *= 4.0;
    }
    let inv = 1.0 / (pow4 * a);
    let xx = (a0 - x0) * inv;
    let yy = (a0 - y0) * inv;
    let zz = (a0 - z0) * inv;
    let pp = -0.5 * (xx + yy + zz);
    let p2 = pp * pp;
    let e2 = xx * yy + xx * zz + yy * zz - 3.0 * p2;
    let e3 = xx * yy * zz + 2.0 * e2 * pp + 4.0 * p2 * pp;
    let e4 = (2.0 * xx * yy * zz + e2 * pp + 3.0 * p2 * pp) * pp;
    let e5 = xx * yy * zz * p2;
    // Carlson (1995) Eq. (2.7), the terms of total degree ≤ 5.
    let series = 1.0 - e2 * (3.0 / 14.0) + e3 * (1.0 / 6.0) + e2 * e2 * (9.0 / 88.0)
        - e4 * (3.0 / 22.0)
        - e2 * e3 * (9.0 / 52.0)
        + e5 * (3.0 / 26.0);
    series / (pow4 * a * a.sqrt()) + 6.0 * sum
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        let ok = (a - b).abs() <= rel * b.abs();
        if !ok {
            eprintln!("{a} vs {b}: {:e}", (a - b).abs() / b.abs());
        }
        ok
    }

    /// R_C from `reference/special-reference.txt`, including y ≪ x where `atanh` near 1 loses
    /// digits.
    #[test]
    fn rc_against_reference() {
        let text = include_str!("../../reference/special-reference.txt");
        for line in text.lines().filter(|l| l.starts_with("rc ")) {
            let v: Vec<f64> = line[3..]
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            let got = rc(v[0], v[1]);
            assert!(
                (got - v[2]).abs() <= 2.0 * f64::EPSILON * v[2],
                "R_C({}, {}) = {got}, want {}",
                v[0],
                v[1],
                v[2]
            );
        }
    }

    // Values from DLMF 19.20 special cases, which need no stored table.
    #[test]
    fn special_values() {
        // R_F(x, x, x) = x^{-1/2}; R_F(0, 1, 1) = π/2; R_F(0, y, y) = π/(2√y).
        assert!(close(rf(4.0, 4.0, 4.0), 0.5, 1e-16));
        assert!(close(rf(0.0, 1.0, 1.0), std::f64::consts::FRAC_PI_2, 2e-16));
        assert!(close(
            rf(0.0, 9.0, 9.0),
            std::f64::consts::FRAC_PI_2 / 3.0,
            5e-16
        ));
        // R_J(x, x, x, x) = x^{-3/2}; R_C(0, 1) = π/2; R_C(1, 2) = π/4.
        assert!(close(rj(4.0, 4.0, 4.0, 4.0), 0.125, 2e-16));
        assert!(close(rc(0.0, 1.0), std::f64::consts::FRAC_PI_2, 2e-16));
        assert!(close(rc(1.0, 2.0), std::f64::consts::FRAC_PI_4, 2e-16));
        // R_C(x, y) = R_F(x, y, y) and R_J(x, y, z, z) = R_D(x, y, z), and R_D(0, 2, 1) from
        // Carlson (1995) Table: 1.7972103521034.
        assert!(close(rc(2.0, 3.0), rf(2.0, 3.0, 3.0), 8e-16));
        assert!(close(rc(3.0, 2.0), rf(3.0, 2.0, 2.0), 8e-16));
        assert!(close(rj(0.0, 2.0, 1.0, 1.0), 1.797_210_352_103_4, 1e-13));
        // Carlson (1995) test values: R_F(1, 2, 0) = 1.3110287771461, R_J(0, 1, 2, 3) = 0.77688623778582.
        assert!(close(rf(1.0, 2.0, 0.0), 1.311_028_777_146_1, 1e-13));
        assert!(close(rj(0.0, 1.0, 2.0, 3.0), 0.776_886_237_785_82, 1e-13));
    }
}
