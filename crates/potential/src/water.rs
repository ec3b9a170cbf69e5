//! Soft sticky dipole water: SSD/E (C. J. Fennell and J. D. Gezelter, J. Chem. Phys. 120,
//! 9175 (2004), "FG04"), a single-site rigid water model.
//!
//! **Units** (the molecular units of the rods): energy kJ/mol, length Å, mass amu (g/mol), time
//! ps, so that `1 kJ/mol = 100 amu Å²/ps²`; dipoles are given in debye and enter the energy
//! through `(1 D)²/(4πε₀ Å³) = N_A·10⁻¹⁹ J = 60.221 407 6 kJ/mol`. The published kcal/mol values
//! are converted with `1 kcal = 4.184 kJ`.
//!
//! **Body frame.** `ẑ` is the dipole axis, pointing from the oxygen towards the hydrogens (the
//! positive end); the hydrogens lie in the `yz` plane at `z > 0`, the lone pairs in the `xz`
//! plane at `z < 0`. These are the principal axes of the inertia tensor
//! ([`SoftStickyDipole::INERTIA`]: the largest moment about `x`, normal to the molecular plane,
//! the smallest about `y`, parallel to the H–H line).
//!
//! **The pair energy** (FG04 Eqs. 1–5, the SSD form of Liu and Ichiye with Chandra and Ichiye's
//! `w'`):
//!
//! ```text
//! U = g(r) [u_LJ(r) + u_dp] + u_sp
//! u_LJ = 4ε[(σ/r)¹² − (σ/r)⁶]
//! u_dp = μ²[ẑ_i·ẑ_j − 3(ẑ_i·r̂)(ẑ_j·r̂)]/r³                     (point dipoles along ẑ)
//! u_sp = (ν₀/2)[s(r) w + s'(r) w']
//! w    = sin θ_ij sin 2θ_ij cos 2φ_ij + sin θ_ji sin 2θ_ji cos 2φ_ji
//!      = Σ_a 2 z_a (x_a² − y_a²)/r³
//! w'   = Σ_a (cos θ_a − 0.6)² (cos θ_a + 0.8)² − 2w₀,  cos θ_a = z_a/r
//! ```
//!
//! where `(x_a, y_a, z_a)` are the body-frame coordinates of the other molecule as seen from
//! molecule `a` (`θ_ij`, `φ_ij` the polar angles of `r_j − r_i` in the frame of `i`). `w` is a
//! tetrahedral function: it is most negative, `−4/(3√3)` per molecule, when the partner sits in
//! a hydrogen direction (`yz` plane, `cos θ = 1/√3`) or in a lone-pair direction (`xz` plane,
//! `cos θ = −1/√3`), and `|w| ≤ 8/(3√3)` always. `w'` corrects the tetrahedral angles. The
//! sticky switches `s` and `s'` are the cubic of 003 Eq. 26, `(r_U − r)²(r_U + 2r − 3r_L)/
//! (r_U − r_L)³` between `r_L` and `r_U` (1 inside, 0 outside), with their own windows.
//!
//! **Cut-off (our choice, stated).** SSD/E is the variant parameterised *without* a reaction
//! field or any other long-range correction of the dipoles (FG04; SSD/RF is the reaction-field
//! variant), with a spherical cut-off of 9 Å. A bare truncation makes `U` jump, which a terraced
//! potential cannot use, so [`SoftStickyDipole::ssd_e`] multiplies the Lennard-Jones and
//! dipolar terms by the cubic switch `g(r)` of 003 Eq. 26 between `r_sw = 7.65 Å` (0.85 r_c)
//! and `r_c = 9 Å`, as [`Smoothed`](crate::Smoothed) does for the rods: `U` and its first
//! derivatives are continuous and `U ≡ 0` for `r ≥ r_c` (the sticky term ends at
//! `max(r_U, r_U') < r_c`). Other windows through [`SsdParameters`].
//!
//! **Bounds for the terrace map.** With `|u_dp| ≤ 2μ²/r³`, `|w| ≤ 8/(3√3)` and
//! `−2w₀ ≤ w' ≤ 2·0.5184 − 2w₀` (`(c − 0.6)²(c + 0.8)²` is at most `0.5184`, at `c = 1`),
//! `U(r, Ω)` lies between two functions of `r` alone. [`RigidPairPotential::minimum`] is the
//! minimum of the lower one (a rigorous lower bound, loose because the dipolar and sticky
//! optima are incompatible), and [`RigidPairPotential::reach`] bisects monotone envelopes of
//! the two (the repulsion dropped from the lower one), so it is an upper bound on the true
//! reach.

