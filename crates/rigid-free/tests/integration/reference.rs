//! The propagators against `reference/propagator-reference.txt`, 40-digit data made by
//! `reference/make_reference.py` with mpmath (its own Jacobi functions and a quadrature of
//! dψ/dt, checked there against a Taylor integration of Euler's equations).
//!
//! Required (issue 3): max abs error of `P(t)` and of `ω(t)/|ω(0)|` ≤ 1e-13 up to t = 100 and
//! ≤ 2e-11 up to t = 10⁴ (times in units of ~ one rotation period; the fast-spin case has its
//! times scaled with its spin).

use glam::{DMat3, DVec3};
use rigid_free::{FreeMotion, Moments, MotionKind};

struct Case {
    name: String,
    moments: [f64; 3],
    omega: [f64; 3],
    rows: Vec<(f64, [f64; 12])>,
}

fn cases() -> Vec<Case> {
    let text = include_str!("../../reference/propagator-reference.txt");
    let mut out: Vec<Case> = Vec::new();
    for line in text.lines() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        if f[0] == "case" {
            let v: Vec<f64> = f[2..].iter().map(|s| s.parse().unwrap()).collect();
            out.push(Case {
                name: f[1].to_owned(),
                moments: [v[0], v[1], v[2]],
                omega: [v[3], v[4], v[5]],
                rows: Vec::new(),
            });
        } else {
            let v: Vec<f64> = f.iter().map(|s| s.parse().unwrap()).collect();
            let mut vals = [0.0; 12];
            vals.copy_from_slice(&v[1..13]);
            out.last_mut().unwrap().rows.push((v[0], vals));
        }
    }
    out
}

fn errors(c: &Case) -> Vec<(f64, f64, f64)> {
    let moments = Moments::new(c.moments).unwrap();
    let w0 = DVec3::from(c.omega);
    let motion = FreeMotion::new(&moments, DMat3::IDENTITY, w0).unwrap();
    c.rows
        .iter()
        .map(|(t, want)| {
            let pose = motion.pose(*t);
            let p = motion.propagator(*t);
            let w_err = (0..3)
                .map(|k| (pose.omega[k] - want[k]).abs())
                .fold(0.0, f64::max)
                / w0.length();
            // Row-major P(t) against glam's column-major storage.
            let p_err = (0..9)
                .map(|k| (p.col(k % 3)[k / 3] - want[3 + k]).abs())
                .fold(0.0, f64::max);
            (*t, w_err, p_err)
        })
        .collect()
}

#[test]
fn every_case_meets_the_required_accuracy() {
    let cases = cases();
    assert_eq!(cases.len(), 13);
    let mut report = String::new();
    let mut failures = Vec::new();
    for c in &cases {
        let errs = errors(c);
        assert_eq!(errs.len(), 6, "{}", c.name);
        for (k, (t, w_err, p_err)) in errs.iter().enumerate() {
            // Rows 0..=3 are t ≤ 100 periods, rows 4 and 5 are 10³ and 10⁴.
            let tol = if k <= 3 { 1e-13 } else { 2e-11 };
            report += &format!("{:<22} t={t:<8} ω {w_err:.1e}  P {p_err:.1e}\n", c.name);
            if !(*w_err <= tol && *p_err <= tol) {
                failures.push(format!(
                    "{} at t = {t}: ω error {w_err:e}, P error {p_err:e} (tolerance {tol:e})",
                    c.name
                ));
            }
        }
    }
    eprintln!("{report}");
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn each_case_takes_the_intended_branch() {
    for c in cases() {
        let motion = FreeMotion::new(
            &Moments::new(c.moments).unwrap(),
            DMat3::IDENTITY,
            DVec3::from(c.omega),
        )
        .unwrap();
        let want = match c.name.as_str() {
            "separatrix" => MotionKind::Separatrix,
            "symmetric" => MotionKind::Symmetric,
            _ => MotionKind::Asymmetric,
        };
        assert_eq!(motion.kind(), want, "{}", c.name);
    }
}
