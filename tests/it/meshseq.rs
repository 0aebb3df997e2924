//! Mesh-sequence sources: one textured mesh per frame (OBJ + MTL + texture, textured PLY), the topology changing
//! every frame; keyed per frame by the frame's files; bad input named by file and line.

use std::path::Path;
use std::process::Command;

use vvgen::build::{build, Options, Silent};
use vvgen::plan::actions::Kind;

/// A 2×2 texture: red, green (top row), blue, white (bottom row).
fn texture_png(path: &Path) {
    let img = image::RgbaImage::from_raw(
        2,
        2,
        [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255], [255, 255, 255, 255]].concat(),
    )
    .unwrap();
    img.save(path).unwrap();
}

/// Frame `f`: a unit quad in the XY plane facing +Z (y up), shifted by `0.1·f` along x, textured over the whole
/// texture; odd frames add a triangle (the topology changes).
fn obj(f: usize) -> String {
    let x = 0.1 * f as f64;
    let mut s = String::from("# frame\nmtllib skin.mtl\n");
    for (px, py) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
        s.push_str(&format!("v {} {py} 0\n", px + x));
    }
    s.push_str("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl skin\nf 1/1 2/2 3/3 4/4\n");
    if f % 2 == 1 {
        s.push_str("v 0.6 0.6 0\nv 0.9 0.6 0\nv 0.75 0.9 0\nf 5/1 6/2 7/3\n");
    }
    s
}

fn write_sequence(d: &Path) {
    std::fs::create_dir_all(d.join("seq")).unwrap();
    texture_png(&d.join("seq/tex.png"));
    std::fs::write(d.join("seq/skin.mtl"), "newmtl skin\nKd 1 1 1\nmap_Kd tex.png\n").unwrap();
    for f in 0..3 {
        std::fs::write(d.join(format!("seq/f_{f:03}.obj")), obj(f)).unwrap();
    }
}

fn manifest(source: &str) -> String {
    format!(
        "[dataset]\nname = \"ms\"\nout = \"out\"\ncache = \"cache\"\n\
         [source.cap]\n{source}\nframes = {{ start = 0, end = 2, fps = 10 }}\n\
         [render]\nresolution = [48, 48]\nsamples = 4\n\
         [rig.front]\nkind = \"explicit\"\nposes = [{{ position = [0.1, -3.0, 0.0] }}]\n\
         [split.train]\nrig = \"front\"\n\
         [output.d]\nwriter = \"dnerf\"\ninit_points = 0\n\
         [output.p]\nwriter = \"ply-sequence\"\npoints = 400\n"
    )
}

fn run(d: &Path) -> vvgen::build::Report {
    let m = crate::common::load(&d.join("m.toml"));
    build(&m, &d.join("cache"), Options::default(), &Silent).unwrap()
}

fn pixel(d: &Path, rel: &str, x: u32, y: u32) -> [u8; 4] {
    image::open(d.join(rel)).unwrap().to_rgba8().get_pixel(x, y).0
}

#[test]
fn an_obj_sequence_renders_its_textures_and_rebuilds_per_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    write_sequence(d);
    std::fs::write(d.join("m.toml"), manifest("mesh_sequence = \"seq/f_{frame:03}.obj\"")).unwrap();
    let r = run(d);
    assert_eq!(r.ran(Kind::RenderPass), 3);
    // OBJ is y up; the world is z up: the quad stands facing the camera at -y. Its top half is the texture's top
    // row (red left, green right), its bottom half the bottom row (blue, white).
    let root = "out/ms_dnerf/train";
    let quarter = |f: usize, x: u32, y: u32| pixel(d, &format!("{root}/r_{f:04}.png"), x, y);
    let (tl, tr, bl, br) = (quarter(0, 18, 18), quarter(0, 29, 18), quarter(0, 18, 29), quarter(0, 29, 29));
    assert!(tl[0] > 200 && tl[1] < 60 && tl[2] < 60 && tl[3] == 255, "top left is red: {tl:?}");
    assert!(tr[1] > 200 && tr[0] < 60, "top right is green: {tr:?}");
    assert!(bl[2] > 200 && bl[0] < 60, "bottom left is blue: {bl:?}");
    assert!(br.iter().all(|&c| c > 200), "bottom right is white: {br:?}");
    // The topology changes every frame: frame 1 has a triangle more; the point samples follow each frame.
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("out/ms_points").join(vvgen::export::META)).unwrap()).unwrap();
    assert!(meta["sources"][0]["topology"].as_str().unwrap().contains("no temporal correspondence"));
    assert!(d.join("out/ms_points/ms_0002.ply").is_file());
    // Keys are the frame's files: editing frame 2 re-renders frame 2 alone; editing the shared texture, every frame.
    std::fs::write(d.join("seq/f_002.obj"), obj(2).replace("usemtl skin\n", "usemtl skin\ns off\n") + "v 9 9 9\n")
        .unwrap();
    let r = run(d);
    assert_eq!((r.ran(Kind::RenderPass), r.ran(Kind::PointFrame)), (1, 1));
    image::RgbaImage::from_pixel(2, 2, image::Rgba([10, 20, 30, 255])).save(d.join("seq/tex.png")).unwrap();
    assert_eq!(run(d).ran(Kind::RenderPass), 3);
    // Correspondence cannot hold across topology changes: refused.
    let with = manifest("mesh_sequence = \"seq/f_{frame:03}.obj\"")
        .replace("points = 400\n", "points = 400\ncorrespondence = true\n");
    let errors = vvgen::manifest::parse(&with, &d.join("m.toml")).unwrap_err();
    assert!(errors.render(false).contains("`correspondence` needs mesh sources"), "{}", errors.render(false));
}

