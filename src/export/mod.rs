//! Export: the rendered blobs and the plan's cameras → dataset directories in the layouts trainers load
//! unchanged (../shared/specs/consumer-formats.md is the contract). Every writer works from the same camera list;
//! each file lands atomically, and every dataset gets a `vvgen/dataset.json` describing what is in it
//! ([`META`]; out of the root, where consumers scan).

mod colmap;
mod dynerf;
mod meta;
pub(crate) use meta::previous_files;
mod nerf;
mod points;
mod preview;

pub use meta::META;

use std::collections::BTreeMap;
use std::path::PathBuf;

use glam::{DMat4, Vec3};

use crate::atomic;
use crate::cache::{self, Digest, StatCache, Store};
use crate::manifest::output::{Output, Writer};
use crate::manifest::render::Pass;
use crate::manifest::Manifest;
use crate::plan::actions::Action;
use crate::plan::graph::Graph;
use crate::plan::{Image, Plan};
use crate::scene::Scene;

/// What can go wrong writing a dataset.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Placing a file or writing the dataset directory failed.
    #[error(transparent)]
    Cache(#[from] cache::Error),
    /// A file name pattern cannot be formatted.
    #[error("file pattern")]
    Pattern(#[from] crate::manifest::sequence::Error),
    /// The geometry has no extent where a writer needs bounds.
    #[error("the scene is empty: there are no bounds to write")]
    EmptyScene,
    /// A number a writer would emit is NaN or infinite (the last line of defence: no writer emits one).
    #[error("{0} is not finite (degenerate or overflowing input geometry or transforms)")]
    NonFinite(String),
    /// A preview's cached inputs do not read back (a damaged cache).
    #[error("preview")]
    Preview(#[from] crate::preview::Error),
    /// A writer asked for an action the graph did not plan (a bug: all work is planned).
    #[error("BUG: the plan has no {0}")]
    Unplanned(String),
}

/// Everything the writers read.
pub(crate) struct Export<'a> {
    /// The manifest.
    pub manifest: &'a Manifest,
    /// The loaded scene (names and transforms for the metadata).
    pub scene: &'a Scene,
    /// The image plan.
    pub plan: &'a Plan,
    /// The action graph.
    pub graph: &'a Graph<'a>,
    /// Per graph node, its blobs.
    pub blobs: &'a [Option<Vec<Digest>>],
    /// Where the blobs are.
    pub store: &'a Store,
    /// The dataset's stat cache.
    pub stat: &'a StatCache,
}

impl Export<'_> {
    /// The blobs of `action`, which the graph planned and the build ran (or found).
    fn blobs_of(&self, action: &Action) -> Result<&[Digest], Error> {
        let id = self.graph.id(action).ok_or_else(|| Error::Unplanned(format!("{action:?}")))?;
        self.blobs[id.0 as usize].as_deref().ok_or_else(|| Error::Unplanned(format!("result of {action:?}")))
    }

    /// The one blob of `action`.
    fn blob(&self, action: &Action) -> Result<Digest, Error> {
        self.blobs_of(action)?.first().copied().ok_or_else(|| Error::Unplanned(format!("blob of {action:?}")))
    }

    /// The rendered files of plan image `image`.
    fn rendered(&self, image: usize) -> Result<Rendered, Error> {
        let mut r = Rendered::default();
        for &pass in self.manifest.render.passes() {
            let b = self.blobs_of(&Action::RenderPass { image, pass })?;
            let (first, second) = (b.first().copied(), b.get(1).copied());
            match pass {
                Pass::Rgba => r.rgba = first,
                Pass::Depth => (r.depth, r.depth_exr) = (first, second),
                Pass::Normal => (r.normal, r.normal_exr) = (first, second),
                Pass::Mask => r.mask = first,
                Pass::Instance => r.instance = first,
                Pass::Albedo => r.albedo = first,
            }
        }
        Ok(r)
    }

    /// Bounds of the geometry over `frames`, from their bounds action.
    fn bounds(&self, frames: &[usize]) -> Result<Option<(Vec3, Vec3)>, Error> {
        let d = self.blob(&Action::Bounds { frames: frames.to_vec() })?;
        let b = crate::execute::decode_bounds(&self.store.get(&d)?);
        if b.is_some_and(|(lo, hi)| !(lo.is_finite() && hi.is_finite())) {
            return Err(Error::NonFinite("the bounds of the posed geometry".into()));
        }
        Ok(b)
    }

    /// Every number the writers take from the plan and the scene (cameras, times, source matrices) is finite.
    fn check_finite(&self, images: &[usize]) -> Result<(), Error> {
        for &i in images {
            let (img, c) = (&self.plan.images[i], &self.plan.images[i].camera);
            let numbers = [c.fx, c.fy, c.cx, c.cy, c.near, c.far, img.time];
            if !(c.c2w.is_finite() && numbers.iter().all(|v| v.is_finite())) {
                return Err(Error::NonFinite(format!(
                    "the camera of {}",
                    crate::plan::graph::image_label(self.plan, i)
                )));
            }
        }
        for (i, src) in self.scene.sources.iter().enumerate() {
            if !self.scene.world_from_source(i).is_finite() {
                return Err(Error::NonFinite(format!("source `{}`'s world matrix", src.name)));
            }
        }
        Ok(())
    }

    /// The initialization cloud of `frames` with `n` points.
    fn init_cloud(&self, frames: &[usize], n: u64) -> Result<Digest, Error> {
        self.blob(&Action::InitCloud { frames: frames.to_vec(), points: n })
    }

    /// Image `image` composited over the opaque background.
    fn opaque_rgb(&self, image: usize) -> Result<Digest, Error> {
        let background = crate::plan::graph::opaque_background(self.manifest);
        self.blob(&Action::Composite { image, background })
    }
}

