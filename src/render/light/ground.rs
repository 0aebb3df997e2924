//! The ground: a `plane` source's receiving-only diffuse plane. How it is lit (grids of the environment's
//! visibility and of the suns' shadows over it, and a shortcut for its top face), and what it gives back to the
//! subject standing on it: the first bounce of its light, with its shadows in it.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::brdf::{basis, hammersley};
use super::penumbra::SunShade;
use super::plane_grid::{
    locate, read3, summed_areas, sun_irradiance, PlaneGrids, PlaneVisibility, GRID_POINTS, PLANE_CELLS,
};
use super::{EnvLight, FrameLight, Light, LightKind, Visibility};
use crate::scene::{PosedPrimitive, PosedScene, PrimKind};

/// Directions (cosine-weighted about the normal) a point gathers the ground's bounce from: the bounce is a
/// smooth average of the grids, so a fixed set this size changes it by under 2 % between neighbouring vertices.
const BOUNCE_DIRECTIONS: u32 = 64;

/// The [`BOUNCE_DIRECTIONS`] directions in the tangent frame (z along the normal), cosine-weighted: the same for
/// every point, so found once rather than per vertex and frame.
static BOUNCE: std::sync::LazyLock<Vec<Vec3>> = std::sync::LazyLock::new(|| {
    (0..BOUNCE_DIRECTIONS)
        .map(|i| {
            let xi = hammersley(i, BOUNCE_DIRECTIONS);
            let (r, phi) = (xi.x.sqrt(), 2.0 * PI * xi.y);
            Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - xi.x).sqrt())
        })
        .collect()
});

/// A ground plane's first bounce: a receiving-only diffuse plane (the `plane` source) stands in for the map
/// below the horizon, as it does in a path tracer. Points above it receive the sky from the map and, from below,
/// what lies below the horizon: E(n) = π·L·(1 − n_z)/2 with L the radiance from there averaged over the cosine
/// lobe, the plane's own where the lobe meets it, its shadows in it ([`FrameLight::below`]). Point and spot lights
/// do not enter the bounce.
#[derive(Debug, Clone, Copy)]
pub(super) struct Ground {
    pub(super) z: f32,
    /// The plane's colour.
    albedo: Vec3,
    /// The open plane's outgoing radiance under the environment's sky, and under the suns.
    sky: Vec3,
    sun: Vec3,
}

impl Ground {
    /// The scene's ground: the first of its [`ground_planes`].
    pub(super) fn find(scene: &PosedScene, lights: &[&Light], env: &EnvLight) -> Option<Ground> {
        let prim = ground_planes(scene).next()?;
        let albedo = scene.material(prim.material).base_color.truncate();
        let sky = env.prefiltered.sky_irradiance(Vec3::Z) * env.strength;
        let sun = lights.iter().map(|l| sun_irradiance(l)).sum::<Vec3>();
        Some(Ground { z: prim.positions[0].z, albedo, sky: albedo * sky / PI, sun: albedo * sun / PI })
    }

    /// Where the ray from `p` (on or above the ground) along `d` (pointing down) meets the ground's plane, and
    /// how far along the ray.
    #[inline]
    fn hit(&self, p: Vec3, d: Vec3) -> (Vec3, f32) {
        let t = (p.z - self.z).max(0.0) / -d.z;
        (p + d * t, t)
    }

    /// Its outgoing radiance where the fractions `light` (environment, suns) of the open plane's arrive.
    #[inline]
    pub(super) fn radiance(&self, light: Vec2) -> Vec3 {
        self.sky * light.x + self.sun * light.y
    }
}

/// The scene's ground planes: triangles whose material casts no shadow (only a plane source's does).
pub(super) fn ground_planes(scene: &PosedScene) -> impl Iterator<Item = &PosedPrimitive> {
    scene.primitives.iter().filter(|p| {
        p.kind == PrimKind::Triangles
            && !p.positions.is_empty()
            && scene.materials.get(p.material as usize).is_some_and(|m| !m.casts_shadows && !m.unlit)
    })
}

