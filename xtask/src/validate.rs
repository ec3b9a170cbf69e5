//! `cargo xtask validate`: the slow physics and algorithm checks.
//!
//! Each [`Check`] is a release-built example of the crate it validates. The example prints a
//! Markdown fragment on stdout (tables, links to figures it wrote under `--figures DIR`) and exits
//! non-zero if a check failed. A full run rewrites the check's section of `docs/VALIDATION.md`;
//! `--quick` runs the reduced arguments and writes to `target/validate-quick/` instead.
//!
//! Adding a validation = adding one entry to [`CHECKS`].

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::report::splice;
use crate::workspace_root;

/// One validation: an example of a crate, run with full or quick arguments.
pub(crate) struct Check {
    /// Section key in `docs/VALIDATION.md` and the name `--only` selects.
    pub(crate) name: &'static str,
    /// Section heading.
    pub(crate) title: &'static str,
    /// Cargo package that owns the example.
    pub(crate) package: &'static str,
    /// Example target name.
    pub(crate) example: &'static str,
    /// Arguments of a full run.
    pub(crate) full: &'static [&'static str],
    /// Arguments of the quick CI subset.
    pub(crate) quick: &'static [&'static str],
}

/// Every validation, in the order the report shows them.
pub(crate) const CHECKS: &[Check] = &[
    Check {
        name: "event-queue",
        title: "Event queue: model check at scale and the hold benchmark",
        package: "dmd-event-queue",
        example: "validate_queue",
        full: &["--events", "10000000"],
        quick: &["--events", "200000", "--quick"],
    },
    Check {
        name: "rigid-free",
        title: "Free rigid body: accuracy, error against run time (exact vs RK4), conservation",
        package: "rigid-free",
        example: "validate_free",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "root-search",
        title: "Root search: missed roots against evaluations over the adversarial corpus",
        package: "root-search",
        example: "corpus",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "dmd-sim",
        title: "Simulator: hard spheres and square wells against published references, conservation, determinism",
        package: "dmd-sim",
        example: "validate_spheres",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "dmd-sim-rods",
        title: "Rigid rods on terraced potentials: conservation, events per ps against the paper, structure and dynamics, extreme cases",
        package: "dmd-sim",
        example: "validate_rods",
        full: &["--part", "physics"],
        quick: &["--part", "physics", "--quick"],
    },
    Check {
        name: "dmd-sim-rods-cost",
        title: "Rigid rods: error against run time (missed events against search settings, terrace step and rules)",
        package: "dmd-sim",
        example: "validate_rods",
        full: &["--part", "cost"],
        quick: &["--part", "cost", "--quick"],
    },
    Check {
        name: "sites",
        title: "Site-based rigid molecules: conservation, contact vs constrained rule, missed events against search settings",
        package: "dmd-sim",
        example: "validate_sites",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "sites-eos",
        title: "Hard dumbbells: compressibility factor from the molecular collision virial against the Tildesley–Streett equation of state at two elongations",
        package: "dmd-sim",
        example: "validate_sites_eos",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "flexible",
        title: "Semi-flexible molecules: RATTLE between events, error against run time for the RATTLE step, rigid limit, conservation, the measure of constrained dynamics and HMC",
        package: "dmd-sim",
        example: "validate_flexible",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "hmc",
        title: "Hybrid Monte Carlo: exact canonical answers with deliberate misses, acceptance against segment length, stiff systems, checkpoints, chains",
        package: "dmd-sim",
        example: "validate_hmc",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "errors",
        title: "Error bars: the scatter of independent runs against the errors they report (hard spheres and rods)",
        package: "dmd-sim",
        example: "validate_errors",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "signals",
        title: "Signals: SIGTERM at random moments of 30 s runs, resumed bit for bit (hard spheres and rods)",
        package: "dmd-sim",
        example: "validate_signals",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "collide",
        title: "Impulse rules: conservation, constraints, reversibility and cross-check statistics",
        package: "dmd-collide",
        example: "validate_collide",
        full: &["--events", "1000000"],
        quick: &["--events", "20000", "--quick"],
    },
    Check {
        name: "potential",
        title: "Pair potentials and terrace maps: forces and torques, reaches, B2 of terraced potentials",
        package: "dmd-potential",
        example: "validate_potential",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "dmd-vs-smd",
        title: "Event-driven against standard MD: error against run time, efficiency, Lennard-Jones convergence",
        package: "dmd-sim",
        example: "validate_compare",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "terraced-mc",
        title: "Terraced dynamics against a Monte Carlo of the same terraced model",
        package: "dmd-sim",
        example: "validate_terraced_mc",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "frontier",
        title: "The error-against-cost frontier: DMD at several ΔV and level rules against SMD at several time steps, dense fluid, gas and SSD/E water",
        package: "dmd-sim",
        example: "validate_frontier",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "tune",
        title: "`dmd tune` on the shipped scenes: its recommendation run for real against a finer setting",
        package: "dmd-sim",
        example: "validate_tune",
        full: &[],
        quick: &["--quick"],
    },
    Check {
        name: "smd",
        title: "Standard MD reference: energy against time step and cost, reversibility, stability, Lennard-Jones against its equation of state",
        package: "dmd-smd",
        example: "validate_smd",
        full: &[],
        quick: &["--quick"],
    },
];

