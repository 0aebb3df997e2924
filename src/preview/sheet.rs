//! Contact sheets: one PNG per split, a grid of thumbnails answering "does it look right?" at a glance. Views
//! run down and frames across for multi-view video (so time runs left to right and a wrong time axis shows);
//! monocular and random splits are shown time-major. Each cell is the RGBA render over a checkerboard (so
//! transparency and crops show), with depth and mask below when those passes exist, and a label.

use super::canvas::{shrink, shrink_depth, shrink_rgba, viridis, Canvas, Pixels, Rgb, RgbaPixels};

/// Thumbnail width in pixels.
const THUMB: u32 = 160;

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

/// A cell's thumbnails: each render decoded and shrunk in one task, so a sheet holds thumbnails, not renders
/// (32 renders at 4K would be gigabytes).
struct Thumbs {
    rgba: Vec<Rgb>,
    depth: Option<DepthThumb>,
    mask: Option<Vec<Rgb>>,
}

/// A depth thumbnail: mean millimetres and coverage per pixel, and the render's nearest and farthest depth.
type DepthThumb = (Vec<(f32, f32)>, u16, u16);

/// The size of `c`'s RGBA render (from its PNG header).
fn size(c: &Cell) -> Result<(u32, u32), Error> {
    let bad = || Error { view: c.view, frame: c.frame, what: "the RGBA render" };
    let r = image::ImageReader::new(std::io::Cursor::new(&c.rgba)).with_guessed_format().map_err(|_| bad())?;
    r.into_dimensions().map_err(|_| bad())
}

/// `c`'s thumbnails at tw × th (depth and mask at half size).
fn thumbs(c: &Cell, tw: u32, th: u32) -> Result<Thumbs, Error> {
    let read = |b: &[u8], what| image::load_from_memory(b).map_err(|_| Error { view: c.view, frame: c.frame, what });
    let (hw, hh) = (tw / 2, th / 2);
    let rgba = read(&c.rgba, "the RGBA render")?.into_rgba8();
    let (w, h) = rgba.dimensions();
    let rgba = shrink_rgba(RgbaPixels { px: rgba.as_raw(), width: w, height: h }, tw, th);
    let depth = match &c.depth {
        Some(b) => {
            let d = read(b, "the depth render")?.into_luma16();
            let (w, h) = d.dimensions();
            let covered = d.as_raw().iter().copied().filter(|&v| v > 0);
            let (lo, hi) = covered.fold((u16::MAX, 0u16), |(lo, hi), v| (lo.min(v), hi.max(v)));
            Some((shrink_depth(d.as_raw(), w, h, hw, hh), lo, hi))
        }
        None => None,
    };
    let mask = match &c.mask {
        Some(b) => {
            let m = read(b, "the mask render")?.into_luma8();
            let (w, h) = m.dimensions();
            let px: Vec<Rgb> = m.as_raw().iter().map(|&v| [v, v, v]).collect();
            Some(shrink(Pixels { px: &px, width: w, height: h }, tw - hw, hh))
        }
        None => None,
    };
    Ok(Thumbs { rgba, depth, mask })
}

