//! PNG encoding of rendered passes, with fast deflate by default (PNG encoding otherwise dominates render time).

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};

use crate::manifest::render::PngCompression;

fn encoder(buf: &mut Vec<u8>, c: PngCompression) -> PngEncoder<&mut Vec<u8>> {
    let ct = match c {
        PngCompression::Fast => CompressionType::Fast,
        PngCompression::Default => CompressionType::Default,
        PngCompression::Best => CompressionType::Best,
    };
    PngEncoder::new_with_quality(buf, ct, FilterType::Adaptive)
}

/// RGBA8 PNG.
pub fn rgba_png(rgba: &[u8], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    let mut buf = Vec::new();
    encoder(&mut buf, c).write_image(rgba, w, h, ExtendedColorType::Rgba8).expect("BUG: buffer size matches the image");
    buf
}

/// 8-bit single-channel PNG (masks).
pub fn gray8_png(v: &[u8], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    let mut buf = Vec::new();
    encoder(&mut buf, c).write_image(v, w, h, ExtendedColorType::L8).expect("BUG: buffer size matches the image");
    buf
}

/// 16-bit single-channel PNG (instance ids).
pub fn gray16_png(v: &[u16], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    let mut buf = Vec::new();
    encoder(&mut buf, c)
        .write_image(bytemuck::cast_slice(v), w, h, ExtendedColorType::L16)
        .expect("BUG: buffer size matches the image");
    buf
}

/// RGB8 PNG (normals, images composited on a background).
pub fn rgb_png(rgb: &[u8], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    let mut buf = Vec::new();
    encoder(&mut buf, c).write_image(rgb, w, h, ExtendedColorType::Rgb8).expect("BUG: buffer size matches the image");
    buf
}

/// 16-bit single-channel PNG of depth in millimetres (0 = no depth; clamped at 65.535 m).
pub fn depth_mm_png(depth: &[f32], w: u32, h: u32, c: PngCompression) -> Vec<u8> {
    let mm: Vec<u16> = depth.iter().map(|d| (d * 1000.0).round().clamp(0.0, 65535.0) as u16).collect();
    gray16_png(&mm, w, h, c)
}
