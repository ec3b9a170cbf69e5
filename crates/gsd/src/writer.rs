//! Writing hoomd-schema GSD files frame by frame.

use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::Path;

use crate::layout::{
    ENTRY_SIZE, Entry, FILE_VERSION, HEADER_SIZE, Header, INITIAL_INDEX_ENTRIES,
    INITIAL_NAME_SEGMENTS, NAME_SEGMENT, SCHEMA_VERSION, version,
};
use crate::reader::Reader;
use crate::{Element, Error, Frame, Result, SimBox, Values};

/// What frame 0 stored of the chunks a later frame may leave out when unchanged.
#[derive(Debug)]
struct FirstFrame {
    dimensions: u8,
    sim_box: SimBox,
    n: usize,
    typeid: Vec<u32>,
    types: Vec<String>,
    type_shapes: Vec<String>,
}

/// Writes a hoomd-schema GSD file (file layer 2.0, schema `hoomd` 1.4), one [`Frame`] at a
/// time.
///
/// Each [`Writer::append`] commits its frame: the data chunks go to the end of the file, then
/// new chunk names to the name list, then the frame's index entries (sorted by name id) to the
/// index, and the header last when the index or the name list had to move to a larger block.
/// A reader that opens the file after `append` returns sees the frame, and a writer killed in
/// the middle leaves every earlier frame readable. [`Writer::flush`] additionally asks the
/// operating system to put the bytes on disk; dropping the writer needs no further writing.
///
/// From frame 1 on, the writer leaves out `configuration/dimensions`, `configuration/box`,
/// `particles/N`, `particles/typeid`, `particles/types` and `particles/type_shapes` when they
/// equal frame 0's: every reader takes them from frame 0.
#[derive(Debug)]
pub struct Writer {
    file: File,
    len: u64,
    header: Header,
    ids: HashMap<String, u16>,
    /// Names in id order.
    names: Vec<String>,
    names_used: u64,
    entries: u64,
    frames: u64,
    first: Option<FirstFrame>,
    /// Set when a write failed half-way; the file is then left as it was at the last
    /// complete frame, and the writer refuses further frames.
    broken: bool,
}

impl Writer {
    /// Creates (or truncates) the file at `path` and writes an empty GSD file: header, an
    /// index of 128 entries and a name list of 1024 bytes. `application` (at most 63 bytes,
    /// no NUL) names the program in the header.
    ///
    /// # Errors
    /// [`Error::Invalid`] for a bad application name, [`Error::Io`] if the file cannot be
    /// written.
    pub fn create(path: impl AsRef<Path>, application: &str) -> Result<Writer> {
        if application.len() > 63 || application.contains('\0') {
            return Err(Error::Invalid(format!(
                "application name {application:?} is longer than 63 bytes or holds a NUL byte"
            )));
        }
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(path)?;
        let index_bytes = INITIAL_INDEX_ENTRIES * ENTRY_SIZE;
        let header = Header {
            index_location: HEADER_SIZE,
            index_allocated: INITIAL_INDEX_ENTRIES,
            namelist_location: HEADER_SIZE + index_bytes,
            namelist_allocated: INITIAL_NAME_SEGMENTS,
            schema_version: version(SCHEMA_VERSION.0, SCHEMA_VERSION.1),
            gsd_version: version(FILE_VERSION.0, FILE_VERSION.1),
            application: application.to_string(),
            schema: "hoomd".to_string(),
        };
        let len = HEADER_SIZE + index_bytes + INITIAL_NAME_SEGMENTS * NAME_SEGMENT;
        let mut bytes = header.encode().to_vec();
        bytes.resize(len as usize, 0);
        file.write_all(&bytes)?;
        Ok(Writer {
            file,
            len,
            header,
            ids: HashMap::new(),
            names: Vec::new(),
            names_used: 0,
            entries: 0,
            frames: 0,
            first: None,
            broken: false,
        })
    }

    /// Opens an existing hoomd-schema file written in file layer 2.x to append frames after
    /// its last one.
    ///
    /// # Errors
    /// The errors of [`Reader::open`], [`Error::NotHoomd`] for another schema, and
    /// [`Error::UnsupportedVersion`] for a file layer 1.x file.
    pub fn append_to(path: impl AsRef<Path>) -> Result<Writer> {
        let file = OpenOptions::new().read(true).write(true).open(path)?;
        let mut reader = Reader::from_file(file)?;
        let (major, minor) = reader.file_version();
        if major != 2 {
            return Err(Error::UnsupportedVersion { major, minor });
        }
        let first = if reader.frames() > 0 {
            let f = reader.read_frame(0)?;
            Some(FirstFrame {
                dimensions: f.dimensions,
                sim_box: f.sim_box,
                n: f.n(),
                typeid: f.typeid,
                types: f.types,
                type_shapes: f
                    .type_shapes
                    .iter()
                    .map(|s| s.to_json().unwrap_or_default())
                    .collect(),
            })
        } else if reader.schema() != "hoomd" {
            return Err(Error::NotHoomd {
                schema: reader.schema().to_string(),
                version: reader.schema_version(),
            });
        } else {
            None
        };
        let ids = reader
            .names
            .iter()
            .enumerate()
            .map(|(i, s)| (s.clone(), i as u16))
            .collect();
        Ok(Writer {
            len: reader.len,
            header: reader.header.clone(),
            ids,
            names: std::mem::take(&mut reader.names),
            names_used: reader.names_used,
            entries: reader.entries.len() as u64,
            frames: reader.frames(),
            first,
            broken: false,
            file: reader.file,
        })
    }

