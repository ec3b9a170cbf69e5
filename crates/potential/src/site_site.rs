//! Rigid molecules of interaction sites: the molecular pair energy is the sum of site–site
//! Lennard-Jones and damped shifted force (DSF) Coulomb terms, with SPC/E water as the shipped
//! molecule.
//!
//! **Units** (the molecular units of the rods and of SSD/E): energy kJ/mol, length Å, charge
//! the elementary charge `e`, so that the Coulomb constant is `e²/(4πε₀) = 1389.354 576 kJ/mol Å`
//! ([`COULOMB`]); masses amu (g/mol).
//!
//! **The molecule.** Each [`Site`] has a position in the body frame (the principal frame of the
//! molecule's inertia tensor, centre of mass at the origin), a Lennard-Jones `σ`, `ε` and a
//! charge `q`. Unlike sites mix by the Lorentz–Berthelot rules, `σ_ab = (σ_a + σ_b)/2` and
//! `ε_ab = √(ε_a ε_b)` (a site with `ε = 0` has no Lennard-Jones term with any site).
//!
//! **The pair energy.** With `d = r_ij + A_a − B_b` the separation of site `a` of `i` (lab arm
//! `A_a = q_i·a`) from site `b` of `j` and `r = |d|`, `U = Σ_ab [u_C(r) + u_LJ(r)]` over the
//! site pairs with `r < R_c`, where
//!
//! ```text
//! u_C  = K q_a q_b [erfc(αr)/r − erfc(αR_c)/R_c + (erfc(αR_c)/R_c² + (2α/√π) e^{−α²R_c²}/R_c)(r − R_c)]
//! u_LJ = φ(r) − φ(R_c) − φ'(R_c)(r − R_c),   φ(r) = 4ε_ab[(σ_ab/r)¹² − (σ_ab/r)⁶]
//! ```
//!
//! `u_C` is the damped shifted force Coulomb term of C. J. Fennell and J. D. Gezelter, J. Chem.
//! Phys. 124, 234104 (2006), "FG06", Eq. 14 there; `u_LJ` is Lennard-Jones shifted the same way
//! (our choice, stated): both vanish with their first derivative at the site cut-off `R_c`, so
//! the pair energy and its force and torques are continuous everywhere, and `U ≡ 0` for centre
//! distances beyond `R_c + max(|a| + |b|)`, the molecular reach. The shift changes the
//! energy against a plain cut-off; for SPC/E at 0.997 g/cm³ and `R_c = 9 Å` the
//! Lennard-Jones shift adds about 0.6 kJ/mol per molecule.
//!
//! **Force and torques.** The force on site `a` from site `b` is `f_ab = −u'(r) d/r`; the
//! molecule's force is their sum, and its torque about the centre of mass the sum of the
//! moments of the site forces about it: `F_ij = Σ f_ab`, `τ_ij = Σ A_a × f_ab`,
//! `τ_ji = −Σ B_b × f_ab`. Every `f_ab` is parallel to its `d`, so
//! `r_ij × F_ij + τ_ij + τ_ji = Σ d × f_ab = 0` (003 Eq. 6) term by term.
//!
//! **Bounds for the terrace map.** A site pair with arm sum `s = |a| + |b|` at centre distance
//! `R` is between `R − s` and `R + s` apart. `u_C/(K q_a q_b)` is positive, decreasing and
//! convex on `(0, R_c)` (erfc and `1/r` are positive, decreasing and convex, and the shift
//! makes it vanish with its slope at `R_c`), and `u_LJ` decreases to its minimum at `r*` and
//! rises to 0 at `R_c`. So `U` lies between two functions of `R` alone: the attractive Coulomb
//! pairs at their closest plus each Lennard-Jones term at its lowest over the interval below,
//! the repulsive pairs at their closest plus each Lennard-Jones term at its highest above.
//! [`RigidPairPotential::reach`] bisects monotone envelopes of the two, an upper bound on the
//! true reach.
//!
//! **The minimum behind a barrier.** A molecule whose charged sites carry no Lennard-Jones
//! core (SPC/E's hydrogens) is unbounded below: a hydrogen of one molecule pulled onto the
//! oxygen of another gains `−∞` from the Coulomb term, past a Lennard-Jones wall between the
//! oxygens (the bound below puts it at 2.7·10⁵ kJ/mol). No trajectory below that wall reaches it. The lower bound,
//! taken on cells of `R` of 10⁻³ Å (each cell's attractive terms at its inner edge, the
//! Lennard-Jones terms at their lowest over the cell), rises to a highest cell, the
//! [`barrier`](SiteSite::barrier), before it falls to `−∞`: every path from far apart to
//! inside it passes a configuration with `U` at least the barrier. [`RigidPairPotential::minimum`]
//! is the lowest bound outside the barrier: a rigorous lower bound on `U` for every
//! configuration a terraced or standard-MD trajectory can reach while its energy stays below
//! the barrier (a terrace map's hard core must lie below it, which the scene checks). The bound
//! ignores that the attractive pairs cannot all be at their closest at once, so it is loose
//! (−1332 kJ/mol for SPC/E, where dimers sit at tens of kJ/mol below zero).

