//! Checkpoints: a run saved to a file and continued bit for bit by `dmd resume`.
//!
//! **When.** A plain run is saved at a re-basing of the time origin (see
//! [`simulation::SimState`](crate::engine::simulation::SimState) for why that continues bit for bit):
//! the loop pauses at every re-basing (every `run.rebase_events` events, 10⁶ or more by
//! default) and a checkpoint is written there once the interval asked for
//! (`--checkpoint-every`, in events or wall-clock time) has passed. A hybrid Monte Carlo run is
//! saved between segments. Saving never changes the trajectory: a run with checkpoints gives
//! the same bits as one without.
//!
//! **What.** The scene's text and overrides (the scene is read again from them), the stage of
//! the run and what is left of it, the loop's [`SimState`], the accumulators of the outputs
//! (observables, the trajectory file's length), the HMC chain with its generator, and the run's
//! reference values (energy and momentum at the start of production, time spent).
//!
//! **Format.** A header, then the [postcard](https://docs.rs/postcard) encoding of
//! [`Checkpoint`]:
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `\x89DMD-CK\n` (the high byte and the newline catch text-mode mangling) |
//! | 4 | format version, little endian ([`FORMAT_VERSION`]) |
//! | 4 | CRC-32 (IEEE) of everything after this field |
//! | 8 | payload length, little endian |
//! | 2 + n | length and UTF-8 text of the `dmd` version that wrote it |
//! | payload | postcard |
//!
//! Reading checks, in this order: the magic (not a checkpoint), the format version (a layout
//! this `dmd` cannot read), the length (truncated), the CRC (corrupted), the code version (a
//! different `dmd` would not continue bit for bit), the decoding and the fit of the state to
//! the scene. Each gets its own message; nothing is written before all of them pass. Files are
//! written to a temporary name and renamed, so a crash while saving leaves the previous
//! checkpoint whole.

use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::analysis::observable::{Correlations, Rdf, SeriesState};
use crate::analysis::output::{OutputError, write_atomically};
use crate::driver::hmc::Chain;
use crate::engine::simulation::SimState;
use crate::models::search::SearchStats;

/// First bytes of every checkpoint.
pub const MAGIC: &[u8; 8] = b"\x89DMD-CK\n";
/// The layout version this `dmd` writes and reads.
pub const FORMAT_VERSION: u32 = 8;
/// The `dmd` version written into checkpoints.
pub const CODE_VERSION: &str = env!("CARGO_PKG_VERSION");
/// The checkpoint's file name in the output folder.
pub const FILE_NAME: &str = "checkpoint.dmd";

/// A checkpoint that cannot be used.
#[derive(Debug, thiserror::Error)]
#[error("checkpoint {path}: {problem}")]
pub struct CheckpointError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong.
    pub problem: Problem,
}

/// What is wrong with a checkpoint.
#[derive(Debug, thiserror::Error)]
pub enum Problem {
    /// It cannot be read.
    #[error("cannot read it: {0}")]
    Io(std::io::Error),
    /// It does not start with the magic bytes.
    #[error("not a dmd checkpoint (it does not start with the checkpoint signature)")]
    NotACheckpoint,
    /// It is shorter than its header says.
    #[error("truncated: {got} bytes, the header announces {expected}")]
    Truncated {
        /// Bytes the header announces.
        expected: u64,
        /// Bytes present.
        got: u64,
    },
    /// Its CRC does not match (or bytes follow the payload).
    #[error("corrupted: {0}")]
    Corrupted(String),
    /// Written in another layout.
    #[error("format version {found}, this dmd reads version {FORMAT_VERSION}")]
    FormatVersion {
        /// The file's version.
        found: u32,
    },
    /// Written by another version of `dmd`.
    #[error(
        "written by dmd {found}, this is dmd {CODE_VERSION}: another version would not continue \
         the run bit for bit; resume it with dmd {found}"
    )]
    CodeVersion {
        /// The version that wrote it.
        found: String,
    },
    /// Its scene or state does not fit (or does not decode).
    #[error("{0}")]
    Inconsistent(String),
}

/// How often a checkpoint is written.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Every {
    /// After at least this many events since the last one (at the next re-basing or segment end).
    Events(u64),
    /// After at least this much wall-clock time, in seconds.
    Seconds(f64),
}

