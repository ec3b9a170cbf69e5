//! Full-orientation pair potentials ([`RigidPairPotential`]): SSD/E water and the uniaxial
//! potentials through the [`Uniaxial`] adapter. Forces and torques against central finite
//! differences of `energy` (torques as minus the derivative with respect to a rotation of one
//! body about a lab axis), Newton's third law and 003 Eq. 6, rotational invariance, `U̇` along
//! free motion, the cut-off, the hydrogen-bond dimer by hand, the bounds the terrace map uses,
//! and near-contact / fast-spin extremes.

use glam::{DQuat, DVec3};
use potential::water::KCAL;
use potential::{
    GayBerne, LevelSet, LjRod, PairEval, PotentialError, RigidGeometry, RigidPairPotential,
    SoftStickyDipole, SsdParameters, TerraceOptions, Uniaxial,
};
use proptest::prelude::*;

/// A unit quaternion from four numbers (`None` if they are too close to zero to normalise).
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

/// Central differences of `energy`: (force, torque on i, torque on j).
fn finite_differences<P: RigidPairPotential>(p: &P, g: &RigidGeometry, h: f64) -> [DVec3; 3] {
    let mut out = [DVec3::ZERO; 3];
    #[allow(clippy::needless_range_loop)] // k indexes both the axes and the components
    for k in 0..3 {
        let e = DVec3::AXES[k];
        let u = |g: RigidGeometry| p.energy(&g);
        let mut plus = *g;
        let mut minus = *g;
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

/// The largest error of force and torques against finite differences, relative to
/// `1 + |exact|`.
fn fd_error<P: RigidPairPotential>(p: &P, g: &RigidGeometry) -> f64 {
    let e = p.evaluate(g).expect("outside the core");
    let fd = finite_differences(p, g, 1e-5);
    let exact = [e.force, e.torque_i, e.torque_j];
    (0..3)
        .map(|k| (fd[k] - exact[k]).length() / (1.0 + exact[k].length()))
        .fold(0.0, f64::max)
}

/// Both attitudes turned about their lab angular velocities for time `t`, centres moved
/// along `v_ij`.
fn flown(g: &RigidGeometry, v: DVec3, w_i: DVec3, w_j: DVec3, t: f64) -> RigidGeometry {
    RigidGeometry::new(
        g.r_ij + v * t,
        DQuat::from_scaled_axis(w_i * t) * g.q_i,
        DQuat::from_scaled_axis(w_j * t) * g.q_j,
    )
}

fn close(a: DVec3, b: DVec3, rel: f64) -> bool {
    (a - b).length() <= rel * (1.0 + a.length().max(b.length()))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn ssd_e_forces_and_torques_match_finite_differences(
        r in 2.4f64..9.2,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform4(-1.0f64..1.0),
        b in prop::array::uniform4(-1.0f64..1.0),
    ) {
        let Some(g) = geometry(r, dir, a, b) else { return Ok(()) };
        let err = fd_error(&SoftStickyDipole::ssd_e(), &g);
        prop_assert!(err < 2e-6, "r = {r}: relative error {err:e}");
    }

    #[test]
    fn uniaxial_adapter_torques_are_full_rotation_derivatives(
        r in 3.3f64..8.0,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform4(-1.0f64..1.0),
        b in prop::array::uniform4(-1.0f64..1.0),
    ) {
        let Some(g) = geometry(r, dir, a, b) else { return Ok(()) };
        let rod = Uniaxial(LjRod::paper());
        prop_assert!(fd_error(&rod, &g) < 1e-6);
        let gb = Uniaxial(GayBerne::default());
        let g = RigidGeometry::new(g.r_ij / 2.0, g.q_i, g.q_j); // GB's σ₀ = 1
        if gb.evaluate(&g).is_ok_and(|e| e.energy.abs() < 50.0) {
            prop_assert!(fd_error(&gb, &g) < 1e-6);
        }
    }

    #[test]
    fn newton_third_law_and_eq_6_to_round_off(
        r in 2.4f64..9.2,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform4(-1.0f64..1.0),
        b in prop::array::uniform4(-1.0f64..1.0),
    ) {
        let Some(g) = geometry(r, dir, a, b) else { return Ok(()) };
        let w = SoftStickyDipole::ssd_e();
        let e = w.evaluate(&g).unwrap();
        prop_assert!(e.torque_imbalance(g.r_ij) < 1e-14, "Eq. 6: {:e}", e.torque_imbalance(g.r_ij));
        // Seen from j: the same energy, the opposite force, the torques exchanged.
        let s = w.evaluate(&g.swapped()).unwrap();
        prop_assert!((s.energy - e.energy).abs() <= 1e-13 * (1.0 + e.energy.abs()));
        prop_assert!(close(s.force, -e.force, 1e-13));
        prop_assert!(close(s.torque_i, e.torque_j, 1e-13));
        prop_assert!(close(s.torque_j, e.torque_i, 1e-13));
    }

    #[test]
    fn turning_the_whole_pair_changes_nothing_but_the_frame(
        r in 2.4f64..9.2,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform4(-1.0f64..1.0),
        b in prop::array::uniform4(-1.0f64..1.0),
        c in prop::array::uniform4(-1.0f64..1.0),
    ) {
        let (Some(g), Some(rot)) = (geometry(r, dir, a, b), quat(c)) else { return Ok(()) };
        let w = SoftStickyDipole::ssd_e();
        let e = w.evaluate(&g).unwrap();
        let t = w.evaluate(&g.rotated(rot)).unwrap();
        prop_assert!((t.energy - e.energy).abs() <= 1e-12 * (1.0 + e.energy.abs()));
        prop_assert!(close(t.force, rot * e.force, 1e-12));
        prop_assert!(close(t.torque_i, rot * e.torque_i, 1e-12));
        prop_assert!(close(t.torque_j, rot * e.torque_j, 1e-12));
    }

    #[test]
    fn rate_matches_the_derivative_along_free_motion(
        r in 2.4f64..9.2,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform4(-1.0f64..1.0),
        b in prop::array::uniform4(-1.0f64..1.0),
        v in prop::array::uniform3(-10.0f64..10.0),
        wi in prop::array::uniform3(-30.0f64..30.0),
        wj in prop::array::uniform3(-30.0f64..30.0),
    ) {
        let Some(g) = geometry(r, dir, a, b) else { return Ok(()) };
        let w = SoftStickyDipole::ssd_e();
        let (v, wi, wj) = (DVec3::from(v), DVec3::from(wi), DVec3::from(wj));
        let rate = w.evaluate(&g).unwrap().rate(v, wi, wj);
        let h = 1e-7;
        let fd = (w.energy(&flown(&g, v, wi, wj, h)) - w.energy(&flown(&g, v, wi, wj, -h)))
            / (2.0 * h);
        prop_assert!((fd - rate).abs() <= 1e-5 * (1.0 + rate.abs()), "{fd} vs {rate}");
    }

    #[test]
    fn never_nan_near_contact_or_at_any_distance(
        log_r in -320.0f64..1.0,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform4(-1.0f64..1.0),
        b in prop::array::uniform4(-1.0f64..1.0),
    ) {
        let Some(g) = geometry(10f64.powf(log_r), dir, a, b) else { return Ok(()) };
        let w = SoftStickyDipole::ssd_e();
        let u = w.energy(&g);
        prop_assert!(!u.is_nan());
        prop_assert!(u >= w.minimum());
        match w.evaluate(&g) {
            Ok(e) => {
                prop_assert!(e.is_finite());
                prop_assert_eq!(e.energy, u);
            }
            Err(PotentialError::Overlap { .. }) => prop_assert_eq!(u, f64::INFINITY),
            Err(other) => prop_assert!(false, "{other}"),
        }
    }

    #[test]
    fn the_bounds_hold_for_random_pairs(
        r in 2.2f64..9.5,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform4(-1.0f64..1.0),
        b in prop::array::uniform4(-1.0f64..1.0),
    ) {
        let Some(g) = geometry(r, dir, a, b) else { return Ok(()) };
        let w = SoftStickyDipole::ssd_e();
        let u = w.energy(&g);
        prop_assert!(u >= w.minimum());
        // Reach: a pair at distance r can only be at or beyond a level it reaches.
        if u < 0.0 {
            prop_assert!(r <= w.reach(u).unwrap());
        } else if u > 0.0 {
            prop_assert!(r <= w.reach(u).unwrap());
        }
    }
}

#[test]
fn fast_spin_and_near_contact_rates_stay_finite_and_right() {
    let w = SoftStickyDipole::ssd_e();
    let g = RigidGeometry::new(
        DVec3::new(0.3, -2.0, 1.2),
        DQuat::from_rotation_x(0.3),
        DQuat::from_rotation_y(2.0),
    );
    for spin in [1e2, 1e4, 1e6] {
        let (wi, wj) = (
            DVec3::new(1.0, 2.0, -0.5) * spin,
            DVec3::new(-0.3, 0.1, 1.0) * spin,
        );
        let v = DVec3::new(3.0, 1.0, -2.0);
        let rate = w.evaluate(&g).unwrap().rate(v, wi, wj);
        assert!(rate.is_finite());
        let h = 1e-4 / spin;
        let fd =
            (w.energy(&flown(&g, v, wi, wj, h)) - w.energy(&flown(&g, v, wi, wj, -h))) / (2.0 * h);
        assert!(
            (fd - rate).abs() <= 1e-6 * rate.abs(),
            "spin {spin}: {fd} {rate}"
        );
    }
    // Deep inside the core: an overlap error, never NaN; the centres coinciding too.
    for r in [1e-200, 1e-40, 1e-3, 0.5, 1.0] {
        let g = RigidGeometry::new(DVec3::new(r, 0.0, 0.0), DQuat::IDENTITY, DQuat::IDENTITY);
        match w.evaluate(&g) {
            Ok(e) => assert!(e.is_finite() && e.energy > 0.0, "r = {r}"),
            Err(e) => assert!(matches!(e, PotentialError::Overlap { .. }), "{e}"),
        }
        assert!(w.energy(&g) > 0.0);
    }
    let g = RigidGeometry::new(DVec3::ZERO, DQuat::IDENTITY, DQuat::IDENTITY);
    assert_eq!(w.energy(&g), f64::INFINITY);
    let g = RigidGeometry::new(DVec3::X * f64::NAN, DQuat::IDENTITY, DQuat::IDENTITY);
    assert!(w.energy(&g).is_nan());
    assert!(matches!(w.evaluate(&g), Err(PotentialError::NotFinite(_))));
}

#[test]
fn energy_vanishes_at_the_cutoff_continuously() {
    let w = SoftStickyDipole::ssd_e();
    let (q_i, q_j) = (DQuat::from_rotation_x(0.2), DQuat::from_rotation_y(-0.7));
    let at = |r: f64| w.evaluate(&RigidGeometry::new(DVec3::new(0.0, 0.6, 0.8) * r, q_i, q_j));
    assert_eq!(w.cutoff(), 9.0);
    assert_eq!(at(9.0).unwrap(), PairEval::default());
    assert_eq!(at(12.0).unwrap(), PairEval::default());
    // g(r_c − δ) = O(δ²): energy O(δ²), force O(δ).
    for d in [1e-2, 1e-3, 1e-4] {
        let e = at(9.0 - d).unwrap();
        assert!(e.energy.abs() < 2.0 * d * d, "{d}: {}", e.energy);
        assert!(e.force.length() < 2.0 * d, "{d}: {}", e.force);
    }
    // Inside the switch window the unswitched dipolar + LJ energy is scaled by g.
    let (g, _) = w.cutoff_switch(8.5);
    assert!(g > 0.0 && g < 1.0);
    assert!(at(8.5).unwrap().energy.abs() > 0.0);
}

/// The hydrogen-bond dimer of [`SoftStickyDipole::hydrogen_bond`] by hand from FG04 Eqs. 1–5:
/// `u_dp = 0` (parallel dipoles at the magic angle with r̂), `w = −8/(3√3)`, and
/// `w' = (1/√3 − 0.6)²(1/√3 + 0.8)² + (−1/√3 − 0.6)²(−1/√3 + 0.8)² − 2w₀`.
fn dimer_by_hand(d: f64) -> f64 {
    let p = SsdParameters::SSD_E;
    let cubic = |r: f64, lo: f64, hi: f64| {
        if r <= lo {
            1.0
        } else if r >= hi {
            0.0
        } else {
            (hi - r).powi(2) * (hi + 2.0 * r - 3.0 * lo) / (hi - lo).powi(3)
        }
    };
    let x = (p.sigma / d).powi(6);
    let lj = 4.0 * p.epsilon * (x * x - x) * cubic(d, p.r_switch, p.r_cut);
    let c = 1.0 / 3f64.sqrt();
    let w = -8.0 / (3.0 * 3f64.sqrt());
    let wp = (c - 0.6f64).powi(2) * (c + 0.8f64).powi(2)
        + (-c - 0.6f64).powi(2) * (-c + 0.8f64).powi(2)
        - 2.0 * p.w0;
    lj + 0.5 * p.nu0 * cubic(d, p.r_l, p.r_u) * w
        + 0.5 * p.nu0_prime * cubic(d, p.r_l_prime, p.r_u_prime) * wp
}

#[test]
fn hydrogen_bond_dimer_by_hand() {
    let w = SoftStickyDipole::ssd_e();
    for d in [2.5, 2.75, 2.9, 3.1, 3.5, 4.0, 6.0] {
        let g = SoftStickyDipole::hydrogen_bond(d);
        assert!((g.r_ij.length() - d).abs() < 1e-14);
        let (u, hand) = (w.energy(&g), dimer_by_hand(d));
        assert!(
            (u - hand).abs() <= 1e-12 * (1.0 + hand.abs()),
            "{d}: {u} {hand}"
        );
    }
    // At d = 2.75 Å by hand: s = (1.05² · 2.1)/1.4³ = 0.84375, s' = 1, g = 1:
    // 4ε[(σ/d)¹² − (σ/d)⁶] = 3.70954, (ν₀/2) s w = −10.59859, (ν₀'/2) w' = −0.69033;
    // U = −7.57938 kJ/mol (−1.81151 kcal/mol).
    let u = w.energy(&SoftStickyDipole::hydrogen_bond(2.75));
    assert!((u - -7.57938).abs() < 1e-5, "{u}");
    // The best distance of this family: golden-section search on the hand formula. The
    // dipoles contribute nothing here, so this is only an upper bound on the dimer minimum;
    // FG04 report no SSD/E dimer energy that we could check against.
    let (mut a, mut b) = (2.4, 3.6);
    for _ in 0..100 {
        let (m1, m2) = (a + 0.382 * (b - a), b - 0.382 * (b - a));
        if dimer_by_hand(m1) < dimer_by_hand(m2) {
            b = m2;
        } else {
            a = m1;
        }
    }
    let d_star = 0.5 * (a + b);
    let u_star = w.energy(&SoftStickyDipole::hydrogen_bond(d_star));
    assert!((u_star - dimer_by_hand(d_star)).abs() < 1e-12);
    // The force at the optimum of the family has no component along r̂ (dU/dd = 0).
    let e = w
        .evaluate(&SoftStickyDipole::hydrogen_bond(d_star))
        .unwrap();
    let r_hat = SoftStickyDipole::hydrogen_bond(d_star).r_ij / d_star;
    assert!(e.force.dot(r_hat).abs() < 1e-6, "{}", e.force.dot(r_hat));
    assert!(u_star <= u && u_star > w.minimum());
    println!(
        "H-bond family optimum: d* = {d_star:.4} Å, U = {u_star:.4} kJ/mol = {:.4} kcal/mol",
        u_star / KCAL
    );
}

#[test]
fn the_minimum_bound_supports_a_level_set_and_bounds_a_random_search() {
    let w = SoftStickyDipole::ssd_e();
    let m = w.minimum();
    assert!(m < -7.6 && m > -60.0, "{m}");
    // A descent from many random starts stays above the bound.
    let mut best = 0.0f64;
    let mut seed = 0x1234_5678_u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for _ in 0..200 {
        let q = |n: &mut dyn FnMut() -> f64| DQuat::from_xyzw(n(), n(), n(), n()).normalize();
        let mut g = RigidGeometry::new(
            DVec3::new(next(), next(), next()).normalize() * (2.6 + 0.3 * next()),
            q(&mut next),
            q(&mut next),
        );
        let mut u = w.energy(&g);
        let mut step = 0.2;
        while step > 1e-4 {
            let mut improved = false;
            for k in 0..9 {
                for sgn in [-1.0, 1.0] {
                    let mut t = g;
                    let axis = DVec3::AXES[k % 3] * sgn * step;
                    match k / 3 {
                        0 => t.r_ij += axis,
                        1 => t.q_i = DQuat::from_scaled_axis(axis) * t.q_i,
                        _ => t.q_j = DQuat::from_scaled_axis(axis) * t.q_j,
                    }
                    let ut = w.energy(&t);
                    if ut < u {
                        (g, u, improved) = (t, ut, true);
                    }
                }
            }
            if !improved {
                step *= 0.5;
            }
        }
        best = best.min(u);
    }
    assert!(best >= m, "{best} < {m}");
    println!("lowest SSD/E dimer energy found: {best:.4} kJ/mol; bound {m:.4}");
    // The terrace map's level checks accept the bound as the minimum.
    let levels: Vec<f64> = (1..=10)
        .rev()
        .map(|k| m * (k as f64 - 0.5) / 10.0)
        .collect();
    assert!(LevelSet::new(m, &levels, &TerraceOptions::default()).is_ok());
}

#[test]
fn reach_is_a_monotone_upper_bound_within_the_cutoff() {
    let w = SoftStickyDipole::ssd_e();
    let mut last = 0.0;
    for u_k in [-20.0, -5.0, -1.0, -0.1, -1e-3] {
        let r = w.reach(u_k).unwrap();
        assert!(r > last && r <= 9.0, "{u_k}: {r}");
        last = r;
    }
    assert!(w.reach(-1e-3).unwrap() > w.reach(-1.0).unwrap());
    assert_eq!(w.reach(2.0 * w.minimum()).unwrap(), 0.0);
    assert!(w.reach(1.0).unwrap() > 2.0 && w.reach(1.0).unwrap() <= 9.0);
    assert!(matches!(w.reach(0.0), Err(PotentialError::LevelAtZero(_))));
    // The head-to-tail pair (dipoles along r̂) reaches −2μ²g/r³ + LJ: within the reach.
    for u_k in [-5.0, -1.0, -0.1] {
        let r = w.reach(u_k).unwrap();
        let g = RigidGeometry::new(DVec3::Z * r * 1.0001, DQuat::IDENTITY, DQuat::IDENTITY);
        assert!(w.energy(&g) > u_k, "{u_k}");
    }
}