use glam::{DQuat, DVec3};

use crate::certify::{RigidFlight, TaylorModel};
use crate::error::{non_negative, positive};
use crate::rigid::{RigidGeometry, RigidPairPotential};
use crate::solve::golden_min;
use crate::{PairEval, PotentialError};

/// `e²/(4πε₀)` in kJ/mol Å (CODATA 2018: `N_A e²/(4πε₀ · 1 Å) = 1389.354 576 kJ/mol`).
pub const COULOMB: f64 = 1_389.354_576;

/// The most sites a molecule may have (the lab arms live on the stack).
pub const MAX_SITES: usize = 8;

/// `2/√π`.
const TWO_OVER_SQRT_PI: f64 = std::f64::consts::FRAC_2_SQRT_PI;

/// One interaction site of a rigid molecule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Site {
    /// Position in the body frame (Å; the principal frame, centre of mass at the origin).
    pub position: DVec3,
    /// Lennard-Jones diameter `σ` (Å; mixed by the arithmetic mean).
    pub sigma: f64,
    /// Lennard-Jones well depth `ε` (kJ/mol; mixed by the geometric mean, 0 for none).
    pub epsilon: f64,
    /// Charge `q` (e).
    pub charge: f64,
    /// Mass (amu): the molecule's centre of mass and inertia tensor, not the energy.
    pub mass: f64,
}

/// The damped shifted force Coulomb term's parameters (FG06).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dsf {
    /// Damping `α` (Å⁻¹; 0 is the undamped shifted force).
    pub alpha: f64,
    /// Site–site cut-off `R_c` (Å), also of the Lennard-Jones terms.
    pub r_cut: f64,
}

impl Dsf {
    /// `α = 0.2 Å⁻¹`, `R_c = 9 Å`: the damping of FG06's DSF with the shortest cut-off of the
    /// range they compare with smooth particle-mesh Ewald (SPC/E water among their systems);
    /// the shortest, because the terraced engine's cells must fit the reach three times
    /// along the box.
    pub const FG06: Self = Self {
        alpha: 0.2,
        r_cut: 9.0,
    };
}

/// SPC/E water (H. J. C. Berendsen, J. R. Grigera and T. P. Straatsma, J. Phys. Chem. 91, 6269
/// (1987)): O–H 1.0 Å, H–O–H 109.47°, `q_O = −0.8476 e`, `q_H = +0.4238 e`, Lennard-Jones on the
/// oxygen only, `σ = 3.166 Å`, `ε = 0.650 kJ/mol`; masses 15.9994 and 1.008 amu.
///
/// Body frame: the principal frame, centre of mass at the origin; `ẑ` along the H–O–H
/// bisector from the oxygen towards the hydrogens (the dipole), the hydrogens in the `yz` plane,
/// `x̂` normal to the plane. The principal moments are [`SPC_E_MOMENTS`].
pub fn spc_e_sites() -> [Site; 3] {
    let half = 0.5 * 109.47_f64.to_radians();
    let (m_o, m_h) = (15.9994, 1.008);
    let (y, z) = (half.sin(), half.cos());
    // The centre of mass lies 2 m_H z / M above the oxygen along the bisector.
    let z_cm = 2.0 * m_h * z / (m_o + 2.0 * m_h);
    let h = |y: f64| Site {
        position: DVec3::new(0.0, y, z - z_cm),
        sigma: 0.0,
        epsilon: 0.0,
        charge: 0.4238,
        mass: m_h,
    };
    [
        Site {
            position: DVec3::new(0.0, 0.0, -z_cm),
            sigma: 3.166,
            epsilon: 0.650,
            charge: -0.8476,
            mass: m_o,
        },
        h(y),
        h(-y),
    ]
}

/// SPC/E's principal moments `(I_xx, I_yy, I_zz)` (amu Å²) in the body frame of
/// [`spc_e_sites`], from the site masses (an asymmetric top; `I_xx = I_yy + I_zz`, planar),
/// rounded to five significant digits as a scene gives them.
pub const SPC_E_MOMENTS: [f64; 3] = [1.9408, 0.59680, 1.3440];

