//! Random geometries and finite differences of `U`, computed from `energy` alone (never from
//! the crate's derivatives). Shared by the integration tests and the validation example
//! (`examples/validate_potential.rs` includes this file).
#![allow(dead_code, unreachable_pub)]

use glam::{DQuat, DVec3};
use potential::{GayBerne, LennardJones, LjRod, PairGeometry, PairPotential, Smoothed};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

pub type Rng = Xoshiro256PlusPlus;

pub fn rng(seed: u64) -> Rng {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

pub fn uniform(r: &mut Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * r.random::<f64>()
}

/// A uniformly distributed unit vector.
pub fn unit(r: &mut Rng) -> DVec3 {
    loop {
        let v = DVec3::new(
            uniform(r, -1.0, 1.0),
            uniform(r, -1.0, 1.0),
            uniform(r, -1.0, 1.0),
        );
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

/// `v` rotated by `angle` about the unit `axis`.
pub fn rotate(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    DQuat::from_axis_angle(axis, angle) * v
}

/// A potential under test and how to draw geometries in its interesting range.
pub struct Case {
    pub name: &'static str,
    pub potential: Box<dyn PairPotential>,
    /// Draws a geometry: the centre distance is chosen so that the (orientation-dependent)
    /// effective gap lies between 0.85 and 3 contact distances, from deep in the repulsive
    /// wall to the tail.
    pub sample: Box<dyn Fn(&mut Rng) -> PairGeometry>,
    /// Distances within this set of switching knots are avoided (the smoothing switch is C¹).
    pub knots: Vec<f64>,
}

fn axes(r: &mut Rng) -> (DVec3, DVec3, DVec3) {
    (unit(r), unit(r), unit(r))
}

/// Every potential of the crate, with the paper's rods in their own units (Å, kJ/mol).
pub fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    let lj = LennardJones::new(1.0, 1.0).unwrap();
    out.push(Case {
        name: "Lennard-Jones spheres",
        potential: Box::new(lj),
        sample: Box::new(|r| {
            let d = uniform(r, 0.85, 3.0);
            PairGeometry::spheres(unit(r) * d)
        }),
        knots: vec![],
    });
    for (name, rod) in [
        ("LJ rods (ζ = 0.33σ)", LjRod::new(1.0, 1.0, 0.33).unwrap()),
        ("LJ rods, paper units", LjRod::paper()),
    ] {
        out.push(Case {
            name,
            potential: Box::new(rod),
            sample: Box::new(move |r| {
                let (n, si, sj) = axes(r);
                let re = uniform(r, 0.85, 3.0) * rod.sigma();
                let c = si.dot(sj);
                let d = re - rod.zeta() * (0.5 - c * c);
                PairGeometry::new(n * d, si, sj)
            }),
            knots: vec![],
        });
    }
    for (name, gb) in [
        ("Gay-Berne GB(3, 5, 2, 1)", GayBerne::default()),
        (
            "Gay-Berne oblate (0.5, 0.2, 1, 3)",
            GayBerne::new(1.0, 1.0, 0.5, 0.2, 1.0, 3.0).unwrap(),
        ),
    ] {
        out.push(Case {
            name,
            potential: Box::new(gb),
            sample: Box::new(move |r| {
                let (n, si, sj) = axes(r);
                let (sigma, _) = gb.contact_and_depth(n.dot(si), n.dot(sj), si.dot(sj));
                let d = uniform(r, 0.85, 3.0) + sigma - 1.0;
                PairGeometry::new(n * d, si, sj)
            }),
            knots: vec![],
        });
    }
    let rod = LjRod::paper();
    let s = rod.sigma();
    out.push(Case {
        name: "smoothed LJ rods (003 Eq. 26)",
        potential: Box::new(Smoothed::paper(rod, s).unwrap()),
        sample: Box::new(move |r| {
            let (n, si, sj) = axes(r);
            PairGeometry::new(n * uniform(r, 2.3 * s, 3.05 * s), si, sj)
        }),
        knots: vec![2.5 * s, 3.0 * s],
    });
    let gb = GayBerne::default();
    out.push(Case {
        name: "smoothed Gay-Berne (r_l = 3.5, r_u = 4.5)",
        potential: Box::new(Smoothed::new(gb, 3.5, 4.5).unwrap()),
        sample: Box::new(move |r| {
            let (n, si, sj) = axes(r);
            PairGeometry::new(n * uniform(r, 3.3, 4.6), si, sj)
        }),
        knots: vec![3.5, 4.5],
    });
    out
}

/// Richardson-extrapolated central difference of `f` at 0 with step `h`: error `O(h⁴)`.
pub fn derivative(mut f: impl FnMut(f64) -> f64, h: f64) -> f64 {
    let d = |f: &mut dyn FnMut(f64) -> f64, h: f64| (f(h) - f(-h)) / (2.0 * h);
    let (a, b) = (d(&mut f, h), d(&mut f, 0.5 * h));
    (4.0 * b - a) / 3.0
}

/// `−∇_{r_ij} U` by finite differences.
pub fn fd_force(p: &dyn PairPotential, g: &PairGeometry, h: f64) -> DVec3 {
    let mut f = DVec3::ZERO;
    for (k, e) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
        f[k] = -derivative(
            |t| p.energy(&PairGeometry::new(g.r_ij + e * t, g.s_i, g.s_j)),
            h,
        );
    }
    f
}

/// Torque on body `i` (`body = 0`) or `j` (`body = 1`): `τ·e = −dU/dθ` for a rotation of that
/// body's axis by `θ` about each lab axis `e`.
pub fn fd_torque(p: &dyn PairPotential, g: &PairGeometry, body: usize, h: f64) -> DVec3 {
    let mut t = DVec3::ZERO;
    for (k, e) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
        t[k] = -derivative(|a| p.energy(&turned(g, body, e, a)), h);
    }
    t
}

