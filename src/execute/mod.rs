//! Execution: run the graph's actions the cache lacks, and record each result (blobs plus the fields it was
//! keyed by) in the action cache. A kind runs once every kind its actions read has finished ([`Kind::ALL`] is
//! an order that respects this), so an action's inputs exist before it runs; kinds that do not read each other
//! run at once, and within a kind, actions run in parallel, all on the same worker threads. `lookup` is the
//! side table every reader of the graph shares: which actions are cached, which must run, which are not
//! needed.

mod points;
mod preview;
mod render;
pub mod video;

use std::collections::{BTreeMap, BTreeSet};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use rayon::prelude::*;
use serde::Serialize;

pub use points::{decode_bounds, Grid};

use crate::cache::{self, Digest, StatCache, Store};
use crate::plan::actions::{Action, Kind};
use crate::plan::graph::{ActionId, Graph};
use crate::scene::Scene;

/// Set to stop a running build early (the CLI sets it on Ctrl-C; setting it is async-signal-safe): no action
/// starts or hands over a result after it, what was handed over still commits, and the running build returns
/// [`Error::Interrupted`]. The next build finds those results in the cache.
pub static INTERRUPT: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// What can go wrong running an action.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// [`INTERRUPT`] was set: the build stopped, keeping what had finished.
    #[error("interrupted after {finished} of {work} actions")]
    Interrupted {
        /// Actions that finished (and are in the cache).
        finished: usize,
        /// Actions the build was to run.
        work: usize,
    },
    /// Posing the scene for an action failed (a source file that changed or broke since planning).
    #[error("{action}")]
    Scene {
        /// The action's label.
        action: String,
        /// Why.
        #[source]
        source: crate::scene::Error,
    },
    /// Reading or writing the cache failed.
    #[error("{action}")]
    Cache {
        /// The action's label.
        action: String,
        /// Why.
        #[source]
        source: cache::Error,
    },
    /// Sampling failed: a damaged sample blob, or a topology that changed under correspondence.
    #[error("{action}")]
    Sample {
        /// The action's label.
        action: String,
        /// Why.
        #[source]
        source: crate::sample::Error,
    },
    /// The environment map cannot be read, or its prefiltered blob is damaged.
    #[error("{action}")]
    Environment {
        /// The action's label.
        action: String,
        /// Why.
        #[source]
        source: crate::render::light::environment::Error,
    },
    /// Encoding a video failed.
    #[error("{action}")]
    Video {
        /// The action's label.
        action: String,
        /// Why.
        #[source]
        source: video::Error,
    },
    /// A preview picture cannot be drawn from its inputs (a damaged cache).
    #[error("{action}")]
    Preview {
        /// The action's label.
        action: String,
        /// Why.
        #[source]
        source: crate::preview::Error,
    },
    /// The scene cannot give what the action asks (an empty scene to bound).
    #[error("{action}: {message}")]
    Content {
        /// The action's label.
        action: String,
        /// Why.
        message: String,
    },
}

/// Refuses a posed frame with a NaN or infinite vertex (transforms that overflow, degenerate skins): it would
/// render empty images and sample no points without a word.
fn check_posed(posed: &crate::scene::PosedScene, action: &str) -> Result<(), Error> {
    let bad = posed.primitives.iter().any(|p| p.positions.iter().any(|v| !v.is_finite()));
    if bad {
        let message = "the posed geometry is not finite (a transform or skin overflows)".into();
        return Err(Error::Content { action: action.into(), message });
    }
    Ok(())
}

/// What an executor made: each action it ran, with its blobs.
type Made = Vec<(ActionId, Vec<Digest>)>;

/// Which actions this process runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This process's index, `0..count`.
    pub index: u64,
    /// Number of processes sharing the work.
    pub count: u64,
}

impl Shard {
    /// Whether the action with `key` belongs to this shard (a deterministic partition by key).
    pub fn owns(&self, key: &Digest) -> bool {
        key.prefix_u64() % self.count == self.index
    }
}

