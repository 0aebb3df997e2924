//! Meshopt-compressed buffer views (`EXT_meshopt_compression`: gltfpack's `-c`, glTF-Transform's `meshopt`; and
//! its Khronos successor `KHR_meshopt_compression`, gltfpack's `-ce khr`, which adds a colour filter and a newer
//! vertex codec). Each view is decoded once, when the file loads, by meshoptimizer itself (the `meshopt` crate
//! vendors it), its filter undone, into a buffer of its own that the view is pointed at; accessors, animations and
//! images then read it as any view. The buffer a compressed view names as its own is a fallback: it is not read,
//! whether or not it has data (gltfpack's `-cf` writes a plain copy there for loaders without the extension).

use gltf::json::validation::USize64;
use gltf::json::Index;
use serde_json::Value;

/// The extension's names, older first.
pub(super) const NAMES: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// Decoded bytes one view may declare. The vertex codec stores a group of 16 equal bytes in 2 header bits (64
/// to 1, its most), the index codecs spend at least a byte per triangle or index; so a claim past this many bytes
/// per compressed byte, or past 2 GiB, is a hostile count, not a mesh, and what a file makes vvgen allocate stays
/// within a fixed multiple of its size.
const MAX_RATIO: u64 = 128;
const MAX_DECODED_BYTES: u64 = 2 << 30;

/// The extension's object on a buffer view.
#[derive(serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Compressed {
    buffer: usize,
    #[serde(default)]
    byte_offset: u64,
    byte_length: u64,
    byte_stride: u64,
    count: u64,
    mode: String,
    #[serde(default)]
    filter: Option<String>,
}

/// Whether buffer `b` is a compressed views' fallback (the extension's `fallback`), which is not read.
pub(super) fn is_fallback(b: &gltf::Buffer<'_>) -> bool {
    NAMES.iter().any(|n| b.extension_value(n).and_then(|e| e.get("fallback")).and_then(Value::as_bool) == Some(true))
}

/// Decodes every meshopt-compressed view of `doc`, whose buffers are `buffers` (one is appended, holding the
/// decoded views), and returns the document with those views pointed at it. A document without the extension is
/// returned as it is.
pub(super) fn decode(doc: gltf::Document, buffers: &mut Vec<Vec<u8>>) -> Result<gltf::Document, String> {
    let compressed = |v: &gltf::buffer::View<'_>| NAMES.iter().any(|n| v.extension_value(n).is_some());
    if !doc.views().any(|v| compressed(&v)) {
        return Ok(doc);
    }
    let mut root = doc.into_json();
    // The buffer the decoded views go to, appended after them.
    let (buffer, mut bytes) = (Index::new(root.buffers.len() as u32), Vec::new());
    for (i, view) in root.buffer_views.iter_mut().enumerate() {
        let found = view.extensions.as_ref().and_then(|e| NAMES.iter().find_map(|&n| Some((n, e.others.get(n)?))));
        let Some((name, ext)) = found else { continue };
        let at = format!("bufferViews[{i}].extensions.{name}");
        let ext: Compressed = serde_json::from_value(ext.clone())
            .map_err(|e| format!("{at}: {e} (it needs `buffer`, `byteLength`, `byteStride`, `count` and `mode`)"))?;
        let data = decode_view(&ext, buffers).map_err(|e| format!("{at}: {e}"))?;
        if (data.len() as u64) < view.byte_length.0 {
            return Err(format!(
                "{at}: decodes to {} bytes ({} × {}), where the view declares {}",
                data.len(),
                ext.count,
                ext.byte_stride,
                view.byte_length.0
            ));
        }
        bytes.resize(bytes.len().next_multiple_of(4), 0);
        (view.buffer, view.byte_offset) = (buffer, Some(USize64::from(bytes.len())));
        bytes.extend_from_slice(&data);
    }
    super::uri::push_buffer(&mut root, buffers, bytes, "decoded meshopt views");
    Ok(gltf::Document::from_json_without_validation(root))
}

/// A filter's decoding, in place on one element.
type Unfilter = fn(&mut [u8]);

/// How a view's elements were encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Attributes,
    Triangles,
    Indices,
}

