//! Lit (`pbr`) shading: of a drawn tile, deferred, once per pixel and triangle at the centroid of the
//! triangle's samples there ([`super::deferred`]), from what [`super::raster_tile`] left per sample (triangle,
//! barycentrics, depth, albedo); and of single samples (blended surfaces).
//!
//! A glossy surface's rays ([`crate::render::light::FrameLight::shade_lobe`]) are most of its pixels' cost (FlightHelmet's renders
//! took twice as long with them), and what they find, the share of the reflection open to the sky, changes
//! slowly across a surface: it steps only where a ray starts or stops meeting a caster. So a tile casts them at
//! every other pixel of every other row first, the anchors, and a pixel between anchors takes the mean of
//! theirs when they agree: all found an answer within [`LOBE_AGREE`] of each other, on the pixel's own
//! material, facing as it does ([`SAME_FACING`]) at its depth ([`SAME_DEPTH`]). Everything else (textures,
//! normals, lights and their shadows, the environment) is still found at every pixel; a pixel whose anchors do
//! not agree, or lie past the tile or off the surface, casts its own rays.

use glam::{Vec2, Vec3, Vec4};

use super::deferred::{for_each_share, Pixels, Share};
use super::{Lit, Projection, Rect, SampleTile, Tri, Tris};
use crate::render::light::{Lobe, Surface, Visibility};
use crate::scene::material::{AlphaMode, Material};
use crate::scene::texture::{Texture, TextureRef};
use crate::scene::PosedScene;

/// How far apart the anchors' open shares may lie for a pixel between them to take their mean: less than one
/// ray's weight (an eighth of the lobe), so the anchors' rays met the same casters.
const LOBE_AGREE: f32 = 0.05;
/// The least cosine between a pixel's interpolated normal and its anchors', and the largest relative step of
/// its inverse depth (linear across a plane in screen space) from their mean: the same smooth surface.
const SAME_FACING: f32 = 0.9;
const SAME_DEPTH: f32 = 0.01;

/// What an anchor pixel's rays found, and where: the share of its lobe open to the sky, its material, its
/// interpolated normal and its inverse depth.
#[derive(Debug, Clone, Copy)]
pub(super) struct Anchor {
    open: f32,
    material: u32,
    normal: Vec3,
    inv_z: f32,
    samples: usize,
}

/// Lit shading of a drawn tile's deferred samples: once per pixel and triangle, at the centroid of its samples
/// there, with their mean albedo, and copied to each of them (lighting is smooth across a pixel; textures are
/// filtered over the pixel's footprint). The anchors first, then the pixels between them (see the module's
/// note).
pub(super) fn shade_tile(
    scene: &PosedScene,
    tris: &Tris,
    l: &Lit,
    k: i64,
    rect: Rect,
    proj: &Projection,
    t: &mut SampleTile,
) {
    let sample = |s: &Share| Sample { at: s.at, bary: s.bary, z: s.z, footprint: k as f32 };
    if !l.light.casts_rays() {
        // No glossy lobe casts rays (CesiumMan's frames): one pass, no anchors.
        for_each_share(t, rect.x0, rect.y0, k, Pixels::All, |s, t| {
            let (c, _) = shade_lobe(scene, tris.get(s.id), l, proj, sample(s), albedo(s, t), Lobe::Rays);
            fill(t, s, c);
        });
        return;
    }
    let aw = ((t.w / k) as usize).div_ceil(2);
    let mut anchors = std::mem::take(&mut t.anchors);
    anchors.clear();
    anchors.resize(aw * ((t.h / k) as usize).div_ceil(2), None);
    for_each_share(t, rect.x0, rect.y0, k, Pixels::Even, |s, t| {
        let tri = tris.get(s.id);
        let (c, open) = shade_lobe(scene, tri, l, proj, sample(s), albedo(s, t), Lobe::Rays);
        let slot = &mut anchors[(s.py / 2) as usize * aw + (s.px / 2) as usize];
        if let Some(open) = open.filter(|_| slot.is_none_or(|a| a.samples < s.n)) {
            let (normal, inv_z) = (tri.normal_at(s.bary), 1.0 / s.z);
            *slot = Some(Anchor { open, material: tri.material, normal, inv_z, samples: s.n });
        }
        fill(t, s, c);
    });
    for_each_share(t, rect.x0, rect.y0, k, Pixels::NotEven, |s, t| {
        let tri = tris.get(s.id);
        let given = agreed(tri, s, &anchors, aw);
        let lobe = given.map_or(Lobe::Rays, Lobe::Found);
        let (c, _) = shade_lobe(scene, tri, l, proj, sample(s), albedo(s, t), lobe);
        fill(t, s, c);
    });
    t.anchors = anchors;
}