/// The files of one rendered image, one per requested pass.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
struct Rendered {
    rgba: Option<Digest>,
    depth: Option<Digest>,
    depth_exr: Option<Digest>,
    normal: Option<Digest>,
    normal_exr: Option<Digest>,
    mask: Option<Digest>,
    instance: Option<Digest>,
    albedo: Option<Digest>,
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
    /// Files this write placed or replaced (0 when the directory already held every file).
    pub changed: usize,
}

/// A dataset directory being filled.
pub(crate) struct Files<'a> {
    root: PathBuf,
    store: &'a Store,
    stat: &'a StatCache,
    files: Vec<(String, Digest)>,
    warnings: Vec<String>,
    /// Per image: pass name → root-relative path, for the metadata.
    placed: BTreeMap<usize, BTreeMap<&'static str, String>>,
    /// Writer-specific sections of the metadata (e.g. a point-cloud sequence's grid and counts).
    meta: serde_json::Map<String, serde_json::Value>,
    /// Files placed or replaced so far.
    changed: usize,
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
            changed: 0,
        }
    }

    /// Places stored blob `d` at `rel` as pass `pass` of plan image `image`.
    fn image_blob(&mut self, image: usize, pass: &'static str, rel: &str, d: Digest) -> Result<(), Error> {
        self.placed.entry(image).or_default().insert(pass, rel.to_string());
        self.blob(rel, d)
    }

    /// Places stored blob `d` at `rel`.
    fn blob(&mut self, rel: &str, d: Digest) -> Result<(), Error> {
        let dest = self.root.join(rel);
        self.changed += usize::from(self.store.materialize(&d, &dest, self.stat)?);
        self.files.push((rel.to_string(), d));
        Ok(())
    }

    /// Writes `bytes` at `rel` (through the store, so identical files are stored once).
    fn bytes(&mut self, rel: &str, bytes: &[u8]) -> Result<(), Error> {
        let d = self.store.put(bytes, self.stat)?;
        self.blob(rel, d)
    }

    /// Writes pretty JSON at `rel`.
    fn json(&mut self, rel: &str, v: &serde_json::Value) -> Result<(), Error> {
        self.bytes(rel, json_text(v).as_bytes())
    }

    /// Adds section `key` to the dataset's metadata.
    fn meta(&mut self, key: &str, v: serde_json::Value) {
        self.meta.insert(key.to_string(), v);
    }

    fn warn(&mut self, w: String) {
        self.warnings.push(w);
    }

    fn finish(self) -> Written {
        Written { root: self.root, files: self.files, warnings: self.warnings, changed: self.changed }
    }
}

