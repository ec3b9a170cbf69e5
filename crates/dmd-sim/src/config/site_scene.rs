//! Rigid site molecules in scenes: from the `sites`/`molecule` keys of the species,
//! the `[[site_pair]]` tables and `[impulse]` to a [`Sites`] model with its initial
//! attitudes.
//!
//! A scene of site molecules names its atoms by *site kind*; every unordered pair of site
//! kinds needs a stepped potential (`site_pair`, the format of `pair.steps`). The body species
//! of the event loop are the molecule types (one per scene species), whose mass is the sum of
//! their site masses. Random initial orientations are drawn uniformly on SO(3) and re-drawn
//! for a molecule that would overlap one placed before it, so a lattice denser than random
//! orientations allow is refused with a clear message rather than started with overlaps.

use glam::{DMat3, DQuat, DVec3};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::analysis::output::given;
use crate::config::init::Configuration;
use crate::config::scene::{
    ImpulseRuleSpec, MoleculeSpec, Orientations, Positions, Scene, SceneError, SearchMethodSpec,
};
use crate::engine::model::PairModel;
use crate::engine::potential::Potentials;
use crate::models::search::{SearchMethod, SearchSettings};
use crate::models::site_pairs::SiteAtom;
use crate::models::sites::{ImpulseRule, MoleculeType, Sites, draw_body_omega, molecules};

/// Default `search.max_step` in units of the shortest length of the site–site tables over the
/// fastest thermal site speed (see [`search_settings`]).
pub const STEP_FRACTION: f64 = 0.03;

/// Default `search.window` in units of the maximum step.
pub const WINDOW_STEPS: f64 = 5.0;

/// Re-draws of one molecule's random orientation before the start is refused.
pub const ORIENTATION_TRIES: usize = 1000;

impl Scene {
    /// Whether the bodies are rigid site molecules (a species has `sites` or `molecule`).
    pub fn has_sites(&self) -> bool {
        self.species
            .iter()
            .any(|s| s.sites.is_some() || s.molecule.is_some())
    }
}

/// Before the document is read: a molecule's mass is the sum of its sites' masses, so a
/// species with `sites` or `molecule` must not give `mass` (the key has a default, so only the
/// document shows whether it was written).
///
/// # Errors
/// [`SceneError::Invalid`] at `species[k].mass`.
pub fn check_document(doc: &toml::Table) -> Result<(), SceneError> {
    let Some(toml::Value::Array(species)) = doc.get("species") else {
        return Ok(());
    };
    for (k, sp) in species.iter().enumerate() {
        if let toml::Value::Table(t) = sp
            && (t.contains_key("sites") || t.contains_key("molecule"))
            && t.contains_key("mass")
        {
            return Err(SceneError::invalid(
                format!("species[{k}].mass"),
                "a molecule's mass is the sum of its site masses: remove the key",
            ));
        }
    }
    Ok(())
}

/// After the document is read: every molecule species gets its molecule's mass (used for the
/// initial velocities and reported in the summary).
pub fn fill_masses(scene: &mut Scene) {
    for s in &mut scene.species {
        if let Some(sites) = &s.sites {
            // A bad site mass is reported at the site by the checks.
            if sites.iter().all(|a| a.mass.is_finite() && a.mass > 0.0) {
                s.mass = sites.iter().map(|a| a.mass).sum();
            }
        } else if let Some(m) = s.molecule {
            s.mass = match m {
                MoleculeSpec::Dumbbell { .. } => 2.0,
                MoleculeSpec::MethaneLike => molecules::methane_like().0.mass(),
                MoleculeSpec::BenzeneLike => molecules::benzene_like().0.mass(),
            };
        }
    }
}

/// A scene without site molecules must not use their keys.
///
/// # Errors
/// [`SceneError::Invalid`] naming the key.
pub(crate) fn refuse_site_keys(scene: &Scene) -> Result<(), SceneError> {
    if !scene.site_pair.is_empty() {
        return Err(SceneError::invalid(
            "site_pair",
            "only used by rigid site molecules (species with `sites` or `molecule`)",
        ));
    }
    if scene.impulse.is_some() {
        return Err(SceneError::invalid(
            "impulse",
            "only used by rigid site molecules (species with `sites` or `molecule`)",
        ));
    }
    Ok(())
}

