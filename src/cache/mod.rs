//! The content-addressed store: every rendered or sampled artifact is a blob named by the blake3 of its bytes
//! (`objects/ab/cdef…`). Execution puts blobs here; export materializes them into dataset directories by hard link
//! (or copy). Identical bytes are stored once, whichever split, output or manifest produced them.

pub mod commit;
pub mod gc;
pub mod stat;

use std::fs;
use std::path::{Path, PathBuf};

use crate::atomic::{self, Staged};
pub use commit::Committer;
pub use stat::StatCache;

/// What can go wrong in the cache.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Reading or writing a cache file (or a dataset file placed from it) failed.
    #[error("{}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A blob's content does not match its name (the file was damaged on disk).
    #[error("cache blob {digest} is corrupt (its content does not match its name)")]
    Corrupt {
        /// The blob's name.
        digest: String,
    },
    /// A blob holds bytes of the wrong form for what reads it.
    #[error("cache blob {digest} is damaged: {why}")]
    Damaged {
        /// The blob's name.
        digest: String,
        /// What is wrong with it.
        why: String,
    },
    /// A result was not stored because the build is stopping: an earlier one could not be committed, or
    /// another action failed (that failure is the one to report; see [`Committer`]).
    #[error("not stored: the build stopped after an earlier failure")]
    Stopped,
}

impl Error {
    /// An I/O error on `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Error {
        Error::Io { path: path.to_path_buf(), source }
    }
}

/// First line of an action record; records of another version are skipped (a miss), never misread.
const ACTION_MAGIC: &str = "vvgen-action 2";

/// A blob's name: blake3 of its content.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Digest(pub [u8; 32]);

impl Digest {
    /// The digest of `bytes`.
    pub fn of(bytes: &[u8]) -> Digest {
        Digest(*blake3::hash(bytes).as_bytes())
    }

    /// Lower-case hex.
    pub fn hex(&self) -> String {
        blake3::Hash::from_bytes(self.0).to_hex().to_string()
    }

    /// Parses 64 hex digits.
    pub fn from_hex(s: &str) -> Option<Digest> {
        blake3::Hash::from_hex(s).ok().map(|h| Digest(*h.as_bytes()))
    }

    /// The first 8 bytes as an integer (for sharding).
    pub fn prefix_u64(&self) -> u64 {
        u64::from_le_bytes(self.0[..8].try_into().expect("32 bytes"))
    }
}

/// Builds a content key: blake3 in derive-key mode over a kind and length-prefixed parts (source frames'
/// content keys; actions are keyed by [`crate::plan::key`]).
pub fn key(kind: &str, parts: &[&[u8]]) -> Digest {
    let mut h = blake3::Hasher::new_derive_key(&format!("vvgen key {kind}"));
    for p in parts {
        h.update(&(p.len() as u64).to_le_bytes());
        h.update(p);
    }
    Digest(*h.finalize().as_bytes())
}

/// How a staged file goes into place: [`Staged::commit`] (synced, then renamed), or, after a batch's
/// [`crate::atomic::sync_together`], [`Staged::commit_synced`].
type Commit = fn(Staged) -> std::io::Result<()>;

/// Commits a staged file by `how`, naming it in the error.
fn commit(f: Staged, how: Commit) -> Result<(), Error> {
    let dest = f.dest().to_path_buf();
    how(f).map_err(|e| Error::io(&dest, e))
}

/// Commits the staged blob `d` by `how` and notes it in the stat cache (so this build does not hash it again).
fn place(d: Digest, f: Staged, stat: &StatCache, how: Commit) -> Result<(), Error> {
    let dest = f.dest().to_path_buf();
    commit(f, how)?;
    stat.record(&dest, d);
    Ok(())
}

/// The file that marks a folder as a cache (<https://bford.info/cachedir/>).
pub const CACHE_TAG: &str = "CACHEDIR.TAG";
const CACHE_TAG_TEXT: &str = "Signature: 8a477f597d28d172789f06886806bc55\n\
    # This file is a cache directory tag created by vvgen: its objects are rebuilt by `vvgen build`.\n";

/// A cache directory.
#[derive(Debug, Clone)]
pub struct Store {
    root: PathBuf,
}

impl Store {
    /// Opens (creating) the store at `root`, tagged as a cache (`CACHEDIR.TAG`, the convention backup tools and
    /// vvgen's own texture search skip).
    pub fn open(root: &Path) -> Result<Store, Error> {
        let objects = root.join("objects");
        fs::create_dir_all(&objects).map_err(|e| Error::io(&objects, e))?;
        let tag = root.join(CACHE_TAG);
        if !tag.exists() {
            // Best effort: a store on a read-only copy still reads.
            let _ = fs::write(&tag, CACHE_TAG_TEXT);
        }
        Ok(Store { root: root.to_path_buf() })
    }

    /// The store's directory.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Where the blob `d` lives.
    pub fn object_path(&self, d: &Digest) -> PathBuf {
        let hex = d.hex();
        self.root.join("objects").join(&hex[..2]).join(&hex[2..])
    }

