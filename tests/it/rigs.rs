//! Camera rigs and the plan: the NeRF-synthetic facts, numpy-compatible draws, pose stability when views are
//! added, time modes, and the shared-pose hygiene check.

use std::f64::consts::{FRAC_PI_2, TAU};
use std::path::Path;

use glam::{DMat3, DVec3};
use vvgen::manifest::{parse, Manifest};
use vvgen::plan::Plan;

fn manifest(body: &str) -> Manifest {
    let text = format!(
        "[dataset]\nname = \"t\"\nout = \"out\"\nseed = 11\n[source.a]\ngltf = \"gltf/BoxTextured/BoxTextured.glb\"\n\
         [render]\nresolution = [64, 64]\n{body}"
    );
    match parse(&text, &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/m.toml")) {
        Ok((m, _)) => m,
        Err(r) => panic!("{}", r.render(false)),
    }
}

fn positions(p: &Plan, split: &str) -> Vec<DVec3> {
    p.splits.iter().find(|s| s.name == split).unwrap().poses.iter().map(|m| m.w_axis.truncate()).collect()
}

#[test]
fn nerf_test_orbit_starts_at_the_published_lego_camera() {
    let m = manifest("[rig.r]\nkind = \"orbit\"\nschedule = \"nerf-test\"\n[split.test]\nrig = \"r\"\nviews = 200");
    let p = Plan::new(&m, 1).unwrap();
    let c = positions(&p, "test");
    assert!((c[0] - DVec3::new(0.0, 2.73726, 2.95929)).length() < 1e-5, "{}", c[0]);
    // Every camera at the NeRF radius, looking at the origin.
    for (pos, m) in c.iter().zip(&p.splits[0].poses) {
        assert!((pos.length() - 4.031128874149275).abs() < 1e-9);
        let back = m.z_axis.truncate();
        assert!((back - pos.normalize()).length() < 1e-9);
    }
}

