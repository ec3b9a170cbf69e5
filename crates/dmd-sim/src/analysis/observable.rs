//! Observables sampled at fixed intervals of simulated time: radial distribution function (of
//! the centres), mean-square displacement, velocity autocorrelation, the long-axis
//! orientational autocorrelation of rods, pressure and energy time series.
//!
//! Sampling reads positions `r + v (t − t_i)` without touching the bodies (no invalidation):
//! asking for observables does not change the trajectory, and nothing here runs unless asked.

use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::analysis::block::{BlockEstimate, Blocks};
use crate::analysis::output::{CsvStream, OutputError};
use crate::analysis::pairs::{for_each_pair, pair_index, ratio, shell_volume, wrap};
use crate::analysis::site_rdf::{MoleculeSites, SiteRdf};
use crate::engine::simulation::{Sampler, View};

/// Radial distribution function `g(r)` of all pairs, and for bodies of two or more species
/// the partial `g_ab(r)` of every unordered pair of species `a ≤ b`.
///
/// Normalisation: `g(r)` counts pairs in a shell against the `N (N − 1) / 2` pairs of an
/// ideal gas at the same density; `g_aa(r)` against `N_a (N_a − 1) / 2` and `g_ab(r)` (`a ≠
/// b`) against `N_a N_b`, so every one tends to 1 at large `r` in an ideal mixture and
/// `g = Σ_a N_a (N_a − 1) g_aa / (N (N − 1)) + Σ_{a<b} 2 N_a N_b g_ab / (N (N − 1))` holds bin
/// by bin. Molecules with named sites also get the site–site g(r) in the same bins
/// ([`with_sites`](Self::with_sites), [`SiteRdf`]).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Rdf {
    every: u64,
    seen: u64,
    r_max: f64,
    width: f64,
    counts: Vec<u64>,
    samples: u64,
    n: usize,
    volume: f64,
    /// Bodies of each species (set at the first evaluation; empty before).
    members: Vec<u64>,
    /// Counts of every pair of species `a ≤ b` ([`pair_index`]), `bins` each; empty for one
    /// species.
    partial: Vec<u64>,
    /// Each bin's `g` of every evaluated configuration, blocked in sample order: the
    /// error of `g(r)` per bin.
    blocks: Vec<Blocks>,
    /// The same for every partial `g_ab` (laid out as `partial`; empty for one species).
    partial_blocks: Vec<Blocks>,
    /// The current configuration's counts (scratch, kept to save an allocation a sample).
    #[serde(skip)]
    scratch: Vec<u64>,
    /// The site–site g(r) of rigid molecules with named sites, in the same bins and at the
    /// same samples (`None` for bodies without them).
    sites: Option<SiteRdf>,
}

/// Index of the unordered pair of species `a ≤ b` among `kinds` species: `(0,0), (0,1), …,
/// (0,k−1), (1,1), …`.
/// The least-squares line `a + b t` through the second half of an MSD table's lags, as
/// `(a, b)`: the fit behind [`Correlations::diffusion_from_msd`] (`D = b / 6`) and the line the
/// MSD plot draws.
pub(crate) fn msd_fit(t: &[(f64, f64)]) -> Option<(f64, f64)> {
    let half = &t[t.len() / 2..];
    if half.len() < 2 {
        return None;
    }
    let n = half.len() as f64;
    let mx = half.iter().map(|p| p.0).sum::<f64>() / n;
    let my = half.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = half.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = half.iter().map(|p| (p.0 - mx).powi(2)).sum();
    (sxx > 0.0).then(|| {
        let b = sxy / sxx;
        (my - b * mx, b)
    })
}

impl Rdf {
    /// `bins` bins up to `r_max` (at most half the smallest box side), evaluated at every
    /// `every`-th sample.
    pub fn new(bins: usize, r_max: f64, every: u64) -> Self {
        Rdf {
            every: every.max(1),
            seen: 0,
            r_max,
            width: r_max / bins as f64,
            counts: vec![0; bins],
            samples: 0,
            n: 0,
            volume: 0.0,
            members: Vec::new(),
            partial: Vec::new(),
            partial_blocks: Vec::new(),
            blocks: vec![Blocks::default(); bins],
            scratch: Vec::new(),
            sites: None,
        }
    }

    /// The same g(r), and with it the site–site g(r) of molecules whose species (in the
    /// scene's order) have the named sites `species`: the samples then need the bodies'
    /// attitudes ([`needs_attitudes`](Self::needs_attitudes)).
    pub fn with_sites(mut self, species: Vec<MoleculeSites>) -> Self {
        self.sites = Some(SiteRdf::new(species, self.counts.len(), self.r_max));
        self
    }

    /// Whether the samples must carry the bodies' attitudes (for the site–site g(r)).
    pub fn needs_attitudes(&self) -> bool {
        self.sites.is_some()
    }

    /// The site–site g(r), if the bodies have named sites.
    pub fn sites(&self) -> Option<&SiteRdf> {
        self.sites.as_ref()
    }

