//! The stat cache: (path → size, mtime, inode, blake3) for files vvgen has hashed, so a no-op build re-reads
//! nothing whose metadata is unchanged: source files, and blobs (which are also the dataset files, by hard
//! link). A file whose metadata changed is hashed again; a file edited in place gets a new mtime, so a flipped
//! byte in a blob or a dataset file is noticed.
//!
//! It also remembers small facts derived from a file's content, by the content's digest ([`StatCache::derived`]):
//! the material libraries an OBJ frame names, which keying needs on every build and which would otherwise mean
//! reading every frame in full. A fact is kept while some file with that content is tracked.

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::Digest;
use crate::atomic;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Meta {
    size: u64,
    mtime_ns: i128,
    ino: u64,
}

fn meta(p: &Path) -> std::io::Result<Meta> {
    let m = fs::metadata(p)?;
    let mtime_ns = m
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos() as i128);
    #[cfg(unix)]
    let ino = std::os::unix::fs::MetadataExt::ino(&m);
    #[cfg(not(unix))]
    let ino = 0;
    Ok(Meta { size: m.len(), mtime_ns, ino })
}

/// How close to the clock a file's mtime makes its entry racy: coarse file systems (FAT, some NFS servers)
/// keep 1–2 s timestamps.
pub const RACY: std::time::Duration = std::time::Duration::from_secs(2);

/// Whether a file with metadata `m` may still change without its metadata showing it.
fn racy(m: &Meta) -> bool {
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos() as i128);
    now - m.mtime_ns < RACY.as_nanos() as i128
}

/// Remembered digests of files, by path.
#[derive(Debug)]
pub struct StatCache {
    path: PathBuf,
    /// Path → metadata, digest, and whether the entry is racy (hash again before trusting it).
    entries: Mutex<HashMap<PathBuf, (Meta, Digest, bool)>>,
    /// (kind, content digest) → a fact derived from that content.
    derived: Mutex<HashMap<(String, Digest), String>>,
    /// Whether anything changed since loading (a no-op build need not rewrite the file).
    dirty: std::sync::atomic::AtomicBool,
}

/// The first field of a derived-fact line (never a digest's hex).
const DERIVED: &str = "derived";

impl StatCache {
    /// Loads the cache file at `path` (a missing or damaged file is an empty cache).
    pub fn load(path: &Path) -> StatCache {
        Self::load_with(path, false)
    }

    /// [`StatCache::load`], trusting no entry when `verify`: every file is hashed again once (`--verify`), which
    /// finds bit rot that left size, mtime and inode alone.
    pub fn load_with(path: &Path, verify: bool) -> StatCache {
        let mut entries = HashMap::new();
        let mut derived = HashMap::new();
        if let Ok(text) = fs::read_to_string(path) {
            for line in text.lines() {
                if let Some(rest) = line.strip_prefix(DERIVED).and_then(|r| r.strip_prefix('\t')) {
                    // `derived <kind> <digest> <JSON string>`; not trusted under `verify`.
                    let f: Vec<&str> = rest.splitn(3, '\t').collect();
                    let value = f.get(2).and_then(|v| serde_json::from_str::<String>(v).ok());
                    if let (false, [kind, d, _], Some(value)) = (verify, f.as_slice(), value) {
                        if let Some(d) = Digest::from_hex(d) {
                            derived.insert((kind.to_string(), d), value);
                        }
                    }
                    continue;
                }
                let f: Vec<&str> = line.splitn(5, '\t').collect();
                if f.len() != 5 {
                    continue;
                }
                let (Some(d), Ok(size), Ok(mtime_ns), Ok(ino)) =
                    (Digest::from_hex(f[0]), f[1].parse(), f[2].parse(), f[3].parse())
                else {
                    continue;
                };
                entries.insert(PathBuf::from(f[4]), (Meta { size, mtime_ns, ino }, d, verify));
            }
        }
        StatCache {
            path: path.to_path_buf(),
            entries: Mutex::new(entries),
            derived: Mutex::new(derived),
            dirty: false.into(),
        }
    }

    /// blake3 of the file at `p`, from the cache when its size, mtime and inode are unchanged.
    pub fn digest(&self, p: &Path) -> std::io::Result<Digest> {
        let m = meta(p)?;
        if let Some((cm, d, is_racy)) = self.entries.lock().expect("BUG: poisoned only by a panic elsewhere").get(p) {
            if *cm == m && !is_racy {
                return Ok(*d);
            }
        }
        let d = Digest::of(&fs::read(p)?);
        // Metadata read before the content: a write racing the read leaves a stale entry that the next stat
        // rejects, never a wrong one that looks current.
        self.entries.lock().expect("BUG: poisoned only by a panic elsewhere").insert(p.to_path_buf(), (m, d, racy(&m)));
        self.dirty.store(true, std::sync::atomic::Ordering::Relaxed);
        Ok(d)
    }

    /// Whether the file at `p` holds exactly the content named `d`.
    pub fn holds(&self, p: &Path, d: &Digest) -> bool {
        self.digest(p).is_ok_and(|got| got == *d)
    }

    /// Records that `p` (just written by us) holds `d`.
    pub fn record(&self, p: &Path, d: Digest) {
        if let Ok(m) = meta(p) {
            self.entries
                .lock()
                .expect("BUG: poisoned only by a panic elsewhere")
                .insert(p.to_path_buf(), (m, d, racy(&m)));
            self.dirty.store(true, std::sync::atomic::Ordering::Relaxed);
        }
    }

