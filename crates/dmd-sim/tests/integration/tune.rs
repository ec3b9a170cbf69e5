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
        "--budget",
        "0",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    // ΔV and search step at four values each, three level rules; the scene's setting and the
    // finest ΔV (the rules' reference) are run once; with no budget left after the first
    // pass, nothing is lengthened.
    assert!(stderr.contains("[10/10]"), "progress on stderr: {stderr}");
    assert!(stderr.contains("wall-clock budget 0 s"), "{stderr}");
    assert!(!stderr.contains("round 2"), "{stderr}");
    assert!(stdout.contains("no probe was lengthened"), "{stdout}");
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
    // Three knobs, four rows each, coarsest first; the level rule's rows are labelled by rule,
    // its reference is the ΔV knob's.
    assert_eq!(rows.len(), 12);
    let rules: Vec<&Vec<&str>> = rows
        .iter()
        .filter(|r| r[0].contains("step_energy") || r[0].starts_with("scene's rule"))
        .collect();
    assert_eq!(rules.len(), 4, "{rows:?}");
    assert!(
        rules[3][0].starts_with("scene's rule at pair.0.terraces.step_kt=0.125"),
        "{:?}",
        rules[3]
    );
    let step_ref = rows
        .iter()
        .find(|r| r[0] == "pair.0.terraces.step_kt" && r[1].parse::<f64>().unwrap() == 0.125)
        .unwrap();
    assert_eq!(rules[3][2..7], step_ref[2..7], "the same probe");
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

/// At a target the first pass cannot certify, probes are lengthened: each lengthened probe
/// pools runs, and a knob's reference is lengthened with its candidate.
#[test]
fn tune_lengthens_the_probes_that_noise_keeps_out_within_its_budget() {
    let d = scratch("tune-longer");
    let scene = rods_scene(&d);
    let out = d.join("out");
    let o = dmd(&[
        "tune",
        &scene,
        "--target",
        "0.1",
        "--time",
        "0.2",
        "--budget",
        "1h",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("wall-clock budget 1 h 00 min"), "{stderr}");
    assert!(stderr.contains("round 2: "), "{stderr}");
    assert!(stdout.contains("lengthened, each pooled"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("tune.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let num = |r: &[&str], c: &str| r[col(c)].parse::<f64>().unwrap();
    let mut lengthened = 0;
    for key in ["pair.0.terraces.step_kt", "search.max_step"] {
        let knob: Vec<&Vec<&str>> = rows.iter().filter(|r| r[0] == key).collect();
        let long: Vec<&&Vec<&str>> = knob.iter().filter(|r| num(r, "runs") > 1.0).collect();
        for r in &long {
            // More production than one first-pass probe of 0.2 τ.
            assert!(num(r, "production (τ)") > 0.2 * (1.0 + 1e-9), "{r:?}");
        }
        if !long.is_empty() {
            // A candidate is lengthened with its knob's reference (the last row), unless the
            // scene's own probe, shared with the other knob, was lengthened for that one.
            lengthened += 1;
            assert!(
                num(knob[3], "runs") > 1.0 || long.iter().all(|r| r[1] == "1e-2" || r[1] == "5e-1"),
                "{key}: {knob:?}"
            );
        }
    }
    assert!(lengthened > 0, "{csv}");
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
    for budget in ["-1", "9 minutes", "x"] {
        let o = dmd(&[
            "tune", &scene, "--target", "0.02", "--budget", budget, "--out", out,
        ]);
        assert_eq!(o.status.code(), Some(2), "--budget {budget}");
        assert!(String::from_utf8_lossy(&o.stderr).contains("--budget"));
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

/// A terraced pair of Lennard-Jones spheres (or rods) is tuned in its ΔV and in its level rule:
/// every terrace-energy rule other than the scene's at the scene's ΔV, against the scene's rule
/// at the finest ΔV probed (the same probe as the ΔV knob's reference).
#[test]
fn a_terraced_pair_is_tuned_in_its_step_and_its_level_rule() {
    use dmd_sim::scene::Scene;
    use dmd_sim::tune::knobs;
    let lj = crate::support::scenes_dir().join("stepped-lj.toml");
    let as_terraces = [
        "pair.0.steps=".to_owned(),
        r#"pair.0.potential={kind="lennard-jones", epsilon=1.0, sigma=1.0}"#.to_owned(),
        "pair.0.terraces={step=0.5, core=10.0}".to_owned(),
    ];
    let (scene, _) = Scene::load(&lj, &as_terraces).unwrap();
    let k = knobs(&scene).unwrap();
    assert_eq!(k.len(), 2, "{k:?}");
    assert_eq!(k[0].key, "pair.0.terraces.step");
    assert_eq!(k[0].values(), [1.0, 0.5, 0.25, 0.125]);
    let rule = &k[1];
    assert_eq!(rule.label, "level rule of pair 0");
    assert_eq!(rule.values(), [0.0, 1.0, 2.0, 3.0]);
    let sets: Vec<Vec<String>> = rule.values().iter().map(|&v| rule.sets(v)).collect();
    let energy = |e: &str| vec![format!("pair.0.terraces.step_energy=\"{e}\"")];
    assert_eq!(
        sets,
        [
            energy("virial"),
            energy("midpoint"),
            energy("volume-average"),
            // The reference is the ΔV knob's.
            k[0].sets(0.125),
        ]
    );
    // Choosing the reference keeps the scene's rule: nothing to paste for it.
    assert!(rule.recommend(3.0).is_empty());
    assert_eq!(rule.recommend(0.0), sets[0]);
    assert!(rule.finer_sets().is_empty());
    assert_eq!(k[0].finer_sets(), ["pair.0.terraces.step=0.0625"]);
    // Every probe is a valid scene.
    for s in &sets {
        let mut all = as_terraces.to_vec();
        all.extend(s.iter().cloned());
        Scene::load(&lj, &all).unwrap();
    }
    // A scene on B₂-matched terraces is offered the paper's equal steps instead of its own.
    let mut virial = as_terraces.to_vec();
    virial.push("pair.0.terraces.step_energy=\"virial\"".to_owned());
    let (scene, _) = Scene::load(&lj, &virial).unwrap();
    let rule = knobs(&scene).unwrap().pop().unwrap();
    assert_eq!(rule.sets(0.0), energy("equal"));
    assert_eq!(rule.values().len(), 4);
    // Explicit levels are a rule of their own: no rule knob (and no ΔV knob).
    let mut levels = as_terraces.to_vec();
    levels.push("pair.0.terraces={levels=[-0.5, 0.5], step_energy=\"midpoint\"}".to_owned());
    let (scene, _) = Scene::load(&lj, &levels).unwrap();
    assert!(knobs(&scene).is_err());
    // The paper's rods: ΔV, the level rule and the search step.
    let rods = crate::support::scenes_dir().join("rods-paper.toml");
    let (scene, _) = Scene::load(&rods, &[]).unwrap();
    let keys: Vec<String> = knobs(&scene).unwrap().into_iter().map(|k| k.key).collect();
    assert_eq!(
        keys,
        [
            "pair.0.terraces.step_kt",
            "pair.0.terraces.step_energy",
            "search.max_step"
        ]
    );
}
