//! From a scene to its interaction model: stepped tables for spheres, terraced potentials for
//! rods and tops (003 Eq. 7), and the search settings and initial rotation of the bodies.
//!
//! Lennard-Jones spheres on terraces need no root search: their terraces are radial steps with
//! analytic event times ([`terraced::radial_steps`](crate::models::terraced::radial_steps)), so they run on the
//! stepped path. Potentials that depend on orientations build a
//! [`Terraced`](crate::models::terraced::Terraced) model through their
//! kind (`config::kinds`), on the bodies of [`Bodies`]: uniaxial ones on rods ([`rods_model`]), ones that read
//! whole attitudes (SSD/E or SPC/E water, biaxial ellipsoids) on rigid tops ([`tops_model`]), with random orientations and
//! equipartitioned angular velocities. This module holds what the kinds share: terrace maps,
//! search settings, starting rotations and the smooth estimators.

use std::path::Path;

use glam::DVec3;
use potential::{
    Layout, LevelSet, NearMinimum, PairPotential, Placement, Profile, RigidPairPotential,
    StepEnergy, Steps, TerraceMap, TerraceOptions,
};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::analysis::output::short;
use crate::config::init::{Configuration, read_attitudes, read_orientations};
use crate::config::scene::{
    NearMinimumSpec, Orientations, PlacementSpec, Scene, SceneError, SearchMethodSpec,
    StepEnergySpec, TerraceSpec,
};
use crate::models::rotor::{Rotor, Top, TopInertia};
use crate::models::search::{SearchMethod, SearchSettings};
use crate::models::terraced::{
    BodySpecies, ModelError, PairTable, PairTerraces, Rigid, RodSpecies, Terraced, draw_omega,
};

/// SSD/E water on terraces, between rigid tops.
pub type Water = Rigid<potential::SoftStickyDipole>;

/// The core and near-minimum rule of a pair's terraces.
fn terrace_options(t: &TerraceSpec) -> TerraceOptions {
    let mut opts = TerraceOptions::default();
    if let Some(c) = t.core {
        opts = opts.with_core(c);
    }
    if t.near_minimum == NearMinimumSpec::Shift {
        opts.near_minimum = NearMinimum::Shift;
    }
    opts
}

/// The terrace map that needs nothing of the potential but its (lower bound on the)
/// `minimum`: the paper's evenly spaced levels, or explicit levels with their energies (the
/// placement and step-energy rules need a radial profile: [`terrace_map`]).
pub(crate) fn plain_terrace_map(
    k: usize,
    minimum: f64,
    t: &TerraceSpec,
    kt: f64,
    scale: f64,
) -> Result<TerraceMap, SceneError> {
    let err = |e| terrace_error(k, e, scale);
    let opts = terrace_options(t);
    if let Some(levels) = &t.levels {
        let energies = t
            .energies
            .as_ref()
            .expect("checked: explicit levels need energies");
        let set = LevelSet::new(minimum, levels, &opts).map_err(err)?;
        return TerraceMap::new(set, Steps::Energies(energies)).map_err(err);
    }
    let step = t
        .step
        .or(t.step_kt.map(|x| x * kt))
        .expect("checked: step, step_kt or levels");
    let set = LevelSet::evenly_spaced(minimum, step, &opts).map_err(err)?;
    TerraceMap::new(set, Steps::Uniform(step)).map_err(err)
}

