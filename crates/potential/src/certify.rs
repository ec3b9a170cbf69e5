//! Certified event prediction: a Taylor model with a rigorous remainder of an *effective
//! coordinate* of a pair, which proves stretches of free flight in which the pair cannot cross a
//! level of its terraced potential.
//!
//! An event-driven engine looks for the first time `U(t)` leaves the band `[U_lo, U_hi]` of
//! the pair's terrace (003 Eqs. 7–8). For many potentials `U` depends on the pair's geometry
//! through one scalar `x` alone: the centre distance `r` for Lennard-Jones spheres, the
//! effective distance `r_e = r + ζ(½ − (s_i·s_j)²)` for the rods of 003 Eq. 23. Then the band
//! is a set of intervals of `x` ([`PairPotential::coordinate_intervals`](crate::PairPotential::coordinate_intervals)), and a second-order
//! Taylor model of `x(t)` along the exact free flight,
//!
//! ```text
//! x(t₀ + τ) = x + ẋ τ + ẍ τ²/2 + R(τ),   |R(τ)| ≤ M τ³/6,   M ≥ sup |x⃛| on [t₀, t₀ + h],
//! ```
//!
//! ([`PairPotential::taylor_model`](crate::PairPotential::taylor_model)) bounds `x` on the whole window without evaluating `U`:
//! [`TaylorModel::safe_time`] returns a time up to which `x` provably stays inside the interval
//! `(a, b)` that holds it ([`interval_containing`]), so
//! a search may jump it and can never step over a crossing there. The bound `M` comes from
//! bounds on `|v|`, `|ω|` and the closest approach of the centres over the window.
//!
//! The contract of [`PairPotential::taylor_model`](crate::PairPotential::taylor_model), property-tested for the potentials that
//! implement it: for every `τ ∈ [0, h]` of a [`FreeFlight`] (straight-line relative motion,
//! each axis turning uniformly about a fixed `ω`),
//! `|x(τ) − x − ẋτ − ẍτ²/2| ≤ spread · τ²/2 + third · τ³/6`.
//!
//! **Rigid bodies of any shape** ([`RigidPairPotential::taylor_model`](crate::RigidPairPotential::taylor_model)): where `U` depends on
//! the whole attitudes, the coordinate is `U` itself and the model is of first order with a
//! second-order remainder, `U(τ) ∈ U + U̇τ ± Kτ²/2` with `K ≥ sup |Ü|` over the window
//! ([`TaylorModel::spread`]): for a potential with a cut-off `Ü` jumps where a site pair
//! crosses it, so no bound on `U⃛` exists, while `U̇` stays continuous and the bound on `|Ü|`
//! holds almost everywhere, which is all the integral form of the remainder needs. The bound
//! comes from bounds on the sites' speeds and accelerations over the window ([`RigidFlight`]).

use glam::{DQuat, DVec3};

/// The interval of `intervals` (disjoint, as [`PairPotential::coordinate_intervals`](crate::PairPotential::coordinate_intervals) returns
/// them) that holds `x` strictly inside, if any.
#[inline]
pub fn interval_containing(intervals: &[(f64, f64)], x: f64) -> Option<(f64, f64)> {
    intervals.iter().copied().find(|&(a, b)| a < x && x < b)
}

/// The interval of `intervals` that holds `x` to within the round-off margin `1e-8·|x|` that
/// [`TaylorModel::safe_time`] and [`TaylorModel::monotone`] allow: a pair that has just crossed
/// onto a terrace sits on an end of its interval, on either side of it by round-off.
#[inline]
pub fn interval_near(intervals: &[(f64, f64)], x: f64) -> Option<(f64, f64)> {
    let margin = 1e-8 * x.abs();
    intervals
        .iter()
        .copied()
        .find(|&(a, b)| a - margin <= x && x <= b + margin)
}

/// The free flight of a pair over a window: relative position and velocity of the centres
/// (`r_ij`, `v_ij = v_i − v_j`) at the window's start, each body's axis there, and its angular
/// velocity. The axes turn uniformly about their fixed `ω` (a linear rotor, or a sphere) and the
/// centres move on straight lines: the motion between events of 003 §V.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeFlight {
    /// `r_ij` at the window's start.
    pub r: DVec3,
    /// `v_ij`, constant over the window.
    pub v: DVec3,
    /// Axis of body `i` at the window's start.
    pub s_i: DVec3,
    /// Angular velocity of body `i` (constant).
    pub w_i: DVec3,
    /// Axis of body `j` at the window's start.
    pub s_j: DVec3,
    /// Angular velocity of body `j` (constant).
    pub w_j: DVec3,
    /// `ṡ_i = ω_i × s_i` at the window's start.
    pub ds_i: DVec3,
    /// `ṡ_j`.
    pub ds_j: DVec3,
    /// `s̈_i = ω_i × ṡ_i` (`−|ω_i|² s_i` for a linear rotor, whose `ω ⟂ s`).
    pub dds_i: DVec3,
    /// `s̈_j`.
    pub dds_j: DVec3,
    /// `Ω ≥ |ω_i| + |ω_j|` (engines keep the rates; [`FreeFlight::new`] computes it).
    pub spin: f64,
}

