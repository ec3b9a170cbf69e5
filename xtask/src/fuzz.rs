//! `cargo xtask fuzz [--minutes M] [--only TARGET,..] [--seed S]`: the fuzz targets of
//! `crates/dmd-sim/tests/integration/fuzz.rs` (scene, set, xyz, gsd, checkpoint), one after the
//! other, each for `M` minutes (1 by default) in the test profile (debug assertions on), from
//! seed `S` (the clock by default, so every run explores new inputs). Prints each target's
//! count of inputs tried; exits non-zero when a target finds something (the inputs are kept
//! under the target directory's `tmp/fuzz-findings/`).

use std::process::Command;

use crate::{parse_only, workspace_root};

/// The targets: name and test function.
const TARGETS: &[(&str, &str)] = &[
    ("scene", "fuzz::fuzz_scene_parser_and_checker"),
    ("set", "fuzz::fuzz_set_overrides"),
    ("xyz", "fuzz::fuzz_xyz_start_file"),
    ("gsd", "fuzz::fuzz_gsd_start_file"),
    ("checkpoint", "fuzz::fuzz_checkpoint_reader"),
];

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    let mut minutes = 1.0f64;
    let mut seed: Option<u64> = None;
    let mut k = 0;
    while k < args.len() {
        match args[k].as_str() {
            "--minutes" => {
                minutes = args
                    .get(k + 1)
                    .and_then(|m| m.parse().ok())
                    .filter(|m: &f64| m.is_finite() && *m > 0.0)
                    .ok_or("`--minutes` needs a positive number")?;
                k += 2;
            }
            "--seed" => {
                seed = Some(
                    args.get(k + 1)
                        .and_then(|s| s.parse().ok())
                        .ok_or("`--seed` needs a whole number")?,
                );
                k += 2;
            }
            "--only" => k += 2,
            other => return Err(format!("`fuzz` does not take `{other}`")),
        }
    }
    let only = parse_only(args)?;
    if let Some(names) = &only
        && let Some(bad) = names.iter().find(|n| !TARGETS.iter().any(|(t, _)| t == n))
    {
        return Err(format!(
            "no fuzz target `{bad}`; the targets are {}",
            TARGETS.iter().map(|t| t.0).collect::<Vec<_>>().join(", ")
        ));
    }
    let seed = seed.unwrap_or_else(|| {
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(1, |d| d.as_secs())
    });
    let mut failed = Vec::new();
    for (name, test) in TARGETS {
        if only.as_ref().is_some_and(|o| !o.iter().any(|n| n == name)) {
            continue;
        }
        eprintln!("==> fuzz {name}: {minutes} min, seed {seed}");
        let status = Command::new(env!("CARGO"))
            .current_dir(workspace_root())
            .args([
                "test",
                "-p",
                "dmd-sim",
                "--test",
                "integration",
                "--",
                "--exact",
                test,
                "--nocapture",
                "--test-threads=1",
            ])
            .env("DMD_FUZZ_SECONDS", (minutes * 60.0).to_string())
            .env("DMD_FUZZ_SEED", seed.to_string())
            .status()
            .map_err(|e| format!("cannot start cargo: {e}"))?;
        if !status.success() {
            failed.push(*name);
        }
    }
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!("fuzz targets with findings: {}", failed.join(", ")))
    }
}
