//! Limits a scene is checked against before anything runs, so that a legal but absurd value
//! gets a message naming its key instead of an allocation failure, a run that never ends or
//! a state that loses all precision.
//!
//! - **Output sizes** ([`check_outputs`]): the correlation buffers of `msd`/`vacf`/
//!   `orientation_acf` (known from the keys alone), and with `run.time` the rows of
//!   `series.csv` and the size of the trajectories, are estimated and refused above
//!   `output.max_bytes` ([`DEFAULT_MAX_BYTES`] unless given). A run whose length is given in
//!   events cannot be estimated beforehand: [`Observers`](crate::analysis::observable::Observers) stops
//!   it when the series or a trajectory reach the same limit. The samples behind the
//!   summary's error bars need no limit: they are accumulated online, in memory that grows as
//!   the logarithm of their number.
//! - **Temperatures** ([`check_temperatures`]): normal numbers within [`TEMPERATURE_RATIO`] of
//!   the potential's energy scale (its smallest finite step or well depth), or within
//!   [`TEMPERATURE_RANGE`] for pure hard cores, which have no energy scale.
//! - **Step energies**: at most [`MAX_STEP_ENERGY`] in magnitude (in `scene::check_steps_at`).
//! - **Skin**: at least [`MIN_SKIN_FRACTION`] of the interaction reach (in `run`, where the
//!   reach is known).

pub use crate::analysis::output::{
    GSD_FRAME_BYTES, GSD_PARTICLE_BYTES, LAG_BYTES, SERIES_ROW_BYTES, short, trajectory_line_bytes,
};
pub use crate::config::scene::{DEFAULT_MAX_BYTES, MAX_STEP_ENERGY};
use crate::config::scene::{Scene, SceneError};
use crate::config::units::Units;

/// `kT` must lie within this factor of the energy scale of the potential (either way): the
/// sums of kinetic and potential energy then keep about ten significant digits of each.
pub const TEMPERATURE_RATIO: f64 = 1e6;

/// Without an energy scale (hard cores only) `kT` must lie in this range: squared velocities
/// and kinetic energies then stay normal numbers with room to spare.
pub const TEMPERATURE_RANGE: [f64; 2] = [1e-100, 1e100];

/// Smallest `run.skin` as a fraction of the interaction reach: below it every distance of the
/// order of the reach costs more than a thousand neighbour-list rebuilds, and a skin below the
/// round-off of positions never lets simulated time advance.
pub const MIN_SKIN_FRACTION: f64 = 1e-3;

/// The scene's `output.max_bytes`, or the default.
pub fn max_bytes(scene: &Scene) -> u64 {
    scene.output.max_bytes.unwrap_or(DEFAULT_MAX_BYTES)
}

/// All the checks of this module that need only the scene.
///
/// # Errors
/// A [`SceneError`] naming the key.
pub fn check(scene: &Scene) -> Result<(), SceneError> {
    check_temperatures(scene)?;
    check_outputs(scene)
}

/// The energy scale of the scene's potentials (scene units): the smallest finite |ΔU| of any
/// step table, or the smallest well depth; `None` for hard cores only.
fn energy_scale(scene: &Scene) -> Option<f64> {
    let steps = scene
        .pair
        .iter()
        .flat_map(|p| p.steps.iter())
        .chain(scene.site_pair.iter().flat_map(|p| p.steps.iter()))
        .map(|s| s[1].abs());
    let depths = scene
        .pair
        .iter()
        .filter_map(|p| p.potential.map(|q| q.describe().well_depth().abs()));
    steps
        .chain(depths)
        .filter(|e| e.is_finite() && *e > 0.0)
        .min_by(f64::total_cmp)
}

/// `init.temperature` and `thermostat.temperature`: normal positive numbers within
/// [`TEMPERATURE_RATIO`] of the energy scale (or in [`TEMPERATURE_RANGE`]).
///
/// # Errors
/// A [`SceneError`] naming the key.
pub fn check_temperatures(scene: &Scene) -> Result<(), SceneError> {
    let units = Units::of(scene.units);
    let scale = energy_scale(scene);
    let temps = [
        ("init.temperature", Some(scene.init.temperature)),
        ("thermostat.temperature", scene.thermostat.temperature),
    ];
    for (key, t) in temps {
        let Some(t) = t else { continue };
        if !(t.is_normal() && t > 0.0) {
            return Err(SceneError::invalid(
                key,
                format!("must be a positive normal number, got {t:e}"),
            ));
        }
        // kT in the scene's energy unit.
        let kt = t * units.temperature / units.energy;
        let (lo, hi, what) = match scale {
            Some(e) => (
                e / TEMPERATURE_RATIO,
                e * TEMPERATURE_RATIO,
                format!(
                    "within a factor {} of the energy scale of the potential ({})",
                    short(TEMPERATURE_RATIO),
                    short(e)
                ),
            ),
            None => (
                TEMPERATURE_RANGE[0],
                TEMPERATURE_RANGE[1],
                format!(
                    "between {} and {} (hard cores have no energy scale)",
                    short(TEMPERATURE_RANGE[0]),
                    short(TEMPERATURE_RANGE[1])
                ),
            ),
        };
        if !(lo..=hi).contains(&kt) {
            return Err(SceneError::invalid(
                key,
                format!(
                    "{} is out of range: kT must be {what}, so that the energies keep their \
                     precision",
                    short(t)
                ),
            ));
        }
    }
    Ok(())
}

