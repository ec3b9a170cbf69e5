//! The situations a simulator puts a search in: a start on the root just executed, brackets
//! from the centre-of-mass motion, virtual events, and bad input.

use root_search::{
    Adaptive, Crossing, Direction, Grid, Method, Outcome, SearchError, Tolerances, sphere_window,
};

fn both() -> (Adaptive, Grid) {
    (Adaptive::new(0.01).unwrap(), Grid::new(0.01, 0.1).unwrap())
}

/// `sin ω(t − t0) + δ`: zero at `t0` up to `δ`, rising there.
fn sine(t0: f64, delta: f64) -> impl FnMut(f64) -> (f64, f64) {
    move |t: f64| {
        let x = 20.0 * (t - t0);
        (x.sin() + delta, 20.0 * x.cos())
    }
}

#[test]
fn a_start_on_the_event_just_executed_moves_off_it() {
    let (a, g) = both();
    let t0 = 3.25;
    let half = std::f64::consts::PI / 20.0;
    for delta in [0.0, 1e-16, -1e-16, 1e-13, -1e-13] {
        // f rises through zero at t0 (the event just executed): the next falling root is half a
        // period later, whatever side of zero round-off left f(t0) on.
        let mut f = sine(t0, delta);
        let r = a
            .start(&mut f, t0, t0 + 1.0, Crossing::Falling, f64::INFINITY)
            .unwrap();
        assert!(
            (r.root().unwrap() - (t0 + half)).abs() < 1e-9,
            "adaptive, δ = {delta}"
        );
        let r = g
            .start(&mut f, t0, t0 + 1.0, Crossing::Falling, f64::INFINITY)
            .unwrap();
        assert!(
            (r.root().unwrap() - (t0 + half)).abs() < 1e-9,
            "grid, δ = {delta}"
        );
        // After a reflection the slope is reversed: the next rising root is half a period on.
        let mut f = move |t: f64| {
            let (v, d) = sine(t0, -delta)(t);
            (-v, -d)
        };
        let r = a
            .start(&mut f, t0, t0 + 1.0, Crossing::Rising, f64::INFINITY)
            .unwrap();
        assert!(
            (r.root().unwrap() - (t0 + half)).abs() < 1e-9,
            "adaptive, δ = {delta}"
        );
        let r = g
            .start(&mut f, t0, t0 + 1.0, Crossing::Rising, f64::INFINITY)
            .unwrap();
        assert!(
            (r.root().unwrap() - (t0 + half)).abs() < 1e-9,
            "grid, δ = {delta}"
        );
    }
}

#[test]
fn an_exact_zero_start_is_not_a_root_even_when_either_direction_is_accepted() {
    let (a, g) = both();
    let mut f = sine(0.0, 0.0);
    let half = std::f64::consts::PI / 20.0;
    for r in [
        a.start(&mut f, 0.0, 1.0, Crossing::Either, f64::INFINITY)
            .unwrap(),
        g.start(&mut f, 0.0, 1.0, Crossing::Either, f64::INFINITY)
            .unwrap(),
    ] {
        let Outcome::Root(root) = r.outcome else {
            panic!("{r:?}")
        };
        assert!((root.t - half).abs() < 1e-9);
        assert_eq!(root.direction, Direction::Falling);
    }
}

#[test]
fn a_pair_through_its_interaction_sphere_with_virtual_events() {
    // Relative motion past a wall U = r⁻⁶ with terrace U_k = 1 (reached at r = 1), searched
    // only while the centres are within 2 of each other, 0.05 at a time.
    let r0 = [3.0, 0.4, 0.0];
    let v = [-1.5, 0.0, 0.0];
    let mut f = |t: f64| {
        let x = r0[0] + v[0] * t;
        let r2 = x * x + r0[1] * r0[1];
        (r2.powi(-3) - 1.0, -3.0 * r2.powi(-4) * 2.0 * x * v[0])
    };
    let w = sphere_window(r0, v, 2.0).unwrap().unwrap();
    let (start, end) = w.after(0.0).unwrap();
    let a = Adaptive::new(0.004).unwrap();
    let mut report = a.start(&mut f, start, end, Crossing::Rising, 0.05).unwrap();
    let mut virtual_events = 0;
    while let Outcome::Suspended(state) = report.outcome {
        assert!(state.time() <= end && state.end() == end);
        virtual_events += 1;
        report = a.resume(&mut f, state, 0.05).unwrap();
    }
    let expect = (3.0 - (1.0f64 - 0.16).sqrt()) / 1.5;
    assert!((report.root().unwrap() - expect).abs() < 1e-10);
    assert!(virtual_events >= 10, "{virtual_events}");
}

