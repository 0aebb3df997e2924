//! `kind = "path"`: cameras that move over time, from keyframes, a nerfstudio `camera_path.json` and a 6-DoF
//! trace. Checked by reprojection on what the nerfstudio writer records, and by what an edit re-renders.

use std::path::Path;
use std::process::Command;

use glam::{DMat4, DVec3, DVec4};
use serde_json::Value;

use crate::common::cesium_head;
use vvgen::build::{build, Options, Silent};
use vvgen::plan::actions::Kind;

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// CesiumMan, `frames` frames at 4 fps (0.25 s apart), 48² with a 90° vertical field of view, `rig` as rig
/// `p`, one split over it, written for nerfstudio.
fn manifest(frames: u32, rig: &str) -> String {
    format!(
        "{}\n[render]\nresolution = [48, 48]\ncamera_angle_x = 1.5707963267948966\nsamples = 1\n\
         passes = [\"rgba\"]\n\n[rig.p]\nkind = \"path\"\n{rig}\n\n[split.walk]\nrig = \"p\"\n\n\
         [output.ns]\nwriter = \"nerfstudio\"\ninit_points = 0\n",
        cesium_head(frames, 4, 2.0, "", "")
    )
}

fn build_in(dir: &Path, text: &str) -> vvgen::build::Report {
    std::fs::write(dir.join("m.toml"), text).unwrap();
    let m = crate::common::load(&dir.join("m.toml"));
    build(&m, &dir.join("cache"), Options::default(), &Silent).unwrap()
}

/// The camera-to-world matrices nerfstudio will read, in frame order.
fn written(dir: &Path) -> Vec<DMat4> {
    let doc: Value =
        serde_json::from_slice(&std::fs::read(dir.join("out/m_nerfstudio/transforms.json")).unwrap()).unwrap();
    let mut frames: Vec<&Value> = doc["frames"].as_array().unwrap().iter().collect();
    frames.sort_by_key(|f| f["frame"].as_u64().unwrap());
    frames
        .iter()
        .map(|f| {
            let rows: Vec<Vec<f64>> = serde_json::from_value(f["transform_matrix"].clone()).unwrap();
            let a: [[f64; 4]; 4] = std::array::from_fn(|r| std::array::from_fn(|c| rows[r][c]));
            DMat4::from_cols_array_2d(&a).transpose()
        })
        .collect()
}

/// Where `world` lands in a 48² image with a 90° field of view seen from `c2w` (OpenGL axes), pixels.
fn project(c2w: &DMat4, world: DVec3) -> (f64, f64) {
    let p = c2w.inverse() * DVec4::new(world.x, world.y, world.z, 1.0);
    assert!(p.z < 0.0, "behind the camera: {p}");
    let f = 24.0; // 24 / tan(45°)
    (24.0 + f * p.x / -p.z, 24.0 - f * p.y / -p.z)
}

#[test]
fn a_path_renders_one_image_per_frame_passing_through_its_keyframes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rig = "keyframes = [\n  { time = 0, position = [0, -4, 1], target = [0, 0, 0.5] },\n  \
               { time = 1, position = [4, 0, 2], target = [0, 0, 0] },\n  \
               { time = 2, position = [0, 4, 1], target = [0, 0, -0.5] },\n]";
    let r = build_in(d, &manifest(9, rig));
    assert_eq!(r.renders, 9, "one image per frame");
    let c2w = written(d);
    assert_eq!(c2w.len(), 9);
    // Frames 0, 4 and 8 are at t = 0, 1 and 2 s: the keyframes, exactly.
    for (frame, eye, aim) in
        [(0, [0.0, -4.0, 1.0], [0.0, 0.0, 0.5]), (4, [4.0, 0.0, 2.0], [0.0; 3]), (8, [0.0, 4.0, 1.0], [0.0, 0.0, -0.5])]
    {
        let m = &c2w[frame];
        assert!(m.w_axis.truncate().distance(DVec3::from(eye)) < 1e-9, "frame {frame}: {m}");
        let (u, v) = project(m, DVec3::from(aim));
        assert!((u - 24.0).abs() < 1e-6 && (v - 24.0).abs() < 1e-6, "frame {frame}: the aim lands at {u}, {v}");
        // World +Z stays up in the image.
        let (_, above) = project(m, DVec3::from(aim) + DVec3::Z * 0.1);
        assert!(above < v, "frame {frame}: up is not up");
    }
    // Between keyframes the camera moves on, smoothly: no step is much longer than its neighbours'.
    let steps: Vec<f64> = c2w.windows(2).map(|w| w[0].w_axis.distance(w[1].w_axis)).collect();
    for s in steps.windows(2) {
        assert!(s[0] > 0.1 && s[1] > 0.1 && s[1] / s[0] < 2.0 && s[0] / s[1] < 2.0, "{steps:?}");
    }
}

