//! Shapes of particle types for visualisation (`particles/type_shapes`): one JSON object per
//! type, as GSD's shape visualisation specification defines them.

use crate::{Error, Result};

/// The shape of a particle type, one row of `particles/type_shapes`. Lengths are in the
/// simulation's length unit (the unit of positions and of the box).
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// `{}`: no shape given; a viewer draws what it likes.
    Undefined,
    /// `{"type": "Sphere", "diameter": d}` (a disk in a 2D box).
    Sphere {
        /// Diameter (length).
        diameter: f64,
    },
    /// `{"type": "Ellipsoid", "a": a, "b": b, "c": c}`: semi-axes along the body's x, y and z.
    Ellipsoid {
        /// Semi-axis along the body x axis (length).
        a: f64,
        /// Semi-axis along the body y axis (length).
        b: f64,
        /// Semi-axis along the body z axis (length).
        c: f64,
    },
    /// `{"type": "ConvexPolyhedron", "rounding_radius": r, "vertices": [[x, y, z], ...]}`: the
    /// convex hull of the vertices in the body frame, dilated by a sphere of radius `r` (a
    /// spheropolyhedron; `r = 0` for a sharp polyhedron).
    ConvexPolyhedron {
        /// Rounding radius (length).
        rounding_radius: f64,
        /// Vertices in the body frame (length).
        vertices: Vec<[f64; 3]>,
    },
    /// Any other shape object (`Polygon`, `Mesh`, `SphereUnion`, ...), kept as its JSON text.
    /// Writing checks that it is a JSON object.
    Other(String),
}

impl Shape {
    /// The JSON text of the shape, as stored in the file.
    ///
    /// # Errors
    /// [`Error::Invalid`] for a non-finite number or an `Other` that is not a JSON object.
    pub fn to_json(&self) -> Result<String> {
        fn num(x: f64) -> Result<String> {
            if x.is_finite() {
                // Debug gives the shortest text that reads back as the same f64, with a
                // decimal point or an exponent: valid JSON either way.
                Ok(format!("{x:?}"))
            } else {
                Err(Error::Invalid(format!("shape parameter {x} is not finite")))
            }
        }
        Ok(match self {
            Shape::Undefined => "{}".to_string(),
            Shape::Sphere { diameter } => {
                format!(r#"{{"type":"Sphere","diameter":{}}}"#, num(*diameter)?)
            }
            Shape::Ellipsoid { a, b, c } => format!(
                r#"{{"type":"Ellipsoid","a":{},"b":{},"c":{}}}"#,
                num(*a)?,
                num(*b)?,
                num(*c)?
            ),
            Shape::ConvexPolyhedron {
                rounding_radius,
                vertices,
            } => {
                let mut vs = Vec::with_capacity(vertices.len());
                for v in vertices {
                    vs.push(format!("[{},{},{}]", num(v[0])?, num(v[1])?, num(v[2])?));
                }
                format!(
                    r#"{{"type":"ConvexPolyhedron","rounding_radius":{},"vertices":[{}]}}"#,
                    num(*rounding_radius)?,
                    vs.join(",")
                )
            }
            Shape::Other(text) => match json::parse(text) {
                Some(json::Value::Object(_)) => text.clone(),
                _ => {
                    return Err(Error::Invalid(format!(
                        "shape `{text}` is not a JSON object"
                    )));
                }
            },
        })
    }

    /// The shape a JSON text describes. A text that is not one of the shapes this enum names
    /// (or not JSON at all) comes back as [`Shape::Other`] with the text unchanged; this never
    /// fails.
    pub fn from_json(text: &str) -> Shape {
        Shape::known(text).unwrap_or_else(|| Shape::Other(text.to_string()))
    }

    fn known(text: &str) -> Option<Shape> {
        let json::Value::Object(fields) = json::parse(text)? else {
            return None;
        };
        let get = |key: &str| fields.iter().find(|(k, _)| k == key).map(|(_, v)| v);
        let number = |key: &str| match get(key) {
            Some(json::Value::Number(x)) => Some(*x),
            _ => None,
        };
        if fields.is_empty() {
            return Some(Shape::Undefined);
        }
        let json::Value::String(kind) = get("type")? else {
            return None;
        };
        let expect_keys = |keys: &[&str]| fields.iter().all(|(k, _)| keys.contains(&k.as_str()));
        match kind.as_str() {
            "Sphere" if expect_keys(&["type", "diameter"]) => Some(Shape::Sphere {
                diameter: number("diameter")?,
            }),
            "Ellipsoid" if expect_keys(&["type", "a", "b", "c"]) => Some(Shape::Ellipsoid {
                a: number("a")?,
                b: number("b")?,
                c: number("c")?,
            }),
            "ConvexPolyhedron" if expect_keys(&["type", "rounding_radius", "vertices"]) => {
                let rounding_radius = match get("rounding_radius") {
                    None => 0.0,
                    Some(_) => number("rounding_radius")?,
                };
                let json::Value::Array(rows) = get("vertices")? else {
                    return None;
                };
                let mut vertices = Vec::with_capacity(rows.len());
                for row in rows {
                    match row {
                        json::Value::Array(xyz) => match xyz.as_slice() {
                            [
                                json::Value::Number(x),
                                json::Value::Number(y),
                                json::Value::Number(z),
                            ] => vertices.push([*x, *y, *z]),
                            _ => return None,
                        },
                        _ => return None,
                    }
                }
                Some(Shape::ConvexPolyhedron {
                    rounding_radius,
                    vertices,
                })
            }
            _ => None,
        }
    }
}

/// Just enough JSON to read shape objects: a recursive-descent parser with a depth limit, so
/// that no file content can make it overflow the stack.
mod json {
    #[derive(Debug, PartialEq)]
    pub(super) enum Value {
        Null,
        Bool,
        Number(f64),
        String(String),
        Array(Vec<Value>),
        Object(Vec<(String, Value)>),
    }

