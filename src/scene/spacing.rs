//! How far apart a cloud's points lie: what a point-cloud sequence's splats default to when its frames are not
//! on a whole-number grid.
//!
//! 8i and vsense frames hold integer coordinates, one unit a voxel, and a splat of one unit closes their surfaces
//! exactly. Clouds in metres (a capture rig's, a simulation's, Gaussian splatting's centres) have no such unit: a
//! cube of one unit there is the whole subject many times over, so every splat reached behind the camera and was
//! dropped, and the images came out empty. Their splats take the distance within which nine points in ten have
//! a neighbour instead: on a regular grid that is the grid's step (each point's nearest neighbour is one step
//! away), on an irregular sampling it is wide enough that the splats of a surface's points meet.

use glam::Vec3;

/// Points whose nearest neighbour is measured (evenly spread through the cloud, in its order): the percentile is
/// found from a sample, not from every point of a million-point frame.
const SAMPLE: usize = 4096;

/// Which of the measured nearest-neighbour distances is taken, as a fraction of them.
const PERCENTILE: f64 = 0.9;

/// Rings of cells searched around a point for its nearest neighbour (cells hold about two points each where
/// the cloud fills its bounds, more on a surface): a point with none that near is a stray.
const RINGS: i64 = 3;

/// Whether every coordinate of `points` is a whole number: an 8i-style voxel grid.
pub fn on_whole_grid(points: &[Vec3]) -> bool {
    points.iter().all(|p| p.to_array().iter().all(|c| c.fract() == 0.0))
}

/// The distance within which [`PERCENTILE`] of the points (of a sample of [`SAMPLE`]) have their nearest
/// neighbour, points at the very same place as a sampled one not counted as its neighbours. `None` when fewer
/// than two distinct points are finite, or when that many lie apart from the rest (nothing typical to measure).
pub fn typical(points: &[Vec3]) -> Option<f32> {
    let finite: Vec<Vec3> = points.iter().copied().filter(|p| p.is_finite()).collect();
    let grid = Grid::of(&finite)?;
    let step = finite.len().div_ceil(SAMPLE).max(1);
    // Strays (no neighbour within the rings searched) sort last.
    let mut d: Vec<f32> =
        finite.iter().step_by(step).map(|&p| grid.nearest(&finite, p).unwrap_or(f32::INFINITY)).collect();
    d.sort_by(f32::total_cmp);
    let k = ((d.len() - 1) as f64 * PERCENTILE).round() as usize;
    d.get(k).copied().filter(|d| d.is_finite())
}

/// The points binned into cubic cells, about two points a cell were they spread through the bounds' volume; a
/// cell's points are a run of `order`, sorted by cell (ties in the cloud's order, so the result never depends on
/// anything but the points).
struct Grid {
    lo: Vec3,
    cell: f32,
    dims: [i64; 3],
    /// Point indices sorted by cell number.
    order: Vec<u32>,
    /// Cell numbers of `order`'s points, in the same order.
    cells: Vec<i64>,
}

impl Grid {
    fn of(points: &[Vec3]) -> Option<Grid> {
        let (lo, hi) = points.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let extent = hi - lo;
        if points.len() < 2 || extent.max_element() <= 0.0 || u32::try_from(points.len()).is_err() {
            return None;
        }
        // Cells of the side that would hold two points each in the bounds' volume (flat clouds: in their plane),
        // at most 2^20 cells along an axis.
        let n = points.len() as f64;
        let e = extent.as_dvec3().max(glam::DVec3::splat(extent.max_element() as f64 * 1e-3));
        let cell = ((e.x * e.y * e.z * 2.0 / n).cbrt()).max(extent.max_element() as f64 / (1 << 20) as f64) as f32;
        let dims = (extent / cell).floor().as_i64vec3().to_array().map(|d| d + 1);
        let mut g = Grid { lo, cell, dims, order: Vec::new(), cells: Vec::new() };
        let mut keyed: Vec<(i64, u32)> = points.iter().zip(0u32..).map(|(&p, i)| (g.cell_of(p), i)).collect();
        keyed.sort_unstable();
        (g.cells, g.order) = keyed.into_iter().unzip();
        Some(g)
    }

