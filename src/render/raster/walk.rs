//! One triangle's walk over its samples in a tile: exact integer edge functions stepped from the box's first
//! sample, the tie rule that gives a sample on a shared edge to exactly one of the two triangles, and, for wide
//! triangles, each row's run of inside samples found at once.

use super::{Projection, Tri, SUBPIXEL};

/// Twice the signed area of (a, b, p), y down.
#[inline]
pub(super) fn edge(ax: i64, ay: i64, bx: i64, by: i64, px: i64, py: i64) -> i64 {
    (bx - ax) * (py - ay) - (by - ay) * (px - ax)
}

/// The bounding-box width in samples (within a tile) from which a triangle's rows are walked over their inside
/// runs ([`row_span`]) rather than tested sample by sample: measured, narrower ones lose by it (a 100k-triangle
/// torus 10 % slower), a ground plane gains (unlit, 6 % of the build).
const SPAN_MIN: i64 = 16;

/// The samples `j` in `0..=n` of a row at which every edge value `v[i] + j·s[i]` is ≥ 0 (`v` at the row's first
/// sample, tie bias included), as an inclusive run; `None` when there are none. Each edge is linear along the
/// row, so each bounds the run on one side: the bound is estimated in floating point (exact to a sample or so,
/// without the integer division's latency) and then settled by the exact integer test on either side of it.
#[inline]
fn row_span(v: [i64; 3], s: [i64; 3], n: i64) -> Option<(i64, i64)> {
    let (mut lo, mut hi) = (0, n);
    for i in 0..3 {
        let (v, s) = (v[i], s[i]);
        let inside = |j: i64| v + j * s >= 0;
        if s > 0 {
            // Rising: inside from the first j with v + j·s ≥ 0 on.
            if v < 0 {
                let mut j = ((-v) as f64 / s as f64).clamp(0.0, (n + 1) as f64) as i64;
                while j > 0 && inside(j - 1) {
                    j -= 1;
                }
                while j <= n && !inside(j) {
                    j += 1;
                }
                lo = lo.max(j);
            }
        } else if s < 0 {
            // Falling: inside up to the last j with v + j·s ≥ 0.
            if v < 0 {
                return None;
            }
            let mut j = (v as f64 / -s as f64).min(n as f64) as i64;
            while j < n && inside(j + 1) {
                j += 1;
            }
            while j >= 0 && !inside(j) {
                j -= 1;
            }
            hi = hi.min(j);
        } else if v < 0 {
            return None;
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// Whether an edge owns the samples exactly on it. Antisymmetric: of (u→v) and (v→u), exactly one owns.
#[inline]
fn owns(dx: i64, dy: i64) -> bool {
    dy > 0 || (dy == 0 && dx < 0)
}

/// One triangle's walk over its samples in a tile: edge functions stepped from the box's first sample.
pub(super) struct Walk<'a> {
    tri: &'a Tri,
    /// The box in the tile: first and last column and row, inclusive.
    bbox: [i64; 4],
    /// The edge values at the box's first sample, their steps along x and y, and the tie bias.
    first: [i64; 3],
    step_x: [i64; 3],
    step_y: [i64; 3],
    bias: [i64; 3],
    near: f32,
    far: f32,
}

impl<'a> Walk<'a> {
    /// The walk of `tri` over the samples of `bbox` (first and last column and row, inclusive, within a tile).
    pub(super) fn new(tri: &'a Tri, bbox: [i64; 4], proj: &Projection) -> Walk<'a> {
        let (x, y) = (tri.x, tri.y);
        // Edge i is opposite vertex i: (1→2), (2→0), (0→1). Each is evaluated once at the first sample and then
        // stepped (it is linear in the sample position). A sample exactly on an edge belongs to the triangle only
        // if the edge owns it: `bias` is −1 for the others, so "inside" is `v + bias ≥ 0` for all three.
        let e = [(1, 2), (2, 0), (0, 1)];
        let (px0, py0) = (bbox[0] * SUBPIXEL + SUBPIXEL / 2, bbox[1] * SUBPIXEL + SUBPIXEL / 2);
        Walk {
            tri,
            bbox,
            first: e.map(|(a, b)| edge(x[a], y[a], x[b], y[b], px0, py0)),
            step_x: e.map(|(a, b)| -(y[b] - y[a]) * SUBPIXEL),
            step_y: e.map(|(a, b)| (x[b] - x[a]) * SUBPIXEL),
            bias: e.map(|(a, b)| if owns(x[b] - x[a], y[b] - y[a]) { 0 } else { -1 }),
            near: proj.near,
            far: proj.far,
        }
    }

    /// Calls `hit(i, (sx, sy), k, z)` for every sample inside the triangle, between the planes and nearer than
    /// `depth[i]` (the tile's buffers start at sample (`x0`, `y0`) and are `w` samples wide), row by row: `i` is the
    /// sample's index in the tile, `k` its perspective-correct barycentrics, `z` its view depth. The sample's
    /// depth becomes `z` when `hit` returns true (it keeps the sample).
    #[inline(always)]
    pub(super) fn hits(
        &self,
        x0: i64,
        y0: i64,
        w: i64,
        depth: &mut [f32],
        mut hit: impl FnMut(usize, (i64, i64), [f32; 3], f32) -> bool,
    ) {
        // A wide triangle's row is walked over its run of inside samples only, found from the edge values at
        // its start; a narrow one's is tested sample by sample (cheaper than finding the run). One copy of the
        // row loop each, so that neither tests which it is per sample.
        if self.bbox[2] - self.bbox[0] >= SPAN_MIN {
            self.rows::<true>(x0, y0, w, depth, &mut hit);
        } else {
            self.rows::<false>(x0, y0, w, depth, &mut hit);
        }
    }

    /// [`Walk::hits`] for narrow or (`WIDE`) wide triangles.
    #[inline(always)]
    fn rows<const WIDE: bool>(
        &self,
        x0: i64,
        y0: i64,
        w: i64,
        depth: &mut [f32],
        hit: &mut impl FnMut(usize, (i64, i64), [f32; 3], f32) -> bool,
    ) {
        let Walk { tri, bbox: [bx0, by0, bx1, by1], first, step_x, step_y, bias, near, far } = *self;
        let inv_area = 1.0 / tri.area as f32;
        let mut row = first;
        for sy in by0..by1 + 1 {
            let start = row;
            for i in 0..3 {
                row[i] += step_y[i];
            }
            let (lo, hi) = if WIDE {
                let biased = [start[0] + bias[0], start[1] + bias[1], start[2] + bias[2]];
                let Some(run) = row_span(biased, step_x, bx1 - bx0) else { continue };
                run
            } else {
                (0, bx1 - bx0)
            };
            let mut wgt: [i64; 3] = std::array::from_fn(|i| start[i] + lo * step_x[i]);
            // The sample at (sx, sy) is `row_at + sx` in the tile buffers.
            let row_at = (sy - y0) * w - x0;
            for sx in bx0 + lo..bx0 + hi + 1 {
                let v = wgt;
                for i in 0..3 {
                    wgt[i] += step_x[i];
                }
                if !WIDE && ((v[0] + bias[0]) | (v[1] + bias[1]) | (v[2] + bias[2])) < 0 {
                    continue;
                }
                debug_assert!(((v[0] + bias[0]) | (v[1] + bias[1]) | (v[2] + bias[2])) >= 0);
                let b = v.map(|v| v as f32 * inv_area);
                let pb = [b[0] * tri.inv_z[0], b[1] * tri.inv_z[1], b[2] * tri.inv_z[2]];
                let s = pb[0] + pb[1] + pb[2];
                let z = 1.0 / s;
                let i = (row_at + sx) as usize;
                if !(z >= near && z <= far) || z >= depth[i] {
                    continue;
                }
                let k = [pb[0] * z, pb[1] * z, pb[2] * z];
                if hit(i, (sx, sy), k, z) {
                    depth[i] = z;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The run `row_span` finds is exactly the samples the per-sample test accepts, for edges of every slope
    /// and offset (ties at zero included) and rows of every width a tile has: the two paths draw the same bytes.
    #[test]
    fn row_spans_are_exactly_the_inside_samples() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |m: i64| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 33) as i64).rem_euclid(2 * m + 1) - m
        };
        for case in 0..20_000 {
            // Small magnitudes hit exact zeros and ties; large ones the floating-point estimate's rounding.
            let scale = if case % 2 == 0 { 40 } else { 1 << 40 };
            let s = [next(scale), next(scale), next(scale)];
            let v = [next(scale * 64), next(scale * 64), next(scale * 64)];
            let n = next(64).abs() + 1;
            let inside: Vec<i64> = (0..=n).filter(|&j| (0..3).all(|i| v[i] + j * s[i] >= 0)).collect();
            let expected = inside.first().map(|&lo| (lo, *inside.last().unwrap()));
            assert_eq!(row_span(v, s, n), expected, "v {v:?} s {s:?} n {n}");
            // The inside samples of a row through a triangle are one run (edges are linear).
            if let Some((lo, hi)) = expected {
                assert_eq!(inside.len() as i64, hi - lo + 1);
            }
        }
    }
}
