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
}

/// Calls `f` for every triangle's share of every pixel of the tile, pixels in row order and, within a pixel,
/// triangles in the order of their first sample (so the result never depends on anything but the tile).
/// `k` is the number of samples along a pixel side (at most 4).
pub(super) fn for_each_share(t: &mut SampleTile, x0: i64, y0: i64, k: i64, mut f: impl FnMut(&Share, &mut SampleTile)) {
    let (w, k) = (t.w as usize, k as usize);
    let n = k * k;
    // Each sample slot's offset within its pixel, from its top-left sample.
    let offset: [Vec2; 16] = std::array::from_fn(|j| Vec2::new((j % k) as f32, (j / k) as f32));
    let mut share = Share { id: NO_TRI, samples: [0; 16], n: 0, at: Vec2::ZERO, bary: [0.0; 3], z: 0.0 };
    let (mut index, mut ids) = ([0u32; 16], [NO_TRI; 16]);
    for py in 0..t.h as usize / k {
        // Only the pixels between the row's first and last deferred sample (a tile around a figure is mostly
        // empty, and scanning it was a third of texturing's instructions).
        let band = &t.tri[py * k * w..(py + 1) * k * w];
        let deferred = |&d: &u32| d != NO_TRI;
        let Some(lo) = band.chunks_exact(w).filter_map(|r| r.iter().position(deferred)).min() else {
            continue;
        };
        let hi = band.chunks_exact(w).filter_map(|r| r.iter().rposition(deferred)).max().unwrap_or(lo);
        for px in lo / k..=hi / k {
            let first = py * k * w + px * k;
            let mut j = 0;
            for row in (0..k).map(|sy| first + sy * w) {
                for i in row..row + k {
                    (index[j], ids[j]) = (i as u32, t.tri[i]);
                    j += 1;
                }
            }
            let corner = Vec2::new(x0 as f32 + (px * k) as f32, y0 as f32 + (py * k) as f32) + 0.5;
            let id = ids[0];
            if id != NO_TRI && ids[1..n].iter().all(|&d| d == id) {
                // Inside one triangle (most covered pixels): no sorting out.
                gather(&mut share, t, id, corner, (0..n).map(|b| (index[b], offset[b])));
                f(&share, t);
                continue;
            }
            // Each triangle in the order of its first sample; its samples are taken out of `ids` once gathered.
            for a in 0..n {
                let id = ids[a];
                if id == NO_TRI {
                    continue;
                }
                let mine = (a..n).filter(|&b| ids[b] == id).map(|b| (index[b], offset[b]));
                gather(&mut share, t, id, corner, mine);
                ids[a..n].iter_mut().filter(|d| **d == id).for_each(|d| *d = NO_TRI);
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

/// Unlit (or Lambert) shading of the deferred samples of a drawn tile: opaque surfaces with a base colour
/// texture read it once per pixel and triangle, over the pixel's footprint; each sample then multiplies its
/// own albedo (base colour × vertex colour, left by [`super::raster_tile`]) and is shaded with its own normal.
pub(super) fn texture_tile(scene: &PosedScene, tris: &Tris, shade: &Shade, x0: i64, y0: i64, t: &mut SampleTile) {
    let k = shade.per_side;
    for_each_share(t, x0, y0, k, |s, t| {
        let tri = tris.get(s.id);
        let mat = scene.material(tri.material);
        debug_assert_eq!(mat.alpha_mode, AlphaMode::Opaque);
        // A texture the scene does not have (never from the loaders) reads as white.
        let texel = match mat.base_color_texture.and_then(|r| scene.textures.get(r.texture as usize).map(|t| (r, t))) {
            Some((r, tex)) => {
                let (uv, dx, dy) = tri.uv_footprint(s.bary, s.z, k as f32);
                tex.sample_footprint(&r, uv, dx, dy).truncate()
            }
            None => Vec3::ONE,
        };
        for &i in &s.samples[..s.n] {
            let i = i as usize;
            let albedo = t.color[i].truncate() * texel;
            t.color[i] = (super::shade_unlit(shade, albedo, t.normal[i]) + mat.emissive).extend(1.0);
        }
    });
}