use glam::{DQuat, DVec3};

use crate::certify::{Rates, RigidFlight, TaylorModel};
use crate::error::{non_negative, positive};
use crate::lennard_jones::energy_and_virial;
use crate::pair::{Invariants, Partials, assemble};
use crate::rigid::{RigidGeometry, RigidPairPotential};
use crate::solve::golden_min;
use crate::{PairEval, PairGeometry, PotentialError};

/// `(1 D)²/(4πε₀ Å³)` in kJ/mol.
pub const DEBYE2_PER_A3: f64 = 60.221_407_6;

/// `1 kcal/mol` in kJ/mol.
pub const KCAL: f64 = 4.184;

/// `(c − 0.6)²(c + 0.8)²` and its derivative in `c`: the angular part of `w'`.
#[inline]
fn w_prime_part(c: f64) -> (f64, f64) {
    let (a, b) = (c - 0.6, c + 0.8);
    (a * a * b * b, 2.0 * a * b * (a + b))
}

/// Largest value of [`w_prime_part`] on `[−1, 1]` (at `c = 1`; the local maximum at
/// `c = −0.1` is `0.2401`).
const W_PRIME_PART_MAX: f64 = 0.5184;

/// `max |w|`, `2 · 4/(3√3)`.
const W_MAX: f64 = 1.539_600_717_839_002;

/// The cubic switch of 003 Eq. 26 on `[lo, hi]`: `(value, derivative)`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cubic {
    lo: f64,
    hi: f64,
    inv_w3: f64,
}

impl Cubic {
    fn new(
        lo_name: &'static str,
        lo: f64,
        hi_name: &'static str,
        hi: f64,
    ) -> Result<Self, PotentialError> {
        let lo = positive(lo_name, lo)?;
        let hi = positive(hi_name, hi)?;
        if hi <= lo {
            return Err(PotentialError::Parameter {
                name: hi_name,
                value: hi,
                why: "larger than the inner radius of its switch",
            });
        }
        let w = hi - lo;
        Ok(Self {
            lo,
            hi,
            inv_w3: 1.0 / (w * w * w),
        })
    }

    #[inline]
    fn eval(&self, r: f64) -> (f64, f64) {
        if r <= self.lo {
            (1.0, 0.0)
        } else if r >= self.hi {
            (0.0, 0.0)
        } else {
            let (du, dl) = (self.hi - r, r - self.lo);
            (
                du * du * (self.hi - 3.0 * self.lo + 2.0 * r) * self.inv_w3,
                -6.0 * du * dl * self.inv_w3,
            )
        }
    }
}

/// The parameters of a soft sticky dipole model, in kJ/mol, Å and debye (module documentation
/// for the form they enter).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SsdParameters {
    /// Lennard-Jones well depth `ε` (kJ/mol).
    pub epsilon: f64,
    /// Lennard-Jones diameter `σ` (Å).
    pub sigma: f64,
    /// Point dipole `μ` along body `ẑ` (debye).
    pub dipole: f64,
    /// Sticky strength `ν₀` of `w` (kJ/mol).
    pub nu0: f64,
    /// Sticky strength `ν₀'` of `w'` (kJ/mol; `ν₀` in the published models).
    pub nu0_prime: f64,
    /// The offset `w₀` of `w'`.
    pub w0: f64,
    /// Inner radius `r_L` of the switch `s` of `w` (Å).
    pub r_l: f64,
    /// Outer radius `r_U` of `s` (Å).
    pub r_u: f64,
    /// Inner radius `r_L'` of the switch `s'` of `w'` (Å).
    pub r_l_prime: f64,
    /// Outer radius `r_U'` of `s'` (Å).
    pub r_u_prime: f64,
    /// Where the switch `g` of the Lennard-Jones and dipolar terms starts (Å).
    pub r_switch: f64,
    /// The cut-off `r_c`: `U ≡ 0` beyond it (Å).
    pub r_cut: f64,
}

