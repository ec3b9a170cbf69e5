//! The scene file: what to simulate, read from TOML.
//!
//! A scene is read in three steps, each with its own kind of error:
//!
//! 1. the text is parsed as TOML ([`SceneError::Syntax`], with line and column);
//! 2. `--set KEY=VALUE` overrides are applied to the parsed document
//!    ([`Scene::apply_override`]), so a sweep needs no file edits;
//! 3. the document is read into the typed structs below, which deny unknown keys
//!    ([`SceneError::Key`] names the dotted key, for a file and an override alike), and the
//!    values are checked against each other ([`SceneError::Invalid`], again naming the key).
//!
//! Every key is documented in `docs/USER-GUIDE.md`; the corpus of bad scenes in
//! `tests/integration/scene_errors.rs` pins the message of each kind of mistake.

use std::fmt;
use std::path::PathBuf;

use serde::{Deserialize, Deserializer};

use crate::analysis::output::Drawing;
use crate::analysis::output::given;
use crate::analysis::site_rdf::MoleculeSites;

/// The scene format this version of `dmd` reads.
pub const FORMAT_VERSION: u32 = 1;

/// What is wrong with a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The text is not valid TOML.
    #[error("scene is not valid TOML: {}", clip(.0))]
    Syntax(String),
    /// A key is unknown, missing, or has a value of the wrong type.
    #[error("scene key `{}`: {}", clip(.key), clip(.problem))]
    Key {
        /// Dotted path of the key (`.` for the whole scene).
        key: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A value is of the right type but not acceptable (alone or with others).
    #[error("scene key `{}`: {}", clip(.key), clip(.problem))]
    Invalid {
        /// Dotted path of the key.
        key: String,
        /// What is wrong with it.
        problem: String,
    },
    /// A `--set` argument is malformed.
    #[error("override `{}`: {}", clip(.arg), clip(.problem))]
    Override {
        /// The argument as given.
        arg: String,
        /// What is wrong with it.
        problem: String,
    },
}

/// Longest word of a message quoted whole (longer ones, a value pasted by mistake, are cut).
pub const LONGEST_WORD: usize = 160;
/// Longest line of a message quoted whole.
pub const LONGEST_LINE: usize = 600;

/// A message part as shown: every word longer than [`LONGEST_WORD`] characters and every line
/// longer than [`LONGEST_LINE`] cut with `…` and the count of characters left out, so that a
/// message never echoes a huge input.
pub fn clip(text: &str) -> String {
    let mut out = String::with_capacity(text.len().min(4 * LONGEST_LINE));
    for (k, line) in text.split('\n').enumerate() {
        if k > 0 {
            out.push('\n');
        }
        let mut shown = String::new();
        for (w, word) in line.split(' ').enumerate() {
            if w > 0 {
                shown.push(' ');
            }
            let n = word.chars().count();
            if n > LONGEST_WORD {
                shown.extend(word.chars().take(LONGEST_WORD / 2));
                shown.push_str(&format!("… ({} more characters)", n - LONGEST_WORD / 2));
            } else {
                shown.push_str(word);
            }
        }
        let n = shown.chars().count();
        if n > LONGEST_LINE {
            out.extend(shown.chars().take(LONGEST_LINE));
            out.push_str(&format!("… ({} more characters)", n - LONGEST_LINE));
        } else {
            out.push_str(&shown);
        }
    }
    out
}

impl SceneError {
    pub(crate) fn invalid(key: impl Into<String>, problem: impl Into<String>) -> Self {
        SceneError::Invalid {
            key: key.into(),
            problem: problem.into(),
        }
    }
}

/// A whole scene.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Format version; must be [`FORMAT_VERSION`].
    pub version: u32,
    /// Seed of every random number of the run (initial velocities, thermostat).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// The unit system of every number in the scene (default `reduced`).
    #[serde(default)]
    pub units: UnitSystem,
    /// The periodic box.
    #[serde(rename = "box")]
    pub box_: BoxSpec,
    /// Species of bodies, with their counts and masses.
    pub species: Vec<SpeciesSpec>,
    /// Pair potentials, one per unordered pair of species.
    #[serde(default)]
    pub pair: Vec<PairSpec>,
    /// Initial positions and velocities.
    pub init: InitSpec,
    /// Thermostat (off unless given).
    #[serde(default)]
    pub thermostat: ThermostatSpec,
    /// Run length, queue and numerical settings.
    pub run: RunSpec,
    /// What is written besides `summary.json`.
    #[serde(default)]
    pub output: OutputSpec,
    /// Root searches of event times (terraced potentials of rods only).
    pub search: Option<SearchSpec>,
    /// Hybrid Monte Carlo (off unless given).
    #[serde(default)]
    pub hmc: Option<HmcSpec>,
    /// Independent chains of the scene run in parallel.
    #[serde(default)]
    pub chains: Option<ChainsSpec>,
    /// A parameter sweep: the scene run once per value of a key.
    #[serde(default)]
    pub sweep: Option<SweepSpec>,
    /// The engine: `dmd` (event-driven, default) or `smd` (standard MD).
    #[serde(default)]
    pub engine: Engine,
    /// Settings of the standard-MD engine (ignored by the event-driven one).
    #[serde(default)]
    pub smd: Option<SmdSpec>,
    /// Site–site potentials of rigid site molecules, one per unordered pair of site kinds.
    #[serde(default)]
    pub site_pair: Vec<SitePairSpec>,
    /// How events of rigid site molecules are executed.
    pub impulse: Option<ImpulseSpec>,
    /// The RATTLE integration of semi-flexible molecules (species with `bonds`).
    pub rattle: Option<RattleSpec>,
}

/// The unit system of a scene's numbers.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum UnitSystem {
    /// Numbers as they are, with Boltzmann's constant 1 (temperatures are energies).
    #[default]
    Reduced,
    /// Lengths in Å, masses in g/mol, energies in kJ/mol, times in ps, temperatures in K,
    /// moments of inertia in g/mol·Å² (see the `units` module).
    Molecular,
}

// ----- Hybrid Monte Carlo, chains and sweeps -----------------------------------------------------

/// The ensemble an HMC chain samples.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum EnsembleKind {
    /// Gaussian momenta at `hmc.temperature`, Metropolis acceptance.
    #[default]
    Canonical,
    /// Velocity exchanges, acceptance only if the energy did not change.
    Microcanonical,
}

/// How HMC segments are accepted.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum AcceptKind {
    /// The HMC rule (default).
    #[default]
    Metropolis,
    /// Every segment: plain dynamics with momentum refreshes (a validation comparison).
    Always,
}

/// Which configuration measure a canonical HMC chain samples (`hmc.measure`).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum MeasureKind {
    /// The measure the dynamics samples (default): with bonds, it carries `√det Z`.
    #[default]
    Dynamics,
    /// The limit of infinitely stiff bonds (semi-flexible molecules only).
    StiffBonds,
}

/// `[hmc]`: event-driven segments inside a hybrid Monte Carlo chain (seed 000 §V).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HmcSpec {
    /// `canonical` (default) or `microcanonical`.
    #[serde(default)]
    pub ensemble: EnsembleKind,
    /// Simulated time of a segment, τ.
    pub segment_time: f64,
    /// Production segments.
    #[serde(deserialize_with = "count")]
    pub segments: u64,
    /// Segments before production (not recorded).
    #[serde(default, deserialize_with = "count")]
    pub equilibration_segments: u64,
    /// Temperature of the canonical chain (default `init.temperature`); the energy unit of the
    /// ΔH histogram of a microcanonical one.
    pub temperature: Option<f64>,
    /// Velocity exchanges per segment (microcanonical; default N).
    #[serde(default, deserialize_with = "opt_count")]
    pub exchanges: Option<u64>,
    /// Relative tolerance on ΔH within which it is round-off (default 1e-9).
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// `metropolis` (default) or `always`.
    #[serde(default)]
    pub accept: AcceptKind,
    /// `dynamics` (default) or `stiff-bonds`.
    #[serde(default)]
    pub measure: MeasureKind,
    /// Validation: fraction of pairs blind to their events in each segment (default 0).
    #[serde(default)]
    pub fault_fraction: f64,
    /// Write `hmc.csv`, one row per production segment.
    #[serde(default)]
    pub series: bool,
    /// Bins of the ΔH histogram (default 40).
    #[serde(default = "default_histogram_bins", deserialize_with = "count")]
    pub histogram_bins: u64,
    /// Half width of the ΔH histogram in units of the temperature (default 10).
    #[serde(default = "default_histogram_range")]
    pub histogram_range: f64,
}

/// Default of `output.max_bytes`: 4 GB for any one output (in memory or on disk).
pub const DEFAULT_MAX_BYTES: u64 = 4_000_000_000;

/// Largest |ΔU| of a finite step, in the scene's energy unit: far beyond any physical energy,
/// and far enough below `f64::MAX` (1.8e308) that sums over any number of pairs stay finite.
pub const MAX_STEP_ENERGY: f64 = 1e100;

/// Which engine runs a scene.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Engine {
    /// The event-driven engine (default).
    #[default]
    Dmd,
    /// Standard MD of the `smd` crate on the smoothed continuous potential.
    Smd,
}

/// `[smd]`: the numerical settings of the standard-MD engine.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SmdSpec {
    /// Time step, in the scene's time unit (default: `smd_spec::default_dt`).
    pub dt: Option<f64>,
    /// Verlet-list skin, a length (default 0.6σ, the measured optimum of docs/PERFORMANCE.md).
    pub skin: Option<f64>,
    /// The window of 003 Eq. 26 over which the potential is switched off.
    pub smoothing: Option<SmoothingSpec>,
    /// Stop if the total energy leaves its value after equilibration by more than this
    /// fraction of `K + |U|` (default 0.1; `inf` turns it off).
    pub guard: Option<f64>,
}

/// The smoothing window of 003 Eq. 26.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SmoothingSpec {
    /// Where the switch starts (default 2.5σ).
    pub r_l: Option<f64>,
    /// Where the potential reaches zero: the cut-off (default 3σ).
    pub r_u: Option<f64>,
}

