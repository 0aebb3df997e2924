//! Diffuse interreflection off the subject: the light its parts reflect onto each other, gathered once per posed
//! frame at every vertex and shared by every view of the frame (see [`Subject::gather`]).
//!
//! Cycles follows every bounce; the direct light, the environment's occlusion and the ground's first bounce leave
//! out what the subject reflects onto itself, which made it 4–14 % dark where it sees little sky and sun. Each
//! vertex casts a fixed set of cosine-weighted rays against the posed frame's casters; a ray that meets one
//! carries the radiance of the diffuse surface there, interpolated from the vertices' irradiance, and the gather
//! repeats over the same hits so that light bounces [`BOUNCES`] times. Rays that meet nothing add nothing: the
//! environment's share of them is already in the occlusion.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::brdf::{basis, hammersley};
use super::rays::{Rays, Tracer};
use super::{caster_bounds, is_caster, FrameLight, Visibility};
use crate::scene::PosedScene;

/// Diffuse bounces the gather follows. Each adds about ρF of the one before (ρ the albedo, F the share of a
/// vertex's hemisphere the subject fills: 7 % of CesiumMan's rays meet it), so what the fourth and later would
/// add is (ρF)³ of the first, under 3 % of it wherever ρF < 0.3.
pub(super) const BOUNCES: usize = 3;

/// Rays a frame's gather may cast in all: a vertex casts `RAY_BUDGET / vertices` rays, a power of two between
/// [`MIN_RAYS`] and [`MAX_RAYS`] (CesiumMan's 3 273 vertices cast 32 each, FlightHelmet's 55 392 cast 16): the
/// cost of a frame stays about that of a million rays up to a mesh of 256 000 vertices, and past that grows
/// by 4 rays a vertex (a 5-million-vertex scan: 20 million rays, seconds a frame). Smoothing over each vertex's
/// neighbours ([`Neighbours::smooth`]) makes up for the few rays of a dense mesh.
const RAY_BUDGET: usize = 1 << 20;
const MIN_RAYS: usize = 4;
const MAX_RAYS: usize = 32;
/// Rays each point a ground gathers at (see `FrameLight::with_bounce`: every fourth grid point, 1 089 in all)
/// casts over its hemisphere when it lies inside the subject's bounding sphere, and over the cone the sphere
/// fills when it lies outside (see [`Subject::onto`]).
const GROUND_RAYS: u32 = 256;
const CONE_RAYS: u32 = 64;

/// Where one gathering ray met a caster: the triangle, the barycentric weights of its second and third corners
/// there, whether it met the triangle's back, the diffuse reflectance of the surface there and the radiance it
/// emits (its material's emission: a glowing part lights the rest, as in a path tracer).
#[derive(Clone, Copy)]
struct Hit {
    tri: u32,
    k: [f32; 2],
    back: bool,
    albedo: [u8; 3],
    emission: Vec3,
}

/// The frame's subject as the gather reads it: its casters, in a ray-tracing tree, and its vertices.
pub(super) struct Subject {
    tracer: Arc<Tracer>,
    /// A sphere about the casters: the middle of their bounds and half its diagonal.
    sphere: (Vec3, f32),
    /// The gathering vertices (every caster's), as (primitive, vertex), numbered in primitive order (a vertex's
    /// serial number); `first[p]` is primitive p's first. A two-sided primitive's ([`super::sides`]) back sides
    /// follow its front sides, as vertices `n..2n` of its `n`; `back[p]` is where they start within it (0: one
    /// side, whose back a ray meeting it reads as its front, as before).
    vertices: Vec<(u32, u32)>,
    first: Vec<usize>,
    back: Vec<usize>,
    /// Primitive p's first front side's number counting front sides alone: what turns a vertex's rays (so that
    /// how many sides other primitives gather does not).
    fronts: Vec<usize>,
}

/// What the gather found: per serial number, the irradiance the subject reflects onto the vertex, and all it
/// receives (that and its direct light).
pub(super) struct Gathered {
    pub(super) bounce: Vec<Vec3>,
    total: Vec<Vec3>,
}

