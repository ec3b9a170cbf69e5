//! Validation of semi-flexible molecules: the error of the RATTLE propagation between events
//! against its cost (step `h`), a rigid molecule run by the flexible engine against the exact
//! rigid engine, conservation over a long run, and the measure the constrained dynamics and HMC
//! sample (the bend angle of free trimers against the distribution the bonds' metric gives).
//!
//! Prints a Markdown report on stdout and exits non-zero if a check fails. `--quick` runs the
//! reduced CI subset; `--figures DIR` writes `flexible-error-vs-cost.svg` there.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use collide::Bond;
use dmd_sim::flexible::{Flexible, FlexibleType, RattleSettings, random_internal};
use dmd_sim::hmc::{Acceptance, Chain, Ensemble, HmcSettings, Measure, Outcome};
use dmd_sim::model::PairModel;
use dmd_sim::potential::Potentials;
use dmd_sim::run::thread_cpu_seconds;
use dmd_sim::search::{SearchMethod, SearchSettings};
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use dmd_sim::site_pairs::SiteAtom;
use dmd_sim::sites::{ImpulseRule, MoleculeType, Sites, random_orientations};
use event_queue::{BoundedQueue, LazyQueue, Ticket};
use glam::{DMat3, DVec3};
use plotters::prelude::*;

type Queue = LazyQueue<BoundedQueue<Ticket>>;

struct Report {
    text: String,
    ok: bool,
}

impl Report {
    fn check(&mut self, ok: bool) -> &'static str {
        self.ok &= ok;
        if ok { "pass" } else { "**FAIL**" }
    }
}

fn search(verify: Option<f64>) -> SearchSettings {
    SearchSettings {
        method: SearchMethod::Adaptive,
        max_step: 0.02,
        window: 0.1,
        jitter: 0.0,
        verify_step: verify,
        max_change: f64::INFINITY,
        horizon: 0.0,
    }
}

fn rattle(step: f64, rescale: bool) -> RattleSettings {
    RattleSettings {
        step,
        tolerance: 1e-12,
        rescale,
    }
}

fn atom(x: f64, y: f64, z: f64, mass: f64, species: u32) -> SiteAtom {
    SiteAtom {
        position: DVec3::new(x, y, z),
        mass,
        species,
    }
}

/// A 4-atom chain: bonds 0.6, free bond and torsion angles, sites of species 0, 1, 1, 0.
fn chain() -> Result<FlexibleType, String> {
    FlexibleType::new(
        &[
            atom(0.0, 0.0, 0.0, 1.0, 0),
            atom(0.6, 0.0, 0.0, 1.0, 1),
            atom(0.9, 0.52, 0.0, 1.0, 1),
            atom(1.5, 0.52, 0.05, 1.0, 0),
        ],
        &[Bond::new(0, 1), Bond::new(1, 2), Bond::new(2, 3)],
    )
    .map_err(|e| e.to_string())
}

/// An asymmetric triangle (unequal masses, two site species).
fn triangle_atoms() -> Vec<SiteAtom> {
    vec![
        atom(0.0, 0.0, 0.0, 3.0, 0),
        atom(0.6, 0.2, 0.0, 1.0, 1),
        atom(-0.3, 0.5, 0.0, 2.0, 1),
    ]
}

/// Hard cores with square wells of two depths, and a repulsive shoulder.
fn wells() -> Potentials {
    Potentials::from_tables(
        2,
        &[
            ((0, 0), vec![[1.0, f64::INFINITY], [1.3, -1.0]]),
            (
                (0, 1),
                vec![[0.8, f64::INFINITY], [1.0, -0.5], [1.25, -0.25]],
            ),
            ((1, 1), vec![[0.6, f64::INFINITY], [0.9, 0.3]]),
        ],
    )
}

/// A simple cubic lattice of at least `n` molecules at density `rho` in a box that fits the
/// cell list.
fn lattice(n: usize, rho: f64, reach: f64) -> (f64, Vec<DVec3>) {
    let need = 3.0 * (reach + 0.4) * 1.01;
    let k = ((n as f64).cbrt().ceil() as usize).max((rho * need.powi(3)).cbrt().ceil() as usize);
    let l = ((k * k * k) as f64 / rho).cbrt();
    let a = l / k as f64;
    let mut r = Vec::new();
    for x in 0..k {
        for y in 0..k {
            for z in 0..k {
                r.push((DVec3::new(x as f64, y as f64, z as f64) + 0.5) * a);
            }
        }
    }
    (l, r)
}