/// The geometry with one body's axis turned by `angle` about `axis`.
pub fn turned(g: &PairGeometry, body: usize, axis: DVec3, angle: f64) -> PairGeometry {
    let mut out = *g;
    if body == 0 {
        out.s_i = rotate(g.s_i, axis, angle);
    } else {
        out.s_j = rotate(g.s_j, axis, angle);
    }
    out
}

/// `|a − e| / max(|e|, floor)`.
pub fn rel(a: DVec3, e: DVec3, floor: f64) -> f64 {
    (a - e).length() / e.length().max(floor)
}

/// Worst relative errors of the analytic force and torques against finite differences, and
/// the 003 Eq. 6 residual.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FdErrors {
    pub force: f64,
    pub torque_i: f64,
    pub torque_j: f64,
    pub balance: f64,
}

impl FdErrors {
    pub fn max(self, o: Self) -> Self {
        Self {
            force: self.force.max(o.force),
            torque_i: self.torque_i.max(o.torque_i),
            torque_j: self.torque_j.max(o.torque_j),
            balance: self.balance.max(o.balance),
        }
    }
}

/// Finite-difference step, relative to the length scale.
pub const FD_STEP: f64 = 1e-4;
/// Floors of the relative errors, relative to the round-off scale of `U`,
/// `|U| + r|F| + |U_min|` (`U` is computed from `r` and the axes with relative round-off `ε`,
/// so it carries an absolute error of order `ε(|U| + r|dU/dr|)`), and divided by a length
/// scale for the force. Finite differences of `U` carry that error divided by the step: an
/// analytic value below the floor is compared absolutely.
pub const FD_FLOOR: f64 = 1e-4;

/// Errors of one geometry; `None` if it is in an overlap (no finite force).
pub fn fd_errors(p: &dyn PairPotential, g: &PairGeometry) -> Option<FdErrors> {
    let e = p.evaluate(g).ok()?;
    let l = p.length_scale();
    let h = FD_STEP * l;
    let scale = round_off_scale(p, g, &e);
    let (ff, tf) = (FD_FLOOR * scale / l, FD_FLOOR * scale);
    Some(FdErrors {
        force: rel(e.force, fd_force(p, g, h), ff),
        torque_i: rel(e.torque_i, fd_torque(p, g, 0, FD_STEP), tf),
        torque_j: rel(e.torque_j, fd_torque(p, g, 1, FD_STEP), tf),
        balance: e.torque_imbalance(g.r_ij),
    })
}

/// `|U| + r|F| + |U_min|`: the scale of the absolute round-off of `U` (see [`FD_FLOOR`]).
pub fn round_off_scale(p: &dyn PairPotential, g: &PairGeometry, e: &potential::PairEval) -> f64 {
    e.energy.abs() + g.r_ij.length() * e.force.length() + p.minimum().abs()
}

/// Whether `g` lies within `margin` of a switching knot.
pub fn near_knot(case: &Case, g: &PairGeometry, margin: f64) -> bool {
    let r = g.r_ij.length();
    case.knots.iter().any(|k| (r - k).abs() < margin)
}

/// Draws a geometry of `case` clear of its knots by four finite-difference steps.
pub fn draw(case: &Case, r: &mut Rng) -> PairGeometry {
    let margin = 4.0 * FD_STEP * case.potential.length_scale();
    loop {
        let g = (case.sample)(r);
        if !near_knot(case, &g, margin) {
            return g;
        }
    }
}
