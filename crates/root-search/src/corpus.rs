//! Adversarial indicators with known roots, to test and compare root searches.
//!
//! Each [`Case`] is an indicator ([`Shape`]), a bracket, a requested [`Crossing`] and the
//! earliest root expected (or none). Times are in Lennard-Jones units `τ = σ √(m/ε)`; for the
//! rods of 003 §V, `τ ≈ 0.74 ps`, so the paper's maximum step of 4 fs is about `0.005 τ`.
//! Values of `f` are of order one, so a touch tolerance of `1e-12` is round-off level.
//!
//! The families ([`Family`]) cover what makes the first root hard to find: grazing dips barely
//! below zero between samples and near misses barely above it, exact double roots, clusters
//! of roots where the earliest must be found, oscillations from products of sines with
//! incommensurate frequencies, tumbling rods with the modified Lennard-Jones potential of
//! 003 Eqs. 22–23, stiff Lennard-Jones walls, nearly flat functions, starts exactly at zero
//! after an event (with and without round-off), and roots at the ends of the bracket.
//!
//! Roots are analytic wherever the family allows. The sines and the rods have none in closed
//! form; their expected root comes from [`reference_root`], a dense scan with bisection that is
//! far too slow for a simulator but leaves no extremum unexamined, and cases whose outcome
//! would hinge on an extremum within `1e-8` of zero are not generated.
//!
//! ```
//! use root_search::corpus::{cases, Verdict};
//! use root_search::{Adaptive, Method, Tolerances};
//!
//! let search = Adaptive::new(0.005)?.with_tolerances(Tolerances {
//!     touch: 1e-12,
//!     ..Tolerances::relative_to(0.005)
//! })?;
//! for mut case in cases(7, 2) {
//!     let report = search.start(&mut case.shape, case.t0, case.end, case.seek, f64::INFINITY)?;
//!     assert_eq!(case.judge(report.root()), Verdict::Right, "{}", case.name);
//! }
//! # Ok::<(), root_search::SearchError>(())
//! ```

use std::f64::consts::PI;

use crate::Indicator;
use crate::indicator::{Crossing, Side};

/// Which difficulty a case poses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// A Gaussian dip whose minimum lies barely below zero (by `1e-9` to `1e-2`).
    Grazing,
    /// The same dip with its minimum barely above zero: no root.
    NearMiss,
    /// `f` touches zero and turns back (an exact double root).
    DoubleRoot,
    /// Products of `tanh` with several roots, some pairs `1e-4` apart.
    SeveralRoots,
    /// `a + sin(ω₁t + φ₁) sin(ω₂t + φ₂)` with `ω₂/ω₁` the golden ratio.
    Oscillating,
    /// A tumbling pair of rods (003 Eqs. 22–23) on a straight relative course.
    Tumbling,
    /// A Lennard-Jones wall met at speed, terraces up to `200 ε`.
    Stiff,
    /// Nearly flat functions: slopes down to `1e-9`, a fifth-order root, a tiny positive floor.
    Flat,
    /// A start exactly at zero, or at zero up to round-off, after an event.
    StartAtZero,
    /// Roots exactly at, just inside and just outside the bracket ends.
    BracketEnds,
}

impl Family {
    /// Every family, in the order [`cases`] generates them.
    pub const ALL: [Family; 10] = [
        Family::Grazing,
        Family::NearMiss,
        Family::DoubleRoot,
        Family::SeveralRoots,
        Family::Oscillating,
        Family::Tumbling,
        Family::Stiff,
        Family::Flat,
        Family::StartAtZero,
        Family::BracketEnds,
    ];

    /// A short lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Family::Grazing => "grazing",
            Family::NearMiss => "near-miss",
            Family::DoubleRoot => "double-root",
            Family::SeveralRoots => "several-roots",
            Family::Oscillating => "oscillating",
            Family::Tumbling => "tumbling",
            Family::Stiff => "stiff",
            Family::Flat => "flat",
            Family::StartAtZero => "start-at-zero",
            Family::BracketEnds => "bracket-ends",
        }
    }
}

