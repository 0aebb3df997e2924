//! Voxel downsampling on a lattice anchored at the world origin, so every frame of a sequence shares one grid
//! (Open3D's legacy API anchors at each cloud's own minimum, which makes the lattice drift between frames).
//!
//! Points are keyed by lattice cell, sorted by (cell, input index) and reduced run by run. The sort fixes the
//! order of every sum, so the result is the same bytes whatever the thread count.

use rayon::prelude::*;

use super::Points;
pub use crate::manifest::output::{Reduce, VoxelPosition};

/// How a voxel's points become one.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Reduction {
    /// Which point or mean represents the voxel.
    pub reduce: Reduce,
    /// Where the representative is placed.
    pub position: VoxelPosition,
}

/// Merges the points in each voxel of edge `size` into one: the mean position, linear colour and normalized
/// normal (`Reduce::Mean`), or those of the point nearest the voxel centre (`Nearest`, ties to the earlier
/// point) or of the first point in input order (`First`); placed at that position or at the voxel centre.
/// Output order is by voxel index (z, y, x), independent of the input order.
pub fn downsample(p: &Points, size: f32, how: Reduction) -> Points {
    let inv = 1.0 / size as f64;
    let cell = |q: &[f32; 3]| q.map(|v| floor(v as f64 * inv));
    // Cell indices relative to the smallest, packed as z | y | x with as many bits as each axis spans, so
    // integer order is (z, y, x) order and the radix sort runs as few passes as the extent allows.
    // floor is monotonic, so the cells of the coordinate-wise extremes bound every cell.
    let (min, max) = p
        .positions
        .par_iter()
        .fold_with(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), q| {
            ([0, 1, 2].map(|k| lo[k].min(q[k])), [0, 1, 2].map(|k| hi[k].max(q[k])))
        })
        .reduce(
            || ([f32::MAX; 3], [f32::MIN; 3]),
            |a, b| ([0, 1, 2].map(|k| a.0[k].min(b.0[k])), [0, 1, 2].map(|k| a.1[k].max(b.1[k]))),
        );
    let (lo, hi) = (cell(&min), cell(&max));
    let bits = [0, 1, 2].map(|k| 64 - ((hi[k] as i128 - lo[k] as i128) as u64).leading_zeros());
    // Each entry is one u64: the packed cell above the point's index. Sorting on the cell bits alone, stably,
    // leaves each voxel's points in input order.
    let idx_bits = 64 - (p.len().max(2) as u64 - 1).leading_zeros();
    let key_bits: u32 = bits.iter().sum();
    if p.is_empty() || key_bits + idx_bits > 64 {
        return downsample_wide(p, size, how);
    }
    let pack = |c: [i64; 3]| {
        let [x, y, z] = [0, 1, 2].map(|k| c[k].wrapping_sub(lo[k]) as u64);
        (z << bits[1] << bits[0]) | (y << bits[0]) | x
    };
    let keyed: Vec<u64> =
        p.positions.par_iter().enumerate().map(|(i, q)| pack(cell(q)) << idx_bits | i as u64).collect();
    let order = sort_packed(keyed, idx_bits, key_bits);
    let idx_mask = (1u64 << idx_bits) - 1;
    let unpack = |k: u64| {
        let m = |b: u32| (1u64 << b) - 1;
        [k & m(bits[0]), (k >> bits[0]) & m(bits[1]), k >> bits[0] >> bits[1]].map(|v| v as f64)
    };
    let starts: Vec<usize> = (0..order.len())
        .into_par_iter()
        .filter(|&i| i == 0 || order[i] >> idx_bits != order[i - 1] >> idx_bits)
        .collect();
    let reps: Vec<([f32; 3], [f32; 3], [f32; 3])> = starts
        .par_iter()
        .enumerate()
        .map(|(r, &s)| {
            let e = starts.get(r + 1).copied().unwrap_or(order.len());
            let c = unpack(order[s] >> idx_bits);
            let centre = [0, 1, 2].map(|k| ((c[k] + lo[k] as f64 + 0.5) * size as f64) as f32);
            reduce_run(p, order[s..e].iter().map(|o| (o & idx_mask) as usize), centre, how)
        })
        .collect();
    let mut out = Points::default();
    out.positions.reserve(reps.len());
    out.normals.reserve(reps.len());
    out.colors.reserve(reps.len());
    for (pos, n, c) in reps {
        out.positions.push(pos);
        out.normals.push(n);
        out.colors.push(c);
    }
    out
}

