//! Reversibility, conservation of momentum and angular momentum, the linear-rotor invariant,
//! the forces against a brute-force sum, and loud failure of unstable steps.

use crate::common;
use glam::{DMat3, DQuat, DVec3};
use potential::{LennardJones, LjRod, PairGeometry, PairPotential, Smoothed};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use smd::{
    BodyModel, Integrator, Observer, Orientations, Settings, Setup, SmdError, Snapshot, System,
    units,
};

fn unit(r: &mut Xoshiro256PlusPlus) -> DVec3 {
    loop {
        let v = DVec3::new(
            r.random::<f64>() - 0.5,
            r.random::<f64>() - 0.5,
            r.random::<f64>() - 0.5,
        );
        if let Some(u) = v.try_normalize() {
            return u;
        }
    }
}

/// Runs `steps` forward, reverses the momenta, runs `steps` back, reverses again, and returns
/// the largest deviation of positions (unwrapped) and axes from the start.
fn round_trip<P: PairPotential>(md: &mut Integrator<Smoothed<P>>, steps: u64) -> (f64, f64) {
    let s = md.system();
    let r0: Vec<DVec3> = (0..s.n()).map(|i| s.unwrapped(i)).collect();
    let a0 = s.axes().to_vec();
    let v0 = s.velocities().to_vec();
    md.run(steps, steps, &mut ()).unwrap();
    let s = md.system();
    let moved = (0..s.n())
        .map(|i| (s.unwrapped(i) - r0[i]).length())
        .fold(0.0, f64::max);
    assert!(moved > 0.01, "the bodies must have moved ({moved})");
    md.reverse_momenta();
    md.run(steps, steps, &mut ()).unwrap();
    md.reverse_momenta();
    let s = md.system();
    let dr = (0..s.n())
        .map(|i| (s.unwrapped(i) - r0[i]).length())
        .fold(0.0, f64::max);
    let da = s
        .axes()
        .iter()
        .zip(&a0)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    let dv = s
        .velocities()
        .iter()
        .zip(&v0)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    eprintln!("round trip of {steps} steps: |dr| {dr:.2e}, |ds| {da:.2e}, |dv| {dv:.2e}");
    (dr, da)
}

/// Out and back, the trajectory retraces itself to round-off. Round-off itself grows
/// exponentially along a chaotic trajectory (measured for the rods: ~1e-14 Å after 2 × 25
/// steps, ~1e-13 after 2 × 100, ~1e-11 after 2 × 200, ~1e-9 after 2 × 300: a Lyapunov exponent
/// of about 13/ps), so the trips are kept short; an irreversible step (a one-sided kick, a
/// drift that is not the exact flow) would show up at once, at 1e-6 or worse.
#[test]
fn time_reversible_to_round_off() {
    let rods = common::rods(256, 200, 3);
    let lj = common::lj(256, 200, 0.005);
    let tops = tops(256, 5);
    let side = rods.system().lengths().x;
    for steps in [25, 100] {
        let bound = if steps == 25 { 1e-13 } else { 1e-10 };
        let (dr, ds) = round_trip(&mut rods.clone(), steps);
        assert!(
            dr < bound * side && ds < bound,
            "rods, {steps} steps: {dr} {ds}"
        );
        let (dr, _) = round_trip(&mut lj.clone(), steps);
        assert!(
            dr < bound * lj.system().lengths().x,
            "spheres, {steps} steps: {dr}"
        );
        let (dr, ds) = round_trip(&mut tops.clone(), steps);
        assert!(
            dr < bound * side && ds < bound,
            "tops, {steps} steps: {dr} {ds}"
        );
    }
}

/// Asymmetric tops (moments 0.8, 1.154, 1.5 g/mol·Å²) carrying the paper's rod potential along
/// their body z axis, at the rods' state point.
fn tops(n: usize, seed: u64) -> Integrator<Smoothed<LjRod>> {
    let rod = LjRod::paper();
    let kt = 1.4 * rod.epsilon();
    let body = BodyModel::rigid(18.0, [0.8, 1.154, 1.5], DVec3::Z).unwrap();
    let setup = Setup {
        seed,
        ..Setup::new(n, units::density_from_reduced(0.5, rod.sigma()), body, kt)
    };
    let mut md = Integrator::new(
        System::new(&setup).unwrap(),
        Smoothed::paper(rod, rod.sigma()).unwrap(),
        Settings::new(units::from_fs(1.8), 1.0),
    )
    .unwrap();
    md.equilibrate(200, 25, kt).unwrap();
    md
}

