//! Compressed glTF meshes. Draco (`KHR_draco_mesh_compression`) decodes as Google's own decoder decodes it (the
//! reference files were decoded by glTF-Transform, which runs it); meshopt (`EXT_meshopt_compression`,
//! `KHR_meshopt_compression`) as meshoptimizer's WebAssembly decoder (three.js's and glTF-Transform's) does. Both
//! draw through `new` and `build` from their folder, and a malformed stream is an error naming the file and the
//! primitive or view, in `check` and `build`, never a panic.

use std::path::Path;
use std::process::Command;

use glam::Mat4;
use serde_json::{json, Value};
use vvgen::scene::gltf::{self, GltfAsset, PoseScratch};
use vvgen::scene::PosedScene;

use crate::common::{data, glb_join as join, glb_split as split};

fn load(rel: &str) -> GltfAsset {
    gltf::load(&data(rel), None).unwrap_or_else(|e| panic!("{e}"))
}

fn pose(a: &GltfAsset, t: f32) -> PosedScene {
    let mut out = PosedScene::default();
    a.pose(&[0], t, Mat4::IDENTITY, &mut PoseScratch::default(), &mut out);
    out
}

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Writes `doc` (with binary chunk `bin`) as `model.glb` beside a two-view manifest: `check` and `build` each
/// refuse it with exit 2, saying every one of `parts`.
fn refused_by_check_and_build(doc: &Value, bin: &[u8], parts: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("model.glb"), join(doc, bin)).unwrap();
    let manifest = "[dataset]\nname = \"s\"\nout = \"out\"\n[source.s]\ngltf = \"model.glb\"\n[rig.h]\n\
                    kind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n[output.d]\nwriter = \"dnerf\"\n";
    std::fs::write(tmp.path().join("m.toml"), manifest).unwrap();
    for command in ["check", "build"] {
        let (code, err) = vvgen(tmp.path(), &[command, "m.toml"]);
        assert_eq!(code, 2, "{command}: {err}");
        for part in parts {
            assert!(err.contains(part), "{command}: `{part}` not in {err}");
        }
    }
}

/// Loads `json` (with binary chunk `bin`) with each byte of `at` set in turn to 0, 255 and itself with bit 4
/// flipped: every file loads or is refused with an error saying all of `parts`. Returns how many loaded and how
/// many were refused.
fn damaged(json: &Value, bin: &[u8], at: impl Iterator<Item = usize>, parts: &[&str]) -> (usize, usize) {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("model.glb");
    let (mut loaded, mut refused) = (0, 0);
    for at in at {
        for value in [0u8, 0xff, bin[at] ^ 0x10] {
            let mut damaged = bin.to_vec();
            damaged[at] = value;
            match gltf::load_slice(&join(json, &damaged), &path, None) {
                Ok(_) => loaded += 1,
                Err(e) => {
                    let e = e.to_string();
                    assert!(parts.iter().all(|p| e.contains(p)), "{e}");
                    refused += 1;
                }
            }
        }
    }
    (loaded, refused)
}

/// CesiumMan exported by Blender 4.5 with Draco compression (its encoder's defaults: EdgeBreaker, positions on 14
/// bits), and the same file decoded to plain accessors by glTF-Transform with Google's decoder. Posed over its
/// walk, every vertex, normal, texture coordinate and triangle is the reference's, bit for bit: the skin reads
/// the decoded joints and weights.
#[test]
fn a_draco_skinned_mesh_poses_as_googles_decoder_reads_it() {
    let draco = load("gltf/draco/CesiumMan_draco.glb");
    let plain = load("gltf/draco/CesiumMan_draco_decoded.glb");
    assert!(draco.warnings.is_empty(), "{:?}", draco.warnings);
    let first = pose(&draco, 0.0);
    for t in [0.0, 0.45, 1.1, 1.9] {
        let (a, b) = (pose(&draco, t), pose(&plain, t));
        assert_eq!(a.primitives.len(), b.primitives.len());
        for (p, q) in a.primitives.iter().zip(&b.primitives) {
            assert_eq!(p.indices, q.indices, "t = {t}: triangles");
            assert_eq!(p.positions, q.positions, "t = {t}: positions");
            assert_eq!(p.normals, q.normals, "t = {t}: normals");
            assert_eq!(p.uvs, q.uvs, "t = {t}: texture coordinates");
        }
        assert!(a.primitives[0].indices.len() == 3 * 4672, "{}", a.primitives[0].indices.len());
        if t > 0.0 {
            let moved = a.primitives[0].positions.iter().zip(&first.primitives[0].positions);
            assert!(moved.filter(|(p, q)| p.distance(**q) > 0.01).count() > 100, "t = {t}: the walk poses the mesh");
        }
    }
}

