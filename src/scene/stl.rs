//! STL files (`mesh = "part.stl"`, and `.stl` frames of a `mesh_sequence`), read as Blender 4.5's importer reads
//! them: binary or ASCII, one mesh of every solid in the file, flat-shaded (each triangle's normal is its own, from
//! its corners; the normals the file writes are ignored, as Blender ignores them by default), grey, both sides
//! drawn, triangles with two corners at one point left out.
//!
//! Hand-written rather than through the `stl_io` crate: that crate takes any file starting with `solid ` for
//! ASCII, and SolidWorks, Onshape and others write binary files that start so (seven of trimesh's sixteen binary
//! test files); its errors carry no line. Which form a file is in is decided by its size, as Blender decides it:
//! a binary file is an 80-byte header, a 32-bit triangle count and 50 bytes per triangle.

use std::path::Path;

use glam::Vec3;

use super::material::Material;
use super::posed::{PosedScene, PrimKind};
use super::Error;

/// A binary STL's header, triangle count and bytes per triangle.
const HEADER: usize = 80;
const COUNTED: usize = HEADER + 4;
const TRIANGLE: usize = 50;

/// A problem at a place in an STL file: the 1-based line of an ASCII file (`None` for a binary one) and what is
/// wrong, the column in it.
#[derive(Debug, PartialEq)]
struct Problem {
    line: Option<usize>,
    message: String,
}

impl Problem {
    fn at(line: usize, message: String) -> Problem {
        Problem { line: Some(line), message }
    }
}

/// An STL file's mesh in source space (STL is +Z up, in whatever unit it was made in: millimetres for most
/// printed parts).
pub fn scene(path: &Path) -> Result<PosedScene, Error> {
    let bytes = std::fs::read(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    let corners =
        triangles(&bytes).map_err(|p| Error::Mesh { path: path.to_path_buf(), line: p.line, message: p.message })?;
    // The file's bytes go before the mesh is made (a load's peak: 100 MB for two million triangles).
    drop(bytes);
    Ok(posed(corners))
}

/// Whether a file is an STL, by its extension.
pub(crate) fn is_stl(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("stl"))
}

/// Every triangle's three corners, in the file's order, the degenerate ones (two corners at one point, which
/// Blender's importer removes) left out.
fn triangles(bytes: &[u8]) -> Result<Vec<[Vec3; 3]>, Problem> {
    let mut out = match form(bytes, bytes.len() as u64)? {
        Form::Binary(n) => binary(bytes, n)?,
        Form::Ascii => ascii(bytes)?,
    };
    out.retain(|[a, b, c]| a != b && b != c && a != c);
    Ok(out)
}

/// What `vvgen check` can refuse in an STL frame without reading it all (a sequence's frames are read when they
/// render): not an STL, or a binary one cut short. Reads its first bytes and its size.
pub(crate) fn check_file(path: &Path) -> Result<(), Error> {
    use std::io::Read;
    let io = |e| Error::Io { path: path.to_path_buf(), source: e };
    let file = std::fs::File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let mut head = Vec::with_capacity(HEAD);
    file.take(HEAD as u64).read_to_end(&mut head).map_err(io)?;
    let problem = match form(&head, len) {
        Ok(Form::Binary(n)) => cut_short(n, len),
        Ok(Form::Ascii) => None,
        Err(p) => Some(p),
    };
    problem.map_or(Ok(()), |p| Err(Error::Mesh { path: path.to_path_buf(), line: p.line, message: p.message }))
}

/// How much of a file's start [`form`] looks at.
const HEAD: usize = 4096;

/// An STL's form, and a binary one's triangle count.
enum Form {
    Binary(usize),
    Ascii,
}

