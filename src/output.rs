//! Run outputs: `blocks.csv`, `contacts.csv` and `summary.json` (the command-line contract).
//!
//! The files are written so that a run stopped at any moment leaves something a reader can
//! use. Rows are staged in memory and reach the CSV files only in whole steps, both files
//! together ([`RunWriter::commit`]): after a kill, each file ends with a complete row unless
//! the kill landed inside a write, and then only its last line lacks its newline (a reader
//! drops such a line). A failed write (a full disk) is cut back to the last whole step.
//! `summary.json` is replaced atomically (written beside it, then renamed), so it is always
//! one whole JSON document. [`vtk`] writes the ParaView series.

mod background;
pub mod vtk;

pub use background::RunWriter;

use std::fs::File;
use std::io::{self, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::rockmass::report::RockMassReport;
use crate::snapshot::Snapshot;
use crate::snapshot::{EquilibriumReport, RunTotals, Timings};

/// Staged rows beyond this many bytes are committed at the end of the step. Small, so that a
/// kill or a full disk loses little more than a step (about as often as the 8 KiB buffer of a
/// plain buffered writer writes, and never inside a step).
const STAGE_LIMIT: usize = 16 << 10;

/// A file of the run that could not be created or written, and why.
#[derive(Clone, Debug)]
pub struct OutputError {
    pub path: PathBuf,
    pub message: String,
}

impl OutputError {
    pub(crate) fn io(path: &Path, what: &str, e: impl std::fmt::Display) -> OutputError {
        OutputError {
            path: path.to_path_buf(),
            message: format!("{what}: {e}"),
        }
    }
}

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.message)
    }
}

impl std::error::Error for OutputError {}

/// One CSV file whose rows are staged in memory and reach the disk only in whole steps.
struct StagedCsv {
    rows: csv::Writer<Vec<u8>>,
    file: File,
    path: PathBuf,
    /// Bytes on disk, all of them whole rows.
    committed: u64,
}

impl StagedCsv {
    fn create(path: PathBuf, header: &[&str]) -> Result<StagedCsv, OutputError> {
        let file = File::create(&path).map_err(|e| OutputError::io(&path, "cannot create", e))?;
        let mut staged = StagedCsv {
            rows: csv::Writer::from_writer(Vec::new()),
            file,
            path,
            committed: 0,
        };
        staged.row(header)?;
        Ok(staged)
    }

    fn row<I, T>(&mut self, fields: I) -> Result<(), OutputError>
    where
        I: IntoIterator<Item = T>,
        T: AsRef<[u8]>,
    {
        // Into memory: fails only if the allocator does.
        self.rows
            .write_record(fields)
            .map_err(|e| OutputError::io(&self.path, "cannot format a row", e))
    }

    /// Bytes staged and not yet on disk (up to the csv writer's own 8 KiB buffer more).
    fn staged(&self) -> usize {
        self.rows.get_ref().len()
    }

    /// Appends the staged rows to the file. On failure the file is cut back to what it held
    /// before (best effort: a full disk frees the partial block, /dev/full cannot be cut).
    fn commit(&mut self) -> Result<(), OutputError> {
        let rows = std::mem::replace(&mut self.rows, csv::Writer::from_writer(Vec::new()));
        let mut bytes = rows
            .into_inner()
            .map_err(|e| OutputError::io(&self.path, "cannot format a row", e.error()))?;
        if let Err(e) = self.file.write_all(&bytes) {
            self.roll_back(self.committed);
            return Err(OutputError::io(&self.path, "cannot write", e));
        }
        self.committed += bytes.len() as u64;
        bytes.clear();
        self.rows = csv::Writer::from_writer(bytes);
        Ok(())
    }

    fn roll_back(&mut self, len: u64) {
        let _ = self.file.set_len(len);
        let _ = self.file.seek(SeekFrom::Start(len));
        self.committed = len;
    }
}

/// Streams one row per block and one per active contact for every completed step (on the
/// thread of [`RunWriter`]).
pub(crate) struct RowWriter {
    blocks: StagedCsv,
    contacts: StagedCsv,
    /// Time of the last step staged, and of the last step on disk in both files.
    staged_time: Option<f64>,
    written_time: Option<f64>,
    /// Set by a failed commit: nothing more is written after one.
    failed: bool,
}

