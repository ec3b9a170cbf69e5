//! The corpus of bad scenes: every file in `tests/bad-scenes/` starts with
//! `# expect: MESSAGE`, the exact first line of the error `dmd` must give for it, and every one
//! is bad input found before the run: `dmd run` refuses it with exit status 2 and that message
//! (after `dmd: FILE: `). Also checks that an override (`--set`) gets the same message as the
//! same mistake in a file.

use std::path::{Path, PathBuf};

use dmd_sim::run::{Quiet, check_setup, run_scene};
use dmd_sim::scene::Scene;
use dmd_sim::smd_engine::{self, Engine};

fn corpus() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-scenes");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

/// The first line of the error of loading and setting up a scene (runs nothing: every scene
/// of the corpus fails before its first event).
fn first_error_line(path: &Path, overrides: &[String]) -> Option<String> {
    let message = match Scene::load(path, overrides) {
        Err(e) => e.to_string(),
        // `dmd check`'s set-up, then the run, as for the event-driven engine.
        Ok((scene, base)) if scene.engine == Engine::Smd => {
            match smd_engine::check_setup(&scene, &base)
                .and_then(|()| smd_engine::run(&scene, &base, None).map(|_| ()))
            {
                Err(e) => e.to_string(),
                Ok(()) => return None,
            }
        }
        // `dmd check`'s set-up (every point of a sweep), then the run.
        Ok((scene, base)) => {
            let text = std::fs::read_to_string(path).unwrap();
            match check_setup(&scene, &base, &text, overrides)
                .and_then(|()| run_scene(&scene, &base, None, &mut Quiet).map(|_| ()))
            {
                Err(e) => e.to_string(),
                Ok(()) => return None,
            }
        }
    };
    Some(message.lines().next().unwrap_or("").to_owned())
}

