//! ns per event of each impulse rule of `collide`, each next to its baseline:
//!
//! - spheres: the crate's hard-sphere rule against the textbook elastic-collision formula
//!   (normalised line of centres, no energy equation) and against the general contact rule
//!   applied to particles;
//! - rigid bodies: the terrace rule (003 Eq. 21) for rods and full tensors, with and without
//!   building the body from its attitude;
//! - molecules: the constrained rule (000 §IV.A, faer Cholesky of Z) against the rigid-body rule
//!   for the same event between two rigid tetrahedra.
//!
//! Each measurement cycles through 1024 pre-generated random events.

use collide::{
    Bond, ConstraintSolver, Contact, LinearBody, Molecule, PairForce, Particle, RigidBody,
    Velocity, contact, spheres, terrace,
};
use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DMat3, DQuat, DVec3};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::hint::black_box;

const N: usize = 1024;

fn v3(r: &mut Xoshiro256PlusPlus) -> DVec3 {
    DVec3::new(
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
    ) * 2.0
}

fn quat(r: &mut Xoshiro256PlusPlus) -> DQuat {
    DQuat::from_xyzw(
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
        r.random::<f64>() - 0.5,
    )
    .normalize()
}

/// The textbook hard-sphere collision: v_i' = v_i − 2 m_j/(m_i+m_j) (v_ij·n̂) n̂.
#[inline]
fn textbook(mi: f64, mj: f64, vi: DVec3, vj: DVec3, r: DVec3) -> (DVec3, DVec3) {
    let n = r.normalize();
    let vn = (vi - vj).dot(n);
    if vn >= 0.0 {
        return (vi, vj);
    }
    let k = 2.0 * vn / (mi + mj);
    (vi - (k * mj) * n, vj + (k * mi) * n)
}

fn bench_spheres(c: &mut Criterion) {
    let mut r = Xoshiro256PlusPlus::seed_from_u64(1);
    let ev: Vec<(DVec3, DVec3, DVec3)> = (0..N)
        .map(|_| (v3(&mut r), v3(&mut r), v3(&mut r)))
        .collect();
    let (pi, pj) = (Particle::new(1.0).unwrap(), Particle::new(2.5).unwrap());
    let mut g = c.benchmark_group("collide/spheres");
    let mut k = 0;
    g.bench_function("textbook elastic formula (baseline)", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            let (vi, vj, rr) = ev[k];
            black_box(textbook(1.0, 2.5, black_box(vi), vj, rr))
        })
    });
    g.bench_function("spheres hard core", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            let (vi, vj, rr) = ev[k];
            black_box(spheres(&pi, &pj, black_box(vi), vj, rr, f64::INFINITY))
        })
    });
    g.bench_function("spheres square well (step -0.3)", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            let (vi, vj, rr) = ev[k];
            black_box(spheres(&pi, &pj, black_box(vi), vj, rr, -0.3))
        })
    });
    g.bench_function("contact rule on particles", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            let (vi, vj, rr) = ev[k];
            let at = Contact::new(rr, DVec3::ZERO, DVec3::ZERO);
            black_box(contact(
                &pi,
                &pj,
                Velocity::new(black_box(vi), DVec3::ZERO),
                Velocity::new(vj, DVec3::ZERO),
                &at,
                f64::INFINITY,
            ))
        })
    });
    g.finish();
}

struct RigidEvent {
    q_i: DQuat,
    q_j: DQuat,
    vi: Velocity,
    vj: Velocity,
    push: PairForce,
    at: Contact,
}

fn bench_rigid(c: &mut Criterion) {
    let mut r = Xoshiro256PlusPlus::seed_from_u64(2);
    let ev: Vec<RigidEvent> = (0..N)
        .map(|_| {
            let (q_i, q_j) = (quat(&mut r), quat(&mut r));
            let (si, sj) = (q_i * DVec3::Z, q_j * DVec3::Z);
            let f = v3(&mut r);
            RigidEvent {
                q_i,
                q_j,
                vi: Velocity::new(v3(&mut r), v3(&mut r).cross(si)),
                vj: Velocity::new(v3(&mut r), v3(&mut r).cross(sj)),
                // Torques perpendicular to the rods' axes, as a rod potential gives.
                push: PairForce::new(f, si.cross(v3(&mut r)), sj.cross(v3(&mut r))),
                at: Contact::new(v3(&mut r), si * 0.5, -sj * 0.5),
            }
        })
        .collect();
    let moments = DVec3::new(1.0, 1.4, 2.0);
    let mut g = c.benchmark_group("collide/rigid");
    let mut k = 0;
    g.bench_function("terrace rule, two rods", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            let e = &ev[k];
            let ri = LinearBody::new(1.0, 0.3, e.q_i * DVec3::Z).unwrap();
            let rj = LinearBody::new(1.0, 0.3, e.q_j * DVec3::Z).unwrap();
            black_box(terrace(&ri, &rj, black_box(e.vi), e.vj, &e.push, -0.2))
        })
    });
    let bodies: Vec<(RigidBody, RigidBody)> = ev
        .iter()
        .map(|e| {
            (
                RigidBody::from_principal(1.0, moments, e.q_i).unwrap(),
                RigidBody::from_principal(3.0, moments, e.q_j).unwrap(),
            )
        })
        .collect();
    g.bench_function("terrace rule, full tensors (bodies prebuilt)", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            let e = &ev[k];
            let (bi, bj) = &bodies[k];
            black_box(terrace(bi, bj, black_box(e.vi), e.vj, &e.push, -0.2))
        })
    });
    g.bench_function("terrace rule, full tensors (bodies from attitude)", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            let e = &ev[k];
            let bi = RigidBody::from_principal(1.0, moments, black_box(e.q_i)).unwrap();
            let bj = RigidBody::from_principal(3.0, moments, e.q_j).unwrap();
            black_box(terrace(&bi, &bj, black_box(e.vi), e.vj, &e.push, -0.2))
        })
    });
    g.bench_function("contact rule, full tensors (bodies from attitude)", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            let e = &ev[k];
            let bi = RigidBody::from_principal(1.0, moments, black_box(e.q_i)).unwrap();
            let bj = RigidBody::from_principal(3.0, moments, e.q_j).unwrap();
            black_box(contact(
                &bi,
                &bj,
                black_box(e.vi),
                e.vj,
                &e.at,
                f64::INFINITY,
            ))
        })
    });
    g.finish();
}

