//! A ground plane's light on a grid ([`PlaneVisibility`]): the environment's visibility, the suns' shadows and
//! the lamps' light sampled at [`PLANE_CELLS`]² cells over the plane, summed per grid point once a frame and read
//! bilinearly by every pixel that sees the plane; the summed-area tables that average it over a glossy lobe's
//! footprint ([`super::ground`] lights the plane with it and bounces its light onto the subject).

use glam::{Vec2, Vec3};

use super::penumbra::SunShade;
use super::{Light, LightKind};

/// Cells along each side of a ground plane's grids: about 3 cm on a 4 m plane, fine enough for a subject's
/// contact shadow to show.
pub(super) const PLANE_CELLS: usize = 128;

/// A ground plane's light, sampled on a grid of [`PLANE_CELLS`]² cells over its extent and read bilinearly:
/// the environment's visibility and the suns'. A plane's vertices are only its corners, so it cannot carry its
/// occlusion per vertex as other surfaces do; a grid costs the same to prepare as a finely tessellated plane did
/// and nothing to rasterize.
#[derive(Debug)]
pub(super) struct PlaneVisibility {
    /// The plane's material (only a plane source's triangles cast no shadow, and each has its own material).
    pub(super) material: u32,
    /// Corner of the grid (x, y) and the size of one cell.
    pub(super) lo: Vec2,
    pub(super) cell: Vec2,
    /// What costs rays and shadow lookups to find: the grids (see [`PlaneGrids`]).
    pub(super) grids: PlaneGrids,
    /// Summed-area tables of `vis` and `sun` ((PLANE_CELLS + 2)² entries, rows along +y; entry (i, j) sums the
    /// grid points below and left of it), for averages over a footprint.
    pub(super) sums: Vec<[f64; 2]>,
    /// The same of `lamps` (point and spot lights' irradiance), per channel; empty without such lights.
    pub(super) lamp_sums: Vec<[f64; 3]>,
    /// The environment's irradiance on the plane's top face (before its visibility): the same everywhere on it.
    pub(super) sky: Vec3,
    /// Per light, per cell (rows along +y): whether the light's shadow surely misses the whole cell
    /// ([`super::ShadowMap::open_over`]), so its pixels need no shadow lookup. Empty for a light that cannot tell.
    pub(super) open: Vec<Vec<bool>>,
    /// The top face's irradiance from the environment, the subject's bounce and every sun unshadowed, at the
    /// grid points: all a pixel in a cell where no sun's shadow reaches reads (see [`PlaneVisibility::combine`]).
    pub(super) lit: Vec<Vec3>,
    /// The same without the suns: a pixel in a cell some sun's shadow may reach adds each sun's light past its
    /// shadow to it.
    pub(super) unsunned: Vec<Vec3>,
    /// Per cell: whether no sun's shadow reaches it (every sun is open there, or casts no shadow).
    pub(super) sunlit: Vec<bool>,
}

/// A ground plane's grids that cost rays and shadow lookups to find: what a frame's light action keeps of a plane.
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct PlaneGrids {
    /// The environment's visibility at (PLANE_CELLS + 1)² grid points, rows along +y.
    pub(super) vis: Vec<f32>,
    /// The suns' visibility at the same points, each sun weighted by the irradiance it brings the plane (what
    /// its bounce carries of their shadows). Empty when no sun lights the plane.
    pub(super) sun: Vec<f32>,
    /// The irradiance point and spot lights bring the same points, with their shadows (suns are in `sun`):
    /// what their bounce off the ground carries. Empty without such lights.
    pub(super) lamps: Vec<Vec3>,
    /// The irradiance the subject reflects onto the same points ([`super::bounce::Subject::onto`]). Empty until
    /// the subject's own bounce is known, and without a subject.
    pub(super) bounce: Vec<Vec3>,
    /// Per light (in the frame's order), its shadow sampled where it may fall on the plane: a sun's, once per
    /// frame for all its views ([`SunShade`]); empty for other lights, which pixels look up themselves.
    pub(super) shades: Vec<SunShade>,
}

