//! RATTLE for free atoms under distance constraints, and the cached trajectory of one molecule.
//!
//! Between events no force acts on a molecule but the constraint forces (000 §II.A), whose
//! multipliers depend on positions and velocities: no closed form exists for a set of bonds that
//! does not hold the molecule rigid. One RATTLE step of size `h` (the velocity-Verlet form of
//! SHAKE with a velocity stage) from `(q, u)`, with `w_k = 1/m_k` and bonds `α = (a, b)` of
//! length `d_α`:
//!
//! ```text
//! q' = q + h u − h² Σ_α λ_α w_k (q_a − q_b)(±)     with |q'_a − q'_b|² = d_α² for every α,
//! u½ = (q' − q) / h,
//! u' = u½ − Σ_α μ_α w_k (q'_a − q'_b)(±)           with (q'_a − q'_b)·(u'_a − u'_b) = 0.
//! ```
//!
//! Both multiplier sets are solved for all bonds at once: `λ` by Newton's method on the bond
//! equations (matrix SHAKE: the matrix `r'_α·r_β (w s)` of the bonds now and a step ago, a
//! small dense solve per iteration, quadratic convergence), `μ` by one solve of the linear
//! system with the `Z` matrix of 000 §II.A at the new positions (and a refinement if needed),
//! to the relative tolerance [`Constraints::tolerance`]: a bond is converged when
//! `|r² − d²| ≤ 2 tol d²` (its length is right to `tol`), a velocity constraint when
//! `|r·ṙ| ≤ tol d v` with `v` the r.m.s. atom speed. The bond-by-bond sweeps of the original
//! SHAKE converge only linearly along a chain (a step cost twice as much with them). A bond
//! that turned by nearly a right angle in one step (`r'·r` small: the corrections along the
//! old bond cannot restore its length), a singular matrix, or no convergence after
//! [`MAX_NEWTON`] iterations is an error ([`RattleError`]) — the step is too long for the
//! motion — never a silently wrong state.
//!
//! RATTLE is symplectic and time-reversible on the constraint manifold: the bond lengths hold to
//! the tolerance at every step, the linear and angular momenta of the atoms are conserved (the
//! constraint forces are central and pairwise), and the kinetic energy (the whole energy of free
//! motion) has an error `O(h²)` that oscillates without drift.
//!
//! **Between steps.** [`Trajectory`] keeps the steps computed so far from the molecule's last
//! change (root searches mostly move forward in time, so nothing is computed twice) and gives
//! positions at any time by the cubic Hermite interpolant of the positions and velocities at the
//! two neighbouring steps, velocities by its derivative: a `C¹` path (the indicator of a root
//! search and its derivative are consistent) that meets the RATTLE steps exactly at the grid
//! points, and whose constraint error between them is `O(h⁴)`.

use collide::Bond;
use glam::DVec3;

use crate::engine::saved::StateReader;

/// Newton iterations of the position stage before it is declared not converged (it converges
/// quadratically: a handful suffice unless the step is far too long).
pub const MAX_NEWTON: usize = 50;

/// A bond whose `r'·r` is below this fraction of `d²` has turned by nearly a right angle within
/// one step: the SHAKE update along the old bond cannot restore its length.
const TURN_LIMIT: f64 = 1e-3;

/// Why a RATTLE step (or a projection onto the constraints) failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RattleError {
    /// SHAKE did not converge.
    #[error(
        "SHAKE did not converge in {MAX_NEWTON} Newton iterations (largest relative bond error \
         {violation:e}): the RATTLE step is too long for the motion, or the bonds are dependent"
    )]
    Shake {
        /// Largest `|r² − d²| / 2d²` at the end.
        violation: f64,
    },
    /// The velocity stage did not converge.
    #[error(
        "the RATTLE velocity stage did not converge in four solves (largest \
         relative rate {violation:e}): the bonds are (nearly) dependent"
    )]
    Velocity {
        /// Largest `|r·ṙ| / (d v)` at the end.
        violation: f64,
    },
    /// A bond turned by about a right angle in one step.
    #[error(
        "bond {bond} turned by about a right angle within one RATTLE step: the step is too long \
         for the molecule's internal motion"
    )]
    Turned {
        /// The bond's index.
        bond: usize,
    },
    /// A position or velocity is not finite.
    #[error("a RATTLE state is not finite")]
    NotFinite,
}

