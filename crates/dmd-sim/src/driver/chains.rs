//! Independent chains and parameter sweeps of one scene, run in parallel.
//!
//! A scene with `[chains] count = C` and/or `[sweep] key = "…", values = [v₀, v₁, …]` is a set
//! of **jobs**: for every sweep point `p` (the key set to `v_p`, as `--set` would) and every
//! chain `c`, the scene with `seed` replaced by a seed derived from the scene's seed and `c`
//! alone (so chain `c` of every point shares its random numbers: differences between points
//! are smoother). Each job is an ordinary single-threaded run writing its own folder
//! (`DIR/point-P/chain-C/`); rayon runs the jobs on a pool of the requested size, and the
//! results are put in job order, so **the results do not depend on the number of threads**
//! (each job is deterministic, and nothing is shared between jobs).
//!
//! The aggregate (`DIR/ensemble.json`, `DIR/ensemble.csv`) gives per point and quantity the
//! mean over chains, its standard error from the scatter between chains (independent runs, so
//! the plain `s/√C`, with `C ≥ 2`), and, for the HMC chain averages, the block-average error
//! of each chain combined over chains (`√Σσ_c² / C`): two estimates that must agree.
//!
//! `DIR/ensemble-source.json` records the scene (text, overrides) and the checkpoint interval,
//! so that [`resume_ensemble`] (`dmd resume DIR`) can finish an interrupted ensemble: finished
//! jobs (those with a `summary.json`) are read back, interrupted ones resumed from their
//! checkpoint, jobs never started are run; the aggregate is the one an uninterrupted run gives.
//!
//! The same steps serve a scheduler that runs the jobs elsewhere (the Python package's Dask
//! ensembles): [`start_ensemble`] prepares the folder, [`run_or_resume_job`] runs, resumes or
//! reads back job `k` of the recorded ensemble in any process that sees the folder, and
//! [`write_aggregate`] aggregates the jobs' `summary.json` files with [`aggregate`], as
//! `dmd run` does.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use serde::Serialize;

use crate::analysis::output::{OutputError, write_atomically, write_csv};
use crate::config::scene::{Scene, SceneError};
use crate::driver::checkpoint::{self, Every, SceneSource};
use crate::driver::run::{Quiet, RunError, RunOptions, Summary, run_scene_with};

/// One run of an ensemble.
#[derive(Clone, Debug)]
pub struct Job {
    /// Sweep point.
    pub point: usize,
    /// Chain.
    pub chain: usize,
    /// The overrides that make its scene from the scene text.
    pub overrides: Vec<String>,
    /// Its scene.
    pub scene: Scene,
    /// Its folder, relative to the output folder.
    pub dir: PathBuf,
}

/// The seed of chain `c` of a scene seeded `seed` (SplitMix64 of both: chains differ in every
/// bit, and chain `c` is the same at every sweep point).
pub fn chain_seed(seed: u64, c: u64) -> u64 {
    let mut z = seed ^ (c.wrapping_add(1)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)) >> 1
}

/// The jobs of a scene read from `text` with `overrides`.
///
/// # Errors
/// The [`SceneError`] of a point (under `sweep.values[k]`).
pub fn jobs(scene: &Scene, text: &str, overrides: &[String]) -> Result<Vec<Job>, SceneError> {
    let points = scene.sweep.as_ref().map_or(1, |s| s.values.len());
    let chains = scene.chains.as_ref().map_or(1, |c| c.count as usize);
    let mut out = Vec::with_capacity(points * chains);
    for p in 0..points {
        let point = scene.sweep_point(text, overrides, p)?;
        for c in 0..chains {
            let mut o = overrides.to_vec();
            if let Some(sw) = &scene.sweep {
                o.push(format!("{}={}", sw.key, sw.values[p]));
                o.push("sweep=".to_owned());
            }
            if scene.chains.is_some() {
                o.push("chains=".to_owned());
                o.push(format!("seed={}", chain_seed(point.seed, c as u64)));
            }
            let job_scene = Scene::from_str_with(text, &o)?;
            let mut dir = PathBuf::new();
            if scene.sweep.is_some() {
                dir.push(format!("point-{p}"));
            }
            if scene.chains.is_some() {
                dir.push(format!("chain-{c}"));
            }
            out.push(Job {
                point: p,
                chain: c,
                overrides: o,
                scene: job_scene,
                dir,
            });
        }
    }
    Ok(out)
}