    fn sample(&mut self, view: &View<'_>) {
        self.seen += 1;
        if !(self.seen - 1).is_multiple_of(self.every) {
            return;
        }
        let n = view.bodies.len();
        let pos: Vec<DVec3> = (0..n)
            .map(|i| wrap(view.position(i), view.lengths))
            .collect();
        let species: Vec<u32> = view.bodies.iter().map(|b| b.species).collect();
        if let Some(s) = &mut self.sites {
            // The driver asks for attitudes whenever `needs_attitudes` says so; a view without
            // them is a wiring bug, which debug builds (every test) stop at. A release build
            // leaves the site table without that sample rather than reading past the end.
            debug_assert_eq!(
                view.attitudes.len(),
                n,
                "the site-site g(r) is sampled from a view without attitudes"
            );
            if view.attitudes.len() == n {
                s.accumulate(&pos, &species, &view.attitudes, view.lengths);
            }
        }
        self.accumulate(&pos, &species, view.lengths);
    }

    /// Adds the pairs of one configuration: positions wrapped into the box `l`, and the
    /// species of each body.
    fn accumulate(&mut self, pos: &[DVec3], species: &[u32], l: DVec3) {
        let n = pos.len();
        let bins = self.counts.len();
        if self.members.is_empty() {
            let kinds = species.iter().map(|&s| s as usize + 1).max().unwrap_or(0);
            self.members = vec![0; kinds];
            for &s in species {
                self.members[s as usize] += 1;
            }
            if kinds >= 2 {
                self.partial = vec![0; kinds * (kinds + 1) / 2 * bins];
                self.partial_blocks = vec![Blocks::default(); kinds * (kinds + 1) / 2 * bins];
            }
        }
        let kinds = self.members.len();
        self.n = n;
        self.volume = l.x * l.y * l.z;
        self.samples += 1;
        let r2max = self.r_max * self.r_max;
        let inv_w = 1.0 / self.width;
        let mut counts = std::mem::take(&mut self.scratch);
        counts.clear();
        counts.resize(bins, 0);
        // This configuration's partial counts follow the total's in the same scratch vector.
        let per_pair = !self.partial.is_empty();
        if per_pair {
            counts.resize(bins + self.partial.len(), 0);
        }
        for_each_pair(pos, l, self.r_max, |i, j, d| {
            let r2 = d.length_squared();
            if r2 < r2max {
                let k = (r2.sqrt() * inv_w) as usize;
                if k < bins {
                    counts[k] += 1;
                    if per_pair {
                        let p = pair_index(species[i] as usize, species[j] as usize, kinds);
                        counts[bins + p * bins + k] += 1;
                    }
                }
            }
        });
        if per_pair {
            for a in 0..kinds {
                for b in a..kinds {
                    let p = pair_index(a, b, kinds);
                    let pairs = self.pairs_of(a, b);
                    for k in 0..bins {
                        let c = counts[bins + p * bins + k];
                        self.partial[p * bins + k] += c;
                        let ideal = pairs * self.shell_volume(k) / self.volume;
                        self.partial_blocks[p * bins + k].push(ratio(c, ideal));
                    }
                }
            }
            counts.truncate(bins);
        }
        // This configuration's g in every bin: `table` is their mean (same volume each time).
        let pairs = 0.5 * n as f64 * (n as f64 - 1.0);
        self.blocks.resize_with(bins, Blocks::default);
        for (k, &c) in counts.iter().enumerate() {
            self.counts[k] += c;
            let ideal = pairs * self.shell_volume(k) / self.volume;
            self.blocks[k].push(ratio(c, ideal));
        }
        self.scratch = counts;
    }

    /// Pairs of bodies of species `a` and `b`.
    fn pairs_of(&self, a: usize, b: usize) -> f64 {
        let (na, nb) = (self.members[a] as f64, self.members[b] as f64);
        if a == b {
            0.5 * na * (na - 1.0)
        } else {
            na * nb
        }
    }

    /// Volume of the shell of bin `k`.
    fn shell_volume(&self, k: usize) -> f64 {
        shell_volume(self.width, k)
    }

    /// The block-average error of `g(r)` in every bin (the rows of [`table`](Self::table)),
    /// from the `g` of each evaluated configuration in sample order; NaN with fewer than 16
    /// configurations.
    pub fn errors(&self) -> Vec<f64> {
        self.blocks.iter().map(|b| b.estimate().error).collect()
    }

    /// Volume of the shell of bin `k` times the samples taken.
    fn shell(&self, k: usize) -> (f64, f64) {
        let (a, b) = (k as f64 * self.width, (k + 1) as f64 * self.width);
        (
            0.5 * (a + b),
            self.shell_volume(k) * self.samples as f64 / self.volume,
        )
    }

    /// Rows `(r at bin centre, g(r))`.
    pub fn table(&self) -> Vec<(f64, f64)> {
        let n = self.n as f64;
        (0..self.counts.len())
            .map(|k| {
                let (r, shell) = self.shell(k);
                (r, ratio(self.counts[k], 0.5 * n * (n - 1.0) * shell))
            })
            .collect()
    }

