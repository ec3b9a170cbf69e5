//! The rotation of a rigid body between events: what the event loop's straight lines leave
//! out of a body's state, behind one trait, and [`Rotations`], every body's rotation as a
//! model of rigid bodies keeps it.
//!
//! A [`Rotor`] is the exact free rotation of one body from the moment of its last change (its
//! *anchor*): its pose and lab angular velocity at any later time, its kinetic energy and
//! angular momentum (constant between events), how a fresh one is drawn from equipartition, how
//! it is reversed, saved bit for bit and turned into the body of an impulse rule. Two kinds of
//! body implement it, and a terraced scene pays only for its own (static dispatch):
//!
//! - [`LinearRotor`] (the rods of 003 §V): the pose is the unit axis, two rotational degrees of
//!   freedom, no spin about the axis; the impulse acts on a `collide::LinearBody`.
//! - [`Top`]: any rigid body with three principal moments, a `rigid_free::FreeMotion` (sphere,
//!   symmetric top, asymmetric top near or on the separatrix, each by its exact solution); the
//!   pose is the unit quaternion taking body to lab coordinates, three rotational degrees of
//!   freedom, the impulse acts on a `collide::RigidBody` with the full lab inertia tensor
//!   (003 Eq. 21).

use collide::{CollideError, LinearBody, RigidBody};
use glam::{DMat3, DQuat, DVec3};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use rigid_free::{FreeMotion, LinearRotor, Moments};

/// The exact free rotation of one body since its anchor (module documentation). Times are
/// measured from the anchor.
pub trait Rotor: Copy + std::fmt::Debug + PartialEq + Send + Sync + 'static {
    /// A species' rotational inertia.
    type Inertia: Copy + std::fmt::Debug + PartialEq + Send + Sync + 'static;
    /// What a pair potential reads of the body's attitude.
    type Pose: Copy + std::fmt::Debug + Send + Sync + 'static;
    /// The body of the impulse rule.
    type Body: collide::Body;
    /// Numbers per rotor in a saved state.
    const PARTS: usize;
    /// Rotational degrees of freedom per body.
    const DOF: f64;

    /// Whether `inertia` is usable: `Err((what, value))` names the first bad number.
    ///
    /// # Errors
    /// The name and value of a moment that is not finite and positive.
    fn check(inertia: &Self::Inertia) -> Result<(), (&'static str, f64)>;

    /// The rotation that starts at `pose` with lab angular velocity `omega`.
    ///
    /// # Errors
    /// A non-finite input, or a pose that is not a rotation.
    fn start(inertia: &Self::Inertia, pose: Self::Pose, omega: DVec3) -> Result<Self, String>;

    /// The pose `dt` after the anchor.
    fn pose(&self, dt: f64) -> Self::Pose;

    /// The pose and the lab angular velocity `dt` after the anchor.
    fn pose_omega(&self, dt: f64) -> (Self::Pose, DVec3);

    /// The lab angular velocity at the anchor.
    fn omega(&self) -> DVec3;

    /// The rotational kinetic energy (constant).
    fn kinetic(&self, inertia: &Self::Inertia) -> f64;

    /// The lab angular momentum (constant).
    fn momentum(&self, inertia: &Self::Inertia) -> DVec3;

    /// A lab angular velocity for a body at `pose`, drawn from equipartition at `kt`.
    fn draw(
        inertia: &Self::Inertia,
        pose: Self::Pose,
        kt: f64,
        rng: &mut Xoshiro256PlusPlus,
    ) -> DVec3;

    /// The same rotation run backwards from its anchor: its pose at `dt` is this one's at
    /// `−dt` (hybrid Monte Carlo's momentum reversal).
    ///
    /// # Errors
    /// As [`start`](Self::start).
    fn reversed(&self, inertia: &Self::Inertia) -> Result<Self, String>;

    /// The unit quaternion taking body to lab coordinates at `pose`.
    fn attitude(pose: &Self::Pose) -> DQuat;

    /// The body's reference axis in the lab at `pose` (the rod's axis; a top's body `ẑ`).
    fn axis(pose: &Self::Pose) -> DVec3;

    /// The body of the impulse rule at `pose`.
    ///
    /// # Errors
    /// The rule's checks of mass and moments.
    fn body(
        mass: f64,
        inertia: &Self::Inertia,
        pose: &Self::Pose,
    ) -> Result<Self::Body, CollideError>;

    /// Appends the [`PARTS`](Self::PARTS) numbers from which [`read`](Self::read) rebuilds
    /// this rotation bit for bit.
    fn write(&self, out: &mut Vec<f64>);

    /// The rotation [`write`](Self::write) saved.
    ///
    /// # Errors
    /// Numbers that describe no rotation.
    fn read(inertia: &Self::Inertia, parts: &[f64]) -> Result<Self, String>;
}

