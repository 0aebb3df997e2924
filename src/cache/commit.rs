//! Group commit of a build's results. A worker that made an action's blobs writes them, and the action's record,
//! under temporary names ([`Store::stage`], [`Store::stage_action`]) and hands them to one committer thread,
//! which syncs each file to disk and renames it into place: the blobs first, the record last, so a record only
//! ever names blobs that are in place (what [`Store::hit`] relies on). Rendering goes on meanwhile: a worker that
//! synced its own files waited about half a millisecond per file with its core idle, a tenth of a build's wall
//! time on two cores.
//!
//! Readers of a kind's blobs run after [`Committer::flush`], which waits for every commit handed over so far and
//! reports the first failure. The queue is bounded, so a slow disk slows the workers rather than filling memory
//! with written but uncommitted files. An interrupted build leaves only temporaries, as [`crate::atomic`] does.
//!
//! [`Store::stage`]: super::Store::stage
//! [`Store::stage_action`]: super::Store::stage_action
//! [`Store::hit`]: super::Store::hit

use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::{Condvar, Mutex};

use super::{commit, place, Digest, Error, StatCache};
use crate::atomic::Staged;

/// Commits waiting at most: enough to ride out a slow sync, few enough to bound the open temporaries (three
/// files each at most).
const QUEUE: usize = 32;

/// One action's files, in commit order: its blobs (with their digests, for the stat cache), then its record.
struct Job {
    label: String,
    blobs: Vec<(Digest, Staged)>,
    record: Staged,
}

/// Hands staged files to the committer thread; see the module documentation.
pub struct Committer {
    tx: Mutex<Option<SyncSender<Job>>>,
    progress: Mutex<Progress>,
    settled: Condvar,
}

/// Commits handed over and finished, whether one failed, and the first failure (with the action's label) until
/// `flush` reports it.
#[derive(Default)]
struct Progress {
    sent: u64,
    done: u64,
    failed: bool,
    error: Option<(String, Error)>,
}

impl Committer {
    /// Runs `f` with a committer whose thread places blobs in `stat`'s view as it commits them; the thread ends
    /// with `f`. Call [`Committer::flush`] inside `f` before reading what it committed, and at its end: what is
    /// handed over after the last flush is committed, but its failure is not reported.
    pub fn scope<R>(stat: &StatCache, f: impl FnOnce(&Committer) -> R) -> R {
        let (tx, rx) = sync_channel(QUEUE);
        let c =
            Committer { tx: Mutex::new(Some(tx)), progress: Mutex::new(Progress::default()), settled: Condvar::new() };
        /// Closes the queue, which ends the thread once it has drained, however `f` ends (a panic too: the
        /// scope would otherwise wait for the thread forever).
        struct Close<'a>(&'a Committer);
        impl Drop for Close<'_> {
            fn drop(&mut self) {
                self.0.tx.lock().unwrap_or_else(|p| p.into_inner()).take();
            }
        }
        std::thread::scope(|s| {
            s.spawn(|| c.work(rx, stat));
            let _close = Close(&c);
            f(&c)
        })
    }

    /// Hands over the staged `blobs` of the action `label` and its `record`, to be committed in that order.
    /// Fails (and drops the files) when an earlier commit failed: the build stops.
    pub fn submit(&self, label: &str, blobs: Vec<(Digest, Staged)>, record: Staged) -> Result<(), Error> {
        {
            let mut p = self.lock();
            if p.failed {
                return Err(Error::Stopped);
            }
            p.sent += 1;
        }
        let tx = self.tx.lock().unwrap_or_else(|p| p.into_inner()).clone();
        if tx.is_none_or(|tx| tx.send(Job { label: label.to_string(), blobs, record }).is_err()) {
            // The queue is closed, or the thread is gone: the job is settled here.
            self.settle(Some((label.to_string(), Error::Stopped)));
            return Err(Error::Stopped);
        }
        Ok(())
    }

    /// Waits until every commit handed over so far is done; the first failure, with its action's label.
    pub fn flush(&self) -> Result<(), (String, Error)> {
        let mut p = self.lock();
        while p.done < p.sent {
            p = self.settled.wait(p).unwrap_or_else(|p| p.into_inner());
        }
        match p.error.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The progress (a panicking holder cannot leave it inconsistent: every update is one field at a time).
    fn lock(&self) -> std::sync::MutexGuard<'_, Progress> {
        self.progress.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Marks one job finished, with its failure if it failed (the first failure is kept).
    fn settle(&self, error: Option<(String, Error)>) {
        let mut p = self.lock();
        p.done += 1;
        if let Some(e) = error {
            p.failed = true;
            p.error.get_or_insert(e);
        }
        self.settled.notify_all();
    }

    /// The committer thread: commits jobs in the order they came until the queue closes. After a failure, the
    /// jobs still coming are dropped (their temporaries removed), not committed.
    fn work(&self, rx: Receiver<Job>, stat: &StatCache) {
        let mut panicked = None;
        for Job { label, blobs, record } in rx {
            if self.lock().failed {
                self.settle(None);
                continue;
            }
            // A panic (a bug) settles its job as a failure and the queue drains, or `flush` would wait forever;
            // it is raised when the queue closes, and the scope raises it again when `f` returns.
            match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| commit_action(blobs, record, stat))) {
                Ok(result) => self.settle(result.err().map(|e| (label, e))),
                Err(panic) => {
                    self.settle(Some((label, Error::Stopped)));
                    panicked.get_or_insert(panic);
                }
            }
        }
        if let Some(panic) = panicked {
            std::panic::resume_unwind(panic);
        }
    }
}

