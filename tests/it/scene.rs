//! Scene sources on real assets: accessor decoding, interpolation, skinning, morphs, materials, primitive
//! modes, and clear errors for malformed files.
#![allow(clippy::needless_range_loop)] // index loops read clearer when several arrays share the index

use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec3};
use vvgen::scene::gltf::{self, GltfAsset, PoseScratch};
use vvgen::scene::{PosedScene, PrimKind};

fn asset_path(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel)
}

fn load(rel: &str) -> GltfAsset {
    gltf::load(&asset_path(rel), None).unwrap_or_else(|e| panic!("{e}"))
}

fn pose(a: &GltfAsset, clips: &[usize], t: f32) -> PosedScene {
    let mut out = PosedScene::default();
    a.pose(clips, t, Mat4::IDENTITY, &mut PoseScratch::default(), &mut out);
    out
}

/// The posed primitive of a node (first primitive of its mesh).
fn of_node<'a>(a: &GltfAsset, posed: &'a PosedScene, node: usize) -> &'a vvgen::scene::PosedPrimitive {
    let object = a.order.iter().position(|(n, _)| *n == node).unwrap() as u32;
    posed.primitives.iter().find(|p| p.object == object).unwrap()
}

fn assert_close(a: Vec3, b: Vec3, tol: f32, what: &str) {
    assert!((a - b).abs().max_element() <= tol, "{what}: {a} vs {b}");
}

/// Every POSITION accessor's declared min/max (written by the exporter) must match what we decode,
/// sparse substitution included.
#[test]
fn decoded_positions_match_declared_bounds() {
    for rel in [
        "gltf/SimpleSparseAccessor/SimpleSparseAccessor.gltf",
        "gltf/BoxTextured/BoxTextured.glb",
        "gltf/CesiumMan/CesiumMan.glb",
        "gltf/VertexColorTest/VertexColorTest.gltf",
        "gltf/InterpolationTest/InterpolationTest.gltf",
        "gltf/MorphPrimitivesTest/MorphPrimitivesTest.gltf",
    ] {
        let a = load(rel);
        let doc = ::gltf::Gltf::open(asset_path(rel)).unwrap();
        for (mi, mesh) in doc.meshes().enumerate() {
            for (pi, p) in mesh.primitives().enumerate() {
                let acc = p.get(&::gltf::Semantic::Positions).unwrap();
                let (Some(min), Some(max)) = (acc.min(), acc.max()) else {
                    continue;
                };
                let min = Vec3::new(
                    min[0].as_f64().unwrap() as f32,
                    min[1].as_f64().unwrap() as f32,
                    min[2].as_f64().unwrap() as f32,
                );
                let max = Vec3::new(
                    max[0].as_f64().unwrap() as f32,
                    max[1].as_f64().unwrap() as f32,
                    max[2].as_f64().unwrap() as f32,
                );
                let ours = &a.meshes[mi][pi].positions;
                let lo = ours.iter().fold(Vec3::INFINITY, |m, p| m.min(*p));
                let hi = ours.iter().fold(Vec3::NEG_INFINITY, |m, p| m.max(*p));
                assert_close(lo, min, 1e-4, &format!("{rel} mesh {mi} min"));
                assert_close(hi, max, 1e-4, &format!("{rel} mesh {mi} max"));
            }
        }
    }
}

