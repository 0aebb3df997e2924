//! The content-addressed store: every rendered or sampled artifact is a blob named by the blake3 of its bytes
//! (`objects/ab/cdef…`). Execution puts blobs here; export materializes them into dataset directories by hard link
//! (or copy). Identical bytes are stored once, whichever split, output or manifest produced them.

use std::fs;
use std::path::{Path, PathBuf};

use crate::atomic;

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
}

/// A cache directory.
#[derive(Debug, Clone)]
pub struct Store {
    root: PathBuf,
}

impl Store {
    /// Opens (creating) the store at `root`.
    pub fn open(root: &Path) -> std::io::Result<Store> {
        fs::create_dir_all(root.join("objects"))?;
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

    /// Stores `bytes` (atomically; a blob already present is not rewritten) and returns its digest.
    pub fn put(&self, bytes: &[u8]) -> std::io::Result<Digest> {
        let d = Digest::of(bytes);
        let p = self.object_path(&d);
        if fs::metadata(&p).map(|m| m.len() != bytes.len() as u64).unwrap_or(true) {
            atomic::write(&p, bytes)?;
        }
        Ok(d)
    }

    /// Reads blob `d`, verifying its digest.
    pub fn get(&self, d: &Digest) -> std::io::Result<Vec<u8>> {
        let bytes = fs::read(self.object_path(d))?;
        if Digest::of(&bytes) != *d {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!("cache blob {} is corrupt (its content does not match its name)", d.hex()),
            ));
        }
        Ok(bytes)
    }

    /// Places blob `d` at `dest` (hard link, else copy), atomically.
    pub fn materialize(&self, d: &Digest, dest: &Path) -> std::io::Result<()> {
        atomic::link_or_copy(&self.object_path(d), dest)
    }
}
