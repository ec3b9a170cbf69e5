//! Shared set-ups of the integration tests.
#![allow(dead_code, unreachable_pub)]

use potential::{LennardJones, LjRod, Smoothed};
use smd::{BodyModel, Integrator, Lattice, Settings, Setup, System, units};

/// The paper's rods (kJ/mol, Å, g/mol) at ρ* = 0.5, T* = 1.4: `n` of them on a simple cubic
/// lattice, equilibrated for `eq_steps` steps of 1.8 fs with velocity rescaling.
pub fn rods(n: usize, eq_steps: u64, seed: u64) -> Integrator<Smoothed<LjRod>> {
    let rod = LjRod::paper();
    let kt = 1.4 * rod.epsilon();
    let setup = Setup {
        lattice: Lattice::Sc,
        seed,
        ..Setup::new(
            n,
            units::density_from_reduced(0.5, rod.sigma()),
            BodyModel::paper_rod(),
            kt,
        )
    };
    let mut md = Integrator::new(
        System::new(&setup).unwrap(),
        Smoothed::paper(rod, rod.sigma()).unwrap(),
        Settings::new(units::from_fs(1.8), 1.0),
    )
    .unwrap();
    md.equilibrate(eq_steps, 25, kt).unwrap();
    md
}

/// Lennard-Jones spheres in reduced units at ρ* = 0.5, T* = 2 (fcc), equilibrated.
pub fn lj(n: usize, eq_steps: u64, dt: f64) -> Integrator<Smoothed<LennardJones>> {
    let setup = Setup::new(n, 0.5, BodyModel::sphere(1.0).unwrap(), 2.0);
    let mut md = Integrator::new(
        System::new(&setup).unwrap(),
        Smoothed::paper(LennardJones::new(1.0, 1.0).unwrap(), 1.0).unwrap(),
        Settings::new(dt, 0.4),
    )
    .unwrap();
    md.equilibrate(eq_steps, 25, 2.0).unwrap();
    md
}

/// The same system and potential with another time step (same state, fresh lists).
pub fn with_dt<P: potential::PairPotential + Clone>(
    md: &Integrator<Smoothed<P>>,
    dt: f64,
) -> Integrator<Smoothed<P>> {
    Integrator::new(
        md.system().clone(),
        md.potential().clone(),
        Settings::new(dt, 1.0f64.min(0.1 * md.system().lengths().min_element())),
    )
    .unwrap()
}

/// Total energies sampled every `every` steps over `steps` steps.
pub fn energies<P: potential::PairPotential>(
    md: &mut Integrator<Smoothed<P>>,
    steps: u64,
    every: u64,
) -> Vec<f64> {
    struct E(Vec<f64>);
    impl smd::Observer for E {
        fn sample(&mut self, s: &smd::Snapshot<'_>) {
            self.0.push(s.energy.total());
        }
    }
    let mut e = E(Vec::new());
    md.run(steps, every, &mut e).unwrap();
    e.0
}

/// Standard deviation.
pub fn std_dev(x: &[f64]) -> f64 {
    let m = x.iter().sum::<f64>() / x.len() as f64;
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
}
