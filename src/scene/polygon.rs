//! Polygons into triangles, as Blender fills them: a convex polygon as a fan from its first corner (Blender's
//! split of a quad along its first diagonal, tobj's and every reader's fan), a concave one by ear clipping in its
//! own plane, so that it covers what it outlines (a fan of a concave polygon covers its notches and overlaps
//! itself: trimesh's wallhole.obj drew 5 % more area than Blender's import, assimp's concave_polygon.obj 13 times
//! as much). Each triangle keeps the polygon's winding.

use glam::{Vec2, Vec3};

/// What filling polygons reuses from one to the next.
#[derive(Default)]
pub(crate) struct Scratch {
    ear: earcut::Earcut<f32>,
    flat: Vec<Vec2>,
    tris: Vec<u32>,
}

/// Appends the triangles of polygon `poly` (indices into `positions`) to `out`. Fewer than three corners give the
/// triangles without area tobj makes of them (a point `a a a`, a line `a b b`), which draw nothing.
pub(crate) fn triangulate(positions: &[Vec3], poly: &[u32], scratch: &mut Scratch, out: &mut Vec<u32>) {
    match *poly {
        [] => {}
        [a] => out.extend_from_slice(&[a, a, a]),
        [a, b] => out.extend_from_slice(&[a, b, b]),
        [a, b, c] => out.extend_from_slice(&[a, b, c]),
        // Most polygons are quads: split along the first diagonal unless that folds the quad (its two halves
        // facing apart, the test Blender makes), without projecting it.
        [a, b, c, d] if unfolded(positions, [a, b, c, d]) => out.extend_from_slice(&[a, b, c, a, c, d]),
        _ => {
            let Scratch { ear, flat, tris } = scratch;
            projected(positions, poly, flat);
            let area = signed_area(flat);
            if area == 0.0 || convex(flat, area) {
                fan(poly, out);
                return;
            }
            tris.clear();
            ear.earcut(flat.iter().map(|p| [p.x, p.y]), &[] as &[u32], tris);
            if tris.len() != 3 * (poly.len() - 2) {
                // A polygon that crosses itself or folds: what the fan makes of it, as before.
                fan(poly, out);
                return;
            }
            for t in tris.chunks_exact(3) {
                let [i, j, k] = [t[0], t[1], t[2]].map(|i| i as usize);
                let turn = (flat[j] - flat[i]).perp_dot(flat[k] - flat[i]);
                let (j, k) = if (turn > 0.0) == (area > 0.0) { (j, k) } else { (k, j) };
                out.extend_from_slice(&[poly[i], poly[j], poly[k]]);
            }
        }
    }
}

/// Whether quad `q`'s halves along its first diagonal face the same way.
fn unfolded(positions: &[Vec3], q: [u32; 4]) -> bool {
    let [a, b, c, d] = q.map(|i| positions.get(i as usize).copied().unwrap_or(Vec3::ZERO));
    (b - a).cross(c - a).dot((c - a).cross(d - a)) > 0.0
}

/// The fan from the first corner.
fn fan(poly: &[u32], out: &mut Vec<u32>) {
    for k in 1..poly.len() - 1 {
        out.extend_from_slice(&[poly[0], poly[k], poly[k + 1]]);
    }
}

/// The polygon's corners in the plane its normal (Newell's) is most nearly perpendicular to, into `flat`.
fn projected(positions: &[Vec3], poly: &[u32], flat: &mut Vec<Vec2>) {
    let at = |i: u32| positions.get(i as usize).copied().unwrap_or(Vec3::ZERO);
    let mut n = Vec3::ZERO;
    for (k, &i) in poly.iter().enumerate() {
        let (p, q) = (at(i), at(poly[(k + 1) % poly.len()]));
        n += Vec3::new((p.y - q.y) * (p.z + q.z), (p.z - q.z) * (p.x + q.x), (p.x - q.x) * (p.y + q.y));
    }
    let a = n.abs();
    // The dominant axis is dropped; the other two are kept in the order that keeps the winding (swapped when the
    // dropped axis' component is negative).
    let (i, j, positive) = if a.z >= a.x && a.z >= a.y {
        (0, 1, n.z >= 0.0)
    } else if a.x >= a.y {
        (1, 2, n.x >= 0.0)
    } else {
        (2, 0, n.y >= 0.0)
    };
    let (i, j) = if positive { (i, j) } else { (j, i) };
    flat.clear();
    flat.extend(poly.iter().map(|&k| {
        let p = at(k);
        Vec2::new(p[i], p[j])
    }));
}

/// Twice the signed area of the closed outline `p` (positive counter-clockwise).
fn signed_area(p: &[Vec2]) -> f32 {
    (0..p.len()).map(|k| p[k].perp_dot(p[(k + 1) % p.len()])).sum()
}

/// Whether every corner of `p` turns the way its area does (or not at all).
fn convex(p: &[Vec2], area: f32) -> bool {
    let n = p.len();
    (0..n).all(|k| {
        let (a, b, c) = (p[k], p[(k + 1) % n], p[(k + 2) % n]);
        let turn = (b - a).perp_dot(c - b);
        turn == 0.0 || (turn > 0.0) == (area > 0.0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Area of the triangles `t` over `p`.
    fn area(p: &[Vec3], t: &[u32]) -> f32 {
        let at = |i: u32| p[i as usize];
        t.chunks_exact(3).map(|t| (at(t[1]) - at(t[0])).cross(at(t[2]) - at(t[0])).length() / 2.0).sum()
    }

    #[test]
    fn a_convex_polygon_is_a_fan_and_a_concave_one_covers_its_outline_in_its_winding() {
        let mut scratch = Scratch::default();
        let quad = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let mut out = Vec::new();
        triangulate(&quad, &[0, 1, 2, 3], &mut scratch, &mut out);
        assert_eq!(out, [0, 1, 2, 0, 2, 3]);
        // An L (area 3) in the XZ plane, fanned from a corner that does not see its far arm: the fan is wrong.
        let outline = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]];
        let l = outline.map(|[x, z]| Vec3::new(x, 0.0, z));
        let poly = [1, 2, 3, 4, 5, 0];
        let mut fanned = Vec::new();
        fan(&poly, &mut fanned);
        assert!((area(&l, &fanned) - 3.0).abs() > 0.5);
        for order in [poly, [0, 5, 4, 3, 2, 1]] {
            let mut out = Vec::new();
            triangulate(&l, &order, &mut scratch, &mut out);
            assert_eq!(out.len(), 12);
            assert!((area(&l, &out) - 3.0).abs() < 1e-5, "{out:?}");
            // Every triangle faces the way the polygon does (Newell's normal).
            let normal = |t: &[u32]| (l[t[1] as usize] - l[t[0] as usize]).cross(l[t[2] as usize] - l[t[0] as usize]);
            let mut whole = Vec::new();
            fan(&order, &mut whole);
            let n: Vec3 = whole.chunks_exact(3).map(normal).sum();
            assert!(out.chunks_exact(3).all(|t| normal(t).dot(n) > 0.0), "{out:?}");
        }
    }
}
