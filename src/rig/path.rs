//! `kind = "path"`: a camera whose pose is a function of time, one pose per frame of the split.
//!
//! Keyframes are interpolated smoothly: positions (and aim points, when every keyframe aims at one) along a
//! centripetal Catmull–Rom spline through them, which neither overshoots nor loops between close keyframes;
//! orientations, when a keyframe gives a matrix, by slerp. Sampled paths (a nerfstudio `camera_path.json`, a
//! viewer trace, [`super::path_files`]) are dense already: between two samples the position moves linearly and
//! the orientation by slerp. Before the first keyframe and after the last the camera holds still.
//!
//! A frame's pose depends only on the keyframes about its own time (the two it lies between and their
//! neighbours), so editing one keyframe moves only the frames near it, and only their images render again.
//!
//! A path may zoom: keyframes' `fov_deg` (or a camera path's `fov`) change the vertical field of view linearly
//! between them; the planner turns it into each image's focal length, and only writers that record intrinsics
//! per image take such a split.

use std::path::Path;

use glam::{DMat3, DMat4, DQuat, DVec3};

use super::path_files::{self, Sample};
use super::{look_at, Error};
use crate::manifest::rig::{Keyframe, Rig};

/// A path at the split's frames.
#[derive(Debug, Clone)]
pub struct Placed {
    /// Camera-to-world per frame.
    pub poses: Vec<DMat4>,
    /// The vertical field of view per frame, degrees, when the path gives one (a zoom); `None`: `[render]`'s.
    pub fov_deg: Option<Vec<f64>>,
    /// A note when the path ends before the last frame.
    pub note: Option<String>,
}

/// The poses of a path rig at `times` (seconds from the dataset's first frame). `render_fov_deg` is
/// `[render]`'s vertical field of view, what keyframes without `fov_deg` keep.
pub fn poses(rig: &Rig, times: &[f64], dir: &Path, render_fov_deg: f64) -> Result<Placed, Error> {
    let samples = if let Some(file) = rig.file() {
        let transforms = rig.dataparser_transforms().map(|d| dir.join(d));
        path_files::camera_path(&dir.join(file), transforms.as_deref())?
    } else if let Some(trace) = rig.trace() {
        let to_world = rig.trace_to_world().unwrap_or(IDENTITY);
        let left = rig.trace_handedness == Some(crate::manifest::rig::Handedness::Left);
        path_files::trace(&dir.join(trace), to_world, left)?
    } else {
        return keyframed(rig.keyframes(), times, render_fov_deg);
    };
    let end = samples.last().map_or(0.0, |s| s.time);
    let zooms = samples.iter().any(|s| s.fov_deg.is_some_and(|f| (f - render_fov_deg).abs() > 1e-6));
    let fov_deg = zooms.then(|| times.iter().map(|&t| sampled_fov(&samples, t).unwrap_or(render_fov_deg)).collect());
    Ok(Placed { poses: times.iter().map(|&t| sampled(&samples, t)).collect(), fov_deg, note: held(times, end) })
}

const IDENTITY: [[f64; 4]; 4] =
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];

/// The note for frames past the path's end, which hold its last pose.
fn held(times: &[f64], end: f64) -> Option<String> {
    let past = times.iter().filter(|&&t| t > end + 1e-9).count();
    (past > 0).then(|| {
        format!(
            "the path ends at {end:.3} s and the split's last frame is at {:.3} s: its last {past} frame(s) hold the \
             path's last pose",
            times.last().copied().unwrap_or(0.0)
        )
    })
}

