//! Points in shadow maps: a point primitive's points cast shadows as the images draw them, so that a point
//! cloud or a file of 3D Gaussians standing on a lit ground darkens it under the sun and where it meets it (the
//! environment's occlusion maps are shadow maps too). Before, only triangles cast, and a cloud floated over a
//! ground lit right under it.
//!
//! A plain point casts its splat's silhouette seen from the light at twice the splat's size: a cube's (the box
//! about its projection), or a disk's facing the light (squares, disks and surfels), when the splats have a world
//! size; pixel-sized splats have none there and cast nothing. Twice, because a map is finer than the images: the
//! splats of an irregular sampling (a voxel of 9 neighbours in 10) close its surface in an image, where the
//! back layer shows through a gap as the same colour, but not in a 2048² map, where the gaps of both layers let
//! the sun through as specks all over the shadow (a 45 000-point donut). A disk of twice the size reaches every
//! point within a voxel of a sample; the silhouette grows by half a splat, under a soft shadow's blur.
//!
//! A 3D Gaussian casts its opaque core, where its alpha, its opacity times its falloff, reaches one half: inside
//! the ellipse d·Σ⁻¹·d ≤ 2·ln(2·opacity) of its projected covariance, so one under half opaque casts nothing. Either holds its centre's depth over its footprint, and a
//! footprint that covers no texel's centre covers the texel its centre falls in, as images draw a point too
//! small for its samples: a dense cloud's shadow has no holes however fine the map.

use glam::{Mat3, Vec2, Vec3};

use super::{Projection, ShadowMap, NEAR};
use crate::render::splat::{Shape, Size, SplatSettings};
use crate::scene::texture::floor;
use crate::scene::{PosedPrimitive, PosedScene, PrimKind};

/// How a point primitive's points cast shadows: plain points as the splats images draw them, at twice their
/// size, when those have a world size; 3D Gaussians by their cores.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PointCasters {
    /// The casters' edge (cube) or diameter (square, disk, surfel) in world units, twice the splats'; `None`
    /// for pixel-sized splats, which cast nothing.
    pub size: Option<f32>,
    /// Cubes: their silhouettes. Otherwise disks facing the light.
    pub cube: bool,
    /// Whether 3D Gaussians cast.
    pub gaussians: bool,
}

impl PointCasters {
    /// No point casts: what a point's own baked colour is lit by (its neighbours would stand in front of it,
    /// their footprints at their centres' depths, and shadow it all over), and what triangle-only tests use.
    pub const NONE: PointCasters = PointCasters { size: None, cube: false, gaussians: false };

    /// For splats drawn as `s` says: twice their size (see the module's header); 3D Gaussians cast.
    pub fn of(s: &SplatSettings) -> PointCasters {
        let size = match s.size {
            Size::World(w) if w.is_finite() && w > 0.0 => Some(2.0 * w),
            _ => None,
        };
        PointCasters { size, cube: s.shape == Shape::Cube, gaussians: true }
    }

    /// Half the widest reach of a point's footprint from its centre, in world units: how far past the points
    /// a map's bounds must reach (a cube's half diagonal).
    fn reach(&self) -> f32 {
        self.size.map_or(0.0, |s| if self.cube { 0.5 * s * 3f32.sqrt() } else { 0.5 * s })
    }
}

/// How many times over a map's texels its points' footprints may visit: enough for a cloud of millions drawn a
/// few texels wide, and a bound on a file of giant Gaussians (a scene capture's background, each covering much of
/// the map), past which a footprint keeps the texel its centre falls in.
const COVER_BUDGET: u64 = 64;

/// Whether point primitive `p` casts: plain points drawn at a world size, or 3D Gaussians; not a shadeless
/// (`KHR_materials_unlit`) or shadowless material's, as for triangles.
fn casts(scene: &PosedScene, p: &PosedPrimitive, points: PointCasters) -> bool {
    p.kind == PrimKind::Points
        && if p.gaussians.is_some() { points.gaussians } else { points.size.is_some() }
        && scene.materials.get(p.material as usize).is_none_or(|m| m.casts_shadows && !m.unlit)
}

