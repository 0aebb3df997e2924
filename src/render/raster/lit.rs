//! Deferred lit (`pbr`) shading of a drawn tile: once per pixel and triangle, after every triangle of the tile
//! is drawn, so hidden samples cost nothing. Reads what [`super::raster_tile`] left per sample (triangle,
//! barycentrics, depth, interpolated normal, albedo).

use glam::{Vec3, Vec4};

use super::{Lit, Projection, Rect, SampleTile, Tri, Tris, NO_TRI};
use crate::render::light::Surface;
use crate::scene::material::{AlphaMode, Material, Texture, TextureRef};
use crate::scene::PosedScene;

/// Lit shading of a drawn tile, deferred so that hidden surfaces cost nothing: once per pixel and triangle, at
/// the pixel's first sample on that triangle, copied to its other samples there (lighting is smooth across a
/// pixel; the albedo is filtered over the pixel's footprint already).
pub(super) fn shade_tile(scene: &PosedScene, tris: &Tris, l: &Lit, rect: Rect, proj: &Projection, t: &mut SampleTile) {
    let Rect { x0, y0, w, h } = rect;
    let k = l.per_side;
    let mut done: [(u32, Vec4); 16] = [(NO_TRI, Vec4::ZERO); 16];
    for py in 0..h / k {
        for px in 0..w / k {
            let mut n_done = 0;
            for sy in 0..k {
                for sx in 0..k {
                    let (lx, ly) = (px * k + sx, py * k + sy);
                    let i = (ly * w + lx) as usize;
                    let id = t.tri[i];
                    if id == NO_TRI {
                        continue;
                    }
                    if let Some(&(_, c)) = done[..n_done].iter().find(|(d, _)| *d == id) {
                        t.color[i] = c;
                        continue;
                    }
                    let at = Sample { at: (x0 + lx, y0 + ly), bary: t.bary[i], z: t.depth[i], normal: t.normal[i] };
                    let c = shade_sample(scene, tris.get(id), l, proj, at, t.color[i].truncate()).extend(1.0);
                    t.color[i] = c;
                    if n_done < done.len() {
                        done[n_done] = (id, c);
                        n_done += 1;
                    }
                }
            }
        }
    }
}

/// Where a triangle covers a sample: the sample's coordinates, the perspective-correct barycentrics there, the
/// view depth and the interpolated normal (toward the eye).
#[derive(Debug, Clone, Copy)]
pub(super) struct Sample {
    pub at: (i64, i64),
    pub bary: [f32; 3],
    pub z: f32,
    pub normal: Vec3,
}

/// Lit radiance of triangle `tri` of albedo `albedo` at sample `s`.
pub(super) fn shade_sample(scene: &PosedScene, tri: &Tri, l: &Lit, proj: &Projection, s: Sample, albedo: Vec3) -> Vec3 {
    let Sample { at, bary: k, z, normal: nrm } = s;
    let mat = scene.material(tri.material);
    let m = LitMaterial::of(mat, &scene.textures);
    let uv = tri.uv[0] * k[0] + tri.uv[1] * k[1] + tri.uv[2] * k[2];
    // d(uv)/dstep = (d(Σ pᵢ·uvᵢ) − uv·d(Σ pᵢ)) / Σ pᵢ, with pᵢ = bᵢ/zᵢ.
    let (dx, dy) = ((tri.duv_step[0] - uv * tri.ds_step[0]) * z, (tri.duv_step[1] - uv * tri.ds_step[1]) * z);
    let sample = |t: Option<(TextureRef, &Texture)>| t.map(|(r, t)| t.sample_footprint(&r, uv, dx, dy));
    // Back to the world: the sample's view-space point at depth z.
    let (sx, sy) = ((at.0 as f32 + 0.5 - proj.f[2]) / proj.f[0], (at.1 as f32 + 0.5 - proj.f[3]) / proj.f[1]);
    let p = l.c2w.transform_point3(Vec3::new(sx * z, -sy * z, -z));
    let v = (l.eye - p).normalize_or_zero();
    // An opaque surface's base colour texture is read here, once per pixel and triangle (see `raster_tile`).
    let mut albedo = albedo;
    if mat.alpha_mode == AlphaMode::Opaque {
        let base = mat.base_color_texture.and_then(|r| scene.textures.get(r.texture as usize).map(|t| (r, t)));
        if let Some(t) = sample(base) {
            albedo *= t.truncate();
        }
    }
    let mut surface =
        Surface { base: albedo, metallic: mat.metallic, roughness: mat.roughness, specular: mat.specular };
    if let Some(mr) = sample(m.metallic_roughness) {
        surface.roughness *= mr.y;
        surface.metallic *= mr.z;
    }
    let ao = m.occlusion.map_or(1.0, |(r, t, strength)| 1.0 + strength * (t.sample_footprint(&r, uv, dx, dy).x - 1.0));
    let vis = tri.vis[0] * k[0] + tri.vis[1] * k[1] + tri.vis[2] * k[2];
    let n = match m.normal {
        Some((r, tex, scale)) => {
            let tangent = tri.tangent[0] * k[0] + tri.tangent[1] * k[1] + tri.tangent[2] * k[2];
            normal_mapped(nrm, tri.back, tangent, tex.sample_footprint(&r, uv, dx, dy), scale)
        }
        None => nrm,
    };
    let emission = mat.emissive * sample(m.emissive).map_or(Vec3::ONE, |e| e.truncate());
    l.light.shade(p, n, v, &surface, ao, vis) + emission
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
fn normal_mapped(n: Vec3, back: bool, tangent: Vec4, texel: Vec4, scale: f32) -> Vec3 {
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
