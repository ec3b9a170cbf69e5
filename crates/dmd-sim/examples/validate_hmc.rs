//! `cargo xtask validate --only hmc`: hybrid Monte Carlo (000 §V) against exact canonical
//! answers, with deliberate misses; acceptance and sampling error against the segment length
//! and the miss rate, with the cost; stiff and extreme systems; checkpoints and chains.
//!
//! Prints a Markdown report on stdout and exits non-zero if a check fails. `--quick` runs the
//! reduced CI subset; `--figures DIR` is where the SVG figures go.
//!
//! Misses are injected with `hmc.fault_fraction` (see `dmd_sim::hmc`): in each segment that
//! fraction of the pairs is blind to its events, as a root search that missed them would
//! leave it. The sphere engine itself misses nothing.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use collide::Particle;
use dmd_sim::checkpoint::{self, Every, SceneSource};
use dmd_sim::hmc::{Acceptance, Chain, Ensemble, HmcSettings, Measure, block_average};
use dmd_sim::model::{HardSpheres, Stepped};
use dmd_sim::output::{Curve, plot_svg};
use dmd_sim::potential::Potentials;
use dmd_sim::run::{Quiet, RunError, RunOptions, Summary, run_scene, run_scene_with};
use dmd_sim::scene::Scene;
use dmd_sim::simulation::{LoopSettings, Simulation};
use event_queue::{BoundedQueue, HeapQueue, LazyQueue, Ticket};
use glam::DVec3;

struct Args {
    quick: bool,
    figures: PathBuf,
}

fn parse() -> Result<Args, String> {
    let mut quick = false;
    let mut figures = PathBuf::from("target/validate-figures");
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--figures" => figures = PathBuf::from(it.next().ok_or("--figures needs a folder")?),
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    Ok(Args { quick, figures })
}

struct Report {
    ok: bool,
}

impl Report {
    fn check(&mut self, ok: bool) -> &'static str {
        self.ok &= ok;
        if ok { "pass" } else { "**FAIL**" }
    }
}

fn main() -> ExitCode {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("validate_hmc: {e}");
            return ExitCode::from(2);
        }
    };
    let _ = std::fs::create_dir_all(&args.figures);
    let mut r = Report { ok: true };
    let mut w = String::new();
    if let Err(e) = validate(&args, &mut w, &mut r) {
        r.ok = false;
        let _ = writeln!(w, "\n**Error:** {e}");
    }
    print!("{w}");
    if r.ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

type Heap = LazyQueue<HeapQueue<Ticket>>;

const L2: f64 = 5.2;

/// Exact probability that two bodies in a periodic box of side `L2` sit in the square well
/// (σ = 1, λ = 1.5, ε = 1) at kT = 1: the Boltzmann-weighted shell volume over `Z`.
fn exact_well() -> f64 {
    let sphere = |r: f64| 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let shell = (sphere(1.5) - sphere(1.0)) * 1f64.exp();
    shell / (L2 * L2 * L2 - sphere(1.5) + shell)
}

/// Two bodies in the square well: the fraction of chain states in the well (block error),
/// acceptance, ⟨e^{−βΔH}⟩, CPU seconds.
fn two_body(fault: f64, acceptance: Acceptance, segments: usize, seed: u64) -> [f64; 5] {
    let pots = Potentials::from_tables(1, &[((0, 0), vec![[1.0, f64::INFINITY], [1.5, -1.0]])]);
    let model = Stepped::new(pots, vec![Particle::new(1.0).unwrap()], 2);
    let mut sim: Simulation<_, Heap> = Simulation::new(
        DVec3::splat(L2),
        &[DVec3::new(1.0, 1.0, 1.0), DVec3::new(3.5, 3.0, 2.0)],
        &[DVec3::new(0.3, -0.2, 0.1), DVec3::new(-0.3, 0.2, -0.1)],
        &[0, 0],
        model,
        LoopSettings {
            rebase_events: 1_000_000,
            seed,
            debug_check_events: 0,
            skin: 0.1,
            start_time: 0.0,
        },
    )
    .expect("a valid start");
    sim.set_fault_fraction(fault, seed);
    let mut chain = Chain::new(
        HmcSettings {
            ensemble: Ensemble::Canonical,
            segment_time: 2.0,
            temperature: 1.0,
            exchanges: 0,
            tolerance: 1e-9,
            acceptance,
            histogram_bins: 40,
            histogram_range: 10.0,
            seed,
            measure: Measure::Dynamics,
        },
        false,
    );
    let t = Instant::now();
    for _ in 0..200 {
        chain.segment(&mut sim).expect("a segment runs");
    }
    chain.recording = true;
    let mut well = Vec::with_capacity(segments);
    for _ in 0..segments {
        let s = chain.segment(&mut sim).expect("a segment runs");
        well.push(f64::from(u8::from(s.potential == -1.0)));
    }
    let b = block_average(&well);
    let s = chain.summary(2);
    [
        b.mean,
        b.error,
        s.acceptance_rate,
        s.exp_minus_beta_delta_h,
        t.elapsed().as_secs_f64(),
    ]
}

