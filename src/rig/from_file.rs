//! `kind = "from-file"`: the cameras of an existing transforms.json (NeRF-synthetic, D-NeRF, nerfstudio,
//! instant-ngp), so a published camera set can be re-rendered, or of a 3D Gaussian splatting model's
//! `cameras.json` (graphdeco-inria's `camera_to_JSON`: the cameras its splats were trained on). Only the poses are
//! read: `frames[].transform_matrix` (OpenGL camera-to-world, rows), or each camera's `rotation` (camera-to-world,
//! rows, OpenCV's axes: +Y down, +Z forward) and `position`; cameras keep the file's order.

use std::path::Path;

use glam::DMat4;
use serde::Deserialize;

use super::Error;

/// Largest transforms.json read (a 100 000-frame file is ~40 MB).
const MAX_BYTES: u64 = 256 << 20;

#[derive(Deserialize)]
struct File {
    frames: Vec<Frame>,
}

#[derive(Deserialize)]
struct Frame {
    transform_matrix: Vec<Vec<f64>>,
}

/// One camera of a splatting trainer's cameras.json (its other fields, the image's name, size and focal
/// lengths, are not read: `[render]` sets the images).
#[derive(Deserialize)]
struct SplatCamera {
    position: [f64; 3],
    rotation: [[f64; 3]; 3],
}

/// The poses of `path`'s frames.
pub fn read(path: &Path) -> Result<Vec<DMat4>, Error> {
    let file = || path.to_path_buf();
    let len = std::fs::metadata(path).map_err(|e| Error::Read { path: file(), source: e })?.len();
    if len > MAX_BYTES {
        return Err(Error::TooLarge { path: file(), len, max: MAX_BYTES });
    }
    let text = std::fs::read_to_string(path).map_err(|e| Error::Read { path: file(), source: e })?;
    // A list of cameras is a splatting trainer's cameras.json; an object, a transforms.json.
    if text.trim_start().starts_with('[') {
        let cameras: Vec<SplatCamera> =
            serde_json::from_str(&text).map_err(|e| Error::NotTransforms { path: file(), source: e })?;
        if cameras.is_empty() {
            return Err(Error::NoFrames { path: file() });
        }
        return cameras
            .iter()
            .enumerate()
            .map(|(i, c)| splat_pose(c).ok_or(Error::BadMatrix { path: file(), frame: i }))
            .collect();
    }
    let parsed: File = serde_json::from_str(&text).map_err(|e| Error::NotTransforms { path: file(), source: e })?;
    if parsed.frames.is_empty() {
        return Err(Error::NoFrames { path: file() });
    }
    parsed
        .frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let m = &f.transform_matrix;
            let rows = m.len();
            if !(rows == 3 || rows == 4) || m.iter().any(|r| r.len() != 4) || m.iter().flatten().any(|v| !v.is_finite())
            {
                return Err(Error::BadMatrix { path: file(), frame: i });
            }
            let mut a = [[0.0, 0.0, 0.0, 1.0]; 4];
            for (r, row) in m.iter().enumerate() {
                a[r].copy_from_slice(row);
            }
            Ok(DMat4::from_cols_array_2d(&a).transpose())
        })
        .collect()
}

/// A cameras.json camera's pose: [rotation | position] is camera-to-world in OpenCV's axes (`camera_to_JSON`
/// inverts the world-to-camera [Rᵀ | T] it trained with), turned to OpenGL's by flipping the camera's Y and Z.
/// `None` where a value is not finite.
fn splat_pose(c: &SplatCamera) -> Option<DMat4> {
    let r = &c.rotation;
    let finite = r.iter().flatten().chain(&c.position).all(|v| v.is_finite());
    let col = |j: usize| glam::DVec3::new(r[0][j], r[1][j], r[2][j]);
    let m = DMat4::from_cols(
        col(0).extend(0.0),
        col(1).extend(0.0),
        col(2).extend(0.0),
        glam::DVec3::from(c.position).extend(1.0),
    );
    finite.then(|| m * crate::camera::GL_TO_CV)
}
