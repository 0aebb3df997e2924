//! From a file's bytes to a validated glTF document, and which extensions a file may require: those vvgen reads
//! are let through (editing the document where gltf 1.4 cannot read them itself), any other is refused before
//! gltf's validation, with the way out.

/// Extensions vvgen understands; a file that *requires* any other is refused.
const SUPPORTED_REQUIRED: &[&str] = &[
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
    "KHR_lights_punctual",
    "KHR_materials_pbrSpecularGlossiness",
    // Shadeless materials (scans' and photogrammetry's exports use them) and the dielectric layer's IOR and
    // specular colour: read as Blender's importer reads them (`super::materials`).
    "KHR_materials_unlit",
    "KHR_materials_ior",
    "KHR_materials_specular",
    // Material variants (product configurators): the primitives' own materials are the default look, which
    // viewers and Blender's importer show until a variant is chosen.
    "KHR_materials_variants",
    // Animation channels that target a JSON pointer: those at nodes and morph weights are followed, the others
    // dropped with a warning (`super::pointer`).
    "KHR_animation_pointer",
    // Integer attributes (gltfpack's and glTF-Transform's `quantize` default): the accessor decoder reads every
    // component type, normalized or not, as the spec allows; the dequantizing scale is the nodes' transform.
    "KHR_mesh_quantization",
    // WebP images (glTF-Transform's `webp`; image-to-3D generators' output, TRELLIS 2's among them): `parse`
    // points the texture at its WebP image and the image decoder reads it.
    "EXT_texture_webp",
    // KTX2 images (glTF-Transform's `etc1s` and `uastc`, gltfpack's `-tc`): `parse` points a texture without a core
    // image at its KTX2 image, which `super::image` transcodes.
    "KHR_texture_basisu",
    // A mesh drawn many times (gltfpack's `-mi` requires it): every copy is posed (`super::instancing`).
    "EXT_mesh_gpu_instancing",
    // 3D Gaussians (`super::splats`), required by the files that compress them (refused below) or by choice.
    "KHR_gaussian_splatting",
    // Draco-compressed meshes (Blender's exporter's "Compression", glTF-Transform's `draco`): decoded once, when
    // the file loads (`super::draco`).
    "KHR_draco_mesh_compression",
    // Meshopt-compressed views (gltfpack's `-c`, glTF-Transform's `meshopt`): decoded once, when the file loads
    // (`super::meshopt`).
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
];

/// Extensions Blender 4.5's importer reads that vvgen refuses when a file requires them (the material looks it
/// does not draw, `super::materials`): for those, Blender is the way out.
const BLENDER_READS: &[&str] = &[
    "KHR_materials_clearcoat",
    "KHR_materials_transmission",
    "KHR_materials_sheen",
    "KHR_materials_volume",
    "KHR_materials_anisotropy",
];