/// InterpolationTest: node = T·R·S of the rest mesh; expected TRS computed by hand from the keys.
#[test]
fn interpolation_step_linear_cubic() {
    let a = load("gltf/InterpolationTest/InterpolationTest.gltf");
    let check = |clip: usize, node: usize, t: f32, trs: (Vec3, Quat, Vec3)| {
        let posed = pose(&a, &[clip], t);
        let p = of_node(&a, &posed, node);
        let rest = &a.meshes[a.nodes[node].mesh.unwrap()][0].positions;
        let m = Mat4::from_scale_rotation_translation(trs.2, trs.1, trs.0);
        for (i, r) in rest.iter().enumerate() {
            assert_close(p.positions[i], m.transform_point3(*r), 2e-4, &format!("clip {clip} t {t} vertex {i}"));
        }
    };
    let n = |i: usize| a.nodes[i].translation;
    // STEP translation (node 8): keys y = 6.665, 10, 6, … at 0, 0.458, 0.833: t = 0.6 holds key 1.
    check(6, 8, 0.6, (Vec3::new(0.0, 10.0, 0.0), Quat::IDENTITY, Vec3::ONE));
    // LINEAR translation (node 10): halfway between y = 6.621 and 10.
    check(
        8,
        10,
        0.416_666_66 / 2.0,
        (Vec3::new(-3.2975807, (6.621_014_6 + 10.0) / 2.0, 0.0), Quat::IDENTITY, Vec3::ONE),
    );
    // CUBICSPLINE translation (node 9) with zero tangents: the Hermite midpoint is the mean.
    check(7, 9, 0.416_666_66 / 2.0, (Vec3::new(3.30518, (6.640_117 + 10.0) / 2.0, 0.0), Quat::IDENTITY, Vec3::ONE));
    // LINEAR rotation (node 7): halfway from identity to -45° about Z is -22.5°.
    check(5, 7, 0.416_666_66 / 2.0, (n(7), Quat::from_rotation_z(-22.5f32.to_radians()), Vec3::ONE));
    // STEP scale (node 0): before the first key clamps to it (1), at 0.5 holds key 1 (0.5); after the last key: last.
    check(0, 0, 0.0, (n(0), Quat::IDENTITY, Vec3::ONE));
    check(0, 0, 0.5, (n(0), Quat::IDENTITY, Vec3::splat(0.5)));
    // CUBICSPLINE scale (node 4): keys 1 → 0.5 with zero tangents; midpoint 0.75, quarter smoothstep.
    let (t0, t1) = (0.041_666_668f32, 0.416_666_66f32);
    check(2, 4, (t0 + t1) / 2.0, (n(4), Quat::IDENTITY, Vec3::splat(0.75)));
    let s = 0.25f32;
    let h = 3.0 * s * s - 2.0 * s * s * s;
    check(2, 4, t0 + s * (t1 - t0), (n(4), Quat::IDENTITY, Vec3::splat(1.0 - 0.5 * h)));
}

/// World matrix of a node at rest, from the parent chain.
fn rest_world(a: &GltfAsset, node: usize) -> Mat4 {
    let n = &a.nodes[node];
    let local = n.matrix.unwrap_or_else(|| Mat4::from_scale_rotation_translation(n.scale, n.rotation, n.translation));
    match a.order.iter().find(|(x, _)| *x == node).and_then(|(_, p)| *p) {
        Some(p) => rest_world(a, p) * local,
        None => local,
    }
}

/// With no animation, every joint is at its bind pose: skinning must place the mesh where its node's own
/// transform would (the file's inverse bind matrices invert the joints' rest transforms).
#[test]
fn skins_at_bind_pose_reproduce_the_mesh() {
    for rel in ["gltf/QuadSkinMultiInfluence/quad_skin.glb"] {
        let a = load(rel);
        let posed = pose(&a, &[], 0.0);
        let mut checked = 0;
        for (object, &(node, _)) in a.order.iter().enumerate() {
            let Some(mesh) = a.nodes[node].mesh else {
                continue;
            };
            let p = posed.primitives.iter().find(|p| p.object == object as u32).unwrap();
            for (i, r) in a.meshes[mesh][0].positions.iter().enumerate() {
                let expect = rest_world(&a, node).transform_point3(*r);
                assert_close(p.positions[i], expect, 1e-3, &format!("{rel} vertex {i}"));
                checked += 1;
            }
        }
        assert!(checked > 0);
    }
    // QuadSkinMultiInfluence uses JOINTS_0..2: 12 influences per vertex, renormalized.
    let a = load("gltf/QuadSkinMultiInfluence/quad_skin.glb");
    let prim = a.meshes.iter().flatten().find(|p| p.influences > 0).unwrap();
    assert!(prim.influences > 4, "{}", prim.influences);
    for w in prim.weights.chunks_exact(prim.influences) {
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
    }
}

