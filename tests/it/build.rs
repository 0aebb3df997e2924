//! `vvgen build` end to end: identical bytes whatever the thread count, a published camera set re-rendered
//! from its transforms.json, and point-cloud sequences.

use std::path::{Path, PathBuf};

use crate::common::{cesium_head, load, tree};

fn write_manifest(dir: &Path, extra: &str) -> PathBuf {
    let text = format!(
        r#"{}
[render]
resolution = [64, 64]
samples    = 4
passes     = ["rgba", "depth", "normal", "mask"]
[rig.h]
kind = "hemisphere"
[split.train]
rig   = "h"
views = 3
[output.d]
writer = "dnerf"
init_points = 300
{extra}
"#,
        cesium_head(2, 4, 2.4, "", "")
    );
    let p = dir.join("m.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn build(manifest: &Path, threads: usize) -> vvgen::build::Report {
    let m = load(manifest);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        vvgen::build::build(&m, &vvgen::build::default_cache_dir(&m), Default::default(), &vvgen::build::Silent)
    })
    .unwrap()
}

#[test]
fn same_bytes_with_one_and_two_threads() {
    let points = "[output.p]\nwriter = \"ply-sequence\"\npoints = 5000\nvoxel = 0.02\n";
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let ra = build(&write_manifest(a.path(), points), 1);
    let rb = build(&write_manifest(b.path(), points), 2);
    // Both builds did the work themselves (each has its own cache, whatever VVGEN_CACHE says to the CLI).
    for r in [&ra, &rb] {
        assert_eq!((r.images, r.renders), (6, 6));
        assert_eq!(r.ran(vvgen::plan::actions::Kind::PointFrame), 2);
        assert_eq!(r.ran(vvgen::plan::actions::Kind::SampleFrame), 2);
    }
    let (ta, tb) = (tree(&a.path().join("out")), tree(&b.path().join("out")));
    assert!(ta.len() > 20, "{:?}", ta.keys().collect::<Vec<_>>());
    assert_eq!(ta.keys().collect::<Vec<_>>(), tb.keys().collect::<Vec<_>>());
    for (k, v) in &ta {
        assert!(v == &tb[k], "{k} differs between 1 and 2 threads");
    }
    // Every requested pass landed, with its consumer's channel layout.
    let d = a.path().join("out/m_dnerf");
    assert_eq!(image::open(d.join("normal/train/r_0000.png")).unwrap().color(), image::ColorType::Rgb8);
    assert_eq!(image::open(d.join("mask/train/r_0000.png")).unwrap().color(), image::ColorType::L8);
    assert_eq!(image::open(d.join("depth/train/r_0000.png")).unwrap().color(), image::ColorType::L16);
}

#[test]
fn from_file_rig_rerenders_a_published_camera_set() {
    let a = tempfile::tempdir().unwrap();
    build(&write_manifest(a.path(), ""), 2);
    let published = a.path().join("out/m_dnerf/transforms_train.json");
    let b = tempfile::tempdir().unwrap();
    let extra = format!(
        "[rig.pub]\nkind = \"from-file\"\nfile = \"{}\"\n[split.again]\nrig = \"pub\"\ntime = \"monocular\"\n",
        published.display()
    );
    let path = write_manifest(b.path(), &extra);
    let (m, _) = vvgen::manifest::load(&path).unwrap_or_else(|r| panic!("{}", r.render(false)));
    let plan = vvgen::plan::Plan::new(&m, 2).unwrap();
    let train = &plan.splits.iter().find(|s| s.name == "train").unwrap().poses;
    let again = &plan.splits.iter().find(|s| s.name == "again").unwrap().poses;
    // The published file lists each of the 3 views at both frames, time-major.
    assert_eq!(again.len(), 6);
    for (i, p) in again.iter().enumerate() {
        assert!(p.abs_diff_eq(train[i % 3], 1e-12), "pose {i}");
    }
    // Both splits now share poses, and the hygiene check says so.
    assert!(plan.warnings.iter().any(|w| w.contains("share")), "{:?}", plan.warnings);
}

#[test]
fn ply_sequence_writes_exact_counts_and_one_lattice() {
    let dir = tempfile::tempdir().unwrap();
    let extra = "[output.raw]\nwriter = \"ply-sequence\"\npoints = 4000\n\
                 [output.vox]\nwriter = \"ply-sequence\"\npoints = 20000\nvoxel = 0.05\ndir = \"vox\"\n";
    build(&write_manifest(dir.path(), extra), 2);
    let out = dir.path().join("out");
    let read = |p: PathBuf| vvgen::scene::ply::read(&std::fs::read(&p).unwrap()).unwrap();
    for f in 0..2 {
        let raw = read(out.join(format!("m_points/m_{f:04}.ply")));
        assert_eq!(raw.positions.len(), 4000);
        assert!(raw.normals.is_some() && raw.colors.is_some());
        // Voxel means of one origin-anchored lattice: no two points share a cell, fewer points than samples.
        let v = read(out.join(format!("vox/m_{f:04}.ply")));
        let mut cells: Vec<[i64; 3]> =
            v.positions.iter().map(|p| p.map(|c| (c as f64 / 0.05).floor() as i64)).collect();
        let n = cells.len();
        cells.sort_unstable();
        cells.dedup();
        assert_eq!(cells.len(), n, "one point per voxel");
        assert!(n > 100 && n < 20000, "{n}");
    }
}

