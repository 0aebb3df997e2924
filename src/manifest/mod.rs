//! The manifest language: TOML text → a validated [`Manifest`], or every problem in it.
//!
//! Each table has its own module and type; [`parse`] walks the spanned TOML tree, deserializes every entry
//! on its own (so all errors are found, not just the first), then runs the table checks and the checks that
//! span tables (references, file existence, writer/render contradictions). The manifest reference is
//! `docs/manifest.md`.

mod after;
pub mod consumers;
pub mod dataset;
pub mod diag;
pub mod frames;
pub mod framing;
pub mod light;
pub mod output;
pub mod render;
pub mod rig;
pub mod schema;
pub mod sequence;
pub mod source;
pub mod split;
pub mod suggest;
pub mod transform;
mod walk;

use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};

pub use dataset::Dataset;
pub use diag::{Diagnostic, Report, Severity};
pub use output::{Output, Writer};
pub use render::Render;
pub use rig::{Rig, RigKind};
pub use source::{Source, SourceKind};
pub use split::{Split, TimeMode};
pub use transform::Transform;

pub(crate) use after::lexical;
use suggest::did_you_mean;

/// The top-level tables, in the order the reference documents them.
pub const TABLES: &[&str] =
    &["dataset", "source", "transform", "render", "environment", "light", "rig", "split", "output"];

