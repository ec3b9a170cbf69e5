//! Rust writes, Rust reads: values bit for bit, the frame-0 fallback, growth of the index and
//! the name list, reading while the writer is open, appending to an existing file, and the
//! errors of the typed API.

use std::path::PathBuf;

use gsd::{Chunk, Error, Frame, Reader, Shape, SimBox, Type, Writer};

fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("gsd-roundtrip-{}-{name}", std::process::id()))
}

/// Awkward floats: signed zero, subnormals, extremes, infinities, a NaN with a payload.
const ODD: [f32; 8] = [
    -0.0,
    1.0e-45,
    -1.17e-38,
    f32::MAX,
    f32::NEG_INFINITY,
    f32::INFINITY,
    0.1,
    -3.5,
];

fn odd(i: usize) -> f32 {
    if i % 9 == 8 {
        f32::from_bits(0x7fc0_1234)
    } else {
        ODD[i % 8]
    }
}

fn frame(k: u64, n: usize) -> Frame {
    let mut f = Frame {
        step: k * 10,
        dimensions: 3,
        sim_box: SimBox {
            lx: 10.0,
            ly: 11.0,
            lz: 12.0,
            xy: 0.1,
            xz: -0.2,
            yz: 0.3,
        },
        position: (0..n)
            .map(|i| [odd(i + k as usize), i as f32, -(k as f32)])
            .collect(),
        orientation: Some((0..n).map(|i| [odd(i), 0.5, -0.5, odd(i + 3)]).collect()),
        velocity: Some((0..n).map(|i| [odd(i + 1), odd(i + 2), 1.0]).collect()),
        angmom: Some((0..n).map(|i| [0.0, odd(i + 5), 2.0, k as f32]).collect()),
        image: Some(
            (0..n as i32)
                .map(|i| [i - 1, i32::MIN + i, i32::MAX - k as i32])
                .collect(),
        ),
        typeid: (0..n as u32).map(|i| i % 3).collect(),
        types: vec!["A".into(), "rod".into(), "benzene-like".into()],
        type_shapes: vec![
            Shape::Sphere { diameter: 1.0 },
            Shape::Ellipsoid {
                a: 2.0,
                b: 0.5,
                c: 0.5,
            },
            Shape::Undefined,
        ],
        log: Default::default(),
    };
    f.log.insert("time".into(), Chunk::scalar(k as f64 * 0.1));
    f.log
        .insert("events".into(), Chunk::column(vec![k, k + 1, u64::MAX]));
    f.log.insert(
        "pressure_tensor".into(),
        Chunk::rows(vec![1.0_f64, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], 3).unwrap(),
    );
    f.log.insert("flags".into(), Chunk::scalar(-7_i16));
    f
}

/// f32 rows compared by bits (NaN == NaN with the same payload, -0 != +0).
fn bits<const K: usize>(rows: &[[f32; K]]) -> Vec<u32> {
    rows.iter().flatten().map(|x| x.to_bits()).collect()
}

fn assert_same(a: &Frame, b: &Frame) {
    assert_eq!(a.step, b.step);
    assert_eq!(a.dimensions, b.dimensions);
    assert_eq!(a.sim_box, b.sim_box);
    assert_eq!(bits(&a.position), bits(&b.position));
    assert_eq!(
        a.orientation.as_deref().map(bits),
        b.orientation.as_deref().map(bits)
    );
    assert_eq!(
        a.velocity.as_deref().map(bits),
        b.velocity.as_deref().map(bits)
    );
    assert_eq!(a.angmom.as_deref().map(bits), b.angmom.as_deref().map(bits));
    assert_eq!(a.image, b.image);
    assert_eq!(a.typeid, b.typeid);
    assert_eq!(a.types, b.types);
    assert_eq!(a.type_shapes, b.type_shapes);
    assert_eq!(a.log, b.log);
}

