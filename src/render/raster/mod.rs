//! Triangle rasterization: near-plane clipping in view space, snapping to a 1/256-sample fixed-point grid,
//! exact integer edge functions with a tie rule that gives every sample on a shared edge to exactly one of the
//! two triangles (no cracks, no double hits), perspective-correct attributes, and a strict depth test in
//! triangle order. Tiles are independent, so the image is the same whatever the thread count.

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use rayon::prelude::*;

mod lit;

use super::bin::Binned;
use super::splat::{Layer, Splats};
use crate::scene::material::AlphaMode;
use crate::scene::{PosedScene, PrimKind};

/// Sub-sample precision of the fixed-point grid (8 bits).
pub const SUBPIXEL: i64 = 256;

/// The fixed-point value (1/[`SUBPIXEL`] sample) nearest `v` samples, ties to even, for |v · SUBPIXEL| < 2⁵⁰.
/// Adding 1.5·2⁵² leaves that integer in the low bits of the f64's mantissa: exact, the same on every machine,
/// and without the libm call `f64::round` is on baseline x86-64 (six per triangle, three per splat).
#[inline]
pub fn snap(v: f64) -> i64 {
    const MAGIC: f64 = 6755399441055744.0;
    ((v * SUBPIXEL as f64 + MAGIC).to_bits() & ((1 << 52) - 1)) as i64 - (1 << 51)
}

/// A vertex in view space with its attributes, for clipping.
#[derive(Debug, Clone, Copy)]
struct ClipVert {
    view: Vec3,
    uv: Vec2,
    normal: Vec3,
    color: Vec4,
    /// The environment's visibility (lit shading; 1 otherwise).
    vis: f32,
    /// Tangent and handedness for a normal texture (zero without one).
    tangent: Vec4,
}

impl ClipVert {
    fn lerp(&self, o: &ClipVert, t: f32) -> ClipVert {
        ClipVert {
            view: self.view.lerp(o.view, t),
            uv: self.uv.lerp(o.uv, t),
            normal: self.normal.lerp(o.normal, t),
            color: self.color.lerp(o.color, t),
            vis: self.vis + (o.vis - self.vis) * t,
            tangent: self.tangent.lerp(o.tangent, t),
        }
    }
}

/// A triangle ready to rasterize, in sample space (supersampled pixels, y down), oriented counter-clockwise
/// on screen so that inside means all three edge functions are ≥ 0.
#[derive(Debug, Clone)]
pub struct Tri {
    x: [i64; 3],
    y: [i64; 3],
    area: i64,
    inv_z: [f32; 3],
    uv: [Vec2; 3],
    normal: [Vec3; 3],
    color: [Vec4; 3],
    vis: [f32; 3],
    tangent: [Vec4; 3],
    /// Per sample step along x and y: the change of Σ bᵢ·uvᵢ/zᵢ and of Σ bᵢ/zᵢ (constants of the triangle), from
    /// which the perspective-correct uv derivative at any sample follows for the mip level.
    duv_step: [Vec2; 2],
    ds_step: [f32; 2],
    /// Inclusive sample bounding box.
    pub bbox: [i64; 4],
    /// Material index.
    pub material: u32,
    /// Object id.
    pub object: u32,
    /// The camera sees the back face (normals are flipped toward it).
    back: bool,
}

/// Projection constants in sample space.
#[derive(Debug, Clone, Copy)]
pub struct Projection {
    /// View matrix.
    pub w2c: Mat4,
    /// fx·k, fy·k, cx·k, cy·k.
    pub f: [f32; 4],
    /// Near and far planes.
    pub near: f32,
    /// Far plane.
    pub far: f32,
    /// Sample grid size.
    pub size: (i64, i64),
}

/// Triangles per setup task: large enough to amortize the task, small enough to balance two cores.
const SETUP_CHUNK: usize = 4096;

/// Bits of a [`Tris`] id that index within a chunk: a chunk of [`SETUP_CHUNK`] triangles yields at most twice
/// as many (a near-clipped triangle becomes two).
const CHUNK_BITS: u32 = 13;

/// The set-up triangles of a view, as the setup tasks made them (chunks in scene order): not concatenated, since
/// copying a 100k-triangle view's 25 MB costs more than the indirection. Each chunk also bins its triangles by
/// tile, in the same parallel task (a stable counting sort), so a tile walks the chunks' lists in scene order.
#[derive(Debug, Default)]
pub struct Tris {
    chunks: Vec<Chunk>,
}

