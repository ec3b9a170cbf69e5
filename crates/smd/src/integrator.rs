//! The symplectic splitting integrator for rigid bodies with the exact free rotation.
//!
//! One step of length `h` is the symmetric (Strang) splitting of the Hamiltonian into the
//! potential `U` and the free motion `K` (the "exact-rotation" splitting that 003 §V.B uses
//! for its standard-MD reference; Dullweber, Leimkuhler & McLachlan, J. Chem. Phys. 107, 5840
//! (1997), with the free rotation solved exactly as in van Zon & Schofield, J. Comput. Phys.
//! 225, 145 (2007)):
//!
//! ```text
//! kick(h/2):  v_i += (h/2) F_i / m,      L_i += (h/2) τ_i          (U flow: exact)
//! drift(h):   r_i += h v_i,              orientation ← free motion over h (K flow: exact)
//! kick(h/2):  with the forces and torques at the new positions and orientations
//! ```
//!
//! Each sub-step is the exact flow of a part of the Hamiltonian, so the map is symplectic
//! and, being symmetric, time reversible; its energy error is bounded and of order `h²`. The
//! free rotation is that of `rigid-free`: [`rigid_free::LinearRotor`] for rods (uniform
//! rotation of the axis about the constant `ω ⊥ s`), [`rigid_free::FreeMotion`] for general
//! tops (trigonometric or Jacobi elliptic). Spheres only translate.
//!
//! A step that cannot be completed is an error, never NaN: an overlap the potential cannot
//! evaluate, a non-finite energy, or a total energy that left the guard band around its
//! reference ([`Settings::guard`]) stops the run with [`SmdError::Overlap`] or
//! [`SmdError::Unstable`].

use glam::{DMat3, DQuat, DVec3};
use rigid_free::{FreeMotion, LinearRotor};

use crate::error::positive;
use crate::forces::{Interaction, PairFailure, PairSums};
use crate::neighbour::NeighbourList;
use crate::timing::Stopwatch;
use crate::{BodyModel, SmdError, System};

/// Default [`Settings::guard`]: the run stops if the total energy moves by more than 10 % of
/// the system's energy scale (`K + |U|` at the reference).
pub const DEFAULT_GUARD: f64 = 0.1;

/// Numerical settings of an [`Integrator`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Time step.
    pub dt: f64,
    /// Neighbour-list skin `δ` (the list radius is `r_u + δ`); any positive value gives the
    /// same trajectory up to round-off, it only trades list builds for pairs per step. Measured
    /// best (docs/PERFORMANCE.md): about 0.6σ (2 Å for the paper's rods, 0.6σ for LJ at
    /// ρ* = 0.5), with a flat optimum.
    pub skin: f64,
    /// Stability guard: the run fails if `|E − E_ref| > guard · (K_ref + |U_ref|)`, with the
    /// reference taken at the start and after every velocity rescaling. `f64::INFINITY`
    /// turns it off (non-finite energies are still errors).
    pub guard: f64,
}

impl Settings {
    /// Time step `dt` and skin `skin`, default guard.
    pub fn new(dt: f64, skin: f64) -> Self {
        Self {
            dt,
            skin,
            guard: DEFAULT_GUARD,
        }
    }
}

/// Energies of the current state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// `½ m Σ v²`.
    pub kinetic_translational: f64,
    /// `½ Σ ω·L`.
    pub kinetic_rotational: f64,
    /// `Σ U_ij` of the interaction (the smoothed potential, or the rigid one).
    pub potential: f64,
    /// `Σ r_ij · F_ij` over pairs (centre-of-mass separations and forces).
    pub virial: f64,
}

impl Energy {
    /// Total kinetic energy.
    pub fn kinetic(&self) -> f64 {
        self.kinetic_translational + self.kinetic_rotational
    }

    /// Total energy.
    pub fn total(&self) -> f64 {
        self.kinetic() + self.potential
    }
}