/// The inertia tensor of point masses about the origin (amu Å²), row-major.
pub fn inertia_tensor(sites: &[Site]) -> [[f64; 3]; 3] {
    let mut t = [[0.0; 3]; 3];
    for s in sites {
        let p = s.position.to_array();
        let r2 = s.position.length_squared();
        for (a, row) in t.iter_mut().enumerate() {
            for (b, x) in row.iter_mut().enumerate() {
                *x += s.mass * (if a == b { r2 } else { 0.0 } - p[a] * p[b]);
            }
        }
    }
    t
}

/// The shifted-force Lennard-Jones term of one site pair.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LjTerm {
    four_eps: f64,
    sigma2: f64,
    /// `φ(R_c)` and `φ'(R_c)`.
    shift: f64,
    slope: f64,
    /// Where `u_LJ` is lowest, and its value there less a margin for the search's tolerance.
    r_star: f64,
    u_star: f64,
}

impl LjTerm {
    /// `φ(r)` and `φ'(r)`.
    #[inline]
    fn phi(four_eps: f64, sigma2: f64, r: f64) -> (f64, f64) {
        let s2 = sigma2 / (r * r);
        let s6 = s2 * s2 * s2;
        let s12 = s6 * s6;
        (
            four_eps * (s12 - s6),
            -four_eps * (12.0 * s12 - 6.0 * s6) / r,
        )
    }

    /// `u_LJ(r)` and its derivative for `r < R_c` (the caller cuts).
    #[inline]
    fn eval(&self, r: f64, r_cut: f64) -> (f64, f64) {
        let (p, dp) = Self::phi(self.four_eps, self.sigma2, r);
        (p - self.shift - self.slope * (r - r_cut), dp - self.slope)
    }

    /// `u_LJ(r)`, zero at and beyond `R_c`, `+∞` at `r ≤ 0`.
    fn value(&self, r: f64, r_cut: f64) -> f64 {
        if r >= r_cut {
            0.0
        } else if r <= 0.0 {
            f64::INFINITY
        } else {
            self.eval(r, r_cut).0
        }
    }

    /// The lowest `u_LJ` over `[lo, hi]`.
    fn lowest(&self, lo: f64, hi: f64, r_cut: f64) -> f64 {
        if self.r_star < lo {
            self.value(lo, r_cut)
        } else if self.r_star > hi {
            self.value(hi, r_cut)
        } else {
            self.u_star
        }
    }
}

/// One site pair `(a, b)`: what its two terms need.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Term {
    a: usize,
    b: usize,
    /// `|a| + |b|`: the site distance is within this of the centre distance.
    arm: f64,
    /// `|a|` and `|b|` apart, for the certified model's speeds.
    arm_a: f64,
    arm_b: f64,
    /// `K q_a q_b` (0 for no Coulomb term).
    coulomb: f64,
    lj: Option<LjTerm>,
}

/// The first site distance of the tables of [`SiteSite::derivative_bounds_at`] (Å).
const BOUNDS_START: f64 = 0.5;
/// Their spacing (Å): the bound at a distance is read at the grid point at or below it.
const BOUNDS_STEP: f64 = 0.01;

/// The pair potential of two like rigid molecules of sites: site–site Lennard-Jones and damped
/// shifted force Coulomb (module documentation). A [`RigidPairPotential`].
///
/// ```
/// use glam::{DQuat, DVec3};
/// use potential::{RigidGeometry, RigidPairPotential, SiteSite};
///
/// let water = SiteSite::spc_e();
/// // Two parallel molecules 3 Å apart along x, normal to their planes.
/// let g = RigidGeometry::new(DVec3::new(3.0, 0.0, 0.0), DQuat::IDENTITY, DQuat::IDENTITY);
/// let e = water.evaluate(&g)?;
/// assert!(e.energy > 0.0); // like charges face each other
/// assert!(e.torque_imbalance(g.r_ij) < 1e-12); // 003 Eq. 6
/// assert!(water.minimum() <= e.energy && water.reach(0.5)? <= water.cutoff());
/// # Ok::<(), potential::PotentialError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct SiteSite {
    sites: Vec<Site>,
    terms: Vec<Term>,
    dsf: Dsf,
    r_cut2: f64,
    /// `erfc(αR_c)/R_c` and `erfc(αR_c)/R_c² + (2α/√π) e^{−α²R_c²}/R_c`.
    c_shift: f64,
    c_slope: f64,
    /// `2α/√π` and `α²`.
    two_a_sqrt_pi: f64,
    alpha2: f64,
    /// `R_c + max(|a| + |b|)`: `U ≡ 0` beyond it.
    cutoff: f64,
    cutoff2: f64,
    minimum: f64,
    barrier: f64,
    length: f64,
    /// Per term, [`derivative_bounds`](Self::derivative_bounds) at `BOUNDS_START +
    /// g·BOUNDS_STEP` for `g < grid` (to `R_c`), the terms one after the other.
    bounds: Vec<(f64, f64)>,
    grid: usize,
}

