//! The terrace map (003 Eq. 7) and what it does to the second virial coefficient: reference
//! values, exactness of the B2-matching rule, convergence as ΔV → 0, the shape of V(U), levels
//! at the minimum, the reach, and the rods' orientation average checked against a direct
//! quadrature over orientations.

use potential::quadrature::{GaussLegendre, Tolerance, integrate};
use potential::{
    GayBerne, Layout, LennardJones, LevelSet, LjRod, PairPotential, Placement, PotentialError,
    StepEnergy, Steps, TerraceMap, TerraceOptions, profile, virial,
};
use proptest::prelude::*;

const LJ_B2: &str = include_str!("../../reference/lj_b2.txt");

fn lj() -> LennardJones {
    LennardJones::new(1.0, 1.0).unwrap()
}

fn rods() -> LjRod {
    // The paper's rods in reduced units: ζ = 1 Å / 3.035 Å.
    LjRod::new(1.0, 1.0, 1.0 / 3.035).unwrap()
}

fn rules(dv: f64, kt: f64) -> Vec<(Placement, StepEnergy)> {
    let mut out = vec![(Placement::EqualEnergy, StepEnergy::Equal(dv))];
    for p in Placement::ALL {
        for e in [
            StepEnergy::Midpoint,
            StepEnergy::VolumeAverage,
            StepEnergy::Virial { kt },
        ] {
            out.push((p, e));
        }
    }
    out
}

#[test]
fn lennard_jones_b2_against_the_reference_table_and_the_published_value() {
    let p = profile::lennard_jones(&lj()).unwrap();
    for line in LJ_B2.lines() {
        let v: Vec<f64> = line
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        let b = virial::b2(&p, v[0]).unwrap();
        assert!(
            (b - v[1]).abs() < 1e-12 * v[1].abs(),
            "T* = {}: {b} vs {}",
            v[0],
            v[1]
        );
    }
    // Hirschfelder, Curtiss & Bird (1954), Table I-B: B2/b0 = −2.538 at T* = 1.00,
    // b0 = 2πσ³/3.
    let b = virial::b2(&p, 1.0).unwrap() / (2.0 * std::f64::consts::PI / 3.0);
    assert!((b + 2.538).abs() < 5e-4, "{b}");
}

#[test]
fn b2_matching_is_exact_shell_by_shell_at_its_temperature_only() {
    let p = profile::lennard_jones(&lj()).unwrap();
    check_matching("LJ", &p, 1.0, -1.0);
    check_matching("LJ", &p, 2.0, -1.0);
    check_matching("rods", &profile::rods(&rods()).unwrap(), 1.4, -1.0);
}

fn check_matching<F: Fn(f64) -> f64>(name: &str, prof: &potential::Profile<F>, kt: f64, min: f64) {
    let opts = TerraceOptions::default().shifting().with_core(25.0 * kt);
    for dv in [kt, kt / 4.0] {
        let layout = Layout::paper(min, dv, &opts).unwrap();
        for placement in Placement::ALL {
            let map = TerraceMap::from_profile(
                prof,
                placement,
                &layout,
                StepEnergy::Virial { kt },
                &opts,
            )
            .unwrap();
            let t = virial::terms(prof, &map, kt).unwrap();
            let scale = t.b2_continuous_total().abs();
            for k in 0..map.terraces() {
                if k == t.zero {
                    continue;
                }
                let d = t.b2_terraced[k] - t.b2_continuous[k];
                assert!(
                    d.abs() < 1e-11 * scale,
                    "{name} {placement:?} ΔV={dv}: terrace {k}: {d:e}"
                );
            }
            // The total differs by the zero terrace (far pairs carry V = 0) and the core.
            let gap = t.b2_terraced_total() - t.b2_continuous_total();
            let expected = -t.b2_continuous[t.zero] + (t.b2_core.1 - t.b2_core.0);
            assert!(
                (gap - expected).abs() < 1e-11 * scale,
                "{name}: {gap} vs {expected}"
            );
            // At another temperature the same map is not exact: the test can fail.
            let other = virial::terms(prof, &map, 1.5 * kt).unwrap();
            let worst = (0..map.terraces())
                .filter(|&k| k != other.zero)
                .map(|k| (other.b2_terraced[k] - other.b2_continuous[k]).abs())
                .fold(0.0, f64::max);
            assert!(worst > 1e-4 * scale, "{name}: matching at 1.5 kT is exact?");
        }
    }
}