/// The site kinds of the scene in order of first appearance, and per species its atoms with
/// their kinds as indices into that list.
///
/// # Errors
/// A species that is not a molecule, or a shipped molecule that refuses its parameters.
pub(crate) fn atoms_of(scene: &Scene) -> Result<(Vec<String>, Vec<Vec<SiteAtom>>), SceneError> {
    let mut kinds: Vec<String> = Vec::new();
    let mut index = |name: &str| -> u32 {
        if let Some(k) = kinds.iter().position(|m| m == name) {
            k as u32
        } else {
            kinds.push(name.to_owned());
            (kinds.len() - 1) as u32
        }
    };
    let mut all = Vec::new();
    for (k, s) in scene.species.iter().enumerate() {
        let atoms: Vec<SiteAtom> = if let Some(sites) = &s.sites {
            sites
                .iter()
                .map(|a| SiteAtom {
                    position: DVec3::from(a.position),
                    mass: a.mass,
                    species: index(&a.kind),
                })
                .collect()
        } else {
            let (t, names): (MoleculeType, &[&str]) = match s.molecule {
                Some(MoleculeSpec::Dumbbell { elongation }) => (
                    molecules::dumbbell(elongation).map(|p| p.0).map_err(|e| {
                        SceneError::invalid(
                            format!("species[{k}].molecule.elongation"),
                            e.to_string(),
                        )
                    })?,
                    &["A"],
                ),
                Some(MoleculeSpec::MethaneLike) => (molecules::methane_like().0, &["C", "H"]),
                Some(MoleculeSpec::BenzeneLike) => (molecules::benzene_like().0, &["C", "H"]),
                None => {
                    return Err(SceneError::invalid(
                        format!("species[{k}].sites"),
                        "not a molecule: give `sites` or `molecule`",
                    ));
                }
            };
            t.sites()
                .iter()
                .zip(t.masses())
                .zip(t.site_species())
                .map(|((&p, &m), &sp)| SiteAtom {
                    position: p,
                    mass: m,
                    species: index(names[sp as usize]),
                })
                .collect()
        };
        all.push(atoms);
    }
    Ok((kinds, all))
}

