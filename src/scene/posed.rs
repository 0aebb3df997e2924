//! The posed scene: what the renderer and the sampler consume for one frame, in world space, after every
//! transform. Static per-vertex data (indices, uvs, colours) is shared between frames through `Arc`; positions
//! and normals are rewritten in place each frame, so posing a frame after the first allocates nothing.

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::light::Light;
use super::material::Material;
use super::texture::Texture;

/// What a primitive is drawn as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PrimKind {
    /// Triangle list (`indices` in threes).
    Triangles,
    /// Points (rendered as splats).
    Points,
}

/// One posed primitive.
#[derive(Debug, Clone)]
pub struct PosedPrimitive {
    /// Triangles or points.
    pub kind: PrimKind,
    /// World-space positions.
    pub positions: Vec<Vec3>,
    /// World-space unit normals (same length as positions; zero where unknown for points).
    pub normals: Vec<Vec3>,
    /// World-space unit tangents with their handedness in w, for a normal texture (empty when none).
    pub tangents: Vec<Vec4>,
    /// Texture coordinates for the base colour texture (empty when none).
    pub uvs: Arc<Vec<Vec2>>,
    /// Linear RGBA vertex colours, COLOR_0 (empty means white).
    pub colors: Arc<Vec<Vec4>>,
    /// Triangle indices (empty for points).
    pub indices: Arc<Vec<u32>>,
    /// Index into the scene's materials.
    pub material: u32,
    /// Object id (for instance masks): one per source node instance.
    pub object: u32,
    /// For points read from a 3D Gaussian splatting file: the Gaussian each point is the centre of, drawn as
    /// splatting draws it in images (point outputs take the centres).
    pub gaussians: Option<super::gaussians::Gaussians>,
}

/// Everything drawn at one frame.
#[derive(Debug, Clone, Default)]
pub struct PosedScene {
    /// The primitives, in a fixed order.
    pub primitives: Vec<PosedPrimitive>,
    /// Materials.
    pub materials: Arc<Vec<Material>>,
    /// Textures.
    pub textures: Arc<Vec<Texture>>,
    /// Lights the sources bring (a glTF's `KHR_lights_punctual`), placed where their nodes are at this frame.
    pub lights: Vec<Light>,
}

impl PosedScene {
    /// A scene of one quad: `corners` in order around it, facing `normal`, drawn as the two triangles 0 1 2 and
    /// 0 2 3, of `material` (the ground plane, test fixtures).
    pub fn quad(corners: [Vec3; 4], normal: Vec3, material: Material) -> PosedScene {
        let indices = vec![0, 1, 2, 0, 2, 3];
        PosedScene::single(PrimKind::Triangles, corners.to_vec(), vec![normal; 4], Vec::new(), indices, material)
    }

    /// A scene of one untextured primitive (object 0) with one material: a PLY mesh or cloud, a test fixture.
    pub fn single(
        kind: PrimKind,
        positions: Vec<Vec3>,
        normals: Vec<Vec3>,
        colors: Vec<Vec4>,
        indices: Vec<u32>,
        material: Material,
    ) -> PosedScene {
        PosedScene {
            primitives: vec![PosedPrimitive {
                kind,
                positions,
                normals,
                tangents: Vec::new(),
                uvs: Arc::new(Vec::new()),
                colors: Arc::new(colors),
                indices: Arc::new(indices),
                material: 0,
                object: 0,
                gaussians: None,
            }],
            materials: Arc::new(vec![material]),
            textures: Arc::new(Vec::new()),
            lights: Vec::new(),
        }
    }

    /// The material of primitive material index `i`: the default material when `i` is out of range (the loaders
    /// never give one; a hand-built scene might, and drawing it must not panic).
    #[inline]
    pub fn material(&self, i: u32) -> &Material {
        static DEFAULT: std::sync::LazyLock<Material> = std::sync::LazyLock::new(Material::default);
        self.materials.get(i as usize).unwrap_or(&DEFAULT)
    }

    /// Takes every material's own opacity as 1 (a source's `opaque`): its base colour's alpha becomes 1, and a
    /// blended material without a base colour texture, whose alpha was its own alone, is drawn opaque. A texture's
    /// alpha still cuts out or blends. Materials already so are left shared.
    pub fn make_opaque(&mut self) {
        use super::material::AlphaMode;
        let own_alpha = |m: &Material| m.alpha_mode == AlphaMode::Blend && m.base_color_texture.is_none();
        if self.materials.iter().any(|m| m.base_color.w < 1.0 || own_alpha(m)) {
            for m in Arc::make_mut(&mut self.materials) {
                m.base_color.w = 1.0;
                if own_alpha(m) {
                    m.alpha_mode = AlphaMode::Opaque;
                }
            }
        }
    }

