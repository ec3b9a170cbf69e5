//! The contract of certified event prediction (`potential::certify`): along exact free flights
//! (straight centres, axes turning uniformly about fixed `ω`), the effective coordinate never
//! leaves its Taylor model's remainder bound, and never leaves the band's interval before the
//! model's safe time. Random and stiff flights: fast spin, grazing and head-on approach, near
//! contact, parallel and perpendicular axes.

use glam::{DQuat, DVec3};
use potential::certify::interval_containing;
use potential::{FreeFlight, LennardJones, LjRod, PairGeometry, PairPotential};
use proptest::prelude::*;

/// The flight advanced by `tau`: the exact motion the model describes.
fn at(f: &FreeFlight, tau: f64) -> PairGeometry {
    let turn = |s: DVec3, w: DVec3| -> DVec3 {
        let n = w.length();
        if n == 0.0 {
            s
        } else {
            DQuat::from_axis_angle(w / n, n * tau) * s
        }
    };
    PairGeometry::new(f.r + f.v * tau, turn(f.s_i, f.w_i), turn(f.s_j, f.w_j))
}

/// The effective coordinate of each potential, computed from the geometry directly.
fn coordinate(zeta: f64, g: &PairGeometry) -> f64 {
    let c = g.s_i.dot(g.s_j);
    g.r_ij.length() + zeta * (0.5 - c * c)
}

fn unit() -> impl Strategy<Value = DVec3> {
    (-1.0f64..1.0, 0.0f64..std::f64::consts::TAU).prop_map(|(z, phi)| {
        let rho = (1.0 - z * z).sqrt();
        DVec3::new(rho * phi.cos(), rho * phi.sin(), z)
    })
}

/// A linear rotor's angular velocity: perpendicular to its axis, magnitude `w`.
fn spin(s: DVec3, dir: DVec3, w: f64) -> DVec3 {
    let p = dir - s * s.dot(dir);
    if p.length() < 1e-6 {
        s.any_orthonormal_vector() * w
    } else {
        p.normalize() * w
    }
}

/// Flights from gentle to stiff: speeds up to 100, spins up to 1000, centres from near
/// contact (0.3) to far; `v` may point straight at the other centre (head-on) or skim it.
fn flight() -> impl Strategy<Value = FreeFlight> {
    (
        unit(),
        0.3f64..4.0,
        unit(),
        prop_oneof![Just(0.0), 0.01f64..1.0, 1.0f64..100.0],
        prop::bool::ANY,
        unit(),
        unit(),
        unit(),
        unit(),
        prop_oneof![Just(0.0), 0.1f64..10.0, 10.0f64..1000.0],
        prop_oneof![Just(0.0), 0.1f64..10.0, 10.0f64..1000.0],
    )
        .prop_map(|(rd, r, vd, v, head_on, si, sj, wi, wj, a, b)| {
            let rr = rd * r;
            let v = if head_on { -rd * v } else { vd * v };
            FreeFlight::new(rr, v, si, spin(si, wi, a), sj, spin(sj, wj, b))
        })
}

