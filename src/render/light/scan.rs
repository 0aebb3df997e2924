//! Scan conversion of a light-space triangle into a square depth map's texels: what every shadow map
//! ([`super::shadow::ShadowMap`]) draws its casters with. A triangle is set up once ([`Scan::new`]) and drawn band
//! by band of rows ([`Scan::rows`]), the bands side by side.

use glam::{Vec3, Vec4};

use super::shadow::NEAR;
use crate::scene::texture::floor;

/// How many caster triangles a shadow map sets up at a time (`ShadowMap::rasterize`): 64 k of about 90 bytes.
pub(super) const SCAN_RUN: usize = 1 << 16;

/// A light-space triangle `v` of a `size`² map set up to visit the texels whose centre it covers (barycentrics
/// all at least `min_w`): its bounding texels, clamped to the map, and what the barycentrics need. Perspective
/// maps interpolate 1/depth (linear in screen space), parallel ones depth.
pub(super) struct Scan {
    v: [Vec3; 3],
    /// Depth (parallel) or 1/depth (perspective) at the corners.
    z: [f32; 3],
    inv_area: f32,
    persp: bool,
    min_w: f32,
    /// First and last texel column and row (inclusive).
    x: (u32, u32),
    pub(super) y: (u32, u32),
}

impl Scan {
    /// `None` for a triangle that visits nothing: crossing a perspective map's near plane, of no area, or off
    /// the map.
    pub(super) fn new(v: [Vec3; 3], size: u32, persp: bool, min_w: f32) -> Option<Scan> {
        let n = size as f32;
        if persp && v.iter().any(|p| p.z < NEAR) {
            return None;
        }
        let area = (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[1].y - v[0].y) * (v[2].x - v[0].x);
        if area.abs() < 1e-12 {
            return None;
        }
        // (`floor` and `ceil` through integers, as `texture::floor`: the same values once clamped to the map.)
        let floor_f = |x: f32| floor(x) as f32;
        let ceil_f = |x: f32| -(floor(-x) as f32);
        let x0 = floor_f(v.iter().map(|p| p.x).fold(f32::INFINITY, f32::min)).max(0.0);
        let x1 = ceil_f(v.iter().map(|p| p.x).fold(f32::NEG_INFINITY, f32::max)).min(n - 1.0);
        let y0 = floor_f(v.iter().map(|p| p.y).fold(f32::INFINITY, f32::min)).max(0.0);
        let y1 = ceil_f(v.iter().map(|p| p.y).fold(f32::NEG_INFINITY, f32::max)).min(n - 1.0);
        if x0 > x1 || y0 > y1 {
            return None;
        }
        let z = v.map(|p| if persp { 1.0 / p.z } else { p.z });
        let (x, y) = ((x0 as u32, x1 as u32), (y0 as u32, y1 as u32));
        Some(Scan { v, z, inv_area: 1.0 / area, persp, min_w, x, y })
    }

