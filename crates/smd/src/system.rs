//! The state of a system of rigid bodies in a periodic box, and how to build one.
//!
//! The state is kept in flat arrays (one `Vec` per quantity, indexed by body), which is what
//! the force loop and the kicks stream through:
//!
//! - positions, kept inside the box at every neighbour-list build and moving freely in between
//!   (so that the list's image shifts stay valid), with integral image counters so that the
//!   unwrapped trajectory (for the MSD) is `r + n ∘ L`;
//! - velocities;
//! - for rotating bodies, the lab axis `s` the potential sees and the lab angular momentum `L`;
//!   a linear rotor's angular velocity is `L / I`, a rigid body's is `R I⁻¹ Rᵀ L`;
//! - for general rigid bodies, the orientation `R` (body → lab; `s = R s̃`).

use glam::{DMat3, DQuat, DVec3};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::error::{non_negative, positive};
use crate::{BodyModel, SmdError};

/// The initial lattice.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Lattice {
    /// Face-centred cubic (4 sites per unit cell).
    #[default]
    Fcc,
    /// Simple cubic.
    Sc,
}

/// How to build a fresh system: a lattice at a density, random orientations, and
/// Maxwell–Boltzmann velocities with zero total momentum, all from one seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setup {
    /// Number of bodies (at least 2).
    pub n: usize,
    /// Number density `N/V` (in the length unit of the potential).
    pub density: f64,
    /// Proportions of the box edges (default cubic).
    pub aspect: [f64; 3],
    /// The lattice the bodies start on.
    pub lattice: Lattice,
    /// The bodies.
    pub body: BodyModel,
    /// `kT` of the initial velocities, in the energy unit of the potential (`0` for rest).
    pub temperature: f64,
    /// Seed of the orientations and velocities (Xoshiro256++).
    pub seed: u64,
}

impl Setup {
    /// `n` bodies at `density` and temperature `kT`, fcc, cubic box, seed 1.
    pub fn new(n: usize, density: f64, body: BodyModel, temperature: f64) -> Self {
        Self {
            n,
            density,
            aspect: [1.0; 3],
            lattice: Lattice::Fcc,
            body,
            temperature,
            seed: 1,
        }
    }
}

/// The orientations given to [`System::from_parts`].
#[derive(Clone, Debug, PartialEq)]
pub enum Orientations {
    /// Spheres: no orientation.
    None,
    /// Linear rotors: one lab axis per body (normalised on input).
    Axes(Vec<DVec3>),
    /// Rigid bodies: one orientation `R` (body → lab) per body; must be proper rotations.
    Rotations(Vec<DMat3>),
}

/// The bodies of a simulation and their box.
#[derive(Clone, Debug, PartialEq)]
pub struct System {
    pub(crate) lengths: DVec3,
    pub(crate) body: BodyModel,
    pub(crate) pos: Vec<DVec3>,
    pub(crate) image: Vec<DVec3>,
    pub(crate) vel: Vec<DVec3>,
    pub(crate) axis: Vec<DVec3>,
    pub(crate) ang_mom: Vec<DVec3>,
    pub(crate) rot: Vec<DMat3>,
}

/// Largest number of bodies: a neighbour-list entry packs the partner index into 27 bits.
pub const MAX_BODIES: usize = 1 << 27;

impl System {
    /// A fresh system from a [`Setup`]: the box sized to the density, bodies on the first sites
    /// of the lattice (unit cells per axis in proportion to the edges), uniformly random axes
    /// or orientations, and Maxwell–Boltzmann velocities and angular velocities at `kT` with
    /// the total momentum removed, each part then scaled to exactly `kT` per degree of freedom
    /// (`3N − 3` translational, `2N` or `3N` rotational).
    ///
    /// # Errors
    /// [`SmdError::Count`] for fewer than 2 or more than [`MAX_BODIES`] bodies,
    /// [`SmdError::Parameter`] for a bad density, aspect or temperature.
    pub fn new(setup: &Setup) -> Result<Self, SmdError> {
        check_count(setup.n)?;
        let density = positive("density", setup.density)?;
        for a in setup.aspect {
            positive("aspect", a)?;
        }
        let kt = non_negative("temperature", setup.temperature)?;
        let n = setup.n;
        let a = DVec3::from(setup.aspect);
        let lengths = a * (n as f64 / density / (a.x * a.y * a.z)).cbrt();
        let pos = lattice_sites(setup.lattice, n, lengths);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(setup.seed);
        let (axis, rot) = match setup.body {
            BodyModel::Sphere { .. } => (Vec::new(), Vec::new()),
            BodyModel::LinearRotor { .. } => {
                ((0..n).map(|_| random_unit(&mut rng)).collect(), Vec::new())
            }
            BodyModel::Rigid { axis, .. } => {
                let rot: Vec<DMat3> = (0..n).map(|_| random_rotation(&mut rng)).collect();
                (rot.iter().map(|r| *r * axis).collect(), rot)
            }
        };
        let mut system = Self {
            lengths,
            body: setup.body,
            image: vec![DVec3::ZERO; n],
            vel: vec![DVec3::ZERO; n],
            ang_mom: if setup.body.rotates() {
                vec![DVec3::ZERO; n]
            } else {
                Vec::new()
            },
            pos,
            axis,
            rot,
        };
        system.thermalize(kt, &mut rng);
        Ok(system)
    }

