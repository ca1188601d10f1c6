//! Saving what the window shows:
//! - `--screenshot`: the whole window (3-D view and panels) on the last frame. egui draws the
//!   frame a second time into a texture of the surface's format, which is read back, because
//!   reading the surface itself works on Vulkan only (not on GL); the result is the same pixels
//!   on every backend;
//! - the screenshot button: the 3-D view at window size through the `render` command's
//!   off-screen path (4× MSAA);
//! - recordings: every new step through the `render` command's capture pipeline.
//!
//! The slow parts run on worker threads, which report back through [`Background`] and wake the
//! window.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, Sender};

use winit::event_loop::EventLoopProxy;

use super::Wake;
use crate::render::capture::write_png;
use crate::render::offscreen::{ChannelOrder, Readback, readable_target};
use crate::render::{
    CameraOverride, CaptureOptions, FrameCapture, Framing, Gpu, Offscreen, RenderError,
};
use crate::viewer::ViewerError;
use crate::viewer::state::{RecordingInfo, UiState};

/// Results of work done off the window thread.
enum Background {
    Screenshot(Result<PathBuf, RenderError>),
    RecordFinished(Result<(usize, PathBuf), RenderError>),
}

/// A recording in progress.
struct Recording {
    capture: FrameCapture,
    /// (generation, step) of the last snapshot submitted, so each step is written once.
    last: Option<(u64, u64)>,
}

/// The screenshots and recordings of one window.
pub(super) struct Capture {
    /// Where the screenshot button and recordings write.
    out_dir: PathBuf,
    /// `--screenshot`: the PNG the whole window is written to on the last frame.
    window_png: Option<PathBuf>,
    recording: Option<Recording>,
    bg_tx: Sender<Background>,
    bg_rx: Receiver<Background>,
    proxy: EventLoopProxy<Wake>,
}

impl Capture {
    pub fn new(
        out_dir: PathBuf,
        window_png: Option<PathBuf>,
        proxy: EventLoopProxy<Wake>,
    ) -> Capture {
        let (bg_tx, bg_rx) = mpsc::channel();
        Capture {
            out_dir,
            window_png,
            recording: None,
            bg_tx,
            bg_rx,
            proxy,
        }
    }

    pub fn is_recording(&self) -> bool {
        self.recording.is_some()
    }

    /// A second target for this frame's egui drawing when `--screenshot` asked for the window.
    pub fn window_shot(
        &self,
        gpu: &Gpu,
        format: wgpu::TextureFormat,
        (width, height): (u32, u32),
    ) -> Result<Option<WindowCapture>, ViewerError> {
        self.window_png
            .as_ref()
            .map(|path| WindowCapture::new(gpu, format, width, height, path.clone()))
            .transpose()
    }

    /// The screenshot button: the 3-D view at `size` on a worker thread, so the window does not
    /// stall.
    pub fn screenshot_view(&self, gpu: &Gpu, ui: &mut UiState, (w, h): (u32, u32)) {
        let Some(scene) = ui.scene.clone() else {
            ui.error("nothing to draw yet");
            return;
        };
        let mut camera = ui.view.camera.clone();
        camera.aspect = w as f32 / h as f32;
        let step = ui.frame.as_ref().map_or(0, |f| f.snapshot.step);
        let path = unused_path(&self.out_dir, &format!("screenshot_step{step:06}"), "png");
        let gpu = gpu.clone();
        let tx = self.bg_tx.clone();
        let proxy = self.proxy.clone();
        ui.info("writing screenshot...");
        let spawned = std::thread::Builder::new()
            .name("dda3d-screenshot".into())
            .spawn(move || {
                let r = (|| {
                    if let Some(dir) = path.parent() {
                        crate::render::capture::create_output_dir(dir)?;
                    }
                    let mut off = Offscreen::new(gpu, w, h)?;
                    let rgba = off.render(&scene, &camera)?;
                    write_png(&path, &rgba, w, h, false)?;
                    Ok(path)
                })();
                let _ = tx.send(Background::Screenshot(r));
                let _ = proxy.send_event(Wake);
            });
        if let Err(e) = spawned {
            ui.error(format!("cannot start the screenshot thread: {e}"));
        }
    }

    /// The record button: starts a recording of the view as it is now (camera, framing, style,
    /// `size`, `samples`), or finishes the one in progress.
    pub fn toggle_record(&mut self, gpu: &Gpu, ui: &mut UiState, size: (u32, u32), samples: u32) {
        if let Some(rec) = self.recording.take() {
            ui.recording = None;
            ui.info("finishing recording...");
            let tx = self.bg_tx.clone();
            let proxy = self.proxy.clone();
            // Finishing waits for the PNG encoders; keep that off the window thread.
            let _ = std::thread::Builder::new()
                .name("dda3d-record-finish".into())
                .spawn(move || {
                    let r = rec.capture.finish().map(|r| (r.frames, r.out_dir));
                    let _ = tx.send(Background::RecordFinished(r));
                    let _ = proxy.send_event(Wake);
                });
            return;
        }
        let dir = unused_path(&self.out_dir, "record", "");
        let opts = recording_options(ui, &dir, size, samples);
        match FrameCapture::start_with_gpu(gpu.clone(), opts) {
            Ok(capture) => {
                ui.recording = Some(RecordingInfo {
                    dir: dir.clone(),
                    frames: 0,
                });
                self.recording = Some(Recording {
                    capture,
                    last: None,
                });
                ui.info(format!("recording to {}", dir.display()));
            }
            Err(e) => ui.error(format!("cannot record: {e}")),
        }
    }

