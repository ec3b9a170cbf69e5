//! Unit systems: the numbers of a scene, the numbers the simulator computes with, and the
//! numbers it reports.
//!
//! A scene in **reduced** units is taken as it is (Boltzmann's constant 1). A scene in
//! **molecular** units gives lengths in Å, masses in g/mol, energies in kJ/mol, times in ps,
//! temperatures in K and moments of inertia in g/mol·Å² (003 §V gives its rods this way). The
//! simulator then computes in Å, g/mol and ps, whose energy unit is
//! `1 g/mol·Å²/ps² = 10 J/mol = 0.01 kJ/mol`: lengths, masses, times and inertia pass
//! unchanged, energies are multiplied by 100 and temperatures by `R = 0.831446… (10 J/mol)/K`
//! on the way in ([`Scene::internal`]), and the summary converts back (energies in kJ/mol,
//! temperatures in K, pressures in bar).

use crate::config::scene::{Scene, UnitSystem};

/// Internal energy units per kJ/mol (the internal unit is 1 g/mol·Å²/ps² = 10 J/mol).
pub const PER_KJ_PER_MOL: f64 = 100.0;

/// The molar gas constant in internal energy units per kelvin (8.314462618 J/(mol K), CODATA
/// 2018, exact in the SI).
pub const GAS_CONSTANT: f64 = 0.831_446_261_815_324;

/// Bar per internal pressure unit: `(10 J/mol) / Å³ / N_A = 1.66053906660·10⁷ Pa`.
pub const BAR_PER_UNIT: f64 = 166.053_906_660;

/// The factors of a scene's unit system.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Units {
    /// The system.
    pub system: UnitSystem,
    /// Internal energy per scene energy.
    pub energy: f64,
    /// Internal `kT` per scene temperature.
    pub temperature: f64,
}

impl Units {
    /// The factors of `system`.
    pub fn of(system: UnitSystem) -> Self {
        match system {
            UnitSystem::Reduced => Units {
                system,
                energy: 1.0,
                temperature: 1.0,
            },
            UnitSystem::Molecular => Units {
                system,
                energy: PER_KJ_PER_MOL,
                temperature: GAS_CONSTANT,
            },
        }
    }

    /// How `series.csv` converts its internal numbers ([`energy_out`](Self::energy_out),
    /// [`temperature_out`](Self::temperature_out), [`pressure_out`](Self::pressure_out)).
    pub fn series(&self) -> crate::analysis::observable::SeriesUnits {
        crate::analysis::observable::SeriesUnits {
            energy: self.energy,
            temperature: self.temperature,
            pressure: match self.system {
                UnitSystem::Reduced => None,
                UnitSystem::Molecular => Some(BAR_PER_UNIT),
            },
        }
    }

    /// An internal energy in the scene's unit.
    pub fn energy_out(&self, e: f64) -> f64 {
        e / self.energy
    }

    /// An internal `kT` as a temperature in the scene's unit.
    pub fn temperature_out(&self, kt: f64) -> f64 {
        kt / self.temperature
    }

    /// An internal pressure in the reported unit (bar in molecular units).
    pub fn pressure_out(&self, p: f64) -> f64 {
        match self.system {
            UnitSystem::Reduced => p,
            UnitSystem::Molecular => p * BAR_PER_UNIT,
        }
    }

    /// Names of the units a person reads (terminal, plots).
    pub fn names(&self) -> &'static UnitNames {
        UnitNames::of(self.system)
    }
}

/// Names of the units of reported numbers, as the terminal and the plots print them: molecular
/// units by name, reduced units in σ (length), ε (energy), k_B = 1 and τ = σ√(m/ε) (time).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UnitNames {
    /// Length: `Å` or `σ`.
    pub length: &'static str,
    /// Time: `ps` or `τ`.
    pub time: &'static str,
    /// Energy: `kJ/mol` or `ε`.
    pub energy: &'static str,
    /// Temperature: `K` or `ε/k_B`.
    pub temperature: &'static str,
    /// Pressure: `bar` or `ε/σ³`.
    pub pressure: &'static str,
    /// Number density: `Å⁻³` or `σ⁻³`.
    pub density: &'static str,
    /// Area (mean squared displacement): `Å²` or `σ²`.
    pub area: &'static str,
    /// Diffusion coefficient: `Å²/ps` or `σ²/τ`.
    pub diffusion: &'static str,
    /// Velocity squared (velocity autocorrelation): `Å²/ps²` or `σ²/τ²`.
    pub speed_squared: &'static str,
    /// The system in a few words, for a header.
    pub system: &'static str,
    /// Whether these are reduced units.
    pub reduced: bool,
}