    /// The number of frames in the file.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Appends `frame` as the next frame and commits it to the file (see the type's
    /// documentation for what is left out when unchanged).
    ///
    /// # Errors
    /// [`Error::Invalid`] if the frame fails [`Frame::validate`], has a shape that is not valid
    /// JSON, or would need more than 65534 chunk names; nothing is written then.
    /// [`Error::Io`] if a write fails; the file then still holds every earlier frame, and the
    /// writer refuses further frames.
    pub fn append(&mut self, frame: &Frame) -> Result<()> {
        if self.broken {
            return Err(Error::Invalid(
                "an earlier write failed; the writer takes no more frames".into(),
            ));
        }
        frame.validate()?;
        let shapes = frame
            .type_shapes
            .iter()
            .map(|s| s.to_json())
            .collect::<Result<Vec<_>>>()?;
        let chunks = self.chunks_of(frame, &shapes);

        // Names first (in memory), so that an error leaves nothing half-written.
        let mut new_names = Vec::new();
        let mut ids = Vec::with_capacity(chunks.len());
        for (name, _, _) in &chunks {
            let id = match self.ids.get(name.as_str()) {
                Some(&id) => id,
                None => {
                    let id = self.names.len() + new_names.len();
                    if id >= usize::from(u16::MAX) {
                        return Err(Error::Invalid(format!(
                            "chunk `{name}` would be the 65535th name; GSD holds 65534"
                        )));
                    }
                    new_names.push(name.clone());
                    id as u16
                }
            };
            ids.push(id);
        }

        let result = self.commit(frame, &chunks, &ids, new_names, shapes);
        if result.is_err() {
            self.broken = true;
        }
        result
    }

    /// Asks the operating system to write the file's data to disk (`fsync`). Every appended
    /// frame is already in the file; this only makes it durable.
    ///
    /// # Errors
    /// [`Error::Io`] if the system reports a failure.
    pub fn flush(&mut self) -> Result<()> {
        self.file.sync_all()?;
        Ok(())
    }

    /// Flushes and closes the file, reporting any error (dropping the writer closes it
    /// without syncing or reporting).
    ///
    /// # Errors
    /// As [`Writer::flush`].
    pub fn finish(mut self) -> Result<()> {
        self.flush()
    }

    /// The chunks to store for `frame`: name, values, columns.
    fn chunks_of(&self, frame: &Frame, shapes: &[String]) -> Vec<(String, Values, u32)> {
        let first = self.first.as_ref();
        let n = frame.n();
        let mut out = vec![(
            "configuration/step".to_string(),
            Values::U64(vec![frame.step]),
            1,
        )];
        let mut add = |name: &str, values: Values, m: u32| {
            if !values.is_empty() {
                out.push((name.to_string(), values, m));
            }
        };
        if first.is_none_or(|f| f.dimensions != frame.dimensions) {
            add(
                "configuration/dimensions",
                Values::U8(vec![frame.dimensions]),
                1,
            );
        }
        if first.is_none_or(|f| f.sim_box != frame.sim_box) {
            add(
                "configuration/box",
                Values::F32(frame.sim_box.to_array().to_vec()),
                1,
            );
        }
        if first.is_none_or(|f| f.n != n) {
            add("particles/N", Values::U32(vec![n as u32]), 1);
        }
        add("particles/position", flat(&frame.position), 3);
        if let Some(q) = &frame.orientation {
            add("particles/orientation", flat(q), 4);
        }
        if let Some(v) = &frame.velocity {
            add("particles/velocity", flat(v), 3);
        }
        if let Some(p) = &frame.angmom {
            add("particles/angmom", flat(p), 4);
        }
        if let Some(p) = &frame.image {
            add("particles/image", flat(p), 3);
        }
        if first.is_none_or(|f| f.n != n || f.typeid != frame.typeid) {
            add("particles/typeid", Values::U32(frame.typeid.clone()), 1);
        }
        if first.is_none_or(|f| f.types != frame.types) {
            let (values, m) = text_rows(&frame.types);
            add("particles/types", values, m);
        }
        if first.is_none_or(|f| f.type_shapes != shapes) {
            let (values, m) = text_rows(shapes);
            add("particles/type_shapes", values, m);
        }
        for (key, chunk) in &frame.log {
            add(&format!("log/{key}"), chunk.values().clone(), chunk.m());
        }
        out
    }

