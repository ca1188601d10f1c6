//! The CSV rows written on their own thread. Formatting the numbers of a step's rows cost as
//! much as the step itself on a wall of 1000 blocks (about 10 000 contact rows a step); here the
//! solver hands each step's snapshot over and goes on while [`RowWriter`] formats and writes it.
//!
//! The files are the same, byte for byte, and so are their guarantees: rows reach the disk in
//! whole steps, both files together. [`RunWriter::commit`] waits until every step handed over
//! is on disk, so what summary.json reports as written is. A failed write is reported by the
//! next call (the step after the one it happened in, or the commit), and nothing more is written
//! after it.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use super::{OutputError, RowWriter};
use crate::snapshot::Snapshot;

/// Steps that may wait for the writer thread before the solver waits for it: enough to ride
/// out a slow write, few enough that memory stays a few steps' worth of snapshots.
const QUEUE: usize = 4;

enum Job {
    Rows(Box<Snapshot>),
    /// Commit everything handed over so far, and answer.
    Commit(SyncSender<Result<(), OutputError>>),
}

/// What the writer thread tells the solver's side between commits.
#[derive(Default)]
struct Shared {
    /// Time of the last step whose rows are on disk in both files.
    written_time: Option<f64>,
    /// The first failed write; later calls return it.
    error: Option<OutputError>,
}

/// Streams one row per block and one per active contact for every completed step, formatted
/// and written on a thread of its own.
pub struct RunWriter {
    dir: PathBuf,
    jobs: Option<SyncSender<Job>>,
    worker: Option<JoinHandle<()>>,
    shared: Arc<Mutex<Shared>>,
}

impl RunWriter {
    /// Creates `dir` and the two CSV files, their headers staged, and starts the writer thread.
    pub fn create(dir: &Path) -> Result<Self, OutputError> {
        let rows = RowWriter::create(dir)?;
        let shared = Arc::new(Mutex::new(Shared::default()));
        let (jobs, inbox) = sync_channel(QUEUE);
        let side = Arc::clone(&shared);
        let worker = std::thread::Builder::new()
            .name("dda3d-rows".into())
            .spawn(move || work(rows, &inbox, &side))
            .map_err(|e| OutputError::io(dir, "cannot start the writer thread", e))?;
        Ok(RunWriter {
            dir: dir.to_path_buf(),
            jobs: Some(jobs),
            worker: Some(worker),
            shared,
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Time of the last step whose rows are on disk, complete, in both files.
    pub fn written_time(&self) -> Option<f64> {
        self.lock().written_time
    }

    /// Hands the rows of one completed step to the writer thread (which commits them once
    /// enough are staged). Fails if an earlier write failed.
    pub fn write(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        self.failure()?;
        self.send(Job::Rows(Box::new(s.clone())))
    }

    /// Writes every step handed over so far, so both files end with the same whole step, and
    /// waits until they are on disk. If a write fails, both files are cut back to the previous
    /// step and later calls do nothing but return the error.
    pub fn commit(&mut self) -> Result<(), OutputError> {
        self.failure()?;
        let (reply, answer) = sync_channel(1);
        self.send(Job::Commit(reply))?;
        answer.recv().unwrap_or_else(|_| Err(self.gone()))
    }

    fn send(&self, job: Job) -> Result<(), OutputError> {
        let jobs = self.jobs.as_ref().expect("open until dropped");
        jobs.send(job).map_err(|_| self.gone())
    }

    fn failure(&self) -> Result<(), OutputError> {
        match &self.lock().error {
            Some(e) => Err(e.clone()),
            None => Ok(()),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Shared> {
        // A panic on the writer thread poisons nothing the solver needs: the data is plain.
        self.shared.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The error for a writer thread that has stopped (it panicked).
    fn gone(&self) -> OutputError {
        OutputError::io(&self.dir, "cannot write", "the writer thread stopped")
    }
}

impl Drop for RunWriter {
    /// Lets the thread finish what it was handed (staged rows of an uncommitted step stay
    /// uncommitted, as before) and joins it.
    fn drop(&mut self) {
        self.jobs.take();
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}

/// The writer thread: formats and stages each step's rows, commits when asked or when enough
/// are staged, and reports the written time and the first failure through `shared`.
fn work(mut rows: RowWriter, inbox: &Receiver<Job>, shared: &Mutex<Shared>) {
    let mut failed = false;
    for job in inbox {
        let result = match job {
            Job::Rows(s) if !failed => rows.write(&s),
            Job::Rows(_) => Ok(()),
            Job::Commit(reply) => {
                let r = if failed { Ok(()) } else { rows.commit() };
                if r.is_ok() {
                    record(shared, |sh| sh.written_time = rows.written_time());
                }
                let _ = reply.send(r.clone());
                r
            }
        };
        match result {
            Ok(()) => record(shared, |sh| sh.written_time = rows.written_time()),
            Err(e) if !failed => {
                failed = true;
                record(shared, |sh| sh.error = Some(e));
            }
            Err(_) => {}
        }
    }
}

fn record(shared: &Mutex<Shared>, f: impl FnOnce(&mut Shared)) {
    f(&mut shared.lock().unwrap_or_else(|p| p.into_inner()));
}
