//! Validation of the event queues at scale, for `cargo xtask validate` (prints Markdown).
//!
//! 1. **Exact order at scale**: `--events` events pushed (times from several adversarial
//!    distributions: exponential, heavy ties, far from zero, tiny scales, ±∞, round-off earlier
//!    than the last pop) and popped, by every queue; the pop sequence must equal a sort by
//!    (time, arrival) and the queues must agree event by event in an interleaved hold run.
//! 2. **Hold model**: holds per second at n = 10³ … 10⁶ (quick: … 10⁵), exponential and uniform
//!    increments, every queue and `std::collections::BinaryHeap` in the same run; the bounded
//!    queue's layout and work per hold; a figure.
//!
//! Exits non-zero if any order check fails. Speed targets are reported, not enforced: a shared
//! machine's timings are not a pass/fail criterion.
//!
//! `cargo run --release -p dmd-event-queue --example validate_queue -- [--events N] [--quick] [--figures DIR]`

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use event_queue::hold::{Hold, Increment, PairHold, PairScheduler, StdHeap};
use event_queue::{BoundedQueue, EventQueue, HeapQueue, Layout, LazyQueue, TournamentTree, Tuning};

struct Args {
    events: usize,
    quick: bool,
    figures: Option<PathBuf>,
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        events: 10_000_000,
        quick: false,
        figures: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(f) = it.next() {
        match f.as_str() {
            "--events" => {
                let v = it.next().ok_or("`--events` needs a number")?;
                a.events = v
                    .parse()
                    .map_err(|_| format!("bad `--events` value `{v}`"))?;
            }
            "--quick" => a.quick = true,
            "--figures" => a.figures = Some(it.next().ok_or("`--figures` needs a folder")?.into()),
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    Ok(a)
}

/// SplitMix64, for reproducible workloads.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f64 {
        ((self.next() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }
}

/// A named distribution of event times for the order checks.
struct Workload {
    name: &'static str,
    draw: fn(&mut Rng, usize) -> f64,
    /// Whether the times stay within a few hundred windows of the fixed layout (2¹⁴ × 10⁻³):
    /// a fixed layout is for a bounded horizon, beyond it each wrap costs O(overflow).
    fixed_horizon: bool,
}

const WORKLOADS: &[Workload] = &[
    Workload {
        name: "exponential",
        draw: |r, _| -r.unit().ln(),
        fixed_horizon: true,
    },
    Workload {
        name: "heavy ties (1000 distinct times)",
        draw: |r, _| (r.next() % 1000) as f64,
        fixed_horizon: true,
    },
    Workload {
        name: "far from zero (1e12 + uniform[0,1))",
        draw: |r, _| 1e12 + r.unit(),
        fixed_horizon: true,
    },
    Workload {
        name: "tiny scale (1e-12 uniform)",
        draw: |r, _| 1e-12 * r.unit(),
        fixed_horizon: true,
    },
    Workload {
        name: "mixed scales, ±inf, -0.0",
        draw: |r, i| match i % 97 {
            0 => f64::INFINITY,
            1 => f64::NEG_INFINITY,
            2 => -0.0,
            _ => r.unit() * 10f64.powi((r.next() % 24) as i32 - 12),
        },
        fixed_horizon: false,
    },
    Workload {
        name: "bursts of simultaneous events",
        draw: |r, i| (i / 5000) as f64 + if r.next() % 2 == 0 { 0.0 } else { r.unit() },
        fixed_horizon: true,
    },
];

/// Pushes all `times` then pops them all; checks the order against a sort by (time, arrival).
fn push_all_pop_all<Q: EventQueue<Payload = u32>>(
    mut q: Q,
    times: &[f64],
    expected: &[u32],
) -> bool {
    for (i, &t) in times.iter().enumerate() {
        q.push(t, i as u32).expect("no NaN in the workloads");
    }
    let mut k = 0;
    while let Some(e) = q.pop() {
        if expected.get(k) != Some(&e.payload) {
            return false;
        }
        k += 1;
    }
    k == expected.len()
}

/// Interleaved run: each step pops one event and pushes one or two later ones (sometimes one
/// slightly *earlier* than the pop, as round-off does), on all queues in lockstep.
fn lockstep(steps: usize, seed: u64) -> Result<(), String> {
    let mut rng = Rng(seed);
    let mut heap = HeapQueue::new();
    let mut bounded = BoundedQueue::new();
    let mut fixed = BoundedQueue::with_tuning(Tuning::Fixed(Layout {
        width: 1e-3,
        buckets: 1 << 14,
    }))
    .expect("valid layout");
    let mut std_heap = StdHeap::new();
    let mut id = 0u32;
    let push = |t: f64,
                id: u32,
                h: &mut HeapQueue<u32>,
                b: &mut BoundedQueue<u32>,
                f: &mut BoundedQueue<u32>,
                s: &mut StdHeap<u32>| {
        h.push(t, id).unwrap();
        b.push(t, id).unwrap();
        f.push(t, id).unwrap();
        s.push(t, id).unwrap();
    };
    for _ in 0..10_000 {
        push(
            -rng.unit().ln(),
            id,
            &mut heap,
            &mut bounded,
            &mut fixed,
            &mut std_heap,
        );
        id += 1;
    }
    for step in 0..steps {
        let a = heap.pop();
        let b = bounded.pop();
        let c = fixed.pop();
        let d = std_heap.pop();
        if a != b || a != c || a != d {
            return Err(format!(
                "step {step}: heap {a:?}, bounded {b:?}, fixed {c:?}, std {d:?}"
            ));
        }
        let Some(e) = a else { break };
        let n_new = 1 + usize::from(rng.next().is_multiple_of(3) && heap.len() < 20_000);
        for _ in 0..n_new {
            let t = if rng.next().is_multiple_of(50) {
                e.time - 1e-12 * rng.unit() // round-off: before the last pop
            } else {
                e.time - rng.unit().ln()
            };
            push(t, id, &mut heap, &mut bounded, &mut fixed, &mut std_heap);
            id = id.wrapping_add(1);
        }
    }
    Ok(())
}

struct HoldRow {
    n: usize,
    dist: &'static str,
    rates: [f64; 3],
    bounded: String,
}

fn holds_per_second<Q: EventQueue<Payload = u64>>(
    q: Q,
    n: usize,
    inc: Increment,
    holds: u64,
) -> (f64, Hold<Q>) {
    let mut h = Hold::new(q, n, inc, 11);
    h.run(n as u64);
    let t = Instant::now();
    std::hint::black_box(h.run(holds));
    (holds as f64 / t.elapsed().as_secs_f64(), h)
}

fn median3(mut v: [f64; 3]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[1]
}

fn hold_table(sizes: &[usize], holds: u64) -> Vec<HoldRow> {
    let mut rows = Vec::new();
    for (inc, dist) in [
        (Increment::Exponential, "exp"),
        (Increment::Uniform, "uniform"),
    ] {
        for &n in sizes {
            // rounds[rep][queue]: the three queues in turn, three rounds.
            let mut rounds = [[0.0; 3]; 3];
            let mut bounded = String::new();
            for round in &mut rounds {
                round[0] = holds_per_second(StdHeap::new(), n, inc, holds).0;
                round[1] = holds_per_second(HeapQueue::new(), n, inc, holds).0;
                let (rate, h) = holds_per_second(BoundedQueue::new(), n, inc, holds);
                round[2] = rate;
                let s = h.queue().stats();
                let l = h.queue().layout();
                bounded = format!(
                    "Δ = {:.3e}, {} buckets, {:.2} events/bucket, {:.2} moves/hold",
                    l.width,
                    l.buckets,
                    s.bucket_events as f64 / s.buckets_consumed.max(1) as f64,
                    (s.block_moves + s.overflow_moves) as f64 / (holds + n as u64) as f64
                );
            }
            let r: [[f64; 3]; 3] =
                std::array::from_fn(|k| std::array::from_fn(|rep| rounds[rep][k]));
            eprintln!("hold {dist} n={n} done");
            rows.push(HoldRow {
                n,
                dist,
                rates: [median3(r[0]), median3(r[1]), median3(r[2])],
                bounded,
            });
        }
    }
    rows
}

/// Steps per second of the pair-hold model on one scheduler, after n warm-up steps.
fn steps_per_second<S: PairScheduler>(s: S, n: u32, steps: u64) -> f64 {
    let mut m = PairHold::new(s, n, Increment::Exponential, 13);
    m.run(u64::from(n));
    let t = Instant::now();
    std::hint::black_box(m.run(steps));
    steps as f64 / t.elapsed().as_secs_f64()
}

/// Rows of (n, [tree, lazy heap, lazy bounded] steps/s), median of 3 rounds.
fn pair_table(sizes: &[usize], steps: u64) -> Vec<(usize, [f64; 3])> {
    sizes
        .iter()
        .map(|&n| {
            let m = n as u32;
            let mut rounds = [[0.0; 3]; 3];
            for round in &mut rounds {
                round[0] = steps_per_second(TournamentTree::new(n), m, steps);
                round[1] = steps_per_second(LazyQueue::new(HeapQueue::new(), n), m, steps);
                round[2] = steps_per_second(LazyQueue::new(BoundedQueue::new(), n), m, steps);
            }
            eprintln!("pair hold n={n} done");
            (
                n,
                std::array::from_fn(|k| median3(std::array::from_fn(|r| rounds[r][k]))),
            )
        })
        .collect()
}

fn plot(rows: &[HoldRow], path: &std::path::Path) -> Result<(), String> {
    use plotters::prelude::*;
    let root = SVGBackend::new(path, (720, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let n_max = rows.iter().map(|r| r.n).max().unwrap_or(1000) as f64;
    let y_max = rows.iter().flat_map(|r| r.rates).fold(0.0, f64::max) * 1.3 / 1e6;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Hold model: throughput against queue size",
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((500f64..n_max * 2.0).log_scale(), 0f64..y_max)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("queue size n")
        .y_desc("million holds per second")
        .draw()
        .map_err(|e| e.to_string())?;
    let names = ["std BinaryHeap", "HeapQueue", "BoundedQueue"];
    let colors = [BLACK, BLUE, RED];
    for dist in ["exp", "uniform"] {
        for (k, name) in names.iter().enumerate() {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.dist == dist)
                .map(|r| (r.n as f64, r.rates[k] / 1e6))
                .collect();
            let style = if dist == "exp" {
                colors[k].stroke_width(2)
            } else {
                colors[k].mix(0.5).stroke_width(1)
            };
            chart
                .draw_series(LineSeries::new(pts.clone(), style))
                .map_err(|e| e.to_string())?
                .label(format!("{name} ({dist})"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, style.filled())))
                .map_err(|e| e.to_string())?;
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

fn main() -> ExitCode {
    let a = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("validate: {e}");
            return ExitCode::from(2);
        }
    };
    let mut ok = true;

    println!("### Exact order at scale\n");
    println!(
        "Each workload pushes {} events into every queue, then pops them all; the pop sequence must \
         equal a sort by (time, arrival). `BoundedQueue` runs auto-tuned and with a fixed layout of \
         2¹⁴ buckets of width 10⁻³ (four blocks). A fixed layout is for a bounded horizon (Paul's \
         setting); on times spread over 24 decades each of its wrap-arounds would cost O(n), so it \
         is not run there.\n",
        a.events
    );
    println!(
        "| workload | HeapQueue | BoundedQueue (auto) | BoundedQueue (fixed) | std BinaryHeap | seconds |"
    );
    println!("|---|---|---|---|---|---|");
    for (w, workload) in WORKLOADS.iter().enumerate() {
        let t0 = Instant::now();
        let mut rng = Rng(1000 + w as u64);
        let times: Vec<f64> = (0..a.events)
            .map(|i| (workload.draw)(&mut rng, i))
            .collect();
        let mut expected: Vec<u32> = (0..a.events as u32).collect();
        // Stable sort by time = sort by (time, arrival); -0.0 and +0.0 compare equal as in the queues.
        expected.sort_by(|&x, &y| {
            times[x as usize]
                .partial_cmp(&times[y as usize])
                .expect("no NaN")
        });
        let fixed = BoundedQueue::with_tuning(Tuning::Fixed(Layout {
            width: 1e-3,
            buckets: 1 << 14,
        }))
        .expect("valid layout");
        // None: not run (times far outside the fixed layout's horizon).
        let results = [
            Some(push_all_pop_all(HeapQueue::new(), &times, &expected)),
            Some(push_all_pop_all(BoundedQueue::new(), &times, &expected)),
            workload
                .fixed_horizon
                .then(|| push_all_pop_all(fixed, &times, &expected)),
            Some(push_all_pop_all(StdHeap::new(), &times, &expected)),
        ];
        ok &= results.iter().all(|r| r.unwrap_or(true));
        let cell = |r: Option<bool>| match r {
            Some(true) => "exact",
            Some(false) => "**WRONG**",
            None => "outside its horizon",
        };
        println!(
            "| {} | {} | {} | {} | {} | {:.1} |",
            workload.name,
            cell(results[0]),
            cell(results[1]),
            cell(results[2]),
            cell(results[3]),
            t0.elapsed().as_secs_f64()
        );
        eprintln!("order check `{}` done", workload.name);
    }
    let steps = a.events;
    let t0 = Instant::now();
    let lock = lockstep(steps, 7);
    println!(
        "\nInterleaved run, {steps} pops with one or two pushes each (2 % of them slightly *before* \
         the event just popped, as round-off produces), all queues in lockstep: {} ({:.1} s).\n",
        match &lock {
            Ok(()) => "identical pops".to_owned(),
            Err(e) => format!("**MISMATCH** {e}"),
        },
        t0.elapsed().as_secs_f64()
    );
    ok &= lock.is_ok();

    let (sizes, holds): (&[usize], u64) = if a.quick {
        (&[1_000, 10_000, 100_000], 1_000_000)
    } else {
        (&[1_000, 10_000, 100_000, 1_000_000], 10_000_000)
    };
    let rows = hold_table(sizes, holds);
    println!("### Hold model\n");
    println!(
        "Fill with n events, n warm-up holds, then {holds} timed holds (pop the earliest, push it \
         again at its time plus an increment of mean 1); median of 3 rounds, queues measured in turn. \
         Wall-clock on a shared 2-core machine: compare within a row.\n"
    );
    println!(
        "| increments | n | std BinaryHeap (holds/s) | HeapQueue | BoundedQueue | bounded / std | bounded layout |"
    );
    println!("|---|---|---|---|---|---|---|");
    for r in &rows {
        println!(
            "| {} | {} | {:.3e} | {:.3e} | {:.3e} | {:.2} | {} |",
            r.dist,
            r.n,
            r.rates[0],
            r.rates[1],
            r.rates[2],
            r.rates[2] / r.rates[0],
            r.bounded
        );
    }
    println!();
    for dist in ["exp", "uniform"] {
        let at = |n: usize| rows.iter().find(|r| r.dist == dist && r.n == n);
        if let (Some(small), Some(big)) = (at(1_000), at(*sizes.last().unwrap())) {
            let flat = small.rates[2] / big.rates[2];
            let verdict = |pass: bool| if pass { "met" } else { "missed" };
            println!(
                "- {dist}: bounded at n = 10³ is {:.2}× std (target ≥ 1: {}); at n = {} it is {:.2}× std \
                 (target ≥ 5 at 10⁶: {}); throughput at 10³ is {flat:.2}× that at n = {} (target ≤ 2: {}).",
                small.rates[2] / small.rates[0],
                verdict(small.rates[2] >= small.rates[0]),
                big.n,
                big.rates[2] / big.rates[0],
                if big.n == 1_000_000 {
                    verdict(big.rates[2] >= 5.0 * big.rates[0])
                } else {
                    "not measured in a quick run"
                },
                big.n,
                verdict(flat <= 2.0),
            );
        }
    }
    println!("\n### One event per participant: tournament tree or lazy invalidation\n");
    println!(
        "The pair-hold model: n participants with one pending event each; a step executes the \
         earliest and gives it and a random partner new events (exponential increments), as a \
         collision does. `TournamentTree` updates two leaves; a `LazyQueue` invalidates both \
         participants and pushes two events, leaving the partner's old one stale. {holds} steps, \
         median of 3 rounds.\n"
    );
    println!(
        "| n | TournamentTree (steps/s) | LazyQueue<HeapQueue> | LazyQueue<BoundedQueue> | bounded / tree |"
    );
    println!("|---|---|---|---|---|");
    for (n, r) in pair_table(sizes, holds) {
        println!(
            "| {n} | {:.3e} | {:.3e} | {:.3e} | {:.2} |",
            r[0],
            r[1],
            r[2],
            r[2] / r[0]
        );
    }
    if let Some(dir) = &a.figures {
        if let Err(e) = std::fs::create_dir_all(dir) {
            eprintln!("validate: cannot create {}: {e}", dir.display());
            return ExitCode::FAILURE;
        }
        let path = dir.join("event-queue-hold.svg");
        match plot(&rows, &path) {
            Ok(()) => {
                println!("\n![Hold throughput against queue size](figures/event-queue-hold.svg)")
            }
            Err(e) => {
                eprintln!("validate: could not draw {}: {e}", path.display());
                ok = false;
            }
        }
    }
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
