//! Parallel chains and sweeps (issue 9): results independent of the thread count, aggregated
//! with error bars that agree with the chains' own block averages.

use std::path::PathBuf;

use dmd_sim::chains::{chain_seed, jobs, run_ensemble};
use dmd_sim::checkpoint::SceneSource;
use dmd_sim::scene::Scene;

const SCENE: &str = r#"
version = 1
seed = 3
[box]
density = 0.4
[[species]]
name = "A"
count = 64
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf], [1.5, -1.0]]
[init]
positions = "sc"
temperature = 1.5
[run]
equilibration_events = 3000
[hmc]
segment_time = 0.5
segments = 100
[chains]
count = 4
[sweep]
key = "hmc.temperature"
values = [1.5, 3.0]
"#;

fn source() -> SceneSource {
    SceneSource {
        text: SCENE.to_owned(),
        overrides: Vec::new(),
        base: PathBuf::from("."),
        file: PathBuf::from("chains.toml"),
    }
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dmd-chains-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn jobs_are_keyed_by_point_and_chain() {
    let scene = Scene::from_str_with(SCENE, &[]).unwrap();
    let j = jobs(&scene, SCENE, &[]).unwrap();
    assert_eq!(j.len(), 8);
    assert_eq!(j[5].dir, PathBuf::from("point-1/chain-1"));
    assert_eq!(j[5].scene.hmc.as_ref().unwrap().temperature, Some(3.0));
    assert_eq!(j[5].scene.seed, chain_seed(3, 1));
    // Chain c has the same seed at every point (common random numbers), and chains differ.
    assert_eq!(j[1].scene.seed, j[5].scene.seed);
    assert_ne!(j[0].scene.seed, j[1].scene.seed);
    assert!(
        j.iter()
            .all(|x| x.scene.chains.is_none() && x.scene.sweep.is_none())
    );
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let scene = Scene::from_str_with(SCENE, &[]).unwrap();
    let one = dir("t1");
    let two = dir("t2");
    let a = run_ensemble(&scene, &source(), &one, Some(1), None, &|_, _| {}).unwrap();
    let b = run_ensemble(&scene, &source(), &two, Some(2), None, &|_, _| {}).unwrap();
    assert_eq!(a, b);
    assert_eq!(
        std::fs::read(one.join("ensemble.json")).unwrap(),
        std::fs::read(two.join("ensemble.json")).unwrap()
    );
    assert_eq!(
        std::fs::read(one.join("point-1/chain-3/summary.json"))
            .ok()
            .map(|_| ()),
        Some(())
    );
    // The aggregate: 4 chains per point, each value that chain's summary; the scatter between
    // chains and the chains' block errors estimate the same standard error (each estimate
    // from 4 chains is uncertain by ~40 %, hence the factor 3).
    for p in &a.points {
        let u = &p.quantities["hmc.potential_energy_per_body.mean"];
        assert_eq!(u.values.len(), 4);
        let (e, b) = (u.error.unwrap(), u.block_error.unwrap());
        assert!(
            e > 0.0 && b > 0.0 && e / b < 3.0 && b / e < 3.0,
            "{e} vs {b}"
        );
        let acc = &p.quantities["hmc.acceptance_rate"];
        assert_eq!(acc.mean, 1.0, "exact dynamics: every segment accepted");
    }
    // Hotter: less bound.
    let u = |k: usize| a.points[k].quantities["hmc.potential_energy_per_body.mean"].mean;
    assert!(u(1) > u(0) + 0.05, "{} {}", u(0), u(1));
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(one.join("point-0/chain-2/summary.json")).unwrap())
            .unwrap();
    assert_eq!(
        s["hmc"]["potential_energy_per_body"]["mean"].as_f64(),
        Some(a.points[0].quantities["hmc.potential_energy_per_body.mean"].values[2])
    );
    let _ = std::fs::remove_dir_all(one);
    let _ = std::fs::remove_dir_all(two);
}

