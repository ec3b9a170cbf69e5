//! Element types of chunks, typed arrays and untyped chunk values.

use std::fmt;

/// The element type of a chunk, as the file layer numbers it (the `type` byte of an index entry).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Type {
    /// `u8` (1).
    U8 = 1,
    /// `u16` (2).
    U16 = 2,
    /// `u32` (3).
    U32 = 3,
    /// `u64` (4).
    U64 = 4,
    /// `i8` (5); the hoomd schema stores text rows (type names, shapes) as `i8`.
    I8 = 5,
    /// `i16` (6).
    I16 = 6,
    /// `i32` (7).
    I32 = 7,
    /// `i64` (8).
    I64 = 8,
    /// `f32` (9).
    F32 = 9,
    /// `f64` (10).
    F64 = 10,
    /// A UTF-8 string, one byte per element (11; file layer 2.1).
    Char = 11,
}

impl Type {
    /// The type of a stored type byte, `None` for a byte no file layer version defines.
    pub fn from_code(code: u8) -> Option<Type> {
        Some(match code {
            1 => Type::U8,
            2 => Type::U16,
            3 => Type::U32,
            4 => Type::U64,
            5 => Type::I8,
            6 => Type::I16,
            7 => Type::I32,
            8 => Type::I64,
            9 => Type::F32,
            10 => Type::F64,
            11 => Type::Char,
            _ => return None,
        })
    }

    /// The type byte stored in index entries.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// Bytes per element.
    pub fn size(self) -> u64 {
        match self {
            Type::U8 | Type::I8 | Type::Char => 1,
            Type::U16 | Type::I16 => 2,
            Type::U32 | Type::I32 | Type::F32 => 4,
            Type::U64 | Type::I64 | Type::F64 => 8,
        }
    }
}

impl fmt::Display for Type {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Type::U8 => "u8",
            Type::U16 => "u16",
            Type::U32 => "u32",
            Type::U64 => "u64",
            Type::I8 => "i8",
            Type::I16 => "i16",
            Type::I32 => "i32",
            Type::I64 => "i64",
            Type::F32 => "f32",
            Type::F64 => "f64",
            Type::Char => "char",
        })
    }
}

mod sealed {
    pub trait Sealed {}
}

/// A Rust number type that is a chunk element type: `u8` … `u64`, `i8` … `i64`, `f32`, `f64`.
///
/// Values are stored little-endian, as every GSD file in practice is.
pub trait Element: Copy + Default + PartialEq + fmt::Debug + sealed::Sealed + 'static {
    /// The element type in the file.
    const TYPE: Type;
    /// Reads one element from exactly `size_of::<Self>()` little-endian bytes.
    #[doc(hidden)]
    fn read_le(bytes: &[u8]) -> Self;
    /// Appends the element's little-endian bytes.
    #[doc(hidden)]
    fn write_le(self, out: &mut Vec<u8>);
    /// Wraps a vector of elements as untyped [`Values`].
    fn into_values(values: Vec<Self>) -> Values;
    /// The elements of `values` if they are of this type.
    fn from_values(values: &Values) -> Option<&[Self]>;
}

