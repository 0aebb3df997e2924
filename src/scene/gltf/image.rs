//! A glTF's textures ([`textures`]): its images' bytes to pixels, PNG, JPEG and WebP through the `image` crate, KTX2
//! (`KHR_texture_basisu`: Basis Universal's ETC1S and UASTC, Zstandard-supercompressed or not) through `basisu`, a
//! port of Binomial's transcoder that gives its RGBA bytes exactly (the tests hold it to the C++ transcoder's
//! output). Either way the image's own header sizes the decode, bounded by [`MAX_TEXTURE_SIDE`] as OBJ and FBX
//! textures are.

use std::path::Path;

use rayon::prelude::*;

use super::uri::fetch_uri;
use crate::scene::obj::MAX_TEXTURE_SIDE;
use crate::scene::texture::Texture;

/// KTX 2.0's file identifier.
const KTX2: &[u8; 12] = b"\xABKTX 20\xBB\r\n\x1A\n";

/// Every texture of `doc`, in its order, as sRGB RGBA: the images they use are read in the file's order (from
/// `buffers`, or from files beside it in `dir`), then decoded once each, in parallel (a file's 2048² textures are
/// most of its load: FlightHelmet's fifteen took 46 ms one after another, 27 ms on two cores). An image's pixels
/// depend on its bytes alone, and a failure is reported for the first failing image in the file's order.
pub(super) fn textures(doc: &gltf::Document, buffers: &[Vec<u8>], dir: &Path) -> Result<Vec<Texture>, String> {
    // Each image's bytes and its name in errors: its index, and its file when it has one.
    let mut bytes: Vec<Option<(Vec<u8>, String)>> = vec![None; doc.images().len()];
    for t in doc.textures() {
        let index = t.source().index();
        if bytes[index].is_some() {
            continue;
        }
        bytes[index] = Some(match t.source().source() {
            gltf::image::Source::View { view, .. } => {
                let buf = &buffers[view.buffer().index()];
                // Offsets come from the file: a sum that wraps is a range past the buffer, not a small one.
                let end = view.offset().saturating_add(view.length());
                if end > buf.len() {
                    return Err(format!("images[{index}]: bufferView {} runs past its buffer", view.index()));
                }
                (buf[view.offset()..end].to_vec(), format!("images[{index}]"))
            }
            gltf::image::Source::Uri { uri, .. } => {
                let read = fetch_uri(dir, uri).map_err(|e| format!("image {index}: {e}"))?;
                let name = if uri.starts_with("data:") {
                    format!("images[{index}]")
                } else {
                    format!("images[{index}] ({uri})")
                };
                (read, name)
            }
        });
    }
    let decoded: Vec<_> = bytes.par_iter().map(|b| b.as_ref().map(|(b, name)| decode(b, name)).transpose()).collect();
    drop(bytes);
    let mut images = decoded.into_iter().collect::<Result<Vec<_>, _>>()?;
    // An image's last texture takes its pixels; textures before it that share the image copy them.
    let mut last = vec![usize::MAX; images.len()];
    for (ti, t) in doc.textures().enumerate() {
        last[t.source().index()] = ti;
    }
    let mut textures = Vec::with_capacity(doc.textures().len());
    for (ti, t) in doc.textures().enumerate() {
        let i = t.source().index();
        let img = if last[i] == ti { images[i].take() } else { images[i].clone() };
        let img = img.expect("BUG: every texture's image was decoded above, and taken by its last texture only");
        textures.push(Texture::new(img.width(), img.height(), img.into_raw(), true));
    }
    Ok(textures)
}

/// Decodes the bytes of the image errors call `name` to 8-bit RGBA, KTX2 by its identifier, anything else by its own
/// magic bytes.
fn decode(bytes: &[u8], name: &str) -> Result<image::RgbaImage, String> {
    if bytes.starts_with(KTX2) {
        return ktx2(bytes).map_err(|e| format!("{name}: a KTX2 image {e}"));
    }
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("{name}: cannot decode: {e}"))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    reader.limits(limits);
    let decoded = reader.decode().map_err(|e| format!("{name}: cannot decode: {e}"))?;
    Ok(decoded.to_rgba8())
}

/// The way out for a damaged KTX2 image.
const AGAIN: &str = "Way out: export or download the model again";

/// The way out for a KTX2 image vvgen cannot read.
const KTX2_WAY_OUT: &str = "Way out: export the model again with PNG or JPEG textures, or with KTX2 textures in Basis \
                            Universal's ETC1S or UASTC LDR (what gltfpack's `-tc` and glTF-Transform's `etc1s` and \
                            `uastc` write)";

