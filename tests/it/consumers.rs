//! What each writer's consumers cannot read is said by `vvgen check`, before anything renders, per writer and
//! about that writer's consumers only; what `build` refuses, `check` refuses first.

use std::path::Path;
use std::process::{Command, Output};

use glam::{DMat3, DMat4, DVec2, DVec3, DVec4};

use crate::common::animated_triangle;

/// A 4-frame triangle dataset with `render` lines, train/val/test splits (or `splits`) and one output.
fn manifest(render: &str, splits: &str, output: &str) -> String {
    format!(
        "[dataset]\nname = \"tri\"\nout = \"out\"\ncache = \"cache\"\n\
         [source.tri]\ngltf = \"tri.gltf\"\nframes = {{ count = 4, fps = 1 }}\n\
         [render]\nresolution = [32, 32]\n{render}\n\
         [rig.o]\nkind = \"orbit\"\n{splits}\n[output.o]\n{output}\n"
    )
}

/// Orbit views are deterministic, so the splits share view 0: said so, not what these tests are about.
const SPLITS: &str = "[split.train]\nrig = \"o\"\nviews = 2\n[split.val]\nrig = \"o\"\nviews = 1\n\
                      allow_shared_poses = true\n[split.test]\nrig = \"o\"\nviews = 1\nallow_shared_poses = true\n";

fn vvgen(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap()
}

/// `vvgen check` of `text` in a fresh folder: exit code and standard error.
fn check(text: &str) -> (Option<i32>, String, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tri.gltf"), animated_triangle(0.3)).unwrap();
    std::fs::write(dir.path().join("m.toml"), text).unwrap();
    let out = vvgen(dir.path(), &["check", "--color", "never", "m.toml"]);
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned(), dir)
}

/// One case: writer, render lines, splits, refused (exit 2), what check must say, and what it must not say.
type Row<'a> = (&'a str, &'a str, &'a str, bool, &'a [&'a str], &'a [&'a str]);