/// The bounds the casting points of `scene` reach (their footprints included), when any cast.
pub(in crate::render::light) fn bounds(scene: &PosedScene, points: PointCasters) -> Option<(Vec3, Vec3)> {
    let mut out: Option<(Vec3, Vec3)> = None;
    for p in scene.primitives.iter().filter(|p| casts(scene, p, points)) {
        for (i, &c) in p.positions.iter().enumerate() {
            if !c.is_finite() {
                continue;
            }
            let r = match &p.gaussians {
                // The core's ellipsoid lies within the 3σ sphere of its longest axis (a core reaches
                // √(2·ln 2) ≈ 1.18σ at most).
                Some(g) => 3.0 * longest_axis(g.to_world * g.data.factors[i]),
                None => points.reach(),
            };
            let r = Vec3::splat(if r.is_finite() { r } else { 0.0 });
            out = Some(match out {
                None => (c - r, c + r),
                Some((lo, hi)) => (lo.min(c - r), hi.max(c + r)),
            });
        }
    }
    out
}

/// A bound on the largest standard deviation of the Gaussian whose covariance is F·Fᵀ: F's Frobenius norm
/// (cheap, and only a bound is needed).
fn longest_axis(f: Mat3) -> f32 {
    (f.x_axis.length_squared() + f.y_axis.length_squared() + f.z_axis.length_squared()).sqrt()
}

/// One point's footprint in a map: its centre (texels), depth, and outline there.
#[derive(Debug, Clone, Copy)]
struct Footprint {
    centre: Vec2,
    depth: f32,
    shape: Outline,
}

/// What a point covers of a map about its centre, in texels.
#[derive(Debug, Clone, Copy)]
enum Outline {
    /// A box of these half sides.
    Box(Vec2),
    /// A disk of this radius.
    Disk(f32),
    /// An ellipse d·C·d ≤ 1, C = [[a, b], [b, c]], within a box of these half sides.
    Ellipse { conic: [f32; 3], half: Vec2 },
}

/// Point `i` of point primitive `p` as a map sees it, `j0` and `j1` the map's texel axes as rows over world
/// offsets about the point (the view's rotation through the projection's Jacobian there); `None` where it casts
/// nothing.
fn outline(j0: Vec3, j1: Vec3, p: &PosedPrimitive, i: usize, points: PointCasters) -> Option<Outline> {
    Some(match &p.gaussians {
        Some(g) => {
            let opacity = g.data.opacities[i];
            // (Not finite, or at most half opaque: no core.)
            if opacity.is_nan() || opacity <= 0.5 {
                return None;
            }
            // The core: α·exp(−m²/2) ≥ ½ ⇔ m² ≤ 2·ln(2α), with m² = d·Σ₂⁻¹·d and Σ₂ = (J·F)(J·F)ᵀ.
            let f = g.to_world * g.data.factors[i];
            let (u0, u1) = (f.transpose() * j0, f.transpose() * j1);
            let (a, b, cc) = (u0.dot(u0), u0.dot(u1), u1.dot(u1));
            let det = a * cc - b * b;
            let k2 = 2.0 * (2.0 * opacity).ln();
            if det.is_nan() || det <= 0.0 || !det.is_finite() {
                return None;
            }
            // d·(Σ₂/k²)⁻¹·d ≤ 1; the box of that ellipse has half sides k·√Σ₂ₓₓ and k·√Σ₂ᵧᵧ.
            let conic = [cc / (det * k2), -b / (det * k2), a / (det * k2)];
            Outline::Ellipse { conic, half: Vec2::new((k2 * a).sqrt(), (k2 * cc).sqrt()) }
        }
        None => {
            let s = points.size?;
            if points.cube {
                // The box about a world-aligned cube's projection: each axis's half edge through the map.
                let h = 0.5 * s;
                let half = |j: Vec3| h * (j.x.abs() + j.y.abs() + j.z.abs());
                Outline::Box(Vec2::new(half(j0), half(j1)))
            } else {
                // A disk facing the light: its radius through the map (the larger of the two axes' scales,
                // the same for a parallel map).
                Outline::Disk(0.5 * s * j0.length().max(j1.length()))
            }
        }
    })
}

