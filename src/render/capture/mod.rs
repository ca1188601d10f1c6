//! Headless frame capture: snapshots in, `frame_00000.png …`, `frames.csv` and optionally
//! `animation.gif` out.
//!
//! Pipeline (each stage on its own thread, joined by bounded channels so memory stays flat):
//!
//! ```text
//! caller ──Snapshot──▶ render thread ──RGBA──▶ PNG encoder threads (N) ──▶ frame_NNNNN.png
//!   (solver)          scene → GPU → readback  └──RGBA──▶ GIF thread ──▶ animation.gif
//! ```
//!
//! The render thread keeps two frames on the GPU (draw frame n+1 while frame n is read back),
//! and PNG encoding runs beside it, so a long capture costs max(solver, render, encode) per
//! frame rather than their sum.
//!
//! This room holds the threads and their hand-offs; `options` what a capture is asked for,
//! `frames` the look that stays fixed across a sequence (and single screenshots), `encode`
//! the PNG and GIF writers.

mod encode;
mod frames;
mod options;
mod pair;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::RenderError;
use super::gpu::Gpu;
use super::offscreen::{Offscreen, Pending};
use crate::snapshot::Snapshot;
use encode::{EncodeJob, GifFrame, encode_loop, gif_loop};
use frames::FrameState;
use pair::Job;

pub use encode::{unpremultiply, write_png};
pub use frames::{render_rgba, render_to_png};
pub use options::{CaptureOptions, Framing};

/// Creates a directory the capture writes into, and its parents: a file in the way is named
/// ([`crate::files::create_dir_clearly`]), as `run` names it.
pub(crate) fn create_output_dir(dir: &Path) -> Result<(), RenderError> {
    crate::files::create_dir_clearly(dir)
        .map_err(|e| RenderError::io(dir, format!("cannot create the output directory: {e}")))
}

/// First error of any worker thread, shared by all of them.
type Failure = Arc<Mutex<Option<RenderError>>>;
/// A worker thread: its result is its busy time (or statistics), or why it stopped.
type Worker<T> = JoinHandle<Result<T, RenderError>>;

/// What a finished capture did and where its time went.
#[derive(Clone, Debug)]
pub struct CaptureReport {
    pub frames: usize,
    pub out_dir: PathBuf,
    pub csv: PathBuf,
    pub gif: Option<PathBuf>,
    /// "name (backend, type)".
    pub adapter: String,
    pub msaa_samples: u32,
    /// Device, pipelines and threads.
    pub setup_seconds: f64,
    /// Render thread busy time: scene building, GPU draw and readback (the two overlap with
    /// the caller and the encoders).
    pub render_seconds: f64,
    /// PNG encoding and writing, summed over the encoder threads.
    pub encode_seconds: f64,
    pub gif_seconds: f64,
    /// Time the caller spent blocked in [`FrameCapture::submit`] because the pipeline was full
    /// (zero when the solver is the bottleneck).
    pub submit_blocked_seconds: f64,
    /// From `start` to the end of `finish`.
    pub wall_seconds: f64,
}

impl CaptureReport {
    /// Mean render + readback time per frame, ms.
    pub fn render_ms_per_frame(&self) -> f64 {
        per_frame_ms(self.render_seconds, self.frames)
    }

    /// Mean PNG encode time per frame, ms.
    pub fn encode_ms_per_frame(&self) -> f64 {
        per_frame_ms(self.encode_seconds, self.frames)
    }
}

fn per_frame_ms(s: f64, n: usize) -> f64 {
    if n == 0 { 0.0 } else { s * 1e3 / n as f64 }
}

#[derive(Default)]
struct RenderStats {
    frames: usize,
    busy: Duration,
}

/// A running capture. Submit snapshots in time order, then call [`FrameCapture::finish`].
pub struct FrameCapture {
    tx: Option<SyncSender<Job>>,
    render: Option<Worker<RenderStats>>,
    encoders: Vec<Worker<Duration>>,
    gif: Option<Worker<Duration>>,
    /// First error of any worker, so `submit` can report it instead of a bare "closed".
    failure: Failure,
    submitted: AtomicUsize,
    blocked_nanos: AtomicU64,
    started: Instant,
    setup: Duration,
    adapter: String,
    samples: u32,
    out_dir: PathBuf,
    csv: PathBuf,
    gif_path: Option<PathBuf>,
}

fn record(failure: &Mutex<Option<RenderError>>, e: &RenderError) {
    if let Ok(mut f) = failure.lock() {
        f.get_or_insert_with(|| e.clone());
    }
}

impl FrameCapture {
    /// Opens the GPU (→ [`RenderError::NoAdapter`] without one), creates the output directory
    /// and `frames.csv`, and starts the worker threads.
    pub fn start(opts: CaptureOptions) -> Result<FrameCapture, RenderError> {
        let started = Instant::now();
        opts.validate()?;
        let gpu = Gpu::headless()?;
        FrameCapture::start_on(gpu, opts, started)
    }

