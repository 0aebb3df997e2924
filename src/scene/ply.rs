//! PLY reading and writing: ascii, binary little and big endian; every scalar type and alias; list
//! properties with any count type; LF, CRLF and CR headers; any property order; extra elements read past.
//!
//! Reading never trusts the header: element counts are checked against what the remaining bytes could hold
//! before anything is allocated, and every read is bounds-checked, so a malformed file gives an error, never a
//! panic or an unbounded allocation.

use std::fmt::Write as _;
use std::io::Write;

use thiserror::Error;

/// A PLY problem, with the line (header) or element row (body) where it was found.
#[derive(Debug, Error, PartialEq)]
pub enum PlyError {
    /// The file does not start with `ply`.
    #[error("not a PLY file (it does not start with `ply`)")]
    NotPly,
    /// The header never ends.
    #[error("the header has no `end_header` line")]
    NoEndHeader,
    /// A header line that cannot be understood.
    #[error("header line {line}: {msg}")]
    Header {
        /// 1-based header line.
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// The body is shorter than the header says.
    #[error("the file ends early: {0}")]
    Truncated(String),
    /// A bad value in the body.
    #[error("element `{element}` row {row}: {msg}")]
    Body {
        /// Element name.
        element: String,
        /// 0-based row.
        row: usize,
        /// What is wrong.
        msg: String,
    },
    /// Valid PLY, but not something vvgen can use.
    #[error("{0}")]
    Unusable(String),
}

/// Body encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Text.
    Ascii,
    /// Little-endian binary.
    BinaryLe,
    /// Big-endian binary.
    BinaryBe,
}

/// A scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scalar {
    /// int8 / char
    I8,
    /// uint8 / uchar
    U8,
    /// int16 / short
    I16,
    /// uint16 / ushort
    U16,
    /// int32 / int
    I32,
    /// uint32 / uint
    U32,
    /// float32 / float
    F32,
    /// float64 / double
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// Size in bytes.
    pub fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    #[inline]
    fn read(self, b: &[u8], be: bool) -> f64 {
        macro_rules! rd {
            ($t:ty, $n:expr) => {{
                let a: [u8; $n] = b[..$n].try_into().unwrap();
                (if be { <$t>::from_be_bytes(a) } else { <$t>::from_le_bytes(a) }) as f64
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => rd!(i16, 2),
            Scalar::U16 => rd!(u16, 2),
            Scalar::I32 => rd!(i32, 4),
            Scalar::U32 => rd!(u32, 4),
            Scalar::F32 => rd!(f32, 4),
            Scalar::F64 => rd!(f64, 8),
        }
    }
}

/// A property of an element.
#[derive(Debug, Clone, PartialEq)]
pub struct Property {
    /// Name.
    pub name: String,
    /// `None` for a scalar, `Some(count type)` for a list.
    pub list: Option<Scalar>,
    /// Scalar (or list item) type.
    pub ty: Scalar,
}

/// An element declaration.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    /// Name (`vertex`, `face`, …).
    pub name: String,
    /// Row count.
    pub count: usize,
    /// Properties in file order.
    pub props: Vec<Property>,
}

/// A parsed header.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// Body encoding.
    pub format: Format,
    /// Elements in file order.
    pub elements: Vec<Element>,
    /// `comment` lines.
    pub comments: Vec<String>,
    /// `obj_info` lines.
    pub obj_info: Vec<String>,
    /// Byte offset where the body starts.
    pub body_start: usize,
}