impl FreeFlight {
    /// The flight of these vectors, with `Ω = |ω_i| + |ω_j|`.
    pub fn new(r: DVec3, v: DVec3, s_i: DVec3, w_i: DVec3, s_j: DVec3, w_j: DVec3) -> Self {
        let (ds_i, ds_j) = (w_i.cross(s_i), w_j.cross(s_j));
        FreeFlight {
            r,
            v,
            s_i,
            w_i,
            s_j,
            w_j,
            ds_i,
            ds_j,
            dds_i: w_i.cross(ds_i),
            dds_j: w_j.cross(ds_j),
            spin: w_i.length() + w_j.length(),
        }
    }

    /// The square of the smallest centre distance over `[0, h]` (exact for straight-line
    /// motion).
    #[inline]
    pub fn closest_approach_squared(&self, h: f64) -> f64 {
        let b = self.r.dot(self.v);
        let v2 = self.v.length_squared();
        // Receding (or at rest): the start is the closest point, no division.
        if b >= 0.0 || v2 == 0.0 {
            return self.r.length_squared();
        }
        let tau = (-b / v2).min(h);
        (self.r + self.v * tau).length_squared()
    }

    /// `|r⃛|` bounded over `[0, h]`: along a straight line `r⃛ = −3 ṙ r̈ / r` with
    /// `r̈ = (|v|² − ṙ²)/r`, and `|ṙ|(|v|² − ṙ²) ≤ 2|v|³/(3√3)`, so `|r⃛| ≤ (2/√3)|v|³/r_lo²`.
    #[inline]
    pub fn distance_third_bound(&self, h: f64) -> f64 {
        let v2 = self.v.length_squared();
        if v2 == 0.0 {
            return 0.0;
        }
        let r_lo2 = self.closest_approach_squared(h);
        if r_lo2 == 0.0 {
            return f64::INFINITY;
        }
        (2.0 / 3f64.sqrt()) * v2 * v2.sqrt() / r_lo2
    }

    /// `r`, `ṙ`, `r̈` at the window's start.
    #[inline]
    pub fn distance_derivatives(&self) -> (f64, f64, f64) {
        let r = self.r.length();
        let inv = 1.0 / r;
        let rd = self.r.dot(self.v) * inv;
        let rdd = ((self.v.length_squared() - rd * rd) * inv).max(0.0);
        (r, rd, rdd)
    }

    /// `c = s_i·s_j`, `ċ`, `c̈` at the window's start.
    #[inline]
    pub fn alignment_derivatives(&self) -> (f64, f64, f64) {
        let (di, dj, ddi, ddj) = (self.ds_i, self.ds_j, self.dds_i, self.dds_j);
        (
            self.s_i.dot(self.s_j),
            di.dot(self.s_j) + self.s_i.dot(dj),
            ddi.dot(self.s_j) + 2.0 * di.dot(dj) + self.s_i.dot(ddj),
        )
    }
}

/// The free flight of a pair of rigid bodies of any shape over a window: relative position and
/// velocity of the centres at the window's start, each body's attitude and lab angular velocity
/// there, and bounds on `|ω|` and `|ω̇|` that hold over the whole window (for torque-free
/// motion, over all time: [`torque_free_bounds`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidFlight {
    /// `r_ij` at the window's start.
    pub r: DVec3,
    /// `v_ij`, constant over the window.
    pub v: DVec3,
    /// Attitude of body `i` (body → lab) at the window's start.
    pub q_i: DQuat,
    /// Attitude of body `j`.
    pub q_j: DQuat,
    /// Lab angular velocity of body `i` at the window's start.
    pub w_i: DVec3,
    /// Lab angular velocity of body `j`.
    pub w_j: DVec3,
    /// `≥ sup |ω_i|` over the window.
    pub spin_i: f64,
    /// `≥ sup |ω_j|`.
    pub spin_j: f64,
    /// `≥ sup |ω̇_i|` over the window.
    pub turn_i: f64,
    /// `≥ sup |ω̇_j|`.
    pub turn_j: f64,
}

impl RigidFlight {
    /// A bound on the relative acceleration of a point of `i` at distance `arm_i` from its
    /// centre and a point of `j` at `arm_j` from its centre, over the window (their relative
    /// speed is at most `|v| + sup|ω_i| arm_i + sup|ω_j| arm_j`): a body point at lab arm
    /// `A` has `Ä = ω̇ × A + ω × (ω × A)`, so `|Ä| ≤ (sup|ω̇| + sup|ω|²)|A|`; the centres do not
    /// accelerate.
    #[inline]
    pub fn point_acceleration(&self, arm_i: f64, arm_j: f64) -> f64 {
        (self.turn_i + self.spin_i * self.spin_i) * arm_i
            + (self.turn_j + self.spin_j * self.spin_j) * arm_j
    }
}

