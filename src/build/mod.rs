//! A build, end to end: manifest → scene → plan (the action graph, every action keyed) → execute (run what the
//! cache lacks) → export (place blobs, write metadata). [`Build`] is the entry point for Rust callers; the
//! command line only adds progress display and exit codes. [`status()`] answers what a build would do, and why,
//! from the same graph; [`reachable`] is what `gc --keep` keeps.

mod error;
pub mod record;
mod status;

use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use crate::execute::{Counts, Shard};
pub use error::Error;
pub use status::{status, status_noting, status_with, ActionStatus, KindStatus, State, Status};

use crate::cache::{gc, Digest, StatCache, Store};
use crate::execute::{self, Inputs};
use crate::export::{self, Export, Written};
use crate::manifest::Manifest;
use crate::plan::actions::Kind;
use crate::plan::graph::{ActionId, Graph};
use crate::plan::{keys, Plan};
use crate::scene::Scene;
use record::{LastBuild, OutputRecord};

/// A build of one manifest, configured up front (ripgrep's builders): where the cache is, the shard.
///
/// ```
/// # let dir = tempfile::tempdir().unwrap();
/// # let ply = dir.path().join("tri.ply");
/// # std::fs::write(&ply, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
/// #   property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
/// #   0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
/// let manifest = r#"
///     [dataset]
///     name = "tri"
///     out  = "out"
///     [source.tri]
///     mesh = "tri.ply"
///     [render]
///     resolution = [32, 32]
///     [rig.ring]
///     kind = "orbit"
///     radius = 3
///     [split.train]
///     rig   = "ring"
///     views = 4
///     [output.cloud]
///     writer = "ply-sequence"
///     points = 100
///     [output.images]
///     writer = "dnerf"
///     init_points = 0
/// "#;
/// let report = vvgen::build::Build::from_manifest_str(manifest, dir.path())?
///     .cache(dir.path().join("cache"))
///     .run(&vvgen::build::Silent)?;
/// assert_eq!(report.ran(vvgen::Kind::RenderPass), 4);
/// assert_eq!(report.ran(vvgen::Kind::PointFrame), 1);
///
/// // Asked again, the cache holds everything.
/// let again = vvgen::build::Build::from_manifest_str(manifest, dir.path())?.cache(dir.path().join("cache"));
/// assert!(again.status(false)?.up_to_date());
///
/// // A mistake is refused with its place and fix, before anything runs.
/// match vvgen::build::Build::from_manifest_str("[dataset]\nnaem = \"x\"\n", dir.path()) {
///     Err(vvgen::build::Error::Manifest(report)) => assert!(report.render(false).contains("did you mean `name`")),
///     other => panic!("{other:?}"),
/// }
/// # Ok::<(), vvgen::build::Error>(())
/// ```
#[derive(Debug)]
pub struct Build {
    manifest: Manifest,
    cache: Option<PathBuf>,
    shard: Option<Shard>,
    verify: bool,
}

impl Build {
    /// A build of `manifest`.
    pub fn new(manifest: Manifest) -> Build {
        Build { manifest, cache: None, shard: None, verify: false }
    }

    /// A build of the manifest `text`, whose relative paths resolve against `base_dir`.
    pub fn from_manifest_str(text: &str, base_dir: &Path) -> Result<Build, Error> {
        let path = base_dir.join("manifest.toml");
        let (m, _) = crate::manifest::parse(text, &path).map_err(|r| Error::Manifest(Box::new(r)))?;
        Ok(Build::new(m))
    }

    /// A build of the manifest file at `path`.
    pub fn from_manifest_file(path: &Path) -> Result<Build, Error> {
        let (m, _) = crate::settings::load(path).map_err(|r| Error::Manifest(Box::new(r)))?;
        Ok(Build::new(m))
    }

    /// Uses the cache at `dir` (default: the manifest's `[dataset] cache`, else `cache/` beside the manifest).
    pub fn cache(mut self, dir: impl Into<PathBuf>) -> Build {
        self.cache = Some(dir.into());
        self
    }