#[test]
fn every_bad_scene_gets_its_exact_message() {
    let files = corpus();
    assert!(
        files.len() >= 15,
        "the corpus has only {} scenes",
        files.len()
    );
    let mut failures = Vec::new();
    for path in &files {
        let text = std::fs::read_to_string(path).unwrap();
        let expected = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("# expect: "))
            .unwrap_or_else(|| panic!("{} lacks its `# expect:` line", path.display()));
        match first_error_line(path, &[]) {
            Some(got) if got == expected => {}
            got => failures.push(format!(
                "{}:\n  expected: {expected}\n  got:      {}",
                path.file_name().unwrap().to_string_lossy(),
                got.as_deref().unwrap_or("(no error: the scene ran)")
            )),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The command gives every scene of the corpus exit status 2 (a bad scene, docs/USER-GUIDE.md)
/// and the same first line, whether the scene fails when it is read or when it is set up; `dmd
/// check` gives the same.
#[test]
fn the_command_refuses_every_bad_scene_with_exit_status_2() {
    let out = std::env::temp_dir().join(format!("dmd-bad-scenes-{}", std::process::id()));
    let mut failures = Vec::new();
    for path in &corpus() {
        let text = std::fs::read_to_string(path).unwrap();
        let expected = text
            .lines()
            .next()
            .unwrap()
            .trim_start_matches("# expect: ");
        let _ = std::fs::remove_dir_all(&out);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_dmd"))
            .args(["run", "--quiet", "--out"])
            .arg(&out)
            .arg(path)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        let first = err.lines().next().unwrap_or("");
        let want = format!("dmd: {}: {expected}", path.display());
        if o.status.code() != Some(2) || first != want {
            failures.push(format!(
                "{}: exit {:?}\n  expected: {want}\n  got:      {first}",
                path.file_name().unwrap().to_string_lossy(),
                o.status.code()
            ));
        }
        // `dmd check` refuses it the same way: it sets the scene up as `dmd run` does, for
        // either engine.
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_dmd"))
            .arg("check")
            .arg(path)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        let first = err.lines().next().unwrap_or("");
        if o.status.code() != Some(2) || first != want {
            failures.push(format!(
                "dmd check {}: exit {:?}\n  expected: {want}\n  got:      {first}",
                path.file_name().unwrap().to_string_lossy(),
                o.status.code()
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&out);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn an_override_gets_the_same_message_as_a_file() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-scenes");
    let good = dir.join("../../../../scenes/hard-spheres.toml");
    let pairs = [
        ("unknown-key.toml", "box.densty=0.5", Some("box.density=")),
        ("negative-density.toml", "box.density=-0.5", None),
        (
            "steps-not-increasing.toml",
            "pair.0.steps=[[1.0, inf], [1.5, -1.0], [1.2, -0.5]]",
            None,
        ),
        ("count-not-a-number.toml", "species.0.count=\"many\"", None),
    ];
    for (file, set, unset) in pairs {
        let from_file = first_error_line(&dir.join(file), &[]).unwrap();
        let mut overrides = vec![set.to_owned()];
        overrides.extend(unset.map(str::to_owned));
        let from_override = first_error_line(&good, &overrides).unwrap();
        assert_eq!(from_file, from_override, "{file} vs --set {set}");
    }
}

#[test]
fn shipped_scenes_are_valid() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            Scene::load(&path, &[]).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            n += 1;
        }
    }
    assert!(n >= 1);
}

#[test]
fn an_override_of_a_site_scene_gets_the_same_message_as_a_file() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-scenes");
    let good = dir.join("../../../../scenes/hard-dumbbells.toml");
    for (file, set) in [
        (
            "sites-zero-elongation.toml",
            "species.0.molecule.elongation=0.0",
        ),
        ("sites-unknown-impulse-rule.toml", "impulse.rule=lagrangian"),
        ("sites-zero-window.toml", "search.window=0.0"),
    ] {
        let from_file = first_error_line(&dir.join(file), &[]).unwrap();
        let from_override = first_error_line(&good, &[set.to_owned()]).unwrap();
        assert_eq!(from_file, from_override, "{file} vs --set {set}");
    }
}

/// `dmd check --engine smd` sets an event-driven scene up as `dmd run --engine smd` would: a
/// sampling interval shorter than half the smd time step passes the event-driven check (which
/// has no time step) and is refused for the smd engine, by both commands, exit status 2, with
/// the same message, and nothing is written by the check.
#[test]
fn check_with_engine_smd_refuses_what_run_with_engine_smd_refuses() {
    let dir = std::env::temp_dir().join(format!("dmd-check-smd-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("lj.toml");
    std::fs::write(
        &scene,
        "version = 1\n[box]\ndensity = 0.5\n[[species]]\nname = \"A\"\ncount = 256\n\
         [[pair]]\nspecies = [\"A\", \"A\"]\n\
         potential = { kind = \"lennard-jones\", epsilon = 1.0, sigma = 1.0 }\n\
         terraces = { step_kt = 0.5 }\n[init]\npositions = \"fcc\"\ntemperature = 2.0\n\
         [run]\ntime = 0.01\n[output]\nsample_interval = 0.0001\nseries = true\n",
    )
    .unwrap();
    let dmd = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_dmd"))
            .args(args)
            .arg(&scene)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr)
            .lines()
            .next()
            .map(str::to_owned);
        (o.status.code(), err)
    };
    let (code, err) = dmd(&["check"]);
    assert_eq!(code, Some(0), "the event-driven check: {err:?}");
    let want = format!(
        "dmd: {}: scene key `output.sample_interval`: 0.0001 is shorter than half the time \
         step smd.dt = 0.001",
        scene.display()
    );
    let smd = ["--engine", "smd", "--set", "smd.dt=0.001"];
    let (code, err) = dmd(&[&["check"][..], &smd].concat());
    assert_eq!((code, err.as_deref()), (Some(2), Some(want.as_str())));
    let out = dir.join("out");
    let out_arg = out.to_string_lossy().into_owned();
    let (code, err) = dmd(&[&["run", "--quiet", "--out", out_arg.as_str()][..], &smd].concat());
    assert_eq!((code, err.as_deref()), (Some(2), Some(want.as_str())));
    let _ = std::fs::remove_dir_all(&dir);
}
