//! The glossy lobe's occlusion: how much of the environment's specular light reaches a glossy surface. A rough
//! lobe, about the whole hemisphere, is occluded as the hemisphere is; a glossy one looks along its own narrow
//! reflection, with rays where the frame has a ray tree, so that a wall under an overhang mirrors the overhang
//! seen from below and the open sky seen from above.

use glam::Vec3;

use super::{brdf, environment, FrameLight, Surface};
use crate::scene::material::Material;
use crate::scene::{PosedScene, PrimKind};

/// How a glossy lobe's occlusion is found ([`FrameLight::shade_lobe`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lobe {
    /// By the lobe's own rays ([`super::rays::Tracer::lobe_visibility`]), where the frame has a ray tree and the lobe
    /// is glossy enough.
    Rays,
    /// As rays found it already: the share of the lobe open to the environment (agreeing neighbours', see
    /// `raster::lit`), so no ray is cast.
    Found(f32),
    /// By the hemisphere's occlusion alone, as a rough lobe is: a transparent (`BLEND`) surface's, shaded per
    /// sample and per layer. A glass of 32 nested shells cast 8 rays per sample per layer, and its renders took
    /// twelve times as long.
    Hemisphere,
}

impl FrameLight {
    /// How much of the environment's specular light reaches a lobe of perceptual `roughness` about unit normal
    /// `n` at `p`, seen from `v`, under the environment's occlusion `occlusion` (the material's ambient occlusion
    /// times the vertices' visibility), and what the lobe's rays found when it cast them. A glossy lobe
    /// ([`GLOSSY_RAYS`]) looks along itself with rays ([`super::rays::Tracer::lobe_visibility`]), or takes `given`,
    /// their answer found already; a rough one, whose lobe is about the hemisphere, reads the hemisphere's
    /// occlusion (`specular_occlusion`); between the two, a blend. The rays leave the occlusion texture out: it
    /// bakes the same geometry's occlusion they meet (FlightHelmet's, multiplied in, was 2 % dark against Cycles,
    /// which Blender's importer does not give the texture to).
    #[inline]
    pub(super) fn lobe_occlusion(
        &self,
        p: Vec3,
        n: Vec3,
        v: Vec3,
        roughness: f32,
        occlusion: f32,
        lobe: Lobe,
    ) -> (f32, Option<f32>) {
        let hemisphere = specular_occlusion(n.dot(v), occlusion, roughness);
        let rays = 1.0 - environment::smoothstep(GLOSSY_RAYS.0, GLOSSY_RAYS.1, roughness);
        let Some(tracer) = self.tracer.as_ref().filter(|_| rays > 0.0 && lobe != Lobe::Hemisphere) else {
            return (hemisphere, None);
        };
        let a = roughness.max(brdf::MIN_ROUGHNESS).powi(2);
        let open = match lobe {
            Lobe::Found(open) => Some(open),
            _ => tracer.lobe_visibility(p, n, v, a),
        };
        (open.map_or(hemisphere, |open| hemisphere + (open - hemisphere) * rays), open)
    }
}

/// How much of the environment's specular light a glossy lobe keeps where occlusion `occlusion` (of the
/// cosine-weighted hemisphere) reaches the diffuse layer, seen at n·v = `nv`, for perceptual `roughness`: Lagarde
/// and de Rousiers' fit ("Moving Frostbite to physically based rendering", 2014, with their roughness α). A
/// rough lobe is occluded as the hemisphere is; a glossy one, looking along its narrow reflection, less so. The
/// hemisphere's occlusion on every lobe made FlightHelmet's glossy hose 20 % dark against Cycles.
#[inline]
fn specular_occlusion(nv: f32, occlusion: f32, roughness: f32) -> f32 {
    let a = roughness.max(brdf::MIN_ROUGHNESS).powi(2);
    ((nv.max(0.0) + occlusion).powf((-16.0 * a - 1.0).exp2()) - 1.0 + occlusion).clamp(0.0, 1.0)
}

/// Perceptual roughness below which a specular lobe's occlusion is looked up with rays alone, and above which
/// with the hemisphere's occlusion alone (see [`FrameLight::lobe_occlusion`]). Against Cycles on FlightHelmet, rays
/// on every lobe below 0.7 or below 0.9 scored the same; a rough lobe's rays would cost as much for no gain.
const GLOSSY_RAYS: (f32, f32) = (0.5, 0.8);

/// Whether a surface of `scene` may have a lobe glossy enough for rays ([`GLOSSY_RAYS`]): a specular layer and a
/// roughness below the rough end, or a roughness texture (which scales the roughness down). CesiumMan's
/// (roughness 1, untextured) has none, and its frames build no ray-tracing tree for it.
pub(super) fn may_be_glossy(scene: &PosedScene) -> bool {
    scene.primitives.iter().filter(|p| p.kind == PrimKind::Triangles).any(|p| glossy(scene.material(p.material)))
}

