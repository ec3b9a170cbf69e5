//! A frame of the hoomd schema: the standard chunks, typed, and free log quantities.

use std::collections::BTreeMap;

use crate::{Chunk, Error, Result, Shape};

/// The simulation box of `configuration/box`: edge lengths and tilt factors.
///
/// The box spans `[-L/2, L/2)` along each axis around the origin (HOOMD's convention); positions
/// are expected inside it. The three box vectors are `(Lx, 0, 0)`, `(xy·Ly, Ly, 0)` and
/// `(xz·Lz, yz·Lz, Lz)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimBox {
    /// Edge length along x (length).
    pub lx: f32,
    /// Edge length along y (length).
    pub ly: f32,
    /// Edge length along z (length; ignored in a 2D box).
    pub lz: f32,
    /// Tilt factor xy (dimensionless).
    pub xy: f32,
    /// Tilt factor xz (dimensionless).
    pub xz: f32,
    /// Tilt factor yz (dimensionless).
    pub yz: f32,
}

impl SimBox {
    /// An orthorhombic box with edges `lx`, `ly`, `lz` (length).
    pub fn orthorhombic(lx: f32, ly: f32, lz: f32) -> SimBox {
        SimBox {
            lx,
            ly,
            lz,
            xy: 0.0,
            xz: 0.0,
            yz: 0.0,
        }
    }

    /// A cubic box of edge `l` (length).
    pub fn cubic(l: f32) -> SimBox {
        SimBox::orthorhombic(l, l, l)
    }

    /// The six stored values `[Lx, Ly, Lz, xy, xz, yz]`.
    pub fn to_array(self) -> [f32; 6] {
        [self.lx, self.ly, self.lz, self.xy, self.xz, self.yz]
    }

    /// The box of six stored values `[Lx, Ly, Lz, xy, xz, yz]`.
    pub fn from_array(a: [f32; 6]) -> SimBox {
        SimBox {
            lx: a[0],
            ly: a[1],
            lz: a[2],
            xy: a[3],
            xz: a[4],
            yz: a[5],
        }
    }
}

impl Default for SimBox {
    /// The hoomd schema's default: a unit cube.
    fn default() -> SimBox {
        SimBox::cubic(1.0)
    }
}

/// One frame of a hoomd-schema trajectory.
///
/// Lengths, velocities and angular momenta are in the simulation's own units (whatever length,
/// time and mass units it uses; GSD stores numbers, not units). `N`, the number of particles,
/// is `position.len()`.
///
/// Per-particle fields that are `None` are not written. Readers (this crate's and HOOMD's) then
/// take them from frame 0 when frame 0 stores them for the same `N`: `None` in a later frame
/// means "as in frame 0", not "absent".
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// The time step (`configuration/step`, `u64`); for an event-driven run, any increasing
    /// counter (e.g. the number of events).
    pub step: u64,
    /// 2 or 3 (`configuration/dimensions`, `u8`).
    pub dimensions: u8,
    /// The simulation box (`configuration/box`, `f32` × 6).
    pub sim_box: SimBox,
    /// Particle positions (`particles/position`, `f32` N×3; length).
    pub position: Vec<[f32; 3]>,
    /// Orientations as unit quaternions `(r, i, j, k)` rotating body to lab frame
    /// (`particles/orientation`, `f32` N×4; dimensionless).
    pub orientation: Option<Vec<[f32; 4]>>,
    /// Velocities (`particles/velocity`, `f32` N×3; length/time).
    pub velocity: Option<Vec<[f32; 3]>>,
    /// Angular momenta as quaternions (`particles/angmom`, `f32` N×4; HOOMD's convention is
    /// `p = 2 q ⊗ (0, L_body)`, in mass·length²/time).
    pub angmom: Option<Vec<[f32; 4]>>,
    /// Periodic images (`particles/image`, `i32` N×3; box lengths): the unwrapped position is
    /// `position + image · (box vectors)`.
    pub image: Option<Vec<[i32; 3]>>,
    /// The type of each particle, an index into `types` (`particles/typeid`, `u32` N).
    pub typeid: Vec<u32>,
    /// Type names (`particles/types`, NUL-padded `i8` rows).
    pub types: Vec<String>,
    /// One shape per type for viewers (`particles/type_shapes`, JSON in NUL-padded `i8` rows);
    /// empty: not written.
    pub type_shapes: Vec<Shape>,
    /// Free quantities, stored as `log/<key>`: e.g. `"time"` → `Chunk::scalar(t)` with the
    /// simulated time in the simulation's time unit. A key missing from a frame reads as frame
    /// 0's value. Python's `gsd.hoomd` (5.x) fails on a frame that lacks a key frame 0 lacks
    /// too: for files it should read, log the same keys in every frame from frame 0 on.
    pub log: BTreeMap<String, Chunk>,
}

impl Default for Frame {
    /// An empty 3D frame in a unit cube with no types.
    fn default() -> Frame {
        Frame {
            step: 0,
            dimensions: 3,
            sim_box: SimBox::default(),
            position: Vec::new(),
            orientation: None,
            velocity: None,
            angmom: None,
            image: None,
            typeid: Vec::new(),
            types: Vec::new(),
            type_shapes: Vec::new(),
            log: BTreeMap::new(),
        }
    }
}

impl Frame {
    /// The number of particles `N`.
    pub fn n(&self) -> usize {
        self.position.len()
    }

    /// Checks that the frame can be written: lengths agree with `N`, every type id names a
    /// type, names hold no NUL byte, `dimensions` is 2 or 3.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the first problem.
    pub fn validate(&self) -> Result<()> {
        let n = self.n();
        let bad = |why: String| Err(Error::Invalid(why));
        if n > u32::MAX as usize {
            return bad(format!("{n} particles do not fit particles/N (u32)"));
        }
        if !(2..=3).contains(&self.dimensions) {
            return bad(format!("dimensions is {}, not 2 or 3", self.dimensions));
        }
        if self.typeid.len() != n {
            return bad(format!("{} type ids for {n} particles", self.typeid.len()));
        }
        let lens = [
            ("orientation", self.orientation.as_ref().map(Vec::len)),
            ("velocity", self.velocity.as_ref().map(Vec::len)),
            ("angmom", self.angmom.as_ref().map(Vec::len)),
            ("image", self.image.as_ref().map(Vec::len)),
        ];
        for (what, len) in lens {
            if let Some(len) = len.filter(|&l| l != n) {
                return bad(format!("{len} {what} rows for {n} particles"));
            }
        }
        if let Some(&t) = self
            .typeid
            .iter()
            .find(|&&t| t as usize >= self.types.len())
        {
            return bad(format!(
                "type id {t} but only {} type names",
                self.types.len()
            ));
        }
        if !self.type_shapes.is_empty() && self.type_shapes.len() != self.types.len() {
            return bad(format!(
                "{} type shapes for {} types",
                self.type_shapes.len(),
                self.types.len()
            ));
        }
        for name in self.types.iter().chain(self.log.keys()) {
            if name.is_empty() || name.contains('\0') {
                return bad(format!("name {name:?} is empty or holds a NUL byte"));
            }
        }
        Ok(())
    }
}