#[test]
fn hemisphere_numpy_mode_reproduces_the_toolkits_80_cameras() {
    // The 6-DoF toolkit's own cameras, from its script run in Blender: every view, not just the first.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/toolkit-cameras/seed0_train_80.json");
    let blender: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    let frames = blender["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 80);
    let m = manifest("[rig.h]\nkind = \"hemisphere\"\nnumpy_seed = 0\n[split.train]\nrig = \"h\"\nviews = 80");
    let p = Plan::new(&m, 1).unwrap();
    let ours = &p.splits[0].poses;
    for (i, f) in frames.iter().enumerate() {
        assert_eq!(f["view"].as_u64(), Some(i as u64));
        let rows: Vec<Vec<f64>> = serde_json::from_value(f["transform_matrix"].clone()).unwrap();
        let col = |c: usize| DVec3::new(rows[0][c], rows[1][c], rows[2][c]);
        let (pos, rot) = (col(3), DMat3::from_cols(col(0), col(1), col(2)));
        let got = ours[i];
        let dp = (got.w_axis.truncate() - pos).length();
        assert!(dp <= 1e-5, "view {i}: position {} vs Blender's {pos} ({dp})", got.w_axis.truncate());
        // The largest angle between a camera axis of ours and Blender's (atan2 of |a×b| and a·b: well
        // conditioned near 0, where acos of the trace is not).
        let ours_rot = DMat3::from_mat4(got);
        let angle = (0..3)
            .map(|k| {
                let (a, b) = (ours_rot.col(k), rot.col(k));
                a.cross(b).length().atan2(a.dot(b)).to_degrees()
            })
            .fold(0.0, f64::max);
        assert!(angle <= 1e-3, "view {i}: {angle}° from Blender's camera");
    }
    // And the stream itself: view 0 is numpy's first draw, np.random.seed(0); uniform(0, 1, 3).
    let u: [f64; 3] = [0.5488135039273248, 0.7151893663724195, 0.6027633760716439];
    let tilt = ((1.0 - 2.0 * u[0]).acos() - FRAC_PI_2).abs();
    let expect = DMat3::from_rotation_z(TAU * u[2]) * DMat3::from_rotation_x(tilt) * DVec3::new(0.0, 4.0, 0.5);
    assert!((positions(&p, "train")[0] - expect).length() < 1e-9);
}

#[test]
fn adding_views_leaves_earlier_poses_bit_identical() {
    for rig in [
        "kind = \"hemisphere\"",
        "kind = \"sphere\"\nband = \"full\"",
        "kind = \"hemisphere\"\nnumpy_seed = 4",
        "kind = \"sphere\"\njitter = { position = 0.1, target = 0.05 }",
    ] {
        let few = Plan::new(&manifest(&format!("[rig.r]\n{rig}\n[split.train]\nrig = \"r\"\nviews = 80")), 1).unwrap();
        let more =
            Plan::new(&manifest(&format!("[rig.r]\n{rig}\n[split.train]\nrig = \"r\"\nviews = 100")), 1).unwrap();
        let (a, b) = (&few.splits[0].poses, &more.splits[0].poses);
        assert_eq!(a.len(), 80);
        assert_eq!(&b[..80], &a[..], "{rig}");
        assert_ne!(b[80], b[79]);
    }
    // Jitter is drawn per view too: appending an explicit pose moves none of the others.
    let rig = "kind = \"explicit\"\njitter = { position = 0.2 }\nposes = [{ position = [0, -4, 1] }, { position = [4, 0, 1] }";
    let a = Plan::new(&manifest(&format!("[rig.r]\n{rig}]\n[split.s]\nrig = \"r\"")), 1).unwrap();
    let b = Plan::new(&manifest(&format!("[rig.r]\n{rig}, {{ position = [0, 4, 1] }}]\n[split.s]\nrig = \"r\"")), 1)
        .unwrap();
    assert_eq!(&b.splits[0].poses[..2], &a.splits[0].poses[..]);
    assert!((a.splits[0].poses[0].w_axis.truncate() - DVec3::new(0.0, -4.0, 1.0)).length() > 1e-6, "jittered");
}

#[test]
fn random_rigs_differ_between_splits_and_seeds() {
    let m = manifest(
        "[rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 5\n[split.val]\nrig = \"h\"\nviews = 5",
    );
    let p = Plan::new(&m, 1).unwrap();
    assert_ne!(positions(&p, "train"), positions(&p, "val"));
    assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    for c in positions(&p, "train") {
        assert!(c.z > 0.0, "upper hemisphere");
    }
}

#[test]
fn shared_poses_warn_unless_allowed() {
    let body = "[rig.e]\nkind = \"explicit\"\nposes = [{ position = [0, -4, 1] }, { position = [4, 0, 1] }]\n\
                [split.train]\nrig = \"e\"\n[split.test]\nrig = \"e\"\n";
    let p = Plan::new(&manifest(body), 1).unwrap();
    assert_eq!(p.warnings.len(), 1, "{:?}", p.warnings);
    assert!(p.warnings[0].contains("share 2"));
    let p = Plan::new(&manifest(&format!("{body}allow_shared_poses = true\n")), 1).unwrap();
    assert!(p.warnings.is_empty());
}

#[test]
fn time_modes_all_monocular_random() {
    let m = manifest(
        "[rig.f]\nkind = \"fibonacci\"\n\
         [split.all]\nrig = \"f\"\nviews = 3\nframes = { start = 2, end = 8, every = 3 }\n\
         [split.mono]\nrig = \"f\"\ntime = \"monocular\"\n\
         [split.rand]\nrig = \"f\"\nviews = 4\ntime = \"random\"\npairs = 7\n",
    );
    let p = Plan::new(&m, 11).unwrap();
    let imgs = |name: &str| {
        let s = p.splits.iter().find(|s| s.name == name).unwrap();
        s.images.iter().map(|&i| &p.images[i]).collect::<Vec<_>>()
    };
    let all = imgs("all");
    assert_eq!(all.len(), 9);
    assert_eq!(all.iter().map(|i| i.frame).collect::<Vec<_>>(), [2, 2, 2, 5, 5, 5, 8, 8, 8]);
    assert_eq!(all[3].time, 0.5);
    let mono = imgs("mono");
    assert_eq!(mono.len(), 11, "one view per frame");
    assert!(mono.iter().enumerate().all(|(i, m)| m.frame == i && m.view as usize == i));
    assert_eq!((mono[0].time, mono[10].time), (0.0, 1.0));
    let rand = imgs("rand");
    assert_eq!(rand.len(), 7);
    let mut pairs: Vec<_> = rand.iter().map(|i| (i.frame, i.view)).collect();
    assert!(pairs.windows(2).all(|w| w[0] < w[1]), "distinct and time-major: {pairs:?}");
    pairs.retain(|&(f, v)| f < 11 && v < 4);
    assert_eq!(pairs.len(), 7);
    // Indices are time-major positions within the split.
    assert!(rand.iter().enumerate().all(|(k, i)| i.index == k));
}

#[test]
fn every_rig_looks_at_its_target() {
    for rig in [
        "kind = \"sphere\"\nelevation_range_deg = [-10, 40]",
        "kind = \"fibonacci\"\nband = \"full\"",
        "kind = \"dome\"\nrings = 3",
        "kind = \"forward-facing\"\nlayout = \"spiral\"",
        "kind = \"forward-facing\"",
        "kind = \"orbit\"",
    ] {
        let m = manifest(&format!("[rig.r]\n{rig}\ntarget = [0.5, 0.0, 1.0]\n[split.s]\nrig = \"r\"\nviews = 12"));
        let p = Plan::new(&m, 1).unwrap();
        for img in &p.images {
            let (u, v, _) = img.camera.project(glam::Vec3::new(0.5, 0.0, 1.0)).unwrap();
            assert!((u - 32.0).abs() < 1e-6 && (v - 32.0).abs() < 1e-6, "{rig}: target at ({u}, {v})");
            // Image up is world up (no roll).
            assert!(img.camera.c2w.x_axis.z.abs() < 1e-9, "{rig}: rolled camera");
        }
        if rig.contains("elevation_range") {
            for img in &p.images {
                let d = (img.camera.c2w.w_axis.truncate() - DVec3::new(0.5, 0.0, 1.0)).normalize();
                let el = d.z.asin().to_degrees();
                assert!((-10.0 - 1e-9..=40.0 + 1e-9).contains(&el), "{el}");
            }
        }
    }
}