    /// Axis-aligned bounds of every position, or `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self.primitives.iter().flat_map(|p| p.positions.iter());
        let first = *it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))))
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.primitives.iter().filter(|p| p.kind == PrimKind::Triangles).map(|p| p.indices.len() / 3).sum()
    }

    /// Number of point primitives' points.
    pub fn point_count(&self) -> usize {
        self.primitives.iter().filter(|p| p.kind == PrimKind::Points).map(|p| p.positions.len()).sum()
    }

    /// blake3 of the posed geometry and material/texture content: equal hashes mean equal renders.
    pub fn digest(&self) -> blake3::Hash {
        let mut h = blake3::Hasher::new();
        h.update(self.geometry_digest().as_bytes());
        h.update(self.material_digest().as_bytes());
        h.finalize()
    }

    /// blake3 of the materials and texture content only (constant over a source's frames): what an albedo
    /// render reads. The fields that only lit (`pbr`) shading reads are in [`PosedScene::lit_material_digest`],
    /// so that adding them to vvgen left the keys of existing unlit datasets as they were.
    pub fn material_digest(&self) -> blake3::Hash {
        let mut h = blake3::Hasher::new();
        let legacy: Vec<legacy::Material> = self.materials.iter().map(legacy::Material::of).collect();
        h.update(format!("{legacy:?}").as_bytes());
        // Colour textures only: linear copies for data slots are lit-only.
        for t in self.textures.iter().filter(|t| t.srgb) {
            h.update(&t.width.to_le_bytes());
            h.update(&t.height.to_le_bytes());
            h.update(&[t.srgb as u8]);
            h.update(&t.rgba);
        }
        h.finalize()
    }

    /// blake3 of everything in the materials and textures, lit-only fields included: what a `pbr` render reads.
    pub fn lit_material_digest(&self) -> blake3::Hash {
        let mut h = blake3::Hasher::new();
        h.update(b"vvgen.materials.lit.v2");
        let mut bytes = Vec::new();
        for m in self.materials.iter() {
            canonical::material(m, &mut bytes);
        }
        h.update(&bytes);
        for t in self.textures.iter() {
            h.update(&t.width.to_le_bytes());
            h.update(&t.height.to_le_bytes());
            h.update(&[t.srgb as u8]);
            h.update(&t.rgba);
        }
        h.finalize()
    }

    /// blake3 of the posed tangents (what a normal texture is read along), `None` when no primitive has any.
    pub fn tangents_digest(&self) -> Option<blake3::Hash> {
        if self.primitives.iter().all(|p| p.tangents.is_empty()) {
            return None;
        }
        let mut h = blake3::Hasher::new();
        h.update(b"vvgen.posed.tangents.v1");
        for p in &self.primitives {
            let part: &[u8] = bytemuck::cast_slice(&p.tangents);
            h.update(&(part.len() as u64).to_le_bytes());
            h.update(part);
        }
        Some(h.finalize())
    }

    /// blake3 of the lights the sources bring, as placed at this frame (empty input when there are none).
    pub fn lights_digest(&self) -> blake3::Hash {
        let mut h = blake3::Hasher::new();
        h.update(b"vvgen.posed.lights.v2");
        let mut bytes = Vec::new();
        for l in &self.lights {
            canonical::light(l, &mut bytes);
        }
        h.update(&bytes);
        h.finalize()
    }

    /// blake3 of the posed geometry (positions, normals, uvs, colours, indices, material and object ids).
    pub fn geometry_digest(&self) -> blake3::Hash {
        let mut h = blake3::Hasher::new();
        h.update(b"vvgen.posed.v1");
        for p in &self.primitives {
            h.update(&[p.kind as u8]);
            for part in [
                bytemuck::cast_slice::<Vec3, u8>(&p.positions),
                bytemuck::cast_slice(&p.normals),
                bytemuck::cast_slice(&p.uvs),
                bytemuck::cast_slice(&p.colors),
                bytemuck::cast_slice(&p.indices),
            ] {
                h.update(&(part.len() as u64).to_le_bytes());
                h.update(part);
            }
            h.update(&p.material.to_le_bytes());
            h.update(&p.object.to_le_bytes());
            // Only Gaussians add bytes: every other frame keeps its digest.
            if let Some(g) = &p.gaussians {
                g.data.hash_into(&mut h);
                h.update(bytemuck::cast_slice(&g.to_world.to_cols_array()));
            }
        }
        h.finalize()
    }
}

/// The material as albedo rendering saw it before lit shading existed: its `Debug` text is what
/// [`PosedScene::material_digest`] hashes, byte for byte as before (the struct keeps the name and field order).
mod legacy {
    use glam::{Vec3, Vec4};

    use crate::scene::material::{self as m, AlphaMode};
    use crate::scene::texture::TextureRef;