/// Google's own Draco test file (the Khronos box) renders as its uncompressed twin from the same repository,
/// through `new` and `build` run in its folder as a newcomer runs them: the file needs the extension, and vvgen
/// refused it before.
#[test]
fn googles_draco_box_builds_as_its_plain_twin() {
    let tmp = tempfile::tempdir().unwrap();
    let mut hashes = Vec::new();
    for name in ["Box_Draco.glb", "Box.glb"] {
        let dir = tmp.path().join(name.replace('.', "_"));
        std::fs::create_dir(&dir).unwrap();
        std::fs::copy(data(&format!("gltf/draco/{name}")), dir.join(name)).unwrap();
        let (code, err) = vvgen(&dir, &["new", name, "-o", "m.toml"]);
        assert_eq!(code, 0, "{err}");
        let (code, err) = vvgen(&dir, &["-q", "check", "m.toml"]);
        assert_eq!(code, 0, "{name}: {err}");
        let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(&dir).args(["inspect", "m.toml"]).output();
        let out = String::from_utf8(out.unwrap().stdout).unwrap();
        let hash = out.lines().find(|l| l.contains("posed-geometry hash")).expect("a frame line").to_string();
        assert!(hash.contains("12 triangle(s)"), "{hash}");
        hashes.push(hash.split("hash ").nth(1).unwrap().to_string());
    }
    assert_eq!(hashes[0], hashes[1], "the box's corners (±0.5) survive Draco's 14-bit positions exactly");
}

/// A damaged Draco stream, an attribute id its stream lacks, and a primitive mode Draco cannot hold: each is an
/// error naming the file and the primitive, in `check` as in `build`, with exit 2.
#[test]
fn bad_draco_data_is_an_error_naming_the_primitive() {
    let (json, bin) = split(&std::fs::read(data("gltf/draco/Box_Draco.glb")).unwrap());
    let ext = "/meshes/0/primitives/0/extensions/KHR_draco_mesh_compression";
    let view = json.pointer(&format!("{ext}/bufferView")).unwrap().as_u64().unwrap() as usize;
    let mut truncated = json.clone();
    let length = truncated["bufferViews"][view]["byteLength"].as_u64().unwrap();
    truncated["bufferViews"][view]["byteLength"] = json!(length / 2);
    let mut missing = json.clone();
    *missing.pointer_mut(&format!("{ext}/attributes/POSITION")).unwrap() = json!(7);
    let mut lines = json.clone();
    lines["meshes"][0]["primitives"][0]["mode"] = json!(1);
    let cases = [
        (truncated, "its Draco data (bufferView 0) does not decode"),
        (missing, "its Draco data has no attribute 7, which the extension names for POSITION"),
        (lines, "must be TRIANGLES or TRIANGLE_STRIP"),
    ];
    for (doc, says) in cases {
        refused_by_check_and_build(&doc, &bin, &["model.glb", "meshes[0].primitives[0]", says]);
    }
}

