//! Deferred shading of a drawn tile, once per pixel and triangle: what the triangle's samples in a pixel share
//! (texture lookups, lit shading) is evaluated once, at the centroid of those samples, after every triangle of
//! the tile is drawn, so that hidden samples cost nothing. This is how a GPU shades under multisampling
//! (centroid interpolation); what varies per sample (coverage, depth, vertex colour, a Lambert normal) stays
//! per sample.
//!
//! The centroid matters: shading at one of the samples would shift every texture by up to half a sample toward
//! that sample, which shows as blur and misregistration against a reference renderer. Fully covered pixels are
//! shaded at their centre.

use glam::{Vec2, Vec3};

use super::{SampleTile, Shade, Tris, NO_TRI};
use crate::scene::material::AlphaMode;
use crate::scene::texture::{Texture, TextureRef};
use crate::scene::PosedScene;

/// One triangle's share of one pixel: the samples it won there and its attributes at their centroid.
#[derive(Debug, Clone, Copy)]
pub(super) struct Share {
    /// The triangle's id.
    pub id: u32,
    /// Indices of its samples in the tile buffer (the first `n`).
    pub samples: [u32; 16],
    pub n: usize,
    /// The centroid in sample coordinates (continuous: a sample's centre is at +0.5).
    pub at: Vec2,
    /// Perspective-correct barycentrics at the centroid (the mean of the samples' own).
    pub bary: [f32; 3],
    /// View depth at the centroid (the mean of the samples').
    pub z: f32,
    /// The pixel, counted from the tile's first.
    pub px: u32,
    pub py: u32,
}

/// Calls `f` for every triangle's share of every pixel of the tile, pixels in row order and, within a pixel,
/// triangles in the order of their first sample (so the result never depends on anything but the tile).
/// `k` is the number of samples along a pixel side (at most 4). Only the pixels `pixels` keeps are visited.
pub(super) fn for_each_share(
    t: &mut SampleTile,
    x0: i64,
    y0: i64,
    k: i64,
    pixels: Pixels,
    f: impl FnMut(&Share, &mut SampleTile),
) {
    // One copy per sample grid: with the pixel's sample count known, its loops unroll and its indexing is
    // checked once (the generic loops were as many instructions as the texture lookups they feed).
    match k {
        1 => shares::<1, 1>(t, x0, y0, pixels, f),
        2 => shares::<2, 4>(t, x0, y0, pixels, f),
        3 => shares::<3, 9>(t, x0, y0, pixels, f),
        _ => shares::<4, 16>(t, x0, y0, pixels, f),
    }
}

/// Which of a tile's pixels [`for_each_share`] visits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Pixels {
    All,
    /// Those in an even column of an even row (counted from the tile's first, 0).
    Even,
    /// The others.
    NotEven,
}

/// [`for_each_share`] for `K` × `K` samples per pixel (`N` = `K`²).
#[inline(always)]
fn shares<const K: usize, const N: usize>(
    t: &mut SampleTile,
    x0: i64,
    y0: i64,
    pixels: Pixels,
    mut f: impl FnMut(&Share, &mut SampleTile),
) {
    debug_assert_eq!(N, K * K);
    let w = t.w as usize;
    // Each sample slot's offset within its pixel, from its top-left sample, and a full pixel's centroid (their
    // mean, computed as `gather` computes any share's).
    let offset: [Vec2; N] = std::array::from_fn(|j| Vec2::new((j % K) as f32, (j / K) as f32));
    let full = offset.iter().fold(Vec2::ZERO, |a, &o| a + o) * (1.0 / N as f32);
    let mut share = Share { id: NO_TRI, samples: [0; 16], n: 0, at: Vec2::ZERO, bary: [0.0; 3], z: 0.0, px: 0, py: 0 };
    for py in 0..t.h as usize / K {
        if pixels == Pixels::Even && py % 2 == 1 {
            continue;
        }
        // Only the pixels between the row's first and last deferred sample (a tile around a figure is mostly
        // empty, and scanning it was a third of texturing's instructions).
        let band = &t.tri[py * K * w..(py + 1) * K * w];
        let deferred = |&d: &u32| d != NO_TRI;
        let Some(lo) = band.chunks_exact(w).filter_map(|r| r.iter().position(deferred)).min() else {
            continue;
        };
        let hi = band.chunks_exact(w).filter_map(|r| r.iter().rposition(deferred)).max().unwrap_or(lo);
        for px in lo / K..=hi / K {
            let even = px % 2 == 0 && py % 2 == 0;
            if (pixels == Pixels::Even && !even) || (pixels == Pixels::NotEven && even) {
                continue;
            }
            let index: [usize; N] = super::pixel_samples::<K, N>(w, px, py);
            let mut ids: [u32; N] = index.map(|i| t.tri[i]);
            let corner = Vec2::new(x0 as f32 + (px * K) as f32, y0 as f32 + (py * K) as f32) + 0.5;
            (share.px, share.py) = (px as u32, py as u32);
            let id = ids[0];
            if id != NO_TRI && ids.iter().all(|&d| d == id) {
                // Inside one triangle (most covered pixels): its centroid is the pixel's, no sorting out. `gather`'s
                // sums written out over the whole pixel (through `gather` this path cost 2.8 % more of a
                // 4-sample render's instructions: its count and slot checks are not constants there).
                let (mut bary, mut z) = ([0.0f32; 3], 0.0);
                for (slot, &i) in share.samples.iter_mut().zip(&index) {
                    *slot = i as u32;
                    let v = t.bary[i];
                    (bary[0], bary[1], bary[2]) = (bary[0] + v[0], bary[1] + v[1], bary[2] + v[2]);
                    z += t.depth[i];
                }
                let inv = 1.0 / N as f32;
                (share.id, share.n, share.at) = (id, N, corner + full);
                (share.bary, share.z) = (bary.map(|b| b * inv), z * inv);
                f(&share, t);
                continue;
            }
            // Each triangle in the order of its first sample; its samples are taken out of `ids` once gathered.
            for a in 0..N {
                let id = ids[a];
                if id == NO_TRI {
                    continue;
                }
                let mine = (a..N).filter(|&b| ids[b] == id).map(|b| (index[b] as u32, offset[b]));
                gather(&mut share, t, id, corner, mine);
                ids[a..].iter_mut().filter(|d| **d == id).for_each(|d| *d = NO_TRI);
                f(&share, t);
            }
        }
    }
}

