//! `KHR_animation_pointer` (Blender 4.x's exporter, the Khronos samples): channels whose target is a JSON pointer.
//! Pointers at a node's transform or morph weights, or at a mesh's default weights, pose the subject exactly as
//! the core channels they name; pointers at anything else (materials, lights, cameras) are warned of and the
//! property keeps the file's value.

use std::path::Path;
use std::process::Command;

use serde_json::{json, Value};

use crate::common::data;

/// Builds `model.gltf` in `dir` over six frames from two views at 48², returning every training image's bytes
/// in order and what the build printed.
fn frames(dir: &Path) -> (Vec<Vec<u8>>, String) {
    let manifest = "[dataset]\nname = \"s\"\nout = \"out\"\npreview = false\n\
                    [source.s]\ngltf = \"model.gltf\"\nframes = { count = 6, fps = 2 }\n\
                    [transform]\nfit = \"frame\"\n[render]\nresolution = [48, 48]\n\
                    [rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n[output.d]\nwriter = \"dnerf\"\n";
    std::fs::write(dir.join("m.toml"), manifest).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(["build", "m.toml"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    let mut names: Vec<_> =
        std::fs::read_dir(dir.join("out/s_dnerf/train")).unwrap().map(|e| e.unwrap().path()).collect();
    names.sort();
    assert_eq!(names.len(), 12, "six frames, two views");
    (names.iter().map(|p| std::fs::read(p).unwrap()).collect(), err)
}

/// A folder holding `json` as `model.gltf`, with `side` (file names in `from`) copied beside it.
fn folder(json: &Value, from: &str, side: &[&str]) -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("model.gltf"), serde_json::to_vec(json).unwrap()).unwrap();
    for s in side {
        std::fs::copy(data(&format!("{from}/{s}")), d.path().join(s)).unwrap();
    }
    d
}

/// `json` with every channel's target written as `pointer(target)`, the extension required, and one more
/// channel pointing at material 0's base colour (on the first channel's sampler).
fn as_pointers(json: &Value, pointer: impl Fn(&Value) -> String) -> Value {
    let mut p = json.clone();
    for anim in p["animations"].as_array_mut().unwrap() {
        let channels = anim["channels"].as_array_mut().unwrap();
        for ch in channels.iter_mut() {
            let to = pointer(&ch["target"]);
            ch["target"] = json!({"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": to}}});
        }
        let sampler = channels[0]["sampler"].clone();
        channels.push(json!({"sampler": sampler, "target": {"path": "pointer",
            "extensions": {"KHR_animation_pointer": {"pointer": "/materials/0/pbrMetallicRoughness/baseColorFactor"}}}}));
    }
    p["extensionsUsed"] = json!(["KHR_animation_pointer"]);
    p["extensionsRequired"] = json!(["KHR_animation_pointer"]);
    p
}

/// BoxAnimated (a node's rotation and another's translation) and AnimatedMorphCube (a node's morph weights,
/// pointed at through its mesh's default weights): the pointer files' frames are the core files', byte for
/// byte, and they move. The material channel is named in a warning.
#[test]
fn node_and_mesh_pointers_pose_as_the_core_channels_they_name() {
    let node = |t: &Value| format!("/nodes/{}/{}", t["node"], t["path"].as_str().unwrap());
    let mesh = |t: &Value| {
        assert_eq!(t["path"], "weights");
        "/meshes/0/weights".to_string()
    };
    type Pointer<'a> = &'a dyn Fn(&Value) -> String;
    let cases: [(&str, &str, &[&str], Pointer); 2] = [
        ("gltf/BoxAnimated", "BoxAnimated.gltf", &[], &node),
        ("gltf/AnimatedMorphCube", "AnimatedMorphCube.gltf", &["AnimatedMorphCube.bin"], &mesh),
    ];
    for (from, file, side, pointer) in cases {
        let json: Value = serde_json::from_slice(&std::fs::read(data(&format!("{from}/{file}"))).unwrap()).unwrap();
        let (want, _) = frames(folder(&json, from, side).path());
        let (got, said) = frames(folder(&as_pointers(&json, pointer), from, side).path());
        let distinct: std::collections::HashSet<&Vec<u8>> = want.iter().collect();
        assert!(distinct.len() > 2, "{file}: the subject moves (two still views would give two images)");
        assert!(want == got, "{file}: the pointer file's frames differ from the core file's");
        let warned = "`/materials/0/pbrMetallicRoughness/baseColorFactor` through `KHR_animation_pointer`";
        assert!(said.contains(warned), "{file}: {said}");
    }
}