/// The terraced model of a scene of rigid tops: attitudes uniform on SO(3) (or every body
/// frame turned so that its `ẑ` lies along `init.axis`) and angular velocities from
/// equipartition, scaled to exactly `3/2 N kT`, each from its own stream of the scene's seed;
/// or `start`, the attitudes and lab angular velocities a start file gives.
///
/// # Errors
/// [`SceneError::Invalid`] naming `search` when the model refuses its settings.
pub fn tops_model<P: RigidPairPotential>(
    scene: &Scene,
    body_species: &[u32],
    tables: Vec<PairTable<Rigid<P>>>,
    attitudes: Option<Vec<glam::DQuat>>,
    omegas: Option<Vec<DVec3>>,
) -> Result<Terraced<Rigid<P>>, SceneError> {
    let species: Vec<BodySpecies<TopInertia>> = scene
        .species
        .iter()
        .map(|s| {
            let m = s.moments.expect("checked: tops have moments");
            TopInertia::new(DVec3::from(m))
                .map(|inertia| BodySpecies {
                    mass: s.mass,
                    inertia,
                })
                .map_err(|e| SceneError::invalid("species.moments", e))
        })
        .collect::<Result<_, _>>()?;
    let inertia: Vec<TopInertia> = species.iter().map(|s| s.inertia).collect();
    let (poses, omegas) = match (attitudes, omegas) {
        (Some(q), Some(w)) => (q, w),
        (q, _) => tops_start(scene, &inertia, body_species, q),
    };
    let mut settings = search_settings(scene);
    if scene.search.as_ref().and_then(|s| s.horizon).is_none() {
        let certified = tables
            .iter()
            .all(|(_, t)| t.potential().0.certifies_by_default());
        settings.horizon = if certified {
            top_horizon(scene, settings.window)
        } else {
            0.0
        };
    }
    Terraced::new(
        species,
        tables,
        body_species,
        &poses,
        &omegas,
        0.0,
        settings,
        scene.seed ^ 0x5ea2_c400_0000_0007,
    )
    .map_err(|e| SceneError::invalid("search", e.to_string()))
}

/// What the event-driven engine builds for a terraced potential besides its tables: the model
/// with its bodies started (rods for uniaxial potentials, tops for rigid ones) and the
/// estimator of the continuous model along the run.
pub trait Bodies: crate::models::terraced::TerracedPotential + Sized {
    /// The terraced model: bodies' orientations and angular velocities from the scene (or a
    /// start file's `omegas`, lab frame).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the key that fails.
    fn model(
        scene: &Scene,
        base: &Path,
        config: &Configuration,
        tables: Vec<PairTable<Self>>,
        omegas: Option<&[DVec3]>,
    ) -> Result<Terraced<Self>, SceneError>;

    /// The estimators of the continuous model along a run, or `None`.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming `output.smooth_estimators` or `smd.smoothing`.
    fn estimator(
        scene: &Scene,
        lengths: DVec3,
        tables: &[PairTable<Self>],
    ) -> Result<Option<Box<dyn crate::analysis::smooth::Evaluate>>, SceneError>;
}

/// Uniaxial potentials act between rods.
impl<P: PairPotential + Clone + std::fmt::Debug + Send + 'static> Bodies for P {
    fn model(
        scene: &Scene,
        base: &Path,
        config: &Configuration,
        tables: Vec<PairTable<P>>,
        omegas: Option<&[DVec3]>,
    ) -> Result<Terraced<P>, SceneError> {
        rods_model(scene, base, config, tables, omegas)
    }

    fn estimator(
        scene: &Scene,
        lengths: DVec3,
        tables: &[PairTable<P>],
    ) -> Result<Option<Box<dyn crate::analysis::smooth::Evaluate>>, SceneError> {
        estimator(scene, lengths, tables)
    }
}

/// Potentials that read whole attitudes (SSD/E and SPC/E water, biaxial ellipsoids) act between rigid
/// tops.
impl<P: RigidPairPotential + Clone + std::fmt::Debug + Send + 'static> Bodies for Rigid<P> {
    fn model(
        scene: &Scene,
        base: &Path,
        config: &Configuration,
        tables: Vec<PairTable<Rigid<P>>>,
        omegas: Option<&[DVec3]>,
    ) -> Result<Terraced<Rigid<P>>, SceneError> {
        tops_model_of(scene, base, config, tables, omegas)
    }

    fn estimator(
        scene: &Scene,
        lengths: DVec3,
        tables: &[PairTable<Rigid<P>>],
    ) -> Result<Option<Box<dyn crate::analysis::smooth::Evaluate>>, SceneError> {
        tops_estimator(scene, lengths, tables)
    }
}

