//! Environment lighting: an HDR equirectangular map (Radiance `.hdr` or OpenEXR), mapped exactly as Blender's
//! Environment Texture node maps it, and prefiltered once per map ([`prefilter()`], a cached action of the build)
//! into what shading reads: diffuse irradiance as 9 spherical-harmonic coefficients, and the map convolved
//! with the GGX lobe at a few roughnesses (the split-sum approximation's first factor).

use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use crate::scene::texture::floor;

mod prefilter;

pub use prefilter::{prefilter, prefilter_here, Prefiltered};

/// Largest map side read (a 16k map is 1.6 GB of f32 texels; environment maps are 1k–8k wide).
pub const MAX_SIDE: u32 = 16384;

/// Roughnesses of the prefiltered specular levels: `i / (LEVELS − 1)`.
pub const LEVELS: usize = 6;

/// Version of the prefiltered data's bytes: bump when prefiltering changes.
pub const SALT: &str = "environment 5";

/// Version of the built-in studio map ([`studio`]), which stands for a map's content key: bump when it changes.
pub const STUDIO: &str = "studio 2";

/// What can go wrong reading an environment map.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file cannot be read.
    #[error("{}: cannot read", path.display())]
    Io {
        /// The map.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a map vvgen reads.
    #[error("{}: {message}", path.display())]
    Format {
        /// The map.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A prefiltered blob is damaged (a damaged cache).
    #[error("damaged prefiltered environment: {0}")]
    Damaged(&'static str),
}

/// An equirectangular map: linear RGB radiance, rows top (+Z) first, columns as Blender's (see [`dir_to_uv`]).
#[derive(Debug, Clone, PartialEq)]
pub struct EnvMap {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Linear RGB, `width × height`, rows top first.
    pub texels: Vec<Vec3>,
}

/// Whether `path` names a map format vvgen reads (by extension).
pub fn is_map_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("hdr") || e.eq_ignore_ascii_case("exr"))
}

/// The map's size from its header alone (what `vvgen check` reads): an error for what [`load`] would refuse.
pub fn header(path: &Path) -> Result<(u32, u32), Error> {
    let bad = |message: String| Error::Format { path: path.to_path_buf(), message };
    let (w, h) = if is_exr(path) {
        let meta = exr::meta::MetaData::read_from_file(path, false)
            .map_err(|e| bad(format!("not a readable OpenEXR file: {e}")))?;
        let layer = meta.headers.first().ok_or_else(|| bad("an OpenEXR file without layers".into()))?;
        let size = layer.layer_size;
        (size.width() as u32, size.height() as u32)
    } else {
        let file = std::fs::File::open(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
        let dec = image::codecs::hdr::HdrDecoder::new(std::io::BufReader::new(file))
            .map_err(|e| bad(format!("not a readable Radiance HDR file: {e}")))?;
        let m = dec.metadata();
        (m.width, m.height)
    };
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        return Err(bad(format!("{w}×{h} texels: an environment map is 1..={MAX_SIDE} texels a side")));
    }
    Ok((w, h))
}