/// Keying remembers what each frame's own content decides (its face indices check out, the libraries it names),
/// so a build with nothing to do reads no frame in full; the libraries and textures are checked every build, and
/// an edited frame is scanned again.
#[test]
fn keying_remembers_each_frames_libraries_by_content() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    write_sequence(d);
    std::fs::write(d.join("m.toml"), manifest("mesh_sequence = \"seq/f_{frame:03}.obj\"")).unwrap();
    run(d);
    // One remembered fact per frame content (three different frames), in the dataset's stat cache.
    let stat_dir = d.join("cache/stat");
    let facts: usize = std::fs::read_dir(&stat_dir)
        .unwrap()
        .map(|e| std::fs::read_to_string(e.unwrap().path()).unwrap())
        .map(|t| t.lines().filter(|l| l.starts_with("derived\tobj libraries 3\t")).count())
        .sum();
    assert_eq!(facts, 3);
    assert!(run(d).nothing_to_do());
    // A remembered frame's library is still checked: a texture the MTL now names but that is missing is warned of
    // at the MTL's line, though no frame changed.
    std::fs::write(d.join("seq/skin.mtl"), "newmtl skin\nKd 1 1 1\nmap_Kd gone.png\n").unwrap();
    let m = crate::common::load(&d.join("m.toml"));
    let report = build(&m, &d.join("cache"), Options::default(), &Silent).unwrap();
    assert!(
        report.warnings.iter().any(|w| w.contains("skin.mtl:3") && w.contains("gone.png")),
        "{:?}",
        report.warnings
    );
    std::fs::write(d.join("seq/skin.mtl"), "newmtl skin\nKd 1 1 1\nmap_Kd tex.png\n").unwrap();
    // An edited frame is scanned again: a face index out of range is named at its line.
    std::fs::write(d.join("seq/f_001.obj"), obj(1) + "f 1 2 99\n").unwrap();
    let err = build(&m, &d.join("cache"), Options::default(), &Silent).unwrap_err();
    let text = format!("{:#}", anyhow::Error::from(err));
    assert!(text.contains("f_001.obj") && text.contains("vertex 99"), "{text}");
}

#[test]
fn a_textured_ply_sequence_reads_texture_coordinates_and_its_texture_file() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir_all(d.join("seq")).unwrap();
    texture_png(&d.join("seq/tex.png"));
    for f in 0..3 {
        // MeshLab's convention: per-vertex texture_u/texture_v (v up), `comment TextureFile`. Z up. The name as
        // written on Windows too: a path from the capture machine (found by its base name), a backslash.
        let name = ["tex.png", "C:\\capture\\take 2\\tex.png", ".\\tex.png"][f];
        let mut s = format!("ply\nformat ascii 1.0\ncomment TextureFile {name}\nelement vertex 4\n");
        s.push_str("property float x\nproperty float y\nproperty float z\nproperty float texture_u\nproperty float texture_v\n");
        s.push_str("element face 1\nproperty list uchar int vertex_indices\nend_header\n");
        for (x, z, u, v) in [(-0.5, -0.5, 0, 0), (0.5, -0.5, 1, 0), (0.5, 0.5, 1, 1), (-0.5, 0.5, 0, 1)] {
            s.push_str(&format!("{} 0 {z} {u} {v}\n", x + 0.1 * f as f64));
        }
        s.push_str("4 0 1 2 3\n");
        std::fs::write(d.join(format!("seq/f_{f:03}.ply")), s).unwrap();
    }
    std::fs::write(d.join("m.toml"), manifest("mesh_sequence = \"seq/f_{frame:03}.ply\"")).unwrap();
    run(d);
    for f in 0..3 {
        // Each frame is 0.1 further along x; the 2 × 2 texture is filtered, pure only at its texels' centres: the
        // top row holds a red pixel, the bottom row a white one.
        let row = |y: u32| (8..40).map(move |x| pixel(d, &format!("out/ms_dnerf/train/r_{f:04}.png"), x, y));
        assert!(row(18).any(|p| p[0] > 200 && p[1] < 60 && p[2] < 60), "frame {f}: no red on the top row");
        assert!(row(29).any(|p| p.iter().all(|&c| c > 200)), "frame {f}: no white on the bottom row");
    }
}