impl Subject {
    /// The casters of `scene`, `None` when nothing casts shadows; `visibility` (the frame's per vertex) holds both
    /// sides of a primitive that gathers on both ([`super::sides`]).
    pub(super) fn of(scene: &PosedScene, visibility: &[Vec<Visibility>]) -> Option<Subject> {
        let mut first = vec![0usize; scene.primitives.len()];
        let mut back = vec![0usize; scene.primitives.len()];
        let mut fronts = vec![0usize; scene.primitives.len()];
        let (mut vertices, mut front_count): (Vec<(u32, u32)>, usize) = (Vec::new(), 0);
        for (i, prim) in scene.primitives.iter().enumerate() {
            if is_caster(scene, prim) {
                let n = prim.positions.len();
                let sides = if visibility.get(i).is_some_and(|v| v.len() == 2 * n && n > 0) { 2 } else { 1 };
                (first[i], fronts[i]) = (vertices.len(), front_count);
                back[i] = if sides == 2 { n } else { 0 };
                front_count += n;
                vertices.extend((0..(n * sides) as u32).map(|v| (i as u32, v)));
            }
        }
        let (lo, hi) = caster_bounds(scene)?;
        if vertices.is_empty() {
            return None;
        }
        let tracer = Arc::new(Tracer::of(scene, Rays::Many)?);
        let sphere = ((lo + hi) * 0.5, 0.5 * (hi - lo).length());
        Some(Subject { tracer, sphere, vertices, first, back, fronts })
    }

    /// Vertex `v` of primitive `pi` as the gather numbers them: the mesh's vertex, and whether it is its back side.
    #[inline]
    fn vertex(&self, pi: u32, v: u32) -> (usize, bool) {
        let (v, back) = (v as usize, self.back[pi as usize]);
        if back > 0 && v >= back {
            (v - back, true)
        } else {
            (v, false)
        }
    }

    /// The position and normal of vertex `v` of primitive `pi` as the gather numbers them: a back side's normal
    /// reversed.
    #[inline]
    fn side(&self, scene: &PosedScene, pi: u32, v: u32) -> (Vec3, Vec3) {
        let prim = &scene.primitives[pi as usize];
        let (v, back) = self.vertex(pi, v);
        (prim.positions[v], if back { -prim.normals[v] } else { prim.normals[v] })
    }

    /// Its casters' tree.
    pub(super) fn tracer(&self) -> Arc<Tracer> {
        Arc::clone(&self.tracer)
    }

    /// The light the subject reflects onto each of its vertices, by serial number, in a frame whose direct
    /// light, environment and vertices' view of it `light` holds.
    pub(super) fn gather(&self, scene: &PosedScene, light: &FrameLight) -> Gathered {
        let n = self.vertices.len();
        let rays = 1usize << (RAY_BUDGET / n).clamp(MIN_RAYS, MAX_RAYS).ilog2();
        let hits = self.trace_all(scene, rays);
        let neighbours = Neighbours::of(scene, self);
        // The direct light each vertex receives (irradiance, by its normal; its sides as the light holds them).
        let direct: Vec<Vec3> = self
            .vertices
            .par_iter()
            .map(|&(pi, v)| {
                let (p, n) = self.side(scene, pi, v);
                let vis = light.vertex_visibility[pi as usize].get(v as usize).copied().unwrap_or(Visibility::OPEN);
                light.direct_irradiance(p, n, &vis)
            })
            .collect();
        // The bounces: each gather reads the irradiance the last one left at the vertices.
        let mut g = Gathered { bounce: vec![Vec3::ZERO; n], total: direct.clone() };
        for _ in 0..BOUNCES {
            let raw: Vec<Vec3> = (0..n)
                .into_par_iter()
                .map(|k| hits.of(k).iter().map(|h| self.reflected(&g, h)).sum::<Vec3>() * (PI / rays as f32))
                .collect();
            g.bounce = neighbours.smooth(&raw);
            g.total = direct.iter().zip(&g.bounce).map(|(d, b)| *d + *b).collect();
        }
        g
    }

