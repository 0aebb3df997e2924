//! OBJ and MTL text as exporters write it and Blender 4.5's importer reads it, where tobj alone refuses it or reads
//! it otherwise: legacy encodings (3ds Max's Latin-1 names; UTF-16; a byte-order mark), one-number colours and
//! unnamed materials, colours on some vertices only, polylines, point clouds, and numbers that do not parse.
//! Found on assimp's OBJ test models, run as a newcomer runs them.

use std::path::Path;
use std::process::Command;

use vvgen::scene::obj;
use vvgen::scene::PosedScene;

/// A unit quad of material `NAME` (two triangles), its library named first.
const QUAD: &str = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl NAME\nf 1 2 3 4\n";

fn read(d: &Path, file: &str) -> PosedScene {
    obj::scene(&d.join(file)).unwrap_or_else(|e| panic!("{file}: {}", crate::common::error_chain(&e)))
}

/// The quad's geometry and its material's base colour.
fn quad(s: &PosedScene) -> (Vec<glam::Vec3>, Vec<u32>, glam::Vec4) {
    assert_eq!(s.primitives.len(), 1);
    let p = &s.primitives[0];
    (p.positions.clone(), p.indices.to_vec(), s.material(p.material).base_color)
}

fn utf16(text: &str, big_endian: bool) -> Vec<u8> {
    let mut bytes = if big_endian { vec![0xFE, 0xFF] } else { vec![0xFF, 0xFE] };
    for u in text.encode_utf16() {
        bytes.extend(if big_endian { u.to_be_bytes() } else { u.to_le_bytes() });
    }
    bytes
}

#[test]
fn text_in_a_legacy_encoding_reads_as_its_utf8_twin() {
    let d = tempfile::tempdir().unwrap();
    let d = d.path();
    // The twin: UTF-8, a material whose name is not ASCII, red.
    std::fs::write(d.join("m.mtl"), "newmtl Terraindæk\nKd 0.8 0.1 0.1\n").unwrap();
    std::fs::write(d.join("utf8.obj"), QUAD.replace("NAME", "Terraindæk")).unwrap();
    let twin = quad(&read(d, "utf8.obj"));
    assert_eq!(twin.1.len(), 6);
    assert!(twin.2.x > 0.5 && twin.2.y < 0.2, "the material is found: {:?}", twin.2);
    // UTF-16 (both byte orders, with their mark) and a UTF-8 byte-order mark before the `mtllib` line.
    std::fs::write(d.join("be.obj"), utf16(&QUAD.replace("NAME", "Terraindæk"), true)).unwrap();
    std::fs::write(d.join("le.obj"), utf16(&QUAD.replace("NAME", "Terraindæk"), false)).unwrap();
    std::fs::write(d.join("bom.obj"), format!("\u{FEFF}{}", QUAD.replace("NAME", "Terraindæk"))).unwrap();
    for file in ["be.obj", "le.obj", "bom.obj"] {
        assert_eq!(quad(&read(d, file)), twin, "{file}");
    }
    // 3ds Max's Latin-1: the name's `æ` is one byte (0xE6) in the OBJ and in its own MTL, neither UTF-8.
    let mut obj = QUAD.replace("m.mtl", "latin1.mtl").replace("NAME", "Terraind\u{1}k").into_bytes();
    let mut mtl = b"newmtl Terraind\x01k\r\nKd 0.8 0.1 0.1\r\n".to_vec();
    for b in obj.iter_mut().chain(mtl.iter_mut()).filter(|b| **b == 1) {
        *b = 0xE6;
    }
    assert!(std::str::from_utf8(&obj).is_err() && std::str::from_utf8(&mtl).is_err());
    std::fs::write(d.join("latin1.obj"), obj).unwrap();
    std::fs::write(d.join("latin1.mtl"), mtl).unwrap();
    assert_eq!(quad(&read(d, "latin1.obj")), twin);
}

#[test]
fn mtl_statements_blender_reads_are_read() {
    let d = tempfile::tempdir().unwrap();
    let d = d.path();
    // A colour of one number is a grey (the format's own rule; Blender's exporter wrote `Ks 0`).
    std::fs::write(d.join("m.mtl"), "newmtl a\nKd 0.25\nKs 0\n").unwrap();
    std::fs::write(d.join("grey.obj"), QUAD.replace("NAME", "a")).unwrap();
    let grey = quad(&read(d, "grey.obj")).2;
    std::fs::write(d.join("m.mtl"), "newmtl a\nKd 0.25 0.25 0.25\nKs 0 0 0\n").unwrap();
    assert_eq!(grey, quad(&read(d, "grey.obj")).2);
    // A material without a name, used by `usemtl` without a name (Blender 2.61 wrote them so).
    std::fs::write(d.join("m.mtl"), "newmtl \nKd 0.1 0.8 0.1\n").unwrap();
    std::fs::write(d.join("unnamed.obj"), QUAD.replace("NAME", "")).unwrap();
    let green = quad(&read(d, "unnamed.obj")).2;
    assert!(green.y > 0.5 && green.x < 0.2, "the unnamed material is used: {green:?}");
    // Two numbers are neither: an error at the line.
    std::fs::write(d.join("m.mtl"), "newmtl a\nKd 0.25 0.5\n").unwrap();
    let e = obj::scene(&d.join("grey.obj")).unwrap_err().to_string();
    assert!(e.contains("m.mtl:2") && e.contains("or one, a grey"), "{e}");
}

