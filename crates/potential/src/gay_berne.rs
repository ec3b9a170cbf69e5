//! The Gay–Berne potential between uniaxial bodies.
//!
//! J. G. Gay and B. J. Berne, "Modification of the overlap potential to mimic a linear
//! site-site potential", J. Chem. Phys. 74, 3316 (1981), in the form with general exponents
//! `μ`, `ν` used in liquid-crystal simulation; we took the formula as written out in
//! D. Andrienko's lecture "Introduction to liquid crystals" (IMPRS school, Bad Marienberg; the
//! Gay–Berne slide, Eq. 3) and checked `χ`, `χ'` against the SklogWiki "Gay-Berne model" page.
//! With `r̂ = r_ij/r`, `a = r̂·s_i`, `b = r̂·s_j`, `c = s_i·s_j`:
//!
//! ```text
//! U     = 4 ε(r̂, s_i, s_j) [ ρ¹² − ρ⁶ ],     ρ = σ₀ / (r − σ(r̂, s_i, s_j) + σ₀)
//! σ     = σ₀ [1 − (χ/2) H_χ]^{−1/2},          H_χ = (a + b)²/(1 + χc) + (a − b)²/(1 − χc)
//! ε     = ε₀ ε₁^ν ε₂^μ,   ε₁ = (1 − χ²c²)^{−1/2},   ε₂ = 1 − (χ'/2) H_χ'
//! χ     = (κ² − 1)/(κ² + 1),   χ' = (κ'^{1/μ} − 1)/(κ'^{1/μ} + 1)
//! ```
//!
//! `κ = σ_e/σ_s` is the length-to-breadth ratio and `κ' = ε_s/ε_e` the ratio of the
//! side-by-side to the end-to-end well depth. For the standard GB(3, 5, 2, 1) (`κ = 3`,
//! `κ' = 5`, `μ = 2`, `ν = 1`): contact distances `σ₀` (side by side, crossed), `√5 σ₀` (T),
//! `3σ₀` (end to end); well depths `5/3 ε₀` (side by side), `ε₀` (crossed),
//! `(2/(1 + √5))² ε₀ ≈ 0.382 ε₀` (T), `1/3 ε₀` (end to end).
//!
//! The derivatives are ours: with `G_q = ∂U/∂q` at fixed `r` for `q = a, b, c`,
//!
//! ```text
//! G_q = U ∂ln ε/∂q − U_R ∂σ/∂q,            U_R = 4ε dL/dR = −24ε ρ⁶(2ρ⁶ − 1)/R,
//! ∂σ/∂q = (χ/4) (σ/(1 − χH_χ/2)) ∂H_χ/∂q,   ∂ln ε/∂q = ν ∂ln ε₁/∂q − (μχ'/2ε₂) ∂H_χ'/∂q,
//! ∂H/∂a = 2(a+b)/(1+χc) + 2(a−b)/(1−χc),    ∂H/∂b = 2(a+b)/(1+χc) − 2(a−b)/(1−χc),
//! ∂H/∂c = −χ(a+b)²/(1+χc)² + χ(a−b)²/(1−χc)²,  ∂ln ε₁/∂c = χ²c/(1 − χ²c²),
//! ```
//!
//! and the chain rule through `a = x_i/r`, `b = x_j/r` gives the [`Partials`]:
//! `∂U/∂r = U_R − (a G_a + b G_b)/r`, `∂U/∂x_i = G_a/r`, `∂U/∂x_j = G_b/r`, `∂U/∂c = G_c`.

use crate::error::{non_negative, positive};
use crate::pair::{Invariants, Partials, assemble, overlap};
use crate::{PairEval, PairGeometry, PairPotential, PotentialError};

/// An exponent stored so that the common integer values cost a multiplication, not a `powf`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Exponent {
    Zero,
    One,
    Two,
    Int(i32),
    Real(f64),
}

impl Exponent {
    fn new(p: f64) -> Self {
        match p {
            0.0 => Self::Zero,
            1.0 => Self::One,
            2.0 => Self::Two,
            _ if p.fract() == 0.0 && p.abs() <= 64.0 => Self::Int(p as i32),
            _ => Self::Real(p),
        }
    }

    #[inline]
    fn pow(self, x: f64) -> f64 {
        match self {
            Self::Zero => 1.0,
            Self::One => x,
            Self::Two => x * x,
            Self::Int(n) => x.powi(n),
            Self::Real(p) => x.powf(p),
        }
    }
}

/// The Gay–Berne potential (module documentation for the formula and its source).
///
/// `+∞` where `r − σ(r̂, s_i, s_j) + σ₀ ≤ 0` (the bodies are inside each other beyond the
/// shifted Lennard-Jones core) and at `r = 0`; `evaluate` then returns
/// [`PotentialError::Overlap`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GayBerne {
    sigma0: f64,
    epsilon0: f64,
    kappa: f64,
    kappa_prime: f64,
    mu: f64,
    nu: f64,
    chi: f64,
    chi_prime: f64,
    pow_mu: Exponent,
    pow_nu: Exponent,
}

