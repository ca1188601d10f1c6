//! The simulation thread: applies the window's commands, steps the solver (paced to the
//! real-time factor, or back to back), and publishes frames and step records to the mailbox.

use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::{Command, Frame, Mailbox, Origin, RunState, Speed, StepRecord, lock, states};
use crate::model::Model;
use crate::params::SolverParams;
use crate::snapshot::ContactState;
use crate::solver::{Solver, checkpoint};

/// Prefix of the message for a SetParams that failed validation.
const REJECTED: &str = "parameters not applied";

/// Records kept in the mailbox when the window does not drain them (minimised for hours).
const MAILBOX_RECORD_CAP: usize = 200_000;
/// Publications while running are at most this often: enough for any display, and cheap
/// even for large models whose snapshots take a while to copy.
const PUBLISH_INTERVAL: Duration = Duration::from_micros(8_333);
/// Relative distance from a step limit that counts as on it (rounding of `t + (limit - t)`).
const LIMIT_SNAP: f64 = 1e-12;
/// Window over which steps per second are measured.
const RATE_WINDOW: Duration = Duration::from_millis(500);

/// What a simulation thread runs: the scene's `model` with `params` (`params.duration` is the
/// end time), from t = 0 or from the checkpoint `origin` (of `model`'s blocks, `params` its
/// settings), which Reset goes back to.
pub(super) struct Start {
    pub model: Model,
    pub params: SolverParams,
    pub origin: Option<Origin>,
}

impl Start {
    /// The solver a run starts with, and starts over with on Reset, with `params` (the
    /// panel's): the model at t = 0, or the checkpoint decoded and given them as a change in
    /// the panel is ([`Solver::set_params`]). A checkpoint that does not decode is an error
    /// (checked when the thread starts, so Reset never meets one).
    fn solver(&self, params: SolverParams) -> Result<Solver, String> {
        let Some(bytes) = self.origin.as_deref() else {
            return Ok(Solver::new(self.model.clone(), params));
        };
        let mut solver = checkpoint::decode(bytes).map_err(|e| e.to_string())?;
        solver.set_params(params);
        Ok(solver)
    }
}

/// Starts the thread on `start`; the first frame is in the mailbox when this returns. A
/// checkpoint that does not decode is an error of kind `InvalidData`.
pub(super) fn start(
    start: Start,
    (speed, play): (Speed, bool),
    mailbox: Arc<Mutex<Mailbox>>,
    waker: Box<dyn Fn() + Send>,
    rx: Receiver<(u64, Command)>,
) -> std::io::Result<JoinHandle<()>> {
    let solver = start
        .solver(start.params.clone())
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))?;
    let mut sim = Sim::new(start, solver, speed, mailbox, waker);
    if play {
        sim.play();
    }
    sim.publish();
    std::thread::Builder::new()
        .name("dda3d-sim".into())
        // The same priority as the window's: the solver is what the user came for. (It ran at
        // nice +10 until issue #15, so that the window never waited; on two cores with llvmpipe
        // that left the struck wall of 1000 blocks a median 54 % of its headless speed, and 65 %
        // at the same priority, with the window still at 39 frames/s: README, issue #15.)
        .spawn(move || sim.run(rx))
}

/// The thread's state.
struct Sim {
    /// What the run started from, and Reset goes back to.
    start: Start,
    /// The scene's end time, restored on reset and used as the increment past the end.
    scene_duration: f64,
    solver: Solver,
    state: RunState,
    speed: Speed,
    error: Option<String>,
    /// See [`Frame::notice`].
    notice: Option<(u64, String)>,
    /// A single step was requested while paused.
    step_once: bool,
    /// See [`Command::SetLimit`].
    limit: Option<f64>,
    applied: u64,
    generation: u64,
    seq: u64,
    mailbox: Arc<Mutex<Mailbox>>,
    waker: Box<dyn Fn() + Send>,
    records: Vec<StepRecord>,
    last_publish: Instant,
    /// Something other than a step changed since the last publication.
    dirty: bool,
    /// Real-time pacing: simulated time `anchor_sim` at wall time `anchor_wall`.
    anchor_wall: Instant,
    anchor_sim: f64,
    /// Steps and stepping time since `rate_start`, for steps per second.
    rate_start: Instant,
    rate_steps: u64,
    rate_busy: Duration,
    steps_per_second: f64,
    seconds_per_step: f64,
    /// Wall time in the Running state, before the current stretch.
    running_before: Duration,
    /// Start of the current Running stretch.
    running_since: Option<Instant>,
    /// The solver's step count when this run started, was reset or loaded: a checkpoint's
    /// steps are not this window's.
    steps_before: u64,
}

