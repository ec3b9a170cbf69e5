//! Legendre's elliptic integrals K, F and Π from Carlson's forms, taking `m_c = 1 − m`.

use super::carlson::{rf, rj};
use super::jacobi::Jacobi;
use crate::FreeError;
use std::f64::consts::PI;

fn check_m_c(function: &'static str, m_c: f64) -> Result<(), FreeError> {
    if (0.0..=1.0).contains(&m_c) {
        Ok(())
    } else {
        Err(FreeError::ParameterOutOfRange {
            function,
            name: "m_c",
            value: m_c,
        })
    }
}

/// The complete integral of the first kind `K(m) = R_F(0, m_c, 1)` (DLMF 19.25.1), `m = 1 − m_c`.
///
/// # Errors
/// [`FreeError::ParameterOutOfRange`] unless `0 ≤ m_c ≤ 1`. `m_c = 0` gives `+∞`.
pub fn complete_k(m_c: f64) -> Result<f64, FreeError> {
    check_m_c("complete_k", m_c)?;
    Ok(if m_c == 0.0 {
        f64::INFINITY
    } else {
        rf(0.0, m_c, 1.0)
    })
}

/// The incomplete integral of the first kind `F(φ | m)`, any real `φ`, `m = 1 − m_c`.
///
/// `F(φ|m) = sin φ · R_F(cos²φ, cos²φ + m_c sin²φ, 1)` for `|φ| ≤ π/2` (DLMF 19.25.5, written
/// with `m_c` so that no `1 − m` is formed), and `F(φ + jπ) = F(φ) + 2jK` beyond (DLMF 19.2.10).
///
/// # Errors
/// [`FreeError::ParameterOutOfRange`] unless `0 ≤ m_c ≤ 1` and `φ` is finite, or if `m_c = 0`
/// and `|φ| ≥ π/2` (where the integral diverges).
pub fn incomplete_f(phi: f64, m_c: f64) -> Result<f64, FreeError> {
    check_m_c("incomplete_f", m_c)?;
    if !phi.is_finite() {
        return Err(FreeError::ParameterOutOfRange {
            function: "incomplete_f",
            name: "phi",
            value: phi,
        });
    }
    // Reduce to |r| ≤ π/2 only when needed, with π split in three (30 + 30 + 53 bits) so that
    // j·π is subtracted exactly for |j| < 2²³ (Cody–Waite).
    const PI_A: f64 = 3.141592651605606;
    const PI_B: f64 = 1.984_187_158_327_044_3e-9;
    const PI_C: f64 = 1.034_036_596_358_821e-18;
    let j = if phi.abs() <= std::f64::consts::FRAC_PI_2 {
        0.0
    } else {
        (phi / PI).round()
    };
    let r = ((phi - j * PI_A) - j * PI_B) - j * PI_C;
    if j != 0.0 && m_c == 0.0 {
        return Err(FreeError::ParameterOutOfRange {
            function: "incomplete_f (m = 1)",
            name: "phi",
            value: phi,
        });
    }
    let (s, c) = r.sin_cos();
    let c2 = c * c;
    let f = if c2 == 0.0 && m_c == 0.0 {
        f64::INFINITY.copysign(s)
    } else {
        s * rf(c2, c2 + m_c * s * s, 1.0)
    };
    Ok(if j == 0.0 {
        f
    } else {
        f + 2.0 * j * rf(0.0, m_c, 1.0)
    })
}

/// The complete integral of the third kind `Π(n | m) = K + (n/3) R_J(0, m_c, 1, 1 − n)`
/// (DLMF 19.25.2), for `n < 1`, `m = 1 − m_c`.
///
/// # Errors
/// [`FreeError::ParameterOutOfRange`] unless `0 < m_c ≤ 1` and `n < 1` (finite).
pub fn complete_pi(n: f64, m_c: f64) -> Result<f64, FreeError> {
    check_m_c("complete_pi", m_c)?;
    if m_c == 0.0 {
        return Err(FreeError::ParameterOutOfRange {
            function: "complete_pi",
            name: "m_c",
            value: m_c,
        });
    }
    if !n.is_finite() || n >= 1.0 {
        return Err(FreeError::ParameterOutOfRange {
            function: "complete_pi",
            name: "n",
            value: n,
        });
    }
    let k = rf(0.0, m_c, 1.0);
    if n >= 0.0 {
        return Ok(k + n / 3.0 * rj(0.0, m_c, 1.0, 1.0 - n));
    }
    // For n < 0 the two terms cancel (badly as n → −∞). The transformation to
    // N = (m − n)/(1 − n) ∈ (m, 1) (DLMF 19.7.5) leaves a sum of positive terms:
    // Π(n) = m/(m − n) K − n m_c / ((1 − n)(m − n)) Π(N),  with 1 − N = m_c/(1 − n).
    let m = 1.0 - m_c;
    let one_minus_n = 1.0 - n;
    let m_minus_n = m - n;
    let big_n = m_minus_n / one_minus_n;
    let pi_big_n = k + big_n / 3.0 * rj(0.0, m_c, 1.0, m_c / one_minus_n);
    Ok(m / m_minus_n * k - n * m_c / (one_minus_n * m_minus_n) * pi_big_n)
}

