//! `cargo xtask ci` and `cargo xtask bench`.
//!
//! The CI step list is the single source of truth: `.ci/run` lists the same commands literally,
//! and the test `ci_script_matches_steps` below fails if the two (or the README) drift apart.

use std::process::Command;

use crate::workspace_root;

/// The test command the README gives a newcomer. `.ci/run` must run exactly this.
pub(crate) const TEST_COMMAND: &str = "cargo test --workspace";

/// Environment of every CI step. Property tests draw from a fixed seed in CI, so that a red run
/// is reproducible and a green one stays green; run locally without it, they explore new cases
/// every time (which is how they keep finding things).
pub(crate) const CI_ENV: &[(&str, &str)] = &[("PROPTEST_RNG_SEED", "2007")];

/// The README's first command, the main job: a `dmd run` of a shipped scene.
#[cfg(test)]
pub(crate) const MAIN_COMMAND: &str = "cargo run --release -p dmd-sim --bin dmd -- run scenes/hard-spheres.toml --out out/hard-spheres";

/// One CI step: what it checks, the command line, and extra environment variables.
pub(crate) type Step = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
);

/// Every CI step, in order.
pub(crate) const STEPS: &[Step] = &[
    ("format", "cargo fmt --all -- --check", &[]),
    // `validation` adds the `validate_*` examples, which `cargo test` does not build.
    (
        "lints",
        "cargo clippy --workspace --all-targets --features validation -- -D warnings",
        &[],
    ),
    // The gsd crate's tests exchange files with the reference Python package; dmd-sim's
    // check that ASE and OVITO's Python module read its trajectories.
    (
        "python packages",
        "python3 -m pip install --quiet --disable-pip-version-check ase gsd numpy ovito",
        &[],
    ),
    ("tests", TEST_COMMAND, &[]),
    // The Python package (python/): built by pip through maturin in the dev profile (its
    // crates are mostly built by the tests above), then its pytest suite (Dask for its
    // ensembles on a cluster).
    (
        "python package",
        "python3 -m pip install --quiet --disable-pip-version-check ./python pytest dask distributed",
        &[("MATURIN_PEP517_ARGS", "--profile dev")],
    ),
    ("python tests", "python3 -m pytest -q python/tests", &[]),
    (
        "docs",
        "cargo doc --workspace --no-deps",
        &[("RUSTDOCFLAGS", "-D warnings")],
    ),
    ("quick validation", "cargo xtask validate --quick", &[]),
];

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    if let Some(extra) = args.first() {
        return Err(format!("`ci` takes no arguments, got `{extra}`"));
    }
    for (what, command, env) in STEPS {
        eprintln!("==> {what}: {command}");
        shell(command, &[CI_ENV, env].concat())?;
    }
    eprintln!("==> all CI steps passed");
    Ok(())
}

pub(crate) fn bench(args: &[String]) -> Result<(), String> {
    let only = crate::parse_only(args)?;
    let passthrough: Vec<&str> = match args.iter().position(|a| a == "--") {
        Some(i) => args[i + 1..].iter().map(String::as_str).collect(),
        None => Vec::new(),
    };
    let mut cmd = Command::new("cargo");
    cmd.current_dir(workspace_root())
        .args(["bench", "--package", "dmd-benches"]);
    for name in only.iter().flatten() {
        cmd.args(["--bench", name]);
    }
    if !passthrough.is_empty() {
        cmd.arg("--").args(passthrough);
    }
    status_ok(&mut cmd, "cargo bench")
}

/// Runs a whitespace-separated command line (no shell involved) from the workspace root.
fn shell(command: &str, env: &[(&str, &str)]) -> Result<(), String> {
    let mut words = command.split_whitespace();
    let program = words.next().ok_or("empty command")?;
    let mut cmd = Command::new(program);
    cmd.current_dir(workspace_root()).args(words);
    for (k, v) in env {
        cmd.env(k, v);
    }
    status_ok(&mut cmd, command)
}

pub(crate) fn status_ok(cmd: &mut Command, what: &str) -> Result<(), String> {
    let status = cmd
        .status()
        .map_err(|e| format!("could not start `{what}`: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{what}` failed ({status})"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(rel: &str) -> String {
        std::fs::read_to_string(workspace_root().join(rel))
            .unwrap_or_else(|e| panic!("cannot read {rel}: {e}"))
    }

    #[test]
    fn ci_script_matches_steps() {
        let script = read(".ci/run");
        let lines: Vec<&str> = script.lines().map(str::trim).collect();
        for (what, command, env) in STEPS {
            let found = lines.iter().any(|l| {
                l.ends_with(command) && env.iter().all(|(k, v)| l.contains(&format!("{k}=\"{v}\"")))
            });
            assert!(
                found,
                ".ci/run lacks the `{what}` step `{command}` (env {env:?})"
            );
        }
    }

    #[test]
    fn readme_starts_with_the_main_command_and_its_scene_exists() {
        let readme = read("README.md");
        let first = readme
            .split("```sh\n")
            .nth(1)
            .and_then(|b| b.lines().next())
            .expect("README.md has a ```sh block");
        assert_eq!(
            first, MAIN_COMMAND,
            "the README's first command is not the main job"
        );
        let scene = MAIN_COMMAND
            .split_whitespace()
            .find(|w| w.ends_with(".toml"))
            .expect("the main command names a scene file");
        assert!(
            workspace_root().join(scene).is_file(),
            "the main command's scene {scene} does not exist"
        );
    }

    #[test]
    fn ci_script_exports_the_ci_environment() {
        let script = read(".ci/run");
        for (k, v) in CI_ENV {
            assert!(
                script
                    .lines()
                    .any(|l| l.trim() == format!("export {k}={v}")),
                ".ci/run must `export {k}={v}`"
            );
        }
    }

    #[test]
    fn readme_gives_the_test_command() {
        let readme = read("README.md");
        assert!(
            readme.contains(&format!("\n{TEST_COMMAND}\n")),
            "README.md must show `{TEST_COMMAND}` on a line of its own"
        );
    }
}
