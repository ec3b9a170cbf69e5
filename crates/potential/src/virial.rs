//! Second virial coefficients and low-density energies of a profile and of its terraced map:
//! the static measure of how much a terrace map changes the thermodynamics.
//!
//! For a pair potential with orientation-averaged shell measure `w(x)` ([`Profile`]):
//!
//! ```text
//! B₂(T) = −2π ∫ (e^{−U(x)/kT} − 1) w(x) dx          (per pair; B₂ in units of length³)
//! E₂(T) =  2π ∫ U(x) e^{−U(x)/kT} w(x) dx           (excess energy per particle = ρ E₂ + O(ρ²))
//! ```
//!
//! For the terraced potential the integrals become sums over shells of measure `W_k`,
//! `B₂ = −2π Σ_k (e^{−V_k/kT} − 1) W_k + 2π W_core` and `E₂ = 2π Σ_k V_k e^{−V_k/kT} W_k`,
//! exact (no quadrature) once the shells are known. [`terms`] returns both, terrace by
//! terrace, so a report can say where the difference comes from.
//!
//! Below the profile's floor `δ_max` the potential is taken as infinite (`e^{−U/kT} = 0`); this
//! is exact in binary64 for the shipped potentials (the rods' `U(ζ/2)` is `~10¹⁰ ε`).

use crate::placement::{boltzmann_tolerance, shell_integral};
use crate::{PotentialError, Profile, TerraceMap};

/// `B₂` and `E₂` of a profile and of a terraced map on it, by terrace.
#[derive(Clone, Debug, PartialEq)]
pub struct Terms {
    /// Contributions of the continuous potential to `B₂` from the shells of each terrace.
    pub b2_continuous: Vec<f64>,
    /// Contributions of the terraced potential to `B₂` from each terrace.
    pub b2_terraced: Vec<f64>,
    /// `B₂` contributions of the core region (`U ≥ U_core`): continuous, terraced.
    pub b2_core: (f64, f64),
    /// Contributions of the continuous potential to `E₂` from each terrace's shells.
    pub e2_continuous: Vec<f64>,
    /// Contributions of the terraced potential to `E₂` from each terrace.
    pub e2_terraced: Vec<f64>,
    /// The terrace holding `U = 0` (its terraced contributions are zero: `V = 0`).
    pub zero: usize,
}

impl Terms {
    /// Total `B₂` of the continuous potential.
    pub fn b2_continuous_total(&self) -> f64 {
        self.b2_continuous.iter().sum::<f64>() + self.b2_core.0
    }

    /// Total `B₂` of the terraced potential.
    pub fn b2_terraced_total(&self) -> f64 {
        self.b2_terraced.iter().sum::<f64>() + self.b2_core.1
    }

    /// Total `E₂` of the continuous potential.
    pub fn e2_continuous_total(&self) -> f64 {
        self.e2_continuous.iter().sum()
    }

    /// Total `E₂` of the terraced potential.
    pub fn e2_terraced_total(&self) -> f64 {
        self.e2_terraced.iter().sum()
    }
}

fn check_kt(kt: f64) -> Result<f64, PotentialError> {
    crate::error::positive("kt", kt)
}

/// `B₂(T)` of the continuous profile, by adaptive quadrature (`[floor, x_min]`, then
/// `[x_min, ∞)` mapped to a finite interval).
///
/// # Errors
/// [`PotentialError::Parameter`] for a bad `kT`; quadrature errors.
pub fn b2<F: Fn(f64) -> f64>(profile: &Profile<F>, kt: f64) -> Result<f64, PotentialError> {
    let kt = check_kt(kt)?;
    let g = |x: f64, u: f64| (-u / kt).exp_m1() * profile.weight(x);
    let (x_min, _) = profile.minimum();
    let floor = profile.floor();
    let rel = rel_for(profile, kt);
    let inner = shell_integral(g, profile, floor, x_min, rel)?;
    let outer = shell_integral(g, profile, x_min, f64::INFINITY, rel)?;
    let pi2 = 2.0 * std::f64::consts::PI;
    Ok(-pi2 * (inner + outer) + pi2 * profile.volume(floor))
}

/// `E₂(T) = 2π ∫ U e^{−U/kT} w dx` of the continuous profile.
///
/// # Errors
/// As [`b2`].
pub fn e2<F: Fn(f64) -> f64>(profile: &Profile<F>, kt: f64) -> Result<f64, PotentialError> {
    let kt = check_kt(kt)?;
    let g = |x: f64, u: f64| boltzmann_energy(u, kt) * profile.weight(x);
    let (x_min, _) = profile.minimum();
    let rel = rel_for(profile, kt);
    let inner = shell_integral(g, profile, profile.floor(), x_min, rel)?;
    let outer = shell_integral(g, profile, x_min, f64::INFINITY, rel)?;
    Ok(2.0 * std::f64::consts::PI * (inner + outer))
}

/// The quadrature tolerance for Boltzmann factors of this profile at `kT`.
fn rel_for<F: Fn(f64) -> f64>(profile: &Profile<F>, kt: f64) -> f64 {
    boltzmann_tolerance(profile.minimum().1.abs() / kt)
}

/// `U e^{−U/kT}`, zero (not NaN) for `U = +∞`.
fn boltzmann_energy(u: f64, kt: f64) -> f64 {
    let b = (-u / kt).exp();
    if b == 0.0 { 0.0 } else { u * b }
}

