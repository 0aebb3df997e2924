//! `colmap`: a COLMAP text model per frame, as 3DGS's and nerfstudio's COLMAP readers parse it:
//! `images/<name>.png` (RGB, background baked in: the COLMAP path does no alpha compositing),
//! `sparse/0/cameras.txt` (one PINHOLE camera), `images.txt` (two lines per image; world→camera quaternion and
//! translation in OpenCV axes) and `points3D.txt` (surface samples of that frame), the same model again in
//! `colmap/sparse/0/` for nerfstudio. A single-frame dataset is
//! written at the root; a dynamic one gets a model per frame under `frame_<NNNN>/`.
//!
//! Images are named by number (`0000.png`, … in split order, the image's id less one): Deformable-3DGS'
//! COLMAP reader takes `int(name)` of every image (`scene/dataset_readers.py` l.136) and stops with a
//! ValueError on any other name; 3DGS, 4DGaussians and nerfstudio take the name as a file name. Which split and
//! view each image is stays in `vvgen/dataset.json`, and beside each model in `train_list.txt`, `val_list.txt`
//! and `test_list.txt`, the names nerfstudio's colmap parser reads its splits from (colmap_dataparser.py
//! `_get_image_indices`): without them it would split by its own interval and train on the test views. It
//! requires every list once one is there, so a missing split borrows its neighbour's
//! ([`super::nerfstudio_splits`], as the nerfstudio writer's lists do).

use std::fmt::Write;

use glam::{DMat3, DQuat};

use super::{init_points, pad_for, Error, Export, Files};
use crate::camera::Camera;
use crate::manifest::output::Output;
use crate::plan::actions::Action;

/// COLMAP's world→camera rotation (Hamilton quaternion `w x y z`, scalar first, `w ≥ 0`) and translation.
pub fn colmap_pose(c: &Camera) -> ([f64; 4], [f64; 3]) {
    let w2c = c.w2c_opencv();
    let q = DQuat::from_mat3(&DMat3::from_mat4(w2c)).normalize();
    let q = if q.w < 0.0 { -q } else { q };
    ([q.w, q.x, q.y, q.z], w2c.w_axis.truncate().to_array())
}

/// Where the model goes, each a copy of the other: `sparse/0` is where 3DGS (and 4DGaussians' and
/// Deformable-3DGS' copies of its reader) look, `colmap/sparse/0` where nerfstudio's colmap parser looks by
/// default (`colmap_path`, colmap_dataparser.py l.88), so both train on the folder as written. The points are the
/// same cache blob, linked twice.
const MODELS: [&str; 2] = ["sparse/0", "colmap/sparse/0"];

pub fn write(x: &Export, out: &Output, images: &[usize], files: &mut Files) -> Result<(), Error> {
    let frames = x.plan.frames_of(images);
    let fpad = pad_for(x.plan.frames);
    let n_points = init_points(out);
    for &f in &frames {
        let prefix = if frames.len() > 1 { format!("frame_{f:0fpad$}/") } else { String::new() };
        let in_frame: Vec<usize> = images.iter().copied().filter(|&i| x.plan.images[i].frame == f).collect();
        let c = &x.plan.images[in_frame[0]].camera;
        let cameras = format!(
            "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n\
             # Number of cameras: 1\n1 PINHOLE {} {} {} {} {} {}\n",
            c.width,
            c.height,
            ryu_f64(c.fx),
            ryu_f64(c.fy),
            ryu_f64(c.cx),
            ryu_f64(c.cy)
        );
        let mut imgs = String::from(
            "# Image list with two lines of data per image:\n#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n\
             #   POINTS2D[] as (X, Y, POINT3D_ID)\n",
        );
        let pad = pad_for(in_frame.len());
        // Each split's image names, in the order the splits first appear.
        let mut lists: Vec<(&str, Vec<String>)> = Vec::new();
        for (id, &i) in in_frame.iter().enumerate() {
            let img = &x.plan.images[i];
            let name = format!("{id:0pad$}.png");
            let split = x.plan.splits[img.split].name.as_str();
            match lists.iter_mut().find(|(s, _)| *s == split) {
                Some((_, names)) => names.push(name.clone()),
                None => lists.push((split, vec![name.clone()])),
            }
            files.image_blob(i, "rgb", &format!("{prefix}images/{name}"), x.opaque_rgb(i)?)?;
            let (q, t) = colmap_pose(&img.camera);
            let _ = writeln!(
                imgs,
                "{} {} {} {} {} {} {} {} 1 {name}\n",
                id + 1,
                ryu_f64(q[0]),
                ryu_f64(q[1]),
                ryu_f64(q[2]),
                ryu_f64(q[3]),
                ryu_f64(t[0]),
                ryu_f64(t[1]),
                ryu_f64(t[2])
            );
        }
        for (split, names) in ["train", "val", "test"].into_iter().zip(super::nerfstudio_splits(&lists)) {
            let text: String = names.iter().map(|n| format!("{n}\n")).collect();
            files.bytes(&format!("{prefix}{split}_list.txt"), text.as_bytes())?;
        }
        let pts = x.blob(&Action::ColmapPoints { frame: f, points: n_points })?;
        for model in MODELS {
            files.bytes(&format!("{prefix}{model}/cameras.txt"), cameras.as_bytes())?;
            files.bytes(&format!("{prefix}{model}/images.txt"), imgs.as_bytes())?;
            files.blob(&format!("{prefix}{model}/points3D.txt"), pts)?;
        }
    }
    Ok(())
}

/// Shortest round-tripping decimal.
fn ryu_f64(v: f64) -> String {
    ryu::Buffer::new().format(v).to_string()
}
