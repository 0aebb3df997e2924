//! Whether each planned image sees the whole subject, and a warning per split whose cameras crop it: how many
//! views, the worst one, and the setting that keeps it whole. `check` and `build` both ask, so a dataset whose
//! every view cuts the subject off never builds silently.
//!
//! The subject is every source but ground planes (which reach past every image by design), posed at each
//! image's frame. A view crops it when some vertex or point is outside the image or behind the camera; the
//! share outside is counted over vertices. A frame's bounding box inside the frustum (its eight corners, the
//! frustum being convex) settles a view without looking at its vertices.
//!
//! The same pass measures how far 4DGaussians' and Deformable-3DGS' Blender readers misplace the subject in
//! each view (see [`Misread`]), since only the posed vertices can say it in pixels.

use std::collections::BTreeMap;

use glam::{DMat4, DVec3, Vec3};
use rayon::prelude::*;

use super::Plan;
use crate::manifest::{framing, transform::FRAME_MARGIN, Manifest, Writer};
use crate::scene::{self, Poser, Scene};

/// One view that crops the subject.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crop {
    /// The image (index into [`Plan::images`]).
    pub image: usize,
    /// The share of the subject's vertices outside the image, in (0, 1].
    pub outside: f64,
}

/// How far 4DGaussians' and Deformable-3DGS' Blender readers (`readCamerasFromTransforms`) draw the subject
/// from where it is in one image.
///
/// Both take `T = -inv(c2w)[:3, 3]` after flipping the camera's axes (4DGaussians
/// `scene/dataset_readers.py` l.275, Deformable-3DGS l.238) where 3DGS takes `diag(1, -1, -1) · inv(c2w)[:3, 3]`:
/// the rotation agrees and the x translation has the wrong sign. Every point then sits `2·t_x` to the side in
/// camera space, `2·fx·|t_x| / z` pixels in the image at depth `z`; `t_x` is zero exactly when the camera's
/// optical axis and up vector span a plane through the world origin (any camera aimed at the origin).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Misread {
    /// The image (index into [`Plan::images`]).
    pub image: usize,
    /// The shift averaged over the subject's vertices in front of the camera, pixels.
    pub mean_px: f64,
    /// The shift of the nearest vertex, pixels.
    pub max_px: f64,
}

/// A shift below this is not reported (an eighth of a pixel).
const MISREAD_PX: f64 = 0.125;

/// What [`measure`] found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Coverage {
    /// The images that crop the subject, in image order.
    pub crops: Vec<Crop>,
    /// The images measured.
    pub measured: usize,
    /// How far from the origin the subject reaches over the measured frames, world units.
    pub reach: f64,
    /// The images of `dnerf` outputs whose subject 4DGaussians and Deformable-3DGS would draw at least an eighth
    /// of a pixel off, in image order.
    pub misread: Vec<Misread>,
    /// Each measured image and how far across the subject's box reaches in it, pixels (clipped to the image;
    /// infinite when the box reaches behind the camera), in image order.
    pub spans: Vec<(usize, f64)>,
    /// The diagonal of each measured frame's subject box, in frame order.
    pub frame_sizes: Vec<f64>,
    /// The diagonal of the box of every measured frame: against [`Coverage::frame_sizes`], how far the subject
    /// moves for its size.
    pub extent: f64,
}

/// A subject whose box spans under this share of the image's shorter side in half a split's views is said to be
/// small: a tenth, 40 pixels of a 400² image.
const SMALL: f64 = 0.1;