impl Sim {
    fn new(
        start: Start,
        solver: Solver,
        speed: Speed,
        mailbox: Arc<Mutex<Mailbox>>,
        waker: Box<dyn Fn() + Send>,
    ) -> Sim {
        let now = Instant::now();
        Sim {
            scene_duration: start.params.duration,
            start,
            state: RunState::Paused,
            speed,
            error: None,
            notice: None,
            step_once: false,
            limit: None,
            applied: 0,
            generation: 0,
            seq: 0,
            mailbox,
            waker,
            records: Vec::new(),
            last_publish: now,
            dirty: true,
            anchor_wall: now,
            anchor_sim: 0.0,
            rate_start: now,
            rate_steps: 0,
            rate_busy: Duration::ZERO,
            steps_per_second: 0.0,
            seconds_per_step: 0.0,
            running_before: Duration::ZERO,
            running_since: None,
            steps_before: solver.totals.steps,
            solver,
        }
    }

    fn run(mut self, rx: Receiver<(u64, Command)>) {
        loop {
            // Everything queued applies before the next step.
            loop {
                match rx.try_recv() {
                    Ok(m) => {
                        if !self.apply(m) {
                            return;
                        }
                    }
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => return,
                }
            }
            if self.wants_step() {
                if let Some(wait) = self.pace_wait() {
                    // Ahead of the wall clock: sleep, but wake for any command.
                    if self.dirty {
                        self.publish();
                    }
                    match rx.recv_timeout(wait) {
                        Ok(m) => {
                            if !self.apply(m) {
                                return;
                            }
                        }
                        Err(RecvTimeoutError::Timeout) => {}
                        Err(RecvTimeoutError::Disconnected) => return,
                    }
                    continue;
                }
                self.do_step();
                if self.dirty || self.last_publish.elapsed() >= PUBLISH_INTERVAL {
                    self.publish();
                }
            } else {
                if self.dirty || !self.records.is_empty() {
                    self.publish();
                }
                match rx.recv() {
                    Ok(m) => {
                        if !self.apply(m) {
                            return;
                        }
                    }
                    Err(_) => return,
                }
            }
        }
    }

    fn wants_step(&self) -> bool {
        (self.state == RunState::Running || self.step_once)
            && !self.solver.finished()
            && self.limit.is_none_or(|t| self.solver.time < t)
    }

    /// How long to sleep before the next step to keep to the real-time factor (None: step now).
    fn pace_wait(&mut self) -> Option<Duration> {
        let Speed::RealTime(factor) = self.speed else {
            return None;
        };
        if self.step_once || !(factor.is_finite() && factor > 0.0) {
            return None;
        }
        let now = Instant::now();
        let target = self.anchor_sim + factor * (now - self.anchor_wall).as_secs_f64();
        let lead = self.solver.time - target;
        if lead > 0.0 {
            // Sleep in slices so the step rate readout decays while waiting.
            return Some(Duration::from_secs_f64((lead / factor).min(0.05)));
        }
        if -lead > 0.25 * factor {
            // The solver cannot keep up: do not build a backlog it would race through later.
            self.anchor_wall = now;
            self.anchor_sim = self.solver.time;
        }
        None
    }

