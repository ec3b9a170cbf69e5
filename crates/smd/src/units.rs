//! Units. The integrator works in whatever consistent units the potential uses; these are the
//! conversions for the two systems the project simulates.
//!
//! **Molecular units** (the paper's rods, 003 §V): energy kJ/mol, length Å, mass g/mol. Then
//! the unit of time is `√(g/mol · Å² / (kJ/mol)) = √(10⁻³ kg · 10⁻²⁰ m² / 10³ J) = 10⁻¹³ s`,
//! i.e. **0.1 ps = 100 fs**, and the unit of pressure is `kJ/mol/Å³ = 1.660 539 07·10⁹ Pa`.
//! Temperatures enter as `kT` in kJ/mol ([`BOLTZMANN_KJ_PER_MOL_K`]).
//!
//! **Reduced Lennard-Jones units**: `ε = σ = m = 1`, time `τ = σ √(m/ε)`, temperature
//! `T* = kT/ε`, density `ρ* = ρσ³`, pressure `P* = Pσ³/ε`.

/// Femtoseconds per internal time unit in molecular units (kJ/mol, Å, g/mol): 100 fs.
pub const FS_PER_TIME_UNIT: f64 = 100.0;

/// Boltzmann's constant in kJ/mol/K (CODATA 2018: `R = 8.314 462 618 J/mol/K`).
pub const BOLTZMANN_KJ_PER_MOL_K: f64 = 8.314_462_618e-3;

/// Pascal per internal pressure unit kJ/mol/Å³ (`10³ J / N_A / 10⁻³⁰ m³`, `N_A` exact).
pub const PASCAL_PER_PRESSURE_UNIT: f64 = 1.0e33 / 6.022_140_76e23;

/// A time in femtoseconds, in internal molecular units (0.1 ps).
#[inline]
pub fn from_fs(fs: f64) -> f64 {
    fs / FS_PER_TIME_UNIT
}

/// An internal molecular time in femtoseconds.
#[inline]
pub fn to_fs(t: f64) -> f64 {
    t * FS_PER_TIME_UNIT
}

/// A time in picoseconds, in internal molecular units.
#[inline]
pub fn from_ps(ps: f64) -> f64 {
    ps * (1000.0 / FS_PER_TIME_UNIT)
}

/// An internal molecular time in picoseconds.
#[inline]
pub fn to_ps(t: f64) -> f64 {
    t * (FS_PER_TIME_UNIT / 1000.0)
}

/// A temperature in kelvin as `kT` in kJ/mol.
#[inline]
pub fn kt_from_kelvin(kelvin: f64) -> f64 {
    kelvin * BOLTZMANN_KJ_PER_MOL_K
}

/// A number density from its reduced value `ρ* = ρσ³`.
#[inline]
pub fn density_from_reduced(rho_star: f64, sigma: f64) -> f64 {
    rho_star / (sigma * sigma * sigma)
}

/// The Lennard-Jones time unit `τ = σ √(m/ε)` in the units of `σ`, `m`, `ε` (0.1 ps for Å,
/// g/mol, kJ/mol).
#[inline]
pub fn lj_time(sigma: f64, mass: f64, epsilon: f64) -> f64 {
    sigma * (mass / epsilon).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_round_trip_and_match_the_paper() {
        // The paper's time step, 1.8 fs, is 0.018 internal units.
        assert!((from_fs(1.8) - 0.018).abs() < 1e-17);
        assert!((to_fs(from_fs(3.6)) - 3.6).abs() < 1e-15);
        assert_eq!(from_ps(1.0), 10.0);
        assert_eq!(to_ps(10.0), 1.0);
        // T* = 1.4 with ε = 3 kJ/mol is kT = 4.2 kJ/mol, about 505 K.
        let kelvin = 4.2 / BOLTZMANN_KJ_PER_MOL_K;
        assert!((kelvin - 505.14).abs() < 0.01, "{kelvin}");
        assert!((kt_from_kelvin(kelvin) - 4.2).abs() < 1e-15);
        // 1 kJ/mol/Å³ = 16 605.39 bar.
        assert!((PASCAL_PER_PRESSURE_UNIT / 1e5 - 16_605.390_7).abs() < 1e-3);
        // Water-like rods: τ = 3.035 Å √(18/3) in 0.1 ps.
        assert!((lj_time(3.035, 18.0, 3.0) - 3.035 * 6f64.sqrt()).abs() < 1e-15);
        assert!((density_from_reduced(0.5, 2.0) - 0.0625).abs() < 1e-17);
    }
}