/// Measures `images` (all when `None`) of `m`'s plan, posing each frame they show once, frames in parallel; the
/// misread poses only of the images a `dnerf` output writes (the readers that misread them read only those).
pub fn measure(m: &Manifest, scene: &Scene, plan: &Plan, images: Option<&[usize]>) -> Result<Coverage, scene::Error> {
    let all: Vec<usize>;
    let images = match images {
        Some(i) => i,
        None => {
            all = (0..plan.images.len()).collect();
            &all
        }
    };
    let mut by_frame: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for &i in images {
        by_frame.entry(plan.images[i].frame).or_default().push(i);
    }
    let subject: Vec<usize> = (0..scene.sources.len()).filter(|&i| scene.sources[i].ground.is_none()).collect();
    let mut dnerf = vec![false; plan.images.len()];
    // A split the plan lacks was reported when the plan was made.
    for out in m.outputs.values().filter(|o| o.writer() == Writer::Dnerf) {
        for i in plan.images_of(out).unwrap_or_default() {
            dnerf[i] = true;
        }
    }
    type Found = (Vec<Crop>, Vec<Misread>, Vec<(usize, f64)>, f64, (Vec3, Vec3));
    let per_frame: Vec<Result<Found, scene::Error>> = by_frame
        .into_par_iter()
        .map_init(Poser::default, |poser, (frame, list)| {
            let mut points: Vec<Vec3> = Vec::new();
            for &s in &subject {
                for p in &scene.pose_source(s, frame, poser)?.primitives {
                    points.extend_from_slice(&p.positions);
                }
            }
            let reach = points.iter().map(|p| p.as_dvec3().length_squared()).fold(0.0, f64::max).sqrt();
            let bounds = points.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| (l.min(*p), h.max(*p)));
            let (mut crops, mut misreads, mut spans) = (Vec::new(), Vec::new(), Vec::new());
            for i in list {
                let w2c = plan.images[i].camera.w2c();
                crops.extend(crop(plan, i, &w2c, &points, bounds));
                misreads.extend(dnerf[i].then(|| misread(plan, i, &w2c, &points)).flatten());
                spans.extend((!points.is_empty()).then(|| (i, span(&plan.images[i].camera, &w2c, bounds))));
            }
            Ok((crops, misreads, spans, reach, bounds))
        })
        .collect();
    let mut out = Coverage { measured: images.len(), ..Coverage::default() };
    let mut all = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for r in per_frame {
        let (crops, misread, spans, reach, (lo, hi)) = r?;
        out.crops.extend(crops);
        out.misread.extend(misread);
        out.spans.extend(spans);
        out.reach = out.reach.max(reach);
        if lo.cmple(hi).all() {
            out.frame_sizes.push(f64::from((hi - lo).length()));
            all = (all.0.min(lo), all.1.max(hi));
        }
    }
    if all.0.cmple(all.1).all() {
        out.extent = f64::from((all.1 - all.0).length());
    }
    out.crops.sort_by_key(|c| c.image);
    out.misread.sort_by_key(|m| m.image);
    out.spans.sort_by_key(|s| s.0);
    Ok(out)
}

/// How far across, in pixels, the box `(lo, hi)` reaches in the image of `cam` (whose world-to-camera is `w2c`):
/// the larger side of its eight corners' projections, clipped to the image; infinite when a corner is behind the
/// camera (the box is then all around it).
fn span(cam: &crate::camera::Camera, w2c: &DMat4, (lo, hi): (Vec3, Vec3)) -> f64 {
    let (mut u, mut v) = ((f64::INFINITY, f64::NEG_INFINITY), (f64::INFINITY, f64::NEG_INFINITY));
    for c in corners(lo, hi) {
        let p = w2c.transform_point3(c);
        let z = -p.z;
        if z <= 0.0 {
            return f64::INFINITY;
        }
        let (x, y) = (cam.cx + cam.fx * p.x / z, cam.cy - cam.fy * p.y / z);
        u = (u.0.min(x), u.1.max(x));
        v = (v.0.min(y), v.1.max(y));
    }
    let (w, h) = (f64::from(cam.width), f64::from(cam.height));
    (u.1.min(w) - u.0.max(0.0)).max(v.1.min(h) - v.0.max(0.0)).max(0.0)
}