/// Bounds `(W, Ẇ)` with `|ω(t)| ≤ W` and `|ω̇(t)| ≤ Ẇ` at every time of the torque-free motion
/// of a body with principal moments `moments` and body-frame angular velocity `omega_body` at
/// some time. The rotational energy `E = ½ Σ I_k ω_k²` is conserved and at least
/// `½ I_min |ω|²`, so `W = √(2E / I_min)`; Euler's equations `I_k ω̇_k = (I_{k+1} − I_{k+2})
/// ω_{k+1} ω_{k+2}` give `|ω̇|² ≤ c² Σ_{a<b} ω_a² ω_b² ≤ c² |ω|⁴/3` with
/// `c = max_k |I_{k+1} − I_{k+2}| / I_k`, and the lab-frame `ω̇` has the body frame's length.
pub fn torque_free_bounds(moments: [f64; 3], omega_body: DVec3) -> (f64, f64) {
    let w = omega_body.to_array();
    let two_e: f64 = (0..3).map(|k| moments[k] * w[k] * w[k]).sum();
    let i_min = moments[0].min(moments[1]).min(moments[2]);
    let spin = (two_e / i_min).sqrt();
    let c = (0..3)
        .map(|k| (moments[(k + 1) % 3] - moments[(k + 2) % 3]).abs() / moments[k])
        .fold(0.0, f64::max);
    (spin, c * spin * spin / 3f64.sqrt())
}

/// Bounds `(sup|f|, sup|ḟ|, sup|f̈|)` on a factor of a pair energy over a window, from which
/// the rigid potentials build `K ≥ sup|Ü|`: products follow the product rule
/// `(fg)¨ = f̈g + 2ḟġ + fg̈` (each bound of a product is a bound of the product's derivative),
/// sums add, and a constant scales all three.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates(pub f64, pub f64, pub f64);

impl Rates {
    /// A constant factor of size at most `size`.
    pub const fn constant(size: f64) -> Self {
        Rates(size, 0.0, 0.0)
    }

    /// A function of the centre distance `r` along a straight flight with relative speed
    /// `speed` that stays at `r ≥ r_lo`, from bounds `f0, f1, f2` on `|f|, |f'|, |f''|` over
    /// the distances it reaches: `|ṙ| ≤ |v|` and `|r̈| ≤ |v|²/r_lo`.
    pub fn radial(f0: f64, f1: f64, f2: f64, speed: f64, r_lo: f64) -> Self {
        let v2 = speed * speed;
        Rates(f0, f1 * speed, f2 * v2 + f1 * v2 / r_lo)
    }

    /// The cubic switch of 003 Eq. 26, 1 up to `on` and 0 from `off`, over distances
    /// `[r_lo, r_hi]` reached at relative speed `speed`: `|S'| ≤ 1.5/w` and `|S''| ≤ 6/w²`
    /// (`w = off − on`) where the distances meet the switch.
    pub fn cubic_switch(on: f64, off: f64, r_lo: f64, r_hi: f64, speed: f64) -> Self {
        if r_hi <= on {
            Rates::constant(1.0)
        } else if r_lo >= off {
            Rates::constant(0.0)
        } else {
            let w = off - on;
            Rates::radial(1.0, 1.5 / w, 6.0 / (w * w), speed, r_lo)
        }
    }
}

impl std::ops::Mul for Rates {
    type Output = Rates;
    #[inline]
    fn mul(self, b: Rates) -> Rates {
        Rates(
            self.0 * b.0,
            self.1 * b.0 + self.0 * b.1,
            self.2 * b.0 + 2.0 * self.1 * b.1 + self.0 * b.2,
        )
    }
}

impl std::ops::Mul<Rates> for f64 {
    type Output = Rates;
    #[inline]
    fn mul(self, b: Rates) -> Rates {
        Rates(self * b.0, self * b.1, self * b.2)
    }
}

impl std::ops::Add for Rates {
    type Output = Rates;
    #[inline]
    fn add(self, b: Rates) -> Rates {
        Rates(self.0 + b.0, self.1 + b.1, self.2 + b.2)
    }
}

