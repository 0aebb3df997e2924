//! The point-cloud strip: a few frames of a `ply-sequence` output, read back from the PLY files the dataset
//! holds and drawn by the project's own renderer from one fixed camera, so motion, colour and density (holes,
//! a voxel grid too coarse) show side by side.

use glam::{Vec3, Vec4};

use super::canvas::{Canvas, RgbaPixels};
use crate::camera::Camera;
use crate::render::{self, RenderSettings, Shading, SplatSettings, SplatShape, SplatSize};
use crate::scene::material::{srgb_to_linear, Material};
use crate::scene::ply::{self, PlyData};
use crate::scene::{PosedScene, PrimKind};

/// Each frame's picture, square, in pixels.
const SIDE: u32 = 240;

/// Why a strip cannot be drawn.
#[derive(Debug, thiserror::Error)]
#[error("frame {frame}: the point-cloud file does not read back")]
pub struct Error {
    frame: usize,
    #[source]
    source: ply::PlyError,
}

/// Draws frames `frames` (scene frame numbers) from their PLY files `plys`; `title` heads the strip.
pub fn draw(title: &str, frames: &[usize], plys: &[Vec<u8>]) -> Result<Vec<u8>, Error> {
    let clouds: Vec<PlyData> = frames
        .iter()
        .zip(plys)
        .map(|(&frame, b)| ply::read(b).map_err(|source| Error { frame, source }))
        .collect::<Result<_, _>>()?;
    // One camera for every frame, framing the union of their points: a front three-quarter view, +Z up.
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in clouds.iter().flat_map(|c| c.positions.iter()) {
        let p = Vec3::from_array(*p);
        if p.is_finite() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    let (centre, radius) =
        if lo.x <= hi.x { ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-6)) } else { (Vec3::ZERO, 1.0) };
    // A 40° field of view, far enough back that the bounding sphere fits with a margin.
    let f = SIDE as f64 / 2.0 / (20f64.to_radians()).tan();
    let distance = radius / (18f32.to_radians()).sin();
    let eye = centre + Vec3::new(0.6, -1.0, 0.35).normalize() * distance;
    let camera = Camera {
        width: SIDE,
        height: SIDE,
        fx: f,
        fy: f,
        cx: SIDE as f64 / 2.0,
        cy: SIDE as f64 / 2.0,
        near: (distance - 2.0 * radius).max(distance * 1e-3) as f64,
        far: (distance + 2.0 * radius) as f64,
        c2w: Camera::look_at(eye, centre, Vec3::Z),
    };
    let settings = RenderSettings {
        samples: 4,
        shading: Shading::Unlit,
        splat: SplatSettings { shape: SplatShape::Square, size: SplatSize::Pixels(1.5), min_px: 1.0 },
        ..RenderSettings::default()
    };
    let (pad, head, label) = (8u32, 34u32, 20u32);
    let width = pad + clouds.len().max(1) as u32 * (SIDE + pad);
    let mut c = Canvas::new(width, head + SIDE + label + pad, [32, 32, 36]);
    c.text(pad as f32, 22.0, 15.0, title, [235, 235, 235]);
    for (k, (cloud, &frame)) in clouds.into_iter().zip(frames).enumerate() {
        let n = cloud.positions.len();
        let colors = match &cloud.colors {
            Some(cs) => cs
                .iter()
                .map(|c| {
                    Vec4::new(
                        srgb_to_linear(c[0] as f32 / 255.0),
                        srgb_to_linear(c[1] as f32 / 255.0),
                        srgb_to_linear(c[2] as f32 / 255.0),
                        1.0,
                    )
                })
                .collect(),
            None => Vec::new(),
        };
        let positions: Vec<Vec3> = cloud.positions.iter().map(|p| Vec3::from_array(*p)).collect();
        let scene = PosedScene::single(
            PrimKind::Points,
            positions,
            vec![Vec3::ZERO; n],
            colors,
            Vec::new(),
            Material::default(),
        );
        let picture = render::render(&scene, &camera, &settings);
        let x = (pad + k as u32 * (SIDE + pad)) as i64;
        c.image_rgba(x, head as i64, SIDE, SIDE, RgbaPixels { px: &picture.rgba, width: SIDE, height: SIDE });
        let text = format!("frame {frame} · {n} points");
        c.text(x as f32 + 2.0, (head + SIDE + 15) as f32, 12.0, &text, [200, 200, 200]);
    }
    Ok(c.png())
}