fn check_remainder(zeta: f64, p: &dyn PairPotential, f: &FreeFlight, h: f64) {
    let m = p.taylor_model(f, h).expect("a Taylor model");
    let x0 = coordinate(zeta, &at(f, 0.0));
    assert!(
        (m.x - x0).abs() <= 1e-12 * x0.abs().max(1.0),
        "{} vs {x0}",
        m.x
    );
    for q in 1..=64 {
        let tau = h * f64::from(q) / 64.0;
        let x = coordinate(zeta, &at(f, tau));
        let p2 = m.x + m.dx * tau + 0.5 * m.ddx * tau * tau;
        let bound = m.third * tau * tau * tau / 6.0;
        // Round-off of x and of the polynomial: a few ulps of the values involved.
        let slack = 1e-12 * (x.abs() + m.dx.abs() * tau + m.ddx.abs() * tau * tau + 1.0);
        assert!(
            (x - p2).abs() <= bound + slack,
            "τ = {tau}: |x − p| = {} > M τ³/6 = {bound} ({m:?}, {f:?})",
            (x - p2).abs()
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn rods_never_leave_the_remainder_bound(f in flight(), h in prop_oneof![1e-4f64..1e-2, 1e-2f64..0.5]) {
        for zeta in [0.0, 0.33, 1.0] {
            let rod = LjRod::new(1.0, 1.0, zeta).unwrap();
            check_remainder(zeta, &rod, &f, h);
        }
    }

    #[test]
    fn spheres_never_leave_the_remainder_bound(f in flight(), h in 1e-4f64..0.5) {
        check_remainder(0.0, &LennardJones::new(1.0, 1.0).unwrap(), &f, h);
    }

    /// Up to the safe time the pair's `U` stays strictly inside the band of levels `lo < U <
    /// hi` it started in: the property the search relies on to jump the stretch.
    #[test]
    fn no_level_is_crossed_before_the_safe_time(
        f in flight(),
        h in 1e-4f64..0.2,
        zeta in prop_oneof![Just(0.0), 0.1f64..1.0],
        dv in 0.05f64..1.0,
    ) {
        let rod = LjRod::new(1.0, 1.0, zeta).unwrap();
        let g0 = at(&f, 0.0);
        let u0 = rod.energy(&g0);
        prop_assume!(u0.is_finite() && u0 < 50.0);
        // Evenly spaced levels (k − ½)ΔV around the start, as the paper's terraces.
        let k = (u0 / dv + 0.5).floor();
        let (lo, hi) = ((k - 0.5) * dv, (k + 0.5) * dv);
        let lo = if lo <= -1.0 { f64::NEG_INFINITY } else { lo };
        let parts = rod.coordinate_intervals(lo, hi);
        let (a, b) = interval_containing(&parts, coordinate(zeta, &g0))
            .expect("the start lies inside its band");
        let m = rod.taylor_model(&f, h).unwrap();
        let safe = m.safe_time(a, b, h);
        prop_assert!((0.0..=h).contains(&safe));
        for q in 0..=200 {
            let tau = safe * f64::from(q) / 200.0;
            let u = rod.energy(&at(&f, tau));
            prop_assert!(u > lo && u < hi, "U = {u} outside ({lo}, {hi}) at τ = {tau} < {safe}");
        }
    }
}

/// The band's ends are the levels' preimages: `U` at each finite end equals a level, `U` is
/// inside the band in between, and the intervals hold the well's two flanks.
#[test]
fn band_ends_are_at_the_levels() {
    let rod = LjRod::new(1.0, 1.0, 0.5).unwrap();
    let e_of = |x: f64| rod.energy_of_effective(x);
    let x_m = 2f64.powf(1.0 / 6.0);
    for &(lo, hi, parts) in &[
        (-0.75, -0.25, 2),
        (-0.25, 0.25, 2),
        (0.25, 0.75, 1),
        (f64::NEG_INFINITY, -0.75, 1),
        (50.0, 100.0, 1),
    ] {
        let iv = rod.coordinate_intervals(lo, hi);
        assert_eq!(iv.len(), parts, "({lo}, {hi}): {iv:?}");
        for &(a, b) in &iv {
            assert!(a < b);
            for end in [a, b] {
                if end.is_finite() {
                    let u = e_of(end);
                    let at_level = (u - lo).abs() < 1e-12 || (u - hi).abs() < 1e-12;
                    assert!(at_level, "U({end}) = {u} is not a level of ({lo}, {hi})");
                }
            }
            for q in 1..100 {
                let x = if b.is_finite() {
                    a + (b - a) * f64::from(q) / 100.0
                } else {
                    a * (1.0 + f64::from(q))
                };
                let u = e_of(x);
                assert!(u > lo && u < hi, "U({x}) = {u} outside ({lo}, {hi})");
            }
        }
    }
    // The lowest terrace spans the well; the far terrace reaches infinity.
    let low = rod.coordinate_intervals(f64::NEG_INFINITY, -0.75);
    assert!(low[0].0 < x_m && x_m < low[0].1);
    assert_eq!(rod.coordinate_intervals(-0.25, 0.25)[1].1, f64::INFINITY);
    assert_eq!(interval_containing(&low, x_m), Some(low[0]));
    assert_eq!(interval_containing(&low, 10.0), None);
}

/// Potentials without a model say so, and their band proves nothing.
#[test]
fn gay_berne_offers_no_model() {
    let gb = potential::GayBerne::default();
    let f = FreeFlight::new(
        DVec3::X * 3.0,
        DVec3::Y,
        DVec3::Z,
        DVec3::X,
        DVec3::Z,
        DVec3::Y,
    );
    assert!(gb.taylor_model(&f, 0.1).is_none());
    assert!(gb.coordinate_intervals(-0.5, 0.5).is_empty());
}