    /// A system from explicit state. `angular_momenta` are lab vectors (empty for spheres);
    /// a linear rotor's component along its axis is dropped.
    ///
    /// # Errors
    /// [`SmdError::Inconsistent`] if the lists' lengths differ, the orientations do not fit
    /// the body model, or a value is not finite; [`SmdError::Parameter`] for a bad box;
    /// [`SmdError::Count`] for a bad number of bodies.
    pub fn from_parts(
        lengths: DVec3,
        body: BodyModel,
        positions: Vec<DVec3>,
        velocities: Vec<DVec3>,
        orientations: Orientations,
        angular_momenta: Vec<DVec3>,
    ) -> Result<Self, SmdError> {
        for l in lengths.to_array() {
            positive("box length", l)?;
        }
        let n = positions.len();
        check_count(n)?;
        let bad = |what: String| Err(SmdError::Inconsistent(what));
        if velocities.len() != n {
            return bad(format!("{n} positions but {} velocities", velocities.len()));
        }
        if let Some(i) = (0..n).find(|&i| !(positions[i].is_finite() && velocities[i].is_finite()))
        {
            return bad(format!("body {i}: position or velocity is not finite"));
        }
        let want_l = if body.rotates() { n } else { 0 };
        if angular_momenta.len() != want_l {
            return bad(format!(
                "{} angular momenta for {n} bodies of a model with {} rotational degrees of \
                 freedom (give {want_l})",
                angular_momenta.len(),
                body.rotational_dof()
            ));
        }
        if let Some(i) = angular_momenta.iter().position(|l| !l.is_finite()) {
            return bad(format!("body {i}: angular momentum is not finite"));
        }
        let (axis, rot, ang_mom) = match (body, orientations) {
            (BodyModel::Sphere { .. }, Orientations::None) => (Vec::new(), Vec::new(), Vec::new()),
            (BodyModel::LinearRotor { .. }, Orientations::Axes(axes)) if axes.len() == n => {
                let mut unit = Vec::with_capacity(n);
                for (i, s) in axes.iter().enumerate() {
                    match s.is_finite().then(|| s.try_normalize()).flatten() {
                        Some(u) => unit.push(u),
                        None => return bad(format!("body {i}: axis {s} is zero or not finite")),
                    }
                }
                let l = angular_momenta
                    .iter()
                    .zip(&unit)
                    .map(|(l, s)| *l - *s * s.dot(*l))
                    .collect();
                (unit, Vec::new(), l)
            }
            (BodyModel::Rigid { axis, .. }, Orientations::Rotations(rots)) if rots.len() == n => {
                for (i, r) in rots.iter().enumerate() {
                    let dev = (r.transpose() * *r - DMat3::IDENTITY)
                        .to_cols_array()
                        .iter()
                        .fold(0.0f64, |m, x| m.max(x.abs()))
                        .max((r.determinant() - 1.0).abs());
                    if dev.is_nan() || dev > 1e-9 {
                        return bad(format!(
                            "body {i}: orientation is not a proper rotation (deviation {dev:e})"
                        ));
                    }
                }
                let s = rots.iter().map(|r| *r * axis).collect();
                (s, rots, angular_momenta)
            }
            (b, o) => {
                let what = match o {
                    Orientations::None => "no orientations".to_owned(),
                    Orientations::Axes(a) => format!("{} axes", a.len()),
                    Orientations::Rotations(r) => format!("{} rotations", r.len()),
                };
                let want = match b {
                    BodyModel::Sphere { .. } => "Orientations::None",
                    BodyModel::LinearRotor { .. } => "Orientations::Axes, one per body",
                    BodyModel::Rigid { .. } => "Orientations::Rotations, one per body",
                };
                return bad(format!(
                    "{what} for {n} bodies: this body model needs {want}"
                ));
            }
        };
        Ok(Self {
            lengths,
            body,
            image: vec![DVec3::ZERO; n],
            pos: positions,
            vel: velocities,
            axis,
            ang_mom,
            rot,
        })
    }