/// Where an action stands before a build.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum State {
    /// Its result is in the cache, intact.
    Cached,
    /// It must run: not cached, and an action that runs (or an output) reads it.
    Run,
    /// Not cached, but nothing that runs reads it (its readers are cached).
    Unneeded,
}

/// The cache's answer for every node of a graph.
#[derive(Debug)]
pub(crate) struct Lookup {
    /// Per node, its blobs when cached.
    pub blobs: Vec<Option<Vec<Digest>>>,
    /// Per node, its state. Outputs ([`Kind::WriteOutput`]) are always [`State::Run`]: a build always
    /// places their files (cheaply, when they are in place).
    pub state: Vec<State>,
}

/// Looks every action of `g` up in the store and decides what must run: every output runs; an action that
/// runs needs its inputs, which run in turn when they are not cached (n2's "want" walk, over ids in reverse:
/// inputs come before their readers).
pub(crate) fn lookup(g: &Graph, store: &Store, stat: &StatCache) -> Lookup {
    let blobs: Vec<Option<Vec<Digest>>> =
        g.nodes.par_iter().map(|n| if n.action.kind().cached() { store.hit(&n.key, stat) } else { None }).collect();
    let mut needed: Vec<bool> = g.nodes.iter().map(|n| n.action.kind() == Kind::WriteOutput).collect();
    let mut state = vec![State::Unneeded; g.nodes.len()];
    for i in (0..g.nodes.len()).rev() {
        if blobs[i].is_some() {
            state[i] = State::Cached;
        } else if needed[i] {
            state[i] = State::Run;
            for d in &g.nodes[i].deps {
                needed[d.0 as usize] = true;
            }
        }
    }
    Lookup { blobs, state }
}

/// Counts of one action kind in a build.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Counts {
    /// Actions of this kind in the graph.
    pub planned: usize,
    /// Found in the cache.
    pub cached: usize,
    /// Run by this build.
    pub ran: usize,
    /// Left to other shards.
    pub elsewhere: usize,
    /// Seconds spent running this kind's actions.
    pub seconds: f64,
}

impl Counts {
    /// Adds `other`'s counts to these.
    pub fn add(&mut self, other: &Counts) {
        self.planned += other.planned;
        self.cached += other.cached;
        self.ran += other.ran;
        self.elsewhere += other.elsewhere;
        self.seconds += other.seconds;
    }
}

/// What [`run`] did.
#[derive(Debug)]
pub(crate) struct Outcome {
    /// Per node, its blobs (none for outputs, for actions left to other shards and for unneeded ones).
    pub blobs: Vec<Option<Vec<Digest>>>,
    /// Per kind, what happened (outputs excluded: export counts them).
    pub counts: BTreeMap<Kind, Counts>,
    /// Per node, whether it was found in the cache.
    pub cached: Vec<bool>,
    /// Per node, whether this process ran it.
    pub ran: Vec<bool>,
}

/// What the executors read besides the graph.
pub(crate) struct Inputs<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The blob store.
    pub store: &'a Store,
    /// The stat cache of this dataset.
    pub stat: &'a StatCache,
    /// The `[environment] map`, when there is one.
    pub environment: Option<&'a std::path::Path>,
    /// Where results go to be synced and renamed into the store, off the workers' threads.
    pub commit: &'a cache::Committer,
}