/// A molecule's masses and distance constraints: what RATTLE needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Constraints {
    inv_mass: Vec<f64>,
    bonds: Vec<Bond>,
    length2: Vec<f64>,
    tolerance: f64,
}

impl Constraints {
    /// Atoms of `masses` with `bonds` of the given `lengths`, converged to the relative
    /// `tolerance` (module documentation). The inputs are checked by the molecule type
    /// ([`FlexibleType`](super::FlexibleType)); here they are only assumed consistent.
    pub fn new(masses: &[f64], bonds: &[Bond], lengths: &[f64], tolerance: f64) -> Self {
        Constraints {
            inv_mass: masses.iter().map(|m| 1.0 / m).collect(),
            bonds: bonds.to_vec(),
            length2: lengths.iter().map(|d| d * d).collect(),
            tolerance,
        }
    }

    /// Number of atoms.
    pub fn n_atoms(&self) -> usize {
        self.inv_mass.len()
    }

    /// The bonds.
    pub fn bonds(&self) -> &[Bond] {
        &self.bonds
    }

    /// The relative tolerance of the iterations.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// Largest relative bond-length error `|r − d| / d` of positions `q`.
    pub fn violation(&self, q: &[DVec3]) -> f64 {
        self.bonds
            .iter()
            .zip(&self.length2)
            .map(|(b, &d2)| ((q[b.a] - q[b.b]).length() / d2.sqrt() - 1.0).abs())
            .fold(0.0, f64::max)
    }

    /// Largest relative bond rate `|r·ṙ| / (d v)` of velocities `u` at positions `q` (`v`: the
    /// r.m.s. atom speed; 0 for atoms at rest).
    pub fn rate_violation(&self, q: &[DVec3], u: &[DVec3]) -> f64 {
        let v = rms(u);
        if v == 0.0 {
            return 0.0;
        }
        self.bonds
            .iter()
            .zip(&self.length2)
            .map(|(b, &d2)| (q[b.a] - q[b.b]).dot(u[b.a] - u[b.b]).abs() / (d2.sqrt() * v))
            .fold(0.0, f64::max)
    }

    /// `s(k, β)`: +1 if atom `k` is bond `β`'s first atom, −1 if its second, else 0, times
    /// `w_k`: the weight with which a correction along bond `β` moves atom `k`.
    #[inline]
    fn weight(&self, k: usize, beta: usize) -> f64 {
        let b = self.bonds[beta];
        if k == b.a {
            self.inv_mass[k]
        } else if k == b.b {
            -self.inv_mass[k]
        } else {
            0.0
        }
    }

    /// The matrix `M_αβ = x_α·y_β (w s)(a_α, β) − x_α·y_β (w s)(b_α, β)`: the change of
    /// `x_α·r_α` per unit multiplier of bond `β` moving atoms along `y_β`. With `x = y` it is
    /// the `Z` matrix of 000 §II.A.
    fn matrix(&self, x: &[DVec3], y: &[DVec3], m: &mut Vec<f64>) {
        let nb = self.bonds.len();
        m.clear();
        m.resize(nb * nb, 0.0);
        for (al, b) in self.bonds.iter().enumerate() {
            for be in 0..nb {
                let c = self.weight(b.a, be) - self.weight(b.b, be);
                if c != 0.0 {
                    m[al * nb + be] = c * x[al].dot(y[be]);
                }
            }
        }
    }

    /// Moves atoms by `g_β` along `w_k s(k, β) y_β` for every bond.
    fn apply(&self, g: &[f64], y: &[DVec3], q: &mut [DVec3], mut shift: Option<&mut [DVec3]>) {
        for ((b, &gb), &yb) in self.bonds.iter().zip(g).zip(y) {
            let (da, db) = (gb * self.inv_mass[b.a] * yb, gb * self.inv_mass[b.b] * yb);
            q[b.a] += da;
            q[b.b] -= db;
            if let Some(sh) = shift.as_deref_mut() {
                sh[b.a] += da;
                sh[b.b] -= db;
            }
        }
    }

