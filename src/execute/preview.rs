//! Preview actions: contact sheets, rig plots and point-cloud strips, drawn from their inputs' blobs (renders,
//! bounds, samples, point frames) by [`crate::preview`], in parallel.

use super::{Error, Inputs, Made};
use crate::cache::Digest;
use crate::plan::actions::{rig_subject_frame, Action};
use crate::plan::graph::{ActionId, Graph};
use crate::preview::{self, rig_plot, sheet, strip};

/// Runs the preview actions `ids`; their inputs are in `blobs`.
pub(super) fn run(
    g: &Graph,
    x: &Inputs,
    blobs: &[Option<Vec<Digest>>],
    ids: &[ActionId],
    done: &(dyn Fn() + Sync),
) -> Result<Made, Error> {
    use rayon::prelude::*;
    ids.par_iter()
        .map(|&id| {
            let stored = x.store(g, id, &make(g, x, blobs, id)?)?;
            done();
            Ok((id, stored))
        })
        .collect()
}

/// The blobs of preview action `id`: its picture (and a point sequence's thinned frames for the viewer).
fn make(g: &Graph, x: &Inputs, blobs: &[Option<Vec<Digest>>], id: ActionId) -> Result<Vec<Vec<u8>>, Error> {
    let n = g.node(id);
    let failed = |source: preview::Error| Error::Preview { action: n.label.clone(), source };
    let plan = g.keying.plan;
    let dataset = &g.keying.dataset;
    match &n.action {
        Action::PreviewSheet { split, extras } => {
            let layout = crate::plan::preview::layout(plan, *split);
            let per = 1 + extras.len();
            let mut cells = Vec::with_capacity(layout.images.len());
            for (k, &i) in layout.images.iter().enumerate() {
                let img = &plan.images[i];
                let mut cell = sheet::Cell {
                    view: img.view,
                    frame: img.frame,
                    time: img.time,
                    rgba: x.read(g, blobs, n.deps[k * per], 0)?,
                    depth: None,
                    mask: None,
                };
                for (j, pass) in extras.iter().enumerate() {
                    let bytes = Some(x.read(g, blobs, n.deps[k * per + 1 + j], 0)?);
                    match pass {
                        crate::manifest::render::Pass::Depth => cell.depth = bytes,
                        _ => cell.mask = bytes,
                    }
                }
                cells.push(cell);
            }
            let sp = &plan.splits[*split];
            let title = format!("{dataset} · split `{}` · {} images, {} shown", sp.name, sp.images.len(), cells.len());
            Ok(vec![sheet::draw(&title, &cells, layout.columns).map_err(|e| failed(e.into()))?])
        }
        Action::PreviewRig { splits } => {
            let bounds = super::decode_bounds(&x.read(g, blobs, n.deps[0], 0)?);
            let samples = preview::cloud(&x.read(g, blobs, n.deps[1], 0)?).map_err(failed)?;
            let cams: Vec<rig_plot::SplitCameras> = splits
                .iter()
                .map(|&s| {
                    let sp = &plan.splits[s];
                    let base = sp.images.first().map(|&i| plan.images[i].camera);
                    let cameras = match base {
                        Some(c) => sp.poses.iter().map(|p| crate::camera::Camera { c2w: *p, ..c }).collect(),
                        None => Vec::new(),
                    };
                    rig_plot::SplitCameras { name: &sp.name, cameras }
                })
                .collect();
            let subject = rig_plot::Subject {
                points: &samples.positions,
                colors: &samples.colors,
                frame: rig_subject_frame(plan, splits),
                bounds,
            };
            Ok(vec![rig_plot::draw(&format!("{dataset} · cameras and subject"), &cams, &subject)])
        }
        Action::PreviewStrip { output } => {
            // The deps are the point frames of `point_frames`, in order.
            let read: Vec<usize> = preview::point_frames(plan.frames);
            let ply = |f: usize| match read.iter().position(|&r| r == f) {
                Some(k) => x.read(g, blobs, n.deps[k], 0),
                None => unreachable!("the strip's and the viewer's frames are its deps"),
            };
            let frames = preview::strip_frames(plan.frames);
            let plys = frames.iter().map(|&f| ply(f)).collect::<Result<Vec<_>, _>>()?;
            let title = format!("{dataset} · output `{output}` · {} frames, {} shown", plan.frames, frames.len());
            let png = strip::draw(&title, &frames, &plys).map_err(|e| failed(e.into()))?;
            let mut clouds = Vec::new();
            for f in preview::viewer_frames(plan.frames) {
                let thin =
                    preview::thin(&ply(f)?).map_err(|source| failed(preview::Error::Frame { frame: f, source }))?;
                clouds.push((f, thin));
            }
            Ok(vec![png, preview::encode_clouds(&clouds)])
        }
        _ => unreachable!("not a preview action"),
    }
}