impl Inputs<'_> {
    /// Stores `outputs` as the result of node `id` and records the action with the fields it is keyed by: both
    /// are written here and committed (synced, renamed into place, the record last) by [`Inputs::commit`].
    fn store(&self, g: &Graph, id: ActionId, outputs: &[Vec<u8>]) -> Result<Vec<Digest>, Error> {
        let n = g.node(id);
        let cache_err = |source| Error::Cache { action: n.label.clone(), source };
        let (mut blobs, mut staged) = (Vec::with_capacity(outputs.len()), Vec::new());
        for b in outputs {
            let (d, s) = self.store.stage(b, self.stat).map_err(cache_err)?;
            blobs.push(d);
            staged.extend(s.map(|s| (d, s)));
        }
        let record = self.store.stage_action(&n.key, &blobs, &g.explain(id)).map_err(cache_err)?;
        self.commit.submit(&n.label, staged, record).map_err(cache_err)?;
        Ok(blobs)
    }

    /// Makes the one blob of each action of `ids` with `make`, in parallel, and stores and records it.
    fn each(
        &self,
        g: &Graph,
        ids: &[ActionId],
        done: &(dyn Fn() + Sync),
        make: impl Fn(ActionId) -> Result<Vec<u8>, Error> + Sync,
    ) -> Result<Made, Error> {
        ids.par_iter()
            .map(|&id| {
                let blobs = self.store(g, id, &[make(id)?])?;
                done();
                Ok((id, blobs))
            })
            .collect()
    }

    /// The bytes of node `id`'s `k`-th blob, found in `blobs`.
    fn read(&self, g: &Graph, blobs: &[Option<Vec<Digest>>], id: ActionId, k: usize) -> Result<Vec<u8>, Error> {
        let n = g.node(id);
        let d = blobs[id.0 as usize]
            .as_ref()
            .and_then(|b| b.get(k))
            .ok_or_else(|| Error::Content { action: n.label.clone(), message: "BUG: read before it ran".into() })?;
        self.store.get(d).map_err(|source| Error::Cache { action: n.label.clone(), source })
    }
}

/// Which actions this process runs, of those `state` says must run: those of `shard` (all, without one), and
/// the inputs they read that must run too (a shared input such as a sequence's bounds: cheap, and the same bytes
/// whichever shard makes it). Readers come after their inputs, so one walk from the end settles it.
pub(crate) fn runs_here(g: &Graph, state: &[State], shard: Option<Shard>) -> Vec<bool> {
    // A video reads every frame of its camera, a contact sheet a whole split: in a shard they would pull renders
    // other shards own, so they are left to the unsharded build that writes the outputs (`Kind::gathers`).
    let owns = |id: ActionId| match shard {
        None => true,
        Some(s) => !g.node(id).action.kind().gathers() && s.owns(&owner_key(g, id)),
    };
    let mut here = vec![false; g.nodes.len()];
    for id in g.ids().rev() {
        let i = id.0 as usize;
        let n = g.node(id);
        if n.action.kind().cached() && state[i] == State::Run && (here[i] || owns(id)) {
            here[i] = true;
            for d in &n.deps {
                if state[d.0 as usize] == State::Run {
                    here[d.0 as usize] = true;
                }
            }
        }
    }
    here
}

/// Images (plan indices) with a render pass among `here`.
pub(crate) fn images_to_render(g: &Graph, here: &[bool]) -> Vec<usize> {
    let mut images: Vec<usize> = g
        .ids()
        .filter(|id| here[id.0 as usize])
        .filter_map(|id| match g.node(id).action {
            Action::RenderPass { image, .. } => Some(image),
            _ => None,
        })
        .collect();
    images.sort_unstable();
    images.dedup();
    images
}