/// The form of the STL of size `len` that starts with `head` (its first [`HEAD`] bytes, or all of it). Blender
/// decides by size alone (binary when it is what the triangle count makes it); here a file is text when it starts
/// with `solid` and reads as text after that line (ASCII, with a `facet` or `endsolid` in it), else binary when it
/// is long enough to be: so SolidWorks' binary files, whose header starts with `solid`, are binary whatever their
/// size, and one cut short says so. A file too short for a binary STL's header that does not start with `solid`
/// is none.
fn form(head: &[u8], len: u64) -> Result<Form, Problem> {
    let head = &head[..head.len().min(HEAD)];
    let after = head.iter().position(|&b| b == b'\n').map_or(&[][..], |i| &head[i + 1..]);
    let keyword = |k: &[u8]| after.windows(k.len()).any(|w| w == k);
    let text = starts_solid(head) && after.is_ascii() && (keyword(b"facet") || keyword(b"endsolid"));
    if let Some(n) = count(head).filter(|_| !text) {
        return Ok(Form::Binary(n as usize));
    }
    if starts_solid(head) {
        return Ok(Form::Ascii);
    }
    // Shorter than a binary header (else it was taken as binary above): `head` is the whole file.
    let message = if head.iter().all(u8::is_ascii_whitespace) {
        "empty: neither a binary nor an ASCII STL".to_string()
    } else {
        format!(
            "{len} bytes: too short for a binary STL (its header is {COUNTED} bytes) and not text starting with \
                 `solid`"
        )
    };
    Err(Problem { line: None, message })
}

/// Why a binary STL of `n` triangles and `len` bytes cannot be read, when it is shorter than they need.
fn cut_short(n: usize, len: u64) -> Option<Problem> {
    let need = COUNTED as u64 + (n as u64) * TRIANGLE as u64;
    (len < need).then(|| Problem {
        line: None,
        message: format!(
            "a binary STL whose header counts {n} triangles ({need} bytes) but that holds {len} bytes: it is cut \
             short; copy or export it again"
        ),
    })
}

/// A binary STL's triangle count, when `bytes` are long enough to hold one.
fn count(bytes: &[u8]) -> Option<u32> {
    bytes.get(HEADER..COUNTED).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
}

/// Whether `bytes` start as an ASCII STL does: `solid`, after any blank space.
fn starts_solid(bytes: &[u8]) -> bool {
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(bytes.len());
    bytes[start..].starts_with(b"solid")
}

/// A binary STL's `n` triangles. The count is checked against the file's size before anything is allocated
/// for it.
fn binary(bytes: &[u8], n: usize) -> Result<Vec<[Vec3; 3]>, Problem> {
    if let Some(p) = cut_short(n, bytes.len() as u64) {
        return Err(p);
    }
    let body = &bytes[COUNTED..];
    let f = |b: &[u8], i: usize| f32::from_le_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]]);
    let mut out = Vec::with_capacity(n);
    for (t, b) in body.chunks_exact(TRIANGLE).take(n).enumerate() {
        // 12 bytes of normal (ignored), three corners, two bytes of attributes (ignored, as Blender does).
        let corner = |k: usize| Vec3::new(f(b, 3 + 3 * k), f(b, 4 + 3 * k), f(b, 5 + 3 * k));
        let tri = [corner(0), corner(1), corner(2)];
        if !tri.iter().all(|v| v.is_finite()) {
            return Err(Problem {
                line: None,
                message: format!(
                    "triangle {t} (byte {}) has a corner that is not a finite number",
                    COUNTED + t * TRIANGLE
                ),
            });
        }
        out.push(tri);
    }
    Ok(out)
}

/// The words an ASCII STL is made of, each with the 1-based column it starts at.
fn words(line: &str) -> impl Iterator<Item = (usize, &str)> {
    line.split_ascii_whitespace().map(move |w| (w.as_ptr() as usize - line.as_ptr() as usize + 1, w))
}