/// Three independent Gaussians.
fn gaussian3(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    DVec3::new(
        StandardNormal.sample(rng),
        StandardNormal.sample(rng),
        StandardNormal.sample(rng),
    )
}

fn finite_positive(what: &'static str, x: f64) -> Result<(), (&'static str, f64)> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err((what, x))
    }
}

/// A rod: the inertia is its moment `I₁ = I₂` about axes perpendicular to its own.
/// One body's free rotation since its last change at time `t` (its anchor).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anchored<R> {
    /// The rotation from the anchor.
    pub rotor: R,
    /// The anchor's time on the loop's clock.
    pub t: f64,
}

impl<R: Rotor> Anchored<R> {
    /// The pose at `now`.
    #[inline(always)]
    pub fn pose(&self, now: f64) -> R::Pose {
        self.rotor.pose(now - self.t)
    }

    /// The pose and lab angular velocity at `now`.
    #[inline(always)]
    pub fn pose_omega(&self, now: f64) -> (R::Pose, DVec3) {
        self.rotor.pose_omega(now - self.t)
    }
}

/// The free rotations of every body of a model of rigid bodies, each anchored at its last
/// change, with the inertia of each body's species: what such a model does with them at the
/// loop's hooks (re-basing, kinetic energy, the thermostat, HMC's draw, reversal and scaling,
/// checkpoints), written once for every model and every [`Rotor`].
#[derive(Clone, Debug)]
pub struct Rotations<R: Rotor> {
    /// Each body's rotation.
    pub bodies: Vec<Anchored<R>>,
    /// Each body's species.
    species: Vec<u32>,
    /// Each species' inertia.
    inertia: Vec<R::Inertia>,
}

impl<R: Rotor> Rotations<R> {
    /// The rotations `bodies` of bodies of species `species` (indexing `inertia`).
    pub fn new(bodies: Vec<Anchored<R>>, species: &[u32], inertia: Vec<R::Inertia>) -> Self {
        assert_eq!(bodies.len(), species.len(), "one species per body");
        Rotations {
            bodies,
            species: species.to_vec(),
            inertia,
        }
    }

    /// The inertia of body `i`.
    #[inline(always)]
    pub fn inertia_of(&self, i: u32) -> &R::Inertia {
        &self.inertia[self.species[i as usize] as usize]
    }

    /// Body `i` rotates from `pose` with lab angular velocity `omega` from `now` on.
    ///
    /// # Errors
    /// A pose or angular velocity that is not finite.
    pub fn restart(&mut self, i: u32, pose: R::Pose, omega: DVec3, now: f64) -> Result<(), String> {
        let rotor = R::start(self.inertia_of(i), pose, omega)?;
        self.bodies[i as usize] = Anchored { rotor, t: now };
        Ok(())
    }

    /// Re-anchors every rotation at the new time origin `t0` (rotation angles stay small).
    pub fn rebase(&mut self, t0: f64) {
        for (r, &s) in self.bodies.iter_mut().zip(&self.species) {
            let (pose, omega) = r.pose_omega(t0);
            if let Ok(rotor) = R::start(&self.inertia[s as usize], pose, omega) {
                *r = Anchored { rotor, t: 0.0 };
            } else {
                // Not finite (a broken invariant, reported elsewhere): keep the old anchor.
                r.t -= t0;
            }
        }
    }

    /// Rotational kinetic energy of all bodies.
    pub fn kinetic(&self) -> f64 {
        let mut k = crate::engine::sum::Compensated::ZERO;
        for (r, &s) in self.bodies.iter().zip(&self.species) {
            k.add(r.rotor.kinetic(&self.inertia[s as usize]));
        }
        k.value()
    }

