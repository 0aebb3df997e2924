//! Atomic file writes: a file appears under its final name complete or not at all. Bytes go to a temporary
//! file in the destination's directory (same file system, so the rename is atomic), are synced, then renamed
//! over the destination. An interrupted build therefore leaves only `.vvgen-tmp-*` files, never a half file
//! that looks complete.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Prefix of temporary files; anything with it is debris of an interrupted write.
pub const TMP_PREFIX: &str = ".vvgen-tmp-";

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// This host's name as it goes into temporary names (`-` and `.` become `_`, so the name parses back).
fn host() -> &'static str {
    static HOST: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    HOST.get_or_init(|| {
        let h = fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_else(|_| "host".into());
        h.trim().chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect()
    })
}

/// A temporary name beside `dest`, unique within and across processes and hosts (a shared cache sees several):
/// `.vvgen-tmp-<pid>@<host>-<n>-<name>`.
pub fn temp_path(dest: &Path) -> PathBuf {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = dest.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    dest.with_file_name(format!("{TMP_PREFIX}{}@{}-{n}-{name}", std::process::id(), host()))
}

/// Whether the temporary file named `name` was left by a process of this host that is gone (Linux: no
/// `/proc/<pid>`). Temporaries of other hosts, of live processes, and names that do not parse are kept.
fn dead_debris(name: &str) -> bool {
    let Some((pid, rest)) = name.strip_prefix(TMP_PREFIX).and_then(|r| r.split_once('@')) else { return false };
    let Some((h, _)) = rest.split_once('-') else { return false };
    let alive = Path::new("/proc").join(pid);
    cfg!(target_os = "linux") && h == host() && pid.parse::<u32>().is_ok() && !alive.exists()
}

/// Removes temporaries left by killed processes of this host in `dir` and its immediate subdirectories (the
/// cache's `builds/` and `stat/`, or the fans of `objects/` and `actions/`), so a killed build's debris does not
/// wait for `gc`.
pub fn clean_dead_debris(dir: &Path) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let path = e.path();
        if path.is_dir() {
            for f in fs::read_dir(&path).into_iter().flatten().flatten() {
                if dead_debris(&f.file_name().to_string_lossy()) {
                    let _ = fs::remove_file(f.path());
                }
            }
        } else if dead_debris(&e.file_name().to_string_lossy()) {
            let _ = fs::remove_file(path);
        }
    }
}

/// Writes `bytes` to `dest` atomically, creating parent directories.
pub fn write(dest: &Path, bytes: &[u8]) -> std::io::Result<()> {
    stage(dest, bytes)?.commit()
}

/// A file written under a temporary name beside its destination, not yet synced nor renamed: the first half of
/// [`write()`], whose second half, [`Staged::commit`], may run later on another thread (a build's renders do not
/// wait on the disk). Dropped uncommitted, the temporary is removed.
#[derive(Debug)]
pub struct Staged {
    file: fs::File,
    tmp: PathBuf,
    dest: PathBuf,
    committed: bool,
}

/// Writes `bytes` to a new temporary file beside `dest` (creating parent directories), to be committed.
pub fn stage(dest: &Path, bytes: &[u8]) -> std::io::Result<Staged> {
    if let Some(parent) = dest.parent() {
        fs::create_dir_all(parent)?;
    }
    let tmp = temp_path(dest);
    let file = fs::File::create(&tmp)?;
    // From here on, dropping `staged` (on a write error too) removes the temporary.
    let mut staged = Staged { file, tmp, dest: dest.to_path_buf(), committed: false };
    staged.file.write_all(bytes)?;
    Ok(staged)
}

impl Staged {
    /// Where the file goes.
    pub fn dest(&self) -> &Path {
        &self.dest
    }

    /// Syncs the file's bytes to disk, then renames it over its destination: after a power cut the destination
    /// holds the old file or the whole new one.
    pub fn commit(self) -> std::io::Result<()> {
        self.file.sync_all()?;
        self.commit_synced()
    }

    /// Renames the file over its destination: the second half of [`Staged::commit`], for files that
    /// [`sync_together`] made durable (renamed unsynced, a power cut could leave the name on a hole).
    pub fn commit_synced(mut self) -> std::io::Result<()> {
        fs::rename(&self.tmp, &self.dest)?;
        self.committed = true;
        Ok(())
    }
}

