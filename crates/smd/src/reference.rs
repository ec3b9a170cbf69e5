//! Published Lennard-Jones thermodynamics to check simulations against, and the correction
//! from a smoothed to the full potential.
//!
//! The equation of state of J. Kolafa and I. Nezbeda, "The Lennard-Jones fluid:
//! an accurate analytic and theoretically-based equation of state", Fluid Phase Equilibria 100,
//! 1–34 (1994), for the full (untruncated) 12-6 potential in reduced units (ε = σ = k = 1).
//!
//! The residual Helmholtz energy per particle is a hard-sphere term with the temperature-
//! dependent Barker–Henderson diameter `d(T)`, a second-virial correction that dies off as
//! `exp(−γρ²)`, and a double power series in `T^{-1/2}` and `ρ`:
//!
//! ```text
//! A_res/N = T [ A_HS(η)/NkT + ρ ΔB₂(T) e^{−γρ²} ] + Σ_ij C_ij T^{i/2} ρ^j,   η = (π/6) ρ d³
//! A_HS/NkT = (5/3) ln(1 − η) + η (34 − 33η + 4η²) / (6 (1 − η)²)
//! d(T) = Σ_i C_d,i T^{i/2} + C_ln ln T,    ΔB₂(T) = Σ_i C_B,i T^{i/2}
//! ```
//!
//! with the coefficients of the paper (its Table; transcribed below). Pressure and
//! configurational energy follow by differentiation, done here numerically (Richardson-
//! extrapolated central differences, ~1e-11 relative): `P = ρT + ρ² ∂(A_res/N)/∂ρ`,
//! `U/N = A_res/N − T ∂(A_res/N)/∂T`. [`self_check`] compares with values printed alongside
//! the SklogWiki Fortran transcription of the same equation, so a transcription slip here
//! fails the tests instead of moving the reference. Those printed values agree with this
//! code to 5·10⁻⁶ (relative) and no better: the Fortran writes its coefficients as default
//! (single-precision) literals, and evaluating that Fortran's formulas in double precision
//! reproduces this code to 10⁻¹². Either is three orders below the equation's own accuracy.

use potential::{LennardJones, Smoothed};

/// `(i, C)`: terms `C T^{i/2}` of the hBH diameter, plus `C_LN ln T`.
const D_TERMS: [(i32, f64); 4] = [
    (-2, 0.011_117_524),
    (-1, -0.076_383_859),
    (0, 1.080_142_248),
    (1, 0.000_693_129),
];
const D_LN: f64 = -0.063_920_968;

/// `(i, C)`: terms `C T^{i/2}` of ΔB₂ with respect to the hBH hard spheres.
const B2_TERMS: [(i32, f64); 7] = [
    (-7, -0.585_449_78),
    (-6, 0.431_020_52),
    (-5, 0.873_613_69),
    (-4, -4.137_499_95),
    (-3, 2.906_162_79),
    (-2, -7.021_819_62),
    (0, 0.024_598_77),
];

const GAMMA: f64 = 1.929_072_78;

/// `(i, j, C)`: terms `C T^{i/2} ρ^j` of the residual series.
const A_TERMS: [(i32, i32, f64); 19] = [
    (0, 2, 2.015_467_97),
    (0, 3, -28.178_816_36),
    (0, 4, 28.283_138_47),
    (0, 5, -10.424_028_73),
    (-1, 2, -19.583_716_55),
    (-1, 3, 75.623_402_89),
    (-1, 4, -120.705_865_98),
    (-1, 5, 93.927_403_28),
    (-1, 6, -27.377_373_54),
    (-2, 2, 29.344_705_20),
    (-2, 3, -112.353_569_37),
    (-2, 4, 170.649_089_80),
    (-2, 5, -123.066_691_87),
    (-2, 6, 34.422_889_69),
    (-4, 2, -13.370_319_68),
    (-4, 3, 65.380_595_70),
    (-4, 4, -115.092_331_13),
    (-4, 5, 88.919_730_82),
    (-4, 6, -25.620_998_90),
];