/// The mean albedo of a share's samples.
#[inline]
fn albedo(s: &Share, t: &SampleTile) -> Vec3 {
    s.samples[..s.n].iter().map(|&i| t.color[i as usize].truncate()).sum::<Vec3>() / s.n as f32
}

/// Writes radiance `c` to each of a share's samples.
#[inline]
fn fill(t: &mut SampleTile, s: &Share, c: Vec3) {
    let c = c.extend(1.0);
    for &i in &s.samples[..s.n] {
        t.color[i as usize] = c;
    }
}

/// The mean of the open shares the anchors about share `s` (of a pixel that is not an anchor) of triangle `tri`
/// found, when there are such anchors (of `anchors`, `aw` to a row) and they agree; else `None`, and the share
/// casts its own rays. The anchors about a pixel: left and right on an anchor row, above and below on an anchor
/// column, the four corners otherwise.
fn agreed(tri: &Tri, s: &Share, anchors: &[Option<Anchor>], aw: usize) -> Option<f32> {
    let (ax, ay) = ((s.px / 2) as usize, (s.py / 2) as usize);
    let (nx, ny) = (1 + (s.px % 2) as usize, 1 + (s.py % 2) as usize);
    if ax + nx > aw {
        return None;
    }
    let mut found = [None; 4];
    for j in 0..ny {
        for i in 0..nx {
            found[j * nx + i] = Some(anchors.get((ay + j) * aw + ax + i).copied().flatten()?);
        }
    }
    // (The normal only once every anchor is there: most pixels with a missing one are not glossy at all.)
    let normal = tri.normal_at(s.bary);
    let (mut lo, mut hi, mut sum, mut inv_z) = (f32::INFINITY, f32::NEG_INFINITY, 0.0, 0.0);
    for a in found.iter().flatten() {
        if a.material != tri.material || a.normal.dot(normal) < SAME_FACING {
            return None;
        }
        (lo, hi, sum, inv_z) = (lo.min(a.open), hi.max(a.open), sum + a.open, inv_z + a.inv_z);
    }
    let w = 1.0 / (nx * ny) as f32;
    let mine = 1.0 / s.z;
    (hi - lo <= LOBE_AGREE && (inv_z * w - mine).abs() <= SAME_DEPTH * mine).then_some(sum * w)
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

/// Lit radiance of triangle `tri` of albedo `albedo` at sample `s`, its glossy lobe's occlusion found as `lobe`
/// says, and what the lobe's rays found, when it cast them ([`crate::render::light::FrameLight::shade_lobe`]).
pub(super) fn shade_lobe(
    scene: &PosedScene,
    tri: &Tri,
    l: &Lit,
    proj: &Projection,
    s: Sample,
    albedo: Vec3,
    lobe: Lobe,
) -> (Vec3, Option<f32>) {
    let Sample { at, bary: k, z, footprint } = s;
    let mat = scene.material(tri.material);
    // Back to the world: the point's view-space position at depth z.
    let (sx, sy) = ((at.x - proj.f[2]) / proj.f[0], (at.y - proj.f[3]) / proj.f[1]);
    let p = l.c2w.transform_point3(Vec3::new(sx * z, -sy * z, -z));
    if !tri.back && plain(mat) {
        if let Some(c) = l.light.shade_ground(tri.material, p, albedo) {
            return (l.light.exposed(c + mat.emissive), None);
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
    if mat.unlit {
        // Shadeless: what Blender's Emission of the base colour shows the camera, through the film's exposure.
        return (l.light.exposed(albedo), None);
    }
    let mut surface = Surface {
        base: albedo,
        metallic: mat.metallic,
        roughness: mat.roughness,
        specular: mat.specular,
        f0: mat.specular_f0,
    };
    if let Some(mr) = sample(m.metallic_roughness) {
        surface.roughness *= mr.y;
        surface.metallic *= mr.z;
    }
    if let Some((r, t)) = m.specular {
        surface.specular *= t.sample_footprint(&r, uv, dx, dy).w;
    }
    if let Some(c) = sample(m.specular_color) {
        surface.f0 = (surface.f0 * c).min(Vec3::ONE);
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
    let (c, open) = l.light.shade_lobe(p, n, v, &surface, ao, vis, false, lobe);
    (l.light.exposed(c + emission), open)
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
    /// `KHR_materials_specular`'s strength (alpha) and colour.
    specular: Option<(TextureRef, &'t Texture)>,
    specular_color: Option<(TextureRef, &'t Texture)>,
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
            specular: get(m.specular_texture),
            specular_color: get(m.specular_color_texture),
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

#[cfg(test)]
mod tests {
    use super::super::{draw_triangles, raster_tile, setup, Shade, TileWork, Tiles};
    use super::*;
    use crate::render::light::FrameLight;
    use crate::render::light::PointCasters;
    use crate::scene::material::Material;
    use glam::Mat4;

    #[test]
    fn pixels_that_take_their_anchors_rays_shade_as_if_they_cast_their_own() {
        // A glossy metal floor, half under a low roof: its reflection of the sky is open on one side, blocked on
        // the other, and steps between along the roof's edge. Every tile is shaded as a render does (anchors,
        // then the pixels between) and again with every pixel casting its own rays.
        let quad = |corners: [Vec3; 4], normal: Vec3| {
            let m = Material { roughness: 0.3, metallic: 1.0, ..Material::default() };
            PosedScene::quad(corners, normal, m)
        };
        let floor = [
            Vec3::new(-2.0, -2.0, 0.0),
            Vec3::new(2.0, -2.0, 0.0),
            Vec3::new(2.0, 2.0, 0.0),
            Vec3::new(-2.0, 2.0, 0.0),
        ];
        let roof = [
            Vec3::new(-2.0, -2.0, 0.4),
            Vec3::new(-2.0, 2.0, 0.4),
            Vec3::new(0.0, 2.0, 0.4),
            Vec3::new(0.0, -2.0, 0.4),
        ];
        let mut scene = PosedScene::default();
        crate::scene::merge(&[quad(floor, Vec3::Z), quad(roof, -Vec3::Z)], &mut scene);
        let light =
            FrameLight::prepare(&scene, &[], crate::render::Environment::default().studio(), PointCasters::NONE)
                .with_bounce(&scene);
        let (eye, k, side) = (Vec3::new(3.0, 0.3, 2.5), 2i64, 64i64);
        // Camera to world: x right, y up, looking along −z.
        let ahead = (Vec3::new(-0.5, 0.0, 0.0) - eye).normalize();
        let right = ahead.cross(Vec3::Z).normalize();
        let c2w =
            Mat4::from_cols(right.extend(0.0), right.cross(ahead).extend(0.0), (-ahead).extend(0.0), eye.extend(1.0));
        let f = (side * k) as f32;
        let proj = Projection {
            w2c: c2w.inverse(),
            f: [f, f, f * 0.5, f * 0.5],
            near: 0.01,
            far: 100.0,
            size: (side * k, side * k),
        };
        let across = side / crate::render::TILE;
        let ts = crate::render::TILE * k;
        let tris = setup(&scene, &proj, Tiles { side: ts, across, down: across }, Some(&light.vertex_visibility));
        let lit = Lit { light: &light, c2w, eye };
        let shade = Shade { lambert: None, lit: Some(lit), normals: false, per_side: k };
        let (mut worst, mut open, mut blocked, mut samples, mut astray) = (0.0f32, 0, 0, 0, 0);
        for ti in 0..(across * across) as usize {
            let (tx, ty) = (ti as i64 % across, ti as i64 / across);
            let rect = Rect { x0: tx * ts, y0: ty * ts, w: ts, h: ts };
            let work = TileWork { tris: &tris, tile: ti, splats: None };
            let mut rendered = SampleTile::new(rect);
            raster_tile(&scene, work, &shade, rect, &proj, &mut rendered);
            let mut traced = SampleTile::new(rect);
            traced.reset_deferred();
            draw_triangles(&scene, work, &shade, rect, &proj, true, &mut traced);
            for_each_share(&mut traced, rect.x0, rect.y0, k, Pixels::All, |s, t| {
                let tri = tris.get(s.id);
                let at = Sample { at: s.at, bary: s.bary, z: s.z, footprint: k as f32 };
                let (c, found) = shade_lobe(&scene, tri, &lit, &proj, at, albedo(s, t), Lobe::Rays);
                match found {
                    Some(v) if v > 0.99 => open += 1,
                    Some(v) if v < 0.01 => blocked += 1,
                    _ => {}
                }
                fill(t, s, c);
            });
            for i in (0..rendered.color.len()).filter(|&i| traced.object[i] != 0) {
                let (a, b) = (rendered.color[i].truncate(), traced.color[i].truncate());
                let off = (a - b).abs().max_element() / b.max_element().max(0.05);
                worst = worst.max(off);
                (samples, astray) = (samples + 1, astray + usize::from(off > 0.01));
            }
        }
        assert!(open > 200 && blocked > 200, "the floor's reflection is {open} open, {blocked} blocked");
        assert!(samples > 10_000, "{samples}");
        // Where a pixel's own rays would have met another caster than its agreeing anchors' (one ray of eight, by a
        // corner of the roof's reflection), it is off by that ray's share of the reflection; nowhere else.
        assert!(astray * 200 < samples, "{astray} of {samples} samples more than 1 % off what their own rays give");
        assert!(worst < 0.25, "a pixel between anchors is {worst} off what its own rays give");
    }
}
