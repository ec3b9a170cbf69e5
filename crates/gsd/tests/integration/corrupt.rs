//! Corrupt and truncated files: every one is an `Error`, never a panic (nor a huge
//! allocation).

use std::path::{Path, PathBuf};

use gsd::{Chunk, Error, Frame, Reader, Shape, SimBox, Writer};
use proptest::prelude::*;

fn scratch(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("gsd-corrupt-{}-{name}", std::process::id()))
}

/// A small valid file of three frames, as bytes.
fn valid_file() -> Vec<u8> {
    let path = scratch("valid.gsd");
    let mut w = Writer::create(&path, "corrupt").unwrap();
    for k in 0..3 {
        let mut f = Frame {
            step: k,
            sim_box: SimBox::cubic(4.0),
            position: vec![[0.5, 1.0, -1.0], [k as f32, 0.0, 0.0]],
            orientation: Some(vec![[1.0, 0.0, 0.0, 0.0]; 2]),
            typeid: vec![0, 1],
            types: vec!["A".into(), "B".into()],
            type_shapes: vec![Shape::Sphere { diameter: 1.0 }, Shape::Undefined],
            ..Frame::default()
        };
        f.log.insert("time".into(), Chunk::scalar(k as f64));
        w.append(&f).unwrap();
    }
    drop(w);
    let bytes = std::fs::read(&path).unwrap();
    std::fs::remove_file(&path).ok();
    bytes
}

/// Opens and reads everything a reader offers; returns the first error.
fn read_everything(path: &Path) -> Result<(), Error> {
    let mut r = Reader::open(path)?;
    let names = r.chunk_names().to_vec();
    for k in 0..r.frames() {
        let _ = r.read_frame(k);
        for name in &names {
            let _ = r.chunk_info(k, name);
            let _ = r.read_chunk_untyped(k, name);
            let _ = r.read_chunk::<f32>(k, name);
        }
    }
    let _ = r.read_frame(r.frames());
    Ok(())
}

const HEADER: usize = 256;
const INDEX: usize = 256 + 128 * 32; // end of the first index block
const NAMES: usize = INDEX + 1024; // end of the first name list

#[test]
fn every_truncation_is_reported_as_truncated() {
    let bytes = valid_file();
    let path = scratch("truncated.gsd");
    for len in 0..bytes.len() {
        std::fs::write(&path, &bytes[..len]).unwrap();
        match Reader::open(&path) {
            Ok(_) => panic!("a file cut at {len} of {} bytes opened", bytes.len()),
            Err(Error::Truncated { .. }) => {}
            Err(e) => panic!("a file cut at {len} bytes: {e}"),
        }
    }
    std::fs::remove_file(&path).ok();
}

