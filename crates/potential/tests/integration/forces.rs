//! Forces and torques of every potential against finite differences of its energy, the
//! angular-momentum balance (003 Eq. 6), invariances, the pair symmetry, and `U̇` (003 Eq. 12).

use crate::common::*;
use glam::{DQuat, DVec3};
use potential::{LennardJones, LjRod, PairGeometry, PairPotential};

const SAMPLES: usize = 2000;

#[test]
fn forces_and_torques_match_finite_differences() {
    for (c, case) in cases().iter().enumerate() {
        let mut r = rng(1000 + c as u64);
        let mut worst = FdErrors::default();
        let mut n = 0;
        for _ in 0..SAMPLES {
            let g = draw(case, &mut r);
            if let Some(e) = fd_errors(case.potential.as_ref(), &g) {
                worst = worst.max(e);
                n += 1;
            }
        }
        assert!(
            n > SAMPLES / 2,
            "{}: only {n} geometries evaluated",
            case.name
        );
        assert!(
            worst.force <= 1e-7,
            "{}: force {:e}",
            case.name,
            worst.force
        );
        assert!(
            worst.torque_i <= 1e-7,
            "{}: τ_ij {:e}",
            case.name,
            worst.torque_i
        );
        assert!(
            worst.torque_j <= 1e-7,
            "{}: τ_ji {:e}",
            case.name,
            worst.torque_j
        );
        assert!(
            worst.balance <= 1e-12,
            "{}: Eq. 6 {:e}",
            case.name,
            worst.balance
        );
    }
}

#[test]
fn torque_about_a_random_axis_is_minus_the_rotation_derivative() {
    // dU = −τ·n δθ for a rotation of one body's axis by δθ about n.
    for (c, case) in cases().iter().enumerate() {
        let p = case.potential.as_ref();
        let mut r = rng(2000 + c as u64);
        for _ in 0..100 {
            let g = draw(case, &mut r);
            let Ok(e) = p.evaluate(&g) else { continue };
            let floor = FD_FLOOR * round_off_scale(p, &g, &e);
            for (body, tau) in [(0, e.torque_i), (1, e.torque_j)] {
                let n = unit(&mut r);
                let du = derivative(|a| p.energy(&turned(&g, body, n, a)), FD_STEP);
                let err = (du + tau.dot(n)).abs() / tau.length().max(floor);
                assert!(err < 1e-7, "{}: body {body}: {err:e}", case.name);
            }
        }
    }
}

#[test]
fn energy_is_invariant_and_forces_rotate_with_the_pair() {
    for (c, case) in cases().iter().enumerate() {
        let p = case.potential.as_ref();
        let mut r = rng(3000 + c as u64);
        for _ in 0..100 {
            let g = draw(case, &mut r);
            let Ok(e) = p.evaluate(&g) else { continue };
            let q = DQuat::from_axis_angle(unit(&mut r), uniform(&mut r, 0.0, 6.0));
            let turned = PairGeometry::new(q * g.r_ij, q * g.s_i, q * g.s_j);
            let f = p.evaluate(&turned).unwrap();
            let scale = e.energy.abs() + p.minimum().abs();
            assert!(
                (f.energy - e.energy).abs() < 1e-12 * scale,
                "{}: rotation",
                case.name
            );
            let fs = e.force.length().max(1e-6 * scale);
            assert!(
                (f.force - q * e.force).length() < 1e-11 * fs,
                "{}",
                case.name
            );
            let ts = (e.torque_i.length() + e.torque_j.length()).max(1e-6 * scale);
            assert!(
                (f.torque_i - q * e.torque_i).length() < 1e-11 * ts,
                "{}",
                case.name
            );
            assert!(
                (f.torque_j - q * e.torque_j).length() < 1e-11 * ts,
                "{}",
                case.name
            );
            // Translating both bodies changes r_ij only by the round-off of the subtraction.
            let shift = unit(&mut r) * uniform(&mut r, 1.0, 100.0);
            let (ri, rj) = (shift + g.r_ij, shift);
            let moved = PairGeometry::new(ri - rj, g.s_i, g.s_j);
            let u = p.energy(&moved);
            assert!(
                (u - e.energy).abs() < 1e-10 * scale,
                "{}: translation",
                case.name
            );
        }
    }
}

#[test]
fn the_pair_seen_from_j_has_opposite_force_and_exchanged_torques() {
    for (c, case) in cases().iter().enumerate() {
        let p = case.potential.as_ref();
        let mut r = rng(4000 + c as u64);
        for _ in 0..100 {
            let g = draw(case, &mut r);
            let Ok(e) = p.evaluate(&g) else { continue };
            let s = p.evaluate(&g.swapped()).unwrap();
            let scale = e.force.length() + e.torque_i.length() + e.torque_j.length();
            assert!((s.energy - e.energy).abs() <= 1e-14 * e.energy.abs().max(1.0));
            assert!(
                (s.force + e.force).length() <= 1e-13 * scale,
                "{}",
                case.name
            );
            assert!(
                (s.torque_i - e.torque_j).length() <= 1e-13 * scale,
                "{}",
                case.name
            );
            assert!(
                (s.torque_j - e.torque_i).length() <= 1e-13 * scale,
                "{}",
                case.name
            );
        }
    }
}

