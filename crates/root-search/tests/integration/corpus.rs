//! The adversarial corpus, run by both methods at settings that must miss nothing.
//!
//! The full sweep of settings (error against evaluations) is `cargo xtask validate --only
//! root-search`; this is the fast subset that `cargo test` runs.

use root_search::corpus::{Case, Family, Verdict, cases};
use root_search::{Adaptive, Grid, Method, Tolerances};

fn tol(step: f64) -> Tolerances {
    Tolerances {
        touch: 1e-12,
        ..Tolerances::relative_to(step)
    }
}

fn failures<M: Method>(m: &M, corpus: &mut [Case]) -> Vec<String> {
    let mut out = Vec::new();
    for c in corpus.iter_mut() {
        let r = m
            .start(&mut c.shape, c.t0, c.end, c.seek, f64::INFINITY)
            .unwrap_or_else(|e| panic!("{}: {e}", c.name));
        let v = c.judge(r.root());
        if v != Verdict::Right {
            out.push(format!(
                "{}: {v:?}: expected {:?}, got {:?}",
                c.name,
                c.expected,
                r.root()
            ));
        }
    }
    out
}

#[test]
fn adaptive_at_the_papers_step_misses_nothing() {
    let mut corpus = cases(41, 5);
    let a = Adaptive::new(0.005)
        .unwrap()
        .with_tolerances(tol(0.005))
        .unwrap();
    let f = failures(&a, &mut corpus);
    assert!(f.is_empty(), "{f:#?}");
}

#[test]
fn adaptive_with_a_long_step_still_misses_nothing() {
    let mut corpus = cases(43, 5);
    let a = Adaptive::new(0.02)
        .unwrap()
        .with_tolerances(tol(0.02))
        .unwrap();
    let f = failures(&a, &mut corpus);
    assert!(f.is_empty(), "{f:#?}");
}

#[test]
fn grid_with_grazing_detection_misses_nothing_at_a_fine_step() {
    let mut corpus = cases(47, 5);
    let g = Grid::new(0.004, 0.1)
        .unwrap()
        .with_tolerances(tol(0.004))
        .unwrap();
    let f = failures(&g, &mut corpus);
    assert!(f.is_empty(), "{f:#?}");
}

#[test]
fn the_corpus_defeats_a_grid_without_grazing_detection() {
    // If this passed, the corpus would not be adversarial and the tests above would prove little.
    let mut corpus: Vec<Case> = cases(53, 8)
        .into_iter()
        .filter(|c| c.family == Family::Grazing)
        .collect();
    let g = Grid::new(0.004, 0.0)
        .unwrap()
        .with_tolerances(tol(0.004))
        .unwrap();
    let f = failures(&g, &mut corpus);
    assert!(
        f.len() >= corpus.len() / 2,
        "only {} of {} missed",
        f.len(),
        corpus.len()
    );
}

#[test]
fn the_adaptive_search_is_cheaper_than_a_grid_that_also_misses_nothing() {
    let mut corpus = cases(59, 4);
    let evals = |m: &dyn Fn(&mut Case) -> u32, corpus: &mut [Case]| -> u32 {
        corpus.iter_mut().map(m).sum()
    };
    let a = Adaptive::new(0.02)
        .unwrap()
        .with_tolerances(tol(0.02))
        .unwrap();
    let g = Grid::new(0.008, 0.1)
        .unwrap()
        .with_tolerances(tol(0.008))
        .unwrap();
    let ea = evals(
        &|c| {
            a.start(&mut c.shape, c.t0, c.end, c.seek, f64::INFINITY)
                .unwrap()
                .evals
        },
        &mut corpus,
    );
    let eg = evals(
        &|c| {
            g.start(&mut c.shape, c.t0, c.end, c.seek, f64::INFINITY)
                .unwrap()
                .evals
        },
        &mut corpus,
    );
    assert!(failures(&a, &mut corpus).is_empty());
    assert!(2 * ea < eg, "adaptive {ea} evaluations, grid {eg}");
}