/// Mean and errors of one quantity at one point.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Estimate {
    /// Mean over chains.
    pub mean: f64,
    /// Standard error from the scatter between chains (`null` with one chain).
    pub error: Option<f64>,
    /// The chains' own block-average errors combined, `√Σσ²/C` (quantities whose summary
    /// has an `_error`, when every chain has one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub block_error: Option<f64>,
    /// Each chain's value.
    pub values: Vec<f64>,
}

/// One sweep point of the aggregate.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Point {
    /// The swept value (as TOML text), if a sweep.
    pub value: Option<String>,
    /// Quantities by name.
    pub quantities: std::collections::BTreeMap<String, Estimate>,
}

/// `ensemble.json`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Ensemble {
    /// The swept key, if any.
    pub key: Option<String>,
    /// Chains per point.
    pub chains: usize,
    /// The points.
    pub points: Vec<Point>,
    /// Job folders, in job order.
    pub jobs: Vec<String>,
}

/// Summary fields aggregated (dotted paths into `summary.json`), and the path of each job's own
/// block-average error of it where the summary has one.
const QUANTITIES: &[(&str, Option<&str>)] = &[
    ("temperature", Some("temperature_error")),
    (
        "translational_temperature",
        Some("translational_temperature_error"),
    ),
    (
        "rotational_temperature",
        Some("rotational_temperature_error"),
    ),
    ("pressure", Some("pressure_error")),
    ("compressibility", None),
    (
        "potential_energy_per_body",
        Some("potential_energy_per_body_error"),
    ),
    (
        "potential_energy_per_body_smooth",
        Some("potential_energy_per_body_smooth_error"),
    ),
    ("pressure_smooth", Some("pressure_smooth_error")),
    ("collision_rate", None),
    ("mean_free_time", None),
    ("diffusion_msd", Some("diffusion_msd_error")),
    ("diffusion_vacf", Some("diffusion_vacf_error")),
    ("hmc.acceptance_rate", None),
    ("hmc.exp_minus_beta_delta_h", None),
    (
        "hmc.potential_energy_per_body.mean",
        Some("hmc.potential_energy_per_body.error"),
    ),
    (
        "hmc.kinetic_energy_per_body.mean",
        Some("hmc.kinetic_energy_per_body.error"),
    ),
];

fn field(v: &serde_json::Value, path: &str) -> Option<f64> {
    path.split('.')
        .try_fold(v, |v, k| v.get(k))
        .and_then(serde_json::Value::as_f64)
}

/// Aggregates the summaries of `jobs` (in job order, as `summary.json` values).
pub fn aggregate(scene: &Scene, jobs: &[Job], values: &[serde_json::Value]) -> Ensemble {
    let points = scene.sweep.as_ref().map_or(1, |s| s.values.len());
    let chains = scene.chains.as_ref().map_or(1, |c| c.count as usize);
    let mut out = Vec::with_capacity(points);
    for p in 0..points {
        let of_point: Vec<&serde_json::Value> = jobs
            .iter()
            .zip(values)
            .filter(|(j, _)| j.point == p)
            .map(|(_, v)| v)
            .collect();
        let mut quantities = std::collections::BTreeMap::new();
        for &(name, block) in QUANTITIES {
            let xs: Vec<f64> = of_point.iter().filter_map(|v| field(v, name)).collect();
            if xs.len() != of_point.len() || xs.is_empty() {
                continue;
            }
            let n = xs.len() as f64;
            let mean = xs.iter().sum::<f64>() / n;
            let error = (xs.len() >= 2).then(|| {
                let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
                (var / n).sqrt()
            });
            let block_error = block.and_then(|b| {
                let es: Vec<f64> = of_point.iter().filter_map(|v| field(v, b)).collect();
                (es.len() == xs.len()).then(|| es.iter().map(|e| e * e).sum::<f64>().sqrt() / n)
            });
            quantities.insert(
                name.to_owned(),
                Estimate {
                    mean,
                    error,
                    block_error,
                    values: xs,
                },
            );
        }
        out.push(Point {
            value: scene.sweep.as_ref().map(|s| s.values[p].to_string()),
            quantities,
        });
    }
    Ensemble {
        key: scene.sweep.as_ref().map(|s| s.key.clone()),
        chains,
        points: out,
        jobs: jobs
            .iter()
            .map(|j| j.dir.to_string_lossy().into_owned())
            .collect(),
    }
}