    /// The radiance coming back along a ray that met the subject at `h`: the diffuse surface there under all it
    /// receives (`g`'s totals of the side the ray met, interpolated across the triangle), and what it emits.
    #[inline]
    fn reflected(&self, g: &Gathered, h: &Hit) -> Vec3 {
        let (pi, [a, b, c]) = self.tracer.casters.corners[h.tri as usize];
        let first = self.first[pi as usize] + if h.back { self.back[pi as usize] } else { 0 };
        let at = |v: u32| g.total.get(first + v as usize).map_or(Vec3::ZERO, |e| e.max(Vec3::ZERO));
        let e = at(a) * (1.0 - h.k[0] - h.k[1]) + at(b) * h.k[0] + at(c) * h.k[1];
        Vec3::new(h.albedo[0] as f32, h.albedo[1] as f32, h.albedo[2] as f32) * (1.0 / 255.0) * e * (1.0 / PI)
            + h.emission
    }

    /// The serial numbers of primitive `prim`'s vertices (their back sides' after them when it is two-sided).
    pub(super) fn serials(&self, scene: &PosedScene, prim: usize) -> std::ops::Range<usize> {
        let k = self.first[prim];
        k..k + scene.primitives[prim].positions.len() + self.back[prim]
    }

    /// The irradiance the subject (lit as `g` found) reflects onto each of `points`, surfaces facing `normal`
    /// that are not its own (a ground plane's grid), rotating each point's ray set. From outside the subject's
    /// bounding sphere the rays go only where it is: [`CONE_RAYS`] spread evenly over the cone it fills, each
    /// weighted by its cosine (far from the subject a hemisphere's rays would nearly all miss, and the few that
    /// meet it would be noise); from inside it, [`GROUND_RAYS`] cosine-weighted over the hemisphere.
    pub(super) fn onto(&self, scene: &PosedScene, g: &Gathered, points: &[Vec3], normal: Vec3) -> Vec<Vec3> {
        let (t, b) = basis(normal);
        let (centre, radius) = self.sphere;
        points
            .par_iter()
            .enumerate()
            .map(|(serial, &p)| {
                let shift = hammersley(serial as u32 % 4093, 4093);
                let o = p + normal * self.tracer.eps;
                let to = centre - p;
                let far = to.length();
                if far <= radius * 1.001 {
                    let mut sum = Vec3::ZERO;
                    for i in 0..GROUND_RAYS {
                        let d = cosine_direction(i, GROUND_RAYS, shift, t, b, normal);
                        if let Some(h) = self.trace(scene, o, d) {
                            sum += self.reflected(g, &h);
                        }
                    }
                    return sum * (PI / GROUND_RAYS as f32);
                }
                // Uniform over the cone's solid angle Ω = 2π(1 − cos θ): E = Ω/N Σ L·cos.
                let axis = to / far;
                let cos_max = (1.0 - (radius / far).powi(2)).max(0.0).sqrt();
                let (u, v) = basis(axis);
                let mut sum = Vec3::ZERO;
                for i in 0..CONE_RAYS {
                    let xi = (hammersley(i, CONE_RAYS) + shift).fract();
                    let cos = 1.0 - xi.x * (1.0 - cos_max);
                    let sin = (1.0 - cos * cos).max(0.0).sqrt();
                    let phi = 2.0 * PI * xi.y;
                    let d = u * (sin * phi.cos()) + v * (sin * phi.sin()) + axis * cos;
                    let facing = d.dot(normal);
                    if facing <= 0.0 {
                        continue;
                    }
                    if let Some(h) = self.trace(scene, o, d) {
                        sum += self.reflected(g, &h) * facing;
                    }
                }
                sum * (2.0 * PI * (1.0 - cos_max) / CONE_RAYS as f32)
            })
            .collect()
    }