macro_rules! element {
    ($t:ty, $variant:ident) => {
        impl sealed::Sealed for $t {}
        impl Element for $t {
            const TYPE: Type = Type::$variant;
            fn read_le(bytes: &[u8]) -> Self {
                let mut a = [0u8; size_of::<$t>()];
                a.copy_from_slice(bytes);
                <$t>::from_le_bytes(a)
            }
            fn write_le(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            fn into_values(values: Vec<Self>) -> Values {
                Values::$variant(values)
            }
            fn from_values(values: &Values) -> Option<&[Self]> {
                match values {
                    Values::$variant(v) => Some(v),
                    _ => None,
                }
            }
        }
    };
}

element!(u8, U8);
element!(u16, U16);
element!(u32, U32);
element!(u64, U64);
element!(i8, I8);
element!(i16, I16);
element!(i32, I32);
element!(i64, I64);
element!(f32, F32);
element!(f64, F64);

/// The elements of a chunk, of whichever type the file stores them in.
#[derive(Clone, Debug, PartialEq)]
#[allow(missing_docs)] // one variant per element type, named after it
pub enum Values {
    U8(Vec<u8>),
    U16(Vec<u16>),
    U32(Vec<u32>),
    U64(Vec<u64>),
    I8(Vec<i8>),
    I16(Vec<i16>),
    I32(Vec<i32>),
    I64(Vec<i64>),
    F32(Vec<f32>),
    F64(Vec<f64>),
    /// UTF-8 bytes of a character chunk.
    Char(Vec<u8>),
}

impl Values {
    /// The element type.
    pub fn element_type(&self) -> Type {
        match self {
            Values::U8(_) => Type::U8,
            Values::U16(_) => Type::U16,
            Values::U32(_) => Type::U32,
            Values::U64(_) => Type::U64,
            Values::I8(_) => Type::I8,
            Values::I16(_) => Type::I16,
            Values::I32(_) => Type::I32,
            Values::I64(_) => Type::I64,
            Values::F32(_) => Type::F32,
            Values::F64(_) => Type::F64,
            Values::Char(_) => Type::Char,
        }
    }

    /// The number of elements.
    pub fn len(&self) -> usize {
        match self {
            Values::U8(v) | Values::Char(v) => v.len(),
            Values::U16(v) => v.len(),
            Values::U32(v) => v.len(),
            Values::U64(v) => v.len(),
            Values::I8(v) => v.len(),
            Values::I16(v) => v.len(),
            Values::I32(v) => v.len(),
            Values::I64(v) => v.len(),
            Values::F32(v) => v.len(),
            Values::F64(v) => v.len(),
        }
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Appends the little-endian bytes of every element.
    pub(crate) fn write_le(&self, out: &mut Vec<u8>) {
        fn all<T: Element>(v: &[T], out: &mut Vec<u8>) {
            for &x in v {
                x.write_le(out);
            }
        }
        match self {
            Values::U8(v) | Values::Char(v) => out.extend_from_slice(v),
            Values::U16(v) => all(v, out),
            Values::U32(v) => all(v, out),
            Values::U64(v) => all(v, out),
            Values::I8(v) => all(v, out),
            Values::I16(v) => all(v, out),
            Values::I32(v) => all(v, out),
            Values::I64(v) => all(v, out),
            Values::F32(v) => all(v, out),
            Values::F64(v) => all(v, out),
        }
    }

    /// Decodes little-endian bytes of a chunk of type `ty` (`bytes.len()` a multiple of its size).
    pub(crate) fn from_le(ty: Type, bytes: &[u8]) -> Values {
        fn all<T: Element>(bytes: &[u8]) -> Vec<T> {
            bytes.chunks_exact(size_of::<T>()).map(T::read_le).collect()
        }
        match ty {
            Type::U8 => Values::U8(bytes.to_vec()),
            Type::Char => Values::Char(bytes.to_vec()),
            Type::U16 => Values::U16(all(bytes)),
            Type::U32 => Values::U32(all(bytes)),
            Type::U64 => Values::U64(all(bytes)),
            Type::I8 => Values::I8(all(bytes)),
            Type::I16 => Values::I16(all(bytes)),
            Type::I32 => Values::I32(all(bytes)),
            Type::I64 => Values::I64(all(bytes)),
            Type::F32 => Values::F32(all(bytes)),
            Type::F64 => Values::F64(all(bytes)),
        }
    }
}

/// An untyped chunk: `N` rows of `M` columns of one element type (row-major, `M` the fast
/// index). The free `log/...` quantities of a [`Frame`](crate::Frame) are chunks.
#[derive(Clone, Debug, PartialEq)]
pub struct Chunk {
    values: Values,
    columns: u32,
}

impl Chunk {
    /// A `1 × 1` chunk holding one number, e.g. `Chunk::scalar(12.5_f64)` for a time in the
    /// simulation's time unit.
    pub fn scalar<T: Element>(x: T) -> Chunk {
        Chunk {
            values: T::into_values(vec![x]),
            columns: 1,
        }
    }

    /// An `N × 1` chunk (a column of `N` numbers).
    pub fn column<T: Element>(values: Vec<T>) -> Chunk {
        Chunk {
            values: T::into_values(values),
            columns: 1,
        }
    }

    /// An `N × M` chunk from its row-major elements; `None` when `columns` is 0 or does not
    /// divide the number of elements.
    pub fn rows<T: Element>(values: Vec<T>, columns: u32) -> Option<Chunk> {
        Chunk::from_values(T::into_values(values), columns)
    }

    /// An `N × M` chunk from untyped values; `None` when `columns` is 0 or does not divide the
    /// number of values.
    pub fn from_values(values: Values, columns: u32) -> Option<Chunk> {
        (columns > 0 && values.len().is_multiple_of(columns as usize))
            .then_some(Chunk { values, columns })
    }

    /// The elements, row-major.
    pub fn values(&self) -> &Values {
        &self.values
    }

    /// The elements if they are of type `T`.
    pub fn get<T: Element>(&self) -> Option<&[T]> {
        T::from_values(&self.values)
    }

    /// The single element of a `1 × 1` chunk of type `T`.
    pub fn as_scalar<T: Element>(&self) -> Option<T> {
        match self.get::<T>()? {
            [x] => Some(*x),
            _ => None,
        }
    }

    /// The number of rows `N`.
    pub fn n(&self) -> u64 {
        (self.values.len() / self.columns as usize) as u64
    }

    /// The number of columns `M` (at least 1).
    pub fn m(&self) -> u32 {
        self.columns
    }

    /// The element type.
    pub fn element_type(&self) -> Type {
        self.values.element_type()
    }
}

/// A chunk read with a known element type: `N` rows of `M` columns, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Array<T> {
    /// The `N·M` elements, row-major (`M` the fast index).
    pub data: Vec<T>,
    /// Rows.
    pub n: u64,
    /// Columns.
    pub m: u32,
    /// The frame the chunk was read from: the frame asked for, or 0 when the chunk is absent
    /// from that frame and the hoomd schema's fallback to frame 0 applied.
    pub frame: u64,
}

impl<T: Element> Array<T> {
    /// The rows as fixed-size arrays, `None` unless `M == K`.
    pub fn rows<const K: usize>(&self) -> Option<Vec<[T; K]>> {
        (self.m as usize == K).then(|| {
            self.data
                .chunks_exact(K)
                .map(|r| {
                    let mut a = [T::default(); K];
                    a.copy_from_slice(r);
                    a
                })
                .collect()
        })
    }
}
