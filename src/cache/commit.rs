//! Group commit of a build's results. A worker that made an action's blobs writes them, and the action's record,
//! under temporary names ([`Store::stage`], [`Store::stage_action`]) and hands them to one committer thread,
//! which makes them durable and renames them into place: the blobs first, the record last, so a record only
//! ever names blobs that are in place (what [`Store::hit`] relies on). Rendering goes on meanwhile: a worker that
//! synced its own files waited about half a millisecond per file with its core idle, a tenth of a build's wall
//! time on two cores.
//!
//! The committer takes every job waiting when it wakes as one batch and syncs the batch's files together
//! ([`atomic::sync_together`]) before renaming any of them: one flush of the disk's cache per batch rather
//! than one per file (on a cut of the seed-scale set, a sixth of the machine's busy CPU time, mostly in the
//! kernel). The guarantee is the same: nothing is renamed into place before its bytes are on disk.
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
use crate::atomic::{self, Staged};

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
    /// New submissions are refused ([`Committer::refuse`]); those handed over still commit.
    refusing: bool,
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
            if p.failed || p.refusing {
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
    /// Submissions made meanwhile (by kinds running beside the caller's) are not waited for: jobs commit in the
    /// order they were sent, so once as many are done as had been counted on entry, all of the caller's are.
    /// The failure goes to the first flush after it; later ones report [`Error::Stopped`] (unlabelled), since
    /// their own jobs may have been dropped behind the failed one.
    pub fn flush(&self) -> Result<(), (String, Error)> {
        let mut p = self.lock();
        let target = p.sent;
        while p.done < target {
            p = self.settled.wait(p).unwrap_or_else(|p| p.into_inner());
        }
        if !p.failed {
            return Ok(());
        }
        Err(p.error.take().unwrap_or_else(|| (String::new(), Error::Stopped)))
    }

    /// Refuses every later submission with [`Error::Stopped`], while the jobs already handed over still
    /// commit: an action failed and the build stops, keeping what the other actions made.
    pub fn refuse(&self) {
        self.lock().refusing = true;
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

    /// The committer thread: commits jobs in the order they came, in batches of those waiting, until the queue
    /// closes. After a failure, the jobs still coming are dropped (their temporaries removed), not committed.
    fn work(&self, rx: Receiver<Job>, stat: &StatCache) {
        let mut panicked = None;
        while let Ok(first) = rx.recv() {
            let batch: Vec<Job> = std::iter::once(first).chain(rx.try_iter().take(QUEUE)).collect();
            if self.lock().failed {
                batch.iter().for_each(|_| self.settle(None));
                continue;
            }
            // A panic (a bug) settles the batch's jobs as failures and the queue drains, or `flush` would wait
            // forever; it is raised when the queue closes, and the scope raises it again when `f` returns.
            let labels: Vec<String> = batch.iter().map(|j| j.label.clone()).collect();
            match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| commit_batch(batch, stat))) {
                Ok(results) => {
                    for (label, result) in labels.into_iter().zip(results) {
                        self.settle(result.err().map(|e| (label, e)));
                    }
                }
                Err(panic) => {
                    labels.into_iter().for_each(|label| self.settle(Some((label, Error::Stopped))));
                    panicked.get_or_insert(panic);
                }
            }
        }
        if let Some(panic) = panicked {
            std::panic::resume_unwind(panic);
        }
    }
}

/// Commits a batch of jobs: syncs all their files together, then places each job's blobs and (only if they all
/// went in) its record, until one fails. Each job's outcome, in order; when the sync fails, every job fails.
fn commit_batch(batch: Vec<Job>, stat: &StatCache) -> Vec<Result<(), Error>> {
    let files = batch.iter().flat_map(|j| j.blobs.iter().map(|(_, f)| f).chain([&j.record]));
    if let Err(e) = atomic::sync_together(files) {
        // Named by each job's record (the batch's files are synced as one, so any of them may be the cause).
        let failed = |j: &Job| {
            let source = std::io::Error::new(e.kind(), format!("syncing the cache's new files: {e}"));
            Err(Error::io(j.record.dest(), source))
        };
        return batch.iter().map(failed).collect();
    }
    // After a failure the rest are dropped, uncommitted (and settled without an error of their own), as the
    // jobs that come after one are.
    let mut failed = false;
    let commit = |j: Job| {
        if failed {
            return Ok(());
        }
        commit_action(j.blobs, j.record, stat).inspect_err(|_| failed = true)
    };
    batch.into_iter().map(commit).collect()
}

/// Commits one action's synced blobs, then (only if they all went in) its synced record.
fn commit_action(blobs: Vec<(Digest, Staged)>, record: Staged, stat: &StatCache) -> Result<(), Error> {
    for (d, f) in blobs {
        place(d, f, stat, Staged::commit_synced)?;
    }
    commit(record, Staged::commit_synced)
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

    /// A job of one blob with content `bytes`, keyed by them.
    fn job(store: &Store, stat: &StatCache, bytes: &[u8]) -> (Digest, Digest, Job) {
        let key = crate::cache::key("test", &[bytes]);
        let (d, staged) = store.stage(bytes, stat).unwrap();
        let record = store.stage_action(&key, &[d], &[]).unwrap();
        (key, d, Job { label: String::from_utf8_lossy(bytes).into_owned(), blobs: vec![(d, staged.unwrap())], record })
    }

    #[test]
    fn a_batch_commits_in_order_up_to_its_first_failure() {
        let (dir, store, stat) = fixture();
        let jobs: Vec<_> = [&b"first"[..], b"second", b"third"].iter().map(|b| job(&store, &stat, b)).collect();
        // The second job's blob cannot be renamed into place.
        std::fs::create_dir_all(store.object_path(&jobs[1].1).join("x")).unwrap();
        let keys: Vec<_> = jobs.iter().map(|(k, d, _)| (*k, *d)).collect();
        let results = commit_batch(jobs.into_iter().map(|(.., j)| j).collect(), &stat);
        assert!(results[0].is_ok() && results[1].is_err() && results[2].is_ok(), "{results:?}");
        assert_eq!(store.hit(&keys[0].0, &stat), Some(vec![keys[0].1]));
        // The failed job has no record; the one after it was dropped: neither record nor blob, nor temporaries.
        assert!(store.action(&keys[1].0).is_none());
        assert!(store.action(&keys[2].0).is_none() && !store.object_path(&keys[2].1).exists());
        assert_eq!(debris(&dir), 0);
    }

    #[test]
    fn many_jobs_handed_over_at_once_are_all_committed() {
        let (dir, store, stat) = fixture();
        let n = 3 * QUEUE;
        let keys = Committer::scope(&stat, |c| {
            let keys: Vec<_> = (0..n)
                .map(|i| {
                    let (key, d, j) = job(&store, &stat, format!("blob {i}").as_bytes());
                    c.submit(&j.label, j.blobs, j.record).unwrap();
                    (key, d)
                })
                .collect();
            c.flush().unwrap();
            keys
        });
        for (key, d) in keys {
            assert_eq!(store.hit(&key, &stat), Some(vec![d]));
        }
        assert_eq!(debris(&dir), 0);
    }
}
