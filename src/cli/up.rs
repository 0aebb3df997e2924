//! The up axis `vvgen new` writes for an asset, with the line that says how it was decided: a format's convention
//! (glTF's and OBJ's +Y, STL's and FBX's +Z), a splatting model's training cameras, or a scan's extents.

use std::path::{Path, PathBuf};

use crate::scene;

/// OBJ's up axis: +Y, the convention of Blender's and most exporters. Not guessed from the extents, which a
/// wide subject (a car, a plate) would get wrong.
pub(super) fn obj_up() -> (&'static str, String) {
    ("y", "up \"y\": OBJ files are +Y up by convention (Blender's exporter and most others)".into())
}

/// An STL file's up axis, and why.
pub(super) fn stl_up() -> (&'static str, String) {
    ("z", "up \"z\": STL files are +Z up, as a 3D printer's bed and Blender's importer take them".into())
}

/// The up axis of a 3D Gaussian splatting file, from the cameras it was trained on: graphdeco-inria's trainer
/// writes them to `cameras.json` in its model folder, two folders above `point_cloud/iteration_N/point_cloud.ply`
/// (each a camera-to-world `rotation` in OpenCV's axes, +Y down). The axis nearest their mean up, when they agree
/// on one (the mean at least half a unit long, its largest part at least 0.7 of it): a COLMAP reconstruction of
/// upright photos is −Y up, which the extents cannot tell from +Y. `None` for other files, or without such cameras.
pub(super) fn cameras_up(s: &scene::PosedScene, ply: &Path) -> Option<(&'static str, String)> {
    let file = training_cameras(s, ply)?;
    let dir = ply.parent()?;
    // Read as a from-file rig reads it: camera-to-world in OpenGL's axes, whose +Y is each camera's up.
    let poses = crate::rig::camera_file(&file).ok()?;
    let mean = poses.iter().map(|c2w| c2w.y_axis.truncate()).sum::<glam::DVec3>() / poses.len() as f64;
    let (k, part) = mean.abs().to_array().into_iter().enumerate().max_by(|a, b| a.1.total_cmp(&b.1))?;
    if !(mean.length() >= 0.5 && part >= 0.7 * mean.length()) {
        return None;
    }
    let axis = match (k, mean[k] > 0.0) {
        (0, true) => "x",
        (0, false) => "-x",
        (1, true) => "y",
        (1, false) => "-y",
        (2, true) => "z",
        _ => "-z",
    };
    let shown = pathdiff(&file, dir);
    Some((
        axis,
        format!(
            "up \"{axis}\" from the {} in {shown} its splats were trained on (their mean up ({:.2}, {:.2}, {:.2}))",
            if poses.len() == 1 { "camera".to_string() } else { format!("{} cameras", poses.len()) },
            mean.x,
            mean.y,
            mean.z
        ),
    ))
}

/// The `cameras.json` a splatting trainer wrote beside the model folder of `ply` (in its folder or up to two
/// above), when `s`, read from it, holds 3D Gaussians.
pub(super) fn training_cameras(s: &scene::PosedScene, ply: &Path) -> Option<PathBuf> {
    if !s.primitives.iter().any(|p| p.gaussians.is_some()) {
        return None;
    }
    ply.parent()?.ancestors().take(3).map(|d| d.join("cameras.json")).find(|f| f.is_file())
}

/// `file` as seen from `dir`, one of its ancestors' children (`../../cameras.json`), for notes.
fn pathdiff(file: &Path, dir: &Path) -> String {
    let up = dir.ancestors().position(|a| file.parent() == Some(a)).unwrap_or(0);
    let name = file.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    format!("{}{name}", "../".repeat(up))
}

/// The up axis of a scan, said with the extents: the thin one of y and z of a flat subject (a terrain, a pond, a
/// table top: under half of each other extent), which lies on the ground; else the taller of y and z (a standing
/// subject). (The taller alone stood flat terrain up as a wall.)
pub(super) fn tallest(s: &scene::PosedScene, path: &Path) -> (&'static str, String) {
    let e = s.bounds().map_or(glam::Vec3::ZERO, |(lo, hi)| hi - lo);
    let name = path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
    let extent = format!("(extent {:.3} × {:.3} × {:.3})", e.x, e.y, e.z);
    let thin = |a: f32, b: f32, c: f32| a < 0.5 * b && a < 0.5 * c;
    let flat = [("y", thin(e.y, e.x, e.z)), ("z", thin(e.z, e.x, e.y))].into_iter().find(|f| f.1);
    if let Some((up, _)) = flat {
        return (up, format!("up \"{up}\" guessed: {name} is flat along {up} {extent}, lying as terrain lies"));
    }
    let up = if e.y >= e.z { "y" } else { "z" };
    (up, format!("up \"{up}\" guessed: the taller of y and z in {name} {extent}"))
}

/// The comment beside `up` in the manifest, from the note [`super::new`] made of how it was decided.
pub(super) fn up_note(note: &str) -> &'static str {
    if note.contains("cameras.json") {
        "the trained splats' cameras' mean up; the world is +Z up"
    } else if note.contains("guessed") {
        "guessed from the first frame's extents: check it"
    } else if note.contains("OBJ") {
        "OBJ's usual up axis; the world is +Z up"
    } else if note.contains("STL") {
        "STL's up axis (a printer's bed is XY); the world is +Z up"
    } else if note.contains("FBX") {
        "FBX is loaded in the world's axes"
    } else if note.contains("as Blender shows it") {
        "Blender's own axes: the world is +Z up, as Blender's"
    } else {
        "glTF's own up axis; the world is +Z up"
    }
}
