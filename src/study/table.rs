//! A study's directory: one record file per finished case (`cases/case_<k>.json`, what a resumed
//! study skips), and the tables made of them — `study.csv`, `study.json` — and the plots.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use super::draw::Distribution;
use super::plots::{PlotColumn, write_plots};
use super::{CaseRecord, Study, StudyError};
use crate::output::write_atomically;

/// `DIR/cases`, where the records are.
pub fn cases_dir(out: &Path) -> PathBuf {
    out.join("cases")
}

/// The record file of case `case`.
pub fn record_path(out: &Path, case: usize) -> PathBuf {
    cases_dir(out).join(format!("case_{case}.json"))
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), StudyError> {
    write_atomically(path, bytes)
        .map_err(|e| StudyError::io(format!("{}: cannot write: {e}", path.display())))
}

/// Creates `out` and `out/cases`.
pub fn create_dirs(out: &Path) -> Result<(), StudyError> {
    let dir = cases_dir(out);
    crate::files::create_dir_clearly(&dir).map_err(|e| {
        StudyError::io(format!(
            "{}: cannot create the output directory: {e}",
            dir.display()
        ))
    })
}

/// Writes a finished case's record, atomically: a killed study loses only the cases in flight.
pub fn write_record(out: &Path, record: &CaseRecord) -> Result<(), StudyError> {
    create_dirs(out)?;
    let mut text = record.to_json();
    text.push('\n');
    write(&record_path(out, record.case), text.as_bytes())
}

/// A table cell of a parameter value: numbers as Rust writes them (they read back exactly),
/// strings as they are.
fn cell(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Number(n) => match (n.as_i64(), n.as_f64()) {
            (Some(i), _) => i.to_string(),
            (None, Some(x)) => x.to_string(),
            _ => n.to_string(),
        },
        other => other.to_string(),
    }
}

/// The header of study.csv.
pub fn header(study: &Study) -> Vec<String> {
    let mut h = vec!["case".to_string()];
    h.extend(study.keys());
    h.extend(study.outcomes());
    h.extend(["status", "wall_seconds", "error"].map(String::from));
    h
}

/// One row of study.csv.
pub fn row(record: &CaseRecord) -> Vec<String> {
    let mut r = vec![record.case.to_string()];
    r.extend(record.values.iter().map(cell));
    r.extend(
        record
            .outcomes
            .iter()
            .map(|o| o.map(|x| x.to_string()).unwrap_or_default()),
    );
    r.push(record.status.clone());
    r.push(record.wall_seconds.to_string());
    r.push(record.error.clone().unwrap_or_default());
    r
}

/// study.csv's text: the header and these rows (as they are; sorted by the caller).
pub fn csv_text(header: &[String], rows: &[Vec<String>]) -> Result<Vec<u8>, StudyError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let bad = |e: &dyn std::fmt::Display| StudyError::io(format!("study.csv: {e}"));
    w.write_record(header).map_err(|e| bad(&e))?;
    for r in rows {
        w.write_record(r).map_err(|e| bad(&e))?;
    }
    w.into_inner().map_err(|e| bad(&e))
}

/// The records sorted by case, one per case (the last given wins).
fn sorted(records: &[CaseRecord]) -> Vec<&CaseRecord> {
    let mut r: Vec<&CaseRecord> = records.iter().collect();
    r.sort_by_key(|r| r.case);
    let mut out: Vec<&CaseRecord> = Vec::with_capacity(r.len());
    for rec in r {
        match out.last_mut() {
            Some(last) if last.case == rec.case => *last = rec,
            _ => out.push(rec),
        }
    }
    out
}

/// Writes study.csv and study.json (no plots): what a running study rewrites as cases finish.
pub fn write_tables(study: &Study, out: &Path, records: &[CaseRecord]) -> Result<(), StudyError> {
    create_dirs(out)?;
    let records = sorted(records);
    let rows: Vec<Vec<String>> = records.iter().map(|r| row(r)).collect();
    write(&out.join("study.csv"), &csv_text(&header(study), &rows)?)?;
    let mut text = serde_json::to_vec_pretty(&summary(study, &records))
        .map_err(|e| StudyError::io(format!("study.json: {e}")))?;
    text.push(b'\n');
    write(&out.join("study.json"), &text)
}

/// Writes study.csv, study.json and the plots into `out`.
pub fn assemble(study: &Study, out: &Path, records: &[CaseRecord]) -> Result<(), StudyError> {
    write_tables(study, out, records)?;
    let records = sorted(records);
    let (parameters, outcomes) = plot_columns(study, &records);
    write_plots(out, &parameters, &outcomes)
        .map_err(|e| StudyError::io(format!("{}: plots: {e}", out.display())))?;
    Ok(())
}

