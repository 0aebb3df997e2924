//! Export: the rendered blobs and the plan's cameras → dataset directories in the layouts trainers load
//! unchanged (../shared/specs/consumer-formats.md is the contract). Every writer works from the same camera list;
//! each file lands atomically, and every dataset root gets a `vvgen.json` describing what is in it.

mod colmap;
mod dynerf;
mod meta;
mod nerf;
mod points;

use std::collections::BTreeMap;
use std::path::PathBuf;

use glam::{DMat4, Vec3};

use crate::atomic;
use crate::cache::{key, Digest, StatCache, Store};
use crate::execute::Rendered;
use crate::manifest::output::{Output, Writer};
use crate::manifest::Manifest;
use crate::plan::{Image, Plan};
use crate::sample::{self, Points};
use crate::scene::{Poser, Scene};

/// Default number of points in an image dataset's initialization cloud.
pub const DEFAULT_INIT_POINTS: u64 = 100_000;

/// Everything the writers read.
pub struct Export<'a> {
    /// The manifest.
    pub manifest: &'a Manifest,
    /// The loaded scene (posed again for point clouds and bounds).
    pub scene: &'a Scene,
    /// The plan.
    pub plan: &'a Plan,
    /// The plan's rendered blobs, by image.
    pub rendered: &'a [Rendered],
    /// Where the blobs are.
    pub store: &'a Store,
    /// The dataset's stat cache.
    pub stat: &'a StatCache,
    /// Key of every scene frame.
    pub frame_keys: &'a [Digest],
}

impl Export<'_> {
    /// The blob of the task `key`, from the cache, or made by `make` and recorded.
    fn cached(&self, key: Digest, make: impl FnOnce() -> Result<Vec<u8>, String>) -> Result<Digest, String> {
        if let Some(b) = self.store.hit(&key, self.stat) {
            if let [d] = b.as_slice() {
                return Ok(*d);
            }
        }
        let d = self.store.put(&make()?, self.stat).map_err(|e| format!("cache: {e}"))?;
        self.store.record_action(&key, &[d]).map_err(|e| format!("cache: {e}"))?;
        Ok(d)
    }
}

/// What one writer produced.
#[derive(Debug, Clone)]
pub struct Written {
    /// The dataset root.
    pub root: PathBuf,
    /// Files written, root-relative with `/` separators, and their digests.
    pub files: Vec<(String, Digest)>,
    /// Things a user should know (e.g. a consumer quirk the dataset trips).
    pub warnings: Vec<String>,
}

/// A dataset directory being filled.
pub(crate) struct Files<'a> {
    root: PathBuf,
    store: &'a Store,
    stat: &'a StatCache,
    files: Vec<(String, Digest)>,
    warnings: Vec<String>,
    /// Per image: pass name → root-relative path, for vvgen.json.
    placed: BTreeMap<usize, BTreeMap<&'static str, String>>,
    /// Writer-specific sections of vvgen.json (e.g. a point-cloud sequence's grid and counts).
    meta: serde_json::Map<String, serde_json::Value>,
}

impl<'a> Files<'a> {
    fn new(root: PathBuf, store: &'a Store, stat: &'a StatCache) -> Files<'a> {
        Files {
            root,
            store,
            stat,
            files: Vec::new(),
            warnings: Vec::new(),
            placed: BTreeMap::new(),
            meta: Default::default(),
        }
    }

    /// Places stored blob `d` at `rel` as pass `pass` of plan image `image`.
    fn image_blob(&mut self, image: usize, pass: &'static str, rel: &str, d: Digest) -> Result<(), String> {
        self.placed.entry(image).or_default().insert(pass, rel.to_string());
        self.blob(rel, d)
    }

    /// Places stored blob `d` at `rel`.
    fn blob(&mut self, rel: &str, d: Digest) -> Result<(), String> {
        let dest = self.root.join(rel);
        self.store.materialize(&d, &dest, self.stat).map_err(|e| format!("{}: {e}", dest.display()))?;
        self.files.push((rel.to_string(), d));
        Ok(())
    }

    /// Writes `bytes` at `rel` (through the store, so identical files are stored once).
    fn bytes(&mut self, rel: &str, bytes: &[u8]) -> Result<(), String> {
        let d = self.store.put(bytes, self.stat).map_err(|e| format!("cache: {e}"))?;
        self.blob(rel, d)
    }

    /// Writes pretty JSON at `rel`.
    fn json(&mut self, rel: &str, v: &serde_json::Value) -> Result<(), String> {
        self.bytes(rel, json_text(v).as_bytes())
    }

    /// Adds section `key` to the dataset's vvgen.json.
    fn meta(&mut self, key: &str, v: serde_json::Value) {
        self.meta.insert(key.to_string(), v);
    }

    fn warn(&mut self, w: String) {
        self.warnings.push(w);
    }

    fn finish(self) -> Written {
        Written { root: self.root, files: self.files, warnings: self.warnings }
    }
}

