//! Fuzz targets that run on stable Rust: a seeded mutation loop over real inputs (the shipped
//! scenes, the bad-scene corpus, its start files, checkpoints of real runs) for the five ways
//! text or bytes enter `dmd` — the scene parser and checker, `--set KEY=VALUE`, the XYZ and the
//! GSD start file, the checkpoint reader with its resume checks. Mutations are those a user or a damaged
//! disk makes: byte flips, truncations, huge or non-finite numbers put in place of numbers,
//! deleted, duplicated and swapped lines, lines spliced from another input.
//!
//! What counts as a finding: a panic, an input that takes more than [`SLOW`], an error message
//! whose first line is longer than [`LONGEST_LINE`] (messages quote at most a line), and for
//! checkpoints an exit status of `dmd resume` other than 0, 1 or 2 (no abort, no panic).
//! Findings are written to `$CARGO_TARGET_TMPDIR/fuzz-findings/` and fail the test.
//!
//! Each target runs `DMD_FUZZ_SECONDS` seconds (1 by default, so `cargo test` tries every seed
//! input and hundreds to thousands of mutations of them) from seed `DMD_FUZZ_SEED` (fixed by
//! default, so a failure repeats); `cargo xtask fuzz --minutes M` runs them longer with a fresh
//! seed and prints how many inputs each tried.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use rand::{Rng as _, SeedableRng};
use rand_xoshiro::SplitMix64;

use dmd_sim::checkpoint::{self, Every};
use dmd_sim::init;
use dmd_sim::run::{Quiet, RunError, run_scene};
use dmd_sim::scene::Scene;

use crate::support::{self, options, run_text};

/// An input slower than this is a finding (a hang, or work out of proportion to the input).
const SLOW: Duration = Duration::from_secs(20);
/// The longest first line of an error message that is not a finding.
const LONGEST_LINE: usize = 1500;

/// SplitMix64: small, seedable, and the same on every platform.
struct Rng(SplitMix64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0.next_u64()
    }

    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }

    fn pick<'a, T>(&mut self, xs: &'a [T]) -> &'a T {
        &xs[self.below(xs.len())]
    }
}

/// Numbers that break arithmetic: beyond every range, non-finite, subnormal, at integer limits.
const HUGE: &[&str] = &[
    "1e308",
    "-1e308",
    "1e309",
    "inf",
    "-inf",
    "nan",
    "18446744073709551615",
    "18446744073709551616",
    "9223372036854775807",
    "-9223372036854775808",
    "4294967295",
    "4294967296",
    "65536",
    "1e20",
    "1e12",
    "1e-320",
    "5e-324",
    "1e-300",
    "0",
    "-0.0",
    "-1",
    "0.5",
    "99999999999999999999999999999",
];

/// Values of other types, for a key's value.
const VALUES: &[&str] = &[
    "\"\"",
    "\"x\"",
    "[]",
    "{}",
    "true",
    "[[1.0, inf]]",
    "[1, 2]",
    "[1e308, 1e308, 1e308]",
    "\"fcc\"",
    "{ interval = 1e-9 }",
];

/// Structure characters inserted into text.
const INSERTS: &[&[u8]] = &[
    b"[",
    b"]",
    b"=",
    b"\"",
    b"{",
    b"\n[[species]]\n",
    b"\n[run]\n",
    b"#",
    b",",
    b"\n",
    b" ",
];

/// Varints of postcard (lengths and counts) near 2^64 and 2^32.
const HUGE_VARINTS: &[&[u8]] = &[
    &[0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01],
    &[0xff, 0xff, 0xff, 0xff, 0x0f],
    &[0x80, 0x80, 0x80, 0x80, 0x01],
];