impl SiteSite {
    /// Two like molecules of `sites` (kJ/mol, Å, e), with the Coulomb constant `coulomb` (in
    /// the energy unit times Å per e²; [`COULOMB`] for kJ/mol) and the DSF parameters `dsf`.
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] unless there are 1 to [`MAX_SITES`] sites with finite
    /// positions, `σ ≥ 0`, `ε ≥ 0` (`σ > 0` where `ε > 0`) and finite charges, `coulomb > 0`,
    /// `α ≥ 0`, `R_c` beyond every Lennard-Jones well `2^{1/6} σ_ab`, and the lower bound has
    /// a barrier (module documentation) with a finite minimum outside it.
    pub fn new(sites: &[Site], coulomb: f64, dsf: Dsf) -> Result<Self, PotentialError> {
        let bad = |name, value, why| Err(PotentialError::Parameter { name, value, why });
        if sites.is_empty() || sites.len() > MAX_SITES {
            return bad("sites", sites.len() as f64, "1 to 8 sites");
        }
        let coulomb = positive("coulomb", coulomb)?;
        let alpha = non_negative("alpha", dsf.alpha)?;
        let r_cut = positive("r_cut", dsf.r_cut)?;
        for s in sites {
            if !s.position.is_finite() {
                return bad("position", f64::NAN, "finite");
            }
            non_negative("sigma", s.sigma)?;
            non_negative("epsilon", s.epsilon)?;
            if !s.charge.is_finite() {
                return bad("charge", s.charge, "finite");
            }
            if s.epsilon > 0.0 && s.sigma == 0.0 {
                return bad("sigma", s.sigma, "> 0 for a site with epsilon > 0");
            }
        }
        let mut terms = Vec::new();
        for (a, sa) in sites.iter().enumerate() {
            for (b, sb) in sites.iter().enumerate() {
                let eps = (sa.epsilon * sb.epsilon).sqrt();
                let lj = if eps > 0.0 {
                    let sigma = 0.5 * (sa.sigma + sb.sigma);
                    let r_min = 2f64.powf(1.0 / 6.0) * sigma;
                    if r_cut <= r_min {
                        return bad(
                            "r_cut",
                            r_cut,
                            "beyond every Lennard-Jones well 2^(1/6) sigma",
                        );
                    }
                    let (four_eps, sigma2) = (4.0 * eps, sigma * sigma);
                    let (shift, slope) = LjTerm::phi(four_eps, sigma2, r_cut);
                    let mut t = LjTerm {
                        four_eps,
                        sigma2,
                        shift,
                        slope,
                        r_star: r_min,
                        u_star: 0.0,
                    };
                    // u_LJ is unimodal on [r_min, R_c]: it falls to r* (where φ' = φ'(R_c))
                    // and rises to 0.
                    let (r_star, u) = golden_min(&mut |r| t.value(r, r_cut), r_min, r_cut);
                    t.r_star = r_star;
                    t.u_star = u - 1e-9 * u.abs();
                    Some(t)
                } else {
                    None
                };
                let q = coulomb * sa.charge * sb.charge;
                if q == 0.0 && lj.is_none() {
                    continue;
                }
                terms.push(Term {
                    a,
                    b,
                    arm: sa.position.length() + sb.position.length(),
                    arm_a: sa.position.length(),
                    arm_b: sb.position.length(),
                    coulomb: q,
                    lj,
                });
            }
        }
        let e = libm::erfc(alpha * r_cut);
        let max_arm = terms.iter().map(|t| t.arm).fold(0.0, f64::max);
        let cutoff = r_cut + max_arm;
        let length = sites.iter().map(|s| s.sigma).fold(0.0, f64::max);
        let mut out = Self {
            sites: sites.to_vec(),
            terms,
            dsf: Dsf { alpha, r_cut },
            r_cut2: r_cut * r_cut,
            c_shift: e / r_cut,
            c_slope: e / (r_cut * r_cut)
                + TWO_OVER_SQRT_PI * alpha * (-alpha * alpha * r_cut * r_cut).exp() / r_cut,
            two_a_sqrt_pi: TWO_OVER_SQRT_PI * alpha,
            alpha2: alpha * alpha,
            cutoff,
            cutoff2: cutoff * cutoff,
            minimum: 0.0,
            barrier: f64::INFINITY,
            length: if length > 0.0 { length } else { cutoff },
            bounds: Vec::new(),
            grid: 0,
        };
        (out.minimum, out.barrier) = out.minimum_behind_barrier()?;
        out.grid = ((r_cut - BOUNDS_START) / BOUNDS_STEP).ceil().max(0.0) as usize + 1;
        out.bounds = out
            .terms
            .iter()
            .flat_map(|t| {
                (0..out.grid)
                    .map(|g| out.derivative_bounds(t, BOUNDS_START + g as f64 * BOUNDS_STEP))
            })
            .collect();
        Ok(out)
    }

    /// SPC/E water ([`spc_e_sites`]) in kJ/mol with FG06's DSF parameters ([`Dsf::FG06`]).
    pub fn spc_e() -> Self {
        Self::new(&spc_e_sites(), COULOMB, Dsf::FG06).expect("SPC/E's parameters are valid")
    }

    /// The sites.
    pub fn sites(&self) -> &[Site] {
        &self.sites
    }

    /// The DSF parameters.
    pub fn dsf(&self) -> Dsf {
        self.dsf
    }

    /// The molecular cut-off `R_c + max(|a| + |b|)`: `U = 0` for centre distances at or beyond
    /// it.
    pub fn cutoff(&self) -> f64 {
        self.cutoff
    }

    /// The height of the lower bound's barrier (module documentation): no configuration
    /// reached from far apart with `U` below it is inside the barrier; `+∞` when the bound
    /// never falls to `−∞`.
    pub fn barrier(&self) -> f64 {
        self.barrier
    }

    /// `u_C/(K q_a q_b)` at site distance `r` (`+∞` at `r ≤ 0`, 0 at and beyond `R_c`).
    pub fn dsf_kernel(&self, r: f64) -> f64 {
        if r >= self.dsf.r_cut {
            0.0
        } else if r <= 0.0 {
            f64::INFINITY
        } else {
            libm::erfc(self.dsf.alpha * r) / r - self.c_shift + self.c_slope * (r - self.dsf.r_cut)
        }
    }

    /// The sites' lab arms of two molecules with attitudes `q_i` and `q_j` (the first
    /// `sites.len()` entries; the lab arms live on the stack).
    #[inline]
    fn lab_arms(&self, q_i: DQuat, q_j: DQuat) -> ([DVec3; MAX_SITES], [DVec3; MAX_SITES]) {
        let mut arm_i = [DVec3::ZERO; MAX_SITES];
        let mut arm_j = [DVec3::ZERO; MAX_SITES];
        for (k, s) in self.sites.iter().enumerate() {
            arm_i[k] = q_i * s.position;
            arm_j[k] = q_j * s.position;
        }
        (arm_i, arm_j)
    }

    /// Bounds on `|u'|` and `|u''|` of site pair `t` over site distances in `[d, R_c)`, both
    /// attained at `d` because every envelope below decreases. Coulomb, with `f = erfc(αr)/r`,
    /// `E = erfc(αr)` and `g = (2α/√π)e^{−α²r²}` (so `E' = −g`, `g' = −2α²rg`):
    /// `u_C' = Kq_aq_b(f' − f'(R_c))` with `|f'| = g/r + E/r²` decreasing and `f' ≤ f'(R_c) < 0`
    /// below `R_c`, so `|u_C'| ≤ K|q_aq_b|(|f'(d)| − |f'(R_c)|)`; `u_C'' = Kq_aq_b f''` with
    /// `f'' = 2α²g + 2g/r² + 2E/r³`, positive and decreasing. Lennard-Jones, with `s = σ/r`:
    /// `|φ'| ≤ 4ε(12s¹² + 6s⁶)/r`, `|φ''| ≤ 4ε(156s¹² + 42s⁶)/r²`, and `u_LJ' = φ' − φ'(R_c)`.
    #[inline]
    fn derivative_bounds(&self, t: &Term, d: f64) -> (f64, f64) {
        let (mut d1, mut d2) = (0.0, 0.0);
        let inv = 1.0 / d;
        if t.coulomb != 0.0 {
            let e = libm::erfc(self.dsf.alpha * d);
            let g = self.two_a_sqrt_pi * (-self.alpha2 * d * d).exp();
            let q = t.coulomb.abs();
            d1 += q * (g * inv + e * inv * inv - self.c_slope).max(0.0);
            d2 += q * 2.0 * (self.alpha2 * g + g * inv * inv + e * inv * inv * inv);
        }
        if let Some(lj) = &t.lj {
            let s2 = lj.sigma2 * inv * inv;
            let s6 = s2 * s2 * s2;
            let s12 = s6 * s6;
            d1 += lj.four_eps * (12.0 * s12 + 6.0 * s6) * inv + lj.slope.abs();
            d2 += lj.four_eps * (156.0 * s12 + 42.0 * s6) * inv * inv;
        }
        (d1, d2)
    }

    /// [`derivative_bounds`](Self::derivative_bounds) of `t` at `d`, read from its table at
    /// the grid point at or below `d` (the envelopes decrease, so that bound holds at `d`),
    /// computed directly below the table.
    #[inline]
    fn derivative_bounds_at(&self, index: usize, t: &Term, d: f64) -> (f64, f64) {
        let k = ((d - BOUNDS_START) / BOUNDS_STEP).floor();
        if k.is_nan() || k < 0.0 || self.grid == 0 {
            return self.derivative_bounds(t, d);
        }
        let k = (k as usize).min(self.grid - 1);
        // The grid point as the table computed it must not lie beyond `d` by round-off.
        let k = k - usize::from(k > 0 && BOUNDS_START + k as f64 * BOUNDS_STEP > d);
        self.bounds[index * self.grid + k]
    }

    /// A lower bound on `U` for centre distances in `[lo, hi]`: the attractive Coulomb pairs
    /// at their closest, the Lennard-Jones terms at their lowest.
    fn lower_on(&self, lo: f64, hi: f64) -> f64 {
        let rc = self.dsf.r_cut;
        self.terms
            .iter()
            .map(|t| {
                let c = if t.coulomb < 0.0 {
                    t.coulomb * self.dsf_kernel(lo - t.arm)
                } else {
                    0.0
                };
                let lj = t.lj.map_or(0.0, |l| {
                    l.lowest((lo - t.arm).max(0.0), (hi + t.arm).min(rc), rc)
                });
                c + lj
            })
            .sum()
    }

    /// `−U ≤ attract(R)`, non-increasing: the attractive pairs at their closest and each
    /// Lennard-Jones well at its deepest below `R`.
    fn attract(&self, r: f64) -> f64 {
        let rc = self.dsf.r_cut;
        self.terms
            .iter()
            .map(|t| {
                let d = r - t.arm;
                let c = if t.coulomb < 0.0 {
                    -t.coulomb * self.dsf_kernel(d)
                } else {
                    0.0
                };
                let lj = t.lj.map_or(0.0, |l| {
                    -(if d <= l.r_star {
                        l.u_star
                    } else {
                        l.value(d, rc)
                    })
                });
                c + lj
            })
            .sum()
    }

    /// `U ≤ repel(R)`, non-increasing: the repulsive pairs at their closest and each
    /// Lennard-Jones term at its highest.
    fn repel(&self, r: f64) -> f64 {
        let rc = self.dsf.r_cut;
        self.terms
            .iter()
            .map(|t| {
                let d = r - t.arm;
                let c = if t.coulomb > 0.0 {
                    t.coulomb * self.dsf_kernel(d)
                } else {
                    0.0
                };
                c + t.lj.map_or(0.0, |l| l.value(d, rc).max(0.0))
            })
            .sum()
    }

    /// The minimum outside the barrier and the barrier (module documentation), on cells of
    /// 10⁻³ Å from the cut-off inwards.
    fn minimum_behind_barrier(&self) -> Result<(f64, f64), PotentialError> {
        const H: f64 = 1e-3;
        let n = (self.cutoff / H).ceil() as usize;
        let mut bounds = Vec::with_capacity(n);
        for k in (0..n).rev() {
            let lo = k as f64 * H;
            let b = self.lower_on(lo, (lo + H).min(self.cutoff));
            if b == f64::NEG_INFINITY || b.is_nan() {
                break;
            }
            bounds.push(b);
        }
        // The highest cell is the barrier; the minimum is over the cells outside it.
        let (top, barrier) =
            bounds
                .iter()
                .copied()
                .enumerate()
                .fold((0, f64::NEG_INFINITY), |best, (k, b)| {
                    if b > best.1 { (k, b) } else { best }
                });
        let minimum = bounds[..=top].iter().copied().fold(0.0, f64::min);
        if !(minimum.is_finite() && barrier > 0.0) {
            return Err(PotentialError::Parameter {
                name: "sites",
                value: minimum,
                why: "a molecule whose bound energy has no barrier before it falls without \
                      limit (attractive charges without a Lennard-Jones core around them)",
            });
        }
        // The bottom cell with a bound of +∞ only: the bound never fell to −∞.
        let barrier = if bounds.len() == n {
            f64::INFINITY
        } else {
            barrier
        };
        Ok((minimum, barrier))
    }

    /// The largest `R` in `(0, cutoff)` with `f(R) ≥ target` for a non-increasing `f`, by
    /// bisection, from the outer side (an upper bound).
    fn outermost(&self, f: impl Fn(f64) -> f64, target: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, self.cutoff);
        if f(hi) >= target {
            return hi;
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

    #[cold]
    fn overlap(r: f64, what: &'static str) -> PotentialError {
        PotentialError::Overlap { r, what }
    }
}