/// SimpleSkin: joints are nodes 1 (at y = 1) and 2 (its child, rotating about Z); both inverse bind matrices
/// are a translation by (-0.5, -1, 0) (from the file), so joint 0 shifts vertices by -0.5 in x and joint 1
/// rotates them about (0.5, 1, 0) before the same shift... written out: J1·r = R·(r - (0.5, 1, 0)) + (0, 1, 0).
#[test]
fn skinning_follows_the_joint() {
    let a = load("gltf/SimpleSkin/SimpleSkin.gltf");
    let ch = &a.animations[0].channels[0];
    let mut q = [0f32; 4];
    let t = 2.0;
    ch.sampler.sample(t, &mut q);
    let rot = Quat::from_slice(&q);
    assert!(rot.angle_between(Quat::IDENTITY) > 0.1, "pick a time with a visible rotation");
    let posed = pose(&a, &[0], t);
    let prim = &a.meshes[0][0];
    let ibm = Vec3::new(-0.5, -1.0, 0.0);
    let joint = Vec3::new(0.0, 1.0, 0.0);
    for v in 0..prim.positions.len() {
        let w = &prim.weights[v * 4..v * 4 + 4];
        let j = &prim.joints[v * 4..v * 4 + 4];
        // Blend of joint 0 (identity) and joint 1 (rotation about the pivot).
        let (w0, w1) = (
            if j[0] == 0 { w[0] } else { 0.0 } + if j[1] == 0 { w[1] } else { 0.0 },
            if j[0] == 1 { w[0] } else { 0.0 } + if j[1] == 1 { w[1] } else { 0.0 },
        );
        let r = prim.positions[v];
        let expect = (r + ibm + joint) * w0 + (rot * (r + ibm) + joint) * w1;
        assert_close(posed.primitives[0].positions[v], expect, 1e-4, &format!("vertex {v}"));
    }
    for n in &posed.primitives[0].normals {
        assert!((n.length() - 1.0).abs() < 1e-4 || *n == Vec3::ZERO);
    }
}

#[test]
fn cesium_man_poses_every_frame_sanely() {
    let a = load("gltf/CesiumMan/CesiumMan.glb");
    assert_eq!(a.skins[0].joints.len(), 19);
    assert_eq!(a.textures.len(), 1);
    let mut last = None;
    for f in 0..20 {
        let posed = pose(&a, &[0], f as f32 * 0.1);
        let (lo, hi) = posed.bounds().unwrap();
        assert!(lo.is_finite() && hi.is_finite());
        // The man is ~1.5 units tall in his file units whatever the frame.
        let size = (hi - lo).max_element();
        assert!(size > 1.0 && size < 2.5, "{size}");
        for p in &posed.primitives {
            assert!(p.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-3));
        }
        let d = posed.digest();
        assert_ne!(Some(d), last, "frame {f} equals the previous one: the animation is not applied");
        last = Some(d);
    }
}

#[test]
fn morph_weights_blend_deltas() {
    // MorphPrimitivesTest: static mesh.weights = [0.5] on two primitives.
    let a = load("gltf/MorphPrimitivesTest/MorphPrimitivesTest.gltf");
    let posed = pose(&a, &[], 0.0);
    let node = a.order.iter().find(|(n, _)| a.nodes[*n].mesh.is_some()).unwrap().0;
    let model = a.nodes[node].matrix.unwrap_or_else(|| {
        Mat4::from_scale_rotation_translation(a.nodes[node].scale, a.nodes[node].rotation, a.nodes[node].translation)
    });
    assert_eq!(a.nodes[node].weights, [0.5]);
    for (pi, prim) in a.meshes[a.nodes[node].mesh.unwrap()].iter().enumerate() {
        let d = &prim.morph_positions[0];
        assert!(d.iter().any(|v| *v != Vec3::ZERO));
        for v in 0..prim.positions.len() {
            assert_close(
                posed.primitives[pi].positions[v],
                model.transform_point3(prim.positions[v] + d[v] * 0.5),
                1e-5,
                "morph",
            );
        }
    }
    // AnimatedMorphCube: weights animated LINEAR; at the first key both weights are 0 → the rest cube.
    let a = load("gltf/AnimatedMorphCube/AnimatedMorphCube.gltf");
    let mut w = [0f32; 2];
    a.animations[0].channels[0].sampler.sample(1.0, &mut w);
    let posed = pose(&a, &[0], 1.0);
    let n = &a.nodes[0];
    let model = Mat4::from_scale_rotation_translation(n.scale, n.rotation, n.translation);
    let prim = &a.meshes[0][0];
    for v in 0..prim.positions.len() {
        let p = prim.positions[v] + prim.morph_positions[0][v] * w[0] + prim.morph_positions[1][v] * w[1];
        assert_close(posed.primitives[0].positions[v], model.transform_point3(p), 1e-4, "animated morph");
    }
    // SparseMorphTargets: deltas in a sparse accessor without a bufferView.
    let a = load("gltf/SparseMorphTargets/singleBlendshapeCube_sparse.glb");
    let prim = &a.meshes[0][0];
    let nonzero = prim.morph_positions[0].iter().filter(|v| **v != Vec3::ZERO).count();
    assert!(nonzero > 0 && nonzero < prim.positions.len(), "{nonzero}");
    // SimpleMorph: two targets, default weights from the mesh.
    let a = load("gltf/SimpleMorph/SimpleMorph.gltf");
    assert_eq!(a.meshes[0][0].morph_positions.len(), 2);
    assert_eq!(pose(&a, &[0], 0.5).primitives.len(), 1);
}

