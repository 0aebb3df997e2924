//! The frame's casters in a ray-tracing tree: what the gather's rays meet ([`super::bounce`]) and what blocks a
//! glossy surface's reflection ([`Tracer::lobe_visibility`]).
//!
//! Why a glossy surface needs rays: the environment's occlusion at a vertex is one number for its whole
//! hemisphere, and a glossy lobe sees a small part of it. FlightHelmet's varnished stand, under the helmet and
//! over its base, has part of its hemisphere blocked, but its reflection points at the open sky: occluded by the
//! hemisphere's number it was 7–11 % dark against Cycles. The helmet's lining, whose hemisphere the
//! occlusion maps see open through the shell (their texels are a centimetre wide), mirrored the sky through it:
//! twice Cycles' brightness. A few rays along the lobe tell both apart. A ray passes through a cut-out (`MASK`)
//! caster's holes ([`super::cutout`]), as the shadow maps do; a transparent (`BLEND`) caster blocks it as an opaque
//! one does, as it does the gather's rays.

use glam::Vec3;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

use std::sync::Arc;

use super::brdf::{basis, ggx_half, hammersley};
use super::cutout::{Cutout, Hole};
use super::{caster_bounds, is_caster};
use crate::scene::texture::Texture;
use crate::scene::PosedScene;

/// Rays a glossy surface casts along its lobe ([`Tracer::lobe_visibility`]). Against Cycles (FlightHelmet from
/// below, worst view), 4 rays reached SSIM 0.955, 8 reached 0.957 and 32 0.961: 8 keep most of it at a quarter of
/// the cost of 32.
pub(super) const LOBE_RAYS: u32 = 8;

/// The casters of one posed frame: their triangles as the ray tracer reads them and, per triangle, its
/// primitive and its corners' vertex indices; the cut-out ones' alpha ([`Hole`], by `hole`: `u32::MAX` for an
/// opaque triangle) and the textures it reads.
pub(super) struct Casters {
    pub(super) tris: Vec<Triangle>,
    pub(super) corners: Vec<(u32, [u32; 3])>,
    hole: Vec<u32>,
    holes: Vec<Hole>,
    textures: Arc<Vec<Texture>>,
}

impl Casters {
    fn of(scene: &PosedScene) -> Casters {
        let (mut tris, mut corners, mut hole, mut holes) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (pi, prim) in scene.primitives.iter().enumerate() {
            if !is_caster(scene, prim) {
                continue;
            }
            let cutout = Cutout::of(scene, prim);
            for t in prim.indices.chunks_exact(3) {
                let c = [t[0], t[1], t[2]];
                let [a, b, d] = c.map(|i| prim.positions.get(i as usize).copied().unwrap_or(Vec3::ZERO));
                tris.push(Triangle { v0: a.into(), v1: b.into(), v2: d.into() });
                corners.push((pi as u32, c));
                hole.push(cutout.as_ref().map_or(u32::MAX, |cut| {
                    holes.push(Hole::of(cut, c));
                    holes.len() as u32 - 1
                }));
            }
        }
        Casters { tris, corners, hole, holes, textures: scene.textures.clone() }
    }

    /// Where ray `r` meets triangle `i` (ours), given where it meets its plane inside its edges, `t` (∞ for a
    /// miss, as [`Triangle::intersect`] answers); a miss (∞) where a cut-out's alpha leaves a hole there.
    #[inline]
    fn meet(&self, t: f32, i: usize, r: &Ray) -> f32 {
        if t == f32::INFINITY || self.holes.is_empty() {
            return t;
        }
        match self.hole.get(i) {
            Some(&h) if h != u32::MAX => {
                let (o, d) = (Vec3::from(r.origin), Vec3::from(r.direction));
                let tri = &self.tris[i];
                let corners = [tri.v0, tri.v1, tri.v2].map(Vec3::from);
                if self.holes[h as usize].holds(corners, &self.textures, o, d, t) {
                    t
                } else {
                    f32::INFINITY
                }
            }
            _ => t,
        }
    }
}

/// The casters in a tree, and how far off a surface rays start.
pub(super) struct Tracer {
    pub(super) casters: Casters,
    bvh: CwBvh,
    /// The casters' triangles in the tree's leaf order, with their edges and normal worked out once (the
    /// intersection a ray walk makes at each leaf it reaches, the same arithmetic as [`Triangle::intersect`]'s,
    /// so the same distances), read where the walk reads them instead of through the tree's index.
    leaves: Vec<RtTriangle>,
    /// How far off a surface its rays start: a hair, scaled to the casters.
    pub(super) eps: f32,
}

impl std::fmt::Debug for Tracer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tracer").field("triangles", &self.casters.tris.len()).field("eps", &self.eps).finish()
    }
}

/// How much a tree is worth building well: by the rays it will answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Rays {
    /// A frame's gather, about a million rays: obvhs' slow build, whose walks are about a fifth cheaper
    /// (RobotExpressive's gather: 175 → 140 ms a frame on one thread) for twice the build (7 000 triangles:
    /// 12 → 27 ms; 800 000: 1.0 → 1.9 s).
    Many,
    /// A render pass's glossy lobes, a few rays at a tile's anchors: the fast build, since a frame's every
    /// view builds its own.
    Few,
}