#[test]
fn terraced_b2_converges_like_the_square_root_of_the_step() {
    // The zero terrace cuts the tail at U = −ΔV/2, r_c ∝ ΔV^{−1/6}; the missing tail of B2 is
    // ∝ r_c⁻³ ∝ ΔV^{1/2}. Every rule converges, at that rate, as ΔV → 0.
    let p = profile::lennard_jones(&lj()).unwrap();
    let kt = 1.0;
    let b = virial::b2(&p, kt).unwrap();
    let steps: Vec<f64> = (2..7).map(|j| kt * 2f64.powi(-j)).collect();
    for (placement, energy) in rules(1.0, kt) {
        let mut errors = Vec::new();
        for &dv in &steps {
            let opts = TerraceOptions::default().shifting().with_core(25.0 * kt);
            let layout = Layout::paper(-1.0, dv, &opts).unwrap();
            let energy = match energy {
                StepEnergy::Equal(_) => StepEnergy::Equal(dv),
                e => e,
            };
            let map = TerraceMap::from_profile(&p, placement, &layout, energy, &opts).unwrap();
            let t = virial::terms(&p, &map, kt).unwrap();
            errors.push(((t.b2_terraced_total() - b) / b).abs());
        }
        let label = format!("{} + {}", placement.name(), energy.name());
        assert!(errors.last().unwrap() < &0.15, "{label}: {errors:?}");
        // Ratio per halving of ΔV over the last three halvings: √½ ≈ 0.71 (0.6 .. 0.8).
        let ratio = (errors[4] / errors[1]).powf(1.0 / 3.0);
        assert!(
            (0.6..0.8).contains(&ratio),
            "{label}: ratio {ratio}, {errors:?}"
        );
    }
}

#[test]
fn paper_map_shape_and_eq_7_literally() {
    let map = TerraceMap::evenly_spaced(&lj(), 0.3, &TerraceOptions::default()).unwrap();
    let levels = map.levels();
    let dv = 0.3;
    let mut last = f64::NEG_INFINITY;
    for i in 0..=20_000 {
        let u = -1.0 + i as f64 * 0.001;
        let v = map.value(u);
        assert!(v <= u + dv, "V({u}) = {v}");
        assert!(v >= last, "V must not decrease");
        last = v;
        // 003 Eq. 7 term by term: V_min + Σ Θ(U − U_k) ΔV_k with Θ(0) = 1.
        let literal = map.v_min()
            + levels
                .iter()
                .enumerate()
                .filter(|&(_, &l)| u >= l)
                .map(|(k, _)| map.step_up(k).unwrap())
                .sum::<f64>();
        assert!((literal - v).abs() < 1e-12, "{u}: {literal} vs {v}");
    }
    assert_eq!(map.value(-1e-12), 0.0);
    assert_eq!(map.value(1e-12), 0.0);
}

#[test]
fn every_rule_stays_within_its_terrace_and_is_monotone() {
    let p = profile::lennard_jones(&lj()).unwrap();
    let kt = 1.0;
    for dv in [2.0 * kt, kt / 4.0] {
        let opts = TerraceOptions::default().shifting().with_core(25.0 * kt);
        let layout = Layout::paper(-1.0, dv, &opts).unwrap();
        for (placement, energy) in rules(dv, kt).into_iter().skip(1) {
            let map = TerraceMap::from_profile(&p, placement, &layout, energy, &opts).unwrap();
            let l = map.levels();
            for (k, &v) in map.energies().iter().enumerate() {
                let lo = if k == 0 { -1.0 } else { l[k - 1] };
                let hi = l.get(k).copied().unwrap_or(map.core());
                assert!(
                    v >= lo && v <= hi,
                    "{placement:?} {energy:?}: V_{k} = {v} ∉ [{lo}, {hi}]"
                );
            }
            assert!(map.energies().windows(2).all(|w| w[1] >= w[0]));
        }
    }
}

