//! A rigid molecule type: what the rigid-sites model and the rigid molecules of a scene of
//! semi-flexible ones share. [`MoleculeType::new`] takes the atoms (mass, site species, position
//! in any frame), puts the centre of mass at the origin and diagonalises the inertia tensor once
//! (cyclic Jacobi); the body frame is the principal frame, with the moments in increasing
//! order. Moments equal to within [`MOMENT_SNAP`] of the largest are made exactly equal, so that
//! a methane-like molecule is a spherical rotor and a benzene-like ring a symmetric top (the
//! cheap exact propagators of `rigid_free`) rather than asymmetric tops whose moments differ in
//! the last bits; a molecule whose smallest moment is below that is linear (a dumbbell: its
//! spin about the axis carries no site and is dropped, 003 §V). [`SiteBody`] is the molecule as
//! an impulse rule of `collide` sees it.

use collide::{Body as CollideBody, Bond, CollideError, LinearBody, RigidBody};
use glam::{DMat3, DQuat, DVec3};
use rigid_free::Moments;

use crate::models::site_pairs::SiteAtom;

/// Moments within this fraction of the largest are made equal (and a smallest moment below it
/// is zero: a linear molecule). Far above the round-off of the Jacobi rotations (1e-15), far
/// below anything physical.
pub const MOMENT_SNAP: f64 = 1e-10;

/// Why a molecule type could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MoleculeError {
    /// Fewer than two atoms.
    #[error("a molecule needs at least two atoms, got {0}")]
    TooFewAtoms(usize),
    /// A mass is not positive and finite.
    #[error("atom {atom}: mass {mass} must be positive and finite")]
    Mass {
        /// The atom.
        atom: usize,
        /// The mass.
        mass: f64,
    },
    /// A position is not finite.
    #[error("atom {0}: position is not finite")]
    Position(usize),
    /// Two atoms at the same place.
    #[error("atoms {0} and {1} coincide")]
    Coincident(usize, usize),
    /// The principal moments are unusable (collinear atoms of a molecule whose moments
    /// `rigid_free` refuses, say).
    #[error("principal moments {moments:?}: {problem}")]
    Moments {
        /// The moments.
        moments: [f64; 3],
        /// What is wrong.
        problem: String,
    },
}

/// The checks every molecule's atoms pass, rigid or not: at least two, masses positive and
/// finite, positions finite.
///
/// # Errors
/// The first atom that fails, as a [`MoleculeError`].
pub fn check_atoms(atoms: &[SiteAtom]) -> Result<(), MoleculeError> {
    if atoms.len() < 2 {
        return Err(MoleculeError::TooFewAtoms(atoms.len()));
    }
    for (k, a) in atoms.iter().enumerate() {
        if !(a.mass.is_finite() && a.mass > 0.0) {
            return Err(MoleculeError::Mass {
                atom: k,
                mass: a.mass,
            });
        }
        if !a.position.is_finite() {
            return Err(MoleculeError::Position(k));
        }
    }
    Ok(())
}

/// A rigid molecule type: atoms in the principal frame, mass, moments, bounding radius.
#[derive(Clone, Debug, PartialEq)]
pub struct MoleculeType {
    pub(crate) mass: f64,
    pub(crate) moments: Moments,
    pub(crate) principal: DVec3,
    pub(crate) sites: Vec<DVec3>,
    pub(crate) species: Vec<u32>,
    pub(crate) masses: Vec<f64>,
    pub(crate) radii: Vec<f64>,
    pub(crate) radius: f64,
    pub(crate) centre: DVec3,
    pub(crate) frame: DMat3,
    pub(crate) bonds: Result<Vec<Bond>, &'static str>,
}

