//! Lit (`pbr`) shading: lights in Blender's units, an HDR environment, shadows, and the glTF metallic-roughness
//! BRDF ([`brdf`]). Everything that does not depend on the camera — shadow maps, the environment's visibility
//! at every vertex — is prepared once per posed frame ([`FrameLight::prepare`]) and shared by every view.
//!
//! Units are Blender's, measured against Cycles 3.4: a sun of strength S W/m² gives a white Lambertian surface
//! facing it the value S/π; a point light of P W at distance d gives P/(4π²d²); a spot is a point light times
//! the cosine of the angle off its axis, faded over `blend` (Blender 3.x's spot falloff); an environment of
//! radiance L lights a white Lambertian surface to L.

mod bake;
mod bounce;
pub mod brdf;
mod cutout;
pub mod environment;
mod gathered;
mod ground;
mod lamp;
mod lobe;
mod occlusion;
mod pcf;
mod penumbra;
mod plane_grid;
mod pyramid;
mod rays;
mod scan;
pub mod shadow;
mod sides;

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Mat3, Vec3};
use rayon::prelude::*;

pub use crate::scene::light::{Light, LightKind};
use crate::scene::{PosedPrimitive, PosedScene, PrimKind};
pub use bake::BAKE_SALT;
pub use brdf::Surface;
pub use environment::{EnvMap, Prefiltered};
pub use gathered::{Gathered, GatheredError};
use ground::{ground_planes, Ground};
use lamp::{lamps, Lamp};
use lobe::may_be_glossy;
pub use lobe::{glossy, Lobe};
use occlusion::occlusion_maps;
use plane_grid::PlaneVisibility;
pub use shadow::PointCasters;
use shadow::ShadowMap;
pub use sides::two_sided;

/// What reaches a surface point of the environment's light: interpolated across a triangle from its vertices,
/// like any vertex attribute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Visibility {
    /// The fraction of the environment's light (weighted by where it comes from and by the normal) that no
    /// caster blocks.
    pub env: f32,
    /// Above a ground: the radiance arriving from below the horizon, averaged over the cosine lobe — the
    /// ground's, its shadows in it, and past its edges the map's (see `FrameLight::below`). Unread without a
    /// ground.
    pub below: Vec3,
    /// The irradiance the subject's own parts reflect onto the point, all [`bounce::BOUNCES`] bounces of it
    /// (see [`bounce`]); zero on a ground plane and on points.
    pub bounce: Vec3,
}

impl Visibility {
    /// In the open, without a ground.
    pub const OPEN: Visibility = Visibility { env: 1.0, below: Vec3::ZERO, bounce: Vec3::ZERO };

    /// The linear blend `self` → `o` at `t`.
    #[inline]
    pub fn lerp(self, o: Visibility, t: f32) -> Visibility {
        Visibility {
            env: self.env + (o.env - self.env) * t,
            below: self.below.lerp(o.below, t),
            bounce: self.bounce.lerp(o.bounce, t),
        }
    }

    /// The blend of three vertices' by barycentric weights `k`.
    #[inline]
    pub fn blend(v: &[Visibility; 3], k: [f32; 3]) -> Visibility {
        Visibility {
            env: v[0].env * k[0] + v[1].env * k[1] + v[2].env * k[2],
            below: v[0].below * k[0] + v[1].below * k[1] + v[2].below * k[2],
            bounce: v[0].bounce * k[0] + v[1].bounce * k[1] + v[2].bounce * k[2],
        }
    }
}

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