impl Tracer {
    /// The casters of `scene` in a tree built for `rays`; `None` when nothing casts shadows. Which tree answers
    /// does not change an answer: a ray's nearest hit and whether it meets anything depend on the triangles
    /// alone.
    pub(super) fn of(scene: &PosedScene, rays: Rays) -> Option<Tracer> {
        let (lo, hi) = caster_bounds(scene)?;
        let casters = Casters::of(scene);
        if casters.tris.is_empty() {
            return None;
        }
        let params = match rays {
            Rays::Many => BvhBuildParams::slow_build(),
            Rays::Few => BvhBuildParams::fast_build(),
        };
        let bvh = build_cwbvh_from_tris(&casters.tris, params, &mut Default::default());
        let leaves = bvh.primitive_indices.iter().map(|&i| RtTriangle::from(&casters.tris[i as usize])).collect();
        Some(Tracer { casters, bvh, leaves, eps: 1e-4 * (hi - lo).length().max(1e-6) })
    }

    /// The nearest caster along the ray from `o` along unit `d` (past [`Tracer::eps`]): its triangle (an index
    /// into [`Tracer::casters`]) and how far along the ray.
    pub(super) fn nearest(&self, o: Vec3, d: Vec3) -> Option<(usize, f32)> {
        let (casters, bvh) = (&self.casters, &self.bvh);
        let ray = Ray::new(o.into(), d.into(), self.eps, f32::INFINITY);
        let mut hit = RayHit::none();
        // The tree numbers its leaves' triangles in its own order: `primitive_indices` maps them back to ours.
        let ours = |id: usize| bvh.primitive_indices[id] as usize;
        let leaves = &self.leaves;
        if !bvh.ray_traverse(ray, &mut hit, |r, id| casters.meet(leaves[id].intersect(r), ours(id), r)) {
            return None;
        }
        Some((ours(hit.primitive_id as usize), hit.t))
    }

    /// Whether the ray from `o` along unit `d` (past [`Tracer::eps`]) meets no caster. Which caster it meets
    /// first does not matter here, so the walk stops at any; with cut-out casters, whose holes a hit must be
    /// checked for, it is the nearest caster's walk, and the plain walk stays as it was for every other scene.
    pub(super) fn open(&self, o: Vec3, d: Vec3) -> bool {
        if !self.casters.holes.is_empty() {
            return self.nearest(o, d).is_none();
        }
        let bvh = &self.bvh;
        let ray = Ray::new(o.into(), d.into(), self.eps, f32::INFINITY);
        let leaves = &self.leaves;
        bvh.ray_traverse_miss(ray, |r, id| leaves[id].intersect(r))
    }

    /// The share of a GGX lobe (α = `a`, about unit normal `n`, seen from unit `v`) that reaches past the
    /// casters from point `p`: [`LOBE_RAYS`] reflected directions, importance-sampled as the environment's
    /// prefiltering samples the lobe, each weighted by its cosine to `n`. The same directions at every point
    /// (relative to its normal), so the answer varies smoothly over a surface, without noise; `None` when the
    /// whole lobe lies below the surface. Rays start a few hairs off the surface, along `n`.
    pub(super) fn lobe_visibility(&self, p: Vec3, n: Vec3, v: Vec3, a: f32) -> Option<f32> {
        let (t, b) = basis(n);
        let o = p + n * (4.0 * self.eps);
        let (mut open, mut all) = (0.0f32, 0.0f32);
        for i in 0..LOBE_RAYS {
            let h = ggx_half(hammersley(i, LOBE_RAYS), a);
            let h = t * h.x + b * h.y + n * h.z;
            let l = 2.0 * v.dot(h) * h - v;
            let nl = n.dot(l);
            if nl <= 0.0 {
                continue;
            }
            all += nl;
            if self.open(o, l) {
                open += nl;
            }
        }
        (all > 0.0).then(|| open / all)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::PrimKind;

    #[test]
    fn a_ray_is_open_exactly_when_it_meets_nothing_and_a_lobe_under_its_surface_sees_nothing() {
        // A unit square at z = 1 facing down.
        let square = PosedScene::single(
            PrimKind::Triangles,
            vec![
                Vec3::new(-0.5, -0.5, 1.0),
                Vec3::new(0.5, -0.5, 1.0),
                Vec3::new(0.5, 0.5, 1.0),
                Vec3::new(-0.5, 0.5, 1.0),
            ],
            vec![-Vec3::Z; 4],
            Vec::new(),
            vec![0, 2, 1, 0, 3, 2],
            crate::scene::material::Material::default(),
        );
        let tracer = Tracer::of(&square, Rays::Few).expect("a caster");
        let (mut met, mut missed) = (0, 0);
        for i in 0..400 {
            let xi = hammersley(i, 400);
            let d = Vec3::new(xi.x * 2.0 - 1.0, xi.y * 2.0 - 1.0, 0.8).normalize();
            let nearest = tracer.nearest(Vec3::ZERO, d);
            assert_eq!(tracer.open(Vec3::ZERO, d), nearest.is_none(), "{d}");
            if let Some((_, t)) = nearest {
                assert!(((d * t).z - 1.0).abs() < 1e-5, "{d} at {t}");
                met += 1;
            } else {
                missed += 1;
            }
        }
        assert!(met > 50 && missed > 50, "{met} met, {missed} missed");
        // From under the square's middle, a glossy lobe straight up meets it, one pointing away does not; a
        // lobe seen from behind the surface has no direction above it.
        let up = tracer.lobe_visibility(Vec3::ZERO, Vec3::Z, Vec3::Z, 0.01).expect("above the surface");
        let away = tracer.lobe_visibility(Vec3::ZERO, -Vec3::Z, -Vec3::Z, 0.01).expect("above the surface");
        assert_eq!((up, away), (0.0, 1.0));
        assert_eq!(tracer.lobe_visibility(Vec3::ZERO, Vec3::Z, -Vec3::Z, 0.01), None);
    }
}