impl Default for GayBerne {
    /// The standard GB(3, 5, 2, 1) with `σ₀ = ε₀ = 1`.
    fn default() -> Self {
        Self::new(1.0, 1.0, 3.0, 5.0, 2.0, 1.0).expect("GB(3, 5, 2, 1) is valid")
    }
}

impl GayBerne {
    /// `σ₀` (breadth), `ε₀` (energy scale), `κ = σ_e/σ_s` (shape anisotropy: `> 1` for rods,
    /// `< 1` for discs), `κ' = ε_s/ε_e` (energy anisotropy), and the exponents `μ > 0` and
    /// `ν ≥ 0`.
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] unless `σ₀`, `ε₀`, `κ`, `κ'`, `μ` are finite and
    /// positive and `ν` finite and non-negative.
    pub fn new(
        sigma0: f64,
        epsilon0: f64,
        kappa: f64,
        kappa_prime: f64,
        mu: f64,
        nu: f64,
    ) -> Result<Self, PotentialError> {
        let sigma0 = positive("sigma0", sigma0)?;
        let epsilon0 = positive("epsilon0", epsilon0)?;
        let kappa = positive("kappa", kappa)?;
        let kappa_prime = positive("kappa_prime", kappa_prime)?;
        let mu = positive("mu", mu)?;
        let nu = non_negative("nu", nu)?;
        let k2 = kappa * kappa;
        let chi = (k2 - 1.0) / (k2 + 1.0);
        let kp = kappa_prime.powf(1.0 / mu);
        let chi_prime = (kp - 1.0) / (kp + 1.0);
        // |χ| < 1 and |χ'| < 1 keep every denominator positive; extreme ratios round them to
        // ±1, which the formula cannot take.
        if chi.is_nan() || chi.abs() >= 1.0 {
            return Err(PotentialError::Parameter {
                name: "kappa",
                value: kappa,
                why: "a ratio whose chi = (kappa^2 - 1)/(kappa^2 + 1) stays below 1 in binary64",
            });
        }
        if chi_prime.is_nan() || chi_prime.abs() >= 1.0 {
            return Err(PotentialError::Parameter {
                name: "kappa_prime",
                value: kappa_prime,
                why: "a ratio whose chi' = (kappa'^(1/mu) - 1)/(kappa'^(1/mu) + 1) stays below 1 in binary64",
            });
        }
        Ok(Self {
            sigma0,
            epsilon0,
            kappa,
            kappa_prime,
            mu,
            nu,
            chi,
            chi_prime,
            pow_mu: Exponent::new(mu),
            pow_nu: Exponent::new(nu),
        })
    }

    /// `σ₀`.
    pub fn sigma0(&self) -> f64 {
        self.sigma0
    }

    /// `ε₀`.
    pub fn epsilon0(&self) -> f64 {
        self.epsilon0
    }

    /// `(κ, κ', μ, ν)`.
    pub fn shape(&self) -> (f64, f64, f64, f64) {
        (self.kappa, self.kappa_prime, self.mu, self.nu)
    }

    /// `(χ, χ')`.
    pub fn chi(&self) -> (f64, f64) {
        (self.chi, self.chi_prime)
    }

    /// The orientation-dependent contact distance `σ(r̂, s_i, s_j)` and well depth
    /// `ε(r̂, s_i, s_j)` for `a = r̂·s_i`, `b = r̂·s_j`, `c = s_i·s_j`.
    #[inline]
    pub fn contact_and_depth(&self, a: f64, b: f64, c: f64) -> (f64, f64) {
        let t = self.shape_terms(a, b, c);
        (t.sigma, t.eps)
    }

    /// The orientation-dependent factors, computed one way for the energy and the derivatives
    /// alike, so that `energy` and `evaluate` agree bit for bit.
    #[inline]
    fn shape_terms(&self, a: f64, b: f64, c: f64) -> Shape {
        let (chi, chp) = (self.chi, self.chi_prime);
        let (sp, sm) = (a + b, a - b);
        let (psp, psm) = (sp / (1.0 + chi * c), sm / (1.0 - chi * c));
        let (psp_p, psm_p) = (sp / (1.0 + chp * c), sm / (1.0 - chp * c));
        let h = sp * psp + sm * psm;
        let hp = sp * psp_p + sm * psm_p;
        let q = 1.0 - 0.5 * chi * h;
        let w1 = 1.0 - chi * chi * c * c;
        let e2 = 1.0 - 0.5 * chp * hp;
        Shape {
            psp,
            psm,
            psp_p,
            psm_p,
            q,
            w1,
            e2,
            sigma: self.sigma0 / q.sqrt(),
            eps: self.epsilon0 * self.pow_nu.pow(1.0 / w1.sqrt()) * self.pow_mu.pow(e2),
        }
    }

    /// `(U, ρ⁶, R, shape)` from the invariants; `None` where `U` is infinite.
    #[inline]
    fn energy_terms(&self, inv: &Invariants) -> Option<(f64, f64, f64, Shape)> {
        let r = inv.r;
        if r.is_nan() || r <= 0.0 {
            return None;
        }
        let t = self.shape_terms(inv.x_i / r, inv.x_j / r, inv.c);
        let big_r = r - t.sigma + self.sigma0;
        if big_r.is_nan() || big_r <= 0.0 {
            return None;
        }
        let rho = self.sigma0 / big_r;
        let rho2 = rho * rho;
        let rho6 = rho2 * rho2 * rho2;
        Some((4.0 * t.eps * rho6 * (rho6 - 1.0), rho6, big_r, t))
    }

    /// `U` and its [`Partials`] from the invariants; `None` where `U` is infinite.
    #[inline]
    fn partials(&self, inv: &Invariants) -> Option<Partials> {
        let (energy, rho6, big_r, t) = self.energy_terms(inv)?;
        let r = inv.r;
        let (a, b, c) = (inv.x_i / r, inv.x_j / r, inv.c);
        let (chi, chp) = (self.chi, self.chi_prime);
        let u_big_r = -24.0 * t.eps * rho6 * (2.0 * rho6 - 1.0) / big_r;
        // ∂H/∂(a, b, c) for χ and χ'.
        let (h_a, h_b) = (2.0 * (t.psp + t.psm), 2.0 * (t.psp - t.psm));
        let h_c = chi * (t.psm * t.psm - t.psp * t.psp);
        let (hp_a, hp_b) = (2.0 * (t.psp_p + t.psm_p), 2.0 * (t.psp_p - t.psm_p));
        let hp_c = chp * (t.psm_p * t.psm_p - t.psp_p * t.psp_p);
        // ∂σ/∂H and ∂ln ε/∂H', ∂ln ε₁^ν/∂c.
        let dsigma = 0.25 * chi * t.sigma / t.q;
        let dlne = -0.5 * self.mu * chp / t.e2;
        let dlne_c = self.nu * chi * chi * c / t.w1;
        let g_a = energy * dlne * hp_a - u_big_r * dsigma * h_a;
        let g_b = energy * dlne * hp_b - u_big_r * dsigma * h_b;
        let g_c = energy * (dlne * hp_c + dlne_c) - u_big_r * dsigma * h_c;
        Some(Partials {
            energy,
            d_r: u_big_r - (a * g_a + b * g_b) / r,
            d_xi: g_a / r,
            d_xj: g_b / r,
            d_c: g_c,
        })
    }
}

