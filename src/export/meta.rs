//! `vvgen/dataset.json` in every dataset: what made the dataset (tool, manifest digest, normalization), the
//! camera model and depth convention, and the split / view / frame / time of every image, so a dataset describes
//! itself without the manifest.
//!
//! It sits in a `vvgen/` folder, not at the root, because consumers scan dataset roots: instant-ngp's directory
//! mode loads every `*.json` there and advances its image index by `json["frames"].size()` for any `frames` key,
//! so a metadata file with a scalar `frames` shifts every later image. No consumer looks into `vvgen/`.

use serde_json::{json, Value};

use super::{Error, Export, Files};
use crate::manifest::output::Output;
use crate::manifest::render::{DepthKind, NormalSpace};

/// Where a dataset's metadata lives, root-relative.
pub const META: &str = "vvgen/dataset.json";

/// Where older vvgen versions wrote it: at the root, where instant-ngp's directory mode misreads it.
pub(super) const OLD_META: &str = "vvgen.json";

pub fn write(x: &Export, name: &str, out: &Output, images: &[usize], files: &mut Files) -> Result<(), Error> {
    let m = x.manifest;
    let sources: Vec<Value> = x
        .scene
        .sources
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let mut v = json!({
                "name": s.name,
                "world_from_source": super::rows(&x.scene.world_from_source(i).as_dmat4()),
            });
            if matches!(s.data, crate::scene::SourceData::MeshSequence(_)) {
                // Nothing relates a vertex of one frame to a vertex of the next.
                v["topology"] =
                    json!("per frame: a mesh sequence may change topology every frame; no temporal correspondence");
            }
            v
        })
        .collect();
    // Image entries: every file of each image, keyed by pass, as placed by the writer.
    let mut entries = Vec::new();
    let cam = images.first().map(|&i| x.plan.images[i].camera);
    for &i in images {
        let img = &x.plan.images[i];
        let c = &img.camera;
        let mut e = json!({
            "split": x.plan.splits[img.split].name,
            "view": img.view,
            "frame": img.frame,
            "time": img.time,
            "index": img.index,
            "files": files.placed.get(&i),
            "c2w": super::rows(&c.c2w),
        });
        // A path that zooms: this image's focal lengths, where they are not the camera model's.
        if cam.is_some_and(|m| (m.fx, m.fy) != (c.fx, c.fy)) {
            e["fl_x"] = json!(c.fx);
            e["fl_y"] = json!(c.fy);
        }
        entries.push(e);
    }
    let mut doc = json!({
        "tool": "vvgen",
        "version": env!("CARGO_PKG_VERSION"),
        "dataset": m.dataset.name(),
        "dataset_version": m.dataset.version,
        "output": name,
        "writer": out.writer().name(),
        "manifest_blake3": x.graph.keying.manifest.hex(),
        "seed": m.dataset.seed,
        "frames": x.plan.frames,
        "sources": sources,
        "camera": cam.map(|c| json!({
            "model": "pinhole",
            "pose": "camera-to-world, OpenGL axes (camera looks down -Z, +Y up), world +Z up",
            "pixel_centers": 0.5,
            "w": c.width, "h": c.height, "fl_x": c.fx, "fl_y": c.fy, "cx": c.cx, "cy": c.cy,
            "near": c.near, "far": c.far,
        })),
        "depth": {
            "kind": match m.render.depth.kind { DepthKind::Planar => "planar z-depth", DepthKind::Ray => "ray distance" },
            "encoding": "16-bit PNG, millimetres (1 world unit = 1 m), 0 = background",
            "exr": m.render.depth.exr.then_some("32-bit float OpenEXR beside each PNG, metres, channel Y, 0 = background"),
        },
        "normal": {
            "space": match m.render.normal.space { NormalSpace::World => "world", NormalSpace::Camera => "camera (OpenGL axes)" },
            "encoding": "8-bit RGB PNG, (n + 1) / 2, 0 = background",
            "exr": m.render.normal.exr.then_some("32-bit float OpenEXR beside each PNG, unit normals in R G B, 0 = background"),
        },
        "rgba": "8-bit sRGB PNG, straight (un-premultiplied) alpha = coverage",
        "images": entries,
    });
    for (k, v) in &files.meta {
        doc[k] = v.clone();
    }
    // Every other file this output wrote: what the next build removes when its plan no longer has them, even
    // with another cache (whose record of this build it would not find).
    doc["written"] = json!(files.files.iter().map(|(f, _)| f.as_str()).collect::<Vec<_>>());
    files.json(META, &doc)
}

/// The files a previous build of the output at `root` wrote, from its `vvgen/dataset.json` (none when there is
/// none, or it is not vvgen's): root-relative, with this file itself.
pub fn previous_files(root: &std::path::Path) -> Vec<String> {
    let Ok(bytes) = std::fs::read(root.join(META)) else { return Vec::new() };
    let Ok(doc) = serde_json::from_slice::<Value>(&bytes) else { return Vec::new() };
    if doc.get("tool").and_then(Value::as_str) != Some("vvgen") {
        return Vec::new();
    }
    let listed = doc.get("written").and_then(Value::as_array).into_iter().flatten();
    // Only plain relative names inside the root: a hand-edited list must not reach outside it.
    let inside = |f: &&str| {
        let p = std::path::Path::new(f);
        p.components().all(|c| matches!(c, std::path::Component::Normal(_)))
    };
    let mut v: Vec<String> = listed.filter_map(Value::as_str).filter(inside).map(str::to_string).collect();
    v.push(META.to_string());
    v
}