impl Compressed {
    /// Its mode and the filter to undo (none for NONE), checked against its stride and count: the codecs' own
    /// preconditions (meshoptimizer asserts them), so that a file cannot break them.
    fn layout(&self) -> Result<(Mode, Option<Unfilter>), String> {
        let (count, stride) = (self.count, self.byte_stride);
        let (mode, fits) = match self.mode.as_str() {
            "ATTRIBUTES" => (Mode::Attributes, stride % 4 == 0 && (4..=256).contains(&stride)),
            "TRIANGLES" => (Mode::Triangles, matches!(stride, 2 | 4) && count % 3 == 0),
            "INDICES" => (Mode::Indices, matches!(stride, 2 | 4)),
            other => return Err(format!("mode `{other}` is none of ATTRIBUTES, TRIANGLES and INDICES")),
        };
        if !fits {
            return Err(format!(
                "{count} elements of {stride} bytes cannot be {} (attributes take 4 to 256 bytes in fours; indices 2 \
                 or 4, triangles in threes)",
                self.mode
            ));
        }
        let filter = self.filter.as_deref().unwrap_or("NONE");
        let (unfilter, fits): (Option<Unfilter>, bool) = match filter {
            "NONE" => (None, true),
            "OCTAHEDRAL" => (Some(octahedral), matches!(stride, 4 | 8)),
            "COLOR" => (Some(color), matches!(stride, 4 | 8)),
            "QUATERNION" => (Some(quaternion), stride == 8),
            "EXPONENTIAL" => (Some(exponential), true),
            other => {
                return Err(format!("filter `{other}` is none of NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL and COLOR"))
            }
        };
        if !fits || (unfilter.is_some() && mode != Mode::Attributes) {
            return Err(format!("filter {filter} does not apply to {} of {stride}-byte elements", self.mode));
        }
        Ok((mode, unfilter))
    }
}

/// The bytes of one compressed view (`count` elements of `byteStride` bytes), its filter undone.
fn decode_view(ext: &Compressed, buffers: &[Vec<u8>]) -> Result<Vec<u8>, String> {
    let source = buffers.get(ext.buffer).ok_or_else(|| format!("buffer {} does not exist", ext.buffer))?;
    let end = ext.byte_offset.checked_add(ext.byte_length).filter(|&e| e <= source.len() as u64);
    let end = end.ok_or_else(|| format!("its data runs past buffer {} ({} bytes)", ext.buffer, source.len()))?;
    let source = &source[ext.byte_offset as usize..end as usize];
    let (mode, unfilter) = ext.layout()?;
    let (count, stride) = (ext.count, ext.byte_stride);
    let size = count.saturating_mul(stride);
    if size > MAX_DECODED_BYTES.min(MAX_RATIO.saturating_mul(source.len() as u64 + 16)) {
        return Err(format!(
            "declares {count} elements of {stride} bytes from {} compressed bytes: past what meshopt's codecs can \
             expand that far (vvgen's limit is {MAX_RATIO} times, at most {MAX_DECODED_BYTES} bytes)",
            source.len()
        ));
    }
    if count == 0 {
        return Ok(Vec::new());
    }
    let (count, stride) = (count as usize, stride as usize);
    // Words: the index decoders store 16- and 32-bit integers through typed pointers, which must be aligned.
    let mut words = vec![0u32; (count * stride).div_ceil(4)];
    let out: &mut [u8] = bytemuck::cast_slice_mut(&mut words);
    let (dst, src) = (out.as_mut_ptr().cast(), source.as_ptr());
    // SAFETY: `out` holds at least `count × stride` bytes, what each decoder writes at most; `source` is a live
    // slice of `source.len()` bytes, which the decoders read within (meshoptimizer: "safe to use for untrusted
    // input"); their preconditions on sizes and counts were checked by `layout`.
    let code = unsafe {
        match mode {
            Mode::Attributes => meshopt::ffi::meshopt_decodeVertexBuffer(dst, count, stride, src, source.len()),
            Mode::Triangles => meshopt::ffi::meshopt_decodeIndexBuffer(dst, count, stride, src, source.len()),
            Mode::Indices => meshopt::ffi::meshopt_decodeIndexSequence(dst, count, stride, src, source.len()),
        }
    };
    if code != 0 {
        return Err(format!("its data does not decode (meshoptimizer's code {code}): it is damaged or truncated"));
    }
    let mut out = bytemuck::cast_slice::<u32, u8>(&words)[..count * stride].to_vec();
    if let Some(unfilter) = unfilter {
        out.chunks_exact_mut(stride).for_each(unfilter);
    }
    Ok(out)
}

// The filters: the extension's formulas, in the arithmetic of meshoptimizer's WebAssembly decoder (the one three.js
// and glTF-Transform run), so that a file decodes here bit for bit as it does there. The library's native filters
// are not called: its SSE path scales 8-bit octahedral vectors and colours by an approximate reciprocal (square
// root) and its NEON path fuses multiply-adds (the spec allows their one-unit errors), so their last bits differ
// between machines, and a dataset must come out the same on every machine. These are plain IEEE operations.

