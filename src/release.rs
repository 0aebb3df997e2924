//! Releases: `vvgen.lock` at each dataset root lists the tool version, the manifest digest, every input file's
//! digest and every dataset file with its size and blake3, so anyone can check a downloaded dataset byte for
//! byte with `vvgen verify`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::build::{self, Error, Options, Silent};
use crate::cache::{self, Digest, Store};
use crate::manifest::{sequence, Manifest, SourceKind};

/// Name of the lock file at a dataset root.
pub const LOCK: &str = "vvgen.lock";

/// The content of `vvgen.lock`.
#[derive(Debug, Serialize, Deserialize)]
pub struct Lock {
    /// Always "vvgen".
    pub tool: String,
    /// Tool version.
    pub version: String,
    /// blake3 of the manifest text.
    pub manifest_blake3: String,
    /// Input files (manifest-relative where possible) → blake3.
    pub inputs: BTreeMap<String, String>,
    /// Dataset files (root-relative, `/`-separated) → size and blake3.
    pub files: BTreeMap<String, FileEntry>,
}

/// One dataset file in a lock.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileEntry {
    /// Bytes.
    pub size: u64,
    /// blake3, hex.
    pub blake3: String,
}

/// Writes `vvgen.lock` into every output root of `m`; refuses while any action of its graph is not built.
pub fn release(m: &Manifest, cache: &Path) -> Result<Vec<PathBuf>, Error> {
    // Every action must be cached: this build runs none and only (re)places files and rewrites metadata.
    let report = build::build(m, cache, Options { require_built: true, ..Options::default() }, &Silent)?;
    let store = Store::open(cache).map_err(|e| Error::cache(m, e))?;
    let stat = store.stat_cache(&m.out_dir(), false);
    let mut inputs = BTreeMap::new();
    for f in input_files(m, &stat)? {
        let d = stat.digest(&f).map_err(|e| Error::cache(m, cache::Error::io(&f, e)))?;
        let name = f.strip_prefix(&m.dir).unwrap_or(&f).to_string_lossy().replace('\\', "/");
        inputs.insert(name, d.hex());
    }
    let manifest_blake3 = Digest::of(m.text.as_bytes()).hex();
    let mut roots = Vec::new();
    for (_, w) in &report.outputs {
        let mut files = BTreeMap::new();
        for (rel, d) in &w.files {
            // Certify what is on disk, hashed now: the stat cache trusts size, mtime and inode, which bit rot
            // (and some copy tools) leave unchanged.
            let path = w.root.join(rel);
            let bytes = std::fs::read(&path).map_err(|e| Error::cache(m, cache::Error::io(&path, e)))?;
            if Digest::of(&bytes) != *d {
                // The dataset file is a hard link to its blob: remove both, so the next build runs the action
                // again instead of placing the same damaged bytes.
                let _ = std::fs::remove_file(store.object_path(d));
                let _ = std::fs::remove_file(&path);
                return Err(Error::Damaged { path });
            }
            files.insert(rel.clone(), FileEntry { size: bytes.len() as u64, blake3: d.hex() });
        }
        let lock = Lock {
            tool: "vvgen".into(),
            version: env!("CARGO_PKG_VERSION").into(),
            manifest_blake3: manifest_blake3.clone(),
            inputs: inputs.clone(),
            files,
        };
        let mut text = serde_json::to_string_pretty(&lock).expect("BUG: the lock serializes");
        text.push('\n');
        let path = w.root.join(LOCK);
        crate::atomic::write(&path, text.as_bytes()).map_err(|e| Error::cache(m, cache::Error::io(&path, e)))?;
        roots.push(w.root.clone());
    }
    Ok(roots)
}

/// The files `m`'s sources are read from: the glTF or mesh file, or every frame of a sequence (listed from the
/// manifest, as `check` lists them; nothing is loaded or posed). A mesh frame's libraries come from what the
/// build's keying remembered in `stat`.
fn input_files(m: &Manifest, stat: &crate::cache::StatCache) -> Result<Vec<PathBuf>, Error> {
    let mut out = Vec::new();
    for (name, s) in &m.sources {
        match s.kind() {
            Some((kind, spec)) if kind.is_sequence() => {
                let frames = s.frames().cloned().unwrap_or_default();
                let seq = sequence::resolve(&m.dir, spec, &frames).map_err(|source| Error::Scene {
                    manifest: m.path.clone(),
                    source: Box::new(crate::scene::Error::Sequence { name: name.clone(), message: source.to_string() }),
                    hint: "",
                })?;
                for f in seq {
                    // A mesh frame's MTL files and textures are inputs too.
                    if kind == SourceKind::MeshSequence {
                        let deps = crate::scene::source::mesh_frame_deps_cached(&f.path, stat)
                            .map_err(|e| Error::Scene { manifest: m.path.clone(), source: Box::new(e), hint: "" })?;
                        out.extend(deps);
                    }
                    out.push(f.path);
                }
            }
            Some((_, path)) => out.push(m.resolve(path)),
            None => {}
        }
    }
    Ok(out)
}

/// Differences between a dataset directory and its lock.
#[derive(Debug, Default)]
pub struct Verification {
    /// Files the lock lists that are absent.
    pub missing: Vec<String>,
    /// Files whose size or content differs.
    pub modified: Vec<String>,
    /// Files present but not in the lock.
    pub extra: Vec<String>,
    /// Files checked.
    pub checked: usize,
}

impl Verification {
    /// Whether the directory matches its lock exactly.
    pub fn ok(&self) -> bool {
        self.missing.is_empty() && self.modified.is_empty() && self.extra.is_empty()
    }
}

/// Why a dataset cannot be verified at all.
#[derive(Debug, thiserror::Error)]
pub enum VerifyError {
    /// The lock or the directory cannot be read.
    #[error("{}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The lock is not a vvgen lock.
    #[error("{}: not a vvgen lock", path.display())]
    NotALock {
        /// The lock file.
        path: PathBuf,
        /// Why.
        #[source]
        source: serde_json::Error,
    },
}

/// Checks `dir` against its `vvgen.lock`, hashing every file.
pub fn verify(dir: &Path) -> Result<Verification, VerifyError> {
    let lock_path = dir.join(LOCK);
    let text =
        std::fs::read_to_string(&lock_path).map_err(|e| VerifyError::Io { path: lock_path.clone(), source: e })?;
    let lock: Lock =
        serde_json::from_str(&text).map_err(|e| VerifyError::NotALock { path: lock_path.clone(), source: e })?;
    let mut v = Verification::default();
    for (rel, entry) in &lock.files {
        let p = dir.join(rel);
        match std::fs::read(&p) {
            Err(_) => v.missing.push(rel.clone()),
            Ok(bytes) => {
                v.checked += 1;
                if bytes.len() as u64 != entry.size || Digest::of(&bytes).hex() != entry.blake3 {
                    v.modified.push(rel.clone());
                }
            }
        }
    }
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).map_err(|e| VerifyError::Io { path: d.clone(), source: e })?.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let rel = p.strip_prefix(dir).expect("walked under dir").to_string_lossy().replace('\\', "/");
            if rel != LOCK && !lock.files.contains_key(&rel) {
                v.extra.push(rel);
            }
        }
    }
    v.extra.sort();
    Ok(v)
}
