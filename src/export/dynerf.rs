//! `dynerf`: the DyNeRF / LLFF layout K-Planes, 4DGaussians and Deformable-3DGS read: `poses_bounds.npy`
//! (one row of 17 per camera: the 3×5 matrix [down, right, back, centre, (H, W, focal)] then near, far),
//! `camNN.mp4` (H.264, [`crate::execute::video`]), the same frames as PNG in `frames/camNN/NNNN.png` and
//! `camNN/images/NNNN.png` (RGB, background baked in), and the init cloud as `points3D_downsample2.ply` and
//! `points3D.ply`. Camera 00 is the one the loaders hold out for testing: a split named `test` goes first.
//!
//! A path split (a moving camera) has no place in `poses_bounds.npy`, which holds one fixed pose per video: it is
//! written beside the cameras, where no loader looks, as `path_SPLIT.mp4`, its frames `path_SPLIT/NNNN.png`, and
//! its cameras `path_SPLIT.json` in nerfstudio's camera-path format (row-major OpenGL `camera_to_world` per
//! frame, vertical `fov` in degrees, `fps`, `seconds`, and `render_time`, the frame's time 0 … 1), the ground
//! truth a trained model's render along that path is scored against.

use glam::{DMat4, DVec3, Vec3};

use super::{init_points, Error, Export, Files};
use crate::manifest::output::Output;
use crate::plan::actions::Action;

pub fn write(x: &Export, out: &Output, images: &[usize], files: &mut Files) -> Result<(), Error> {
    // Cameras: split by split, `test` first; the plan checked each split sees every frame (synchronized video).
    let mut splits: Vec<usize> = Vec::new();
    for &i in images {
        let s = x.plan.images[i].split;
        if !splits.contains(&s) {
            splits.push(s);
        }
    }
    let (paths, mut splits): (Vec<usize>, Vec<usize>) = splits.into_iter().partition(|&s| x.plan.splits[s].moving);
    for &s in &paths {
        write_path(x, s, files)?;
    }
    let fixed: Vec<usize> = images.iter().copied().filter(|&i| !x.plan.splits[x.plan.images[i].split].moving).collect();
    let (images, frames) = (fixed.as_slice(), x.plan.frames_of(&fixed));
    splits.sort_by_key(|&s| x.plan.splits[s].name != "test");
    let mut cams: Vec<(usize, u32)> = Vec::new();
    for &s in &splits {
        let sp = &x.plan.splits[s];
        cams.extend((0..sp.poses.len() as u32).map(|v| (s, v)));
    }
    let c0 = &x.plan.images[images[0]].camera;
    let bounds = x.bounds(&frames)?;
    let mut rows: Vec<f64> = Vec::new();
    for (ci, &(s, v)) in cams.iter().enumerate() {
        let c2w = x.plan.splits[s].poses[v as usize];
        let (near, far) = depth_range(&c2w, bounds, c0.near);
        rows.extend(llff_row(&c2w, c0.height, c0.width, c0.fx));
        rows.extend([near, far]);
        for (fi, &f) in frames.iter().enumerate() {
            let img = x.plan.splits[s]
                .images
                .iter()
                .copied()
                .find(|&i| x.plan.images[i].frame == f && x.plan.images[i].view == v)
                .ok_or_else(|| Error::Unplanned(format!("image of camera {v} at frame {f}")))?;
            // The same frame where each loader looks: Deformable-3DGS lists frames/<cam>/, 4DGaussians reads
            // camNN/images/ (and extracts them from the video only when that folder is missing).
            let rgb = x.opaque_rgb(img)?;
            files.image_blob(img, "rgb", &format!("frames/cam{ci:02}/{fi:04}.png"), rgb)?;
            files.blob(&format!("cam{ci:02}/images/{fi:04}.png"), rgb)?;
        }
        // K-Planes decodes camNN.mp4 (sorted, cam00 is its test camera); 4DGaussians asserts they exist.
        files.blob(&format!("cam{ci:02}.mp4"), x.blob(&Action::Video { split: s, view: v })?)?;
    }
    files.bytes("poses_bounds.npy", &npy_f64(&rows, cams.len(), 17))?;
    let n = init_points(out);
    if n > 0 {
        // 4DGaussians reads points3D_downsample2.ply, Deformable-3DGS points3D.ply (else it invents 100k
        // random points and writes them into the dataset).
        let cloud = x.init_cloud(&frames, n)?;
        files.blob("points3D_downsample2.ply", cloud)?;
        files.blob("points3D.ply", cloud)?;
    }
    Ok(())
}

