//! Min and max pyramids of a shadow map's depths: level l (from 1) holds the nearest and the farthest depth of
//! each 2^l × 2^l block, so that a soft lookup tells in at most four reads that nothing over its search region
//! is nearer than its receiver (it is lit), or that everything it would filter is (it is in shadow).

use rayon::prelude::*;

/// The min and max pyramids over the `side`² depths `base` (never NaN): each level halves the side (rounded up)
/// and folds each 2 × 2 block of the level below (an odd last row or column alone), down to one value.
pub(super) fn pyramids(base: &[f32], side: usize) -> (Vec<Vec<f32>>, Vec<Vec<f32>>) {
    let (mut side, mut mins, mut maxs) = (side, Vec::<Vec<f32>>::new(), Vec::<Vec<f32>>::new());
    while side > 1 {
        let (lo, hi) = (mins.last().map_or(base, |l| l), maxs.last().map_or(base, |l| l));
        let (m, n) = fold(lo, hi, side);
        mins.push(m);
        maxs.push(n);
        side = side.div_ceil(2);
    }
    (mins, maxs)
}

/// One level of [`pyramids`]: the min of `lo`'s and the max of `hi`'s 2 × 2 blocks (`side`² each), rows of
/// blocks side by side (a sun's 2048² map and its pyramids were folded on one thread, twice a frame). Each block
/// is folded in the same order whatever the threads (its rows, then its columns; the first of equal values
/// kept), so the same bits.
fn fold(lo: &[f32], hi: &[f32], side: usize) -> (Vec<f32>, Vec<f32>) {
    let next = side.div_ceil(2);
    let (mut m, mut n) = (vec![0.0f32; next * next], vec![0.0f32; next * next]);
    let row = |y: usize, (mins, maxs): (&mut [f32], &mut [f32])| {
        let (r0, r1) = (2 * y, (2 * y + 1).min(side - 1));
        let (a0, a1) = (&lo[r0 * side..(r0 + 1) * side], &lo[r1 * side..(r1 + 1) * side]);
        let (b0, b1) = (&hi[r0 * side..(r0 + 1) * side], &hi[r1 * side..(r1 + 1) * side]);
        for (x, (min, max)) in mins.iter_mut().zip(maxs.iter_mut()).enumerate() {
            let (c0, c1) = (2 * x, (2 * x + 1).min(side - 1));
            let (mut a, mut b) = (f32::INFINITY, f32::NEG_INFINITY);
            for u in [a0[c0], a0[c1], a1[c0], a1[c1]] {
                a = if u < a { u } else { a };
            }
            for v in [b0[c0], b0[c1], b1[c0], b1[c1]] {
                b = if v > b { v } else { b };
            }
            (*min, *max) = (a, b);
        }
    };
    m.par_chunks_mut(next).zip(n.par_chunks_mut(next)).enumerate().with_min_len(32).for_each(|(y, rows)| row(y, rows));
    (m, n)
}

/// The nearest depth over texels `r = [x0, y0, x1, y1]` (inclusive, clamped to the `side`² map; +∞ outside it)
/// of the layer `base` with its min pyramid `mins`, in at most four reads.
pub(super) fn region_min(base: &[f32], mins: &[Vec<f32>], side: usize, r: [i64; 4]) -> f32 {
    let n = side as i64;
    let [x0, y0, x1, y1] = r;
    let (x0, y0, x1, y1) = (x0.max(0), y0.max(0), x1.min(n - 1), y1.min(n - 1));
    if x0 > x1 || y0 > y1 {
        return f32::INFINITY;
    }
    region(base, mins, side, [x0, y0, x1, y1], f32::INFINITY, f32::min)
}

/// The farthest depth over texels `r = [x0, y0, x1, y1]` of the layer `base` with its max pyramid `maxs`, or +∞
/// when the region leaves the `side`² map, in at most four reads.
pub(super) fn region_max(base: &[f32], maxs: &[Vec<f32>], side: usize, r: [i64; 4]) -> f32 {
    let n = side as i64;
    let [x0, y0, x1, y1] = r;
    if x0 < 0 || y0 < 0 || x1 >= n || y1 >= n || x0 > x1 || y0 > y1 {
        return f32::INFINITY;
    }
    region(base, maxs, side, r, f32::NEG_INFINITY, f32::max)
}

/// `fold` of a pyramid's blocks covering the region `[x0, y0, x1, y1]` (inside the `side`² map): those of the
/// level whose blocks are at least as wide as the region, so at most 2 × 2 of them; a single texel is read from
/// the layer `base` the pyramid was built from.
fn region(base: &[f32], levels: &[Vec<f32>], side: usize, r: [i64; 4], init: f32, fold: fn(f32, f32) -> f32) -> f32 {
    let [x0, y0, x1, y1] = r;
    let span = (x1 - x0).max(y1 - y0) + 1;
    let level = (64 - (span as u64 - 1).leading_zeros()) as usize;
    if level == 0 {
        return base[(y0 * side as i64 + x0) as usize];
    }
    let Some(m) = levels.get(level - 1) else { return levels.last().map_or(init, |m| m[0]) };
    let blocks = side.div_ceil(1 << level) as i64;
    let (bx0, by0, bx1, by1) = (x0 >> level, y0 >> level, x1 >> level, y1 >> level);
    let mut v = init;
    for by in by0..=by1.min(blocks - 1) {
        for bx in bx0..=bx1.min(blocks - 1) {
            v = fold(v, m[(by * blocks + bx) as usize]);
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_pyramid_level_folds_the_blocks_below_odd_sides_included() {
        let side = 5;
        let base: Vec<f32> = (0..side * side).map(|i| ((i * 7919) % 23) as f32).collect();
        let (mins, maxs) = pyramids(&base, side);
        assert_eq!(mins.iter().map(Vec::len).collect::<Vec<_>>(), [9, 4, 1]);
        // Level l's block (bx, by) folds the base texels (x, y) with x >> l == bx and y >> l == by.
        for (l, (m, n)) in mins.iter().zip(&maxs).enumerate() {
            let next = (side as f32 / (2 << l) as f32).ceil() as usize;
            for b in 0..m.len() {
                let (bx, by) = (b % next, b / next);
                let block: Vec<f32> = (0..side * side)
                    .filter(|i| (i % side) >> (l + 1) == bx && (i / side) >> (l + 1) == by)
                    .map(|i| base[i])
                    .collect();
                assert_eq!(m[b], block.iter().copied().fold(f32::INFINITY, f32::min), "level {} block {b}", l + 1);
                assert_eq!(n[b], block.iter().copied().fold(f32::NEG_INFINITY, f32::max), "level {} block {b}", l + 1);
            }
        }
    }
}
