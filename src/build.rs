//! A build, end to end: manifest → scene → plan (with content keys) → execute (render what the cache lacks)
//! → export (writers, materialized from the cache). The command line only adds progress display; tests and
//! other front ends call [`build`] directly. [`status`] answers what a build would do without doing it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cache::{Digest, StatCache, Store};
use crate::execute::{self, Inputs, Shard};
use crate::export::{self, Export, Written};
use crate::manifest::Manifest;
use crate::plan::{keys, Plan};
use crate::scene::Scene;

/// Where the cache lives: `VVGEN_CACHE`, else `[dataset] cache` (manifest-relative), else `cache/` in the
/// working directory.
pub fn cache_dir(m: &Manifest) -> PathBuf {
    if let Some(p) = std::env::var_os("VVGEN_CACHE").filter(|p| !p.is_empty()) {
        return PathBuf::from(p);
    }
    match &m.dataset.cache {
        Some(c) => m.resolve(c.get_ref()),
        None => PathBuf::from("cache"),
    }
}

/// Progress events of a build.
pub trait Progress: Sync {
    /// The cache has been consulted: `hits` images are cached, `work` will be rendered here.
    fn started(&self, hits: usize, work: usize);
    /// `done` of the `work` images are rendered.
    fn rendered(&self, done: usize);
    /// Output `name` is being written.
    fn writing(&self, name: &str);
}

/// A progress sink that ignores everything.
pub struct Silent;

impl Progress for Silent {
    fn started(&self, _: usize, _: usize) {}
    fn rendered(&self, _: usize) {}
    fn writing(&self, _: &str) {}
}

/// Build options.
#[derive(Debug, Clone, Copy, Default)]
pub struct Options {
    /// Render only this shard's part of the missing images and write no outputs.
    pub shard: Option<Shard>,
}

/// What a build did.
#[derive(Debug)]
pub struct Report {
    /// Images in the plan.
    pub images: usize,
    /// Images found in the cache.
    pub hits: usize,
    /// Images rendered by this build.
    pub renders: usize,
    /// Images left to other shards.
    pub elsewhere: usize,
    /// Seconds spent rendering (including encoding and storing).
    pub render_seconds: f64,
    /// Seconds in all.
    pub total_seconds: f64,
    /// Each output's dataset (none for a shard build).
    pub outputs: Vec<(String, Written)>,
    /// The outputs of the `[dataset] after` manifests, named `file.toml/output`.
    pub after: Vec<(String, Written)>,
    /// Warnings from the scene and the plan.
    pub warnings: Vec<String>,
}

/// The record of the last complete build of a dataset, kept in the cache: which files each output produced (so
/// files a later build no longer produces are removed) and what determined each image (for `plan --explain`).
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct LastBuild {
    /// Output name → (root, root-relative files).
    pub outputs: BTreeMap<String, (PathBuf, Vec<String>)>,
    /// `split/view/frame` → the image's key parts.
    pub images: BTreeMap<String, ImageParts>,
}

/// What one image's keys were made of, by part.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ImageParts {
    /// The frame's content key.
    pub frame: String,
    /// Camera intrinsics and pose.
    pub camera: String,
    /// Render settings.
    pub settings: String,
    /// Passes.
    pub passes: Vec<String>,
    /// Renderer version.
    pub salt: String,
}

/// One record per (dataset directory, manifest): two manifests may share an `out` directory (a point-cloud
/// sequence and the renders made from it), and neither may prune the other's files.
fn last_build_path(store: &Store, m: &Manifest) -> PathBuf {
    let abs = |p: PathBuf| std::path::absolute(&p).unwrap_or(p).to_string_lossy().into_owned();
    let id = format!("{}\0{}", abs(m.out_dir()), abs(m.path.clone()));
    let name = blake3::hash(id.as_bytes()).to_hex();
    store.root().join("builds").join(format!("{}.json", &name[..32]))
}

/// Reads the last build record of `m`'s dataset (empty when none).
pub fn last_build(store: &Store, m: &Manifest) -> LastBuild {
    std::fs::read_to_string(last_build_path(store, m))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default()
}

/// Everything up to the keys: shared by `build`, `plan`, `status` and `release`.
pub struct Prepared {
    /// The scene.
    pub scene: Scene,
    /// The plan.
    pub plan: Plan,
    /// The store.
    pub store: Store,
    /// The dataset's stat cache.
    pub stat: StatCache,
    /// Key of every scene frame.
    pub frame_keys: Vec<Digest>,
}

