//! Lit (`pbr`) shading: lights in Blender's units, an HDR environment, shadows, and the glTF metallic-roughness
//! BRDF ([`brdf`]). Everything that does not depend on the camera — shadow maps, the environment's visibility
//! at every vertex — is prepared once per posed frame ([`FrameLight::prepare`]) and shared by every view.
//!
//! Units are Blender's, measured against Cycles 3.4: a sun of strength S W/m² gives a white Lambertian surface
//! facing it the value S/π; a point light of P W at distance d gives P/(4π²d²); a spot is a point light times
//! the cosine of the angle off its axis, faded over `blend` (Blender 3.x's spot falloff); an environment of
//! radiance L lights a white Lambertian surface to L.

pub mod brdf;
pub mod environment;
pub mod shadow;

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Mat3, Vec3};
use rayon::prelude::*;

pub use crate::scene::light::{Light, LightKind};
use crate::scene::{PosedScene, PrimKind};
pub use brdf::Surface;
pub use environment::{EnvMap, Prefiltered};
use shadow::ShadowMap;

/// Side of a sun's shadow map, of a spot's, and of each face of a point light's cube.
const SUN_MAP: u32 = 2048;
const SPOT_MAP: u32 = 1024;
const POINT_MAP: u32 = 512;
/// Directions the environment's visibility is sampled in, and the side of each direction's map.
const ENV_DIRECTIONS: usize = 32;
/// Each direction stands for a cone of the sphere's 1/32 (half-angle acos(1 − 1/16) ≈ 20.4°): its shadows are
/// as soft as a light that wide (the tangent of the half-angle), so 32 directions blend into one smooth occlusion
/// instead of 32 faint copies of the subject's outline.
const ENV_CONE: f32 = 0.372;
const ENV_MAP: u32 = 256;

/// The environment as one frame's shading reads it.
#[derive(Debug, Clone)]
pub struct EnvLight {
    /// Prefiltered lighting.
    pub prefiltered: Arc<Prefiltered>,
    /// Multiplier of its radiance.
    pub strength: f32,
    /// World → map frame: the lookup direction is `rotation · d` (a Mapping node rotating Z in Blender).
    pub rotation: Mat3,
    /// The full-resolution map, when it is the visible background.
    pub background: Option<Arc<EnvMap>>,
}

/// Version of baked point colours ([`FrameLight::bake`]): part of their keys.
pub const BAKE_SALT: &str = "bake 1";

/// Everything a frame's lit shading needs besides the camera.
#[derive(Debug)]
pub struct FrameLight {
    lights: Vec<Lamp>,
    env: EnvLight,
    /// The ground plane, when the scene has one: its height and the radiance it reflects (see [`Ground`]).
    ground: Option<Ground>,
    /// The environment's occlusion: directions over the sphere, each with its weight (the map's brightness there)
    /// and a parallel shadow map from it. Empty when nothing casts shadows.
    occlusion: Vec<(Vec3, f32, ShadowMap)>,
    /// Per primitive, per vertex: the fraction of the environment's light (weighted by where it comes from and
    /// by the vertex normal) that no caster blocks. Empty for point primitives.
    pub vertex_visibility: Vec<Vec<f32>>,
    /// The same fraction over each ground plane, on a grid (see [`PlaneVisibility`]).
    planes: Vec<PlaneVisibility>,
}

/// A light as a frame's shading reads it.
#[derive(Debug)]
struct Lamp {
    light: Light,
    /// Its shadow maps: none (no shadows), one (sun, spot) or a cube's six (point).
    maps: Vec<ShadowMap>,
    /// Its size as [`ShadowMap::visibility`] reads it: a sun's angular radius as a tangent, else its radius.
    size: f32,
}

impl Lamp {
    /// The unit direction toward the light from `p`, and the radiance it brings there per unit of its colour ×
    /// intensity (before shadows).
    #[inline]
    fn incidence(&self, p: Vec3) -> (Vec3, f32) {
        match self.light.kind {
            LightKind::Sun { direction, .. } => (-direction, 1.0),
            LightKind::Point { position, .. } => {
                let d = position - p;
                let d2 = d.length_squared().max(1e-8);
                (d / d2.sqrt(), 1.0 / (4.0 * PI * d2))
            }
            LightKind::Spot { position, direction, cone, blend, .. } => {
                let d = position - p;
                let d2 = d.length_squared().max(1e-8);
                let l = d / d2.sqrt();
                (l, spot_falloff(-l.dot(direction), cone, blend) / (4.0 * PI * d2))
            }
        }
    }