#[test]
fn rebasing_a_state_keeps_the_search_on_course() {
    let a = Adaptive::new(0.01).unwrap();
    let mut f = |t: f64| (t - 1000.75, 1.0);
    let r = a
        .start(&mut f, 1000.0, 1001.0, Crossing::Rising, 0.1)
        .unwrap();
    let Outcome::Suspended(state) = r.outcome else {
        panic!()
    };
    let moved = state.rebased(1000.0).unwrap();
    assert!((moved.time() - (state.time() - 1000.0)).abs() < 1e-12);
    let mut g = |t: f64| (t - 0.75, 1.0);
    let mut report = a.resume(&mut g, moved, f64::INFINITY).unwrap();
    if let Outcome::Suspended(s) = report.outcome {
        report = a.resume(&mut g, s, f64::INFINITY).unwrap();
    }
    assert!((report.root().unwrap() - 0.75).abs() < 1e-12);
    assert!(state.rebased(f64::NAN).is_err());
}

fn err<T: std::fmt::Debug>(r: Result<T, SearchError>) -> String {
    r.unwrap_err().to_string()
}

#[test]
fn bad_input_gets_one_clear_error_each() {
    let a = Adaptive::new(0.01).unwrap();
    let mut f = |t: f64| (t - 0.5, 1.0);
    assert!(err(a.start(&mut f, f64::NAN, 1.0, Crossing::Either, 1.0)).contains("start"));
    assert!(err(a.start(&mut f, 0.0, f64::NAN, Crossing::Either, 1.0)).contains("end"));
    assert!(err(a.start(&mut f, 1.0, 0.0, Crossing::Either, 1.0)).contains("before"));
    assert!(err(a.start(&mut f, 0.0, 1.0, Crossing::Either, 0.0)).contains("window"));
    assert!(err(a.start(&mut f, 0.0, 1.0, Crossing::Either, f64::NAN)).contains("window"));
    assert!(
        err(a.start(&mut f, 0.0, f64::INFINITY, Crossing::Either, f64::INFINITY))
            .contains("infinite")
    );
    let mut nan = |t: f64| if t > 0.3 { (f64::NAN, 1.0) } else { (1.0, 0.0) };
    assert!(err(a.start(&mut nan, 0.0, 1.0, Crossing::Either, 1.0)).contains("NaN"));
    let mut inf = |_t: f64| (1.0, f64::INFINITY);
    assert!(matches!(
        a.start(&mut inf, 0.0, 1.0, Crossing::Either, 1.0),
        Err(SearchError::NonFiniteIndicator { .. })
    ));
    // A step that cannot move a large time.
    let tiny = Adaptive::new(1e-9).unwrap();
    assert!(matches!(
        tiny.start(&mut f, 1e10, 1e10 + 1.0, Crossing::Either, 1.0),
        Err(SearchError::StepBelowResolution { .. })
    ));
    assert!(Adaptive::new(0.0).is_err());
    assert!(Adaptive::new(f64::INFINITY).is_err());
    assert!(a.with_overshoot(-1.0).is_err());
    assert!(Grid::new(0.1, -1.0).is_err());
    assert!(Grid::new(f64::NAN, 0.1).is_err());
    let bad = Tolerances {
        root: 0.0,
        ..Tolerances::relative_to(1.0)
    };
    assert!(err(a.with_tolerances(bad)).contains("root tolerance"));
    // An empty bracket is no error: there is simply no root in it.
    let r = a.start(&mut f, 0.25, 0.25, Crossing::Either, 1.0).unwrap();
    assert_eq!((r.outcome, r.evals), (Outcome::NoRoot, 0));
}

