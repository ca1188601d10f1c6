//! Parameter studies (`dda3d study`, issue #18): one base scene run many times with some of its
//! keys varied, and a table of what each run gave.
//!
//! ```toml
//! scene = "../scenes/rock_column_rockfall.toml"   # relative to the study file
//! seed = 1                  # default 0
//! cases = 200               # random draws per grid point; ignored without random parameters
//! outcomes = ["runout", "blocks_toppled"]
//! watch = ["column*"]       # the blocks the block outcomes consider (default: every free block)
//! moved_threshold = 0.1     # m, for blocks_moved
//! toppled_angle = 30.0      # degrees, for blocks_toppled
//! case_timeout = 600.0      # wall seconds a case may take (default: no limit)
//! set = { "solver.duration" = 4.0 }               # keys given one value in every case
//! [[parameters]]
//! key = "joint.friction_angle"
//! values = [25.0, 30.0, 35.0]                     # a grid axis
//! [[parameters]]
//! key = "blocks.rock.velocity[0]"
//! uniform = [-14.0, -6.0]   # or log_uniform = [lo, hi], normal = [mean, sd] (+ bounds = [lo, hi])
//! ```
//!
//! - **Keys** ([`keys`]): a dotted path into the scene's TOML; arrays of tables by an
//!   element's `name` (`blocks.rock`, `rock_masses.slope.joint_sets.J1.dip`) or index,
//!   vectors by `[i]`. The case's scene is the base scene's text with the values set
//!   (comments kept). Every key is checked at load by setting it to the base's own value (or
//!   the parameter's first value, lower bound or mean) and parsing the scene. A drawn number
//!   is rounded where the base's value is an integer.
//! - **Cases** ([`draw`]): G, the product of the `values` lists' lengths, grid points, crossed
//!   with `cases` random draws each: case k = g × cases + d, the first `values` parameter
//!   varying slowest. With only `values` parameters the grid is the study. The draws of case k
//!   come from ChaCha8 seeded with `seed` on stream k, parameters in file order: the same
//!   whichever worker, order or `--case` runs it. At most [`MAX_CASES`] cases.
//! - **Outcomes** ([`outcomes::Outcome`]): `max_displacement` (m, largest centroid
//!   displacement of a watched free block over the run), `runout` (m, largest distance
//!   perpendicular to gravity between a watched block's centroid at the end and at the start),
//!   `blocks_moved` (watched blocks ending more than `moved_threshold` from their start),
//!   `blocks_toppled` (watched blocks tilted more than `toppled_angle` at the end: the angle
//!   between gravity's direction and its image under the best-fit rotation of the block's
//!   vertices), `blocks_rotated` (the same with the whole rotation angle), `peak_normal_force` (N, largest contact normal
//!   force over the run), `final_kinetic_energy` (J), `max_penetration` (m, as summary.json),
//!   `steps`. The start is t = 0, after any initial equilibrium stage.
//! - **Running** ([`run_task`]): a case runs its scene to its duration; a scene error, a
//!   divergence, a panic or `case_timeout` make it a failed case with a one-line error, and the
//!   others go on.
//! - **Output** ([`table`]): `DIR/cases/case_<k>.json` per finished case (what resuming
//!   skips), `study.csv` (`case`, the keys, the outcomes, `status`, `wall_seconds`, `error`),
//!   `study.json` (settings, fingerprint, counts, outcome statistics, records) and
//!   `plots/`. The fingerprint (a hash of the study file's and the base scene's text) marks
//!   the directory: another study's directory is refused.

pub mod draw;
pub mod keys;
pub mod outcomes;
pub mod plots;
mod run;
mod spec;
pub mod table;

use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use keys::override_scene_text;
pub use outcomes::{Outcome, OutcomeSettings};
pub use run::{run_task, run_task_until};

use crate::text::one_line;
use draw::{Distribution, Drawn};

/// The most cases a study may have: a table of a million rows is already more than a plot or a
/// spreadsheet takes.
pub const MAX_CASES: usize = 1_000_000;