/// A warning when, in half of some split's measured views, the subject spans under [`SMALL`] of the image: in
/// which splits, how small, why (a motion many times the subject's size, all of which `fit = "frame"` keeps in
/// every view), and what makes it larger. Such a dataset builds, and a trainer sees a few pixels of subject.
pub fn small_warnings(m: &Manifest, plan: &Plan, c: &Coverage) -> Vec<String> {
    let mut per_split: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
    for &(i, px) in &c.spans {
        per_split.entry(plan.images[i].split).or_default().push(px);
    }
    let (mut splits, mut medians, mut size) = (Vec::new(), Vec::new(), None);
    for (s, mut spans) in per_split {
        let Some(cam) = plan.splits[s].images.first().map(|&i| &plan.images[i].camera) else { continue };
        spans.sort_by(f64::total_cmp);
        let median = spans[spans.len() / 2];
        if median < SMALL * f64::from(cam.width.min(cam.height)) {
            splits.push(format!("`{}`", plan.splits[s].name));
            medians.push(median);
            size.get_or_insert((cam.width, cam.height));
        }
    }
    let Some((w, h)) = size else { return Vec::new() };
    let px = |v: f64| format!("{v:.0}");
    let (lo, hi) = medians.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &v| (l.min(v), h.max(v)));
    let across = if px(lo) == px(hi) { px(lo) } else { format!("{}–{}", px(lo), px(hi)) };
    // How far the subject moves for its size: its whole box against a typical frame's.
    let mut frames = c.frame_sizes.clone();
    frames.sort_by(f64::total_cmp);
    let typical = frames.get(frames.len() / 2).copied().unwrap_or(0.0);
    let moves = (typical > 0.0 && c.extent >= 3.0 * typical).then(|| c.extent / typical);
    let frame_fit = m.transform.fit().is_some_and(|f| f.frame);
    let (why, fix) = match (moves, frame_fit) {
        (Some(k), true) => (
            format!(
                ": it moves across {k:.0}× its own size, and fit = \"frame\" keeps all of its motion in every \
                 view"
            ),
            "take a shorter stretch of the clip (`frames`), play the motion in place, or raise `resolution`",
        ),
        (_, false) => (String::new(), "[transform] fit = \"frame\" sizes it for the cameras"),
        (None, true) => (String::new(), "bring the rig's cameras closer, or raise `resolution`"),
    };
    vec![format!(
        "the subject is small in {}: about {across} px across in half of the views ({w}×{h} images){why}; {fix}",
        splits.join(", ")
    )]
}

/// [`Misread`] of image `i` showing `points`, when at least [`MISREAD_PX`].
fn misread(plan: &Plan, i: usize, w2c: &DMat4, points: &[Vec3]) -> Option<Misread> {
    let cam = &plan.images[i].camera;
    let per_depth = 2.0 * cam.fx * w2c.w_axis.x.abs();
    // Under this, no vertex beyond the near plane can shift by MISREAD_PX: skip the vertices (aimed rigs land
    // here, t_x being rounding noise).
    if per_depth < MISREAD_PX * cam.near {
        return None;
    }
    let (mut sum, mut n, mut max) = (0.0, 0usize, 0.0f64);
    for p in points {
        let z = -w2c.transform_point3(p.as_dvec3()).z;
        if z > 0.0 {
            let px = per_depth / z;
            sum += px;
            n += 1;
            max = max.max(px);
        }
    }
    (n > 0 && max >= MISREAD_PX).then(|| Misread { image: i, mean_px: sum / n as f64, max_px: max })
}

/// Whether image `i` (whose world-to-camera is `w2c`) crops `points` (whose bounds are `(lo, hi)`, found once per
/// frame), and by how much.
fn crop(plan: &Plan, i: usize, w2c: &DMat4, points: &[Vec3], (lo, hi): (Vec3, Vec3)) -> Option<Crop> {
    if points.is_empty() {
        return None;
    }
    let cam = &plan.images[i].camera;
    if corners(lo, hi).all(|c| cam.shows(w2c, c)) {
        return None;
    }
    let outside = points.iter().filter(|p| !cam.shows(w2c, p.as_dvec3())).count();
    (outside > 0).then(|| Crop { image: i, outside: outside as f64 / points.len() as f64 })
}

/// The eight corners of the box `(lo, hi)`.
fn corners(lo: Vec3, hi: Vec3) -> impl Iterator<Item = DVec3> {
    (0..8).map(move |k| {
        DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x } as f64,
            if k & 2 == 0 { lo.y } else { hi.y } as f64,
            if k & 4 == 0 { lo.z } else { hi.z } as f64,
        )
    })
}