#[test]
fn stiff_steps_far_above_and_far_below_kt() {
    let p = profile::lennard_jones(&lj()).unwrap();
    for (kt, dv) in [(0.02, 1.0), (50.0, 0.05)] {
        // ΔV = 50 kT and ΔV = kT/1000.
        let opts = TerraceOptions::default().shifting().with_core(30.0);
        let layout = Layout::paper(-1.0, dv, &opts).unwrap();
        for placement in Placement::ALL {
            let map =
                TerraceMap::from_profile(&p, placement, &layout, StepEnergy::Virial { kt }, &opts)
                    .unwrap();
            let t = virial::terms(&p, &map, kt).unwrap();
            assert!(t.b2_terraced_total().is_finite() && t.e2_terraced_total().is_finite());
            let scale = t.b2_continuous_total().abs();
            for k in (0..map.terraces()).filter(|&k| k != t.zero) {
                let d = t.b2_terraced[k] - t.b2_continuous[k];
                assert!(d.abs() < 1e-9 * scale, "kT = {kt}: terrace {k}: {d:e}");
            }
        }
    }
}

#[test]
fn levels_within_1e_9_of_the_minimum() {
    // ε chosen so that the paper's grid with ΔV = 0.4 has a level 1e-9 above −ε.
    let eps = 1.0 - 1e-9;
    let lj = LennardJones::new(eps, 1.0).unwrap();
    let opts = TerraceOptions::default();
    let e = TerraceMap::evenly_spaced(&lj, 0.4, &opts).unwrap_err();
    assert!(matches!(e, PotentialError::LevelAtMinimum { .. }), "{e}");
    assert!(e.to_string().contains("zero width"));
    let map = TerraceMap::evenly_spaced(&lj, 0.4, &opts.shifting()).unwrap();
    assert_eq!(map.level_set().shifted(), &[0]);
    let first = map.levels()[0];
    assert!(
        (first - (-eps + 0.25 * (-0.6 + eps))).abs() < 1e-15,
        "{first}"
    );
    // Every terrace has a width of at least a tenth of the spacing.
    let p = profile::lennard_jones(&lj).unwrap();
    let (shells, _) = p.shells(map.level_set()).unwrap();
    for (k, s) in shells.iter().enumerate().take(3) {
        let (a, b) = s.inner.unwrap();
        assert!(b - a > 1e-3, "terrace {k}: inner width {}", b - a);
    }
    // The same within 1e-9 below the minimum (the grid continues below the well).
    let lj = LennardJones::new(1.0 + 1e-9, 1.0).unwrap();
    assert!(TerraceMap::evenly_spaced(&lj, 0.4, &opts).is_err());
    // Explicit lists too.
    assert!(TerraceMap::from_levels(&lj, &[-1.0], Steps::Uniform(0.5), &opts).is_err());
}

