//! Pixel filters: how a pixel's colour gathers the scene around it. `Box` (the default) averages the pixel's own
//! samples; `BlackmanHarris` is Cycles' default filter (Blender's Film ▸ Pixel Filter, width 1.5 px), which
//! spreads every pixel over its neighbours out to ±width pixels, so edges and fine texture look as soft as in the
//! Blender renders that NeRF-synthetic and the 6-DoF toolkit ship.
//!
//! The filter is applied to the resolved image (each pixel the mean of its samples, premultiplied, in linear
//! light), separably, as a kernel over whole pixels: its weights are Cycles' filter summed over each pixel's
//! sample positions, blended with the identity so that the kernel's spread plus the pixel's own (its samples'
//! box) equals the filter's spread over the samples. A pixel's samples are averaged before the kernel sees them,
//! so the exact filter (which weighs a neighbour's near samples more than its far ones) cannot be had without
//! every sample; matching the spread keeps the blur the same.

use glam::Vec4;
use rayon::prelude::*;

use crate::scene::material::Srgb8;

/// A pixel filter.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum PixelFilter {
    /// Each pixel is the mean of its own samples.
    #[default]
    Box,
    /// Cycles' Blackman-Harris filter reaching `width` pixels either side of the pixel's centre (Blender's
    /// "Width"; Cycles doubles the window of its formula, so the support is ±width).
    BlackmanHarris {
        /// Half the support, in pixels.
        width: f32,
    },
}

/// Widest `width` accepted: 10 px, Blender's own limit.
pub const MAX_WIDTH: f32 = 10.0;

impl PixelFilter {
    /// The kernel over whole pixels (offsets −r..=r) for `k` × `k` samples per pixel, or `None` for the box
    /// (nothing to do after resolving).
    pub fn kernel(&self, k: u32) -> Option<Vec<f32>> {
        let PixelFilter::BlackmanHarris { width } = *self else { return None };
        let width = width.clamp(1e-3, MAX_WIDTH) as f64;
        let k = k.max(1) as f64;
        let r = (width + 0.5).ceil() as i64;
        // Cycles' filter at every sample position of pixels −r..=r (offsets within a pixel from its centre).
        let offsets: Vec<f64> = (0..k as i64).map(|s| (s as f64 + 0.5) / k - 0.5).collect();
        let mass: Vec<f64> =
            (-r..=r).map(|d| offsets.iter().map(|o| blackman_harris(d as f64 + o, width)).sum()).collect();
        let total: f64 = mass.iter().sum();
        let shape: Vec<f64> = mass.iter().map(|m| m / total).collect();
        // Spreads (variances, px²): the filter's over the samples, the pixel's own box, and the shape's.
        let target: f64 = (-r..=r)
            .flat_map(|d| offsets.iter().map(move |o| d as f64 + o))
            .map(|x| blackman_harris(x, width) * x * x)
            .sum::<f64>()
            / total;
        let own = (k * k - 1.0) / (12.0 * k * k);
        let spread: f64 = (-r..=r).zip(&shape).map(|(d, w)| w * (d * d) as f64).sum();
        let t = if spread > 0.0 { ((target - own) / spread).clamp(0.0, 1.0) } else { 0.0 };
        let kernel: Vec<f32> =
            (-r..=r).zip(&shape).map(|(d, w)| (t * w + if d == 0 { 1.0 - t } else { 0.0 }) as f32).collect();
        Some(kernel)
    }
}

/// Cycles' Blackman-Harris window at `x` pixels from the centre, support ±`width` (Cycles evaluates its formula
/// over a window twice the user's width, centred).
fn blackman_harris(x: f64, width: f64) -> f64 {
    if x.abs() >= width {
        return 0.0;
    }
    let v = std::f64::consts::TAU * (x / (2.0 * width) + 0.5);
    0.35875 - 0.48829 * v.cos() + 0.14128 * (2.0 * v).cos() - 0.01168 * (3.0 * v).cos()
}