impl FrameLight {
    /// The light over the plane through `corners` (horizontal, facing +Z).
    pub(super) fn plane_visibility(&self, material: u32, corners: &[Vec3]) -> PlaneVisibility {
        let lo = corners.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let hi = corners.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        let n = PLANE_CELLS;
        let cell = (hi - lo).truncate().max(Vec2::splat(1e-6)) / n as f32;
        // Grid point (i, j), and grid point k in row order.
        let corner = |i: usize, j: usize| Vec3::new(lo.x + cell.x * i as f32, lo.y + cell.y * j as f32, lo.z);
        let point = |k: usize| corner(k % (n + 1), k / (n + 1));
        let vis: Vec<f32> =
            (0..(n + 1) * (n + 1)).into_par_iter().map(|k| self.environment_visibility(point(k), Vec3::Z)).collect();
        // Each sun counts by the luminance of the irradiance it brings: the bounce's colour stays the open
        // plane's (its sky and sun parts apart), only how much of the suns' light arrives varies.
        let suns: Vec<(&super::Lamp, f32)> = self
            .lights
            .iter()
            .map(|lamp| (lamp, sun_irradiance(&lamp.light).dot(Vec3::new(0.2126, 0.7152, 0.0722))))
            .filter(|&(_, w)| w > 0.0)
            .collect();
        let total: f32 = suns.iter().map(|&(_, w)| w).sum();
        let sun: Vec<f32> = if total > 0.0 {
            (0..(n + 1) * (n + 1))
                .into_par_iter()
                .map(|k| suns.iter().map(|&(lamp, w)| w * lamp.visibility(point(k), Vec3::Z)).sum::<f32>() / total)
                .collect()
        } else {
            Vec::new()
        };
        // Point and spot lights vary over the plane by distance and angle: their irradiance itself, per point.
        let lamps: Vec<&super::Lamp> =
            self.lights.iter().filter(|l| !matches!(l.light.kind, LightKind::Sun { .. })).collect();
        let lamps: Vec<Vec3> = if lamps.is_empty() {
            Vec::new()
        } else {
            (0..(n + 1) * (n + 1))
                .into_par_iter()
                .map(|k| {
                    let p = point(k);
                    lamps.iter().map(|lamp| lamp.irradiance(p, Vec3::Z)).sum()
                })
                .collect()
        };
        let mut plane =
            self.assemble(material, corners, PlaneGrids { vis, sun, lamps, bounce: Vec::new(), shades: Vec::new() });
        plane.grids.shades = self
            .lights
            .iter()
            .zip(&plane.open)
            .map(|(lamp, open)| match lamp.maps.as_slice() {
                [map] if !open.is_empty() => SunShade::sample(map, lamp.size, open, lo, cell, n),
                _ => SunShade::default(),
            })
            .collect();
        plane
    }

    /// The plane through `corners` with its grids `grids` (found by [`FrameLight::plane_visibility`], here or in
    /// the frame's light action): what its shading reads besides them, found from this frame's lights.
    pub(super) fn assemble(&self, material: u32, corners: &[Vec3], grids: PlaneGrids) -> PlaneVisibility {
        let lo = corners.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let hi = corners.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        let n = PLANE_CELLS;
        let cell = (hi - lo).truncate().max(Vec2::splat(1e-6)) / n as f32;
        let corner = |i: usize, j: usize| Vec3::new(lo.x + cell.x * i as f32, lo.y + cell.y * j as f32, lo.z);
        // A cell's box reaches a millimetre above and below the plane and a hair past its sides, so that every
        // point shaded in it (rounding included) lies inside.
        let margin = Vec3::new(1e-4 * cell.x.max(1e-3), 1e-4 * cell.y.max(1e-3), 1e-3);
        let open = self
            .lights
            .iter()
            .map(|lamp| match lamp.maps.as_slice() {
                [map] if matches!(lamp.light.kind, LightKind::Sun { .. }) => (0..n * n)
                    .into_par_iter()
                    .map(|k| {
                        let (i, j) = (k % n, k / n);
                        let (a, b) = (corner(i, j) - margin, corner(i + 1, j + 1) + margin);
                        let corners: [Vec3; 8] = std::array::from_fn(|c| {
                            Vec3::new([a.x, b.x][c & 1], [a.y, b.y][(c >> 1) & 1], [a.z, b.z][c >> 2])
                        });
                        map.open_over(&corners, Vec3::Z, lamp.size)
                    })
                    .collect(),
                _ => Vec::new(),
            })
            .collect();
        let sky = self.irradiance(lo, Vec3::Z, Vec3::ZERO);
        // (An empty sun grid sums as all ones.)
        let sums = summed_areas(|k| [grids.vis[k] as f64, grids.sun.get(k).map_or(1.0, |&s| s as f64)]);
        let lamp_sums = if grids.lamps.len() == GRID_POINTS {
            summed_areas(|k| grids.lamps[k].to_array().map(f64::from))
        } else {
            Vec::new()
        };
        let mut plane = PlaneVisibility {
            material,
            lo: lo.truncate(),
            cell,
            grids,
            sums,
            lamp_sums,
            sky,
            open,
            lit: Vec::new(),
            unsunned: Vec::new(),
            sunlit: Vec::new(),
        };
        plane.combine(&self.lights);
        plane
    }