    /// Bodies of each species in the sampled configurations (empty before the first).
    pub fn members(&self) -> &[u64] {
        &self.members
    }

    /// The partial `g_ab(r)` of every pair of species `a ≤ b`, in the order `(0,0), (0,1), …,
    /// (1,1), …`. Empty for one species.
    pub fn partials(&self) -> Vec<PartialRdf> {
        let kinds = self.members.len();
        if self.partial.is_empty() {
            return Vec::new();
        }
        let bins = self.counts.len();
        let mut out = Vec::new();
        for a in 0..kinds {
            for b in a..kinds {
                let pairs = self.pairs_of(a, b);
                let p = pair_index(a, b, kinds);
                let rows = (0..bins)
                    .map(|k| {
                        let (r, shell) = self.shell(k);
                        (r, ratio(self.partial[p * bins + k], pairs * shell))
                    })
                    .collect();
                let errors = (0..bins)
                    .map(|k| {
                        self.partial_blocks
                            .get(p * bins + k)
                            .map_or(f64::NAN, |b| b.estimate().error)
                    })
                    .collect();
                out.push(PartialRdf { a, b, rows, errors });
            }
        }
        out
    }
}

/// The partial radial distribution function of one pair of species ([`Rdf::partials`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PartialRdf {
    /// The first species (index in the scene's order).
    pub a: usize,
    /// The second species, `b ≥ a`.
    pub b: usize,
    /// Rows `(r at bin centre, g_ab(r))`.
    pub rows: Vec<(f64, f64)>,
    /// The block-average error of each row, as [`Rdf::errors`].
    pub errors: Vec<f64>,
}

/// One time origin of the correlations.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct Origin {
    sample: u64,
    r0: Vec<DVec3>,
    v0: Vec<DVec3>,
    s0: Vec<DVec3>,
    /// This origin's own `D` from the MSD and from the VACF, summed lag by lag with the
    /// weights of [`Correlations::diffusion_weights`].
    d_msd: f64,
    d_vacf: f64,
}

/// Mean-square displacement, velocity autocorrelation and (for rods) the long-axis
/// orientational autocorrelations `⟨s(0)·s(t)⟩` and `⟨P₂(s(0)·s(t))⟩` over sliding time
/// origins.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Correlations {
    dt: f64,
    lags: usize,
    origin_every: u64,
    samples: u64,
    origins: Vec<Origin>,
    msd: Vec<f64>,
    vacf: Vec<f64>,
    oacf1: Vec<f64>,
    oacf2: Vec<f64>,
    counts: Vec<u64>,
    want_msd: bool,
    want_vacf: bool,
    want_oacf: bool,
    /// The value of every origin at each lag, blocked in origin order (MSD, VACF, and the two
    /// orientational correlations; empty when not asked for): the errors of the tables.
    msd_blocks: Vec<Blocks>,
    vacf_blocks: Vec<Blocks>,
    oacf1_blocks: Vec<Blocks>,
    oacf2_blocks: Vec<Blocks>,
    /// Each origin's own `D` from the MSD and from the VACF, pushed when its last lag is
    /// sampled, blocked in origin order.
    d_msd_blocks: Blocks,
    d_vacf_blocks: Blocks,
}

/// The diffusion coefficients of a run ([`Correlations::diffusions`]), each with its
/// block-average error (length²/time).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diffusions {
    /// From the slope of the MSD.
    pub msd: Option<f64>,
    /// The error of `msd`.
    pub msd_error: Option<f64>,
    /// From the Green–Kubo integral of the VACF.
    pub vacf: Option<f64>,
    /// The error of `vacf`.
    pub vacf_error: Option<f64>,
    /// The summary keys of those errors whose blocking found no plateau (lower bounds).
    pub without_plateau: Vec<&'static str>,
}

impl Correlations {
    /// Lags `0, dt, …` up to `max_lag`; a new time origin every `max_lag / 10` (at least every
    /// sample).
    pub fn new(dt: f64, max_lag: f64, want_msd: bool, want_vacf: bool) -> Self {
        Self::with_orientations(dt, max_lag, want_msd, want_vacf, false)
    }

    /// As [`new`](Self::new), and the orientational autocorrelation of rods if `want_oacf`.
    pub fn with_orientations(
        dt: f64,
        max_lag: f64,
        want_msd: bool,
        want_vacf: bool,
        want_oacf: bool,
    ) -> Self {
        let lags = (max_lag / dt).round().max(1.0) as usize + 1;
        let origin_every = ((lags - 1) / 10).max(1) as u64;
        Correlations {
            dt,
            lags,
            origin_every,
            samples: 0,
            origins: Vec::new(),
            msd: vec![0.0; lags],
            vacf: vec![0.0; lags],
            oacf1: vec![0.0; lags],
            oacf2: vec![0.0; lags],
            counts: vec![0; lags],
            want_msd,
            want_vacf,
            want_oacf,
            msd_blocks: vec![Blocks::default(); if want_msd { lags } else { 0 }],
            vacf_blocks: vec![Blocks::default(); if want_vacf { lags } else { 0 }],
            oacf1_blocks: vec![Blocks::default(); if want_oacf { lags } else { 0 }],
            oacf2_blocks: vec![Blocks::default(); if want_oacf { lags } else { 0 }],
            d_msd_blocks: Blocks::default(),
            d_vacf_blocks: Blocks::default(),
        }
    }