/// Runs every job of a scene on `threads` threads (all cores if `None`), each into its folder
/// under `out` (with checkpoints every `every`), and writes `ensemble.json` and `ensemble.csv`.
/// `done(finished, total)` is called as jobs finish (from worker threads).
///
/// # Errors
/// The first failing job's [`RunError`] (the others still run and write their folders), a
/// scene error of a point, or an output error.
pub fn run_ensemble(
    scene: &Scene,
    source: &SceneSource,
    out: &Path,
    threads: Option<usize>,
    every: Option<Every>,
    done: &(dyn Fn(usize, usize) + Sync),
) -> Result<Ensemble, RunError> {
    run_jobs(scene, source, out, threads, every, false, false, done)
}

/// [`run_ensemble`] with every job stopped right after its first checkpoint, as a crash would
/// leave them (tests of [`resume_ensemble`]); returns the first job's [`RunError::Halted`].
///
/// # Errors
/// As [`run_ensemble`].
pub fn run_ensemble_halting(
    scene: &Scene,
    source: &SceneSource,
    out: &Path,
    threads: Option<usize>,
    every: Every,
) -> Result<Ensemble, RunError> {
    run_jobs(
        scene,
        source,
        out,
        threads,
        Some(every),
        false,
        true,
        &|_, _| {},
    )
}

/// What `ensemble-source.json` holds.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct EnsembleSource {
    source: SceneSource,
    every: Option<Every>,
}

/// The file recording an ensemble's scene in its folder.
pub const SOURCE_FILE: &str = "ensemble-source.json";

/// Finishes the ensemble in `out` (see the module documentation).
///
/// # Errors
/// [`RunError`]: a missing or unreadable `ensemble-source.json`, its scene, a job's failure.
pub fn resume_ensemble(
    out: &Path,
    threads: Option<usize>,
    done: &(dyn Fn(usize, usize) + Sync),
) -> Result<Ensemble, RunError> {
    let r = read_ensemble(out)?;
    run_jobs(
        &r.scene, &r.source, out, threads, r.every, true, false, done,
    )
}

/// How [`run_or_resume_job`] found a job.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JobStart {
    /// Nothing saved: run from its start.
    Fresh,
    /// Interrupted: continued from its checkpoint.
    Resumed,
    /// Finished: its `summary.json` read back.
    Finished,
}

impl JobStart {
    /// `"fresh"`, `"resumed"` or `"finished"`.
    pub fn name(self) -> &'static str {
        match self {
            JobStart::Fresh => "fresh",
            JobStart::Resumed => "resumed",
            JobStart::Finished => "finished",
        }
    }
}

/// An ensemble as recorded in its folder by [`start_ensemble`].
#[derive(Clone, Debug)]
pub struct Recorded {
    /// The scene.
    pub scene: Scene,
    /// Its text, overrides and base folder.
    pub source: SceneSource,
    /// The jobs' checkpoint interval.
    pub every: Option<Every>,
    /// The jobs, in job order.
    pub jobs: Vec<Job>,
}

/// Prepares `out` for the jobs of `scene` (creates it and records the scene and the checkpoint
/// interval in [`SOURCE_FILE`]) without running any; returns the jobs in job order.
///
/// # Errors
/// The [`SceneError`] of a point, or an output error.
pub fn start_ensemble(
    scene: &Scene,
    source: &SceneSource,
    out: &Path,
    every: Option<Every>,
) -> Result<Vec<Job>, RunError> {
    let jobs = jobs(scene, &source.text, &source.overrides)?;
    std::fs::create_dir_all(out).map_err(|e| OutputError {
        path: out.to_owned(),
        message: e.to_string(),
    })?;
    let record = EnsembleSource {
        source: source.clone(),
        every,
    };
    let json = serde_json::to_string_pretty(&record).expect("a record serialises");
    write_atomically(&out.join(SOURCE_FILE), json.as_bytes())?;
    Ok(jobs)
}