/// [`tops_model`] with a start file's attitudes: with its angular velocities (`omegas`, lab
/// frame) when it gives them, or alone with `init.orientations = "file"`.
///
/// # Errors
/// As [`tops_model`], and [`SceneError::Invalid`] naming `init.velocities` or
/// `init.orientations` for a file without attitudes.
pub fn tops_model_of<P: RigidPairPotential>(
    scene: &Scene,
    base: &Path,
    config: &Configuration,
    tables: Vec<PairTable<Rigid<P>>>,
    omegas: Option<&[DVec3]>,
) -> Result<Terraced<Rigid<P>>, SceneError> {
    let file = || base.join(scene.init.file.as_ref().expect("checked"));
    let n = config.positions.len();
    let attitudes = match (omegas, scene.init.orientations) {
        (Some(_), _) => Some(read_attitudes(scene, &file(), n, "init.velocities")?),
        (None, Orientations::File) => Some(read_attitudes(scene, &file(), n, "init.orientations")?),
        (None, _) => None,
    };
    tops_model(
        scene,
        &config.species,
        tables,
        attitudes,
        omegas.map(<[DVec3]>::to_vec),
    )
}

/// The largest component of a start file's angular velocity along its rod's axis, relative to
/// `|ω|`, that is taken for the round-off of the file's numbers (six significant digits of the
/// axis and of `ω` leave about 2·10⁻⁶).
pub const OMEGA_ALONG_AXIS: f64 = 1e-5;

/// A start file's lab angular velocities of rods (`omegas`, one per axis in `axes`), with the
/// component along each axis, round-off of the file's numbers, dropped: a linear rotor turns
/// only about its short axes (seed 003 §V), so `ω` must be perpendicular to the axis.
///
/// # Errors
/// [`SceneError::Invalid`] naming `init.velocities` for a body whose `ω` has a component along
/// its axis above [`OMEGA_ALONG_AXIS`] of `|ω|`.
pub fn rotor_omegas(
    scene: &Scene,
    omegas: &[DVec3],
    axes: &[DVec3],
) -> Result<Vec<DVec3>, SceneError> {
    let file = scene
        .init
        .file
        .as_deref()
        .map_or(String::new(), |f| format!("{}: ", f.display()));
    omegas
        .iter()
        .zip(axes)
        .enumerate()
        .map(|(i, (&w, &a))| {
            let along = w.dot(a);
            if along.abs() > OMEGA_ALONG_AXIS * w.length() {
                let v = |x: DVec3| format!("({}, {}, {})", short(x.x), short(x.y), short(x.z));
                return Err(SceneError::invalid(
                    "init.velocities",
                    format!(
                        "{file}body {i}: the angular velocity {} (1/time) has a component {} \
                         along the rod's axis {}: a rod turns only about its short axes, so \
                         its angular velocity must be perpendicular to its axis",
                        v(w),
                        short(along),
                        v(a)
                    ),
                ));
            }
            Ok(w - along * a)
        })
        .collect()
}

/// The terraced model of a rods scene: orientations, and equipartitioned angular velocities or
/// a start file's (`omegas`, lab frame, checked by [`rotor_omegas`]).
///
/// # Errors
/// [`SceneError::Invalid`] naming `init.orientations` for a bad file, `search` when the model
/// refuses its settings.
pub fn rods_model<P: PairPotential>(
    scene: &Scene,
    base: &Path,
    config: &Configuration,
    tables: Vec<PairTable<P>>,
    omegas: Option<&[DVec3]>,
) -> Result<Terraced<P>, SceneError> {
    let n = config.positions.len();
    let axes = match scene.init.orientations {
        Orientations::Random => random_axes(n, scene.seed),
        Orientations::Aligned => {
            let a = glam::DVec3::from(scene.init.axis.expect("checked")).normalize();
            vec![a; n]
        }
        Orientations::File => {
            let file = scene.init.file.as_ref().expect("checked");
            read_orientations(scene, &base.join(file), n)?
        }
    };
    let species = rod_species(scene);
    let inertia: Vec<f64> = config
        .species
        .iter()
        .map(|&s| species[s as usize].inertia)
        .collect();
    let omegas = match omegas {
        Some(w) => rotor_omegas(scene, w, &axes)?,
        None => equipartitioned_omegas(&axes, &inertia, scene.init.temperature, scene.seed),
    };
    Terraced::new(
        species,
        tables,
        &config.species,
        &axes,
        &omegas,
        0.0,
        search_settings(scene),
        scene.seed ^ 0x5ea2_c400_0000_0007,
    )
    .map_err(|e| SceneError::invalid("search", e.to_string()))
}

