//! The `[smd]` keys: the standard-MD engine's time step, list skin and smoothing window, their
//! defaults, and the keys of a scene that engine cannot honour (refused when the scene is read)
//! or does not use (listed in its summary).

use glam::DVec3;

use crate::analysis::output::given;
use crate::config::scene::{
    Engine, PotentialSpec, QueueKind, Scene, SceneError, ThermostatKind, ThermostatPhase,
};

/// The default smoothing window: 003 Eq. 26's `r_l = 2.5σ`, `r_u = 3σ`, shifted outwards by
/// the contact distance beyond σ (Gay–Berne's end-to-end κσ₀), so that the potential is cut
/// where its tail is as small as the Lennard-Jones one at 2.5σ in every orientation. A kind
/// that vanishes beyond a cut-off of its own (SSD/E's switch to 9 Å, SPC/E's site cut-off)
/// gives its own window, and is not smoothed again.
pub fn default_window(p: &PotentialSpec) -> (f64, f64) {
    if let Some(own) = p.describe().own_window() {
        return own;
    }
    let (sigma, contact) = p.describe().lengths();
    (contact + 1.5 * sigma, contact + 2.0 * sigma)
}

/// The default time step of SSD/E water: 2 fs (in ps), the longest round step that meets the
/// energy criterion of docs/PERFORMANCE.md, std(E)/std(U) ≤ 1 % in NVE production. Measured
/// on `scenes/water-ssd.toml` with 1000 molecules (298.15 K): after 10 ps of equilibration, 1 ps
/// of production gives 0.20 % at 1 fs, 0.84 % at 2 fs, 1.4 % at 2.5 fs (the `dt²` of the
/// splitting); right after the lattice melts (0.2 ps + 0.2 ps) the still relaxing `U`
/// fluctuates more and the ratios are lower, 0.023, 0.092, 0.38, 0.84 % at 0.5, 1, 2, 3 fs.
/// 2 fs costs 2.4 CPU s per simulated ps.
pub const SSD_E_DT: f64 = 0.002;

/// The default time step: `0.0028 σ √(m / max(kT, ε))`, and for rods at most `√(I / kT)/30`.
/// For the paper's rods (σ = 3.035 Å, m = 18 g/mol, kT = 4.2 kJ/mol, I = 1.154 g/mol·Å²) both
/// give 1.75 fs, close to 003 §V.B's 1.8 fs; for Lennard-Jones at T* = 1 it is 0.0028.
/// SSD/E water: [`SSD_E_DT`], measured.
pub fn default_dt(p: &PotentialSpec, mass: f64, inertia: Option<f64>, kt: f64) -> f64 {
    if let Some(dt) = p.describe().smd_dt() {
        return dt;
    }
    let (sigma, _) = p.describe().lengths();
    let e = kt.max(p.describe().well_depth());
    let dt = 0.0028 * sigma * (mass / e).sqrt();
    match inertia {
        Some(i) => dt.min((i / e).sqrt() / 30.0),
        None => dt,
    }
}

