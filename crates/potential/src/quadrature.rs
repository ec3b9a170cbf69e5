//! Quadrature for the terrace rules and the virial coefficients: adaptive Gauss–Kronrod
//! (7-point Gauss, 15-point Kronrod) and fixed-order Gauss–Legendre.
//!
//! The G7–K15 nodes and weights are the published ones (R. Piessens, E. de Doncker-Kapenga,
//! C. W. Überhuber, D. K. Kahaner, *QUADPACK*, Springer 1983); a test checks that K15
//! integrates polynomials of degree 22 and G7 of degree 13 exactly, which any misprinted digit
//! would break. The adaptive driver bisects the subinterval with the largest error estimate
//! `|K15 − G7|` (an overestimate of the K15 error, which is what is returned) until the sum of
//! estimates is below `max(abs, rel·∫|f|)`: relative to the integral of `|f|`, so that an
//! integrand changing sign, whose integral may nearly cancel, still converges to the accuracy
//! its parts allow (for an integrand of one sign this is `rel·|I|`). Gauss–Legendre nodes come from Newton's method on the
//! three-term recurrence of `P_n`.

use std::collections::BinaryHeap;

use crate::PotentialError;

/// Kronrod abscissae on `[0, 1)`, descending; the odd-indexed ones are the Gauss nodes.
#[allow(clippy::excessive_precision)] // as published, 33 digits
const XGK: [f64; 8] = [
    0.991_455_371_120_812_639_206_854_697_526_329,
    0.949_107_912_342_758_524_526_189_684_047_851,
    0.864_864_423_359_769_072_789_712_788_640_926,
    0.741_531_185_599_394_439_863_864_773_280_788,
    0.586_087_235_467_691_130_294_144_845_693_013,
    0.405_845_151_377_397_166_906_606_412_076_961,
    0.207_784_955_007_898_467_600_689_403_773_245,
    0.0,
];
/// Kronrod weights for `XGK`.
#[allow(clippy::excessive_precision)] // as published, 33 digits
const WGK: [f64; 8] = [
    0.022_935_322_010_529_224_963_732_008_058_970,
    0.063_092_092_629_978_553_290_700_663_189_204,
    0.104_790_010_322_250_183_839_876_322_541_518,
    0.140_653_259_715_525_918_745_189_590_510_238,
    0.169_004_726_639_267_902_826_583_426_598_550,
    0.190_350_578_064_785_409_913_256_402_421_014,
    0.204_432_940_075_298_892_414_161_999_234_649,
    0.209_482_141_084_727_828_012_999_174_891_714,
];
/// Gauss weights for `XGK[1], XGK[3], XGK[5], XGK[7]`.
#[allow(clippy::excessive_precision)] // as published, 33 digits
const WG: [f64; 4] = [
    0.129_484_966_168_869_693_270_611_432_679_082,
    0.279_705_391_489_276_667_901_467_771_423_780,
    0.381_830_050_505_118_944_950_369_775_488_975,
    0.417_959_183_673_469_387_755_102_040_816_327,
];

/// Requested accuracy: the sum of the error estimates must fall below `max(abs, rel·∫|f|)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Absolute tolerance.
    pub abs: f64,
    /// Relative tolerance.
    pub rel: f64,
    /// Most subintervals before giving up.
    pub max_intervals: usize,
}

impl Default for Tolerance {
    /// `abs = 1e-300`, `rel = 1e-13`, 4000 subintervals.
    fn default() -> Self {
        Self {
            abs: 1e-300,
            rel: 1e-13,
            max_intervals: 4000,
        }
    }
}

/// An integral and its error estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Integral {
    /// The value (sum of the K15 results).
    pub value: f64,
    /// Sum of the `|K15 − G7|` estimates.
    pub error: f64,
    /// `∫|f|` (K15), the scale of the relative tolerance.
    pub magnitude: f64,
    /// Subintervals used.
    pub intervals: usize,
}

/// G7, K15 and K15 of `|f|` on `[a, b]`.
fn gk15(f: &mut impl FnMut(f64) -> f64, a: f64, b: f64) -> (f64, f64, f64) {
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let fc = f(c);
    let mut k = WGK[7] * fc;
    let mut g = WG[3] * fc;
    let mut m = WGK[7] * fc.abs();
    for (i, (&x, &w)) in XGK.iter().zip(&WGK).take(7).enumerate() {
        let (f1, f2) = (f(c - h * x), f(c + h * x));
        let pair = f1 + f2;
        k += w * pair;
        m += w * (f1.abs() + f2.abs());
        if i % 2 == 1 {
            g += WG[i / 2] * pair;
        }
    }
    (k * h, g * h, m * h.abs())
}

/// One subinterval in the adaptive queue, ordered by its error estimate.
#[derive(Clone, Copy, Debug)]
struct Piece {
    a: f64,
    b: f64,
    value: f64,
    error: f64,
    magnitude: f64,
}