/// The indicator of a case; every variant gives `f` and `f'` in closed form.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// `s (1 − (1 + d) exp(−((t − c)/w)²))`.
    Dip {
        /// Sign `s` (±1): a dip from above, or a bump from below.
        s: f64,
        /// Centre.
        c: f64,
        /// Width.
        w: f64,
        /// Depth below zero (negative: height above zero).
        d: f64,
    },
    /// `s tanh((t − c)/w)²`, touching zero at `c`.
    Touch {
        /// Sign (±1).
        s: f64,
        /// Where it touches.
        c: f64,
        /// Width.
        w: f64,
    },
    /// `s Π tanh((t − rᵢ)/wᵢ)`.
    Tanh {
        /// Overall sign (±1).
        s: f64,
        /// Roots and widths.
        roots: Vec<(f64, f64)>,
    },
    /// `a + sin(ω₁ t + φ₁) sin(ω₂ t + φ₂)`.
    Sines {
        /// Offset.
        a: f64,
        /// Angular frequencies.
        w: [f64; 2],
        /// Phases.
        phi: [f64; 2],
    },
    /// `U(r_e(t)) − U_k` for two rods rotating in fixed planes (003 Eqs. 22–23, ε = σ = 1).
    Rods(Box<Rods>),
    /// `4(r⁻¹² − r⁻⁶) − U_k`, `r = √(b² + (x₀ + v t)²)`.
    Wall {
        /// Impact parameter.
        b: f64,
        /// Position along the course at `t = 0`.
        x0: f64,
        /// Velocity along the course.
        v: f64,
        /// Terrace value.
        uk: f64,
    },
    /// `k (t − r)^n` for odd `n`.
    Power {
        /// Scale.
        k: f64,
        /// Root.
        r: f64,
        /// Odd power.
        n: i32,
    },
    /// `floor + k (t − c)²`: a positive minimum `floor` at `c`.
    Floor {
        /// The minimum value.
        floor: f64,
        /// Curvature scale.
        k: f64,
        /// Where the minimum is.
        c: f64,
    },
    /// `a sin(ω (t − t₀)) + δ`: a start at zero at `t₀`, up to the offset `δ`.
    Sine {
        /// Amplitude (its sign sets the direction of motion at `t₀`).
        a: f64,
        /// Angular frequency.
        omega: f64,
        /// Phase origin.
        t0: f64,
        /// Offset.
        offset: f64,
    },
}

/// Two rods with the modified Lennard-Jones potential of 003 Eqs. 22–23.
#[derive(Clone, Debug, PartialEq)]
pub struct Rods {
    /// Relative centre position at `t = 0`.
    pub r0: [f64; 3],
    /// Relative centre velocity.
    pub v: [f64; 3],
    /// For each rod, two orthonormal vectors spanning its plane of rotation.
    pub planes: [[[f64; 3]; 2]; 2],
    /// Angular velocity and phase of each rod in its plane.
    pub spin: [(f64, f64); 2],
    /// `ζ` of Eq. 23 in units of `σ`.
    pub zeta: f64,
    /// The terrace value `U_k`.
    pub uk: f64,
}

impl Rods {
    fn axis(&self, i: usize, t: f64) -> ([f64; 3], [f64; 3]) {
        let (w, phase) = self.spin[i];
        let (s, c) = (w * t + phase).sin_cos();
        let [e1, e2] = self.planes[i];
        let mut a = [0.0; 3];
        let mut da = [0.0; 3];
        for k in 0..3 {
            a[k] = c * e1[k] + s * e2[k];
            da[k] = w * (-s * e1[k] + c * e2[k]);
        }
        (a, da)
    }

