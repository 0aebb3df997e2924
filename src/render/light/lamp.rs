//! The frame's lights as its shading reads them ([`Lamp`]): where each one's light comes from at a point, how
//! much of it arrives (Blender's units and spot falloff), and its shadow maps over the casters.

use std::f32::consts::PI;

use glam::Vec3;
use rayon::prelude::*;

use super::environment;
use super::shadow::{self, PointCasters, ShadowMap};
use crate::scene::light::{Light, LightKind};
use crate::scene::PosedScene;

/// Side of a sun's shadow map, of a spot's, and of each face of a point light's cube.
const SUN_MAP: u32 = 2048;
const SPOT_MAP: u32 = 1024;
const POINT_MAP: u32 = 512;

/// A light as a frame's shading reads it.
#[derive(Debug)]
pub(super) struct Lamp {
    pub(super) light: Light,
    /// Its shadow maps: none (no shadows), one (sun, spot) or a cube's six (point).
    pub(super) maps: Vec<ShadowMap>,
    /// Its size as [`ShadowMap::visibility`] reads it: a sun's angular radius as a tangent, else its radius.
    pub(super) size: f32,
}

impl Lamp {
    /// The unit direction toward the light from `p`, and the radiance it brings there per unit of its colour ×
    /// intensity (before shadows).
    #[inline]
    pub(super) fn incidence(&self, p: Vec3) -> (Vec3, f32) {
        match self.light.kind {
            LightKind::Sun { direction, .. } => (-direction, 1.0),
            LightKind::Point { position, .. } => {
                let d = position - p;
                let d2 = d.length_squared().max(1e-8);
                (d / d2.sqrt(), 1.0 / (4.0 * PI * d2))
            }
            LightKind::Spot { position, direction, cone, blend, .. } => {
                let d = position - p;
                let d2 = d.length_squared().max(1e-8);
                let l = d / d2.sqrt();
                (l, spot_falloff(-l.dot(direction), cone, blend) / (4.0 * PI * d2))
            }
        }
    }

    /// The irradiance the light brings `p` on a surface of unit normal `n`, past its shadow casters.
    #[inline]
    pub(super) fn irradiance(&self, p: Vec3, n: Vec3) -> Vec3 {
        let (l, radiance) = self.incidence(p);
        let c = n.dot(l);
        if c <= 0.0 || radiance == 0.0 {
            return Vec3::ZERO;
        }
        self.light.color * (radiance * self.light.intensity * c * self.visibility(p, n))
    }

    /// The fraction of the light reaching `p` (unit normal `n`) past its shadow casters.
    #[inline]
    pub(super) fn visibility(&self, p: Vec3, n: Vec3) -> f32 {
        match (self.light.kind, self.maps.len()) {
            (_, 0) => 1.0,
            (LightKind::Point { position, .. }, 6) => {
                self.maps[shadow::cube_face(p - position)].visibility(p, n, self.size)
            }
            _ => self.maps[0].visibility(p, n, self.size),
        }
    }
}

/// The lights (`lights`, the manifest's, then the scene's own) with their shadow maps over the casters within
/// `bounds` (plain points casting as `points` says), made side by side.
pub(super) fn lamps(
    scene: &PosedScene,
    lights: &[Light],
    bounds: Option<(Vec3, Vec3)>,
    points: PointCasters,
) -> Vec<Lamp> {
    let all: Vec<&Light> = lights.iter().chain(&scene.lights).collect();
    all.par_iter()
        .map(|l| {
            let maps = match (l.shadows, bounds) {
                (true, Some(b)) => match l.kind {
                    LightKind::Sun { direction, .. } => vec![ShadowMap::sun(scene, direction, b, SUN_MAP, points)],
                    LightKind::Spot { position, direction, cone, .. } => {
                        vec![ShadowMap::perspective(scene, position, direction, cone + 0.05, SPOT_MAP, points)]
                    }
                    LightKind::Point { position, .. } => shadow::CUBE
                        .iter()
                        .map(|&d| ShadowMap::perspective(scene, position, d, PI / 2.0 + 0.02, POINT_MAP, points))
                        .collect(),
                },
                _ => Vec::new(),
            };
            let size = match l.kind {
                LightKind::Sun { angle, .. } => (0.5 * angle).tan(),
                LightKind::Point { radius, .. } | LightKind::Spot { radius, .. } => radius,
            };
            Lamp { light: (*l).clone(), maps, size }
        })
        .collect()
}

/// Blender 3.x's spot falloff at `cos_angle` off the axis: the cosine itself inside the cone, smoothed to 0 over
/// the outer `blend` fraction.
fn spot_falloff(cos_angle: f32, cone: f32, blend: f32) -> f32 {
    let cos_half = (0.5 * cone).cos();
    let t = cos_angle - cos_half;
    if t <= 0.0 {
        return 0.0;
    }
    let smooth = (1.0 - cos_half) * blend;
    let mut a = cos_angle;
    if t < smooth {
        a *= environment::smoothstep(0.0, smooth, t);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blenders_spot_is_its_point_light_times_the_cosine_inside_the_cone() {
        let cone = 120f32.to_radians();
        assert!((spot_falloff(1.0, cone, 0.0) - 1.0).abs() < 1e-6);
        assert!((spot_falloff(0.9, cone, 0.0) - 0.9).abs() < 1e-6);
        assert_eq!(spot_falloff(0.4, cone, 0.0), 0.0);
        // Blend fades toward the edge.
        assert!(spot_falloff(0.55, cone, 1.0) < 0.1);
    }
}
