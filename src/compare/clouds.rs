//! Point clouds against their ground truth: D1 (point-to-point) and D2 (point-to-plane) geometry PSNR and colour
//! PSNR (Y, Cb, Cr), as MPEG's `pc_error` (mpeg-pcc-dmetric 0.14.1, its default options) defines them, so a
//! codec's output scores here as it does in the papers that report those numbers:
//!
//! - Reading: positions as 32-bit floats; points with identical positions merged into one, their colours
//!   averaged (truncated to integers), the first one's normal kept (`--dropdups 2`).
//! - One direction, A → B: for each point of A its nearest point of B, and the points of B at the same distance
//!   (squared distances within 1e-8 of the previous one, among the 10 nearest, or 15 … 30 while the 10th … 25th
//!   is as near as the first). D1 is the squared distance to the nearest; D2 the squared projection of the error
//!   vector on the normals of B, averaged over those points; the colour is their average, rounded, compared in
//!   BT.709 Y′CbCr over 0 … 1. Mean squared errors over A's points.
//! - Normals of B come from the reference's: each reference point gives its normal to the points of B nearest it
//!   (all those at exactly the same distance), averaged; a point of B that none gives one takes the average of
//!   its nearest reference points' normals. Without normals in the reference there is no D2, as in `pc_error`.
//! - Symmetric: the worse (higher-error) of A → B and B → A, per metric.
//! - PSNR: geometry `10 log10(3 p² / mse)`, with `p` the peak given (`--peak 1023` for vox10) or, by default,
//!   the largest distance from a reference point to its nearest neighbour (pc_error's "intrinsic
//!   resolution"); colour `10 log10(1 / mse)`.
//!
//! Every sum is taken in point order, so the scores do not depend on the thread count.
//!
//! One difference in what is read: pc_error takes colours only from `uchar red, green, blue`; vvgen's PLY reader
//! also takes `diffuse_red …` and float colours, so a file with those gets colour PSNRs here and none from
//! pc_error (checked on `shared/assets` pond, a binary scan with `diffuse_*` colours: D1 and D2 agree).

use std::path::Path;

use rayon::prelude::*;

use super::kdtree::KdTree;
use super::Error;

/// A cloud as `pc_error` reads it.
#[derive(Debug, Clone)]
pub struct Cloud {
    /// Positions.
    pub positions: Vec<[f32; 3]>,
    /// Normals, when the file has them.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Colours, when the file has them.
    pub colors: Option<Vec<[u8; 3]>>,
}

impl Cloud {
    /// Reads a PLY file and merges duplicate points.
    pub fn read(path: &Path) -> Result<Cloud, Error> {
        let ply = crate::scene::ply::read_file(path)
            .map_err(|e| Error::Cloud { path: path.to_path_buf(), message: e.to_string() })?;
        if ply.positions.is_empty() {
            return Err(Error::Cloud { path: path.to_path_buf(), message: "has no points".into() });
        }
        let colors = ply.colors.map(|c| c.into_iter().map(|[r, g, b, _]| [r, g, b]).collect());
        Ok(Cloud { positions: ply.positions, normals: ply.normals, colors }.merged())
    }

    /// This cloud with the normals of `other`, the same points with normals (pc_error's `-n`: vox10 frames
    /// carry none, and MPEG distributes them beside); `path` names `other` in the error.
    pub fn with_normals_of(mut self, other: Cloud, path: &Path) -> Result<Cloud, Error> {
        match other.normals {
            Some(n) if other.positions == self.positions => {
                self.normals = Some(n);
                Ok(self)
            }
            Some(_) => Err(Error::Cloud {
                path: path.to_path_buf(),
                message: format!(
                    "its {} points are not the reference's {}: give the reference's own points with normals",
                    other.positions.len(),
                    self.positions.len()
                ),
            }),
            None => Err(Error::Cloud { path: path.to_path_buf(), message: "has no normals (nx, ny, nz)".into() }),
        }
    }

    /// Sorted by position (ties in file order), identical positions merged: colours averaged and truncated,
    /// the first normal kept.
    pub fn merged(self) -> Cloud {
        let n = self.positions.len();
        let mut order: Vec<usize> = (0..n).collect();
        // Lexicographic on the values (pc_error sorts `std::array<float, 3>` with `<`); positions are finite.
        order.sort_by(|&a, &b| {
            let (p, q) = (self.positions[a], self.positions[b]);
            p.partial_cmp(&q).unwrap_or(std::cmp::Ordering::Equal).then(a.cmp(&b))
        });
        let mut out = Cloud {
            positions: Vec::with_capacity(n),
            normals: self.normals.as_ref().map(|_| Vec::with_capacity(n)),
            colors: self.colors.as_ref().map(|_| Vec::with_capacity(n)),
        };
        let mut i = 0;
        while i < n {
            let first = order[i];
            let mut j = i + 1;
            while j < n && self.positions[order[j]] == self.positions[first] {
                j += 1;
            }
            out.positions.push(self.positions[first]);
            if let (Some(src), Some(dst)) = (&self.normals, out.normals.as_mut()) {
                dst.push(src[first]);
            }
            if let (Some(src), Some(dst)) = (&self.colors, out.colors.as_mut()) {
                let mut sum = [0u64; 3];
                for &k in &order[i..j] {
                    for c in 0..3 {
                        sum[c] += u64::from(src[k][c]);
                    }
                }
                let count = (j - i) as u64;
                dst.push(sum.map(|s| (s / count) as u8));
            }
            i = j;
        }
        out
    }
}