/// The fuzzing budget of one target and the seed of its generator.
fn budget(target: &str) -> (Duration, u64) {
    let seconds = std::env::var("DMD_FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0)
        .unwrap_or(1.0);
    let seed = std::env::var("DMD_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .unwrap_or(20);
    let salt = target.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    (Duration::from_secs_f64(seconds), seed ^ salt)
}

/// Spans of number-like tokens (digits with signs, dots and exponents) in `text`.
fn number_spans(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut k = 0;
    while k < text.len() {
        if text[k].is_ascii_digit() {
            let mut a = k;
            while a > 0 && matches!(text[a - 1], b'-' | b'+' | b'.') {
                a -= 1;
            }
            let mut b = k;
            while b < text.len()
                && matches!(text[b], b'0'..=b'9' | b'.' | b'e' | b'E' | b'-' | b'+')
            {
                b += 1;
            }
            spans.push((a, b));
            k = b;
        } else {
            k += 1;
        }
    }
    spans
}

fn lines(text: &[u8]) -> Vec<Vec<u8>> {
    text.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect()
}

fn join(lines: &[Vec<u8>]) -> Vec<u8> {
    lines.join(&b'\n')
}

/// One to four mutations of a text input; `others` are inputs to splice lines from.
fn mutate_text(rng: &mut Rng, input: &[u8], others: &[Vec<u8>]) -> Vec<u8> {
    let mut x = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        match rng.below(11) {
            // A huge or odd number in place of a number.
            0..=2 => {
                let spans = number_spans(&x);
                if !spans.is_empty() {
                    let (a, b) = *rng.pick(&spans);
                    x.splice(a..b, rng.pick(HUGE).bytes());
                }
            }
            // A key deleted (a whole line).
            3 => {
                let mut l = lines(&x);
                let k = rng.below(l.len());
                l.remove(k);
                x = join(&l);
            }
            // A line duplicated, or two swapped.
            4 => {
                let mut l = lines(&x);
                let (a, b) = (rng.below(l.len()), rng.below(l.len()));
                if rng.below(2) == 0 {
                    let dup = l[a].clone();
                    l.insert(b, dup);
                } else {
                    l.swap(a, b);
                }
                x = join(&l);
            }
            // A value of another type after an `=`.
            5 => {
                let mut l = lines(&x);
                let k = rng.below(l.len());
                if let Some(eq) = l[k].iter().position(|&c| c == b'=') {
                    l[k].truncate(eq + 1);
                    l[k].push(b' ');
                    l[k].extend_from_slice(rng.pick(VALUES).as_bytes());
                }
                x = join(&l);
            }
            // Truncated.
            6 => {
                let k = rng.below(x.len() + 1);
                x.truncate(k);
            }
            // Bytes flipped.
            7 => {
                for _ in 0..1 + rng.below(3) {
                    if !x.is_empty() {
                        let k = rng.below(x.len());
                        x[k] ^= 1 << rng.below(8);
                    }
                }
            }
            // A line of another input spliced in.
            8 => {
                if !others.is_empty() {
                    let other: &Vec<u8> = rng.pick(others);
                    let o = lines(other);
                    let line = rng.pick(&o).clone();
                    let mut l = lines(&x);
                    let k = rng.below(l.len() + 1);
                    l.insert(k, line);
                    x = join(&l);
                }
            }
            // Structure characters inserted.
            9 => {
                let k = rng.below(x.len() + 1);
                let s = *rng.pick::<&[u8]>(INSERTS);
                x.splice(k..k, s.iter().copied());
            }
            // A long run of one character (long lines, long numbers).
            _ => {
                let k = rng.below(x.len() + 1);
                let c = *rng.pick(b"9ax ");
                let n = [10, 1000, 100_000][rng.below(3)];
                x.splice(k..k, std::iter::repeat_n(c, n));
            }
        }
    }
    x
}

/// A finding's description for a panic payload.
fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".to_owned())
}

/// An error message's first line must be short (a message quotes at most a line of input).
fn message_ok(message: &str) -> Result<(), String> {
    let first = message.lines().next().unwrap_or("");
    if first.chars().count() > LONGEST_LINE {
        Err(format!(
            "a message of {} characters: {}…",
            first.chars().count(),
            first.chars().take(200).collect::<String>()
        ))
    } else {
        Ok(())
    }
}

