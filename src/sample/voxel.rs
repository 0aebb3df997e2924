//! Voxel downsampling on a lattice anchored at the world origin, so every frame of a sequence shares one grid
//! (Open3D's legacy API anchors at each cloud's own minimum, which makes the lattice drift between frames).

use std::collections::HashMap;

use super::Points;

/// Sums of position, normal and colour, count, and lattice index of one voxel.
type Cell = ([f64; 3], [f64; 3], [f64; 3], u32, [i64; 3]);

/// Merges the points in each voxel of edge `size` into one: mean position, mean linear colour, normalized mean
/// normal. Output order is by voxel index (z, y, x), independent of the input order.
pub fn downsample(p: &Points, size: f32) -> Points {
    let mut cells: HashMap<[i64; 3], usize> = HashMap::with_capacity(p.len() / 2);
    let mut acc: Vec<Cell> = Vec::new();
    let inv = 1.0 / size as f64;
    for i in 0..p.len() {
        let key = p.positions[i].map(|v| (v as f64 * inv).floor() as i64);
        let slot = *cells.entry(key).or_insert_with(|| {
            acc.push(([0.0; 3], [0.0; 3], [0.0; 3], 0, key));
            acc.len() - 1
        });
        let a = &mut acc[slot];
        for k in 0..3 {
            a.0[k] += p.positions[i][k] as f64;
            a.1[k] += p.normals[i][k] as f64;
            a.2[k] += p.colors[i][k] as f64;
        }
        a.3 += 1;
    }
    acc.sort_unstable_by_key(|a| [a.4[2], a.4[1], a.4[0]]);
    let mut out = Points::default();
    for (pos, nrm, col, n, _) in acc {
        let n = n as f64;
        out.positions.push(pos.map(|v| (v / n) as f32));
        let len = nrm.iter().map(|v| v * v).sum::<f64>().sqrt();
        out.normals.push(if len > 0.0 { nrm.map(|v| (v / len) as f32) } else { [0.0; 3] });
        out.colors.push(col.map(|v| (v / n) as f32));
    }
    out
}
