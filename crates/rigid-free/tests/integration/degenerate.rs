//! Degenerate and extreme states: each is dispatched to the right solution, and the solutions
//! join continuously where the kinds meet (near-symmetric ↔ symmetric, near-separatrix ↔
//! separatrix, slow ↔ rest), with a short-time RK4 integration of Euler + dA/dt as the
//! independent referee.

use glam::{DMat3, DQuat, DVec3};
use rigid_free::{FreeError, FreeMotion, LinearRotor, Moments, MotionKind};

fn motion(i: [f64; 3], a: DMat3, w: DVec3) -> FreeMotion {
    FreeMotion::new(&Moments::new(i).unwrap(), a, w).unwrap()
}

fn max_abs(m: DMat3) -> f64 {
    m.to_cols_array().iter().fold(0.0, |a, v| a.max(v.abs()))
}

fn some_attitude() -> DMat3 {
    rigid_free::attitude_from_quat(DQuat::from_xyzw(0.3, -0.5, 0.1, 0.8))
}

/// RK4 on Euler's equations and dA/dt = −W(ω) A with `n` steps to time `t`.
fn rk4(i: [f64; 3], a0: DMat3, w0: DVec3, t: f64, n: usize) -> (DMat3, DVec3) {
    let iv = DVec3::from(i);
    let f = |a: DMat3, w: DVec3| {
        // A rod (one zero moment) without spin keeps ω: Euler's equations are 0/0 there.
        let wd = if iv.min_element() == 0.0 {
            DVec3::ZERO
        } else {
            (iv * w).cross(w) / iv
        };
        // −W(ω) A: column c of A is mapped to −ω × column.
        let ad = DMat3::from_cols(-w.cross(a.x_axis), -w.cross(a.y_axis), -w.cross(a.z_axis));
        (ad, wd)
    };
    let h = t / n as f64;
    let (mut a, mut w) = (a0, w0);
    for _ in 0..n {
        let (k1a, k1w) = f(a, w);
        let (k2a, k2w) = f(a + k1a * (0.5 * h), w + k1w * (0.5 * h));
        let (k3a, k3w) = f(a + k2a * (0.5 * h), w + k2w * (0.5 * h));
        let (k4a, k4w) = f(a + k3a * h, w + k3w * h);
        a += (k1a + k2a * 2.0 + k3a * 2.0 + k4a) * (h / 6.0);
        w += (k1w + k2w * 2.0 + k3w * 2.0 + k4w) * (h / 6.0);
    }
    (a, w)
}

#[test]
fn rest_and_steady_spin() {
    let a = some_attitude();
    let m = motion([1.0, 2.0, 3.0], a, DVec3::ZERO);
    assert_eq!(m.kind(), MotionKind::Rest);
    assert_eq!(m.pose(1e6).attitude(), a);
    for axis in 0..3 {
        let mut w = DVec3::ZERO;
        w[axis] = -1.7;
        let m = motion([1.0, 2.0, 3.0], a, w);
        assert_eq!(m.kind(), MotionKind::SteadySpin);
        let p = m.pose(123.0);
        // Spin about a principal axis, even the unstable middle one, stays exactly steady.
        assert_eq!(p.omega, w);
        let expect = DMat3::from_axis_angle(a.transpose() * w.normalize(), 1.7 * 123.0);
        assert!(max_abs(p.orientation - expect * a.transpose()) < 1e-13);
    }
}

#[test]
fn exactly_equal_moments_use_the_trigonometric_solutions() {
    let a = some_attitude();
    let w = DVec3::new(0.4, -1.2, 0.9);
    assert_eq!(motion([2.0; 3], a, w).kind(), MotionKind::Spherical);
    assert_eq!(motion([1.0, 2.0, 2.0], a, w).kind(), MotionKind::Symmetric);
    // A symmetric top and an asymmetric top 1e-12 away from it agree to ~1e-12·t. The last
    // pair keeps L circling the axis whose moment is nearly the middle one (ω1 tiny), where the
    // characteristic of Π(n|m) is n ≈ −2e12.
    let w_axis3 = DVec3::new(1e-7, 0.6, 0.8);
    for (sym, near, w) in [
        ([1.0, 1.0, 2.0], [1.0, 1.0 + 1e-12, 2.0], w),
        ([1.0, 2.0, 2.0], [1.0, 2.0, 2.0 + 1e-12], w),
        ([2.0, 1.0, 2.0], [2.0 - 1e-12, 1.0, 2.0], w),
        ([1.0, 2.0, 2.0], [1.0, 2.0, 2.0 + 1e-12], w_axis3),
    ] {
        let (ms, mn) = (motion(sym, a, w), motion(near, a, w));
        assert_eq!(ms.kind(), MotionKind::Symmetric);
        assert_eq!(mn.kind(), MotionKind::Asymmetric);
        for t in [0.5, 5.0, 50.0] {
            let d = max_abs(ms.propagator(t) - mn.propagator(t));
            assert!(d < 1e-11 * t.max(1.0), "{sym:?} t={t}: {d:e}");
        }
    }
}