    /// Moves positions `q` onto the constraints by corrections along the bonds of the reference
    /// positions `reference` (`q` itself for a projection): mass-weighted, so the centre of mass
    /// does not move. All multipliers at once by Newton's method on the bond equations
    /// (matrix SHAKE: quadratic convergence, a few small solves, instead of the bond-by-bond
    /// sweeps that converge linearly along a chain). `shift` receives the displacement of every
    /// atom (used for the velocity of a RATTLE step).
    ///
    /// # Errors
    /// [`RattleError::Turned`], [`RattleError::Shake`], [`RattleError::NotFinite`].
    fn shake(
        &self,
        reference: &[DVec3],
        q: &mut [DVec3],
        mut shift: Option<&mut [DVec3]>,
    ) -> Result<(), RattleError> {
        let nb = self.bonds.len();
        let tol2 = 2.0 * self.tolerance;
        let old: Vec<DVec3> = self
            .bonds
            .iter()
            .map(|b| reference[b.a] - reference[b.b])
            .collect();
        let (mut m, mut res) = (Vec::with_capacity(nb * nb), vec![0.0; nb]);
        let mut now = vec![DVec3::ZERO; nb];
        let mut worst = f64::INFINITY;
        for _ in 0..MAX_NEWTON {
            worst = 0.0;
            for (al, (b, &d2)) in self.bonds.iter().zip(&self.length2).enumerate() {
                let s = q[b.a] - q[b.b];
                now[al] = s;
                res[al] = 0.5 * (d2 - s.length_squared());
                worst = worst.max(2.0 * res[al].abs() / d2);
                let dot = s.dot(old[al]);
                if dot.is_nan() || dot <= TURN_LIMIT * d2 {
                    return Err(if dot.is_finite() {
                        RattleError::Turned { bond: al }
                    } else {
                        RattleError::NotFinite
                    });
                }
            }
            if worst <= tol2 {
                return Ok(());
            }
            // Σ_β M_αβ g_β = (d² − |r'_α|²)/2, M from the bonds now (x) and before (y).
            self.matrix(&now, &old, &mut m);
            if !solve(&mut m, &mut res) {
                return Err(RattleError::Shake { violation: worst });
            }
            self.apply(&res, &old, q, shift.as_deref_mut());
        }
        Err(RattleError::Shake { violation: worst })
    }

    /// Projects velocities `u` onto the tangent of the constraints at positions `q` (the RATTLE
    /// velocity stage): mass-weighted corrections along the bonds, so the total momentum does
    /// not change, from one solve of `Z μ = (r_α·ṙ_α)` (000 §II.A) and a refinement if the
    /// rates are not yet below the tolerance.
    ///
    /// # Errors
    /// [`RattleError::Velocity`], [`RattleError::NotFinite`].
    pub fn project_velocities(&self, q: &[DVec3], u: &mut [DVec3]) -> Result<(), RattleError> {
        let v = rms(u);
        if !v.is_finite() {
            return Err(RattleError::NotFinite);
        }
        if v == 0.0 {
            return Ok(());
        }
        let nb = self.bonds.len();
        let tol = self.tolerance * v;
        let r: Vec<DVec3> = self.bonds.iter().map(|b| q[b.a] - q[b.b]).collect();
        let (mut m, mut rate) = (Vec::with_capacity(nb * nb), vec![0.0; nb]);
        for _ in 0..4 {
            let mut worst: f64 = 0.0;
            for ((b, &d2), (x, ra)) in self
                .bonds
                .iter()
                .zip(&self.length2)
                .zip(rate.iter_mut().zip(&r))
            {
                *x = -ra.dot(u[b.a] - u[b.b]);
                worst = worst.max(x.abs() / d2.sqrt());
            }
            if worst <= tol {
                return Ok(());
            }
            self.matrix(&r, &r, &mut m);
            if !solve(&mut m, &mut rate) {
                break;
            }
            self.apply(&rate, &r, u, None);
        }
        Err(RattleError::Velocity {
            violation: self.rate_violation(q, u),
        })
    }

    /// Projects positions onto the constraints (SHAKE along their own bonds; centre of mass
    /// kept).
    ///
    /// # Errors
    /// [`RattleError::Turned`], [`RattleError::Shake`].
    pub fn project_positions(&self, q: &mut [DVec3]) -> Result<(), RattleError> {
        let reference = q.to_vec();
        self.shake(&reference, q, None)
    }

