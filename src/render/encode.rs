//! PNG encoding of rendered passes, with fast deflate by default (PNG encoding otherwise dominates render time).

/// PNG deflate effort (and the EXR compression that goes with it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PngCompression {
    /// Fast deflate: PNG encoding otherwise dominates render time (the default).
    Fast,
    /// The encoder's default.
    Default,
    /// Smallest files, slowest.
    Best,
}

/// The space normals are written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NormalSpace {
    /// World axes.
    World,
    /// Camera axes (OpenGL: +X right, +Y up, +Z back).
    Camera,
}

/// How rendered passes become files: the settings of encoding, apart from those of rendering.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Encoding {
    /// PNG deflate effort (and EXR compression).
    pub png: PngCompression,
    /// The space normals are written in.
    pub normal_space: NormalSpace,
    /// Also write depth as float OpenEXR.
    pub depth_exr: bool,
    /// Also write normals as float OpenEXR.
    pub normal_exr: bool,
}

/// Version of the PNG encodings (deflate effort and row filters per [`PngCompression`]): every action that
/// writes a PNG keys it, since a change here moves the files' bytes (not their pixels).
pub const PNG_SALT: &str = "png 2: fast filters up (colour) and paeth (grey)";

/// A PNG of `data` (rows top first, 16-bit samples big-endian as PNG stores them) written by the png crate
/// directly: the image crate would copy every 16-bit sample once more to swap its bytes, and gives the same
/// bytes otherwise. `Fast` writes one row filter instead of trying all five per row (adaptive): on seed-scale
/// renders (800², 10 % covered) Up encodes RGBA in 0.60 ms instead of 1.35 ms for 5 % larger files, and Paeth
/// 16-bit depth in 1.05 ms instead of 1.23 ms at the same size (Up there: 0.84 ms, 15 % larger). `Default` and
/// `Best` favour size and keep the adaptive choice.
fn png(data: &[u8], w: u32, h: u32, colour: png::ColorType, depth: png::BitDepth, c: PngCompression) -> Vec<u8> {
    let (compression, filter) = match c {
        PngCompression::Fast => (
            png::Compression::Fast,
            if colour == png::ColorType::Grayscale { png::Filter::Paeth } else { png::Filter::Up },
        ),
        PngCompression::Default => (png::Compression::Balanced, png::Filter::Adaptive),
        PngCompression::Best => (png::Compression::High, png::Filter::Adaptive),
    };
    let mut buf = Vec::new();
    let mut e = png::Encoder::new(&mut buf, w, h);
    e.set_color(colour);
    e.set_depth(depth);
    e.set_compression(compression);
    e.set_filter(filter);
    let mut writer = e.write_header().expect("BUG: writing to memory");
    writer.write_image_data(data).expect("BUG: buffer size matches the image");
    writer.finish().expect("BUG: writing to memory");
    buf
}

/// RGBA8 PNG.
pub fn rgba_png(rgba: &[u8], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    png(rgba, w, h, png::ColorType::Rgba, png::BitDepth::Eight, c)
}

/// 8-bit single-channel PNG (masks).
pub fn gray8_png(v: &[u8], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    png(v, w, h, png::ColorType::Grayscale, png::BitDepth::Eight, c)
}

/// 16-bit single-channel PNG (instance ids).
pub fn gray16_png(v: &[u16], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    gray16(v, |v| v, w, h, c)
}

/// 16-bit single-channel PNG of `samples` (row-major, top row first) as `sample` turns them into 16 bits,
/// written big-endian as PNG stores them. `sample` must map the zero value to 0: runs of zeros (the background of
/// a dataset image, nine tenths of it) are left as the buffer starts, and the rest is converted in a loop the
/// compiler vectorizes.
fn gray16<S: Copy + Default + PartialEq>(
    samples: &[S],
    sample: impl Fn(S) -> u16,
    w: u32,
    h: u32,
    c: PngCompression,
) -> Vec<u8> {
    const RUN: usize = 16;
    let mut be = vec![0u8; samples.len() * 2];
    for (out, run) in be.chunks_mut(2 * RUN).zip(samples.chunks(RUN)) {
        // One branch per run (`&` of the comparisons rather than `all`, which would branch per sample).
        if run.iter().fold(true, |zero, &v| zero & (v == S::default())) {
            continue;
        }
        for (out, &v) in out.chunks_exact_mut(2).zip(run) {
            out.copy_from_slice(&sample(v).to_be_bytes());
        }
    }
    png(&be, w, h, png::ColorType::Grayscale, png::BitDepth::Sixteen, c)
}

/// RGB8 PNG (normals, images composited on a background).
pub fn rgb_png(rgb: &[u8], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    png(rgb, w, h, png::ColorType::Rgb, png::BitDepth::Eight, c)
}