/// One setup task's triangles and their tile bins (indices into `tris`).
#[derive(Debug, Default)]
struct Chunk {
    tris: Vec<Tri>,
    bins: Binned<u32>,
}

/// The tiles of a frame: side in samples, tiles across and down.
#[derive(Debug, Clone, Copy)]
pub struct Tiles {
    /// Tile side in samples.
    pub side: i64,
    /// Tiles across.
    pub across: i64,
    /// Tiles down.
    pub down: i64,
}

impl Chunk {
    fn new(tris: Vec<Tri>, g: Tiles) -> Chunk {
        let rect = |t: &Tri| t.bbox.map(|v| (v / g.side) as usize);
        let bins = Binned::sort(&tris, g.across as usize, (g.across * g.down) as usize, rect, |i, _| i as u32);
        Chunk { tris, bins }
    }
}

impl Tris {
    /// The ids of tile `t`'s triangles, in scene order.
    pub fn tile(&self, t: usize) -> impl Iterator<Item = u32> + '_ {
        self.chunks
            .iter()
            .enumerate()
            .flat_map(move |(c, ch)| ch.bins.cell(t).iter().map(move |&i| ((c as u32) << CHUNK_BITS) | i))
    }

    /// Whether no triangle reaches tile `t`.
    pub fn tile_is_empty(&self, t: usize) -> bool {
        self.chunks.iter().all(|ch| ch.bins.cell(t).is_empty())
    }

    /// The triangle with id `id`.
    #[inline]
    pub fn get(&self, id: u32) -> &Tri {
        &self.chunks[(id >> CHUNK_BITS) as usize].tris[(id & ((1 << CHUNK_BITS) - 1)) as usize]
    }
}

/// Clips, projects and orients every triangle of the scene, in scene order (chunks run in parallel and keep
/// their order, so the order does not depend on threads), and bins them by tile.
/// `visibility` is the environment's visibility per primitive and vertex (lit shading), or `None`.
pub fn setup(scene: &PosedScene, p: &Projection, tiles: Tiles, visibility: Option<&[Vec<f32>]>) -> Tris {
    let mut out = Tris::default();
    for (pi, prim) in scene.primitives.iter().enumerate().filter(|(_, q)| q.kind == PrimKind::Triangles) {
        let vis: &[f32] = visibility.and_then(|v| v.get(pi)).map_or(&[], |v| v.as_slice());
        let double_sided = scene.materials.get(prim.material as usize).is_some_and(|m| m.double_sided);
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
                            vis: vis.get(i).copied().unwrap_or(1.0),
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
    let bbox = [
        first(*x.iter().min().unwrap()).max(0),
        first(*y.iter().min().unwrap()).max(0),
        last(*x.iter().max().unwrap()).min(p.size.0 - 1),
        last(*y.iter().max().unwrap()).min(p.size.1 - 1),
    ];
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
        vis: [v[idx[0]].vis, v[idx[1]].vis, v[idx[2]].vis],
        tangent: [v[idx[0]].tangent, v[idx[1]].tangent, v[idx[2]].tangent],
        bbox,
        material,
        object,
        back,
    })
}

/// Twice the signed area of (a, b, p), y down.
#[inline]
fn edge(ax: i64, ay: i64, bx: i64, by: i64, px: i64, py: i64) -> i64 {
    (bx - ax) * (py - ay) - (by - ay) * (px - ax)
}

/// Whether an edge owns the samples exactly on it. Antisymmetric: of (u→v) and (v→u), exactly one owns.
#[inline]
fn owns(dx: i64, dy: i64) -> bool {
    dy > 0 || (dy == 0 && dx < 0)
}

/// Samples of one tile: linear colour (straight), view depth, world normal, object id + 1 (0 = empty).
#[derive(Debug, Clone)]
pub struct SampleTile {
    /// First sample column.
    pub x0: i64,
    /// First sample row.
    pub y0: i64,
    /// Width in samples.
    pub w: i64,
    /// Height in samples.
    pub h: i64,
    /// Linear RGB and alpha of the surface at each sample.
    pub color: Vec<Vec4>,
    /// View depth (planar), +∞ where empty.
    pub depth: Vec<f32>,
    /// World-space unit normal.
    pub normal: Vec<Vec3>,
    /// Object id + 1, 0 where empty.
    pub object: Vec<u32>,
    /// Lit shading, deferred: the triangle at each sample ([`NO_TRI`] where none, or where a splat won) and its
    /// perspective-correct barycentrics there. Empty unless the render is lit.
    tri: Vec<u32>,
    bary: Vec<[f32; 3]>,
    /// Fragments of alpha BLEND surfaces, composited over the opaque samples once every triangle is drawn.
    blend: Vec<Fragment>,
}

