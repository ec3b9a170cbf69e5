//! Time per step of the `dmd-smd` standard-MD integrator, reported per body
//! ([`Throughput::Elements`] = N, so criterion's element rate is particle-steps per second).
//!
//! Each benchmark builds and equilibrates its system once (outside the measurement), then
//! times single steps of the continuing NVE run: force loop, kicks, exact free drift, and the
//! neighbour-list builds as often as the displacement criterion asks. Systems:
//!
//! - the paper's rods (003 §V: ρ* = 0.5, T* = 1.4, dt = 1.8 fs, smoothing 2.5σ–3σ, skin 2 Å)
//!   at N = 512 and N = 4096, and at the gas state point of the report (T* = 10, ρ* = 0.01,
//!   dt = 0.9 fs);
//! - Lennard-Jones spheres at ρ* = 0.5, T* = 2 (the validation's state point; dt = 0.005 τ,
//!   smoothing 2.5σ–3σ, skin 0.6σ) at N = 500 and N = 4000;
//! - LAMMPS's `bench/in.lj` problem (32 000 atoms, fcc at ρ* = 0.8442 melting from T* = 1.44,
//!   dt = 0.005 τ, cut-off 2.5σ — here switched from 2.2σ —, skin 0.3σ), to compare with
//!   LAMMPS's published serial timings of the same problem.
//!
//! Times are CPU time of the benchmarking thread ([`CpuTime`]), not wall time: the machine is
//! shared. The throughput line reads "ns per element": ns per particle-step.
//!
//! The baseline in the same run (`pairs-only`) evaluates the smoothed potential alone over the
//! pairs within the cut-off of the same state, stored as a flat array of geometries: the floor
//! a step cannot go below. step / pairs-only is the overhead of lists, accumulation and
//! integration.

use std::hint::black_box;

use criterion::measurement::{Measurement, ValueFormatter};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use potential::{LennardJones, LjRod, PairGeometry, PairPotential, Smoothed};
use smd::{BodyModel, Integrator, Lattice, Settings, Setup, System, units};

/// Criterion measurement by CPU time of the benchmarking thread (Linux
/// `/proc/thread-self/schedstat`), so that time the shared machine gives to other jobs is not
/// counted. Values are nanoseconds.
struct CpuTime;

fn cpu_ns() -> f64 {
    smd::timing::thread_cpu_seconds().expect("/proc/thread-self/schedstat (Linux) is needed") * 1e9
}

impl Measurement for CpuTime {
    type Intermediate = f64;
    type Value = f64;
    fn start(&self) -> f64 {
        cpu_ns()
    }
    fn end(&self, start: f64) -> f64 {
        cpu_ns() - start
    }
    fn add(&self, a: &f64, b: &f64) -> f64 {
        a + b
    }
    fn zero(&self) -> f64 {
        0.0
    }
    fn to_f64(&self, v: &f64) -> f64 {
        *v
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        &CpuFormatter
    }
}

struct CpuFormatter;

impl ValueFormatter for CpuFormatter {
    fn scale_values(&self, typical: f64, values: &mut [f64]) -> &'static str {
        let (div, unit) = if typical < 1e3 {
            (1.0, "ns (CPU)")
        } else if typical < 1e6 {
            (1e3, "µs (CPU)")
        } else if typical < 1e9 {
            (1e6, "ms (CPU)")
        } else {
            (1e9, "s (CPU)")
        };
        for v in values {
            *v /= div;
        }
        unit
    }
    fn scale_throughputs(&self, _typical: f64, t: &Throughput, values: &mut [f64]) -> &'static str {
        // ns of CPU per element (per particle-step).
        let n = match *t {
            Throughput::Elements(n)
            | Throughput::Bytes(n)
            | Throughput::BytesDecimal(n)
            | Throughput::Bits(n) => n as f64,
            #[allow(unreachable_patterns)]
            _ => 1.0,
        };
        for v in values {
            *v /= n;
        }
        "ns per element (CPU)"
    }
    fn scale_for_machines(&self, _values: &mut [f64]) -> &'static str {
        "ns"
    }
}