impl PartialEq for Piece {
    fn eq(&self, other: &Self) -> bool {
        self.error.total_cmp(&other.error).is_eq()
    }
}
impl Eq for Piece {}
impl PartialOrd for Piece {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Piece {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.error.total_cmp(&other.error)
    }
}

/// `∫_a^b f(x) dx` by adaptive G7–K15.
///
/// # Errors
/// [`PotentialError::NotFinite`] for non-finite limits or a non-finite integrand value;
/// [`PotentialError::Quadrature`] if the tolerance is not met within `max_intervals`.
pub fn integrate(
    mut f: impl FnMut(f64) -> f64,
    a: f64,
    b: f64,
    tol: Tolerance,
) -> Result<Integral, PotentialError> {
    if !(a.is_finite() && b.is_finite()) {
        return Err(PotentialError::NotFinite("integration limit"));
    }
    if a == b {
        return Ok(Integral {
            value: 0.0,
            error: 0.0,
            magnitude: 0.0,
            intervals: 1,
        });
    }
    let piece = |f: &mut dyn FnMut(f64) -> f64, a: f64, b: f64| {
        let (k, g, m) = gk15(&mut |x| f(x), a, b);
        Piece {
            a,
            b,
            value: k,
            error: (k - g).abs(),
            magnitude: m,
        }
    };
    let first = piece(&mut f, a, b);
    let (mut value, mut error, mut magnitude) = (first.value, first.error, first.magnitude);
    let mut heap = BinaryHeap::from([first]);
    loop {
        if !(value.is_finite() && error.is_finite()) {
            return Err(PotentialError::NotFinite("integrand"));
        }
        let goal = tol.abs.max(tol.rel * magnitude);
        if error <= goal {
            break;
        }
        if heap.len() >= tol.max_intervals {
            return Err(PotentialError::Quadrature {
                error,
                tolerance: goal,
                intervals: heap.len(),
            });
        }
        let worst = heap.pop().expect("the heap is never empty");
        let mid = 0.5 * (worst.a + worst.b);
        if mid <= worst.a.min(worst.b) || mid >= worst.a.max(worst.b) {
            // The interval cannot be split in binary64: accept what we have.
            heap.push(worst);
            break;
        }
        let (l, r) = (piece(&mut f, worst.a, mid), piece(&mut f, mid, worst.b));
        // Re-sum rather than update, so rounding never accumulates across thousands of splits.
        heap.push(l);
        heap.push(r);
        value = heap.iter().map(|p| p.value).sum();
        error = heap.iter().map(|p| p.error).sum();
        magnitude = heap.iter().map(|p| p.magnitude).sum();
    }
    Ok(Integral {
        value,
        error,
        magnitude,
        intervals: heap.len(),
    })
}

/// `∫_a^∞ f(x) dx`, mapped to `t ∈ (0, 1]` by `x = a + (1 − t)/t` (`dx = dt/t²`); the map
/// never evaluates `t = 0`. Suited to integrands decaying at least like `x⁻²`.
///
/// # Errors
/// As [`integrate`].
pub fn integrate_to_infinity(
    mut f: impl FnMut(f64) -> f64,
    a: f64,
    tol: Tolerance,
) -> Result<Integral, PotentialError> {
    if !a.is_finite() {
        return Err(PotentialError::NotFinite("integration limit"));
    }
    integrate(
        |t| {
            let x = a + (1.0 - t) / t;
            f(x) / (t * t)
        },
        0.0,
        1.0,
        tol,
    )
}