fn bench_molecules(c: &mut Criterion) {
    // Two rigid tetrahedra (6 constraints each); event k hits atom k % 4 of one with atom
    // (k / 4) % 4 of the other.
    let mut r = Xoshiro256PlusPlus::seed_from_u64(3);
    let tet = [
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1.0, -1.0, -1.0),
        DVec3::new(-1.0, 1.0, -1.0),
        DVec3::new(-1.0, -1.0, 1.0),
    ];
    let masses = [1.0, 2.0, 3.0, 4.0];
    let total: f64 = masses.iter().sum();
    let com0 = masses.iter().zip(&tet).map(|(m, p)| *m * *p).sum::<DVec3>() / total;
    let bonds: Vec<Bond> = (0..4)
        .flat_map(|a| (a + 1..4).map(move |b| Bond::new(a, b)))
        .collect();
    struct Ev {
        pos_i: [DVec3; 4],
        pos_j: [DVec3; 4],
        vel_i: [DVec3; 4],
        vel_j: [DVec3; 4],
        body_i: (Velocity, DMat3),
        body_j: (Velocity, DMat3),
        a: usize,
        b: usize,
    }
    let inertia = |off: &[DVec3; 4]| {
        let mut t = DMat3::ZERO;
        for (m, d) in masses.iter().zip(off) {
            t += (DMat3::from_diagonal(DVec3::splat(d.length_squared()))
                - DMat3::from_cols(*d * d.x, *d * d.y, *d * d.z))
                * *m;
        }
        t
    };
    let ev: Vec<Ev> = (0..N)
        .map(|k| {
            let (qi, qj) = (quat(&mut r), quat(&mut r));
            let off_i = tet.map(|p| qi * (p - com0));
            let off_j = tet.map(|p| qj * (p - com0));
            let (a, b) = (k % 4, (k / 4) % 4);
            let dir = v3(&mut r).normalize();
            let com_i = DVec3::ZERO;
            let com_j = com_i + off_i[a] - dir * 1.0 - off_j[b];
            let (vi, wi, vj, wj) = (v3(&mut r), v3(&mut r), v3(&mut r), v3(&mut r));
            Ev {
                pos_i: off_i.map(|d| com_i + d),
                pos_j: off_j.map(|d| com_j + d),
                vel_i: off_i.map(|d| vi + wi.cross(d)),
                vel_j: off_j.map(|d| vj + wj.cross(d)),
                body_i: (Velocity::new(vi, wi), inertia(&off_i)),
                body_j: (Velocity::new(vj, wj), inertia(&off_j)),
                a,
                b,
            }
        })
        .collect();
    let mut g = c.benchmark_group("collide/molecules");
    let mut k = 0;
    g.bench_function("rigid-body rule, two tetrahedra (baseline)", |bch| {
        bch.iter(|| {
            k = (k + 1) % N;
            let e = &ev[k];
            let bi = RigidBody::from_lab_inertia(total, e.body_i.1).unwrap();
            let bj = RigidBody::from_lab_inertia(total, e.body_j.1).unwrap();
            let at = Contact::new(
                e.pos_i[e.a] - e.pos_j[e.b],
                e.pos_i[e.a]
                    - e.pos_i
                        .iter()
                        .zip(&masses)
                        .map(|(p, m)| *p * *m)
                        .sum::<DVec3>()
                        / total,
                e.pos_j[e.b]
                    - e.pos_j
                        .iter()
                        .zip(&masses)
                        .map(|(p, m)| *p * *m)
                        .sum::<DVec3>()
                        / total,
            );
            black_box(contact(
                &bi,
                &bj,
                black_box(e.body_i.0),
                e.body_j.0,
                &at,
                f64::INFINITY,
            ))
        })
    });
    let mut solver = ConstraintSolver::new();
    g.bench_function("constrained rule, two tetrahedra (12 constraints)", |bch| {
        bch.iter(|| {
            k = (k + 1) % N;
            let e = &ev[k];
            let (mut vi, mut vj) = (e.vel_i, e.vel_j);
            let imp = solver.between(
                Molecule {
                    masses: &masses,
                    positions: &e.pos_i,
                    velocities: &mut vi,
                    bonds: &bonds,
                },
                e.a,
                Molecule {
                    masses: &masses,
                    positions: &e.pos_j,
                    velocities: &mut vj,
                    bonds: &bonds,
                },
                e.b,
                black_box(f64::INFINITY),
            );
            black_box((imp, vi, vj))
        })
    });
    g.finish();
}

criterion_group!(benches, bench_spheres, bench_rigid, bench_molecules);
criterion_main!(benches);
