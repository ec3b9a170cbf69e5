//! Random events with conserved quantities computed independently of the crate (from masses,
//! principal moments and attitudes, never from the crate's inverse tensors). Shared by the
//! property tests and by the validation example (`examples/validate_collide.rs` includes this file).
#![allow(dead_code, unreachable_pub)]

use collide::{
    Body, Bond, CollideError, Contact, LinearBody, PairForce, Particle, RigidBody, Velocity,
};
use glam::{DMat3, DQuat, DVec3};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

pub type Rng = Xoshiro256PlusPlus;

pub fn rng(seed: u64) -> Rng {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

pub fn uniform(r: &mut Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * r.random::<f64>()
}

/// A uniform index in `0..n`.
pub fn pick(r: &mut Rng, n: usize) -> usize {
    r.random_range(0..n)
}

/// `10^U(lo, hi)`.
pub fn log_uniform(r: &mut Rng, lo: f64, hi: f64) -> f64 {
    10f64.powf(uniform(r, lo, hi))
}

pub fn cube(r: &mut Rng, scale: f64) -> DVec3 {
    DVec3::new(
        uniform(r, -1.0, 1.0),
        uniform(r, -1.0, 1.0),
        uniform(r, -1.0, 1.0),
    ) * scale
}

pub fn unit(r: &mut Rng) -> DVec3 {
    loop {
        let v = cube(r, 1.0);
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

pub fn attitude(r: &mut Rng) -> DQuat {
    loop {
        let q = DQuat::from_xyzw(
            uniform(r, -1.0, 1.0),
            uniform(r, -1.0, 1.0),
            uniform(r, -1.0, 1.0),
            uniform(r, -1.0, 1.0),
        );
        let l = q.length();
        if l > 0.1 && l <= 1.0 {
            return q / l;
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Particle,
    Linear,
    Rigid,
}

pub const KINDS: [Kind; 3] = [Kind::Particle, Kind::Linear, Kind::Rigid];

/// A body as the test knows it: mass, principal moments and attitude.
#[derive(Clone, Copy, Debug)]
pub struct Spec {
    pub kind: Kind,
    pub mass: f64,
    /// Principal moments; a linear body has `(I, I, 0)` about its axis `attitude * Z`.
    pub moments: DVec3,
    pub attitude: DQuat,
}

impl Spec {
    pub fn random(r: &mut Rng, kind: Kind, mass: f64) -> Spec {
        // Radius of gyration between 0.1 and 10: moments from 1e-2 m to 1e2 m.
        let scale = mass * log_uniform(r, -2.0, 2.0);
        let moments = match kind {
            Kind::Particle => DVec3::ZERO,
            Kind::Linear => DVec3::new(scale, scale, 0.0),
            Kind::Rigid => {
                let (a, b) = (uniform(r, 0.1, 1.0), uniform(r, 0.1, 1.0));
                // Triangle inequality: |a − b| ≤ c ≤ a + b.
                let c = uniform(r, (a - b).abs(), a + b).max(0.01);
                DVec3::new(a, b, c) * scale
            }
        };
        Spec {
            kind,
            mass,
            moments,
            attitude: attitude(r),
        }
    }

    pub fn axis(&self) -> DVec3 {
        self.attitude * DVec3::Z
    }

    /// The lab-frame inertia tensor, built from the principal moments.
    pub fn inertia(&self) -> DMat3 {
        let r = DMat3::from_quat(self.attitude);
        r * DMat3::from_diagonal(self.moments) * r.transpose()
    }

    /// The body as the crate sees it.
    pub fn body(&self) -> TestBody {
        match self.kind {
            Kind::Particle => TestBody::P(Particle::new(self.mass).unwrap()),
            Kind::Linear => {
                TestBody::L(LinearBody::new(self.mass, self.moments.x, self.axis()).unwrap())
            }
            Kind::Rigid => TestBody::R(
                RigidBody::from_principal(self.mass, self.moments, self.attitude).unwrap(),
            ),
        }
    }

    /// Body-fixed unit vectors a potential may depend on (003 Eqs. 4–5).
    pub fn vectors(&self) -> Vec<DVec3> {
        match self.kind {
            Kind::Particle => vec![],
            Kind::Linear => vec![self.axis()],
            Kind::Rigid => vec![
                self.attitude * DVec3::X,
                self.attitude * DVec3::new(0.0, 0.6, 0.8),
            ],
        }
    }

    /// A thermal-looking velocity: speeds ~ 1/√m, angular speeds ~ 1/√I.
    pub fn random_velocity(&self, r: &mut Rng) -> Velocity {
        let linear = cube(r, 1.0 / self.mass.sqrt());
        let angular = match self.kind {
            Kind::Particle => DVec3::ZERO,
            Kind::Linear => {
                let w = cube(r, 1.0 / self.moments.x.sqrt());
                w - w.dot(self.axis()) * self.axis()
            }
            Kind::Rigid => cube(r, 1.0 / self.moments.element_sum().sqrt()),
        };
        Velocity::new(linear, angular)
    }

    /// A point of the body (offset from the centre of mass, lab frame): anywhere for a rigid
    /// body, on the axis for a linear one, the centre for a particle.
    pub fn random_arm(&self, r: &mut Rng) -> DVec3 {
        match self.kind {
            Kind::Particle => DVec3::ZERO,
            Kind::Linear => self.axis() * uniform(r, -1.0, 1.0),
            Kind::Rigid => cube(r, 1.0),
        }
    }
}

/// The three kinds behind one type, through the crate's public [`Body`] extension point.
#[derive(Clone, Copy, Debug)]
pub enum TestBody {
    P(Particle),
    L(LinearBody),
    R(RigidBody),
}

impl Body for TestBody {
    fn inv_mass(&self) -> f64 {
        match self {
            TestBody::P(b) => b.inv_mass(),
            TestBody::L(b) => b.inv_mass(),
            TestBody::R(b) => b.inv_mass(),
        }
    }

    fn angular_response(&self, torque: DVec3) -> Result<DVec3, CollideError> {
        match self {
            TestBody::P(b) => b.angular_response(torque),
            TestBody::L(b) => b.angular_response(torque),
            TestBody::R(b) => b.angular_response(torque),
        }
    }
}

/// Totals over a set of bodies, with the scales their errors are measured against.
#[derive(Clone, Copy, Debug, Default)]
pub struct Totals {
    pub energy: f64,
    pub momentum: DVec3,
    pub angular: DVec3,
    pub momentum_scale: f64,
    pub angular_scale: f64,
}

impl Totals {
    pub fn add(&mut self, mass: f64, inertia: DMat3, pos: DVec3, v: Velocity) {
        let l_spin = inertia * v.angular;
        let p = mass * v.linear;
        self.energy += 0.5 * mass * v.linear.length_squared() + 0.5 * v.angular.dot(l_spin);
        self.momentum += p;
        self.angular += pos.cross(p) + l_spin;
        self.momentum_scale += p.length();
        self.angular_scale += pos.cross(p).length() + l_spin.length();
    }

    pub fn of_bodies(bodies: &[(&Spec, DVec3, Velocity)]) -> Totals {
        let mut t = Totals::default();
        for (spec, pos, v) in bodies {
            t.add(spec.mass, spec.inertia(), *pos, *v);
        }
        t
    }

    pub fn of_atoms(masses: &[f64], pos: &[DVec3], vel: &[DVec3]) -> Totals {
        let mut t = Totals::default();
        for ((m, r), v) in masses.iter().zip(pos).zip(vel) {
            t.add(*m, DMat3::ZERO, *r, Velocity::new(*v, DVec3::ZERO));
        }
        t
    }

    pub fn merge(self, o: Totals) -> Totals {
        Totals {
            energy: self.energy + o.energy,
            momentum: self.momentum + o.momentum,
            angular: self.angular + o.angular,
            momentum_scale: self.momentum_scale + o.momentum_scale,
            angular_scale: self.angular_scale + o.angular_scale,
        }
    }
}

/// Relative conservation errors of one event.
#[derive(Clone, Copy, Debug, Default)]
pub struct Errors {
    /// `|K' + ΔV_applied − K| / (K + |ΔV_applied|)`.
    pub energy: f64,
    /// `|P' − P| / Σ|p|` (before and after).
    pub momentum: f64,
    /// `|L' − L| / Σ(|r × p| + |I ω|)` (before and after), about the lab origin.
    pub angular: f64,
}

impl Errors {
    pub fn between(before: &Totals, after: &Totals, delta_v_applied: f64) -> Errors {
        let ratio = |num: f64, den: f64| if den == 0.0 { num } else { num / den };
        Errors {
            energy: ratio(
                (after.energy + delta_v_applied - before.energy).abs(),
                before.energy + delta_v_applied.abs(),
            ),
            momentum: ratio(
                (after.momentum - before.momentum).length(),
                before.momentum_scale + after.momentum_scale,
            ),
            angular: ratio(
                (after.angular - before.angular).length(),
                before.angular_scale + after.angular_scale,
            ),
        }
    }

    pub fn max(self, o: Errors) -> Errors {
        Errors {
            energy: self.energy.max(o.energy),
            momentum: self.momentum.max(o.momentum),
            angular: self.angular.max(o.angular),
        }
    }

    pub fn worst(&self) -> f64 {
        self.energy.max(self.momentum).max(self.angular)
    }
}

/// Force and torques of a random rotationally invariant potential
/// `U(r_ij, {r_ij·s_iα}, {r_ij·s_jβ}, {s_iα·s_jβ})` (003 Eqs. 4–5): random partial derivatives.
/// They satisfy 003 Eq. 6 by construction.
pub fn potential_push(r: &mut Rng, si: &Spec, sj: &Spec, r_ij: DVec3) -> PairForce {
    let (vi, vj) = (si.vectors(), sj.vectors());
    let mut force = -uniform(r, -1.0, 1.0) * r_ij.normalize();
    let mut torque_i = DVec3::ZERO;
    let mut torque_j = DVec3::ZERO;
    for s in &vi {
        let d = uniform(r, -1.0, 1.0); // ∂U/∂(r_ij·s_iα)
        force -= d * *s;
        torque_i -= d * s.cross(r_ij);
    }
    for s in &vj {
        let d = uniform(r, -1.0, 1.0); // ∂U/∂(r_ij·s_jβ)
        force -= d * *s;
        torque_j -= d * s.cross(r_ij);
    }
    for a in &vi {
        for b in &vj {
            let d = uniform(r, -1.0, 1.0); // ∂U/∂(s_iα·s_jβ)
            torque_i -= d * a.cross(*b);
            torque_j += d * a.cross(*b);
        }
    }
    PairForce::new(force, torque_i, torque_j)
}

/// Centres of mass and a contact between two sites on the line of action.
pub fn contact_geometry(r: &mut Rng, si: &Spec, sj: &Spec) -> (DVec3, DVec3, Contact) {
    let arm_i = si.random_arm(r);
    let arm_j = sj.random_arm(r);
    let normal = unit(r);
    let pos_j = cube(r, 10.0);
    let site_j = pos_j + arm_j;
    let site_i = site_j + normal * uniform(r, 0.5, 2.0);
    let pos_i = site_i - arm_i;
    // The normal as a simulator computes it, from the two sites.
    (pos_i, pos_j, Contact::new(site_i - site_j, arm_i, arm_j))
}

/// The kinetic energy of the motion along the impulse, `b²/4a`, measured from the velocity
/// changes of the participants (`a S² = Σ ½ Δv·M Δv`, `b S = Σ v·M Δv`): what the pair brings
/// to the step. Items are (mass, inertia, before, after).
pub fn normal_energy(items: &[(f64, DMat3, Velocity, Velocity)]) -> f64 {
    let (mut a_s2, mut b_s) = (0.0, 0.0);
    for (m, inertia, v0, v1) in items {
        let dl = v1.linear - v0.linear;
        let dw = v1.angular - v0.angular;
        a_s2 += 0.5 * (m * dl.length_squared() + dw.dot(*inertia * dw));
        b_s += m * v0.linear.dot(dl) + v0.angular.dot(*inertia * dw);
    }
    if a_s2 == 0.0 {
        0.0
    } else {
        b_s * b_s / (4.0 * a_s2)
    }
}

/// The condition number of the approach rate `b = Σ v·M Δv / S`: the sum of the magnitudes of
/// its terms over the magnitude of the sum. Round-off in `b` (and so in `S`) is this many ulps;
/// it is large when the pair drifts fast compared with its relative motion.
pub fn approach_conditioning(items: &[(f64, DMat3, Velocity, Velocity)]) -> f64 {
    let (mut sum, mut abs) = (0.0, 0.0);
    for (m, inertia, v0, v1) in items {
        let dl = v1.linear - v0.linear;
        let dw = v1.angular - v0.angular;
        let t = [m * v0.linear.dot(dl), v0.angular.dot(*inertia * dw)];
        sum += t[0] + t[1];
        abs += t[0].abs() + t[1].abs();
    }
    if sum == 0.0 {
        1.0
    } else {
        (abs / sum.abs()).max(1.0)
    }
}

fn atom_items(masses: &[f64], v0: &[DVec3], v1: &[DVec3]) -> Vec<(f64, DMat3, Velocity, Velocity)> {
    masses
        .iter()
        .zip(v0.iter().zip(v1))
        .map(|(m, (a, b))| {
            (
                *m,
                DMat3::ZERO,
                Velocity::new(*a, DVec3::ZERO),
                Velocity::new(*b, DVec3::ZERO),
            )
        })
        .collect()
}

/// [`approach_conditioning`] of two sets of atoms.
pub fn approach_conditioning_atoms(masses: &[&[f64]], v0: &[&[DVec3]], v1: &[&[DVec3]]) -> f64 {
    let mut items = Vec::new();
    for k in 0..masses.len() {
        items.extend(atom_items(masses[k], v0[k], v1[k]));
    }
    approach_conditioning(&items)
}

/// [`normal_energy`] of one or more sets of atoms taking part in the same event.
pub fn normal_energy_atoms(masses: &[&[f64]], v0: &[&[DVec3]], v1: &[&[DVec3]]) -> f64 {
    let mut items = Vec::new();
    for k in 0..masses.len() {
        items.extend(atom_items(masses[k], v0[k], v1[k]));
    }
    normal_energy(&items)
}

/// Potential steps relative to a kinetic energy `k`: hard cores, zero, tiny, moderate (both
/// outcomes happen) and huge, of either sign.
pub const DELTA_V_CLASSES: usize = 15;

pub fn delta_v(class: usize, k: f64) -> f64 {
    match class % DELTA_V_CLASSES {
        0 => f64::INFINITY,
        1 => 0.0,
        2 => 1e-14 * k,
        3 => -1e-14 * k,
        4 => 1e-6 * k,
        5 => -1e-6 * k,
        6 => 0.05 * k,
        7 => 0.3 * k,
        8 => -0.3 * k,
        9 => k,
        10 => -k,
        11 => 1e6 * k,
        12 => -1e6 * k,
        13 => 1e12 * k,
        _ => -1e12 * k,
    }
}

/// The potential change the reversed event sees: crossing back releases what crossing took;
/// a reflected pair still faces the same step.
pub fn reverse_delta_v(original: f64, applied: f64, crossed: bool) -> f64 {
    if crossed { -applied } else { original }
}

// ---------------------------------------------------------------------------------------------
// Molecules as atoms with distance constraints.

/// Atoms of one molecule: masses, offsets from the centre of mass (lab frame) and constraints.
#[derive(Clone, Debug)]
pub struct Atoms {
    pub masses: Vec<f64>,
    pub offsets: Vec<DVec3>,
    pub bonds: Vec<Bond>,
    /// Whether the bonds make the molecule rigid.
    pub rigid: bool,
}

fn centred(masses: Vec<f64>, points: Vec<DVec3>, bonds: Vec<Bond>, rigid: bool) -> Atoms {
    let total: f64 = masses.iter().sum();
    let com = masses
        .iter()
        .zip(&points)
        .map(|(m, p)| *m * *p)
        .sum::<DVec3>()
        / total;
    Atoms {
        offsets: points.iter().map(|p| *p - com).collect(),
        masses,
        bonds,
        rigid,
    }
}

fn all_pairs(n: usize) -> Vec<Bond> {
    let mut v = Vec::new();
    for a in 0..n {
        for b in a + 1..n {
            v.push(Bond::new(a, b));
        }
    }
    v
}

fn masses(r: &mut Rng, n: usize, spread: f64) -> Vec<f64> {
    (0..n).map(|_| log_uniform(r, -spread, spread)).collect()
}

/// A rigid diatomic: one constraint; a linear body.
pub fn diatomic(r: &mut Rng, spread: f64) -> Atoms {
    let m = masses(r, 2, spread);
    centred(
        m,
        vec![DVec3::ZERO, unit(r) * uniform(r, 0.5, 2.0)],
        all_pairs(2),
        true,
    )
}

/// A rigid bent triatomic: three constraints, well away from linear.
pub fn triatomic(r: &mut Rng, spread: f64) -> Atoms {
    let m = masses(r, 3, spread);
    let (u, w) = loop {
        let (u, w) = (unit(r), unit(r));
        if u.cross(w).length() > 0.3 {
            break (u, w);
        }
    };
    let p = vec![
        DVec3::ZERO,
        u * uniform(r, 0.5, 2.0),
        w * uniform(r, 0.5, 2.0),
    ];
    centred(m, p, all_pairs(3), true)
}

/// A rigid tetrahedron (irregular, not flat): six constraints.
pub fn tetrahedron(r: &mut Rng, spread: f64) -> Atoms {
    let m = masses(r, 4, spread);
    loop {
        let p: Vec<DVec3> = (0..4).map(|_| cube(r, 1.0)).collect();
        let vol = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])).abs();
        let size: f64 = (1..4).map(|k| (p[k] - p[0]).length()).product();
        if vol > 0.2 * size && size > 0.05 {
            return centred(m, p, all_pairs(4), true);
        }
    }
}

/// A semi-flexible chain: bonds between neighbours only.
pub fn chain(r: &mut Rng, n: usize, spread: f64) -> Atoms {
    let m = masses(r, n, spread);
    let mut p = vec![DVec3::ZERO];
    for k in 1..n {
        let next = p[k - 1] + unit(r) * uniform(r, 0.5, 1.5);
        p.push(next);
    }
    let bonds = (0..n - 1).map(|k| Bond::new(k, k + 1)).collect();
    centred(m, p, bonds, false)
}

impl Atoms {
    /// The same molecule with every mass multiplied by `factor`.
    pub fn scaled(mut self, factor: f64) -> Atoms {
        for m in &mut self.masses {
            *m *= factor;
        }
        self
    }

    pub fn total_mass(&self) -> f64 {
        self.masses.iter().sum()
    }

    /// Inertia tensor about the centre of mass, `Σ m (|d|² 1 − d dᵀ)`.
    pub fn inertia(&self) -> DMat3 {
        let mut t = DMat3::ZERO;
        for (m, d) in self.masses.iter().zip(&self.offsets) {
            let outer = DMat3::from_cols(*d * d.x, *d * d.y, *d * d.z);
            t += (DMat3::from_diagonal(DVec3::splat(d.length_squared())) - outer) * *m;
        }
        t
    }

    /// Velocities obeying the constraints: a rigid motion, plus for a chain a random velocity
    /// perpendicular to each bond, passed down the chain.
    pub fn velocities(&self, r: &mut Rng, linear: DVec3, angular: DVec3) -> Vec<DVec3> {
        let mut v: Vec<DVec3> = self
            .offsets
            .iter()
            .map(|d| linear + angular.cross(*d))
            .collect();
        if !self.rigid {
            let mut extra = vec![DVec3::ZERO; v.len()];
            for k in 1..v.len() {
                let bond = self.offsets[k] - self.offsets[k - 1];
                let w = cube(r, 1.0 / self.masses[k].sqrt());
                extra[k] = extra[k - 1] + w - w.dot(bond) / bond.length_squared() * bond;
            }
            // Remove the added centre-of-mass drift so momentum stays what `linear` says.
            let drift = self
                .masses
                .iter()
                .zip(&extra)
                .map(|(m, e)| *m * *e)
                .sum::<DVec3>()
                / self.total_mass();
            for (vk, e) in v.iter_mut().zip(extra) {
                *vk += e - drift;
            }
        }
        v
    }

    /// `max_α |∇σ_α·v| / (|r_ab| (|v_a| + |v_b|))`: how far velocities break the constraints.
    pub fn constraint_violation(&self, vel: &[DVec3]) -> f64 {
        self.bonds
            .iter()
            .map(|b| {
                let r = self.offsets[b.a] - self.offsets[b.b];
                let dv = vel[b.a] - vel[b.b];
                let scale = r.length() * (vel[b.a].length() + vel[b.b].length());
                if scale == 0.0 {
                    0.0
                } else {
                    r.dot(dv).abs() / scale
                }
            })
            .fold(0.0, f64::max)
    }
}

/// Largest `|x − y|` over two lists of vectors, relative to the largest `|x|`, `|y|`.
pub fn max_relative_difference(x: &[DVec3], y: &[DVec3]) -> f64 {
    let scale = x.iter().chain(y).map(|v| v.length()).fold(0.0, f64::max);
    let diff = x
        .iter()
        .zip(y)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    if scale == 0.0 { diff } else { diff / scale }
}