    const MAX_DEPTH: usize = 64;

    pub(super) fn parse(text: &str) -> Option<Value> {
        let mut p = Parser {
            b: text.as_bytes(),
            at: 0,
        };
        let v = p.value(0)?;
        p.ws();
        (p.at == p.b.len()).then_some(v)
    }

    struct Parser<'a> {
        b: &'a [u8],
        at: usize,
    }

    impl Parser<'_> {
        fn ws(&mut self) {
            while self
                .b
                .get(self.at)
                .is_some_and(|c| matches!(c, b' ' | b'\t' | b'\n' | b'\r'))
            {
                self.at += 1;
            }
        }

        fn eat(&mut self, c: u8) -> bool {
            self.ws();
            if self.b.get(self.at) == Some(&c) {
                self.at += 1;
                true
            } else {
                false
            }
        }

        fn literal(&mut self, word: &str) -> bool {
            if self.b[self.at..].starts_with(word.as_bytes()) {
                self.at += word.len();
                true
            } else {
                false
            }
        }

        fn value(&mut self, depth: usize) -> Option<Value> {
            if depth > MAX_DEPTH {
                return None;
            }
            self.ws();
            match *self.b.get(self.at)? {
                b'{' => {
                    self.at += 1;
                    let mut fields = Vec::new();
                    if self.eat(b'}') {
                        return Some(Value::Object(fields));
                    }
                    loop {
                        self.ws();
                        let key = self.string()?;
                        if !self.eat(b':') {
                            return None;
                        }
                        fields.push((key, self.value(depth + 1)?));
                        if self.eat(b'}') {
                            return Some(Value::Object(fields));
                        }
                        if !self.eat(b',') {
                            return None;
                        }
                    }
                }
                b'[' => {
                    self.at += 1;
                    let mut items = Vec::new();
                    if self.eat(b']') {
                        return Some(Value::Array(items));
                    }
                    loop {
                        items.push(self.value(depth + 1)?);
                        if self.eat(b']') {
                            return Some(Value::Array(items));
                        }
                        if !self.eat(b',') {
                            return None;
                        }
                    }
                }
                b'"' => self.string().map(Value::String),
                b't' => self.literal("true").then_some(Value::Bool),
                b'f' => self.literal("false").then_some(Value::Bool),
                b'n' => self.literal("null").then_some(Value::Null),
                _ => self.number(),
            }
        }