    /// The fraction of the light reaching `p` (unit normal `n`) past its shadow casters.
    #[inline]
    fn visibility(&self, p: Vec3, n: Vec3) -> f32 {
        match (self.light.kind, self.maps.len()) {
            (_, 0) => 1.0,
            (LightKind::Point { position, .. }, 6) => {
                self.maps[shadow::cube_face(p - position)].visibility(p, n, self.size)
            }
            _ => self.maps[0].visibility(p, n, self.size),
        }
    }
}

/// Cells along each side of a ground plane's visibility grid: about 3 cm on a 4 m plane, fine enough for a
/// subject's contact shadow to show.
const PLANE_CELLS: usize = 128;

/// The environment's visibility over a ground plane (the `plane` source: two triangles, receiving, casting
/// nothing), sampled on a grid of [`PLANE_CELLS`]² cells over its extent and read bilinearly. A plane's
/// vertices are only its corners, so it cannot carry its occlusion per vertex as other surfaces do; a grid
/// costs the same to prepare as a finely tessellated plane did and nothing to rasterize.
#[derive(Debug)]
struct PlaneVisibility {
    /// The plane's material (only a plane source's triangles cast no shadow, and each has its own material).
    material: u32,
    /// Corner of the grid (x, y) and the size of one cell.
    lo: glam::Vec2,
    cell: glam::Vec2,
    /// (PLANE_CELLS + 1)² values, rows along +y.
    vis: Vec<f32>,
    /// The environment's irradiance on the plane's top face (before its visibility): the same everywhere on it.
    sky: Vec3,
    /// Per light, per cell (rows along +y): whether the light's shadow surely misses the whole cell
    /// ([`ShadowMap::open_over`]), so its pixels need no shadow lookup. Empty for a light that cannot tell.
    open: Vec<Vec<bool>>,
}

impl PlaneVisibility {
    /// The visibility at world (x, y), bilinear between grid points, held at the edges.
    #[inline]
    fn at(&self, x: f32, y: f32) -> f32 {
        self.cell_at(x, y).1
    }

    /// The cell holding world (x, y) (edge cells hold what lies past the edges; index rows along +y) and the
    /// visibility there.
    #[inline]
    fn cell_at(&self, x: f32, y: f32) -> (usize, f32) {
        let n = PLANE_CELLS;
        let u = ((x - self.lo.x) / self.cell.x).clamp(0.0, n as f32);
        let v = ((y - self.lo.y) / self.cell.y).clamp(0.0, n as f32);
        let (i, j) = ((u as usize).min(n - 1), (v as usize).min(n - 1));
        let (tu, tv) = (u - i as f32, v - j as f32);
        let row = |j: usize| {
            let a = self.vis[j * (n + 1) + i];
            a + (self.vis[j * (n + 1) + i + 1] - a) * tu
        };
        let (a, b) = (row(j), row(j + 1));
        (j * n + i, a + (b - a) * tv)
    }
}

/// A ground plane's first bounce: a receiving-only diffuse plane (the `plane` source) stands in for the map
/// below the horizon, as it does in a path tracer. Points above it receive the sky from the map and, from below,
/// the plane's outgoing radiance (its albedo under the sky and the suns, unshadowed), as from an infinite plane:
/// E(n) = π·L·(1 − n_z)/2. Point and spot lights do not enter the bounce.
#[derive(Debug, Clone, Copy)]
struct Ground {
    z: f32,
    radiance: Vec3,
}

impl Ground {
    /// The scene's ground: the first of its [`ground_planes`].
    fn find(scene: &PosedScene, lights: &[&Light], env: &EnvLight) -> Option<Ground> {
        let prim = ground_planes(scene).next()?;
        let albedo = scene.material(prim.material).base_color.truncate();
        let mut e = env.prefiltered.sky_irradiance(Vec3::Z) * env.strength;
        for l in lights {
            if let LightKind::Sun { direction, .. } = l.kind {
                e += l.color * (l.intensity * (-direction.z).max(0.0));
            }
        }
        Some(Ground { z: prim.positions[0].z, radiance: albedo * e / PI })
    }
}