#[test]
fn tops_conserve_energy_and_follow_dt_squared() {
    let base = tops(256, 9);
    let mut fluct = Vec::new();
    for dt_fs in [0.9, 0.45] {
        let mut md = common::with_dt(&base, units::from_fs(dt_fs));
        let steps = (180.0 / dt_fs) as u64;
        let e = common::energies(&mut md, steps, (1.8 / dt_fs) as u64);
        fluct.push(common::std_dev(&e));
    }
    let ratio = fluct[0] / fluct[1];
    eprintln!("tops: std(E) {fluct:?}, ratio {ratio:.3}");
    assert!((ratio - 4.0).abs() < 0.6, "{ratio}");
    // Against N kT = 1075 kJ/mol: a few parts in 10⁴ at 0.9 fs.
    assert!(fluct[0] < 5e-4 * 256.0 * 4.2, "{}", fluct[0]);
}

/// A cluster of 27 bodies in a box far larger than the cut-off: no periodic image is ever
/// within reach, so the total angular momentum about the centre of mass is conserved, as
/// is the momentum. This checks the torques against the forces (003 Eq. 6) as the integrator
/// applies them, and that the drift moves orientations the way the kick's torques assume.
fn cluster(body: BodyModel, seed: u64) -> System {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let spacing = 3.6;
    let centre = DVec3::splat(100.0);
    let mut pos = Vec::new();
    for x in 0..3 {
        for y in 0..3 {
            for z in 0..3 {
                let jitter = unit(&mut rng) * 0.2;
                pos.push(
                    centre + (DVec3::new(x as f64, y as f64, z as f64) - 1.0) * spacing + jitter,
                );
            }
        }
    }
    // Thermal velocities plus a rigid spin of the whole cluster about a tilted axis.
    let spin = DVec3::new(0.3, -0.5, 1.0) * 0.8;
    let vel: Vec<DVec3> = pos
        .iter()
        .map(|p| unit(&mut rng) * 3.0 * rng.random::<f64>() + spin.cross(*p - centre) * 0.1)
        .collect();
    let (orient, l) = match body {
        BodyModel::LinearRotor { .. } => {
            let axes: Vec<DVec3> = (0..27).map(|_| unit(&mut rng)).collect();
            let l = axes.iter().map(|s| s.cross(unit(&mut rng)) * 2.0).collect();
            (Orientations::Axes(axes), l)
        }
        BodyModel::Rigid { .. } => {
            let rots: Vec<DMat3> = (0..27)
                .map(|_| {
                    DMat3::from_quat(DQuat::from_axis_angle(
                        unit(&mut rng),
                        rng.random::<f64>() * 6.0,
                    ))
                })
                .collect();
            let l = (0..27).map(|_| unit(&mut rng) * 2.0).collect();
            (Orientations::Rotations(rots), l)
        }
        BodyModel::Sphere { .. } => (Orientations::None, Vec::new()),
    };
    System::from_parts(DVec3::splat(200.0), body, pos, vel, orient, l).unwrap()
}

#[test]
fn free_clusters_conserve_momentum_and_angular_momentum() {
    let rod = LjRod::paper();
    for body in [
        BodyModel::paper_rod(),
        BodyModel::rigid(18.0, [0.8, 1.154, 1.5], DVec3::Z).unwrap(),
        BodyModel::sphere(18.0).unwrap(),
    ] {
        let sys = cluster(body, 21);
        let com = |s: &System| (0..s.n()).map(|i| s.unwrapped(i)).sum::<DVec3>() / s.n() as f64;
        let c0 = com(&sys);
        let (p0, l0) = (sys.momentum(), sys.angular_momentum(c0));
        // The scale of the sums: Σ |r − c| m |v| + Σ |L|.
        let scale: f64 = (0..sys.n())
            .map(|i| (sys.unwrapped(i) - c0).length() * 18.0 * sys.velocities()[i].length())
            .sum::<f64>()
            + sys
                .angular_momenta()
                .iter()
                .map(|l| l.length())
                .sum::<f64>();
        let pscale: f64 = sys.velocities().iter().map(|v| 18.0 * v.length()).sum();
        let mut md = Integrator::new(
            sys,
            Smoothed::paper(rod, rod.sigma()).unwrap(),
            Settings::new(units::from_fs(1.8), 1.0),
        )
        .unwrap();
        let e0 = md.energy().total();
        md.run(1000, 1000, &mut ()).unwrap();
        let s = md.system();
        // The centre of mass moves uniformly: angular momentum about the moved centre.
        let c1 = c0 + p0 / (18.0 * 27.0) * md.time();
        let dp = (s.momentum() - p0).length() / pscale;
        let dl = (s.angular_momentum(c1) - l0).length() / scale;
        let de = (md.energy().total() - e0).abs() / md.energy().kinetic();
        eprintln!(
            "{body:?}: |dP| {dp:.2e}, |dL| {dl:.2e}, |dE|/K {de:.2e}, |L| {:.3e}",
            l0.length()
        );
        assert!(dp < 1e-13, "momentum {dp}");
        assert!(dl < 1e-11, "angular momentum {dl}");
        assert!(de < 1e-3, "energy {de}");
        assert!(
            l0.length() > 0.05 * scale,
            "the cluster must carry angular momentum"
        );
    }
}

