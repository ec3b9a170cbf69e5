//! Observables along a run, the same ones the event-driven engine reports so that the two can
//! be compared like with like (003 Figs. 3–5): the centre-of-mass radial distribution
//! function, the mean-square displacement, the normalised centre-of-mass velocity
//! autocorrelation, the normalised orientational autocorrelation of the long axis
//! `⟨s(0)·s(t)⟩` (and its second Legendre moment), and the energy, temperature and pressure
//! series. All are sampled at the integrator's sampling interval and written as CSV with
//! headers.

use std::path::Path;

use glam::DVec3;

use crate::integrator::{Observer, Snapshot};
use crate::output::write_csv;
use crate::{SmdError, System};

/// Centre-of-mass radial distribution function `g(r)` of all pairs (minimum image).
#[derive(Clone, Debug)]
pub struct Rdf {
    every: u64,
    seen: u64,
    r_max: f64,
    width: f64,
    counts: Vec<u64>,
    samples: u64,
    n: usize,
    volume: f64,
    scratch: Vec<DVec3>,
}

impl Rdf {
    /// `bins` bins up to `r_max` (at most half the shortest box edge: the caller checks),
    /// histogrammed at every `every`-th sample.
    ///
    /// # Errors
    /// [`SmdError::Count`] for zero bins or `every = 0`, [`SmdError::Parameter`] for a bad
    /// `r_max`.
    pub fn new(bins: usize, r_max: f64, every: u64) -> Result<Self, SmdError> {
        if bins == 0 {
            return Err(SmdError::Count {
                name: "rdf bins",
                value: 0,
                why: "at least 1",
            });
        }
        if every == 0 {
            return Err(SmdError::Count {
                name: "rdf every",
                value: 0,
                why: "at least 1",
            });
        }
        let r_max = crate::error::positive("rdf r_max", r_max)?;
        Ok(Self {
            every,
            seen: 0,
            r_max,
            width: r_max / bins as f64,
            counts: vec![0; bins],
            samples: 0,
            n: 0,
            volume: 0.0,
            scratch: Vec::new(),
        })
    }

    /// Histograms the pair distances of one state.
    pub fn add(&mut self, system: &System) {
        self.seen += 1;
        if !(self.seen - 1).is_multiple_of(self.every) {
            return;
        }
        let l = system.lengths();
        self.n = system.n();
        self.volume = system.volume();
        self.samples += 1;
        // Positions in [0, L) (they may be half a skin outside between list builds).
        self.scratch.clear();
        self.scratch
            .extend(system.positions().iter().map(|p| wrap_into(*p, l)));
        let pos = &self.scratch;
        let r2max = self.r_max * self.r_max;
        let inv_w = 1.0 / self.width;
        let counts = &mut self.counts;
        let mut add = |d: DVec3| {
            let r2 = d.length_squared();
            if r2 < r2max {
                let k = (r2.sqrt() * inv_w) as usize;
                if let Some(c) = counts.get_mut(k) {
                    *c += 1;
                }
            }
        };
        // Cells at least r_max wide when three fit along every axis, else all pairs.
        let dims: [usize; 3] = std::array::from_fn(|a| (l[a] / self.r_max).floor() as usize);
        if dims.iter().all(|&d| d >= 3) {
            let n_cells = dims[0] * dims[1] * dims[2];
            let cell_of = |p: DVec3| -> [usize; 3] {
                std::array::from_fn(|a| {
                    (((p[a] / l[a]) * dims[a] as f64) as usize).min(dims[a] - 1)
                })
            };
            let lin = |c: [usize; 3]| c[0] + dims[0] * (c[1] + dims[1] * c[2]);
            let mut head = vec![usize::MAX; n_cells];
            let mut next = vec![usize::MAX; pos.len()];
            for (i, p) in pos.iter().enumerate() {
                let c = lin(cell_of(*p));
                next[i] = head[c];
                head[c] = i;
            }
            for (i, p) in pos.iter().enumerate() {
                let c = cell_of(*p);
                for dz in [dims[2] - 1, 0, 1] {
                    for dy in [dims[1] - 1, 0, 1] {
                        for dx in [dims[0] - 1, 0, 1] {
                            let nc = [
                                (c[0] + dx) % dims[0],
                                (c[1] + dy) % dims[1],
                                (c[2] + dz) % dims[2],
                            ];
                            let mut j = head[lin(nc)];
                            while j != usize::MAX {
                                if j > i {
                                    add(min_image(*p - pos[j], l));
                                }
                                j = next[j];
                            }
                        }
                    }
                }
            }
        } else {
            for i in 0..pos.len() {
                for j in i + 1..pos.len() {
                    add(min_image(pos[i] - pos[j], l));
                }
            }
        }
    }