/// `Π(n | m) / K(m)` by the arithmetic-geometric mean (DLMF 19.8.6–19.8.8), reusing the AGM
/// table of the Jacobi functions: quadratically convergent and free of the R_C logarithms
/// that make R_J expensive. `n < 1`, `m_c > 0`.
///
/// The result is accurate in absolute terms (a few ulp of `max(1, Π/K)`), which is what the
/// secular rate of the asymmetric top needs; for `n → −∞`, where `Π/K → 0`, the relative error
/// grows (the public [`complete_pi`] transforms such `n` and stays accurate relatively).
pub(crate) fn pi_over_k(jacobi: &Jacobi, n: f64) -> f64 {
    let one_minus_n = 1.0 - n;
    let (a, b) = jacobi.table();
    // Π = π/(4M) (2 + n/(1−n) Σ Q_j) with K = π/(2M): Π/K = 1 + n Σ Q_j / (2(1 − n)).
    let mut p = one_minus_n.sqrt();
    let mut qj = 1.0_f64;
    let mut sum = 0.0;
    let mut level = 0;
    let (mut an, mut gn) = (a[0], b[0]);
    loop {
        let (pp, ag) = (p * p, an * gn);
        let eps = (pp - ag) / (pp + ag);
        sum += qj;
        qj *= 0.5 * eps;
        p = 0.5 * (pp + ag) / p;
        if level + 1 < a.len() {
            level += 1;
            (an, gn) = (a[level], b[level]);
        } else {
            // The AGM has converged; p and Q keep converging quadratically on their own.
            let mean = 0.5 * (an + gn);
            (an, gn) = (mean, mean);
        }
        if qj.abs() <= 1e-17 * sum.abs() {
            break;
        }
    }
    1.0 + n * sum / (2.0 * one_minus_n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_parameters_are_refused() {
        assert!(complete_k(1.5).is_err());
        assert!(incomplete_f(f64::NAN, 0.5).is_err());
        assert!(incomplete_f(2.0, 0.0).is_err());
        assert!(complete_pi(1.0, 0.5).is_err());
        assert!(complete_pi(0.5, 0.0).is_err());
        assert_eq!(complete_k(0.0).unwrap(), f64::INFINITY);
    }

    /// `Π(n | m)` from `reference/special-reference.txt` (40-digit mpmath), both the R_J form
    /// and the AGM form the propagator uses, including n = −2e8 and m_c = 3e-14.
    #[test]
    fn third_kind_against_reference() {
        let text = include_str!("../../reference/special-reference.txt");
        let mut count = 0;
        for line in text.lines().filter(|l| l.starts_with("pi ")) {
            let v: Vec<f64> = line[3..]
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            let (n, m_c, want) = (v[0], v[1], v[2]);
            let got = complete_pi(n, m_c).unwrap();
            assert!(
                (got - want).abs() <= 4.0 * f64::EPSILON * want,
                "R_J form: Π({n} | m_c = {m_c}) = {got}, want {want}"
            );
            let k = complete_k(m_c).unwrap();
            // The AGM form is accurate in absolute terms of Π/K (what the propagator needs).
            let agm = pi_over_k(&Jacobi::new(m_c).unwrap(), n);
            let want_ratio = want / k;
            assert!(
                (agm - want_ratio).abs() <= 4.0 * f64::EPSILON * want_ratio.max(1.0),
                "AGM form: Π/K({n} | m_c = {m_c}) = {agm}, want {want_ratio}"
            );
            count += 1;
        }
        assert_eq!(count, 60);
    }

    #[test]
    fn agm_and_carlson_third_kind_agree() {
        for m_c in [1e-14, 1e-6, 0.1, 0.5, 0.9, 1.0] {
            let j = Jacobi::new(m_c).unwrap();
            let k = complete_k(m_c).unwrap();
            assert!(
                (j.quarter_period() - k).abs() <= 8e-16 * k,
                "{} vs {k}",
                j.quarter_period()
            );
            for n in [-1e6, -30.0, -1.0, -1e-8, 0.0, 0.3, 0.9] {
                let carlson = complete_pi(n, m_c).unwrap() / k;
                let agm = pi_over_k(&j, n);
                assert!(
                    (carlson - agm).abs() <= 2e-15 * carlson.abs().max(1.0),
                    "m_c {m_c} n {n}: {carlson} vs {agm}"
                );
            }
        }
    }
}