impl UnitNames {
    const MOLECULAR: UnitNames = UnitNames {
        length: "Å",
        time: "ps",
        energy: "kJ/mol",
        temperature: "K",
        pressure: "bar",
        density: "Å⁻³",
        area: "Å²",
        diffusion: "Å²/ps",
        speed_squared: "Å²/ps²",
        system: "molecular units (Å, ps, kJ/mol, K, bar)",
        reduced: false,
    };

    const REDUCED: UnitNames = UnitNames {
        length: "σ",
        time: "τ",
        energy: "ε",
        temperature: "ε/k_B",
        pressure: "ε/σ³",
        density: "σ⁻³",
        area: "σ²",
        diffusion: "σ²/τ",
        speed_squared: "σ²/τ²",
        system: "reduced units (length σ, energy ε, k_B = 1, time τ = σ√(m/ε))",
        reduced: true,
    };

    /// The names of `system`.
    pub fn of(system: UnitSystem) -> &'static UnitNames {
        match system {
            UnitSystem::Molecular => &Self::MOLECULAR,
            UnitSystem::Reduced => &Self::REDUCED,
        }
    }

    /// The names of a summary's `units` field (`"molecular"` or `"reduced"`).
    pub fn of_summary(units: &str) -> &'static UnitNames {
        Self::of(if units == "molecular" {
            UnitSystem::Molecular
        } else {
            UnitSystem::Reduced
        })
    }
}

impl Scene {
    /// The same scene in the simulator's internal units (module documentation): energies and
    /// temperatures scaled, everything else as it is.
    pub fn internal(&self) -> Scene {
        let u = Units::of(self.units);
        if u.energy == 1.0 && u.temperature == 1.0 {
            return self.clone();
        }
        let e = u.energy;
        let mut s = self.clone();
        for p in &mut s.pair {
            for step in &mut p.steps {
                step[1] *= e;
            }
            if let Some(pot) = &mut p.potential {
                pot.describe_mut().scale_energy(e);
            }
            if let Some(t) = &mut p.terraces {
                let scale = |x: &mut Option<f64>| {
                    if let Some(v) = x {
                        *v *= e;
                    }
                };
                scale(&mut t.step);
                scale(&mut t.core);
                scale(&mut t.outermost);
                for list in [&mut t.levels, &mut t.energies].into_iter().flatten() {
                    for v in list {
                        *v *= e;
                    }
                }
            }
        }
        // Site–site steps are energies too.
        for p in &mut s.site_pair {
            for step in &mut p.steps {
                step[1] *= e;
            }
        }
        s.init.temperature *= u.temperature;
        if let Some(t) = &mut s.thermostat.temperature {
            *t *= u.temperature;
        }
        if let Some(t) = s.hmc.as_mut().and_then(|h| h.temperature.as_mut()) {
            *t *= u.temperature;
        }
        // The grazing threshold of site molecules is a squared length, not an energy.
        if let Some(sr) = &mut s.search
            && !self.has_sites()
            && let Some(g) = &mut sr.grid_threshold
        {
            *g *= e;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_state_point_in_internal_units() {
        let u = Units::of(UnitSystem::Molecular);
        // T* = kT/ε = 1.4 with ε = 3 kJ/mol: T = 1.4 · 3000 / 8.314462618 K = 505.14 K.
        let t = 1.4 * 3.0 * 1000.0 / 8.314_462_618_153_24;
        let kt = t * u.temperature;
        assert!((kt - 1.4 * 3.0 * PER_KJ_PER_MOL).abs() < 1e-9, "{kt}");
        // Thermal speed of the rods, √(kT/m) with m = 18 g/mol: 4.83 Å/ps.
        assert!(((kt / 18.0).sqrt() - 4.830_459).abs() < 1e-5);
        assert!((u.temperature_out(kt) - t).abs() < 1e-12 * t);
        assert_eq!(u.energy_out(300.0), 3.0);
        // 1 kJ/mol/Å³ is 16 605.39 bar.
        assert!((u.pressure_out(PER_KJ_PER_MOL) - 16_605.390_666).abs() < 1e-3);
    }
}
