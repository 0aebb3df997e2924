//! What a build would do, and why: every action of the graph with its state, and for each that would run the
//! fields that changed since the last build. The reasons come from the keyed walk that made the key (the
//! current fields) and from the fields recorded with the last build's result, so they cannot drift from keying.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

pub use crate::execute::State;

use super::record::{self, LastBuild};
use super::{prepare, Error};
use crate::cache::{Digest, StatCache, Store};
use crate::execute;
use crate::manifest::Manifest;
use crate::plan::actions::{Action, Kind};
use crate::plan::graph::{ActionId, Graph};
use crate::plan::key;

/// Counts of one action kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct KindStatus {
    /// Actions of this kind in the graph.
    pub planned: usize,
    /// Cached (outputs: up to date on disk).
    pub cached: usize,
    /// To run.
    pub run: usize,
    /// Not cached, but not needed: everything that reads them is cached.
    pub unneeded: usize,
}

/// One action's state.
#[derive(Debug, Clone, Serialize)]
pub struct ActionStatus {
    /// Its kind.
    pub kind: Kind,
    /// Its label, e.g. `render train/3/12 depth`.
    pub label: String,
    /// Its key (hex).
    pub key: String,
    /// Cached, to run, or not needed.
    pub state: State,
    /// Why it runs (with `explain`, or always for outputs), one line per changed field.
    pub reasons: Vec<String>,
}

/// What a build of a manifest would do.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Status {
    /// Per kind.
    pub kinds: BTreeMap<Kind, KindStatus>,
    /// Every action, in graph order (inputs first).
    pub actions: Vec<ActionStatus>,
    /// Images a build would render.
    pub images_to_render: usize,
    /// An upper bound of the bytes those images' passes take uncompressed (PNG files are smaller).
    pub bytes_upper_bound: u64,
    /// Seconds the actions to run would take at the rates the last builds here measured: rendering at its
    /// pixel rate, every other kind at its seconds per action (none before a build has run any).
    pub seconds_estimate: Option<f64>,
    /// Kinds with actions to run that no build here has timed yet, left out of the estimate.
    pub not_estimated: Vec<Kind>,
}

impl Status {
    /// Actions of cached kinds that would run (what `release` refuses on).
    pub fn pending(&self) -> usize {
        self.kinds.iter().filter(|(k, _)| k.cached()).map(|(_, s)| s.run).sum()
    }

    /// Actions of `kind` that would run.
    pub fn to_run(&self, kind: Kind) -> usize {
        self.kinds.get(&kind).map_or(0, |s| s.run)
    }

    /// Whether a build would do nothing: every action cached and every output up to date on disk.
    pub fn up_to_date(&self) -> bool {
        self.kinds.values().all(|s| s.run == 0)
    }
}

/// Plans `m` and classifies every action as cached, to run or not needed; with `explain`, says why each action
/// that would run does. Outputs are judged by their files on disk and their key.
pub fn status(m: &Manifest, cache: &Path, explain: bool) -> Result<Status, Error> {
    status_with(m, cache, explain, false)
}

/// [`status`]; with `verify`, every cached file is hashed again instead of trusted by its metadata.
pub fn status_with(m: &Manifest, cache: &Path, explain: bool, verify: bool) -> Result<Status, Error> {
    status_noting(m, cache, explain, verify, None)
}

