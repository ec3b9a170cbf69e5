//! Two derivations, one answer: a rigid molecule described as atoms with distance constraints
//! (000 §IV.A, through the `Z` matrix) and as a rigid body with its inertia tensor (000 §IV.B)
//! must leave every atom with the same velocity, and the same `S`.

use crate::common;
use crate::common::*;
use collide::{
    ConstraintSolver, Contact, LinearBody, Molecule, Particle, RigidBody, Velocity, contact,
};
use glam::DVec3;
use proptest::prelude::*;

/// Agreement demanded of the two rules, relative to the largest atom velocity.
const TOL: f64 = 1e-11;

/// A molecule's state both ways: atoms, and centre-of-mass motion.
struct Both {
    atoms: Atoms,
    com: DVec3,
    linear: DVec3,
    angular: DVec3,
}

impl Both {
    fn new(r: &mut common::Rng, atoms: Atoms) -> Both {
        let m = atoms.total_mass();
        Both {
            com: cube(r, 5.0),
            linear: cube(r, 1.0 / m.sqrt()),
            angular: cube(r, 1.0),
            atoms,
        }
    }

    fn positions(&self) -> Vec<DVec3> {
        self.atoms.offsets.iter().map(|d| self.com + *d).collect()
    }

    /// Atom velocities of a rigid motion (for a diatomic the spin about its axis is dropped:
    /// it carries no energy and no constraint sees it).
    fn atom_velocities(&self, v: Velocity) -> Vec<DVec3> {
        self.atoms
            .offsets
            .iter()
            .map(|d| v.linear + v.angular.cross(*d))
            .collect()
    }
}

/// Runs both rules for atom `a` of `x` against atom `b` of `y` and returns the worst relative
/// difference of atom velocities and of `S`.
fn compare(x: &Both, a: usize, y: &Both, b: usize, dv: f64) -> (f64, f64) {
    let (px, py) = (x.positions(), y.positions());
    let vx = Velocity::new(x.linear, x.angular);
    let vy = Velocity::new(y.linear, y.angular);
    let (mut ax, mut ay) = (x.atom_velocities(vx), y.atom_velocities(vy));
    let imp = ConstraintSolver::new()
        .between(
            Molecule {
                masses: &x.atoms.masses,
                positions: &px,
                velocities: &mut ax,
                bonds: &x.atoms.bonds,
            },
            a,
            Molecule {
                masses: &y.atoms.masses,
                positions: &py,
                velocities: &mut ay,
                bonds: &y.atoms.bonds,
            },
            b,
            dv,
        )
        .unwrap();
    let at = Contact::new(px[a] - py[b], x.atoms.offsets[a], y.atoms.offsets[b]);
    let out = with_body(x, |bx| {
        with_body(y, |by| contact(bx, by, vx, vy, &at, dv).unwrap())
    });
    let (rx, ry) = (x.atom_velocities(out.i), y.atom_velocities(out.j));
    let d = max_relative_difference(&[ax.clone(), ay.clone()].concat(), &[rx, ry].concat());
    let ds = (imp.s - out.impulse.s).abs() / imp.s.abs().max(f64::MIN_POSITIVE);
    assert_eq!(imp.outcome, out.impulse.outcome);
    (d, ds)
}

/// The rigid-body description: a particle for one atom, a linear body for a diatomic, a rigid
/// body with the lab-frame inertia tensor of the atoms otherwise.
fn with_body<T>(x: &Both, f: impl FnOnce(&TestBody) -> T) -> T {
    let m = x.atoms.total_mass();
    let body = match x.atoms.masses.len() {
        1 => TestBody::P(Particle::new(m).unwrap()),
        2 => {
            let d = x.atoms.offsets[0] - x.atoms.offsets[1];
            let reduced = x.atoms.masses[0] * x.atoms.masses[1] / m;
            TestBody::L(LinearBody::new(m, reduced * d.length_squared(), d).unwrap())
        }
        _ => TestBody::R(RigidBody::from_lab_inertia(m, x.atoms.inertia()).unwrap()),
    };
    f(&body)
}