#[test]
fn editing_one_keyframe_rerenders_only_the_frames_whose_pose_moves() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rig = |last: f64| {
        format!(
            "keyframes = [\n  {{ time = 0, position = [0, -4, 1] }},\n  {{ time = 1, position = [4, 0, 1] }},\n  \
             {{ time = 2, position = [0, 4, 1] }},\n  {{ time = 3, position = [{last}, 0, 1] }},\n]"
        )
    };
    let text = manifest(13, &rig(-4.0));
    assert_eq!(build_in(d, &text).renders, 13);
    let before = written(d);
    // The last keyframe bends the segments it is a neighbour of (t ∈ (1, 3]): frames 5 … 12, but for frame 8,
    // which sits on keyframe 2 at t = 2 s.
    let edited = manifest(13, &rig(-5.0));
    std::fs::write(d.join("m.toml"), &edited).unwrap();
    let m = crate::common::load(&d.join("m.toml"));
    let st = vvgen::build::status(&m, &d.join("cache"), true).unwrap();
    let mut stale: Vec<String> = st
        .actions
        .iter()
        .filter(|a| a.state == vvgen::build::State::Run && a.kind == Kind::RenderPass)
        .map(|a| a.label.clone())
        .collect();
    stale.sort_by_key(|l| l.split('/').nth(2).and_then(|f| f.split(' ').next()?.parse::<u32>().ok()));
    let moved = |f: usize| f >= 5 && f != 8;
    let want: Vec<String> = (0..13).filter(|&f| moved(f)).map(|f| format!("render walk/{f}/{f} rgba")).collect();
    assert_eq!(stale, want);
    assert_eq!(build_in(d, &edited).renders, 7);
    let after = written(d);
    for f in 0..13 {
        assert_eq!(before[f] == after[f], !moved(f), "frame {f}");
    }
}

/// `world`'s camera-to-world as nerfstudio's model sees it after its dataparser: `scale · (T · c2w)` in
/// translation, `T`'s rotation applied to the axes.
fn to_model(world: &DMat4, t: &DMat4, scale: f64) -> Vec<f64> {
    let mut m = *t * *world;
    m.w_axis = (m.w_axis.truncate() * scale).extend(1.0);
    m.transpose().to_cols_array().to_vec()
}