    fn commit(
        &mut self,
        frame: &Frame,
        chunks: &[(String, Values, u32)],
        ids: &[u16],
        new_names: Vec<String>,
        shapes: Vec<String>,
    ) -> Result<()> {
        // 1. The data, in one write at the end of the file.
        let mut data = Vec::new();
        let mut entries = Vec::with_capacity(chunks.len());
        for ((_, values, m), &id) in chunks.iter().zip(ids) {
            entries.push(Entry {
                frame: self.frames,
                n: (values.len() / *m as usize) as u64,
                location: self.len + data.len() as u64,
                m: *m,
                id,
                ty: values.element_type().code(),
                flags: 0,
            });
            values.write_le(&mut data);
        }
        self.write_at(self.len, &data)?;
        self.len += data.len() as u64;

        // 2. New names: in place if they fit (the block must keep a NUL at its end), else a
        //    larger block at the end of the file.
        let mut header_moved = false;
        if !new_names.is_empty() {
            let mut bytes = Vec::new();
            for name in &new_names {
                bytes.extend_from_slice(name.as_bytes());
                bytes.push(0);
            }
            let used = self.names_used + bytes.len() as u64;
            let mut segments = self.header.namelist_allocated;
            if used < segments * NAME_SEGMENT {
                self.write_at(self.header.namelist_location + self.names_used, &bytes)?;
            } else {
                while used >= segments * NAME_SEGMENT {
                    segments *= 2;
                }
                let mut block = Vec::with_capacity((segments * NAME_SEGMENT) as usize);
                for name in self.names.iter().chain(&new_names) {
                    block.extend_from_slice(name.as_bytes());
                    block.push(0);
                }
                block.resize((segments * NAME_SEGMENT) as usize, 0);
                self.write_at(self.len, &block)?;
                self.header.namelist_location = self.len;
                self.header.namelist_allocated = segments;
                self.len += block.len() as u64;
                header_moved = true;
            }
            self.names_used = used;
        }

        // 3. Index entries, sorted by id within the frame; the index keeps at least one
        //    entry at location 0 after the last.
        entries.sort_by_key(|e| e.id);
        let mut bytes = Vec::with_capacity(entries.len() * ENTRY_SIZE as usize);
        for e in &entries {
            e.encode(&mut bytes);
        }
        let needed = self.entries + entries.len() as u64;
        if needed < self.header.index_allocated {
            self.write_at(
                self.header.index_location + self.entries * ENTRY_SIZE,
                &bytes,
            )?;
        } else {
            let mut allocated = self.header.index_allocated.max(1);
            while allocated <= needed {
                allocated *= 2;
            }
            let mut block = vec![0u8; (self.entries * ENTRY_SIZE) as usize];
            self.file
                .seek(SeekFrom::Start(self.header.index_location))?;
            self.file.read_exact(&mut block)?;
            block.extend_from_slice(&bytes);
            block.resize((allocated * ENTRY_SIZE) as usize, 0);
            self.write_at(self.len, &block)?;
            self.header.index_location = self.len;
            self.header.index_allocated = allocated;
            self.len += block.len() as u64;
            header_moved = true;
        }

        // 4. The header, when a block moved.
        if header_moved {
            self.write_at(0, &self.header.encode())?;
        }

        for name in new_names {
            self.ids.insert(name.clone(), self.names.len() as u16);
            self.names.push(name);
        }
        self.entries = needed;
        self.frames += 1;
        if self.first.is_none() {
            self.first = Some(FirstFrame {
                dimensions: frame.dimensions,
                sim_box: frame.sim_box,
                n: frame.n(),
                typeid: frame.typeid.clone(),
                types: frame.types.clone(),
                type_shapes: shapes,
            });
        }
        Ok(())
    }

    fn write_at(&mut self, at: u64, bytes: &[u8]) -> Result<()> {
        self.file.seek(SeekFrom::Start(at))?;
        self.file.write_all(bytes)?;
        Ok(())
    }
}

/// Rows of `K` elements as one flat vector.
fn flat<T: Element, const K: usize>(rows: &[[T; K]]) -> Values {
    T::into_values(rows.iter().flatten().copied().collect())
}

/// Strings as NUL-padded `i8` rows as wide as the longest plus its NUL.
fn text_rows(strings: &[String]) -> (Values, u32) {
    let width = strings.iter().map(String::len).max().unwrap_or(0) + 1;
    let mut v = Vec::with_capacity(width * strings.len());
    for s in strings {
        v.extend(s.bytes().map(|b| b as i8));
        v.resize(v.len() + width - s.len(), 0);
    }
    (Values::I8(v), width as u32)
}
