//! The one camera model every stage shares: a pinhole with fx, fy, cx, cy in pixels (pixel centres at +0.5)
//! and a camera-to-world pose in the OpenGL/Blender convention (camera looks down −Z, +Y up; world +Z up).
//! The OpenCV/COLMAP conversion lives here, next to the model, so writers never re-derive it.

use glam::{DMat4, Mat4, Vec3};

/// A pinhole camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length, x, pixels.
    pub fx: f64,
    /// Focal length, y, pixels.
    pub fy: f64,
    /// Principal point x, pixels (image left edge = 0).
    pub cx: f64,
    /// Principal point y, pixels (image top edge = 0).
    pub cy: f64,
    /// Near clip distance.
    pub near: f64,
    /// Far clip distance.
    pub far: f64,
    /// Camera-to-world, OpenGL axes.
    pub c2w: DMat4,
}

/// `diag(1, -1, -1, 1)`: flips camera Y and Z between the OpenGL and OpenCV conventions.
pub const GL_TO_CV: DMat4 =
    DMat4::from_cols_array(&[1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);

impl Camera {
    /// A camera at `eye` looking at `target`, with image up as close to `up` as possible.
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> DMat4 {
        Self::look_at_f64(eye.as_dvec3(), target.as_dvec3(), up.as_dvec3())
    }

    /// [`Camera::look_at`] in double precision (what the rigs place cameras with).
    pub fn look_at_f64(eye: glam::DVec3, target: glam::DVec3, up: glam::DVec3) -> DMat4 {
        let back = (eye - target).normalize();
        // A view straight along `up` has no defined roll: fall back to world +Y as up.
        let up = if back.cross(up).length_squared() < 1e-12 { glam::DVec3::Y } else { up };
        let right = up.cross(back).normalize();
        let cam_up = back.cross(right);
        DMat4::from_cols(right.extend(0.0), cam_up.extend(0.0), back.extend(0.0), eye.extend(1.0))
    }

    /// World-to-camera (OpenGL axes).
    pub fn w2c(&self) -> DMat4 {
        self.c2w.inverse()
    }

    /// Camera-to-world in OpenCV/COLMAP axes (+X right, +Y down, +Z forward).
    pub fn c2w_opencv(&self) -> DMat4 {
        self.c2w * GL_TO_CV
    }

    /// World-to-camera in OpenCV/COLMAP axes (what COLMAP's images.txt stores).
    pub fn w2c_opencv(&self) -> DMat4 {
        self.c2w_opencv().inverse()
    }

    /// Horizontal field of view in radians (`camera_angle_x`).
    pub fn angle_x(&self) -> f64 {
        2.0 * (0.5 * self.width as f64 / self.fx).atan()
    }

    /// Projects a world point to continuous pixel coordinates (x right, y down; pixel (i, j) covers
    /// [i, i+1) × [j, j+1)) and its planar depth; `None` behind the camera.
    pub fn project(&self, p: Vec3) -> Option<(f64, f64, f64)> {
        let v = self.w2c().transform_point3(p.as_dvec3());
        let z = -v.z;
        (z > 0.0).then(|| (self.cx + self.fx * v.x / z, self.cy - self.fy * v.y / z, z))
    }

    /// Whether world point `p` is in front of the camera and projects inside the image (edges included);
    /// `w2c` is [`Camera::w2c`], computed once by a caller that tests many points.
    pub fn shows(&self, w2c: &DMat4, p: glam::DVec3) -> bool {
        let v = w2c.transform_point3(p);
        let z = -v.z;
        let (u, t) = (self.cx + self.fx * v.x / z, self.cy - self.fy * v.y / z);
        z > 0.0 && (0.0..=self.width as f64).contains(&u) && (0.0..=self.height as f64).contains(&t)
    }

    /// The world-to-camera matrix as f32, for the rasterizer.
    pub fn w2c_f32(&self) -> Mat4 {
        self.w2c().as_mat4()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opencv_projection_matches_opengl() {
        let c2w = Camera::look_at(Vec3::new(1.0, -4.0, 2.0), Vec3::ZERO, Vec3::Z);
        let cam =
            Camera { width: 800, height: 600, fx: 700.0, fy: 710.0, cx: 400.0, cy: 300.0, near: 0.1, far: 100.0, c2w };
        let p = Vec3::new(0.3, 0.2, -0.1);
        let (u, v, z) = cam.project(p).unwrap();
        // OpenCV: x_cam = R p + t, u = fx x/z + cx, v = fy y/z + cy.
        let q = cam.w2c_opencv().transform_point3(p.as_dvec3());
        assert!((q.z - z).abs() < 1e-9);
        assert!((cam.fx * q.x / q.z + cam.cx - u).abs() < 1e-9 && (cam.fy * q.y / q.z + cam.cy - v).abs() < 1e-9);
        // The target projects to the principal point.
        let (u, v, _) = cam.project(Vec3::ZERO).unwrap();
        assert!((u - 400.0).abs() < 1e-9 && (v - 300.0).abs() < 1e-9);
    }

    #[test]
    fn look_at_keeps_world_up_in_the_image() {
        let c2w = Camera::look_at(Vec3::new(0.0, -4.0, 0.0), Vec3::ZERO, Vec3::Z);
        let cam =
            Camera { width: 100, height: 100, fx: 100.0, fy: 100.0, cx: 50.0, cy: 50.0, near: 0.1, far: 10.0, c2w };
        let (_, v_top, _) = cam.project(Vec3::new(0.0, 0.0, 1.0)).unwrap();
        assert!(v_top < 50.0, "world +Z appears above the centre");
        let (u_right, _, _) = cam.project(Vec3::new(1.0, 0.0, 0.0)).unwrap();
        assert!(u_right > 50.0, "looking along +Y, world +X is to the right");
    }
}
