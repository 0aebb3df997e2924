//! glTF materials as vvgen's: the metallic-roughness model's factors and textures, with their samplers and
//! `KHR_texture_transform`; data textures (metallic-roughness, occlusion, normal) get linear copies.

use glam::{Vec2, Vec3, Vec4};

use super::spec_gloss::SpecGloss;
use crate::scene::material::{dielectric_f0, AlphaMode, Material, DIELECTRIC_F0};
use crate::scene::texture::{Texture, TextureRef, Wrap};

/// The material, and its specular-glossiness parameters when it has `KHR_materials_pbrSpecularGlossiness`
/// (which then takes the place of its metallic-roughness ones, as in Blender's importer, once the textures are
/// decoded: [`SpecGloss::apply`]).
pub(super) fn material(m: &gltf::Material<'_>) -> (Material, Option<SpecGloss>) {
    let sg = SpecGloss::of(m, |i| texture_ref(&i.texture(), i.tex_coord(), i.texture_transform()));
    (core(m), sg)
}

fn core(m: &gltf::Material<'_>) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, a] = pbr.base_color_factor();
    // An unlit material shows its base colour alone (the extension's other properties are ignored, as Blender's
    // importer ignores them).
    let unlit = m.unlit();
    let strength = if unlit { 0.0 } else { m.emissive_strength().unwrap_or(1.0) };
    let (specular, specular_f0, specular_texture, specular_color_texture) = specular(m);
    Material {
        base_color: Vec4::new(r, g, b, a),
        base_color_texture: pbr
            .base_color_texture()
            .map(|i| texture_ref(&i.texture(), i.tex_coord(), i.texture_transform())),
        alpha_mode: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask,
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        alpha_cutoff: m.alpha_cutoff().unwrap_or(0.5),
        double_sided: m.double_sided(),
        emissive: Vec3::from(m.emissive_factor()) * strength,
        emissive_texture: m
            .emissive_texture()
            .filter(|_| !unlit)
            .map(|i| texture_ref(&i.texture(), i.tex_coord(), i.texture_transform())),
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        metallic_roughness_texture: pbr
            .metallic_roughness_texture()
            .map(|i| texture_ref(&i.texture(), i.tex_coord(), i.texture_transform())),
        occlusion_texture: m
            .occlusion_texture()
            .map(|i| (texture_ref(&i.texture(), i.tex_coord(), None), i.strength())),
        normal_texture: m.normal_texture().map(|i| (texture_ref(&i.texture(), i.tex_coord(), None), i.scale())),
        specular,
        specular_f0,
        specular_texture,
        specular_color_texture,
        casts_shadows: true,
        unlit,
    }
}

/// The dielectric specular layer of glTF's `KHR_materials_specular` and `KHR_materials_ior`, as vvgen keeps it:
/// its weight (`specularFactor`, 1 without it), its reflectance at normal incidence (the IOR's, 1.5 without it,
/// times `specularColorFactor`, at most 1) and the textures that multiply each.
///
/// The factor scales the layer's Fresnel at normal and at grazing incidence alike, as the extension specifies,
/// so it is that layer's weight, what vvgen's `specular` is. Blender 4.5 exports a Principled BSDF's Specular
/// IOR Level ℓ as the factor 2ℓ (a matte material, ℓ = 0, as 0; the default 0.5 writes nothing) and imports it
/// back as ℓ; Cycles then scales reflection at normal incidence only, so the two agree at 0 and 1 and differ
/// between at grazing angles. Its importer sets the IOR and the colour as the Principled BSDF's IOR and
/// Specular Tint, which tint reflection at normal incidence, as the extension's colour does. An IOR no material
/// has (negative) reads as glTF's default.
fn specular(m: &gltf::Material<'_>) -> (f32, Vec3, Option<TextureRef>, Option<TextureRef>) {
    let f0 = m.ior().and_then(dielectric_f0).unwrap_or(DIELECTRIC_F0);
    let Some(s) = m.specular() else {
        return (1.0, Vec3::splat(f0), None, None);
    };
    let unit = |f: f32| if f.is_finite() { f.clamp(0.0, 1.0) } else { 1.0 };
    let colour = Vec3::from(s.specular_color_factor().map(|c| if c.is_finite() { c.max(0.0) } else { 1.0 }));
    let texture = |i: gltf::texture::Info<'_>| texture_ref(&i.texture(), i.tex_coord(), i.texture_transform());
    (
        unit(s.specular_factor()),
        (colour * f0).min(Vec3::ONE),
        s.specular_texture().map(texture),
        s.specular_color_texture().map(texture),
    )
}

