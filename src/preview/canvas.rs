//! An opaque sRGB canvas the preview pictures are drawn on: filled rectangles, anti-aliased lines and dots,
//! images scaled in, and text set in an embedded font through `ab_glyph`. Drawing is plain sequential code, so
//! a picture's bytes depend only on what is drawn, in order.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};

/// DejaVu Sans, subset to printable ASCII and a few symbols (`vendor/DejaVu.LICENSE`): 26 KB in the binary.
const FONT: &[u8] = include_bytes!("vendor/DejaVuSans-subset.ttf");

/// The embedded font (parsing it reads its table directory only).
fn font() -> FontRef<'static> {
    FontRef::try_from_slice(FONT).expect("BUG: the embedded font parses")
}

/// An sRGB colour.
pub type Rgb = [u8; 3];

/// Borrowed RGB pixels, rows top first: what [`Canvas::blit`] draws and [`shrink`] scales.
#[derive(Clone, Copy)]
pub struct Pixels<'a> {
    /// The pixels.
    pub px: &'a [Rgb],
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
}

/// Borrowed straight-alpha sRGB RGBA bytes, rows top first: what [`Canvas::image_rgba`] scales in.
#[derive(Clone, Copy)]
pub struct RgbaPixels<'a> {
    /// The bytes, 4 per pixel.
    pub px: &'a [u8],
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
}

/// An opaque RGB picture, rows top first.
pub struct Canvas {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    px: Vec<Rgb>,
    font: FontRef<'static>,
}

impl Canvas {
    /// A `width` × `height` canvas filled with `background`.
    pub fn new(width: u32, height: u32, background: Rgb) -> Canvas {
        let font = font();
        Canvas { width, height, px: vec![background; width as usize * height as usize], font }
    }

