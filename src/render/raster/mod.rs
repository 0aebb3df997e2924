//! Triangle rasterization: near-plane clipping in view space, snapping to a 1/256-sample fixed-point grid,
//! exact integer edge functions with a tie rule that gives every sample on a shared edge to exactly one of the
//! two triangles (no cracks, no double hits), perspective-correct attributes, and a strict depth test in
//! triangle order. Tiles are independent, so the image is the same whatever the thread count.

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

mod blend;
mod deferred;
mod lit;
mod setup;
mod walk;

pub use setup::setup;
use walk::Walk;

use super::bin::Binned;
use super::splat::{Layer, Splats};
use crate::render::light::{Lobe, Visibility};
use crate::scene::material::AlphaMode;
use crate::scene::PosedScene;

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
    /// What reaches it of the environment's light (lit shading; 1 otherwise), on its front side and on its back
    /// side (the same unless its primitive gathers on both sides: see [`crate::render::light::two_sided`]).
    vis: Visibility,
    vis_back: Visibility,
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
            vis: self.vis.lerp(o.vis, t),
            vis_back: self.vis_back.lerp(o.vis_back, t),
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
    vis: [Visibility; 3],
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

impl Tri {
    /// The interpolated unit normal at perspective-correct barycentrics `k`, toward the eye (flipped on a back
    /// face).
    #[inline]
    fn normal_at(&self, k: [f32; 3]) -> Vec3 {
        let n = (self.normal[0] * k[0] + self.normal[1] * k[1] + self.normal[2] * k[2]).normalize_or_zero();
        if self.back {
            -n
        } else {
            n
        }
    }

    /// The uv at barycentrics `k` and its derivatives across `scale` sample steps in x and y at view depth
    /// `z`: d(uv)/dstep = (d(Σ pᵢ·uvᵢ) − uv·d(Σ pᵢ)) / Σ pᵢ, with pᵢ = bᵢ/zᵢ.
    #[inline]
    fn uv_footprint(&self, k: [f32; 3], z: f32, scale: f32) -> (Vec2, Vec2, Vec2) {
        let uv = self.uv[0] * k[0] + self.uv[1] * k[1] + self.uv[2] * k[2];
        let dx = (self.duv_step[0] - uv * self.ds_step[0]) * (z * scale);
        let dy = (self.duv_step[1] - uv * self.ds_step[1]) * (z * scale);
        (uv, dx, dy)
    }
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

/// The tile-buffer indices of pixel (px, py)'s `K` × `K` samples (`N` = `K`²) in a tile `w` samples wide, row by
/// row: the order deferred shading and resolving walk a pixel's samples in.
#[inline(always)]
pub(super) fn pixel_samples<const K: usize, const N: usize>(w: usize, px: usize, py: usize) -> [usize; N] {
    let first = py * K * w + px * K;
    std::array::from_fn(|j| first + (j / K) * w + j % K)
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
    /// Linear RGB and alpha of the surface at each sample (meaningful where `object` is not 0).
    pub color: Vec<Vec4>,
    /// View depth (planar), +∞ where empty.
    pub depth: Vec<f32>,
    /// World-space unit normal (meaningful where `object` is not 0).
    pub normal: Vec<Vec3>,
    /// Object id + 1, 0 where empty.
    pub object: Vec<u32>,
    /// Lit shading, deferred: the triangle at each sample ([`NO_TRI`] where none, or where a splat won) and its
    /// perspective-correct barycentrics there. Empty unless the render is lit.
    tri: Vec<u32>,
    bary: Vec<[f32; 3]>,
    /// Fragments of alpha BLEND surfaces, composited over the opaque samples once every triangle is drawn.
    blend: Vec<blend::Fragment>,
    /// What lit shading's anchor pixels found, kept from tile to tile ([`lit::shade_tile`]).
    anchors: Vec<Option<lit::Anchor>>,
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
            anchors: Vec::new(),
        };
        t.reset(rect);
        t
    }

    /// Empties the deferred-shading buffers for the current rect (barycentrics are written with the triangle
    /// and read only where one is, so they keep whatever they hold).
    fn reset_deferred(&mut self) {
        let n = (self.w * self.h) as usize;
        self.tri.clear();
        self.tri.resize(n, NO_TRI);
        self.bary.resize(n, [0.0; 3]);
    }

    /// Empties the tile and moves it to `rect` (keeping its allocations). Only the depth and the object ids
    /// are cleared: colour and normal are written wherever an object id is, and read nowhere else (this
    /// clearing was 5 % of a textured render).
    pub fn reset(&mut self, rect: Rect) {
        let n = (rect.w * rect.h) as usize;
        (self.x0, self.y0, self.w, self.h) = (rect.x0, rect.y0, rect.w, rect.h);
        self.color.resize(n, Vec4::ZERO);
        self.depth.clear();
        self.depth.resize(n, f32::INFINITY);
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
    /// Whether anything reads the normals per sample (Lambert or the normal pass): if not, they are not
    /// interpolated.
    pub normals: bool,
    /// Samples per pixel side: deferred shading runs once per pixel and triangle.
    pub per_side: i64,
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
    let TileWork { tris, splats, .. } = work;
    let Rect { x0, y0, w, h } = rect;
    t.reset(rect);
    let lit = shade.lit.is_some();
    // Opaque textured surfaces are textured once per pixel and triangle ([`deferred`]), and lit ones are shaded
    // so; the samples they win keep their triangle and barycentrics until every triangle is drawn.
    let deferring =
        lit || scene.materials.iter().any(|m| m.alpha_mode == AlphaMode::Opaque && m.base_color_texture.is_some());
    if deferring {
        t.reset_deferred();
    }
    draw_triangles(scene, work, shade, rect, proj, deferring, t);
    if let Some((splats, layer)) = splats {
        // The tile's samples as (index in the tile, index in the band's layer).
        let rows = (y0..y0 + h).map(|sy| ((sy - y0) * w - x0, (sy - layer.y0) * layer.w));
        let samples = rows.flat_map(|(ti, li)| (x0..x0 + w).map(move |sx| ((ti + sx) as usize, (li + sx) as usize)));
        // The samples a splat wins read its point's colour: ask for them all first (see [`Splats::prefetch`]).
        for (_, j) in samples.clone().filter(|&(i, j)| layer.depth(j) < t.depth[i]) {
            splats.prefetch(layer, j);
        }
        for (i, j) in samples {
            let z = layer.depth(j);
            if z < t.depth[i] {
                // Points carry their own colour: unlit.
                let (color, normal, object) = splats.attributes(layer, j);
                t.color[i] = color.truncate().extend(1.0);
                t.depth[i] = z;
                t.normal[i] = normal;
                t.object[i] = object + 1;
                if let Some(d) = t.tri.get_mut(i) {
                    *d = NO_TRI;
                }
            }
        }
    }
    if let Some(l) = &shade.lit {
        lit::shade_tile(scene, tris, l, shade.per_side, rect, proj, t);
    } else if deferring {
        deferred::texture_tile(scene, tris, shade, rect.x0, rect.y0, t);
    }
    blend::composite(t);
}

