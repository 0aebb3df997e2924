//! The transforms.json family: D-NeRF / NeRF-synthetic (`dnerf`), nerfstudio, instant-ngp, and one static
//! NeRF-synthetic set per time step (`static-frames`). One image layout serves them all
//! (`<split>/r_<index>.png`, depth and masks in parallel trees), so several of them may share a directory.

use serde_json::{json, Map, Value};

use super::{init_points, pad_for, r_name, rows, Error, Export, Files};
use crate::manifest::output::Output;
use crate::manifest::render::Pass;
use crate::plan::Image;

/// Image-relative paths of one image's passes, without extension: `train/r_0001`, `depth/train/r_0001`, ….
struct Names {
    rgba: String,
    depth: String,
    normal: String,
    mask: String,
    instance: String,
    albedo: String,
}

fn names(split: &str, base: &str) -> Names {
    Names {
        rgba: format!("{split}/{base}"),
        depth: format!("depth/{split}/{base}"),
        normal: format!("normal/{split}/{base}"),
        mask: format!("mask/{split}/{base}"),
        instance: format!("instance/{split}/{base}"),
        albedo: format!("albedo/{split}/{base}"),
    }
}

/// Materializes every pass of image `i` under `prefix` (`""` or `t_0003/`).
fn place(x: &Export, i: usize, n: &Names, prefix: &str, files: &mut Files) -> Result<(), Error> {
    let r = x.rendered(i)?;
    let passes = [
        ("rgba", r.rgba, &n.rgba, "png"),
        ("depth", r.depth, &n.depth, "png"),
        ("depth_exr", r.depth_exr, &n.depth, "exr"),
        ("normal", r.normal, &n.normal, "png"),
        ("normal_exr", r.normal_exr, &n.normal, "exr"),
        ("mask", r.mask, &n.mask, "png"),
        ("instance", r.instance, &n.instance, "png"),
        ("albedo", r.albedo, &n.albedo, "png"),
    ];
    for (pass, d, rel, ext) in passes {
        if let Some(d) = d {
            files.image_blob(i, pass, &format!("{prefix}{rel}.{ext}"), d)?;
        }
    }
    Ok(())
}

/// Places image `i` and starts its frame entry with `file_path` (with extension) and `transform_matrix`.
fn placed_entry(
    x: &Export,
    i: usize,
    split: &str,
    pad: usize,
    files: &mut Files,
) -> Result<(Names, Map<String, Value>), Error> {
    let img = &x.plan.images[i];
    let n = names(split, &r_name(img, pad));
    place(x, i, &n, "", files)?;
    let mut f = Map::new();
    f.insert("file_path".into(), json!(format!("{}.png", n.rgba)));
    f.insert("transform_matrix".into(), rows(&img.camera.c2w));
    Ok((n, f))
}

/// The intrinsics header shared by every transforms file: `camera_angle_x` and `fl_x/fl_y/cx/cy/w/h`.
fn intrinsics(img: &Image) -> Map<String, Value> {
    let c = &img.camera;
    let mut m = Map::new();
    m.insert("camera_angle_x".into(), json!(c.angle_x()));
    m.insert("fl_x".into(), json!(c.fx));
    m.insert("fl_y".into(), json!(c.fy));
    m.insert("cx".into(), json!(c.cx));
    m.insert("cy".into(), json!(c.cy));
    m.insert("w".into(), json!(c.width));
    m.insert("h".into(), json!(c.height));
    m
}

/// Images of `images` grouped by split (in order of first appearance).
fn by_split(x: &Export, images: &[usize]) -> Vec<(String, Vec<usize>)> {
    let mut v: Vec<(String, Vec<usize>)> = Vec::new();
    for &i in images {
        let name = &x.plan.splits[x.plan.images[i].split].name;
        match v.iter_mut().find(|(n, _)| n == name) {
            Some((_, l)) => l.push(i),
            None => v.push((name.clone(), vec![i])),
        }
    }
    v
}

fn pad(x: &Export, images: &[usize]) -> usize {
    pad_for(images.iter().map(|&i| x.plan.images[i].index + 1).max().unwrap_or(1))
}