    /// Draws Maxwell–Boltzmann velocities (and angular velocities) at `kT`, removes the total
    /// momentum, and scales each part to exactly `kT` per degree of freedom.
    fn thermalize(&mut self, kt: f64, rng: &mut Xoshiro256PlusPlus) {
        let n = self.n();
        let m = self.body.mass();
        let sd = (kt / m).sqrt();
        for v in &mut self.vel {
            *v = gaussian3(rng) * sd;
        }
        let mean = self.vel.iter().copied().sum::<DVec3>() / n as f64;
        for v in &mut self.vel {
            *v -= mean;
        }
        match self.body {
            BodyModel::Sphere { .. } => {}
            BodyModel::LinearRotor { inertia, .. } => {
                for (l, s) in self.ang_mom.iter_mut().zip(&self.axis) {
                    let g = gaussian3(rng);
                    *l = (g - *s * s.dot(g)) * (kt * inertia).sqrt();
                }
            }
            BodyModel::Rigid { moments, .. } => {
                let i = DVec3::from(moments.get());
                for (l, r) in self.ang_mom.iter_mut().zip(&self.rot) {
                    // Body-frame L_k = I_k ω_k with ω_k ~ N(0, kT/I_k): sd √(kT I_k).
                    let lb = gaussian3(rng) * (i * kt).map(f64::sqrt);
                    *l = *r * lb;
                }
            }
        }
        self.scale_to(kt, kt);
    }

    /// Scales velocities and angular momenta so that the translational and rotational kinetic
    /// temperatures are `kt_trans` and `kt_rot` (a part at rest stays at rest).
    pub(crate) fn scale_to(&mut self, kt_trans: f64, kt_rot: f64) {
        let (kin_t, kin_r) = self.kinetic_energy();
        let (dof_t, dof_r) = (self.dof_translational(), self.dof_rotational());
        if kin_t > 0.0 {
            let f = (0.5 * dof_t * kt_trans / kin_t).sqrt();
            for v in &mut self.vel {
                *v *= f;
            }
        }
        if kin_r > 0.0 {
            let f = (0.5 * dof_r * kt_rot / kin_r).sqrt();
            for l in &mut self.ang_mom {
                *l *= f;
            }
        }
    }

    /// Number of bodies.
    pub fn n(&self) -> usize {
        self.pos.len()
    }

    /// Box edge lengths.
    pub fn lengths(&self) -> DVec3 {
        self.lengths
    }

    /// Box volume.
    pub fn volume(&self) -> f64 {
        self.lengths.x * self.lengths.y * self.lengths.z
    }

    /// The body model.
    pub fn body(&self) -> &BodyModel {
        &self.body
    }

    /// Positions. They are put back in the box at every neighbour-list build and may be up to
    /// half a skin outside it in between; [`System::unwrapped`] follows bodies across walls.
    pub fn positions(&self) -> &[DVec3] {
        &self.pos
    }

    /// Sets the integral image counters per body (unwrapped = position + image ∘ L), for a
    /// run that continues another's unwrapped positions.
    ///
    /// # Errors
    /// [`SmdError::Inconsistent`] unless there is one per body.
    pub fn set_images(&mut self, images: &[[i32; 3]]) -> Result<(), SmdError> {
        if images.len() != self.pos.len() {
            return Err(SmdError::Inconsistent(format!(
                "{} image counters for {} bodies",
                images.len(),
                self.pos.len()
            )));
        }
        self.image = images
            .iter()
            .map(|m| DVec3::new(m[0].into(), m[1].into(), m[2].into()))
            .collect();
        Ok(())
    }

    /// The position of body `i` without periodic wrapping (continuous in time).
    #[inline]
    pub fn unwrapped(&self, i: usize) -> DVec3 {
        self.pos[i] + self.image[i] * self.lengths
    }

    /// Velocities.
    pub fn velocities(&self) -> &[DVec3] {
        &self.vel
    }

    /// Lab-frame axes `s` of the bodies (empty for spheres).
    pub fn axes(&self) -> &[DVec3] {
        &self.axis
    }

    /// Lab-frame angular momenta about each body's centre (empty for spheres).
    pub fn angular_momenta(&self) -> &[DVec3] {
        &self.ang_mom
    }

    /// Orientations `R` (body → lab) of general rigid bodies (empty otherwise).
    pub fn orientations(&self) -> &[DMat3] {
        &self.rot
    }