/// Every single-byte change of a Draco stream (each byte of the box's, set to three values) loads or is refused
/// with an error: none panics, and none allocates past the decoder's limits.
#[test]
fn damaged_draco_streams_fail_cleanly() {
    let (json, bin) = split(&std::fs::read(data("gltf/draco/Box_Draco.glb")).unwrap());
    let draco = json.pointer("/meshes/0/primitives/0/extensions/KHR_draco_mesh_compression/bufferView").unwrap();
    let view = &json["bufferViews"][draco.as_u64().unwrap() as usize];
    let (start, length) = (view["byteOffset"].as_u64().unwrap_or(0) as usize, view["byteLength"].as_u64().unwrap());
    let (loaded, refused) = damaged(&json, &bin, start..start + length as usize, &["model.glb", "primitive"]);
    assert!(loaded > 0 && refused > 0, "{loaded} loaded, {refused} refused");
}

/// The accessor data of two loaded files, field by field: meshes, skins and animations (not nodes, which
/// glTF-Transform rewrites as it decodes: a matrix as TRS, a scale of 1.0000001 as 1).
fn same_data(a: &GltfAsset, b: &GltfAsset, what: &str) {
    let (pa, pb): (Vec<_>, Vec<_>) = (a.meshes.iter().flatten().collect(), b.meshes.iter().flatten().collect());
    assert_eq!(pa.len(), pb.len(), "{what}");
    for (p, q) in pa.iter().zip(&pb) {
        assert_eq!(p.positions, q.positions, "{what}: positions");
        assert_eq!(p.normals, q.normals, "{what}: normals");
        assert_eq!(p.uvs, q.uvs, "{what}: texture coordinates");
        assert_eq!(p.indices, q.indices, "{what}: triangles");
        assert_eq!((&p.joints, &p.weights), (&q.joints, &q.weights), "{what}: skin weights");
    }
    let inverse_binds = |x: &GltfAsset| x.skins.iter().map(|s| s.inverse_bind.clone()).collect::<Vec<_>>();
    assert_eq!(inverse_binds(a), inverse_binds(b), "{what}: inverse bind matrices");
    assert_eq!(format!("{:?}", a.animations), format!("{:?}", b.animations), "{what}: animation keys");
}

/// CesiumMan packed by gltfpack 1.3 with `-cc` (meshopt, quantized attributes, normals through the octahedral
/// filter, rotation keys through the quaternion one, translation keys through the exponential one) loads as
/// glTF-Transform decodes it with meshoptimizer's WebAssembly decoder: every vertex, normal, uv, joint, weight,
/// triangle, inverse bind matrix and key, bit for bit. The same file packed as `KHR_meshopt_compression` (its newer
/// vertex codec) loads the same.
#[test]
fn a_meshopt_file_loads_as_the_reference_decoder_reads_it() {
    let packed = load("gltf/meshopt/CesiumMan_meshopt.glb");
    assert!(packed.warnings.is_empty(), "{:?}", packed.warnings);
    same_data(&packed, &load("gltf/meshopt/CesiumMan_meshopt_decoded.glb"), "glTF-Transform's decoding");
    same_data(&packed, &load("gltf/meshopt/CesiumMan_meshopt_khr.glb"), "KHR_meshopt_compression");
    assert_eq!(packed.meshes[0][0].indices.len(), 3 * 4672);
    // The walk poses the mesh: the animation and the skin were read from decoded views.
    let (a, b) = (pose(&packed, 0.0), pose(&packed, 0.7));
    let moved = a.primitives[0].positions.iter().zip(&b.primitives[0].positions);
    assert!(moved.filter(|(p, q)| p.distance(**q) > 0.01).count() > 100);
}

