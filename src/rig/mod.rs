//! Camera rigs: `[rig.NAME]` recipes → camera-to-world poses (OpenGL axes, world +Z up). Intrinsics come from
//! `[render]`; a rig only places cameras. Random recipes draw from streams keyed by (split seed, rig, view), so
//! adding views to a split appends poses and leaves the earlier ones bit-identical.

mod from_file;
/// The camera-to-world poses (OpenGL axes) of a transforms.json or a splatting trainer's cameras.json, as a
/// `from-file` rig reads them.
pub(crate) use from_file::read as camera_file;
pub mod path;
mod path_files;
pub mod random;

use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DVec3};

use crate::camera::Camera;
use crate::manifest::rig::{Band, ForwardLayout, OrbitSchedule, Rig, RigKind, NERF_RADIUS};
use random::{Keyed, Mt19937};

/// NeRF-synthetic's starting camera position before the tilt and azimuth: (0, 4, 0.5).
pub const NERF_START: DVec3 = DVec3::new(0.0, 4.0, 0.5);

/// What identifies a rig's draws.
#[derive(Debug, Clone, Copy)]
pub struct Identity<'a> {
    /// The rig's name.
    pub rig: &'a str,
    /// The split's seed (explicit, or derived from the dataset seed and the split name).
    pub seed: u64,
}

/// Why a rig cannot place its cameras.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An explicit pose gives neither a matrix nor a position.
    #[error("an explicit pose needs `c2w` or `position`")]
    PoseUnderspecified,
    /// A from-file rig names no file.
    #[error("a from-file rig needs `file`")]
    NoFile,
    /// The camera file cannot be read.
    #[error("{}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The camera file is implausibly large.
    #[error("{}: {len} bytes is more than a camera file should be ({max})", path.display())]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size.
        len: u64,
        /// The largest read.
        max: u64,
    },
    /// The camera file is not a transforms.json or a splatting trainer's cameras.json.
    #[error("{}: neither a transforms.json nor a splatting trainer's cameras.json", path.display())]
    NotTransforms {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: serde_json::Error,
    },
    /// The camera file lists no frames.
    #[error("{}: no frames", path.display())]
    NoFrames {
        /// The file.
        path: PathBuf,
    },
    /// A path file (camera path, trace, dataparser transforms) is malformed.
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    PathFile {
        /// The file.
        path: PathBuf,
        /// The 1-based line, when the problem has one.
        line: Option<usize>,
        /// What is wrong, and the fix.
        message: String,
    },
    /// A path rig lists no keyframe.
    #[error("a path needs `keyframes`, `file` or `trace`")]
    PathEmpty,
    /// A frame's matrix is malformed.
    #[error("{}: frame {frame}: its pose (transform_matrix, or rotation and position) is not a finite 3×4 or 4×4 matrix", path.display())]
    BadMatrix {
        /// The file.
        path: PathBuf,
        /// The frame's index.
        frame: usize,
    },
}