    /// The weights `w_k` with which `D = Σ_k w_k c(k·dt)` of a full table, `c` the MSD or the
    /// VACF: the least-squares slope over the second half of the lags over 6 (as
    /// [`msd_fit`]), and the trapezoids of the Green–Kubo integral over 3. Zero weights where
    /// a table is too short for its estimate.
    fn diffusion_weights(&self, k: usize) -> (f64, f64) {
        let lags = self.lags;
        let from = lags / 2;
        let m = (lags - from) as f64;
        let msd = if m >= 2.0 && k >= from {
            // Lags `from..lags`: mean `t̄`, `Sxx = Σ (t − t̄)²` in closed form.
            let mean = 0.5 * (from + lags - 1) as f64;
            let sxx = m * (m * m - 1.0) / 12.0;
            (k as f64 - mean) / sxx / self.dt / 6.0
        } else {
            0.0
        };
        let vacf = if lags >= 2 {
            let end = k == 0 || k == lags - 1;
            (if end { 0.5 } else { 1.0 }) * self.dt / 3.0
        } else {
            0.0
        };
        (msd, vacf)
    }

    fn sample(&mut self, view: &View<'_>) {
        let n = view.bodies.len();
        let k = self.samples;
        self.samples += 1;
        if k.is_multiple_of(self.origin_every) {
            self.origins.push(Origin {
                sample: k,
                r0: (0..n).map(|i| view.unwrapped(i)).collect(),
                v0: view.bodies.iter().map(|b| b.v).collect(),
                s0: if self.want_oacf {
                    view.axes.clone()
                } else {
                    Vec::new()
                },
                d_msd: 0.0,
                d_vacf: 0.0,
            });
        }
        let lags = self.lags as u64;
        self.origins.retain(|o| k - o.sample < lags);
        let now: Vec<DVec3> = (0..n).map(|i| view.unwrapped(i)).collect();
        let mut origins = std::mem::take(&mut self.origins);
        for o in &mut origins {
            let lag = (k - o.sample) as usize;
            let (mut m, mut c) = (0.0, 0.0);
            for (i, b) in view.bodies.iter().enumerate() {
                m += (now[i] - o.r0[i]).length_squared();
                c += b.v.dot(o.v0[i]);
            }
            let (m, c) = (m / n as f64, c / n as f64);
            self.msd[lag] += m;
            self.vacf[lag] += c;
            let (w_msd, w_vacf) = self.diffusion_weights(lag);
            o.d_msd += w_msd * m;
            o.d_vacf += w_vacf * c;
            if self.want_msd {
                self.msd_blocks[lag].push(m);
            }
            if self.want_vacf {
                self.vacf_blocks[lag].push(c);
            }
            if lag + 1 == self.lags {
                // Why per origin: each origin's D is its own table's linear functional, so the
                // pooled D is (nearly) their mean, and blocking them in origin order absorbs
                // the overlap of consecutive origins' windows.
                self.d_msd_blocks.push(o.d_msd);
                self.d_vacf_blocks.push(o.d_vacf);
            }
            if self.want_oacf && o.s0.len() == view.axes.len() && !o.s0.is_empty() {
                let (mut c1, mut c2) = (0.0, 0.0);
                for (a, b) in o.s0.iter().zip(&view.axes) {
                    let x = a.dot(*b);
                    c1 += x;
                    c2 += 1.5 * x * x - 0.5;
                }
                let k = o.s0.len() as f64;
                self.oacf1[lag] += c1 / k;
                self.oacf2[lag] += c2 / k;
                self.oacf1_blocks[lag].push(c1 / k);
                self.oacf2_blocks[lag].push(c2 / k);
            }
            self.counts[lag] += 1;
        }
        self.origins = origins;
    }

    /// The block-average errors of the rows of `table` from `blocks` (NaN for a lag with fewer
    /// than 16 origins).
    fn errors_of(&self, blocks: &[Blocks]) -> Vec<f64> {
        (0..self.lags)
            .filter(|&k| self.counts[k] > 0)
            .map(|k| blocks.get(k).map_or(f64::NAN, |b| b.estimate().error))
            .collect()
    }

    /// The error of each row of [`msd_table`](Self::msd_table): block averages over the time
    /// origins, in their order.
    pub fn msd_errors(&self) -> Vec<f64> {
        self.errors_of(&self.msd_blocks)
    }