#[test]
fn frames_read_back_bit_for_bit_past_index_and_name_list_growth() {
    let path = scratch("many.gsd");
    let mut w = Writer::create(&path, "roundtrip").unwrap();
    // 12 chunks per frame: the initial index of 128 entries is outgrown at frame 10 and again
    // later; 60 long log names outgrow the initial 1024-byte name list.
    let frames: Vec<Frame> = (0..70)
        .map(|k| {
            let mut f = frame(k, 17);
            f.log.insert(
                format!("a_rather_long_name_for_a_quantity_number_{k:03}"),
                Chunk::scalar(k as u32),
            );
            f
        })
        .collect();
    for f in &frames {
        w.append(f).unwrap();
    }
    assert_eq!(w.frames(), 70);
    w.finish().unwrap();

    let mut r = Reader::open(&path).unwrap();
    assert_eq!(r.frames(), 70);
    assert_eq!(r.application(), "roundtrip");
    assert_eq!((r.schema(), r.schema_version()), ("hoomd", (1, 4)));
    assert_eq!(r.file_version(), (2, 0));
    assert!(r.chunk_names().iter().any(|s| s == "particles/angmom"));
    for (k, f) in frames.iter().enumerate() {
        let got = r.read_frame(k as u64).unwrap();
        // A log name stored in one frame only is read in that frame (and, by the schema's
        // rule, in the frames that fall back on frame 0 for it, i.e. all for frame 0's).
        let mut want = f.clone();
        want.log.insert(
            "a_rather_long_name_for_a_quantity_number_000".into(),
            Chunk::scalar(0_u32),
        );
        assert_same(&got, &want);
    }
    let p = r.read_chunk::<f32>(69, "particles/position").unwrap();
    assert_eq!((p.n, p.m, p.frame), (17, 3, 69));
    assert_eq!(
        p.data.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
        bits(&frames[69].position)
    );
    std::fs::remove_file(&path).ok();
}

#[test]
fn unchanged_chunks_are_stored_once_and_read_from_frame_0() {
    let path = scratch("fallback.gsd");
    let mut w = Writer::create(&path, "fallback").unwrap();
    let f0 = frame(0, 4);
    let mut f1 = frame(1, 4);
    f1.orientation = None; // "as in frame 0"
    let mut f2 = frame(2, 6); // N changes: per-particle fallbacks stop
    f2.orientation = None;
    f2.sim_box = SimBox::cubic(20.0);
    for f in [&f0, &f1, &f2] {
        w.append(f).unwrap();
    }
    drop(w);

    let mut r = Reader::open(&path).unwrap();
    for name in [
        "configuration/dimensions",
        "configuration/box",
        "particles/N",
        "particles/typeid",
        "particles/types",
        "particles/type_shapes",
        "particles/orientation",
    ] {
        assert!(r.chunk_info(0, name).is_some(), "{name} in frame 0");
        assert!(
            r.chunk_info(1, name).is_none(),
            "{name} left out of frame 1"
        );
    }
    assert!(r.chunk_info(2, "configuration/box").is_some());
    assert!(r.chunk_info(2, "particles/N").is_some());
    assert!(r.chunk_info(2, "particles/typeid").is_some());
    assert!(r.chunk_info(2, "particles/types").is_none());

    let g1 = r.read_frame(1).unwrap();
    assert_eq!(
        g1.orientation.as_deref().map(bits),
        f0.orientation.as_deref().map(bits)
    );
    assert_eq!(g1.types, f0.types);
    assert_eq!(g1.sim_box, f0.sim_box);
    let q = r.read_chunk::<f32>(1, "particles/orientation").unwrap();
    assert_eq!(q.frame, 0);

    let g2 = r.read_frame(2).unwrap();
    assert_eq!(g2.n(), 6);
    assert_eq!(
        g2.orientation, None,
        "frame 0's orientations are for 4 particles"
    );
    assert_eq!(g2.sim_box, SimBox::cubic(20.0));
    assert_eq!(g2.types, f0.types);
    assert_eq!(g2.typeid, f2.typeid);
    std::fs::remove_file(&path).ok();
}

#[test]
fn a_file_reads_while_its_writer_is_open_and_appends_after_reopening() {
    let path = scratch("live.gsd");
    let mut w = Writer::create(&path, "live").unwrap();
    assert_eq!(Reader::open(&path).unwrap().frames(), 0);
    for k in 0..3 {
        w.append(&frame(k, 5)).unwrap();
        let mut r = Reader::open(&path).unwrap();
        assert_eq!(r.frames(), k + 1);
        assert_same(&r.read_frame(k).unwrap(), &frame(k, 5));
    }
    w.flush().unwrap();
    drop(w);

    let mut w = Writer::append_to(&path).unwrap();
    assert_eq!(w.frames(), 3);
    let mut f3 = frame(3, 5);
    f3.log.insert("new".into(), Chunk::scalar(1.5_f32));
    w.append(&f3).unwrap();
    w.finish().unwrap();

    let mut r = Reader::open(&path).unwrap();
    assert_eq!(r.frames(), 4);
    for k in 0..3 {
        assert_same(&r.read_frame(k).unwrap(), &frame(k, 5));
    }
    assert_same(&r.read_frame(3).unwrap(), &f3);
    // The reopened writer knew frame 0 and left the unchanged type names out.
    assert!(r.chunk_info(3, "particles/types").is_none());
    std::fs::remove_file(&path).ok();
}