/// The orientation-dependent intermediate results of the Gay–Berne potential.
#[derive(Clone, Copy, Debug)]
struct Shape {
    /// `(a + b)/(1 + χc)`, `(a − b)/(1 − χc)` and the same with `χ'`.
    psp: f64,
    psm: f64,
    psp_p: f64,
    psm_p: f64,
    /// `1 − χH/2`, `1 − χ²c²`, `ε₂`.
    q: f64,
    w1: f64,
    e2: f64,
    sigma: f64,
    eps: f64,
}

impl PairPotential for GayBerne {
    #[inline]
    fn energy(&self, g: &PairGeometry) -> f64 {
        self.energy_terms(&g.invariants())
            .map_or(f64::INFINITY, |(u, ..)| u)
    }

    #[inline]
    fn evaluate(&self, g: &PairGeometry) -> Result<PairEval, PotentialError> {
        let inv = g.invariants();
        match self.partials(&inv) {
            Some(p) => assemble(g, &inv, &p),
            None => Err(overlap(
                g,
                inv.r,
                "r - sigma(orientation) + sigma0 <= 0 or r = 0",
            )),
        }
    }

    /// `−ε₀ (1 − χ²)^{−ν/2} max(1, 1/κ')`: the side-by-side well for `κ' ≥ 1` (both `ε₁` and
    /// `ε₂` are largest for parallel axes perpendicular to `r̂`), the end-to-end one for
    /// `κ' < 1` (then `ε₂` is largest for parallel axes along `r̂`, where `ε₂^μ = 1/κ'`).
    fn minimum(&self) -> f64 {
        let e1 = 1.0 / (1.0 - self.chi * self.chi).sqrt();
        -self.epsilon0 * self.pow_nu.pow(e1) * (1.0f64).max(1.0 / self.kappa_prime)
    }