/// The state handed to an [`Observer`] at a sample.
#[derive(Clone, Copy, Debug)]
pub struct Snapshot<'a> {
    /// Steps since the integrator was built.
    pub step: u64,
    /// Simulated time since the integrator was built (`step · dt`, rescaled runs included).
    pub time: f64,
    /// The bodies.
    pub system: &'a System,
    /// The energies of this state.
    pub energy: Energy,
}

impl Snapshot<'_> {
    /// Translational kinetic temperature `2 K_t / (3N − 3)` (energy units).
    pub fn temperature_translational(&self) -> f64 {
        2.0 * self.energy.kinetic_translational / self.system.dof_translational()
    }

    /// Rotational kinetic temperature `2 K_r / f_r` (zero for spheres).
    pub fn temperature_rotational(&self) -> f64 {
        let dof = self.system.dof_rotational();
        if dof > 0.0 {
            2.0 * self.energy.kinetic_rotational / dof
        } else {
            0.0
        }
    }

    /// Kinetic temperature over all degrees of freedom.
    pub fn temperature(&self) -> f64 {
        2.0 * self.energy.kinetic()
            / (self.system.dof_translational() + self.system.dof_rotational())
    }

    /// Instantaneous pressure from the molecular virial, `(N kT_t + W/3) / V`.
    pub fn pressure(&self) -> f64 {
        let n = self.system.n() as f64;
        (n * self.temperature_translational() + self.energy.virial / 3.0) / self.system.volume()
    }
}

/// Receives the state at every sample of [`Integrator::run`].
pub trait Observer {
    /// Called at the start of a run and after every `sample_every` steps.
    fn sample(&mut self, snapshot: &Snapshot<'_>);
}

/// Observes nothing (for timing runs).
impl Observer for () {
    fn sample(&mut self, _: &Snapshot<'_>) {}
}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn sample(&mut self, snapshot: &Snapshot<'_>) {
        (**self).sample(snapshot);
    }
}

/// What a run cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunStats {
    /// Bodies.
    pub bodies: usize,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time covered.
    pub simulated_time: f64,
    /// Neighbour-list builds.
    pub builds: u64,
    /// Pair evaluations (pairs closer than the cut-off, summed over steps).
    pub pair_evaluations: u64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// CPU seconds of the running thread (Linux), if available.
    pub cpu_seconds: Option<f64>,
}

impl RunStats {
    /// CPU seconds if known, else wall seconds.
    pub fn seconds(&self) -> f64 {
        self.cpu_seconds.unwrap_or(self.wall_seconds)
    }

    /// Nanoseconds per body per step (CPU time if known).
    pub fn ns_per_particle_step(&self) -> f64 {
        self.seconds() * 1e9 / (self.bodies as f64 * self.steps.max(1) as f64)
    }

    /// Seconds of run time per unit of simulated time.
    pub fn seconds_per_time_unit(&self) -> f64 {
        self.seconds() / self.simulated_time
    }

    /// Mean steps between neighbour-list builds.
    pub fn steps_per_build(&self) -> f64 {
        self.steps as f64 / self.builds.max(1) as f64
    }
}

/// Standard MD of a [`System`] with an [`Interaction`]: a uniaxial pair potential smoothed to
/// zero ([`potential::Smoothed`]) or a rigid-body potential on whole attitudes
/// ([`crate::Rigid`]). The splitting integrator, its neighbour list and force buffers.
///
/// ```
/// use potential::{LennardJones, Smoothed};
/// use smd::{BodyModel, Integrator, Settings, Setup, System};
///
/// // 256 Lennard-Jones spheres (reduced units) at ρ* = 0.5, T* = 2.
/// let body = BodyModel::sphere(1.0)?;
/// let system = System::new(&Setup::new(256, 0.5, body, 2.0))?;
/// let lj = Smoothed::paper(LennardJones::new(1.0, 1.0)?, 1.0)?; // r_l = 2.5, r_u = 3
/// let mut md = Integrator::new(system, lj, Settings::new(0.002, 0.4))?;
/// let e0 = md.energy().total();
/// md.run(200, 10, &mut ())?;
/// assert!((md.energy().total() - e0).abs() < 1e-3 * 256.0);
/// # Ok::<(), smd::SmdError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Integrator<F> {
    sys: System,
    pot: F,
    dt: f64,
    cutoff2: f64,
    torques: bool,
    list: NeighbourList,
    force: Vec<DVec3>,
    torque: Vec<DVec3>,
    /// Scratch for the interaction (the attitudes of rigid tops as quaternions).
    attitudes: Vec<DQuat>,
    energy: Energy,
    step: u64,
    time: f64,
    pair_evaluations: u64,
    guard: f64,
    e_ref: f64,
    e_scale: f64,
}

