//! Execution: render the plan's images into the content-addressed store. Each frame is posed once and shared by
//! every view of that frame; views render and encode in parallel on the worker threads (PNG encoding costs as
//! much as rendering, so it must not serialize on one thread).

use glam::Vec3;
use rayon::prelude::*;

use crate::cache::{Digest, Store};
use crate::manifest::render::{NormalSpace, Pass, PngCompression, Render};
use crate::plan::{Image, Plan};
use crate::render::{self, encode, Frame, RenderSettings};
use crate::scene::{PosedScene, Poser, Scene};

/// The blobs of one rendered image, one per requested pass.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Rendered {
    /// RGBA8 PNG, straight alpha.
    pub rgba: Option<Digest>,
    /// 16-bit PNG, millimetres.
    pub depth: Option<Digest>,
    /// RGB8 PNG, `(n + 1) / 2`.
    pub normal: Option<Digest>,
    /// 8-bit PNG coverage.
    pub mask: Option<Digest>,
    /// 16-bit PNG instance ids (object + 1, 0 = background), with `mask` when the scene has several objects.
    pub instance: Option<Digest>,
}

/// Renders every image of `plan`; `done(n)` is called after each image with the count so far.
pub fn render_plan(
    scene: &Scene,
    plan: &Plan,
    r: &Render,
    store: &Store,
    done: &(dyn Fn(usize) + Sync),
) -> Result<Vec<Rendered>, String> {
    let settings = RenderSettings::from_manifest(r, scene.voxel_size());
    let mut out = vec![Rendered::default(); plan.images.len()];
    let mut poser = Poser::default();
    let count = std::sync::atomic::AtomicUsize::new(0);
    for (frame, images) in plan.by_frame() {
        let posed = scene.pose(frame, &mut poser)?;
        let objects = posed.primitives.iter().map(|p| p.object).max().map_or(0, |m| m + 1);
        let results: Vec<Result<Rendered, String>> = images
            .par_iter()
            .map(|&i| {
                let rendered = render_image(posed, &plan.images[i], r, &settings, objects > 1, store);
                done(count.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                rendered
            })
            .collect();
        for (&i, res) in images.iter().zip(results) {
            out[i] = res?;
        }
    }
    Ok(out)
}

/// Renders one image and stores its passes.
pub fn render_image(
    posed: &PosedScene,
    image: &Image,
    r: &Render,
    settings: &RenderSettings,
    instances: bool,
    store: &Store,
) -> Result<Rendered, String> {
    let f = render::render(posed, &image.camera, settings);
    let put = |bytes: Vec<u8>| store.put(&bytes).map_err(|e| format!("cache {}: {e}", store.root().display()));
    let mut out = Rendered::default();
    for pass in r.passes.get_ref() {
        for (slot, bytes) in encode_pass(&f, *pass, r, image, instances) {
            let d = Some(put(bytes)?);
            match slot {
                Slot::Rgba => out.rgba = d,
                Slot::Depth => out.depth = d,
                Slot::Normal => out.normal = d,
                Slot::Mask => out.mask = d,
                Slot::Instance => out.instance = d,
            }
        }
    }
    Ok(out)
}

enum Slot {
    Rgba,
    Depth,
    Normal,
    Mask,
    Instance,
}

fn encode_pass(f: &Frame, pass: Pass, r: &Render, image: &Image, instances: bool) -> Vec<(Slot, Vec<u8>)> {
    let (w, h, c): (u32, u32, PngCompression) = (f.width, f.height, r.png_compression);
    match pass {
        Pass::Rgba => vec![(Slot::Rgba, encode::rgba_png(&f.rgba, w, h, c))],
        Pass::Depth => vec![(Slot::Depth, encode::depth_mm_png(&f.depth, w, h, c))],
        Pass::Normal => {
            // Camera space: the inverse rotation of the (orthonormal) camera-to-world.
            let rot = glam::DMat3::from_mat4(image.camera.c2w).transpose().as_mat3();
            let rgb: Vec<u8> = f
                .normal
                .iter()
                .flat_map(|n| {
                    if *n == Vec3::ZERO {
                        return [0, 0, 0];
                    }
                    let n = if r.normal.space == NormalSpace::Camera { rot * *n } else { *n };
                    n.to_array().map(|v| ((v + 1.0) * 0.5 * 255.0).round().clamp(0.0, 255.0) as u8)
                })
                .collect();
            vec![(Slot::Normal, encode::rgb_png(&rgb, w, h, c))]
        }
        Pass::Mask => {
            let mut v = vec![(Slot::Mask, encode::gray8_png(&f.coverage, w, h, c))];
            if instances {
                let ids: Vec<u16> = f.object.iter().map(|&o| o.min(u16::MAX as u32) as u16).collect();
                v.push((Slot::Instance, encode::gray16_png(&ids, w, h, c)));
            }
            v
        }
    }
}