    /// `(U, dU/dt)` at `t`.
    fn potential(&self, t: f64) -> (f64, f64) {
        let r: [f64; 3] = std::array::from_fn(|k| self.r0[k] + self.v[k] * t);
        let dist = dot(r, r).sqrt();
        let ddist = dot(r, self.v) / dist;
        let (si, dsi) = self.axis(0, t);
        let (sj, dsj) = self.axis(1, t);
        let c = dot(si, sj);
        let dc = dot(dsi, sj) + dot(si, dsj);
        // 003 Eq. 23.
        let re = dist + self.zeta * (0.5 - c * c);
        let dre = ddist - 2.0 * self.zeta * c * dc;
        let x6 = re.powi(-6);
        // 003 Eqs. 22 and 24 with ε = σ = 1.
        let u = 4.0 * (x6 * x6 - x6);
        let du = -24.0 / re * (2.0 * x6 * x6 - x6);
        (u, du * dre)
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Indicator for Shape {
    fn eval(&mut self, t: f64) -> (f64, f64) {
        match self {
            Shape::Dip { s, c, w, d } => {
                let x = (t - *c) / *w;
                let g = (1.0 + *d) * (-x * x).exp();
                (*s * (1.0 - g), *s * 2.0 * x / *w * g)
            }
            Shape::Touch { s, c, w } => {
                let th = ((t - *c) / *w).tanh();
                (*s * th * th, *s * 2.0 * th * (1.0 - th * th) / *w)
            }
            Shape::Tanh { s, roots } => {
                let mut f = *s;
                let mut df = 0.0;
                for &(r, w) in roots.iter() {
                    let th = ((t - r) / w).tanh();
                    // d(f·th) = df·th + f·th'.
                    df = df * th + f * (1.0 - th * th) / w;
                    f *= th;
                }
                (f, df)
            }
            Shape::Sines { a, w, phi } => {
                let (s1, c1) = (w[0] * t + phi[0]).sin_cos();
                let (s2, c2) = (w[1] * t + phi[1]).sin_cos();
                (*a + s1 * s2, w[0] * c1 * s2 + w[1] * s1 * c2)
            }
            Shape::Rods(rods) => {
                let (u, du) = rods.potential(t);
                (u - rods.uk, du)
            }
            Shape::Wall { b, x0, v, uk } => {
                let x = *x0 + *v * t;
                let r2 = *b * *b + x * x;
                let x6 = r2.powi(-3);
                let u = 4.0 * (x6 * x6 - x6);
                // dU/dr · dr/dt with dr/dt = x v / r: dU/d(r²) · 2 x v.
                let du_dr2 = 4.0 * (-6.0 * x6 * x6 + 3.0 * x6) / r2;
                (u - *uk, du_dr2 * 2.0 * x * *v)
            }
            Shape::Power { k, r, n } => {
                let x = t - *r;
                (*k * x.powi(*n), *k * f64::from(*n) * x.powi(*n - 1))
            }
            Shape::Floor { floor, k, c } => {
                let x = t - *c;
                (*floor + *k * x * x, 2.0 * *k * x)
            }
            Shape::Sine {
                a,
                omega,
                t0,
                offset,
            } => {
                let (s, c) = (*omega * (t - *t0)).sin_cos();
                (*a * s + *offset, *a * *omega * c)
            }
        }
    }
}

/// One test: an indicator, a bracket, a direction and the answer.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Family and index, e.g. `grazing/3`.
    pub name: String,
    /// Which difficulty it poses.
    pub family: Family,
    /// The indicator.
    pub shape: Shape,
    /// Start of the search.
    pub t0: f64,
    /// End of the bracket.
    pub end: f64,
    /// Requested crossings.
    pub seek: Crossing,
    /// The earliest accepted root in `(t0, end]`, if any.
    pub expected: Option<f64>,
    /// How far a returned root may be from the expected one and still be right.
    pub accuracy: f64,
}

/// How a search did on a case.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Verdict {
    /// The expected root to within the accuracy, or correctly none.
    Right,
    /// The expected root was not returned: none, or a later one.
    Missed,
    /// A root where there is none, or one earlier than the expected root.
    Wrong,
}

