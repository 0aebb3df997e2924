//! The manifest language: TOML text → a validated [`Manifest`], or every problem in it.
//!
//! Each table has its own module and type; [`parse`] walks the spanned TOML tree, deserializes every entry
//! on its own (so all errors are found, not just the first), then runs the table checks, the source files'
//! existence, and the checks that span tables (`cross`: references, writer/render contradictions). The manifest
//! reference is `docs/manifest.md`.

mod after;
pub mod consumers;
mod cross;
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
    let fail = |d: Diagnostic| Report { path: path.to_path_buf(), source: String::new(), diagnostics: vec![d] };
    if let Some(d) = not_a_manifest(path) {
        return Err(fail(d));
    }
    match std::fs::read_to_string(path) {
        Ok(text) => parse(&text, path),
        Err(e) => Err(fail(Diagnostic::error(format!("cannot read the manifest: {e}"), None))),
    }
}

/// A newcomer's first try is often `vvgen build model.glb`: an asset or a folder where a manifest belongs is
/// named as such, with the command that writes its manifest, instead of a TOML syntax error at its first byte.
fn not_a_manifest(path: &Path) -> Option<Diagnostic> {
    let shown = path.display().to_string();
    // As it would be typed: a name with spaces (`Breathing Idle.fbx`, as Mixamo names them) in quotes.
    let typed = if shown.contains(|c: char| c.is_whitespace() || "'\"$&;|()<>*?".contains(c)) {
        format!("'{}'", shown.replace('\'', r"'\''"))
    } else {
        shown.clone()
    };
    if path.is_dir() {
        let mut tomls: Vec<String> = std::fs::read_dir(path)
            .ok()?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "toml") && p.is_file())
            .map(|p| p.display().to_string())
            .collect();
        tomls.sort();
        let help = match tomls.len() {
            0 => format!("`vvgen new {typed}` writes a manifest for a folder of PLY, OBJ, STL or Draco frames"),
            _ => format!("name a manifest: {}", tomls.join(", ")),
        };
        return Some(Diagnostic::error(format!("{shown} is a folder, not a manifest"), None).with_help(help));
    }
    let ext = path.extension()?.to_string_lossy().to_ascii_lowercase();
    let kind = match ext.as_str() {
        "gltf" | "glb" => "a glTF file",
        "fbx" => "an FBX file",
        "blend" => "a Blender file",
        "ply" => "a PLY file",
        "obj" => "an OBJ file",
        "stl" => "an STL file",
        "drc" => "a Draco file",
        _ => return None,
    };
    let help = format!("`vvgen new {typed}` writes a manifest for it; check and build that");
    Some(Diagnostic::error(format!("{shown} is {kind}, not a manifest"), None).with_help(help))
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
    let broken = cross::Broken { sources: sources.1, rigs: rigs.1, splits: splits.1, split_keys };
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
    cross::cross_check(&manifest, &broken, diags);
    Some(manifest)
}

fn strip<T>(m: Named<T>) -> BTreeMap<String, T> {
    m.into_iter().map(|(k, (v, _, _))| (k, v)).collect()
}

type Named<T> = BTreeMap<String, (T, Range<usize>, Vec<(String, Range<usize>)>)>;

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
