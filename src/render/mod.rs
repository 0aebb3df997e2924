//! The CPU renderer: `render(&PosedScene, &Camera, &RenderSettings) -> Frame`. Triangles are clipped,
//! snapped and rasterized per tile ([`raster`]); each pixel's `samples` are resolved into straight-alpha
//! colour (alpha = coverage), depth and normal. Tiles run in parallel with rayon and never share
//! accumulators, so the bytes do not depend on the thread count.

pub mod agx;
pub mod bin;
pub mod encode;
pub mod filter;
mod gaussians;
pub mod light;
pub mod raster;
pub mod splat;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

pub use crate::camera::Camera;
pub use filter::PixelFilter;
pub use splat::{Shape as SplatShape, Size as SplatSize, SplatSettings};

use crate::scene::material::{linear_to_srgb8, Srgb8};
use crate::scene::PosedScene;
use raster::{Projection, Shade};

/// Tile side in pixels.
pub(crate) const TILE: i64 = 32;

/// Surface shading.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Shading {
    /// Albedo only: base colour × texture × vertex colour.
    Unlit,
    /// Albedo × (ambient + Σ lights · max(0, n·l)).
    Lambert,
    /// glTF metallic-roughness shading under the scene's lights and environment, with shadows ([`light`]).
    Pbr,
}

/// What lights a `pbr` render (a description: the environment's data is prepared per build, see
/// [`light::FrameLight`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Lighting {
    /// Lights, manifest order.
    pub lights: Vec<light::Light>,
    /// The environment.
    pub environment: Environment,
    /// Exposure in stops: lit radiance (and the visible environment) times 2^exposure before encoding.
    pub exposure: f32,
    /// How lit light becomes display values.
    pub view: ViewTransform,
}

/// How a lit render's linear light becomes display light before the sRGB encoding (Blender's view transforms).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ViewTransform {
    /// None: light above 1 clips.
    #[default]
    Standard,
    /// Blender 4.x's AgX ([`agx`]).
    Agx,
}

/// A view transform as pixels and baked colours read it: scene light → the display light the sRGB encoding takes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Display {
    agx: Option<&'static agx::Agx>,
}

impl Display {
    /// The display of view transform `view`.
    pub(crate) fn new(view: ViewTransform) -> Display {
        Display { agx: (view == ViewTransform::Agx).then(agx::Agx::get) }
    }

    /// The display of a render with settings `s`: its view transform's when it is lit, else the standard one.
    pub(crate) fn of(s: &RenderSettings) -> Display {
        Display::new(if s.shading == Shading::Pbr { s.lighting.view } else { ViewTransform::Standard })
    }

    /// The display light of scene light `c` (itself under the standard view).
    #[inline]
    pub(crate) fn light(&self, c: Vec3) -> Vec3 {
        match self.agx {
            Some(a) => a.display(c),
            None => c,
        }
    }
}

/// The environment a `pbr` render is lit by.
#[derive(Debug, Clone, PartialEq)]
pub struct Environment {
    /// Which map: the built-in studio, or a file by its content key (hex blake3 of its bytes).
    pub map: Option<String>,
    /// Radiance multiplier.
    pub strength: f32,
    /// Rotation about world +Z, degrees.
    pub rotation_deg: f32,
    /// Whether the map is the RGBA pass's background.
    pub visible: bool,
}

impl Default for Environment {
    fn default() -> Self {
        Environment { map: None, strength: 1.0, rotation_deg: 0.0, visible: false }
    }
}

impl Environment {
    /// World → map frame: the lookup direction is this times the world direction (Blender: a Mapping node of
    /// type Point rotating Z by `rotation_deg`, in front of the Environment Texture node).
    pub fn rotation(&self) -> glam::Mat3 {
        glam::Mat3::from_rotation_z(self.rotation_deg.to_radians())
    }