impl Case {
    /// Judges a search's answer.
    pub fn judge(&self, found: Option<f64>) -> Verdict {
        match (self.expected, found) {
            (None, None) => Verdict::Right,
            (None, Some(_)) => Verdict::Wrong,
            (Some(_), None) => Verdict::Missed,
            (Some(e), Some(t)) => {
                if (t - e).abs() <= self.accuracy {
                    Verdict::Right
                } else if t > e {
                    Verdict::Missed
                } else {
                    Verdict::Wrong
                }
            }
        }
    }
}

/// A small deterministic generator (SplitMix64) so the corpus is the same on every machine.
#[derive(Clone, Debug)]
struct Mix(u64);

impl Mix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    fn log_range(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.unit()).exp()
    }

    fn sign(&mut self) -> f64 {
        if self.next() & 1 == 0 { 1.0 } else { -1.0 }
    }

    fn normal(&mut self) -> f64 {
        let u = 1.0 - self.unit();
        (-2.0 * u.ln()).sqrt() * (2.0 * PI * self.unit()).cos()
    }

    fn unit_vector(&mut self) -> [f64; 3] {
        loop {
            let v = [self.normal(), self.normal(), self.normal()];
            let n = dot(v, v).sqrt();
            if n > 1e-3 {
                return v.map(|x| x / n);
            }
        }
    }

    fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[(self.next() % items.len() as u64) as usize]
    }
}

/// Accuracy demanded of a crossing root (far above any root tolerance, far below any feature).
const ROOT_ACCURACY: f64 = 1e-9;
/// Extrema closer to zero than this (and not designed to touch it) make a case ambiguous.
const AMBIGUOUS: f64 = 1e-8;

/// The corpus: `per_family` cases of each [`Family`], the same for the same `seed`.
pub fn cases(seed: u64, per_family: usize) -> Vec<Case> {
    let mut rng = Mix(seed);
    let mut out = Vec::new();
    for family in Family::ALL {
        let mut made = 0;
        while made < per_family {
            if let Some(mut case) = make(family, made, &mut rng) {
                case.name = format!("{}/{made}", family.name());
                out.push(case);
                made += 1;
            }
        }
    }
    out
}

fn case(family: Family, shape: Shape, t0: f64, end: f64, seek: Crossing) -> Case {
    Case {
        name: String::new(),
        family,
        shape,
        t0,
        end,
        seek,
        expected: None,
        accuracy: ROOT_ACCURACY,
    }
}

