//! Point splats: screen-aligned squares and disks (one depth per splat), true 3D cubes, drawn by intersecting
//! each covered sample's ray with the box (exact silhouette, depth and face per sample, no triangles), and
//! surfels: disks in the plane of the point's normal, drawn the same way (exact ellipse and depth).
//!
//! An 800k-point frame is dominated by per-point overhead and cache misses, so:
//! - a splat is a small record carrying what drawing needs; colour, normal and object are read from its
//!   primitive only for the samples that end up showing it. Most splats of a dense cloud are `Flat` (one depth
//!   over a square, 24 bytes); only cubes and surfels drawn at their own size are `Solid` (ray-tested);
//! - points are projected four at a time where the shape allows (squares, disks, cubes: `lanes`, SSE2), with the
//!   same bits as one at a time (`project`);
//! - binning happens inside the parallel setup: each chunk of points sorts its splats by band of tile rows (a
//!   counting sort into a few sequential streams);
//! - a band's splats are drawn on their own into a [`Layer`] (nearest splat per sample, first in scene order among
//!   equals, as one integer `key` per sample), which each tile then merges behind its triangles: the same result
//!   as drawing the splats after the triangles, since "first nearest" of a sequence is the first nearest of its
//!   head and of the rest. A sample keeps the smallest key and keys are unique, so the layer does not depend on
//!   the order splats are drawn in: not on the thread count, nor on flat and solid splats being drawn apart;
//! - a tile asks for the colours of all the points it will show before reading any ([`Splats::prefetch`]): a
//!   cloud's points land on the image in no spatial order, and those reads are the merge's cache misses.
//!
//! (Measured and dropped: drawing each point straight into a private frame-sized layer per worker, merged by
//! the keys' minimum, with no binning at all. It was 15–20 % faster for sub-pixel splats but 15–25 % slower for
//! cubes of a few pixels, whose rows miss the cache where a band's layer stays in L2.)

use glam::{Vec3, Vec4};
use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
mod lanes;
mod layer;
mod rays;

use layer::key;
pub use layer::Layer;
use rays::Rays;

use super::bin::Binned;
use super::raster::{snap, Projection, SUBPIXEL};
use crate::scene::{PosedPrimitive, PosedScene, PrimKind};

/// Splat shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// A 3D cube centred on the point.
    Cube,
    /// A screen-aligned square.
    Square,
    /// A screen-aligned disk.
    Disk,
    /// A disk in the plane perpendicular to the point's normal (facing the camera where the cloud has none).
    Surfel,
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
    /// The smallest footprint on screen, in pixels (edge or diameter): a splat that would be smaller is drawn
    /// as a screen-aligned square (disk) of this size, so that points cannot fall between sample positions and
    /// leave holes. A sub-pixel cube is such a square at its near depth, showing the face turned most towards
    /// the camera. 0 draws every splat at its true size.
    pub min_px: f32,
}

impl Default for SplatSettings {
    fn default() -> Self {
        SplatSettings { shape: Shape::Square, size: Size::Pixels(1.0), min_px: 1.0 }
    }
}

/// A splat of one depth over a screen-aligned square (or disk) of samples, in fixed-point sample coordinates:
/// squares and disks, and cubes and surfels below the minimum footprint. The common splat of a dense cloud, so it
/// is kept small (24 bytes): setup writes it, binning copies it and a band reads it, once per point per image.
#[derive(Debug, Clone, Copy, Default)]
struct Flat {
    x: i32,
    y: i32,
    /// Half width and height.
    r: i32,
    /// [`WHOLE`] for a square or disk drawn at its own size; [`CLAMPED`] for one drawn as a square of the minimum
    /// footprint (and a small surfel); for a cube below it, the face it shows (an index into [`FACES`]).
    small: u8,
    /// Depth and point as one [`key`].
    key: u64,
}

/// A cube or surfel drawn at its own size, by a ray test per covered sample: centre, half width and height of its
/// screen box (fixed point), the nearest depth any of its samples can have (the near side of its view-space
/// bounding box, which lets a sample already holding something nearer skip the ray test), and its point.
#[derive(Debug, Clone, Copy, Default)]
struct Solid {
    x: i32,
    y: i32,
    rx: i32,
    ry: i32,
    z: f32,
    /// The point's index over the scene's point primitives, in order.
    point: u32,
    /// The centre relative to the eye: carried here, since reading it back from the positions misses the cache
    /// once per splat when a cloud's order is not spatial.
    centre: Vec3,
}

