//! Triangle setup: every triangle of a view clipped against the near plane (and a guard band), projected,
//! snapped, oriented and bounded, in scene order, and binned by tile.

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::walk::edge;
use super::{snap, Chunk, ClipVert, Projection, Tiles, Tri, Tris, SETUP_CHUNK, SUBPIXEL};
use crate::render::light::Visibility;
use crate::scene::{PosedScene, PrimKind};

/// Clips, projects and orients every triangle of the scene, in scene order (chunks run in parallel and keep
/// their order, so the order does not depend on threads), and bins them by tile.
/// `visibility` is what reaches each vertex of each primitive of the environment's light (lit shading), or
/// `None`.
pub fn setup(scene: &PosedScene, p: &Projection, tiles: Tiles, visibility: Option<&[Vec<Visibility>]>) -> Tris {
    let mut out = Tris::default();
    for (pi, prim) in scene.primitives.iter().enumerate().filter(|(_, q)| q.kind == PrimKind::Triangles) {
        let vis: &[Visibility] = visibility.and_then(|v| v.get(pi)).map_or(&[], |v| v.as_slice());
        let double_sided = scene.materials.get(prim.material as usize).is_some_and(|m| m.double_sided);
        let count = prim.positions.len();
        // Vertices are shared by about six triangles of a mesh: project each once. Triangles whose vertices are
        // all inside the clip planes use these; clipped ones project their new vertices the same way.
        let planes = clip_planes(p);
        let view: Vec<(Vec3, Screen, bool)> = prim
            .positions
            .par_iter()
            .map(|v| {
                let v = p.w2c.transform_point3(*v);
                (v, Screen::of(v, p), planes.iter().all(|&q| side(q, v) >= 0.0))
            })
            .collect();
        let chunks: Vec<Chunk> = prim
            .indices
            .par_chunks(3 * SETUP_CHUNK)
            .map(|chunk| {
                let mut tris = Vec::with_capacity(chunk.len() / 3);
                for t in chunk.chunks_exact(3) {
                    let vert = |i: u32| {
                        let i = i as usize;
                        ClipVert {
                            view: view[i].0,
                            uv: prim.uvs.get(i).copied().unwrap_or(Vec2::ZERO),
                            normal: prim.normals[i],
                            color: prim.colors.get(i).copied().unwrap_or(Vec4::ONE),
                            vis: vis.get(i).copied().unwrap_or(Visibility::OPEN),
                            // A two-sided primitive's back sides follow its front sides.
                            vis_back: vis.get(count + i).or(vis.get(i)).copied().unwrap_or(Visibility::OPEN),
                            tangent: prim.tangents.get(i).copied().unwrap_or(Vec4::ZERO),
                        }
                    };
                    let v = [vert(t[0]), vert(t[1]), vert(t[2])];
                    if t.iter().all(|&i| view[i as usize].2) {
                        let screen = [0, 1, 2].map(|k| view[t[k] as usize].1);
                        tris.extend(assemble(v, screen, p, double_sided, prim.material, prim.object));
                        continue;
                    }
                    let (poly, n) = clip(v, &planes);
                    for k in 1..n.saturating_sub(1) {
                        let fan = [poly[0], poly[k], poly[k + 1]];
                        let screen = fan.map(|c| Screen::of(c.view, p));
                        tris.extend(assemble(fan, screen, p, double_sided, prim.material, prim.object));
                    }
                }
                Chunk::new(tris, tiles)
            })
            .collect();
        out.chunks.extend(chunks);
    }
    out
}

/// How far beyond the image (in samples) a triangle may reach before it is clipped: coordinates stay within
/// ±2²¹ samples (2²⁹ in fixed point), so edge functions, products of two coordinate differences, stay below 2⁶¹.
const GUARD: f32 = (1 << 20) as f32;

/// The planes a triangle is clipped against, as (a, b, c, e) with inside meaning a·x + b·y + c·(−z) + e ≥ 0 in
/// view space: the near plane first (so that the others only see vertices in front of the eye), then the four
/// sides of the image widened by [`GUARD`] samples. The sides cut only triangles reaching millions of samples
/// off-screen (a ground plane running under the camera), whose visible part they keep.
fn clip_planes(p: &Projection) -> [Vec4; 5] {
    let [fx, fy, cx, cy] = p.f;
    let (w, h) = (p.size.0 as f32, p.size.1 as f32);
    [
        Vec4::new(0.0, 0.0, 1.0, -p.near),
        Vec4::new(fx, 0.0, cx + GUARD, 0.0),      // sx ≥ −GUARD
        Vec4::new(-fx, 0.0, w + GUARD - cx, 0.0), // sx ≤ w + GUARD
        Vec4::new(0.0, -fy, cy + GUARD, 0.0),     // sy ≥ −GUARD
        Vec4::new(0.0, fy, h + GUARD - cy, 0.0),  // sy ≤ h + GUARD
    ]
}

/// The signed distance-like value of view-space `v` to `plane` (≥ 0 inside).
#[inline]
fn side(plane: Vec4, v: Vec3) -> f32 {
    plane.x * v.x + plane.y * v.y + plane.z * -v.z + plane.w
}