/// Makes the bytes of every staged file in `files` durable, for [`Staged::commit_synced`]: a group commit. On
/// Linux, one `syncfs` per file system the files are on: the disk's write cache is flushed once for the batch,
/// where a `sync_all` per file flushes it once per file (a build's cache takes two files per image; on a cut of
/// the seed-scale set the machine's busy CPU time fell by a sixth, docs/benchmarks.md). `syncfs` writes back whatever else
/// on that file system is dirty too: the price of the one flush, paid on the committer's thread. (Linux reports
/// a failed writeback through `syncfs` from 5.8 on; older kernels return success regardless.) Elsewhere each
/// file's `sync_all`.
pub fn sync_together<'a>(files: impl IntoIterator<Item = &'a Staged>) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        use std::os::unix::fs::MetadataExt;
        let mut synced: Vec<u64> = Vec::new();
        for f in files {
            let dev = f.file.metadata()?.dev();
            if !synced.contains(&dev) {
                // SAFETY: the descriptor is open for as long as `f` lives; `syncfs` only reads it.
                if unsafe { libc::syncfs(f.file.as_raw_fd()) } != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                synced.push(dev);
            }
        }
        Ok(())
    }
    #[cfg(not(target_os = "linux"))]
    files.into_iter().try_for_each(|f| f.file.sync_all())
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_file(&self.tmp);
        }
    }
}

/// Places a copy of the file `src` at `dest` atomically: a hard link when the file system allows, else a copy.
pub fn link_or_copy(src: &Path, dest: &Path) -> std::io::Result<()> {
    if let Some(parent) = dest.parent() {
        fs::create_dir_all(parent)?;
    }
    if same_file(src, dest) {
        return Ok(());
    }
    let tmp = temp_path(dest);
    let result = fs::hard_link(src, &tmp)
        .or_else(|_| {
            fs::copy(src, &tmp)?;
            fs::File::open(&tmp)?.sync_all()
        })
        .and_then(|_| fs::rename(&tmp, dest));
    // POSIX rename does nothing when both names are links to one file; the temporary name must not stay behind.
    let _ = fs::remove_file(&tmp);
    result
}

/// Whether two paths name the same file (same device and inode).
#[cfg(unix)]
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (fs::metadata(a), fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_: &Path, _: &Path) -> bool {
    false
}

/// Removes the debris of interrupted writes directly inside `dir` (not recursive).
pub fn clean_debris(dir: &Path) {
    if let Ok(entries) = fs::read_dir(dir) {
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with(TMP_PREFIX) {
                let _ = fs::remove_file(e.path());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn debris_of_dead_processes_of_this_host_is_removed_and_no_other() {
        let dir = tempfile::tempdir().unwrap();
        let fan = dir.path().join("ab");
        fs::create_dir(&fan).unwrap();
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let names = [
            format!("{TMP_PREFIX}{dead}@{}-0-cdef", host()),
            format!("{TMP_PREFIX}{}@{}-0-cdef", std::process::id(), host()),
            format!("{TMP_PREFIX}{dead}@another_host-0-cdef"),
            "cdef".to_string(),
        ];
        for n in &names {
            fs::write(fan.join(n), b"x").unwrap();
        }
        clean_dead_debris(dir.path());
        let mut left: Vec<String> =
            fs::read_dir(&fan).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        left.sort();
        let mut expect = names[1..].to_vec();
        expect.sort();
        assert_eq!(left, expect);
    }

    #[test]
    fn writes_replace_and_leave_no_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a/b.txt");
        write(&p, b"one").unwrap();
        write(&p, b"two").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"two");
        let q = dir.path().join("c.txt");
        link_or_copy(&p, &q).unwrap();
        assert_eq!(fs::read(&q).unwrap(), b"two");
        // Linking again onto the same file (rename is a no-op then) leaves no temporary behind.
        link_or_copy(&p, &q).unwrap();
        let top: Vec<_> = fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(top.len(), 2, "{top:?}");
        let names: Vec<_> = fs::read_dir(dir.path().join("a")).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 1, "{names:?}");
    }
}