/// Opens the scene, plans, and keys every frame.
pub fn prepare(m: &Manifest, cache: &Path) -> Result<Prepared, String> {
    check_directories(m)?;
    let scene = Scene::open(m).map_err(|e| match m.after.is_empty() {
        true => e,
        false => format!("{e} (an `after` manifest may write it: `vvgen build` builds those first)"),
    })?;
    let plan = Plan::new(m, scene.frames)?;
    let store = Store::open(cache).map_err(|e| format!("cache {}: {e}", cache.display()))?;
    let stat = store.stat_cache(&m.out_dir());
    let frame_keys = keys::frame_keys(&scene, &stat)?;
    Ok(Prepared { scene, plan, store, stat, frame_keys })
}

/// Builds every output of `m`, using the store at `cache`: renders only images the cache lacks.
/// The `[dataset] after` manifests are built first, whole (also for a shard build: this manifest's sources may
/// be their outputs), through the same cache.
pub fn build(m: &Manifest, cache: &Path, opts: Options, progress: &dyn Progress) -> Result<Report, String> {
    let t0 = Instant::now();
    let mut before = Vec::new();
    for a in &m.after {
        let file = a.path.file_name().map_or(String::new(), |f| f.to_string_lossy().into_owned());
        let r = build(a, cache, Options::default(), progress).map_err(|e| format!("`after` manifest {file}: {e}"))?;
        before.extend(r.after.into_iter().chain(r.outputs.into_iter().map(|(name, w)| (format!("{file}/{name}"), w))));
    }
    let p = prepare(m, cache)?;
    // Only image writers need renders.
    let needs_images = m.outputs.values().any(|o| o.writer.get_ref().renders_images());
    let t1 = Instant::now();
    let inputs =
        Inputs { scene: &p.scene, render: &m.render, store: &p.store, stat: &p.stat, frame_keys: &p.frame_keys };
    let outcome = if needs_images {
        execute::render_plan(&inputs, &p.plan, opts.shard, &|h, w| progress.started(h, w), &|n| progress.rendered(n))?
    } else {
        progress.started(0, 0);
        execute::Outcome { rendered: vec![Default::default(); p.plan.images.len()], hits: 0, renders: 0, elsewhere: 0 }
    };
    let render_seconds = t1.elapsed().as_secs_f64();
    let mut warnings = p.scene.warnings.clone();
    warnings.extend(p.plan.warnings.iter().cloned());
    let mut report = Report {
        images: if needs_images { p.plan.images.len() } else { 0 },
        hits: outcome.hits,
        renders: outcome.renders,
        elsewhere: outcome.elsewhere,
        render_seconds,
        total_seconds: 0.0,
        outputs: Vec::new(),
        after: before,
        warnings,
    };
    if opts.shard.is_some() {
        // A shard only fills the cache; the final unsharded build writes the datasets.
        let _ = p.stat.save();
        report.total_seconds = t0.elapsed().as_secs_f64();
        return Ok(report);
    }
    let x = Export {
        manifest: m,
        scene: &p.scene,
        plan: &p.plan,
        rendered: &outcome.rendered,
        store: &p.store,
        stat: &p.stat,
        frame_keys: &p.frame_keys,
    };
    let previous = last_build(&p.store, m);
    let mut record = LastBuild::default();
    for (name, out) in &m.outputs {
        progress.writing(name);
        let w = export::write(&x, name, out).map_err(|e| format!("output `{name}`: {e}"))?;
        record.outputs.insert(name.clone(), (w.root.clone(), w.files.iter().map(|(f, _)| f.clone()).collect()));
        report.outputs.push((name.clone(), w));
    }
    prune(&previous, &record);
    if needs_images {
        record.images = image_parts(m, &p);
    }
    let text = serde_json::to_string(&record).expect("BUG: the record serializes");
    crate::atomic::write(&last_build_path(&p.store, m), text.as_bytes()).map_err(|e| format!("cache: {e}"))?;
    p.stat.save().map_err(|e| format!("cache: {e}"))?;
    report.total_seconds = t0.elapsed().as_secs_f64();
    Ok(report)
}

/// Removes files the previous build produced and this one did not (a split that shrank, a renamed output).
fn prune(previous: &LastBuild, now: &LastBuild) {
    let keep: BTreeSet<PathBuf> =
        now.outputs.values().flat_map(|(root, files)| files.iter().map(move |f| root.join(f))).collect();
    for (root, files) in previous.outputs.values() {
        for f in files {
            let p = root.join(f);
            if !keep.contains(&p) {
                let _ = std::fs::remove_file(&p);
            }
        }
    }
}

