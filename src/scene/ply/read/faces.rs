//! A PLY's faces: polygons filled into triangles as Blender fills them ([`crate::scene::polygon`]), and
//! triangle strips (the `tristrips` element of Stanford's scans) cut into triangles as Blender 4.x cuts them.

use super::super::header::Element;
use super::super::PlyError;
use super::Cursor;

/// Reads a `face` element's rows: each polygon of its vertex-index list is filled into triangles (appended to
/// `tris`) as Blender fills it; returns whether some polygon was filled otherwise than by its fan.
pub(super) fn read(
    c: &mut Cursor<'_>,
    el: &Element,
    positions: &[[f32; 3]],
    tris: &mut Vec<u32>,
) -> Result<bool, PlyError> {
    let corners: &[glam::Vec3] = bytemuck::cast_slice(positions);
    tris.reserve(el.count.min(c.remaining()) * 3);
    let (mut scratch, mut unfanned) = (Default::default(), false);
    each_list(c, el, positions.len(), false, |poly| {
        // Fewer than three corners draw nothing.
        if poly.len() >= 3 {
            let start = tris.len();
            crate::scene::polygon::triangulate(corners, poly, &mut scratch, tris);
            unfanned |= poly.len() > 3 && !fanned(poly, &tris[start..]);
        }
    })?;
    Ok(unfanned)
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
    each_list(c, el, positions.len(), true, |strip| {
        for (k, w) in strip.split(|&i| i == RESTART).flat_map(|s| s.windows(3).enumerate()) {
            let [a, b, c] = [w[0], w[1], w[2]];
            if a != b && b != c && a != c {
                tris.extend_from_slice(&if k % 2 == 1 { [b, a, c] } else { [a, b, c] });
            }
        }
    })
}

/// A strip's restart index (−1) as [`each_list`] gives it.
const RESTART: u32 = u32::MAX;

/// Calls `f` with the vertex-index list (`vertex_indices`, or `vertex_index` as some writers name it) of each of
/// `el`'s rows, other properties skipped; an index out of `0..n_vertices` is an error naming the row, but for −1
/// when `restarts` (given as [`RESTART`]). An element with rows but no such list is refused: its rows would be
/// dropped without a word.
fn each_list(
    c: &mut Cursor<'_>,
    el: &Element,
    n_vertices: usize,
    restarts: bool,
    mut f: impl FnMut(&[u32]),
) -> Result<(), PlyError> {
    c.check_count(el)?;
    let list_idx =
        el.props.iter().position(|p| p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index"));
    if list_idx.is_none() && el.count > 0 {
        let msg = format!("element `{}` has no `vertex_indices` list: which vertices it joins is unknown", el.name);
        return Err(PlyError::Unusable(msg));
    }
    let mut list: Vec<u32> = Vec::new();
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
                        return Err(PlyError::Truncated(format!("{} row {row} lists {len} vertices", el.name)));
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
                    f(&list);
                }
            }
        }
        c.end_row();
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