/// Everything a frame's lit shading needs besides the camera.
#[derive(Debug)]
pub struct FrameLight {
    lights: Vec<Lamp>,
    env: EnvLight,
    /// The ground plane, when the scene has one: its height and the radiance it reflects (see [`Ground`]).
    ground: Option<Ground>,
    /// What lit radiance is multiplied by before it is encoded: 2^exposure.
    exposure: f32,
    /// The view transform baked colours are displayed through (images apply theirs when they are resolved).
    view: super::Display,
    /// The environment's occlusion: directions over the sphere, each with its weight (the map's brightness there)
    /// and a parallel shadow map from it. Empty when nothing casts shadows.
    occlusion: Vec<(Vec3, f32, ShadowMap)>,
    /// Per primitive, per vertex: what reaches it of the environment's light ([`Visibility`], by the vertex
    /// normal), then, for a primitive that gathers on both sides ([`sides`]), per vertex its back side's (by the
    /// reversed normal).
    /// Empty for point primitives.
    pub vertex_visibility: Vec<Vec<Visibility>>,
    /// The light over each ground plane, on a grid (see [`PlaneVisibility`]).
    planes: Vec<PlaneVisibility>,
    /// The frame's casters in a ray-tracing tree, when a surface may be glossy enough to look its reflection's
    /// occlusion up with rays ([`rays::Tracer::lobe_visibility`]): made by [`FrameLight::from_gathered`], or the
    /// gather's ([`FrameLight::with_bounce`]). A light only prepared has none (it bakes points, which have no
    /// specular layer).
    tracer: Option<Arc<rays::Tracer>>,
}

/// Whether primitive `p` casts shadows, and so occludes and reflects light onto others: triangles whose material
/// casts them (every material but a `plane` source's).
fn is_caster(scene: &PosedScene, p: &PosedPrimitive) -> bool {
    p.kind == PrimKind::Triangles
        && scene.materials.get(p.material as usize).is_none_or(|m| m.casts_shadows && !m.unlit)
}

/// Bounds of the geometry that casts shadows.
fn caster_bounds(scene: &PosedScene) -> Option<(Vec3, Vec3)> {
    let mut it = scene.primitives.iter().filter(|p| is_caster(scene, p)).flat_map(|p| p.positions.iter());
    let first = *it.next()?;
    Some(it.fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))))
}

/// Bounds of what casts into shadow maps: [`caster_bounds`] with the casting points' footprints (plain points
/// casting as `points` says, 3D Gaussians by their cores), which rays do not meet.
fn shadow_bounds(scene: &PosedScene, points: PointCasters) -> Option<(Vec3, Vec3)> {
    match (caster_bounds(scene), shadow::point_bounds(scene, points)) {
        (Some((a, b)), Some((c, d))) => Some((a.min(c), b.max(d))),
        (a, b) => a.or(b),
    }
}

impl FrameLight {
    /// Prepares the lights and environment for one posed frame: shadow maps of every shadowing light (`lights`,
    /// the manifest's, then the scene's own), and the environment's visibility at every vertex. Plain points
    /// cast shadows as `points` says (as images draw them), 3D Gaussians by their cores.
    pub fn prepare(scene: &PosedScene, lights: &[Light], env: EnvLight, points: PointCasters) -> FrameLight {
        let bounds = shadow_bounds(scene, points);
        // The lights' maps and the environment's are made side by side (a single sun's 2048² map would otherwise
        // keep one core busy while the other waits).
        let env_maps = || match bounds {
            Some(b) => occlusion_maps(scene, &env, b, points),
            None => Vec::new(),
        };
        let (lamps, occlusion) = rayon::join(|| lamps(scene, lights, bounds, points), env_maps);
        let mut light = FrameLight::bare(scene, lights, lamps, env);
        light.occlusion = occlusion;
        // The planes first: a vertex's bounce reads them.
        light.planes =
            ground_planes(scene).map(|prim| light.plane_visibility(prim.material, &prim.positions)).collect();
        let lit = &light;
        let vertex_visibility = scene
            .primitives
            .iter()
            .map(|prim| match prim.kind {
                PrimKind::Triangles => {
                    let side = |s: f32| {
                        let normals = prim.normals.par_iter();
                        prim.positions.par_iter().zip(normals).map(move |(&p, &n)| lit.visibility(p, n * s))
                    };
                    let mut v: Vec<Visibility> = side(1.0).collect();
                    if sides::sides(scene, prim) == 2 {
                        v.par_extend(side(-1.0));
                    }
                    v
                }
                PrimKind::Points => Vec::new(),
            })
            .collect();
        light.vertex_visibility = vertex_visibility;
        light
    }

