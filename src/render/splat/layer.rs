//! A band's splats drawn on their own, before each tile merges them behind its triangles: per sample one integer
//! key (depth above point) and the face a cube shows.

/// A sample's depth test and tie rule as one integer: the depth's bits (a positive float's order is its bits'
/// order) above the point's index. The smaller key is the nearer splat, and among equal depths the earlier
/// point, the first drawn in scene order: "strictly nearer wins" in one compare, and a layer's merge with the
/// tile's triangles reads one word per sample.
#[inline]
pub(super) fn key(z: f32, point: u32) -> u64 {
    debug_assert!(z.is_sign_positive(), "splat depths are past the near plane (> 0)");
    (u64::from(z.to_bits()) << 32) | u64::from(point)
}

/// The key of a sample no splat covers: depth +∞.
const EMPTY: u64 = ((f32::INFINITY.to_bits() as u64) << 32) | u32::MAX as u64;

/// A band's splats drawn alone, full image width: per sample the nearest splat's depth and point, and (cubes) the
/// face it shows.
#[derive(Debug, Default)]
pub struct Layer {
    /// First sample row.
    pub y0: i64,
    /// Width in samples.
    pub w: i64,
    /// Depth and point as one [`key`]; [`EMPTY`] where no splat.
    pub(super) key: Vec<u64>,
    /// The entered face of a cube, an index into [`FACES`](super::FACES) (meaningful where a splat is).
    pub(super) face: Vec<u8>,
}

impl Layer {
    /// Whether any sample of columns `x0 .. x0 + w` shows a splat.
    pub fn any(&self, x0: i64, w: i64) -> bool {
        self.key
            .chunks_exact(self.w as usize)
            .any(|row| row[x0 as usize..(x0 + w) as usize].iter().any(|&k| k != EMPTY))
    }

    /// The view depth at sample `j`, +∞ where no splat.
    #[inline]
    pub fn depth(&self, j: usize) -> f32 {
        f32::from_bits((self.key[j] >> 32) as u32)
    }

    /// The point shown at sample `j` (meaningful where the depth is finite).
    #[inline]
    pub(super) fn point(&self, j: usize) -> u32 {
        self.key[j] as u32
    }

    /// Empties the layer and moves it to the `w × h` samples from row `y0`.
    pub(super) fn reset(&mut self, y0: i64, w: i64, h: i64) {
        let n = (w * h) as usize;
        (self.y0, self.w) = (y0, w);
        self.key.clear();
        self.key.resize(n, EMPTY);
        self.face.clear();
        self.face.resize(n, 0);
    }
}
