//! The PLY header: body format, scalar types, elements and their properties, parsed and checked before any
//! of the body is read.

use super::PlyError;

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

    pub(super) fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The value at the start of `b` (big endian when `be`), as f64.
    #[inline]
    pub(super) fn read(self, b: &[u8], be: bool) -> f64 {
        macro_rules! rd {
            ($t:ty, $n:expr) => {{
                let a: [u8; $n] = b[..$n].try_into().expect("BUG: a slice of $n bytes");
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
        // A comment may be in a legacy encoding (a Latin-1 author's name): read as far as it is text.
        let raw = &rest[..end];
        let line = match std::str::from_utf8(raw) {
            Ok(line) => std::borrow::Cow::Borrowed(line),
            Err(_) if raw.starts_with(b"comment") || raw.starts_with(b"obj_info") => String::from_utf8_lossy(raw),
            Err(_) => return Err(PlyError::Header { line: line_no, msg: "not text".into() }),
        };
        let line = line.as_ref();
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
            // Blender 2.4x's exporter wrote its "Created by Blender3D …" line after `format`, without
            // `comment`; Blender's importer reads any such line before the first element as a comment.
            Some(_) if elements.is_empty() => comments.push(line.trim().to_string()),
            Some(w) => return Err(herr(format!("unknown header keyword `{w}`"))),
        }
        pos = next;
    }
}