/// Residual Helmholtz energy per particle (units of ε).
pub fn helmholtz_residual(t: f64, rho: f64) -> f64 {
    let half = |i: i32| t.powf(f64::from(i) / 2.0);
    let d = D_TERMS.iter().map(|&(i, c)| c * half(i)).sum::<f64>() + D_LN * t.ln();
    let eta = std::f64::consts::PI / 6.0 * rho * d * d * d;
    let a_hs = 5.0 / 3.0 * (1.0 - eta).ln()
        + eta * (34.0 - 33.0 * eta + 4.0 * eta * eta) / (6.0 * (1.0 - eta) * (1.0 - eta));
    let db2: f64 = B2_TERMS.iter().map(|&(i, c)| c * half(i)).sum();
    let series: f64 = A_TERMS
        .iter()
        .map(|&(i, j, c)| c * half(i) * rho.powi(j))
        .sum();
    t * (a_hs + rho * db2 * (-GAMMA * rho * rho).exp()) + series
}

/// `df/dx` by central differences at steps `h` and `h/2`, Richardson-extrapolated.
fn derivative(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
    let c = |h: f64| (f(x + h) - f(x - h)) / (2.0 * h);
    (4.0 * c(0.5 * h) - c(h)) / 3.0
}

/// Pressure `P σ³/ε` at temperature `T*` and density `ρ*`.
pub fn pressure(t: f64, rho: f64) -> f64 {
    rho * t + rho * rho * derivative(|r| helmholtz_residual(t, r), rho, 1e-3)
}

/// Configurational energy per particle `U/Nε`.
pub fn energy(t: f64, rho: f64) -> f64 {
    helmholtz_residual(t, rho) - t * derivative(|s| helmholtz_residual(s, rho), t, 1e-3)
}

/// Values printed with the SklogWiki Fortran transcription of this equation of state ("a few
/// values for confidence, cp. Fig. 3 of the original paper"): `(T, ρ, U/N, P)`.
const CHECKS: [(f64, f64, f64, f64); 2] = [
    (1.3, 0.2, -1.537_151_127_739_686_8, 0.121_479_368_105_787_08),
    (1.3, 0.4, -2.806_016_725_054_152, 0.112_533_347_568_064_82),
];

/// Largest relative deviation from the printed check values (5·10⁻⁶: see the module text).
pub fn self_check() -> f64 {
    CHECKS
        .iter()
        .flat_map(|&(t, rho, u, p)| {
            [
                ((energy(t, rho) - u) / u).abs(),
                ((pressure(t, rho) - p) / p).abs(),
            ]
        })
        .fold(0.0, f64::max)
}

