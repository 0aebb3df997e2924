//! Shadow maps: the depth of the nearest caster seen from a light, rasterized once per posed frame (lights do
//! not move with the camera, so every view of a frame shares them), and looked up with a normal offset and a
//! slope-free constant bias measured in texels (no acne on lit faces, no gap where an object meets the
//! ground). Soft shadows filter over the penumbra a light of the given size casts (percentage-closer soft
//! shadows: a blocker search, then a filter whose width grows with the receiver's distance from the blocker).
//!
//! Transparent (`BLEND`) casters do not enter the depth map: they go to a second layer, the nearest such caster's
//! depth and the light the layers pass, `Π (1 − α)` over them (α per triangle: its material's alpha factor, times
//! the mean of its vertex colours' and base-colour texture's alpha at its corners), as Cycles' transparent
//! shadows pass `1 − α` through a glTF `BLEND` material imported by Blender. A receiver behind that caster gets
//! its visibility times the layer's transmittance (read at its texel, unfiltered). One layer per texel: a
//! receiver between two panes is dimmed by both (a closed glass object's back face by its front and itself).

use glam::{Mat4, Vec2, Vec3};

mod points;
mod raster;

pub(super) use points::bounds as point_bounds;
pub use points::PointCasters;

use super::pcf::{self, Depths, PcfAxis};
use super::pyramid;
use crate::scene::texture::floor;
use crate::scene::PosedScene;

/// How a map projects.
#[derive(Debug, Clone, Copy)]
enum Projection {
    /// Parallel rays (a sun): texels per world unit.
    Ortho { scale: f32, offset: Vec2 },
    /// Rays from a point (point and spot lights): focal length in texels.
    Persp { focal: f32 },
}

/// One shadow map.
#[derive(Debug, Clone)]
pub struct ShadowMap {
    view: Mat4,
    projection: Projection,
    size: u32,
    /// Nearest caster depth (distance along the light's axis), +∞ where nothing is.
    depth: Vec<f32>,
    /// A min pyramid of `depth`: level l (from 1) holds the nearest depth of each 2^l × 2^l block, so a soft
    /// lookup can tell in four reads that nothing in its search region is nearer than its receiver.
    mins: Vec<Vec<f32>>,
    /// The max pyramid beside it: a soft lookup inside a shadow tells in four reads that everything it would
    /// filter is nearer than its receiver.
    maxs: Vec<Vec<f32>>,
    /// Transparent casters, when there are any.
    glass: Option<Glass>,
}

/// The transparent casters' layer of a map (see the module's header).
#[derive(Debug, Clone)]
struct Glass {
    /// Nearest transparent caster's depth per texel, +∞ where there is none.
    depth: Vec<f32>,
    /// The light its layers pass, per texel (1 where there is none).
    pass: Vec<f32>,
    /// The min pyramid of `depth`, so that an open region stays a few reads.
    mins: Vec<Vec<f32>>,
}

/// Bias, in texels of world size at the receiver, along the surface normal and along the light's axis.
const NORMAL_BIAS: f32 = 1.5;
const DEPTH_BIAS: f32 = 1.5;
/// Nearest depth a perspective map records.
pub(super) const NEAR: f32 = 1e-3;

/// A light-space frame looking along `dir` (unit) from `eye`.
fn look(eye: Vec3, dir: Vec3) -> Mat4 {
    let up = if dir.z.abs() > 0.99 { Vec3::Y } else { Vec3::Z };
    let f = dir.normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    // Rows s, u, −f: camera space with −z along the light.
    Mat4::from_cols(
        glam::Vec4::new(s.x, u.x, -f.x, 0.0),
        glam::Vec4::new(s.y, u.y, -f.y, 0.0),
        glam::Vec4::new(s.z, u.z, -f.z, 0.0),
        glam::Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    )
}

