//! `vvgen compare` against the references it is held to: scikit-image's PSNR and SSIM on images (within 1e-4,
//! the bar), MPEG pc_error's D1, D2 and colour PSNR on point clouds (within 0.01 dB). The reference figures were
//! computed outside the suite (benches/compare_reference.py, benches/pc_error_reference.py) and are stored with
//! the files they score (tests/data/compare/SOURCE.txt).

use std::path::Path;
use std::process::Command;

use serde_json::Value;

use crate::common::data;
use vvgen::compare::clouds::{self, Cloud};

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code().unwrap_or(-1), text(&out.stdout), text(&out.stderr))
}

fn json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn images_score_as_scikit_image_scores_them() {
    let d = data("compare/images");
    let (code, out, err) = vvgen(&d, &["compare", "gt", "test", "--json"]);
    assert_eq!(code, 0, "{err}");
    let ours: Value = serde_json::from_str(&out).unwrap();
    let reference = json(&d.join("skimage.json"));
    let (ours, reference) = (ours["images"].as_array().unwrap(), reference.as_array().unwrap());
    assert_eq!(ours.len(), 3);
    for (o, r) in ours.iter().zip(reference) {
        assert_eq!(o["name"], r["name"]);
        for k in ["psnr", "ssim", "psnr_masked", "ssim_masked"] {
            let (a, b) = (o[k].as_f64().unwrap(), r[k].as_f64().unwrap());
            // The bar is 1e-4; what is measured is float rounding.
            assert!((a - b).abs() < 1e-6, "{} {k}: {a} against scikit-image's {b}", r["name"]);
        }
    }
}

#[test]
fn renders_pair_by_a_transforms_files_frames_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let src = data("compare/images");
    std::fs::create_dir_all(d.join("truth/test")).unwrap();
    std::fs::create_dir_all(d.join("renders")).unwrap();
    let mut frames = Vec::new();
    for i in 0..3 {
        let name = format!("r_{i:04}.png");
        std::fs::copy(src.join("gt").join(&name), d.join("truth/test").join(&name)).unwrap();
        // Trainers number their renders from 0, five digits, in the transforms file's order.
        std::fs::copy(src.join("test").join(&name), d.join("renders").join(format!("{i:05}.png"))).unwrap();
        frames.push(serde_json::json!({ "file_path": format!("./test/r_{i:04}"), "transform_matrix": [] }));
    }
    std::fs::write(d.join("truth/transforms_test.json"), serde_json::json!({ "frames": frames }).to_string()).unwrap();
    let (code, out, err) =
        vvgen(d, &["compare", "truth/test", "renders", "--frames", "truth/transforms_test.json", "--json"]);
    assert_eq!(code, 0, "{err}");
    let by_order: Value = serde_json::from_str(&out).unwrap();
    let (_, by_name, _) = vvgen(&src, &["compare", "gt", "test", "--json"]);
    let by_name: Value = serde_json::from_str(&by_name).unwrap();
    for (a, b) in by_order["images"].as_array().unwrap().iter().zip(by_name["images"].as_array().unwrap()) {
        assert_eq!(a["psnr"], b["psnr"]);
        assert_eq!(a["ssim_masked"], b["ssim_masked"]);
    }
    // The table gives each image and the mean over them.
    let (code, table, _) = vvgen(d, &["compare", "truth/test", "renders", "--frames", "truth/transforms_test.json"]);
    assert_eq!(code, 0);
    assert!(table.contains("test/r_0001.png") && table.contains("mean of 3"), "{table}");
}

#[test]
fn point_clouds_score_as_pc_error_scores_them() {
    let d = data("compare/clouds");
    let reference = json(&d.join("pc_error.json"));
    let mut checked = 0;
    for (key, want) in reference.as_object().unwrap() {
        let (pair, peak) = match key.split_once(" peak ") {
            Some((p, k)) => (p, Some(k.parse::<f64>().unwrap())),
            None => (key.as_str(), None),
        };
        let (base, _) = pair.split_once('/').unwrap();
        let a = Cloud::read(&d.join(format!("{base}.ply"))).unwrap();
        let b = Cloud::read(&d.join(format!("{pair}.ply"))).unwrap();
        let got = clouds::score(pair, &a, &b, peak);
        let close = |what: &str, ours: f64, theirs: &Value| {
            let theirs = theirs.as_f64().unwrap();
            assert!((ours - theirs).abs() < 0.01, "{key} {what}: {ours} against pc_error's {theirs}");
        };
        close("peak", got.peak, &want["peak"]);
        close("D1", got.d1_psnr, &want["d1_psnr"]);
        match (&want.get("d2_psnr"), got.d2_psnr) {
            (Some(w), Some(g)) => close("D2", g, w),
            (None, None) => {}
            (w, g) => panic!("{key}: D2 {g:?} where pc_error gives {w:?}"),
        }
        let colour = got.color_psnr.expect("both clouds have colours");
        for (c, w) in want["color_psnr"].as_array().unwrap().iter().enumerate() {
            close(["Y", "Cb", "Cr"][c], colour[c], w);
        }
        checked += 1;
    }
    // Both grids, the default peak and a given one, D2 from the reference's normals: nine pairs.
    assert_eq!(checked, 9);
}