/// What an ASCII STL may hold, said when a line holds something else.
const ASCII_HELP: &str =
    "an ASCII STL holds `solid NAME`, then per triangle `facet normal X Y Z`, `outer loop`, three \
                          `vertex X Y Z` lines, `endloop` and `endfacet`, and ends with `endsolid NAME`";

/// An ASCII STL's triangles, of every `solid` in it (Blender reads them into one mesh). The facets' normals are
/// not read (some writers put `nan` there for a degenerate facet).
fn ascii(bytes: &[u8]) -> Result<Vec<[Vec3; 3]>, Problem> {
    let mut out = Vec::new();
    // The open facet's corners and the line it opened at; whether a solid is open.
    let (mut facet, mut opened, mut solid): (Vec<Vec3>, usize, bool) = (Vec::new(), 0, false);
    let mut in_facet = false;
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = i + 1;
        // Names after `solid` may be in any encoding; the keywords and numbers are ASCII.
        let line = String::from_utf8_lossy(raw);
        let mut w = words(&line);
        let Some((col, key)) = w.next() else {
            continue;
        };
        let unexpected =
            |what: &str| Problem::at(line_no, format!("column {col}: `{key}` where {what} was expected. {ASCII_HELP}"));
        match key {
            "solid" if !solid && !in_facet => solid = true,
            _ if !solid => {
                return Err(unexpected(if out.is_empty() { "`solid`" } else { "`solid` or the end of the file" }))
            }
            "endsolid" if !in_facet => solid = false,
            "facet" if !in_facet => (in_facet, opened) = (true, line_no),
            "outer" | "endloop" if in_facet => {}
            "vertex" if in_facet => {
                let mut v = [0.0f32; 3];
                for (k, slot) in v.iter_mut().enumerate() {
                    let Some((c, word)) = w.next() else {
                        return Err(Problem::at(line_no, format!("`vertex` needs three numbers; it has {k}")));
                    };
                    *slot =
                        word.parse::<f32>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                            Problem::at(line_no, format!("column {c}: `{word}` is not a finite number"))
                        })?;
                }
                facet.push(Vec3::from(v));
            }
            "endfacet" if in_facet => {
                let [a, b, c] = facet[..] else {
                    return Err(Problem::at(
                        opened,
                        format!("this facet has {} `vertex` lines; an STL facet has three", facet.len()),
                    ));
                };
                out.push([a, b, c]);
                facet.clear();
                in_facet = false;
            }
            _ if in_facet => return Err(unexpected("`outer loop`, `vertex`, `endloop` or `endfacet`")),
            _ => return Err(unexpected("`facet` or `endsolid`")),
        }
    }
    if in_facet {
        return Err(Problem::at(opened, "the file ends inside this facet: it is cut short".into()));
    }
    Ok(out)
}