/// A bad-input case: what, how the fixture is damaged, what the error says.
type Case = (&'static str, fn(&Path), &'static str);

/// Bad mesh frames: `check` names the file and line (and `build` refuses the same way, before rendering).
#[test]
fn bad_mesh_frames_are_named_by_file_and_line() {
    let cases: [Case; 4] = [
        (
            "a face index out of range",
            |d| std::fs::write(d.join("seq/f_001.obj"), obj(1).replace("f 5/1 6/2 7/3", "f 5/1 6/2 17/3")).unwrap(),
            "f_001.obj:16: face corner `17/3` refers to vertex 17, but only 7 are defined above",
        ),
        (
            // tobj itself panics on a colour short of three numbers (found by the fuzzer).
            "a colour with two numbers",
            |d| std::fs::write(d.join("seq/skin.mtl"), "newmtl skin\nKd 1 1\nmap_Kd tex.png\n").unwrap(),
            "skin.mtl:2: `Kd` needs 3 finite numbers (or one, a grey): `Kd 1 1`",
        ),
        (
            "an opacity that is not a number",
            |d| std::fs::write(d.join("seq/skin.mtl"), "newmtl skin\nd nan\nmap_Kd tex.png\n").unwrap(),
            "skin.mtl:2: `d` needs a finite number: `d nan`",
        ),
        (
            "an unreadable texture",
            |d| std::fs::write(d.join("seq/tex.png"), b"not a png").unwrap(),
            "tex.png: cannot decode the texture",
        ),
    ];
    for (what, damage, says) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        write_sequence(d);
        std::fs::write(d.join("m.toml"), manifest("mesh_sequence = \"seq/f_{frame:03}.obj\"")).unwrap();
        damage(d);
        let check =
            Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["check", "m.toml"]).output().unwrap();
        let err = String::from_utf8_lossy(&check.stderr);
        if what != "an unreadable texture" {
            // Decoding is the renderer's: the header scan cannot tell a broken PNG.
            assert_eq!(check.status.code(), Some(2), "{what}: {err}");
            assert!(err.contains(says), "{what}: {err}");
        }
        let out =
            Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["-q", "build", "m.toml"]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{what}: {err}");
        assert!(err.contains(says), "{what}: {err}");
        assert!(!d.join("out/ms_dnerf/train").exists(), "{what}: nothing is rendered");
    }
}

#[test]
fn a_gltf_per_frame_sequence_builds() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir_all(d.join("seq")).unwrap();
    for f in 0..3 {
        // The triangle at rest (a mesh frame is posed at t = 0), a different size each frame.
        let gltf = crate::common::animated_triangle(0.3).replace(
            "\"nodes\": [{\"mesh\": 0}]",
            &format!("\"nodes\": [{{\"mesh\": 0, \"scale\": [{s}, {s}, {s}]}}]", s = 1.0 + f as f64),
        );
        std::fs::write(d.join(format!("seq/f_{f:03}.gltf")), gltf).unwrap();
    }
    std::fs::write(
        d.join("m.toml"),
        manifest("mesh_sequence = \"seq/f_*.gltf\"").replace("frames = { start = 0, end = 2, fps = 10 }\n", ""),
    )
    .unwrap();
    let r = run(d);
    assert_eq!(r.ran(Kind::RenderPass), 3);
    let covered = |f: usize| {
        let img = image::open(d.join(format!("out/ms_dnerf/train/r_{f:04}.png"))).unwrap().to_rgba8();
        img.pixels().filter(|p| p[3] > 0).count()
    };
    assert!(covered(0) > 20 && covered(2) > 3 * covered(0), "{} {}", covered(0), covered(2));
}

