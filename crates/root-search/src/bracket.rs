//! Analytic brackets from the centre-of-mass motion (000 §III.A, 003 §V.A).
//!
//! Two bodies can only interact while their centres are closer than the interaction reach
//! (`r_m`, 003 Eq. 25, or the sum of bounding-sphere radii, 000 §III.A). The relative centre
//! moves on a straight line between events, `r(t) = r + v t`, so the times at which its distance
//! enters and leaves a sphere of radius `R` solve `|r + v t|² = R²`, a quadratic
//! `a t² + 2 b t + c = 0` with `a = v·v`, `b = r·v`, `c = r·r − R²`. Those times bound every
//! root search of the pair.
//!
//! Two cancellations spoil the textbook formula and are avoided here: the discriminant is
//! computed as `a R² − |r × v|²` (Lagrange's identity) instead of `b² − a c`, so a far pair
//! on a nearly tangent course keeps its precision; `c` as `(|r| − R)(|r| + R)`; and of the two
//! roots only the one without cancellation comes from the `−b ∓ √…` formula, the other from
//! the product of the roots, `c / a`.

use crate::SearchError;

/// The times during which the centre distance is at most the radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereWindow {
    /// When the distance falls to the radius (negative or `−∞` if already inside).
    pub enter: f64,
    /// When it rises back to the radius (`+∞` if the pair never separates).
    pub exit: f64,
}

impl SphereWindow {
    /// The part of the window after `now`, as a search bracket `(start, end)`; `None` if the
    /// window is already over.
    pub fn after(&self, now: f64) -> Option<(f64, f64)> {
        (self.exit >= now).then(|| (self.enter.max(now), self.exit))
    }
}

/// When a relative position `r` moving with constant relative velocity `v` is within `radius`
/// of the origin, with times relative to the moment `r` was taken. `None` if never.
///
/// A tangent course gives `enter == exit`; no relative velocity gives `(−∞, +∞)` inside the
/// sphere and `None` outside.
///
/// ```
/// use root_search::sphere_window;
///
/// // Head-on at unit speed from distance 5 towards a sphere of radius 2: in at 3, out at 7.
/// let w = sphere_window([5.0, 0.0, 0.0], [-1.0, 0.0, 0.0], 2.0)?.unwrap();
/// assert_eq!((w.enter, w.exit), (3.0, 7.0));
/// assert_eq!(w.after(4.0), Some((4.0, 7.0)));
/// # Ok::<(), root_search::SearchError>(())
/// ```
///
/// # Errors
/// [`SearchError::BadSetting`] if a component is not finite or the radius is negative.
#[inline]
pub fn sphere_window(
    r: [f64; 3],
    v: [f64; 3],
    radius: f64,
) -> Result<Option<SphereWindow>, SearchError> {
    // One branch on the fast path; the message is only built for bad input.
    let finite = r[0].is_finite()
        & r[1].is_finite()
        & r[2].is_finite()
        & v[0].is_finite()
        & v[1].is_finite()
        & v[2].is_finite()
        & radius.is_finite();
    if !(finite && radius >= 0.0) {
        return Err(bad_input(r, v, radius));
    }
    let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let a = dot(v, v);
    let b = dot(r, v);
    let dist = dot(r, r).sqrt();
    let c = (dist - radius) * (dist + radius);
    if a == 0.0 {
        return Ok((c <= 0.0).then_some(SphereWindow {
            enter: f64::NEG_INFINITY,
            exit: f64::INFINITY,
        }));
    }
    let cross = [
        r[1] * v[2] - r[2] * v[1],
        r[2] * v[0] - r[0] * v[2],
        r[0] * v[1] - r[1] * v[0],
    ];
    let disc = a * radius * radius - dot(cross, cross);
    if disc < 0.0 {
        return Ok(None);
    }
    if disc == 0.0 {
        // Tangent course: one instant of contact, at the closest approach.
        let t = -b / a;
        return Ok(Some(SphereWindow { enter: t, exit: t }));
    }
    let q = -(b + disc.sqrt().copysign(b));
    if q == 0.0 {
        // b = 0 and a tangent course: the closest approach is now, on the sphere.
        return Ok(Some(SphereWindow {
            enter: 0.0,
            exit: 0.0,
        }));
    }
    let (t1, t2) = (q / a, c / q);
    Ok(Some(SphereWindow {
        enter: t1.min(t2),
        exit: t1.max(t2),
    }))
}

