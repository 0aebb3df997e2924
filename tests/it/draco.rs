//! Draco-compressed glTF meshes (`KHR_draco_mesh_compression`): decoded as Google's own decoder decodes them (the
//! reference files were decoded by glTF-Transform, which runs it), drawn by `new` and `build` from their folder,
//! and a malformed stream is an error naming the file and the primitive, in `check` and `build`, never a panic.

use std::path::Path;
use std::process::Command;

use glam::Mat4;
use serde_json::json;
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
        let tmp = tempfile::tempdir().unwrap();
        std::fs::write(tmp.path().join("model.glb"), join(&doc, &bin)).unwrap();
        let manifest = "[dataset]\nname = \"s\"\nout = \"out\"\n[source.s]\ngltf = \"model.glb\"\n[rig.h]\n\
                        kind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n[output.d]\nwriter = \"dnerf\"\n";
        std::fs::write(tmp.path().join("m.toml"), manifest).unwrap();
        for command in ["check", "build"] {
            let (code, err) = vvgen(tmp.path(), &[command, "m.toml"]);
            assert_eq!(code, 2, "{command}: {err}");
            for part in ["model.glb", "meshes[0].primitives[0]", says] {
                assert!(err.contains(part), "{command}: `{part}` not in {err}");
            }
        }
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
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("model.glb");
    let (mut loaded, mut refused) = (0, 0);
    for at in start..start + length as usize {
        for value in [0u8, 0xff, bin[at] ^ 0x10] {
            let mut damaged = bin.clone();
            damaged[at] = value;
            match gltf::load_slice(&join(&json, &damaged), &path, None) {
                Ok(_) => loaded += 1,
                Err(e) => {
                    let e = e.to_string();
                    assert!(e.contains("model.glb") && e.contains("primitive"), "{e}");
                    refused += 1;
                }
            }
        }
    }
    assert!(loaded > 0 && refused > 0, "{loaded} loaded, {refused} refused");
}