fn loop_settings(seed: u64) -> LoopSettings {
    LoopSettings {
        rebase_events: 1_000_000,
        seed,
        debug_check_events: 0,
        skin: 0.2,
        start_time: 0.0,
    }
}

/// 125 chains at density `rho` and temperature `kt`.
fn chains(
    rho: f64,
    kt: f64,
    rat: RattleSettings,
    s: SearchSettings,
    seed: u64,
) -> Result<Simulation<Flexible, Queue>, String> {
    gas(chain()?, wells(), 125, rho, kt, rat, s, seed)
}

/// At least `n` molecules of type `ty` on a simple cubic lattice at density `rho`, randomly
/// turned and flexed, at temperature `kt`.
#[allow(clippy::too_many_arguments)]
fn gas(
    ty: FlexibleType,
    potentials: Potentials,
    n: usize,
    rho: f64,
    kt: f64,
    rat: RattleSettings,
    s: SearchSettings,
    seed: u64,
) -> Result<Simulation<Flexible, Queue>, String> {
    let types = vec![ty];
    let probe = Flexible::new(
        types.clone(),
        potentials.clone(),
        &[],
        &[],
        &[],
        0.0,
        rat,
        s,
        seed,
    )
    .map_err(|e| e.to_string())?;
    let (l, r) = lattice(n, rho, probe.reach());
    let n = r.len();
    let kinds = vec![0u32; n];
    let (q, u) = random_internal(&types, &kinds, kt, seed);
    let v = dmd_sim::init::maxwell_boltzmann(&vec![types[0].mass(); n], kt, seed + 1);
    let model = Flexible::new(types, potentials, &kinds, &q, &u, 0.0, rat, s, seed)
        .map_err(|e| e.to_string())?;
    Simulation::new(DVec3::splat(l), &r, &v, &kinds, model, loop_settings(seed))
        .map_err(|e| format!("{e:?}"))
}

/// A bent trimer: ends of mass [`END_MASS`], a centre of mass 1, unit bonds and a free bend
/// angle θ (site species 0 at the ends, 1 at the centre).
fn trimer() -> Result<FlexibleType, String> {
    FlexibleType::new(
        &[
            atom(1.0, 0.0, 0.0, END_MASS, 0),
            atom(0.0, 0.0, 0.0, 1.0, 1),
            atom(0.0, 1.0, 0.0, END_MASS, 0),
        ],
        &[Bond::new(0, 1), Bond::new(1, 2)],
    )
    .map_err(|e| e.to_string())
}

/// The trimer's end mass: heavy ends on a light centre make the bonds' metric vary strongly
/// with the bend angle.
const END_MASS: f64 = 10.0;

/// Tiny hard cores between the sites of different trimers: an ideal gas to the precision of
/// the check (the excluded volume `ρ·9·(4π/3)·0.05³` is 2e-5), so the bend angle is
/// distributed as in one free molecule.
fn cores() -> Potentials {
    let core = vec![[0.05, f64::INFINITY]];
    Potentials::from_tables(
        2,
        &[
            ((0, 0), core.clone()),
            ((0, 1), core.clone()),
            ((1, 1), core),
        ],
    )
}

/// `cos²θ` of every trimer's bend angle now.
fn bend_cos2(sim: &Simulation<Flexible, Queue>) -> Result<Vec<f64>, String> {
    (0..sim.bodies().len() as u32)
        .map(|i| {
            let (q, _) = sim.model().atoms(i, sim.now()).ok_or("no atom positions")?;
            let (a, b) = (q[0] - q[1], q[2] - q[1]);
            Ok(a.dot(b).powi(2) / (a.length_squared() * b.length_squared()))
        })
        .collect()
}