impl Every {
    /// Reads `1e7` (events), or `90s`, `10m`, `2h` (wall-clock time).
    ///
    /// # Errors
    /// A message naming the value.
    pub fn parse(text: &str) -> Result<Self, String> {
        let t = text.trim();
        let bad = || {
            format!(
                "`{text}` is not an interval: give a number of events (1e7) or a wall-clock \
                 time (90s, 10m, 2h)"
            )
        };
        let (num, unit) = match t.char_indices().last() {
            Some((k, c @ ('s' | 'm' | 'h'))) => (&t[..k], Some(c)),
            _ => (t, None),
        };
        let x: f64 = num.parse().map_err(|_| bad())?;
        if !(x.is_finite() && x > 0.0) {
            return Err(bad());
        }
        Ok(match unit {
            None => {
                if x.fract() != 0.0 || x >= 1.8e19 {
                    return Err(bad());
                }
                Every::Events(x as u64)
            }
            Some(u) => {
                let seconds = x * match u {
                    's' => 1.0,
                    'm' => 60.0,
                    _ => 3600.0,
                };
                // A checked conversion: the interval is compared with elapsed `Duration`s.
                if Duration::try_from_secs_f64(seconds).is_err() {
                    return Err(format!(
                        "`{text}` is too long a wall-clock time: at most {}s (about {} years)",
                        crate::config::limits::short(Duration::MAX.as_secs_f64()),
                        crate::config::limits::short(Duration::MAX.as_secs_f64() / 31_557_600.0)
                    ));
                }
                Every::Seconds(seconds)
            }
        })
    }
}

/// The scene a checkpoint belongs to.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneSource {
    /// The scene file's text.
    pub text: String,
    /// `--set` overrides, in order.
    pub overrides: Vec<String>,
    /// The folder relative paths of the scene were read from.
    pub base: PathBuf,
    /// The scene file (for messages).
    pub file: PathBuf,
}

/// Where a run stands.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Stage {
    /// In equilibration with this much left.
    Equilibration(Left),
    /// In production with this much left.
    Production(Left),
}

/// What is left of a phase.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Left {
    /// Events.
    Events(u64),
    /// Simulated time.
    Time(f64),
    /// HMC segments.
    Segments(u64),
}

/// The run's values that outlive a phase.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Events of equilibration.
    pub equilibration_events: u64,
    /// Whether a thermostat acted in equilibration.
    pub had_thermostat: bool,
    /// Kinetic and total energy, momentum and momentum scale at the start of production.
    pub start: Option<(f64, f64, [f64; 3], f64)>,
    /// Wall-clock and CPU seconds of production before this process.
    pub seconds: (f64, f64),
    /// The model's search counters at the start of production (rods).
    pub search_start: Option<SearchStats>,
    /// Every count of the model's report at the start of production, by name.
    #[serde(default)]
    pub counts_start: std::collections::BTreeMap<String, u64>,
}

/// The accumulated observables.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ObserverState {
    /// g(r).
    pub rdf: Option<Rdf>,
    /// MSD and VACF.
    pub correlations: Option<Correlations>,
    /// The series: its rows are in `series.csv`, whose length it records.
    pub series: Option<SeriesState>,
    /// The trajectory's temporary file length and frames.
    pub trajectory: Option<(u64, u64)>,
    /// The GSD trajectory's frames.
    pub gsd: Option<u64>,
    /// The online accumulators of the summary's error bars and smooth estimators.
    pub samples: Option<crate::analysis::smooth::Samples>,
}

/// Everything needed to continue a run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The scene.
    pub source: SceneSource,
    /// The checkpoint interval.
    pub every: Option<Every>,
    /// Where the run stands.
    pub stage: Stage,
    /// The loop's state.
    pub sim: SimState,
    /// Run-level values.
    pub record: RunRecord,
    /// Observables.
    pub observers: ObserverState,
    /// The HMC chain.
    pub chain: Option<Chain>,
}

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320).
pub fn crc32(bytes: &[u8]) -> u32 {
    const fn table() -> [u32; 256] {
        let mut t = [0u32; 256];
        let mut i = 0;
        while i < 256 {
            let mut c = i as u32;
            let mut k = 0;
            while k < 8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
                k += 1;
            }
            t[i] = c;
            i += 1;
        }
        t
    }
    const TABLE: [u32; 256] = table();
    let mut c = !0u32;
    for &b in bytes {
        c = TABLE[((c ^ u32::from(b)) & 0xff) as usize] ^ (c >> 8);
    }
    !c
}