    /// What reaches world point `p` of a surface of material `material` of the environment's light, when that
    /// is a ground plane's (whose visibility is a grid, not per vertex); from below it sees the open ground.
    #[inline]
    pub fn plane_visibility_at(&self, material: u32, p: Vec3) -> Option<Visibility> {
        let g = self.planes.iter().find(|g| g.material == material)?;
        let below = self.ground.map_or(Vec3::ZERO, |g| g.radiance(Vec2::ONE));
        Some(Visibility { env: g.at(p.x, p.y), below, bounce: g.bounce_at(p.x, p.y) })
    }

    /// The radiance a point `p` with unit normal `n` receives from below the horizon, averaged over the cosine
    /// lobe about `n` ([`BOUNCE_DIRECTIONS`] fixed directions): where a direction meets the ground, the
    /// ground's radiance there, its shadows in it; past the ground's edges, the map's (what a path tracer sees
    /// there). A side facing the subject's own shadow is lit from below by that shadow, not by open sunlit ground:
    /// against Cycles, the open ground's radiance everywhere made such sides up to twice too bright.
    /// Zero without a ground or below it.
    pub(super) fn below(&self, p: Vec3, n: Vec3) -> Vec3 {
        let Some(g) = self.ground else {
            return Vec3::ZERO;
        };
        if p.z < g.z - 1e-3 {
            return Vec3::ZERO;
        }
        let (t, b) = basis(n);
        let (mut sum, mut count) = (Vec3::ZERO, 0u32);
        for h in BOUNCE.iter() {
            let d = t * h.x + b * h.y + n * h.z;
            if d.z >= -1e-4 {
                continue;
            }
            sum += self.below_along(p, d);
            count += 1;
        }
        if count == 0 {
            // The lobe misses the lower hemisphere (a normal pointing up), whose weight (1 − n_z)/2 is then
            // below 1/64: the open ground.
            g.radiance(Vec2::ONE)
        } else {
            sum / count as f32
        }
    }

    /// The radiance [`FrameLight::below`] counts along unit direction `d` (pointing down) from `p` (on or above
    /// the ground): the ground's where `d` meets it, else the map's.
    pub(super) fn below_along(&self, p: Vec3, d: Vec3) -> Vec3 {
        let Some(g) = self.ground else {
            return Vec3::ZERO;
        };
        let (q, _) = g.hit(p, d);
        match self.planes.first().and_then(|plane| plane.light_at(q.x, q.y)) {
            Some((light, lamps)) => g.radiance(light) + g.albedo * lamps * (1.0 / PI),
            None => self.map_below(d),
        }
    }

    /// The map's radiance along `d`, blurred (its roughest prefiltered level): what lies past the ground.
    #[inline]
    pub(super) fn map_below(&self, d: Vec3) -> Vec3 {
        let e = &self.env;
        e.prefiltered.levels.last().map_or(Vec3::ZERO, |m| m.radiance(e.rotation * d)) * e.strength
    }