/// The checks of a scene of site molecules (called from `Scene::check` instead of the pair
/// tables of spheres and rods).
///
/// # Errors
/// [`SceneError::Invalid`] naming the key.
pub(crate) fn check(scene: &Scene) -> Result<(), SceneError> {
    if !scene.pair.is_empty() {
        return Err(SceneError::invalid(
            "pair",
            "a scene of rigid site molecules takes its potentials from `site_pair` tables \
             between site kinds, not from `pair` tables between species",
        ));
    }
    for (k, s) in scene.species.iter().enumerate() {
        let key = |name: &str| format!("species[{k}].{name}");
        match (&s.sites, &s.molecule) {
            (None, None) => {
                return Err(SceneError::invalid(
                    key("sites"),
                    "every species of a scene of site molecules needs `sites` or `molecule` \
                     (a sphere is not a rigid molecule: give it two sites or use a scene of \
                     spheres)",
                ));
            }
            (Some(_), Some(_)) => {
                return Err(SceneError::invalid(
                    format!("species[{k}]"),
                    "give either `sites` or `molecule`, not both",
                ));
            }
            _ => {}
        }
        if s.inertia.is_some() {
            return Err(SceneError::invalid(
                key("inertia"),
                "a molecule's moments of inertia follow from its sites: remove the key",
            ));
        }
        if let Some(MoleculeSpec::Dumbbell { elongation }) = s.molecule
            && !(elongation.is_finite() && elongation > 0.0)
        {
            return Err(SceneError::invalid(
                key("molecule.elongation"),
                format!(
                    "must be a positive finite site separation, got {}",
                    given(elongation)
                ),
            ));
        }
        if let Some(sites) = &s.sites {
            if sites.len() < 2 {
                return Err(SceneError::invalid(
                    key("sites"),
                    format!(
                        "a rigid molecule needs at least two sites, got {}",
                        sites.len()
                    ),
                ));
            }
            for (a, site) in sites.iter().enumerate() {
                let here = |name: &str| format!("species[{k}].sites[{a}].{name}");
                if site.kind.trim().is_empty() || site.kind.contains(char::is_whitespace) {
                    return Err(SceneError::invalid(
                        here("kind"),
                        format!("`{}` is not a name: use letters, digits, _ or -", site.kind),
                    ));
                }
                if !(site.mass.is_finite() && site.mass > 0.0) {
                    return Err(SceneError::invalid(
                        here("mass"),
                        format!("must be a positive finite number, got {}", given(site.mass)),
                    ));
                }
                if site.position.iter().any(|x| !x.is_finite()) {
                    return Err(SceneError::invalid(
                        here("position"),
                        format!("must be three finite numbers, got {:?}", site.position),
                    ));
                }
                if let Some(b) = sites[..a].iter().position(|o| o.position == site.position) {
                    return Err(SceneError::invalid(
                        key("sites"),
                        format!(
                            "sites {b} and {a} are both at {:?}: two sites of a molecule cannot \
                             coincide",
                            site.position
                        ),
                    ));
                }
            }
        }
    }
    let (kinds, atoms) = atoms_of(scene)?;
    let flexible = scene.has_bonds();
    let mut types = Vec::new();
    if !flexible && scene.rattle.is_some() {
        return Err(SceneError::invalid(
            "rattle",
            "only used by semi-flexible molecules: give the species `bonds`",
        ));
    }
    for (k, a) in atoms.iter().enumerate().filter(|_| !flexible) {
        let t = MoleculeType::new(a).map_err(|e| {
            SceneError::invalid(
                format!("species[{k}].sites"),
                format!("not a usable rigid molecule: {e}"),
            )
        })?;
        types.push(t);
    }
    // Site–site tables.
    let nk = kinds.len();
    let list = || {
        kinds
            .iter()
            .map(|m| format!("`{m}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut seen = vec![None::<usize>; nk * nk];
    for (k, p) in scene.site_pair.iter().enumerate() {
        let mut ab = [0usize; 2];
        for (x, name) in p.sites.iter().enumerate() {
            ab[x] = kinds.iter().position(|m| m == name).ok_or_else(|| {
                SceneError::invalid(
                    format!("site_pair[{k}].sites"),
                    format!(
                        "unknown site kind `{name}` (the molecules have sites of kinds {})",
                        list()
                    ),
                )
            })?;
        }
        let [a, b] = ab;
        if let Some(first) = seen[a * nk + b] {
            return Err(SceneError::invalid(
                format!("site_pair[{k}].sites"),
                format!(
                    "the site kinds `{}`–`{}` already have a table (site_pair[{first}])",
                    p.sites[0], p.sites[1]
                ),
            ));
        }
        seen[a * nk + b] = Some(k);
        seen[b * nk + a] = Some(k);
        crate::config::scene::check_steps_at(&format!("site_pair[{k}].steps"), &p.steps)?;
    }
    for a in 0..nk {
        for b in a..nk {
            if seen[a * nk + b].is_none() {
                return Err(SceneError::invalid(
                    "site_pair",
                    format!(
                        "no site_pair table for site kinds `{}` and `{}`: every pair of site \
                         kinds needs one",
                        kinds[a], kinds[b]
                    ),
                ));
            }
        }
    }
    if flexible {
        // The molecules' bonds and RATTLE keys: `flexible_scene::check`.
        return Ok(());
    }
    // Impulse rule.
    if scene
        .impulse
        .as_ref()
        .is_some_and(|i| i.rule == ImpulseRuleSpec::Constrained)
    {
        for (k, t) in types.iter().enumerate() {
            if let Err(why) = t.bonds() {
                return Err(SceneError::invalid(
                    "impulse.rule",
                    format!(
                        "species `{}`: {why}; use `contact-point` (the same physics)",
                        scene.species[k].name
                    ),
                ));
            }
        }
    }
    crate::config::scene::check_orientation_keys_saying(
        &scene.init,
        "needed by `orientations = \"aligned\"`: the common direction [x, y, z] of every \
         molecule's first principal axis",
        "`file` reads the attitudes of `init.file` (its orientation column or \
         particles/orientation chunk): it needs `positions = \"file\"`",
    )?;
    check_search(scene)?;
    let o = &scene.output;
    if let Some(c) = &o.orientation_acf {
        crate::config::scene::positive("output.orientation_acf.max_lag", c.max_lag)?;
        match o.sample_interval {
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
                        c.max_lag
                    ),
                ));
            }
            _ => {}
        }
    }
    Ok(())
}