impl SsdParameters {
    /// SSD/E as published (FG04, Table I), converted to kJ/mol: `σ = 3.035 Å`,
    /// `ε = 0.152 kcal/mol`, `μ = 2.42 D`, `ν₀ = ν₀' = 3.90 kcal/mol`, `w₀ = 0.07715`,
    /// `r_L = 2.40 Å`, `r_U = 3.80 Å`, `r_L' = 2.75 Å`, `r_U' = 3.35 Å`; with our switched
    /// cut-off of the Lennard-Jones and dipolar terms, `7.65 Å` to `9 Å`.
    pub const SSD_E: Self = Self {
        epsilon: 0.152 * KCAL,
        sigma: 3.035,
        dipole: 2.42,
        nu0: 3.90 * KCAL,
        nu0_prime: 3.90 * KCAL,
        w0: 0.07715,
        r_l: 2.40,
        r_u: 3.80,
        r_l_prime: 2.75,
        r_u_prime: 3.35,
        r_switch: 7.65,
        r_cut: 9.0,
    };
}

/// A soft sticky dipole water model (module documentation): Lennard-Jones plus point dipole,
/// switched off at a cut-off, plus the tetrahedral sticky potential. A
/// [`RigidPairPotential`]: the molecule has no axis of symmetry.
///
/// ```
/// use potential::{RigidPairPotential, SoftStickyDipole};
///
/// let water = SoftStickyDipole::ssd_e();
/// let g = SoftStickyDipole::hydrogen_bond(2.75); // donor i, acceptor j, 2.75 Å apart
/// let e = water.evaluate(&g)?;
/// assert!((e.energy - -7.579_38).abs() < 1e-5); // kJ/mol, by hand in tests/integration/rigid_water.rs
/// assert!(e.torque_imbalance(g.r_ij) < 1e-14); // 003 Eq. 6
/// assert!(water.minimum() <= e.energy && water.reach(-1.0)? <= water.cutoff());
/// # Ok::<(), potential::PotentialError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoftStickyDipole {
    p: SsdParameters,
    four_eps: f64,
    sigma2: f64,
    /// `μ²/(4πε₀)` in kJ/mol Å³.
    mu2: f64,
    g: Cubic,
    s: Cubic,
    s_prime: Cubic,
    /// Beyond this distance the sticky term vanishes.
    sticky_range: f64,
    minimum: f64,
}

impl SoftStickyDipole {
    /// Mass of a water molecule (amu).
    pub const MASS: f64 = 18.0153;

    /// Principal moments of inertia `(I_xx, I_yy, I_zz)` in the body frame (amu Å²), those the
    /// SSD family uses (OpenMD's `SSD_E` type; the moments of a rigid TIP3P-like geometry).
    pub const INERTIA: DVec3 = DVec3::new(1.7696, 0.6145, 1.1550);

