//! Garbage collection: drop blobs and action records that no kept manifest needs, or the least recently
//! written beyond a size budget. Anything younger than [`GRACE`] is kept, so a build running now (whose blobs may
//! not be recorded yet) never loses its work.

use std::collections::HashSet;
use std::fs;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

use super::Digest;

/// Files written this recently are never collected.
pub const GRACE: Duration = Duration::from_secs(3600);

/// What a collection removed.
#[derive(Debug, Default)]
pub struct Collected {
    /// Files removed.
    pub files: usize,
    /// Bytes removed.
    pub bytes: u64,
    /// Bytes left.
    pub left: u64,
    /// Files that would have gone but were younger than the minimum age, and kept.
    pub young: usize,
}

/// Every file under `dir`, with its size and modification time.
pub(super) fn walk(dir: &Path, out: &mut Vec<(PathBuf, u64, SystemTime)>) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let Ok(m) = e.metadata() else { continue };
        if m.is_dir() {
            walk(&e.path(), out);
        } else {
            out.push((e.path(), m.len(), m.modified().unwrap_or(SystemTime::UNIX_EPOCH)));
        }
    }
}

/// The digest a blob or record path names (`…/ab/cdef…` → `abcdef…`).
fn name_of(p: &Path) -> Option<Digest> {
    let file = p.file_name()?.to_str()?;
    let dir = p.parent()?.file_name()?.to_str()?;
    Digest::from_hex(&format!("{dir}{file}"))
}

/// Removes from the store at `root` every blob and record not in `keep` (when given) and then, oldest first,
/// whatever exceeds `max_bytes` (when given); nothing younger than `min_age` ([`GRACE`] unless told).
pub fn collect(root: &Path, keep: Option<&HashSet<Digest>>, max_bytes: Option<u64>, min_age: Duration) -> Collected {
    let mut files = Vec::new();
    walk(&root.join("objects"), &mut files);
    walk(&root.join("actions"), &mut files);
    let now = SystemTime::now();
    let young = |t: SystemTime| now.duration_since(t).map_or(true, |age| age < min_age);
    let mut c = Collected::default();
    let mut left = Vec::new();
    for (p, size, t) in files {
        let needed = keep.is_none_or(|k| name_of(&p).is_some_and(|d| k.contains(&d)));
        c.young += usize::from(!needed && young(t));
        if !needed && !young(t) && fs::remove_file(&p).is_ok() {
            c.files += 1;
            c.bytes += size;
        } else {
            // Whether it is already counted as kept for its age.
            left.push((p, size, t, !needed));
        }
    }
    let mut total: u64 = left.iter().map(|f| f.1).sum();
    if let Some(max) = max_bytes {
        left.sort_by_key(|f| f.2);
        for (p, size, t, counted) in &left {
            if total <= max {
                break;
            }
            if young(*t) {
                c.young += usize::from(!counted);
            } else if fs::remove_file(p).is_ok() {
                c.files += 1;
                c.bytes += size;
                total -= size;
            }
        }
    }
    c.left = total;
    // A `.blend` import's placed files (`blend/<import key>/`, hard links of its blobs) go with its record, and
    // an interrupted import's scratch folder (`tmp/`) once it is old.
    let record = |d: &Digest| {
        let hex = d.hex();
        root.join("actions").join(&hex[..2]).join(&hex[2..])
    };
    for (dir, gone) in [("blend", true), ("tmp", false)] {
        let Ok(entries) = fs::read_dir(root.join(dir)) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            let stale = if gone {
                Digest::from_hex(&e.file_name().to_string_lossy()).is_none_or(|d| !record(&d).exists())
            } else {
                true
            };
            let t = e.metadata().and_then(|m| m.modified()).unwrap_or(SystemTime::UNIX_EPOCH);
            if stale && !young(t) && fs::remove_dir_all(&p).is_ok() {
                c.files += 1;
            }
        }
    }
    c
}