#[test]
fn energy_rate_matches_the_derivative_along_a_moving_rotating_pair() {
    // 003 Eq. 12: U̇ = −F·v_ij − τ_ij·ω_i − τ_ji·ω_j along r_ij(t) = r_ij + v t and axes
    // turning at constant angular velocities.
    for (c, case) in cases().iter().enumerate() {
        let p = case.potential.as_ref();
        let mut r = rng(5000 + c as u64);
        for _ in 0..100 {
            let g = draw(case, &mut r);
            let Ok(e) = p.evaluate(&g) else { continue };
            let l = p.length_scale();
            let v = unit(&mut r) * uniform(&mut r, 0.1, 2.0) * l;
            let (wi, wj) = (
                unit(&mut r) * uniform(&mut r, 0.1, 3.0),
                unit(&mut r) * uniform(&mut r, 0.1, 3.0),
            );
            let at = |t: f64| {
                let turn = |w: DVec3, s: DVec3| {
                    if w == DVec3::ZERO {
                        s
                    } else {
                        rotate(s, w.normalize(), w.length() * t)
                    }
                };
                p.energy(&PairGeometry::new(
                    g.r_ij + v * t,
                    turn(wi, g.s_i),
                    turn(wj, g.s_j),
                ))
            };
            let fd = derivative(at, FD_STEP);
            let rate = e.rate(v, wi, wj);
            let scale = e.force.length() * v.length()
                + e.torque_i.length() * wi.length()
                + e.torque_j.length() * wj.length();
            let floor = FD_FLOOR * round_off_scale(p, &g, &e);
            let err = (rate - fd).abs() / scale.max(floor);
            assert!(err < 1e-7, "{}: U̇ {rate} vs {fd} ({err:e})", case.name);
        }
    }
}

#[test]
fn rod_torque_is_perpendicular_to_the_rod() {
    // 003 after Eq. 24: τ_ij ⊥ s_i, so the spin about the long axis is conserved.
    let rod = LjRod::paper();
    let mut r = rng(6);
    for _ in 0..1000 {
        let (n, si, sj) = (unit(&mut r), unit(&mut r), unit(&mut r));
        let g = PairGeometry::new(n * uniform(&mut r, 3.0, 9.0), si, sj);
        let e = rod.evaluate(&g).unwrap();
        let t = e.torque_i.length();
        assert!(e.torque_i.dot(si).abs() <= 1e-15 * t.max(f64::MIN_POSITIVE));
        assert!(e.torque_j.dot(sj).abs() <= 1e-15 * t.max(f64::MIN_POSITIVE));
        assert_eq!(e.torque_i, -e.torque_j);
    }
}

#[test]
fn rods_with_zero_zeta_are_lennard_jones_to_the_last_bit() {
    let rod = LjRod::new(1.7, 1.3, 0.0).unwrap();
    let lj = LennardJones::new(1.7, 1.3).unwrap();
    assert!(!rod.depends_on_orientation());
    let mut r = rng(7);
    for _ in 0..2000 {
        let g = PairGeometry::new(
            unit(&mut r) * uniform(&mut r, 0.9, 5.0),
            unit(&mut r),
            unit(&mut r),
        );
        let (a, b) = (rod.evaluate(&g).unwrap(), lj.evaluate(&g).unwrap());
        assert_eq!(a, b);
        assert_eq!(rod.energy(&g), lj.energy(&g));
        assert_eq!(rod.energy(&g), a.energy);
    }
    assert_eq!(rod.reach(-0.3).unwrap(), lj.reach(-0.3).unwrap());
}

#[test]
fn smoothed_energy_and_force_are_continuous_at_both_knots() {
    // 003 Eq. 26: g and g' are continuous at r_l and r_u, so U and F are. Across a knot at
    // distance δ the jump must be O(δ) (here δ = 1e-9 of the knot), not O(1).
    let rod = LjRod::paper();
    let smooth_rod = potential::Smoothed::paper(rod, rod.sigma()).unwrap();
    let smooth_gb = potential::Smoothed::new(potential::GayBerne::default(), 3.5, 4.5).unwrap();
    let gb = potential::GayBerne::default();
    let list: [(&dyn PairPotential, &dyn PairPotential, [f64; 2]); 2] = [
        (&smooth_rod, &rod, [2.5 * rod.sigma(), 3.0 * rod.sigma()]),
        (&smooth_gb, &gb, [3.5, 4.5]),
    ];
    let mut r = rng(8);
    for (p, inner, knots) in list {
        for _ in 0..200 {
            let (n, si, sj) = (unit(&mut r), unit(&mut r), unit(&mut r));
            for k in knots {
                let d = 1e-9 * k;
                let at = |x: f64| p.evaluate(&PairGeometry::new(n * x, si, sj)).unwrap();
                let (a, b) = (at(k - d), at(k + d));
                // Scales from the unsmoothed potential at the knot (the smoothed one vanishes
                // at r_u).
                let e = inner.evaluate(&PairGeometry::new(n * k, si, sj)).unwrap();
                let scale = e.energy.abs() + k * e.force.length();
                assert!(
                    (a.energy - b.energy).abs() <= 1e-7 * scale,
                    "U jumps at {k}"
                );
                let fs = e.force.length() + e.energy.abs() / k;
                assert!((a.force - b.force).length() <= 1e-6 * fs, "F jumps at {k}");
                let ts = e.torque_i.length() + e.energy.abs();
                assert!(
                    (a.torque_i - b.torque_i).length() <= 1e-6 * ts,
                    "τ jumps at {k}"
                );
            }
            // Beyond r_u: exactly zero, force and torques too.
            let far = p
                .evaluate(&PairGeometry::new(n * knots[1] * 1.0001, si, sj))
                .unwrap();
            assert_eq!(far, potential::PairEval::default());
        }
    }
}
