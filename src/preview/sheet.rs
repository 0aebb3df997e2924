//! Contact sheets: one PNG per split, a grid of thumbnails answering "does it look right?" at a glance. Views
//! run down and frames across for multi-view video (so time runs left to right and a wrong time axis shows);
//! monocular and random splits are shown time-major. Each cell is the RGBA render over a checkerboard (so
//! transparency and crops show), with depth and mask below when those passes exist, and a label.

use super::canvas::{viridis, Canvas, Pixels, Rgb, RgbaPixels};
use crate::manifest::render::Pass;
use crate::manifest::split::TimeMode;
use crate::plan::Plan;

/// Most thumbnails on a sheet.
const MOST: usize = 32;
/// Most frames (columns) and views (rows) of a multi-view video sheet.
const MOST_FRAMES: usize = 8;
const MOST_VIEWS: usize = 4;
/// Thumbnail width in pixels.
const THUMB: u32 = 160;

/// What a sheet shows: images of the plan in reading order, and the number of columns.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Layout {
    /// Plan image indices, row by row.
    pub images: Vec<usize>,
    /// Columns of the grid.
    pub columns: usize,
}

/// `k` indices spread evenly over `0..n`, first and last included (all of them when `n ≤ k`).
pub fn evenly(n: usize, k: usize) -> Vec<usize> {
    if n <= k {
        return (0..n).collect();
    }
    if k <= 1 {
        return vec![0];
    }
    (0..k).map(|i| i * (n - 1) / (k - 1)).collect()
}

/// The images split `s`'s sheet shows.
pub fn layout(plan: &Plan, s: usize) -> Layout {
    let split = &plan.splits[s];
    if split.time == TimeMode::All && split.frames.len() > 1 {
        // Rows are views, columns frames; images of a synchronized split are frame-major.
        let views = split.poses.len();
        let rows = evenly(views, MOST_VIEWS);
        let cols = evenly(split.frames.len(), MOST_FRAMES);
        let images = rows.iter().flat_map(|&v| cols.iter().map(move |&f| split.images[f * views + v])).collect();
        return Layout { images, columns: cols.len() };
    }
    let mut order = split.images.clone();
    // Time-major: by frame, then view (a random split's pairs come in draw order).
    order.sort_by_key(|&i| (plan.images[i].frame, plan.images[i].view, i));
    let images: Vec<usize> = evenly(order.len(), MOST).into_iter().map(|k| order[k]).collect();
    let columns = images.len().clamp(1, MOST_FRAMES);
    Layout { images, columns }
}

/// The passes a sheet shows besides RGBA, of those rendered.
pub fn extra_passes(passes: &[Pass]) -> Vec<Pass> {
    [Pass::Depth, Pass::Mask].into_iter().filter(|p| passes.contains(p)).collect()
}

/// One thumbnail's decoded passes.
pub struct Cell {
    /// View, frame and time, for the label.
    pub view: u32,
    /// Scene frame.
    pub frame: usize,
    /// Normalized time.
    pub time: f64,
    /// The RGBA render (PNG bytes).
    pub rgba: Vec<u8>,
    /// The depth render (16-bit PNG, millimetres), when rendered.
    pub depth: Option<Vec<u8>>,
    /// The mask render (8-bit PNG), when rendered.
    pub mask: Option<Vec<u8>>,
}

/// Why a sheet cannot be drawn: a blob that is not the PNG its pass writes (a damaged cache).
#[derive(Debug, thiserror::Error)]
#[error("view {view}, frame {frame}: {what} is not a readable PNG")]
pub struct Error {
    view: u32,
    frame: usize,
    what: &'static str,
}

/// A cell's passes, decoded.
struct Decoded {
    rgba: image::RgbaImage,
    depth: Option<image::ImageBuffer<image::Luma<u16>, Vec<u16>>>,
    mask: Option<image::GrayImage>,
}

fn decode(c: &Cell) -> Result<Decoded, Error> {
    let read = |b: &[u8], what| image::load_from_memory(b).map_err(|_| Error { view: c.view, frame: c.frame, what });
    Ok(Decoded {
        rgba: read(&c.rgba, "the RGBA render")?.into_rgba8(),
        depth: c.depth.as_deref().map(|b| read(b, "the depth render")).transpose()?.map(|d| d.into_luma16()),
        mask: c.mask.as_deref().map(|b| read(b, "the mask render")).transpose()?.map(|m| m.into_luma8()),
    })
}