    /// Rows `(r at the bin centre, g(r))`, normalised by the ideal-gas count of `N − 1`
    /// partners in the box.
    pub fn table(&self) -> Vec<(f64, f64)> {
        let n = self.n as f64;
        let rho = (n - 1.0) / self.volume;
        self.counts
            .iter()
            .enumerate()
            .map(|(k, &c)| {
                let (a, b) = (k as f64 * self.width, (k + 1) as f64 * self.width);
                let shell = 4.0 / 3.0 * std::f64::consts::PI * (b * b * b - a * a * a);
                let ideal = 0.5 * n * rho * shell * self.samples as f64;
                (
                    0.5 * (a + b),
                    if ideal > 0.0 { c as f64 / ideal } else { 0.0 },
                )
            })
            .collect()
    }

    /// States histogrammed so far.
    pub fn samples(&self) -> u64 {
        self.samples
    }
}

fn wrap_into(p: DVec3, l: DVec3) -> DVec3 {
    let mut q = p;
    for a in 0..3 {
        q[a] = p[a].rem_euclid(l[a]);
        if q[a] >= l[a] {
            q[a] = 0.0;
        }
    }
    q
}

fn min_image(mut d: DVec3, l: DVec3) -> DVec3 {
    for a in 0..3 {
        if d[a] > 0.5 * l[a] {
            d[a] -= l[a];
        } else if d[a] < -0.5 * l[a] {
            d[a] += l[a];
        }
    }
    d
}

/// One time origin of the correlations.
#[derive(Clone, Debug)]
struct Origin {
    sample: u64,
    r0: Vec<DVec3>,
    v0: Vec<DVec3>,
    s0: Vec<DVec3>,
}

/// Time correlations over sliding time origins: mean-square displacement of the centres,
/// centre-of-mass velocity autocorrelation `⟨v(0)·v(t)⟩`, and the orientational
/// autocorrelations `⟨s(0)·s(t)⟩` (P₁) and `⟨P₂(s(0)·s(t))⟩` of the long axis.
#[derive(Clone, Debug)]
pub struct Correlations {
    dt: f64,
    lags: usize,
    origin_every: u64,
    samples: u64,
    origins: Vec<Origin>,
    msd: Vec<f64>,
    vacf: Vec<f64>,
    p1: Vec<f64>,
    p2: Vec<f64>,
    counts: Vec<u64>,
}

impl Correlations {
    /// Lags `0, dt, 2dt, …, lags·dt` where `dt` is the time between samples; a new time origin
    /// every `origin_every` samples.
    ///
    /// # Errors
    /// [`SmdError::Parameter`] for a bad `dt`, [`SmdError::Count`] for zero lags or
    /// `origin_every = 0`.
    pub fn new(dt: f64, lags: usize, origin_every: u64) -> Result<Self, SmdError> {
        let dt = crate::error::positive("correlation sample interval", dt)?;
        if lags == 0 || origin_every == 0 {
            return Err(SmdError::Count {
                name: if lags == 0 {
                    "correlation lags"
                } else {
                    "origin_every"
                },
                value: 0,
                why: "at least 1",
            });
        }
        let k = lags + 1;
        Ok(Self {
            dt,
            lags: k,
            origin_every,
            samples: 0,
            origins: Vec::new(),
            msd: vec![0.0; k],
            vacf: vec![0.0; k],
            p1: vec![0.0; k],
            p2: vec![0.0; k],
            counts: vec![0; k],
        })
    }