    /// Runs only shard `shard`'s part of the actions into the cache, and writes no outputs.
    pub fn shard(mut self, shard: Option<Shard>) -> Build {
        self.shard = shard;
        self
    }

    /// Hashes every cached file again instead of trusting its metadata (`--verify`).
    pub fn verify(mut self, verify: bool) -> Build {
        self.verify = verify;
        self
    }

    /// The manifest.
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// The cache directory this build uses.
    pub fn cache_dir(&self) -> PathBuf {
        self.cache.clone().unwrap_or_else(|| default_cache_dir(&self.manifest))
    }

    /// Runs the build.
    pub fn run(&self, progress: &dyn Progress) -> Result<Report, Error> {
        let opts = Options { shard: self.shard, verify: self.verify, ..Options::default() };
        build(&self.manifest, &self.cache_dir(), opts, progress)
    }

    /// What the build would do, and (with `explain`) why.
    pub fn status(&self, explain: bool) -> Result<Status, Error> {
        status::status_with(&self.manifest, &self.cache_dir(), explain, self.verify)
    }
}

/// The manifest's cache: `[dataset] cache` (manifest-relative), else `cache/` beside the manifest, as `out`
/// resolves: where a command runs never changes which cache a manifest uses (a build from another folder would
/// otherwise render everything again into a new cache). The CLI's `VVGEN_CACHE` overrides both; the library
/// reads no environment.
pub fn default_cache_dir(m: &Manifest) -> PathBuf {
    m.resolve(m.dataset.cache().unwrap_or("cache"))
}

/// Progress events of a build.
pub trait Progress: Sync {
    /// The cache has been consulted: `cached` actions are cached, `work` will run here.
    fn started(&self, cached: usize, work: usize);
    /// `done` of the `work` actions have run.
    fn ran(&self, done: usize);
    /// Output `name` is being written.
    fn writing(&self, name: &str);
    /// Another build of the same dataset (manifest `what`) holds its lock: this one waits for it.
    fn waiting(&self, what: &str) {
        let _ = what;
    }
    /// Blender is importing a `.blend` source (seconds, once per content: the cache keeps it).
    fn importing(&self, what: &str) {
        let _ = what;
    }
}

/// A progress sink that ignores everything.
pub struct Silent;

impl Progress for Silent {
    fn started(&self, _: usize, _: usize) {}
    fn ran(&self, _: usize) {}
    fn writing(&self, _: &str) {}
}

/// Build options.
#[derive(Debug, Clone, Copy, Default)]
pub struct Options {
    /// Run only this shard's part of the actions and write no outputs.
    pub shard: Option<Shard>,
    /// Hash every cached blob and dataset file again instead of trusting its metadata (finds bit rot).
    pub verify: bool,
    /// Refuse to start when this process would render more images than this (the CLI's guard against a
    /// mistyped view count; `--yes` lifts it).
    pub max_images: Option<usize>,
    /// Refuse ([`Error::NotBuilt`]) when any cacheable action would run: what `release` certifies must be
    /// built already, decided by the same lookup the build makes.
    pub require_built: bool,
    /// Refuse ([`Error::Warnings`]) before anything runs when the scene, the plan or the framing warns
    /// (`[dataset] strict`, the CLI's `--deny-warnings`).
    pub deny_warnings: bool,
}

/// What a build did.
#[derive(Debug, Default)]
pub struct Report {
    /// Per action kind: planned, cached, run, left to other shards. Outputs count as cached when they were
    /// already up to date.
    pub actions: BTreeMap<Kind, Counts>,
    /// The same for the `[dataset] after` manifests, summed.
    pub after_actions: BTreeMap<Kind, Counts>,
    /// Images in the plan that some output renders.
    pub images: usize,
    /// Images whose every pass was cached.
    pub hits: usize,
    /// Images rendered (some pass ran) by this build.
    pub renders: usize,
    /// Seconds in all.
    pub total_seconds: f64,
    /// Each output's dataset (none for a shard build).
    pub outputs: Vec<(String, Written)>,
    /// The outputs of the `[dataset] after` manifests, named `file.toml/output`.
    pub after: Vec<(String, Written)>,
    /// Warnings from the scene and the plan.
    pub warnings: Vec<String>,
    /// Files an earlier build of these outputs wrote that this plan no longer has, removed.
    pub stale_removed: usize,
}

