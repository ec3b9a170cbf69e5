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
//! `|x(τ) − x − ẋτ − ẍτ²/2| ≤ third · τ³/6`.

use glam::DVec3;

/// The interval of `intervals` (disjoint, as [`PairPotential::coordinate_intervals`](crate::PairPotential::coordinate_intervals) returns
/// them) that holds `x` strictly inside, if any.
#[inline]
pub fn interval_containing(intervals: &[(f64, f64)], x: f64) -> Option<(f64, f64)> {
    intervals.iter().copied().find(|&(a, b)| a < x && x < b)
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
    /// `Ω ≥ |ω_i| + |ω_j|` (engines keep the rates; [`FreeFlight::new`] computes it).
    pub spin: f64,
}

impl FreeFlight {
    /// The flight of these vectors, with `Ω = |ω_i| + |ω_j|`.
    pub fn new(r: DVec3, v: DVec3, s_i: DVec3, w_i: DVec3, s_j: DVec3, w_j: DVec3) -> Self {
        FreeFlight {
            r,
            v,
            s_i,
            w_i,
            s_j,
            w_j,
            spin: w_i.length() + w_j.length(),
        }
    }

    /// The square of the smallest centre distance over `[0, h]` (exact for straight-line
    /// motion).
    #[inline]
    pub fn closest_approach_squared(&self, h: f64) -> f64 {
        let v2 = self.v.length_squared();
        let tau = if v2 > 0.0 {
            (-self.r.dot(self.v) / v2).clamp(0.0, h)
        } else {
            0.0
        };
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
        let rd = self.r.dot(self.v) / r;
        let rdd = ((self.v.length_squared() - rd * rd) / r).max(0.0);
        (r, rd, rdd)
    }

    /// `c = s_i·s_j`, `ċ`, `c̈` at the window's start (`ṡ = ω × s`, `s̈ = ω × ṡ`).
    #[inline]
    pub fn alignment_derivatives(&self) -> (f64, f64, f64) {
        let di = self.w_i.cross(self.s_i);
        let dj = self.w_j.cross(self.s_j);
        let ddi = self.w_i.cross(di);
        let ddj = self.w_j.cross(dj);
        (
            self.s_i.dot(self.s_j),
            di.dot(self.s_j) + self.s_i.dot(dj),
            ddi.dot(self.s_j) + 2.0 * di.dot(dj) + self.s_i.dot(ddj),
        )
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
}

impl TaylorModel {
    /// A time `τ ∈ [0, h]` up to which `x` provably stays strictly inside `(a, b)` (0 if the
    /// model cannot prove `h / 32`, e.g. right after a crossing, with `x` on a boundary). `h`
    /// must not exceed the window the model's [`third`](Self::third) was bounded on.
    ///
    /// The excursion towards each end is majorised by `F(τ) = c₁⁺τ + c₂⁺τ² + (M/6)τ³`
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
        let (u1, u2) = (self.dx.max(0.0), (0.5 * self.ddx).max(0.0));
        let (d1, d2) = ((-self.dx).max(0.0), (-0.5 * self.ddx).max(0.0));
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

#[cfg(test)]
mod tests {
    use super::*;

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
        };
        // Moving down at speed 2 towards a = 0.5: a quarter of a time unit, proven as the
        // largest halving of the window below it.
        assert_eq!(m.safe_time(0.5, 10.0, 1.0), 0.125);
        assert_eq!(m.safe_time(0.5, 10.0, 0.25), 0.125);
        assert_eq!(m.safe_time(0.49, 10.0, 0.25), 0.25);
        assert_eq!(m.safe_time(1.0, 2.0, 1.0), 0.0);
    }
}