    #[derive(Debug)]
    pub(super) struct Material {
        #[allow(dead_code)] // read through Debug
        base_color: Vec4,
        #[allow(dead_code)]
        base_color_texture: Option<TextureRef>,
        #[allow(dead_code)]
        alpha_mode: AlphaMode,
        #[allow(dead_code)]
        alpha_cutoff: f32,
        #[allow(dead_code)]
        double_sided: bool,
        #[allow(dead_code)]
        emissive: Vec3,
    }

    impl Material {
        pub(super) fn of(x: &m::Material) -> Material {
            Material {
                base_color: x.base_color,
                base_color_texture: x.base_color_texture,
                alpha_mode: x.alpha_mode,
                alpha_cutoff: x.alpha_cutoff,
                double_sided: x.double_sided,
                emissive: x.emissive,
            }
        }
    }
}

/// The bytes lit keys hash for materials and lights: every field, in declaration order, numbers little-endian,
/// enums by their variant's index, an absent option as 0 and a present one as 1 then its value. Each value is
/// taken apart field by field, so a field added to these types does not compile until it is keyed here, and a
/// change in a dependency's `Debug` text cannot move a key.
mod canonical {
    use glam::Vec3;

    use crate::scene::light::{Light, LightKind};
    use crate::scene::material::{Material, DIELECTRIC_F0};
    use crate::scene::texture::TextureRef;