/// Runs the writer of `[output.name]`: places its actions' blobs and writes its metadata.
pub(crate) fn write(x: &Export, name: &str, out: &Output) -> Result<Written, Error> {
    let root = root(x.manifest, out);
    std::fs::create_dir_all(&root).map_err(|e| cache::Error::io(&root, e))?;
    atomic::clean_debris(&root);
    remove_old_meta(&root);
    let mut files = Files::new(root, x.store, x.stat);
    let writer = out.writer();
    let images = if writer.renders_images() {
        x.plan.images_of(out).map_err(|e| Error::Unplanned(e.to_string()))?
    } else {
        Vec::new()
    };
    x.check_finite(&images)?;
    // What depends on the frame count (the rest of the consumers' caveats came with the manifest's diagnostics).
    let frames = x.plan.output_frames(out).map_err(|e| Error::Unplanned(e.to_string()))?;
    if let Some(d) = crate::manifest::consumers::frame_diagnostic(name, out, frames) {
        files.warn(d.message + &d.help.map(|h| format!(": {h}")).unwrap_or_default());
    }
    match writer {
        Writer::Dnerf => nerf::dnerf(x, out, &images, &mut files)?,
        Writer::Nerfstudio => nerf::nerfstudio(x, out, &images, &mut files)?,
        Writer::InstantNgp => nerf::instant_ngp(x, out, &images, &mut files)?,
        Writer::StaticFrames => nerf::static_frames(x, out, &images, &mut files)?,
        Writer::Colmap => colmap::write(x, out, &images, &mut files)?,
        Writer::Dynerf => dynerf::write(x, out, &images, &mut files)?,
        Writer::PlySequence => points::sequence(x, name, &mut files)?,
    }
    preview::place(x, name, out, &images, &mut files)?;
    meta::write(x, name, out, &images, &mut files)?;
    Ok(files.finish())
}

/// Removes the root `vvgen.json` an older vvgen wrote (only if it is vvgen's: `"tool": "vvgen"`), which
/// instant-ngp's directory mode would misread.
fn remove_old_meta(root: &std::path::Path) {
    let path = root.join(meta::OLD_META);
    let ours = std::fs::read(&path)
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .is_some_and(|v| v.get("tool").and_then(|t| t.as_str()) == Some("vvgen"));
    if ours {
        let _ = std::fs::remove_file(&path);
    }
}

/// The output's dataset root.
pub(crate) fn root(m: &Manifest, out: &Output) -> PathBuf {
    // `dir = "."` (the dataset at `out` itself) and `a/./b` name plain directories: drop the `.` components,
    // which directory creation would trip over.
    m.out_dir().join(dir_name(m, out)).components().filter(|c| *c != std::path::Component::CurDir).collect()
}

/// The output's directory name under `[dataset] out`.
pub(crate) fn dir_name(m: &Manifest, out: &Output) -> String {
    out.dir_name(m.dataset.name())
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

/// nerfstudio's train, val and test lists from each split's names (`lists`, in split order, none empty): it
/// requires all three once any is given, so a missing split borrows its neighbour's (train: the first split's;
/// val and test each other's, else none). Its `transforms.json` lists and its colmap parser's `*_list.txt` read
/// them alike.
fn nerfstudio_splits(lists: &[(impl AsRef<str>, Vec<String>)]) -> [Vec<String>; 3] {
    let get = |name: &str| lists.iter().find(|(n, _)| n.as_ref() == name).map(|(_, l)| l.clone());
    let train = get("train").unwrap_or_else(|| lists.first().map(|(_, l)| l.clone()).unwrap_or_default());
    let val = get("val").or_else(|| get("test")).unwrap_or_default();
    let test = get("test").or_else(|| get("val")).unwrap_or_default();
    [train, val, test]
}

/// Number of init points an image output asks for.
fn init_points(out: &Output) -> u64 {
    out.init_points().unwrap_or(crate::plan::graph::DEFAULT_INIT_POINTS)
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