fn make(family: Family, i: usize, rng: &mut Mix) -> Option<Case> {
    match family {
        Family::Grazing | Family::NearMiss => {
            let s = rng.sign();
            let c = rng.range(0.2, 0.8);
            let w = rng.range(0.01, 0.05);
            let depth = rng.log_range(1e-9, 1e-2);
            let d = if family == Family::Grazing {
                depth
            } else {
                -depth.max(AMBIGUOUS)
            };
            let seek = if i % 3 == 2 {
                Crossing::Either
            } else if s > 0.0 {
                Crossing::Falling
            } else {
                Crossing::Rising
            };
            let mut k = case(family, Shape::Dip { s, c, w, d }, 0.0, 1.0, seek);
            if d > 0.0 {
                k.expected = Some(c - w * d.ln_1p().sqrt());
            }
            Some(k)
        }
        Family::DoubleRoot => {
            let s = rng.sign();
            let c = rng.range(0.2, 0.8);
            let w = rng.range(0.01, 0.05);
            let seek = if s > 0.0 {
                Crossing::Falling
            } else {
                Crossing::Rising
            };
            let mut k = case(family, Shape::Touch { s, c, w }, 0.0, 1.0, seek);
            k.expected = Some(c);
            // A touch is found where |f| ≤ 1e-12, i.e. within w·1e-6 of c.
            k.accuracy = 2e-6 * w;
            Some(k)
        }
        Family::SeveralRoots => {
            let n = 2 + (rng.next() % 5) as usize;
            let mut roots = Vec::with_capacity(n + 1);
            for _ in 0..n {
                roots.push((rng.range(0.05, 0.95), rng.range(0.01, 0.05)));
            }
            // Half the cases get a close pair, which makes a shallow dip.
            if i.is_multiple_of(2) {
                let (r, w) = roots[0];
                roots.push((r + rng.log_range(1e-4, 1e-2), w));
            }
            roots.sort_by(|a, b| a.0.total_cmp(&b.0));
            if roots.windows(2).any(|p| p[1].0 - p[0].0 < 5e-5) {
                return None;
            }
            let s = rng.sign();
            let seek = rng.pick(&[Crossing::Rising, Crossing::Falling, Crossing::Either]);
            let mut shape = Shape::Tanh { s, roots };
            let mut k = case(family, shape.clone(), 0.0, 1.0, seek);
            k.expected = first_listed_root(&mut shape, 0.0, 1.0, seek);
            Some(k)
        }
        Family::Oscillating => {
            let w1 = rng.range(10.0, 30.0);
            let shape = Shape::Sines {
                a: rng.range(0.0, 1.0),
                w: [w1, w1 * 1.618_033_988_749_895],
                phi: [rng.range(0.0, 2.0 * PI), rng.range(0.0, 2.0 * PI)],
            };
            let seek = rng.pick(&[Crossing::Rising, Crossing::Falling, Crossing::Either]);
            referenced(case(family, shape, 0.0, 2.0, seek), 1e-4)
        }
        Family::Tumbling => tumbling(rng),
        Family::Stiff => {
            let uk = if i % 4 == 3 {
                -rng.range(0.05, 0.95)
            } else {
                rng.log_range(1.0, 200.0)
            };
            let speed = rng.range(1.0, 10.0);
            let reach = 2.5;
            let b = rng.range(0.0, 1.1);
            let x0 = (reach * reach - b * b).sqrt();
            let end = 2.0 * x0 / speed;
            // U(r) = U_k: y = (σ/r)⁶ solves 4(y² − y) = U_k; the larger y is the inner radius.
            let disc = (1.0 + uk).sqrt();
            let y = if uk >= 0.0 {
                0.5 * (1.0 + disc)
            } else {
                0.5 * (1.0 - disc)
            };
            let rk = y.powf(-1.0 / 6.0);
            let seek = if uk >= 0.0 {
                Crossing::Rising
            } else {
                Crossing::Falling
            };
            let mut k = case(
                family,
                Shape::Wall {
                    b,
                    x0,
                    v: -speed,
                    uk,
                },
                0.0,
                end,
                seek,
            );
            if rk > b {
                k.expected = Some((x0 - (rk * rk - b * b).sqrt()) / speed);
            }
            Some(k)
        }
        Family::Flat => {
            let r = rng.range(0.2, 0.8);
            let mut k = match i % 4 {
                0 => {
                    // Tiny, yet above the touch margin of 1e-12 at the start.
                    let slope = rng.log_range(1e-9, 1e-6) * rng.sign();
                    case(
                        family,
                        Shape::Power { k: slope, r, n: 1 },
                        0.0,
                        1.0,
                        Crossing::Either,
                    )
                }
                1 => case(
                    family,
                    Shape::Power {
                        k: rng.sign(),
                        r,
                        n: 5,
                    },
                    0.0,
                    1.0,
                    Crossing::Either,
                ),
                2 => case(
                    family,
                    Shape::Tanh {
                        s: rng.log_range(1e-6, 1e-3) * rng.sign(),
                        roots: vec![(r, rng.range(10.0, 100.0))],
                    },
                    0.0,
                    1.0,
                    Crossing::Either,
                ),
                _ => case(
                    family,
                    Shape::Floor {
                        floor: rng.log_range(AMBIGUOUS, 1e-4),
                        k: rng.log_range(1e-4, 1.0),
                        c: r,
                    },
                    0.0,
                    1.0,
                    Crossing::Falling,
                ),
            };
            if i % 4 != 3 {
                k.expected = Some(r);
            }
            Some(k)
        }
        Family::StartAtZero => {
            let omega = rng.range(5.0, 30.0);
            let t0 = rng.pick(&[0.0, 0.731, 12.5, 1234.5678]);
            let a = rng.sign();
            let offset = rng.pick(&[0.0, 1e-16, -1e-16, 3e-14, -3e-14]);
            // Moving up at t0 (a > 0) after a rising event the pair passed: next is the fall.
            // Moving down (a < 0) after a reflection: next is the rise.
            let seek = if i % 3 == 2 {
                // With a touch margin above the offset, even a search for either direction must
                // leave the start the way f' points.
                Crossing::Either
            } else if a > 0.0 {
                Crossing::Falling
            } else {
                Crossing::Rising
            };
            // a sin θ + δ = 0 with θ = ω (t − t0): θ = π + asin(δ/a) is the next crossing of
            // the wanted direction for either sign of a.
            let theta = PI + (offset / a).asin();
            let mut k = case(
                family,
                Shape::Sine {
                    a,
                    omega,
                    t0,
                    offset,
                },
                t0,
                t0 + 2.0 * PI / omega * 0.75,
                seek,
            );
            k.expected = Some(t0 + theta / omega);
            // Large times carry their own round-off.
            k.accuracy = ROOT_ACCURACY.max(64.0 * f64::EPSILON * t0.abs());
            Some(k)
        }
        Family::BracketEnds => {
            let end = 0.75;
            let k = match i % 4 {
                // Rising exactly at the end: f(end) = 0 exactly.
                0 => {
                    let mut k = case(
                        family,
                        Shape::Power {
                            k: 1.0,
                            r: end,
                            n: 1,
                        },
                        0.0,
                        end,
                        Crossing::Rising,
                    );
                    k.expected = Some(end);
                    k
                }
                // Just beyond the end: none.
                1 => case(
                    family,
                    Shape::Power {
                        k: 1.0,
                        r: end + 1e-7,
                        n: 1,
                    },
                    0.0,
                    end,
                    Crossing::Rising,
                ),
                // Just after the start.
                2 => {
                    let r = 1e-7 * rng.range(1.0, 10.0);
                    let mut k = case(
                        family,
                        Shape::Power { k: -1.0, r, n: 1 },
                        0.0,
                        end,
                        Crossing::Falling,
                    );
                    k.expected = Some(r);
                    k
                }
                // Just before the start: already crossed, none after.
                _ => case(
                    family,
                    Shape::Power {
                        k: -1.0,
                        r: -1e-7,
                        n: 1,
                    },
                    0.0,
                    end,
                    Crossing::Falling,
                ),
            };
            Some(k)
        }
    }
}