    /// One RATTLE step of size `h` from `(q, u)` into `(q_out, u_out)` (module documentation).
    ///
    /// # Errors
    /// [`RattleError`] when the step is too long for the motion.
    pub fn step(
        &self,
        h: f64,
        q: &[DVec3],
        u: &[DVec3],
        q_out: &mut [DVec3],
        u_out: &mut [DVec3],
    ) -> Result<(), RattleError> {
        for k in 0..q.len() {
            q_out[k] = q[k] + h * u[k];
            u_out[k] = DVec3::ZERO;
        }
        // `u_out` collects the SHAKE displacements; u½ = u + displacement / h (not (q' − q)/h,
        // which would lose the digits of q that cancel).
        self.shake(q, q_out, Some(u_out))?;
        for k in 0..q.len() {
            u_out[k] = u[k] + u_out[k] / h;
        }
        self.project_velocities(q_out, u_out)?;
        if q_out.iter().chain(u_out.iter()).all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(RattleError::NotFinite)
        }
    }
}

/// Solves `m x = b` (`m` row major, `b.len()` square) in place by Gaussian elimination with
/// partial pivoting; `false` for a (numerically) singular `m`.
fn solve(m: &mut [f64], b: &mut [f64]) -> bool {
    let n = b.len();
    let scale = m.iter().fold(0.0_f64, |s, x| s.max(x.abs()));
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&x, &y| m[x * n + col].abs().total_cmp(&m[y * n + col].abs()))
            .unwrap_or(col);
        let p = m[piv * n + col];
        if p.is_nan() || p.abs() <= 1e-14 * scale {
            return false;
        }
        if piv != col {
            for k in 0..n {
                m.swap(piv * n + k, col * n + k);
            }
            b.swap(piv, col);
        }
        for row in col + 1..n {
            let f = m[row * n + col] / p;
            if f != 0.0 {
                for k in col..n {
                    m[row * n + k] -= f * m[col * n + k];
                }
                b[row] -= f * b[col];
            }
        }
    }
    for row in (0..n).rev() {
        let mut s = b[row];
        for k in row + 1..n {
            s -= m[row * n + k] * b[k];
        }
        b[row] = s / m[row * n + row];
    }
    true
}

/// Root mean square of vectors' lengths.
fn rms(u: &[DVec3]) -> f64 {
    if u.is_empty() {
        return 0.0;
    }
    (u.iter().map(|x| x.length_squared()).sum::<f64>() / u.len() as f64).sqrt()
}

/// Steps held before [`Trajectory::trim`] drops those behind the present. A molecule holds at
/// most this many behind the present plus those its searches looked ahead (up to
/// `search.window / rattle.step`), whatever the time since its last change: its memory does not
/// grow with the run. The steps dropped are never asked for again (the loop only moves
/// forward), so the value changes memory, not results; dropping costs a copy of the steps
/// ahead, a few dozen.
pub const TRIM_AT: usize = 32;

/// The internal motion of one molecule from its last change: RATTLE steps of size `h` from
/// time `t0`, computed on demand and kept (module documentation). Steps behind the loop's
/// present can be dropped ([`Trajectory::trim`]), so a molecule that goes long without an event
/// holds a bounded number of them.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    t0: f64,
    h: f64,
    n: usize,
    /// The state at the last change (step 0), kept whatever is trimmed.
    q0: Vec<DVec3>,
    u0: Vec<DVec3>,
    /// Index of the first step held.
    first: usize,
    /// Positions of step `first + k` at `q[k n .. (k + 1) n]`.
    q: Vec<DVec3>,
    /// Velocities likewise.
    u: Vec<DVec3>,
    failed: Option<RattleError>,
}

impl Trajectory {
    /// A trajectory from positions `q` and velocities `u` (relative to the centre of mass, on
    /// the constraints) at time `t0`, with RATTLE step `h`.
    pub fn new(t0: f64, h: f64, q: &[DVec3], u: &[DVec3]) -> Self {
        Trajectory {
            t0,
            h,
            n: q.len(),
            q0: q.to_vec(),
            u0: u.to_vec(),
            first: 0,
            q: q.to_vec(),
            u: u.to_vec(),
            failed: None,
        }
    }

    /// Appends the trajectory to a saved state: `t0`, the index of the first step held, the
    /// number of steps held, whether a step failed, the state at the last change and the
    /// steps held. Restoring the steps rather than computing them again keeps a resumed run's
    /// step counts equal to an uninterrupted run's.
    pub fn write_numbers(&self, out: &mut Vec<f64>) {
        out.extend_from_slice(&[
            self.t0,
            self.first as f64,
            self.held_steps() as f64,
            f64::from(u8::from(self.failed.is_some())),
        ]);
        for v in [&self.q0, &self.u0, &self.q, &self.u] {
            out.extend(v.iter().flat_map(|x| x.to_array()));
        }
    }

