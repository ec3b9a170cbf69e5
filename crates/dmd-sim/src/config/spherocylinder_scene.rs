//! Hard spherocylinders in scenes: the `shape` table of the species (`kind =
//! "spherocylinder"`, `length`, `diameter`), their checks, and the
//! [`Spherocylinders`] model with its initial orientations.
//!
//! Every species of such a scene has a shape, and the scene has no pair tables: the hard core
//! is the only interaction. A species' moment of inertia about its short axes is
//! `species.inertia`, or by default that of a uniform solid spherocylinder of its mass
//! ([`uniform_inertia`]). Random initial orientations are uniform on the sphere and re-drawn for
//! a body that would overlap one placed before it, so a lattice denser than random orientations
//! allow is refused with a clear message rather than started with overlaps.

use std::path::Path;

use glam::DVec3;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::analysis::output::given;
use crate::config::init::{Configuration, read_orientations};
use crate::config::rods::{equipartitioned_omegas, rotor_omegas};
use crate::config::scene::{Engine, Orientations, Scene, SceneError, positive};
use crate::models::spherocylinders::{Spherocylinder, Spherocylinders, closest_points};

/// The `kind` of a spherocylinder's `shape` table.
pub const KIND: &str = "spherocylinder";

/// Re-draws of one body's random orientation before the start is refused.
pub const ORIENTATION_TRIES: usize = 1000;

/// Whether the scene's bodies are hard spherocylinders (a species has a `shape`).
pub fn is_spherocylinders(scene: &Scene) -> bool {
    scene.species.iter().any(|s| s.shape.is_some())
}

/// The moment of inertia about a short axis through the centre of a uniform solid
/// spherocylinder of mass `mass`, segment length `length` and diameter `diameter`: the cylinder
/// (`m_c (L²/12 + a²/4)`) and two hemispheres (each `m_h (83/320 a² + (L/2 + 3a/8)²)`, its
/// centre of mass `3a/8` beyond the cylinder's end), masses in proportion to the volumes, `a =
/// D/2`. A sphere (`L = 0`) gets `2/5 m a²`.
pub fn uniform_inertia(mass: f64, length: f64, diameter: f64) -> f64 {
    let a = 0.5 * diameter;
    let (vc, vs) = (length, 4.0 / 3.0 * a);
    let (mc, mh) = (mass * vc / (vc + vs), 0.5 * mass * vs / (vc + vs));
    let cylinder = mc * (length * length / 12.0 + a * a / 4.0);
    let arm = 0.5 * length + 3.0 / 8.0 * a;
    let hemisphere = mh * (83.0 / 320.0 * a * a + arm * arm);
    cylinder + 2.0 * hemisphere
}

/// The bodies of a checked spherocylinder scene (internal units).
#[derive(Clone, Debug, PartialEq)]
pub struct SpherocylindersPlan {
    /// One per species.
    pub species: Vec<Spherocylinder>,
}

impl SpherocylindersPlan {
    /// The species of a checked scene.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the `shape` key that fails.
    pub fn of(scene: &Scene) -> Result<Self, SceneError> {
        let species = scene
            .species
            .iter()
            .enumerate()
            .map(|(k, sp)| {
                let (length, diameter) = shape_of(k, sp.shape.as_ref())?;
                Ok(Spherocylinder {
                    length,
                    diameter,
                    mass: sp.mass,
                    inertia: sp
                        .inertia
                        .unwrap_or_else(|| uniform_inertia(sp.mass, length, diameter)),
                })
            })
            .collect::<Result<_, SceneError>>()?;
        Ok(SpherocylindersPlan { species })
    }

    /// The largest centre distance at which two bodies touch.
    pub fn reach(&self) -> f64 {
        let mut r = 0.0f64;
        for a in &self.species {
            for b in &self.species {
                r = r.max(0.5 * (a.length + b.length + a.diameter + b.diameter));
            }
        }
        r
    }

    /// The smallest diameter: lattice sites closer than it hold no body.
    pub fn smallest_diameter(&self) -> f64 {
        self.species
            .iter()
            .map(|s| s.diameter)
            .fold(f64::INFINITY, f64::min)
    }
}

/// A number of a `shape` table.
fn number(key: &str, v: &toml::Value) -> Result<f64, SceneError> {
    match v {
        toml::Value::Float(x) => Ok(*x),
        toml::Value::Integer(x) => Ok(*x as f64),
        other => Err(SceneError::invalid(
            key,
            format!("must be a number (length), got {other}"),
        )),
    }
}

