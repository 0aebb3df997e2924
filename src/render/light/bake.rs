//! Baked point colours: what a `ply-sequence` with `color = "lit"` writes, a view-independent colour per point
//! lit as the frame's renders light the surface it lies on ([`FrameLight::bake_on`]), or from the lights and the
//! environment's occlusion where no vertex gathered anything ([`FrameLight::bake`]).

use glam::Vec3;

use super::brdf::DIELECTRIC;
use super::{FrameLight, Surface, Visibility};
use crate::scene::PosedScene;

/// Version of baked point colours ([`FrameLight::bake`]): part of their keys.
pub const BAKE_SALT: &str = "bake 4";

impl FrameLight {
    /// A view-independent ("baked") colour at world point `p` with unit normal `n`: the Lambertian surface of
    /// colour `albedo` under every light, with their shadows, and the environment with its occlusion at `p`,
    /// plus `emission`. What a `ply-sequence` with `color = "lit"` writes; a point without a normal keeps its
    /// albedo.
    pub fn bake(&self, p: Vec3, n: Vec3, albedo: Vec3, emission: Vec3) -> Vec3 {
        if n == Vec3::ZERO {
            return albedo + emission;
        }
        let s = Surface { base: albedo, metallic: 0.0, roughness: 1.0, specular: 0.0, f0: DIELECTRIC };
        self.displayed(self.shade(p, n, n, &s, 1.0, self.visibility(p, n), true) + emission)
    }

    /// Radiance `c` as a baked colour shows it: through the film's exposure and the view transform. A shadeless
    /// (`KHR_materials_unlit`) surface bakes as its albedo displayed so, whatever the lights.
    pub fn displayed(&self, c: Vec3) -> Vec3 {
        self.view.light(self.exposed(c))
    }

    /// [`FrameLight::bake`] of a point on the triangle of primitive `prim` with corners `corners` (vertex indices),
    /// at barycentric weights `k`, lit as the frame's renders light it: a ground's top face by its grids (as its
    /// pixels are read), any other surface by what its corners gathered, the subject's bounce included rather
    /// than estimated. For a light read from the frame's light action ([`FrameLight::from_gathered`]); a corner
    /// it holds nothing for bakes as [`FrameLight::bake`]. A shadeless (`unlit`) surface keeps its albedo.
    #[allow(clippy::too_many_arguments)]
    pub fn bake_on(
        &self,
        scene: &PosedScene,
        prim: usize,
        corners: [u32; 3],
        k: [f32; 3],
        p: Vec3,
        n: Vec3,
        albedo: Vec3,
        emission: Vec3,
    ) -> Vec3 {
        let material = scene.primitives.get(prim).map(|q| q.material);
        if material.and_then(|m| scene.materials.get(m as usize)).is_some_and(|m| m.unlit) {
            return self.displayed(albedo);
        }
        let top = n.z > 0.0;
        if let Some(c) = material.filter(|_| top).and_then(|m| self.shade_ground(m, p, albedo)) {
            return self.displayed(c + emission);
        }
        let side = |offset: usize| {
            let v = self.vertex_visibility.get(prim)?;
            let at = corners.map(|c| v.get(offset + c as usize).copied());
            Some(Visibility::blend(&[at[0]?, at[1]?, at[2]?], k))
        };
        // A two-sided surface's point takes the side the world sees more of (the outside of an inside-out scan):
        // a point has one colour, and a camera would mostly see that side.
        let count = scene.primitives.get(prim).map_or(0, |q| q.positions.len());
        let gathered = match (side(0), side(count)) {
            (Some(front), Some(back)) if back.env > front.env => Some((back, -n)),
            (front, _) => front.map(|v| (v, n)),
        };
        match gathered {
            Some((v, n)) if n != Vec3::ZERO => {
                // A plane's visibility is its grid's, as its pixels read it (its underside here).
                let vis = material.and_then(|m| self.plane_visibility_at(m, p)).unwrap_or(v);
                let s = Surface { base: albedo, metallic: 0.0, roughness: 1.0, specular: 0.0, f0: DIELECTRIC };
                self.displayed(self.shade(p, n, n, &s, 1.0, vis, false) + emission)
            }
            _ => self.bake(p, n, albedo, emission),
        }
    }
}
