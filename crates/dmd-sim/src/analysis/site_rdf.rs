//! Site–site radial distribution functions of rigid molecules: `g_ab(r)` between the named
//! sites of different molecules (for water O–O, O–H and H–H), from the molecules' centres and
//! attitudes and each species' site offsets in its body frame.
//!
//! Normalisation, per unordered pair of site types `a ≤ b`: the sites of type `a` and `b` on
//! different molecules in a shell against the same pairs in an ideal gas of molecules at the
//! same density, `P_ab · 4π r² dr / V` with `P_ab = N_a N_b − Σ_m n_a,m n_b,m` (halved for
//! `a = b`), `N_a` the sites of type `a` and `n_a,m` those on molecule `m`: the `N_a N_b / V`
//! density with the intramolecular pairs left out, so every `g_ab` tends to 1 at large `r`
//! in an ideal gas of molecules, and the intramolecular distances (O–H at 1 Å in water) never
//! appear.

use glam::{DQuat, DVec3};

use crate::analysis::block::Blocks;
use crate::analysis::pairs::{for_each_pair, pair_index, ratio, shell_volume, wrap};

/// The named sites of a rigid molecule species: each site's name (its type; sites of one
/// name on any species count as one type) and its offset from the centre in the body frame
/// (length, the frame of the bodies' attitudes).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MoleculeSites {
    /// The name of each site (`O`, `H`, …).
    pub names: Vec<String>,
    /// The offset of each site from the centre, body frame (length).
    pub offsets: Vec<DVec3>,
}

/// The site–site `g_ab(r)` of every unordered pair of site types `a ≤ b` (module docs for
/// the normalisation), in the bins of the centres' g(r).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SiteRdf {
    /// The sites of each species.
    species: Vec<MoleculeSites>,
    /// The site types: the distinct names, in order of first appearance.
    types: Vec<String>,
    r_max: f64,
    width: f64,
    bins: usize,
    /// Counts of every pair of types ([`pair_index`]), `bins` each.
    counts: Vec<u64>,
    /// Each bin's `g_ab` of every evaluated configuration, blocked in sample order (laid out
    /// as `counts`).
    blocks: Vec<Blocks>,
    /// `P_ab` of every pair of types (set at the first evaluation; empty before).
    pairs: Vec<f64>,
    samples: u64,
    volume: f64,
    /// The current configuration's counts (scratch, kept to save an allocation a sample).
    #[serde(skip)]
    scratch: Vec<u64>,
}

/// A rows table of one pair of site types ([`SiteRdf::partials`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SitePairRdf {
    /// The first site type's name.
    pub a: String,
    /// The second site type's name.
    pub b: String,
    /// Rows `(r at bin centre, g_ab(r))`.
    pub rows: Vec<(f64, f64)>,
    /// The block-average error of each row (NaN with fewer than 16 configurations).
    pub errors: Vec<f64>,
}

impl SiteRdf {
    /// The site–site g(r) of molecules whose species have the sites `species` (one entry per
    /// species, in the scene's order), in `bins` bins up to `r_max` (at most half the
    /// smallest box side).
    pub fn new(species: Vec<MoleculeSites>, bins: usize, r_max: f64) -> Self {
        let mut types: Vec<String> = Vec::new();
        for n in species.iter().flat_map(|s| &s.names) {
            if !types.contains(n) {
                types.push(n.clone());
            }
        }
        let k = types.len();
        let cells = k * (k + 1) / 2 * bins;
        SiteRdf {
            species,
            types,
            r_max,
            width: r_max / bins as f64,
            bins,
            counts: vec![0; cells],
            blocks: vec![Blocks::default(); cells],
            pairs: Vec::new(),
            samples: 0,
            volume: 0.0,
            scratch: Vec::new(),
        }
    }

    /// The type index of every site of species `s`.
    fn site_types(&self, s: usize) -> Vec<usize> {
        self.species[s]
            .names
            .iter()
            .map(|n| self.types.iter().position(|t| t == n).unwrap_or(0))
            .collect()
    }

    /// `P_ab` of every pair of types for molecules of `species`.
    fn pair_counts(&self, species: &[u32]) -> Vec<f64> {
        let k = self.types.len();
        // Sites of each type per molecule of each species, and molecules of each species.
        let per: Vec<Vec<f64>> = (0..self.species.len())
            .map(|s| {
                let mut c = vec![0.0; k];
                for t in self.site_types(s) {
                    c[t] += 1.0;
                }
                c
            })
            .collect();
        let mut molecules = vec![0.0; self.species.len()];
        for &s in species {
            molecules[s as usize] += 1.0;
        }
        let total: Vec<f64> = (0..k)
            .map(|t| (0..per.len()).map(|s| molecules[s] * per[s][t]).sum())
            .collect();
        let mut pairs = vec![0.0; k * (k + 1) / 2];
        for a in 0..k {
            for b in a..k {
                let own: f64 = (0..per.len())
                    .map(|s| molecules[s] * per[s][a] * per[s][b])
                    .sum();
                let p = total[a] * total[b] - own;
                pairs[pair_index(a, b, k)] = if a == b { 0.5 * p } else { p };
            }
        }
        pairs
    }