    /// Rotational degrees of freedom of all bodies.
    pub fn dof(&self) -> f64 {
        R::DOF * self.bodies.len() as f64
    }

    /// An Andersen collision of body `i` at `now`: a fresh angular velocity at `kt`; returns
    /// the change of kinetic energy (0 if it could not be drawn).
    pub fn thermalize(&mut self, i: u32, now: f64, kt: f64, rng: &mut Xoshiro256PlusPlus) -> f64 {
        let inertia = *self.inertia_of(i);
        let r = self.bodies[i as usize];
        let pose = r.pose(now);
        let w = R::draw(&inertia, pose, kt, rng);
        let Ok(rotor) = R::start(&inertia, pose, w) else {
            return 0.0;
        };
        let dk = rotor.kinetic(&inertia) - r.rotor.kinetic(&inertia);
        self.bodies[i as usize] = Anchored { rotor, t: now };
        dk
    }

    /// Angular momentum of body `i`.
    #[inline]
    pub fn spin(&self, i: u32) -> DVec3 {
        self.bodies[i as usize].rotor.momentum(self.inertia_of(i))
    }

    /// Lab angular velocity of body `i`.
    #[inline]
    pub fn omega(&self, i: u32) -> DVec3 {
        self.bodies[i as usize].rotor.omega()
    }

    /// Body `i`'s axis at `now` ([`Rotor::axis`]).
    #[inline]
    pub fn axis(&self, i: u32, now: f64) -> DVec3 {
        R::axis(&self.bodies[i as usize].pose(now))
    }

    /// Body `i`'s attitude at `now` ([`Rotor::attitude`]).
    #[inline]
    pub fn attitude(&self, i: u32, now: f64) -> DQuat {
        R::attitude(&self.bodies[i as usize].pose(now))
    }

    /// Fresh angular velocities for every body at `now`, drawn at `kt` (HMC's refresh).
    pub fn draw(&mut self, now: f64, kt: f64, rng: &mut Xoshiro256PlusPlus) {
        for (r, &s) in self.bodies.iter_mut().zip(&self.species) {
            let inertia = &self.inertia[s as usize];
            let pose = r.pose(now);
            let w = R::draw(inertia, pose, kt, rng);
            if let Ok(rotor) = R::start(inertia, pose, w) {
                *r = Anchored { rotor, t: now };
            }
        }
    }

    /// Reverses every rotation at time 0 (HMC reverses at a re-basing, where every body is
    /// anchored: there the reversal is exact, the body turns back the way it came).
    pub fn reverse(&mut self) {
        for (r, &s) in self.bodies.iter_mut().zip(&self.species) {
            let inertia = &self.inertia[s as usize];
            let reversed = if r.t == 0.0 {
                r.rotor.reversed(inertia)
            } else {
                let (pose, omega) = r.pose_omega(0.0);
                R::start(inertia, pose, -omega)
            };
            if let Ok(rotor) = reversed {
                *r = Anchored { rotor, t: 0.0 };
            }
        }
    }

    /// Scales every angular velocity by `factor` at `now`: each rotation restarts from its
    /// present pose (a linear rotor's ω stays perpendicular to its axis, a top's keeps its
    /// direction in the body, so the energy is exactly factor² times the old one up to
    /// round-off).
    pub fn scale(&mut self, now: f64, factor: f64) {
        for (r, &s) in self.bodies.iter_mut().zip(&self.species) {
            let (pose, omega) = r.pose_omega(now);
            if let Ok(rotor) = R::start(&self.inertia[s as usize], pose, factor * omega) {
                *r = Anchored { rotor, t: now };
            }
        }
    }

    /// Numbers of the rotations in a saved state.
    pub fn numbers(&self) -> usize {
        (R::PARTS + 1) * self.bodies.len()
    }

    /// Appends every rotation and its anchor time to a saved state, bit for bit.
    pub fn write(&self, x: &mut Vec<f64>) {
        for r in &self.bodies {
            r.rotor.write(x);
            x.push(r.t);
        }
    }

