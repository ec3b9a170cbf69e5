//! The terraced dynamics sample the terraced model's canonical ensemble: event-driven runs of
//! Lennard-Jones spheres on terraces (`scenes/stepped-lj.toml` with the paper's levels, an
//! Andersen thermostat throughout) against a Metropolis Monte Carlo of the same terraced
//! potential, written here from the formulas alone and sharing no code with the engine.
//!
//! Both sample the configurations of the terraced model at the bath temperature, so their
//! averages of the terraced energy ⟨V⟩/N, of the smooth estimator U/N and of the smooth
//! configurational pressure W/(3V) must agree within the statistics at any ΔV, however far the
//! terraced model is from the continuous one: a wrong terrace map, impulse, thermostat or
//! estimator shows as a difference. The Monte Carlo's terraced potential is
//! V = ΔV·⌊U/ΔV + ½⌋ where the Lennard-Jones U < core (0 beyond the outermost level, where
//! |U| < ΔV/2) and a hard core where U ≥ core; the smooth potential is U cut and switched
//! by a cubic between 2.5σ and 3σ, as the smd engine's.
//!
//! The paper's rods (`scenes/rods-paper.toml`, kT/2 terraces) are compared the same way in
//! ⟨V⟩/N: rigid linear rotors whose events follow the rigid-body impulse rule (003 Eq. 21),
//! against Metropolis moves of a rod's centre and axis (the axis uniform on the sphere at
//! equilibrium, the linear rotor's orientational measure).
//!
//! The check can fail: a Monte Carlo 3.3 % too cold fails the quick run by 8.6 standard
//! errors in the spheres' ⟨V⟩/N (5.5 in U/N) and by 4.2 in the rods' ⟨V⟩/N.
//!
//! Prints a Markdown report on stdout and exits non-zero if a difference exceeds
//! [`SIGMAS`] combined standard errors. `--quick` runs the CI-sized version; `--figures DIR`
//! is accepted for symmetry with the other validations (no figure is written). Every seed is
//! fixed, so the report is reproducible to the last digit on one build.

use std::fmt::Write as _;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use dmd_sim::run::{Quiet, Summary, run_scene};
use dmd_sim::scene::Scene;
use rayon::prelude::*;

/// The largest accepted difference, in combined standard errors.
const SIGMAS: f64 = 3.0;
/// Bath temperature (ε) and number density (σ⁻³) of `scenes/stepped-lj.toml`.
const KT: f64 = 1.5;
const DENSITY: f64 = 0.5;
/// The smooth potential's switching window (σ).
const R_SWITCH: f64 = 2.5;
const R_CUT: f64 = 3.0;
/// Terrace energy above which the pair is a hard core (ε), as `terraces.core`.
const CORE: f64 = 10.0;

/// One state of the comparison.
struct Case {
    /// Terrace step ΔV (ε).
    step: f64,
    /// Spheres: an fcc lattice of 4n³, so the Monte Carlo and the engine start alike.
    n: usize,
    /// Event-driven runs (seeds) and their equilibration and production times (τ).
    runs: u64,
    equilibration: f64,
    production: f64,
    /// Monte Carlo chains (seeds) and sweeps of each (the first tenth discarded).
    chains: u64,
    sweeps: usize,
}

const FULL: &[Case] = &[
    Case {
        step: 0.125,
        n: 256,
        runs: 16,
        equilibration: 10.0,
        production: 100.0,
        chains: 4,
        sweeps: 40_000,
    },
    Case {
        step: 0.0625,
        n: 256,
        runs: 16,
        equilibration: 10.0,
        production: 100.0,
        chains: 4,
        sweeps: 40_000,
    },
];

const QUICK: &[Case] = &[Case {
    step: 0.125,
    n: 256,
    runs: 8,
    equilibration: 5.0,
    production: 30.0,
    chains: 2,
    sweeps: 20_000,
}];

/// Plain Lennard-Jones in reduced units: `(U, r dU/dr)` at squared distance `r2`.
fn lennard_jones(r2: f64) -> (f64, f64) {
    let s6 = 1.0 / (r2 * r2 * r2);
    let s12 = s6 * s6;
    (4.0 * (s12 - s6), -48.0 * s12 + 24.0 * s6)
}