    /// A model with these parameters.
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] unless `ε`, `σ`, the radii are finite and positive, every
    /// switch's outer radius exceeds its inner one, `μ`, `ν₀`, `ν₀'` are finite and
    /// non-negative, `0 ≤ w₀ ≤ 0.5184`, and the sticky range `max(r_U, r_U')` does not exceed
    /// the cut-off.
    pub fn new(p: SsdParameters) -> Result<Self, PotentialError> {
        let epsilon = positive("epsilon", p.epsilon)?;
        let sigma = positive("sigma", p.sigma)?;
        let dipole = non_negative("dipole", p.dipole)?;
        non_negative("nu0", p.nu0)?;
        non_negative("nu0_prime", p.nu0_prime)?;
        let w0 = non_negative("w0", p.w0)?;
        if w0 > W_PRIME_PART_MAX {
            return Err(PotentialError::Parameter {
                name: "w0",
                value: w0,
                why: "at most 0.5184 (the largest value of (c - 0.6)^2 (c + 0.8)^2)",
            });
        }
        let g = Cubic::new("r_switch", p.r_switch, "r_cut", p.r_cut)?;
        let s = Cubic::new("r_l", p.r_l, "r_u", p.r_u)?;
        let s_prime = Cubic::new("r_l_prime", p.r_l_prime, "r_u_prime", p.r_u_prime)?;
        let sticky_range = p.r_u.max(p.r_u_prime);
        if sticky_range > p.r_cut {
            return Err(PotentialError::Parameter {
                name: "r_cut",
                value: p.r_cut,
                why: "at least the sticky range max(r_u, r_u_prime)",
            });
        }
        let mut out = Self {
            p,
            four_eps: 4.0 * epsilon,
            sigma2: sigma * sigma,
            mu2: dipole * dipole * DEBYE2_PER_A3,
            g,
            s,
            s_prime,
            sticky_range,
            minimum: 0.0,
        };
        out.minimum = out.lower_bound_minimum();
        Ok(out)
    }

    /// SSD/E with the published parameters ([`SsdParameters::SSD_E`]).
    pub fn ssd_e() -> Self {
        Self::new(SsdParameters::SSD_E).expect("the published SSD/E parameters are valid")
    }

    /// The parameters.
    pub fn parameters(&self) -> &SsdParameters {
        &self.p
    }

    /// The cut-off `r_c`: `U = 0` for `r ≥ r_c`.
    pub fn cutoff(&self) -> f64 {
        self.p.r_cut
    }

    /// `μ²/(4πε₀)` in kJ/mol Å³.
    pub fn dipole_squared(&self) -> f64 {
        self.mu2
    }

    /// `(g(r), g'(r))`: the switch of the Lennard-Jones and dipolar terms.
    pub fn cutoff_switch(&self, r: f64) -> (f64, f64) {
        self.g.eval(r)
    }

    /// `(s(r), s'(r))` of `w` and `(s'(r), ds'/dr)` of `w'`: the sticky switches.
    pub fn sticky_switches(&self, r: f64) -> ((f64, f64), (f64, f64)) {
        (self.s.eval(r), self.s_prime.eval(r))
    }

    /// A hydrogen-bond-like dimer at oxygen distance `d`: the donor `i` in the lab frame at the
    /// origin, the acceptor `j` at `d` along one of `i`'s hydrogen directions
    /// `(0, √(2/3), 1/√3)`, turned by −90° about `ẑ` so that `i` sits in one of its lone-pair
    /// directions and the dipoles are parallel. Both `w` terms are at their minimum,
    /// `−4/(3√3)` each, and the dipolar energy vanishes (the dipoles make the magic angle with
    /// `r̂`).
    pub fn hydrogen_bond(d: f64) -> RigidGeometry {
        let h = DVec3::new(0.0, (2.0f64 / 3.0).sqrt(), 1.0 / 3.0f64.sqrt());
        RigidGeometry::new(
            -d * h,
            DQuat::IDENTITY,
            DQuat::from_rotation_z(-std::f64::consts::FRAC_PI_2),
        )
    }

    /// The sticky energy of molecule `a` and its gradient with respect to `d`, the body-frame
    /// vector from `a` to its partner, `|d| = r`.
    #[inline]
    fn sticky_one(&self, d: DVec3, r: f64, sw: (f64, f64), swp: (f64, f64)) -> (f64, DVec3) {
        let (x, y, z) = (d.x, d.y, d.z);
        let inv_r = 1.0 / r;
        let inv_r2 = inv_r * inv_r;
        let inv_r3 = inv_r2 * inv_r;
        let dxy = x * x - y * y;
        let w = 2.0 * z * dxy * inv_r3;
        // ∇w = (4xz, −4yz, 2(x² − y²))/r³ − 3w d/r².
        let grad_w =
            DVec3::new(4.0 * x * z, -4.0 * y * z, 2.0 * dxy) * inv_r3 - (3.0 * w * inv_r2) * d;
        let c = z * inv_r;
        let (wp, dwp) = w_prime_part(c);
        let wp = wp - self.p.w0;
        // ∇c = ẑ/r − z d/r³.
        let grad_c = DVec3::new(0.0, 0.0, inv_r) - (z * inv_r3) * d;
        let (h, hp) = (0.5 * self.p.nu0, 0.5 * self.p.nu0_prime);
        let energy = h * sw.0 * w + hp * swp.0 * wp;
        let grad = h * (sw.0 * grad_w + (sw.1 * w * inv_r) * d)
            + hp * ((swp.0 * dwp) * grad_c + (swp.1 * wp * inv_r) * d);
        (energy, grad)
    }

    /// `U ≥ lower(r)` for every attitude: `g(u_LJ − 2μ²/r³) − (ν₀/2) s max|w| − ν₀' s' w₀`.
    fn lower(&self, r: f64) -> f64 {
        let (g, _) = self.g.eval(r);
        let (s, _) = self.s.eval(r);
        let (sp, _) = self.s_prime.eval(r);
        let (u_lj, _) = energy_and_virial(self.four_eps, self.sigma2 / (r * r));
        g * (u_lj - 2.0 * self.mu2 / (r * r * r))
            - 0.5 * self.p.nu0 * s * W_MAX
            - 0.5 * self.p.nu0_prime * sp * 2.0 * self.p.w0
    }

    /// `−U ≤ attract(r)`, non-increasing in `r`: `lower` without the repulsion.
    fn attract(&self, r: f64) -> f64 {
        let (g, _) = self.g.eval(r);
        let (s, _) = self.s.eval(r);
        let (sp, _) = self.s_prime.eval(r);
        let s6 = (self.sigma2 / (r * r)).powi(3);
        g * (self.four_eps * s6 + 2.0 * self.mu2 / (r * r * r))
            + 0.5 * self.p.nu0 * s * W_MAX
            + 0.5 * self.p.nu0_prime * sp * 2.0 * self.p.w0
    }

    /// `U ≤ repel(r)`, non-increasing in `r`.
    fn repel(&self, r: f64) -> f64 {
        let (g, _) = self.g.eval(r);
        let (s, _) = self.s.eval(r);
        let (sp, _) = self.s_prime.eval(r);
        let s6 = (self.sigma2 / (r * r)).powi(3);
        g * (self.four_eps * s6 * s6 + 2.0 * self.mu2 / (r * r * r))
            + 0.5 * self.p.nu0 * s * W_MAX
            + 0.5 * self.p.nu0_prime * sp * 2.0 * (W_PRIME_PART_MAX - self.p.w0)
    }

    /// The minimum of [`lower`](Self::lower) over `0 < r < r_c`: a grid of `10⁻³ σ` from `σ/2`
    /// (where the repulsion alone is `4ε·4032`, far above any attraction of the bound) and a
    /// golden-section refinement around the lowest sample, less `10⁻⁹` relative for the
    /// refinement's tolerance.
    fn lower_bound_minimum(&self) -> f64 {
        let (lo, hi) = (0.5 * self.p.sigma, self.p.r_cut);
        let step = 1e-3 * self.p.sigma;
        let n = ((hi - lo) / step).ceil() as usize;
        let (mut best_r, mut best) = (lo, f64::INFINITY);
        for k in 0..=n {
            let r = (lo + k as f64 * step).min(hi);
            let u = self.lower(r);
            if u < best {
                best = u;
                best_r = r;
            }
        }
        let (_, refined) = golden_min(
            &mut |r| self.lower(r),
            (best_r - step).max(lo),
            (best_r + step).min(hi),
        );
        let m = best.min(refined);
        (m - 1e-9 * m.abs()).min(0.0)
    }

    /// The largest `r` in `(0, r_c)` with `f(r) ≥ target` for a non-increasing `f`, by
    /// bisection, returned from the outer side (an upper bound).
    fn outermost(&self, f: impl Fn(f64) -> f64, target: f64) -> f64 {
        let (mut lo, mut hi) = (1e-3 * self.p.sigma, self.p.r_cut);
        if f(lo) < target {
            return 0.0;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if f(mid) >= target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }

    /// The overlap error for a geometry without finite energy.
    #[cold]
    fn overlap(g: &RigidGeometry, r: f64, what: &'static str) -> PotentialError {
        if g.is_finite() {
            PotentialError::Overlap { r, what }
        } else {
            PotentialError::NotFinite("rigid pair geometry (r_ij, q_i or q_j)")
        }
    }
}

