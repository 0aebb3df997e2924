//! Framing from the manifest alone: how large a subject centred on the origin may be for every camera of every
//! rig a split uses to see it whole (what `fit = "frame"` sizes to), and the rig radius that would keep a given
//! subject whole (what a crop warning suggests).
//!
//! A subject is "whole" in a camera when its bounding sphere lies inside the cone inscribed in the image (the
//! cone from the eye to the image's nearest edge) and beyond the near plane. The cone is inside the frustum, so
//! that is sufficient for any image shape and principal point; for a square, centred image it is also the
//! tightest bound a sphere allows.
//!
//! Rigs that aim at a target from a distance (`hemisphere`, `sphere`, `fibonacci`, `orbit`, `dome`,
//! `forward-facing`) are bounded from their settings, whatever their random draws, jitter included; `explicit`
//! poses are measured one by one; `from-file` cameras live in a file the manifest does not read, so they size
//! nothing here (the crop check, which sees every planned camera, still covers them).

use glam::DVec3;

use super::rig::{Rig, RigKind, NERF_RADIUS};
use super::Manifest;

/// The largest sphere about the origin every sizing camera sees whole, and the rig that bounds it.
#[derive(Debug, Clone, PartialEq)]
pub struct Reach {
    /// The sphere's radius, world units (may be ≤ 0: no sphere fits).
    pub radius: f64,
    /// The rig whose cameras bound it.
    pub rig: String,
}

/// The angle from the optical axis to the nearest image edge, radians (0 when the principal point is outside
/// the image).
pub fn half_angle(m: &Manifest) -> f64 {
    let (w, h) = m.render.size();
    let (fx, fy, cx, cy) = m.render.intrinsics();
    let edges = [cx / fx, (w as f64 - cx) / fx, cy / fy, (h as f64 - cy) / fy];
    edges.into_iter().map(f64::atan).fold(f64::INFINITY, f64::min).max(0.0)
}

/// The near clipping distance the renderer uses.
fn near(m: &Manifest) -> f64 {
    m.render.near.unwrap_or(0.05)
}

/// The least reach of the rigs the splits use; `None` when every split uses a `from-file` rig. A manifest with
/// no split (point clouds only) is sized for NeRF-synthetic's hemisphere, so adding images later keeps the
/// subject's size.
pub fn reach(m: &Manifest) -> Option<Reach> {
    let alpha = half_angle(m);
    if m.splits.is_empty() {
        let d = NERF_RADIUS;
        return Some(Reach { radius: (d * alpha.sin()).min(d - near(m)), rig: "the default hemisphere".into() });
    }
    let mut rigs: Vec<&str> = m.splits.values().map(|s| s.rig()).collect();
    rigs.sort_unstable();
    rigs.dedup();
    rigs.into_iter()
        .filter_map(|name| {
            let r = rig_reach(m.rigs.get(name)?, alpha, near(m))?;
            Some(Reach { radius: r, rig: name.to_string() })
        })
        .min_by(|a, b| a.radius.total_cmp(&b.radius))
}

/// Offsets of an aimed rig: its distance to the target, and how far its eye and aim may stray from it.
struct Aim {
    distance: f64,
    /// |target|: how far the aim point is from the origin the subject is centred on, plus the target jitter.
    off: f64,
    /// Position jitter plus target jitter: how much closer than `distance` the eye may come to its aim point.
    closer: f64,
}

fn aim(rig: &Rig) -> Option<Aim> {
    match rig.kind() {
        RigKind::Explicit | RigKind::FromFile | RigKind::Path => None,
        // Forward-facing cameras sit on a plane at `radius` in front of the target: none is nearer than that.
        _ => {
            let j = rig.jitter.unwrap_or_default();
            let t = DVec3::from(rig.target.unwrap_or([0.0; 3])).length();
            Some(Aim {
                distance: rig.radius().unwrap_or(NERF_RADIUS),
                off: t + j.target.abs(),
                closer: j.position.abs() + j.target.abs(),
            })
        }
    }
}

/// The largest sphere about the origin every camera of `rig` sees whole (`None` for `from-file`).
fn rig_reach(rig: &Rig, alpha: f64, near: f64) -> Option<f64> {
    if rig.kind() == RigKind::Explicit {
        return rig
            .poses()
            .iter()
            .filter_map(|p| {
                let (eye, forward) = match (p.c2w, p.position) {
                    (Some(c), _) => (DVec3::new(c[0][3], c[1][3], c[2][3]), -DVec3::new(c[0][2], c[1][2], c[2][2])),
                    (None, Some(pos)) => {
                        let eye = DVec3::from(pos);
                        (eye, DVec3::from(p.target.or(rig.target).unwrap_or([0.0; 3])) - eye)
                    }
                    (None, None) => return None,
                };
                Some(pose_reach(eye, forward, alpha, near))
            })
            .reduce(f64::min);
    }
    let a = aim(rig)?;
    // The sphere about the origin lies inside the sphere of radius r + off about the aim point, which is on
    // the axis at a distance of at least `distance - closer`.
    let d = a.distance - a.closer;
    Some((d * alpha.sin()).min(d - near) - a.off)
}

