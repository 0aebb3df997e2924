//! A sun's shadow on a ground plane, sampled once per frame where it may fall ([`SunShade`]), so that the
//! frame's views read it instead of each looking its pixels up in the sun's shadow map.
//!
//! A soft shadow's lookup is a blocker search and a filter, 80 depth reads in a penumbra: on the lit example's
//! ground (CesiumMan on a 3 m plane, 16 views a frame) those lookups were a tenth of the build, 810 000 a frame,
//! most of them the same ground seen again from another view. The shadow is a property of the frame, not of the
//! view: the frame's light action samples it on a lattice over the cells it may reach (the ground's grid cells
//! that [`super::ShadowMap::open_over`] cannot clear), about three shadow-map texels apart, and pixels read it
//! bilinearly. A frame has about half as many lattice points as its views have pixels in those cells (the lit
//! example: 400 000 against 810 000), so each point can afford a finer lookup than a pixel's: 8 × 8 taps
//! ([`ShadowMap::visibility_smooth`]), under which a wide penumbra shows no steps.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::ShadowMap;

/// Most lattice intervals along a cell's side: 32 keeps a cell's block at 2 KB and a 6 m plane's lattice at
/// 1.5 mm, finer than a contact shadow's edge blurs.
pub(super) const MAX_SIDE: usize = 32;

/// A sun's visibility over the ground cells its shadow may reach: per such cell a block of (`side` + 1)² lattice
/// points (its corners included), each [`ShadowMap::visibility_smooth`] there, stored to 1/65 535. Cells it cannot reach hold no block: their pixels are fully lit.
#[derive(Debug, Clone, PartialEq, Default)]
pub(super) struct SunShade {
    /// Lattice intervals along a cell's side.
    side: usize,
    /// Per cell of the plane's grid (rows along +y): 0 for none, else its block's number plus one.
    block: Vec<u32>,
    /// The blocks' visibilities, each block row by row.
    vis: Vec<u16>,
}

impl SunShade {
    /// The sun's visibility sampled over the cells of a plane at height `z` (grid corner `lo`, cells of size
    /// `cell`, `n` × `n` of them) where `open` says its shadow may fall, from its map `map` and its angular
    /// radius as a tangent, `size`.
    pub(super) fn sample(map: &ShadowMap, size: f32, open: &[bool], lo: Vec3, cell: Vec2, n: usize) -> SunShade {
        let shaded: Vec<usize> = (0..n * n).filter(|&c| open.get(c) != Some(&true)).collect();
        if shaded.is_empty() {
            return SunShade::default();
        }
        // About three texels apart: the lookup filters over at least two (its bilinear taps), and wider in a
        // penumbra, so the lattice loses little of it (two texels apart, the same fidelity for more points).
        let side = ((cell.max_element() / (3.0 * map.texel_size())).ceil() as usize).clamp(1, MAX_SIDE);
        let points = (side + 1) * (side + 1);
        let step = cell / side as f32;
        let vis = shaded
            .par_iter()
            .flat_map_iter(|&c| {
                let corner = lo + (cell * Vec2::new((c % n) as f32, (c / n) as f32)).extend(0.0);
                (0..points).map(move |k| {
                    let p = corner + (step * Vec2::new((k % (side + 1)) as f32, (k / (side + 1)) as f32)).extend(0.0);
                    (map.visibility_smooth(p, Vec3::Z, size).clamp(0.0, 1.0) * 65535.0).round() as u16
                })
            })
            .collect();
        let mut block = vec![0u32; n * n];
        for (b, &c) in shaded.iter().enumerate() {
            block[c] = b as u32 + 1;
        }
        SunShade { side, block, vis }
    }

    /// Whether nothing was sampled: the sun's shadow reaches no cell, or it was not sampled.
    pub(super) fn is_empty(&self) -> bool {
        self.block.is_empty()
    }

    /// The visibility in cell `cell` at fractions `t` across it, bilinear between lattice points; `None` where
    /// nothing was sampled.
    #[inline]
    pub(super) fn at(&self, cell: usize, t: Vec2) -> Option<f32> {
        let b = *self.block.get(cell)? as usize;
        if b == 0 {
            return None;
        }
        let (s, row) = (self.side, self.side + 1);
        let f = (t * s as f32).clamp(Vec2::ZERO, Vec2::splat(s as f32));
        let (i, j) = ((f.x as usize).min(s - 1), (f.y as usize).min(s - 1));
        let (tx, ty) = (f.x - i as f32, f.y - j as f32);
        let base = (b - 1) * row * row + j * row + i;
        let v = |k: usize| self.vis[k] as f32;
        let (a, c) = (v(base) + (v(base + 1) - v(base)) * tx, v(base + row) + (v(base + row + 1) - v(base + row)) * tx);
        Some((a + (c - a) * ty) * (1.0 / 65535.0))
    }

    /// Appends the bytes of the light action's blob: side, the cells' block numbers and the visibilities, each
    /// list after its count (little-endian).
    pub(super) fn encode(&self, out: &mut Vec<u8>) {
        out.extend((self.side as u32).to_le_bytes());
        out.extend((self.block.len() as u32).to_le_bytes());
        self.block.iter().for_each(|b| out.extend(b.to_le_bytes()));
        out.extend((self.vis.len() as u32).to_le_bytes());
        self.vis.iter().for_each(|v| out.extend(v.to_le_bytes()));
    }

