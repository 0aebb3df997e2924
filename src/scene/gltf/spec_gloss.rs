//! `KHR_materials_pbrSpecularGlossiness` as the metallic-roughness material vvgen renders. Khronos archived the
//! extension, but many downloads of 2017–2021 (Sketchfab's among them) still require it, so a newcomer meets it
//! early. Blender's importer renders such a material as a Diffuse shader of the diffuse colour `D` plus a Glossy
//! shader of the specular colour `S`, both at roughness one minus glossiness; vvgen matches that per texel:
//!
//! - a dielectric (`S` at most 0.17 bright, water to diamond) keeps `D` as its base colour, so unlit images show
//!   the file's diffuse texture as it is, and its specular reflectance goes to the material's specular scale
//!   (`F0 = 0.04 × specular`: one per material, from the specular factor and the mean of the texture's
//!   dielectric texels);
//! - a metal (`D` black, `S` bright) is metallic with `S` as its base colour;
//! - between, the metalness `m` and base colour make the diffuse albedo `base (1 − m)` and the specular
//!   reflectance `a (1 − m) + base m` (with `a` the material's dielectric F0) match `D` and `S` on perceived
//!   brightness (`√(0.299 r² + 0.587 g² + 0.114 b²)`): `a m² + (d + s − 2a) m + a − s = 0`; the base colour
//!   blends what `D` and `S` each ask for by `m²`. This is the conversion Khronos published with the extension,
//!   with Blender's unscaled diffuse and the material's own dielectric F0 in place of 0.04: with 0.04, a dark
//!   leather of specular 0.05 came out half metal, and its unlit colour half again as bright as its texture.

use glam::{Vec2, Vec3, Vec4};

use crate::scene::material::{linear_to_srgb8, Material};
use crate::scene::texture::{Texture, TextureRef};

/// The dielectric specular reflectance of glTF's core materials: a material's specular scale 1.
const GLTF_DIELECTRIC: f32 = 0.04;

/// The brightest specular reflectance of a dielectric (diamond's 0.17); above it a specular colour is a metal's.
const MAX_DIELECTRIC: f32 = 0.17;

/// A material's specular-glossiness parameters, kept until the textures are decoded.
#[derive(Debug, Clone)]
pub(super) struct SpecGloss {
    /// Linear RGBA diffuse factor.
    pub diffuse: Vec4,
    /// Linear specular colour factor.
    pub specular: Vec3,
    /// Glossiness factor, 0..1.
    pub glossiness: f32,
    /// Diffuse texture (sRGB RGB, linear alpha).
    pub diffuse_texture: Option<TextureRef>,
    /// Specular (sRGB RGB) and glossiness (linear alpha) texture.
    pub specular_glossiness_texture: Option<TextureRef>,
}