    /// The error of each row of [`vacf_table`](Self::vacf_table), as [`msd_errors`](Self::msd_errors).
    pub fn vacf_errors(&self) -> Vec<f64> {
        self.errors_of(&self.vacf_blocks)
    }

    /// The errors of each row of [`oacf_table`](Self::oacf_table), as
    /// [`msd_errors`](Self::msd_errors): `(⟨s(0)·s(t)⟩, ⟨P₂⟩)`.
    pub fn oacf_errors(&self) -> Vec<(f64, f64)> {
        self.errors_of(&self.oacf1_blocks)
            .into_iter()
            .zip(self.errors_of(&self.oacf2_blocks))
            .collect()
    }

    /// `D` from the MSD of every time origin that has reached the last lag, with its
    /// block-average error over those origins in their order (NaN with fewer than 16).
    pub fn diffusion_from_msd_blocks(&self) -> BlockEstimate {
        self.d_msd_blocks.estimate()
    }

    /// `D` from the VACF of every time origin that has reached the last lag, as
    /// [`diffusion_from_msd_blocks`](Self::diffusion_from_msd_blocks).
    pub fn diffusion_from_vacf_blocks(&self) -> BlockEstimate {
        self.d_vacf_blocks.estimate()
    }

    /// The error of [`diffusion_from_msd`](Self::diffusion_from_msd) (see
    /// [`diffusion_from_msd_blocks`](Self::diffusion_from_msd_blocks)); `None` unless finite.
    pub fn diffusion_from_msd_error(&self) -> Option<f64> {
        Some(self.d_msd_blocks.estimate().error).filter(|e| e.is_finite())
    }

    /// The error of [`diffusion_from_vacf`](Self::diffusion_from_vacf); `None` unless finite.
    pub fn diffusion_from_vacf_error(&self) -> Option<f64> {
        Some(self.d_vacf_blocks.estimate().error).filter(|e| e.is_finite())
    }

    /// Rows `(lag, MSD)` of the lags with data.
    pub fn msd_table(&self) -> Vec<(f64, f64)> {
        self.table(&self.msd)
    }

    /// Rows `(lag, ⟨v(0)·v(t)⟩)` of the lags with data.
    pub fn vacf_table(&self) -> Vec<(f64, f64)> {
        self.table(&self.vacf)
    }

    /// Rows `(lag, ⟨s(0)·s(t)⟩, ⟨P₂(s(0)·s(t))⟩)` of the lags with data (rods).
    pub fn oacf_table(&self) -> Vec<(f64, f64, f64)> {
        (0..self.lags)
            .filter(|&k| self.counts[k] > 0)
            .map(|k| {
                let c = self.counts[k] as f64;
                (k as f64 * self.dt, self.oacf1[k] / c, self.oacf2[k] / c)
            })
            .collect()
    }

    /// Whether the orientational autocorrelation was asked for.
    pub fn wants_oacf(&self) -> bool {
        self.want_oacf
    }

    fn table(&self, acc: &[f64]) -> Vec<(f64, f64)> {
        (0..self.lags)
            .filter(|&k| self.counts[k] > 0)
            .map(|k| (k as f64 * self.dt, acc[k] / self.counts[k] as f64))
            .collect()
    }

    /// Whether the MSD was asked for.
    pub fn wants_msd(&self) -> bool {
        self.want_msd
    }

    /// Whether the VACF was asked for.
    pub fn wants_vacf(&self) -> bool {
        self.want_vacf
    }

    /// The diffusion coefficients a run reports and their errors: those of the correlations
    /// asked for, none without correlations.
    pub fn diffusions(correlations: Option<&Self>) -> Diffusions {
        let msd = correlations.filter(|c| c.wants_msd());
        let vacf = correlations.filter(|c| c.wants_vacf());
        let mut without_plateau = Vec::new();
        if msd.is_some_and(|c| !c.d_msd_blocks.estimate().converged) {
            without_plateau.push("diffusion_msd_error");
        }
        if vacf.is_some_and(|c| !c.d_vacf_blocks.estimate().converged) {
            without_plateau.push("diffusion_vacf_error");
        }
        Diffusions {
            msd: msd.and_then(Self::diffusion_from_msd),
            msd_error: msd.and_then(Self::diffusion_from_msd_error),
            vacf: vacf.and_then(Self::diffusion_from_vacf),
            vacf_error: vacf.and_then(Self::diffusion_from_vacf_error),
            without_plateau,
        }
    }

    /// Self-diffusion coefficient from the slope of the MSD over the second half of the lags
    /// (least squares), `D = slope / 6`.
    pub fn diffusion_from_msd(&self) -> Option<f64> {
        msd_fit(&self.msd_table()).map(|(_, slope)| slope / 6.0)
    }

    /// Self-diffusion coefficient from the Green–Kubo integral of the VACF (trapezoids),
    /// `D = ⅓ ∫ ⟨v(0)·v(t)⟩ dt`.
    pub fn diffusion_from_vacf(&self) -> Option<f64> {
        let t = self.vacf_table();
        if t.len() < 2 {
            return None;
        }
        let integral: f64 = t
            .windows(2)
            .map(|w| 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0))
            .sum();
        Some(integral / 3.0)
    }
}

