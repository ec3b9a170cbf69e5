//! Reading GSD files: typed chunks with the hoomd schema's fallback to frame 0, whole frames.

use std::collections::HashMap;
use std::fs::File;
use std::io::{ErrorKind, Read, Seek, SeekFrom};
use std::path::Path;

use crate::layout::{ENTRY_SIZE, Entry, HEADER_SIZE, Header, NAME_SEGMENT, split_version, version};
use crate::{Array, Chunk, Element, Error, Frame, Result, Shape, SimBox, Type, Values};

/// Where a chunk of one frame is, without its data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChunkInfo {
    /// Element type.
    pub ty: Type,
    /// Rows.
    pub n: u64,
    /// Columns.
    pub m: u32,
}

/// A GSD file open for reading.
///
/// The header, name list and index are read and checked once, by [`Reader::open`]: every index
/// entry must have a known type, a known name and data inside the file, and frames must not
/// decrease. A file that fails is reported as [`Error::BadMagic`], [`Error::Truncated`] or
/// [`Error::Corrupt`]; no file content makes the reader panic or allocate more than the file's
/// length. Frames appended after `open` (by a [`Writer`](crate::Writer) that has the file open)
/// are not seen; open the file again to see them.
///
/// **Frame-0 fallback.** In the hoomd schema a chunk that a frame `k > 0` does not store has
/// the value it has in frame 0 (writers leave out what does not change, such as type names).
/// [`Reader::read_chunk`] and [`Reader::read_frame`] apply that rule; [`Reader::chunk_info`]
/// does not, and tells whether a frame stores a chunk itself.
#[derive(Debug)]
pub struct Reader {
    pub(crate) file: File,
    pub(crate) len: u64,
    pub(crate) header: Header,
    pub(crate) names: Vec<String>,
    /// Bytes of the name list in use (version 2.x layout).
    pub(crate) names_used: u64,
    ids: HashMap<String, u16>,
    pub(crate) entries: Vec<Entry>,
    frames: u64,
}

impl Reader {
    /// Opens a GSD file and reads its header, name list and index.
    ///
    /// # Errors
    /// [`Error::Io`] if the file cannot be opened or read, [`Error::BadMagic`],
    /// [`Error::UnsupportedVersion`], [`Error::Truncated`] or [`Error::Corrupt`] for a file
    /// that is not a readable GSD file.
    pub fn open(path: impl AsRef<Path>) -> Result<Reader> {
        Reader::from_file(File::open(path)?)
    }