/// The mutation loop: mutates a random seed input with `mutate` and calls `check` on it until
/// the target's budget is spent; asserts that nothing was found. Returns the inputs tried.
fn fuzz(
    target: &str,
    seeds: &[Vec<u8>],
    mut mutate: impl FnMut(&mut Rng, &[u8]) -> Vec<u8>,
    mut check: impl FnMut(&[u8]) -> Result<(), String>,
) -> u64 {
    assert!(!seeds.is_empty(), "{target}: no seed inputs");
    let (budget, seed) = budget(target);
    let mut rng = Rng(SplitMix64::seed_from_u64(seed));
    let findings_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-findings");
    let start = Instant::now();
    let mut tried = 0u64;
    let mut findings = Vec::new();
    // The seeds themselves first, then mutations.
    let mut k = 0;
    while k < seeds.len() || start.elapsed() < budget {
        let input = if k < seeds.len() {
            k += 1;
            seeds[k - 1].clone()
        } else {
            let base = rng.below(seeds.len());
            mutate(&mut rng, &seeds[base])
        };
        let t = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| check(&input)));
        tried += 1;
        let finding = match outcome {
            Err(p) => Some(format!("panic: {}", panic_text(p.as_ref()))),
            Ok(Err(m)) => Some(m),
            Ok(Ok(())) if t.elapsed() > SLOW => Some(format!("took {:?}", t.elapsed())),
            Ok(Ok(())) => None,
        };
        if let Some(f) = finding {
            std::fs::create_dir_all(&findings_dir).unwrap();
            let file = findings_dir.join(format!("{target}-{seed:016x}-{tried}"));
            std::fs::write(&file, &input).unwrap();
            findings.push(format!("{}: {f}", file.display()));
            if findings.len() >= 5 {
                break;
            }
        }
    }
    println!(
        "fuzz {target}: {tried} inputs in {:.1} s (seed {}), {} findings",
        start.elapsed().as_secs_f64(),
        std::env::var("DMD_FUZZ_SEED").unwrap_or_else(|_| "20".into()),
        findings.len()
    );
    assert!(findings.is_empty(), "{target}:\n{}", findings.join("\n"));
    tried
}

fn read_all(dir: &Path, ext: &str) -> Vec<Vec<u8>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    files.sort();
    files.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-scenes")
}

/// The shipped scenes and the bad-scene corpus.
fn scene_seeds() -> Vec<Vec<u8>> {
    let mut seeds = read_all(&support::scenes_dir(), "toml");
    seeds.extend(read_all(&corpus_dir(), "toml"));
    seeds
}

/// Reads and checks a scene as `dmd check` does; an error must be short.
fn check_scene(text: &str, overrides: &[String]) -> Result<(), String> {
    match Scene::from_str_with(text, overrides) {
        Ok(_) => Ok(()),
        Err(e) => message_ok(&e.to_string()),
    }
}

#[test]
fn fuzz_scene_parser_and_checker() {
    let seeds = scene_seeds();
    let others = seeds.clone();
    fuzz(
        "scene",
        &seeds,
        |rng, s| mutate_text(rng, s, &others),
        |input| check_scene(&String::from_utf8_lossy(input), &[]),
    );
}

/// Every dotted key of a scene document (`run.events`, `species.0.count`).
fn keys(prefix: &str, v: &toml::Value, out: &mut Vec<String>) {
    match v {
        toml::Value::Table(t) => {
            for (k, x) in t {
                let p = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                out.push(p.clone());
                keys(&p, x, out);
            }
        }
        toml::Value::Array(a) => {
            for (k, x) in a.iter().enumerate() {
                if x.is_table() {
                    keys(&format!("{prefix}.{k}"), x, out);
                }
            }
        }
        _ => {}
    }
}