    /// Replaces the run (a reset, or a loaded state): new plots, no error, not stepping.
    fn start_over(&mut self, solver: Solver) {
        self.running_before = Duration::ZERO;
        self.running_since = None;
        self.steps_before = solver.totals.steps;
        self.solver = solver;
        self.generation += 1;
        self.records.clear();
        self.error = None;
        if self.state != RunState::Running || self.solver.finished() {
            self.state = RunState::Paused;
        }
        self.step_once = false;
        self.re_anchor();
        self.reset_rate();
    }

    fn re_anchor(&mut self) {
        self.anchor_wall = Instant::now();
        self.anchor_sim = self.solver.time;
    }

    fn play(&mut self) {
        if self.solver.finished() {
            // Continue past the end: another scene duration.
            self.solver.params.duration = self.solver.time + self.scene_duration;
        }
        self.state = RunState::Running;
        self.re_anchor();
        self.reset_rate();
    }

    /// Applies one command; false means quit.
    fn apply(&mut self, (id, cmd): (u64, Command)) -> bool {
        self.applied = self.applied.max(id);
        self.dirty = true;
        match cmd {
            Command::Quit => return false,
            Command::Play => {
                self.error = None;
                self.play();
            }
            Command::Pause => {
                if self.state == RunState::Running {
                    self.state = RunState::Paused;
                }
                self.steps_per_second = 0.0;
            }
            Command::Step => {
                self.error = None;
                if self.solver.finished() {
                    self.solver.params.duration = self.solver.time + self.scene_duration;
                }
                self.state = RunState::Paused;
                self.step_once = true;
            }
            Command::Reset => {
                let mut params = self.solver.params.clone();
                params.duration = self.scene_duration;
                let solver = self.start.solver(params);
                self.start_over(solver.expect("the checkpoint decoded when the thread started"));
            }
            // Δt_max also against the heaviest block, as the scene file and the flags are.
            Command::SetParams(p) => match p
                .validate()
                .and_then(|()| crate::scene::check_inertia_scale(&self.solver.model.blocks, &p))
            {
                Ok(()) => {
                    self.solver.set_params(*p);
                    // The end time may have moved past or before the current time.
                    match (&self.state, self.solver.finished()) {
                        (RunState::Finished, false) => self.state = RunState::Paused,
                        (RunState::Running, true) => self.state = RunState::Finished,
                        _ => {}
                    }
                    // A solver error stays up (it explains the failed state) until the run
                    // is retried or reset; only a previous rejection is cleared.
                    if self
                        .error
                        .as_deref()
                        .is_some_and(|e| e.starts_with(REJECTED))
                    {
                        self.error = None;
                    }
                }
                Err(m) => self.error = Some(format!("{REJECTED}: {m}")),
            },
            Command::SetLimit(t) => self.limit = t,
            Command::SetSpeed(s) => {
                self.speed = s;
                self.re_anchor();
            }
            Command::SaveState(dir) => match states::save(&self.solver, &dir) {
                Ok(m) => self.notice = Some((id, m)),
                Err(m) => self.error = Some(m),
            },
            Command::LoadState(path) => match states::load(&path, &self.start.model) {
                Ok(solver) => {
                    self.start_over(solver);
                    self.state = RunState::Paused;
                    self.notice = Some((id, format!("state loaded from {}", path.display())));
                }
                Err(m) => self.error = Some(m),
            },
        }
        true
    }

    fn reset_rate(&mut self) {
        self.rate_start = Instant::now();
        self.rate_steps = 0;
        self.rate_busy = Duration::ZERO;
    }

