//! The checks that span a manifest's tables ([`cross_check`]): references between them (a split's rig, an
//! output's splits and sources), counts that depend on the rig, and settings of one table that another's
//! contradict (a writer against the render settings, a point output's source and colours).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use super::suggest::{self, did_you_mean};
use super::{consumers, frames, Diagnostic, Manifest, Output, RigKind, Source, Split, TimeMode, Writer};

/// Names of entries that did not parse, so checks across tables do not call them undefined.
pub(super) struct Broken {
    pub(super) sources: BTreeSet<String>,
    pub(super) rigs: BTreeSet<String>,
    pub(super) splits: BTreeSet<String>,
    /// Per split, the keys written in it (a refused value's key included).
    pub(super) split_keys: BTreeMap<String, BTreeSet<String>>,
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

/// Whether `path` holds a splatting trainer's cameras.json (a JSON list, where a transforms.json is an object).
fn holds_splat_cameras(path: &Path) -> bool {
    use std::io::Read as _;
    let mut head = [0u8; 64];
    let n = std::fs::File::open(path).and_then(|mut f| f.read(&mut head)).unwrap_or(0);
    head[..n].iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'[')
}

/// A from-file rig reading a splatting model's cameras.json, whose cameras are in the splat file's coordinates,
/// where a `[transform]` moves the sources off them: the cameras would not see the scene as they did in training.
fn splat_camera_checks(m: &Manifest, diags: &mut Vec<Diagnostic>) {
    let moved = std::iter::once(("[transform]".to_string(), &m.transform))
        .chain(
            m.sources.iter().filter_map(|(n, s)| s.transform.as_ref().map(|t| (format!("[source.{n}.transform]"), t))),
        )
        .find_map(|(table, t)| t.moves().map(|key| (table, key)));
    let Some((table, key)) = moved else { return };
    for (name, rig) in &m.rigs {
        let file = rig.file().filter(|_| *rig.kind.get_ref() == RigKind::FromFile);
        if file.is_some_and(|f| holds_splat_cameras(&m.resolve(f))) {
            diags.push(
                Diagnostic::warning(
                    format!(
                        "rig `{name}` reads a splatting model's cameras.json, whose cameras are in the splat file's \
                         coordinates, and {table}'s `{key}` moves the scene off them: they will not see it as they did \
                         in training"
                    ),
                    Some(rig.kind.span()),
                )
                .with_help("leave the world as the file's: up = \"z\", and no fit, center, matrix or other move"),
            );
        }
    }
}

/// Checks that span tables: references, counts that depend on the rig, writer/render contradictions.
pub(super) fn cross_check(m: &Manifest, broken: &Broken, diags: &mut Vec<Diagnostic>) {
    splat_camera_checks(m, diags);
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
                            format!(
                                "split `{name}`: rig `{rig_name}` is a path, one camera per frame at that frame's pose"
                            ),
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
