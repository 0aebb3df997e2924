//! Execution: render the plan's images into the content-addressed store. Each frame is posed once and shared by
//! every view of that frame; views render and encode in parallel on the worker threads (PNG encoding costs as
//! much as rendering, so it must not serialize on one thread). Every pass of every image has a content key
//! ([`keys`]); a pass whose key has an action record with intact blobs is not rendered again.

use glam::Vec3;
use rayon::prelude::*;

use crate::cache::{Digest, StatCache, Store};
use crate::manifest::render::{NormalSpace, Pass, PngCompression, Render};
use crate::plan::{keys, Image, Plan};
use crate::render::{self, encode, Frame, RenderSettings};
use crate::scene::{PosedScene, Poser, Scene};

/// The blobs of one rendered image, one per requested pass.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Rendered {
    /// RGBA8 PNG, straight alpha.
    pub rgba: Option<Digest>,
    /// 16-bit PNG, millimetres.
    pub depth: Option<Digest>,
    /// 32-bit float OpenEXR, metres (`[render.depth] exr`).
    pub depth_exr: Option<Digest>,
    /// RGB8 PNG, `(n + 1) / 2`.
    pub normal: Option<Digest>,
    /// 32-bit float OpenEXR of unit normals (`[render.normal] exr`).
    pub normal_exr: Option<Digest>,
    /// 8-bit PNG coverage.
    pub mask: Option<Digest>,
    /// 16-bit PNG instance ids (object + 1, 0 = background), with `mask` when the scene has several objects.
    pub instance: Option<Digest>,
}

/// Which tasks of a plan this process runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This process's index, `0..count`.
    pub index: u64,
    /// Number of processes sharing the work.
    pub count: u64,
}

impl Shard {
    /// Whether the task with `key` belongs to this shard (a deterministic partition by key).
    pub fn owns(&self, key: &Digest) -> bool {
        key.prefix_u64() % self.count == self.index
    }
}

/// The keys of an image's requested passes, in `[render] passes` order.
pub fn image_keys(plan: &Plan, frame_keys: &[Digest], r: &Render, settings: &[u8], i: usize) -> Vec<(Pass, Digest)> {
    let img = &plan.images[i];
    r.passes
        .get_ref()
        .iter()
        .map(|&p| (p, keys::pass_key(&frame_keys[img.frame], img, settings, &keys::pass_tag(r, p))))
        .collect()
}

/// The cached result of image `i`, when every pass ran before and its blobs are intact.
pub fn lookup(store: &Store, stat: &StatCache, keys: &[(Pass, Digest)]) -> Option<Rendered> {
    let mut out = Rendered::default();
    for (pass, k) in keys {
        let blobs = store.hit(k, stat)?;
        match (pass, blobs.as_slice()) {
            (Pass::Rgba, [d]) => out.rgba = Some(*d),
            (Pass::Depth, [d]) => out.depth = Some(*d),
            (Pass::Depth, [d, e]) => (out.depth, out.depth_exr) = (Some(*d), Some(*e)),
            (Pass::Normal, [d]) => out.normal = Some(*d),
            (Pass::Normal, [d, e]) => (out.normal, out.normal_exr) = (Some(*d), Some(*e)),
            (Pass::Mask, [d]) => out.mask = Some(*d),
            (Pass::Mask, [d, e]) => (out.mask, out.instance) = (Some(*d), Some(*e)),
            _ => return None,
        }
    }
    Some(out)
}

/// What [`render_plan`] did.
#[derive(Debug)]
pub struct Outcome {
    /// Per plan image, its blobs (default for images another shard renders).
    pub rendered: Vec<Rendered>,
    /// Images found in the cache.
    pub hits: usize,
    /// Images rendered now.
    pub renders: usize,
    /// Images left to other shards.
    pub elsewhere: usize,
}

/// Everything [`render_plan`] reads besides the plan.
pub struct Inputs<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// `[render]`.
    pub render: &'a Render,
    /// The blob store.
    pub store: &'a Store,
    /// The stat cache of this dataset.
    pub stat: &'a StatCache,
    /// Key of every scene frame.
    pub frame_keys: &'a [Digest],
}