    pub(crate) fn from_file(mut file: File) -> Result<Reader> {
        let len = file.metadata()?.len();
        if len < HEADER_SIZE {
            return Err(Error::Truncated {
                what: "header",
                needed: HEADER_SIZE,
                len,
            });
        }
        let mut raw = [0u8; HEADER_SIZE as usize];
        read_at(&mut file, 0, &mut raw, len, "header")?;
        let header = Header::decode(&raw)?;
        let v2 = header.gsd_version >= version(2, 0);

        // The name list.
        let size = header
            .namelist_allocated
            .checked_mul(NAME_SEGMENT)
            .ok_or_else(|| corrupt("the name list size overflows"))?;
        let block = read_block(&mut file, header.namelist_location, size, len, "name list")?;
        if block.last() != Some(&0) {
            return Err(corrupt(
                "the name list is empty or does not end in a NUL byte",
            ));
        }
        let mut names = Vec::new();
        let mut at = 0usize;
        while at < block.len() && block[at] != 0 {
            let end = if v2 {
                at + block[at..].iter().position(|&b| b == 0).unwrap_or(0)
            } else {
                at + block[at..at + NAME_SEGMENT as usize]
                    .iter()
                    .position(|&b| b == 0)
                    .unwrap_or(NAME_SEGMENT as usize - 1)
            };
            let name = std::str::from_utf8(&block[at..end])
                .map_err(|_| corrupt(&format!("name {} is not UTF-8", names.len())))?;
            names.push(name.to_string());
            at = if v2 {
                end + 1
            } else {
                at + NAME_SEGMENT as usize
            };
        }
        if names.len() >= usize::from(u16::MAX) {
            return Err(corrupt("more than 65534 names"));
        }
        let mut ids = HashMap::with_capacity(names.len());
        for (id, name) in names.iter().enumerate() {
            ids.entry(name.clone()).or_insert(id as u16);
        }

        // The index, up to its first entry at location 0.
        let size = header
            .index_allocated
            .checked_mul(ENTRY_SIZE)
            .ok_or_else(|| corrupt("the index size overflows"))?;
        let block = read_block(&mut file, header.index_location, size, len, "index")?;
        let mut entries: Vec<Entry> = Vec::new();
        for raw in block.chunks_exact(ENTRY_SIZE as usize) {
            let e = Entry::decode(raw);
            if e.location == 0 {
                break;
            }
            check_entry(&e, entries.len(), &header, names.len(), len)?;
            if let Some(prev) = entries.last()
                && e.frame < prev.frame
            {
                return Err(corrupt(&format!(
                    "index entry {} is for frame {} after one for frame {}",
                    entries.len(),
                    e.frame,
                    prev.frame
                )));
            }
            entries.push(e);
        }
        // check_entry bounds frames by the allocated index size, so this does not overflow.
        let frames = entries.last().map_or(0, |e| e.frame + 1);
        Ok(Reader {
            file,
            len,
            header,
            names,
            names_used: at as u64,
            ids,
            entries,
            frames,
        })
    }

    /// The number of frames.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// The application that created the file (up to 63 bytes).
    pub fn application(&self) -> &str {
        &self.header.application
    }

    /// The schema name, `hoomd` for trajectories.
    pub fn schema(&self) -> &str {
        &self.header.schema
    }

    /// The schema version `(major, minor)`.
    pub fn schema_version(&self) -> (u16, u16) {
        split_version(self.header.schema_version)
    }

    /// The file layer version `(major, minor)`.
    pub fn file_version(&self) -> (u16, u16) {
        split_version(self.header.gsd_version)
    }

    /// Every chunk name in the file, in the order the names were first written (a name may be
    /// stored in some frames only).
    pub fn chunk_names(&self) -> &[String] {
        &self.names
    }

    /// Type and shape of the chunk `name` as frame `frame` itself stores it; `None` when that
    /// frame does not store it (no frame-0 fallback here).
    pub fn chunk_info(&self, frame: u64, name: &str) -> Option<ChunkInfo> {
        self.find(frame, name).map(|e| ChunkInfo {
            ty: Type::from_code(e.ty).expect("checked at open"),
            n: e.n,
            m: e.m,
        })
    }

    /// Reads chunk `name` of frame `frame` as elements of type `T`, with its `N × M` shape.
    /// A chunk absent from a frame `k > 0` is read from frame 0 (the hoomd schema's rule);
    /// [`Array::frame`] says which frame it came from.
    ///
    /// # Errors
    /// [`Error::FrameOutOfRange`], [`Error::MissingChunk`] when neither frame has it,
    /// [`Error::WrongType`] when it is stored as another type, [`Error::Io`] or
    /// [`Error::Truncated`] if the file cannot be read.
    pub fn read_chunk<T: Element>(&mut self, frame: u64, name: &str) -> Result<Array<T>> {
        let (e, from) = self.locate(frame, name)?;
        let found = Type::from_code(e.ty).expect("checked at open");
        if found != T::TYPE {
            return Err(Error::WrongType {
                name: name.to_string(),
                expected: T::TYPE,
                found,
            });
        }
        let bytes = self.read_data(&e)?;
        Ok(Array {
            data: bytes.chunks_exact(size_of::<T>()).map(T::read_le).collect(),
            n: e.n,
            m: e.m,
            frame: from,
        })
    }

