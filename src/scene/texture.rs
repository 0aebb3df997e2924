//! Textures as the renderer and the point sampler read them: RGBA8 as decoded from the file, filtered in linear
//! light (bilinear within a level, trilinear across a mip chain under a screen footprint), with glTF's wrap modes
//! and `KHR_texture_transform`.

use std::sync::{LazyLock, OnceLock};

use glam::{Vec2, Vec3, Vec4};

use super::material::{linear_to_srgb8, SRGB8_TO_LINEAR};

/// A decoded texture, RGBA8, shared by every material that uses it.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// RGBA8 rows, top row first.
    pub rgba: Vec<u8>,
    /// Whether the bytes are sRGB-encoded (base colour and emissive textures are; data textures are not).
    pub srgb: bool,
    /// Levels 1.. of the mip chain, built on the renderer's first minified lookup (the point sampler reads
    /// level 0 only and never pays for it).
    mips: OnceLock<Vec<Texture>>,
    /// The tables that decode its bytes, looked up once here: each lookup of a lazily built table checks that it
    /// is built, and a trilinear lookup decodes 32 values.
    tables: Tables,
}

/// A mip level to read: trilinear between `level` and the next, by `t` in [0, 1).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Lod {
    /// The finer level (0 is the texture itself).
    level: usize,
    /// The weight of the coarser one.
    t: f32,
}

/// Texture wrap mode (glTF sampler).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// REPEAT (10497), the default.
    Repeat,
    /// CLAMP_TO_EDGE (33071).
    Clamp,
    /// MIRRORED_REPEAT (33648).
    Mirror,
}

/// A material's use of a texture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureRef {
    /// Index into the scene's textures.
    pub texture: u32,
    /// Which TEXCOORD_n set.
    pub tex_coord: u32,
    /// Wrap along u.
    pub wrap_s: Wrap,
    /// Wrap along v.
    pub wrap_t: Wrap,
    /// Magnification filter is NEAREST.
    pub nearest: bool,
    /// KHR_texture_transform as a 2×3 affine map of uv (columns x, y, translation).
    pub transform: Option<[Vec2; 3]>,
}

impl TextureRef {
    /// A use of texture `texture` with glTF's default sampler: TEXCOORD_0, REPEAT both ways, linear filtering,
    /// no transform.
    pub fn new(texture: u32) -> TextureRef {
        TextureRef {
            texture,
            tex_coord: 0,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            nearest: false,
            transform: None,
        }
    }

    /// Applies the texture transform to a uv.
    #[inline]
    pub fn map(&self, uv: Vec2) -> Vec2 {
        match &self.transform {
            Some([x, y, t]) => *x * uv.x + *y * uv.y + *t,
            None => uv,
        }
    }
}

/// Byte → [0, 1] (`v / 255`), tabulated: texel reads divide no more.
static UNORM8: LazyLock<[f32; 256]> = LazyLock::new(|| std::array::from_fn(|i| i as f32 / 255.0));

impl Texture {
    /// A texture of `width × height` RGBA8 texels, top row first.
    pub fn new(width: u32, height: u32, rgba: Vec<u8>, srgb: bool) -> Texture {
        let unorm: &'static [f32; 256] = &UNORM8;
        let tables = Tables { unorm, colour: if srgb { &SRGB8_TO_LINEAR } else { unorm } };
        Texture { width, height, rgba, srgb, mips: OnceLock::new(), tables }
    }

    /// Levels 1.. of the mip chain: each halves the previous level (rounding down, at least 1) by averaging
    /// 2×2 texels in linear light (a non-power-of-two level drops its odd last row/column: a small, documented
    /// approximation), down to 1×1.
    fn mips(&self) -> &[Texture] {
        self.mips.get_or_init(|| {
            let mut levels: Vec<Texture> = Vec::new();
            while let Some(next) = levels.last().unwrap_or(self).half() {
                levels.push(next);
            }
            levels
        })
    }