    /// Adds the site pairs of one configuration: the centres in the box `l`, the species and
    /// the body → lab attitude of each molecule.
    pub(crate) fn accumulate(
        &mut self,
        pos: &[DVec3],
        species: &[u32],
        attitudes: &[DQuat],
        l: DVec3,
    ) {
        let k = self.types.len();
        let bins = self.bins;
        if self.pairs.is_empty() {
            self.pairs = self.pair_counts(species);
        }
        self.volume = l.x * l.y * l.z;
        self.samples += 1;
        // Every site in the box, with its molecule and type.
        let types: Vec<Vec<usize>> = (0..self.species.len())
            .map(|s| self.site_types(s))
            .collect();
        let mut sites = Vec::new();
        let mut owner = Vec::new();
        let mut kinds = Vec::new();
        for (i, ((&s, q), &c)) in species.iter().zip(attitudes).zip(pos).enumerate() {
            let s = s as usize;
            for (&o, &t) in self.species[s].offsets.iter().zip(&types[s]) {
                sites.push(wrap(c + *q * o, l));
                owner.push(i);
                kinds.push(t);
            }
        }
        let mut counts = std::mem::take(&mut self.scratch);
        counts.clear();
        counts.resize(self.counts.len(), 0);
        let inv_w = 1.0 / self.width;
        // The sites' own cell list: the same cut-off, so the same cells, as the centres' g(r).
        for_each_pair(&sites, l, self.r_max, |u, w, d| {
            if owner[u] != owner[w] {
                let bin = (d.length() * inv_w) as usize;
                if bin < bins {
                    counts[pair_index(kinds[u], kinds[w], k) * bins + bin] += 1;
                }
            }
        });
        for (p, &pairs) in self.pairs.iter().enumerate() {
            for bin in 0..bins {
                let c = counts[p * bins + bin];
                self.counts[p * bins + bin] += c;
                let ideal = pairs * self.shell_volume(bin) / self.volume;
                self.blocks[p * bins + bin].push(ratio(c, ideal));
            }
        }
        self.scratch = counts;
    }

    /// Volume of the shell of bin `k`.
    fn shell_volume(&self, k: usize) -> f64 {
        shell_volume(self.width, k)
    }

    /// The site types' names, in the order of [`partials`](Self::partials).
    pub fn types(&self) -> &[String] {
        &self.types
    }

