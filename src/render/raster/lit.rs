//! Lit (`pbr`) shading: of a drawn tile, deferred, once per pixel and triangle at the centroid of the
//! triangle's samples there ([`super::deferred`]), from what [`super::raster_tile`] left per sample (triangle,
//! barycentrics, depth, albedo); and of single samples (blended surfaces).

use glam::{Vec2, Vec3, Vec4};

use super::deferred::for_each_share;
use super::{Lit, Projection, Rect, SampleTile, Tri, Tris};
use crate::render::light::{Surface, Visibility};
use crate::scene::material::{AlphaMode, Material};
use crate::scene::texture::{Texture, TextureRef};
use crate::scene::PosedScene;

/// Lit shading of a drawn tile's deferred samples: once per pixel and triangle, at the centroid of its samples
/// there, with their mean albedo, and copied to each of them (lighting is smooth across a pixel; textures are
/// filtered over the pixel's footprint).
pub(super) fn shade_tile(
    scene: &PosedScene,
    tris: &Tris,
    l: &Lit,
    k: i64,
    rect: Rect,
    proj: &Projection,
    t: &mut SampleTile,
) {
    for_each_share(t, rect.x0, rect.y0, k, |s, t| {
        let tri = tris.get(s.id);
        let albedo = s.samples[..s.n].iter().map(|&i| t.color[i as usize].truncate()).sum::<Vec3>() / s.n as f32;
        let at = Sample { at: s.at, bary: s.bary, z: s.z, footprint: k as f32 };
        let c = shade_sample(scene, tri, l, proj, at, albedo).extend(1.0);
        for &i in &s.samples[..s.n] {
            t.color[i as usize] = c;
        }
    });
}

/// Where a triangle is shaded: the point's sample coordinates (continuous: a sample's centre is at +0.5), the
/// perspective-correct barycentrics there, the view depth and the footprint of the shading in samples (textures
/// are filtered over it).
#[derive(Debug, Clone, Copy)]
pub(super) struct Sample {
    pub at: Vec2,
    pub bary: [f32; 3],
    pub z: f32,
    pub footprint: f32,
}

/// Lit radiance of triangle `tri` of albedo `albedo` at sample `s`.
pub(super) fn shade_sample(scene: &PosedScene, tri: &Tri, l: &Lit, proj: &Projection, s: Sample, albedo: Vec3) -> Vec3 {
    let Sample { at, bary: k, z, footprint } = s;
    let mat = scene.material(tri.material);
    // Back to the world: the point's view-space position at depth z.
    let (sx, sy) = ((at.x - proj.f[2]) / proj.f[0], (at.y - proj.f[3]) / proj.f[1]);
    let p = l.c2w.transform_point3(Vec3::new(sx * z, -sy * z, -z));
    if !tri.back && plain(mat) {
        if let Some(c) = l.light.shade_ground(tri.material, p, albedo) {
            return l.light.exposed(c + mat.emissive);
        }
    }
    let nrm = tri.normal_at(k);
    let m = LitMaterial::of(mat, &scene.textures);
    let (uv, dx, dy) = tri.uv_footprint(k, z, footprint);
    // Opaque base colour and the data textures ignore alpha.
    let sample = |t: Option<(TextureRef, &Texture)>| t.map(|(r, t)| t.sample_footprint_rgb(&r, uv, dx, dy));
    let v = (l.eye - p).normalize_or_zero();
    // An opaque surface's base colour texture is read here, once per pixel and triangle (see `raster_tile`).
    let mut albedo = albedo;
    if mat.alpha_mode == AlphaMode::Opaque {
        let base = mat.base_color_texture.and_then(|r| scene.textures.get(r.texture as usize).map(|t| (r, t)));
        if let Some(t) = sample(base) {
            albedo *= t;
        }
    }
    let mut surface =
        Surface { base: albedo, metallic: mat.metallic, roughness: mat.roughness, specular: mat.specular };
    if let Some(mr) = sample(m.metallic_roughness) {
        surface.roughness *= mr.y;
        surface.metallic *= mr.z;
    }
    let ao =
        m.occlusion.map_or(1.0, |(r, t, strength)| 1.0 + strength * (t.sample_footprint_rgb(&r, uv, dx, dy).x - 1.0));
    // A ground plane's visibility is a grid; a subject's comes from its vertices, with the bounce they gathered.
    let vis = match l.light.plane_visibility_at(tri.material, p) {
        Some(v) => v,
        None => Visibility::blend(&tri.vis, k),
    };
    let n = match m.normal {
        Some((r, tex, scale)) => {
            let tangent = tri.tangent[0] * k[0] + tri.tangent[1] * k[1] + tri.tangent[2] * k[2];
            normal_mapped(nrm, tri.back, tangent, tex.sample_footprint_rgb(&r, uv, dx, dy), scale)
        }
        None => nrm,
    };
    let emission = mat.emissive * sample(m.emissive).unwrap_or(Vec3::ONE);
    l.light.exposed(l.light.shade(p, n, v, &surface, ao, vis, false) + emission)
}

