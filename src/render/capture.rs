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

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use image::ImageEncoder;

use super::camera::{Camera, CameraOverride};
use super::mesh::{self, hex};
use super::offscreen::{Offscreen, Pending};
use super::scene::{BACKGROUND_SRGB, Coloring, Scene, SceneFrame, SceneStyle};
use super::{Gpu, RenderError};
use crate::snapshot::Snapshot;

/// Which box the camera frames.
#[derive(Clone, Debug, PartialEq)]
pub enum Framing {
    /// The blocks of the first snapshot, then fixed: the camera, grid, force scale and
    /// colour-map range do not move between frames.
    FirstFrame,
    /// Re-framed on every snapshot (follows falling blocks, but the view jumps).
    EachFrame,
    /// A fixed box given by the caller (e.g. the scene's full extent).
    Box { lo: [f64; 3], hi: [f64; 3] },
}

/// Settings of a capture.
#[derive(Clone, Debug)]
pub struct CaptureOptions {
    pub out_dir: PathBuf,
    pub width: u32,
    pub height: u32,
    /// Overrides of the automatic camera (`--camera az,el,dist`).
    pub camera: CameraOverride,
    pub framing: Framing,
    pub style: SceneStyle,
    /// Also write `animation.gif`.
    pub gif: bool,
    /// Playback rate of the GIF, frames per second (normally the capture rate, `--fps`).
    pub fps: f64,
    /// GIF frames are downscaled by a whole factor to at most this width (GIF colour
    /// quantisation is slow and files get large at full HD).
    pub gif_max_width: u32,
    /// PNG encoder threads; 0 = one per core beyond the first, at least one.
    pub encoder_threads: usize,
    /// Upper bound on MSAA samples (4 by default; 1 turns antialiasing off, about 3× faster
    /// on the software driver, for quick previews).
    pub max_msaa_samples: u32,
}

impl CaptureOptions {
    /// 1280×720 PNGs into `out_dir`, automatic camera fixed on the first frame.
    pub fn new(out_dir: impl Into<PathBuf>) -> CaptureOptions {
        CaptureOptions {
            out_dir: out_dir.into(),
            width: 1280,
            height: 720,
            camera: CameraOverride::default(),
            framing: Framing::FirstFrame,
            style: SceneStyle::default(),
            gif: false,
            fps: 30.0,
            gif_max_width: 640,
            encoder_threads: 0,
            max_msaa_samples: 4,
        }
    }

    fn validate(&self) -> Result<(), RenderError> {
        if self.width == 0 || self.height == 0 {
            return Err(RenderError::InvalidOptions(format!(
                "image size must be positive, got {}x{}",
                self.width, self.height
            )));
        }
        if self.gif && !(self.fps.is_finite() && self.fps > 0.0) {
            return Err(RenderError::InvalidOptions(format!(
                "GIF frame rate must be positive, got {}",
                self.fps
            )));
        }
        if let Framing::Box { lo, hi } = &self.framing
            && !lo.iter().chain(hi.iter()).all(|v| v.is_finite())
        {
            return Err(RenderError::InvalidOptions(
                "camera box has non-finite corners".into(),
            ));
        }
        Ok(())
    }

    fn encoder_count(&self) -> usize {
        if self.encoder_threads > 0 {
            return self.encoder_threads.min(64);
        }
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        (cores - 1).clamp(1, 8)
    }
}

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

struct EncodeJob {
    path: PathBuf,
    rgba: Arc<Vec<u8>>,
    width: u32,
    height: u32,
    transparent: bool,
}

struct GifFrame {
    rgba: Arc<Vec<u8>>,
    width: u32,
    height: u32,
    transparent: bool,
}

#[derive(Default)]
struct RenderStats {
    frames: usize,
    busy: Duration,
}

/// A running capture. Submit snapshots in time order, then call [`FrameCapture::finish`].
pub struct FrameCapture {
    tx: Option<SyncSender<Snapshot>>,
    render: Option<JoinHandle<Result<RenderStats, RenderError>>>,
    encoders: Vec<JoinHandle<Result<Duration, RenderError>>>,
    gif: Option<JoinHandle<Result<Duration, RenderError>>>,
    /// First error of any worker, so `submit` can report it instead of a bare "closed".
    failure: Arc<Mutex<Option<RenderError>>>,
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

