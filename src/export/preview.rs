//! Places an output's preview (`preview/`): the pictures its preview actions drew, and the HTML viewer, written
//! here because it links the files the writer just placed.

use super::{Error, Export, Files};
use crate::manifest::output::{Output, Writer};
use crate::plan::actions::{rig_frames, rig_subject_frame, splits_of, Action};
use crate::preview::{self, viewer, DIR};

/// Writes `preview/` for output `name` over `images`, when the manifest asks for previews.
pub(super) fn place(x: &Export, name: &str, out: &Output, images: &[usize], files: &mut Files) -> Result<(), Error> {
    if !x.manifest.dataset.preview {
        return Ok(());
    }
    let title = format!("{} · {name}", x.manifest.dataset.name());
    let load = loading(out.writer());
    let page = if out.writer() == Writer::PlySequence {
        points(x, name, &title, load, files)?
    } else {
        pictures(x, images, &title, load, files)?
    };
    files.bytes(&format!("{DIR}/index.html"), page.as_bytes())?;
    files.bytes(&format!("{DIR}/three.min.js"), viewer::THREE_JS)
}

/// How the writer's consumers load this folder (DIR), as the page says it: the step a user gets wrong first.
fn loading(writer: Writer) -> &'static str {
    match writer {
        Writer::Dnerf => {
            "Load DIR with D-NeRF, K-Planes (its path must contain \"dnerf\"), 3DGS, 4DGaussians or Deformable-3DGS \
             (-s DIR), or nerfstudio: ns-train … dnerf-data --data DIR."
        }
        Writer::Nerfstudio => "Load with nerfstudio: ns-train nerfacto --data DIR (transforms.json).",
        Writer::InstantNgp => {
            "Load with instant-ngp: ./instant-ngp DIR/transforms_train.json (the folder itself trains on every split)."
        }
        Writer::StaticFrames => {
            "Each t_NNNN/ is one static NeRF-synthetic set (3DGS -s DIR/t_NNNN, instant-ngp, nerfstudio)."
        }
        Writer::Colmap => {
            "Load with 3DGS (-s DIR, or DIR/frame_NNNN when the scene moves; it reads sparse/0) or nerfstudio \
             (ns-train … colmap --data DIR; it reads colmap/sparse/0, the same model, and the splits from \
             train_list.txt, val_list.txt and test_list.txt)."
        }
        Writer::Dynerf => {
            "Load DIR with K-Planes (DyNeRF config), 4DGaussians (dynerf) or Deformable-3DGS (plenoptic)."
        }
        Writer::PlySequence => "One PLY per frame: Open3D, plyfile, trimesh and the codecs' tools read them.",
    }
}

/// A point-cloud output's strip; returns its viewer page (the frames thinned by the strip action).
fn points(x: &Export, name: &str, title: &str, load: &str, files: &mut Files) -> Result<String, Error> {
    let strip = Action::PreviewStrip { output: name.to_string() };
    let (png, thinned) = match x.blobs_of(&strip)? {
        &[png, thinned] => (png, thinned),
        _ => return Err(Error::Unplanned("the preview strip's two blobs".into())),
    };
    files.blob(&format!("{DIR}/points.png"), png)?;
    let clouds = preview::decode_clouds(&x.store.get(&thinned)?).ok_or(preview::Error::Thinned)?;
    let shown: Vec<viewer::Cloud> = clouds
        .iter()
        .map(|(f, s)| viewer::Cloud {
            frame: *f,
            time: crate::plan::time_of(*f, x.plan.frames),
            positions: &s.positions,
            colors: &s.colors,
        })
        .collect();
    Ok(viewer::html(title, load, &[], &shown, None, Some(x.plan.frames)))
}

/// An image output's contact sheets and rig plot; returns its viewer page (its cameras, linking the images the
/// writer placed, around the subject's samples).
fn pictures(x: &Export, images: &[usize], title: &str, load: &str, files: &mut Files) -> Result<String, Error> {
    let plan = x.plan;
    let splits = splits_of(plan, images);
    let extras = crate::plan::preview::extra_passes(x.manifest.render.passes());
    for &s in &splits {
        // Sheets exist where RGBA is rendered.
        let a = Action::PreviewSheet { split: s, extras: extras.clone() };
        if x.graph.id(&a).is_some() {
            files.blob(&format!("{DIR}/sheet-{}.png", plan.splits[s].name), x.blob(&a)?)?;
        }
    }
    files.blob(&format!("{DIR}/rig.png"), x.blob(&Action::PreviewRig { splits: splits.clone() })?)?;

    let bounds = x.bounds(&rig_frames(plan, &splits))?;
    let subject = rig_subject_frame(plan, &splits);
    let cloud = x.store.get(&x.blob(&Action::InitCloud { frames: vec![subject], points: preview::POINTS })?)?;
    let samples = preview::cloud(&cloud)?;
    let list: Vec<viewer::ViewerImage> = images
        .iter()
        .filter_map(|&i| {
            // The image a trainer reads: RGBA, else the opaque RGB of the COLMAP and DyNeRF layouts.
            let placed = files.placed.get(&i)?;
            let path = placed.get("rgba").or_else(|| placed.get("rgb")).or_else(|| placed.values().next())?;
            let img = &plan.images[i];
            Some(viewer::ViewerImage {
                split: &plan.splits[img.split].name,
                split_index: img.split,
                view: img.view,
                frame: img.frame,
                time: img.time,
                camera: &img.camera,
                path,
            })
        })
        .collect();
    let cloud = viewer::Cloud {
        frame: subject,
        time: crate::plan::time_of(subject, plan.frames),
        positions: &samples.positions,
        colors: &samples.colors,
    };
    Ok(viewer::html(title, load, &list, &[cloud], bounds, None))
}
