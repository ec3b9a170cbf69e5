//! The output folder of `dmd run`, checked before the run starts: it must be a folder that can
//! be created and written, and it must not hold another run's files (which a new run would mix
//! with its own: a stale `trajectory.xyz` or `checkpoint.dmd` next to a new `summary.json`).
//!
//! Only files `dmd` writes are ever removed ([`is_dmd_file`]): `*.partial` files left by an
//! interrupted run at the start of every run, and with `--force` the previous run's outputs.

use std::path::{Path, PathBuf};

/// Every name `dmd` writes into an output folder (the job folders of chains and sweeps,
/// `point-P` and `chain-C`, hold the same names).
pub const FILES: &[&str] = &[
    "summary.json",
    "checkpoint.dmd",
    "trajectory.xyz",
    "trajectory.gsd",
    "rdf.csv",
    "rdf.svg",
    "rdf-sites.csv",
    "rdf-sites.svg",
    "msd.csv",
    "msd.svg",
    "vacf.csv",
    "vacf.svg",
    "oacf.csv",
    "oacf.svg",
    "series.csv",
    "series-energy.svg",
    "series-pressure.svg",
    "hmc.csv",
    "ensemble.json",
    "ensemble.csv",
    crate::driver::chains::SOURCE_FILE,
];

/// Why an output folder cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum OutDirError {
    /// It exists and is not a folder.
    #[error("--out {}: exists and is not a folder", .0.display())]
    NotAFolder(PathBuf),
    /// It cannot be created or written.
    #[error("--out {}: cannot {what}: {message}", path.display())]
    Unwritable {
        /// The folder.
        path: PathBuf,
        /// `create the folder` or `write into the folder`.
        what: &'static str,
        /// The system's reason.
        message: String,
    },
    /// It holds another run's files.
    #[error(
        "--out {}: holds the files of another run ({}): use --force to replace them, or \
         `dmd resume` to continue that run",
        path.display(),
        files.join(", ")
    )]
    Occupied {
        /// The folder.
        path: PathBuf,
        /// The files found (at most a few named).
        files: Vec<String>,
    },
}

/// Whether `name` is a file `dmd` writes: one of [`FILES`], or one of them with `.partial`
/// appended (written, then renamed when complete).
pub fn is_dmd_file(name: &str) -> bool {
    let base = name.strip_suffix(".partial").unwrap_or(name);
    FILES.contains(&base)
}

/// Whether `name` is a job folder of chains or a sweep (`point-3`, `chain-0`).
fn is_job_folder(name: &str) -> bool {
    ["point-", "chain-"].iter().any(|p| {
        name.strip_prefix(p)
            .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
    })
}

/// The run's files in `dir`, recursively through job folders (paths relative to `dir`);
/// `partial` selects the `*.partial` files or the others. A job folder counts only if it holds
/// nothing but such files and folders, so that nothing else is ever removed.
fn dmd_files(dir: &Path, partial: bool) -> std::io::Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(std::fs::DirEntry::file_name);
    for e in entries {
        let name = e.file_name();
        let Some(name) = name.to_str() else { continue };
        let kind = e.file_type()?;
        if kind.is_file() && is_dmd_file(name) && name.ends_with(".partial") == partial {
            found.push(PathBuf::from(name));
        } else if kind.is_dir() && is_job_folder(name) && only_dmd_files(&e.path())? {
            for f in dmd_files(&e.path(), partial)? {
                found.push(Path::new(name).join(f));
            }
        }
    }
    Ok(found)
}

/// Whether a folder holds nothing but `dmd`'s files and job folders.
fn only_dmd_files(dir: &Path) -> std::io::Result<bool> {
    for e in std::fs::read_dir(dir)? {
        let e = e?;
        let name = e.file_name();
        let Some(name) = name.to_str() else {
            return Ok(false);
        };
        let kind = e.file_type()?;
        let ours = (kind.is_file() && is_dmd_file(name))
            || (kind.is_dir() && is_job_folder(name) && only_dmd_files(&e.path())?);
        if !ours {
            return Ok(false);
        }
    }
    Ok(true)
}

/// Removes `files` (relative to `dir`) and then the job folders they leave empty.
fn remove(dir: &Path, files: &[PathBuf]) -> std::io::Result<()> {
    for f in files {
        std::fs::remove_file(dir.join(f))?;
    }
    let mut folders: Vec<PathBuf> = files
        .iter()
        .filter_map(|f| f.parent().map(Path::to_owned))
        .collect();
    // Deepest first, so that `point-0/chain-1` goes before `point-0`.
    folders.sort_by_key(|f| std::cmp::Reverse(f.components().count()));
    folders.dedup();
    for f in folders.iter().filter(|f| !f.as_os_str().is_empty()) {
        for a in f.ancestors().filter(|a| !a.as_os_str().is_empty()) {
            // Only empty folders go (`remove_dir` refuses others).
            let _ = std::fs::remove_dir(dir.join(a));
        }
    }
    Ok(())
}

