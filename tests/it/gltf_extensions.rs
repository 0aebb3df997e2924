//! glTF files that require an extension: `KHR_materials_pbrSpecularGlossiness` (many downloads of 2017–2021)
//! loads and renders its diffuse colour, `KHR_mesh_quantization` (gltfpack's and glTF-Transform's output) and
//! `EXT_texture_webp` render as their float and PNG twins, `EXT_mesh_gpu_instancing` copies as the nodes they
//! stand for, and a required extension vvgen does not read is refused with the way out; the material extensions
//! that change how a surface reflects (`KHR_materials_unlit`, `KHR_materials_specular`, `KHR_materials_ior`)
//! render as Blender's importer builds them.

use std::path::Path;
use std::process::Command;

use serde_json::{json, Value};

use crate::common::{data, glb_join as join, glb_split as split};

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Builds `model.glb` in `dir` unlit, two views at 64², and returns the first image's RGBA.
fn render(dir: &Path) -> image::RgbaImage {
    render_with(dir, "[transform]\nfit = \"frame\"\n", "unlit")
}

/// Builds `model.glb` in `dir` placed by `transform` (a table, or nothing) with `shading`, two views at 64², and
/// returns the first image's RGBA.
fn render_with(dir: &Path, transform: &str, shading: &str) -> image::RgbaImage {
    let manifest = format!(
        "[dataset]\nname = \"s\"\nout = \"out\"\npreview = false\n[source.s]\ngltf = \"model.glb\"\n\
         {transform}[render]\nresolution = [64, 64]\nshading = \"{shading}\"\n{TWO_VIEWS}"
    );
    first_image(dir, &manifest)
}

/// A manifest's tail: two hemisphere views, a D-NeRF output.
const TWO_VIEWS: &str =
    "[rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n[output.d]\nwriter = \"dnerf\"\n";

/// Builds `manifest` as `m.toml` in `dir` and returns its first training image's RGBA.
fn first_image(dir: &Path, manifest: &str) -> image::RgbaImage {
    std::fs::write(dir.join("m.toml"), manifest).unwrap();
    let (code, err) = vvgen(dir, &["-q", "build", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    image::open(dir.join("out/s_dnerf/train/r_0000.png")).unwrap().to_rgba8()
}

/// A folder holding `model.glb` of `json` and `bin`.
fn model(json: &Value, bin: &[u8]) -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("model.glb"), join(json, bin)).unwrap();
    d
}