    /// Reads what [`write_numbers`](Self::write_numbers) wrote, for a molecule of `n` atoms
    /// moved with RATTLE step `h`.
    ///
    /// # Errors
    /// Numbers that do not fit, or a trajectory whose step had failed.
    pub fn read_numbers(r: &mut StateReader, h: f64, n: usize) -> Result<Self, String> {
        let t0 = r.real("a trajectory's start")?;
        let first = r.index("a trajectory's first step", 1 << 52)? as usize;
        let held = r.index("a trajectory's steps held", 1 << 32)? as usize;
        if r.index("a trajectory's failure flag", 2)? == 1 {
            return Err("a RATTLE step of the saved state had failed".to_owned());
        }
        if held == 0 {
            return Err("a trajectory holds no step".to_owned());
        }
        let mut vecs = |count: usize, what: &str| -> Result<Vec<DVec3>, String> {
            let x = r.take(3 * count, what)?;
            Ok(x.chunks_exact(3).map(DVec3::from_slice).collect())
        };
        let q0 = vecs(n, "a molecule's positions")?;
        let u0 = vecs(n, "a molecule's velocities")?;
        let q = vecs(held * n, "a trajectory's positions")?;
        let u = vecs(held * n, "a trajectory's velocities")?;
        Ok(Trajectory {
            t0,
            h,
            n,
            q0,
            u0,
            first,
            q,
            u,
            failed: None,
        })
    }

    /// Starts afresh from `(q, u)` at `t0` (the molecule changed).
    pub fn reset(&mut self, t0: f64, q: &[DVec3], u: &[DVec3]) {
        self.t0 = t0;
        for v in [&mut self.q0, &mut self.q] {
            v.clear();
            v.extend_from_slice(q);
        }
        for v in [&mut self.u0, &mut self.u] {
            v.clear();
            v.extend_from_slice(u);
        }
        self.first = 0;
        self.failed = None;
    }

    /// The time of the last change.
    pub fn t0(&self) -> f64 {
        self.t0
    }

    /// Moves the time origin by `-dt` (the loop's re-basing): the steps stay.
    pub fn shift_time(&mut self, dt: f64) {
        self.t0 -= dt;
    }

    /// Positions and velocities at the last change.
    pub fn initial(&self) -> (&[DVec3], &[DVec3]) {
        (&self.q0, &self.u0)
    }

    /// Steps computed since the last change (including the initial state), held or trimmed.
    pub fn computed_steps(&self) -> usize {
        self.first + self.q.len() / self.n.max(1)
    }

    /// Steps held.
    pub fn held_steps(&self) -> usize {
        self.q.len() / self.n.max(1)
    }

    /// Why the trajectory could not be continued, if it could not.
    pub fn failure(&self) -> Option<&RattleError> {
        self.failed.as_ref()
    }

    /// Drops the steps before the one containing `now` once more than [`TRIM_AT`] are held.
    /// The loop never asks for a time before its present, so they are not needed again (if
    /// one were, it would be computed afresh from the initial state, identically).
    pub fn trim(&mut self, now: f64) {
        let (k, _) = self.locate(now);
        if self.held_steps() > TRIM_AT && k > self.first && k < self.computed_steps() {
            let drop = (k - self.first) * self.n;
            self.q.drain(..drop);
            self.u.drain(..drop);
            self.first = k;
        }
    }

    /// Step index and fraction `s ∈ [0, 1)` of time `t` (times before `t0`, which the loop
    /// never asks for beyond round-off, extrapolate the first interval).
    #[inline]
    fn locate(&self, t: f64) -> (usize, f64) {
        let x = (t - self.t0) / self.h;
        if x <= 0.0 {
            return (0, x);
        }
        let k = x.floor();
        (k as usize, x - k)
    }

