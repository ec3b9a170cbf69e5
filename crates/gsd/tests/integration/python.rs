//! Exchange with the reference implementation, Python's `gsd.hoomd`, in both directions.
//!
//! Needs `python3` with the `gsd` and `numpy` packages (`python3 -m pip install gsd numpy`).
//! Without them the tests print why they skip and pass, unless the environment variable `CI`
//! is set, where they fail.

use std::path::{Path, PathBuf};
use std::process::Command;

use gsd::{Chunk, Frame, Reader, Shape, SimBox, Writer};

fn scripts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python")
}

fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("gsd-python-{}-{name}", std::process::id()))
}

/// Whether `import gsd.hoomd, numpy` works; without it, fails under CI and skips otherwise.
fn python_ready(test: &str) -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import gsd.hoomd, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        let why = "python3 cannot `import gsd.hoomd, numpy` (install them with \
                   `python3 -m pip install gsd numpy`)";
        assert!(std::env::var_os("CI").is_none(), "{test}: {why}");
        eprintln!("SKIPPED {test}: {why}");
    }
    ok
}

fn run_python(script: &str, args: &[&Path]) {
    let out = Command::new("python3")
        .arg(scripts().join(script))
        .args(args)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "{script} failed:\nstdout: {}\nstderr: {}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn json_list<T: ToString>(xs: impl IntoIterator<Item = T>) -> String {
    let items: Vec<String> = xs.into_iter().map(|x| x.to_string()).collect();
    format!("[{}]", items.join(","))
}