impl RigidPairPotential for SoftStickyDipole {
    fn evaluate(&self, g: &RigidGeometry) -> Result<PairEval, PotentialError> {
        if !g.is_finite() {
            return Err(Self::overlap(g, f64::NAN, ""));
        }
        let r2 = g.r_ij.length_squared();
        let r = r2.sqrt();
        if r >= self.p.r_cut {
            return Ok(PairEval::default());
        }
        if r2 == 0.0 {
            return Err(Self::overlap(g, r, "the centres coincide"));
        }
        // Lennard-Jones and dipole, switched by g(r): a uniaxial potential of the dipole axes,
        // assembled from its partial derivatives (003 Eqs. 4–5).
        let (u_lj, vir) = energy_and_virial(self.four_eps, self.sigma2 / r2);
        if !u_lj.is_finite() {
            return Err(Self::overlap(g, r, "(sigma/r)^12 overflows binary64"));
        }
        let a = g.q_i * DVec3::Z;
        let b = g.q_j * DVec3::Z;
        let inv = Invariants {
            r,
            x_i: g.r_ij.dot(a),
            x_j: g.r_ij.dot(b),
            c: a.dot(b),
        };
        let inv_r = 1.0 / r;
        let inv_r2 = inv_r * inv_r;
        let inv_r3 = inv_r2 * inv_r;
        let inv_r5 = inv_r3 * inv_r2;
        let m = self.mu2;
        let xx = inv.x_i * inv.x_j;
        let u_dp = m * (inv.c * inv_r3 - 3.0 * xx * inv_r5);
        let du_dp = m * (-3.0 * inv.c * inv_r3 + 15.0 * xx * inv_r5) * inv_r;
        let (sw, dsw) = self.g.eval(r);
        let u0 = u_lj + u_dp;
        let partials = Partials {
            energy: sw * u0,
            d_r: sw * (vir * inv_r + du_dp) + dsw * u0,
            d_xi: sw * (-3.0 * m * inv.x_j * inv_r5),
            d_xj: sw * (-3.0 * m * inv.x_i * inv_r5),
            d_c: sw * m * inv_r3,
        };
        let mut out = assemble(&PairGeometry::new(g.r_ij, a, b), &inv, &partials)?;
        // The sticky term: f_i(d_i) + f_j(d_j), d_i = q_i⁻¹(r_j − r_i), d_j = q_j⁻¹(r_i − r_j).
        // With G_a = q_a ∇f_a (lab frame): F_ij gains G_i − G_j, τ_ij gains G_i × r_ij and
        // τ_ji gains −G_j × r_ij (module documentation of `rigid`; each pair of terms balances
        // 003 Eq. 6 on its own).
        if r < self.sticky_range {
            let sw = self.s.eval(r);
            let swp = self.s_prime.eval(r);
            let (f_i, grad_i) = self.sticky_one(g.q_i.inverse() * -g.r_ij, r, sw, swp);
            let (f_j, grad_j) = self.sticky_one(g.q_j.inverse() * g.r_ij, r, sw, swp);
            let (big_i, big_j) = (g.q_i * grad_i, g.q_j * grad_j);
            out.energy += f_i + f_j;
            out.force += big_i - big_j;
            out.torque_i += big_i.cross(g.r_ij);
            out.torque_j -= big_j.cross(g.r_ij);
        }
        if out.is_finite() {
            Ok(out)
        } else {
            Err(Self::overlap(
                g,
                r,
                "the energy or its derivatives overflow binary64",
            ))
        }
    }