#[test]
fn what_does_not_pair_up_is_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let src = data("compare/images");
    // A render of another size.
    std::fs::create_dir_all(d.join("small")).unwrap();
    image::RgbImage::new(32, 32).save(d.join("small/r_0000.png")).unwrap();
    std::fs::create_dir_all(d.join("gt")).unwrap();
    std::fs::copy(src.join("gt/r_0000.png"), d.join("gt/r_0000.png")).unwrap();
    let (code, _, err) = vvgen(d, &["compare", "gt", "small"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("is 96×96") && err.contains("is 32×32"), "{err}");
    // A ground-truth image without a render.
    std::fs::copy(src.join("gt/r_0001.png"), d.join("gt/r_0001.png")).unwrap();
    std::fs::copy(src.join("test/r_0000.png"), d.join("small/r_0000.png")).unwrap();
    let (code, _, err) = vvgen(d, &["compare", "gt", "small"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("1 of 2 ground-truth images have no counterpart") && err.contains("r_0001.png"), "{err}");
    // A broken cloud names its file.
    std::fs::write(d.join("bad.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n")
        .unwrap();
    std::fs::copy(data("compare/clouds/vox.ply"), d.join("good.ply")).unwrap();
    let (code, _, err) = vvgen(d, &["compare", "good.ply", "bad.ply"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("bad.ply"), "{err}");
    // Folders of frames must hold as many.
    std::fs::create_dir_all(d.join("a")).unwrap();
    std::fs::create_dir_all(d.join("b")).unwrap();
    std::fs::copy(data("compare/clouds/vox.ply"), d.join("a/f0.ply")).unwrap();
    std::fs::copy(data("compare/clouds/vox.ply"), d.join("a/f1.ply")).unwrap();
    std::fs::copy(data("compare/clouds/vox/sub.ply"), d.join("b/f0.ply")).unwrap();
    let (code, _, err) = vvgen(d, &["compare", "a", "b"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("holds 2 PLY files") && err.contains("holds 1"), "{err}");
    let (code, _, err) = vvgen(d, &["compare", "a", "b", "--peak", "-3"]);
    assert_eq!(code, 2, "{err}");
    // As many: frame by frame, in name order, and the mean over them.
    std::fs::copy(data("compare/clouds/vox/noise.ply"), d.join("b/f1.ply")).unwrap();
    let (code, out, err) = vvgen(d, &["compare", "a", "b", "--peak", "255", "--json"]);
    assert_eq!(code, 0, "{err}");
    let doc: Value = serde_json::from_str(&out).unwrap();
    let want = json(&data("compare/clouds/pc_error.json"));
    let got: Vec<f64> = doc["frames"].as_array().unwrap().iter().map(|f| f["d1_psnr"].as_f64().unwrap()).collect();
    let theirs =
        [&want["vox/sub peak 255"]["d1_psnr"], &want["vox/noise peak 255"]["d1_psnr"]].map(|v| v.as_f64().unwrap());
    assert!(got.iter().zip(theirs).all(|(a, b)| (a - b).abs() < 0.01), "{got:?} against {theirs:?}");
    assert!((doc["mean"]["d1_psnr"].as_f64().unwrap() - (theirs[0] + theirs[1]) / 2.0).abs() < 0.01);
}

#[test]
fn identical_clouds_and_images_score_perfectly() {
    let d = data("compare/clouds");
    let a = Cloud::read(&d.join("float.ply")).unwrap();
    let s = clouds::score("self", &a, &a, None);
    assert_eq!((s.d1_mse, s.d2_mse), (0.0, Some(0.0)));
    assert!(s.d1_psnr.is_infinite() && s.color_psnr.unwrap().iter().all(|c| c.is_infinite()));
    let img = data("compare/images");
    let (code, out, err) = vvgen(&img, &["compare", "gt", "gt"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("inf") && out.contains("3 image(s) identical"), "{out}");
}

#[test]
fn normals_from_beside_the_reference_give_its_d2() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let src = data("compare/clouds");
    // The reference without its normals (as vox10 frames come), in ascii: every f32 round-trips.
    let c = Cloud::read(&src.join("float.ply")).unwrap();
    let colors = c.colors.as_ref().unwrap();
    let mut text = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
        c.positions.len()
    );
    for (p, k) in c.positions.iter().zip(colors) {
        text += &format!("{} {} {} {} {} {}\n", p[0], p[1], p[2], k[0], k[1], k[2]);
    }
    std::fs::write(d.join("bare.ply"), text).unwrap();
    let noise = src.join("float/noise.ply");
    let (code, out, err) = vvgen(d, &["compare", "bare.ply", noise.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let without: Value = serde_json::from_str(&out).unwrap();
    assert!(without["frames"][0]["d2_psnr"].is_null(), "no normals, no D2 (as pc_error)");
    let normals = src.join("float.ply");
    let args = ["compare", "bare.ply", noise.to_str().unwrap(), "--normals", normals.to_str().unwrap(), "--json"];
    let (code, out, err) = vvgen(d, &args);
    assert_eq!(code, 0, "{err}");
    let with: Value = serde_json::from_str(&out).unwrap();
    let want = json(&src.join("pc_error.json"))["float/noise"]["d2_psnr"].as_f64().unwrap();
    let got = with["frames"][0]["d2_psnr"].as_f64().unwrap();
    assert!((got - want).abs() < 0.01, "D2 {got} against pc_error's {want}");
    // Normals of other points are refused.
    let other = src.join("float/sub.ply");
    let (code, _, err) =
        vvgen(d, &["compare", "bare.ply", noise.to_str().unwrap(), "--normals", other.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("sub.ply") && err.contains("are not the reference's"), "{err}");
}