    /// Reads chunk `name` of frame `frame` in whatever type it is stored, with the same
    /// frame-0 fallback as [`Reader::read_chunk`].
    ///
    /// # Errors
    /// As [`Reader::read_chunk`], except that any type is accepted.
    pub fn read_chunk_untyped(&mut self, frame: u64, name: &str) -> Result<Chunk> {
        let (e, _) = self.locate(frame, name)?;
        let ty = Type::from_code(e.ty).expect("checked at open");
        let bytes = self.read_data(&e)?;
        Chunk::from_values(Values::from_le(ty, &bytes), e.m)
            .ok_or_else(|| corrupt(&format!("chunk `{name}` has 0 columns")))
    }

    /// Reads frame `frame` as a hoomd-schema [`Frame`].
    ///
    /// Chunks absent from the frame come from frame 0 (per-particle chunks only when frame 0
    /// has as many particles), else take the schema's defaults: step 0, 3 dimensions, a unit
    /// cube, positions at the origin, type ids 0, the type names `["A"]`, no shapes; absent
    /// orientations, velocities and angular momenta stay `None`. Every `log/...` chunk is
    /// read into [`Frame::log`] under its name without the `log/` prefix.
    ///
    /// Floating-point chunks must be `f32` (schema 1.x, and 2.x written in single precision);
    /// a file written in double precision reads through [`Reader::read_chunk`] with `f64`.
    ///
    /// # Errors
    /// [`Error::NotHoomd`] for another schema, [`Error::WrongType`] or [`Error::WrongShape`]
    /// for a standard chunk stored otherwise than the schema says, [`Error::Corrupt`] for type
    /// names or shapes that are not UTF-8, and the errors of [`Reader::read_chunk`].
    pub fn read_frame(&mut self, frame: u64) -> Result<Frame> {
        let (major, _) = self.schema_version();
        if self.header.schema != "hoomd" || !(1..=2).contains(&major) {
            return Err(Error::NotHoomd {
                schema: self.header.schema.clone(),
                version: self.schema_version(),
            });
        }
        if frame >= self.frames {
            return Err(Error::FrameOutOfRange {
                frame,
                frames: self.frames,
            });
        }
        let step = self.scalar::<u64>(frame, "configuration/step")?;
        let dimensions = self.scalar::<u8>(frame, "configuration/dimensions")?;
        let sim_box = match self.optional::<f32>(frame, "configuration/box")? {
            None => SimBox::default(),
            Some(a) => match <[f32; 6]>::try_from(a.data.as_slice()) {
                Ok(six) => SimBox::from_array(six),
                Err(_) => {
                    return Err(Error::WrongShape {
                        name: "configuration/box".into(),
                        expected: (6, 1),
                        found: (a.n, a.m),
                    });
                }
            },
        };
        let n = self.scalar::<u32>(frame, "particles/N")?.unwrap_or(0);
        if u64::from(n) > self.len {
            // Defaults for absent per-particle chunks would allocate N rows; a valid file
            // stores at least a byte per particle somewhere.
            return Err(corrupt(&format!(
                "particles/N is {n} in a file of {} bytes",
                self.len
            )));
        }
        let n0 = if frame == 0 {
            n
        } else {
            self.scalar::<u32>(0, "particles/N")?.unwrap_or(0)
        };
        let types = match self.text_rows(frame, "particles/types")? {
            Some(rows) => rows,
            None => vec!["A".to_string()],
        };
        let type_shapes = self
            .text_rows(frame, "particles/type_shapes")?
            .map(|rows| rows.iter().map(|s| Shape::from_json(s)).collect())
            .unwrap_or_default();
        let pick = |n: u32| n as usize;
        let position = self
            .per_particle::<f32, 3>(frame, "particles/position", n, n0)?
            .unwrap_or_else(|| vec![[0.0; 3]; pick(n)]);
        let orientation = self.per_particle::<f32, 4>(frame, "particles/orientation", n, n0)?;
        let velocity = self.per_particle::<f32, 3>(frame, "particles/velocity", n, n0)?;
        let angmom = self.per_particle::<f32, 4>(frame, "particles/angmom", n, n0)?;
        let image = self.per_particle::<i32, 3>(frame, "particles/image", n, n0)?;
        let typeid = self
            .per_particle::<u32, 1>(frame, "particles/typeid", n, n0)?
            .map(|rows| rows.into_iter().map(|[t]| t).collect())
            .unwrap_or_else(|| vec![0; pick(n)]);
        let mut log = std::collections::BTreeMap::new();
        let log_names: Vec<String> = self
            .names
            .iter()
            .filter(|s| s.starts_with("log/"))
            .cloned()
            .collect();
        for name in log_names {
            match self.read_chunk_untyped(frame, &name) {
                Ok(chunk) => {
                    log.insert(name["log/".len()..].to_string(), chunk);
                }
                Err(Error::MissingChunk { .. }) => {}
                Err(e) => return Err(e),
            }
        }
        Ok(Frame {
            step: step.unwrap_or(0),
            dimensions: dimensions.unwrap_or(3),
            sim_box,
            position,
            orientation,
            velocity,
            angmom,
            image,
            typeid,
            types,
            type_shapes,
            log,
        })
    }