/// A bad study file, an unusable output directory or a record that cannot be read: one line
/// naming the file.
#[derive(Clone, Debug, PartialEq)]
pub struct StudyError {
    message: String,
    io: bool,
}

impl StudyError {
    pub(crate) fn input(message: impl Into<String>) -> StudyError {
        StudyError {
            message: one_line(&message.into()),
            io: false,
        }
    }

    pub(crate) fn io(message: impl Into<String>) -> StudyError {
        StudyError {
            message: one_line(&message.into()),
            io: true,
        }
    }

    /// A file could not be written or read (exit status 74), rather than bad input (2).
    pub fn is_io(&self) -> bool {
        self.io
    }
}

impl fmt::Display for StudyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for StudyError {}

/// One varied key.
#[derive(Clone, Debug)]
struct Parameter {
    key: String,
    dist: Distribution,
    /// The base's value at the key is an integer: drawn numbers are rounded.
    integer: bool,
}

/// A loaded, validated study file (its base scene read, every key checked against it).
#[derive(Clone, Debug)]
pub struct Study {
    path: PathBuf,
    /// `scene` as the study file writes it (messages), and the file it names.
    scene_written: String,
    scene_text: String,
    scene_default_name: String,
    /// The `set` table: keys given one value in every case.
    fixed: Vec<(String, toml::Value)>,
    seed: u64,
    /// Random draws per grid point (1 without random parameters).
    draws: usize,
    len: usize,
    parameters: Vec<Parameter>,
    outcomes: Vec<Outcome>,
    settings: OutcomeSettings,
    case_timeout: Option<f64>,
    fingerprint: String,
}

/// Case `case` of a study, self-contained: everything a worker needs to run it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Task {
    pub case: usize,
    /// The varied keys and this case's values of them (as in [`CaseRecord::values`]).
    pub keys: Vec<String>,
    pub values: Vec<serde_json::Value>,
    /// The base scene's path as the study names it, for messages.
    pub scene_path: String,
    /// The scene's name where it has none: the base file's stem.
    pub scene_default_name: String,
    /// The base scene's text with this case's values set.
    pub scene_text: String,
    pub outcomes: Vec<String>,
    pub settings: OutcomeSettings,
    /// Wall seconds the case may take.
    pub case_timeout: Option<f64>,
    pub fingerprint: String,
}

impl Task {
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    pub fn from_json(text: &str) -> Result<Task, StudyError> {
        serde_json::from_str(text).map_err(|e| StudyError::input(format!("task JSON: {e}")))
    }
}

/// What one case gave.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CaseRecord {
    pub case: usize,
    /// The case's parameter values, in key order, as JSON values (numbers, or strings/bools for
    /// `values` grids of such).
    pub values: Vec<serde_json::Value>,
    /// One per outcome, in outcome order; None for a failed case.
    pub outcomes: Vec<Option<f64>>,
    /// "ok" or "failed".
    pub status: String,
    pub error: Option<String>,
    pub wall_seconds: f64,
    /// The study's fingerprint: a record of another study is not taken for one of this one.
    #[serde(default)]
    pub fingerprint: String,
}

impl CaseRecord {
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    pub fn from_json(text: &str) -> Result<CaseRecord, StudyError> {
        serde_json::from_str(text).map_err(|e| StudyError::input(format!("case record JSON: {e}")))
    }

    pub fn is_ok(&self) -> bool {
        self.status == "ok"
    }
}

impl Study {
    /// Reads and checks a study file and its base scene.
    pub fn load(path: &Path) -> Result<Study, StudyError> {
        spec::load(path)
    }

