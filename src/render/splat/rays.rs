//! Per-sample rays for the splats drawn at their own size: cubes (where a ray enters the box, and through which
//! face) and surfels (where it meets the disk).

use glam::Vec3;

use crate::render::raster::Projection;

/// Per-sample rays of a band for cube splats: the reciprocal of each sample's world direction, scaled so that the
/// ray parameter is the planar view depth.
pub(super) struct Rays {
    inv: Vec<Vec3>,
}

impl Rays {
    /// Rays through the sample centres of the `w × h` samples at (`x0`, `y0`).
    pub(super) fn new(p: &Projection, x0: i64, y0: i64, w: i64, h: i64) -> Rays {
        let rot = glam::Mat3::from_mat4(p.w2c.inverse());
        let [fx, fy, cx, cy] = p.f;
        let mut inv = Vec::with_capacity((w * h) as usize);
        for sy in y0..y0 + h {
            for sx in x0..x0 + w {
                // Camera space, looking down −Z: z = −1 makes the ray parameter the planar depth.
                let d = Vec3::new((sx as f32 + 0.5 - cx) / fx, -(sy as f32 + 0.5 - cy) / fy, -1.0);
                inv.push((rot * d).recip());
            }
        }
        Rays { inv }
    }

    /// Where sample `i`'s ray meets the disk of radius `r` centred at `c` (relative to the eye) perpendicular to
    /// `n`: its planar depth, `None` on a miss or a ray parallel to the disk.
    #[inline]
    pub(super) fn disk_hit(&self, i: usize, c: Vec3, n: Vec3, r: f32) -> Option<f32> {
        let d = self.inv[i].recip();
        let nd = n.dot(d);
        if nd.abs() < 1e-12 {
            return None;
        }
        let t = n.dot(c) / nd;
        ((d * t - c).length_squared() <= r * r && t > 0.0).then_some(t)
    }

    /// Where sample `i`'s ray enters the cube (centre `c` relative to the eye, half edge `h`): planar depth and
    /// the entered face (an index into [`FACES`](super::FACES)); `None` on a miss.
    #[inline]
    pub(super) fn hit(&self, i: usize, c: Vec3, h: f32) -> Option<(f32, u8)> {
        let inv = self.inv[i];
        let t1 = (c - Vec3::splat(h)) * inv;
        let t2 = (c + Vec3::splat(h)) * inv;
        let (lo, hi) = (t1.min(t2), t1.max(t2));
        let enter = lo.max_element();
        if enter > hi.min_element() {
            return None;
        }
        // The entered face is on the axis that entered last, facing against the ray.
        let axis = if enter == lo.x {
            0
        } else if enter == lo.y {
            1
        } else {
            2
        };
        Some((enter, 2 * axis + (inv[axis as usize] < 0.0) as u8))
    }
}