/// Runs every action `look` says must run ([`runs_here`]: those of `shard` only, when given, with the inputs
/// they read). `started(cached, work)` is called once the cache has been consulted, `done(n)` after each
/// action.
pub(crate) fn run(
    g: &Graph,
    x: &Inputs,
    look: Lookup,
    shard: Option<Shard>,
    started: &dyn Fn(usize, usize),
    done: &(dyn Fn(usize) + Sync),
) -> Result<Outcome, Error> {
    let Lookup { blobs, state } = look;
    let here = runs_here(g, &state, shard);
    let mut counts: BTreeMap<Kind, Counts> = BTreeMap::new();
    for id in g.ids() {
        let i = id.0 as usize;
        let kind = g.node(id).action.kind();
        if !kind.cached() {
            continue;
        }
        let c = counts.entry(kind).or_default();
        c.planned += 1;
        match state[i] {
            State::Cached => c.cached += 1,
            State::Run if here[i] => c.ran += 1,
            State::Run => c.elsewhere += 1,
            State::Unneeded => {}
        }
    }
    let cached = counts.values().map(|c| c.cached).sum();
    let work = counts.values().map(|c| c.ran).sum();
    started(cached, work);
    let count = AtomicUsize::new(0);
    let tick = || done(count.fetch_add(1, Ordering::Relaxed) + 1);
    let kinds = KindGraph::new(g, &here);
    let run = Running { g, x, here: &here, kinds: &kinds, tick: &tick, state: Mutex::new(Shared::new(blobs, &kinds)) };
    let over = std::sync::atomic::AtomicBool::new(false);
    std::thread::scope(|t| {
        // An interruption stops the build as a failure does: the committer refuses what comes after it.
        t.spawn(|| {
            while !over.load(Ordering::Relaxed) {
                if INTERRUPT.load(Ordering::Relaxed) {
                    x.commit.refuse();
                    return;
                }
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
        });
        rayon::scope(|s| kinds.roots().for_each(|kind| run.spawn(s, kind)));
        over.store(true, Ordering::Relaxed);
    });
    let Shared { blobs, seconds, failure, .. } = run.state.into_inner().unwrap_or_else(|p| p.into_inner());
    if INTERRUPT.load(Ordering::Relaxed) {
        // What was handed over commits as the committer drains; the echoes of its refusal are not failures.
        let _ = x.commit.flush();
        return Err(Error::Interrupted { finished: count.load(Ordering::Relaxed), work });
    }
    if let Some(e) = failure {
        return Err(e);
    }
    for (kind, secs) in seconds {
        counts.entry(kind).or_default().seconds = secs;
    }
    let cached = state.iter().map(|s| *s == State::Cached).collect();
    Ok(Outcome { blobs, counts, cached, ran: here })
}

/// The kinds a build runs and which read which: a kind starts once every kind its actions read has finished, so
/// kinds that do not read each other (a dataset's images and its point clouds) run at once on the same workers,
/// and neither waits at the other's end.
struct KindGraph {
    /// Per kind that runs, the kinds it reads (that run too: cached inputs are already there).
    reads: BTreeMap<Kind, BTreeSet<Kind>>,
}

impl KindGraph {
    /// The kinds of the actions `here` marks, and which of them each reads.
    fn new(g: &Graph, here: &[bool]) -> KindGraph {
        let mut reads: BTreeMap<Kind, BTreeSet<Kind>> = BTreeMap::new();
        for id in g.ids().filter(|id| here[id.0 as usize]) {
            let n = g.node(id);
            let kind = n.action.kind();
            let mine = reads.entry(kind).or_default();
            for d in n.deps.iter().filter(|d| here[d.0 as usize]) {
                let dep = g.node(*d).action.kind();
                // Actions read only kinds earlier in `Kind::ALL` (the graph is built so), so this cannot cycle.
                debug_assert!(order(dep) < order(kind), "{kind:?} reads {dep:?}");
                mine.insert(dep);
            }
        }
        KindGraph { reads }
    }

    /// Kinds that read no kind that runs.
    fn roots(&self) -> impl Iterator<Item = Kind> + '_ {
        self.reads.iter().filter(|(_, r)| r.is_empty()).map(|(k, _)| *k)
    }

    /// Kinds that read `kind`.
    fn readers(&self, kind: Kind) -> impl Iterator<Item = Kind> + '_ {
        self.reads.iter().filter(move |(_, r)| r.contains(&kind)).map(|(k, _)| *k)
    }
}

/// `kind`'s place in [`Kind::ALL`].
fn order(kind: Kind) -> usize {
    Kind::ALL.iter().position(|k| *k == kind).unwrap_or(usize::MAX)
}

