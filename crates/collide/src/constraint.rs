//! The constrained-Lagrangian rule (000 §IV.A): atoms held together by distance constraints.
//!
//! A molecule is a set of atoms (masses `m_k`, positions `r_k`, velocities `v_k`) and holonomic
//! distance constraints `σ_α = ½(|r_p − r_q|² − d_α²) = 0` between atom pairs `α = (p, q)`: all
//! the distances of a rigid molecule, or only some (bond lengths) for a semi-flexible one.
//! When atom `i` collides with atom `j` (of another molecule, or of the same one if no chain of
//! constraints holds them rigidly) the atoms receive the impulse `±S n`, `n = r_i − r_j`, and
//! the constraint forces an impulsive part `−Λ_α ∇_k σ_α` (000 §IV.A):
//!
//! ```text
//! Δp_k = S e_k − Λ_α ∇_k σ_α,          e_i = n, e_j = −n, e_k = 0 otherwise.
//! ```
//!
//! The velocity constraints `∇σ_α·v = 0` must hold before and after, which fixes the multipliers
//! linearly in `S`: `Z Λ = S g` with the `Z` matrix of 000 §II.A,
//! `Z_αβ = Σ_k (1/m_k) ∇_kσ_α·∇_kσ_β`, and `g_α = Σ_k (1/m_k) ∇_kσ_α·e_k`. So
//! `Δp_k = S D_k` with `D_k = e_k − μ_α ∇_kσ_α`, `Z μ = g`, and energy conservation is again
//! the quadratic `a S² + b S + ΔV = 0` with
//!
//! ```text
//! a = ½ Σ_k |D_k|²/m_k,    b = Σ_k v_k·D_k   (= n·(v_i − v_j) when the constraints hold).
//! ```
//!
//! Both are evaluated as the sums over atoms: `a` is then a sum of positive terms (no
//! cancellation, unlike the equivalent `½(1/m_i + 1/m_j − g·μ)`), and energy is conserved
//! exactly for the impulse actually applied, even if the incoming velocities violate the
//! constraints by round-off.
//!
//! `Z` is symmetric positive definite when the constraints are independent; it is factorised by
//! Cholesky (faer) and a pivot smaller than [`PIVOT_TOLERANCE`] times its diagonal entry
//! reports the constraint set as redundant or singular (a linear triatomic with three distance
//! constraints, say) instead of producing NaN. Constraints of different molecules never share
//! an atom, so `Z` is block diagonal and each molecule is solved on its own.
//!
//! Linear momentum is conserved since `Σ_k ∇_kσ_α = 0`, angular momentum about any point since
//! `Σ_k r_k × ∇_kσ_α = 0` and `n ∥ r_i − r_j`.

use faer::MatMut;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use glam::DVec3;

use crate::energy::{self, Impulse};
use crate::{Body, CollideError, Velocity};

/// Smallest accepted Cholesky pivot of `Z`, relative to its diagonal entry. Below it the
/// constraint is (numerically) implied by the others. Near the limit the multipliers lose about
/// `-log10(pivot)` digits: velocity constraints are preserved to roughly `ε/pivot`.
pub const PIVOT_TOLERANCE: f64 = 1e-10;

/// Smallest accepted inverse effective mass of the colliding pair, relative to that of the two
/// atoms unconstrained. Below it the constraints hold the two atoms (numerically) rigidly
/// together and no finite impulse resolves the collision.
pub const MOBILITY_TOLERANCE: f64 = 1e-10;

/// A distance constraint: the distance between atoms `a` and `b` of a molecule is fixed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Bond {
    /// One atom.
    pub a: usize,
    /// The other atom.
    pub b: usize,
}

impl Bond {
    /// The constraint between atoms `a` and `b`.
    #[inline]
    pub const fn new(a: usize, b: usize) -> Self {
        Self { a, b }
    }
}

/// One molecule at the instant of the event: its atoms and constraints. The velocities are
/// updated in place.
#[derive(Debug)]
pub struct Molecule<'a> {
    /// Atom masses.
    pub masses: &'a [f64],
    /// Atom positions (lab frame, unwrapped: distances are taken directly).
    pub positions: &'a [DVec3],
    /// Atom velocities; replaced by the post-event velocities.
    pub velocities: &'a mut [DVec3],
    /// Distance constraints between atoms of this molecule.
    pub bonds: &'a [Bond],
}