/// VertexColorTest packed as `KHR_meshopt_compression` by gltfpack (its colours through the COLOR filter, YCoCg
/// in 8 bits) renders as the plain file, unlit: the same pixels but for the colours' quantization.
#[test]
fn meshopt_colours_render_as_the_plain_files() {
    let tmp = tempfile::tempdir().unwrap();
    for f in ["VertexColorTest.gltf", "VertexColorTest.bin", "VertexColorChecks.png", "VertexColorTestLabels.png"] {
        std::fs::copy(data(&format!("gltf/VertexColorTest/{f}")), tmp.path().join(f)).unwrap();
    }
    std::fs::copy(data("gltf/meshopt/VertexColorTest_meshopt_khr.glb"), tmp.path().join("packed.glb")).unwrap();
    let image = |file: &str| {
        let manifest = format!(
            "[dataset]\nname = \"s\"\nout = \"out-{file}\"\npreview = false\n[source.s]\ngltf = \"{file}\"\n\
             [transform]\nfit = \"frame\"\n[render]\nresolution = [160, 160]\nshading = \"unlit\"\n[rig.h]\n\
             kind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n[output.d]\nwriter = \"dnerf\"\n"
        );
        std::fs::write(tmp.path().join("m.toml"), manifest).unwrap();
        let (code, err) = vvgen(tmp.path(), &["-q", "build", "m.toml"]);
        assert_eq!(code, 0, "{file}: {err}");
        image::open(tmp.path().join(format!("out-{file}/s_dnerf/train/r_0000.png"))).unwrap().to_rgba8()
    };
    let (plain, packed) = (image("VertexColorTest.gltf"), image("packed.glb"));
    let covered = plain.pixels().filter(|p| p[3] == 255).count();
    let off = plain.pixels().zip(packed.pixels()).filter(|(a, b)| (0..4).any(|c| a[c].abs_diff(b[c]) > 3)).count();
    assert!(covered > 1200, "{covered} pixels covered");
    assert!(off * 100 < covered, "{off} of {covered} pixels differ by more than 3");
}

/// Compressed views the codecs cannot decode as declared: a stride no attribute takes, an unknown mode, a filter
/// on indices, a count past what the data could expand to, data past its buffer, a truncated stream. Each is an
/// error naming the file and the view, in `check` as in `build`, with exit 2.
#[test]
fn bad_meshopt_data_is_an_error_naming_the_view() {
    let (json, bin) = split(&std::fs::read(data("gltf/meshopt/CesiumMan_meshopt.glb")).unwrap());
    let ext = |view: usize| format!("/bufferViews/{view}/extensions/EXT_meshopt_compression");
    let edit = |view: usize, key: &str, value: serde_json::Value| {
        let mut doc = json.clone();
        doc.pointer_mut(&ext(view)).unwrap()[key] = value;
        doc
    };
    let length = json.pointer(&format!("{}/byteLength", ext(4))).unwrap().as_u64().unwrap();
    let cases = [
        (edit(0, "byteStride", json!(6)), 0, "cannot be ATTRIBUTES"),
        (edit(0, "mode", json!("STRIPS")), 0, "mode `STRIPS` is none of"),
        (edit(4, "filter", json!("OCTAHEDRAL")), 4, "filter OCTAHEDRAL does not apply to TRIANGLES"),
        (edit(0, "count", json!(4_000_000_000u64)), 0, "past what meshopt's codecs can expand"),
        (edit(0, "byteOffset", json!(1 << 20)), 0, "its data runs past buffer 0"),
        (edit(4, "byteLength", json!(length / 2)), 4, "does not decode"),
    ];
    for (doc, view, says) in cases {
        let at = format!("bufferViews[{view}].extensions.EXT_meshopt_compression");
        refused_by_check_and_build(&doc, &bin, &["model.glb", &at, says]);
    }
}