#[test]
fn stiff_wall_far_beyond_the_terraces_is_found_to_full_precision() {
    // A Lennard-Jones wall met at 10 σ/τ: U rises by ~1e4 ε per τ near U_k = 200.
    let uk = 200.0;
    let mut f = |t: f64| {
        let x = 2.5 - 10.0 * t;
        let x6 = x.powi(-6);
        (
            4.0 * (x6 * x6 - x6) - uk,
            4.0 * (-12.0 * x6 * x6 + 6.0 * x6) / x * -10.0,
        )
    };
    let y = 0.5 * (1.0 + (1.0f64 + uk).sqrt());
    let expect = (2.5 - y.powf(-1.0 / 6.0)) / 10.0;
    let (a, g) = both();
    for r in [
        a.start(&mut f, 0.0, 0.24, Crossing::Rising, f64::INFINITY)
            .unwrap(),
        g.start(&mut f, 0.0, 0.24, Crossing::Rising, f64::INFINITY)
            .unwrap(),
    ] {
        assert!((r.root().unwrap() - expect).abs() < 1e-12, "{r:?}");
    }
}

#[test]
fn a_touch_margin_makes_a_start_on_zero_safe_for_either_direction() {
    let touchy = |m: f64| Tolerances {
        touch: 1e-12,
        ..Tolerances::relative_to(m)
    };
    let a = Adaptive::new(0.01)
        .unwrap()
        .with_tolerances(touchy(0.01))
        .unwrap();
    let g = Grid::new(0.01, 0.1)
        .unwrap()
        .with_tolerances(touchy(0.01))
        .unwrap();
    let half = std::f64::consts::PI / 20.0;
    // Reflected upwards at t0 = 0, with f(0) left a hair below zero: without the margin an
    // Either search would return the round-off crossing at t ≈ 5e-18.
    let mut f = sine(0.0, -1e-16);
    for r in [
        a.start(&mut f, 0.0, 1.0, Crossing::Either, f64::INFINITY)
            .unwrap(),
        g.start(&mut f, 0.0, 1.0, Crossing::Either, f64::INFINITY)
            .unwrap(),
    ] {
        assert!((r.root().unwrap() - half).abs() < 1e-9, "{r:?}");
    }
    let plain = Adaptive::new(0.01).unwrap();
    let r = plain
        .start(&mut f, 0.0, 1.0, Crossing::Either, f64::INFINITY)
        .unwrap();
    assert!(
        r.root().unwrap() < 1e-15,
        "without a margin the round-off crossing is found"
    );
    // A function that is merely small at the start, and rises to its root much later, is not
    // mistaken for one that left zero and came back.
    let mut slow = |t: f64| (1e-13 * (t - 0.5), 1e-13);
    for r in [
        a.start(&mut slow, 0.0, 1.0, Crossing::Either, f64::INFINITY)
            .unwrap(),
        g.start(&mut slow, 0.0, 1.0, Crossing::Either, f64::INFINITY)
            .unwrap(),
    ] {
        let Outcome::Root(root) = r.outcome else {
            panic!("{r:?}")
        };
        assert!((root.t - 0.5).abs() < 1e-9 && root.direction == Direction::Rising);
    }
}

#[test]
fn a_jittered_step_finds_the_same_roots() {
    // 003 §V.A: a small random change of the maximum step per call keeps virtual events apart.
    let base = Adaptive::new(0.005).unwrap();
    let mut f = |t: f64| {
        let x = (t - 0.4137) / 0.02;
        let g = 1.000001 * (-x * x).exp();
        (1.0 - g, 2.0 * x / 0.02 * g)
    };
    let expect = 0.4137 - 0.02 * 1.000001f64.ln().sqrt();
    let mut state = None;
    let mut k = 0u32;
    let root = loop {
        k += 1;
        let jitter = 1.0 + 0.01 * ((f64::from(k) * 0.618_033_988_7).fract() - 0.5);
        let m = base.with_max_step(0.005 * jitter).unwrap();
        let r = match state {
            None => m.start(&mut f, 0.0, 1.0, Crossing::Falling, 0.005).unwrap(),
            Some(s) => m.resume(&mut f, s, 0.005).unwrap(),
        };
        match r.outcome {
            Outcome::Suspended(s) => state = Some(s),
            Outcome::Root(root) => break root.t,
            Outcome::NoRoot => panic!("missed the dip"),
        }
    };
    assert!((root - expect).abs() < 1e-10);
    assert!(k > 50);
}