/// The ensemble recorded in `out` by [`start_ensemble`] (or `dmd run`).
///
/// # Errors
/// A missing or unreadable [`SOURCE_FILE`], or a scene that no longer reads.
pub fn read_ensemble(out: &Path) -> Result<Recorded, RunError> {
    let path = out.join(SOURCE_FILE);
    let bad = |m: String| -> RunError {
        checkpoint::CheckpointError {
            path: path.clone(),
            problem: checkpoint::Problem::Inconsistent(m),
        }
        .into()
    };
    let text = std::fs::read_to_string(&path).map_err(|e| bad(format!("cannot read it: {e}")))?;
    let e: EnsembleSource =
        serde_json::from_str(&text).map_err(|e| bad(format!("not an ensemble record: {e}")))?;
    let scene = Scene::from_str_with(&e.source.text, &e.source.overrides)
        .map_err(|x| bad(format!("its scene no longer reads: {x}")))?;
    let jobs = jobs(&scene, &e.source.text, &e.source.overrides)?;
    Ok(Recorded {
        scene,
        source: e.source,
        every: e.every,
        jobs,
    })
}

/// Job `k` of the ensemble recorded in `out`, whatever state its folder is in: a finished job's
/// `summary.json` is read back, an interrupted one continues from its checkpoint (bit for bit),
/// one never started runs. Returns its summary (as `summary.json`) and how it was found.
///
/// One process at a time may run a job: two would write the same files (their temporary
/// names included).
///
/// # Errors
/// [`RunError::Job`] naming the job (an unknown `k` included), or the record's error.
pub fn run_or_resume_job(out: &Path, k: usize) -> Result<(serde_json::Value, JobStart), RunError> {
    let r = read_ensemble(out)?;
    let Some(j) = r.jobs.get(k) else {
        return Err(RunError::Job {
            job: format!("#{k}"),
            source: Box::new(
                OutputError {
                    path: out.to_owned(),
                    message: format!("the ensemble has {} jobs", r.jobs.len()),
                }
                .into(),
            ),
        });
    };
    let dir = out.join(&j.dir);
    let start = if dir.join("summary.json").exists() {
        JobStart::Finished
    } else if dir.join(checkpoint::FILE_NAME).exists() {
        JobStart::Resumed
    } else {
        JobStart::Fresh
    };
    run_job(j, &r.source, out, r.every, true, false)
        .map(|v| (v, start))
        .map_err(|e| RunError::Job {
            job: j.dir.display().to_string(),
            source: Box::new(e),
        })
}

/// Aggregates the finished jobs of the ensemble recorded in `out` (their `summary.json`) and
/// writes `ensemble.json` and `ensemble.csv`, as `dmd run` does after running them.
///
/// # Errors
/// The record's error, or [`RunError::Job`] for a job without a readable summary.
pub fn write_aggregate(out: &Path) -> Result<Ensemble, RunError> {
    let r = read_ensemble(out)?;
    let mut summaries = Vec::with_capacity(r.jobs.len());
    for j in &r.jobs {
        let path = out.join(&j.dir).join("summary.json");
        let read = std::fs::read_to_string(&path)
            .map_err(|e| e.to_string())
            .and_then(|t| {
                serde_json::from_str::<serde_json::Value>(&t)
                    .map_err(|e| format!("not a summary: {e}"))
            });
        match read {
            Ok(v) => summaries.push(v),
            Err(message) => {
                return Err(RunError::Job {
                    job: j.dir.display().to_string(),
                    source: Box::new(OutputError { path, message }.into()),
                });
            }
        }
    }
    finish(&r.scene, &r.jobs, &summaries, out)
}

/// Aggregates `summaries` (in job order) and writes `ensemble.json` and `ensemble.csv`.
fn finish(
    scene: &Scene,
    jobs: &[Job],
    summaries: &[serde_json::Value],
    out: &Path,
) -> Result<Ensemble, RunError> {
    let ensemble = aggregate(scene, jobs, summaries);
    let json = serde_json::to_string_pretty(&ensemble).expect("an ensemble serialises");
    write_atomically(&out.join("ensemble.json"), json.as_bytes())?;
    write_table(&out.join("ensemble.csv"), &ensemble)?;
    Ok(ensemble)
}