/// Every byte of the compressed triangles and of the octahedral normals, set to three values: each file loads or
/// is refused with an error naming it; none panics.
#[test]
fn damaged_meshopt_streams_fail_cleanly() {
    let (json, bin) = split(&std::fs::read(data("gltf/meshopt/CesiumMan_meshopt.glb")).unwrap());
    let (mut loaded, mut refused) = (0, 0);
    for view in [1, 4] {
        let ext = &json["bufferViews"][view]["extensions"]["EXT_meshopt_compression"];
        let start = ext["byteOffset"].as_u64().unwrap() as usize;
        // Every byte of the first 200, and every 7th after: the header, the control bytes and the data.
        let bytes =
            (start..start + ext["byteLength"].as_u64().unwrap() as usize).filter(|i| i - start < 200 || i % 7 == 0);
        let (l, r) = damaged(&json, &bin, bytes, &["model.glb"]);
        (loaded, refused) = (loaded + l, refused + r);
    }
    assert!(loaded > 0 && refused > 0, "{loaded} loaded, {refused} refused");
}

/// BoxTextured with its one image replaced by `image` (of MIME type `mime`), appended to its binary chunk. For
/// KTX2 the texture names it through `KHR_texture_basisu` alone, required, as glTF-Transform's `etc1s` and `uastc`
/// write it; `fallback` keeps the core PNG `source` beside it and requires nothing.
pub(crate) fn box_with_image(image: &[u8], mime: &str, fallback: bool) -> (Value, Vec<u8>) {
    let (mut json, mut bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    bin.resize(bin.len().next_multiple_of(4), 0);
    let offset = bin.len();
    bin.extend(image);
    let views = json["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": image.len()}));
    let view = views.len() - 1;
    json["buffers"][0]["byteLength"] = json!(bin.len());
    if mime != "image/ktx2" {
        json["images"][0] = json!({"bufferView": view, "mimeType": mime});
        return (json, bin);
    }
    json["images"].as_array_mut().unwrap().push(json!({"bufferView": view, "mimeType": mime}));
    json["textures"][0]["extensions"] = json!({"KHR_texture_basisu": {"source": 1}});
    json["extensionsUsed"] = json!(["KHR_texture_basisu"]);
    if !fallback {
        json["textures"][0].as_object_mut().unwrap().remove("source");
        json["extensionsRequired"] = json!(["KHR_texture_basisu"]);
    }
    (json, bin)
}

/// The texture's RGBA bytes as vvgen loads `json` and `bin`.
fn texture_of(json: &Value, bin: &[u8]) -> image::RgbaImage {
    let tmp = tempfile::tempdir().unwrap();
    let a = gltf::load_slice(&join(json, bin), &tmp.path().join("model.glb"), None).unwrap_or_else(|e| panic!("{e}"));
    let t = &a.textures[0];
    image::RgbaImage::from_raw(t.width, t.height, t.rgba.clone()).unwrap()
}