impl Molecule<'_> {
    fn check(&self) -> Result<(), CollideError> {
        let n = self.masses.len();
        if self.positions.len() != n || self.velocities.len() != n {
            return Err(CollideError::Lengths {
                masses: n,
                positions: self.positions.len(),
                velocities: self.velocities.len(),
            });
        }
        for (index, &mass) in self.masses.iter().enumerate() {
            if !(mass.is_finite() && mass > 0.0) {
                return Err(CollideError::AtomMass { index, mass });
            }
        }
        for bond in self.bonds {
            for index in [bond.a, bond.b] {
                if index >= n {
                    return Err(CollideError::AtomIndex { index, count: n });
                }
            }
            if bond.a == bond.b || self.positions[bond.a] == self.positions[bond.b] {
                return Err(CollideError::Coincident(bond.a, bond.b));
            }
        }
        Ok(())
    }

    fn atom(&self, index: usize) -> Result<DVec3, CollideError> {
        self.positions
            .get(index)
            .copied()
            .ok_or(CollideError::AtomIndex {
                index,
                count: self.positions.len(),
            })
    }
}

/// The constrained-Lagrangian rule with its reusable workspace: after the first events of a given
/// size it allocates nothing.
///
/// ```
/// use collide::{Bond, ConstraintSolver, Molecule, Outcome};
/// use glam::DVec3;
///
/// // Two rigid diatomics; atom 1 of the first hits atom 0 of the second head on.
/// let (pos_a, pos_b) = ([DVec3::ZERO, DVec3::X], [DVec3::new(2.0, 0.0, 0.0), DVec3::new(2.0, 1.0, 0.0)]);
/// let mut vel_a = [DVec3::new(1.0, 0.0, 0.0); 2];
/// let mut vel_b = [DVec3::ZERO; 2];
/// let bond = [Bond::new(0, 1)];
/// let mut solver = ConstraintSolver::new();
/// let imp = solver.between(
///     Molecule { masses: &[1.0, 1.0], positions: &pos_a, velocities: &mut vel_a, bonds: &bond },
///     1,
///     Molecule { masses: &[1.0, 1.0], positions: &pos_b, velocities: &mut vel_b, bonds: &bond },
///     0,
///     f64::INFINITY,
/// )?;
/// assert_eq!(imp.outcome, Outcome::Reflected);
/// // The bond lengths are still constant: no relative velocity along either bond.
/// assert!((vel_a[1] - vel_a[0]).dot(pos_a[1] - pos_a[0]).abs() < 1e-15);
/// assert!((vel_b[1] - vel_b[0]).dot(pos_b[1] - pos_b[0]).abs() < 1e-15);
/// # Ok::<(), collide::CollideError>(())
/// ```
#[derive(Debug)]
pub struct ConstraintSolver {
    work: Workspace,
    /// `D_k` of the first molecule (or of the only one).
    dir_i: Vec<DVec3>,
    /// `D_k` of the second molecule.
    dir_j: Vec<DVec3>,
}

struct Workspace {
    /// Room for the `Z` matrix (column major, `capacity²`).
    z: Vec<f64>,
    /// Right-hand side `g`, then the multipliers `μ`.
    rhs: Vec<f64>,
    /// `Z` before factorisation (lower triangle), for the pivots and the refinement step.
    z0: Vec<f64>,
    /// `g`, kept for the refinement step.
    g: Vec<f64>,
    /// Residual `g − Zμ`, then the correction to `μ`.
    residual: Vec<f64>,
    /// faer's scratch for the factorisation.
    stack: MemBuffer,
    capacity: usize,
}

impl Default for ConstraintSolver {
    fn default() -> Self {
        Self::new()
    }
}

impl ConstraintSolver {
    /// A solver with an empty workspace (it grows to the largest constraint set seen).
    pub fn new() -> Self {
        Self {
            work: Workspace::with_capacity(0),
            dir_i: Vec::new(),
            dir_j: Vec::new(),
        }
    }

