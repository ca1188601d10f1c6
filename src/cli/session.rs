//! A headless run driven from outside the command line, a step or a stretch of simulated time at
//! a time (the Python package's `Simulation`). It takes the steps `dda3d run` takes and, given an
//! output directory, writes the files `dda3d run` writes through the same [`Record`], so
//! blocks.csv and contacts.csv are byte for byte the command's; its failures are the command's
//! one-line [`Failure`]s.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::exit::Failure;
use super::run::{self, End, Record, settle};
use crate::scene::Scene;
use crate::snapshot::Snapshot;
use crate::solver::Solver;

/// A run of one scene, started by its first step and ended by its last step, a divergence, a
/// failed write, or [`RunSession::close`] (also on drop).
pub struct RunSession {
    solver: Solver,
    /// The outputs, when the run writes any.
    rec: Option<Record>,
    /// The file the scene came from (or a stand-in such as `<text>`), for messages.
    source: PathBuf,
    /// The first step has run the start: the equilibrium stage and the first rows.
    started: bool,
    /// How the run ended, once it has (summary.json is final then): `Ok` for its end or a close,
    /// the failure that ended it otherwise, returned again by every later step.
    ended: Option<Result<(), Failure>>,
}

impl RunSession {
    /// A run of `scene` (loaded from `source`), writing blocks.csv, contacts.csv and
    /// summary.json (and the VTK series when the scene's `[output]` asks for it) into `out`,
    /// or nothing when `out` is `None`. The directory is created now: a failure here is an
    /// I/O failure naming it.
    pub fn new(scene: Scene, source: &Path, out: Option<&Path>) -> Result<RunSession, Failure> {
        let solver = Solver::new(scene.model, scene.params);
        let output = scene.output;
        let rec = out
            .map(|dir| Record::create(dir, &solver, &scene.name, scene.rock_masses, output, None))
            .transpose()?;
        Ok(RunSession {
            solver,
            rec,
            source: source.to_path_buf(),
            started: false,
            ended: None,
        })
    }

    pub fn solver(&self) -> &Solver {
        &self.solver
    }

    /// The state now (before the first step: the scene as loaded).
    pub fn snapshot(&self) -> Snapshot {
        self.solver.snapshot()
    }

    /// The run has reached its duration, or ended otherwise: no more steps.
    pub fn finished(&self) -> bool {
        self.ended.is_some() || self.solver.finished()
    }

    /// One step (the first also runs the initial equilibrium stage, if the scene has one, and
    /// writes the rows of the state the run starts from). Returns whether a step was taken:
    /// none once the run is over. A divergence or a failed write ends the run (its summary.json
    /// says so) and is returned, now and by every later call.
    pub fn step(&mut self) -> Result<bool, Failure> {
        if let Some(ended) = &self.ended {
            return ended.clone().map(|()| false);
        }
        if !self.started && !self.start() {
            return self.conclusion().map(|()| true);
        }
        if self.solver.finished() {
            self.end(End::Completed);
            return self.conclusion().map(|()| false);
        }
        if let Err(e) = self.solver.step() {
            self.end(End::Diverged(e));
        } else if let Some(rec) = &mut self.rec
            && let Err(e) = rec.step(&self.solver)
        {
            self.end(End::Io(e));
        } else if self.solver.finished() {
            self.end(End::Completed);
        }
        self.conclusion().map(|()| true)
    }

    /// Steps until the simulated time reaches `until` or the run ends, or until `deadline`
    /// passes (checked after each step), whichever comes first. Steps are never shortened to
    /// land on `until` (they are the command's steps), so the time reached may pass it by part
    /// of a step. Returns whether the run got there (reached `until`, or ended).
    pub fn advance(&mut self, until: f64, deadline: Option<Instant>) -> Result<bool, Failure> {
        // The solver's own "finished" tolerance, so that until = duration runs to the end.
        let tolerance = 1e-9 * self.solver.params.max_time_step;
        while !self.finished() && (!self.started || self.solver.time < until - tolerance) {
            self.step()?;
            if deadline.is_some_and(|d| Instant::now() >= d) {
                return Ok(self.finished() || self.solver.time >= until - tolerance);
            }
        }
        self.conclusion()?;
        Ok(true)
    }

    /// Ends the run now: the rows are committed and summary.json is final, with status
    /// "interrupted" when the run stopped short of its duration. Nothing happens to a run that
    /// has ended already.
    pub fn close(&mut self) -> Result<(), Failure> {
        if self.ended.is_none() {
            let end = if self.solver.finished() {
                End::Completed
            } else {
                End::Stopped(self.solver.time)
            };
            self.end(end);
        }
        self.conclusion()
    }

    /// The start of `dda3d run`; false when the run ended there.
    fn start(&mut self) -> bool {
        self.started = true;
        let quiet = true;
        let end = match &mut self.rec {
            Some(rec) => run::begin(&mut self.solver, rec, &self.source, quiet)
                .unwrap_or_else(|e| Some(End::Io(e))),
            None => match settle(&mut self.solver, &self.source, quiet) {
                Ok(signal) => signal.map(End::Interrupted),
                Err(e) => Some(End::Diverged(e)),
            },
        };
        match end {
            Some(end) => {
                self.end(end);
                false
            }
            None => true,
        }
    }

    /// Records how the run ended: the last rows and summary.json when it writes files, and the
    /// failure `dda3d run` would report.
    fn end(&mut self, end: End) {
        let result = match &mut self.rec {
            Some(rec) => {
                let (end, saved) = rec.close(&self.solver, end);
                run::report(&self.solver, rec, end, saved, (&self.source, true))
            }
            None => match end {
                End::Diverged(e) => {
                    Err(Failure::Diverged(format!("{}: {e}", self.source.display())))
                }
                _ => Ok(()),
            },
        };
        self.ended = Some(result);
    }

    /// How the run ended, `Ok` while it goes on.
    fn conclusion(&self) -> Result<(), Failure> {
        self.ended.clone().unwrap_or(Ok(()))
    }
}

impl Drop for RunSession {
    /// A run dropped before its end still leaves whole files and a final summary.json.
    fn drop(&mut self) {
        let _ = self.close();
    }
}