/// A second-order Taylor model of an effective coordinate `x(τ)` over a window (module
/// documentation): value, first and second derivatives at the window's start and a bound on
/// the third derivative over the window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaylorModel {
    /// `x` at the window's start.
    pub x: f64,
    /// `ẋ`.
    pub dx: f64,
    /// `ẍ`.
    pub ddx: f64,
    /// `M ≥ sup |x⃛|` over the window (may be `+∞`).
    pub third: f64,
    /// `K ≥ 0`: a second-order remainder, for a coordinate whose second derivative is bounded
    /// but may jump (a potential with a cut-off where only `U` and `U̇` are continuous). The
    /// model then claims `|x(τ) − x − ẋτ − ẍτ²/2| ≤ Kτ²/2 + Mτ³/6`; a model with `K > 0` is
    /// used by [`safe_time`](Self::safe_time) alone ([`monotone`](Self::monotone) and
    /// [`convex`](Self::convex) prove nothing from it).
    pub spread: f64,
}

impl TaylorModel {
    /// A model of `U` itself over a window: `U(τ) ∈ x + ẋτ ± Kτ²/2`, value and rate at the
    /// window's start and `K = spread ≥ sup |Ü|` (the rigid potentials' models).
    pub fn first_order(x: f64, dx: f64, spread: f64) -> Self {
        TaylorModel {
            x,
            dx,
            ddx: 0.0,
            third: 0.0,
            spread,
        }
    }

    /// A time `τ ∈ [0, h]` up to which `x` provably stays strictly inside `(a, b)` (0 if the
    /// model cannot prove `h / 32`, e.g. right after a crossing, with `x` on a boundary). `h`
    /// must not exceed the window the model's [`third`](Self::third) was bounded on.
    ///
    /// The excursion towards each end is majorised by `F(τ) = c₁⁺τ + (c₂⁺ + K/2)τ² + (M/6)τ³`
    /// (negative coefficients dropped, so `F` increases); the largest of `h, h/2, …, h/32` at
    /// which both stay below their distances is returned. The candidates are independent, a
    /// few multiplications each and no division: this runs for every pair after every event.
    pub fn safe_time(&self, a: f64, b: f64, h: f64) -> f64 {
        let usable = self.x.is_finite() && self.dx.is_finite() && self.ddx.is_finite() && h > 0.0;
        if !usable {
            return 0.0;
        }
        // Round-off of x and of the band's ends: a relative margin.
        let margin = 1e-8 * self.x.abs();
        let (room_up, room_down) = (b - self.x - margin, self.x - a - margin);
        let c3 = self.third / 6.0;
        let room = room_up > 0.0 && room_down > 0.0 && c3 < f64::INFINITY;
        if !room {
            return 0.0;
        }
        if !(self.spread >= 0.0 && self.spread < f64::INFINITY) {
            return 0.0;
        }
        let k2 = 0.5 * self.spread;
        let (u1, u2) = (self.dx.max(0.0), (0.5 * self.ddx).max(0.0) + k2);
        let (d1, d2) = ((-self.dx).max(0.0), (-0.5 * self.ddx).max(0.0) + k2);
        let mut t = h;
        for _ in 0..6 {
            let up = ((c3 * t + u2) * t + u1) * t;
            let down = ((c3 * t + d2) * t + d1) * t;
            if up <= room_up && down <= room_down {
                return t;
            }
            t *= 0.5;
        }
        0.0
    }
}

/// What a [`TaylorModel`] proves while its coordinate moves one way
/// ([`TaylorModel::monotone`]) or bends one way ([`TaylorModel::convex`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Proof {
    /// `x` stays inside the interval on `[0, τ]`.
    Safe(f64),
    /// `x` crosses an end of the interval once, located ([`Crossing`]).
    Crossing(Crossing),
    /// Nothing: `x` may turn within the window, or starts outside the interval.
    Unknown,
}

/// A crossing a [`Proof`] locates: `x` crosses the interval's end `end` exactly once in
/// `(from, within)` and stays inside before (`x − end` changes sign once there), so it needs
/// refinement, not a search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// The end crossed (`a` or `b`).
    pub end: f64,
    /// Whether `x` rises through it (`end = b`).
    pub rising: bool,
    /// A time by which the crossing has certainly happened.
    pub within: f64,
    /// Where the Taylor polynomial crosses `end`: a start for refinement.
    pub guess: f64,
    /// A time in `[0, guess]` from which on `x` is inside until the crossing: the lower end
    /// of the refinement's bracket (0 unless the pair starts on `end`).
    pub from: f64,
}

/// A model oriented along the sign of one of its derivatives ([`TaylorModel::oriented`]):
/// `y = s·(x − x₀)` has `ẏ = d1`, `ÿ = 2·d2` and `|y⃛| ≤ 6·c3`.
struct Oriented {
    rising: bool,
    s: f64,
    ahead: f64,
    behind: f64,
    margin: f64,
    d1: f64,
    d2: f64,
    c3: f64,
}