/// The error naming the first non-finite component or the bad radius.
#[cold]
fn bad_input(r: [f64; 3], v: [f64; 3], radius: f64) -> SearchError {
    let components = r
        .iter()
        .map(|&x| ("relative position", x))
        .chain(v.iter().map(|&x| ("relative velocity", x)));
    for (name, value) in components {
        if !value.is_finite() {
            return SearchError::BadSetting {
                name,
                value,
                why: "finite in every component",
            };
        }
    }
    SearchError::BadSetting {
        name: "radius",
        value: radius,
        why: "finite and >= 0",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn dist_at(r: [f64; 3], v: [f64; 3], t: f64) -> f64 {
        let p = [r[0] + v[0] * t, r[1] + v[1] * t, r[2] + v[2] * t];
        (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
    }

    #[test]
    fn inside_moving_out_and_outside_moving_away() {
        let w = sphere_window([0.5, 0.0, 0.0], [1.0, 0.0, 0.0], 1.0)
            .unwrap()
            .unwrap();
        assert_eq!((w.enter, w.exit), (-1.5, 0.5));
        assert_eq!(w.after(0.0), Some((0.0, 0.5)));
        let w = sphere_window([3.0, 0.0, 0.0], [1.0, 0.0, 0.0], 1.0)
            .unwrap()
            .unwrap();
        assert!(w.exit < 0.0 && w.after(0.0).is_none());
    }

    #[test]
    fn misses_tangent_and_resting_pairs() {
        assert_eq!(
            sphere_window([3.0, 2.0, 0.0], [-1.0, 0.0, 0.0], 1.0).unwrap(),
            None
        );
        let w = sphere_window([3.0, 1.0, 0.0], [-1.0, 0.0, 0.0], 1.0)
            .unwrap()
            .unwrap();
        assert_eq!((w.enter, w.exit), (3.0, 3.0));
        let w = sphere_window([0.1, 0.0, 0.0], [0.0; 3], 1.0)
            .unwrap()
            .unwrap();
        assert_eq!((w.enter, w.exit), (f64::NEG_INFINITY, f64::INFINITY));
        assert_eq!(sphere_window([2.0, 0.0, 0.0], [0.0; 3], 1.0).unwrap(), None);
    }

    #[test]
    fn bad_inputs_are_named() {
        let e = sphere_window([f64::NAN, 0.0, 0.0], [0.0; 3], 1.0).unwrap_err();
        assert!(e.to_string().contains("relative position"));
        let e = sphere_window([0.0; 3], [0.0, f64::INFINITY, 0.0], 1.0).unwrap_err();
        assert!(e.to_string().contains("relative velocity"));
        assert!(sphere_window([0.0; 3], [0.0; 3], -1.0).is_err());
    }

    #[test]
    fn far_nearly_tangent_course_keeps_its_precision() {
        // Distance 1e6, impact parameter just inside the radius: the textbook b² − ac loses
        // about 12 digits to cancellation here.
        let (x, y, radius) = (1e6, 1.0 - 1e-6, 1.0);
        let w = sphere_window([x, y, 0.0], [-1.0, 0.0, 0.0], radius)
            .unwrap()
            .unwrap();
        let half = (radius * radius - y * y).sqrt();
        assert!(
            (w.enter - (x - half)).abs() <= 1e-9,
            "{}",
            w.enter - (x - half)
        );
        assert!((w.exit - (x + half)).abs() <= 1e-9);
        // The textbook formula for comparison, to show the test can tell them apart.
        let (a, b, c) = (1.0, -x, x * x + y * y - radius * radius);
        let naive = (-b - (b * b - a * c).max(0.0).sqrt()) / a;
        assert!((naive - (x - half)).abs() > 1e-6);
    }

    proptest! {
        #[test]
        fn ends_lie_on_the_sphere(
            r in prop::array::uniform3(-10.0f64..10.0),
            v in prop::array::uniform3(-3.0f64..3.0),
            radius in 0.1f64..5.0,
        ) {
            let speed = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            prop_assume!(speed > 1e-3);
            match sphere_window(r, v, radius).unwrap() {
                Some(w) => {
                    prop_assert!(w.enter <= w.exit);
                    for t in [w.enter, w.exit] {
                        prop_assert!((dist_at(r, v, t) - radius).abs() < 1e-9 * (1.0 + radius));
                    }
                    let mid = 0.5 * (w.enter + w.exit);
                    prop_assert!(dist_at(r, v, mid) <= radius * (1.0 + 1e-12));
                }
                None => {
                    // Closest approach is outside.
                    let tc = -(r[0] * v[0] + r[1] * v[1] + r[2] * v[2]) / (speed * speed);
                    prop_assert!(dist_at(r, v, tc) > radius * (1.0 - 1e-12));
                }
            }
        }
    }
}
