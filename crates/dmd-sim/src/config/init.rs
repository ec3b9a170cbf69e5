//! Initial configurations: lattices, files, and Maxwell–Boltzmann velocities.

use std::path::Path;

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::analysis::output::{ASE_VELOCITY_IN_A_PER_PS, short};
use crate::config::scene::{Positions, PotentialSpec, Scene, SceneError, UnitSystem};
use crate::engine::simulation::MAX_IMAGE;

/// Positions, species and box of the initial configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Configuration {
    /// Box edge lengths.
    pub lengths: DVec3,
    /// Positions.
    pub positions: Vec<DVec3>,
    /// Species index of each body.
    pub species: Vec<u32>,
    /// Nearest-neighbour distance of the lattice (`None` for a file).
    pub lattice_spacing: Option<f64>,
}

/// Sites of a lattice: unit-cell basis in fractions of the cell.
fn basis(kind: Positions) -> &'static [[f64; 3]] {
    match kind {
        Positions::Fcc => &[
            [0.25, 0.25, 0.25],
            [0.75, 0.75, 0.25],
            [0.75, 0.25, 0.75],
            [0.25, 0.75, 0.75],
        ],
        _ => &[[0.5, 0.5, 0.5]],
    }
}

/// The box of a scene that gives `density` (and `aspect`) or `lengths`.
pub fn box_lengths(scene: &Scene) -> Option<DVec3> {
    let n = scene.n_bodies() as f64;
    match (scene.box_.density, scene.box_.lengths) {
        (_, Some(l)) => Some(DVec3::from(l)),
        (Some(rho), None) => {
            let a = DVec3::from(scene.box_.aspect.unwrap_or([1.0; 3]));
            let volume = n / rho;
            let unit = (volume / (a.x * a.y * a.z)).cbrt();
            Some(a * unit)
        }
        (None, None) => None,
    }
}

/// Builds the lattice of a scene: unit cells per axis in proportion to the box edges, enough
/// sites for every body, bodies on the first sites in lattice order and species dealt in the
/// order the scene lists them, then shuffled over the sites with the scene's seed (so a
/// mixture is mixed).
///
/// # Errors
/// [`SceneError::Invalid`] naming `box.density` if neighbouring lattice sites are closer
/// than the smallest hard-core diameter (no species could sit on them).
pub fn lattice(scene: &Scene, smallest_core: f64) -> Result<Configuration, SceneError> {
    let lengths = box_lengths(scene).expect("a lattice scene has a box");
    let n = scene.n_bodies() as usize;
    let basis = basis(scene.init.positions);
    let cells_needed = n.div_ceil(basis.len()) as f64;
    // Unit cells per axis ∝ edge length, product ≥ cells needed.
    let scale = (cells_needed / (lengths.x * lengths.y * lengths.z)).cbrt();
    let mut k = [0usize; 3];
    for a in 0..3 {
        k[a] = ((lengths[a] * scale).round() as usize).max(1);
    }
    while k[0] * k[1] * k[2] < cells_needed as usize {
        // Grow the axis whose cells are widest.
        let a = (0..3)
            .max_by(|&x, &y| (lengths[x] / k[x] as f64).total_cmp(&(lengths[y] / k[y] as f64)))
            .unwrap_or(0);
        k[a] += 1;
    }
    let cell = DVec3::new(
        lengths.x / k[0] as f64,
        lengths.y / k[1] as f64,
        lengths.z / k[2] as f64,
    );
    let spacing = match scene.init.positions {
        Positions::Fcc => {
            // Nearest neighbours of an fcc lattice are half a face diagonal apart.
            let d = |a: usize, b: usize| 0.5 * (cell[a] * cell[a] + cell[b] * cell[b]).sqrt();
            d(0, 1).min(d(0, 2)).min(d(1, 2))
        }
        _ => cell.min_element(),
    };
    // Single-cell-thick axes: the periodic image along that axis is one cell away.
    let spacing = spacing.min(cell.min_element());
    if smallest_core > 0.0 && spacing < smallest_core {
        let name = match scene.init.positions {
            Positions::Fcc => "fcc",
            _ => "sc",
        };
        let rho = n as f64 / (lengths.x * lengths.y * lengths.z);
        // The nearest-neighbour distance of each lattice at this density with cubic cells,
        // every one filled: an fcc cell of side a holds 4 sites a/√2 apart, an sc cell one.
        let fcc_spacing = (4.0 / rho).cbrt() / std::f64::consts::SQRT_2;
        let cubic_spacing = match scene.init.positions {
            Positions::Fcc => fcc_spacing,
            _ => rho.cbrt().recip(),
        };
        let (key, lower) = if scene.box_.lengths.is_some() {
            ("box.lengths", "enlarge the box")
        } else {
            ("box.density", "lower the density")
        };
        let (key, advice) = if cubic_spacing >= smallest_core {
            // The lattice fits at this density: the box's shape, or cells left partly empty
            // by the count, squeeze it.
            let key = match (scene.box_.lengths, scene.box_.aspect) {
                (None, Some(a)) if a.iter().any(|&x| x != a[0]) => "box.aspect",
                _ => key,
            };
            (
                key,
                format!(
                    "the box holds {}×{}×{} cells of {}×{}×{}, not cubic or not all filled \
                     (with cubic cells, all filled, the sites would be {} apart): give box \
                     sides in proportion to whole numbers of cubic cells and a count that \
                     fills them, {lower}, or start from a file",
                    k[0],
                    k[1],
                    k[2],
                    short(cell.x),
                    short(cell.y),
                    short(cell.z),
                    short(cubic_spacing)
                ),
            )
        } else if scene.init.positions != Positions::Fcc && fcc_spacing >= smallest_core {
            (
                key,
                format!(
                    "{lower}, use an fcc lattice (its sites would be {} apart at this \
                     density), or start from a file",
                    short(fcc_spacing)
                ),
            )
        } else {
            // fcc is the densest packing of spheres: √2/d³ with its sites a diameter d apart.
            let densest = std::f64::consts::SQRT_2 / smallest_core.powi(3);
            (
                key,
                format!(
                    "no lattice holds cores of diameter {smallest_core} at this density (fcc, \
                     the densest, holds at most ρ = {}): {lower}, or start from a file",
                    short(densest)
                ),
            )
        };
        return Err(SceneError::invalid(
            key,
            format!(
                "density {rho:.6} is too high for an {name} lattice of {n} bodies: neighbouring \
                 sites are {spacing:.6} apart, less than the hard-core diameter {smallest_core}; \
                 {advice}"
            ),
        ));
    }
    let mut positions = Vec::with_capacity(n);
    'fill: for z in 0..k[2] {
        for y in 0..k[1] {
            for x in 0..k[0] {
                for b in basis {
                    if positions.len() == n {
                        break 'fill;
                    }
                    let f = DVec3::new(x as f64 + b[0], y as f64 + b[1], z as f64 + b[2]);
                    positions.push(f * cell);
                }
            }
        }
    }
    let mut species: Vec<u32> = scene
        .species
        .iter()
        .enumerate()
        .flat_map(|(s, sp)| std::iter::repeat_n(s as u32, sp.count as usize))
        .collect();
    if scene.species.len() > 1 {
        // Fisher–Yates with the scene's seed (a stream apart from the velocities').
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(scene.seed ^ 0x5eed_5eed_0000_0001);
        for i in (1..species.len()).rev() {
            let j = rng.random_range(0..=i);
            species.swap(i, j);
        }
    }
    Ok(Configuration {
        lengths,
        positions,
        species,
        lattice_spacing: Some(spacing),
    })
}

