//! Stiff and extreme events, set up physically: grazing contact, energy exactly at the barrier,
//! steps far larger than the kinetic energy, bad masses, linear bodies, non-finite input.

use collide::{
    CollideError, Contact, LinearBody, Outcome, PairForce, Particle, RigidBody, Velocity, contact,
    spheres, terrace,
};
use glam::{DQuat, DVec3};

fn kinetic(m: f64, v: DVec3) -> f64 {
    0.5 * m * v.length_squared()
}

#[test]
fn grazing_contact() {
    // Relative velocity perpendicular to the line of centres but for 1e-13 of it.
    let p = Particle::new(1.0).unwrap();
    let r = DVec3::X;
    let vi = DVec3::new(-1e-13, 1.0, 0.0);
    // Hard core: a reflection that only flips the tiny normal component.
    let hard = spheres(&p, &p, vi, DVec3::ZERO, r, f64::INFINITY).unwrap();
    assert_eq!(hard.impulse.outcome, Outcome::Reflected);
    assert_eq!((hard.i - hard.j).x, 1e-13);
    assert_eq!(hard.i.y, 1.0);
    // Barrier: same. Well: captured, with the normal speed the well depth gives.
    let barrier = spheres(&p, &p, vi, DVec3::ZERO, r, 0.5).unwrap();
    assert_eq!(barrier.impulse.outcome, Outcome::Reflected);
    let well = spheres(&p, &p, vi, DVec3::ZERO, r, -0.25).unwrap();
    assert_eq!(well.impulse.outcome, Outcome::Crossed);
    // ½ μ u² = 0.25 + tiny with μ = ½: u = -1 (still approaching).
    assert!(((well.i - well.j).x + 1.0).abs() < 1e-15);
    let e = kinetic(1.0, well.i) + kinetic(1.0, well.j) - kinetic(1.0, vi);
    assert!((e - 0.25).abs() < 1e-15);
}

#[test]
fn exactly_grazing_on_rigid_bodies() {
    // U̇ = 0 exactly: a barrier changes nothing; a well is entered in the direction of the sign
    // of the zero.
    let body = RigidBody::from_principal(1.0, DVec3::new(1.0, 2.0, 2.5), DQuat::IDENTITY).unwrap();
    let at = Contact::new(
        DVec3::X,
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.0, -1.0, 0.0),
    );
    let v = Velocity::new(DVec3::new(0.0, 0.0, 1.0), DVec3::ZERO);
    let out = contact(&body, &body, v, v, &at, 1.0).unwrap();
    assert_eq!(out.impulse.outcome, Outcome::Reflected);
    assert_eq!(out.impulse.s, 0.0);
    assert_eq!((out.i, out.j), (v, v));
}

#[test]
fn energy_exactly_at_the_barrier() {
    // Reduced mass ½, approach speed 2: ½ μ u² = 1 = ΔV exactly. The tie is a reflection.
    let p = Particle::new(1.0).unwrap();
    let out = spheres(
        &p,
        &p,
        DVec3::new(-2.0, 0.0, 0.0),
        DVec3::ZERO,
        DVec3::X,
        1.0,
    )
    .unwrap();
    assert_eq!(out.impulse.outcome, Outcome::Reflected);
    assert_eq!(out.i, DVec3::ZERO);
    assert_eq!(out.j, DVec3::new(-2.0, 0.0, 0.0));
    // 2⁻³⁰ more energy (exactly representable): it climbs, and leaves with the speed the
    // excess gives, ½ μ u² = 2⁻³⁰ → u = −2⁻¹⁴, to full precision despite the cancellation.
    let excess = 2f64.powi(-30);
    let up = spheres(
        &p,
        &p,
        DVec3::new(-2.0, 0.0, 0.0),
        DVec3::ZERO,
        DVec3::X,
        1.0 - excess,
    )
    .unwrap();
    assert_eq!(up.impulse.outcome, Outcome::Crossed);
    let u = (up.i - up.j).x;
    let expected = -(2f64.powi(-14));
    assert!((u / expected - 1.0).abs() < 1e-12, "{u} vs {expected}");
}