#[test]
fn an_interrupted_ensemble_is_finished_by_resume() {
    use dmd_sim::checkpoint::Every;
    use dmd_sim::run::RunError;
    let scene = Scene::from_str_with(SCENE, &["hmc.segments=60".into()]).unwrap();
    let src = SceneSource {
        overrides: vec!["hmc.segments=60".into()],
        ..source()
    };
    let straight = dir("straight");
    let a = run_ensemble(&scene, &src, &straight, Some(2), None, &|_, _| {}).unwrap();
    let crashed = dir("crashed");
    let e =
        dmd_sim::chains::run_ensemble_halting(&scene, &src, &crashed, Some(2), Every::Events(3000))
            .unwrap_err();
    assert!(
        matches!(&e, RunError::Job { source, .. } if matches!(**source, RunError::Halted)),
        "{e}"
    );
    // One job finished before the crash (its summary is read back), one never started.
    std::fs::remove_dir_all(crashed.join("point-1/chain-3")).unwrap();
    std::fs::copy(
        straight.join("point-0/chain-0/summary.json"),
        crashed.join("point-0/chain-0/summary.json"),
    )
    .unwrap();
    let b = dmd_sim::chains::resume_ensemble(&crashed, Some(1), &|_, _| {}).unwrap();
    assert_eq!(a, b);
    let hmc = |d: &std::path::Path| -> serde_json::Value {
        serde_json::from_slice::<serde_json::Value>(
            &std::fs::read(d.join("point-1/chain-2/summary.json")).unwrap(),
        )
        .unwrap()["hmc"]
            .clone()
    };
    assert_eq!(hmc(&straight), hmc(&crashed));
    let _ = std::fs::remove_dir_all(straight);
    let _ = std::fs::remove_dir_all(crashed);
}

#[test]
fn jobs_run_one_by_one_give_the_aggregate_of_run_ensemble() {
    use dmd_sim::chains::{JobStart, run_or_resume_job, start_ensemble, write_aggregate};
    let set = vec!["hmc.segments=20".to_owned()];
    let scene = Scene::from_str_with(SCENE, &set).unwrap();
    let src = SceneSource {
        overrides: set,
        ..source()
    };
    let together = dir("together");
    let a = run_ensemble(&scene, &src, &together, Some(2), None, &|_, _| {}).unwrap();
    // As a scheduler elsewhere runs them: the folder prepared, then each job on its own, in
    // any order, then the aggregate of the summaries on disk.
    let apart = dir("apart");
    let jobs = start_ensemble(&scene, &src, &apart, None).unwrap();
    for k in (0..jobs.len()).rev() {
        let (_, start) = run_or_resume_job(&apart, k).unwrap();
        assert_eq!(start, JobStart::Fresh);
    }
    let (summary, start) = run_or_resume_job(&apart, 3).unwrap();
    assert_eq!(start, JobStart::Finished, "a finished job is read back");
    assert_eq!(summary["hmc"]["acceptance_rate"].as_f64(), Some(1.0));
    let e = run_or_resume_job(&apart, jobs.len())
        .unwrap_err()
        .to_string();
    assert!(e.contains("the ensemble has 8 jobs"), "{e}");
    let b = write_aggregate(&apart).unwrap();
    assert_eq!(a, b);
    for file in ["ensemble.json", "ensemble.csv"] {
        assert_eq!(
            std::fs::read(together.join(file)).unwrap(),
            std::fs::read(apart.join(file)).unwrap(),
            "{file}"
        );
    }
    let _ = std::fs::remove_dir_all(together);
    let _ = std::fs::remove_dir_all(apart);
}

/// Plain event-driven chains: each chain's block-average errors (`_error` in its summary) are
/// combined into `block_error`, which estimates what the scatter between the chains does.
#[test]
fn the_chains_block_errors_are_combined_and_agree_with_their_scatter() {
    let text = SCENE
        .replace("[hmc]\nsegment_time = 0.5\nsegments = 100\n", "")
        .replace("count = 4", "count = 6")
        .replace(
            "key = \"hmc.temperature\"\nvalues = [1.5, 3.0]",
            "key = \"init.temperature\"\nvalues = [1.5]",
        )
        + "[output]\nsample_interval = 0.05\n";
    let text = text.replace(
        "equilibration_events = 3000",
        "equilibration_events = 3000\nevents = 40000",
    );
    let scene = Scene::from_str_with(&text, &[]).unwrap();
    let src = SceneSource {
        text: text.clone(),
        ..source()
    };
    let out = dir("blocks");
    let e = run_ensemble(&scene, &src, &out, Some(2), None, &|_, _| {}).unwrap();
    for name in ["temperature", "pressure", "potential_energy_per_body"] {
        let q = &e.points[0].quantities[name];
        let (err, block) = (q.error.unwrap(), q.block_error.unwrap());
        // Each estimate from 6 chains is uncertain by ~30 %, hence the factor 3.
        assert!(
            err > 0.0 && block > 0.0 && err / block < 3.0 && block / err < 3.0,
            "{name}: scatter {err}, blocks {block}"
        );
    }
    let csv = std::fs::read_to_string(out.join("ensemble.csv")).unwrap();
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .contains("temperature_error,temperature_block_error")
    );
    let _ = std::fs::remove_dir_all(out);
}