/// Prepares `dir` for a new run: creates it if missing, checks that it is writable, removes
/// stale `*.partial` files of `dmd`, and refuses it if it holds another run's files unless
/// `force`, in which case they are removed (only `dmd`'s own names: [`FILES`]). Returns the
/// files removed.
///
/// # Errors
/// [`OutDirError`], before anything is written.
pub fn prepare(dir: &Path, force: bool) -> Result<Vec<PathBuf>, OutDirError> {
    check_writable(dir)?;
    let unwritable = |e: std::io::Error| OutDirError::Unwritable {
        path: dir.to_owned(),
        what: "clean the folder",
        message: e.to_string(),
    };
    let mut removed = dmd_files(dir, true).map_err(unwritable)?;
    remove(dir, &removed).map_err(unwritable)?;
    let previous = dmd_files(dir, false).map_err(unwritable)?;
    if !previous.is_empty() {
        if !force {
            let mut files: Vec<String> = previous
                .iter()
                .take(4)
                .map(|p| p.display().to_string())
                .collect();
            if previous.len() > 4 {
                files.push(format!("and {} more", previous.len() - 4));
            }
            return Err(OutDirError::Occupied {
                path: dir.to_owned(),
                files,
            });
        }
        remove(dir, &previous).map_err(unwritable)?;
        removed.extend(previous);
    }
    Ok(removed)
}

/// Checks that `dir` is a folder (created if missing) that can be written into.
///
/// # Errors
/// [`OutDirError::NotAFolder`], [`OutDirError::Unwritable`].
pub fn check_writable(dir: &Path) -> Result<(), OutDirError> {
    if dir.exists() && !dir.is_dir() {
        return Err(OutDirError::NotAFolder(dir.to_owned()));
    }
    std::fs::create_dir_all(dir).map_err(|e| OutDirError::Unwritable {
        path: dir.to_owned(),
        what: "create the folder",
        message: e.to_string(),
    })?;
    // A probe file under a name dmd never uses otherwise, removed at once.
    let probe = dir.join(format!(".dmd-write-test-{}.partial", std::process::id()));
    let written = std::fs::write(&probe, b"dmd");
    let _ = std::fs::remove_file(&probe);
    written.map_err(|e| OutDirError::Unwritable {
        path: dir.to_owned(),
        what: "write into the folder",
        message: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_dmd_files_are_cleaned_and_replaced() {
        let d = std::env::temp_dir().join(format!("dmd-outdir-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        // A fresh folder is created.
        assert!(prepare(&d, false).unwrap().is_empty());
        // Stale temporary files of dmd go; a user's file stays.
        std::fs::write(d.join("series.csv.partial"), "x").unwrap();
        std::fs::write(d.join("notes.txt"), "mine").unwrap();
        std::fs::write(d.join("notes.txt.partial"), "mine").unwrap();
        assert_eq!(
            prepare(&d, false).unwrap(),
            vec![PathBuf::from("series.csv.partial")]
        );
        assert!(d.join("notes.txt.partial").exists());
        // Another run's files: refused, then replaced with force (job folders too).
        std::fs::write(d.join("summary.json"), "{}").unwrap();
        std::fs::create_dir_all(d.join("point-0/chain-1")).unwrap();
        std::fs::write(d.join("point-0/chain-1/checkpoint.dmd"), "x").unwrap();
        std::fs::create_dir_all(d.join("point-1")).unwrap();
        std::fs::write(d.join("point-1/summary.json"), "x").unwrap();
        std::fs::write(d.join("point-1/mine.txt"), "x").unwrap();
        let e = prepare(&d, false).unwrap_err().to_string();
        assert!(
            e.ends_with(
                "holds the files of another run (point-0/chain-1/checkpoint.dmd, summary.json): \
                 use --force to replace them, or `dmd resume` to continue that run"
            ),
            "{e}"
        );
        prepare(&d, true).unwrap();
        assert!(!d.join("summary.json").exists() && !d.join("point-0").exists());
        // A job folder holding a user's file is left alone.
        assert!(d.join("point-1/summary.json").exists() && d.join("notes.txt").exists());
        std::fs::remove_dir_all(&d).unwrap();
        // A file is not a folder.
        let f = std::env::temp_dir().join(format!("dmd-outdir-file-{}", std::process::id()));
        std::fs::write(&f, "x").unwrap();
        assert!(matches!(prepare(&f, true), Err(OutDirError::NotAFolder(_))));
        std::fs::remove_file(&f).unwrap();
    }
}