/// One row of the pressure and energy time series.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SeriesRow {
    /// Simulated time since the start of production.
    pub time: f64,
    /// Kinetic energy.
    pub kinetic: f64,
    /// Potential energy.
    pub potential: f64,
    /// Total energy.
    pub total: f64,
    /// Instantaneous kinetic temperature.
    pub temperature: f64,
    /// Pressure averaged over the interval since the previous sample.
    pub pressure: f64,
}

/// The columns of `series.csv`.
pub const SERIES_HEADER: [&str; 6] = [
    "t",
    "kinetic",
    "potential",
    "total",
    "temperature",
    "pressure",
];

/// How the rows of `series.csv` are written from internal units: energies and temperatures
/// divided by their units, the pressure times its factor (`None`: unchanged), as the scene's
/// unit system converts them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeriesUnits {
    /// The energy unit (internal energy per scene unit).
    pub energy: f64,
    /// The temperature unit (internal kT per scene unit).
    pub temperature: f64,
    /// The factor from internal pressure to the reported unit.
    pub pressure: Option<f64>,
}

/// What a checkpoint keeps of a [`Series`]: its rows are in the file, of which it records the
/// length.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SeriesState {
    /// Rows written.
    pub rows: u64,
    /// Time, virial and kinetic-energy integral at the previous sample.
    pub last: Option<(f64, f64, f64)>,
    /// Bytes of `series.csv` (its temporary file) at the checkpoint.
    pub bytes: u64,
}

/// Pressure and energy time series: a row at every sample but the first (at the start of
/// production), which only opens the first interval of the pressure. The rows go to
/// `series.csv` as they are made ([`CsvStream`]): memory does not grow with the run.
#[derive(Debug, Default)]
pub struct Series {
    rows: u64,
    last: Option<(f64, f64, f64)>,
    file: Option<(CsvStream, SeriesUnits)>,
    /// A run without an output folder (the Python API's): the rows, held for its tables.
    held: Option<(Vec<Vec<f64>>, SeriesUnits)>,
}

impl Series {
    /// A series written to `path` (`series.csv`) in `units`.
    ///
    /// # Errors
    /// [`OutputError`] if the file cannot be created.
    pub fn streamed(path: &Path, units: SeriesUnits) -> Result<Self, OutputError> {
        Ok(Series {
            rows: 0,
            last: None,
            file: Some((CsvStream::create(path, &SERIES_HEADER)?, units)),
            held: None,
        })
    }

    /// A series of a run without an output folder, its rows held in memory (bounded by
    /// `output.max_bytes` as a file would be) so that [`table`](Self::table) can give them.
    pub fn held(units: SeriesUnits) -> Self {
        Series {
            held: Some((Vec::new(), units)),
            ..Series::default()
        }
    }

    /// Every row so far, as `series.csv` holds them (held, or flushed and read back from the
    /// file; empty for a resumed run without a folder, whose earlier rows are not kept).
    ///
    /// # Errors
    /// [`OutputError`] if the file cannot be flushed or read.
    pub fn table(&mut self) -> Result<Vec<Vec<f64>>, OutputError> {
        if let Some((rows, _)) = &self.held {
            return Ok(rows.clone());
        }
        let Some((f, _)) = &mut self.file else {
            return Ok(Vec::new());
        };
        f.mark()?;
        crate::analysis::output::read_csv_rows(f.temporary_path())
    }

    /// The series of a resumed run, continuing `path` where `state` left it (`path: None`:
    /// rows counted only).
    ///
    /// # Errors
    /// [`OutputError`] if the file is missing or shorter than the checkpoint recorded.
    pub fn resumed(
        path: Option<&Path>,
        units: SeriesUnits,
        state: &SeriesState,
    ) -> Result<Self, OutputError> {
        Ok(Series {
            rows: state.rows,
            last: state.last,
            file: match path {
                Some(p) => Some((CsvStream::reopen(p, state.bytes)?, units)),
                None => None,
            },
            held: None,
        })
    }

    /// Flushes the file and gives what a checkpoint keeps.
    ///
    /// # Errors
    /// [`OutputError`] if the file cannot be written.
    pub fn mark(&mut self) -> Result<SeriesState, OutputError> {
        let bytes = match &mut self.file {
            Some((f, _)) => f.mark()?,
            None => 0,
        };
        Ok(SeriesState {
            rows: self.rows,
            last: self.last,
            bytes,
        })
    }

    /// Closes `series.csv` under its name and gives its path (`None` without a file).
    ///
    /// # Errors
    /// [`OutputError`] if the file cannot be written.
    pub fn finish(self) -> Result<Option<PathBuf>, OutputError> {
        self.file.map(|(f, _)| f.finish()).transpose()
    }