#[test]
fn primitive_modes() {
    let tris = |rel: &str| {
        let a = load(rel);
        (
            a.meshes.iter().flatten().map(|p| (p.kind, p.indices.len() / 3, p.positions.len())).collect::<Vec<_>>(),
            a.warnings,
        )
    };
    let (p, _) = tris("gltf/Mesh_PrimitiveMode/Mesh_PrimitiveMode_00.gltf");
    assert_eq!(p[0].0, PrimKind::Points);
    for rel in [
        "gltf/Mesh_PrimitiveMode/Mesh_PrimitiveMode_01.gltf",
        "gltf/Mesh_PrimitiveMode/Mesh_PrimitiveMode_02.gltf",
        "gltf/Mesh_PrimitiveMode/Mesh_PrimitiveMode_03.gltf",
    ] {
        let (p, w) = tris(rel);
        assert!(p.is_empty(), "{rel}: lines are skipped");
        assert_eq!(w.len(), 1, "{rel}: one warning per line primitive: {w:?}");
    }
    for rel in [
        "gltf/Mesh_PrimitiveMode/Mesh_PrimitiveMode_04.gltf",
        "gltf/Mesh_PrimitiveMode/Mesh_PrimitiveMode_05.gltf",
        "gltf/Mesh_PrimitiveMode/Mesh_PrimitiveMode_14.gltf",
    ] {
        let (p, _) = tris(rel);
        assert_eq!(
            (p[0].0, p[0].1),
            (PrimKind::Triangles, 2),
            "{rel}: a strip, a fan or uint8 indices make the 2-triangle square"
        );
    }
}

#[test]
fn materials_textures_and_vertex_colours() {
    let a = load("gltf/BoxTextured/BoxTextured.glb");
    let m = &a.materials[0];
    let r = m.base_color_texture.expect("BoxTextured has a base colour texture");
    let t = &a.textures[r.texture as usize];
    assert!(t.width > 0 && t.srgb);
    assert!(!a.meshes[0][0].uvs.is_empty());
    let a = load("gltf/VertexColorTest/VertexColorTest.gltf");
    assert!(a.meshes.iter().flatten().any(|p| !p.colors.is_empty()));
    let a = load("gltf/Cameras/Cameras.gltf");
    assert!(a.cameras.iter().any(|c| c.kind == "perspective") && a.cameras.iter().any(|c| c.kind == "orthographic"));
}

#[test]
fn generated_normals_are_unit_and_outward() {
    // The primitive-mode squares have no NORMAL: generated normals face +Z for a counter-clockwise square.
    let a = load("gltf/Mesh_PrimitiveMode/Mesh_PrimitiveMode_14.gltf");
    for n in &a.meshes[0][0].normals {
        assert!((n.length() - 1.0).abs() < 1e-5);
    }
}

/// The file and the problem of a malformed-glTF error (any other variant fails the test).
fn gltf_problem(e: vvgen::scene::Error) -> (PathBuf, String) {
    match e {
        vvgen::scene::Error::Gltf { path, message } => (path, message),
        e => panic!("not a malformed-glTF error: {e:?}"),
    }
}