/// BoxTextured with its material in the specular-glossiness model, as a dielectric (specular 0.04): the
/// diffuse texture is then the base colour, and the images are BoxTextured's, though the file's core
/// metallic-roughness colour is black (as in the downloads that carry both: the extension wins, as in Blender).
#[test]
fn a_specular_glossiness_dielectric_renders_as_its_metallic_roughness_twin() {
    let (json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    let twin = model(&json, &bin);
    let want = render(twin.path());

    let mut sg = json.clone();
    let texture = sg["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"].clone();
    assert!(texture.is_object(), "BoxTextured has a base colour texture");
    sg["materials"][0]["pbrMetallicRoughness"] = json!({"baseColorFactor": [0, 0, 0, 1]});
    sg["materials"][0]["extensions"] = json!({"KHR_materials_pbrSpecularGlossiness": {
        "diffuseTexture": texture, "specularFactor": [0.04, 0.04, 0.04], "glossinessFactor": 0.5}});
    sg["extensionsUsed"] = json!(["KHR_materials_pbrSpecularGlossiness"]);
    sg["extensionsRequired"] = json!(["KHR_materials_pbrSpecularGlossiness"]);
    let tmp = model(&sg, &bin);
    let got = render(tmp.path());
    assert!(want.pixels().filter(|p| p[3] == 255).count() > 500, "the box is in view");
    let worst = want.pixels().zip(got.pixels()).flat_map(|(a, b)| (0..4).map(|c| a[c].abs_diff(b[c]))).max();
    assert!(worst <= Some(1), "the dielectric's images differ from the twin's by up to {worst:?} levels");

    // The same texture read as a coloured metal's specular instead: no longer the twin.
    sg["materials"][0]["extensions"] = json!({"KHR_materials_pbrSpecularGlossiness": {
        "diffuseFactor": [0, 0, 0, 1], "specularGlossinessTexture": texture, "specularFactor": [1, 1, 1]}});
    let metal = model(&sg, &bin);
    let got = render(metal.path());
    let differ = want.pixels().zip(got.pixels()).filter(|(a, b)| a[0].abs_diff(b[0]) > 8).count();
    assert!(differ == 0, "unlit, a metal's base colour is its specular colour: {differ} pixels differ");
}

/// A required extension vvgen does not read: every command refuses the file, naming it, the extension and
/// the way out, with exit 2.
#[test]
fn a_required_extension_vvgen_does_not_read_is_refused_with_the_way_out() {
    let (mut json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    // AVIF textures have glTF-Transform's converter (Blender's importer refuses them); material extensions Blender
    // reads, Blender; any other, the tool that wrote it. (Compressed meshes, Draco and meshopt, and KTX2 textures
    // are read: `super::compressed`.)
    let cases = [
        ("EXT_texture_avif", ["AVIF", "Blender's importer does not read either", "cli png", "--formats"]),
        ("KHR_materials_transmission", ["does not read.", "Blender", "blend = ", "without"]),
        ("EXT_made_up", ["neither vvgen nor Blender", "importer reads", "its tool", "without `EXT_made_up`"]),
    ];
    for (ext, way_out) in cases {
        json["extensionsUsed"] = json!([ext]);
        json["extensionsRequired"] = json!([ext]);
        let tmp = model(&json, &bin);
        let d = tmp.path();
        let (code, err) = vvgen(d, &["new", "model.glb"]);
        assert_eq!(code, 2, "{err}");
        let named = format!("`{ext}`");
        for says in ["model.glb", named.as_str()].into_iter().chain(way_out) {
            assert!(err.contains(says), "`{says}` not in: {err}");
        }
    }
}

/// A file may require an extension vvgen reads whether or not it is required: shadeless materials (scans'
/// exports require `KHR_materials_unlit`), the dielectric layer's IOR and colour, material variants (whose
/// default look is the primitives' own materials) and animation pointers. Each builds and renders as the same
/// file that only uses it (all four were refused with "does not read").
#[test]
fn a_required_extension_vvgen_reads_renders_as_the_file_that_only_uses_it() {
    let (json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    let mut second = json["materials"][0].clone();
    second["pbrMetallicRoughness"] = json!({"baseColorFactor": [1, 0, 0, 1]});
    let cases = [
        ("KHR_materials_unlit", json!({"KHR_materials_unlit": {}})),
        ("KHR_materials_ior", json!({"KHR_materials_ior": {"ior": 1.33}})),
        ("KHR_materials_specular", json!({"KHR_materials_specular": {"specularFactor": 0.5}})),
        ("KHR_animation_pointer", json!({})),
    ];
    for (ext, material_ext) in cases {
        let mut used = json.clone();
        used["materials"][0]["extensions"] = material_ext;
        used["extensionsUsed"] = json!([ext]);
        let want = render_with(model(&used, &bin).path(), "", "pbr");
        let mut required = used.clone();
        required["extensionsRequired"] = json!([ext]);
        let got = render_with(model(&required, &bin).path(), "", "pbr");
        assert!(want.pixels().filter(|p| p[3] == 255).count() > 500, "{ext}: the box is in view");
        assert_eq!(want, got, "{ext}: required, the file renders otherwise");
    }
    // Variants: a second, red material mapped to variant `red`; the default look is the texture's.
    let mut variants = json.clone();
    variants["materials"] = json!([json["materials"][0], second]);
    variants["extensions"] = json!({"KHR_materials_variants": {"variants": [{"name": "red"}]}});
    variants["meshes"][0]["primitives"][0]["extensions"] =
        json!({"KHR_materials_variants": {"mappings": [{"material": 1, "variants": [0]}]}});
    variants["extensionsUsed"] = json!(["KHR_materials_variants"]);
    variants["extensionsRequired"] = json!(["KHR_materials_variants"]);
    assert_eq!(render(model(&json, &bin).path()), render(model(&variants, &bin).path()), "variants: the default look");
}

/// BoxTextured quantized as gltfpack quantizes (`KHR_mesh_quantization`): positions as unnormalized 16-bit
/// integers scaled back by their node, normals as normalized bytes, texture coordinates as unnormalized bytes.
/// Every value dequantizes exactly, so its images are the float file's, unlit and lit; nothing rescales the
/// subject to fit (a dequantizing scale read wrongly would show).
#[test]
fn a_quantized_mesh_renders_as_its_float_twin() {
    let (json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    let floats = |acc: usize| -> Vec<f32> {
        let a = &json["accessors"][acc];
        let view = &json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let at = (view["byteOffset"].as_u64().unwrap() + a["byteOffset"].as_u64().unwrap_or(0)) as usize;
        let n = a["count"].as_u64().unwrap() as usize * if a["type"] == "VEC2" { 2 } else { 3 };
        bin[at..at + 4 * n].chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect()
    };
    let attributes = json["meshes"][0]["primitives"][0]["attributes"].clone();
    let index = |name: &str| attributes[name].as_u64().unwrap() as usize;
    let (positions, normals, uvs) = (floats(index("POSITION")), floats(index("NORMAL")), floats(index("TEXCOORD_0")));
    // The box's corners are ±0.5: 16 384 × 2⁻¹⁵. Its normals are axes (±127 normalized is ±1), its uvs 0 … 6.
    let mut q = bin.clone();
    let mut chunk = |bytes: Vec<u8>| -> (usize, usize) {
        let at = q.len();
        q.extend(&bytes);
        q.resize(q.len().next_multiple_of(4), 0);
        (at, bytes.len())
    };
    // Each element padded to 4 bytes, as glTF 2.0 § 3.6.2.4 asks of vertex attributes: strides 8, 4 and 4.
    let padded = |values: Vec<u8>, size: usize, stride: usize| -> Vec<u8> {
        values.chunks_exact(size).flat_map(|e| e.iter().copied().chain(std::iter::repeat_n(0, stride - size))).collect()
    };
    let p16: Vec<u8> = positions.iter().flat_map(|&v| ((v * 32768.0).round() as i16).to_le_bytes()).collect();
    let n8: Vec<u8> = normals.iter().map(|&v| (v * 127.0).round() as i8 as u8).collect();
    let t8: Vec<u8> = uvs.iter().map(|&v| v.round() as u8).collect();
    assert!(uvs.iter().all(|v| (v - v.round()).abs() < 1e-6), "BoxTextured's uvs are whole numbers");
    let (p, n, t) = (chunk(padded(p16, 6, 8)), chunk(padded(n8, 3, 4)), chunk(padded(t8, 2, 4)));
    let mut qj = json.clone();
    let views = qj["bufferViews"].as_array_mut().unwrap();
    let first = views.len();
    for ((at, len), stride) in [(p, 8), (n, 4), (t, 4)] {
        views.push(json!({"buffer": 0, "byteOffset": at, "byteLength": len, "byteStride": stride}));
    }
    let accessors = qj["accessors"].as_array_mut().unwrap();
    let count = positions.len() / 3;
    let base = accessors.len();
    accessors.push(json!({"bufferView": first, "componentType": 5122, "count": count, "type": "VEC3",
        "min": [-16384, -16384, -16384], "max": [16384, 16384, 16384]}));
    accessors.push(json!({"bufferView": first + 1, "componentType": 5120, "normalized": true, "count": count,
        "type": "VEC3"}));
    accessors.push(json!({"bufferView": first + 2, "componentType": 5121, "count": count, "type": "VEC2"}));
    qj["meshes"][0]["primitives"][0]["attributes"] =
        json!({"POSITION": base, "NORMAL": base + 1, "TEXCOORD_0": base + 2});
    qj["buffers"][0]["byteLength"] = json!(q.len());
    // The mesh moves to a child node whose scale dequantizes it.
    let mesh_node = (0..qj["nodes"].as_array().unwrap().len()).find(|&i| qj["nodes"][i]["mesh"] == 0).unwrap();
    qj["nodes"][mesh_node].as_object_mut().unwrap().remove("mesh");
    let child = qj["nodes"].as_array().unwrap().len();
    qj["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!({"mesh": 0, "scale": [1.0 / 32768.0, 1.0 / 32768.0, 1.0 / 32768.0]}));
    qj["nodes"][mesh_node]["children"] = json!([child]);
    qj["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    qj["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    for shading in ["unlit", "pbr"] {
        let (twin, quantized) = (model(&json, &bin), model(&qj, &q));
        let (want, got) = (render_with(twin.path(), "", shading), render_with(quantized.path(), "", shading));
        let covered = want.pixels().filter(|p| p[3] == 255).count();
        assert!((200..2000).contains(&covered), "the 1 m box is in view at its size: {covered} pixels");
        let worst = want.pixels().zip(got.pixels()).flat_map(|(a, b)| (0..4).map(|c| a[c].abs_diff(b[c]))).max();
        assert!(worst <= Some(1), "{shading}: the quantized box's image differs from the float one's by {worst:?}");
    }
}

/// BoxTextured with its texture as a WebP image only (`EXT_texture_webp` required, no core `source`, as
/// glTF-Transform's `webp` writes it): lossless, so its images are the PNG file's.
#[test]
fn a_webp_texture_renders_as_its_png_twin() {
    let (json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    let image = &json["images"][0];
    let view = &json["bufferViews"][image["bufferView"].as_u64().unwrap() as usize];
    let at = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    let png = &bin[at..at + view["byteLength"].as_u64().unwrap() as usize];
    let rgba = image::load_from_memory(png).unwrap().to_rgba8();
    let mut webp = Vec::new();
    image::codecs::webp::WebPEncoder::new_lossless(&mut webp)
        .encode(rgba.as_raw(), rgba.width(), rgba.height(), image::ExtendedColorType::Rgba8)
        .unwrap();
    assert!(webp.starts_with(b"RIFF"), "a WebP file");
    let mut w = bin.clone();
    w.resize(w.len().next_multiple_of(4), 0);
    let offset = w.len();
    w.extend(&webp);
    let mut wj = json.clone();
    let views = wj["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": webp.len()}));
    let webp_view = views.len() - 1;
    wj["images"] = json!([{"bufferView": webp_view, "mimeType": "image/webp"}]);
    for t in wj["textures"].as_array_mut().unwrap() {
        let t = t.as_object_mut().unwrap();
        t.remove("source");
        t.insert("extensions".into(), json!({"EXT_texture_webp": {"source": 0}}));
    }
    wj["buffers"][0]["byteLength"] = json!(w.len());
    wj["extensionsUsed"] = json!(["EXT_texture_webp"]);
    wj["extensionsRequired"] = json!(["EXT_texture_webp"]);
    let (twin, webp_dir) = (model(&json, &bin), model(&wj, &w));
    let (want, got) = (render(twin.path()), render(webp_dir.path()));
    let shades: std::collections::BTreeSet<_> = want.pixels().filter(|p| p[3] == 255).map(|p| p.0).collect();
    assert!(shades.len() > 20, "the texture shows: {} shades", shades.len());
    let worst = want.pixels().zip(got.pixels()).flat_map(|(a, b)| (0..4).map(|c| a[c].abs_diff(b[c]))).max();
    assert!(worst <= Some(1), "the WebP box's image differs from the PNG one's by {worst:?} levels");
}

/// Builds `model.glb` when `subject` (no fit), beside a ground plane when `floor`, lit by an oblique sun and the studio map, two
/// views at 64², and returns the first image's RGBA.
fn render_lit(dir: &Path, floor: bool, subject: bool) -> image::RgbaImage {
    let mut m = String::from("[dataset]\nname = \"s\"\nout = \"out\"\npreview = false\n");
    if subject {
        m += "[source.s]\ngltf = \"model.glb\"\n";
    }
    if floor {
        m += "[source.floor]\nplane = { size = [6, 6], z = -0.5 }\n";
    }
    m += "[render]\nresolution = [64, 64]\nshading = \"pbr\"\n\
          [light.sun]\nkind = \"sun\"\ndirection = [0.5, 0.3, -0.8]\nintensity = 2\n";
    first_image(dir, &(m + TWO_VIEWS))
}

/// `KHR_materials_unlit`, as Blender's importer builds it (an Emission of the base colour seen by camera rays
/// only): lit, the box shows its texture as unlit shading does, and it is transparent to every other ray: the
/// ground around it is lit as if the box were not there (no shadow, no occlusion, no bounce). The same box with
/// its ordinary material shades and shadows.
#[test]
fn a_shadeless_material_shows_its_colour_and_casts_no_shadow() {
    let (json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    let mut unlit = json.clone();
    unlit["materials"][0]["extensions"] = json!({"KHR_materials_unlit": {}});
    unlit["extensionsUsed"] = json!(["KHR_materials_unlit"]);
    let (plain_dir, unlit_dir) = (model(&json, &bin), model(&unlit, &bin));
    let albedo = render_with(plain_dir.path(), "", "unlit");
    let differ = |a: &image::RgbaImage, b: &image::RgbaImage, at: &dyn Fn(usize) -> bool| {
        a.pixels()
            .zip(b.pixels())
            .enumerate()
            .filter(|(i, _)| at(*i))
            .map(|(_, (p, q))| (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap())
            .max()
            .unwrap_or(0)
    };
    let on_box = |i: usize| albedo.as_raw()[4 * i + 3] == 255;
    assert!((0..64 * 64).filter(|&i| on_box(i)).count() > 200, "the box is in view");
    let lit_unlit = render_lit(unlit_dir.path(), false, true);
    let lit_plain = render_lit(plain_dir.path(), false, true);
    assert!(differ(&albedo, &lit_unlit, &on_box) <= 1, "lit, a shadeless box shows its albedo");
    assert!(differ(&albedo, &lit_plain, &on_box) > 16, "lit, an ordinary box is shaded");
    // The ground where the box is not: as bare ground with the shadeless box, shadowed with the ordinary one.
    let off_box = |i: usize| albedo.as_raw()[4 * i + 3] == 0;
    let bare = render_lit(tempfile::tempdir().unwrap().path(), true, false);
    let with_unlit = render_lit(unlit_dir.path(), true, true);
    let with_plain = render_lit(plain_dir.path(), true, true);
    assert!(differ(&bare, &with_unlit, &off_box) <= 1, "the shadeless box changes no light on the ground");
    assert!(differ(&bare, &with_plain, &off_box) > 16, "the ordinary box shadows the ground");
    // Untextured, `vvgen new` writes a one-colour box lit (its shape shows only so), a shadeless one unlit.
    for (shadeless, lit) in [(false, true), (true, false)] {
        let mut j = if shadeless { unlit.clone() } else { json.clone() };
        j["materials"][0]["pbrMetallicRoughness"].as_object_mut().unwrap().remove("baseColorTexture");
        let d = model(&j, &bin);
        let (code, err) = vvgen(d.path(), &["new", "model.glb", "-o", "n.toml"]);
        assert_eq!(code, 0, "{err}");
        let text = std::fs::read_to_string(d.path().join("n.toml")).unwrap();
        assert_eq!(text.contains("shading        = \"pbr\""), lit, "shadeless {shadeless}:\n{text}");
    }
}

/// A material extension that changes a surface's look far past what vvgen draws (here glass) is warned of by
/// `check`, naming the material and how it renders; the file still builds.
#[test]
fn a_material_extension_vvgen_does_not_draw_is_warned_of() {
    let (mut json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    json["materials"][0]["name"] = json!("Glass");
    json["materials"][0]["extensions"] = json!({"KHR_materials_transmission": {"transmissionFactor": 1.0}});
    json["extensionsUsed"] = json!(["KHR_materials_transmission"]);
    let tmp = model(&json, &bin);
    render(tmp.path());
    let (code, err) = vvgen(tmp.path(), &["check", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    for says in ["model.glb", "material 0 (`Glass`) uses `KHR_materials_transmission`", "opaque"] {
        assert!(err.contains(says), "`{says}` not in: {err}");
    }
}

/// `KHR_materials_specular`'s factor is the dielectric layer's weight: Blender 4.5 exports a matte material
/// (Specular IOR Level 0) as `specularFactor: 0`, which renders without reflection; the factor 1 is the
/// material without the extension, byte for byte.
#[test]
fn a_specular_factor_weighs_the_dielectric_layer() {
    let (json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    let with = |factor: Option<f64>| {
        let mut j = json.clone();
        if let Some(f) = factor {
            j["materials"][0]["extensions"] = json!({"KHR_materials_specular": {"specularFactor": f}});
            j["extensionsUsed"] = json!(["KHR_materials_specular"]);
        }
        let d = model(&j, &bin);
        let asset = vvgen::scene::gltf::load(&d.path().join("model.glb"), None).unwrap();
        let lit = render_with(d.path(), "[transform]\nfit = \"frame\"\n", "pbr");
        (asset.materials[0].specular, lit)
    };
    let (plain, plain_lit) = with(None);
    let (one, one_lit) = with(Some(1.0));
    let (matte, matte_lit) = with(Some(0.0));
    let (half, _) = with(Some(0.5));
    assert_eq!((plain, one, matte, half), (1.0, 1.0, 0.0, 0.5));
    assert!(plain_lit == one_lit, "the factor 1 is the material without the extension");
    let differ = plain_lit.pixels().zip(matte_lit.pixels()).filter(|(a, b)| a[0].abs_diff(b[0]) > 2).count();
    assert!(differ > 50, "without its dielectric layer the box renders otherwise: {differ} pixels differ");
}

/// `KHR_materials_ior` and `KHR_materials_specular`'s colour set the dielectric layer's reflectance at normal
/// incidence, as Blender's importer sets the Principled BSDF's IOR and Specular Tint. On a black box, where that
/// layer is all that shows: glTF's default IOR (1.5) is the file without the extension byte for byte, water's
/// (1.33) reflects less and 2 more; a colour tints the reflection; and the extension's textures (the colour's
/// sRGB, the strength's alpha, here one image for both) act as the factors they hold do.
#[test]
fn an_ior_and_a_specular_colour_set_the_dielectric_reflection() {
    let (mut json, mut bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    json["materials"][0]["pbrMetallicRoughness"] =
        json!({"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.3});
    // A 4 × 4 image of one texel: colour sRGB (255, 137, 137), linear (1, 0.2502, 0.2502); alpha 128/255.
    let texel = image::RgbaImage::from_pixel(4, 4, image::Rgba([255, 137, 137, 128]));
    let mut png = std::io::Cursor::new(Vec::new());
    texel.write_to(&mut png, image::ImageFormat::Png).unwrap();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let offset = bin.len();
    bin.extend(png.get_ref());
    json["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": 0, "byteOffset": offset, "byteLength": png.get_ref().len()}));
    json["images"] =
        json!([{"bufferView": json["bufferViews"].as_array().unwrap().len() - 1, "mimeType": "image/png"}]);
    json["buffers"][0]["byteLength"] = json!(bin.len());
    let with = |ext: Value| {
        let mut j = json.clone();
        if ext != json!({}) {
            j["extensionsUsed"] = json!(ext.as_object().unwrap().keys().collect::<Vec<_>>());
            j["materials"][0]["extensions"] = ext;
        }
        let d = model(&j, &bin);
        let asset = vvgen::scene::gltf::load(&d.path().join("model.glb"), None).unwrap();
        let lit = render_with(d.path(), "[transform]\nfit = \"frame\"\n", "pbr");
        (asset.materials[0].specular_f0, lit)
    };
    // Mean red, green and blue over the box.
    let mean = |im: &image::RgbaImage| {
        let on: Vec<_> = im.pixels().filter(|p| p[3] == 255).collect();
        assert!(on.len() > 200, "the box is in view");
        [0, 1, 2].map(|c| on.iter().map(|p| p[c] as f64).sum::<f64>() / on.len() as f64)
    };
    let (plain_f0, plain) = with(json!({}));
    let (default_f0, default) = with(json!({"KHR_materials_ior": {"ior": 1.5}}));
    let (water_f0, water) = with(json!({"KHR_materials_ior": {"ior": 1.33}}));
    let (dense_f0, dense) = with(json!({"KHR_materials_ior": {"ior": 2.0}}));
    assert_eq!((plain_f0.x, default_f0.x), (0.04, 0.04));
    assert!((water_f0.x - 0.0201).abs() < 1e-4 && (dense_f0.x - 1.0 / 9.0).abs() < 1e-6, "{water_f0} {dense_f0}");
    assert!(default == plain, "glTF's default IOR is the file without the extension");
    let [w, p, d] = [&water, &plain, &dense].map(|im| mean(im)[1]);
    assert!(w + 1.0 < p && p + 2.0 < d, "reflection grows with the IOR: {w:.1} < {p:.1} < {d:.1}");
    // A reddish colour: red stays as it was, green and blue fall.
    let factors = json!({"KHR_materials_specular": {"specularColorFactor": [1.0, 0.2502, 0.2502], "specularFactor": 128.0 / 255.0}});
    let (tint_f0, tinted) = with(factors);
    assert!((tint_f0 - glam::Vec3::new(0.04, 0.01001, 0.01001)).abs().max_element() < 1e-5, "{tint_f0}");
    let [r, g, b] = mean(&tinted);
    assert!(r > g + 2.0 && g == b, "the reflection is tinted: {r:.1} {g:.1} {b:.1}");
    let textured =
        json!({"KHR_materials_specular": {"specularColorTexture": {"index": 0}, "specularTexture": {"index": 0}}});
    let (_, from_textures) = with(textured);
    let worst =
        tinted.pixels().zip(from_textures.pixels()).flat_map(|(a, b)| (0..4).map(|c| a[c].abs_diff(b[c]))).max();
    assert!(worst <= Some(1), "the textures act as their factors: {worst:?} levels apart");
    // A texture index past the file's textures is refused, naming it.
    let mut bad = json.clone();
    bad["materials"][0]["extensions"] = json!({"KHR_materials_specular": {"specularTexture": {"index": 7}}});
    let d = model(&bad, &bin);
    let err = vvgen::scene::gltf::load(&d.path().join("model.glb"), None).unwrap_err().to_string();
    assert!(err.contains("KHR_materials_specular.specularTexture.index = 7"), "{err}");
}

/// BoxTextured drawn six times by one node's `EXT_mesh_gpu_instancing` (as gltfpack `-mi` writes it: required;
/// translations and scales as floats, rotations as normalized shorts) renders as six nodes placed by the same
/// numbers, byte for byte, unlit and lit; instances that cannot be read or would pose too many vertices are
/// refused, naming the node.
#[test]
fn instanced_copies_render_as_the_nodes_they_stand_for() {
    let (json, bin) = split(&std::fs::read(data("gltf/BoxTextured/BoxTextured.glb")).unwrap());
    let mesh_node = (0..json["nodes"].as_array().unwrap().len()).find(|&i| json["nodes"][i]["mesh"] == 0).unwrap();
    let placements: Vec<([f32; 3], [i16; 4], [f32; 3])> = (0..6)
        .map(|i| {
            let a = i as f32 * 0.7;
            let (s, c) = (a.sin(), a.cos());
            let q = [s * 0.6, c * 0.6, 0.0, 0.8].map(|v| (v * 32767.0).round() as i16);
            ([i as f32 * 1.5 - 3.75, (i % 2) as f32, -(i as f32) * 0.25], q, [1.0, 0.5 + 0.1 * i as f32, 1.0])
        })
        .collect();
    // What the decoder makes of a normalized short, done the same way.
    let unit = |v: i16| (v as f32 / 32767.0).max(-1.0);

    // Six nodes.
    let mut nodes = json.clone();
    nodes["nodes"][mesh_node].as_object_mut().unwrap().remove("mesh");
    let first = nodes["nodes"].as_array().unwrap().len();
    for (t, q, s) in &placements {
        nodes["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!({"mesh": 0, "translation": t, "rotation": q.map(unit), "scale": s}));
    }
    nodes["nodes"][mesh_node]["children"] = json!((first..first + 6).collect::<Vec<_>>());

    // One node, six instances.
    let (mut inst, mut ibin) = (json.clone(), bin.clone());
    let mut view = |bytes: Vec<u8>, inst: &mut Value| -> usize {
        let at = ibin.len();
        ibin.extend(&bytes);
        ibin.resize(ibin.len().next_multiple_of(4), 0);
        let views = inst["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": at, "byteLength": bytes.len()}));
        views.len() - 1
    };
    let f32s = |v: Vec<f32>| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let t = view(f32s(placements.iter().flat_map(|p| p.0).collect()), &mut inst);
    let r = view(placements.iter().flat_map(|p| p.1).flat_map(i16::to_le_bytes).collect(), &mut inst);
    let s = view(f32s(placements.iter().flat_map(|p| p.2).collect()), &mut inst);
    let accessors = inst["accessors"].as_array_mut().unwrap();
    let base = accessors.len();
    accessors.push(json!({"bufferView": t, "componentType": 5126, "count": 6, "type": "VEC3"}));
    accessors.push(json!({"bufferView": r, "componentType": 5122, "normalized": true, "count": 6, "type": "VEC4"}));
    accessors.push(json!({"bufferView": s, "componentType": 5126, "count": 6, "type": "VEC3"}));
    let attributes = json!({"TRANSLATION": base, "ROTATION": base + 1, "SCALE": base + 2});
    inst["nodes"][mesh_node]["extensions"] = json!({"EXT_mesh_gpu_instancing": {"attributes": attributes}});
    inst["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
    inst["extensionsRequired"] = json!(["EXT_mesh_gpu_instancing"]);
    inst["buffers"][0]["byteLength"] = json!(ibin.len());

    let one = render(model(&json, &bin).path()).pixels().filter(|p| p[3] == 255).count();
    for shading in ["unlit", "pbr"] {
        let fit = "[transform]\nfit = \"frame\"\n";
        let (six, copies) = (model(&nodes, &bin), model(&inst, &ibin));
        let (want, got) = (render_with(six.path(), fit, shading), render_with(copies.path(), fit, shading));
        let covered = want.pixels().filter(|p| p[3] == 255).count();
        assert!(covered > 0 && covered < one, "six boxes fitted cover less than one: {covered} against {one}");
        assert!(want == got, "{shading}: the instanced copies' image is not the six nodes'");
    }

    // What cannot be read is refused, naming the node and what is wrong.
    let refused = |edit: &dyn Fn(&mut Value), says: &[&str]| {
        let mut bad = inst.clone();
        edit(&mut bad);
        let tmp = model(&bad, &ibin);
        let (code, err) = vvgen(tmp.path(), &["new", "model.glb"]);
        assert_eq!(code, 2, "{err}");
        let node = format!("node {mesh_node}");
        for s in says.iter().chain([&"model.glb", &node.as_str()]) {
            assert!(err.contains(s), "`{s}` not in: {err}");
        }
    };
    let ext = format!("/nodes/{mesh_node}/extensions/EXT_mesh_gpu_instancing/attributes");
    // `count` instances placed by translations alone, read from an accessor without data (zeros).
    let zeros = |j: &mut Value, count: usize| {
        j["accessors"][base]["count"] = json!(count);
        j["accessors"][base].as_object_mut().unwrap().remove("bufferView");
        let e = j.pointer_mut(&ext).unwrap().as_object_mut().unwrap();
        e.remove("ROTATION");
        e.remove("SCALE");
    };
    refused(&|j| *j.pointer_mut(&format!("{ext}/SCALE")).unwrap() = json!(999), &["SCALE names no accessor"]);
    refused(&|j| j["accessors"][base + 2]["count"] = json!(5), &["count different instances"]);
    refused(&|j| j["accessors"][base + 1]["type"] = json!("VEC3"), &["ROTATION", "not a VEC4"]);
    // A zero rotation: no bufferView reads as zeros.
    refused(
        &|j| j["accessors"][base + 1].as_object_mut().unwrap().retain(|k, _| k != "bufferView"),
        &["instance 0 is not a transform"],
    );
    // Twelve copies of a three-million-vertex mesh (zeros, no bufferView): refused before any is posed.
    refused(
        &|j| {
            let big = j["accessors"].as_array().unwrap().len();
            j["accessors"]
                .as_array_mut()
                .unwrap()
                .push(json!({"componentType": 5126, "count": 3_000_000, "type": "VEC3",
                "min": [0, 0, 0], "max": [0, 0, 0]}));
            j["meshes"][0]["primitives"][0] = json!({"attributes": {"POSITION": big}});
            zeros(j, 12);
        },
        &["3000000 vertices 12 times", "keep fewer instances"],
    );
    // Two million copies of the box, asked for in a few bytes (an accessor without data).
    refused(
        &|j| {
            zeros(j, 2_000_000);
        },
        &["2000000 times", "1048576 copies"],
    );
}

/// 3D Gaussians in glTF (`KHR_gaussian_splatting`) are drawn (`clouds::a_gaussian_splatting_file_renders_as_the_
/// splatting_reference`); those vvgen cannot draw as the file means them are refused by `check` and `build`,
/// naming the file and why: another kernel or colour space, no band-0 colour, a value that is not finite, an
/// attribute of another length than POSITION.
#[test]
fn gaussians_in_gltf_that_cannot_be_drawn_are_refused_saying_why() {
    // Two Gaussians: centres, unit quaternions (xyzw), scales, opacities, band-0 colours.
    let floats: Vec<f32> = [
        vec![0.0, 0.0, 0.0, 0.1, 0.0, 0.0],
        vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        vec![0.02; 6],
        vec![0.9, 0.8],
        vec![0.5, 0.2, -0.3, 0.1, 0.4, 0.0],
    ]
    .concat();
    let bin: Vec<u8> = floats.iter().flat_map(|v| v.to_le_bytes()).collect();
    let base = |attributes: Value, ext: Value| {
        json!({
            "asset": { "version": "2.0", "generator": "splat-transform" },
            "extensionsUsed": ["KHR_gaussian_splatting"],
            "buffers": [{ "byteLength": bin.len() }],
            "bufferViews": [
                { "buffer": 0, "byteOffset": 0, "byteLength": 24 }, { "buffer": 0, "byteOffset": 24, "byteLength": 32 },
                { "buffer": 0, "byteOffset": 56, "byteLength": 24 }, { "buffer": 0, "byteOffset": 80, "byteLength": 8 },
                { "buffer": 0, "byteOffset": 88, "byteLength": 24 }
            ],
            "accessors": [
                { "bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [0.1, 0.0, 0.0] },
                { "bufferView": 1, "componentType": 5126, "count": 2, "type": "VEC4" },
                { "bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC3" },
                { "bufferView": 3, "componentType": 5126, "count": 2, "type": "SCALAR" },
                { "bufferView": 4, "componentType": 5126, "count": 2, "type": "VEC3" },
                { "bufferView": 3, "componentType": 5126, "count": 1, "type": "SCALAR" }
            ],
            "meshes": [{ "primitives": [{ "attributes": attributes, "mode": 0, "extensions": { "KHR_gaussian_splatting": ext } }] }],
            "nodes": [{ "mesh": 0 }],
            "scenes": [{ "nodes": [0] }],
            "scene": 0
        })
    };
    let all = json!({ "POSITION": 0, "KHR_gaussian_splatting:ROTATION": 1, "KHR_gaussian_splatting:SCALE": 2,
                      "KHR_gaussian_splatting:OPACITY": 3, "KHR_gaussian_splatting:SH_DEGREE_0_COEF_0": 4 });
    let srgb = json!({ "kernel": "ellipse", "colorSpace": "srgb_rec709_display" });
    let with = |k: &str, v: Value| {
        let mut a = all.clone();
        a[k] = v;
        a
    };
    let mut no_colour = all.clone();
    no_colour.as_object_mut().unwrap().remove("KHR_gaussian_splatting:SH_DEGREE_0_COEF_0");
    let mut nan = bin.clone();
    nan[80..84].copy_from_slice(&f32::NAN.to_le_bytes());
    let cases = [
        (
            base(all.clone(), json!({ "kernel": "customShape", "colorSpace": "srgb_rec709_display" })),
            bin.clone(),
            "kernel `customShape`",
        ),
        (
            base(all.clone(), json!({ "kernel": "ellipse", "colorSpace": "lin_rec709_display" })),
            bin.clone(),
            "colour space `lin_rec709_display`",
        ),
        (base(no_colour, srgb.clone()), bin.clone(), "without KHR_gaussian_splatting:SH_DEGREE_0_COEF_0"),
        (base(all.clone(), srgb.clone()), nan, "Gaussian 0's rotation, scale or opacity is not finite"),
        (
            base(with("KHR_gaussian_splatting:OPACITY", json!(5)), srgb.clone()),
            bin.clone(),
            "KHR_gaussian_splatting:OPACITY: accessor 5 has 1 elements, POSITION has 2",
        ),
    ];
    for (json, bin, says) in cases {
        let d = model(&json, &bin);
        let manifest = format!(
            "[dataset]\nname = \"s\"\nout = \"out\"\npreview = false\n[source.s]\ngltf = \"model.glb\"\n{TWO_VIEWS}"
        );
        std::fs::write(d.path().join("m.toml"), manifest).unwrap();
        for cmd in ["check", "build"] {
            let (code, err) = vvgen(d.path(), &[cmd, "m.toml"]);
            assert_eq!(code, 2, "{cmd}: {err}");
            assert!(err.contains("model.glb") && err.contains(says), "{cmd}: `{says}` not in {err}");
        }
    }
    // Compressed Gaussians (SPZ in glTF) are refused with the uncompressed way out, not Blender's (it reads none).
    let mut spz = base(all.clone(), srgb.clone());
    spz["extensionsRequired"] = json!(["KHR_gaussian_splatting", "KHR_gaussian_splatting_compression_spz_2"]);
    let d = model(&spz, &bin);
    std::fs::write(
        d.path().join("m.toml"),
        format!(
            "[dataset]\nname = \"s\"\nout = \"out\"\npreview = false\n[source.s]\ngltf = \"model.glb\"\n{TWO_VIEWS}"
        ),
    )
    .unwrap();
    let (code, err) = vvgen(d.path(), &["check", "m.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("compressed") && err.contains("splat-transform") && !err.contains("Blender"), "{err}");
    // As written, the two draw, the extension required or not.
    let mut required = base(all, srgb);
    required["extensionsRequired"] = json!(["KHR_gaussian_splatting"]);
    let d = model(&required, &bin);
    let image = first_image(d.path(), &format!("[dataset]\nname = \"s\"\nout = \"out\"\npreview = false\n[source.s]\ngltf = \"model.glb\"\n[transform]\nfit = \"frame\"\n{TWO_VIEWS}"));
    assert!(image.pixels().filter(|p| p[3] > 0).count() > 20);
}