/// How errors name a start file: as the scene gives it (`init.file`), else its path.
fn shown(scene: &Scene, path: &Path) -> String {
    scene
        .init
        .file
        .as_ref()
        .map_or(path, |f| f.as_path())
        .display()
        .to_string()
}

/// One frame of an XYZ file: its comment line and its rows, split into words, each with its
/// line number in the file (from 1), in body order: by the `id:I:1` column when the frame has
/// one (`dmd` writes it), else as they stand.
struct XyzFrame<'a> {
    comment: &'a str,
    rows: Vec<(usize, Vec<&'a str>)>,
}

/// Frame `index` of `text` (0 the first, −1 the last) for `n` bodies (any number with `None`);
/// errors as plain messages (the caller names the key and the file).
fn xyz_frame(text: &str, index: i64, n: Option<usize>) -> Result<XyzFrame<'_>, String> {
    let lines: Vec<&str> = text.lines().collect();
    // The first line of every frame up to the one asked for (all of them from the end).
    let mut starts = Vec::new();
    let mut at = 0;
    while at < lines.len() && (index < 0 || starts.len() as i64 <= index) {
        if starts.is_empty() || !lines[at].trim().is_empty() {
            let count: usize = lines[at].trim().parse().map_err(|_| {
                if starts.is_empty() {
                    "the first line must be the number of bodies".to_owned()
                } else {
                    format!("line {}: expected the number of bodies of a frame", at + 1)
                }
            })?;
            starts.push(at);
            // Saturating: a count near 2^64 ends the file, it does not wrap around.
            at = at.saturating_add(count).saturating_add(2);
        } else {
            at += 1;
        }
    }
    if starts.is_empty() {
        return Err("the first line must be the number of bodies".into());
    }
    let frames = starts.len() as i64;
    let k = if index < 0 { frames + index } else { index };
    if !(0..frames).contains(&k) {
        return Err(format!(
            "init.frame = {index}, but the file has {} {}",
            if index < 0 { frames } else { k.min(frames) },
            if frames == 1 { "frame" } else { "frames" }
        ));
    }
    let start = starts[k as usize];
    let count: usize = lines[start].trim().parse().expect("parsed above");
    if let Some(n) = n.filter(|&n| n != count) {
        return Err(format!(
            "the file has {count} bodies, the scene's species count {n}"
        ));
    }
    let comment = lines.get(start + 1).copied().unwrap_or("");
    let mut rows = Vec::with_capacity(count);
    for j in 0..count {
        let line = start + 2 + j;
        let text = lines
            .get(line)
            .ok_or_else(|| format!("ends after {j} of {count} bodies"))?;
        rows.push((line + 1, text.split_whitespace().collect::<Vec<_>>()));
    }
    if let Some(at) = column(comment, "id", 1)? {
        let mut ordered: Vec<Option<(usize, Vec<&str>)>> = vec![None; count];
        for (line, words) in rows {
            let id = words
                .get(at)
                .and_then(|w| w.parse::<usize>().ok())
                .filter(|&id| id < count && ordered[id].is_none())
                .ok_or_else(|| {
                    format!(
                        "line {line}: id `{}`: the ids of a frame must be 0 … {}, each once",
                        words.get(at).unwrap_or(&""),
                        count - 1
                    )
                })?;
            ordered[id] = Some((line, words));
        }
        rows = ordered
            .into_iter()
            .map(|r| r.expect("each id once"))
            .collect();
    }
    Ok(XyzFrame { comment, rows })
}

/// The first word of column `name` (of `width` components) in the `Properties=…` of an
/// extended-XYZ comment line; `None` without that column or without `Properties`.
fn column(comment: &str, name: &str, width: usize) -> Result<Option<usize>, String> {
    let Some(props) = comment
        .split_whitespace()
        .find_map(|w| w.strip_prefix("Properties="))
    else {
        return Ok(None);
    };
    let fields: Vec<&str> = props.split(':').collect();
    let mut at = 0;
    for f in fields.chunks(3) {
        let [field, _, count] = f else {
            return Err(format!("malformed Properties={props}"));
        };
        let count: usize = count
            .parse()
            .map_err(|_| format!("malformed Properties={props}"))?;
        if *field == name {
            if count != width {
                return Err(format!("the {name} column must have {width} components"));
            }
            return Ok(Some(at));
        }
        at = at
            .checked_add(count)
            .ok_or_else(|| format!("malformed Properties={props}"))?;
    }
    Ok(None)
}