/// The poses of `views` cameras of `rig` (`views` is ignored by rigs that count themselves).
/// `dir` resolves `from-file` paths.
pub fn poses(rig: &Rig, id: Identity, views: u32, dir: &Path) -> Result<Vec<DMat4>, Error> {
    let target = DVec3::from(rig.target.unwrap_or([0.0; 3]));
    let radius = rig.radius().unwrap_or(NERF_RADIUS);
    let n = views as usize;
    let look = |eye: DVec3| look_at(eye, target);
    let mut out: Vec<DMat4> = match rig.kind() {
        RigKind::Hemisphere => {
            let scale = radius / NERF_START.length();
            let draw = |u0: f64, u2: f64| {
                // The NeRF-synthetic Blender recipe: Euler (|acos(1-2u) - π/2|, 0, 2πu) applied to (0, 4, 0.5).
                let tilt = ((1.0 - 2.0 * u0).acos() - FRAC_PI_2).abs();
                look(target + DMat3::from_rotation_z(TAU * u2) * DMat3::from_rotation_x(tilt) * NERF_START * scale)
            };
            match rig.numpy_seed {
                Some(s) => {
                    let mut mt = Mt19937::new(s);
                    (0..n)
                        .map(|_| {
                            // The toolkit draws `np.random.uniform(0, 1, 3)` before each render (the middle draw
                            // is multiplied by 0), and once more after it, a draw the next view's overwrites: so
                            // view i uses draw 2i, and each view consumes six uniforms.
                            let (u0, _, u2) = (mt.uniform(), mt.uniform(), mt.uniform());
                            for _ in 0..3 {
                                mt.uniform();
                            }
                            draw(u0, u2)
                        })
                        .collect()
                }
                None => (0..n)
                    .map(|i| {
                        let mut k = stream(id, "hemisphere", i);
                        let (u0, u2) = (k.uniform(), k.uniform());
                        draw(u0, u2)
                    })
                    .collect(),
            }
        }
        RigKind::Sphere => {
            let (lo, hi) = band(rig);
            (0..n)
                .map(|i| {
                    let mut k = stream(id, "sphere", i);
                    // Uniform on the sphere: z uniform in [sin lo, sin hi], azimuth uniform.
                    let z = lerp(lo.sin(), hi.sin(), k.uniform());
                    look(target + radius * dir_from(z, TAU * k.uniform()))
                })
                .collect()
        }
        RigKind::Fibonacci => {
            let (lo, hi) = band(rig);
            let golden = PI * (3.0 - 5f64.sqrt());
            (0..n)
                .map(|i| {
                    let z = lerp(hi.sin(), lo.sin(), (i as f64 + 0.5) / n as f64);
                    look(target + radius * dir_from(z, golden * i as f64))
                })
                .collect()
        }
        RigKind::Orbit => {
            let start = rig.start_azimuth_deg.unwrap_or(0.0).to_radians();
            let schedule = rig.schedule.unwrap_or(OrbitSchedule::Fixed);
            (0..n)
                .map(|i| {
                    let az = start + TAU * i as f64 / n as f64;
                    let eye = match schedule {
                        OrbitSchedule::Fixed => {
                            let el = rig.elevation_deg.unwrap_or(30.0).to_radians();
                            // Azimuth 0 puts the camera on +Y (NeRF-synthetic's start), looking toward −Y.
                            radius * DVec3::new(-az.sin() * el.cos(), az.cos() * el.cos(), el.sin())
                        }
                        OrbitSchedule::NerfTest => {
                            // Frame 0: Rx(0.7)·(0, 4, 0.5) = (0, 2.73726, 2.95929), the published lego fact.
                            let tilt = 0.7 * ((TAU * i as f64 / n as f64).cos() + 1.0) / 2.0;
                            DMat3::from_rotation_z(az)
                                * DMat3::from_rotation_x(tilt)
                                * NERF_START
                                * (radius / NERF_START.length())
                        }
                    };
                    look(target + eye)
                })
                .collect()
        }
        RigKind::Dome => {
            let (lo, hi) = band(rig);
            let rings = rig.rings().map_or(3, |r| r as usize).min(n.max(1));
            let start = rig.start_azimuth_deg.unwrap_or(0.0).to_radians();
            let mut v = Vec::with_capacity(n);
            for r in 0..rings {
                // Views shared evenly; the lowest rings take the remainder.
                let m = n / rings + usize::from(r < n % rings);
                let el = lerp(lo, hi, (r as f64 + 0.5) / rings as f64);
                // Alternate rings are offset by half a step so cameras do not line up in columns.
                let off = if r % 2 == 1 { PI / m.max(1) as f64 } else { 0.0 };
                for j in 0..m {
                    let az = start + off + TAU * j as f64 / m as f64;
                    v.push(look(target + radius * DVec3::new(-az.sin() * el.cos(), az.cos() * el.cos(), el.sin())));
                }
            }
            v
        }
        RigKind::ForwardFacing => {
            let [w, h] = rig.extent.unwrap_or([1.0, 0.75]);
            // Cameras on a plane at distance `radius` in front of the target (−Y side), all facing it.
            let at = |x: f64, z: f64| look(target + DVec3::new(x, -radius, z));
            match rig.layout.unwrap_or(ForwardLayout::Plane) {
                ForwardLayout::Plane => {
                    let cols = ((n as f64 * w / h.max(1e-9)).sqrt().ceil() as usize).clamp(1, n.max(1));
                    let rows = n.div_ceil(cols);
                    (0..n)
                        .map(|i| {
                            let (c, r) = (i % cols, i / cols);
                            let fx = if cols > 1 { c as f64 / (cols - 1) as f64 - 0.5 } else { 0.0 };
                            let fz = if rows > 1 { 0.5 - r as f64 / (rows - 1) as f64 } else { 0.0 };
                            at(fx * w, fz * h)
                        })
                        .collect()
                }
                ForwardLayout::Spiral => {
                    let golden = PI * (3.0 - 5f64.sqrt());
                    (0..n)
                        .map(|i| {
                            let r = ((i as f64 + 0.5) / n as f64).sqrt();
                            let a = golden * i as f64;
                            at(0.5 * w * r * a.cos(), 0.5 * h * r * a.sin())
                        })
                        .collect()
                }
            }
        }
        RigKind::Explicit => {
            let list = rig.poses();
            list.iter()
                .map(|p| match (p.c2w, p.position) {
                    (Some(m), _) => Ok(DMat4::from_cols_array_2d(&m).transpose()),
                    (None, Some(pos)) => {
                        Ok(look_at(DVec3::from(pos), DVec3::from(p.target.or(rig.target).unwrap_or([0.0; 3]))))
                    }
                    (None, None) => Err(Error::PoseUnderspecified),
                })
                .collect::<Result<_, _>>()?
        }
        RigKind::FromFile => {
            let file = rig.file().ok_or(Error::NoFile)?;
            from_file::read(&dir.join(file))?
        }
        // A path's poses depend on its frames' times: the planner places them with `path::poses`.
        RigKind::Path => Vec::new(),
    };
    if let Some(j) = rig.jitter {
        for (i, m) in out.iter_mut().enumerate() {
            let mut k = stream(id, "jitter", i);
            let dp = DVec3::from(k.in_ball()) * j.position;
            let dt = DVec3::from(k.in_ball()) * j.target;
            let eye = m.w_axis.truncate();
            // Keep the distance to the target the jitter is measured from: aim at the (perturbed) target.
            let back = m.z_axis.truncate();
            let aim = eye - back * (eye - target).length().max(1e-9);
            *m = look_at(eye + dp, aim + dt);
        }
    }
    Ok(out)
}

/// Camera-to-world of a camera at `eye` looking at `target` with world +Z up in the image (OpenGL axes);
/// Blender's Track To with up axis Y. Straight up or down, image up falls back to world +Y.
pub fn look_at(eye: DVec3, target: DVec3) -> DMat4 {
    Camera::look_at_f64(eye, target, DVec3::Z)
}

fn stream(id: Identity, what: &str, view: usize) -> Keyed {
    Keyed::new(what, &[&id.seed.to_le_bytes(), id.rig.as_bytes(), &(view as u64).to_le_bytes()])
}

fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

/// Unit direction with height `z` and azimuth `az` (azimuth 0 on +Y, counter-clockwise seen from above).
fn dir_from(z: f64, az: f64) -> DVec3 {
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(-r * az.sin(), r * az.cos(), z)
}

/// The elevation band in radians.
fn band(rig: &Rig) -> (f64, f64) {
    if let Some([lo, hi]) = rig.elevation_range_deg() {
        return (lo.to_radians(), hi.to_radians());
    }
    match rig.band.unwrap_or(Band::Upper) {
        Band::Full => (-FRAC_PI_2, FRAC_PI_2),
        Band::Upper => (0.0, FRAC_PI_2),
    }
}
