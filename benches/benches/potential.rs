//! ns per evaluation of each pair potential of `dmd-potential`, Lennard-Jones spheres as the
//! baseline in the same run:
//!
//! - `energy/*`: `U` alone (what a root search's sign test or a terrace lookup needs);
//! - `evaluate/*`: `U`, the force and both torques (what `U̇` and an impulse need);
//! - `terrace/*`: the terrace lookup of a value (binary search over the paper's levels) and
//!   the evaluation plus `U̇` (003 Eq. 12) that one root-search sample costs;
//! - `certify/*`: one step of certified prediction on the rods, a Taylor model of `r_e` with its
//!   remainder bound and the safe time inside a band (`potential::certify`), beside the sample.
//!
//! Static dispatch on concrete types, as the engines call them. Each measurement cycles through
//! 1024 pre-generated geometries in the interesting range of the potential (effective gap
//! between 0.85 and 3 contact distances, random directions and axes).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use potential::{
    FreeFlight, GayBerne, LennardJones, LjRod, PairGeometry, PairPotential, Smoothed, TerraceMap,
    TerraceOptions,
};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

const N: usize = 1024;

fn unit(r: &mut Xoshiro256PlusPlus) -> DVec3 {
    loop {
        let v = DVec3::new(
            r.random::<f64>() * 2.0 - 1.0,
            r.random::<f64>() * 2.0 - 1.0,
            r.random::<f64>() * 2.0 - 1.0,
        );
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

/// Geometries with the centre distance from `gap(n, s_i, s_j)` plus a uniform 0.85..3.
fn geometries(seed: u64, offset: impl Fn(DVec3, DVec3, DVec3) -> f64) -> Vec<PairGeometry> {
    let mut r = Xoshiro256PlusPlus::seed_from_u64(seed);
    (0..N)
        .map(|_| {
            let (n, si, sj) = (unit(&mut r), unit(&mut r), unit(&mut r));
            let d = 0.85 + 2.15 * r.random::<f64>() + offset(n, si, sj);
            PairGeometry::new(n * d, si, sj)
        })
        .collect()
}

fn energy<P: PairPotential>(c: &mut Criterion, name: &str, p: &P, geoms: &[PairGeometry]) {
    let mut k = 0;
    c.bench_function(&format!("potential/energy/{name}"), |b| {
        b.iter(|| {
            k = (k + 1) % N;
            black_box(p.energy(black_box(&geoms[k])))
        })
    });
}

fn evaluate<P: PairPotential>(c: &mut Criterion, name: &str, p: &P, geoms: &[PairGeometry]) {
    let mut k = 0;
    c.bench_function(&format!("potential/evaluate/{name}"), |b| {
        b.iter(|| {
            k = (k + 1) % N;
            black_box(p.evaluate(black_box(&geoms[k])))
        })
    });
}

fn bench(c: &mut Criterion) {
    let lj = LennardJones::new(1.0, 1.0).unwrap();
    let rod = LjRod::new(1.0, 1.0, 1.0 / 3.035).unwrap();
    let gb = GayBerne::default();
    let smooth = Smoothed::new(rod, 2.5, 3.0).unwrap();
    let g_lj = geometries(1, |_, _, _| 0.0);
    let g_rod = geometries(2, |_, si, sj| {
        let c = si.dot(sj);
        -rod.zeta() * (0.5 - c * c)
    });
    let g_gb = geometries(3, |n, si, sj| {
        gb.contact_and_depth(n.dot(si), n.dot(sj), si.dot(sj)).0 - 1.0
    });
    // The smoothed rods across the switching window and beyond (r from 2.3σ to 3.05σ): where
    // the switch costs something, and the branch on r is unpredictable.
    let mut r = Xoshiro256PlusPlus::seed_from_u64(4);
    let g_win: Vec<PairGeometry> = (0..N)
        .map(|_| {
            let (n, si, sj) = (unit(&mut r), unit(&mut r), unit(&mut r));
            PairGeometry::new(n * (2.3 + 0.75 * r.random::<f64>()), si, sj)
        })
        .collect();
    energy(c, "Lennard-Jones spheres (baseline)", &lj, &g_lj);
    energy(c, "LJ rods", &rod, &g_rod);
    energy(c, "Gay-Berne GB(3,5,2,1)", &gb, &g_gb);
    energy(c, "smoothed LJ rods, inside r_l", &smooth, &g_rod);
    energy(c, "smoothed LJ rods, r in [2.3, 3.05]", &smooth, &g_win);
    evaluate(c, "Lennard-Jones spheres (baseline)", &lj, &g_lj);
    evaluate(c, "LJ rods", &rod, &g_rod);
    evaluate(c, "Gay-Berne GB(3,5,2,1)", &gb, &g_gb);
    evaluate(c, "smoothed LJ rods, inside r_l", &smooth, &g_rod);
    evaluate(c, "smoothed LJ rods, r in [2.3, 3.05]", &smooth, &g_win);

    // One root-search sample on terraced rods: U and U̇, and the terrace of a value.
    let map = TerraceMap::evenly_spaced(&rod, 0.7, &TerraceOptions::default()).unwrap();
    let us: Vec<f64> = g_rod.iter().map(|g| rod.energy(g).min(99.0)).collect();
    let mut k = 0;
    c.bench_function(
        "potential/terrace/terrace_of (paper levels, dV = kT/2)",
        |b| {
            b.iter(|| {
                k = (k + 1) % N;
                black_box(map.terrace_of(black_box(us[k])))
            })
        },
    );
    let (v, wi, wj) = (DVec3::new(0.3, -0.2, 0.5), DVec3::X, DVec3::Y);
    c.bench_function(
        "potential/terrace/rods: U and U-dot (one search sample)",
        |b| {
            b.iter(|| {
                k = (k + 1) % N;
                black_box(
                    rod.evaluate(black_box(&g_rod[k]))
                        .map(|e| (e.energy, e.rate(v, wi, wj))),
                )
            })
        },
    );
    // One certified step: the Taylor model of r_e over a window of 0.02 and its safe time in
    // the band of the pair's own terrace of the map above (the model's cost alone; the engine
    // adds the two axes at the window's start).
    let flights: Vec<FreeFlight> = g_rod
        .iter()
        .enumerate()
        .map(|(i, g)| {
            let w = 3.0 + (i % 7) as f64;
            let wi = g.s_i.any_orthonormal_vector() * w;
            let wj = g.s_j.any_orthonormal_vector() * -w;
            FreeFlight::new(g.r_ij, v, g.s_i, wi, g.s_j, wj)
        })
        .collect();
    let levels = map.levels();
    let bands: Vec<(f64, f64)> = flights
        .iter()
        .zip(&us)
        .map(|(f, &u)| {
            let x = rod.taylor_model(f, 0.0).unwrap().x;
            let t = map.terrace_of(u).unwrap_or(0);
            let lo = if t == 0 {
                f64::NEG_INFINITY
            } else {
                levels[t - 1]
            };
            let hi = levels.get(t).copied().unwrap_or(map.core());
            let iv = rod.coordinate_intervals(lo, hi);
            potential::certify::interval_containing(&iv, x).unwrap_or((x, x))
        })
        .collect();
    c.bench_function(
        "potential/certify/rods: Taylor model of r_e and safe time",
        |b| {
            b.iter(|| {
                k = (k + 1) % N;
                let m = rod.taylor_model(black_box(&flights[k]), 0.02).unwrap();
                let (a, e) = bands[k];
                black_box(m.safe_time(a, e, 0.02))
            })
        },
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