#[test]
fn typed_reads_report_wrong_types_missing_chunks_and_frames() {
    let path = scratch("errors.gsd");
    let mut w = Writer::create(&path, "errors").unwrap();
    let mut f = frame(0, 3);
    f.velocity = None;
    w.append(&f).unwrap();
    drop(w);
    let mut r = Reader::open(&path).unwrap();
    assert!(matches!(
        r.read_chunk::<f64>(0, "particles/position"),
        Err(Error::WrongType {
            expected: Type::F64,
            found: Type::F32,
            ..
        })
    ));
    let e = r.read_chunk::<f32>(0, "particles/velocity").unwrap_err();
    assert!(matches!(e, Error::MissingChunk { frame: 0, .. }), "{e}");
    assert!(e.to_string().contains("particles/velocity"));
    assert!(matches!(
        r.read_chunk::<f32>(1, "particles/position"),
        Err(Error::FrameOutOfRange {
            frame: 1,
            frames: 1
        })
    ));
    assert!(matches!(
        r.read_frame(5),
        Err(Error::FrameOutOfRange { .. })
    ));
    let step = r.read_chunk::<u64>(0, "configuration/step").unwrap();
    assert_eq!((step.data, step.n, step.m), (vec![0], 1, 1));
    let rows = r.read_chunk::<f32>(0, "particles/orientation").unwrap();
    assert_eq!(rows.rows::<4>().unwrap().len(), 3);
    assert!(rows.rows::<3>().is_none());
    let untyped = r.read_chunk_untyped(0, "log/flags").unwrap();
    assert_eq!(untyped.as_scalar::<i16>(), Some(-7));
    std::fs::remove_file(&path).ok();
}

#[test]
fn invalid_frames_are_refused_and_nothing_is_written() {
    let path = scratch("invalid.gsd");
    let mut w = Writer::create(&path, "invalid").unwrap();
    let len = std::fs::metadata(&path).unwrap().len();
    let good = frame(0, 3);
    let mut bad = Vec::new();
    let mut f = good.clone();
    f.typeid.pop();
    bad.push(f);
    let mut f = good.clone();
    f.typeid[0] = 3;
    bad.push(f);
    let mut f = good.clone();
    f.velocity = Some(vec![[0.0; 3]; 2]);
    bad.push(f);
    let mut f = good.clone();
    f.dimensions = 4;
    bad.push(f);
    let mut f = good.clone();
    f.type_shapes.pop();
    bad.push(f);
    let mut f = good.clone();
    f.types[1] = "r\0d".into();
    bad.push(f);
    let mut f = good.clone();
    f.type_shapes[0] = Shape::Sphere {
        diameter: f64::INFINITY,
    };
    bad.push(f);
    let mut f = good.clone();
    f.type_shapes[0] = Shape::Other("not json".into());
    bad.push(f);
    for f in &bad {
        let e = w.append(f).unwrap_err();
        assert!(matches!(e, Error::Invalid(_)), "{e}");
    }
    assert_eq!(std::fs::metadata(&path).unwrap().len(), len);
    w.append(&good).unwrap();
    assert!(matches!(
        Writer::create(&path, &"x".repeat(64)),
        Err(Error::Invalid(_))
    ));
    drop(w);
    std::fs::remove_file(&path).ok();
}

