//! The window application: the winit event loop and the frame loop that ties the parts together.
//!
//! Each frame ([`Viewer::redraw`]):
//! 1. take the newest [`Frame`](super::sim::Frame) from the simulation thread (never waiting);
//! 2. run the egui UI ([`panels::build`]), which handles camera input and lays out the 3-D view;
//! 3. acquire the window surface's texture;
//! 4. draw the 3-D scene into the view's own texture (`Rgba8Unorm`, which egui can sample and
//!    the renderer handles by encoding sRGB in its shader), sized to the view in pixels;
//! 5. draw egui (panels and the view image) into the window surface, and present it (on a
//!    software rasterizer egui draws into a texture copied into the surface, and a frame that
//!    would draw the same picture copies it again: `frame_cache.rs`);
//! 6. decide when to draw again.
//!
//! The parts: `surface.rs` (the window, its surface, egui), `view_target.rs` (the 3-D view's
//! texture), `frame_cache.rs` (the last composed picture), `capture.rs` (screenshots and
//! recordings), `timing.rs` (pacing and the frame-time report).

mod capture;
mod frame_cache;
mod sim_link;
mod surface;
mod timing;
mod view_target;

use std::time::{Duration, Instant};

use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::window::WindowId;

use super::painter::{EguiPainter, Screen};
use super::panels;
use super::sim::RunState;
use super::state::{Action, UiState};
use super::{ViewerError, ViewerOptions};
use crate::render::Gpu;
use capture::{Capture, WindowCapture};
use frame_cache::{FrameCache, FrameInputs};
use sim_link::SimLink;
use surface::{Acquired, EguiLayer, WindowSurface, is_software};
use timing::{FrameClock, Timing};
use view_target::ViewTarget;

/// Sent to the event loop to wake it (a new simulation frame, a background job done).
#[derive(Debug, Clone, Copy)]
struct Wake;