/// `width` finite numbers from word `at` of each row, or the line that lacks them.
fn numbers(frame: &XyzFrame<'_>, at: usize, width: usize) -> Result<Vec<Vec<f64>>, usize> {
    frame
        .rows
        .iter()
        .map(|(line, words)| {
            let v: Vec<f64> = words
                .iter()
                .skip(at)
                .take(width)
                .filter_map(|w| w.parse::<f64>().ok().filter(|x| x.is_finite()))
                .collect();
            if v.len() == width { Ok(v) } else { Err(*line) }
        })
        .collect()
}

/// Reads positions from an XYZ or extended XYZ file (a GSD file, named `….gsd`:
/// [`read_gsd`]): a count line, a comment line (an
/// extended-XYZ `Lattice="Lx 0 0 0 Ly 0 0 0 Lz"` gives the box), then `species x y z …` per
/// body. The species must be the scene's, in the scene's counts. The frame read is
/// `init.frame` (default the first); with an `id:I:1` column the rows go to the bodies their
/// ids name.
///
/// # Errors
/// [`SceneError::Invalid`] naming `init.file` for unreadable or inconsistent files.
pub fn read_xyz(scene: &Scene, path: &Path) -> Result<Configuration, SceneError> {
    if is_gsd(path) {
        return read_gsd(scene, path);
    }
    let key = "init.file";
    let name = shown(scene, path);
    let err = |msg: String| SceneError::invalid(key, format!("{name}: {msg}"));
    let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
    let count = scene.n_bodies() as usize;
    let frame = xyz_frame(&text, scene.init.frame.unwrap_or(0), Some(count)).map_err(&err)?;
    let file_box = parse_lattice(frame.comment).map_err(&err)?;
    let lengths = match (box_lengths(scene), file_box) {
        (Some(l), Some(f)) if ((l - f).abs().max_element() > 1e-6 * l.max_element()) => {
            // The positions were taken in another box: in this one they would be squeezed or
            // spread apart without a word.
            let v = |x: DVec3| format!("{} × {} × {}", short(x.x), short(x.y), short(x.z));
            return Err(err(format!(
                "its Lattice box {} is not the scene's box {}: the positions belong to another \
                 box; leave box.lengths and box.density out to take the file's box",
                v(f),
                v(l)
            )));
        }
        (Some(l), _) => l,
        (None, Some(l)) => l,
        (None, None) => {
            return Err(err(
                "no box: give `box.lengths` or a Lattice=\"…\" in the file's comment line".into(),
            ));
        }
    };
    let names: Vec<&str> = scene.species.iter().map(|s| s.name.as_str()).collect();
    let mut positions = Vec::with_capacity(count);
    let mut species = Vec::with_capacity(count);
    let mut per_species = vec![0u64; names.len()];
    for (line, words) in &frame.rows {
        let name = words.first().copied().unwrap_or("");
        let s = names
            .iter()
            .position(|&n| n == name)
            .ok_or_else(|| err(format!("line {line}: unknown species `{name}`")))?;
        let mut x = [0.0; 3];
        for (c, w) in x
            .iter_mut()
            .zip(words.iter().skip(1).chain(std::iter::repeat(&"")))
        {
            *c = w
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(format!("line {line}: expected three finite coordinates")))?;
        }
        per_species[s] += 1;
        positions.push(DVec3::from(x));
        species.push(s as u32);
    }
    for (s, sp) in scene.species.iter().enumerate() {
        if per_species[s] != sp.count {
            return Err(err(format!(
                "species `{}` has {} bodies in the file, {} in the scene",
                sp.name, per_species[s], sp.count
            )));
        }
    }
    Ok(Configuration {
        lengths,
        positions,
        species,
        lattice_spacing: None,
    })
}

/// Reads the attitudes of `n` bodies from the frame `init.frame` of an extended XYZ file (as
/// [`read_xyz`] picks it): the `orientation:R:4` column of its `Properties` (unit quaternions
/// with the scalar last, as `dmd` writes them), normalised; of a GSD file, its
/// `particles/orientation` chunk (scalar first). Errors name `key`.
///
/// # Errors
/// [`SceneError::Invalid`] naming `key` for a file without the column or with bad numbers.
pub fn read_attitudes(
    scene: &Scene,
    path: &Path,
    n: usize,
    key: &str,
) -> Result<Vec<glam::DQuat>, SceneError> {
    if is_gsd(path) {
        return gsd_attitudes(&gsd_start(scene, path, Some(n), key)?, scene, path, key);
    }
    let name = shown(scene, path);
    let err = |msg: String| SceneError::invalid(key, format!("{name}: {msg}"));
    let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
    let frame = xyz_frame(&text, scene.init.frame.unwrap_or(0), Some(n)).map_err(&err)?;
    if !frame.comment.contains("Properties=") {
        return Err(err(
            "no Properties=… in the comment line, so no orientation column".into(),
        ));
    }
    let at = column(frame.comment, "orientation", 4)
        .map_err(|e| {
            if e.starts_with("the orientation column") {
                err("the orientation column must have 4 components".into())
            } else {
                err(e)
            }
        })?
        .ok_or_else(|| err("the file has no orientation:R:4 column".into()))?;
    let mut attitudes = Vec::with_capacity(n);
    for (line, words) in &frame.rows {
        let v: Vec<f64> = words
            .iter()
            .skip(at)
            .take(4)
            .map(|x| x.parse::<f64>().unwrap_or(f64::NAN))
            .collect();
        let q = glam::DQuat::from_xyzw(
            *v.first().unwrap_or(&f64::NAN),
            *v.get(1).unwrap_or(&f64::NAN),
            *v.get(2).unwrap_or(&f64::NAN),
            *v.get(3).unwrap_or(&f64::NAN),
        );
        let len = q.length();
        if !(len.is_finite() && len > 0.5 && len < 2.0) {
            return Err(err(format!(
                "line {line}: the orientation is not a unit quaternion"
            )));
        }
        attitudes.push(q / len);
    }
    Ok(attitudes)
}