/// At every sample, each rod's angular momentum is perpendicular to its axis and the axis is a
/// unit vector: the torques the kick applies are those of the current axes.
#[test]
fn linear_rotors_stay_linear_rotors() {
    struct Check(f64, f64, usize);
    impl Observer for Check {
        fn sample(&mut self, s: &Snapshot<'_>) {
            for (a, l) in s.system.axes().iter().zip(s.system.angular_momenta()) {
                self.0 = self.0.max(a.dot(*l).abs() / l.length());
                self.1 = self.1.max((a.length() - 1.0).abs());
            }
            self.2 += 1;
        }
    }
    let mut md = common::rods(256, 100, 17);
    let mut c = Check(0.0, 0.0, 0);
    md.run(1000, 10, &mut c).unwrap();
    eprintln!(
        "max |s·L|/|L| {:.2e}, max ||s| − 1| {:.2e} over {} samples",
        c.0, c.1, c.2
    );
    assert!(c.0 < 1e-12 && c.1 < 1e-13 && c.2 == 101);
}

/// The forces, torques, energy and virial of the list-based loop equal a direct sum over all
/// pairs with the minimum image, after the bodies have moved (lists rebuilt several times).
#[test]
fn forces_match_a_direct_sum_over_all_pairs() {
    let mut md = common::rods(256, 100, 23);
    md.run(100, 100, &mut ()).unwrap();
    assert!(md.builds() > 3);
    let s = md.system();
    let pot = *md.potential();
    let l = s.lengths();
    let n = s.n();
    let (mut f, mut t) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    let (mut u, mut w) = (0.0, 0.0);
    for i in 0..n {
        for j in i + 1..n {
            let mut d = s.positions()[i] - s.positions()[j];
            for a in 0..3 {
                d[a] -= l[a] * (d[a] / l[a]).round();
            }
            let e = pot
                .evaluate(&PairGeometry::new(d, s.axes()[i], s.axes()[j]))
                .unwrap();
            f[i] += e.force;
            f[j] -= e.force;
            t[i] += e.torque_i;
            t[j] += e.torque_j;
            u += e.energy;
            w += d.dot(e.force);
        }
    }
    let fscale = f.iter().map(|x| x.length()).fold(0.0, f64::max);
    let tscale = t.iter().map(|x| x.length()).fold(0.0, f64::max);
    for i in 0..n {
        assert!(
            (md.forces()[i] - f[i]).length() < 1e-12 * fscale,
            "force {i}"
        );
        assert!(
            (md.torques()[i] - t[i]).length() < 1e-12 * tscale,
            "torque {i}"
        );
    }
    let e = md.energy();
    assert!((e.potential - u).abs() < 1e-12 * u.abs());
    assert!((e.virial - w).abs() < 1e-11 * w.abs());
    // The total force vanishes (Newton's third law, pair by pair).
    let total: DVec3 = md.forces().iter().copied().sum();
    assert!(total.length() < 1e-12 * fscale * n as f64);
}