    /// Stores `bytes` (atomically; an intact blob already present is not rewritten) and returns its digest.
    pub fn put(&self, bytes: &[u8], stat: &StatCache) -> Result<Digest, Error> {
        let (d, staged) = self.stage(bytes, stat)?;
        if let Some(f) = staged {
            place(d, f, stat, Staged::commit)?;
        }
        Ok(d)
    }

    /// The first half of [`Store::put`]: `bytes` written beside their place, for a [`Committer`] to sync and
    /// rename (`None` when an intact copy is in place already).
    pub fn stage(&self, bytes: &[u8], stat: &StatCache) -> Result<(Digest, Option<Staged>), Error> {
        let d = Digest::of(bytes);
        let p = self.object_path(&d);
        if stat.holds(&p, &d) {
            return Ok((d, None));
        }
        let staged = atomic::stage(&p, bytes).map_err(|e| Error::io(&p, e))?;
        Ok((d, Some(staged)))
    }

    /// Reads blob `d`, verifying its digest.
    pub fn get(&self, d: &Digest) -> Result<Vec<u8>, Error> {
        let p = self.object_path(d);
        let bytes = fs::read(&p).map_err(|e| Error::io(&p, e))?;
        if Digest::of(&bytes) != *d {
            return Err(Error::Corrupt { digest: d.hex() });
        }
        Ok(bytes)
    }

    /// Places blob `d` at `dest` (hard link, else copy), atomically; a `dest` already holding `d` (by the stat
    /// cache) is left alone. Returns whether it placed the file.
    pub fn materialize(&self, d: &Digest, dest: &Path, stat: &StatCache) -> Result<bool, Error> {
        if stat.holds(dest, d) {
            return Ok(false);
        }
        atomic::link_or_copy(&self.object_path(d), dest).map_err(|e| Error::io(dest, e))?;
        stat.record(dest, *d);
        Ok(true)
    }

    /// Whether blob `d` is present and intact (hashing it only when its metadata changed since last checked).
    /// A corrupt blob is removed, so the task that made it runs again.
    pub fn verify(&self, d: &Digest, stat: &StatCache) -> bool {
        let p = self.object_path(d);
        if stat.holds(&p, d) {
            return true;
        }
        if p.exists() {
            let _ = fs::remove_file(&p);
        }
        false
    }

    fn action_path(&self, key: &Digest) -> PathBuf {
        let hex = key.hex();
        self.root.join("actions").join(&hex[..2]).join(&hex[2..])
    }

    /// The blobs the action `key` produced, if it ran before.
    pub fn action(&self, key: &Digest) -> Option<Vec<Digest>> {
        let text = fs::read_to_string(self.action_path(key)).ok()?;
        let mut lines = text.lines();
        if lines.next() != Some(ACTION_MAGIC) {
            return None;
        }
        lines.map_while(|l| l.strip_prefix("blob ")).map(Digest::from_hex).collect()
    }

    /// The `(field, value)` pairs the action `key` was keyed by, as recorded when it ran.
    pub fn action_fields(&self, key: &Digest) -> Option<Vec<(String, String)>> {
        let text = fs::read_to_string(self.action_path(key)).ok()?;
        let mut lines = text.lines();
        if lines.next() != Some(ACTION_MAGIC) {
            return None;
        }
        let fields = lines.filter_map(|l| l.strip_prefix("field ")?.split_once('\t'));
        Some(fields.map(|(k, v)| (k.to_string(), v.to_string())).collect())
    }

    /// Writes the record that the action `key` produced `blobs`, with the fields it was keyed by (what
    /// `plan --explain` compares a later key against), beside its place, to be committed after the blobs (a
    /// [`Committer`]): a record is whole or absent, and names only blobs in place.
    pub fn stage_action(&self, key: &Digest, blobs: &[Digest], fields: &[(String, String)]) -> Result<Staged, Error> {
        let mut text = format!("{ACTION_MAGIC}\n");
        for d in blobs {
            text.push_str(&format!("blob {}\n", d.hex()));
        }
        for (k, v) in fields {
            // Field names and values are single-line by construction; keep it so.
            let (k, v) = (k.replace(['\t', '\n'], " "), v.replace(['\t', '\n'], " "));
            text.push_str(&format!("field {k}\t{v}\n"));
        }
        let p = self.action_path(key);
        atomic::stage(&p, text.as_bytes()).map_err(|e| Error::io(&p, e))
    }

    /// The blobs of task `key` when it ran before and they are all intact.
    pub fn hit(&self, key: &Digest, stat: &StatCache) -> Option<Vec<Digest>> {
        let blobs = self.action(key)?;
        blobs.iter().all(|d| self.verify(d, stat)).then_some(blobs)
    }

    /// The stat cache for builds of the dataset at `out` (one file per dataset directory).
    pub fn stat_cache(&self, out: &Path, verify: bool) -> StatCache {
        let abs = std::path::absolute(out).unwrap_or_else(|_| out.to_path_buf());
        let name = blake3::hash(abs.to_string_lossy().as_bytes()).to_hex();
        StatCache::load_with(&self.root.join("stat").join(&name[..32]), verify)
    }
}