/// The smooth potential: Lennard-Jones times the cubic switch `S(r)` between `R_SWITCH` and
/// `R_CUT` (S = 1 below, 0 above, S' = 0 at both ends). Returns `(U, r dU/dr)`.
fn smooth(r2: f64) -> (f64, f64) {
    if r2 >= R_CUT * R_CUT {
        return (0.0, 0.0);
    }
    let (u, r_du) = lennard_jones(r2);
    if r2 <= R_SWITCH * R_SWITCH {
        return (u, r_du);
    }
    let r = r2.sqrt();
    let w3 = (R_CUT - R_SWITCH).powi(3);
    let (a, b) = (R_CUT - r, r - R_SWITCH);
    let s = a * a * (R_CUT - 3.0 * R_SWITCH + 2.0 * r) / w3;
    let ds = -6.0 * a * b / w3;
    (s * u, s * r_du + r * ds * u)
}

/// The terraced pair energy with the paper's levels (infinite inside the core).
fn terraced(r2: f64, step: f64) -> f64 {
    if r2 >= R_CUT * R_CUT {
        return 0.0;
    }
    let u = lennard_jones(r2).0;
    if u >= CORE {
        return f64::INFINITY;
    }
    // |U| < ΔV/2 rounds to the zero terrace: beyond the outermost level V = 0.
    step * (u / step + 0.5).floor()
}

/// xorshift64*: a small generator of the Monte Carlo's own, independent of the engine's.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Averages of one sampler: ⟨V⟩/N, smooth U/N and smooth W/(3V), each with its error.
#[derive(Clone, Copy)]
struct Averages {
    terraced: (f64, f64),
    smooth: (f64, f64),
    virial: (f64, f64),
}

/// Mean and standard error over 20 equal blocks of a correlated series.
fn blocked(series: &[f64]) -> (f64, f64) {
    let blocks = 20;
    let len = series.len() / blocks;
    let means: Vec<f64> = series
        .chunks_exact(len)
        .map(|c| c.iter().sum::<f64>() / len as f64)
        .collect();
    mean_error(&means)
}