/// The attitudes (body → lab) and lab angular velocities of rigid tops at the start of a run
/// (both engines): `attitudes` (a start file's), else uniform on SO(3), or every body `ẑ` along
/// `init.axis`; each body-frame component of `ω` Gaussian with variance `kT/I_k` (the moments
/// of `inertia[species]`) from its own stream of the seed, all scaled to exactly `3/2 N kT`.
pub fn tops_start(
    scene: &Scene,
    inertia: &[TopInertia],
    body_species: &[u32],
    attitudes: Option<Vec<glam::DQuat>>,
) -> (Vec<glam::DQuat>, Vec<DVec3>) {
    let n = body_species.len();
    let poses: Vec<glam::DQuat> = match (attitudes, scene.init.axis) {
        (Some(q), _) => q,
        (None, Some(a)) => {
            vec![glam::DQuat::from_rotation_arc(DVec3::Z, DVec3::from(a).normalize()); n]
        }
        (None, None) => random_attitudes(n, scene.seed),
    };
    let kt = scene.init.temperature;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(scene.seed ^ 0x0e6a_0e6a_0000_0009);
    let mut omegas: Vec<DVec3> = poses
        .iter()
        .zip(body_species)
        .map(|(&q, &s)| Top::draw(&inertia[s as usize], q, kt, &mut rng))
        .collect();
    let kinetic: f64 = omegas
        .iter()
        .zip(&poses)
        .zip(body_species)
        .map(|((&w, &q), &s)| {
            let inertia = &inertia[s as usize];
            Top::start(inertia, q, w).map_or(0.0, |top| top.kinetic(inertia))
        })
        .sum();
    if kinetic > 0.0 {
        let f = (1.5 * n as f64 * kt / kinetic).sqrt();
        for w in &mut omegas {
            *w *= f;
        }
    }
    (poses, omegas)
}

/// How trajectories draw a water molecule: its oxygen and hydrogens in the body frame of
/// `potential::water` (the TIP3P geometry whose moments SSD uses: O–H 0.9572 Å, H–O–H
/// 104.52°, centre of mass at the origin), diameters 1.0 Å (O) and 0.6 Å (H): positions and
/// diameters.
pub fn water_drawing() -> (Vec<DVec3>, Vec<f64>) {
    let (oh, half_angle) = (0.9572_f64, 0.5 * 104.52_f64.to_radians());
    let (m_o, m_h) = (15.9994, 1.008);
    let (y, z) = (oh * half_angle.sin(), oh * half_angle.cos());
    // The centre of mass lies 2 m_H z / M above the oxygen.
    let z_cm = 2.0 * m_h * z / (m_o + 2.0 * m_h);
    (
        vec![
            DVec3::new(0.0, 0.0, -z_cm),
            DVec3::new(0.0, y, z - z_cm),
            DVec3::new(0.0, -y, z - z_cm),
        ],
        vec![1.0, 0.6, 0.6],
    )
}

/// Attitudes uniform on SO(3): normalised 4-vectors of independent Gaussians, from the
/// scene's seed (a stream of its own).
pub fn random_attitudes(n: usize, seed: u64) -> Vec<glam::DQuat> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x0a15_0a15_0000_0013);
    (0..n)
        .map(|_| {
            loop {
                let g = glam::DVec4::new(
                    StandardNormal.sample(&mut rng),
                    StandardNormal.sample(&mut rng),
                    StandardNormal.sample(&mut rng),
                    StandardNormal.sample(&mut rng),
                );
                if let Some(q) = g.try_normalize() {
                    break glam::DQuat::from_vec4(q);
                }
            }
        })
        .collect()
}

pub(crate) fn potential_error(k: usize, e: potential::PotentialError) -> SceneError {
    SceneError::invalid(format!("pair[{k}].potential"), e.to_string())
}

