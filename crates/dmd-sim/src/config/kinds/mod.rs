//! The kinds of smooth pair potential a scene can name (`pair.potential.kind`), as plug-ins.
//!
//! The keys of each kind are a struct in [`scene`](crate::config::scene), listed by
//! [`PotentialSpec`]. Each kind has one module here with its
//! [`Describe`] implementation (checks, energy and length scales, drawing) and its [`Kind`]
//! implementation: the terraces the event-driven engine builds on it and the force field the
//! standard-MD engine integrates (and its potential, when the `potential` crate does not have
//! it). [`PotentialSpec::describe`] and [`PotentialSpec::visit`] are the only places in the
//! program that branch on the kind. Hot paths stay statically dispatched: a [`Visit`]or is
//! generic over the kind, so each engine is compiled once per kind.
//!
//! Adding a kind takes three files: its keys in `scene` (a struct, a [`PotentialSpec`]
//! variant and its arm in `describe`), its module here, and its arm in
//! [`PotentialSpec::visit`].

mod biaxial_gay_berne;
mod gay_berne;
mod lennard_jones;
mod lj_rods;
mod spc_e;
mod ssd_e;
mod stockmayer;

use std::any::Any;
use std::fmt::Debug;

use crate::config::rods::Bodies;
use crate::config::scene::{Describe, PotentialSpec, Scene, SceneError, TerraceSpec};
use crate::models::terraced::{PairTable, PairTerraces};

pub use stockmayer::Stockmayer;

impl PotentialSpec {
    /// Hands the kind, as a type, to `v`: the engines' generic code is compiled per kind.
    /// Rods with `ζ = 0` are Lennard-Jones spheres and run as those.
    pub fn visit<V: Visit>(&self, v: V) -> V::Out {
        match self {
            PotentialSpec::Rods(k) if k.zeta == 0.0 => v.visit(&k.as_spheres()),
            PotentialSpec::Rods(k) => v.visit(k),
            PotentialSpec::LennardJones(k) => v.visit(k),
            PotentialSpec::GayBerne(k) => v.visit(k),
            PotentialSpec::SsdE(k) => v.visit(k),
            PotentialSpec::Stockmayer(k) => v.visit(k),
            PotentialSpec::BiaxialGayBerne(k) => v.visit(k),
            PotentialSpec::SpcE(k) => v.visit(k),
        }
    }
}

/// A kind, as a type: what each engine builds from it (scene in internal units).
pub trait Kind: Describe + Copy + 'static {
    /// The model name in the event-driven engine's summary.
    const MODEL: &'static str;
    /// What the event-driven engine terraces (and the bodies it acts between).
    type Terraced: Bodies + Clone + Debug + Send + 'static;
    /// What the standard-MD engine integrates.
    type Smd: smd::Interaction;

    /// The kind's keys from a pair table of the same kind (`None` for another kind).
    fn select(spec: &PotentialSpec) -> Option<Self>;

    /// Radial steps for isotropic potentials (run as stepped spheres, with analytic event
    /// times), from pair table `k`'s terraces `t`; `None` for the others.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the pair table.
    fn radial_steps(
        &self,
        k: usize,
        t: &TerraceSpec,
        kt: f64,
        scale: f64,
    ) -> Option<Result<Vec<[f64; 2]>, SceneError>> {
        let _ = (k, t, kt, scale);
        None
    }

    /// The terraces of pair table `k` (`t`, at temperature `kt`; `scale` converts energies
    /// in messages back to the scene's units).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the pair table.
    fn terraces(
        &self,
        k: usize,
        t: &TerraceSpec,
        kt: f64,
        scale: f64,
    ) -> Result<PairTerraces<Self::Terraced>, SceneError>;

    /// The standard-MD force field, smoothed over `window = (r_l, r_u)` (or its own cut-off).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming `pair[0].potential` or `smd.smoothing`.
    fn smd(&self, window: (f64, f64)) -> Result<Self::Smd, SceneError>;
}

/// Code generic over the kind, run by [`PotentialSpec::visit`].
pub trait Visit {
    /// What it returns.
    type Out;
    /// Runs on kind `K` (the first pair table's keys).
    fn visit<K: Kind>(self, kind: &K) -> Self::Out;
}

/// The terraced pair tables of a scene, built for one kind; the type is the kind's, erased
/// until the engine is built ([`TerracedPlan::take`]).
pub struct TerracedPlan {
    /// The first pair table's potential: its kind picks the engine's type.
    pub spec: PotentialSpec,
    /// `Vec<PairTable<K::Terraced>>`.
    tables: Box<dyn Any + Send>,
    /// The interaction reach (the largest of all pairs).
    pub reach: f64,
    /// The model name in the summary.
    pub model_name: &'static str,
}