/// Keyframes at `times`.
fn keyframed(keys: &[Keyframe], times: &[f64], render_fov_deg: f64) -> Result<Placed, Error> {
    let Some(last) = keys.last() else { return Err(Error::PathEmpty) };
    // A zoom: keyframes without `fov_deg` keep `[render]`'s; between keyframes it changes linearly.
    let fovs: Vec<f64> = keys.iter().map(|k| k.fov_deg.unwrap_or(render_fov_deg)).collect();
    let zooms = fovs.iter().any(|f| (f - render_fov_deg).abs() > 1e-6);
    let eyes: Vec<DVec3> = keys.iter().map(eye).collect();
    let aimed = keys.iter().all(|k| k.position.is_some());
    let aims: Vec<DVec3> = keys.iter().map(|k| DVec3::from(k.target.unwrap_or([0.0; 3]))).collect();
    let turns: Vec<DQuat> = keys.iter().map(orientation).collect();
    let key_times: Vec<f64> = keys.iter().map(|k| k.time).collect();
    let fov_deg = zooms.then(|| {
        times
            .iter()
            .map(|&t| {
                let (i, u) = segment(&key_times, t);
                if i + 1 < fovs.len() {
                    fovs[i] + (fovs[i + 1] - fovs[i]) * u
                } else {
                    fovs[i]
                }
            })
            .collect()
    });
    let poses = times
        .iter()
        .map(|&t| {
            let (i, u) = segment(&key_times, t);
            let eye = catmull_rom(&eyes, i, u);
            if aimed {
                look_at(eye, catmull_rom(&aims, i, u))
            } else {
                let q = if i + 1 < turns.len() { turns[i].slerp(turns[i + 1], u) } else { turns[i] };
                DMat4::from_rotation_translation(q, eye)
            }
        })
        .collect();
    Ok(Placed { poses, fov_deg, note: held(times, last.time) })
}

fn eye(k: &Keyframe) -> DVec3 {
    match (k.position, k.c2w) {
        (Some(p), _) => DVec3::from(p),
        (None, Some(m)) => DVec3::new(m[0][3], m[1][3], m[2][3]),
        (None, None) => DVec3::ZERO,
    }
}

/// A keyframe's camera-to-world rotation.
fn orientation(k: &Keyframe) -> DQuat {
    match (k.position, k.c2w) {
        (Some(p), _) => {
            let m = look_at(DVec3::from(p), DVec3::from(k.target.unwrap_or([0.0; 3])));
            DQuat::from_mat4(&m)
        }
        (None, Some(m)) => rotation_of(DMat3::from_cols_array_2d(&[
            [m[0][0], m[1][0], m[2][0]],
            [m[0][1], m[1][1], m[2][1]],
            [m[0][2], m[1][2], m[2][2]],
        ])),
        (None, None) => DQuat::IDENTITY,
    }
}

/// The rotation nearest a matrix whose columns may be scaled or a little off orthogonal (Gram–Schmidt on the
/// viewing direction first, so the camera looks where the matrix says).
pub(super) fn rotation_of(m: DMat3) -> DQuat {
    let back = m.z_axis.normalize_or(DVec3::Z);
    let up = (m.y_axis - back * m.y_axis.dot(back)).normalize_or(back.any_orthonormal_vector());
    DQuat::from_mat3(&DMat3::from_cols(up.cross(back), up, back)).normalize()
}

/// The segment `t` falls in (keyframes `i` and `i + 1`) and how far along it, 0 … 1; before the first keyframe
/// `(0, 0)`, after the last `(last, 0)`.
fn segment(times: &[f64], t: f64) -> (usize, f64) {
    let last = times.len() - 1;
    if t <= times[0] {
        return (0, 0.0);
    }
    if t >= times[last] {
        return (last, 0.0);
    }
    // The first keyframe after t; t lies in [times[i], times[i + 1]).
    let i = times.partition_point(|&k| k <= t) - 1;
    (i, ((t - times[i]) / (times[i + 1] - times[i])).clamp(0.0, 1.0))
}