/// Parses the header; the body starts right after the `end_header` line's terminator.
pub fn parse_header(bytes: &[u8]) -> Result<Header, PlyError> {
    if !bytes.starts_with(b"ply") {
        return Err(PlyError::NotPly);
    }
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let (mut comments, mut obj_info) = (Vec::new(), Vec::new());
    loop {
        if pos >= bytes.len() {
            return Err(PlyError::NoEndHeader);
        }
        // Lines end in LF, CRLF or a lone CR (Rhino).
        let rest = &bytes[pos..];
        let end = rest.iter().position(|&c| c == b'\n' || c == b'\r').ok_or(PlyError::NoEndHeader)?;
        let mut next = pos + end + 1;
        if rest[end] == b'\r' && rest.get(end + 1) == Some(&b'\n') {
            next += 1;
        }
        line_no += 1;
        let line = std::str::from_utf8(&rest[..end])
            .map_err(|_| PlyError::Header { line: line_no, msg: "not text".into() })?;
        let herr = |msg: String| PlyError::Header { line: line_no, msg };
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            None => {}
            Some("ply") if line_no == 1 => {}
            Some("format") => {
                format = Some(match words.next() {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::BinaryLe,
                    Some("binary_big_endian") => Format::BinaryBe,
                    other => return Err(herr(format!("unknown format `{}`", other.unwrap_or("")))),
                });
            }
            Some("comment") => comments.push(line.trim_start()[7..].trim().to_string()),
            Some("obj_info") => obj_info.push(line.trim_start()[8..].trim().to_string()),
            Some("element") => {
                let name = words.next().ok_or_else(|| herr("element without a name".into()))?;
                let count = words
                    .next()
                    .and_then(|c| c.parse::<usize>().ok())
                    .ok_or_else(|| herr(format!("element `{name}` has no valid count")))?;
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            Some("property") => {
                let el = elements.last_mut().ok_or_else(|| herr("property before any element".into()))?;
                let w: Vec<&str> = words.collect();
                let prop = match w.as_slice() {
                    ["list", c, t, n] => Property {
                        name: n.to_string(),
                        list: Some(
                            Scalar::parse(c)
                                .filter(|c| !c.is_float())
                                .ok_or_else(|| herr(format!("bad list count type `{c}`")))?,
                        ),
                        ty: Scalar::parse(t).ok_or_else(|| herr(format!("unknown type `{t}`")))?,
                    },
                    [t, n] => Property {
                        name: n.to_string(),
                        list: None,
                        ty: Scalar::parse(t).ok_or_else(|| herr(format!("unknown type `{t}`")))?,
                    },
                    _ => return Err(herr(format!("cannot read `{line}`"))),
                };
                el.props.push(prop);
            }
            Some("end_header") => {
                let format = format.ok_or_else(|| herr("no `format` line before end_header".into()))?;
                return Ok(Header { format, elements, comments, obj_info, body_start: next });
            }
            Some(w) => return Err(herr(format!("unknown header keyword `{w}`"))),
        }
        pos = next;
    }
}

/// What vvgen takes from a PLY: points with optional normals and colours, and triangles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlyData {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Vertex normals, when the file has nx/ny/nz.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Vertex colours as sRGB bytes (float colours in 0..1 are converted), when the file has them.
    pub colors: Option<Vec<[u8; 4]>>,
    /// Per-vertex texture coordinates (`texture_u`/`texture_v`, `s`/`t` or `u`/`v`; v up), when the file has them.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Triangles (polygons fan-triangulated), indices into `positions`.
    pub triangles: Vec<u32>,
    /// Header comments.
    pub comments: Vec<String>,
}

const SLOT_X: usize = 0;
const SLOT_NX: usize = 3;
const SLOT_R: usize = 6;
const SLOT_A: usize = 9;
const SLOT_U: usize = 10;
const NO_SLOT: usize = usize::MAX;

fn slot(name: &str) -> usize {
    match name {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        "nx" => 3,
        "ny" => 4,
        "nz" => 5,
        "red" | "r" | "diffuse_red" => 6,
        "green" | "g" | "diffuse_green" => 7,
        "blue" | "b" | "diffuse_blue" => 8,
        "alpha" | "a" | "diffuse_alpha" => 9,
        "texture_u" | "s" | "u" => 10,
        "texture_v" | "t" | "v" => 11,
        _ => NO_SLOT,
    }
}

/// Reads a PLY from memory.
pub fn read(bytes: &[u8]) -> Result<PlyData, PlyError> {
    let header = parse_header(bytes)?;
    let body = &bytes[header.body_start..];
    let mut out = PlyData { comments: header.comments.clone(), ..Default::default() };
    let mut cursor = Cursor { body, pos: 0, format: header.format };
    let mut vertex_seen = false;
    // Some writers call the points `point`; read that element when there is no `vertex`.
    let points = if header.elements.iter().any(|e| e.name == "vertex") { "vertex" } else { "point" };
    for el in &header.elements {
        match el.name.as_str() {
            name if name == points && !vertex_seen => {
                vertex_seen = true;
                read_vertices(&mut cursor, el, &mut out)?;
                // NaN or infinity would reach fits, bounds, cameras and images as garbage.
                // (A branch-free pass first: the search below runs only when something is not finite.)
                let finite = out
                    .positions
                    .iter()
                    .fold(true, |ok, p| ok & p[0].is_finite() & p[1].is_finite() & p[2].is_finite());
                if let Some(row) =
                    (!finite).then(|| out.positions.iter().position(|p| !p.iter().all(|c| c.is_finite()))).flatten()
                {
                    let msg = format!("position {:?} is not finite", out.positions[row]);
                    return Err(PlyError::Body { element: points.into(), row, msg });
                }
            }
            "face" => read_faces(&mut cursor, el, out.positions.len(), &mut out.triangles)?,
            _ => cursor.skip_element(el)?,
        }
    }
    if !vertex_seen {
        return Err(PlyError::Unusable("no `vertex` (or `point`) element".into()));
    }
    Ok(out)
}