    /// The next mip level, or `None` at 1×1.
    fn half(&self) -> Option<Texture> {
        if self.width <= 1 && self.height <= 1 {
            return None;
        }
        let (w, h) = ((self.width / 2).max(1), (self.height / 2).max(1));
        let (sx, sy) = (u32::from(self.width > 1), u32::from(self.height > 1));
        let enc = |v: f32| if self.srgb { linear_to_srgb8(v) } else { (v * 255.0).round().clamp(0.0, 255.0) as u8 };
        let mut rgba = Vec::with_capacity((w * h * 4) as usize);
        for y in 0..h {
            for x in 0..w {
                let (x0, y0) = (x * 2, y * 2);
                let sum = self.texel(x0, y0)
                    + self.texel(x0 + sx, y0)
                    + self.texel(x0, y0 + sy)
                    + self.texel(x0 + sx, y0 + sy);
                let c = sum * 0.25;
                rgba.extend_from_slice(&[enc(c.x), enc(c.y), enc(c.z), (c.w * 255.0).round().clamp(0.0, 255.0) as u8]);
            }
        }
        Some(Texture::new(w, h, rgba, self.srgb))
    }

    /// Linear RGBA of texel (x, y) (sRGB decoded when the texture is sRGB).
    #[inline]
    pub fn texel(&self, x: u32, y: u32) -> Vec4 {
        let i = ((y * self.width + x) * 4) as usize;
        self.tables().decode::<true>(&self.rgba[i..i + 4])
    }

    /// The tables that decode this texture's bytes (and its mip levels').
    #[inline]
    fn tables(&self) -> Tables {
        self.tables
    }

    /// Samples at `uv` (glTF: origin top-left) with the reference's wrap modes and filter; bilinear in linear light,
    /// from the full-resolution level.
    pub fn sample(&self, r: &TextureRef, uv: Vec2) -> Vec4 {
        self.filter::<true>(r, r.map(uv), self.tables())
    }

    /// Samples with a screen footprint: `duv_dx`, `duv_dy` are the uv's derivatives across the footprint (a
    /// pixel, or a sample for per-sample lookups). When it covers more than one texel the lookup is trilinear
    /// between the two mip levels around log2 of its size in texels (`Texture::lod`); magnified and `nearest`
    /// lookups read level 0.
    pub fn sample_footprint(&self, r: &TextureRef, uv: Vec2, duv_dx: Vec2, duv_dy: Vec2) -> Vec4 {
        self.footprint::<true>(r, uv, duv_dx, duv_dy)
    }

    /// [`Texture::sample_footprint`]'s colour alone, for what ignores alpha (opaque surfaces' base colour, data
    /// textures): the same values, without decoding the eight texels' alpha.
    pub fn sample_footprint_rgb(&self, r: &TextureRef, uv: Vec2, duv_dx: Vec2, duv_dy: Vec2) -> Vec3 {
        self.footprint::<false>(r, uv, duv_dx, duv_dy).truncate()
    }

    /// [`Texture::sample_footprint`], with alpha decoded only when `ALPHA` (else it is meaningless): the four
    /// lanes are filtered apart, so the colour is the same either way.
    #[inline(always)]
    fn footprint<const ALPHA: bool>(&self, r: &TextureRef, uv: Vec2, duv_dx: Vec2, duv_dy: Vec2) -> Vec4 {
        let lod = self.lod(r, duv_dx, duv_dy);
        let uv = r.map(uv);
        // Every level decodes through the same tables.
        let d = self.tables();
        if lod.level == 0 && lod.t == 0.0 {
            return self.filter::<ALPHA>(r, uv, d);
        }
        let mips = self.mips();
        // Level i is the texture itself for 0, else mips[i − 1]; past the 1×1 level (or for a 1×1 texture,
        // which has no mips) the coarsest level answers alone.
        let level = |i: usize| if i == 0 { self } else { &mips[i - 1] };
        let i = lod.level.min(mips.len());
        let a = level(i).filter::<ALPHA>(r, uv, d);
        if lod.t == 0.0 || i == mips.len() {
            return a;
        }
        a.lerp(level(i + 1).filter::<ALPHA>(r, uv, d), lod.t)
    }

    /// The mip level [`Texture::sample_footprint`] reads for a footprint. Inlined into both of its callers (an
    /// outlined call cost 10 instructions a lookup, 0.6 % of a textured render).
    #[inline(always)]
    fn lod(&self, r: &TextureRef, duv_dx: Vec2, duv_dy: Vec2) -> Lod {
        let (dx, dy) = match &r.transform {
            Some([x, y, _]) => (*x * duv_dx.x + *y * duv_dx.y, *x * duv_dy.x + *y * duv_dy.y),
            None => (duv_dx, duv_dy),
        };
        let size = Vec2::new(self.width as f32, self.height as f32);
        // The footprint's area in texels: the level where it covers one texel, as if it were square (the
        // geometric mean of its axes). OpenGL's isotropic rule takes the longer axis instead, which blurs
        // oblique surfaces; this one matched Blender's (anisotropic) texturing more closely (benches/fidelity.py).
        // A sliver's area says little of its length: the anisotropy is capped at 16 (the square's side is at
        // least a quarter of the longer axis), so an edge-on surface still reads a coarse enough level.
        let (a, b) = (dx * size, dy * size);
        let rho2 = (a.x * b.y - a.y * b.x).abs().max(a.length_squared().max(b.length_squared()) / 16.0);
        // Magnified, degenerate (NaN from a sliver) or nearest: level 0.
        if r.nearest || rho2.is_nan() || rho2 <= 1.0 {
            return Lod { level: 0, t: 0.0 };
        }
        level_of(rho2)
    }