/// Reads the orientations of rods from an extended XYZ file ([`read_attitudes`] with
/// `init.frame`): each body's axis is its quaternion's image of `z`.
///
/// # Errors
/// [`SceneError::Invalid`] naming `init.orientations` for a file without the column or with
/// bad numbers.
pub fn read_orientations(scene: &Scene, path: &Path, n: usize) -> Result<Vec<DVec3>, SceneError> {
    let q = read_attitudes(scene, path, n, "init.orientations")?;
    Ok(q.into_iter().map(|q| q * DVec3::Z).collect())
}

/// The motion a start file gives (`init.velocities = "file"`), per body in body order.
#[derive(Clone, Debug, PartialEq)]
pub struct FileMotion {
    /// Velocities, the `velo:R:3` column (length/time).
    pub velocities: Vec<DVec3>,
    /// Lab angular velocities, the `omega:R:3` column (1/time), when asked for.
    pub omegas: Option<Vec<DVec3>>,
    /// Periodic images, the `map_shift:I:3` column, when the file has one: a run continues the
    /// file's unwrapped positions (`pos + map_shift · L`) instead of counting from zero.
    pub images: Option<Vec<[i32; 3]>>,
}

/// Reads the velocities (and for bodies with `moments`, their principal moments of inertia
/// per body, the lab angular velocities) of the `n` bodies of the frame `init.frame` of
/// `init.file`, in the units `dmd` writes them; the masses of the `masses:R:1` column, when the
/// file has one, must be the scene's (`masses`, per body). A GSD file gives the
/// `particles/velocity`, `particles/image` and (with `moments`) `particles/orientation` and
/// `particles/angmom` chunks: the lab angular velocity is `R I⁻¹ L_body` of HOOMD's
/// `angmom = 2 q ⊗ (0, L_body)`, no rotation about an axis of zero moment.
///
/// # Errors
/// [`SceneError::Invalid`] naming `init.velocities` for a file without the columns, with bad
/// numbers, or whose bodies' masses are not the scene's.
pub fn read_motion(
    scene: &Scene,
    path: &Path,
    masses: &[f64],
    moments: Option<&[[f64; 3]]>,
) -> Result<FileMotion, SceneError> {
    let key = "init.velocities";
    if is_gsd(path) {
        return gsd_motion(scene, path, masses, moments);
    }
    let rotating = moments.is_some();
    let name = shown(scene, path);
    let err = |msg: String| SceneError::invalid(key, format!("{name}: {msg}"));
    let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
    let n = masses.len();
    let frame = xyz_frame(&text, scene.init.frame.unwrap_or(0), Some(n)).map_err(&err)?;
    let vector = |name: &str, what: &str| -> Result<Vec<DVec3>, SceneError> {
        let at = column(frame.comment, name, 3)
            .map_err(&err)?
            .ok_or_else(|| err(format!("the file has no {name}:R:3 column ({what})")))?;
        numbers(&frame, at, 3)
            .map(|v| {
                v.into_iter()
                    .map(|x| DVec3::new(x[0], x[1], x[2]))
                    .collect()
            })
            .map_err(|line| err(format!("line {line}: expected three finite {what}")))
    };
    let velocities = vector("velo", "velocities")?;
    let omegas = if rotating {
        Some(vector("omega", "angular velocities")?)
    } else {
        None
    };
    if let Some(at) = column(frame.comment, "masses", 1).map_err(&err)? {
        let file = numbers(&frame, at, 1).map_err(|line| err(format!("line {line}: bad mass")))?;
        for ((m, x), (line, words)) in masses.iter().zip(&file).zip(&frame.rows) {
            if (x[0] - m).abs() > 1e-9 * m.abs() {
                return Err(err(format!(
                    "line {line}: mass {} in the file, {m} for species `{}` in the scene: the \
                     velocities belong to other bodies",
                    x[0],
                    words.first().unwrap_or(&"")
                )));
            }
        }
    }
    let images = match column(frame.comment, "map_shift", 3).map_err(&err)? {
        Some(at) => {
            let rows = numbers(&frame, at, 3)
                .map_err(|line| err(format!("line {line}: expected three image counters")))?;
            let mut images = Vec::with_capacity(rows.len());
            for (v, (line, _)) in rows.iter().zip(&frame.rows) {
                if v.iter()
                    .any(|x| x.fract() != 0.0 || x.abs() > f64::from(MAX_IMAGE))
                {
                    return Err(err(format!(
                        "line {line}: map_shift must be three whole numbers of at most {:e} in \
                         size",
                        f64::from(MAX_IMAGE)
                    )));
                }
                images.push([v[0] as i32, v[1] as i32, v[2] as i32]);
            }
            Some(images)
        }
        None => None,
    };
    Ok(FileMotion {
        velocities,
        omegas,
        images,
    })
}

// ----- GSD start files -------------------------------------------------------------------------

/// Whether a start file is read as GSD: its name ends in `.gsd` (any other is read as XYZ).
pub fn is_gsd(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gsd"))
}

/// The frame `init.frame` of a GSD start file, with the per-particle masses when it stores
/// them (`particles/mass`).
struct GsdStart {
    frame: gsd::Frame,
    masses: Option<Vec<f32>>,
}