/// The same in an orthorhombic box with spheres: the list's image shifts follow each edge.
#[test]
fn forces_match_a_direct_sum_in_an_orthorhombic_box() {
    let setup = Setup {
        aspect: [1.0, 1.4, 0.75],
        ..Setup::new(600, 0.6, BodyModel::sphere(1.0).unwrap(), 1.5)
    };
    let pot = Smoothed::paper(LennardJones::new(1.0, 1.0).unwrap(), 1.0).unwrap();
    let mut md =
        Integrator::new(System::new(&setup).unwrap(), pot, Settings::new(0.004, 0.5)).unwrap();
    md.run(300, 300, &mut ()).unwrap();
    let s = md.system();
    let l = s.lengths();
    assert!(l.y > 1.3 * l.x && l.z < 0.8 * l.x);
    let n = s.n();
    let mut f = vec![DVec3::ZERO; n];
    let mut u = 0.0;
    for i in 0..n {
        for j in i + 1..n {
            let mut d = s.positions()[i] - s.positions()[j];
            for a in 0..3 {
                d[a] -= l[a] * (d[a] / l[a]).round();
            }
            let e = pot.evaluate(&PairGeometry::spheres(d)).unwrap();
            f[i] += e.force;
            f[j] -= e.force;
            u += e.energy;
        }
    }
    let scale = f.iter().map(|x| x.length()).fold(0.0, f64::max);
    for (i, (a, b)) in md.forces().iter().zip(&f).enumerate() {
        assert!((*a - *b).length() < 1e-12 * scale, "force {i}");
    }
    assert!((md.energy().potential - u).abs() < 1e-12 * u.abs());
}

#[test]
fn a_far_too_large_step_is_an_error_not_nan() {
    // The paper's rods at 7.2 fs (4× the paper's step): the libration of the rods is faster
    // than the step can follow.
    let base = common::rods(256, 100, 29);
    let mut md = common::with_dt(&base, units::from_fs(7.2));
    let err = md.run(200, 10, &mut ()).unwrap_err();
    eprintln!("{err}");
    assert!(matches!(
        err,
        SmdError::Unstable { .. } | SmdError::Overlap { .. }
    ));
    assert!(err.to_string().contains("time step"));
    // Lennard-Jones spheres at dt = 0.05 τ.
    let base = common::lj(256, 50, 0.005);
    let mut md = common::with_dt(&base, 0.05);
    let err = md.run(200, 10, &mut ()).unwrap_err();
    eprintln!("{err}");
    assert!(matches!(
        err,
        SmdError::Unstable { .. } | SmdError::Overlap { .. }
    ));
    // With the guard off the run still stops at the first non-finite energy or overlap.
    let mut md = Integrator::new(
        base.system().clone(),
        *base.potential(),
        Settings {
            guard: f64::INFINITY,
            ..Settings::new(0.05, 0.4)
        },
    )
    .unwrap();
    match md.run(100_000, 10, &mut ()) {
        Err(SmdError::Unstable { .. } | SmdError::Overlap { .. }) => {}
        other => panic!("expected an error, got {other:?}"),
    }
}

/// A head-on collision at a kinetic energy of 200 ε (T* ≈ 130): the step must resolve the
/// repulsive wall. A fine step conserves the energy; a coarse one is refused loudly.
#[test]
fn close_approach_at_high_temperature() {
    let lj = Smoothed::paper(LennardJones::new(1.0, 1.0).unwrap(), 1.0).unwrap();
    let state = |v: f64| {
        System::from_parts(
            DVec3::splat(10.0),
            BodyModel::sphere(1.0).unwrap(),
            vec![DVec3::new(3.4, 5.0, 5.0), DVec3::new(6.6, 5.0, 5.0)],
            vec![DVec3::new(v, 0.0, 0.0), DVec3::new(-v, 0.0, 0.0)],
            Orientations::None,
            Vec::new(),
        )
        .unwrap()
    };
    let v = 10.0; // K = 2 · ½ · 1 · 100 = 100 per body
    let mut fine = Integrator::new(state(v), lj, Settings::new(1e-4, 0.3)).unwrap();
    let e0 = fine.energy().total();
    let mut closest = f64::INFINITY;
    struct Gap<'a>(&'a mut f64);
    impl Observer for Gap<'_> {
        fn sample(&mut self, s: &Snapshot<'_>) {
            let d = (s.system.positions()[0] - s.system.positions()[1]).length();
            *self.0 = self.0.min(d);
        }
    }
    fine.run(4000, 1, &mut Gap(&mut closest)).unwrap();
    let de = (fine.energy().total() - e0).abs() / e0;
    eprintln!("fine step: closest approach {closest:.4} σ, |dE|/E {de:.2e}");
    assert!(
        closest < 0.8,
        "the pair must reach deep into the wall ({closest})"
    );
    assert!(de < 1e-4, "{de}");
    // Velocities reversed by the collision.
    assert!(fine.system().velocities()[0].x < -9.9);
    let mut coarse = Integrator::new(state(v), lj, Settings::new(0.02, 0.3)).unwrap();
    let err = coarse.run(100, 1, &mut ()).unwrap_err();
    eprintln!("{err}");
    assert!(matches!(
        err,
        SmdError::Unstable { .. } | SmdError::Overlap { .. }
    ));
}
