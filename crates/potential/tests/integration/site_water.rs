//! Site–site rigid molecules ([`SiteSite`]): SPC/E water with Lennard-Jones and damped shifted
//! force Coulomb terms. Force and torques against central finite differences of `energy` over
//! random poses, 003 Eq. 6, invariance under a common rotation, continuity at the site cut-off
//! and zero beyond the molecular one, a dimer energy by hand, and the bounds the terrace map
//! uses (minimum, reach) against sampled pairs.

use glam::{DQuat, DVec3};
use potential::site_site::{COULOMB, spc_e_sites};
use potential::{RigidGeometry, RigidPairPotential, SiteSite};
use proptest::prelude::*;

fn quat(a: [f64; 4]) -> Option<DQuat> {
    let q = DQuat::from_xyzw(a[0], a[1], a[2], a[3]);
    (q.length() > 0.1).then(|| q.normalize())
}

fn geometry(r: f64, dir: [f64; 3], a: [f64; 4], b: [f64; 4]) -> Option<RigidGeometry> {
    let d = DVec3::from(dir);
    if d.length() < 0.1 {
        return None;
    }
    Some(RigidGeometry::new(r * d.normalize(), quat(a)?, quat(b)?))
}

/// Central differences of `energy`: force, torque on i, torque on j (a torque is minus the
/// derivative with respect to a rotation of its body about a lab axis).
fn finite_differences(p: &SiteSite, g: &RigidGeometry, h: f64) -> [DVec3; 3] {
    let mut out = [DVec3::ZERO; 3];
    let u = |g: RigidGeometry| p.energy(&g);
    for (k, e) in DVec3::AXES.into_iter().enumerate() {
        let (mut plus, mut minus) = (*g, *g);
        plus.r_ij += h * e;
        minus.r_ij -= h * e;
        out[0][k] = -(u(plus) - u(minus)) / (2.0 * h);
        let turn = |q: DQuat, s: f64| DQuat::from_axis_angle(e, s * h) * q;
        let (mut plus, mut minus) = (*g, *g);
        plus.q_i = turn(g.q_i, 1.0);
        minus.q_i = turn(g.q_i, -1.0);
        out[1][k] = -(u(plus) - u(minus)) / (2.0 * h);
        let (mut plus, mut minus) = (*g, *g);
        plus.q_j = turn(g.q_j, 1.0);
        minus.q_j = turn(g.q_j, -1.0);
        out[2][k] = -(u(plus) - u(minus)) / (2.0 * h);
    }
    out
}