/// A path split as one video, its frames, and its cameras in nerfstudio's camera-path format.
fn write_path(x: &Export, s: usize, files: &mut Files) -> Result<(), Error> {
    let sp = &x.plan.splits[s];
    let mut list = sp.images.clone();
    list.sort_by_key(|&i| x.plan.images[i].frame);
    let fps = x.graph.keying.video_fps_milli as f64 / 1000.0;
    let mut cams = Vec::with_capacity(list.len());
    for (fi, &i) in list.iter().enumerate() {
        let img = &x.plan.images[i];
        files.image_blob(i, "rgb", &format!("path_{}/{fi:04}.png", sp.name), x.opaque_rgb(i)?)?;
        let c = &img.camera;
        cams.push(serde_json::json!({
            "camera_to_world": c.c2w.transpose().to_cols_array().to_vec(),
            "fov": (2.0 * (c.height as f64 / 2.0 / c.fy).atan()).to_degrees(),
            "aspect": c.width as f64 / c.height as f64,
            "render_time": img.time,
        }));
    }
    let c = &x.plan.images[list[0]].camera;
    let doc = serde_json::json!({
        "camera_type": "perspective",
        "render_height": c.height,
        "render_width": c.width,
        "fps": fps,
        "seconds": list.len() as f64 / fps,
        "camera_path": cams,
    });
    files.json(&format!("path_{}.json", sp.name), &doc)?;
    files.blob(&format!("path_{}.mp4", sp.name), x.blob(&Action::Video { split: s, view: 0 })?)
}

/// The 15 numbers of an LLFF pose from an OpenGL camera-to-world (columns right, up, back, centre): the 3×5
/// matrix [−up, right, back, centre, (H, W, f)], row-major.
pub fn llff_row(c2w: &DMat4, h: u32, w: u32, f: f64) -> [f64; 15] {
    let (r, u, b, c) = (c2w.x_axis.truncate(), c2w.y_axis.truncate(), c2w.z_axis.truncate(), c2w.w_axis.truncate());
    let cols = [-u, r, b, c, DVec3::new(h as f64, w as f64, f)];
    let mut out = [0.0; 15];
    for row in 0..3 {
        for (k, col) in cols.iter().enumerate() {
            out[row * 5 + k] = col[row];
        }
    }
    out
}

/// Planar depth range of the content's bounding box seen from `c2w`, padded, never below `near`.
fn depth_range(c2w: &DMat4, bounds: Option<(Vec3, Vec3)>, near: f64) -> (f64, f64) {
    let Some((lo, hi)) = bounds else { return (near, 100.0) };
    let w2c = c2w.inverse();
    let (mut dmin, mut dmax) = (f64::INFINITY, 0f64);
    for k in 0..8 {
        let p = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x } as f64,
            if k & 2 == 0 { lo.y } else { hi.y } as f64,
            if k & 4 == 0 { lo.z } else { hi.z } as f64,
        );
        let z = -w2c.transform_point3(p).z;
        dmin = dmin.min(z);
        dmax = dmax.max(z);
    }
    ((dmin * 0.9).max(near), (dmax * 1.1).max(near * 2.0))
}

/// A little-endian float64 `.npy` (format 1.0) of shape (rows, cols).
pub fn npy_f64(data: &[f64], rows: usize, cols: usize) -> Vec<u8> {
    let dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({rows}, {cols}), }}");
    // Magic (6) + version (2) + header length (2) + dict, padded with spaces to a multiple of 64, ending in \n.
    let total = (10 + dict.len() + 1).div_ceil(64) * 64;
    let mut header = dict.into_bytes();
    header.resize(total - 10 - 1, b' ');
    header.push(b'\n');
    let mut out = Vec::with_capacity(total + data.len() * 8);
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(&header);
    for v in data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}