    /// Reads what [`write`](Self::write) wrote (exactly [`numbers`](Self::numbers) of
    /// them) and takes it.
    ///
    /// # Errors
    /// A rotation or clock that does not fit the bodies.
    pub fn read(&mut self, state: &[f64]) -> Result<(), String> {
        let per_body = R::PARTS + 1;
        if state.len() != self.numbers() {
            return Err(format!(
                "the rotations' state has {} numbers, {} bodies need {}",
                state.len(),
                self.bodies.len(),
                self.numbers()
            ));
        }
        let mut restored = Vec::with_capacity(self.bodies.len());
        for ((i, x), &s) in state.chunks_exact(per_body).enumerate().zip(&self.species) {
            let (parts, t) = x.split_at(R::PARTS);
            let rotor = R::read(&self.inertia[s as usize], parts)
                .map_err(|e| format!("body {i} cannot be restored: {e}"))?;
            if !t[0].is_finite() {
                return Err(format!("body {i} has a non-finite clock"));
            }
            restored.push(Anchored { rotor, t: t[0] });
        }
        self.bodies = restored;
        Ok(())
    }
}

/// The loop's rotation hooks of [`PairModel`](crate::engine::model::PairModel) for a model
/// of rigid bodies whose rotations are its [`Rotations`] field `$rot`: re-basing, kinetic
/// energy and degrees of freedom, the thermostat, angular momentum and velocity, axis and
/// attitude (a rod's body frame has z along its axis and no spin about it; a top's is its
/// principal frame), and HMC's draw, reversal and scaling. Used inside the model's `impl
/// PairModel`.
macro_rules! rotation_hooks {
    ($rot:ident) => {
        fn rebase(&mut self, t0: f64) {
            self.$rot.rebase(t0);
        }

        fn rotational_kinetic(&self) -> f64 {
            self.$rot.kinetic()
        }

        fn rotational_dof(&self) -> f64 {
            self.$rot.dof()
        }

        fn thermalize(
            &mut self,
            i: u32,
            _s: u32,
            now: f64,
            kt: f64,
            rng: &mut rand_xoshiro::Xoshiro256PlusPlus,
        ) -> f64 {
            self.$rot.thermalize(i, now, kt, rng)
        }

        #[inline]
        fn spin(&self, i: u32, _s: u32) -> glam::DVec3 {
            self.$rot.spin(i)
        }

        #[inline]
        fn omega(&self, i: u32) -> glam::DVec3 {
            self.$rot.omega(i)
        }

        #[inline]
        fn axis(&self, i: u32, now: f64) -> Option<glam::DVec3> {
            Some(self.$rot.axis(i, now))
        }

        fn attitude(&self, i: u32, now: f64) -> Option<glam::DQuat> {
            Some(self.$rot.attitude(i, now))
        }

        fn draw_rotations(
            &mut self,
            now: f64,
            temperature: f64,
            rng: &mut rand_xoshiro::Xoshiro256PlusPlus,
        ) {
            self.$rot.draw(now, temperature, rng);
        }

        fn reverse_rotations(&mut self) {
            self.$rot.reverse();
        }

        fn scale_rotations(&mut self, now: f64, factor: f64) {
            self.$rot.scale(now, factor);
        }
    };
}
pub(crate) use rotation_hooks;

impl Rotor for LinearRotor {
    type Inertia = f64;
    type Pose = DVec3;
    type Body = LinearBody;
    const PARTS: usize = 10;
    const DOF: f64 = 2.0;

    fn check(inertia: &f64) -> Result<(), (&'static str, f64)> {
        finite_positive("inertia", *inertia)
    }

    fn start(_: &f64, pose: DVec3, omega: DVec3) -> Result<Self, String> {
        LinearRotor::new(pose, omega).map_err(|e| e.to_string())
    }

    #[inline(always)]
    fn pose(&self, dt: f64) -> DVec3 {
        self.axis(dt)
    }

    #[inline(always)]
    fn pose_omega(&self, dt: f64) -> (DVec3, DVec3) {
        (self.axis(dt), LinearRotor::omega(self))
    }

    #[inline(always)]
    fn omega(&self) -> DVec3 {
        LinearRotor::omega(self)
    }