    /// The ground's radiance along unit direction `d` from `p` (on or above it), averaged over a footprint that
    /// widens by `spread` per unit of distance (a glossy lobe's), and the fraction of that footprint on the
    /// plane: `None` when there is no ground, `d` does not point down, or the footprint misses the plane.
    #[inline]
    pub(super) fn ground_seen(&self, p: Vec3, d: Vec3, spread: f32) -> Option<(Vec3, f32)> {
        let g = self.ground?;
        let plane = self.planes.first()?;
        if d.z >= -1e-4 || p.z < g.z - 1e-3 {
            return None;
        }
        let (q, t) = g.hit(p, d);
        plane
            .light_over(q.x, q.y, t * spread)
            .map(|(light, lamps, on)| (g.radiance(light) + g.albedo * lamps * (1.0 / PI), on))
    }

    /// [`FrameLight::shade`] of the top face (normal +Z) of ground plane material `material`, when it is one,
    /// at world point `p`, for a Lambertian surface of colour `albedo` (no specular layer, no occlusion
    /// texture): what a `plane` source is. Such a face looks the same from every view, and all but its shadows
    /// and occlusion is the same everywhere on it, so the environment's share was found once per frame.
    #[inline]
    pub fn shade_ground(&self, material: u32, p: Vec3, albedo: Vec3) -> Option<Vec3> {
        let g = self.planes.iter().find(|g| g.material == material)?;
        let at = locate(g.grid_uv(p.x, p.y));
        let cell = at.j * PLANE_CELLS + at.i;
        let sunlit = g.sunlit.get(cell) == Some(&true);
        let mut e = read3(if sunlit { &g.lit } else { &g.unsunned }, at);
        for (k, (lamp, open)) in self.lights.iter().zip(&g.open).enumerate() {
            let sun = matches!(lamp.light.kind, LightKind::Sun { .. });
            if sun && sunlit {
                continue;
            }
            let (l, radiance) = lamp.incidence(p);
            if l.z <= 0.0 || radiance == 0.0 {
                continue;
            }
            let light = &lamp.light;
            // A sun's shadow was sampled once for the frame where it may fall (open cells hold none: fully lit).
            let vis = match g.grids.shades.get(k) {
                Some(s) if !s.is_empty() => s.at(cell, at.t).unwrap_or(1.0),
                _ if open.get(cell) == Some(&true) => 1.0,
                _ => lamp.visibility(p, Vec3::Z),
            };
            e += light.color * (radiance * light.intensity * vis * l.z);
        }
        Some(albedo * e / PI)
    }
}

#[cfg(test)]
mod tests {
    use super::super::brdf::DIELECTRIC;
    use super::super::Surface;
    use super::*;
    use crate::render::light::PointCasters;

    /// A 4 m ground plane of colour (0.7, 0.6, 0.5) at z = 0 under a 0.6 m square caster at z = 1, lit by
    /// `lights` and the studio map.
    fn square_over_ground(lights: &[Light]) -> (PosedScene, FrameLight) {
        let plane = crate::scene::input::Ground { size: [4.0, 4.0], color: [0.7, 0.6, 0.5], z: None };
        let mut scene = PosedScene::default();
        crate::scene::merge(
            &[crate::scene::source::ground(&plane, 0.0), super::super::shadow::tests::quad(1.0, 0.3)],
            &mut scene,
        );
        let frame =
            FrameLight::prepare(&scene, lights, crate::render::Environment::default().studio(), PointCasters::NONE);
        (scene, frame)
    }

    fn light(kind: LightKind) -> Light {
        Light { kind, color: Vec3::new(1.0, 0.9, 0.8), intensity: 3.0, shadows: true }
    }

    /// A sun straight overhead: the square's shadow is the square itself, x and y in −0.3..0.3.
    fn overhead_sun() -> Light {
        light(LightKind::Sun { direction: -Vec3::Z, angle: 0.01 })
    }