/// Whether a material is Lambertian and untextured, as a `plane` source's is: the top face of a ground plane of
/// it is shaded by [`crate::render::light::FrameLight::shade_ground`].
fn plain(m: &Material) -> bool {
    m.base_color_texture.is_none()
        && m.metallic_roughness_texture.is_none()
        && m.occlusion_texture.is_none()
        && m.emissive_texture.is_none()
        && m.normal_texture.is_none()
        && m.metallic == 0.0
        && m.specular == 0.0
}

/// A material's textures that lit shading reads, resolved once per triangle.
struct LitMaterial<'t> {
    metallic_roughness: Option<(TextureRef, &'t Texture)>,
    /// With its strength.
    occlusion: Option<(TextureRef, &'t Texture, f32)>,
    emissive: Option<(TextureRef, &'t Texture)>,
    /// With its scale.
    normal: Option<(TextureRef, &'t Texture, f32)>,
}

impl<'t> LitMaterial<'t> {
    fn of(m: &Material, textures: &'t [Texture]) -> LitMaterial<'t> {
        let get = |r: Option<TextureRef>| r.and_then(|r| textures.get(r.texture as usize).map(|t| (r, t)));
        LitMaterial {
            metallic_roughness: get(m.metallic_roughness_texture),
            occlusion: m.occlusion_texture.and_then(|(r, k)| get(Some(r)).map(|(r, t)| (r, t, k))),
            emissive: get(m.emissive_texture),
            normal: m.normal_texture.and_then(|(r, k)| get(Some(r)).map(|(r, t)| (r, t, k))),
        }
    }
}

/// The shading normal from a normal texture's texel `texel` (linear, 0..1 per channel) in the tangent frame of the
/// interpolated normal `n` (flipped toward the eye when `back`) and `tangent` (xyz, handedness w), glTF's way:
/// the texel's X and Y are scaled by `scale` and the result is T·x + B·y + N·z with B = w·(N × T). A back face is
/// mapped in its front's frame, then flipped, as its geometric normal is. Without a usable tangent (none given,
/// or degenerate) the normal stays as it is.
fn normal_mapped(n: Vec3, back: bool, tangent: Vec4, texel: Vec3, scale: f32) -> Vec3 {
    let front = if back { -n } else { n };
    // Gram–Schmidt: the interpolated tangent leans off the interpolated normal.
    let t = tangent.truncate() - front * front.dot(tangent.truncate());
    if t.length_squared() < 1e-12 {
        return n;
    }
    let t = t.normalize();
    let b = front.cross(t) * if tangent.w < 0.0 { -1.0 } else { 1.0 };
    let x = (texel.x * 2.0 - 1.0) * scale;
    let y = (texel.y * 2.0 - 1.0) * scale;
    let z = texel.z * 2.0 - 1.0;
    let mapped = (t * x + b * y + front * z).normalize_or(front);
    if back {
        -mapped
    } else {
        mapped
    }
}