    /// `U(τ) ∈ U + U̇τ ± Kτ²/2` over `[0, h]` ([`RigidPairPotential::taylor_model`]), with `K`
    /// from bounds `(|f|, |ḟ|, |f̈|)` of every factor along the flight, combined by the product
    /// rule `(fg)¨ = f̈g + 2ḟġ + fg̈`. Over the window the centre distance lies in
    /// `[r_lo, r_hi] = r ∓ |v|h`, with `|ṙ| ≤ |v|` and `|r̈| ≤ |v|²/r_lo`; `r̂` has
    /// `|r̂̇| ≤ |v|/r` and `|r̂̈| ≤ 4|v|²/r²`; a body axis `e` has `|ė| ≤ W` and
    /// `|ë| ≤ Ẇ + W²` (the flight's spin bounds), and the partner direction in a body frame,
    /// `c = Qᵀ(±r̂)`, has `|ċ| ≤ |v|/r + W` and `|c̈| ≤ 4|v|²/r² + 2W|v|/r + Ẇ + W²`. Radial
    /// factors (`u_LJ`, `r⁻³`, the switches) use decreasing envelopes at `r_lo` or, for the
    /// cubic switches, `|S'| ≤ 1.5/w` and `|S''| ≤ 6/w²` where `[r_lo, r_hi]` meets their
    /// window; `ẑ_i·ẑ_j − 3(ẑ_i·r̂)(ẑ_j·r̂)` is at most 2; `w_a = 2c_z(c_x² − c_y²)` has
    /// `|∇| ≤ 2.31` and `‖∇²‖ ≤ √32` on the unit ball, `(c_z − 0.6)²(c_z + 0.8)²` has `|′| ≤
    /// 3.168` and `|″| ≤ 12.56` on `[−1, 1]`. `None` inside half a diameter.
    fn taylor_model(&self, f: &RigidFlight, h: f64) -> Option<TaylorModel> {
        let e = self.evaluate(&RigidGeometry::new(f.r, f.q_i, f.q_j)).ok()?;
        let (x, dx) = (e.energy, e.rate(f.v, f.w_i, f.w_j));
        let model = |spread| TaylorModel::first_order(x, dx, spread);
        let speed = f.v.length();
        let r0 = f.r.length();
        let (lo, hi) = (r0 - speed * h, r0 + speed * h);
        if lo >= self.p.r_cut {
            return Some(model(0.0));
        }
        if lo.is_nan() || lo <= 0.5 * self.p.sigma {
            return None;
        }
        let v2 = speed * speed;
        // A radial factor from sup |f|, |f'|, |f''| over [lo, hi].
        let radial = |f0: f64, f1: f64, f2: f64| Rates::radial(f0, f1, f2, speed, lo);
        let switch = |c: &Cubic| Rates::cubic_switch(c.lo, c.hi, lo, hi, speed);
        let (n1, n2) = (speed / lo, 4.0 * v2 / (lo * lo));
        let (wi, wj) = (f.spin_i, f.spin_j);
        let (ai, aj) = (f.turn_i + wi * wi, f.turn_j + wj * wj);
        // Lennard-Jones and the dipole, switched by g.
        let inv = 1.0 / lo;
        let s2 = self.sigma2 * inv * inv;
        let s6 = s2 * s2 * s2;
        let s12 = s6 * s6;
        let lj = radial(
            self.four_eps * (s12 + s6),
            self.four_eps * (12.0 * s12 + 6.0 * s6) * inv,
            self.four_eps * (156.0 * s12 + 42.0 * s6) * inv * inv,
        );
        let inv3 = inv * inv * inv;
        let r3 = radial(inv3, 3.0 * inv3 * inv, 12.0 * inv3 * inv * inv);
        let angular = Rates(
            2.0,
            (wi + wj) + 3.0 * ((wi + n1) + (wj + n1)),
            (ai + 2.0 * wi * wj + aj)
                + 3.0
                    * ((ai + 2.0 * wi * n1 + n2)
                        + 2.0 * (wi + n1) * (wj + n1)
                        + (aj + 2.0 * wj * n1 + n2)),
        );
        let dipole = self.mu2 * (r3 * angular);
        let mut k = (switch(&self.g) * (lj + dipole)).2;
        // The sticky terms of both molecules.
        if lo < self.sticky_range {
            let direction = |w: f64, a: f64| (n1 + w, n2 + 2.0 * w * n1 + a);
            let ((ci1, ci2), (cj1, cj2)) = (direction(wi, ai), direction(wj, aj));
            let tetra = |c1: f64, c2: f64| {
                Rates(0.5 * W_MAX, 2.31 * c1, 32f64.sqrt() * c1 * c1 + 2.31 * c2)
            };
            let correction = |c1: f64, c2: f64| {
                Rates(W_PRIME_PART_MAX, 3.168 * c1, 12.56 * c1 * c1 + 3.168 * c2)
            };
            let w = tetra(ci1, ci2) + tetra(cj1, cj2);
            let wp = correction(ci1, ci2) + correction(cj1, cj2);
            k += 0.5 * self.p.nu0 * (switch(&self.s) * w).2
                + 0.5 * self.p.nu0_prime * (switch(&self.s_prime) * wp).2;
        }
        k.is_finite().then(|| model(k))
    }