/// The `(length, diameter)` of species `k`'s `shape` table.
fn shape_of(k: usize, shape: Option<&toml::Table>) -> Result<(f64, f64), SceneError> {
    let key = |name: &str| format!("species[{k}].shape.{name}");
    let Some(t) = shape else {
        return Err(SceneError::invalid(
            format!("species[{k}].shape"),
            "needed: every species of a scene of spherocylinders has one, for example \
             `shape = { kind = \"spherocylinder\", length = 3.0, diameter = 1.0 }`",
        ));
    };
    match t.get("kind") {
        Some(toml::Value::String(s)) if s == KIND => {}
        Some(toml::Value::String(s)) => {
            return Err(SceneError::invalid(
                key("kind"),
                format!("unknown shape `{s}` (known: `{KIND}`)"),
            ));
        }
        _ => {
            return Err(SceneError::invalid(
                key("kind"),
                format!("needed: the body model, a string (known: `{KIND}`)"),
            ));
        }
    }
    if let Some(other) = t
        .keys()
        .find(|name| !["kind", "length", "diameter"].contains(&name.as_str()))
    {
        return Err(SceneError::invalid(
            key(other),
            "unknown key: a spherocylinder has `kind`, `length` and `diameter`",
        ));
    }
    let get = |name: &str| -> Result<f64, SceneError> {
        let v = t.get(name).ok_or_else(|| {
            SceneError::invalid(
                key(name),
                "needed: a spherocylinder has a segment `length` (≥ 0) and a `diameter` (> 0)",
            )
        })?;
        number(&key(name), v)
    };
    let (length, diameter) = (get("length")?, get("diameter")?);
    if !(length.is_finite() && length >= 0.0) {
        return Err(SceneError::invalid(
            key("length"),
            format!(
                "the length of the axis segment must be finite and ≥ 0, got {}",
                given(length)
            ),
        ));
    }
    if !(diameter.is_finite() && diameter > 0.0) {
        return Err(SceneError::invalid(
            key("diameter"),
            format!(
                "the diameter of the hard shell must be finite and > 0, got {}",
                given(diameter)
            ),
        ));
    }
    Ok((length, diameter))
}

/// Checks a scene of spherocylinders: every species' shape and inertia, no keys of other
/// body kinds, and the orientation keys.
///
/// # Errors
/// [`SceneError::Invalid`] naming the key.
pub(crate) fn check(scene: &Scene) -> Result<(), SceneError> {
    for (k, sp) in scene.species.iter().enumerate() {
        shape_of(k, sp.shape.as_ref())?;
        let refuse = |name: &str, given: bool| {
            if given {
                Err(SceneError::invalid(
                    format!("species[{k}].{name}"),
                    "not a key of spherocylinders (rigid uniaxial bodies with one moment of \
                     inertia `inertia`): remove it",
                ))
            } else {
                Ok(())
            }
        };
        refuse("moments", sp.moments.is_some())?;
        refuse("sites", sp.sites.is_some())?;
        refuse("molecule", sp.molecule.is_some())?;
        refuse("bonds", sp.bonds.is_some())?;
        if let Some(i) = sp.inertia
            && !(i.is_finite() && i > 0.0)
        {
            return Err(SceneError::invalid(
                format!("species[{k}].inertia"),
                format!("must be finite and > 0, got {}", given(i)),
            ));
        }
    }
    let only_hard = |key: &str, given: bool| {
        if given {
            Err(SceneError::invalid(
                key,
                "spherocylinders interact only through their hard shells (`species.shape`): \
                 remove it",
            ))
        } else {
            Ok(())
        }
    };
    only_hard("pair", !scene.pair.is_empty())?;
    only_hard("site_pair", !scene.site_pair.is_empty())?;
    only_hard("search", scene.search.is_some())?;
    only_hard("impulse", scene.impulse.is_some())?;
    only_hard("rattle", scene.rattle.is_some())?;
    if scene.engine == Engine::Smd {
        return Err(SceneError::invalid(
            "engine",
            "standard MD integrates smooth potentials; hard spherocylinders run on the \
             event-driven engine only (`dmd`)",
        ));
    }
    let init = &scene.init;
    crate::config::scene::check_orientation_keys(init)?;
    if init.velocities == crate::config::scene::Velocities::File
        && init.orientations != Orientations::File
    {
        return Err(SceneError::invalid(
            "init.velocities",
            "`file` gives spherocylinders the angular velocities of `init.file`, which belong \
             to its orientations: set `orientations = \"file\"` too",
        ));
    }
    // The axes' correlation function samples the axes at every sample.
    if let Some(c) = &scene.output.orientation_acf {
        positive("output.orientation_acf.max_lag", c.max_lag)?;
        match scene.output.sample_interval {
            None => {
                return Err(SceneError::invalid(
                    "output.sample_interval",
                    "needed by `output.orientation_acf`: the simulated time between samples",
                ));
            }
            Some(dt) if c.max_lag < dt => {
                return Err(SceneError::invalid(
                    "output.orientation_acf.max_lag",
                    format!(
                        "{} is shorter than output.sample_interval = {dt}",
                        given(c.max_lag)
                    ),
                ));
            }
            _ => {}
        }
    }
    Ok(())
}

