//! `kind = "from-file"`: the cameras of an existing transforms.json (NeRF-synthetic, D-NeRF, nerfstudio,
//! instant-ngp), so a published camera set can be re-rendered. Only `frames[].transform_matrix` is read (OpenGL
//! camera-to-world, rows); frames keep the file's order.

use std::path::Path;

use glam::DMat4;
use serde::Deserialize;

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
pub fn read(path: &Path) -> Result<Vec<DMat4>, String> {
    let name = path.display();
    let len = std::fs::metadata(path).map_err(|e| format!("{name}: {e}"))?.len();
    if len > MAX_BYTES {
        return Err(format!("{name}: {len} bytes is more than a camera file should be ({MAX_BYTES})"));
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("{name}: {e}"))?;
    let file: File = serde_json::from_str(&text).map_err(|e| format!("{name}: not a transforms.json: {e}"))?;
    if file.frames.is_empty() {
        return Err(format!("{name}: no frames"));
    }
    file.frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let m = &f.transform_matrix;
            let rows = m.len();
            if !(rows == 3 || rows == 4) || m.iter().any(|r| r.len() != 4) || m.iter().flatten().any(|v| !v.is_finite())
            {
                return Err(format!("{name}: frame {i}: transform_matrix is not a finite 3×4 or 4×4 matrix"));
            }
            let mut a = [[0.0, 0.0, 0.0, 1.0]; 4];
            for (r, row) in m.iter().enumerate() {
                a[r].copy_from_slice(row);
            }
            Ok(DMat4::from_cols_array_2d(&a).transpose())
        })
        .collect()
}
