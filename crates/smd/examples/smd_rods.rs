//! Standard MD of the paper's rods at its state point (003 §V: N = 512, ρ* = 0.5, T* = 1.4,
//! ε = 3 kJ/mol, σ = 3.035 Å, ζ = 1 Å, m = 18 g/mol, I = 1.154 g/mol·Å², dt = 1.8 fs, the
//! potential smoothed between 2.5σ and 3σ), printing a summary of the observables.
//!
//! ```sh
//! cargo run --release -p dmd-smd --example smd_rods -- [--n 512] [--dt-fs 1.8] \
//!     [--equilibration-ps 5] [--production-ps 20] [--skin 2.0] [--seed 1] [--out DIR] \
//!     [--rho-star 0.5] [--t-star 1.4]
//! ```
//!
//! With `--out DIR` the observables are written there as CSV (rdf, msd, vacf, orientation,
//! series). Units: kJ/mol, Å, g/mol; the internal time unit is 0.1 ps.

use potential::{LjRod, Smoothed};
use smd::run::{CorrelationConfig, RdfConfig, RunConfig, run};
use smd::{BodyModel, Lattice, Settings, Setup, units};

fn main() {
    if let Err(e) = real_main() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> Result<T, String> {
    match args.iter().position(|a| a == name) {
        None => Ok(default),
        Some(k) => args
            .get(k + 1)
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| format!("{name} needs a value")),
    }
}

fn real_main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = arg(&args, "--n", 512)?;
    let dt_fs: f64 = arg(&args, "--dt-fs", 1.8)?;
    let eq_ps: f64 = arg(&args, "--equilibration-ps", 5.0)?;
    let prod_ps: f64 = arg(&args, "--production-ps", 20.0)?;
    let skin: f64 = arg(&args, "--skin", 2.0)?;
    let seed: u64 = arg(&args, "--seed", 1)?;
    let rho_star: f64 = arg(&args, "--rho-star", 0.5)?;
    let t_star: f64 = arg(&args, "--t-star", 1.4)?;
    let out: Option<String> =
        arg(&args, "--out", String::new()).map(|s| Some(s).filter(|s| !s.is_empty()))?;

    let rod = LjRod::paper();
    let kt = t_star * rod.epsilon();
    let dt = units::from_fs(dt_fs);
    let steps = |ps: f64| (units::from_ps(ps) / dt).round() as u64;
    let sample_every = (units::from_fs(9.0) / dt).round().max(1.0) as u64;
    let cube = (n as f64).cbrt().round() as usize;
    let config = RunConfig {
        setup: Setup {
            lattice: if cube.pow(3) == n {
                Lattice::Sc
            } else {
                Lattice::Fcc
            },
            seed,
            ..Setup::new(
                n,
                units::density_from_reduced(rho_star, rod.sigma()),
                BodyModel::paper_rod(),
                kt,
            )
        },
        settings: Settings::new(dt, skin),
        equilibration_steps: steps(eq_ps),
        rescale_every: 50,
        production_steps: steps(prod_ps),
        sample_every,
        rdf: Some(RdfConfig::default()),
        correlations: Some(CorrelationConfig {
            max_lag: units::from_ps(1.0),
            origin_every: 10,
        }),
    };
    let smoothed = Smoothed::paper(rod, rod.sigma())?;
    let result = run(&config, smoothed)?;
    let s = &result.summary;
    let p = &result.production;
    println!("# SMD of the paper's rods (003 §V.B)");
    println!(
        "N = {n}, rho* = {rho_star}, T* = {t_star} (kT = {kt:.4} kJ/mol), dt = {dt_fs} fs, skin = {skin} A, \
         {eq_ps} ps equilibration + {prod_ps} ps NVE"
    );
    println!(
        "T*          = {:.4} ± {:.4}   (translational {:.4})",
        s.temperature.mean / rod.epsilon(),
        s.temperature.error / rod.epsilon(),
        s.temperature_translational.mean / rod.epsilon()
    );
    println!(
        "U/N         = {:.4} ± {:.4} kJ/mol   (U/Nε = {:.4})",
        s.potential_per_body.mean,
        s.potential_per_body.error,
        s.potential_per_body.mean / rod.epsilon()
    );
    println!(
        "P           = {:.1} ± {:.1} bar",
        s.pressure.mean * units::PASCAL_PER_PRESSURE_UNIT / 1e5,
        s.pressure.error * units::PASCAL_PER_PRESSURE_UNIT / 1e5
    );
    println!(
        "energy      : std(E)/|<U>| = {:.3e}, std(E)/std(U) = {:.3e} (paper: about 1 % at 1.8 fs), drift = {:.3e} kJ/mol per body per ps",
        s.relative_fluctuation,
        s.fluctuation_over_potential_std,
        s.drift_per_body / units::to_ps(1.0)
    );
    if let Some(c) = &result.observables.correlations {
        if let Some(d) = c.diffusion_from_msd() {
            println!(
                "D (MSD)     = {:.4e} A^2/ps = {:.4e} cm^2/s",
                d / units::to_ps(1.0),
                d / units::to_ps(1.0) * 1e-4
            );
        }
        let v = c.vacf_normalised();
        if let Some(&(t, _)) = v.iter().find(|p| p.1 < 0.0) {
            println!("VACF        : first negative at {:.3} ps", units::to_ps(t));
        }
        let o = c.orientation_p1();
        if let Some(&(t, x)) = o.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
            println!(
                "<s(0).s(t)> : minimum {x:.4} at {:.3} ps (paper, Fig. 5: anticorrelation near 0.15 ps)",
                units::to_ps(t)
            );
        }
    }
    println!(
        "cost        : {:.1} ns per particle-step, {:.3} CPU s per ps (observables included), {:.1} steps per list build, {:.1} pairs within r_u per body",
        p.ns_per_particle_step(),
        p.seconds() / units::to_ps(p.simulated_time),
        p.steps_per_build(),
        p.pair_evaluations as f64 / (p.steps.max(1) as f64 * n as f64)
    );
    if let Some(dir) = out {
        let files = result.observables.write_csv(std::path::Path::new(&dir))?;
        println!("wrote {} in {dir}", files.join(", "));
    }
    Ok(())
}
