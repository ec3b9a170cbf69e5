//! Property tests: every rule conserves total energy (kinetic + ΔV exchanged), linear momentum
//! and angular momentum about the lab origin to 1e−12 relative, preserves the velocity
//! constraints of molecules, and is reversible, over random states, masses (ratios up to 10⁶),
//! inertia tensors, geometries and potential steps (tiny, huge, of either sign, hard cores).

use crate::common;
use crate::common::*;
use collide::{ConstraintSolver, Molecule, Outcome, Velocity, contact, spheres, terrace};
use glam::DVec3;
use proptest::prelude::*;

const TOL: f64 = 1e-12;
/// Atom masses in a molecule are `10^U(−SPREAD, SPREAD)`.
const SPREAD: f64 = 1.5;

fn neg(v: Velocity) -> Velocity {
    Velocity::new(-v.linear, -v.angular)
}

/// `|x_back − x| / (|x| + |x_after|)`, the round-off scale of the event for that vector.
fn reversal(x: DVec3, after: DVec3, back: DVec3) -> f64 {
    let scale = x.length() + after.length();
    let d = (back - x).length();
    if scale == 0.0 { d } else { d / scale }
}

/// Round-off in the reversed event is that of `S`: `κ` ulps from the approach rate `b` (its
/// condition number, see `approach_conditioning`), amplified by `sqrt(1 + |ΔV|/K_n)` when the
/// reversed event recovers `b` from `b' = ±sqrt(b² − 4aΔV)` (`K_n` the kinetic energy of the
/// motion along the impulse).
fn reversal_tolerance(applied: f64, k_n: f64, kappa: f64) -> f64 {
    let amplification = if applied == 0.0 {
        1.0
    } else {
        (1.0 + applied.abs() / k_n).sqrt()
    };
    TOL * kappa * amplification
}

/// Whether the reversed event is resolved in floating point. Crossing back out of a well needs
/// the pre-event normal kinetic energy `K_n`, recovered from the post-event `K_n + |ΔV|` with an
/// error of `κ` ulps of it; when `K_n` is below that round-off, the reversed event is a tie and
/// reflects by design (see `energy::THRESHOLD_ULPS`). Reversal is checked when the step is at
/// most 10⁹ times `K_n` (the validation example reports how often larger ratios occur).
fn reversible(applied: f64, k_n: f64) -> bool {
    k_n >= 1e-9 * applied.abs()
}

