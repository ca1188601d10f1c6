//! The window: winit event loop, wgpu surface, egui, and the frame loop.
//!
//! Each frame:
//! 1. take the newest [`Frame`](super::sim::Frame) from the simulation thread (never waiting);
//! 2. run the egui UI ([`panels::build`]), which handles camera input and lays out the 3-D view;
//! 3. draw the 3-D scene into the view's own texture (`Rgba8Unorm`, which egui can sample and
//!    the renderer handles by encoding sRGB in its shader), sized to the view in pixels;
//! 4. draw egui (panels and the view image) into the window surface.
//!
//! The whole-window screenshot (`--screenshot`) draws step 4 a second time into a texture of
//! the surface's format and reads that back, because reading the surface itself works on
//! Vulkan only (not on GL); the result is the same pixels on every backend.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, Sender};
use std::time::{Duration, Instant};

use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::window::{Window, WindowId};

use super::painter::{EguiPainter, Screen};
use super::panels;
use super::sim::{Command, RunState, SimHandle, Speed, StepRecord};
use super::state::{Action, RecordingInfo, UiState};
use crate::cli::CliError;
use crate::render::capture::write_png;
use crate::render::offscreen::{padded_bytes_per_row, strip_row_padding};
use crate::render::{
    CameraOverride, CaptureOptions, FrameCapture, Framing, Gpu, Offscreen, RenderError,
    RenderTargets, Renderer,
};
use crate::scene::Scene as SceneFile;

/// What `dda3d view` asked for.
pub struct Options {
    pub scene: SceneFile,
    pub size: (u32, u32),
    pub speed: Speed,
    pub play: bool,
    pub screenshot: Option<PathBuf>,
    pub exit_after_frames: Option<u64>,
    pub msaa: Option<u32>,
    pub out_dir: PathBuf,
}

/// On a software rasterizer, drawing competes with the solver for the same cores: animation is
/// capped at 40 frames/s there, which keeps the window above 30 frames/s while the solver gets the
/// time between frames. GPUs are paced by vsync instead.
const CPU_FRAME_INTERVAL: Duration = Duration::from_millis(25);

/// Sent to the event loop to wake it (a new simulation frame, a background job done).
#[derive(Debug, Clone, Copy)]
struct Wake;

/// Opens the window and runs until it is closed (or `--exit-after-frames`).
pub fn run(opts: Options) -> Result<(), CliError> {
    let event_loop = EventLoop::<Wake>::with_user_event().build().map_err(|e| {
        let no_display = ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"]
            .iter()
            .all(|v| std::env::var_os(v).is_none_or(|s| s.is_empty()));
        CliError::Run(if no_display {
            "cannot open a window: no X11 or Wayland display (DISPLAY and WAYLAND_DISPLAY \
                 are not set); for a virtual one, run under xvfb-run"
                .into()
        } else {
            format!("cannot open a window: {e}")
        })
    })?;
    let proxy = event_loop.create_proxy();
    let mut app = App {
        opts: Some(opts),
        proxy,
        viewer: None,
        result: Ok(()),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| CliError::Run(format!("window event loop failed: {e}")))?;
    // Stop the simulation and finish any recording before reporting.
    drop(app.viewer.take());
    app.result
}

struct App {
    opts: Option<Options>,
    proxy: EventLoopProxy<Wake>,
    viewer: Option<Viewer>,
    result: Result<(), CliError>,
}

impl App {
    fn fail(&mut self, el: &ActiveEventLoop, e: CliError) {
        if self.result.is_ok() {
            self.result = Err(e);
        }
        el.exit();
    }
}

