//! Validation of rigid site molecules against a published equation of state (issue 10): the
//! compressibility factor of the hard-dumbbell fluid from the collision virial of the
//! molecules, at two elongations and three packing fractions, against the equation of state
//! Tildesley and Streett fitted to their Monte Carlo data.
//!
//! The systems are set up through the scene path (`site_scene`: molecule shorthand, lattice,
//! aligned start), so the check covers what `dmd run` runs; the production is cut into blocks
//! for the statistical error.
//!
//! Prints a Markdown report on stdout and exits non-zero if a check fails. `--quick` runs the
//! CI-sized version; `--figures DIR` is accepted for symmetry with the other validations (this
//! one writes no figure).

use std::fmt::Write as _;
use std::process::ExitCode;

use dmd_sim::init::{lattice, maxwell_boltzmann};
use dmd_sim::run::thread_cpu_seconds;
use dmd_sim::scene::Scene;
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use dmd_sim::site_scene::{SitesPlan, model};
use dmd_sim::sites::Sites;
use event_queue::{BoundedQueue, LazyQueue, Ticket};
use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

type Queue = LazyQueue<BoundedQueue<Ticket>>;

/// Volume of two fused spheres of diameter 1 at centre distance `l` ≤ 1:
/// `(π/6)(1 + 3l/2 − l³/2)` (two spheres less the doubly counted lens).
fn dumbbell_volume(l: f64) -> f64 {
    std::f64::consts::PI / 6.0 * (1.0 + 1.5 * l - 0.5 * l.powi(3))
}

/// The hard-dumbbell equation of state of D. J. Tildesley and W. B. Streett, Mol. Phys. 41,
/// 85 (1980), fitted to their Monte Carlo compressibility factors at L* = 0.2–1.0 (a
/// Carnahan–Starling form whose coefficients are polynomials in L*):
/// `Z = (1 + f₁η + f₂η² − f₃η³)/(1 − η)³`, `f₁ = 1 + 0.37836 L* + 1.07860 L*³`,
/// `f₂ = 1 + 1.30376 L* + 1.80010 L*³`, `f₃ = 1 + 2.39803 L* + 0.35700 L*³`. (Coefficients as
/// reproduced in Curro et al., J. Chem. Phys. 153, 244903 (2020), Eq. B6, whose denominator
/// `(1 − η)²` is a misprint: at L* = 0 the fit must be Carnahan–Starling; that paper cites the
/// page as 341, the issue and our records as 85 — not checked against the original.)
fn tildesley_streett(l: f64, eta: f64) -> f64 {
    let f1 = 1.0 + 0.37836 * l + 1.07860 * l.powi(3);
    let f2 = 1.0 + 1.30376 * l + 1.80010 * l.powi(3);
    let f3 = 1.0 + 2.39803 * l + 0.35700 * l.powi(3);
    (1.0 + f1 * eta + f2 * eta * eta - f3 * eta.powi(3)) / (1.0 - eta).powi(3)
}

/// Wertheim's first-order perturbation theory for tangent hard-sphere dimers (L* = 1; M. S.
/// Wertheim, J. Chem. Phys. 87, 7323 (1987); W. G. Chapman et al., Mol. Phys. 65, 1057
/// (1988)): `Z = 2 Z_CS − (1 + η ∂ln g_CS(σ)/∂η)` with `g_CS(σ) = (1 − η/2)/(1 − η)³`.
fn tpt1_dimer(eta: f64) -> f64 {
    let zcs = (1.0 + eta + eta * eta - eta.powi(3)) / (1.0 - eta).powi(3);
    let dlng = -0.5 / (1.0 - 0.5 * eta) + 3.0 / (1.0 - eta);
    2.0 * zcs - (1.0 + eta * dlng)
}