impl ShadowMap {
    /// A map of parallel light travelling along `dir`, fitted around the casters' bounds `(lo, hi)`; plain
    /// points cast as `points` says.
    pub fn sun(scene: &PosedScene, dir: Vec3, bounds: (Vec3, Vec3), size: u32, points: PointCasters) -> ShadowMap {
        let (lo, hi) = bounds;
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-6);
        let view = look(centre - dir * radius * 2.0, dir);
        // A square fitted to the bounding sphere's silhouette, with a texel of margin.
        let c = view.transform_point3(centre);
        let scale = (size as f32 - 2.0) / (2.0 * radius);
        let offset = Vec2::new(c.x - radius - 1.0 / scale, c.y - radius - 1.0 / scale);
        let mut m = ShadowMap {
            view,
            projection: Projection::Ortho { scale, offset },
            size,
            depth: vec![f32::INFINITY; (size * size) as usize],
            mins: Vec::new(),
            maxs: Vec::new(),
            glass: None,
        };
        m.rasterize(scene);
        m.draw_points(scene, points);
        m.build_pyramids();
        m
    }

    /// A map of light from `eye` along `dir`, `fov` radians wide (a spot's cone, or a cube face's 90°); plain
    /// points cast as `points` says.
    pub fn perspective(
        scene: &PosedScene,
        eye: Vec3,
        dir: Vec3,
        fov: f32,
        size: u32,
        points: PointCasters,
    ) -> ShadowMap {
        let focal = 0.5 * size as f32 / (0.5 * fov.min(3.0)).tan();
        let mut m = ShadowMap {
            view: look(eye, dir),
            projection: Projection::Persp { focal },
            size,
            depth: vec![f32::INFINITY; (size * size) as usize],
            mins: Vec::new(),
            maxs: Vec::new(),
            glass: None,
        };
        m.rasterize(scene);
        m.draw_points(scene, points);
        m.build_pyramids();
        m
    }

    /// Builds [`ShadowMap::mins`] and [`ShadowMap::maxs`] (sides halving, rounded up, down to one texel).
    fn build_pyramids(&mut self) {
        (self.mins, self.maxs) = pyramid::pyramids(&self.depth, self.size as usize);
        if let Some(g) = self.glass.as_mut() {
            g.mins = pyramid::pyramids(&g.depth, self.size as usize).0;
        }
    }

    /// The light the transparent layer passes to a receiver at texel `q` (light space) and depth `recv`: its
    /// transmittance where a transparent caster lies in front of the receiver, else 1.
    fn glass_pass(&self, q: Vec3, recv: f32) -> f32 {
        let Some(g) = &self.glass else { return 1.0 };
        let (x, y) = (floor(q.x), floor(q.y));
        if x < 0 || y < 0 || x >= self.size as i64 || y >= self.size as i64 {
            return 1.0;
        }
        let i = (y as u32 * self.size + x as u32) as usize;
        if g.depth[i] < recv {
            g.pass[i]
        } else {
            1.0
        }
    }

    /// The nearest depth over texels `x0..=x1` × `y0..=y1` (clamped to the map; +∞ outside it), in at most four
    /// reads of [`ShadowMap::mins`].
    fn region_min(&self, x0: i64, y0: i64, x1: i64, y1: i64) -> f32 {
        self.region_min_of(&self.depth, &self.mins, [x0, y0, x1, y1])
    }

    /// [`ShadowMap::region_min`] of a depth layer `base` and its min pyramid `mins` (the opaque map's, or the
    /// glass layer's).
    fn region_min_of(&self, base: &[f32], mins: &[Vec<f32>], r: [i64; 4]) -> f32 {
        pyramid::region_min(base, mins, self.size as usize, r)
    }

    /// The farthest depth over texels `x0..=x1` × `y0..=y1`, or +∞ when the region leaves the map (where lookups
    /// read +∞, nothing), in at most four reads of [`ShadowMap::maxs`].
    fn region_max(&self, x0: i64, y0: i64, x1: i64, y1: i64) -> f32 {
        pyramid::region_max(&self.depth, &self.maxs, self.size as usize, [x0, y0, x1, y1])
    }

    /// Light space of world point `p`: texel x, texel y, depth (distance along the light's axis).
    #[inline]
    fn project(&self, p: Vec3) -> Vec3 {
        self.light_space(self.view.transform_point3(p))
    }

    /// Light space of view-space point `q` (see [`ShadowMap::project`]).
    #[inline]
    fn light_space(&self, q: Vec3) -> Vec3 {
        let d = -q.z;
        match self.projection {
            Projection::Ortho { scale, offset } => Vec3::new((q.x - offset.x) * scale, (q.y - offset.y) * scale, d),
            Projection::Persp { focal } => {
                let c = 0.5 * self.size as f32;
                let inv = 1.0 / d.max(NEAR);
                Vec3::new(c + focal * q.x * inv, c - focal * q.y * inv, d)
            }
        }
    }

    /// World size of one texel of a parallel map (a sun's); a perspective map's at unit depth.
    pub fn texel_size(&self) -> f32 {
        self.texel_world(1.0)
    }

    /// World size of one texel at light depth `d`.
    #[inline]
    fn texel_world(&self, d: f32) -> f32 {
        match self.projection {
            Projection::Ortho { scale, .. } => 1.0 / scale,
            Projection::Persp { focal } => d.max(NEAR) / focal,
        }
    }

    /// The depths as the lookups read them.
    #[inline]
    fn depths(&self) -> Depths<'_> {
        Depths { depth: &self.depth, size: self.size }
    }

    /// Nearest caster depth at texel (x, y); outside the map, nothing.
    #[inline]
    fn at(&self, x: i64, y: i64) -> f32 {
        self.depths().at(x, y)
    }

    /// The fraction of the light reaching world point `p` with unit normal `n` (facing the light or not: the
    /// caller weights by n·l). `size` is the light's angular radius as a tangent (sun) or its radius in world
    /// units (point, spot); 0 is a hard shadow.
    pub fn visibility(&self, p: Vec3, n: Vec3, size: f32) -> f32 {
        self.visibility_with::<4>(p, n, size)
    }

    /// [`ShadowMap::visibility`] with 8 × 8 taps in the blocker search and the filter instead of 4 × 4: a wide
    /// penumbra shows no steps (four copies of the caster's edge, where 4 × 4 taps spread over it), for four
    /// times the reads inside a penumbra. For what is read once and seen many times (a ground's shadow, sampled
    /// once per frame for every view: [`super::penumbra`]).
    pub fn visibility_smooth(&self, p: Vec3, n: Vec3, size: f32) -> f32 {
        self.visibility_with::<8>(p, n, size)
    }

    /// [`ShadowMap::visibility`] with `N` × `N` taps.
    #[inline]
    fn visibility_with<const N: usize>(&self, p: Vec3, n: Vec3, size: f32) -> f32 {
        // A parallel map's texels are one size at every depth: no need to project `p` to find it.
        let texel = match self.projection {
            Projection::Ortho { scale, .. } => 1.0 / scale,
            Projection::Persp { .. } => self.texel_world(self.project(p).z),
        };
        let q = self.project(p + n * (NORMAL_BIAS * texel));
        let bias = DEPTH_BIAS * self.texel_world(q.z);
        let recv = q.z - bias;
        let opaque = self.opaque_visibility::<N>(q, recv, n, size);
        if opaque == 0.0 {
            return 0.0;
        }
        opaque * self.glass_pass(q, recv)
    }

    /// [`ShadowMap::visibility`] from the opaque casters alone, at light-space `q` and receiver depth `recv`.
    fn opaque_visibility<const N: usize>(&self, q: Vec3, recv: f32, n: Vec3, size: f32) -> f32 {
        let slope = self.receiver_slope(n);
        if size <= 0.0 {
            return self.pcf(q, recv, slope);
        }
        // Blocker search over the widest penumbra this receiver could have.
        let widest = self.penumbra(recv, 0.0, size) / self.texel_world(q.z);
        let search = widest.clamp(1.0, 24.0);
        // Nothing in the search region is nearer than the receiver's plane anywhere in it: fully lit, as the
        // taps below would find (the usual case, read in four texels instead of sixteen).
        let reach = (slope.x.abs() + slope.y.abs()) * search;
        let (x0, y0) = (floor(q.x - search), floor(q.y - search));
        let (x1, y1) = (floor(q.x + search), floor(q.y + search));
        if self.region_min(x0, y0, x1, y1) >= recv + reach {
            return 1.0;
        }
        // Everything the filter below could read, out to its widest radius (a blocker at depth 0), is nearer
        // than the receiver's plane anywhere in it: fully shadowed, as the taps would find (the inside of a
        // shadow, read in four texels instead of eighty). The inner blocker taps lie in that region, so the
        // search finds blockers; a hair of margin keeps the bound on the safe side of rounding.
        let widest_filter = (0.5 * widest).clamp(1.0, 24.0) + 1.0;
        let reach = (slope.x.abs() + slope.y.abs()) * widest_filter;
        let (x0, y0) = (floor(q.x - widest_filter), floor(q.y - widest_filter));
        let (x1, y1) = (floor(q.x + widest_filter), floor(q.y + widest_filter));
        if self.region_max(x0, y0, x1, y1) < recv - reach - 1e-5 * (1.0 + recv.abs()) {
            return 0.0;
        }
        // The blocker search: an N × N grid of taps over ±`search`, the rows and columns of which are found once.
        let a = axis::<N>(search);
        let (xs, ys) = (a.map(|o| floor(q.x + o)), a.map(|o| floor(q.y + o)));
        let inside = self.holds(xs[0], ys[0], xs[N - 1], ys[N - 1]);
        let (mut sum, mut count) = (0.0, 0);
        for j in 0..N {
            for i in 0..N {
                let d = if inside { self.texel(xs[i], ys[j]) } else { self.at(xs[i], ys[j]) };
                if d < recv + (slope.x * a[i] + slope.y * a[j]) {
                    sum += d;
                    count += 1;
                }
            }
        }
        if count == 0 {
            return 1.0;
        }
        let blocker = sum / count as f32;
        let radius = self.penumbra(recv, blocker, size) / self.texel_world(q.z) * 0.5;
        if radius <= 1.0 {
            return self.pcf(q, recv, slope);
        }
        // The filter: a bilinear percentage-closer lookup (see [`ShadowMap::pcf`]) at each of an N × N grid over
        // ±`radius`, against the receiver's plane there; each column's and row's texels, weights and plane
        // offsets are found once.
        pcf::filter(self.depths(), q, recv, slope, &axis::<N>(radius.min(24.0)))
    }

    /// Whether [`ShadowMap::visibility`] is sure to answer exactly 1 (its first test: no caster anywhere near)
    /// for every receiver with unit normal `n` in the box spanned by `corners`, under a light of `size` (0 for a
    /// hard shadow, whose lookup reads the texels within one of the receiver's: the search below at its
    /// narrowest). Conservative: `false` when unsure, always for perspective maps. A ground plane asks it once
    /// per cell of a grid, so its open cells skip the lookup per pixel, and its sun's lattice skips them.
    pub fn open_over(&self, corners: &[Vec3], n: Vec3, size: f32) -> bool {
        if !matches!(self.projection, Projection::Ortho { .. }) || corners.is_empty() {
            return false;
        }
        // Parallel light: the lookup's point (normal offset included) is an affine function of the receiver, so
        // the box's corners bound it; the texel size is the same everywhere.
        let texel = self.texel_world(0.0);
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for &c in corners {
            let q = self.project(c + n * (NORMAL_BIAS * texel));
            (lo, hi) = (lo.min(q), hi.max(q));
        }
        let recv = hi.z - DEPTH_BIAS * texel;
        // The widest search any receiver in the box makes (it grows with the receiver's depth), the farthest its
        // plane reaches, and a texel and a hair of margin against rounding.
        let search = (self.penumbra(recv, 0.0, size) / texel).clamp(1.0, 24.0);
        let slope = self.receiver_slope(n);
        let reach = (slope.x.abs() + slope.y.abs()) * search;
        let (x0, y0) = (floor(lo.x - search) - 1, floor(lo.y - search) - 1);
        let (x1, y1) = (floor(hi.x + search) + 1, floor(hi.y + search) + 1);
        let bound = recv + reach + 1e-4 * (1.0 + recv.abs());
        // No transparent caster in front either: its light would be dimmed.
        self.region_min(x0, y0, x1, y1) >= bound
            && self.glass.as_ref().is_none_or(|g| self.region_min_of(&g.depth, &g.mins, [x0, y0, x1, y1]) >= bound)
    }

    /// Whether texels `x0..=x1` × `y0..=y1` all lie in the map.
    #[inline]
    fn holds(&self, x0: i64, y0: i64, x1: i64, y1: i64) -> bool {
        self.depths().holds(x0, y0, x1, y1)
    }

    /// Nearest caster depth at texel (x, y), which lies in the map.
    #[inline]
    fn texel(&self, x: i64, y: i64) -> f32 {
        self.depths().texel(x, y)
    }

    /// How the depth of the receiver's plane (normal `n`) changes per texel across an orthographic map: taps away
    /// from the receiver compare against its plane there, not its depth at the centre, so a wide filter does not
    /// shadow a surface with itself (a sphere's limb, a tilted plane). Clamped near grazing; zero for
    /// perspective maps, whose filters stay narrow.
    fn receiver_slope(&self, n: Vec3) -> Vec2 {
        let Projection::Ortho { scale, .. } = self.projection else { return Vec2::ZERO };
        let nl = self.view.transform_vector3(n);
        let max = 4.0 / scale;
        let nz = if nl.z.abs() < 1e-3 { 1e-3f32.copysign(nl.z) } else { nl.z };
        (Vec2::new(nl.x, nl.y) / (nz * scale)).clamp(Vec2::splat(-max), Vec2::splat(max))
    }

    /// Width in world units of the penumbra at receiver depth `recv` behind a blocker at `blocker`.
    fn penumbra(&self, recv: f32, blocker: f32, size: f32) -> f32 {
        match self.projection {
            Projection::Ortho { .. } => 2.0 * size * (recv - blocker).max(0.0),
            Projection::Persp { .. } => 2.0 * size * (recv - blocker).max(0.0) / blocker.max(NEAR),
        }
    }

    /// 2×2 bilinear percentage-closer lookup at light-space `q` against the receiver's depth `recv` there and its
    /// plane's `slope` per texel.
    #[inline]
    fn pcf(&self, q: Vec3, recv: f32, slope: Vec2) -> f32 {
        let (col, row) = (PcfAxis::new(q.x, slope.x), PcfAxis::new(q.y, slope.y));
        pcf::bilinear(self.depths(), &col, &row, recv, self.holds(col.texel, row.texel, col.texel + 1, row.texel + 1))
    }
}