/// The columns of the table as the plots take them.
fn plot_columns(study: &Study, records: &[&CaseRecord]) -> (Vec<PlotColumn>, Vec<PlotColumn>) {
    let parameters = study
        .parameters
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let raw: Vec<Option<&Value>> = records.iter().map(|r| r.values.get(k)).collect();
            let numeric = raw.iter().flatten().all(|v| v.is_number());
            let (values, categories) = if numeric {
                (
                    raw.iter().map(|v| v.and_then(Value::as_f64)).collect(),
                    None,
                )
            } else {
                // Labels in the order of the values list.
                let labels: Vec<String> = match &p.dist {
                    Distribution::Values(v) => {
                        v.iter().map(|x| cell(&super::json_value(x))).collect()
                    }
                    _ => Vec::new(),
                };
                let index = |v: &Value| labels.iter().position(|l| *l == cell(v)).map(|i| i as f64);
                (
                    raw.iter().map(|v| v.and_then(index)).collect(),
                    Some(labels),
                )
            };
            PlotColumn {
                name: p.key.clone(),
                values,
                categories,
                log_scale: matches!(p.dist, Distribution::LogUniform { .. }),
                unit: String::new(),
            }
        })
        .collect();
    let outcomes = study
        .outcomes
        .iter()
        .enumerate()
        .map(|(k, o)| PlotColumn {
            name: o.name().to_string(),
            values: records
                .iter()
                .map(|r| r.outcomes.get(k).copied().flatten())
                .collect(),
            categories: None,
            log_scale: false,
            unit: o.unit().to_string(),
        })
        .collect();
    (parameters, outcomes)
}

/// min, median and max of the finite values.
fn statistics(mut x: Vec<f64>) -> Value {
    x.retain(|v| v.is_finite());
    if x.is_empty() {
        return Value::Null;
    }
    x.sort_by(f64::total_cmp);
    let n = x.len();
    let median = if n % 2 == 1 {
        x[n / 2]
    } else {
        0.5 * (x[n / 2 - 1] + x[n / 2])
    };
    json!({ "min": x[0], "median": median, "max": x[n - 1] })
}

/// study.json.
fn summary(study: &Study, records: &[&CaseRecord]) -> Value {
    let ok = records.iter().filter(|r| r.is_ok()).count();
    let parameters: Vec<Value> = study
        .parameters
        .iter()
        .map(|p| json!({ "key": p.key, "distribution": p.dist, "integer": p.integer }))
        .collect();
    let outcomes: Vec<Value> = study
        .outcomes
        .iter()
        .enumerate()
        .map(|(k, o)| {
            let values = records
                .iter()
                .filter_map(|r| r.outcomes.get(k).copied().flatten())
                .collect();
            json!({ "name": o.name(), "unit": o.unit(), "statistics": statistics(values) })
        })
        .collect();
    json!({
        "study": study.path.display().to_string(),
        "scene": study.scene_written,
        "seed": study.seed,
        "cases": study.len,
        "draws_per_grid_point": study.draws,
        "parameters": parameters,
        "outcomes": outcomes,
        "moved_threshold": study.settings.moved_threshold,
        "toppled_angle": study.settings.toppled_angle,
        "watch": study.settings.watch,
        "case_timeout": study.case_timeout,
        "set": study.fixed.iter().cloned().collect::<toml::Table>(),
        "fingerprint": study.fingerprint,
        "finished": records.len(),
        "ok": ok,
        "failed": records.len() - ok,
        "case_wall_seconds": records.iter().map(|r| r.wall_seconds).sum::<f64>(),
        "records": records,
    })
}

fn another_study(study: &Study, out: &Path, what: &str) -> StudyError {
    StudyError::input(format!(
        "{}: {what} of another study (not {}, fingerprint {}): give another --out, or remove it",
        out.display(),
        study.path.display(),
        study.fingerprint
    ))
}

/// The records already in `out`, sorted by case; empty when there are none. Err: `out` holds
/// another study's results, or a record that cannot be read.
pub fn finished(study: &Study, out: &Path) -> Result<Vec<CaseRecord>, StudyError> {
    let json_path = out.join("study.json");
    if json_path.exists() {
        let text = std::fs::read_to_string(&json_path)
            .map_err(|e| StudyError::io(format!("{}: cannot read: {e}", json_path.display())))?;
        let value: Value = serde_json::from_str(&text).unwrap_or(Value::Null);
        if value.get("fingerprint").and_then(Value::as_str) != Some(study.fingerprint.as_str()) {
            return Err(another_study(study, out, "holds the results"));
        }
    }
    let dir = cases_dir(out);
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return Ok(Vec::new());
    };
    let mut records = Vec::new();
    for entry in entries {
        let path = entry
            .map_err(|e| StudyError::io(format!("{}: cannot list: {e}", dir.display())))?
            .path();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        let Some(case) = name.as_deref().and_then(|n| {
            n.strip_prefix("case_")?
                .strip_suffix(".json")?
                .parse::<usize>()
                .ok()
        }) else {
            continue;
        };
        let text = std::fs::read_to_string(&path)
            .map_err(|e| StudyError::io(format!("{}: cannot read: {e}", path.display())))?;
        let record = CaseRecord::from_json(&text)
            .map_err(|e| StudyError::input(format!("{}: {e}", path.display())))?;
        if record.fingerprint != study.fingerprint {
            return Err(another_study(
                study,
                out,
                &format!("{} is a record", path.display()),
            ));
        }
        if record.case != case || case >= study.len {
            return Err(StudyError::input(format!(
                "{}: holds case {} of a study of {} cases",
                path.display(),
                record.case,
                study.len
            )));
        }
        records.push(record);
    }
    records.sort_by_key(|r| r.case);
    Ok(records)
}