    fn kinetic(&self, inertia: &f64) -> f64 {
        0.5 * inertia * LinearRotor::omega(self).length_squared()
    }

    fn momentum(&self, inertia: &f64) -> DVec3 {
        *inertia * LinearRotor::omega(self)
    }

    /// Each of the two components perpendicular to the axis Gaussian with variance `kT / I`.
    fn draw(inertia: &f64, pose: DVec3, kt: f64, rng: &mut Xoshiro256PlusPlus) -> DVec3 {
        let g = gaussian3(rng) * (kt / inertia).sqrt();
        let s = pose.normalize();
        g - s * s.dot(g)
    }

    fn reversed(&self, _: &f64) -> Result<Self, String> {
        Ok(LinearRotor::reversed(self))
    }

    /// The body frame has `ẑ` along the axis and no spin about it: the attitude is the shortest
    /// rotation taking `ẑ` onto the axis.
    fn attitude(pose: &DVec3) -> DQuat {
        DQuat::from_rotation_arc(DVec3::Z, pose.normalize())
    }

    #[inline(always)]
    fn axis(pose: &DVec3) -> DVec3 {
        *pose
    }

    #[inline]
    fn body(mass: f64, inertia: &f64, pose: &DVec3) -> Result<LinearBody, CollideError> {
        LinearBody::new(mass, *inertia, *pose)
    }

    fn write(&self, out: &mut Vec<f64>) {
        out.extend_from_slice(&self.to_parts());
    }

    fn read(_: &f64, parts: &[f64]) -> Result<Self, String> {
        let p: [f64; 10] = parts
            .try_into()
            .map_err(|_| format!("a rod's rotation has 10 numbers, not {}", parts.len()))?;
        let rotor = LinearRotor::from_parts(p).map_err(|e| e.to_string())?;
        // The saved numbers are those of a rotor made by `LinearRotor::new`: ω ⟂ s, the rate
        // |ω| and v₀ = ω̂ × s, to round-off; anything else is a state no run reaches (a rod
        // spinning about its own axis, or an axis that turns at another rate than ω says).
        let (s, v, w) = (
            DVec3::from_slice(&p[..3]),
            DVec3::from_slice(&p[3..6]),
            rotor.omega(),
        );
        let rate = w.length();
        let tol = 1e-9;
        if w.dot(s).abs() > tol * rate {
            return Err(format!(
                "its angular velocity ({:.3e}, {:.3e}, {:.3e}) has a component {:.3e} along \
                 the rod's axis: a rod turns only about its short axes, so its angular \
                 velocity must be perpendicular to its axis",
                w.x,
                w.y,
                w.z,
                w.dot(s)
            ));
        }
        let v_expected = if rate > 0.0 {
            (w / rate).cross(s)
        } else {
            DVec3::ZERO
        };
        if (p[6] - rate).abs() > tol * rate || (v - v_expected).length() > tol {
            return Err(format!(
                "its rotation rate {:.3e} and axis velocity do not follow from its angular \
                 velocity (|ω| = {rate:.3e})",
                p[6]
            ));
        }
        Ok(rotor)
    }
}

/// How far (relative) a largest moment may exceed the sum of the other two and be taken for
/// a planar body's: the rounding of published moments.
pub const PLANAR_ROUNDING: f64 = 1e-3;

/// The principal moments of a rigid body about body axes `x`, `y`, `z`, checked once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TopInertia {
    moments: Moments,
    principal: DVec3,
}

impl TopInertia {
    /// Moments `(I_x, I_y, I_z)` about the body axes, which are the principal axes. A largest
    /// moment above the sum of the other two by at most [`PLANAR_ROUNDING`] of it is the
    /// rounding of a published planar body's moments (water's `1.7696 > 0.6145 + 1.1550`) and
    /// is set to that sum: the body is planar.
    ///
    /// # Errors
    /// A moment that is not finite and positive, or three that violate the triangle inequality
    /// `I_a ≤ I_b + I_c` by more (no mass distribution has them).
    pub fn new(principal: DVec3) -> Result<Self, String> {
        for (k, &m) in principal.to_array().iter().enumerate() {
            if !(m.is_finite() && m > 0.0) {
                return Err(format!(
                    "moment {k} is {m}: every moment must be finite and > 0"
                ));
            }
        }
        let mut principal = principal;
        let k = principal.max_position();
        let others = principal[(k + 1) % 3] + principal[(k + 2) % 3];
        if principal[k] > others {
            if principal[k] - others > PLANAR_ROUNDING * principal[k] {
                return Err(format!(
                    "moments {:?} violate I_a <= I_b + I_c: no rigid body has them",
                    principal.to_array()
                ));
            }
            principal[k] = others;
        }
        let moments = Moments::new(principal.to_array()).map_err(|e| e.to_string())?;
        Ok(Self { moments, principal })
    }

