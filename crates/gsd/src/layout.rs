//! The byte layout of the file layer: header, index entries, name list.
//!
//! A GSD file is a 256-byte header, an index block of 32-byte entries (one per stored chunk,
//! sorted by frame and then by name id; the first entry with location 0 ends the list), a name
//! list block and the data chunks, in any order after the header. All numbers are
//! little-endian.

use crate::{Error, Result};

/// The first eight bytes of every GSD file.
pub(crate) const MAGIC: u64 = 0x65DF_65DF_65DF_65DF;
/// Bytes in the header.
pub(crate) const HEADER_SIZE: u64 = 256;
/// Bytes in an index entry.
pub(crate) const ENTRY_SIZE: u64 = 32;
/// The name list is allocated in segments of this many bytes (and names of version 1.x files
/// take exactly one segment each).
pub(crate) const NAME_SEGMENT: u64 = 64;
/// Index entries allocated in a new file.
pub(crate) const INITIAL_INDEX_ENTRIES: u64 = 128;
/// Name list segments allocated in a new file (1024 bytes).
pub(crate) const INITIAL_NAME_SEGMENTS: u64 = 16;

/// A version number as the header stores it: major in the high 16 bits, minor in the low 16.
pub(crate) fn version(major: u16, minor: u16) -> u32 {
    (u32::from(major) << 16) | u32::from(minor)
}

/// The `(major, minor)` of a stored version number.
pub(crate) fn split_version(v: u32) -> (u16, u16) {
    ((v >> 16) as u16, (v & 0xffff) as u16)
}

/// The file layer version this crate writes.
pub(crate) const FILE_VERSION: (u16, u16) = (2, 0);
/// The hoomd schema version this crate writes.
pub(crate) const SCHEMA_VERSION: (u16, u16) = (1, 4);

fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    let mut a = [0; 4];
    a.copy_from_slice(&b[at..at + 4]);
    u32::from_le_bytes(a)
}

/// The NUL-terminated string in a fixed-size field (the whole field if it has no NUL).
fn c_string(field: &[u8]) -> String {
    let end = field.iter().position(|&b| b == 0).unwrap_or(field.len());
    String::from_utf8_lossy(&field[..end]).into_owned()
}

/// The 256-byte header.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Header {
    pub(crate) index_location: u64,
    pub(crate) index_allocated: u64,
    pub(crate) namelist_location: u64,
    /// In 64-byte segments.
    pub(crate) namelist_allocated: u64,
    pub(crate) schema_version: u32,
    pub(crate) gsd_version: u32,
    pub(crate) application: String,
    pub(crate) schema: String,
}

impl Header {
    pub(crate) fn encode(&self) -> [u8; HEADER_SIZE as usize] {
        let mut b = [0u8; HEADER_SIZE as usize];
        b[0..8].copy_from_slice(&MAGIC.to_le_bytes());
        b[8..16].copy_from_slice(&self.index_location.to_le_bytes());
        b[16..24].copy_from_slice(&self.index_allocated.to_le_bytes());
        b[24..32].copy_from_slice(&self.namelist_location.to_le_bytes());
        b[32..40].copy_from_slice(&self.namelist_allocated.to_le_bytes());
        b[40..44].copy_from_slice(&self.schema_version.to_le_bytes());
        b[44..48].copy_from_slice(&self.gsd_version.to_le_bytes());
        // Both names keep a NUL in the last byte of their 64-byte fields.
        let app = self.application.as_bytes();
        let n = app.len().min(63);
        b[48..48 + n].copy_from_slice(&app[..n]);
        let schema = self.schema.as_bytes();
        let n = schema.len().min(63);
        b[112..112 + n].copy_from_slice(&schema[..n]);
        b
    }

    /// Decodes and checks the magic number and the file layer version.
    pub(crate) fn decode(b: &[u8; HEADER_SIZE as usize]) -> Result<Header> {
        let magic = u64_at(b, 0);
        if magic != MAGIC {
            return Err(Error::BadMagic { found: magic });
        }
        let h = Header {
            index_location: u64_at(b, 8),
            index_allocated: u64_at(b, 16),
            namelist_location: u64_at(b, 24),
            namelist_allocated: u64_at(b, 32),
            schema_version: u32_at(b, 40),
            gsd_version: u32_at(b, 44),
            application: c_string(&b[48..112]),
            schema: c_string(&b[112..176]),
        };
        let (major, minor) = split_version(h.gsd_version);
        if !(1..=2).contains(&major) {
            return Err(Error::UnsupportedVersion { major, minor });
        }
        Ok(h)
    }
}

/// One 32-byte index entry: where the data of one chunk of one frame is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Entry {
    pub(crate) frame: u64,
    pub(crate) n: u64,
    pub(crate) location: u64,
    pub(crate) m: u32,
    pub(crate) id: u16,
    pub(crate) ty: u8,
    pub(crate) flags: u8,
}

impl Entry {
    pub(crate) fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.frame.to_le_bytes());
        out.extend_from_slice(&self.n.to_le_bytes());
        out.extend_from_slice(&self.location.to_le_bytes());
        out.extend_from_slice(&self.m.to_le_bytes());
        out.extend_from_slice(&self.id.to_le_bytes());
        out.push(self.ty);
        out.push(self.flags);
    }

    /// Decodes an entry from exactly 32 bytes.
    pub(crate) fn decode(b: &[u8]) -> Entry {
        Entry {
            frame: u64_at(b, 0),
            n: u64_at(b, 8),
            // Stored as a signed 64-bit offset; a negative one reads as huge and fails the
            // bounds check like any other location past the end of the file.
            location: u64_at(b, 16),
            m: u32_at(b, 24),
            id: u16::from_le_bytes([b[28], b[29]]),
            ty: b[30],
            flags: b[31],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_round_trips_and_is_256_bytes() {
        let h = Header {
            index_location: 256,
            index_allocated: 128,
            namelist_location: 4352,
            namelist_allocated: 16,
            schema_version: version(1, 4),
            gsd_version: version(2, 0),
            application: "dmd".into(),
            schema: "hoomd".into(),
        };
        let b = h.encode();
        assert_eq!(&b[0..8], &[0xdf, 0x65, 0xdf, 0x65, 0xdf, 0x65, 0xdf, 0x65]);
        assert_eq!(Header::decode(&b).unwrap(), h);
        assert_eq!(split_version(h.schema_version), (1, 4));
    }

    #[test]
    fn entry_round_trips_in_32_bytes() {
        let e = Entry {
            frame: 7,
            n: 1000,
            location: 123_456,
            m: 3,
            id: 513,
            ty: 9,
            flags: 0,
        };
        let mut b = Vec::new();
        e.encode(&mut b);
        assert_eq!(b.len() as u64, ENTRY_SIZE);
        assert_eq!(Entry::decode(&b), e);
    }
}