    fn start_on(
        gpu: Gpu,
        opts: CaptureOptions,
        started: Instant,
    ) -> Result<FrameCapture, RenderError> {
        std::fs::create_dir_all(&opts.out_dir).map_err(|e| RenderError::io(&opts.out_dir, e))?;
        let adapter = gpu.adapter_summary();
        let offscreen =
            Offscreen::with_max_samples(gpu, opts.width, opts.height, opts.max_msaa_samples)?;
        let samples = offscreen.samples();
        let csv_path = opts.out_dir.join("frames.csv");
        let mut csv =
            BufWriter::new(File::create(&csv_path).map_err(|e| RenderError::io(&csv_path, e))?);
        writeln!(csv, "frame,time,step,file").map_err(|e| RenderError::io(&csv_path, e))?;

        let failure: Arc<Mutex<Option<RenderError>>> = Arc::new(Mutex::new(None));
        let n_enc = opts.encoder_count();
        // Two frames per encoder in the queue: enough to ride out jitter, and bounded memory
        // (each 1280×720 frame is 3.7 MB).
        let (enc_tx, enc_rx) = mpsc::sync_channel::<EncodeJob>(2 * n_enc);
        let enc_rx = Arc::new(Mutex::new(enc_rx));
        let mut encoders = Vec::with_capacity(n_enc);
        for k in 0..n_enc {
            let rx = enc_rx.clone();
            let failure = failure.clone();
            let h = std::thread::Builder::new()
                .name(format!("dda3d-png-{k}"))
                .spawn(move || {
                    let r = encode_loop(&rx);
                    if let Err(e) = &r {
                        record(&failure, e);
                    }
                    r
                })
                .map_err(|e| RenderError::Stopped(format!("cannot start encoder thread: {e}")))?;
            encoders.push(h);
        }

        let gif_path = opts.gif.then(|| opts.out_dir.join("animation.gif"));
        let (gif_tx, gif) = match &gif_path {
            Some(path) => {
                let (tx, rx) = mpsc::sync_channel::<GifFrame>(4);
                let file = File::create(path).map_err(|e| RenderError::io(path, e))?;
                let (path, fps, max_w) = (path.clone(), opts.fps, opts.gif_max_width);
                let failure = failure.clone();
                let h = std::thread::Builder::new()
                    .name("dda3d-gif".into())
                    .spawn(move || {
                        let r = gif_loop(rx, file, &path, fps, max_w);
                        if let Err(e) = &r {
                            record(&failure, e);
                        }
                        r
                    })
                    .map_err(|e| RenderError::Stopped(format!("cannot start GIF thread: {e}")))?;
                (Some(tx), Some(h))
            }
            None => (None, None),
        };

        // Bounded: the solver may run at most two snapshots ahead of the renderer.
        let (tx, rx) = mpsc::sync_channel::<Snapshot>(2);
        let render = {
            let failure = failure.clone();
            let opts = opts.clone();
            std::thread::Builder::new()
                .name("dda3d-render".into())
                .spawn(move || {
                    let r = render_loop(rx, offscreen, &opts, enc_tx, gif_tx, csv, &csv_path);
                    if let Err(e) = &r {
                        record(&failure, e);
                    }
                    r
                })
                .map_err(|e| RenderError::Stopped(format!("cannot start render thread: {e}")))?
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
        let Some(tx) = &self.tx else {
            return Err(RenderError::Stopped("capture already finished".into()));
        };
        let t = Instant::now();
        let sent = tx.send(snapshot);
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
        match tx.try_send(snapshot) {
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

/// Keeps camera, grid, force scale and colour range fixed across frames (unless framing is
/// per frame), so a sequence compares frame to frame.
struct FrameState {
    frame: Option<SceneFrame>,
    style: SceneStyle,
    field_max: f64,
}

impl FrameState {
    fn new(opts: &CaptureOptions) -> FrameState {
        FrameState {
            frame: match &opts.framing {
                Framing::Box { lo, hi } => Some(SceneFrame::from_box(*lo, *hi)),
                _ => None,
            },
            style: opts.style.clone(),
            field_max: 0.0,
        }
    }

    fn scene(
        &mut self,
        snap: &Snapshot,
        opts: &CaptureOptions,
        aspect: f32,
    ) -> Result<(Scene, Camera), RenderError> {
        let fixed = opts.framing != Framing::EachFrame;
        let frame = if fixed {
            *self
                .frame
                .get_or_insert_with(|| SceneFrame::of_snapshot(snap))
        } else {
            SceneFrame::of_snapshot(snap)
        };
        if fixed && opts.style.field_range.is_none() && opts.style.coloring != Coloring::PerBlock {
            // The colour range only grows, so a colour means the same speed in later frames.
            self.field_max = self.field_max.max(field_max(snap, opts.style.coloring));
            if self.field_max > 0.0 {
                self.style.field_range = Some((0.0, self.field_max));
            }
        }
        let scene = Scene::build(snap, &self.style, &frame)?;
        if fixed && self.style.force_scale.is_none() {
            // The first frame with contacts sets the arrow scale for the rest of the run.
            self.style.force_scale = scene.force_scale;
        }
        Ok((scene, frame.camera(aspect, &opts.camera)))
    }
}

/// Largest colour-map value among the moving blocks of a snapshot.
fn field_max(snap: &Snapshot, coloring: Coloring) -> f64 {
    snap.blocks
        .iter()
        .filter(|b| !b.fixed)
        .map(|b| match coloring {
            Coloring::Velocity => glam::DVec3::from_array(b.velocity).length(),
            Coloring::Displacement => glam::DVec3::from_array(b.displacement).length(),
            Coloring::PerBlock => 0.0,
        })
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
}

struct FrameMeta {
    index: usize,
    time: f64,
    step: u64,
}

#[allow(clippy::too_many_arguments)]
fn render_loop(
    rx: Receiver<Snapshot>,
    mut off: Offscreen,
    opts: &CaptureOptions,
    enc_tx: SyncSender<EncodeJob>,
    gif_tx: Option<SyncSender<GifFrame>>,
    mut csv: BufWriter<File>,
    csv_path: &Path,
) -> Result<RenderStats, RenderError> {
    let mut state = FrameState::new(opts);
    let mut stats = RenderStats::default();
    let mut pending: Option<(Pending, FrameMeta)> = None;
    let (width, height) = off.size();
    let transparent = opts.style.transparent;

    // Hands a finished frame to the encoders and the GIF thread and logs it in frames.csv.
    let mut dispatch = |meta: FrameMeta, rgba: Vec<u8>| -> Result<(), RenderError> {
        let file = format!("frame_{:05}.png", meta.index);
        writeln!(csv, "{},{},{},{}", meta.index, meta.time, meta.step, file)
            .and_then(|_| csv.flush())
            .map_err(|e| RenderError::io(csv_path, e))?;
        let rgba = Arc::new(rgba);
        if let Some(g) = &gif_tx {
            g.send(GifFrame {
                rgba: rgba.clone(),
                width,
                height,
                transparent,
            })
            .map_err(|_| RenderError::Stopped("GIF writer stopped".into()))?;
        }
        enc_tx
            .send(EncodeJob {
                path: opts.out_dir.join(file),
                rgba,
                width,
                height,
                transparent,
            })
            .map_err(|_| RenderError::Stopped("PNG encoders stopped".into()))
    };

    for snap in rx {
        let t0 = Instant::now();
        let (scene, camera) = state.scene(&snap, opts, off.aspect())?;
        let p = off.submit(&scene, &camera)?;
        let meta = FrameMeta {
            index: stats.frames,
            time: snap.time,
            step: snap.step,
        };
        stats.frames += 1;
        // While this frame draws, read back the previous one.
        let previous = pending.replace((p, meta));
        let mut busy = t0.elapsed();
        if let Some((prev, prev_meta)) = previous {
            let t1 = Instant::now();
            let rgba = off.read(prev)?;
            busy += t1.elapsed();
            dispatch(prev_meta, rgba)?;
        }
        stats.busy += busy;
    }
    if let Some((prev, meta)) = pending.take() {
        let t1 = Instant::now();
        let rgba = off.read(prev)?;
        stats.busy += t1.elapsed();
        dispatch(meta, rgba)?;
    }
    Ok(stats)
}

fn encode_loop(rx: &Mutex<Receiver<EncodeJob>>) -> Result<Duration, RenderError> {
    let mut total = Duration::ZERO;
    loop {
        // The lock is held only while waiting for a job, not while encoding.
        let job = match rx.lock() {
            Ok(r) => r.recv(),
            Err(_) => return Err(RenderError::Stopped("encoder queue poisoned".into())),
        };
        let Ok(job) = job else {
            return Ok(total);
        };
        let t = Instant::now();
        write_png(&job.path, &job.rgba, job.width, job.height, job.transparent)?;
        total += t.elapsed();
    }
}

/// Writes RGBA pixels as read back from the GPU to a PNG: RGB when opaque (smaller, faster);
/// with `transparent`, RGBA with the GPU's premultiplied alpha converted to straight alpha.
pub fn write_png(
    path: &Path,
    rgba: &[u8],
    width: u32,
    height: u32,
    transparent: bool,
) -> Result<(), RenderError> {
    let expected = width as usize * height as usize * 4;
    if rgba.len() != expected {
        return Err(RenderError::Encode(format!(
            "{}: have {} bytes for a {width}x{height} RGBA image (need {expected})",
            path.display(),
            rgba.len()
        )));
    }
    let file = File::create(path).map_err(|e| RenderError::io(path, e))?;
    let mut out = BufWriter::new(file);
    let encoder = image::codecs::png::PngEncoder::new(&mut out);
    let result = if transparent {
        let mut straight = rgba.to_vec();
        unpremultiply(&mut straight);
        encoder.write_image(&straight, width, height, image::ExtendedColorType::Rgba8)
    } else {
        let rgb: Vec<u8> = rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        encoder.write_image(&rgb, width, height, image::ExtendedColorType::Rgb8)
    };
    result.map_err(|e| RenderError::Encode(format!("{}: {e}", path.display())))?;
    out.flush().map_err(|e| RenderError::io(path, e))
}

fn srgb_lut() -> &'static [f32; 256] {
    static LUT: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    LUT.get_or_init(|| {
        let mut t = [0.0; 256];
        for (k, v) in t.iter_mut().enumerate() {
            *v = mesh::srgb_to_linear([k as f32 / 255.0, 0.0, 0.0, 1.0])[0];
        }
        t
    })
}

fn encode_srgb(linear: f32) -> u8 {
    (mesh::linear_to_srgb([linear, 0.0, 0.0, 1.0])[0] * 255.0).round() as u8
}

/// Premultiplied (in linear light, sRGB-encoded) → straight alpha, in place. Only partly
/// covered pixels (antialiased edges, translucent overlay) change.
pub fn unpremultiply(rgba: &mut [u8]) {
    let lut = srgb_lut();
    for p in rgba.chunks_exact_mut(4) {
        let a = p[3];
        if a == 0 || a == 255 {
            continue;
        }
        let af = a as f32 / 255.0;
        for c in &mut p[..3] {
            *c = encode_srgb((lut[*c as usize] / af).min(1.0));
        }
    }
}

/// Composites premultiplied pixels over the opaque background (for GIF, which has only
/// on/off transparency).
fn composite_over_background(rgba: &mut [u8]) {
    let lut = srgb_lut();
    let bg = mesh::srgb_to_linear(hex(BACKGROUND_SRGB));
    for p in rgba.chunks_exact_mut(4) {
        let a = p[3];
        if a == 255 {
            continue;
        }
        let rest = 1.0 - a as f32 / 255.0;
        for k in 0..3 {
            p[k] = encode_srgb(lut[p[k] as usize] + bg[k] * rest);
        }
        p[3] = 255;
    }
}

/// Box-filter downscale of RGBA by a whole factor.
fn downscale(rgba: &[u8], width: u32, height: u32, factor: u32) -> (Vec<u8>, u32, u32) {
    if factor <= 1 {
        return (rgba.to_vec(), width, height);
    }
    let (w, h) = ((width / factor).max(1), (height / factor).max(1));
    let mut out = vec![0u8; (w * h * 4) as usize];
    let n = factor * factor;
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0u32; 4];
            for dy in 0..factor {
                let row = ((y * factor + dy).min(height - 1) * width) as usize;
                for dx in 0..factor {
                    let i = (row + (x * factor + dx).min(width - 1) as usize) * 4;
                    for k in 0..4 {
                        acc[k] += rgba[i + k] as u32;
                    }
                }
            }
            let o = ((y * w + x) * 4) as usize;
            for k in 0..4 {
                out[o + k] = ((acc[k] + n / 2) / n) as u8;
            }
        }
    }
    (out, w, h)
}