/// The first-order correction from the smoothed Lennard-Jones potential (003 Eq. 26, reduced
/// units) to the full one, per particle: `(ΔU/N, ΔP)` with
///
/// ```text
/// ΔU/N = 2πρ ∫ g(r) (u − u_s) r² dr,      ΔP = −(2π/3) ρ² ∫ g(r) r³ (u' − u_s') dr,
/// ```
///
/// `g` from `rdf` (rows of bin centre and value, equal widths, as [`Rdf::table`] gives them)
/// up to its last bin and 1 beyond, where `u_s = 0` and both integrals have a closed form. The
/// switch is C¹, so there is no impulsive (delta-function) term in the pressure. Exact to first
/// order in `u − u_s`: the structure of the smoothed fluid is taken for the full one's.
///
/// [`Rdf::table`]: crate::observe::Rdf::table
pub fn smoothing_correction(
    rdf: &[(f64, f64)],
    pot: &Smoothed<LennardJones>,
    rho: f64,
) -> (f64, f64) {
    let (eps, sigma) = (pot.inner().epsilon(), pot.inner().sigma());
    let (r_l, _) = pot.window();
    let u = |r: f64| 4.0 * eps * ((sigma / r).powi(12) - (sigma / r).powi(6));
    let du = |r: f64| 4.0 * eps * (-12.0 * (sigma / r).powi(12) + 6.0 * (sigma / r).powi(6)) / r;
    let width = match rdf {
        [a, b, ..] => b.0 - a.0,
        _ => 0.0,
    };
    let (mut iu, mut ip) = (0.0, 0.0);
    // Midpoint rule on 20 sub-bins per bin: the switch varies within a bin.
    let sub = 20;
    let h = width / f64::from(sub);
    for &(r, g) in rdf {
        if r + 0.5 * width <= r_l {
            continue;
        }
        for k in 0..sub {
            let x = r - 0.5 * width + (f64::from(k) + 0.5) * h;
            if x <= r_l {
                continue;
            }
            let (s, ds) = pot.switch(x);
            iu += g * (1.0 - s) * u(x) * x * x * h;
            ip += g * ((1.0 - s) * du(x) - ds * u(x)) * x * x * x * h;
        }
    }
    // Beyond the histogram: g = 1, u_s = 0, ∫_R^∞ u r² dr and ∫_R^∞ u' r³ dr in closed form.
    let big_r = rdf.last().map_or(pot.window().1, |b| b.0 + 0.5 * width);
    let (s3, s9) = ((sigma / big_r).powi(3), (sigma / big_r).powi(9));
    let s3v = sigma.powi(3);
    iu += 4.0 * eps * s3v * (s9 / 9.0 - s3 / 3.0);
    ip += 4.0 * eps * s3v * (-(4.0 / 3.0) * s9 + 2.0 * s3);
    let pi = std::f64::consts::PI;
    (2.0 * pi * rho * iu, -(2.0 * pi / 3.0) * rho * rho * ip)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_equation_of_state_reproduces_its_check_values() {
        assert!(self_check() < 1e-5, "{}", self_check());
        // Low density: U/N → 2πρ ∫ u e^{−u/T} r² dr (the second virial level), P → ρT.
        let p = pressure(2.0, 1e-6);
        assert!((p / 2e-6 - 1.0).abs() < 1e-5);
        // The state point of the validation.
        assert!((energy(2.0, 0.5) + 3.1501).abs() < 1e-4);
        assert!((pressure(2.0, 0.5) - 1.0739).abs() < 1e-4);
    }

    #[test]
    fn smoothing_correction_of_an_ideal_structure_is_the_closed_form() {
        // g = 1 everywhere: ΔU/N = 2πρ ∫_{r_l}^∞ (1 − s) u r² dr. With the switch moved far
        // out (r_l → r_u → large) this tends to the textbook tail 8πρ(1/(9R⁹) − 1/(3R³)).
        let pot = Smoothed::new(LennardJones::new(1.0, 1.0).unwrap(), 2.5, 3.0).unwrap();
        let rdf: Vec<(f64, f64)> = (0..500).map(|k| (0.005 + 0.01 * k as f64, 1.0)).collect();
        let (du, dp) = smoothing_correction(&rdf, &pot, 0.5);
        // Bounds: the tail beyond r_u and beyond r_l.
        let tail =
            |r: f64| 8.0 * std::f64::consts::PI * 0.5 * (r.powi(-9) / 9.0 - r.powi(-3) / 3.0);
        assert!(
            du < tail(3.0) && du > tail(2.5),
            "{du} {} {}",
            tail(3.0),
            tail(2.5)
        );
        // The pressure correction is negative (attractive tail), of the same order.
        let ptail = |r: f64| {
            16.0 / 3.0 * std::f64::consts::PI * 0.25 * (2.0 / 3.0 * r.powi(-9) - r.powi(-3))
        };
        assert!(dp < 0.0 && dp > 3.0 * ptail(2.5), "{dp} {}", ptail(2.5));
    }
}
