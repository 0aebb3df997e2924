//! The files a `path` rig follows: a nerfstudio viewer `camera_path.json` (with the `dataparser_transforms.json`
//! of the model it was drawn in), and a 6-DoF viewer trace (CSV). Both become time-stamped camera-to-world
//! samples in the world's frame (OpenGL camera axes, +Z up).
//!
//! `camera_path.json` is read as nerfstudio's own renderer reads it (`get_path_from_json` in
//! `nerfstudio/cameras/camera_paths.py`): the `camera_path` list the viewer sampled from its keyframes, spline,
//! smoothness and transition times, `camera_to_world` a row-major 4×4 (OpenGL axes), `fov` vertical, in degrees;
//! the viewer writes `seconds × fps` of them, camera `i` at `i / fps` s (`render_panel.py`, `_write_json`). So the
//! poses are the ones `ns-render camera-path` renders, whatever the viewer's interpolation.

use std::path::Path;

use glam::{DMat3, DQuat, DVec3};
use serde::Deserialize;

use super::path::rotation_of;
use super::Error;

/// Largest path file read.
const MAX_BYTES: u64 = 256 << 20;

/// One pose of a sampled path.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    /// Seconds from the path's start.
    pub time: f64,
    /// Camera position, world.
    pub position: DVec3,
    /// Camera-to-world rotation (OpenGL camera axes).
    pub rotation: DQuat,
    /// The vertical field of view the path gives, degrees.
    pub fov_deg: Option<f64>,
}

fn bad(path: &Path, line: Option<usize>, message: impl Into<String>) -> Error {
    Error::PathFile { path: path.to_path_buf(), line, message: message.into() }
}

fn read(path: &Path) -> Result<String, Error> {
    let read = |e| Error::Read { path: path.to_path_buf(), source: e };
    let len = std::fs::metadata(path).map_err(read)?.len();
    if len > MAX_BYTES {
        return Err(Error::TooLarge { path: path.to_path_buf(), len, max: MAX_BYTES });
    }
    std::fs::read_to_string(path).map_err(read)
}

#[derive(Deserialize)]
struct CameraPath {
    camera_path: Vec<PathCamera>,
    fps: f64,
    #[serde(default)]
    camera_type: Option<String>,
}

#[derive(Deserialize)]
struct PathCamera {
    camera_to_world: Vec<f64>,
    fov: f64,
}

#[derive(Deserialize)]
struct DataparserTransforms {
    transform: Vec<Vec<f64>>,
    scale: f64,
}

/// The cameras of a nerfstudio `camera_path.json`, mapped back to the world through `transforms` (the model's
/// `dataparser_transforms.json`: nerfstudio's world is `scale · (transform · c2w)` in translation).
pub fn camera_path(path: &Path, transforms: Option<&Path>) -> Result<Vec<Sample>, Error> {
    let text = read(path)?;
    let doc: CameraPath = serde_json::from_str(&text).map_err(|e| {
        bad(path, Some(e.line()), format!("not a nerfstudio camera path ({e}): it needs `camera_path` and `fps`"))
    })?;
    if let Some(t) = doc.camera_type.as_deref().filter(|t| *t != "perspective") {
        return Err(bad(path, None, format!("camera_type = \"{t}\": vvgen renders perspective cameras only")));
    }
    if !(doc.fps.is_finite() && doc.fps > 0.0) {
        return Err(bad(path, None, format!("fps = {} is not a frame rate", doc.fps)));
    }
    if doc.camera_path.is_empty() {
        return Err(bad(path, None, "`camera_path` lists no camera: export the path from the viewer again"));
    }
    // Model → world: c2w_world = T⁻¹ · (c2w_model with its translation divided by the scale).
    let (inv_rot, shift, scale) = match transforms {
        None => (DMat3::IDENTITY, DVec3::ZERO, 1.0),
        Some(t) => {
            let d: DataparserTransforms = serde_json::from_str(&read(t)?)
                .map_err(|e| bad(t, Some(e.line()), format!("not a dataparser_transforms.json ({e})")))?;
            let m = &d.transform;
            if m.len() < 3 || m.iter().take(3).any(|r| r.len() != 4) || m.iter().flatten().any(|v| !v.is_finite()) {
                return Err(bad(t, None, "`transform` is not a finite 3×4 matrix"));
            }
            if !(d.scale.is_finite() && d.scale > 0.0) {
                return Err(bad(t, None, format!("scale = {} is not a positive number", d.scale)));
            }
            let r = DMat3::from_cols_array_2d(&[
                [m[0][0], m[1][0], m[2][0]],
                [m[0][1], m[1][1], m[2][1]],
                [m[0][2], m[1][2], m[2][2]],
            ]);
            if (r.determinant() - 1.0).abs() > 1e-4 {
                return Err(bad(t, None, "`transform` is not a rotation and a translation"));
            }
            (r.transpose(), DVec3::new(m[0][3], m[1][3], m[2][3]), d.scale)
        }
    };
    doc.camera_path
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let m = &c.camera_to_world;
            if m.len() != 16 || m.iter().any(|v| !v.is_finite()) {
                return Err(bad(path, None, format!("camera {i}: `camera_to_world` is not 16 finite numbers")));
            }
            if !(c.fov > 0.0 && c.fov < 180.0) {
                return Err(bad(path, None, format!("camera {i}: fov = {} is not a field of view in degrees", c.fov)));
            }
            let rot = DMat3::from_cols_array_2d(&[[m[0], m[4], m[8]], [m[1], m[5], m[9]], [m[2], m[6], m[10]]]);
            let model = DVec3::new(m[3], m[7], m[11]);
            Ok(Sample {
                time: i as f64 / doc.fps,
                position: inv_rot * (model / scale - shift),
                rotation: rotation_of(inv_rot * rot),
                fov_deg: Some(c.fov),
            })
        })
        .collect()
}