#[test]
fn the_reach_of_a_map() {
    let r = LjRod::paper();
    for dv in [0.5, 1.0, 2.1, 4.2] {
        let map = TerraceMap::evenly_spaced(&r, dv, &TerraceOptions::default()).unwrap();
        // 003 Eq. 25 as printed.
        let eq25 = 0.5 * r.zeta()
            + r.sigma() / (0.5 * (1.0 - (1.0 - dv / (2.0 * r.epsilon())).sqrt())).powf(1.0 / 6.0);
        let got = map.reach(&r).unwrap();
        assert!((got - eq25).abs() < 1e-12 * eq25, "{dv}: {got} vs {eq25}");
    }
    // Gay–Berne: the numerical reach of the outermost levels.
    let gb = GayBerne::default();
    let map = TerraceMap::evenly_spaced(&gb, 0.2, &TerraceOptions::default()).unwrap();
    let got = map.reach(&gb).unwrap();
    let direct = gb.reach(-0.1).unwrap().max(gb.reach(0.1).unwrap());
    assert_eq!(got, direct);
    // No sampled configuration beyond the reach reaches the level.
    let mut r = 12345u64;
    let mut next = || {
        r ^= r << 13;
        r ^= r >> 7;
        r ^= r << 17;
        (r >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for _ in 0..20_000 {
        let v = glam::DVec3::new(next(), next(), next());
        let a = glam::DVec3::new(next(), next(), next());
        let b = glam::DVec3::new(next(), next(), next());
        if v.length() < 0.1 || a.length() < 0.1 || b.length() < 0.1 {
            continue;
        }
        let g = potential::PairGeometry::new(
            v.normalize() * got * 1.000_001,
            a.normalize(),
            b.normalize(),
        );
        assert!(gb.energy(&g) > -0.1, "{g:?}");
    }
}

#[test]
fn rods_orientation_average_against_a_direct_quadrature() {
    // B2 of the rods by the profile's averaged measure, against B2 averaged over c = s_i·s_j
    // (uniform on [−1, 1] for independent random axes) of the radial integral at each c.
    let rod = rods();
    let p = profile::rods(&rod).unwrap();
    let kt = 1.4;
    let gl = GaussLegendre::new(12).unwrap();
    let tol = Tolerance {
        rel: 1e-13,
        ..Tolerance::default()
    };
    let radial = |c: f64, v: &dyn Fn(f64) -> f64| {
        let delta = rod.zeta() * (0.5 - c * c);
        // ∫₀^∞ (e^{−V(r_e)/kT} − 1) r² dr with r_e = r + δ.
        let f = |r: f64| (-v(r + delta) / kt).exp_m1() * r * r;
        let a = integrate(f, 0.0, 1.5, tol).unwrap().value;
        let b = potential::quadrature::integrate_to_infinity(f, 1.5, tol)
            .unwrap()
            .value;
        -2.0 * std::f64::consts::PI * (a + b)
    };
    let cont = gl.integrate(|c| radial(c, &|x| rod.energy_of_effective(x)), 0.0, 1.0);
    let ours = virial::b2(&p, kt).unwrap();
    assert!((cont - ours).abs() < 1e-10 * ours.abs(), "{cont} vs {ours}");

    let opts = TerraceOptions::default().with_core(25.0 * kt);
    let map = TerraceMap::evenly_spaced(&rod, 0.35, &opts).unwrap();
    let t = virial::terms(&p, &map, kt).unwrap();
    // The terraced potential as a function of r_e, then the same average. It is piecewise
    // constant, so integrate shell by shell in r at each c.
    let (shells, core) = p.shells(map.level_set()).unwrap();
    let terr = gl.integrate(
        |c| {
            let delta = rod.zeta() * (0.5 - c * c);
            let cube = |x: f64| (x - delta).max(0.0).powi(3) / 3.0;
            let mut s = cube(core); // e^{−∞} − 1 = −1 inside the core
            for (k, sh) in shells.iter().enumerate() {
                let v = map.energies()[k];
                for (a, b) in [sh.inner, sh.outer].into_iter().flatten() {
                    if k != map.zero_terrace() {
                        s -= (-v / kt).exp_m1() * (cube(b) - cube(a));
                    }
                }
            }
            2.0 * std::f64::consts::PI * s
        },
        0.0,
        1.0,
    );
    let ours = t.b2_terraced_total();
    assert!((terr - ours).abs() < 1e-12 * ours.abs(), "{terr} vs {ours}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn terrace_of_is_consistent_with_the_levels(
        raw in prop::collection::vec(-0.99f64..30.0, 0..40),
        probes in prop::collection::vec(-2.0f64..40.0, 50),
    ) {
        let mut levels: Vec<f64> = raw.into_iter().filter(|l| l.abs() > 1e-6).collect();
        levels.sort_by(f64::total_cmp);
        levels.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        let set = LevelSet::new(-1.0, &levels, &TerraceOptions::default().with_core(35.0)).unwrap();
        let map = TerraceMap::new(set, Steps::Uniform(0.1)).unwrap();
        let mut probes = probes;
        probes.extend(levels.iter().flat_map(|&l| [l, l.next_up(), l.next_down()]));
        for u in probes {
            match map.terrace_of(u) {
                Ok(k) => {
                    if k > 0 { prop_assert!(levels[k - 1] <= u); }
                    if k < levels.len() { prop_assert!(u < levels[k]); }
                    let b = map.bounds(k).unwrap();
                    prop_assert!(b.below.is_none_or(|l| l <= u) && u < b.above);
                }
                Err(_) => prop_assert!(u >= 35.0),
            }
        }
        // Far pairs carry exactly zero.
        prop_assert_eq!(map.value(-1e-7), 0.0);
        let _ = map.reach(&lj()).unwrap();
    }
}

#[test]
fn trait_objects_and_references_work_alike() {
    let boxed: Box<dyn PairPotential> = Box::new(lj());
    let map = TerraceMap::evenly_spaced(&boxed, 0.5, &TerraceOptions::default()).unwrap();
    let direct = TerraceMap::evenly_spaced(&lj(), 0.5, &TerraceOptions::default()).unwrap();
    assert_eq!(map, direct);
    assert_eq!(map.reach(&boxed).unwrap(), direct.reach(&&lj()).unwrap());
}