impl<F: Interaction> Integrator<F> {
    /// Builds the neighbour list and evaluates the forces of the initial state.
    ///
    /// # Errors
    /// [`SmdError::Parameter`] for a non-positive time step, skin or guard;
    /// [`SmdError::BoxTooSmall`] if a box edge is not longer than twice `r_u + skin`;
    /// [`SmdError::Inconsistent`] for bodies the interaction cannot move (a rigid-body
    /// potential on anything but [`BodyModel::Rigid`]);
    /// [`SmdError::Overlap`] if the initial state has a pair without a finite force.
    pub fn new(system: System, potential: F, settings: Settings) -> Result<Self, SmdError> {
        let dt = positive("dt", settings.dt)?;
        let skin = positive("skin", settings.skin)?;
        if settings.guard.is_nan() || settings.guard <= 0.0 {
            return Err(SmdError::Parameter {
                name: "guard",
                value: settings.guard,
                why: "> 0 (f64::INFINITY turns it off)",
            });
        }
        let (r_l, r_u) = potential.window();
        let list = NeighbourList::new(r_l, r_u, skin);
        let side = system.lengths.min_element();
        if side <= 2.0 * list.radius() {
            return Err(SmdError::BoxTooSmall {
                side,
                radius: list.radius(),
            });
        }
        let n = system.n();
        let torques = potential.torques(&system.body)?;
        let mut md = Self {
            pot: potential,
            dt,
            cutoff2: r_u * r_u,
            torques,
            list,
            force: vec![DVec3::ZERO; n],
            torque: if torques {
                vec![DVec3::ZERO; n]
            } else {
                Vec::new()
            },
            attitudes: Vec::new(),
            energy: Energy::default(),
            step: 0,
            time: 0.0,
            pair_evaluations: 0,
            guard: settings.guard,
            e_ref: 0.0,
            e_scale: 0.0,
            sys: system,
        };
        md.list.build(&mut md.sys);
        md.compute_forces()?;
        let (t, r) = md.sys.kinetic_energy();
        md.energy.kinetic_translational = t;
        md.energy.kinetic_rotational = r;
        md.check_finite()?;
        md.set_reference();
        Ok(md)
    }

    /// The bodies.
    pub fn system(&self) -> &System {
        &self.sys
    }

    /// Gives the bodies back.
    pub fn into_system(self) -> System {
        self.sys
    }

    /// The interaction (the smoothed or the rigid potential).
    pub fn potential(&self) -> &F {
        &self.pot
    }

    /// Energies of the current state.
    pub fn energy(&self) -> Energy {
        self.energy
    }

