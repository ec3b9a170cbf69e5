//! Which model a scene builds: [`Plan`] is the one place that branches on the body kind
//! (stepped spheres, terraced rods or tops of a potential kind, rigid site molecules,
//! semi-flexible molecules, hard spherocylinders). [`Plan::of`] decides it with the tables of that model; the plan
//! then answers what the driver asks of a body kind (its reach and name, how frames draw it,
//! whether its bodies rotate, how a start file gives its molecules) and builds the model for
//! a [`UseModel`], which receives it as a type: the event loop stays statically dispatched
//! per model.

use std::path::Path;

use collide::Particle;
use glam::{DQuat, DVec3};

use crate::analysis::output::Drawing;
use crate::analysis::site_rdf::MoleculeSites;
use crate::analysis::smooth::Evaluate;
use crate::config::init::{
    Configuration, FileMolecules, MoleculeShape, read_attitudes, read_molecules, rod_semi_axes,
};
use crate::config::kinds::{self, Built, Kind, TerracedPlan, Visit};
use crate::config::rods::Bodies;
use crate::config::scene::{Orientations, Scene, SceneError};
use crate::config::spherocylinder_scene::{self, SpherocylindersPlan};
use crate::config::{flexible_scene, site_scene};
use crate::engine::model::{HardSpheres, PairModel, Stepped};
use crate::engine::potential::Potentials;
use crate::models::rotor::TopInertia;

/// What a built model is handed to (the driver's run, generic over the model).
pub trait UseModel {
    /// What it gives.
    type Out;
    /// Takes the model and, for a terraced scene, the smooth estimator of its potential.
    fn use_model<M: PairModel + Send + 'static>(
        self,
        model: M,
        smooth: Option<Box<dyn Evaluate>>,
    ) -> Self::Out;
}

/// What building a model needs besides its plan.
pub struct ModelStart<'a> {
    /// The checked scene in internal units.
    pub scene: &'a Scene,
    /// The folder the scene's relative paths start from.
    pub base: &'a Path,
    /// The bodies' configuration.
    pub config: &'a Configuration,
    /// The state comes from a checkpoint afterwards (the model's own start is a placeholder).
    pub resumed: bool,
    /// The start file (`init.file` below `base`).
    pub start_file: &'a Path,
    /// A start file's angular velocities of rods, tops and rigid molecules.
    pub omegas: Option<Vec<DVec3>>,
    /// A start file's semi-flexible molecules ([`Plan::read_molecules`]).
    pub molecules: Option<FileMolecules>,
}

/// How trajectory frames draw a plan's bodies ([`Plan::drawings`]).
pub struct Drawings {
    /// One per species.
    pub species: Vec<Drawing>,
    /// The site kinds of semi-flexible molecules with their diameters (else empty).
    pub kinds: Vec<(String, f64)>,
    /// The principal moments of each species' body frame (empty for bodies without one).
    pub moments: Vec<[f64; 3]>,
}

/// Checks the keys of the scene's body kind, in the order that decides which error a bad scene
/// reports: site molecules (and their bonds), or the pair tables of spheres and terraced
/// bodies, with the other kinds' keys refused.
///
/// # Errors
/// [`SceneError`] naming the key.
pub fn check_bodies(scene: &Scene) -> Result<(), SceneError> {
    if spherocylinder_scene::is_spherocylinders(scene) {
        spherocylinder_scene::check(scene)?;
        // What molecules' keys the spherocylinders' own check leaves to their modules.
        site_scene::refuse_site_keys(scene)?;
        flexible_scene::refuse_keys(scene)?;
    } else if scene.has_sites() {
        site_scene::check(scene)?;
        if scene.has_bonds() {
            flexible_scene::check(scene)?;
        } else {
            flexible_scene::refuse_keys(scene)?;
        }
    } else {
        site_scene::refuse_site_keys(scene)?;
        flexible_scene::refuse_keys(scene)?;
        scene.check_pair_tables()?;
    }
    Ok(())
}

/// The interaction model a scene asks for, built (scene in internal units).
pub enum Plan {
    /// Stepped radial potentials (given as steps, or Lennard-Jones terraces made radial).
    Spheres(Potentials),
    /// Rods or tops on the terraces of a smooth potential (its kind's tables).
    Terraced(TerracedPlan),
    /// Rigid site molecules with stepped site–site potentials.
    Sites(site_scene::SitesPlan),
    /// Semi-flexible molecules (species with `bonds`): RATTLE between events; species without
    /// bonds among them are rigid molecules on their exact free motion.
    Flexible(flexible_scene::FlexiblePlan),
    /// Hard spherocylinders (species with a `shape`): no potential but the hard shells.
    Spherocylinders(SpherocylindersPlan),
}