impl Report {
    /// Actions of `kind` run by this build.
    pub fn ran(&self, kind: Kind) -> usize {
        self.actions.get(&kind).map_or(0, |c| c.ran)
    }

    /// Actions of `kind` left to other shards.
    pub fn elsewhere(&self, kind: Kind) -> usize {
        self.actions.get(&kind).map_or(0, |c| c.elsewhere)
    }

    /// Whether the build ran nothing (its `after` manifests included): every action was cached and every output
    /// up to date.
    pub fn nothing_to_do(&self) -> bool {
        self.actions.values().chain(self.after_actions.values()).all(|c| c.ran == 0)
    }
}

/// Everything up to the graph: shared by `build`, `status`, `release` and `gc`.
pub(crate) struct Prepared {
    /// The scene.
    pub scene: Scene,
    /// The image plan.
    pub plan: Plan,
    /// The store.
    pub store: Store,
    /// The dataset's stat cache.
    pub stat: StatCache,
    /// Key of every scene frame.
    pub frame_keys: keys::FrameKeys,
    /// The import actions' keys and blobs (`.blend` sources), which a garbage collection keeps.
    pub imported: Vec<Digest>,
    /// Content key of the environment map, when there is one.
    pub environment: Option<Digest>,
}

impl Prepared {
    /// The action graph of `m` (the manifest this was prepared from).
    pub fn graph(&self, m: &Manifest) -> Result<Graph<'_>, Error> {
        Graph::new(m, &self.plan, &self.scene, &self.frame_keys, self.environment).map_err(|e| Error::plan(m, e))
    }
}

/// Opens the scene, plans the images and keys every frame.
/// With `verify`, every cached file is hashed again instead of trusted by its metadata.
/// `note` hears when a `.blend` import starts Blender.
pub(crate) fn prepare(
    m: &Manifest,
    cache: &Path,
    verify: bool,
    note: Option<&(dyn Fn(&str) + Sync)>,
) -> Result<Prepared, Error> {
    // The store is created before the scene opens only for a `.blend` (imported into it): a manifest whose
    // sources are broken leaves no empty cache behind.
    let blend = m.sources.values().any(|s| s.blend().is_some());
    let early = if blend { Some(Store::open(cache).map_err(|e| Error::cache(m, e))?) } else { None };
    let early_stat = early.as_ref().map(|s| s.stat_cache(&m.out_dir(), verify));
    let importer =
        early.as_ref().zip(early_stat.as_ref()).map(|(s, st)| crate::scene::blend::Importer::new(s, st, note));
    let scene = crate::settings::scene::open(m, importer.as_ref()).map_err(|source| Error::Scene {
        manifest: m.path.clone(),
        source: Box::new(source),
        hint: if m.after.is_empty() {
            ""
        } else {
            " (an `after` manifest may write it: `vvgen build` builds those first)"
        },
    })?;
    let imported = importer.map(|i| i.used()).unwrap_or_default();
    let plan = Plan::new(m, scene.frames).map_err(|e| Error::plan(m, e))?;
    let store = match early {
        Some(s) => s,
        None => Store::open(cache).map_err(|e| Error::cache(m, e))?,
    };
    let stat = early_stat.unwrap_or_else(|| store.stat_cache(&m.out_dir(), verify));
    // Lit point colours read the lit materials too, whatever the images' shading.
    let frame_keys = keys::frame_keys(&scene, &stat, m.lit()).map_err(|e| Error::plan(m, e))?;
    let environment = keys::environment_key(m, &stat).map_err(|e| Error::plan(m, e))?;
    Ok(Prepared { scene, plan, store, stat, frame_keys, environment, imported })
}