impl RigidPairPotential for SiteSite {
    #[inline]
    fn evaluate(&self, g: &RigidGeometry) -> Result<PairEval, PotentialError> {
        if !g.is_finite() {
            return Err(PotentialError::NotFinite(
                "rigid pair geometry (r_ij, q_i or q_j)",
            ));
        }
        let mut out = PairEval::default();
        if g.r_ij.length_squared() >= self.cutoff2 {
            return Ok(out);
        }
        let n = self.sites.len();
        let (arm_i, arm_j) = self.lab_arms(g.q_i, g.q_j);
        let (arm_i, arm_j) = (&arm_i[..n], &arm_j[..n]);
        let rc = self.dsf.r_cut;
        for t in &self.terms {
            let (a, b) = (arm_i[t.a], arm_j[t.b]);
            let d = g.r_ij + a - b;
            let r2 = d.length_squared();
            if r2 >= self.r_cut2 {
                continue;
            }
            if r2 == 0.0 {
                return Err(Self::overlap(0.0, "two sites coincide"));
            }
            let r = r2.sqrt();
            let inv_r = 1.0 / r;
            let (mut u, mut du) = (0.0, 0.0);
            if t.coulomb != 0.0 {
                let x = self.dsf.alpha * r;
                let e = libm::erfc(x);
                let gauss = (-self.alpha2 * r2).exp();
                u += t.coulomb * (e * inv_r - self.c_shift + self.c_slope * (r - rc));
                du += t.coulomb
                    * (-e * inv_r * inv_r - self.two_a_sqrt_pi * gauss * inv_r + self.c_slope);
            }
            if let Some(lj) = &t.lj {
                let (v, dv) = lj.eval(r, rc);
                u += v;
                du += dv;
            }
            // The force on site a: −u'(r) d/r; its moments about both centres.
            let f = (-du * inv_r) * d;
            out.energy += u;
            out.force += f;
            out.torque_i += a.cross(f);
            out.torque_j -= b.cross(f);
        }
        if out.is_finite() {
            Ok(out)
        } else {
            Err(Self::overlap(
                g.r_ij.length(),
                "the energy or its derivatives overflow binary64",
            ))
        }
    }

