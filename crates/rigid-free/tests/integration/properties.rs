//! Property tests over random bodies, states and times: conservation of the lab angular momentum
//! and the energy, `A(t)` a proper rotation, the group property, time reversal, and the
//! derivatives `dA/dt = −W(ω) A`, `dω/dt` (Euler) and the lab velocity of body-fixed points.

use glam::{DMat3, DQuat, DVec3};
use proptest::prelude::*;
use rigid_free::{FreeMotion, Moments, MotionKind, Pose};

/// Moments of every kind: asymmetric mostly, sometimes two or three equal, sometimes a rod.
fn moments() -> impl Strategy<Value = [f64; 3]> {
    (0.3f64..3.0, 0.3f64..3.0, 0.3f64..3.0, 0u8..10).prop_filter_map(
        "triangle inequality",
        |(a, b, c, pick)| {
            let i = match pick {
                0 => [a, a, a],
                1 => [a, b, b],
                2 => [b, a, b],
                3 => [0.0, b, b],
                _ => [a, b, c],
            };
            Moments::new(i).ok().map(|_| i)
        },
    )
}

fn attitude() -> impl Strategy<Value = DMat3> {
    (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0).prop_filter_map(
        "non-zero quaternion",
        |(w, x, y, z)| {
            let q = DQuat::from_xyzw(x, y, z, w);
            (q.length() > 0.1).then(|| rigid_free::attitude_from_quat(q))
        },
    )
}

