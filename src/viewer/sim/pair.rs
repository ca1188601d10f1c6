//! Two simulation threads in lock-step of simulated time, for `view --compare`: run A with the
//! scene's settings, run B with the derived ones.
//!
//! Each thread steps at its own pace (its time steps and cuts are its own, so each run is the
//! run `dda3d run` would give), but never past a shared limit ([`Command::SetLimit`]) that
//! this end hands out: when both have landed exactly on the limit T, the next T is handed to
//! both. The faster side waits for the slower one. The window shows only pairs of frames with
//! the same t ([`SimPair::shown`]), so the two panes and the difference plot never compare two
//! different moments.
//!
//! Play, Pause, Step and Reset drive both: Pause stops handing out limits and pauses both once
//! they stand on the same T; Step hands out one more limit (one time step on) and pauses both
//! there.

use std::sync::Arc;
use std::time::Duration;

use super::{Command, Frame, Origin, RunState, SimHandle, Speed, StepRecord};
use crate::model::Model;
use crate::params::SolverParams;

/// Which run a command or an edit is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    A,
    B,
}

/// Simulated time handed out at a time at `--speed max`: it starts at the first value and
/// adapts between the bounds, growing when both runs had already reached the limit by the
/// next frame (the window held them back) and shrinking when they had not (they hold the
/// window back, and the panes would move in jumps). The lower bound is a time step of the
/// shipped scenes, so that the limits shorten few steps.
const MAX_SPEED_CHUNK: (f64, f64, f64) = (0.02, 0.01, 0.25);
/// The factor by which the chunk at `--speed max` grows or shrinks.
const CHUNK_FACTOR: f64 = 1.25;
/// At a real-time factor f, f × this much simulated time is handed out at a time (about two
/// frames at 60 Hz), but not less than [`REAL_TIME_FLOOR`]; each thread still keeps to the
/// factor by itself.
const REAL_TIME_CHUNK: f64 = 1.0 / 30.0;
/// The least simulated time handed out at a time when paced, s: deep slow motion must not cut
/// every step down to a sliver (the panes then move five times a wall second at 0.01×).
const REAL_TIME_FLOOR: f64 = 0.002;

/// What the pair is doing between limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// Both are held (paused) on the same t.
    Paused,
    /// Handing out a new limit whenever both reach the current one.
    Playing,
    /// Going to the current limit, then pausing (Pause while playing, or Step).
    PauseAtLimit,
}

/// The window's end of a comparison: two [`SimHandle`]s and the shared limit.
pub struct SimPair {
    pub a: SimHandle,
    pub b: SimHandle,
    /// Where both runs start, and Reset takes them back to: t = 0, or a checkpoint's time.
    start: f64,
    /// The limit both were last given.
    target: f64,
    mode: Mode,
    speed: Speed,
    /// The simulated time handed out at a time at `--speed max` (see [`MAX_SPEED_CHUNK`]).
    chunk: f64,
    /// The newest pair of frames with the same simulated time.
    shown: (Arc<Frame>, Arc<Frame>),
}

impl SimPair {
    /// Starts both threads (paused, limited to their start: t = 0, or the time of the
    /// checkpoint `origin` both start from), then plays both if `play`.
    pub fn spawn(
        model: Model,
        (params_a, params_b): (SolverParams, SolverParams),
        origin: Option<Origin>,
        speed: Speed,
        play: bool,
        waker: impl Fn() + Send + Clone + 'static,
    ) -> std::io::Result<SimPair> {
        let spawn = |p: SolverParams| {
            let w = Box::new(waker.clone());
            SimHandle::spawn(model.clone(), p, origin.clone(), speed, false, w)
        };
        let (mut a, mut b) = (spawn(params_a)?, spawn(params_b)?);
        let first = |h: &SimHandle| h.latest().expect("the first frame is published at spawn");
        let shown = (first(&a), first(&b));
        let start = shown.0.snapshot.time;
        a.send(Command::SetLimit(Some(start)));
        b.send(Command::SetLimit(Some(start)));
        let mut pair = SimPair {
            a,
            b,
            start,
            target: start,
            mode: Mode::Paused,
            speed,
            chunk: MAX_SPEED_CHUNK.0,
            shown,
        };
        if play {
            pair.command(Command::Play);
        }
        Ok(pair)
    }

    /// The handle of one side.
    pub fn side(&mut self, side: Side) -> &mut SimHandle {
        match side {
            Side::A => &mut self.a,
            Side::B => &mut self.b,
        }
    }