/// The scene's ground planes: triangles whose material casts no shadow (only a plane source's does).
fn ground_planes(scene: &PosedScene) -> impl Iterator<Item = &crate::scene::PosedPrimitive> {
    scene.primitives.iter().filter(|p| {
        p.kind == PrimKind::Triangles
            && !p.positions.is_empty()
            && scene.materials.get(p.material as usize).is_some_and(|m| !m.casts_shadows)
    })
}

/// Bounds of the geometry that casts shadows.
fn caster_bounds(scene: &PosedScene) -> Option<(Vec3, Vec3)> {
    let mut it = scene
        .primitives
        .iter()
        .filter(|p| p.kind == PrimKind::Triangles)
        .filter(|p| scene.materials.get(p.material as usize).is_none_or(|m| m.casts_shadows))
        .flat_map(|p| p.positions.iter());
    let first = *it.next()?;
    Some(it.fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))))
}

/// `n` directions spread evenly over the sphere (a Fibonacci lattice).
fn sphere_directions(n: usize) -> Vec<Vec3> {
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f32 + 1.0) / n as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = i as f32 * PI * (3.0 - 5f32.sqrt());
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

impl FrameLight {
    /// Prepares the lights and environment for one posed frame: shadow maps of every shadowing light (`lights`,
    /// the manifest's, then the scene's own), and the environment's visibility at every vertex.
    pub fn prepare(scene: &PosedScene, lights: &[Light], env: EnvLight) -> FrameLight {
        let bounds = caster_bounds(scene);
        let all: Vec<&Light> = lights.iter().chain(&scene.lights).collect();
        // The lights' maps and the environment's are made side by side (a single sun's 2048² map would otherwise
        // keep one core busy while the other waits).
        let light_maps = || {
            all.par_iter()
                .map(|l| {
                    let maps = match (l.shadows, bounds) {
                        (true, Some(b)) => match l.kind {
                            LightKind::Sun { direction, .. } => vec![ShadowMap::sun(scene, direction, b, SUN_MAP)],
                            LightKind::Spot { position, direction, cone, .. } => {
                                vec![ShadowMap::perspective(scene, position, direction, cone + 0.05, SPOT_MAP)]
                            }
                            LightKind::Point { position, .. } => shadow::CUBE
                                .iter()
                                .map(|&d| ShadowMap::perspective(scene, position, d, PI / 2.0 + 0.02, POINT_MAP))
                                .collect(),
                        },
                        _ => Vec::new(),
                    };
                    let size = match l.kind {
                        LightKind::Sun { angle, .. } => (0.5 * angle).tan(),
                        LightKind::Point { radius, .. } | LightKind::Spot { radius, .. } => radius,
                    };
                    Lamp { light: (*l).clone(), maps, size }
                })
                .collect()
        };
        let env_maps = || match bounds {
            Some(b) => occlusion_maps(scene, &env, b),
            None => Vec::new(),
        };
        let (lights, occlusion) = rayon::join(light_maps, env_maps);
        let ground = Ground::find(scene, &all, &env);
        let mut light =
            FrameLight { lights, env, ground, occlusion, vertex_visibility: Vec::new(), planes: Vec::new() };
        light.vertex_visibility = scene
            .primitives
            .iter()
            .map(|prim| match prim.kind {
                PrimKind::Triangles => prim
                    .positions
                    .par_iter()
                    .zip(prim.normals.par_iter())
                    .map(|(&p, &n)| light.environment_visibility(p, n))
                    .collect(),
                PrimKind::Points => Vec::new(),
            })
            .collect();
        light.planes =
            ground_planes(scene).map(|prim| light.plane_visibility(prim.material, &prim.positions)).collect();
        light
    }