/// The oxygens' distance of a pair (the Lennard-Jones site).
fn oo(g: &RigidGeometry) -> f64 {
    let o = spc_e_sites()[0].position;
    (g.r_ij + g.q_i * o - g.q_j * o).length()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Force = −∂U/∂r and torque = −∂U/∂angle, by central differences, over random poses from
    /// contact to beyond the cut-off (where both vanish).
    #[test]
    fn force_and_torques_are_derivatives_of_the_energy(
        r in 2.2f64..11.5,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform4(-1.0f64..1.0),
        b in prop::array::uniform4(-1.0f64..1.0),
    ) {
        let w = SiteSite::spc_e();
        let Some(g) = geometry(r, dir, a, b) else { return Ok(()) };
        // Hydrogens pulled onto an oxygen: the energy is steep there, not wrong.
        prop_assume!(oo(&g) > 2.2);
        let e = w.evaluate(&g).unwrap();
        prop_assume!(e.energy.abs() < 500.0);
        prop_assert_eq!(e.energy, w.energy(&g));
        let fd = finite_differences(&w, &g, 1e-6);
        let exact = [e.force, e.torque_i, e.torque_j];
        for k in 0..3 {
            let err = (fd[k] - exact[k]).length() / (1.0 + exact[k].length());
            prop_assert!(err < 1e-6, "{k}: fd {} exact {} ({g:?})", fd[k], exact[k]);
        }
        // 003 Eq. 6: the torques balance the force's moment.
        let scale = 1.0 + e.force.length() * r;
        prop_assert!(e.torque_imbalance(g.r_ij) < 1e-12 * scale);
        // The reach bounds every level the pair sits at.
        if e.energy != 0.0 {
            prop_assert!(r <= w.reach(e.energy).unwrap() * (1.0 + 1e-12));
            prop_assert!(e.energy >= w.minimum());
        } else {
            prop_assert_eq!(e.force, DVec3::ZERO);
        }
    }

    /// A common rotation of both molecules and their separation leaves the energy alone and
    /// turns force and torques with it.
    #[test]
    fn invariant_under_a_common_rotation(
        r in 2.6f64..10.5,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform4(-1.0f64..1.0),
        b in prop::array::uniform4(-1.0f64..1.0),
        c in prop::array::uniform4(-1.0f64..1.0),
    ) {
        let w = SiteSite::spc_e();
        let (Some(g), Some(rot)) = (geometry(r, dir, a, b), quat(c)) else { return Ok(()) };
        prop_assume!(oo(&g) > 2.2);
        let e = w.evaluate(&g).unwrap();
        let t = w.evaluate(&g.rotated(rot)).unwrap();
        let tol = 1e-11 * (1.0 + e.energy.abs());
        prop_assert!((e.energy - t.energy).abs() < tol, "{} vs {}", e.energy, t.energy);
        for (x, y) in [(e.force, t.force), (e.torque_i, t.torque_i), (e.torque_j, t.torque_j)] {
            prop_assert!((rot * x - y).length() < 1e-10 * (1.0 + x.length()));
        }
        // Seen from the other molecule: the same energy, the force reversed.
        let s = w.evaluate(&g.swapped()).unwrap();
        prop_assert!((s.energy - e.energy).abs() < tol);
        prop_assert!((s.force + e.force).length() < 1e-10 * (1.0 + e.force.length()));
    }
}

/// The DSF Coulomb term of one site pair as FG06 Eq. 14 writes it, and shifted-force
/// Lennard-Jones, by hand (no code of the potential).
fn dsf(qq: f64, r: f64, alpha: f64, rc: f64) -> f64 {
    let erfc = |x: f64| libm::erfc(x);
    let slope = erfc(alpha * rc) / (rc * rc)
        + 2.0 * alpha / std::f64::consts::PI.sqrt() * (-(alpha * rc).powi(2)).exp() / rc;
    COULOMB * qq * (erfc(alpha * r) / r - erfc(alpha * rc) / rc + slope * (r - rc))
}

fn lj_sf(r: f64, rc: f64) -> f64 {
    let (s, e) = (3.166_f64, 0.650);
    let phi = |r: f64| 4.0 * e * ((s / r).powi(12) - (s / r).powi(6));
    let dphi = |r: f64| 4.0 * e * (-12.0 * s.powi(12) / r.powi(13) + 6.0 * s.powi(6) / r.powi(7));
    phi(r) - phi(rc) - dphi(rc) * (r - rc)
}

#[test]
fn parallel_dimer_by_hand() {
    // Both molecules in their body frames (yz plane), 3 Å apart along x: like sites face each
    // other at 3 Å, O–H at √(3² + 1²), H–H' at √(3² + (2 · sin 54.735°)²).
    let w = SiteSite::spc_e();
    let (alpha, rc) = (0.2, 9.0);
    let (qo, qh) = (-0.8476, 0.4238);
    let d = 3.0;
    let hh = 2.0 * (0.5 * 109.47_f64.to_radians()).sin();
    let want = dsf(qo * qo, d, alpha, rc)
        + 2.0 * dsf(qh * qh, d, alpha, rc)
        + 2.0 * dsf(qh * qh, (d * d + hh * hh).sqrt(), alpha, rc)
        + 4.0 * dsf(qo * qh, (d * d + 1.0).sqrt(), alpha, rc)
        + lj_sf(d, rc);
    let g = RigidGeometry::new(DVec3::new(d, 0.0, 0.0), DQuat::IDENTITY, DQuat::IDENTITY);
    let e = w.evaluate(&g).unwrap();
    assert!(
        (e.energy - want).abs() < 1e-11 * want.abs(),
        "{} vs {want}",
        e.energy
    );
    // 13.506 286 921 69 kJ/mol from the same formulas in Python's math.erfc.
    assert!((e.energy - 13.506_286_921_69).abs() < 1e-9, "{}", e.energy);
    // The mirrors y → −y and x → d − x (which swaps the molecules): the force is along x,
    // the torques about y only, opposite (each dipole is turned towards the other's tilt).
    assert!(e.force.y.abs() < 1e-12 && e.force.z.abs() < 1e-12 && e.force.x > 0.0);
    let (ti, tj) = (e.torque_i, e.torque_j);
    assert!(ti.x.abs() < 1e-12 && ti.z.abs() < 1e-12 && ti.y.abs() > 1e-3);
    assert!((ti + tj).length() < 1e-12);
}