/// The `[search]` keys of site molecules.
pub(crate) fn check_search(scene: &Scene) -> Result<(), SceneError> {
    let Some(sr) = &scene.search else {
        return Ok(());
    };
    crate::config::scene::check_search_keys(sr, "a squared length ≥ 0 or inf (site molecules)")?;
    if let Some(x) = sr.verify_step
        && let Some(step) = sr.max_step
        && x >= step
    {
        return Err(SceneError::invalid(
            "search.verify_step",
            format!(
                "{x} is not finer than search.max_step = {step}: the verification grid \
                 would find nothing the search cannot"
            ),
        ));
    }
    if sr.horizon.is_some() {
        return Err(SceneError::invalid(
            "search.horizon",
            "only used by rods on terraced potentials: the searches of site molecules have no \
             certified prediction",
        ));
    }
    if sr.max_change.is_some() {
        return Err(SceneError::invalid(
            "search.max_change",
            "only used by rods on terraced potentials: the searches of site molecules step by \
             `max_step` (and the window)",
        ));
    }
    Ok(())
}

/// The built model tables of a scene of site molecules (internal units).
#[derive(Clone, Debug)]
pub struct SitesPlan {
    /// One molecule type per species.
    pub types: Vec<MoleculeType>,
    /// The site–site potentials over the site kinds.
    pub potentials: Potentials,
    /// The site kinds, in the order of the potential table.
    pub kinds: Vec<String>,
    reach: f64,
}