/// Mean and standard error of independent values.
fn mean_error(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// One Metropolis chain of single-particle moves from the fcc lattice.
fn monte_carlo(case: &Case, seed: u64) -> Averages {
    let cells = ((case.n / 4) as f64).cbrt().round() as usize;
    let edge = (case.n as f64 / DENSITY).cbrt();
    let a = edge / cells as f64;
    let basis = [
        [0.0, 0.0, 0.0],
        [0.5, 0.5, 0.0],
        [0.5, 0.0, 0.5],
        [0.0, 0.5, 0.5],
    ];
    let mut x: Vec<[f64; 3]> = Vec::with_capacity(case.n);
    for i in 0..cells {
        for j in 0..cells {
            for k in 0..cells {
                for b in &basis {
                    x.push([
                        (i as f64 + b[0] + 0.25) * a,
                        (j as f64 + b[1] + 0.25) * a,
                        (k as f64 + b[2] + 0.25) * a,
                    ]);
                }
            }
        }
    }
    let n = x.len();
    let image = |d: f64| d - edge * (d / edge).round();
    let r2_of = |p: &[f64; 3], q: &[f64; 3]| {
        let d = [image(p[0] - q[0]), image(p[1] - q[1]), image(p[2] - q[2])];
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    };
    let energy_of = |x: &[[f64; 3]], i: usize, p: &[f64; 3]| {
        let mut e = 0.0;
        for (j, q) in x.iter().enumerate() {
            if j != i {
                e += terraced(r2_of(p, q), case.step);
            }
        }
        e
    };
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let mut delta = 0.3;
    let (mut accepted, mut tried) = (0usize, 0usize);
    let equilibration = case.sweeps / 10;
    let volume = edge * edge * edge;
    let (mut vs, mut us, mut ws) = (Vec::new(), Vec::new(), Vec::new());
    for sweep in 0..case.sweeps {
        for _ in 0..n {
            let i = ((rng.uniform() * n as f64) as usize).min(n - 1);
            let old = x[i];
            let mut new = old;
            for c in &mut new {
                *c = (*c + delta * (2.0 * rng.uniform() - 1.0)).rem_euclid(edge);
            }
            let e1 = energy_of(&x, i, &new);
            tried += 1;
            if e1.is_finite() {
                let e0 = energy_of(&x, i, &old);
                if e1 <= e0 || rng.uniform() < (-(e1 - e0) / KT).exp() {
                    x[i] = new;
                    accepted += 1;
                }
            }
        }
        // The step adapts during equilibration only, so production is a fixed Markov chain.
        if sweep < equilibration && sweep % 20 == 19 {
            let f = accepted as f64 / tried as f64;
            delta *= if f > 0.45 {
                1.1
            } else if f < 0.35 {
                0.9
            } else {
                1.0
            };
            (accepted, tried) = (0, 0);
        }
        if sweep >= equilibration && sweep % 2 == 0 {
            let (mut v, mut u, mut w) = (0.0, 0.0, 0.0);
            for i in 0..n {
                for j in i + 1..n {
                    let r2 = r2_of(&x[i], &x[j]);
                    v += terraced(r2, case.step);
                    let (e, r_du) = smooth(r2);
                    u += e;
                    w -= r_du;
                }
            }
            vs.push(v / n as f64);
            us.push(u / n as f64);
            ws.push(w / (3.0 * volume));
        }
    }
    Averages {
        terraced: blocked(&vs),
        smooth: blocked(&us),
        virial: blocked(&ws),
    }
}

/// Combines independent estimates of one mean: their average, with the larger of the
/// propagated errors and the standard error of their scatter.
fn combine(parts: &[(f64, f64)]) -> (f64, f64) {
    let k = parts.len() as f64;
    let values: Vec<f64> = parts.iter().map(|p| p.0).collect();
    let propagated = parts.iter().map(|p| p.1 * p.1).sum::<f64>().sqrt() / k;
    let (m, scatter) = mean_error(&values);
    (m, propagated.max(scatter))
}

/// A compared quantity: its name, `(value, reported error)` of one event-driven run, and its
/// `(mean, error)` from one Monte Carlo chain.
type Quantity = (
    &'static str,
    fn(&Summary) -> (f64, f64),
    fn(&Averages) -> (f64, f64),
);

/// The paper's rods (003 §V, `scenes/rods-paper.toml`): kJ/mol, Å; kT at 505.144 K.
mod rods {
    /// `ε`, `σ`, `ζ` of 003 Eqs. 22–23.
    pub(crate) const EPSILON: f64 = 3.0;
    pub(crate) const SIGMA: f64 = 3.035;
    pub(crate) const ZETA: f64 = 1.0;
    /// kT = R · 505.144 K (T* = 1.4).
    pub(crate) const KT: f64 = 8.314_462_618e-3 * 505.144;
    /// Number density (Å⁻³): ρσ³ = 0.5.
    pub(crate) const DENSITY: f64 = 0.017_885_380_6;
    /// The default hard core, 100 ε.
    pub(crate) const CORE: f64 = 100.0 * EPSILON;

    /// The rods' Lennard-Jones of the effective distance `r_e = r + ζ(½ − (s_i·s_j)²)`.
    pub(crate) fn energy(r: f64, c: f64) -> f64 {
        let re = r + ZETA * (0.5 - c * c);
        if re <= 0.0 {
            return f64::INFINITY;
        }
        let x = (SIGMA / re).powi(6);
        4.0 * EPSILON * (x * x - x)
    }

    /// The terraced energy with the paper's levels at step `step` (kJ/mol).
    pub(crate) fn terraced(r: f64, c: f64, step: f64) -> f64 {
        let u = energy(r, c);
        if u >= CORE {
            return f64::INFINITY;
        }
        // No test on r: near-parallel rods beyond σ can still be deep in the repulsion.
        step * (u / step + 0.5).floor()
    }
}

/// One Metropolis chain of the terraced rods: moves of one rod's centre and axis together
/// (the axis by a random vector in a ball, renormalised: a proposal symmetric in the angle),
/// from the simple cubic lattice with random axes; returns ⟨V⟩/N with its block error.
fn rods_monte_carlo(n: usize, step: f64, sweeps: usize, seed: u64) -> (f64, f64) {
    let side = (n as f64).cbrt().round() as usize;
    let edge = (n as f64 / rods::DENSITY).cbrt();
    let a = edge / side as f64;
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let ball = |rng: &mut Rng| loop {
        let v = [
            2.0 * rng.uniform() - 1.0,
            2.0 * rng.uniform() - 1.0,
            2.0 * rng.uniform() - 1.0,
        ];
        let q = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if q <= 1.0 && q > 1e-12 {
            return v;
        }
    };
    let unit = |v: [f64; 3]| {
        let q = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / q, v[1] / q, v[2] / q]
    };
    let mut x: Vec<[f64; 3]> = Vec::with_capacity(n);
    let mut s: Vec<[f64; 3]> = Vec::with_capacity(n);
    for i in 0..side {
        for j in 0..side {
            for k in 0..side {
                x.push([
                    (i as f64 + 0.5) * a,
                    (j as f64 + 0.5) * a,
                    (k as f64 + 0.5) * a,
                ]);
                let v = ball(&mut rng);
                s.push(unit(v));
            }
        }
    }
    let image = |d: f64| d - edge * (d / edge).round();
    let pair = |p: &[f64; 3], sp: &[f64; 3], q: &[f64; 3], sq: &[f64; 3]| {
        let d = [image(p[0] - q[0]), image(p[1] - q[1]), image(p[2] - q[2])];
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if r > 3.0 * rods::SIGMA {
            return 0.0;
        }
        let c = sp[0] * sq[0] + sp[1] * sq[1] + sp[2] * sq[2];
        rods::terraced(r, c, step)
    };
    let energy_of = |x: &[[f64; 3]], s: &[[f64; 3]], i: usize, p: &[f64; 3], sp: &[f64; 3]| {
        let mut e = 0.0;
        for j in 0..x.len() {
            if j != i {
                e += pair(p, sp, &x[j], &s[j]);
            }
        }
        e
    };
    let (mut shift, mut turn) = (0.3, 0.3);
    let (mut accepted, mut tried) = (0usize, 0usize);
    let equilibration = sweeps / 10;
    let mut vs = Vec::new();
    for sweep in 0..sweeps {
        for _ in 0..n {
            let i = ((rng.uniform() * n as f64) as usize).min(n - 1);
            let b = ball(&mut rng);
            let new_x = [
                (x[i][0] + shift * b[0]).rem_euclid(edge),
                (x[i][1] + shift * b[1]).rem_euclid(edge),
                (x[i][2] + shift * b[2]).rem_euclid(edge),
            ];
            let t = ball(&mut rng);
            let new_s = unit([
                s[i][0] + turn * t[0],
                s[i][1] + turn * t[1],
                s[i][2] + turn * t[2],
            ]);
            let e1 = energy_of(&x, &s, i, &new_x, &new_s);
            tried += 1;
            if e1.is_finite() {
                let e0 = energy_of(&x, &s, i, &x[i], &s[i]);
                if e1 <= e0 || rng.uniform() < (-(e1 - e0) / rods::KT).exp() {
                    x[i] = new_x;
                    s[i] = new_s;
                    accepted += 1;
                }
            }
        }
        if sweep < equilibration && sweep % 20 == 19 {
            let f = accepted as f64 / tried as f64;
            let k = if f > 0.45 {
                1.1
            } else if f < 0.35 {
                0.9
            } else {
                1.0
            };
            shift *= k;
            turn = (turn * k).min(2.0);
            (accepted, tried) = (0, 0);
        }
        if sweep >= equilibration && sweep % 2 == 0 {
            let mut v = 0.0;
            for i in 0..n {
                for j in i + 1..n {
                    v += pair(&x[i], &s[i], &x[j], &s[j]);
                }
            }
            vs.push(v / n as f64);
        }
    }
    blocked(&vs)
}