fn molecule(r: &mut common::Rng, shape: usize) -> Atoms {
    match shape {
        0 => chain(r, 1, 1.0),
        1 => diatomic(r, 1.0),
        2 => triatomic(r, 1.0),
        _ => tetrahedron(r, 1.0),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Rigid triatomics and tetrahedra (and, for the linear case, diatomics) against each other
    /// and against single atoms, with every kind of step.
    #[test]
    fn constrained_and_rigid_rules_agree(
        seed: u64, sx in 0usize..4, sy in 0usize..4, class in 0..DELTA_V_CLASSES,
    ) {
        let mut r = rng(seed);
        let mx = molecule(&mut r, sx);
        let x = Both::new(&mut r, mx);
        let my = molecule(&mut r, sy);
        let mut y = Both::new(&mut r, my);
        let a = pick(&mut r, x.atoms.masses.len());
        let b = pick(&mut r, y.atoms.masses.len());
        // Put y's atom b at a random distance from x's atom a.
        let site = x.com + x.atoms.offsets[a] - unit(&mut r) * uniform(&mut r, 0.5, 2.0);
        y.com = site - y.atoms.offsets[b];
        check(&admissible(x), a, &admissible(y), b, class)?;
    }
}

/// Drops the angular velocity a body of this kind cannot have: all of it for a single atom,
/// the spin about the axis for a diatomic (a linear body).
fn admissible(mut w: Both) -> Both {
    match w.atoms.masses.len() {
        1 => w.angular = DVec3::ZERO,
        2 => {
            let axis = (w.atoms.offsets[0] - w.atoms.offsets[1]).normalize();
            w.angular -= w.angular.dot(axis) * axis;
        }
        _ => {}
    }
    w
}

fn check(x: &Both, a: usize, y: &Both, b: usize, class: usize) -> Result<(), TestCaseError> {
    let k = {
        let mut t = Totals::default();
        for w in [x, y] {
            let v = w.atom_velocities(Velocity::new(w.linear, w.angular));
            t = t.merge(Totals::of_atoms(&w.atoms.masses, &w.positions(), &v));
        }
        t.energy
    };
    let (d, ds) = compare(x, a, y, b, delta_v(class, k));
    prop_assert!(d <= TOL, "velocities differ by {d:e}");
    prop_assert!(ds <= TOL, "S differs by {ds:e}");
    Ok(())
}

#[test]
fn tetrahedron_hit_on_every_atom_by_every_kind() {
    // A fixed, readable instance: a regular tetrahedron of unequal masses, hit on each atom
    // in turn by a single atom, a diatomic and a triatomic, hard core and well.
    let s = 1.0 / 3f64.sqrt();
    let pts = [
        DVec3::new(s, s, s),
        DVec3::new(s, -s, -s),
        DVec3::new(-s, s, -s),
        DVec3::new(-s, -s, s),
    ];
    let masses = [1.0, 2.0, 3.0, 4.0];
    let total: f64 = masses.iter().sum();
    let com = masses.iter().zip(&pts).map(|(m, p)| *m * *p).sum::<DVec3>() / total;
    let tet = Atoms {
        masses: masses.to_vec(),
        offsets: pts.iter().map(|p| *p - com).collect(),
        bonds: (0..4)
            .flat_map(|a| (a + 1..4).map(move |b| collide::Bond::new(a, b)))
            .collect(),
        rigid: true,
    };
    let mut r = rng(7);
    let mut worst: f64 = 0.0;
    for a in 0..4 {
        for other in 0..3 {
            for dv in [f64::INFINITY, -0.2, 0.2] {
                let x = Both {
                    atoms: tet.clone(),
                    com: DVec3::ZERO,
                    linear: DVec3::new(0.1, -0.2, 0.3),
                    angular: DVec3::new(0.5, 0.1, -0.4),
                };
                let atoms = molecule(&mut r, other);
                let b = 0;
                let dir = tet.offsets[a].normalize();
                let com = tet.offsets[a] + dir * 0.8 - atoms.offsets[b];
                let y = admissible(Both {
                    atoms,
                    com,
                    linear: -dir * 1.5,
                    angular: DVec3::new(0.2, -0.3, 0.1),
                });
                let (d, ds) = compare(&x, a, &y, b, dv);
                worst = worst.max(d).max(ds);
            }
        }
    }
    assert!(worst <= 1e-13, "worst disagreement {worst:e}");
}
