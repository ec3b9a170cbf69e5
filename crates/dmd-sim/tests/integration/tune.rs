//! `dmd tune`: the command runs its probes on a small rods scene, writes its table and plot,
//! recommends what its own table says, and refuses bad input with exit status 2.

use std::path::Path;
use std::process::{Command, Output};

use crate::support::{REDUCED_RODS, scratch};

fn dmd(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dmd"))
        .args(args)
        .output()
        .unwrap()
}

/// The reduced rods with a search step (so that two knobs are probed) and sampling (so that
/// U/N and P carry error bars).
fn rods_scene(dir: &Path) -> String {
    let path = dir.join("rods.toml");
    std::fs::write(
        &path,
        format!(
            "{REDUCED_RODS}[search]\nmax_step = 0.01\nwindow = 0.01\n[output]\nsample_interval = 0.01\n"
        ),
    )
    .unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn tune_writes_its_table_and_recommends_the_cheapest_row_within_the_target() {
    let d = scratch("tune");
    let scene = rods_scene(&d);
    let out = d.join("out");
    let target = 0.5;
    let o = dmd(&[
        "tune",
        &scene,
        "--target",
        &target.to_string(),
        "--time",
        "0.2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("[7/7]"), "progress on stderr: {stderr}");
    assert!(out.join("tune.svg").is_file());
    let csv = std::fs::read_to_string(out.join("tune.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    // Terraced rods are judged by their smooth estimators (the continuous model).
    assert!(header.contains(&"U_per_body_smooth (ε)"), "{header:?}");
    assert!(stdout.contains("U/N smooth (ε)"), "{stdout}");
    assert!(header.contains(&"cpu_seconds_per_τ (s/τ)"), "{header:?}");
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    // Two knobs, four values each, coarsest first.
    assert_eq!(rows.len(), 8);
    let num = |r: &[&str], c: &str| r[col(c)].parse::<f64>().unwrap();
    for key in ["pair.0.terraces.step_kt", "search.max_step"] {
        let knob: Vec<&Vec<&str>> = rows.iter().filter(|r| r[0] == key).collect();
        assert_eq!(knob.len(), 4, "{key}");
        // The last is the reference: no deviation from itself.
        assert_eq!(num(knob[3], "bound"), 0.0);
        for r in &knob {
            // The bound is the larger of U's and P's error plus uncertainty.
            let b = (num(r, "U_rel_error") + num(r, "U_rel_uncertainty"))
                .max(num(r, "P_rel_error") + num(r, "P_rel_uncertainty"));
            assert!((b - num(r, "bound")).abs() <= 1e-12 * b.max(1.0), "{r:?}");
            assert_eq!(r[col("within_target")] == "true", b <= target, "{r:?}");
        }
        let cost = |r: &Vec<&str>| num(r, "cpu_seconds_per_τ (s/τ)");
        let chosen: Vec<&&Vec<&str>> = knob
            .iter()
            .filter(|r| r[col("recommended")] == "true")
            .collect();
        assert_eq!(chosen.len(), 1, "{key}: one recommendation");
        let cheapest = knob
            .iter()
            .filter(|r| r[col("within_target")] == "true")
            .map(|r| cost(r))
            .fold(f64::INFINITY, f64::min);
        assert_eq!(cost(chosen[0]), cheapest, "{key}");
        let value: f64 = chosen[0][1].parse().unwrap();
        assert!(
            stdout.contains(&format!("--set {key}={value}")),
            "{key}={value} not among the --set lines:\n{stdout}"
        );
    }
}

#[test]
fn tune_refuses_bad_targets_and_scenes_without_a_knob() {
    let d = scratch("tune-bad");
    let scene = rods_scene(&d);
    let out = d.join("out");
    let out = out.to_str().unwrap();
    for target in ["0", "-0.1", "nan", "inf"] {
        let o = dmd(&["tune", &scene, "--target", target, "--out", out]);
        assert_eq!(o.status.code(), Some(2), "--target {target}");
        assert!(String::from_utf8_lossy(&o.stderr).contains("--target"));
    }
    let hs = crate::support::scenes_dir().join("hard-spheres.toml");
    let o = dmd(&[
        "tune",
        hs.to_str().unwrap(),
        "--target",
        "0.02",
        "--out",
        out,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nothing to tune"));
    let o = dmd(&[
        "tune",
        "no-such-scene.toml",
        "--target",
        "0.02",
        "--out",
        out,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!Path::new(out).join("tune.csv").exists());
}

/// Semi-flexible molecules are tuned in their search step and their RATTLE step (the scene's,
/// or the default the run would use when `[rattle]` does not give it); rigid site molecules in
/// their search step.
#[test]
fn molecules_are_tuned_in_their_search_and_rattle_steps() {
    use dmd_sim::scene::Scene;
    use dmd_sim::tune::knobs;
    let chains = crate::support::scenes_dir().join("flexible-chains.toml");
    let (scene, _) = Scene::load(&chains, &[]).unwrap();
    let k = knobs(&scene).unwrap();
    let keys: Vec<(&str, f64)> = k.iter().map(|k| (k.key.as_str(), k.value)).collect();
    assert_eq!(keys, [("search.max_step", 0.02), ("rattle.step", 0.005)]);
    // Without `rattle.step`: 0.01 × the shortest bond (0.6) / √(kT/m) at kT = 1.5, m = 1.
    let (scene, _) = Scene::load(&chains, &["rattle.step=".to_owned()]).unwrap();
    let rattle = knobs(&scene).unwrap().pop().unwrap();
    assert_eq!(rattle.key, "rattle.step");
    assert!(
        (rattle.value - 0.01 * 0.6 / 1.5f64.sqrt()).abs() < 1e-12,
        "{rattle:?}"
    );
    let sites = crate::support::scenes_dir().join("benzene-like.toml");
    let (scene, _) = Scene::load(&sites, &["search.max_step=0.004".to_owned()]).unwrap();
    let k = knobs(&scene).unwrap();
    assert!(
        k.iter()
            .any(|k| k.key == "search.max_step" && k.value == 0.004),
        "{k:?}"
    );
}