/// The earliest accepted root of a `Tanh` shape, from its listed roots.
fn first_listed_root(shape: &mut Shape, t0: f64, end: f64, seek: Crossing) -> Option<f64> {
    let Shape::Tanh { roots, .. } = shape else {
        return None;
    };
    let list = roots.clone();
    let (f0, df0) = shape.eval(t0);
    let mut side = Side::of(f0, df0, Side::Pos);
    for (r, _) in list {
        if r <= t0 || r > end {
            continue;
        }
        if seek.accepts(side.leaving()) {
            return Some(r);
        }
        side = side.flip();
    }
    None
}

/// A random tumbling pair entering the interaction sphere, with a random terrace.
fn tumbling(rng: &mut Mix) -> Option<Case> {
    // 003 §V: ε = 3 kJ/mol, σ = 3.035 Å, ζ = 1 Å, m = 18 g/mol, I = 1.154 g/mol·Å², T* = 1.4.
    let zeta: f64 = 1.0 / 3.035;
    let inertia: f64 = 1.154 / (18.0 * 3.035 * 3.035);
    let kt: f64 = 1.4;
    let reach = 2.0;
    let speed = (2.0 * kt).sqrt() * rng.normal().abs().max(0.3);
    let dir = rng.unit_vector();
    let mut side = rng.unit_vector();
    let along = dot(side, dir);
    side = std::array::from_fn(|k| side[k] - along * dir[k]);
    let n = dot(side, side).sqrt();
    if n < 1e-6 {
        return None;
    }
    side = side.map(|x| x / n);
    let b = reach * 0.8 * rng.unit().sqrt();
    let back = (reach * reach - b * b).sqrt();
    let r0 = std::array::from_fn(|k| -back * dir[k] + b * side[k]);
    let v = dir.map(|x| x * speed);
    let end = 2.0 * back / speed;
    let mut plane = || {
        let e1 = rng.unit_vector();
        let mut e2 = rng.unit_vector();
        let p = dot(e1, e2);
        e2 = std::array::from_fn(|k| e2[k] - p * e1[k]);
        let n = dot(e2, e2).sqrt();
        [e1, e2.map(|x| x / n)]
    };
    let planes = [plane(), plane()];
    let mut spin = || {
        let w = (kt / inertia).sqrt() * (-2.0 * (1.0 - rng.unit()).ln()).sqrt();
        (w, rng.range(0.0, 2.0 * PI))
    };
    let spin = [spin(), spin()];
    let dv = 0.5 * kt;
    let k = rng.pick(&[-1i32, 0, 0, 1, 1, 2, 3, 5, 8]);
    let uk = (f64::from(k) - 0.5) * dv;
    let seek = if k >= 1 {
        Crossing::Rising
    } else {
        Crossing::Falling
    };
    let shape = Shape::Rods(Box::new(Rods {
        r0,
        v,
        planes,
        spin,
        zeta,
        uk,
    }));
    referenced(case(Family::Tumbling, shape, 0.0, end, seek), 2e-4)
}