/// Builds every output of `m`, using the store at `cache`: runs only the actions the cache lacks. The
/// `[dataset] after` manifests are built first, whole (also for a shard build: this manifest's sources may be
/// their outputs), through the same cache.
pub fn build(m: &Manifest, cache: &Path, opts: Options, progress: &dyn Progress) -> Result<Report, Error> {
    let t0 = Instant::now();
    // What only the renderer's readers check of the inputs (a manifest may come here without `settings::load`).
    let found = crate::settings::diagnose(m);
    if found.iter().any(|d| d.is_error()) {
        let report = crate::manifest::Report { path: m.path.clone(), source: m.text.clone(), diagnostics: found };
        return Err(Error::Manifest(Box::new(report)));
    }
    let mut before = Vec::new();
    let mut before_actions: BTreeMap<Kind, Counts> = BTreeMap::new();
    for a in &m.after {
        let file = a.path.file_name().map_or(String::new(), |f| f.to_string_lossy().into_owned());
        // A shard runs its part of the prerequisites too, so N shards do their work once, not N times.
        let r = build(a, cache, opts, progress)
            .map_err(|e| Error::After { manifest: a.path.clone(), source: Box::new(e) })?;
        for (kind, c) in r.actions.iter().chain(&r.after_actions) {
            before_actions.entry(*kind).or_default().add(c);
        }
        before.extend(r.after.into_iter().chain(r.outputs.into_iter().map(|(name, w)| (format!("{file}/{name}"), w))));
    }
    let p = match prepare(m, cache, opts.verify, Some(&|what: &str| progress.importing(what))) {
        Ok(p) => p,
        // This manifest's sources are its prerequisites' outputs, which only the final unsharded build writes:
        // this shard's part is the prerequisites' work.
        Err(Error::Scene { .. }) if opts.shard.is_some() && !m.after.is_empty() => {
            return Ok(Report {
                after_actions: before_actions,
                total_seconds: t0.elapsed().as_secs_f64(),
                after: before,
                warnings: vec![format!(
                    "{}: waits for its `after` manifests' outputs: the final build runs its actions",
                    m.path.display()
                )],
                ..Report::default()
            });
        }
        Err(e) => return Err(e),
    };
    let g = p.graph(m)?;
    let _lock = record::lock(&p.store, m, opts.shard, || progress.waiting(&m.path.display().to_string()))
        .map_err(|e| Error::cache(m, e))?;
    // Debris of killed builds on this host goes now, not an hour later through `gc`.
    let root = p.store.root();
    for dir in [root.to_path_buf(), root.join("objects"), root.join("actions")] {
        crate::atomic::clean_dead_debris(&dir);
    }
    let last = record::read(&p.store, m);
    let look = execute::lookup(&g, &p.store, &p.stat);
    if opts.require_built {
        let cacheable = |id: &ActionId| g.node(*id).action.kind().cached();
        let pending = g.ids().filter(cacheable).filter(|id| look.state[id.0 as usize] == State::Run).count();
        if pending > 0 {
            return Err(Error::NotBuilt { pending });
        }
    }
    let to_render = execute::images_to_render(&g, &execute::runs_here(&g, &look.state, opts.shard));
    if let Some(max) = opts.max_images {
        if to_render.len() > max {
            return Err(Error::TooMuchWork { manifest: m.path.clone(), images: to_render.len(), max });
        }
    }
    let mut warnings = p.scene.warnings.clone();
    warnings.extend(p.plan.warnings.iter().cloned());
    warnings.extend(crop_warnings(m, &p, &to_render)?);
    if (opts.deny_warnings || m.dataset.strict) && !warnings.is_empty() {
        return Err(Error::Warnings { manifest: m.path.clone(), warnings });
    }
    let environment = m.environment.as_ref().and_then(|e| e.map()).map(|f| m.resolve(f));
    let outcome = crate::cache::Committer::scope(&p.stat, |commit| {
        let inputs =
            Inputs { scene: &p.scene, store: &p.store, stat: &p.stat, environment: environment.as_deref(), commit };
        execute::run(&g, &inputs, look, opts.shard, &|c, w| progress.started(c, w), &|n| progress.ran(n))
    })
    .map_err(|source| Error::Execute { manifest: m.path.clone(), source: Box::new(source) })?;
    let (images, hits, renders) = image_counts(&g, &outcome);
    let mut report = Report {
        actions: outcome.counts.clone(),
        after_actions: before_actions,
        images,
        hits,
        renders,
        total_seconds: 0.0,
        outputs: Vec::new(),
        after: before,
        warnings,
        stale_removed: 0,
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
        graph: &g,
        blobs: &outcome.blobs,
        store: &p.store,
        stat: &p.stat,
    };
    // What earlier builds of these outputs wrote: the cache's record of the last build here (renamed and removed
    // outputs too), and each output's own `vvgen/dataset.json` (which holds even when the cache moved). Read
    // before the outputs are written over.
    let mut previous: BTreeSet<PathBuf> =
        last.outputs.values().flat_map(|o| o.files.iter().map(move |(f, _)| o.root.join(f))).collect();
    for out in m.outputs.values() {
        let root = crate::manifest::lexical(&export::root(m, out));
        previous.extend(export::previous_files(&root).into_iter().map(|f| root.join(f)));
    }
    let mut record = LastBuild::new();
    let write_ids: Vec<_> = g.ids().filter(|id| g.node(*id).action.kind() == Kind::WriteOutput).collect();
    for ((name, out), id) in m.outputs.iter().zip(&write_ids) {
        progress.writing(name);
        let w = export::write(&x, name, out).map_err(|source| Error::Export {
            manifest: m.path.clone(),
            output: name.clone(),
            source: Box::new(source),
        })?;
        let written = OutputRecord {
            root: crate::manifest::lexical(&w.root),
            key: g.node(*id).key.hex(),
            manifest: g.keying.manifest.hex(),
            files: w.files.iter().map(|(f, d)| (f.clone(), d.hex())).collect(),
        };
        // Up to date: the same files as the last build wrote, for the same key, and none had to be placed.
        let fresh = w.changed == 0 && last.outputs.get(name) == Some(&written);
        let c = report.actions.entry(Kind::WriteOutput).or_default();
        c.planned += 1;
        if fresh {
            c.cached += 1;
        } else {
            c.ran += 1;
        }
        record.outputs.insert(name.clone(), written);
        report.outputs.push((name.clone(), w));
    }
    report.stale_removed = prune(&previous, &record, &crate::manifest::lexical(&m.out_dir()));
    record.actions = g.ids().map(|id| (g.node(id).label.clone(), g.node(id).key.hex())).collect();
    let rendered = report.actions.get(&Kind::RenderPass).copied().unwrap_or_default();
    record.seconds_per_action = last.seconds_per_action.clone();
    for (kind, c) in &report.actions {
        if kind.cached() && *kind != Kind::RenderPass && c.ran > 0 && c.seconds > 0.0 {
            record.seconds_per_action.insert(kind.name().to_string(), c.seconds / c.ran as f64);
        }
    }
    record.render_rate = if report.renders > 0 && rendered.seconds > 0.0 {
        Some(report.renders as f64 * pixel_samples(m) / rendered.seconds)
    } else {
        last.render_rate
    };
    record::write(&p.store, m, &record, &last).map_err(|e| Error::cache(m, e))?;
    p.stat.save().map_err(|e| Error::cache(m, crate::cache::Error::io(p.store.root(), e)))?;
    report.total_seconds = t0.elapsed().as_secs_f64();
    Ok(report)
}

