//! The CPU renderer: `render(&PosedScene, &Camera, &RenderSettings) -> Frame`. Triangles are clipped,
//! snapped and rasterized per tile ([`raster`]); each pixel's `samples` are resolved into straight-alpha
//! colour (alpha = coverage), depth and normal. Tiles run in parallel with rayon and never share
//! accumulators, so the bytes do not depend on the thread count.

pub mod camera;
pub mod encode;
pub mod raster;
pub mod splat;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

pub use camera::Camera;
pub use splat::{Shape as SplatShape, Size as SplatSize, SplatSettings};

use crate::manifest::render::{DepthKind, Shading};
use crate::scene::material::linear_to_srgb8;
use crate::scene::PosedScene;
use raster::{Projection, Shade};

/// Tile side in pixels.
const TILE: i64 = 32;

/// What the renderer needs from `[render]`.
#[derive(Debug, Clone)]
pub struct RenderSettings {
    /// Samples per pixel: 1, 4, 9 or 16 (a k×k grid).
    pub samples: u32,
    /// Unlit or Lambert.
    pub shading: Shading,
    /// Lambert lights: direction the light travels, intensity. Empty: a head light.
    pub lights: Vec<(Vec3, f32)>,
    /// Lambert ambient term.
    pub ambient: f32,
    /// Opaque background (linear RGB), or transparent.
    pub background: Option<Vec3>,
    /// Planar z-depth or ray distance in the depth buffer.
    pub depth: DepthKind,
    /// How point primitives are drawn.
    pub splat: SplatSettings,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            samples: 1,
            shading: Shading::Unlit,
            lights: Vec::new(),
            ambient: 0.3,
            background: None,
            depth: DepthKind::Planar,
            splat: SplatSettings::default(),
        }
    }
}

impl RenderSettings {
    /// The settings `[render]` asks for. `voxel` is the world size of one voxel of a point-cloud source, the
    /// default splat size; without it, splats default to 1.5 px.
    pub fn from_manifest(r: &crate::manifest::render::Render, voxel: Option<f32>) -> RenderSettings {
        use crate::manifest::render::{Background, SplatShape as S};
        use crate::scene::material::srgb_to_linear;
        let lin = |c: [f64; 3]| {
            Vec3::new(srgb_to_linear(c[0] as f32), srgb_to_linear(c[1] as f32), srgb_to_linear(c[2] as f32))
        };
        let background = match r.background.as_ref().map(|b| b.get_ref()) {
            Some(Background::Named(n)) if n == "white" => Some(Vec3::ONE),
            Some(Background::Named(n)) if n == "black" => Some(Vec3::ZERO),
            Some(Background::Rgb(c)) => Some(lin(*c)),
            _ => None,
        };
        let size = match (r.splat.size, r.splat.size_px, voxel) {
            (Some(w), _, _) => SplatSize::World(w as f32),
            (None, Some(px), _) => SplatSize::Pixels(px as f32),
            (None, None, Some(v)) => SplatSize::World(v),
            (None, None, None) => SplatSize::Pixels(1.5),
        };
        let shape = match r.splat.shape {
            S::Cube => SplatShape::Cube,
            S::Square => SplatShape::Square,
            S::Disk => SplatShape::Disk,
        };
        RenderSettings {
            samples: *r.samples.get_ref(),
            shading: r.shading,
            lights: r.lights.iter().map(|l| (glam::DVec3::from(l.direction).as_vec3(), l.intensity as f32)).collect(),
            ambient: r.ambient.unwrap_or(0.3) as f32,
            background,
            depth: r.depth.kind,
            splat: SplatSettings { shape, size },
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
    /// sRGB RGBA8, straight alpha, rows top first.
    pub rgba: Vec<u8>,
    /// Depth in scene units (planar or ray, per the settings); 0 where less than half the pixel is covered.
    pub depth: Vec<f32>,
    /// World-space unit normals (zero where less than half the pixel is covered).
    pub normal: Vec<Vec3>,
    /// Object id + 1 of the majority of the pixel's covered samples (0 = background).
    pub object: Vec<u32>,
    /// Coverage in 0..=255 (the alpha of a transparent background, whatever the background).
    pub coverage: Vec<u8>,
}

/// Renders one view of a posed scene.
pub fn render(scene: &PosedScene, cam: &Camera, s: &RenderSettings) -> Frame {
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
    let tris = raster::setup(scene, &proj);
    let splats = splat::setup(scene, &proj, &s.splat, k as f32);
    // Bin triangles into tiles in scene order: the depth test keeps the first of equal depths, so order matters
    // and must not depend on threads.
    let (tw, th) = ((w + TILE - 1) / TILE, (h + TILE - 1) / TILE);
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); (tw * th) as usize];
    let ts = TILE * k;
    let bin = |bins: &mut Vec<Vec<u32>>, i: usize, bbox: &[i64; 4]| {
        for ty in bbox[1] / ts..=bbox[3] / ts {
            for tx in bbox[0] / ts..=bbox[2] / ts {
                bins[(ty * tw + tx) as usize].push(i as u32);
            }
        }
    };
    for (i, t) in tris.iter().enumerate() {
        bin(&mut bins, i, &t.bbox);
    }
    let mut splat_bins: Vec<Vec<u32>> = vec![Vec::new(); (tw * th) as usize];
    for (i, sp) in splats.iter().enumerate() {
        bin(&mut splat_bins, i, &sp.bbox);
    }
    let shade = Shade {
        lambert: (s.shading == Shading::Lambert).then(|| {
            let lights = if s.lights.is_empty() {
                vec![(raster::camera_back(&cam.c2w.as_mat4()), 1.0 - s.ambient)]
            } else {
                s.lights.iter().map(|(d, i)| (-d.normalize(), *i)).collect()
            };
            (s.ambient, lights)
        }),
    };
    let tiles: Vec<_> = (0..tw * th)
        .into_par_iter()
        .map(|ti| {
            let (tx, ty) = (ti % tw, ti / tw);
            let (x0, y0) = (tx * TILE, ty * TILE);
            let (pw, ph) = (TILE.min(w - x0), TILE.min(h - y0));
            let rect = raster::Rect { x0: x0 * k, y0: y0 * k, w: pw * k, h: ph * k };
            let work = raster::TileWork {
                tris: &tris,
                bin: &bins[ti as usize],
                splats: &splats,
                splat_bin: &splat_bins[ti as usize],
            };
            let st = raster::raster_tile(scene, work, &shade, rect, &proj);
            resolve(&st, k, s)
        })
        .collect();
    let n = (w * h) as usize;
    let mut f = Frame {
        width: cam.width,
        height: cam.height,
        rgba: vec![0; n * 4],
        depth: vec![0.0; n],
        normal: vec![Vec3::ZERO; n],
        object: vec![0; n],
        coverage: vec![0; n],
    };
    for (ti, px) in tiles.into_iter().enumerate() {
        let (x0, y0) = ((ti as i64 % tw) * TILE, (ti as i64 / tw) * TILE);
        let pw = TILE.min(w - x0);
        for (j, p) in px.into_iter().enumerate() {
            let (x, y) = (x0 + j as i64 % pw, y0 + j as i64 / pw);
            let i = (y * w + x) as usize;
            f.rgba[i * 4..i * 4 + 4].copy_from_slice(&p.0);
            f.depth[i] = match s.depth {
                DepthKind::Planar => p.1,
                DepthKind::Ray => {
                    let (dx, dy) = ((x as f64 + 0.5 - cam.cx) / cam.fx, (y as f64 + 0.5 - cam.cy) / cam.fy);
                    (p.1 as f64 * (dx * dx + dy * dy + 1.0).sqrt()) as f32
                }
            };
            f.normal[i] = p.2;
            f.object[i] = p.3;
            f.coverage[i] = p.4;
        }
    }
    f
}