    /// As [`FrameCapture::start`] on an existing device.
    pub fn start_with_gpu(gpu: Gpu, opts: CaptureOptions) -> Result<FrameCapture, RenderError> {
        opts.validate()?;
        FrameCapture::start_on(gpu, opts, Instant::now())
    }

    /// Creates the output directory, frames.csv and the off-screen target, then starts the
    /// encoders, the GIF thread and the render thread that feeds them.
    fn start_on(
        gpu: Gpu,
        opts: CaptureOptions,
        started: Instant,
    ) -> Result<FrameCapture, RenderError> {
        create_output_dir(&opts.out_dir)?;
        let adapter = gpu.adapter_summary();
        // A side-by-side frame is two half-width pictures of the same size and camera.
        let (w, halves) = match &opts.sides {
            Some(_) => (opts.width / 2, 2),
            None => (opts.width, 1),
        };
        let offscreen = Offscreen::with_max_samples(gpu, w, opts.height, opts.max_msaa_samples)?;
        let samples = offscreen.samples();
        let csv = FramesCsv::create(opts.out_dir.join("frames.csv"), opts.sides.is_some())?;
        let failure: Failure = Arc::new(Mutex::new(None));
        let (encode_tx, encoders) = spawn_encoders(opts.encoder_count(), &failure)?;
        let gif_path = opts.gif.then(|| opts.out_dir.join("animation.gif"));
        let (gif_tx, gif) = match &gif_path {
            Some(path) => {
                let (tx, worker) = spawn_gif(path, &opts, &failure)?;
                (Some(tx), Some(worker))
            }
            None => (None, None),
        };
        let (width, height) = offscreen.size();
        let width = width * halves;
        let sink = FrameSink {
            out_dir: opts.out_dir.clone(),
            csv,
            encoders: encode_tx,
            gif: gif_tx,
            width,
            height,
            transparent: opts.style.transparent,
        };
        // Bounded: the solver may run at most two snapshots ahead of the renderer.
        let (tx, rx) = mpsc::sync_channel::<Job>(2);
        let render = {
            let opts = opts.clone();
            spawn_worker("dda3d-render".into(), "render", &failure, move || {
                render_loop(rx, offscreen, &opts, sink)
            })?
        };
        Ok(FrameCapture {
            tx: Some(tx),
            render: Some(render),
            encoders,
            gif,
            failure,
            submitted: AtomicUsize::new(0),
            blocked_nanos: AtomicU64::new(0),
            setup: started.elapsed(),
            started,
            adapter,
            samples,
            csv: opts.out_dir.join("frames.csv"),
            out_dir: opts.out_dir,
            gif_path,
        })
    }

    /// Queues a snapshot as the next frame. Blocks while the pipeline is full; returns the
    /// workers' error if they have stopped.
    pub fn submit(&self, snapshot: Snapshot) -> Result<(), RenderError> {
        self.send(Job::One(snapshot))
    }

    /// Queues the snapshots of run A and run B at one time as the next side-by-side frame
    /// (a capture with [`CaptureOptions::sides`]).
    pub fn submit_pair(&self, a: Snapshot, b: Snapshot) -> Result<(), RenderError> {
        self.send(Job::Pair(a, Box::new(b)))
    }

    fn send(&self, job: Job) -> Result<(), RenderError> {
        let Some(tx) = &self.tx else {
            return Err(RenderError::Stopped("capture already finished".into()));
        };
        let t = Instant::now();
        let sent = tx.send(job);
        self.blocked_nanos
            .fetch_add(t.elapsed().as_nanos() as u64, Ordering::Relaxed);
        match sent {
            Ok(()) => {
                self.submitted.fetch_add(1, Ordering::Relaxed);
                Ok(())
            }
            Err(_) => Err(self.failure().unwrap_or_else(|| {
                RenderError::Stopped("render thread ended unexpectedly".into())
            })),
        }
    }

    /// As [`FrameCapture::submit`], but returns `Ok(false)` instead of blocking when the
    /// pipeline is full: the interactive viewer records without stalling its window and simply
    /// skips the steps that arrive while the writer is busy.
    pub fn try_submit(&self, snapshot: Snapshot) -> Result<bool, RenderError> {
        let Some(tx) = &self.tx else {
            return Err(RenderError::Stopped("capture already finished".into()));
        };
        match tx.try_send(Job::One(snapshot)) {
            Ok(()) => {
                self.submitted.fetch_add(1, Ordering::Relaxed);
                Ok(true)
            }
            Err(mpsc::TrySendError::Full(_)) => Ok(false),
            Err(mpsc::TrySendError::Disconnected(_)) => Err(self.failure().unwrap_or_else(|| {
                RenderError::Stopped("render thread ended unexpectedly".into())
            })),
        }
    }