impl MoleculeType {
    /// The type of the rigid molecule made of `atoms` (module documentation).
    ///
    /// # Errors
    /// [`MoleculeError`] for fewer than two atoms, bad masses or positions, coincident atoms, and
    /// moments `rigid_free` refuses.
    pub fn new(atoms: &[SiteAtom]) -> Result<Self, MoleculeError> {
        check_atoms(atoms)?;
        for (k, a) in atoms.iter().enumerate() {
            for (l, b) in atoms[..k].iter().enumerate() {
                if a.position == b.position {
                    return Err(MoleculeError::Coincident(l, k));
                }
            }
        }
        let mass: f64 = atoms.iter().map(|a| a.mass).sum();
        let centre = atoms
            .iter()
            .fold(DVec3::ZERO, |c, a| c + a.mass * a.position)
            / mass;
        // I = Σ m (|d|² 1 − d dᵀ) about the centre of mass.
        let mut inertia = DMat3::ZERO;
        for a in atoms {
            let d = a.position - centre;
            inertia += DMat3::from_diagonal(DVec3::splat(a.mass * d.length_squared()))
                - a.mass * outer(d, d);
        }
        let (mut moments, mut frame) = symmetric_eigen(inertia);
        if frame.determinant() < 0.0 {
            frame.z_axis = -frame.z_axis;
        }
        let top = moments.max_element();
        let linear = moments.x <= MOMENT_SNAP * top;
        if linear {
            moments.x = 0.0;
        }
        // Equal moments made exactly equal (ascending order: only neighbours can be equal).
        if (moments.z - moments.x) <= MOMENT_SNAP * top && !linear {
            moments = DVec3::splat(moments.element_sum() / 3.0);
        } else {
            if (moments.y - moments.x) <= MOMENT_SNAP * top && !linear {
                let m = 0.5 * (moments.x + moments.y);
                moments.x = m;
                moments.y = m;
            }
            if (moments.z - moments.y) <= MOMENT_SNAP * top {
                let m = 0.5 * (moments.y + moments.z);
                moments.y = m;
                moments.z = m;
            }
        }
        // A planar molecule sits on the triangle inequality, I₃ = I₁ + I₂: round-off must not
        // push it over.
        if (moments.z - (moments.x + moments.y)).abs() <= MOMENT_SNAP * top {
            moments.z = moments.x + moments.y;
        }
        let checked = Moments::new(moments.to_array()).map_err(|e| MoleculeError::Moments {
            moments: moments.to_array(),
            problem: e.to_string(),
        })?;
        let sites: Vec<DVec3> = atoms
            .iter()
            .map(|a| {
                let d = frame.transpose() * (a.position - centre);
                // A linear molecule's atoms are on its axis; round-off off it would be a lever
                // arm for the dropped spin.
                if linear { DVec3::new(d.x, 0.0, 0.0) } else { d }
            })
            .collect();
        let radii: Vec<f64> = sites.iter().map(|d| d.length()).collect();
        let radius = radii.iter().copied().fold(0.0, f64::max);
        let bonds = rigid_framework(&sites, linear);
        Ok(MoleculeType {
            mass,
            moments: checked,
            principal: moments,
            species: atoms.iter().map(|a| a.species).collect(),
            masses: atoms.iter().map(|a| a.mass).collect(),
            sites,
            radii,
            radius,
            centre,
            frame,
            bonds,
        })
    }

    /// Total mass.
    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// Principal moments, in increasing order (`I₁ = 0` for a linear molecule).
    pub fn moments(&self) -> DVec3 {
        self.principal
    }

    /// Whether the molecule is linear (no moment about its axis, body axis 1).
    pub fn is_linear(&self) -> bool {
        self.principal.x == 0.0
    }

    /// Atom positions in the principal frame, relative to the centre of mass.
    pub fn sites(&self) -> &[DVec3] {
        &self.sites
    }

    /// Site species of the atoms.
    pub fn site_species(&self) -> &[u32] {
        &self.species
    }

    /// Atom masses.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// The largest distance of a site from the centre (the bounding sphere, 000 §III.A).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The centre of mass in the frame the atoms were given in.
    pub fn centre(&self) -> DVec3 {
        self.centre
    }

    /// The principal axes in the frame the atoms were given in (columns, right-handed).
    pub fn frame(&self) -> DMat3 {
        self.frame
    }