/// The columns a trace's header must name (any order; other columns are ignored).
pub const TRACE_COLUMNS: [&str; 8] = ["time", "x", "y", "z", "qx", "qy", "qz", "qw"];

/// The poses of a 6-DoF trace: a CSV whose header names [`TRACE_COLUMNS`]; `time` in seconds (the first row is
/// the path's start), the position, and the camera-to-trace rotation as a quaternion. A left-handed trace
/// (`left`: the camera looks along +Z, Unity's convention) is mirrored in Z into a right-handed one first; then
/// `to_world` (rows) maps it onto the world.
pub fn trace(path: &Path, to_world: [[f64; 4]; 4], left: bool) -> Result<Vec<Sample>, Error> {
    let text = read(path)?;
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let Some((_, header)) = lines.next() else {
        return Err(bad(path, None, format!("empty: a trace starts with a header naming {}", TRACE_COLUMNS.join(","))));
    };
    let names: Vec<String> = header.split(',').map(|c| c.trim().to_ascii_lowercase()).collect();
    let mut at = [0usize; 8];
    let mut missing = Vec::new();
    for (k, want) in TRACE_COLUMNS.iter().enumerate() {
        match names.iter().position(|n| n == want) {
            Some(i) => at[k] = i,
            None => missing.push(*want),
        }
    }
    if !missing.is_empty() {
        return Err(bad(
            path,
            Some(1),
            format!(
                "the header `{}` lacks {}: name the columns {} (in any order)",
                header.trim(),
                missing.join(", "),
                TRACE_COLUMNS.join(",")
            ),
        ));
    }
    let t = DMat3::from_cols_array_2d(&[
        [to_world[0][0], to_world[1][0], to_world[2][0]],
        [to_world[0][1], to_world[1][1], to_world[2][1]],
        [to_world[0][2], to_world[1][2], to_world[2][2]],
    ]);
    let shift = DVec3::new(to_world[0][3], to_world[1][3], to_world[2][3]);
    let mirror = DMat3::from_diagonal(DVec3::new(1.0, 1.0, if left { -1.0 } else { 1.0 }));
    let mut out: Vec<Sample> = Vec::new();
    for (n, line) in lines {
        let line_no = Some(n + 1);
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != names.len() {
            return Err(bad(path, line_no, format!("{} cells where the header names {}", cells.len(), names.len())));
        }
        let mut v = [0.0f64; 8];
        for (k, &i) in at.iter().enumerate() {
            v[k] = cells[i].parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                bad(path, line_no, format!("column `{}`: `{}` is not a finite number", TRACE_COLUMNS[k], cells[i]))
            })?;
        }
        let q = DQuat::from_xyzw(v[4], v[5], v[6], v[7]);
        if q.length() < 1e-6 {
            return Err(bad(path, line_no, "the quaternion (qx, qy, qz, qw) is zero"));
        }
        if let Some(prev) = out.last() {
            if v[0] <= prev.time {
                return Err(bad(path, line_no, format!("time {} does not come after the row before's", v[0])));
            }
        }
        let r = mirror * DMat3::from_quat(q.normalize()) * mirror;
        let p = mirror * DVec3::new(v[1], v[2], v[3]);
        out.push(Sample { time: v[0], position: t * p + shift, rotation: rotation_of(t * r), fov_deg: None });
    }
    let Some(start) = out.first().map(|s| s.time) else {
        return Err(bad(path, None, "the trace has a header and no rows"));
    };
    for s in &mut out {
        s.time -= start;
    }
    Ok(out)
}