    /// Computes the steps up to index `k` (from the initial state again if `k` was trimmed).
    fn extend(&mut self, c: &Constraints, k: usize) -> Result<(), RattleError> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        let n = self.n;
        if k < self.first + 1 {
            self.q.clone_from(&self.q0);
            self.u.clone_from(&self.u0);
            self.first = 0;
        }
        while self.computed_steps() < k + 1 {
            let last = self.q.len() - n;
            self.q.resize(last + 2 * n, DVec3::ZERO);
            self.u.resize(last + 2 * n, DVec3::ZERO);
            let (q_old, q_new) = self.q[last..].split_at_mut(n);
            let (u_old, u_new) = self.u[last..].split_at_mut(n);
            if let Err(e) = c.step(self.h, q_old, u_old, q_new, u_new) {
                self.q.truncate(last + n);
                self.u.truncate(last + n);
                self.failed = Some(e.clone());
                return Err(e);
            }
        }
        Ok(())
    }

    /// Position and velocity of atom `atom` at time `t` (the Hermite interpolant), computing
    /// and keeping the steps it needs.
    ///
    /// # Errors
    /// The RATTLE step that failed.
    #[inline]
    pub fn atom_at(
        &mut self,
        c: &Constraints,
        t: f64,
        atom: usize,
    ) -> Result<(DVec3, DVec3), RattleError> {
        let (k, s) = self.locate(t);
        self.extend(c, k + 1)?;
        let (n, j) = (self.n, k - self.first);
        Ok(hermite(
            self.h,
            s,
            (self.q[j * n + atom], self.u[j * n + atom]),
            (self.q[(j + 1) * n + atom], self.u[(j + 1) * n + atom]),
        ))
    }

    /// Positions and velocities of every atom at `t`, computing and keeping the steps.
    ///
    /// # Errors
    /// The RATTLE step that failed.
    pub fn state_at(
        &mut self,
        c: &Constraints,
        t: f64,
    ) -> Result<(Vec<DVec3>, Vec<DVec3>), RattleError> {
        let (k, s) = self.locate(t);
        self.extend(c, k + 1)?;
        Ok(self.interpolate(k - self.first, s, &self.q, &self.u))
    }

    /// As [`Trajectory::state_at`], without keeping new steps (for the read-only checks): steps
    /// beyond the cache are computed into a scratch copy.
    ///
    /// # Errors
    /// The RATTLE step that failed.
    pub fn peek(&self, c: &Constraints, t: f64) -> Result<(Vec<DVec3>, Vec<DVec3>), RattleError> {
        let (k, s) = self.locate(t);
        if k >= self.first && k + 2 <= self.computed_steps() {
            return Ok(self.interpolate(k - self.first, s, &self.q, &self.u));
        }
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        // Continue from the last held step, or from the start for a trimmed one.
        let (have, q, u) = if k < self.first {
            (0, &self.q0[..], &self.u0[..])
        } else {
            let last = self.held_steps() - 1;
            let n = self.n;
            (self.first + last, &self.q[last * n..], &self.u[last * n..])
        };
        let mut scratch = Trajectory::new(self.t0 + have as f64 * self.h, self.h, q, u);
        scratch.extend(c, k + 1 - have)?;
        Ok(scratch.interpolate(k - have, s, &scratch.q, &scratch.u))
    }

    fn interpolate(&self, k: usize, s: f64, q: &[DVec3], u: &[DVec3]) -> (Vec<DVec3>, Vec<DVec3>) {
        let n = self.n;
        (0..n)
            .map(|a| {
                hermite(
                    self.h,
                    s,
                    (q[k * n + a], u[k * n + a]),
                    (q[(k + 1) * n + a], u[(k + 1) * n + a]),
                )
            })
            .unzip()
    }
}