    fn coords(&self, p: Vec3) -> [i64; 3] {
        let c = ((p - self.lo) / self.cell).floor().as_i64vec3().to_array();
        [0, 1, 2].map(|k| c[k].clamp(0, self.dims[k] - 1))
    }

    fn cell_of(&self, p: Vec3) -> i64 {
        let [x, y, z] = self.coords(p);
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    /// The distance from `p` to the nearest point of `points` not at `p` itself, searched ring by ring of cells
    /// around `p`'s out to [`RINGS`]; `None` when none lies that near (a stray point: it counts as the farthest).
    fn nearest(&self, points: &[Vec3], p: Vec3) -> Option<f32> {
        let c = self.coords(p);
        let mut best = f32::INFINITY;
        for r in 0..=RINGS {
            // `p` lies anywhere in its cell, so ring r's points are at least r − 1 cells from it.
            if r >= 1 && best <= (r - 1) as f32 * self.cell {
                return Some(best);
            }
            for dz in -r..=r {
                for dy in -r..=r {
                    // Inside the shell only its two end cells of the row; on its faces the whole row.
                    let whole = dz.abs() == r || dy.abs() == r;
                    let (first, stride) = if whole || r == 0 { (-r, 1) } else { (-r, (2 * r) as usize) };
                    for dx in (first..=r).step_by(stride) {
                        let (x, y, z) = (c[0] + dx, c[1] + dy, c[2] + dz);
                        if ![x, y, z].iter().zip(&self.dims).all(|(&v, &d)| (0..d).contains(&v)) {
                            continue;
                        }
                        for &i in self.run((z * self.dims[1] + y) * self.dims[0] + x) {
                            let d = points[i as usize].distance(p);
                            if d > 0.0 && d < best {
                                best = d;
                            }
                        }
                    }
                }
            }
        }
        (best <= RINGS as f32 * self.cell).then_some(best)
    }

    /// The points of cell number `cell`.
    fn run(&self, cell: i64) -> &[u32] {
        let a = self.cells.partition_point(|&c| c < cell);
        let b = self.cells.partition_point(|&c| c <= cell);
        &self.order[a..b]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_measures_its_step_and_an_irregular_cloud_nine_neighbours_in_ten() {
        // A 40 × 40 grid of step 0.25 on a tilted plane, every point twice (duplicates are not neighbours).
        let grid: Vec<Vec3> = (0..1600)
            .flat_map(|i| {
                let p = Vec3::new((i % 40) as f32 * 0.25, (i / 40) as f32 * 0.25, (i % 40) as f32 * 0.1);
                [p, p]
            })
            .collect();
        let step = Vec3::new(0.25, 0.0, 0.1).length().min(0.25);
        assert!((typical(&grid).unwrap() - step).abs() < 1e-5, "{:?}", typical(&grid));
        assert!(!on_whole_grid(&grid));
        assert!(on_whole_grid(&[Vec3::new(3.0, -7.0, 1023.0)]));
        // Points at distances 1, 2, …, 10 from their partners: nine in ten have theirs within 9.
        let pairs: Vec<Vec3> = (1..=10)
            .flat_map(|k| [Vec3::new(k as f32 * 100.0, 0.0, 0.0), Vec3::new(k as f32 * 100.0, k as f32, 0.0)])
            .collect();
        assert_eq!(typical(&pairs), Some(9.0));
        // The brute-force nearest neighbour, on a clumped cloud the grid bins unevenly.
        let mut s = 12345u32;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as f32 / u32::MAX as f32
        };
        let cloud: Vec<Vec3> =
            (0..3000).map(|i| Vec3::new(rnd(), rnd(), rnd()) * if i % 3 == 0 { 10.0 } else { 0.5 }).collect();
        let g = Grid::of(&cloud).unwrap();
        for &p in cloud.iter().step_by(37) {
            let brute = cloud.iter().map(|q| q.distance(p)).filter(|&d| d > 0.0).fold(f32::INFINITY, f32::min);
            match g.nearest(&cloud, p) {
                Some(d) => assert_eq!(d, brute),
                None => assert!(brute > RINGS as f32 * g.cell, "{brute} is within the rings searched"),
            }
        }
        assert_eq!(typical(&[Vec3::ONE, Vec3::ONE]), None);
        assert_eq!(typical(&[]), None);
    }
}