#[test]
fn malformed_gltf_files_fail_clearly() {
    let bad = |rel: &str| gltf_problem(gltf::load(&asset_path(rel), None).unwrap_err());
    let (path, msg) = bad("bad/gltf/assimp/MissingBin_BoxTextured.gltf");
    assert!(path.ends_with("MissingBin_BoxTextured.gltf") && msg.contains("BoxTextured0.bin"), "{msg}");
    let (path, msg) = bad("bad/gltf/validator/animation/sampler_too_few_cubic_frames.gltf");
    assert!(path.ends_with("sampler_too_few_cubic_frames.gltf"));
    assert!(msg.contains("CUBICSPLINE sampler needs at least 2 keyframes"), "{msg}");
    let (path, msg) = bad("bad/gltf/validator/mesh_data/index_buffer_oob.gltf");
    assert!(path.ends_with("index_buffer_oob.gltf") && msg.contains("index 5 is out of range"), "{msg}");
    // Non-unit rotation keys are valid enough to load: they are normalized, with a warning.
    let a = gltf::load(&asset_path("bad/gltf/validator/animation_data/quaternion_non_unit_values.gltf"), None).unwrap();
    assert!(a.warnings.iter().any(|w| w.contains("normalized")), "{:?}", a.warnings);
}

#[test]
fn uris_may_not_escape_the_folder() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("secret.bin"), [0u8; 64]).unwrap();
    let sub = dir.path().join("model");
    std::fs::create_dir(&sub).unwrap();
    let json = r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"../secret.bin","byteLength":64}]}"#;
    std::fs::write(sub.join("m.gltf"), json).unwrap();
    let (_, msg) = gltf_problem(gltf::load(&sub.join("m.gltf"), None).unwrap_err());
    assert!(msg.contains("../secret.bin") && msg.contains("outside") && msg.contains("keep the files"), "{msg}");
    // A symlink inside the folder that leads out of it is refused too (containment is judged on resolved paths)…
    std::os::unix::fs::symlink(dir.path().join("secret.bin"), sub.join("link.bin")).unwrap();
    std::fs::write(sub.join("m.gltf"), json.replace("../secret.bin", "link.bin")).unwrap();
    let (_, msg) = gltf_problem(gltf::load(&sub.join("m.gltf"), None).unwrap_err());
    assert!(msg.contains("link.bin") && msg.contains("outside"), "{msg}");
    // … while a path through `..` that stays inside is read.
    std::fs::create_dir(sub.join("a")).unwrap();
    std::fs::write(sub.join("x.bin"), [0u8; 64]).unwrap();
    std::fs::write(sub.join("m.gltf"), json.replace("../secret.bin", "a/../x.bin")).unwrap();
    assert!(gltf::load(&sub.join("m.gltf"), None).is_ok());
}

#[test]
fn indices_beyond_the_vertices_are_an_error() {
    use base64::Engine as _;
    let mut bin = Vec::new();
    for v in [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    bin.extend_from_slice(&[0u8, 1, 5, 0]);
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                     {{"bufferView":1,"componentType":5121,"count":3,"type":"SCALAR"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":3}}],
        "buffers":[{{"uri":"{uri}","byteLength":40}}]}}"#
    );
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("oob.gltf"), json).unwrap();
    let (path, msg) = gltf_problem(gltf::load(&dir.path().join("oob.gltf"), None).unwrap_err());
    assert!(path.ends_with("oob.gltf") && msg.contains("index 5 is out of range"), "{msg}");
}

/// FlightHelmet (6 meshes, 15 PNG textures, 7 MB) is too large to ship in tests/data; it is read from the
/// project's shared assets when they sit beside the clone (as in CI), and the test says so when they do not.
#[test]
fn flight_helmet_multi_mesh_textures() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/gltf/FlightHelmet/FlightHelmet.gltf");
    if !p.is_file() {
        eprintln!("flight_helmet_multi_mesh_textures: {} not found, not checked", p.display());
        return;
    }
    let a = gltf::load(&p, None).unwrap();
    assert_eq!(a.meshes.len(), 6);
    // 15 images; the 5 metallic-roughness (ORM) and 5 normal ones also as linear copies, since data textures are
    // not sRGB.
    assert_eq!(a.textures.len(), 15 + 10);
    for m in a.materials.iter().filter_map(|m| m.normal_texture) {
        assert!(!a.textures[m.0.texture as usize].srgb, "normal textures are read linear");
    }
    // Every primitive of a normal-mapped material has a tangent per vertex (the file has none: MikkTSpace).
    for p in a.meshes.iter().flatten().filter(|p| a.materials[p.material as usize].normal_texture.is_some()) {
        assert_eq!(p.tangents.len(), p.positions.len());
        assert!(p.tangents.iter().all(|t| t.w.abs() == 1.0 && (t.truncate().length() - 1.0).abs() < 1e-3));
    }
    assert!(a.textures[15..].iter().all(|t| !t.srgb) && a.textures[..15].iter().all(|t| t.srgb));
    for m in &a.materials {
        if let Some(r) = m.metallic_roughness_texture {
            assert!(!a.textures[r.texture as usize].srgb, "data textures are read linear");
        }
    }
    assert!(a.materials.iter().filter(|m| m.base_color_texture.is_some()).count() >= 5);
    let posed = pose(&a, &[], 0.0);
    assert_eq!(posed.primitives.len(), 6);
    assert!(posed
        .primitives
        .iter()
        .all(|p| !p.uvs.is_empty() && p.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-3)));
}