/// Reads frame `init.frame` (negative: from the end) of the GSD file `path` with `n` particles
/// (any number with `None`); errors name `key`.
fn gsd_start(
    scene: &Scene,
    path: &Path,
    n: Option<usize>,
    key: &str,
) -> Result<GsdStart, SceneError> {
    let name = shown(scene, path);
    let err = |msg: String| SceneError::invalid(key, format!("{name}: {msg}"));
    let mut reader = gsd::Reader::open(path).map_err(|e| err(e.to_string()))?;
    let frames = reader.frames() as i64;
    let index = scene.init.frame.unwrap_or(0);
    let k = if index < 0 { frames + index } else { index };
    if !(0..frames).contains(&k) {
        return Err(err(format!(
            "init.frame = {index}, but the file has {frames} {}",
            if frames == 1 { "frame" } else { "frames" }
        )));
    }
    let frame = reader
        .read_frame(k as u64)
        .map_err(|e| err(format!("frame {k}: {e}")))?;
    let count = frame.n();
    if let Some(n) = n.filter(|&n| n != count) {
        return Err(err(format!(
            "frame {k} has {count} particles, the scene's species count {n}"
        )));
    }
    if let Some((i, t)) = frame
        .typeid
        .iter()
        .enumerate()
        .find(|(_, t)| **t as usize >= frame.types.len())
    {
        return Err(err(format!(
            "particle {i} has type id {t}, but the file names {} types",
            frame.types.len()
        )));
    }
    let masses = match reader.read_chunk::<f32>(k as u64, "particles/mass") {
        Ok(a) if a.data.len() == count => Some(a.data),
        Ok(a) => {
            return Err(err(format!(
                "particles/mass has {} rows for {count} particles",
                a.data.len()
            )));
        }
        Err(gsd::Error::MissingChunk { .. }) => None,
        Err(e) => return Err(err(e.to_string())),
    };
    Ok(GsdStart { frame, masses })
}

/// The box of a GSD frame (orthorhombic only).
fn gsd_box(frame: &gsd::Frame) -> Result<DVec3, String> {
    let b = frame.sim_box;
    if (b.xy, b.xz, b.yz) != (0.0, 0.0, 0.0) {
        return Err(
            "only orthorhombic boxes are supported (configuration/box tilts must be 0)".into(),
        );
    }
    let l = DVec3::new(f64::from(b.lx), f64::from(b.ly), f64::from(b.lz));
    if !(l.is_finite() && l.min_element() > 0.0) {
        return Err("configuration/box edges must be positive".into());
    }
    Ok(l)
}

/// Reads positions from frame `init.frame` of a GSD file (HOOMD's format, as `output.gsd`
/// writes it): `particles/position` (length; a position outside the box is as good as its
/// image inside), the species of each particle by the name `particles/types` gives its
/// `particles/typeid`, and the box from `configuration/box` unless the scene gives one. The
/// species must be the scene's, in the scene's counts, in body order.
///
/// # Errors
/// [`SceneError::Invalid`] naming `init.file` for unreadable or inconsistent files.
pub fn read_gsd(scene: &Scene, path: &Path) -> Result<Configuration, SceneError> {
    let key = "init.file";
    let name = shown(scene, path);
    let err = |msg: String| SceneError::invalid(key, format!("{name}: {msg}"));
    let count = scene.n_bodies() as usize;
    let GsdStart { frame, .. } = gsd_start(scene, path, Some(count), key)?;
    let lengths = match box_lengths(scene) {
        Some(l) => l,
        None => gsd_box(&frame).map_err(&err)?,
    };
    let names: Vec<&str> = scene.species.iter().map(|s| s.name.as_str()).collect();
    let mut positions = Vec::with_capacity(count);
    let mut species = Vec::with_capacity(count);
    let mut per_species = vec![0u64; names.len()];
    for (i, (p, &t)) in frame.position.iter().zip(&frame.typeid).enumerate() {
        let type_name = frame.types[t as usize].as_str();
        let s = names.iter().position(|&n| n == type_name).ok_or_else(|| {
            err(format!(
                "particle {i}: type `{type_name}` is not a species of the scene"
            ))
        })?;
        let x = DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
        if !x.is_finite() {
            return Err(err(format!("particle {i}: the position is not finite")));
        }
        per_species[s] += 1;
        positions.push(x);
        species.push(s as u32);
    }
    for (s, sp) in scene.species.iter().enumerate() {
        if per_species[s] != sp.count {
            return Err(err(format!(
                "species `{}` has {} bodies in the file, {} in the scene",
                sp.name, per_species[s], sp.count
            )));
        }
    }
    Ok(Configuration {
        lengths,
        positions,
        species,
        lattice_spacing: None,
    })
}

/// The unit quaternions of `particles/orientation` (`(w, x, y, z)`), normalised; without the
/// chunk, the hoomd schema's default, the identity (writers leave out a chunk that holds only
/// its default).
fn gsd_attitudes(
    start: &GsdStart,
    scene: &Scene,
    path: &Path,
    key: &str,
) -> Result<Vec<glam::DQuat>, SceneError> {
    let name = shown(scene, path);
    let err = |msg: String| SceneError::invalid(key, format!("{name}: {msg}"));
    let Some(rows) = start.frame.orientation.as_ref() else {
        return Ok(vec![glam::DQuat::IDENTITY; start.frame.n()]);
    };
    rows.iter()
        .enumerate()
        .map(|(i, q)| {
            let q = glam::DQuat::from_xyzw(
                f64::from(q[1]),
                f64::from(q[2]),
                f64::from(q[3]),
                f64::from(q[0]),
            );
            let len = q.length();
            if len.is_finite() && len > 0.5 && len < 2.0 {
                Ok(q / len)
            } else {
                Err(err(format!(
                    "particle {i}: the orientation is not a unit quaternion"
                )))
            }
        })
        .collect()
}

