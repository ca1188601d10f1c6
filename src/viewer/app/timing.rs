//! Frame pacing and measurement: when the window draws next, when `--exit-after-frames` ends
//! it, the one-line frame-time report printed then, and the per-phase timings of a frame that
//! `DDA3D_VIEWER_TIMING` prints (for tuning).

use std::time::{Duration, Instant};

use crate::viewer::sim::{Frame, RunState};

/// On a software rasterizer, drawing competes with the solver for the same cores: animation is
/// capped at 30 frames/s there (video's rate), and the solver gets the time between frames.
/// GPUs are paced by vsync instead. (The cap was 40 frames/s until issue #15: on two cores the
/// solver behind the window of a struck wall of 1000 blocks kept a median 69 % of its headless
/// speed at 40 and 74 % at 30, six rounds alternating.)
const CPU_FRAME_INTERVAL: Duration = Duration::from_micros(33_333);

/// Frames drawn so far, and when to draw the next one.
pub(super) struct FrameClock {
    pub frames: u64,
    started: Instant,
    /// `--exit-after-frames`.
    exit_after: Option<u64>,
    /// A redraw is due at this time (the event loop waits until then).
    pub next_repaint: Option<Instant>,
    /// The steps/s of the last frame that had the solver running (for the exit report).
    last_steps_per_second: f64,
    /// Animation frames are not started more often than this (software rasterizers only).
    min_frame_interval: Option<Duration>,
}

impl FrameClock {
    pub fn new(exit_after: Option<u64>, software_rasterizer: bool) -> FrameClock {
        FrameClock {
            frames: 0,
            started: Instant::now(),
            exit_after,
            next_repaint: None,
            last_steps_per_second: 0.0,
            min_frame_interval: software_rasterizer.then_some(CPU_FRAME_INTERVAL),
        }
    }

    /// Whether the window closes by itself after a number of frames.
    pub fn exits_by_itself(&self) -> bool {
        self.exit_after.is_some()
    }

    /// Whether the frame being drawn is the last one.
    pub fn drawing_last_frame(&self) -> bool {
        self.exit_after.is_some_and(|n| self.frames + 1 >= n)
    }

    /// Whether all frames asked for have been drawn.
    pub fn done(&self) -> bool {
        self.exit_after.is_some_and(|n| self.frames >= n)
    }

    /// Counts a drawn frame showing `frame`.
    pub fn frame_drawn(&mut self, frame: Option<&Frame>) {
        self.frames += 1;
        if let Some(f) = frame
            && f.state == RunState::Running
            && f.steps_per_second > 0.0
        {
            self.last_steps_per_second = f.steps_per_second;
        }
    }

    /// Something new to show (a simulation frame, a finished background job) and the last
    /// frame started at `last_start`: true to draw at once, else the redraw is scheduled no
    /// sooner than the frame cap allows.
    pub fn wake(&mut self, last_start: Option<Instant>) -> bool {
        match (self.min_frame_interval, last_start) {
            (Some(min), Some(last)) if last.elapsed() < min => {
                let at = last + min;
                self.next_repaint = Some(self.next_repaint.map_or(at, |t| t.min(at)));
                false
            }
            _ => true,
        }
    }

    /// After a frame that started at `started`: true to draw again at once, else the next
    /// redraw is scheduled. `animating`: something moves (the run, a recording, a counted
    /// exit); `delay`: when egui wants to draw again.
    pub fn schedule(&mut self, started: Instant, animating: bool, delay: Duration) -> bool {
        if animating || delay.is_zero() {
            match self.min_frame_interval {
                // Input still redraws at once (winit events request a redraw); only the
                // animation is paced, leaving the solver the rest of the CPU.
                Some(min) if started.elapsed() < min => {
                    self.next_repaint = Some(started + min);
                    false
                }
                _ => true,
            }
        } else {
            if delay < Duration::from_secs(3600) {
                self.next_repaint = Some(Instant::now() + delay);
            }
            false
        }
    }

    /// One line on stderr for `--exit-after-frames`: how fast the window drew and the solver
    /// ran. `intervals` and `busy` are the seconds between frame starts and spent drawing, of
    /// every frame; `frame` is the simulation frame last shown.
    pub fn report(
        &self,
        intervals: &[f64],
        busy: &[f64],
        frame: Option<&Frame>,
        view_size: (u32, u32),
        adapter: &str,
    ) {
        // The first frames include shader compilation and layout; leave them out.
        let skip = (intervals.len() / 10).max(2);
        let mut iv: Vec<f64> = intervals.iter().skip(skip).copied().collect();
        let busy: Vec<f64> = busy.iter().skip(skip).copied().collect();
        if iv.is_empty() {
            iv = intervals.to_vec();
        }
        let mean = |v: &[f64]| {
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64 * 1e3
            }
        };
        let mut sorted = iv.clone();
        sorted.sort_by(f64::total_cmp);
        let p95 = sorted
            .get(((sorted.len() as f64 * 0.95) as usize).min(sorted.len().saturating_sub(1)))
            .copied()
            .unwrap_or(0.0)
            * 1e3;
        let m = mean(&iv);
        let (steps, t, run_s) = frame.map_or((0, 0.0, 0.0), |f| {
            (f.steps_run, f.snapshot.time, f.running_seconds)
        });
        let avg_sps = if run_s > 0.0 {
            steps as f64 / run_s
        } else {
            0.0
        };
        eprintln!(
            "viewer: {} frames in {:.2} s; frame interval mean {:.1} ms ({:.1} fps), p95 {:.1} ms; \
             CPU {:.1} ms/frame; view {}x{} at {}; solver {} steps to t = {:.3} s in {:.2} s \
             running: {:.0} steps/s (last 0.5 s: {:.0} steps/s)",
            self.frames,
            self.started.elapsed().as_secs_f64(),
            m,
            if m > 0.0 { 1e3 / m } else { 0.0 },
            p95,
            mean(&busy),
            view_size.0,
            view_size.1,
            adapter,
            steps,
            t,
            run_s,
            avg_sps,
            self.last_steps_per_second
        );
    }
}

/// The exit report's line for run B of a comparison: its solver's speed (the frame times and
/// A's solver are on the line before).
pub(super) fn report_b(b: &Frame) {
    let (steps, run_s) = (b.steps_run, b.running_seconds);
    eprintln!(
        "viewer: compare run B ({}): solver {} steps to t = {:.3} s in {:.2} s running: {:.0} \
         steps/s (last 0.5 s: {:.0} steps/s)",
        b.params.method.as_str(),
        steps,
        b.snapshot.time,
        run_s,
        if run_s > 0.0 {
            steps as f64 / run_s
        } else {
            0.0
        },
        b.steps_per_second
    );
}

/// Phase timings of a frame, printed when `DDA3D_VIEWER_TIMING` is set (for tuning).
pub(super) struct Timing {
    pub on: bool,
    last: Instant,
    marks: Vec<(&'static str, f64)>,
}

impl Timing {
    pub fn new() -> Timing {
        Timing {
            on: std::env::var_os("DDA3D_VIEWER_TIMING").is_some(),
            last: Instant::now(),
            marks: Vec::new(),
        }
    }
    pub fn mark(&mut self, name: &'static str) {
        if self.on {
            let now = Instant::now();
            self.marks
                .push((name, (now - self.last).as_secs_f64() * 1e3));
            self.last = now;
        }
    }
    pub fn print(&self) {
        if self.on {
            let parts: Vec<String> = self
                .marks
                .iter()
                .map(|(n, t)| format!("{n} {t:.1}"))
                .collect();
            eprintln!("frame ms: {}", parts.join(", "));
        }
    }
}
