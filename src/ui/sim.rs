//! The simulation thread and its protocol with the window.
//!
//! ```text
//! window ──(id, Command)──▶ mpsc channel ──▶ sim thread: apply commands, step, step, …
//! window ◀── latest Frame + step records ◀── Mutex<Mailbox> ◀── publish (≤ 120 Hz)
//! ```
//!
//! Neither side waits for the other: the window takes whatever frame is newest when it draws
//! (the mailbox holds only the latest, older ones are dropped), and the solver publishes without
//! knowing whether anyone looked. Per-step statistics travel separately as [`StepRecord`]s,
//! collected between publications, so the diagnostic plots see every step even when the solver
//! runs hundreds of steps per drawn frame.
//!
//! Every command gets a sequence number from [`SimHandle::send`]; each [`Frame`] says how many
//! commands had been applied when it was published ([`Frame::applied`]). The panel uses this to
//! tell a frame that already reflects an edit from a stale one still in flight, and the tests use
//! it to check that a parameter change shows up in the next published frame.

use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::model::Model;
use crate::params::SolverParams;
use crate::snapshot::RunTotals;
use crate::snapshot::{ContactState, Snapshot};
use crate::solver::Solver;

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
    /// `id` (as returned by [`SimHandle::send`]) when `applied >= id`.
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
    /// Solver steps per wall-clock second while running (over the last ~0.5 s; 0 when idle).
    pub steps_per_second: f64,
    /// Mean wall time of one step, s (over the same window).
    pub seconds_per_step: f64,
    /// Wall-clock time spent running (playing or stepping) since the start, s: with
    /// `totals.steps` it gives the solver's average speed.
    pub running_seconds: f64,
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
}

/// What the sim thread leaves for the window.
#[derive(Default)]
struct Mailbox {
    latest: Option<Arc<Frame>>,
    /// Step records since the window last drained them.
    records: Vec<StepRecord>,
    /// The window has not picked up `latest` yet (the waker is called only on false → true).
    unread: bool,
}

/// Prefix of the message for a SetParams that failed validation.
const REJECTED: &str = "parameters not applied";

/// Records kept in the mailbox when the window does not drain them (minimised for hours).
const MAILBOX_RECORD_CAP: usize = 200_000;
/// Publications while running are at most this often: enough for any display, and cheap
/// even for large models whose snapshots take a while to copy.
const PUBLISH_INTERVAL: Duration = Duration::from_micros(8_333);
/// Window over which steps per second are measured.
const RATE_WINDOW: Duration = Duration::from_millis(500);

/// The window's end of the protocol. Dropping it stops the thread.
pub struct SimHandle {
    tx: Sender<(u64, Command)>,
    mailbox: Arc<Mutex<Mailbox>>,
    next_id: u64,
    thread: Option<JoinHandle<()>>,
}

impl SimHandle {
    /// Starts the thread on `model` with `params` (`params.duration` is the scene's end time).
    /// `waker` is called (from the sim thread) when a new frame is waiting; the window uses it to
    /// schedule a redraw. The first frame (t = 0) is published before this returns.
    pub fn spawn(
        model: Model,
        params: SolverParams,
        speed: Speed,
        play: bool,
        waker: Box<dyn Fn() + Send>,
    ) -> std::io::Result<SimHandle> {
        let (tx, rx) = mpsc::channel();
        let mailbox = Arc::new(Mutex::new(Mailbox::default()));
        let mut sim = Sim::new(model, params, speed, mailbox.clone(), waker);
        if play {
            sim.play();
        }
        sim.publish();
        let thread = std::thread::Builder::new()
            .name("dda3d-sim".into())
            .spawn(move || {
                lower_priority();
                sim.run(rx)
            })?;
        Ok(SimHandle {
            tx,
            mailbox,
            next_id: 0,
            thread: Some(thread),
        })
    }

    /// Queues a command; returns its sequence number (compare with [`Frame::applied`]).
    /// A command sent after the thread has stopped is dropped.
    pub fn send(&mut self, cmd: Command) -> u64 {
        self.next_id += 1;
        let _ = self.tx.send((self.next_id, cmd));
        self.next_id
    }