impl TaylorModel {
    /// The model oriented along the sign of `rate` (`ẋ` or `ẍ`), with the round-off margin
    /// `1e-8·|x|` of [`safe_time`](Self::safe_time); none for an unusable model or a zero
    /// `rate`.
    #[inline]
    fn oriented(&self, rate: f64, a: f64, b: f64, h: f64) -> Option<Oriented> {
        let usable = self.x.is_finite()
            && self.dx.is_finite()
            && self.ddx.is_finite()
            && self.third.is_finite()
            && self.spread == 0.0
            && h > 0.0;
        if !usable || rate == 0.0 {
            return None;
        }
        let rising = rate > 0.0;
        let s = if rising { 1.0 } else { -1.0 };
        Some(Oriented {
            rising,
            s,
            ahead: if rising { b } else { a },
            behind: if rising { a } else { b },
            margin: 1e-8 * self.x.abs(),
            d1: s * self.dx,
            d2: 0.5 * s * self.ddx,
            c3: self.third / 6.0,
        })
    }

    /// What the model proves about `x` in `(a, b)` over `[0, h]` while `x` moves one way.
    ///
    /// With `y(τ) = ±(x(τ) − x)` oriented along `ẋ`, `ẏ(τ) ≥ |ẋ| ± ẍτ − Mτ²/2`, which stays
    /// positive up to the root `τ*` of that parabola: on `[0, min(h, τ*))` (the monotone
    /// window) `x` moves strictly one way. So the end behind cannot be reached there (a pair
    /// that has just crossed it onto this terrace, sitting on it up to round-off, is moving
    /// away), and the end ahead is crossed at most once: never if the upper bound
    /// `|ẋ|τ ± ẍτ²/2 + Mτ³/6` stays below its distance at the window's end, certainly if the
    /// lower bound (`− Mτ³/6`) passes it. Where [`safe_time`](Self::safe_time) proves nothing
    /// (right after a crossing, or a crossing ahead) this proves the way to the next level or
    /// the level's crossing itself, which then needs no search, only refinement
    /// (`root_search::taylor_root`).
    pub fn monotone(&self, a: f64, b: f64, h: f64) -> Proof {
        let Some(Oriented {
            rising,
            s,
            ahead,
            behind,
            margin,
            d1,
            d2,
            c3,
        }) = self.oriented(self.dx, a, b, h)
        else {
            return Proof::Unknown;
        };
        // Off the interval behind by more than round-off: not this model's business.
        if s * (self.x - behind) < -margin {
            return Proof::Unknown;
        }
        let room = s * (ahead - self.x) - margin;
        if room <= 0.0 {
            return Proof::Unknown;
        }
        // ẏ ≥ d1 + 2·d2·τ − (M/2)τ² > 0 before τ* = 2·d1 / (√(4d2² + 2M·d1) − 2d2) (the
        // cancellation-free root; a zero denominator means no root).
        let denominator = (4.0 * d2 * d2 + 2.0 * self.third * d1).sqrt() - 2.0 * d2;
        let turn = if denominator > 0.0 {
            2.0 * d1 / denominator * (1.0 - 1e-9)
        } else {
            f64::INFINITY
        };
        let window = h.min(turn);
        if window.is_nan() || window <= 0.0 {
            return Proof::Unknown;
        }
        let upper = |t: f64| ((c3 * t + d2) * t + d1) * t;
        let lower = |t: f64| ((-c3 * t + d2) * t + d1) * t;
        if upper(window) <= room {
            return Proof::Safe(window);
        }
        if lower(window) >= room + 2.0 * margin {
            // The quadratic's crossing, cancellation-free; outside the window: its middle.
            let dist = s * (ahead - self.x);
            let q = d1 * d1 + 4.0 * d2 * dist;
            let guess = if q >= 0.0 {
                2.0 * dist / (d1 + q.sqrt())
            } else {
                0.5 * window
            };
            return Proof::Crossing(Crossing {
                end: ahead,
                rising,
                within: window,
                guess,
                from: 0.0,
            });
        }
        // Perhaps crossed within the window: safe while the upper bound (increasing on the
        // window) stays below the distance, to within a halving.
        last_halving(window, |t| upper(t) <= room)
    }