    /// Atom `atom_i` of molecule `mol_i` collides with atom `atom_j` of another molecule
    /// `mol_j`; `delta_v` is the potential-energy change of crossing (`+∞` for a hard core).
    /// Updates both molecules' velocities; the impulse on `atom_i` from `atom_j` is
    /// `S (r_i − r_j)`.
    ///
    /// # Errors
    /// Malformed molecules ([`CollideError::Lengths`], [`CollideError::AtomMass`],
    /// [`CollideError::AtomIndex`], [`CollideError::Coincident`]), dependent constraints
    /// ([`CollideError::DependentConstraints`]), and the errors of [`energy::solve`]. On error the
    /// velocities are left unchanged.
    pub fn between(
        &mut self,
        mol_i: Molecule<'_>,
        atom_i: usize,
        mol_j: Molecule<'_>,
        atom_j: usize,
        delta_v: f64,
    ) -> Result<Impulse, CollideError> {
        mol_i.check()?;
        mol_j.check()?;
        let n = mol_i.atom(atom_i)? - mol_j.atom(atom_j)?;
        if n == DVec3::ZERO {
            return Err(CollideError::Coincident(atom_i, atom_j));
        }
        let free =
            0.5 * (1.0 / mol_i.masses[atom_i] + 1.0 / mol_j.masses[atom_j]) * n.length_squared();
        let (a_i, b_i) = self.work.directions(
            &mol_i,
            [(atom_i, n), (atom_i, DVec3::ZERO)],
            &mut self.dir_i,
        )?;
        let (a_j, b_j) = self.work.directions(
            &mol_j,
            [(atom_j, -n), (atom_j, DVec3::ZERO)],
            &mut self.dir_j,
        )?;
        let impulse = solve(a_i + a_j, b_i + b_j, free, delta_v)?;
        apply(mol_i, &self.dir_i, impulse.s);
        apply(mol_j, &self.dir_j, impulse.s);
        Ok(impulse)
    }

    /// Atoms `atom_a` and `atom_b` of the same molecule collide (a semi-flexible molecule whose
    /// constraints leave them free to approach); the impulse on `atom_a` is
    /// `S (r_a − r_b)`.
    ///
    /// # Errors
    /// As [`between`](Self::between); [`CollideError::Coincident`] if `atom_a == atom_b`,
    /// [`CollideError::NoImpulse`] if the constraints hold the two atoms rigidly together.
    pub fn within(
        &mut self,
        mol: Molecule<'_>,
        atom_a: usize,
        atom_b: usize,
        delta_v: f64,
    ) -> Result<Impulse, CollideError> {
        mol.check()?;
        let n = mol.atom(atom_a)? - mol.atom(atom_b)?;
        if atom_a == atom_b || n == DVec3::ZERO {
            return Err(CollideError::Coincident(atom_a, atom_b));
        }
        let free = 0.5 * (1.0 / mol.masses[atom_a] + 1.0 / mol.masses[atom_b]) * n.length_squared();
        let (a, b) = self
            .work
            .directions(&mol, [(atom_a, n), (atom_b, -n)], &mut self.dir_i)?;
        let impulse = solve(a, b, free, delta_v)?;
        apply(mol, &self.dir_i, impulse.s);
        Ok(impulse)
    }
    /// Atom `atom_i` of molecule `mol_i` collides with a site of the rigid body `body_j`
    /// (velocity `vel_j`): the site is at `site_j` (in the frame of `mol_i.positions`) and at
    /// `arm_j` from `j`'s centre of mass. The molecule's side is 000 §IV.A, the rigid body's
    /// 000 §IV.B (the push `−S n` at its site, `n = r_i − r_jβ`); both add to the same
    /// quadratic, `a = a_i + ½(|n|²/M_j + τ·I_j⁻¹τ)`, `b = b_i + τ·ω_j − n·v_j` with
    /// `τ = arm_j × (−n)`. Updates the molecule's velocities and returns the body's new one.
    ///
    /// # Errors
    /// As [`between`](Self::between), and a torque the body cannot take (a torque along a
    /// linear body's axis, any on a particle with a nonzero arm). On error nothing changes.
    #[allow(clippy::too_many_arguments)]
    pub fn against_rigid<B: Body>(
        &mut self,
        mol_i: Molecule<'_>,
        atom_i: usize,
        body_j: &B,
        vel_j: Velocity,
        site_j: DVec3,
        arm_j: DVec3,
        delta_v: f64,
    ) -> Result<(Impulse, Velocity), CollideError> {
        mol_i.check()?;
        let n = mol_i.atom(atom_i)? - site_j;
        if n == DVec3::ZERO {
            return Err(CollideError::NoImpulse(
                "the atom and the rigid body's site coincide",
            ));
        }
        let torque = arm_j.cross(-n);
        let spin = body_j.angular_response(torque)?;
        let w_j = body_j.inv_mass();
        let free = 0.5 * (1.0 / mol_i.masses[atom_i] + w_j) * n.length_squared();
        let (a_i, b_i) = self.work.directions(
            &mol_i,
            [(atom_i, n), (atom_i, DVec3::ZERO)],
            &mut self.dir_i,
        )?;
        let a_j = 0.5 * (w_j * n.length_squared() + torque.dot(spin));
        let b_j = torque.dot(vel_j.angular) - n.dot(vel_j.linear);
        let impulse = solve(a_i + a_j, b_i + b_j, free, delta_v)?;
        apply(mol_i, &self.dir_i, impulse.s);
        let s = impulse.s;
        Ok((
            impulse,
            Velocity::new(vel_j.linear - (s * w_j) * n, vel_j.angular + s * spin),
        ))
    }
}