/// Level 0 of a Basis Universal KTX2 image as RGBA, or what is wrong with it (completing "a KTX2 image …").
///
/// The header is checked here before the transcoder sees it: the transcoder trusts the file's level index (a
/// Zstandard level's stated size is allocated as given, its range summed unchecked), and `KHR_texture_basisu`
/// allows a 2D image only.
fn ktx2(bytes: &[u8]) -> Result<image::RgbaImage, String> {
    let header = Ktx2Header::read(bytes)
        .ok_or_else(|| format!("is truncated: its header or level index runs past its end. {AGAIN}"))?;
    // Basis Universal's payloads have no Vulkan format of their own (VK_FORMAT_UNDEFINED, 0).
    if header.vk_format != 0 {
        return Err(not_basis(&header));
    }
    let (w, h) = (header.width, header.height);
    if w == 0 || h == 0 || w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
        return Err(format!(
            "is {w} × {h} texels: sides of 1 to {MAX_TEXTURE_SIDE} are read. Way out: export the model again with \
             smaller textures"
        ));
    }
    if header.depth > 1 || header.layers > 1 || header.faces != 1 {
        return Err(format!(
            "is not one 2D image ({} deep, {} layers, {} faces), as `KHR_texture_basisu` requires. {KTX2_WAY_OUT}",
            header.depth, header.layers, header.faces
        ));
    }
    // UASTC holds 16 bytes per 4 × 4 block: a level that inflates past the first level's blocks is damaged (ETC1S
    // states no size).
    let blocks = 16 * u64::from(w.div_ceil(4)) * u64::from(h.div_ceil(4));
    for (i, l) in header.levels.iter().enumerate() {
        let end = l.offset.checked_add(l.length).filter(|&e| e <= bytes.len() as u64);
        if end.is_none() || l.uncompressed > blocks {
            return Err(format!("is damaged: level {i} runs past the file or states an impossible size. {AGAIN}"));
        }
    }
    let t = basisu::Transcoder::new(bytes).map_err(|e| match e {
        basisu::Error::Truncated => format!("is truncated. {AGAIN}"),
        _ => not_basis(&header),
    })?;
    match t.source_format() {
        basisu::SourceFormat::Etc1s | basisu::SourceFormat::UastcLdr => {}
        other => {
            return Err(format!(
                "holds Basis Universal's {other:?}, not the ETC1S or UASTC LDR that `KHR_texture_basisu` allows. \
                 {KTX2_WAY_OUT}"
            ))
        }
    }
    let rgba = t
        .transcode(0, basisu::TargetFormat::Rgba32, basisu::DecodeFlags::NONE)
        .map_err(|e| format!("is damaged: it does not transcode ({e:?}). {AGAIN}"))?;
    image::RgbaImage::from_raw(w, h, rgba)
        .ok_or_else(|| format!("is damaged: it transcodes to the wrong size. {AGAIN}"))
}

/// The error for a KTX2 image that holds no Basis Universal payload (or a damaged one).
fn not_basis(header: &Ktx2Header) -> String {
    format!(
        "is not Basis Universal's ETC1S or UASTC (vkFormat {}, supercompression {}), which `KHR_texture_basisu` \
         requires, or is damaged. {KTX2_WAY_OUT}",
        header.vk_format, header.scheme
    )
}

/// The fields of a KTX2 header that decide whether its image can be read.
#[derive(Debug)]
struct Ktx2Header {
    vk_format: u32,
    width: u32,
    height: u32,
    depth: u32,
    layers: u32,
    faces: u32,
    scheme: u32,
    levels: Vec<Level>,
}

/// One entry of a KTX2 level index.
#[derive(Debug, Clone, Copy)]
struct Level {
    offset: u64,
    length: u64,
    uncompressed: u64,
}

impl Ktx2Header {
    /// Reads the header and level index, `None` when the file ends inside them.
    fn read(b: &[u8]) -> Option<Ktx2Header> {
        let u32_at = |o: usize| b.get(o..o + 4).map(|s| u32::from_le_bytes(s.try_into().expect("4 bytes")));
        let u64_at = |o: usize| b.get(o..o + 8).map(|s| u64::from_le_bytes(s.try_into().expect("8 bytes")));
        // A level count of 0 asks the reader to make the mipmaps: one level is stored.
        let count = u32_at(40)?.max(1) as usize;
        // The index lies before the data: a count it has no room for is a damaged file, not an allocation.
        if count > b.len() / 24 {
            return None;
        }
        let levels = (0..count)
            .map(|i| {
                let o = 80 + 24 * i;
                Some(Level { offset: u64_at(o)?, length: u64_at(o + 8)?, uncompressed: u64_at(o + 16)? })
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Ktx2Header {
            vk_format: u32_at(12)?,
            width: u32_at(20)?,
            height: u32_at(24)?,
            depth: u32_at(28)?,
            layers: u32_at(32)?,
            faces: u32_at(36)?,
            scheme: u32_at(44)?,
            levels,
        })
    }
}