/// Runs the writer of `[output.name]`.
pub fn write(x: &Export, name: &str, out: &Output) -> Result<Written, String> {
    let root = x.manifest.out_dir().join(dir_name(x.manifest, out));
    std::fs::create_dir_all(&root).map_err(|e| format!("{}: {e}", root.display()))?;
    atomic::clean_debris(&root);
    let mut files = Files::new(root, x.store, x.stat);
    let writer = *out.writer.get_ref();
    let images = selected_images(x, out)?;
    if writer.renders_images() && images.is_empty() {
        return Err(format!("output `{name}` has no images (its splits are empty)"));
    }
    match writer {
        Writer::Dnerf => nerf::dnerf(x, out, &images, &mut files)?,
        Writer::Nerfstudio => nerf::nerfstudio(x, out, &images, &mut files)?,
        Writer::InstantNgp => nerf::instant_ngp(x, out, &images, &mut files)?,
        Writer::StaticFrames => nerf::static_frames(x, out, &images, &mut files)?,
        Writer::Colmap => colmap::write(x, out, &images, &mut files)?,
        Writer::Dynerf => dynerf::write(x, out, &images, &mut files)?,
        Writer::PlySequence => points::sequence(x, out, &mut files)?,
    }
    meta::write(x, name, out, &images, &mut files)?;
    Ok(files.finish())
}

/// The output's directory name under `[dataset] out`.
pub fn dir_name(m: &Manifest, out: &Output) -> String {
    out.dir_name(m.dataset.name.get_ref())
}

/// Indices of the images of the output's splits, split by split (manifest order), time-major within each.
fn selected_images(x: &Export, out: &Output) -> Result<Vec<usize>, String> {
    let names: Vec<&str> = match &out.splits {
        Some(list) => list.iter().map(|s| s.get_ref().as_str()).collect(),
        None => x.plan.splits.iter().map(|s| s.name.as_str()).collect(),
    };
    let mut v = Vec::new();
    for n in names {
        let s = x.plan.splits.iter().find(|s| s.name == n).ok_or_else(|| format!("no split `{n}`"))?;
        v.extend(&s.images);
    }
    Ok(v)
}

/// The rows of a 4×4 matrix, as written in transforms.json files.
fn rows(m: &DMat4) -> serde_json::Value {
    let t = m.transpose().to_cols_array_2d();
    serde_json::json!(t)
}

/// Digits for zero-padded image indices: at least 4, enough for `n`.
fn pad_for(n: usize) -> usize {
    n.saturating_sub(1).to_string().len().max(4)
}

/// The NeRF-style base name of an image, `r_<index>` zero-padded.
fn r_name(img: &Image, pad: usize) -> String {
    format!("r_{:0pad$}", img.index)
}

/// The initialization cloud: `n` surface samples spread over `frames` (the union of the motion), in world space.
fn init_cloud(x: &Export, frames: &[usize], n: usize) -> Result<Points, String> {
    let mut out = Points::default();
    if n == 0 || frames.is_empty() {
        return Ok(out);
    }
    let mut poser = Poser::default();
    let seed = x.manifest.dataset.seed.to_le_bytes();
    for (i, &f) in frames.iter().enumerate() {
        // An even share per frame; the first frames take the remainder.
        let share = n / frames.len() + usize::from(i < n % frames.len());
        let posed = x.scene.pose(f, &mut poser)?;
        out.extend(&sample::sample(posed, share, &[b"init", &seed, &(f as u64).to_le_bytes()]));
    }
    Ok(out)
}

/// [`init_cloud`] encoded by [`init_ply`], through the cache (keyed by the frames' content, `n` and the seed).
fn init_ply_blob(x: &Export, frames: &[usize], n: usize) -> Result<Digest, String> {
    let mut parts: Vec<&[u8]> = frames.iter().map(|&f| &x.frame_keys[f].0[..]).collect();
    let (nb, seed) = ((n as u64).to_le_bytes(), x.manifest.dataset.seed.to_le_bytes());
    parts.extend([crate::plan::keys::SAMPLE_SALT, &nb[..], &seed[..]]);
    x.cached(key("init cloud", &parts), || Ok(init_ply(&init_cloud(x, frames, n)?)))
}

/// Bounds of the geometry over `frames`.
fn bounds(x: &Export, frames: &[usize]) -> Result<Option<(Vec3, Vec3)>, String> {
    let mut poser = Poser::default();
    let mut b: Option<(Vec3, Vec3)> = None;
    for &f in frames {
        if let Some((lo, hi)) = x.scene.pose(f, &mut poser)?.bounds() {
            b = Some(b.map_or((lo, hi), |(a, c)| (a.min(lo), c.max(hi))));
        }
    }
    Ok(b)
}

