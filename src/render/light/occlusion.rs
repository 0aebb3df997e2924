//! The environment's occlusion: parallel shadow maps from directions over the sphere, weighted by the map's
//! brightness there ([`occlusion_maps`]), and the share of the environment's light that reaches a point past the
//! casters ([`FrameLight::environment_visibility`]), which every vertex and ground cell keeps.

use std::f32::consts::PI;

use glam::Vec3;
use rayon::prelude::*;

use super::shadow::{PointCasters, ShadowMap};
use super::{EnvLight, FrameLight};
use crate::scene::PosedScene;

/// Directions the environment's visibility is sampled in, and the side of each direction's map.
const ENV_DIRECTIONS: usize = 32;
/// Each direction stands for a cone of the sphere's 1/32 (half-angle acos(1 − 1/16) ≈ 20.4°): its shadows are
/// as soft as a light that wide (the tangent of the half-angle), so 32 directions blend into one smooth occlusion
/// instead of 32 faint copies of the subject's outline.
const ENV_CONE: f32 = 0.372;
const ENV_MAP: u32 = 256;

/// `n` directions spread evenly over the sphere (a Fibonacci lattice).
fn sphere_directions(n: usize) -> Vec<Vec3> {
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f32 + 1.0) / n as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = i as f32 * PI * (3.0 - 5f32.sqrt());
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// The environment's occlusion maps: [`ENV_DIRECTIONS`] parallel shadow maps from directions over the sphere,
/// each weighted by the environment's brightness there (so a bright sky above shadows more than a dark floor);
/// plain points cast as `points` says.
pub(super) fn occlusion_maps(
    scene: &PosedScene,
    env: &EnvLight,
    bounds: (Vec3, Vec3),
    points: PointCasters,
) -> Vec<(Vec3, f32, ShadowMap)> {
    let roughest = env.prefiltered.levels.last();
    sphere_directions(ENV_DIRECTIONS)
        .par_iter()
        .map(|&d| {
            let w =
                roughest.map_or(1.0, |m| m.radiance(env.rotation * d).dot(Vec3::new(0.2126, 0.7152, 0.0722))).max(1e-6);
            (d, w, ShadowMap::sun(scene, -d, bounds, ENV_MAP, points))
        })
        .collect()
}

impl FrameLight {
    /// The fraction of the environment's light (weighted by where it comes from and by the cosine to `n`) that
    /// reaches `p` past the casters. The hemisphere `n` faces is the one that counts (a double-sided surface seen
    /// from behind, such as the ground's underside, is shaded with its front's visibility).
    pub fn environment_visibility(&self, p: Vec3, n: Vec3) -> f32 {
        let (mut lit, mut all) = (0.0, 0.0);
        for (d, w, m) in &self.occlusion {
            let c = n.dot(*d) * w;
            if c <= 0.0 {
                continue;
            }
            all += c;
            lit += c * m.visibility(p, n, ENV_CONE);
        }
        if all > 0.0 {
            lit / all
        } else {
            1.0
        }
    }
}