    /// Snapshots accepted so far.
    pub fn submitted(&self) -> usize {
        self.submitted.load(Ordering::Relaxed)
    }

    /// Where the frames go.
    pub fn out_dir(&self) -> &Path {
        &self.out_dir
    }

    fn failure(&self) -> Option<RenderError> {
        self.failure.lock().ok().and_then(|f| f.clone())
    }

    /// Drains the pipeline, waits for every file to be written and reports timings.
    pub fn finish(mut self) -> Result<CaptureReport, RenderError> {
        drop(self.tx.take());
        let join_err = |what: &str| RenderError::Stopped(format!("{what} thread panicked"));
        let stats = match self.render.take() {
            Some(h) => h.join().map_err(|_| join_err("render"))?,
            None => Ok(RenderStats::default()),
        };
        let mut encode = Duration::ZERO;
        let mut first_err = stats.as_ref().err().cloned();
        for h in self.encoders.drain(..) {
            match h.join().map_err(|_| join_err("PNG encoder"))? {
                Ok(d) => encode += d,
                Err(e) => {
                    first_err.get_or_insert(e);
                }
            }
        }
        let gif = match self.gif.take() {
            Some(h) => match h.join().map_err(|_| join_err("GIF"))? {
                Ok(d) => d,
                Err(e) => {
                    first_err.get_or_insert(e);
                    Duration::ZERO
                }
            },
            None => Duration::ZERO,
        };
        // Prefer the root cause recorded first (e.g. a render error that made encoders stop).
        if let Some(e) = self.failure().or(first_err) {
            return Err(e);
        }
        let stats = stats?;
        Ok(CaptureReport {
            frames: stats.frames,
            out_dir: self.out_dir.clone(),
            csv: self.csv.clone(),
            gif: self.gif_path.clone(),
            adapter: self.adapter.clone(),
            msaa_samples: self.samples,
            setup_seconds: self.setup.as_secs_f64(),
            render_seconds: stats.busy.as_secs_f64(),
            encode_seconds: encode.as_secs_f64(),
            gif_seconds: gif.as_secs_f64(),
            submit_blocked_seconds: self.blocked_nanos.load(Ordering::Relaxed) as f64 * 1e-9,
            wall_seconds: self.started.elapsed().as_secs_f64(),
        })
    }
}

impl Drop for FrameCapture {
    /// Dropping without `finish` still stops the threads (files already queued get written).
    fn drop(&mut self) {
        drop(self.tx.take());
        if let Some(h) = self.render.take() {
            let _ = h.join();
        }
        for h in self.encoders.drain(..) {
            let _ = h.join();
        }
        if let Some(h) = self.gif.take() {
            let _ = h.join();
        }
    }
}

/// Starts a named thread running `work`; its error, if any, is also recorded in `failure`.
fn spawn_worker<T: Send + 'static>(
    name: String,
    what: &str,
    failure: &Failure,
    work: impl FnOnce() -> Result<T, RenderError> + Send + 'static,
) -> Result<Worker<T>, RenderError> {
    let failure = failure.clone();
    std::thread::Builder::new()
        .name(name)
        .spawn(move || {
            let r = work();
            if let Err(e) = &r {
                record(&failure, e);
            }
            r
        })
        .map_err(|e| RenderError::Stopped(format!("cannot start {what} thread: {e}")))
}