/// Fills in the expected root from the dense reference scan; `None` if the case is ambiguous.
fn referenced(mut k: Case, step: f64) -> Option<Case> {
    let r = reference_root(&mut k.shape, k.t0, k.end, k.seek, step);
    if r.closest_extremum < AMBIGUOUS {
        return None;
    }
    k.expected = r.root;
    Some(k)
}

/// What the reference scan found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reference {
    /// The earliest accepted root.
    pub root: Option<f64>,
    /// The smallest `|f|` at an extremum turning towards zero that did not cross it, before
    /// the root: a case whose answer hinges on such an extremum is ambiguous.
    pub closest_extremum: f64,
}

/// The earliest accepted root by brute force: samples every `step`, locates every extremum
/// that turns towards zero by bisection on `f'`, and every root by bisection on `f`. Slow
/// (thousands of evaluations) and meant only as the corpus's answer key.
pub fn reference_root<I: Indicator>(
    f: &mut I,
    t0: f64,
    end: f64,
    seek: Crossing,
    step: f64,
) -> Reference {
    let fallback = match seek {
        Crossing::Falling => Side::Neg,
        _ => Side::Pos,
    };
    let (f0, d0) = f.eval(t0);
    let mut side = Side::of(f0, d0, fallback);
    let mut p = (t0, f0, d0);
    let mut closest = f64::INFINITY;
    let n = ((end - t0) / step).ceil().max(1.0) as u64;
    for k in 1..=n {
        let t = if k == n {
            end
        } else {
            t0 + (end - t0) * k as f64 / n as f64
        };
        let (fq, dq) = f.eval(t);
        let q = (t, fq, dq);
        let q_side = Side::of(fq, dq, side);
        if q_side != side {
            if seek.accepts(side.leaving()) {
                return Reference {
                    root: Some(bisect_root(f, p.0, q.0, side)),
                    closest_extremum: closest,
                };
            }
            side = q_side;
        } else {
            let turns = match side {
                Side::Pos => p.2 < 0.0 && q.2 > 0.0,
                Side::Neg => p.2 > 0.0 && q.2 < 0.0,
            };
            if turns {
                let m = bisect_slope(f, p.0, q.0, p.2 < 0.0);
                let (fm, _) = f.eval(m);
                if side.sign() * fm < 0.0 {
                    let first = side.leaving();
                    let root = if seek.accepts(first) {
                        bisect_root(f, p.0, m, side)
                    } else {
                        bisect_root(f, m, q.0, side.flip())
                    };
                    return Reference {
                        root: Some(root),
                        closest_extremum: closest,
                    };
                }
                closest = closest.min(fm.abs());
            }
        }
        p = q;
    }
    Reference {
        root: None,
        closest_extremum: closest,
    }
}