/// Shortest round-trip text of a number, in exponent form when it is tiny (penetrations of
/// 1e-16 m would otherwise print as thirty zeros).
pub(crate) fn num(x: f64) -> String {
    if x != 0.0 && x.abs() < 1e-4 {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}

/// Creates `dir` (and its parents) as the output directory, with a clear message when the
/// path is taken by a file.
fn create_output_dir(dir: &Path) -> Result<(), OutputError> {
    crate::files::create_dir_clearly(dir)
        .map_err(|e| OutputError::io(dir, "cannot create the output directory", e))
}

impl RowWriter {
    /// Creates `dir` and the two CSV files, their headers staged.
    pub fn create(dir: &Path) -> Result<Self, OutputError> {
        create_output_dir(dir)?;
        let blocks = StagedCsv::create(
            dir.join("blocks.csv"),
            &["time", "block", "x", "y", "z", "vx", "vy", "vz"],
        )?;
        let contacts = StagedCsv::create(
            dir.join("contacts.csv"),
            &[
                "time",
                "block_i",
                "block_j",
                "mode",
                "state",
                "px",
                "py",
                "pz",
                "nx",
                "ny",
                "nz",
                "normal_force",
                "shear_force",
                "penetration",
                "penalty",
                "lambda",
                "joint",
            ],
        )?;
        Ok(RowWriter {
            blocks,
            contacts,
            staged_time: None,
            written_time: None,
            failed: false,
        })
    }

    /// Time of the last step whose rows are on disk, complete, in both files.
    pub fn written_time(&self) -> Option<f64> {
        self.written_time
    }

    /// Stages the rows of one completed step; commits them once enough are staged.
    pub fn write(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        let t = num(s.time);
        for b in &s.blocks {
            let c = b.centroid;
            let v = b.velocity;
            self.blocks.row([
                t.as_str(),
                &b.name,
                &num(c[0]),
                &num(c[1]),
                &num(c[2]),
                &num(v[0]),
                &num(v[1]),
                &num(v[2]),
            ])?;
        }
        for c in &s.contacts {
            let f = num;
            self.contacts.row([
                t.clone(),
                s.blocks[c.block_i].name.clone(),
                s.blocks[c.block_j].name.clone(),
                c.mode.as_str().to_string(),
                c.state.as_str().to_string(),
                f(c.point[0]),
                f(c.point[1]),
                f(c.point[2]),
                f(c.normal[0]),
                f(c.normal[1]),
                f(c.normal[2]),
                f(c.normal_force),
                f(c.shear_force),
                f(c.penetration),
                f(c.penalty),
                f(c.lambda),
                c.joint
                    .and_then(|k| s.joint_sets.get(usize::from(k)))
                    .cloned()
                    .unwrap_or_default(),
            ])?;
        }
        self.staged_time = Some(s.time);
        if self.blocks.staged() + self.contacts.staged() > STAGE_LIMIT {
            self.commit()?;
        }
        Ok(())
    }

    /// Writes the staged rows of both files, so both end with the same whole step. If either
    /// write fails, both files are cut back to the previous step and later calls do nothing.
    pub fn commit(&mut self) -> Result<(), OutputError> {
        if self.failed {
            return Ok(());
        }
        let before = (self.blocks.committed, self.contacts.committed);
        let result = self.blocks.commit().and_then(|_| self.contacts.commit());
        if result.is_err() {
            self.failed = true;
            self.blocks.roll_back(before.0);
            self.contacts.roll_back(before.1);
        } else {
            self.written_time = self.staged_time;
        }
        result
    }
}

/// When the outputs of a run are due: its first state, then every later step, or with an
/// interval the first step at or past each multiple of it (see [`interval_slot`]); and its
/// final state, whatever the schedule, unless it was the last output.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Schedule {
    /// Simulated time between outputs, s (`None`: every step).
    interval: Option<f64>,
    /// Time of the last output.
    last: Option<f64>,
}

impl Schedule {
    pub(crate) fn new(interval: Option<f64>) -> Self {
        Schedule {
            interval,
            last: None,
        }
    }

    /// Whether a state at `time` is written.
    pub(crate) fn due(&self, time: f64) -> bool {
        let Some(last) = self.last else {
            return true;
        };
        match self.interval {
            None => time > last,
            // Steps do not end on the multiples: the slot index of the time decides, with a
            // relative tolerance so that a step ending a rounding error short of a multiple
            // counts as reaching it.
            Some(dt) => interval_slot(time, dt) > interval_slot(last, dt),
        }
    }

    /// Whether the final state, at `time`, still has to be written.
    pub(crate) fn final_due(&self, time: f64) -> bool {
        self.last != Some(time)
    }

    /// Notes an output of the state at `time`.
    pub(crate) fn wrote(&mut self, time: f64) {
        self.last = Some(time);
    }
}

/// Which interval of length `dt` the time `t` falls in, a step a hair short of a multiple
/// counted in the next. Outputs at an interval (`--output-interval`, `--checkpoint-every`) take
/// the first step at or past each multiple: steps do not end on them, and this keeps the
/// schedule a function of time alone.
pub(crate) fn interval_slot(t: f64, dt: f64) -> i64 {
    (t / dt + 1e-9).floor() as i64
}

