//! The `hold` example's command line, run in-process (its source is included as a module): one
//! line per queue with the ratio to `std::collections::BinaryHeap` last, and one message per bad
//! argument.

#[allow(dead_code)]
#[path = "../../examples/hold.rs"]
mod hold;

fn run(args: &str) -> Result<String, String> {
    let args: Vec<String> = args.split_whitespace().map(str::to_owned).collect();
    hold::parse(&args).and_then(|a| hold::report(&a))
}

#[test]
fn prints_one_line_per_queue_with_the_ratio_last() {
    for dist in ["exp", "uniform"] {
        let out = run(&format!("--size 500 --holds 20000 --reps 1 --dist {dist}")).unwrap();
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), 4, "{out}");
        assert!(lines[0].starts_with('#') && lines[0].contains(&format!("dist {dist}")));
        let last = |l: &str| l.split_whitespace().last().unwrap().parse::<f64>().unwrap();
        assert!(lines[1].starts_with("std BinaryHeap") && last(lines[1]) == 1.0);
        assert!(lines[3].contains("bounded"), "{}", lines[3]);
        for l in &lines[1..] {
            assert!(l.contains("holds/s"), "{l}");
            assert!(last(l) > 0.0 && last(l).is_finite(), "{l}");
        }
    }
}

#[test]
fn bad_arguments_get_a_clear_error() {
    let cases = [
        ("--dist gauss", "`--dist` is exp or uniform, not `gauss`"),
        ("--size ten", "`--size` expects a whole number, got `ten`"),
        ("--size 0", "must be at least 1"),
        ("--holds", "`--holds` needs a value"),
        ("--frobnicate 1", "unknown argument `--frobnicate`"),
    ];
    for (args, message) in cases {
        let err = run(args).unwrap_err();
        assert!(err.contains(message), "`{args}` gave `{err}`");
    }
}
