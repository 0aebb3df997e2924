//! `kind = "from-file"`: the cameras of an existing transforms.json (NeRF-synthetic, D-NeRF, nerfstudio,
//! instant-ngp), so a published camera set can be re-rendered. Only `frames[].transform_matrix` is read (OpenGL
//! camera-to-world, rows); frames keep the file's order.

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

/// The poses of `path`'s frames.
pub fn read(path: &Path) -> Result<Vec<DMat4>, Error> {
    let file = || path.to_path_buf();
    let len = std::fs::metadata(path).map_err(|e| Error::Read { path: file(), source: e })?.len();
    if len > MAX_BYTES {
        return Err(Error::TooLarge { path: file(), len, max: MAX_BYTES });
    }
    let text = std::fs::read_to_string(path).map_err(|e| Error::Read { path: file(), source: e })?;
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