#[test]
fn continuous_at_the_site_cut_off_and_zero_beyond_the_molecular_one() {
    let w = SiteSite::spc_e();
    let rc = w.dsf().r_cut;
    // Parallel molecules along x: the O–O and both H–H pairs reach R_c together; the energy
    // goes to zero with its slope (second order in the distance to R_c).
    let at = |r: f64| {
        let g = RigidGeometry::new(DVec3::new(r, 0.0, 0.0), DQuat::IDENTITY, DQuat::IDENTITY);
        w.evaluate(&g).unwrap()
    };
    for h in [1e-3, 1e-5, 1e-7] {
        let inside = at(rc - h);
        assert!(inside.energy.abs() < 2.0 * h * h, "{h}: {}", inside.energy);
        assert!(inside.force.length() < 3.0 * h, "{h}: {}", inside.force);
    }
    // One pair crossing R_c on its own: turned molecules, the energy on both sides within the
    // force times the step.
    let q = DQuat::from_euler(glam::EulerRot::ZYX, 0.7, -0.4, 1.9);
    let g0 = RigidGeometry::new(DVec3::new(8.0, 2.0, -1.0), q, DQuat::IDENTITY);
    let sites = spc_e_sites();
    let mut crossings = 0;
    for a in &sites {
        for b in &sites {
            // Move along r̂ until this site pair is at R_c, then step across.
            let dir = g0.r_ij.normalize();
            let off = q * a.position - b.position;
            // |s dir + off| = R_c.
            let p = dir.dot(off);
            let s = -p + (p * p - off.length_squared() + rc * rc).sqrt();
            let e = |s: f64| w.energy(&RigidGeometry::new(s * dir, q, DQuat::IDENTITY));
            let (lo, hi) = (e(s - 1e-9), e(s + 1e-9));
            assert!((lo - hi).abs() < 1e-9, "{lo} {hi}");
            crossings += 1;
        }
    }
    assert_eq!(crossings, 9);
    let beyond = RigidGeometry::new(DVec3::new(w.cutoff(), 0.0, 0.0), q, DQuat::IDENTITY);
    assert_eq!(w.evaluate(&beyond).unwrap(), potential::PairEval::default());
    // The molecular cut-off is R_c plus the two longest arms (the hydrogens').
    let arm = sites[1].position.length();
    assert!((w.cutoff() - (rc + 2.0 * arm)).abs() < 1e-12);
}

#[test]
fn bounds_hold_on_sampled_pairs() {
    // Random pairs from 2.4 Å outwards: none below the minimum, none at a level beyond its
    // reach; the deepest sampled energy is a hydrogen-bonded dimer's order of magnitude.
    let w = SiteSite::spc_e();
    let mut x = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut lowest = f64::INFINITY;
    for _ in 0..20_000 {
        let r = 2.4 + 9.0 * (0.5 + 0.5 * next());
        let Some(g) = geometry(
            r,
            [next(), next(), next()],
            [next(), next(), next(), next()],
            [next(), next(), next(), next()],
        ) else {
            continue;
        };
        let u = w.energy(&g);
        lowest = lowest.min(u);
        assert!(u >= w.minimum());
        if u != 0.0 {
            assert!(r <= w.reach(u).unwrap() * (1.0 + 1e-12), "{r} {u}");
        }
    }
    assert!(lowest < -10.0 && lowest > -40.0, "{lowest}");
    assert!(w.minimum() < lowest);
}