/// `⟨cos²θ⟩` of the bend angle for the density `sin θ · √det Z(θ)^power` in θ, with
/// `det Z = c² − cos²θ` (`c = 1/m_end + 1/m_centre`, centre mass 1, unit gradients),
/// by Simpson's rule in `x = cos θ`.
fn exact_cos2(power: f64) -> f64 {
    let c = 1.0 / END_MASS + 1.0;
    let w = |x: f64| (c * c - x * x).powf(0.5 * power);
    let n = 20_000;
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..=n {
        let x = -1.0 + 2.0 * k as f64 / n as f64;
        let f = if k == 0 || k == n {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        num += f * x * x * w(x);
        den += f * w(x);
    }
    num / den
}

fn energy<M: PairModel>(sim: &Simulation<M, Queue>) -> f64 {
    sim.kinetic_energy() + sim.potential_energy()
}

fn main() -> ExitCode {
    let mut quick = false;
    let mut figures: Option<PathBuf> = None;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--figures" => figures = it.next().map(PathBuf::from),
            other => {
                eprintln!("validate_flexible: unknown argument {other}");
                return ExitCode::from(2);
            }
        }
    }
    let mut r = Report {
        text: String::new(),
        ok: true,
    };
    if let Err(e) = validate(quick, figures, &mut r) {
        r.ok = false;
        let _ = writeln!(r.text, "\n**Error:** {e}");
    }
    print!("{}", r.text);
    if r.ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// One row of the error-against-cost table.
struct Row {
    h: f64,
    cpu_per_time: f64,
    raw_drift: f64,
    trajectory: f64,
    bond: f64,
}