    /// The distance constraints that hold the molecule rigid (the constrained-Lagrangian
    /// rule's), or why there are none.
    ///
    /// # Errors
    /// The molecule is planar or collinear with more than two atoms.
    pub fn bonds(&self) -> Result<&[Bond], &'static str> {
        self.bonds.as_deref().map_err(|e| *e)
    }

    /// Rotational degrees of freedom (2 for a linear molecule, else 3).
    pub fn rotational_dof(&self) -> f64 {
        if self.is_linear() { 2.0 } else { 3.0 }
    }

    /// The body a rule sees at lab orientation `orientation` (body → lab).
    pub fn body(&self, orientation: DMat3) -> Result<SiteBody, CollideError> {
        if self.is_linear() {
            Ok(SiteBody::Linear(LinearBody::new(
                self.mass,
                self.principal.y,
                orientation.x_axis,
            )?))
        } else {
            Ok(SiteBody::Rigid(RigidBody::from_principal(
                self.mass,
                self.principal,
                DQuat::from_mat3(&orientation),
            )?))
        }
    }

    /// Body-frame angular velocity from lab angular momentum `l` (linear: its part
    /// perpendicular to the axis).
    pub fn omega_from_momentum(&self, orientation: DMat3, l: DVec3) -> DVec3 {
        let lb = orientation.transpose() * l;
        if self.is_linear() {
            DVec3::new(0.0, lb.y / self.principal.y, lb.z / self.principal.z)
        } else {
            lb / self.principal
        }
    }
}

/// `a bᵀ`.
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Eigenvalues (increasing) and eigenvectors (columns) of a symmetric 3×3 matrix by cyclic
/// Jacobi rotations: converges quadratically to round-off, and a 3×3 needs a handful of sweeps.
fn symmetric_eigen(m: DMat3) -> (DVec3, DMat3) {
    let mut a = m.to_cols_array_2d();
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..64 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off <= 1e-34 * diag || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            // The rotation that zeroes a[p][q] (Numerical Recipes' stable form of θ).
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in &mut a {
                let (x, y) = (row[p], row[q]);
                row[p] = c * x - s * y;
                row[q] = s * x + c * y;
            }
            let (row_p, row_q) = (a[p], a[q]);
            for (k, (x, y)) in row_p.into_iter().zip(row_q).enumerate() {
                a[p][k] = c * x - s * y;
                a[q][k] = s * x + c * y;
            }
            for col in &mut v {
                let (x, y) = (col[p], col[q]);
                col[p] = c * x - s * y;
                col[q] = s * x + c * y;
            }
        }
    }
    // `v[k]` is row k of the eigenvector matrix: column j holds eigenvector j.
    let mut order = [0usize, 1, 2];
    order.sort_by(|&x, &y| a[x][x].total_cmp(&a[y][y]));
    let vec = |j: usize| DVec3::new(v[0][j], v[1][j], v[2][j]);
    (
        DVec3::new(
            a[order[0]][order[0]],
            a[order[1]][order[1]],
            a[order[2]][order[2]],
        ),
        DMat3::from_cols(vec(order[0]), vec(order[1]), vec(order[2])),
    )
}

/// `3n − 6` distance constraints holding the atoms rigid to first order: a tetrahedron of
/// reference atoms, and every other atom tied to the three reference atoms whose plane it is
/// farthest from (one bond for a dumbbell).
fn rigid_framework(sites: &[DVec3], linear: bool) -> Result<Vec<Bond>, &'static str> {
    let n = sites.len();
    if n == 2 {
        return Ok(vec![Bond::new(0, 1)]);
    }
    if linear {
        return Err(
            "a collinear molecule of more than two atoms has dependent distance constraints: \
             the constrained rule cannot be used",
        );
    }
    let size = sites.iter().map(|d| d.length()).fold(0.0, f64::max);
    let far = |from: &dyn Fn(DVec3) -> f64| {
        (0..n)
            .max_by(|&a, &b| from(sites[a]).total_cmp(&from(sites[b])))
            .expect("atoms")
    };
    let p0 = 0;
    let p1 = far(&|d| (d - sites[p0]).length());
    let axis = (sites[p1] - sites[p0]).normalize();
    let p2 = far(&|d| (d - sites[p0]).cross(axis).length());
    let normal = (sites[p1] - sites[p0])
        .cross(sites[p2] - sites[p0])
        .normalize();
    let p3 = far(&|d| (d - sites[p0]).dot(normal).abs());
    if (sites[p3] - sites[p0]).dot(normal).abs() < 1e-6 * size {
        return Err(
            "a planar molecule cannot be held rigid by distance constraints (its atoms can move \
             out of the plane to first order): the constrained rule cannot be used",
        );
    }
    let refs = [p0, p1, p2, p3];
    let mut bonds = Vec::with_capacity(3 * n - 6);
    for a in 0..4 {
        for b in a + 1..4 {
            bonds.push(Bond::new(refs[a], refs[b]));
        }
    }
    for k in (0..n).filter(|k| !refs.contains(k)) {
        let mut best = (0.0, [0, 1, 2]);
        for face in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
            let [a, b, c] = face.map(|f| sites[refs[f]]);
            let nrm = (b - a).cross(c - a).normalize();
            let h = (sites[k] - a).dot(nrm).abs();
            if h > best.0 {
                best = (h, face);
            }
        }
        for f in best.1 {
            bonds.push(Bond::new(refs[f], k));
        }
    }
    Ok(bonds)
}