    /// The entry of `name` in `frame` itself.
    fn find(&self, frame: u64, name: &str) -> Option<Entry> {
        let id = *self.ids.get(name)?;
        let start = self.entries.partition_point(|e| e.frame < frame);
        self.entries[start..]
            .iter()
            .take_while(|e| e.frame == frame)
            .find(|e| e.id == id)
            .copied()
    }

    /// The entry to read for `name` in `frame`, with the fallback to frame 0.
    fn locate(&self, frame: u64, name: &str) -> Result<(Entry, u64)> {
        if frame >= self.frames {
            return Err(Error::FrameOutOfRange {
                frame,
                frames: self.frames,
            });
        }
        if let Some(e) = self.find(frame, name) {
            return Ok((e, frame));
        }
        if frame > 0
            && let Some(e) = self.find(0, name)
        {
            return Ok((e, 0));
        }
        Err(Error::MissingChunk {
            name: name.to_string(),
            frame,
        })
    }

    fn read_data(&mut self, e: &Entry) -> Result<Vec<u8>> {
        // Checked at open: the size does not overflow and the data lies inside the file.
        let size = e.n * u64::from(e.m) * Type::from_code(e.ty).expect("checked").size();
        read_block(
            &mut self.file,
            e.location,
            size,
            self.len,
            "data of a chunk",
        )
    }