impl ShadowMap {
    /// Draws the casting points of `scene` (see the module's header) into the depth map.
    pub(super) fn draw_points(&mut self, scene: &PosedScene, points: PointCasters) {
        // The view's rotation, row by row: world offsets about a point to the light's axes.
        let rot = Mat3::from_mat4(self.view);
        let (r0, r1, r2) = (rot.row(0), rot.row(1), rot.row(2));
        let mut budget = COVER_BUDGET * (self.size as u64) * (self.size as u64);
        for p in scene.primitives.iter().filter(|p| casts(scene, p, points)) {
            // Under parallel light a plain point's outline is the same everywhere: found once (a cloud of half a
            // million points is drawn into 33 maps a frame).
            let fixed = match self.projection {
                Projection::Ortho { scale, .. } if p.gaussians.is_none() => {
                    outline(r0 * scale, r1 * scale, p, 0, points)
                }
                _ => None,
            };
            for (i, &c) in p.positions.iter().enumerate() {
                let q = self.view.transform_point3(c);
                let (centre, depth) = (self.light_space(q).truncate(), -q.z);
                if !centre.is_finite() || !depth.is_finite() {
                    continue;
                }
                let shape = match (fixed, self.projection) {
                    (Some(o), _) => Some(o),
                    (None, Projection::Ortho { scale, .. }) => outline(r0 * scale, r1 * scale, p, i, points),
                    // The projection's Jacobian at the centre: scaled by the depth, its rows through the depth's
                    // change too.
                    (None, Projection::Persp { focal }) if depth >= NEAR => {
                        let k = focal / depth;
                        outline(r0 * k + r2 * (k * q.x / depth), -(r1 * k + r2 * (k * q.y / depth)), p, i, points)
                    }
                    _ => None,
                };
                if let Some(shape) = shape {
                    self.fill(&Footprint { centre, depth, shape }, &mut budget);
                }
            }
        }
    }