    /// Number of cases.
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The study file as given.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The varied keys, in file order (study.csv's parameter columns).
    pub fn keys(&self) -> Vec<String> {
        self.parameters.iter().map(|p| p.key.clone()).collect()
    }

    /// The outcome names, in file order (study.csv's outcome columns).
    pub fn outcomes(&self) -> Vec<String> {
        self.outcomes.iter().map(|o| o.name().to_string()).collect()
    }

    /// A hash of the study file's and the base scene's text.
    pub fn fingerprint(&self) -> &str {
        &self.fingerprint
    }

    /// The values of case `case`, as the scene takes them (TOML) and as the table shows them.
    fn values(&self, case: usize) -> Vec<(toml::Value, serde_json::Value)> {
        let dists: Vec<&Distribution> = self.parameters.iter().map(|p| &p.dist).collect();
        let drawn = draw::case_values(&dists, self.draws, self.seed, case);
        self.parameters
            .iter()
            .zip(drawn)
            .map(|(p, d)| match d {
                Drawn::Number(x) if p.integer => {
                    let i = x.round() as i64;
                    (toml::Value::Integer(i), serde_json::Value::from(i))
                }
                Drawn::Number(x) => (toml::Value::Float(x), serde_json::Value::from(x)),
                Drawn::Value(v) => (v.clone(), json_value(&v)),
            })
            .collect()
    }

    /// Case `case` (0-based), self-contained: everything a worker needs to run it, with the
    /// scene as text (the case's values set), not a model.
    pub fn task(&self, case: usize) -> Result<Task, StudyError> {
        if case >= self.len {
            return Err(StudyError::input(format!(
                "{}: case {case} does not exist: the study has cases 0 to {}",
                self.path.display(),
                self.len - 1
            )));
        }
        let values = self.values(case);
        let mut overrides = self.fixed.clone();
        overrides.extend(
            self.parameters
                .iter()
                .zip(&values)
                .map(|(p, (v, _))| (p.key.clone(), v.clone())),
        );
        let scene_text = override_scene_text(&self.scene_text, &overrides)
            .map_err(|e| StudyError::input(format!("{}: case {case}: {e}", self.path.display())))?;
        Ok(Task {
            case,
            keys: self.keys(),
            values: values.into_iter().map(|(_, j)| j).collect(),
            scene_path: self.scene_written.clone(),
            scene_default_name: self.scene_default_name.clone(),
            scene_text,
            outcomes: self.outcomes(),
            settings: self.settings.clone(),
            case_timeout: self.case_timeout,
            fingerprint: self.fingerprint.clone(),
        })
    }

    /// Writes study.csv, study.json and the plots into `out` from these records (any order;
    /// sorted by case), exactly as `dda3d study` does.
    pub fn assemble(&self, out: &Path, records: &[CaseRecord]) -> Result<(), StudyError> {
        table::assemble(self, out, records)
    }

    /// Records already finished in `out` (for resume), empty when none. Err: `out` holds
    /// another study's results, or a record that cannot be read.
    pub fn finished(&self, out: &Path) -> Result<Vec<CaseRecord>, StudyError> {
        table::finished(self, out)
    }

    /// What resuming in `out` starts from: the finished records kept (a failed one only
    /// without `retry_failed`) and the cases still to run, in order. The command and the
    /// Python runners both resume through this.
    pub fn pending(
        &self,
        out: &Path,
        retry_failed: bool,
    ) -> Result<(Vec<CaseRecord>, Vec<usize>), StudyError> {
        let kept: Vec<CaseRecord> = self
            .finished(out)?
            .into_iter()
            .filter(|r| r.is_ok() || !retry_failed)
            .collect();
        let todo = (0..self.len())
            .filter(|k| !kept.iter().any(|r| r.case == *k))
            .collect();
        Ok((kept, todo))
    }
}

/// The output directory of a study file when none is given: `out/<its stem as a slug>`.
pub fn default_out(study_file: &Path) -> PathBuf {
    let stem = study_file.file_stem().unwrap_or_default().to_string_lossy();
    PathBuf::from("out").join(crate::output::slug(&stem))
}

/// A TOML value from a `values` list as the table shows it.
fn json_value(v: &toml::Value) -> serde_json::Value {
    match v {
        toml::Value::Integer(i) => (*i).into(),
        toml::Value::Float(x) => serde_json::Number::from_f64(*x)
            .map_or_else(|| x.to_string().into(), serde_json::Value::Number),
        toml::Value::Boolean(b) => (*b).into(),
        toml::Value::String(s) => s.as_str().into(),
        other => other.to_string().into(),
    }
}
