//! The theta series that gives the rotation angle ψ of an asymmetric top about `L`.
//!
//! With the nome `q`, `c_n = (−1)ⁿ q^{n(n+1)}` and the phase `x = πu/(2K)` (free-rigid-body.md
//! §(c), after van Zon & Schofield 2007):
//!
//! ```text
//! r(u) =  2 Σ c_n cosh((2n+1)η) sin((2n+1)x),     i(u) = −2 Σ c_n sinh((2n+1)η) cos((2n+1)x)
//! ```
//!
//! Only the direction of `(r, i)` enters ψ, so the common factor `2e^{|η|}` is dropped: the
//! coefficients become `P_n ± N_n` with `P_n = q^{n(n+1)} e^{2n|η|}` and
//! `N_n = q^{n(n+1)} e^{−(2n+2)|η|}`, built by multiplication (`P_n = P_{n−1} q^{2n} e^{2|η|}`),
//! so no `cosh` overflows however large `η` is, and no exponential is evaluated per term. Since
//! `|η| ≤ πK'/(2K)`, `P_n ≤ q^{n²}`: about 4 terms at `q = 0.1`, 12 near `m_c = 1e-14`, 50 at
//! `m_c = 1e-300`.

/// The series of one state: nome, `η`, and how many terms reach full precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ThetaSeries {
    q2: f64,
    e2: f64,
    e2_inv: f64,
    sign_eta: f64,
    terms: u32,
}

impl ThetaSeries {
    /// For the nome `q ∈ [0, 1)` and `η` (any sign).
    pub(crate) fn new(q: f64, eta: f64) -> Self {
        let h = eta.abs();
        let q2 = q * q;
        let e2 = (2.0 * h).exp();
        let mut s = Self {
            q2,
            e2,
            e2_inv: 1.0 / e2,
            sign_eta: if eta < 0.0 { -1.0 } else { 1.0 },
            terms: 1,
        };
        // Count the terms until P_n (≥ N_n) falls below 2⁻⁵⁸ of P_0 = 1.
        let (mut p, mut g) = (1.0_f64, 1.0_f64);
        while s.terms < 400 {
            g *= q2;
            p *= g * e2;
            if p < 3.5e-18 {
                break;
            }
            s.terms += 1;
        }
        s
    }

    /// How many terms an evaluation sums.
    #[inline]
    pub(crate) fn terms(&self) -> u32 {
        self.terms
    }

    /// `(r, i)` up to a common positive factor, from `sin x`, `cos x`.
    #[inline]
    pub(crate) fn eval(&self, sin_x: f64, cos_x: f64) -> (f64, f64) {
        let (s2, c2) = (2.0 * sin_x * cos_x, (cos_x - sin_x) * (cos_x + sin_x));
        let (mut sn, mut cn) = (sin_x, cos_x); // sin, cos of (2n+1)x
        let (mut p, mut nn, mut g) = (1.0_f64, self.e2_inv, 1.0_f64);
        let (mut r, mut i) = ((p + nn) * sn, (p - nn) * cn);
        let mut sign = 1.0_f64;
        for _ in 1..self.terms {
            g *= self.q2;
            p *= g * self.e2;
            nn *= g * self.e2_inv;
            (sn, cn) = (sn * c2 + cn * s2, cn * c2 - sn * s2);
            sign = -sign;
            r += sign * (p + nn) * sn;
            i += sign * (p - nn) * cn;
        }
        (r, -self.sign_eta * i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct evaluation of the defining sums with cosh/sinh and sin/cos per term.
    fn direct(q: f64, eta: f64, x: f64) -> (f64, f64) {
        let (mut r, mut i) = (0.0, 0.0);
        for n in 0..30 {
            let k = f64::from(2 * n + 1);
            let c = if n % 2 == 0 { 1.0 } else { -1.0 } * q.powi(n * (n + 1));
            r += 2.0 * c * (k * eta).cosh() * (k * x).sin();
            i -= 2.0 * c * (k * eta).sinh() * (k * x).cos();
        }
        (r, i)
    }

    #[test]
    fn matches_the_defining_sums() {
        for (q, eta) in [(0.1, 0.5), (0.3, -0.9), (0.7, 0.1), (0.01, 2.0)] {
            let t = ThetaSeries::new(q, eta);
            for x in [0.0_f64, 0.3, 1.7, -2.4, 40.0] {
                let (r, i) = t.eval(x.sin(), x.cos());
                let (rd, id) = direct(q, eta, x);
                // Same direction: cross product zero, dot product positive.
                let norm = (r * r + i * i).sqrt() * (rd * rd + id * id).sqrt();
                assert!(
                    (r * id - i * rd).abs() < 1e-14 * norm,
                    "q {q} eta {eta} x {x}"
                );
                assert!(r * rd + i * id > 0.0);
            }
        }
    }
}