    /// Lab-frame angular velocity of body `i` (zero for spheres).
    pub fn angular_velocity(&self, i: usize) -> DVec3 {
        match self.body {
            BodyModel::Sphere { .. } => DVec3::ZERO,
            BodyModel::LinearRotor { inertia, .. } => self.ang_mom[i] / inertia,
            BodyModel::Rigid { moments, .. } => {
                let r = self.rot[i];
                r * ((r.transpose() * self.ang_mom[i]) / DVec3::from(moments.get()))
            }
        }
    }

    /// Kinetic energy `(translational, rotational)`.
    pub fn kinetic_energy(&self) -> (f64, f64) {
        let m = self.body.mass();
        let t = 0.5 * m * self.vel.iter().map(|v| v.length_squared()).sum::<f64>();
        let r = match self.body {
            BodyModel::Sphere { .. } => 0.0,
            BodyModel::LinearRotor { inertia, .. } => {
                0.5 / inertia * self.ang_mom.iter().map(|l| l.length_squared()).sum::<f64>()
            }
            BodyModel::Rigid { moments, .. } => {
                let inv = DVec3::ONE / DVec3::from(moments.get());
                0.5 * self
                    .ang_mom
                    .iter()
                    .zip(&self.rot)
                    .map(|(l, r)| {
                        let lb = r.transpose() * *l;
                        (lb * lb * inv).element_sum()
                    })
                    .sum::<f64>()
            }
        };
        (t, r)
    }

    /// Translational degrees of freedom, `3N − 3` (the total momentum is conserved).
    pub fn dof_translational(&self) -> f64 {
        3.0 * self.n() as f64 - 3.0
    }

    /// Rotational degrees of freedom, `2N` (linear rotors), `3N` (rigid) or 0.
    pub fn dof_rotational(&self) -> f64 {
        (self.body.rotational_dof() * self.n()) as f64
    }

    /// Total linear momentum.
    pub fn momentum(&self) -> DVec3 {
        self.vel.iter().copied().sum::<DVec3>() * self.body.mass()
    }

    /// Total angular momentum about `origin`: `Σ (r_i − origin) × m v_i + L_i`, with unwrapped
    /// positions. Conserved only without periodic images (an isolated cluster).
    pub fn angular_momentum(&self, origin: DVec3) -> DVec3 {
        let m = self.body.mass();
        let orbital: DVec3 = (0..self.n())
            .map(|i| (self.unwrapped(i) - origin).cross(self.vel[i] * m))
            .sum();
        orbital + self.ang_mom.iter().copied().sum::<DVec3>()
    }

    /// Negates every velocity and angular momentum: the time-reversed state.
    pub fn reverse_momenta(&mut self) {
        for v in &mut self.vel {
            *v = -*v;
        }
        for l in &mut self.ang_mom {
            *l = -*l;
        }
    }
}

fn check_count(n: usize) -> Result<(), SmdError> {
    if (2..=MAX_BODIES).contains(&n) {
        Ok(())
    } else {
        Err(SmdError::Count {
            name: "number of bodies",
            value: n as u64,
            why: "between 2 and 2^27",
        })
    }
}

/// The first `n` sites of a lattice filling the box: unit cells per axis in proportion to the
/// edges, as few as hold `n` sites.
fn lattice_sites(lattice: Lattice, n: usize, lengths: DVec3) -> Vec<DVec3> {
    let basis: &[[f64; 3]] = match lattice {
        Lattice::Fcc => &[
            [0.25, 0.25, 0.25],
            [0.75, 0.75, 0.25],
            [0.75, 0.25, 0.75],
            [0.25, 0.75, 0.75],
        ],
        Lattice::Sc => &[[0.5, 0.5, 0.5]],
    };
    let cells_needed = n.div_ceil(basis.len());
    let scale = (cells_needed as f64 / (lengths.x * lengths.y * lengths.z)).cbrt();
    let mut k = [0usize; 3];
    for a in 0..3 {
        k[a] = ((lengths[a] * scale).round() as usize).max(1);
    }
    while k[0] * k[1] * k[2] < cells_needed {
        // Grow the axis whose cells are widest.
        let a = (0..3)
            .max_by(|&x, &y| (lengths[x] / k[x] as f64).total_cmp(&(lengths[y] / k[y] as f64)))
            .unwrap_or(0);
        k[a] += 1;
    }
    let cell = lengths / DVec3::new(k[0] as f64, k[1] as f64, k[2] as f64);
    let mut out = Vec::with_capacity(n);
    'fill: for z in 0..k[2] {
        for y in 0..k[1] {
            for x in 0..k[0] {
                for b in basis {
                    if out.len() == n {
                        break 'fill;
                    }
                    out.push(DVec3::new(x as f64 + b[0], y as f64 + b[1], z as f64 + b[2]) * cell);
                }
            }
        }
    }
    out
}