#[test]
fn two_outputs_in_one_directory_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    // An explicit `dir` equal to another output's default, and two point outputs with the same default.
    let extra = "[output.e]\nwriter = \"nerfstudio\"\ndir = \"m_dnerf\"\n\
                 [output.p]\nwriter = \"ply-sequence\"\npoints = 10\n[output.q]\nwriter = \"ply-sequence\"\npoints = 10\n";
    let report = vvgen::manifest::load(&write_manifest(dir.path(), extra)).unwrap_err();
    let errors: Vec<&str> = report.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.message.as_str()).collect();
    assert_eq!(
        errors,
        [
            "outputs `d` and `e` write to the same directory `m_dnerf`",
            "outputs `p` and `q` write to the same directory `m_points`"
        ]
    );
    assert!(!dir.path().join("out").exists(), "refused before anything was written");
    // One output's folder inside another's: the outer dataset's lock would count the inner files as extra, and
    // `vvgen verify` of a released dataset would fail.
    let extra = "[output.e]\nwriter = \"nerfstudio\"\ndir = \".\"\n";
    let report = vvgen::manifest::load(&write_manifest(dir.path(), extra)).unwrap_err();
    let errors: Vec<&str> = report.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.message.as_str()).collect();
    assert_eq!(errors, ["output `e`'s directory `.` holds output `d`'s (`m_dnerf`)"]);
    let extra = "[output.e]\nwriter = \"nerfstudio\"\ndir = \"m_dnerf/./nested/\"\n";
    let report = vvgen::manifest::load(&write_manifest(dir.path(), extra)).unwrap_err();
    let errors: Vec<&str> = report.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.message.as_str()).collect();
    assert_eq!(errors, ["output `d`'s directory `m_dnerf` holds output `e`'s (`m_dnerf/./nested/`)"]);
}

#[test]
fn correspondence_tracks_surface_points_and_motion() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tri.gltf"), crate::common::animated_triangle(0.3)).unwrap();
    let outputs = "[output.p]\nwriter = \"ply-sequence\"\npoints = 500\nmotion = true\n";
    let text = crate::common::triangle_manifest(4, 1, 16, 1, outputs);
    std::fs::write(d.join("m.toml"), text).unwrap();
    build(&d.join("m.toml"), 2);
    let read = |f: usize| {
        let bytes = std::fs::read(d.join(format!("out/tri_points/tri_{f:04}.ply"))).unwrap();
        (vvgen::scene::ply::read(&bytes).unwrap(), String::from_utf8_lossy(&bytes[..600]).to_string())
    };
    let (f0, head) = read(0);
    assert!(head.contains("property uint point_id") && head.contains("property float motion_x"), "{head}");
    assert_eq!(f0.positions.len(), 500);
    // The keys translate the triangle by x = 0, 0.1, 0.2, 0.3: point i moves by exactly that (same surface point).
    for (f, dx) in [(1, 0.1f32), (2, 0.2), (3, 0.3)] {
        let (pf, _) = read(f);
        for (a, b) in f0.positions.iter().zip(&pf.positions) {
            assert!((b[0] - a[0] - dx).abs() < 1e-5 && (b[1] - a[1]).abs() < 1e-6, "frame {f}: {a:?} → {b:?}");
        }
    }
}

#[test]
fn vox_quantizes_onto_one_integer_grid() {
    let dir = tempfile::tempdir().unwrap();
    let extra = "[output.v]\nwriter = \"ply-sequence\"\npoints = 30000\nvox = 8\n";
    build(&write_manifest(dir.path(), extra), 2);
    let mut grids = Vec::new();
    for f in 0..2 {
        let bytes = std::fs::read(dir.path().join(format!("out/m_points/m_{f:04}.ply"))).unwrap();
        let head = String::from_utf8_lossy(&bytes[..400]).to_string();
        assert!(!head.contains("property float nx"), "8i layout: x y z and colours only");
        grids.push(head.lines().find(|l| l.contains("grid origin")).unwrap().to_string());
        let p = vvgen::scene::ply::read(&bytes).unwrap();
        let mut cells: Vec<[i32; 3]> = p
            .positions
            .iter()
            .map(|q| {
                assert!(q.iter().all(|c| c.fract() == 0.0 && (0.0..=255.0).contains(c)), "{q:?}");
                q.map(|c| c as i32)
            })
            .collect();
        let n = cells.len();
        cells.sort_unstable();
        cells.dedup();
        assert_eq!(cells.len(), n, "duplicate voxels merged");
    }
    assert_eq!(grids[0], grids[1], "one grid for the whole sequence");
}