/// The bytes of a checkpoint as written by `code_version`.
pub fn encode_with_version(c: &Checkpoint, code_version: &str) -> Vec<u8> {
    let payload = postcard::to_allocvec(c).expect("a checkpoint serialises");
    let mut tail = Vec::with_capacity(payload.len() + 64);
    tail.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    tail.extend_from_slice(&(code_version.len() as u16).to_le_bytes());
    tail.extend_from_slice(code_version.as_bytes());
    tail.extend_from_slice(&payload);
    let mut out = Vec::with_capacity(tail.len() + 16);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&crc32(&tail).to_le_bytes());
    out.extend_from_slice(&tail);
    out
}

/// Writes a checkpoint atomically (temporary file, then rename).
///
/// # Errors
/// [`OutputError`] naming the file.
pub fn write(path: &Path, c: &Checkpoint) -> Result<(), OutputError> {
    write_atomically(path, &encode_with_version(c, CODE_VERSION))
}

/// Reads and checks a checkpoint (see the module documentation for the order of the checks).
///
/// # Errors
/// [`CheckpointError`] saying what is wrong.
pub fn read(path: &Path) -> Result<Checkpoint, CheckpointError> {
    let err = |problem| CheckpointError {
        path: path.to_owned(),
        problem,
    };
    let bytes = std::fs::read(path).map_err(|e| err(Problem::Io(e)))?;
    decode(&bytes).map_err(err)
}

/// Decodes checkpoint bytes.
///
/// # Errors
/// The [`Problem`].
pub fn decode(bytes: &[u8]) -> Result<Checkpoint, Problem> {
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(Problem::NotACheckpoint);
    }
    let fixed = 8 + 4 + 4 + 8 + 2;
    let truncated = |expected: u64| Problem::Truncated {
        expected,
        got: bytes.len() as u64,
    };
    if bytes.len() < 12 {
        return Err(truncated(fixed as u64));
    }
    let word = |k: usize| u32::from_le_bytes(bytes[k..k + 4].try_into().expect("4 bytes"));
    let format = word(8);
    if format != FORMAT_VERSION {
        return Err(Problem::FormatVersion { found: format });
    }
    if bytes.len() < fixed {
        return Err(truncated(fixed as u64));
    }
    let crc = word(12);
    let payload_len = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    let version_len = u16::from_le_bytes(bytes[24..26].try_into().expect("2 bytes")) as u64;
    // Checked: a forged length near 2^64 must not wrap around to a small one.
    let Some(expected) = (fixed as u64)
        .checked_add(version_len)
        .and_then(|x| x.checked_add(payload_len))
    else {
        return Err(Problem::Corrupted(format!(
            "its header announces a payload of {payload_len} bytes, more than any file holds"
        )));
    };
    if (bytes.len() as u64) < expected {
        return Err(truncated(expected));
    }
    if bytes.len() as u64 > expected {
        return Err(Problem::Corrupted(format!(
            "{} bytes follow the announced end",
            bytes.len() as u64 - expected
        )));
    }
    if crc32(&bytes[16..]) != crc {
        return Err(Problem::Corrupted(
            "its CRC-32 does not match its contents".into(),
        ));
    }
    let version_end = fixed + version_len as usize;
    let version = String::from_utf8_lossy(&bytes[fixed..version_end]).into_owned();
    if version != CODE_VERSION {
        return Err(Problem::CodeVersion { found: version });
    }
    postcard::from_bytes(&bytes[version_end..])
        .map_err(|e| Problem::Inconsistent(format!("its contents do not decode: {e}")))
}

