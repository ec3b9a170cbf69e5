//! Project automation for the `dmd` workspace, run as `cargo xtask <command>`.
//!
//! - `ci`: the checks `.ci/run` performs (format, clippy, the README's test command, docs).
//! - `validate [--quick] [--only NAME,..]`: slow physics and algorithm validation; each check
//!   rewrites its own section of `docs/VALIDATION.md` (with `--quick`, a reduced run whose report
//!   goes to `target/validate-quick/` so CI never edits tracked files).
//! - `frontier [--quick]`: shorthand for `validate --only frontier [--quick]`, the error-against-cost
//!   frontier of DMD and SMD on the paper's rods (dense and gas) and on SSD/E water.
//! - `bench [--only NAME,..]`: the criterion benchmarks of `benches/`.
//! - `fuzz [--minutes M] [--only TARGET,..] [--seed S]`: the fuzz targets of the input surface
//!   (scene, `--set`, XYZ start file, checkpoint), each for `M` minutes.
//!
//! xtask depends on nothing but std and compiles in seconds: validations are release-built
//! examples of the crates they check, which print a Markdown fragment and exit non-zero when a
//! check fails. This keeps the physics code in the crates that own it.

mod ci;
mod fuzz;
mod report;
mod validate;

use std::path::PathBuf;
use std::process::ExitCode;

const USAGE: &str = "\
usage: cargo xtask <command> [options]

commands:
  ci                         fmt --check, clippy -D warnings, the README test command, rustdoc -D warnings
  validate [--quick] [--only NAME[,NAME..]] [--list]
                             run validation checks; full runs rewrite docs/VALIDATION.md sections
  frontier [--quick]         the same as `validate --only frontier [--quick]`: DMD against SMD,
                             error against cost on the paper's rods and SSD/E water
  bench [--only NAME[,NAME..]] [-- CRITERION ARGS]
                             run the criterion benchmarks in benches/
  fuzz [--minutes M] [--only TARGET[,TARGET..]] [--seed S]
                             run the fuzz targets (scene, set, xyz, gsd, checkpoint), M minutes each
";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("ci") => ci::run(&args[1..]),
        Some("validate") => validate::run(&args[1..]),
        Some("frontier") => frontier(&args[1..]),
        Some("bench") => ci::bench(&args[1..]),
        Some("fuzz") => fuzz::run(&args[1..]),
        Some("-h" | "--help" | "help") => {
            print!("{USAGE}");
            Ok(())
        }
        Some(other) => Err(format!("unknown command `{other}`\n{USAGE}")),
        None => Err(format!("no command given\n{USAGE}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("xtask: {msg}");
            ExitCode::FAILURE
        }
    }
}

/// `cargo xtask frontier [--quick]`: the `frontier` validation alone.
fn frontier(args: &[String]) -> Result<(), String> {
    let mut forwarded = vec!["--only".to_owned(), "frontier".to_owned()];
    for a in args {
        match a.as_str() {
            "--quick" => forwarded.push(a.clone()),
            other => return Err(format!("`frontier` takes only `--quick`, got `{other}`")),
        }
    }
    validate::run(&forwarded)
}

/// The workspace root (the parent of `xtask/`), whatever directory cargo was started from.
fn workspace_root() -> PathBuf {
    let manifest_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest_dir
        .parent()
        .expect("xtask lives one level below the workspace root")
        .to_path_buf()
}

/// Parses `--only a,b` into a list of names; `None` when the flag is absent.
fn parse_only(args: &[String]) -> Result<Option<Vec<String>>, String> {
    match args.iter().position(|a| a == "--only") {
        None => Ok(None),
        Some(i) => {
            let list = args
                .get(i + 1)
                .ok_or("`--only` needs a comma-separated list of names")?;
            Ok(Some(list.split(',').map(str::to_owned).collect()))
        }
    }
}