/// KTX2 textures (`KHR_texture_basisu`) load as Binomial's own transcoder (basisu 2.50, `-unpack`, its RGBA32
/// output) transcodes them, byte for byte: ETC1S (BasisLZ) and UASTC (Zstandard), mipmapped, 211 texels square
/// (not a whole number of blocks), made by basisu from BoxTextured's PNG; and two files from glTF-Transform's tests,
/// made by KTX-Software. The ETC1S box is lossy but its own picture: near its PNG.
#[test]
fn ktx2_textures_load_as_binomials_transcoder_decodes_them() {
    for name in ["BoxTextured_etc1s", "BoxTextured_uastc", "2d_etc1s", "2d_uastc"] {
        let ktx2 = std::fs::read(data(&format!("gltf/ktx2/{name}.ktx2"))).unwrap();
        let want = image::open(data(&format!("gltf/ktx2/{name}.png"))).unwrap().to_rgba8();
        let (json, bin) = box_with_image(&ktx2, "image/ktx2", false);
        let got = texture_of(&json, &bin);
        assert_eq!(got.dimensions(), want.dimensions(), "{name}");
        let differ = got.pixels().zip(want.pixels()).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{name}: {differ} texels differ from the reference transcoder's");
    }
    let (json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    let png = texture_of(&json, &bin);
    let ktx2 = std::fs::read(data("gltf/ktx2/BoxTextured_etc1s.ktx2")).unwrap();
    let (json, bin) = box_with_image(&ktx2, "image/ktx2", false);
    let etc1s = texture_of(&json, &bin);
    let off = png.pixels().zip(etc1s.pixels()).map(|(a, b)| (0..3).map(|c| a[c].abs_diff(b[c]) as u32).sum::<u32>());
    let mean = off.sum::<u32>() as f64 / (3 * png.len() / 4) as f64;
    assert!(mean < 4.0, "the ETC1S texture is BoxTextured's picture: {mean} levels off on average");
}

/// A texture with a KTX2 image and a PNG fallback (the extension optional) shows the PNG, as Blender's importer
/// does: the KTX2 image is a lossy copy of it.
#[test]
fn a_ktx2_texture_with_a_png_fallback_shows_the_png() {
    let (json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    let ktx2 = std::fs::read(data("gltf/ktx2/BoxTextured_etc1s.ktx2")).unwrap();
    let (with, with_bin) = box_with_image(&ktx2, "image/ktx2", true);
    assert_eq!(texture_of(&with, &with_bin), texture_of(&json, &bin));
}

/// A box textured with KTX2 alone runs through `new`, `check` and `build` from its folder, as a newcomer runs them,
/// and its images are those of the same box with the reference transcoder's PNG.
#[test]
fn a_ktx2_textured_box_builds_as_its_transcoded_twin() {
    let tmp = tempfile::tempdir().unwrap();
    let mut images = Vec::new();
    for (name, file, mime) in
        [("ktx2", "BoxTextured_uastc.ktx2", "image/ktx2"), ("png", "BoxTextured_uastc.png", "image/png")]
    {
        let dir = tmp.path().join(name);
        std::fs::create_dir(&dir).unwrap();
        let (json, bin) = box_with_image(&std::fs::read(data(&format!("gltf/ktx2/{file}"))).unwrap(), mime, false);
        std::fs::write(dir.join("box.glb"), join(&json, &bin)).unwrap();
        let (code, err) = vvgen(&dir, &["new", "box.glb", "-o", "m.toml"]);
        assert_eq!(code, 0, "{err}");
        let manifest = std::fs::read_to_string(dir.join("m.toml")).unwrap();
        // Two small views keep it quick; the rest is what `new` wrote.
        let manifest = manifest.replace("[400, 400]", "[96, 96]").replace("views = 100", "views = 2");
        std::fs::write(dir.join("m.toml"), manifest).unwrap();
        for command in ["check", "build"] {
            let (code, err) = vvgen(&dir, &["-q", command, "m.toml"]);
            assert_eq!(code, 0, "{name} {command}: {err}");
        }
        images.push(image::open(dir.join("out/box/box_dnerf/train/r_0000.png")).unwrap().to_rgba8());
    }
    let shades: std::collections::BTreeSet<_> = images[0].pixels().filter(|p| p[3] == 255).map(|p| p.0).collect();
    assert!(shades.len() > 20, "the texture shows: {} shades", shades.len());
    assert_eq!(images[0], images[1], "the KTX2 box's image is its transcoded twin's");
}

/// KTX2 images vvgen cannot read are errors naming the file and the image, with what is wrong, in `check` as in
/// `build`: an uncompressed RGBA8 one (glTF-Transform's test file; `KHR_texture_basisu` allows Basis Universal
/// only), a cube map, absurd sides, a Zstandard level that claims to inflate to 1 TiB, a level index past the end.
#[test]
fn bad_ktx2_images_are_errors_naming_the_image() {
    let uastc = std::fs::read(data("gltf/ktx2/BoxTextured_uastc.ktx2")).unwrap();
    let edit = |at: usize, value: &[u8]| {
        let mut k = uastc.clone();
        k[at..at + value.len()].copy_from_slice(value);
        k
    };
    let cases = [
        (
            std::fs::read(data("gltf/ktx2/2d_rgba8.ktx2")).unwrap(),
            "is not Basis Universal's ETC1S or UASTC (vkFormat 43",
        ),
        (edit(36, &6u32.to_le_bytes()), "is not one 2D image (0 deep, 0 layers, 6 faces)"),
        (edit(20, &100_000u32.to_le_bytes()), "is 100000 × 211 texels"),
        (edit(80 + 16, &(1u64 << 40).to_le_bytes()), "level 0 runs past the file or states an impossible size"),
        (edit(40, &1_000_000u32.to_le_bytes()), "is truncated"),
        (uastc[..60].to_vec(), "is truncated"),
    ];
    for (ktx2, says) in cases {
        let (json, bin) = box_with_image(&ktx2, "image/ktx2", false);
        refused_by_check_and_build(&json, &bin, &["model.glb", "images[1]: a KTX2 image", says]);
    }
}

/// Every byte of two KTX2 files (ETC1S and UASTC, made by KTX-Software) set to three values: each loads or is
/// refused with an error naming the image; none panics.
#[test]
fn damaged_ktx2_images_fail_cleanly() {
    let (mut loaded, mut refused) = (0, 0);
    for name in ["2d_etc1s", "2d_uastc"] {
        let ktx2 = std::fs::read(data(&format!("gltf/ktx2/{name}.ktx2"))).unwrap();
        let (json, bin) = box_with_image(&ktx2, "image/ktx2", false);
        let start = bin.len() - ktx2.len();
        let (l, r) = damaged(&json, &bin, start..bin.len(), &["model.glb", "images[1]"]);
        (loaded, refused) = (loaded + l, refused + r);
    }
    assert!(loaded > 0 && refused > 0, "{loaded} loaded, {refused} refused");
}

/// Images decode in parallel, but a file with two bad ones is refused for the first in its order, every time.
#[test]
fn of_two_bad_images_the_first_is_reported() {
    let ktx2 = std::fs::read(data("gltf/ktx2/2d_uastc.ktx2")).unwrap();
    let (mut json, mut bin) = box_with_image(&ktx2[..60], "image/ktx2", false);
    // A second texture on a second, also truncated, KTX2 image (PNG's magic bytes and nothing else).
    let offset = bin.len().next_multiple_of(4);
    bin.resize(offset, 0);
    bin.extend(b"\x89PNG\r\n\x1a\n");
    let views = json["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": 8}));
    let view = views.len() - 1;
    json["images"].as_array_mut().unwrap().push(json!({"bufferView": view, "mimeType": "image/png"}));
    json["textures"].as_array_mut().unwrap().push(json!({"source": 2}));
    json["buffers"][0]["byteLength"] = json!(bin.len());
    let tmp = tempfile::tempdir().unwrap();
    for _ in 0..20 {
        let e = gltf::load_slice(&join(&json, &bin), &tmp.path().join("model.glb"), None).map(|_| ()).unwrap_err();
        let e = e.to_string();
        assert!(e.contains("images[1]: a KTX2 image is truncated"), "{e}");
    }
}

/// A KTX2 image in a file of its own beside a `.gltf` is named by that file in the error.
#[test]
fn a_bad_ktx2_file_beside_a_gltf_is_named() {
    let (mut json, bin) = box_with_image(b"", "image/ktx2", false);
    let tmp = tempfile::tempdir().unwrap();
    json["images"][1] = json!({"uri": "logo.ktx2"});
    json["buffers"][0]["uri"] = json!("box.bin");
    std::fs::write(tmp.path().join("box.bin"), &bin).unwrap();
    std::fs::copy(data("gltf/ktx2/2d_rgba8.ktx2"), tmp.path().join("logo.ktx2")).unwrap();
    std::fs::write(tmp.path().join("box.gltf"), serde_json::to_vec(&json).unwrap()).unwrap();
    let e = gltf::load(&tmp.path().join("box.gltf"), None).map(|_| ()).unwrap_err().to_string();
    assert!(
        e.contains("box.gltf") && e.contains("images[1] (logo.ktx2): a KTX2 image is not Basis Universal's"),
        "{e}"
    );
}