impl SpecGloss {
    /// The extension's parameters, if the material has it.
    pub fn of(m: &gltf::Material<'_>, texture_ref: impl Fn(gltf::texture::Info<'_>) -> TextureRef) -> Option<Self> {
        let sg = m.pbr_specular_glossiness()?;
        Some(SpecGloss {
            diffuse: Vec4::from(sg.diffuse_factor()),
            specular: Vec3::from(sg.specular_factor()),
            glossiness: sg.glossiness_factor(),
            diffuse_texture: sg.diffuse_texture().map(&texture_ref),
            specular_glossiness_texture: sg.specular_glossiness_texture().map(&texture_ref),
        })
    }

    /// Sets `m`'s base colour, metalness and roughness from these parameters; with textures, bakes the
    /// converted texels into two new textures appended to `textures`. Returns a warning when the two textures
    /// read different texture coordinates (they cannot share one baked image: the specular texture is dropped
    /// for its factor).
    pub fn apply(&self, m: &mut Material, textures: &mut Vec<Texture>) -> Option<String> {
        let (mut sg_texture, mut warning) = (self.specular_glossiness_texture, None);
        if let (Some(d), Some(s)) = (&self.diffuse_texture, &sg_texture) {
            if d.tex_coord != s.tex_coord || d.transform != s.transform {
                warning = Some(
                    "its diffuse and specular-glossiness textures read different texture coordinates: the \
                     specular-glossiness texture is left out (its factors kept)"
                        .to_string(),
                );
                sg_texture = None;
            }
        }
        let f0 = self.dielectric_f0(sg_texture.map(|r| &textures[r.texture as usize]));
        m.specular = f0 / GLTF_DIELECTRIC;
        // The baked images follow the texture that lays out the surface: the diffuse one when there is one.
        let Some(layout) = self.diffuse_texture.or(sg_texture) else {
            let (base, metallic) = metal_rough(self.diffuse.truncate(), self.specular, f0);
            m.base_color = base.extend(self.diffuse.w);
            m.base_color_texture = None;
            m.metallic = metallic;
            m.roughness = 1.0 - self.glossiness;
            m.metallic_roughness_texture = None;
            return warning;
        };
        let (w, h) = {
            let t = &textures[layout.texture as usize];
            (t.width, t.height)
        };
        let read = |r: Option<TextureRef>, uv: Vec2| match r {
            // Sampled at the baked texel's centre without the transform: the baked image keeps the layout's
            // reference (sampler, coordinates, transform) and so is laid out as the source images are.
            Some(r) => textures[r.texture as usize].sample(&TextureRef { transform: None, ..r }, uv),
            None => Vec4::ONE,
        };
        let mut base_rgba = Vec::with_capacity((w * h * 4) as usize);
        let mut mr_rgba = Vec::with_capacity((w * h * 4) as usize);
        for y in 0..h {
            for x in 0..w {
                let uv = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                let d = self.diffuse * read(self.diffuse_texture, uv);
                let s = read(sg_texture, uv);
                let (base, metallic) = metal_rough(d.truncate(), self.specular * s.truncate(), f0);
                let roughness = 1.0 - self.glossiness * s.w;
                let unorm = |v: f32| (v * 255.0).round().clamp(0.0, 255.0) as u8;
                base_rgba.extend_from_slice(&[
                    linear_to_srgb8(base.x),
                    linear_to_srgb8(base.y),
                    linear_to_srgb8(base.z),
                    unorm(d.w),
                ]);
                mr_rgba.extend_from_slice(&[0, unorm(roughness), unorm(metallic), 255]);
            }
        }
        textures.push(Texture::new(w, h, base_rgba, true));
        m.base_color = Vec4::ONE;
        m.base_color_texture = Some(TextureRef { texture: textures.len() as u32 - 1, ..layout });
        textures.push(Texture::new(w, h, mr_rgba, false));
        m.metallic = 1.0;
        m.roughness = 1.0;
        m.metallic_roughness_texture = Some(TextureRef { texture: textures.len() as u32 - 1, ..layout });
        warning
    }

    /// The material's dielectric F0: the mean brightness of its dielectric specular colours (the factor's, or
    /// the factor × each texel's of the texture up to [`MAX_DIELECTRIC`]), or glTF's 0.04 when it has none.
    fn dielectric_f0(&self, texture: Option<&Texture>) -> f32 {
        let (mut sum, mut n) = (0.0f64, 0u64);
        let mut add = |s: f32| {
            if s <= MAX_DIELECTRIC {
                sum += f64::from(s);
                n += 1;
            }
        };
        match texture {
            Some(t) => {
                for (y, x) in (0..t.height).flat_map(|y| (0..t.width).map(move |x| (y, x))) {
                    add(brightness(self.specular * t.texel(x, y).truncate()));
                }
            }
            None => add(brightness(self.specular)),
        }
        if n == 0 {
            GLTF_DIELECTRIC
        } else {
            (sum / n as f64) as f32
        }
    }
}

/// Perceived brightness, the scalar both models are matched on.
fn brightness(c: Vec3) -> f32 {
    (0.299 * c.x * c.x + 0.587 * c.y * c.y + 0.114 * c.z * c.z).sqrt()
}

