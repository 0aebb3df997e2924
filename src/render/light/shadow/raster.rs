//! Drawing a frame's casters into a shadow map: each opaque triangle's nearest depth, in bands of rows side by
//! side, and each transparent one into the glass layer with the light it passes.

use glam::Vec3;
use rayon::prelude::*;

use super::{Glass, Projection, ShadowMap};
use crate::render::light::scan::{Scan, SCAN_RUN};
use crate::scene::PosedScene;

impl ShadowMap {
    /// Draws the frame's casters into the map: opaque triangles' nearest depth (cut-outs' holes left open),
    /// transparent ones into the glass layer.
    pub(super) fn rasterize(&mut self, scene: &PosedScene) {
        let (size, persp) = (self.size, matches!(self.projection, Projection::Persp { .. }));
        // The casters projected once, and per triangle whether it is glass (a transparent triangle passes 1 − α of
        // the light: into the glass layer, not the depth map).
        #[allow(clippy::type_complexity)]
        let casters: Vec<(
            &crate::scene::PosedPrimitive,
            Vec<Vec3>,
            Vec<bool>,
            Option<super::super::cutout::Cutout>,
        )> = scene
            .primitives
            .iter()
            .filter(|prim| super::super::is_caster(scene, prim))
            .map(|prim| {
                let light: Vec<Vec3> = prim.positions.iter().map(|&p| self.project(p)).collect();
                let blend = scene
                    .materials
                    .get(prim.material as usize)
                    .filter(|m| m.alpha_mode == crate::scene::material::AlphaMode::Blend);
                let mut glass = Vec::new();
                if let Some(m) = blend {
                    for t in prim.indices.chunks_exact(3) {
                        let alpha = triangle_alpha(scene, prim, m, t);
                        glass.push(alpha < 1.0);
                        if alpha >= 1.0 {
                            continue;
                        }
                        let n = (size * size) as usize;
                        let g = self.glass.get_or_insert_with(|| Glass {
                            depth: vec![f32::INFINITY; n],
                            pass: vec![1.0; n],
                            mins: Vec::new(),
                        });
                        let v = [light[t[0] as usize], light[t[1] as usize], light[t[2] as usize]];
                        // Strictly inside (half-open edges would count a texel on a shared edge twice, squaring
                        // 1 − α).
                        if let Some(t) = Scan::new(v, size, persp, 0.0) {
                            t.rows(size, (0, size), |i, d, _| {
                                g.depth[i] = g.depth[i].min(d);
                                g.pass[i] *= 1.0 - alpha;
                            });
                        }
                    }
                }
                (prim, light, glass, super::super::cutout::Cutout::of(scene, prim))
            })
            .collect();
        // Each opaque triangle set up once, in the casters' order: its bounds, area and depths (set up in every
        // band below, with libm's floor and ceil, this was a sixth of FlightHelmet's lit frame). In runs of
        // `SCAN_RUN`, so that a mesh of millions of triangles holds a run's set-ups at a time, not all of them.
        let mut opaque = casters.iter().enumerate().flat_map(|(c, (prim, light, glass, _))| {
            prim.indices.chunks_exact(3).enumerate().filter_map(move |(k, t)| {
                if glass.get(k) == Some(&true) {
                    return None;
                }
                let v = [light[t[0] as usize], light[t[1] as usize], light[t[2] as usize]];
                // A texel whose centre any triangle touches counts (conservative by a hair: casters thinner than a
                // texel still cast).
                Scan::new(v, size, persp, -1e-4).map(|s| (c, [t[0], t[1], t[2]], s))
            })
        });
        // Each run's triangles in bands of rows side by side, each band drawing those whose rows reach it: a texel
        // keeps the least depth over it, which no order changes, so the map is the same bits as one pass over it
        // (a sun's 2048² map on one thread held up every view of its frame).
        let band = size.div_ceil(8).max(1);
        loop {
            let run: Vec<(usize, [u32; 3], Scan)> = opaque.by_ref().take(SCAN_RUN).collect();
            if run.is_empty() {
                break;
            }
            self.depth.par_chunks_mut((band * size) as usize).enumerate().for_each(|(b, depth)| {
                let rows = (b as u32 * band, ((b as u32 + 1) * band).min(size));
                let first = (rows.0 * size) as usize;
                for (c, corners, t) in &run {
                    if t.y.0 >= rows.1 || t.y.1 < rows.0 {
                        continue;
                    }
                    // Unless a cut-out's alpha leaves a hole there.
                    let cutout = casters[*c].3.as_ref();
                    t.rows(size, rows, |i, d, w| {
                        let i = i - first;
                        if d < depth[i] && cutout.is_none_or(|c| c.holds(*corners, w)) {
                            depth[i] = d;
                        }
                    });
                }
            });
        }
    }
}

/// A transparent triangle's alpha: its material's factor times the mean alpha of its corners' vertex colours
/// and base-colour texture (read at the corners' uvs).
fn triangle_alpha(
    scene: &PosedScene,
    prim: &crate::scene::PosedPrimitive,
    m: &crate::scene::material::Material,
    t: &[u32],
) -> f32 {
    let mut a = m.base_color.w;
    if prim.colors.len() == prim.positions.len() {
        a *= t.iter().map(|&i| prim.colors[i as usize].w).sum::<f32>() / 3.0;
    }
    let texture = m.base_color_texture.and_then(|r| scene.textures.get(r.texture as usize).map(|tex| (r, tex)));
    if let (Some((r, tex)), true) = (texture, prim.uvs.len() == prim.positions.len()) {
        a *= t.iter().map(|&i| tex.sample(&r, prim.uvs[i as usize]).w).sum::<f32>() / 3.0;
    }
    a.clamp(0.0, 1.0)
}