/// Minimum image of `d` in a periodic box of edges `l`.
fn minimum_image(d: DVec3, l: DVec3) -> DVec3 {
    d - l * (d / l).round()
}

/// Random axes uniform on the sphere for bodies at `config`'s positions, each re-drawn while it
/// overlaps a body placed before it (bodies binned in cells at least one reach wide, so each
/// is compared with its neighbours only).
fn placed_axes(
    scene: &Scene,
    config: &Configuration,
    plan: &SpherocylindersPlan,
) -> Result<Vec<DVec3>, SceneError> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(scene.seed ^ 0x5c71_0000_0000_0017);
    let l = config.lengths;
    let reach = plan.reach();
    let cells = (l / reach).floor().max(DVec3::ONE);
    let k = [cells.x as usize, cells.y as usize, cells.z as usize];
    let cell_of = |r: DVec3| -> [usize; 3] {
        let f = (r / l).fract_gl() * cells;
        [0, 1, 2].map(|a| (f[a] as usize).min(k[a] - 1))
    };
    let index = |c: [usize; 3]| (c[0] * k[1] + c[1]) * k[2] + c[2];
    let mut bins: Vec<Vec<usize>> = vec![Vec::new(); k[0] * k[1] * k[2]];
    let mut axes = Vec::with_capacity(config.positions.len());
    for (i, &ri) in config.positions.iter().enumerate() {
        let si = config.species[i] as usize;
        let c = cell_of(ri);
        // The neighbouring cells, each once (a box fewer than three cells wide wraps onto
        // itself).
        let mut near: Vec<usize> = Vec::with_capacity(27);
        for dx in -1i64..=1 {
            for dy in -1i64..=1 {
                for dz in -1i64..=1 {
                    let w = |a: usize, d: i64| (c[a] as i64 + d).rem_euclid(k[a] as i64) as usize;
                    let b = index([w(0, dx), w(1, dy), w(2, dz)]);
                    if !near.contains(&b) {
                        near.push(b);
                    }
                }
            }
        }
        let mut tries = 0;
        let axis = loop {
            let g = DVec3::new(
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            );
            let Some(u) = g.try_normalize() else {
                continue;
            };
            let a = plan.species[si];
            let clear = near.iter().flat_map(|&b| &bins[b]).all(|&j| {
                let b = plan.species[config.species[j] as usize];
                let dr = minimum_image(ri - config.positions[j], l);
                let core = 0.5 * (a.diameter + b.diameter);
                let (_, _, w) = closest_points(dr, u, 0.5 * a.length, axes[j], 0.5 * b.length);
                w.length() >= core * (1.0 + 1e-9)
            });
            if clear {
                break u;
            }
            tries += 1;
            if tries == ORIENTATION_TRIES {
                let key = if scene.box_.lengths.is_some() {
                    "box.lengths"
                } else {
                    "box.density"
                };
                return Err(SceneError::invalid(
                    key,
                    format!(
                        "body {i} overlaps a neighbour in each of {ORIENTATION_TRIES} random \
                         orientations: the lattice is too dense for spherocylinders of this \
                         length; lower the density, or start them aligned \
                         (`init.orientations = \"aligned\"` with a lattice spacing above the \
                         length plus the diameter along the axis)"
                    ),
                ));
            }
        };
        axes.push(axis);
        bins[index(c)].push(i);
    }
    Ok(axes)
}

