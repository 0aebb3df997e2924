//! A PLY's faces: polygons filled into triangles as Blender fills them ([`crate::scene::polygon`]), and
//! triangle strips (the `tristrips` element of Stanford's scans) cut into triangles as Blender 4.x cuts them; a
//! face's texture coordinates per corner and texture number, and what a header says of how its faces are textured.

use super::super::header::Element;
use super::super::PlyError;
use super::{points_element, slot, Cursor, PlyData, SLOT_R, SLOT_U};

/// Reads a `face` element's rows into `out`: each polygon of its vertex-index list is filled into triangles
/// (appended to `out.triangles`) as Blender fills them, `out.unfanned` set when some polygon was filled otherwise
/// than by its fan. A `texcoord` list (MeshLab's and OpenMVS's wedge texture coordinates: a u, v pair per corner,
/// v up) gives each triangle's corners their own coordinates (`out.corner_uvs`), and a `texnumber` picks the
/// face's texture among the header's `TextureFile` comments (`out.texnumbers`, per triangle), read when the header
/// names a texture: a texture seam is then where one vertex has two coordinates, which per-vertex
/// coordinates cannot say.
pub(super) fn read(c: &mut Cursor<'_>, el: &Element, out: &mut PlyData) -> Result<(), PlyError> {
    let corners: &[glam::Vec3] = bytemuck::cast_slice(&out.positions);
    let tris = &mut out.triangles;
    tris.reserve(el.count.min(c.remaining()) * 3);
    let textures = out.comments.iter().filter(|c| texture_comment(c).is_some()).count();
    let want = Wanted::of(el, textures > 0);
    let mut uvs = want.texcoord.map(|_| Vec::with_capacity(el.count.min(c.remaining()) * 3));
    let mut numbers = want.texnumber.map(|_| Vec::with_capacity(el.count.min(c.remaining())));
    let mut scratch = Default::default();
    each_list(c, el, corners.len(), false, want, |r| {
        // Fewer than three corners draw nothing.
        if r.corners.len() < 3 {
            return Ok(());
        }
        let start = tris.len();
        crate::scene::polygon::triangulate(corners, r.corners, &mut scratch, tris);
        out.unfanned |= r.corners.len() > 3 && !fanned(r.corners, &tris[start..]);
        if let Some(uvs) = &mut uvs {
            if r.texcoord.len() != 2 * r.corners.len() {
                let msg = format!(
                    "its `texcoord` list has {} values for {} corners (a u, v pair per corner): re-export the mesh \
                     with its texture coordinates, or remove the property from the header to read it untextured",
                    r.texcoord.len(),
                    r.corners.len()
                );
                return Err(PlyError::Body { element: el.name.clone(), row: r.row, msg });
            }
            if let Some(v) = r.texcoord.iter().find(|v| !v.is_finite()) {
                let msg = format!("its `texcoord` list holds {v}, not a finite number");
                return Err(PlyError::Body { element: el.name.clone(), row: r.row, msg });
            }
            // Each triangle corner's own pair: the polygon corner it came from (a corner listed twice in one
            // polygon draws nothing between its two places, so either pair will do).
            for &v in &tris[start..] {
                let k = r.corners.iter().position(|&w| w == v).unwrap_or(0);
                uvs.push([r.texcoord[2 * k], r.texcoord[2 * k + 1]]);
            }
        }
        if let Some(numbers) = &mut numbers {
            let n = r.texnumber.unwrap_or(0.0);
            if !(n >= 0.0 && n.fract() == 0.0 && (n as usize) < textures) {
                let msg = format!(
                    "`texnumber` {n} names no texture: the header names {textures} (`comment TextureFile`, counted \
                     from 0)"
                );
                return Err(PlyError::Body { element: el.name.clone(), row: r.row, msg });
            }
            numbers.extend(std::iter::repeat_n(n as u32, (tris.len() - start) / 3));
        }
        Ok(())
    })?;
    out.corner_uvs = uvs;
    out.texnumbers = numbers;
    Ok(())
}