/// The triangles as one flat-shaded primitive of Blender's grey, drawn from both sides (Cycles draws both): each
/// triangle has its own three vertices, with its own normal.
fn posed(triangles: Vec<[Vec3; 3]>) -> PosedScene {
    let mut normals = Vec::with_capacity(3 * triangles.len());
    for [a, b, c] in &triangles {
        normals.extend([(*b - *a).cross(*c - *a).normalize_or_zero(); 3]);
    }
    // The corners are the positions, in place.
    let positions = triangles.into_flattened();
    // Three vertices per triangle: a file of over 1.4 billion triangles (72 GB) would overflow the indices.
    let indices = (0..positions.len().min(u32::MAX as usize) as u32).collect();
    let material = Material { double_sided: true, ..Material::unassigned() };
    PosedScene::single(PrimKind::Triangles, positions, normals, Vec::new(), indices, material)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binary_file(header: &[u8], tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut b = header.to_vec();
        b.resize(HEADER, b' ');
        b.extend((tris.len() as u32).to_le_bytes());
        for t in tris {
            b.extend([0u8; 12]);
            t.iter().flatten().for_each(|x| b.extend(x.to_le_bytes()));
            b.extend([0u8; 2]);
        }
        b
    }

    const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn a_binary_file_is_told_by_its_size_even_when_it_starts_with_solid() {
        for header in [&b"solid part exported by SolidWorks"[..], b"Binary STL output from Blender"] {
            let got = triangles(&binary_file(header, &[TRI, TRI])).unwrap();
            assert_eq!(got.len(), 2);
            assert_eq!(got[0], TRI.map(Vec3::from));
        }
        // Cut short: the count says two, one is there.
        let mut cut = binary_file(b"x", &[TRI, TRI]);
        cut.truncate(COUNTED + TRIANGLE);
        let e = triangles(&cut).unwrap_err();
        assert!(e.message.contains("counts 2 triangles") && e.message.contains("cut short"), "{}", e.message);
        // An absurd count on a short file is refused before anything is allocated for it.
        let mut absurd = binary_file(b"x", &[TRI]);
        absurd[HEADER..COUNTED].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(triangles(&absurd).unwrap_err().message.contains("cut short"));
        let mut nan = binary_file(b"x", &[TRI]);
        nan[COUNTED + 12..COUNTED + 16].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(triangles(&nan).unwrap_err().message.contains("triangle 0"));
    }

    #[test]
    fn ascii_files_read_every_solid_and_say_where_they_go_wrong() {
        let facet = |z: f32| {
            format!(
                "  facet normal nan nan nan\n    outer loop\n      vertex 0 0 {z}\n      vertex 1 0 {z}\r\n      \
                 vertex 0 1e0 {z}\n    endloop\n  endfacet\n"
            )
        };
        let text = format!("solid a\n{}endsolid a\nsolid b\n{}endsolid b\n", facet(0.0), facet(2.0));
        let got = triangles(text.as_bytes()).unwrap();
        assert_eq!(got.len(), 2);
        assert_eq!(got[1][2], Vec3::new(0.0, 1.0, 2.0));
        // Without `endsolid` at the end, as some writers leave it.
        assert_eq!(triangles(format!("solid\n{}", facet(0.0)).as_bytes()).unwrap().len(), 1);
        let bad = |text: &str| triangles(text.as_bytes()).unwrap_err();
        let e = bad("solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 zero\n");
        assert_eq!(e.line, Some(4));
        assert!(e.message.contains("column 15: `zero` is not a finite number"), "{}", e.message);
        let two = "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n  endloop\n \
                   endfacet\n";
        let e = bad(two);
        assert_eq!((e.line, e.message.contains("has 2 `vertex` lines")), (Some(2), true), "{}", e.message);
        let e = bad("solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n");
        assert_eq!((e.line, e.message.contains("cut short")), (Some(2), true), "{}", e.message);
        let e = bad("solid x\n  color 1 0 0\n");
        assert_eq!(e.line, Some(2));
        assert!(e.message.starts_with("column 3: `color` where `facet` or `endsolid` was expected"), "{}", e.message);
        assert!(bad("").message.contains("empty"));
        assert!(bad("hello").message.contains("too short"));
    }

    #[test]
    fn triangles_with_two_corners_at_one_point_are_left_out_and_the_rest_are_flat() {
        let degenerate = [[0.0; 3], [0.0; 3], [1.0, 0.0, 0.0]];
        let flipped = [[0.0, 0.0, 1.0], [0.0, 1.0, 1.0], [1.0, 0.0, 1.0]];
        let s = posed(triangles(&binary_file(b"x", &[TRI, degenerate, flipped])).unwrap());
        let p = &s.primitives[0];
        assert_eq!((p.positions.len(), p.indices.len()), (6, 6));
        // Each triangle's own normal, from its winding: +Z, then −Z.
        assert_eq!(&p.normals[..], &[Vec3::Z, Vec3::Z, Vec3::Z, -Vec3::Z, -Vec3::Z, -Vec3::Z]);
        assert!(s.materials[0].double_sided);
    }
}
