//! STL files, read as Blender 4.5's importer reads them and used as a newcomer uses them: a part from its own
//! folder by its bare name with the manifest `vvgen new` writes, a folder of STL frames, and files that are
//! damaged. The files are assimp's and trimesh's test models (outside vvgen's own making): a trueSpace spider in
//! both forms, SolidWorks' unit cube (binary, yet its header starts with `solid`), and two ASCII solids in one
//! file.

use std::path::Path;
use std::process::Command;

use glam::Vec3;

use crate::common::data;

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// A file's triangles (as vvgen reads them: three corners each), their total area and their bounds.
fn measure(path: &Path) -> (Vec<[Vec3; 3]>, f64, Vec3, Vec3) {
    let s = vvgen::scene::stl::scene(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let p = &s.primitives[0];
    let tris: Vec<[Vec3; 3]> =
        p.indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| p.positions[t[k] as usize])).collect();
    let area = tris.iter().map(|[a, b, c]| 0.5 * (*b - *a).cross(*c - *a).length() as f64).sum();
    let lo = p.positions.iter().fold(Vec3::INFINITY, |m, &v| m.min(v));
    let hi = p.positions.iter().fold(Vec3::NEG_INFINITY, |m, &v| m.max(v));
    (tris, area, lo, hi)
}

#[test]
fn stl_files_read_as_blenders_importer_reads_them() {
    // Blender 4.5's `wm.stl_import` (default settings) on each file: triangles, total area, bounds, printed to 6
    // significant digits and 5 decimals. It drops the spider's 56 facets with two corners at one point.
    type Figures = (&'static str, usize, f64, [f32; 3], [f32; 3]);
    let blender: [Figures; 4] = [
        ("Spider_binary.stl", 1312, 56.9476, [-3.11489, -4.0, -1.64933], [3.11489, 4.0, 1.64933]),
        ("Spider_ascii.stl", 1312, 56.9476, [-3.1149, -4.0, -1.64933], [3.1149, 4.0, 1.64933]),
        ("unit_cube.STL", 12, 6.0, [-0.5; 3], [0.5; 3]),
        ("multibody.stl", 32, 0.367239, [-0.51079, -0.71881, -0.05193], [0.12524, 0.36962, 0.288]),
    ];
    for (file, count, area, lo, hi) in blender {
        let (tris, a, l, h) = measure(&data(&format!("stl/{file}")));
        assert_eq!(tris.len(), count, "{file}");
        assert!((a / area - 1.0).abs() < 1e-5, "{file}: area {a} vs Blender's {area}");
        assert!((l - Vec3::from(lo)).abs().max_element() < 1e-5, "{file}: {l} vs {lo:?}");
        assert!((h - Vec3::from(hi)).abs().max_element() < 1e-5, "{file}: {h} vs {hi:?}");
    }
    // The spider's two forms are one mesh: the same triangles in the same order, the ASCII's six decimals apart.
    let (binary, ..) = measure(&data("stl/Spider_binary.stl"));
    let (ascii, ..) = measure(&data("stl/Spider_ascii.stl"));
    let off = binary.iter().zip(&ascii).flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs().max_element()));
    assert!(off.fold(0.0f32, f32::max) < 1e-5);
    // Flat: each triangle's normal is its own, from its winding (the file's normals are not read).
    let s = vvgen::scene::stl::scene(&data("stl/unit_cube.STL")).unwrap();
    let p = &s.primitives[0];
    for t in p.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| p.positions[t[k] as usize]);
        let n = (b - a).cross(c - a).normalize();
        assert!(t.iter().all(|&i| (p.normals[i as usize] - n).length() < 1e-6));
        // A cube's faces are axis-aligned, and its winding outward: the normal points away from the centre.
        assert!(n.abs().max_element() > 0.999 && n.dot((a + b + c) / 3.0) > 0.0, "{n}");
    }
}

