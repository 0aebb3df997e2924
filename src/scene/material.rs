//! Materials as the renderer and the point sampler read them: glTF 2.0 metallic-roughness (base colour,
//! metallic and roughness, occlusion, emissive), with what `shading = "pbr"` needs besides albedo; and the sRGB
//! transfer function their colours are written in. Their textures are [`super::texture`]'s.

use std::sync::LazyLock;

use glam::{Vec2, Vec3, Vec4};

use super::texture::{Texture, TextureRef};

/// A dielectric's reflectance at normal incidence at glTF's default index of refraction, 1.5.
pub const DIELECTRIC_F0: f32 = 0.04;

/// The reflectance at normal incidence of a dielectric of index of refraction `ior` (in air): ((ior − 1) /
/// (ior + 1))², [`DIELECTRIC_F0`] exactly at 1.5 (so a file that states glTF's default renders as one that does
/// not), and 1 at glTF's special value 0. `None` for an index no material has (negative, or not finite).
pub fn dielectric_f0(ior: f32) -> Option<f32> {
    if !(ior.is_finite() && ior >= 0.0) {
        return None;
    }
    if ior == 1.5 {
        return Some(DIELECTRIC_F0);
    }
    Some(((ior - 1.0) / (ior + 1.0)).powi(2))
}

/// How alpha is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AlphaMode {
    /// Alpha ignored.
    Opaque,
    /// Alpha below the cutoff discards the fragment.
    Mask,
    /// Alpha blends.
    Blend,
}

/// One material.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Linear RGBA base colour factor.
    pub base_color: Vec4,
    /// Base colour texture (sRGB).
    pub base_color_texture: Option<TextureRef>,
    /// Alpha mode.
    pub alpha_mode: AlphaMode,
    /// Cutoff for MASK (default 0.5).
    pub alpha_cutoff: f32,
    /// Render back faces too.
    pub double_sided: bool,
    /// Linear emissive factor (× strength).
    pub emissive: Vec3,
    /// Emissive texture (sRGB), multiplying `emissive`.
    pub emissive_texture: Option<TextureRef>,
    /// Metalness factor, 0..1.
    pub metallic: f32,
    /// Perceptual roughness factor, 0..1.
    pub roughness: f32,
    /// Metallic-roughness texture (linear; roughness in G, metalness in B), multiplying the factors.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Occlusion texture (linear, R) and its strength.
    pub occlusion_texture: Option<(TextureRef, f32)>,
    /// Tangent-space normal texture (linear, RGB) and its scale (of X and Y).
    pub normal_texture: Option<(TextureRef, f32)>,
    /// Scale of the dielectric specular layer: 1 is glTF's (F0 = 0.04), 0 a purely diffuse (Lambertian)
    /// surface such as the built-in ground plane.
    pub specular: f32,
    /// The dielectric layer's reflectance at normal incidence, per channel, before `specular` scales it:
    /// ((ior − 1) / (ior + 1))² for glTF's `KHR_materials_ior` (1.5 when absent: 0.04) times
    /// `KHR_materials_specular`'s colour, at most 1, as Blender's importer sets the Principled BSDF's IOR and
    /// Specular Tint.
    pub specular_f0: Vec3,
    /// `KHR_materials_specular`'s strength texture (linear, its alpha multiplying `specular`).
    pub specular_texture: Option<TextureRef>,
    /// `KHR_materials_specular`'s colour texture (sRGB, multiplying `specular_f0`).
    pub specular_color_texture: Option<TextureRef>,
    /// Whether the surface casts shadows (the ground plane receives only).
    pub casts_shadows: bool,
    /// Shadeless (glTF's `KHR_materials_unlit`, as Blender's importer builds it): lit or not, it shows its
    /// base colour (× vertex colour × texture) as it is, and it is transparent to every ray but the camera's,
    /// so it casts no shadow and bounces no light.
    pub unlit: bool,
}