    /// The environment's visibility over the plane through `corners` (horizontal, facing +Z).
    fn plane_visibility(&self, material: u32, corners: &[Vec3]) -> PlaneVisibility {
        let lo = corners.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let hi = corners.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        let n = PLANE_CELLS;
        let cell = (hi - lo).truncate().max(glam::Vec2::splat(1e-6)) / n as f32;
        let vis = (0..(n + 1) * (n + 1))
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k % (n + 1), k / (n + 1));
                let p = Vec3::new(lo.x + cell.x * i as f32, lo.y + cell.y * j as f32, lo.z);
                self.environment_visibility(p, Vec3::Z)
            })
            .collect();
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
                        let a = Vec3::new(lo.x + cell.x * i as f32, lo.y + cell.y * j as f32, lo.z) - margin;
                        let b =
                            Vec3::new(lo.x + cell.x * (i + 1) as f32, lo.y + cell.y * (j + 1) as f32, lo.z) + margin;
                        let corners: [Vec3; 8] = std::array::from_fn(|c| {
                            Vec3::new([a.x, b.x][c & 1], [a.y, b.y][(c >> 1) & 1], [a.z, b.z][c >> 2])
                        });
                        map.open_over(&corners, Vec3::Z, lamp.size)
                    })
                    .collect(),
                _ => Vec::new(),
            })
            .collect();
        PlaneVisibility { material, lo: lo.truncate(), cell, vis, sky: self.irradiance(lo, Vec3::Z), open }
    }

    /// The environment's visibility at world point `p` of a surface of material `material`, when that is a
    /// ground plane's (whose visibility is a grid, not per vertex).
    #[inline]
    pub fn plane_visibility_at(&self, material: u32, p: Vec3) -> Option<f32> {
        self.planes.iter().find(|g| g.material == material).map(|g| g.at(p.x, p.y))
    }

    /// The fraction of the environment's light (weighted by where it comes from and by the cosine to `n`) that
    /// reaches `p` past the casters. The hemisphere `n` faces is the one that counts (a double-sided surface seen
    /// from behind, such as the ground's underside, is shaded with its front's visibility).
    pub fn environment_visibility(&self, p: Vec3, n: Vec3) -> f32 {
        let (mut lit, mut all) = (0.0, 0.0);
        for (d, w, m) in &self.occlusion {
            let c = n.dot(*d) * w;
            if c <= 0.0 {
                continue;
            }
            all += c;
            lit += c * m.visibility(p, n, ENV_CONE);
        }
        if all > 0.0 {
            lit / all
        } else {
            1.0
        }
    }

    /// A view-independent ("baked") colour at world point `p` with unit normal `n`: the Lambertian surface of
    /// colour `albedo` under every light, with their shadows, and the environment with its occlusion at `p`,
    /// plus `emission`. What a `ply-sequence` with `color = "lit"` writes; a point without a normal keeps its
    /// albedo.
    pub fn bake(&self, p: Vec3, n: Vec3, albedo: Vec3, emission: Vec3) -> Vec3 {
        if n == Vec3::ZERO {
            return albedo + emission;
        }
        let s = Surface { base: albedo, metallic: 0.0, roughness: 1.0, specular: 0.0 };
        self.shade(p, n, n, &s, 1.0, self.environment_visibility(p, n)) + emission
    }

    /// Outgoing radiance (linear RGB) at world point `p` with unit shading normal `n`, seen from unit direction
    /// `v` (toward the eye), for surface `s`, with ambient occlusion `ao` (the material's) and the environment's
    /// visibility `env_vis` (interpolated from the vertices).
    pub fn shade(&self, p: Vec3, n: Vec3, v: Vec3, s: &Surface, ao: f32, env_vis: f32) -> Vec3 {
        let mut out = Vec3::ZERO;
        for lamp in &self.lights {
            let (l, radiance) = lamp.incidence(p);
            let f = s.eval(n, v, l);
            if f == Vec3::ZERO || radiance == 0.0 {
                continue;
            }
            let light = &lamp.light;
            out += f * light.color * (radiance * light.intensity * lamp.visibility(p, n));
        }
        // Environment: irradiance for the diffuse layer, the split sum for the specular one.
        let e = &self.env;
        // A purely diffuse surface (the ground) reads no specular lobe: skip its lookups, which would add zero.
        let w = s.specular_weight();
        let spec_f = if w > 0.0 {
            let ab = brdf::dfg(n.dot(v).max(1e-4), s.roughness);
            (s.f0() * ab.x + Vec3::splat(ab.y)) * w
        } else {
            Vec3::ZERO
        };
        let irradiance = self.irradiance(p, n);
        let diffuse = s.diffuse() * (Vec3::ONE - spec_f) * (irradiance / PI);
        let specular = if w > 0.0 {
            let r = 2.0 * n.dot(v) * n - v;
            let mut l = e.prefiltered.specular(e.rotation * r, s.roughness) * e.strength;
            // Above a ground, reflections below the horizon see the ground, not the map's lower half: blended
            // in over a band that widens with roughness (the lobe straddles the horizon).
            if let Some(g) = self.ground.filter(|g| p.z >= g.z - 1e-3 && r.z < 0.0) {
                let x = (-r.z / (0.05 + s.roughness)).min(1.0);
                l = l.lerp(g.radiance, x * x * (3.0 - 2.0 * x));
            }
            spec_f * l
        } else {
            Vec3::ZERO
        };
        out + (diffuse + specular) * (ao * env_vis)
    }

    /// The environment's irradiance at world point `p` on a surface of unit normal `n`, before occlusion.
    #[inline]
    fn irradiance(&self, p: Vec3, n: Vec3) -> Vec3 {
        let e = &self.env;
        match self.ground {
            // On or above the ground (within a millimetre: the plane itself sees the sky alone): the sky from the
            // map, the ground's bounce from below.
            Some(g) if p.z >= g.z - 1e-3 => {
                e.prefiltered.sky_irradiance(e.rotation * n) * e.strength + g.radiance * (PI * 0.5 * (1.0 - n.z))
            }
            _ => e.prefiltered.irradiance(e.rotation * n) * e.strength,
        }
    }

    /// [`FrameLight::shade`] of the top face (normal +Z) of ground plane material `material`, when it is one,
    /// at world point `p`, for a Lambertian surface of colour `albedo` (no specular layer, no occlusion
    /// texture): what a `plane` source is. Such a face looks the same from every view, and all but its shadows
    /// and occlusion is the same everywhere on it, so the environment's share was found once per frame.
    #[inline]
    pub fn shade_ground(&self, material: u32, p: Vec3, albedo: Vec3) -> Option<Vec3> {
        let g = self.planes.iter().find(|g| g.material == material)?;
        let (cell, vis) = g.cell_at(p.x, p.y);
        let mut e = g.sky * vis;
        for (lamp, open) in self.lights.iter().zip(&g.open) {
            let (l, radiance) = lamp.incidence(p);
            if l.z <= 0.0 || radiance == 0.0 {
                continue;
            }
            let light = &lamp.light;
            let vis = if open.get(cell) == Some(&true) { 1.0 } else { lamp.visibility(p, Vec3::Z) };
            e += light.color * (radiance * light.intensity * vis * l.z);
        }
        Some(albedo * e / PI)
    }

    /// The visible background's radiance along world direction `d`, when the environment is visible.
    #[inline]
    pub fn background(&self, d: Vec3) -> Option<Vec3> {
        let map = self.env.background.as_ref()?;
        Some(map.radiance(self.env.rotation * d) * self.env.strength)
    }

    /// Whether the environment shows as the background.
    pub fn has_background(&self) -> bool {
        self.env.background.is_some()
    }
}