impl SitesPlan {
    /// The molecule types and site–site tables of a checked scene in internal units.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] if the model refuses them (never for a checked scene).
    pub fn of(scene: &Scene) -> Result<Self, SceneError> {
        let (kinds, potentials, atoms) = kinds_and_tables(scene)?;
        let types = atoms
            .iter()
            .enumerate()
            .map(|(k, a)| {
                MoleculeType::new(a)
                    .map_err(|e| SceneError::invalid(format!("species[{k}].sites"), e.to_string()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        // A model without bodies tells the reach of the molecule pairs.
        let probe = Sites::new(
            types.clone(),
            potentials.clone(),
            &[],
            &[],
            &[],
            0.0,
            SearchSettings::paper(1.0),
            ImpulseRule::ContactPoint,
            0,
        )
        .map_err(|e| SceneError::invalid("site_pair", e.to_string()))?;
        Ok(SitesPlan {
            reach: probe.reach(),
            types,
            potentials,
            kinds,
        })
    }

    /// The largest centre distance at which two molecules interact.
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// The shortest length of the site–site tables.
    fn shortest_length(&self) -> f64 {
        shortest_length(&self.potentials)
    }

    /// The fastest thermal speed of a site at `kt`: `√(kT/M) + ρ max_k √(kT/I_k)` over the
    /// types (`ρ` the largest arm, moments that carry rotation only).
    fn site_speed(&self, kt: f64) -> f64 {
        self.types
            .iter()
            .map(|t| {
                let spin = t
                    .moments()
                    .to_array()
                    .iter()
                    .filter(|&&i| i > 0.0)
                    .map(|&i| (kt / i).sqrt())
                    .fold(0.0, f64::max);
                (kt / t.mass()).sqrt() + t.radius() * spin
            })
            .fold(0.0, f64::max)
    }
}

/// Site kinds, site–site potentials and the atoms of every species.
pub(crate) type KindsAndTables = (Vec<String>, Potentials, Vec<Vec<SiteAtom>>);

/// The site kinds, the site–site potentials over them and the atoms of every species of a
/// checked scene of site molecules (rigid or semi-flexible).
///
/// # Errors
/// A species that is not a molecule (never for a checked scene).
pub(crate) fn kinds_and_tables(scene: &Scene) -> Result<KindsAndTables, SceneError> {
    let (kinds, atoms) = atoms_of(scene)?;
    let index = |n: &str| kinds.iter().position(|m| m == n).expect("checked");
    let tables: Vec<_> = scene
        .site_pair
        .iter()
        .map(|p| ((index(&p.sites[0]), index(&p.sites[1])), p.steps.clone()))
        .collect();
    let potentials = Potentials::from_tables(kinds.len(), &tables);
    Ok((kinds, potentials, atoms))
}

/// The shortest length of site–site tables: the innermost radius or the narrowest band
/// between two radii.
pub(crate) fn shortest_length(potentials: &Potentials) -> f64 {
    let mut l = f64::INFINITY;
    for p in potentials.all() {
        let r = p.radii();
        for (k, &x) in r.iter().enumerate() {
            l = l.min(x);
            if k > 0 {
                l = l.min((x - r[k - 1]).abs());
            }
        }
    }
    l
}

/// The search settings of a scene of site molecules: `[search]` with its defaults. The default
/// maximum step lets the fastest thermal site move [`STEP_FRACTION`] of the shortest length of
/// the site–site tables (0.021 for hard dumbbells of L* = 0.6 at kT = 1, where the validation
/// finds no miss up to 0.5); the window is [`WINDOW_STEPS`] steps.
pub fn search_settings(scene: &Scene, plan: &SitesPlan) -> SearchSettings {
    let spec = scene.search.clone().unwrap_or_default();
    let speed = plan.site_speed(scene.init.temperature);
    let max_step = spec
        .max_step
        .unwrap_or(STEP_FRACTION * plan.shortest_length() / speed);
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

/// The first overlap of molecule `i` (type `ti`, attitude `ri`) with molecule `j`: site
/// indices, distance and hard core.
fn overlap(
    plan: &SitesPlan,
    lengths: DVec3,
    (pi, ti, ri): (DVec3, usize, &DMat3),
    (pj, tj, rj): (DVec3, usize, &DMat3),
) -> Option<(usize, usize, f64, f64)> {
    let mut dr = pi - pj;
    dr -= (dr / lengths).round() * lengths;
    let (a, b) = (&plan.types[ti], &plan.types[tj]);
    if dr.length() > plan.reach {
        return None;
    }
    for (x, (&sa, &ka)) in a.sites().iter().zip(a.site_species()).enumerate() {
        for (y, (&sb, &kb)) in b.sites().iter().zip(b.site_species()).enumerate() {
            let pot = &plan.potentials.all()[plan.potentials.index(ka, kb)];
            if let Some(core) = pot.core() {
                let d = (dr + *ri * sa - *rj * sb).length();
                if d < core {
                    return Some((x, y, d, core));
                }
            }
        }
    }
    None
}

/// The [`Sites`] model of a scene: attitudes (a start file's `attitudes`, random without
/// overlaps, or aligned), angular velocities (a start file's lab `omegas`, or from
/// equipartition at the scene temperature), search settings and impulse rule.
///
/// For a `resumed` run the attitudes and angular velocities drawn here are placeholders that
/// the checkpoint's state replaces: they are drawn once, without the overlap search (the
/// checkpoint's positions are not the start's).
///
/// # Errors
/// [`SceneError::Invalid`]: molecules that overlap at the start, named.
pub fn model(
    scene: &Scene,
    config: &Configuration,
    plan: SitesPlan,
    resumed: bool,
    attitudes: Option<Vec<DQuat>>,
    omegas: Option<Vec<DVec3>>,
) -> Result<Sites, SceneError> {
    let n = config.positions.len();
    let kt = scene.init.temperature;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(scene.seed ^ 0x517e_5000_0000_000a);
    let ty = |i: usize| config.species[i] as usize;
    let aligned = match scene.init.orientations {
        Orientations::Aligned => {
            // The body's first principal axis (x) turned onto the given axis.
            let a = DVec3::from(scene.init.axis.expect("checked")).normalize();
            Some(DQuat::from_rotation_arc(DVec3::X, a))
        }
        _ => None,
    };
    let mut qs: Vec<DQuat> = Vec::with_capacity(n);
    let mut mats: Vec<DMat3> = Vec::with_capacity(n);
    let where_ = match scene.init.positions {
        Positions::File => "init.file",
        _ => "box.density",
    };
    for i in 0..n {
        let tries = if aligned.is_some() || resumed {
            1
        } else {
            ORIENTATION_TRIES
        };
        let mut placed = None;
        let mut last = None;
        let given = attitudes.as_ref().map(|q| q[i]);
        let tries = if given.is_some() { 1 } else { tries };
        for _ in 0..tries {
            let q = given
                .or(aligned)
                .unwrap_or_else(|| random_quaternion(&mut rng));
            let r = DMat3::from_quat(q);
            let others = if resumed { 0 } else { i };
            let hit = (0..others).find_map(|j| {
                overlap(
                    &plan,
                    config.lengths,
                    (config.positions[i], ty(i), &r),
                    (config.positions[j], ty(j), &mats[j]),
                )
                .map(|(a, b, d, core)| (i, j, a, b, d, core))
            });
            match hit {
                None => {
                    placed = Some((q, r));
                    break;
                }
                Some(h) => last = Some(h),
            }
        }
        match (placed, last) {
            (Some((q, r)), _) => {
                qs.push(q);
                mats.push(r);
            }
            (None, Some(h)) if aligned.is_some() || given.is_some() => {
                return Err(overlap_error(config, where_, h, &plan));
            }
            (None, _) => {
                return Err(SceneError::invalid(
                    where_,
                    format!(
                        "molecule {i} ({}) overlaps a neighbour in every one of \
                         {ORIENTATION_TRIES} random orientations: the start is too dense for \
                         random orientations; lower the density, start aligned \
                         (`init.orientations = \"aligned\"`), or give the positions in a file",
                        scene.species[ty(i)].name
                    ),
                ));
            }
        }
    }
    let omegas: Vec<DVec3> = match omegas {
        Some(w) => w,
        None => (0..n)
            .map(|i| mats[i] * draw_body_omega(&plan.types[ty(i)], kt, &mut rng))
            .collect(),
    };
    let rule = match scene.impulse.as_ref().map(|i| i.rule).unwrap_or_default() {
        ImpulseRuleSpec::ContactPoint => ImpulseRule::ContactPoint,
        ImpulseRuleSpec::Constrained => ImpulseRule::Constrained,
    };
    let settings = search_settings(scene, &plan);
    Sites::new(
        plan.types,
        plan.potentials,
        &config.species,
        &qs,
        &omegas,
        0.0,
        settings,
        rule,
        scene.seed ^ 0x5ea2_c400_0000_000a,
    )
    .map_err(|e| SceneError::invalid("search", e.to_string()))
}

fn overlap_error(
    config: &Configuration,
    key: &str,
    (i, j, a, b, d, core): (usize, usize, usize, usize, f64, f64),
    plan: &SitesPlan,
) -> SceneError {
    let kind = |m: usize, s: usize| {
        let t = &plan.types[config.species[m] as usize];
        plan.kinds[t.site_species()[s] as usize].clone()
    };
    SceneError::invalid(
        key,
        format!(
            "molecules {i} and {j} overlap at the start: site {a} (`{}`) of {i} and site {b} \
             (`{}`) of {j} are {d:.6} apart, inside their hard core {core}; lower the density \
             or choose other positions or orientations",
            kind(i, a),
            kind(j, b)
        ),
    )
}

/// A unit quaternion uniform on SO(3) (a normalised 4-D Gaussian).
fn random_quaternion(rng: &mut Xoshiro256PlusPlus) -> DQuat {
    loop {
        let c: [f64; 4] = std::array::from_fn(|_| StandardNormal.sample(rng));
        let q = DQuat::from_xyzw(c[0], c[1], c[2], c[3]);
        if q.length_squared() > 1e-6 {
            return q.normalize();
        }
    }
}
