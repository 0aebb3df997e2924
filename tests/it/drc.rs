//! Draco files (`.drc`, `draco_encoder`'s output): a mesh and a point cloud decode as Google's decoder decodes them
//! (positions, triangles and colours bit for bit as DracoPy, which runs it, wrote them to PLY), a folder of
//! Draco frames runs through `new`, `check` and `build` as a newcomer runs it, and damaged files are errors naming
//! the file, never a panic.

use std::path::Path;
use std::process::Command;

use vvgen::scene::{drc, source};

use crate::common::data;

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// google/draco's `car.drc` (an EdgeBreaker mesh with normals) and `point_cloud_no_qp.drc` (a point cloud with
/// colours, unquantized) against the PLYs DracoPy 2.2 (Google's decoder) and trimesh wrote from them.
#[test]
fn draco_files_decode_as_googles_decoder_decodes_them() {
    for (name, triangles, points) in [("car", 1744, 0), ("point_cloud_no_qp", 0, 21)] {
        let got = drc::scene(&data(&format!("drc/{name}.drc"))).unwrap_or_else(|e| panic!("{e}"));
        let want = source::ply_scene(&data(&format!("drc/{name}_decoded.ply"))).unwrap();
        assert_eq!((got.triangle_count(), got.point_count()), (triangles, points), "{name}");
        let (p, q) = (&got.primitives[0], &want.primitives[0]);
        assert_eq!(p.positions, q.positions, "{name}: positions");
        assert_eq!(p.indices, q.indices, "{name}: triangles");
        assert_eq!(p.colors, q.colors, "{name}: colours");
    }
    // The car's own normals (Draco keeps them, the PLY does not): unit, and the mesh's own normals within a
    // smoothing's difference.
    let car = drc::scene(&data("drc/car.drc")).unwrap();
    let normals = &car.primitives[0].normals;
    assert!(normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-4), "unit normals");
}

/// A folder of Draco point-cloud frames, as a newcomer brings it: `vvgen new` on the folder writes a sequence,
/// `check` and `build` run it, and the frames are drawn in their colours.
#[test]
fn a_folder_of_draco_frames_builds_as_a_sequence() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    for i in 0..3 {
        std::fs::copy(data("drc/pc_kd_color.drc"), frames.join(format!("scan_{i:03}.drc"))).unwrap();
    }
    let (code, err) = vvgen(tmp.path(), &["new", "frames", "-o", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    let manifest = std::fs::read_to_string(tmp.path().join("m.toml")).unwrap();
    assert!(manifest.contains("mesh_sequence") && manifest.contains("*.drc"), "{manifest}");
    let manifest = manifest.replace("[400, 400]", "[64, 64]").replace("views = 100", "views = 2");
    std::fs::write(tmp.path().join("m.toml"), manifest).unwrap();
    for command in ["check", "build"] {
        let (code, err) = vvgen(tmp.path(), &["-q", command, "m.toml"]);
        assert_eq!(code, 0, "{command}: {err}");
    }
    let image = image::open(tmp.path().join("out/frames/frames_dnerf/train/r_0000.png")).unwrap().to_rgba8();
    let shades: std::collections::BTreeSet<_> = image.pixels().filter(|p| p[3] == 255).map(|p| p.0).collect();
    assert!(shades.len() > 50, "the scan's colours show: {} shades", shades.len());
}

/// Every byte of a Draco point cloud set to three values: each decodes or is an error, none panics; a damaged file
/// is refused by `check` and `build` with exit 2, naming it.
#[test]
fn damaged_draco_files_fail_cleanly() {
    let bytes = std::fs::read(data("drc/cube_pc.drc")).unwrap();
    let (mut decoded, mut refused) = (0, 0);
    for at in 0..bytes.len() {
        for value in [0u8, 0xff, bytes[at] ^ 0x10] {
            let mut b = bytes.clone();
            b[at] = value;
            match drc::scene_slice(&b, Path::new("cube_pc.drc")) {
                Ok(_) => decoded += 1,
                Err(e) => {
                    let e = e.to_string();
                    assert!(e.contains("cube_pc.drc") && e.contains("Draco"), "{e}");
                    refused += 1;
                }
            }
        }
    }
    assert!(decoded > 0 && refused > 0, "{decoded} decoded, {refused} refused");
    let tmp = tempfile::tempdir().unwrap();
    let mut cut = bytes.clone();
    cut.truncate(40);
    std::fs::write(tmp.path().join("cloud.drc"), cut).unwrap();
    let manifest = "[dataset]\nname = \"s\"\nout = \"out\"\n[source.s]\nmesh = \"cloud.drc\"\n[rig.h]\nkind = \
                    \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n[output.d]\nwriter = \"dnerf\"\n";
    std::fs::write(tmp.path().join("m.toml"), manifest).unwrap();
    for command in ["check", "build"] {
        let (code, err) = vvgen(tmp.path(), &[command, "m.toml"]);
        assert_eq!(code, 2, "{command}: {err}");
        assert!(err.contains("cloud.drc") && err.contains("a damaged Draco file"), "{command}: {err}");
    }
}
