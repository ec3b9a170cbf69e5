//! Rigid and semi-flexible molecules in one scene: the shipped mixture shortened (energy, degrees
//! of freedom, rigid molecules staying rigid in the trajectory), and a rigid dumbbell against the
//! same dumbbell held by its one bond under RATTLE: the same physics, so the same events.

use crate::support;
use crate::support::run_shipped as run;

#[test]
fn rigid_and_flexible_molecules_share_a_scene() {
    let d = support::scratch("mixed-molecules");
    let s = run(
        "mixed-molecules.toml",
        &[
            "run.equilibration_time=1.0",
            "run.time=3.0",
            "output.trajectory.interval=0.5",
        ],
        Some(&d),
    );
    assert_eq!(s.model, "semi-flexible");
    support::assert_conserved(&s, "mixed molecules", 1e-10);
    assert_eq!(s.anomalies, 0);
    assert!(s.reflections > 0 && s.terrace_crossings > 0, "{s:?}");
    // Centres 3 each less the momentum, the chains' 3·4 − 3 − 3 internal ones, the bent
    // triatomics' three rotations.
    assert_eq!(
        s.degrees_of_freedom,
        3.0 * 128.0 - 3.0 + 64.0 * 6.0 + 64.0 * 3.0
    );
    assert!(s.rattle.expect("RATTLE statistics").failures == 0);
    // Every frame: each triatomic's three sites keep the distances of the given ones.
    let xyz = std::fs::read_to_string(d.join("trajectory.xyz")).unwrap();
    let arms = [0.5, 0.5, 2.0 * 0.5 * (105f64.to_radians() / 2.0).sin()];
    let (mut frames, mut worst) = (0, 0.0f64);
    let mut lines = xyz.lines();
    while let Some(n) = lines.next() {
        let n: usize = n.trim().parse().unwrap();
        let comment = lines.next().unwrap();
        let side: f64 = comment
            .split("Lattice=\"")
            .nth(1)
            .and_then(|l| l.split_whitespace().next())
            .unwrap()
            .parse()
            .unwrap();
        // W atoms by molecule (column 15 of the extended XYZ), in site order.
        let mut bent: std::collections::BTreeMap<u64, Vec<[f64; 3]>> = Default::default();
        for _ in 0..n {
            let f: Vec<&str> = lines.next().unwrap().split_whitespace().collect();
            if f[0] == "W" {
                let p = [f[1], f[2], f[3]].map(|x| x.parse::<f64>().unwrap());
                bent.entry(f[15].parse().unwrap()).or_default().push(p);
            }
        }
        assert_eq!(bent.len(), 64);
        let dist = |a: [f64; 3], b: [f64; 3]| {
            (0..3)
                .map(|k| {
                    let x = a[k] - b[k];
                    (x - side * (x / side).round()).powi(2)
                })
                .sum::<f64>()
                .sqrt()
        };
        for s in bent.values() {
            for (k, (a, b)) in [(0, 1), (0, 2), (1, 2)].into_iter().enumerate() {
                worst = worst.max((dist(s[a], s[b]) - arms[k]).abs());
            }
        }
        frames += 1;
    }
    assert_eq!(frames, 7);
    // The given sites are at 5 digits; the file has 10 decimals.
    assert!(
        worst < 2e-5,
        "a triatomic's site distance is off by {worst}"
    );
    let _ = std::fs::remove_dir_all(d);
}

/// Chains of three atoms among dumbbells, the dumbbells with `bonds` given or not.
fn chains_and_dumbbells(bonds: &str) -> String {
    format!(
        r#"version = 1
seed = 5
[box]
density = 0.1
[[species]]
name = "chain"
count = 32
sites = [
  {{ kind = "A", mass = 1.0, position = [0.0, 0.0, 0.0] }},
  {{ kind = "A", mass = 1.0, position = [0.6, 0.0, 0.0] }},
  {{ kind = "A", mass = 1.0, position = [0.9, 0.52, 0.0] }},
]
bonds = [[0, 1], [1, 2]]
[[species]]
name = "dumbbell"
count = 32
sites = [
  {{ kind = "D", mass = 2.0, position = [0.0, 0.0, 0.0] }},
  {{ kind = "D", mass = 1.0, position = [0.7, 0.0, 0.0] }},
]
{bonds}
[[site_pair]]
sites = ["A", "A"]
steps = [[1.0, inf], [1.3, -1.0]]
[[site_pair]]
sites = ["A", "D"]
steps = [[0.9, inf], [1.25, -0.7]]
[[site_pair]]
sites = ["D", "D"]
steps = [[0.8, inf], [1.1, -0.5]]
[rattle]
step = 0.0005
[search]
max_step = 0.02
window = 0.1
[init]
positions = "sc"
temperature = 3.0
[run]
time = 1.5
"#
    )
}

#[test]
fn a_rigid_dumbbell_meets_chains_as_its_bonded_twin_does() {
    // A dumbbell with its one bond under RATTLE is a rigid dumbbell up to the O(h²) error of
    // the step, and both start alike (the bonded one's velocities projected on the bond's
    // tangent, the rigid one's the rotation of the same angular momentum). With a small step
    // the two runs see the same events, through chain–dumbbell events (constrained rule on one
    // side, rigid body on the other) and dumbbell–dumbbell ones (contact rule against the
    // constrained rule).
    let rigid = support::run_with(&chains_and_dumbbells(""), &[]);
    let bonded = support::run_with(&chains_and_dumbbells("bonds = [[0, 1]]"), &[]);
    for s in [&rigid, &bonded] {
        support::assert_conserved(s, "chains and dumbbells", 1e-10);
        assert_eq!(s.anomalies, 0);
    }
    assert_eq!(rigid.degrees_of_freedom, bonded.degrees_of_freedom);
    for kind in ["core", "step_in", "step_out", "step_reflect"] {
        assert_eq!(
            rigid.events_by_kind.get(kind),
            bonded.events_by_kind.get(kind),
            "{kind}: {:?} vs {:?}",
            rigid.events_by_kind,
            bonded.events_by_kind
        );
    }
    assert!(
        rigid.events_by_kind["step_in"] > 100,
        "{:?}",
        rigid.events_by_kind
    );
    assert_eq!(rigid.energy_potential, bonded.energy_potential);
    // The impulses differ by the step's error only.
    let dp = (rigid.pressure - bonded.pressure).abs() / bonded.pressure;
    assert!(
        dp < 1e-2,
        "pressure {} vs {}",
        rigid.pressure,
        bonded.pressure
    );
}