/// Each row: writer, render lines, splits, what check must say (errors exit 2), and what it must not say.
#[test]
fn check_says_each_writers_consumer_limits_and_only_its_own() {
    let square_off_centre = "fx = 40.0\nfy = 42.0\ncx = 14.0\ncy = 17.0";
    let rows: &[Row] = &[
        // D-NeRF-path loaders take one focal from camera_angle_x and the image centre.
        (
            "dnerf",
            "fx = 40.0\nfy = 42.0",
            SPLITS,
            false,
            &["fy = 42 (non-square pixels)", "D-NeRF (load_blender.py), 3DGS"],
            &["off-centre"],
        ),
        (
            "dnerf",
            "cx = 14.0",
            SPLITS,
            false,
            &["off-centre principal point (14, 16)", "project about the image centre"],
            &["non-square"],
        ),
        (
            "dnerf",
            "",
            &SPLITS.replace("[split.test]", "[split.test_ring]"),
            true,
            &["`test_ring`, whose name contains `_r`", "K-Planes"],
            &[],
        ),
        // static-frames: the static NeRF-synthetic loaders, not the dynamic ones.
        (
            "static-frames",
            square_off_centre,
            SPLITS,
            false,
            &["NeRF's load_blender.py, 3DGS (Blender path)"],
            &["K-Planes", "Deformable", "4DGaussians"],
        ),
        // nerfstudio-data reads fx, fy, cx, cy, w, h exactly: nothing to say about them.
        ("nerfstudio", square_off_centre, SPLITS, false, &[], &["warning"]),
        (
            "nerfstudio",
            "passes = [\"rgba\", \"depth\"]\ndepth = { kind = \"ray\" }",
            SPLITS,
            false,
            &["ray-distance depth", "--pipeline.model.is-euclidean-depth True"],
            &["error"],
        ),
        // instant-ngp: no place for another depth kind, and no time.
        (
            "instant-ngp",
            "passes = [\"rgba\", \"depth\"]\ndepth = { kind = \"ray\" }",
            SPLITS,
            true,
            &["ray-distance depth", "planar z-depth"],
            &[],
        ),
        (
            "instant-ngp",
            square_off_centre,
            SPLITS,
            false,
            &["has 4 frames", "instant-ngp has no time"],
            &["non-square", "off-centre"],
        ),
        // 3DGS's COLMAP reader: two focals are fine, the principal point is not read.
        ("colmap", "fx = 40.0\nfy = 42.0", SPLITS, false, &[], &["warning"]),
        ("colmap", "cx = 14.0", SPLITS, false, &["off-centre", "3DGS's COLMAP reader"], &["non-square"]),
        // DyNeRF: one focal, the centre, 4DGaussians' 2704×2028 and 300 frames, Deformable-3DGS' 24.
        (
            "dynerf",
            square_off_centre,
            "[split.train]\nrig = \"o\"\nviews = 2\n[split.test]\nrig = \"o\"\nviews = 1\n",
            false,
            &[
                "poses_bounds.npy holds one focal length",
                "assume the image centre",
                "hard-codes DyNeRF's 2704×2028",
                "has 4 frames",
                "i/300",
                "i/23",
            ],
            &[],
        ),
        (
            "dynerf",
            "",
            "[split.train]\nrig = \"o\"\nviews = 2\ntime = \"monocular\"\n",
            true,
            &["time is not \"all\""],
            &[],
        ),
    ];
    for (writer, render, splits, refused, says, not) in rows {
        let text = manifest(render, splits, &format!("writer = \"{writer}\"\ninit_points = 0"));
        let (code, err, dir) = check(&text);
        let ctx = format!("{writer} with {render:?}:\n{err}");
        assert_eq!(code, Some(if *refused { 2 } else { 0 }), "{ctx}");
        for s in *says {
            assert!(err.contains(s), "missing {s:?} in {ctx}");
        }
        for s in *not {
            assert!(!err.contains(s), "{s:?} does not apply: {ctx}");
        }
        if *refused {
            // What check refuses, build refuses the same way, before any work.
            let out = vvgen(dir.path(), &["-q", "build", "m.toml"]);
            assert_eq!(out.status.code(), Some(2), "{ctx}");
            assert!(!dir.path().join("out").exists(), "build wrote output before refusing: {ctx}");
            assert!(!dir.path().join("cache/objects").exists(), "build rendered before refusing: {ctx}");
        }
    }
}

/// Errors the planner raises from the manifest and its inputs reach `check` too (it plans without rendering).
#[test]
fn check_plans_and_opens_the_inputs() {
    // A split selecting frames the 4-frame scene does not have: only the planner, with the frame count, knows.
    let text = manifest("", "[split.train]\nrig = \"o\"\nviews = 1\nframes = [7]\n", "writer = \"dnerf\"");
    let (code, err, _dir) = check(&text);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("selects no frames"), "{err}");
    // A malformed glTF is an error at check time, not mid-build.
    let (code, err, dir) = check(&manifest("", SPLITS, "writer = \"dnerf\""));
    assert_eq!(code, Some(0), "{err}");
    std::fs::write(dir.path().join("tri.gltf"), "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 3}]}")
        .unwrap();
    let out = vvgen(dir.path(), &["check", "m.toml"]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    // What only the build's planning of outputs refused before: a writer without the pass it needs.
    let (code, err, _dir) = check(&manifest("passes = [\"depth\"]", SPLITS, "writer = \"colmap\""));
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("output `o`: the `rgba` pass is needed for this writer"), "{err}");
}