    #[test]
    fn the_grounds_bounce_carries_its_shadows_and_the_map_lies_past_its_edges() {
        let (_, frame) = square_over_ground(&[overhead_sun()]);
        let g = frame.ground.expect("a ground");
        let open = g.radiance(Vec2::ONE);
        let lum = |c: Vec3| c.dot(Vec3::splat(1.0 / 3.0));
        // Facing down a few centimetres over open ground, far from the caster: the open ground, give or take its
        // own visibility of the sky there.
        let far = frame.below(Vec3::new(-1.5, -1.5, 0.05), -Vec3::Z);
        assert!((lum(far) / lum(open) - 1.0).abs() < 0.05, "{far} vs {open}");
        // Facing down over the middle of the square's shadow, close to it: the shadowed ground, lit by what the
        // square leaves of the sky, without the sun.
        let shadowed = frame.below(Vec3::new(0.0, 0.0, 0.05), -Vec3::Z);
        let sky = g.radiance(Vec2::X);
        assert!(lum(shadowed) < lum(sky) && lum(shadowed) > 0.5 * lum(sky), "{shadowed}: {sky} .. {open}");
        // A side facing the shadow receives less from below than a side facing away from it, at the same point.
        let p = Vec3::new(0.5, 0.0, 0.3);
        let toward = frame.below(p, Vec3::new(-1.0, 0.0, -0.3).normalize());
        let away = frame.below(p, Vec3::new(1.0, 0.0, -0.3).normalize());
        assert!(lum(toward) < lum(away) - 0.02, "{toward} vs {away}");
        // Past the plane's edges the lobe meets the map's lower half, not an endless ground.
        let beyond = frame.below(Vec3::new(10.0, 0.0, 0.05), -Vec3::Z);
        // The map's lower half, cosine-weighted about −Z, by a dense quadrature of its own.
        let m = 64;
        let map = (0..m * m)
            .map(|k| {
                let (ct, phi) = (((k / m) as f32 + 0.5) / m as f32, ((k % m) as f32 + 0.5) / m as f32 * 2.0 * PI);
                let (c, s) = (ct.sqrt(), (1.0 - ct).sqrt());
                frame.map_below(Vec3::new(s * phi.cos(), s * phi.sin(), -c))
            })
            .sum::<Vec3>()
            / (m * m) as f32;
        assert!((beyond - map).abs().max_element() < 0.05 * map.max_element(), "{beyond} vs {map}");
        assert!((beyond - open).abs().max_element() > 0.1, "{beyond} vs {open}");
        // Below the ground nothing comes from below it; the ground's bounce reaches shading through the vertices.
        assert_eq!(frame.below(Vec3::new(0.0, 0.0, -0.5), -Vec3::Z), Vec3::ZERO);
        assert_eq!(frame.vertex_visibility[1][0].below, frame.below(Vec3::new(-0.3, -0.3, 1.0), Vec3::Z));
    }

    #[test]
    fn the_grounds_reflection_averages_its_light_over_the_lobes_footprint() {
        let (_, frame) = square_over_ground(&[overhead_sun()]);
        let (g, plane) = (frame.ground.expect("a ground"), &frame.planes[0]);
        // Seen straight down from 1 m: a sharp lobe reads the shadow's middle as shadowed, a footprint four times
        // the shadow's width reads mostly open ground.
        let down = -Vec3::Z;
        let (sharp, on) = frame.ground_seen(Vec3::new(0.0, 0.0, 0.9), down, 0.01).expect("on the plane");
        assert_eq!(on, 1.0);
        let (wide, _) = frame.ground_seen(Vec3::new(0.0, 0.0, 0.9), down, 1.2).expect("on the plane");
        assert!(sharp.x < g.radiance(Vec2::new(1.0, 0.1)).x && wide.x > g.radiance(Vec2::new(1.0, 0.8)).x);
        // The footprint's average moves continuously with it: across the shadow's edge in 1 mm steps, no step
        // jumps by more than a tenth of the edge's contrast.
        let contrast = g.radiance(Vec2::ONE).x - g.radiance(Vec2::X).x;
        let mut last: Option<f32> = None;
        for i in 0..200 {
            let p = Vec3::new(0.2 + i as f32 * 1e-3, 0.0, 0.5);
            let (c, _) = frame.ground_seen(p, down, 0.05).expect("on the plane");
            if let Some(l) = last {
                assert!((c.x - l).abs() < 0.1 * contrast, "{p}: {l} → {}", c.x);
            }
            last = Some(c.x);
        }
        // A box over the plane's corner is a quarter on it; one past the edges is not on it at all.
        let (_, _, quarter) = plane.light_over(2.0, 2.0, 0.2).expect("partly on the plane");
        assert!((quarter - 0.25).abs() < 0.02, "{quarter}");
        assert!(plane.light_over(3.0, 0.0, 0.2).is_none());
        // The summed areas agree with the grid: a box over whole cells averages the grid points it spans.
        let n = PLANE_CELLS + 1;
        let (i0, j0, k) = (40, 60, 9);
        let mean = |g: &[f32]| {
            (0..k).flat_map(|j| (0..k).map(move |i| (i0 + i, j0 + j))).map(|(i, j)| g[j * n + i]).sum::<f32>()
                / (k * k) as f32
        };
        let (x, y) = (plane.lo.x + plane.cell.x * (i0 as f32 + 4.0), plane.lo.y + plane.cell.y * (j0 as f32 + 4.0));
        let (avg, _, on) = plane.light_over(x, y, plane.cell.x * 4.5).expect("on the plane");
        assert_eq!(on, 1.0);
        assert!(
            (avg.x - mean(&plane.grids.vis)).abs() < 1e-4 && (avg.y - mean(&plane.grids.sun)).abs() < 1e-4,
            "{avg}"
        );
    }