    fn sample(&mut self, view: &View<'_>) {
        let n = view.bodies.len() as f64;
        let l = view.lengths;
        let volume = l.x * l.y * l.z;
        // The first sample (and one at the same time as the previous) has no interval yet.
        let last = self
            .last
            .replace((view.elapsed, view.virial, view.kinetic_integral));
        let Some((t, w, kint)) = last.filter(|&(t, _, _)| view.elapsed > t) else {
            return;
        };
        let dt = view.elapsed - t;
        let kt = 2.0 * (view.kinetic_integral - kint) / dt / view.dof;
        let pressure = (n * kt + (view.virial - w) / (3.0 * dt)) / volume;
        self.rows += 1;
        let row = |u: &SeriesUnits| {
            let e = |x: f64| x / u.energy;
            [
                view.elapsed,
                e(view.kinetic),
                e(view.potential),
                e(view.kinetic + view.potential),
                2.0 * view.kinetic / view.dof / u.temperature,
                u.pressure.map_or(pressure, |k| pressure * k),
            ]
        };
        if let Some((f, u)) = &mut self.file {
            f.write_row(&row(u));
        }
        if let Some((rows, u)) = &mut self.held {
            rows.push(row(u).to_vec());
        }
    }

    /// The rows written.
    pub fn rows(&self) -> u64 {
        self.rows
    }
}

/// The observables a scene asked for.
#[derive(Debug, Default)]
pub struct Observers {
    /// Radial distribution function.
    pub rdf: Option<Rdf>,
    /// MSD and VACF.
    pub correlations: Option<Correlations>,
    /// Pressure and energy series.
    pub series: Option<Series>,
    /// Trajectory frames (written by the output module), frame stream 0.
    pub trajectory: Option<crate::analysis::output::Trajectory>,
    /// GSD trajectory frames, frame stream 1.
    pub gsd: Option<crate::analysis::output::GsdTrajectory>,
    /// The online accumulators of the per-sample quantities behind the summary's error bars.
    pub samples: Option<crate::analysis::smooth::Samples>,
    /// The smooth potential (terraced rods and Gay–Berne), evaluated at every
    /// `smooth_every`-th sample.
    pub smooth: Option<Box<dyn crate::analysis::smooth::Evaluate>>,
    /// Samples between evaluations of the smooth potential (`output.smooth_every`; 0 counts
    /// as 1). The count is the sample's index in `samples`, which checkpoints keep, so a
    /// resumed run evaluates at the same samples.
    pub smooth_every: u64,
    /// `output.max_bytes`: the most the series and the trajectory may take, checked as they
    /// grow ([`Sampler::over_budget`]); the estimates are those of
    /// the scene's output checks (`limits::check_outputs`), so a run that passed that check never reaches it.
    pub max_bytes: Option<u64>,
    /// Estimated bytes of one trajectory frame (set at the first frame).
    frame_bytes: f64,
    /// Estimated bytes of one GSD frame (set at the first frame).
    gsd_frame_bytes: f64,
}

impl Sampler for Observers {
    fn sample(&mut self, view: &View<'_>) {
        if let Some(r) = &mut self.rdf {
            r.sample(view);
        }
        if let Some(c) = &mut self.correlations {
            c.sample(view);
        }
        if let Some(s) = &mut self.series {
            s.sample(view);
        }
        if let Some(s) = &mut self.samples {
            let due = s.count().is_multiple_of(self.smooth_every.max(1));
            let smooth = self
                .smooth
                .as_ref()
                .filter(|_| due)
                .map(|e| e.evaluate(view));
            s.sample(view, smooth);
        }
    }

    fn frame(&mut self, stream: usize, view: &View<'_>) {
        use crate::analysis::output::{GSD_FRAME_BYTES, GSD_PARTICLE_BYTES, trajectory_line_bytes};
        // Semi-flexible molecules are written as their atoms.
        let atoms = !view.atoms.is_empty();
        let particles = if atoms {
            view.atoms.iter().map(|(q, _)| q.len()).sum()
        } else {
            view.bodies.len()
        } as f64;
        match stream {
            0 => {
                if let Some(t) = &mut self.trajectory {
                    t.write_frame(view);
                    let oriented = !view.attitudes.is_empty();
                    self.frame_bytes = particles * trajectory_line_bytes(oriented, atoms) + 200.0;
                }
            }
            _ => {
                if let Some(g) = &mut self.gsd {
                    g.write_frame(view);
                    self.gsd_frame_bytes = particles * GSD_PARTICLE_BYTES + GSD_FRAME_BYTES;
                }
            }
        }
    }

