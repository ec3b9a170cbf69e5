//! Semi-flexible molecules in scenes: a species with `sites` and `bonds` runs with the
//! [`Flexible`] model (RATTLE between events, seed 000 §VI), configured by `[rattle]`.
//!
//! The site kinds, `[[site_pair]]` tables and `[search]` keys are those of rigid site molecules
//! ([`site_scene`](crate::config::site_scene)); this module adds the bonds, the RATTLE settings and the
//! start. A species without `bonds` in such a scene is a rigid molecule: it moves by its exact
//! free motion and meets the others through the same site tables (the [`Flexible`] model runs
//! both). Bonds that happen to make a molecule rigid are still integrated by RATTLE (the user
//! asked for constraints; the exact rigid motion is what the same species without `bonds`
//! gives).
//!
//! **Start.** Centres on the scene's lattice (or file), each molecule's given configuration
//! turned by a rotation uniform on SO(3) with Maxwell–Boltzmann internal velocities
//! ([`random_internal`]); a molecule whose sites would lie inside the hard core of a site of a
//! molecule placed before it is re-drawn, up to [`ORIENTATION_TRIES`] times, then the start is
//! refused.

use collide::Bond;
use glam::DVec3;

use crate::analysis::output::given;
use crate::config::init::Configuration;
use crate::config::scene::{Orientations, Positions, Scene, SceneError, SearchMethodSpec};
use crate::config::site_scene::{ORIENTATION_TRIES, STEP_FRACTION, WINDOW_STEPS};
use crate::engine::potential::Potentials;
use crate::models::flexible::{Flexible, FlexibleType, RattleSettings, random_internal};
use crate::models::search::{SearchMethod, SearchSettings};
use crate::models::site_pairs::SiteAtom;

/// Default `rattle.step` in units of the shortest bond over the thermal speed `√(kT/m)` of the
/// lightest atom: 0.0049 for the chains of the flexible validation (bonds 0.6, unit masses,
/// kT = 1.5), whose energy and bond errors are measured at h = 0.005.
pub const STEP_BOND_FRACTION: f64 = 0.01;

/// Default `rattle.tolerance`.
pub const DEFAULT_TOLERANCE: f64 = 1e-12;

impl Scene {
    /// Whether the bodies are semi-flexible molecules (a species has `bonds`).
    pub fn has_bonds(&self) -> bool {
        self.species.iter().any(|s| s.bonds.is_some())
    }
}

/// A scene that is not one of semi-flexible molecules must not use their keys.
///
/// # Errors
/// [`SceneError::Invalid`] naming the key.
pub(crate) fn refuse_keys(scene: &Scene) -> Result<(), SceneError> {
    if let Some(k) = scene.species.iter().position(|s| s.bonds.is_some()) {
        return Err(SceneError::invalid(
            format!("species[{k}].bonds"),
            "bonds join the `sites` of a molecule: give the species `sites`",
        ));
    }
    if let Some(k) = scene
        .species
        .iter()
        .position(|s| s.interact_beyond_bonds.is_some())
    {
        return Err(SceneError::invalid(
            format!("species[{k}].interact_beyond_bonds"),
            "only semi-flexible molecules (species with `sites` and `bonds`) have sites that \
             meet each other: the sites of a rigid molecule keep their distances",
        ));
    }
    if scene.rattle.is_some() {
        return Err(SceneError::invalid(
            "rattle",
            "only used by semi-flexible molecules (species with `sites` and `bonds`)",
        ));
    }
    Ok(())
}

/// The checks of a scene of semi-flexible molecules after those its sites share with rigid
/// molecules (`site_scene::check`): the bonds of every species, then the RATTLE and search keys.
///
/// # Errors
/// [`SceneError::Invalid`] naming the key.
pub(crate) fn check(scene: &Scene) -> Result<(), SceneError> {
    let (_, atoms) = crate::config::site_scene::atoms_of(scene)?;
    types_of(scene, &atoms)?;
    check_rest(scene)
}