fn default_tolerance() -> f64 {
    1e-9
}

fn default_histogram_bins() -> u64 {
    40
}

fn default_histogram_range() -> f64 {
    10.0
}

/// `[chains]`: independent copies of the scene with their own seeds.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ChainsSpec {
    /// Number of chains.
    #[serde(deserialize_with = "count")]
    pub count: u64,
}

/// `[sweep]`: the scene run once per value of one key.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// The dotted key (as for `--set`).
    pub key: String,
    /// Its values.
    pub values: Vec<toml::Value>,
}

fn default_seed() -> u64 {
    1
}

/// The periodic box: `density` (with `aspect`) or explicit `lengths`.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Number density N/V; the box is sized to hold all bodies at it.
    pub density: Option<f64>,
    /// Edge lengths (Lx, Ly, Lz).
    pub lengths: Option<[f64; 3]>,
    /// Proportions of the edges when the box is sized from `density` (default cubic).
    pub aspect: Option<[f64; 3]>,
}

/// One species.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpeciesSpec {
    /// Name, used by pair tables and written to trajectories.
    pub name: String,
    /// Number of bodies.
    #[serde(deserialize_with = "count")]
    pub count: u64,
    /// Mass (default 1).
    #[serde(default = "one")]
    pub mass: f64,
    /// The chemical element trajectories give the species' bodies (the `Z` column of
    /// `trajectory.xyz`, which ASE types atoms by): a symbol such as `O` or `Ar`, or `X` for
    /// none (default: the name when it is a chemical symbol, else `X`).
    pub element: Option<String>,
    /// Moment of inertia about an axis through the centre perpendicular to the body's own:
    /// the body is a rod (a linear rotor, 003 §V). Spheres have none.
    pub inertia: Option<f64>,
    /// Principal moments of inertia `[I_x, I_y, I_z]` about the body axes of a rigid body of
    /// any shape (an asymmetric top), for potentials that read each body's whole attitude
    /// (`ssd-e`, `spc-e`, `biaxial-gay-berne`).
    pub moments: Option<[f64; 3]>,
    /// The shape of a hard body whose model reads its own keys: `kind` names the model, whose
    /// scene module checks the other keys of the table (module `config::plan`).
    pub shape: Option<toml::Table>,
    /// The atoms of a rigid site molecule.
    pub sites: Option<Vec<SiteSpec>>,
    /// Or: a shipped rigid site molecule.
    pub molecule: Option<MoleculeSpec>,
    /// Distance constraints `[a, b]` between sites (0-based indices into `sites`), lengths as
    /// given by the positions: the species is a semi-flexible molecule.
    pub bonds: Option<Vec<[i64; 2]>>,
    /// Sites of one semi-flexible molecule more than this many bonds apart (along the
    /// shortest bond path) interact with each other through their `site_pair` table, as sites
    /// of different molecules do (default: sites of one molecule do not interact).
    pub interact_beyond_bonds: Option<i64>,
}

/// `[rattle]`: the RATTLE integration of the internal motion of semi-flexible molecules.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RattleSpec {
    /// The step `h` (default from the thermal atom speed and the shortest bond,
    /// `flexible_scene::STEP_BOND_FRACTION`).
    pub step: Option<f64>,
    /// Relative tolerance of the SHAKE and velocity iterations (default 1e-12).
    #[serde(default = "rattle_tolerance")]
    pub tolerance: f64,
    /// Reset each molecule's internal kinetic energy at events to its conserved value (default
    /// true).
    #[serde(default = "yes")]
    pub rescale: bool,
}

fn rattle_tolerance() -> f64 {
    1e-12
}

// ----- Rigid site molecules ----------------------------------------------------------------------

/// One atom (site) of a rigid molecule.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SiteSpec {
    /// Site kind: names the site–site potentials (`site_pair`).
    pub kind: String,
    /// Mass.
    pub mass: f64,
    /// Position in any frame (the centre of mass and principal axes are found).
    pub position: [f64; 3],
}

/// A shipped rigid site molecule (`sites::molecules`).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum MoleculeSpec {
    /// Two sites of kind `A`, unit masses, `elongation` apart (L* = L/σ with σ the `A`–`A`
    /// hard core).
    Dumbbell {
        /// Site separation.
        elongation: f64,
    },
    /// A site of kind `C` (mass 12) inside a tetrahedron of four of kind `H` (mass 1) at 0.32.
    MethaneLike,
    /// A hexagon of six `C` (mass 12) at radius 0.41 with six `H` (mass 1) at 0.73.
    BenzeneLike,
}

/// The stepped potential between two site kinds.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SitePairSpec {
    /// The two site kinds (the same name twice for like pairs).
    pub sites: [String; 2],
    /// `[radius, energy step]` pairs, as `pair.steps`.
    pub steps: Vec<[f64; 2]>,
}

/// Which impulse rule executes the events of site molecules.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum ImpulseRuleSpec {
    /// The impulse at the two sites along the line joining them (000 §IV.B).
    #[default]
    ContactPoint,
    /// Impulses on the atoms plus impulsive constraint forces (000 §IV.A).
    Constrained,
}

/// `[impulse]`: the impulse rule of site molecules.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImpulseSpec {
    /// `contact-point` (default) or `constrained`.
    #[serde(default)]
    pub rule: ImpulseRuleSpec,
    /// Also run the other rule at every event and report how far apart they land.
    #[serde(default)]
    pub cross_check: bool,
}

fn one() -> f64 {
    1.0
}

/// The pair potential between two species: a stepped radial potential (`steps`), or a smooth
/// potential (`potential`) on energy terraces (`terraces`, 003 Eq. 7).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PairSpec {
    /// The two species (the same name twice for like pairs).
    pub species: [String; 2],
    /// `[radius, energy step]` pairs with strictly increasing radii: crossing radius `r`
    /// inwards changes the pair energy by the step (`inf` = hard core, innermost only). The
    /// energy beyond the last radius is zero. Empty when `potential` is given.
    #[serde(default)]
    pub steps: Vec<[f64; 2]>,
    /// A smooth pair potential, simulated on `terraces`.
    pub potential: Option<PotentialSpec>,
    /// The terraces of `potential`.
    pub terraces: Option<TerraceSpec>,
}

/// A smooth pair potential (crate `potential`), by its `kind`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum PotentialSpec {
    /// The modified Lennard-Jones rods of 003 Eqs. 22–23.
    Rods(LjRodsSpec),
    /// Lennard-Jones spheres (003 Eq. 22 with ζ = 0): terraces become radial steps with
    /// analytic event times.
    LennardJones(LennardJonesSpec),
    /// Gay–Berne GB(κ, κ', μ, ν) (defaults GB(3, 5, 2, 1)).
    GayBerne(GayBerneSpec),
    /// Soft sticky dipole water, SSD/E, between rigid tops; molecular units only.
    SsdE(SsdESpec),
    /// Stockmayer rods: Lennard-Jones plus a point dipole along each body's axis.
    Stockmayer(StockmayerSpec),
    /// Biaxial Gay–Berne ellipsoids (Berardi, Fava and Zannoni) between rigid tops.
    BiaxialGayBerne(BiaxialGayBerneSpec),
    /// SPC/E water: three sites, site–site Lennard-Jones and damped shifted force Coulomb,
    /// between rigid tops; molecular units only.
    SpcE(SpcESpec),
}

impl PotentialSpec {
    /// What every kind tells about itself (object safe: checks, scales, drawing).
    pub fn describe(&self) -> &dyn Describe {
        match self {
            PotentialSpec::Rods(k) => k,
            PotentialSpec::LennardJones(k) => k,
            PotentialSpec::GayBerne(k) => k,
            PotentialSpec::SsdE(k) => k,
            PotentialSpec::Stockmayer(k) => k,
            PotentialSpec::BiaxialGayBerne(k) => k,
            PotentialSpec::SpcE(k) => k,
        }
    }

    /// As [`describe`](Self::describe), to change (the conversion to internal units).
    pub fn describe_mut(&mut self) -> &mut dyn Describe {
        match self {
            PotentialSpec::Rods(k) => k,
            PotentialSpec::LennardJones(k) => k,
            PotentialSpec::GayBerne(k) => k,
            PotentialSpec::SsdE(k) => k,
            PotentialSpec::Stockmayer(k) => k,
            PotentialSpec::BiaxialGayBerne(k) => k,
            PotentialSpec::SpcE(k) => k,
        }
    }

    /// Whether the potential depends on the orientations (bodies are rods or tops).
    pub fn is_anisotropic(&self) -> bool {
        self.describe().body() != Body::Sphere
    }

    /// Whether the potential reads each body's whole attitude (bodies are tops with three
    /// `moments`), not one axis.
    pub fn is_rigid(&self) -> bool {
        self.describe().body() == Body::Top
    }

    /// The kind, as written in the scene.
    pub fn kind(&self) -> &'static str {
        self.describe().name()
    }
}

/// The bodies a potential acts between.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Body {
    /// Spheres: no orientation.
    Sphere,
    /// Linear rotors (one axis each; `species.inertia`).
    Rod,
    /// Rigid tops (a whole attitude; `species.moments`).
    Top,
}

