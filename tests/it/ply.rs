//! PLY reading on real odd and malformed files (tests/data/bad/ply): each loads correctly or fails clearly.

use std::path::Path;
use std::process::Command;

use vvgen::scene::ply::{self, PlyError};

fn load(name: &str) -> Result<ply::PlyData, PlyError> {
    let bytes = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad/ply").join(name)).unwrap();
    ply::read(&bytes)
}

#[test]
fn corrupt_header_is_an_error() {
    let e = load("assimp_crash_corrupt_header.ply").unwrap_err();
    assert!(matches!(e, PlyError::Header { .. } | PlyError::NoEndHeader), "{e}");
}

#[test]
fn empty_file_is_not_ply() {
    assert_eq!(load("assimp_empty_0bytes.ply").unwrap_err(), PlyError::NotPly);
}

/// Blender 2.4x's exporter wrote "Created by Blender3D 247 …" after `format`, without `comment` (assimp's
/// Wuson.ply has it), and comments may be in a legacy encoding: both read as comments, as Blender 4.5 reads them.
/// An unknown keyword among the elements is still an error at its line.
#[test]
fn a_blender_2_4_header_line_and_a_latin1_comment_are_comments() {
    let header = |extra: &[u8], after: &[u8]| {
        [
            b"ply\nformat ascii 1.0\n",
            extra,
            b"element vertex 1\n",
            after,
            b"property float x\nproperty float y\n\
           property float z\nend_header\n1 2 3\n",
        ]
        .concat()
    };
    let old = ply::read(&header(b"Created by Blender3D 247 - www.blender.org, source file: \n", b"")).unwrap();
    assert_eq!(old.positions, [[1.0, 2.0, 3.0]]);
    let latin1 = ply::read(&header(b"comment Cr\xe9\xe9 par Ren\xe9\n", b"")).unwrap();
    assert_eq!(latin1.positions, [[1.0, 2.0, 3.0]]);
    let e = ply::read(&header(b"", b"propety float w\n")).unwrap_err();
    assert_eq!(e, PlyError::Header { line: 4, msg: "unknown header keyword `propety`".into() });
}

/// An ASCII row's values past those its header declares, on its line, are ignored, as Blender's importer and
/// trimesh ignore them (VCGLIB, MeshLab's library, writes face rows so: trimesh's fuze_ascii.ply); a row that runs
/// over two lines still reads.
#[test]
fn values_past_an_ascii_rows_declared_ones_are_ignored() {
    let text = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                 element face 2\nproperty list uchar int vertex_indices\nproperty uchar red\nend_header\n\
                 0 0 0 7 7\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2 255 9 1 1 1 1 1 1 1 1 1\n3 1 3\n2 255\n";
    let d = ply::read(text).unwrap();
    assert_eq!(d.positions, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]);
    assert_eq!(d.triangles, [0, 1, 2, 1, 3, 2]);
}

#[test]
fn binary_body_starting_with_newline_is_kept() {
    let d = load("assimp_cube_binary_starts_with_nl.ply").unwrap();
    assert_eq!(d.positions.len(), 8);
    assert_eq!(d.triangles.len(), 6 * 2 * 3);
    // The first x is the body's first 4 bytes, 0x0A included: skipping it as whitespace would shift everything.
    assert_eq!(d.positions[0], [f32::from_le_bytes([0x0a, 0xf6, 0xbe, 0x40]), 0.0, 0.0]);
    assert_eq!(d.positions[1], [f32::from_le_bytes([0x0a, 0xf6, 0xbe, 0x40]), 0.0, 1.0]);
}

#[test]
fn float_colours_scale_to_bytes() {
    let d = load("assimp_float_color.ply").unwrap();
    let c = d.colors.unwrap();
    assert_eq!(c.len(), 3);
    assert!(c.iter().flatten().any(|&v| v == 255), "{c:?}");
}

#[test]
fn rows_that_do_not_match_the_header_are_an_error() {
    // The header declares a list after six floats; the rows have no list, so the 7th value is read as a count.
    let e = load("assimp_issue623_comment_between_properties.ply").unwrap_err();
    assert!(matches!(e, PlyError::Body { row: 0, .. }), "{e}");
    assert!(e.to_string().contains("not a count"), "{e}");
}