/// An `n`-point Gauss–Legendre rule on `[-1, 1]`, exact for polynomials of degree `2n − 1`.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// The rule with `n ≥ 1` points (nodes ascending).
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] for `n = 0` or `n > 1000`.
    pub fn new(n: usize) -> Result<Self, PotentialError> {
        if n == 0 || n > 1000 {
            return Err(PotentialError::Parameter {
                name: "n",
                value: n as f64,
                why: "between 1 and 1000",
            });
        }
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        let nf = n as f64;
        for i in 0..n.div_ceil(2) {
            // Tricomi's initial guess for the i-th largest root, then Newton.
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() <= 1e-16 * x.abs().max(1e-3) {
                    break;
                }
            }
            let (_, d) = legendre(n, x);
            if d != 0.0 {
                dp = d;
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[n - 1 - i] = x;
            nodes[i] = -x;
            weights[n - 1 - i] = w;
            weights[i] = w;
        }
        if n % 2 == 1 {
            nodes[n / 2] = 0.0;
        }
        Ok(Self { nodes, weights })
    }

    /// Nodes on `[-1, 1]`, ascending.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Weights, in the order of the nodes.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// `∫_a^b f(x) dx` by the rule.
    pub fn integrate(&self, mut f: impl FnMut(f64) -> f64, a: f64, b: f64) -> f64 {
        let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
        h * self
            .nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| w * f(c + h * x))
            .sum::<f64>()
    }
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    if n == 0 {
        return (1.0, 0.0);
    }
    let d = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kronrod_and_gauss_degrees_of_exactness() {
        for k in 0..=24u32 {
            let exact = if k % 2 == 0 {
                2.0 / (k as f64 + 1.0)
            } else {
                0.0
            };
            let (kr, g, _) = gk15(&mut |x: f64| x.powi(k as i32), -1.0, 1.0);
            if k <= 22 {
                assert!((kr - exact).abs() < 4e-16, "K15, x^{k}: {kr} vs {exact}");
            } else if k % 2 == 0 {
                // (Odd powers vanish by symmetry for any symmetric rule.)
                assert!(
                    (kr - exact).abs() > 1e-12,
                    "K15 should not be exact for x^{k}"
                );
            }
            if k <= 13 {
                assert!((g - exact).abs() < 4e-16, "G7, x^{k}");
            } else if k % 2 == 0 {
                assert!((g - exact).abs() > 1e-6, "G7 should not be exact for x^{k}");
            }
        }
    }

    #[test]
    fn adaptive_integrals_against_closed_forms() {
        let t = Tolerance::default();
        let i = integrate(f64::sin, 0.0, std::f64::consts::PI, t).unwrap();
        assert!((i.value - 2.0).abs() < 1e-14);
        // A peaked integrand: ∫₀¹ 1/(10⁻⁴ + x²) = 100 atan(100).
        let i = integrate(|x| 1.0 / (1e-4 + x * x), 0.0, 1.0, t).unwrap();
        assert!((i.value - 100.0 * 100f64.atan()).abs() < 1e-12 * i.value);
        assert!(i.intervals > 5);
        // ∫₀^∞ e^{−x} = 1, ∫₁^∞ x⁻⁴ = 1/3, ∫₀^∞ x² e^{−x²} = √π/4.
        let i = integrate_to_infinity(|x| (-x).exp(), 0.0, t).unwrap();
        assert!((i.value - 1.0).abs() < 1e-14);
        let i = integrate_to_infinity(|x| x.powi(-4), 1.0, t).unwrap();
        assert!((i.value - 1.0 / 3.0).abs() < 1e-15);
        let i = integrate_to_infinity(|x| x * x * (-x * x).exp(), 0.0, t).unwrap();
        assert!((i.value - std::f64::consts::PI.sqrt() / 4.0).abs() < 1e-14);
        // A sign change whose integral nearly cancels, ∫_{-1}^{1.000001} x dx = 1.0000005e-6:
        // converges, to the accuracy the parts allow (round-off of ∫|x| ≈ 1).
        let i = integrate(|x| x, -1.0, 1.000_001, t).unwrap();
        assert!((i.value - 1.000_000_5e-6).abs() < 1e-15, "{}", i.value);
        // (∫|f| is only a scale: K15 of |x| across its kink, not converged.)
        assert!((i.magnitude - 1.0).abs() < 0.1);
        // Reversed limits change the sign.
        let i = integrate(|x| x * x, 2.0, 0.0, t).unwrap();
        assert!((i.value + 8.0 / 3.0).abs() < 1e-14);
    }

    #[test]
    fn failures_are_errors() {
        let t = Tolerance {
            max_intervals: 10,
            ..Tolerance::default()
        };
        assert!(matches!(
            integrate(|x: f64| x.sin() * 1e3 * (1e3 * x).cos(), 0.0, 100.0, t),
            Err(PotentialError::Quadrature { .. })
        ));
        assert!(integrate(|x| 1.0 / x, 0.0, 1.0, Tolerance::default()).is_err());
        assert!(integrate(|x| x, 0.0, f64::INFINITY, Tolerance::default()).is_err());
    }

    #[test]
    fn gauss_legendre_is_exact_to_degree_2n_minus_1() {
        for n in [1usize, 2, 5, 20, 64] {
            let rule = GaussLegendre::new(n).unwrap();
            assert!((rule.weights().iter().sum::<f64>() - 2.0).abs() < 1e-14);
            let k = 2 * n - 2; // even, the hardest exact degree
            let got = rule.integrate(|x| x.powi(k as i32), -1.0, 1.0);
            let exact = 2.0 / (k as f64 + 1.0);
            assert!((got - exact).abs() < 1e-14, "n = {n}: {got} vs {exact}");
        }
        let rule = GaussLegendre::new(20).unwrap();
        let e = rule.integrate(f64::exp, 0.0, 1.0);
        assert!((e - (1f64.exp() - 1.0)).abs() < 1e-15);
        assert!(GaussLegendre::new(0).is_err());
    }
}