impl Default for Material {
    /// The default material: white, opaque, single-sided, dielectric with roughness 0.5.
    fn default() -> Self {
        Material {
            base_color: Vec4::ONE,
            base_color_texture: None,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            double_sided: false,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            // Blender's default surface (what its glTF importer gives a primitive without a material), not glTF's
            // metallic default: an unmaterialed mesh should look grey and diffuse, not like a mirror.
            metallic: 0.0,
            roughness: 0.5,
            metallic_roughness_texture: None,
            occlusion_texture: None,
            normal_texture: None,
            specular: 1.0,
            specular_f0: Vec3::splat(DIELECTRIC_F0),
            specular_texture: None,
            specular_color_texture: None,
            casts_shadows: true,
            unlit: false,
        }
    }
}

impl Material {
    /// What a surface renders as when its file gives it neither a material nor colours: Blender's default
    /// surface, a diffuse grey of 0.8 without a specular layer (Cycles 4.5 renders it 0.80 under a uniform white
    /// sky, head-on and at 69°). White instead sat at the top of the range, clipped when lit and lost on the
    /// white backgrounds NeRF-synthetic trains on. A surface with vertex colours keeps the white default: its
    /// colours are its colour (as glTF specifies for a primitive's COLOR_0).
    pub fn unassigned() -> Material {
        Material { base_color: Vec4::new(0.8, 0.8, 0.8, 1.0), specular: 0.0, ..Material::default() }
    }
}

/// sRGB byte → linear float.
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear float → sRGB float.
#[inline]
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB byte → linear, tabulated (texture sampling decodes four texels per sample; `powf` would dominate).
pub(super) static SRGB8_TO_LINEAR: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0)));

/// Linear values where the sRGB byte code steps up: code k+1 starts at `linear(k + 0.5)`; entry 255 is +∞.
static SRGB8_STEPS: LazyLock<[f32; 256]> = LazyLock::new(|| {
    std::array::from_fn(|k| if k < 255 { srgb_to_linear((k as f32 + 0.5) / 255.0) } else { f32::INFINITY })
});

/// Buckets of [`SRGB8_START`]: the top 16 bits of an f32 in [0, 1] (exponent and 7 mantissa bits, so each bucket
/// spans 1/128 of its octave). That is fine enough for at most one code boundary per bucket: boundaries are
/// ≥ 3e-4 apart in linear light where buckets are narrower still, and 0.009 apart near 1, where they are 0.004.
const SRGB8_BUCKETS: usize = (1.0f32.to_bits() >> 16) as usize + 1;

/// The sRGB code at each bucket's lower end: where [`linear_to_srgb8`] starts.
static SRGB8_START: LazyLock<[u8; SRGB8_BUCKETS]> = LazyLock::new(|| {
    std::array::from_fn(|i| SRGB8_STEPS.partition_point(|&t| t <= f32::from_bits((i as u32) << 16)) as u8)
});

/// Linear float → nearest sRGB byte: the number of code boundaries at or below `c`, from its bucket's first code
/// and one comparison with the next boundary (exactly what a binary search over the boundaries gives, without
/// its unpredictable branches; this runs three times per covered pixel).
#[inline]
pub fn linear_to_srgb8(c: f32) -> u8 {
    Srgb8::tables().encode(c)
}

/// [`linear_to_srgb8`] with its tables looked up once, for loops over pixels (each lookup of a lazily built
/// table checks that it is built).
#[derive(Debug, Clone, Copy)]
pub struct Srgb8 {
    start: &'static [u8; SRGB8_BUCKETS],
    steps: &'static [f32; 256],
}

impl Srgb8 {
    /// The encoder's tables.
    #[inline]
    pub fn tables() -> Srgb8 {
        Srgb8 { start: &SRGB8_START, steps: &SRGB8_STEPS }
    }