/// What [`project`] makes of a point.
#[derive(Debug)]
enum Projected {
    Flat(Flat),
    Solid(Solid),
}

/// [`Flat::small`] of a square or disk drawn at its own size.
const WHOLE: u8 = u8::MAX;
/// [`Flat::small`] of a square or disk drawn as a square of the minimum footprint.
const CLAMPED: u8 = u8::MAX - 1;

/// One point primitive, as splats read it.
#[derive(Debug)]
struct Source<'a> {
    /// Index of its first point over all point primitives.
    first: u32,
    prim: &'a PosedPrimitive,
    /// The material's base colour (points are unlit: colour = base × COLOR_0).
    base: Vec4,
}

/// Every splat of a frame, binned by band, and what they point at.
#[derive(Debug)]
pub struct Splats<'a> {
    sources: Vec<Source<'a>>,
    /// Each setup chunk's flat splats, binned by band.
    flat: Vec<Binned<Flat>>,
    /// Each setup chunk's solid splats, binned by band.
    solid: Vec<Binned<Solid>>,
    /// Half the edge of a cube splat, or the radius of a surfel (`None`: squares or disks).
    cube: Option<f32>,
    /// The solid splats are surfels, not cubes.
    surfel: bool,
    disk: bool,
    /// Sample rows per band.
    band_rows: i64,
}

/// Points per setup task.
const SETUP_CHUNK: usize = 16384;

/// What [`project`] needs of the settings: the cube's half edge (or none) and the half extents of its view-space
/// bounding box, the size, samples per pixel side, the eye.
struct Footprint {
    cube: Option<f32>,
    surfel: bool,
    extent: Vec3,
    size: Size,
    /// Half the minimum footprint, in samples.
    min_half: f32,
    k: f32,
    /// The eye in world space (cube centres are taken relative to it).
    eye: Vec3,
}

impl Footprint {
    /// What drawing splats of `s` under `p` at `k` samples per pixel side takes.
    fn new(p: &Projection, s: &SplatSettings, k: f32) -> Footprint {
        let [fx, ..] = p.f;
        // Half the edge of a cube; a pixel size is taken at unit distance.
        let half = |size: Size| {
            0.5 * match size {
                Size::World(w) => w,
                Size::Pixels(px) => px * k / fx,
            }
        };
        let cube = matches!(s.shape, Shape::Cube | Shape::Surfel).then(|| half(s.size));
        let surfel = s.shape == Shape::Surfel;
        // A world-axis-aligned cube of half edge h spans h·Σⱼ|Rᵢⱼ| along view axis i (R: the view rotation), a box
        // much tighter than the circumscribed sphere; widened by a hair so that rounding never trims a sample.
        let rot = glam::Mat3::from_mat4(p.w2c).transpose();
        let extent = [rot.x_axis, rot.y_axis, rot.z_axis].map(|row| row.abs().element_sum());
        // A surfel of radius r lies in its bounding sphere: r along every view axis.
        let extent = if surfel { Vec3::ONE } else { Vec3::from(extent) };
        let extent = extent * cube.unwrap_or(0.0) * (1.0 + 1e-4);
        let eye = p.w2c.inverse().w_axis.truncate();
        Footprint { cube, surfel, extent, size: s.size, min_half: 0.5 * s.min_px.max(0.0) * k, k, eye }
    }
}