#[test]
fn fuzz_set_overrides() {
    // Inputs are a shipped scene's index, then overrides one per line.
    let scenes: Vec<String> = read_all(&support::scenes_dir(), "toml")
        .into_iter()
        .map(|b| String::from_utf8(b).unwrap())
        .collect();
    let all_keys: Vec<Vec<String>> = scenes
        .iter()
        .map(|t| {
            let mut k = Vec::new();
            keys("", &toml::Value::Table(t.parse().unwrap()), &mut k);
            k
        })
        .collect();
    let seeds: Vec<Vec<u8>> = (0..scenes.len())
        .map(|k| format!("{k}\nrun.events=100").into_bytes())
        .collect();
    fuzz(
        "set",
        &seeds,
        |rng, s| {
            let text = String::from_utf8_lossy(s);
            let scene = text.lines().next().unwrap_or("0").to_owned();
            let k: usize = scene.parse().unwrap_or(0) % scenes.len();
            let mut out = vec![k.to_string()];
            for _ in 0..1 + rng.below(3) {
                let key = if rng.below(8) == 0 {
                    // A key that is not quite one.
                    let base = rng.pick(&all_keys[k]).clone();
                    [
                        format!("{base}."),
                        format!(".{base}"),
                        format!("{base}.9999999999999999999999"),
                        format!("{base}.0.x"),
                        base.replace('.', ".."),
                        format!("{base}x"),
                        String::new(),
                    ][rng.below(7)]
                    .clone()
                } else {
                    rng.pick(&all_keys[k]).clone()
                };
                let value = match rng.below(6) {
                    0 => String::new(),
                    1 | 2 => (*rng.pick(HUGE)).to_owned(),
                    3 => (*rng.pick(VALUES)).to_owned(),
                    4 => String::from_utf8_lossy(&mutate_text(
                        rng,
                        b"[[1.0, inf], [1.5, -1.0]]",
                        &[],
                    ))
                    .into_owned(),
                    _ => "x".repeat([1, 100, 10_000][rng.below(3)]),
                };
                out.push(match rng.below(12) {
                    0 => format!("{key}{value}"),
                    1 => format!("{key}=={value}"),
                    _ => format!("{key}={value}"),
                });
            }
            let mutated = out.join("\n").into_bytes();
            if rng.below(4) == 0 {
                // Byte-level damage of the arguments too (the first line stays the index).
                let body = mutate_text(rng, &mutated, &[]);
                let mut v = format!("{k}\n").into_bytes();
                v.extend(body.splitn(2, |&b| b == b'\n').nth(1).unwrap_or(&[]));
                v
            } else {
                mutated
            }
        },
        |input| {
            let text = String::from_utf8_lossy(input);
            let mut l = text.lines();
            let k: usize = l.next().and_then(|s| s.parse().ok()).unwrap_or(0) % scenes.len();
            let overrides: Vec<String> = l.map(str::to_owned).collect();
            check_scene(&scenes[k], &overrides)
        },
    );
}

/// Scenes that read their start from `start.xyz`: spheres with velocities from the file, and
/// rods with orientations and velocities from it.
const XYZ_SPHERES: &str = r#"
version = 1
[box]
lengths = [6.0, 6.0, 6.0]
[[species]]
name = "A"
count = 4
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf], [1.5, -1.0]]
[init]
positions = "file"
file = "start.xyz"
velocities = "file"
temperature = 1.0
[run]
events = 50
"#;

const XYZ_RODS: &str = r#"
version = 1
[box]
lengths = [6.0, 6.0, 6.0]
[[species]]
name = "rod"
count = 4
mass = 1.0
inertia = 0.007
[[pair]]
species = ["rod", "rod"]
potential = { kind = "rods", epsilon = 1.0, sigma = 1.0, zeta = 0.33 }
terraces = { step_kt = 0.5 }
[init]
positions = "file"
file = "start.xyz"
orientations = "file"
velocities = "file"
temperature = 1.4
[run]
events = 50
"#;

