//! Root searches over the adversarial corpus of `root_search::corpus`.
//!
//! - `corpus/*`: one pass over 100 corpus cases per method, at the cheapest settings that miss
//!   nothing in the validation (`docs/VALIDATION.md`), the paper's step, and the baseline of
//!   evaluating the indicators alone at as many points as the adaptive search used (so the
//!   difference is the search's own overhead).
//! - `resume/*`: the same adaptive search run whole and cut into 4 fs windows (virtual events).
//! - `sphere_window/*`: the cancellation-free bracket against the textbook quadratic formula.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use root_search::corpus::{Case, cases};
use root_search::{Adaptive, Grid, Indicator, Method, Outcome, Tolerances, sphere_window};

fn tol(step: f64) -> Tolerances {
    Tolerances {
        touch: 1e-12,
        ..Tolerances::relative_to(step)
    }
}

fn pass<M: Method>(m: &M, corpus: &mut [Case]) -> u32 {
    let mut evals = 0;
    for c in corpus.iter_mut() {
        let r = m
            .start(&mut c.shape, c.t0, c.end, c.seek, f64::INFINITY)
            .expect("corpus cases are valid");
        evals += r.evals;
    }
    evals
}

fn chained<M: Method>(m: &M, corpus: &mut [Case], window: f64) -> u32 {
    let mut evals = 0;
    for c in corpus.iter_mut() {
        let mut r = m
            .start(&mut c.shape, c.t0, c.end, c.seek, window)
            .expect("valid");
        evals += r.evals;
        while let Outcome::Suspended(s) = r.outcome {
            r = m.resume(&mut c.shape, s, window).expect("valid");
            evals += r.evals;
        }
    }
    evals
}

fn corpus(c: &mut Criterion) {
    let mut cases = cases(2008, 10);
    // The cheapest settings that miss nothing on the 600-case corpus of the validation.
    let grid = Grid::new(0.016, 1.0)
        .unwrap()
        .with_tolerances(tol(0.016))
        .unwrap();
    let fast = Adaptive::new(0.03)
        .unwrap()
        .with_tolerances(tol(0.03))
        .unwrap();
    let paper = Adaptive::new(0.005)
        .unwrap()
        .with_tolerances(tol(0.005))
        .unwrap();
    // Evaluations each case costs the adaptive search, for the bare-evaluation baseline.
    let counts: Vec<u32> = cases
        .iter_mut()
        .map(|k| {
            fast.start(&mut k.shape, k.t0, k.end, k.seek, f64::INFINITY)
                .unwrap()
                .evals
        })
        .collect();
    eprintln!(
        "evaluations per pass: grid {}, adaptive 0.03 {}, adaptive 0.005 {}",
        pass(&grid, &mut cases),
        pass(&fast, &mut cases),
        pass(&paper, &mut cases)
    );
    let mut g = c.benchmark_group("corpus");
    g.sample_size(20).measurement_time(Duration::from_secs(4));
    g.bench_function("evaluations only (adaptive 0.03 count)", |b| {
        b.iter(|| {
            // Each time depends on the previous value, as a search's next sample does, so the
            // evaluations cannot overlap in the processor any more than a search's can.
            let mut acc = 0.0;
            for (k, &n) in cases.iter_mut().zip(&counts) {
                let h = (k.end - k.t0) / f64::from(n);
                let mut t = k.t0;
                for _ in 0..n {
                    let (f, _) = k.shape.eval(t);
                    t += h + 0.0 * f;
                    acc += f;
                }
            }
            black_box(acc)
        })
    });
    g.bench_function("grid dt=0.016 threshold=1", |b| {
        b.iter(|| black_box(pass(&grid, &mut cases)))
    });
    g.bench_function("adaptive dt=0.03", |b| {
        b.iter(|| black_box(pass(&fast, &mut cases)))
    });
    g.bench_function("adaptive dt=0.005", |b| {
        b.iter(|| black_box(pass(&paper, &mut cases)))
    });
    g.finish();

    let mut g = c.benchmark_group("resume");
    g.sample_size(20).measurement_time(Duration::from_secs(4));
    g.bench_function("adaptive dt=0.005 whole", |b| {
        b.iter(|| black_box(pass(&paper, &mut cases)))
    });
    g.bench_function("adaptive dt=0.005 in 0.005 windows", |b| {
        b.iter(|| black_box(chained(&paper, &mut cases, 0.005)))
    });
    g.finish();
}

/// The textbook quadratic formula, the baseline of [`sphere_window`].
fn textbook(r: [f64; 3], v: [f64; 3], radius: f64) -> Option<(f64, f64)> {
    let a = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    let b = r[0] * v[0] + r[1] * v[1] + r[2] * v[2];
    let c = r[0] * r[0] + r[1] * r[1] + r[2] * r[2] - radius * radius;
    let disc = b * b - a * c;
    if a == 0.0 || disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    Some(((-b - s) / a, (-b + s) / a))
}

fn brackets(c: &mut Criterion) {
    // 1024 pairs on random-looking courses (a fixed low-discrepancy pattern, no RNG needed).
    let pairs: Vec<([f64; 3], [f64; 3])> = (0..1024)
        .map(|i| {
            let x = f64::from(i);
            (
                [
                    3.0 * (x * 0.618).fract() - 1.5,
                    3.0 * (x * 0.414).fract() - 1.5,
                    3.0 * (x * 0.732).fract() - 1.5,
                ],
                [
                    (x * 0.236).fract() - 0.5,
                    (x * 0.171).fract() - 0.5,
                    (x * 0.302).fract() - 0.5,
                ],
            )
        })
        .collect();
    let mut g = c.benchmark_group("sphere_window");
    g.sample_size(30).measurement_time(Duration::from_secs(3));
    g.bench_function("textbook (1024 pairs)", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (r, v) in &pairs {
                if let Some((t0, t1)) = textbook(*r, *v, 1.2) {
                    acc += t0 + t1;
                }
            }
            black_box(acc)
        })
    });
    g.bench_function("sphere_window (1024 pairs)", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (r, v) in &pairs {
                if let Ok(Some(w)) = sphere_window(*r, *v, 1.2) {
                    acc += w.enter + w.exit;
                }
            }
            black_box(acc)
        })
    });
    g.finish();
}

criterion_group!(benches, corpus, brackets);
criterion_main!(benches);