/// Distinct frames of `images`, ascending.
fn frames_of(x: &Export, images: &[usize]) -> Vec<usize> {
    let mut f: Vec<usize> = images.iter().map(|&i| x.plan.images[i].frame).collect();
    f.sort_unstable();
    f.dedup();
    f
}

/// The init cloud as the PLY 3DGS-family loaders read: x y z, nx ny nz (float), red green blue (uchar).
fn init_ply(p: &Points) -> Vec<u8> {
    let colors = p.srgb8();
    crate::scene::ply::write(&crate::scene::ply::PlyOut {
        positions: &p.positions,
        normals: Some(&p.normals),
        colors: Some(&colors),
        extra_u32: &[],
        extra_f32: &[],
        triangles: None,
        comments: &["generated by vvgen: surface samples over the union of the frames"],
        ascii: false,
    })
}

/// Number of init points an image output asks for.
fn init_points(out: &Output) -> usize {
    out.init_points.as_ref().map_or(DEFAULT_INIT_POINTS, |p| *p.get_ref()) as usize
}

/// The RGBA blob of an image composited over an opaque background (sRGB bytes, as loaders composite), as an RGB
/// PNG in the store: for consumers that do not read alpha (COLMAP, DyNeRF).
fn opaque_rgb(x: &Export, image: usize, bg: [u8; 3]) -> Result<Digest, String> {
    let d = x.rendered[image].rgba.ok_or("the `rgba` pass is needed for this writer")?;
    let png_setting = format!("{:?}", x.manifest.render.png_compression);
    x.cached(key("composite 1", &[&d.0, &bg, png_setting.as_bytes()]), || {
        let png = x.store.get(&d).map_err(|e| format!("cache: {e}"))?;
        let img = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
            .map_err(|e| format!("cache blob {}: {e}", d.hex()))?
            .into_rgba8();
        let (w, h) = img.dimensions();
        let rgb: Vec<u8> = img
            .pixels()
            .flat_map(|p| {
                let a = p[3] as u32;
                [0, 1, 2].map(|k| ((p[k] as u32 * a + bg[k] as u32 * (255 - a) + 127) / 255) as u8)
            })
            .collect();
        Ok(crate::render::encode::rgb_png(&rgb, w, h, x.manifest.render.png_compression))
    })
}

/// The background that opaque exports bake in: the manifest's, else white (NeRF-synthetic's convention).
fn opaque_background(m: &Manifest) -> [u8; 3] {
    use crate::manifest::render::Background;
    match m.render.background.as_ref().map(|b| b.get_ref()) {
        Some(Background::Named(n)) if n == "black" => [0, 0, 0],
        Some(Background::Rgb(c)) => c.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8),
        _ => [255, 255, 255],
    }
}

/// JSON with two-space indentation where arrays of plain numbers (matrix rows, vectors) stay on one line.
fn json_text(v: &serde_json::Value) -> String {
    fn scalar(v: &serde_json::Value) -> bool {
        !matches!(v, serde_json::Value::Array(_) | serde_json::Value::Object(_))
    }
    fn go(v: &serde_json::Value, indent: usize, out: &mut String) {
        use serde_json::Value;
        let pad = |n: usize| "  ".repeat(n);
        match v {
            Value::Array(a) if a.iter().all(scalar) => {
                out.push('[');
                for (i, x) in a.iter().enumerate() {
                    if i > 0 {
                        out.push_str(", ");
                    }
                    out.push_str(&x.to_string());
                }
                out.push(']');
            }
            // Matrices: one row per line.
            Value::Array(a) if a.iter().all(|r| matches!(r, Value::Array(x) if x.iter().all(scalar))) => {
                out.push('[');
                for (i, x) in a.iter().enumerate() {
                    out.push_str(if i > 0 { ", " } else { "" });
                    go(x, indent + 1, out);
                }
                out.push(']');
            }
            Value::Array(a) => {
                out.push('[');
                for (i, x) in a.iter().enumerate() {
                    out.push_str(if i > 0 { ",\n" } else { "\n" });
                    out.push_str(&pad(indent + 1));
                    go(x, indent + 1, out);
                }
                out.push_str(&format!("\n{}]", pad(indent)));
            }
            Value::Object(m) if m.is_empty() => out.push_str("{}"),
            Value::Object(m) => {
                out.push('{');
                for (i, (k, x)) in m.iter().enumerate() {
                    out.push_str(if i > 0 { ",\n" } else { "\n" });
                    out.push_str(&format!("{}{}: ", pad(indent + 1), Value::String(k.clone())));
                    go(x, indent + 1, out);
                }
                out.push_str(&format!("\n{}}}", pad(indent)));
            }
            x => out.push_str(&x.to_string()),
        }
    }
    let mut s = String::new();
    go(v, 0, &mut s);
    s.push('\n');
    s
}