    /// `g_ab(r)` of every pair of site types `a ≤ b`, in the order `(0,0), (0,1), …, (1,1), …`
    /// of [`types`](Self::types) (for water: O–O, O–H, H–H).
    pub fn partials(&self) -> Vec<SitePairRdf> {
        let k = self.types.len();
        let mut out = Vec::new();
        for a in 0..k {
            for b in a..k {
                let p = pair_index(a, b, k);
                let pairs = self.pairs.get(p).copied().unwrap_or(0.0);
                let rows = (0..self.bins)
                    .map(|bin| {
                        let r = (bin as f64 + 0.5) * self.width;
                        let ideal = if self.samples == 0 {
                            0.0
                        } else {
                            pairs * self.shell_volume(bin) * self.samples as f64 / self.volume
                        };
                        (r, ratio(self.counts[p * self.bins + bin], ideal))
                    })
                    .collect();
                let errors = (0..self.bins)
                    .map(|bin| self.blocks[p * self.bins + bin].estimate().error)
                    .collect();
                out.push(SitePairRdf {
                    a: self.types[a].clone(),
                    b: self.types[b].clone(),
                    rows,
                    errors,
                });
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// A bent three-site molecule: O at the origin-ish, two H at 1 Å from it.
    fn water() -> MoleculeSites {
        let half = 0.5 * 109.47_f64.to_radians();
        let o = DVec3::new(0.0, 0.0, -0.065);
        let h = |y: f64| o + DVec3::new(0.0, y * half.sin(), half.cos());
        MoleculeSites {
            names: vec!["O".into(), "H".into(), "H".into()],
            offsets: vec![o, h(1.0), h(-1.0)],
        }
    }

    /// Two molecules, the second's centre 3.05 Å along x and turned by 90° about z: the O–O
    /// pair is in the bin of 3.0–3.1 Å with the count the normalisation of two molecules gives,
    /// every O–H and H–H pair lies where the geometry puts it, and no bin holds the
    /// intramolecular O–H distance of 1 Å or H–H distance of 1.633 Å.
    #[test]
    fn two_molecules_count_their_intermolecular_pairs_only() {
        let l = DVec3::splat(20.0);
        let sites = water();
        let mut rdf = SiteRdf::new(vec![sites.clone()], 50, 5.0);
        let q = [
            DQuat::IDENTITY,
            DQuat::from_rotation_z(0.5 * std::f64::consts::PI),
        ];
        let pos = [DVec3::splat(5.0), DVec3::new(8.05, 5.0, 5.0)];
        rdf.accumulate(&pos, &[0, 0], &q, l);
        assert_eq!(rdf.types(), ["O", "H"]);
        let p = rdf.partials();
        assert_eq!(
            p.iter()
                .map(|x| format!("{}{}", x.a, x.b))
                .collect::<Vec<_>>(),
            ["OO", "OH", "HH"]
        );
        // Every bin's count back from g: g · P_ab · shell / V.
        let count = |x: &SitePairRdf, bin: usize| -> f64 {
            let w = 0.1;
            let shell = 4.0 / 3.0
                * std::f64::consts::PI
                * (((bin + 1) as f64 * w).powi(3) - (bin as f64 * w).powi(3));
            x.rows[bin].1 * shell / 8000.0
        };
        // P_OO = (2·2 − 2·1·1) / 2 = 1, P_OH = 2·4 − 2·1·2 = 4, P_HH = (4·4 − 2·2·2) / 2 = 4.
        assert_eq!(rdf.pairs, vec![1.0, 4.0, 4.0]);
        // O–O at 3.05 Å: bin 30, one pair.
        assert!(
            (count(&p[0], 30) - 1.0).abs() < 1e-9,
            "{}",
            count(&p[0], 30)
        );
        let oo: f64 = (0..50).map(|b| count(&p[0], b)).sum();
        assert!((oo - 1.0).abs() < 1e-9);
        // The intermolecular distances, by hand, binned.
        let lab = |i: usize, s: usize| pos[i] + q[i] * sites.offsets[s];
        let mut expected = [[0.0; 50]; 3];
        for u in 0..3 {
            for w in 0..3 {
                let r = (lab(0, u) - lab(1, w)).length();
                let t = match (u.min(1), w.min(1)) {
                    (0, 0) => 0,
                    (1, 1) => 2,
                    _ => 1,
                };
                expected[t][(r / 0.1) as usize] += 1.0;
            }
        }
        for (t, x) in p.iter().enumerate() {
            for (bin, &e) in expected[t].iter().enumerate() {
                let c = count(x, bin) * rdf.pairs[t];
                assert!(
                    (c - e).abs() < 1e-9,
                    "{}–{} bin {bin}: {c} vs {e}",
                    x.a,
                    x.b
                );
            }
        }
        // Intramolecular O–H (1 Å, bin 10) and H–H (1.633 Å, bin 16) are absent: the
        // nearest intermolecular O–H and H–H pairs lie beyond 1.7 Å.
        for x in &p[1..] {
            for bin in 0..17 {
                assert_eq!(x.rows[bin].1, 0.0, "{}–{} bin {bin}", x.a, x.b);
            }
        }
    }

    /// The minimum image of each site pair: two molecules across the box face count the same
    /// as side by side in the box.
    #[test]
    fn site_pairs_take_the_minimum_image() {
        let l = DVec3::splat(12.0);
        let q = [DQuat::from_rotation_x(0.3), DQuat::from_rotation_y(1.1)];
        let mut inside = SiteRdf::new(vec![water()], 30, 6.0);
        inside.accumulate(
            &[DVec3::splat(5.0), DVec3::new(7.5, 5.0, 5.0)],
            &[0, 0],
            &q,
            l,
        );
        let mut across = SiteRdf::new(vec![water()], 30, 6.0);
        across.accumulate(
            &[DVec3::new(9.7, 5.0, 5.0), DVec3::new(0.2, 5.0, 5.0)],
            &[0, 0],
            &q,
            l,
        );
        assert_eq!(inside.counts, across.counts);
        assert_eq!(inside.counts.iter().sum::<u64>(), 9);
    }

    /// An ideal gas of randomly placed and turned molecules: every g_ab is 1 within its
    /// noise at every r (intramolecular pairs left out of count and normalisation alike),
    /// with the cell list (a box of three cells of r_max and more) and without it (fewer).
    #[test]
    fn an_ideal_gas_of_molecules_gives_one() {
        for side in [11.0, 30.0] {
            let l = DVec3::splat(side);
            let n = (0.02 * side * side * side) as usize;
            let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
            let mut rdf = SiteRdf::new(vec![water()], 10, 4.0);
            for _ in 0..100 {
                let pos: Vec<DVec3> = (0..n)
                    .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) * l)
                    .collect();
                let q: Vec<DQuat> = (0..n)
                    .map(|_| {
                        let v: [f64; 4] = std::array::from_fn(|_| rng.random::<f64>() - 0.5);
                        DQuat::from_array(v).normalize()
                    })
                    .collect();
                rdf.accumulate(&pos, &vec![0; n], &q, l);
            }
            for x in rdf.partials() {
                for (bin, &(r, g)) in x.rows.iter().enumerate().skip(3) {
                    let e = x.errors[bin];
                    assert!(
                        (g - 1.0).abs() < 5.0 * e && e < 0.1,
                        "L = {side}: g_{}{}({r}) = {g} ± {e}",
                        x.a,
                        x.b
                    );
                }
            }
        }
    }
}