/// A cloud's points, for its neighbour queries.
struct Index {
    tree: KdTree,
}

/// Points per parallel task: fixed, so sums are taken in the same order whatever the thread count.
const CHUNK: usize = 1 << 14;

/// Squared distances closer than this to the previous neighbour's count as the same distance.
const SAME: f64 = 1e-8;

impl Index {
    fn new(points: &[[f32; 3]]) -> Index {
        Index { tree: KdTree::new(points) }
    }

    /// The nearest point to `q` and the others pc_error counts as equally near: the chain of neighbours each
    /// within [`SAME`] of the one before, among the `k` nearest (10, grown by 5 up to 30 while the last of them
    /// is exactly as near as the first). Returns the squared distance of the nearest and the indices, nearest
    /// first.
    fn nearest_set(&self, q: [f64; 3], start: usize, chain: bool, out: &mut Vec<(f64, u32)>) -> f64 {
        out.clear();
        let (d0, first) = self.tree.nearest(&q, u32::MAX);
        if first == u32::MAX {
            return f64::INFINITY;
        }
        // Everything the chain can reach (29 steps of SAME) lies within this radius.
        self.tree.within(&q, d0 + 30.0 * SAME, out);
        out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let exact = out.iter().take_while(|e| e.0 == d0).count();
        let mut k = start;
        while exact >= k && k + 5 <= 30 {
            k += 5;
        }
        out.truncate(k);
        if chain {
            let mut keep = 1;
            while keep < out.len() && (out[keep].0 - out[keep - 1].0).abs() < SAME {
                keep += 1;
            }
            out.truncate(keep);
        } else {
            // Only the points at exactly the first's distance (how normals are handed over).
            out.truncate(exact.min(out.len()));
        }
        d0
    }
}

fn f64s(p: &[f32; 3]) -> [f64; 3] {
    p.map(f64::from)
}

/// Normals for `b`'s points from the reference `a`'s (pc_error's `scaleNormals` with averaging).
fn derived_normals(
    a: &[[f32; 3]],
    a_normals: &[[f32; 3]],
    a_index: &Index,
    b: &[[f32; 3]],
    b_index: &Index,
) -> Vec<[f64; 3]> {
    // (reference point, test point) pairs, chunk by chunk in point order: eight bytes a pair, where a list per
    // point would cost an allocation each.
    let given: Vec<Vec<(u32, u32)>> = a
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            let (mut out, mut buf) = (Vec::with_capacity(chunk.len()), Vec::new());
            for (k, p) in chunk.iter().enumerate() {
                b_index.nearest_set(f64s(p), 5, false, &mut buf);
                out.extend(buf.iter().map(|e| ((ci * CHUNK + k) as u32, e.1)));
            }
            out
        })
        .collect();
    let mut sum = vec![[0.0f64; 3]; b.len()];
    let mut count = vec![0u32; b.len()];
    for &(i, j) in given.iter().flatten() {
        for c in 0..3 {
            sum[j as usize][c] += f64::from(a_normals[i as usize][c]);
        }
        count[j as usize] += 1;
    }
    sum.into_par_iter()
        .zip(count)
        .zip(b.par_iter())
        .map_init(Vec::new, |buf, ((s, n), p)| {
            if n > 0 {
                return s.map(|v| v / f64::from(n));
            }
            a_index.nearest_set(f64s(p), 5, false, buf);
            let mut acc = [0.0; 3];
            for e in buf.iter() {
                for c in 0..3 {
                    acc[c] += f64::from(a_normals[e.1 as usize][c]);
                }
            }
            acc.map(|v| v / buf.len().max(1) as f64)
        })
        .collect()
}

/// BT.709 Y′CbCr over 0 … 1 of 8-bit RGB, in single precision as pc_error keeps it.
fn ycbcr(c: [u8; 3]) -> [f32; 3] {
    let [r, g, b] = c.map(f64::from);
    [
        ((0.2126 * r + 0.7152 * g + 0.0722 * b) / 255.0) as f32,
        ((-0.1146 * r - 0.3854 * g + 0.5 * b) / 255.0 + 0.5) as f32,
        ((0.5 * r - 0.4542 * g - 0.0458 * b) / 255.0 + 0.5) as f32,
    ]
}

/// Mean squared errors of one direction.
#[derive(Debug, Clone, Copy, Default)]
struct Errors {
    d1: f64,
    d2: Option<f64>,
    color: Option<[f64; 3]>,
}

