//! The one error type of the crate.

use std::fmt;

use crate::Type;

/// What can go wrong reading or writing a GSD file.
///
/// A corrupt or truncated file is always one of these, never a panic.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// The operating system refused a read or a write.
    Io(std::io::Error),
    /// The file does not start with the GSD magic number `0x65DF65DF65DF65DF`.
    BadMagic {
        /// The first eight bytes, read as a little-endian `u64`.
        found: u64,
    },
    /// The file layer version is one this crate does not read (it reads 1.x and 2.x).
    UnsupportedVersion {
        /// Major version.
        major: u16,
        /// Minor version.
        minor: u16,
    },
    /// The file is shorter than a block its header or index points to.
    Truncated {
        /// The block that does not fit.
        what: &'static str,
        /// The byte offset one past the end of that block.
        needed: u64,
        /// The length of the file in bytes.
        len: u64,
    },
    /// The header, index or name list holds values no valid file can hold.
    Corrupt(String),
    /// A chunk is stored with another element type than the one asked for.
    WrongType {
        /// Chunk name, e.g. `particles/position`.
        name: String,
        /// The type asked for.
        expected: Type,
        /// The type in the file.
        found: Type,
    },
    /// A chunk has another shape (`N` rows × `M` columns) than the schema requires.
    WrongShape {
        /// Chunk name.
        name: String,
        /// What the schema requires: `(N, M)`.
        expected: (u64, u32),
        /// What the file holds: `(N, M)`.
        found: (u64, u32),
    },
    /// The chunk is in neither the frame asked for nor frame 0.
    MissingChunk {
        /// Chunk name.
        name: String,
        /// The frame asked for.
        frame: u64,
    },
    /// A frame index at or beyond the number of frames in the file.
    FrameOutOfRange {
        /// The frame asked for.
        frame: u64,
        /// The number of frames in the file.
        frames: u64,
    },
    /// The file is a valid GSD file of another schema than `hoomd` 1.x or 2.x.
    NotHoomd {
        /// The schema name in the header.
        schema: String,
        /// The schema version `(major, minor)`.
        version: (u16, u16),
    },
    /// A frame or an argument handed to the writer cannot be stored (lengths that disagree, a
    /// name with a NUL byte, a non-finite number in a shape, ...).
    Invalid(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Io(e) => write!(f, "GSD file input/output failed: {e}"),
            Error::BadMagic { found } => write!(
                f,
                "not a GSD file: the magic number is {found:#018x}, not 0x65df65df65df65df"
            ),
            Error::UnsupportedVersion { major, minor } => write!(
                f,
                "GSD file layer version {major}.{minor} is not supported (1.x and 2.x are)"
            ),
            Error::Truncated { what, needed, len } => write!(
                f,
                "truncated GSD file: the {what} ends at byte {needed} but the file has {len} bytes"
            ),
            Error::Corrupt(why) => write!(f, "corrupt GSD file: {why}"),
            Error::WrongType {
                name,
                expected,
                found,
            } => write!(
                f,
                "chunk `{name}` holds {found} values, not the {expected} values asked for"
            ),
            Error::WrongShape {
                name,
                expected,
                found,
            } => write!(
                f,
                "chunk `{name}` is {}×{}, not {}×{} as the hoomd schema requires",
                found.0, found.1, expected.0, expected.1
            ),
            Error::MissingChunk { name, frame } => {
                write!(f, "chunk `{name}` is in neither frame {frame} nor frame 0")
            }
            Error::FrameOutOfRange { frame, frames } => {
                write!(
                    f,
                    "frame {frame} does not exist: the file has {frames} frames"
                )
            }
            Error::NotHoomd { schema, version } => write!(
                f,
                "the file's schema is `{schema}` {}.{}, not `hoomd` 1.x or 2.x",
                version.0, version.1
            ),
            Error::Invalid(why) => write!(f, "cannot write to the GSD file: {why}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io(e) => Some(e),
            _ => None,
        }
    }
}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Error::Io(e)
    }
}

/// The crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