/// What the kinds running at once share: the blobs made so far, what each kind still waits for, wall times, and
/// the first failure.
struct Shared {
    blobs: Vec<Option<Vec<Digest>>>,
    /// Per kind not yet started, the kinds it reads that have not finished.
    waiting: BTreeMap<Kind, usize>,
    /// Per finished kind, the wall time from its start to its end (kinds running at once overlap).
    seconds: BTreeMap<Kind, f64>,
    failure: Option<Error>,
}

impl Shared {
    fn new(blobs: Vec<Option<Vec<Digest>>>, kinds: &KindGraph) -> Shared {
        let waiting = kinds.reads.iter().map(|(k, r)| (*k, r.len())).collect();
        Shared { blobs, waiting, seconds: BTreeMap::new(), failure: None }
    }

    /// Keeps the first failure that is a cause: [`cache::Error::Stopped`] is only the echo of one (a kind
    /// refused beside the one that failed), reported only when there is nothing else.
    fn fail(&mut self, e: Error) {
        let echo = |e: &Error| matches!(e, Error::Cache { source: cache::Error::Stopped, .. });
        if self.failure.as_ref().is_none_or(|f| echo(f) && !echo(&e)) {
            self.failure = Some(e);
        }
    }
}

/// One build's kinds running on the worker threads.
struct Running<'a> {
    g: &'a Graph<'a>,
    x: &'a Inputs<'a>,
    here: &'a [bool],
    kinds: &'a KindGraph,
    tick: &'a (dyn Fn() + Sync),
    state: Mutex<Shared>,
}

impl<'a> Running<'a> {
    fn lock(&self) -> std::sync::MutexGuard<'_, Shared> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Runs `kind`'s actions as a task of `s`, then starts the kinds that were waiting only for it. After a
    /// failure nothing new starts, and the committer refuses the running kinds' next results (what they
    /// handed over is kept).
    fn spawn<'s>(&'s self, s: &rayon::Scope<'s>, kind: Kind) {
        s.spawn(move |s| {
            // The kinds it reads are done: their blobs are all in (a copy, so that kinds finishing meanwhile can
            // add theirs).
            let blobs = {
                let p = self.lock();
                if p.failure.is_some() {
                    return;
                }
                p.blobs.clone()
            };
            let (g, x) = (self.g, self.x);
            let ids: Vec<ActionId> =
                g.ids().filter(|id| self.here[id.0 as usize] && g.node(*id).action.kind() == kind).collect();
            let t = std::time::Instant::now();
            let tick = self.tick;
            let made: Result<Made, Error> = match kind {
                Kind::Environment => render::environment(g, x, &ids, tick),
                Kind::Light => render::lights(g, x, &blobs, &ids, tick),
                Kind::RenderPass => render::passes(g, x, &blobs, &ids, tick),
                Kind::Composite => render::composites(g, x, &blobs, &ids, tick),
                Kind::Video => video::videos(g, x, &blobs, &ids, tick),
                Kind::PreviewSheet | Kind::PreviewRig | Kind::PreviewStrip => preview::run(g, x, &blobs, &ids, tick),
                Kind::WriteOutput => unreachable!("outputs are not cached actions"),
                _ => points::run(g, x, &blobs, &ids, tick),
            };
            drop(blobs);
            // Its readers read these results: every commit must be done. A failed commit is the cause to report
            // (the actions after it stopped with `Stopped`).
            let flushed = x.commit.flush().map_err(|(action, source)| Error::Cache { action, source });
            let mut p = self.lock();
            let made = match flushed.and(made) {
                Ok(made) => made,
                Err(e) => {
                    p.fail(e);
                    x.commit.refuse();
                    return;
                }
            };
            for (id, b) in made {
                p.blobs[id.0 as usize] = Some(b);
            }
            p.seconds.insert(kind, t.elapsed().as_secs_f64());
            let mut ready = Vec::new();
            for r in self.kinds.readers(kind) {
                let left = p.waiting.get_mut(&r).expect("BUG: every reader waits");
                *left -= 1;
                if *left == 0 {
                    ready.push(r);
                }
            }
            drop(p);
            ready.into_iter().for_each(|r| self.spawn(s, r));
        });
    }
}