fn is_exr(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

/// Reads an equirectangular map: OpenEXR (its RGB channels, any sample type and compression the `exr` crate
/// reads) or Radiance RGBE. Non-finite or negative texels become 0 (a NaN would spread through every lookup).
pub fn load(path: &Path) -> Result<EnvMap, Error> {
    let (w, h) = header(path)?;
    let bad = |message: String| Error::Format { path: path.to_path_buf(), message };
    let mut texels = vec![Vec3::ZERO; w as usize * h as usize];
    if is_exr(path) {
        use exr::prelude::*;
        let image = read_first_rgba_layer_from_file(
            path,
            |res, _| (res.width(), vec![Vec3::ZERO; res.width() * res.height()]),
            |(width, px): &mut (usize, Vec<Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * *width + pos.x()] = Vec3::new(r, g, b);
            },
        )
        .map_err(|e| bad(format!("cannot decode: {e}")))?;
        let (width, px) = image.layer_data.channel_data.pixels;
        if width != w as usize || px.len() != texels.len() {
            return Err(bad("the layer's size differs from its header's".into()));
        }
        texels = px;
    } else {
        let file = std::fs::File::open(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
        let dec = image::codecs::hdr::HdrDecoder::new(std::io::BufReader::new(file))
            .map_err(|e| bad(format!("cannot decode: {e}")))?;
        let img = image::DynamicImage::from_decoder(dec).map_err(|e| bad(format!("cannot decode: {e}")))?.into_rgb32f();
        for (t, p) in texels.iter_mut().zip(img.pixels()) {
            *t = Vec3::new(p[0], p[1], p[2]);
        }
    }
    for t in &mut texels {
        *t = Vec3::new(clean(t.x), clean(t.y), clean(t.z));
    }
    Ok(EnvMap { width: w, height: h, texels })
}

fn clean(v: f32) -> f32 {
    if v.is_finite() && v > 0.0 {
        v
    } else {
        0.0
    }
}

/// The built-in neutral "studio" environment (for `shading = "pbr"` without an `[environment]` map): a soft
/// overhead sky fading to a darker floor, grey, with a broad brighter key from the front-left (+X −Y, above),
/// so forms read without one harsh highlight. Radiance 0.2 below to 0.65 overhead, 2 in the key.
pub fn studio() -> EnvMap {
    let (w, h) = (256u32, 128u32);
    let key = Vec3::new(0.6, -0.5, 0.62).normalize();
    let texels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let d = uv_to_dir(Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32));
            // Exposed so that a white diffuse surface facing up or into the key reflects 0.80 (a side 0.55,
            // the underside 0.20): at 1.46, as it was, lit subjects of plain white or grey clipped.
            let sky = 0.2 + 0.45 * smoothstep(-0.3, 0.6, d.z);
            let lobe = d.dot(key).max(0.0).powi(8) * 1.4;
            Vec3::splat(sky + lobe)
        })
        .collect();
    EnvMap { width: w, height: h, texels }
}

pub(super) fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Blender's equirectangular mapping (Cycles' `direction_to_equirectangular`): a world direction (+Z up) →
/// `(u, t)` with `u` across (0 at the left edge, +X at the centre, +Y at a quarter) and `t` down from the top
/// row (0 is +Z). Blender's `v` is `1 − t` (its images are stored bottom row first).
#[inline]
pub fn dir_to_uv(d: Vec3) -> Vec2 {
    let len = d.length();
    if len == 0.0 {
        return Vec2::ZERO;
    }
    let u = 0.5 - atan2(d.y, d.x) / (2.0 * PI);
    let t = acos((d.z / len).clamp(-1.0, 1.0)) / PI;
    Vec2::new(u, t)
}

/// `y.atan2(x)` within 1.3e-7 rad (a ten-thousandth of a texel of a 16k map) from a polynomial: the
/// environment is read this way several times per lit pixel, and libm's `atan2f` was a twentieth of a lit
/// render. Arithmetic only, so the same on every machine. (0, 0) gives 0.
#[inline]
fn atan2(y: f32, x: f32) -> f32 {
    // atan on [0, 1] as x·P(x²), P fitted to it (iteratively reweighted least squares, evaluated in f32).
    const P: [f32; 8] = [
        0.999_999_34,
        -0.333_298_62,
        0.199_465_95,
        -0.139_087_8,
        0.096_425_95,
        -0.055_917_9,
        0.021_866_9,
        -0.004_055_675,
    ];
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    if hi == 0.0 {
        return 0.0;
    }
    let a = lo / hi;
    let a2 = a * a;
    let mut r = a * P.iter().rev().fold(0.0, |acc, &c| acc * a2 + c);
    if ay > ax {
        r = 0.5 * PI - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 {
        -r
    } else {
        r
    }
}

/// `x.acos()` for x in [−1, 1] within 2.4e-7 rad: Abramowitz and Stegun's 4.4.46, √(1 − |x|)·P(|x|), reflected
/// for negative x (see [`atan2`] for why not libm).
#[inline]
fn acos(x: f32) -> f32 {
    const P: [f32; 8] = [
        std::f32::consts::FRAC_PI_2,
        -0.214_598_8,
        0.088_978_99,
        -0.050_174_303,
        0.030_891_88,
        -0.017_088_126,
        0.006_670_09,
        -0.001_262_491_1,
    ];
    let a = x.abs();
    let r = (1.0 - a).max(0.0).sqrt() * P.iter().rev().fold(0.0, |acc, &c| acc * a + c);
    if x < 0.0 {
        PI - r
    } else {
        r
    }
}

/// The inverse of [`dir_to_uv`].
#[inline]
pub fn uv_to_dir(uv: Vec2) -> Vec3 {
    let phi = PI - 2.0 * PI * uv.x;
    let theta = PI * uv.y;
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new(st * cp, st * sp, ct)
}

impl EnvMap {
    /// Bilinear lookup at `(u, t)`, wrapping across and clamping down.
    pub fn lookup(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let fx = uv.x * w as f32 - 0.5;
        let fy = (uv.y * h as f32 - 0.5).clamp(0.0, (h - 1) as f32);
        let (x0, y0) = (floor(fx), floor(fy));
        let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
        // The two columns wrapped and the two rows clamped once, not per texel (a wrap is a division, and this
        // is read several times per lit pixel).
        let xa = if (0..w).contains(&x0) { x0 } else { x0.rem_euclid(w) };
        let xb = if xa + 1 == w { 0 } else { xa + 1 };
        let (ya, yb) = (y0.clamp(0, h - 1) * w, (y0 + 1).clamp(0, h - 1) * w);
        // In SIMD lanes: the same products and sums per channel, so the same bits.
        let at = |row: i64, x: i64| glam::Vec3A::from(self.texels[(row + x) as usize]);
        let top = at(ya, xa).lerp(at(ya, xb), tx);
        let bottom = at(yb, xa).lerp(at(yb, xb), tx);
        top.lerp(bottom, ty).into()
    }

    /// Radiance arriving from world direction `d`.
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        self.lookup(dir_to_uv(d))
    }

    /// Half the size (rounding up), box-filtered in 2×2 texels weighted by their solid angle.
    fn half(&self) -> EnvMap {
        let (w, h) = (self.width.div_ceil(2).max(1), self.height.div_ceil(2).max(1));
        let mut texels = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let (mut sum, mut wsum) = (Vec3::ZERO, 0.0);
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (sx, sy) = ((2 * x + dx).min(self.width - 1), (2 * y + dy).min(self.height - 1));
                    let s = row_solid_angle(sy, self.height);
                    sum += self.texels[(sy * self.width + sx) as usize] * s;
                    wsum += s;
                }
                texels.push(if wsum > 0.0 { sum / wsum } else { Vec3::ZERO });
            }
        }
        EnvMap { width: w, height: h, texels }
    }
}