/// Writes `bytes` to `path` atomically: into a temporary file in the same directory, then
/// renamed over `path`, so a reader (or a kill) never meets a half-written file.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let written = File::create(&tmp).and_then(|mut f| f.write_all(bytes));
    match written.and_then(|_| std::fs::rename(&tmp, path)) {
        Ok(()) => Ok(()),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub scene: String,
    pub method: String,
    pub mode: String,
    /// "completed", "diverged", "interrupted" (SIGINT or SIGTERM), "io_error" (a write
    /// failed), or "running" (a checkpoint of a run still going, or one that was killed).
    pub status: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    pub steps: u64,
    pub simulated_time: f64,
    /// Time of the last step whose rows are complete in both CSV files (at least; the files
    /// may hold later steps too). Less than `simulated_time` only after a failed write.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub written_time: Option<f64>,
    pub wall_seconds: f64,
    /// Largest penetration of a closed contact over the run beyond its kept overlap, m.
    pub max_penetration: f64,
    /// Largest overlap kept by a contact over the run, m (see `StepStats::max_overlap`).
    pub max_overlap: f64,
    pub open_close_iterations: u64,
    pub alm_iterations: u64,
    pub time_step_cuts: u64,
    pub factorizations: u64,
    pub symbolic_analyses: u64,
    pub contacts_per_step: f64,
    pub unconverged_steps: u64,
    pub alm_cap_hits: u64,
    /// Contacts settled after cycling between states within one attempt, or at the open–close
    /// pass limit.
    pub frozen_contacts: u64,
    /// Steps in which at least one block slept, held still with its island (absent when none
    /// did; see `solver.sleep_velocity`).
    #[serde(skip_serializing_if = "is_zero")]
    pub sleeping_steps: u64,
    /// Seconds spent in each phase.
    pub timings: Timings,
    /// The initial equilibrium stage (`[solver] initial_equilibrium`): its static steps, R_max
    /// at its end, and whether R_max fell below the tolerance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<EquilibriumReport>,
    /// What cutting each rock mass of the scene gave (absent without rock masses).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rock_masses: Vec<RockMassReport>,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

impl Summary {
    pub fn new(scene: &str, method: &str, mode: &str, time: f64, wall: f64, t: &RunTotals) -> Self {
        Summary {
            scene: scene.to_string(),
            method: method.to_string(),
            mode: mode.to_string(),
            status: "completed".into(),
            error: None,
            steps: t.steps,
            simulated_time: time,
            written_time: None,
            wall_seconds: wall,
            max_penetration: t.max_penetration,
            max_overlap: t.max_overlap,
            open_close_iterations: t.open_close_iterations,
            alm_iterations: t.alm_iterations,
            time_step_cuts: t.time_step_cuts,
            factorizations: t.factorizations,
            symbolic_analyses: t.symbolic_analyses,
            contacts_per_step: t.contacts_per_step,
            unconverged_steps: t.unconverged_steps,
            alm_cap_hits: t.alm_cap_hits,
            frozen_contacts: t.frozen_contacts,
            sleeping_steps: t.sleeping_steps,
            timings: t.timings.clone(),
            equilibrium: None,
            rock_masses: Vec::new(),
        }
    }

    /// Replaces `dir/summary.json` atomically; returns its path or the error naming it.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, OutputError> {
        let path = dir.join("summary.json");
        let mut text = serde_json::to_vec_pretty(self)
            .map_err(|e| OutputError::io(&path, "cannot format", e))?;
        text.push(b'\n');
        write_atomically(&path, &text).map_err(|e| OutputError::io(&path, "cannot write", e))?;
        Ok(path)
    }
}

/// The longest [`slug`]: well inside the 255 bytes a file name may have, so that any scene
/// name gives a directory that can be created.
pub const MAX_SLUG: usize = 100;

/// A directory name from a scene name: lower case, runs of other characters become '-', cut
/// to [`MAX_SLUG`] characters.
pub fn slug(name: &str) -> String {
    let mut s = String::new();
    for ch in name.chars() {
        if ch.is_ascii_alphanumeric() {
            s.push(ch.to_ascii_lowercase());
        } else if !s.ends_with('-') {
            s.push('-');
        }
    }
    let mut s = s.trim_matches('-').to_string();
    // ASCII only, so any byte index is a character boundary.
    s.truncate(MAX_SLUG);
    let s = s.trim_end_matches('-').to_string();
    if s.is_empty() { "scene".into() } else { s }
}

#[cfg(test)]
mod tests {
    #[test]
    fn slugs() {
        assert_eq!(
            super::slug("Block sliding on a 30 degree slope"),
            "block-sliding-on-a-30-degree-slope"
        );
        assert_eq!(super::slug("  ?? "), "scene");
        let long = super::slug(&"Rock fall ".repeat(100));
        assert!(long.len() <= super::MAX_SLUG && long.starts_with("rock-fall-rock"));
        assert!(!long.ends_with('-'), "{long}");
    }
}