/// One warning per split whose views crop the subject: how many, the worst, and what keeps it whole.
pub fn warnings(m: &Manifest, plan: &Plan, c: &Coverage) -> Vec<String> {
    let mut per_split: BTreeMap<usize, Vec<Crop>> = BTreeMap::new();
    for crop in &c.crops {
        per_split.entry(plan.images[crop.image].split).or_default().push(*crop);
    }
    let frame_fit = m.transform.fit().is_some_and(|f| f.frame);
    per_split
        .into_iter()
        .map(|(s, crops)| {
            let split = &plan.splits[s];
            let worst = crops.iter().max_by(|a, b| a.outside.total_cmp(&b.outside)).expect("a split listed has crops");
            let img = &plan.images[worst.image];
            let share = if worst.outside < 0.01 { "under 1 %".to_string() } else { format!("{:.0} %", worst.outside * 100.0) };
            let views: std::collections::BTreeSet<u32> = crops.iter().map(|c| plan.images[c.image].view).collect();
            let rig_name = m.splits.get(&split.name).map(|s| s.rig()).unwrap_or_default();
            let radius = m
                .rigs
                .get(rig_name)
                .and_then(|rig| framing::radius_keeping(m, rig, c.reach, FRAME_MARGIN))
                .map(|r| format!("rig `{rig_name}` radius = {:.1}", (r * 10.0).ceil() / 10.0));
            let fix = match (frame_fit, radius) {
                (false, Some(r)) => format!("[transform] fit = \"frame\" or {r} keeps it whole"),
                (false, None) => "[transform] fit = \"frame\" sizes the subject for the cameras".to_string(),
                (true, Some(r)) => format!("{r} keeps it whole"),
                (true, None) => format!("these cameras are not sized by fit = \"frame\": move rig `{rig_name}`'s cameras back"),
            };
            format!(
                "{} of {} `{}` images crop the subject ({} of {} views; worst: view {}, frame {}, {share} of its vertices \
                 outside the image); {fix}",
                crops.len(),
                split.images.len(),
                split.name,
                views.len(),
                split.poses.len(),
                img.view,
                img.frame,
            )
        })
        .collect()
}

/// One warning per `dnerf` output whose images 4DGaussians and Deformable-3DGS would misread (see [`Misread`]):
/// how many, by how much, the worst, and what makes them exact. Only the measured images count (see
/// [`measure`]).
pub fn misread_warnings(m: &Manifest, plan: &Plan, c: &Coverage) -> Vec<String> {
    if c.misread.is_empty() {
        return Vec::new();
    }
    let by_image: BTreeMap<usize, &Misread> = c.misread.iter().map(|r| (r.image, r)).collect();
    let mut said = Vec::new();
    for (name, out) in &m.outputs {
        if out.writer() != Writer::Dnerf {
            continue;
        }
        // A split the plan lacks was reported when the plan was made.
        let Ok(images) = plan.images_of(out) else { continue };
        let hit: Vec<&Misread> = images.iter().filter_map(|i| by_image.get(i).copied()).collect();
        let Some(worst) = hit.iter().max_by(|a, b| a.max_px.total_cmp(&b.max_px)) else { continue };
        let mean = hit.iter().map(|r| r.mean_px).sum::<f64>() / hit.len() as f64;
        let img = &plan.images[worst.image];
        let split = &plan.splits[img.split].name;
        let rigs: std::collections::BTreeSet<&str> = hit
            .iter()
            .filter_map(|r| m.splits.get(&plan.splits[plan.images[r.image].split].name).map(|s| s.rig()))
            .collect();
        let rigs: Vec<String> = rigs.into_iter().map(|r| format!("`{r}`")).collect();
        said.push(format!(
            "output `{name}` (dnerf): 4DGaussians and Deformable-3DGS draw the subject up to {:.1} px off ({:.1} px \
             on average) in {} of {} images (worst: `{split}` view {}, frame {}): their Blender readers negate the \
             camera's x translation (T = -inv(c2w)[:3, 3] after the axis flip), which is exact only for cameras aimed \
             through the world origin; aim rig {} at target = [0, 0, 0] without target jitter, with the subject \
             there ([transform] fit = \"frame\" centres it)",
            worst.max_px,
            mean,
            hit.len(),
            images.len(),
            img.view,
            img.frame,
            rigs.join(", "),
        ));
    }
    said
}
