//! Reading and writing GSD files, the trajectory format of HOOMD-blue, in pure Rust.
//!
//! A GSD file (file layer 2.0) is a 256-byte header, an index of 32-byte entries, a list of
//! chunk names and the data chunks. A *chunk* is an `N × M` array of one element type stored
//! under a name such as `particles/position`, and belongs to one *frame*. The `hoomd` schema
//! (1.4 here) says which names hold what; viewers and analysis tools (OVITO, freud, `gsd.hoomd`
//! in Python) read it. This crate depends on `std` only and gives:
//!
//! - [`Writer`]: creates a file (or appends to one) and [`Writer::append`]s [`Frame`]s, each
//!   committed to the file at once, so that the file can be read while it grows;
//! - [`Reader`]: opens a file, counts frames, lists chunk names, reads a chunk of a frame as a
//!   typed [`Array`] with its shape, or a whole [`Frame`];
//! - [`Frame`]: the standard chunks, typed — step, [`SimBox`], positions, optional
//!   orientations, velocities, angular momenta and periodic images, type ids, type names, type [`Shape`]s — and
//!   free `log/...` quantities as [`Chunk`]s;
//! - [`Error`]: every failure, including every way a file can be corrupt or truncated; reading
//!   never panics on file content.
//!
//! Numbers are stored as given, in the simulation's units: positions and box edges in its
//! length unit, velocities in length per time unit, and so on. GSD records no units.
//!
//! **Frame-0 fallback.** In the hoomd schema a chunk absent from a frame `k > 0` takes its value
//! from frame 0. [`Writer`] uses that to skip type names, shapes and other chunks that do not
//! change; [`Reader::read_chunk`] and [`Reader::read_frame`] apply it when reading (and
//! [`Reader::chunk_info`] tells what a frame stores itself).
//!
//! ```
//! use gsd::{Chunk, Frame, Reader, Shape, SimBox, Writer};
//!
//! let path = std::env::temp_dir().join(format!("gsd-doc-{}.gsd", std::process::id()));
//! let mut writer = Writer::create(&path, "dmd")?;
//! for k in 0..3_u64 {
//!     let x = 0.5 * k as f32; // length unit of the simulation
//!     let mut frame = Frame {
//!         step: 100 * k,
//!         sim_box: SimBox::cubic(10.0),
//!         position: vec![[x, 0.0, 0.0], [-x, 1.5, 0.0]],
//!         orientation: Some(vec![[1.0, 0.0, 0.0, 0.0]; 2]),
//!         typeid: vec![0, 0],
//!         types: vec!["rod".into()],
//!         type_shapes: vec![Shape::Ellipsoid { a: 1.5, b: 0.5, c: 0.5 }],
//!         ..Frame::default()
//!     };
//!     frame.log.insert("time".into(), Chunk::scalar(0.25 * k as f64)); // time unit
//!     writer.append(&frame)?;
//! }
//! writer.finish()?;
//!
//! let mut reader = Reader::open(&path)?;
//! assert_eq!(reader.frames(), 3);
//! let position = reader.read_chunk::<f32>(2, "particles/position")?;
//! assert_eq!((position.n, position.m), (2, 3));
//! assert_eq!(position.data[0], 1.0);
//! // Type names are stored in frame 0 only; frame 2 takes them from there.
//! assert!(reader.chunk_info(2, "particles/types").is_none());
//! let frame = reader.read_frame(2)?;
//! assert_eq!(frame.types, ["rod"]);
//! assert_eq!(frame.log["time"].as_scalar::<f64>(), Some(0.5));
//! # std::fs::remove_file(&path).ok();
//! # Ok::<(), gsd::Error>(())
//! ```

mod error;
mod frame;
mod layout;
mod reader;
mod shape;
mod types;
mod writer;

pub use error::{Error, Result};
pub use frame::{Frame, SimBox};
pub use reader::{ChunkInfo, Reader};
pub use shape::Shape;
pub use types::{Array, Chunk, Element, Type, Values};
pub use writer::Writer;