fn gif_loop(
    rx: Receiver<GifFrame>,
    file: File,
    path: &Path,
    fps: f64,
    max_width: u32,
) -> Result<Duration, RenderError> {
    use image::codecs::gif::{GifEncoder, Repeat};
    let mut total = Duration::ZERO;
    // Speed 10 of 1–30: close to the best palette at a fraction of the time of speed 1.
    let mut enc = GifEncoder::new_with_speed(BufWriter::new(file), 10);
    let err = |e: image::ImageError| RenderError::Encode(format!("{}: {e}", path.display()));
    enc.set_repeat(Repeat::Infinite).map_err(err)?;
    let delay = image::Delay::from_saturating_duration(Duration::from_secs_f64(1.0 / fps));
    for f in rx {
        let t = Instant::now();
        let factor = f.width.div_ceil(max_width.max(1)).max(1);
        let (mut px, w, h) = downscale(&f.rgba, f.width, f.height, factor);
        drop(f.rgba);
        if f.transparent {
            composite_over_background(&mut px);
        }
        let img = image::RgbaImage::from_raw(w, h, px)
            .ok_or_else(|| RenderError::Encode("GIF frame has the wrong size".into()))?;
        enc.encode_frame(image::Frame::from_parts(img, 0, 0, delay))
            .map_err(err)?;
        total += t.elapsed();
    }
    drop(enc);
    Ok(total)
}