    /// Blends `c` over pixel (x, y) with opacity `a` (0..=1); outside the canvas, nothing.
    pub fn blend(&mut self, x: i64, y: i64, c: Rgb, a: f32) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 || a <= 0.0 {
            return;
        }
        let p = &mut self.px[y as usize * self.width as usize + x as usize];
        let a = a.min(1.0);
        for k in 0..3 {
            p[k] = (p[k] as f32 + (c[k] as f32 - p[k] as f32) * a).round() as u8;
        }
    }

    /// Fills the rectangle at (x, y) of size w × h.
    pub fn fill(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        for yy in y.max(0)..(y + h).min(self.height as i64) {
            for xx in x.max(0)..(x + w).min(self.width as i64) {
                self.px[yy as usize * self.width as usize + xx as usize] = c;
            }
        }
    }

    /// The outline of the rectangle at (x, y) of size w × h, one pixel wide.
    pub fn frame(&mut self, x: i64, y: i64, w: i64, h: i64, c: Rgb) {
        self.fill(x, y, w, 1, c);
        self.fill(x, y + h - 1, w, 1, c);
        self.fill(x, y, 1, h, c);
        self.fill(x + w - 1, y, 1, h, c);
    }

    /// An anti-aliased line (Xiaolin Wu's), with opacity `a`.
    pub fn line(&mut self, (x0, y0): (f32, f32), (x1, y1): (f32, f32), c: Rgb, a: f32) {
        if !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite()) {
            return;
        }
        let steep = (y1 - y0).abs() > (x1 - x0).abs();
        let (mut x0, mut y0, mut x1, mut y1) = if steep { (y0, x0, y1, x1) } else { (x0, y0, x1, y1) };
        if x0 > x1 {
            std::mem::swap(&mut x0, &mut x1);
            std::mem::swap(&mut y0, &mut y1);
        }
        // Lines far outside the canvas are clipped to a generous range, so a wild projection costs little.
        let limit = 4.0 * (self.width.max(self.height) as f32);
        if x1 < -limit || x0 > limit {
            return;
        }
        let dx = x1 - x0;
        let gradient = if dx.abs() < 1e-6 { 1.0 } else { (y1 - y0) / dx };
        let start = x0.round().max(-limit);
        let end = x1.round().min(limit);
        let mut x = start;
        while x <= end {
            let y = y0 + gradient * (x - x0);
            let (yi, frac) = (y.floor(), y - y.floor());
            let (px, py) = (x as i64, yi as i64);
            if steep {
                self.blend(py, px, c, a * (1.0 - frac));
                self.blend(py + 1, px, c, a * frac);
            } else {
                self.blend(px, py, c, a * (1.0 - frac));
                self.blend(px, py + 1, c, a * frac);
            }
            x += 1.0;
        }
    }

    /// A filled dot of radius `r` pixels at (x, y), with opacity `a`.
    pub fn dot(&mut self, x: f32, y: f32, r: f32, c: Rgb, a: f32) {
        if !(x.is_finite() && y.is_finite()) {
            return;
        }
        let (lo_x, hi_x) = ((x - r - 1.0).floor() as i64, (x + r + 1.0).ceil() as i64);
        let (lo_y, hi_y) = ((y - r - 1.0).floor() as i64, (y + r + 1.0).ceil() as i64);
        for yy in lo_y..=hi_y {
            for xx in lo_x..=hi_x {
                let d = ((xx as f32 + 0.5 - x).powi(2) + (yy as f32 + 0.5 - y).powi(2)).sqrt();
                self.blend(xx, yy, c, a * (r + 0.5 - d).clamp(0.0, 1.0));
            }
        }
    }

    /// Draws `img` scaled into the rectangle at (x, y) of size tw × th over a checkerboard ([`shrink_rgba`]).
    pub fn image_rgba(&mut self, x: i64, y: i64, tw: u32, th: u32, img: RgbaPixels) {
        self.blit(x, y, Pixels { px: &shrink_rgba(img, tw, th), width: tw, height: th });
    }

    /// Copies `img` to (x, y), pixel for pixel (clipped to the canvas).
    pub fn blit(&mut self, x: i64, y: i64, img: Pixels) {
        for (i, c) in img.px.iter().take(img.width as usize * img.height as usize).enumerate() {
            let (tx, ty) = ((i as u32 % img.width) as i64, (i as u32 / img.width) as i64);
            self.blend(x + tx, y + ty, *c, 1.0);
        }
    }

    /// Sets `text` at (x, baseline y) in `size`-pixel type; returns the width it took.
    pub fn text(&mut self, x: f32, y: f32, size: f32, text: &str, c: Rgb) -> f32 {
        let font = self.font.clone();
        let scaled = font.as_scaled(PxScale::from(size));
        let mut pen = x;
        let mut last = None;
        for ch in text.chars() {
            let id = scaled.glyph_id(ch);
            if let Some(prev) = last {
                pen += scaled.kern(prev, id);
            }
            let glyph = id.with_scale_and_position(size, ab_glyph::point(pen, y));
            if let Some(outline) = font.outline_glyph(glyph) {
                let b = outline.px_bounds();
                outline.draw(|gx, gy, cov| self.blend(b.min.x as i64 + gx as i64, b.min.y as i64 + gy as i64, c, cov));
            }
            pen += scaled.h_advance(id);
            last = Some(id);
        }
        pen - x
    }

    /// The width `text` takes in `size`-pixel type (no canvas needed: a layout measures before it draws).
    pub fn text_width(size: f32, text: &str) -> f32 {
        let font = font();
        let scaled = font.as_scaled(PxScale::from(size));
        let mut w = 0.0;
        let mut last = None;
        for ch in text.chars() {
            let id = scaled.glyph_id(ch);
            if let Some(prev) = last {
                w += scaled.kern(prev, id);
            }
            w += scaled.h_advance(id);
            last = Some(id);
        }
        w
    }

    /// The picture as PNG.
    pub fn png(&self) -> Vec<u8> {
        let bytes: Vec<u8> = self.px.iter().flatten().copied().collect();
        crate::render::encode::rgb_png(&bytes, self.width, self.height, crate::render::encode::PngCompression::Fast)
    }
}

