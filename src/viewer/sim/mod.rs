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
//!
//! - `protocol.rs`: what travels between the two sides ([`Command`], [`Frame`], [`StepRecord`],
//!   [`RunState`], [`Speed`]);
//! - `thread.rs`: the simulation thread itself (stepping, pacing, publishing);
//! - [`pair`]: two threads in lock-step of simulated time (`view --compare`);
//! - this file: the window's end, [`SimHandle`], and the mailbox the two sides share.

pub mod pair;
mod protocol;
pub mod states;
mod thread;

use std::sync::mpsc::{self, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::model::Model;
use crate::params::SolverParams;

pub use protocol::{Command, Frame, RunState, Speed, StepRecord};

/// A checkpoint (`crate::solver::checkpoint`, encoded) that a run starts from and Reset goes
/// back to: `view --resume`.
pub type Origin = Arc<[u8]>;

/// What the sim thread leaves for the window.
#[derive(Default)]
struct Mailbox {
    latest: Option<Arc<Frame>>,
    /// Step records since the window last drained them.
    records: Vec<StepRecord>,
    /// The window has not picked up `latest` yet (the waker is called only on false → true).
    unread: bool,
}

/// The window's end of the protocol. Dropping it stops the thread.
pub struct SimHandle {
    tx: Sender<(u64, Command)>,
    mailbox: Arc<Mutex<Mailbox>>,
    next_id: u64,
    thread: Option<JoinHandle<()>>,
}

impl SimHandle {
    /// Starts the thread on `model` with `params` (`params.duration` is the scene's end time), or
    /// from the checkpoint `origin` (`view --resume`: encoded, of `model`'s blocks, `params`
    /// its settings), which Reset then goes back to. `waker` is called (from the sim thread)
    /// when a new frame is waiting; the window uses it to schedule a redraw. The first frame
    /// (t = 0, or the checkpoint's time) is published before this returns. An `origin` that
    /// does not decode is an error of kind `InvalidData`, and no thread starts.
    pub fn spawn(
        model: Model,
        params: SolverParams,
        origin: Option<Origin>,
        speed: Speed,
        play: bool,
        waker: Box<dyn Fn() + Send>,
    ) -> std::io::Result<SimHandle> {
        let (tx, rx) = mpsc::channel();
        let mailbox = Arc::new(Mutex::new(Mailbox::default()));
        let start = thread::Start {
            model,
            params,
            origin,
        };
        let thread = thread::start(start, (speed, play), mailbox.clone(), waker, rx)?;
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

fn lock(m: &Mutex<Mailbox>) -> std::sync::MutexGuard<'_, Mailbox> {
    // A poisoned mailbox only means the other side panicked mid-update of plain data.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// What the simulation thread's tests start from: the shipped rockfall, and a checkpoint of it.
#[cfg(test)]
mod test_support {
    use super::Origin;
    use crate::solver::{Solver, checkpoint};

    pub fn rockfall() -> crate::scene::Scene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join("rock_column_rockfall.toml");
        crate::scene::load(&path).expect("shipped scene loads")
    }

    /// The rockfall's solver after `steps` steps, and its checkpoint (`view --resume`).
    pub fn rockfall_checkpoint(steps: usize) -> (crate::scene::Scene, Solver, Origin) {
        let s = rockfall();
        let mut solver = Solver::new(s.model.clone(), s.params.clone());
        for _ in 0..steps {
            solver.step().unwrap();
        }
        let origin = checkpoint::encode(&solver).into();
        (s, solver, origin)
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::{rockfall, rockfall_checkpoint};
    use super::*;
    use crate::params::Method;

    fn spawn(speed: Speed, play: bool) -> SimHandle {
        let s = rockfall();
        SimHandle::spawn(s.model, s.params, None, speed, play, Box::new(|| {})).unwrap()
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
    fn a_saved_state_loads_back_paused_at_its_time_with_a_notice() {
        let dir = std::env::temp_dir().join(format!("dda3d-sim-state-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut h = spawn(Speed::Max, false);
        for _ in 0..3 {
            let id = h.send(Command::Step);
            h.wait_for(WAIT, |f| f.applied >= id && f.snapshot.step >= id)
                .expect("steps");
        }
        let saved = h.latest().unwrap();
        let id = h.send(Command::SaveState(dir.clone()));
        let f = h.wait_for(WAIT, |f| f.applied >= id).unwrap();
        let notice = f.notice.clone().expect("a notice");
        assert_eq!(notice.0, id);
        assert!(notice.1.contains("state saved"), "{notice:?}");
        let id = h.send(Command::Play);
        h.wait_for(WAIT, |f| {
            f.applied >= id && f.snapshot.step > saved.snapshot.step + 5
        })
        .expect("runs on");
        let file = states::list(&dir).remove(0);
        let id = h.send(Command::LoadState(file));
        let f = h.wait_for(WAIT, |f| f.applied >= id).unwrap();
        assert_eq!(f.state, RunState::Paused);
        assert_eq!(f.snapshot.step, saved.snapshot.step);
        assert_eq!(f.snapshot.time.to_bits(), saved.snapshot.time.to_bits());
        assert!(f.generation > saved.generation, "plots start over");
        assert!(f.notice.as_ref().is_some_and(|n| n.0 == id));
        // A file that is not a checkpoint is an error line, and the run stays as it was.
        let bad = dir.join("checkpoint_9.000000.ckpt");
        std::fs::write(&bad, b"not a checkpoint").unwrap();
        let id = h.send(Command::LoadState(bad));
        let f = h.wait_for(WAIT, |f| f.applied >= id).unwrap();
        assert!(
            f.error
                .as_deref()
                .is_some_and(|e| e.contains("not a dda3d checkpoint"))
        );
        assert_eq!(f.snapshot.step, saved.snapshot.step);
        std::fs::remove_dir_all(&dir).unwrap();
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
        // A Δt_max within its range but too short for the heaviest block, as the scene file
        // and the flags refuse it.
        let mut p = f.params.clone();
        let good_dt = p.max_time_step;
        p.max_time_step = 1e-6;
        let id = h.send(Command::SetParams(Box::new(p)));
        let f = h.wait_for(WAIT, |f| f.applied >= id).unwrap();
        assert_eq!(f.params.max_time_step, good_dt);
        let msg = f.error.as_deref().expect("an error message");
        assert!(msg.contains("too short for block"), "{msg}");
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

    /// `view --resume`: a run started from a checkpoint opens at its time and step, its next
    /// step is the one the checkpoint's solver takes, and Reset goes back to it, not to t = 0.
    #[test]
    fn a_run_from_a_checkpoint_starts_and_resets_there() {
        let (s, mut solver, origin) = rockfall_checkpoint(20);
        let at = solver.snapshot();
        solver.step().unwrap();
        let next = solver.snapshot();
        let params = solver.params.clone();
        let mut h = SimHandle::spawn(
            s.model,
            params,
            Some(origin),
            Speed::Max,
            false,
            Box::new(|| {}),
        )
        .unwrap();
        let first = h.latest().expect("a frame at start");
        assert_eq!((first.snapshot.time, first.snapshot.step), (at.time, 20));
        assert_eq!(first.snapshot.blocks[1].vertices, at.blocks[1].vertices);
        // The checkpoint's steps are not this window's (the exit report's speed counts these).
        assert_eq!(first.steps_run, 0);

        let id = h.send(Command::Step);
        let f = h.wait_for(WAIT, |f| f.applied >= id && f.snapshot.step == 21);
        let f = f.expect("one step");
        assert_eq!(f.steps_run, 1);
        assert_eq!(f.snapshot.time.to_bits(), next.time.to_bits());
        for (a, b) in f.snapshot.blocks.iter().zip(&next.blocks) {
            assert_eq!(a.vertices, b.vertices, "{}", a.name);
        }

        let id = h.send(Command::Reset);
        let f = h.wait_for(WAIT, |f| f.applied >= id).unwrap();
        assert_eq!((f.snapshot.time, f.snapshot.step), (at.time, 20));
        assert_eq!(f.steps_run, 0);
        // Bytes that are no checkpoint start nothing.
        let junk: Origin = vec![0u8; 64].into();
        let s = rockfall();
        let e = SimHandle::spawn(
            s.model,
            s.params,
            Some(junk),
            Speed::Max,
            false,
            Box::new(|| {}),
        );
        assert_eq!(
            e.err().map(|e| e.kind()),
            Some(std::io::ErrorKind::InvalidData)
        );
        assert_eq!(f.snapshot.blocks[1].vertices, at.blocks[1].vertices);
        assert_eq!(f.generation, 1);
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
            None,
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