fn validate(quick: bool, figures: Option<PathBuf>, r: &mut Report) -> Result<(), String> {
    let mut w = String::new();
    writeln!(
        w,
        "Reduced units: site diameter σ = 1 (species 0), atom masses 1 (chains) or 3, 1, 2 \
         (triangle), kT as listed. Chains of 4 atoms with bond length 0.6σ and free bond and \
         torsion angles (6 internal degrees of freedom); site–site hard cores, square wells and a \
         shoulder (the potentials of `tests/integration/flexible.rs`). Internal motion by RATTLE (SHAKE \
         tolerance 1e-12) with cubic Hermite interpolation between steps; adaptive root search, \
         step 0.02, window 0.1. {} run. Timings are CPU seconds of one thread on a shared \
         2-core machine: noisy, for orders of magnitude only.\n",
        if quick { "Quick (CI)" } else { "Full" }
    )
    .ok();

    // ---- 1. Error against run time for the RATTLE step ------------------------------------
    let t_run = if quick { 2.0 } else { 10.0 };
    let t_cmp = 1.0;
    let steps: Vec<f64> = if quick {
        vec![0.01, 0.005, 0.0025, 0.000625]
    } else {
        vec![0.02, 0.01, 0.005, 0.0025, 0.00125, 0.000625, 0.0003125]
    };
    let h_ref = *steps.last().expect("steps");
    writeln!(
        w,
        "### Error against run time for the RATTLE step\n\n\
         125 chains at ρσ³ = 0.04, kT = 1.5, from the same start for every step `h`. \
         *Raw drift*: `|ΔE|/E` after t = {t_run} with the interpolated internal velocities used \
         as they are (the interpolant's derivative overestimates the speed between steps by up \
         to (ωh)²/4, so every event adds energy). *Trajectory*: largest difference of a centre \
         position at t = {t_cmp} from the run at the finest step ({h_ref}), with the internal \
         kinetic energy kept at events (`RattleSettings::rescale`, energy then conserved to \
         round-off). *Bond error*: largest relative bond-length error of an interpolated state \
         at an event (RATTLE's own steps hold the bonds to 1e-12). *Misses*: roots a uniform \
         grid of spacing 10⁻³ (examining every extremum) finds before the search's answer, \
         over the rescaled run to t = {t_cmp}. CPU time per unit of simulated time, rescaled \
         run.\n\n\
         | h | pair events (t = {t_run}) | raw drift \\|ΔE\\|/E | energy, rescaled \\|ΔE\\|/E | trajectory difference | bond error | misses | RATTLE steps per molecule and unit time | CPU s per unit time | check |\n\
         |---|---|---|---|---|---|---|---|---|---|"
    )
    .ok();
    // The reference trajectory.
    let reference = {
        let mut sim = chains(0.04, 1.5, rattle(h_ref, true), search(None), 21)?;
        sim.run(Stop::Time(t_cmp), &mut NoSampler, &mut |_| {})
            .map_err(|e| format!("{e:?}"))?;
        sim.positions()
    };
    let mut rows = Vec::new();
    for &h in &steps {
        // Raw energy drift over the long run.
        let mut raw = chains(0.04, 1.5, rattle(h, false), search(None), 21)?;
        let e0 = energy(&raw);
        let raw_result = raw.run(Stop::Time(t_run), &mut NoSampler, &mut |_| {});
        let fx_raw = raw.model().flex_stats();
        if raw_result.is_err() || fx_raw.failures > 0 {
            writeln!(
                w,
                "| {h} | – | RATTLE failed: the step is too long for the chains' internal motion | – | – | – | – | – | – | report |"
            )
            .ok();
            continue;
        }
        let raw_drift = (energy(&raw) - e0).abs() / e0.abs();
        let pair_events = raw.counters().pair_events();
        // Rescaled: trajectory against the reference, misses, cost, energy.
        let verify = if h == h_ref { None } else { Some(1e-3) };
        let mut sim = chains(0.04, 1.5, rattle(h, true), search(verify), 21)?;
        let e0 = energy(&sim);
        let c0 = thread_cpu_seconds();
        sim.run(Stop::Time(t_cmp), &mut NoSampler, &mut |_| {})
            .map_err(|e| format!("{e:?}"))?;
        let cpu_verify = thread_cpu_seconds().zip(c0).map(|(a, b)| a - b);
        let trajectory = sim
            .positions()
            .iter()
            .zip(&reference)
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0, f64::max);
        let misses = sim.model().search_stats().verify_misses;
        // Cost without the verification grid: the same run again.
        let mut timed = chains(0.04, 1.5, rattle(h, true), search(None), 21)?;
        let c0 = thread_cpu_seconds();
        timed
            .run(Stop::Time(t_run), &mut NoSampler, &mut |_| {})
            .map_err(|e| format!("{e:?}"))?;
        let cpu = thread_cpu_seconds()
            .zip(c0)
            .map(|(a, b)| (a - b) / t_run)
            .or(cpu_verify);
        let fx = timed.model().flex_stats();
        let de = (energy(&timed) - e0).abs() / e0.abs();
        let n = timed.bodies().len() as f64;
        let bond = fx
            .interpolated_bond_error
            .max(sim.model().flex_stats().interpolated_bond_error);
        let anomalies = timed.anomalies().total() + sim.anomalies().total();
        // Pass: energy to round-off with the rescale, bonds to 1e-5, no anomaly; the finer
        // steps (h ≤ 0.005) miss nothing.
        let ok = de < 1e-10
            && anomalies == 0
            && fx.failures == 0
            && (h > 0.005 || (misses == 0 && bond < 1e-5));
        writeln!(
            w,
            "| {h} | {pair_events} | {raw_drift:.1e} | {de:.1e} | {} | {bond:.1e} | {misses} | {:.0} | {} | {} |",
            if h == h_ref {
                "(reference)".to_owned()
            } else {
                format!("{trajectory:.1e}")
            },
            fx.steps as f64 / (n * t_run),
            cpu.map_or("–".into(), |t| format!("{t:.2}")),
            r.check(ok)
        )
        .ok();
        rows.push(Row {
            h,
            cpu_per_time: cpu.unwrap_or(f64::NAN),
            raw_drift,
            trajectory,
            bond,
        });
    }
    // Orders: the raw drift and the trajectory difference fall as h² (ratio ≈ 4 per halving)
    // while above round-off and the reference's own error.
    let order = |f: &dyn Fn(&Row) -> f64| -> Option<f64> {
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|x| x.h >= 4.0 * h_ref && f(x) > 0.0)
            .map(|x| (x.h.ln(), f(x).ln()))
            .collect();
        if pts.len() < 2 {
            return None;
        }
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        Some((a.1 - b.1) / (a.0 - b.0))
    };
    let (p_raw, p_traj) = (order(&|x| x.raw_drift), order(&|x| x.trajectory));
    let fmt = |p: Option<f64>| p.map_or("–".into(), |p| format!("{p:.2}"));
    let ok = p_raw.is_some_and(|p| p > 1.5) && p_traj.is_some_and(|p| p > 1.5);
    writeln!(
        w,
        "\nFitted orders over h ≥ {}: raw energy drift {}, trajectory difference {} ({}: both \
         above 1.5, the method being second order). Pass per row: energy conserved to 1e-10 \
         with the rescale, no anomaly, and for h ≤ 0.005 no missed event and a bond error \
         below 1e-5.\n",
        4.0 * h_ref,
        fmt(p_raw),
        fmt(p_traj),
        r.check(ok)
    )
    .ok();
    if let Some(dir) = &figures {
        let path = dir.join("flexible-error-vs-cost.svg");
        plot(&rows, &path)?;
        writeln!(
            w,
            "![error against run time for the RATTLE step](figures/flexible-error-vs-cost.svg)\n"
        )
        .ok();
    }

    // ---- 2. A rigid molecule through the flexible engine ----------------------------------
    writeln!(
        w,
        "### A rigid molecule: flexible engine against the exact rigid engine\n\n\
         Triangles (all three distances bonded) at ρσ³ = 0.1, kT = 1, run by `Flexible` (RATTLE, \
         constrained-Lagrangian impulses) and by `Sites` (exact free rotation, contact-point \
         impulses) from the same start to t = 1. Largest difference of a centre position and \
         event counts by kind.\n\n\
         | h | core | in | out | reflect | rigid engine (core, in, out, reflect) | largest centre difference | check |\n\
         |---|---|---|---|---|---|---|---|"
    )
    .ok();
    let ty = MoleculeType::new(&triangle_atoms()).map_err(|e| e.to_string())?;
    let flex_type = FlexibleType::new(
        &triangle_atoms(),
        &[Bond::new(0, 1), Bond::new(1, 2), Bond::new(0, 2)],
    )
    .map_err(|e| e.to_string())?;
    let s = SearchSettings {
        max_step: 0.01,
        window: 0.05,
        ..search(None)
    };
    let probe = Flexible::new(
        vec![flex_type.clone()],
        wells(),
        &[],
        &[],
        &[],
        0.0,
        rattle(0.01, false),
        s,
        1,
    )
    .map_err(|e| e.to_string())?;
    let (l, pos) = lattice(27, 0.1, probe.reach());
    let n = pos.len();
    let kinds = vec![0u32; n];
    let (q, om) = random_orientations(std::slice::from_ref(&ty), &kinds, 1.0, 8);
    let v = dmd_sim::init::maxwell_boltzmann(&vec![ty.mass(); n], 1.0, 9);
    let mut rigid = {
        let model = Sites::new(
            vec![ty.clone()],
            wells(),
            &kinds,
            &q,
            &om,
            0.0,
            s,
            ImpulseRule::ContactPoint,
            1,
        )
        .map_err(|e| e.to_string())?;
        Simulation::<_, Queue>::new(DVec3::splat(l), &pos, &v, &kinds, model, loop_settings(1))
            .map_err(|e| format!("{e:?}"))?
    };
    rigid
        .run(Stop::Time(1.0), &mut NoSampler, &mut |_| {})
        .map_err(|e| format!("{e:?}"))?;
    let cr = rigid.counters();
    let mut diffs = Vec::new();
    for h in [0.02, 0.01, 0.005, 0.0025, 0.00125] {
        let (mut ap, mut av) = (Vec::new(), Vec::new());
        for (qi, wi) in q.iter().zip(&om) {
            let o = DMat3::from_quat(*qi);
            let arms: Vec<DVec3> = ty.sites().iter().map(|&d| o * d).collect();
            av.push(arms.iter().map(|&d| wi.cross(d)).collect());
            ap.push(arms);
        }
        let model = Flexible::new(
            vec![flex_type.clone()],
            wells(),
            &kinds,
            &ap,
            &av,
            0.0,
            rattle(h, true),
            s,
            1,
        )
        .map_err(|e| e.to_string())?;
        let mut sim =
            Simulation::<_, Queue>::new(DVec3::splat(l), &pos, &v, &kinds, model, loop_settings(1))
                .map_err(|e| format!("{e:?}"))?;
        sim.run(Stop::Time(1.0), &mut NoSampler, &mut |_| {})
            .map_err(|e| format!("{e:?}"))?;
        let c = sim.counters();
        let d = sim
            .positions()
            .iter()
            .zip(rigid.positions())
            .map(|(a, b)| (*a - b).length())
            .fold(0.0, f64::max);
        let same = (c.core, c.step_in, c.step_out, c.step_reflect)
            == (cr.core, cr.step_in, cr.step_out, cr.step_reflect);
        let ok = h > 0.005 || (same && d < 1e-3);
        writeln!(
            w,
            "| {h} | {} | {} | {} | {} | {}, {}, {}, {} | {d:.1e} | {} |",
            c.core,
            c.step_in,
            c.step_out,
            c.step_reflect,
            cr.core,
            cr.step_in,
            cr.step_out,
            cr.step_reflect,
            if h > 0.005 { "report" } else { r.check(ok) }
        )
        .ok();
        diffs.push(d);
    }
    let ratio = diffs[2] / diffs[3];
    writeln!(
        w,
        "\nPass: for h ≤ 0.005 the same events of every kind and centres within 1e-3; the \
         difference shrinks by {ratio:.1} from h = 0.005 to 0.0025 ({}: above 3, second \
         order).\n",
        r.check(ratio > 3.0)
    )
    .ok();

    // ---- 3. Long run ----------------------------------------------------------------------
    let events: u64 = if quick { 50_000 } else { 1_000_000 };
    writeln!(
        w,
        "### Conservation over a long run\n\n\
         125 chains at ρσ³ = 0.04, kT = 1.5, h = 0.005, internal kinetic energy kept at events, \
         {events} events.\n\n\
         | pair events | \\|ΔE\\|/E | \\|ΔP\\| | bond error (starts, now) | ⟨T_internal⟩ / ⟨T_centres⟩ | overlaps | off-level starts | misfits | failures | RATTLE steps per event | indicator evaluations per event | events/s | check |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|"
    )
    .ok();
    let mut sim = chains(0.04, 1.5, rattle(0.005, true), search(None), 5)?;
    let e0 = energy(&sim);
    let (p0, _) = sim.momentum_and_mass();
    let c0 = thread_cpu_seconds();
    // Temperatures averaged over the last 19 of 20 pieces (the first equilibrates).
    let (mut sum_int, mut sum_com) = (0.0, 0.0);
    let n = sim.bodies().len() as f64;
    for piece in 1..=20u64 {
        // `Stop::Events` counts the events of this call.
        sim.run(Stop::Events(events / 20), &mut NoSampler, &mut |_| {})
            .map_err(|e| format!("{e:?}"))?;
        if piece > 1 {
            sum_int += 2.0 * sim.model().rotational_kinetic() / sim.model().rotational_dof();
            sum_com += 2.0 * sim.translational_kinetic() / (3.0 * n - 3.0);
        }
    }
    let cpu = thread_cpu_seconds().zip(c0).map(|(a, b)| a - b);
    let de = (energy(&sim) - e0).abs() / e0.abs();
    let (p1, _) = sim.momentum_and_mass();
    let dp = (p1 - p0).length();
    let bonds = sim.model().bond_error(sim.now());
    let equipartition = sum_int / sum_com;
    let st = sim.model().search_stats();
    let fx = sim.model().flex_stats();
    let checked = sim.check();
    let ok = de < 1e-10
        && dp < 1e-10
        && bonds < 1e-5
        && sim.anomalies().total() == 0
        && st.off_terrace == 0
        && st.failures == 0
        && fx.failures == 0
        && (equipartition - 1.0).abs() < 0.1
        && checked.is_ok();
    writeln!(
        w,
        "| {} | {de:.1e} | {dp:.1e} | {bonds:.1e} | {:.3} | {} | {} | {} | {} | {:.1} | {:.0} | {} | {} |",
        sim.counters().pair_events(),
        equipartition,
        sim.anomalies().overlap,
        st.off_terrace,
        st.misfits,
        st.failures + fx.failures,
        fx.steps as f64 / events as f64,
        st.evaluations as f64 / events as f64,
        cpu.map_or("–".into(), |t| format!("{:.2e}", events as f64 / t)),
        r.check(ok)
    )
    .ok();
    // The share of RATTLE in the run: one chain's steps timed alone.
    let ns_per_step = {
        let t = chain()?;
        let c = dmd_sim::flexible::Constraints::new(t.masses(), t.bonds(), t.lengths(), 1e-12);
        let (q, u) = random_internal(std::slice::from_ref(&t), &[0], 1.5, 3);
        let mut traj = dmd_sim::flexible::Trajectory::new(0.0, 0.005, &q[0], &u[0]);
        let steps = 200_000;
        let c0 = thread_cpu_seconds();
        for k in (0..steps).step_by(1000) {
            traj.state_at(&c, 0.005 * k as f64)
                .map_err(|e| e.to_string())?;
            traj.trim(0.005 * k as f64);
        }
        thread_cpu_seconds()
            .zip(c0)
            .map(|(a, b)| (a - b) / steps as f64 * 1e9)
    };
    if let (Some(ns), Some(total)) = (ns_per_step, cpu) {
        writeln!(
            w,
            "\nOne RATTLE step of a chain costs {ns:.0} ns (timed alone): the {:.1} steps per \
             event are {:.0} % of the run's CPU time; the rest is the searches (indicator \
             evaluations: two Hermite interpolations each), events and the loop.",
            fx.steps as f64 / events as f64,
            100.0 * ns * 1e-9 * fx.steps as f64 / total
        )
        .ok();
    }
    writeln!(
        w,
        "\nPass: energy and momentum to 1e-10, bonds to 1e-5, no overlap, no search that \
         started off its level, no failure, the full invariant check at the end{}, and \
         equipartition: the internal and centre temperatures (6 internal degrees of freedom \
         per chain), each averaged over 19 snapshots after the first twentieth of the run, \
         within 10 %.\n",
        match &checked {
            Ok(()) => String::new(),
            Err(e) => format!(" (failed: {e})"),
        }
    )
    .ok();
    measure(quick, r, &mut w)?;
    r.text.push_str(&w);
    Ok(())
}