/// The molecule types of a scene of semi-flexible molecules (`atoms` per species, as
/// `site_scene` reads them).
///
/// # Errors
/// [`SceneError::Invalid`] at the species' `bonds`.
pub(crate) fn types_of(
    scene: &Scene,
    atoms: &[Vec<SiteAtom>],
) -> Result<Vec<FlexibleType>, SceneError> {
    let mut types = Vec::with_capacity(atoms.len());
    for (k, (s, a)) in scene.species.iter().zip(atoms).enumerate() {
        let Some(list) = &s.bonds else {
            // A rigid molecule among semi-flexible ones: its exact free motion.
            if s.interact_beyond_bonds.is_some() {
                return Err(SceneError::invalid(
                    format!("species[{k}].interact_beyond_bonds"),
                    "only semi-flexible molecules (species with `bonds`) have sites that meet \
                     each other: the sites of a rigid molecule keep their distances",
                ));
            }
            types.push(FlexibleType::rigid(a).map_err(|e| {
                SceneError::invalid(
                    format!("species[{k}].sites"),
                    format!("not a usable rigid molecule: {e}"),
                )
            })?);
            continue;
        };
        if s.molecule.is_some() {
            return Err(SceneError::invalid(
                format!("species[{k}].bonds"),
                "bonds index explicit `sites`: give the sites instead of `molecule`",
            ));
        }
        if list.is_empty() {
            return Err(SceneError::invalid(
                format!("species[{k}].bonds"),
                "empty: a molecule needs bonds joining its sites",
            ));
        }
        let n = a.len();
        let mut bonds = Vec::with_capacity(list.len());
        for (b, &[x, y]) in list.iter().enumerate() {
            for v in [x, y] {
                if v < 0 || v as usize >= n {
                    return Err(SceneError::invalid(
                        format!("species[{k}].bonds[{b}]"),
                        format!(
                            "site index {v} is out of range: the molecule has {n} sites, \
                             indices 0 to {}",
                            n - 1
                        ),
                    ));
                }
            }
            bonds.push(Bond::new(x as usize, y as usize));
        }
        let mut t = FlexibleType::new(a, &bonds).map_err(|e| {
            SceneError::invalid(
                format!("species[{k}].bonds"),
                format!("not a usable semi-flexible molecule: {e}"),
            )
        })?;
        if let Some(beyond) = s.interact_beyond_bonds {
            if !(1..=i64::from(u16::MAX)).contains(&beyond) {
                return Err(SceneError::invalid(
                    format!("species[{k}].interact_beyond_bonds"),
                    format!(
                        "must be a number of bonds ≥ 1 (bonded sites keep their distance), got \
                         {beyond}"
                    ),
                ));
            }
            t = t.interacting_beyond(beyond as u32);
        }
        types.push(t);
    }
    Ok(types)
}

/// The checks of a scene of semi-flexible molecules after the site kinds and `site_pair`
/// tables (shared with rigid site molecules).
///
/// # Errors
/// [`SceneError::Invalid`] naming the key.
pub(crate) fn check_rest(scene: &Scene) -> Result<(), SceneError> {
    if scene.impulse.is_some() {
        return Err(SceneError::invalid(
            "impulse",
            "not used by semi-flexible molecules: their events always apply the impulse with \
             the impulsive constraint forces of the bonds (000 §IV.A)",
        ));
    }
    match (scene.init.orientations, scene.init.axis) {
        (Orientations::Random, None) => {}
        (Orientations::Random, Some(_)) => {
            return Err(SceneError::invalid(
                "init.axis",
                "not used by semi-flexible molecules (they start randomly turned)",
            ));
        }
        _ => {
            return Err(SceneError::invalid(
                "init.orientations",
                "semi-flexible molecules start randomly turned: use `random` (the default)",
            ));
        }
    }
    crate::config::site_scene::check_search(scene)?;
    if let Some(r) = &scene.rattle {
        if let Some(h) = r.step {
            crate::config::scene::positive("rattle.step", h)?;
        }
        if !(1e-15..=1e-4).contains(&r.tolerance) {
            return Err(SceneError::invalid(
                "rattle.tolerance",
                format!("must be in [1e-15, 1e-4], got {}", given(r.tolerance)),
            ));
        }
    }
    let o = &scene.output;
    if o.orientation_acf.is_some() {
        return Err(SceneError::invalid(
            "output.orientation_acf",
            "not available for semi-flexible molecules: they have no fixed axis",
        ));
    }
    Ok(())
}

/// The built model tables of a scene of semi-flexible molecules (internal units).
#[derive(Clone, Debug)]
pub struct FlexiblePlan {
    /// One molecule type per species.
    pub types: Vec<FlexibleType>,
    /// The site–site potentials over the site kinds.
    pub potentials: Potentials,
    /// The site kinds, in the order of the potential table.
    pub kinds: Vec<String>,
    reach: f64,
}