#[test]
fn fuzz_xyz_start_file() {
    let dir = support::scratch("fuzz-xyz");
    let mut seeds = read_all(&corpus_dir(), "xyz");
    // A start file with every column a rod's start reads.
    seeds.push(
        b"4\nLattice=\"6 0 0 0 6 0 0 0 6\" Properties=species:S:1:pos:R:3:velo:R:3:\
orientation:R:4:omega:R:3:masses:R:1:id:I:1 Time=0\n\
rod 1.0 1.0 1.0 0.1 0.0 0.0 0 0 0 1 0 1 0 1 0\n\
rod 3.0 1.0 1.0 -0.1 0.0 0.0 0 0 0 1 1 0 0 1 1\n\
rod 1.0 3.0 1.0 0.0 0.1 0.0 0 0 0 1 0 0 1 1 2\n\
rod 1.0 1.0 3.0 0.0 -0.1 0.0 0 0 0 1 0 1 1 1 3\n"
            .to_vec(),
    );
    let spheres = Scene::from_str_with(XYZ_SPHERES, &[]).unwrap();
    let rods = Scene::from_str_with(XYZ_RODS, &[]).unwrap();
    let others = seeds.clone();
    let mut count = 0u64;
    fuzz(
        "xyz",
        &seeds,
        |rng, s| mutate_text(rng, s, &others),
        |input| {
            count += 1;
            let file = dir.join("start.xyz");
            std::fs::write(&file, input).map_err(|e| e.to_string())?;
            // Every reader of a start file, then (for spheres always, for rods now and then:
            // their set-up builds terrace tables) the whole set-up and a few events.
            let rod_names = String::from_utf8_lossy(input).contains("rod");
            let scene = if rod_names { &rods } else { &spheres };
            let mut messages = Vec::new();
            match init::read_xyz(scene, &file) {
                Ok(c) => {
                    let masses = vec![1.0; c.positions.len()];
                    let moments = vec![[1.0, 1.0, 0.0]; c.positions.len()];
                    if let Err(e) =
                        init::read_motion(scene, &file, &masses, rod_names.then_some(&moments[..]))
                    {
                        messages.push(e.to_string());
                    }
                }
                Err(e) => messages.push(e.to_string()),
            }
            if rod_names && let Err(e) = init::read_orientations(scene, &file, 4) {
                messages.push(e.to_string());
            }
            if (!rod_names || count.is_multiple_of(25))
                && let Err(e) = run_scene(scene, &dir, None, &mut Quiet)
            {
                messages.push(e.to_string());
            }
            messages.iter().try_for_each(|m| message_ok(m))
        },
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// One to three mutations of a GSD file: flipped bits, 4-byte words set to special numbers
/// (NaN, infinities, huge and negative values, as `f32` and as integers), or a cut-off tail.
fn mutate_gsd(rng: &mut Rng, input: &[u8]) -> Vec<u8> {
    let mut x = input.to_vec();
    let specials: [u32; 9] = [
        f32::NAN.to_bits(),
        f32::INFINITY.to_bits(),
        f32::MAX.to_bits(),
        (-1.0f32).to_bits(),
        1e30f32.to_bits(),
        0,
        u32::MAX,
        7,
        1 << 31,
    ];
    for _ in 0..1 + rng.below(3) {
        let n = x.len();
        if n < 8 {
            break;
        }
        let at = rng.below(n - 4);
        match rng.below(6) {
            0 | 1 => x[at] ^= 1 << rng.below(8),
            2..=4 => x[at..at + 4].copy_from_slice(&rng.pick(&specials).to_le_bytes()),
            _ => x.truncate(at),
        }
    }
    x
}

#[test]
fn fuzz_gsd_start_file() {
    let dir = support::scratch("fuzz-gsd");
    let mut seeds = read_all(&corpus_dir(), "gsd");
    // A rods' frame with every chunk a start reads, written by the `gsd` crate.
    let rods = dir.join("rods-seed.gsd");
    let mut w = gsd::Writer::create(&rods, "dmd").unwrap();
    let frame = gsd::Frame {
        sim_box: gsd::SimBox::cubic(6.0),
        position: vec![
            [1.0, 1.0, 1.0],
            [-1.0, 1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, -1.0],
        ],
        orientation: Some(vec![[0.5, 0.5, 0.5, 0.5]; 4]),
        velocity: Some(vec![[0.1, 0.0, -0.1]; 4]),
        angmom: Some(vec![[0.0, 0.01, -0.02, 0.0]; 4]),
        image: Some(vec![[0, 1, -1]; 4]),
        typeid: vec![0; 4],
        types: vec!["rod".into()],
        ..gsd::Frame::default()
    };
    w.append(&frame).unwrap();
    w.finish().unwrap();
    seeds.push(std::fs::read(&rods).unwrap());
    let on_gsd =
        |text: &str| Scene::from_str_with(&text.replace("start.xyz", "start.gsd"), &[]).unwrap();
    let (spheres, rod_scene) = (on_gsd(XYZ_SPHERES), on_gsd(XYZ_RODS));
    let mut count = 0u64;
    fuzz("gsd", &seeds, mutate_gsd, |input| {
        count += 1;
        let file = dir.join("start.gsd");
        std::fs::write(&file, input).map_err(|e| e.to_string())?;
        // Every reader of a start file, with each scene; now and then the whole set-up.
        let mut messages = Vec::new();
        for scene in [&spheres, &rod_scene] {
            match init::read_xyz(scene, &file) {
                Ok(c) => {
                    let masses = vec![1.0; c.positions.len()];
                    let moments = vec![[0.007, 0.007, 0.0]; c.positions.len()];
                    if let Err(e) = init::read_motion(scene, &file, &masses, Some(&moments)) {
                        messages.push(e.to_string());
                    }
                    if let Err(e) = init::read_orientations(scene, &file, c.positions.len()) {
                        messages.push(e.to_string());
                    }
                }
                Err(e) => messages.push(e.to_string()),
            }
        }
        if count.is_multiple_of(10)
            && let Err(e) = run_scene(&spheres, &dir, None, &mut Quiet)
        {
            messages.push(e.to_string());
        }
        messages.iter().try_for_each(|m| message_ok(m))
    });
    let _ = std::fs::remove_dir_all(dir);
}

/// Small runs whose checkpoints seed the checkpoint target: a square well with every output
/// and a thermostat, hard spheres, and a hybrid Monte Carlo chain.
const CK_SCENES: &[&str] = &[
    r#"
version = 1
seed = 5
[box]
density = 0.5
[[species]]
name = "A"
count = 108
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf], [1.5, -1.0]]
[init]
positions = "fcc"
temperature = 1.5
[thermostat]
kind = "andersen"
rate = 1.0
during = "equilibration"
[run]
equilibration_events = 600
events = 2500
rebase_events = 500
[output]
sample_interval = 0.05
rdf = { bins = 20, every = 2 }
msd = { max_lag = 0.3 }
vacf = { max_lag = 0.3 }
series = true
plots = false
"#,
    r#"
version = 1
[box]
density = 0.6
[[species]]
name = "A"
count = 32
[[pair]]
species = ["A", "A"]
steps = [[1.0, inf]]
[init]
positions = "fcc"
temperature = 1.0
[run]
events = 1500
rebase_events = 500
"#,
    r#"
version = 1
seed = 3
[box]
density = 0.3
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
equilibration_events = 200
[hmc]
segment_time = 0.2
segments = 6
equilibration_segments = 1
"#,
];