/// One direction: every point of `a` against `b` (with `b`'s normals, when there are any).
fn one_way(a: &Cloud, b: &Cloud, b_index: &Index, b_normals: Option<&[[f64; 3]]>) -> Errors {
    let colors = a.colors.as_deref().zip(b.colors.as_deref());
    // Sums per chunk of points in order, then over the chunks in order: the same figures at any thread count.
    let parts: Vec<[f64; 5]> = a
        .positions
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            let (mut acc, mut buf) = ([0.0f64; 5], Vec::new());
            for (k, p) in chunk.iter().enumerate() {
                let i = ci * CHUNK + k;
                b_index.nearest_set(f64s(p), 10, true, &mut buf);
                let j = buf[0].1 as usize;
                let e = [p[0] - b.positions[j][0], p[1] - b.positions[j][1], p[2] - b.positions[j][2]].map(f64::from);
                acc[0] += e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
                if let Some(n) = b_normals {
                    let s: f64 = buf
                        .iter()
                        .map(|&(_, k)| {
                            let (bp, bn) = (b.positions[k as usize], n[k as usize]);
                            let dot: f64 = (0..3).map(|c| f64::from(p[c] - bp[c]) * bn[c]).sum();
                            dot * dot
                        })
                        .sum();
                    acc[1] += s / buf.len() as f64;
                }
                if let Some((ca, cb)) = colors {
                    let mut sum = [0u32; 3];
                    for &(_, k) in buf.iter() {
                        for c in 0..3 {
                            sum[c] += u32::from(cb[k as usize][c]);
                        }
                    }
                    let n = buf.len() as f64;
                    let avg = sum.map(|s| (f64::from(s) / n).round() as u8);
                    let (x, y) = (ycbcr(ca[i]), ycbcr(avg));
                    for c in 0..3 {
                        let d = x[c] - y[c];
                        acc[2 + c] += f64::from(d * d);
                    }
                }
            }
            acc
        })
        .collect();
    let n = a.positions.len() as f64;
    let (mut d1, mut d2, mut col) = (0.0, 0.0, [0.0; 3]);
    for part in &parts {
        d1 += part[0];
        d2 += part[1];
        for k in 0..3 {
            col[k] += part[2 + k];
        }
    }
    Errors { d1: d1 / n, d2: b_normals.map(|_| d2 / n), color: colors.map(|_| col.map(|v| v / n)) }
}

/// The scores of one pair of clouds.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Score {
    /// The pair's name (the reference file).
    pub name: String,
    /// Points after merging duplicates: reference, test.
    pub points: [usize; 2],
    /// The peak the geometry PSNRs use.
    pub peak: f64,
    /// D1 mean squared error (the worse direction).
    pub d1_mse: f64,
    /// D1 PSNR, dB.
    pub d1_psnr: f64,
    /// D2 mean squared error, when the reference has normals.
    pub d2_mse: Option<f64>,
    /// D2 PSNR, dB.
    pub d2_psnr: Option<f64>,
    /// Y, Cb, Cr PSNR, dB, when both clouds have colours.
    pub color_psnr: Option<[f64; 3]>,
}

fn psnr(mse: f64, peak_sq: f64) -> f64 {
    10.0 * (peak_sq / mse).log10()
}

/// The largest distance from a point of `c` to its nearest other point (pc_error's default peak).
fn intrinsic_resolution(c: &Cloud, index: &Index) -> f64 {
    c.positions
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let (d, _) = index.tree.nearest(&f64s(p), i as u32);
            if d.is_finite() {
                d.sqrt()
            } else {
                0.0
            }
        })
        .reduce(|| 0.0, f64::max)
}

/// D1, D2 and colour PSNR of `test` against `reference`; `peak` as given, else the reference's intrinsic
/// resolution.
pub fn score(name: &str, reference: &Cloud, test: &Cloud, peak: Option<f64>) -> Score {
    let (ia, ib) = (Index::new(&reference.positions), Index::new(&test.positions));
    let peak = peak.unwrap_or_else(|| intrinsic_resolution(reference, &ia));
    let b_normals =
        reference.normals.as_deref().map(|n| derived_normals(&reference.positions, n, &ia, &test.positions, &ib));
    let a_normals: Option<Vec<[f64; 3]>> =
        reference.normals.as_ref().map(|n| n.iter().map(|v| v.map(f64::from)).collect());
    let ab = one_way(reference, test, &ib, b_normals.as_deref());
    let ba = one_way(test, reference, &ia, a_normals.as_deref());
    let peak_sq = 3.0 * peak * peak;
    let d1 = ab.d1.max(ba.d1);
    let d2 = ab.d2.zip(ba.d2).map(|(x, y)| x.max(y));
    let color = ab.color.zip(ba.color).map(|(x, y)| std::array::from_fn(|c| psnr(x[c].max(y[c]), 1.0)));
    Score {
        name: name.to_string(),
        points: [reference.positions.len(), test.positions.len()],
        peak,
        d1_mse: d1,
        d1_psnr: psnr(d1, peak_sq),
        d2_mse: d2,
        d2_psnr: d2.map(|m| psnr(m, peak_sq)),
        color_psnr: color,
    }
}
