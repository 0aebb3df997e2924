//! A PLY's faces: polygons filled into triangles as Blender fills them ([`crate::scene::polygon`]).

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
    c.check_count(el)?;
    let n_vertices = positions.len();
    let corners: &[glam::Vec3] = bytemuck::cast_slice(positions);
    let list_idx =
        el.props.iter().position(|p| p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index"));
    tris.reserve(el.count.min(c.remaining()) * 3);
    let (mut poly, mut scratch, mut unfanned): (Vec<u32>, _, _) = (Vec::new(), Default::default(), false);
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
                    // Fewer than three corners draw nothing.
                    if poly.len() >= 3 {
                        let start = tris.len();
                        crate::scene::polygon::triangulate(corners, &poly, &mut scratch, tris);
                        unfanned |= poly.len() > 3 && !fanned(&poly, &tris[start..]);
                    }
                }
            }
        }
        c.end_row();
    }
    Ok(unfanned)
}

/// Whether `tris` are polygon `poly`'s fan from its first corner.
fn fanned(poly: &[u32], tris: &[u32]) -> bool {
    let fan = |(t, k): (&[u32], usize)| t == [poly[0], poly[k], poly[k + 1]];
    tris.len() == 3 * (poly.len() - 2) && tris.chunks_exact(3).zip(1..).all(fan)
}