/// The virial coefficients the Tildesley–Streett fit implies, `B₂/v_m = 3 + f₁` and
/// `B₃/v_m² = 6 + 3f₁ + f₂`, and its `B₄/v_m³ = 10 + 6f₁ + 3f₂ − f₃` (expanding
/// `(1 − η)⁻³`).
fn tildesley_streett_virials(l: f64) -> [f64; 3] {
    let f1 = 1.0 + 0.37836 * l + 1.07860 * l.powi(3);
    let f2 = 1.0 + 1.30376 * l + 1.80010 * l.powi(3);
    let f3 = 1.0 + 2.39803 * l + 0.35700 * l.powi(3);
    [
        3.0 + f1,
        6.0 + 3.0 * f1 + f2,
        10.0 + 6.0 * f1 + 3.0 * f2 - f3,
    ]
}

/// Whether hard dumbbells of elongation `l` with centres `r` apart (from 2 to 1) and axes
/// `u1`, `u2` overlap: some pair of sites closer than σ = 1.
fn overlap(r: DVec3, u1: DVec3, u2: DVec3, l: f64) -> bool {
    [-0.5, 0.5].iter().any(|&a| {
        [-0.5, 0.5]
            .iter()
            .any(|&b| (r + a * l * u2 - b * l * u1).length_squared() < 1.0)
    })
}

/// `B₂/v_m` and `B₃/v_m²` of hard dumbbells of elongation `l`, with standard errors, by
/// Monte Carlo integration over `samples` configurations: molecules 2 and 3 uniform in the
/// ball of radius σ + L around molecule 1 (beyond it nothing overlaps), all axes uniform;
/// `B₂ = ½ V_ball P(1–2 overlap)`, `B₃ = ⅓ V_ball² P(all three pairs overlap)` (the Mayer
/// functions are −1 on overlap).
fn virial_coefficients(l: f64, samples: u64, seed: u64) -> [(f64, f64); 2] {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let unit = |rng: &mut Xoshiro256PlusPlus| loop {
        let g = DVec3::new(
            StandardNormal.sample(rng),
            StandardNormal.sample(rng),
            StandardNormal.sample(rng),
        );
        if let Some(u) = g.try_normalize() {
            break u;
        }
    };
    let reach = 1.0 + l;
    let ball = 4.0 / 3.0 * std::f64::consts::PI * reach.powi(3);
    let (mut two, mut three) = (0u64, 0u64);
    for _ in 0..samples {
        let inside = |rng: &mut Xoshiro256PlusPlus| {
            let u: f64 = rng.random();
            unit(rng) * reach * u.cbrt()
        };
        let (r2, r3) = (inside(&mut rng), inside(&mut rng));
        let (u1, u2, u3) = (unit(&mut rng), unit(&mut rng), unit(&mut rng));
        let o12 = overlap(r2, u1, u2, l);
        two += u64::from(o12);
        if o12 && overlap(r3, u1, u3, l) && overlap(r3 - r2, u2, u3, l) {
            three += 1;
        }
    }
    let vm = dumbbell_volume(l);
    let est = |hits: u64, scale: f64| {
        let p = hits as f64 / samples as f64;
        (scale * p, scale * (p * (1.0 - p) / samples as f64).sqrt())
    };
    [
        est(two, 0.5 * ball / vm),
        est(three, ball * ball / (3.0 * vm * vm)),
    ]
}

/// Accuracy assumed for the Tildesley–Streett fit (relative): the Monte Carlo data it was
/// fitted to carry errors of about a per cent.
const REFERENCE_ACCURACY: f64 = 0.01;

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

