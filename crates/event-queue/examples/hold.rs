//! The hold benchmark as a command: one line per queue with holds per second and the speed-up
//! over `std::collections::BinaryHeap` (the last number on each line).
//!
//! ```text
//! cargo run --release -p dmd-event-queue --example hold -- --size 1000000 --holds 20000000 --dist exp
//! ```
//!
//! Each queue is filled with `--size` events, warmed up with `--size` holds (so an auto-tuned
//! queue has settled), then timed over `--holds` holds. Queues are measured in turn, `--reps`
//! rounds, and the median is reported, so slow drifts of a shared machine hit all alike.

use std::process::ExitCode;
use std::time::Instant;

use event_queue::hold::{Hold, Increment, StdHeap};
use event_queue::{BoundedQueue, EventQueue, HeapQueue};

pub(crate) struct Args {
    size: usize,
    holds: u64,
    dist: Increment,
    reps: usize,
    seed: u64,
}

/// Parses the command line (without the program name).
pub(crate) fn parse(args: &[String]) -> Result<Args, String> {
    let mut a = Args {
        size: 100_000,
        holds: 2_000_000,
        dist: Increment::Exponential,
        reps: 3,
        seed: 1,
    };
    let mut it = args.iter().cloned();
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("`{flag}` needs a value"));
        match flag.as_str() {
            "--size" => a.size = number(&flag, &value()?)?,
            "--holds" => a.holds = number(&flag, &value()?)?,
            "--reps" => a.reps = number(&flag, &value()?)?,
            "--seed" => a.seed = number(&flag, &value()?)?,
            "--dist" => {
                a.dist = match value()?.as_str() {
                    "exp" => Increment::Exponential,
                    "uniform" => Increment::Uniform,
                    other => return Err(format!("`--dist` is exp or uniform, not `{other}`")),
                }
            }
            "-h" | "--help" => {
                return Err(
                    "usage: hold [--size N] [--holds H] [--dist exp|uniform] [--reps R] [--seed S]"
                        .into(),
                );
            }
            other => return Err(format!("unknown argument `{other}` (see --help)")),
        }
    }
    if a.size == 0 || a.holds == 0 || a.reps == 0 {
        return Err("`--size`, `--holds` and `--reps` must be at least 1".into());
    }
    Ok(a)
}

fn number<T: std::str::FromStr>(flag: &str, v: &str) -> Result<T, String> {
    v.parse()
        .map_err(|_| format!("`{flag}` expects a whole number, got `{v}`"))
}

/// Holds per second of one timed run (after a warm-up of `size` holds).
fn measure<Q: EventQueue<Payload = u64>>(q: Q, a: &Args) -> (f64, f64) {
    let mut h = Hold::new(q, a.size, a.dist, a.seed);
    std::hint::black_box(h.run(a.size as u64));
    let start = Instant::now();
    let checksum = std::hint::black_box(h.run(a.holds));
    (a.holds as f64 / start.elapsed().as_secs_f64(), checksum)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs the benchmark and returns the table: a `#` header line, then one line per queue ending
/// with its holds per second relative to `std::collections::BinaryHeap`.
pub(crate) fn report(a: &Args) -> Result<String, String> {
    let names = [
        "std BinaryHeap",
        "HeapQueue (binary heap)",
        "BoundedQueue (bounded, Paul 2007)",
    ];
    let mut rates = vec![Vec::new(); names.len()];
    let mut sums = vec![0.0; names.len()];
    for _ in 0..a.reps {
        for (i, r) in rates.iter_mut().enumerate() {
            let (rate, sum) = match i {
                0 => measure(StdHeap::new(), a),
                1 => measure(HeapQueue::new(), a),
                _ => measure(BoundedQueue::new(), a),
            };
            r.push(rate);
            sums[i] = sum;
        }
    }
    if sums.iter().any(|&s| s != sums[0]) {
        return Err(format!("the queues disagree on the popped times: {sums:?}"));
    }
    let dist = match a.dist {
        Increment::Exponential => "exp",
        Increment::Uniform => "uniform",
    };
    let mut out = format!(
        "# hold model: size {} holds {} dist {dist}, median of {} rounds; last column: holds/s relative to std BinaryHeap\n",
        a.size, a.holds, a.reps
    );
    let base = median(rates[0].clone());
    for (name, r) in names.iter().zip(rates) {
        let m = median(r);
        out.push_str(&format!(
            "{name:<36} {m:>14.0} holds/s  {:>6.2}\n",
            m / base
        ));
    }
    Ok(out)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match parse(&args).and_then(|a| report(&a)) {
        Ok(table) => {
            print!("{table}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("hold: {e}");
            ExitCode::from(2)
        }
    }
}