#[test]
fn a_part_from_its_own_folder_builds_with_the_manifest_new_writes() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::copy(data("stl/unit_cube.STL"), d.join("unit_cube.STL")).unwrap();
    let (code, err) = vvgen(d, &["new", "unit_cube.STL"]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(d.join("unit-cube.toml")).unwrap();
    // The bare name, STL's +Z up, and lit: a part has no colours, so unlit every view would be a silhouette.
    for says in ["mesh   = \"unit_cube.STL\"", "up     = \"z\"    # STL's up axis", "shading        = \"pbr\""] {
        assert!(text.contains(says), "{says:?} not in\n{text}");
    }
    let quick = text
        .replace("views = 100", "views = 3")
        .replace("views = 10", "views = 1")
        .replace("views    = 20", "views    = 1");
    std::fs::write(d.join("unit-cube.toml"), quick).unwrap();
    let (code, err) = vvgen(d, &["check", "unit-cube.toml"]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = vvgen(d, &["-q", "build", "unit-cube.toml"]);
    assert_eq!(code, 0, "{err}");
    // The cube fills part of the view, its faces in distinct flat shades (lit from different sides).
    let img = image::open(d.join("out/unit-cube/unit-cube_dnerf/train/r_0000.png")).unwrap().to_rgba8();
    let covered = img.pixels().filter(|p| p[3] == 255).count() as f64 / (img.width() * img.height()) as f64;
    assert!(covered > 0.1 && covered < 0.9, "{covered}");
    let mut shades: Vec<u8> = img.pixels().filter(|p| p[3] == 255).map(|p| p[0]).collect();
    shades.sort_unstable();
    let (dark, light) = (shades[shades.len() / 10], shades[shades.len() * 9 / 10]);
    assert!(light as i32 - dark as i32 > 20, "faces lit alike: {dark}..{light}");
}

/// A binary STL of one tetrahedron whose apex is at height `h`, its header starting with `solid` as CAD
/// programs write it.
fn tetrahedron(h: f32) -> Vec<u8> {
    let (a, b, c, top) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.3, 0.3, h]);
    let tris = [[a, c, b], [a, b, top], [b, c, top], [c, a, top]];
    let mut bytes = b"solid tetrahedron".to_vec();
    bytes.resize(80, b' ');
    bytes.extend((tris.len() as u32).to_le_bytes());
    for t in tris {
        bytes.extend([0u8; 12]);
        t.iter().flatten().for_each(|x: &f32| bytes.extend(x.to_le_bytes()));
        bytes.extend([0u8; 2]);
    }
    bytes
}

#[test]
fn a_folder_of_stl_frames_is_a_mesh_sequence() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir_all(d.join("print")).unwrap();
    for (f, h) in [0.8f32, 1.6].iter().enumerate() {
        std::fs::write(d.join(format!("print/layer_{f}.stl")), tetrahedron(*h)).unwrap();
    }
    let (code, err) = vvgen(d, &["new", "print"]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(d.join("print.toml")).unwrap();
    assert!(text.contains("mesh_sequence = \"print/*.stl\""), "{text}");
    assert!(text.contains("up     = \"z\""), "{text}");
    let quick = text
        .replace("views = 100", "views = 1")
        .replace("views = 10", "views = 1")
        .replace("views    = 20", "views    = 1");
    std::fs::write(d.join("print.toml"), quick).unwrap();
    let (code, err) = vvgen(d, &["-q", "build", "print.toml"]);
    assert_eq!(code, 0, "{err}");
    // The tall frame stands higher in the same camera than the short one.
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("out/print/print_dnerf/transforms_test.json")).unwrap()).unwrap();
    let frames = json["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2, "one view per frame");
    let covered = |f: &serde_json::Value| {
        let png = d.join("out/print/print_dnerf").join(format!("{}.png", f["file_path"].as_str().unwrap()));
        image::open(png).unwrap().to_rgba8().pixels().filter(|p| p[3] == 255).count()
    };
    assert!(covered(&frames[1]) as f64 > 1.3 * covered(&frames[0]) as f64);
    // A frame cut short in a copy: `check` names it (from its size: frames are read in full when they render).
    let whole = std::fs::read(d.join("print/layer_1.stl")).unwrap();
    std::fs::write(d.join("print/layer_1.stl"), &whole[..whole.len() - 7]).unwrap();
    let (code, err) = vvgen(d, &["check", "print.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("layer_1.stl: a binary STL whose header counts 4 triangles") && err.contains("cut short"),
        "{err}"
    );
}

#[test]
fn damaged_stl_files_are_refused_with_where_and_why() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let manifest = |file: &str| {
        format!(
            "[dataset]\nname = \"s\"\nout = \"out\"\n[source.s]\nmesh = \"{file}\"\n[render]\nresolution = [64, 64]\n\
             [rig.r]\nkind = \"hemisphere\"\n[split.train]\nrig = \"r\"\nviews = 1\n[output.d]\nwriter = \"dnerf\"\n"
        )
    };
    let refused = |file: &str, bytes: &[u8]| {
        std::fs::write(d.join(file), bytes).unwrap();
        std::fs::write(d.join("m.toml"), manifest(file)).unwrap();
        let (code, err) = vvgen(d, &["check", "m.toml"]);
        assert_eq!(code, 2, "{file}: {err}");
        err
    };
    // A binary file cut short in a transfer: its header's count against its size.
    let whole = std::fs::read(data("stl/Spider_binary.stl")).unwrap();
    let err = refused("cut.stl", &whole[..whole.len() / 2]);
    assert!(
        err.contains("cut.stl: a binary STL whose header counts 1368 triangles") && err.contains("cut short"),
        "{err}"
    );
    // A number that does not parse in an ASCII file: its line and column.
    let text = std::fs::read_to_string(data("stl/multibody.stl")).unwrap();
    let err = refused(
        "typo.stl",
        text.replacen("vertex -0.440789347 -0.718809786", "vertex -0.440789347 -0,718809786", 1).as_bytes(),
    );
    assert!(err.contains("typo.stl:5: column 27: `-0,718809786` is not a finite number"), "{err}");
    // Nothing in it: nothing to render, as for an empty glTF.
    let err = refused("empty.stl", b"solid empty\nendsolid empty\n");
    assert!(err.contains("`empty.stl`: nothing to render"), "{err}");
}