    /// Visits each covered texel in rows `rows.0..rows.1` with its index, the triangle's depth there and its
    /// barycentric weights on the triangle.
    ///
    /// Four texels of a row are tested at a time (most of a bounding box is not covered: this test was most of
    /// a detailed subject's shadow maps). Each lane does what one texel's test did, operation for operation in
    /// f32 (no fused multiply-add), so the same texels are visited with the same bits: a texel is skipped when
    /// a weight is below `min_w` (a NaN weight is not below it, and is visited, as before).
    #[inline(always)]
    pub(super) fn rows(&self, size: u32, rows: (u32, u32), mut visit: impl FnMut(usize, f32, [f32; 3])) {
        let Scan { v, z, inv_area, persp, min_w, .. } = *self;
        let (y0, y1) = (self.y.0.max(rows.0), self.y.1.min(rows.1.saturating_sub(1)));
        if rows.1 == 0 || y0 > y1 {
            return;
        }
        let min = Vec4::splat(min_w);
        let (v0x, v1x, v2x) = (Vec4::splat(v[0].x), Vec4::splat(v[1].x), Vec4::splat(v[2].x));
        for y in y0..=y1 {
            let py = y as f32 + 0.5;
            let (d0, d1, d2) = (Vec4::splat(v[0].y - py), Vec4::splat(v[1].y - py), Vec4::splat(v[2].y - py));
            let mut x = self.x.0;
            // Texel centres x + 0.5, stepped by 4: exact (a map's side is far below 2²²), so each lane holds what
            // `x as f32 + 0.5` gives.
            let mut px = Vec4::new(0.5, 1.5, 2.5, 3.5) + x as f32;
            while x <= self.x.1 {
                let w0 = ((v1x - px) * d2 - d1 * (v2x - px)) * inv_area;
                let w1 = ((v2x - px) * d0 - d2 * (v0x - px)) * inv_area;
                let w2 = Vec4::ONE - w0 - w1;
                // Lanes past the box's last column are not texels of it.
                let past = (self.x.1 - x).min(3) + 1;
                let mut hit = !(w0.cmplt(min) | w1.cmplt(min) | w2.cmplt(min)).bitmask() & ((1u32 << past) - 1);
                while hit != 0 {
                    let k = hit.trailing_zeros() as usize;
                    hit &= hit - 1;
                    let (w0, w1, w2) = (w0[k], w1[k], w2[k]);
                    let zi = w0 * z[0] + w1 * z[1] + w2 * z[2];
                    // The weights on the triangle itself (perspective-correct: z holds 1/depth there).
                    let w = if persp { [w0 * z[0] / zi, w1 * z[1] / zi, w2 * z[2] / zi] } else { [w0, w1, w2] };
                    visit((y * size + x + k as u32) as usize, if persp { 1.0 / zi } else { zi }, w);
                }
                x += 4;
                px += 4.0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What [`Scan::rows`] visits, found one texel at a time as the test was first written: each texel of the
    /// box whose weights are none below `min_w`, in row order, with the same f32 arithmetic.
    fn one_at_a_time(s: &Scan, size: u32) -> Vec<(usize, u32, [u32; 3])> {
        let mut out = Vec::new();
        let Scan { v, z, inv_area, persp, min_w, .. } = *s;
        for y in s.y.0..=s.y.1 {
            let py = y as f32 + 0.5;
            for x in s.x.0..=s.x.1 {
                let px = x as f32 + 0.5;
                let w0 = ((v[1].x - px) * (v[2].y - py) - (v[1].y - py) * (v[2].x - px)) * inv_area;
                let w1 = ((v[2].x - px) * (v[0].y - py) - (v[2].y - py) * (v[0].x - px)) * inv_area;
                let w2 = 1.0 - w0 - w1;
                if w0 < min_w || w1 < min_w || w2 < min_w {
                    continue;
                }
                let zi = w0 * z[0] + w1 * z[1] + w2 * z[2];
                let w = if persp { [w0 * z[0] / zi, w1 * z[1] / zi, w2 * z[2] / zi] } else { [w0, w1, w2] };
                let d = if persp { 1.0 / zi } else { zi };
                out.push(((y * size + x) as usize, d.to_bits(), w.map(f32::to_bits)));
            }
        }
        out
    }

    #[test]
    fn four_texels_at_a_time_visit_what_one_at_a_time_does_bit_for_bit() {
        // Triangles of every size and slant (slivers, boxes of every width modulo 4, over the map's edges), from
        // a fixed stream, parallel and perspective, with the shadow maps' two thresholds.
        let size = 64;
        let mut state = 0x9e37_79b9_u32;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32
        };
        let (mut triangles, mut texels) = (0, 0);
        for k in 0..3000 {
            let span = [0.7, 3.0, 12.0, 80.0][k % 4];
            let c = Vec3::new(next() * 70.0 - 3.0, next() * 70.0 - 3.0, 0.0);
            let v = [0, 1, 2].map(|_| c + Vec3::new((next() - 0.5) * span, (next() - 0.5) * span, 0.5 + next() * 4.0));
            for (persp, min_w) in [(false, -1e-4), (true, 0.0)] {
                let Some(s) = Scan::new(v, size, persp, min_w) else { continue };
                let mut got = Vec::new();
                s.rows(size, (0, size), |i, d, w| got.push((i, d.to_bits(), w.map(f32::to_bits))));
                let want = one_at_a_time(&s, size);
                assert_eq!(got, want, "triangle {k} {v:?} (perspective: {persp})");
                triangles += 1;
                texels += got.len();
                // Drawn band by band, the same texels.
                let mut banded = Vec::new();
                for b in 0..8 {
                    s.rows(size, (b * 8, b * 8 + 8), |i, d, w| banded.push((i, d.to_bits(), w.map(f32::to_bits))));
                }
                assert_eq!(banded, want, "triangle {k} in bands");
            }
        }
        assert!(triangles > 4000 && texels > 100_000, "{triangles} triangles, {texels} texels");
    }
}