/// Runs (or, with `resume`, finishes) every job; `halt` stops each after its first
/// checkpoint (tests).
#[allow(clippy::too_many_arguments)]
fn run_jobs(
    scene: &Scene,
    source: &SceneSource,
    out: &Path,
    threads: Option<usize>,
    every: Option<Every>,
    resume: bool,
    halt: bool,
    done: &(dyn Fn(usize, usize) + Sync),
) -> Result<Ensemble, RunError> {
    let jobs = if resume {
        jobs(scene, &source.text, &source.overrides)?
    } else {
        start_ensemble(scene, source, out, every)?
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| OutputError {
            path: out.to_owned(),
            message: format!("cannot start the worker threads: {e}"),
        })?;
    let finished = AtomicUsize::new(0);
    let total = jobs.len();
    let results: Vec<Result<serde_json::Value, RunError>> = pool.install(|| {
        jobs.par_iter()
            .map(|j| {
                let r = run_job(j, source, out, every, resume, halt);
                done(finished.fetch_add(1, Ordering::Relaxed) + 1, total);
                r
            })
            .collect()
    });
    let mut summaries = Vec::with_capacity(total);
    for (j, r) in jobs.iter().zip(results) {
        match r {
            Ok(s) => summaries.push(s),
            Err(e) => {
                return Err(RunError::Job {
                    job: j.dir.display().to_string(),
                    source: Box::new(e),
                });
            }
        }
    }
    finish(scene, &jobs, &summaries, out)
}

/// One job: with `resume`, a finished job's `summary.json` is read back and an interrupted
/// one continued from its checkpoint.
fn run_job(
    j: &Job,
    source: &SceneSource,
    out: &Path,
    every: Option<Every>,
    resume: bool,
    halt: bool,
) -> Result<serde_json::Value, RunError> {
    let dir = out.join(&j.dir);
    let summary = dir.join("summary.json");
    let checkpoint_file = dir.join(checkpoint::FILE_NAME);
    let json = |s: Summary| serde_json::to_value(s).expect("a summary serialises");
    if resume && summary.exists() {
        let text = std::fs::read_to_string(&summary).map_err(|e| OutputError {
            path: summary.clone(),
            message: e.to_string(),
        })?;
        return serde_json::from_str(&text).map_err(|e| {
            OutputError {
                path: summary.clone(),
                message: format!("not a summary: {e}"),
            }
            .into()
        });
    }
    let mut options = RunOptions {
        checkpoint_every: every,
        source: Some(SceneSource {
            overrides: j.overrides.clone(),
            ..source.clone()
        }),
        resume: None,
        halt_after_checkpoint: halt,
    };
    if resume && checkpoint_file.exists() {
        let c = checkpoint::read(&checkpoint_file)?;
        options.source = None;
        options.resume = Some((checkpoint_file, c));
    }
    run_scene_with(&j.scene, &source.base, Some(&dir), &mut Quiet, &options).map(json)
}

/// `ensemble.csv`: per point the swept value (its index if not a number) and the mean and
/// error of each quantity present at every point.
fn write_table(path: &Path, e: &Ensemble) -> Result<(), OutputError> {
    let names: Vec<&String> = e.points[0]
        .quantities
        .keys()
        .filter(|k| e.points.iter().all(|p| p.quantities.contains_key(*k)))
        .collect();
    let mut header = vec!["point".to_owned(), "value".to_owned()];
    for n in &names {
        header.push((*n).clone());
        header.push(format!("{n}_error"));
        header.push(format!("{n}_block_error"));
    }
    let rows: Vec<Vec<f64>> = e
        .points
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut row = vec![
                k as f64,
                p.value
                    .as_deref()
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(f64::NAN),
            ];
            for n in &names {
                let q = &p.quantities[*n];
                row.push(q.mean);
                row.push(q.error.unwrap_or(f64::NAN));
                row.push(q.block_error.unwrap_or(f64::NAN));
            }
            row
        })
        .collect();
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    write_csv(path, &header, &rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chain_seeds_differ_and_are_non_negative_toml_integers() {
        let s: Vec<u64> = (0..100).map(|c| chain_seed(1, c)).collect();
        for (k, a) in s.iter().enumerate() {
            assert!(*a < 1 << 63, "TOML integers are signed 64-bit");
            assert!(!s[..k].contains(a));
        }
        assert_ne!(chain_seed(1, 0), chain_seed(2, 0));
    }
}