/// Component `i` of an element of four 8-bit (`wide` false) or 16-bit components, read signed or not.
fn signed(e: &[u8], i: usize, wide: bool) -> i32 {
    if wide {
        i16::from_le_bytes([e[2 * i], e[2 * i + 1]]) as i32
    } else {
        e[i] as i8 as i32
    }
}
fn unsigned(e: &[u8], i: usize, wide: bool) -> i32 {
    if wide {
        u16::from_le_bytes([e[2 * i], e[2 * i + 1]]) as i32
    } else {
        e[i] as i32
    }
}

/// Stores `v` rounded to the nearest integer (ties to even) in component `i`: adding 1.5 · 2²³ leaves the
/// integer in the sum's low mantissa bits (two's complement), whose low 8 or 16 are the component.
fn put(e: &mut [u8], i: usize, wide: bool, v: f32) {
    let bits = (v + 12_582_912.0).to_bits();
    if wide {
        e[2 * i..2 * i + 2].copy_from_slice(&(bits as u16).to_le_bytes());
    } else {
        e[i] = bits as u8;
    }
}

/// `v`, or 0 where its sign bit is set (the decoder's integer min/max against zero on the float's bits).
fn unless_negative(v: f32) -> f32 {
    if (v.to_bits() as i32) < 0 {
        0.0
    } else {
        v
    }
}

/// OCTAHEDRAL: a unit vector from its octahedral x, y (the third component holds 1.0 at their bit count, so the
/// normalization divides it out), as signed normalized integers; the fourth component passes through.
fn octahedral(e: &mut [u8]) {
    let wide = e.len() == 8;
    let max = if wide { 32767.0 } else { 127.0 };
    let (mut x, mut y) = (signed(e, 0, wide) as f32, signed(e, 1, wide) as f32);
    let z = signed(e, 2, wide) as f32 - (x.abs() + y.abs());
    // Below the equator the octahedron folds over: x and y move toward zero by z's depth.
    let t = if (z.to_bits() as i32) < 0 { z } else { 0.0 };
    x += f32::from_bits(t.to_bits() ^ (x.to_bits() & 0x8000_0000));
    y += f32::from_bits(t.to_bits() ^ (y.to_bits() & 0x8000_0000));
    let s = max / (x * x + (y * y + z * z)).sqrt();
    for (i, v) in [x, y, z].into_iter().enumerate() {
        put(e, i, wide, v * s);
    }
}

/// QUATERNION: a unit quaternion from its three smallest components (scaled by √2) and the index of the largest,
/// which the fourth component's low two bits hold (its other bits, 1.0 at the components' bit count).
fn quaternion(e: &mut [u8]) {
    let last = signed(e, 3, true);
    let s = (last | 3) as f32;
    let [x, y, z] = [0, 1, 2].map(|i| signed(e, i, true) as f32);
    // All unscaled: w² = 2·s² − x² − y² − z² in the components' fixed point.
    let ws = s * s;
    let w = unless_negative((ws + ws) - (x * x + (y * y + z * z))).sqrt();
    let ss = (32767.0 / 2f32.sqrt()) / s;
    let largest = (last & 3) as usize;
    for (k, v) in [w, x, y, z].into_iter().enumerate() {
        put(e, (largest + k) % 4, true, v * ss);
    }
}

/// EXPONENTIAL: each 32-bit component a float 2^e · m, from a signed 8-bit exponent and 24-bit mantissa.
fn exponential(e: &mut [u8]) {
    for c in e.chunks_exact_mut(4) {
        let v = i32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        let (exponent, mantissa) = (v >> 24, (v << 8) >> 8);
        let power = f32::from_bits(((exponent + 127) << 23) as u32);
        c.copy_from_slice(&(power * mantissa as f32).to_le_bytes());
    }
}