/// The payload of checkpoint bytes made whole again after an edit: the length field set to
/// what follows and the CRC recomputed, as a forger would.
pub(crate) fn reseal(bytes: &mut [u8]) {
    if bytes.len() < 26 {
        return;
    }
    let version_len = u16::from_le_bytes([bytes[24], bytes[25]]) as usize;
    let payload = bytes.len().saturating_sub(26 + version_len) as u64;
    bytes[16..24].copy_from_slice(&payload.to_le_bytes());
    let crc = checkpoint::crc32(&bytes[16..]);
    bytes[12..16].copy_from_slice(&crc.to_le_bytes());
}

/// Real checkpoints: each scene above halted at its first checkpoint.
fn checkpoint_seeds(dir: &Path) -> Vec<Vec<u8>> {
    let mut seeds = Vec::new();
    for (k, text) in CK_SCENES.iter().enumerate() {
        for every in [Every::Events(100), Every::Events(900)] {
            let out = dir.join(format!("seed-{k}-{every:?}"));
            let _ = std::fs::remove_dir_all(&out);
            std::fs::create_dir_all(&out).unwrap();
            let r = run_text(text, &[], &out, &options(text, &[], Some(every), true));
            match (r, std::fs::read(out.join(checkpoint::FILE_NAME))) {
                (Err(RunError::Halted), Ok(b)) => seeds.push(b),
                (r, _) => panic!("seed run {k} every {every:?}: {:?}", r.err()),
            }
        }
    }
    seeds
}