    /// Adds one sample (samples must be `dt` apart).
    pub fn add(&mut self, system: &System) {
        let n = system.n();
        let k = self.samples;
        self.samples += 1;
        let lags = self.lags as u64;
        if k.is_multiple_of(self.origin_every) {
            // Recycle the buffers of an origin that has run out of lags.
            let mut o = match self.origins.iter().position(|o| k - o.sample >= lags) {
                Some(idx) => self.origins.swap_remove(idx),
                None => Origin {
                    sample: 0,
                    r0: Vec::with_capacity(n),
                    v0: Vec::with_capacity(n),
                    s0: Vec::with_capacity(n),
                },
            };
            o.sample = k;
            o.r0.clear();
            o.r0.extend((0..n).map(|i| system.unwrapped(i)));
            o.v0.clear();
            o.v0.extend_from_slice(system.velocities());
            o.s0.clear();
            o.s0.extend_from_slice(system.axes());
            self.origins.push(o);
        }
        self.origins.retain(|o| k - o.sample < lags);
        let inv_n = 1.0 / n as f64;
        let v = system.velocities();
        let s = system.axes();
        for o in &self.origins {
            let lag = (k - o.sample) as usize;
            let (mut m, mut c) = (0.0, 0.0);
            for (i, (r0, v0)) in o.r0.iter().zip(&o.v0).enumerate() {
                m += (system.unwrapped(i) - *r0).length_squared();
                c += v[i].dot(*v0);
            }
            let (mut a1, mut a2) = (0.0, 0.0);
            for (s, s0) in s.iter().zip(&o.s0) {
                let x = s.dot(*s0);
                a1 += x;
                a2 += 1.5 * x * x - 0.5;
            }
            self.msd[lag] += m * inv_n;
            self.vacf[lag] += c * inv_n;
            self.p1[lag] += a1 * inv_n;
            self.p2[lag] += a2 * inv_n;
            self.counts[lag] += 1;
        }
    }

    fn table(&self, acc: &[f64], norm: bool) -> Vec<(f64, f64)> {
        let c0 = if norm && self.counts[0] > 0 {
            acc[0] / self.counts[0] as f64
        } else {
            1.0
        };
        (0..self.lags)
            .filter(|&k| self.counts[k] > 0)
            .map(|k| (k as f64 * self.dt, acc[k] / self.counts[k] as f64 / c0))
            .collect()
    }

    /// Rows `(t, ⟨|r(t) − r(0)|²⟩)`.
    pub fn msd(&self) -> Vec<(f64, f64)> {
        self.table(&self.msd, false)
    }

    /// Rows `(t, ⟨v(0)·v(t)⟩)` (not normalised).
    pub fn vacf(&self) -> Vec<(f64, f64)> {
        self.table(&self.vacf, false)
    }

    /// Rows `(t, ⟨v(0)·v(t)⟩ / ⟨v(0)·v(0)⟩)`.
    pub fn vacf_normalised(&self) -> Vec<(f64, f64)> {
        self.table(&self.vacf, true)
    }

    /// Rows `(t, ⟨s(0)·s(t)⟩)` (normalised: `s` is a unit vector). Empty for spheres' zero.
    pub fn orientation_p1(&self) -> Vec<(f64, f64)> {
        self.table(&self.p1, false)
    }

    /// Rows `(t, ⟨P₂(s(0)·s(t))⟩)`.
    pub fn orientation_p2(&self) -> Vec<(f64, f64)> {
        self.table(&self.p2, false)
    }

    /// Self-diffusion coefficient from the least-squares slope of the MSD over the second half
    /// of the lags, `D = slope/6`.
    pub fn diffusion_from_msd(&self) -> Option<f64> {
        let t = self.msd();
        let half = &t[t.len() / 2..];
        if half.len() < 2 {
            return None;
        }
        let n = half.len() as f64;
        let mx = half.iter().map(|p| p.0).sum::<f64>() / n;
        let my = half.iter().map(|p| p.1).sum::<f64>() / n;
        let sxy: f64 = half.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let sxx: f64 = half.iter().map(|p| (p.0 - mx).powi(2)).sum();
        (sxx > 0.0).then(|| sxy / sxx / 6.0)
    }
}

/// One row of the energy series.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeriesRow {
    /// Simulated time.
    pub time: f64,
    /// Translational kinetic energy.
    pub kinetic_translational: f64,
    /// Rotational kinetic energy.
    pub kinetic_rotational: f64,
    /// Potential energy (smoothed potential).
    pub potential: f64,
    /// Total energy.
    pub total: f64,
    /// Kinetic temperature over all degrees of freedom.
    pub temperature: f64,
    /// Translational kinetic temperature.
    pub temperature_translational: f64,
    /// Instantaneous virial pressure.
    pub pressure: f64,
}

