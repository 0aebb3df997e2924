//! The posed scene: what the renderer and the sampler consume for one frame, in world space, after every
//! transform. Static per-vertex data (indices, uvs, colours) is shared between frames through `Arc`; positions
//! and normals are rewritten in place each frame, so posing a frame after the first allocates nothing.

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::light::Light;
use super::material::{Material, Texture};

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
        h.update(b"vvgen.materials.lit.v1");
        h.update(format!("{:?}", self.materials).as_bytes());
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
        h.update(b"vvgen.posed.lights.v1");
        h.update(format!("{:?}", self.lights).as_bytes());
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
        }
        h.finalize()
    }
}

/// The material as albedo rendering saw it before lit shading existed: its `Debug` text is what
/// [`PosedScene::material_digest`] hashes, byte for byte as before (the struct keeps the name and field order).
mod legacy {
    use glam::{Vec3, Vec4};

    use crate::scene::material::{self as m, AlphaMode, TextureRef};

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