/// The crop warnings of a build (and the misread poses of [`crate::plan::coverage::Misread`]): over every image when the scene poses from memory (cheap), over the images
/// this build renders when frames are files (their frames are read for rendering anyway, and a build with
/// nothing to render reads none). `vvgen check` measures every image.
fn crop_warnings(m: &Manifest, p: &Prepared, to_render: &[usize]) -> Result<Vec<String>, Error> {
    use crate::plan::coverage;
    let images = p.scene.reads_frame_files().then_some(to_render);
    let c = coverage::measure(m, &p.scene, &p.plan, images).map_err(|source| Error::Scene {
        manifest: m.path.clone(),
        source: Box::new(source),
        hint: "",
    })?;
    let mut said = coverage::warnings(m, &p.plan, &c);
    said.extend(coverage::misread_warnings(m, &p.plan, &c));
    said.extend(coverage::small_warnings(m, &p.plan, &c));
    Ok(said)
}

/// Images planned, found whole in the cache, and rendered (some pass ran), from the render-pass actions.
fn image_counts(g: &Graph, outcome: &execute::Outcome) -> (usize, usize, usize) {
    use crate::plan::actions::Action;
    // Per image: (every pass cached, some pass ran).
    let mut images: BTreeMap<usize, (bool, bool)> = BTreeMap::new();
    for id in g.ids() {
        if let Action::RenderPass { image, .. } = g.node(id).action {
            let e = images.entry(image).or_insert((true, false));
            e.0 &= outcome.cached[id.0 as usize];
            e.1 |= outcome.ran[id.0 as usize];
        }
    }
    let hits = images.values().filter(|v| v.0).count();
    let renders = images.values().filter(|v| v.1).count();
    (images.len(), hits, renders)
}