impl Plan {
    /// Builds the model tables of a checked scene in internal units.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the pair table whose potential or terraces fail.
    pub fn of(scene: &Scene) -> Result<Plan, SceneError> {
        if spherocylinder_scene::is_spherocylinders(scene) {
            return Ok(Plan::Spherocylinders(SpherocylindersPlan::of(scene)?));
        }
        if scene.has_bonds() {
            return Ok(Plan::Flexible(flexible_scene::FlexiblePlan::of(scene)?));
        }
        if scene.has_sites() {
            return Ok(Plan::Sites(site_scene::SitesPlan::of(scene)?));
        }
        match scene.pair.first().and_then(|p| p.potential) {
            None => Ok(Plan::Spheres(Potentials::from_scene(scene))),
            Some(first) => Ok(match kinds::plan(scene, first)? {
                Built::Radial(tables) => {
                    Plan::Spheres(Potentials::from_tables(scene.species.len(), &tables))
                }
                Built::Terraced(plan) => Plan::Terraced(plan),
            }),
        }
    }

    /// The interaction reach (the largest of all pairs).
    pub fn reach(&self) -> f64 {
        match self {
            Plan::Spheres(p) => p.reach(),
            Plan::Terraced(t) => t.reach,
            Plan::Sites(p) => p.reach(),
            Plan::Flexible(p) => p.reach(),
            Plan::Spherocylinders(p) => p.reach(),
        }
    }