/// Resolves a tile's k×k samples per pixel: alpha is coverage, colour the mean of covered samples (straight).
fn resolve(st: &raster::SampleTile, k: i64, s: &RenderSettings) -> Vec<([u8; 4], f32, Vec3, u32, u8)> {
    let (pw, ph) = (st.w / k, st.h / k);
    let mut out = Vec::with_capacity((pw * ph) as usize);
    let total = (k * k) as u32;
    // Most pixels of a dataset image are background: one precomputed value for them.
    let empty = match s.background {
        Some(bg) => ([linear_to_srgb8(bg.x), linear_to_srgb8(bg.y), linear_to_srgb8(bg.z), 255], 0.0, Vec3::ZERO, 0, 0),
        None => ([0; 4], 0.0, Vec3::ZERO, 0, 0),
    };
    let mut ids = [0u32; 16];
    for py in 0..ph {
        for px in 0..pw {
            let (mut sum, mut covered, mut depth, mut normal) = (Vec4::ZERO, 0u32, 0f32, Vec3::ZERO);
            for sy in 0..k {
                let row = ((py * k + sy) * st.w + px * k) as usize;
                for i in row..row + k as usize {
                    if st.object[i] == 0 {
                        continue;
                    }
                    ids[covered as usize] = st.object[i];
                    covered += 1;
                    sum += st.color[i];
                    depth += st.depth[i];
                    normal += st.normal[i];
                }
            }
            if covered == 0 {
                out.push(empty);
                continue;
            }
            let alpha = covered as f32 / total as f32;
            let mut rgb = sum.truncate() / covered as f32;
            let coverage = (alpha * 255.0).round() as u8;
            let mut a8 = coverage;
            if let Some(bg) = s.background {
                rgb = rgb * alpha + bg * (1.0 - alpha);
                a8 = 255;
            }
            let majority = 2 * covered >= total;
            out.push((
                [linear_to_srgb8(rgb.x), linear_to_srgb8(rgb.y), linear_to_srgb8(rgb.z), a8],
                if majority { depth / covered as f32 } else { 0.0 },
                if majority { normal.normalize_or_zero() } else { Vec3::ZERO },
                majority_id(&ids[..covered as usize]),
                coverage,
            ));
        }
    }
    out
}

/// The most frequent id (ties: the smallest), for at most 16 samples.
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