/// Projects every point of the scene's point primitives and bins the splats by band of `band_rows` sample rows.
pub fn setup<'a>(scene: &'a PosedScene, p: &Projection, s: &SplatSettings, k: f32, band_rows: i64) -> Splats<'a> {
    let foot = Footprint::new(p, s, k);
    let mut out = Splats {
        sources: Vec::new(),
        flat: Vec::new(),
        solid: Vec::new(),
        cube: foot.cube,
        surfel: foot.surfel,
        disk: s.shape == Shape::Disk,
        band_rows,
    };
    #[cfg(target_arch = "x86_64")]
    let lanes = lanes::Lanes::new(p, &foot);
    let bands = ((p.size.1 + band_rows - 1) / band_rows) as usize;
    let mut first = 0u32;
    let size = p.size;
    // Each sample row's band, looked up (dividing, twice per splat in each of the sort's passes, was a tenth of
    // the setup), once per splat, from the rows that made it visible.
    let band_of: Vec<u32> = (0..size.1).map(|y| (y / band_rows) as u32).collect();
    // Gaussians are drawn as splatting draws them (`render::gaussians`), not as points.
    for prim in scene.primitives.iter().filter(|q| q.kind == PrimKind::Points && q.gaussians.is_none()) {
        let base = scene.materials.get(prim.material as usize).map_or(Vec4::ONE, |m| m.base_color);
        out.sources.push(Source { first, prim, base });
        let bins: Vec<(Binned<Flat>, Binned<Solid>)> = prim
            .positions
            .par_chunks(SETUP_CHUNK)
            .enumerate()
            .map_init(
                || (Vec::new(), Vec::new()),
                |(flat, solid), (c, chunk)| {
                    flat.clear();
                    solid.clear();
                    let offset = first + (c * SETUP_CHUNK) as u32;
                    // Only a surfel reads its normal here (its tilt): a cloud's normals are as large as its
                    // positions.
                    let normals =
                        if foot.surfel { prim.normals.get(c * SETUP_CHUNK..).unwrap_or_default() } else { &[] };
                    let mut sink = Sink { flat, solid, band_of: &band_of };
                    // Four at a time where the lanes draw the shape, the rest one by one.
                    let mut done = 0;
                    #[cfg(target_arch = "x86_64")]
                    if let Some(lanes) = &lanes {
                        let fours = chunk.chunks_exact(4);
                        done = chunk.len() - fours.remainder().len();
                        for (q, four) in fours.enumerate() {
                            let four = four.try_into().expect("BUG: chunks of four");
                            lanes.project4(four, offset + 4 * q as u32, p, &foot, &mut sink);
                        }
                    }
                    for (j, pos) in chunk.iter().enumerate().skip(done) {
                        let normal = normals.get(j).copied().unwrap_or(Vec3::ZERO);
                        sink.push(project(*pos, normal, p, &foot, offset + j as u32));
                    }
                    // A splat overlapping two bands is in each.
                    (
                        Binned::sort(flat, 1, bands, band_cells, |_, (sp, _)| *sp),
                        Binned::sort(solid, 1, bands, band_cells, |_, (sp, _)| *sp),
                    )
                },
            )
            .collect();
        let (flat, solid): (Vec<_>, Vec<_>) = bins.into_iter().unzip();
        out.flat.extend(flat);
        out.solid.extend(solid);
        first += prim.positions.len() as u32;
    }
    out
}

/// A setup task's splats, each with its first and last band, found once from the rows that made it visible (the
/// sort reads them twice).
struct Sink<'a> {
    flat: &'a mut Vec<(Flat, [u32; 2])>,
    solid: &'a mut Vec<(Solid, [u32; 2])>,
    /// Each sample row's band.
    band_of: &'a [u32],
}

impl Sink<'_> {
    /// The bands of sample rows `y0` to `y1`.
    #[inline]
    fn bands(&self, [y0, y1]: [i64; 2]) -> [u32; 2] {
        [self.band_of[y0 as usize], self.band_of[y1 as usize]]
    }

    #[inline]
    fn flat(&mut self, sp: Flat, rows: [i64; 2]) {
        let bands = self.bands(rows);
        self.flat.push((sp, bands));
    }

    #[inline]
    fn solid(&mut self, sp: Solid, rows: [i64; 2]) {
        let bands = self.bands(rows);
        self.solid.push((sp, bands));
    }

    /// What [`project`] made of a point.
    #[inline]
    fn push(&mut self, splat: Option<(Projected, [i64; 2])>) {
        match splat {
            Some((Projected::Flat(sp), rows)) => self.flat(sp, rows),
            Some((Projected::Solid(sp), rows)) => self.solid(sp, rows),
            None => {}
        }
    }
}

/// The cells (a column of bands) of a splat binned with its first and last band.
fn band_cells<T>((_, [first, last]): &(T, [u32; 2])) -> [usize; 4] {
    [0, *first as usize, 0, *last as usize]
}