/// Bisection for the crossing in `[a, b]`, `f` on `side` at `a`.
fn bisect_root<I: Indicator>(f: &mut I, mut a: f64, mut b: f64, side: Side) -> f64 {
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let (fm, _) = f.eval(m);
        if side.sign() * fm > 0.0 {
            a = m;
        } else {
            b = m;
        }
    }
    b
}

/// Bisection for the zero of `f'` in `[a, b]`; `rising` if `f'` goes from negative to positive.
fn bisect_slope<I: Indicator>(f: &mut I, mut a: f64, mut b: f64, rising: bool) -> f64 {
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let (_, dm) = f.eval(m);
        if (dm < 0.0) == rising {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn numeric_slope(shape: &mut Shape, t: f64) -> f64 {
        let h = 1e-6;
        (shape.eval(t + h).0 - shape.eval(t - h).0) / (2.0 * h)
    }

    #[test]
    fn every_shape_has_a_derivative_that_matches_its_values() {
        for mut case in cases(11, 4) {
            for k in 1..10 {
                let t = case.t0 + (case.end - case.t0) * f64::from(k) / 10.0;
                let (_, df) = case.shape.eval(t);
                let num = numeric_slope(&mut case.shape, t);
                assert!(
                    (df - num).abs() <= 1e-5 * (1.0 + num.abs()),
                    "{}: t = {t}: f' = {df}, numeric {num}",
                    case.name
                );
            }
        }
    }

    #[test]
    fn expected_roots_are_roots_in_the_bracket() {
        for mut case in cases(3, 6) {
            if let Some(r) = case.expected {
                assert!(r > case.t0 && r <= case.end, "{}", case.name);
                let (v, _) = case.shape.eval(r);
                let (_, slope) = case.shape.eval(r);
                // |f| at the root is at most its slope times the accuracy (plus round-off).
                assert!(
                    v.abs() <= slope.abs() * case.accuracy + 1e-12,
                    "{}: f({r}) = {v}",
                    case.name
                );
            }
        }
    }

    #[test]
    fn reference_agrees_with_analytic_roots() {
        // The scan is the answer key of two families: check it where the answer is known.
        for mut case in cases(5, 8) {
            if !matches!(
                case.family,
                Family::Grazing | Family::NearMiss | Family::SeveralRoots | Family::Stiff
            ) {
                continue;
            }
            let r = reference_root(&mut case.shape, case.t0, case.end, case.seek, 1e-4);
            assert_eq!(
                case.judge(r.root),
                Verdict::Right,
                "{}: {r:?} vs {:?}",
                case.name,
                case.expected
            );
        }
    }

    #[test]
    fn corpus_is_reproducible_and_complete() {
        let a = cases(1, 3);
        assert_eq!(a, cases(1, 3));
        assert_eq!(a.len(), 3 * Family::ALL.len());
        assert_ne!(a, cases(2, 3));
    }

    #[test]
    fn judge_distinguishes_missed_from_wrong() {
        let mut k = case(
            Family::Flat,
            Shape::Power {
                k: 1.0,
                r: 0.5,
                n: 1,
            },
            0.0,
            1.0,
            Crossing::Rising,
        );
        k.expected = Some(0.5);
        assert_eq!(k.judge(Some(0.5 + 1e-12)), Verdict::Right);
        assert_eq!(k.judge(Some(0.6)), Verdict::Missed);
        assert_eq!(k.judge(None), Verdict::Missed);
        assert_eq!(k.judge(Some(0.4)), Verdict::Wrong);
        k.expected = None;
        assert_eq!(k.judge(Some(0.4)), Verdict::Wrong);
        assert_eq!(k.judge(None), Verdict::Right);
    }
}