impl FlexiblePlan {
    /// The molecule types and site–site tables of a checked scene in internal units.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] if the model refuses them (never for a checked scene).
    pub fn of(scene: &Scene) -> Result<Self, SceneError> {
        let (kinds, potentials, atoms) = crate::config::site_scene::kinds_and_tables(scene)?;
        let types = types_of(scene, &atoms)?;
        // A model without bodies tells the reach of the molecule pairs.
        let probe = Flexible::new(
            types.clone(),
            potentials.clone(),
            &[],
            &[],
            &[],
            0.0,
            RattleSettings {
                step: 1.0,
                tolerance: DEFAULT_TOLERANCE,
                rescale: true,
            },
            SearchSettings::paper(1.0),
            0,
        )
        .map_err(|e| SceneError::invalid("site_pair", e.to_string()))?;
        Ok(FlexiblePlan {
            reach: crate::engine::model::PairModel::reach(&probe),
            types,
            potentials,
            kinds,
        })
    }

    /// The largest centre distance at which two molecules interact.
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// The fastest thermal speed of an atom at `kt`: `√(kT/M) + √(kT/m)` over the types
    /// (`M` the molecule's mass, `m` its lightest atom's).
    fn site_speed(&self, kt: f64) -> f64 {
        self.types
            .iter()
            .map(|t| {
                let m = t.masses().iter().copied().fold(f64::INFINITY, f64::min);
                (kt / t.mass()).sqrt() + (kt / m).sqrt()
            })
            .fold(0.0, f64::max)
    }
}

/// The RATTLE settings of a scene: `[rattle]` with its defaults. The default step is
/// [`STEP_BOND_FRACTION`] times the shortest bond over the thermal speed `√(kT/m)` of the
/// lightest atom, the smallest over the species.
pub fn rattle_settings(scene: &Scene, plan: &FlexiblePlan) -> RattleSettings {
    let kt = scene.init.temperature;
    let default_step = plan
        .types
        .iter()
        .map(|t| {
            let m = t.masses().iter().copied().fold(f64::INFINITY, f64::min);
            let l = t.lengths().iter().copied().fold(f64::INFINITY, f64::min);
            STEP_BOND_FRACTION * l / (kt / m).sqrt()
        })
        .fold(f64::INFINITY, f64::min);
    let r = scene.rattle.as_ref();
    RattleSettings {
        step: r.and_then(|r| r.step).unwrap_or(default_step),
        tolerance: r.map_or(DEFAULT_TOLERANCE, |r| r.tolerance),
        rescale: r.is_none_or(|r| r.rescale),
    }
}

/// The search settings: `[search]` with the defaults of rigid site molecules (the fastest
/// thermal site moves [`STEP_FRACTION`] of the shortest length of the site–site tables per
/// maximum step; the window is [`WINDOW_STEPS`] steps).
pub fn search_settings(scene: &Scene, plan: &FlexiblePlan) -> SearchSettings {
    let spec = scene.search.clone().unwrap_or_default();
    let speed = plan.site_speed(scene.init.temperature);
    let max_step = spec.max_step.unwrap_or(
        STEP_FRACTION * crate::config::site_scene::shortest_length(&plan.potentials) / speed,
    );
    SearchSettings {
        method: match spec.method {
            SearchMethodSpec::Adaptive => SearchMethod::Adaptive,
            SearchMethodSpec::Grid => SearchMethod::Grid {
                threshold: spec.grid_threshold.unwrap_or(f64::INFINITY),
            },
        },
        max_step,
        window: spec.window.unwrap_or(WINDOW_STEPS * max_step),
        jitter: spec.jitter.unwrap_or(0.01),
        verify_step: spec.verify_step,
        max_change: f64::INFINITY,
        horizon: 0.0,
    }
}