/// Parses and validates, except that an accessor without a bufferView is accepted (the spec says it reads as
/// zeros, then sparse values, but gltf 1.4's validation calls it missing data), so is a position accessor
/// without `min` and `max` (as Blender's importer accepts it), and so is a required extension
/// of [`SUPPORTED_REQUIRED`] that gltf 1.4 calls unsupported (`KHR_mesh_quantization`, `EXT_texture_webp`, …).
/// Returns the document and what reading it set aside (dropped pointer channels). vvgen's own reference check
/// ([`super::validate`]) runs first, on the raw JSON, because the crate's validation panics on some dangling
/// references.
pub(super) fn parse(bytes: &[u8]) -> Result<(gltf::Gltf, Vec<String>), String> {
    let (json, bin): (std::borrow::Cow<'_, [u8]>, _) = if bytes.starts_with(b"glTF") {
        if bytes.get(4..8) == Some(&[1, 0, 0, 0]) {
            return Err(version_one("a binary glTF 1.0 file (GLB version 1)"));
        }
        let glb = gltf::Glb::from_slice(bytes).map_err(|e| format!("a truncated or malformed GLB ({e})"))?;
        (glb.json, glb.bin)
    } else if bytes.iter().find(|b| !b.is_ascii_whitespace()) != Some(&b'{') {
        return Err("neither a GLB (it does not start with `glTF`) nor glTF JSON (it does not start with `{`); \
                    a .bin is a glTF's side-car buffer: name the .gltf"
            .into());
    } else {
        (bytes.into(), None)
    };
    let mut doc: serde_json::Value = serde_json::from_slice(&json).map_err(|e| format!("not glTF JSON: {e}"))?;
    if let Some(version) = doc.pointer("/asset/version").and_then(|v| v.as_str()) {
        if version.starts_with("1.") || version.starts_with("0.") {
            return Err(version_one(&format!("glTF {version} (`asset.version`)")));
        }
    } else if ["scenes", "nodes", "meshes", "accessors"].iter().any(|k| doc.get(k).is_some_and(|v| v.is_object())) {
        // glTF 1.0 makes `asset` optional; its objects are keyed by name where 2.0's are arrays.
        return Err(version_one("glTF 1.0 (its objects are keyed by name)"));
    }
    required_extensions(&doc)?;
    super::validate::check(&doc)?;
    // After the check, whose messages name the file's own attributes.
    let splats = super::splats::rename(&mut doc)?;
    let followed = super::pointer::follow(&mut doc)?;
    let edited = image_sources(&mut doc) | scene_nodes(&mut doc) | splats | followed.changed;
    // The JSON is parsed again from the edited document only when there was something to edit.
    let read = |validate: bool| -> Result<gltf::Gltf, gltf::Error> {
        if !edited {
            return if validate {
                gltf::Gltf::from_slice(bytes)
            } else {
                gltf::Gltf::from_slice_without_validation(bytes)
            };
        }
        let blob = bin.as_deref().map(<[u8]>::to_vec);
        let root: gltf::json::Root = serde_json::from_value(doc.clone()).map_err(gltf::Error::Deserialize)?;
        let document = if validate {
            gltf::Document::from_json(root)?
        } else {
            gltf::Document::from_json_without_validation(root)
        };
        Ok(gltf::Gltf { document, blob })
    };
    let parsed = match read(true) {
        Err(gltf::Error::Validation(errors))
            if errors.iter().all(|(p, e)| {
                let p = p.as_str();
                let no_view = p.starts_with("accessors[") && p.ends_with("].bufferView");
                // The spec requires a position accessor's bounds; readers (Blender's importer, three.js) compute
                // them, and so does vvgen, which never reads them.
                let no_bounds = p.ends_with("\"POSITION\"].min") || p.ends_with("\"POSITION\"].max");
                // gltf 1.4 has no feature for some extensions vvgen reads (quantized attributes, WebP images,
                // instancing, Gaussians, pointers …): a required one of [`SUPPORTED_REQUIRED`] is read here.
                let read_here = p.starts_with("extensionsRequired[")
                    && SUPPORTED_REQUIRED.iter().any(|x| p.ends_with(&format!("\"{x}\"")));
                use gltf::json::validation::Error::{Missing, Unsupported};
                ((no_view || no_bounds) && matches!(e, Missing)) || (read_here && matches!(e, Unsupported))
            }) =>
        {
            read(false)
        }
        other => other,
    };
    parsed.map(|gltf| (gltf, followed.warnings)).map_err(|e| e.to_string())
}

/// The error for a file in glTF 1.0, which glTF 2.0 replaced in 2017 (its objects are keyed by name, its materials
/// are shader techniques): `what` says how the file says so. Blender's importer refuses it too.
fn version_one(what: &str) -> String {
    format!(
        "{what}, which vvgen does not read (nor does Blender's importer): glTF 2.0 replaced it. Way out: \
         `npx gltf-pipeline -i in.gltf -o out.glb` upgrades it to glTF 2.0; name that"
    )
}

/// Gives every scene without `nodes` an empty list: the spec makes the key optional (an empty scene, as
/// Blender's exporter writes one), gltf 1.4 calls it a missing field. Returns whether anything changed.
fn scene_nodes(doc: &mut serde_json::Value) -> bool {
    let Some(scenes) = doc.get_mut("scenes").and_then(|s| s.as_array_mut()) else { return false };
    let mut changed = false;
    for scene in scenes.iter_mut().filter_map(|s| s.as_object_mut()) {
        if !scene.contains_key("nodes") {
            scene.insert("nodes".into(), serde_json::Value::Array(Vec::new()));
            changed = true;
        }
    }
    changed
}

/// Points every texture at the image a reader that decodes its extensions would use: an `EXT_texture_webp` image
/// always (the extension's intent: the core `source`, if any, is a fallback of the same picture; Blender's
/// importer does the same), a `KHR_texture_basisu` (KTX2) image only when there is no core `source`. A KTX2 image
/// is lossy and block-compressed: its PNG or JPEG fallback, where there is one, is the picture it was made from
/// and the one Blender's importer shows. Returns whether anything changed.
fn image_sources(doc: &mut serde_json::Value) -> bool {
    let Some(textures) = doc.get_mut("textures").and_then(|t| t.as_array_mut()) else { return false };
    let mut changed = false;
    for t in textures {
        let webp = t.pointer("/extensions/EXT_texture_webp/source").and_then(|s| s.as_u64());
        let ktx2 = t.pointer("/extensions/KHR_texture_basisu/source").and_then(|s| s.as_u64());
        let Some(t) = t.as_object_mut() else { continue };
        let source = webp.or(ktx2.filter(|_| !t.contains_key("source")));
        if let Some(source) = source {
            changed |= t.insert("source".into(), source.into()).is_none_or(|old| old != source);
        }
    }
    changed
}