    /// Sequence number of the last command sent.
    pub fn last_sent(&self) -> u64 {
        self.next_id
    }

    /// The newest frame (the same one again if nothing new was published).
    pub fn latest(&self) -> Option<Arc<Frame>> {
        let mut m = lock(&self.mailbox);
        m.unread = false;
        m.latest.clone()
    }

    /// Moves the step records published since the last call into `out`.
    pub fn drain_records(&self, out: &mut Vec<StepRecord>) {
        let mut m = lock(&self.mailbox);
        out.append(&mut m.records);
    }

    /// Waits (polling the mailbox) until a frame satisfies `pred`, or `timeout` passes. For
    /// tests and the headless screenshot mode; the window never blocks like this.
    pub fn wait_for(
        &self,
        timeout: Duration,
        mut pred: impl FnMut(&Frame) -> bool,
    ) -> Option<Arc<Frame>> {
        let end = Instant::now() + timeout;
        loop {
            if let Some(f) = self.latest()
                && pred(&f)
            {
                return Some(f);
            }
            if Instant::now() >= end {
                return None;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Whether the thread is still alive (false after Quit or a panic).
    pub fn is_alive(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }
}

impl Drop for SimHandle {
    fn drop(&mut self) {
        let _ = self.tx.send((self.next_id + 1, Command::Quit));
        if let Some(t) = self.thread.take() {
            // The thread sees Quit after its current step. A step of a large model can take
            // seconds; closing the window should not wait that long, and the thread owns
            // nothing but its solver, so after a short grace period it is left to end with
            // the process.
            let end = Instant::now() + Duration::from_secs(1);
            while !t.is_finished() && Instant::now() < end {
                std::thread::sleep(Duration::from_millis(2));
            }
            if t.is_finished() {
                let _ = t.join();
            }
        }
    }
}

/// Gives the simulation thread a lower scheduling priority than the window, so that on a
/// machine with few cores (where a software rasterizer also needs them) the solver uses what
/// the window leaves instead of making it stutter. It still gets a whole core when one is idle.
fn lower_priority() {
    #[cfg(target_os = "linux")]
    {
        unsafe extern "C" {
            /// POSIX `nice`; on Linux it applies to the calling thread only.
            fn nice(inc: std::ffi::c_int) -> std::ffi::c_int;
        }
        // SAFETY: `nice` takes an integer and only changes this thread's scheduling weight;
        // its result (the new nice value, or -1 on failure) is not needed.
        unsafe {
            nice(SIM_NICE);
        }
    }
}

/// Nice increment of the simulation thread (0 = same as the window, 19 = lowest).
#[cfg(target_os = "linux")]
const SIM_NICE: std::ffi::c_int = 10;

fn lock(m: &Mutex<Mailbox>) -> std::sync::MutexGuard<'_, Mailbox> {
    // A poisoned mailbox only means the other side panicked mid-update of plain data.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// The thread's state.
struct Sim {
    model: Model,
    /// The scene's end time, restored on reset and used as the increment past the end.
    scene_duration: f64,
    solver: Solver,
    state: RunState,
    speed: Speed,
    error: Option<String>,
    /// A single step was requested while paused.
    step_once: bool,
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
}

impl Sim {
    fn new(
        model: Model,
        params: SolverParams,
        speed: Speed,
        mailbox: Arc<Mutex<Mailbox>>,
        waker: Box<dyn Fn() + Send>,
    ) -> Sim {
        let now = Instant::now();
        Sim {
            scene_duration: params.duration,
            solver: Solver::new(model.clone(), params),
            model,
            state: RunState::Paused,
            speed,
            error: None,
            step_once: false,
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
        (self.state == RunState::Running || self.step_once) && !self.solver.finished()
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
                self.running_before = Duration::ZERO;
                self.running_since = None;
                let mut params = self.solver.params.clone();
                params.duration = self.scene_duration;
                self.solver = Solver::new(self.model.clone(), params);
                self.generation += 1;
                self.records.clear();
                self.error = None;
                if self.state != RunState::Running {
                    self.state = RunState::Paused;
                }
                self.step_once = false;
                self.re_anchor();
                self.reset_rate();
            }
            Command::SetParams(p) => match p.validate() {
                Ok(()) => {
                    self.solver.params = *p;
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
            Command::SetSpeed(s) => {
                self.speed = s;
                self.re_anchor();
            }
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
        let result = self.solver.step().cloned();
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
            steps_per_second: if idle { 0.0 } else { self.steps_per_second },
            seconds_per_step: self.seconds_per_step,
            running_seconds: (self.running_before
                + self.running_since.map_or(Duration::ZERO, |t| t.elapsed()))
            .as_secs_f64(),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Method;

    fn rockfall() -> crate::scene::Scene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join("rock_column_rockfall.toml");
        crate::scene::load(&path).expect("shipped scene loads")
    }

    fn spawn(speed: Speed, play: bool) -> SimHandle {
        let s = rockfall();
        SimHandle::spawn(s.model, s.params, speed, play, Box::new(|| {})).unwrap()
    }

    const WAIT: Duration = Duration::from_secs(30);

    #[test]
    fn first_frame_is_published_at_t0() {
        let h = spawn(Speed::Max, false);
        let f = h.latest().expect("a frame at start");
        assert_eq!(f.snapshot.step, 0);
        assert_eq!(f.state, RunState::Paused);
        assert_eq!(f.applied, 0);
    }

    #[test]
    fn parameter_change_while_running_shows_in_the_next_frame() {
        // Slow pacing keeps the run going for the whole test.
        let mut h = spawn(Speed::RealTime(0.05), true);
        let running = h
            .wait_for(WAIT, |f| {
                f.state == RunState::Running && f.snapshot.step >= 2
            })
            .expect("runs");
        let mut p = running.params.clone();
        p.contact.alpha = 7.5;
        p.contact.initial_penalty = 4.0e8;
        p.joint.friction_angle = 20.0;
        p.method = Method::Penalty;
        let id = h.send(Command::SetParams(Box::new(p.clone())));
        // The first frame published after the command was taken carries the new parameters,
        // and so does every later one.
        let f = h.wait_for(WAIT, |f| f.applied >= id).expect("applied");
        assert_eq!(f.params, p);
        assert_eq!(f.state, RunState::Running);
        let step_then = f.snapshot.step;
        let later = h
            .wait_for(WAIT, |f| f.snapshot.step > step_then)
            .expect("keeps stepping with the new parameters");
        assert_eq!(later.params, p);
        assert!(later.error.is_none());
    }

    #[test]
    fn frames_before_the_command_keep_old_parameters() {
        let mut h = spawn(Speed::Max, false);
        let before = h.latest().unwrap();
        let mut p = before.params.clone();
        p.contact.eps1 = 0.005;
        let id = h.send(Command::SetParams(Box::new(p.clone())));
        let after = h.wait_for(WAIT, |f| f.applied >= id).unwrap();
        assert!(after.seq > before.seq);
        assert_eq!(before.params.contact.eps1, 0.01);
        assert_eq!(after.params.contact.eps1, 0.005);
    }

    #[test]
    fn invalid_parameters_are_rejected_with_a_message() {
        let mut h = spawn(Speed::Max, false);
        let mut p = h.latest().unwrap().params.clone();
        let good_alpha = p.contact.alpha;
        p.contact.alpha = 0.5; // must be > 1
        let id = h.send(Command::SetParams(Box::new(p)));
        let f = h.wait_for(WAIT, |f| f.applied >= id).unwrap();
        assert_eq!(f.params.contact.alpha, good_alpha);
        let msg = f.error.as_deref().expect("an error message");
        assert!(msg.contains("alpha"), "{msg}");
    }

    #[test]
    fn step_pause_and_reset() {
        let mut h = spawn(Speed::Max, false);
        let id = h.send(Command::Step);
        let f = h.wait_for(WAIT, |f| f.applied >= id && f.snapshot.step == 1);
        let f = f.expect("one step");
        assert_eq!(f.state, RunState::Paused);
        assert!(f.snapshot.time > 0.0);
        let mut records = Vec::new();
        h.drain_records(&mut records);
        assert_eq!(records.len(), 1);
        assert_eq!(records[0].step, 1);

        let id = h.send(Command::Reset);
        let f = h.wait_for(WAIT, |f| f.applied >= id).unwrap();
        assert_eq!(f.snapshot.step, 0);
        assert_eq!(f.generation, 1);
        assert_eq!(f.state, RunState::Paused);
    }

    #[test]
    fn runs_to_the_end_then_play_continues() {
        let mut h = spawn(Speed::Max, false);
        let mut p = h.latest().unwrap().params.clone();
        p.duration = 0.05;
        h.send(Command::SetParams(Box::new(p)));
        let id = h.send(Command::Play);
        let f = h
            .wait_for(WAIT, |f| f.applied >= id && f.state == RunState::Finished)
            .expect("finishes");
        assert!((f.snapshot.time - 0.05).abs() < 1e-9, "{}", f.snapshot.time);
        let mut records = Vec::new();
        h.drain_records(&mut records);
        assert_eq!(records.len() as u64, f.snapshot.step, "a record per step");

        // Play past the end extends the end time by the scene's duration (2 s).
        let id = h.send(Command::Play);
        let f = h
            .wait_for(WAIT, |f| f.applied >= id && f.snapshot.time > 0.06)
            .expect("continues past the end");
        assert!(
            (f.params.duration - 2.05).abs() < 1e-9,
            "{}",
            f.params.duration
        );
        h.send(Command::Pause);
    }

    #[test]
    fn solver_error_is_published_and_reset_recovers() {
        let mut h = spawn(Speed::Max, false);
        let mut p = h.latest().unwrap().params.clone();
        // A penalty far too soft: the column sinks into its base until the solver gives up.
        p.method = Method::Penalty;
        p.contact.initial_penalty = 2.0e3;
        h.send(Command::SetParams(Box::new(p)));
        let id = h.send(Command::Play);
        let f = h
            .wait_for(WAIT, |f| f.applied >= id && f.state == RunState::Failed)
            .expect("the run fails");
        let msg = f.error.as_deref().expect("an error message");
        assert!(msg.contains("diverged"), "{msg}");
        assert!(h.is_alive(), "the thread survives a solver error");

        let id = h.send(Command::Reset);
        let f = h.wait_for(WAIT, |f| f.applied >= id).unwrap();
        assert_eq!(f.snapshot.step, 0);
        assert_eq!(f.state, RunState::Paused);
        assert!(f.error.is_none());
    }

    #[test]
    fn real_time_pacing_holds_the_solver_back() {
        let h = spawn(Speed::RealTime(0.2), true);
        std::thread::sleep(Duration::from_millis(300));
        let f = h.latest().unwrap();
        // 0.3 s wall at 0.2× is 0.06 s simulated; allow one step (≤ 0.01 s) of lead.
        assert!(
            f.snapshot.time <= 0.06 + 0.011 + 0.01,
            "t = {}",
            f.snapshot.time
        );
        assert!(f.snapshot.time > 0.0);
    }

    #[test]
    fn waker_fires_on_new_frames() {
        let s = rockfall();
        let (tx, rx) = mpsc::channel();
        let mut h = SimHandle::spawn(
            s.model,
            s.params,
            Speed::Max,
            false,
            Box::new(move || {
                let _ = tx.send(());
            }),
        )
        .unwrap();
        rx.recv_timeout(WAIT).expect("woken for the first frame");
        let _ = h.latest();
        h.send(Command::Step);
        rx.recv_timeout(WAIT).expect("woken after a step");
    }

    #[test]
    fn quit_stops_the_thread_and_drop_does_not_hang() {
        let mut h = spawn(Speed::Max, true);
        std::thread::sleep(Duration::from_millis(20));
        h.send(Command::Quit);
        let end = Instant::now() + WAIT;
        while h.is_alive() && Instant::now() < end {
            std::thread::sleep(Duration::from_millis(1));
        }
        assert!(!h.is_alive(), "the thread ends on Quit");

        let h = spawn(Speed::Max, true);
        std::thread::sleep(Duration::from_millis(20));
        let t = Instant::now();
        drop(h);
        assert!(
            t.elapsed() < Duration::from_secs(3),
            "closing does not wait long"
        );
    }
}