/// Blender 3.x's spot falloff at `cos_angle` off the axis: the cosine itself inside the cone, smoothed to 0 over
/// the outer `blend` fraction.
fn spot_falloff(cos_angle: f32, cone: f32, blend: f32) -> f32 {
    let cos_half = (0.5 * cone).cos();
    let t = cos_angle - cos_half;
    if t <= 0.0 {
        return 0.0;
    }
    let smooth = (1.0 - cos_half) * blend;
    let mut a = cos_angle;
    if t < smooth {
        let x = t / smooth;
        a *= x * x * (3.0 - 2.0 * x);
    }
    a
}

/// The environment's occlusion maps: [`ENV_DIRECTIONS`] parallel shadow maps from directions over the sphere,
/// each weighted by the environment's brightness there (so a bright sky above shadows more than a dark floor).
fn occlusion_maps(scene: &PosedScene, env: &EnvLight, bounds: (Vec3, Vec3)) -> Vec<(Vec3, f32, ShadowMap)> {
    let roughest = env.prefiltered.levels.last();
    sphere_directions(ENV_DIRECTIONS)
        .par_iter()
        .map(|&d| {
            let w =
                roughest.map_or(1.0, |m| m.radiance(env.rotation * d).dot(Vec3::new(0.2126, 0.7152, 0.0722))).max(1e-6);
            (d, w, ShadowMap::sun(scene, -d, bounds, ENV_MAP))
        })
        .collect()
}

