//! Propagates one free rigid body and prints the state as JSON lines.
//!
//! ```text
//! cargo run --release -p rigid-free --example propagate -- \
//!     --inertia I1,I2,I3 --omega w1,w2,w3 (--time t | --times t1,t2,...)
//! ```
//!
//! With `A(0)` = identity, prints one object per time:
//! `{"t": t, "omega": [body-frame ω(t)], "P": [row-major P(t) = A(t) A(0)ᵀ]}`, 17 significant
//! digits. A zero moment makes a linear rotor (the other two must be equal); its spin about the
//! rod axis is decoupled and dropped, so that component of ω prints as 0.

use glam::{DMat3, DVec3};
use rigid_free::{FreeMotion, Moments};
use std::process::ExitCode;

const USAGE: &str =
    "usage: propagate --inertia I1,I2,I3 --omega w1,w2,w3 (--time t | --times t1,t2,...)";

fn parse_list(flag: &str, text: &str) -> Result<Vec<f64>, String> {
    text.split(',')
        .map(|s| {
            let s = s.trim();
            s.parse::<f64>()
                .map_err(|_| format!("{flag}: `{s}` is not a number"))
        })
        .collect()
}

fn parse3(flag: &str, text: &str) -> Result<[f64; 3], String> {
    let v = parse_list(flag, text)?;
    <[f64; 3]>::try_from(v.as_slice()).map_err(|_| {
        format!(
            "{flag} needs exactly 3 comma-separated numbers, got {}",
            v.len()
        )
    })
}

pub(crate) fn run(args: &[String]) -> Result<String, String> {
    let (mut inertia, mut omega, mut times) = (None, None, None);
    let mut it = args.iter();
    while let Some(flag) = it.next() {
        let mut value = || {
            it.next()
                .ok_or_else(|| format!("{flag} needs a value\n{USAGE}"))
        };
        match flag.as_str() {
            "--inertia" => inertia = Some(parse3(flag, value()?)?),
            "--omega" => omega = Some(parse3(flag, value()?)?),
            "--time" | "--times" => {
                if times.is_some() {
                    return Err("give either --time or --times, once".to_owned());
                }
                times = Some(parse_list(flag, value()?)?);
            }
            "-h" | "--help" => return Ok(format!("{USAGE}\n")),
            other => return Err(format!("unknown argument `{other}`\n{USAGE}")),
        }
    }
    let inertia = inertia.ok_or(format!("--inertia is required\n{USAGE}"))?;
    let omega = omega.ok_or(format!("--omega is required\n{USAGE}"))?;
    let times = times.ok_or(format!("--time or --times is required\n{USAGE}"))?;
    if let Some(t) = times.iter().find(|t| !t.is_finite()) {
        return Err(format!("time {t} is not a finite number"));
    }
    let moments = Moments::new(inertia).map_err(|e| e.to_string())?;
    let motion = FreeMotion::new(&moments, DMat3::IDENTITY, DVec3::from(omega))
        .map_err(|e| e.to_string())?;
    let mut out = String::new();
    let num = |x: f64| format!("{x:.16e}");
    for &t in &times {
        let w = motion.omega(t);
        let p = motion.propagator(t);
        let rows: Vec<String> = (0..3)
            .flat_map(|r| (0..3).map(move |c| (r, c)))
            .map(|(r, c)| num(p.col(c)[r]))
            .collect();
        out += &format!(
            "{{\"t\": {}, \"omega\": [{}, {}, {}], \"P\": [{}]}}\n",
            num(t),
            num(w.x),
            num(w.y),
            num(w.z),
            rows.join(", ")
        );
    }
    Ok(out)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