/// Checks the accumulated observables of a checkpoint against fresh ones the scene gives
/// (`rdf`, `correlations`, the samples behind the error bars if `sampled`) for `n` bodies of
/// `species`: the same settings, arrays of the sizes
/// the settings give, time origins of the right length taken at past samples. The observables
/// keep their fields private; they are read through their serialised form (a field renamed
/// there fails the checkpoint tests).
///
/// # Errors
/// What does not fit.
pub fn check_observers(
    saved: &ObserverState,
    rdf: Option<&Rdf>,
    correlations: Option<&Correlations>,
    sampled: bool,
    species: &[u32],
    volume: f64,
) -> Result<(), String> {
    if saved.samples.is_some() != sampled {
        return Err("its samples do not match the scene's output.sample_interval".into());
    }
    if let Some(s) = &saved.samples {
        s.check()?;
    }
    use serde_json::Value;
    let n = species.len() as u64;
    let num = |v: &Value, k: &str| v.get(k).and_then(Value::as_u64);
    let len = |v: &Value, k: &str| v.get(k).and_then(Value::as_array).map(Vec::len);
    let same = |a: &Value, b: &Value, keys: &[&str]| keys.iter().all(|k| a.get(k) == b.get(k));
    if saved.rdf.is_some() != rdf.is_some() {
        return Err("its g(r) does not match the scene's output.rdf".into());
    }
    if let (Some(s), Some(f)) = (&saved.rdf, rdf) {
        let (s, f) = (json(s), json(f));
        let samples = num(&s, "samples").unwrap_or(u64::MAX);
        let bins = len(&f, "counts").unwrap_or(0);
        let members: Option<Vec<u64>> = s
            .get("members")
            .and_then(Value::as_array)
            .map(|m| m.iter().filter_map(Value::as_u64).collect());
        let kinds = species.iter().map(|&x| x as usize + 1).max().unwrap_or(0);
        let mut expected = vec![0u64; kinds];
        for &x in species {
            expected[x as usize] += 1;
        }
        let (members_ok, partial) = if samples == 0 {
            (members.as_ref().is_some_and(Vec::is_empty), 0)
        } else {
            (
                members.as_ref() == Some(&expected),
                if kinds >= 2 {
                    kinds * (kinds + 1) / 2 * bins
                } else {
                    0
                },
            )
        };
        let sampled_ok = samples == 0
            || (num(&s, "n") == Some(n) && s.get("volume").and_then(Value::as_f64) == Some(volume));
        // The site–site g(r): the same sites and bins, its arrays of the sizes they give.
        let sites = |v: &Value| {
            v.get("sites").filter(|x| !x.is_null()).map(|x| {
                (
                    ["species", "types", "r_max", "width", "bins"].map(|k| x.get(k).cloned()),
                    len(x, "counts"),
                    len(x, "blocks"),
                )
            })
        };
        let sites_ok = match (sites(&s), sites(&f)) {
            (Some((keys_s, counts, blocks)), Some((keys_f, fresh, _))) => {
                keys_s == keys_f && counts == fresh && blocks == fresh
            }
            (a, b) => a.is_none() && b.is_none(),
        };
        if !(same(&s, &f, &["every", "r_max", "width"])
            && len(&s, "counts") == Some(bins)
            && len(&s, "partial") == Some(partial)
            && len(&s, "partial_blocks") == Some(partial)
            && members_ok
            && sampled_ok
            && sites_ok
            && num(&s, "seen").is_some_and(|seen| seen >= samples))
        {
            return Err("its g(r) does not fit the scene's output.rdf and bodies".into());
        }
    }
    if saved.correlations.is_some() != correlations.is_some() {
        return Err(
            "its correlations do not match the scene's output.msd, vacf or \
                    orientation_acf"
                .into(),
        );
    }
    if let (Some(s), Some(f)) = (&saved.correlations, correlations) {
        let (s, f) = (json(s), json(f));
        let lags = len(&f, "counts");
        let samples = num(&s, "samples").unwrap_or(0);
        let arrays_ok = ["msd", "vacf", "oacf1", "oacf2", "counts"]
            .iter()
            .all(|k| len(&s, k) == lags);
        let origins_ok = s.get("origins").and_then(Value::as_array).is_some_and(|o| {
            o.iter().all(|o| {
                let l = |k: &str| len(o, k).map(|x| x as u64);
                num(o, "sample").is_some_and(|k| k < samples)
                    && l("r0") == Some(n)
                    && l("v0") == Some(n)
                    && matches!(l("s0"), Some(x) if x == 0 || x == n)
            })
        });
        if !(same(
            &s,
            &f,
            &[
                "dt",
                "lags",
                "origin_every",
                "want_msd",
                "want_vacf",
                "want_oacf",
            ],
        ) && arrays_ok
            && origins_ok)
        {
            return Err("its correlations do not fit the scene's outputs and bodies".into());
        }
    }
    Ok(())
}