    /// The model's name in the summary.
    pub fn name(&self) -> &'static str {
        match self {
            Plan::Spheres(p) if p.all_hard_spheres() => "hard-spheres",
            Plan::Spheres(_) => "stepped",
            Plan::Terraced(t) => t.model_name,
            Plan::Sites(_) => "rigid-sites",
            Plan::Flexible(_) => "semi-flexible",
            Plan::Spherocylinders(_) => "hard-spherocylinders",
        }
    }

    /// Hard spheres (the model without levels).
    pub fn is_hard_spheres(&self) -> bool {
        matches!(self, Plan::Spheres(p) if p.all_hard_spheres())
    }

    /// The bodies carry an attitude and angular velocity (rods, tops, rigid molecules), so a
    /// start file may give their angular velocities.
    pub fn rotates(&self) -> bool {
        matches!(
            self,
            Plan::Terraced(_) | Plan::Sites(_) | Plan::Spherocylinders(_)
        )
    }

    /// The smallest hard-core diameter of stepped spheres or spherocylinders (0 for other
    /// bodies): a lattice denser than it allows holds no species.
    pub fn smallest_core(&self) -> f64 {
        let core = match self {
            Plan::Spheres(potentials) => potentials
                .all()
                .iter()
                .filter_map(|p| p.core())
                .fold(f64::INFINITY, f64::min),
            Plan::Spherocylinders(p) => p.smallest_diameter(),
            _ => 0.0,
        };
        if core.is_finite() { core } else { 0.0 }
    }

    /// The fewest events between re-basings by default. A signal stops a run at its next
    /// re-basing, so the interval is also how long a stop can take: 10⁶ events of spheres or
    /// rods take about a second; an event of rigid-site or semi-flexible molecules costs tens of
    /// times more (site searches, RATTLE), so theirs is 10⁴, and a re-basing still costs about
    /// 1 % of the run (every pair predicted once against `100 N` events); spherocylinders'
    /// conservative advancement costs several times a sphere's event, so theirs is 10⁵.
    pub fn fewest_rebase_events(&self) -> u64 {
        match self {
            Plan::Sites(_) | Plan::Flexible(_) => 10_000,
            Plan::Spherocylinders(_) => 100_000,
            Plan::Spheres(_) | Plan::Terraced(_) => 1_000_000,
        }
    }

    /// Semi-flexible molecules from a start file of their atoms (`None` for other bodies, and
    /// for a file of the molecules' centres).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming `init.file` or `init.velocities` ([`read_molecules`]).
    pub fn read_molecules(
        &self,
        scene: &Scene,
        start_file: &Path,
    ) -> Result<Option<FileMolecules>, SceneError> {
        let Plan::Flexible(p) = self else {
            return Ok(None);
        };
        let shapes: Vec<MoleculeShape> = p
            .types
            .iter()
            .map(|t| MoleculeShape {
                kinds: t
                    .site_species()
                    .iter()
                    .map(|&k| p.kinds[k as usize].clone())
                    .collect(),
                masses: t.masses().to_vec(),
            })
            .collect();
        read_molecules(scene, start_file, &shapes)
    }

    /// How trajectory frames draw each species: spheres of their hard-core diameter (or
    /// innermost step), rods as the ellipsoids of their potential ([`rod_semi_axes`]), tops
    /// as their kind draws them, rigid site molecules as their sites, semi-flexible molecules
    /// as their atoms, spherocylinders as the ellipsoids of their length and width; with the
    /// moments of inertia of each species' body frame.
    pub fn drawings(&self, scene: &Scene) -> Drawings {
        let diameter =
            |p: &crate::engine::potential::StepPotential| p.core().unwrap_or(p.radii()[0]);
        let n = scene.species.len() as u32;
        let rod = |name: &str| {
            // The like pair's potential, else the first pair the species is in.
            let pairs = || {
                scene
                    .pair
                    .iter()
                    .filter(|p| p.species.iter().any(|s| s == name))
            };
            pairs()
                .find(|p| p.species[0] == p.species[1])
                .into_iter()
                .chain(pairs())
                .find_map(|p| p.potential.as_ref().and_then(rod_semi_axes))
                .unwrap_or([0.5; 3])
        };
        match self {
            Plan::Spheres(potentials) => Drawings {
                species: (0..n)
                    .map(|s| Drawing::Sphere {
                        diameter: diameter(potentials.get(s, s)),
                    })
                    .collect(),
                kinds: Vec::new(),
                moments: Vec::new(),
            },
            Plan::Terraced(t) => Drawings {
                species: scene
                    .species
                    .iter()
                    .map(|s| match t.spec.describe().drawing() {
                        Drawing::Rod { .. } => Drawing::Rod {
                            semi_axes: rod(&s.name),
                        },
                        d => d,
                    })
                    .collect(),
                kinds: Vec::new(),
                // A rod's moments, or a top's as its model takes them (a rounded planar body
                // made planar).
                moments: scene
                    .species
                    .iter()
                    .map(|s| match (s.inertia, s.moments) {
                        (Some(i), _) => [i, i, 0.0],
                        (None, Some(m)) => {
                            TopInertia::new(DVec3::from(m)).map_or(m, |t| t.principal().to_array())
                        }
                        (None, None) => [0.0; 3],
                    })
                    .collect(),
            },
            Plan::Sites(p) => Drawings {
                species: p
                    .types
                    .iter()
                    .map(|t| Drawing::Sites {
                        centres: t.sites().to_vec(),
                        diameters: t
                            .site_species()
                            .iter()
                            .map(|&k| diameter(p.potentials.get(k, k)))
                            .collect(),
                    })
                    .collect(),
                kinds: Vec::new(),
                moments: p.types.iter().map(|t| t.moments().to_array()).collect(),
            },
            Plan::Flexible(p) => Drawings {
                species: p
                    .types
                    .iter()
                    .map(|t| Drawing::Atoms {
                        kinds: t.site_species().to_vec(),
                        masses: t.masses().to_vec(),
                    })
                    .collect(),
                kinds: p
                    .kinds
                    .iter()
                    .enumerate()
                    .map(|(k, name)| (name.clone(), diameter(p.potentials.get(k as u32, k as u32))))
                    .collect(),
                moments: Vec::new(),
            },
            Plan::Spherocylinders(p) => Drawings {
                species: p
                    .species
                    .iter()
                    .map(|s| Drawing::Rod {
                        semi_axes: [
                            0.5 * s.diameter,
                            0.5 * s.diameter,
                            0.5 * (s.length + s.diameter),
                        ],
                    })
                    .collect(),
                kinds: Vec::new(),
                moments: p
                    .species
                    .iter()
                    .map(|s| [s.inertia, s.inertia, 0.0])
                    .collect(),
            },
        }
    }

    /// The named sites of each species for the site–site g(r) of `output.rdf`: tops of a
    /// kind with several sites (SPC/E: O, H, H), and rigid site molecules (their sites named
    /// by their site kinds); `None` for bodies without named sites in a rigid frame (spheres,
    /// rods, tops of one site such as SSD/E, semi-flexible molecules, spherocylinders).
    pub fn sites(&self, scene: &Scene) -> Option<Vec<MoleculeSites>> {
        match self {
            Plan::Terraced(t) => {
                let sites = t.spec.describe().sites()?;
                Some(vec![sites; scene.species.len()])
            }
            Plan::Sites(p) => Some(
                p.types
                    .iter()
                    .map(|t| MoleculeSites {
                        names: t
                            .site_species()
                            .iter()
                            .map(|&k| p.kinds[k as usize].clone())
                            .collect(),
                        offsets: t.sites().to_vec(),
                    })
                    .collect(),
            ),
            Plan::Spheres(_) | Plan::Flexible(_) | Plan::Spherocylinders(_) => None,
        }
    }

    /// The general stepped model of sphere scenes, which HMC's fault injection runs on, with
    /// the smooth estimator of Lennard-Jones spheres on terraces.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming `hmc.fault_fraction` for other bodies.
    pub fn fault_model(
        self,
        scene: &Scene,
        config: &Configuration,
    ) -> Result<(Stepped, Option<Box<dyn Evaluate>>), SceneError> {
        let Plan::Spheres(potentials) = self else {
            return Err(SceneError::invalid(
                "hmc.fault_fraction",
                "fault injection hides pairs of the analytic sphere models; it is not available \
                 for rods"
                    .to_owned(),
            ));
        };
        let n = config.positions.len();
        Ok((
            Stepped::new(potentials, particles(scene), n),
            radial_smooth(scene, config)?,
        ))
    }

    /// Builds the model of the plan from `start` and hands it to `user`.
    ///
    /// # Errors
    /// [`SceneError`] of a start the model refuses (overlaps, unreadable attitudes …).
    pub fn build<U: UseModel>(self, start: ModelStart<'_>, user: U) -> Result<U::Out, SceneError> {
        let ModelStart {
            scene,
            base,
            config,
            resumed,
            start_file,
            omegas,
            molecules,
        } = start;
        let n = config.positions.len();
        Ok(match self {
            Plan::Spheres(potentials) => {
                let smooth = radial_smooth(scene, config)?;
                if potentials.all_hard_spheres() {
                    user.use_model(HardSpheres::new(potentials, particles(scene)), smooth)
                } else {
                    user.use_model(Stepped::new(potentials, particles(scene), n), smooth)
                }
            }
            Plan::Terraced(plan) => {
                let spec = plan.spec;
                spec.visit(TerracedBuild {
                    scene,
                    base,
                    config,
                    plan,
                    omegas: omegas.as_deref(),
                    user,
                })?
            }
            Plan::Sites(plan) => {
                let attitudes: Option<Vec<DQuat>> = match (resumed, scene.init.orientations) {
                    (false, Orientations::File) => {
                        Some(read_attitudes(scene, start_file, n, "init.orientations")?)
                    }
                    _ => None,
                };
                let model = site_scene::model(scene, config, plan, resumed, attitudes, omegas)?;
                user.use_model(model, None)
            }
            Plan::Flexible(plan) => {
                let start = molecules.map(|m| (m.atoms, m.internal));
                let model = flexible_scene::model(scene, config, plan, resumed, start)?;
                user.use_model(model, None)
            }
            Plan::Spherocylinders(plan) => {
                let model =
                    spherocylinder_scene::model(scene, base, config, plan, resumed, omegas)?;
                user.use_model(model, None)
            }
        })
    }
}

