//! `vvgen new ASSET`: the manifest it writes checks clean and builds as written, for every kind of asset.

use std::path::Path;
use std::process::Command;

use crate::common::data;

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn new_manifests_check_clean_and_build_for_every_asset_kind() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // Assets the test makes: a folder of OBJ frames (the topology changing) and a single PLY mesh (z up, tall).
    std::fs::create_dir_all(d.join("objs")).unwrap();
    for f in 0..2 {
        let mut s = String::new();
        for (x, y, z) in [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.5, 2.0, 0.0), (0.5, 0.0, 1.0)] {
            s.push_str(&format!("v {} {y} {z}\n", x + 0.1 * f as f64));
        }
        s.push_str(if f == 0 { "f 1 2 3\nf 1 3 4\n" } else { "f 1 2 3\nf 1 3 4\nf 2 3 4\n" });
        std::fs::write(d.join(format!("objs/frame_{f}.obj")), s).unwrap();
    }
    std::fs::write(
        d.join("tall.ply"),
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
         element face 2\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0.5 0.3 3\n0.5 1 0\n3 0 1 2\n3 1 3 2\n",
    )
    .unwrap();
    // Flat terrain lies on its thin axis, y or z, whichever other extent is larger (the tallest of y and z stood
    // it up as a wall).
    let terrain = |file: &str, [x, y, z]: [f32; 3]| {
        let text = format!(
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
             element face 2\nproperty list uchar int vertex_indices\nend_header\n\
             0 0 0\n{x} 0 0\n{x} {y} {z}\n0 {y} {z}\n3 0 1 2\n3 0 2 3\n"
        );
        std::fs::write(d.join(file), text).unwrap();
    };
    terrain("pond.ply", [3.5, 0.5, 3.1]);
    terrain("field.ply", [2.0, 3.0, 0.2]);
    // A long subject (x) of triangle strips, as Stanford's scans are stored: a mesh (it read as a point cloud
    // before), standing on the taller of y and z (it stood on z whenever x was the longest: cows lay on their side).
    let mut strips = String::from(
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n\
         element tristrips 1\nproperty list int int vertex_indices\nend_header\n",
    );
    for [x, y, z] in [[0, 0, 0], [0, 2, 1], [1, 0, 1], [1, 2, 0], [2, 0, 0], [2, 2, 1], [3, 0, 1], [4, 2, 0]] {
        strips += &format!("{x} {y} {z}\n");
    }
    std::fs::write(d.join("long.ply"), strips + "9 0 1 2 3 -1 3 4 5 6 7\n").unwrap();
    let cases: [(&str, String, &str, &str); 9] = [
        (
            "animated glTF",
            data("gltf/CesiumMan/CesiumMan.glb").display().to_string(),
            "dnerf",
            "frames = { count = 61, fps = 30 }",
        ),
        ("static glTF", data("gltf/BoxTextured/BoxTextured.glb").display().to_string(), "static-frames", "mesh   ="),
        ("PLY frames", data("seq").display().to_string(), "nerfstudio", "ply_sequence = \""),
        ("PLY frames as points", data("seq").display().to_string(), "ply-sequence", "points = 200000"),
        ("OBJ frames", d.join("objs").display().to_string(), "dnerf", "mesh_sequence = \"objs/*.obj\""),
        ("a PLY mesh", d.join("tall.ply").display().to_string(), "dnerf", "up     = \"z\""),
        ("flat along y", d.join("pond.ply").display().to_string(), "dnerf", "up     = \"y\""),
        ("flat along z", d.join("field.ply").display().to_string(), "dnerf", "up     = \"z\""),
        ("a long PLY of strips", d.join("long.ply").display().to_string(), "dnerf", "up     = \"y\""),
    ];
    for (i, (what, asset, writer, says)) in cases.iter().enumerate() {
        let name = format!("m{i}.toml");
        let (code, err) = vvgen(d, &["new", asset, "--writer", writer, "-o", &name]);
        assert_eq!(code, 0, "{what}: {err}");
        let text = std::fs::read_to_string(d.join(&name)).unwrap();
        assert!(text.contains(says), "{what}: {says:?} not in\n{text}");
        let (code, err) = vvgen(d, &["check", &name]);
        assert_eq!(code, 0, "{what}: {err}");
        assert!(!err.contains("error"), "{what}: {err}");
        let (code, err) = vvgen(d, &["-q", "build", &name]);
        assert_eq!(code, 0, "{what}: {err}\n{text}");
    }
    assert!(d.join("out/CesiumMan/CesiumMan_dnerf/transforms_train.json").is_file());
    assert!(d.join("out/tall/tall_dnerf/transforms_test.json").is_file());
    // The strips are a surface: written lit, as a mesh without colours is (a cloud stays unlit).
    assert!(std::fs::read_to_string(d.join("m8.toml")).unwrap().contains("shading        = \"pbr\""));
    // Never overwrites.
    let (code, err) = vvgen(d, &["new", &data("seq").display().to_string(), "-o", "m0.toml"]);
    assert_eq!(code, 2);
    assert!(err.contains("exists"), "{err}");
    let (code, err) = vvgen(d, &["new", "no-such.glb"]);
    assert_eq!(code, 2, "{err}");
}