    /// A shade read back from its parts, or why they cannot be one written by [`SunShade::encode`] for a grid
    /// of `cells` cells: a side past [`MAX_SIDE`], a cell list of another length, visibilities that are not
    /// whole blocks, a block number past them.
    pub(super) fn from_parts(
        side: usize,
        block: Vec<u32>,
        vis: Vec<u16>,
        cells: usize,
    ) -> Result<SunShade, &'static str> {
        if block.is_empty() && vis.is_empty() {
            return Ok(SunShade::default());
        }
        if !(1..=MAX_SIDE).contains(&side) {
            return Err("a ground shadow lattice of another side");
        }
        let points = (side + 1) * (side + 1);
        if block.len() != cells || !vis.len().is_multiple_of(points) {
            return Err("a ground shadow lattice of another size");
        }
        if block.iter().any(|&b| b as usize > vis.len() / points) {
            return Err("a ground shadow cell past its lattice");
        }
        Ok(SunShade { side, block, vis })
    }
}

#[cfg(test)]
mod tests {
    use super::super::shadow::tests::quad;
    use super::*;
    use crate::render::light::PointCasters;

    /// A 1 m square caster 1 m over the ground (z = 0), its map seen from straight above.
    fn caster() -> (ShadowMap, Vec3) {
        let h = 0.5;
        let bounds = (Vec3::new(-h, -h, 0.0), Vec3::new(h, h, 1.0));
        (ShadowMap::sun(&quad(1.0, h), -Vec3::Z, bounds, 512, PointCasters::NONE), Vec3::new(-1.0, -1.0, 0.0))
    }

    #[test]
    fn a_lattice_holds_the_lookup_at_its_points_and_blends_it_between_them() {
        let (map, lo) = caster();
        // 8 × 8 cells of 25 cm over 2 m; the two in the corner at (0, 0) are open.
        let (n, cell, size) = (8, Vec2::splat(0.25), 0.1);
        let mut open = vec![false; n * n];
        open[0] = true;
        open[1] = true;
        let shade = SunShade::sample(&map, size, &open, lo, cell, n);
        assert_eq!(shade.side, MAX_SIDE.min((0.25 / (3.0 * map.texel_size())).ceil() as usize));
        assert_eq!(shade.at(0, Vec2::splat(0.5)), None);
        let (s, mut dark, mut soft) = (shade.side, 0, 0);
        for c in 2..n * n {
            let corner = lo + (cell * Vec2::new((c % n) as f32, (c / n) as f32)).extend(0.0);
            for k in 0..(s + 1) * (s + 1) {
                let f = Vec2::new((k % (s + 1)) as f32, (k / (s + 1)) as f32) / s as f32;
                let p = corner + (cell * f).extend(0.0);
                let (want, got) = (map.visibility_smooth(p, Vec3::Z, size), shade.at(c, f).unwrap());
                assert!((want - got).abs() <= 1.0 / 65535.0 + 1e-6, "cell {c} point {k}: {got} for {want}");
                dark += (want == 0.0) as usize;
                soft += (want > 0.05 && want < 0.95) as usize;
            }
            // Between lattice points: within what its four neighbours hold.
            let f = Vec2::new(0.5 / s as f32, 1.5 / s as f32);
            let near = [(0, 1), (1, 1), (0, 2), (1, 2)]
                .map(|(i, j)| shade.at(c, Vec2::new(i as f32, j as f32) / s as f32).unwrap());
            let v = shade.at(c, f).unwrap();
            let (lo_v, hi_v) = near.iter().fold((1.0f32, 0.0f32), |(a, b), &x| (a.min(x), b.max(x)));
            assert!(v >= lo_v - 1e-6 && v <= hi_v + 1e-6, "cell {c}: {v} outside {lo_v}..{hi_v}");
        }
        assert!(dark > 100 && soft > 100, "{dark} dark, {soft} soft lattice points");
    }

    #[test]
    fn a_wide_penumbra_read_smoothly_rises_without_steps() {
        // Across the caster's edge at x = 0.5 under a sun 11° wide the penumbra spans 20 cm: the 4 × 4 lookup
        // rises in four steps (a jump of about a quarter within a texel or two), the 8 × 8 one in small ones.
        let (map, _) = caster();
        let profile = |smooth: bool| -> Vec<f32> {
            (0..400)
                .map(|i| {
                    let p = Vec3::new(0.3 + i as f32 * 0.001, 0.0, 0.0);
                    if smooth {
                        map.visibility_smooth(p, Vec3::Z, 0.1)
                    } else {
                        map.visibility(p, Vec3::Z, 0.1)
                    }
                })
                .collect()
        };
        let steepest = |v: &[f32]| v.windows(4).map(|w| w[3] - w[0]).fold(0.0f32, f32::max);
        let (coarse, smooth) = (profile(false), profile(true));
        for v in [&coarse, &smooth] {
            assert!(v[0] < 0.05 && v[399] > 0.95, "{} .. {}", v[0], v[399]);
            assert!(v.windows(2).all(|w| w[1] >= w[0] - 0.02), "not rising");
        }
        assert!(steepest(&smooth) < 0.6 * steepest(&coarse), "{} against {}", steepest(&smooth), steepest(&coarse));
    }

    #[test]
    fn parts_it_cannot_have_written_are_refused() {
        let cells = 4;
        assert_eq!(SunShade::from_parts(0, Vec::new(), Vec::new(), cells), Ok(SunShade::default()));
        let ok = SunShade::from_parts(1, vec![0, 1, 0, 2], vec![0; 8], cells).expect("two blocks of 2 × 2");
        assert_eq!(ok.at(1, Vec2::ZERO), Some(0.0));
        assert!(SunShade::from_parts(MAX_SIDE + 1, vec![0; 4], vec![0; 4], cells).is_err());
        assert!(SunShade::from_parts(1, vec![0; 3], vec![0; 4], cells).is_err());
        assert!(SunShade::from_parts(1, vec![0, 1, 0, 2], vec![0; 7], cells).is_err());
        assert!(SunShade::from_parts(1, vec![0, 1, 0, 3], vec![0; 8], cells).is_err());
    }
}