/// The texture name a header comment gives (`TextureFile NAME`, MeshLab's and OpenMVS's), if it is one.
pub(crate) fn texture_comment(comment: &str) -> Option<&str> {
    comment.trim().strip_prefix("TextureFile").map(str::trim)
}

/// How a PLY's header says its surface is textured ([`texturing`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Texturing {
    /// It names a texture (`comment TextureFile`) and has texture coordinates to read it by: per vertex
    /// (`texture_u`/`texture_v`, `s`/`t`, `u`/`v`) or per face corner (a face `texcoord` list).
    pub textured: bool,
    /// Its coordinates are per face corner.
    pub wedge: bool,
    /// Its vertices have colours too (which a texture takes the place of).
    pub colours: bool,
}

/// How the PLY with `header` is textured, from its header alone.
pub(crate) fn texturing(header: &super::super::Header) -> Texturing {
    let points = points_element(header);
    let vertex = header.elements.iter().find(|e| e.name == points);
    let has = |s: usize| vertex.is_some_and(|el| el.props.iter().any(|p| p.list.is_none() && slot(&p.name) == s));
    let wedge = header
        .elements
        .iter()
        .any(|e| e.name == "face" && e.count > 0 && e.props.iter().any(|p| p.name == "texcoord" && p.list.is_some()));
    let named = header.comments.iter().any(|c| texture_comment(c).is_some());
    let per_vertex = has(SLOT_U) && has(SLOT_U + 1);
    Texturing {
        textured: named && (wedge || per_vertex),
        wedge: named && wedge,
        colours: (SLOT_R..SLOT_R + 3).all(has),
    }
}

/// Reads a `tristrips` element's rows (Stanford's scans hold one, a strip of the whole mesh) into triangles
/// appended to `tris`, as Blender 4.x's importer cuts them: an index of −1 ends a strip and starts the next, every
/// other triangle of a strip is turned (its first two corners swapped) so that all face the same way, and a
/// triangle with a repeated corner (strips join that way) is left out. Before, such files read as their vertices
/// alone: a point cloud.
pub(super) fn read_strips(
    c: &mut Cursor<'_>,
    el: &Element,
    positions: &[[f32; 3]],
    tris: &mut Vec<u32>,
) -> Result<(), PlyError> {
    each_list(c, el, positions.len(), true, Wanted::default(), |r| {
        for (k, w) in r.corners.split(|&i| i == RESTART).flat_map(|s| s.windows(3).enumerate()) {
            let [a, b, c] = [w[0], w[1], w[2]];
            if a != b && b != c && a != c {
                tris.extend_from_slice(&if k % 2 == 1 { [b, a, c] } else { [a, b, c] });
            }
        }
        Ok(())
    })
}

/// A strip's restart index (−1) as [`each_list`] gives it.
const RESTART: u32 = u32::MAX;

/// Which of a face element's properties besides its vertex-index list are read: the positions among its
/// properties of a `texcoord` list and a `texnumber` scalar.
#[derive(Debug, Clone, Copy, Default)]
struct Wanted {
    texcoord: Option<usize>,
    texnumber: Option<usize>,
}

impl Wanted {
    /// A `face` element's wedge texture coordinates and texture numbers, when the file names a texture (`textured`):
    /// without one they colour nothing, and are skipped as before.
    fn of(el: &Element, textured: bool) -> Wanted {
        let find = |name: &str, list: bool| el.props.iter().position(|p| p.name == name && p.list.is_some() == list);
        match textured {
            true => Wanted { texcoord: find("texcoord", true), texnumber: find("texnumber", false) },
            false => Wanted::default(),
        }
    }
}

/// One row of a face-like element as [`each_list`] gives it: its vertex indices and what [`Wanted`] asks.
struct Row<'r> {
    row: usize,
    corners: &'r [u32],
    /// The `texcoord` list's values (empty unless asked).
    texcoord: &'r [f32],
    texnumber: Option<f64>,
}