/// Where a point falls on a plane's grid: its cell (column, row) and the fractions across it.
#[derive(Clone, Copy)]
pub(super) struct GridPoint {
    pub(super) i: usize,
    pub(super) j: usize,
    pub(super) t: Vec2,
}

impl PlaneVisibility {
    /// The environment's visibility at world (x, y), bilinear between grid points, held at the edges.
    #[inline]
    pub(super) fn at(&self, x: f32, y: f32) -> f32 {
        read(&self.grids.vis, locate(self.grid_uv(x, y)))
    }

    /// The plane's light at world (x, y) as fractions of the open plane's (environment, suns) and the
    /// irradiance of its point and spot lights, or `None` past its edges.
    #[inline]
    pub(super) fn light_at(&self, x: f32, y: f32) -> Option<(Vec2, Vec3)> {
        let uv = self.grid_uv(x, y);
        let n = PLANE_CELLS as f32;
        if !(0.0..=n).contains(&uv.x) || !(0.0..=n).contains(&uv.y) {
            return None;
        }
        let g = locate(uv);
        let fractions =
            Vec2::new(read(&self.grids.vis, g), if self.grids.sun.is_empty() { 1.0 } else { read(&self.grids.sun, g) });
        Some((fractions, read3(&self.grids.lamps, g)))
    }

    /// The irradiance the subject reflects onto world (x, y), bilinear between grid points, held at the edges.
    #[inline]
    pub(super) fn bounce_at(&self, x: f32, y: f32) -> Vec3 {
        read3(&self.grids.bounce, locate(self.grid_uv(x, y)))
    }

    /// Every `stride`-th of the grid's points along each axis, in row order (rows along +y), on the plane.
    pub(super) fn points(&self, z: f32, stride: usize) -> Vec<Vec3> {
        let n = PLANE_CELLS / stride + 1;
        (0..n * n)
            .map(|k| {
                let (i, j) = ((k % n) * stride, (k / n) * stride);
                Vec3::new(self.lo.x + self.cell.x * i as f32, self.lo.y + self.cell.y * j as f32, z)
            })
            .collect()
    }

    /// The plane's light averaged over the square of half-side `w` (world units, at least half a cell) about
    /// world (x, y): as fractions of the open plane's (environment, suns), the irradiance of its point and spot
    /// lights, and the fraction of the square on the plane; `None` when none of it is.
    pub(super) fn light_over(&self, x: f32, y: f32, w: f32) -> Option<(Vec2, Vec3, f32)> {
        let n = PLANE_CELLS as f64;
        // In grid units, where grid point k stands for the span [k − ½, k + ½]; the box is cut to the plane.
        let uv = self.grid_uv(x, y);
        let (u, v) = (uv.x as f64, uv.y as f64);
        let (wu, wv) = ((w / self.cell.x).max(0.5) as f64, (w / self.cell.y).max(0.5) as f64);
        let (u0, u1) = ((u - wu).max(0.0), (u + wu).min(n));
        let (v0, v1) = ((v - wv).max(0.0), (v + wv).min(n));
        if u1 <= u0 || v1 <= v0 {
            return None;
        }
        let on = ((u1 - u0) * (v1 - v0) / (4.0 * wu * wv)) as f32;
        let area = (u1 - u0) * (v1 - v0);
        // The box's sum from a table's four corners, over its area.
        fn mean<const N: usize>(t: &[[f64; N]], [u0, v0, u1, v1]: [f64; 4], area: f64) -> [f64; N] {
            let at = |u: f64, v: f64| sum_at(t, u + 0.5, v + 0.5);
            let (a, b, c, d) = (at(u1, v1), at(u0, v1), at(u1, v0), at(u0, v0));
            std::array::from_fn(|k| (a[k] - b[k] - c[k] + d[k]) / area)
        }
        let corners = [u0, v0, u1, v1];
        // (An empty sun grid was summed as all ones.)
        let light = mean(&self.sums, corners, area).map(|f| f.clamp(0.0, 1.0) as f32);
        let lamps = if self.lamp_sums.is_empty() {
            Vec3::ZERO
        } else {
            let e = mean(&self.lamp_sums, corners, area).map(|e| e.max(0.0) as f32);
            Vec3::from_array(e)
        };
        Some((Vec2::new(light[0], light[1]), lamps, on))
    }