/// Pixel-samples of one image of `m`: what rendering time scales with.
pub(crate) fn pixel_samples(m: &Manifest) -> f64 {
    let [w, h] = m.render.resolution();
    w as f64 * h as f64 * m.render.samples() as f64
}

/// Removes the files earlier builds wrote (`previous`) that this one did not (a split that shrank, a frame count
/// cut, a renamed output, another writer), then the folders that leaves empty, up to the dataset's `out` (kept).
/// Only listed files go, and only empty folders: nothing a user put there. Returns how many files it removed.
fn prune(previous: &BTreeSet<PathBuf>, now: &LastBuild, out: &Path) -> usize {
    let keep: BTreeSet<PathBuf> =
        now.outputs.values().flat_map(|o| o.files.iter().map(move |(f, _)| o.root.join(f))).collect();
    let mut removed = 0;
    let mut emptied = BTreeSet::new();
    for p in previous.difference(&keep) {
        if std::fs::remove_file(p).is_ok() {
            removed += 1;
            emptied.extend(p.parent().map(Path::to_path_buf));
        }
    }
    // Deepest first, so a folder whose only content was emptied folders goes too; `remove_dir` refuses a folder
    // that still holds anything.
    for dir in emptied.iter().rev() {
        let mut d = dir.as_path();
        while d.starts_with(out) && d != out && std::fs::remove_dir(d).is_ok() {
            let Some(up) = d.parent() else { break };
            d = up;
        }
    }
    removed
}

/// Every cache entry `m`'s graph reaches: each action's record and blobs (intermediate ones included, so a
/// reduction change still finds its samples), and the blobs of the files its outputs last wrote.
pub fn reachable(m: &Manifest, cache: &Path, keep: &mut HashSet<Digest>) -> Result<(), Error> {
    for a in &m.after {
        reachable(a, cache, keep)?;
    }
    let p = prepare(m, cache, false, None)?;
    keep.extend(p.imported.iter().copied());
    let g = p.graph(m)?;
    for id in g.ids() {
        let n = g.node(id);
        if n.action.kind().cached() {
            keep.insert(n.key);
            keep.extend(p.store.action(&n.key).unwrap_or_default());
        }
    }
    for o in record::read(&p.store, m).outputs.values() {
        keep.extend(o.files.iter().filter_map(|(_, d)| Digest::from_hex(d)));
    }
    Ok(())
}

/// Collects the cache at `cache`: drops what none of `keep` reaches (when any is given), then the oldest
/// beyond `max_bytes` (when given); nothing younger than `min_age` (`gc::GRACE` keeps a running build's
/// unrecorded blobs).
pub fn collect_garbage(
    keep: &[Manifest],
    cache: &Path,
    max_bytes: Option<u64>,
    min_age: std::time::Duration,
) -> Result<gc::Collected, Error> {
    let reach = if keep.is_empty() {
        None
    } else {
        let mut set = HashSet::new();
        for m in keep {
            reachable(m, cache, &mut set)?;
        }
        Some(set)
    };
    Ok(gc::collect(cache, reach.as_ref(), max_bytes, min_age))
}