/// A single-part, scan-line, 32-bit float OpenEXR with the given channels (each `w·h` values, row-major, top
/// row first). Written in increasing line order on one thread, so the bytes are reproducible; RLE with
/// `png_compression = "fast"` (cheap, and the empty background compresses), ZIP otherwise.
pub fn f32_exr(channels: &[(&str, &[f32])], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    use exr::prelude::*;
    let list: Vec<AnyChannel<FlatSamples>> =
        channels.iter().map(|(name, v)| AnyChannel::new(*name, FlatSamples::F32(v.to_vec()))).collect();
    let compression = match c {
        PngCompression::Fast => Compression::RLE,
        PngCompression::Default | PngCompression::Best => Compression::ZIP16,
    };
    let encoding = exr::prelude::Encoding { compression, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing };
    let layer =
        Layer::new((w as usize, h as usize), LayerAttributes::default(), encoding, AnyChannels::sort(list.into()));
    let mut buf = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer).write().non_parallel().to_buffered(&mut buf).expect("BUG: an in-memory EXR writes");
    buf.into_inner()
}

/// Depth `d` in metres as whole millimetres, rounded half away from zero and clamped to u16 (NaN → 0):
/// `(d · 1000).round()` exactly, without the libm call `round` is on baseline x86-64 and without branches or
/// saturating float-to-integer casts, so that a frame's worth vectorizes (this runs once per pixel).
#[inline]
#[allow(clippy::manual_clamp)] // `clamp` keeps NaN, which must become 0
fn millimetres(d: f32) -> u16 {
    const TWO_23: f32 = 8_388_608.0;
    // `max` and `min` return the number when the other side is NaN: NaN becomes 0.
    let x = (d * 1000.0).max(0.0).min(65535.0);
    // Below 2²³, adding 2²³ leaves x rounded to an integer (ties to even) in the low mantissa bits; the floor is
    // one less where that rounded up. x − ⌊x⌋ is exact, so the half-way test is too.
    let m = x + TWO_23;
    let nearest = m - TWO_23;
    let above = nearest > x;
    let floor = nearest - f32::from(u8::from(above));
    let half_up = x - floor >= 0.5;
    ((m.to_bits() & 0x7f_ffff) - u32::from(above) + u32::from(half_up)) as u16
}

/// 16-bit single-channel PNG of depth in millimetres (0 = no depth; clamped at 65.535 m).
pub fn depth_mm_png(depth: &[f32], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    gray16(depth, millimetres, w, h, c)
}

#[cfg(test)]
mod tests {
    use super::millimetres;

    #[test]
    fn every_compression_decodes_to_the_pixels_it_was_given() {
        use super::{gray16_png, gray8_png, rgb_png, rgba_png, PngCompression};
        // An odd size and bytes that vary in every direction, so each row filter has something to predict.
        let (w, h) = (37u32, 23u32);
        let bytes = |n: u32| -> Vec<u8> { (0..n).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8).collect() };
        let depth: Vec<u16> = (0..w * h).map(|i| (i * 977 % 65_521) as u16).collect();
        for c in [PngCompression::Fast, PngCompression::Default, PngCompression::Best] {
            let decode = |png: Vec<u8>| image::load_from_memory_with_format(&png, image::ImageFormat::Png).unwrap();
            let rgba = bytes(w * h * 4);
            assert_eq!(decode(rgba_png(&rgba, w, h, c)).into_rgba8().into_raw(), rgba, "{c:?}");
            let rgb = bytes(w * h * 3);
            assert_eq!(decode(rgb_png(&rgb, w, h, c)).into_rgb8().into_raw(), rgb, "{c:?}");
            let grey = bytes(w * h);
            assert_eq!(decode(gray8_png(&grey, w, h, c)).into_luma8().into_raw(), grey, "{c:?}");
            assert_eq!(decode(gray16_png(&depth, w, h, c)).into_luma16().into_raw(), depth, "{c:?}");
        }
    }

    #[test]
    fn depth_runs_of_zeros_and_values_decode_to_their_millimetres() {
        use super::{depth_mm_png, PngCompression};
        // Runs of background (0, −0) of every length around the 16-sample runs, and depths in between.
        let (w, h) = (53u32, 7u32);
        let depth: Vec<f32> = (0..w * h)
            .map(|i| match (i / 11) % 3 {
                0 => 0.0,
                1 if i % 2 == 0 => -0.0,
                _ => 0.25 + i as f32 * 0.0137,
            })
            .collect();
        let png = depth_mm_png(&depth, w, h, PngCompression::Fast);
        let got = image::load_from_memory_with_format(&png, image::ImageFormat::Png).unwrap().into_luma16().into_raw();
        let want: Vec<u16> = depth.iter().map(|&d| millimetres(d)).collect();
        assert_eq!(got, want);
        assert!(want.iter().filter(|&&v| v != 0).count() > 100);
    }

    #[test]
    fn millimetres_round_as_libm_does() {
        // Every 61st f32 from 0 to past the clamp (half-way cases included by the special values below).
        let top = 70.0f32.to_bits();
        let specials = [0.0005f32, 0.0015, 0.0025, 65.5345, 65.5355, 1e9, -1.0, -0.0, f32::NAN, f32::INFINITY];
        for d in (0..top).step_by(61).map(f32::from_bits).chain(specials) {
            let want = (d * 1000.0).round().clamp(0.0, 65535.0) as u16;
            assert_eq!(millimetres(d), want, "{d}");
        }
    }
}