/// Renders one snapshot to a PNG (a screenshot for a report) with the same look as a
/// capture. Returns the camera used, so callers can relate world points to pixels.
pub fn render_to_png(
    snapshot: &Snapshot,
    opts: &CaptureOptions,
    path: &Path,
) -> Result<Camera, RenderError> {
    opts.validate()?;
    let gpu = Gpu::headless()?;
    let mut off = Offscreen::with_max_samples(gpu, opts.width, opts.height, opts.max_msaa_samples)?;
    let (rgba, camera) = render_rgba(&mut off, snapshot, opts)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| RenderError::io(dir, e))?;
    }
    write_png(path, &rgba, opts.width, opts.height, opts.style.transparent)?;
    Ok(camera)
}

/// Renders one snapshot on an existing off-screen target; returns RGBA (premultiplied when
/// transparent) and the camera.
pub fn render_rgba(
    off: &mut Offscreen,
    snapshot: &Snapshot,
    opts: &CaptureOptions,
) -> Result<(Vec<u8>, Camera), RenderError> {
    let mut state = FrameState::new(opts);
    let (scene, camera) = state.scene(snapshot, opts, off.aspect())?;
    let rgba = off.render(&scene, &camera)?;
    Ok((rgba, camera))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unpremultiply_restores_colour() {
        // Half-covered pure red over transparent: premultiplied linear red = 0.5.
        let half = encode_srgb(0.5);
        let mut px = vec![half, 0, 0, 128, 10, 20, 30, 255, 0, 0, 0, 0];
        unpremultiply(&mut px);
        assert!(px[0] >= 254, "{}", px[0]);
        assert_eq!(&px[4..8], &[10, 20, 30, 255]);
        assert_eq!(&px[8..12], &[0, 0, 0, 0]);
    }

    #[test]
    fn downscale_averages() {
        let px: Vec<u8> = [0u8, 0, 0, 255, 200, 200, 200, 255].repeat(2);
        let (out, w, h) = downscale(&px, 2, 2, 2);
        assert_eq!((w, h), (1, 1));
        assert_eq!(out, vec![100, 100, 100, 255]);
    }

    #[test]
    fn options_are_checked() {
        let mut o = CaptureOptions::new("/tmp/x");
        o.width = 0;
        assert!(matches!(o.validate(), Err(RenderError::InvalidOptions(_))));
        let mut o = CaptureOptions::new("/tmp/x");
        o.gif = true;
        o.fps = 0.0;
        assert!(o.validate().is_err());
        assert!(CaptureOptions::new("/tmp/x").encoder_count() >= 1);
    }

    #[test]
    fn png_size_mismatch_is_an_error() {
        let dir = std::env::temp_dir().join(format!("dda3d-png-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let e = write_png(&dir.join("x.png"), &[0; 10], 2, 2, false);
        assert!(matches!(e, Err(RenderError::Encode(_))));
        write_png(&dir.join("ok.png"), &[7; 16], 2, 2, true).unwrap();
        let img = image::open(dir.join("ok.png")).unwrap();
        assert_eq!((img.width(), img.height()), (2, 2));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