#[test]
fn colours_on_some_vertices_only_are_dropped_per_object_as_blender_drops_them() {
    let d = tempfile::tempdir().unwrap();
    let d = d.path();
    // Object `a`: every vertex coloured. Object `b`: one of three.
    let text = "o a\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n\
                o b\nv 2 0 0\nv 3 0 0 1 1 0\nv 2 1 0\nf 4 5 6\n";
    std::fs::write(d.join("part.obj"), text).unwrap();
    let s = read(d, "part.obj");
    assert_eq!(s.primitives.len(), 2);
    assert_eq!(s.primitives[0].colors.len(), 3, "object a keeps its colours");
    assert_eq!(s.primitives[0].colors[0], glam::Vec4::new(1.0, 0.0, 0.0, 1.0));
    assert!(s.primitives[1].colors.is_empty(), "object b has none");
    // Object b is drawn as a face without material or colours is: Blender's grey.
    std::fs::write(d.join("plain.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let plain = read(d, "plain.obj");
    let grey = plain.material(plain.primitives[0].material).base_color;
    assert_eq!(s.material(s.primitives[1].material).base_color, grey);
}

#[test]
fn polylines_draw_nothing_as_in_blender() {
    let d = tempfile::tempdir().unwrap();
    let d = d.path();
    // A triangle and a square polyline: tobj filled the polyline as a polygon (two more triangles).
    std::fs::write(d.join("lines.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nl 1 2 3 4 1\n").unwrap();
    assert_eq!(read(d, "lines.obj").triangle_count(), 1);
    // Vertices with lines and no faces (a wireframe): an error that says so, and that without its lines the
    // vertices are drawn as points.
    std::fs::write(d.join("wire.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2 3\nl 3 1\n").unwrap();
    let says = "3 vertices, 2 lines and no faces";
    let e = obj::scene(&d.join("wire.obj")).unwrap_err().to_string();
    assert!(e.contains(says) && e.contains("as a point cloud"), "{e}");
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["new", "wire.obj"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains(says));
}

/// An OBJ of vertices alone (MeshLab's and CloudCompare's point clouds, `v x y z r g b`) is drawn as points, as the
/// same cloud in PLY is: a coloured scan saved both ways renders the same images, from a manifest `vvgen new` writes
/// for the OBJ by its bare name. Vertices without colours are white; colours on only some vertices are dropped.
#[test]
fn an_obj_point_cloud_renders_as_its_ply_twin() {
    let d = tempfile::tempdir().unwrap();
    let d = d.path();
    let ply = std::fs::read(crate::common::data("seq/torus_vox10_1000.ply")).unwrap();
    std::fs::write(d.join("scan.ply"), &ply).unwrap();
    let cloud = vvgen::scene::ply::read(&ply).unwrap();
    let colours = cloud.colors.as_ref().expect("a coloured scan");
    let mut obj = String::from("# MeshLab\n");
    for (p, c) in cloud.positions.iter().zip(colours) {
        let [r, g, b] = [c[0], c[1], c[2]].map(|v| v as f64 / 255.0);
        obj += &format!("v {} {} {} {r:.9} {g:.9} {b:.9}\n", p[0], p[1], p[2]);
    }
    std::fs::write(d.join("scan.obj"), obj).unwrap();
    let s = read(d, "scan.obj");
    assert_eq!((s.point_count(), s.triangle_count()), (cloud.positions.len(), 0));
    let vvgen = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(args).output().unwrap();
        assert_eq!(out.status.code(), Some(0), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    };
    vvgen(&["new", "scan.obj"]);
    let text = std::fs::read_to_string(d.join("scan.toml")).unwrap();
    // A cloud keeps its scanner's axes: its up is guessed as a PLY scan's is, not taken as OBJ's +Y.
    assert!(text.contains("mesh   = \"scan.obj\"") && text.contains("guessed"), "{text}");
    let quick = text
        .replace("views = 100", "views = 2")
        .replace("views = 10", "views = 1")
        .replace("views    = 20", "views    = 1");
    std::fs::write(d.join("obj.toml"), quick.replace("out/scan", "out/obj")).unwrap();
    std::fs::write(d.join("ply.toml"), quick.replace("out/scan", "out/ply").replace("scan.obj", "scan.ply")).unwrap();
    vvgen(&["-q", "build", "obj.toml"]);
    vvgen(&["-q", "build", "ply.toml"]);
    let image =
        |which: &str| image::open(d.join(format!("out/{which}/scan_dnerf/train/r_0001.png"))).unwrap().to_rgba8();
    let (a, b) = (image("obj"), image("ply"));
    assert!(a.pixels().filter(|p| p[3] == 255).count() > 1000, "the cloud shows");
    let off = a.pixels().zip(b.pixels()).map(|(p, q)| (0..4).map(|k| p[k].abs_diff(q[k])).max().unwrap()).max();
    assert!(off.unwrap() <= 1, "the OBJ and PLY clouds differ by {off:?} levels");
    // Colours on some vertices only: dropped (white), as for a mesh.
    std::fs::write(d.join("partial.obj"), "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 1 0\n").unwrap();
    let s = read(d, "partial.obj");
    assert_eq!((s.point_count(), s.primitives[0].colors.len()), (3, 0));
    assert_eq!(s.material(s.primitives[0].material).base_color, glam::Vec4::ONE);
}

#[test]
fn a_number_tobj_cannot_read_is_an_error_at_its_line() {
    let d = tempfile::tempdir().unwrap();
    let d = d.path();
    std::fs::write(d.join("n.obj"), "v 1e2 2. +3.0\nv 1 2 3\nv 1e+2 2.e+1 3.1+e2\nvt 0.5\nf 1 2 3\n").unwrap();
    let e = obj::scene(&d.join("n.obj")).unwrap_err().to_string();
    assert!(e.contains("n.obj:3") && e.contains("`3.1+e2` is not a number"), "{e}");
    std::fs::write(d.join("n.obj"), "v 1e2 2. +3.0\nv 1 2 3\nv 1 1 1\nvt 0.5\nf 1 2 3\n").unwrap();
    let e = obj::scene(&d.join("n.obj")).unwrap_err().to_string();
    assert!(e.contains("n.obj:4") && e.contains("`vt` needs 2 numbers"), "{e}");
}

/// A line continued by `\` (the OBJ spec's continuation, trimesh's wallhole.obj) reads joined, as Blender reads
/// it, and later lines keep their numbers in errors; a texture coordinate or normal index out of range is
/// dropped as Blender drops it (trimesh's cubevt.obj), a vertex index out of range stays an error.
#[test]
fn continued_lines_join_and_corner_indices_out_of_range_are_dropped() {
    let d = tempfile::tempdir().unwrap();
    let d = d.path();
    std::fs::write(d.join("one.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
    std::fs::write(d.join("split.obj"), "v 0 0 0\nv 1 0 \\\n0\nv 1 1 0\r\nv 0 1 0\nf 1 2 \\\r\n3 \\\n4\n").unwrap();
    let geometry = |s: &PosedScene| (s.primitives[0].positions.clone(), s.primitives[0].indices.to_vec());
    assert_eq!(geometry(&read(d, "split.obj")), geometry(&read(d, "one.obj")));
    std::fs::write(d.join("bad.obj"), "v 0 0 0\nv 1 \\\n0 0\nv 1 1 0\nf 1 2 \\\n3\nf 1 2 9\n").unwrap();
    let e = obj::scene(&d.join("bad.obj")).unwrap_err().to_string();
    assert!(e.contains("bad.obj:7") && e.contains("vertex 9"), "{e}");
    // `vt` and `vn` named but never given: the corners keep their vertices.
    std::fs::write(d.join("corners.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/4/7\n")
        .unwrap();
    let s = read(d, "corners.obj");
    assert_eq!(geometry(&s), geometry(&read(d, "one.obj")));
    assert!(s.primitives[0].uvs.is_empty());
}

/// A concave polygon covers what it outlines, as Blender fills it (tobj's fan covered its notch: trimesh's
/// wallhole.obj drew 5 % more area than Blender's import of it, assimp's concave_polygon.obj 13 times as much);
/// a convex one is the fan it always was.
#[test]
fn a_concave_polygon_covers_its_outline() {
    let d = tempfile::tempdir().unwrap();
    let d = d.path();
    // An L of area 3, listed from a corner that does not see its far arm.
    std::fs::write(d.join("l.obj"), "v 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 0\nf 1 2 3 4 5 6\n").unwrap();
    let s = read(d, "l.obj");
    let (p, t) = (&s.primitives[0].positions, &s.primitives[0].indices);
    let tri = |t: &[u32]| (p[t[1] as usize] - p[t[0] as usize]).cross(p[t[2] as usize] - p[t[0] as usize]);
    let area: f32 = t.chunks_exact(3).map(|t| tri(t).length() / 2.0).sum();
    assert!((area - 3.0).abs() < 1e-5, "{area}");
    assert!(t.chunks_exact(3).all(|t| tri(t).z > 0.0), "the polygon's winding kept");
    std::fs::write(d.join("q.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
    assert_eq!(read(d, "q.obj").primitives[0].indices.to_vec(), [0, 1, 2, 0, 2, 3]);
}