const SW: &str = r#"
version = 1
seed = 5
[box]
density = 0.5
[[species]]
name = "A"
count = 108
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf], [1.5, -1.0]]
[init]
positions = "fcc"
temperature = 1.5
[run]
equilibration_events = 3e4
[hmc]
segment_time = 1.0
segments = 1000
"#;

fn scene_run(text: &str, overrides: &[String]) -> Result<Summary, String> {
    let scene = Scene::from_str_with(text, overrides).map_err(|e| e.to_string())?;
    run_scene(&scene, Path::new("."), None, &mut Quiet).map_err(|e| e.to_string())
}

fn validate(args: &Args, w: &mut String, r: &mut Report) -> Result<(), String> {
    let q = args.quick;
    let s = |x: &str| x.to_owned();
    writeln!(
        w,
        "Reduced units (σ = m = ε = 1, k = 1). Misses are injected deliberately \
         (`hmc.fault_fraction`: in each segment that fraction of the pairs is blind to its \
         events); the sphere engine itself misses nothing. {} run; CPU seconds on the shared \
         2-core machine are indicative only.\n",
        if q { "Quick (CI)" } else { "Full" }
    )
    .ok();

    // ---- 1. Exact two-body answer -----------------------------------------------------------
    writeln!(
        w,
        "### Exact canonical answer: two bodies in a square well\n"
    )
    .ok();
    let exact = exact_well();
    writeln!(
        w,
        "Two bodies in a periodic box of side {L2} with a square well (σ = 1, λ = 1.5, ε = 1) at \
         kT = 1, τ = 2: the probability of the well is exactly its Boltzmann-weighted volume \
         over Z, **{exact:.5}**. Chain states after each segment; errors are block averages \
         (1σ). HMC must match at every miss rate (within 4σ); the same faulty segments \
         accepted blindly (plain dynamics with momentum refreshes) drift away.\n"
    )
    .ok();
    writeln!(
        w,
        "| blind fraction | acceptance rule | P(well) | ± (1σ) | deviation / σ | acceptance | ⟨e^(−βΔH)⟩ | CPU s | check |"
    )
    .ok();
    writeln!(w, "|---|---|---|---|---|---|---|---|---|").ok();
    let segs = if q { 8000 } else { 60000 };
    let faults: &[f64] = if q {
        &[0.0, 0.3]
    } else {
        &[0.0, 0.01, 0.1, 0.3, 0.6]
    };
    let (mut hmc_pts, mut plain_pts) = (Vec::new(), Vec::new());
    for &f in faults {
        for acc in [Acceptance::Metropolis, Acceptance::Always] {
            if f == 0.0 && acc == Acceptance::Always {
                continue;
            }
            let [p, e, a, x, cpu] = two_body(f, acc, segs, 31);
            let z = (p - exact) / e;
            let verdict = match acc {
                Acceptance::Metropolis => {
                    hmc_pts.push((f, p));
                    r.check(z.abs() < 4.0 && (f > 0.0 || a == 1.0))
                }
                Acceptance::Always => {
                    plain_pts.push((f, p));
                    if f >= 0.1 {
                        r.check(z.abs() > 5.0)
                    } else {
                        "reported"
                    }
                }
            };
            writeln!(
                w,
                "| {f} | {} | {p:.5} | {e:.5} | {z:+.1} | {a:.4} | {x:.4} | {cpu:.2} | {verdict} |",
                if acc == Acceptance::Metropolis {
                    "HMC"
                } else {
                    "always (plain)"
                }
            )
            .ok();
        }
    }
    plot_svg(
        &args.figures.join("hmc-two-body.svg"),
        "Two bodies in a square well: P(well) against the fraction of blind pairs",
        "fraction of segments with the pair blind",
        "P(well)",
        &[
            Curve {
                label: "exact",
                points: faults.iter().map(|&f| (f, exact)).collect(),
            },
            Curve {
                label: "HMC",
                points: hmc_pts,
            },
            Curve {
                label: "plain (every segment accepted)",
                points: plain_pts,
            },
        ],
    )
    .map_err(|e| e.to_string())?;
    writeln!(w, "\n![two-body well](figures/hmc-two-body.svg)\n").ok();

    // ---- 2. Acceptance and error against τ and the miss rate --------------------------------
    writeln!(
        w,
        "### Many bodies: acceptance and sampling error against segment length and miss rate\n"
    )
    .ok();
    writeln!(
        w,
        "Square well λ = 1.5, N = 108, ρσ³ = 0.5, kT = 1.5, canonical HMC. The reference ⟨U⟩/N \
         is the fault-free chain (exact dynamics, every segment accepted). The same CPU budget \
         is spread over segments of length τ: short segments decorrelate less per segment, \
         long ones are rejected more once misses happen (a blind interacting pair is likelier \
         to cross a step unseen). `CPU/seg` is per segment run. For reversible, \
         volume-preserving segments ⟨e^(−βΔH)⟩ is the probability that a segment run backwards \
         from an allowed state starts in one, i.e. 1 − the rate of segments ending in an \
         overlap: the sum shown must be 1 within its (large, heavy-tailed) scatter.\n"
    )
    .ok();
    let (n_ref, budget) = if q { (1500.0, 60.0) } else { (12000.0, 400.0) };
    let reference = scene_run(
        SW,
        &[s("hmc.segment_time=1.0"), format!("hmc.segments={n_ref}")],
    )?;
    let hr = reference.hmc.as_ref().ok_or("no hmc section")?;
    let (u_ref, e_ref) = (
        hr.potential_energy_per_body.mean,
        hr.potential_energy_per_body.error,
    );
    let eos = dmd_sim::reference::square_well::SquareWellEos::new(1.5)
        .ok_or("λ = 1.5 is fitted")?
        .energy_per_particle(1.5, 0.5);
    let verdict =
        r.check(hr.accepted == hr.segments && (hr.exp_minus_beta_delta_h - 1.0).abs() < 1e-12);
    writeln!(
        w,
        "Reference: ⟨U⟩/N = {u_ref:.4} ± {e_ref:.4} from {} segments, every one accepted, \
         ⟨e^(−βΔH)⟩ − 1 = {:.1e} ({verdict}); the published equation of state gives {eos:.4} \
         for N → ∞ (a size effect of N = 108 and the fit's accuracy, not checked here).\n",
        hr.segments,
        hr.exp_minus_beta_delta_h - 1.0
    )
    .ok();
    writeln!(
        w,
        "| τ | blind fraction | segments | acceptance | segments with a miss | ⟨U⟩/N | ± (1σ) | (U − U_ref)/σ | ⟨e^(−βΔH)⟩ + overlap rate | CPU s | CPU/seg ms | check |"
    )
    .ok();
    writeln!(w, "|---|---|---|---|---|---|---|---|---|---|---|---|").ok();
    let taus: &[f64] = if q {
        &[0.3, 1.0]
    } else {
        &[0.1, 0.3, 1.0, 3.0]
    };
    let fr: &[f64] = if q {
        &[0.003]
    } else {
        &[0.0, 0.001, 0.003, 0.01]
    };
    let mut acc_curves: Vec<(f64, Vec<(f64, f64)>)> = fr.iter().map(|&f| (f, Vec::new())).collect();
    let mut hist = None;
    for &tau in taus {
        for (k, &f) in fr.iter().enumerate() {
            // About the same simulated time per run, so roughly the same CPU budget.
            let n = ((budget / tau).round() as u64).max(100);
            let sum = scene_run(
                SW,
                &[
                    format!("hmc.segment_time={tau}"),
                    format!("hmc.segments={n}"),
                    format!("hmc.fault_fraction={f}"),
                    format!("seed={}", 40 + k),
                ],
            )?;
            let h = sum.hmc.as_ref().ok_or("no hmc section")?;
            let u = &h.potential_energy_per_body;
            let sigma = (u.error * u.error + e_ref * e_ref).sqrt();
            let z = (u.mean - u_ref) / sigma;
            let verdict = r.check(z.abs() < 4.0);
            acc_curves[k].1.push((tau, h.acceptance_rate));
            if tau == 1.0 && (f - 0.003).abs() < 1e-12 {
                hist = Some(h.delta_h_histogram.clone());
            }
            let cpu = sum.cpu_seconds;
            writeln!(
                w,
                "| {tau} | {f} | {} | {:.3} | {} | {:.4} | {:.4} | {z:+.1} | {:.3} | {cpu:.1} | {:.2} | {verdict} |",
                h.segments,
                h.acceptance_rate,
                h.segments_with_misses,
                u.mean,
                u.error,
                h.exp_minus_beta_delta_h
                    + h.rejected_by_cause["overlap"] as f64 / h.segments as f64,
                1e3 * cpu / h.segments as f64,
            )
            .ok();
        }
    }
    plot_svg(
        &args.figures.join("hmc-acceptance.svg"),
        "Acceptance against segment length (square well, N = 108)",
        "segment length τ",
        "acceptance rate",
        &acc_curves
            .iter()
            .map(|(f, p)| Curve {
                label: Box::leak(format!("blind fraction {f}").into_boxed_str()),
                points: p.clone(),
            })
            .collect::<Vec<_>>(),
    )
    .map_err(|e| e.to_string())?;
    writeln!(w, "\n![acceptance against τ](figures/hmc-acceptance.svg)\n").ok();
    if let Some(h) = hist {
        let width = (h.high - h.low) / h.counts.len() as f64;
        let pts: Vec<(f64, f64)> = h
            .counts
            .iter()
            .enumerate()
            .map(|(k, &c)| (h.low + (k as f64 + 0.5) * width, c as f64))
            .collect();
        plot_svg(
            &args.figures.join("hmc-delta-h.svg"),
            "ΔH at the end of segments (τ = 1, blind fraction 0.003)",
            "ΔH / ε",
            "segments",
            &[Curve {
                label: "ΔH histogram",
                points: pts,
            }],
        )
        .map_err(|e| e.to_string())?;
        writeln!(
            w,
            "ΔH of the segments at τ = 1, blind fraction 0.003: {} within round-off of 0 (in \
             the central bin), {} overlapping (+∞, always rejected), {} beyond ±{}.\n\n\
             ![ΔH histogram](figures/hmc-delta-h.svg)\n",
            h.within_round_off,
            h.infinite,
            h.below + h.above,
            h.high
        )
        .ok();
    }

    // ---- 3. Microcanonical ----------------------------------------------------------------
    writeln!(w, "### Microcanonical chains\n").ok();
    writeln!(
        w,
        "Velocity exchanges between random pairs (N per segment), acceptance only if ΔH = 0 \
         within 10⁻⁹ relative. The energy of every chain state must equal the first one's to \
         round-off, with or without misses.\n"
    )
    .ok();
    writeln!(
        w,
        "| blind fraction | segments | acceptance | rejected (overlap / energy) | max over chain states of abs(E − E₀)/abs(E₀) | check |"
    )
    .ok();
    writeln!(w, "|---|---|---|---|---|---|").ok();
    for f in [0.0, 0.003] {
        let sum = scene_run(
            SW,
            &[
                s("hmc.ensemble=microcanonical"),
                s("hmc.segment_time=0.5"),
                format!("hmc.segments={}", if q { 300 } else { 2000 }),
                format!("hmc.fault_fraction={f}"),
            ],
        )?;
        let h = sum.hmc.as_ref().ok_or("no hmc section")?;
        let drift =
            (sum.energy_total_end - sum.energy_total_start).abs() / sum.energy_total_start.abs();
        let ok = drift < 1e-11 && (f > 0.0 || h.accepted == h.segments);
        let verdict = r.check(ok);
        writeln!(
            w,
            "| {f} | {} | {:.3} | {} / {} | {drift:.1e} | {verdict} |",
            h.segments,
            h.acceptance_rate,
            h.rejected_by_cause["overlap"],
            h.rejected_by_cause["energy"]
        )
        .ok();
    }

    // ---- 4. Stiff and extreme systems --------------------------------------------------------
    writeln!(w, "\n### Stiff and extreme systems\n").ok();
    writeln!(
        w,
        "Without misses every segment must be accepted and ⟨e^(−βΔH)⟩ = 1 to round-off, \
         whatever the system; with misses (blind fraction 0.01) the chain must stay free of \
         overlaps.\n"
    )
    .ok();
    writeln!(
        w,
        "| system | τ | acceptance (exact) | max abs(ΔH) (exact) | acceptance (misses) | chain states overlapping | check |"
    )
    .ok();
    writeln!(w, "|---|---|---|---|---|---|---|").ok();
    let n_stiff = if q { 100 } else { 400 };
    let cases: Vec<(&str, Vec<String>)> = vec![
        (
            "segments of 10⁻⁶ (almost no events)",
            vec![s("hmc.segment_time=1e-6")],
        ),
        (
            "deep well, ε = 50 kT",
            vec![s("pair.0.steps=[[1.0, inf], [1.5, -75.0]]")],
        ),
        (
            "steep shoulder, +50 kT",
            vec![s("pair.0.steps=[[1.0, inf], [1.2, 75.0], [1.5, -1.0]]")],
        ),
        (
            "hard spheres near freezing, ρσ³ = 0.93",
            vec![
                s("pair.0.steps=[[1.0, inf]]"),
                s("box.density=0.93"),
                s("hmc.segment_time=0.1"),
            ],
        ),
        (
            "mass ratio 10⁴ (species B heavy)",
            vec![
                s(
                    "species=[{ name = \"A\", count = 81 }, { name = \"B\", count = 27, mass = 1e4 }]",
                ),
                s(
                    "pair=[{ species = [\"A\", \"A\"], steps = [[1.0, inf], [1.5, -1.0]] }, { species = [\"A\", \"B\"], steps = [[1.0, inf], [1.5, -1.0]] }, { species = [\"B\", \"B\"], steps = [[1.0, inf]] }]",
                ),
            ],
        ),
    ];
    for (name, extra) in cases {
        let tau = extra
            .iter()
            .find_map(|o| o.strip_prefix("hmc.segment_time="))
            .unwrap_or("1.0")
            .to_owned();
        let mut exact_o = extra.clone();
        exact_o.push(format!("hmc.segments={n_stiff}"));
        let a = scene_run(SW, &exact_o)?;
        let ha = a.hmc.as_ref().ok_or("no hmc section")?;
        let mut miss_o = exact_o.clone();
        miss_o.push(s("hmc.fault_fraction=0.01"));
        let b = scene_run(SW, &miss_o)?;
        let hb = b.hmc.as_ref().ok_or("no hmc section")?;
        let ok = ha.accepted == ha.segments
            && (ha.exp_minus_beta_delta_h - 1.0).abs() < 1e-9
            && hb.overlapping_states == 0
            && a.anomalies == 0;
        let verdict = r.check(ok);
        writeln!(
            w,
            "| {name} | {tau} | {:.3} | {:.1e} | {:.3} | {} | {verdict} |",
            ha.acceptance_rate, ha.delta_h_max_abs, hb.acceptance_rate, hb.overlapping_states
        )
        .ok();
    }

    // ---- 5. Cost ---------------------------------------------------------------------------
    writeln!(w, "\n### Cost of HMC, checkpoints and chains\n").ok();
    cost(args, w, r)?;
    Ok(())
}