#[test]
fn lone_cr_header_and_extra_element() {
    let d = load("draco_delim_test.ply").unwrap();
    assert_eq!(d.positions.len(), 24);
    // 8 polygons (quads and triangles), fan-triangulated.
    assert_eq!(d.triangles.len(), 12 * 3);
    assert!(d.normals.is_some() && d.colors.is_some());
}

#[test]
fn tabs_and_extra_whitespace() {
    let d = load("draco_test_extra_whitespace.ply").unwrap();
    assert_eq!(d.positions.len(), 3);
    assert_eq!(d.triangles, [0, 1, 2]);
}

#[test]
fn every_scalar_type_and_alias_parses_without_xyz_being_usable() {
    // A custom element "point" with every type: the header parses; there is no vertex element to use.
    let bytes = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad/ply/plyrs_all_atomic_types_ok_ascii.ply"),
    )
    .unwrap();
    let h = ply::parse_header(&bytes).unwrap();
    assert_eq!(h.elements[0].props.len(), 16);
    assert!(matches!(ply::read(&bytes), Err(PlyError::Unusable(_))));
}

#[test]
fn empty_cloud_loads_empty() {
    let d = load("plyrs_empty_2_ok_little_endian.ply").unwrap();
    assert!(d.positions.is_empty() && d.triangles.is_empty());
}

#[test]
fn greg_turk_example_with_edges() {
    let d = load("plyrs_greg_turk_example2_ok_ascii.ply").unwrap();
    assert_eq!(d.positions.len(), 8);
    assert!(d.colors.is_some());
    assert!(!d.triangles.is_empty());
}

#[test]
fn leading_spaces_load_without_xyz_z() {
    // "point" element with x, y only: parses, but has no vertex element.
    assert!(matches!(load("plyrs_leading_spaces_ok_ascii.ply"), Err(PlyError::Unusable(_))));
}

#[test]
fn crlf_and_char_face_property() {
    let d = load("trimesh_metadata_char_face_prop.ply").unwrap();
    assert_eq!(d.positions.len(), 4);
    assert_eq!(d.triangles.len(), 6);
}

#[test]
fn lists_in_custom_elements_are_skipped() {
    let d = load("trimesh_points_ascii_with_lists.ply").unwrap();
    assert_eq!(d.positions.len(), 5);
}

/// A vertex with a NaN or infinite coordinate is an error naming the element and row, not a garbage dataset.
#[test]
fn non_finite_positions_are_an_error_naming_the_row() {
    for bad in ["nan", "inf", "-inf", "1e39"] {
        let text = format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n\
             0 0 0\n1 0 0\n0 {bad} 0\n"
        );
        match vvgen::scene::ply::read(text.as_bytes()) {
            Err(vvgen::scene::ply::PlyError::Body { element, row, .. }) => {
                assert_eq!((element.as_str(), row), ("vertex", 2))
            }
            other => panic!("{bad}: {other:?}"),
        }
    }
}

/// A cloud whose element is called `point` (valid, and in ply-rs's suite) reads like `vertex`.
#[test]
fn a_point_element_reads_as_the_points() {
    let text =
        "ply\nformat ascii 1.0\nelement point 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n\
                1 2 3\n4 5 6\n";
    let d = vvgen::scene::ply::read(text.as_bytes()).unwrap();
    assert_eq!(d.positions, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
}

/// Whatever `check_file` refuses from a header and a size, reading the whole file refuses too: over the real odd
/// and malformed files, and each of them cut short at every eighth of its length.
#[test]
fn check_file_refuses_nothing_a_read_accepts() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad/ply");
    let tmp = tempfile::tempdir().unwrap();
    let mut refused = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let bytes = std::fs::read(entry.unwrap().path()).unwrap();
        for k in 1..=8 {
            let cut = &bytes[..bytes.len() * k / 8];
            let p = tmp.path().join("cut.ply");
            std::fs::write(&p, cut).unwrap();
            if let Err(e) = ply::check_file(&p) {
                refused += 1;
                assert!(ply::read(cut).is_err(), "check_file refused what read accepts: {e}");
            }
        }
    }
    assert!(refused > 10, "only {refused} cut files refused");
}

