//! The protocol between the window and the simulation thread: the commands the window sends,
//! the frames and per-step records the thread publishes, and the run's state and speed.

use std::path::PathBuf;
use std::sync::Arc;

use crate::params::SolverParams;
use crate::snapshot::RunTotals;
use crate::snapshot::Snapshot;

/// How fast simulated time advances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Speed {
    /// Step back to back, as fast as the solver goes.
    Max,
    /// Simulated seconds per wall-clock second (1 = real time). The solver sleeps when it is
    /// ahead, so a rockfall that computes in 0.1 s can still be watched.
    RealTime(f64),
}

impl Default for Speed {
    fn default() -> Self {
        Speed::RealTime(1.0)
    }
}

/// What the window can ask of the simulation thread. All take effect before the next step.
#[derive(Clone, Debug)]
pub enum Command {
    Play,
    Pause,
    /// One step, then pause.
    Step,
    /// Back to t = 0 with the current parameters (the run's end time goes back to the scene's).
    Reset,
    /// Replace all solver parameters (method, mode, contact law, joint, time step, end time).
    /// Rejected with a message when [`SolverParams::validate`] fails.
    SetParams(Box<SolverParams>),
    SetSpeed(Speed),
    /// Never step past this simulated time (None: no limit). A running thread that reaches it
    /// lands exactly on it (its last step is shortened) and holds there, still Running, until
    /// the limit moves: how the two runs of a comparison keep in lock-step of simulated time.
    SetLimit(Option<f64>),
    /// Save the solver's state as `DIR/checkpoint_<t>.ckpt` (the format of `run
    /// --checkpoint-every`).
    SaveState(PathBuf),
    /// Replace the run with the state in this checkpoint file (of the same scene), paused.
    LoadState(PathBuf),
    /// Stop the thread.
    Quit,
}

/// Where the run stands.
#[derive(Clone, Debug, PartialEq)]
pub enum RunState {
    Paused,
    Running,
    /// Reached the end time; Play continues past it.
    Finished,
    /// The solver failed (message in [`Frame::error`]); Reset starts over, Play retries.
    Failed,
}

/// One published picture of the run.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Publication counter (increases by one per frame).
    pub seq: u64,
    /// Number of commands applied before this frame was published: a frame reflects command
    /// `id` (as returned by [`SimHandle::send`](super::SimHandle::send)) when `applied >= id`.
    pub applied: u64,
    /// Increases on every reset, so the window can clear plots of the previous run.
    pub generation: u64,
    pub snapshot: Arc<Snapshot>,
    /// The parameters the solver holds now: those the next step will use (and, unless a
    /// command arrived in between, those the snapshot's last step used).
    pub params: SolverParams,
    pub state: RunState,
    pub speed: Speed,
    /// The last solver error, or a rejected command, as one line.
    pub error: Option<String>,
    /// The outcome of the last Save state or Load state that succeeded, with the id of its
    /// command (so the window shows it once).
    pub notice: Option<(u64, String)>,
    /// Solver steps per wall-clock second while running (over the last ~0.5 s; 0 when idle).
    pub steps_per_second: f64,
    /// Mean wall time of one step, s (over the same window).
    pub seconds_per_step: f64,
    /// Wall-clock time spent running (playing or stepping) since the start, s: with
    /// `steps_run` it gives the solver's average speed.
    pub running_seconds: f64,
    /// Steps this window ran since the run started, was reset or loaded (the steps in
    /// `totals` include those of the checkpoint it started from): with `running_seconds`, the
    /// solver's average speed.
    pub steps_run: u64,
    pub totals: RunTotals,
    /// d_n,max = 2 δ w0 of (P22), m: the penetration scale ε1 is measured against.
    pub max_step_penetration: f64,
}

/// Per-step numbers for the live plots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepRecord {
    pub generation: u64,
    pub step: u64,
    pub time: f64,
    pub time_step: f64,
    pub max_penetration: f64,
    pub lock: u32,
    pub slide: u32,
    pub open: u32,
    pub alm_iterations: u32,
    pub open_close_iterations: u32,
    pub cuts: u32,
    pub kinetic_energy: f64,
    /// Smallest, mean and largest normal penalty p_n over the closed contacts, N/m (NaN without
    /// contacts).
    pub penalty_min: f64,
    pub penalty_mean: f64,
    pub penalty_max: f64,
    /// A static step of the initial equilibrium stage: its number in the stage and R_max after
    /// it (`None` for the run's own steps, and for the stage's last, which ends it).
    pub stage: Option<(u64, f64)>,
}
