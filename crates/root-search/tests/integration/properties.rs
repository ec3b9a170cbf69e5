//! Property tests: random smooth functions built from known roots, and resumed searches.

use proptest::prelude::*;
use root_search::corpus::Shape;
use root_search::{Adaptive, Crossing, Direction, Grid, Method, Outcome, Report, Tolerances};

/// Roots at least `gap` apart in `(0.02, 0.98)`, each with a tanh width in `[0.02, 0.05]`.
fn roots(gap: f64) -> impl Strategy<Value = Vec<(f64, f64)>> {
    prop::collection::vec((0.02f64..0.98, 0.02f64..0.05), 0..6).prop_filter_map(
        "roots too close",
        move |mut v| {
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            v.windows(2).all(|w| w[1].0 - w[0].0 >= gap).then_some(v)
        },
    )
}

fn seek() -> impl Strategy<Value = Crossing> {
    prop_oneof![
        Just(Crossing::Rising),
        Just(Crossing::Falling),
        Just(Crossing::Either)
    ]
}

/// The earliest accepted root of `s Π tanh((t − rᵢ)/wᵢ)` after 0, from the list.
fn earliest(s: f64, roots: &[(f64, f64)], seek: Crossing) -> Option<(f64, Direction)> {
    // The sign at t = 0 is s times (−1)^(number of roots), since every factor is negative there.
    let mut positive = (s > 0.0) == roots.len().is_multiple_of(2);
    for &(r, _) in roots {
        let dir = if positive {
            Direction::Falling
        } else {
            Direction::Rising
        };
        if seek.accepts(dir) {
            return Some((r, dir));
        }
        positive = !positive;
    }
    None
}

fn check(report: Report, expect: Option<(f64, Direction)>) -> Result<(), TestCaseError> {
    match (report.outcome, expect) {
        (Outcome::Root(r), Some((t, d))) => {
            prop_assert!((r.t - t).abs() < 1e-9, "root {} expected {t}", r.t);
            prop_assert_eq!(r.direction, d);
        }
        (Outcome::NoRoot, None) => {}
        (got, want) => prop_assert!(false, "got {got:?}, expected {want:?}"),
    }
    Ok(())
}

fn tol(step: f64) -> Tolerances {
    Tolerances {
        touch: 1e-12,
        ..Tolerances::relative_to(step)
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// Roots as close as a fifth of the maximum step: the interpolant has to see the dip.
    #[test]
    fn adaptive_returns_the_earliest_root_or_correctly_none(
        roots in roots(0.004), s in prop_oneof![Just(1.0), Just(-1.0)], seek in seek(),
    ) {
        let a = Adaptive::new(0.02).unwrap().with_tolerances(tol(0.02)).unwrap();
        let mut f = Shape::Tanh { s, roots: roots.clone() };
        let report = a.start(&mut f, 0.0, 1.0, seek, f64::INFINITY).unwrap();
        check(report, earliest(s, &roots, seek))?;
    }

    #[test]
    fn grid_returns_the_earliest_root_or_correctly_none(
        roots in roots(0.004), s in prop_oneof![Just(1.0), Just(-1.0)], seek in seek(),
    ) {
        let g = Grid::new(0.005, 1.0).unwrap().with_tolerances(tol(0.005)).unwrap();
        let mut f = Shape::Tanh { s, roots: roots.clone() };
        let report = g.start(&mut f, 0.0, 1.0, seek, f64::INFINITY).unwrap();
        check(report, earliest(s, &roots, seek))?;
    }

    /// Gaussian dips from 1e-9 to 1e-2 below zero, or as far above it, anywhere between the
    /// samples: found exactly when they cross, by both methods at settings that resolve them.
    #[test]
    fn grazing_dips_are_found_exactly_when_they_cross(
        c in 0.1f64..0.9, w in 0.01f64..0.05, log_depth in -9.0f64..-2.0,
        below in any::<bool>(), s in prop_oneof![Just(1.0), Just(-1.0)],
    ) {
        let d = if below { 10f64.powf(log_depth) } else { -10f64.powf(log_depth) };
        let expect = below.then(|| {
            let dir = if s > 0.0 { Direction::Falling } else { Direction::Rising };
            (c - w * d.ln_1p().sqrt(), dir)
        });
        let a = Adaptive::new(0.02).unwrap().with_tolerances(tol(0.02)).unwrap();
        // The grid's contract (000 §III.A): it examines a dip only if |f| at a grid point next
        // to it is below the threshold, and a grid point lies within Δt/2 of the bottom, where
        // f ≤ f_min + f''·(Δt/2)²/2 with f'' = 2(1 + d)/w². A threshold of 0.1 misses narrow
        // dips (w = 0.01: f = 0.139 at the grid points), so it is set from that bound.
        let dt = 0.008;
        let threshold = 1.25 * (1.0 + d.abs()) * (dt / w).powi(2) / 4.0;
        let g = Grid::new(dt, threshold).unwrap().with_tolerances(tol(dt)).unwrap();
        let mut f = Shape::Dip { s, c, w, d };
        check(a.start(&mut f, 0.0, 1.0, Crossing::Either, f64::INFINITY).unwrap(), expect)?;
        check(g.start(&mut f, 0.0, 1.0, Crossing::Either, f64::INFINITY).unwrap(), expect)?;
    }

    /// A search cut into windows and resumed gives the same root, bit for bit, with the same
    /// total number of evaluations.
    #[test]
    fn resuming_a_truncated_search_changes_nothing(
        roots in roots(0.004), s in prop_oneof![Just(1.0), Just(-1.0)], seek in seek(),
        window in 0.001f64..0.2, grid in any::<bool>(),
    ) {
        let mut f = Shape::Tanh { s, roots };
        let a = Adaptive::new(0.02).unwrap().with_tolerances(tol(0.02)).unwrap();
        let g = Grid::new(0.005, 1.0).unwrap().with_tolerances(tol(0.005)).unwrap();
        let (whole, parts, evals) = if grid {
            chain(&g, &mut f, seek, window)
        } else {
            chain(&a, &mut f, seek, window)
        };
        prop_assert_eq!(whole.evals, evals);
        match (whole.outcome, parts) {
            (Outcome::Root(x), Outcome::Root(y)) => {
                prop_assert_eq!(x.t.to_bits(), y.t.to_bits());
                prop_assert_eq!(x.direction, y.direction);
            }
            (Outcome::NoRoot, Outcome::NoRoot) => {}
            (x, y) => prop_assert!(false, "{x:?} vs {y:?}"),
        }
    }
}

fn chain<M: Method>(m: &M, f: &mut Shape, seek: Crossing, window: f64) -> (Report, Outcome, u32) {
    let whole = m.start(f, 0.0, 1.0, seek, f64::INFINITY).unwrap();
    let mut part = m.start(f, 0.0, 1.0, seek, window).unwrap();
    let mut evals = part.evals;
    let mut last = 0.0;
    while let Outcome::Suspended(state) = part.outcome {
        // Every call makes progress and stops where its window ends or earlier.
        assert!(state.time() > last);
        last = state.time();
        part = m.resume(f, state, window).unwrap();
        evals += part.evals;
    }
    (whole, part.outcome, evals)
}
