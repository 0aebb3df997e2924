//! Lights a glTF file brings (`KHR_lights_punctual`): converted to Blender's units as its importer converts them,
//! moved by their animated nodes, keyed per frame in lit builds, switched off by `[render] gltf_lights = false`,
//! and malformed ones refused with the file named.

use std::path::Path;

use crate::common::{load, tree};

/// A 2 × 2 m floor (glTF Y up) with a sun of `lux` pointing straight down and, when `point_cd` is not zero, a point
/// light of that many candela 1 m above the floor, animated from x = 0.6 at t = 0 s to x = −0.6 at t = 1 s.
/// `spot` replaces the point light's definition with a spot's JSON when given.
pub(crate) fn floor_with_lights(lux: f32, point_cd: f32, spot: Option<&str>) -> String {
    use base64::Engine;
    let mut buf: Vec<u8> = Vec::new();
    let mut put = |v: &[f32]| v.iter().for_each(|c| buf.extend(c.to_le_bytes()));
    put(&[-1.0, 0.0, -1.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0, -1.0, 0.0, 1.0]); // positions, 48 bytes
    put(&[0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0]); // normals, 48
    put(&[0.0, 1.0]); // key times, 8
    put(&[0.6, 1.0, 0.0, -0.6, 1.0, 0.0]); // translations, 24
    for i in [0u16, 3, 2, 0, 2, 1] {
        buf.extend(i.to_le_bytes()); // indices, 12
    }
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&buf));
    let point = spot.map_or_else(|| format!(r#"{{"type": "point", "intensity": {point_cd}}}"#), str::to_string);
    let q = std::f32::consts::FRAC_1_SQRT_2;
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0, 1, 2]}}],
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
     {{"type": "directional", "name": "sun", "intensity": {lux}}}, {point}]}}}},
  "nodes": [{{"mesh": 0}},
            {{"rotation": [-{q}, 0, 0, {q}], "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}},
            {{"translation": [0.6, 1, 0], "extensions": {{"KHR_lights_punctual": {{"light": 1}}}}}}],
  "materials": [{{"doubleSided": true, "pbrMetallicRoughness": {{"metallicFactor": 0, "roughnessFactor": 1}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1}}, "indices": 4, "material": 0}}]}}],
  "buffers": [{{"byteLength": {}, "uri": "{uri}"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
                  {{"buffer": 0, "byteOffset": 96, "byteLength": 8}}, {{"buffer": 0, "byteOffset": 104, "byteLength": 24}},
                  {{"buffer": 0, "byteOffset": 128, "byteLength": 12}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]}},
    {{"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}},
    {{"bufferView": 4, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
  "animations": [{{"channels": [{{"sampler": 0, "target": {{"node": 2, "path": "translation"}}}}],
                   "samplers": [{{"input": 2, "output": 3, "interpolation": "LINEAR"}}]}}]}}"#,
        buf.len()
    )
}

/// A lit build of `floor.gltf` (2 frames, one view from above, no environment light) with `extra` lines.
fn manifest(extra: &str) -> String {
    format!(
        "[dataset]\nname = \"f\"\nout = \"out\"\ncache = \"cache\"\npreview = false\n\
         [source.floor]\ngltf = \"floor.gltf\"\nframes = {{ count = 2, fps = 1 }}\n\
         [render]\nresolution = [32, 32]\nsamples = 4\nshading = \"pbr\"\npasses = [\"rgba\", \"albedo\"]\n{extra}\n\
         [environment]\nstrength = 0\n\
         [rig.top]\nkind = \"explicit\"\nposes = [{{ c2w = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]] }}]\n\
         [split.train]\nrig = \"top\"\n[output.d]\nwriter = \"dnerf\"\n"
    )
}

fn build(dir: &Path, gltf: &str, text: &str) -> (vvgen::build::Report, std::collections::BTreeMap<String, Vec<u8>>) {
    std::fs::write(dir.join("floor.gltf"), gltf).unwrap();
    std::fs::write(dir.join("m.toml"), text).unwrap();
    let report =
        vvgen::build::build(&load(&dir.join("m.toml")), &dir.join("cache"), Default::default(), &vvgen::build::Silent)
            .unwrap();
    (report, tree(&dir.join("out")))
}

fn pixels(files: &std::collections::BTreeMap<String, Vec<u8>>, name: &str) -> Vec<u8> {
    let bytes = files.get(&format!("f_dnerf/{name}")).unwrap_or_else(|| panic!("no {name}"));
    image::load_from_memory(bytes).unwrap().into_rgba8().into_raw()
}

#[test]
fn a_files_sun_in_lux_lights_like_the_manifest_sun_blenders_importer_makes_of_it() {
    // Blender's importer: 683 lx is 1 W/m². The file's sun (1366 lx, straight down) against a manifest sun of
    // 2 W/m² straight down with the file's lights off: the same image, ±1 level (the directions differ by rounding).
    let a = tempfile::tempdir().unwrap();
    let (_, file_lit) = build(a.path(), &floor_with_lights(1366.0, 0.0, None), &manifest(""));
    let b = tempfile::tempdir().unwrap();
    let manifest_sun =
        manifest("gltf_lights = false\n[light.sun]\nkind = \"sun\"\ndirection = [0, 0, -1]\nintensity = 2");
    let (_, by_manifest) = build(b.path(), &floor_with_lights(1366.0, 0.0, None), &manifest_sun);
    let (x, y) = (pixels(&file_lit, "train/r_0000.png"), pixels(&by_manifest, "train/r_0000.png"));
    assert!(x.iter().zip(&y).all(|(p, q)| p.abs_diff(*q) <= 1), "the file's sun and the manifest's differ");
    // 2 W/m² on the default white base colour: 2/π linear (sRGB 207), less what the specular layer takes.
    let centre = (16 * 32 + 16) * 4;
    assert!(x[centre].abs_diff(205) <= 3, "{}", x[centre]);
    // Without any light the floor is black: the sun is what lit it.
    let c = tempfile::tempdir().unwrap();
    let (_, dark) = build(c.path(), &floor_with_lights(1366.0, 0.0, None), &manifest("gltf_lights = false"));
    assert_eq!(pixels(&dark, "train/r_0000.png")[centre], 0);
}

#[test]
fn an_animated_light_moves_with_its_node_and_keys_the_lit_frames_only() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let gltf = floor_with_lights(0.0, 100.0, None);
    let (first, files) = build(d, &gltf, &manifest(""));
    // Two lit passes, and one albedo pass: the floor does not move, so both frames' albedo have one key.
    assert_eq!(first.ran(vvgen::plan::actions::Kind::RenderPass), 3);
    let (f0, f1) = (pixels(&files, "train/r_0000.png"), pixels(&files, "train/r_0001.png"));
    // The light is over +x at frame 0 and over −x at frame 1 (x to the right from above, with y up the image).
    let brightness = |p: &[u8], x: usize| (8..24).map(|y| p[(y * 32 + x) * 4] as u32).sum::<u32>();
    assert!(brightness(&f0, 24) > brightness(&f0, 8) + 100, "frame 0 is lit from +x");
    assert!(brightness(&f1, 8) > brightness(&f1, 24) + 100, "frame 1 is lit from −x");
    assert_eq!(pixels(&files, "albedo/train/r_0000.png"), pixels(&files, "albedo/train/r_0001.png"));
    // Nothing changed: nothing runs. A brighter light re-renders the lit passes, not albedo.
    assert!(build(d, &gltf, &manifest("")).0.nothing_to_do());
    let brighter = build(d, &floor_with_lights(0.0, 200.0, None), &manifest("")).0;
    assert_eq!(brighter.ran(vvgen::plan::actions::Kind::RenderPass), 2);
    // Switched off: the light neither shades nor keys, so the two frames render alike.
    let (_, off) = build(d, &gltf, &manifest("gltf_lights = false"));
    assert_eq!(pixels(&off, "train/r_0000.png"), pixels(&off, "train/r_0001.png"));
}

#[test]
fn a_malformed_file_light_is_an_error_naming_the_file_and_the_light() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (
            floor_with_lights(
                1.0,
                1.0,
                Some(r#"{"type": "spot", "spot": {"innerConeAngle": 0.9, "outerConeAngle": 0.5}}"#),
            ),
            "KHR_lights_punctual.lights[1]",
        ),
        (floor_with_lights(1.0, 1.0, Some(r#"{"type": "point", "intensity": -3}"#)), "intensity -3"),
        (floor_with_lights(1.0, 1.0, None).replace(r#""light": 1"#, r#""light": 7"#), "does not index `lights`"),
        (floor_with_lights(1.0, 1.0, Some(r#"{"type": "area"}"#)), "\"area\" is not one of"),
    ];
    for (gltf, want) in cases {
        std::fs::write(d.join("floor.gltf"), &gltf).unwrap();
        std::fs::write(d.join("m.toml"), manifest("")).unwrap();
        let m = load(&d.join("m.toml"));
        let err = vvgen::settings::scene::open(&m, None).expect_err(want).to_string();
        assert!(err.contains("floor.gltf") && err.contains(want), "{err}\n(wanted {want})");
    }
}