/// Mutations of checkpoint bytes: mostly of the payload with the header made consistent again
/// (the CRC and length recomputed), now and then of the header itself.
fn mutate_checkpoint(rng: &mut Rng, input: &[u8]) -> Vec<u8> {
    let mut x = input.to_vec();
    let head = 26 + u16::from_le_bytes([x[24], x[25]]) as usize;
    let specials: [u64; 10] = [
        f64::NAN.to_bits(),
        f64::INFINITY.to_bits(),
        f64::MAX.to_bits(),
        1e300f64.to_bits(),
        (-1e300f64).to_bits(),
        1e-300f64.to_bits(),
        0,
        u64::MAX,
        1e9f64.to_bits(),
        (-1.0f64).to_bits(),
    ];
    for _ in 0..1 + rng.below(3) {
        let n = x.len();
        if n <= head + 8 {
            break;
        }
        let at = head + rng.below(n - head - 8);
        match rng.below(8) {
            0 | 1 => x[at] ^= 1 << rng.below(8),
            2 | 3 => {
                let v = *rng.pick(&specials);
                x[at..at + 8].copy_from_slice(&v.to_le_bytes());
            }
            // A varint (a length or a count) made huge.
            4 => {
                let huge = *rng.pick::<&[u8]>(HUGE_VARINTS);
                x.splice(at..at + 1, huge.iter().copied());
            }
            5 => x.truncate(at),
            6 => {
                let len = 1 + rng.below(16);
                let fill = (rng.next() & 0xff) as u8;
                x.splice(at..at, std::iter::repeat_n(fill, len));
            }
            _ => {
                let len = (1 + rng.below(64)).min(n - at);
                x.drain(at..at + len);
            }
        }
    }
    match rng.below(10) {
        // The header: a length of 2^64 − 1, a version length beyond the file, a byte flipped.
        0 => {
            x[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
            let crc = checkpoint::crc32(&x[16..]);
            x[12..16].copy_from_slice(&crc.to_le_bytes());
        }
        1 => {
            let k = rng.below(head.min(x.len()));
            x[k] ^= 1 << rng.below(8);
        }
        _ => reseal(&mut x),
    }
    x
}

#[test]
fn fuzz_checkpoint_reader() {
    let dir = support::scratch("fuzz-checkpoint");
    let seeds = checkpoint_seeds(&dir);

    let exe = env!("CARGO_BIN_EXE_dmd");
    let mut decoded = 0u64;
    let tried = fuzz("checkpoint", &seeds, mutate_checkpoint, |input| {
        // The reader in this process (every input), then `dmd resume` on the inputs that
        // decode: the state checks, the run, the exit status.
        let c = match checkpoint::decode(input) {
            Ok(c) => c,
            Err(e) => return message_ok(&e.to_string()),
        };
        decoded += 1;
        let case = dir.join("case");
        let _ = std::fs::remove_dir_all(&case);
        std::fs::create_dir_all(&case).map_err(|e| e.to_string())?;
        let file = case.join(checkpoint::FILE_NAME);
        std::fs::write(&file, input).map_err(|e| e.to_string())?;
        let _ = c;
        let mut child = Command::new(exe)
            .args(["resume", "--quiet"])
            .arg(&file)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| e.to_string())?;
        let t = Instant::now();
        loop {
            if let Some(status) = child.try_wait().map_err(|e| e.to_string())? {
                let mut err = String::new();
                if let Some(mut s) = child.stderr.take() {
                    use std::io::Read;
                    let _ = s.read_to_string(&mut err);
                }
                return match status.code() {
                    Some(0..=2) => message_ok(&err),
                    code => Err(format!("dmd resume exited with {code:?}: {err}")),
                };
            }
            if t.elapsed() > SLOW {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!("dmd resume still ran after {SLOW:?}"));
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    });
    println!("fuzz checkpoint: {decoded} of {tried} inputs decoded and went to dmd resume");
    let _ = std::fs::remove_dir_all(dir);
}