    fn f32s(out: &mut Vec<u8>, v: &[f32]) {
        for x in v {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }

    fn vec3(out: &mut Vec<u8>, v: Vec3) {
        f32s(out, &v.to_array());
    }

    fn texture(out: &mut Vec<u8>, t: &Option<TextureRef>) {
        let Some(TextureRef { texture, tex_coord, wrap_s, wrap_t, nearest, transform }) = t else {
            out.push(0);
            return;
        };
        out.push(1);
        out.extend_from_slice(&texture.to_le_bytes());
        out.extend_from_slice(&tex_coord.to_le_bytes());
        out.extend_from_slice(&[*wrap_s as u8, *wrap_t as u8, *nearest as u8]);
        match transform {
            Some(m) => {
                out.push(1);
                for c in m {
                    f32s(out, &c.to_array());
                }
            }
            None => out.push(0),
        }
    }

    /// A texture with a factor (occlusion strength, normal scale).
    fn scaled(out: &mut Vec<u8>, t: &Option<(TextureRef, f32)>) {
        texture(out, &t.map(|(r, _)| r));
        if let Some((_, k)) = t {
            f32s(out, &[*k]);
        }
    }

    pub(super) fn material(m: &Material, out: &mut Vec<u8>) {
        let Material {
            base_color,
            base_color_texture,
            alpha_mode,
            alpha_cutoff,
            double_sided,
            emissive,
            emissive_texture,
            metallic,
            roughness,
            metallic_roughness_texture,
            occlusion_texture,
            normal_texture,
            specular,
            specular_f0,
            specular_texture,
            specular_color_texture,
            casts_shadows,
            unlit,
        } = m;
        f32s(out, &base_color.to_array());
        texture(out, base_color_texture);
        out.push(*alpha_mode as u8);
        f32s(out, &[*alpha_cutoff]);
        out.push(*double_sided as u8);
        vec3(out, *emissive);
        texture(out, emissive_texture);
        f32s(out, &[*metallic, *roughness]);
        texture(out, metallic_roughness_texture);
        scaled(out, occlusion_texture);
        scaled(out, normal_texture);
        f32s(out, &[*specular]);
        // One byte for both flags: a material that is not unlit keeps the bytes (and cached images) it had.
        out.push(*casts_shadows as u8 | (*unlit as u8) << 1);
        // The same for a specular layer at glTF's defaults (no `KHR_materials_ior` or `KHR_materials_specular`
        // colour, no textures): nothing follows; any other ends the material with a 1 and the three.
        let plain = *specular_f0 == Vec3::splat(DIELECTRIC_F0);
        if !plain || specular_texture.is_some() || specular_color_texture.is_some() {
            out.push(1);
            vec3(out, *specular_f0);
            texture(out, specular_texture);
            texture(out, specular_color_texture);
        }
    }

    pub(super) fn light(l: &Light, out: &mut Vec<u8>) {
        let Light { kind, color, intensity, shadows } = l;
        match *kind {
            LightKind::Sun { direction, angle } => {
                out.push(0);
                vec3(out, direction);
                f32s(out, &[angle]);
            }
            LightKind::Point { position, radius } => {
                out.push(1);
                vec3(out, position);
                f32s(out, &[radius]);
            }
            LightKind::Spot { position, direction, cone, blend, radius } => {
                out.push(2);
                vec3(out, position);
                vec3(out, direction);
                f32s(out, &[cone, blend, radius]);
            }
        }
        vec3(out, *color);
        f32s(out, &[*intensity]);
        out.push(*shadows as u8);
    }

    #[cfg(test)]
    mod tests {
        use glam::{Vec2, Vec4};

        use super::*;
        use crate::scene::material::AlphaMode;
        use crate::scene::texture::Wrap;

        fn bytes(m: &Material) -> Vec<u8> {
            let mut out = Vec::new();
            material(m, &mut out);
            out
        }

        #[test]
        fn every_field_of_a_material_and_a_light_moves_its_bytes() {
            let base = Material { base_color_texture: Some(TextureRef::new(0)), ..Material::default() };
            let t = TextureRef::new(0);
            let changed: Vec<Material> = vec![
                Material { base_color: Vec4::new(1.0, 0.5, 1.0, 1.0), ..base.clone() },
                Material { base_color_texture: None, ..base.clone() },
                Material { base_color_texture: Some(TextureRef { texture: 1, ..t }), ..base.clone() },
                Material { base_color_texture: Some(TextureRef { tex_coord: 1, ..t }), ..base.clone() },
                Material { base_color_texture: Some(TextureRef { wrap_s: Wrap::Clamp, ..t }), ..base.clone() },
                Material { base_color_texture: Some(TextureRef { wrap_t: Wrap::Mirror, ..t }), ..base.clone() },
                Material { base_color_texture: Some(TextureRef { nearest: true, ..t }), ..base.clone() },
                Material {
                    base_color_texture: Some(TextureRef { transform: Some([Vec2::X, Vec2::Y, Vec2::ZERO]), ..t }),
                    ..base.clone()
                },
                Material { alpha_mode: AlphaMode::Blend, ..base.clone() },
                Material { alpha_cutoff: 0.25, ..base.clone() },
                Material { double_sided: true, ..base.clone() },
                Material { emissive: Vec3::X, ..base.clone() },
                Material { emissive_texture: Some(t), ..base.clone() },
                Material { metallic: 1.0, ..base.clone() },
                Material { roughness: 0.1, ..base.clone() },
                Material { metallic_roughness_texture: Some(t), ..base.clone() },
                Material { occlusion_texture: Some((t, 1.0)), ..base.clone() },
                Material { normal_texture: Some((t, 1.0)), ..base.clone() },
                Material { normal_texture: Some((t, 0.5)), ..base.clone() },
                Material { specular: 0.0, ..base.clone() },
                Material { specular_f0: Vec3::splat(0.03), ..base.clone() },
                Material { specular_f0: Vec3::new(0.04, 0.04, 0.03), ..base.clone() },
                Material { specular_texture: Some(t), ..base.clone() },
                Material { specular_color_texture: Some(t), ..base.clone() },
                Material { casts_shadows: false, ..base.clone() },
                Material { unlit: true, ..base.clone() },
                Material { casts_shadows: false, unlit: true, ..base.clone() },
            ];
            let mut seen = vec![bytes(&base)];
            for m in &changed {
                let b = bytes(m);
                assert!(!seen.contains(&b), "{m:?}");
                seen.push(b);
            }
            let sun = Light {
                kind: LightKind::Sun { direction: -Vec3::Z, angle: 0.0 },
                color: Vec3::ONE,
                intensity: 1.0,
                shadows: true,
            };
            let lights = [
                sun.clone(),
                Light { kind: LightKind::Sun { direction: -Vec3::Z, angle: 0.1 }, ..sun.clone() },
                Light { kind: LightKind::Sun { direction: -Vec3::Y, angle: 0.0 }, ..sun.clone() },
                Light { kind: LightKind::Point { position: Vec3::ZERO, radius: 0.0 }, ..sun.clone() },
                Light { kind: LightKind::Point { position: Vec3::ZERO, radius: 0.1 }, ..sun.clone() },
                Light {
                    kind: LightKind::Spot {
                        position: Vec3::ZERO,
                        direction: -Vec3::Z,
                        cone: 1.0,
                        blend: 0.1,
                        radius: 0.0,
                    },
                    ..sun.clone()
                },
                Light {
                    kind: LightKind::Spot {
                        position: Vec3::ZERO,
                        direction: -Vec3::Z,
                        cone: 1.0,
                        blend: 0.2,
                        radius: 0.0,
                    },
                    ..sun.clone()
                },
                Light { color: Vec3::X, ..sun.clone() },
                Light { intensity: 2.0, ..sun.clone() },
                Light { shadows: false, ..sun.clone() },
            ];
            let mut seen: Vec<Vec<u8>> = Vec::new();
            for l in &lights {
                let mut b = Vec::new();
                light(l, &mut b);
                assert!(!seen.contains(&b), "{l:?}");
                seen.push(b);
            }
        }
    }
}