/// An ASCII PLY pyramid: four sloped faces over a square base, its base corners and apex of the `(base, apex)`
/// colours when given, else without colours.
fn pyramid(colours: Option<([u8; 3], [u8; 3])>) -> String {
    let mut ply =
        String::from("ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n");
    if colours.is_some() {
        ply += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    }
    ply += "element face 6\nproperty list uchar int vertex_indices\nend_header\n";
    let corners = ["-1 -1 0", "1 -1 0", "1 1 0", "-1 1 0", "0 0 1.2"];
    for (i, at) in corners.iter().enumerate() {
        let colour = colours.map_or(String::new(), |(base, apex)| {
            let [r, g, b] = if i == 4 { apex } else { base };
            format!(" {r} {g} {b}")
        });
        ply += &format!("{at}{colour}\n");
    }
    ply + "3 0 1 4\n3 1 2 4\n3 2 3 4\n3 3 0 4\n3 0 2 1\n3 0 3 2\n"
}

/// A subject of one colour (a scan without colours, a mesh without materials) unlit is a filled silhouette in
/// every view: `new` writes it lit, and its views show its shape (many shades where unlit has one). A textured
/// subject stays unlit, as the NeRF-synthetic recipe renders it.
#[test]
fn a_subject_of_one_colour_is_written_lit_and_its_views_show_its_shape() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // A pyramid: four sloped faces and a base, no colours.
    std::fs::write(d.join("pyramid.ply"), pyramid(None)).unwrap();
    let (code, err) = vvgen(d, &["new", "pyramid.ply"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("no texture or vertex colours"), "{err}");
    let text = std::fs::read_to_string(d.join("pyramid.toml")).unwrap();
    assert!(text.contains("shading        = \"pbr\""), "{text}");
    // Fewer views than `new` writes, to keep the test quick; the rest is as written.
    let quick = text
        .replace("views = 100", "views = 4")
        .replace("views = 10", "views = 1")
        .replace("views    = 20", "views    = 1");
    let shades = |manifest: &str, name: &str| {
        std::fs::write(d.join(name), manifest).unwrap();
        let (code, err) = vvgen(d, &["-q", "build", name]);
        assert_eq!(code, 0, "{err}");
        let img = image::open(d.join("out/pyramid/pyramid_dnerf/train/r_0000.png")).unwrap().to_rgba8();
        let mut seen: Vec<[u8; 3]> = img.pixels().filter(|p| p[3] == 255).map(|p| [p[0], p[1], p[2]]).collect();
        seen.sort_unstable();
        seen.dedup();
        seen.len()
    };
    let lit = shades(&quick, "lit.toml");
    let unlit = shades(&quick.replace("shading        = \"pbr\"", "shading        = \"unlit\""), "unlit.toml");
    assert!(unlit <= 2, "unlit, the pyramid is one colour: {unlit} shades");
    assert!(lit >= 20, "lit, its faces differ: {lit} shades");
    // A subject whose texture carries its shading is written unlit; a flat logo's is a palette, written lit.
    let (code, err) = vvgen(d, &["new", &data("gltf/CesiumMan/CesiumMan.glb").display().to_string()]);
    assert_eq!(code, 0, "{err}");
    assert!(!std::fs::read_to_string(d.join("CesiumMan.toml")).unwrap().contains("shading"));
    let (code, err) = vvgen(d, &["new", &data("gltf/BoxTextured/BoxTextured.glb").display().to_string()]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("a palette of 59"), "{err}");
}