/// What the program asks of a kind that needs no type: object safe.
pub trait Describe {
    /// The kind, as written in the scene.
    fn name(&self) -> &'static str;
    /// The bodies it acts between.
    fn body(&self) -> Body;
    /// Checks the keys (`key(name)` is a key's full name, e.g. `pair[0].potential.sigma`).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the first bad key.
    fn check(&self, key: &dyn Fn(&str) -> String) -> Result<(), SceneError>;
    /// Multiplies every energy parameter by `e` (scene → internal units).
    fn scale_energy(&mut self, e: f64);
    /// The depth of the well (energy; the smallest energy parameter for several).
    fn well_depth(&self) -> f64;
    /// σ, and the longest contact distance (length).
    fn lengths(&self) -> (f64, f64);
    /// How trajectories draw a body (lengths from the potential).
    fn drawing(&self) -> Drawing;
    /// Whether the potential has a radial profile, which level placements other than equal
    /// energy and step-energy rules need.
    fn has_profile(&self) -> bool {
        false
    }
    /// A cut-off of the potential's own (zero beyond it), which the standard-MD engine takes
    /// instead of smoothing it: `(r_switch, r_cut)`.
    fn own_window(&self) -> Option<(f64, f64)> {
        None
    }
    /// The standard-MD time step measured for this potential, if any (else the engine's rule).
    fn smd_dt(&self) -> Option<f64> {
        None
    }
    /// The unit system the parameters are given in, if the kind has one.
    fn units(&self) -> Option<UnitSystem> {
        None
    }
    /// The named interaction sites of a body of several sites, in the frame of its attitude
    /// (the site–site g(r) of `output.rdf`); `None` for a body of one site at its centre,
    /// whose centre g(r) is already the site–site one.
    fn sites(&self) -> Option<MoleculeSites> {
        None
    }
}

/// The keys of `kind = "rods"`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LjRodsSpec {
    /// Well depth ε.
    pub epsilon: f64,
    /// Diameter σ.
    pub sigma: f64,
    /// Orientation shift ζ of the effective distance.
    pub zeta: f64,
}

/// The keys of `kind = "lennard-jones"` (003 Eq. 22 with ζ = 0).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LennardJonesSpec {
    /// Well depth ε.
    pub epsilon: f64,
    /// Diameter σ.
    pub sigma: f64,
}

/// The keys of `kind = "gay-berne"` (defaults GB(3, 5, 2, 1)).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GayBerneSpec {
    /// Breadth σ₀.
    pub sigma0: f64,
    /// Energy scale ε₀.
    pub epsilon0: f64,
    /// Length-to-breadth ratio κ.
    #[serde(default = "kappa")]
    pub kappa: f64,
    /// Side-by-side to end-to-end well-depth ratio κ'.
    #[serde(default = "kappa_prime")]
    pub kappa_prime: f64,
    /// Exponent μ.
    #[serde(default = "mu")]
    pub mu: f64,
    /// Exponent ν.
    #[serde(default = "nu")]
    pub nu: f64,
}

fn kappa() -> f64 {
    3.0
}
fn kappa_prime() -> f64 {
    5.0
}
fn mu() -> f64 {
    2.0
}
fn nu() -> f64 {
    1.0
}

/// The keys of `kind = "ssd-e"`: none (the published parameters); bodies are rigid tops
/// with `moments`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SsdESpec {
    /// Internal energy units per kJ/mol (set by `Scene::internal`, not a scene key).
    #[serde(skip, default = "one")]
    pub energy_unit: f64,
}

/// The keys of `kind = "spc-e"` (`config::kinds::spc_e`): the damped shifted force Coulomb
/// term's damping and the site cut-off; bodies are rigid tops with `moments`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpcESpec {
    /// Damping α of the Coulomb term (1/Å; default 0.2, Fennell and Gezelter 2006).
    pub alpha: Option<f64>,
    /// Site–site cut-off R_c of both terms (Å; default 9).
    pub r_cut: Option<f64>,
    /// Internal energy units per kJ/mol (set by `Scene::internal`, not a scene key).
    #[serde(skip, default = "one")]
    pub energy_unit: f64,
}

/// The keys of `kind = "stockmayer"`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StockmayerSpec {
    /// Well depth ε of the Lennard-Jones part.
    pub epsilon: f64,
    /// Diameter σ.
    pub sigma: f64,
    /// Dipole moment μ (`μ²` an energy × length³).
    pub dipole: f64,
}

/// The keys of `kind = "biaxial-gay-berne"` (`config::kinds::biaxial_gay_berne`): bodies are
/// rigid tops with `moments` about the body axes the semi-axes and well depths are given along.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BiaxialGayBerneSpec {
    /// Semi-axes `[σ_x, σ_y, σ_z]` (length) along the body axes.
    pub semi_axes: [f64; 3],
    /// Energy scale ε₀.
    pub epsilon0: f64,
    /// Relative well depths `[ε_x, ε_y, ε_z]` (dimensionless) of contacts along the body axes
    /// (default `[1, 1, 1]`).
    #[serde(default = "ones")]
    pub epsilon: [f64; 3],
    /// Exponent μ of the strength term (default 2).
    #[serde(default = "mu")]
    pub mu: f64,
    /// Exponent ν of the shape term (default 1).
    #[serde(default = "nu")]
    pub nu: f64,
    /// Softness σ_c (length; default twice the shortest semi-axis).
    pub sigma_c: Option<f64>,
    /// Where the switch to zero starts (length; default `2 max σ_k + 1.5σ_c`).
    pub r_switch: Option<f64>,
    /// Where the potential ends (length; default `2 max σ_k + 2σ_c`).
    pub r_cut: Option<f64>,
}

fn ones() -> [f64; 3] {
    [1.0; 3]
}

/// Where the terrace levels go (see `potential::Placement`).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum PlacementSpec {
    /// Evenly in `U`: the paper's `U_k = (k − ½) ΔV`.
    #[default]
    EqualEnergy,
    /// Evenly in distance (effective distance for the rods).
    EqualDistance,
    /// Evenly in shell volume.
    EqualVolume,
}

/// What energy each terrace gets (see `potential::StepEnergy`).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum StepEnergySpec {
    /// Every step `ΔV` (the paper).
    #[default]
    Equal,
    /// The middle of each terrace's range of `U`.
    Midpoint,
    /// The shell average of `U`.
    VolumeAverage,
    /// Each terrace's share of `B₂` exact at the scene temperature.
    Virial,
}

/// What to do with a level on the potential's minimum (a terrace of zero width, 003 §V).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum NearMinimumSpec {
    /// Refuse the scene.
    #[default]
    Refuse,
    /// Move the level a quarter of the way to the next one.
    Shift,
}

/// The energy terraces of a smooth potential (003 Eq. 7).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TerraceSpec {
    /// The energy step ΔV between levels (and the step of the paper's equal steps).
    pub step: Option<f64>,
    /// Or: ΔV in units of kT at `init.temperature` (`0.5` is the paper's kT/2).
    pub step_kt: Option<f64>,
    /// Or: explicit levels `U_k`, ascending.
    pub levels: Option<Vec<f64>>,
    /// With `levels`: the energy of every terrace (one more than levels); shifted so that
    /// far-apart pairs have 0.
    pub energies: Option<Vec<f64>>,
    /// Level placement between the first and last of the paper's levels (default
    /// `equal-energy`).
    #[serde(default)]
    pub placement: PlacementSpec,
    /// Terrace energies (default `equal`).
    #[serde(default)]
    pub step_energy: StepEnergySpec,
    /// A level on the potential's minimum: `refuse` (default) or `shift`.
    #[serde(default)]
    pub near_minimum: NearMinimumSpec,
    /// The hard-core level `U_core` (default 100 |U_min|).
    pub core: Option<f64>,
    /// Move the outermost level to this (negative) `U` (placement rules only).
    pub outermost: Option<f64>,
}

/// How event times are searched (rods on terraced potentials).
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum SearchMethodSpec {
    /// The adaptive search with cubic interpolation (003 §III).
    #[default]
    Adaptive,
    /// The uniform grid (000 §III.A).
    Grid,
}

/// Root-search settings.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SearchSpec {
    /// `adaptive` (default) or `grid`.
    #[serde(default)]
    pub method: SearchMethodSpec,
    /// Maximum step of the adaptive search, or the grid spacing (a time).
    pub max_step: Option<f64>,
    /// How far one search call goes before a virtual event (a time; `inf`: no virtual
    /// events). Default: `max_step`.
    pub window: Option<f64>,
    /// Relative random shortening of each call's step, in `[0, 0.5)` (default 0.01).
    pub jitter: Option<f64>,
    /// Grid only: extrema are examined where `|g|` at a grid point is below this energy
    /// (default `inf`: every extremum).
    pub grid_threshold: Option<f64>,
    /// Validation: search every interval again on a uniform grid of this spacing (a time)
    /// and count the events the search missed.
    pub verify_step: Option<f64>,
    /// Adaptive only: limit each step so that `U` is predicted to change by at most this
    /// fraction of the terrace's width (`inf`: no limit).
    pub max_change: Option<f64>,
    /// Certified prediction: how far ahead one search call may jump the stretch that a Taylor
    /// model of the potential's effective coordinate proves free of crossings (a time; 0: off).
    /// Default: `rods::DEFAULT_HORIZON_WINDOWS` windows for potentials with a model.
    pub horizon: Option<f64>,
}

/// Where the initial positions come from.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Positions {
    /// Face-centred cubic lattice filling the box (4 sites per unit cell).
    Fcc,
    /// Simple cubic lattice filling the box.
    Sc,
    /// An (extended) XYZ file, `init.file`.
    File,
}

/// Initial configuration.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InitSpec {
    /// `fcc`, `sc` or `file`.
    pub positions: Positions,
    /// The XYZ file when `positions = "file"` (relative to the scene file).
    pub file: Option<PathBuf>,
    /// Temperature of the Maxwell–Boltzmann velocities (energy units, k = 1).
    pub temperature: f64,
    /// Initial orientations of rods: `random` (default), `aligned` (along `axis`) or `file`.
    #[serde(default)]
    pub orientations: Orientations,
    /// The common axis of `orientations = "aligned"`.
    pub axis: Option<[f64; 3]>,
    /// Initial velocities: `maxwell-boltzmann` (default) at `temperature`, or `file`: the
    /// `velo:R:3` column of `init.file` and, for rods and tops, its `omega:R:3` column (the
    /// lab angular velocities), in the units `dmd` writes them.
    #[serde(default)]
    pub velocities: Velocities,
    /// The frame of `init.file` to start from: 0 the first (default), 1 the second, …, −1 the
    /// last, −2 the one before.
    pub frame: Option<i64>,
}