/// A sample of a BLEND surface: where, how far, in what order it was drawn, and what it shows.
#[derive(Debug, Clone, Copy)]
struct Fragment {
    /// Sample index in the tile.
    i: u32,
    /// Triangle id (scene order), for equal depths.
    tri: u32,
    z: f32,
    /// Straight linear RGB and alpha.
    color: Vec4,
    normal: Vec3,
    object: u32,
}

/// No triangle at a sample (deferred lit shading).
const NO_TRI: u32 = u32::MAX;

impl SampleTile {
    /// An empty tile with room for `rect`.
    pub fn new(rect: Rect) -> SampleTile {
        let mut t = SampleTile {
            x0: 0,
            y0: 0,
            w: 0,
            h: 0,
            color: Vec::new(),
            depth: Vec::new(),
            normal: Vec::new(),
            object: Vec::new(),
            tri: Vec::new(),
            bary: Vec::new(),
            blend: Vec::new(),
        };
        t.reset(rect);
        t
    }

    /// Empties the deferred-shading buffers for the current rect (lit renders only).
    fn reset_deferred(&mut self) {
        let n = (self.w * self.h) as usize;
        self.tri.clear();
        self.tri.resize(n, NO_TRI);
        self.bary.clear();
        self.bary.resize(n, [0.0; 3]);
    }

    /// Empties the tile and moves it to `rect` (keeping its allocations).
    pub fn reset(&mut self, rect: Rect) {
        let n = (rect.w * rect.h) as usize;
        (self.x0, self.y0, self.w, self.h) = (rect.x0, rect.y0, rect.w, rect.h);
        self.color.clear();
        self.color.resize(n, Vec4::ZERO);
        self.depth.clear();
        self.depth.resize(n, f32::INFINITY);
        self.normal.clear();
        self.normal.resize(n, Vec3::ZERO);
        self.object.clear();
        self.object.resize(n, 0);
        self.blend.clear();
    }
}

/// What shading needs besides the scene.
#[derive(Debug, Clone)]
pub struct Shade<'a> {
    /// `None` for unlit; else ambient and lights as (direction toward the light, intensity).
    pub lambert: Option<(f32, Vec<(Vec3, f32)>)>,
    /// Lit (`pbr`) shading, when asked.
    pub lit: Option<Lit<'a>>,
    /// Whether anything reads the normals (Lambert, lit shading or the normal pass): if not, they are not
    /// interpolated.
    pub normals: bool,
}

/// What lit shading needs of the view: the frame's lighting and how to go from a sample back to the world.
#[derive(Debug, Clone, Copy)]
pub struct Lit<'a> {
    /// The frame's lights, shadows and environment.
    pub light: &'a crate::render::light::FrameLight,
    /// Camera to world.
    pub c2w: Mat4,
    /// The camera centre.
    pub eye: Vec3,
    /// Samples per pixel side: shading runs once per pixel and triangle.
    pub per_side: i64,
}

/// A rectangle of samples.
#[derive(Debug, Clone, Copy)]
pub struct Rect {
    /// First column.
    pub x0: i64,
    /// First row.
    pub y0: i64,
    /// Width.
    pub w: i64,
    /// Height.
    pub h: i64,
}

/// What one tile draws: indices (in scene order) into the frame's triangles, and its band's splats.
#[derive(Debug, Clone, Copy)]
pub struct TileWork<'a> {
    /// All triangles.
    pub tris: &'a Tris,
    /// This tile's index.
    pub tile: usize,
    /// The frame's splats and the band's layer of them, when it has any.
    pub splats: Option<(&'a Splats<'a>, &'a Layer)>,
}