/// A subject painted by part with a few vertex colours (a low-poly model's palette: three.js' Flamingo has 4)
/// shows flat patches unlit, so `new` writes it lit and says why; one whose vertex colours carry shading (a
/// scan's: here a grid of 100 distinct colours) stays unlit.
#[test]
fn a_subject_painted_with_a_palette_is_written_lit_and_a_scan_unlit() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // The pyramid again, its base red and its apex white: two colours.
    std::fs::write(d.join("painted.ply"), pyramid(Some(([200, 30, 30], [250, 250, 250])))).unwrap();
    let (code, err) = vvgen(d, &["new", "painted.ply"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("a palette of 2"), "{err}");
    let text = std::fs::read_to_string(d.join("painted.toml")).unwrap();
    assert!(text.contains("shading        = \"pbr\"   # a palette of 2 flat colours"), "{text}");
    // A 10 × 10 grid of a gentle bump, every vertex its own colour.
    let mut ply = String::from(
        "ply\nformat ascii 1.0\nelement vertex 100\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 162\n\
         property list uchar int vertex_indices\nend_header\n",
    );
    for i in 0..100 {
        let (x, y) = ((i % 10) as f32 * 0.2, (i / 10) as f32 * 0.2);
        ply += &format!("{x} {y} {} {} {} 90\n", 0.3 - (x - 0.9).powi(2) * 0.2, 100 + i, 200 - i);
    }
    for y in 0..9 {
        for x in 0..9 {
            let a = y * 10 + x;
            ply += &format!("3 {a} {} {}\n3 {a} {} {}\n", a + 1, a + 11, a + 11, a + 10);
        }
    }
    std::fs::write(d.join("scan.ply"), ply).unwrap();
    let (code, err) = vvgen(d, &["new", "scan.ply"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("palette") && !err.contains("lit ("), "{err}");
    assert!(!std::fs::read_to_string(d.join("scan.toml")).unwrap().contains("shading"));
}

/// An animation-only export (a skeleton and its clips, no mesh: Mixamo's "Without Skin") is refused by `new`,
/// `check` and `build` alike, naming the file, what it holds and the way out, in glTF and in FBX.
#[test]
fn an_animation_only_export_is_refused_with_the_way_out() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // CesiumMan without its mesh and skin: the joints and the walk remain.
    let (mut json, bin) = crate::common::glb_split(&std::fs::read(data("gltf/CesiumMan/CesiumMan.glb")).unwrap());
    let o = json.as_object_mut().unwrap();
    for key in ["meshes", "skins", "materials", "textures", "images", "samplers"] {
        o.remove(key);
    }
    for n in json["nodes"].as_array_mut().unwrap() {
        let n = n.as_object_mut().unwrap();
        n.remove("mesh");
        n.remove("skin");
    }
    std::fs::write(d.join("Walk Only.glb"), crate::common::glb_join(&json, &bin)).unwrap();
    std::fs::copy(data("fbx/external/skeleton_only.fbx"), d.join("skeleton_only.fbx")).unwrap();
    let says = |err: &str, file: &str, clip: &str| {
        for s in [file, "no mesh", clip, "animation-only", "With Skin", ".blend"] {
            assert!(err.contains(s), "`{s}` not in: {err}");
        }
    };
    for (file, key, clip) in [
        ("Walk Only.glb", "gltf", "1 animation"),
        ("Walk Only.glb", "mesh", "1 animation"),
        ("skeleton_only.fbx", "fbx", "1 take"),
    ] {
        let (code, err) = vvgen(d, &["new", file]);
        assert_eq!(code, 2, "{err}");
        says(&err, file, clip);
        let manifest = format!(
            "[dataset]\nname = \"a\"\nout = \"out\"\n[source.a]\n{key} = \"{file}\"\n[rig.r]\nkind = \"orbit\"\n\
             [split.train]\nrig = \"r\"\nviews = 2\n[output.o]\nwriter = \"nerfstudio\"\n"
        );
        std::fs::write(d.join("a.toml"), manifest).unwrap();
        for cmd in ["check", "build"] {
            let (code, err) = vvgen(d, &[cmd, "a.toml"]);
            assert_eq!(code, 2, "{cmd}: {err}");
            says(&err, file, clip);
        }
        assert!(!d.join("out").exists(), "a refused build wrote its output");
    }
}