/// [`read_motion`] of a GSD file.
fn gsd_motion(
    scene: &Scene,
    path: &Path,
    masses: &[f64],
    moments: Option<&[[f64; 3]]>,
) -> Result<FileMotion, SceneError> {
    let key = "init.velocities";
    let name = shown(scene, path);
    let err = |msg: String| SceneError::invalid(key, format!("{name}: {msg}"));
    let start = gsd_start(scene, path, Some(masses.len()), key)?;
    let frame = &start.frame;
    let vector = |v: &[f32; 3]| DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
    let velocities: Vec<DVec3> = frame
        .velocity
        .as_ref()
        .ok_or_else(|| {
            err(
                "the file has no particles/velocity chunk (the hoomd schema's default would \
                 start every body at rest: use `init.velocities = \"maxwell-boltzmann\"`)"
                    .into(),
            )
        })?
        .iter()
        .map(vector)
        .collect();
    if let Some(i) = velocities.iter().position(|v| !v.is_finite()) {
        return Err(err(format!("particle {i}: the velocity is not finite")));
    }
    if let Some(file) = &start.masses {
        check_masses(masses, file, &frame.typeid, &frame.types).map_err(&err)?;
    }
    let omegas = match moments {
        Some(moments) => {
            let attitudes = gsd_attitudes(&start, scene, path, key)?;
            let angmom = frame.angmom.as_ref().ok_or_else(|| {
                err(
                    "the file has no particles/angmom chunk (angular momenta; the hoomd \
                     schema's default would start every body without rotation)"
                        .into(),
                )
            })?;
            let mut omegas = Vec::with_capacity(attitudes.len());
            for (i, ((&q, p), m)) in attitudes.iter().zip(angmom).zip(moments).enumerate() {
                // angmom = 2 q ⊗ (0, L_body) = 2 (0, L_lab) ⊗ q: L_lab = ½ angmom ⊗ q*.
                let p = glam::DQuat::from_xyzw(
                    f64::from(p[1]),
                    f64::from(p[2]),
                    f64::from(p[3]),
                    f64::from(p[0]),
                );
                let l = (p * q.conjugate()) * 0.5;
                let l = DVec3::new(l.x, l.y, l.z);
                if !l.is_finite() {
                    return Err(err(format!(
                        "particle {i}: the angular momentum is not finite"
                    )));
                }
                omegas.push(crate::analysis::output::angular_velocity(q, l, *m));
            }
            Some(omegas)
        }
        None => None,
    };
    let images = match &frame.image {
        Some(rows) => {
            if let Some(i) = rows
                .iter()
                .position(|im| im.iter().any(|x| x.unsigned_abs() > MAX_IMAGE))
            {
                return Err(err(format!(
                    "particle {i}: particles/image must be at most {:e} in size",
                    f64::from(MAX_IMAGE)
                )));
            }
            Some(rows.clone())
        }
        None => None,
    };
    Ok(FileMotion {
        velocities,
        omegas,
        images,
    })
}

/// The masses a GSD file stores (`particles/mass`, single precision) against the scene's.
fn check_masses(
    masses: &[f64],
    file: &[f32],
    typeid: &[u32],
    types: &[String],
) -> Result<(), String> {
    for (i, ((&m, &x), &t)) in masses.iter().zip(file).zip(typeid).enumerate() {
        if (f64::from(x) - m).abs() > 1e-6 * m.abs() {
            return Err(format!(
                "particle {i}: mass {x} in the file, {m} for species `{}` in the scene: the \
                 velocities belong to other bodies",
                types[t as usize]
            ));
        }
    }
    Ok(())
}

// ----- Semi-flexible molecules from their atoms ------------------------------------------------

/// Semi-flexible molecules read from the atoms of a start file.
#[derive(Clone, Debug)]
pub struct FileMolecules {
    /// The molecules' centres of mass (unwrapped: atom 0 as the file places it, the others at
    /// their nearest image of it), species and box.
    pub config: Configuration,
    /// Each molecule's atom positions relative to its centre of mass (lab frame, length).
    pub atoms: Vec<Vec<DVec3>>,
    /// With `init.velocities = "file"`: each molecule's atom velocities relative to its
    /// centre's (length/time).
    pub internal: Option<Vec<Vec<DVec3>>>,
    /// With `init.velocities = "file"`: the centres' velocities and, when the file has image
    /// counters, zero images (the centres are unwrapped already).
    pub motion: Option<FileMotion>,
}

/// One atom of a start file: its kind's name, position, velocity and image counter.
struct AtomRow {
    kind: String,
    position: DVec3,
    velocity: Option<DVec3>,
    image: Option<[i32; 3]>,
}

/// The molecule type of each species: its atoms' kind names and masses.
pub struct MoleculeShape {
    /// The kind name of each atom.
    pub kinds: Vec<String>,
    /// The mass of each atom (mass).
    pub masses: Vec<f64>,
}