#[test]
fn an_empty_file_has_no_frames_and_two_dimensional_frames_keep_their_dimension() {
    let path = scratch("empty.gsd");
    let w = Writer::create(&path, "empty").unwrap();
    drop(w);
    let mut r = Reader::open(&path).unwrap();
    assert_eq!(r.frames(), 0);
    assert!(r.chunk_names().is_empty());
    assert!(matches!(
        r.read_frame(0),
        Err(Error::FrameOutOfRange { .. })
    ));

    let mut w = Writer::append_to(&path).unwrap();
    let mut f = frame(0, 2);
    f.dimensions = 2;
    f.sim_box = SimBox::orthorhombic(5.0, 6.0, 1.0);
    w.append(&f).unwrap();
    let mut empty = Frame {
        step: 99,
        dimensions: 2,
        sim_box: f.sim_box,
        types: f.types.clone(),
        type_shapes: f.type_shapes.clone(),
        ..Frame::default()
    };
    w.append(&empty).unwrap();
    drop(w);
    let mut r = Reader::open(&path).unwrap();
    let got = r.read_frame(1).unwrap();
    assert_eq!((got.step, got.dimensions, got.n()), (99, 2, 0));
    // Frame 0's logs carry over to a frame that stores none (the schema's rule).
    empty.log = f.log.clone();
    assert_same(&got, &empty);
    std::fs::remove_file(&path).ok();
}

/// A file layer 1.0 file, built byte by byte: names in 64-byte slots, one frame of
/// `configuration/step` (u64) and `particles/position` (f32, 1×3).
#[test]
fn a_file_layer_1_0_file_reads() {
    let mut b = Vec::new();
    b.extend_from_slice(&0x65DF_65DF_65DF_65DF_u64.to_le_bytes());
    b.extend_from_slice(&256_u64.to_le_bytes()); // index location
    b.extend_from_slice(&4_u64.to_le_bytes()); // index entries
    b.extend_from_slice(&(256_u64 + 4 * 32).to_le_bytes()); // name list location
    b.extend_from_slice(&4_u64.to_le_bytes()); // name list: 4 slots of 64 bytes
    b.extend_from_slice(&(1_u32 << 16 | 3).to_le_bytes()); // schema hoomd 1.3
    b.extend_from_slice(&(1_u32 << 16).to_le_bytes()); // file layer 1.0
    let field = |text: &str| {
        let mut f = [0u8; 64];
        f[..text.len()].copy_from_slice(text.as_bytes());
        f
    };
    let (app, schema) = (field("handmade"), field("hoomd"));
    b.extend_from_slice(&app);
    b.extend_from_slice(&schema);
    b.resize(256, 0);
    let data = 256 + 4 * 32 + 4 * 64;
    let entry = |frame: u64, n: u64, loc: u64, m: u32, id: u16, ty: u8| {
        let mut e = Vec::new();
        e.extend_from_slice(&frame.to_le_bytes());
        e.extend_from_slice(&n.to_le_bytes());
        e.extend_from_slice(&loc.to_le_bytes());
        e.extend_from_slice(&m.to_le_bytes());
        e.extend_from_slice(&id.to_le_bytes());
        e.extend_from_slice(&[ty, 0]);
        e
    };
    b.extend(entry(0, 1, data, 1, 0, 4));
    b.extend(entry(0, 1, data + 8, 3, 1, 9));
    b.resize(256 + 4 * 32, 0);
    b.extend_from_slice(&field("configuration/step"));
    b.extend_from_slice(&field("particles/position"));
    b.resize(data as usize, 0);
    b.extend_from_slice(&42_u64.to_le_bytes());
    for x in [1.5_f32, -2.0, 0.25] {
        b.extend_from_slice(&x.to_le_bytes());
    }
    let path = scratch("v1.gsd");
    std::fs::write(&path, &b).unwrap();

    let mut r = Reader::open(&path).unwrap();
    assert_eq!(r.file_version(), (1, 0));
    assert_eq!(r.schema_version(), (1, 3));
    assert_eq!(r.application(), "handmade");
    assert_eq!(
        r.chunk_names(),
        ["configuration/step", "particles/position"]
    );
    assert_eq!(r.frames(), 1);
    let p = r.read_chunk::<f32>(0, "particles/position").unwrap();
    assert_eq!(p.data, [1.5, -2.0, 0.25]);
    // No particles/N: the schema's default of 0 particles, so the stored row is too many.
    assert!(matches!(r.read_frame(0), Err(Error::WrongShape { .. })));
    assert!(matches!(
        Writer::append_to(&path),
        Err(Error::UnsupportedVersion { major: 1, .. })
    ));
    std::fs::remove_file(&path).ok();
}