/// One axis of an N × N grid of offsets spanning ±`radius` texels: the blocker search's and the soft filter's
/// taps are the grid's points (x from this, y from this).
fn axis<const N: usize>(radius: f32) -> [f32; N] {
    let half = (N - 1) as f32 * 0.5;
    std::array::from_fn(|i| (i as f32 - half) * (radius / half))
}

/// The six 90° faces of a point light's cube, as directions.
pub const CUBE: [Vec3; 6] = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];

/// The cube face a direction from a point light falls in.
#[inline]
pub fn cube_face(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 {
            0
        } else {
            1
        }
    } else if a.y >= a.z {
        if d.y >= 0.0 {
            2
        } else {
            3
        }
    } else if d.z >= 0.0 {
        4
    } else {
        5
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::render::light::scan::SCAN_RUN;
    use crate::scene::material::Material;
    use crate::scene::PrimKind;

    /// A square of side 2·`half` at height `z`, facing +Z: the casters of the light module's tests.
    pub(in crate::render::light) fn quad(z: f32, half: f32) -> PosedScene {
        let p = [
            Vec3::new(-half, -half, z),
            Vec3::new(half, -half, z),
            Vec3::new(half, half, z),
            Vec3::new(-half, half, z),
        ];
        PosedScene::quad(p, Vec3::Z, Material::default())
    }

    #[test]
    fn glass_passes_one_minus_its_alpha_and_layers_multiply() {
        // Two panes of alpha 0.25 and 0.5 above each other, over part of the ground; an opaque block beside.
        let glass = |z: f32, alpha: f32| {
            let mut q = quad(z, 0.5);
            let m = Material {
                alpha_mode: crate::scene::material::AlphaMode::Blend,
                base_color: glam::Vec4::new(1.0, 1.0, 1.0, alpha),
                ..Material::default()
            };
            q.materials = std::sync::Arc::new(vec![m]);
            q
        };
        let mut scene = PosedScene::default();
        let mut block = quad(1.0, 0.2);
        for p in &mut block.primitives[0].positions {
            p.x += 1.5;
        }
        crate::scene::merge(&[glass(1.0, 0.25), glass(2.0, 0.5), block], &mut scene);
        let bounds = scene.bounds().unwrap();
        let m = ShadowMap::sun(&scene, -Vec3::Z, bounds, 512, PointCasters::NONE);
        let under = m.visibility(Vec3::new(0.1, -0.2, 0.0), Vec3::Z, 0.0);
        assert!((under - 0.75 * 0.5).abs() < 1e-6, "{under}");
        // On top of the upper pane nothing is in front. (Between the panes the layer counts both: one layer per
        // texel, the nearest depth and every pane's share.)
        assert_eq!(m.visibility(Vec3::new(0.1, -0.2, 2.0), Vec3::Z, 0.0), 1.0);
        // The opaque block still blocks; open ground is open, and a ground grid is not told it is open under glass.
        assert_eq!(m.visibility(Vec3::new(1.5, 0.0, 0.0), Vec3::Z, 0.0), 0.0);
        assert_eq!(m.visibility(Vec3::new(-0.9, 0.9, 0.0), Vec3::Z, 0.01), 1.0);
        let cell = |x: f32, y: f32| [Vec3::new(x, y, 0.0), Vec3::new(x + 0.05, y + 0.05, 0.0)];
        assert!(!m.open_over(&cell(0.0, 0.0), Vec3::Z, 0.01));
        assert!(m.open_over(&cell(-0.9, 0.9), Vec3::Z, 0.01));
    }

    #[test]
    fn a_box_said_open_is_lit_all_over_and_near_the_shadow_none_is() {
        // Cells of 2 cm over the ground around a 1 m square's shadow, under a hard sun and a soft one: every
        // point of a cell `open_over` calls open is looked up fully lit, and it calls open most of the ground but
        // not the cells at the shadow's edge.
        let scene = quad(1.0, 0.5);
        let m = ShadowMap::sun(
            &scene,
            Vec3::new(0.3, 0.2, -1.0).normalize(),
            scene.bounds().unwrap(),
            512,
            PointCasters::NONE,
        );
        for size in [0.0, 0.02] {
            let (mut open, mut cells) = (0, 0);
            for j in 0..60 {
                for i in 0..60 {
                    let (x, y) = (-1.2 + i as f32 * 0.04, -1.2 + j as f32 * 0.04);
                    let corners = [Vec3::new(x, y, 0.0), Vec3::new(x + 0.02, y + 0.02, 0.0)];
                    cells += 1;
                    if !m.open_over(&corners, Vec3::Z, size) {
                        continue;
                    }
                    open += 1;
                    for (u, v) in [(0.0, 0.0), (0.5, 0.5), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.3, 0.8)] {
                        let p = Vec3::new(x + 0.02 * u, y + 0.02 * v, 0.0);
                        assert_eq!(m.visibility(p, Vec3::Z, size), 1.0, "size {size} at {p}");
                    }
                }
            }
            assert!(open > cells / 2 && open < cells, "size {size}: {open} of {cells} cells open");
        }
    }

    #[test]
    fn a_sun_shadow_falls_under_its_caster_and_nowhere_else() {
        let scene = quad(1.0, 0.5);
        let bounds = scene.bounds().unwrap();
        let m = ShadowMap::sun(&scene, -Vec3::Z, bounds, 512, PointCasters::NONE);
        // Under the caster: dark; beside it and on the caster's own top face: lit (no acne).
        assert_eq!(m.visibility(Vec3::new(0.0, 0.0, 0.0), Vec3::Z, 0.0), 0.0);
        assert_eq!(m.visibility(Vec3::new(0.8, 0.0, 0.0), Vec3::Z, 0.0), 1.0);
        assert_eq!(m.visibility(Vec3::new(0.1, 0.2, 1.0), Vec3::Z, 0.0), 1.0);
        // A soft sun blurs the edge: half-lit right under it.
        let edge = m.visibility(Vec3::new(0.5, 0.0, 0.0), Vec3::Z, 0.05);
        assert!(edge > 0.2 && edge < 0.8, "{edge}");
    }

    #[test]
    fn a_caster_of_more_triangles_than_a_run_casts_every_run() {
        // A square of 2 × 182² triangles (a run and more), its last triangles at its +y edge: the map drawn
        // from it holds the depth the two-triangle square's map holds wherever either is covered.
        let (n, half) = (182usize, 0.5f32);
        assert!(2 * n * n > SCAN_RUN);
        let at = |i: usize, j: usize| {
            Vec3::new(-half + 2.0 * half * i as f32 / n as f32, -half + 2.0 * half * j as f32 / n as f32, 1.0)
        };
        let p: Vec<Vec3> = (0..=n).flat_map(|j| (0..=n).map(move |i| at(i, j))).collect();
        let k = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let indices: Vec<u32> = (0..n)
            .flat_map(|j| {
                (0..n).flat_map(move |i| [k(i, j), k(i + 1, j), k(i + 1, j + 1), k(i, j), k(i + 1, j + 1), k(i, j + 1)])
            })
            .collect();
        let fine = PosedScene::single(
            PrimKind::Triangles,
            p.clone(),
            vec![Vec3::Z; p.len()],
            Vec::new(),
            indices,
            Material::default(),
        );
        let coarse = quad(1.0, half);
        let bounds = coarse.bounds().unwrap();
        let (a, b) = (
            ShadowMap::sun(&fine, -Vec3::Z, bounds, 256, PointCasters::NONE),
            ShadowMap::sun(&coarse, -Vec3::Z, bounds, 256, PointCasters::NONE),
        );
        let covered = b.depth.iter().filter(|d| d.is_finite()).count();
        assert!(covered > 170 * 170, "{covered}");
        for (i, (x, y)) in a.depth.iter().zip(&b.depth).enumerate() {
            assert_eq!(x.is_finite(), y.is_finite(), "texel {i}");
            if y.is_finite() {
                assert!((x - y).abs() < 1e-4, "texel {i}: {x} against {y}");
            }
        }
    }

    #[test]
    fn a_spot_shadow_is_a_projection_from_the_light() {
        let scene = quad(1.0, 0.25);
        let m = ShadowMap::perspective(&scene, Vec3::new(0.0, 0.0, 2.0), -Vec3::Z, 1.5, 512, PointCasters::NONE);
        // The caster (half width 0.25 at 1 m from the light) shades half width 0.5 at 2 m.
        assert_eq!(m.visibility(Vec3::new(0.4, 0.0, 0.0), Vec3::Z, 0.0), 0.0);
        assert_eq!(m.visibility(Vec3::new(0.6, 0.0, 0.0), Vec3::Z, 0.0), 1.0);
        assert_eq!(cube_face(Vec3::new(0.1, -2.0, 0.3)), 3);
    }
}