impl TerracedPlan {
    /// The tables of kind `K`.
    ///
    /// # Panics
    /// If the plan was built for another kind (visit it with its own `spec`).
    pub fn take<K: Kind>(self) -> Vec<PairTable<K::Terraced>> {
        *self
            .tables
            .downcast::<Vec<PairTable<K::Terraced>>>()
            .expect("a terraced plan is taken by the kind that built it")
    }
}

/// What [`plan`] builds: radial steps (isotropic kinds) or terraced tables.
pub enum Built {
    /// `((species a, species b), steps)` per pair table.
    Radial(Vec<crate::engine::potential::PairTable>),
    /// Terraced tables.
    Terraced(TerracedPlan),
}

/// Builds the tables of a scene whose pairs have smooth potentials (internal units).
///
/// # Errors
/// [`SceneError::Invalid`] naming the pair table whose potential or terraces fail.
pub fn plan(scene: &Scene, first: PotentialSpec) -> Result<Built, SceneError> {
    struct Build<'a> {
        scene: &'a Scene,
        first: PotentialSpec,
    }
    impl Visit for Build<'_> {
        type Out = Result<Built, SceneError>;
        fn visit<K: Kind>(self, _: &K) -> Self::Out {
            let mut radial = Vec::new();
            let mut tables: Vec<PairTable<K::Terraced>> = Vec::new();
            each_pair::<K>(self.scene, |k, pair, kind, t, kt, scale| {
                match kind.radial_steps(k, t, kt, scale) {
                    Some(steps) => radial.push((pair, steps?)),
                    None => tables.push((pair, kind.terraces(k, t, kt, scale)?)),
                }
                Ok(())
            })?;
            if !radial.is_empty() {
                return Ok(Built::Radial(radial));
            }
            let reach = tables.iter().map(|(_, p)| p.reach()).fold(0.0, f64::max);
            Ok(Built::Terraced(TerracedPlan {
                spec: self.first,
                tables: Box::new(tables),
                reach,
                model_name: K::MODEL,
            }))
        }
    }
    first.visit(Build { scene, first })
}

/// Calls `f(k, (species a, species b), keys, terraces, kT, energy scale)` for every pair table
/// `k` of a checked scene of kind `K` (internal units; the scale converts energies in messages
/// back to the scene's).
fn each_pair<K: Kind>(
    scene: &Scene,
    mut f: impl FnMut(usize, (usize, usize), &K, &TerraceSpec, f64, f64) -> Result<(), SceneError>,
) -> Result<(), SceneError> {
    let scale = crate::config::units::Units::of(scene.units).energy;
    let kt = scene.init.temperature;
    let index = |n: &str| {
        scene
            .species
            .iter()
            .position(|s| s.name == n)
            .expect("checked")
    };
    for (k, p) in scene.pair.iter().enumerate() {
        let kind = p
            .potential
            .as_ref()
            .and_then(K::select)
            .expect("checked: one kind per scene");
        let t = p.terraces.as_ref().expect("checked");
        f(
            k,
            (index(&p.species[0]), index(&p.species[1])),
            &kind,
            t,
            kt,
            scale,
        )?;
    }
    Ok(())
}

/// The smooth estimator of a scene whose smooth potentials run as radial steps (Lennard-Jones
/// spheres on terraces): the same estimator as for terraced bodies, over each pair table's
/// smooth potential (`None` when the scene does not want one or its cut-off does not fit a box
/// of `lengths`).
///
/// # Errors
/// [`SceneError::Invalid`] naming the pair table, `output.smooth_estimators` or
/// `smd.smoothing`.
pub fn radial_estimator(
    scene: &Scene,
    lengths: glam::DVec3,
) -> Result<Option<Box<dyn crate::analysis::smooth::Evaluate>>, SceneError> {
    struct Estimate<'a> {
        scene: &'a Scene,
        lengths: glam::DVec3,
    }
    impl Visit for Estimate<'_> {
        type Out = Result<Option<Box<dyn crate::analysis::smooth::Evaluate>>, SceneError>;
        fn visit<K: Kind>(self, _: &K) -> Self::Out {
            let mut tables: Vec<PairTable<K::Terraced>> = Vec::new();
            each_pair::<K>(self.scene, |k, pair, kind, t, kt, scale| {
                tables.push((pair, kind.terraces(k, t, kt, scale)?));
                Ok(())
            })?;
            <K::Terraced as Bodies>::estimator(self.scene, self.lengths, &tables)
        }
    }
    if !scene.wants_smooth_estimators() {
        return Ok(None);
    }
    let Some(first) = scene.pair.first().and_then(|p| p.potential) else {
        return Ok(None);
    };
    first.visit(Estimate { scene, lengths })
}