/// The splat of point `point` at world `pos` and its first and last sample row, or `None` when it is clipped or
/// falls outside the image.
#[inline]
fn project(pos: Vec3, normal: Vec3, p: &Projection, s: &Footprint, point: u32) -> Option<(Projected, [i64; 2])> {
    let [fx, fy, cx, cy] = p.f;
    let lim = (p.size.0.max(p.size.1) + 2) as f32;
    let v = p.w2c.transform_point3(pos);
    let z = -v.z;
    if !(z >= p.near && z <= p.far) {
        return None;
    }
    let iz = 1.0 / z;
    let fixed = |v: f32| snap(v.clamp(-lim, lim) as f64) as i32;
    match (s.cube, s.size) {
        (Some(h), _) => {
            // The near plane would cut the cube: drop it (cubes are voxel-sized).
            if z - h * 3f32.sqrt() < p.near {
                return None;
            }
            // The screen box of the view-space box: each side's extreme ratio X / depth is at the box's nearer
            // or farther depth, by the sign of X.
            let e = s.extent;
            let (near_z, far_z) = (z - e.z, z + e.z);
            let ratio = |lo: f32, hi: f32| {
                (lo / if lo >= 0.0 { far_z } else { near_z }, hi / if hi >= 0.0 { near_z } else { far_z })
            };
            let (x0, x1) = ratio(v.x - e.x, v.x + e.x);
            let (y0, y1) = ratio(v.y - e.y, v.y + e.y);
            let (sx0, sx1) = (cx + fx * x0, cx + fx * x1);
            let (sy0, sy1) = (cy - fy * y1, cy - fy * y0);
            let (x, y) = (fixed((sx0 + sx1) / 2.0), fixed((sy0 + sy1) / 2.0));
            let centre = pos - s.eye;
            let (wx, wy) = ((sx1 - sx0) / 2.0, (sy1 - sy0) / 2.0);
            // The silhouette holds the inscribed sphere's disk, of radius h·f/z samples; no point is farther
            // than √2/2 samples from a sample centre of its own pixel. A cube whose disk is smaller than that
            // (or than the minimum footprint) can let its pixel's samples miss it.
            // A surfel's narrowest screen extent shrinks with the cosine of its tilt from the view ray.
            let tilt = if s.surfel && normal != Vec3::ZERO {
                normal.normalize().dot(centre.normalize_or_zero()).abs()
            } else {
                1.0
            };
            if s.min_half > 0.0 && h * fx * iz * tilt < s.min_half.max(std::f32::consts::FRAC_1_SQRT_2) {
                // A square of its screen box (at least the minimum) at the cube's near depth, showing the face
                // turned most towards the eye (against `centre`, which points from the eye).
                let axis = centre.abs().max_position();
                let face = if s.surfel { CLAMPED } else { 2 * axis as u8 + (centre[axis] < 0.0) as u8 };
                // One fixed-point unit more, so that a centre on a pixel border still covers its own pixel.
                // (A surfel's square is as wide as its ellipse's minor axis; a cube's as its screen box.)
                let width = if s.surfel { h * fx * iz * tilt } else { wx.min(wy) };
                let r = fixed(s.min_half.max(width)) + 1;
                return Flat { x, y, r, small: face, key: key(near_z, point) }.visible(p.size);
            }
            // One fixed-point unit more on each side, for the rounding of centre and half size.
            let (rx, ry) = (fixed(wx) + 1, fixed(wy) + 1);
            Solid { x, y, rx, ry, z: near_z, point, centre }.visible(p.size)
        }
        (None, size) => {
            let half = match size {
                Size::World(w) => 0.5 * w * fx * iz,
                Size::Pixels(px) => 0.5 * px * s.k,
            };
            // At the minimum: a square (a disk that small can miss its own pixel's only sample), one fixed-point
            // unit wider, as for small cubes.
            let clamped = half < s.min_half;
            let r = if clamped { fixed(s.min_half) + 1 } else { fixed(half.min(lim)) };
            let (x, y) = (fixed(cx + fx * v.x * iz), fixed(cy - fy * v.y * iz));
            Flat { x, y, r, small: if clamped { CLAMPED } else { WHOLE }, key: key(z, point) }.visible(p.size)
        }
    }
}

impl Flat {
    /// Whether the sample centre (fixed point) is inside the splat as a disk (a square covers its bounding box).
    #[inline]
    fn disk_covers(&self, px: i64, py: i64) -> bool {
        let (dx, dy, r) = (px - self.x as i64, py - self.y as i64, self.r as i64);
        dx * dx + dy * dy < r * r
    }
}

/// A splat's screen box: centre and half extents in fixed point, and what follows from them.
trait ScreenBox: Copy {
    /// Centre x and y, half width and height.
    fn half_box(&self) -> [i32; 4];

    /// What [`project`] makes of it.
    fn projected(self) -> Projected;