/// Draws the sheet of `cells` (in reading order) with `columns` columns; `title` heads it.
pub fn draw(title: &str, cells: &[Cell], columns: usize) -> Result<Vec<u8>, Error> {
    use rayon::prelude::*;
    let (w, h) = match cells.first() {
        Some(c) => size(c)?,
        None => (1, 1),
    };
    let tw = THUMB;
    let th = ((THUMB as u64 * h.max(1) as u64 / w.max(1) as u64) as u32).clamp(8, 2 * THUMB);
    // Decoding and shrinking are most of the work: in parallel (the drawing after it is sequential, so bytes do
    // not depend on threads).
    let thumbs: Vec<Thumbs> = cells.par_iter().map(|c| thumbs(c, tw, th)).collect::<Result<_, _>>()?;
    let extras = thumbs.first().is_some_and(|c| c.depth.is_some() || c.mask.is_some());
    let strip = if extras { th / 2 } else { 0 };
    // Depth is coloured over one range for the whole sheet, so depths compare across thumbnails.
    let (lo, hi) = thumbs
        .iter()
        .filter_map(|t| t.depth.as_ref())
        .filter(|(_, lo, hi)| lo <= hi)
        .fold((u16::MAX, 0u16), |(a, b), (_, lo, hi)| (a.min(*lo), b.max(*hi)));
    let note = (extras && hi > 0).then(|| {
        let mask = if thumbs.first().is_some_and(|c| c.mask.is_some()) { " · mask" } else { "" };
        format!("below each: depth {:.2}–{:.2} m (near bright){mask}", lo as f64 / 1000.0, hi as f64 / 1000.0)
    });

    let (pad, label) = (8u32, 16u32);
    let cell_h = th + strip + label;
    let columns = columns.max(1);
    let rows = cells.len().div_ceil(columns).max(1);
    let width = pad + columns as u32 * (tw + pad);
    // The note goes right of the title where both fit, else on a line of its own below it (a sheet of one or
    // two thumbnails is narrower than the two).
    let note_w = note.as_deref().map_or(0.0, |n| Canvas::text_width(12.0, n));
    let beside = pad as f32 + Canvas::text_width(15.0, title) + 16.0 + note_w + pad as f32 <= width as f32;
    let head = if beside { 34 } else { 50 };
    let height = head + rows as u32 * (cell_h + pad) + pad;
    let mut c = Canvas::new(width, height, [32, 32, 36]);
    c.text(pad as f32, 22.0, 15.0, title, [235, 235, 235]);
    if let Some(note) = &note {
        let (x, y) = if beside { (width as f32 - pad as f32 - note_w, 22.0) } else { (pad as f32, 40.0) };
        c.text(x, y, 12.0, note, [170, 170, 170]);
    }

    for (k, (cell, t)) in cells.iter().zip(&thumbs).enumerate() {
        let (col, row) = ((k % columns) as u32, (k / columns) as u32);
        let (x, y) = ((pad + col * (tw + pad)) as i64, (head + row * (cell_h + pad)) as i64);
        c.blit(x, y, Pixels { px: &t.rgba, width: tw, height: th });
        if extras {
            // Depth and mask side by side at half size (the thumbnail's aspect kept).
            let half = tw / 2;
            if let Some((d, _, _)) = &t.depth {
                let span = (hi.saturating_sub(lo)).max(1) as f32;
                // Near is bright: 1 at the nearest depth on the sheet, 0 at the farthest; background black, edges
                // blended by coverage.
                let px: Vec<Rgb> = d
                    .iter()
                    .map(|&(mm, cover)| {
                        let v = viridis(1.0 - (mm - lo as f32).max(0.0) / span);
                        v.map(|c| (c as f32 * cover).round() as u8)
                    })
                    .collect();
                c.blit(x, y + th as i64, Pixels { px: &px, width: half, height: strip });
            }
            if let Some(m) = &t.mask {
                c.blit(x + half as i64, y + th as i64, Pixels { px: m, width: tw - half, height: strip });
            }
        }
        c.frame(x - 1, y - 1, tw as i64 + 2, (th + strip) as i64 + 2, [70, 70, 78]);
        let text = format!("v{} · f{} · t {:.2}", cell.view, cell.frame, cell.time);
        c.text(x as f32 + 2.0, (y + (th + strip + label) as i64 - 3) as f32, 12.0, &text, [200, 200, 200]);
    }
    Ok(c.png())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png<P: image::PixelWithColorType>(img: &image::ImageBuffer<P, Vec<P::Subpixel>>) -> Vec<u8>
    where
        [P::Subpixel]: image::EncodableLayout,
    {
        let mut out = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png).unwrap();
        out
    }

    /// The depth note sits right of the title when both fit, and on a line of its own below it on a sheet too
    /// narrow for both (one or two thumbnails): they overlapped there.
    #[test]
    fn the_depth_note_never_overlaps_the_title() {
        let rgba = png(&image::RgbaImage::from_pixel(64, 64, image::Rgba([200, 30, 30, 255])));
        let depth = png(&image::ImageBuffer::<image::Luma<u16>, _>::from_pixel(64, 64, image::Luma([3000u16])));
        let cell = || Cell { view: 0, frame: 0, time: 0.0, rgba: rgba.clone(), depth: Some(depth.clone()), mask: None };
        let title = "a dataset · split `train` · 2 images, 2 shown";
        let size = |cells: usize| {
            let sheet = draw(title, &(0..cells).map(|_| cell()).collect::<Vec<_>>(), cells).unwrap();
            let sheet = image::load_from_memory(&sheet).unwrap();
            (sheet.width(), sheet.height())
        };
        // One row each: two thumbnails are too narrow for the title and the note side by side, eight are not.
        let ((w2, h2), (w8, h8)) = (size(2), size(8));
        // The narrow sheet's header is one text line taller than the wide one's, its cells the same.
        assert_eq!(h2, h8 + 16, "narrow {w2}×{h2}, wide {w8}×{h8}");
    }
}