impl Surface {
    /// How much of the Fresnel-weighted specular layer is present: all of it for metals, `specular` for
    /// dielectrics (0 makes a Lambertian surface).
    #[inline]
    pub fn specular_weight(&self) -> f32 {
        self.specular + (1.0 - self.specular) * self.metallic
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grounds_shortcut_shades_as_the_full_model_does_in_and_out_of_shadow() {
        // A ground plane and a square caster over it, under a soft oblique sun, a point light and the studio map.
        let plane = crate::manifest::source::Plane { size: [4.0, 4.0], color: [0.7, 0.6, 0.5], z: None };
        let h = 0.3;
        let caster = PosedScene::single(
            PrimKind::Triangles,
            vec![Vec3::new(-h, -h, 1.0), Vec3::new(h, -h, 1.0), Vec3::new(h, h, 1.0), Vec3::new(-h, h, 1.0)],
            vec![Vec3::Z; 4],
            Vec::new(),
            vec![0, 1, 2, 0, 2, 3],
            crate::scene::material::Material::default(),
        );
        let mut scene = PosedScene::default();
        crate::scene::merge(&[crate::scene::source::ground(&plane, 0.0), caster], &mut scene);
        let light = |kind| Light { kind, color: Vec3::new(1.0, 0.9, 0.8), intensity: 3.0, shadows: true };
        let lights = [
            light(LightKind::Sun { direction: Vec3::new(0.3, 0.2, -1.0).normalize(), angle: 0.05 }),
            light(LightKind::Point { position: Vec3::new(-1.0, 0.5, 2.0), radius: 0.1 }),
        ];
        let frame = FrameLight::prepare(&scene, &lights, crate::render::Environment::default().studio());
        let ground = scene.primitives[0].material;
        let albedo = Vec3::new(0.7, 0.6, 0.5);
        let lambert = Surface { base: albedo, metallic: 0.0, roughness: 0.5, specular: 0.0 };
        let (mut shadowed, mut open) = (0, 0);
        // A grid over the whole plane, and two lines a millimetre apart across the shadow's edges (the square's
        // shadow is the square moved by (0.3, 0.2): x in 0..0.6, y in −0.1..0.5), through its penumbra.
        let grid =
            (0..10_000).map(|i| Vec3::new(-1.98 + (i % 100) as f32 * 0.04, -1.98 + (i / 100) as f32 * 0.04, 0.0));
        let across = (0..1000).map(|i| Vec3::new(-0.2 + i as f32 * 1e-3, 0.2, 0.0));
        let along = (0..1000).map(|i| Vec3::new(0.3, -0.3 + i as f32 * 1e-3, 0.0));
        for p in grid.chain(across).chain(along) {
            let vis = frame.plane_visibility_at(ground, p).expect("the plane's material is a ground's");
            let full = frame.shade(p, Vec3::Z, Vec3::new(0.2, -0.4, 0.9).normalize(), &lambert, 1.0, vis);
            let fast = frame.shade_ground(ground, p, albedo).expect("a ground");
            assert!((full - fast).abs().max_element() <= 1e-5 * (1.0 + full.max_element()), "{p}: {full} vs {fast}");
            let sun = frame.lights[0].visibility(p, Vec3::Z);
            (shadowed, open) = (shadowed + (sun == 0.0) as u32, open + (sun == 1.0) as u32);
        }
        // Both sides of the sun's shadow were compared, and the shortcut skipped the sun's lookup in most cells
        // but not near the shadow (the point light, a perspective map, always looks up).
        assert!(shadowed > 1000 && open > 8500, "{shadowed} in shadow, {open} open");
        let cells = &frame.planes[0].open;
        let skipped = cells[0].iter().filter(|&&o| o).count();
        assert!(skipped > cells[0].len() / 2 && skipped < cells[0].len(), "{skipped} of {}", cells[0].len());
        assert!(cells[1].is_empty());
        // Only a ground plane's material takes the shortcut.
        assert!(frame.shade_ground(scene.primitives[1].material, Vec3::ZERO, albedo).is_none());
    }

    #[test]
    fn blenders_spot_is_its_point_light_times_the_cosine_inside_the_cone() {
        let cone = 120f32.to_radians();
        assert!((spot_falloff(1.0, cone, 0.0) - 1.0).abs() < 1e-6);
        assert!((spot_falloff(0.9, cone, 0.0) - 0.9).abs() < 1e-6);
        assert_eq!(spot_falloff(0.4, cone, 0.0), 0.0);
        // Blend fades toward the edge.
        assert!(spot_falloff(0.55, cone, 1.0) < 0.1);
    }
}