/// Sutherland–Hodgman against [`clip_planes`]: the visible part of a triangle, as its first `n` vertices (0 or
/// 3 to 8; no allocation: this runs for every triangle that needs it).
fn clip(tri: [ClipVert; 3], planes: &[Vec4; 5]) -> ([ClipVert; 8], usize) {
    let mut poly = [tri[0]; 8];
    poly[..3].copy_from_slice(&tri);
    let mut n = 3;
    for &plane in planes {
        if poly[..n].iter().all(|v| side(plane, v.view) >= 0.0) {
            continue;
        }
        let mut out = [tri[0]; 8];
        let mut m = 0;
        for i in 0..n {
            let (a, b) = (&poly[i], &poly[(i + 1) % n]);
            let (da, db) = (side(plane, a.view), side(plane, b.view));
            if da >= 0.0 {
                out[m] = *a;
                m += 1;
            }
            if (da >= 0.0) != (db >= 0.0) {
                out[m] = a.lerp(b, da / (da - db));
                m += 1;
            }
        }
        (poly, n) = (out, m);
        if n < 3 {
            return (poly, 0);
        }
    }
    (poly, n)
}

/// A vertex in front of the near plane, projected: snapped sample position and 1 / view depth.
#[derive(Debug, Clone, Copy)]
struct Screen {
    x: i64,
    y: i64,
    inv_z: f32,
}

impl Screen {
    /// The projection of view-space `v` (meaningful when in front of the near plane).
    #[inline]
    fn of(v: Vec3, p: &Projection) -> Screen {
        let [fx, fy, cx, cy] = p.f;
        let z = -v.z;
        let sx = cx + fx * v.x / z;
        let sy = cy - fy * v.y / z;
        // Far beyond the image, snapping would overflow: such triangles are clipped by the bbox anyway, but keep
        // the arithmetic in range.
        let lim = (1u64 << 32) as f64;
        Screen { x: snap((sx as f64).clamp(-lim, lim)), y: snap((sy as f64).clamp(-lim, lim)), inv_z: 1.0 / z }
    }
}

/// The triangle of the view-space vertices `v` (in front of the near plane) projected to `screen`, oriented and
/// bounded; `None` when beyond the far plane, degenerate, culled or outside the image.
fn assemble(
    v: [ClipVert; 3],
    screen: [Screen; 3],
    p: &Projection,
    double_sided: bool,
    material: u32,
    object: u32,
) -> Option<Tri> {
    let x = screen.map(|s| s.x);
    let y = screen.map(|s| s.y);
    let inv_z = screen.map(|s| s.inv_z);
    if v.iter().all(|c| -c.view.z > p.far) {
        return None;
    }
    let area = edge(x[0], y[0], x[1], y[1], x[2], y[2]);
    if area == 0 {
        return None;
    }
    // Counter-clockwise in the view (front) is clockwise in y-down screen space: negative area.
    let back = area > 0;
    if back && !double_sided {
        return None;
    }
    let mut idx = [0usize, 1, 2];
    if !back {
        idx = [0, 2, 1]; // make the screen area positive
    }
    let pick = |a: [i64; 3]| [a[idx[0]], a[idx[1]], a[idx[2]]];
    let (x, y) = (pick(x), pick(y));
    // The samples whose centres (s·S + S/2) lie within the vertices' extent, inclusive: nothing outside can be
    // inside the triangle, and a triangle between sample centres is dropped here.
    let first = |a: i64| -(SUBPIXEL / 2 - a).div_euclid(SUBPIXEL);
    let last = |b: i64| (b - SUBPIXEL / 2).div_euclid(SUBPIXEL);
    let (min, max) = (|a: [i64; 3]| a[0].min(a[1]).min(a[2]), |a: [i64; 3]| a[0].max(a[1]).max(a[2]));
    let bbox =
        [first(min(x)).max(0), first(min(y)).max(0), last(max(x)).min(p.size.0 - 1), last(max(y)).min(p.size.1 - 1)];
    if bbox[0] > bbox[2] || bbox[1] > bbox[3] {
        return None;
    }
    let inv_z = [inv_z[idx[0]], inv_z[idx[1]], inv_z[idx[2]]];
    let uv = [v[idx[0]].uv, v[idx[1]].uv, v[idx[2]].uv];
    // Weight i is edge (a, b) / area, and edge(a, b, p) changes by −(y_b − y_a) per unit of p.x and by
    // (x_b − x_a) per unit of p.y; one sample step is SUBPIXEL units.
    let (mut duv_step, mut ds_step) = ([Vec2::ZERO; 2], [0.0f32; 2]);
    let step = SUBPIXEL as f32 / area.abs() as f32;
    for (i, (a, b)) in [(1, 2), (2, 0), (0, 1)].into_iter().enumerate() {
        let db = [-(y[b] - y[a]) as f32 * step, (x[b] - x[a]) as f32 * step];
        for axis in 0..2 {
            duv_step[axis] += uv[i] * (db[axis] * inv_z[i]);
            ds_step[axis] += db[axis] * inv_z[i];
        }
    }
    Some(Tri {
        x,
        y,
        area: area.abs(),
        inv_z,
        uv,
        duv_step,
        ds_step,
        normal: [v[idx[0]].normal, v[idx[1]].normal, v[idx[2]].normal],
        color: [v[idx[0]].color, v[idx[1]].color, v[idx[2]].color],
        // The camera sees the side it sees: an inside-out mesh shows its back sides, lit as they are.
        vis: idx.map(|i| if back { v[i].vis_back } else { v[i].vis }),
        tangent: [v[idx[0]].tangent, v[idx[1]].tangent, v[idx[2]].tangent],
        bbox,
        material,
        object,
        back,
    })
}