    /// The lighting of a frame with its lights' shadow maps `lamps` and nothing else prepared.
    fn bare(scene: &PosedScene, lights: &[Light], lamps: Vec<Lamp>, env: EnvLight) -> FrameLight {
        let all: Vec<&Light> = lights.iter().chain(&scene.lights).collect();
        let ground = Ground::find(scene, &all, &env);
        FrameLight {
            lights: lamps,
            env,
            ground,
            exposure: 1.0,
            view: super::Display::new(super::ViewTransform::Standard),
            occlusion: Vec::new(),
            vertex_visibility: Vec::new(),
            planes: Vec::new(),
            tracer: None,
        }
    }

    /// The lighting of a frame whose light action found `g` ([`FrameLight::gather`] of the same frame, lights
    /// and environment): only the lights' shadow maps are made again, which pixels read; the environment's
    /// occlusion, which only the vertices and the ground's grids read, is not. `points` must be what the light
    /// action cast with. An error names what does not fit the frame.
    pub fn from_gathered(
        scene: &PosedScene,
        lights: &[Light],
        env: EnvLight,
        points: PointCasters,
        g: Gathered,
    ) -> Result<FrameLight, GatheredError> {
        let fits = scene.primitives.len() == g.vertices.len()
            && scene.primitives.iter().zip(&g.vertices).all(|(prim, v)| match prim.kind {
                PrimKind::Triangles => {
                    let n = prim.positions.len();
                    v.len() == n || (v.len() == 2 * n && two_sided(scene, prim))
                }
                PrimKind::Points => v.is_empty(),
            })
            && ground_planes(scene).count() == g.planes.len();
        if !fits {
            return Err(GatheredError::OtherScene);
        }
        let mut light =
            FrameLight::bare(scene, lights, lamps(scene, lights, shadow_bounds(scene, points), points), env);
        light.tracer = may_be_glossy(scene).then(|| rays::Tracer::of(scene, rays::Rays::Few).map(Arc::new)).flatten();
        light.vertex_visibility = g.vertices;
        light.planes = ground_planes(scene)
            .zip(g.planes)
            .map(|(prim, grids)| light.assemble(prim.material, &prim.positions, grids))
            .collect();
        Ok(light)
    }

    /// This lighting with what the subject reflects onto itself and onto the ground gathered ([`bounce`]): what
    /// rendered meshes read (a baked point has no vertices to gather at, and estimates it instead).
    pub fn with_bounce(mut self, scene: &PosedScene) -> FrameLight {
        let Some(subject) = bounce::Subject::of(scene, &self.vertex_visibility) else {
            return self;
        };
        // The gather's tree serves the glossy lobes' rays too, as a render's does (`from_gathered`).
        if may_be_glossy(scene) {
            self.tracer = Some(subject.tracer());
        }
        let gathered = subject.gather(scene, &self);
        for (i, vis) in self.vertex_visibility.iter_mut().enumerate() {
            if vis.is_empty() {
                continue;
            }
            for (v, b) in vis.iter_mut().zip(&gathered.bounce[subject.serials(scene, i)]) {
                v.bounce = *b;
            }
        }
        let z = self.ground.map_or(0.0, |g| g.z);
        for plane in &mut self.planes {
            // The bounce varies over the subject's size, not a cell's: gathered on every fourth grid point,
            // spread between them, then blurred over about five, where far from the subject a point's rays meet
            // it by chance or not (that noise falls under 1/255).
            let coarse = subject.onto(scene, &gathered, &plane.points(z, plane_grid::BOUNCE_STRIDE), Vec3::Z);
            plane.grids.bounce = plane_grid::blur(&plane_grid::spread(&coarse, plane_grid::BOUNCE_STRIDE), 2);
            plane.combine(&self.lights);
        }
        self
    }