/// 4DGaussians' and Deformable-3DGS' Blender readers negate the camera's x translation: `check` says by how many
/// pixels they misplace the subject, and that figure is what their reader, replayed on the built dataset, does to
/// the subject's posed vertices. Cameras aimed at the origin are read exactly and not warned of.
#[test]
fn off_origin_targets_say_how_far_4dgs_and_deformable_misplace_the_subject() {
    let splits = "[split.train]\nrig = \"h\"\nviews = 6\n[split.val]\nrig = \"h\"\nviews = 2\nseed = 3\n\
                  [split.test]\nrig = \"h\"\nviews = 2\nseed = 4\n";
    for (target, warned) in [("[0.3, 0.2, 0.1]", true), ("[0.0, 0.0, 0.0]", false)] {
        let text = manifest("", splits, "writer = \"dnerf\"\ninit_points = 0\ndir = \"tri_dnerf\"")
            .replace("[render]\nresolution = [32, 32]", "[render]\nresolution = [64, 64]")
            .replace("[rig.o]\nkind = \"orbit\"", &format!("[rig.h]\nkind = \"hemisphere\"\ntarget = {target}"));
        let (code, err, dir) = check(&text);
        assert_eq!(code, Some(0), "{err}");
        let said = err.split("draw the subject up to ").nth(1).map(|s| s.split(' ').next().unwrap().to_string());
        assert_eq!(said.is_some(), warned, "{err}");
        let out = vvgen(dir.path(), &["build", "m.toml"]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let posed: Vec<Vec<[f32; 3]>> = (0..4)
            .map(|f| {
                let p = dir.path().join(format!("f{f}.ply"));
                let args = ["inspect", "m.toml", "--frame", &f.to_string(), "--ply", p.to_str().unwrap()];
                assert!(vvgen(dir.path(), &args).status.success());
                vvgen::scene::ply::read(&std::fs::read(&p).unwrap()).unwrap().positions
            })
            .collect();
        let mut worst = 0.0f64;
        for split in ["train", "val", "test"] {
            let path = dir.path().join(format!("out/tri_dnerf/transforms_{split}.json"));
            let json: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
            let fovx = json["camera_angle_x"].as_f64().unwrap();
            for frame in json["frames"].as_array().unwrap() {
                let m: Vec<Vec<f64>> = serde_json::from_value(frame["transform_matrix"].clone()).unwrap();
                let c2w = DMat4::from_cols_array_2d(&[0, 1, 2, 3].map(|c| [0, 1, 2, 3].map(|r| m[r][c])));
                let f = (frame["time"].as_f64().unwrap() * 3.0).round() as usize;
                for p in &posed[f] {
                    let (a, b) = (project(&gaussians_3dgs(c2w), fovx, p), project(&gaussians_4dgs(c2w), fovx, p));
                    worst = worst.max((a - b).length());
                }
            }
        }
        match said {
            Some(px) => {
                assert!(worst > 1.0, "an off-origin target misplaces by pixels, not {worst}");
                assert_eq!(format!("{worst:.1}"), px, "check's figure is the replayed reader's: {err}");
            }
            None => assert!(worst < 1e-6, "aimed at the origin, the readers agree ({worst} px)"),
        }
    }
}

/// 3DGS's `readCamerasFromTransforms`: flip the camera's Y and Z, invert, `R = w2c[:3, :3]ᵀ`, `T = w2c[:3, 3]`;
/// returned as world→camera (OpenCV axes), as `getWorld2View2(R, T)` builds it.
fn gaussians_3dgs(c2w: DMat4) -> DMat4 {
    (c2w * DMat4::from_diagonal(DVec4::new(1.0, -1.0, -1.0, 1.0))).inverse()
}

/// 4DGaussians' (dataset_readers.py l.272-275) and Deformable-3DGS' (l.235-238) version of it:
/// `matrix = inv(c2w)`, `R = -matrix[:3, :3]ᵀ`, `R[:, 0] = -R[:, 0]`, `T = -matrix[:3, 3]`.
fn gaussians_4dgs(c2w: DMat4) -> DMat4 {
    let m = c2w.inverse();
    let mut r = -DMat3::from_mat4(m).transpose();
    r.x_axis = -r.x_axis;
    let t = -m.w_axis.truncate();
    // getWorld2View2: Rt[:3, :3] = Rᵀ, Rt[:3, 3] = T.
    let rt = r.transpose();
    DMat4::from_cols(rt.x_axis.extend(0.0), rt.y_axis.extend(0.0), rt.z_axis.extend(0.0), t.extend(1.0))
}

/// Pixel position of `p` through world→camera `w2c` (OpenCV axes) with the readers' symmetric 64² frustum of
/// horizontal field of view `fovx`.
fn project(w2c: &DMat4, fovx: f64, p: &[f32; 3]) -> DVec2 {
    let v = w2c.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
    let f = 32.0 / (fovx / 2.0).tan();
    DVec2::new(32.0 + f * v.x / v.z, 32.0 + f * v.y / v.z)
}

/// The pixels `check` says a reader is off by are what the reader's own projection does: every pixel centre of
/// the image, cast at depth 1 through the written camera and projected as each loader projects it (see
/// docs/consumers.md for the lines), on the non-square 120×90 set and its fx 100 / fy 105, cx 66 / cy 41.
#[test]
fn the_pixels_check_says_are_the_readers_own() {
    // The first number after `after` in `text`.
    let figure = |text: &str, after: &str| -> f64 {
        let rest = text.split(after).nth(1).unwrap_or_else(|| panic!("no {after:?} in {text}"));
        let num: String =
            rest.chars().take_while(|c| c.is_ascii_digit() || *c == '.' || *c == '-' || *c == '+').collect();
        num.parse().unwrap_or_else(|_| panic!("{num:?} after {after:?}"))
    };
    let (w, h) = (120.0f64, 90.0f64);
    let check_with = |render: &str| {
        let text = manifest("", SPLITS, "writer = \"dnerf\"\ninit_points = 0\ndir = \"x_dnerf\"");
        check(&text.replace("resolution = [32, 32]", &format!("resolution = [120, 90]\n{render}"))).1
    };
    // (fx, fy, cx, cy) → the largest offset of a reader's projection `proj(x, y)` (x, y = ray at depth 1).
    let worst = |k: (f64, f64, f64, f64), proj: &dyn Fn(f64, f64) -> (f64, f64)| -> f64 {
        let mut m = 0.0f64;
        for j in 0..h as usize {
            for i in 0..w as usize {
                let (u, v) = (i as f64 + 0.5, j as f64 + 0.5);
                let (pu, pv) = proj((u - k.2) / k.0, (v - k.3) / k.1);
                m = m.max((pu - u).hypot(pv - v));
            }
        }
        m
    };
    let angle_x = |fx: f64| 2.0 * (w / 2.0 / fx).atan();
    // D-NeRF, 3DGS, nerfstudio's blender parser: focal = .5·W / tan(.5·camera_angle_x) for both axes, centred.
    let one_focal = |fx: f64| {
        move |x: f64, y: f64| {
            let f = 0.5 * w / (0.5 * angle_x(fx)).tan();
            (w / 2.0 + f * x, h / 2.0 + f * y)
        }
    };

    let err = check_with("fx = 100.0\nfy = 105.0");
    let said = figure(&err, "ignore fl_y: points land up to ");
    // The loaders' own vertical error at cy = 45: what check says, to its 0.1 px.
    let k = (100.0, 105.0, 60.0, 45.0);
    assert!((worst(k, &one_focal(100.0)) - said).abs() < 0.6, "{said} vs replay {}", worst(k, &one_focal(100.0)));

    let err = check_with("cx = 66.0\ncy = 41.0");
    let (dx, dy) = (figure(&err, "every point lands ("), figure(&err, "every point lands (-6.0, "));
    let f = 0.5 * w / (0.5 * 0.6911112070083618f64).tan();
    let replay = worst((f, f, 66.0, 41.0), &one_focal(f));
    assert!(((dx * dx + dy * dy).sqrt() - replay).abs() < 1e-6, "({dx}, {dy}) vs replay {replay}");

    let err = check_with("");
    assert!(err.contains("resizes each 120×90 image to 90×120") && err.contains("stops with a ValueError"), "{err}");
    let fovx = 0.6911112070083618f64;
    let f = 0.5 * w / (0.5 * fovx).tan();
    let k = (f, f, 60.0, 45.0);
    // Deformable-3DGS: fovy = focal2fov(fov2focal(fovx, W), H); FovY = fovx; FovX = fovy.
    let fovy = 2.0 * ((h / 2.0) / f).atan();
    let deformable =
        move |x: f64, y: f64| (w / 2.0 + w / 2.0 * x / (fovy / 2.0).tan(), h / 2.0 + h / 2.0 * y / (fovx / 2.0).tan());
    let said = figure(&err, "swaps FovX and FovY: points land up to ");
    assert!((worst(k, &deformable) - said).abs() < 0.6, "Deformable {said} vs replay {}", worst(k, &deformable));
    // 4DGaussians: PILtoTorch(image, (800, 800)); FovY = focal2fov(fov2focal(fovx, 800), 800) = fovx; back in
    // this image's pixels.
    let gaussians = move |x: f64, y: f64| {
        let (pu, pv) = (400.0 + 400.0 * x / (fovx / 2.0).tan(), 400.0 + 400.0 * y / (fovx / 2.0).tan());
        (pu * w / 800.0, pv * h / 800.0)
    };
    let said = figure(&err, "takes FovY = FovX: up to ");
    assert!((worst(k, &gaussians) - said).abs() < 0.6, "4DGaussians {said} vs replay {}", worst(k, &gaussians));

    // 4DGaussians' Neural3D reader at 320×240: frames resized to 1352×1014, focal = poses_bounds' focal / 2
    // (downsample = 2704 / 1352), projected about the centre; measured in those frames' pixels.
    let (w, h) = (320.0f64, 240.0f64);
    let text = manifest("", "[split.train]\nrig = \"o\"\nviews = 2\n", "writer = \"dynerf\"\ninit_points = 0");
    let (_, err, _d) = check(&text.replace("resolution = [32, 32]", "resolution = [320, 240]"));
    let f = 0.5 * w / (0.5 * fovx).tan();
    let mut replay = 0.0f64;
    for (u, v) in [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)] {
        let (x, y) = ((u - w / 2.0) / f, (v - h / 2.0) / f);
        let (pu, pv) = (676.0 + f / 2.0 * x, 507.0 + f / 2.0 * y);
        replay = replay.max((pu - u * 1352.0 / w).hypot(pv - v * 1014.0 / h));
    }
    let said = figure(&err, "its cameras are off by up to ");
    assert!((replay - said).abs() < 0.6, "4DGaussians Neural3D {said} vs replay {replay}");
}

/// What a loader reads from a path or a size it does not expect is said, by what the user will see.
#[test]
fn paths_and_sizes_the_loaders_misread_are_said() {
    let one = "[split.train]\nrig = \"o\"\nviews = 2\n";
    let cases: &[(&str, &str, &str)] = &[
        ("writer = \"dnerf\"\ndir = \"plain\"", "", "directory `plain` does not contain \"dnerf\""),
        ("writer = \"dynerf\"\ndir = \"my.set\"", "", "contains a `.`"),
        ("writer = \"dynerf\"\ndir = \"my_dnerf_set\"", "", "contains `dnerf` or `lego`"),
        ("writer = \"static-frames\"", "resolution = [48, 32]", "resizes every image to 400×400"),
    ];
    for (output, render, says) in cases {
        let text = manifest("", one, &format!("{output}\ninit_points = 0"));
        let text = if render.is_empty() { text } else { text.replace("resolution = [32, 32]", render) };
        let (code, err, _d) = check(&text);
        assert_eq!(code, Some(0), "{err}");
        assert!(err.contains(says), "missing {says:?}:\n{err}");
    }
}