    fn do_step(&mut self) {
        self.step_once = false;
        let t0 = Instant::now();
        let result = match self.limit {
            Some(limit) => self.solver.step_until(limit).cloned(),
            None => self.solver.step().cloned(),
        };
        if let Some(limit) = self.limit
            && (self.solver.time - limit).abs() <= LIMIT_SNAP * limit.abs().max(1.0)
        {
            // A step shortened to end on the limit lands within rounding of it; both sides of
            // a comparison must show the very same t, so the last bits are made equal.
            self.solver.time = limit;
            // Publish at once: the window hands out the next limit when both sides are here.
            self.dirty = true;
        }
        let busy = t0.elapsed();
        match result {
            Ok(stats) => {
                let (mut pmin, mut pmax, mut psum, mut n) =
                    (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
                for c in self.solver.contacts() {
                    if c.state != ContactState::Open && c.penalty.is_finite() {
                        pmin = pmin.min(c.penalty);
                        pmax = pmax.max(c.penalty);
                        psum += c.penalty;
                        n += 1;
                    }
                }
                let (pmin, pmean, pmax) = if n == 0 {
                    (f64::NAN, f64::NAN, f64::NAN)
                } else {
                    (pmin, psum / n as f64, pmax)
                };
                self.records.push(StepRecord {
                    generation: self.generation,
                    step: self.solver.step,
                    time: self.solver.time,
                    time_step: stats.time_step,
                    max_penetration: stats.max_penetration,
                    lock: stats.contacts_lock,
                    slide: stats.contacts_slide,
                    open: stats.contacts_open,
                    alm_iterations: stats.alm_iterations,
                    open_close_iterations: stats.open_close_iterations,
                    cuts: stats.time_step_cuts,
                    kinetic_energy: stats.kinetic_energy,
                    penalty_min: pmin,
                    penalty_mean: pmean,
                    penalty_max: pmax,
                    stage: self
                        .solver
                        .equilibrium()
                        .filter(|r| r.running)
                        .map(|r| (r.steps, r.residual)),
                });
                self.rate_steps += 1;
                self.rate_busy += busy;
                let span = self.rate_start.elapsed();
                if span >= RATE_WINDOW {
                    self.steps_per_second = self.rate_steps as f64 / span.as_secs_f64();
                    self.seconds_per_step = self.rate_busy.as_secs_f64() / self.rate_steps as f64;
                    self.reset_rate();
                } else if self.steps_per_second == 0.0 && self.rate_steps > 0 {
                    // First readout before a full window has passed.
                    self.seconds_per_step = self.rate_busy.as_secs_f64() / self.rate_steps as f64;
                }
                if self.solver.finished() {
                    self.state = RunState::Finished;
                    self.dirty = true;
                }
            }
            Err(e) => {
                self.error = Some(e.to_string());
                self.state = RunState::Failed;
                self.dirty = true;
            }
        }
    }

    fn publish(&mut self) {
        match (self.state == RunState::Running, self.running_since) {
            (true, None) => self.running_since = Some(Instant::now()),
            (false, Some(t)) => {
                self.running_before += t.elapsed();
                self.running_since = None;
            }
            _ => {}
        }
        self.seq += 1;
        let idle = !matches!(self.state, RunState::Running);
        let frame = Frame {
            seq: self.seq,
            applied: self.applied,
            generation: self.generation,
            snapshot: Arc::new(self.solver.snapshot()),
            params: self.solver.params.clone(),
            state: self.state.clone(),
            speed: self.speed,
            error: self.error.clone(),
            notice: self.notice.clone(),
            steps_per_second: if idle { 0.0 } else { self.steps_per_second },
            seconds_per_step: self.seconds_per_step,
            running_seconds: (self.running_before
                + self.running_since.map_or(Duration::ZERO, |t| t.elapsed()))
            .as_secs_f64(),
            steps_run: self.solver.totals.steps.saturating_sub(self.steps_before),
            totals: self.solver.totals.clone(),
            max_step_penetration: self.solver.max_step_penetration(),
        };
        let wake = {
            let mut m = lock(&self.mailbox);
            m.latest = Some(Arc::new(frame));
            if self.generation
                != m.records
                    .last()
                    .map(|r| r.generation)
                    .unwrap_or(self.generation)
            {
                m.records.clear();
            }
            m.records.append(&mut self.records);
            if m.records.len() > MAILBOX_RECORD_CAP {
                let excess = m.records.len() - MAILBOX_RECORD_CAP;
                m.records.drain(..excess);
            }
            let wake = !m.unread;
            m.unread = true;
            wake
        };
        self.last_publish = Instant::now();
        self.dirty = false;
        if wake {
            (self.waker)();
        }
    }
}