/// `dnerf`: transforms_{split}.json with `camera_angle_x` and fl_x…, time-major `./<split>/r_<i>` paths, times
/// in [0, 1]; points3d.ply and an identical fused.ply.
pub fn dnerf(x: &Export, out: &Output, images: &[usize], files: &mut Files) -> Result<(), Error> {
    let pad = pad(x, images);
    let groups = by_split(x, images);
    for (split, list) in &groups {
        let mut frames = Vec::new();
        for &i in list {
            let img = &x.plan.images[i];
            let n = names(split, &r_name(img, pad));
            place(x, i, &n, "", files)?;
            frames.push(json!({
                "file_path": format!("./{}", n.rgba),
                "time": img.time,
                "transform_matrix": rows(&img.camera.c2w),
                "view": img.view,
                "frame": img.frame,
            }));
        }
        let first = x.plan.images[list[0]].time;
        let last = x.plan.images[*list.last().expect("BUG: by_split lists no empty split")].time;
        if first != 0.0 {
            files.warn(format!("split `{split}` starts at time {first}: D-NeRF asserts every split starts at 0"));
        }
        // A one-frame scene is a NeRF-synthetic set (time 0 throughout), which NeRF, 3DGS and nerfstudio read
        // as it is; only D-NeRF's own loader asserts the end, and it is for scenes that move.
        if split == "train" && last != 1.0 && x.plan.frames > 1 {
            files.warn(format!("split `train` ends at time {last}: D-NeRF asserts it ends at exactly 1"));
        }
        let mut doc = intrinsics(&x.plan.images[list[0]]);
        doc.insert("frames".into(), Value::Array(frames));
        files.json(&format!("transforms_{split}.json"), &Value::Object(doc))?;
    }
    let n = init_points(out);
    if n > 0 {
        let ply = x.init_cloud(&x.plan.frames_of(images), n)?;
        files.blob("points3d.ply", ply)?;
        files.blob("fused.ply", ply)?;
    }
    Ok(())
}

/// `nerfstudio`: one transforms.json with fl_x…, `camera_model`, paths with extension, the three
/// `*_filenames` lists, optional depth/mask paths, `ply_file_path`, identity `applied_transform`, `time`.
pub fn nerfstudio(x: &Export, out: &Output, images: &[usize], files: &mut Files) -> Result<(), Error> {
    let pad = pad(x, images);
    let r = &x.manifest.render;
    let (depth, mask) = (r.has_pass(Pass::Depth), r.has_pass(Pass::Mask));
    let mut frames = Vec::new();
    let mut lists: Vec<(String, Vec<String>)> = Vec::new();
    // A path that zooms: nerfstudio reads per-frame focal lengths only when the file gives none for all.
    let c0 = &x.plan.images[images[0]].camera;
    let zooms = images.iter().any(|&i| {
        let c = &x.plan.images[i].camera;
        (c.fx, c.fy) != (c0.fx, c0.fy)
    });
    for (split, list) in by_split(x, images) {
        let mut names_of_split = Vec::new();
        for &i in &list {
            let img = &x.plan.images[i];
            let (n, mut f) = placed_entry(x, i, &split, pad, files)?;
            f.insert("time".into(), json!(img.time));
            if depth {
                f.insert("depth_file_path".into(), json!(format!("{}.png", n.depth)));
            }
            if mask {
                f.insert("mask_path".into(), json!(format!("{}.png", n.mask)));
            }
            f.insert("view".into(), json!(img.view));
            f.insert("frame".into(), json!(img.frame));
            if zooms {
                f.insert("fl_x".into(), json!(img.camera.fx));
                f.insert("fl_y".into(), json!(img.camera.fy));
            }
            frames.push(Value::Object(f));
            names_of_split.push(format!("{}.png", n.rgba));
        }
        lists.push((split, names_of_split));
    }
    let c = &x.plan.images[images[0]].camera;
    let mut doc = Map::new();
    doc.insert("camera_model".into(), json!("OPENCV"));
    for (k, v) in [("fl_x", c.fx), ("fl_y", c.fy), ("cx", c.cx), ("cy", c.cy)] {
        if !(zooms && k.starts_with("fl_")) {
            doc.insert(k.into(), json!(v));
        }
    }
    doc.insert("w".into(), json!(c.width));
    doc.insert("h".into(), json!(c.height));
    doc.insert("applied_transform".into(), json!([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]));
    let [train, val, test] = super::nerfstudio_splits(&lists);
    doc.insert("train_filenames".into(), json!(train));
    doc.insert("val_filenames".into(), json!(val));
    doc.insert("test_filenames".into(), json!(test));
    let n = init_points(out);
    if n > 0 {
        files.blob("points3d.ply", x.init_cloud(&x.plan.frames_of(images), n)?)?;
        doc.insert("ply_file_path".into(), json!("points3d.ply"));
    }
    doc.insert("frames".into(), Value::Array(frames));
    files.json("transforms.json", &Value::Object(doc))
}