/// Refuses an extension the file requires and vvgen does not read, saying the way out. Checked on the raw
/// JSON, before gltf's validation, which says only "Unsupported extension".
fn required_extensions(doc: &serde_json::Value) -> Result<(), String> {
    let Some(required) = doc.get("extensionsRequired").and_then(|v| v.as_array()) else { return Ok(()) };
    for (i, ext) in required.iter().enumerate() {
        let Some(ext) = ext.as_str() else { return Err(format!("extensionsRequired[{i}] is not a string")) };
        if SUPPORTED_REQUIRED.contains(&ext) {
            continue;
        }
        if ext.starts_with("KHR_gaussian_splatting_compression") || ext.starts_with("EXT_gaussian_splatting") {
            // Blender reads no Gaussians: the way out is the uncompressed form, which vvgen reads.
            return Err(format!(
                "requires the extension `{ext}`, which vvgen does not read (its 3D Gaussians are compressed). Way \
                 out: write them uncompressed, as `KHR_gaussian_splatting` alone or as a 3D Gaussian splatting PLY, \
                 from the file they were made from (`npx @playcanvas/splat-transform in.ply out.glb`), and name that"
            ));
        }
        // Blender's importer refuses a file that requires an extension it does not manage, so it is a way out only
        // for those it reads; texture formats have their converters.
        return Err(match ext {
            "EXT_texture_avif" => format!(
                "requires the extension `{ext}`, which vvgen does not read (its textures are AVIF, which Blender's \
                 importer does not read either). Way out: `npx @gltf-transform/cli png in.glb out.glb --formats \"*\"` \
                 rewrites them as PNG; name that"
            ),
            _ if BLENDER_READS.contains(&ext) => format!(
                "requires the extension `{ext}`, which vvgen does not read. Way out: import the file in Blender \
                 (File → Import → glTF 2.0), save it as a .blend and name that (`blend = \"….blend\"`), or export it \
                 again from its tool without `{ext}`"
            ),
            _ => format!(
                "requires the extension `{ext}`, which neither vvgen nor Blender's importer reads. Way out: export \
                 the file again from its tool without `{ext}`"
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    /// glTF 1.0, binary or JSON, with or without its optional `asset`, is refused with the way out.
    #[test]
    fn gltf_1_is_refused_with_the_way_out() {
        let mut glb = b"glTF\x01\x00\x00\x00\x14\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00".to_vec();
        glb.truncate(20);
        let json = br#"{"asset": {"version": "1.0"}, "scene": "s", "scenes": {"s": {"nodes": []}}}"#;
        let bare = br#"{"scene": "s", "scenes": {"s": {"nodes": []}}}"#;
        for (bytes, says) in [(&glb[..], "binary glTF 1.0"), (json, "glTF 1.0 (`asset.version`)"), (bare, "glTF 1.0")] {
            let e = super::parse(bytes).map(|_| ()).unwrap_err();
            assert!(e.contains(says) && e.contains("npx gltf-pipeline"), "{e}");
        }
    }

    /// A position accessor without the `min` and `max` the spec requires reads (Blender's importer reads it; vvgen
    /// never reads them); without a `count` it is still an error.
    #[test]
    fn a_position_accessor_without_bounds_reads() {
        let json = r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}"#;
        assert!(super::parse(json.as_bytes()).is_ok());
        let e = super::parse(json.replace(r#""count": 3, "#, "").as_bytes()).map(|_| ()).unwrap_err();
        assert!(e.contains("count"), "{e}");
    }

    /// A scene without `nodes` (Blender's exporter writes an empty scene so) is an empty scene, not an error.
    #[test]
    fn a_scene_without_nodes_is_empty() {
        let json = br#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}, {"name": "Empty"}], "nodes": [{}]}"#;
        let (gltf, notes) = super::parse(json).unwrap();
        let counts: Vec<usize> = gltf.document.scenes().map(|s| s.nodes().count()).collect();
        assert_eq!(counts, [1, 0]);
        assert!(notes.is_empty());
    }
}