    #[test]
    fn a_glossy_lobe_sees_the_ground_a_point_light_lights() {
        // The square over the ground under a point light alone (the map's strength 0): looking down from a
        // point beside the square, a narrow lobe sees the ground's radiance there, its colour times the lamp's
        // irradiance over π (it saw black before point lights entered the footprint's average).
        let lamp = light(LightKind::Point { position: Vec3::new(-1.0, 0.5, 2.0), radius: 0.1 });
        let plane = crate::scene::input::Ground { size: [4.0, 4.0], color: [0.7, 0.6, 0.5], z: None };
        let mut scene = PosedScene::default();
        crate::scene::merge(&[crate::scene::source::ground(&plane, 0.0)], &mut scene);
        let mut env = crate::render::Environment::default().studio();
        env.strength = 0.0;
        let frame = FrameLight::prepare(&scene, std::slice::from_ref(&lamp), env, PointCasters::NONE);
        let q = Vec3::new(0.8, -0.6, 0.0);
        let (seen, on) = frame.ground_seen(q + Vec3::Z * 0.5, -Vec3::Z, 0.01).expect("on the plane");
        let expected = Vec3::new(0.7, 0.6, 0.5) * frame.lights[0].irradiance(q, Vec3::Z) / PI;
        assert_eq!(on, 1.0);
        assert!(expected.x > 1e-3 && (seen - expected).abs().max_element() < 0.02 * expected.x, "{seen} vs {expected}");
    }