    /// What the model proves about `x` in `(a, b)` over `[0, h]` while `x` bends one way: the
    /// case of a turn, where [`monotone`](Self::monotone) proves little.
    ///
    /// With `σ` the sign of `ẍ`, `σẍ(τ) ≥ |ẍ| − Mτ > 0` up to `|ẍ|/M`: on that window `σx` is
    /// strictly convex, so `{σx < σe}` is an interval and the end `e` that `ẍ` bends towards
    /// (`b` for `σ > 0`) is crossed at most once, and not at all if the convex upper bound
    /// `σ(x − e) + σẋτ + |ẍ|τ²/2 + Mτ³/6` stays negative. The other end is safe while the
    /// tangent `x + ẋτ` (which `σx` lies above) has not reached it. A pair that has just
    /// crossed onto a terrace and turns back at once (a grazing return) gets its crossing
    /// proven, and located, this way.
    pub fn convex(&self, a: f64, b: f64, h: f64) -> Proof {
        let Some(Oriented {
            rising,
            s,
            ahead,
            behind,
            margin,
            d1,
            d2,
            c3,
        }) = self.oriented(self.ddx, a, b, h)
        else {
            return Proof::Unknown;
        };
        // y = σ(x − ahead): negative inside (with the margin), crossing zero at the event. A
        // pair on that end (y within round-off of 0, just crossed onto the terrace) must be
        // moving in: it comes back, and the crossing is its return.
        let y0 = s * (self.x - ahead);
        let on_end = y0 >= -margin;
        if (on_end && (y0 > margin || d1 >= 0.0)) || s * (self.x - behind) < -margin {
            return Proof::Unknown;
        }
        let bend = if self.third > 0.0 {
            2.0 * d2 / self.third * (1.0 - 1e-9)
        } else {
            f64::INFINITY
        };
        let mut window = h.min(bend);
        // The end behind: σx ≥ σx₀ + σẋτ (convexity), so moving away from it (d1 ≥ 0) is safe
        // and moving towards it is safe while the tangent keeps off it.
        if d1 < 0.0 {
            let room_behind = s * (self.x - behind) - margin;
            window = window.min(room_behind / -d1);
        }
        if window.is_nan() || window <= 0.0 {
            return Proof::Unknown;
        }
        let upper = |t: f64| y0 + ((c3 * t + d2) * t + d1) * t;
        let lower = |t: f64| y0 + ((-c3 * t + d2) * t + d1) * t;
        // The convex upper bound stays below max(y0, upper(t)) on [0, t]: below the round-off
        // margin (a pair on the end stays within it until it is inside).
        if upper(window) <= -margin {
            return Proof::Safe(window);
        }
        if lower(window) >= margin {
            // The quadratic's later crossing of zero (the one after the turn, if any).
            let q = d1 * d1 - 4.0 * d2 * y0;
            let guess = if q >= 0.0 {
                (q.sqrt() - d1) / (2.0 * d2)
            } else {
                0.5 * window
            };
            // A pair on the end: from a time at which it is proven inside, where the upper
            // bound dips below the margin (near the quadratic's turn), there is one crossing.
            let from = if on_end {
                let turn = (-d1 / (2.0 * d2)).min(window);
                match [turn, 0.5 * turn, 0.5 * (turn + guess.min(window))]
                    .into_iter()
                    .find(|&t| t > 0.0 && upper(t) <= -margin)
                {
                    Some(t) => t,
                    None => return Proof::Unknown,
                }
            } else {
                0.0
            };
            return Proof::Crossing(Crossing {
                end: ahead,
                rising,
                within: window,
                guess,
                from,
            });
        }
        // The upper bound is convex and starts below zero: below it up to the last halving
        // found below.
        last_halving(window, |t| upper(t) <= -margin)
    }
}