    /// What this frame's light holds that costs rays and shadow lookups and no camera changes: every vertex's
    /// [`Visibility`] with the bounce gathered, and the ground's grids. A build keeps it as the frame's light
    /// action and renders from it ([`FrameLight::from_gathered`]).
    pub fn gather(self, scene: &PosedScene) -> Gathered {
        let light = self.with_bounce(scene);
        Gathered { vertices: light.vertex_visibility, planes: light.planes.into_iter().map(|p| p.grids).collect() }
    }

    /// What reaches `p` (unit normal `n`) of the environment's light: see [`Visibility`].
    pub fn visibility(&self, p: Vec3, n: Vec3) -> Visibility {
        Visibility { env: self.environment_visibility(p, n), below: self.below(p, n), bounce: Vec3::ZERO }
    }

    /// The irradiance reaching `p` (unit normal `n`) straight from the lights, with their shadows, and from the
    /// environment past its occlusion `vis` (and the ground's bounce): all but what the subject reflects.
    pub(super) fn direct_irradiance(&self, p: Vec3, n: Vec3, vis: &Visibility) -> Vec3 {
        self.lights.iter().fold(self.irradiance(p, n, vis.below) * vis.env, |e, lamp| e + lamp.irradiance(p, n))
    }

    /// Outgoing radiance (linear RGB) at world point `p` with unit shading normal `n`, seen from unit direction
    /// `v` (toward the eye), for surface `s`, with ambient occlusion `ao` (the material's) and what reaches it
    /// of the environment's light, `vis` (interpolated from the vertices, with what the subject reflects onto
    /// it). `estimate_bounce`: where no gathered bounce is known (a baked point), whether what the casters block
    /// comes partly back to the diffuse layer by an estimate (`multi_bounce`) instead: yes on a subject, whose
    /// casters are mostly its own parts, of colours like its own.
    #[allow(clippy::too_many_arguments)]
    pub fn shade(
        &self,
        p: Vec3,
        n: Vec3,
        v: Vec3,
        s: &Surface,
        ao: f32,
        vis: Visibility,
        estimate_bounce: bool,
    ) -> Vec3 {
        self.shade_lobe(p, n, v, s, ao, vis, estimate_bounce, Lobe::Rays).0
    }

    /// [`FrameLight::shade`], and what the glossy lobe's rays found ([`rays::Tracer::lobe_visibility`]: the share of
    /// the lobe open to the environment) when it cast them; `lobe`: how that share is found ([`Lobe`]).
    #[allow(clippy::too_many_arguments)]
    pub fn shade_lobe(
        &self,
        p: Vec3,
        n: Vec3,
        v: Vec3,
        s: &Surface,
        ao: f32,
        vis: Visibility,
        estimate_bounce: bool,
        lobe: Lobe,
    ) -> (Vec3, Option<f32>) {
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
        let spec_f = if w > 0.0 { s.specular_albedo(n.dot(v).max(1e-4)) } else { Vec3::ZERO };
        let irradiance = self.irradiance(p, n, vis.below);
        let diffuse = s.diffuse() * (Vec3::ONE - spec_f) * (1.0 / PI);
        let occlusion = ao * vis.env;
        let mut traced = None;
        let specular = if w > 0.0 {
            let r = 2.0 * n.dot(v) * n - v;
            let mut l = e.prefiltered.specular(e.rotation * r, s.roughness) * e.strength;
            // Above a ground, the part of the lobe below the horizon sees the ground, not the map's lower half: its
            // light averaged over the lobe's footprint there (GGX's half vectors spread about α in tangent,
            // reflected directions twice that), so that the ground's shadows show, blurred with roughness, as a
            // path tracer's do (read at a point, they printed sharp patches on rough rubber). The lobe spans about
            // w = sin(atan 2α) in height about `r`, so the share of it below the horizon runs from none at
            // r.z = w to all at −w: that share of the map's radiance there is swapped for the ground's, both read
            // along the lobe's lower part (`r` lowered to at most −w/2). A glossy face looking at the horizon
            // reflects half ground: without it, FlightHelmet's stand seen from below was 30–40 % dark in green
            // and blue against Cycles, the sunlit ground it mirrors missing.
            let a = s.roughness.max(brdf::MIN_ROUGHNESS).powi(2);
            let w = (2.0 * a / (1.0 + 4.0 * a * a).sqrt()).max(1e-3);
            let x = (0.5 - r.z / (2.0 * w)).clamp(0.0, 1.0);
            let below = x * x * (3.0 - 2.0 * x);
            if below > 0.0 {
                // (A lobe pointing well down reads the map where it already has: `l` itself.)
                let lowered = r.z > -0.5 * w;
                let d = if lowered { Vec3::new(r.x, r.y, -0.5 * w).normalize() } else { r };
                if let Some((g, on)) = self.ground_seen(p, d, 2.0 * a) {
                    let map =
                        if lowered { e.prefiltered.specular(e.rotation * d, s.roughness) * e.strength } else { l };
                    l = (l + (g - map) * (below * on)).max(Vec3::ZERO);
                }
            }
            let (open, found) = self.lobe_occlusion(p, n, v, s.roughness, occlusion, lobe);
            traced = found;
            spec_f * l * open
        } else {
            Vec3::ZERO
        };
        // What the occluders block is not all lost: they reflect some of it back (interreflection, which a path
        // tracer follows). A mesh's vertices gathered it ([`bounce`]); a baked point estimates it by Jimenez et
        // al.'s multi-bounce fit ("Practical real-time strategies for accurate indirect occlusion", 2016), with
        // the surface's own colour standing in for its surroundings' (see `estimate_bounce`).
        let returned = if estimate_bounce { multi_bounce(occlusion, s.diffuse()) } else { Vec3::splat(occlusion) };
        // The specular layer sees the same occluders where its lobe is blocked: their mean radiance, which the
        // gathered irradiance over π is (for a rough lobe; a sharp one would see one of them).
        let bounce = vis.bounce.max(Vec3::ZERO) * ao;
        (out + diffuse * (irradiance * returned + bounce) + specular + spec_f * bounce * (1.0 / PI), traced)
    }