fn main() -> ExitCode {
    let mut quick = false;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--figures" => {
                let _ = it.next();
            }
            other => {
                eprintln!("validate_sites_eos: unknown argument {other}");
                return ExitCode::from(2);
            }
        }
    }
    let mut r = Report {
        text: String::new(),
        ok: true,
    };
    if let Err(e) = validate(quick, &mut r) {
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

/// One state point: a scene of `n` dumbbells of elongation `l` at packing fraction `eta`,
/// started aligned on an fcc lattice.
fn scene(n: usize, l: f64, eta: f64, seed: u64) -> Result<Scene, String> {
    let rho = eta / dumbbell_volume(l);
    let text = format!(
        r#"
version = 1
seed = {seed}
[box]
density = {rho}
[[species]]
name = "dumbbell"
count = {n}
molecule = {{ kind = "dumbbell", elongation = {l} }}
[[site_pair]]
sites = ["A", "A"]
steps = [[1.0, inf]]
[init]
positions = "fcc"
orientations = "aligned"
axis = [0, 0, 1]
temperature = 1.0
[run]
time = 1.0
"#
    );
    Scene::from_str_with(&text, &[]).map_err(|e| e.to_string())
}

fn system(scene: &Scene) -> Result<Simulation<Sites, Queue>, String> {
    let scene = scene.internal();
    let config = lattice(&scene, 0.0).map_err(|e| e.to_string())?;
    let plan = SitesPlan::of(&scene).map_err(|e| e.to_string())?;
    let mass = scene.species[0].mass;
    let v = maxwell_boltzmann(
        &vec![mass; config.positions.len()],
        scene.init.temperature,
        scene.seed,
    );
    let sites = model(&scene, &config, plan, false, None, None).map_err(|e| e.to_string())?;
    let settings = LoopSettings {
        rebase_events: 1_000_000,
        seed: scene.seed,
        debug_check_events: 0,
        skin: 0.15,
        start_time: 0.0,
    };
    Simulation::new(
        config.lengths,
        &config.positions,
        &v,
        &config.species,
        sites,
        settings,
    )
    .map_err(|e| format!("{e:?}"))
}

/// `⟨P₂(u·z)⟩` of the molecular axes (0 in an isotropic fluid, 1 when all along z).
fn order(sim: &Simulation<Sites, Queue>) -> f64 {
    let n = sim.bodies().len();
    let now = sim.now();
    (0..n as u32)
        .map(|i| {
            let c = sim.model().pose(i, now).0.x_axis.z;
            1.5 * c * c - 0.5
        })
        .sum::<f64>()
        / n as f64
}

/// What one state point gave.
struct Point {
    z: f64,
    se: f64,
    collisions: u64,
    p2: f64,
    drift: f64,
    anomalies: u64,
    cpu: Option<f64>,
}

impl Point {
    fn healthy(&self) -> bool {
        self.p2.abs() < 0.1 && self.drift < 1e-10 && self.anomalies == 0
    }
}

/// Runs `n` dumbbells of elongation `l` at packing fraction `eta`: a melt of `equil`, then
/// `blocks` blocks of `block_time` whose Z are averaged.
fn measure(
    n: usize,
    l: f64,
    eta: f64,
    seed: u64,
    (equil, blocks, block_time): (f64, usize, f64),
) -> Result<Point, String> {
    let sc = scene(n, l, eta, seed)?;
    let mut sim = system(&sc)?;
    let c0 = thread_cpu_seconds();
    sim.run(Stop::Time(equil), &mut NoSampler, &mut |_| {})
        .map_err(|e| format!("{e:?}"))?;
    let p2 = order(&sim);
    let e0 = sim.kinetic_energy() + sim.potential_energy();
    let mut zs = Vec::with_capacity(blocks);
    let mut collisions = 0;
    let mut anomalies = 0;
    for _ in 0..blocks {
        sim.begin_phase(false, None, None);
        sim.run(Stop::Time(block_time), &mut NoSampler, &mut |_| {})
            .map_err(|e| format!("{e:?}"))?;
        let t = sim.phase_elapsed();
        let kt = 2.0 * sim.kinetic_integral() / t / sim.dof();
        let nb = sim.bodies().len() as f64;
        zs.push(1.0 + sim.virial() / (3.0 * nb * kt * t));
        collisions += sim.counters().core;
        // Failed searches, searches that began with their site pair across a boundary (the
        // trace of a missed collision) and events off their boundary.
        anomalies += sim.anomalies().total()
            + sim.model().search_stats().failures
            + sim.model().search_stats().off_terrace
            + sim.model().search_stats().misfits;
    }
    let e1 = sim.kinetic_energy() + sim.potential_energy();
    let m = zs.iter().sum::<f64>() / blocks as f64;
    let var = zs.iter().map(|z| (z - m).powi(2)).sum::<f64>() / (blocks - 1) as f64;
    Ok(Point {
        z: m,
        se: (var / blocks as f64).sqrt(),
        collisions,
        p2,
        drift: (e1 - e0).abs() / e0.abs(),
        anomalies,
        cpu: thread_cpu_seconds().zip(c0).map(|(a, b)| a - b),
    })
}

fn cpu(p: &Point) -> String {
    p.cpu.map_or("–".into(), |t| format!("{t:.1}"))
}

fn validate(quick: bool, r: &mut Report) -> Result<(), String> {
    let (n, equil, blocks, block_time) = if quick {
        (256, 5.0, 10, 1.0)
    } else {
        (500, 30.0, 20, 20.0)
    };
    let mut w = String::new();
    writeln!(
        w,
        "Hard dumbbells: two fused hard spheres of diameter σ (site masses m) at centre \
         distance L = L*σ, kT = 1, N = {n}, started aligned along z on an fcc lattice and \
         melted for {equil} τ (τ = σ√(m/kT)) before {blocks} production blocks of {block_time} \
         τ (NVE). Packing fraction η = ρ v_m with v_m = (πσ³/6)(1 + 3L*/2 − L*³/2). Z = 1 + \
         Σ r_ij·J_ij / (3 N kT t), the molecular collision virial (centre separation r_ij, \
         impulse J_ij at the touching sites), with the standard error of the block means. \
         Reference: the equation of state of Tildesley and Streett, Mol. Phys. 41, 85 (1980), \
         fitted to their Monte Carlo data for L* = 0.2–1.0; at L* = 1 Wertheim's TPT1 for \
         tangent dimers is shown for comparison. Pass: |Z − Z_TS| below {:.0} % of Z_TS (our \
         assumption for the fit's accuracy) plus three standard errors; P₂ of the axes along \
         the initial direction below 0.1 after the melt (an isotropic fluid); energy conserved \
         to 1e-10, no anomaly, no missed or misplaced event. {} run; CPU seconds of one thread on a shared machine.\n",
        REFERENCE_ACCURACY * 100.0,
        if quick { "Quick (CI)" } else { "Full" }
    )
    .ok();
    writeln!(
        w,
        "| L* | η | ρσ³ | collisions | P₂ after melt | Z (DMD) | Z Tildesley–Streett | Z TPT1 \
         | (Z − Z_TS)/Z_TS | \\|ΔE\\|/E | CPU s | check |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|"
    )
    .ok();
    let run = (equil, blocks, block_time);
    for (k, &(l, eta)) in [
        (0.6, 0.2),
        (0.6, 0.3),
        (0.6, 0.4),
        (1.0, 0.2),
        (1.0, 0.3),
        (1.0, 0.4),
    ]
    .iter()
    .enumerate()
    {
        let p = measure(n, l, eta, 100 + k as u64, run)?;
        let z_ts = tildesley_streett(l, eta);
        let ok = (p.z - z_ts).abs() < REFERENCE_ACCURACY * z_ts + 3.0 * p.se && p.healthy();
        writeln!(
            w,
            "| {l} | {eta} | {:.5} | {} | {:+.3} | {:.4} ± {:.4} | {z_ts:.4} | {} | {:+.2} % \
             | {:.1e} | {} | {} |",
            eta / dumbbell_volume(l),
            p.collisions,
            p.p2,
            p.z,
            p.se,
            if l == 1.0 {
                format!("{:.4}", tpt1_dimer(eta))
            } else {
                "–".into()
            },
            100.0 * (p.z - z_ts) / z_ts,
            p.drift,
            cpu(&p),
            r.check(ok)
        )
        .ok();
    }
    writeln!(
        w,
        "\nThe fit reproduces Carnahan–Starling at L* = 0 and agrees with TPT1 at L* = 1 to a \
         few parts in a thousand over this range, so the reference is not the limiting factor \
         at the 1 % level.\n"
    )
    .ok();
    low_density(quick, n, run, &mut w, r)?;
    r.text.push_str(&w);
    Ok(())
}

/// The exact low-density check: the virial coefficients by integration, and Z at η = 0.05
/// against the virial series through B₃.
fn low_density(
    quick: bool,
    n: usize,
    run: (f64, usize, f64),
    w: &mut String,
    r: &mut Report,
) -> Result<(), String> {
    let samples: u64 = if quick { 1_000_000 } else { 20_000_000 };
    writeln!(
        w,
        "### Low density: the collision virial against exact virial coefficients\n\n\
         B₂ and B₃ of hard dumbbells by Monte Carlo integration of the Mayer functions \
         ({samples} configurations; L* = 0 is hard spheres, exactly 4 and 10 in units of the \
         molecular volume), and those the Tildesley–Streett fit implies (expanding its \
         (1 − η)⁻³). Pass for the integration: within three standard errors of 4 and 10 at \
         L* = 0.\n\n\
         | L* | B₂/v_m | B₂/v_m (fit) | B₃/v_m² | B₃/v_m² (fit) | check |\n\
         |---|---|---|---|---|---|"
    )
    .ok();
    let mut coefficients = Vec::new();
    for (k, l) in [0.0, 0.6, 1.0].into_iter().enumerate() {
        let [(b2, e2), (b3, e3)] = virial_coefficients(l, samples, 7 + k as u64);
        let fit = tildesley_streett_virials(l);
        let check = if l == 0.0 {
            // Every configuration overlaps at L* = 0 for B₂ (zero variance): round-off only.
            r.check((b2 - 4.0).abs() < 3.0 * e2 + 1e-12 && (b3 - 10.0).abs() < 3.0 * e3 + 1e-12)
        } else {
            "report"
        };
        writeln!(
            w,
            "| {l} | {b2:.4} ± {e2:.4} | {:.4} | {b3:.3} ± {e3:.3} | {:.3} | {check} |",
            fit[0], fit[1]
        )
        .ok();
        coefficients.push((l, (b2, e2), (b3, e3), fit[2]));
    }
    let eta = 0.05;
    writeln!(
        w,
        "\nZ at η = {eta} (N = {n}, production ten times as long as above: collisions are rarer) \
         against the virial series \
         1 + B₂η + B₃η² + B₄η³ with the integrated B₂, B₃ and the fit's B₄ (the only \
         approximate term: half of it is counted as its uncertainty). Pass: within three \
         standard errors (run and integration) plus that uncertainty.\n\n\
         | L* | Z (DMD) | Z virial series | B₄η³ term | (Z − Z_vir)/(Z_vir − 1) | collisions | \\|ΔE\\|/E | CPU s | check |\n\
         |---|---|---|---|---|---|---|---|---|"
    )
    .ok();
    for (k, &(l, (b2, e2), (b3, e3), b4)) in coefficients.iter().skip(1).enumerate() {
        let p = measure(n, l, eta, 200 + k as u64, (run.0, run.1, 10.0 * run.2))?;
        let b4_term = b4 * eta.powi(3);
        let z_vir = 1.0 + b2 * eta + b3 * eta * eta + b4_term;
        let integration = e2 * eta + e3 * eta * eta;
        let tol = 3.0 * (p.se + integration) + 0.5 * b4_term;
        let ok = (p.z - z_vir).abs() < tol && p.healthy();
        writeln!(
            w,
            "| {l} | {:.5} ± {:.5} | {z_vir:.5} ± {integration:.5} | {b4_term:.5} | {:+.2} % | {} \
             | {:.1e} | {} | {} |",
            p.z,
            p.se,
            100.0 * (p.z - z_vir) / (z_vir - 1.0),
            p.collisions,
            p.drift,
            cpu(&p),
            r.check(ok)
        )
        .ok();
    }
    // How much of the L* = 0.6, η = 0.2 row's deviation the fit's B₃ alone explains.
    let (_, _, (b3, _), _) = coefficients[1];
    let excess = (tildesley_streett_virials(0.6)[1] - b3) * 0.04 / tildesley_streett(0.6, 0.2);
    writeln!(
        w,
        "\nThe fit's B₃ is {:.1} % above the integrated one at L* = 0.6: at η = 0.2 that alone \
         raises the fit's Z by {:.2} %, the size of the deviation of the DMD value from the fit \
         in that row of the first table.\n",
        100.0 * (tildesley_streett_virials(0.6)[1] / b3 - 1.0),
        100.0 * excess
    )
    .ok();
    Ok(())
}