    /// The state as an observer sees it.
    pub fn snapshot(&self) -> Snapshot<'_> {
        Snapshot {
            step: self.step,
            time: self.time,
            system: &self.sys,
            energy: self.energy,
        }
    }

    /// Forces on the bodies in the current state.
    pub fn forces(&self) -> &[DVec3] {
        &self.force
    }

    /// Torques on the bodies in the current state, lab frame (empty when no torques are
    /// computed: spheres, or a potential that does not depend on orientation).
    pub fn torques(&self) -> &[DVec3] {
        &self.torque
    }

    /// Time step.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Steps taken since construction.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// Simulated time since construction.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Neighbour-list builds since construction (the first included).
    pub fn builds(&self) -> u64 {
        self.list.builds()
    }

    /// Negates every velocity and angular momentum. The forces stay valid (they depend on
    /// positions only), so the next steps retrace the trajectory backwards.
    pub fn reverse_momenta(&mut self) {
        self.sys.reverse_momenta();
    }

    /// Scales velocities and angular momenta to the kinetic temperature `kt` (translational
    /// and rotational parts separately) and takes the new total energy as the guard's
    /// reference.
    ///
    /// # Errors
    /// [`SmdError::Parameter`] unless `kt` is finite and positive.
    pub fn rescale(&mut self, kt: f64) -> Result<(), SmdError> {
        let kt = positive("temperature", kt)?;
        self.sys.scale_to(kt, kt);
        let (t, r) = self.sys.kinetic_energy();
        self.energy.kinetic_translational = t;
        self.energy.kinetic_rotational = r;
        self.set_reference();
        Ok(())
    }

    fn set_reference(&mut self) {
        self.e_ref = self.energy.total();
        self.e_scale = self.energy.kinetic() + self.energy.potential.abs();
    }

    /// One step of the splitting (kick, drift with the exact free motion, kick).
    ///
    /// # Errors
    /// [`SmdError::Overlap`] or [`SmdError::Unstable`]; the state is then that of the failed
    /// step and should not be continued.
    pub fn step(&mut self) -> Result<(), SmdError> {
        let h = 0.5 * self.dt;
        self.kick(h);
        self.drift()?;
        if self.list.needs_rebuild(&self.sys.pos) {
            self.list.build(&mut self.sys);
            self.reorthonormalise();
        }
        self.compute_forces()?;
        let (t, r) = self.kick(h);
        self.energy.kinetic_translational = t;
        self.energy.kinetic_rotational = r;
        self.step += 1;
        self.time = self.step as f64 * self.dt;
        self.check_finite()?;
        self.check_guard()
    }

    /// `steps` steps, sampling `observer` at the start and after every `sample_every` steps.
    ///
    /// # Errors
    /// [`SmdError::Count`] for `sample_every = 0`; any error of [`Integrator::step`].
    pub fn run<O: Observer + ?Sized>(
        &mut self,
        steps: u64,
        sample_every: u64,
        observer: &mut O,
    ) -> Result<RunStats, SmdError> {
        if sample_every == 0 {
            return Err(SmdError::Count {
                name: "sample_every",
                value: 0,
                why: "at least 1",
            });
        }
        let watch = Stopwatch::start();
        let (b0, p0, t0) = (self.list.builds(), self.pair_evaluations, self.time);
        observer.sample(&self.snapshot());
        for k in 1..=steps {
            self.step()?;
            if k % sample_every == 0 {
                observer.sample(&self.snapshot());
            }
        }
        Ok(self.stats(&watch, steps, b0, p0, t0))
    }

    /// `steps` steps of equilibration, rescaling to `kt` before the first and after every
    /// `rescale_every` steps (and at the end), so that production starts at `kt`.
    ///
    /// # Errors
    /// As [`Integrator::run`] and [`Integrator::rescale`].
    pub fn equilibrate(
        &mut self,
        steps: u64,
        rescale_every: u64,
        kt: f64,
    ) -> Result<RunStats, SmdError> {
        if rescale_every == 0 {
            return Err(SmdError::Count {
                name: "rescale_every",
                value: 0,
                why: "at least 1",
            });
        }
        let watch = Stopwatch::start();
        let (b0, p0, t0) = (self.list.builds(), self.pair_evaluations, self.time);
        self.rescale(kt)?;
        for k in 1..=steps {
            self.step()?;
            if k % rescale_every == 0 || k == steps {
                self.rescale(kt)?;
            }
        }
        Ok(self.stats(&watch, steps, b0, p0, t0))
    }

    fn stats(&self, watch: &Stopwatch, steps: u64, b0: u64, p0: u64, t0: f64) -> RunStats {
        let (wall_seconds, cpu_seconds) = watch.read();
        RunStats {
            bodies: self.sys.n(),
            steps,
            simulated_time: self.time - t0,
            builds: self.list.builds() - b0,
            pair_evaluations: self.pair_evaluations - p0,
            wall_seconds,
            cpu_seconds,
        }
    }

    /// Half kick: `v += h F/m`, `L += h τ`. Returns the kinetic energies after it.
    fn kick(&mut self, h: f64) -> (f64, f64) {
        let m = self.sys.body.mass();
        let hm = h / m;
        let mut v2 = 0.0;
        for (v, f) in self.sys.vel.iter_mut().zip(&self.force) {
            *v += *f * hm;
            v2 += v.length_squared();
        }
        let rot = match self.sys.body {
            BodyModel::Sphere { .. } => 0.0,
            BodyModel::LinearRotor { inertia, .. } => {
                let mut l2 = 0.0;
                if self.torques {
                    for (l, t) in self.sys.ang_mom.iter_mut().zip(&self.torque) {
                        *l += *t * h;
                        l2 += l.length_squared();
                    }
                } else {
                    l2 = self.sys.ang_mom.iter().map(|l| l.length_squared()).sum();
                }
                0.5 * l2 / inertia
            }
            BodyModel::Rigid { moments, .. } => {
                let inv = DVec3::ONE / DVec3::from(moments.get());
                let mut k = 0.0;
                for (i, (l, r)) in self.sys.ang_mom.iter_mut().zip(&self.sys.rot).enumerate() {
                    if self.torques {
                        *l += self.torque[i] * h;
                    }
                    let lb = r.transpose() * *l;
                    k += (lb * lb * inv).element_sum();
                }
                0.5 * k
            }
        };
        (0.5 * m * v2, rot)
    }

    /// Free motion over `dt`: translation, and the exact free rotation of `rigid-free`.
    fn drift(&mut self) -> Result<(), SmdError> {
        let dt = self.dt;
        for (p, v) in self.sys.pos.iter_mut().zip(&self.sys.vel) {
            *p += *v * dt;
        }
        match self.sys.body {
            BodyModel::Sphere { .. } => {}
            BodyModel::LinearRotor { inertia, .. } => {
                let inv = 1.0 / inertia;
                for i in 0..self.sys.n() {
                    let l = self.sys.ang_mom[i];
                    if l == DVec3::ZERO {
                        continue;
                    }
                    // ω = L/I, constant; the axis turns uniformly about it. The rotor drops
                    // any component of ω along the axis (the decoupled spin).
                    let rotor = LinearRotor::new(self.sys.axis[i], l * inv)
                        .map_err(|e| self.unstable(format!("body {i}: {e}")))?;
                    self.sys.axis[i] = rotor.axis(dt);
                    self.sys.ang_mom[i] = rotor.omega() * inertia;
                }
            }
            BodyModel::Rigid { moments, axis, .. } => {
                let inv = DVec3::ONE / DVec3::from(moments.get());
                for i in 0..self.sys.n() {
                    let (r, l) = (self.sys.rot[i], self.sys.ang_mom[i]);
                    if l == DVec3::ZERO {
                        continue;
                    }
                    // The lab angular momentum is constant in free motion; only the
                    // orientation moves (FreeMotion takes the attitude A = Rᵀ).
                    let omega_body = (r.transpose() * l) * inv;
                    let motion = FreeMotion::new(&moments, r.transpose(), omega_body)
                        .map_err(|e| self.unstable(format!("body {i}: {e}")))?;
                    let r = motion.pose(dt).orientation;
                    self.sys.rot[i] = r;
                    self.sys.axis[i] = r * axis;
                }
            }
        }
        Ok(())
    }

    /// Rigid bodies: brings the orientations back to exact rotations (round-off accumulates
    /// over many steps; rigid-free refuses attitudes more than 1e-9 from orthogonal). Done at
    /// list builds, every few tens of steps.
    fn reorthonormalise(&mut self) {
        if let BodyModel::Rigid { axis, .. } = self.sys.body {
            for (r, s) in self.sys.rot.iter_mut().zip(self.sys.axis.iter_mut()) {
                *r = DMat3::from_quat(DQuat::from_mat3(r).normalize());
                *s = *r * axis;
            }
        }
    }

    fn compute_forces(&mut self) -> Result<(), SmdError> {
        let out = self.pot.evaluate(
            self.torques,
            self.cutoff2,
            &self.list,
            &self.sys,
            &mut self.attitudes,
            &mut self.force,
            &mut self.torque,
        );
        match out {
            Ok(PairSums {
                energy,
                virial,
                pairs,
            }) => {
                self.energy.potential = energy;
                self.energy.virial = virial;
                self.pair_evaluations += pairs;
                Ok(())
            }
            Err(PairFailure { i, j, error }) => Err(SmdError::Overlap {
                step: self.step,
                time: self.time,
                i,
                j,
                source: error,
            }),
        }
    }

    fn unstable(&self, what: String) -> SmdError {
        SmdError::Unstable {
            step: self.step,
            time: self.time,
            what,
        }
    }

    fn check_finite(&self) -> Result<(), SmdError> {
        let e = self.energy;
        if e.total().is_finite() && e.virial.is_finite() {
            Ok(())
        } else {
            Err(self.unstable(format!(
                "the energy is not finite (kinetic {} + {}, potential {}, virial {})",
                e.kinetic_translational, e.kinetic_rotational, e.potential, e.virial
            )))
        }
    }

    fn check_guard(&self) -> Result<(), SmdError> {
        let e = self.energy.total();
        let band = self.guard * self.e_scale;
        if (e - self.e_ref).abs() <= band {
            Ok(())
        } else {
            Err(self.unstable(format!(
                "the total energy moved from {:.6e} to {e:.6e}, more than the guard band \
                 {band:.3e} ({} of K + |U| = {:.3e} at the reference)",
                self.e_ref, self.guard, self.e_scale
            )))
        }
    }
}