    fn optional<T: Element>(&mut self, frame: u64, name: &str) -> Result<Option<Array<T>>> {
        match self.read_chunk::<T>(frame, name) {
            Ok(a) => Ok(Some(a)),
            Err(Error::MissingChunk { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    }

    fn scalar<T: Element>(&mut self, frame: u64, name: &str) -> Result<Option<T>> {
        let Some(a) = self.optional::<T>(frame, name)? else {
            return Ok(None);
        };
        match a.data.as_slice() {
            [x] => Ok(Some(*x)),
            _ => Err(Error::WrongShape {
                name: name.to_string(),
                expected: (1, 1),
                found: (a.n, a.m),
            }),
        }
    }

    /// Rows of NUL-padded text (type names, shape JSON), stored as 1-byte elements of any
    /// type.
    fn text_rows(&mut self, frame: u64, name: &str) -> Result<Option<Vec<String>>> {
        let (e, _) = match self.locate(frame, name) {
            Ok(found) => found,
            Err(Error::MissingChunk { .. }) => return Ok(None),
            Err(err) => return Err(err),
        };
        let ty = Type::from_code(e.ty).expect("checked at open");
        if ty.size() != 1 {
            return Err(Error::WrongType {
                name: name.to_string(),
                expected: Type::I8,
                found: ty,
            });
        }
        let bytes = self.read_data(&e)?;
        let mut rows = Vec::with_capacity(e.n as usize);
        for row in bytes.chunks_exact(e.m as usize) {
            let end = row.iter().position(|&b| b == 0).unwrap_or(row.len());
            let text = std::str::from_utf8(&row[..end])
                .map_err(|_| corrupt(&format!("a row of `{name}` is not UTF-8")))?;
            rows.push(text.to_string());
        }
        Ok(Some(rows))
    }

    /// A per-particle chunk of `K` columns for `n` particles, from this frame, else from
    /// frame 0 if frame 0 has `n` particles too.
    fn per_particle<T: Element, const K: usize>(
        &mut self,
        frame: u64,
        name: &str,
        n: u32,
        n0: u32,
    ) -> Result<Option<Vec<[T; K]>>> {
        let source = if self.find(frame, name).is_some() {
            frame
        } else if n0 == n {
            0
        } else {
            return Ok(None);
        };
        let Some(a) = self.optional::<T>(source, name)? else {
            return Ok(None);
        };
        if a.n != u64::from(n) || a.m as usize != K {
            return Err(Error::WrongShape {
                name: name.to_string(),
                expected: (u64::from(n), K as u32),
                found: (a.n, a.m),
            });
        }
        Ok(a.rows::<K>())
    }
}

fn corrupt(why: &str) -> Error {
    Error::Corrupt(why.to_string())
}

/// Checks one index entry against the header, the names and the file length.
fn check_entry(e: &Entry, i: usize, h: &Header, names: usize, len: u64) -> Result<()> {
    let ty = Type::from_code(e.ty)
        .ok_or_else(|| corrupt(&format!("index entry {i} has the unknown type {}", e.ty)))?;
    if e.flags != 0 {
        return Err(corrupt(&format!("index entry {i} has flags {}", e.flags)));
    }
    if usize::from(e.id) >= names {
        return Err(corrupt(&format!(
            "index entry {i} names id {} of {names} names",
            e.id
        )));
    }
    if e.m == 0 {
        return Err(corrupt(&format!("index entry {i} has 0 columns")));
    }
    if e.frame >= h.index_allocated {
        // Every frame stores at least one chunk, so frames cannot outnumber index entries.
        return Err(corrupt(&format!(
            "index entry {i} is for frame {} of an index of {} entries",
            e.frame, h.index_allocated
        )));
    }
    let end =
        e.n.checked_mul(u64::from(e.m))
            .and_then(|k| k.checked_mul(ty.size()))
            .and_then(|size| size.checked_add(e.location))
            .ok_or_else(|| corrupt(&format!("index entry {i} has a size that overflows")))?;
    if end > len {
        return Err(Error::Truncated {
            what: "data of a chunk",
            needed: end,
            len,
        });
    }
    Ok(())
}

/// Reads `size` bytes at `location`, after checking that they lie inside a file of `len`
/// bytes (so a corrupt size never allocates more than the file holds).
fn read_block(
    file: &mut File,
    location: u64,
    size: u64,
    len: u64,
    what: &'static str,
) -> Result<Vec<u8>> {
    let end = location
        .checked_add(size)
        .ok_or_else(|| corrupt(&format!("the {what} lies beyond 2^64 bytes")))?;
    if end > len {
        return Err(Error::Truncated {
            what,
            needed: end,
            len,
        });
    }
    let mut buf = vec![0u8; size as usize];
    read_at(file, location, &mut buf, len, what)?;
    Ok(buf)
}

fn read_at(file: &mut File, at: u64, buf: &mut [u8], len: u64, what: &'static str) -> Result<()> {
    file.seek(SeekFrom::Start(at))?;
    file.read_exact(buf).map_err(|e| {
        if e.kind() == ErrorKind::UnexpectedEof {
            // The file shrank after it was opened.
            Error::Truncated {
                what,
                needed: at + buf.len() as u64,
                len,
            }
        } else {
            Error::Io(e)
        }
    })
}