/// A terrace map's error for pair table `k`, energies divided by `scale` (internal per scene
/// unit).
pub(crate) fn terrace_error(k: usize, e: potential::PotentialError, scale: f64) -> SceneError {
    let key = format!("pair[{k}].terraces");
    let out = |x: f64| x / scale;
    let problem = match e {
        potential::PotentialError::LevelAtMinimum { level, minimum, .. } => format!(
            "level {} lies on the potential's minimum {}: the terrace below it would have zero \
             width (003 §V); choose another step or levels, or set `near_minimum = \"shift\"`",
            out(level),
            out(minimum)
        ),
        potential::PotentialError::LevelBelowMinimum { level, minimum } => format!(
            "level {} lies below the potential's minimum {}: no pair can cross it",
            out(level),
            out(minimum)
        ),
        potential::PotentialError::LevelAboveCore { level, core } => format!(
            "level {} is not below the hard-core level {}",
            out(level),
            out(core)
        ),
        e => e.to_string(),
    };
    SceneError::invalid(key, problem)
}

/// Pair table `k`'s terraces as built, or the model's refusal naming `pair[k].terraces`.
pub(crate) fn pair_terraces<P>(
    k: usize,
    built: Result<PairTerraces<P>, ModelError>,
) -> Result<PairTerraces<P>, SceneError> {
    built.map_err(|e| SceneError::invalid(format!("pair[{k}].terraces"), e.to_string()))
}

/// A uniaxial potential smoothed over the window `(r_l, r_u)` (003 Eq. 26), as the smd engine
/// and the smooth estimators take it, or the refusal naming `smd.smoothing`.
pub(crate) fn smoothed<P: PairPotential>(
    p: P,
    (r_l, r_u): (f64, f64),
) -> Result<potential::Smoothed<P>, SceneError> {
    potential::Smoothed::new(p, r_l, r_u)
        .map_err(|e| SceneError::invalid("smd.smoothing", e.to_string()))
}

/// The terrace map of a pair table (003 Eq. 7 and the placement and step-energy rules).
pub(crate) fn terrace_map<P: PairPotential, F: Fn(f64) -> f64>(
    k: usize,
    pot: &P,
    prof: Option<&Profile<F>>,
    t: &TerraceSpec,
    kt: f64,
    scale: f64,
) -> Result<TerraceMap, SceneError> {
    // The paper's evenly spaced map and explicit levels with energies need only the minimum.
    let plain = match &t.levels {
        Some(_) => t.energies.is_some(),
        None => {
            t.placement == PlacementSpec::EqualEnergy
                && t.step_energy == StepEnergySpec::Equal
                && t.outermost.is_none()
        }
    };
    if plain {
        return plain_terrace_map(k, pot.minimum(), t, kt, scale);
    }
    let err = |e| terrace_error(k, e, scale);
    let opts = terrace_options(t);
    let step = t.step.or(t.step_kt.map(|x| x * kt));
    let rule = |step: f64| match t.step_energy {
        StepEnergySpec::Equal => StepEnergy::Equal(step),
        StepEnergySpec::Midpoint => StepEnergy::Midpoint,
        StepEnergySpec::VolumeAverage => StepEnergy::VolumeAverage,
        StepEnergySpec::Virial => StepEnergy::Virial { kt },
    };
    let profile_needed = || {
        prof.ok_or_else(|| {
            SceneError::invalid(
                format!("pair[{k}].terraces"),
                "this rule needs a radial profile of the potential",
            )
        })
    };
    if let Some(levels) = &t.levels {
        // Without energies (`plain` took those): a step-energy rule on the profile.
        let set = LevelSet::new(pot.minimum(), levels, &opts).map_err(err)?;
        let energies = rule(1.0).energies(profile_needed()?, &set).map_err(err)?;
        return TerraceMap::new(set, Steps::Energies(&energies)).map_err(err);
    }
    let step = step.expect("checked: step, step_kt or levels");
    let mut layout = Layout::paper(pot.minimum(), step, &opts).map_err(err)?;
    if let Some(o) = t.outermost {
        layout = layout.with_outermost(o);
    }
    let placement = match t.placement {
        PlacementSpec::EqualEnergy => Placement::EqualEnergy,
        PlacementSpec::EqualDistance => Placement::EqualDistance,
        PlacementSpec::EqualVolume => Placement::EqualVolume,
    };
    TerraceMap::from_profile(profile_needed()?, placement, &layout, rule(step), &opts).map_err(err)
}