/// The first overlap of molecule `i` (atoms `qi` about centre `pi`) with molecule `j`: site
/// indices, distance and hard core.
fn overlap(
    plan: &FlexiblePlan,
    lengths: DVec3,
    (pi, ti, qi): (DVec3, usize, &[DVec3]),
    (pj, tj, qj): (DVec3, usize, &[DVec3]),
) -> Option<(usize, usize, f64, f64)> {
    let mut dr = pi - pj;
    dr -= (dr / lengths).round() * lengths;
    if dr.length() > plan.reach {
        return None;
    }
    let (a, b) = (&plan.types[ti], &plan.types[tj]);
    for (x, (&sa, &ka)) in qi.iter().zip(a.site_species()).enumerate() {
        for (y, (&sb, &kb)) in qj.iter().zip(b.site_species()).enumerate() {
            let pot = &plan.potentials.all()[plan.potentials.index(ka, kb)];
            if let Some(core) = pot.core() {
                let d = (dr + sa - sb).length();
                if d < core {
                    return Some((x, y, d, core));
                }
            }
        }
    }
    None
}

/// The atoms of each molecule about its centre (lab, length) and, when the file gives them,
/// their velocities relative to the centre's (length/time).
pub type FileConformations = (Vec<Vec<DVec3>>, Option<Vec<Vec<DVec3>>>);

/// The [`Flexible`] model of a scene: a start file's conformations (`start`: each molecule's
/// atoms about its centre, with their velocities relative to the centre's or, without them,
/// Maxwell–Boltzmann ones that the model projects onto the bonds' tangent) or random starts
/// without overlaps, RATTLE and search settings.
///
/// For a `resumed` run the conformations drawn here are placeholders that the checkpoint's
/// state replaces: they are drawn once, without the overlap search.
///
/// # Errors
/// [`SceneError::Invalid`]: a start that stays overlapping after [`ORIENTATION_TRIES`] draws.
pub fn model(
    scene: &Scene,
    config: &Configuration,
    plan: FlexiblePlan,
    resumed: bool,
    start: Option<FileConformations>,
) -> Result<Flexible, SceneError> {
    let n = config.positions.len();
    let kt = scene.init.temperature;
    if let Some((qs, us)) = start {
        let us = us.unwrap_or_else(|| {
            random_internal(
                &plan.types,
                &config.species,
                kt,
                scene.seed ^ 0xf1e7_0000_0000_0000,
            )
            .1
        });
        let (rattle, settings) = (rattle_settings(scene, &plan), search_settings(scene, &plan));
        return Flexible::new(
            plan.types,
            plan.potentials,
            &config.species,
            &qs,
            &us,
            0.0,
            rattle,
            settings,
            scene.seed ^ 0x5ea2_c400_0000_000b,
        )
        .map_err(|e| SceneError::invalid("init.file", e.to_string()));
    }
    let ty = |i: usize| config.species[i] as usize;
    let where_ = match scene.init.positions {
        Positions::File => "init.file",
        _ => "box.density",
    };
    let mut qs: Vec<Vec<DVec3>> = Vec::with_capacity(n);
    let mut us: Vec<Vec<DVec3>> = Vec::with_capacity(n);
    for i in 0..n {
        let mut placed = None;
        for attempt in 0..ORIENTATION_TRIES as u64 {
            let seed = scene.seed
                ^ 0xf1e7_0000_0000_0000
                ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
                ^ attempt.wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
            let (mut q, mut u) = random_internal(&plan.types, &[config.species[i]], kt, seed);
            let (q, u) = (q.remove(0), u.remove(0));
            let others = if resumed { 0 } else { i };
            let hit = (0..others).any(|j| {
                overlap(
                    &plan,
                    config.lengths,
                    (config.positions[i], ty(i), &q),
                    (config.positions[j], ty(j), &qs[j]),
                )
                .is_some()
            });
            if !hit {
                placed = Some((q, u));
                break;
            }
        }
        let Some((q, u)) = placed else {
            return Err(SceneError::invalid(
                where_,
                format!(
                    "molecule {i} ({}) overlaps a neighbour in every one of {ORIENTATION_TRIES} \
                     random orientations: the start is too dense; lower the density or give the \
                     positions in a file",
                    scene.species[ty(i)].name
                ),
            ));
        };
        qs.push(q);
        us.push(u);
    }
    let rattle = rattle_settings(scene, &plan);
    let settings = search_settings(scene, &plan);
    Flexible::new(
        plan.types,
        plan.potentials,
        &config.species,
        &qs,
        &us,
        0.0,
        rattle,
        settings,
        scene.seed ^ 0x5ea2_c400_0000_000b,
    )
    .map_err(|e| SceneError::invalid("rattle", e.to_string()))
}