fn rods(n: usize, rho_star: f64, t_star: f64, dt_fs: f64) -> Integrator<Smoothed<LjRod>> {
    let rod = LjRod::paper();
    let kt = t_star * rod.epsilon();
    let setup = Setup {
        lattice: Lattice::Sc,
        ..Setup::new(
            n,
            units::density_from_reduced(rho_star, rod.sigma()),
            BodyModel::paper_rod(),
            kt,
        )
    };
    let mut md = Integrator::new(
        System::new(&setup).unwrap(),
        Smoothed::paper(rod, rod.sigma()).unwrap(),
        Settings::new(units::from_fs(dt_fs), 2.0),
    )
    .unwrap();
    md.equilibrate(1000, 25, kt).unwrap();
    md
}

fn lj(
    n: usize,
    rho: f64,
    kt: f64,
    window: (f64, f64),
    skin: f64,
    eq: u64,
) -> Integrator<Smoothed<LennardJones>> {
    let setup = Setup::new(n, rho, BodyModel::sphere(1.0).unwrap(), kt);
    let pot = Smoothed::new(LennardJones::new(1.0, 1.0).unwrap(), window.0, window.1).unwrap();
    let mut md = Integrator::new(
        System::new(&setup).unwrap(),
        pot,
        Settings::new(0.005, skin),
    )
    .unwrap();
    if eq > 0 {
        md.equilibrate(eq, 25, kt).unwrap();
    }
    md
}

/// Every pair of the current state within the cut-off, as the force loop sees it.
fn pairs<P: PairPotential>(md: &Integrator<Smoothed<P>>) -> Vec<PairGeometry> {
    let s = md.system();
    let (_, r_u) = md.potential().window();
    let l = s.lengths();
    let rot = !s.axes().is_empty();
    let mut out = Vec::new();
    for i in 0..s.n() {
        for j in i + 1..s.n() {
            let mut d = s.positions()[i] - s.positions()[j];
            for a in 0..3 {
                d[a] -= l[a] * (d[a] / l[a]).round();
            }
            if d.length() < r_u {
                out.push(if rot {
                    PairGeometry::new(d, s.axes()[i], s.axes()[j])
                } else {
                    PairGeometry::spheres(d)
                });
            }
        }
    }
    out
}

fn case<P: PairPotential + Clone>(
    c: &mut Criterion<CpuTime>,
    name: &str,
    mut md: Integrator<Smoothed<P>>,
    baseline: bool,
) {
    let n = md.system().n();
    let mut g = c.benchmark_group(format!("smd/{name}"));
    g.throughput(Throughput::Elements(n as u64));
    if baseline {
        let geoms = pairs(&md);
        let pot = md.potential().clone();
        g.bench_function(BenchmarkId::new("pairs-only", n), |b| {
            b.iter(|| {
                let mut u = 0.0;
                for geom in &geoms {
                    if let Ok(e) = pot.evaluate(black_box(geom)) {
                        u += e.energy
                            + e.force.element_sum()
                            + e.torque_i.element_sum()
                            + e.torque_j.element_sum();
                    }
                }
                black_box(u)
            })
        });
    }
    g.bench_function(BenchmarkId::new("step", n), |b| {
        b.iter(|| md.step().unwrap());
    });
    g.finish();
}

fn bench(c: &mut Criterion<CpuTime>) {
    case(c, "rods", rods(512, 0.5, 1.4, 1.8), true);
    case(c, "rods", rods(4096, 0.5, 1.4, 1.8), false);
    // The report's gas (003 §V.B: T* = 10, ρ* = 0.01) at 0.9 fs, the step its close
    // collisions need (std(E)/std(U) = 1.7 %; 1.24 at 1.8 fs).
    case(c, "rods-gas", rods(512, 0.01, 10.0, 0.9), false);
    case(c, "lj", lj(500, 0.5, 2.0, (2.5, 3.0), 0.6, 1000), true);
    case(c, "lj", lj(4000, 0.5, 2.0, (2.5, 3.0), 0.6, 1000), false);
    // LAMMPS bench/in.lj: 20³ fcc cells at 0.8442 melting from T* = 1.44 (its timing is of the
    // first 100 steps), cut-off 2.5σ. LAMMPS truncates there; a switch must have some width to
    // keep the energy (a 10⁻⁶σ switch is an impulsive force that blows the run up), so the
    // pairs between 2.2σ and 2.5σ take the switch's branch: as many pairs evaluated as there.
    case(
        c,
        "lammps-in.lj",
        lj(32_000, 0.8442, 1.44, (2.2, 2.5), 0.3, 0),
        false,
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(CpuTime).sample_size(20);
    targets = bench
}
criterion_main!(benches);