/// The cubic Hermite interpolant through `(q0, u0)` at `s = 0` and `(q1, u1)` at `s = 1` of an
/// interval of length `h`, at fraction `s`: position and time derivative.
#[inline(always)]
fn hermite(h: f64, s: f64, (q0, u0): (DVec3, DVec3), (q1, u1): (DVec3, DVec3)) -> (DVec3, DVec3) {
    // p(s) = q0 + h u0 s + c2 s² + c3 s³ with c2 = 3Δ − h(2u0 + u1), c3 = h(u0 + u1) − 2Δ.
    let delta = q1 - q0;
    let c2 = 3.0 * delta - h * (2.0 * u0 + u1);
    let c3 = h * (u0 + u1) - 2.0 * delta;
    let p = q0 + s * (h * u0 + s * (c2 + s * c3));
    let v = u0 + s * (2.0 * c2 + 3.0 * s * c3) / h;
    (p, v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// A 4-atom chain with unequal masses: three bonds, free bond and torsion angles.
    fn chain() -> (Vec<DVec3>, Vec<DVec3>, Constraints) {
        let q = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.4, 0.9, 0.0),
            DVec3::new(2.1, 1.1, 0.6),
        ];
        let masses = [1.0, 2.0, 1.5, 0.7];
        let bonds = [Bond::new(0, 1), Bond::new(1, 2), Bond::new(2, 3)];
        let lengths: Vec<f64> = bonds.iter().map(|b| (q[b.a] - q[b.b]).length()).collect();
        let c = Constraints::new(&masses, &bonds, &lengths, 1e-12);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        let mut u: Vec<DVec3> = (0..4)
            .map(|_| {
                DVec3::new(
                    rng.random::<f64>() - 0.5,
                    rng.random::<f64>() - 0.5,
                    rng.random::<f64>() - 0.5,
                ) * 3.0
            })
            .collect();
        // No centre-of-mass motion, then onto the tangent.
        let m: f64 = masses.iter().sum();
        let p = masses
            .iter()
            .zip(&u)
            .fold(DVec3::ZERO, |s, (&mk, &uk)| s + mk * uk);
        for x in &mut u {
            *x -= p / m;
        }
        c.project_velocities(&q, &mut u).unwrap();
        (q, u, c)
    }

    fn kinetic(c: &Constraints, u: &[DVec3]) -> f64 {
        c.inv_mass
            .iter()
            .zip(u)
            .map(|(w, x)| 0.5 * x.length_squared() / w)
            .sum()
    }

    #[test]
    fn a_chain_keeps_its_bonds_and_momenta_over_many_steps() {
        let (q0, u0, c) = chain();
        assert!(c.rate_violation(&q0, &u0) < 1e-11);
        let (mut q, mut u) = (q0.clone(), u0.clone());
        let (mut q1, mut u1) = (q.clone(), u.clone());
        let k0 = kinetic(&c, &u);
        let mut worst: f64 = 0.0;
        let mut worst_rate: f64 = 0.0;
        let mut ke_dev: f64 = 0.0;
        for _ in 0..100_000 {
            c.step(0.002, &q, &u, &mut q1, &mut u1).unwrap();
            std::mem::swap(&mut q, &mut q1);
            std::mem::swap(&mut u, &mut u1);
            worst = worst.max(c.violation(&q));
            worst_rate = worst_rate.max(c.rate_violation(&q, &u));
            ke_dev = ke_dev.max((kinetic(&c, &u) - k0).abs() / k0);
        }
        // Bond lengths to the SHAKE tolerance, rates to the velocity tolerance.
        assert!(worst <= 1.01e-12, "bond error {worst:e}");
        assert!(worst_rate <= 1.01e-12, "rate error {worst_rate:e}");
        // Momentum stays zero, the angular momentum constant (central constraint forces).
        let masses: Vec<f64> = c.inv_mass.iter().map(|w| 1.0 / w).collect();
        let p = masses
            .iter()
            .zip(&u)
            .fold(DVec3::ZERO, |s, (&m, &x)| s + m * x);
        assert!(p.length() < 1e-12, "P {p}");
        let l = |q: &[DVec3], u: &[DVec3]| {
            masses
                .iter()
                .zip(q.iter().zip(u))
                .fold(DVec3::ZERO, |s, (&m, (&x, &v))| s + m * x.cross(v))
        };
        let (la, lb) = (l(&q0, &u0), l(&q, &u));
        assert!((la - lb).length() < 1e-9 * la.length(), "L {la} -> {lb}");
        // The kinetic energy oscillates at O(h²) without drift.
        assert!(ke_dev < 1e-3, "kinetic energy deviates by {ke_dev:e}");
        assert!(ke_dev > 0.0);
    }

    #[test]
    fn kinetic_energy_error_scales_as_h_squared() {
        let dev = |h: f64| {
            let (mut q, mut u, c) = chain();
            let (mut q1, mut u1) = (q.clone(), u.clone());
            let k0 = kinetic(&c, &u);
            let mut d: f64 = 0.0;
            let steps = (2.0 / h).round() as usize;
            for _ in 0..steps {
                c.step(h, &q, &u, &mut q1, &mut u1).unwrap();
                std::mem::swap(&mut q, &mut q1);
                std::mem::swap(&mut u, &mut u1);
                d = d.max((kinetic(&c, &u) - k0).abs());
            }
            d
        };
        let (a, b) = (dev(0.01), dev(0.005));
        let ratio = a / b;
        assert!(ratio > 3.3 && ratio < 4.8, "{a:e} / {b:e} = {ratio}");
    }

    #[test]
    fn too_long_a_step_is_an_error_not_a_state() {
        let (q, u, c) = chain();
        let (mut q1, mut u1) = (q.clone(), u.clone());
        // Speeds of order 1 over bonds of order 1: a step of 3 turns the bonds far around.
        let e = c.step(3.0, &q, &u, &mut q1, &mut u1).unwrap_err();
        assert!(
            matches!(e, RattleError::Turned { .. } | RattleError::Shake { .. }),
            "{e:?}"
        );
        let bad = vec![DVec3::NAN; 4];
        assert!(c.step(0.01, &q, &bad, &mut q1, &mut u1).is_err());
    }

    #[test]
    fn hermite_meets_the_steps_and_is_consistent() {
        let (q, u, c) = chain();
        let h = 0.01;
        let mut t = Trajectory::new(2.0, h, &q, &u);
        let (p, v) = t.atom_at(&c, 2.0, 2).unwrap();
        assert_eq!((p, v), (q[2], u[2]));
        let (p5, v5) = t.atom_at(&c, 2.05, 3).unwrap();
        let (qs, us) = (&t.q[5 * 4..6 * 4].to_vec(), &t.u[5 * 4..6 * 4].to_vec());
        assert!((p5 - qs[3]).length() < 1e-14 && (v5 - us[3]).length() < 1e-13);
        // The derivative is the derivative of the position.
        let (ta, tb) = (2.0333, 2.0333 + 1e-7);
        let (pa, va) = t.atom_at(&c, ta, 1).unwrap();
        let (pb, _) = t.atom_at(&c, tb, 1).unwrap();
        assert!(((pb - pa) / 1e-7 - va).length() < 1e-6);
        // Between steps the bonds hold to O(h⁴).
        let (qm, _) = t.state_at(&c, 2.0337).unwrap();
        assert!(c.violation(&qm) < 1e-7, "{:e}", c.violation(&qm));
        // Peeking beyond the cache agrees with computing, and keeps nothing.
        let before = t.computed_steps();
        let (qp, up) = t.peek(&c, 2.4321).unwrap();
        assert_eq!(t.computed_steps(), before);
        let (qc, uc) = t.state_at(&c, 2.4321).unwrap();
        assert_eq!((qp, up), (qc, uc));
    }

    /// A molecule that goes 10⁵ steps without a change, asked for its state as the loop moves
    /// on and trimmed as the model does, holds at most [`TRIM_AT`] steps and a few, in storage
    /// that does not grow with the steps.
    #[test]
    fn a_long_free_flight_holds_a_bounded_number_of_steps() {
        let (q, u, c) = chain();
        let h = 0.001;
        let mut t = Trajectory::new(0.0, h, &q, &u);
        let mut most = 0;
        for k in 1..100_000 {
            let now = k as f64 * h + 0.3 * h;
            t.trim(now);
            // A search looks a few steps ahead.
            t.state_at(&c, now + 5.0 * h).unwrap();
            most = most.max(t.held_steps());
        }
        assert!(most <= TRIM_AT + 8, "{most} steps held");
        let per_step = t.n;
        assert!(
            t.q.capacity() <= 2 * (TRIM_AT + 8) * per_step,
            "{} positions of capacity",
            t.q.capacity()
        );
    }

    #[test]
    fn trimming_keeps_the_trajectory() {
        let (q, u, c) = chain();
        let mut t = Trajectory::new(0.0, 0.001, &q, &u);
        let (early, late) = (0.4567, 1.7891);
        let a = t.state_at(&c, early).unwrap();
        let b = t.state_at(&c, late).unwrap();
        assert!(t.held_steps() > TRIM_AT);
        t.trim(late);
        assert!(t.held_steps() <= 2, "{}", t.held_steps());
        assert_eq!(t.computed_steps(), 1791);
        // The same states after trimming: held, peeked and recomputed from the start.
        assert_eq!(t.state_at(&c, late).unwrap(), b);
        assert_eq!(t.peek(&c, early).unwrap(), a);
        assert_eq!(t.state_at(&c, early).unwrap(), a);
        assert_eq!(t.initial(), (&q[..], &u[..]));
    }
}