/// Fills `share` with triangle `id`'s samples (tile index and offset from the pixel's top-left sample, whose
/// centre is `corner`), their centroid and their mean barycentrics and depth.
#[inline]
fn gather(share: &mut Share, t: &SampleTile, id: u32, corner: Vec2, samples: impl Iterator<Item = (u32, Vec2)>) {
    let (mut at, mut bary, mut z) = (Vec2::ZERO, [0.0f32; 3], 0.0);
    share.n = 0;
    for (i, off) in samples {
        share.samples[share.n] = i;
        share.n += 1;
        at += off;
        let v = t.bary[i as usize];
        (bary[0], bary[1], bary[2]) = (bary[0] + v[0], bary[1] + v[1], bary[2] + v[2]);
        z += t.depth[i as usize];
    }
    let inv = 1.0 / share.n as f32;
    share.id = id;
    share.at = corner + at * inv;
    share.bary = bary.map(|b| b * inv);
    share.z = z * inv;
}

/// A material's base colour texture and the texture it reads, when it has one.
type BaseColour<'a> = Option<(TextureRef, &'a Texture)>;

/// Unlit (or Lambert) shading of the deferred samples of a drawn tile: opaque surfaces with a base colour
/// texture read it once per pixel and triangle, over the pixel's footprint; each sample then multiplies its
/// own albedo (base colour × vertex colour, left by [`super::raster_tile`]) and is shaded with its own normal.
pub(super) fn texture_tile(scene: &PosedScene, tris: &Tris, shade: &Shade, x0: i64, y0: i64, t: &mut SampleTile) {
    let k = shade.per_side;
    // What the last share's material needs (its texture and emissive): neighbouring shares are mostly one
    // triangle's, or one mesh's, so the material is looked up again only when it changes.
    let mut last: Option<(u32, BaseColour, Vec3, bool)> = None;
    for_each_share(t, x0, y0, k, Pixels::All, |s, t| {
        let tri = tris.get(s.id);
        let (texture, emissive, shadeless) = match last {
            Some((m, texture, emissive, shadeless)) if m == tri.material => (texture, emissive, shadeless),
            _ => {
                let mat = scene.material(tri.material);
                debug_assert_eq!(mat.alpha_mode, AlphaMode::Opaque);
                // A texture the scene does not have (never from the loaders) reads as white.
                let texture =
                    mat.base_color_texture.and_then(|r| scene.textures.get(r.texture as usize).map(|t| (r, t)));
                last = Some((tri.material, texture, mat.emissive, mat.unlit));
                (texture, mat.emissive, mat.unlit)
            }
        };
        let texel = match texture {
            Some((r, tex)) => {
                let (uv, dx, dy) = tri.uv_footprint(s.bary, s.z, k as f32);
                tex.sample_footprint_rgb(&r, uv, dx, dy)
            }
            None => Vec3::ONE,
        };
        let samples = s.samples[..s.n].iter().map(|&i| i as usize);
        if shade.lambert.is_none() {
            // Unlit: the albedo itself (in four lanes at once: the same products and sums per channel).
            let (texel, emissive) = (texel.extend(1.0), emissive.extend(0.0));
            samples.for_each(|i| t.color[i] = (t.color[i] * texel + emissive).with_w(1.0));
        } else {
            samples.for_each(|i| {
                let albedo = t.color[i].truncate() * texel;
                t.color[i] = (super::shade_unlit(shade, shadeless, albedo, t.normal[i]) + emissive).extend(1.0);
            });
        }
    });
}