#[test]
fn a_nerfstudio_camera_path_renders_its_cameras_back_in_the_world() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The viewer's path at 4 fps (the dataset's): five cameras about the subject, in the world.
    let world: Vec<DMat4> = (0..5)
        .map(|i| {
            let a = i as f64 * 0.4;
            vvgen::rig::look_at(DVec3::new(3.5 * a.sin(), -3.5 * a.cos(), 0.5 + 0.2 * i as f64), DVec3::ZERO)
        })
        .collect();
    // The model's frame: nerfstudio's orientation and centring (a rotation and a shift) and its scale.
    let t = DMat4::from_rotation_translation(
        glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.7),
        DVec3::new(0.3, -0.2, 0.1),
    );
    let scale = 0.37;
    let path: Vec<Value> = world
        .iter()
        .map(|w| serde_json::json!({ "camera_to_world": to_model(w, &t, scale), "fov": 90.0, "aspect": 1.0 }))
        .collect();
    let doc = serde_json::json!({
        "keyframes": [], "camera_type": "perspective", "render_height": 48, "render_width": 48,
        "fps": 4, "seconds": 1.25, "is_cycle": false, "smoothness_value": 0.5, "camera_path": path,
    });
    std::fs::write(d.join("camera_path.json"), doc.to_string()).unwrap();
    let rows: Vec<Vec<f64>> = (0..3).map(|r| (0..4).map(|c| t.col(c)[r]).collect()).collect();
    let transforms = serde_json::json!({ "transform": rows, "scale": scale });
    std::fs::write(d.join("dataparser_transforms.json"), transforms.to_string()).unwrap();
    let rig = "file = \"camera_path.json\"\ndataparser_transforms = \"dataparser_transforms.json\"";
    assert_eq!(build_in(d, &manifest(5, rig)).renders, 5);
    let got = written(d);
    for (i, (g, w)) in got.iter().zip(&world).enumerate() {
        // Reprojection: points about the subject land on the same pixels as through the original camera.
        for p in [DVec3::ZERO, DVec3::new(0.3, 0.2, 0.8), DVec3::new(-0.4, 0.1, -0.6)] {
            let (a, b) = (project(g, p), project(w, p));
            assert!((a.0 - b.0).abs() < 1e-6 && (a.1 - b.1).abs() < 1e-6, "camera {i}: {a:?} against {b:?}");
        }
    }
    // A path drawn at another field of view renders at its own: nerfstudio records its focal length.
    let narrow = doc.to_string().replace("\"fov\":90.0", "\"fov\":60.0");
    std::fs::write(d.join("camera_path.json"), narrow).unwrap();
    build_in(d, &manifest(5, rig));
    let meta: Value =
        serde_json::from_slice(&std::fs::read(d.join("out/m_nerfstudio/transforms.json")).unwrap()).unwrap();
    let f = 24.0 / (30f64).to_radians().tan();
    assert!((meta["fl_x"].as_f64().unwrap() - f).abs() < 1e-9 && (meta["fl_y"].as_f64().unwrap() - f).abs() < 1e-9);
    // A format with [render]'s one focal length refuses it, naming the way out.
    std::fs::write(d.join("m.toml"), manifest(5, rig).replace("\"nerfstudio\"", "\"dnerf\"")).unwrap();
    let (code, err) = vvgen(d, &["check", "m.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("split `walk`, whose path's field of view is not [render]'s"), "{err}");
    assert!(err.contains("write that split with a nerfstudio output"), "{err}");
}

#[test]
fn a_zooming_path_writes_each_frames_focal_length() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // From [render]'s 90° at t = 0 to 45° at t = 1 s, linearly; the camera stays put, aimed at the origin.
    let rig = "keyframes = [{ time = 0, position = [0, -4, 1] }, { time = 1, position = [0, -4, 1], fov_deg = 45 }]";
    assert_eq!(build_in(d, &manifest(5, rig)).renders, 5);
    let meta: Value =
        serde_json::from_slice(&std::fs::read(d.join("out/m_nerfstudio/transforms.json")).unwrap()).unwrap();
    // nerfstudio reads per-frame focal lengths only when the file gives none for all.
    assert!(meta.get("fl_x").is_none() && meta.get("fl_y").is_none() && meta["cx"] == 24.0, "{meta}");
    let mut frames: Vec<&Value> = meta["frames"].as_array().unwrap().iter().collect();
    frames.sort_by_key(|f| f["frame"].as_u64().unwrap());
    for (i, f) in frames.iter().enumerate() {
        let fov = 90.0 - 45.0 * i as f64 / 4.0;
        let want = 24.0 / (fov / 2.0f64).to_radians().tan();
        assert!((f["fl_x"].as_f64().unwrap() - want).abs() < 1e-9, "frame {i}: {f}");
        assert_eq!(f["fl_x"], f["fl_y"]);
    }
    // And the images zoom: the subject grows, frame by frame.
    let covered = |i: usize| {
        let p = d.join(format!("out/m_nerfstudio/walk/r_{i:04}.png"));
        image::open(p).unwrap().to_rgba8().pixels().filter(|p| p[3] > 0).count()
    };
    let sizes: Vec<usize> = (0..5).map(covered).collect();
    assert!(sizes.windows(2).all(|w| w[1] > w[0]), "{sizes:?}");
}