    /// The built-in studio environment's lighting under these settings (its prefiltering is computed once per
    /// process).
    pub fn studio(&self) -> light::EnvLight {
        static STUDIO: std::sync::LazyLock<(std::sync::Arc<light::EnvMap>, std::sync::Arc<light::Prefiltered>)> =
            std::sync::LazyLock::new(|| {
                let map = light::environment::studio();
                let pre = light::environment::prefilter_here(&map);
                (std::sync::Arc::new(map), std::sync::Arc::new(pre))
            });
        self.with(STUDIO.1.clone(), Some(STUDIO.0.clone()))
    }

    /// These settings over a prefiltered map and the map itself (the background, used when `visible`; a caller
    /// that knows it is not may pass `None`).
    pub fn with(
        &self,
        prefiltered: std::sync::Arc<light::Prefiltered>,
        map: Option<std::sync::Arc<light::EnvMap>>,
    ) -> light::EnvLight {
        light::EnvLight {
            prefiltered,
            strength: self.strength,
            rotation: self.rotation(),
            background: map.filter(|_| self.visible),
        }
    }
}

/// What the depth buffer holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DepthKind {
    /// Distance along the optical axis.
    Planar,
    /// Distance from the camera centre.
    Ray,
}

/// Everything that shapes a render (the manifest's `[render]` converts into it; the renderer knows no
/// manifest).
#[derive(Debug, Clone)]
pub struct RenderSettings {
    /// Samples per pixel: 1, 4, 9 or 16 (a k×k grid).
    pub samples: u32,
    /// How a pixel's colour gathers its samples and its neighbours' (RGBA only; the other buffers are per pixel).
    pub filter: PixelFilter,
    /// Unlit or Lambert.
    pub shading: Shading,
    /// Lambert lights: direction the light travels, intensity. Empty: a head light.
    pub lights: Vec<(Vec3, f32)>,
    /// Lambert ambient term.
    pub ambient: f32,
    /// Lights and environment of `pbr` shading.
    pub lighting: Lighting,
    /// Opaque background (linear RGB), or transparent.
    pub background: Option<Vec3>,
    /// Planar z-depth or ray distance in the depth buffer.
    pub depth: DepthKind,
    /// How point primitives are drawn.
    pub splat: SplatSettings,
    /// Which auxiliary buffers to fill; the others stay empty in the [`Frame`] (an 800² normal buffer alone is
    /// 7.7 MB to allocate and fault in per image).
    pub buffers: Buffers,
}

/// Auxiliary buffers of a [`Frame`] (colour and coverage are always made).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Buffers {
    /// Depth.
    pub depth: bool,
    /// Normals.
    pub normal: bool,
    /// Object ids.
    pub object: bool,
}

impl Default for Buffers {
    fn default() -> Self {
        Buffers { depth: true, normal: true, object: true }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            samples: 1,
            filter: PixelFilter::Box,
            shading: Shading::Unlit,
            lights: Vec::new(),
            ambient: 0.3,
            lighting: Lighting::default(),
            background: None,
            depth: DepthKind::Planar,
            splat: SplatSettings::default(),
            buffers: Buffers::default(),
        }
    }
}

/// One rendered view.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// sRGB RGBA8, straight alpha (the coverage, spread by the pixel filter when it is not a box), rows top first.
    pub rgba: Vec<u8>,
    /// Depth in scene units (planar or ray, per the settings); 0 where less than half the pixel is covered.
    /// Empty unless [`Buffers::depth`].
    pub depth: Vec<f32>,
    /// World-space unit normals (zero where less than half the pixel is covered). Empty unless
    /// [`Buffers::normal`].
    pub normal: Vec<Vec3>,
    /// Object id + 1 of the majority of the pixel's covered samples (0 = background). Empty unless
    /// [`Buffers::object`].
    pub object: Vec<u32>,
    /// Coverage in 0..=255 (the alpha of a transparent background, whatever the background).
    pub coverage: Vec<u8>,
}