/// A molecule as an impulse rule sees it (static dispatch over the two kinds).
#[derive(Clone, Copy, Debug)]
pub enum SiteBody {
    /// Three rotational degrees of freedom.
    Rigid(RigidBody),
    /// A linear molecule: no spin about its axis.
    Linear(LinearBody),
}

impl CollideBody for SiteBody {
    #[inline]
    fn inv_mass(&self) -> f64 {
        match self {
            SiteBody::Rigid(b) => b.inv_mass(),
            SiteBody::Linear(b) => b.inv_mass(),
        }
    }

    #[inline]
    fn angular_response(&self, torque: DVec3) -> Result<DVec3, CollideError> {
        match self {
            SiteBody::Rigid(b) => b.angular_response(torque),
            SiteBody::Linear(b) => b.angular_response(torque),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::site_pairs::atom;

    #[test]
    fn principal_frame_diagonalises_the_inertia_tensor() {
        // An irregular molecule with unequal masses, given in a rotated, shifted frame.
        let q = DQuat::from_axis_angle(DVec3::new(1.0, -2.0, 0.5).normalize(), 0.9);
        let raw = [
            atom(0.0, 0.0, 0.0, 12.0),
            atom(1.1, 0.0, 0.0, 1.0),
            atom(-0.3, 0.9, 0.1, 16.0),
            atom(0.2, -0.4, 0.8, 2.0),
        ];
        let atoms: Vec<SiteAtom> = raw
            .iter()
            .map(|a| SiteAtom {
                position: q * a.position + DVec3::new(3.0, -1.0, 2.0),
                ..*a
            })
            .collect();
        let t = MoleculeType::new(&atoms).unwrap();
        assert_eq!(t.mass(), 31.0);
        // Body-frame sites: centre at the origin, diagonal inertia with the moments ascending.
        let c = t
            .sites()
            .iter()
            .zip(t.masses())
            .fold(DVec3::ZERO, |s, (&d, &m)| s + m * d);
        assert!(c.length() < 1e-13, "{c}");
        let mut inertia = DMat3::ZERO;
        for (&d, &m) in t.sites().iter().zip(t.masses()) {
            inertia += DMat3::from_diagonal(DVec3::splat(m * d.length_squared())) - m * outer(d, d);
        }
        let m = t.moments();
        assert!(m.x < m.y && m.y < m.z);
        for r in 0..3 {
            for c in 0..3 {
                let want = if r == c { m[r] } else { 0.0 };
                assert!((inertia.col(c)[r] - want).abs() < 1e-12 * m.z, "{inertia}");
            }
        }
        // The frame maps body sites back to the input, and is a proper rotation.
        assert!((t.frame().determinant() - 1.0).abs() < 1e-14);
        for (a, &d) in atoms.iter().zip(t.sites()) {
            assert!((t.frame() * d + t.centre() - a.position).length() < 1e-13);
        }
        assert!(t.bonds().unwrap().len() == 6);
    }

    #[test]
    fn symmetric_molecules_get_exactly_equal_moments() {
        // A tetrahedron around a centre atom: a spherical rotor.
        let s = 1.0 / 3f64.sqrt();
        let methane = [
            atom(0.0, 0.0, 0.0, 12.0),
            atom(s, s, s, 1.0),
            atom(s, -s, -s, 1.0),
            atom(-s, s, -s, 1.0),
            atom(-s, -s, s, 1.0),
        ];
        let t = MoleculeType::new(&methane).unwrap();
        assert_eq!(t.moments.kind(), rigid_free::BodyKind::Spherical);
        assert!((t.moments().x - 8.0 / 3.0).abs() < 1e-13);
        assert_eq!(t.bonds().unwrap().len(), 3 * 5 - 6);
        // A hexagon: a symmetric top (planar: I3 = I1 + I2), refused by the constrained rule.
        let ring: Vec<SiteAtom> = (0..6)
            .map(|k| {
                let a = std::f64::consts::PI / 3.0 * k as f64;
                atom(1.4 * a.cos(), 1.4 * a.sin(), 0.0, 13.0)
            })
            .collect();
        let t = MoleculeType::new(&ring).unwrap();
        assert_eq!(
            t.moments.kind(),
            rigid_free::BodyKind::Symmetric { axis: 2 }
        );
        assert!((t.moments().z - 2.0 * t.moments().x).abs() < 1e-12 * t.moments().z);
        assert!(t.bonds().unwrap_err().contains("planar"));
        // A dumbbell: linear, its sites on body axis 1.
        let d = MoleculeType::new(&[atom(0.0, 0.0, 0.0, 1.0), atom(0.3, 0.4, 0.0, 1.0)]).unwrap();
        assert!(d.is_linear());
        assert_eq!(d.moments.kind(), rigid_free::BodyKind::Linear { axis: 0 });
        assert!((d.sites()[0].x.abs() - 0.25).abs() < 1e-15 && d.sites()[0].y == 0.0);
        assert!((d.moments().y - 2.0 * 0.25 * 0.25).abs() < 1e-15);
        assert_eq!(d.bonds().unwrap(), &[Bond::new(0, 1)]);
    }

    #[test]
    fn bad_molecules_are_refused_with_their_reason() {
        assert_eq!(
            MoleculeType::new(&[atom(0.0, 0.0, 0.0, 1.0)]),
            Err(MoleculeError::TooFewAtoms(1))
        );
        assert!(matches!(
            MoleculeType::new(&[atom(0.0, 0.0, 0.0, 1.0), atom(1.0, 0.0, 0.0, -1.0)]),
            Err(MoleculeError::Mass { atom: 1, .. })
        ));
        assert_eq!(
            MoleculeType::new(&[atom(0.0, 0.0, 0.0, 1.0), atom(0.0, 0.0, 0.0, 1.0)]),
            Err(MoleculeError::Coincident(0, 1))
        );
        assert_eq!(
            MoleculeType::new(&[atom(f64::NAN, 0.0, 0.0, 1.0), atom(0.0, 0.0, 0.0, 1.0)]),
            Err(MoleculeError::Position(0))
        );
        // Three collinear atoms: linear, but no independent framework of constraints.
        let t = MoleculeType::new(&[
            atom(-1.0, 0.0, 0.0, 1.0),
            atom(0.0, 0.0, 0.0, 1.0),
            atom(1.0, 0.0, 0.0, 1.0),
        ])
        .unwrap();
        assert!(t.is_linear() && t.bonds().is_err());
    }

    #[test]
    fn extreme_mass_ratio_keeps_an_exact_frame() {
        // A heavy atom with a feather-light one far off: the moments span many decades.
        let t = MoleculeType::new(&[
            atom(0.0, 0.0, 0.0, 1e6),
            atom(1.0, 0.0, 0.0, 1e-3),
            atom(0.0, 1.0, 0.0, 1.0),
        ])
        .unwrap();
        let m = t.moments();
        assert!(m.x > 0.0 && m.x < m.y && m.y <= m.z);
        let lab = t.frame() * DMat3::from_diagonal(m) * t.frame().transpose();
        // Reconstructed tensor from the atoms (input frame, about the centre).
        let mut inertia = DMat3::ZERO;
        for (&d, &ms) in t.sites().iter().zip(t.masses()) {
            let d = t.frame() * d;
            inertia +=
                DMat3::from_diagonal(DVec3::splat(ms * d.length_squared())) - ms * outer(d, d);
        }
        assert!(
            (lab - inertia)
                .abs()
                .to_cols_array()
                .iter()
                .all(|&x| x < 1e-12 * m.z)
        );
    }
}
