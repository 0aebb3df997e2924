//! Binning for the parallel setup: a stable counting sort of one chunk's primitives into the cells of a grid
//! (tiles for triangles, bands of tile rows for splats). An item goes into every cell of its inclusive rectangle,
//! and each cell keeps the chunk's order, so walking the chunks' cells in chunk order is scene order.

/// Items sorted by cell: cell `c`'s are `items[start[c]..start[c + 1]]`.
#[derive(Debug, Default)]
pub struct Binned<V> {
    /// Where each cell begins in `items`, plus the end.
    pub start: Vec<u32>,
    /// The items' values, cell by cell.
    pub items: Vec<V>,
}

impl<V: Copy + Default> Binned<V> {
    /// Sorts `items` into a grid `across` cells wide and `cells` cells in all; `rect` gives an item's inclusive
    /// cell rectangle `[x0, y0, x1, y1]` and `value` what the cell stores of item `i`.
    pub fn sort<T>(
        items: &[T],
        across: usize,
        cells: usize,
        rect: impl Fn(&T) -> [usize; 4],
        value: impl Fn(usize, &T) -> V,
    ) -> Binned<V> {
        let mut start = vec![0u32; cells + 1];
        for t in items {
            let [x0, y0, x1, y1] = rect(t);
            for y in y0..y1 + 1 {
                for x in x0..x1 + 1 {
                    start[y * across + x + 1] += 1;
                }
            }
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        let mut next = start.clone();
        let mut out = vec![V::default(); start[cells] as usize];
        for (i, t) in items.iter().enumerate() {
            let [x0, y0, x1, y1] = rect(t);
            for y in y0..y1 + 1 {
                for x in x0..x1 + 1 {
                    let c = y * across + x;
                    out[next[c] as usize] = value(i, t);
                    next[c] += 1;
                }
            }
        }
        Binned { start, items: out }
    }

    /// Cell `c`'s items, in order.
    #[inline]
    pub fn cell(&self, c: usize) -> &[V] {
        &self.items[self.start[c] as usize..self.start[c + 1] as usize]
    }
}