    /// Writes footprint `f`'s depth where it is nearer, over the texels whose centres it covers, or over the
    /// texel its centre falls in when it covers none.
    ///
    /// `budget` is how many texels the map's points may still visit: a footprint that would visit more keeps the
    /// texel its centre falls in.
    fn fill(&mut self, f: &Footprint, budget: &mut u64) {
        let n = self.size as i64;
        let half = match f.shape {
            Outline::Box(h) => h,
            Outline::Disk(r) => Vec2::splat(r),
            Outline::Ellipse { half, .. } => half,
        };
        if half.x < 0.5 && half.y < 0.5 {
            // Narrower than a texel: the only centre it could cover is that of the texel its centre falls in,
            // which it falls back to otherwise (most points of a cloud in the environment's 256² maps).
            self.nearer(floor(f.centre.x), floor(f.centre.y), f.depth);
            return;
        }
        // Texel (x, y)'s centre is at (x + 0.5, y + 0.5): the first and last centres within `lo..=hi`.
        // Clamped to the map, so that a footprint of any size visits at most its texels.
        let span = |lo: f32, hi: f32| (floor(0.5 - lo).saturating_neg().max(0), floor(hi - 0.5).min(n - 1));
        let (x0, x1) = span(f.centre.x - half.x, f.centre.x + half.x);
        let (y0, y1) = span(f.centre.y - half.y, f.centre.y + half.y);
        let area = ((x1 - x0 + 1).max(0) * (y1 - y0 + 1).max(0)) as u64;
        if area > *budget {
            self.nearer(floor(f.centre.x), floor(f.centre.y), f.depth);
            return;
        }
        *budget -= area;
        let mut any = false;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let d = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) - f.centre;
                let inside = match f.shape {
                    Outline::Box(_) => true,
                    Outline::Disk(r) => d.length_squared() <= r * r,
                    Outline::Ellipse { conic: [a, b, c], .. } => {
                        a * d.x * d.x + 2.0 * b * d.x * d.y + c * d.y * d.y <= 1.0
                    }
                };
                if inside {
                    any = true;
                    let t = &mut self.depth[(y * n + x) as usize];
                    *t = t.min(f.depth);
                }
            }
        }
        // A footprint between texel centres (an ellipse that misses the centres its box holds): the texel the
        // centre falls in.
        if !any {
            self.nearer(floor(f.centre.x), floor(f.centre.y), f.depth);
        }
    }

    /// Keeps depth `d` at texel (x, y) where it is nearer; nothing off the map.
    #[inline]
    fn nearer(&mut self, x: i64, y: i64, d: f32) {
        let n = self.size as i64;
        if (0..n).contains(&x) && (0..n).contains(&y) {
            let t = &mut self.depth[(y * n + x) as usize];
            *t = t.min(d);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::quad;
    use super::*;
    use crate::scene::gaussians::{GaussianData, Gaussians};
    use crate::scene::material::Material;

    /// A square sheet of points `side` wide, `step` apart, at height `z`.
    fn sheet(side: f32, step: f32, z: f32) -> Vec<Vec3> {
        let n = (side / step).round() as usize;
        (0..=n)
            .flat_map(|j| {
                (0..=n).map(move |i| Vec3::new(-0.5 * side + i as f32 * step, -0.5 * side + j as f32 * step, z))
            })
            .collect()
    }

    fn cloud(positions: Vec<Vec3>) -> PosedScene {
        PosedScene::single(PrimKind::Points, positions, Vec::new(), Vec::new(), Vec::new(), Material::default())
    }

    /// Flat round Gaussians of standard deviation `sigma` (and a hundredth of it across) and `opacity` on
    /// `positions`.
    fn gaussians(positions: Vec<Vec3>, sigma: f32, opacity: f32) -> PosedScene {
        let n = positions.len();
        let mut s = cloud(positions);
        let data = GaussianData {
            factors: vec![Mat3::from_diagonal(Vec3::new(sigma, sigma, 0.01 * sigma)); n],
            opacities: vec![opacity; n],
            degree: 0,
            sh: vec![Vec3::ZERO; n],
        };
        s.primitives[0].gaussians = Some(Gaussians::new(data));
        s
    }

    #[test]
    fn a_sheet_of_points_or_gaussians_shadows_the_ground_as_the_quad_it_samples_does() {
        // A 1 m square at z = 1 as two triangles, as cubes and disks 2 cm wide on its 2 cm grid, and as opaque
        // Gaussians there, under a sun straight overhead and an oblique one: the ground's visibility below
        // agrees everywhere but within two samples' width of the edges (hard shadows: the map's own edges).
        let bounds = (Vec3::new(-0.6, -0.6, 0.0), Vec3::new(0.6, 0.6, 1.0));
        let step = 0.02;
        let points = cloud(sheet(1.0, step, 1.0));
        let splats = gaussians(sheet(1.0, step, 1.0), step, 0.99);
        // As splats one grid step wide are drawn.
        let splats_of = |shape: Shape| PointCasters::of(&SplatSettings { shape, size: Size::World(step), min_px: 1.0 });
        let (cubes, disks) = (splats_of(Shape::Cube), splats_of(Shape::Disk));
        assert_eq!(cubes, PointCasters { size: Some(2.0 * step), cube: true, gaussians: true });
        let cores = PointCasters::of(&SplatSettings::default());
        for dir in [-Vec3::Z, Vec3::new(0.3, -0.2, -1.0).normalize()] {
            let quad_map = ShadowMap::sun(&quad(1.0, 0.5), dir, bounds, 512, PointCasters::NONE);
            let maps = [
                ("cubes", ShadowMap::sun(&points, dir, bounds, 512, cubes)),
                ("disks", ShadowMap::sun(&points, dir, bounds, 512, disks)),
                ("gaussians", ShadowMap::sun(&splats, dir, bounds, 512, cores)),
            ];
            // Where the sun through the sheet meets the ground: the sheet moved by dir·(1/|dir.z|).
            let shift = (dir / -dir.z).truncate();
            for (name, map) in &maps {
                let (mut shadowed, mut lit) = (0, 0);
                for j in 0..60 {
                    for i in 0..60 {
                        let p = Vec3::new(-0.75 + i as f32 * 0.025, -0.75 + j as f32 * 0.025, 0.0);
                        let local = p.truncate() - shift;
                        // Two samples' width (and the map's texel) from the edge either way.
                        if (local.abs().max_element() - 0.5).abs() < 0.05 {
                            continue;
                        }
                        let (want, got) = (quad_map.visibility(p, Vec3::Z, 0.0), map.visibility(p, Vec3::Z, 0.0));
                        assert_eq!(want, got, "{name} under {dir} at {p}");
                        (shadowed, lit) = (shadowed + (got == 0.0) as u32, lit + (got == 1.0) as u32);
                    }
                }
                assert!(shadowed > 1000 && lit > 1000, "{name}: {shadowed} shadowed, {lit} lit");
            }
        }
        // Pixel-sized splats cast nothing, and neither do Gaussians under half opaque, nor any point when none
        // is to cast.
        let none = ShadowMap::sun(&points, -Vec3::Z, bounds, 512, cores);
        let faint = ShadowMap::sun(&gaussians(sheet(1.0, step, 1.0), step, 0.45), -Vec3::Z, bounds, 512, cores);
        let uncast = ShadowMap::sun(&splats, -Vec3::Z, bounds, 512, PointCasters::NONE);
        for m in [none, faint, uncast] {
            assert_eq!(m.visibility(Vec3::ZERO, Vec3::Z, 0.0), 1.0);
        }
    }

    #[test]
    fn points_finer_than_the_maps_texels_leave_no_holes() {
        // A 1 m sheet of points 1 mm wide and 5 mm apart under a map of 256² (a texel of about 4.7 mm): a texel
        // centre rarely falls inside a point, yet every texel under the sheet holds it.
        let bounds = (Vec3::new(-0.6, -0.6, 0.0), Vec3::new(0.6, 0.6, 1.0));
        let points = cloud(sheet(1.0, 0.005, 1.0));
        let map = ShadowMap::sun(
            &points,
            -Vec3::Z,
            bounds,
            256,
            PointCasters { size: Some(0.001), cube: true, gaussians: true },
        );
        for j in 0..40 {
            for i in 0..40 {
                let p = Vec3::new(-0.45 + i as f32 * 0.0231, -0.45 + j as f32 * 0.0231, 0.0);
                assert_eq!(map.visibility(p, Vec3::Z, 0.0), 0.0, "{p}");
            }
        }
    }

    #[test]
    fn giant_gaussians_visit_a_bounded_number_of_texels() {
        // Seventy opaque Gaussians, each wider than the map, stacked 1 cm apart from 1 m up, the highest last,
        // beside one of σ = 1e30 (its covariance overflows) and one 10³⁰ m away: the first 64 cover the map
        // (the budget: 64 maps' worth), the rest only the texels their centres fall in, so the map's corner
        // holds the 64th's depth, not the highest's.
        let mut centres: Vec<Vec3> = (0..70).map(|i| Vec3::new(0.0, 0.0, 1.0 + 0.01 * i as f32)).collect();
        centres.extend([Vec3::new(0.1, 0.1, 0.5), Vec3::new(1e30, 0.0, 0.5)]);
        let mut giants = gaussians(centres, 5.0, 0.99);
        let data = std::sync::Arc::make_mut(&mut giants.primitives[0].gaussians.as_mut().expect("Gaussians").data);
        data.factors[70] = Mat3::from_diagonal(Vec3::splat(1e30));
        let bounds = (Vec3::new(-0.6, -0.6, 0.0), Vec3::new(0.6, 0.6, 2.0));
        let map = ShadowMap::sun(&giants, -Vec3::Z, bounds, 256, PointCasters::of(&SplatSettings::default()));
        let at = |p: Vec3| map.project(p).z;
        assert_eq!(map.depth[0], at(Vec3::new(0.0, 0.0, 1.63)), "the corner");
        let centre = map.project(Vec3::new(0.0, 0.0, 1.0));
        let i = (centre.y as usize) * 256 + centre.x as usize;
        assert_eq!(map.depth[i], at(Vec3::new(0.0, 0.0, 1.69)), "under the stack");
    }

    #[test]
    fn a_perspective_map_sees_a_points_footprint_grow_as_it_nears_the_light() {
        // One cube 10 cm wide, 1 m and then 0.5 m below a spot looking down: its footprint spans about twice the
        // texels nearer the light (focal / depth).
        let scene = |z: f32| cloud(vec![Vec3::new(0.0, 0.0, z)]);
        let cubes = PointCasters { size: Some(0.1), cube: true, gaussians: true };
        let covered = |z: f32| {
            let m = ShadowMap::perspective(&scene(z), Vec3::new(0.0, 0.0, 2.0), -Vec3::Z, 1.5, 512, cubes);
            m.depth.iter().filter(|d| d.is_finite()).count() as f32
        };
        let (far, near) = (covered(1.0), covered(1.5));
        assert!(far > 50.0, "{far}");
        let ratio = (near / far).sqrt();
        assert!((ratio - 2.0).abs() < 0.15, "{near} against {far} texels: {ratio}");
    }
}