/// Where the initial velocities come from.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Velocities {
    /// Maxwell–Boltzmann at `init.temperature`, zero total momentum.
    #[default]
    MaxwellBoltzmann,
    /// The `velo:R:3` (and `omega:R:3`) columns of `init.file`, as they are.
    File,
}

/// Where the initial orientations of rods come from.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Orientations {
    /// Uniformly random on the sphere.
    #[default]
    Random,
    /// All along `init.axis`.
    Aligned,
    /// The `orientation:R:4` column (unit quaternions, scalar last) of `init.file`.
    File,
}

/// Thermostat kinds.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum ThermostatKind {
    /// No thermostat: NVE throughout.
    #[default]
    None,
    /// Andersen: random bodies get fresh Maxwell–Boltzmann velocities at a given rate.
    Andersen,
}

/// When the thermostat acts.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum ThermostatPhase {
    /// During equilibration only; production is NVE.
    #[default]
    Equilibration,
    /// During equilibration and production (NVT production).
    Always,
}

/// The thermostat.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ThermostatSpec {
    /// `none` or `andersen`.
    #[serde(default)]
    pub kind: ThermostatKind,
    /// Thermostat collisions per body per unit time (Andersen's ν).
    pub rate: Option<f64>,
    /// Bath temperature (default `init.temperature`).
    pub temperature: Option<f64>,
    /// `equilibration` (default) or `always`.
    #[serde(default)]
    pub during: ThermostatPhase,
    /// Scale all velocities (translational and rotational, one factor) when equilibration
    /// ends, so that NVE production starts at the bath temperature exactly (default true;
    /// only with `during = "equilibration"`).
    pub rescale_at_end: Option<bool>,
}

impl ThermostatSpec {
    /// Whether production starts with the velocities scaled to the bath temperature: an
    /// Andersen thermostat that stops when equilibration ends, and `rescale_at_end` not off.
    pub fn rescales_at_end(&self) -> bool {
        self.kind == ThermostatKind::Andersen
            && self.during == ThermostatPhase::Equilibration
            && self.rescale_at_end.unwrap_or(true)
    }
}

/// Which priority queue schedules the events.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum QueueKind {
    /// G. Paul's O(1) bounded queue with lazy invalidation.
    Bounded,
    /// Binary heap, O(log n).
    Heap,
    /// Tournament tree, one leaf per body, updated in place.
    Tournament,
    /// Indexed calendar queue: one entry per body in linked buckets, updated in place
    /// (default).
    #[default]
    Calendar,
}

/// Run length and numerical settings.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// Events of equilibration before production (default 0).
    #[serde(default, deserialize_with = "count")]
    pub equilibration_events: u64,
    /// Or: simulated time of equilibration.
    pub equilibration_time: Option<f64>,
    /// Production length in events (pair events, cell crossings, thermostat events).
    #[serde(default, deserialize_with = "opt_count")]
    pub events: Option<u64>,
    /// Or: production length in simulated time.
    pub time: Option<f64>,
    /// Event queue (default `calendar`).
    #[serde(default)]
    pub queue: QueueKind,
    /// Events between re-basings of the time origin (default 100 N, at least 10⁶, at most 2³¹).
    #[serde(default, deserialize_with = "opt_count")]
    pub rebase_events: Option<u64>,
    /// Neighbour-list skin δ, a length (default: chosen from the density, see the user guide).
    pub skin: Option<f64>,
}

/// Radial distribution function.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RdfSpec {
    /// Number of bins (default 200).
    #[serde(default = "default_bins", deserialize_with = "count")]
    pub bins: u64,
    /// Largest distance (default: half the smallest box side, at most 5).
    pub r_max: Option<f64>,
    /// Evaluate g(r) at every `every`-th sample only (default 10): one evaluation costs about
    /// as much as N · ρ · (4π/3) r_max³ pair distances.
    #[serde(default = "default_rdf_every", deserialize_with = "count")]
    pub every: u64,
}

fn default_rdf_every() -> u64 {
    10
}

fn default_bins() -> u64 {
    200
}

/// A time correlation (mean-square displacement or velocity autocorrelation).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CorrelationSpec {
    /// Longest time lag.
    pub max_lag: f64,
}

/// Trajectory output.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TrajectorySpec {
    /// Simulated time between frames.
    pub interval: f64,
}

/// Outputs besides `summary.json`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Simulated time between samples of the observables.
    pub sample_interval: Option<f64>,
    /// Radial distribution function → `rdf.csv`.
    pub rdf: Option<RdfSpec>,
    /// Mean-square displacement → `msd.csv`.
    pub msd: Option<CorrelationSpec>,
    /// Velocity autocorrelation → `vacf.csv`.
    pub vacf: Option<CorrelationSpec>,
    /// Long-axis orientational autocorrelation of rods → `oacf.csv`.
    pub orientation_acf: Option<CorrelationSpec>,
    /// Pressure and energy time series → `series.csv`.
    #[serde(default)]
    pub series: bool,
    /// Extended XYZ trajectory → `trajectory.xyz`.
    pub trajectory: Option<TrajectorySpec>,
    /// GSD trajectory (HOOMD-blue's format) → `trajectory.gsd`.
    pub gsd: Option<TrajectorySpec>,
    /// An SVG plot next to each CSV file (default true).
    #[serde(default = "yes")]
    pub plots: bool,
    /// Evaluate the smooth potential (`[smd] smoothing`) at every sample of a run on the
    /// terraces of a smooth potential: `potential_energy_per_body_smooth`, `pressure_smooth`
    /// (default: on for those scenes when `sample_interval` is given).
    pub smooth_estimators: Option<bool>,
    /// Samples between two evaluations of the smooth estimators (default
    /// [`DEFAULT_SMOOTH_EVERY`]): each costs a sum over every pair within the cut-off.
    pub smooth_every: Option<u64>,
    /// The most bytes any one output may take in memory or on disk (default
    /// [`DEFAULT_MAX_BYTES`]); see the `limits` module.
    #[serde(default, deserialize_with = "opt_count")]
    pub max_bytes: Option<u64>,
}

/// Default of `output.smooth_every` (as `output.rdf.every`): at every 20th sample the
/// estimators cost a few per cent of a run of the paper's rods (at every sample +40 %), and
/// samples 5 fs apart are correlated over picoseconds anyway (docs/PERFORMANCE.md).
pub const DEFAULT_SMOOTH_EVERY: u64 = 20;

fn yes() -> bool {
    true
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            sample_interval: None,
            rdf: None,
            msd: None,
            vacf: None,
            orientation_acf: None,
            series: false,
            trajectory: None,
            gsd: None,
            plots: true,
            smooth_estimators: None,
            smooth_every: None,
            max_bytes: None,
        }
    }
}

/// A count: a non-negative integer, also accepted as an integral float (`1e7`).
fn count<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
    struct V;
    impl serde::de::Visitor<'_> for V {
        type Value = u64;
        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("a non-negative whole number")
        }
        fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<u64, E> {
            Ok(v)
        }
        fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<u64, E> {
            u64::try_from(v)
                .map_err(|_| E::custom(format!("expected a non-negative whole number, got {v}")))
        }
        fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<u64, E> {
            if v >= 0.0 && v.fract() == 0.0 && v < 1.8e19 {
                Ok(v as u64)
            } else if v >= 1.8e19 && v.is_finite() {
                Err(E::custom(format!(
                    "expected a whole number below 1.8e19, got {}",
                    given(v)
                )))
            } else {
                Err(E::custom(format!(
                    "expected a non-negative whole number, got {}",
                    given(v)
                )))
            }
        }
    }
    d.deserialize_any(V)
}

fn opt_count<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    count(d).map(Some)
}

/// The stepped tables of a scene of spheres and square wells (the engine's potentials know
/// nothing of scenes).
impl crate::engine::potential::Potentials {
    /// From a checked scene (every pair of species has exactly one table).
    pub fn from_scene(scene: &Scene) -> Self {
        let index = |name: &str| {
            scene
                .species
                .iter()
                .position(|s| s.name == name)
                .expect("checked")
        };
        let tables: Vec<crate::engine::potential::PairTable> = scene
            .pair
            .iter()
            .map(|p| {
                (
                    (index(&p.species[0]), index(&p.species[1])),
                    p.steps.clone(),
                )
            })
            .collect();
        Self::from_tables(scene.species.len(), &tables)
    }
}