/// Section 4: the bend-angle distribution of a gas of trimers from long dynamics and from HMC
/// in both measures, against the distributions derived from the bonds' metric.
fn measure(quick: bool, r: &mut Report, w: &mut String) -> Result<(), String> {
    let (kt, rho, n) = (1.0, 0.05, 64);
    let span = if quick { 600.0 } else { 4000.0 };
    let exact_dyn = exact_cos2(1.0);
    let exact_flat = exact_cos2(0.0);
    writeln!(
        w,
        "### The measure of constrained dynamics: a gas of bent trimers\n\n\
         {n} trimers (ends of mass {END_MASS}, centre of mass 1, unit bonds, free bend angle θ) \
         with hard cores of 0.05 between the sites of different trimers (an ideal gas: the \
         excluded volume would bias the bend angle of a dense one) at ρσ³ = {rho}, kT = {kt}, h = 0.005. The constrained dynamics leaves the \
         measure `e^(−βU) √det Z dσ` invariant (000 §II.A), so the bend angle is distributed as \
         `sin θ · √det Z(θ)` with `det Z = (1/m_end + 1/m_centre)² − cos²θ/m_centre²` (unit \
         gradients): `⟨cos²θ⟩ = {exact_dyn:.4}`. Infinitely stiff bonds give `sin θ` alone: \
         `⟨cos²θ⟩ = {exact_flat:.4}`. Dynamics: an Andersen thermostat (rate 1 per τ: the \
         free molecules do not collide) over 10 + {span} τ, sampled every 0.5 τ. HMC: canonical segments of 1 τ ({span} of them after \
         10), sampled after each; `hmc.measure = \"stiff-bonds\"` divides `√det Z` out of the \
         acceptance. Errors by blocking over the snapshots' means.\n\n\
         | sampler | snapshots | acceptance | ⟨cos²θ⟩ | expected | deviation | check |\n\
         |---|---|---|---|---|---|---|"
    )
    .ok();
    let mut row = |w: &mut String, name: &str, means: &[f64], acc: Option<f64>, expected: f64| {
        let b = dmd_sim::hmc::block_average(means);
        let z = (b.mean - expected) / b.error;
        // 4 standard errors, and errors small enough that the two measures differ by at
        // least 6 of them: the check can tell the metric factor from none.
        let ok = z.abs() < 4.0 && (exact_dyn - exact_flat).abs() > 6.0 * b.error;
        writeln!(
            w,
            "| {name} | {} | {} | {:.4} ± {:.4} | {expected:.4} | {z:+.1} σ | {} |",
            means.len(),
            acc.map_or("–".into(), |a| format!("{a:.3}")),
            b.mean,
            b.error,
            r.check(ok)
        )
        .ok();
    };
    let mean = |v: Vec<f64>| v.iter().sum::<f64>() / v.len() as f64;
    let rat = rattle(0.005, true);
    let s = search(None);
    // Long dynamics.
    let mut sim = gas(trimer()?, cores(), n, rho, kt, rat, s, 41)?;
    let run = |sim: &mut Simulation<Flexible, Queue>, t: f64| {
        sim.run(Stop::Time(t), &mut NoSampler, &mut |_| {})
            .map_err(|e| format!("{e:?}"))
    };
    sim.set_thermostat(Some(dmd_sim::simulation::Andersen {
        rate: 1.0,
        temperature: kt,
    }));
    run(&mut sim, 10.0)?;
    let mut means = Vec::new();
    for _ in 0..(2.0 * span) as usize {
        run(&mut sim, 0.5)?;
        means.push(mean(bend_cos2(&sim)?));
    }
    row(w, "dynamics (Andersen)", &means, None, exact_dyn);
    // HMC in both measures.
    for (name, m, expected) in [
        ("HMC, `dynamics`", Measure::Dynamics, exact_dyn),
        ("HMC, `stiff-bonds`", Measure::StiffBonds, exact_flat),
    ] {
        let mut sim = gas(trimer()?, cores(), n, rho, kt, rat, s, 43)?;
        let mut chain = Chain::new(
            HmcSettings {
                ensemble: Ensemble::Canonical,
                segment_time: 1.0,
                temperature: kt,
                exchanges: 0,
                tolerance: 1e-9,
                acceptance: Acceptance::Metropolis,
                histogram_bins: 40,
                histogram_range: 10.0,
                seed: 7,
                measure: m,
            },
            false,
        );
        for _ in 0..10 {
            chain.segment(&mut sim).map_err(|e| format!("{e:?}"))?;
        }
        let (mut means, mut accepted) = (Vec::new(), 0);
        for _ in 0..span as usize {
            let seg = chain.segment(&mut sim).map_err(|e| format!("{e:?}"))?;
            accepted += usize::from(seg.outcome == Outcome::Accepted);
            means.push(mean(bend_cos2(&sim)?));
        }
        row(w, name, &means, Some(accepted as f64 / span), expected);
    }
    writeln!(
        w,
        "\nPass: each within 4 standard errors of its expected value, with errors below a \
         sixth of the difference between the two measures (so the check tells the metric \
         factor from none).\n"
    )
    .ok();
    Ok(())
}