/// Renders one view of a posed scene. A `pbr` render is lit by the built-in studio environment and
/// `s.lighting`'s lights; a build prepares each frame's lighting once and calls [`render_lit`].
pub fn render(scene: &PosedScene, cam: &Camera, s: &RenderSettings) -> Frame {
    if s.shading == Shading::Pbr {
        let light = light::FrameLight::prepare(
            scene,
            &s.lighting.lights,
            s.lighting.environment.studio(),
            light::PointCasters::of(&s.splat),
        )
        .with_bounce(scene)
        .with_exposure(s.lighting.exposure);
        return render_lit(scene, cam, s, Some(&light));
    }
    render_lit(scene, cam, s, None)
}

/// Renders one view with a frame's prepared lighting (used when `s.shading` is `pbr`).
pub fn render_lit(scene: &PosedScene, cam: &Camera, s: &RenderSettings, light: Option<&light::FrameLight>) -> Frame {
    let light = light.filter(|_| s.shading == Shading::Pbr);
    let k = (s.samples as f64).sqrt().round().max(1.0) as i64;
    let (w, h) = (cam.width as i64, cam.height as i64);
    let proj = Projection {
        w2c: cam.w2c_f32(),
        f: [
            (cam.fx * k as f64) as f32,
            (cam.fy * k as f64) as f32,
            (cam.cx * k as f64) as f32,
            (cam.cy * k as f64) as f32,
        ],
        near: cam.near as f32,
        far: cam.far as f32,
        size: (w * k, h * k),
    };
    let (tw, th) = ((w + TILE - 1) / TILE, (h + TILE - 1) / TILE);
    let ts = TILE * k;
    // Triangles and splats are binned in scene order: the depth test keeps the first of equal depths, so order
    // matters and must not depend on threads.
    let vis = light.map(|l| l.vertex_visibility.as_slice());
    let tris = raster::setup(scene, &proj, raster::Tiles { side: ts, across: tw, down: th }, vis);
    let splats = splat::setup(scene, &proj, &s.splat, k as f32, ts);
    let shade = Shade {
        lambert: (s.shading == Shading::Lambert).then(|| {
            let lights = if s.lights.is_empty() {
                vec![(raster::camera_back(&cam.c2w.as_mat4()), 1.0 - s.ambient)]
            } else {
                s.lights.iter().map(|(d, i)| (-d.normalize(), *i)).collect()
            };
            (s.ambient, lights)
        }),
        lit: light.map(|light| raster::Lit { light, c2w: cam.c2w.as_mat4(), eye: cam.c2w.w_axis.truncate().as_vec3() }),
        normals: s.shading == Shading::Lambert || s.buffers.normal,
        per_side: k,
    };
    let n = (w * h) as usize;
    // Gaussians are drawn last and stop at the depth of what was drawn before them.
    let gaussians = gaussians::any(scene);
    let b = Buffers { depth: s.buffers.depth || gaussians, ..s.buffers };
    let mut f = Frame {
        width: cam.width,
        height: cam.height,
        rgba: vec![0; n * 4],
        depth: if b.depth { vec![0.0; n] } else { Vec::new() },
        normal: if b.normal { vec![Vec3::ZERO; n] } else { Vec::new() },
        object: if b.object { vec![0; n] } else { Vec::new() },
        coverage: vec![0; n],
    };
    // A filter wider than the pixel reads its neighbours, which other bands resolve: the bands leave linear
    // premultiplied colour, filtered once they are all done.
    let kernel = s.filter.kernel(k as u32);
    let mut linear = if kernel.is_some() { vec![Vec4::ZERO; n] } else { Vec::new() };
    // One task per band of TILE rows: its tiles run in order through one reused sample buffer and resolve
    // straight into the band's rows of the frame (no per-tile allocation, no copy afterwards). Buffers not
    // asked for give every band an empty slice.
    let band = (TILE * w) as usize;
    let mut lin = linear.chunks_mut(band);
    let (mut rgba, mut depth) = (f.rgba.chunks_mut(band * 4), f.depth.chunks_mut(band));
    let (mut normal, mut object) = (f.normal.chunks_mut(band), f.object.chunks_mut(band));
    let mut coverage = f.coverage.chunks_mut(band);
    let bands: Vec<Pixels> = (0..th)
        .map(|_| Pixels {
            rgba: rgba.next().expect("BUG: one chunk per band"),
            linear: lin.next().unwrap_or_default(),
            depth: depth.next().unwrap_or_default(),
            normal: normal.next().unwrap_or_default(),
            object: object.next().unwrap_or_default(),
            coverage: coverage.next().expect("BUG: one chunk per band"),
            width: w,
        })
        .collect();
    let env_bg =
        light.filter(|l| l.has_background()).map(|light| EnvBackground { light, cam, display: Display::of(s) });
    // Sample buffers are reused by the bands a worker takes.
    let scratch = || (None::<raster::SampleTile>, splat::Layer::default());
    bands.into_par_iter().enumerate().for_each_init(scratch, |(st, layer), (band, mut out)| {
        let ty = band as i64;
        let drawn = splats.draw_band(band, &proj, layer);
        for tx in 0..tw {
            let (x0, y0) = (tx * TILE, ty * TILE);
            let (pw, ph) = (TILE.min(w - x0), TILE.min(h - y0));
            let rect = raster::Rect { x0: x0 * k, y0: y0 * k, w: pw * k, h: ph * k };
            let ti = (ty * tw + tx) as usize;
            let has_splats = drawn && layer.any(rect.x0, rect.w);
            if tris.tile_is_empty(ti) && !has_splats {
                // Nothing reaches this tile (most of a dataset image): only an opaque background is written,
                // the other buffers start zeroed.
                if !out.linear.is_empty() {
                    for py in 0..ph {
                        for px in 0..pw {
                            out.linear[(py * w + x0 + px) as usize] =
                                empty_linear(s, env_bg.as_ref(), x0 + px, ty * TILE + py);
                        }
                    }
                } else if let Some(env) = &env_bg {
                    for py in 0..ph {
                        for px in 0..pw {
                            let i = ((py * w + x0 + px) * 4) as usize;
                            out.rgba[i..i + 4].copy_from_slice(&env.pixel(x0 + px, ty * TILE + py));
                        }
                    }
                } else if let Some(bg) = empty_pixel(s).filter(|p| p[3] != 0) {
                    for py in 0..ph {
                        let row = ((py * w + x0) * 4) as usize;
                        for px in out.rgba[row..row + (pw * 4) as usize].chunks_exact_mut(4) {
                            px.copy_from_slice(&bg);
                        }
                    }
                }
                continue;
            }
            let work = raster::TileWork { tris: &tris, tile: ti, splats: has_splats.then_some((&splats, &*layer)) };
            let st = st.get_or_insert_with(|| raster::SampleTile::new(rect));
            raster::raster_tile(scene, work, &shade, rect, &proj, st);
            resolve(st, k, s, cam, x0, env_bg.as_ref(), &mut out);
        }
    });
    if let Some(kernel) = kernel {
        filter::apply(&kernel, &mut linear, w as usize, h as usize, &mut f.rgba);
    }
    if gaussians {
        gaussians::draw(scene, cam, s.depth, &mut f);
        if !s.buffers.depth {
            f.depth = Vec::new();
        }
    }
    f
}