/// Default of `search.horizon` in windows: how far certified prediction may jump ahead in
/// one call (measured on the paper's rods, docs/PERFORMANCE.md).
pub const DEFAULT_HORIZON_WINDOWS: f64 = 2.0;

/// Default of `search.horizon` for rigid tops on a potential whose models pay (the water
/// models; elsewhere, the biaxial Gay–Berne included, the horizon is 0), in windows. A model of
/// `U` itself costs about one evaluation and proves short stretches; on water each molecule
/// changes every fraction of a femtosecond, so proving a third of a window (0.67 fs on SPC/E
/// and SSD/E) with one model and certifying again at the virtual event beats longer jumps and
/// the search alike (docs/PERFORMANCE.md, *Certified prediction of rigid molecules*).
pub const DEFAULT_TOP_HORIZON_WINDOWS: f64 = 1.0 / 3.0;

/// The default horizon of certified tops: [`DEFAULT_TOP_HORIZON_WINDOWS`] of a window at
/// ΔV = kT/2 and above, shorter by `√(ΔV / (kT/2))` for finer steps (a model proves a stretch
/// in which `Kτ²/2` stays below the gap to a level, so about `√ΔV`; measured on SPC/E: best near
/// 0.6, 0.4 and 0.15 fs at kT/2, kT/4 and kT/16). ΔV is the finest evenly spaced step of the
/// scene's pairs; explicit levels keep the kT/2 horizon.
fn top_horizon(scene: &Scene, window: f64) -> f64 {
    let kt = scene.init.temperature;
    let step = scene
        .pair
        .iter()
        .filter_map(|p| p.terraces.as_ref())
        .filter_map(|t| t.step.or(t.step_kt.map(|x| x * kt)))
        .fold(f64::INFINITY, f64::min);
    let finer = if step.is_finite() && step > 0.0 {
        (step / (0.5 * kt)).min(1.0).sqrt()
    } else {
        1.0
    };
    DEFAULT_TOP_HORIZON_WINDOWS * window * finer
}

/// Default of `search.max_change`: steps limited to where `U` is predicted to cross at most
/// this fraction of the terrace's width (see `docs/VALIDATION.md` for the misses and the cost
/// against it).
pub const DEFAULT_MAX_CHANGE: f64 = 0.5;

/// The search settings of a rods scene (internal units): the scene's `[search]` with its
/// defaults. The default maximum step is the paper's 4 fs carried over to any rods by the two
/// time scales it resolves (003 §V.A): `min(0.076 √(I/kT), 0.0064 σ √(m/kT))` over the species
/// and pairs (3.98 fs for the paper's rods at T* = 1.4).
pub fn search_settings(scene: &Scene) -> SearchSettings {
    let spec = scene.search.clone().unwrap_or_default();
    let kt = scene.init.temperature;
    let mut step = f64::INFINITY;
    for s in &scene.species {
        if let Some(i) = s.inertia {
            step = step.min(0.076 * (i / kt).sqrt());
        }
        if let Some(m) = s.moments {
            let smallest = m.iter().copied().fold(f64::INFINITY, f64::min);
            step = step.min(0.076 * (smallest / kt).sqrt());
        }
        for p in &scene.pair {
            let Some(sigma) = p.potential.map(|q| q.describe().lengths().0) else {
                continue;
            };
            step = step.min(0.0064 * sigma * (s.mass / kt).sqrt());
        }
    }
    let max_step = spec.max_step.unwrap_or(step);
    SearchSettings {
        method: match spec.method {
            SearchMethodSpec::Adaptive => SearchMethod::Adaptive,
            SearchMethodSpec::Grid => SearchMethod::Grid {
                threshold: spec.grid_threshold.unwrap_or(f64::INFINITY),
            },
        },
        max_step,
        window: spec.window.unwrap_or(max_step),
        jitter: spec.jitter.unwrap_or(0.01),
        verify_step: spec.verify_step,
        max_change: spec.max_change.unwrap_or(DEFAULT_MAX_CHANGE),
        horizon: spec
            .horizon
            .unwrap_or(DEFAULT_HORIZON_WINDOWS * spec.window.unwrap_or(max_step)),
    }
}