/// Calls `f` with each of `el`'s rows: its vertex-index list (`vertex_indices`, or `vertex_index` as some writers
/// name it) and the properties `want` asks, others skipped; an index out of `0..n_vertices` is an error naming the
/// row, but for −1 when `restarts` (given as [`RESTART`]). An element with rows but no such list is refused: its
/// rows would be dropped without a word.
fn each_list(
    c: &mut Cursor<'_>,
    el: &Element,
    n_vertices: usize,
    restarts: bool,
    want: Wanted,
    mut f: impl FnMut(Row<'_>) -> Result<(), PlyError>,
) -> Result<(), PlyError> {
    c.check_count(el)?;
    let list_idx =
        el.props.iter().position(|p| p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index"));
    if list_idx.is_none() && el.count > 0 {
        let msg = format!("element `{}` has no `vertex_indices` list: which vertices it joins is unknown", el.name);
        return Err(PlyError::Unusable(msg));
    }
    let (mut list, mut texcoord): (Vec<u32>, Vec<f32>) = Default::default();
    for row in 0..el.count {
        let mut texnumber = None;
        for (i, p) in el.props.iter().enumerate() {
            match p.list {
                None => {
                    let v = c.value(p.ty, el, row)?;
                    if Some(i) == want.texnumber {
                        texnumber = Some(v);
                    }
                }
                Some(ct) => {
                    let len = c.list_len(ct, el, row)?;
                    if len > c.remaining() {
                        return Err(PlyError::Truncated(format!("{} row {row} lists {len} values", el.name)));
                    }
                    if Some(i) == want.texcoord {
                        texcoord.clear();
                        for _ in 0..len {
                            texcoord.push(c.value(p.ty, el, row)? as f32);
                        }
                        continue;
                    }
                    if Some(i) != list_idx {
                        for _ in 0..len {
                            c.value(p.ty, el, row)?;
                        }
                        continue;
                    }
                    list.clear();
                    for _ in 0..len {
                        let v = c.value(p.ty, el, row)?;
                        list.push(match v {
                            v if v >= 0.0 && (v as usize) < n_vertices => v as u32,
                            v if restarts && v == -1.0 => RESTART,
                            v => {
                                return Err(PlyError::Body {
                                    element: el.name.clone(),
                                    row,
                                    msg: format!("vertex index {v} is out of range (0..{n_vertices})"),
                                })
                            }
                        });
                    }
                }
            }
        }
        c.end_row();
        f(Row { row, corners: &list, texcoord: &texcoord, texnumber })?;
    }
    Ok(())
}

/// Whether `tris` are polygon `poly`'s fan from its first corner.
fn fanned(poly: &[u32], tris: &[u32]) -> bool {
    let fan = |(t, k): (&[u32], usize)| t == [poly[0], poly[k], poly[k + 1]];
    tris.len() == 3 * (poly.len() - 2) && tris.chunks_exact(3).zip(1..).all(fan)
}

#[cfg(test)]
mod tests {
    use super::super::{read, PlyError};

    /// An ASCII PLY of `n` vertices (a zigzag along x) with a `tristrips` element of the rows `strips`, each
    /// property list `props` (the header's lines after `element tristrips`).
    fn strips(n: usize, props: &str, strips: &[&str]) -> Vec<u8> {
        let mut s = format!(
            "ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n\
             element tristrips {}\n{props}end_header\n",
            strips.len()
        );
        for i in 0..n {
            s.push_str(&format!("{} {} 0\n", i / 2, i % 2));
        }
        for row in strips {
            s.push_str(row);
            s.push('\n');
        }
        s.into_bytes()
    }

    const LIST: &str = "property list int int vertex_indices\n";

    #[test]
    fn strips_are_cut_into_triangles_as_blender_cuts_them() {
        // Two strips parted by a restart: every other triangle turned, counted from each strip's start, and one
        // with a repeated corner (2 2 3) left out but counted. Blender 4.5's importer gives this very list.
        let d = read(&strips(7, LIST, &["11 0 1 2 3 -1 2 2 3 4 5 6"])).unwrap();
        assert_eq!(d.triangles, [0, 1, 2, 2, 1, 3, 3, 2, 4, 3, 4, 5, 5, 4, 6]);
        // The turns keep a strip's triangles facing one way (the zigzag's first strip: −z, all four).
        let d = read(&strips(6, LIST, &["6 0 1 2 3 4 5"])).unwrap();
        let p = |i: u32| glam::Vec3::from(d.positions[i as usize]);
        let facing = |t: &[u32]| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).z;
        assert!(d.triangles.chunks_exact(3).all(|t| facing(t) < 0.0), "{:?}", d.triangles);
        // Several rows, other properties beside the list, a binary body: the same.
        let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n\
                        property float y\nproperty float z\nelement tristrips 2\nproperty uchar flag\n\
                        property list uchar int vertex_indices\nend_header\n"
            .to_vec();
        for i in 0..4 {
            for c in [(i / 2) as f32, (i % 2) as f32, 0.0] {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        for row in [&[0i32, 1, 2][..], &[1, 2, 3]] {
            bin.extend_from_slice(&[7, row.len() as u8]);
            row.iter().for_each(|i| bin.extend_from_slice(&i.to_le_bytes()));
        }
        assert_eq!(read(&bin).unwrap().triangles, [0, 1, 2, 1, 2, 3]);
    }

    #[test]
    fn a_polygons_corner_coordinates_follow_its_corners_into_its_triangles() {
        // A concave pentagon (ear-clipped, not fanned) and a triangle, each corner's pair its vertex's x, y (in
        // another order than the vertices: the list is per corner), a `texnumber` each; and a file naming no
        // texture, whose lists are skipped.
        let ply = |comment: &str| {
            format!(
                "ply\nformat ascii 1.0\n{comment}element vertex 6\nproperty float x\nproperty float y\n\
                 property float z\nelement face 2\nproperty list uchar int vertex_indices\n\
                 property list uchar float texcoord\nproperty uchar texnumber\nend_header\n\
                 0 0 0\n2 0 0\n2 2 0\n1 0.5 0\n0 2 0\n3 3 0\n\
                 5 0 1 2 3 4 10 0 0 2 0 2 2 1 0.5 0 2 1\n3 5 2 1 6 3 3 2 2 2 0 0\n"
            )
        };
        let d = read(ply("comment TextureFile a.png\ncomment TextureFile b.png\n").as_bytes()).unwrap();
        assert!(d.unfanned, "the pentagon is concave");
        let uvs = d.corner_uvs.expect("corner coordinates");
        assert_eq!(uvs.len(), d.triangles.len());
        for (&v, uv) in d.triangles.iter().zip(&uvs) {
            assert_eq!(*uv, [d.positions[v as usize][0], d.positions[v as usize][1]], "vertex {v}");
        }
        assert_eq!(d.texnumbers.expect("texture numbers"), [1, 1, 1, 0]);
        let d = read(ply("").as_bytes()).unwrap();
        assert_eq!((d.corner_uvs, d.texnumbers, d.triangles.len()), (None, None, 12));
    }

    #[test]
    fn a_strip_out_of_range_or_without_its_list_is_refused_with_its_row() {
        let e = read(&strips(4, LIST, &["4 0 1 2 3", "3 0 -2 1"])).unwrap_err();
        assert!(matches!(&e, PlyError::Body { row: 1, .. }) && e.to_string().contains("-2"), "{e}");
        let e = read(&strips(4, LIST, &["3 0 1 4"])).unwrap_err();
        assert!(e.to_string().contains("vertex index 4 is out of range (0..4)"), "{e}");
        let e = read(&strips(4, "property list int int corners\n", &["3 0 1 2"])).unwrap_err();
        assert!(e.to_string().contains("`tristrips` has no `vertex_indices` list"), "{e}");
        // A face's −1 is no restart: out of range, as before.
        let face = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                     property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
                     0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n";
        assert!(read(face).unwrap_err().to_string().contains("vertex index -1 is out of range"));
    }
}