    /// `U(τ) ∈ U + U̇τ ± Kτ²/2` over `[0, h]` ([`RigidPairPotential::taylor_model`]). Each
    /// site pair's distance `d` has `Ü = Σ (u''ḋ² + u'd̈)`, with `|ḋ| ≤ S = |v| + W_i|a| +
    /// W_j|b|` (`W` the flight's spin bounds, `a`, `b` the two arms), `d ≥ d₀ − Sh` on the window
    /// and `|d̈| = |(|ḋ_vec|² − ḋ²)/d + d̂·d̈_vec| ≤ S²/d + A` (`A` the
    /// [`point_acceleration`](RigidFlight::point_acceleration)); `|u'|` and `|u''|` are bounded
    /// at that closest distance (decreasing envelopes, tabulated every 0.01 Å). A site pair
    /// that stays beyond `R_c` adds nothing; `u''` jumps where one crosses `R_c` while `u` and
    /// `u'` are continuous, which a second-order remainder allows. `None` where a site pair
    /// may come within `10⁻³ Å` (the bounds are useless there).
    fn taylor_model(&self, f: &RigidFlight, h: f64) -> Option<TaylorModel> {
        let g = RigidGeometry::new(f.r, f.q_i, f.q_j);
        let e = self.evaluate(&g).ok()?;
        let x = e.energy;
        let dx = e.rate(f.v, f.w_i, f.w_j);
        let vrel = f.v.length();
        // Centres that stay beyond the molecular cut-off: U ≡ 0 on the whole window.
        if f.r.length() - vrel * h >= self.cutoff {
            return Some(TaylorModel::first_order(x, dx, 0.0));
        }
        let n = self.sites.len();
        let (arm_i, arm_j) = self.lab_arms(f.q_i, f.q_j);
        let (arm_i, arm_j) = (&arm_i[..n], &arm_j[..n]);
        let rc = self.dsf.r_cut;
        let mut k = 0.0;
        for (index, t) in self.terms.iter().enumerate() {
            let d0 = (f.r + arm_i[t.a] - arm_j[t.b]).length();
            let speed = vrel + f.spin_i * t.arm_a + f.spin_j * t.arm_b;
            let d_lo = d0 - speed * h;
            if d_lo >= rc {
                continue;
            }
            if d_lo.is_nan() || d_lo <= 1e-3 {
                return None;
            }
            let accel = f.point_acceleration(t.arm_a, t.arm_b);
            let (d1, d2) = self.derivative_bounds_at(index, t, d_lo);
            k += d2 * speed * speed + d1 * (speed * speed / d_lo + accel);
        }
        k.is_finite().then_some(TaylorModel::first_order(x, dx, k))
    }