/// Draws the sheet of `cells` (in reading order) with `columns` columns; `title` heads it.
pub fn draw(title: &str, cells: &[Cell], columns: usize) -> Result<Vec<u8>, Error> {
    use rayon::prelude::*;
    // Decoding is most of the work: in parallel (the drawing after it is sequential, so bytes do not depend on
    // threads).
    let decoded: Vec<Decoded> = cells.par_iter().map(decode).collect::<Result<_, _>>()?;
    let (w, h) = decoded.first().map_or((1, 1), |d| (d.rgba.width().max(1), d.rgba.height().max(1)));
    let tw = THUMB;
    let th = ((THUMB as u64 * h as u64 / w as u64) as u32).clamp(8, 2 * THUMB);
    let extras = decoded.first().is_some_and(|c| c.depth.is_some() || c.mask.is_some());
    let strip = if extras { th / 2 } else { 0 };
    let (pad, label, head) = (8u32, 16u32, 34u32);
    let cell_h = th + strip + label;
    let columns = columns.max(1);
    let rows = cells.len().div_ceil(columns).max(1);
    let width = pad + columns as u32 * (tw + pad);
    let height = head + rows as u32 * (cell_h + pad) + pad;
    let mut c = Canvas::new(width, height, [32, 32, 36]);
    c.text(pad as f32, 22.0, 15.0, title, [235, 235, 235]);

    // Depth is coloured over one range for the whole sheet, so depths compare across thumbnails.
    let (lo, hi) = decoded
        .iter()
        .filter_map(|d| d.depth.as_ref())
        .flat_map(|d| d.as_raw().iter().copied().filter(|&v| v > 0))
        .fold((u16::MAX, 0u16), |(lo, hi), v| (lo.min(v), hi.max(v)));

    for (k, (cell, dec)) in cells.iter().zip(&decoded).enumerate() {
        let (col, row) = ((k % columns) as u32, (k / columns) as u32);
        let (x, y) = ((pad + col * (tw + pad)) as i64, (head + row * (cell_h + pad)) as i64);
        let (iw, ih) = dec.rgba.dimensions();
        c.image_rgba(x, y, tw, th, RgbaPixels { px: dec.rgba.as_raw(), width: iw, height: ih });
        if extras {
            // Depth and mask side by side at half size (the thumbnail's aspect kept).
            let half = tw / 2;
            if let Some(d) = &dec.depth {
                let (dw, dh) = d.dimensions();
                let span = (hi.saturating_sub(lo)).max(1) as f32;
                // Near is bright: 1 at the nearest depth on the sheet, 0 at the farthest; background black.
                let px: Vec<Rgb> = d
                    .as_raw()
                    .iter()
                    .map(|&v| if v == 0 { [0, 0, 0] } else { viridis(1.0 - (v - lo.min(v)) as f32 / span) })
                    .collect();
                c.image(x, y + th as i64, half, strip, Pixels { px: &px, width: dw, height: dh });
            }
            if let Some(m) = &dec.mask {
                let (mw, mh) = m.dimensions();
                let px: Vec<Rgb> = m.as_raw().iter().map(|&v| [v, v, v]).collect();
                c.image(x + half as i64, y + th as i64, tw - half, strip, Pixels { px: &px, width: mw, height: mh });
            }
        }
        c.frame(x - 1, y - 1, tw as i64 + 2, (th + strip) as i64 + 2, [70, 70, 78]);
        let text = format!("v{} · f{} · t {:.2}", cell.view, cell.frame, cell.time);
        c.text(x as f32 + 2.0, (y + (th + strip + label) as i64 - 3) as f32, 12.0, &text, [200, 200, 200]);
    }
    if extras && hi > 0 {
        let mask = if decoded.first().is_some_and(|c| c.mask.is_some()) { " · mask" } else { "" };
        let note =
            format!("below each: depth {:.2}–{:.2} m (near bright){mask}", lo as f64 / 1000.0, hi as f64 / 1000.0);
        let w = c.text_width(12.0, &note);
        c.text(width as f32 - pad as f32 - w, 22.0, 12.0, &note, [170, 170, 170]);
    }
    Ok(c.png())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evenly_keeps_both_ends() {
        assert_eq!(evenly(3, 8), vec![0, 1, 2]);
        assert_eq!(evenly(60, 8), vec![0, 8, 16, 25, 33, 42, 50, 59]);
        assert_eq!(evenly(10, 1), vec![0]);
    }
}
