//! Point splats: screen-aligned squares and disks (one depth per splat, depth-tested against everything),
//! and true 3D cubes, drawn by intersecting each covered sample's ray with the box (exact silhouette, depth
//! and face normal per sample, no triangles).

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::raster::{Projection, SUBPIXEL};
use crate::scene::{PosedScene, PrimKind};

/// Splat shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// A 3D cube centred on the point.
    Cube,
    /// A screen-aligned square.
    Square,
    /// A screen-aligned disk.
    Disk,
}

/// Splat size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Size {
    /// Edge (cube, square) or diameter (disk) in world units.
    World(f32),
    /// Edge or diameter in pixels.
    Pixels(f32),
}

/// How points are drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplatSettings {
    /// Shape.
    pub shape: Shape,
    /// Size.
    pub size: Size,
}

impl Default for SplatSettings {
    fn default() -> Self {
        SplatSettings { shape: Shape::Square, size: Size::Pixels(1.0) }
    }
}

/// A screen-space splat, in fixed-point sample coordinates: kept small (tiles copy the splats they overlap and
/// walk them in order), with colour, normal and object looked up in [`Splats`] only when a sample is written.
#[derive(Debug, Clone, Copy)]
pub struct Splat {
    x: i32,
    y: i32,
    r: i32,
    /// View depth (of the centre; a cube's samples take their own depth).
    pub z: f32,
    /// Index into [`Splats`]' attributes.
    pub point: u32,
    disk: bool,
    /// For cubes: the centre relative to the eye (world axes) and half the edge.
    pub cube: Option<(Vec3, f32)>,
}

/// Every splat of a frame and the attributes of its point.
#[derive(Debug, Default)]
pub struct Splats {
    /// Splats in scene order.
    pub splats: Vec<Splat>,
    /// Linear colour per splat.
    pub colors: Vec<Vec4>,
    /// World normal per splat.
    pub normals: Vec<Vec3>,
    /// Object id per splat.
    pub objects: Vec<u32>,
}

/// Screen-space splats for every point primitive, in scene order. Cubes are world-axis-aligned boxes of edge
/// `size` around each point, drawn exactly by intersecting each sample's ray with the box (see [`Rays`]); their
/// bounding box is the projection of the circumscribed sphere.
pub fn setup(scene: &PosedScene, p: &Projection, s: &SplatSettings, k: f32) -> Splats {
    let n = scene.point_count();
    let mut out = Splats {
        splats: Vec::with_capacity(n),
        colors: Vec::with_capacity(n),
        normals: Vec::with_capacity(n),
        objects: Vec::with_capacity(n),
    };
    let eye = p.w2c.inverse().w_axis.truncate();
    for prim in scene.primitives.iter().filter(|q| q.kind == PrimKind::Points) {
        let base = scene.materials.get(prim.material as usize).map_or(Vec4::ONE, |m| m.base_color);
        // Chunks in parallel, concatenated in order: the splat order (which decides depth ties) is the scene's.
        let chunks: Vec<Splats> = prim
            .positions
            .par_chunks(SETUP_CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut part = Splats::default();
                for (j, pos) in chunk.iter().enumerate() {
                    let Some(sp) = project(*pos, p, s, k, eye) else { continue };
                    let i = c * SETUP_CHUNK + j;
                    part.splats.push(Splat { point: part.colors.len() as u32, ..sp });
                    part.colors.push(base * prim.colors.get(i).copied().unwrap_or(Vec4::ONE));
                    part.normals.push(prim.normals.get(i).copied().unwrap_or(Vec3::ZERO));
                    part.objects.push(prim.object);
                }
                part
            })
            .collect();
        for part in chunks {
            let offset = out.colors.len() as u32;
            out.splats.extend(part.splats.into_iter().map(|sp| Splat { point: sp.point + offset, ..sp }));
            out.colors.extend(part.colors);
            out.normals.extend(part.normals);
            out.objects.extend(part.objects);
        }
    }
    out
}

/// Points per setup task.
const SETUP_CHUNK: usize = 16384;