/// The largest sphere about the origin one camera (eye, looking along `forward`) sees whole.
fn pose_reach(eye: DVec3, forward: DVec3, alpha: f64, near: f64) -> f64 {
    let d = eye.length();
    let f = forward.normalize_or_zero();
    if d <= 0.0 || f == DVec3::ZERO {
        return 0.0;
    }
    // β: the angle between the axis and the direction to the origin.
    let beta = f.dot(-eye / d).clamp(-1.0, 1.0).acos();
    if beta >= alpha {
        return 0.0;
    }
    (d * (alpha - beta).sin()).min(d * beta.cos() - near)
}

/// The `radius` that would let `rig` see a subject reaching `subject` from the origin whole with `margin`
/// (`None` when the rig has no radius: explicit and from-file cameras).
pub fn radius_keeping(m: &Manifest, rig: &Rig, subject: f64, margin: f64) -> Option<f64> {
    let a = aim(rig)?;
    let s = half_angle(m).sin();
    (s > 0.0).then(|| (subject / (1.0 - margin) + a.off) / s + a.closer)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest(extra: &str) -> Manifest {
        manifest_with(extra, &[])
    }

    fn manifest_with(extra: &str, files: &[(&str, &str)]) -> Manifest {
        let text = format!(
            "[dataset]\nname = \"t\"\nout = \"out\"\n[source.a]\nmesh = \"a.ply\"\n[render]\nresolution = [400, 400]\n\
             {extra}\n[split.train]\nrig = \"r\"\nviews = 4\n[output.o]\nwriter = \"dnerf\"\n"
        );
        let dir = tempfile::tempdir().unwrap();
        let ply = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
                   end_header\n0 0 0\n";
        std::fs::write(dir.path().join("a.ply"), ply).unwrap();
        for (name, text) in files {
            std::fs::write(dir.path().join(name), text).unwrap();
        }
        let (m, _) =
            super::super::parse(&text, &dir.path().join("m.toml")).unwrap_or_else(|r| panic!("{}", r.render(false)));
        m
    }

    #[test]
    fn the_nerf_hemisphere_frames_a_sphere_of_about_1_37() {
        // NeRF-synthetic: radius 4.031, camera_angle_x 0.6911: sin(0.3456) · 4.031 = 1.365.
        let m = manifest("[rig.r]\nkind = \"hemisphere\"\n");
        let r = reach(&m).unwrap();
        assert!((r.radius - 4.031128874149275 * (0.6911112070083618f64 / 2.0).sin()).abs() < 1e-9, "{r:?}");
        // And the radius that keeps that sphere whole with no margin is the rig's own.
        let rig = &m.rigs["r"];
        assert!((radius_keeping(&m, rig, r.radius, 0.0).unwrap() - 4.031128874149275).abs() < 1e-9);
    }

    #[test]
    fn an_off_centre_target_and_jitter_shrink_the_reach() {
        let plain = reach(&manifest("[rig.r]\nkind = \"orbit\"\nradius = 5\n")).unwrap().radius;
        let off = reach(&manifest("[rig.r]\nkind = \"orbit\"\nradius = 5\ntarget = [0.3, 0, 0.4]\n")).unwrap().radius;
        assert!((plain - off - 0.5).abs() < 1e-9, "{plain} {off}");
        let j = "[rig.r]\nkind = \"orbit\"\nradius = 5\njitter = { position = 0.2, target = 0.1 }\n";
        let jit = reach(&manifest(j)).unwrap().radius;
        assert!((jit - ((5.0 - 0.3) * half_angle(&manifest(j)).sin() - 0.1)).abs() < 1e-9, "{jit}");
    }

    #[test]
    fn explicit_poses_are_measured_one_by_one() {
        // One camera on +Y looking at the origin; another looking past it, at (1, 0, 0): its reach is smaller.
        let at = reach(&manifest("[rig.r]\nkind = \"explicit\"\nposes = [{ position = [0, 4, 0] }]\n")).unwrap();
        let past =
            reach(&manifest("[rig.r]\nkind = \"explicit\"\nposes = [{ position = [0, 4, 0], target = [1, 0, 0] }]\n"))
                .unwrap();
        assert!((at.radius - 4.0 * (0.6911112070083618f64 / 2.0).sin()).abs() < 1e-9, "{at:?}");
        assert!(past.radius < at.radius && past.radius > 0.0, "{past:?}");
    }

    #[test]
    fn from_file_rigs_size_nothing() {
        let cams = (r#"c.json"#, r#"{"frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]]}]}"#);
        assert_eq!(reach(&manifest_with("[rig.r]\nkind = \"from-file\"\nfile = \"c.json\"\n", &[cams])), None);
    }
}