/// The paper's rods on kT/2 terraces against the Monte Carlo: ⟨V⟩/N only (their smooth
/// estimators switch the potential in `r_e`, which the check leaves to the `dmd-vs-smd` one).
/// Appends its report to `out`; returns whether it passed.
fn rods_case(quick: bool, out: &mut String) -> Result<bool, String> {
    let n = 216;
    let step = 0.5 * rods::KT;
    let (runs, equilibration, production, chains, sweeps) = if quick {
        (8u64, 4.0, 10.0, 2u64, 10_000)
    } else {
        (16, 5.0, 40.0, 4, 40_000)
    };
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/rods-paper.toml");
    let overrides: Vec<String> = vec![
        format!("species.0.count={n}"),
        "thermostat.during=always".into(),
        "thermostat.rate=20.0".into(),
        format!("run.equilibration_time={equilibration}"),
        format!("run.time={production}"),
        "output.sample_interval=0.01".into(),
        "output.series=false".into(),
        "output.rdf=".into(),
        "output.msd=".into(),
        "output.vacf=".into(),
        "output.orientation_acf=".into(),
    ];
    let wall = Instant::now();
    let runs = run_seeds(&scene_path, &overrides, runs)?;
    let dmd_wall = wall.elapsed().as_secs_f64();
    let parts: Vec<(f64, f64)> = (1..=chains)
        .into_par_iter()
        .map(|seed| rods_monte_carlo(n, step, sweeps, seed))
        .collect();
    let mc_wall = wall.elapsed().as_secs_f64() - dmd_wall;
    let cpu: f64 = runs.iter().map(|s| s.cpu_seconds).sum();
    let _ = writeln!(
        out,
        "**The paper's rods, ΔV = kT/2 = {step:.3} kJ/mol, N = {n}** (`scenes/rods-paper.toml`, \
         T = 505.144 K, Andersen thermostat at rate 20 per ps throughout; Monte Carlo moves of \
         one rod's centre and axis together, the axis uniform on the sphere at equilibrium): \
         {} event-driven runs of {production} ps after {equilibration} ps ({} CPU s, {:.0} s \
         wall clock); {chains} Monte Carlo chains of {sweeps} sweeps ({:.0} s wall clock).\n",
        runs.len(),
        cpu.round(),
        dmd_wall,
        mc_wall
    );
    let _ = writeln!(out, "{TABLE_HEAD}");
    let per_run: Vec<(f64, f64)> = runs
        .iter()
        .map(|s| {
            (
                s.potential_energy_per_body,
                s.potential_energy_per_body_error.unwrap_or(f64::NAN),
            )
        })
        .collect();
    let pass = compare(out, "terraced ⟨V⟩/N (kJ/mol)", &per_run, &parts);
    let _ = writeln!(out);
    Ok(pass)
}