        fn number(&mut self) -> Option<Value> {
            let start = self.at;
            while self
                .b
                .get(self.at)
                .is_some_and(|c| matches!(c, b'0'..=b'9' | b'-' | b'+' | b'.' | b'e' | b'E'))
            {
                self.at += 1;
            }
            let text = std::str::from_utf8(&self.b[start..self.at]).ok()?;
            // Rust's float syntax is a superset of JSON's on these characters except for
            // a leading '+' and forms like "1." or ".5"; refuse those.
            let digit_at = |i: usize| text.as_bytes().get(i).is_some_and(u8::is_ascii_digit);
            let first = usize::from(text.starts_with('-'));
            if !digit_at(first) || text.contains(".e") || text.contains(".E") || text.ends_with('.')
            {
                return None;
            }
            text.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .map(Value::Number)
        }

        fn string(&mut self) -> Option<String> {
            if self.b.get(self.at) != Some(&b'"') {
                return None;
            }
            self.at += 1;
            let mut out = String::new();
            loop {
                let c = *self.b.get(self.at)?;
                self.at += 1;
                match c {
                    b'"' => return Some(out),
                    b'\\' => {
                        let e = *self.b.get(self.at)?;
                        self.at += 1;
                        out.push(match e {
                            b'"' => '"',
                            b'\\' => '\\',
                            b'/' => '/',
                            b'b' => '\u{8}',
                            b'f' => '\u{c}',
                            b'n' => '\n',
                            b'r' => '\r',
                            b't' => '\t',
                            b'u' => {
                                let hex = self.b.get(self.at..self.at + 4)?;
                                self.at += 4;
                                let code =
                                    u32::from_str_radix(std::str::from_utf8(hex).ok()?, 16).ok()?;
                                // Surrogate pairs are not needed for shape keys; they read
                                // as the replacement character.
                                char::from_u32(code).unwrap_or('\u{fffd}')
                            }
                            _ => return None,
                        });
                    }
                    _ => {
                        // Copy one UTF-8 sequence (the input is a &str, so it is whole).
                        let start = self.at - 1;
                        let mut end = self.at;
                        while end < self.b.len() && (self.b[end] & 0xc0) == 0x80 {
                            end += 1;
                        }
                        out.push_str(std::str::from_utf8(&self.b[start..end]).ok()?);
                        self.at = end;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_shapes_round_trip_through_json() {
        let shapes = [
            Shape::Undefined,
            Shape::Sphere { diameter: 1.0 },
            Shape::Ellipsoid {
                a: 0.5,
                b: 0.25,
                c: 1e-7,
            },
            Shape::ConvexPolyhedron {
                rounding_radius: 0.1,
                vertices: vec![[0.5, 0.5, 0.5], [0.5, -0.5, -0.5], [-0.5, 0.5, -0.5]],
            },
            Shape::Other(
                r#"{"type": "SphereUnion", "diameters": [0.5], "centers": [[0, 0, 1]]}"#.into(),
            ),
        ];
        for s in shapes {
            let text = s.to_json().unwrap();
            assert_eq!(Shape::from_json(&text), s, "{text}");
        }
        assert_eq!(
            Shape::to_json(&Shape::Sphere { diameter: 1.0 }).unwrap(),
            r#"{"type":"Sphere","diameter":1.0}"#
        );
    }

    #[test]
    fn python_style_json_reads() {
        let s = Shape::from_json(
            r#"{"type": "ConvexPolyhedron", "rounding_radius": 0, "vertices": [[1, -2.5e-1, 3E2]]}"#,
        );
        assert_eq!(
            s,
            Shape::ConvexPolyhedron {
                rounding_radius: 0.0,
                vertices: vec![[1.0, -0.25, 300.0]]
            }
        );
    }

    #[test]
    fn garbage_is_kept_as_other_and_refused_on_write() {
        for text in [
            "",
            "{",
            "[1,2]",
            "{\"type\":",
            "nul",
            "{\"a\":1.}",
            &"[".repeat(10_000),
        ] {
            let s = Shape::from_json(text);
            assert_eq!(s, Shape::Other(text.to_string()));
            assert!(s.to_json().is_err());
        }
        assert!(Shape::Sphere { diameter: f64::NAN }.to_json().is_err());
    }
}