    /// Whether some surface of the frame may cast rays along its glossy lobe ([`FrameLight::shade_lobe`]).
    pub(crate) fn casts_rays(&self) -> bool {
        self.tracer.is_some()
    }

    /// The environment's irradiance at world point `p` on a surface of unit normal `n`, before occlusion, with
    /// `below` the radiance from below the horizon when there is a ground (see [`Visibility::below`]).
    #[inline]
    fn irradiance(&self, p: Vec3, n: Vec3, below: Vec3) -> Vec3 {
        let e = &self.env;
        match self.ground {
            // On or above the ground (within a millimetre: the plane itself sees the sky alone): the sky from the
            // map, the ground's bounce (and the map past its edges) from below.
            Some(g) if p.z >= g.z - 1e-3 => {
                e.prefiltered.sky_irradiance(e.rotation * n) * e.strength + below * (PI * 0.5 * (1.0 - n.z))
            }
            _ => e.prefiltered.irradiance(e.rotation * n) * e.strength,
        }
    }

    /// The visible background's radiance along world direction `d`, when the environment is visible.
    #[inline]
    pub fn background(&self, d: Vec3) -> Option<Vec3> {
        let map = self.env.background.as_ref()?;
        Some(map.radiance(self.env.rotation * d) * (self.env.strength * self.exposure))
    }

    /// This lighting seen with an exposure of `stops` (Blender's Color Management ▸ Exposure): what
    /// [`FrameLight::exposed`] and [`FrameLight::background`] multiply by. The prepared maps do not change.
    pub fn with_exposure(mut self, stops: f32) -> FrameLight {
        self.exposure = stops.exp2();
        self
    }

    /// This lighting's baked colours ([`FrameLight::bake`]) displayed through `view`, as the images' are.
    pub fn with_view(mut self, view: super::ViewTransform) -> FrameLight {
        self.view = super::Display::new(view);
        self
    }

    /// Lit radiance `c` as the image records it: times the exposure.
    #[inline]
    pub fn exposed(&self, c: Vec3) -> Vec3 {
        c * self.exposure
    }

    /// Whether the environment shows as the background.
    pub fn has_background(&self) -> bool {
        self.env.background.is_some()
    }
}