impl SeriesRow {
    /// The row of a snapshot.
    pub fn of(s: &Snapshot<'_>) -> Self {
        Self {
            time: s.time,
            kinetic_translational: s.energy.kinetic_translational,
            kinetic_rotational: s.energy.kinetic_rotational,
            potential: s.energy.potential,
            total: s.energy.total(),
            temperature: s.temperature(),
            temperature_translational: s.temperature_translational(),
            pressure: s.pressure(),
        }
    }

    /// Total kinetic energy.
    pub fn kinetic(&self) -> f64 {
        self.kinetic_translational + self.kinetic_rotational
    }
}

/// Mean and standard error of a series, the error from block averages (10 blocks, so that
/// correlated samples do not make it look smaller than it is).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Estimate {
    /// Mean.
    pub mean: f64,
    /// Standard error of the mean from the spread of block means.
    pub error: f64,
    /// Standard deviation of the samples.
    pub std_dev: f64,
}

impl Estimate {
    /// Estimates from samples (zeros for fewer than two).
    pub fn of(x: &[f64]) -> Self {
        let n = x.len();
        if n < 2 {
            return Self {
                mean: x.first().copied().unwrap_or(0.0),
                ..Self::default()
            };
        }
        let mean = x.iter().sum::<f64>() / n as f64;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let blocks = 10.min(n);
        let size = n / blocks;
        let means: Vec<f64> = (0..blocks)
            .map(|b| x[b * size..(b + 1) * size].iter().sum::<f64>() / size as f64)
            .collect();
        let bm = means.iter().sum::<f64>() / blocks as f64;
        let bvar = means.iter().map(|m| (m - bm).powi(2)).sum::<f64>() / (blocks - 1) as f64;
        Self {
            mean,
            error: (bvar / blocks as f64).sqrt(),
            std_dev: var.sqrt(),
        }
    }
}

/// What a run's energy series says: means with errors, the energy drift and fluctuation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Summary {
    /// Bodies.
    pub bodies: usize,
    /// Samples in the series.
    pub samples: usize,
    /// Simulated time covered by the series.
    pub duration: f64,
    /// Kinetic temperature (all degrees of freedom).
    pub temperature: Estimate,
    /// Translational kinetic temperature.
    pub temperature_translational: Estimate,
    /// Virial pressure.
    pub pressure: Estimate,
    /// Potential energy per body.
    pub potential_per_body: Estimate,
    /// Total energy: its mean and standard deviation (the fluctuation).
    pub total: Estimate,
    /// Least-squares slope of the total energy per body per unit time (the drift).
    pub drift_per_body: f64,
    /// Standard deviation of the total energy about its least-squares line (the fluctuation
    /// without the drift).
    pub total_detrended_std: f64,
    /// `std(E) / |⟨U⟩|` (detrended std).
    pub relative_fluctuation: f64,
    /// `std(E) / std(U)` (detrended std of E): the reading of the paper's "relative
    /// fluctuations of the total energy to the potential energy of about 1 %" at 1.8 fs
    /// (003 §V.B) that its rods reproduce (0.8 % here).
    pub fluctuation_over_potential_std: f64,
}

impl Summary {
    /// Summarises series rows.
    pub fn of(rows: &[SeriesRow], bodies: usize) -> Self {
        let col = |f: &dyn Fn(&SeriesRow) -> f64| -> Vec<f64> { rows.iter().map(f).collect() };
        let n = bodies.max(1) as f64;
        let total = Estimate::of(&col(&|r| r.total));
        let potential_per_body = Estimate::of(&col(&|r| r.potential / n));
        let (t, e) = (col(&|r| r.time), col(&|r| r.total));
        let drift_per_body = slope(&t, &e) / n;
        let detrended = detrended_std(&t, &e);
        let u_mean = potential_per_body.mean * n;
        let u_std = potential_per_body.std_dev * n;
        Self {
            bodies,
            samples: rows.len(),
            duration: match (rows.first(), rows.last()) {
                (Some(a), Some(b)) => b.time - a.time,
                _ => 0.0,
            },
            temperature: Estimate::of(&col(&|r| r.temperature)),
            temperature_translational: Estimate::of(&col(&|r| r.temperature_translational)),
            pressure: Estimate::of(&col(&|r| r.pressure)),
            potential_per_body,
            total,
            drift_per_body,
            total_detrended_std: detrended,
            relative_fluctuation: if u_mean != 0.0 {
                detrended / u_mean.abs()
            } else {
                f64::NAN
            },
            fluctuation_over_potential_std: if u_std > 0.0 {
                detrended / u_std
            } else {
                f64::NAN
            },
        }
    }
}

