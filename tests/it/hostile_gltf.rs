//! Hostile glTF documents (issue 50): each a single mutation of a valid file that once panicked or asked for
//! gigabytes, found by structure-aware fuzzing. Each is refused by `check`, naming the file and the JSON path,
//! and `inspect` and `build` refuse it the same way (exit 2), never a panic or an abort.

use std::path::Path;
use std::process::Command;

use serde_json::{json, Value};

/// A valid textured triangle: POSITION, NORMAL, COLOR_0, TEXCOORD_0, u16 indices, a PNG in a bufferView, a
/// perspective camera; `model.bin` beside it.
fn base(dir: &Path) -> Value {
    let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let mut bin = Vec::new();
    bin.extend(f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0])); // 0: positions, 36
    bin.extend(f32s(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0])); // 36: normals, 36
    bin.extend(f32s(&[1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0])); // 72: colours, 48
    bin.extend(f32s(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0])); // 120: uvs, 24
    bin.extend([0u8, 0, 1, 0, 2, 0, 0, 0]); // 144: indices, 6 (+2)
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 100, 50, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let png_at = bin.len();
    bin.extend(&png);
    std::fs::write(dir.join("model.bin"), &bin).unwrap();
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1, "COLOR_0": 2, "TEXCOORD_0": 3},
            "indices": 4, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}],
        "images": [{"bufferView": 5, "mimeType": "image/png"}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC4"},
            {"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC2"},
            {"bufferView": 4, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 36},
            {"buffer": 0, "byteOffset": 72, "byteLength": 48},
            {"buffer": 0, "byteOffset": 120, "byteLength": 24},
            {"buffer": 0, "byteOffset": 144, "byteLength": 6},
            {"buffer": 0, "byteOffset": png_at, "byteLength": png.len()}
        ],
        "buffers": [{"uri": "model.bin", "byteLength": bin.len()}]
    })
}

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Writes `doc` and a manifest of it, and runs `check`, `inspect` and `build`: each must refuse it with exit 2
/// and say `says` (a JSON path or what is wrong) with the file's name.
fn refused(dir: &Path, doc: &Value, says: &str) {
    std::fs::write(dir.join("model.gltf"), serde_json::to_vec_pretty(doc).unwrap()).unwrap();
    std::fs::write(
        dir.join("m.toml"),
        "[dataset]\nname = \"h\"\nout = \"out\"\n[source.s]\ngltf = \"model.gltf\"\n[render]\nresolution = [16, 16]\n\
         [rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 1\n[output.d]\nwriter = \"nerfstudio\"\n",
    )
    .unwrap();
    for args in [&["check", "m.toml"][..], &["inspect", "m.toml", "--ply", "x.ply"], &["build", "m.toml"]] {
        let (code, err) = vvgen(dir, args);
        assert!(!err.contains("panicked"), "{args:?} panicked on `{says}`: {err}");
        assert_eq!(code, 2, "{args:?} on `{says}`: {err}");
        assert!(err.contains("model.gltf") && err.contains(says), "{args:?}: wanted `{says}` in: {err}");
    }
}

#[test]
fn the_base_document_builds() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let doc = base(d);
    std::fs::write(d.join("model.gltf"), serde_json::to_vec_pretty(&doc).unwrap()).unwrap();
    let (code, err) = vvgen(d, &["new", "model.gltf"]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = vvgen(d, &["build", "model.toml"]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn attributes_of_the_wrong_shape_are_refused_with_their_json_path() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // pose.rs indexed normals by vertex: a NORMAL retyped VEC2, or pointed at a VEC2 accessor, or short.
    let mut doc = base(d);
    doc["accessors"][1]["type"] = json!("VEC2");
    refused(d, &doc, "meshes[0].primitives[0].attributes.NORMAL: accessor 1 is VEC2, where NORMAL must be VEC3");
    let mut doc = base(d);
    doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(3);
    refused(d, &doc, "attributes.NORMAL: accessor 3 is VEC2");
    let mut doc = base(d);
    doc["accessors"][1]["count"] = json!(2);
    refused(d, &doc, "attributes.NORMAL: accessor 1 has 2 elements, POSITION has 3");
    // load.rs read a colour's c[1] and c[2].
    for ty in ["SCALAR", "VEC2"] {
        let mut doc = base(d);
        doc["accessors"][2]["type"] = json!(ty);
        refused(d, &doc, &format!("attributes.COLOR_0: accessor 2 is {ty}, where COLOR_0 must be VEC3 or VEC4"));
    }
    // Indices that are not unsigned integer scalars.
    let mut doc = base(d);
    doc["accessors"][4]["type"] = json!("VEC2");
    refused(d, &doc, "meshes[0].primitives[0].indices: accessor 4 is VEC2");
}

#[test]
fn an_image_range_that_wraps_is_refused() {
    // load.rs added an image's bufferView offset and length unchecked: near 2^64 the sum wrapped and passed.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let mut doc = base(d);
    doc["bufferViews"][5]["byteOffset"] = json!(u64::MAX);
    refused(d, &doc, "images[0]: bufferView 5 runs past its buffer");
}

#[test]
fn a_camera_without_its_projection_is_refused() {
    // The gltf crate unwraps the projection object its `type` names.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    for (ty, remove) in [("perspective", "perspective"), ("orthographic", "perspective")] {
        let mut doc = base(d);
        doc["cameras"][0]["type"] = json!(ty);
        doc["cameras"][0].as_object_mut().unwrap().remove(remove);
        refused(d, &doc, &format!("cameras[0].type is \"{ty}\" but cameras[0].{ty} is missing"));
    }
}

#[test]
fn counts_the_file_cannot_back_are_refused_before_anything_is_allocated() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // A sparse accessor with no bufferView and a huge count: count × components zeros (3–206 GB) were allocated.
    let mut doc = base(d);
    doc["accessors"][1] = json!({"componentType": 5126, "count": 3_000_000_000u64, "type": "VEC3",
        "sparse": {"count": 1, "indices": {"bufferView": 4, "componentType": 5123},
                   "values": {"bufferView": 1}}});
    refused(d, &doc, "accessors[1].count = 3000000000 (3 components each) with no bufferView");
    // Indices with no bufferView and exactly 2^28 of them passed a `> 2^28` cap; the rasterizer's setup aborted.
    let mut doc = base(d);
    doc["accessors"][4] = json!({"componentType": 5125, "count": 268_435_456u64, "type": "SCALAR"});
    refused(d, &doc, "accessors[4].count = 268435456 (1 components each) with no bufferView");
}

/// CRC-32 (PNG's), to forge a chunk.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
        }
    }
    !c
}

#[test]
fn an_image_whose_header_declares_gigapixels_is_refused() {
    // A PNG of a few bytes whose header says 100 000 × 100 000: decoding it whole would ask for 40 GB.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let doc = base(d);
    let mut bin = std::fs::read(d.join("model.bin")).unwrap();
    let png_at = doc["bufferViews"][5]["byteOffset"].as_u64().unwrap() as usize;
    // IHDR: length (4), "IHDR" (4), width (4), height (4), … ; its CRC covers "IHDR" and the 13 data bytes.
    let ihdr = png_at + 8;
    bin[ihdr + 8..ihdr + 16].copy_from_slice(&[0, 1, 0x86, 0xA0, 0, 1, 0x86, 0xA0]);
    let crc = crc32(&bin[ihdr + 4..ihdr + 21]);
    bin[ihdr + 21..ihdr + 25].copy_from_slice(&crc.to_be_bytes());
    std::fs::write(d.join("model.bin"), &bin).unwrap();
    refused(d, &doc, "images[0]: cannot decode");
}
