//! The record of the last complete build of a dataset, kept in the cache (`builds/`): which files each output
//! produced (so files a later build no longer produces are removed, and damage is noticed), and the key of
//! every action by label (so `plan --explain` can find the last build's version of an action and compare the
//! fields it was keyed by, recorded beside its result in the action cache).

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::cache::{self, Store};
use crate::manifest::Manifest;

/// Format version of the record; a record of another version reads as none.
const VERSION: u32 = 3;

/// The last complete build of one manifest's dataset ([`Default`] is "no build": version 0).
#[derive(Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LastBuild {
    /// Format version.
    pub version: u32,
    /// Output name → what it wrote.
    pub outputs: BTreeMap<String, OutputRecord>,
    /// Action label → key (hex).
    pub actions: BTreeMap<String, String>,
    /// Pixel-samples rendered per second by the last build that rendered here (what `plan` estimates time
    /// from).
    #[serde(default)]
    pub render_rate: Option<f64>,
    /// Per action kind other than renders (by name), the wall seconds per action the last build that ran some
    /// measured (kinds run beside each other, so this is each kind's span over its count).
    #[serde(default)]
    pub seconds_per_action: BTreeMap<String, f64>,
}

impl LastBuild {
    /// An empty record of the current version.
    pub fn new() -> LastBuild {
        LastBuild { version: VERSION, ..Default::default() }
    }
}

/// What one output wrote.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutputRecord {
    /// The dataset root, absolute (a build from another folder finds the same files).
    pub root: PathBuf,
    /// The key of its write-output action (hex).
    pub key: String,
    /// blake3 of the manifest text it was written from (hex).
    pub manifest: String,
    /// Root-relative files and their blake3 (hex).
    pub files: Vec<(String, String)>,
}

/// One record per (dataset directory, manifest): two manifests may share an `out` directory (a point-cloud
/// sequence and the renders made from it), and neither may prune the other's files.
fn path(store: &Store, m: &Manifest) -> PathBuf {
    // `.` and `..` resolved by name: a build from another folder (`vvgen build ../m.toml`) finds the same record.
    let abs = |p: PathBuf| crate::manifest::lexical(&p).to_string_lossy().into_owned();
    let id = format!("{}\0{}", abs(m.out_dir()), abs(m.path.clone()));
    let name = blake3::hash(id.as_bytes()).to_hex();
    store.root().join("builds").join(format!("{}.json", &name[..32]))
}

/// Reads the last build record of `m`'s dataset (empty when none, damaged or of another version).
pub fn read(store: &Store, m: &Manifest) -> LastBuild {
    std::fs::read_to_string(path(store, m))
        .ok()
        .and_then(|t| serde_json::from_str::<LastBuild>(&t).ok())
        .filter(|r| r.version == VERSION)
        .unwrap_or_default()
}

/// Writes `now` as the last build of `m`, unless it equals `before` (a no-op build writes nothing).
pub fn write(store: &Store, m: &Manifest, now: &LastBuild, before: &LastBuild) -> Result<(), cache::Error> {
    if now == before {
        return Ok(());
    }
    let text = serde_json::to_string(now).expect("BUG: the record serializes");
    let p = path(store, m);
    crate::atomic::write(&p, text.as_bytes()).map_err(|e| cache::Error::io(&p, e))
}

/// Holds the lock of one build of `m`'s dataset (of one shard, for a shard build) until dropped, so a second
/// `vvgen build` of the same dataset waits and then finds the first one's work in the cache instead of doing it
/// again. Shards lock apart: they are meant to run together. `waiting` is called when another build holds the
/// lock. Where the file system has no locks (some network file systems), the build goes on unlocked.
pub(crate) fn lock(
    store: &Store,
    m: &Manifest,
    shard: Option<crate::execute::Shard>,
    waiting: impl FnOnce(),
) -> Result<std::fs::File, cache::Error> {
    let mut p = path(store, m);
    p.set_extension(match shard {
        Some(s) => format!("shard-{}-of-{}.lock", s.index, s.count),
        None => "lock".into(),
    });
    if let Some(dir) = p.parent() {
        std::fs::create_dir_all(dir).map_err(|e| cache::Error::io(dir, e))?;
    }
    let f = std::fs::File::options()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&p)
        .map_err(|e| cache::Error::io(&p, e))?;
    match f.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            waiting();
            // An error here (no lock support) leaves the build unlocked, as below.
            let _ = f.lock();
        }
        Err(std::fs::TryLockError::Error(_)) => {}
    }
    Ok(f)
}