    /// Casts `rays` cosine-weighted rays from each vertex against the casters.
    fn trace_all(&self, scene: &PosedScene, rays: usize) -> Hits {
        let per_vertex: Vec<Vec<Hit>> = self
            .vertices
            .par_iter()
            .map(|&(pi, v)| {
                let (p, n) = self.side(scene, pi, v);
                let (t, b) = basis(n);
                // The same set rotated per vertex (Cranley–Patterson, by its number among the frame's front
                // sides): neighbours sample different directions, so their errors average out where they are
                // smoothed. A back side turns it as its front side does (a mesh stored inside out gathers as the
                // same mesh right side out).
                let front = self.fronts[pi as usize] + self.vertex(pi, v).0;
                let shift = hammersley(front as u32 % 4093, 4093);
                (0..rays as u32)
                    .filter_map(|i| {
                        self.trace(scene, p + n * self.tracer.eps, cosine_direction(i, rays as u32, shift, t, b, n))
                    })
                    .collect()
            })
            .collect();
        let mut start = Vec::with_capacity(per_vertex.len() + 1);
        start.push(0);
        for h in &per_vertex {
            start.push(start.last().copied().unwrap_or(0) + h.len());
        }
        Hits { start, hits: per_vertex.concat() }
    }

    /// The nearest caster along the ray from `o` along unit `d`, with the diffuse reflectance there.
    fn trace(&self, scene: &PosedScene, o: Vec3, d: Vec3) -> Option<Hit> {
        let (tri, at) = self.tracer.nearest(o, d)?;
        let casters = &self.tracer.casters;
        let (pi, c) = casters.corners[tri];
        let t = &casters.tris[tri];
        let (v0, v1, v2): (Vec3, Vec3, Vec3) = (t.v0.into(), t.v1.into(), t.v2.into());
        let k = barycentric(o + d * at, v0, v1, v2);
        // The back of a triangle is the side its corners turn clockwise on, as a camera's back faces are.
        let back = d.dot((v1 - v0).cross(v2 - v0)) > 0.0;
        let (albedo, emission) = surface_at(scene, &scene.primitives[pi as usize], c, k);
        let q = |x: f32| (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
        Some(Hit { tri: tri as u32, k, back, albedo: [q(albedo.x), q(albedo.y), q(albedo.z)], emission })
    }
}

/// The hits of every vertex's rays, the misses left out: vertex k's are `hits[start[k]..start[k + 1]]`.
struct Hits {
    start: Vec<usize>,
    hits: Vec<Hit>,
}

impl Hits {
    fn of(&self, k: usize) -> &[Hit] {
        &self.hits[self.start[k]..self.start[k + 1]]
    }
}

/// Direction `i` of `n` cosine-weighted about unit `normal` (tangents `t`, `b`), its set rotated by `shift`.
#[inline]
fn cosine_direction(i: u32, n: u32, shift: Vec2, t: Vec3, b: Vec3, normal: Vec3) -> Vec3 {
    let xi = (hammersley(i, n) + shift).fract();
    let (r, phi) = (xi.x.sqrt(), 2.0 * PI * xi.y);
    t * (r * phi.cos()) + b * (r * phi.sin()) + normal * (1.0 - xi.x).max(0.0).sqrt()
}

/// Each gathering vertex's neighbours across its primitive's triangles, with the weight its normal gives them.
struct Neighbours {
    start: Vec<usize>,
    list: Vec<(u32, f32)>,
}

impl Neighbours {
    /// Of `subject`'s gathering vertices: a back side's neighbours are its neighbours' back sides.
    fn of(scene: &PosedScene, subject: &Subject) -> Neighbours {
        let count = subject.vertices.len();
        let mut sets: Vec<Vec<u32>> = vec![Vec::new(); count];
        for (i, prim) in scene.primitives.iter().enumerate() {
            if !is_caster(scene, prim) {
                continue;
            }
            let (first, back) = (subject.first[i], subject.back[i]);
            for first in std::iter::once(first).chain((back > 0).then_some(first + back)) {
                for t in prim.indices.chunks_exact(3) {
                    for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                        let (ka, kb) = (first + a as usize, first + b as usize);
                        if ka < count && kb < count && ka != kb {
                            sets[ka].push(kb as u32);
                            sets[kb].push(ka as u32);
                        }
                    }
                }
            }
        }
        let normals: Vec<Vec3> = subject.vertices.iter().map(|&(pi, v)| subject.side(scene, pi, v).1).collect();
        let (mut start, mut list) = (vec![0], Vec::new());
        for (k, set) in sets.iter_mut().enumerate() {
            set.sort_unstable();
            set.dedup();
            // Neighbours facing another way see other things: they count by how alike the normals are.
            list.extend(set.iter().map(|&j| (j, normals[k].dot(normals[j as usize]).max(0.0).powi(2))));
            start.push(list.len());
        }
        Neighbours { start, list }
    }