/// The solid angle of one texel of row `y` of an equirectangular map `h` rows high, per texel column unit
/// (times 2π / width for a texel): the exact band area, so the rows of a map sum to exactly 2 (· 2π = 4π).
fn row_solid_angle(y: u32, h: u32) -> f32 {
    let t0 = PI * y as f32 / h as f32;
    let t1 = PI * (y + 1) as f32 / h as f32;
    t0.cos() - t1.cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mappings_trigonometry_is_libms_within_a_millionth() {
        // Every quadrant and octant boundary, both signs of zero, and a dense sweep of angles and heights.
        let special = [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0), (1.0, 1.0), (-1.0, -1.0), (1e-30, -1.0)];
        let sweep = (0..100_000).map(|i| {
            let a = i as f32 * 0.000_062_9 - 3.2;
            (a.sin() * 3.7, a.cos() * 3.7)
        });
        for (y, x) in special.into_iter().chain(sweep) {
            let (got, want) = (atan2(y, x), y.atan2(x));
            assert!(
                (got - want).abs() < 1e-6 || (got.abs() - PI).abs() < 1e-6 && (want.abs() - PI).abs() < 1e-6,
                "atan2({y}, {x}): {got} vs {want}"
            );
        }
        assert_eq!(atan2(0.0, 0.0), 0.0);
        for i in 0..=100_000 {
            let x = i as f32 / 50_000.0 - 1.0;
            assert!((acos(x) - x.acos()).abs() < 1e-6, "acos({x}): {} vs {}", acos(x), x.acos());
        }
    }

    #[test]
    fn blenders_mapping_round_trips_and_puts_axes_where_blender_does() {
        // +X at the centre column, +Y a quarter across, −Y three quarters, +Z the top row.
        let c = |d: Vec3| dir_to_uv(d);
        assert!((c(Vec3::X) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((c(Vec3::Y) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((c(-Vec3::Y) - Vec2::new(0.75, 0.5)).length() < 1e-6);
        assert!(c(Vec3::Z).y.abs() < 1e-6 && (c(-Vec3::Z).y - 1.0).abs() < 1e-6);
        for i in 0..200 {
            let uv = Vec2::new((i as f32 * 0.618).fract(), 0.02 + 0.96 * (i as f32 * 0.377).fract());
            let back = dir_to_uv(uv_to_dir(uv));
            // u wraps: 0 and 1 are the same column edge.
            let du = (back.x - uv.x + 0.5).rem_euclid(1.0) - 0.5;
            assert!(du.abs() < 1e-4 && (back.y - uv.y).abs() < 1e-4, "{uv} → {back}");
        }
    }
}
