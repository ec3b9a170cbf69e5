//! Prints the `steps` of a stepped Lennard-Jones potential for a scene file.
//!
//! `cargo run -p dmd-sim --example stepped_lj -- [ΔV] [U_core]` (defaults 0.5 and 10, in units
//! of ε; lengths in σ). The pair energy is the Lennard-Jones energy `U(r) = 4(r⁻¹² − r⁻⁶)`
//! rounded to the nearest multiple of ΔV, as in the terraced potentials of van Zon and
//! Schofield (J. Chem. Phys. 128, 154119, 2008, Eq. 7 with evenly spaced terraces
//! `U_k = (k − ½)ΔV`): a step of ±ΔV at every radius where `U` crosses a half-integer multiple
//! of ΔV, zero beyond the outermost crossing, and a hard core where `U` reaches `U_core`.

fn lj(r: f64) -> f64 {
    let s6 = r.powi(-6);
    4.0 * (s6 * s6 - s6)
}

/// The radius in `[a, b]` where the monotonic `lj` equals `level` (bisection to round-off).
fn solve(level: f64, mut a: f64, mut b: f64) -> f64 {
    let fa = lj(a) - level;
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if (lj(m) - level).signum() == fa.signum() {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let dv = args.first().copied().unwrap_or(0.5);
    let core_energy = args.get(1).copied().unwrap_or(10.0);
    let r_min = 2f64.powf(1.0 / 6.0);
    let mut steps: Vec<(f64, f64)> = Vec::new();
    // Repulsive side, from the hard core outwards: crossings of (k - 1/2) ΔV going down.
    let core = solve(core_energy, 0.5, r_min);
    steps.push((core, f64::INFINITY));
    let mut k = (core_energy / dv + 0.5).floor() as i64;
    while (k as f64 - 0.5) * dv > -1.0 {
        let level = (k as f64 - 0.5) * dv;
        if level < core_energy && level > lj(r_min) {
            // Inwards across this radius the energy rises by ΔV.
            steps.push((solve(level, core, r_min), dv));
        }
        k -= 1;
    }
    // Attractive side, outwards: crossings of (k - 1/2) ΔV going up towards 0.
    let mut k = ((lj(r_min) / dv) + 0.5).ceil() as i64;
    while ((k as f64) - 0.5) * dv < 0.0 {
        let level = (k as f64 - 0.5) * dv;
        if level > lj(r_min) {
            // Inwards across this radius the energy falls by ΔV.
            steps.push((solve(level, r_min, 10.0), -dv));
        }
        k += 1;
    }
    steps.sort_by(|a, b| a.0.total_cmp(&b.0));
    let body: Vec<String> = steps
        .iter()
        .map(|(r, e)| {
            if e.is_infinite() {
                format!("[{r:.12}, inf]")
            } else {
                format!("[{r:.12}, {e}]")
            }
        })
        .collect();
    println!("# stepped Lennard-Jones, ΔV = {dv}, hard core where U = {core_energy}");
    println!("steps = [\n    {},\n]", body.join(",\n    "));
}
