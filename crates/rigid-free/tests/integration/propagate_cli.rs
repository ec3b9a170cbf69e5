//! The `propagate` example's command line, run in-process (the example's source is included as
//! a module): output format, agreement with the library, and one message per bad argument.

#[allow(dead_code)]
#[path = "../../examples/propagate.rs"]
mod propagate;

fn run(args: &str) -> Result<String, String> {
    let args: Vec<String> = args.split_whitespace().map(str::to_owned).collect();
    propagate::run(&args)
}

fn numbers(line: &str, key: &str) -> Vec<f64> {
    let start = line.find(&format!("\"{key}\": [")).unwrap() + key.len() + 5;
    let end = start + line[start..].find(']').unwrap();
    line[start..end]
        .split(", ")
        .map(|s| s.parse().unwrap())
        .collect()
}

#[test]
fn prints_one_json_object_per_time_at_full_precision() {
    let out = run("--inertia 1.3,1.9,2.6 --omega 0.7,-1.1,1.9 --times 0,1,100").unwrap();
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 3);
    assert!(lines[0].starts_with("{\"t\": 0.0000000000000000e0, \"omega\": ["));
    assert_eq!(numbers(lines[0], "omega"), vec![0.7, -1.1, 1.9]);
    assert_eq!(
        numbers(lines[0], "P"),
        vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    );
    // t = 100 against the 40-digit reference (case `generic` of propagator-reference.txt).
    let p = numbers(lines[2], "P");
    let want_p00 = -0.152_125_682_027_295_3;
    assert_eq!(p.len(), 9);
    assert!((p[0] - want_p00).abs() < 1e-13, "{}", p[0]);
    // 17 significant digits: a mantissa with 16 decimals.
    let first = lines[2].split("\"P\": [").nth(1).unwrap();
    let mantissa = first.split('e').next().unwrap();
    assert_eq!(mantissa.trim_start_matches('-').len(), 18, "{mantissa}");
}

#[test]
fn a_zero_moment_is_a_rod() {
    let out = run("--inertia 0,1,1 --omega 3,1,1 --time 1").unwrap();
    assert_eq!(numbers(&out, "omega"), vec![0.0, 1.0, 1.0]);
}

#[test]
fn bad_arguments_get_a_clear_error() {
    for (args, want) in [
        (
            "--inertia -1,2,3 --omega 1,1,1 --time 1",
            "I1 = -1 is negative",
        ),
        (
            "--inertia 0,0,1 --omega 1,1,1 --time 1",
            "at most one moment",
        ),
        ("--inertia 0,1,2 --omega 1,1,1 --time 1", "must be equal"),
        (
            "--inertia 1,1,3 --omega 1,1,1 --time 1",
            "triangle inequality",
        ),
        (
            "--inertia NaN,1,1 --omega 1,1,1 --time 1",
            "not a finite number",
        ),
        (
            "--inertia 1,2,3 --omega 1,NaN,1 --time 1",
            "angular velocity",
        ),
        ("--inertia 1,2,3 --omega 1,1 --time 1", "exactly 3"),
        (
            "--inertia 1,2,3 --omega 1,x,1 --time 1",
            "`x` is not a number",
        ),
        ("--inertia 1,2,3 --omega 1,1,1 --time NaN", "time NaN"),
        (
            "--inertia 1,2,3 --omega 1,1,1",
            "--time or --times is required",
        ),
        (
            "--inertia 1,2,3 --omega 1,1,1 --time 1 --frobnicate",
            "unknown argument",
        ),
    ] {
        let e = run(args).unwrap_err();
        assert!(e.contains(want), "{args}: {e}");
    }
}