/// Draws the tile's triangles (of `work`; its splats are merged after), in scene order, into `t` (reset to
/// `rect`): depth-tested samples, shaded now or left for deferred shading (`deferring`: the tile has deferred
/// surfaces, so shaded samples must clear theirs). The tile's buffers are taken apart first so that their
/// pointers and lengths stay in registers across the sample loop (through `t` they were reloaded per sample:
/// writes through one `Vec` may alias another's header).
fn draw_triangles(
    scene: &PosedScene,
    work: TileWork,
    shade: &Shade,
    rect: Rect,
    proj: &Projection,
    deferring: bool,
    t: &mut SampleTile,
) {
    let TileWork { tris, tile, .. } = work;
    let Rect { x0, y0, w, h } = rect;
    let lit = shade.lit.is_some();
    let SampleTile { color, depth, normal, object, tri: tri_at, bary, blend: blends, .. } = t;
    let (color, depth, normal, object) = (&mut color[..], &mut depth[..], &mut normal[..], &mut object[..]);
    let (tri_at, bary) = (&mut tri_at[..], &mut bary[..]);
    for ti in tris.tile(tile) {
        let tri = tris.get(ti);
        let (bx0, by0) = (tri.bbox[0].max(x0), tri.bbox[1].max(y0));
        let (bx1, by1) = (tri.bbox[2].min(x0 + w - 1), tri.bbox[3].min(y0 + h - 1));
        if bx0 > bx1 || by0 > by1 {
            continue;
        }
        let mat = scene.material(tri.material);
        // Opaque surfaces read their base colour texture when shaded, once per pixel and triangle: every sample
        // but the shaded one would read it for nothing. Alpha-tested and blended ones need it per sample.
        let deferred_texture = mat.alpha_mode == AlphaMode::Opaque && (lit || mat.base_color_texture.is_some());
        // Lit surfaces are all shaded deferred (blended ones excepted, below).
        let deferred = lit || deferred_texture;
        // No vertex colours (white, the common case): their interpolation is the sum of the weights, the same
        // sum in the same order as that of their products with 1, without the vector products.
        let white = tri.color == [Vec4::ONE; 3];
        let vertex_colour = |k: [f32; 3]| {
            if white {
                Vec4::splat(k[0] + k[1] + k[2])
            } else {
                tri.color[0] * k[0] + tri.color[1] * k[1] + tri.color[2] * k[2]
            }
        };
        let walk = Walk::new(tri, [bx0, by0, bx1, by1], proj);
        if deferred && mat.alpha_mode == AlphaMode::Opaque {
            // Deferred opaque surfaces (a textured dataset render's every triangle): what a sample that wins keeps
            // for shading, without the tests the others need. The writes repeat the alpha-tested deferred case's
            // below: folded into one helper over the tile's buffers they cost 1 % more of a textured render's
            // instructions (callgrind, the render bench's CesiumMan at 4 samples).
            walk.hits(x0, y0, w, depth, |i, _, k, _| {
                color[i] = (mat.base_color * vertex_colour(k)).truncate().extend(1.0);
                if shade.normals {
                    // Read by Lambert shading and the normal pass only.
                    normal[i] = tri.normal_at(k);
                }
                object[i] = tri.object + 1;
                tri_at[i] = ti;
                bary[i] = k;
                true
            });
            continue;
        }
        if mat.alpha_mode == AlphaMode::Opaque {
            // Opaque and shaded now (unlit, untextured: a ground plane, a vertex-coloured mesh), the same writes
            // as the general case below without its alpha and blending branches. Apart, the walk inlines it:
            // called per sample, the general closure cost an unlit build with a ground half its time.
            walk.hits(x0, y0, w, depth, |i, _, k, _| {
                let albedo = mat.base_color * vertex_colour(k);
                let nrm = if shade.normals { tri.normal_at(k) } else { Vec3::ZERO };
                color[i] = (shade_unlit(shade, mat.unlit, albedo.truncate(), nrm) + mat.emissive).extend(1.0);
                normal[i] = nrm;
                object[i] = tri.object + 1;
                if deferring {
                    tri_at[i] = NO_TRI;
                }
                true
            });
            continue;
        }
        let tex = mat
            .base_color_texture
            .filter(|_| !deferred_texture)
            .and_then(|r| scene.textures.get(r.texture as usize).map(|t| (r, t)));
        walk.hits(x0, y0, w, depth, |i, (sx, sy), k, z| {
            let mut albedo = mat.base_color * vertex_colour(k);
            if let Some((r, texture)) = tex {
                let (uv, dx, dy) = tri.uv_footprint(k, z, 1.0);
                albedo *= texture.sample_footprint(&r, uv, dx, dy);
            }
            match mat.alpha_mode {
                AlphaMode::Mask if albedo.w < mat.alpha_cutoff => return false,
                AlphaMode::Blend if albedo.w <= 0.0 => return false,
                _ => {}
            }
            // Lit shading interpolates its own normal where it shades (deferred or, for a blended sample, here).
            let nrm = if shade.normals { tri.normal_at(k) } else { Vec3::ZERO };
            if mat.alpha_mode == AlphaMode::Blend {
                // Shaded now (it may show through others), composited in depth order when the tile is drawn; the
                // depth it is tested against stays the opaque surfaces'.
                let rgb = match &shade.lit {
                    Some(l) => {
                        let at = Vec2::new(sx as f32 + 0.5, sy as f32 + 0.5);
                        let s = lit::Sample { at, bary: k, z, footprint: 1.0 };
                        // Shaded per sample and per layer: its lobe's occlusion is the hemisphere's, no rays.
                        lit::shade_lobe(scene, tri, l, proj, s, albedo.truncate(), Lobe::Hemisphere).0
                    }
                    None => shade_unlit(shade, mat.unlit, albedo.truncate(), nrm) + mat.emissive,
                };
                let color = rgb.extend(albedo.w.min(1.0));
                blends.push(blend::Fragment { i: i as u32, tri: ti, z, color, normal: nrm, object: tri.object });
                return false;
            }
            if deferred {
                // Alpha-tested, shaded once per pixel and triangle when every triangle is drawn ([`lit`]).
                color[i] = albedo.truncate().extend(1.0);
                if shade.normals {
                    normal[i] = nrm;
                }
                object[i] = tri.object + 1;
                tri_at[i] = ti;
                bary[i] = k;
                return true;
            }
            let rgb = shade_unlit(shade, mat.unlit, albedo.truncate(), nrm) + mat.emissive;
            color[i] = rgb.extend(1.0);
            normal[i] = nrm;
            object[i] = tri.object + 1;
            if deferring {
                // Shaded already: a deferred surface this one hides must not shade it again.
                tri_at[i] = NO_TRI;
            }
            true
        });
    }
}

/// Unlit or Lambert colour of albedo `albedo` with normal `nrm`; a `shadeless` material's is its albedo in either.
#[inline]
fn shade_unlit(shade: &Shade, shadeless: bool, albedo: Vec3, nrm: Vec3) -> Vec3 {
    match &shade.lambert {
        Some((ambient, lights)) if !shadeless => {
            let sum: f32 = lights.iter().map(|(l, k)| k * nrm.dot(*l).max(0.0)).sum();
            albedo * (ambient + sum)
        }
        _ => albedo,
    }
}

/// The camera's backward axis in world space (the head light's direction toward the light).
pub fn camera_back(c2w: &Mat4) -> Vec3 {
    Mat3::from_mat4(*c2w).z_axis.normalize()
}