    /// The fact of kind `kind` derived from the file at `p`, computed by `derive` unless it is remembered for
    /// the file's current content. The outer error is hashing the file; `derive`'s errors are returned inside
    /// and not remembered.
    pub fn derived<E>(
        &self,
        kind: &str,
        p: &Path,
        derive: impl FnOnce() -> Result<String, E>,
    ) -> std::io::Result<Result<String, E>> {
        let d = self.digest(p)?;
        let key = (kind.to_string(), d);
        if let Some(v) = self.derived.lock().expect("BUG: poisoned only by a panic elsewhere").get(&key) {
            return Ok(Ok(v.clone()));
        }
        let v = match derive() {
            Ok(v) => v,
            Err(e) => return Ok(Err(e)),
        };
        self.derived.lock().expect("BUG: poisoned only by a panic elsewhere").insert(key, v.clone());
        self.dirty.store(true, std::sync::atomic::Ordering::Relaxed);
        Ok(Ok(v))
    }

    /// Writes the cache back (atomically; entries for vanished files are dropped, and facts about content no
    /// tracked file holds any more).
    pub fn save(&self) -> std::io::Result<()> {
        if !self.dirty.load(std::sync::atomic::Ordering::Relaxed) && self.path.exists() {
            return Ok(());
        }
        let entries = self.entries.lock().expect("BUG: poisoned only by a panic elsewhere");
        let mut lines: Vec<String> = entries
            .iter()
            // Racy entries are not saved: the next build hashes those files once more (git's "smudging").
            .filter(|(p, (_, _, is_racy))| !is_racy && p.exists())
            .map(|(p, (m, d, _))| format!("{}\t{}\t{}\t{}\t{}", d.hex(), m.size, m.mtime_ns, m.ino, p.display()))
            .collect();
        let held: std::collections::HashSet<Digest> = entries.values().map(|(_, d, _)| *d).collect();
        for ((kind, d), v) in self
            .derived
            .lock()
            .expect("BUG: poisoned only by a panic elsewhere")
            .iter()
            .filter(|((_, d), _)| held.contains(d))
        {
            let value = serde_json::Value::String(v.clone());
            lines.push(format!("{DERIVED}\t{kind}\t{}\t{value}", d.hex()));
        }
        lines.sort();
        let mut text = lines.join("\n");
        text.push('\n');
        atomic::write(&self.path, text.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file rewritten within its timestamp tick (same size, same mtime, same inode) is hashed again, not
    /// served from the entry recorded before the rewrite.
    #[test]
    fn a_racy_entry_is_hashed_again() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f");
        std::fs::write(&p, b"aaaa").unwrap();
        let stat = StatCache::load(&dir.path().join("stat"));
        assert_eq!(stat.digest(&p).unwrap(), Digest::of(b"aaaa"));
        let mtime = std::fs::metadata(&p).unwrap().modified().unwrap();
        let f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
        std::os::unix::fs::FileExt::write_all_at(&f, b"b", 0).unwrap();
        f.set_modified(mtime).unwrap();
        assert_eq!(stat.digest(&p).unwrap(), Digest::of(b"baaa"));
        // Racy entries are not saved; an old file's entry is.
        let old = dir.path().join("old");
        std::fs::write(&old, b"x").unwrap();
        std::fs::File::options().append(true).open(&old).unwrap().set_modified(std::time::UNIX_EPOCH).unwrap();
        stat.digest(&old).unwrap();
        stat.save().unwrap();
        let saved = std::fs::read_to_string(dir.path().join("stat")).unwrap();
        assert!(saved.contains("/old") && !saved.contains("/f\n"), "{saved}");
    }

    /// A derived fact is computed once per content, survives a reload, and is recomputed after an edit.
    #[test]
    fn derived_facts_follow_content() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.obj");
        std::fs::write(&p, b"mtllib a.mtl\n").unwrap();
        std::fs::File::options().append(true).open(&p).unwrap().set_modified(std::time::UNIX_EPOCH).unwrap();
        let calls = std::cell::Cell::new(0);
        let derive = || -> std::io::Result<String> {
            calls.set(calls.get() + 1);
            Ok(String::from_utf8(std::fs::read(&p)?).unwrap().replace('\n', "\t"))
        };
        let get = |s: &StatCache| s.derived("libs", &p, derive).unwrap().unwrap();
        let stat = StatCache::load(&dir.path().join("stat"));
        assert_eq!(get(&stat), "mtllib a.mtl\t");
        assert_eq!(get(&stat), "mtllib a.mtl\t");
        stat.save().unwrap();
        let again = StatCache::load(&dir.path().join("stat"));
        assert_eq!(get(&again), "mtllib a.mtl\t");
        assert_eq!(calls.get(), 1, "remembered across builds");
        std::fs::write(&p, b"mtllib b.mtl\n").unwrap();
        assert_eq!(get(&again), "mtllib b.mtl\t");
        assert_eq!(calls.get(), 2);
        // A failure is not remembered.
        let failing = again.derived("other", &p, || Err::<String, &str>("no"));
        assert_eq!(failing.unwrap(), Err("no"));
        assert_eq!(again.derived("other", &p, || Ok::<_, &str>("yes".into())).unwrap(), Ok("yes".to_string()));
        // Under --verify nothing remembered is trusted.
        assert_eq!(StatCache::load_with(&dir.path().join("stat"), true).derived.lock().unwrap().len(), 0);
    }
}