    /// World (x, y) in grid units: grid point (i, j) is at (i, j).
    #[inline]
    pub(super) fn grid_uv(&self, x: f32, y: f32) -> Vec2 {
        Vec2::new((x - self.lo.x) / self.cell.x, (y - self.lo.y) / self.cell.y)
    }

    /// Sums the top face's light, per grid point, into what its pixels read ([`PlaneVisibility::lit`],
    /// [`PlaneVisibility::unsunned`], [`PlaneVisibility::sunlit`]), under `lights`: once the bounce is known.
    /// A sum of grids read bilinearly is the bilinear read of their sum, so a pixel makes one read instead of
    /// one per grid (the ground is most of an image's pixels, and its reads were a tenth of a lit render).
    pub(super) fn combine(&mut self, lights: &[super::Lamp]) {
        let n = (PLANE_CELLS + 1) * (PLANE_CELLS + 1);
        let suns: Vec3 = lights.iter().map(|lamp| sun_irradiance(&lamp.light)).sum();
        self.unsunned = (0..n)
            .map(|k| self.sky * self.grids.vis[k] + self.grids.bounce.get(k).copied().unwrap_or(Vec3::ZERO))
            .collect();
        self.lit = self.unsunned.iter().map(|&e| e + suns).collect();
        let shadowing: Vec<&Vec<bool>> = lights
            .iter()
            .zip(&self.open)
            .filter(|(lamp, _)| sun_irradiance(&lamp.light) != Vec3::ZERO && !lamp.maps.is_empty())
            .map(|(_, open)| open)
            .collect();
        self.sunlit =
            (0..PLANE_CELLS * PLANE_CELLS).map(|c| shadowing.iter().all(|open| open.get(c) == Some(&true))).collect();
    }
}

/// The grid point at `uv` (grid units), held at the grid's edges.
#[inline]
pub(super) fn locate(uv: Vec2) -> GridPoint {
    let n = PLANE_CELLS;
    let (u, v) = (uv.x.clamp(0.0, n as f32), uv.y.clamp(0.0, n as f32));
    // Through i32: both lie in 0..=n, and x86-64 converts to i32 in one instruction (to usize it cannot).
    let (i, j) = ((u as i32 as usize).min(n - 1), (v as i32 as usize).min(n - 1));
    GridPoint { i, j, t: Vec2::new(u - i as f32, v - j as f32) }
}

/// Grid `g` of colours ((PLANE_CELLS + 1)² points) read bilinearly at `at`; zero when it is empty.
#[inline]
pub(super) fn read3(g: &[Vec3], at: GridPoint) -> Vec3 {
    let n = PLANE_CELLS + 1;
    if g.len() < n * n {
        return Vec3::ZERO;
    }
    // In SIMD lanes: the same products and sums per channel, so the same bits.
    let row = |j: usize| glam::Vec3A::from(g[j * n + at.i]).lerp(g[j * n + at.i + 1].into(), at.t.x);
    row(at.j).lerp(row(at.j + 1), at.t.y).into()
}

/// Points in a plane's grids.
pub(super) const GRID_POINTS: usize = (PLANE_CELLS + 1) * (PLANE_CELLS + 1);

/// The stride at which the subject's bounce onto a ground is gathered ([`spread`]).
pub(super) const BOUNCE_STRIDE: usize = 4;

/// A coarse grid `c` of every `stride`-th grid point (as [`PlaneVisibility::points`] lists them) spread to the
/// whole grid, bilinearly.
pub(super) fn spread(c: &[Vec3], stride: usize) -> Vec<Vec3> {
    let (n, m) = (PLANE_CELLS + 1, PLANE_CELLS / stride + 1);
    (0..n * n)
        .map(|k| {
            let (u, v) = ((k % n) as f32 / stride as f32, (k / n) as f32 / stride as f32);
            let (i, j) = ((u as i32 as usize).min(m - 2), (v as i32 as usize).min(m - 2));
            let (tu, tv) = (u - i as f32, v - j as f32);
            let row = |j: usize| c[j * m + i].lerp(c[j * m + i + 1], tu);
            row(j).lerp(row(j + 1), tv)
        })
        .collect()
}

