//! Gay–Berne energy, force and torques against 40-digit values computed independently
//! (`reference/gay_berne.py`: the textbook formula in mpmath, with force and torques by
//! numerical differentiation, not by our analytic derivatives).

use glam::DVec3;
use potential::{GayBerne, PairGeometry, PairPotential};

const TABLE: &str = include_str!("../../reference/gay_berne.txt");

#[test]
fn energy_force_and_torques_match_the_mpmath_reference() {
    let mut cases = 0;
    for line in TABLE.lines().filter(|l| !l.trim().is_empty()) {
        let mut f = line.split_whitespace();
        let name = f.next().unwrap();
        let v: Vec<f64> = f.map(|x| x.parse().unwrap()).collect();
        assert_eq!(v.len(), 4 + 9 + 10, "{name}");
        let gb = GayBerne::new(1.0, 1.0, v[0], v[1], v[2], v[3]).unwrap();
        let vec3 = |i: usize| DVec3::new(v[i], v[i + 1], v[i + 2]);
        let g = PairGeometry::new(vec3(4), vec3(7), vec3(10));
        let (u, force, ti, tj) = (v[13], vec3(14), vec3(17), vec3(20));
        let e = gb.evaluate(&g).unwrap();
        // The inputs are binary64 numbers; what remains is our round-off, amplified near the
        // repulsive wall by |dU/dr| r (the condition number of U).
        let cond = force.length() * g.r_ij.length() + u.abs();
        assert!(
            (e.energy - u).abs() <= 1e-14 * cond,
            "{name}: U {} vs {u}",
            e.energy
        );
        assert_eq!(gb.energy(&g), e.energy, "{name}");
        let vs = force.length() + ti.length() + tj.length() + u.abs();
        assert!(
            (e.force - force).length() <= 1e-13 * vs,
            "{name}: F {} vs {force}",
            e.force
        );
        assert!(
            (e.torque_i - ti).length() <= 1e-13 * vs,
            "{name}: τ_ij {} vs {ti}",
            e.torque_i
        );
        assert!(
            (e.torque_j - tj).length() <= 1e-13 * vs,
            "{name}: τ_ji {} vs {tj}",
            e.torque_j
        );
        cases += 1;
    }
    assert_eq!(cases, 32);
}