/// Reads semi-flexible molecules from frame `init.frame` of a start file that holds their
/// atoms, as `output.gsd` and `output.trajectory` write them: one particle per atom, the
/// molecules one after the other in body order, each atom named by its site kind (GSD
/// `particles/types`, XYZ `species`), with positions (GSD `particles/position`, XYZ `pos`),
/// image counters (`particles/image`, `map_shift`) and, with `init.velocities = "file"`,
/// velocities (`particles/velocity`, `velo`). Each molecule's species is the one whose atom
/// kinds come next. `shapes` gives the atoms of each species. A file with one row per
/// molecule (its centre) gives `None`: [`read_xyz`] reads it.
///
/// # Errors
/// [`SceneError::Invalid`] naming `init.file` (positions) or `init.velocities` for files
/// that are unreadable, have neither the molecules' nor their atoms' count, or whose atoms
/// do not spell the scene's molecules in its species counts.
pub fn read_molecules(
    scene: &Scene,
    path: &Path,
    shapes: &[MoleculeShape],
) -> Result<Option<FileMolecules>, SceneError> {
    let key = "init.file";
    let name = shown(scene, path);
    let err = |key: &str, msg: String| SceneError::invalid(key, format!("{name}: {msg}"));
    let with_velocities = scene.init.velocities == crate::config::scene::Velocities::File;
    let n_molecules = scene.n_bodies() as usize;
    let n_atoms: usize = scene
        .species
        .iter()
        .zip(shapes)
        .map(|(sp, t)| sp.count as usize * t.kinds.len())
        .sum();
    let (rows, file_box) = if is_gsd(path) {
        let start = gsd_start(scene, path, None, key)?;
        if start.frame.n() == n_molecules {
            return Ok(None);
        }
        let f = start.frame;
        let file_box = match box_lengths(scene) {
            Some(_) => None,
            None => Some(gsd_box(&f).map_err(|e| err(key, e))?),
        };
        let velocity = f.velocity.clone();
        let rows: Vec<AtomRow> = (0..f.n())
            .map(|i| {
                let p = f.position[i];
                AtomRow {
                    kind: f.types[f.typeid[i] as usize].clone(),
                    position: DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])),
                    velocity: velocity.as_ref().map(|v| {
                        DVec3::new(f64::from(v[i][0]), f64::from(v[i][1]), f64::from(v[i][2]))
                    }),
                    image: f.image.as_ref().map(|im| im[i]),
                }
            })
            .collect();
        (rows, file_box)
    } else {
        let text = std::fs::read_to_string(path).map_err(|e| err(key, e.to_string()))?;
        let frame =
            xyz_frame(&text, scene.init.frame.unwrap_or(0), None).map_err(|e| err(key, e))?;
        if frame.rows.len() == n_molecules {
            return Ok(None);
        }
        let file_box = parse_lattice(frame.comment).map_err(|e| err(key, e))?;
        let positions = numbers(&frame, 1, 3).map_err(|line| {
            err(
                key,
                format!("line {line}: expected three finite coordinates"),
            )
        })?;
        let velocities = match column(frame.comment, "velo", 3).map_err(|e| err(key, e))? {
            Some(at) => Some(numbers(&frame, at, 3).map_err(|line| {
                err(
                    "init.velocities",
                    format!("line {line}: expected three finite velocities"),
                )
            })?),
            None => None,
        };
        let images =
            match column(frame.comment, "map_shift", 3).map_err(|e| err(key, e))? {
                Some(at) => Some(numbers(&frame, at, 3).map_err(|line| {
                    err(key, format!("line {line}: expected three image counters"))
                })?),
                None => None,
            };
        let rows = frame
            .rows
            .iter()
            .enumerate()
            .map(|(i, (_, words))| AtomRow {
                kind: words.first().copied().unwrap_or("").to_owned(),
                position: DVec3::from_slice(&positions[i]),
                velocity: velocities.as_ref().map(|v| DVec3::from_slice(&v[i])),
                image: images.as_ref().map(|im| {
                    let x = &im[i];
                    [x[0] as i32, x[1] as i32, x[2] as i32]
                }),
            })
            .collect();
        (rows, file_box)
    };
    if rows.len() != n_atoms {
        return Err(err(
            key,
            format!(
                "the file has {} particles: neither the scene's {n_molecules} molecules (their \
                 centres) nor their {n_atoms} atoms",
                rows.len()
            ),
        ));
    }
    let lengths = match (box_lengths(scene), file_box) {
        (Some(l), _) | (None, Some(l)) => l,
        (None, None) => {
            return Err(err(
                key,
                "no box: give `box.lengths` or a box in the file".into(),
            ));
        }
    };
    if with_velocities && rows.iter().any(|r| r.velocity.is_none()) {
        return Err(err(
            "init.velocities",
            "the file has no velocities of the atoms (particles/velocity or velo:R:3)".into(),
        ));
    }
    let mut positions = Vec::with_capacity(n_molecules);
    let mut species = Vec::with_capacity(n_molecules);
    let mut atoms = Vec::with_capacity(n_molecules);
    let mut internal = Vec::with_capacity(n_molecules);
    let mut centre_velocities = Vec::with_capacity(n_molecules);
    let mut at = 0;
    while at < rows.len() {
        // The species whose atom kinds come next.
        let fits: Vec<usize> = shapes
            .iter()
            .enumerate()
            .filter(|(_, t)| {
                rows.get(at..at + t.kinds.len())
                    .is_some_and(|r| r.iter().zip(&t.kinds).all(|(a, k)| a.kind == *k))
            })
            .map(|(s, _)| s)
            .collect();
        let s = match fits.as_slice() {
            [s] => *s,
            [] => {
                return Err(err(
                    key,
                    format!(
                        "particle {at} (`{}`) starts molecule {}, but no species' atoms come \
                         next in the file",
                        rows[at].kind,
                        positions.len()
                    ),
                ));
            }
            _ => {
                return Err(err(
                    key,
                    format!(
                        "molecule {} (from particle {at}) could be any of the species {}: \
                         their atoms have the same kinds",
                        positions.len(),
                        fits.iter()
                            .map(|&s| format!("`{}`", scene.species[s].name))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ));
            }
        };
        let t = &shapes[s];
        let mol = &rows[at..at + t.kinds.len()];
        // Atom 0 unwrapped, the others at their nearest image of it.
        let image = |r: &AtomRow| {
            let im = r.image.unwrap_or([0; 3]);
            DVec3::new(f64::from(im[0]), f64::from(im[1]), f64::from(im[2])) * lengths
        };
        let first = mol[0].position + image(&mol[0]);
        let lab: Vec<DVec3> = mol
            .iter()
            .map(|r| {
                let mut d = r.position - mol[0].position;
                d -= (d / lengths).round() * lengths;
                first + d
            })
            .collect();
        let mass: f64 = t.masses.iter().sum();
        let centre = lab
            .iter()
            .zip(&t.masses)
            .map(|(x, m)| *x * *m)
            .sum::<DVec3>()
            / mass;
        atoms.push(lab.iter().map(|x| *x - centre).collect());
        if with_velocities {
            let v: Vec<DVec3> = mol.iter().map(|r| r.velocity.expect("checked")).collect();
            let vc = v.iter().zip(&t.masses).map(|(x, m)| *x * *m).sum::<DVec3>() / mass;
            internal.push(v.iter().map(|x| *x - vc).collect());
            centre_velocities.push(vc);
        }
        positions.push(centre);
        species.push(s as u32);
        at += t.kinds.len();
    }
    for (s, sp) in scene.species.iter().enumerate() {
        let have = species.iter().filter(|&&x| x as usize == s).count() as u64;
        if have != sp.count {
            return Err(err(
                key,
                format!(
                    "species `{}` has {have} molecules in the file, {} in the scene",
                    sp.name, sp.count
                ),
            ));
        }
    }
    let has_images = rows.iter().all(|r| r.image.is_some());
    let motion = with_velocities.then(|| FileMotion {
        velocities: centre_velocities,
        omegas: None,
        images: has_images.then(|| vec![[0; 3]; n_molecules]),
    });
    Ok(Some(FileMolecules {
        config: Configuration {
            lengths,
            positions,
            species,
            lattice_spacing: None,
        },
        atoms,
        internal: with_velocities.then_some(internal),
        motion,
    }))
}

