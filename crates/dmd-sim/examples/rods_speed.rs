//! Events per second of the rods, for docs/PERFORMANCE.md: the paper's scene and the gas state
//! point, with virtual events on and off and on the bounded queue, the calendar queue, the
//! binary heap and the tournament tree, all in one run (interleaved, so that the load of the
//! shared machine hits every variant alike).
//!
//! ```sh
//! cargo run --release -p dmd-sim --example rods_speed -- [--repeats 3] [--time 4] [--gas-time 100] [--n 512]
//! ```
//!
//! `--n` scales the paper's scene to another number of rods at the same density (the gas too).
//!
//! Each variant runs `repeats` times (seeds 1, 2, …) after its own equilibration; the table
//! gives medians of pair events (crossings and reflections) and of all events (with virtual
//! events and neighbour-list shell crossings) per CPU second of production, and the ratio of
//! pair events per CPU second to the first variant (bounded queue, virtual events on).

use std::path::Path;

use dmd_sim::run::{Quiet, Summary, run_scene};
use dmd_sim::scene::Scene;

const PAPER: &str = include_str!("../../../scenes/rods-paper.toml");

fn main() {
    let mut repeats = 3;
    let mut time = 4.0;
    let mut gas_time = 100.0;
    let mut n = 512u64;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let v = it.next().unwrap_or_default();
        match a.as_str() {
            "--repeats" => repeats = v.parse().expect("--repeats N"),
            "--time" => time = v.parse().expect("--time PS"),
            "--gas-time" => gas_time = v.parse().expect("--gas-time PS"),
            "--n" => n = v.parse().expect("--n RODS"),
            _ => panic!("unknown argument {a}"),
        }
    }
    let gas = [
        format!("init.temperature={}", 10.0 / 1.4 * 505.144),
        "box.density=0.000357707612".to_owned(),
    ];
    let variants: Vec<(&str, &str, Vec<String>)> = vec![
        (
            "paper",
            "bounded queue, virtual events",
            vec!["run.queue=bounded".to_owned()],
        ),
        (
            "paper",
            "calendar queue (default)",
            vec!["run.queue=calendar".to_owned()],
        ),
        ("paper", "binary heap", vec!["run.queue=heap".to_owned()]),
        (
            "paper",
            "tournament tree",
            vec!["run.queue=tournament".to_owned()],
        ),
        (
            "paper",
            "no virtual events (window ∞)",
            vec!["search.window=inf".to_owned()],
        ),
        (
            "paper",
            "no virtual events, binary heap",
            vec!["search.window=inf".to_owned(), "run.queue=heap".to_owned()],
        ),
        ("gas", "bounded queue, virtual events", {
            let mut g = gas.to_vec();
            g.push("run.queue=bounded".to_owned());
            g
        }),
        ("gas", "binary heap", {
            let mut g = gas.to_vec();
            g.push("run.queue=heap".to_owned());
            g
        }),
        ("gas", "no virtual events (window ∞)", {
            let mut g = gas.to_vec();
            g.push("search.window=inf".to_owned());
            g
        }),
    ];
    // results[variant] = (pair events per CPU s, all events per CPU s, events per ps)
    let mut results: Vec<Vec<(f64, f64, f64)>> = vec![Vec::new(); variants.len()];
    for r in 0..repeats {
        for (k, (state, _, o)) in variants.iter().enumerate() {
            let t = if *state == "gas" { gas_time } else { time };
            let mut o = o.clone();
            o.extend(
                [
                    "output.rdf=",
                    "output.msd=",
                    "output.vacf=",
                    "output.orientation_acf=",
                    "output.series=false",
                ]
                .iter()
                .map(|s| (*s).to_owned()),
            );
            o.push(format!("run.time={t}"));
            o.push(format!(
                "run.equilibration_time={}",
                if *state == "gas" { 10.0 } else { 2.0 }
            ));
            o.push(format!("seed={}", r + 1));
            o.push(format!("species.0.count={n}"));
            if (n as f64).cbrt().fract() != 0.0 {
                o.push("init.positions=fcc".to_owned());
            }
            let s = run(&o);
            let pe = (s.terrace_crossings + s.reflections) as f64;
            results[k].push((
                pe / s.cpu_seconds,
                s.events_per_cpu_second,
                s.pair_event_rate(),
            ));
            eprintln!(
                "{state} {}: {:.3e} pair events per CPU s",
                variants[k].1,
                pe / s.cpu_seconds
            );
        }
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "| state | variant | events per ps | pair events per CPU s | all events per CPU s | vs bounded queue |"
    );
    println!("|---|---|---|---|---|---|");
    // The reference of each state is its first variant (the bounded queue).
    let mut reference = 0.0;
    for (k, (state, name, _)) in variants.iter().enumerate() {
        let pe = median(results[k].iter().map(|x| x.0).collect());
        let all = median(results[k].iter().map(|x| x.1).collect());
        let rate = median(results[k].iter().map(|x| x.2).collect());
        if name.starts_with("bounded queue") {
            reference = pe;
        }
        println!(
            "| {state} | {name} | {rate:.3e} | {pe:.3e} | {all:.3e} | {:.2} |",
            pe / reference
        );
    }
}

fn run(overrides: &[String]) -> Summary {
    let scene = Scene::from_str_with(PAPER, overrides).unwrap_or_else(|e| panic!("{e}"));
    run_scene(&scene, Path::new("."), None, &mut Quiet).unwrap_or_else(|e| panic!("{e}"))
}