/// The model of a checked scene: orientations (random without overlaps, aligned, or a start
/// file's) and equipartitioned angular velocities, or a start file's (`omegas`, lab frame).
/// A `resumed` run takes its state from a checkpoint afterwards, so its start is random axes
/// with no placement.
///
/// # Errors
/// [`SceneError::Invalid`] naming `box.density` for a lattice too dense for random
/// orientations, `init.orientations` or `init.velocities` for a bad start file, `species` for
/// numbers the model refuses.
pub fn model(
    scene: &Scene,
    base: &Path,
    config: &Configuration,
    plan: SpherocylindersPlan,
    resumed: bool,
    omegas: Option<Vec<DVec3>>,
) -> Result<Spherocylinders, SceneError> {
    let n = config.positions.len();
    let axes = match scene.init.orientations {
        Orientations::Random if resumed => vec![DVec3::Z; n],
        Orientations::Random => placed_axes(scene, config, &plan)?,
        Orientations::Aligned => {
            let a = DVec3::from(scene.init.axis.expect("checked")).normalize();
            vec![a; n]
        }
        Orientations::File => {
            let file = scene.init.file.as_ref().expect("checked");
            read_orientations(scene, &base.join(file), n)?
        }
    };
    let inertia: Vec<f64> = config
        .species
        .iter()
        .map(|&s| plan.species[s as usize].inertia)
        .collect();
    let omegas = match omegas {
        Some(w) => rotor_omegas(scene, &w, &axes)?,
        None => equipartitioned_omegas(&axes, &inertia, scene.init.temperature, scene.seed),
    };
    Spherocylinders::new(plan.species, &config.species, &axes, &omegas)
        .map_err(|e| SceneError::invalid("species", e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(extra: &str) -> Result<Scene, SceneError> {
        let text = format!(
            "version = 1\n[box]\ndensity = 0.03\n[[species]]\nname = \"R\"\ncount = 64\n\
             shape = {{ kind = \"spherocylinder\", length = 3.0, diameter = 1.0 }}\n{extra}\n\
             [init]\npositions = \"sc\"\ntemperature = 1.0\n[run]\nevents = 100\n"
        );
        Scene::from_str_with(&text, &[])
    }

    #[test]
    fn a_sphere_of_zero_length_has_the_moment_of_a_ball() {
        let i = uniform_inertia(2.0, 0.0, 1.0);
        assert!((i - 0.4 * 2.0 * 0.25).abs() < 1e-15, "{i}");
        // A long rod tends to the thin rod's m L²/12.
        let i = uniform_inertia(1.0, 1e4, 1.0);
        assert!((i / (1e8 / 12.0) - 1.0).abs() < 1e-3, "{i}");
    }

    #[test]
    fn bad_shapes_name_their_key() {
        if let Err(e) = scene("") {
            panic!("{e}");
        }
        let key = |e: SceneError| match e {
            SceneError::Invalid { key, .. } => key,
            other => panic!("{other}"),
        };
        let bad = |shape: &str| {
            let text = format!(
                "version = 1\n[box]\ndensity = 0.03\n[[species]]\nname = \"R\"\ncount = 64\n\
                 shape = {shape}\n[init]\npositions = \"sc\"\ntemperature = 1.0\n[run]\nevents = 100\n"
            );
            key(Scene::from_str_with(&text, &[]).unwrap_err())
        };
        assert_eq!(
            bad("{ kind = \"spherocylinder\", length = -1.0, diameter = 1.0 }"),
            "species[0].shape.length"
        );
        assert_eq!(
            bad("{ kind = \"spherocylinder\", length = 2.0, diameter = 0.0 }"),
            "species[0].shape.diameter"
        );
        assert_eq!(
            bad("{ kind = \"cube\", length = 2.0, diameter = 1.0 }"),
            "species[0].shape.kind"
        );
        assert_eq!(
            bad("{ kind = \"spherocylinder\", length = 2.0, diameter = 1.0, width = 1 }"),
            "species[0].shape.width"
        );
        assert_eq!(
            bad("{ kind = \"spherocylinder\", diameter = 1.0 }"),
            "species[0].shape.length"
        );
        let e = scene("[[pair]]\nspecies = [\"R\", \"R\"]\nsteps = [[1.0, inf]]").unwrap_err();
        assert_eq!(key(e), "pair");
    }
}