/// Runs `scene` with `overrides` once for each seed `1..=runs`, in parallel, as `dmd run` does.
fn run_seeds(scene: &Path, overrides: &[String], runs: u64) -> Result<Vec<Summary>, String> {
    let name = scene
        .file_name()
        .map_or_else(String::new, |f| f.to_string_lossy().into_owned());
    (1..=runs)
        .into_par_iter()
        .map(|seed| {
            let mut o = overrides.to_vec();
            o.push(format!("seed={seed}"));
            let (scene, base) = Scene::load(scene, &o).map_err(|e| format!("{name}: {e}"))?;
            run_scene(&scene, &base, None, &mut Quiet).map_err(|e| format!("{name}: {e}"))
        })
        .collect()
}

/// The head of each comparison table.
const TABLE_HEAD: &str = "| quantity | event-driven | Monte Carlo | difference | in standard errors | |\n\
                          |---|---|---|---|---|---|";

/// One row of a comparison table: the event-driven runs' `(value, reported error)` against
/// the Monte Carlo chains' `(mean, error)`. The runs' mean carries the larger of their
/// standard error and their mean reported error over √runs; the row passes when the
/// difference is within [`SIGMAS`] combined errors. Writes the row; returns whether it passed.
fn compare(out: &mut String, name: &str, per_run: &[(f64, f64)], chains: &[(f64, f64)]) -> bool {
    let values: Vec<f64> = per_run.iter().map(|p| p.0).collect();
    let (dmd, scatter) = mean_error(&values);
    let reported = per_run.iter().map(|p| p.1).sum::<f64>()
        / per_run.len() as f64
        / (values.len() as f64).sqrt();
    let dmd_error = scatter.max(reported);
    let (mc, mc_error) = combine(chains);
    let diff = dmd - mc;
    let z = diff / (dmd_error * dmd_error + mc_error * mc_error).sqrt();
    let pass = z.is_finite() && z.abs() <= SIGMAS;
    let _ = writeln!(
        out,
        "| {name} | {} ± {} | {} ± {} | {diff:+.5} | {z:+.2} | {} |",
        sig(dmd),
        sig(dmd_error),
        sig(mc),
        sig(mc_error),
        if pass { "ok" } else { "**FAIL**" }
    );
    pass
}