    #[inline]
    fn certifies(&self) -> bool {
        true
    }

    /// A rigorous lower bound on `U` outside the barrier (module documentation).
    fn minimum(&self) -> f64 {
        self.minimum
    }

    /// The largest Lennard-Jones `σ` of a site.
    fn length_scale(&self) -> f64 {
        self.length
    }

    /// An upper bound on the reach from the monotone envelopes of the module documentation;
    /// at most [`cutoff`](SiteSite::cutoff).
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
    fn spc_e_geometry_and_moments() {
        let s = spc_e_sites();
        let oh = (s[1].position - s[0].position).length();
        assert!((oh - 1.0).abs() < 1e-15);
        let angle = (s[1].position - s[0].position)
            .angle_between(s[2].position - s[0].position)
            .to_degrees();
        assert!((angle - 109.47).abs() < 1e-12);
        // Centre of mass at the origin, neutral, principal frame.
        let com: DVec3 = s.iter().map(|x| x.mass * x.position).sum();
        assert!(com.length() < 1e-15);
        assert!(s.iter().map(|x| x.charge).sum::<f64>().abs() < 1e-15);
        let t = inertia_tensor(&s);
        for (a, row) in t.iter().enumerate() {
            for (b, x) in row.iter().enumerate() {
                if a == b {
                    let want = SPC_E_MOMENTS[a];
                    assert!((x - want).abs() < 5e-5 * want, "{a}: {x} vs {want}");
                } else {
                    assert!(x.abs() < 1e-15);
                }
            }
        }
        // Dipole 2.351 D along body z (0.2081943 e Å per D).
        let mu: DVec3 = s.iter().map(|x| x.charge * x.position).sum();
        assert!(mu.x == 0.0 && mu.y.abs() < 1e-16 && mu.z > 0.0);
        assert!(
            (mu.z / 0.208_194_3 - 2.351).abs() < 1e-3,
            "{}",
            mu.z / 0.2081943
        );
    }