/// A 3D Gaussian splatting model folder as graphdeco-inria's trainer writes it (`cameras.json` beside
/// `point_cloud/iteration_N/point_cloud.ply`), used from its own folder: `new` takes the up axis from the
/// training cameras, −Y for upright photos reconstructed by COLMAP (OpenCV's +Y down in every image), which the
/// extents cannot tell from +Y; the manifest builds. Without the cameras, the extents' guess as before.
#[test]
fn a_splatting_model_folder_takes_its_up_from_its_training_cameras() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let iteration = d.join("point_cloud/iteration_30000");
    std::fs::create_dir_all(&iteration).unwrap();
    std::fs::copy(data("splats/donut_2000.ply"), iteration.join("point_cloud.ply")).unwrap();
    // Cameras on a ring about the Y axis, each level (its image's +Y along the world's +Y, so its up is −Y),
    // looking inwards: camera-to-world rotations, rows, as camera_to_JSON writes them.
    let cameras: Vec<String> = (0..8)
        .map(|i| {
            let a = i as f64 * std::f64::consts::TAU / 8.0;
            let (s, c) = a.sin_cos();
            // Columns: right (c, 0, −s), down (0, 1, 0), forward (s, 0, c).
            format!(
                "{{\"id\": {i}, \"img_name\": \"{i:05}\", \"width\": 800, \"height\": 600, \"position\": [{}, 0.0, {}], \
                 \"rotation\": [[{c}, 0.0, {s}], [0.0, 1.0, 0.0], [{}, 0.0, {c}]], \"fy\": 700.0, \"fx\": 700.0}}",
                -3.0 * s,
                -3.0 * c,
                -s
            )
        })
        .collect();
    std::fs::write(d.join("cameras.json"), format!("[{}]", cameras.join(", "))).unwrap();
    let (code, err) = vvgen(d, &["new", "point_cloud/iteration_30000/point_cloud.ply"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("up \"-y\" from the 8 cameras in ../../cameras.json"), "{err}");
    let text = std::fs::read_to_string(d.join("point-cloud.toml")).unwrap();
    assert!(text.contains("up     = \"-y\""), "{text}");
    // The training cameras are offered as a rig, commented.
    assert!(text.contains("# [rig.trained]\n# kind = \"from-file\"\n# file = \"cameras.json\""), "{text}");
    let small = text
        .replace("views = 100", "views = 1")
        .replace("views = 10", "views = 1")
        .replace("views    = 20", "views = 1");
    std::fs::write(d.join("point-cloud.toml"), small.replace("[400, 400]", "[48, 48]")).unwrap();
    let (code, err) = vvgen(d, &["build", "point-cloud.toml"]);
    assert_eq!(code, 0, "{err}");
    // Without the cameras: the extents' guess (the donut lies flat along z).
    std::fs::remove_file(d.join("cameras.json")).unwrap();
    std::fs::remove_file(d.join("point-cloud.toml")).unwrap();
    let (code, err) = vvgen(d, &["new", "point_cloud/iteration_30000/point_cloud.ply"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("up \"z\" guessed"), "{err}");
}

/// What ufbx's corpus of exporters' files showed `new` (each used from its own folder): a name of other scripts
/// than Latin gives a dataset name `check` accepts; a take left 92 hours long gives its first 10 minutes, not a
/// count `check` refuses, and is listed with the most frames a manifest takes; a layered texture (no image file
/// of its own) is a warning, where it stopped `new` reading the folder as an image; a file of NURBS alone, or of
/// lights alone, is refused saying what it holds.
#[test]
fn exporters_leftovers_give_a_manifest_that_checks_or_say_what_the_file_holds() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::copy(data("fbx/maya_long_keyframes_6100_binary.fbx"), d.join("長い take.fbx")).unwrap();
    let (code, err) = vvgen(d, &["new", "長い take.fbx"]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(d.join("take.toml")).unwrap();
    assert!(text.contains("name = \"take\""), "{text}");
    assert!(text.contains("frames = { count = 18000, fps = 30 }   # the first 10 minutes"), "{text}");
    assert!(text.contains("10000001 frames"), "{text}");
    // The take's listing offers no count a manifest refuses: the most it takes, saying so.
    let listed = "frames = { count = 1000000, fps = 30 }   # its first 1000000 of 10000001 frames at 30 fps";
    assert!(text.contains(listed) && !text.contains("count = 10000001"), "{text}");
    let (code, err) = vvgen(d, &["check", "take.toml"]);
    assert_eq!(code, 0, "{err}");
    // Without `frames`, the whole take: refused by `check` with the way out, never planned frame by frame.
    let whole: String = text.lines().filter(|l| !l.starts_with("frames")).map(|l| format!("{l}\n")).collect();
    std::fs::write(d.join("whole.toml"), whole).unwrap();
    let (code, err) = vvgen(d, &["check", "whole.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("the take is 333333.333 s long: 10000001 frames at 30 fps, more than 1000000"), "{err}");
    assert!(err.contains("`frames = { count = N }`"), "{err}");

    std::fs::copy(data("fbx/leftovers/maya_texture_layers_7500_binary.fbx"), d.join("layers.fbx")).unwrap();
    let (code, err) = vvgen(d, &["new", "layers.fbx"]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = vvgen(d, &["check", "layers.toml"]);
    assert_eq!(code, 0, "{err}");
    for s in ["warning", "layers.fbx", "`lambert2`", "`layeredTexture1` is a layered texture", "colour alone"] {
        assert!(err.contains(s), "`{s}` not in: {err}");
    }

    for (file, says) in [
        ("maya_nurbs_surface_plane_7500_binary.fbx", "holds 1 curve or NURBS object(s) and no polygon mesh"),
        ("maya_anim_light_7500_binary.fbx", "holds 1 node(s) and 1 take(s) and no mesh (cameras, lights"),
    ] {
        std::fs::copy(data(&format!("fbx/leftovers/{file}")), d.join(file)).unwrap();
        let (code, err) = vvgen(d, &["new", file]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(says), "`{says}` not in: {err}");
        assert!(!err.contains("animation-only"), "{err}");
    }
}

/// A subject that travels many times its size (ufbx's cube with extrapolated keys) is small in every view once
/// `fit = "frame"` keeps its whole motion there: `check` says how small, why, and what makes it larger; the
/// first frame alone, framed by itself, is not small. A static subject made small by its fit is told the fit.
#[test]
fn a_subject_small_in_its_views_is_warned_of_with_why_and_the_way_out() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::copy(data("fbx/leftovers/maya_extrapolate_cube_7700_ascii.fbx"), d.join("cube.fbx")).unwrap();
    let (code, err) = vvgen(d, &["new", "cube.fbx"]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(d.join("cube.toml")).unwrap();
    // `check` of manifest `name`, which passes: what it said.
    let check = |name: &str| {
        let (code, err) = vvgen(d, &["--color", "never", "check", name]);
        assert_eq!(code, 0, "{err}");
        err
    };
    let err = check("cube.toml");
    for s in [
        "the subject is small in `test`, `train`, `val`: about ",
        "px across in half of the views (400×400 images): it moves across ",
        "× its own size, and fit = \"frame\" keeps all of its motion in every view",
        "take a shorter stretch of the clip (`frames`)",
    ] {
        assert!(err.contains(s), "`{s}` not in: {err}");
    }
    let px: f64 =
        err.split("about ").nth(1).unwrap().split(|c: char| !c.is_ascii_digit()).next().unwrap().parse().unwrap();
    assert!(px < 40.0, "{err}");
    let first: Vec<&str> =
        text.lines().map(|l| if l.starts_with("frames") { "frames = { count = 1 }" } else { l }).collect();
    let first = first.join("\n");
    std::fs::write(d.join("first.toml"), &first).unwrap();
    let err = check("first.toml");
    assert!(!err.contains("small"), "{err}");
    // One frame, small because its fit says so.
    let tiny = first.replace("fit    = \"frame\"", "fit = { height = 0.1 }");
    assert_ne!(tiny, first);
    std::fs::write(d.join("tiny.toml"), tiny).unwrap();
    let err = check("tiny.toml");
    assert!(err.contains("the subject is small in") && err.contains("[transform] fit = \"frame\" sizes it"), "{err}");
}

/// Frames copied from a Mac arrive each beside its `._` companion (AppleDouble metadata, 4 KB that is no PLY):
/// `new` and the manifest's glob leave hidden files out, as a shell's `*` does, where the first one stopped `new`
/// ("not a PLY file").
#[test]
fn a_folder_of_frames_copied_from_a_mac_reads_its_frames_alone() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir(d.join("frames")).unwrap();
    for f in 0..2 {
        std::fs::write(d.join(format!("frames/frame_{f}.ply")), pyramid(None)).unwrap();
        std::fs::write(d.join(format!("frames/._frame_{f}.ply")), [0u8, 5, 22, 7, 0, 2, 0, 0]).unwrap();
    }
    std::fs::write(d.join("frames/.DS_Store"), [0u8; 8]).unwrap();
    let (code, err) = vvgen(d, &["new", "frames", "-o", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(d.join("m.toml")).unwrap();
    assert!(text.contains("ply_sequence = \"frames/*.ply\"   # 2 file(s)"), "{text}");
    let (code, err) = vvgen(d, &["check", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("error") && !err.contains("warning"), "{err}");
}

/// Globs are case-sensitive: a folder of `FRAME_0.PLY` frames (a capture rig's, a Windows tool's) gets `*.PLY`,
/// and one of both spellings a class per letter, so the manifest matches every frame `new` counted. It wrote
/// `*.ply` for both, which matched none of the first and some of the second.
#[test]
fn frames_named_in_capitals_are_matched_as_spelt() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    for (folder, names, glob) in [
        ("caps", ["F_0.PLY", "F_1.PLY", "F_2.PLY"], "caps/*.PLY"),
        ("mixed", ["f_0.ply", "f_1.PLY", "f_2.Ply"], "mixed/*.[pP][lL][yY]"),
    ] {
        std::fs::create_dir(d.join(folder)).unwrap();
        for (f, name) in names.iter().enumerate() {
            // Each frame its own apex height: three light actions, one per frame matched.
            let ply = pyramid(None).replace("0 0 1.2", &format!("0 0 {}", 1.0 + 0.1 * f as f64));
            std::fs::write(d.join(folder).join(name), ply).unwrap();
        }
        let m = format!("{folder}.toml");
        let (code, err) = vvgen(d, &["new", folder, "-o", &m]);
        assert_eq!(code, 0, "{err}");
        let text = std::fs::read_to_string(d.join(&m)).unwrap();
        assert!(text.contains(&format!("ply_sequence = \"{glob}\"   # 3 file(s)")), "{text}");
        let (code, err) = vvgen(d, &["check", &m]);
        assert_eq!(code, 0, "{folder}: {err}");
        let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["plan", &m]).output().unwrap();
        let plan = String::from_utf8_lossy(&out.stdout);
        assert!(plan.lines().any(|l| l.starts_with("light") && l.contains(" 3 planned")), "{folder}: {plan}");
    }
}