/// The metallic-roughness base colour (linear) and metalness whose diffuse albedo `base (1 − m)` and specular
/// reflectance `f0 (1 − m) + base m` are diffuse colour `diffuse` and specular colour `specular`, matched on
/// brightness (see the module's documentation); `f0` is the material's dielectric reflectance.
pub(crate) fn metal_rough(diffuse: Vec3, specular: Vec3, f0: f32) -> (Vec3, f32) {
    let (d, s) = (brightness(diffuse), brightness(specular));
    let metallic = if s <= f0 {
        0.0
    } else if f0 < 1e-6 {
        // No dielectric reflectance: the quadratic is linear, d m + s m − s = 0.
        s / (d + s)
    } else {
        let (a, b, c) = (f0, d + s - 2.0 * f0, f0 - s);
        ((-b + (b * b - 4.0 * a * c).max(0.0).sqrt()) / (2.0 * a)).clamp(0.0, 1.0)
    };
    let from_diffuse = diffuse / (1.0 - metallic).max(1e-4);
    let from_specular = (specular - Vec3::splat(f0 * (1.0 - metallic))) / metallic.max(1e-4);
    let base = from_diffuse.lerp(from_specular, metallic * metallic).clamp(Vec3::ZERO, Vec3::ONE);
    (base, metallic)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What a metallic-roughness material reflects: (diffuse albedo, specular F0).
    fn reflects(base: Vec3, metallic: f32, f0: f32) -> (Vec3, Vec3) {
        (base * (1.0 - metallic), Vec3::splat(f0).lerp(base, metallic))
    }

    #[test]
    fn dielectrics_and_metals_reflect_what_they_asked_for() {
        // A dielectric at the material's F0: its diffuse colour is its base colour, as it is.
        let diffuse = Vec3::new(0.6, 0.3, 0.1);
        assert_eq!(metal_rough(diffuse, Vec3::splat(0.05), 0.05), (diffuse, 0.0));
        assert_eq!(metal_rough(diffuse, Vec3::splat(0.01), 0.04), (diffuse, 0.0));
        // Gold: no diffuse, a coloured specular. A metal whose base colour is that specular.
        let gold = Vec3::new(1.0, 0.766, 0.336);
        let (base, m) = metal_rough(Vec3::ZERO, gold, 0.04);
        assert!(m > 0.999, "{m}");
        assert!((base - gold).abs().max_element() < 1e-3, "{base}");
        // In between (a dull grey metal, some diffuse): both reflectances within 2 % of brightness.
        for f0 in [0.0, 0.04, 0.1] {
            let (diffuse, specular) = (Vec3::splat(0.2), Vec3::splat(0.5));
            let (base, m) = metal_rough(diffuse, specular, f0);
            let (d, s) = reflects(base, m, f0);
            assert!((brightness(s) - brightness(specular)).abs() < 0.02, "{s} for {specular} at {f0}");
            assert!((brightness(d) - brightness(diffuse)).abs() < 0.02, "{d} for {diffuse} at {f0}");
        }
    }

    #[test]
    fn the_dielectric_f0_is_the_mean_of_the_dielectric_texels() {
        // sRGB 56 is linear 0.0395, 99 is 0.125, 255 is 1 (a metal's, left out).
        let t = Texture::new(3, 1, vec![56, 56, 56, 255, 99, 99, 99, 255, 255, 255, 255, 255], true);
        let sg = |specular: Vec3| SpecGloss {
            diffuse: Vec4::ONE,
            specular,
            glossiness: 1.0,
            diffuse_texture: None,
            specular_glossiness_texture: None,
        };
        let f0 = sg(Vec3::ONE).dielectric_f0(Some(&t));
        assert!((f0 - (0.0395 + 0.125) / 2.0).abs() < 1e-3, "{f0}");
        assert_eq!(sg(Vec3::splat(0.08)).dielectric_f0(None), 0.08);
        assert_eq!(sg(Vec3::ONE).dielectric_f0(None), GLTF_DIELECTRIC);
    }

    #[test]
    fn textures_are_baked_texel_by_texel() {
        // 2×1 diffuse (red, white half transparent) and specular-glossiness (dielectric 0.033 and glossy; gold
        // and rough) textures.
        let mut textures = vec![
            Texture::new(2, 1, vec![255, 0, 0, 255, 255, 255, 255, 128], true),
            Texture::new(2, 1, vec![51, 51, 51, 255, 255, 225, 156, 0], true),
        ];
        let sg = SpecGloss {
            diffuse: Vec4::ONE,
            specular: Vec3::ONE,
            glossiness: 0.8,
            diffuse_texture: Some(TextureRef::new(0)),
            specular_glossiness_texture: Some(TextureRef::new(1)),
        };
        let mut m = Material::default();
        assert!(sg.apply(&mut m, &mut textures).is_none());
        assert_eq!(textures.len(), 4);
        let (base, mr) = (&textures[2], &textures[3]);
        assert!(base.srgb && !mr.srgb);
        assert_eq!(m.base_color_texture.unwrap().texture, 2);
        assert_eq!(m.metallic_roughness_texture.unwrap().texture, 3);
        assert_eq!((m.metallic, m.roughness, m.base_color), (1.0, 1.0, Vec4::ONE));
        // The one dielectric texel (linear 0.033) sets the material's F0.
        assert!((m.specular * GLTF_DIELECTRIC - 0.0331).abs() < 1e-3, "{}", m.specular);
        // Texel 0: that dielectric: its red diffuse as it is, roughness 1 − 0.8.
        assert_eq!(&base.rgba[0..4], &[255, 0, 0, 255]);
        assert_eq!(&mr.rgba[0..4], &[0, 51, 0, 255]);
        // Texel 1: a white diffuse and a gold specular both (more light than either model's energy allows):
        // about half metal, its base colour the white the diffuse asks for (the blend weighs the specular's
        // by m², a quarter); glossiness 0 is roughness 1; the diffuse alpha is kept.
        assert!((80..200).contains(&mr.rgba[6]), "{:?}", &mr.rgba[4..8]);
        assert_eq!(mr.rgba[5], 255);
        assert!(base.rgba[4..7].iter().all(|&c| c > 240), "{:?}", &base.rgba[4..8]);
        assert_eq!(base.rgba[7], 128);
        // Different texture coordinates cannot share one baked image: warned, the specular texture dropped
        // (its factors: a white specular, mostly metal on the red diffuse; glossiness 0.8).
        let sg =
            SpecGloss { specular_glossiness_texture: Some(TextureRef { tex_coord: 1, ..TextureRef::new(1) }), ..sg };
        let mut m = Material::default();
        assert!(sg.apply(&mut m, &mut textures).is_some());
        let mr = &textures[5].rgba[0..4];
        assert!(mr[1] == 51 && mr[2] > 100, "{mr:?}");
    }
}