impl ApplicationHandler<Wake> for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.viewer.is_some() {
            return;
        }
        let Some(opts) = self.opts.take() else {
            return;
        };
        match Viewer::new(el, opts, self.proxy.clone()) {
            Ok(v) => {
                v.window.request_redraw();
                self.viewer = Some(v);
            }
            Err(e) => self.fail(el, e),
        }
    }

    fn user_event(&mut self, _el: &ActiveEventLoop, _event: Wake) {
        if let Some(v) = &mut self.viewer {
            v.wake();
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(v) = self.viewer.as_mut() else {
            return;
        };
        match &event {
            WindowEvent::CloseRequested => {
                el.exit();
                return;
            }
            WindowEvent::Resized(size) => v.resize(*size),
            WindowEvent::RedrawRequested => {
                match v.redraw() {
                    Ok(Flow::Continue) => {}
                    Ok(Flow::Exit) => el.exit(),
                    Err(e) => self.fail(el, e),
                }
                return;
            }
            _ => {}
        }
        let r = v.egui_state.on_window_event(&v.window, &event);
        if r.repaint {
            v.window.request_redraw();
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        let Some(v) = &self.viewer else {
            return;
        };
        match v.next_repaint {
            Some(t) if t <= Instant::now() => {
                v.window.request_redraw();
                el.set_control_flow(ControlFlow::Wait);
            }
            Some(t) => el.set_control_flow(ControlFlow::WaitUntil(t)),
            None => el.set_control_flow(ControlFlow::Wait),
        }
    }
}

enum Flow {
    Continue,
    Exit,
}

/// Results of work done off the window thread.
enum Background {
    Screenshot(Result<PathBuf, RenderError>),
    RecordFinished(Result<(usize, PathBuf), RenderError>),
}

/// The 3-D view's render target: a colour texture egui samples, plus the renderer's MSAA and
/// depth attachments.
struct ViewTarget {
    renderer: Renderer,
    targets: RenderTargets,
    view: wgpu::TextureView,
    id: egui::TextureId,
    size: (u32, u32),
    /// (scene version, camera, size) of the picture in the texture.
    drawn: Option<(u64, crate::render::Camera, (u32, u32))>,
}

/// The colour format of the view texture: non-sRGB like the window (the renderer then encodes
/// sRGB in its shader), so egui shows its bytes as they are.
const VIEW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

impl ViewTarget {
    fn new(gpu: &Gpu, egui: &mut EguiPainter, samples: u32) -> ViewTarget {
        let renderer = Renderer::with_max_samples(gpu, VIEW_FORMAT, samples);
        let (targets, view) = Self::textures(gpu, &renderer, 1, 1);
        let id = egui.register_native_texture(&gpu.device, &view);
        ViewTarget {
            renderer,
            targets,
            view,
            id,
            size: (1, 1),
            drawn: None,
        }
    }

    fn textures(
        gpu: &Gpu,
        renderer: &Renderer,
        w: u32,
        h: u32,
    ) -> (RenderTargets, wgpu::TextureView) {
        let targets = renderer.create_targets(&gpu.device, w, h);
        let tex = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("dda3d view"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: VIEW_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        (targets, tex.create_view(&Default::default()))
    }

    fn resize(&mut self, gpu: &Gpu, egui: &mut EguiPainter, w: u32, h: u32) {
        let max = gpu.device.limits().max_texture_dimension_2d;
        let (w, h) = (w.clamp(1, max), h.clamp(1, max));
        if (w, h) == self.size {
            return;
        }
        let (targets, view) = Self::textures(gpu, &self.renderer, w, h);
        egui.update_native_texture(&gpu.device, &view, self.id);
        self.targets = targets;
        self.view = view;
        self.size = (w, h);
        self.drawn = None;
    }
}

struct Viewer {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The format egui draws in: the surface's, or its non-sRGB view.
    render_format: wgpu::TextureFormat,
    gpu: Gpu,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_painter: EguiPainter,
    view: ViewTarget,
    sim: SimHandle,
    ui: UiState,
    records: Vec<StepRecord>,
    frames: u64,
    started: Instant,
    exit_after: Option<u64>,
    screenshot: Option<PathBuf>,
    out_dir: PathBuf,
    next_repaint: Option<Instant>,
    bg_tx: Sender<Background>,
    bg_rx: Receiver<Background>,
    proxy: EventLoopProxy<Wake>,
    recording: Option<Recording>,
    /// The steps/s of the last frame that had the solver running (for the exit report).
    last_steps_per_second: f64,
    /// Animation frames are not started more often than this (software rasterizers only).
    min_frame_interval: Option<Duration>,
}

struct Recording {
    capture: FrameCapture,
    /// (generation, step) of the last snapshot submitted, so each step is written once.
    last: Option<(u64, u64)>,
}

impl Viewer {
    fn new(
        el: &ActiveEventLoop,
        opts: Options,
        proxy: EventLoopProxy<Wake>,
    ) -> Result<Viewer, CliError> {
        let attrs = Window::default_attributes()
            .with_title(format!("dda3d — {}", opts.scene.name))
            .with_inner_size(PhysicalSize::new(opts.size.0, opts.size.1))
            .with_min_inner_size(PhysicalSize::new(640, 400));
        let window = Arc::new(
            el.create_window(attrs)
                .map_err(|e| CliError::Run(format!("cannot create a window: {e}")))?,
        );
        let instance = wgpu::Instance::new(
            wgpu::InstanceDescriptor::new_with_display_handle(Box::new(el.owned_display_handle()))
                .with_env(),
        );
        let surface = match instance.create_surface(window.clone()) {
            Ok(s) => s,
            Err(e) => {
                // With no usable backend at all, say what to install, as `render` does.
                let any = pollster::block_on(
                    instance.request_adapter(&wgpu::RequestAdapterOptions::default()),
                );
                return Err(match any {
                    Err(_) => CliError::Input(RenderError::NoAdapter.to_string()),
                    Ok(_) => CliError::Run(format!("cannot draw into the window: {e}")),
                });
            }
        };
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|_| CliError::Input(RenderError::NoAdapter.to_string()))?;
        let gpu = Gpu::from_adapter(instance, adapter).map_err(|e| CliError::Run(e.to_string()))?;

        let caps = surface.get_capabilities(&gpu.adapter);
        // egui blends in gamma space and wants a non-sRGB target; take one if the surface
        // offers it, else draw through a non-sRGB view of an sRGB surface.
        let (format, render_format) = match caps.formats.iter().copied().find(|f| {
            matches!(
                f,
                wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
            )
        }) {
            Some(f) => (f, f),
            None => {
                let f = *caps.formats.first().ok_or_else(|| {
                    CliError::Run(format!(
                        "the GPU ({}) cannot draw into this window",
                        gpu.adapter_summary()
                    ))
                })?;
                (f, f.remove_srgb_suffix())
            }
        };
        // 4× MSAA costs about three times as much per frame on a software rasterizer, where
        // the window must stay interactive; real GPUs get it for free.
        let cpu = gpu.adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let samples = opts.msaa.unwrap_or(if cpu { 1 } else { 4 });
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            // A software rasterizer rarely makes a 60 Hz deadline; with vsync a 20 ms frame
            // would wait for the next vblank and show at 30 fps. On a GPU, vsync.
            present_mode: if cpu {
                wgpu::PresentMode::AutoNoVsync
            } else {
                wgpu::PresentMode::AutoVsync
            },
            color_space: Default::default(),
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: if render_format != format {
                vec![render_format]
            } else {
                vec![]
            },
        };
        surface.configure(&gpu.device, &config);

        let egui_ctx = egui::Context::default();
        setup_style(&egui_ctx);
        let max_tex = gpu.device.limits().max_texture_dimension_2d as usize;
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_tex),
        );
        let mut egui_painter = EguiPainter::new(&gpu.device, render_format);
        let view = ViewTarget::new(&gpu, &mut egui_painter, samples);
        let adapter = format!(
            "{}, {}× MSAA",
            gpu.adapter_summary(),
            view.renderer.samples()
        );

        let scene = opts.scene;
        let waker = {
            let proxy = proxy.clone();
            Box::new(move || {
                let _ = proxy.send_event(Wake);
            })
        };
        let sim = SimHandle::spawn(
            scene.model.clone(),
            scene.params.clone(),
            opts.speed,
            opts.play,
            waker,
        )
        .map_err(|e| CliError::Run(format!("cannot start the simulation thread: {e}")))?;
        let first = sim
            .latest()
            .ok_or_else(|| CliError::Run("the simulation published no state".into()))?;
        let ui = UiState::new(&scene, &first.snapshot, adapter);
        let (bg_tx, bg_rx) = mpsc::channel();
        Ok(Viewer {
            window,
            surface,
            config,
            render_format,
            gpu,
            egui_ctx,
            egui_state,
            egui_painter,
            view,
            sim,
            ui,
            records: Vec::new(),
            frames: 0,
            started: Instant::now(),
            exit_after: opts.exit_after_frames,
            screenshot: opts.screenshot,
            out_dir: opts.out_dir,
            next_repaint: None,
            bg_tx,
            bg_rx,
            proxy,
            recording: None,
            last_steps_per_second: 0.0,
            min_frame_interval: cpu.then_some(CPU_FRAME_INTERVAL),
        })
    }

    /// A new simulation frame or a finished background job: draw it, but no sooner than the
    /// frame cap allows.
    fn wake(&mut self) {
        match (self.min_frame_interval, self.ui.perf.last_start()) {
            (Some(min), Some(last)) if last.elapsed() < min => {
                let at = last + min;
                self.next_repaint = Some(self.next_repaint.map_or(at, |t| t.min(at)));
            }
            _ => self.window.request_redraw(),
        }
    }

    fn resize(&mut self, size: PhysicalSize<u32>) {
        if size.width == 0 || size.height == 0 {
            return; // minimised
        }
        self.config.width = size.width;
        self.config.height = size.height;
        self.surface.configure(&self.gpu.device, &self.config);
        self.window.request_redraw();
    }

    fn redraw(&mut self) -> Result<Flow, CliError> {
        let started = self.ui.perf.frame_started();
        let mut tm = Timing::new();
        self.next_repaint = None;

        // 1. Newest simulation state (never waits).
        let frame = self.sim.latest();
        self.sim.drain_records(&mut self.records);
        self.ui.update(frame, &mut self.records);
        self.poll_background();
        self.record_frame();

        tm.mark("sim");
        // 2. UI.
        let raw = self.egui_state.take_egui_input(&self.window);
        let texture = self.view.id;
        let mut actions = Vec::new();
        let ui_state = &mut self.ui;
        let out = self.egui_ctx.run_ui(raw, |ui| {
            actions = panels::build(ui, ui_state, texture);
        });
        self.egui_state
            .handle_platform_output(&self.window, out.platform_output);
        self.apply(actions);
        // egui's texture updates (font atlas) apply even when this frame is not drawn, or
        // later frames would miss glyphs.
        let ppp = out.pixels_per_point;
        let primitives = self.egui_ctx.tessellate(out.shapes, ppp);
        for (id, deltas) in &out.textures_delta.set {
            for delta in deltas {
                self.egui_painter
                    .update_texture(&self.gpu.device, &self.gpu.queue, *id, delta);
            }
        }
        let free_textures = |painter: &mut EguiPainter| {
            for id in &out.textures_delta.free {
                painter.free_texture(id);
            }
        };

        tm.mark("ui");
        // 3. The surface.
        let surface_tex = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => t,
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                // Use this one; reconfigure for the next frame.
                self.next_repaint = Some(Instant::now());
                self.surface.configure(&self.gpu.device, &self.config);
                t
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                free_textures(&mut self.egui_painter);
                self.next_repaint = Some(Instant::now() + Duration::from_millis(50));
                return Ok(Flow::Continue);
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                free_textures(&mut self.egui_painter);
                let size = self.window.inner_size();
                self.resize(size);
                return Ok(Flow::Continue);
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                let e = self.gpu.take_error().err();
                return Err(CliError::Run(format!(
                    "cannot draw into the window: {}",
                    e.map(|e| e.to_string())
                        .unwrap_or_else(|| "surface validation error".into())
                )));
            }
        };
        tm.mark("acquire");
        let (sw, sh) = (surface_tex.texture.width(), surface_tex.texture.height());

        // 4. The 3-D view into its texture, at the view's size in pixels.
        let r = self.ui.view_rect;
        let (vw, vh) = if r.is_positive() {
            (
                (r.width() * ppp).round().max(1.0) as u32,
                (r.height() * ppp).round().max(1.0) as u32,
            )
        } else {
            (1, 1)
        };
        self.view.resize(&self.gpu, &mut self.egui_painter, vw, vh);
        let device = &self.gpu.device;
        let queue = &self.gpu.queue;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("dda3d viewer frame"),
        });
        if let Some(scene) = &self.ui.scene {
            let mut camera = self.ui.view.camera.clone();
            camera.aspect = vw as f32 / vh as f32;
            let (w, h) = self.view.size;
            // The view texture keeps its picture: redraw only when something in it changed.
            let key = (self.ui.scene_version, camera.clone(), (w, h));
            if self.view.drawn.as_ref() != Some(&key) {
                match self
                    .view
                    .renderer
                    .prepare(device, queue, scene, &camera, w, h)
                {
                    Ok(()) => {
                        self.view.renderer.encode(
                            &mut encoder,
                            &self.view.targets,
                            &self.view.view,
                        );
                        self.view.drawn = Some(key);
                    }
                    Err(e) => self.ui.error(format!("cannot draw this step: {e}")),
                }
            }
        }

        tm.mark("3d");
        // 5. egui into the surface (and into the capture texture for --screenshot).
        let capture_now = self.exit_after.is_some_and(|n| self.frames + 1 >= n);
        let screen = Screen {
            size_in_pixels: [sw, sh],
            pixels_per_point: ppp,
        };
        tm.mark("tess");
        self.egui_painter
            .prepare(device, queue, &primitives, screen);
        tm.mark("upd");
        let surface_view = surface_tex
            .texture
            .create_view(&wgpu::TextureViewDescriptor {
                format: Some(self.render_format),
                ..Default::default()
            });
        let bg = self.egui_ctx.global_style().visuals.panel_fill;
        egui_pass(&self.egui_painter, &mut encoder, &surface_view, bg);
        let capture = if capture_now && self.screenshot.is_some() {
            let c = WindowCapture::new(&self.gpu, self.render_format, sw, sh);
            egui_pass(&self.egui_painter, &mut encoder, &c.view, bg);
            c.copy(&mut encoder);
            Some(c)
        } else {
            None
        };
        tm.mark("encode");
        queue.submit([encoder.finish()]);
        if tm.on {
            let _ = device.poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: None,
            });
            tm.mark("gpu");
        }
        self.window.pre_present_notify();
        queue.present(surface_tex);
        tm.mark("present");
        free_textures(&mut self.egui_painter);
        if let Err(e) = self.gpu.take_error() {
            self.ui.error(e.to_string());
        }
        self.frames += 1;
        if let Some(f) = &self.ui.frame
            && f.state == RunState::Running
            && f.steps_per_second > 0.0
        {
            self.last_steps_per_second = f.steps_per_second;
        }
        self.ui.perf.frame_done(started);
        tm.mark("end");
        tm.print();

        if let Some(c) = capture {
            let path = self.screenshot.clone().unwrap_or_default();
            let rgba = c
                .read(&self.gpu, self.render_format)
                .map_err(|e| CliError::Run(format!("{}: {e}", path.display())))?;
            write_png(&path, &rgba, sw, sh, false).map_err(|e| CliError::Run(e.to_string()))?;
            eprintln!("wrote {} ({sw}x{sh})", path.display());
        }
        if self.exit_after.is_some_and(|n| self.frames >= n) {
            self.report();
            return Ok(Flow::Exit);
        }

        // 6. When to draw again: continuously while something moves, else on demand.
        let busy = self.exit_after.is_some()
            || self.recording.is_some()
            || self
                .ui
                .frame
                .as_ref()
                .is_some_and(|f| f.state == RunState::Running);
        let delay = out
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map(|v| v.repaint_delay)
            .unwrap_or(Duration::MAX);
        if busy || delay.is_zero() {
            match self.min_frame_interval {
                // Input still redraws at once (winit events request a redraw); only the
                // animation is paced, leaving the solver the rest of the CPU.
                Some(min) if started.elapsed() < min => self.next_repaint = Some(started + min),
                _ => self.window.request_redraw(),
            }
        } else if delay < Duration::from_secs(3600) {
            self.next_repaint = Some(Instant::now() + delay);
        }
        Ok(Flow::Continue)
    }

    /// Sends the panel's commands to the simulation and runs screenshot/record requests.
    fn apply(&mut self, actions: Vec<Action>) {
        for a in actions {
            match a {
                Action::Sim(cmd) => {
                    let shown = matches!(cmd, Command::SetSpeed(_));
                    let id = self.sim.send(cmd);
                    if shown {
                        self.ui.params_sent(id);
                    }
                }
                Action::Screenshot => self.screenshot_view(),
                Action::ToggleRecord => self.toggle_record(),
            }
        }
        if let Some(p) = self.ui.param_change() {
            let id = self.sim.send(Command::SetParams(Box::new(p)));
            self.ui.params_sent(id);
        }
    }

    /// The screenshot button: the 3-D view at window size through the `render` command's
    /// off-screen path (4× MSAA), on a worker thread so the window does not stall.
    fn screenshot_view(&mut self) {
        let Some(scene) = self.ui.scene.clone() else {
            self.ui.error("nothing to draw yet");
            return;
        };
        let (w, h) = (self.config.width, self.config.height);
        let mut camera = self.ui.view.camera.clone();
        camera.aspect = w as f32 / h as f32;
        let step = self.ui.frame.as_ref().map_or(0, |f| f.snapshot.step);
        let path = unused_path(&self.out_dir, &format!("screenshot_step{step:06}"), "png");
        let gpu = self.gpu.clone();
        let tx = self.bg_tx.clone();
        let proxy = self.proxy.clone();
        self.ui.info("writing screenshot...");
        let spawned = std::thread::Builder::new()
            .name("dda3d-screenshot".into())
            .spawn(move || {
                let r = (|| {
                    if let Some(dir) = path.parent() {
                        std::fs::create_dir_all(dir).map_err(|e| RenderError::io(dir, e))?;
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
            self.ui
                .error(format!("cannot start the screenshot thread: {e}"));
        }
    }

    fn toggle_record(&mut self) {
        if let Some(rec) = self.recording.take() {
            self.ui.recording = None;
            self.ui.info("finishing recording...");
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
        let cam = &self.ui.view.camera;
        let target = cam.origin + cam.target.as_dvec3();
        let mut opts = CaptureOptions::new(&dir);
        opts.width = self.config.width;
        opts.height = self.config.height;
        opts.camera = CameraOverride {
            azimuth_deg: Some(cam.azimuth.to_degrees()),
            elevation_deg: Some(cam.elevation.to_degrees()),
            distance: Some(cam.distance),
            target: Some(target.to_array()),
            fov_y_deg: Some(cam.fov_y.to_degrees()),
        };
        let f = self.ui.scene_frame;
        opts.framing = Framing::Box {
            lo: f.lo.to_array(),
            hi: f.hi.to_array(),
        };
        opts.style = self.ui.style();
        opts.max_msaa_samples = self.view.renderer.samples();
        match FrameCapture::start_with_gpu(self.gpu.clone(), opts) {
            Ok(capture) => {
                self.ui.recording = Some(RecordingInfo {
                    dir: dir.clone(),
                    frames: 0,
                });
                self.recording = Some(Recording {
                    capture,
                    last: None,
                });
                self.ui.info(format!("recording to {}", dir.display()));
            }
            Err(e) => self.ui.error(format!("cannot record: {e}")),
        }
    }

    /// Hands each new step to the recorder; a step that arrives while the recorder is busy is
    /// skipped rather than stalling the window.
    fn record_frame(&mut self) {
        let (Some(rec), Some(frame)) = (&mut self.recording, &self.ui.frame) else {
            return;
        };
        let key = (frame.generation, frame.snapshot.step);
        if rec.last == Some(key) {
            return;
        }
        match rec.capture.try_submit((*frame.snapshot).clone()) {
            Ok(true) => {
                rec.last = Some(key);
                if let Some(info) = &mut self.ui.recording {
                    info.frames = rec.capture.submitted();
                }
            }
            Ok(false) => {}
            Err(e) => {
                self.recording = None;
                self.ui.recording = None;
                self.ui.error(format!("recording stopped: {e}"));
            }
        }
    }

    fn poll_background(&mut self) {
        while let Ok(b) = self.bg_rx.try_recv() {
            match b {
                Background::Screenshot(Ok(p)) => self.ui.info(format!("wrote {}", p.display())),
                Background::Screenshot(Err(e)) => self.ui.error(format!("screenshot failed: {e}")),
                Background::RecordFinished(Ok((n, dir))) => self
                    .ui
                    .info(format!("wrote {n} frames to {}", dir.display())),
                Background::RecordFinished(Err(e)) => {
                    self.ui.error(format!("recording failed: {e}"))
                }
            }
        }
    }

    /// One line on stderr for `--exit-after-frames`: how fast the window drew and the solver ran.
    fn report(&self) {
        // The first frames include shader compilation and layout; leave them out.
        let skip = (self.ui.perf.all_intervals.len() / 10).max(2);
        let mut iv: Vec<f64> = self
            .ui
            .perf
            .all_intervals
            .iter()
            .skip(skip)
            .copied()
            .collect();
        let busy: Vec<f64> = self.ui.perf.all_busy.iter().skip(skip).copied().collect();
        if iv.is_empty() {
            iv = self.ui.perf.all_intervals.clone();
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
        let (steps, t, run_s) = self.ui.frame.as_ref().map_or((0, 0.0, 0.0), |f| {
            (f.totals.steps, f.snapshot.time, f.running_seconds)
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
            self.view.size.0,
            self.view.size.1,
            self.ui.adapter,
            steps,
            t,
            run_s,
            avg_sps,
            self.last_steps_per_second
        );
    }
}

fn egui_pass(
    painter: &EguiPainter,
    encoder: &mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    clear: egui::Color32,
) {
    let [r, g, b, a] = clear.to_normalized_gamma_f32();
    let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("dda3d egui"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                // egui works in gamma space on a non-sRGB target, so the clear value is the
                // gamma-encoded colour as it is.
                load: wgpu::LoadOp::Clear(wgpu::Color {
                    r: r as f64,
                    g: g as f64,
                    b: b as f64,
                    a: a as f64,
                }),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let mut pass = pass;
    painter.render(&mut pass);
}

/// A texture of the surface's format and size that egui draws into a second time, plus the
/// buffer it is copied to, for the whole-window screenshot on any backend.
struct WindowCapture {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    buffer: wgpu::Buffer,
    padded_row: u32,
    width: u32,
    height: u32,
}

impl WindowCapture {
    fn new(gpu: &Gpu, format: wgpu::TextureFormat, width: u32, height: u32) -> WindowCapture {
        let texture = crate::render::offscreen::readable_target(
            &gpu.device,
            "dda3d window capture",
            format,
            width,
            height,
        );
        let view = texture.create_view(&Default::default());
        let padded_row = padded_bytes_per_row(width);
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("dda3d window readback"),
            size: padded_row as u64 * height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        WindowCapture {
            texture,
            view,
            buffer,
            padded_row,
            width,
            height,
        }
    }

    fn copy(&self, encoder: &mut wgpu::CommandEncoder) {
        crate::render::offscreen::copy_to_readback(
            encoder,
            &self.texture,
            &self.buffer,
            self.padded_row,
            self.width,
            self.height,
        );
    }

    /// Waits for the copy and returns RGBA bytes, top row first.
    fn read(&self, gpu: &Gpu, format: wgpu::TextureFormat) -> Result<Vec<u8>, RenderError> {
        let bgra = match format {
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb => true,
            wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb => false,
            other => {
                return Err(RenderError::InvalidOptions(format!(
                    "window format {other:?} cannot be saved as PNG"
                )));
            }
        };
        let (tx, rx) = mpsc::channel();
        self.buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        gpu.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: None,
            })
            .map_err(|e| RenderError::Gpu(e.to_string()))?;
        rx.recv()
            .map_err(|_| RenderError::Gpu("readback callback never ran".into()))?
            .map_err(|e| RenderError::Gpu(format!("readback failed: {e}")))?;
        let mut px = {
            let view = self
                .buffer
                .get_mapped_range(..)
                .map_err(|e| RenderError::Gpu(format!("readback mapping: {e}")))?;
            strip_row_padding(&view, self.width, self.height, self.padded_row)
        };
        self.buffer.unmap();
        if bgra {
            for p in px.chunks_exact_mut(4) {
                p.swap(0, 2);
            }
        }
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

/// A light theme that sits well next to the light-grey 3-D view, with slightly roomier rows.
fn setup_style(ctx: &egui::Context) {
    ctx.set_theme(egui::Theme::Light);
    ctx.all_styles_mut(|s| {
        s.spacing.item_spacing = egui::vec2(8.0, 5.0);
        s.spacing.slider_width = 120.0;
        s.spacing.interact_size.y = 20.0;
        s.visuals.panel_fill = egui::Color32::from_rgb(0xFA, 0xFA, 0xF8);
    });
}

/// Phase timings of a frame, printed when `DDA3D_VIEWER_TIMING` is set (for tuning).
struct Timing {
    on: bool,
    last: Instant,
    marks: Vec<(&'static str, f64)>,
}

impl Timing {
    fn new() -> Timing {
        Timing {
            on: std::env::var_os("DDA3D_VIEWER_TIMING").is_some(),
            last: Instant::now(),
            marks: Vec::new(),
        }
    }
    fn mark(&mut self, name: &'static str) {
        if self.on {
            let now = Instant::now();
            self.marks
                .push((name, (now - self.last).as_secs_f64() * 1e3));
            self.last = now;
        }
    }
    fn print(&self) {
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