/// [`status_with`], saying through `note` what it must do first that takes time: a `.blend` source's import by
/// Blender, when the cache does not hold it yet (its frames are what the plan counts).
pub fn status_noting(
    m: &Manifest,
    cache: &Path,
    explain: bool,
    verify: bool,
    note: Option<&(dyn Fn(&str) + Sync)>,
) -> Result<Status, Error> {
    let p = prepare(m, cache, verify, note)?;
    let g = p.graph(m)?;
    let look = execute::lookup(&g, &p.store, &p.stat);
    let images_to_render = execute::images_to_render(&g, &execute::runs_here(&g, &look.state, None)).len();
    let [w, h] = m.render.resolution();
    let per_pixel: u64 = m
        .render
        .passes()
        .iter()
        .map(|p| match p {
            crate::manifest::render::Pass::Rgba => 4,
            crate::manifest::render::Pass::Depth => 2 + if m.render.depth.exr { 4 } else { 0 },
            crate::manifest::render::Pass::Normal => 3 + if m.render.normal.exr { 12 } else { 0 },
            crate::manifest::render::Pass::Mask => 1,
            crate::manifest::render::Pass::Instance => 2,
            crate::manifest::render::Pass::Albedo => 4,
        })
        .sum();
    let bytes_upper_bound = images_to_render as u64 * w as u64 * h as u64 * per_pixel;
    let last = record::read(&p.store, m);
    let mut st = Status { images_to_render, bytes_upper_bound, ..Default::default() };
    for id in g.ids() {
        let n = g.node(id);
        let kind = n.action.kind();
        let (state, reasons) = if kind == Kind::WriteOutput {
            let r = output_reasons(&g, id, &last, &p.stat);
            (if r.is_empty() { State::Cached } else { State::Run }, r)
        } else {
            let s = look.state[id.0 as usize];
            let r = if explain && s == State::Run { action_reasons(&g, id, &last, &p.store) } else { Vec::new() };
            (s, r)
        };
        let k = st.kinds.entry(kind).or_default();
        k.planned += 1;
        match state {
            State::Cached => k.cached += 1,
            State::Run => k.run += 1,
            State::Unneeded => k.unneeded += 1,
        }
        st.actions.push(ActionStatus { kind, label: n.label.clone(), key: n.key.hex(), state, reasons });
    }
    // Rendering at the last measured pixel rate, every other kind at its last seconds per action.
    let mut estimate = None;
    if images_to_render > 0 {
        match last.render_rate {
            Some(rate) => estimate = Some(images_to_render as f64 * super::pixel_samples(m) / rate),
            None => st.not_estimated.push(Kind::RenderPass),
        }
    }
    for (kind, k) in st.kinds.iter().filter(|(k, s)| k.cached() && **k != Kind::RenderPass && s.run > 0) {
        match last.seconds_per_action.get(kind.name()) {
            Some(s) => *estimate.get_or_insert(0.0) += s * k.run as f64,
            None => st.not_estimated.push(*kind),
        }
    }
    st.seconds_estimate = estimate;
    Ok(st)
}

/// Why a cached-kind action must run: new, its result lost, or the fields that changed since the last build.
fn action_reasons(g: &Graph, id: ActionId, last: &LastBuild, store: &Store) -> Vec<String> {
    let n = g.node(id);
    match last.actions.get(&n.label) {
        None => vec!["new: the last build had no such action".into()],
        Some(k) if *k == n.key.hex() => {
            vec!["cached result missing or corrupt (cache cleared, collected or damaged)".into()]
        }
        Some(k) => match Digest::from_hex(k).and_then(|d| store.action_fields(&d)) {
            Some(before) => {
                let d = key::diff(&before, &g.explain(id));
                if d.is_empty() {
                    vec!["its key changed".into()]
                } else {
                    d
                }
            }
            None => vec!["its inputs changed since the last build (whose record of them was collected)".into()],
        },
    }
}

/// Why an output must be written again (empty when it is up to date): new, the manifest or an input changed, or
/// files the last build wrote are missing or modified on disk.
fn output_reasons(g: &Graph, id: ActionId, last: &LastBuild, stat: &StatCache) -> Vec<String> {
    let n = g.node(id);
    let Action::WriteOutput { output } = &n.action else { return Vec::new() };
    let Some(rec) = last.outputs.get(output) else { return vec!["new: the last build did not write it".into()] };
    let mut r = Vec::new();
    if rec.manifest != g.keying.manifest.hex() {
        r.push("the manifest changed (vvgen/dataset.json records its digest)".to_string());
    } else if rec.key != n.key.hex() {
        r.push("its inputs changed (a source, a setting, or a result it places)".to_string());
    }
    let damaged: Vec<&str> = rec
        .files
        .iter()
        .filter(|(f, d)| Digest::from_hex(d).is_none_or(|d| !stat.holds(&rec.root.join(f), &d)))
        .map(|(f, _)| f.as_str())
        .collect();
    if !damaged.is_empty() {
        let head: Vec<&str> = damaged.iter().take(3).copied().collect();
        let more = if damaged.len() > head.len() { format!(" … ({} in all)", damaged.len()) } else { String::new() };
        r.push(format!("files missing or modified on disk: {}{more}", head.join(", ")));
    }
    r
}