/// One band of the frame's buffers (rows `TILE·band ..`), written by [`resolve`].
struct Pixels<'a> {
    rgba: &'a mut [u8],
    /// Linear premultiplied colour instead of `rgba`, when a pixel filter follows (else empty).
    linear: &'a mut [Vec4],
    depth: &'a mut [f32],
    normal: &'a mut [Vec3],
    object: &'a mut [u32],
    coverage: &'a mut [u8],
    width: i64,
}

/// The visible environment behind a lit render.
struct EnvBackground<'a> {
    light: &'a light::FrameLight,
    cam: &'a Camera,
    display: Display,
}

impl EnvBackground<'_> {
    /// The environment's display light along the ray through pixel (x, y)'s centre.
    fn at(&self, x: i64, y: i64) -> Vec3 {
        let c = self.cam;
        let d = glam::DVec3::new((x as f64 + 0.5 - c.cx) / c.fx, -((y as f64 + 0.5 - c.cy) / c.fy), -1.0);
        let world = glam::DMat3::from_mat4(c.c2w) * d;
        self.display.light(self.light.background(world.as_vec3().normalize()).unwrap_or(Vec3::ZERO))
    }

    /// The opaque sRGB pixel (x, y) where nothing covers it.
    fn pixel(&self, x: i64, y: i64) -> [u8; 4] {
        let c = self.at(x, y);
        [linear_to_srgb8(c.x), linear_to_srgb8(c.y), linear_to_srgb8(c.z), 255]
    }
}

