//! A static 3-d tree for the two queries point-cloud metrics make of every point: the nearest point (maybe
//! leaving one out), and every point within a radius.
//!
//! Why not a crate: `rstar`, tried first, spent 6.1 s on a pair of 1M-point clouds where pc_error spends 5.3 s
//! (its R*-tree's best-first heap dominated the profile), and `kiddo` brings a coroutine runtime and `tracing`
//! with it for these two queries. Distances are squared Euclidean in f64 of the f32 coordinates, so ties between
//! points on an integer grid are exact, as the metrics need them to be.

/// Points per leaf.
const LEAF: usize = 12;

#[derive(Debug, Clone, Copy)]
struct Node {
    /// 0, 1, 2: the split axis; 3: a leaf.
    axis: u8,
    /// The split value: the left subtree is ≤ it, the right ≥ it.
    value: f64,
    /// Split: the children's node indices; leaf: the range of points.
    a: u32,
    b: u32,
}

/// The tree: points reordered so every leaf's are contiguous.
#[derive(Debug)]
pub struct KdTree {
    nodes: Vec<Node>,
    points: Vec<[f64; 3]>,
    ids: Vec<u32>,
}

fn dist2(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

impl KdTree {
    /// Builds the tree of `points` (their indices are what queries return).
    pub fn new(points: &[[f32; 3]]) -> KdTree {
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        let pts: Vec<[f64; 3]> = points.iter().map(|p| p.map(f64::from)).collect();
        let mut nodes = Vec::with_capacity(2 * points.len() / LEAF + 2);
        build(&pts, &mut order, 0, &mut nodes);
        let points = order.iter().map(|&i| pts[i as usize]).collect();
        KdTree { nodes, points, ids: order }
    }

    /// The nearest point to `q` other than `skip`: its squared distance and index (`u32::MAX` when there is
    /// none).
    pub fn nearest(&self, q: &[f64; 3], skip: u32) -> (f64, u32) {
        let mut best = (f64::INFINITY, u32::MAX);
        if !self.nodes.is_empty() {
            self.nearest_in(0, q, skip, &mut best);
        }
        best
    }

    fn nearest_in(&self, n: usize, q: &[f64; 3], skip: u32, best: &mut (f64, u32)) {
        let node = self.nodes[n];
        if node.axis == 3 {
            for i in node.a as usize..node.b as usize {
                let d = dist2(&self.points[i], q);
                // Ties go to the lower index, whatever the tree's order.
                if (d < best.0 || d == best.0 && self.ids[i] < best.1) && self.ids[i] != skip {
                    *best = (d, self.ids[i]);
                }
            }
            return;
        }
        let off = q[node.axis as usize] - node.value;
        let (near, far) = if off <= 0.0 { (node.a, node.b) } else { (node.b, node.a) };
        self.nearest_in(near as usize, q, skip, best);
        if off * off <= best.0 {
            self.nearest_in(far as usize, q, skip, best);
        }
    }

    /// Every point within squared distance `r2` of `q`, as (squared distance, index), into `out` (unsorted).
    pub fn within(&self, q: &[f64; 3], r2: f64, out: &mut Vec<(f64, u32)>) {
        if !self.nodes.is_empty() {
            self.within_in(0, q, r2, out);
        }
    }

    fn within_in(&self, n: usize, q: &[f64; 3], r2: f64, out: &mut Vec<(f64, u32)>) {
        let node = self.nodes[n];
        if node.axis == 3 {
            for i in node.a as usize..node.b as usize {
                let d = dist2(&self.points[i], q);
                if d <= r2 {
                    out.push((d, self.ids[i]));
                }
            }
            return;
        }
        let off = q[node.axis as usize] - node.value;
        if off <= 0.0 || off * off <= r2 {
            self.within_in(node.a as usize, q, r2, out);
        }
        if off >= 0.0 || off * off <= r2 {
            self.within_in(node.b as usize, q, r2, out);
        }
    }
}

/// Builds the subtree of `order` (whose first element is at `start` in the final order) and returns its node.
fn build(pts: &[[f64; 3]], order: &mut [u32], start: usize, nodes: &mut Vec<Node>) -> u32 {
    let id = nodes.len() as u32;
    if order.len() <= LEAF {
        nodes.push(Node { axis: 3, value: 0.0, a: start as u32, b: (start + order.len()) as u32 });
        return id;
    }
    // Split the widest axis at the median.
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &i in order.iter() {
        for c in 0..3 {
            lo[c] = lo[c].min(pts[i as usize][c]);
            hi[c] = hi[c].max(pts[i as usize][c]);
        }
    }
    let axis = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap_or(0);
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&a, &b| pts[a as usize][axis].total_cmp(&pts[b as usize][axis]));
    let value = pts[order[mid] as usize][axis];
    nodes.push(Node { axis: axis as u8, value, a: 0, b: 0 });
    let (left, right) = order.split_at_mut(mid);
    let a = build(pts, left, start, nodes);
    let b = build(pts, right, start + mid, nodes);
    nodes[id as usize].a = a;
    nodes[id as usize].b = b;
    id
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_agree_with_brute_force_on_a_grid_full_of_ties() {
        // Integer points, many on the same planes and at equal distances.
        let pts: Vec<[f32; 3]> =
            (0..2000u32).map(|i| [(i % 13) as f32, ((i / 13) % 11) as f32, (i % 7) as f32]).collect();
        let t = KdTree::new(&pts);
        let mut got = Vec::new();
        for (k, q) in [[0.5, 0.5, 0.5], [12.0, 10.0, 6.0], [6.2, 5.0, 3.0], [-3.0, 20.0, 1.0]].iter().enumerate() {
            let brute = pts
                .iter()
                .enumerate()
                .map(|(i, p)| (dist2(&p.map(f64::from), q), i as u32))
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                .unwrap();
            assert_eq!(t.nearest(q, u32::MAX), brute, "query {k}");
            got.clear();
            t.within(q, brute.0 + 1.0, &mut got);
            got.sort_by_key(|e| e.1);
            let want: Vec<u32> =
                (0..pts.len() as u32).filter(|&i| dist2(&pts[i as usize].map(f64::from), q) <= brute.0 + 1.0).collect();
            assert_eq!(got.iter().map(|e| e.1).collect::<Vec<_>>(), want, "query {k}");
        }
        // Leaving a point out finds its nearest other point.
        let (d, i) = t.nearest(&[3.0, 4.0, 5.0], u32::MAX);
        assert_eq!(d, 0.0);
        assert!(t.nearest(&[3.0, 4.0, 5.0], i).1 != i);
    }
}