/// COLOR (`KHR_meshopt_compression`): RGBA from YCoCg and an alpha whose top set bit marks the bit count K, as
/// unsigned normalized integers.
fn color(e: &mut [u8]) {
    let wide = e.len() == 8;
    let max = if wide { 65535.0 } else { 255.0 };
    let alpha = unsigned(e, 3, wide);
    // Every bit below the top one set: the K-bit range.
    let range = [1, 2, 4, 8].iter().fold(alpha, |m, k| m | (m >> k));
    let (y, co, cg) = (unsigned(e, 0, wide), signed(e, 1, wide), signed(e, 2, wide));
    let a = ((alpha << 1) & range) | (alpha & 1);
    let ss = max / range as f32;
    for (i, v) in [y + (co - cg), y + cg, y - (co + cg), a].into_iter().enumerate() {
        put(e, i, wide, v as f32 * ss);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshopt::encoding as enc;

    /// `n` deterministic values in −1..1 (xorshift), four to an element.
    fn values(n: usize, mut seed: u64) -> Vec<[f32; 4]> {
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 23) as f32 - 1.0
        };
        (0..n).map(|_| [next(), next(), next(), next()]).collect()
    }

    /// Unit vectors (normalized `v`), for the octahedral and quaternion filters.
    fn unit(v: &[[f32; 4]], three: bool) -> Vec<[f32; 4]> {
        v.iter()
            .map(|c| {
                let k = if three { 3 } else { 4 };
                let l = c[..k].iter().map(|x| x * x).sum::<f32>().sqrt();
                std::array::from_fn(|i| if i < k { c[i] / l } else { c[i] })
            })
            .collect()
    }

    /// The filters here against meshoptimizer's own on this machine, on 4096 elements each that meshoptimizer's
    /// encoders wrote (every bit count the filters take): the same but for the last unit of a few 8-bit
    /// octahedral vectors and colours, where its SSE path takes an approximate square root or reciprocal (its
    /// NEON path fuses multiply-adds): the spec allows that unit, which is why its filters are not used.
    #[test]
    fn the_filters_agree_with_meshoptimizers_own() {
        type Native = unsafe extern "C" fn(*mut std::ffi::c_void, usize, usize);
        // A filter, its stride, encoded elements, and meshoptimizer's decoding and this module's of them.
        type Case = (&'static str, usize, Vec<u8>, Native, fn(&mut [u8]));
        let n = 4096;
        let v = values(n, 0x9e37_79b9);
        let colours: Vec<[f32; 4]> = v.iter().map(|c| c.map(|x| x * 0.5 + 0.5)).collect();
        let cases: Vec<Case> = (2..=16)
            .flat_map(|bits| {
                let (oct, quat) = (unit(&v, true), unit(&v, false));
                let mut c: Vec<Case> = vec![(
                    "OCTAHEDRAL",
                    8,
                    bytemuck::cast_slice(&enc::encode_filter_oct::<i16>(&oct, bits)).to_vec(),
                    meshopt::ffi::meshopt_decodeFilterOct,
                    octahedral,
                )];
                if bits <= 8 {
                    let b = bytemuck::cast_slice(&enc::encode_filter_oct::<i8>(&oct, bits)).to_vec();
                    c.push(("OCTAHEDRAL", 4, b, meshopt::ffi::meshopt_decodeFilterOct, octahedral));
                    let b = bytemuck::cast_slice(&enc::encode_filter_color::<u8>(&colours, bits)).to_vec();
                    c.push(("COLOR", 4, b, meshopt::ffi::meshopt_decodeFilterColor, color));
                }
                let b = bytemuck::cast_slice(&enc::encode_filter_color::<u16>(&colours, bits)).to_vec();
                c.push(("COLOR", 8, b, meshopt::ffi::meshopt_decodeFilterColor, color));
                if bits >= 4 {
                    let b = bytemuck::cast_slice(&enc::encode_filter_quat(&quat, bits)).to_vec();
                    c.push(("QUATERNION", 8, b, meshopt::ffi::meshopt_decodeFilterQuat, quaternion));
                }
                let scaled: Vec<[f32; 4]> = v.iter().map(|c| c.map(|x| x * 1e3f32.powf(x * 4.0))).collect();
                let b = enc::encode_filter_exp(&scaled, bits, enc::EncodeExpMode::Separate);
                c.push((
                    "EXPONENTIAL",
                    16,
                    bytemuck::cast_slice(&b).to_vec(),
                    meshopt::ffi::meshopt_decodeFilterExp,
                    exponential,
                ));
                c
            })
            .collect();
        let mut approximate = 0;
        for (filter, stride, input, native, ours) in cases {
            let mut words = vec![0u32; input.len() / 4];
            bytemuck::cast_slice_mut::<u32, u8>(&mut words).copy_from_slice(&input);
            // SAFETY: `words` holds `n` elements of `stride` bytes, 4-byte aligned, as the filter needs.
            unsafe { native(words.as_mut_ptr().cast(), n, stride) };
            let theirs: &[u8] = bytemuck::cast_slice(&words);
            let mut mine = input.clone();
            mine.chunks_exact_mut(stride).for_each(ours);
            for (a, b) in mine.chunks_exact(stride).zip(theirs.chunks_exact(stride)) {
                if a == b {
                    continue;
                }
                // Only 8-bit octahedral vectors and colours may differ, by one unit per component.
                assert!(stride == 4 && filter != "EXPONENTIAL", "{filter}, {stride}-byte: {a:?} vs {b:?}");
                let unit = |x: u8, y: u8| match filter {
                    "COLOR" => x.abs_diff(y) <= 1,
                    _ => (x as i8 as i32 - y as i8 as i32).abs() <= 1,
                };
                assert!(a.iter().zip(b).all(|(x, y)| unit(*x, *y)), "{filter}: {a:?} vs {b:?}");
                approximate += 1;
            }
        }
        assert!(approximate < n, "{approximate} 8-bit elements differ");
    }
}