/// Standard deviation of `y` about its least-squares line against `x` (0 for fewer than three
/// points).
pub fn detrended_std(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len());
    if n < 3 {
        return 0.0;
    }
    let b = slope(x, y);
    let mx = x[..n].iter().sum::<f64>() / n as f64;
    let my = y[..n].iter().sum::<f64>() / n as f64;
    let ss: f64 = (0..n).map(|k| (y[k] - my - b * (x[k] - mx)).powi(2)).sum();
    (ss / (n - 2) as f64).sqrt()
}

/// Least-squares slope of `y` against `x` (0 for fewer than two points).
pub fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len());
    if n < 2 {
        return 0.0;
    }
    let mx = x[..n].iter().sum::<f64>() / n as f64;
    let my = y[..n].iter().sum::<f64>() / n as f64;
    let sxy: f64 = (0..n).map(|k| (x[k] - mx) * (y[k] - my)).sum();
    let sxx: f64 = (0..n).map(|k| (x[k] - mx).powi(2)).sum();
    if sxx > 0.0 { sxy / sxx } else { 0.0 }
}

/// Every observable of a run, sampled together; an [`Observer`].
#[derive(Clone, Debug, Default)]
pub struct Observables {
    /// Radial distribution function (if asked for).
    pub rdf: Option<Rdf>,
    /// MSD, VACF and orientational correlations (if asked for).
    pub correlations: Option<Correlations>,
    /// Energy, temperature and pressure at every sample.
    pub series: Vec<SeriesRow>,
}

impl Observer for Observables {
    fn sample(&mut self, s: &Snapshot<'_>) {
        if let Some(r) = &mut self.rdf {
            r.add(s.system);
        }
        if let Some(c) = &mut self.correlations {
            c.add(s.system);
        }
        self.series.push(SeriesRow::of(s));
    }
}

impl Observables {
    /// The summary of the energy series.
    pub fn summary(&self, bodies: usize) -> Summary {
        Summary::of(&self.series, bodies)
    }

    /// Writes `rdf.csv`, `msd.csv`, `vacf.csv`, `orientation.csv` (those asked for) and
    /// `series.csv` into `dir` (created if missing), each atomically; returns the file names.
    ///
    /// # Errors
    /// [`SmdError::Output`] naming the file.
    pub fn write_csv(&self, dir: &Path) -> Result<Vec<String>, SmdError> {
        std::fs::create_dir_all(dir).map_err(|e| SmdError::Output {
            path: dir.to_owned(),
            message: e.to_string(),
        })?;
        let mut files = Vec::new();
        let mut put = |name: &str, header: &[&str], rows: Vec<Vec<f64>>| {
            write_csv(&dir.join(name), header, &rows).map(|()| files.push(name.to_owned()))
        };
        if let Some(r) = &self.rdf {
            put(
                "rdf.csv",
                &["r", "g"],
                r.table().iter().map(|&(r, g)| vec![r, g]).collect(),
            )?;
        }
        if let Some(c) = &self.correlations {
            put(
                "msd.csv",
                &["t", "msd"],
                c.msd().iter().map(|&(t, m)| vec![t, m]).collect(),
            )?;
            let raw = c.vacf();
            let c0 = raw.first().map(|p| p.1).unwrap_or(1.0);
            put(
                "vacf.csv",
                &["t", "vacf", "vacf_normalised"],
                raw.iter().map(|&(t, v)| vec![t, v, v / c0]).collect(),
            )?;
            let p2 = c.orientation_p2();
            put(
                "orientation.csv",
                &["t", "p1", "p2"],
                c.orientation_p1()
                    .iter()
                    .zip(&p2)
                    .map(|(&(t, a), &(_, b))| vec![t, a, b])
                    .collect(),
            )?;
        }
        put(
            "series.csv",
            &[
                "t",
                "kinetic",
                "kinetic_translational",
                "kinetic_rotational",
                "potential",
                "total",
                "temperature",
                "pressure",
            ],
            self.series
                .iter()
                .map(|r| {
                    vec![
                        r.time,
                        r.kinetic(),
                        r.kinetic_translational,
                        r.kinetic_rotational,
                        r.potential,
                        r.total,
                        r.temperature,
                        r.pressure,
                    ]
                })
                .collect(),
        )?;
        Ok(files)
    }
}