/// Opens the window and runs until it is closed (or `exit_after_frames` have been drawn).
pub fn run_viewer(opts: ViewerOptions) -> Result<(), ViewerError> {
    let event_loop = EventLoop::<Wake>::with_user_event().build().map_err(|e| {
        let no_display = ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"]
            .iter()
            .all(|v| std::env::var_os(v).is_none_or(|s| s.is_empty()));
        ViewerError::Failed(if no_display {
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
        .map_err(|e| ViewerError::Failed(format!("window event loop failed: {e}")))?;
    // Stop the simulation and finish any recording before reporting.
    drop(app.viewer.take());
    app.result
}

struct App {
    opts: Option<ViewerOptions>,
    proxy: EventLoopProxy<Wake>,
    viewer: Option<Viewer>,
    result: Result<(), ViewerError>,
}

impl App {
    fn fail(&mut self, el: &ActiveEventLoop, e: ViewerError) {
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
                v.surface.window.request_redraw();
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
            WindowEvent::Resized(size) => v.surface.resize(&v.gpu, *size),
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
        let r = v.egui.state.on_window_event(&v.surface.window, &event);
        if r.repaint {
            v.surface.window.request_redraw();
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        let Some(v) = &self.viewer else {
            return;
        };
        match v.clock.next_repaint {
            Some(t) if t <= Instant::now() => {
                v.surface.window.request_redraw();
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

/// What egui produced for one frame, ready to paint.
struct UiFrame {
    /// egui's shapes, tessellated only when the frame is drawn anew.
    shapes: Vec<egui::epaint::ClippedShape>,
    /// egui set or replaced a texture this frame.
    textures_changed: bool,
    pixels_per_point: f32,
    /// Textures egui no longer needs, freed once the frame is drawn or skipped.
    free: Vec<egui::TextureId>,
    /// When egui wants to draw again (zero: at once, e.g. during an animation).
    repaint_delay: Duration,
}

impl UiFrame {
    fn free_textures(&self, painter: &mut EguiPainter) {
        for id in &self.free {
            painter.free_texture(id);
        }
    }
}

struct Viewer {
    surface: WindowSurface,
    gpu: Gpu,
    egui: EguiLayer,
    view: ViewTarget,
    /// Run B's 3-D view in a comparison.
    view_b: Option<ViewTarget>,
    sim: SimLink,
    ui: UiState,
    capture: Capture,
    clock: FrameClock,
    /// The last composed picture, on software rasterizers (see `frame_cache.rs`).
    frame_cache: Option<FrameCache>,
    /// The scene as loaded, the checkpoint resumed (if any) and the event loop's waker: a
    /// comparison started or ended from the panel restarts the simulation threads from them.
    scene: crate::scene::Scene,
    origin: Option<crate::viewer::sim::Origin>,
    proxy: EventLoopProxy<Wake>,
}

impl Viewer {
    fn new(
        el: &ActiveEventLoop,
        opts: ViewerOptions,
        proxy: EventLoopProxy<Wake>,
    ) -> Result<Viewer, ViewerError> {
        let (surface, gpu) = WindowSurface::open(el, &opts.scene.name, opts.size)?;
        let software = is_software(&gpu);
        let copies = surface.config.usage.contains(wgpu::TextureUsages::COPY_DST);
        let frame_cache = (software && copies).then(FrameCache::new);
        let mut egui = EguiLayer::new(&surface.window, &gpu, surface.render_format);
        // 4× MSAA costs about three times as much per frame on a software rasterizer, where
        // the window must stay interactive; real GPUs get it for free.
        let samples = opts.msaa.unwrap_or(if software { 1 } else { 4 });
        let view = ViewTarget::new(&gpu, &mut egui.painter, samples);
        let adapter = format!(
            "{}, {}× MSAA",
            gpu.adapter_summary(),
            view.renderer.samples()
        );
        let sim = SimLink::start(&opts, proxy.clone())?;
        let first = sim
            .first_frame()
            .ok_or_else(|| ViewerError::Failed("the simulation published no state".into()))?;
        let mut ui = UiState::new(&opts.scene, &first.snapshot, adapter);
        ui.out_dir = opts.out_dir.clone();
        ui.selected = opts.selected;
        ui.compare = sim.compare_ui(&opts);
        ui.resumed_from = opts.origin.is_some().then_some(first.snapshot.time);
        let view_b = ui.compare.as_mut().map(|c| {
            let v = ViewTarget::new(&gpu, &mut egui.painter, samples);
            c.texture_b = Some(v.id);
            v
        });
        Ok(Viewer {
            surface,
            gpu,
            egui,
            view,
            view_b,
            sim,
            ui,
            capture: Capture::new(opts.out_dir, opts.screenshot, proxy.clone()),
            clock: FrameClock::new(opts.exit_after_frames, software),
            frame_cache,
            scene: opts.scene,
            origin: opts.origin,
            proxy,
        })
    }

    /// A new simulation frame or a finished background job: draw it, but no sooner than the
    /// frame cap allows.
    fn wake(&mut self) {
        if self.clock.wake(self.ui.perf.last_start()) {
            self.surface.window.request_redraw();
        }
    }

    /// The window's size in pixels.
    fn window_size(&self) -> (u32, u32) {
        (self.surface.config.width, self.surface.config.height)
    }

    fn redraw(&mut self) -> Result<Flow, ViewerError> {
        let started = self.ui.perf.frame_started();
        let mut tm = Timing::new();
        self.clock.next_repaint = None;

        // 1. Newest simulation state (never waits).
        self.take_simulation_state();
        tm.mark("sim");
        // 2. UI.
        let mut frame = self.run_ui();
        tm.mark("ui");
        // 3. The surface.
        let Some(surface_tex) = self.acquire(&frame)? else {
            return Ok(Flow::Continue);
        };
        tm.mark("acquire");
        // 4. The 3-D view into its texture, at the view's size in pixels.
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("dda3d viewer frame"),
            });
        let view_redrawn = self.draw_view(&mut encoder, frame.pixels_per_point);
        tm.mark("3d");
        // 5. egui into the surface (and into the capture texture for --screenshot), or the last
        // picture again where nothing in it changed.
        let shot = self.draw_egui(
            &mut encoder,
            &surface_tex,
            &mut frame,
            view_redrawn,
            &mut tm,
        )?;
        self.present(encoder, surface_tex, &frame, &mut tm);
        self.clock.frame_drawn(self.ui.frame.as_deref());
        self.ui.perf.frame_done(started);
        tm.mark("end");
        tm.print();

        if let Some(shot) = shot {
            shot.save(&self.gpu)?;
        }
        if self.clock.done() {
            self.report();
            return Ok(Flow::Exit);
        }
        // 6. When to draw again: continuously while something moves, else on demand.
        self.schedule_next(started, frame.repaint_delay);
        Ok(Flow::Continue)
    }

    /// Step 1: the newest frame and step records for the panel, finished background jobs, and
    /// the new step for a recording.
    fn take_simulation_state(&mut self) {
        self.sim.update(&mut self.ui);
        self.capture.poll_background(&mut self.ui);
        self.capture.record_frame(&mut self.ui);
    }

    /// Step 2: runs the panels, carries out what they asked for, and tessellates the result.
    fn run_ui(&mut self) -> UiFrame {
        let window = &self.surface.window;
        let raw = self.egui.state.take_egui_input(window);
        let texture = self.view.id;
        let mut actions = Vec::new();
        let ui_state = &mut self.ui;
        let out = self.egui.ctx.run_ui(raw, |ui| {
            actions = panels::build(ui, ui_state, texture);
        });
        self.egui
            .state
            .handle_platform_output(window, out.platform_output);
        self.apply(actions);
        // egui's texture updates (font atlas) apply even when this frame is not drawn, or
        // later frames would miss glyphs.
        let pixels_per_point = out.pixels_per_point;
        let textures_changed = !out.textures_delta.set.is_empty();
        for (id, deltas) in &out.textures_delta.set {
            for delta in deltas {
                self.egui
                    .painter
                    .update_texture(&self.gpu.device, &self.gpu.queue, *id, delta);
            }
        }
        let repaint_delay = out
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map(|v| v.repaint_delay)
            .unwrap_or(Duration::MAX);
        UiFrame {
            shapes: out.shapes,
            textures_changed,
            pixels_per_point,
            free: out.textures_delta.free.iter().copied().collect(),
            repaint_delay,
        }
    }

    /// Sends the panel's commands to the simulation and runs screenshot/record requests.
    fn apply(&mut self, actions: Vec<Action>) {
        let size = self.window_size();
        for a in actions {
            match a {
                Action::Sim(cmd) => self.sim.command(cmd, &mut self.ui),
                Action::Screenshot => self.capture.screenshot_view(&self.gpu, &mut self.ui, size),
                Action::ToggleRecord => {
                    let samples = self.view.renderer.samples();
                    self.capture
                        .toggle_record(&self.gpu, &mut self.ui, size, samples);
                }
                Action::Compare(b) => self.set_compare(b.map(|b| *b)),
            }
        }
        self.sim.send_params(&mut self.ui);
    }

    /// Starts a comparison with run B's settings `b`, or ends it (`None`): the simulation
    /// restarts from t = 0 (or the checkpoint resumed), paused, with run A's present settings.
    fn set_compare(&mut self, b: Option<crate::params::SolverParams>) {
        let mut scene = self.scene.clone();
        if let Some(f) = self.ui.frame.as_ref() {
            scene.params = f.params.clone();
        }
        let opts = ViewerOptions {
            scene,
            size: self.window_size(),
            speed: self.ui.speed,
            play: false,
            screenshot: None,
            exit_after_frames: None,
            msaa: None,
            out_dir: self.ui.out_dir.clone(),
            compare: b,
            ghost: false,
            selected: self.ui.selected,
            origin: self.origin.clone(),
        };
        let sim = match SimLink::start(&opts, self.proxy.clone()) {
            Ok(sim) => sim,
            Err(e) => return self.ui.error(e.to_string()),
        };
        // The old threads stop as their handles drop; the plots start over.
        self.sim = sim;
        self.ui.frame = None;
        self.ui.history = Default::default();
        self.ui.compare = self.sim.compare_ui(&opts);
        let samples = self.view.renderer.samples();
        self.view_b = self.ui.compare.as_mut().map(|c| {
            let v = ViewTarget::new(&self.gpu, &mut self.egui.painter, samples);
            c.texture_b = Some(v.id);
            v
        });
        self.sim.update(&mut self.ui);
    }

    /// Step 3: the surface texture to draw into; `None` skips this frame (and schedules the
    /// next one where waiting helps).
    fn acquire(&mut self, frame: &UiFrame) -> Result<Option<wgpu::SurfaceTexture>, ViewerError> {
        Ok(match self.surface.acquire(&self.gpu)? {
            Acquired::Texture {
                texture,
                suboptimal,
            } => {
                if suboptimal {
                    self.clock.next_repaint = Some(Instant::now());
                }
                Some(texture)
            }
            Acquired::Later => {
                frame.free_textures(&mut self.egui.painter);
                self.clock.next_repaint = Some(Instant::now() + Duration::from_millis(50));
                None
            }
            Acquired::Reconfigured => {
                frame.free_textures(&mut self.egui.painter);
                None
            }
        })
    }

    /// Step 4: fits the view texture to the view's rectangle and draws the scene into it.
    /// Returns whether a view was drawn anew (else the textures hold last frame's pictures).
    fn draw_view(&mut self, encoder: &mut wgpu::CommandEncoder, pixels_per_point: f32) -> bool {
        let redrawn_b = self.draw_view_b(encoder, pixels_per_point);
        let (vw, vh) = pixels(self.ui.view_rect, pixels_per_point);
        self.view.resize(&self.gpu, &mut self.egui.painter, vw, vh);
        let Some(scene) = &self.ui.scene else {
            return redrawn_b;
        };
        let mut camera = self.ui.view.camera.clone();
        camera.aspect = vw as f32 / vh as f32;
        let drawn = self
            .view
            .draw(&self.gpu, encoder, scene, &camera, self.ui.scene_version);
        match drawn {
            Ok(redrawn) => redrawn || redrawn_b,
            Err(e) => {
                self.ui.error(format!("cannot draw this step: {e}"));
                true
            }
        }
    }

    /// Step 4 for run B of a comparison: its pane, with the same camera as A's.
    fn draw_view_b(&mut self, encoder: &mut wgpu::CommandEncoder, pixels_per_point: f32) -> bool {
        let (Some(view), Some(c)) = (self.view_b.as_mut(), self.ui.compare.as_deref()) else {
            return false;
        };
        if c.ghost {
            return false; // B is drawn by egui over A's pane
        }
        let (vw, vh) = pixels(c.view_rect_b, pixels_per_point);
        view.resize(&self.gpu, &mut self.egui.painter, vw, vh);
        let Some(scene) = &c.scene_b else {
            return false;
        };
        let mut camera = self.ui.view.camera.clone();
        camera.aspect = vw as f32 / vh as f32;
        let drawn = view.draw(&self.gpu, encoder, scene, &camera, c.scene_b_version);
        match drawn {
            Ok(redrawn) => redrawn,
            Err(e) => {
                self.ui.error(format!("cannot draw this step of B: {e}"));
                true
            }
        }
    }

    /// Step 5: records egui's pass into the surface and, on the last frame with
    /// `--screenshot`, a second one into a texture that is read back after presenting.
    fn draw_egui(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        surface_tex: &wgpu::SurfaceTexture,
        frame: &mut UiFrame,
        view_redrawn: bool,
        tm: &mut Timing,
    ) -> Result<Option<WindowCapture>, ViewerError> {
        let size = (surface_tex.texture.width(), surface_tex.texture.height());
        let capture_now = self.clock.drawing_last_frame();
        let inputs = FrameInputs {
            shapes: &frame.shapes,
            pixels_per_point: frame.pixels_per_point,
            size,
            textures_changed: frame.textures_changed,
            view_redrawn,
        };
        if let Some(cache) = &self.frame_cache
            && !capture_now
            && cache.unchanged(&inputs)
        {
            cache.copy_to(encoder, &surface_tex.texture);
            tm.mark("copy");
            return Ok(None);
        }
        let screen = Screen {
            size_in_pixels: [size.0, size.1],
            pixels_per_point: frame.pixels_per_point,
        };
        let shapes = if self.frame_cache.is_some() {
            frame.shapes.clone()
        } else {
            std::mem::take(&mut frame.shapes)
        };
        let primitives = self.egui.ctx.tessellate(shapes, frame.pixels_per_point);
        tm.mark("tess");
        self.egui
            .painter
            .prepare(&self.gpu.device, &self.gpu.queue, &primitives, screen);
        tm.mark("upd");
        let format = self.surface.render_format;
        if let Some(cache) = &mut self.frame_cache {
            let target = cache.target(&self.gpu, format, size);
            self.egui.paint(encoder, target);
            cache.copy_to(encoder, &surface_tex.texture);
            cache.keep(std::mem::take(&mut frame.shapes), frame.pixels_per_point);
        } else {
            let surface_view = surface_tex
                .texture
                .create_view(&wgpu::TextureViewDescriptor {
                    format: Some(format),
                    ..Default::default()
                });
            self.egui.paint(encoder, &surface_view);
        }
        let shot = if capture_now {
            self.capture.window_shot(&self.gpu, format, size)?
        } else {
            None
        };
        if let Some(c) = &shot {
            self.egui.paint(encoder, &c.view);
            c.copy(encoder);
        }
        tm.mark("encode");
        Ok(shot)
    }

    /// Submits the frame's work, presents the surface, and frees what egui no longer needs.
    fn present(
        &mut self,
        encoder: wgpu::CommandEncoder,
        surface_tex: wgpu::SurfaceTexture,
        frame: &UiFrame,
        tm: &mut Timing,
    ) {
        let queue = &self.gpu.queue;
        queue.submit([encoder.finish()]);
        if tm.on {
            let _ = self.gpu.device.poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: None,
            });
            tm.mark("gpu");
        }
        self.surface.window.pre_present_notify();
        queue.present(surface_tex);
        tm.mark("present");
        frame.free_textures(&mut self.egui.painter);
        if let Err(e) = self.gpu.take_error() {
            self.ui.error(e.to_string());
        }
    }

    /// Step 6: draws again at once while something moves (within the frame cap), else when
    /// egui asks to.
    fn schedule_next(&mut self, started: Instant, repaint_delay: Duration) {
        let animating = self.clock.exits_by_itself()
            || self.capture.is_recording()
            || self
                .ui
                .frame
                .as_ref()
                .is_some_and(|f| f.state == RunState::Running);
        if self.clock.schedule(started, animating, repaint_delay) {
            self.surface.window.request_redraw();
        }
    }

    /// The `--exit-after-frames` report (with B's solver speed in a comparison).
    fn report(&self) {
        self.clock.report(
            &self.ui.perf.all_intervals,
            &self.ui.perf.all_busy,
            self.ui.frame.as_deref(),
            self.view.size,
            &self.ui.adapter,
        );
        if let Some(b) = SimLink::frame_b(&self.ui) {
            timing::report_b(&b);
        }
    }
}

/// A rectangle in points as a texture size in pixels (at least 1×1).
fn pixels(r: egui::Rect, pixels_per_point: f32) -> (u32, u32) {
    if r.is_positive() {
        (
            (r.width() * pixels_per_point).round().max(1.0) as u32,
            (r.height() * pixels_per_point).round().max(1.0) as u32,
        )
    } else {
        (1, 1)
    }
}