    /// The samples it may cover ([`bbox`]).
    #[inline]
    fn bbox(&self, size: (i64, i64)) -> [i64; 4] {
        let [x, y, rx, ry] = self.half_box();
        bbox(x, y, rx, ry, size)
    }

    /// The splat and its first and last sample row, when its box holds a sample of the `size` sample grid.
    #[inline]
    fn visible(self, size: (i64, i64)) -> Option<(Projected, [i64; 2])> {
        let b = self.bbox(size);
        (self.half_box()[2] > 0 && b[0] <= b[2] && b[1] <= b[3]).then(|| (self.projected(), [b[1], b[3]]))
    }
}

impl ScreenBox for Flat {
    #[inline]
    fn half_box(&self) -> [i32; 4] {
        [self.x, self.y, self.r, self.r]
    }

    #[inline]
    fn projected(self) -> Projected {
        Projected::Flat(self)
    }
}

impl ScreenBox for Solid {
    #[inline]
    fn half_box(&self) -> [i32; 4] {
        [self.x, self.y, self.rx, self.ry]
    }

    #[inline]
    fn projected(self) -> Projected {
        Projected::Solid(self)
    }
}

/// Inclusive bounding box, within a `size` sample grid, of the samples whose centres lie in
/// [x − rx, x + rx) × [y − ry, y + ry) (fixed point): exactly a square's samples (half-open, so that squares one
/// size apart tile without double hits), and those a disk or a solid may cover (empty when min > max).
#[inline]
fn bbox(x: i32, y: i32, rx: i32, ry: i32, size: (i64, i64)) -> [i64; 4] {
    let (x, y, rx, ry) = (x as i64, y as i64, rx as i64, ry as i64);
    // Sample s has its centre at s·S + S/2: the first centre ≥ a and the last centre < b. (An arithmetic shift
    // is the floor of a division by S, as `div_euclid` is, in one instruction; this runs several times per splat.)
    const _: () = assert!(1 << SUBPIXEL_BITS == SUBPIXEL);
    let first = |a: i64| -((SUBPIXEL / 2 - a) >> SUBPIXEL_BITS);
    let last = |b: i64| (b - 1 - SUBPIXEL / 2) >> SUBPIXEL_BITS;
    [first(x - rx).max(0), first(y - ry).max(0), last(x + rx).min(size.0 - 1), last(y + ry).min(size.1 - 1)]
}

/// log₂ [`SUBPIXEL`].
const SUBPIXEL_BITS: u32 = SUBPIXEL.trailing_zeros();

impl<'a> Splats<'a> {
    /// Band `b`'s flat splats.
    fn flat(&self, b: usize) -> impl Iterator<Item = &Flat> {
        self.flat.iter().flat_map(move |bin| bin.cell(b))
    }

    /// Band `b`'s solid splats.
    fn solid(&self, b: usize) -> impl Iterator<Item = &Solid> {
        self.solid.iter().flat_map(move |bin| bin.cell(b))
    }

    /// The primitive and index within it of point `i`.
    #[inline]
    fn source(&self, i: u32) -> (&Source<'a>, usize) {
        let s = match self.sources.len() {
            1 => &self.sources[0],
            _ => &self.sources[self.sources.partition_point(|s| s.first <= i) - 1],
        };
        (s, (i - s.first) as usize)
    }

    /// Linear colour (base × COLOR_0), world normal and object id that sample `j` of `layer` shows (the cube face's
    /// normal, or the point's own for squares and disks, zero when unknown).
    #[inline]
    pub fn attributes(&self, layer: &Layer, j: usize) -> (Vec4, Vec3, u32) {
        let (s, i) = self.source(layer.point(j));
        let color = s.base * s.prim.colors.get(i).copied().unwrap_or(Vec4::ONE);
        let normal = match FACES.get(layer.face[j] as usize) {
            Some(face) if self.face_normals() => *face,
            _ => s.prim.normals.get(i).copied().unwrap_or(Vec3::ZERO),
        };
        (color, normal, s.prim.object)
    }

    /// Whether a shown sample's normal is its cube face's rather than its point's.
    #[inline]
    fn face_normals(&self) -> bool {
        self.cube.is_some() && !self.surfel
    }

    /// The unit normal of point `i`, when it has one.
    #[inline]
    fn normal_of(&self, i: u32) -> Option<Vec3> {
        let (s, i) = self.source(i);
        s.prim.normals.get(i).and_then(|n| n.try_normalize())
    }

