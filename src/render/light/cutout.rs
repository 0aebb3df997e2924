//! Cut-out casters: a glTF `MASK` material is there only where its alpha (the base colour factor's, times the
//! vertex colour's and the base colour texture's) reaches its cutoff, as the camera's rasterizer draws it. Its
//! shadows and the rays that meet it see the same holes: a leaf card's shadow is a leaf's, not a rectangle's,
//! and light reaches through a fence.

use glam::{Vec2, Vec3, Vec4};

use crate::scene::material::AlphaMode;
use crate::scene::texture::{Texture, TextureRef};
use crate::scene::{PosedPrimitive, PosedScene};

/// A cut-out primitive's alpha, as its corners and texture give it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Cutout<'a> {
    factor: f32,
    cutoff: f32,
    /// Vertex colours, when the primitive has one per vertex.
    colors: Option<&'a [Vec4]>,
    /// The base colour texture and the coordinates it is read at, when it has both.
    texture: Option<(TextureRef, &'a Texture, &'a [Vec2])>,
}

impl<'a> Cutout<'a> {
    /// The cut-out of primitive `prim` of `scene`, when its material is `MASK`.
    pub(super) fn of(scene: &'a PosedScene, prim: &'a PosedPrimitive) -> Option<Cutout<'a>> {
        let m = scene.materials.get(prim.material as usize).filter(|m| m.alpha_mode == AlphaMode::Mask)?;
        let n = prim.positions.len();
        let colors = (prim.colors.len() == n).then_some(prim.colors.as_slice());
        let texture = m
            .base_color_texture
            .and_then(|r| scene.textures.get(r.texture as usize).map(|t| (r, t)))
            .filter(|_| prim.uvs.len() == n)
            .map(|(r, t)| (r, t, prim.uvs.as_slice()));
        Some(Cutout { factor: m.base_color.w, cutoff: m.alpha_cutoff, colors, texture })
    }

    /// Whether triangle `t` (vertex indices) is there at barycentric weights `w`: its alpha reaches the cutoff.
    #[inline]
    pub(super) fn holds(&self, t: [u32; 3], w: [f32; 3]) -> bool {
        let (alpha, uv) = self.corners(t);
        reaches(alpha, uv, self.cutoff, self.texture.map(|(r, tex, _)| (r, tex)), w)
    }

    /// Triangle `t`'s corners' alpha before the texture (factor × vertex colour) and texture coordinates.
    #[inline]
    fn corners(&self, t: [u32; 3]) -> ([f32; 3], [Vec2; 3]) {
        let alpha = t.map(|i| self.factor * self.colors.map_or(1.0, |v| v.get(i as usize).map_or(1.0, |c| c.w)));
        let uv = t.map(|i| self.texture.and_then(|(_, _, uvs)| uvs.get(i as usize).copied()).unwrap_or(Vec2::ZERO));
        (alpha, uv)
    }
}

/// Whether a cut-out triangle whose corners have alpha `alpha` (before the texture) and texture coordinates `uv`
/// is there at barycentric weights `w`: the blended alpha, times the texture's there, reaches `cutoff`.
#[inline]
fn reaches(alpha: [f32; 3], uv: [Vec2; 3], cutoff: f32, texture: Option<(TextureRef, &Texture)>, w: [f32; 3]) -> bool {
    let mut a = alpha[0] * w[0] + alpha[1] * w[1] + alpha[2] * w[2];
    if let Some((r, tex)) = texture {
        a *= tex.sample(&r, uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2]).w;
    }
    a >= cutoff
}

/// One cut-out triangle's alpha as a ray tracer keeps it, apart from the scene: its corners' alpha before the
/// texture and texture coordinates ([`Cutout::corners`]), the cutoff and the texture (the corners' positions are
/// the tracer's own triangle).
#[derive(Debug, Clone)]
pub(super) struct Hole {
    alpha: [f32; 3],
    uv: [Vec2; 3],
    cutoff: f32,
    texture: Option<TextureRef>,
}