/// Whether material `m` may have a lobe glossy enough for rays ([`may_be_glossy`]).
pub fn glossy(m: &Material) -> bool {
    let surface = Surface {
        base: Vec3::ONE,
        metallic: m.metallic,
        roughness: m.roughness,
        specular: m.specular,
        f0: m.specular_f0,
    };
    surface.specular_weight() > 0.0 && (m.roughness < GLOSSY_RAYS.1 || m.metallic_roughness_texture.is_some())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::light::PointCasters;

    #[test]
    fn a_glossy_lobe_is_occluded_less_than_the_hemisphere_and_a_rough_one_as_much() {
        for occlusion in [0.0, 0.3, 0.7, 1.0] {
            // Rough: the hemisphere's occlusion; open stays open, closed stays closed at any roughness.
            assert!((specular_occlusion(0.8, occlusion, 1.0) - occlusion).abs() < 1e-3, "{occlusion}");
            assert_eq!(specular_occlusion(0.3, 1.0, 0.2), 1.0);
            assert_eq!(specular_occlusion(0.3, 0.0, 0.2), 0.0);
        }
        // Glossy, looking straight on: more than the hemisphere keeps; less the more grazing the view (the lobe
        // then leans toward the horizon, where occluders are).
        let (straight, grazing) = (specular_occlusion(1.0, 0.5, 0.2), specular_occlusion(0.1, 0.5, 0.2));
        assert!(straight > 0.6 && grazing < 0.5, "{straight} {grazing}");
    }

    #[test]
    fn a_glossy_lobe_looks_along_itself_for_what_blocks_it() {
        // A wall facing +X (x = 0, 2 m square) under an overhang 1.2 m over the point looked at (a roof from
        // the wall out to x = 3). The point's hemisphere is as occluded for every view; its reflection is not:
        // seen from below, the wall mirrors the overhang; from above, the open space below it.
        let quad = |corners: [Vec3; 4], normal: Vec3, roughness: f32| {
            let m = crate::scene::material::Material { roughness, metallic: 1.0, ..Default::default() };
            PosedScene::quad(corners, normal, m)
        };
        let scene_of = |roughness: f32| {
            let wall = [
                Vec3::new(0.0, -1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 2.0),
                Vec3::new(0.0, -1.0, 2.0),
            ];
            let roof = [
                Vec3::new(0.0, -1.0, 2.2),
                Vec3::new(3.0, -1.0, 2.2),
                Vec3::new(3.0, 1.0, 2.2),
                Vec3::new(0.0, 1.0, 2.2),
            ];
            let mut scene = PosedScene::default();
            crate::scene::merge(&[quad(wall, Vec3::X, roughness), quad(roof, -Vec3::Z, roughness)], &mut scene);
            scene
        };
        let (p, n, hemisphere) = (Vec3::new(0.0, 0.0, 1.0), Vec3::X, 0.6);
        let seen_from = |r: Vec3| 2.0 * n.dot(r) * n - r;
        let (below, above) =
            (seen_from(Vec3::new(1.0, 0.0, 1.0).normalize()), seen_from(Vec3::new(1.0, 0.0, -1.0).normalize()));
        let studio = || crate::render::Environment::default().studio();
        let glossy = FrameLight::prepare(&scene_of(0.2), &[], studio(), PointCasters::NONE).with_bounce(&scene_of(0.2));
        assert!(glossy.tracer.is_some());
        let lobe = |light: &FrameLight, v: Vec3, roughness: f32| {
            light.lobe_occlusion(p, n, v, roughness, hemisphere, Lobe::Rays)
        };
        let ((up, found_up), (down, found_down)) = (lobe(&glossy, below, 0.2), lobe(&glossy, above, 0.2));
        assert!(up < 0.05 && down > 0.95, "mirroring the roof {up}, the open space {down}");
        // What the rays found comes back with the answer; given, it stands for them (no ray is cast).
        assert_eq!((found_up, found_down), (Some(up), Some(down)));
        assert_eq!(glossy.lobe_occlusion(p, n, below, 0.2, hemisphere, Lobe::Found(down)), (down, Some(down)));
        // The hemisphere's occlusion alone cannot tell the two apart.
        let (a, b) =
            (specular_occlusion(n.dot(below), hemisphere, 0.2), specular_occlusion(n.dot(above), hemisphere, 0.2));
        assert!((a - b).abs() < 1e-6 && a > 0.3 && a < 0.9, "{a} {b}");
        // A transparent layer's lobe reads the hemisphere's, with the tree at hand: no ray is cast.
        assert_eq!(glossy.lobe_occlusion(p, n, below, 0.2, hemisphere, Lobe::Hemisphere), (a, None));
        // A rough lobe, about the whole hemisphere, reads the hemisphere's occlusion, without rays.
        for v in [below, above] {
            assert_eq!(lobe(&glossy, v, 0.9), (specular_occlusion(n.dot(v), hemisphere, 0.9), None));
        }
        // Between glossy and rough, between the two.
        let (mid, traced) = (lobe(&glossy, below, 0.65).0, lobe(&glossy, below, 0.5).0);
        let rough = specular_occlusion(n.dot(below), hemisphere, 0.65);
        assert!(mid > traced.min(rough) && mid < traced.max(rough), "{traced} < {mid} < {rough}");
        // Surfaces that cannot be glossy (roughness 1, no roughness texture: CesiumMan's) make no tree, and keep
        // the hemisphere's occlusion.
        let rough_scene =
            FrameLight::prepare(&scene_of(1.0), &[], studio(), PointCasters::NONE).with_bounce(&scene_of(1.0));
        assert!(rough_scene.tracer.is_none());
        assert_eq!(lobe(&rough_scene, below, 0.2), (a, None));
    }
}