/// Renders the images of `plan` whose passes are not cached (those of `shard` only, when given); `started(hits,
/// work)` is called once the cache has been consulted and `done(n)` after each rendered image.
pub fn render_plan(
    x: &Inputs,
    plan: &Plan,
    shard: Option<Shard>,
    started: &dyn Fn(usize, usize),
    done: &(dyn Fn(usize) + Sync),
) -> Result<Outcome, String> {
    let settings_bytes = keys::render_settings(x.render, x.scene.voxel_size());
    let all_keys: Vec<Vec<(Pass, Digest)>> = (0..plan.images.len())
        .into_par_iter()
        .map(|i| image_keys(plan, x.frame_keys, x.render, &settings_bytes, i))
        .collect();
    let found: Vec<Option<Rendered>> = all_keys.par_iter().map(|k| lookup(x.store, x.stat, k)).collect();
    let hits = found.iter().filter(|f| f.is_some()).count();
    let mut out: Vec<Rendered> = found.iter().map(|f| f.clone().unwrap_or_default()).collect();
    let todo: Vec<usize> = (0..plan.images.len())
        .filter(|&i| found[i].is_none())
        .filter(|&i| shard.is_none_or(|s| s.owns(&all_keys[i][0].1)))
        .collect();
    let elsewhere = plan.images.len() - hits - todo.len();
    started(hits, todo.len());
    let settings = RenderSettings::from_manifest(x.render, x.scene.voxel_size());
    let mut poser = Poser::default();
    let count = std::sync::atomic::AtomicUsize::new(0);
    for (frame, images) in plan.by_frame() {
        let images: Vec<usize> = images.into_iter().filter(|i| todo.binary_search(i).is_ok()).collect();
        if images.is_empty() {
            continue;
        }
        let posed = x.scene.pose(frame, &mut poser)?;
        let objects = posed.primitives.iter().map(|p| p.object).max().map_or(0, |m| m + 1);
        let results: Vec<Result<Rendered, String>> = images
            .par_iter()
            .map(|&i| {
                let r = render_image(posed, &plan.images[i], x.render, &settings, objects > 1, x.store, x.stat);
                let r = r.and_then(|r| record(x.store, &all_keys[i], &r).map(|_| r));
                done(count.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                r
            })
            .collect();
        for (&i, res) in images.iter().zip(results) {
            out[i] = res?;
        }
    }
    Ok(Outcome { rendered: out, hits, renders: todo.len(), elsewhere })
}

/// Writes the action records of one rendered image (after its blobs are stored).
fn record(store: &Store, keys: &[(Pass, Digest)], r: &Rendered) -> Result<(), String> {
    for (pass, k) in keys {
        let blobs: Vec<Digest> = match pass {
            Pass::Rgba => r.rgba.into_iter().collect(),
            Pass::Depth => r.depth.into_iter().chain(r.depth_exr).collect(),
            Pass::Normal => r.normal.into_iter().chain(r.normal_exr).collect(),
            Pass::Mask => r.mask.into_iter().chain(r.instance).collect(),
        };
        store.record_action(k, &blobs).map_err(|e| format!("cache: {e}"))?;
    }
    Ok(())
}

/// Renders one image and stores its passes.
pub fn render_image(
    posed: &PosedScene,
    image: &Image,
    r: &Render,
    settings: &RenderSettings,
    instances: bool,
    store: &Store,
    stat: &StatCache,
) -> Result<Rendered, String> {
    let f = render::render(posed, &image.camera, settings);
    let put = |bytes: Vec<u8>| store.put(&bytes, stat).map_err(|e| format!("cache {}: {e}", store.root().display()));
    let mut out = Rendered::default();
    for pass in r.passes.get_ref() {
        for (slot, bytes) in encode_pass(&f, *pass, r, image, instances) {
            let d = Some(put(bytes)?);
            match slot {
                Slot::Rgba => out.rgba = d,
                Slot::Depth => out.depth = d,
                Slot::DepthExr => out.depth_exr = d,
                Slot::Normal => out.normal = d,
                Slot::NormalExr => out.normal_exr = d,
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
    DepthExr,
    Normal,
    NormalExr,
    Mask,
    Instance,
}

fn encode_pass(f: &Frame, pass: Pass, r: &Render, image: &Image, instances: bool) -> Vec<(Slot, Vec<u8>)> {
    let (w, h, c): (u32, u32, PngCompression) = (f.width, f.height, r.png_compression);
    match pass {
        Pass::Rgba => vec![(Slot::Rgba, encode::rgba_png(&f.rgba, w, h, c))],
        Pass::Depth => {
            let mut v = vec![(Slot::Depth, encode::depth_mm_png(&f.depth, w, h, c))];
            if r.depth.exr {
                v.push((Slot::DepthExr, encode::f32_exr(&[("Y", &f.depth)], w, h, c)));
            }
            v
        }
        Pass::Normal => {
            // Camera space: the inverse rotation of the (orthonormal) camera-to-world.
            let rot = glam::DMat3::from_mat4(image.camera.c2w).transpose().as_mat3();
            let normals: Vec<Vec3> = match r.normal.space {
                NormalSpace::Camera => f.normal.iter().map(|n| rot * *n).collect(),
                NormalSpace::World => f.normal.clone(),
            };
            let rgb: Vec<u8> = normals
                .iter()
                .flat_map(|n| {
                    if *n == Vec3::ZERO {
                        return [0, 0, 0];
                    }
                    n.to_array().map(|v| ((v + 1.0) * 0.5 * 255.0).round().clamp(0.0, 255.0) as u8)
                })
                .collect();
            let mut v = vec![(Slot::Normal, encode::rgb_png(&rgb, w, h, c))];
            if r.normal.exr {
                let axis = |i: usize| normals.iter().map(|n| n[i]).collect::<Vec<f32>>();
                let (x, y, z) = (axis(0), axis(1), axis(2));
                v.push((Slot::NormalExr, encode::f32_exr(&[("R", &x), ("G", &y), ("B", &z)], w, h, c)));
            }
            v
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