fn gaussian3(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    DVec3::new(
        StandardNormal.sample(rng),
        StandardNormal.sample(rng),
        StandardNormal.sample(rng),
    )
}

/// A unit vector uniform on the sphere (a normalised Gaussian vector).
fn random_unit(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    loop {
        if let Some(u) = gaussian3(rng).try_normalize() {
            return u;
        }
    }
}

/// A rotation uniform on SO(3) (a normalised Gaussian quaternion).
fn random_rotation(rng: &mut Xoshiro256PlusPlus) -> DMat3 {
    loop {
        let g = gaussian3(rng);
        let w: f64 = StandardNormal.sample(rng);
        let q = DQuat::from_xyzw(g.x, g.y, g.z, w);
        let len = q.length();
        if len > 1e-6 {
            return DMat3::from_quat(q / len);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresh_systems_are_at_the_temperature_with_zero_momentum() {
        for body in [
            BodyModel::sphere(2.0).unwrap(),
            BodyModel::paper_rod(),
            BodyModel::rigid(3.0, [1.0, 2.0, 2.5], DVec3::Z).unwrap(),
        ] {
            let s = System::new(&Setup::new(108, 0.5, body, 1.3)).unwrap();
            assert_eq!(s.n(), 108);
            assert!((s.volume() - 108.0 / 0.5).abs() < 1e-10);
            assert!(s.momentum().length() < 1e-12);
            let (kt, kr) = s.kinetic_energy();
            assert!((2.0 * kt / s.dof_translational() - 1.3).abs() < 1e-12);
            if body.rotates() {
                assert!((2.0 * kr / s.dof_rotational() - 1.3).abs() < 1e-12);
                for (a, l) in s.axes().iter().zip(s.angular_momenta()) {
                    assert!((a.length() - 1.0).abs() < 1e-15);
                    if let BodyModel::LinearRotor { .. } = body {
                        assert!(a.dot(*l).abs() < 1e-12 * l.length());
                    }
                }
            } else {
                assert_eq!(kr, 0.0);
            }
            // Every body on a distinct lattice site inside the box.
            let l = s.lengths();
            for (i, p) in s.positions().iter().enumerate() {
                assert!(p.cmpge(DVec3::ZERO).all() && p.cmplt(l).all());
                for q in &s.positions()[..i] {
                    assert!((*p - *q).length() > 0.5);
                }
            }
        }
    }

    #[test]
    fn the_seed_decides_everything() {
        let setup = Setup::new(32, 0.3, BodyModel::paper_rod(), 4.2);
        let a = System::new(&setup).unwrap();
        assert_eq!(a, System::new(&setup).unwrap());
        let b = System::new(&Setup { seed: 2, ..setup }).unwrap();
        assert_ne!(a.velocities(), b.velocities());
    }

    #[test]
    fn bad_setups_are_refused_with_their_name() {
        let body = BodyModel::sphere(1.0).unwrap();
        let e = System::new(&Setup::new(1, 0.5, body, 1.0)).unwrap_err();
        assert!(e.to_string().contains("number of bodies"), "{e}");
        let e = System::new(&Setup::new(10, -0.5, body, 1.0)).unwrap_err();
        assert!(e.to_string().contains("density"), "{e}");
        let e = System::new(&Setup::new(10, 0.5, body, f64::NAN)).unwrap_err();
        assert!(e.to_string().contains("temperature"), "{e}");
        let e = System::from_parts(
            DVec3::ONE * 5.0,
            BodyModel::paper_rod(),
            vec![DVec3::ZERO, DVec3::X],
            vec![DVec3::ZERO; 2],
            Orientations::None,
            vec![DVec3::ZERO; 2],
        )
        .unwrap_err();
        assert!(e.to_string().contains("Orientations::Axes"), "{e}");
        let e = System::from_parts(
            DVec3::ONE * 5.0,
            BodyModel::paper_rod(),
            vec![DVec3::ZERO, DVec3::X],
            vec![DVec3::ZERO; 2],
            Orientations::Axes(vec![DVec3::X, DVec3::ZERO]),
            vec![DVec3::ZERO; 2],
        )
        .unwrap_err();
        assert!(e.to_string().contains("body 1"), "{e}");
    }
}