/// The splat of the point at world `pos`, or `None` when it is clipped or falls outside the image.
#[inline]
fn project(pos: Vec3, p: &Projection, s: &SplatSettings, k: f32, eye: Vec3) -> Option<Splat> {
    let [fx, fy, cx, cy] = p.f;
    let lim = (p.size.0.max(p.size.1) + 2) as f32 * SUBPIXEL as f32;
    let v = p.w2c.transform_point3(pos);
    let z = -v.z;
    if !(z >= p.near && z <= p.far) {
        return None;
    }
    let (sx, sy) = (cx + fx * v.x / z, cy - fy * v.y / z);
    let (half, cube) = match (s.shape, s.size) {
        (Shape::Cube, size) => {
            // A pixel size is taken at unit distance.
            let h = 0.5
                * match size {
                    Size::World(w) => w,
                    Size::Pixels(px) => px * k / fx,
                };
            let reach = h * 3f32.sqrt();
            // The near plane would cut the cube: drop it (cubes are voxel-sized).
            if z - reach < p.near {
                return None;
            }
            (reach * fx.max(fy) / (z - reach), Some((pos - eye, h)))
        }
        (_, Size::World(w)) => (0.5 * w * fx / z, None),
        (_, Size::Pixels(px)) => (0.5 * px * k, None),
    };
    let fixed = |v: f32| (v * SUBPIXEL as f32).round().clamp(-lim, lim) as i32;
    let sp = Splat { x: fixed(sx), y: fixed(sy), r: fixed(half), z, point: 0, disk: s.shape == Shape::Disk, cube };
    let b = sp.bbox(p.size);
    (sp.r > 0 && b[0] <= b[2] && b[1] <= b[3]).then_some(sp)
}

impl Splat {
    /// Inclusive bounding box, within a `size` sample grid, of the samples whose centres lie in
    /// [x − r, x + r) × [y − r, y + r): exactly the ones [`Splat::covers`] may accept (empty when min > max).
    #[inline]
    pub fn bbox(&self, size: (i64, i64)) -> [i64; 4] {
        let (x, y, r) = (self.x as i64, self.y as i64, self.r as i64);
        // Sample s has its centre at s·S + S/2: the first centre ≥ a and the last centre < b.
        let first = |a: i64| -(SUBPIXEL / 2 - a).div_euclid(SUBPIXEL);
        let last = |b: i64| (b - 1 - SUBPIXEL / 2).div_euclid(SUBPIXEL);
        [first(x - r).max(0), first(y - r).max(0), last(x + r).min(size.0 - 1), last(y + r).min(size.1 - 1)]
    }

    /// Whether the sample centre (fixed point) is covered. Squares are half-open so that splats one size
    /// apart tile without double hits.
    #[inline]
    pub fn covers(&self, px: i64, py: i64) -> bool {
        let (dx, dy, r) = (px - self.x as i64, py - self.y as i64, self.r as i64);
        if self.disk {
            dx * dx + dy * dy < r * r
        } else {
            dx >= -r && dx < r && dy >= -r && dy < r
        }
    }
}

/// Per-sample rays of a tile for cube splats: the reciprocal of each sample's world direction, scaled so that the
/// ray parameter is the planar view depth.
pub struct Rays {
    inv: Vec<Vec3>,
}

impl Rays {
    /// Rays through the sample centres of the `w × h` samples at (`x0`, `y0`).
    pub fn new(p: &Projection, x0: i64, y0: i64, w: i64, h: i64) -> Rays {
        let rot = glam::Mat3::from_mat4(p.w2c.inverse());
        let [fx, fy, cx, cy] = p.f;
        let mut inv = Vec::with_capacity((w * h) as usize);
        for sy in y0..y0 + h {
            for sx in x0..x0 + w {
                // Camera space, looking down −Z: z = −1 makes the ray parameter the planar depth.
                let d = Vec3::new((sx as f32 + 0.5 - cx) / fx, -(sy as f32 + 0.5 - cy) / fy, -1.0);
                inv.push((rot * d).recip());
            }
        }
        Rays { inv }
    }

    /// Where sample `i`'s ray enters the cube (centre `c` relative to the eye, half edge `h`): planar depth and
    /// the entered face's normal; `None` on a miss.
    #[inline]
    pub fn hit(&self, i: usize, c: Vec3, h: f32) -> Option<(f32, Vec3)> {
        let inv = self.inv[i];
        let t1 = (c - Vec3::splat(h)) * inv;
        let t2 = (c + Vec3::splat(h)) * inv;
        let (lo, hi) = (t1.min(t2), t1.max(t2));
        let enter = lo.max_element();
        if enter > hi.min_element() {
            return None;
        }
        // The entered face is on the axis that entered last, facing against the ray.
        let n = if enter == lo.x {
            Vec3::new(-inv.x.signum(), 0.0, 0.0)
        } else if enter == lo.y {
            Vec3::new(0.0, -inv.y.signum(), 0.0)
        } else {
            Vec3::new(0.0, 0.0, -inv.z.signum())
        };
        Some((enter, n))
    }
}