    /// Draws band `band` (sample rows from `band · band_rows`) into `layer`: per sample, the nearest splat and its
    /// depth, the first in scene order among equals. Returns whether any sample was written.
    pub fn draw_band(&self, band: usize, p: &Projection, layer: &mut Layer) -> bool {
        let (mut solid, mut flat) = (self.solid(band).peekable(), self.flat(band).peekable());
        if solid.peek().is_none() && flat.peek().is_none() {
            return false;
        }
        let y0 = band as i64 * self.band_rows;
        let (w, h) = (p.size.0, self.band_rows.min(p.size.1 - y0));
        layer.reset(y0, w, h);
        let mut any = false;
        // Keys are unique (a point is drawn once per sample) and a sample keeps the smallest, so the order in which
        // splats are drawn, solid or flat, does not change the layer.
        if let (Some(half), Some(_)) = (self.cube, solid.peek()) {
            let rays = Rays::new(p, 0, y0, w, h);
            for sp in solid {
                let b = sp.bbox(p.size);
                let (by0, by1) = (b[1].max(y0), b[3].min(y0 + h - 1));
                // A surfel's plane; without a normal, it faces the eye.
                let n = if self.surfel { self.normal_of(sp.point).unwrap_or(sp.centre) } else { Vec3::ZERO };
                let nearest = key(sp.z, sp.point);
                for sy in by0..by1 + 1 {
                    for sx in b[0]..b[2] + 1 {
                        let i = ((sy - y0) * w + sx) as usize;
                        // No part of the cube is nearer than `sp.z`: a sample already holding something at
                        // least that near cannot change (dense clouds overdraw many times), so skip its ray test.
                        if nearest >= layer.key[i] {
                            continue;
                        }
                        let hit = if self.surfel {
                            rays.disk_hit(i, sp.centre, n, half).map(|z| (z, CLAMPED))
                        } else {
                            rays.hit(i, sp.centre, half)
                        };
                        if let Some((z, face)) = hit {
                            if z >= p.near && z <= p.far && key(z, sp.point) < layer.key[i] {
                                (layer.key[i], layer.face[i]) = (key(z, sp.point), face);
                                any = true;
                            }
                        }
                    }
                }
            }
        }
        // Squares and disks, and splats below the minimum footprint (squares; cubes showing one face). The
        // bounding box is exactly a square's samples; a disk tests each.
        for sp in flat {
            let b = sp.bbox(p.size);
            let (by0, by1) = (b[1].max(y0), b[3].min(y0 + h - 1));
            let disk = self.disk && sp.small == WHOLE;
            for sy in by0..by1 + 1 {
                let row = ((sy - y0) * w) as usize;
                for sx in b[0]..b[2] + 1 {
                    let i = row + sx as usize;
                    if disk && !sp.disk_covers(sx * SUBPIXEL + SUBPIXEL / 2, sy * SUBPIXEL + SUBPIXEL / 2) {
                        continue;
                    }
                    if sp.key < layer.key[i] {
                        (layer.key[i], layer.face[i]) = (sp.key, sp.small);
                        any = true;
                    }
                }
            }
        }
        any
    }

    /// Asks the memory system for the colour (and normal) [`Splats::attributes`] will read for sample `j` of
    /// `layer`. A dense cloud's points land on samples in no spatial order, so those reads miss the cache one
    /// after another; issued ahead for a whole tile, the misses overlap.
    #[inline]
    pub fn prefetch(&self, layer: &Layer, j: usize) {
        let (s, i) = self.source(layer.point(j));
        prefetch(s.prim.colors.get(i));
        if !self.face_normals() {
            prefetch(s.prim.normals.get(i));
        }
    }
}

/// A hint that `v` will be read soon (nothing where there is no such instruction).
#[inline]
fn prefetch<T>(v: Option<&T>) {
    #[cfg(target_arch = "x86_64")]
    if let Some(v) = v {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: SSE is part of x86-64's baseline, and a prefetch never faults (the address is a live reference
        // anyway).
        unsafe { _mm_prefetch::<_MM_HINT_T0>((v as *const T).cast()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v;
}

/// Cube face normals: −x, +x, −y, +y, −z, +z.
const FACES: [Vec3; 6] = [Vec3::NEG_X, Vec3::X, Vec3::NEG_Y, Vec3::Y, Vec3::NEG_Z, Vec3::Z];