    /// The moments about body `x`, `y`, `z`.
    pub fn principal(&self) -> DVec3 {
        self.principal
    }
}

/// A rigid body with three principal moments, moving by the exact torque-free solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Top {
    motion: FreeMotion,
    /// [`Top::spin_bounds`], computed once per motion.
    spin: (f64, f64),
}

impl Top {
    fn new(motion: FreeMotion) -> Self {
        let spin = potential::certify::torque_free_bounds(
            motion.moments().get(),
            motion.initial_pose().omega,
        );
        Self { motion, spin }
    }

    #[inline(always)]
    fn quat(orientation: &DMat3) -> DQuat {
        DQuat::from_mat3(orientation).normalize()
    }

    /// `(W, Ẇ)`: bounds on `|ω|` and `|ω̇|` at every time of this motion
    /// ([`potential::certify::torque_free_bounds`]), for certified prediction.
    #[inline]
    pub fn spin_bounds(&self) -> (f64, f64) {
        self.spin
    }
}

impl Rotor for Top {
    type Inertia = TopInertia;
    type Pose = DQuat;
    type Body = RigidBody;
    const PARTS: usize = 12;
    const DOF: f64 = 3.0;

    fn check(inertia: &TopInertia) -> Result<(), (&'static str, f64)> {
        let p = inertia.principal;
        finite_positive("moment x", p.x)?;
        finite_positive("moment y", p.y)?;
        finite_positive("moment z", p.z)
    }

    fn start(inertia: &TopInertia, pose: DQuat, omega: DVec3) -> Result<Self, String> {
        let body_omega = pose.normalize().inverse() * omega;
        FreeMotion::from_quat(&inertia.moments, pose, body_omega)
            .map(Top::new)
            .map_err(|e| e.to_string())
    }

    #[inline]
    fn pose(&self, dt: f64) -> DQuat {
        Self::quat(&self.motion.pose(dt).orientation)
    }

    #[inline]
    fn pose_omega(&self, dt: f64) -> (DQuat, DVec3) {
        let p = self.motion.pose(dt);
        (Self::quat(&p.orientation), p.omega_lab())
    }

    #[inline]
    fn omega(&self) -> DVec3 {
        self.motion.initial_pose().omega_lab()
    }

    fn kinetic(&self, inertia: &TopInertia) -> f64 {
        let w = self.motion.initial_pose().omega;
        0.5 * (inertia.principal * w * w).element_sum()
    }

    fn momentum(&self, inertia: &TopInertia) -> DVec3 {
        let p = self.motion.initial_pose();
        p.orientation * (inertia.principal * p.omega)
    }

    /// Each body-frame component Gaussian with variance `kT / I_k`.
    fn draw(inertia: &TopInertia, pose: DQuat, kt: f64, rng: &mut Xoshiro256PlusPlus) -> DVec3 {
        let w = gaussian3(rng) * (DVec3::splat(kt) / inertia.principal).map(f64::sqrt);
        pose.normalize() * w
    }

    fn reversed(&self, inertia: &TopInertia) -> Result<Self, String> {
        let p = self.motion.initial_pose();
        FreeMotion::new(&inertia.moments, p.orientation.transpose(), -p.omega)
            .map(Top::new)
            .map_err(|e| e.to_string())
    }

    #[inline(always)]
    fn attitude(pose: &DQuat) -> DQuat {
        *pose
    }

    #[inline]
    fn axis(pose: &DQuat) -> DVec3 {
        *pose * DVec3::Z
    }