/// Key parts of every image, by `split/view/frame`.
pub fn image_parts(m: &Manifest, p: &Prepared) -> BTreeMap<String, ImageParts> {
    let settings = keys::render_settings(&m.render, p.scene.voxel_size());
    let settings = blake3::hash(&settings).to_hex().to_string();
    let passes: Vec<String> = m.render.passes.get_ref().iter().map(|p| format!("{p:?}").to_lowercase()).collect();
    p.plan
        .images
        .iter()
        .map(|img| {
            let c = &img.camera;
            let cam = format!(
                "{} {} {} {} {} {} {} {} {:?}",
                c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.near, c.far, c.c2w
            );
            let id = format!("{}/{}/{}", p.plan.splits[img.split].name, img.view, img.frame);
            let parts = ImageParts {
                frame: p.frame_keys[img.frame].hex(),
                camera: blake3::hash(cam.as_bytes()).to_hex().to_string(),
                settings: settings.clone(),
                passes: passes.clone(),
                salt: String::from_utf8_lossy(keys::RENDER_SALT).into_owned(),
            };
            (id, parts)
        })
        .collect()
}

/// What a build would do.
#[derive(Debug, Default, Serialize)]
pub struct Status {
    /// Images in the plan.
    pub images: usize,
    /// Cached images.
    pub fresh: usize,
    /// Images that existed in the last build and changed, with why.
    pub stale: Vec<(String, Vec<String>)>,
    /// Images new since the last build.
    pub new: Vec<String>,
    /// Output files of the last build that are missing or modified on disk.
    pub damaged_outputs: Vec<String>,
}

/// Plans `m` and classifies every image as fresh (cached), stale (changed since the last build, with reasons)
/// or new, and checks the last build's output files on disk.
pub fn status(m: &Manifest, cache: &Path) -> Result<Status, String> {
    let p = prepare(m, cache)?;
    let settings = keys::render_settings(&m.render, p.scene.voxel_size());
    let last = last_build(&p.store, m);
    let mut st = Status { images: p.plan.images.len(), ..Default::default() };
    let needs_images = m.outputs.values().any(|o| o.writer.get_ref().renders_images());
    if needs_images {
        let cached: Vec<bool> = (0..p.plan.images.len())
            .into_par_iter()
            .map(|i| {
                let keys = execute::image_keys(&p.plan, &p.frame_keys, &m.render, &settings, i);
                execute::lookup(&p.store, &p.stat, &keys).is_some()
            })
            .collect();
        for (i, img) in p.plan.images.iter().enumerate() {
            if cached[i] {
                st.fresh += 1;
                continue;
            }
            let id = format!("{}/{}/{}", p.plan.splits[img.split].name, img.view, img.frame);
            match last.images.get(&id) {
                None => st.new.push(id),
                Some(_) => st.stale.push((id.clone(), vec![])),
            }
        }
        if !st.stale.is_empty() {
            // Key parts only for the explanation, and only when something is stale.
            let parts = image_parts(m, &p);
            for (id, reasons) in &mut st.stale {
                *reasons = why(&last.images[id.as_str()], &parts[id.as_str()]);
            }
        }
    } else {
        st.images = 0;
    }
    for (root, files) in last.outputs.values() {
        for f in files {
            let path = root.join(f);
            if !path.exists() {
                st.damaged_outputs.push(format!("{}: missing", path.display()));
            }
        }
    }
    Ok(st)
}

/// Why an image's key changed, part by part.
fn why(before: &ImageParts, now: &ImageParts) -> Vec<String> {
    let mut r = Vec::new();
    if before.frame != now.frame {
        r.push("scene content of the frame changed (source file, animation, or transform)".to_string());
    }
    if before.camera != now.camera {
        r.push("camera changed (rig, seed, resolution or intrinsics)".to_string());
    }
    if before.settings != now.settings {
        r.push("[render] settings changed".to_string());
    }
    if before.passes != now.passes {
        r.push(format!("passes changed: {:?} → {:?}", before.passes, now.passes));
    }
    if before.salt != now.salt {
        r.push(format!("renderer version changed ({} → {})", before.salt, now.salt));
    }
    if r.is_empty() {
        r.push("cached result missing or corrupt (cache cleared, collected or damaged)".to_string());
    }
    r
}

/// Two outputs writing one directory would overwrite each other's `vvgen.json` (and possibly images).
fn check_directories(m: &Manifest) -> Result<(), String> {
    let mut seen: Vec<(String, &str)> = Vec::new();
    for (name, out) in &m.outputs {
        let dir = export::dir_name(m, out);
        let norm = dir.trim_end_matches('/').to_string();
        if let Some((_, other)) = seen.iter().find(|(d, _)| *d == norm) {
            return Err(format!(
                "outputs `{other}` and `{name}` both write to `{dir}`: give one of them its own `dir`"
            ));
        }
        seen.push((norm, name));
    }
    Ok(())
}