/// The energy equation, after checking that the constraints leave the pair free to move.
fn solve(a: f64, b: f64, free: f64, delta_v: f64) -> Result<Impulse, CollideError> {
    if a <= MOBILITY_TOLERANCE * free {
        return Err(CollideError::NoImpulse(
            "the distance constraints hold the colliding atoms rigidly together",
        ));
    }
    energy::solve(a, b, delta_v)
}

/// `v_k += S D_k / m_k`.
fn apply(mol: Molecule<'_>, dir: &[DVec3], s: f64) {
    for ((v, d), m) in mol.velocities.iter_mut().zip(dir).zip(mol.masses) {
        *v += (s / m) * *d;
    }
}

impl std::fmt::Debug for Workspace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Workspace")
            .field("capacity", &self.capacity)
            .finish_non_exhaustive()
    }
}

impl Workspace {
    fn with_capacity(capacity: usize) -> Self {
        let req = llt::factor::cholesky_in_place_scratch::<f64>(
            capacity,
            faer::Par::Seq,
            Default::default(),
        );
        Self {
            z: vec![0.0; capacity * capacity],
            rhs: vec![0.0; capacity],
            z0: vec![0.0; capacity * capacity],
            g: vec![0.0; capacity],
            residual: vec![0.0; capacity],
            stack: MemBuffer::new(req),
            capacity,
        }
    }

    /// Fills `dir` with `D_k` for the unit pushes `pushes` (atom, vector) on `mol`, and returns
    /// this molecule's parts of `a` and `b`.
    fn directions(
        &mut self,
        mol: &Molecule<'_>,
        pushes: [(usize, DVec3); 2],
        dir: &mut Vec<DVec3>,
    ) -> Result<(f64, f64), CollideError> {
        let atoms = mol.masses.len();
        dir.clear();
        dir.resize(atoms, DVec3::ZERO);
        for (k, e) in pushes {
            dir[k] += e;
        }
        let nc = mol.bonds.len();
        if nc > 0 {
            if nc > self.capacity {
                *self = Self::with_capacity(nc.next_power_of_two());
            }
            let mu = self.multipliers(mol, dir)?;
            // D_k = e_k − μ_α ∇_kσ_α, with ∇_pσ = r_p − r_q = −∇_qσ.
            for (bond, &m) in mol.bonds.iter().zip(mu) {
                let grad = mol.positions[bond.a] - mol.positions[bond.b];
                dir[bond.a] -= m * grad;
                dir[bond.b] += m * grad;
            }
        }
        let mut a = 0.0;
        let mut b = 0.0;
        for ((d, v), m) in dir.iter().zip(mol.velocities.iter()).zip(mol.masses) {
            a += d.length_squared() / m;
            b += d.dot(*v);
        }
        Ok((0.5 * a, b))
    }