/// The sizes the outputs of a scene imply, against `output.max_bytes`.
///
/// # Errors
/// A [`SceneError`] naming the key and the estimate.
pub fn check_outputs(scene: &Scene) -> Result<(), SceneError> {
    let o = &scene.output;
    let max = max_bytes(scene);
    let limit = max as f64;
    let n = scene.n_bodies() as f64;
    let too_big = |key: String, what: String, bytes: f64, fix: &str| {
        SceneError::invalid(
            key,
            format!(
                "{what} would take about {} bytes, more than output.max_bytes = {}: {fix}, or \
                 raise output.max_bytes",
                short(bytes),
                short(limit)
            ),
        )
    };
    if let Some(dt) = o.sample_interval {
        for (name, spec) in [
            ("msd", &o.msd),
            ("vacf", &o.vacf),
            ("orientation_acf", &o.orientation_acf),
        ] {
            let Some(c) = spec else { continue };
            let lags = (c.max_lag / dt).round() + 1.0;
            // The buffers, and about 11 time origins of positions, velocities and axes.
            let bytes = lags * LAG_BYTES + 11.0 * n * 72.0;
            if bytes > limit {
                return Err(too_big(
                    format!("output.{name}.max_lag"),
                    format!(
                        "{} lags of output.sample_interval = {} in the correlation buffers",
                        short(lags),
                        short(dt)
                    ),
                    bytes,
                    "shorten the lag or lengthen the sample interval",
                ));
            }
        }
        if o.series
            && let Some(t) = scene.run.time
        {
            let rows = (t / dt).floor() + 1.0;
            let bytes = rows * SERIES_ROW_BYTES;
            if bytes > limit {
                return Err(too_big(
                    "output.series".to_owned(),
                    format!(
                        "{} rows (run.time = {} every output.sample_interval = {})",
                        short(rows),
                        short(t),
                        short(dt)
                    ),
                    bytes,
                    "lengthen output.sample_interval",
                ));
            }
        }
    }
    // Semi-flexible molecules are written as their atoms; rods and rigid site molecules with
    // their attitudes.
    let atoms = scene.has_bonds();
    let particles = if atoms {
        scene
            .species
            .iter()
            .map(|s| s.count as f64 * s.sites.as_ref().map_or(1, Vec::len) as f64)
            .sum()
    } else {
        n
    };
    let oriented = !atoms
        && (scene.has_sites()
            || scene
                .species
                .iter()
                .any(|s| s.inertia.is_some() || s.moments.is_some()));
    let what = if atoms { "atoms" } else { "bodies" };
    for (key, spec, frame_bytes) in [
        (
            "output.trajectory.interval",
            &o.trajectory,
            particles * trajectory_line_bytes(oriented, atoms) + 200.0,
        ),
        (
            "output.gsd.interval",
            &o.gsd,
            particles * GSD_PARTICLE_BYTES + GSD_FRAME_BYTES,
        ),
    ] {
        let (Some(tr), Some(t)) = (spec, scene.run.time) else {
            continue;
        };
        let frames = (t / tr.interval).floor() + 1.0;
        let bytes = frames * frame_bytes;
        if bytes > limit {
            return Err(too_big(
                key.to_owned(),
                format!(
                    "{} frames of {} {what} (run.time = {} every {})",
                    short(frames),
                    particles,
                    short(t),
                    short(tr.interval)
                ),
                bytes,
                "lengthen the interval",
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::short;

    #[test]
    fn numbers_in_short_form() {
        assert_eq!(short(8e15), "8e15");
        assert_eq!(short(2.8e9), "2.8e9");
        assert_eq!(short(0.001), "0.001");
        assert_eq!(short(150.0), "150");
        assert_eq!(short(1e-12), "1e-12");
        assert_eq!(short(4_000_000_000.0), "4e9");
        assert_eq!(short(1.2345e-7), "1.23e-7");
    }
}