    /// Bilinear (or nearest) lookup of already transformed `uv` in this level. Inlined into its callers: a
    /// trilinear lookup makes two, and a call each cost a third of its instructions (registers saved and
    /// restored, the checks below repeated).
    #[inline(always)]
    fn filter<const ALPHA: bool>(&self, r: &TextureRef, uv: Vec2, d: Tables) -> Vec4 {
        let (w, h) = (self.width as f32, self.height as f32);
        let (fx, fy) = (uv.x * w - 0.5, uv.y * h - 0.5);
        // All four texels inside (almost every lookup): `floor(fx)` is in 0..width − 1 exactly when `fx` is in
        // [0, width − 1) (NaN is in neither; an empty or one-texel-wide level has no such `fx`), and there the
        // floor is the truncation, which fits an i32 (a cheaper conversion than to u32). No wrapping, and each
        // row's two texels are one 8-byte read decoded through tables looked up once (this is the texturing
        // loop's innermost step).
        let inside = |f: f32, n: u32| f >= 0.0 && f < n.saturating_sub(1) as f32;
        if !r.nearest && inside(fx, self.width) && inside(fy, self.height) {
            let (x0, y0) = truncate2(fx, fy);
            let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
            let row = self.width as usize * 4;
            let i = y0 as usize * row + x0 as usize * 4;
            let texels = &self.rgba[i..i + row + 8];
            let (a, b) = (&texels[..8], &texels[row..]);
            let top = d.decode::<ALPHA>(&a[..4]).lerp(d.decode::<ALPHA>(&a[4..8]), tx);
            let bottom = d.decode::<ALPHA>(&b[..4]).lerp(d.decode::<ALPHA>(&b[4..8]), tx);
            return top.lerp(bottom, ty);
        }
        self.filter_edge(r, uv)
    }

    /// [`Texture::filter`] where it wraps or clamps (or reads nearest, or the level is empty).
    #[inline(never)]
    fn filter_edge(&self, r: &TextureRef, uv: Vec2) -> Vec4 {
        if self.width == 0 || self.height == 0 {
            return Vec4::ONE;
        }
        let (w, h) = (self.width as f32, self.height as f32);
        if r.nearest {
            let x = wrap(r.wrap_s, floor(uv.x * w), self.width);
            let y = wrap(r.wrap_t, floor(uv.y * h), self.height);
            return self.texel(x, y);
        }
        let (fx, fy) = (uv.x * w - 0.5, uv.y * h - 0.5);
        let (x0, y0) = (floor(fx), floor(fy));
        let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
        let xs = [wrap(r.wrap_s, x0, self.width), wrap(r.wrap_s, x0.saturating_add(1), self.width)];
        let ys = [wrap(r.wrap_t, y0, self.height), wrap(r.wrap_t, y0.saturating_add(1), self.height)];
        let top = self.texel(xs[0], ys[0]).lerp(self.texel(xs[1], ys[0]), tx);
        let bottom = self.texel(xs[0], ys[1]).lerp(self.texel(xs[1], ys[1]), tx);
        top.lerp(bottom, ty)
    }
}