fn plot(rows: &[Row], path: &std::path::Path) -> Result<(), String> {
    let root = SVGBackend::new(path, (760, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let finite: Vec<&Row> = rows.iter().filter(|x| x.cpu_per_time.is_finite()).collect();
    let xs = finite.iter().map(|x| x.cpu_per_time);
    let (x0, x1) = (
        xs.clone().fold(f64::INFINITY, f64::min) * 0.5,
        xs.fold(0.0, f64::max) * 2.0,
    );
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Semi-flexible chains: error against run time (RATTLE step h)",
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (x0.max(1e-4)..x1.max(1e-3)).log_scale(),
            (1e-12f64..1.0).log_scale(),
        )
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("CPU seconds per unit of simulated time")
        .y_desc("error")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(|e| e.to_string())?;
    type Get = fn(&Row) -> f64;
    let series: [(&str, RGBColor, Get); 3] = [
        ("raw energy drift |ΔE|/E", RED, |x| x.raw_drift),
        ("centre difference from finest h (rescaled)", BLUE, |x| {
            x.trajectory
        }),
        ("bond error of interpolated states", GREEN, |x| x.bond),
    ];
    for (label, col, get) in series {
        let pts: Vec<(f64, f64)> = finite
            .iter()
            .filter(|x| get(x) > 0.0)
            .map(|x| (x.cpu_per_time, get(x).clamp(1e-12, 1.0)))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), col.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2)));
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, col.filled())))
            .map_err(|e| e.to_string())?;
    }
    for x in &finite {
        chart
            .draw_series(std::iter::once(Text::new(
                format!("h={}", x.h),
                (x.cpu_per_time, x.raw_drift.clamp(1e-12, 1.0) * 1.6),
                ("sans-serif", 11),
            )))
            .map_err(|e| e.to_string())?;
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}