fn json_string(s: &str) -> String {
    // Test names are plain ASCII; escape the two characters that could still break JSON.
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

#[test]
fn python_reads_what_rust_writes() {
    if !python_ready("python_reads_what_rust_writes") {
        return;
    }
    let path = scratch("rust-written.gsd");
    let types = vec!["rod".to_string(), "sphere".to_string()];
    let shapes = vec![
        Shape::ConvexPolyhedron {
            rounding_radius: 0.5,
            vertices: vec![[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
        },
        Shape::Sphere { diameter: 1.0 },
    ];
    let n = 5;
    let mut frames = Vec::new();
    // 30 frames of 39 chunks, 30 of them logs with long names: the name list (1024 bytes) and
    // the index (128 entries) both move to larger blocks on the way.
    for k in 0..30_u32 {
        let position: Vec<[f32; 3]> = (0..n)
            .map(|i| {
                let x = i as f32 * 0.3 + k as f32 * 0.01;
                [x, -x / 3.0, (x * 1.7).sin()]
            })
            .collect();
        let orientation: Vec<[f32; 4]> = (0..n)
            .map(|i| {
                let h = 0.1 * (i + k as usize) as f32;
                [h.cos(), h.sin(), 0.0, 0.0]
            })
            .collect();
        let mut frame = Frame {
            step: 7 + 1000 * u64::from(k),
            sim_box: SimBox::orthorhombic(11.0, 12.5, 13.0 + k as f32),
            position,
            orientation: Some(orientation),
            velocity: Some(vec![[0.25, -0.5, 1.0]; n]),
            typeid: (0..n as u32).map(|i| i % 2).collect(),
            types: types.clone(),
            type_shapes: shapes.clone(),
            ..Frame::default()
        };
        frame
            .log
            .insert("time".into(), Chunk::scalar(0.1 * f64::from(k) + 1e-3));
        // gsd.hoomd reads only log keys that frame 0 has, so every frame logs the same.
        for j in 0..30_u32 {
            frame.log.insert(
                format!("quantity_with_a_name_long_enough_to_fill_the_list_{j:02}"),
                Chunk::scalar(j + k),
            );
        }
        frames.push(frame);
    }
    let mut writer = Writer::create(&path, "dmd gsd test").unwrap();
    for f in &frames {
        writer.append(f).unwrap();
    }
    writer.finish().unwrap();

    let mut expected = String::from("{\"application\":\"dmd gsd test\",\"frames\":[");
    for (k, f) in frames.iter().enumerate() {
        if k > 0 {
            expected.push(',');
        }
        let shapes: Vec<String> = f.type_shapes.iter().map(|s| s.to_json().unwrap()).collect();
        expected.push_str(&format!(
            "{{\"step\":{},\"N\":{},\"box_bits\":{},\"position_bits\":{},\"orientation_bits\":{},\
             \"typeid\":{},\"types\":{},\"type_shapes\":[{}],\"time_bits\":{}}}",
            f.step,
            f.n(),
            json_list(f.sim_box.to_array().map(f32::to_bits)),
            json_list(f.position.iter().flatten().map(|x| x.to_bits())),
            json_list(
                f.orientation
                    .as_ref()
                    .unwrap()
                    .iter()
                    .flatten()
                    .map(|x| x.to_bits())
            ),
            json_list(&f.typeid),
            json_list(f.types.iter().map(|s| json_string(s))),
            shapes.join(","),
            f.log["time"].as_scalar::<f64>().unwrap().to_bits(),
        ));
    }
    expected.push_str("]}");
    let expected_path = scratch("rust-written.json");
    std::fs::write(&expected_path, expected).unwrap();

    run_python("read_rust.py", &[&path, &expected_path]);
    std::fs::remove_file(&path).ok();
    std::fs::remove_file(&expected_path).ok();
}

#[test]
fn rust_reads_what_python_writes() {
    if !python_ready("rust_reads_what_python_writes") {
        return;
    }
    let path = scratch("python-written.gsd");
    run_python("write_python.py", &[&path]);

    let mut r = Reader::open(&path).unwrap();
    assert_eq!(r.schema(), "hoomd");
    assert_eq!(r.frames(), 3);
    assert!(r.application().starts_with("gsd.hoomd"));
    for k in 0..3_u64 {
        let f = r.read_frame(k).unwrap();
        // gsd.hoomd leaves out a step of 0 (the default) and the unchanged chunks of frames
        // 1 and 2; the reader restores them.
        assert_eq!(f.step, 1000 * k);
        assert_eq!(f.dimensions, 3);
        assert_eq!(f.sim_box, SimBox::orthorhombic(8.0, 9.0, 10.0));
        assert_eq!(f.n(), 4);
        let expected: Vec<[f32; 3]> = (0..4)
            .map(|i| [0.5 * i as f32 + k as f32, -0.25 * i as f32, 1.0 + i as f32])
            .collect();
        assert_eq!(f.position, expected);
        let mut q = vec![[1.0, 0.0, 0.0, 0.0]; 4];
        q[1] = [0.0, 1.0, 0.0, 0.0];
        assert_eq!(f.orientation, Some(q));
        assert_eq!(f.velocity, None);
        assert_eq!(f.typeid, [0, 1, 0, 1]);
        assert_eq!(f.types, ["A", "B"]);
        assert_eq!(
            f.type_shapes,
            [
                Shape::Sphere { diameter: 1.0 },
                Shape::ConvexPolyhedron {
                    rounding_radius: 0.125,
                    vertices: vec![
                        [0.5, 0.5, 0.5],
                        [0.5, -0.5, -0.5],
                        [-0.5, 0.5, -0.5],
                        [-0.5, -0.5, 0.5]
                    ],
                }
            ]
        );
        assert_eq!(f.log["time"].as_scalar::<f64>(), Some(0.125 * k as f64));
    }
    // Frames 1 and 2 store positions but take the type names from frame 0.
    assert!(r.chunk_info(2, "particles/position").is_some());
    assert!(r.chunk_info(2, "particles/types").is_none());
    let types = r.read_chunk::<i8>(2, "particles/types").unwrap();
    assert_eq!((types.n, types.frame), (2, 0));
    std::fs::remove_file(&path).ok();
}
