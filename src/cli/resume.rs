//! `dda3d run --checkpoint-every T` and `dda3d run --resume CHECKPOINT`: the solver's whole
//! state saved as the run goes ([`crate::solver::checkpoint`] has the format), and a run started
//! again from one. A resumed run writes, from the checkpoint's time on, the rows the
//! uninterrupted run wrote, byte for byte.

use std::path::{Path, PathBuf};

use super::SolverOverrides;
use super::exit::Failure;
use crate::output::{OutputError, interval_slot, slug};
use crate::solver::{Solver, checkpoint};
use crate::text::short;

/// The shortest interval: checkpoint names give the time to the microsecond, and two with the
/// same name would overwrite each other.
const SHORTEST: f64 = 1e-6;

/// `--checkpoint-every`, checked before any file is created.
pub(super) fn interval(every: Option<f64>) -> Result<Option<f64>, Failure> {
    match every {
        Some(t) if !(t.is_finite() && t >= SHORTEST) => Err(Failure::Input(format!(
            "--checkpoint-every must be a number of seconds of at least {}, got {}",
            short(SHORTEST),
            short(t)
        ))),
        _ => Ok(every),
    }
}

/// The solver saved in `path`, with `--duration` as its new end time (the total simulated time
/// from t = 0, as a scene's `duration`). A file that is not a checkpoint of this version, or a
/// duration that leaves nothing to run, is bad input.
pub(super) fn resume(path: &Path, o: &SolverOverrides) -> Result<Solver, Failure> {
    let mut solver =
        checkpoint::load(path).map_err(|e| Failure::Input(format!("{}: {e}", path.display())))?;
    if let Some(d) = o.duration {
        if !(d.is_finite() && d > 0.0) {
            return Err(Failure::Input(format!(
                "--duration must be a positive number of seconds, got {}",
                short(d)
            )));
        }
        solver.params.duration = d;
        solver
            .params
            .check()
            .map_err(|e| Failure::Input(format!("--duration: {}", e.message)))?;
    }
    if solver.finished() {
        return Err(Failure::Input(format!(
            "{}: the run ends at t = {} s and the checkpoint is at t = {} s: give a later \
             --duration (the end time, from t = 0)",
            path.display(),
            short(solver.params.duration),
            short(solver.time)
        )));
    }
    Ok(solver)
}

/// Where a resumed run writes by default: beside the run it continues, not over it.
pub(super) fn default_out(solver: &Solver) -> PathBuf {
    PathBuf::from("out").join(format!("{}-resumed", slug(&solver.model.name)))
}

/// Saves the solver at the end of the first step at or after each multiple of the interval.
/// The schedule depends only on the time, so a resumed run saves where the uninterrupted one
/// did, and taking checkpoints never changes a step.
pub(super) struct Checkpoints {
    every: Option<f64>,
    /// The multiple of `every` the next checkpoint waits for.
    next: i64,
}

impl Checkpoints {
    /// The schedule of a run that stands at `time`.
    pub(super) fn new(every: Option<f64>, time: f64) -> Self {
        let next = every.map_or(0, |t| Self::after(time, t));
        Checkpoints { every, next }
    }

    /// The first multiple after `time` (a step that lands a rounding error short of a multiple
    /// counts as on it).
    fn after(time: f64, every: f64) -> i64 {
        interval_slot(time, every) + 1
    }

    /// Called after each step of the run: writes `dir/checkpoint_<t>.ckpt` when one is due.
    pub(super) fn after_step(&mut self, solver: &Solver, dir: &Path) -> Result<(), OutputError> {
        let Some(every) = self.every else {
            return Ok(());
        };
        if interval_slot(solver.time, every) < self.next {
            return Ok(());
        }
        let path = dir.join(checkpoint::file_name(solver.time));
        checkpoint::save(solver, &path).map_err(|e| OutputError {
            path: path.clone(),
            message: format!("cannot write the checkpoint: {e}"),
        })?;
        self.next = Self::after(solver.time, every);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_schedule_counts_from_zero() {
        assert_eq!(Checkpoints::after(0.0, 0.5), 1);
        assert_eq!(Checkpoints::after(0.49, 0.5), 1);
        // A step that ends a rounding error short of 0.5 s is the checkpoint at 0.5 s.
        assert_eq!(Checkpoints::after(0.49999999999999994, 0.5), 2);
        assert_eq!(Checkpoints::after(0.503, 0.5), 2);
        assert_eq!(Checkpoints::after(1.2, 0.5), 3);
    }

    #[test]
    fn intervals_too_short_to_name_are_refused() {
        for t in [0.0, -1.0, 1e-7, f64::NAN, f64::INFINITY] {
            assert!(interval(Some(t)).is_err(), "{t}");
        }
        assert_eq!(interval(Some(0.25)).ok(), Some(Some(0.25)));
        assert_eq!(interval(None).ok(), Some(None));
    }
}