/// `vvgen check` reads every frame's header of a PLY sequence: a frame cut short or not a PLY at all is refused
/// there, naming the file, before anything renders, as the build refuses it when it reaches the frame (here
/// every frame: multi-view video). Check refuses such a frame even where the splits would not read it.
#[test]
fn check_refuses_a_sequence_frame_that_is_cut_short_or_not_a_ply() {
    use std::process::Command;
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir(d.join("seq")).unwrap();
    let frame = |f: usize| {
        let pos: Vec<[f32; 3]> = (0..500).map(|i| [i as f32 * 0.01, f as f32 * 0.1, (i % 7) as f32 * 0.02]).collect();
        ply::write(&ply::PlyOut { positions: &pos, ..Default::default() })
    };
    for f in 0..3 {
        std::fs::write(d.join(format!("seq/f_{f:04}.ply")), frame(f)).unwrap();
    }
    std::fs::write(
        d.join("m.toml"),
        "[dataset]\nname = \"t\"\nout = \"out\"\ncache = \"cache\"\n\
         [source.pc]\nply_sequence = \"seq/f_{frame:04}.ply\"\n\
         [render]\nresolution = [32, 32]\n[rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\ntime = \"all\"\n[output.d]\nwriter = \"dnerf\"\n",
    )
    .unwrap();
    let run = |args: &[&str]| Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(args).output().unwrap();
    assert_eq!(run(&["check", "m.toml"]).status.code(), Some(0));
    let cut = frame(1);
    let damages: [(&str, Vec<u8>, &str); 2] = [
        ("f_0001.ply", cut[..cut.len() - 7].to_vec(), "declares 500 rows"),
        ("f_0002.ply", b"solid not-a-ply\n".to_vec(), "not a PLY file"),
    ];
    for (name, bytes, says) in damages {
        for f in 0..3 {
            std::fs::write(d.join(format!("seq/f_{f:04}.ply")), frame(f)).unwrap();
        }
        std::fs::write(d.join("seq").join(name), bytes).unwrap();
        for args in [&["check", "m.toml"][..], &["-q", "build", "m.toml"][..]] {
            let out = run(args);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?} {name}: {err}");
            assert!(err.contains(name) && err.contains(says), "{args:?} {name}: {err}");
        }
        assert!(!d.join("out/t_dnerf/train").exists(), "{name}: nothing is rendered");
    }
}