pub(crate) fn run(args: &[String]) -> Result<(), String> {
    let quick = args.iter().any(|a| a == "--quick");
    if args.iter().any(|a| a == "--list") {
        for c in CHECKS {
            println!("{:<24} {}", c.name, c.title);
        }
        return Ok(());
    }
    let only = crate::parse_only(args)?;
    if let Some(names) = &only {
        for n in names {
            if !CHECKS.iter().any(|c| c.name == n) {
                return Err(format!(
                    "no validation named `{n}` (see `cargo xtask validate --list`)"
                ));
            }
        }
    }
    let selected: Vec<&Check> = CHECKS
        .iter()
        .filter(|c| only.as_ref().is_none_or(|o| o.iter().any(|n| n == c.name)))
        .collect();

    let root = workspace_root();
    let (doc_path, figures) = if quick {
        let dir = root.join("target/validate-quick");
        (dir.join("VALIDATION.md"), dir.join("figures"))
    } else {
        (root.join("docs/VALIDATION.md"), root.join("docs/figures"))
    };
    std::fs::create_dir_all(&figures).map_err(|e| format!("{}: {e}", figures.display()))?;

    let stamp = provenance(&root, quick);
    let mut failed = Vec::new();
    for check in selected {
        eprintln!("==> validate {}", check.name);
        let (ok, fragment) = run_check(&root, check, quick, &figures)?;
        if !ok {
            failed.push(check.name);
        }
        let body = format!("{stamp}\n\n{}", fragment.trim());
        let doc = std::fs::read_to_string(&doc_path).unwrap_or_else(|_| {
            "# Validation\n\nGenerated sections are rewritten by `cargo xtask validate`.\n"
                .to_owned()
        });
        let doc = splice(&doc, check.name, check.title, &body)?;
        write_atomically(&doc_path, &doc)?;
    }
    eprintln!("==> report written to {}", doc_path.display());
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!("validation failed: {}", failed.join(", ")))
    }
}

/// Runs one check; returns whether it passed and the Markdown it printed.
fn run_check(
    root: &Path,
    check: &Check,
    quick: bool,
    figures: &Path,
) -> Result<(bool, String), String> {
    let args = if quick { check.quick } else { check.full };
    let output = Command::new("cargo")
        .current_dir(root)
        .args(["run", "--quiet", "--release", "--package", check.package])
        .args(validation_feature(check.example))
        .args(["--example", check.example, "--"])
        .args(args)
        .arg("--figures")
        .arg(figures)
        .stderr(std::process::Stdio::inherit())
        .output()
        .map_err(|e| format!("could not start cargo for `{}`: {e}", check.name))?;
    let text = String::from_utf8(output.stdout)
        .map_err(|_| format!("`{}` printed invalid UTF-8", check.name))?;
    if !output.status.success() {
        eprintln!("!!! {} FAILED ({})", check.name, output.status);
    }
    Ok((output.status.success(), text))
}

/// The `validate_*` examples are built only with their crate's `validation` feature, which
/// keeps them out of `cargo test`'s build; the other checked examples need no feature.
fn validation_feature(example: &str) -> &'static [&'static str] {
    if example.starts_with("validate_") {
        &["--features", "validation"]
    } else {
        &[]
    }
}

/// One line saying when, from which commit and in which mode a section was generated.
fn provenance(root: &Path, quick: bool) -> String {
    let capture = |prog: &str, args: &[&str]| -> String {
        Command::new(prog)
            .current_dir(root)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
            .unwrap_or_else(|| "unknown".to_owned())
    };
    let date = capture("date", &["-u", "+%Y-%m-%d"]);
    let rev = capture("git", &["rev-parse", "--short", "HEAD"]);
    let dirty = if capture("git", &["status", "--porcelain"]).is_empty() {
        ""
    } else {
        "+changes"
    };
    let mode = if quick { "quick" } else { "full" };
    format!(
        "_Generated by `cargo xtask validate` ({mode} run) on {date} at commit {rev}{dirty}; \
         do not edit by hand._"
    )
}

fn write_atomically(path: &Path, text: &str) -> Result<(), String> {
    let tmp: PathBuf = path.with_extension("md.tmp");
    std::fs::write(&tmp, text).map_err(|e| format!("{}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, path).map_err(|e| format!("{}: {e}", path.display()))
}