impl Hole {
    /// Triangle `t` (vertex indices) of a primitive whose cut-out is `c`, kept for rays.
    pub(super) fn of(c: &Cutout, t: [u32; 3]) -> Hole {
        let (alpha, uv) = c.corners(t);
        Hole { alpha, uv, cutoff: c.cutoff, texture: c.texture.map(|(r, _, _)| r) }
    }

    /// Whether the triangle of corners `[a, b, c]` is there where the ray from `o` along `d` meets its plane at
    /// distance `t`, its texture one of `textures`.
    pub(super) fn holds(&self, [a, b, c]: [Vec3; 3], textures: &[Texture], o: Vec3, d: Vec3, t: f32) -> bool {
        let p = o + d * t;
        // Barycentric weights of p by areas against the triangle's normal.
        let n = (b - a).cross(c - a);
        let nn = n.length_squared();
        if nn <= 0.0 {
            return true;
        }
        let w1 = (p - a).cross(c - a).dot(n) / nn;
        let w2 = (b - a).cross(p - a).dot(n) / nn;
        let texture = self.texture.and_then(|r| textures.get(r.texture as usize).map(|tex| (r, tex)));
        reaches(self.alpha, self.uv, self.cutoff, texture, [1.0 - w1 - w2, w1, w2])
    }
}

#[cfg(test)]
mod tests {
    use crate::render::light::PointCasters;
    use std::sync::Arc;

    use super::*;
    use crate::render::light::rays::{Rays, Tracer};
    use crate::render::light::shadow::ShadowMap;
    use crate::scene::material::Material;
    use crate::scene::PrimKind;

    #[test]
    fn a_cut_out_casts_its_shape_and_lets_rays_through_its_holes() {
        // A 2 m square at z = 1 facing down, of a MASK material whose texture is clear (alpha 0) on its -x half
        // and solid on its +x half; a sun straight down. Under the clear half the ground is lit and a ray up
        // is open; under the solid half both are blocked. The same square OPAQUE blocks both everywhere.
        let (w, h) = (8u32, 2u32);
        let rgba: Vec<u8> =
            (0..w * h).flat_map(|i| if i % w < w / 2 { [255, 255, 255, 0] } else { [255, 255, 255, 255] }).collect();
        let square = |mode: AlphaMode| {
            let m = Material {
                alpha_mode: mode,
                base_color_texture: Some(TextureRef::new(0)),
                double_sided: true,
                ..Material::default()
            };
            let mut s = PosedScene::single(
                PrimKind::Triangles,
                vec![
                    Vec3::new(-1.0, -1.0, 1.0),
                    Vec3::new(1.0, -1.0, 1.0),
                    Vec3::new(1.0, 1.0, 1.0),
                    Vec3::new(-1.0, 1.0, 1.0),
                ],
                vec![-Vec3::Z; 4],
                Vec::new(),
                vec![0, 2, 1, 0, 3, 2],
                m,
            );
            s.primitives[0].uvs =
                Arc::new(vec![Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)]);
            s.textures = Arc::new(vec![Texture::new(w, h, rgba.clone(), true)]);
            s
        };
        let (clear, solid) = (Vec3::new(-0.5, 0.2, 0.0), Vec3::new(0.5, -0.2, 0.0));
        for (mode, holes) in [(AlphaMode::Mask, true), (AlphaMode::Opaque, false)] {
            let scene = square(mode);
            let bounds = (Vec3::new(-1.0, -1.0, 1.0), Vec3::new(1.0, 1.0, 1.0));
            let map = ShadowMap::sun(&scene, -Vec3::Z, bounds, 256, PointCasters::NONE);
            let tracer = Tracer::of(&scene, Rays::Few).expect("a caster");
            let (lit, shaded) = (map.visibility(clear, Vec3::Z, 0.0), map.visibility(solid, Vec3::Z, 0.0));
            let (open, shut) = (tracer.open(clear, Vec3::Z), tracer.open(solid, Vec3::Z));
            assert_eq!(shaded, 0.0, "{mode:?}");
            assert!(!shut, "{mode:?}");
            assert_eq!((lit, open), if holes { (1.0, true) } else { (0.0, false) }, "{mode:?}");
            assert_eq!(tracer.nearest(clear, Vec3::Z).is_none(), holes, "{mode:?}");
        }
    }
}