    #[test]
    fn the_grounds_shortcut_shades_as_the_full_model_does_in_and_out_of_shadow() {
        // A ground plane and a square caster over it, under a soft oblique sun, a point light and the studio map.
        let lights = [
            light(LightKind::Sun { direction: Vec3::new(0.3, 0.2, -1.0).normalize(), angle: 0.05 }),
            light(LightKind::Point { position: Vec3::new(-1.0, 0.5, 2.0), radius: 0.1 }),
        ];
        let (scene, frame) = square_over_ground(&lights);
        let ground = scene.primitives[0].material;
        let albedo = Vec3::new(0.7, 0.6, 0.5);
        let lambert = Surface { base: albedo, metallic: 0.0, roughness: 0.5, specular: 0.0, f0: DIELECTRIC };
        let (mut shadowed, mut open) = (0, 0);
        // A grid over the whole plane, and two lines a millimetre apart across the shadow's edges (the square's
        // shadow is the square moved by (0.3, 0.2): x in 0..0.6, y in −0.1..0.5), through its penumbra.
        let grid =
            (0..10_000).map(|i| Vec3::new(-1.98 + (i % 100) as f32 * 0.04, -1.98 + (i / 100) as f32 * 0.04, 0.0));
        let across = (0..1000).map(|i| Vec3::new(-0.2 + i as f32 * 1e-3, 0.2, 0.0));
        let along = (0..1000).map(|i| Vec3::new(0.3, -0.3 + i as f32 * 1e-3, 0.0));
        // The shortcut reads the sun's shadow from the frame's lattice ([`SunShade`]), the full model looks it up:
        // the two differ by the sun's light times the difference of the two visibilities, and by nothing else.
        let sun_lamp = &frame.lights[0];
        let sun_term =
            albedo / PI * sun_lamp.light.color * sun_lamp.light.intensity * sun_lamp.incidence(Vec3::ZERO).0.z;
        let plane = &frame.planes[0];
        let mut worst = 0.0f32;
        for p in grid.chain(across).chain(along) {
            let vis = frame.plane_visibility_at(ground, p).expect("the plane's material is a ground's");
            let full = frame.shade(p, Vec3::Z, Vec3::new(0.2, -0.4, 0.9).normalize(), &lambert, 1.0, vis, false);
            let fast = frame.shade_ground(ground, p, albedo).expect("a ground");
            let sun = sun_lamp.visibility(p, Vec3::Z);
            let at = locate(plane.grid_uv(p.x, p.y));
            let lattice = plane.grids.shades[0].at(at.j * PLANE_CELLS + at.i, at.t).unwrap_or(1.0);
            let expected = full - sun_term * (sun - lattice);
            assert!(
                (expected - fast).abs().max_element() <= 1e-5 * (1.0 + full.max_element()),
                "{p}: {expected} vs {fast}"
            );
            worst = worst.max((sun - lattice).abs());
            (shadowed, open) = (shadowed + (sun == 0.0) as u32, open + (sun == 1.0) as u32);
        }
        // Both sides of the sun's shadow were compared, and the shortcut skipped the sun's lookup in most cells
        // but not near the shadow (the point light, a perspective map, always looks up).
        assert!(shadowed > 1000 && open > 8500, "{shadowed} in shadow, {open} open");
        // The lattice's smooth lookup and the pixel's agree but for the latter's steps in the penumbra.
        assert!(worst > 0.0 && worst < 0.2, "{worst}");
        let cells = &frame.planes[0].open;
        let skipped = cells[0].iter().filter(|&&o| o).count();
        assert!(skipped > cells[0].len() / 2 && skipped < cells[0].len(), "{skipped} of {}", cells[0].len());
        assert!(cells[1].is_empty());
        // Only a ground plane's material takes the shortcut.
        assert!(frame.shade_ground(scene.primitives[1].material, Vec3::ZERO, albedo).is_none());
    }

    #[test]
    fn point_and_spot_lights_bounce_off_the_ground() {
        // A 200 W point light 1 m over the middle of a ground of 0.5 under a black sky: a face a centimetre over
        // the ground, looking down, sees the ground's reflection of it, 0.5 · E / π with E = P · cos / (4π d²)
        // (Blender's units: a white surface shows P / (4π² d²)): straight below, d = 1; 1.5 m aside, d² = 3.25
        // and cos = 1/√3.25. A spot there aiming down, its cone wide, is that point light times the cosine off
        // its axis (1 straight below, 1/√3.25 aside).
        let plane = crate::scene::input::Ground { size: [4.0, 4.0], color: [0.5, 0.5, 0.5], z: None };
        let mut scene = PosedScene::default();
        crate::scene::merge(&[crate::scene::source::ground(&plane, 0.0)], &mut scene);
        let position = Vec3::new(0.0, 0.0, 1.0);
        let radiance = |d2: f32, cos: f32| 0.5 * 200.0 * cos / (4.0 * PI * d2) / PI;
        let (point, spot) = (
            LightKind::Point { position, radius: 0.05 },
            LightKind::Spot { position, direction: -Vec3::Z, cone: 170f32.to_radians(), blend: 0.0, radius: 0.05 },
        );
        for (kind, off_axis) in [(point, 1.0), (spot, 1.0 / 3.25f32.sqrt())] {
            let lamp = Light { kind, color: Vec3::ONE, intensity: 200.0, shadows: true };
            let mut env = crate::render::Environment::default().studio();
            env.strength = 0.0;
            let frame = FrameLight::prepare(&scene, &[lamp], env, PointCasters::NONE);
            let below = frame.below(Vec3::new(0.0, 0.0, 0.01), -Vec3::Z);
            assert!((below.x / radiance(1.0, 1.0) - 1.0).abs() < 0.01, "{kind:?}: {below}");
            let aside = frame.below(Vec3::new(1.5, 0.0, 0.01), -Vec3::Z);
            let want = radiance(3.25, 1.0 / 3.25f32.sqrt()) * off_axis;
            assert!((aside.x / want - 1.0).abs() < 0.02, "{kind:?}: {aside} vs {want}");
        }
    }
}