fn omega() -> impl Strategy<Value = DVec3> {
    (-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

fn l_lab(i: [f64; 3], p: &Pose) -> DVec3 {
    p.orientation * (DVec3::from(i) * p.omega)
}

fn energy(i: [f64; 3], p: &Pose) -> f64 {
    0.5 * (DVec3::from(i) * p.omega * p.omega).element_sum()
}

fn max_abs(m: DMat3) -> f64 {
    m.to_cols_array().iter().fold(0.0, |a, v| a.max(v.abs()))
}

fn motion(i: [f64; 3], a: DMat3, w: DVec3) -> FreeMotion {
    FreeMotion::new(&Moments::new(i).unwrap(), a, w).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn conserves_l_and_e_and_stays_a_rotation(
        i in moments(), a in attitude(), w in omega(), t in -60.0f64..60.0
    ) {
        let m = motion(i, a, w);
        let (p0, p) = (m.pose(0.0), m.pose(t));
        let scale = l_lab(i, &p0).length().max(1e-300);
        prop_assert!((l_lab(i, &p) - l_lab(i, &p0)).length() <= 1e-12 * scale,
            "{:?}: L drift {:e}", m.kind(), (l_lab(i, &p) - l_lab(i, &p0)).length() / scale);
        let e0 = energy(i, &p0);
        prop_assert!((energy(i, &p) - e0).abs() <= 1e-13 * e0.max(1e-300));
        prop_assert!(max_abs(p.orientation.transpose() * p.orientation - DMat3::IDENTITY) <= 1e-13);
        prop_assert!((p.orientation.determinant() - 1.0).abs() <= 1e-13);
        // The state at t = 0 is the initial one.
        prop_assert!(max_abs(p0.attitude() - a) <= 1e-14);
        prop_assert!((p0.omega - m.initial_pose().omega).length() <= 1e-14 * w.length().max(1.0));
    }

    #[test]
    fn group_property(
        i in moments(), a in attitude(), w in omega(), t1 in -20.0f64..20.0, t2 in -20.0f64..20.0
    ) {
        let m = motion(i, a, w);
        let p1 = m.pose(t1);
        let m2 = motion(i, p1.attitude(), p1.omega);
        let direct = m.propagator(t1 + t2);
        let composed = m2.propagator(t2) * m.propagator(t1);
        prop_assert!(max_abs(direct - composed) <= 1e-12, "{:?}: {:e}", m.kind(), max_abs(direct - composed));
        let w_err = (m.pose(t1 + t2).omega - m2.pose(t2).omega).length();
        prop_assert!(w_err <= 1e-12 * w.length().max(1.0));
    }

    #[test]
    fn time_reversal(i in moments(), a in attitude(), w in omega(), t in -30.0f64..30.0) {
        let m = motion(i, a, w);
        let p = m.pose(t);
        // Reversing ω at time t retraces the motion: after t more, the initial attitude with −ω(0).
        let back = motion(i, p.attitude(), -p.omega).pose(t);
        prop_assert!(max_abs(back.attitude() - a) <= 1e-12, "{:?}", m.kind());
        prop_assert!((back.omega + m.initial_pose().omega).length() <= 1e-12 * w.length().max(1.0));
        // And P(−t) = P(t)ᵀ for the reversed initial state.
        let rev = motion(i, a, -m.initial_pose().omega);
        prop_assert!(max_abs(rev.propagator(-t) - m.propagator(t)) <= 1e-12);
    }

    #[test]
    fn derivatives_match_finite_differences(
        i in moments(), a in attitude(), w in omega(), t in -10.0f64..10.0
    ) {
        let m = motion(i, a, w);
        let h = 1e-4;
        let (pm, p, pp) = (m.pose(t - h), m.pose(t), m.pose(t + h));
        // dA/dt = −W(ω) A, i.e. dR/dt = R W(ω) = ω_lab × (columns of R); fourth-order accurate
        // differences keep the truncation error below the rounding error.
        let (pm2, pp2) = (m.pose(t - 2.0 * h), m.pose(t + 2.0 * h));
        let d = |f: &dyn Fn(&Pose) -> DMat3| {
            (f(&pm2) - f(&pp2) + (f(&pp) - f(&pm)) * 8.0) * (1.0 / (12.0 * h))
        };
        let dr = d(&|q: &Pose| q.orientation);
        let wl = p.omega_lab();
        let want = DMat3::from_cols(
            wl.cross(p.orientation.x_axis),
            wl.cross(p.orientation.y_axis),
            wl.cross(p.orientation.z_axis),
        );
        let scale = w.length().max(1.0);
        prop_assert!(max_abs(dr - want) <= 1e-8 * scale * scale, "{:?}: {:e}", m.kind(), max_abs(dr - want));
        // dω/dt from Euler's equations.
        let dw = (pm2.omega - pp2.omega + (pp.omega - pm.omega) * 8.0) / (12.0 * h);
        prop_assert!((dw - m.omega_dot(p.omega)).length() <= 1e-8 * scale * scale * scale);
        // Velocity of a body-fixed point.
        let x = DVec3::new(0.3, -0.7, 0.2);
        let dx = (pm2.lab_vector(x) - pp2.lab_vector(x) + (pp.lab_vector(x) - pm.lab_vector(x)) * 8.0) / (12.0 * h);
        prop_assert!((dx - p.lab_velocity(x)).length() <= 1e-8 * scale * scale);
        // The cheap ω(t) is the pose's ω.
        prop_assert!((m.omega(t) - p.omega).length() <= 1e-15 * scale);
    }

    #[test]
    fn quaternion_round_trip(a in attitude()) {
        let q = rigid_free::quat_from_attitude(a);
        prop_assert!(max_abs(rigid_free::attitude_from_quat(q) - a) <= 4e-15);
        prop_assert!(q.w >= 0.0);
    }
}

/// Sanity of the generator itself: every kind of motion is exercised.
#[test]
fn strategies_reach_every_kind() {
    let kinds = [
        motion([1.0, 1.0, 1.0], DMat3::IDENTITY, DVec3::ONE).kind(),
        motion([1.0, 2.0, 2.0], DMat3::IDENTITY, DVec3::ONE).kind(),
        motion([0.0, 2.0, 2.0], DMat3::IDENTITY, DVec3::ONE).kind(),
        motion([1.0, 2.0, 2.5], DMat3::IDENTITY, DVec3::ONE).kind(),
    ];
    assert_eq!(
        kinds,
        [
            MotionKind::Spherical,
            MotionKind::Symmetric,
            MotionKind::LinearRotor,
            MotionKind::Asymmetric
        ]
    );
}