#[test]
fn a_gltf_frame_is_keyed_by_the_buffers_beside_it() {
    // Two frames (two sizes) naming one external buffer: editing the .bin alone (the JSON unchanged) renders
    // them again.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir_all(d.join("seq")).unwrap();
    let triangle = |x: f32| -> Vec<u8> {
        [[-0.5f32, -0.5, 0.0], [x, -0.5, 0.0], [0.0, 0.5, 0.0]].iter().flatten().flat_map(|v| v.to_le_bytes()).collect()
    };
    let gltf = r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "scale": [SZ, SZ, SZ]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [-0.5, -0.5, 0.0], "max": [1.0, 0.5, 0.0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}], "buffers": [{"uri": "tri.bin", "byteLength": 36}]}"#;
    for f in 0..2 {
        std::fs::write(d.join(format!("seq/f_{f:03}.gltf")), gltf.replace("SZ", &format!("{}", 1 + f))).unwrap();
    }
    std::fs::write(d.join("seq/tri.bin"), triangle(0.5)).unwrap();
    let text = manifest("mesh_sequence = \"seq/f_*.gltf\"").replace("frames = { start = 0, end = 2, fps = 10 }\n", "");
    std::fs::write(d.join("m.toml"), text).unwrap();
    assert_eq!(run(d).ran(Kind::RenderPass), 2);
    assert_eq!(run(d).ran(Kind::RenderPass), 0);
    std::fs::write(d.join("seq/tri.bin"), triangle(1.0)).unwrap();
    assert_eq!(run(d).ran(Kind::RenderPass), 2, "the buffer changed, the JSON did not");
}