/// Material extensions that change a surface's look far past what vvgen draws without them (glass, coats,
/// cloth, thin films): a file that uses one is warned of, naming the materials, since its images will not look
/// as Blender's do.
const UNREAD_LOOKS: &[(&str, &str)] = &[
    ("KHR_materials_transmission", "renders opaque, where Blender renders glass"),
    ("KHR_materials_volume", "renders without its absorption"),
    ("KHR_materials_diffuse_transmission", "renders opaque"),
    ("KHR_materials_clearcoat", "renders without its coat"),
    ("KHR_materials_sheen", "renders without its sheen"),
    ("KHR_materials_iridescence", "renders without its thin film"),
    ("KHR_materials_anisotropy", "renders with round highlights"),
    ("KHR_materials_dispersion", "renders without dispersion"),
];

/// A warning per extension of [`UNREAD_LOOKS`] the materials use: which materials, and how they render.
pub(super) fn unread_looks<'a>(materials: impl Iterator<Item = gltf::Material<'a>>) -> Vec<String> {
    let mut users: Vec<Vec<String>> = vec![Vec::new(); UNREAD_LOOKS.len()];
    for m in materials {
        let Some(ext) = m.extensions() else { continue };
        for (i, (name, _)) in UNREAD_LOOKS.iter().enumerate() {
            if ext.contains_key(*name) {
                users[i].push(match (m.index(), m.name()) {
                    (Some(i), Some(n)) => format!("{i} (`{n}`)"),
                    (Some(i), None) => i.to_string(),
                    (None, _) => "the default".into(),
                });
            }
        }
    }
    let shown = |u: &[String]| match u.len() {
        0..=3 => u.join(", "),
        n => format!("{} and {} more", u[..3].join(", "), n - 3),
    };
    UNREAD_LOOKS
        .iter()
        .zip(&users)
        .filter(|(_, u)| !u.is_empty())
        .map(|((name, how), u)| {
            let (who, uses) = if u.len() == 1 { ("material", "uses") } else { ("materials", "use") };
            format!("{who} {} {uses} `{name}`, which vvgen does not read: it {how}", shown(u))
        })
        .collect()
}

/// A material's use of `texture`, with its sampler and `KHR_texture_transform`.
fn texture_ref(
    texture: &gltf::Texture<'_>,
    tex_coord: u32,
    transform: Option<gltf::texture::TextureTransform<'_>>,
) -> TextureRef {
    let s = texture.sampler();
    let wrap = |w: gltf::texture::WrappingMode| match w {
        gltf::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
        gltf::texture::WrappingMode::MirroredRepeat => Wrap::Mirror,
        gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
    };
    let (mut tex_coord, mut map) = (tex_coord, None);
    if let Some(t) = transform {
        // uv' = T · R · S · uv, with R rotating by -rotation as the extension specifies.
        let (sn, cs) = t.rotation().sin_cos();
        let [sx, sy] = t.scale();
        map = Some([Vec2::new(cs * sx, -sn * sx), Vec2::new(sn * sy, cs * sy), Vec2::from(t.offset())]);
        if let Some(tc) = t.tex_coord() {
            tex_coord = tc;
        }
    }
    TextureRef {
        texture: texture.index() as u32,
        tex_coord,
        wrap_s: wrap(s.wrap_s()),
        wrap_t: wrap(s.wrap_t()),
        nearest: s.mag_filter() == Some(gltf::texture::MagFilter::Nearest),
        transform: map,
    }
}

/// Gives every data texture (metallic-roughness, occlusion, normal, specular strength) a linear copy of its image: textures are decoded as
/// sRGB colour, and a data texture read through the sRGB curve would be wrong. An image used both ways is copied.
pub(super) fn linear_data_textures(materials: &mut [Material], textures: &mut Vec<Texture>) {
    let mut linear: std::collections::BTreeMap<u32, u32> = std::collections::BTreeMap::new();
    for m in materials.iter_mut() {
        for (r, srgb) in m.texture_refs_mut() {
            if srgb {
                continue;
            }
            if let Some(&copy) = linear.get(&r.texture) {
                r.texture = copy;
                continue;
            }
            let Some(t) = textures.get(r.texture as usize) else { continue };
            textures.push(Texture::new(t.width, t.height, t.rgba.clone(), false));
            linear.insert(r.texture, textures.len() as u32 - 1);
            r.texture = textures.len() as u32 - 1;
        }
    }
}
