//! Benchmarks of `rigid-free`: set-up per state and evaluation at a new time for each kind of
//! body, against baselines measured in the same run (one libm sine + cosine, the floor of any
//! evaluation; one RK4 step of Euler's equations + dA/dt, the unit of cost of the alternative).
//!
//! Run with `cargo bench -p dmd-benches --bench rigid_free`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DMat3, DQuat, DVec3};
use rigid_free::elliptic::Jacobi;
use rigid_free::{FreeMotion, LinearRotor, Moments, attitude_from_quat};
use std::hint::black_box;

fn attitude() -> DMat3 {
    attitude_from_quat(DQuat::from_xyzw(0.3, -0.5, 0.1, 0.8))
}

/// One RK4 step of Euler's equations and dA/dt = −W(ω) A (the baseline integrator).
fn rk4_step(i: DVec3, a: DMat3, w: DVec3, h: f64) -> (DMat3, DVec3) {
    let f = |a: DMat3, w: DVec3| {
        let wd = (i * w).cross(w) / i;
        let ad = DMat3::from_cols(-w.cross(a.x_axis), -w.cross(a.y_axis), -w.cross(a.z_axis));
        (ad, wd)
    };
    let (k1a, k1w) = f(a, w);
    let (k2a, k2w) = f(a + k1a * (0.5 * h), w + k1w * (0.5 * h));
    let (k3a, k3w) = f(a + k2a * (0.5 * h), w + k2w * (0.5 * h));
    let (k4a, k4w) = f(a + k3a * h, w + k3w * h);
    (
        a + (k1a + k2a * 2.0 + k3a * 2.0 + k4a) * (h / 6.0),
        w + (k1w + k2w * 2.0 + k3w * 2.0 + k4w) * (h / 6.0),
    )
}

/// Evaluations at a new time each iteration (a root search never repeats a time).
fn bench_eval(c: &mut Criterion, name: &str, motion: &FreeMotion) {
    c.bench_function(name, |b| {
        let mut t = 0.37;
        b.iter(|| {
            t += 0.013;
            black_box(motion.pose(black_box(t)))
        })
    });
}

fn benches(c: &mut Criterion) {
    let a = attitude();
    let w = DVec3::new(0.7, -1.1, 1.9);
    let asym = Moments::new([1.3, 1.9, 2.6]).unwrap();
    let sym = Moments::new([1.3, 1.3, 2.6]).unwrap();
    let sphere = Moments::new([1.3, 1.3, 1.3]).unwrap();

    // Baselines.
    c.bench_function("baseline/sin_cos", |b| {
        let mut x = 0.37_f64;
        b.iter(|| {
            x += 0.013;
            black_box(black_box(x).sin_cos())
        })
    });
    c.bench_function("baseline/rk4_step", |b| {
        let i = DVec3::new(1.3, 1.9, 2.6);
        b.iter(|| black_box(rk4_step(i, black_box(a), black_box(w), 1e-3)))
    });

    // Set-up per state.
    c.bench_function("setup/asymmetric", |b| {
        b.iter(|| black_box(FreeMotion::new(&asym, black_box(a), black_box(w)).unwrap()))
    });
    let near_sep = DVec3::new((3.0f64 - 1e-13).sqrt(), 0.5, 1.0);
    let asym123 = Moments::new([1.0, 2.0, 3.0]).unwrap();
    c.bench_function("setup/asymmetric_near_separatrix", |b| {
        b.iter(|| black_box(FreeMotion::new(&asym123, black_box(a), black_box(near_sep)).unwrap()))
    });
    c.bench_function("setup/symmetric", |b| {
        b.iter(|| black_box(FreeMotion::new(&sym, black_box(a), black_box(w)).unwrap()))
    });
    c.bench_function("setup/sphere", |b| {
        b.iter(|| black_box(FreeMotion::new(&sphere, black_box(a), black_box(w)).unwrap()))
    });

    // Evaluation at a new time.
    let m_asym = FreeMotion::new(&asym, a, w).unwrap();
    bench_eval(c, "evaluate/asymmetric", &m_asym);
    bench_eval(
        c,
        "evaluate/asymmetric_near_separatrix",
        &FreeMotion::new(&asym123, a, near_sep).unwrap(),
    );
    bench_eval(
        c,
        "evaluate/symmetric",
        &FreeMotion::new(&sym, a, w).unwrap(),
    );
    bench_eval(
        c,
        "evaluate/sphere",
        &FreeMotion::new(&sphere, a, w).unwrap(),
    );
    c.bench_function("evaluate/asymmetric_omega_only", |b| {
        let mut t = 0.37;
        b.iter(|| {
            t += 0.013;
            black_box(m_asym.omega(black_box(t)))
        })
    });
    let rod = LinearRotor::new(DVec3::new(0.3, 0.4, 0.5), DVec3::new(-1.0, 2.0, 0.1)).unwrap();
    c.bench_function("evaluate/linear_rotor_axis", |b| {
        let mut t = 0.37;
        b.iter(|| {
            t += 0.013;
            black_box(rod.axis(black_box(t)))
        })
    });

    // The special function alone.
    for (name, m_c) in [
        ("jacobi/sn_cn_dn_m0.5", 0.5),
        ("jacobi/sn_cn_dn_mc1e-12", 1e-12),
    ] {
        let j = Jacobi::new(m_c).unwrap();
        c.bench_function(name, |b| {
            let mut u = 0.37;
            b.iter(|| {
                u += 0.013;
                black_box(j.sn_cn_dn(black_box(u)))
            })
        });
    }
}

criterion_group!(rigid_free, benches);
criterion_main!(rigid_free);