/// Grid `g` of colours ((PLANE_CELLS + 1)² points) blurred by a box of 2·`r` + 1 points along each axis, twice
/// (a tent about `r` points wide), held at the edges.
pub(super) fn blur(g: &[Vec3], r: usize) -> Vec<Vec3> {
    let n = PLANE_CELLS + 1;
    // One box pass along the axis whose neighbouring points lie `stride` apart in the grid (1: x, n: y).
    let pass = |g: &[Vec3], stride: usize| -> Vec<Vec3> {
        (0..n * n)
            .map(|k| {
                let along = (k / stride) % n;
                let first = k - along * stride;
                let sum: Vec3 = (0..=2 * r).map(|o| g[first + (along + o).saturating_sub(r).min(n - 1) * stride]).sum();
                sum / (2 * r + 1) as f32
            })
            .collect()
    };
    let mut g = g.to_vec();
    for _ in 0..2 {
        g = pass(&pass(&g, 1), n);
    }
    g
}

/// Summed-area table `t` ((PLANE_CELLS + 2)² entries) at (u, v) in [0, PLANE_CELLS + 1]², interpolated
/// bilinearly between entries.
fn sum_at<const N: usize>(t: &[[f64; N]], u: f64, v: f64) -> [f64; N] {
    let m = PLANE_CELLS + 2;
    // Through i32, as `locate` does: x86-64 converts an f64 to i32 in one instruction, to usize in eight.
    let (i, j) = ((u as i32 as usize).min(m - 2), (v as i32 as usize).min(m - 2));
    let (tu, tv) = (u - i as f64, v - j as f64);
    // The four entries read once (indexed per channel, their reads were a third of the ground's reflections).
    let (a, b) = (t[j * m + i], t[j * m + i + 1]);
    let (c, d) = (t[(j + 1) * m + i], t[(j + 1) * m + i + 1]);
    std::array::from_fn(|k| {
        let lo = a[k] + (b[k] - a[k]) * tu;
        let hi = c[k] + (d[k] - c[k]) * tu;
        lo + (hi - lo) * tv
    })
}

/// The summed-area table ((PLANE_CELLS + 2)² entries, rows along +y; entry (i, j) sums the grid points below and
/// left of it) of `N` grids at once, `point(k)` giving grid point k's values (row order).
pub(super) fn summed_areas<const N: usize>(point: impl Fn(usize) -> [f64; N]) -> Vec<[f64; N]> {
    let (n, m) = (PLANE_CELLS + 1, PLANE_CELLS + 2);
    let mut sums = vec![[0.0f64; N]; m * m];
    for j in 0..n {
        let mut row = [0.0f64; N];
        for i in 0..n {
            let p = point(j * n + i);
            row = std::array::from_fn(|k| row[k] + p[k]);
            let below = sums[j * m + i + 1];
            sums[(j + 1) * m + i + 1] = std::array::from_fn(|k| below[k] + row[k]);
        }
    }
    sums
}

/// Grid `g` ((PLANE_CELLS + 1)² points) read bilinearly at `at`.
#[inline]
fn read(g: &[f32], at: GridPoint) -> f32 {
    let n = PLANE_CELLS + 1;
    let row = |j: usize| {
        let a = g[j * n + at.i];
        a + (g[j * n + at.i + 1] - a) * at.t.x
    };
    let (a, b) = (row(at.j), row(at.j + 1));
    a + (b - a) * at.t.y
}

/// The irradiance light `l` brings a horizontal plane facing +Z when it is a sun, unshadowed.
pub(super) fn sun_irradiance(l: &Light) -> Vec3 {
    match l.kind {
        LightKind::Sun { direction, .. } => l.color * (l.intensity * (-direction.z).max(0.0)),
        _ => Vec3::ZERO,
    }
}
