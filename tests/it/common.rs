//! Fixtures the tests make themselves, and helpers to compare what builds write.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A file under `tests/data`.
pub fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

/// The CesiumMan asset (skinned, textured, animated).
pub fn cesium_glb() -> PathBuf {
    data("gltf/CesiumMan/CesiumMan.glb")
}

/// The head of a CesiumMan manifest: dataset `m` into `out/` with its cache in `cache/`, `frames` frames at
/// `fps`, y-up, fitted to `height` and centred. `dataset` and `transform` add lines to those tables; tests add
/// render settings, rigs, splits and outputs after it.
pub fn cesium_head(frames: u32, fps: u32, height: f64, dataset: &str, transform: &str) -> String {
    format!(
        "[dataset]\nname = \"m\"\nout = \"out\"\ncache = \"cache\"\n{dataset}\n\
         [source.man]\ngltf = \"{}\"\nframes = {{ count = {frames}, fps = {fps} }}\n\
         [transform]\nup = \"y\"\nfit = {{ height = {height} }}\ncenter = \"bbox\"\n{transform}\n",
        cesium_glb().display()
    )
}

/// Loads the manifest at `path`, panicking with its rendered diagnostics.
pub fn load(path: &Path) -> vvgen::manifest::Manifest {
    vvgen::manifest::load(path).unwrap_or_else(|r| panic!("{}", r.render(false))).0
}

/// A triangle whose translation is animated by four LINEAR keys at t = 0, 1, 2, 3 s.
pub fn animated_triangle(last_key_x: f32) -> String {
    use base64::Engine;
    let mut buf: Vec<u8> = Vec::new();
    for v in [[-0.5f32, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.8, 0.0]] {
        v.iter().for_each(|c| buf.extend(c.to_le_bytes()));
    }
    for t in [0f32, 1.0, 2.0, 3.0] {
        buf.extend(t.to_le_bytes());
    }
    for x in [0f32, 0.1, 0.2, last_key_x] {
        [x, 0.0, 0.0].iter().for_each(|c| buf.extend(c.to_le_bytes()));
    }
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&buf));
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "buffers": [{{"byteLength": {}, "uri": "{uri}"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 16}},
                  {{"buffer": 0, "byteOffset": 52, "byteLength": 48}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [-0.5, 0, 0], "max": [0.5, 0.8, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "SCALAR", "min": [0], "max": [3]}},
    {{"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3"}}],
  "animations": [{{"channels": [{{"sampler": 0, "target": {{"node": 0, "path": "translation"}}}}],
                   "samplers": [{{"input": 1, "output": 2, "interpolation": "LINEAR"}}]}}]}}"#,
        buf.len()
    )
}

/// A manifest over `tri.gltf` ([`animated_triangle`], written beside it by the test): dataset `tri`, `count`
/// frames at `fps`, `size`² images, `views` orbit cameras in split `train`, then `outputs`.
pub fn triangle_manifest(count: u32, fps: u32, size: u32, views: u32, outputs: &str) -> String {
    format!(
        "[dataset]\nname = \"tri\"\nout = \"out\"\ncache = \"cache\"\n\
         [source.tri]\ngltf = \"tri.gltf\"\nframes = {{ count = {count}, fps = {fps} }}\n\
         [render]\nresolution = [{size}, {size}]\n[rig.o]\nkind = \"orbit\"\n\
         [split.train]\nrig = \"o\"\nviews = {views}\n{outputs}"
    )
}

/// Every file under `root` (root-relative path → bytes).
pub fn tree(root: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(p.strip_prefix(root).unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// The error and its causes, as the CLI prints them.
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cur = e.source();
    while let Some(c) = cur {
        s.push_str(&format!(": {c}"));
        cur = c.source();
    }
    s
}

/// Largest distance from a point of either set to the nearest of the other (symmetric Hausdorff).
pub fn hausdorff(a: &[glam::Vec3], b: &[glam::Vec3]) -> f32 {
    let one = |a: &[glam::Vec3], b: &[glam::Vec3]| {
        a.iter().map(|p| b.iter().map(|q| p.distance(*q)).fold(f32::INFINITY, f32::min)).fold(0.0, f32::max)
    };
    one(a, b).max(one(b, a))
}

/// A GLB's JSON and BIN chunks.
pub fn glb_split(glb: &[u8]) -> (serde_json::Value, Vec<u8>) {
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    let json_len = word(12);
    let json = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    (json, glb[bin_at + 8..bin_at + 8 + word(bin_at)].to_vec())
}

/// A GLB of `json` and `bin`.
pub fn glb_join(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    j.resize(j.len().next_multiple_of(4), b' ');
    let mut b = bin.to_vec();
    b.resize(b.len().next_multiple_of(4), 0);
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + j.len() + 8 + b.len()) as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    out.extend((b.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(b);
    out
}