/// Lennard-Jones spheres on terraces run as radial steps; their smooth potential is still the
/// scene's: its estimator (none for other spheres).
fn radial_smooth(
    scene: &Scene,
    config: &Configuration,
) -> Result<Option<Box<dyn Evaluate>>, SceneError> {
    if scene.has_terraced_smooth_potential() {
        kinds::radial_estimator(scene, config.lengths)
    } else {
        Ok(None)
    }
}

/// The scene's species as particles of their masses.
fn particles(scene: &Scene) -> Vec<Particle> {
    scene
        .species
        .iter()
        .map(|s| Particle::new(s.mass).expect("masses are checked"))
        .collect()
}

/// Builds the terraced model of kind `K` (and its smooth estimator) from its plan.
struct TerracedBuild<'a, U> {
    scene: &'a Scene,
    base: &'a Path,
    config: &'a Configuration,
    plan: TerracedPlan,
    omegas: Option<&'a [DVec3]>,
    user: U,
}

impl<U: UseModel> Visit for TerracedBuild<'_, U> {
    type Out = Result<U::Out, SceneError>;

    fn visit<K: Kind>(self, _: &K) -> Self::Out {
        let tables = self.plan.take::<K>();
        let smooth = <K::Terraced as Bodies>::estimator(self.scene, self.config.lengths, &tables)?;
        let model = <K::Terraced as Bodies>::model(
            self.scene,
            self.base,
            self.config,
            tables,
            self.omegas,
        )?;
        Ok(self.user.use_model(model, smooth))
    }
}