/// `img` scaled to tw × th by averaging the source pixels each target pixel covers (a box filter: thumbnails of
/// renders stay sharp and alias-free). Empty when either size is 0.
pub fn shrink(img: Pixels, tw: u32, th: u32) -> Vec<Rgb> {
    boxes(img.px, img.width, img.height, tw, th, |_, _, n, rows| {
        let mut sum = [0u32; 3];
        for p in rows.flatten() {
            for k in 0..3 {
                sum[k] += p[k] as u32;
            }
        }
        sum.map(|s| ((s + n / 2) / n) as u8)
    })
}

/// Straight-alpha `img` scaled to tw × th over a checkerboard (so transparency shows): the covered source pixels
/// are averaged premultiplied (a transparent pixel adds no colour), then composited at the target's
/// resolution. Empty when either size is 0.
pub fn shrink_rgba(img: RgbaPixels, tw: u32, th: u32) -> Vec<Rgb> {
    let px: &[[u8; 4]] = bytemuck::cast_slice(&img.px[..img.px.len() / 4 * 4]);
    boxes(px, img.width, img.height, tw, th, |tx, ty, n, rows| {
        // Premultiplied sums, in units of 1/255.
        let (mut sum, mut alpha) = ([0u32; 3], 0u32);
        for p in rows.flatten() {
            let a = p[3] as u32;
            sum[0] += p[0] as u32 * a;
            sum[1] += p[1] as u32 * a;
            sum[2] += p[2] as u32 * a;
            alpha += a;
        }
        let bg = checker(tx, ty);
        [0, 1, 2].map(|k| ((sum[k] + bg[k] as u32 * (255 * n - alpha)) as f32 / (255 * n) as f32).round() as u8)
    })
}

/// Depth (millimetres, 0 = nothing) scaled to tw × th: per target pixel, the mean of the covered source depths
/// and the share of source pixels covered.
pub fn shrink_depth(depth: &[u16], w: u32, h: u32, tw: u32, th: u32) -> Vec<(f32, f32)> {
    boxes(depth, w, h, tw, th, |_, _, n, rows| {
        let (mut sum, mut covered) = (0u64, 0u32);
        for &v in rows.flatten().filter(|&&v| v > 0) {
            sum += v as u64;
            covered += 1;
        }
        (if covered > 0 { sum as f32 / covered as f32 } else { 0.0 }, covered as f32 / n as f32)
    })
}