/// Visibility `v` (0..1) of the environment raised by what the occluders around a surface of colour `albedo`
/// reflect onto it: Jimenez et al.'s cubic fit to multi-bounce ambient occlusion, per channel, between `v` (no
/// interreflection, a black surrounding) and 1.
#[inline]
fn multi_bounce(v: f32, albedo: Vec3) -> Vec3 {
    let a = 2.0404 * albedo - Vec3::splat(0.3324);
    let b = -4.7951 * albedo + Vec3::splat(0.6417);
    let c = 2.7552 * albedo + Vec3::splat(0.6903);
    (((a * v + b) * v + c) * v).clamp(Vec3::splat(v), Vec3::ONE)
}

#[cfg(test)]
mod tests {
    use super::brdf::DIELECTRIC;
    use super::*;
    use crate::render::light::PointCasters;

    #[test]
    fn interreflection_gives_back_part_of_what_occluders_block_and_never_more() {
        for v in [0.0, 0.2, 0.5, 0.8, 1.0] {
            // Between the visibility itself and full light, rising with the surroundings' colour.
            let (black, grey, white) =
                (multi_bounce(v, Vec3::ZERO), multi_bounce(v, Vec3::splat(0.5)), multi_bounce(v, Vec3::ONE));
            assert!(
                black.x >= v && black.x <= grey.x && grey.x <= white.x && white.x <= 1.0,
                "{v}: {black} {grey} {white}"
            );
        }
        // Unoccluded stays unoccluded (the furnace test's white holds); a dark surrounding gives back little.
        assert_eq!(multi_bounce(1.0, Vec3::ONE), Vec3::ONE);
        assert!(multi_bounce(0.5, Vec3::splat(0.05)).x < 0.56);
        assert!(multi_bounce(0.5, Vec3::splat(0.9)).x > 0.7);
        // Per channel.
        let c = multi_bounce(0.5, Vec3::new(0.9, 0.5, 0.1));
        assert!(c.x > c.y && c.y > c.z);
    }

    #[test]
    fn a_glossy_face_mirrors_the_ground_in_the_share_of_its_lobe_below_the_horizon() {
        // A white metal (its specular layer only) half a metre over a 20 m ground, under an overhead sun and the
        // studio map: how much brighter it is over a ground of 0.8 than over a black one, per unit of the sunlit
        // ground's radiance and of the specular layer's weight, is the share of its lobe that meets the ground.
        let share = |z: f32| {
            let shade = |grey: f64| {
                let plane = crate::scene::input::Ground { size: [20.0, 20.0], color: [grey; 3], z: None };
                let mut scene = PosedScene::default();
                crate::scene::merge(&[crate::scene::source::ground(&plane, 0.0)], &mut scene);
                let sun = Light {
                    kind: LightKind::Sun { direction: -Vec3::Z, angle: 0.01 },
                    color: Vec3::ONE,
                    intensity: 3.0,
                    shadows: true,
                };
                let frame = FrameLight::prepare(
                    &scene,
                    &[sun],
                    crate::render::Environment::default().studio(),
                    PointCasters::NONE,
                );
                let metal = Surface { base: Vec3::ONE, metallic: 1.0, roughness: 0.5, specular: 0.5, f0: DIELECTRIC };
                // Facing +X, seen from the direction whose mirror image is (x, 0, z): the lobe's centre.
                let n = Vec3::X;
                let r = Vec3::new((1.0 - z * z).sqrt(), 0.0, z);
                let v = 2.0 * n.dot(r) * n - r;
                let out = frame.shade(Vec3::new(0.0, 0.0, 0.5), n, v, &metal, 1.0, Visibility::OPEN, false);
                (out, frame.ground.map(|g| g.radiance(glam::Vec2::ONE)), metal.specular_albedo(n.dot(v)))
            };
            let ((lit, ground, albedo), (black, _, _)) = (shade(0.8), shade(0.0));
            ((lit - black).x / ground.expect("a ground").x) / albedo.x
        };
        // Looking level with the horizon: half of it. Well above: none; well below: all of it.
        let level = share(0.0);
        assert!((level - 0.5).abs() < 0.05, "{level}");
        assert!(share(0.8).abs() < 0.01, "{}", share(0.8));
        assert!((share(-0.8) - 1.0).abs() < 0.05, "{}", share(-0.8));
    }

