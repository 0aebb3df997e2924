//! A build, end to end: manifest → scene → plan → execute (render into the store) → export (writers). The
//! command line only adds progress display; tests and other front ends call [`build`] directly.

use std::path::PathBuf;
use std::time::Instant;

use crate::cache::Store;
use crate::execute;
use crate::export::{self, Export, Written};
use crate::manifest::Manifest;
use crate::plan::Plan;
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
    /// The scene is loaded and planned: `images` to render.
    fn planned(&self, images: usize);
    /// `done` of the images are rendered.
    fn rendered(&self, done: usize);
    /// Output `name` is being written.
    fn writing(&self, name: &str);
}

/// A progress sink that ignores everything.
pub struct Silent;

impl Progress for Silent {
    fn planned(&self, _: usize) {}
    fn rendered(&self, _: usize) {}
    fn writing(&self, _: &str) {}
}

/// What a build did.
#[derive(Debug)]
pub struct Report {
    /// Images rendered.
    pub images: usize,
    /// Seconds spent rendering (including encoding and storing).
    pub render_seconds: f64,
    /// Seconds in all.
    pub total_seconds: f64,
    /// Each output's dataset.
    pub outputs: Vec<(String, Written)>,
    /// Warnings from the scene and the plan.
    pub warnings: Vec<String>,
}

/// Builds every output of `m`, using the store at `cache`.
pub fn build(m: &Manifest, cache: &std::path::Path, progress: &dyn Progress) -> Result<Report, String> {
    let t0 = Instant::now();
    check_directories(m)?;
    let scene = Scene::open(m)?;
    let plan = Plan::new(m, scene.frames)?;
    let store = Store::open(cache).map_err(|e| format!("cache {}: {e}", cache.display()))?;
    // Only image writers need renders.
    let needs_images = m.outputs.values().any(|o| o.writer.get_ref().renders_images());
    let images = if needs_images { plan.images.len() } else { 0 };
    progress.planned(images);
    let t1 = Instant::now();
    let rendered = if needs_images {
        execute::render_plan(&scene, &plan, &m.render, &store, &|n| progress.rendered(n))?
    } else {
        vec![Default::default(); plan.images.len()]
    };
    let render_seconds = t1.elapsed().as_secs_f64();
    let x = Export { manifest: m, scene: &scene, plan: &plan, rendered: &rendered, store: &store };
    let mut outputs = Vec::new();
    for (name, out) in &m.outputs {
        progress.writing(name);
        let w = export::write(&x, name, out).map_err(|e| format!("output `{name}`: {e}"))?;
        outputs.push((name.clone(), w));
    }
    let mut warnings = scene.warnings.clone();
    warnings.extend(plan.warnings.iter().cloned());
    Ok(Report { images, render_seconds, total_seconds: t0.elapsed().as_secs_f64(), outputs, warnings })
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