/// A value's serialised form (`Null` if it has none).
fn json<T: Serialize>(x: &T) -> serde_json::Value {
    serde_json::to_value(x).unwrap_or(serde_json::Value::Null)
}

/// Decides when to save, and saves.
#[derive(Debug)]
pub struct Saver {
    /// The interval.
    pub every: Option<Every>,
    /// The file.
    pub path: Option<PathBuf>,
    /// The scene.
    pub source: Option<SceneSource>,
    events_at_last: u64,
    last: std::time::Instant,
    /// Checkpoints written by this process.
    pub written: u64,
    /// Seconds spent writing them.
    pub seconds: f64,
}

impl Saver {
    /// Saves into `dir/checkpoint.dmd` every `every` (nothing without an interval, a folder or
    /// the scene's source).
    /// With a folder and the source but no interval it saves only when a signal stops the run
    /// ([`crate::driver::interrupt`]).
    pub fn new(every: Option<Every>, dir: Option<&Path>, source: Option<SceneSource>) -> Self {
        let can = dir.is_some() && source.is_some();
        Saver {
            every: every.filter(|_| can),
            path: dir.filter(|_| can).map(|d| d.join(FILE_NAME)),
            source: source.filter(|_| can),
            events_at_last: 0,
            last: std::time::Instant::now(),
            written: 0,
            seconds: 0.0,
        }
    }

    /// Whether checkpoints are written from time to time.
    pub fn active(&self) -> bool {
        self.every.is_some()
    }

    /// Whether a checkpoint can be written (a folder and the scene's source are known).
    pub fn can_save(&self) -> bool {
        self.path.is_some() && self.source.is_some()
    }

    /// Whether one is due after `events` events in all.
    pub fn due(&mut self, events: u64) -> bool {
        match self.every {
            None => false,
            Some(Every::Events(n)) => events.saturating_sub(self.events_at_last) >= n,
            // `parse` refuses what does not fit a `Duration`; a saved interval that does not
            // (a corrupted checkpoint passes its CRC only by accident) never comes due.
            Some(Every::Seconds(s)) => {
                Duration::try_from_secs_f64(s).is_ok_and(|d| self.last.elapsed() >= d)
            }
        }
    }

    /// Writes `make()`'s checkpoint, counted at `events` events.
    ///
    /// # Errors
    /// [`OutputError`].
    pub fn save(
        &mut self,
        events: u64,
        make: impl FnOnce(SceneSource, Option<Every>) -> Result<Checkpoint, OutputError>,
    ) -> Result<(), OutputError> {
        let (Some(path), Some(source)) = (&self.path, &self.source) else {
            return Ok(());
        };
        let t = std::time::Instant::now();
        let c = make(source.clone(), self.every)?;
        write(path, &c)?;
        self.seconds += t.elapsed().as_secs_f64();
        self.written += 1;
        self.events_at_last = events;
        self.last = std::time::Instant::now();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_of_the_standard_check_string() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn intervals_in_events_and_wall_time() {
        assert_eq!(Every::parse("1e7"), Ok(Every::Events(10_000_000)));
        assert_eq!(Every::parse("250000"), Ok(Every::Events(250_000)));
        assert_eq!(Every::parse("90s"), Ok(Every::Seconds(90.0)));
        assert_eq!(Every::parse("10m"), Ok(Every::Seconds(600.0)));
        assert_eq!(Every::parse("1.5h"), Ok(Every::Seconds(5400.0)));
        for bad in [
            "", "m", "-5", "0", "1.5", "ten", "5d", "inf", "1e20s", "1e300h", "1e18m",
        ] {
            assert!(Every::parse(bad).is_err(), "{bad}");
        }
    }
}