    /// Linear float → nearest sRGB byte ([`linear_to_srgb8`]).
    #[inline]
    pub fn encode(self, c: f32) -> u8 {
        // NaN, negatives and −0 become +0; values above 1 become 1, code 255.
        let c = if c > 0.0 { c.min(1.0) } else { 0.0 };
        let code = self.start[(c.to_bits() >> 16) as usize];
        code + (c >= self.steps[code as usize]) as u8
    }
}

/// sRGB byte → linear float, tabulated.
#[inline]
pub fn srgb8_to_linear(v: u8) -> f32 {
    SRGB8_TO_LINEAR[v as usize]
}

impl Material {
    /// Every texture reference of the material, with whether it holds colour (sRGB) rather than data.
    pub fn texture_refs_mut(&mut self) -> impl Iterator<Item = (&mut TextureRef, bool)> {
        let occlusion = self.occlusion_texture.as_mut().map(|(r, _)| r);
        let normal = self.normal_texture.as_mut().map(|(r, _)| r);
        [
            (self.base_color_texture.as_mut(), true),
            (self.emissive_texture.as_mut(), true),
            (self.metallic_roughness_texture.as_mut(), false),
            (occlusion, false),
            (normal, false),
            (self.specular_texture.as_mut(), false),
            (self.specular_color_texture.as_mut(), true),
        ]
        .into_iter()
        .filter_map(|(r, srgb)| r.map(|r| (r, srgb)))
    }

    /// Albedo (linear RGBA) at a surface point: base colour × texture × vertex colour.
    pub fn albedo(&self, textures: &[Texture], uv: Option<Vec2>, vertex_color: Option<Vec4>) -> Vec4 {
        let mut c = self.base_color;
        if let (Some(r), Some(uv)) = (&self.base_color_texture, uv) {
            if let Some(t) = textures.get(r.texture as usize) {
                c *= t.sample(r, uv);
            }
        }
        if let Some(v) = vertex_color {
            c *= v;
        }
        c
    }

    /// Emitted radiance (linear RGB) at a surface point: the emissive factor × its texture.
    pub fn emission(&self, textures: &[Texture], uv: Option<Vec2>) -> Vec3 {
        match (&self.emissive_texture, uv) {
            (Some(r), Some(uv)) if self.emissive != Vec3::ZERO => {
                textures.get(r.texture as usize).map_or(self.emissive, |t| self.emissive * t.sample(r, uv).truncate())
            }
            _ => self.emissive,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dielectric_reflects_at_normal_incidence_as_its_ior_gives() {
        assert_eq!(dielectric_f0(1.5), Some(DIELECTRIC_F0));
        assert_eq!(dielectric_f0(1.0), Some(0.0));
        assert_eq!(dielectric_f0(0.0), Some(1.0), "glTF's special value: a mirror");
        assert!((dielectric_f0(1.45).unwrap() - 0.033_735).abs() < 1e-6, "Blender 3.x's default IOR");
        for bad in [-1.0, f32::NAN, f32::INFINITY] {
            assert_eq!(dielectric_f0(bad), None, "{bad}");
        }
    }

    #[test]
    fn srgb8_encoding_is_the_exact_nearest_code() {
        // Every boundary, just below and at it, and a dense sweep: the bucketed lookup equals the binary search.
        let reference = |c: f32| SRGB8_STEPS[..255].partition_point(|&t| t <= c) as u8;
        let mut probes: Vec<f32> =
            SRGB8_STEPS[..255].iter().flat_map(|&t| [t, f32::from_bits(t.to_bits() - 1)]).collect();
        probes.extend((0..=100_000).map(|i| i as f32 / 100_000.0));
        probes.extend([-1.0, -0.0, 0.0, 1.0, 1.5, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MIN_POSITIVE / 2.0]);
        for c in probes {
            assert_eq!(linear_to_srgb8(c), reference(c), "{c}");
        }
        for v in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(v)), v, "round trip of {v}");
        }
    }
}