    #[inline]
    fn certifies(&self) -> bool {
        true
    }

    /// A rigorous lower bound (module documentation): `−43.51 kJ/mol` for SSD/E, below the
    /// deepest dimer energy a descent from random starts finds (about `−33.1 kJ/mol`), because
    /// no attitude makes the dipolar and both sticky terms optimal at once.
    fn minimum(&self) -> f64 {
        self.minimum
    }

    fn length_scale(&self) -> f64 {
        self.p.sigma
    }

    /// An upper bound on the reach from the monotone envelopes of the module documentation;
    /// at most `r_c`. Zero for a negative level below [`minimum`](RigidPairPotential::minimum).
    fn reach(&self, u_k: f64) -> Result<f64, PotentialError> {
        crate::rigid::reach_from_envelopes(
            u_k,
            self.minimum,
            |target| self.outermost(|r| self.attract(r), target),
            |target| self.outermost(|r| self.repel(r), target),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn published_parameters_in_molecular_units() {
        let w = SoftStickyDipole::ssd_e();
        let p = w.parameters();
        assert!((p.epsilon - 0.635_968).abs() < 1e-12);
        assert!((p.nu0 - 16.3176).abs() < 1e-12);
        // μ² = 2.42² D² · 60.2214 kJ/mol Å³ per D² (e²/4πε₀ = 1389.3546 kJ/mol Å, 1 D =
        // 0.2081943 e Å).
        let by_charges = 2.42f64.powi(2) * 1_389.354_576 * 0.208_194_333_f64.powi(2);
        assert!((w.dipole_squared() - by_charges).abs() < 1e-6 * by_charges);
        assert!((w.dipole_squared() - 352.6807).abs() < 1e-3);
        assert!((W_MAX - 8.0 / (3.0 * 3f64.sqrt())).abs() < 1e-15);
        assert_eq!(w.cutoff(), 9.0);
        assert_eq!(SoftStickyDipole::INERTIA.x, 1.7696);
    }

    #[test]
    fn sticky_switches_follow_the_published_windows() {
        let w = SoftStickyDipole::ssd_e();
        assert_eq!(w.sticky_switches(2.40), ((1.0, 0.0), (1.0, 0.0)));
        assert_eq!(w.sticky_switches(3.80).0, (0.0, 0.0));
        assert_eq!(w.sticky_switches(3.35).1, (0.0, 0.0));
        // Midpoint of [2.40, 3.80]: s = ½, ds/dr = −6 (0.7 · 0.7)/1.4³ = −1.5/1.4.
        let ((s, ds), _) = w.sticky_switches(3.10);
        assert!((s - 0.5).abs() < 1e-14 && (ds + 1.5 / 1.4).abs() < 1e-13);
    }

    #[test]
    fn w_prime_part_bound_and_derivative() {
        let mut max: f64 = 0.0;
        for k in 0..=20_000 {
            let c = -1.0 + k as f64 * 1e-4;
            let (v, d) = w_prime_part(c);
            max = max.max(v);
            let h = 1e-6;
            let fd = (w_prime_part(c + h).0 - w_prime_part(c - h).0) / (2.0 * h);
            assert!((fd - d).abs() < 1e-8);
        }
        assert!((max - W_PRIME_PART_MAX).abs() < 1e-12);
    }

    #[test]
    fn bad_parameters_are_named() {
        let bad = |f: fn(&mut SsdParameters)| {
            let mut p = SsdParameters::SSD_E;
            f(&mut p);
            SoftStickyDipole::new(p).unwrap_err().to_string()
        };
        assert!(bad(|p| p.sigma = 0.0).contains("sigma"));
        assert!(bad(|p| p.r_u = 2.0).contains("r_u"));
        assert!(bad(|p| p.r_cut = 3.5).contains("r_cut"));
        assert!(bad(|p| p.w0 = 0.6).contains("w0"));
        assert!(bad(|p| p.dipole = f64::NAN).contains("dipole"));
    }
}