/// The mip level of a footprint of `rho2` > 1 texels (squared side), as `0.5 · log2(rho2)` split into its floor
/// and the rest. Inlined into [`Texture::lod`].
#[inline(always)]
fn level_of(rho2: f32) -> Lod {
    // rho2 > 1, so 0 ≤ lod ≤ 64 (at rho2 = +∞). Its floor is half rho2's binary exponent, rounded down (lod is
    // half of that exponent plus log2 of a mantissa in [1, 2)), unless the series' rounding carried the
    // mantissa's log up to 1. So the level is read off the exponent, and the texel reads that depend on it
    // need not wait for the series (its dependent chain was a fifth of a lookup's time; the reads miss the
    // cache): the series only weighs the two levels, and checks the guess. `lod − level` is exact (Sterbenz),
    // so it is in [0, 1) exactly when `level` is the floor, and then the result is what the floor gives.
    let lod = 0.5 * log2(rho2);
    let level = ((rho2.to_bits() >> 23) - 127) >> 1;
    let t = lod - level as f32;
    if !(0.0..1.0).contains(&t) {
        // Not folded into a select: that would make the reads wait for the series again.
        return carried(lod);
    }
    Lod { level: level as usize, t }
}

/// [`level_of`] where the series' rounding carried `lod` to the next integer: its floor, the slow way.
#[cold]
#[inline(never)]
fn carried(lod: f32) -> Lod {
    let level = lod as u32;
    Lod { level: level as usize, t: lod - level as f32 }
}

/// The tables that turn a texel's bytes into linear floats: alpha is always `v / 255`, colour is sRGB-decoded
/// for colour textures.
#[derive(Clone, Copy)]
struct Tables {
    unorm: &'static [f32; 256],
    colour: &'static [f32; 256],
}

impl std::fmt::Debug for Tables {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let srgb = std::ptr::eq(self.colour, &*SRGB8_TO_LINEAR);
        f.debug_struct("Tables").field("srgb", &srgb).finish_non_exhaustive()
    }
}

impl PartialEq for Tables {
    /// The same tables (there are two, both static).
    fn eq(&self, o: &Tables) -> bool {
        std::ptr::eq(self.unorm, o.unorm) && std::ptr::eq(self.colour, o.colour)
    }
}

impl Tables {
    /// Linear RGBA of one texel's four bytes (alpha 0 unless `ALPHA`).
    #[inline]
    fn decode<const ALPHA: bool>(self, t: &[u8]) -> Vec4 {
        let c = self.colour;
        let alpha = if ALPHA { self.unorm[t[3] as usize] } else { 0.0 };
        Vec4::new(c[t[0] as usize], c[t[1] as usize], c[t[2] as usize], alpha)
    }
}

/// `(a as i32, b as i32)` for `a`, `b` in [0, 2³¹): in one SSE2 conversion, without the checks `as` makes for
/// values out of range (the texel lookup's innermost step; its callers have bounded both).
#[inline(always)]
fn truncate2(a: f32, b: f32) -> (i32, i32) {
    debug_assert!((0.0..2_147_483_648.0).contains(&a) && (0.0..2_147_483_648.0).contains(&b));
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvtsi128_si32, _mm_cvttps_epi32, _mm_setr_ps, _mm_srli_si128};
        // SAFETY: SSE2 is part of x86-64's baseline, so these instructions exist on every machine this runs on.
        unsafe {
            let v = _mm_cvttps_epi32(_mm_setr_ps(a, b, 0.0, 0.0));
            (_mm_cvtsi128_si32(v), _mm_cvtsi128_si32(_mm_srli_si128::<4>(v)))
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        (a as i32, b as i32)
    }
}

/// log2 of a positive normal `x` to within 1e-6, from its exponent and an atanh series for the mantissa: only
/// IEEE arithmetic, so the mip level is the same on every machine (libm's `log2f` is not bound to be), and no
/// libm call in the texturing loop.
#[inline]
fn log2(x: f32) -> f32 {
    let bits = x.to_bits();
    let e = ((bits >> 23) & 0xff) as i32 - 127;
    // The mantissa m in [1, 2): ln m = 2·atanh(s) = 2(s + s³/3 + s⁵/5 + …), s = (m − 1)/(m + 1) < 1/3.
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let series = s * (1.0 + s2 * (1.0 / 3.0 + s2 * (1.0 / 5.0 + s2 * (1.0 / 7.0 + s2 * (1.0 / 9.0 + s2 / 11.0)))));
    e as f32 + 2.0 * std::f32::consts::LOG2_E * series
}

/// `x.floor() as i64` without the libm call baseline x86-64 makes of `floor` (no SSE4.1 `roundss`); this is in
/// the innermost loops of texturing and of shadow and environment lookups. Saturates like `as` for huge values.
#[inline]
pub fn floor(x: f32) -> i64 {
    let t = x as i64;
    // Saturating: below -2^63, `t` is already i64::MIN and must stay there.
    t.saturating_sub(i64::from((t as f32) > x))
}