/// The checks of an smd scene that need no set-up (called by the scene's checks): the
/// `[smd]` values, and the keys the standard-MD engine cannot honour.
///
/// # Errors
/// [`SceneError::Invalid`] naming the key.
pub fn check(scene: &Scene) -> Result<(), SceneError> {
    if let Some(s) = &scene.smd {
        let positive = |key: &str, x: Option<f64>| match x {
            Some(v) if !(v.is_finite() && v > 0.0) => Err(SceneError::invalid(
                key,
                format!("must be a positive finite number, got {}", given(v)),
            )),
            _ => Ok(()),
        };
        positive("smd.dt", s.dt)?;
        positive("smd.skin", s.skin)?;
        if let Some(g) = s.guard
            && (g.is_nan() || g <= 0.0)
        {
            return Err(SceneError::invalid(
                "smd.guard",
                format!("must be a positive fraction or inf, got {}", given(g)),
            ));
        }
        if let Some(w) = s.smoothing {
            positive("smd.smoothing.r_l", w.r_l)?;
            positive("smd.smoothing.r_u", w.r_u)?;
        }
    }
    if let Some(sw) = &scene.sweep
        && sw.key == "engine"
    {
        return Err(SceneError::invalid(
            "sweep.key",
            "`engine` cannot be swept (sweeps run event-driven); run the scene once per engine \
             with --engine",
        ));
    }
    if scene.engine != Engine::Smd {
        return Ok(());
    }
    let refuse = |key: &str, why: &str| {
        Err(SceneError::invalid(
            key,
            format!("not available with engine = \"smd\": {why}"),
        ))
    };
    if scene.hmc.is_some() {
        return refuse(
            "hmc",
            "hybrid Monte Carlo chains are built of event-driven segments",
        );
    }
    if scene.chains.is_some() {
        return refuse(
            "chains",
            "run independent chains with the event-driven engine, or run the smd scene once \
             per seed",
        );
    }
    if scene.sweep.is_some() {
        return refuse(
            "sweep",
            "sweeps run with the event-driven engine; run the smd scene once per value with \
             --set",
        );
    }
    if scene.has_sites() {
        return refuse(
            "species",
            "site molecules interact through hard cores and square wells between their sites, \
             which have no continuous force; run them with the event-driven engine",
        );
    }
    if let Some(p) = scene.pair.first().and_then(|p| p.potential)
        && p.is_rigid()
        && let Some((r_switch, r_cut)) = p.describe().own_window()
        && scene.smd.as_ref().is_some_and(|s| s.smoothing.is_some())
    {
        return refuse(
            "smd.smoothing",
            &format!(
                "`{}` switches itself off between {r_switch} and {r_cut} {} and is \
                 integrated as it is, not smoothed again; remove the key",
                p.kind(),
                crate::config::units::UnitNames::of(scene.units).length
            ),
        );
    }
    if scene.pair.is_empty() {
        return refuse(
            "pair",
            "standard MD needs a `[[pair]]` table with a smooth `potential`",
        );
    }
    if scene.species.len() > 1 {
        return refuse(
            "species",
            "the standard-MD engine simulates one species (all bodies alike)",
        );
    }
    for (k, p) in scene.pair.iter().enumerate() {
        if p.potential.is_none() {
            return refuse(
                &format!("pair[{k}].steps"),
                "a stepped potential (hard core, square well) has no continuous force; give \
                 a smooth `potential` (rods, lennard-jones, gay-berne)",
            );
        }
    }
    if scene.output.gsd.is_some() {
        return refuse(
            "output.gsd",
            "the smd engine writes trajectory.xyz (output.trajectory) only",
        );
    }
    if scene.run.events.is_some() {
        return refuse(
            "run.events",
            "standard MD has no events; give the production length as run.time",
        );
    }
    if scene.run.equilibration_events > 0 {
        return refuse(
            "run.equilibration_events",
            "standard MD has no events; give run.equilibration_time",
        );
    }
    if scene.thermostat.kind == ThermostatKind::Andersen
        && scene.thermostat.during == ThermostatPhase::Always
    {
        return refuse(
            "thermostat.during",
            "production is NVE (the smd engine thermostats by velocity rescaling during \
             equilibration only); use `during = \"equilibration\"`",
        );
    }
    if scene.thermostat.rescale_at_end == Some(false) {
        return refuse(
            "thermostat.rescale_at_end",
            "the smd engine thermostats by velocity rescaling, whose last rescaling ends \
             equilibration at the bath temperature; remove the key",
        );
    }
    let pot = scene.pair[0].potential.expect("checked above");
    let (r_l, r_u) = window(scene, &pot);
    if r_l >= r_u {
        return Err(SceneError::invalid(
            "smd.smoothing.r_l",
            format!("r_l = {r_l} must be less than r_u = {r_u}"),
        ));
    }
    // The box, when the scene fixes it (else its file does, checked at the run).
    if let Some(lengths) = crate::config::init::box_lengths(scene) {
        list_skin(
            &pot,
            (r_l, r_u),
            scene.smd.as_ref().and_then(|s| s.skin),
            lengths,
        )?;
    }
    Ok(())
}