/// The species of a rods scene: masses and moments of inertia.
pub fn rod_species(scene: &Scene) -> Vec<RodSpecies> {
    scene
        .species
        .iter()
        .map(|s| RodSpecies {
            mass: s.mass,
            inertia: s.inertia.expect("checked: rods have inertia"),
        })
        .collect()
}

/// Uniformly random unit axes, one per body, from the scene's seed (a stream of its own).
pub fn random_axes(n: usize, seed: u64) -> Vec<DVec3> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x0a15_0a15_0000_0003);
    (0..n)
        .map(|_| {
            loop {
                let g = DVec3::new(
                    StandardNormal.sample(&mut rng),
                    StandardNormal.sample(&mut rng),
                    StandardNormal.sample(&mut rng),
                );
                if let Some(s) = g.try_normalize() {
                    break s;
                }
            }
        })
        .collect()
}

/// Angular velocities of rods with axes `axes` and moments `inertia` equipartitioned at `kt`
/// (two Gaussian components perpendicular to each axis), scaled so that the rotational
/// kinetic energy is exactly `N kT` (two degrees of freedom per rod).
pub fn equipartitioned_omegas(axes: &[DVec3], inertia: &[f64], kt: f64, seed: u64) -> Vec<DVec3> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x0e6a_0e6a_0000_0005);
    let mut w: Vec<DVec3> = axes
        .iter()
        .zip(inertia)
        .map(|(&s, &i)| draw_omega(s, i, kt, &mut rng))
        .collect();
    let k: f64 = w
        .iter()
        .zip(inertia)
        .map(|(w, &i)| 0.5 * i * w.length_squared())
        .sum();
    let target = axes.len() as f64 * kt;
    if k > 0.0 {
        let f = (target / k).sqrt();
        for x in &mut w {
            *x *= f;
        }
    }
    w
}

impl Scene {
    /// Whether the event-driven engine runs this scene on the terraces of a smooth potential
    /// (rods, Gay–Berne bodies, tops, or Lennard-Jones spheres as radial steps), whose smooth
    /// potential the estimators evaluate.
    pub fn has_terraced_smooth_potential(&self) -> bool {
        !self.has_bonds()
            && !self.has_sites()
            && self.pair.first().is_some_and(|p| p.potential.is_some())
    }

    /// Whether a run of this scene evaluates the smooth estimators: `output.smooth_estimators`
    /// (default on), a terraced smooth potential and a sampling interval.
    pub fn wants_smooth_estimators(&self) -> bool {
        self.output.smooth_estimators.unwrap_or(true)
            && self.output.sample_interval.is_some()
            && self.has_terraced_smooth_potential()
    }
}

/// The estimator of a terraced scene (in internal units) over its pair tables, with the
/// smoothing window the smd engine would use for each pair (`[smd] smoothing`, else its
/// default), or `None` when the scene does not want one or its cut-off does not fit the box
/// (minimum image needs `r_u` below half the shortest side; an explicit
/// `output.smooth_estimators = true` then is an error).
///
/// # Errors
/// [`SceneError::Invalid`] naming `output.smooth_estimators` or
/// `smd.smoothing`.
pub fn estimator<P: PairPotential + Clone + std::fmt::Debug + Send + 'static>(
    scene: &Scene,
    lengths: DVec3,
    tables: &[PairTable<P>],
) -> Result<Option<Box<dyn crate::analysis::smooth::Evaluate>>, SceneError> {
    if !scene.wants_smooth_estimators() {
        return Ok(None);
    }
    let mut pots = Vec::with_capacity(tables.len());
    let mut cutoff: f64 = 0.0;
    for (k, ((a, b), t)) in tables.iter().enumerate() {
        let spec = scene.pair[k]
            .potential
            .expect("terraced pairs have a potential");
        let (r_l, r_u) = crate::config::smd_spec::window(scene, &spec);
        let p = smoothed(t.potential().clone(), (r_l, r_u))?;
        cutoff = cutoff.max(r_u);
        pots.push(((*a, *b), p));
    }
    let why = |half: f64| {
        format!(
            "the smooth potential's cut-off r_u = {cutoff} reaches half the shortest box side \
             {half:.6}: a body would interact with two images of another; use more bodies or a \
             smaller smd.smoothing.r_u"
        )
    };
    if !cutoff_fits(scene, lengths, cutoff, why)? {
        return Ok(None);
    }
    Ok(Some(Box::new(crate::analysis::smooth::Estimator::new(
        scene.species.len(),
        pots,
    ))))
}