#[test]
fn a_left_handed_trace_maps_onto_the_world_by_its_transform() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Unity: left-handed, +Y up, the camera looking along its +Z. At (0, 0, -4) with no rotation it faces the
    // origin; half a second later it has turned 90° about +Y, at (-4, 0, 0), still facing it. The header names
    // the columns in its own order, with one vvgen does not read.
    let q = (std::f64::consts::FRAC_PI_4.sin(), std::f64::consts::FRAC_PI_4.cos());
    let csv = format!(
        "# a viewer's head trace\nqw,qx,qy,qz,frame,time,x,y,z\n1,0,0,0,0,10.0,0,0,-4\n{},0,{},0,1,10.5,-4,0,0\n",
        q.1, q.0
    );
    std::fs::write(d.join("viewer.csv"), csv).unwrap();
    let rig = "trace = \"viewer.csv\"\ntrace_handedness = \"left\"\n\
               trace_to_world = [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]]";
    assert_eq!(build_in(d, &manifest(3, rig)).renders, 3);
    let c2w = written(d);
    // Unity's (0, 0, -4) is right-handed (0, 0, 4), and +Y up becomes +Z up: the world's (0, -4, 0).
    // Unity's (-4, 0, 0) turned about +Y (clockwise seen from above in Unity) is the world's (-4, 0, 0).
    for (frame, eye) in [(0, DVec3::new(0.0, -4.0, 0.0)), (2, DVec3::new(-4.0, 0.0, 0.0))] {
        let m = &c2w[frame];
        assert!(m.w_axis.truncate().distance(eye) < 1e-9, "frame {frame}: {m}");
        let (u, v) = project(m, DVec3::ZERO);
        assert!((u - 24.0).abs() < 1e-6 && (v - 24.0).abs() < 1e-6, "frame {frame}: the origin at {u}, {v}");
        let (_, above) = project(m, DVec3::Z * 0.1);
        assert!(above < v, "frame {frame}: up is not up");
    }
    // Half-way, on the chord between the two samples.
    assert!(c2w[1].w_axis.truncate().distance(DVec3::new(-2.0, -2.0, 0.0)) < 1e-9, "{}", c2w[1]);

    // A malformed row is named by file, line and column; a header without the columns says which it lacks.
    std::fs::write(d.join("viewer.csv"), "time,x,y,z,qx,qy,qz,qw\n0,0,0,-4,0,0,0,1\n0.5,0,0,-4,0,0,zero,1\n").unwrap();
    std::fs::write(d.join("m.toml"), manifest(3, rig)).unwrap();
    let (code, err) = vvgen(d, &["check", "m.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("viewer.csv:3: column `qz`: `zero` is not a finite number"), "{err}");
    std::fs::write(d.join("viewer.csv"), "t,x,y,z,w,i,j,k\n0,0,0,-4,1,0,0,0\n").unwrap();
    let (code, err) = vvgen(d, &["check", "m.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("viewer.csv:1: the header `t,x,y,z,w,i,j,k` lacks time, qx, qy, qz, qw"), "{err}");
    // The trace needs its map to the world, and the manifest says where.
    std::fs::write(d.join("m.toml"), manifest(3, "trace = \"viewer.csv\"")).unwrap();
    let (code, err) = vvgen(d, &["check", "m.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("a trace needs `trace_to_world`") && err.contains("m.toml:"), "{err}");
}

#[test]
fn a_dynerf_output_writes_a_path_beside_its_cameras_as_one_video() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rig = "keyframes = [{ time = 0, position = [0, -4, 1] }, { time = 1, position = [4, 0, 1] }]";
    let text = manifest(5, rig).replace("writer = \"nerfstudio\"", "writer = \"dynerf\"")
        + "\n[rig.fixed]\nkind = \"orbit\"\n\n[split.cams]\nrig = \"fixed\"\nviews = 2\n";
    assert_eq!(build_in(d, &text).renders, 5 + 2 * 5);
    let out = d.join("out/m_dynerf");
    // The loaders' cameras are the fixed ones only: two rows of 17.
    let npy = std::fs::read(out.join("poses_bounds.npy")).unwrap();
    assert!(
        String::from_utf8_lossy(&npy[..128]).contains("'shape': (2, 17)"),
        "{}",
        String::from_utf8_lossy(&npy[..128])
    );
    assert!(out.join("cam01.mp4").is_file() && !out.join("cam02.mp4").exists());
    // The path: one video, its frames, and its cameras as nerfstudio's camera path, frame by frame.
    let mp4 = std::fs::read(out.join("path_walk.mp4")).unwrap();
    assert_eq!(&mp4[4..8], b"ftyp");
    assert!((0..5).all(|f| out.join(format!("path_walk/{f:04}.png")).is_file()));
    let doc: Value = serde_json::from_slice(&std::fs::read(out.join("path_walk.json")).unwrap()).unwrap();
    let cams = doc["camera_path"].as_array().unwrap();
    assert_eq!((cams.len(), doc["fps"].as_f64(), doc["render_width"].as_u64()), (5, Some(4.0), Some(48)));
    for (f, eye) in [(0usize, DVec3::new(0.0, -4.0, 1.0)), (4, DVec3::new(4.0, 0.0, 1.0))] {
        let m: Vec<f64> = serde_json::from_value(cams[f]["camera_to_world"].clone()).unwrap();
        let c2w = DMat4::from_cols_array(&m.try_into().unwrap()).transpose();
        assert!(c2w.w_axis.truncate().distance(eye) < 1e-9, "frame {f}: {c2w}");
        let (u, v) = project(&c2w, DVec3::ZERO);
        assert!((u - 24.0).abs() < 1e-6 && (v - 24.0).abs() < 1e-6);
        assert!((cams[f]["fov"].as_f64().unwrap() - 90.0).abs() < 1e-9);
    }
    // A dynerf output of paths alone has no camera for the loaders: refused, naming the split.
    std::fs::write(d.join("m.toml"), manifest(5, rig).replace("writer = \"nerfstudio\"", "writer = \"dynerf\""))
        .unwrap();
    let (code, err) = vvgen(d, &["check", "m.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("only path split `walk`") && err.contains("written beside them"), "{err}");
}