#[cfg(test)]
mod tests {
    use potential::SoftStickyDipole;

    use crate::{Integrator, Lattice, Observer, Rigid, Settings, Setup, Snapshot, System, units};

    /// Total and potential energies at every sample.
    struct Energies(Vec<(f64, f64)>);

    impl Observer for Energies {
        fn sample(&mut self, s: &Snapshot<'_>) {
            self.0.push((s.energy.total(), s.energy.potential));
        }
    }

    fn std(x: impl Iterator<Item = f64> + Clone) -> f64 {
        let n = x.clone().count() as f64;
        let mean = x.clone().sum::<f64>() / n;
        (x.map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt()
    }

    /// 343 SSD/E molecules at liquid density (0.0333 Å⁻³, 21.7 Å box) and 298 K, melted by
    /// rescaled steps, then NVE at 1 fs: the total energy fluctuates by a small fraction of
    /// the potential energy's fluctuation, and the momentum stays zero.
    #[test]
    fn water_conserves_energy_and_momentum() {
        let kt = 2.479; // kJ/mol at 298.15 K
        let setup = Setup {
            lattice: Lattice::Sc,
            ..Setup::new(343, 0.0333, crate::forces::tests::water(), kt)
        };
        let p = SoftStickyDipole::ssd_e();
        let pot = Rigid::new(p, p.cutoff()).unwrap();
        let system = System::new(&setup).unwrap();
        let melt = Settings::new(units::from_fs(0.5), 1.0);
        let mut md = Integrator::new(system, pot, melt).unwrap();
        md.equilibrate(100, 10, kt).unwrap();
        let mut md = Integrator::new(
            md.into_system(),
            pot,
            Settings::new(units::from_fs(1.0), 1.0),
        )
        .unwrap();
        let mut e = Energies(Vec::new());
        md.run(200, 1, &mut e).unwrap();
        let ratio = std(e.0.iter().map(|x| x.0)) / std(e.0.iter().map(|x| x.1));
        assert!(ratio < 0.05, "std(E)/std(U) = {ratio}");
        assert!(
            md.system().momentum().length() < 1e-9 * 343.0,
            "{}",
            md.system().momentum()
        );
        eprintln!(
            "water NVE at 1 fs: std(E)/std(U) = {ratio:.4}, U/N = {:.3} kJ/mol",
            md.energy().potential / 343.0
        );
    }
}