impl Scene {
    /// Which of the dotted `keys` (e.g. `run.events`) the scene `text`, with `overrides`
    /// applied, sets: for callers that must know what a scene gives, not only its values.
    ///
    /// # Errors
    /// [`SceneError::Syntax`] for text that is not TOML, [`SceneError::Override`] as
    /// [`apply_override`](Self::apply_override).
    pub fn given_keys(
        text: &str,
        overrides: &[String],
        keys: &[&str],
    ) -> Result<Vec<bool>, SceneError> {
        let mut doc: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| SceneError::Syntax(e.to_string()))?;
        for o in overrides {
            Self::apply_override(&mut doc, o)?;
        }
        Ok(keys
            .iter()
            .map(|key| {
                let mut table = &doc;
                let mut parts = key.split('.').peekable();
                while let Some(p) = parts.next() {
                    match table.get(p) {
                        Some(_) if parts.peek().is_none() => return true,
                        Some(toml::Value::Table(inner)) => table = inner,
                        _ => return false,
                    }
                }
                false
            })
            .collect())
    }

    /// Applies one `KEY=VALUE` override to a parsed scene document. `KEY` is a dotted path
    /// (`run.events`, `species.0.mass`: an index picks an element of an array); `VALUE` is
    /// read as a TOML value (`0.5`, `[1, 1, 2]`, `"heap"`, `inf`), or as a string if it is not
    /// one (`run.queue=heap`); an empty `VALUE` removes the key (`run.events=` to give
    /// `run.time` instead). Keys the scene does not know are caught by the same check as in a
    /// file.
    ///
    /// # Errors
    /// [`SceneError::Override`] if the argument has no `=` or the path cannot be followed.
    pub fn apply_override(doc: &mut toml::Table, arg: &str) -> Result<(), SceneError> {
        let bad = |problem: String| SceneError::Override {
            arg: arg.to_owned(),
            problem,
        };
        let (key, value) = arg
            .split_once('=')
            .ok_or_else(|| bad("expected KEY=VALUE".to_owned()))?;
        let key = key.trim();
        if key.is_empty() || key.split('.').any(str::is_empty) {
            return Err(bad(format!("`{key}` is not a dotted key path")));
        }
        let parts: Vec<&str> = key.split('.').collect();
        if value.trim().is_empty() {
            return remove_key(doc, &parts).map_err(bad);
        }
        let value = parse_value(value.trim());
        let mut node: &mut toml::Value = {
            // The root is a table; wrap the walk in a Value for uniformity.
            let first = parts[0];
            if parts.len() == 1 {
                doc.insert(first.to_owned(), value);
                return Ok(());
            }
            doc.entry(first.to_owned())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        };
        let mut walked = parts[0].to_owned();
        for (k, part) in parts.iter().enumerate().skip(1) {
            let last = k + 1 == parts.len();
            node = match node {
                toml::Value::Table(t) => {
                    if last {
                        t.insert((*part).to_owned(), value);
                        return Ok(());
                    }
                    t.entry((*part).to_owned())
                        .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                }
                toml::Value::Array(a) => {
                    let idx: usize = part.parse().map_err(|_| {
                        bad(format!("`{walked}` is an array: `{part}` is not an index"))
                    })?;
                    let len = a.len();
                    let slot = a.get_mut(idx).ok_or_else(|| {
                        bad(format!("`{walked}` has {len} elements, no index {idx}"))
                    })?;
                    if last {
                        *slot = value;
                        return Ok(());
                    }
                    slot
                }
                _ => return Err(bad(format!("`{walked}` is a value, not a table"))),
            };
            walked.push('.');
            walked.push_str(part);
        }
        Ok(())
    }

    /// Total number of bodies.
    pub fn n_bodies(&self) -> u64 {
        self.species.iter().map(|s| s.count).sum()
    }

    /// Checks the values against each other (the part serde cannot).
    /// The checks of the species, before the body kind's own.
    pub(crate) fn check_species(&self) -> Result<(), SceneError> {
        if self.version != FORMAT_VERSION {
            return Err(SceneError::invalid(
                "version",
                format!(
                    "unsupported scene format version {} (this dmd reads version {FORMAT_VERSION})",
                    self.version
                ),
            ));
        }
        // Box.
        let b = &self.box_;
        match (b.density, b.lengths) {
            (Some(_), Some(_)) => {
                return Err(SceneError::invalid(
                    "box",
                    "give either `density` or `lengths`, not both",
                ));
            }
            (None, None) if self.init.positions != Positions::File => {
                return Err(SceneError::invalid(
                    "box",
                    "give either `density` or `lengths`",
                ));
            }
            _ => {}
        }
        if let Some(d) = b.density {
            positive("box.density", d)?;
        }
        if let Some(l) = b.lengths {
            for (k, x) in l.iter().enumerate() {
                positive(&format!("box.lengths[{k}]"), *x)?;
            }
            if b.aspect.is_some() {
                return Err(SceneError::invalid(
                    "box.aspect",
                    "only used with `box.density`; `box.lengths` already fixes the shape",
                ));
            }
        }
        if let Some(a) = b.aspect {
            for (k, x) in a.iter().enumerate() {
                positive(&format!("box.aspect[{k}]"), *x)?;
            }
        }
        // Species.
        if self.species.is_empty() {
            return Err(SceneError::invalid(
                "species",
                "at least one species is needed",
            ));
        }
        for (k, s) in self.species.iter().enumerate() {
            if s.name.trim().is_empty() || s.name.contains(char::is_whitespace) {
                return Err(SceneError::invalid(
                    format!("species[{k}].name"),
                    format!("`{}` is not a name: use letters, digits, _ or -", s.name),
                ));
            }
            if self.species[..k].iter().any(|o| o.name == s.name) {
                return Err(SceneError::invalid(
                    format!("species[{k}].name"),
                    format!("species `{}` is defined twice", s.name),
                ));
            }
            positive(&format!("species[{k}].mass"), s.mass)?;
        }
        let n = self.n_bodies();
        if n < 2 {
            return Err(SceneError::invalid(
                "species",
                format!("a simulation needs at least 2 bodies, the species count {n}"),
            ));
        }
        if n > crate::engine::neighbour::MAX_BODIES {
            return Err(SceneError::invalid(
                "species",
                format!(
                    "{n} bodies is more than this dmd can index (2^27 = {})",
                    crate::engine::neighbour::MAX_BODIES
                ),
            ));
        }
        Ok(())
    }

    /// The checks of the initial state, the run, its thermostat, searches and outputs: those
    /// after the body kind's own (the order decides which error of a bad scene is reported).
    pub(crate) fn check_rest(&self) -> Result<(), SceneError> {
        // Initial state.
        positive("init.temperature", self.init.temperature)?;
        match (self.init.positions, &self.init.file) {
            (Positions::File, None) => {
                return Err(SceneError::invalid(
                    "init.file",
                    "needed when `init.positions = \"file\"`",
                ));
            }
            (Positions::Fcc | Positions::Sc, Some(_)) => {
                return Err(SceneError::invalid(
                    "init.file",
                    "only read when `init.positions = \"file\"`",
                ));
            }
            _ => {}
        }
        if self.init.frame.is_some() && self.init.positions != Positions::File {
            return Err(SceneError::invalid(
                "init.frame",
                "only read when `init.positions = \"file\"`",
            ));
        }
        if self.init.velocities == Velocities::File {
            let tops = self
                .pair
                .first()
                .and_then(|p| p.potential)
                .is_some_and(|q| q.is_rigid());
            if self.init.positions != Positions::File {
                return Err(SceneError::invalid(
                    "init.velocities",
                    "`file` reads the velo column of `init.file`: it needs \
                     `positions = \"file\"`",
                ));
            }
            if self.has_sites() && !self.has_bonds() && self.init.orientations != Orientations::File
            {
                return Err(SceneError::invalid(
                    "init.velocities",
                    "`file` gives site molecules the angular velocities of `init.file`, which \
                     belong to its attitudes: set `orientations = \"file\"` too",
                ));
            }
            if self.has_rods() && !tops && self.init.orientations != Orientations::File {
                return Err(SceneError::invalid(
                    "init.velocities",
                    "`file` gives rods the angular velocities of `init.file`, which belong \
                     to its orientations: set `orientations = \"file\"` too",
                ));
            }
            if tops && self.init.orientations == Orientations::Aligned {
                return Err(SceneError::invalid(
                    "init.velocities",
                    "`file` gives tops the attitudes and angular velocities of `init.file` \
                     (its orientation and omega columns): leave `init.orientations` out or \
                     set it to `file`",
                ));
            }
        }
        for (k, sp) in self.species.iter().enumerate() {
            if let Some(e) = &sp.element
                && crate::analysis::output::atomic_number(e).is_none()
            {
                return Err(SceneError::invalid(
                    format!("species[{k}].element"),
                    format!(
                        "`{e}` is not a chemical symbol: write it as the periodic table does \
                         (`O`, `Ar`), or `X` for none"
                    ),
                ));
            }
        }
        // Thermostat.
        let t = &self.thermostat;
        match t.kind {
            ThermostatKind::None => {
                if t.rate.is_some() || t.temperature.is_some() {
                    return Err(SceneError::invalid(
                        "thermostat.kind",
                        "`rate` and `temperature` are given but no thermostat is chosen (kind = \"andersen\")",
                    ));
                }
                if t.rescale_at_end.is_some() {
                    return Err(SceneError::invalid(
                        "thermostat.rescale_at_end",
                        "there is no thermostat (kind = \"none\"): nothing ends equilibration at \
                         a temperature to rescale to",
                    ));
                }
            }
            ThermostatKind::Andersen => {
                let rate = t.rate.ok_or_else(|| {
                    SceneError::invalid(
                        "thermostat.rate",
                        "an Andersen thermostat needs a rate (collisions per body per unit time)",
                    )
                })?;
                positive("thermostat.rate", rate)?;
                if let Some(temp) = t.temperature {
                    positive("thermostat.temperature", temp)?;
                }
                if t.rescale_at_end == Some(true) && t.during == ThermostatPhase::Always {
                    return Err(SceneError::invalid(
                        "thermostat.rescale_at_end",
                        "the thermostat acts in production too (during = \"always\"): there is \
                         no end of equilibration to rescale at; remove the key or use during = \
                         \"equilibration\"",
                    ));
                }
            }
        }
        // Run.
        let r = &self.run;
        if r.equilibration_time.is_some() && r.equilibration_events > 0 {
            return Err(SceneError::invalid(
                "run",
                "give either `equilibration_events` or `equilibration_time`, not both",
            ));
        }
        if let Some(t) = r.equilibration_time {
            non_negative("run.equilibration_time", t)?;
        }
        match (r.events, r.time) {
            (Some(_), Some(_)) => {
                return Err(SceneError::invalid(
                    "run",
                    "give either `events` or `time`, not both",
                ));
            }
            (None, None) if self.hmc.is_none() => {
                return Err(SceneError::invalid(
                    "run",
                    "give the production length: `events` or `time`",
                ));
            }
            (None, None) => {}
            (_, Some(t)) => positive("run.time", t)?,
            (Some(_), None) => {}
        }
        if let Some(skin) = r.skin {
            positive("run.skin", skin)?;
        }
        if let Some(k) = r.rebase_events
            && !(1..=crate::engine::simulation::MAX_REBASE_EVENTS).contains(&k)
        {
            return Err(SceneError::invalid(
                "run.rebase_events",
                format!("must be between 1 and 2^31, got {k}"),
            ));
        }
        // Outputs.
        let o = &self.output;
        if let Some(k) = o.smooth_every {
            if k == 0 {
                return Err(SceneError::invalid(
                    "output.smooth_every",
                    "must be a whole number of samples ≥ 1, got 0",
                ));
            }
            if !self.wants_smooth_estimators() {
                return Err(SceneError::invalid(
                    "output.smooth_every",
                    "only used with the smooth estimators (the terraces of a smooth potential, \
                     output.smooth_estimators not false)",
                ));
            }
        }
        if o.smooth_estimators == Some(true) {
            if !self.has_terraced_smooth_potential() {
                return Err(SceneError::invalid(
                    "output.smooth_estimators",
                    "the smooth estimators evaluate the continuous potential of a scene on the \
                     terraces of a smooth potential (pair.potential with pair.terraces); this \
                     scene has none (explicit steps, site molecules and semi-flexible \
                     molecules are not estimated)",
                ));
            }
            if o.sample_interval.is_none() {
                return Err(SceneError::invalid(
                    "output.smooth_estimators",
                    "needs output.sample_interval: the smooth potential is evaluated at every \
                     sample",
                ));
            }
        }
        let wants_samples = o.rdf.is_some() || o.msd.is_some() || o.vacf.is_some() || o.series;
        match o.sample_interval {
            Some(dt) => positive("output.sample_interval", dt)?,
            None if wants_samples => {
                let which = [
                    (o.rdf.is_some(), "rdf"),
                    (o.msd.is_some(), "msd"),
                    (o.vacf.is_some(), "vacf"),
                    (o.series, "series"),
                ]
                .iter()
                .find(|(on, _)| *on)
                .map(|(_, n)| *n)
                .unwrap_or("series");
                return Err(SceneError::invalid(
                    "output.sample_interval",
                    format!("needed by `output.{which}`: the simulated time between samples"),
                ));
            }
            None => {}
        }
        if let Some(rdf) = &o.rdf {
            if rdf.bins == 0 || rdf.bins > 1_000_000 {
                return Err(SceneError::invalid(
                    "output.rdf.bins",
                    format!("must be between 1 and 10^6, got {}", rdf.bins),
                ));
            }
            if let Some(r) = rdf.r_max {
                positive("output.rdf.r_max", r)?;
            }
            if rdf.every == 0 {
                return Err(SceneError::invalid(
                    "output.rdf.every",
                    "must be at least 1",
                ));
            }
        }
        for (name, c) in [("msd", &o.msd), ("vacf", &o.vacf)] {
            if let Some(c) = c {
                positive(&format!("output.{name}.max_lag"), c.max_lag)?;
                if let Some(dt) = o.sample_interval
                    && c.max_lag < dt
                {
                    return Err(SceneError::invalid(
                        format!("output.{name}.max_lag"),
                        format!(
                            "{} is shorter than output.sample_interval = {dt}",
                            c.max_lag
                        ),
                    ));
                }
            }
        }
        if let Some(tr) = &o.trajectory {
            positive("output.trajectory.interval", tr.interval)?;
        }
        if let Some(g) = &o.gsd {
            positive("output.gsd.interval", g.interval)?;
        }
        if o.max_bytes == Some(0) {
            return Err(SceneError::invalid(
                "output.max_bytes",
                "must be at least 1",
            ));
        }
        Ok(())
    }

    /// The pair tables of spheres and rods, and the checks of their bodies.
    pub(crate) fn check_pair_tables(&self) -> Result<(), SceneError> {
        let names: Vec<&str> = self.species.iter().map(|s| s.name.as_str()).collect();
        let index = |k: usize, name: &str| -> Result<usize, SceneError> {
            names.iter().position(|&m| m == name).ok_or_else(|| {
                SceneError::invalid(
                    format!("pair[{k}].species"),
                    format!(
                        "unknown species `{name}` (the scene defines {})",
                        names
                            .iter()
                            .map(|m| format!("`{m}`"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })
        };
        let ns = names.len();
        let mut seen = vec![None::<usize>; ns * ns];
        for (k, p) in self.pair.iter().enumerate() {
            let (a, b) = (index(k, &p.species[0])?, index(k, &p.species[1])?);
            if let Some(first) = seen[a * ns + b] {
                return Err(SceneError::invalid(
                    format!("pair[{k}].species"),
                    format!(
                        "the pair `{}`–`{}` already has a table (pair[{first}])",
                        p.species[0], p.species[1]
                    ),
                ));
            }
            seen[a * ns + b] = Some(k);
            seen[b * ns + a] = Some(k);
            match (&p.potential, p.steps.is_empty()) {
                (None, _) => {
                    if p.terraces.is_some() {
                        return Err(SceneError::invalid(
                            format!("pair[{k}].terraces"),
                            "only used with `potential` (a smooth potential on terraces)",
                        ));
                    }
                    check_steps(k, &p.steps)?;
                }
                // Standard MD integrates the smooth potential itself.
                (Some(pot), true) if p.terraces.is_none() && self.engine == Engine::Smd => {
                    check_potential(k, pot)?;
                }
                (Some(pot), true) => {
                    check_potential(k, pot)?;
                    let t = p.terraces.as_ref().ok_or_else(|| {
                        SceneError::invalid(
                            format!("pair[{k}].terraces"),
                            "a smooth potential needs its terraces (for example \
                             `terraces = { step_kt = 0.5 }`)",
                        )
                    })?;
                    check_terraces(k, pot, t)?;
                }
                (Some(_), false) => {
                    return Err(SceneError::invalid(
                        format!("pair[{k}]"),
                        "give either `steps` or a `potential` with `terraces`, not both",
                    ));
                }
            }
        }
        self.check_bodies()?;
        for a in 0..ns {
            for b in a..ns {
                if seen[a * ns + b].is_none() {
                    return Err(SceneError::invalid(
                        "pair",
                        format!(
                            "no pair table for species `{}` and `{}`: every pair of species needs one",
                            names[a], names[b]
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Checks `[hmc]`, `[chains]` and `[sweep]`.
    pub(crate) fn check_issue_9(&self) -> Result<(), SceneError> {
        if let Some(h) = &self.hmc {
            positive("hmc.segment_time", h.segment_time)?;
            if h.segments == 0 {
                return Err(SceneError::invalid("hmc.segments", "must be at least 1"));
            }
            if let Some(t) = h.temperature {
                positive("hmc.temperature", t)?;
            }
            if h.exchanges.is_some() && h.ensemble != EnsembleKind::Microcanonical {
                return Err(SceneError::invalid(
                    "hmc.exchanges",
                    "only used by the microcanonical ensemble",
                ));
            }
            positive("hmc.tolerance", h.tolerance)?;
            if h.measure == MeasureKind::StiffBonds {
                let why = if !self.has_bonds() {
                    Some(
                        "only semi-flexible molecules (species with `bonds`) have a measure that differs from the dynamics'",
                    )
                } else if h.ensemble != EnsembleKind::Canonical {
                    Some(
                        "the microcanonical chain accepts only ΔH = 0 and cannot reweight: use the canonical ensemble",
                    )
                } else if h.accept != AcceptKind::Metropolis {
                    Some("`hmc.accept = \"always\"` accepts every segment and cannot reweight")
                } else {
                    None
                };
                if let Some(why) = why {
                    return Err(SceneError::invalid(
                        "hmc.measure",
                        format!("`stiff-bonds`: {why}"),
                    ));
                }
            }
            if !(0.0..1.0).contains(&h.fault_fraction) {
                return Err(SceneError::invalid(
                    "hmc.fault_fraction",
                    format!(
                        "must be at least 0 and less than 1, got {}",
                        given(h.fault_fraction)
                    ),
                ));
            }
            if h.histogram_bins == 0 || h.histogram_bins > 1_000_000 {
                return Err(SceneError::invalid(
                    "hmc.histogram_bins",
                    format!("must be between 1 and 10^6, got {}", h.histogram_bins),
                ));
            }
            positive("hmc.histogram_range", h.histogram_range)?;
            if h.fault_fraction > 0.0 && self.has_rods() {
                return Err(SceneError::invalid(
                    "hmc.fault_fraction",
                    "hmc with rods is not supported with fault injection: it hides pairs of \
                     the analytic sphere models, while the rods' root searches miss events of \
                     their own (coarsen search.max_step to make them miss); set it to 0",
                ));
            }
            for (key, given) in [
                ("run.events", self.run.events.is_some()),
                ("run.time", self.run.time.is_some()),
            ] {
                if given {
                    return Err(SceneError::invalid(
                        key,
                        "with [hmc] the production length is hmc.segments × \
                         hmc.segment_time: remove it",
                    ));
                }
            }
            if self.thermostat.kind == ThermostatKind::Andersen
                && self.thermostat.during == ThermostatPhase::Always
            {
                return Err(SceneError::invalid(
                    "thermostat.during",
                    "HMC is the thermostat of production: an Andersen thermostat may act during \
                     equilibration only",
                ));
            }
            let o = &self.output;
            for (key, on) in [
                ("output.sample_interval", o.sample_interval.is_some()),
                ("output.rdf", o.rdf.is_some()),
                ("output.msd", o.msd.is_some()),
                ("output.vacf", o.vacf.is_some()),
                ("output.series", o.series),
                ("output.trajectory", o.trajectory.is_some()),
                ("output.gsd", o.gsd.is_some()),
                ("output.orientation_acf", o.orientation_acf.is_some()),
            ] {
                if on {
                    return Err(SceneError::invalid(
                        key,
                        "not sampled with [hmc]: the chain states are summarised in the `hmc` \
                         section of summary.json and, with hmc.series = true, in hmc.csv",
                    ));
                }
            }
        }
        if let Some(c) = &self.chains
            && !(1..=10_000).contains(&c.count)
        {
            return Err(SceneError::invalid(
                "chains.count",
                format!("must be between 1 and 10^4, got {}", c.count),
            ));
        }
        if let Some(sw) = &self.sweep {
            if sw.values.is_empty() {
                return Err(SceneError::invalid(
                    "sweep.values",
                    "at least one value is needed",
                ));
            }
            let first = sw.key.split('.').next().unwrap_or("");
            if sw.key.trim().is_empty() || ["sweep", "chains", "version"].contains(&first) {
                return Err(SceneError::invalid(
                    "sweep.key",
                    format!("`{}` cannot be swept", sw.key),
                ));
            }
        }
        Ok(())
    }
}

impl Scene {
    /// Whether the bodies are rods on an orientation-dependent terraced potential.
    pub fn has_rods(&self) -> bool {
        self.pair
            .iter()
            .any(|p| p.potential.is_some_and(|q| q.is_anisotropic()))
    }

    /// The checks of rods, potentials, orientations and searches across keys.
    fn check_bodies(&self) -> Result<(), SceneError> {
        let smooth = self.pair.iter().filter(|p| p.potential.is_some()).count();
        if smooth > 0 && smooth < self.pair.len() {
            return Err(SceneError::invalid(
                "pair",
                "either every pair table has `steps` or every one has a `potential`: a scene \
                 cannot mix stepped and terraced potentials",
            ));
        }
        let kinds: Vec<&str> = self
            .pair
            .iter()
            .filter_map(|p| p.potential.map(|q| q.kind()))
            .collect();
        if let Some(k) = kinds.iter().position(|&k| k != kinds[0]) {
            return Err(SceneError::invalid(
                format!("pair[{k}].potential.kind"),
                format!(
                    "`{}` differs from `{}` of pair[0]: every pair of a scene must use the same \
                     kind of potential",
                    kinds[k], kinds[0]
                ),
            ));
        }
        let anisotropic: Vec<bool> = self
            .pair
            .iter()
            .map(|p| p.potential.is_some_and(|q| q.is_anisotropic()))
            .collect();
        let rods = anisotropic.iter().any(|&a| a);
        if rods && let Some(k) = anisotropic.iter().position(|&a| !a) {
            return Err(SceneError::invalid(
                format!("pair[{k}].potential"),
                "a rods potential with zeta = 0 is isotropic: in a scene of rods every pair \
                 must depend on the orientations (zeta > 0)",
            ));
        }
        let tops = self
            .pair
            .first()
            .and_then(|p| p.potential)
            .is_some_and(|q| q.is_rigid());
        if let Some(q) = self.pair.first().and_then(|p| p.potential)
            && let Some(units) = q.describe().units()
            && units != self.units
        {
            return Err(SceneError::invalid(
                "units",
                format!(
                    "`{}` is parameterised in {}: set units = \"{}\"",
                    q.kind(),
                    match units {
                        UnitSystem::Molecular => "kJ/mol, Å and g/mol",
                        UnitSystem::Reduced => "reduced units",
                    },
                    match units {
                        UnitSystem::Molecular => "molecular",
                        UnitSystem::Reduced => "reduced",
                    }
                ),
            ));
        }
        for (k, sp) in self.species.iter().enumerate() {
            match (sp.moments, tops) {
                (Some(m), true) => {
                    crate::models::rotor::TopInertia::new(glam::DVec3::from(m))
                        .map_err(|e| SceneError::invalid(format!("species[{k}].moments"), e))?;
                }
                (None, true) => {
                    return Err(SceneError::invalid(
                        format!("species[{k}].moments"),
                        "needed: the potential reads the whole attitude of each body, so the \
                         bodies are rigid tops with principal moments [I_x, I_y, I_z] about \
                         their body axes (water: [1.7696, 0.6145, 1.1550] g/mol·Å²; a uniform \
                         ellipsoid of semi-axes a, b, c: m/5·[b² + c², a² + c², a² + b²])",
                    ));
                }
                (Some(_), false) => {
                    return Err(SceneError::invalid(
                        format!("species[{k}].moments"),
                        "only bodies of a potential that reads whole attitudes (`ssd-e`, \
                         `spc-e`, `biaxial-gay-berne`) have three moments: remove the key",
                    ));
                }
                (None, false) => {}
            }
            if tops {
                if sp.inertia.is_some() {
                    return Err(SceneError::invalid(
                        format!("species[{k}].inertia"),
                        "a rigid top has three `moments`, not one moment of a rod: remove \
                         the key",
                    ));
                }
                continue;
            }
            match (sp.inertia, rods) {
                (Some(i), true) => positive(&format!("species[{k}].inertia"), i)?,
                (None, true) => {
                    return Err(SceneError::invalid(
                        format!("species[{k}].inertia"),
                        "needed: the potential depends on orientations, so the bodies are rods \
                         with a moment of inertia about their short axes",
                    ));
                }
                (Some(_), false) => {
                    return Err(SceneError::invalid(
                        format!("species[{k}].inertia"),
                        "only rods have one: give a potential that depends on orientations \
                         (`rods` with zeta > 0 or `gay-berne`), or remove the key",
                    ));
                }
                (None, false) => {}
            }
        }
        // Orientations.
        let init = &self.init;
        if !rods && (init.orientations != Orientations::Random || init.axis.is_some()) {
            return Err(SceneError::invalid(
                "init.orientations",
                "only rods have orientations (the bodies of this scene are spheres)",
            ));
        }
        check_orientation_keys(init)?;
        // Searches.
        if let Some(sr) = &self.search {
            if !rods {
                return Err(SceneError::invalid(
                    "search",
                    "only used by rods on terraced potentials (event times of spheres are \
                     analytic)",
                ));
            }
            check_search_keys(sr, "an energy ≥ 0 or inf")?;
            if let Some(x) = sr.max_change {
                if x.is_nan() || x <= 0.0 {
                    return Err(SceneError::invalid(
                        "search.max_change",
                        format!("must be a positive fraction or inf, got {}", given(x)),
                    ));
                }
                if sr.method != SearchMethodSpec::Adaptive {
                    return Err(SceneError::invalid(
                        "search.max_change",
                        "only used with `method = \"adaptive\"`",
                    ));
                }
            }
            if let Some(x) = sr.horizon {
                non_negative("search.horizon", x)?;
            }
        }
        if let Some(c) = &self.output.orientation_acf {
            if !rods {
                return Err(SceneError::invalid(
                    "output.orientation_acf",
                    "only rods have orientations (the bodies of this scene are spheres)",
                ));
            }
            positive("output.orientation_acf.max_lag", c.max_lag)?;
            match self.output.sample_interval {
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
}

fn check_potential(k: usize, p: &PotentialSpec) -> Result<(), SceneError> {
    p.describe()
        .check(&|name: &str| format!("pair[{k}].potential.{name}"))
}

fn check_terraces(k: usize, p: &PotentialSpec, t: &TerraceSpec) -> Result<(), SceneError> {
    let key = |name: &str| format!("pair[{k}].terraces.{name}");
    let given = [t.step.is_some(), t.step_kt.is_some(), t.levels.is_some()];
    if given.iter().filter(|&&g| g).count() != 1 {
        return Err(SceneError::invalid(
            format!("pair[{k}].terraces"),
            "give exactly one of `step` (ΔV), `step_kt` (ΔV/kT) or `levels`",
        ));
    }
    if let Some(x) = t.step {
        positive(&key("step"), x)?;
    }
    if let Some(x) = t.step_kt {
        positive(&key("step_kt"), x)?;
    }
    if let Some(levels) = &t.levels {
        if levels.is_empty() {
            return Err(SceneError::invalid(
                key("levels"),
                "at least one level is needed",
            ));
        }
        if let Some(x) = levels.iter().find(|x| !x.is_finite()) {
            return Err(SceneError::invalid(
                key("levels"),
                format!(
                    "levels must be finite energies, got {}",
                    crate::analysis::output::given(*x)
                ),
            ));
        }
        if t.placement != PlacementSpec::EqualEnergy {
            return Err(SceneError::invalid(
                key("placement"),
                "places the paper's levels between their ends: not used with explicit `levels`",
            ));
        }
        match (&t.energies, t.step_energy) {
            (Some(_), StepEnergySpec::Equal) => {}
            (Some(_), _) => {
                return Err(SceneError::invalid(
                    key("step_energy"),
                    "give either `energies` or a `step_energy` rule, not both",
                ));
            }
            (None, StepEnergySpec::Equal) => {
                return Err(SceneError::invalid(
                    key("energies"),
                    "explicit `levels` need the terrace energies: give `energies` (one more \
                     than levels) or a `step_energy` rule (midpoint, volume-average, virial)",
                ));
            }
            (None, _) => {}
        }
    } else if t.energies.is_some() {
        return Err(SceneError::invalid(
            key("energies"),
            "only used with explicit `levels`",
        ));
    }
    if let Some(c) = t.core {
        positive(&key("core"), c)?;
    }
    if let Some(o) = t.outermost {
        if !(o.is_finite() && o < 0.0) {
            return Err(SceneError::invalid(
                key("outermost"),
                format!(
                    "must be a negative energy (the outermost level below zero), got {}",
                    crate::analysis::output::given(o)
                ),
            ));
        }
        if t.levels.is_some() {
            return Err(SceneError::invalid(
                key("outermost"),
                "moves the outermost of the levels `step` or `step_kt` makes: not used with \
                 explicit `levels`",
            ));
        }
    }
    let needs_profile = t.placement != PlacementSpec::EqualEnergy
        || t.step_energy != StepEnergySpec::Equal
        || t.outermost.is_some();
    if needs_profile && !p.describe().has_profile() {
        let which = if t.placement != PlacementSpec::EqualEnergy {
            "placement"
        } else if t.step_energy != StepEnergySpec::Equal {
            "step_energy"
        } else {
            "outermost"
        };
        return Err(SceneError::invalid(
            key(which),
            format!(
                "needs a radial profile of the potential, which `{}` has not: available for \
                 `rods` and `lennard-jones`",
                p.kind()
            ),
        ));
    }
    Ok(())
}

/// The `[search]` keys that rods and site molecules share: step, window, jitter, the grid's
/// grazing threshold (`threshold` says what it must be: its unit differs with the indicator)
/// and the verification step.
pub(crate) fn check_search_keys(sr: &SearchSpec, threshold: &str) -> Result<(), SceneError> {
    if let Some(x) = sr.max_step {
        positive("search.max_step", x)?;
    }
    if let Some(x) = sr.window
        && (x.is_nan() || x <= 0.0)
    {
        return Err(SceneError::invalid(
            "search.window",
            format!("must be a positive time or inf, got {}", given(x)),
        ));
    }
    if let Some(j) = sr.jitter
        && !(0.0..0.5).contains(&j)
    {
        return Err(SceneError::invalid(
            "search.jitter",
            format!("must be at least 0 and below 0.5, got {}", given(j)),
        ));
    }
    if let Some(x) = sr.grid_threshold {
        if sr.method != SearchMethodSpec::Grid {
            return Err(SceneError::invalid(
                "search.grid_threshold",
                "only used with `method = \"grid\"`",
            ));
        }
        if x.is_nan() || x < 0.0 {
            return Err(SceneError::invalid(
                "search.grid_threshold",
                format!("must be {threshold}, got {}", given(x)),
            ));
        }
    }
    if let Some(x) = sr.verify_step {
        positive("search.verify_step", x)?;
    }
    Ok(())
}

pub(crate) fn positive(key: &str, x: f64) -> Result<(), SceneError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("must be a positive finite number, got {}", given(x)),
        ))
    }
}

pub(crate) fn non_negative(key: &str, x: f64) -> Result<(), SceneError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("must be a finite number ≥ 0, got {}", given(x)),
        ))
    }
}

fn check_steps(k: usize, steps: &[[f64; 2]]) -> Result<(), SceneError> {
    check_steps_at(&format!("pair[{k}].steps"), steps)
}

/// The checks of a table of `[radius, energy step]` at `key` (`pair[k].steps`,
/// `site_pair[k].steps`).
pub(crate) fn check_steps_at(key: &str, steps: &[[f64; 2]]) -> Result<(), SceneError> {
    let key = key.to_owned();
    if steps.is_empty() {
        return Err(SceneError::invalid(
            key,
            "at least one [radius, energy step] is needed (a hard core is [diameter, inf])",
        ));
    }
    for (s, &[r, dv]) in steps.iter().enumerate() {
        let here = format!("{key}[{s}]");
        if !(r.is_finite() && r > 0.0) {
            return Err(SceneError::invalid(
                here,
                format!(
                    "the radius must be a positive finite number, got {}",
                    given(r)
                ),
            ));
        }
        if dv.is_nan() || dv == f64::NEG_INFINITY {
            return Err(SceneError::invalid(
                here,
                format!(
                    "the energy step must be a number or inf (a hard core), got {}",
                    given(dv)
                ),
            ));
        }
        if dv == 0.0 {
            return Err(SceneError::invalid(
                here,
                "the energy step is 0, which changes nothing: remove the step",
            ));
        }
        if dv.is_finite() && dv.abs() > MAX_STEP_ENERGY {
            return Err(SceneError::invalid(
                here,
                format!(
                    "the energy step {} is beyond any physical energy (at most {} in \
                     magnitude, so that sums of energies stay finite); a hard core is inf",
                    crate::analysis::output::short(dv),
                    crate::analysis::output::short(MAX_STEP_ENERGY)
                ),
            ));
        }
        if dv == f64::INFINITY && s > 0 {
            return Err(SceneError::invalid(
                here,
                "a hard core (step inf) must be the innermost step: nothing inside it is reachable",
            ));
        }
        if s > 0 && r <= steps[s - 1][0] {
            return Err(SceneError::invalid(
                key,
                format!(
                    "step radii must increase strictly, but {} is followed by {r}",
                    steps[s - 1][0]
                ),
            ));
        }
    }
    Ok(())
}

/// Removes a dotted key (an `--set KEY=` override).
fn remove_key(doc: &mut toml::Table, parts: &[&str]) -> Result<(), String> {
    let (last, path) = parts.split_last().expect("a key has at least one part");
    let mut table = doc;
    let mut walked = String::new();
    let mut iter = path.iter().peekable();
    while let Some(part) = iter.next() {
        if !walked.is_empty() {
            walked.push('.');
        }
        walked.push_str(part);
        table = match table.get_mut(*part) {
            Some(toml::Value::Table(t)) => t,
            // An array of tables: the next part picks the element (`pair.0.terraces.step=`).
            Some(toml::Value::Array(a)) => {
                let Some(index) = iter.next() else {
                    return Err(format!("`{walked}` is an array, not a table"));
                };
                let len = a.len();
                let k: usize = index
                    .parse()
                    .map_err(|_| format!("`{walked}` is an array: `{index}` is not an index"))?;
                walked.push('.');
                walked.push_str(index);
                match a.get_mut(k) {
                    Some(toml::Value::Table(t)) => t,
                    Some(_) => return Err(format!("`{walked}` is not a table of the scene")),
                    None => {
                        return Err(format!(
                            "`{}` has {len} elements, no index {k}",
                            &walked[..walked.len() - index.len() - 1]
                        ));
                    }
                }
            }
            _ => return Err(format!("`{walked}` is not a table of the scene")),
        };
    }
    table
        .remove(*last)
        .map(|_| ())
        .ok_or_else(|| format!("the scene has no key `{}` to remove", parts.join(".")))
}

/// Reads an override value as TOML, or as a string if it is not valid TOML.
fn parse_value(text: &str) -> toml::Value {
    format!("v = {text}")
        .parse::<toml::Table>()
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(text.to_owned()))
}

/// The checks of `init.orientations` and `init.axis` shared by every body with an axis: an
/// aligned start needs a nonzero finite axis, the axis is only for an aligned start, and
/// orientations from a file need positions from the file.
///
/// # Errors
/// [`SceneError::Invalid`] naming the key.
pub(crate) fn check_orientation_keys(init: &InitSpec) -> Result<(), SceneError> {
    check_orientation_keys_saying(
        init,
        "needed by `orientations = \"aligned\"`: the common axis [x, y, z]",
        "`file` reads the orientation column of `init.file`: it needs `positions = \"file\"`",
    )
}

/// [`check_orientation_keys`] with the body kind's words for what the missing axis is
/// (`axis_needed`) and for what a file's orientations need (`file_needs`).
///
/// # Errors
/// [`SceneError::Invalid`] naming the key.
pub(crate) fn check_orientation_keys_saying(
    init: &InitSpec,
    axis_needed: &str,
    file_needs: &str,
) -> Result<(), SceneError> {
    match (init.orientations, init.axis) {
        (Orientations::Aligned, None) => {
            return Err(SceneError::invalid("init.axis", axis_needed));
        }
        (Orientations::Aligned, Some(a)) => {
            let len = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            if !(len.is_finite() && len > 0.0) {
                return Err(SceneError::invalid(
                    "init.axis",
                    format!("must be a nonzero finite vector, got {a:?}"),
                ));
            }
        }
        (_, Some(_)) => {
            return Err(SceneError::invalid(
                "init.axis",
                "only used with `orientations = \"aligned\"`",
            ));
        }
        (Orientations::File, None) if init.positions != Positions::File => {
            return Err(SceneError::invalid("init.orientations", file_needs));
        }
        _ => {}
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
version = 1
[box]
density = 0.5
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
events = 1000
"#;

    #[test]
    fn minimal_scene_reads_with_defaults() {
        let s = Scene::from_str_with(MINIMAL, &[]).unwrap();
        assert_eq!(s.seed, 1);
        assert_eq!(s.species[0].mass, 1.0);
        assert_eq!(s.run.queue, QueueKind::Calendar);
        assert_eq!(s.pair[0].steps, vec![[1.0, f64::INFINITY]]);
        assert!(s.output.plots);
    }

    #[test]
    fn overrides_reach_nested_keys_and_array_elements() {
        let s = Scene::from_str_with(
            MINIMAL,
            &[
                "run.events=1e6".into(),
                "run.queue=heap".into(),
                "species.0.mass=2.5".into(),
                "box.density = 0.8".into(),
                "pair.0.steps=[[1.0, inf], [1.5, -1.0]]".into(),
                "seed=7".into(),
            ],
        )
        .unwrap();
        assert_eq!(s.run.events, Some(1_000_000));
        assert_eq!(s.run.queue, QueueKind::Heap);
        assert_eq!(s.species[0].mass, 2.5);
        assert_eq!(s.box_.density, Some(0.8));
        assert_eq!(s.pair[0].steps.len(), 2);
        assert_eq!(s.seed, 7);
    }

    #[test]
    fn override_errors_name_the_argument() {
        let e = Scene::from_str_with(MINIMAL, &["run.events".into()]).unwrap_err();
        assert_eq!(e.to_string(), "override `run.events`: expected KEY=VALUE");
        let e = Scene::from_str_with(MINIMAL, &["species.3.mass=1".into()]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "override `species.3.mass=1`: `species` has 1 elements, no index 3"
        );
        let e = Scene::from_str_with(MINIMAL, &["run.evnts=".into()]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "override `run.evnts=`: the scene has no key `run.evnts` to remove"
        );
        let s =
            Scene::from_str_with(MINIMAL, &["run.events=".into(), "run.time=2".into()]).unwrap();
        // Removing a key inside an element of an array of tables.
        let e = Scene::from_str_with(MINIMAL, &["pair.0.steps=".into()]).unwrap_err();
        assert!(e.to_string().contains("pair[0].steps"), "{e}");
        let e = Scene::from_str_with(MINIMAL, &["pair.2.steps=".into()]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "override `pair.2.steps=`: `pair` has 1 elements, no index 2"
        );
        assert_eq!((s.run.events, s.run.time), (None, Some(2.0)));
        let e = Scene::from_str_with(MINIMAL, &["run.events.x=1".into()]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "override `run.events.x=1`: `run.events` is a value, not a table"
        );
        let e = Scene::from_str_with(MINIMAL, &["seed.x=1".into()]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "scene key `seed`: invalid type: map, expected u64"
        );
    }
}