    #[inline]
    fn body(mass: f64, inertia: &TopInertia, pose: &DQuat) -> Result<RigidBody, CollideError> {
        RigidBody::from_principal(mass, inertia.principal, *pose)
    }

    /// The anchor's orientation matrix and body-frame angular velocity, from which
    /// `FreeMotion::new` builds the same motion bit for bit.
    fn write(&self, out: &mut Vec<f64>) {
        let p = self.motion.initial_pose();
        out.extend_from_slice(&p.orientation.to_cols_array());
        out.extend_from_slice(&p.omega.to_array());
    }

    fn read(inertia: &TopInertia, parts: &[f64]) -> Result<Self, String> {
        if parts.len() != 12 {
            return Err(format!(
                "a top's rotation has 12 numbers, not {}",
                parts.len()
            ));
        }
        let orientation = DMat3::from_cols_slice(&parts[..9]);
        let omega = DVec3::from_slice(&parts[9..]);
        FreeMotion::new(&inertia.moments, orientation.transpose(), omega)
            .map(Top::new)
            .map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn water() -> TopInertia {
        TopInertia::new(DVec3::new(1.7696, 0.6145, 1.1550)).unwrap()
    }

    #[test]
    fn a_top_conserves_energy_and_momentum_and_round_trips() {
        let inertia = water();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        let q = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.9);
        let w = Top::draw(&inertia, q, 2.5, &mut rng);
        let top = Top::start(&inertia, q, w).unwrap();
        assert!((top.omega() - w).length() < 1e-13 * w.length());
        let (e0, l0) = (top.kinetic(&inertia), top.momentum(&inertia));
        for dt in [0.01, 0.3, 7.0] {
            let (pose, omega) = top.pose_omega(dt);
            let later = Top::start(&inertia, pose, omega).unwrap();
            assert!((later.kinetic(&inertia) - e0).abs() < 1e-12 * e0);
            assert!((later.momentum(&inertia) - l0).length() < 1e-12 * l0.length());
        }
        let mut parts = Vec::new();
        top.write(&mut parts);
        assert_eq!(parts.len(), Top::PARTS);
        let back = Top::read(&inertia, &parts).unwrap();
        assert_eq!(back.pose(0.37), top.pose(0.37));
        // Reversed, the top retraces its path.
        let rev = top.reversed(&inertia).unwrap();
        let (a, b) = (rev.pose(0.2), top.pose(-0.2));
        assert!(a.dot(b).abs() > 1.0 - 1e-13);
    }

    #[test]
    fn equipartition_of_drawn_tops_and_rods() {
        let inertia = water();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let n = 20_000;
        let mut k_top = 0.0;
        let mut k_rod = 0.0;
        for _ in 0..n {
            let q = DQuat::from_axis_angle(gaussian3(&mut rng).normalize(), 1.3);
            let w = Top::draw(&inertia, q, 2.0, &mut rng);
            k_top += Top::start(&inertia, q, w).unwrap().kinetic(&inertia);
            let s = q * DVec3::Z;
            let w = LinearRotor::draw(&0.7, s, 2.0, &mut rng);
            k_rod += Rotor::kinetic(&LinearRotor::new(s, w).unwrap(), &0.7);
        }
        // ½ kT per degree of freedom, to 3 standard errors (each term has relative spread √2).
        let tol = 3.0 * (2.0f64 / (3.0 * n as f64)).sqrt();
        assert!(
            (k_top / n as f64 / 3.0 - 1.0).abs() < tol,
            "{}",
            k_top / n as f64
        );
        assert!(
            (k_rod / n as f64 / 2.0 - 1.0).abs() < tol,
            "{}",
            k_rod / n as f64
        );
    }

    #[test]
    fn impossible_moments_are_refused() {
        assert!(TopInertia::new(DVec3::new(1.0, 1.0, 3.0)).is_err());
        assert!(TopInertia::new(DVec3::new(1.0, 0.0, 1.0)).is_err());
        assert!(TopInertia::new(DVec3::new(1.0, f64::NAN, 1.0)).is_err());
        assert!(TopInertia::new(DVec3::new(1.0, 1.0, 2.0)).is_ok());
        // Published water: planar up to the rounding of the last digit.
        let w = water().principal();
        assert_eq!(w.x, w.y + w.z);
    }
}