#[test]
fn unassigned_skeleton_and_box_animated_move() {
    // A skin without `skeleton`, rotation + scale animation, COLOR_0.
    let a = load("gltf/UnassignedSkeleton/unassigned-skeleton.gltf");
    assert!(!a.skins.is_empty() && !a.animations.is_empty());
    assert!(a.meshes.iter().flatten().any(|p| p.influences > 0 && !p.colors.is_empty()));
    let end = a.animations[0].duration();
    let d0 = pose(&a, &[0], 0.0).digest();
    assert!((1..16).any(|i| pose(&a, &[0], end * i as f32 / 16.0).digest() != d0), "the skinned mesh moves");
    for p in &pose(&a, &[0], end * 0.5).primitives {
        assert!(p.positions.iter().all(|v| v.is_finite()));
    }
    // BoxAnimated: two clips (rotation of the inner box, translation of the outer), channels of different lengths.
    let a = load("gltf/BoxAnimated/BoxAnimated.gltf");
    assert_eq!(a.animations.len(), 1.max(a.animations.len()));
    let all: Vec<usize> = (0..a.animations.len()).collect();
    let end = a.animations.iter().map(|x| x.duration()).fold(0.0, f32::max);
    let (lo0, hi0) = pose(&a, &all, 0.0).bounds().unwrap();
    let moved = (1..8).any(|i| {
        let (lo, hi) = pose(&a, &all, end * i as f32 / 8.0).bounds().unwrap();
        (lo - lo0).length() + (hi - hi0).length() > 1e-3
    });
    assert!(moved, "BoxAnimated's boxes move");
    // Past the end, every channel holds its last key.
    assert_eq!(pose(&a, &all, end).digest(), pose(&a, &all, end + 10.0).digest());
}

/// A small animated, textured triangle as glTF JSON (issue 15's fuzzing seeds), for malformed variants.
fn seed_gltf() -> serde_json::Value {
    use base64::Engine as _;
    let mut bin = Vec::new();
    for v in [
        0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0,
        0.0,
    ] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    serde_json::json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}]}],
        "buffers": [{"byteLength": bin.len(), "uri": uri}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24},
                        {"buffer": 0, "byteOffset": 60, "byteLength": 8}, {"buffer": 0, "byteOffset": 68, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
            {"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}],
        "animations": [{"channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
                        "samplers": [{"input": 2, "output": 3, "interpolation": "LINEAR"}]}]
    })
}

/// Loads `doc` written as a file.
fn load_json(doc: &serde_json::Value) -> Result<GltfAsset, vvgen::scene::Error> {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("m.gltf");
    std::fs::write(&p, serde_json::to_vec(doc).unwrap()).unwrap();
    gltf::load(&p, None)
}

/// A side-car `.bin` or a cut GLB given as the model says what the file is and what was expected.
#[test]
fn a_bin_or_a_truncated_glb_is_named_for_what_it_is() {
    let bin = crate::common::data("gltf/Cameras/simpleSquare.bin");
    let (_, msg) = gltf_problem(gltf::load(&bin, None).unwrap_err());
    assert!(msg.contains("side-car buffer"), "{msg}");
    let glb = std::fs::read(crate::common::data("gltf/BoxTextured/BoxTextured.glb")).unwrap();
    let (_, msg) = gltf_problem(gltf::load_slice(&glb[..100], Path::new("cut.glb"), None).unwrap_err());
    assert!(msg.starts_with("a truncated or malformed GLB"), "{msg}");
}