    fn length_scale(&self) -> f64 {
        self.sigma0 * self.kappa.max(1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn gb() -> GayBerne {
        GayBerne::default()
    }

    /// (r̂ along x) side by side, crossed, T and end to end.
    fn configs() -> [(&'static str, DVec3, DVec3, f64, f64); 4] {
        let golden = 2.0 / (1.0 + 5f64.sqrt());
        [
            ("side by side", DVec3::Z, DVec3::Z, 1.0, 5.0 / 3.0),
            ("crossed", DVec3::Z, DVec3::Y, 1.0, 1.0),
            ("T", DVec3::X, DVec3::Z, 5f64.sqrt(), golden * golden),
            ("end to end", DVec3::X, DVec3::X, 3.0, 1.0 / 3.0),
        ]
    }

    #[test]
    fn contact_distances_and_well_depths_of_gb_3_5_2_1() {
        let gb = gb();
        let shift = 2f64.powf(1.0 / 6.0) - 1.0;
        for (name, si, sj, contact, depth) in configs() {
            let at = |r: f64| gb.energy(&PairGeometry::new(DVec3::X * r, si, sj));
            assert!(
                at(contact).abs() < 1e-14,
                "{name}: U(contact) = {}",
                at(contact)
            );
            let r_min = contact + shift;
            assert!(
                (at(r_min) + depth).abs() < 1e-14 * depth,
                "{name}: {}",
                at(r_min)
            );
            let e = gb
                .evaluate(&PairGeometry::new(DVec3::X * r_min, si, sj))
                .unwrap();
            assert!(e.force.length() < 1e-12, "{name}: force at the minimum");
        }
        assert!((gb.minimum() + 5.0 / 3.0).abs() < 1e-15);
    }

    #[test]
    fn isotropic_parameters_reduce_to_lennard_jones() {
        let gb = GayBerne::new(1.2, 0.8, 1.0, 1.0, 2.0, 1.0).unwrap();
        let lj = crate::LennardJones::new(0.8, 1.2).unwrap();
        let g = PairGeometry::new(
            DVec3::new(0.9, 1.1, -0.3),
            DVec3::Y,
            DVec3::new(0.6, 0.0, 0.8),
        );
        let (u, v) = (gb.energy(&g), lj.energy(&g));
        assert!((u - v).abs() <= 4.0 * f64::EPSILON * v.abs());
        let (a, b) = (gb.evaluate(&g).unwrap(), lj.evaluate(&g).unwrap());
        assert!((a.force - b.force).length() <= 1e-14 * b.force.length());
        assert!(a.torque_i.length() <= 1e-14 * b.force.length());
    }

    #[test]
    fn inside_the_core_is_infinite() {
        let gb = gb();
        // End to end at r = 2 < 3σ₀ − σ₀: R = 2 − 3 + 1 = 0.
        let g = PairGeometry::new(DVec3::X * 2.0, DVec3::X, DVec3::X);
        assert_eq!(gb.energy(&g), f64::INFINITY);
        assert!(gb.evaluate(&g).is_err());
        let g = PairGeometry::new(DVec3::X * 1.5, DVec3::X, DVec3::X);
        assert_eq!(gb.energy(&g), f64::INFINITY);
        let g = PairGeometry::new(DVec3::ZERO, DVec3::X, DVec3::Y);
        assert_eq!(gb.energy(&g), f64::INFINITY);
        assert!(gb.evaluate(&g).is_err());
    }

    #[test]
    fn bad_parameters_are_named() {
        for (i, name) in ["sigma0", "epsilon0", "kappa", "kappa_prime", "mu"]
            .iter()
            .enumerate()
        {
            let mut p = [1.0, 1.0, 3.0, 5.0, 2.0, 1.0];
            p[i] = -1.0;
            let e = GayBerne::new(p[0], p[1], p[2], p[3], p[4], p[5]).unwrap_err();
            assert!(e.to_string().contains(name), "{e}");
        }
        assert!(GayBerne::new(1.0, 1.0, 3.0, 5.0, 2.0, -1.0).is_err());
        assert!(GayBerne::new(1.0, 1.0, 1e200, 5.0, 2.0, 1.0).is_err());
    }

    #[test]
    fn oblate_and_weak_end_parameters_have_the_right_minimum() {
        // κ' < 1: the end-to-end well is the deepest.
        let gb = GayBerne::new(1.0, 1.0, 3.0, 0.5, 1.0, 2.0).unwrap();
        let (chi, _) = gb.chi();
        let ee = -(1.0 / (1.0 - chi * chi)) * 2.0;
        assert!((gb.minimum() - ee).abs() < 1e-14);
        let r_min = 3.0 + 2f64.powf(1.0 / 6.0) - 1.0;
        let u = gb.energy(&PairGeometry::new(DVec3::X * r_min, DVec3::X, DVec3::X));
        assert!((u - ee).abs() < 1e-13);
    }
}