/// The key that decides which shard runs node `id`: its own, except where one action feeds exactly one other,
/// which then go together: the passes of one image (one render serves them all, decided by the image's first
/// planned pass) and its composite, and a frame's samples with the point frame that reduces them.
fn owner_key(g: &Graph, id: ActionId) -> Digest {
    use crate::manifest::render::Pass;
    let key_of = |a: &Action| g.id(a).map(|i| g.node(i).key);
    match &g.node(id).action {
        Action::RenderPass { image, .. } | Action::Composite { image, .. } => {
            let first = [Pass::Rgba, Pass::Depth, Pass::Normal, Pass::Mask, Pass::Instance, Pass::Albedo]
                .into_iter()
                .find_map(|pass| key_of(&Action::RenderPass { image: *image, pass }));
            first.unwrap_or(g.node(id).key)
        }
        Action::SampleFrame { output, frame } => {
            key_of(&Action::PointFrame { output: output.clone(), frame: *frame }).unwrap_or(g.node(id).key)
        }
        _ => g.node(id).key,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dataset's images and its point clouds read nothing of each other, so their kinds start together
    /// (neither waits at the other's end); each kind still waits for the kinds it reads.
    #[test]
    fn images_and_point_clouds_run_at_once_and_readers_wait_for_their_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let glb = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf/CesiumMan/CesiumMan.glb");
        let text = format!(
            "[dataset]\nname = \"k\"\nout = \"out\"\ncache = \"cache\"\npreview = false\n\
             [source.man]\ngltf = {:?}\nframes = {{ count = 2, fps = 24 }}\n\
             [render]\nresolution = [16, 16]\n[rig.o]\nkind = \"orbit\"\n\
             [split.train]\nrig = \"o\"\nviews = 2\ntime = \"all\"\n\
             [output.d]\nwriter = \"colmap\"\n\
             [output.p]\nwriter = \"ply-sequence\"\npoints = 100\nvoxel = 0.01\n",
            glb.display().to_string()
        );
        std::fs::write(dir.path().join("m.toml"), text).unwrap();
        let (m, _) =
            crate::manifest::load(&dir.path().join("m.toml")).unwrap_or_else(|r| panic!("{}", r.render(false)));
        let p = crate::build::prepare(&m, &dir.path().join("cache"), false, None).unwrap();
        let g = p.graph(&m).unwrap();
        let look = lookup(&g, &p.store, &p.stat);
        let kinds = KindGraph::new(&g, &runs_here(&g, &look.state, None));
        let roots: BTreeSet<Kind> = kinds.roots().collect();
        assert!(roots.contains(&Kind::RenderPass), "{:?}", kinds.reads);
        assert!(roots.contains(&Kind::SampleFrame) || roots.contains(&Kind::Bounds), "{:?}", kinds.reads);
        let readers = |k| kinds.readers(k).collect::<BTreeSet<Kind>>();
        assert_eq!(readers(Kind::RenderPass), BTreeSet::from([Kind::Composite]), "{:?}", kinds.reads);
        assert!(readers(Kind::SampleFrame).contains(&Kind::PointFrame), "{:?}", kinds.reads);
        assert!(!kinds.reads[&Kind::PointFrame].contains(&Kind::RenderPass));
    }

    /// A refusal echoed by a kind running beside the one that failed never hides the failure, whichever
    /// reports first; the first cause is kept.
    #[test]
    fn the_first_cause_is_reported_not_its_echo() {
        let stopped = || Error::Cache { action: "b".into(), source: cache::Error::Stopped };
        let cause = |a: &str| Error::Content { action: a.into(), message: "broken".into() };
        let mut p = Shared::new(Vec::new(), &KindGraph { reads: BTreeMap::new() });
        p.fail(stopped());
        p.fail(cause("a"));
        p.fail(stopped());
        p.fail(cause("c"));
        assert!(matches!(&p.failure, Some(Error::Content { action, .. }) if action == "a"), "{:?}", p.failure);
    }
}