/// Rasterizes a tile's triangles, then merges its band's splats behind them (a splat shows where it is strictly
/// nearer, as if drawn after the triangles with the same depth test).
/// `t` is reused from tile to tile (a band of tiles shares one): it is reset to `rect`, empty, first.
pub fn raster_tile(
    scene: &PosedScene,
    work: TileWork<'_>,
    shade: &Shade,
    rect: Rect,
    proj: &Projection,
    t: &mut SampleTile,
) {
    let TileWork { tris, tile, splats } = work;
    let Rect { x0, y0, w, h } = rect;
    let (near, far) = (proj.near, proj.far);
    t.reset(rect);
    if shade.lit.is_some() {
        t.reset_deferred();
    }
    for ti in tris.tile(tile) {
        let tri = tris.get(ti);
        let (bx0, by0) = (tri.bbox[0].max(x0), tri.bbox[1].max(y0));
        let (bx1, by1) = (tri.bbox[2].min(x0 + w - 1), tri.bbox[3].min(y0 + h - 1));
        if bx0 > bx1 || by0 > by1 {
            continue;
        }
        let (x, y) = (tri.x, tri.y);
        // Edge i is opposite vertex i: (1→2), (2→0), (0→1). Each is evaluated once at the first sample and then
        // stepped (it is linear in the sample position). A sample exactly on an edge belongs to the triangle only
        // if the edge owns it: `bias` is −1 for the others, so "inside" is `v + bias ≥ 0` for all three.
        let e = [(1, 2), (2, 0), (0, 1)];
        let bias: [i64; 3] = e.map(|(a, b)| if owns(x[b] - x[a], y[b] - y[a]) { 0 } else { -1 });
        let step_x: [i64; 3] = e.map(|(a, b)| -(y[b] - y[a]) * SUBPIXEL);
        let step_y: [i64; 3] = e.map(|(a, b)| (x[b] - x[a]) * SUBPIXEL);
        let (px0, py0) = (bx0 * SUBPIXEL + SUBPIXEL / 2, by0 * SUBPIXEL + SUBPIXEL / 2);
        let mut row: [i64; 3] = e.map(|(a, b)| edge(x[a], y[a], x[b], y[b], px0, py0));
        let inv_area = 1.0 / tri.area as f32;
        let mat = scene.material(tri.material);
        let tex = mat.base_color_texture.and_then(|r| scene.textures.get(r.texture as usize).map(|t| (r, t)));
        let lit = shade.lit.is_some();
        // Only a texture reads the uv here (lit shading interpolates its own, deferred).
        let wants_uv = tex.is_some();
        for sy in by0..=by1 {
            let mut wgt = row;
            for i in 0..3 {
                row[i] += step_y[i];
            }
            for sx in bx0..=bx1 {
                let v = wgt;
                for i in 0..3 {
                    wgt[i] += step_x[i];
                }
                if ((v[0] + bias[0]) | (v[1] + bias[1]) | (v[2] + bias[2])) < 0 {
                    continue;
                }
                let b = v.map(|v| v as f32 * inv_area);
                let pb = [b[0] * tri.inv_z[0], b[1] * tri.inv_z[1], b[2] * tri.inv_z[2]];
                let s = pb[0] + pb[1] + pb[2];
                let z = 1.0 / s;
                let i = ((sy - y0) * w + (sx - x0)) as usize;
                if !(z >= near && z <= far) || z >= t.depth[i] {
                    continue;
                }
                let k = [pb[0] * z, pb[1] * z, pb[2] * z];
                let vc = tri.color[0] * k[0] + tri.color[1] * k[1] + tri.color[2] * k[2];
                let mut albedo = mat.base_color * vc;
                let uv = if wants_uv { tri.uv[0] * k[0] + tri.uv[1] * k[1] + tri.uv[2] * k[2] } else { Vec2::ZERO };
                // d(uv)/dstep = (d(Σ pᵢ·uvᵢ) − uv·d(Σ pᵢ)) / Σ pᵢ, with pᵢ = bᵢ/zᵢ.
                let footprint =
                    || ((tri.duv_step[0] - uv * tri.ds_step[0]) * z, (tri.duv_step[1] - uv * tri.ds_step[1]) * z);
                if let Some((r, texture)) = tex {
                    let (dx, dy) = footprint();
                    albedo *= texture.sample_footprint(&r, uv, dx, dy);
                }
                let blend = mat.alpha_mode == AlphaMode::Blend;
                match mat.alpha_mode {
                    AlphaMode::Mask if albedo.w < mat.alpha_cutoff => continue,
                    AlphaMode::Blend if albedo.w <= 0.0 => continue,
                    _ => {}
                }
                let mut nrm = Vec3::ZERO;
                if shade.normals {
                    nrm = (tri.normal[0] * k[0] + tri.normal[1] * k[1] + tri.normal[2] * k[2]).normalize_or_zero();
                    if tri.back {
                        nrm = -nrm;
                    }
                }
                if blend {
                    // Shaded now (it may show through others), composited in depth order when the tile is drawn.
                    let rgb = match &shade.lit {
                        Some(l) => {
                            let s = lit::Sample { at: (sx, sy), bary: k, z, normal: nrm };
                            lit::shade_sample(scene, tri, l, proj, s, albedo.truncate())
                        }
                        None => shade_unlit(shade, albedo.truncate(), nrm) + mat.emissive,
                    };
                    let color = rgb.extend(albedo.w.min(1.0));
                    t.blend.push(Fragment { i: i as u32, tri: ti, z, color, normal: nrm, object: tri.object });
                    continue;
                }
                if lit {
                    // Deferred: shaded once per pixel and triangle when every triangle is drawn ([`lit`]).
                    t.color[i] = albedo.truncate().extend(1.0);
                    t.depth[i] = z;
                    t.normal[i] = nrm;
                    t.object[i] = tri.object + 1;
                    t.tri[i] = ti;
                    t.bary[i] = k;
                    continue;
                }
                let rgb = shade_unlit(shade, albedo.truncate(), nrm) + mat.emissive;
                t.color[i] = rgb.extend(1.0);
                t.depth[i] = z;
                t.normal[i] = nrm;
                t.object[i] = tri.object + 1;
            }
        }
    }
    if let Some((splats, layer)) = splats {
        for sy in y0..y0 + h {
            let row = ((sy - layer.y0) * layer.w) as usize;
            for sx in x0..x0 + w {
                let (i, j) = (((sy - y0) * w + (sx - x0)) as usize, row + sx as usize);
                if layer.depth[j] < t.depth[i] {
                    // Points carry their own colour: unlit.
                    let (color, normal, object) = splats.attributes(layer, j);
                    t.color[i] = color.truncate().extend(1.0);
                    t.depth[i] = layer.depth[j];
                    t.normal[i] = normal;
                    t.object[i] = object + 1;
                    if let Some(d) = t.tri.get_mut(i) {
                        *d = NO_TRI;
                    }
                }
            }
        }
    }
    if let Some(l) = &shade.lit {
        lit::shade_tile(scene, tris, l, rect, proj, t);
    }
    composite_blend(t);
}