/// `B₂` and `E₂` of the continuous profile and of `map` on it, terrace by terrace (module
/// documentation). The map's levels must be levels of this profile's potential.
///
/// # Errors
/// [`PotentialError::Parameter`] for a bad `kT`; the errors of [`Profile::shells`] and of the
/// quadrature.
pub fn terms<F: Fn(f64) -> f64>(
    profile: &Profile<F>,
    map: &TerraceMap,
    kt: f64,
) -> Result<Terms, PotentialError> {
    let kt = check_kt(kt)?;
    let pi2 = 2.0 * std::f64::consts::PI;
    let (shells, core) = profile.shells(map.level_set())?;
    let zero = map.zero_terrace();
    let rel = rel_for(profile, kt);
    let n = shells.len();
    let mut t = Terms {
        b2_continuous: Vec::with_capacity(n),
        b2_terraced: Vec::with_capacity(n),
        b2_core: (0.0, 0.0),
        e2_continuous: Vec::with_capacity(n),
        e2_terraced: Vec::with_capacity(n),
        zero,
    };
    for (k, shell) in shells.iter().enumerate() {
        let v = map.energies()[k];
        let (mut b_c, mut e_c, mut w) = (0.0, 0.0, 0.0);
        for (a, b) in [shell.inner, shell.outer].into_iter().flatten() {
            b_c += shell_integral(
                |x, u| (-u / kt).exp_m1() * profile.weight(x),
                profile,
                a,
                b,
                rel,
            )?;
            e_c += shell_integral(
                |x, u| boltzmann_energy(u, kt) * profile.weight(x),
                profile,
                a,
                b,
                rel,
            )?;
            w += profile.measure(a, b);
        }
        t.b2_continuous.push(-pi2 * b_c);
        t.e2_continuous.push(pi2 * e_c);
        if k == zero {
            // V = 0 on an infinite shell: no contribution.
            t.b2_terraced.push(0.0);
            t.e2_terraced.push(0.0);
        } else {
            t.b2_terraced.push(-pi2 * (-v / kt).exp_m1() * w);
            t.e2_terraced.push(pi2 * boltzmann_energy(v, kt) * w);
        }
    }
    // The core: U ≥ U_core below `core`, infinite below the floor.
    let floor = profile.floor();
    let inside = shell_integral(
        |x, u| (-u / kt).exp_m1() * profile.weight(x),
        profile,
        floor,
        core,
        rel,
    )?;
    t.b2_core = (
        -pi2 * inside + pi2 * profile.volume(floor),
        pi2 * profile.volume(core),
    );
    let e_core = shell_integral(
        |x, u| boltzmann_energy(u, kt) * profile.weight(x),
        profile,
        floor,
        core,
        rel,
    )?;
    if let Some(last) = t.e2_continuous.last_mut() {
        // Keep the continuous E₂ complete: the core region's (tiny) share goes to the top
        // terrace's entry.
        *last += pi2 * e_core;
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LennardJones, LevelSet, Steps, TerraceOptions, profile};

    #[test]
    fn lennard_jones_b2_at_t1_against_the_reference() {
        // mpmath, 30 digits (reference/lj_b2.txt): B2*(1) = −5.3157451202627758...
        let p = profile::lennard_jones(&LennardJones::new(1.0, 1.0).unwrap()).unwrap();
        let b = b2(&p, 1.0).unwrap();
        assert!((b + 5.315_745_120_262_776).abs() < 1e-12, "{b}");
    }

    #[test]
    fn square_well_closed_form() {
        // One level below zero and a hard core at U = 3: a hard sphere of radius σ_c, V = 0 out
        // to the inner crossing a of U = −0.5, a square well of depth 1 from a to λσ_c.
        let p = profile::lennard_jones(&LennardJones::new(1.0, 1.0).unwrap()).unwrap();
        let set = LevelSet::new(-1.0, &[-0.5], &TerraceOptions::default().with_core(3.0)).unwrap();
        let map = TerraceMap::new(set, Steps::Energies(&[-1.0, 0.0])).unwrap();
        let t = terms(&p, &map, 0.8).unwrap();
        let sc = p.inner_radius(3.0).unwrap();
        let ls = p.outer_radius(-0.5).unwrap();
        let a = p.inner_radius(-0.5).unwrap();
        // B2 = (2π/3)[σ_c³ − (e^{ε/kT} − 1)((λσ_c)³ − a³)].
        let exact = 2.0 * std::f64::consts::PI / 3.0
            * (sc.powi(3) - ((1.0f64 / 0.8).exp() - 1.0) * (ls.powi(3) - a.powi(3)));
        let got = t.b2_terraced_total();
        assert!(
            (got - exact).abs() < 1e-13 * exact.abs(),
            "{got} vs {exact}"
        );
    }

    #[test]
    fn terms_add_up_to_the_direct_integrals() {
        let p = profile::lennard_jones(&LennardJones::new(1.0, 1.0).unwrap()).unwrap();
        let map = TerraceMap::evenly_spaced(
            &LennardJones::new(1.0, 1.0).unwrap(),
            0.3,
            &TerraceOptions::default(),
        )
        .unwrap();
        for kt in [0.7, 1.0, 3.0] {
            let t = terms(&p, &map, kt).unwrap();
            let (b, e) = (b2(&p, kt).unwrap(), e2(&p, kt).unwrap());
            assert!(
                (t.b2_continuous_total() - b).abs() < 1e-11 * b.abs(),
                "{kt}"
            );
            assert!(
                (t.e2_continuous_total() - e).abs() < 1e-11 * e.abs(),
                "{kt}"
            );
        }
    }
}
