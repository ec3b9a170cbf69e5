//! Stiff and extreme geometries: effective distances going to zero, axes exactly and nearly
//! parallel or perpendicular, huge and tiny distances. Never NaN: `energy` is a number or `+∞`,
//! `evaluate` is finite or an `Overlap` error.

use crate::common::*;
use glam::DVec3;
use potential::{
    GayBerne, LennardJones, LjRod, PairGeometry, PairPotential, PotentialError, Smoothed,
};
use proptest::prelude::*;

fn all() -> Vec<(&'static str, Box<dyn PairPotential>)> {
    vec![
        ("LJ", Box::new(LennardJones::new(1.0, 1.0).unwrap())),
        ("rods", Box::new(LjRod::new(1.0, 1.0, 0.33).unwrap())),
        ("rods, ζ = σ", Box::new(LjRod::new(1.0, 1.0, 1.0).unwrap())),
        ("GB(3,5,2,1)", Box::new(GayBerne::default())),
        (
            "GB oblate",
            Box::new(GayBerne::new(1.0, 1.0, 0.5, 0.2, 1.0, 3.0).unwrap()),
        ),
        (
            "GB(3,5,2,1) smoothed",
            Box::new(Smoothed::new(GayBerne::default(), 3.5, 4.5).unwrap()),
        ),
    ]
}

/// The convention every potential keeps for any finite geometry.
fn sane(name: &str, p: &dyn PairPotential, g: &PairGeometry) {
    let u = p.energy(g);
    assert!(!u.is_nan(), "{name}: NaN energy at {g:?}");
    assert!(
        u >= p.minimum() * (1.0 + 1e-12),
        "{name}: U = {u} below the minimum {} at {g:?}",
        p.minimum()
    );
    match p.evaluate(g) {
        Ok(e) => {
            assert!(e.is_finite(), "{name}: non-finite evaluation at {g:?}");
            assert_eq!(e.energy.to_bits(), u.to_bits(), "{name}: energy ≠ evaluate");
        }
        Err(PotentialError::Overlap { .. }) => {
            // Only deep in the core: U infinite, or so large that the force overflows.
            assert!(u > 1e200, "{name}: overlap error at U = {u}");
        }
        Err(e) => panic!("{name}: unexpected error {e}"),
    }
}

#[test]
fn effective_distance_going_to_zero() {
    let rod = LjRod::new(1.0, 1.0, 0.4).unwrap();
    // Parallel rods: r_e = r − 0.2.
    let mut last = 0.0;
    for gap in [
        1e-1, 1e-2, 1e-4, 1e-8, 1e-13, 1e-20, 1e-30, 0.0, -1e-30, -0.1,
    ] {
        let g = PairGeometry::new(DVec3::X * (0.2 + gap), DVec3::Z, DVec3::Z);
        sane("rods", &rod, &g);
        let u = rod.energy(&g);
        assert!(u >= last, "U must grow as r_e → 0: {u} after {last}");
        last = u;
    }
    assert_eq!(last, f64::INFINITY);
    // Gay–Berne end to end: R = r − 3 + 1 → 0.
    let gb = GayBerne::default();
    let mut last = 0.0;
    for gap in [1e-1, 1e-3, 1e-8, 1e-15, 0.0, -1e-12] {
        let g = PairGeometry::new(DVec3::X * (2.0 + gap), DVec3::X, DVec3::X);
        sane("GB", &gb, &g);
        let u = gb.energy(&g);
        assert!(u >= last);
        last = u;
    }
    assert_eq!(last, f64::INFINITY);
}

