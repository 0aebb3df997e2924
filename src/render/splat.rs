//! Point splats: screen-aligned squares and disks (one depth per splat, depth-tested against everything),
//! and cubes, expanded into the camera-facing faces of a true 3D cube and drawn as triangles.

use glam::{Vec3, Vec4};

use super::raster::{Projection, SUBPIXEL};
use crate::scene::{PosedScene, PrimKind};

/// Splat shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// A 3D cube centred on the point.
    Cube,
    /// A screen-aligned square.
    Square,
    /// A screen-aligned disk.
    Disk,
}

/// Splat size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Size {
    /// Edge (cube, square) or diameter (disk) in world units.
    World(f32),
    /// Edge or diameter in pixels.
    Pixels(f32),
}

/// How points are drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplatSettings {
    /// Shape.
    pub shape: Shape,
    /// Size.
    pub size: Size,
}

impl Default for SplatSettings {
    fn default() -> Self {
        SplatSettings { shape: Shape::Square, size: Size::Pixels(1.0) }
    }
}

/// A screen-space splat, in fixed-point sample coordinates.
#[derive(Debug, Clone, Copy)]
pub struct Splat {
    x: i64,
    y: i64,
    r: i64,
    /// View depth.
    pub z: f32,
    /// Linear colour.
    pub color: Vec4,
    /// World normal.
    pub normal: Vec3,
    /// Object id.
    pub object: u32,
    /// Inclusive sample bounding box.
    pub bbox: [i64; 4],
    disk: bool,
}

/// Screen-space splats for every point primitive (squares and disks; cubes are triangles, see [`cube_faces`]).
pub fn setup(scene: &PosedScene, p: &Projection, s: &SplatSettings, k: f32) -> Vec<Splat> {
    let mut out = Vec::new();
    if s.shape == Shape::Cube {
        return out;
    }
    let [fx, fy, cx, cy] = p.f;
    for prim in scene.primitives.iter().filter(|q| q.kind == PrimKind::Points) {
        let base = scene.materials.get(prim.material as usize).map_or(Vec4::ONE, |m| m.base_color);
        for (i, pos) in prim.positions.iter().enumerate() {
            let v = p.w2c.transform_point3(*pos);
            let z = -v.z;
            if !(z >= p.near && z <= p.far) {
                continue;
            }
            let (sx, sy) = (cx + fx * v.x / z, cy - fy * v.y / z);
            let half = match s.size {
                Size::World(w) => 0.5 * w * fx / z,
                Size::Pixels(px) => 0.5 * px * k,
            };
            let (x, y, r) = (
                (sx * SUBPIXEL as f32).round() as i64,
                (sy * SUBPIXEL as f32).round() as i64,
                (half * SUBPIXEL as f32).round() as i64,
            );
            let bbox = [
                ((x - r) / SUBPIXEL - 1).max(0),
                ((y - r) / SUBPIXEL - 1).max(0),
                ((x + r) / SUBPIXEL + 1).min(p.size.0 - 1),
                ((y + r) / SUBPIXEL + 1).min(p.size.1 - 1),
            ];
            if r <= 0 || bbox[0] > bbox[2] || bbox[1] > bbox[3] {
                continue;
            }
            let color = base * prim.colors.get(i).copied().unwrap_or(Vec4::ONE);
            out.push(Splat {
                x,
                y,
                r,
                z,
                color,
                normal: prim.normals[i],
                object: prim.object,
                bbox,
                disk: s.shape == Shape::Disk,
            });
        }
    }
    out
}

impl Splat {
    /// Whether the sample centre (fixed point) is covered. Squares are half-open so that splats one size
    /// apart tile without double hits.
    #[inline]
    pub fn covers(&self, px: i64, py: i64) -> bool {
        let (dx, dy) = (px - self.x, py - self.y);
        if self.disk {
            dx * dx + dy * dy < self.r * self.r
        } else {
            dx >= -self.r && dx < self.r && dy >= -self.r && dy < self.r
        }
    }
}

/// The camera-facing faces of a cube of edge `size` around each point, as a triangle scene with the points'
/// colours (flat, unlit: the colour goes to the vertex colours, the face normal to the normals).
pub fn cube_faces(scene: &PosedScene, eye: Vec3, size: f32) -> PosedScene {
    use std::sync::Arc;
    let h = 0.5 * size;
    let axes = [Vec3::X, Vec3::Y, Vec3::Z];
    let mut out =
        PosedScene { materials: scene.materials.clone(), textures: scene.textures.clone(), primitives: Vec::new() };
    for prim in scene.primitives.iter().filter(|q| q.kind == PrimKind::Points) {
        let (mut pos, mut nrm, mut col, mut idx) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (i, c) in prim.positions.iter().enumerate() {
            let color = prim.colors.get(i).copied().unwrap_or(Vec4::ONE);
            for (a, axis) in axes.iter().enumerate() {
                // Of the two faces along this axis, at most the one toward the eye can be seen, and only when the eye
                // is outside its plane.
                let sign = if (eye - *c).dot(*axis) >= 0.0 { 1.0 } else { -1.0 };
                let n = *axis * sign;
                if (eye - (*c + n * h)).dot(n) <= 0.0 {
                    continue;
                }
                let (u, v) = (axes[(a + 1) % 3] * h, axes[(a + 2) % 3] * h);
                let centre = *c + n * h;
                let base = pos.len() as u32;
                // Counter-clockwise seen from outside.
                let quad = if sign > 0.0 {
                    [centre - u - v, centre + u - v, centre + u + v, centre - u + v]
                } else {
                    [centre - u - v, centre - u + v, centre + u + v, centre + u - v]
                };
                pos.extend_from_slice(&quad);
                nrm.extend_from_slice(&[n; 4]);
                col.extend_from_slice(&[color; 4]);
                idx.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
            }
        }
        out.primitives.push(crate::scene::PosedPrimitive {
            kind: PrimKind::Triangles,
            positions: pos,
            normals: nrm,
            uvs: Arc::new(Vec::new()),
            colors: Arc::new(col),
            indices: Arc::new(idx),
            material: prim.material,
            object: prim.object,
        });
    }
    out
}
