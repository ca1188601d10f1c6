//! The natives of `dda3d.study`: a study file loaded ([`Study`]), each case's self-contained
//! task as JSON (what Ray or Dask ship to a worker: the scene text with the case's overrides
//! and the outcome settings, not a model), a task run on a worker, and the records assembled
//! into study.csv, study.json and the plots exactly as `dda3d study` writes them.

use std::path::PathBuf;

use dda3d::study::{CaseRecord, Study, Task, run_task};
use pyo3::prelude::*;

use crate::errors::{Kind, error};

fn study_error(e: impl std::fmt::Display) -> PyErr {
    error(Kind::Study, e.to_string())
}

/// A loaded, validated study file (`dda3d.study.load`).
#[pyclass(name = "Study", module = "dda3d._native", frozen)]
pub struct PyStudy {
    study: Study,
    path: PathBuf,
}

#[pymethods]
impl PyStudy {
    /// The study file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// The number of cases.
    fn __len__(&self) -> usize {
        self.study.len()
    }

    /// The varied keys, in file order (study.csv's parameter columns).
    fn keys(&self) -> Vec<String> {
        self.study.keys()
    }

    /// The outcome names, in file order (study.csv's outcome columns).
    fn outcomes(&self) -> Vec<String> {
        self.study.outcomes()
    }

    /// Case `case` (0-based) as the JSON a worker needs to run it (`run_task_json`).
    fn task_json(&self, case: usize) -> PyResult<String> {
        self.study
            .task(case)
            .map(|t| t.to_json())
            .map_err(study_error)
    }

    /// The records (JSON texts of `run_task_json`, any order) written into `out` as study.csv,
    /// study.json and the plots, as `dda3d study` writes them.
    fn assemble(&self, py: Python<'_>, out: PathBuf, records: Vec<String>) -> PyResult<()> {
        let records = records
            .iter()
            .map(|r| CaseRecord::from_json(r))
            .collect::<Result<Vec<_>, _>>()
            .map_err(study_error)?;
        py.detach(|| self.study.assemble(&out, &records))
            .map_err(study_error)
    }

    /// Writes a finished case's record (its JSON) into `out/cases/` as `dda3d study` does as
    /// each case finishes, atomically: what a resumed study skips.
    fn save_record(&self, out: PathBuf, record: &str) -> PyResult<()> {
        let record = CaseRecord::from_json(record).map_err(study_error)?;
        dda3d::study::table::write_record(&out, &record).map_err(study_error)
    }

    /// The records already finished in `out` (for resuming), as JSON texts; empty when none.
    fn finished_json(&self, out: PathBuf) -> PyResult<Vec<String>> {
        let done = self.study.finished(&out).map_err(study_error)?;
        Ok(done.iter().map(CaseRecord::to_json).collect())
    }

    /// What resuming in `out` starts from, as `dda3d study` resumes: the finished records kept
    /// (JSON texts; a failed one only without `retry_failed`) and the cases still to run.
    fn pending_json(
        &self,
        out: PathBuf,
        retry_failed: bool,
    ) -> PyResult<(Vec<String>, Vec<usize>)> {
        let (kept, todo) = self
            .study
            .pending(&out, retry_failed)
            .map_err(study_error)?;
        Ok((kept.iter().map(CaseRecord::to_json).collect(), todo))
    }

    fn __repr__(&self) -> String {
        format!(
            "Study({}, {} cases, keys {:?}, outcomes {:?})",
            self.path.display(),
            self.study.len(),
            self.study.keys(),
            self.study.outcomes()
        )
    }
}

/// Loads and checks the study file at `path` (its base scene read, every key checked).
#[pyfunction]
fn load_study(py: Python<'_>, path: PathBuf) -> PyResult<PyStudy> {
    let study = py.detach(|| Study::load(&path)).map_err(study_error)?;
    Ok(PyStudy { study, path })
}

/// Runs one case from its task JSON and returns its record as JSON. A failing case is a
/// record with status "failed" and its one-line error, not an exception; only a task that is
/// not one raises `StudyError`. The GIL is released while it runs.
#[pyfunction]
fn run_task_json(py: Python<'_>, task: &str) -> PyResult<String> {
    let task = Task::from_json(task).map_err(study_error)?;
    Ok(py.detach(|| run_task(&task).to_json()))
}

/// The output directory of a study file when none is given, as `dda3d study` takes it:
/// out/<the file's stem as a slug>.
#[pyfunction]
fn default_study_out(path: PathBuf) -> PathBuf {
    dda3d::study::default_out(&path)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(default_study_out, m)?)?;
    m.add_class::<PyStudy>()?;
    m.add_function(wrap_pyfunction!(load_study, m)?)?;
    m.add_function(wrap_pyfunction!(run_task_json, m)?)?;
    Ok(())
}