/// Whether an estimator's `cutoff` lies below half the shortest side of a box of `lengths`
/// (minimum image); if not, an explicit `output.smooth_estimators = true` is an error saying
/// `why(half)`, and otherwise the run goes without the estimator.
///
/// # Errors
/// [`SceneError::Invalid`] naming `output.smooth_estimators`.
fn cutoff_fits(
    scene: &Scene,
    lengths: DVec3,
    cutoff: f64,
    why: impl FnOnce(f64) -> String,
) -> Result<bool, SceneError> {
    let half = 0.5 * lengths.min_element();
    if cutoff < half {
        return Ok(true);
    }
    match scene.output.smooth_estimators {
        Some(true) => Err(SceneError::invalid("output.smooth_estimators", why(half))),
        _ => Ok(false),
    }
}

/// The estimator of a scene of rigid tops (in internal units): the terraced pairs' own smooth
/// potentials, each zero beyond its own cut-off (the kind's `own_window`; 9 Å for SSD/E,
/// 10.93 Å for SPC/E), or
/// `None` when the scene does not want one (`output.smooth_estimators = false` or no
/// `output.sample_interval`) or the cut-off does not fit the box (then an explicit
/// `output.smooth_estimators = true` is an error).
///
/// # Errors
/// [`SceneError::Invalid`] naming `output.smooth_estimators`, or the pair table whose
/// potential has no cut-off of its own.
pub fn tops_estimator<P: RigidPairPotential + Clone + std::fmt::Debug + Send + 'static>(
    scene: &Scene,
    lengths: DVec3,
    tables: &[PairTable<Rigid<P>>],
) -> Result<Option<Box<dyn crate::analysis::smooth::Evaluate>>, SceneError> {
    if !scene.wants_smooth_estimators() {
        return Ok(None);
    }
    let mut cutoff = 0.0f64;
    for (k, p) in scene.pair.iter().enumerate() {
        let own = p.potential.and_then(|q| q.describe().own_window());
        let Some((_, r_cut)) = own else {
            return Err(SceneError::invalid(
                format!("pair[{k}].potential"),
                "a potential between rigid tops needs a cut-off of its own (zero beyond it) \
                 for its smooth estimator",
            ));
        };
        cutoff = cutoff.max(r_cut);
    }
    let why = |half: f64| {
        format!(
            "the potential's cut-off {cutoff} reaches half the shortest box side {half:.6}: a \
             body would interact with two images of another; use more bodies"
        )
    };
    if !cutoff_fits(scene, lengths, cutoff, why)? {
        return Ok(None);
    }
    let pots = tables
        .iter()
        .map(|((a, b), t)| ((*a, *b), t.potential().0.clone()))
        .collect();
    Ok(Some(Box::new(
        crate::analysis::smooth::RigidEstimator::new(scene.species.len(), pots, cutoff),
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn omegas_are_perpendicular_and_equipartitioned() {
        let axes = random_axes(500, 3);
        let inertia = vec![0.5; 500];
        let w = equipartitioned_omegas(&axes, &inertia, 2.0, 3);
        for (a, w) in axes.iter().zip(&w) {
            assert!((a.length() - 1.0).abs() < 1e-15);
            assert!(a.dot(*w).abs() < 1e-12 * w.length());
        }
        let k: f64 = w.iter().map(|w| 0.25 * w.length_squared()).sum();
        assert!((k - 1000.0).abs() < 1e-9);
        // Axes cover the sphere: mean of each component near zero, of its square near 1/3.
        for c in 0..3 {
            let m: f64 = axes.iter().map(|a| a[c]).sum::<f64>() / 500.0;
            let m2: f64 = axes.iter().map(|a| a[c] * a[c]).sum::<f64>() / 500.0;
            assert!(
                m.abs() < 0.08 && (m2 - 1.0 / 3.0).abs() < 0.05,
                "{c}: {m} {m2}"
            );
        }
    }
}