#[test]
fn separatrix_joins_its_neighbours() {
    // I = (1, 2.5, 3) and ω1 = ω3 put Δ2 = 0 exactly.
    let i = [1.0, 2.5, 3.0];
    let a = some_attitude();
    let w = DVec3::new(0.5, 0.3, 0.5);
    let on = motion(i, a, w);
    assert_eq!(on.kind(), MotionKind::Separatrix);
    for dw in [1e-13, -1e-13] {
        let near = motion(i, a, w + DVec3::new(dw, 0.0, 0.0));
        assert_eq!(near.kind(), MotionKind::Asymmetric);
        for t in [1.0, 5.0, 20.0] {
            let d = max_abs(on.propagator(t) - near.propagator(t));
            // The trajectories separate like e^{λt} from 1e-13; at t ≤ 20 they are close.
            assert!(d < 1e-9, "dw={dw} t={t}: {d:e}");
        }
    }
    // The separatrix against RK4.
    let (ar, wr) = rk4(i, a, w, 3.0, 20_000);
    let p = on.pose(3.0);
    assert!(max_abs(p.attitude() - ar) < 1e-12);
    assert!((p.omega - wr).length() < 1e-12);
}

#[test]
fn short_time_agreement_with_rk4() {
    let a = some_attitude();
    for (i, w) in [
        ([1.0, 2.0, 3.0], DVec3::new(0.7, -1.1, 1.9)),
        ([3.0, 2.0, 1.0], DVec3::new(2.5, 0.4, 0.3)),
        ([1.3, 1.9, 2.6], DVec3::new(-0.2, 2.0, -0.1)),
        ([1.0, 1.0, 1.8], DVec3::new(0.7, -1.1, 1.9)),
        ([0.0, 1.2, 1.2], DVec3::new(0.7, -1.1, 1.9)),
    ] {
        let m = motion(i, a, w);
        let (ar, wr) = rk4(i, a, m.initial_pose().omega, 2.0, 10_000);
        let p = m.pose(2.0);
        let (da, dw) = (max_abs(p.attitude() - ar), (p.omega - wr).length());
        assert!(da < 1e-12 && dw < 1e-12, "{i:?}: {da:e} {dw:e}");
    }
}

#[test]
fn extreme_speeds_scale_exactly() {
    // Motion at ω·s over time t/s is the motion at ω over t: the set-up scales by powers of two
    // internally, so neither tiny nor huge angular velocities under- or overflow.
    let a = some_attitude();
    let i = [1.0, 2.0, 3.0];
    let w = DVec3::new(0.7, -1.1, 1.9);
    let base = motion(i, a, w).propagator(7.0);
    for s in [1e-150, 1e-20, 1e20, 1e150] {
        let p = motion(i, a, w * s).propagator(7.0 / s);
        assert!(p.is_finite(), "s = {s}");
        assert!(
            max_abs(p - base) < 1e-13,
            "s = {s}: {:e}",
            max_abs(p - base)
        );
    }
}

#[test]
fn linear_rotor_drops_its_spin_and_matches_the_axis_propagator() {
    let a = some_attitude();
    let w = DVec3::new(5.0, -1.1, 1.9); // 5.0 about the rod axis (body x) is dropped
    let m = motion([0.0, 1.154, 1.154], a, w);
    assert_eq!(m.kind(), MotionKind::LinearRotor);
    assert_eq!(m.initial_pose().omega, DVec3::new(0.0, -1.1, 1.9));
    let rod = LinearRotor::new(a.row(0), m.pose(0.0).omega_lab()).unwrap();
    for t in [0.3, 3.0, 3e3] {
        let s = m.pose(t).lab_vector(DVec3::X);
        assert!((s - rod.axis(t)).length() < 1e-12, "t={t}");
    }
    // Spin about the rod axis only: the rod is at rest.
    assert_eq!(
        motion([0.0, 1.0, 1.0], a, DVec3::X).kind(),
        MotionKind::Rest
    );
}

#[test]
fn bad_states_are_refused() {
    let i = Moments::new([1.0, 2.0, 3.0]).unwrap();
    let nan = DVec3::new(f64::NAN, 0.0, 0.0);
    assert_eq!(
        FreeMotion::new(&i, DMat3::IDENTITY, nan).unwrap_err(),
        FreeError::NonFiniteVector {
            what: "angular velocity"
        }
    );
    let reflection = DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0));
    let e = FreeMotion::new(&i, reflection, DVec3::ONE).unwrap_err();
    assert!(e.to_string().contains("not a proper rotation"), "{e}");
    assert!(FreeMotion::from_quat(&i, DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0), DVec3::ONE).is_err());
}
