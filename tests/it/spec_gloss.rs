//! glTF files that require `KHR_materials_pbrSpecularGlossiness` (many downloads of 2017–2021) load, and render
//! their diffuse colour; a required extension vvgen does not read is refused with the way out.

use std::path::Path;
use std::process::Command;

use serde_json::{json, Value};

use crate::common::data;

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// A GLB's JSON and BIN chunks.
fn split(glb: &[u8]) -> (Value, Vec<u8>) {
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    let json_len = word(12);
    let json = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    (json, glb[bin_at + 8..bin_at + 8 + word(bin_at)].to_vec())
}

/// A GLB of `json` and `bin`.
fn join(json: &Value, bin: &[u8]) -> Vec<u8> {
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

/// Builds `model.glb` in `dir` unlit, two views at 64², and returns the first image's RGBA.
fn render(dir: &Path) -> image::RgbaImage {
    std::fs::write(
        dir.join("m.toml"),
        "[dataset]\nname = \"s\"\nout = \"out\"\npreview = false\n[source.s]\ngltf = \"model.glb\"\n\
         [transform]\nfit = \"frame\"\n[render]\nresolution = [64, 64]\n\
         [rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n[output.d]\nwriter = \"dnerf\"\n",
    )
    .unwrap();
    let (code, err) = vvgen(dir, &["-q", "build", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    image::open(dir.join("out/s_dnerf/train/r_0000.png")).unwrap().to_rgba8()
}

/// BoxTextured with its material in the specular-glossiness model, as a dielectric (specular 0.04): the
/// diffuse texture is then the base colour, and the images are BoxTextured's, though the file's core
/// metallic-roughness colour is black (as in the downloads that carry both: the extension wins, as in Blender).
#[test]
fn a_specular_glossiness_dielectric_renders_as_its_metallic_roughness_twin() {
    let (json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    let twin = tempfile::tempdir().unwrap();
    std::fs::write(twin.path().join("model.glb"), join(&json, &bin)).unwrap();
    let want = render(twin.path());

    let mut sg = json.clone();
    let texture = sg["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"].clone();
    assert!(texture.is_object(), "BoxTextured has a base colour texture");
    sg["materials"][0]["pbrMetallicRoughness"] = json!({"baseColorFactor": [0, 0, 0, 1]});
    sg["materials"][0]["extensions"] = json!({"KHR_materials_pbrSpecularGlossiness": {
        "diffuseTexture": texture, "specularFactor": [0.04, 0.04, 0.04], "glossinessFactor": 0.5}});
    sg["extensionsUsed"] = json!(["KHR_materials_pbrSpecularGlossiness"]);
    sg["extensionsRequired"] = json!(["KHR_materials_pbrSpecularGlossiness"]);
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("model.glb"), join(&sg, &bin)).unwrap();
    let got = render(tmp.path());
    assert!(want.pixels().filter(|p| p[3] == 255).count() > 500, "the box is in view");
    let worst = want.pixels().zip(got.pixels()).flat_map(|(a, b)| (0..4).map(|c| a[c].abs_diff(b[c]))).max();
    assert!(worst <= Some(1), "the dielectric's images differ from the twin's by up to {worst:?} levels");

    // The same texture read as a coloured metal's specular instead: no longer the twin.
    sg["materials"][0]["extensions"] = json!({"KHR_materials_pbrSpecularGlossiness": {
        "diffuseFactor": [0, 0, 0, 1], "specularGlossinessTexture": texture, "specularFactor": [1, 1, 1]}});
    let metal = tempfile::tempdir().unwrap();
    std::fs::write(metal.path().join("model.glb"), join(&sg, &bin)).unwrap();
    let got = render(metal.path());
    let differ = want.pixels().zip(got.pixels()).filter(|(a, b)| a[0].abs_diff(b[0]) > 8).count();
    assert!(differ == 0, "unlit, a metal's base colour is its specular colour: {differ} pixels differ");
}

/// A required extension vvgen does not read: every command refuses the file, naming it, the extension and
/// the way out, with exit 2.
#[test]
fn a_required_extension_vvgen_does_not_read_is_refused_with_the_way_out() {
    let (mut json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    json["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("model.glb"), join(&json, &bin)).unwrap();
    let (code, err) = vvgen(d, &["new", "model.glb"]);
    assert_eq!(code, 2, "{err}");
    for says in ["model.glb", "`KHR_draco_mesh_compression`", "compressed", "Blender", "blend = "] {
        assert!(err.contains(says), "`{says}` not in: {err}");
    }
}