/// Issue 15's panics on malformed glTF are errors that name the object: dangling references and unknown enums
/// (which the gltf crate's own validation would index or unwrap), and offsets that overflow.
#[test]
fn malformed_references_offsets_and_enums_are_errors_not_panics() {
    assert!(load_json(&seed_gltf()).is_ok());
    /// What is broken, how, and what the error must say.
    type Case = (&'static str, fn(&mut serde_json::Value), &'static str);
    let cases: [Case; 8] = [
        (
            "no accessors",
            |d| drop(d.as_object_mut().unwrap().remove("accessors")),
            "attributes.POSITION = 0 does not index `accessors`",
        ),
        (
            "channel node",
            |d| d["animations"][0]["channels"][0]["target"]["node"] = 7.into(),
            "target.node = 7 does not index `nodes`",
        ),
        (
            "channel path",
            |d| d["animations"][0]["channels"][0]["target"]["path"] = "colour".into(),
            r#"target.path = "colour" is not one of"#,
        ),
        ("accessor type", |d| d["accessors"][1]["type"] = "VEC5".into(), r#"accessors[1].type = "VEC5" is not one of"#),
        (
            "huge offset",
            |d| d["accessors"][0]["byteOffset"] = 18446744073709551000u64.into(),
            "accessor 0 (byteOffset 18446744073709551000",
        ),
        (
            "scalar colours",
            |d| d["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 2.into(),
            "has 2 elements, POSITION has 3",
        ),
        (
            "nan position",
            |d| {
                // The first coordinate of the first vertex becomes NaN (f32 bits 0x7fc00000, little-endian).
                use base64::Engine as _;
                let uri = d["buffers"][0]["uri"].as_str().unwrap().to_string();
                let (head, data) = uri.split_once(',').unwrap();
                let mut bin = base64::engine::general_purpose::STANDARD.decode(data).unwrap();
                bin[..4].copy_from_slice(&f32::NAN.to_le_bytes());
                let data = base64::engine::general_purpose::STANDARD.encode(&bin);
                d["buffers"][0]["uri"] = format!("{head},{data}").into();
            },
            "POSITION 0 (",
        ),
        (
            "morph target",
            |d| d["meshes"][0]["primitives"][0]["targets"] = serde_json::json!([{"POSITION": 9}]),
            "targets[0].POSITION = 9 does not index `accessors`",
        ),
    ];
    for (what, edit, expect) in cases {
        let mut doc = seed_gltf();
        edit(&mut doc);
        let (_, msg) = gltf_problem(load_json(&doc).unwrap_err());
        assert!(msg.contains(expect), "{what}: {msg}");
    }
}

/// A texture transform offset of 1e38, or a corrupt uv, samples a texel inside the texture (no out-of-range
/// index), whatever the wrap mode.
#[test]
fn huge_and_corrupt_uvs_sample_inside_the_texture() {
    use vvgen::scene::texture::{Texture, TextureRef, Wrap};
    let tex = Texture::new(2, 2, vec![255; 16], true);
    for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror] {
        let mut r = TextureRef::new(0);
        (r.wrap_s, r.wrap_t) = (wrap, wrap);
        for uv in [
            glam::Vec2::splat(1e38),
            glam::Vec2::splat(-1e38),
            glam::Vec2::new(f32::NAN, 3.4e38),
            glam::Vec2::splat(f32::INFINITY),
        ] {
            let c = tex.sample(&r, uv);
            assert!(c.x.is_nan() || c.x <= 1.0, "{wrap:?} {uv}: {c}");
            let _ = tex.sample_footprint(&r, uv, glam::Vec2::splat(1e30), glam::Vec2::ZERO);
        }
    }
}

/// A surface its file gives neither a material nor colours is Blender's default surface (diffuse grey 0.8, no
/// specular layer), as Blender renders it; one with vertex colours keeps white, its colours being its colour
/// (glTF's COLOR_0 rule); PLY points stay white (Blender draws no points). OBJ, PLY, glTF and FBX alike.
#[test]
fn surfaces_without_a_material_or_colours_are_blenders_grey() {
    use vvgen::scene::material::Material;
    let grey = |m: &Material| m.base_color == glam::Vec4::new(0.8, 0.8, 0.8, 1.0) && m.specular == 0.0;
    let white = |m: &Material| m.base_color == glam::Vec4::ONE;
    let first = |s: &PosedScene| s.material(s.primitives[0].material).clone();
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();

    // OBJ without a material library, without and with vertex colours.
    std::fs::write(d.join("plain.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(d.join("coloured.obj"), "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n").unwrap();
    let plain = vvgen::scene::obj::scene(&d.join("plain.obj")).unwrap();
    assert!(grey(&first(&plain)), "{:?}", first(&plain));
    let coloured = vvgen::scene::obj::scene(&d.join("coloured.obj")).unwrap();
    assert!(white(&first(&coloured)), "{:?}", first(&coloured));

    // PLY: a mesh without colours, the same with colours, points without colours.
    let ply = |faces: bool, colours: bool| {
        let mut s = String::from(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n",
        );
        if colours {
            s.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
        }
        if faces {
            s.push_str("element face 1\nproperty list uchar int vertex_indices\n");
        }
        s.push_str("end_header\n");
        for v in ["0 0 0", "1 0 0", "0 1 0"] {
            s.push_str(v);
            s.push_str(if colours { " 200 10 10\n" } else { "\n" });
        }
        if faces {
            s.push_str("3 0 1 2\n");
        }
        std::fs::write(d.join("m.ply"), s).unwrap();
        first(&vvgen::scene::source::ply_scene(&d.join("m.ply")).unwrap())
    };
    assert!(grey(&ply(true, false)));
    assert!(white(&ply(true, true)));
    assert!(white(&ply(false, false)));

    // A triangle without a material, with and without COLOR_0.
    let triangle = |colours: bool| {
        use base64::Engine;
        let mut buf: Vec<u8> = Vec::new();
        for c in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0] {
            buf.extend(c.to_le_bytes());
        }
        let colour = if colours { r#", "COLOR_0": 1"# } else { "" };
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
              "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0{colour}}}}}]}}],
              "buffers": [{{"byteLength": 72, "uri": "data:application/octet-stream;base64,{}"}}],
              "bufferViews": [{{"buffer": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 36}}],
              "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
                            {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}}]}}"#,
            base64::engine::general_purpose::STANDARD.encode(&buf)
        );
        let a = gltf::load_slice(json.as_bytes(), Path::new("t.gltf"), None).unwrap();
        let mut posed = PosedScene { materials: std::sync::Arc::new(a.materials.clone()), ..Default::default() };
        a.pose(&[], 0.0, Mat4::IDENTITY, &mut PoseScratch::default(), &mut posed);
        first(&posed)
    };
    assert!(grey(&triangle(false)));
    assert!(white(&triangle(true)));

    // FBX: the two defaults for faces without a material follow the file's own.
    let fbx = vvgen::scene::fbx::load(&asset_path("fbx/blender_340_z_up_7400_binary.fbx")).unwrap();
    let mut rest = PosedScene::default();
    fbx.pose(None, 0.0, Mat4::IDENTITY, &mut rest).unwrap();
    let n = rest.materials.len();
    assert!(white(&rest.materials[n - 2]) && grey(&rest.materials[n - 1]));
}