/// A scan in georeferenced coordinates (UTM: millions of metres from the origin) is stepped by single
/// precision, which positions are held in: `check` says so, with the spacing there and the `origin` to set;
/// with it, the file's doubles are read relative to that point and keep their detail (the same positions as
/// the scan near zero), `vvgen new` writes it, and a sequence's frames are keyed by it.
#[test]
fn a_scan_far_from_the_origin_is_warned_about_and_read_relative_to_its_origin() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(args).output().unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    // A 2 m tent of doubles, 4 × 4 vertices, its ridge 0.23 high, at `offset`.
    let ply = |file: &str, offset: [f64; 3]| {
        let mut body = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                let (x, y) = (i as f64 * 2.0 / 3.0, j as f64 * 2.0 / 3.0);
                let z = 0.35 * (1.0 - ((x - 1.0).abs().max((y - 1.0).abs())));
                for (v, o) in [x, y, z].iter().zip(offset) {
                    body.extend((v + o).to_le_bytes());
                }
            }
        }
        for j in 0..3u32 {
            for i in 0..3u32 {
                let a = j * 4 + i;
                for t in [[a, a + 1, a + 5], [a, a + 5, a + 4]] {
                    body.push(3u8);
                    t.iter().for_each(|k| body.extend(k.to_le_bytes()));
                }
            }
        }
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 16\nproperty double x\n\
            property double y\nproperty double z\nelement face 18\nproperty list uchar uint vertex_indices\n\
            end_header\n"
            .to_vec();
        bytes.extend(body);
        std::fs::write(d.join(file), bytes).unwrap();
    };
    let manifest = |name: &str, source: &str, transform: &str| {
        std::fs::write(
            d.join(format!("{name}.toml")),
            format!(
                "[dataset]\nname = \"{name}\"\nout = \"out-{name}\"\npreview = false\n[source.{name}]\n{source}\n\
                 [transform]\n{transform}\n[render]\nresolution = [32, 32]\n[rig.h]\nkind = \"hemisphere\"\n\
                 [split.train]\nrig = \"h\"\nviews = 2\n[output.d]\nwriter = \"dnerf\"\n"
            ),
        )
        .unwrap();
    };
    let utm = [500_000.0, 4_000_000.0, 100.0];
    ply("utm.ply", utm);
    ply("local.ply", [10.0, -20.0, 3.0]);

    manifest("utm", "mesh = \"utm.ply\"", "fit = \"frame\"");
    let (code, err) = run(&["check", "utm.toml"]);
    assert_eq!(code, Some(0), "a warning, not an error: {err}");
    for says in ["source `utm`", "(500001.0, 4000001.0, 100.1)", "0.25 apart", "origin = [500001, 4000001, 100]"] {
        assert!(err.contains(says), "`{says}` not in: {err}");
    }
    manifest("local", "mesh = \"local.ply\"", "fit = \"frame\"");
    let (code, err) = run(&["check", "local.toml"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(!err.contains("single precision"), "{err}");

    // With the origin it suggests: no warning, and the positions of the scan near zero (single precision
    // stepped them by up to 0.125 without).
    manifest("utm", "mesh = \"utm.ply\"\norigin = [500001, 4000001, 100]", "fit = \"frame\"");
    let (code, err) = run(&["check", "utm.toml"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(!err.contains("single precision"), "{err}");
    let at = |file: &str, o: [f64; 3]| {
        vvgen::scene::source::ply_scene_at(&d.join(file), o).unwrap().primitives[0].positions.clone()
    };
    let (near, read) = (at("local.ply", [11.0, -19.0, 3.0]), at("utm.ply", [500_001.0, 4_000_001.0, 100.0]));
    let worst = near.iter().zip(&read).map(|(a, b)| (*a - *b).abs().max_element()).fold(0.0, f32::max);
    assert!(worst < 1e-6, "{worst}");
    let stepped = at("utm.ply", [0.0; 3]);
    let lost = near
        .iter()
        .zip(&stepped)
        .map(|(a, b)| (*a - (*b - glam::Vec3::new(500_001.0, 4_000_001.0, 100.0))).abs().max_element())
        .fold(0.0, f32::max);
    assert!(lost > 0.05, "without the origin the scan is stepped: {lost}");

    // `origin` is for PLY files; a glTF source is told how to move instead.
    manifest(
        "box",
        &format!(
            "mesh = \"{}\"\norigin = [1, 2, 3]",
            crate::common::data("gltf/BoxTextured/BoxTextured.glb").display()
        ),
        "fit = \"frame\"",
    );
    let (code, err) = run(&["check", "box.toml"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("`origin` applies to PLY and OBJ files") && err.contains("translate"), "{err}");

    // `vvgen new` sets it.
    let (code, err) = run(&["new", "utm.ply", "-o", "new.toml"]);
    assert_eq!(code, Some(0), "{err}");
    let text = std::fs::read_to_string(d.join("new.toml")).unwrap();
    assert!(text.contains("origin = [500001, 4000001, 100]"), "{text}");

    // A sequence's frames are keyed by their bytes and by the origin: moving it re-renders them, even where
    // the placement (a scale about zero) stays the same.
    std::fs::create_dir_all(d.join("seq")).unwrap();
    std::fs::copy(d.join("utm.ply"), d.join("seq/f_0.ply")).unwrap();
    for (x, want) in [(500_001.0, "0 cached"), (500_001.0, "2 cached"), (500_001.5, "0 cached")] {
        manifest(
            "seq",
            &format!("ply_sequence = \"seq/f_*.ply\"\norigin = [{x}, 4000001, 100]"),
            "fit = { height = 2.0 }",
        );
        let (code, err) = run(&["build", "seq.toml"]);
        assert_eq!(code, Some(0), "{err}");
        assert!(err.contains(&format!("2 images: {want}")), "origin x {x}: {err}");
    }
}

/// An ASCII PLY of one hexagon, its corners `corners` listed from the one at `first`.
fn hexagon(corners: [&str; 6], first: usize) -> String {
    let order: Vec<String> = (0..6).map(|k| ((first + k) % 6).to_string()).collect();
    format!(
        "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uchar int vertex_indices\nend_header\n{}\n6 {}\n",
        corners.join("\n"),
        order.join(" ")
    )
}

/// An L of three unit squares (area 3), and a convex hexagon.
const L_SHAPE: [&str; 6] = ["0 0 0", "2 0 0", "2 1 0", "1 1 0", "1 2 0", "0 2 0"];
const CONVEX: [&str; 6] = ["0 0 0", "2 0 0", "3 1 0", "2 2 0", "0 2 0", "-1 1 0"];

/// A concave polygon is filled as Blender fills it (ear clipping in its plane), where the fan from its first corner
/// covered the notch and overlapped itself; a convex polygon keeps its fan, triangle for triangle. Whether a file
/// has a polygon filled otherwise than by its fan keys a sequence's frame apart ("ply polygons 1"), and is
/// remembered by the stat cache; a point cloud's is answered from its header.
#[test]
fn concave_polygons_are_filled_as_blender_fills_them_and_key_their_frames() {
    let area = |d: &ply::PlyData| {
        let p = |i: u32| glam::Vec3::from(d.positions[i as usize]);
        d.triangles.chunks_exact(3).map(|t| 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length()).sum::<f32>()
    };
    // From corner (2, 1), beside the notch: the fan's second triangle lay in the notch, outside the L.
    let notch = ply::read(hexagon(L_SHAPE, 2).as_bytes()).unwrap();
    assert_eq!(notch.triangles.len(), 12);
    assert!((area(&notch) - 3.0).abs() < 1e-5, "{}", area(&notch));
    assert!(notch.unfanned);
    let convex = ply::read(hexagon(CONVEX, 0).as_bytes()).unwrap();
    assert_eq!(convex.triangles, [0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5]);
    assert!(!convex.unfanned);
    let d = tempfile::tempdir().unwrap();
    let stat = vvgen::cache::StatCache::load(&d.path().join("stat"));
    let cloud = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
                 end_header\n0 0 0\n";
    let files = [("notch.ply", hexagon(L_SHAPE, 2), true), ("convex.ply", hexagon(CONVEX, 3), false)];
    for (name, text, unfanned) in files.into_iter().chain([("cloud.ply", cloud.to_string(), false)]) {
        std::fs::write(d.path().join(name), text).unwrap();
        assert_eq!(vvgen::scene::source::ply_facts(&d.path().join(name), &stat).unwrap().unfanned, unfanned, "{name}");
    }
}

/// A file of triangle strips (Stanford's scans are stored so) is a mesh, where it read as its vertices alone, a
/// point cloud: whether a file has strips keys a sequence's frame apart ("ply strips 1"), answered from its header
/// and remembered by the stat cache.
#[test]
fn triangle_strips_are_a_mesh_and_key_their_frames() {
    let header = |el: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
             {el}end_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n"
        )
    };
    let strips = header("element tristrips 1\nproperty list int int vertex_indices\n") + "4 0 1 2 3\n";
    let d = ply::read(strips.as_bytes()).unwrap();
    assert_eq!(d.triangles, [0, 1, 2, 2, 1, 3]);
    let dir = tempfile::tempdir().unwrap();
    let stat = vvgen::cache::StatCache::load(&dir.path().join("stat"));
    let faces = header("element face 1\nproperty list uchar int vertex_indices\n") + "4 0 1 3 2\n";
    for (name, text, has) in
        [("strips.ply", strips, true), ("faces.ply", faces, false), ("cloud.ply", header(""), false)]
    {
        std::fs::write(dir.path().join(name), text).unwrap();
        assert_eq!(vvgen::scene::source::ply_facts(&dir.path().join(name), &stat).unwrap().strips, has, "{name}");
    }
}