/// `n` PNG encoder threads sharing one job queue.
fn spawn_encoders(
    n: usize,
    failure: &Failure,
) -> Result<(SyncSender<EncodeJob>, Vec<Worker<Duration>>), RenderError> {
    // Two frames per encoder in the queue: enough to ride out jitter, and bounded memory
    // (each 1280×720 frame is 3.7 MB).
    let (tx, rx) = mpsc::sync_channel::<EncodeJob>(2 * n);
    let rx = Arc::new(Mutex::new(rx));
    let encoders = (0..n)
        .map(|k| {
            let rx = rx.clone();
            spawn_worker(format!("dda3d-png-{k}"), "encoder", failure, move || {
                encode_loop(&rx)
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((tx, encoders))
}

/// The GIF thread, writing to `path` (created here, so a bad path fails the start).
fn spawn_gif(
    path: &Path,
    opts: &CaptureOptions,
    failure: &Failure,
) -> Result<(SyncSender<GifFrame>, Worker<Duration>), RenderError> {
    let (tx, rx) = mpsc::sync_channel::<GifFrame>(4);
    let file = File::create(path).map_err(|e| RenderError::io(path, e))?;
    let (path, fps, max_w) = (path.to_path_buf(), opts.fps, opts.gif_max_width);
    let worker = spawn_worker("dda3d-gif".into(), "GIF", failure, move || {
        gif_loop(rx, file, &path, fps, max_w)
    })?;
    Ok((tx, worker))
}

struct FrameMeta {
    index: usize,
    time: f64,
    step: u64,
    /// Run B's time and step in a side-by-side frame.
    b: Option<(f64, u64)>,
}

/// `frames.csv`: one row per frame, flushed at once so the file lists every frame handed to
/// the encoders even when the run is cut off.
struct FramesCsv {
    writer: BufWriter<File>,
    path: PathBuf,
}

impl FramesCsv {
    fn create(path: PathBuf, sides: bool) -> Result<FramesCsv, RenderError> {
        let file = File::create(&path).map_err(|e| RenderError::io(&path, e))?;
        let mut writer = BufWriter::new(file);
        let header = if sides {
            "frame,time,step,file,time_b,step_b"
        } else {
            "frame,time,step,file"
        };
        writeln!(writer, "{header}").map_err(|e| RenderError::io(&path, e))?;
        Ok(FramesCsv { writer, path })
    }

    fn row(&mut self, meta: &FrameMeta, file: &str) -> Result<(), RenderError> {
        let b = meta.b.map_or(String::new(), |(t, s)| format!(",{t},{s}"));
        writeln!(
            self.writer,
            "{},{},{},{}{b}",
            meta.index, meta.time, meta.step, file
        )
        .and_then(|_| self.writer.flush())
        .map_err(|e| RenderError::io(&self.path, e))
    }
}

/// Where the render thread hands finished frames: frames.csv, the PNG encoders and the GIF
/// thread.
struct FrameSink {
    out_dir: PathBuf,
    csv: FramesCsv,
    encoders: SyncSender<EncodeJob>,
    gif: Option<SyncSender<GifFrame>>,
    width: u32,
    height: u32,
    transparent: bool,
}

impl FrameSink {
    fn dispatch(&mut self, meta: FrameMeta, rgba: Vec<u8>) -> Result<(), RenderError> {
        let file = format!("frame_{:05}.png", meta.index);
        self.csv.row(&meta, &file)?;
        let rgba = Arc::new(rgba);
        if let Some(g) = &self.gif {
            g.send(GifFrame {
                rgba: rgba.clone(),
                width: self.width,
                height: self.height,
                transparent: self.transparent,
            })
            .map_err(|_| RenderError::Stopped("GIF writer stopped".into()))?;
        }
        self.encoders
            .send(EncodeJob {
                path: self.out_dir.join(file),
                rgba,
                width: self.width,
                height: self.height,
                transparent: self.transparent,
            })
            .map_err(|_| RenderError::Stopped("PNG encoders stopped".into()))
    }
}

/// The render thread: builds each snapshot's scene, draws it, and reads the previous frame
/// back while the GPU works on this one.
fn render_loop(
    rx: Receiver<Job>,
    mut off: Offscreen,
    opts: &CaptureOptions,
    mut sink: FrameSink,
) -> Result<RenderStats, RenderError> {
    let mut state = FrameState::new(opts);
    let mut stats = RenderStats::default();
    let mut pending: Option<(Pending, FrameMeta)> = None;
    for job in rx {
        let snap = match job {
            Job::One(snap) => snap,
            Job::Pair(a, b) => {
                // Drawn in turn on the one target: the previous frame goes out first.
                if let Some((prev, prev_meta)) = pending.take() {
                    let rgba = off.read(prev)?;
                    sink.dispatch(prev_meta, rgba)?;
                }
                let t0 = Instant::now();
                let (meta, rgba) = pair::render(&mut off, &mut state, opts, &a, &b, stats.frames)?;
                stats.frames += 1;
                stats.busy += t0.elapsed();
                sink.dispatch(meta, rgba)?;
                continue;
            }
        };
        let t0 = Instant::now();
        let (scene, camera) = state.scene(&snap, opts, off.aspect())?;
        let p = off.submit(&scene, &camera)?;
        let meta = FrameMeta {
            index: stats.frames,
            time: snap.time,
            step: snap.step,
            b: None,
        };
        stats.frames += 1;
        // While this frame draws, read back the previous one.
        let previous = pending.replace((p, meta));
        let mut busy = t0.elapsed();
        if let Some((prev, prev_meta)) = previous {
            let t1 = Instant::now();
            let rgba = off.read(prev)?;
            busy += t1.elapsed();
            sink.dispatch(prev_meta, rgba)?;
        }
        stats.busy += busy;
    }
    if let Some((prev, meta)) = pending.take() {
        let t1 = Instant::now();
        let rgba = off.read(prev)?;
        stats.busy += t1.elapsed();
        sink.dispatch(meta, rgba)?;
    }
    Ok(stats)
}