/// `x.floor() as i64` without a libm call (baseline x86-64 has no SSE4.1 rounding); saturating like `as`.
#[inline]
fn floor(x: f64) -> i64 {
    let t = x as i64;
    t - i64::from((t as f64) > x)
}

/// Sorts the packed entries ascending (they are distinct: the low bits are the index): halves sorted in
/// parallel and merged, each leaf by [`radix_sort`]. The result is the one sorted order, however it was split.
fn sort_packed(mut v: Vec<u64>, from: u32, bits: u32) -> Vec<u64> {
    if v.len() < 1 << 18 {
        return radix_sort(v, from, bits);
    }
    let right = v.split_off(v.len() / 2);
    let (a, b) = rayon::join(|| sort_packed(v, from, bits), || sort_packed(right, from, bits));
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    // Branch-free: which side is smaller is a coin flip for keys of one cloud's two halves.
    while i < a.len() && j < b.len() {
        let take_a = a[i] < b[j];
        out.push(if take_a { a[i] } else { b[j] });
        i += usize::from(take_a);
        j += usize::from(!take_a);
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

/// Stable LSD radix sort of `v` on bits `from .. from + bits`: entries equal there keep their input order, so
/// each voxel's points are summed in the same order on every run.
fn radix_sort(mut v: Vec<u64>, from: u32, bits: u32) -> Vec<u64> {
    const DIGIT: u32 = 12;
    let mask = (1u64 << DIGIT) - 1;
    let mut tmp = vec![0u64; v.len()];
    let mut shift = from;
    while shift < from + bits {
        let mut start = vec![0usize; 1 << DIGIT];
        for e in &v {
            start[((e >> shift) & mask) as usize] += 1;
        }
        if start.contains(&v.len()) {
            // One digit value for all: the pass would not move anything.
            shift += DIGIT;
            continue;
        }
        let mut sum = 0;
        for c in start.iter_mut() {
            (*c, sum) = (sum, sum + *c);
        }
        for e in &v {
            let b = ((e >> shift) & mask) as usize;
            tmp[start[b]] = *e;
            start[b] += 1;
        }
        std::mem::swap(&mut v, &mut tmp);
        shift += DIGIT;
    }
    v
}

/// One voxel's representative from its points `idx` (in input order).
fn reduce_run(
    p: &Points,
    idx: impl Iterator<Item = usize> + Clone,
    centre: [f32; 3],
    how: Reduction,
) -> ([f32; 3], [f32; 3], [f32; 3]) {
    let (pos, nrm, col) = match how.reduce {
        Reduce::Mean => {
            let (mut pos, mut nrm, mut col, mut n) = ([0f64; 3], [0f64; 3], [0f64; 3], 0f64);
            for i in idx {
                for k in 0..3 {
                    pos[k] += p.positions[i][k] as f64;
                    nrm[k] += p.normals[i][k] as f64;
                    col[k] += p.colors[i][k] as f64;
                }
                n += 1.0;
            }
            let len = nrm.iter().map(|v| v * v).sum::<f64>().sqrt();
            let nrm = if len > 0.0 { nrm.map(|v| (v / len) as f32) } else { [0.0; 3] };
            (pos.map(|v| (v / n) as f32), nrm, col.map(|v| (v / n) as f32))
        }
        Reduce::First | Reduce::Nearest => {
            let mut pick = idx.clone().next().expect("BUG: a voxel run is never empty");
            if how.reduce == Reduce::Nearest {
                let d2 = |i: usize| (0..3).map(|k| ((p.positions[i][k] - centre[k]) as f64).powi(2)).sum::<f64>();
                let mut best = d2(pick);
                for i in idx {
                    let d = d2(i);
                    if d < best {
                        (best, pick) = (d, i);
                    }
                }
            }
            (p.positions[pick], p.normals[pick], p.colors[pick])
        }
    };
    match how.position {
        VoxelPosition::Points => (pos, nrm, col),
        VoxelPosition::Center => (centre, nrm, col),
    }
}

/// The same reduction for clouds too wide to pack (more than 2^21 cells on an axis): keys kept as integers.
fn downsample_wide(p: &Points, size: f32, how: Reduction) -> Points {
    let inv = 1.0 / size as f64;
    let mut order: Vec<([i64; 3], u32)> = p
        .positions
        .iter()
        .enumerate()
        .map(|(i, q)| {
            let c = q.map(|v| floor(v as f64 * inv));
            ([c[2], c[1], c[0]], i as u32)
        })
        .collect();
    order.par_sort_unstable();
    let mut out = Points::default();
    for run in order.chunk_by(|a, b| a.0 == b.0) {
        let [z, y, x] = run[0].0;
        let centre = [x, y, z].map(|c| ((c as f64 + 0.5) * size as f64) as f32);
        let (pos, n, c) = reduce_run(p, run.iter().map(|o| o.1 as usize), centre, how);
        out.positions.push(pos);
        out.normals.push(n);
        out.colors.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud(pos: &[[f32; 3]]) -> Points {
        Points {
            positions: pos.to_vec(),
            normals: vec![[0.0, 0.0, 1.0]; pos.len()],
            colors: (0..pos.len()).map(|i| [i as f32, 0.0, 0.0]).collect(),
        }
    }

    #[test]
    fn reductions_pick_mean_nearest_and_first() {
        // Two points in voxel (0,0,0) of edge 1, one in (−1,0,0).
        let p = cloud(&[[0.9, 0.9, 0.9], [0.45, 0.5, 0.55], [-0.5, 0.5, 0.5]]);
        let r = |reduce, position| downsample(&p, 1.0, Reduction { reduce, position });
        let mean = r(Reduce::Mean, VoxelPosition::Points);
        let want = [[-0.5, 0.5, 0.5], [0.675, 0.7, 0.725]];
        for (got, want) in mean.positions.iter().flatten().zip(want.iter().flatten()) {
            assert!((got - want).abs() < 1e-6, "{:?}", mean.positions);
        }
        assert_eq!(mean.colors, vec![[2.0, 0.0, 0.0], [0.5, 0.0, 0.0]]);
        let near = r(Reduce::Nearest, VoxelPosition::Points);
        assert_eq!(near.positions[1], [0.45, 0.5, 0.55]);
        assert_eq!(near.colors[1], [1.0, 0.0, 0.0]);
        let first = r(Reduce::First, VoxelPosition::Center);
        assert_eq!(first.positions, vec![[-0.5, 0.5, 0.5], [0.5, 0.5, 0.5]]);
        assert_eq!(first.colors[1], [0.0, 0.0, 0.0]);
    }

    #[test]
    fn wide_clouds_reduce_like_packed_ones() {
        let mut pos: Vec<[f32; 3]> = (0..50).map(|i| [i as f32 * 0.37 % 3.0, (i * 7 % 5) as f32 * 0.3, 0.1]).collect();
        let packed = downsample(&cloud(&pos), 0.5, Reduction::default());
        assert_eq!(downsample_wide(&cloud(&pos), 0.5, Reduction::default()), packed);
        // Points 2^22 cells away on every axis force the wide path; the near points keep their voxels.
        pos.push([4.0e6, -4.0e6, 4.0e6]);
        let wide = downsample(&cloud(&pos), 0.5, Reduction::default());
        assert_eq!(wide.len(), packed.len() + 1);
    }
}
