//! The rig plot: every camera of a dataset drawn as a frustum around the subject, from the top, the front and
//! the side, in world axes (+Z up). A subject lying on its back, cameras looking past it, or a frame that cuts
//! it off are what this picture is for: the subject is drawn as its surface samples, its bounds over all frames
//! as a box, and the legend counts the cameras whose image does not hold the whole subject.

use glam::{DVec3, Vec3};

use super::canvas::{Canvas, Rgb};
use crate::camera::Camera;

/// Split colours, in split order (cycled).
pub const SPLIT_COLORS: [Rgb; 6] =
    [[255, 160, 40], [60, 200, 255], [240, 90, 200], [140, 230, 80], [255, 230, 90], [180, 150, 255]];

/// One split's cameras.
pub struct SplitCameras<'a> {
    /// The split's name.
    pub name: &'a str,
    /// One camera per view (its pose and intrinsics).
    pub cameras: Vec<Camera>,
}

/// The subject: surface samples (world positions, sRGB colours) at one frame, and bounds over all frames.
pub struct Subject<'a> {
    /// Sample positions.
    pub points: &'a [[f32; 3]],
    /// Their colours.
    pub colors: &'a [[u8; 3]],
    /// The frame the samples are from.
    pub frame: usize,
    /// Bounds of the posed geometry over the dataset's frames.
    pub bounds: Option<(Vec3, Vec3)>,
}

/// How many of `cameras` see a sample outside their image (or behind them).
pub fn cropping(cameras: &[Camera], points: &[[f32; 3]]) -> usize {
    cameras
        .iter()
        .filter(|c| {
            let w2c = c.w2c();
            points.iter().any(|p| !c.shows(&w2c, DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)))
        })
        .count()
}

/// A panel: which world axes go right and up on it.
struct Panel {
    name: &'static str,
    right: usize,
    up: usize,
}

const PANELS: [Panel; 3] = [
    Panel { name: "top (looking down −Z)", right: 0, up: 1 },
    Panel { name: "front (looking along +Y)", right: 0, up: 2 },
    Panel { name: "side (looking along −X)", right: 1, up: 2 },
];

