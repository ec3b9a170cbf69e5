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
        // Issue 8: a scene for the standard-MD engine goes where `dmd run` sends it.
        Ok((scene, base)) if scene.engine == Engine::Smd => {
            match smd_engine::run(&scene, &base, None) {
                Err(e) => e.to_string(),
                Ok(_) => return None,
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
        // `dmd check` refuses it the same way: it sets the scene up as `dmd run` does
        // (scenes for the smd engine are set up by that engine's run alone).
        if text.contains("engine = \"smd\"") {
            continue;
        }
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