/// The centripetal Catmull–Rom spline through `p` at `u` of segment `i` (Barry and Goldman's pyramid, knots
/// spaced by the square root of the chord). The ends are extended by reflection; a neighbour on top of its
/// point is reflected too, so no knot interval is zero.
fn catmull_rom(p: &[DVec3], i: usize, u: f64) -> DVec3 {
    let n = p.len();
    if i + 1 >= n || u == 0.0 {
        return p[i.min(n - 1)];
    }
    let (p1, p2) = (p[i], p[i + 1]);
    if p1.distance_squared(p2) < 1e-24 {
        return p1;
    }
    let p0 = if i > 0 && p[i - 1].distance_squared(p1) > 1e-24 { p[i - 1] } else { 2.0 * p1 - p2 };
    let p3 = if i + 2 < n && p[i + 2].distance_squared(p2) > 1e-24 { p[i + 2] } else { 2.0 * p2 - p1 };
    let knot = |a: DVec3, b: DVec3| a.distance(b).sqrt();
    let t0 = 0.0;
    let t1 = t0 + knot(p0, p1);
    let t2 = t1 + knot(p1, p2);
    let t3 = t2 + knot(p2, p3);
    let t = t1 + u * (t2 - t1);
    let mix = |a: DVec3, b: DVec3, ta: f64, tb: f64| (tb - t) / (tb - ta) * a + (t - ta) / (tb - ta) * b;
    let a1 = mix(p0, p1, t0, t1);
    let a2 = mix(p1, p2, t1, t2);
    let a3 = mix(p2, p3, t2, t3);
    let b1 = mix(a1, a2, t0, t2);
    let b2 = mix(a2, a3, t1, t3);
    mix(b1, b2, t1, t2)
}

/// The two samples of a dense path about `t` and how far between them, 0 … 1; at or past either end, that end
/// twice (the camera holds still).
fn bracket(s: &[Sample], t: f64) -> (&Sample, &Sample, f64) {
    let first = &s[0];
    if t <= first.time || s.len() == 1 {
        return (first, first, 0.0);
    }
    let i = s.partition_point(|x| x.time <= t);
    if i >= s.len() {
        let last = &s[s.len() - 1];
        return (last, last, 0.0);
    }
    let (a, b) = (&s[i - 1], &s[i]);
    (a, b, ((t - a.time) / (b.time - a.time)).clamp(0.0, 1.0))
}

/// A dense path at `t`: linear between the two samples about it, orientation by slerp; held at the ends.
fn sampled(s: &[Sample], t: f64) -> DMat4 {
    match bracket(s, t) {
        (a, b, _) if std::ptr::eq(a, b) => DMat4::from_rotation_translation(a.rotation, a.position),
        (a, b, u) => DMat4::from_rotation_translation(a.rotation.slerp(b.rotation, u), a.position.lerp(b.position, u)),
    }
}

/// A dense path's field of view at `t`, as [`sampled`] places the camera.
fn sampled_fov(s: &[Sample], t: f64) -> Option<f64> {
    let (a, b, u) = bracket(s, t);
    Some(a.fov_deg? + (b.fov_deg? - a.fov_deg?) * u)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spline_passes_through_its_keyframes_and_stays_between_close_ones() {
        let p = [DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), DVec3::new(1.0, 1.0, 0.0), DVec3::new(1.0, 1.001, 0.0)];
        for i in 0..3 {
            assert!(catmull_rom(&p, i, 0.0).distance(p[i]) < 1e-12);
            assert!(catmull_rom(&p, i, 1.0 - 1e-12).distance(p[i + 1]) < 1e-9);
        }
        // Centripetal: the short last segment neither overshoots nor loops.
        for k in 0..=100 {
            let q = catmull_rom(&p, 2, k as f64 / 100.0);
            assert!(q.y >= 1.0 - 1e-9 && q.y <= 1.001 + 1e-9 && (q.x - 1.0).abs() < 1e-3, "{q}");
        }
        // Collinear, evenly spaced keyframes: a straight line.
        let line = [DVec3::ZERO, DVec3::X, 2.0 * DVec3::X];
        let mid = catmull_rom(&line, 0, 0.5);
        assert!(mid.y.abs() < 1e-12 && mid.z.abs() < 1e-12 && mid.x > 0.0 && mid.x < 1.0, "{mid}");
    }

    #[test]
    fn segments_hold_at_the_ends() {
        let t = [0.0, 1.0, 3.0];
        assert_eq!(segment(&t, -1.0), (0, 0.0));
        assert_eq!(segment(&t, 0.5), (0, 0.5));
        assert_eq!(segment(&t, 2.0), (1, 0.5));
        assert_eq!(segment(&t, 3.0), (2, 0.0));
        assert_eq!(segment(&t, 9.0), (2, 0.0));
    }
}