/// Unlit or Lambert colour of albedo `albedo` with normal `nrm`.
#[inline]
fn shade_unlit(shade: &Shade, albedo: Vec3, nrm: Vec3) -> Vec3 {
    match &shade.lambert {
        Some((ambient, lights)) => {
            let sum: f32 = lights.iter().map(|(l, k)| k * nrm.dot(*l).max(0.0)).sum();
            albedo * (ambient + sum)
        }
        None => albedo,
    }
}

/// Composites the tile's BLEND fragments over what is drawn, per sample from the farthest to the nearest (equal
/// depths in scene order), each "over" the result so far, in premultiplied linear light; fragments behind the
/// opaque surface are hidden. A sample that only transparent surfaces cover takes the nearest one's depth,
/// normal and object. The sort makes the result independent of the order tiles or threads produced them.
fn composite_blend(t: &mut SampleTile) {
    if t.blend.is_empty() {
        return;
    }
    let mut blend = std::mem::take(&mut t.blend);
    blend.sort_by(|a, b| a.i.cmp(&b.i).then(b.z.total_cmp(&a.z)).then(a.tri.cmp(&b.tri)));
    for f in &blend {
        let i = f.i as usize;
        if f.z >= t.depth[i] && t.object[i] != 0 && t.color[i].w >= 1.0 {
            continue; // behind the opaque surface
        }
        let (dst, a) = (t.color[i], f.color.w);
        let premult = f.color.truncate() * a + dst.truncate() * dst.w * (1.0 - a);
        let alpha = a + dst.w * (1.0 - a);
        t.color[i] = if alpha > 0.0 { (premult / alpha).extend(alpha) } else { Vec4::ZERO };
        if t.object[i] == 0 || f.z < t.depth[i] && t.color[i].w < 1.0 {
            t.depth[i] = f.z;
            t.normal[i] = f.normal;
            t.object[i] = f.object + 1;
        }
    }
    blend.clear();
    t.blend = blend;
}

/// The camera's backward axis in world space (the head light's direction toward the light).
pub fn camera_back(c2w: &Mat4) -> Vec3 {
    Mat3::from_mat4(*c2w).z_axis.normalize()
}