/// The box-scaling walk the shrinks share: for each target pixel of tw × th (rows top first), `cell(tx, ty, n,
/// rows)` with the `n` source pixels it covers as row slices. Empty when either size is 0 or `src` is short.
fn boxes<P, T>(
    src: &[P],
    w: u32,
    h: u32,
    tw: u32,
    th: u32,
    mut cell: impl FnMut(u32, u32, u32, &mut dyn Iterator<Item = &[P]>) -> T,
) -> Vec<T> {
    if w == 0 || h == 0 || tw == 0 || th == 0 || src.len() < w as usize * h as usize {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(tw as usize * th as usize);
    for ty in 0..th {
        let (sy0, sy1) = span(ty, th, h);
        for tx in 0..tw {
            let (sx0, sx1) = span(tx, tw, w);
            let n = ((sy1 - sy0) * (sx1 - sx0)).max(1);
            let row = |sy: u32| &src[sy as usize * w as usize + sx0 as usize..sy as usize * w as usize + sx1 as usize];
            out.push(cell(tx, ty, n, &mut (sy0..sy1).map(row)));
        }
    }
    out
}

/// The source rows (or columns) `[a, b)` that target row `t` of `n` covers in a source of `m`; never empty.
fn span(t: u32, n: u32, m: u32) -> (u32, u32) {
    let a = (t as u64 * m as u64 / n as u64) as u32;
    let b = (((t as u64 + 1) * m as u64).div_ceil(n as u64) as u32).max(a + 1).min(m);
    (a.min(m - 1), b)
}

/// The checkerboard transparent pixels are drawn over, at (x, y) of a picture: cells of 8 pixels.
pub fn checker(x: u32, y: u32) -> Rgb {
    if ((x / 8) + (y / 8)).is_multiple_of(2) {
        [200, 200, 200]
    } else {
        [150, 150, 150]
    }
}

/// A perceptual colour map (a few stops of viridis) for `t` in 0..=1.
pub fn viridis(t: f32) -> Rgb {
    const STOPS: [[f32; 3]; 5] =
        [[68.0, 1.0, 84.0], [59.0, 82.0, 139.0], [33.0, 145.0, 140.0], [94.0, 201.0, 98.0], [253.0, 231.0, 37.0]];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * (STOPS.len() - 1) as f32;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f32;
    [0, 1, 2].map(|k| (STOPS[i][k] + (STOPS[i + 1][k] - STOPS[i][k]) * f).round() as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_puts_ink_where_it_is_set_and_nowhere_else() {
        let mut c = Canvas::new(120, 30, [0, 0, 0]);
        let w = c.text(4.0, 20.0, 16.0, "view 3", [255, 255, 255]);
        assert!(w > 30.0 && w < 80.0, "{w}");
        assert!((w - Canvas::text_width(16.0, "view 3")).abs() < 1e-3);
        let inked: Vec<usize> = (0..c.px.len()).filter(|&i| c.px[i][0] > 0).collect();
        assert!(inked.len() > 40, "{}", inked.len());
        assert!(inked.iter().all(|&i| (i % 120) as f32 <= 4.0 + w + 1.0 && i / 120 <= 22));
    }

    #[test]
    fn box_scaling_keeps_the_mean() {
        let img: Vec<Rgb> = (0..64 * 64).map(|i| if (i % 64 + i / 64) % 2 == 0 { [255; 3] } else { [0; 3] }).collect();
        let mut c = Canvas::new(8, 8, [7, 7, 7]);
        c.blit(0, 0, Pixels { px: &shrink(Pixels { px: &img, width: 64, height: 64 }, 8, 8), width: 8, height: 8 });
        assert!(c.px.iter().all(|p| p[0] == 128), "{:?}", &c.px[..4]);
    }

    #[test]
    fn transparent_pixels_add_no_colour_when_scaled() {
        // Half the source opaque red, half transparent (with a green that must not bleed in).
        let img: Vec<u8> =
            (0..16 * 16).flat_map(|i| if i % 2 == 0 { [255, 0, 0, 255] } else { [0, 255, 0, 0] }).collect();
        let mut c = Canvas::new(2, 2, [0, 0, 0]);
        c.image_rgba(0, 0, 2, 2, RgbaPixels { px: &img, width: 16, height: 16 });
        // Half red over the light checker cell.
        assert_eq!(c.px[0], [228, 100, 100]);
    }

    #[test]
    fn shrunk_depth_averages_only_what_is_covered() {
        // Left half at 1000 mm and 3000 mm, right half empty.
        let d: Vec<u16> = (0..16).map(|i| if i % 4 < 2 { 1000 + 2000 * (i / 8) as u16 } else { 0 }).collect();
        assert_eq!(shrink_depth(&d, 4, 4, 1, 1), [(2000.0, 0.5)]);
        assert_eq!(shrink_depth(&d, 4, 4, 2, 1), [(2000.0, 1.0), (0.0, 0.0)]);
    }

    #[test]
    fn lines_reach_both_ends() {
        let mut c = Canvas::new(50, 50, [0, 0, 0]);
        c.line((5.0, 5.0), (44.0, 30.0), [255, 0, 0], 1.0);
        assert!(c.px[5 * 50 + 5][0] > 100 && c.px[30 * 50 + 44][0] > 100);
        assert_eq!(c.px[40 * 50 + 5], [0, 0, 0]);
    }
}