#[test]
fn steps_far_beyond_the_kinetic_energy() {
    let (light, heavy) = (Particle::new(1e-3).unwrap(), Particle::new(1e3).unwrap());
    let (vi, vj) = (DVec3::new(-3.0, 1.0, 0.5), DVec3::new(0.01, 0.0, -0.02));
    let r = DVec3::new(1.0, 0.2, -0.1);
    let k = kinetic(1e-3, vi) + kinetic(1e3, vj);
    for factor in [1e8, 1e15, 1e30] {
        let up = spheres(&light, &heavy, vi, vj, r, factor * k).unwrap();
        assert_eq!(up.impulse.outcome, Outcome::Reflected);
        let k_up = kinetic(1e-3, up.i) + kinetic(1e3, up.j);
        assert!((k_up - k).abs() <= 1e-14 * k);
        let down = spheres(&light, &heavy, vi, vj, r, -factor * k).unwrap();
        assert_eq!(down.impulse.outcome, Outcome::Crossed);
        let k_down = kinetic(1e-3, down.i) + kinetic(1e3, down.j);
        assert!(
            (k_down - k - factor * k).abs() <= 1e-14 * factor * k,
            "{factor}"
        );
        let p0 = 1e-3 * vi + 1e3 * vj;
        let p1 = 1e-3 * down.i + 1e3 * down.j;
        assert!((p1 - p0).length() <= 1e-14 * (1e-3 * down.i.length() + 1e3 * down.j.length()));
    }
}

#[test]
fn zero_and_negative_masses_are_refused() {
    for m in [0.0, -1.0, f64::NAN] {
        assert!(matches!(Particle::new(m), Err(CollideError::Mass(_))));
        let msg = Particle::new(m).unwrap_err().to_string();
        assert!(msg.contains("mass must be positive and finite"), "{msg}");
        assert!(LinearBody::new(m, 1.0, DVec3::X).is_err());
        assert!(RigidBody::from_principal(m, DVec3::ONE, DQuat::IDENTITY).is_err());
    }
}

#[test]
fn linear_body_with_one_zero_moment() {
    // A rod (moments I, I, 0) hit off-centre: its spin stays perpendicular to its axis and the
    // impulse conserves energy and angular momentum about the lab origin.
    let axis = DVec3::new(1.0, 1.0, 0.0).normalize();
    let rod = LinearBody::new(2.0, 0.5, axis).unwrap();
    let ball = Particle::new(1.0).unwrap();
    let (pos_rod, arm) = (DVec3::new(0.0, 0.0, 0.0), axis * 0.7);
    let normal = DVec3::new(0.0, 0.3, 1.0).normalize();
    let pos_ball = pos_rod + arm + normal * 0.5;
    let at = Contact::new(normal, arm, DVec3::ZERO);
    let w0 = DVec3::new(0.0, 0.0, 0.4);
    let v_rod = Velocity::new(DVec3::new(0.1, 0.0, 0.2), w0);
    let v_ball = Velocity::new(DVec3::new(0.0, -0.5, -1.0), DVec3::ZERO);
    let out = contact(&rod, &ball, v_rod, v_ball, &at, f64::INFINITY).unwrap();
    assert!(out.i.angular.dot(axis).abs() < 1e-16);
    assert!(out.i.angular != w0);
    // Inertia of the rod: 0.5 (1 − s sᵀ); its spin is perpendicular to s.
    let l_spin = |w: DVec3| 0.5 * (w - w.dot(axis) * axis);
    let e = |v: Velocity, u: Velocity| {
        kinetic(2.0, v.linear) + 0.5 * v.angular.dot(l_spin(v.angular)) + kinetic(1.0, u.linear)
    };
    let l = |v: Velocity, u: Velocity| {
        pos_rod.cross(2.0 * v.linear) + l_spin(v.angular) + pos_ball.cross(1.0 * u.linear)
    };
    assert!((e(out.i, out.j) - e(v_rod, v_ball)).abs() < 1e-15);
    assert!((l(out.i, out.j) - l(v_rod, v_ball)).length() < 1e-15);
    // A torque along the rod's axis cannot be delivered.
    let axial = PairForce::new(DVec3::X, axis, DVec3::ZERO);
    assert!(matches!(
        terrace(&rod, &ball, v_rod, v_ball, &axial, 1.0),
        Err(CollideError::AxialTorque { .. })
    ));
}

#[test]
fn non_finite_input_is_an_error_not_nan() {
    let p = Particle::new(1.0).unwrap();
    for bad in [f64::NAN, f64::INFINITY] {
        let v = DVec3::new(bad, 0.0, 0.0);
        let err = spheres(&p, &p, v, DVec3::ZERO, DVec3::X, 1.0).unwrap_err();
        assert!(matches!(err, CollideError::NotFinite(_)), "{err}");
        let err = spheres(
            &p,
            &p,
            DVec3::ZERO,
            DVec3::ZERO,
            DVec3::new(bad, 1.0, 0.0),
            1.0,
        )
        .unwrap_err();
        assert!(matches!(err, CollideError::NotFinite(_)), "{err}");
    }
    let err = spheres(&p, &p, DVec3::X, DVec3::ZERO, DVec3::X, f64::NAN).unwrap_err();
    assert!(matches!(err, CollideError::PotentialChange(x) if x.is_nan()));
    assert!(err.to_string().contains("potential-energy change"));
}