    /// `raw` averaged over each vertex and its neighbours: the gather's noise, which would mottle the surface,
    /// shrinks by about the square root of their number.
    fn smooth(&self, raw: &[Vec3]) -> Vec<Vec3> {
        (0..raw.len())
            .into_par_iter()
            .map(|k| {
                let (mut sum, mut w) = (raw[k], 1.0);
                for &(j, wj) in &self.list[self.start[k]..self.start[k + 1]] {
                    sum += raw[j as usize] * wj;
                    w += wj;
                }
                sum / w
            })
            .collect()
    }
}

/// The diffuse layer's colour at barycentric weights `k` (of corners two and three) in triangle `c` of `prim`
/// (base colour × (1 − metallic), textures and vertex colours included), and the radiance it emits there
/// (emissive factor × texture).
fn surface_at(scene: &PosedScene, prim: &crate::scene::PosedPrimitive, c: [u32; 3], k: [f32; 2]) -> (Vec3, Vec3) {
    let mat = scene.material(prim.material);
    let w = [1.0 - k[0] - k[1], k[0], k[1]];
    let uv = (!prim.uvs.is_empty())
        .then(|| (0..3).map(|j| prim.uvs.get(c[j] as usize).copied().unwrap_or(Vec2::ZERO) * w[j]).sum::<Vec2>());
    let color = (!prim.colors.is_empty()).then(|| {
        (0..3).map(|j| prim.colors.get(c[j] as usize).copied().unwrap_or(glam::Vec4::ONE) * w[j]).sum::<glam::Vec4>()
    });
    let texture = |r: Option<crate::scene::texture::TextureRef>| {
        r.and_then(|r| Some((r, scene.textures.get(r.texture as usize)?)))
    };
    let metallic = match (texture(mat.metallic_roughness_texture), uv) {
        (Some((r, t)), Some(uv)) => mat.metallic * t.sample(&r, uv).z,
        _ => mat.metallic,
    };
    let emission = mat.emission(&scene.textures, uv).max(Vec3::ZERO);
    (mat.albedo(&scene.textures, uv, color).truncate() * (1.0 - metallic), emission)
}