fn kind(i: usize) -> Kind {
    KINDS[i % 3]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(384))]

    #[test]
    fn spheres_conserve_and_reverse(
        seed: u64, log_ratio in -6.0f64..6.0, class in 0..DELTA_V_CLASSES,
    ) {
        let mut r = rng(seed);
        let si = Spec::random(&mut r, Kind::Particle, 1.0);
        let sj = Spec::random(&mut r, Kind::Particle, 10f64.powf(log_ratio));
        let (vi, vj) = (si.random_velocity(&mut r), sj.random_velocity(&mut r));
        let pos_j = cube(&mut r, 10.0);
        let r_ij = unit(&mut r) * uniform(&mut r, 0.5, 2.0);
        let pos_i = pos_j + r_ij;
        let before = Totals::of_bodies(&[(&si, pos_i, vi), (&sj, pos_j, vj)]);
        let dv = delta_v(class, before.energy);
        let (pi, pj) = (collide::Particle::new(si.mass).unwrap(), collide::Particle::new(sj.mass).unwrap());
        let out = spheres(&pi, &pj, vi.linear, vj.linear, r_ij, dv).unwrap();
        let (ai, aj) = (Velocity::new(out.i, DVec3::ZERO), Velocity::new(out.j, DVec3::ZERO));
        let after = Totals::of_bodies(&[(&si, pos_i, ai), (&sj, pos_j, aj)]);
        let e = Errors::between(&before, &after, out.impulse.delta_v);
        prop_assert!(e.worst() <= TOL, "{e:?} dv={dv} {:?}", out.impulse);

        let items = [(si.mass, si.inertia(), vi, ai), (sj.mass, sj.inertia(), vj, aj)];
        let (k_n, kappa) = (normal_energy(&items), approach_conditioning(&items));
        if !reversible(out.impulse.delta_v, k_n) {
            return Ok(());
        }
        let crossed = out.impulse.outcome == Outcome::Crossed;
        let back = spheres(&pi, &pj, -out.i, -out.j, r_ij,
            reverse_delta_v(dv, out.impulse.delta_v, crossed)).unwrap();
        prop_assert_eq!(back.impulse.outcome, out.impulse.outcome);
        let tol = reversal_tolerance(out.impulse.delta_v, k_n, kappa);
        let worst = reversal(vi.linear, out.i, -back.i).max(reversal(vj.linear, out.j, -back.j));
        prop_assert!(worst <= tol, "reversal {worst:e} > {tol:e}");
    }

    #[test]
    fn terrace_rule_conserves_and_reverses(
        seed: u64, ki in 0usize..3, kj in 0usize..3, log_ratio in -6.0f64..6.0,
        class in 0..DELTA_V_CLASSES,
    ) {
        let mut r = rng(seed);
        let si = Spec::random(&mut r, kind(ki), 1.0);
        let sj = Spec::random(&mut r, kind(kj), 10f64.powf(log_ratio));
        let (vi, vj) = (si.random_velocity(&mut r), sj.random_velocity(&mut r));
        let pos_j = cube(&mut r, 10.0);
        let r_ij = unit(&mut r) * uniform(&mut r, 0.5, 3.0);
        let pos_i = pos_j + r_ij;
        let push = potential_push(&mut r, &si, &sj, r_ij);
        prop_assert!(push.torque_imbalance(r_ij) < 1e-14);
        let before = Totals::of_bodies(&[(&si, pos_i, vi), (&sj, pos_j, vj)]);
        let dv = delta_v(class, before.energy);
        let (bi, bj) = (si.body(), sj.body());
        let out = terrace(&bi, &bj, vi, vj, &push, dv).unwrap();
        let after = Totals::of_bodies(&[(&si, pos_i, out.i), (&sj, pos_j, out.j)]);
        let e = Errors::between(&before, &after, out.impulse.delta_v);
        prop_assert!(e.worst() <= TOL, "{e:?} dv={dv} {:?}", out.impulse);
        // A linear body keeps its angular velocity perpendicular to its axis.
        for (spec, v) in [(&si, out.i), (&sj, out.j)] {
            if spec.kind == Kind::Linear {
                prop_assert!(v.angular.dot(spec.axis()).abs() <= 1e-12 * v.angular.length());
            }
        }

        let items = [(si.mass, si.inertia(), vi, out.i), (sj.mass, sj.inertia(), vj, out.j)];
        let (k_n, kappa) = (normal_energy(&items), approach_conditioning(&items));
        if !reversible(out.impulse.delta_v, k_n) {
            return Ok(());
        }
        let crossed = out.impulse.outcome == Outcome::Crossed;
        let back = terrace(&bi, &bj, neg(out.i), neg(out.j), &push,
            reverse_delta_v(dv, out.impulse.delta_v, crossed)).unwrap();
        prop_assert_eq!(back.impulse.outcome, out.impulse.outcome);
        let tol = reversal_tolerance(out.impulse.delta_v, k_n, kappa);
        let worst = reversal(vi.linear, out.i.linear, -back.i.linear)
            .max(reversal(vi.angular, out.i.angular, -back.i.angular))
            .max(reversal(vj.linear, out.j.linear, -back.j.linear))
            .max(reversal(vj.angular, out.j.angular, -back.j.angular));
        prop_assert!(worst <= tol, "reversal {worst:e} > {tol:e}");
    }

    #[test]
    fn contact_rule_conserves_and_reverses(
        seed: u64, ki in 0usize..3, kj in 0usize..3, log_ratio in -6.0f64..6.0,
        class in 0..DELTA_V_CLASSES,
    ) {
        let mut r = rng(seed);
        let si = Spec::random(&mut r, kind(ki), 1.0);
        let sj = Spec::random(&mut r, kind(kj), 10f64.powf(log_ratio));
        let (vi, vj) = (si.random_velocity(&mut r), sj.random_velocity(&mut r));
        let (pos_i, pos_j, at) = contact_geometry(&mut r, &si, &sj);
        let before = Totals::of_bodies(&[(&si, pos_i, vi), (&sj, pos_j, vj)]);
        let dv = delta_v(class, before.energy);
        let (bi, bj) = (si.body(), sj.body());
        let out = contact(&bi, &bj, vi, vj, &at, dv).unwrap();
        let after = Totals::of_bodies(&[(&si, pos_i, out.i), (&sj, pos_j, out.j)]);
        let e = Errors::between(&before, &after, out.impulse.delta_v);
        prop_assert!(e.worst() <= TOL, "{e:?} dv={dv} {:?}", out.impulse);

        let items = [(si.mass, si.inertia(), vi, out.i), (sj.mass, sj.inertia(), vj, out.j)];
        let (k_n, kappa) = (normal_energy(&items), approach_conditioning(&items));
        if !reversible(out.impulse.delta_v, k_n) {
            return Ok(());
        }
        let crossed = out.impulse.outcome == Outcome::Crossed;
        let back = contact(&bi, &bj, neg(out.i), neg(out.j), &at,
            reverse_delta_v(dv, out.impulse.delta_v, crossed)).unwrap();
        prop_assert_eq!(back.impulse.outcome, out.impulse.outcome);
        let tol = reversal_tolerance(out.impulse.delta_v, k_n, kappa);
        let worst = reversal(vi.linear, out.i.linear, -back.i.linear)
            .max(reversal(vi.angular, out.i.angular, -back.i.angular))
            .max(reversal(vj.linear, out.j.linear, -back.j.linear))
            .max(reversal(vj.angular, out.j.angular, -back.j.angular));
        prop_assert!(worst <= tol, "reversal {worst:e} > {tol:e}");
    }

    #[test]
    fn constrained_rule_conserves_keeps_constraints_and_reverses(
        seed: u64, shape_i in 0usize..5, shape_j in 0usize..5, within: bool,
        log_ratio in -4.5f64..4.5, class in 0..DELTA_V_CLASSES,
    ) {
        // Atom masses within a molecule span 10³ (a light atom held by heavy ones loses about
        // log10 of that ratio in digits of its constraint velocities, see VALIDATION.md);
        // the second molecule is scaled by up to 10^±4.5, for molecular mass ratios up to 10⁶.
        let mut r = rng(seed);
        let make = |r: &mut common::Rng, shape: usize| match shape {
            0 => chain(r, 1, SPREAD),
            1 => diatomic(r, SPREAD),
            2 => triatomic(r, SPREAD),
            3 => tetrahedron(r, SPREAD),
            _ => chain(r, 5, SPREAD),
        };
        let mut solver = ConstraintSolver::new();
        if within {
            // An intramolecular collision between the ends of a semi-flexible chain.
            let mol = chain(&mut r, 3 + shape_i, SPREAD);
            let com = cube(&mut r, 10.0);
            let pos: Vec<DVec3> = mol.offsets.iter().map(|d| com + *d).collect();
            let (lin, ang) = (cube(&mut r, 1.0), cube(&mut r, 1.0));
            let mut vel = mol.velocities(&mut r, lin, ang);
            let v0 = vel.clone();
            let before = Totals::of_atoms(&mol.masses, &pos, &vel);
            let dv = delta_v(class, before.energy);
            let last = mol.masses.len() - 1;
            let imp = solver.within(Molecule { masses: &mol.masses, positions: &pos,
                velocities: &mut vel, bonds: &mol.bonds }, 0, last, dv).unwrap();
            let after = Totals::of_atoms(&mol.masses, &pos, &vel);
            let e = Errors::between(&before, &after, imp.delta_v);
            prop_assert!(e.worst() <= TOL, "{e:?} dv={dv} {imp:?}");
            prop_assert!(mol.constraint_violation(&v0) <= TOL);
            prop_assert!(mol.constraint_violation(&vel) <= TOL, "{}", mol.constraint_violation(&vel));
            let k_n = normal_energy_atoms(&[&mol.masses], &[&v0], &[&vel]);
            let kappa = approach_conditioning_atoms(&[&mol.masses], &[&v0], &[&vel]);
            if !reversible(imp.delta_v, k_n) {
                return Ok(());
            }
            let v1 = vel.clone();
            for v in vel.iter_mut() { *v = -*v; }
            let crossed = imp.outcome == Outcome::Crossed;
            let back = solver.within(Molecule { masses: &mol.masses, positions: &pos, velocities: &mut vel,
                bonds: &mol.bonds }, 0, last, reverse_delta_v(dv, imp.delta_v, crossed)).unwrap();
            prop_assert_eq!(back.outcome, imp.outcome);
            let tol = reversal_tolerance(imp.delta_v, k_n, kappa);
            for k in 0..vel.len() {
                prop_assert!(reversal(v0[k], v1[k], -vel[k]) <= tol, "atom {k}: {:e} > {tol:e}; v0 {:?} v1 {:?} back {:?} m {:?} imp {imp:?}", reversal(v0[k], v1[k], -vel[k]), v0, v1, vel, mol.masses);
            }
            return Ok(());
        }
        let (mi, mj) = (make(&mut r, shape_i), make(&mut r, shape_j).scaled(10f64.powf(log_ratio)));
        let ai = pick(&mut r, mi.masses.len());
        let aj = pick(&mut r, mj.masses.len());
        let com_i = cube(&mut r, 10.0);
        let pos_i: Vec<DVec3> = mi.offsets.iter().map(|d| com_i + *d).collect();
        let site_j = pos_i[ai] - unit(&mut r) * uniform(&mut r, 0.5, 2.0);
        let com_j = site_j - mj.offsets[aj];
        let pos_j: Vec<DVec3> = mj.offsets.iter().map(|d| com_j + *d).collect();
        let wi = cube(&mut r, 1.0);
        let wj = cube(&mut r, 1.0);
        let lin_i = cube(&mut r, 1.0 / mi.total_mass().sqrt());
        let lin_j = cube(&mut r, 1.0 / mj.total_mass().sqrt());
        let mut vel_i = mi.velocities(&mut r, lin_i, wi);
        let mut vel_j = mj.velocities(&mut r, lin_j, wj);
        let (v0i, v0j) = (vel_i.clone(), vel_j.clone());
        let before = Totals::of_atoms(&mi.masses, &pos_i, &vel_i)
            .merge(Totals::of_atoms(&mj.masses, &pos_j, &vel_j));
        let dv = delta_v(class, before.energy);
        let imp = solver.between(
            Molecule { masses: &mi.masses, positions: &pos_i, velocities: &mut vel_i, bonds: &mi.bonds }, ai,
            Molecule { masses: &mj.masses, positions: &pos_j, velocities: &mut vel_j, bonds: &mj.bonds }, aj,
            dv).unwrap();
        let after = Totals::of_atoms(&mi.masses, &pos_i, &vel_i)
            .merge(Totals::of_atoms(&mj.masses, &pos_j, &vel_j));
        let e = Errors::between(&before, &after, imp.delta_v);
        prop_assert!(e.worst() <= TOL, "{e:?} dv={dv} {imp:?}");
        for (mol, v0, v1) in [(&mi, &v0i, &vel_i), (&mj, &v0j, &vel_j)] {
            prop_assert!(mol.constraint_violation(v0) <= TOL);
            prop_assert!(mol.constraint_violation(v1) <= TOL, "{}", mol.constraint_violation(v1));
        }
        let k_n = normal_energy_atoms(
            &[&mi.masses, &mj.masses], &[&v0i, &v0j], &[&vel_i, &vel_j]);
        let kappa = approach_conditioning_atoms(
            &[&mi.masses, &mj.masses], &[&v0i, &v0j], &[&vel_i, &vel_j]);
        if !reversible(imp.delta_v, k_n) {
            return Ok(());
        }
        let (v1i, v1j) = (vel_i.clone(), vel_j.clone());
        for v in vel_i.iter_mut().chain(vel_j.iter_mut()) { *v = -*v; }
        let crossed = imp.outcome == Outcome::Crossed;
        let back = solver.between(
            Molecule { masses: &mi.masses, positions: &pos_i, velocities: &mut vel_i, bonds: &mi.bonds }, ai,
            Molecule { masses: &mj.masses, positions: &pos_j, velocities: &mut vel_j, bonds: &mj.bonds }, aj,
            reverse_delta_v(dv, imp.delta_v, crossed)).unwrap();
        prop_assert_eq!(back.outcome, imp.outcome);
        let tol = reversal_tolerance(imp.delta_v, k_n, kappa);
        for (v0, v1, vb) in [(&v0i, &v1i, &vel_i), (&v0j, &v1j, &vel_j)] {
            for k in 0..v0.len() {
                prop_assert!(reversal(v0[k], v1[k], -vb[k]) <= tol, "{:e}", reversal(v0[k], v1[k], -vb[k]));
            }
        }
    }
}