/// Significant figures for the report.
fn sig(x: f64) -> String {
    format!("{x:.5}")
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let cases = if quick { QUICK } else { FULL };
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/stepped-lj.toml");
    let mut out = String::new();
    let mut ok = true;
    let _ = writeln!(
        out,
        "Lennard-Jones spheres at ρσ³ = {DENSITY}, kT = {KT}ε on terraces with the paper's \
         levels (core {CORE}ε). Event-driven: `scenes/stepped-lj.toml` through `run_scene`, \
         Andersen thermostat at rate 5 throughout, fixed seeds 1, 2, …; the smooth U/N and \
         the smooth pressure less its kinetic part ρkT_t give U/N and W/(3V), ± the \
         standard error over the runs (or the runs' mean reported error over √runs, if \
         larger). Monte Carlo: single-particle Metropolis moves from the fcc lattice, the \
         step adapted to 35–45 % acceptance in the first tenth of the sweeps and then fixed, \
         averages every 2 sweeps after it, ± from 20 blocks per chain (combined over the \
         chains as the larger of the propagated error and their scatter). A difference \
         passes within {SIGMAS} combined standard errors.\n"
    );
    for case in cases {
        let overrides: Vec<String> = vec![
            format!("species.0.count={}", case.n),
            "pair.0.steps=".into(),
            "pair.0.potential={kind=\"lennard-jones\", epsilon=1.0, sigma=1.0}".into(),
            format!("pair.0.terraces={{step={}, core={CORE}}}", case.step),
            "thermostat.rate=5".into(),
            "thermostat.during=always".into(),
            "run.equilibration_events=".into(),
            "run.events=".into(),
            format!("run.equilibration_time={}", case.equilibration),
            format!("run.time={}", case.production),
            "output.sample_interval=0.05".into(),
            "output.series=false".into(),
            "output.rdf=".into(),
        ];
        let wall = Instant::now();
        let runs = match run_seeds(&scene_path, &overrides, case.runs) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("{e}");
                return ExitCode::FAILURE;
            }
        };
        let dmd_wall = wall.elapsed().as_secs_f64();
        let chains: Vec<Averages> = (1..=case.chains)
            .into_par_iter()
            .map(|seed| monte_carlo(case, seed))
            .collect();
        let mc_wall = wall.elapsed().as_secs_f64() - dmd_wall;
        let cpu: f64 = runs.iter().map(|s| s.cpu_seconds).sum();
        let quantities: [Quantity; 3] = [
            (
                "terraced ⟨V⟩/N (ε)",
                |s| {
                    (
                        s.potential_energy_per_body,
                        s.potential_energy_per_body_error.unwrap_or(f64::NAN),
                    )
                },
                |a| a.terraced,
            ),
            (
                "smooth U/N (ε)",
                |s| {
                    (
                        s.potential_energy_per_body_smooth.unwrap_or(f64::NAN),
                        s.potential_energy_per_body_smooth_error.unwrap_or(f64::NAN),
                    )
                },
                |a| a.smooth,
            ),
            (
                "smooth W/(3V) (ε/σ³)",
                |s| {
                    (
                        s.pressure_smooth.unwrap_or(f64::NAN) - s.density * s.temperature,
                        s.pressure_smooth_error.unwrap_or(f64::NAN),
                    )
                },
                |a| a.virial,
            ),
        ];
        let _ = writeln!(
            out,
            "**ΔV = {}ε, N = {}**: {} event-driven runs of {} τ after {} τ ({} CPU s, {:.0} s \
             wall clock); {} Monte Carlo chains of {} sweeps ({:.0} s wall clock).\n",
            case.step,
            case.n,
            case.runs,
            case.production,
            case.equilibration,
            cpu.round(),
            dmd_wall,
            case.chains,
            case.sweeps,
            mc_wall
        );
        let _ = writeln!(out, "{TABLE_HEAD}");
        for (name, get, pick) in quantities {
            let per_run: Vec<(f64, f64)> = runs.iter().map(get).collect();
            let parts: Vec<(f64, f64)> = chains.iter().map(pick).collect();
            ok &= compare(&mut out, name, &per_run, &parts);
        }
        let _ = writeln!(out);
    }
    match rods_case(quick, &mut out) {
        Ok(pass) => ok &= pass,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    }
    print!("{out}");
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