    #[test]
    fn dsf_kernel_vanishes_with_its_slope_and_is_decreasing() {
        let w = SiteSite::spc_e();
        let rc = w.dsf().r_cut;
        assert_eq!(w.dsf_kernel(rc), 0.0);
        let h = 1e-5;
        assert!(w.dsf_kernel(rc - h) < 1e-9, "{}", w.dsf_kernel(rc - h));
        let mut last = f64::INFINITY;
        for k in 1..900 {
            let v = w.dsf_kernel(k as f64 * 0.01);
            assert!(v > 0.0 && v < last, "{k}");
            last = v;
        }
    }

    #[test]
    fn spc_e_bounds() {
        let w = SiteSite::spc_e();
        // The loose bound and a barrier far above any hard core a scene would use.
        assert!(
            w.minimum() < -30.0 && w.minimum() > -2000.0,
            "{}",
            w.minimum()
        );
        assert!(
            w.barrier() > 1e4 && w.barrier().is_finite(),
            "{}",
            w.barrier()
        );
        assert!(w.reach(-0.5).unwrap() < w.cutoff());
        assert!(w.reach(0.5).unwrap() < w.cutoff());
        assert!(w.reach(-10.0).unwrap() < w.reach(-0.5).unwrap());
        assert_eq!(w.reach(2.0 * w.minimum()).unwrap(), 0.0);
    }

    #[test]
    fn bad_parameters_are_named() {
        let sites = spc_e_sites();
        let err = |s: &[Site], c: f64, d: Dsf| SiteSite::new(s, c, d).unwrap_err().to_string();
        assert!(err(&[], COULOMB, Dsf::FG06).contains("sites"));
        assert!(err(&sites, -1.0, Dsf::FG06).contains("coulomb"));
        let d = Dsf {
            alpha: -0.1,
            ..Dsf::FG06
        };
        assert!(err(&sites, COULOMB, d).contains("alpha"));
        let d = Dsf {
            r_cut: 3.0,
            ..Dsf::FG06
        };
        assert!(err(&sites, COULOMB, d).contains("r_cut"));
        // Charges without any core: nothing stops a collapse.
        let mut bare = sites;
        bare[0].epsilon = 0.0;
        assert!(err(&bare, COULOMB, Dsf::FG06).contains("barrier"));
    }
}