/// Maps an integer texel coordinate into `0..n` by a wrap mode.
#[inline]
pub fn wrap(mode: Wrap, i: i64, n: u32) -> u32 {
    if (0..n as i64).contains(&i) {
        // Inside the texture every mode is the identity; skip the divisions.
        return i as u32;
    }
    let n = n as i64;
    (match mode {
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Mirror => {
            let p = i.rem_euclid(2 * n);
            if p < n {
                p
            } else {
                2 * n - 1 - p
            }
        }
    }) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log2_is_within_a_millionth() {
        for i in 0..100_000 {
            let x = 1.0 + i as f32 * 0.37;
            assert!((log2(x) - x.log2()).abs() < 1e-6 * x.log2().max(1.0), "{x}: {} vs {}", log2(x), x.log2());
        }
        assert_eq!(log2(1.0), 0.0);
        assert_eq!(log2(1024.0), 10.0);
    }

    #[test]
    fn the_level_read_off_the_exponent_is_the_floor_of_the_lod() {
        let floor = |rho2: f32| {
            let lod = 0.5 * log2(rho2);
            Lod { level: lod as usize, t: lod - (lod as u32) as f32 }
        };
        // Around every power of two (where the exponent's guess and the series' rounding can disagree), a sweep,
        // and the far end.
        let mut probes: Vec<f32> = (1..127)
            .flat_map(|e| {
                let p = 2f32.powi(e).to_bits();
                (0..64).flat_map(move |k| [f32::from_bits(p - k), f32::from_bits(p + k)])
            })
            .collect();
        probes.extend((0..100_000).map(|i| 1.0 + i as f32 * 0.731));
        probes.extend([f32::from_bits(1f32.to_bits() + 1), f32::MAX, f32::INFINITY]);
        for rho2 in probes.into_iter().filter(|&r| r > 1.0) {
            assert_eq!(level_of(rho2), floor(rho2), "{rho2:e}");
        }
    }

    #[test]
    fn minified_lookups_past_the_last_level_read_the_coarsest() {
        let r = TextureRef::new(0);
        // A 1×1 texture has no mip levels; a 2×2 one has one. Footprints of 1 and 1000 texels per step.
        let one = Texture::new(1, 1, vec![255, 0, 0, 255], true);
        let two = Texture::new(2, 2, [[255, 255, 255, 255], [0, 0, 0, 255]].repeat(2).concat(), true);
        for d in [1.5, 1000.0] {
            let (dx, dy) = (Vec2::new(d, 0.0), Vec2::new(0.0, d));
            assert_eq!(one.sample_footprint(&r, Vec2::splat(0.3), dx, dy), Vec4::new(1.0, 0.0, 0.0, 1.0));
            let grey = two.sample_footprint(&r, Vec2::splat(0.3), dx, dy);
            assert!(grey.x > 0.2 && grey.x < 0.8, "{grey}");
        }
    }

    #[test]
    fn the_level_is_the_footprints_area_with_anisotropy_capped_at_16() {
        let r = TextureRef::new(0);
        let t = Texture::new(256, 256, vec![0; 256 * 256 * 4], true);
        let texels = |x: f32| x / 256.0;
        let lod = |dx: Vec2, dy: Vec2| t.lod(&r, dx.map(texels), dy.map(texels));
        // A square of 4 texels a side: level 2, exactly.
        assert_eq!(lod(Vec2::new(4.0, 0.0), Vec2::new(0.0, 4.0)), Lod { level: 2, t: 0.0 });
        // 16 × 1 texels has the area of a 4-texel square, rotated or not (the longer axis alone would say 4).
        assert_eq!(lod(Vec2::new(16.0, 0.0), Vec2::new(0.0, 1.0)), Lod { level: 2, t: 0.0 });
        let l = lod(Vec2::new(16.0, 16.0) / 2f32.sqrt(), Vec2::new(-1.0, 1.0) / 2f32.sqrt());
        assert!(l.level == 2 && l.t < 1e-5 || l.level == 1 && l.t > 1.0 - 1e-5, "{l:?}");
        // A sliver 64 texels long and 0 wide reads as a square of 16 (64 / 4): level 4.
        assert_eq!(lod(Vec2::new(64.0, 0.0), Vec2::ZERO), Lod { level: 4, t: 0.0 });
        // Magnified: level 0.
        assert_eq!(lod(Vec2::new(0.5, 0.0), Vec2::new(0.0, 0.5)), Lod { level: 0, t: 0.0 });
    }
}