/// Filters `image` (`w` × `h` pixels, linear premultiplied RGBA, rows top first) with `kernel` along rows (in
/// place) then columns, and writes sRGB straight-alpha RGBA8 into `rgba`. Taps past the image's edge are left
/// out and the rest renormalized (there is nothing rendered there). Only the span of each row that anything
/// covers, widened by the kernel, is filtered: most of a dataset image is transparent.
pub fn apply(kernel: &[f32], image: &mut [Vec4], w: usize, h: usize, rgba: &mut [u8]) {
    let r = kernel.len() / 2;
    // Each row's covered span [first, last + 1) before filtering, then widened by the kernel.
    let spans: Vec<(usize, usize)> = image
        .par_chunks_mut(w)
        .map(|row| {
            let Some(first) = row.iter().position(|c| *c != Vec4::ZERO) else { return (0, 0) };
            let last = row.iter().rposition(|c| *c != Vec4::ZERO).unwrap_or(first);
            let (lo, hi) = (first.saturating_sub(r), (last + r + 1).min(w));
            let filtered: Vec<Vec4> = (lo..hi).map(|x| convolve(kernel, x, w, |j| row[j])).collect();
            row[lo..hi].copy_from_slice(&filtered);
            (lo, hi)
        })
        .collect();
    let image = &*image;
    let srgb = Srgb8::tables();
    rgba.par_chunks_mut(w * 4).enumerate().for_each(|(y, out)| {
        // The columns any row within reach covers.
        let near = &spans[y.saturating_sub(r)..(y + r + 1).min(h)];
        let lo = near.iter().filter(|s| s.1 > s.0).map(|s| s.0).min().unwrap_or(0);
        let hi = near.iter().map(|s| s.1).max().unwrap_or(0);
        for x in lo..hi {
            let c = convolve(kernel, y, h, |j| image[j * w + x]);
            let a8 = (c.w.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            if a8 == 0 {
                continue;
            }
            let rgb = c.truncate() / c.w;
            out[x * 4..x * 4 + 4].copy_from_slice(&[srgb.encode(rgb.x), srgb.encode(rgb.y), srgb.encode(rgb.z), a8]);
        }
    });
}

/// `kernel` (offsets −r..=r) at position `i` of a line of `n` values read by `read`, renormalized where the
/// line ends within reach.
#[inline]
fn convolve(kernel: &[f32], i: usize, n: usize, read: impl Fn(usize) -> Vec4) -> Vec4 {
    let r = kernel.len() / 2;
    if i >= r && i + r < n {
        return kernel.iter().enumerate().fold(Vec4::ZERO, |sum, (t, &c)| sum + read(i + t - r) * c);
    }
    let (lo, hi) = (i.saturating_sub(r), (i + r).min(n - 1));
    let (mut sum, mut weight) = (Vec4::ZERO, 0.0);
    for j in lo..=hi {
        let c = kernel[j + r - i];
        sum += read(j) * c;
        weight += c;
    }
    sum / weight
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kernel_is_normalized_symmetric_and_spreads_as_cycles_filter_does() {
        assert_eq!(PixelFilter::Box.kernel(2), None);
        for k in [1, 2, 3, 4] {
            for width in [0.5f32, 1.0, 1.5, 2.5] {
                let kern = PixelFilter::BlackmanHarris { width }.kernel(k).expect("a kernel");
                let r = kern.len() / 2;
                assert!((kern.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{k} {width}");
                assert!(kern.iter().all(|&c| c >= 0.0));
                for d in 0..=r {
                    assert_eq!(kern[r - d], kern[r + d]);
                }
                // The pixel's own box plus the kernel's spread is the filter's (where the box alone is narrower).
                let kf = k as f64;
                let own = (kf * kf - 1.0) / (12.0 * kf * kf);
                let spread: f64 = kern.iter().enumerate().map(|(i, &c)| c as f64 * (i as f64 - r as f64).powi(2)).sum();
                let (mut m, mut m2) = (0.0, 0.0);
                for i in -40..=40 {
                    for s in 0..k {
                        let x = i as f64 + (s as f64 + 0.5) / kf - 0.5;
                        m += blackman_harris(x, width as f64);
                        m2 += blackman_harris(x, width as f64) * x * x;
                    }
                }
                if m2 / m > own {
                    assert!(
                        (own + spread - m2 / m).abs() < 1e-4,
                        "k {k} width {width}: {} vs {}",
                        own + spread,
                        m2 / m
                    );
                }
            }
        }
        // Cycles' default at 2 × 2 samples: about a twentieth of the weight on each neighbour.
        let kern = PixelFilter::BlackmanHarris { width: 1.5 }.kernel(2).expect("a kernel");
        assert!(kern[kern.len() / 2 + 1] > 0.04 && kern[kern.len() / 2 + 1] < 0.07, "{kern:?}");
    }

    #[test]
    fn a_uniform_image_stays_uniform_and_an_edge_spreads_over_the_filters_width() {
        let kern = PixelFilter::BlackmanHarris { width: 1.5 }.kernel(2).expect("a kernel");
        let (w, h) = (9, 5);
        let grey = Vec4::new(0.2, 0.2, 0.2, 1.0);
        let mut out = vec![0; w * h * 4];
        apply(&kern, &mut vec![grey; w * h], w, h, &mut out);
        assert!(out.chunks(4).all(|p| p == [124, 124, 124, 255]), "{:?}", &out[..8]);
        // An opaque half beside a transparent one: alpha ramps over the pixels next to the edge, and colour
        // (straight) stays the surface's where anything covers.
        let mut image: Vec<Vec4> = (0..w * h).map(|i| if i % w < 4 { grey } else { Vec4::ZERO }).collect();
        let mut out = vec![0; w * h * 4];
        apply(&kern, &mut image, w, h, &mut out);
        let alpha: Vec<u8> = (0..w).map(|x| out[x * 4 + 3]).collect();
        assert_eq!(alpha[..3], [255, 255, 255]);
        assert!(alpha[3] < 255 && alpha[3] > 200 && alpha[4] > 0 && alpha[4] < 55, "{alpha:?}");
        assert_eq!(alpha[6..], [0, 0, 0]);
        assert_eq!(out[4 * 4..4 * 4 + 3], [124, 124, 124]);
    }
}