    /// Hands each new step to the recorder; a step that arrives while the recorder is busy is
    /// skipped rather than stalling the window.
    pub fn record_frame(&mut self, ui: &mut UiState) {
        let (Some(rec), Some(frame)) = (&mut self.recording, &ui.frame) else {
            return;
        };
        let key = (frame.generation, frame.snapshot.step);
        if rec.last == Some(key) {
            return;
        }
        match rec.capture.try_submit((*frame.snapshot).clone()) {
            Ok(true) => {
                rec.last = Some(key);
                if let Some(info) = &mut ui.recording {
                    info.frames = rec.capture.submitted();
                }
            }
            Ok(false) => {}
            Err(e) => {
                self.recording = None;
                ui.recording = None;
                ui.error(format!("recording stopped: {e}"));
            }
        }
    }

    /// Shows what the worker threads finished since the last frame.
    pub fn poll_background(&self, ui: &mut UiState) {
        while let Ok(b) = self.bg_rx.try_recv() {
            match b {
                Background::Screenshot(Ok(p)) => ui.info(format!("wrote {}", p.display())),
                Background::Screenshot(Err(e)) => ui.error(format!("screenshot failed: {e}")),
                Background::RecordFinished(Ok((n, dir))) => {
                    ui.info(format!("wrote {n} frames to {}", dir.display()))
                }
                Background::RecordFinished(Err(e)) => ui.error(format!("recording failed: {e}")),
            }
        }
    }
}

/// The capture pipeline's options for a recording into `dir` that looks like the view now.
fn recording_options(ui: &UiState, dir: &Path, (w, h): (u32, u32), samples: u32) -> CaptureOptions {
    let cam = &ui.view.camera;
    let target = cam.origin + cam.target.as_dvec3();
    let mut opts = CaptureOptions::new(dir);
    opts.width = w;
    opts.height = h;
    opts.camera = CameraOverride {
        azimuth_deg: Some(cam.azimuth.to_degrees()),
        elevation_deg: Some(cam.elevation.to_degrees()),
        distance: Some(cam.distance),
        target: Some(target.to_array()),
        fov_y_deg: Some(cam.fov_y.to_degrees()),
    };
    let f = ui.scene_frame;
    opts.framing = Framing::Box {
        lo: f.lo.to_array(),
        hi: f.hi.to_array(),
    };
    opts.style = ui.style();
    opts.max_msaa_samples = samples;
    opts
}

/// `--screenshot`: a texture of the surface's format and size that egui draws into a second
/// time, and its readback.
pub(super) struct WindowCapture {
    texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    readback: Readback,
    path: PathBuf,
}

impl WindowCapture {
    fn new(
        gpu: &Gpu,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
        path: PathBuf,
    ) -> Result<WindowCapture, ViewerError> {
        let order = ChannelOrder::of(format).ok_or_else(|| {
            ViewerError::Failed(format!(
                "{}: {}",
                path.display(),
                RenderError::InvalidOptions(format!(
                    "window format {format:?} cannot be saved as PNG"
                ))
            ))
        })?;
        let texture = readable_target(&gpu.device, "dda3d window capture", format, width, height);
        let view = texture.create_view(&Default::default());
        let readback = Readback::new(&gpu.device, "dda3d window readback", order, width, height);
        Ok(WindowCapture {
            texture,
            view,
            readback,
            path,
        })
    }

    /// Records the copy of the drawn texture for reading back.
    pub fn copy(&self, encoder: &mut wgpu::CommandEncoder) {
        self.readback.copy_from(encoder, &self.texture);
    }

    /// Waits for the copy and writes the PNG (once the frame has been submitted).
    pub fn save(self, gpu: &Gpu) -> Result<(), ViewerError> {
        let (w, h) = (self.texture.width(), self.texture.height());
        let rgba = self
            .read(gpu)
            .map_err(|e| ViewerError::Failed(format!("{}: {e}", self.path.display())))?;
        write_png(&self.path, &rgba, w, h, false)
            .map_err(|e| ViewerError::Failed(e.to_string()))?;
        eprintln!("wrote {} ({w}x{h})", self.path.display());
        Ok(())
    }

    fn read(&self, gpu: &Gpu) -> Result<Vec<u8>, RenderError> {
        let mapping = self.readback.map();
        let mut px = self.readback.read(&gpu.device, mapping, None)?;
        // The window is opaque whatever the surface's alpha says.
        for p in px.chunks_exact_mut(4) {
            p[3] = 255;
        }
        gpu.take_error()?;
        Ok(px)
    }
}

/// `dir/stem_NNN.ext` (or `dir/stem_NNN` when `ext` is empty) with the first unused NNN.
fn unused_path(dir: &Path, stem: &str, ext: &str) -> PathBuf {
    for n in 1..10_000 {
        let name = if ext.is_empty() {
            format!("{stem}_{n:03}")
        } else {
            format!("{stem}_{n:03}.{ext}")
        };
        let p = dir.join(name);
        if !p.exists() {
            return p;
        }
    }
    dir.join(format!("{stem}.{ext}"))
}