/// The barycentric weights of `b` and `c` for point `p` in triangle (a, b, c) (the projection onto its plane).
fn barycentric(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> [f32; 2] {
    let (e1, e2, w) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det.abs() < 1e-20 {
        return [0.0, 0.0];
    }
    let (w1, w2) = (w.dot(e1), w.dot(e2));
    let u = ((d22 * w1 - d12 * w2) / det).clamp(0.0, 1.0);
    let v = ((d11 * w2 - d12 * w1) / det).clamp(0.0, 1.0 - u);
    [u, v]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::light::PointCasters;
    use crate::scene::light::{Light, LightKind};
    use crate::scene::material::Material;
    use crate::scene::PrimKind;
    use glam::Vec4;

    #[test]
    fn barycentric_weights_rebuild_the_point() {
        let (a, b, c) = (Vec3::new(0.0, 0.0, 1.0), Vec3::new(2.0, 0.0, 1.0), Vec3::new(0.0, 3.0, 1.0));
        let p = a * 0.2 + b * 0.5 + c * 0.3;
        let k = barycentric(p, a, b, c);
        assert!((k[0] - 0.5).abs() < 1e-6 && (k[1] - 0.3).abs() < 1e-6, "{k:?}");
    }

    /// A square of half-side `h` at height `z`, facing `normal` (±Z), as a grid of `n` × `n` cells, of colour
    /// `grey`.
    fn square(h: f32, z: f32, normal: Vec3, n: u32, grey: f32) -> PosedScene {
        let at = |i: u32, j: u32| Vec3::new(-h + 2.0 * h * i as f32 / n as f32, -h + 2.0 * h * j as f32 / n as f32, z);
        let positions: Vec<Vec3> = (0..=n).flat_map(|j| (0..=n).map(move |i| at(i, j))).collect();
        let mut indices = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let k = j * (n + 1) + i;
                let quad = [k, k + 1, k + n + 2, k, k + n + 2, k + n + 1];
                indices.extend(if normal.z > 0.0 {
                    quad
                } else {
                    [quad[0], quad[2], quad[1], quad[3], quad[5], quad[4]]
                });
            }
        }
        let material = Material { base_color: Vec4::new(grey, grey, grey, 1.0), ..Material::default() };
        PosedScene::single(
            PrimKind::Triangles,
            positions,
            vec![normal; ((n + 1) * (n + 1)) as usize],
            Vec::new(),
            indices,
            material,
        )
    }

    /// A sun shining straight up, casting no shadows, and a dark environment: only faces looking down are lit,
    /// all alike, by `e` W/m².
    fn lit_from_below(scene: &PosedScene, e: f32) -> FrameLight {
        let sun = Light {
            kind: LightKind::Sun { direction: Vec3::Z, angle: 0.01 },
            color: Vec3::ONE,
            intensity: e,
            shadows: false,
        };
        let mut env = crate::render::Environment::default().studio();
        env.strength = 0.0;
        FrameLight::prepare(scene, &[sun], env, PointCasters::NONE).with_bounce(scene)
    }

    /// Half the view factor from a point to the rectangle a × b whose corner lies `c` straight above it, in a
    /// parallel plane, over π (the standard closed form, for one quadrant).
    fn quadrant(a: f32, b: f32, c: f32) -> f32 {
        let (x, y) = (a / c, b / c);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
    }

    /// A floor of grey `floor` facing up and, 0.5 m above, a ceiling of 0.8 facing down, both 4 m wide (20 × 20
    /// cells, the middle vertex 10 · 21 + 10), lit from below by 2 W/m²; and the ceiling's view factor from the
    /// floor's middle, F.
    fn floor_under_ceiling(floor: f32) -> (PosedScene, FrameLight, f32) {
        let mut scene = PosedScene::default();
        crate::scene::merge(&[square(2.0, 0.0, Vec3::Z, 20, floor), square(2.0, 0.5, -Vec3::Z, 20, 0.8)], &mut scene);
        let light = lit_from_below(&scene, 2.0);
        (scene, light, 4.0 * quadrant(2.0, 2.0, 0.5))
    }

    #[test]
    fn a_lit_ceiling_lights_the_floor_below_by_its_view_factor() {
        // A black floor facing up and, 0.5 m above, a ceiling of 0.8 facing down, both 4 m wide, lit from below
        // by 2 W/m²: the floor's middle receives 0.8 · 2 · F, F the ceiling's view factor (0.952).
        let (scene, light, f) = floor_under_ceiling(0.0);
        let expected = 0.8 * 2.0 * f;
        let middle = 10 * 21 + 10;
        let got = light.vertex_visibility[0][middle].bounce;
        assert!((got.x / expected - 1.0).abs() < 0.03 && got.x == got.y && got.y == got.z, "{got} vs {expected}");
        // The ceiling, over a black floor, gets nothing back; off the floor's middle, toward its edge, less.
        assert!(light.vertex_visibility[1][middle].bounce.max_element() < 1e-6);
        let edge = 10 * 21 + 1;
        assert!(light.vertex_visibility[0][edge].bounce.x < 0.8 * got.x);
        // The same frame prepared again gives the same bits.
        let again = lit_from_below(&scene, 2.0);
        assert_eq!(format!("{:?}", again.vertex_visibility), format!("{:?}", light.vertex_visibility));
    }

    #[test]
    fn a_glowing_ceiling_lights_the_floor_below_by_its_view_factor() {
        // The floor and ceiling above, both black, the ceiling emitting 1.5 W/(m²·sr), no light and a dark
        // environment: the floor's middle receives π · 1.5 · F, as from a lamp of that shape. Its own emission
        // does not come back to the ceiling.
        let mut scene = PosedScene::default();
        let mut ceiling = square(2.0, 0.5, -Vec3::Z, 20, 0.0);
        std::sync::Arc::make_mut(&mut ceiling.materials)[0].emissive = Vec3::splat(1.5);
        crate::scene::merge(&[square(2.0, 0.0, Vec3::Z, 20, 0.0), ceiling], &mut scene);
        let mut env = crate::render::Environment::default().studio();
        env.strength = 0.0;
        let light = FrameLight::prepare(&scene, &[], env, PointCasters::NONE).with_bounce(&scene);
        let expected = PI * 1.5 * 4.0 * quadrant(2.0, 2.0, 0.5);
        let middle = 10 * 21 + 10;
        let got = light.vertex_visibility[0][middle].bounce;
        assert!((got.x / expected - 1.0).abs() < 0.03 && got.x == got.y && got.y == got.z, "{got} vs {expected}");
        assert!(light.vertex_visibility[1][middle].bounce.max_element() < 1e-6);
    }

    #[test]
    fn light_bounces_back_and_forth_between_facing_surfaces() {
        // Both 0.8: the floor's bounce lights the ceiling, which sends part of it back (a second bounce and a
        // third): the floor gets 0.8 · 2 · F · (1 + (0.8 F)² + …) over the first bounce's 0.8 · 2 · F.
        let (_, light, f) = floor_under_ceiling(0.8);
        let middle = 10 * 21 + 10;
        let floor = light.vertex_visibility[0][middle].bounce.x;
        let ceiling = light.vertex_visibility[1][middle].bounce.x;
        // The ceiling receives the floor's first bounce back: about 0.8 · F times it (its view factor is F too,
        // but the floor is dimmer toward its edges: a little less).
        let first = 0.8 * 2.0 * f;
        assert!(ceiling > 0.8 * f * first * 0.9 && ceiling < 0.8 * f * first * 1.03, "{ceiling}");
        // Three bounces: the floor's third is what the ceiling's second sends it.
        let third = first * (0.8 * f) * (0.8 * f);
        assert!(floor > first + 0.85 * third && floor < (first + third) * 1.03, "{floor} vs {first} + {third}");
    }

    #[test]
    fn a_lit_square_lights_the_ground_below_by_its_view_factor() {
        // A 0.6 m square of 0.5 facing down 1 m over a 4 m ground, lit from below by 3 W/m²: the ground under
        // its middle receives 0.5 · 3 · F (F = 0.102); 1.5 m aside, far less.
        let plane = crate::scene::input::Ground { size: [4.0, 4.0], color: [0.7, 0.6, 0.5], z: None };
        let mut scene = PosedScene::default();
        let ground = crate::scene::source::ground(&plane, 0.0);
        crate::scene::merge(&[ground, square(0.3, 1.0, -Vec3::Z, 6, 0.5)], &mut scene);
        let light = lit_from_below(&scene, 3.0);
        let expected = 0.5 * 3.0 * 4.0 * quadrant(0.3, 0.3, 1.0);
        let got = light.planes[0].bounce_at(0.0, 0.0);
        assert!((got.x / expected - 1.0).abs() < 0.03, "{got} vs {expected}");
        assert!(light.planes[0].bounce_at(1.5, 0.0).x < 0.3 * got.x);
        // Shaded, the ground adds it: its colour × the bounce / π over what the dark sky and the sun give.
        let ground = scene.primitives[0].material;
        let shaded = light.shade_ground(ground, Vec3::ZERO, Vec3::new(0.7, 0.6, 0.5)).expect("a ground");
        assert!((shaded - Vec3::new(0.7, 0.6, 0.5) * got / PI).abs().max_element() < 1e-6, "{shaded}");
    }
}