/// An OBJ in georeferenced coordinates (a photogrammetry export, UTM metres) is read relative to its `origin`
/// in double precision, as a PLY is: the positions are the same file's near zero, vertex colours kept; without
/// the origin, single precision steps them. `vvgen new` sets the origin, and `check` takes it on a `mesh` and on
/// a `mesh_sequence` of OBJ frames.
#[test]
fn an_obj_far_from_the_origin_is_read_relative_to_its_origin() {
    let d = tempfile::tempdir().unwrap();
    let d = d.path();
    // A 5 × 5 bumpy sheet with vertex colours, in dyadic metres (exact in decimal and in binary), written at `at`.
    let write = |file: &str, at: [f64; 3]| {
        let mut text = String::new();
        for j in 0..5 {
            for i in 0..5 {
                let (x, y, z) = (i as f64 * 0.125, j as f64 * 0.125, ((i * 7 + j * 3) % 5) as f64 * 0.015625);
                let c = (i + j) as f64 / 8.0;
                text += &format!("v {:.6} {:.6} {:.6} {c} 0.5 {}\n", at[0] + x, at[1] + y, at[2] + z, 1.0 - c);
            }
        }
        for j in 0..4 {
            for i in 0..4 {
                let a = j * 5 + i + 1;
                text += &format!("f {} {} {}\nf {} {} {}\n", a, a + 1, a + 6, a, a + 6, a + 5);
            }
        }
        std::fs::write(d.join(file), text).unwrap();
    };
    let far = [500_001.0, 4_000_001.0, 100.0];
    write("local.obj", [0.0; 3]);
    write("utm.obj", far);
    let read = |file: &str, o: [f64; 3]| {
        let s = vvgen::scene::obj::scene_at(&d.join(file), o).unwrap();
        (s.primitives[0].positions.clone(), s.primitives[0].colors.clone())
    };
    let (near, near_colours) = read("local.obj", [0.0; 3]);
    let (shifted, colours) = read("utm.obj", far);
    assert_eq!(near.len(), 25, "the sheet's vertices");
    assert_eq!(near, shifted, "read relative to its origin, the scan is the sheet near zero");
    assert_eq!(near_colours, colours, "vertex colours kept");
    let (stepped, _) = read("utm.obj", [0.0; 3]);
    let o = glam::Vec3::new(far[0] as f32, far[1] as f32, far[2] as f32);
    let lost = near.iter().zip(&stepped).map(|(a, b)| (*a - (*b - o)).abs().max_element()).fold(0.0, f32::max);
    assert!(lost > 0.05, "without the origin the scan is stepped: {lost}");

    let vvgen = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(args).output().unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (code, err) = vvgen(&["new", "utm.obj", "-o", "new.toml"]);
    assert_eq!(code, Some(0), "{err}");
    let text = std::fs::read_to_string(d.join("new.toml")).unwrap();
    assert!(text.contains("origin = [500001, 4000001, 100]"), "{text}");
    let (code, err) = vvgen(&["check", "new.toml"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(!err.contains("single precision"), "{err}");
    std::fs::create_dir(d.join("seq")).unwrap();
    std::fs::copy(d.join("utm.obj"), d.join("seq/f_000.obj")).unwrap();
    let seq = "[dataset]\nname = \"s\"\nout = \"out\"\n[source.s]\nmesh_sequence = \"seq/f_*.obj\"\n\
               origin = [500001, 4000001, 100]\n[rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\n\
               views = 2\n[output.d]\nwriter = \"dnerf\"\n";
    std::fs::write(d.join("seq.toml"), seq).unwrap();
    let (code, err) = vvgen(&["check", "seq.toml"]);
    assert_eq!(code, Some(0), "{err}");
}

/// `opaque = true` takes the materials' own opacity as 1: an OBJ sequence whose MTL says `d 0` (an exporter's
/// transparency, `Tr`'s sense) draws nothing, as in Blender, and is warned of; with `opaque` its frames re-render
/// (the option is in their keys, read from files) and show, without the warning. A plane takes no `opaque`.
#[test]
fn opaque_draws_a_sequence_whose_materials_read_as_transparent() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    write_sequence(d);
    std::fs::write(d.join("seq/skin.mtl"), "newmtl skin\nKd 1 1 1\nd 0\nmap_Kd tex.png\n").unwrap();
    let source = "mesh_sequence = \"seq/f_{frame:03}.obj\"";
    std::fs::write(d.join("m.toml"), manifest(source)).unwrap();
    let check = |d: &Path| {
        let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["check", "m.toml"]).output().unwrap();
        assert_eq!(out.status.code(), Some(0));
        String::from_utf8_lossy(&out.stderr).contains("wholly transparent")
    };
    assert!(check(d), "the transparent material is warned of");
    assert_eq!(run(d).ran(Kind::RenderPass), 3);
    let centre = |d: &Path| pixel(d, "out/ms_dnerf/train/r_0000.png", 24, 24)[3];
    assert_eq!(centre(d), 0, "nothing of it shows");
    std::fs::write(d.join("m.toml"), manifest(&format!("{source}\nopaque = true"))).unwrap();
    assert!(!check(d), "no warning once it is drawn opaque");
    assert_eq!(run(d).ran(Kind::RenderPass), 3, "its frames re-render");
    assert_eq!(centre(d), 255);
    let plane = "[dataset]\nname = \"p\"\n[source.g]\nplane = { size = [1.0, 1.0] }\nopaque = true\n";
    let errors = vvgen::manifest::parse(plane, &d.join("p.toml")).unwrap_err();
    assert!(errors.render(false).contains("`opaque` does not apply to a `plane`"), "{}", errors.render(false));
}

/// A sequence whose MTL or texture is missing renders without it, as Blender's importer reads each frame, and is
/// warned of with the file and line; once the file is back, the frames that read it re-render with it.
#[test]
fn a_missing_library_or_texture_is_warned_of_and_keys_the_frames() {
    for (what, file, says) in [
        ("library", "seq/skin.mtl", "f_000.obj:2: material library `skin.mtl` not found"),
        ("texture", "seq/tex.png", "skin.mtl:3: texture `tex.png` not found"),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        write_sequence(d);
        std::fs::write(d.join("m.toml"), manifest("mesh_sequence = \"seq/f_{frame:03}.obj\"")).unwrap();
        let kept = std::fs::read(d.join(file)).unwrap();
        std::fs::remove_file(d.join(file)).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["check", "m.toml"]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{what}: {err}");
        assert!(err.contains(says), "{what}: {err}");
        assert_eq!(run(d).ran(Kind::RenderPass), 3, "{what}");
        let plain = pixel(d, "out/ms_dnerf/train/r_0000.png", 24, 24);
        std::fs::write(d.join(file), kept).unwrap();
        assert_eq!(run(d).ran(Kind::RenderPass), 3, "{what}: back, it keys the frames");
        assert_ne!(pixel(d, "out/ms_dnerf/train/r_0000.png", 24, 24), plain, "{what}");
    }
}
