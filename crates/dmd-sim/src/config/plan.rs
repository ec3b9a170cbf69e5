//! Which model a scene builds: [`Plan::of`] is the one place that decides it from the body
//! kind (stepped spheres, terraced rods or tops of a potential kind, rigid site molecules,
//! semi-flexible molecules), with the tables of that model.

use crate::config::kinds::{self, Built, TerracedPlan};
use crate::config::scene::{Scene, SceneError};
use crate::engine::potential::Potentials;

/// The interaction model a scene asks for, built (scene in internal units).
pub enum Plan {
    /// Stepped radial potentials (given as steps, or Lennard-Jones terraces made radial).
    Spheres(Potentials),
    /// Rods or tops on the terraces of a smooth potential (its kind's tables).
    Terraced(TerracedPlan),
    /// Rigid site molecules with stepped site–site potentials.
    Sites(crate::config::site_scene::SitesPlan),
    /// Semi-flexible molecules (species with `bonds`): RATTLE between events.
    Flexible(crate::config::flexible_scene::FlexiblePlan),
}

impl Plan {
    /// Builds the model tables of a checked scene in internal units.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the pair table whose potential or terraces fail.
    pub fn of(scene: &Scene) -> Result<Plan, SceneError> {
        if scene.has_bonds() {
            return Ok(Plan::Flexible(
                crate::config::flexible_scene::FlexiblePlan::of(scene)?,
            ));
        }
        if scene.has_sites() {
            return Ok(Plan::Sites(crate::config::site_scene::SitesPlan::of(
                scene,
            )?));
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
        }
    }
}