#[test]
fn axes_exactly_and_nearly_parallel_or_perpendicular() {
    for (name, p) in all() {
        let p = p.as_ref();
        for d in [1.05, 1.3, 2.5, 3.4, 4.0] {
            let n = DVec3::new(0.6, 0.0, 0.8);
            for (si, sj) in [
                (DVec3::Y, DVec3::Y),  // s_i × s_j = 0 exactly
                (DVec3::Y, -DVec3::Y), // antiparallel
                (DVec3::Y, DVec3::X),  // perpendicular to each other
                (n, n),                // parallel, tilted to r̂
                (DVec3::X, DVec3::Z),
            ] {
                let g = PairGeometry::new(n * d, si, sj);
                sane(name, p, &g);
                // A turn by 1e-9 rad changes U by O(1e-9) at most (continuity at the
                // symmetric configuration; the torque there is finite).
                let e0 = p.energy(&g);
                for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                    let h = turned(&g, 1, axis, 1e-9);
                    sane(name, p, &h);
                    let e1 = p.energy(&h);
                    if e0.is_finite() {
                        assert!(
                            (e1 - e0).abs() < 1e-6 * (1.0 + e0.abs()),
                            "{name}: {e0} {e1}"
                        );
                    }
                }
                if let Ok(e) = p.evaluate(&g) {
                    assert!(e.torque_imbalance(g.r_ij) < 1e-12, "{name}");
                    if let Some(f) = fd_errors(p, &g) {
                        assert!(f.torque_i < 1e-7 && f.torque_j < 1e-7, "{name}: {f:?}");
                    }
                }
            }
        }
    }
}

#[test]
fn huge_and_tiny_distances() {
    for (name, p) in all() {
        let p = p.as_ref();
        for d in [
            1e-310, 1e-300, 1e-100, 1e-8, 1e8, 1e100, 1e154, 1e160, 1e300,
        ] {
            let g = PairGeometry::new(DVec3::new(0.6, 0.0, -0.8) * d, DVec3::Z, DVec3::X);
            sane(name, p, &g);
            if d > 1.0 {
                let u = p.energy(&g);
                assert!(u <= 0.0 && u > -1e-40, "{name}: U({d:e}) = {u}");
                let e = p.evaluate(&g).unwrap();
                assert!(e.force.length() < 1e-40, "{name}: F({d:e}) = {}", e.force);
            } else if name == "LJ" || name.starts_with("GB(3,5,2,1)") {
                // Deep inside: huge or infinite (overflow), never NaN (checked by `sane`).
                // (Crossed rods keep r_e ≥ ζ/2 down to r → 0, and discs (κ < 1) have
                // σ(r̂, s_i, s_j) < σ₀ for some orientations: their U stays finite there, as the
                // formulas say; the terrace map's hard core keeps such pairs apart.)
                let u = p.energy(&g);
                assert!(u > 1e90, "{name}: U({d:e}) = {u}");
            }
        }
        let g = PairGeometry::new(DVec3::ZERO, DVec3::Z, DVec3::X);
        assert_eq!(p.energy(&g), f64::INFINITY, "{name}: r = 0");
        assert!(matches!(
            p.evaluate(&g),
            Err(PotentialError::Overlap { .. })
        ));
    }
}

#[test]
fn nan_geometry_is_an_error_not_a_force() {
    for (name, p) in all() {
        let g = PairGeometry::new(DVec3::new(f64::NAN, 1.0, 0.0), DVec3::Z, DVec3::X);
        assert!(
            matches!(p.evaluate(&g), Err(PotentialError::NotFinite(_))),
            "{name}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn never_nan_never_below_the_minimum(
        log_d in -320.0f64..300.0,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform3(-1.0f64..1.0),
        b in prop::array::uniform3(-1.0f64..1.0),
        same in any::<bool>(),
    ) {
        let dir = DVec3::from(dir);
        prop_assume!(dir.length() > 0.1);
        let (a, b) = (DVec3::from(a), DVec3::from(b));
        prop_assume!(a.length() > 0.1 && b.length() > 0.1);
        let si = a.normalize();
        let sj = if same { si } else { b.normalize() };
        let g = PairGeometry::new(dir.normalize() * 10f64.powf(log_d), si, sj);
        for (name, p) in all() {
            sane(name, p.as_ref(), &g);
        }
    }

    #[test]
    fn never_nan_near_contact(
        d in 0.0f64..4.0,
        dir in prop::array::uniform3(-1.0f64..1.0),
        a in prop::array::uniform3(-1.0f64..1.0),
        b in prop::array::uniform3(-1.0f64..1.0),
    ) {
        let dir = DVec3::from(dir);
        let (a, b) = (DVec3::from(a), DVec3::from(b));
        prop_assume!(dir.length() > 0.1 && a.length() > 0.1 && b.length() > 0.1);
        let g = PairGeometry::new(dir.normalize() * d, a.normalize(), b.normalize());
        for (name, p) in all() {
            sane(name, p.as_ref(), &g);
        }
    }
}