    /// A command for both runs. Play, Pause, Step and Reset go through the lock-step; the
    /// others (speed, parameters, states) go to both threads as they are.
    pub fn command(&mut self, cmd: Command) {
        match cmd {
            Command::Play => {
                self.mode = Mode::Playing;
                self.both(Command::Play);
                self.hand_out();
            }
            Command::Pause => {
                if self.mode == Mode::Playing {
                    self.mode = Mode::PauseAtLimit;
                }
            }
            Command::Step => {
                if self.mode == Mode::Paused {
                    let dt = self.shown.0.params.max_time_step;
                    self.mode = Mode::PauseAtLimit;
                    self.target = self.shown.0.snapshot.time + dt;
                    self.both(Command::SetLimit(Some(self.target)));
                    self.both(Command::Play);
                }
            }
            Command::Reset => {
                self.mode = Mode::Paused;
                self.target = self.start;
                self.both(Command::Pause);
                self.both(Command::SetLimit(Some(self.start)));
                self.both(Command::Reset);
            }
            Command::SetSpeed(s) => {
                self.speed = s;
                self.both(Command::SetSpeed(s));
            }
            other => self.both(other),
        }
    }

    fn both(&mut self, cmd: Command) {
        self.a.send(cmd.clone());
        self.b.send(cmd);
    }

    /// Whether a side's frame stands on the current limit, having taken every command sent.
    fn on_target(&self, h: &SimHandle, f: &Frame) -> bool {
        f.applied >= h.last_sent() && f.snapshot.time.to_bits() == self.target.to_bits()
    }

    /// Hands out the next limit.
    fn hand_out(&mut self) {
        let chunk = match self.speed {
            Speed::Max => self.chunk,
            Speed::RealTime(f) => (f * REAL_TIME_CHUNK).max(REAL_TIME_FLOOR),
        };
        self.target += chunk;
        self.both(Command::SetLimit(Some(self.target)));
    }

    /// Call once a frame: takes the newest frames, keeps the newest pair with the same t, and
    /// moves the limit on when both stand on it. Returns the pair to show.
    pub fn tick(&mut self) -> (Arc<Frame>, Arc<Frame>) {
        let (Some(fa), Some(fb)) = (self.a.latest(), self.b.latest()) else {
            return self.shown.clone();
        };
        if fa.snapshot.time.to_bits() == fb.snapshot.time.to_bits() {
            self.shown = (fa.clone(), fb.clone());
        } else if fa.generation == self.shown.0.generation
            && fb.generation == self.shown.1.generation
        {
            // Between two common times: the pictures stay at the last one, but the run state
            // and messages are the newest (an error must not wait for a common time).
            self.shown = (
                Arc::new(with_status(&self.shown.0, &fa)),
                Arc::new(with_status(&self.shown.1, &fb)),
            );
        }
        let reached = self.on_target(&self.a, &fa) && self.on_target(&self.b, &fb);
        // Only a frame that has taken every command counts: a Play past the end time has not
        // yet moved the end of a frame still saying Finished.
        let stopped = |h: &SimHandle, f: &Frame| {
            f.applied >= h.last_sent() && matches!(f.state, RunState::Failed | RunState::Finished)
        };
        let stopped = stopped(&self.a, &fa) || stopped(&self.b, &fb);
        match self.mode {
            Mode::Playing if stopped => {
                // One run ended (its end time, or a solver error): the other waits with it.
                self.mode = Mode::PauseAtLimit;
            }
            Mode::Playing if reached => {
                self.chunk = (self.chunk * CHUNK_FACTOR).min(MAX_SPEED_CHUNK.2);
                self.hand_out();
            }
            Mode::Playing => {
                self.chunk = (self.chunk / CHUNK_FACTOR).max(MAX_SPEED_CHUNK.1);
            }
            Mode::PauseAtLimit if reached || stopped => {
                self.mode = Mode::Paused;
                self.both(Command::Pause);
            }
            _ => {}
        }
        self.shown.clone()
    }

    /// Whether the pair is playing (the toolbar's Play/Pause).
    pub fn playing(&self) -> bool {
        self.mode == Mode::Playing
    }

    /// Moves both sides' step records into `a` and `b`.
    pub fn drain_records(&self, a: &mut Vec<StepRecord>, b: &mut Vec<StepRecord>) {
        self.a.drain_records(a);
        self.b.drain_records(b);
    }

    /// Ticks until `pred` holds for the shown pair, or `timeout` passes (tests, headless).
    pub fn wait_for(
        &mut self,
        timeout: Duration,
        mut pred: impl FnMut(&Frame, &Frame) -> bool,
    ) -> Option<(Arc<Frame>, Arc<Frame>)> {
        let end = std::time::Instant::now() + timeout;
        loop {
            let (a, b) = self.tick();
            if pred(&a, &b) {
                return Some((a, b));
            }
            if std::time::Instant::now() >= end {
                return None;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

#[cfg(test)]
#[path = "pair_tests.rs"]
mod tests;

/// `shown` with the run state, error and rates of `newest`.
fn with_status(shown: &Frame, newest: &Frame) -> Frame {
    Frame {
        state: newest.state.clone(),
        error: newest.error.clone(),
        notice: newest.notice.clone(),
        applied: newest.applied,
        params: newest.params.clone(),
        speed: newest.speed,
        steps_per_second: newest.steps_per_second,
        seconds_per_step: newest.seconds_per_step,
        running_seconds: newest.running_seconds,
        ..shown.clone()
    }
}