/// The folder a file's relative names resolve against: its parent, or `.` for a bare name (`Path::parent`
/// of `model.gltf` is the empty path, which `canonicalize` and `read_dir` refuse).
pub fn folder_of(file: &Path) -> &Path {
    match file.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// A validated manifest. Named tables are kept sorted by name, so table order in the file never matters.
#[derive(Debug, Clone)]
pub struct Manifest {
    /// The manifest file.
    pub path: PathBuf,
    /// Its directory: relative paths resolve against it.
    pub dir: PathBuf,
    /// The manifest's bytes, as read.
    pub text: String,
    /// `[dataset]`.
    pub dataset: Dataset,
    /// `[source.NAME]`.
    pub sources: BTreeMap<String, Source>,
    /// The global `[transform]`, applied to the whole scene.
    pub transform: Transform,
    /// `[render]`.
    pub render: Render,
    /// `[environment]`, when given.
    pub environment: Option<light::Environment>,
    /// `[light.NAME]`.
    pub lights: BTreeMap<String, light::Light>,
    /// `[rig.NAME]`.
    pub rigs: BTreeMap<String, Rig>,
    /// `[split.NAME]`.
    pub splits: BTreeMap<String, Split>,
    /// `[output.NAME]`.
    pub outputs: BTreeMap<String, Output>,
    /// The `[dataset] after` manifests, loaded and checked, in the order given.
    pub after: Vec<Manifest>,
}

impl Manifest {
    /// Seconds between consecutive frames of the dataset: `step / fps` of the first source (by name) that gives
    /// `frames`, else 1/30 s. What a `path` rig's keyframe times are measured in (frame `f` at `f × period`).
    pub fn frame_period(&self) -> f64 {
        self.sources.values().find_map(|s| s.frames().map(|f| f.step() as f64 / f.fps())).unwrap_or(1.0 / 30.0)
    }

    /// Whether anything is lit: `pbr` renders, or a `ply-sequence` with `color = "lit"`.
    pub fn lit(&self) -> bool {
        self.render.shading == render::Shading::Pbr
            || self.outputs.values().any(|o| o.color == Some(output::PointColor::Lit))
    }

    /// Resolves a manifest-relative path.
    pub fn resolve(&self, p: &str) -> PathBuf {
        self.dir.join(p)
    }

    /// The dataset output root.
    pub fn out_dir(&self) -> PathBuf {
        self.resolve(self.dataset.out.get_ref())
    }

    /// Whether a source reads a sequence one of the `after` manifests writes: its inputs exist only once
    /// `build` has run those, so `check` cannot open them yet.
    pub fn reads_produced_inputs(&self) -> bool {
        let produced = after::produced_sequences(&self.after);
        self.sources.values().any(|s| {
            matches!(s.kind_spanned(), Some((SourceKind::PlySequence, p))
                if produced.contains(&after::lexical(&self.dir.join(p.get_ref()))))
        })
    }
}

/// Reads and checks a manifest file. `Ok` carries the manifest and its warnings; `Err` every problem found.
pub fn load(path: &Path) -> Result<(Manifest, Report), Report> {
    match std::fs::read_to_string(path) {
        Ok(text) => parse(&text, path),
        Err(e) => Err(Report {
            path: path.to_path_buf(),
            source: String::new(),
            diagnostics: vec![Diagnostic::error(format!("cannot read the manifest: {e}"), None)],
        }),
    }
}

/// Checks manifest `text` as if read from `path` (paths in it resolve against `path`'s directory).
pub fn parse(text: &str, path: &Path) -> Result<(Manifest, Report), Report> {
    parse_with(text, path, &mut vec![after::identity(path)])
}

/// [`parse`], with the `after` manifests being loaded around this one (outermost first).
fn parse_with(text: &str, path: &Path, stack: &mut Vec<PathBuf>) -> Result<(Manifest, Report), Report> {
    let mut diags = Vec::new();
    let manifest = parse_inner(text, path, stack, &mut diags);
    // Report in reading order; problems without a place come last.
    diags.sort_by_key(|d| d.span.as_ref().map_or(usize::MAX, |s| s.start));
    let report = Report { path: path.to_path_buf(), source: text.to_string(), diagnostics: diags };
    match manifest {
        Some(m) if report.error_count() == 0 => Ok((m, report)),
        _ => Err(report),
    }
}

fn parse_inner(text: &str, path: &Path, stack: &mut Vec<PathBuf>, diags: &mut Vec<Diagnostic>) -> Option<Manifest> {
    let (root, syntax) = DeTable::parse_recoverable(text);
    if !syntax.is_empty() {
        for e in syntax {
            let span = e.span();
            diags.push(Diagnostic::error(format!("TOML syntax: {}", e.message().trim()), span));
        }
        return None;
    }
    let root = root.into_inner();
    for (_, value) in root.iter() {
        non_finite(value, diags);
    }
    let mut tables: BTreeMap<&str, &walk::Raw<'_>> = BTreeMap::new();
    for (key, value) in root.iter() {
        let name: &str = key.get_ref().as_ref();
        if let Some(table) = TABLES.iter().find(|t| **t == name) {
            tables.insert(table, value);
        } else {
            let mut d = Diagnostic::error(format!("unknown table `{name}`"), Some(key.span()));
            d = match did_you_mean(name, TABLES.iter().copied()) {
                Some(s) => {
                    d.message = format!("unknown table `{name}`, did you mean `{s}`?");
                    d.with_help(format!("did you mean `[{s}…]`?"))
                }
                None => d.with_help(format!("tables are {}", suggest::one_of(TABLES))),
            };
            diags.push(d);
        }
    }

    let dataset: Option<Dataset> = match tables.get("dataset") {
        Some(v) => walk::typed(v, diags),
        None => {
            diags.push(
                Diagnostic::error("missing `[dataset]` table", Some(0..0))
                    .with_help("start with [dataset] name = \"…\" out = \"out/…\""),
            );
            None
        }
    };
    let transform: Option<Transform> =
        tables.get("transform").map_or(Some(Transform::default()), |v| walk::typed(v, diags));
    let render: Option<Render> = tables.get("render").map_or(Some(Render::default()), |v| walk::typed(v, diags));
    let environment: Option<light::Environment> = tables.get("environment").and_then(|v| walk::typed(v, diags));
    let lights = named::<light::Light>(tables.get("light"), "light", diags);
    let sources = named::<Source>(tables.get("source"), "source", diags);
    let rigs = named::<Rig>(tables.get("rig"), "rig", diags);
    let splits = named::<Split>(tables.get("split"), "split", diags);
    let outputs = named::<Output>(tables.get("output"), "output", diags);

    // Table-local checks run on whatever parsed, so their errors join the type errors above.
    if let Some(d) = &dataset {
        d.validate(diags);
    }
    if let Some(t) = &transform {
        t.validate(diags);
    }
    if let Some(r) = &render {
        r.validate(diags);
    }
    let dir = folder_of(path).to_path_buf();
    let mut after = Vec::new();
    for a in dataset.iter().flat_map(|d| &d.after) {
        match after::load(&dir, a.get_ref(), stack) {
            Ok(m) => after.push(m),
            Err(e) => diags.push(
                Diagnostic::error(format!("`after` manifest: {e}"), Some(a.span()))
                    .with_help("`after` lists manifests, relative to this one's folder, built before it"),
            ),
        }
    }
    let produced = after::produced_sequences(&after);
    {
        let (sources, _) = &sources;
        if sources.is_empty() {
            let span = tables.get("source").map(|v| v.span());
            diags.push(
                Diagnostic::error("no `[source.NAME]` table: there is nothing to render", span)
                    .with_help("add e.g. [source.main] gltf = \"model.glb\""),
            );
        }
        for (name, (s, span, _)) in sources {
            s.validate(name, span.clone(), diags);
            check_source_files(&dir, s, &produced, diags);
        }
    }
    if let Some(e) = &environment {
        e.validate(diags);
    }
    for (name, (l, span, _)) in &lights.0 {
        l.validate(name, span.clone(), diags);
    }
    {
        let (rigs, _) = &rigs;
        for (name, (r, _, keys)) in rigs {
            let keys: Vec<(&str, Range<usize>)> = keys.iter().map(|(k, s)| (k.as_str(), s.clone())).collect();
            r.validate(name, &keys, diags);
            for f in r.file.iter().chain(&r.trace).chain(&r.dataparser_transforms) {
                if !dir.join(f.get_ref()).is_file() {
                    diags.push(
                        Diagnostic::error(
                            format!("file not found: {}", dir.join(f.get_ref()).display()),
                            Some(f.span()),
                        )
                        .with_help("paths are relative to the manifest's folder"),
                    );
                }
            }
        }
    }
    {
        let (splits, _) = &splits;
        for (s, _, _) in splits.values() {
            s.validate(diags);
        }
    }
    {
        let (outputs, _) = &outputs;
        for (name, (o, _, keys)) in outputs {
            let keys: Vec<(&str, Range<usize>)> = keys.iter().map(|(k, s)| (k.as_str(), s.clone())).collect();
            o.validate(name, &keys, diags);
        }
    }

    // Keys written in each split, parsed or not: a key whose value was refused is not "missing" too.
    let split_keys =
        splits.0.iter().map(|(n, (_, _, keys))| (n.clone(), keys.iter().map(|(k, _)| k.clone()).collect())).collect();
    let broken = Broken { sources: sources.1, rigs: rigs.1, splits: splits.1, split_keys };
    let manifest = Manifest {
        path: path.to_path_buf(),
        dir,
        text: text.to_string(),
        dataset: dataset?,
        sources: strip(sources.0),
        transform: transform.unwrap_or_default(),
        render: render.unwrap_or_default(),
        environment,
        lights: strip(lights.0),
        rigs: strip(rigs.0),
        splits: strip(splits.0),
        outputs: strip(outputs.0),
        after,
    };
    cross_check(&manifest, &broken, diags);
    Some(manifest)
}

fn strip<T>(m: Named<T>) -> BTreeMap<String, T> {
    m.into_iter().map(|(k, (v, _, _))| (k, v)).collect()
}

type Named<T> = BTreeMap<String, (T, Range<usize>, Vec<(String, Range<usize>)>)>;

/// Names of entries that did not parse, so checks across tables do not call them undefined.
struct Broken {
    sources: BTreeSet<String>,
    rigs: BTreeSet<String>,
    splits: BTreeSet<String>,
    /// Per split, the keys written in it (a refused value's key included).
    split_keys: BTreeMap<String, BTreeSet<String>>,
}

/// Whether `name` is safe as a file or folder name on every platform: letters, digits, `-`, `_` and `.`, and not
/// dots alone (`.` and `..` name directories).
pub(crate) fn is_plain_name(name: &str) -> bool {
    !name.is_empty()
        && name.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
        && !name.chars().all(|c| c == '.')
}

/// Deserializes every entry of a `[kind.NAME]` table; keeps each entry's span and key list, and returns the
/// names of entries that could not be recovered.
fn named<T: serde::de::DeserializeOwned>(
    value: Option<&&walk::Raw<'_>>,
    kind: &str,
    diags: &mut Vec<Diagnostic>,
) -> (Named<T>, BTreeSet<String>) {
    let mut out = BTreeMap::new();
    let mut broken = BTreeSet::new();
    let Some(value) = value else {
        return (out, broken);
    };
    for (name, key_span, entry) in walk::entries(value, kind, diags) {
        // Split names become file and folder names inside a dataset (`train/r_0000.png`, `transforms_train.json`,
        // `preview/sheet-train.png`), output names folder names (`vvgen preview --out DIR/OUTPUT`): a name that
        // is not a plain file name could write outside the dataset.
        if matches!(kind, "split" | "output") && !is_plain_name(name) {
            diags.push(
                Diagnostic::error(format!("{kind} name `{name}` is not a plain file name"), Some(key_span.clone()))
                    .with_help(
                        "use letters, digits, `-`, `_` and `.` only (not dots alone): it names files in the dataset",
                    ),
            );
            broken.insert(name.to_string());
            continue;
        }
        if !matches!(entry.get_ref(), DeValue::Table(_)) {
            diags.push(
                Diagnostic::error(format!("`{kind}.{name}` must be a table"), Some(key_span))
                    .with_help(format!("write it as [{kind}.{name}] followed by its keys")),
            );
            broken.insert(name.to_string());
            continue;
        }
        let keys = walk::keys(entry).into_iter().map(|(k, s)| (k.to_string(), s)).collect();
        match walk::typed::<T>(entry, diags) {
            Some(t) => {
                out.insert(name.to_string(), (t, entry.span(), keys));
            }
            None => {
                broken.insert(name.to_string());
            }
        }
    }
    (out, broken)
}

/// Checks that a source's files exist; a `ply_sequence` that an `after` manifest writes (`produced`) counts as
/// present, since `vvgen build` writes it first.
fn check_source_files(dir: &Path, s: &Source, produced: &[PathBuf], diags: &mut Vec<Diagnostic>) {
    let Some((kind, p)) = s.kind_spanned() else { return };
    match kind {
        SourceKind::Gltf | SourceKind::Fbx | SourceKind::Blend | SourceKind::Mesh => {
            let full = dir.join(p.get_ref());
            if !full.is_file() {
                diags.push(
                    Diagnostic::error(format!("file not found: {}", full.display()), Some(p.span()))
                        .with_help("paths are relative to the manifest's folder"),
                );
            }
        }
        SourceKind::PlySequence | SourceKind::MeshSequence => {
            if produced.contains(&after::lexical(&dir.join(p.get_ref()))) {
                return;
            }
            let frames = s.frames.as_ref().map(|f| f.get_ref().clone()).unwrap_or_default();
            if let Err(e) = sequence::resolve(dir, p.get_ref(), &frames) {
                diags.push(
                    Diagnostic::error(format!("PLY sequence: {e}"), Some(p.span()))
                        .with_help("paths are relative to the manifest's folder; patterns use {frame} or {frame:04}"),
                );
            }
        }
    }
}

/// The DyNeRF layout is synchronized video: every split it writes has every camera at every frame, over the
/// same frames (the plan refuses it too; here it is refused before anything renders).
fn dynerf_checks(m: &Manifest, name: &str, out: &Output, diags: &mut Vec<Diagnostic>) {
    let selected = consumers::selected_splits(m, out);
    let mut frames: Option<(&str, Option<&frames::FrameSubset>)> = None;
    let moving = |s: &Split| m.rigs.get(s.rig()).is_some_and(|r| r.kind() == RigKind::Path);
    let (mut fixed, mut paths) = (0, Vec::new());
    for split_name in selected {
        let Some(split) = m.splits.get(split_name) else { continue };
        if moving(split) {
            // A path is written beside the synchronized cameras, as one video.
            paths.push(split_name);
            continue;
        }
        fixed += 1;
        let help = "the dynerf layout is synchronized video: every camera at every frame";
        if split.time != TimeMode::All {
            diags.push(
                Diagnostic::error(
                    format!("output `{name}` (dynerf) writes split `{split_name}`, whose time is not \"all\""),
                    Some(out.writer.span()),
                )
                .with_help(help),
            );
        }
        let these = split.frames.as_ref().map(|f| f.get_ref());
        match frames {
            Some((first, f)) if f != these => diags.push(
                Diagnostic::error(
                    format!("output `{name}` (dynerf): splits `{first}` and `{split_name}` select different frames"),
                    Some(out.writer.span()),
                )
                .with_help(help),
            ),
            Some(_) => {}
            None => frames = Some((split_name, these)),
        }
    }
    if let (0, Some(first)) = (fixed, paths.first()) {
        diags.push(
            Diagnostic::error(
                format!("output `{name}` (dynerf) writes only path split `{first}`: the loaders' cameras are fixed"),
                Some(out.writer.span()),
            )
            .with_help("add a split of fixed cameras (e.g. a forward-facing rig, time = \"all\"); a path split is written beside them as one video"),
        );
    }
}

/// Every float of a manifest must be finite: TOML has `nan` and `inf`, and `1e400` overflows to infinity, and
/// any of them would reach matrices, cameras and images as garbage.
fn non_finite(v: &walk::Raw<'_>, diags: &mut Vec<Diagnostic>) {
    match v.get_ref() {
        DeValue::Float(f) => {
            let text = f.as_str();
            if !text.replace('_', "").parse::<f64>().is_ok_and(f64::is_finite) {
                diags.push(
                    Diagnostic::error(format!("`{text}` is not a finite number"), Some(v.span()))
                        .with_help("every number in a manifest must be finite (no nan, no inf, no overflow)"),
                );
            }
        }
        DeValue::Array(a) => a.iter().for_each(|x| non_finite(x, diags)),
        DeValue::Table(t) => t.iter().for_each(|(_, x)| non_finite(x, diags)),
        _ => {}
    }
}

/// A `ply-sequence` output's settings that cannot work together (the plan refuses them too, for library
/// callers that skip `check`).
fn point_output_checks(m: &Manifest, name: &str, out: &Output, diags: &mut Vec<Diagnostic>) {
    let sources: Vec<&Source> = match &out.source {
        Some(s) => m.sources.get(s.get_ref()).into_iter().collect(),
        None => m.sources.values().collect(),
    };
    let sequence = sources.iter().any(|s| s.kind().is_some_and(|(k, _)| k.is_sequence()));
    let span = Some(out.writer.span());
    if out.correspondence == Some(true) && sequence {
        diags.push(
            Diagnostic::error(format!("output `{name}`: `correspondence` needs mesh sources"), span.clone()).with_help(
                "a PLY or mesh sequence has no fixed surface to track (its points or topology change every \
                     frame); sample one mesh source with `source = \"…\"`",
            ),
        );
    }
    let tracked = out.correspondence.unwrap_or(!sequence);
    if out.motion && (!tracked || out.voxel.is_some() || out.vox.is_some()) {
        diags.push(
            Diagnostic::error(format!("output `{name}`: `motion` needs correspondence and no `voxel` or `vox`"), span)
                .with_help("merged points have no track: drop `voxel`/`vox`, or write motion in a second output"),
        );
    }
}

/// Checks that span tables: references, counts that depend on the rig, writer/render contradictions.
fn cross_check(m: &Manifest, broken: &Broken, diags: &mut Vec<Diagnostic>) {
    for (name, split) in &m.splits {
        let rig_name = split.rig.get_ref();
        match m.rigs.get(rig_name) {
            None if broken.rigs.contains(rig_name) => {}
            None => {
                let mut d = Diagnostic::error(
                    format!("split `{name}` uses rig `{rig_name}`, which is not defined"),
                    Some(split.rig.span()),
                );
                d = match did_you_mean(rig_name, m.rigs.keys().map(String::as_str)) {
                    Some(s) => d.with_help(format!("did you mean `{s}`?")),
                    None if m.rigs.is_empty() => d.with_help(format!("add a [rig.{rig_name}] table")),
                    None => d.with_help(format!(
                        "defined rigs: {}",
                        suggest::one_of(&m.rigs.keys().map(String::as_str).collect::<Vec<_>>())
                    )),
                };
                diags.push(d);
            }
            Some(rig) => {
                let kind = *rig.kind.get_ref();
                if kind.counts_itself() {
                    if let Some(v) = &split.views {
                        diags.push(Diagnostic::warning(
                            format!("`views` is ignored: rig `{rig_name}` ({}) fixes its own views", kind.name()),
                            Some(v.span()),
                        ));
                    }
                } else if split.views.is_none()
                    && split.time != TimeMode::Monocular
                    && !broken.split_keys.get(name).is_some_and(|k| k.contains("views"))
                {
                    diags.push(
                        Diagnostic::error(format!("split `{name}` needs `views`"), Some(split.rig.span()))
                            .with_help("e.g. views = 100"),
                    );
                }
                if kind == RigKind::Path && split.time == TimeMode::Random {
                    diags.push(
                        Diagnostic::error(
                            format!("split `{name}`: rig `{rig_name}` is a path, one camera per frame at that frame's pose"),
                            Some(split.rig.span()),
                        )
                        .with_help("remove time = \"random\" (a path split renders every selected frame once)"),
                    );
                }
                if let (RigKind::Dome, Some(r), Some(v)) = (kind, &rig.rings, &split.views) {
                    // rings = 0 is its own error (reported by the rig); no remainder by zero here.
                    if *r.get_ref() > 0 && v.get_ref() % r.get_ref() != 0 {
                        diags.push(
                            Diagnostic::error(
                                format!("views = {} does not divide into {} rings", v.get_ref(), r.get_ref()),
                                Some(v.span()),
                            )
                            .with_help("use a multiple of `rings`"),
                        );
                    }
                }
            }
        }
    }
    for (name, out) in &m.outputs {
        let writer = *out.writer.get_ref();
        for s in out.splits.iter().flatten() {
            if !m.splits.contains_key(s.get_ref()) && !broken.splits.contains(s.get_ref()) {
                let msg = format!("output `{name}` lists split `{}`, which is not defined", s.get_ref());
                diags.push(suggest::undefined(msg, s.get_ref(), m.splits.keys().map(String::as_str), s.span()));
            }
        }
        if let Some(src) = &out.source {
            if !m.sources.contains_key(src.get_ref()) && !broken.sources.contains(src.get_ref()) {
                let msg = format!("output `{name}` uses source `{}`, which is not defined", src.get_ref());
                diags.push(suggest::undefined(msg, src.get_ref(), m.sources.keys().map(String::as_str), src.span()));
            }
        }
        if writer.renders_images() && m.splits.is_empty() && broken.splits.is_empty() {
            diags.push(
                Diagnostic::error(
                    format!("output `{name}` ({}) renders images but no `[split.NAME]` is defined", writer.name()),
                    Some(out.writer.span()),
                )
                .with_help("add e.g. [split.train] rig = \"…\" views = 100"),
            );
        }
        if writer == Writer::PlySequence {
            point_output_checks(m, name, out, diags);
        }
        if writer == Writer::Dynerf {
            dynerf_checks(m, name, out, diags);
        }
        // Default directories too (two `ply-sequence` outputs both default to `<name>_points`).
        let dataset = m.dataset.name.get_ref();
        let here = out.dir_name(dataset);
        // Directories as their plain components (`.` and trailing slashes dropped), to compare and nest.
        let parts = |d: &str| -> Vec<String> {
            Path::new(d)
                .components()
                .filter(|c| *c != std::path::Component::CurDir)
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect()
        };
        let span = out.dir.as_ref().map_or(out.writer.span(), |d| d.span());
        for (other, o2) in &m.outputs {
            let there = o2.dir_name(dataset);
            let (a, b) = (parts(&here), parts(&there));
            if other > name && a == b {
                diags.push(
                    Diagnostic::error(
                        format!("outputs `{name}` and `{other}` write to the same directory `{here}`"),
                        Some(span.clone()),
                    )
                    .with_help("give one of them its own `dir`"),
                );
            } else if other != name && b.len() > a.len() && b.starts_with(&a) {
                // A released dataset must verify: the outer output's lock would list the inner one's files as
                // extra (and a stale-file sweep of one would reach into the other).
                diags.push(
                    Diagnostic::error(
                        format!("output `{name}`'s directory `{here}` holds output `{other}`'s (`{there}`)"),
                        Some(span.clone()),
                    )
                    .with_help(
                        "give each output a directory of its own beside the others, e.g. dir = \"a\" and dir = \"b\"",
                    ),
                );
            }
        }
    }
    if !m.lit() {
        let unused = m
            .lights
            .keys()
            .next()
            .map(|n| format!("`[light.{n}]`"))
            .or(m.environment.as_ref().map(|_| "`[environment]`".to_string()));
        if let Some(what) = unused {
            diags.push(
                Diagnostic::warning(format!("{what} lights nothing: `[render] shading` is not \"pbr\""), None)
                    .with_help(
                        "set `[render] shading = \"pbr\"` to render lit (or a ply-sequence's `color = \"lit\"`)",
                    ),
            );
        }
    }
    consumers::diagnose(m, diags);
    if m.outputs.is_empty() {
        diags.push(
            Diagnostic::warning("no `[output.NAME]` table: a build would write nothing", None)
                .with_help("add e.g. [output.dnerf] writer = \"dnerf\""),
        );
    }
}