const HS: &str = r#"
version = 1
seed = 8
[box]
density = 0.5
[[species]]
name = "A"
count = 4000
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf]]
[init]
positions = "fcc"
temperature = 1.0
[run]
equilibration_events = 2e5
time = 20
"#;

fn cost(args: &Args, w: &mut String, r: &mut Report) -> Result<(), String> {
    let q = args.quick;
    let s = |x: &str| x.to_owned();
    let time: f64 = if q { 5.0 } else { 20.0 };
    let reps = if q { 1 } else { 3 };
    writeln!(
        w,
        "Hard spheres, N = 4000, ρσ³ = 0.5, {time} time units of production. Plain dynamics \
         against canonical HMC with segments of τ (every segment accepted: the cost is the \
         refresh, the snapshot, two energy evaluations and predicting every event afresh per \
         segment). CPU seconds of production (one thread).\n"
    )
    .ok();
    writeln!(
        w,
        "| run | events | CPU s (median of {reps}) | events per CPU µs | CPU per segment beyond its events (ms) |"
    )
    .ok();
    writeln!(w, "|---|---|---|---|---|").ok();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    // Runs are repeated and interleaved so that a burst of load from other work on the shared
    // machine does not land on one configuration only.
    let configs: Vec<(String, Vec<String>, f64)> =
        std::iter::once(("plain".to_owned(), vec![format!("run.time={time}")], 0.0))
            .chain([1e-6, 0.1, 0.5, 2.0].into_iter().map(|tau: f64| {
                let n = if tau < 1e-3 {
                    200.0
                } else {
                    (time / tau).round()
                };
                (
                    format!("HMC τ = {tau} ({n} segments)"),
                    vec![
                        s("run.time="),
                        format!("hmc.segment_time={tau}"),
                        format!("hmc.segments={n}"),
                    ],
                    n,
                )
            }))
            .collect();
    let mut cpu: Vec<Vec<f64>> = vec![Vec::new(); configs.len()];
    let mut events = vec![0u64; configs.len()];
    for _ in 0..reps {
        for (k, (_, o, _)) in configs.iter().enumerate() {
            let sum = scene_run(HS, o)?;
            cpu[k].push(sum.cpu_seconds);
            events[k] = sum.events;
        }
    }
    let cpu: Vec<f64> = cpu.into_iter().map(median).collect();
    let rate = events[0] as f64 / cpu[0];
    for (k, (name, _, n)) in configs.iter().enumerate() {
        let per_seg = if *n > 0.0 {
            format!("{:.2}", (cpu[k] - events[k] as f64 / rate) / n * 1e3)
        } else {
            "—".to_owned()
        };
        writeln!(
            w,
            "| {name} | {} | {:.3} | {:.3} | {per_seg} |",
            events[k],
            cpu[k],
            events[k] as f64 / cpu[k] * 1e-6
        )
        .ok();
    }
    writeln!(
        w,
        "\nThe τ = 10⁻⁶ row has almost no events: its CPU per segment is the overhead itself \
         (refresh, saved state, two energies from the distances, level repair, predicting every \
         event afresh). The other rows estimate it by subtracting their events at the plain \
         rate, which carries the noise of both runs.\n"
    )
    .ok();

    // Checkpoint write and read.
    let dir = std::env::temp_dir().join(format!("dmd-validate-hmc-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    writeln!(
        w,
        "\nCheckpoints of the same hard-sphere system (plain run, saved at a re-basing): file \
         size, time to encode and write it (fsync and rename included), to read and decode it, \
         and to rebuild the event lists and schedule from it. Median of 5.\n"
    )
    .ok();
    writeln!(
        w,
        "| N | file bytes | write ms | read + decode ms | rebuild ms |"
    )
    .ok();
    writeln!(w, "|---|---|---|---|---|").ok();
    let sizes: &[u64] = if q { &[4000] } else { &[4000, 32000] };
    for &n in sizes {
        let o = vec![
            format!("species.0.count={n}"),
            s("run.equilibration_events=0"),
            s("run.time="),
            s("run.events=1e6"),
            format!("run.rebase_events={}", 5 * n),
        ];
        let scene = Scene::from_str_with(HS, &o).map_err(|e| e.to_string())?;
        let opts = RunOptions {
            checkpoint_every: Some(Every::Events(1)),
            source: Some(SceneSource {
                text: HS.to_owned(),
                overrides: o.clone(),
                base: PathBuf::from("."),
                file: PathBuf::from("hs.toml"),
            }),
            resume: None,
            halt_after_checkpoint: true,
        };
        match run_scene_with(&scene, Path::new("."), Some(&dir), &mut Quiet, &opts) {
            Err(RunError::Halted) => {}
            other => return Err(format!("expected a halt after the checkpoint: {other:?}")),
        }
        let path = dir.join(checkpoint::FILE_NAME);
        let bytes = std::fs::metadata(&path).map_err(|e| e.to_string())?.len();
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let mut reads = Vec::new();
        let mut writes = Vec::new();
        let mut rebuilds = Vec::new();
        for _ in 0..5 {
            let t = Instant::now();
            let c = checkpoint::read(&path).map_err(|e| e.to_string())?;
            reads.push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            checkpoint::write(&dir.join("copy.dmd"), &c).map_err(|e| e.to_string())?;
            writes.push(t.elapsed().as_secs_f64() * 1e3);
            let pots = Potentials::from_scene(&scene);
            let model = HardSpheres::new(pots, vec![Particle::new(1.0).unwrap()]);
            let t = Instant::now();
            let sim: Simulation<_, LazyQueue<BoundedQueue<Ticket>>> =
                Simulation::from_state(model, &c.sim).map_err(|e| e.to_string())?;
            rebuilds.push(t.elapsed().as_secs_f64() * 1e3);
            std::hint::black_box(sim.bodies().len());
        }
        writeln!(
            w,
            "| {n} | {bytes} | {:.1} | {:.1} | {:.1} |",
            median(writes),
            median(reads),
            median(rebuilds)
        )
        .ok();
    }

    // Parallel chains.
    writeln!(
        w,
        "\nFour independent chains (square well N = 108, HMC) as one `[chains]` scene on 1 and 2 \
         threads (wall-clock seconds; the machine's 2 cores are shared with other work, so the \
         speed-up is a lower bound); the aggregates must be identical.\n"
    )
    .ok();
    let text = format!("{SW}\n[chains]\ncount = 4\n");
    let scene = Scene::from_str_with(
        &text,
        &[format!("hmc.segments={}", if q { 300 } else { 2000 })],
    )
    .map_err(|e| e.to_string())?;
    let source = SceneSource {
        text: text.clone(),
        overrides: vec![format!("hmc.segments={}", if q { 300 } else { 2000 })],
        base: PathBuf::from("."),
        file: PathBuf::from("chains.toml"),
    };
    let mut results = Vec::new();
    let mut walls = Vec::new();
    for threads in [1, 2] {
        let out = dir.join(format!("chains-{threads}"));
        let t = Instant::now();
        let e =
            dmd_sim::chains::run_ensemble(&scene, &source, &out, Some(threads), None, &|_, _| {})
                .map_err(|e| e.to_string())?;
        walls.push(t.elapsed().as_secs_f64());
        results.push(e);
    }
    let same = results[0] == results[1];
    let verdict = r.check(same);
    let u = &results[0].points[0].quantities["hmc.potential_energy_per_body.mean"];
    writeln!(
        w,
        "| threads | wall s | speed-up |\n|---|---|---|\n| 1 | {:.2} | 1 |\n| 2 | {:.2} | {:.2} |\n\n\
         Identical aggregates on 1 and 2 threads: {verdict}. ⟨U⟩/N over the 4 chains: {:.4} ± \
         {:.4} (scatter between chains), ± {:.4} (chains' block averages combined).\n",
        walls[0],
        walls[1],
        walls[0] / walls[1],
        u.mean,
        u.error.unwrap_or(f64::NAN),
        u.block_error.unwrap_or(f64::NAN)
    )
    .ok();
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