struct Cursor<'a> {
    body: &'a [u8],
    pos: usize,
    format: Format,
}

impl<'a> Cursor<'a> {
    fn remaining(&self) -> usize {
        self.body.len() - self.pos
    }

    /// Rejects counts the rest of the file cannot hold, before allocating for them.
    fn check_count(&self, el: &Element) -> Result<(), PlyError> {
        let min_row: usize = match self.format {
            // Every ascii value takes at least one character and one separator.
            Format::Ascii => 2 * el.props.len().max(1),
            _ => el.props.iter().map(|p| p.list.map_or(p.ty.size(), |c| c.size())).sum::<usize>().max(1),
        };
        if el.count.checked_mul(min_row).is_none_or(|n| n > self.remaining()) {
            return Err(PlyError::Truncated(format!(
                "element `{}` declares {} rows, more than the remaining {} bytes can hold",
                el.name,
                el.count,
                self.remaining()
            )));
        }
        Ok(())
    }

    #[inline]
    fn token(&mut self) -> Option<&'a [u8]> {
        let b = self.body;
        let mut i = self.pos;
        while i < b.len() && b[i].is_ascii_whitespace() {
            i += 1;
        }
        let s = i;
        while i < b.len() && !b[i].is_ascii_whitespace() {
            i += 1;
        }
        self.pos = i;
        (i > s).then(|| &b[s..i])
    }

    /// One value of type `ty`.
    #[inline]
    fn value(&mut self, ty: Scalar, el: &Element, row: usize) -> Result<f64, PlyError> {
        match self.format {
            Format::Ascii => {
                let t = self
                    .token()
                    .ok_or_else(|| PlyError::Truncated(format!("element `{}` row {row} is incomplete", el.name)))?;
                parse_number(t).ok_or_else(|| PlyError::Body {
                    element: el.name.clone(),
                    row,
                    msg: format!("`{}` is not a number", String::from_utf8_lossy(t)),
                })
            }
            f => {
                let n = ty.size();
                if self.remaining() < n {
                    return Err(PlyError::Truncated(format!("element `{}` row {row} is incomplete", el.name)));
                }
                let v = ty.read(&self.body[self.pos..], f == Format::BinaryBe);
                self.pos += n;
                Ok(v)
            }
        }
    }

    fn list_len(&mut self, count_ty: Scalar, el: &Element, row: usize) -> Result<usize, PlyError> {
        let v = self.value(count_ty, el, row)?;
        if !(v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64) {
            return Err(PlyError::Body {
                element: el.name.clone(),
                row,
                msg: format!("list length {v} is not a count"),
            });
        }
        Ok(v as usize)
    }

    fn skip_element(&mut self, el: &Element) -> Result<(), PlyError> {
        self.check_count(el)?;
        for row in 0..el.count {
            for p in &el.props {
                match p.list {
                    None => {
                        self.value(p.ty, el, row)?;
                    }
                    Some(c) => {
                        let n = self.list_len(c, el, row)?;
                        if self.format != Format::Ascii {
                            let bytes = n.checked_mul(p.ty.size()).filter(|&b| b <= self.remaining());
                            self.pos += bytes.ok_or_else(|| {
                                PlyError::Truncated(format!("element `{}` row {row}: list of {n} items", el.name))
                            })?;
                        } else {
                            for _ in 0..n {
                                self.value(p.ty, el, row)?;
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// Parses an ascii number; integers take a fast path (8i frames are all integers).
#[inline]
fn parse_number(t: &[u8]) -> Option<f64> {
    let (neg, digits) = match t.first()? {
        b'-' => (true, &t[1..]),
        b'+' => (false, &t[1..]),
        _ => (false, t),
    };
    if !digits.is_empty() && digits.len() <= 15 && digits.iter().all(u8::is_ascii_digit) {
        let v = digits.iter().fold(0u64, |a, &d| a * 10 + (d - b'0') as u64) as f64;
        return Some(if neg { -v } else { v });
    }
    std::str::from_utf8(t).ok()?.parse::<f64>().ok()
}

fn read_vertices(c: &mut Cursor<'_>, el: &Element, out: &mut PlyData) -> Result<(), PlyError> {
    c.check_count(el)?;
    let slots: Vec<usize> = el.props.iter().map(|p| if p.list.is_some() { NO_SLOT } else { slot(&p.name) }).collect();
    let has = |s: usize| slots.contains(&s);
    if !(has(SLOT_X) && has(SLOT_X + 1) && has(SLOT_X + 2)) {
        return Err(PlyError::Unusable("the vertex element has no x, y, z".into()));
    }
    let has_n = has(SLOT_NX) && has(SLOT_NX + 1) && has(SLOT_NX + 2);
    let has_c = has(SLOT_R) && has(SLOT_R + 1) && has(SLOT_R + 2);
    let has_uv = has(SLOT_U) && has(SLOT_U + 1);
    // Float colours are 0..1; integer colours scale by their type's maximum.
    let color_scale = el
        .props
        .iter()
        .zip(&slots)
        .find(|(_, &s)| s == SLOT_R)
        .map(|(p, _)| match p.ty {
            Scalar::F32 | Scalar::F64 => 255.0,
            Scalar::U16 | Scalar::I16 => 255.0 / 65535.0,
            _ => 1.0,
        })
        .unwrap_or(1.0);
    let n = el.count;
    out.positions = Vec::with_capacity(n);
    let mut normals = Vec::with_capacity(if has_n { n } else { 0 });
    let mut colors = Vec::with_capacity(if has_c { n } else { 0 });
    let mut uvs = Vec::with_capacity(if has_uv { n } else { 0 });
    let fixed: Option<Vec<usize>> =
        (c.format != Format::Ascii && el.props.iter().all(|p| p.list.is_none())).then(|| {
            let mut off = 0;
            el.props
                .iter()
                .map(|p| {
                    let o = off;
                    off += p.ty.size();
                    o
                })
                .collect()
        });
    let mut v = [0f64; 12];
    v[SLOT_A] = 255.0;
    if let Some(offsets) = fixed {
        // Fixed-size rows: one bounds check for the whole element, then straight reads.
        let row_size: usize = el.props.iter().map(|p| p.ty.size()).sum();
        let total = row_size * n;
        if c.remaining() < total {
            return Err(PlyError::Truncated(format!("vertex data needs {total} bytes, {} remain", c.remaining())));
        }
        let be = c.format == Format::BinaryBe;
        let data = &c.body[c.pos..c.pos + total];
        let mapped: Vec<(usize, Scalar, usize)> = el
            .props
            .iter()
            .zip(&offsets)
            .zip(&slots)
            .filter(|(_, &s)| s != NO_SLOT)
            .map(|((p, &o), &s)| (o, p.ty, s))
            .collect();
        let rows = || data.chunks_exact(row_size);
        // Column fast paths: a group of three consecutive properties of one type (x y z float, nx ny nz float,
        // red green blue uchar) is decoded by one tight loop each; anything else goes through the generic row loop.
        let group = |first: usize, ty: Scalar| -> Option<usize> {
            let at = |s: usize| mapped.iter().find(|m| m.2 == s);
            let (a, b, c) = (at(first)?, at(first + 1)?, at(first + 2)?);
            (a.1 == ty && b.1 == ty && c.1 == ty && b.0 == a.0 + ty.size() && c.0 == b.0 + ty.size()).then_some(a.0)
        };
        let f = |r: &[u8], o: usize| {
            let b = [r[o], r[o + 1], r[o + 2], r[o + 3]];
            if be {
                f32::from_be_bytes(b)
            } else {
                f32::from_le_bytes(b)
            }
        };
        let xyz = group(SLOT_X, Scalar::F32);
        let nxyz = if has_n { group(SLOT_NX, Scalar::F32) } else { None };
        let rgb = if has_c && !slots.contains(&SLOT_A) { group(SLOT_R, Scalar::U8) } else { None };
        if let Some(o) = xyz.filter(|_| (!has_n || nxyz.is_some()) && (!has_c || rgb.is_some()) && !has_uv && !be) {
            // Little-endian (what every writer of large clouds emits): each column group read as a fixed-size
            // array (no per-byte bounds checks, no per-value endianness branch), into exactly sized vectors.
            let xyz3 = |r: &[u8], o: usize| {
                let b: &[u8; 12] = r[o..o + 12].try_into().expect("BUG: the row holds the group");
                let w = |k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
                [w(0), w(4), w(8)]
            };
            out.positions = rows().map(|r| xyz3(r, o)).collect();
            if let Some(o) = nxyz {
                normals = rows().map(|r| xyz3(r, o)).collect();
            }
            if let Some(o) = rgb {
                let rgb3 = |r: &[u8]| -> [u8; 4] {
                    let c: &[u8; 3] = r[o..o + 3].try_into().expect("BUG: the row holds the group");
                    [c[0], c[1], c[2], 255]
                };
                colors = rows().map(rgb3).collect();
            }
        } else if let Some(o) = xyz.filter(|_| (!has_n || nxyz.is_some()) && (!has_c || rgb.is_some()) && !has_uv) {
            out.positions = rows().map(|r| [f(r, o), f(r, o + 4), f(r, o + 8)]).collect();
            if let Some(o) = nxyz {
                normals = rows().map(|r| [f(r, o), f(r, o + 4), f(r, o + 8)]).collect();
            }
            if let Some(o) = rgb {
                colors = rows().map(|r| [r[o], r[o + 1], r[o + 2], 255]).collect();
            }
        } else {
            for row in rows() {
                for &(o, t, s) in &mapped {
                    v[s] = t.read(&row[o..], be);
                }
                out.positions.push([v[0] as f32, v[1] as f32, v[2] as f32]);
                if has_n {
                    normals.push([v[3] as f32, v[4] as f32, v[5] as f32]);
                }
                if has_c {
                    colors.push(to_rgba8(&v, color_scale));
                }
                if has_uv {
                    uvs.push([v[SLOT_U] as f32, v[SLOT_U + 1] as f32]);
                }
            }
        }
        c.pos += total;
    } else {
        for row in 0..n {
            for (p, &s) in el.props.iter().zip(&slots) {
                match p.list {
                    None => {
                        let x = c.value(p.ty, el, row)?;
                        if s != NO_SLOT {
                            v[s] = x;
                        }
                    }
                    Some(ct) => {
                        let len = c.list_len(ct, el, row)?;
                        for _ in 0..len {
                            c.value(p.ty, el, row)?;
                        }
                    }
                }
            }
            out.positions.push([v[0] as f32, v[1] as f32, v[2] as f32]);
            if has_n {
                normals.push([v[3] as f32, v[4] as f32, v[5] as f32]);
            }
            if has_c {
                colors.push(to_rgba8(&v, color_scale));
            }
            if has_uv {
                uvs.push([v[SLOT_U] as f32, v[SLOT_U + 1] as f32]);
            }
        }
    }
    out.normals = has_n.then_some(normals);
    out.uvs = has_uv.then_some(uvs);
    out.colors = has_c.then_some(colors);
    Ok(())
}

#[inline]
fn to_rgba8(v: &[f64; 12], scale: f64) -> [u8; 4] {
    let q = |x: f64| (x * scale).round().clamp(0.0, 255.0) as u8;
    [q(v[6]), q(v[7]), q(v[8]), q(v[9])]
}

fn read_faces(c: &mut Cursor<'_>, el: &Element, n_vertices: usize, tris: &mut Vec<u32>) -> Result<(), PlyError> {
    c.check_count(el)?;
    let list_idx =
        el.props.iter().position(|p| p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index"));
    tris.reserve(el.count.min(c.remaining()) * 3);
    let mut poly: Vec<u32> = Vec::new();
    for row in 0..el.count {
        for (i, p) in el.props.iter().enumerate() {
            match p.list {
                None => {
                    c.value(p.ty, el, row)?;
                }
                Some(ct) => {
                    let len = c.list_len(ct, el, row)?;
                    if Some(i) != list_idx {
                        for _ in 0..len {
                            c.value(p.ty, el, row)?;
                        }
                        continue;
                    }
                    if len > c.remaining() {
                        return Err(PlyError::Truncated(format!("face row {row} lists {len} vertices")));
                    }
                    poly.clear();
                    for _ in 0..len {
                        let v = c.value(p.ty, el, row)?;
                        if !(v >= 0.0 && (v as usize) < n_vertices) {
                            return Err(PlyError::Body {
                                element: el.name.clone(),
                                row,
                                msg: format!("vertex index {v} is out of range (0..{n_vertices})"),
                            });
                        }
                        poly.push(v as u32);
                    }
                    for k in 1..poly.len().saturating_sub(1) {
                        tris.extend_from_slice(&[poly[0], poly[k], poly[k + 1]]);
                    }
                }
            }
        }
    }
    Ok(())
}

/// Points (and optional triangles) to write.
#[derive(Debug, Clone, Copy, Default)]
pub struct PlyOut<'a> {
    /// Positions.
    pub positions: &'a [[f32; 3]],
    /// Normals (`nx ny nz` float).
    pub normals: Option<&'a [[f32; 3]]>,
    /// Colours (`red green blue` uchar).
    pub colors: Option<&'a [[u8; 3]]>,
    /// Extra per-vertex `uint` properties, e.g. `point_id`.
    pub extra_u32: &'a [(&'a str, &'a [u32])],
    /// Extra per-vertex `float` properties, e.g. motion vectors.
    pub extra_f32: &'a [(&'a str, &'a [f32])],
    /// Triangles (`face` element, `list uchar int vertex_indices`).
    pub triangles: Option<&'a [u32]>,
    /// `comment` lines.
    pub comments: &'a [&'a str],
    /// Write `ascii` instead of `binary_little_endian`.
    pub ascii: bool,
}

/// Encodes a PLY; the header lists exactly the properties written.
pub fn write(out: &PlyOut<'_>) -> Vec<u8> {
    let n = out.positions.len();
    let mut h = String::from("ply\n");
    h.push_str(if out.ascii { "format ascii 1.0\n" } else { "format binary_little_endian 1.0\n" });
    for c in out.comments {
        let _ = writeln!(h, "comment {c}");
    }
    let _ = writeln!(h, "element vertex {n}");
    h.push_str("property float x\nproperty float y\nproperty float z\n");
    if out.normals.is_some() {
        h.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if out.colors.is_some() {
        h.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    for (name, _) in out.extra_u32 {
        let _ = writeln!(h, "property uint {name}");
    }
    for (name, _) in out.extra_f32 {
        let _ = writeln!(h, "property float {name}");
    }
    let tris = out.triangles.unwrap_or(&[]);
    if out.triangles.is_some() {
        let _ = writeln!(h, "element face {}\nproperty list uchar int vertex_indices", tris.len() / 3);
    }
    h.push_str("end_header\n");
    let mut buf = Vec::with_capacity(h.len() + n * 40);
    buf.extend_from_slice(h.as_bytes());
    if out.ascii {
        let mut fmt = ryu::Buffer::new();
        let mut put = |buf: &mut Vec<u8>, v: f32| {
            // Integer values (8i's vox10 coordinates) are written as integers, like 8i's files; others in the
            // shortest form that reads back to the same f32.
            if v.fract() == 0.0 && v.abs() < 1e7 {
                let _ = write!(buf, "{}", v as i64);
            } else {
                buf.extend_from_slice(fmt.format(v).as_bytes());
            }
        };
        for i in 0..n {
            let mut first = true;
            let mut sep = |buf: &mut Vec<u8>| {
                if !first {
                    buf.push(b' ');
                }
                first = false;
            };
            for v in out.positions[i] {
                sep(&mut buf);
                put(&mut buf, v);
            }
            if let Some(nr) = out.normals {
                for v in nr[i] {
                    sep(&mut buf);
                    put(&mut buf, v);
                }
            }
            if let Some(c) = out.colors {
                for v in c[i] {
                    sep(&mut buf);
                    let _ = write!(buf, "{v}");
                }
            }
            for (_, v) in out.extra_u32 {
                sep(&mut buf);
                let _ = write!(buf, "{}", v[i]);
            }
            for (_, v) in out.extra_f32 {
                sep(&mut buf);
                put(&mut buf, v[i]);
            }
            buf.push(b'\n');
        }
        for t in tris.chunks_exact(3) {
            let _ = writeln!(buf, "3 {} {} {}", t[0], t[1], t[2]);
        }
    } else {
        // Exact-size rows filled in place: no per-value capacity checks.
        let row = 12
            + out.normals.map_or(0, |_| 12)
            + out.colors.map_or(0, |_| 3)
            + 4 * (out.extra_u32.len() + out.extra_f32.len());
        let start = buf.len();
        buf.resize(start + row * n, 0);
        let rows = buf[start..].chunks_exact_mut(row);
        if out.normals.is_none() && out.extra_u32.is_empty() && out.extra_f32.is_empty() {
            // The common layouts (x y z [red green blue]) with fixed offsets, so the loop compiles to plain stores.
            for (i, r) in rows.enumerate() {
                let p = out.positions[i];
                r[0..4].copy_from_slice(&p[0].to_le_bytes());
                r[4..8].copy_from_slice(&p[1].to_le_bytes());
                r[8..12].copy_from_slice(&p[2].to_le_bytes());
                if let Some(c) = out.colors {
                    r[12..15].copy_from_slice(&c[i]);
                }
            }
        } else {
            for (i, r) in rows.enumerate() {
                let mut o = 0;
                let mut put = |bytes: &[u8]| {
                    r[o..o + bytes.len()].copy_from_slice(bytes);
                    o += bytes.len();
                };
                for v in out.positions[i] {
                    put(&v.to_le_bytes());
                }
                if let Some(nr) = out.normals {
                    for v in nr[i] {
                        put(&v.to_le_bytes());
                    }
                }
                if let Some(c) = out.colors {
                    put(&c[i]);
                }
                for (_, v) in out.extra_u32 {
                    put(&v[i].to_le_bytes());
                }
                for (_, v) in out.extra_f32 {
                    put(&v[i].to_le_bytes());
                }
            }
        }
        for t in tris.chunks_exact(3) {
            buf.push(3);
            for &i in t {
                buf.extend_from_slice(&(i as i32).to_le_bytes());
            }
        }
    }
    buf
}

#[cfg(test)]
mod tests {
    use super::*;

    type Cloud = (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<[u8; 3]>);

    fn cloud() -> Cloud {
        let p: Vec<[f32; 3]> = (0..100).map(|i| [i as f32 * 0.5, -(i as f32), 1e-3 * i as f32]).collect();
        let n: Vec<[f32; 3]> = (0..100).map(|i| [0.0, (i % 2) as f32, 1.0 - (i % 2) as f32]).collect();
        let c: Vec<[u8; 3]> = (0..100).map(|i| [i as u8, 255 - i as u8, 7]).collect();
        (p, n, c)
    }

    #[test]
    fn round_trip_binary_and_ascii() {
        let (p, n, c) = cloud();
        let tris = [0u32, 1, 2, 2, 3, 0];
        for ascii in [false, true] {
            let bytes = write(&PlyOut {
                positions: &p,
                normals: Some(&n),
                colors: Some(&c),
                triangles: Some(&tris),
                ascii,
                ..Default::default()
            });
            let d = read(&bytes).unwrap();
            assert_eq!(d.positions, p);
            assert_eq!(d.normals.unwrap(), n);
            assert_eq!(d.colors.unwrap().iter().map(|c| [c[0], c[1], c[2]]).collect::<Vec<_>>(), c);
            assert_eq!(d.triangles, tris);
        }
    }

    #[test]
    fn big_endian_and_lone_cr_headers() {
        let mut b = b"ply\rformat binary_big_endian 1.0\relement vertex 1\rproperty double x\rproperty short y\rproperty uint z\rend_header\r".to_vec();
        b.extend_from_slice(&1.5f64.to_be_bytes());
        b.extend_from_slice(&(-2i16).to_be_bytes());
        b.extend_from_slice(&7u32.to_be_bytes());
        assert_eq!(read(&b).unwrap().positions, [[1.5, -2.0, 7.0]]);
    }

    #[test]
    fn absurd_counts_fail_before_allocating() {
        let b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0";
        assert!(matches!(read(b), Err(PlyError::Truncated(_))));
        let b = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n4 5\n";
        assert!(matches!(read(b), Err(PlyError::Truncated(_))), "{:?}", read(b));
        let b = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 zz\n";
        assert!(matches!(read(b), Err(PlyError::Body { .. })));
    }
}
