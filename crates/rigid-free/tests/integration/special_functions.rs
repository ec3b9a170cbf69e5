//! The special functions against `reference/elliptic-reference.txt` (60-digit mpmath values of
//! exact binary64 inputs; a copy of the team's shared reference sheet).
//!
//! Tolerances are in ulps of the value, or of `|u|` for large arguments, where the rounding of
//! the argument itself (and of `πu/(2K)`) dominates: `|error| ≤ n·ulp(max(|f|, |u|·|f'|))`.

use rigid_free::elliptic::{Jacobi, complete_k, incomplete_f};

const ULP: f64 = f64::EPSILON;

struct Row {
    m_c: f64,
    /// `m` exactly as labelled (`1 − m_c` only for rows labelled by `mc=`).
    m: f64,
    by_m: bool,
    fields: Vec<(String, f64)>,
}

fn rows(section: &str) -> Vec<Row> {
    let text = include_str!("../../reference/elliptic-reference.txt");
    let mut out = Vec::new();
    let mut current = "";
    for line in text.lines() {
        if let Some(h) = line.strip_prefix("# ") {
            current = if h.starts_with("Jacobi") {
                "jacobi"
            } else if h.starts_with("K(m)") {
                "k"
            } else if h.starts_with("F(phi") {
                "f"
            } else {
                current
            };
            continue;
        }
        if line.trim().is_empty() || current != section {
            continue;
        }
        let mut it = line.split_whitespace();
        let label = it.next().unwrap();
        let (m_c, m) = if let Some(v) = label.strip_prefix("mc=") {
            let m_c = v.parse::<f64>().unwrap();
            (m_c, 1.0 - m_c)
        } else {
            let m = label.strip_prefix("m=").unwrap().parse::<f64>().unwrap();
            (1.0 - m, m)
        };
        let by_m = label.starts_with("m=");
        let fields = it
            .map(|kv| {
                let (k, v) = kv.split_once('=').unwrap();
                (k.to_owned(), v.parse::<f64>().unwrap())
            })
            .collect();
        out.push(Row {
            m_c,
            m,
            by_m,
            fields,
        });
    }
    out
}

fn get(r: &Row, k: &str) -> f64 {
    r.fields.iter().find(|(n, _)| n == k).unwrap().1
}

#[test]
fn jacobi_sn_cn_dn_to_a_few_ulp() {
    let rows = rows("jacobi");
    assert_eq!(rows.len(), 35);
    let mut worst = 0.0_f64;
    for r in &rows {
        let u = get(r, "u");
        let j = Jacobi::new(r.m_c).unwrap();
        let f = j.sn_cn_dn(u);
        // Argument rounding: sn, cn, dn have slopes ≤ 1, so ulp(u) of argument error is allowed.
        let scale = u.abs().max(1.0);
        for (got, name) in [(f.sn, "sn"), (f.cn, "cn"), (f.dn, "dn")] {
            let want = get(r, name);
            let err = (got - want).abs() / (ULP * scale);
            worst = worst.max(err);
            assert!(
                err <= 4.0,
                "m_c={} u={u} {name}: {got} vs {want} ({err:.1} ulp·|u|)",
                r.m_c
            );
        }
    }
    eprintln!("worst sn/cn/dn error: {worst:.2} ulp·max(1,|u|)");
}

#[test]
fn complete_k_to_a_few_ulp() {
    for r in rows("k") {
        let want = get(&r, "K");
        let got = complete_k(r.m_c).unwrap();
        let from_agm = Jacobi::new(r.m_c).unwrap().quarter_period();
        if want.is_infinite() {
            continue;
        }
        for g in [got, from_agm] {
            assert!(
                (g - want).abs() <= 3.0 * ULP * want,
                "m_c={}: {g} vs {want}",
                r.m_c
            );
        }
        // K' = K(m) with the roles swapped, where the table has it.
        let kp = get(&r, "K'");
        // Rows labelled by a tiny m_c have m = 1 − m_c rounded, and K(m) then inherits that
        // rounding amplified by 1/m_c: only rows labelled by m give K' exactly.
        if kp.is_finite() && r.by_m {
            let got = complete_k(r.m).unwrap();
            assert!(
                (got - kp).abs() <= 3.0 * ULP * kp,
                "K'({}) = {got} vs {kp}",
                r.m_c
            );
        }
    }
}

#[test]
fn incomplete_f_to_a_few_ulp() {
    for r in rows("f") {
        let phi = get(&r, "phi");
        let want = get(&r, "F");
        let got = incomplete_f(phi, r.m_c).unwrap();
        assert!(
            (got - want).abs() <= 4.0 * ULP * want.abs(),
            "m_c={} phi={phi}: {got} vs {want}",
            r.m_c
        );
    }
}