    fn over_budget(&self) -> Option<String> {
        use crate::analysis::output::{SERIES_ROW_BYTES, short};
        let max = self.max_bytes? as f64;
        let rows = self.series.as_ref().map_or(0, |s| s.rows) as f64;
        if rows * SERIES_ROW_BYTES > max {
            return Some(format!(
                "output.series: series.csv has reached {} rows (about {} bytes), the limit \
                 output.max_bytes = {}: lengthen output.sample_interval, or raise \
                 output.max_bytes",
                short(rows),
                short(rows * SERIES_ROW_BYTES),
                short(max)
            ));
        }
        let frames = self.trajectory.as_ref().map_or(0, |t| t.frames()) as f64;
        if frames * self.frame_bytes > max {
            return Some(format!(
                "output.trajectory: trajectory.xyz has reached {} frames (about {} bytes), \
                 the limit output.max_bytes = {}: lengthen output.trajectory.interval, or \
                 raise output.max_bytes",
                short(frames),
                short(frames * self.frame_bytes),
                short(max)
            ));
        }
        let frames = self.gsd.as_ref().map_or(0, |g| g.frames()) as f64;
        if frames * self.gsd_frame_bytes > max {
            return Some(format!(
                "output.gsd: trajectory.gsd has reached {} frames (about {} bytes), the limit \
                 output.max_bytes = {}: lengthen output.gsd.interval, or raise \
                 output.max_bytes",
                short(frames),
                short(frames * self.gsd_frame_bytes),
                short(max)
            ));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn pair_indices_cover_every_pair_of_species_once() {
        for kinds in 1..6 {
            let mut seen = vec![0; kinds * (kinds + 1) / 2];
            for a in 0..kinds {
                for b in a..kinds {
                    seen[pair_index(a, b, kinds)] += 1;
                    assert_eq!(pair_index(a, b, kinds), pair_index(b, a, kinds));
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "{kinds} species: {seen:?}");
        }
    }

    /// An ideal mixture (uniform random positions) of three species in unequal numbers: every
    /// partial g tends to 1, and their pair-weighted sum is the total g in every bin.
    #[test]
    fn partials_of_an_ideal_mixture_are_one_and_sum_to_the_total() {
        let l = DVec3::new(10.0, 10.0, 12.0);
        let species: Vec<u32> = (0..300).map(|i| [0, 0, 0, 1, 1, 2][i % 6]).collect();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let mut rdf = Rdf::new(10, 5.0, 1);
        for _ in 0..200 {
            let pos: Vec<DVec3> = species
                .iter()
                .map(|_| {
                    DVec3::new(
                        rng.random::<f64>() * l.x,
                        rng.random::<f64>() * l.y,
                        rng.random::<f64>() * l.z,
                    )
                })
                .collect();
            rdf.accumulate(&pos, &species, l);
        }
        assert_eq!(rdf.members(), &[150, 100, 50]);
        let total = rdf.table();
        let partials = rdf.partials();
        assert_eq!(partials.len(), 6);
        let n = 300.0f64;
        // The 200 configurations are independent: each partial's error is its scatter.
        let (mut chi2, mut dof) = (0.0, 0);
        for (k, &(r, g)) in total.iter().enumerate() {
            let mut sum = 0.0;
            for PartialRdf { a, b, rows, .. } in &partials {
                let (na, nb) = (rdf.members()[*a] as f64, rdf.members()[*b] as f64);
                let pairs = if a == b {
                    na * (na - 1.0)
                } else {
                    2.0 * na * nb
                };
                let w = pairs / (n * (n - 1.0));
                sum += w * rows[k].1;
                // Beyond the first bins (few pairs), each partial is 1 within its noise.
                if r > 1.5 {
                    assert!(
                        (rows[k].1 - 1.0).abs() < 0.05,
                        "g_{a}{b}({r}) = {}",
                        rows[k].1
                    );
                }
            }
            assert!(
                (sum - g).abs() < 1e-12 * g.max(1.0),
                "bin {k}: {sum} vs {g}"
            );
            if r > 1.5 {
                for p in &partials {
                    let z = (p.rows[k].1 - 1.0) / p.errors[k];
                    chi2 += z * z;
                    dof += 1;
                }
            }
            if r > 1.5 {
                assert!((g - 1.0).abs() < 0.02, "g({r}) = {g}");
            }
        }
        let reduced = chi2 / dof as f64;
        assert!(
            (0.6..1.6).contains(&reduced),
            "χ²/dof of the partials {reduced}"
        );
    }

    #[test]
    fn one_species_has_no_partials() {
        let l = DVec3::splat(6.0);
        let pos: Vec<DVec3> = (0..27)
            .map(|i| DVec3::new((i % 3) as f64, ((i / 3) % 3) as f64, (i / 9) as f64) * 2.0)
            .collect();
        let mut rdf = Rdf::new(10, 3.0, 1);
        rdf.accumulate(&pos, &[0; 27], l);
        assert!(rdf.partials().is_empty());
        // The simple cubic lattice of spacing 2: six neighbours at r = 2 (bin 6 of width 0.3).
        let t = rdf.table();
        let shell = 4.0 / 3.0 * std::f64::consts::PI * (2.1f64.powi(3) - 1.8f64.powi(3));
        let expected = 27.0 * 6.0 / 2.0 / (0.5 * 27.0 * 26.0 * shell / 216.0);
        assert!((t[6].1 - expected).abs() < 1e-9 * expected, "{:?}", t[6]);
    }
}
