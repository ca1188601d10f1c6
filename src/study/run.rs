//! One case: its scene parsed from the task's text, run to the scene's duration, and its
//! outcomes measured. A case never fails the study: every failure, a panic included, is a
//! record with status "failed" and a one-line error.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

use super::outcomes::{Outcome, Tracker};
use super::{CaseRecord, Task};
use crate::solver::Solver;
use crate::text::one_line;
use crate::text::short;

/// Why a case did not finish.
enum Stop {
    /// The caller asked it to stop (a signal): the case is abandoned, not recorded.
    Asked,
    Failed(String),
}

/// Runs one case; never panics (a panic inside is caught and recorded), never returns Err: a
/// failing case is a record with status "failed" and its one-line error.
pub fn run_task(task: &Task) -> CaseRecord {
    run_task_until(task, &|| false).unwrap_or_else(|| failed(task, "stopped".into(), 0.0))
}

/// [`run_task`], checking `stop` between steps: `None` when it asked the case to stop.
pub fn run_task_until(task: &Task, stop: &dyn Fn() -> bool) -> Option<CaseRecord> {
    let start = Instant::now();
    let result = catch_unwind(AssertUnwindSafe(|| simulate(task, stop, start)));
    let wall = start.elapsed().as_secs_f64();
    match result {
        Ok(Ok(outcomes)) => Some(CaseRecord {
            case: task.case,
            values: task.values.clone(),
            outcomes: outcomes.into_iter().map(Some).collect(),
            status: "ok".into(),
            error: None,
            wall_seconds: wall,
            fingerprint: task.fingerprint.clone(),
        }),
        Ok(Err(Stop::Asked)) => None,
        Ok(Err(Stop::Failed(e))) => Some(failed(task, e, wall)),
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "no message".into());
            Some(failed(task, format!("panic: {what}"), wall))
        }
    }
}

fn failed(task: &Task, error: String, wall: f64) -> CaseRecord {
    CaseRecord {
        case: task.case,
        values: task.values.clone(),
        outcomes: vec![None; task.outcomes.len()],
        status: "failed".into(),
        error: Some(one_line(&error)),
        wall_seconds: wall,
        fingerprint: task.fingerprint.clone(),
    }
}

/// The case's run: the outcomes in the task's order.
fn simulate(task: &Task, stop: &dyn Fn() -> bool, start: Instant) -> Result<Vec<f64>, Stop> {
    let outcomes = task
        .outcomes
        .iter()
        .map(|n| {
            Outcome::from_name(n).ok_or_else(|| Stop::Failed(format!("unknown outcome \"{n}\"")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let shown = format!("{} (case {})", task.scene_path, task.case);
    let scene = crate::scene::parse(&task.scene_text, &shown, &task.scene_default_name)
        .map_err(|e| Stop::Failed(e.to_string()))?;
    let mut solver = Solver::new(scene.model, scene.params);
    // Checked between steps: the case's wall time, and the caller's stop.
    let check = |solver: &Solver| -> Result<(), Stop> {
        if stop() {
            return Err(Stop::Asked);
        }
        match task.case_timeout {
            Some(limit) if start.elapsed().as_secs_f64() > limit => Err(Stop::Failed(format!(
                "case_timeout of {} s exceeded at t = {} s",
                short(limit),
                short(solver.time)
            ))),
            _ => Ok(()),
        }
    };
    let diverged = |e: crate::solver::SolverError| Stop::Failed(format!("{shown}: {e}"));
    while solver.in_equilibrium_stage() {
        check(&solver)?;
        solver.step().map_err(diverged)?;
    }
    let mut tracker = Tracker::start(&solver, &task.settings);
    while !solver.finished() {
        check(&solver)?;
        solver.step().map_err(diverged)?;
        tracker.after_step(&solver);
    }
    Ok(outcomes
        .into_iter()
        .map(|o| tracker.value(o, &solver, &task.settings))
        .collect())
}