/// The largest of `w/2, w/4, …, w/64` at which `safe` holds, as a safe stretch (the callers'
/// bounds make every shorter time safe too), or nothing.
#[inline]
fn last_halving(window: f64, safe: impl Fn(f64) -> bool) -> Proof {
    let mut t = 0.5 * window;
    for _ in 0..6 {
        if safe(t) {
            return Proof::Safe(t);
        }
        t *= 0.5;
    }
    Proof::Unknown
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spin bounds of torque-free motion hold along Euler's equations integrated finely
    /// (RK4), for asymmetric, planar and symmetric tops, near the separatrix and far from it;
    /// and `Ẇ` is reached to within a factor 4 somewhere (not a bound loose by orders).
    #[test]
    fn torque_free_bounds_hold_along_eulers_equations() {
        let euler = |m: [f64; 3], w: DVec3| {
            DVec3::new(
                (m[1] - m[2]) * w.y * w.z / m[0],
                (m[2] - m[0]) * w.z * w.x / m[1],
                (m[0] - m[1]) * w.x * w.y / m[2],
            )
        };
        // (moments, ω(0), whether |ω̇| comes near its bound: not for a steady spin)
        for (m, w0, tight) in [
            ([1.9408, 0.5968, 1.3440], DVec3::new(3.0, -20.0, 11.0), true),
            (
                [1.9408, 0.5968, 1.3440],
                DVec3::new(1e-6, 1e-6, 15.0),
                false,
            ),
            (
                [1.9408, 0.5968, 1.3440],
                DVec3::new(1e-6, 15.0, 1e-6),
                false,
            ),
            ([1.0, 2.0, 3.0], DVec3::new(0.1, 4.0, 0.2), true),
            ([1.0, 1.0, 1.5], DVec3::new(2.0, 0.0, 5.0), true),
            ([1.0, 1.0, 2.0], DVec3::new(6.0, -2.0, 1.0), true),
        ] {
            let (spin, turn) = torque_free_bounds(m, w0);
            let (mut w, dt) = (w0, 1e-4 / spin);
            let (mut top_spin, mut top_turn): (f64, f64) = (0.0, 0.0);
            for _ in 0..200_000 {
                let k1 = euler(m, w);
                let k2 = euler(m, w + k1 * (0.5 * dt));
                let k3 = euler(m, w + k2 * (0.5 * dt));
                let k4 = euler(m, w + k3 * dt);
                w += (k1 + 2.0 * k2 + 2.0 * k3 + k4) * (dt / 6.0);
                top_spin = top_spin.max(w.length());
                top_turn = top_turn.max(euler(m, w).length());
            }
            assert!(
                top_spin <= spin * (1.0 + 1e-9),
                "{m:?}: |ω| {top_spin} > {spin}"
            );
            assert!(
                top_turn <= turn * (1.0 + 1e-9),
                "{m:?}: |ω̇| {top_turn} > {turn}"
            );
            assert!(
                !tight || top_turn > 0.25 * turn,
                "{m:?}: {top_turn} ≪ {turn}"
            );
        }
    }

    /// The safe time never lets the majorant reach an end, and is at least half the largest
    /// such time (down to `h / 32`).
    #[test]
    fn safe_time_is_safe_and_within_a_halving() {
        for &(dx, ddx, third, a, b) in &[
            (1.0, 0.0, 0.0, -10.0, 3.0),
            (0.0, 2.0, 0.0, -10.0, 5.0),
            (0.0, 0.0, 6.0, -8.0, 9.0),
            (0.3, 4.0, 30.0, -0.2, 0.7),
            (-1.0, -4.0, 18.0, -0.1, 0.1),
            (1e-9, 2e3, 6e6, -1e-4, 1e-4),
        ] {
            let m = TaylorModel {
                x: 0.0,
                dx,
                ddx,
                third,
                spread: 0.0,
            };
            let h = 4.0;
            let t = m.safe_time(a, b, h);
            let excursion = |t: f64, s: f64| {
                (s * dx).max(0.0) * t + (0.5 * s * ddx).max(0.0) * t * t + third * t * t * t / 6.0
            };
            assert!(excursion(t, 1.0) <= b && excursion(t, -1.0) <= -a, "{t}");
            if t < h {
                let t2 = 2.0 * t.max(h / 64.0);
                assert!(
                    excursion(t2, 1.0) > b || excursion(t2, -1.0) > -a,
                    "{t} is more than a halving below the safe time"
                );
            }
        }
    }

    #[test]
    fn safe_time_respects_both_ends() {
        let m = TaylorModel {
            x: 1.0,
            dx: -2.0,
            ddx: 0.0,
            third: 0.0,
            spread: 0.0,
        };
        // Moving down at speed 2 towards a = 0.5: a quarter of a time unit, proven as the
        // largest halving of the window below it.
        assert_eq!(m.safe_time(0.5, 10.0, 1.0), 0.125);
        assert_eq!(m.safe_time(0.5, 10.0, 0.25), 0.125);
        assert_eq!(m.safe_time(0.49, 10.0, 0.25), 0.25);
        assert_eq!(m.safe_time(1.0, 2.0, 1.0), 0.0);
    }

    /// A coordinate with known derivatives and a third derivative within the bound: the
    /// cubic `x + ẋτ + ẍτ²/2 + w·Mτ³/6`, `|w| ≤ 1`. What `monotone` and `convex` prove holds
    /// on a fine grid: a safe stretch stays inside, a crossing happens once, before `within`,
    /// and the other end is never reached before it.
    #[test]
    fn monotone_proofs_hold_on_cubics() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut uniform = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut safe, mut crossing) = (0, 0);
        for _ in 0..20_000 {
            let (a, b) = (-1.0 - 2.0 * uniform(), 0.2 + 2.0 * uniform());
            // Starts anywhere inside, or on an end (just after a crossing).
            let x = match (uniform() * 4.0) as u32 {
                0 => a,
                1 => b,
                _ => a + (b - a) * uniform(),
            };
            let m = TaylorModel {
                x,
                dx: 8.0 * (uniform() - 0.5),
                ddx: 20.0 * (uniform() - 0.5),
                third: 60.0 * uniform(),
                spread: 0.0,
            };
            let w = 2.0 * uniform() - 1.0;
            let h = 2.0 * uniform();
            let f = |t: f64| m.x + m.dx * t + 0.5 * m.ddx * t * t + w * m.third * t * t * t / 6.0;
            let convex = uniform() < 0.5;
            let proof = if convex {
                m.convex(a, b, h)
            } else {
                m.monotone(a, b, h)
            };
            match proof {
                Proof::Safe(tau) => {
                    safe += 1;
                    assert!(tau > 0.0 && tau <= h);
                    for k in 1..=400 {
                        let y = f(tau * k as f64 / 400.0);
                        let tol = 1e-12;
                        // Never out through the end ahead; the end behind at most by round-off.
                        assert!(
                            y > a - tol && y < b + tol,
                            "{m:?} w {w} left ({a}, {b}) by {y}"
                        );
                        let towards = if convex { m.ddx } else { m.dx };
                        if towards > 0.0 {
                            assert!(y < b);
                        } else {
                            assert!(y > a);
                        }
                    }
                }
                Proof::Crossing(Crossing {
                    end,
                    rising,
                    within,
                    guess: _,
                    from,
                }) => {
                    crossing += 1;
                    let s = if rising { 1.0 } else { -1.0 };
                    assert!(within > 0.0 && within <= h);
                    assert_eq!(rising, if convex { m.ddx > 0.0 } else { m.dx > 0.0 });
                    assert_eq!(end, if rising { b } else { a });
                    assert!(s * (f(within) - end) > 0.0, "not crossed by {within}");
                    assert!((0.0..within).contains(&from));
                    assert!(s * (f(from) - end) < 0.0, "not inside at {from}");
                    let mut crossings = 0;
                    let mut before = false;
                    for k in 1..=400 {
                        let y = f(from + (within - from) * k as f64 / 400.0);
                        let now = s * (y - end) > 0.0;
                        crossings += usize::from(now != before);
                        before = now;
                        if crossings == 0 {
                            assert!(y > a - 1e-12 && y < b + 1e-12, "{m:?} w {w} left early");
                        }
                    }
                    assert_eq!(crossings, 1, "{m:?} w {w}");
                }
                Proof::Unknown => {}
            }
        }
        assert!(
            safe > 1000 && crossing > 1000,
            "{safe} safe, {crossing} crossings"
        );
    }

    /// A pair that has just crossed up onto its terrace and turns straight back: no monotone
    /// window reaches the return, the convex one proves and locates it.
    #[test]
    fn a_grazing_return_is_located_by_convexity() {
        let m = TaylorModel {
            x: 1.0 + 1e-6,
            dx: 1e-3,
            ddx: -2.0,
            third: 1.0,
            spread: 0.0,
        };
        assert!(matches!(m.monotone(1.0, 2.0, 0.1), Proof::Safe(t) if t < 1e-3));
        let Proof::Crossing(Crossing {
            end,
            rising,
            within,
            guess,
            from,
        }) = m.convex(1.0, 2.0, 0.1)
        else {
            panic!("{:?}", m.convex(1.0, 2.0, 0.1));
        };
        assert_eq!((end, rising, within, from), (1.0, false, 0.1, 0.0));
        // x = 1 + 1e-6 + 1e-3 τ − τ² (M = 1 adds at most τ³/6): back at 1 at τ ≈ 1.6e-3.
        let exact = (1e-3 + (1e-6 + 4e-6f64).sqrt()) / 2.0;
        assert!((guess - exact).abs() < 1e-12, "{guess} against {exact}");
        // Starting on the level itself: the return is the crossing, bracketed from a time
        // at which the pair is proven inside.
        let on = TaylorModel { x: 1.0, ..m };
        assert!(matches!(on.monotone(1.0, 2.0, 0.1), Proof::Safe(t) if t < 1e-3));
        let Proof::Crossing(Crossing {
            end, guess, from, ..
        }) = on.convex(1.0, 2.0, 0.1)
        else {
            panic!("{:?}", on.convex(1.0, 2.0, 0.1));
        };
        assert_eq!(end, 1.0);
        assert!(
            from > 0.0 && from < guess && (guess - 1e-3).abs() < 1e-12,
            "{from} {guess}"
        );
    }

    #[test]
    fn monotone_goes_nowhere_without_a_direction() {
        let m = TaylorModel {
            x: 0.5,
            dx: 0.0,
            ddx: 1.0,
            third: 1.0,
            spread: 0.0,
        };
        assert_eq!(m.monotone(0.0, 1.0, 1.0), Proof::Unknown);
        // Leaving the interval behind it: unknown, not safe.
        let m = TaylorModel {
            x: -0.1,
            dx: 1.0,
            ddx: 0.0,
            third: 0.0,
            spread: 0.0,
        };
        assert_eq!(m.monotone(0.0, 1.0, 1.0), Proof::Unknown);
        // Moving straight up from the lower end: safe to 1 (exactly reaches b at 1: not safe),
        // crossing certain beyond.
        let m = TaylorModel {
            x: 0.0,
            dx: 1.0,
            ddx: 0.0,
            third: 0.0,
            spread: 0.0,
        };
        assert_eq!(m.monotone(0.0, 1.0, 0.5), Proof::Safe(0.5));
        assert!(
            matches!(m.monotone(0.0, 1.0, 2.0), Proof::Crossing(Crossing { end, guess, .. }) if end == 1.0 && guess == 1.0)
        );
    }
}