/// Draws the plot; `title` heads it.
pub fn draw(title: &str, splits: &[SplitCameras], subject: &Subject) -> Vec<u8> {
    const SIDE: u32 = 420;
    const PAD: u32 = 12;
    const HEAD: u32 = 34;
    let legend = 24 * (splits.len() as u32 + 2);
    let width = PAD + 3 * (SIDE + PAD);
    let height = HEAD + SIDE + 24 + legend;
    let mut c = Canvas::new(width, height, [24, 24, 28]);
    c.text(PAD as f32, 22.0, 15.0, title, [235, 235, 235]);

    // The extent every panel shows: cameras, bounds, samples and the origin, in one scale for all three.
    let mut pts: Vec<DVec3> = vec![DVec3::ZERO];
    for s in splits {
        pts.extend(s.cameras.iter().map(|c| c.c2w.w_axis.truncate()));
    }
    if let Some((lo, hi)) = subject.bounds {
        pts.push(lo.as_dvec3());
        pts.push(hi.as_dvec3());
    }
    pts.extend(subject.points.iter().map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)));
    let pts: Vec<DVec3> = pts.into_iter().filter(|p| p.is_finite()).collect();
    let lo = pts.iter().fold(DVec3::splat(f64::INFINITY), |a, p| a.min(*p));
    let hi = pts.iter().fold(DVec3::splat(f64::NEG_INFINITY), |a, p| a.max(*p));
    let centre = (lo + hi) * 0.5;
    let extent = (hi - lo).max_element().max(1e-6);
    let scale = (SIDE as f64 - 2.0 * PAD as f64) / extent;
    // Frusta are drawn a fixed share of the scene deep, so they read at any scale.
    let depth = 0.08 * extent;

    for (k, panel) in PANELS.iter().enumerate() {
        let ox = (PAD + k as u32 * (SIDE + PAD)) as f32;
        let oy = HEAD as f32;
        c.fill(ox as i64, oy as i64, SIDE as i64, SIDE as i64, [36, 36, 42]);
        let to_px = |p: DVec3| -> (f32, f32) {
            let (r, u) = (p[panel.right] - centre[panel.right], p[panel.up] - centre[panel.up]);
            (ox + SIDE as f32 / 2.0 + (r * scale) as f32, oy + SIDE as f32 / 2.0 - (u * scale) as f32)
        };
        for (p, col) in subject.points.iter().zip(subject.colors) {
            let (x, y) = to_px(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
            c.dot(x, y, 0.7, *col, 0.5);
        }
        if let Some((lo, hi)) = subject.bounds {
            let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
            let corner = |r: f64, u: f64| {
                let mut p = centre;
                p[panel.right] = r;
                p[panel.up] = u;
                to_px(p)
            };
            let (a, b) = (corner(lo[panel.right], lo[panel.up]), corner(hi[panel.right], hi[panel.up]));
            for (p, q) in [(a, (b.0, a.1)), ((b.0, a.1), b), (b, (a.0, b.1)), ((a.0, b.1), a)] {
                c.line(p, q, [235, 235, 235], 0.8);
            }
        }
        // World axes from the origin, a quarter of the extent long.
        for (axis, (name, color)) in
            [("X", [230, 70, 70]), ("Y", [80, 210, 90]), ("Z  up", [90, 140, 255])].iter().enumerate()
        {
            if axis != panel.right && axis != panel.up {
                continue;
            }
            let mut tip = DVec3::ZERO;
            tip[axis] = 0.25 * extent;
            let (a, b) = (to_px(DVec3::ZERO), to_px(tip));
            c.line(a, b, *color, 1.0);
            c.dot(b.0, b.1, 2.5, *color, 1.0);
            c.text(b.0 + 4.0, b.1 - 4.0, 12.0, name, *color);
        }
        for (si, s) in splits.iter().enumerate() {
            let color = SPLIT_COLORS[si % SPLIT_COLORS.len()];
            for cam in &s.cameras {
                let apex = cam.c2w.w_axis.truncate();
                let corners = [
                    (0.0, 0.0),
                    (cam.width as f64, 0.0),
                    (cam.width as f64, cam.height as f64),
                    (0.0, cam.height as f64),
                ]
                .map(|(u, v)| {
                    let dir = DVec3::new((u - cam.cx) / cam.fx, -(v - cam.cy) / cam.fy, -1.0);
                    to_px(cam.c2w.transform_point3(dir * depth))
                });
                let a = to_px(apex);
                for (i, q) in corners.iter().enumerate() {
                    c.line(a, *q, color, 0.7);
                    c.line(*q, corners[(i + 1) % 4], color, 0.7);
                }
            }
        }
        c.frame(ox as i64, oy as i64, SIDE as i64, SIDE as i64, [70, 70, 78]);
        c.text(ox + 6.0, oy + SIDE as f32 + 17.0, 12.0, panel.name, [190, 190, 190]);
    }

    // Legend: splits with their colours and crop counts, then the subject.
    let mut y = (HEAD + SIDE + 24 + 18) as f32;
    for (si, s) in splits.iter().enumerate() {
        let color = SPLIT_COLORS[si % SPLIT_COLORS.len()];
        c.fill(PAD as i64, y as i64 - 10, 14, 10, color);
        let crops = cropping(&s.cameras, subject.points);
        let (text, tint) = if subject.points.is_empty() {
            (format!("{}: {} cameras", s.name, s.cameras.len()), [220, 220, 220])
        } else if crops == 0 {
            (format!("{}: {} cameras, each sees the whole subject", s.name, s.cameras.len()), [220, 220, 220])
        } else {
            (
                format!(
                    "{}: {} cameras; {crops} crop the subject (cut off at the image edge)",
                    s.name,
                    s.cameras.len()
                ),
                [255, 110, 90],
            )
        };
        c.text(PAD as f32 + 22.0, y, 13.0, &text, tint);
        y += 24.0;
    }
    let size = subject.bounds.map(|(lo, hi)| hi - lo);
    let text = match size {
        Some(d) => format!(
            "subject: box = bounds over all frames ({:.2} × {:.2} × {:.2}, x × y × z); dots = surface samples at frame {}; world +Z is up",
            d.x, d.y, d.z, subject.frame
        ),
        None => "subject: empty".to_string(),
    };
    c.text(PAD as f32, y, 13.0, &text, [200, 200, 200]);
    c.png()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;

    fn cam(eye: Vec3) -> Camera {
        let c2w = Camera::look_at(eye, Vec3::ZERO, Vec3::Z);
        Camera { width: 100, height: 100, fx: 100.0, fy: 100.0, cx: 50.0, cy: 50.0, near: 0.1, far: 100.0, c2w }
    }

    #[test]
    fn a_camera_too_close_crops_and_one_far_enough_does_not() {
        let subject = [[0.5, 0.0, 0.0], [-0.5, 0.0, 0.0], [0.0, 0.0, 0.5]];
        let far = cam(Vec3::new(0.0, -4.0, 0.0));
        let near = cam(Vec3::new(0.0, -0.6, 0.0));
        let away =
            Camera { c2w: Camera::look_at(Vec3::new(0.0, -4.0, 0.0), Vec3::new(0.0, -8.0, 0.0), Vec3::Z), ..far };
        assert_eq!(cropping(&[far], &subject), 0);
        assert_eq!(cropping(&[near], &subject), 1);
        assert_eq!(cropping(&[far, near, away], &subject), 2);
    }
}