    /// Solves `Z μ = g` (000 §IV.A) for the unit pushes already in `dir`; returns `μ`.
    fn multipliers(&mut self, mol: &Molecule<'_>, dir: &[DVec3]) -> Result<&[f64], CollideError> {
        let nc = mol.bonds.len();
        let grads = |alpha: usize| {
            let bond = mol.bonds[alpha];
            mol.positions[bond.a] - mol.positions[bond.b]
        };
        let inv_m = |k: usize| 1.0 / mol.masses[k];
        // g_α = Σ_k (1/m_k) ∇_kσ_α·e_k.
        for alpha in 0..nc {
            let bond = mol.bonds[alpha];
            let g = grads(alpha);
            self.rhs[alpha] = g.dot(dir[bond.a] * inv_m(bond.a) - dir[bond.b] * inv_m(bond.b));
        }
        self.g[..nc].copy_from_slice(&self.rhs[..nc]);
        // Z_αβ = Σ_k (1/m_k) ∇_kσ_α·∇_kσ_β: nonzero only through shared atoms. Only the lower
        // triangle is read by the factorisation.
        let z = &mut self.z[..nc * nc];
        for beta in 0..nc {
            let (bb, gb) = (mol.bonds[beta], grads(beta));
            for alpha in beta..nc {
                let (ba, ga) = (mol.bonds[alpha], grads(alpha));
                let mut sum = 0.0;
                // ∇_kσ carries sign +1 on the bond's `a` atom and −1 on its `b` atom.
                for (ka, sa) in [(ba.a, 1.0), (ba.b, -1.0)] {
                    for (kb, sb) in [(bb.a, 1.0), (bb.b, -1.0)] {
                        if ka == kb {
                            sum += sa * sb * inv_m(ka);
                        }
                    }
                }
                z[alpha + nc * beta] = sum * ga.dot(gb);
            }
        }
        self.z0[..nc * nc].copy_from_slice(z);
        let mut zmat = MatMut::from_column_major_slice_mut(z, nc, nc);
        let factored = llt::factor::cholesky_in_place(
            zmat.as_mut(),
            Default::default(),
            faer::Par::Seq,
            MemStack::new(&mut self.stack),
            Default::default(),
        );
        // The factor's pivots L_αα² against Z_αα: how much of constraint α is new, not implied
        // by the constraints before it.
        let z0 = &self.z0[..nc * nc];
        let pivot =
            |alpha: usize| zmat[(alpha, alpha)] * zmat[(alpha, alpha)] / z0[alpha * (nc + 1)];
        let dependent = match factored {
            Err(llt::factor::LltError::NonPositivePivot { index }) => Some((index, 0.0)),
            Ok(_) => (0..nc)
                .map(|alpha| (alpha, pivot(alpha)))
                .find(|&(_, p)| p.is_nan() || p < PIVOT_TOLERANCE),
        };
        if let Some((index, pivot)) = dependent {
            return Err(CollideError::DependentConstraints {
                index,
                pivot,
                tolerance: PIVOT_TOLERANCE,
            });
        }
        let mu = &mut self.rhs[..nc];
        let solve = |x: &mut [f64], stack: &mut MemBuffer| {
            let x = MatMut::from_column_major_slice_mut(x, nc, 1);
            llt::solve::solve_in_place(zmat.as_ref(), x, faer::Par::Seq, MemStack::new(stack));
        };
        solve(mu, &mut self.stack);
        // One step of iterative refinement: atom masses spanning orders of magnitude make Z
        // badly scaled, and the residual g − Zμ is exactly the velocity-constraint error the
        // impulse would leave (000 §IV.A). One step brings it back to round-off of g.
        let residual = &mut self.residual[..nc];
        for (alpha, res) in residual.iter_mut().enumerate() {
            let mut r = self.g[alpha];
            for (beta, m) in mu.iter().enumerate() {
                let (lo, hi) = if alpha >= beta {
                    (alpha, beta)
                } else {
                    (beta, alpha)
                };
                r -= z0[lo + nc * hi] * m;
            }
            *res = r;
        }
        solve(residual, &mut self.stack);
        for (m, d) in mu.iter_mut().zip(residual.iter()) {
            *m += d;
        }
        Ok(mu)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Outcome;

    fn ke(m: &[f64], v: &[DVec3]) -> f64 {
        m.iter()
            .zip(v)
            .map(|(m, v)| 0.5 * m * v.length_squared())
            .sum()
    }

    #[test]
    fn a_rigid_side_acts_as_its_bonded_framework() {
        // A bonded dimer (atoms 0, 1) hits atom 2 of a triangle of unequal masses. The triangle
        // once as three atoms held by three bonds, once as a rigid body: the same physics, so
        // the same impulse and the same new velocities of every atom; energy, momentum and
        // angular momentum conserved by the rigid route.
        let (m_d, m_t) = ([1.0, 2.0], [1.0, 3.0, 0.5]);
        let pos_d = [DVec3::new(-1.0, 0.2, 0.1), DVec3::new(-1.6, 0.5, -0.3)];
        let vel_d0 = [DVec3::new(0.9, 0.1, 0.0), DVec3::new(0.7, -0.2, 0.3)];
        let centre = DVec3::new(0.4, 0.1, -0.2);
        let arms = [
            DVec3::new(0.3, 0.5, 0.1),
            DVec3::new(-0.2, -0.1, 0.05),
            DVec3::new(-0.6, 0.0, 0.0),
        ];
        // Centre of mass at `centre`: shift the arms by their weighted mean.
        let mean = arms
            .iter()
            .zip(&m_t)
            .fold(DVec3::ZERO, |s, (d, m)| s + *m * *d)
            / 4.5;
        let arms: Vec<DVec3> = arms.iter().map(|&d| d - mean).collect();
        let pos_t: Vec<DVec3> = arms.iter().map(|&d| centre + d).collect();
        let (v_c, w) = (DVec3::new(-0.3, 0.2, 0.1), DVec3::new(0.5, -1.1, 0.7));
        let vel_t0: Vec<DVec3> = arms.iter().map(|&d| v_c + w.cross(d)).collect();
        let bonds_d = [Bond::new(0, 1)];
        let bonds_t = [Bond::new(0, 1), Bond::new(1, 2), Bond::new(0, 2)];
        for delta_v in [f64::INFINITY, 0.05, -0.2] {
            let (mut vd_a, mut vt_a) = (vel_d0, vel_t0.clone());
            let mut solver = ConstraintSolver::new();
            let bonded = solver
                .between(
                    Molecule {
                        masses: &m_d,
                        positions: &pos_d,
                        velocities: &mut vd_a,
                        bonds: &bonds_d,
                    },
                    0,
                    Molecule {
                        masses: &m_t,
                        positions: &pos_t,
                        velocities: &mut vt_a,
                        bonds: &bonds_t,
                    },
                    2,
                    delta_v,
                )
                .unwrap();
            let inertia = arms
                .iter()
                .zip(&m_t)
                .fold(glam::DMat3::ZERO, |s, (&d, &m)| {
                    s + glam::DMat3::from_diagonal(DVec3::splat(m * d.length_squared()))
                        - m * glam::DMat3::from_cols(d * d.x, d * d.y, d * d.z)
                });
            let body = crate::RigidBody::from_lab_inertia(4.5, inertia).unwrap();
            let mut vd_b = vel_d0;
            let (rigid, after) = solver
                .against_rigid(
                    Molecule {
                        masses: &m_d,
                        positions: &pos_d,
                        velocities: &mut vd_b,
                        bonds: &bonds_d,
                    },
                    0,
                    &body,
                    Velocity::new(v_c, w),
                    pos_t[2],
                    arms[2],
                    delta_v,
                )
                .unwrap();
            assert_eq!(rigid.outcome, bonded.outcome, "ΔV = {delta_v}");
            assert!(
                (rigid.s - bonded.s).abs() < 1e-12 * bonded.s.abs(),
                "{rigid:?} {bonded:?}"
            );
            for k in 0..2 {
                assert!((vd_a[k] - vd_b[k]).length() < 1e-12, "dimer atom {k}");
            }
            let vt_b: Vec<DVec3> = arms
                .iter()
                .map(|&d| after.linear + after.angular.cross(d))
                .collect();
            for k in 0..3 {
                assert!(
                    (vt_a[k] - vt_b[k]).length() < 1e-12,
                    "triangle atom {k}: {} {}",
                    vt_a[k],
                    vt_b[k]
                );
            }
            let energy = |vd: &[DVec3], vt: &[DVec3]| ke(&m_d, vd) + ke(&m_t, vt);
            let gained = energy(&vd_b, &vt_b) - energy(&vel_d0, &vel_t0);
            assert!(
                (gained + rigid.delta_v).abs() < 1e-13,
                "ΔK = {gained}, ΔV = {}",
                rigid.delta_v
            );
            let momentum = |vd: &[DVec3], vt: &[DVec3]| {
                let p = |m: &[f64], v: &[DVec3]| {
                    m.iter().zip(v).fold(DVec3::ZERO, |s, (m, v)| s + *m * *v)
                };
                let l = |m: &[f64], r: &[DVec3], v: &[DVec3]| {
                    m.iter()
                        .zip(r.iter().zip(v))
                        .fold(DVec3::ZERO, |s, (m, (r, v))| s + *m * r.cross(*v))
                };
                (
                    p(&m_d, vd) + p(&m_t, vt),
                    l(&m_d, &pos_d, vd) + l(&m_t, &pos_t, vt),
                )
            };
            let (p0, l0) = momentum(&vel_d0, &vel_t0);
            let (p1, l1) = momentum(&vd_b, &vt_b);
            assert!((p1 - p0).length() < 1e-13 && (l1 - l0).length() < 1e-13);
        }
    }

    #[test]
    fn collinear_triatomic_is_singular() {
        let pos = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        let mut vel = [DVec3::ZERO; 3];
        let bonds = [Bond::new(0, 1), Bond::new(1, 2), Bond::new(0, 2)];
        let other_pos = [DVec3::new(0.0, 1.0, 0.0)];
        let mut other_vel = [DVec3::new(0.0, -1.0, 0.0)];
        let err = ConstraintSolver::new()
            .between(
                Molecule {
                    masses: &[1.0; 3],
                    positions: &pos,
                    velocities: &mut vel,
                    bonds: &bonds,
                },
                1,
                Molecule {
                    masses: &[1.0],
                    positions: &other_pos,
                    velocities: &mut other_vel,
                    bonds: &[],
                },
                0,
                f64::INFINITY,
            )
            .unwrap_err();
        assert!(
            matches!(err, CollideError::DependentConstraints { index: 2, .. }),
            "{err}"
        );
        assert_eq!(vel, [DVec3::ZERO; 3]);
        // A duplicated bond is redundant too.
        let dup = [Bond::new(0, 1), Bond::new(1, 0)];
        let err = ConstraintSolver::new()
            .within(
                Molecule {
                    masses: &[1.0; 3],
                    positions: &pos,
                    velocities: &mut vel,
                    bonds: &dup,
                },
                0,
                2,
                1.0,
            )
            .unwrap_err();
        assert!(
            matches!(err, CollideError::DependentConstraints { index: 1, .. }),
            "{err}"
        );
    }

    #[test]
    fn rigidly_bound_atoms_cannot_collide() {
        let pos = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let mut vel = [DVec3::ZERO; 3];
        let bonds = [Bond::new(0, 1), Bond::new(1, 2), Bond::new(0, 2)];
        let err = ConstraintSolver::new()
            .within(
                Molecule {
                    masses: &[1.0, 2.0, 3.0],
                    positions: &pos,
                    velocities: &mut vel,
                    bonds: &bonds,
                },
                0,
                2,
                1.0,
            )
            .unwrap_err();
        assert!(matches!(err, CollideError::NoImpulse(_)), "{err}");
    }

    #[test]
    fn semi_flexible_chain_end_to_end_collision() {
        // A bent chain 0-1-2 with two bonds: atoms 0 and 2 may approach (the angle is free).
        let pos = [
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
        ];
        let masses = [1.0, 2.0, 0.5];
        let mut vel = [
            DVec3::new(0.5, -0.5, 0.0),
            DVec3::ZERO,
            DVec3::new(-0.25, -0.25, 0.0),
        ];
        let bonds = [Bond::new(0, 1), Bond::new(1, 2)];
        for b in bonds {
            assert!((vel[b.a] - vel[b.b]).dot(pos[b.a] - pos[b.b]).abs() < 1e-15);
        }
        let before = ke(&masses, &vel);
        let imp = ConstraintSolver::new()
            .within(
                Molecule {
                    masses: &masses,
                    positions: &pos,
                    velocities: &mut vel,
                    bonds: &bonds,
                },
                0,
                2,
                f64::INFINITY,
            )
            .unwrap();
        assert_eq!(imp.outcome, Outcome::Reflected);
        assert!((ke(&masses, &vel) - before).abs() < 1e-15);
        for b in bonds {
            assert!((vel[b.a] - vel[b.b]).dot(pos[b.a] - pos[b.b]).abs() < 1e-15);
        }
        // The ends now separate.
        assert!((vel[0] - vel[2]).dot(pos[0] - pos[2]) > 0.0);
    }

    #[test]
    fn malformed_molecules_are_named() {
        let pos = [DVec3::ZERO, DVec3::X];
        let mut vel = [DVec3::ZERO; 2];
        let mut solver = ConstraintSolver::new();
        let mut run = |masses: &[f64], bonds: &[Bond], a: usize, b: usize, vel: &mut [DVec3]| {
            solver
                .within(
                    Molecule {
                        masses,
                        positions: &pos,
                        velocities: vel,
                        bonds,
                    },
                    a,
                    b,
                    1.0,
                )
                .unwrap_err()
        };
        assert!(matches!(
            run(&[1.0], &[], 0, 1, &mut vel),
            CollideError::Lengths { .. }
        ));
        assert_eq!(
            run(&[1.0, -2.0], &[], 0, 1, &mut vel),
            CollideError::AtomMass {
                index: 1,
                mass: -2.0
            }
        );
        assert_eq!(
            run(&[1.0, 1.0], &[Bond::new(0, 5)], 0, 1, &mut vel),
            CollideError::AtomIndex { index: 5, count: 2 }
        );
        assert_eq!(
            run(&[1.0, 1.0], &[Bond::new(1, 1)], 0, 1, &mut vel),
            CollideError::Coincident(1, 1)
        );
        assert_eq!(
            run(&[1.0, 1.0], &[], 0, 0, &mut vel),
            CollideError::Coincident(0, 0)
        );
        assert_eq!(
            run(&[1.0, 1.0], &[], 0, 7, &mut vel),
            CollideError::AtomIndex { index: 7, count: 2 }
        );
        let mut nan_vel = [DVec3::new(f64::NAN, 0.0, 0.0), DVec3::ZERO];
        assert!(matches!(
            run(&[1.0, 1.0], &[], 0, 1, &mut nan_vel),
            CollideError::NotFinite(_)
        ));
    }

    #[test]
    fn workspace_grows_and_is_reused() {
        // A chain of 40 atoms with 39 bonds, then a small one with the same solver.
        let n = 40;
        let pos: Vec<DVec3> = (0..n)
            .map(|k| DVec3::new(k as f64, (k % 2) as f64 * 0.5, 0.0))
            .collect();
        let masses = vec![1.0; n];
        let bonds: Vec<Bond> = (0..n - 1).map(|k| Bond::new(k, k + 1)).collect();
        // The zigzag lies in the xy plane: any velocities along z keep every bond length.
        let mut vel: Vec<DVec3> = (0..n)
            .map(|k| DVec3::new(0.0, 0.0, (k as f64).sin()))
            .collect();
        let mut solver = ConstraintSolver::new();
        solver
            .within(
                Molecule {
                    masses: &masses,
                    positions: &pos,
                    velocities: &mut vel,
                    bonds: &bonds,
                },
                0,
                n - 1,
                -0.5,
            )
            .unwrap();
        for b in &bonds {
            assert!((vel[b.a] - vel[b.b]).dot(pos[b.a] - pos[b.b]).abs() < 1e-13);
        }
        assert!(solver.work.capacity >= n - 1);
    }
}