/// Resolves a tile's samples into its pixels of the band `out` (tile columns from `x0`): straight-alpha colour,
/// majority depth / normal / object.
fn resolve(
    st: &raster::SampleTile,
    k: i64,
    s: &RenderSettings,
    cam: &Camera,
    x0: i64,
    env: Option<&EnvBackground>,
    out: &mut Pixels,
) {
    // One copy per sample grid, as for deferred shading: with the sample count known the per-pixel loops unroll
    // (the generic ones were most of resolving's instructions).
    match k {
        1 => resolve_grid::<1, 1>(st, s, cam, x0, env, out),
        2 => resolve_grid::<2, 4>(st, s, cam, x0, env, out),
        3 => resolve_grid::<3, 9>(st, s, cam, x0, env, out),
        _ => resolve_grid::<4, 16>(st, s, cam, x0, env, out),
    }
}

/// [`resolve`] for `K` × `K` samples per pixel (`N` = `K`²).
#[inline(always)]
fn resolve_grid<const K: usize, const N: usize>(
    st: &raster::SampleTile,
    s: &RenderSettings,
    cam: &Camera,
    x0: i64,
    env: Option<&EnvBackground>,
    out: &mut Pixels,
) {
    debug_assert_eq!(N, K * K);
    let k = K as i64;
    let (pw, ph) = (st.w / k, st.h / k);
    let total = N as u32;
    let y0 = st.y0 / k;
    // Most pixels of a dataset image are background: one precomputed value for them.
    let empty = empty_pixel(s).unwrap_or([0; 4]);
    let mut ids = [0u32; N];
    let w = st.w as usize;
    let srgb = Srgb8::tables();
    let display = Display::of(s);
    for py in 0..ph {
        for px in 0..pw {
            let i = (py * out.width + x0 + px) as usize;
            let (mut sum, mut covered, mut depth) = (Vec4::ZERO, 0u32, 0f32);
            // The pixel's samples, row by row (what is summed only sometimes is summed in a second walk, in the
            // same order).
            let samples: [usize; N] = raster::pixel_samples::<K, N>(w, px as usize, py as usize);
            for j in samples {
                if st.object[j] == 0 {
                    continue;
                }
                ids[covered as usize] = st.object[j];
                covered += 1;
                sum += st.color[j];
                depth += st.depth[j];
            }
            let covered_samples = || samples.into_iter().filter(|&j| st.object[j] != 0);
            if covered == 0 {
                // The other buffers start zeroed.
                if !out.linear.is_empty() {
                    out.linear[i] = empty_linear(s, env, x0 + px, y0 + py);
                    continue;
                }
                let px = env.map_or(empty, |env| env.pixel(x0 + px, y0 + py));
                out.rgba[i * 4..i * 4 + 4].copy_from_slice(&px);
                continue;
            }
            let (mut alpha, mut rgb, mut coverage);
            if sum.w == covered as f32 {
                // Opaque samples only (the sum of their alphas is exact).
                alpha = covered as f32 / total as f32;
                rgb = sum.truncate() / covered as f32;
                // covered·255/total rounded half up, in integers.
                coverage = ((covered * 510 + total) / (2 * total)) as u8;
            } else {
                // Transparent (BLEND) samples have alpha under 1: their colours weigh by it.
                let weighted = covered_samples().fold(Vec3::ZERO, |w, j| w + st.color[j].truncate() * st.color[j].w);
                alpha = sum.w / total as f32;
                rgb = if sum.w > 0.0 { weighted / sum.w } else { Vec3::ZERO };
                coverage = (alpha * 255.0 + 0.5) as u8;
            }
            if coverage == 0 {
                // Nothing shows: a fully transparent surface over the background.
                (alpha, rgb, coverage) = (0.0, Vec3::ZERO, 0);
            }
            // Display light from here on: a background composites over what the view shows of the surface
            // (under AgX, a white background stays white).
            rgb = display.light(rgb);
            let mut a8 = coverage;
            if let Some(env) = env {
                // The environment shows where the surface does not cover the pixel.
                rgb = rgb * alpha + env.at(x0 + px, y0 + py) * (1.0 - alpha);
                (a8, alpha) = (255, 1.0);
            } else if let Some(bg) = s.background {
                rgb = rgb * alpha + bg * (1.0 - alpha);
                (a8, alpha) = (255, 1.0);
            }
            if !out.linear.is_empty() {
                out.linear[i] = (rgb * alpha).extend(alpha);
            } else {
                out.rgba[i * 4..i * 4 + 4].copy_from_slice(&[
                    srgb.encode(rgb.x),
                    srgb.encode(rgb.y),
                    srgb.encode(rgb.z),
                    a8,
                ]);
            }
            out.coverage[i] = coverage;
            if !out.object.is_empty() {
                out.object[i] = majority_id(&ids[..covered as usize]);
            }
            if 2 * covered >= total && !out.depth.is_empty() {
                let z = depth / covered as f32;
                out.depth[i] = match s.depth {
                    DepthKind::Planar => z,
                    DepthKind::Ray => {
                        let (x, y) = ((x0 + px) as f64 + 0.5, (y0 + py) as f64 + 0.5);
                        let (dx, dy) = ((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy);
                        (z as f64 * (dx * dx + dy * dy + 1.0).sqrt()) as f32
                    }
                };
            }
            if 2 * covered >= total && !out.normal.is_empty() {
                let normal = covered_samples().fold(Vec3::ZERO, |n, j| n + st.normal[j]);
                out.normal[i] = normal.normalize_or_zero();
            }
        }
    }
}

/// The RGBA8 of a pixel nothing covers: the opaque background, or `None` when it is transparent.
fn empty_pixel(s: &RenderSettings) -> Option<[u8; 4]> {
    s.background.map(|bg| [linear_to_srgb8(bg.x), linear_to_srgb8(bg.y), linear_to_srgb8(bg.z), 255])
}

/// What a filtered render's pixel (x, y) holds where nothing covers it: the visible environment or the opaque
/// background, in linear light and opaque, else zero (transparent).
fn empty_linear(s: &RenderSettings, env: Option<&EnvBackground>, x: i64, y: i64) -> Vec4 {
    env.map(|env| env.at(x, y)).or(s.background).map_or(Vec4::ZERO, |c| c.extend(1.0))
}

fn majority_id(ids: &[u32]) -> u32 {
    let first = ids[0];
    if ids.iter().all(|&i| i == first) {
        return first;
    }
    let mut best = (0usize, u32::MAX);
    for &a in ids {
        let n = ids.iter().filter(|&&b| b == a).count();
        if n > best.0 || (n == best.0 && a < best.1) {
            best = (n, a);
        }
    }
    best.1
}