/// The smoothing window of a scene: `[smd.smoothing]` or [`default_window`].
pub fn window(scene: &Scene, pot: &PotentialSpec) -> (f64, f64) {
    let (dl, du) = default_window(pot);
    let w = scene
        .smd
        .as_ref()
        .and_then(|s| s.smoothing)
        .unwrap_or_default();
    (w.r_l.unwrap_or(dl), w.r_u.unwrap_or(du))
}

/// The Verlet-list skin in a box of edges `lengths`: `skin` if given, else 0.6σ (the measured
/// optimum is flat about it) or what fits a small box.
///
/// # Errors
/// [`SceneError::Invalid`] naming `smd.smoothing.r_u` (`box` for a kind whose cut-off is its
/// own, such as the water models) or `smd.skin` if the list radius `r_u + skin` reaches half the shortest box side
/// (minimum image).
pub fn list_skin(
    pot: &PotentialSpec,
    (_, r_u): (f64, f64),
    skin: Option<f64>,
    lengths: DVec3,
) -> Result<f64, SceneError> {
    let half = 0.5 * lengths.min_element();
    if r_u >= half && pot.describe().own_window().is_some() {
        // The potential's cut-off is its own, not a key of the scene.
        return Err(SceneError::invalid(
            "box",
            format!(
                "the cut-off {r_u} of `{}` reaches half the shortest box side {half}: a body \
                 would interact with two images of another; use more bodies or a lower \
                 density",
                pot.kind()
            ),
        ));
    }
    if r_u >= half {
        return Err(SceneError::invalid(
            "smd.smoothing.r_u",
            format!(
                "the cut-off {r_u} reaches half the shortest box side {half}: a body would \
                 interact with two images of another; use more bodies, a lower density or a \
                 smaller r_u"
            ),
        ));
    }
    match skin {
        Some(d) if r_u + d >= half => Err(SceneError::invalid(
            "smd.skin",
            format!(
                "{d} is too large: the list radius r_u + skin must stay below half the \
                 shortest box side {half}, so the skin must be below {}",
                half - r_u
            ),
        )),
        Some(d) => Ok(d),
        None => Ok((0.6 * pot.describe().lengths().0).min(0.9 * (half - r_u))),
    }
}

/// The keys of a scene that the standard-MD engine does not use.
pub fn ignored_keys(scene: &Scene) -> Vec<String> {
    let mut keys: Vec<String> = scene
        .pair
        .iter()
        .enumerate()
        .filter(|(_, p)| p.terraces.is_some())
        .map(|(k, _)| format!("pair[{k}].terraces"))
        .collect();
    if scene.search.is_some() {
        keys.push("search".to_owned());
    }
    if scene.run.queue != QueueKind::default() {
        keys.push("run.queue".to_owned());
    }
    if scene.run.rebase_events.is_some() {
        keys.push("run.rebase_events".to_owned());
    }
    if scene.run.skin.is_some() {
        keys.push("run.skin (the smd skin is smd.skin)".to_owned());
    }
    keys
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_for_the_papers_rods_and_lennard_jones() {
        // Internal units (Å, g/mol, ps, 10 J/mol): ε = 300, kT = 1.4 ε = 420.
        let rods = PotentialSpec::Rods(crate::config::scene::LjRodsSpec {
            epsilon: 300.0,
            sigma: 3.035,
            zeta: 1.0,
        });
        let dt = default_dt(&rods, 18.0, Some(1.154), 420.0);
        assert!((dt - 0.00175).abs() < 0.00002, "dt = {dt} ps");
        assert_eq!(default_window(&rods), (2.5 * 3.035, 3.0 * 3.035));
        let lj = PotentialSpec::LennardJones(crate::config::scene::LennardJonesSpec {
            epsilon: 1.0,
            sigma: 1.0,
        });
        // At T* = 1 the energy scale is ε; at T* = 4 it is kT.
        assert_eq!(default_dt(&lj, 1.0, None, 1.0), 0.0028);
        assert_eq!(default_dt(&lj, 1.0, None, 4.0), 0.0014);
        assert_eq!(default_window(&lj), (2.5, 3.0));
    }
}
