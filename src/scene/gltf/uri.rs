//! A glTF's buffers and image URIs: the GLB's BIN chunk, `data:` (base64), or files beside the glTF that stay
//! inside its folder.

use std::path::Path;

use base64::Engine as _;

/// The bytes of every buffer of `document`, from the GLB's BIN chunk `blob` or from its URI (resolved in `dir`,
/// the glTF's folder), each at least as long as declared; a meshopt fallback buffer (never read) is empty.
pub(super) fn buffers(
    document: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    dir: &Path,
) -> Result<Vec<Vec<u8>>, String> {
    let read = |b: &gltf::Buffer<'_>| !super::meshopt::is_fallback(b);
    // The chunk is moved into the last buffer that reads it (the spec allows one), copied only for earlier ones.
    let mut chunk_readers =
        document.buffers().filter(|b| read(b) && matches!(b.source(), gltf::buffer::Source::Bin)).count();
    let mut buffers = Vec::new();
    for b in document.buffers() {
        if !read(&b) {
            buffers.push(Vec::new());
            continue;
        }
        let data = match b.source() {
            gltf::buffer::Source::Bin => {
                chunk_readers -= 1;
                let chunk = if chunk_readers == 0 { blob.take() } else { blob.clone() };
                chunk.ok_or("buffer refers to a GLB BIN chunk the file does not have")?
            }
            gltf::buffer::Source::Uri(uri) => fetch_uri(dir, uri).map_err(|e| format!("buffer {}: {e}", b.index()))?,
        };
        if data.len() < b.length() {
            return Err(format!("buffer {} holds {} bytes, {} declared", b.index(), data.len(), b.length()));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// Appends `bytes`, data decoded at load (Draco geometry, meshopt views), as a buffer named `name` of `root`, whose
/// buffers' bytes are `buffers`; returns its index.
pub(super) fn push_buffer(
    root: &mut gltf::json::Root,
    buffers: &mut Vec<Vec<u8>>,
    bytes: Vec<u8>,
    name: &str,
) -> gltf::json::Index<gltf::json::Buffer> {
    debug_assert_eq!(root.buffers.len(), buffers.len(), "every buffer of the document was read");
    buffers.push(bytes);
    root.push(gltf::json::Buffer {
        byte_length: gltf::json::validation::USize64::from(buffers[buffers.len() - 1].len()),
        name: Some(name.into()),
        uri: None,
        extensions: None,
        extras: Default::default(),
    })
}

/// Reads a buffer or image URI: `data:` (base64) or a file relative to the glTF that stays inside its folder.
pub(super) fn fetch_uri(dir: &Path, uri: &str) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (meta, data) = rest.split_once(',').ok_or("malformed data: URI")?;
        if !meta.ends_with(";base64") {
            return Err("data: URI is not base64".into());
        }
        return base64::engine::general_purpose::STANDARD
            .decode(data.trim())
            .map_err(|e| format!("bad base64 in data: URI: {e}"));
    }
    let decoded = percent_decode(uri);
    let rel = Path::new(&decoded);
    // Out of the folder is refused (a document must not read the disk at large); the fix is a layout.
    let fix = "keep the files it names in the glTF's folder or below it (glTF-Transform's `copy` writes a .glb \
               holding them)";
    if rel.is_absolute() || decoded.contains("://") {
        return Err(format!("URI `{uri}` points outside the glTF's folder; {fix}"));
    }
    // Containment is judged on the resolved paths: `sub/../x.bin` stays inside, a symlink out of the folder
    // does not.
    let full = dir.join(rel);
    let (inside, target) = (std::fs::canonicalize(dir), std::fs::canonicalize(&full));
    match (inside, target) {
        (Ok(inside), Ok(target)) if target.starts_with(&inside) => {}
        (Ok(_), Ok(_)) => return Err(format!("URI `{uri}` points outside the glTF's folder; {fix}")),
        (_, Err(e)) => return Err(format!("cannot read `{}`: {e}", full.display())),
        (Err(e), _) => return Err(format!("cannot read the folder `{}`: {e}", dir.display())),
    }
    std::fs::read(&full).map_err(|e| format!("cannot read `{}`: {e}", full.display()))
}

/// The files beside the glTF at `path` that its buffers and images name (not `data:` URIs), relative to the
/// glTF's folder: what the file's content depends on besides itself (a mesh-sequence frame is keyed by them
/// too). Relative, so the list is a fact of the content alone, wherever the file lies. Containment and
/// existence are judged when they are read (`fetch_uri`).
pub(crate) fn side_files(path: &Path) -> Result<Vec<std::path::PathBuf>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    let json: std::borrow::Cow<'_, [u8]> = if bytes.starts_with(b"glTF") {
        gltf::Glb::from_slice(&bytes).map_err(|e| format!("a truncated or malformed GLB ({e})"))?.json
    } else {
        bytes.as_slice().into()
    };
    let doc: serde_json::Value = serde_json::from_slice(&json).map_err(|e| format!("not glTF JSON: {e}"))?;
    let mut out = Vec::new();
    for list in ["buffers", "images"] {
        for item in doc.get(list).and_then(|v| v.as_array()).map_or(&[][..], |v| v.as_slice()) {
            if let Some(uri) = item.get("uri").and_then(|u| u.as_str()).filter(|u| !u.starts_with("data:")) {
                out.push(std::path::PathBuf::from(percent_decode(uri)));
            }
        }
    }
    out.sort();
    out.dedup();
    Ok(out)
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Some(v) = std::str::from_utf8(&b[i + 1..i + 3]).ok().and_then(|h| u8::from_str_radix(h, 16).ok()) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}
