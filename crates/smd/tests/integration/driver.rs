//! The one-call driver: parameters in, observables and a summary out.

use potential::{LennardJones, Smoothed};
use smd::run::{CorrelationConfig, RdfConfig, RunConfig, run};
use smd::{BodyModel, Settings, Setup, SmdError};

fn config() -> RunConfig {
    RunConfig {
        setup: Setup::new(256, 0.5, BodyModel::sphere(1.0).unwrap(), 2.0),
        settings: Settings::new(0.005, 0.6),
        equilibration_steps: 200,
        rescale_every: 20,
        production_steps: 400,
        sample_every: 4,
        rdf: Some(RdfConfig {
            every: 5,
            ..RdfConfig::default()
        }),
        correlations: Some(CorrelationConfig {
            max_lag: 0.5,
            origin_every: 5,
        }),
    }
}

#[test]
fn a_run_from_parameters_returns_every_observable() {
    let lj = Smoothed::paper(LennardJones::new(1.0, 1.0).unwrap(), 1.0).unwrap();
    let out = run(&config(), lj).unwrap();
    assert_eq!(out.observables.series.len(), 101);
    assert_eq!(out.observables.rdf.as_ref().unwrap().samples(), 21);
    let c = out.observables.correlations.as_ref().unwrap();
    // 0.5 τ of lags at 0.02 τ per sample: lags 0..=25.
    assert_eq!(c.msd().len(), 26);
    assert!((c.vacf_normalised()[0].1 - 1.0).abs() < 1e-12);
    // Equilibrated at T* = 2: the NVE mean stays close.
    let s = out.summary;
    assert!(
        (s.temperature.mean - 2.0).abs() < 0.1,
        "{:?}",
        s.temperature
    );
    assert!(s.pressure.mean > 0.5 && s.potential_per_body.mean < -2.0);
    assert!(s.fluctuation_over_potential_std < 0.05);
    assert_eq!((out.equilibration.steps, out.production.steps), (200, 400));
    assert_eq!(out.system.n(), 256);
}

#[test]
fn bad_driver_inputs_are_errors() {
    let lj = Smoothed::paper(LennardJones::new(1.0, 1.0).unwrap(), 1.0).unwrap();
    let mut c = config();
    c.rdf = Some(RdfConfig {
        r_max: Some(10.0),
        ..RdfConfig::default()
    });
    assert!(matches!(
        run(&c, lj),
        Err(SmdError::Parameter {
            name: "rdf r_max",
            ..
        })
    ));
    let mut c = config();
    c.sample_every = 0;
    assert!(matches!(run(&c, lj), Err(SmdError::Count { .. })));
    let mut c = config();
    c.settings.dt = f64::NAN;
    assert!(run(&c, lj).unwrap_err().to_string().contains("dt"));
    let mut c = config();
    c.setup.n = 64; // L = 5: too small for r_u + skin = 3.6
    assert!(matches!(run(&c, lj), Err(SmdError::BoxTooSmall { .. })));
}