/// Commits one action's blobs, then (only if they all went in) its record.
fn commit_action(blobs: Vec<(Digest, Staged)>, record: Staged, stat: &StatCache) -> Result<(), Error> {
    for (d, f) in blobs {
        place(d, f, stat)?;
    }
    commit(record)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::Store;

    /// A store in a fresh directory, with its stat cache.
    fn fixture() -> (tempfile::TempDir, Store, StatCache) {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let stat = StatCache::load(&dir.path().join("stat"));
        (dir, store, stat)
    }

    /// Temporary files left anywhere under `dir`.
    fn debris(dir: &tempfile::TempDir) -> usize {
        let mut files = Vec::new();
        crate::cache::gc::walk(dir.path(), &mut files);
        files.iter().filter(|(p, ..)| p.to_string_lossy().contains(crate::atomic::TMP_PREFIX)).count()
    }

    #[test]
    fn records_follow_their_blobs_and_flush_waits_for_both() {
        let (dir, store, stat) = fixture();
        let key = crate::cache::key("test", &[b"a"]);
        let d = Committer::scope(&stat, |c| {
            let (d, staged) = store.stage(b"blob bytes", &stat).unwrap();
            let record = store.stage_action(&key, &[d], &[]).unwrap();
            // Nothing is in place before the commit.
            assert!(store.hit(&key, &stat).is_none());
            c.submit("a", vec![(d, staged.unwrap())], record).unwrap();
            c.flush().unwrap();
            d
        });
        assert_eq!(store.hit(&key, &stat), Some(vec![d]));
        assert!(stat.holds(&store.object_path(&d), &d));
        assert_eq!(store.get(&d).unwrap(), b"blob bytes");
        assert_eq!(debris(&dir), 0);
    }

    #[test]
    fn a_failed_commit_is_reported_by_flush_and_stops_later_submissions() {
        let (dir, store, stat) = fixture();
        let key = crate::cache::key("test", &[b"b"]);
        Committer::scope(&stat, |c| {
            let (d, staged) = store.stage(b"other bytes", &stat).unwrap();
            let record = store.stage_action(&key, &[d], &[]).unwrap();
            // The blob's place becomes a non-empty directory: the rename onto it fails.
            let place = store.object_path(&d);
            std::fs::create_dir_all(place.join("x")).unwrap();
            c.submit("the action", vec![(d, staged.unwrap())], record).unwrap();
            let (label, e) = c.flush().unwrap_err();
            assert_eq!(label, "the action");
            assert!(e.to_string().contains(&d.hex()[2..]), "{e}");
            let (d2, staged2) = store.stage(b"more bytes", &stat).unwrap();
            let record2 = store.stage_action(&crate::cache::key("test", &[b"c"]), &[d2], &[]).unwrap();
            assert!(c.submit("later", vec![(d2, staged2.unwrap())], record2).is_err());
        });
        // The failed action has no record, and the dropped files left no temporaries.
        assert!(store.action(&key).is_none());
        assert_eq!(debris(&dir), 0);
    }
}