#[test]
fn named_corruptions_give_named_errors() {
    let bytes = valid_file();
    let path = scratch("named.gsd");
    let open = |b: &[u8]| {
        std::fs::write(&path, b).unwrap();
        Reader::open(&path).map(|_| ())
    };
    assert!(open(&bytes).is_ok());

    let mut b = bytes.clone();
    b[0] ^= 1;
    let e = open(&b).unwrap_err();
    assert!(matches!(e, Error::BadMagic { .. }), "{e}");
    assert!(e.to_string().contains("magic"));

    // File layer version 3.0.
    let mut b = bytes.clone();
    b[44..48].copy_from_slice(&(3_u32 << 16).to_le_bytes());
    assert!(matches!(
        open(&b),
        Err(Error::UnsupportedVersion { major: 3, minor: 0 })
    ));

    // An index of 2^40 entries (32 TiB).
    let mut b = bytes.clone();
    b[16..24].copy_from_slice(&(1_u64 << 40).to_le_bytes());
    assert!(matches!(
        open(&b),
        Err(Error::Truncated { what: "index", .. })
    ));

    // An index size that overflows.
    let mut b = bytes.clone();
    b[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
    assert!(matches!(open(&b), Err(Error::Corrupt(_))));

    // A name list that does not end in NUL.
    let mut b = bytes.clone();
    b[NAMES - 1] = b'x';
    assert!(matches!(open(&b), Err(Error::Corrupt(_))));

    // Entry 0: unknown type, nonzero flags, unknown name id, data past the end, 0 columns.
    let entry = HEADER;
    for (at, value, what) in [
        (30, 12_u8, "type"),
        (31, 1, "flags"),
        (29, 0xff, "name id"),
        (15, 0x7f, "size"),
        (24, 0, "columns"),
    ] {
        let mut b = bytes.clone();
        b[entry + at] = value;
        if at == 24 {
            b[entry + 24..entry + 28].fill(0);
        }
        let e = open(&b).unwrap_err();
        assert!(
            matches!(e, Error::Corrupt(_) | Error::Truncated { .. }),
            "{what}: {e}"
        );
    }

    // Frames that go backwards: entry 1 (of frame 0) claims frame 2, entry 2 is of frame 0.
    let mut b = bytes.clone();
    b[entry + 32] = 2;
    let e = open(&b).unwrap_err();
    assert!(matches!(e, Error::Corrupt(_)), "{e}");

    // A chunk stored with the wrong type for the schema.
    let mut b = bytes.clone();
    let mut r = Reader::open({
        std::fs::write(&path, &b).unwrap();
        &path
    })
    .unwrap();
    assert!(r.read_frame(0).is_ok());
    // Find the entry of configuration/step (name id 0) and call it i64.
    for e in 0..(INDEX - HEADER) / 32 {
        let at = HEADER + 32 * e;
        if b[at + 16..at + 24] == [0; 8] {
            break;
        }
        if b[at + 28..at + 30] == [0, 0] {
            b[at + 30] = 8;
        }
    }
    std::fs::write(&path, &b).unwrap();
    let mut r = Reader::open(&path).unwrap();
    let e = r.read_frame(1).unwrap_err();
    assert!(matches!(e, Error::WrongType { .. }), "{e}");
    assert!(e.to_string().contains("configuration/step"));

    // A particle count far beyond what the file could hold, in a frame without positions.
    let path2 = scratch("huge-n.gsd");
    let mut w = Writer::create(&path2, "huge").unwrap();
    w.append(&Frame::default()).unwrap();
    drop(w);
    let mut b = std::fs::read(&path2).unwrap();
    // particles/N = 0 is the frame's only u32 chunk (type 3): make it u32::MAX.
    for e in 0..(INDEX - HEADER) / 32 {
        let at = HEADER + 32 * e;
        if b[at + 16..at + 24] == [0; 8] {
            break;
        }
        if b[at + 30] == 3 {
            let loc = u64::from_le_bytes(b[at + 16..at + 24].try_into().unwrap()) as usize;
            b[loc..loc + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        }
    }
    std::fs::write(&path2, &b).unwrap();
    let mut r = Reader::open(&path2).unwrap();
    let e = r.read_frame(0).unwrap_err();
    assert!(matches!(e, Error::Corrupt(_)), "{e}");
    std::fs::remove_file(&path2).ok();

    // A schema that is not hoomd.
    let mut b = bytes.clone();
    b[112..117].copy_from_slice(b"other");
    std::fs::write(&path, &b).unwrap();
    let mut r = Reader::open(&path).unwrap();
    assert!(matches!(r.read_frame(0), Err(Error::NotHoomd { .. })));
    assert!(r.read_chunk::<f32>(0, "particles/position").is_ok());
    std::fs::remove_file(&path).ok();
}

#[test]
fn an_empty_or_tiny_file_is_truncated_and_a_text_file_has_a_bad_magic() {
    let path = scratch("tiny.gsd");
    std::fs::write(&path, b"").unwrap();
    let e = Reader::open(&path).unwrap_err();
    assert!(matches!(e, Error::Truncated { what: "header", .. }), "{e}");
    std::fs::write(&path, "x".repeat(1000)).unwrap();
    assert!(matches!(Reader::open(&path), Err(Error::BadMagic { .. })));
    assert!(matches!(
        Reader::open(scratch("does-not-exist.gsd")),
        Err(Error::Io(_))
    ));
    std::fs::remove_file(&path).ok();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Random bytes written over a valid file (header, index, name list or data) never make
    /// the reader panic.
    #[test]
    fn garbled_files_never_panic(
        edits in prop::collection::vec((0..NAMES + 600, any::<u8>()), 1..12),
        region in 0..3_usize,
    ) {
        let mut bytes = valid_file();
        for (at, value) in edits {
            // Aim a third of the cases at the header and the first index entries, where
            // a change matters most.
            let at = match region {
                0 => at % (HEADER + 8 * 32),
                1 => at % bytes.len(),
                _ => HEADER + at % (INDEX - HEADER),
            };
            bytes[at] = value;
        }
        let path = scratch(&format!("garbled-{:?}.gsd", std::thread::current().id()));
        std::fs::write(&path, &bytes).unwrap();
        let _ = read_everything(&path);
        std::fs::remove_file(&path).ok();
    }

    /// A file of arbitrary bytes behind a valid magic number never makes the reader panic.
    #[test]
    fn random_files_never_panic(tail in prop::collection::vec(any::<u8>(), 0..2000)) {
        let mut bytes = 0x65DF_65DF_65DF_65DF_u64.to_le_bytes().to_vec();
        bytes.extend(tail);
        let path = scratch(&format!("random-{:?}.gsd", std::thread::current().id()));
        std::fs::write(&path, &bytes).unwrap();
        let _ = read_everything(&path);
        std::fs::remove_file(&path).ok();
    }
}
