//! Places an output's preview (`preview/`): the pictures its preview actions drew, and the HTML viewer, written
//! here because it links the files the writer just placed.

use super::{Error, Export, Files};
use crate::manifest::output::{Output, Writer};
use crate::plan::actions::{rig_frames, rig_subject_frame, Action};
use crate::preview::{self, sheet, viewer};

/// Writes `preview/` for output `name` over `images`, when the manifest asks for previews.
pub(super) fn place(x: &Export, name: &str, out: &Output, images: &[usize], files: &mut Files) -> Result<(), Error> {
    if !x.manifest.dataset.preview {
        return Ok(());
    }
    let dir = preview::DIR;
    if out.writer() == Writer::PlySequence {
        let strip = Action::PreviewStrip { output: name.to_string() };
        let blobs = x.blobs_of(&strip)?.to_vec();
        let (png, thinned) = match blobs[..] {
            [png, thinned] => (png, thinned),
            _ => return Err(Error::Unplanned("the preview strip's two blobs".into())),
        };
        files.blob(&format!("{dir}/points.png"), png)?;
        let clouds = preview::decode_clouds(&x.store.get(&thinned)?)
            .ok_or_else(|| Error::Unplanned("the viewer's point frames (a damaged cache blob)".into()))?;
        let shown: Vec<viewer::Cloud> = clouds
            .iter()
            .map(|(f, s)| viewer::Cloud {
                frame: *f,
                time: crate::plan::time_of(*f, x.plan.frames),
                positions: &s.positions,
                colors: &s.colors,
            })
            .collect();
        let page = viewer::html(&format!("{} · {name}", x.manifest.dataset.name()), &[], &shown, None);
        files.bytes(&format!("{dir}/index.html"), page.as_bytes())?;
        return files.bytes(&format!("{dir}/three.min.js"), viewer::THREE_JS);
    }
    let plan = x.plan;
    let mut splits: Vec<usize> = images.iter().map(|&i| plan.images[i].split).collect();
    splits.sort_unstable();
    splits.dedup();
    let extras = sheet::extra_passes(x.manifest.render.passes());
    for &s in &splits {
        // Sheets exist where RGBA is rendered.
        let a = Action::PreviewSheet { split: s, extras: extras.clone() };
        if x.graph.id(&a).is_some() {
            files.blob(&format!("{dir}/sheet-{}.png", plan.splits[s].name), x.blob(&a)?)?;
        }
    }
    files.blob(&format!("{dir}/rig.png"), x.blob(&Action::PreviewRig { splits: splits.clone() })?)?;

    let frames = rig_frames(plan, &splits);
    let bounds = x.bounds(&frames)?;
    let subject = vec![rig_subject_frame(plan, &splits)];
    let cloud = x.store.get(&x.blob(&Action::InitCloud { frames: subject, points: preview::POINTS })?)?;
    let samples = preview::cloud(&cloud).map_err(|e| Error::Unplanned(format!("preview samples: {e}")))?;
    let mut shown = Vec::with_capacity(images.len());
    for &i in images {
        // The image a trainer reads: RGBA, else the opaque RGB of COLMAP and DyNeRF layouts.
        let placed = files.placed.get(&i);
        if let Some(path) = placed.and_then(|p| p.get("rgba").or_else(|| p.get("rgb")).or_else(|| p.values().next())) {
            shown.push((i, path.clone()));
        }
    }
    let list: Vec<viewer::ViewerImage> = shown
        .iter()
        .map(|(i, path)| {
            let img = &plan.images[*i];
            viewer::ViewerImage {
                split: &plan.splits[img.split].name,
                split_index: img.split,
                view: img.view,
                frame: img.frame,
                time: img.time,
                camera: &img.camera,
                path,
            }
        })
        .collect();
    let title = format!("{} · {name}", x.manifest.dataset.name());
    let subject = rig_subject_frame(plan, &splits);
    let cloud = viewer::Cloud {
        frame: subject,
        time: crate::plan::time_of(subject, plan.frames),
        positions: &samples.positions,
        colors: &samples.colors,
    };
    let page = viewer::html(&title, &list, &[cloud], bounds);
    files.bytes(&format!("{dir}/index.html"), page.as_bytes())?;
    files.bytes(&format!("{dir}/three.min.js"), viewer::THREE_JS)
}