    #[test]
    fn a_frames_gathered_light_reads_back_as_it_was_and_refuses_other_bytes() {
        // A grey square over a ground under an overhead sun: it reflects light onto the ground (onto itself it
        // cannot: it is flat).
        let plane = crate::scene::input::Ground { size: [4.0, 4.0], color: [0.7, 0.6, 0.5], z: None };
        let h = 0.3;
        let caster = PosedScene::single(
            PrimKind::Triangles,
            vec![Vec3::new(-h, -h, 0.5), Vec3::new(h, -h, 0.5), Vec3::new(h, h, 0.5), Vec3::new(-h, h, 0.5)],
            vec![-Vec3::Z; 4],
            Vec::new(),
            vec![0, 2, 1, 0, 3, 2],
            crate::scene::material::Material::default(),
        );
        let mut scene = PosedScene::default();
        crate::scene::merge(&[crate::scene::source::ground(&plane, 0.0), caster], &mut scene);
        let sun = Light {
            kind: LightKind::Sun { direction: -Vec3::Z, angle: 0.01 },
            color: Vec3::ONE,
            intensity: 3.0,
            shadows: true,
        };
        let lights = std::slice::from_ref(&sun);
        let studio = || crate::render::Environment::default().studio();
        let fresh = FrameLight::prepare(&scene, lights, studio(), PointCasters::NONE).with_bounce(&scene);
        let g = FrameLight::prepare(&scene, lights, studio(), PointCasters::NONE).gather(&scene);
        assert_eq!(g.vertices.iter().map(Vec::len).collect::<Vec<_>>(), [4, 4]);
        assert!(g.planes[0].bounce.iter().any(|v| v.x > 1e-3));
        // The sun's shadow on the ground was sampled where it falls, for every view to read.
        assert!(g.planes[0].shades.iter().any(|s| !s.is_empty()));
        let bytes = g.encode();
        assert_eq!(Gathered::decode(&bytes).as_ref(), Ok(&g));
        // Read back, it lights the frame exactly as preparing it in place does, without the environment's
        // occlusion maps.
        let cached =
            FrameLight::from_gathered(&scene, lights, studio(), PointCasters::NONE, g.clone()).expect("the same frame");
        assert!(cached.occlusion.is_empty() && !fresh.occlusion.is_empty());
        assert_eq!(fresh.vertex_visibility, cached.vertex_visibility);
        let ground = scene.primitives[0].material;
        for i in 0..400 {
            let p = Vec3::new(-1.9 + (i % 20) as f32 * 0.2, -1.9 + (i / 20) as f32 * 0.2, 0.0);
            assert_eq!(fresh.shade_ground(ground, p, Vec3::ONE), cached.shade_ground(ground, p, Vec3::ONE), "{p}");
            let q = p + Vec3::new(0.0, 0.0, 0.3);
            assert_eq!(fresh.ground_seen(q, -Vec3::Z, 0.1), cached.ground_seen(q, -Vec3::Z, 0.1), "{q}");
        }
        // Bytes it cannot have written are refused, a huge count without allocating for it.
        assert!(Gathered::decode(&bytes[..bytes.len() - 1]).is_err());
        assert!(Gathered::decode(&[bytes.as_slice(), &[0]].concat()).is_err());
        let mut huge = bytes.clone();
        huge[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(Gathered::decode(&huge).is_err());
        let mut nan = bytes.clone();
        nan[8..12].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(Gathered::decode(&nan).unwrap_err().to_string().contains("finite"));
        // Another frame's shape is refused.
        let other = Gathered { vertices: vec![vec![Visibility::OPEN; 3]], planes: Vec::new() };
        assert!(FrameLight::from_gathered(&scene, lights, studio(), PointCasters::NONE, other).is_err());
    }
}