/// The image counters of bodies that start at `positions` (as a file gives them) with the
/// file's `images`, once the event-driven engine has wrapped the positions into `[0, L)`: the
/// boxes a position lies outside are added, so that the unwrapped positions are the file's.
pub fn wrapped_images(images: &[[i32; 3]], positions: &[DVec3], lengths: DVec3) -> Vec<[i32; 3]> {
    images
        .iter()
        .zip(positions)
        .map(|(im, p)| {
            let k = (*p / lengths).floor();
            [im[0] + k.x as i32, im[1] + k.y as i32, im[2] + k.z as i32]
        })
        .collect()
}

/// The box of an extended-XYZ comment line (orthorhombic lattices only).
fn parse_lattice(comment: &str) -> Result<Option<DVec3>, String> {
    let Some(start) = comment.find("Lattice=\"") else {
        return Ok(None);
    };
    let rest = &comment[start + 9..];
    let end = rest.find('"').ok_or("unterminated Lattice=\"…\"")?;
    let v: Vec<f64> = rest[..end]
        .split_whitespace()
        .map(|x| {
            x.parse::<f64>()
                .map_err(|_| format!("bad Lattice number `{x}`"))
        })
        .collect::<Result<_, _>>()?;
    if v.len() != 9 {
        return Err("Lattice=\"…\" needs 9 numbers".into());
    }
    let off = [v[1], v[2], v[3], v[5], v[6], v[7]];
    if off.iter().any(|&x| x != 0.0) {
        return Err(
            "only orthorhombic boxes are supported (off-diagonal Lattice entries must be 0)".into(),
        );
    }
    let l = DVec3::new(v[0], v[4], v[8]);
    if !(l.is_finite() && l.min_element() > 0.0) {
        return Err("Lattice=\"…\" edges must be positive".into());
    }
    Ok(Some(l))
}

/// Maxwell–Boltzmann velocities at `temperature` for bodies of `masses`, with zero total
/// momentum and the kinetic energy scaled to exactly `(3N − 3)/2 · kT`.
pub fn maxwell_boltzmann(masses: &[f64], temperature: f64, seed: u64) -> Vec<DVec3> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut v: Vec<DVec3> = masses
        .iter()
        .map(|&m| {
            let s = (temperature / m).sqrt();
            DVec3::new(
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            ) * s
        })
        .collect();
    let total_m: f64 = masses.iter().sum();
    let p: DVec3 = v.iter().zip(masses).map(|(v, &m)| *v * m).sum();
    let u = p / total_m;
    for x in &mut v {
        *x -= u;
    }
    let k: f64 = v
        .iter()
        .zip(masses)
        .map(|(v, &m)| 0.5 * m * v.length_squared())
        .sum();
    let target = 0.5 * (3.0 * masses.len() as f64 - 3.0) * temperature;
    if k > 0.0 {
        let f = (target / k).sqrt();
        for x in &mut v {
            *x *= f;
        }
    }
    v
}

// ----- What trajectories take from a scene -----------------------------------------------------

/// The ellipsoid a rod is drawn as, from its self-pair potential: semi-axes `(a, a, c)`, `c`
/// along the rod (length); `None` for a potential whose bodies are not rods.
pub fn rod_semi_axes(potential: &PotentialSpec) -> Option<[f64; 3]> {
    match potential.describe().drawing() {
        crate::analysis::output::Drawing::Rod { semi_axes } => Some(semi_axes),
        _ => None,
    }
}

/// The `momenta` column per internal momentum `m v` in a scene of unit `system`: in molecular
/// units, where masses are amu and velocities Å/ps, `1 / `[`ASE_VELOCITY_IN_A_PER_PS`] (ASE's unit
/// amu·√(eV/amu)); 1 in reduced units, which ASE has no counterpart of.
pub fn ase_momentum_unit(system: UnitSystem) -> f64 {
    match system {
        UnitSystem::Reduced => 1.0,
        UnitSystem::Molecular => 1.0 / ASE_VELOCITY_IN_A_PER_PS,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocities_have_zero_momentum_and_exact_temperature() {
        let masses: Vec<f64> = (0..100)
            .map(|i| if i % 2 == 0 { 1.0 } else { 3.0 })
            .collect();
        let v = maxwell_boltzmann(&masses, 1.7, 3);
        let p: DVec3 = v.iter().zip(&masses).map(|(v, &m)| *v * m).sum();
        assert!(p.length() < 1e-12);
        let k: f64 = v
            .iter()
            .zip(&masses)
            .map(|(v, &m)| 0.5 * m * v.length_squared())
            .sum();
        assert!((k - 0.5 * 297.0 * 1.7).abs() < 1e-10);
        assert_eq!(v, maxwell_boltzmann(&masses, 1.7, 3));
        assert_ne!(v, maxwell_boltzmann(&masses, 1.7, 4));
    }

    #[test]
    fn lattice_comment_lines() {
        assert_eq!(parse_lattice("Time=3").unwrap(), None);
        assert_eq!(
            parse_lattice("Lattice=\"2 0 0 0 3 0 0 0 4\" Properties=species:S:1:pos:R:3").unwrap(),
            Some(DVec3::new(2.0, 3.0, 4.0))
        );
        assert!(parse_lattice("Lattice=\"2 1 0 0 3 0 0 0 4\"").is_err());
    }
}