/// `instant-ngp`: transforms_{split}.json with fl_x…, `aabb_scale`, and `scale`/`offset` that put the content
/// (over all frames) in NGP's unit cube; `integer_depth_scale` + `depth_path` with a depth pass.
pub fn instant_ngp(x: &Export, out: &Output, images: &[usize], files: &mut Files) -> Result<(), Error> {
    let pad = pad(x, images);
    let (lo, hi) = x.bounds(&x.plan.frames_of(images))?.ok_or(Error::EmptyScene)?;
    let (c, half) = ((lo + hi) * 0.5, ((hi - lo) * 0.5).max_element().max(1e-6));
    // NGP maps p ↦ p·scale + offset (in NeRF axes, before cycling them) into [0, 1]³; keep a 10 % margin.
    let scale = 0.5 / (half as f64 * 1.1);
    let offset = [0.5 - c.x as f64 * scale, 0.5 - c.y as f64 * scale, 0.5 - c.z as f64 * scale];
    let depth = x.manifest.render.has_pass(Pass::Depth);
    for (split, list) in by_split(x, images) {
        let mut frames = Vec::new();
        for &i in &list {
            let img = &x.plan.images[i];
            let (n, mut f) = placed_entry(x, i, &split, pad, files)?;
            if depth {
                f.insert("depth_path".into(), json!(format!("{}.png", n.depth)));
            }
            f.insert("time".into(), json!(img.time));
            frames.push(Value::Object(f));
        }
        let mut doc = intrinsics(&x.plan.images[list[0]]);
        doc.insert("aabb_scale".into(), json!(out.aabb_scale().unwrap_or(1)));
        doc.insert("scale".into(), json!(scale));
        doc.insert("offset".into(), json!(offset));
        if depth {
            // Depth PNGs are millimetres: 0.001 world units per integer step.
            doc.insert("integer_depth_scale".into(), json!(0.001));
        }
        doc.insert("frames".into(), Value::Array(frames));
        files.json(&format!("transforms_{split}.json"), &Value::Object(doc))?;
    }
    Ok(())
}

/// `static-frames`: one NeRF-synthetic dataset per time step, `t_<frame>/transforms_{split}.json` with
/// `<split>/r_<view>` images and its own points3d.ply (what the 6-DoF toolkit does for 8i sequences).
pub fn static_frames(x: &Export, out: &Output, images: &[usize], files: &mut Files) -> Result<(), Error> {
    let frames = x.plan.frames_of(images);
    let views = images.iter().map(|&i| x.plan.images[i].view as usize + 1).max().unwrap_or(1);
    let vpad = pad_for(views);
    let fpad = pad_for(x.plan.frames);
    let n = init_points(out);
    for &f in &frames {
        let prefix = format!("t_{f:0fpad$}/");
        let in_frame: Vec<usize> = images.iter().copied().filter(|&i| x.plan.images[i].frame == f).collect();
        for (split, list) in by_split(x, &in_frame) {
            let mut entries = Vec::new();
            for &i in &list {
                let img = &x.plan.images[i];
                let n = names(&split, &format!("r_{:0vpad$}", img.view));
                place(x, i, &n, &prefix, files)?;
                entries.push(json!({
                    "file_path": format!("./{}", n.rgba),
                    "transform_matrix": rows(&img.camera.c2w),
                    "view": img.view,
                }));
            }
            let mut doc = intrinsics(&x.plan.images[list[0]]);
            doc.insert("time".into(), json!(x.plan.images[list[0]].time));
            doc.insert("frames".into(), Value::Array(entries));
            files.json(&format!("{prefix}transforms_{split}.json"), &Value::Object(doc))?;
        }
        if n > 0 {
            files.blob(&format!("{prefix}points3d.ply"), x.init_cloud(&[f], n)?)?;
        }
    }
    Ok(())
}