/// A file without scenes is a library of nodes: vvgen shows its root nodes, as Blender's importer does (it
/// said "no mesh"), and poses them as the file with its one scene. A scene without `nodes` is empty.
#[test]
fn a_file_without_scenes_shows_its_root_nodes() {
    let text = std::fs::read_to_string(asset_path("gltf/BoxAnimated/BoxAnimated.gltf")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let with_scene = load("gltf/BoxAnimated/BoxAnimated.gltf");
    let obj = json.as_object_mut().unwrap();
    obj.remove("scene");
    obj.remove("scenes");
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("no-scenes.gltf");
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
    let without = gltf::load(&path, None).unwrap_or_else(|e| panic!("{e}"));
    let mut roots = without.roots.clone();
    roots.sort();
    assert_eq!(roots, [0, 3], "the nodes no node holds");
    let (a, b) = (pose(&with_scene, &[0], 0.7), pose(&without, &[0], 0.7));
    let positions = |p: &PosedScene| p.primitives.iter().flat_map(|q| q.positions.clone()).collect::<Vec<Vec3>>();
    let (mut pa, mut pb) = (positions(&a), positions(&b));
    let key = |v: &Vec3| v.to_array().map(f32::to_bits);
    pa.sort_by_key(key);
    pb.sort_by_key(key);
    assert!(!pa.is_empty() && pa == pb, "posed as the file with its scene");

    json["scenes"] = serde_json::json!([{"name": "Empty"}]);
    json["scene"] = serde_json::json!(0);
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
    let empty = gltf::load(&path, None).unwrap_or_else(|e| panic!("{e}"));
    assert!(empty.roots.is_empty(), "an empty scene shows nothing");
}
