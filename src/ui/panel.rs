//! The egui side of the viewer: toolbar, parameter panel, display options, selection details,
//! live diagnostic plots, and the 3-D view's input and overlay. No GPU code here: the 3-D image
//! arrives as an egui texture id and is drawn by [`super::app`].

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use egui::{
    Align, Align2, Color32, CornerRadius, FontId, Key, Layout, PointerButton, Pos2, Rect, RichText,
    Sense, Stroke, Vec2,
};
use egui_plot::{HLine, Legend, Line, LineStyle, Plot, PlotPoints};
use glam::DVec3;

use super::sim::{Command, Frame, RunState, Speed, StepRecord};
use super::view::{DragButton, ViewControls};
use crate::params::{Method, Mode, SolverParams};
use crate::render::mesh::{LOCK_SRGB, OPEN_SRGB, SLIDE_SRGB};
use crate::render::overlay::{format_force, format_time};
use crate::render::{ArrowMode, Coloring, Scene, SceneFrame, SceneStyle, paint_overlay};
use crate::scene::Scene as SceneFile;
use crate::snapshot::{ContactMode, ContactState, Snapshot};

/// What the panel asks the app to do after the frame's UI pass.
#[derive(Debug)]
pub enum Action {
    Sim(Command),
    /// Write the 3-D view at window size to a PNG.
    Screenshot,
    /// Start or stop writing PNG frames.
    ToggleRecord,
}

/// Display options of the 3-D view.
#[derive(Clone, Debug, PartialEq)]
pub struct Display {
    pub coloring: Coloring,
    pub forces: bool,
    pub normals: bool,
    /// Arrow scale chosen from the first frame with contacts (kept fixed after that so arrow
    /// lengths compare between frames), or `force_scale`.
    pub auto_force_scale: bool,
    /// Newtons per metre of arrow (manual scale).
    pub force_scale: f64,
    pub edges: bool,
    /// Outlines only, no faces.
    pub wireframe: bool,
    pub grid: bool,
    /// Block names at their centroids.
    pub labels: bool,
    /// Caption, legends and axis triad.
    pub overlay: bool,
}

impl Default for Display {
    fn default() -> Self {
        Display {
            coloring: Coloring::PerBlock,
            forces: true,
            normals: false,
            auto_force_scale: true,
            force_scale: 1e5,
            edges: true,
            wireframe: false,
            grid: true,
            labels: false,
            overlay: true,
        }
    }
}

/// Static facts about a block from the scene file, for the selection panel.
#[derive(Clone, Debug)]
pub struct BlockInfo {
    pub mass: f64,
    pub density: f64,
    pub young: f64,
    pub poisson: f64,
}

/// Per-step history for the plots (one run; cleared on reset).
#[derive(Default)]
pub struct History {
    pub generation: u64,
    pub records: Vec<StepRecord>,
}

/// Steps kept for the plots; older ones are dropped (a long run keeps its recent past).
const HISTORY_CAP: usize = 200_000;
/// Points per plotted line: about one per pixel of a plot's width. Each point becomes several
/// anti-aliased triangles, and on a software rasterizer triangles, not pixels, dominate the cost
/// of the plots.
const PLOT_POINTS: usize = 240;

/// Frame-time bookkeeping for the toolbar and the benchmark line.
#[derive(Default)]
pub struct Perf {
    /// Start-to-start intervals of recent frames, s.
    intervals: VecDeque<f64>,
    /// CPU time spent building and submitting recent frames, s.
    busy: VecDeque<f64>,
    last_start: Option<Instant>,
    /// All intervals since the start, for the exit report.
    pub all_intervals: Vec<f64>,
    pub all_busy: Vec<f64>,
}

impl Perf {
    pub fn frame_started(&mut self) -> Instant {
        let now = Instant::now();
        if let Some(prev) = self.last_start {
            let dt = (now - prev).as_secs_f64();
            self.intervals.push_back(dt);
            self.all_intervals.push(dt);
            if self.intervals.len() > 60 {
                self.intervals.pop_front();
            }
        }
        self.last_start = Some(now);
        now
    }

    /// When the last frame started.
    pub fn last_start(&self) -> Option<Instant> {
        self.last_start
    }

    pub fn frame_done(&mut self, started: Instant) {
        let b = started.elapsed().as_secs_f64();
        self.busy.push_back(b);
        self.all_busy.push(b);
        if self.busy.len() > 60 {
            self.busy.pop_front();
        }
    }

    /// Mean frame interval (ms) and CPU time per frame (ms) over the last second or so.
    pub fn recent_ms(&self) -> (f64, f64) {
        let mean = |v: &VecDeque<f64>| {
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64 * 1e3
            }
        };
        (mean(&self.intervals), mean(&self.busy))
    }
}

/// A line in the toolbar that fades after a while ("screenshot written to …").
pub struct Message {
    pub text: String,
    pub error: bool,
    pub at: Instant,
}

/// Recording in progress, as the panel shows it.
pub struct RecordingInfo {
    pub dir: PathBuf,
    pub frames: usize,
}

/// Everything the panel remembers between frames.
pub struct UiState {
    pub scene_name: String,
    /// The scene file's parameters ("scene values" button).
    pub scene_params: SolverParams,
    /// E used to express penalties (the smallest Young's modulus of the scene: contacts use
    /// min(E_i, E_j)), Pa.
    pub young: f64,
    pub blocks: Vec<BlockInfo>,
    pub frame: Option<Arc<Frame>>,
    /// What the parameter widgets show and edit.
    pub edit: SolverParams,
    /// Id of the last SetParams sent; frames before it are stale for the widgets.
    params_id: u64,
    last_sent: SolverParams,
    pub speed: Speed,
    pub display: Display,
    pub history: History,
    pub selected: Option<usize>,
    pub view: ViewControls,
    /// Grid and render origin: the initial blocks (fixed, so nothing jumps while blocks move).
    pub scene_frame: SceneFrame,
    /// The scene drawn this frame (built in the UI pass, drawn by the app).
    pub scene: Option<Scene>,
    /// Bumped whenever `scene` is rebuilt, so the app can skip redrawing an unchanged view.
    pub scene_version: u64,
    /// What `scene` was built from: (frame seq, style, wireframe).
    scene_key: Option<(u64, SceneStyle, bool)>,
    locked_force_scale: Option<f64>,
    field_max: f64,
    /// The 3-D view's rectangle in points.
    pub view_rect: Rect,
    pub message: Option<Message>,
    pub recording: Option<RecordingInfo>,
    pub perf: Perf,
    pub show_plots: bool,
    /// "name (backend, type), N× MSAA".
    pub adapter: String,
}

impl UiState {
    pub fn new(scene: &SceneFile, first: &Snapshot, adapter: String) -> UiState {
        let young = scene
            .model
            .blocks
            .iter()
            .map(|b| b.material.young_modulus)
            .filter(|e| e.is_finite() && *e > 0.0)
            .fold(f64::INFINITY, f64::min);
        let young = if young.is_finite() { young } else { 1.0 };
        let frame = SceneFrame::of_snapshot(first);
        UiState {
            scene_name: scene.name.clone(),
            scene_params: scene.params.clone(),
            young,
            blocks: scene
                .model
                .blocks
                .iter()
                .map(|b| BlockInfo {
                    mass: b.mass,
                    density: b.density,
                    young: b.material.young_modulus,
                    poisson: b.material.poisson_ratio,
                })
                .collect(),
            frame: None,
            edit: scene.params.clone(),
            params_id: 0,
            last_sent: scene.params.clone(),
            speed: Speed::default(),
            display: Display::default(),
            history: History::default(),
            selected: None,
            view: ViewControls::new(frame.lo, frame.hi, 16.0 / 9.0),
            scene_frame: frame,
            scene: None,
            scene_version: 0,
            scene_key: None,
            locked_force_scale: None,
            field_max: 0.0,
            view_rect: Rect::NOTHING,
            message: None,
            recording: None,
            perf: Perf::default(),
            show_plots: true,
            adapter,
        }
    }

    /// Takes in the newest frame and the step records since the last call.
    pub fn update(&mut self, frame: Option<Arc<Frame>>, records: &mut Vec<StepRecord>) {
        if let Some(f) = frame {
            if f.generation != self.history.generation {
                self.history.generation = f.generation;
                self.history.records.clear();
                self.locked_force_scale = None;
                self.field_max = 0.0;
            }
            // Only a frame that has seen the last edit may overwrite the widgets; older ones
            // would make a slider jump back while it is being dragged.
            if f.applied >= self.params_id {
                self.edit = f.params.clone();
                self.last_sent = f.params.clone();
                self.speed = f.speed;
            }
            self.frame = Some(f);
        }
        let generation = self.history.generation;
        self.history
            .records
            .extend(records.drain(..).filter(|r| r.generation == generation));
        if self.history.records.len() > HISTORY_CAP {
            let excess = self.history.records.len() - HISTORY_CAP;
            self.history.records.drain(..excess);
        }
    }

    fn say(&mut self, text: impl Into<String>, error: bool) {
        self.message = Some(Message {
            text: text.into(),
            error,
            at: Instant::now(),
        });
    }

    pub fn info(&mut self, text: impl Into<String>) {
        self.say(text, false);
    }

    pub fn error(&mut self, text: impl Into<String>) {
        self.say(text, true);
    }

    /// The edited parameters when they differ from those last sent (then counted as sent).
    pub fn param_change(&mut self) -> Option<SolverParams> {
        if self.edit == self.last_sent {
            return None;
        }
        self.last_sent = self.edit.clone();
        Some(self.edit.clone())
    }

    /// Call after the app sent a SetParams or SetSpeed, so that frames published before the
    /// sim thread took it do not reset the widgets.
    pub fn params_sent(&mut self, id: u64) {
        self.params_id = id;
    }

    /// The style of the 3-D view (the same look the `render` command gives).
    pub fn style(&self) -> SceneStyle {
        let d = &self.display;
        SceneStyle {
            coloring: d.coloring,
            field_range: (self.field_max > 0.0).then_some((0.0, self.field_max)),
            arrows: match (d.forces, d.normals) {
                (true, true) => ArrowMode::Both,
                (true, false) => ArrowMode::Forces,
                (false, true) => ArrowMode::Normals,
                (false, false) => ArrowMode::None,
            },
            force_scale: if d.auto_force_scale {
                self.locked_force_scale
            } else {
                Some(d.force_scale)
            },
            transparent: false,
            grid: d.grid,
            edges: d.edges || d.wireframe,
            overlay: d.overlay,
        }
    }

    /// Builds this frame's scene from the newest snapshot.
    fn build_scene(&mut self) {
        let Some(frame) = self.frame.clone() else {
            self.scene = None;
            return;
        };
        let snap = &frame.snapshot;
        let key = (frame.seq, self.style(), self.display.wireframe);
        if self.scene.is_some() && self.scene_key.as_ref() == Some(&key) {
            return; // same snapshot, same look: a large model is not rebuilt every frame
        }
        if self.display.coloring != Coloring::PerBlock {
            // Grow-only colour range, so a colour means the same speed all run long.
            let m = snap
                .blocks
                .iter()
                .filter(|b| !b.fixed)
                .map(|b| match self.display.coloring {
                    Coloring::Velocity => DVec3::from_array(b.velocity).length(),
                    Coloring::Displacement => DVec3::from_array(b.displacement).length(),
                    Coloring::PerBlock => 0.0,
                })
                .filter(|v| v.is_finite())
                .fold(0.0, f64::max);
            self.field_max = self.field_max.max(m);
        }
        match Scene::build(snap, &self.style(), &self.scene_frame) {
            Ok(mut scene) => {
                if self.display.auto_force_scale && self.locked_force_scale.is_none() {
                    self.locked_force_scale = scene.force_scale;
                }
                if self.display.wireframe {
                    scene.solids.clear();
                }
                self.scene = Some(scene);
                self.scene_version += 1;
                // Keyed on the style it was built with (before a new lock of the arrow scale),
                // so the next frame rebuilds once with the locked scale and then settles.
                self.scene_key = Some(key);
            }
            Err(e) => {
                self.scene = None;
                self.error(format!("cannot draw this step: {e}"));
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Formatting

/// Compact number: plain for 0.01..10⁴, else scientific with 3 significant digits.
pub fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if !v.is_finite() {
        format!("{v}")
    } else if (0.01..1e4).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        let s = format!("{v:.2e}");
        // "2.00e8" reads better as "2e8"; keep meaningful digits.
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        format!("{m}e{e}")
    }
}

/// A length with a unit that suits its size.
pub fn length(m: f64) -> String {
    let a = m.abs();
    if !m.is_finite() {
        format!("{m}")
    } else if a == 0.0 {
        "0 m".into()
    } else if a < 1e-3 {
        format!("{} µm", num(m * 1e6))
    } else if a < 1.0 {
        format!("{} mm", num(m * 1e3))
    } else {
        format!("{} m", num(m))
    }
}

/// A duration in s or ms.
pub fn seconds(s: f64) -> String {
    if s.abs() < 0.1 && s != 0.0 {
        format!("{} ms", num(s * 1e3))
    } else {
        format!("{} s", num(s))
    }
}

fn color32(srgb: u32) -> Color32 {
    Color32::from_rgb((srgb >> 16) as u8, (srgb >> 8) as u8, srgb as u8)
}

const ACCENT: Color32 = Color32::from_rgb(0xE0, 0x7A, 0x10);
const ERROR_RED: Color32 = Color32::from_rgb(0xC0, 0x2A, 0x1E);
const OK_GREEN: Color32 = Color32::from_rgb(0x2E, 0x8B, 0x3E);

// ---------------------------------------------------------------------------------------------
// Whole UI

/// Builds the frame's UI. `view_texture` is the 3-D image drawn by the app (sized to
/// `state.view_rect` × pixels per point).
pub fn build(ui: &mut egui::Ui, state: &mut UiState, view_texture: egui::TextureId) -> Vec<Action> {
    let mut actions = Vec::new();
    state.build_scene();
    // Panels are not filled: the window is cleared to the panel colour, and on a software
    // rasterizer every filled pixel counts (about a third of the frame time).
    let panel = |m: egui::Margin| egui::Frame::new().inner_margin(m);
    egui::Panel::top("toolbar")
        .frame(panel(egui::Margin::symmetric(8, 5)))
        .show(ui, |ui| toolbar(ui, state, &mut actions));
    if state.show_plots {
        egui::Panel::bottom("plots")
            .frame(panel(egui::Margin::symmetric(8, 2)))
            .resizable(true)
            .default_size(190.0)
            .min_size(120.0)
            .show(ui, |ui| plots(ui, state));
    }
    egui::Panel::left("controls")
        .frame(panel(egui::Margin::symmetric(8, 2)))
        .resizable(true)
        .default_size(318.0)
        .min_size(260.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                ui.add_space(4.0);
                if let Some(err) = state.frame.as_ref().and_then(|f| f.error.clone()) {
                    error_box(ui, &err);
                }
                egui::CollapsingHeader::new(RichText::new("Solver").strong())
                    .default_open(true)
                    .show(ui, |ui| solver_section(ui, state));
                egui::CollapsingHeader::new(RichText::new("Display").strong())
                    .default_open(true)
                    .show(ui, |ui| display_section(ui, state));
                let title = match state.selected.zip(state.frame.as_ref()) {
                    Some((i, f)) if i < f.snapshot.blocks.len() => {
                        format!("Selection: {}", f.snapshot.blocks[i].name)
                    }
                    _ => "Selection".to_owned(),
                };
                egui::CollapsingHeader::new(RichText::new(title).strong())
                    .id_salt("selection")
                    .default_open(true)
                    .show(ui, |ui| selection_section(ui, state));
                egui::CollapsingHeader::new(RichText::new("Run statistics").strong())
                    .default_open(false)
                    .show(ui, |ui| run_section(ui, state));
            });
        });
    egui::CentralPanel::no_frame().show(ui, |ui| view_3d(ui, state, view_texture));
    keyboard(ui, state, &mut actions);
    actions
}

fn error_box(ui: &mut egui::Ui, err: &str) {
    egui::Frame::new()
        .fill(Color32::from_rgb(0xFB, 0xE4, 0xE1))
        .stroke(Stroke::new(1.0, ERROR_RED))
        .corner_radius(CornerRadius::same(4))
        .inner_margin(egui::Margin::same(6))
        .show(ui, |ui| {
            ui.set_width(ui.available_width());
            ui.label(RichText::new("Solver error").strong().color(ERROR_RED));
            ui.label(RichText::new(err).color(Color32::from_rgb(0x60, 0x10, 0x10)));
            ui.label(RichText::new("Change parameters and press Play to retry, or Reset.").weak());
        });
    ui.add_space(6.0);
}

fn keyboard(ui: &mut egui::Ui, state: &mut UiState, actions: &mut Vec<Action>) {
    if ui.ctx().egui_wants_keyboard_input() {
        return;
    }
    let (space, step, reset, frame_all, esc) = ui.input(|i| {
        (
            i.key_pressed(Key::Space),
            i.key_pressed(Key::ArrowRight) || i.key_pressed(Key::S),
            i.key_pressed(Key::R),
            i.key_pressed(Key::F),
            i.key_pressed(Key::Escape),
        )
    });
    if space {
        actions.push(Action::Sim(if running(state) {
            Command::Pause
        } else {
            Command::Play
        }));
    }
    if step {
        actions.push(Action::Sim(Command::Step));
    }
    if reset {
        actions.push(Action::Sim(Command::Reset));
    }
    if frame_all && let Some(f) = &state.frame {
        let snap = f.snapshot.clone();
        state.view.frame_all(&snap);
    }
    if esc {
        state.selected = None;
    }
}

fn running(state: &UiState) -> bool {
    state
        .frame
        .as_ref()
        .is_some_and(|f| f.state == RunState::Running)
}

// ---------------------------------------------------------------------------------------------
// Toolbar

const SPEEDS: [f64; 8] = [0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0];

/// Toolbar icons, drawn with the painter (egui's default fonts lack the media symbols).
#[derive(Clone, Copy)]
enum Icon {
    Play,
    Pause,
    Step,
    Reset,
    Record,
    Stop,
    Camera,
}

/// A button of fixed width with an icon left of its text.
fn icon_button(
    ui: &mut egui::Ui,
    width: f32,
    icon: Icon,
    text: &str,
    fill: Option<Color32>,
) -> egui::Response {
    // Leading spaces keep the centred text clear of the icon.
    let mut b = egui::Button::new(format!("      {text}"));
    if let Some(f) = fill {
        b = b.fill(f);
    }
    let r = ui.add_sized([width, 24.0], b);
    let color = ui.style().interact(&r).fg_stroke.color;
    let p = ui.painter();
    let c = Pos2::new(r.rect.left() + 15.0, r.rect.center().y);
    let s = 5.0;
    let tri = |pts: Vec<Pos2>, color: Color32| {
        p.add(egui::Shape::convex_polygon(pts, color, Stroke::NONE));
    };
    let bar = |at: Pos2, size: Vec2, color: Color32| {
        p.rect_filled(Rect::from_center_size(at, size), 0.0, color);
    };
    match icon {
        Icon::Play => tri(
            vec![
                c + Vec2::new(-0.7 * s, -s),
                c + Vec2::new(s, 0.0),
                c + Vec2::new(-0.7 * s, s),
            ],
            OK_GREEN,
        ),
        Icon::Pause => {
            for dx in [-2.5, 2.5] {
                bar(c + Vec2::new(dx, 0.0), Vec2::new(2.5, 2.0 * s), color);
            }
        }
        Icon::Step => {
            tri(
                vec![
                    c + Vec2::new(-s, -s),
                    c + Vec2::new(0.5 * s, 0.0),
                    c + Vec2::new(-s, s),
                ],
                color,
            );
            bar(c + Vec2::new(0.9 * s, 0.0), Vec2::new(2.0, 2.0 * s), color);
        }
        Icon::Reset => {
            // An open circle with an arrow head: "back to the start".
            let pts: Vec<Pos2> = (0..=20)
                .map(|k| {
                    let a = (40.0 + 300.0 * k as f32 / 20.0).to_radians();
                    c + Vec2::new(a.cos(), -a.sin()) * s
                })
                .collect();
            let tip = pts[20];
            p.add(egui::Shape::line(pts, Stroke::new(1.6, color)));
            tri(
                vec![
                    tip + Vec2::new(-3.0, -3.0),
                    tip + Vec2::new(3.0, -1.0),
                    tip + Vec2::new(0.0, 3.0),
                ],
                color,
            );
        }
        Icon::Record => {
            p.circle_filled(c, s, ERROR_RED);
        }
        Icon::Stop => bar(c, Vec2::splat(2.0 * s - 1.0), ERROR_RED),
        Icon::Camera => {
            let body = c + Vec2::new(0.0, 1.0);
            p.rect_stroke(
                Rect::from_center_size(body, Vec2::new(2.4 * s, 1.7 * s)),
                1.5,
                Stroke::new(1.4, color),
                egui::StrokeKind::Middle,
            );
            p.circle_stroke(body, 0.45 * s, Stroke::new(1.4, color));
            bar(
                c + Vec2::new(-0.4 * s, -0.95 * s),
                Vec2::new(0.8 * s, 0.4 * s),
                color,
            );
        }
    }
    r
}

fn speed_label(s: Speed) -> String {
    match s {
        Speed::Max => "as fast as possible".into(),
        Speed::RealTime(f) if (f - 1.0).abs() < 1e-12 => "real time (1×)".into(),
        Speed::RealTime(f) => format!("{}× real time", num(f)),
    }
}

fn toolbar(ui: &mut egui::Ui, state: &mut UiState, actions: &mut Vec<Action>) {
    let Some(frame) = state.frame.clone() else {
        ui.label("starting...");
        return;
    };
    ui.horizontal(|ui| {
        ui.spacing_mut().item_spacing.x = 6.0;
        let is_running = frame.state == RunState::Running;
        let (icon, text) = if is_running {
            (Icon::Pause, "Pause")
        } else {
            (Icon::Play, "Play")
        };
        let tip = if frame.state == RunState::Finished {
            "Continue past the end time (by another scene duration)  [Space]"
        } else {
            "Run / pause the simulation  [Space]"
        };
        let fill = (!is_running).then_some(Color32::from_rgb(0xD5, 0xEC, 0xD9));
        if icon_button(ui, 84.0, icon, text, fill)
            .on_hover_text(tip)
            .clicked()
        {
            actions.push(Action::Sim(if is_running {
                Command::Pause
            } else {
                Command::Play
            }));
        }
        if icon_button(ui, 70.0, Icon::Step, "Step", None)
            .on_hover_text("Advance one time step, then pause  [Right arrow or S]")
            .clicked()
        {
            actions.push(Action::Sim(Command::Step));
        }
        if icon_button(ui, 74.0, Icon::Reset, "Reset", None)
            .on_hover_text("Back to t = 0 with the current parameters  [R]")
            .clicked()
        {
            actions.push(Action::Sim(Command::Reset));
        }
        ui.separator();
        ui.label("Speed");
        let before = state.speed;
        egui::ComboBox::from_id_salt("speed")
            .width(150.0)
            .selected_text(speed_label(state.speed))
            .show_ui(ui, |ui| {
                for f in SPEEDS {
                    ui.selectable_value(
                        &mut state.speed,
                        Speed::RealTime(f),
                        speed_label(Speed::RealTime(f)),
                    );
                }
                ui.selectable_value(&mut state.speed, Speed::Max, speed_label(Speed::Max));
            })
            .response
            .on_hover_text(
                "Simulated seconds per wall-clock second. \"As fast as possible\" steps back \
                 to back; the window keeps drawing the newest state.",
            );
        if state.speed != before {
            actions.push(Action::Sim(Command::SetSpeed(state.speed)));
        }
        ui.separator();
        let snap = &frame.snapshot;
        ui.label(RichText::new(format!("t = {}", format_time(snap.time))).strong())
            .on_hover_text("Simulated time");
        ui.label(RichText::new(format!("/ {}", format_time(frame.params.duration))).weak())
            .on_hover_text("End time: the run pauses here; Play continues past it");
        ui.label(format!("step {}", snap.step));
        ui.label(format!("Δt {}", seconds(snap.stats.time_step)))
            .on_hover_text("Length of the last accepted step");
        ui.label(format!("cuts {}", frame.totals.time_step_cuts))
            .on_hover_text(
                "Time-step cuts so far: attempts redone with a smaller Δt (displacement over \
                 δ·w0, or open–close not converging)",
            );
        ui.separator();
        let (text, color) = match frame.state {
            RunState::Running => ("RUNNING", OK_GREEN),
            RunState::Paused => ("PAUSED", Color32::from_gray(90)),
            RunState::Finished => ("AT END TIME", Color32::from_rgb(0x2F, 0x5F, 0xB0)),
            RunState::Failed => ("SOLVER ERROR", ERROR_RED),
        };
        ui.label(RichText::new(text).strong().color(color));

        ui.with_layout(Layout::right_to_left(Align::Center), |ui| {
            let (interval, busy) = state.perf.recent_ms();
            let fps = if interval > 0.0 { 1e3 / interval } else { 0.0 };
            let sps = frame.steps_per_second;
            ui.label(
                RichText::new(format!(
                    "{fps:.0} fps · {} steps/s",
                    if sps > 0.0 {
                        num(sps.round())
                    } else {
                        "–".into()
                    }
                ))
                .monospace()
                .weak(),
            )
            .on_hover_text(format!(
                "Window: {interval:.1} ms between frames, {busy:.1} ms of CPU per frame.\n\
                 Solver: {} per step.\nGPU: {}",
                seconds(frame.seconds_per_step),
                state.adapter
            ));
            ui.separator();
            let rec = state.recording.is_some();
            let (icon, text) = if rec {
                (Icon::Stop, "Stop")
            } else {
                (Icon::Record, "Record")
            };
            if icon_button(ui, 84.0, icon, text, None)
                .on_hover_text(
                    "Write a PNG of the 3-D view for every new step shown while running \
                     (window size, camera fixed at the start), plus frames.csv",
                )
                .clicked()
            {
                actions.push(Action::ToggleRecord);
            }
            if icon_button(ui, 112.0, Icon::Camera, "Screenshot", None)
                .on_hover_text("Write the 3-D view at window size as a PNG")
                .clicked()
            {
                actions.push(Action::Screenshot);
            }
        });
    });
}

// ---------------------------------------------------------------------------------------------
// Solver parameters

/// A slider that leaves values outside its range alone (a scene may set any valid value;
/// merely showing it must not change it), while keeping new edits inside the range.
fn slider<Num: egui::emath::Numeric>(
    value: &mut Num,
    range: std::ops::RangeInclusive<Num>,
) -> egui::Slider<'_> {
    egui::Slider::new(value, range).clamping(egui::SliderClamping::Edits)
}

fn param_label(ui: &mut egui::Ui, text: &str, tip: &str) {
    ui.label(text).on_hover_text(tip);
}

fn solver_section(ui: &mut egui::Ui, state: &mut UiState) {
    let young = state.young;
    let w0 = state
        .frame
        .as_ref()
        .map(|f| f.max_step_penetration / (2.0 * f.params.max_displacement_ratio))
        .filter(|v| v.is_finite() && *v > 0.0)
        .unwrap_or(1.0);
    let e = &mut state.edit;

    ui.horizontal(|ui| {
        ui.label("Method").on_hover_text(
            "How normal contacts are enforced.\n\
             DDA-3a: augmented Lagrangian — multipliers λ absorb the contact force, so \
             penetration falls below ε1·d_n,max without a huge penalty; p_n grows only where \
             convergence is slow (P21).\n\
             DDA-3p: classic fixed penalty p_n = p_n,1; penetration ≈ N / p_n.",
        );
        ui.selectable_value(&mut e.method, Method::Alm, "ALM (DDA-3a)");
        ui.selectable_value(&mut e.method, Method::Penalty, "Penalty (DDA-3p)");
    });
    ui.horizontal(|ui| {
        ui.label("Mode").on_hover_text(
            "Dynamic: velocities carry over between steps.\n\
             Static: velocities reset to zero every step, so the system creeps into \
             equilibrium (for stability checks).",
        );
        ui.selectable_value(&mut e.mode, Mode::Dynamic, "Dynamic");
        ui.selectable_value(&mut e.mode, Mode::Static, "Static");
    });
    ui.add_space(4.0);

    let alm = e.method == Method::Alm;
    let d_n_max = 2.0 * e.max_displacement_ratio * w0;
    egui::Grid::new("params")
        .num_columns(3)
        .spacing([8.0, 5.0])
        .striped(true)
        .show(ui, |ui| {
            param_label(
                ui,
                "p_n,1",
                "Initial normal penalty of a new contact (ALM), and the fixed penalty in \
                 penalty mode, N/m. The paper uses p_n,1 = 0.01 E (the same as DDA-3p) and \
                 warns it should not be too small.",
            );
            ui.add(
                slider(&mut e.contact.initial_penalty, young * 1e-6..=young * 100.0)
                    .logarithmic(true)
                    .custom_formatter(|v, _| num(v))
                    .suffix(" N/m"),
            );
            ui.label(RichText::new(format!("{} E", num(e.contact.initial_penalty / young))).weak())
                .on_hover_text(format!("as a multiple of E = {} Pa", num(young)));
            ui.end_row();

            ui.add_enabled_ui(alm, |ui| {
                param_label(
                    ui,
                    "α",
                    "(P21) Penalty growth factor: p_n,k = α·p_n,k−1 when |d_n,k| > β·|d_n,k−1| \
                     (a contact whose penetration does not shrink fast enough). Paper: α = 10.",
                )
            });
            ui.add_enabled(
                alm,
                slider(&mut e.contact.alpha, 1.01..=1000.0)
                    .logarithmic(true)
                    .custom_formatter(|v, _| num(v)),
            );
            ui.label("");
            ui.end_row();

            ui.add_enabled_ui(alm, |ui| {
                param_label(
                    ui,
                    "β",
                    "(P21) Convergence-rate threshold in (0, 1): the penalty of a contact grows \
                     when |d_n,k| > β·|d_n,k−1|. Paper: β = 0.25.",
                )
            });
            ui.add_enabled(
                alm,
                slider(&mut e.contact.beta, 0.01..=0.99).fixed_decimals(2),
            );
            ui.label("");
            ui.end_row();

            ui.add_enabled_ui(alm, |ui| {
                param_label(
                    ui,
                    "γ",
                    "(P21b) Penalty cap: p_n ≤ γ·E. The paper advises γ ≤ 100 (the condition \
                     number grows like p·Δt²/m).",
                )
            });
            ui.add_enabled(
                alm,
                slider(&mut e.contact.gamma, 0.01..=1000.0)
                    .logarithmic(true)
                    .custom_formatter(|v, _| num(v))
                    .suffix(" E"),
            );
            ui.label(RichText::new(format!("{} N/m", num(e.contact.gamma * young))).weak());
            ui.end_row();

            ui.add_enabled_ui(alm, |ui| {
                param_label(
                    ui,
                    "ε1",
                    "(P22)–(P23) Penetration tolerance: ALM iterations stop when every closed \
                     contact's |d_n| ≤ ε1·d_n,max, with d_n,max = 2·δ·w0. The paper recommends \
                     0.01 < ε1 < 0.1 and uses 0.01.",
                )
            });
            ui.add_enabled(
                alm,
                slider(&mut e.contact.eps1, 1e-4..=0.5)
                    .logarithmic(true)
                    .custom_formatter(|v, _| num(v)),
            );
            ui.label(RichText::new(format!("≤ {}", length(e.contact.eps1 * d_n_max))).weak())
                .on_hover_text("ε1·d_n,max: the penetration ALM aims for");
            ui.end_row();

            ui.add_enabled_ui(alm, |ui| {
                param_label(
                    ui,
                    "ε2",
                    "(P24) Force tolerance: ALM iterations also require \
                     |λ_k − λ_k−1| / |λ_k−1| < ε2 (relative change of the normal contact forces). \
                     The paper recommends 0 < ε2 < 0.1 and uses 0.01.",
                )
            });
            ui.add_enabled(
                alm,
                slider(&mut e.contact.eps2, 1e-4..=0.5)
                    .logarithmic(true)
                    .custom_formatter(|v, _| num(v)),
            );
            ui.label("");
            ui.end_row();

            param_label(
                ui,
                "φ",
                "Joint friction angle (Mohr–Coulomb): a closed contact slides when its shear \
                 force exceeds N·tan φ (+ cohesion). The paper's examples use 35°.",
            );
            ui.add(
                slider(&mut e.joint.friction_angle, 0.0..=89.0)
                    .fixed_decimals(1)
                    .suffix("°"),
            );
            ui.label(
                RichText::new(format!(
                    "tan φ = {:.2}",
                    e.joint.friction_angle.to_radians().tan()
                ))
                .weak(),
            );
            ui.end_row();

            param_label(
                ui,
                "c",
                "Joint cohesion, Pa. Acts only on joints closed from the start that have never \
                 opened or slid (Shi's rule): once broken a joint keeps only friction.",
            );
            ui.add(
                slider(&mut e.joint.cohesion, 0.0..=1e8)
                    .logarithmic(true)
                    .smallest_positive(1e2)
                    .custom_formatter(|v, _| num(v))
                    .suffix(" Pa"),
            );
            ui.label("");
            ui.end_row();

            param_label(
                ui,
                "δ",
                "Maximum displacement ratio: the largest vertex displacement allowed in one step, \
                 as a fraction of w0 (half the model's largest extent). A step that moves further \
                 is redone with a smaller Δt. It also sets d_n,max = 2·δ·w0 (P22). Paper: 0.01.",
            );
            ui.add(
                slider(&mut e.max_displacement_ratio, 1e-4..=0.1)
                    .logarithmic(true)
                    .custom_formatter(|v, _| num(v)),
            );
            ui.label(
                RichText::new(format!("δ·w0 = {}", length(e.max_displacement_ratio * w0))).weak(),
            );
            ui.end_row();

            param_label(
                ui,
                "Δt_max",
                "Largest time step, s. Steps start at Δt_max, are cut when a step moves too far \
                 or open–close does not converge, and grow back by ≤ 1.3× per step. Paper: 0.01 s.",
            );
            ui.add(
                slider(&mut e.max_time_step, 1e-5..=0.1)
                    .logarithmic(true)
                    .custom_formatter(|v, _| num(v))
                    .suffix(" s"),
            );
            ui.label(RichText::new(seconds(e.max_time_step)).weak());
            ui.end_row();

            param_label(
                ui,
                "End time",
                "The run pauses when simulated time reaches this; Play continues past it.",
            );
            ui.add(
                egui::DragValue::new(&mut e.duration)
                    .range(1e-3..=1e6)
                    .clamp_existing_to_range(false)
                    .speed(0.05)
                    .suffix(" s"),
            );
            ui.label("");
            ui.end_row();
        });

    egui::CollapsingHeader::new("More contact settings")
        .default_open(false)
        .show(ui, |ui| {
            egui::Grid::new("params_more")
                .num_columns(2)
                .spacing([8.0, 5.0])
                .show(ui, |ui| {
                    param_label(
                        ui,
                        "p_τ / p_n,1",
                        "Shear spring of locked contacts relative to p_n,1. The paper does not \
                         give p_τ; Shi's code uses p_n / 2.5.",
                    );
                    ui.add(
                        slider(&mut e.contact.shear_penalty_ratio, 0.01..=10.0)
                            .logarithmic(true)
                            .custom_formatter(|v, _| num(v)),
                    );
                    ui.end_row();
                    param_label(
                        ui,
                        "ALM iterations",
                        "Cap on ALM iterations per open–close pass (the paper's loop has none; \
                         20 is the reference notes' suggestion).",
                    );
                    ui.add(slider(&mut e.contact.max_alm_iterations, 1..=100));
                    ui.end_row();
                    param_label(
                        ui,
                        "Open–close passes",
                        "Open–close passes before the step is redone with 0.3·Δt (Shi: 6 + 2; walls of many blocks need 10–25 at an impact). If at most 1 % of the contacts still change then, they are settled closed and locked instead.",
                    );
                    ui.add(slider(&mut e.contact.max_open_close_iterations, 1..=50));
                    ui.end_row();
                    param_label(
                        ui,
                        "Warm start",
                        "Carry λ and p_n of persisting contacts from one step to the next. The \
                         paper is silent; both converge to the same forces, warm starting in \
                         fewer iterations.",
                    );
                    ui.checkbox(&mut e.contact.warm_start, "");
                    ui.end_row();
                });
        });

    ui.add_space(4.0);
    ui.horizontal(|ui| {
        if ui
            .button("Paper defaults")
            .on_hover_text(
                "Contact law and time stepping of the paper (Zhang Hong 2019, §3): \
                 p_n,1 = 0.01 E, α = 10, β = 0.25, γ = 100, ε1 = ε2 = 0.01, δ = 0.01, \
                 Δt_max = 0.01 s. Method, mode, joint and end time are kept.",
            )
            .clicked()
        {
            let d = SolverParams::default();
            let keep = e.clone();
            *e = SolverParams {
                method: keep.method,
                mode: keep.mode,
                duration: keep.duration,
                gravity: keep.gravity,
                joint: keep.joint.clone(),
                ..d
            };
            e.contact.initial_penalty = 0.01 * young;
        }
        if ui
            .button("Scene values")
            .on_hover_text("Every parameter back to what the scene file says")
            .clicked()
        {
            let end = e.duration;
            *e = state.scene_params.clone();
            e.duration = end.max(state.scene_params.duration);
        }
    });
}

// ---------------------------------------------------------------------------------------------
// Display options

fn display_section(ui: &mut egui::Ui, state: &mut UiState) {
    let d = &mut state.display;
    let before = d.clone();
    ui.horizontal(|ui| {
        ui.label("Colour by");
        egui::ComboBox::from_id_salt("coloring")
            .selected_text(match d.coloring {
                Coloring::PerBlock => "block",
                Coloring::Velocity => "speed |v|",
                Coloring::Displacement => "displacement |u|",
            })
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut d.coloring, Coloring::PerBlock, "block");
                ui.selectable_value(&mut d.coloring, Coloring::Velocity, "speed |v|");
                ui.selectable_value(&mut d.coloring, Coloring::Displacement, "displacement |u|");
            });
    });
    ui.horizontal(|ui| {
        ui.checkbox(&mut d.forces, "Force arrows").on_hover_text(
            "Normal contact force on block i, coloured by state (lock blue, slide red)",
        );
        ui.checkbox(&mut d.normals, "Contact normals");
    });
    ui.add_enabled_ui(d.forces, |ui| {
        ui.horizontal(|ui| {
            ui.label("Scale");
            ui.selectable_value(&mut d.auto_force_scale, true, "auto")
                .on_hover_text("Chosen from the first step with contacts, then kept fixed");
            ui.selectable_value(&mut d.auto_force_scale, false, "manual");
            if d.auto_force_scale {
                if let Some(s) = state.locked_force_scale {
                    ui.label(RichText::new(format!("1 m = {}", format_force(s))).weak());
                }
            } else {
                ui.add(
                    slider(&mut d.force_scale, 1.0..=1e10)
                        .logarithmic(true)
                        .custom_formatter(|v, _| format_force(v))
                        .text("per m"),
                );
            }
        });
    });
    ui.horizontal(|ui| {
        ui.checkbox(&mut d.edges, "Edges");
        ui.checkbox(&mut d.wireframe, "Wireframe");
        ui.checkbox(&mut d.grid, "Grid");
    });
    ui.horizontal(|ui| {
        ui.checkbox(&mut d.labels, "Labels");
        ui.checkbox(&mut d.overlay, "Legend");
        ui.checkbox(&mut state.show_plots, "Plots");
    });
    if d.coloring != before.coloring {
        state.field_max = 0.0;
    }
    if !before.auto_force_scale
        && d.auto_force_scale
        && let Some(s) = state.locked_force_scale
    {
        d.force_scale = s;
    }
    if before.auto_force_scale && !d.auto_force_scale {
        d.force_scale = state.locked_force_scale.unwrap_or(d.force_scale);
    }
    ui.horizontal(|ui| {
        if ui
            .button("Frame all (F)")
            .on_hover_text("Fit every block into the view, keeping the direction")
            .clicked()
            && let Some(f) = &state.frame
        {
            let snap = f.snapshot.clone();
            state.view.frame_all(&snap);
        }
        if ui.button("Reset view").clicked() {
            let aspect = state.view.camera.aspect;
            state.view = ViewControls::new(state.scene_frame.lo, state.scene_frame.hi, aspect);
        }
    });
    ui.label(
        RichText::new("Left drag: orbit · right/middle drag: pan · wheel: zoom · click: select")
            .small()
            .weak(),
    );
}

// ---------------------------------------------------------------------------------------------
// Selection

fn selection_section(ui: &mut egui::Ui, state: &mut UiState) {
    let Some(frame) = state.frame.clone() else {
        return;
    };
    let snap = &frame.snapshot;
    let Some(i) = state.selected.filter(|&i| i < snap.blocks.len()) else {
        ui.label(RichText::new("Click a block in the view to see its state and contacts.").weak());
        return;
    };
    let b = &snap.blocks[i];
    let info = state.blocks.get(i);
    egui::Grid::new("sel")
        .num_columns(2)
        .spacing([10.0, 3.0])
        .show(ui, |ui| {
            ui.label("Block");
            ui.label(
                RichText::new(format!(
                    "{} (#{i}){}",
                    b.name,
                    if b.fixed { ", fixed" } else { "" }
                ))
                .strong(),
            );
            ui.end_row();
            if let Some(info) = info {
                ui.label("Mass");
                ui.label(format!("{} kg", num(info.mass)));
                ui.end_row();
                ui.label("Material");
                ui.label(format!(
                    "ρ {} kg/m³, E {} Pa, ν {}",
                    num(info.density),
                    num(info.young),
                    num(info.poisson)
                ));
                ui.end_row();
            }
            let c = b.centroid;
            ui.label("Centroid");
            ui.label(format!("({:.3}, {:.3}, {:.3}) m", c[0], c[1], c[2]));
            ui.end_row();
            let u = DVec3::from_array(b.displacement);
            ui.label("Displacement");
            ui.label(format!(
                "|u| = {}  ({:.3}, {:.3}, {:.3}) m",
                length(u.length()),
                u.x,
                u.y,
                u.z
            ));
            ui.end_row();
            let v = DVec3::from_array(b.velocity);
            ui.label("Velocity");
            ui.label(format!(
                "|v| = {} m/s  ({:.2}, {:.2}, {:.2})",
                num(v.length()),
                v.x,
                v.y,
                v.z
            ));
            ui.end_row();
        });
    let contacts: Vec<_> = snap
        .contacts
        .iter()
        .filter(|c| c.block_i == i || c.block_j == i)
        .collect();
    ui.add_space(4.0);
    ui.label(RichText::new(format!("{} closed contacts", contacts.len())).strong());
    if contacts.is_empty() {
        return;
    }
    let total_n: f64 = contacts.iter().map(|c| c.normal_force).sum();
    ui.label(
        RichText::new(format!("Σ N = {}", format_force(total_n)))
            .weak()
            .small(),
    );
    egui::ScrollArea::vertical()
        .id_salt("sel_contacts")
        .max_height(220.0)
        .show(ui, |ui| {
            egui::Grid::new("sel_contacts_grid")
                .num_columns(6)
                .striped(true)
                .spacing([8.0, 2.0])
                .show(ui, |ui| {
                    for h in ["with", "type", "state", "N", "d_n", "p_n"] {
                        ui.label(RichText::new(h).small().strong());
                    }
                    ui.end_row();
                    for c in contacts.iter().take(200) {
                        let other = if c.block_i == i { c.block_j } else { c.block_i };
                        let name = snap
                            .blocks
                            .get(other)
                            .map(|b| b.name.as_str())
                            .unwrap_or("?");
                        ui.label(RichText::new(name).small());
                        ui.label(
                            RichText::new(match c.mode {
                                ContactMode::VertexFace => "V–F",
                                ContactMode::EdgeEdge => "E–E",
                            })
                            .small(),
                        )
                        .on_hover_text(if c.block_i == i {
                            "this block owns the vertex / first edge"
                        } else {
                            "this block owns the face / second edge"
                        });
                        let (st, col) = match c.state {
                            ContactState::Lock => ("lock", color32(LOCK_SRGB)),
                            ContactState::Slide => ("slide", color32(SLIDE_SRGB)),
                            ContactState::Open => ("open", color32(OPEN_SRGB)),
                        };
                        ui.label(RichText::new(st).small().color(col));
                        ui.label(RichText::new(format_force(c.normal_force)).small())
                            .on_hover_text(format!(
                                "normal {} , shear {}, λ = {}",
                                format_force(c.normal_force),
                                format_force(c.shear_force),
                                format_force(c.lambda)
                            ));
                        ui.label(RichText::new(length(c.penetration)).small())
                            .on_hover_text("penetration (positive = overlap)");
                        ui.label(
                            RichText::new(format!("{} E", num(c.penalty / state.young))).small(),
                        )
                        .on_hover_text(format!("{} N/m", num(c.penalty)));
                        ui.end_row();
                    }
                });
        });
}

fn run_section(ui: &mut egui::Ui, state: &mut UiState) {
    let Some(f) = state.frame.clone() else {
        return;
    };
    let t = &f.totals;
    egui::Grid::new("totals")
        .num_columns(2)
        .spacing([10.0, 2.0])
        .show(ui, |ui| {
            let mut row = |k: &str, v: String| {
                ui.label(k);
                ui.label(v);
                ui.end_row();
            };
            row("Steps", t.steps.to_string());
            row("Open–close passes", t.open_close_iterations.to_string());
            row("Linear solves (ALM)", t.alm_iterations.to_string());
            row("Factorizations", t.factorizations.to_string());
            row("Time-step cuts", t.time_step_cuts.to_string());
            row("Unconverged steps", t.unconverged_steps.to_string());
            row("ALM cap hits", t.alm_cap_hits.to_string());
            row("Max penetration", length(t.max_penetration));
            row("d_n,max = 2δw0", length(f.max_step_penetration));
            row("Solver time / step", seconds(f.seconds_per_step));
            row("GPU", state.adapter.clone());
        });
}

// ---------------------------------------------------------------------------------------------
// Plots

/// Downsamples `records` to at most `PLOT_POINTS` buckets, applying `reduce` to each bucket's
/// values (max for peaks so a spike is never hidden).
fn series(
    records: &[StepRecord],
    value: impl Fn(&StepRecord) -> f64,
    reduce: fn(f64, f64) -> f64,
) -> Vec<[f64; 2]> {
    let n = records.len();
    if n == 0 {
        return Vec::new();
    }
    let per = n.div_ceil(PLOT_POINTS).max(1);
    records
        .chunks(per)
        .filter_map(|c| {
            let v = c
                .iter()
                .map(&value)
                .filter(|v| v.is_finite())
                .reduce(reduce)?;
            Some([c[c.len() - 1].time, v])
        })
        .collect()
}

fn plot_title(ui: &mut egui::Ui, title: &str, tip: &str) {
    ui.label(RichText::new(title).strong().size(13.0))
        .on_hover_text(tip);
}

/// A dashed grey line marking a limit (a tolerance or a cap) on a plot.
fn limit_line(name: &str, y: f64) -> HLine {
    HLine::new(name, y)
        .style(LineStyle::dashed_loose())
        .color(Color32::from_gray(110))
}

fn small_plot<'a>(id: &str, height: f32) -> Plot<'a> {
    Plot::new(id)
        .height(height)
        .allow_zoom(false)
        .allow_drag(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .allow_double_click_reset(false)
        .show_x(true)
        .show_y(true)
        .y_axis_min_width(34.0)
        .legend(Legend::default().background_alpha(0.6))
        .link_cursor(egui::Id::unique("plots_x"), [true, false])
        .x_axis_formatter(|m, _| format!("{} s", num(m.value)))
}

fn plots(ui: &mut egui::Ui, state: &mut UiState) {
    let recs = &state.history.records;
    let dn_max = state
        .frame
        .as_ref()
        .map(|f| f.max_step_penetration)
        .unwrap_or(0.0);
    let params = state.frame.as_ref().map(|f| f.params.clone());
    let young = state.young;
    let h = (ui.available_height() - 22.0).max(60.0);
    let blue = color32(LOCK_SRGB);
    let red = color32(SLIDE_SRGB);
    let grey = color32(OPEN_SRGB);
    let max = f64::max as fn(f64, f64) -> f64;
    let min = f64::min as fn(f64, f64) -> f64;
    ui.add_space(2.0);
    ui.columns(5, |cols| {
        // 1. Maximum penetration, mm, with the ALM target ε1·d_n,max.
        let ui = &mut cols[0];
        plot_title(
            ui,
            "Max penetration (mm)",
            "Largest penetration over closed contacts after each step. The dashed line is the \
             ALM target ε1·d_n,max (P23).",
        );
        let pen = series(recs, |r| r.max_penetration * 1e3, max);
        small_plot("pen", h).show(ui, |p| {
            p.line(
                Line::new("max d_n", PlotPoints::from(pen))
                    .color(ACCENT)
                    .width(1.5),
            );
            if let Some(pr) = &params
                && pr.method == Method::Alm
                && dn_max > 0.0
            {
                p.hline(limit_line("ε1·d_n,max", pr.contact.eps1 * dn_max * 1e3));
            }
        });

        // 2. Contacts by state.
        let ui = &mut cols[1];
        plot_title(
            ui,
            "Contacts",
            "Closed contacts in the lock and slide states, and detected but open ones.",
        );
        let lock = series(recs, |r| r.lock as f64, max);
        let slide = series(recs, |r| r.slide as f64, max);
        let open = series(recs, |r| r.open as f64, max);
        small_plot("contacts", h).show(ui, |p| {
            p.line(Line::new("lock", PlotPoints::from(lock)).color(blue));
            p.line(Line::new("slide", PlotPoints::from(slide)).color(red));
            p.line(Line::new("open", PlotPoints::from(open)).color(grey));
        });

        // 3. Iterations per step.
        let ui = &mut cols[2];
        plot_title(
            ui,
            "Iterations / step",
            "Linear solves per step (ALM iterations summed over the open–close passes; one \
             per pass in penalty mode) and open–close passes, in the accepted attempt.",
        );
        let alm = series(recs, |r| r.alm_iterations as f64, max);
        let oc = series(recs, |r| r.open_close_iterations as f64, max);
        let cuts = series(recs, |r| r.cuts as f64, max);
        small_plot("iters", h).show(ui, |p| {
            p.line(Line::new("ALM solves", PlotPoints::from(alm)).color(ACCENT));
            p.line(
                Line::new("open–close", PlotPoints::from(oc))
                    .color(Color32::from_rgb(0x2F, 0x5F, 0xB0)),
            );
            p.line(
                Line::new("Δt cuts", PlotPoints::from(cuts))
                    .color(Color32::from_gray(120))
                    .style(LineStyle::dotted_dense()),
            );
        });

        // 4. Penalties, as log10(p_n / E).
        let ui = &mut cols[3];
        plot_title(
            ui,
            "Penalty p_n / E",
            "Smallest, mean and largest normal penalty over the closed contacts (log scale). \
             ALM raises p_n where convergence is slow, up to γ·E (dashed).",
        );
        let lg = move |v: f64| (v / young).log10();
        let pmax = series(recs, |r| lg(r.penalty_max), max);
        let pmean = series(recs, |r| lg(r.penalty_mean), max);
        let pmin = series(recs, |r| lg(r.penalty_min), min);
        small_plot("penalty", h)
            .y_axis_formatter(|m, _| num(10f64.powf(m.value)))
            .show(ui, |p| {
                p.line(Line::new("max", PlotPoints::from(pmax)).color(red));
                p.line(Line::new("mean", PlotPoints::from(pmean)).color(ACCENT));
                p.line(Line::new("min", PlotPoints::from(pmin)).color(blue));
                if let Some(pr) = &params
                    && pr.method == Method::Alm
                {
                    p.hline(limit_line("γ·E", pr.contact.gamma.log10()));
                }
            });

        // 5. Kinetic energy.
        let ui = &mut cols[4];
        plot_title(
            ui,
            "Kinetic energy (kJ)",
            "Kinetic energy 1/2 v^T M v summed over all blocks after each step.",
        );
        let ke = series(recs, |r| r.kinetic_energy * 1e-3, max);
        small_plot("ke", h).show(ui, |p| {
            p.line(
                Line::new("E_k", PlotPoints::from(ke))
                    .color(Color32::from_rgb(0x6A, 0x3D, 0x9A))
                    .fill(0.0)
                    .fill_alpha(0.15),
            );
        });
    });
}

// ---------------------------------------------------------------------------------------------
// 3-D view

fn view_3d(ui: &mut egui::Ui, state: &mut UiState, texture: egui::TextureId) {
    let rect = ui.max_rect();
    state.view_rect = rect;
    state.view.set_viewport(rect.width(), rect.height());
    let response = ui.allocate_rect(rect, Sense::click_and_drag());
    let (w, h) = (rect.width(), rect.height());

    // Camera input.
    let delta = response.drag_delta();
    if response.dragged_by(PointerButton::Primary) {
        state.view.drag(DragButton::Left, delta.x, delta.y, h);
    } else if response.dragged_by(PointerButton::Secondary) {
        state.view.drag(DragButton::Right, delta.x, delta.y, h);
    } else if response.dragged_by(PointerButton::Middle) {
        state.view.drag(DragButton::Middle, delta.x, delta.y, h);
    }
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            state.view.scroll(scroll);
        }
    }
    if response.clicked()
        && let (Some(pos), Some(f)) = (response.interact_pointer_pos(), &state.frame)
    {
        let p = pos - rect.min;
        state.selected = state.view.pick(&f.snapshot, p.x, p.y, w, h);
    }

    let painter = ui.painter_at(rect);
    painter.image(
        texture,
        rect,
        Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
        Color32::WHITE,
    );
    let Some(frame) = state.frame.clone() else {
        return;
    };
    let snap = &frame.snapshot;
    let to_screen = |p: [f64; 3]| {
        state
            .view
            .project(p, w, h)
            .map(|(x, y)| rect.min + Vec2::new(x, y))
    };

    // Selected block: outline on top of everything (drawn through other blocks on purpose, so
    // a block hidden behind others can still be followed).
    if let Some(b) = state.selected.and_then(|i| snap.blocks.get(i)) {
        let pts: Vec<Option<Pos2>> = b.vertices.iter().map(|v| to_screen(*v)).collect();
        let stroke = Stroke::new(2.5, ACCENT);
        for face in &b.faces {
            for k in 0..face.len() {
                let (a, c) = (face[k] as usize, face[(k + 1) % face.len()] as usize);
                if a < c
                    && let (Some(Some(p)), Some(Some(q))) = (pts.get(a), pts.get(c))
                {
                    painter.line_segment([*p, *q], stroke);
                }
            }
        }
        if let Some(c) = to_screen(b.centroid) {
            painter.circle_filled(c, 3.5, ACCENT);
        }
    }

    if state.display.labels {
        for (i, b) in snap.blocks.iter().enumerate().take(300) {
            if let Some(c) = to_screen(b.centroid)
                && rect.contains(c)
            {
                let color = if state.selected == Some(i) {
                    ACCENT
                } else {
                    Color32::from_gray(20)
                };
                let galley =
                    painter.layout_no_wrap(b.name.clone(), FontId::proportional(13.0), color);
                let r = Align2::CENTER_CENTER.anchor_size(c, galley.size());
                painter.rect_filled(
                    r.expand(2.0),
                    3.0,
                    Color32::from_rgba_unmultiplied(255, 255, 255, 190),
                );
                painter.galley(r.min, galley, color);
            }
        }
    }

    if let Some(scene) = &state.scene
        && scene.overlay
    {
        paint_overlay(&painter, scene, &state.view.camera, rect);
    }

    if let Some(i) = state.selected
        && let Some(b) = snap.blocks.get(i)
    {
        selection_card(&painter, rect, state, snap, i, b);
    }
    status_toasts(ui, &painter, rect, state);

    if response.hovered() && !response.dragged() {
        ui.ctx().set_cursor_icon(egui::CursorIcon::Crosshair);
    }
}

/// A translucent card with lines of text, anchored at `anchor` of `rect` (inset by a margin).
fn card(painter: &egui::Painter, rect: Rect, anchor: Align2, lines: &[(String, Color32, bool)]) {
    let galleys: Vec<_> = lines
        .iter()
        .map(|(t, c, strong)| {
            let font = if *strong {
                FontId::proportional(15.0)
            } else {
                FontId::proportional(13.0)
            };
            painter.layout_no_wrap(t.clone(), font, *c)
        })
        .collect();
    let w = galleys.iter().map(|g| g.size().x).fold(0.0, f32::max);
    let h: f32 = galleys.iter().map(|g| g.size().y + 2.0).sum();
    let pad = 18.0;
    let inner = rect.shrink(pad);
    let r = anchor.align_size_within_rect(Vec2::new(w, h), inner);
    painter.rect_filled(
        r.expand(7.0),
        5.0,
        Color32::from_rgba_unmultiplied(255, 255, 255, 215),
    );
    let mut y = r.min.y;
    for (g, (_, c, _)) in galleys.into_iter().zip(lines) {
        let gh = g.size().y;
        painter.galley(Pos2::new(r.min.x, y), g, *c);
        y += gh + 2.0;
    }
}

/// The selected block's vital numbers, top right of the view (the full contact list is in
/// the panel).
fn selection_card(
    painter: &egui::Painter,
    rect: Rect,
    state: &UiState,
    snap: &Snapshot,
    i: usize,
    b: &crate::snapshot::BlockSnapshot,
) {
    let text = Color32::from_gray(25);
    let dim = Color32::from_gray(80);
    let u = DVec3::from_array(b.displacement).length();
    let v = DVec3::from_array(b.velocity).length();
    let contacts: Vec<_> = snap
        .contacts
        .iter()
        .filter(|c| c.block_i == i || c.block_j == i)
        .collect();
    let n: f64 = contacts.iter().map(|c| c.normal_force).sum();
    let sliding = contacts
        .iter()
        .filter(|c| c.state == ContactState::Slide)
        .count();
    let mut lines = vec![(
        format!("{}{}", b.name, if b.fixed { " (fixed)" } else { "" }),
        ACCENT,
        true,
    )];
    if let Some(info) = state.blocks.get(i) {
        lines.push((format!("mass {} kg", num(info.mass)), dim, false));
    }
    lines.push((
        format!("|u| = {}    |v| = {} m/s", length(u), num(v)),
        text,
        false,
    ));
    lines.push((
        format!(
            "{} contacts ({} sliding), Σ N = {}",
            contacts.len(),
            sliding,
            format_force(n)
        ),
        text,
        false,
    ));
    lines.push(("details in the panel · Esc to clear".into(), dim, false));
    card(painter, rect, Align2::RIGHT_TOP, &lines);
}

/// Recording indicator and the latest message, bottom centre of the view.
fn status_toasts(ui: &egui::Ui, painter: &egui::Painter, rect: Rect, state: &UiState) {
    let mut lines = Vec::new();
    if let Some(r) = &state.recording {
        lines.push((
            format!("REC  {} frames to {}", r.frames, r.dir.display()),
            ERROR_RED,
            true,
        ));
    }
    const SHOW: Duration = Duration::from_secs(8);
    if let Some(m) = &state.message {
        let age = m.at.elapsed();
        if age < SHOW {
            let c = if m.error {
                ERROR_RED
            } else {
                Color32::from_gray(40)
            };
            lines.push((m.text.clone(), c, false));
            // Redraw when it should disappear, even if nothing else moves.
            ui.ctx().request_repaint_after(SHOW - age);
        }
    }
    if !lines.is_empty() {
        card(painter, rect, Align2::CENTER_BOTTOM, &lines);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(step: u64, pen: f64) -> StepRecord {
        StepRecord {
            generation: 0,
            step,
            time: step as f64 * 0.01,
            time_step: 0.01,
            max_penetration: pen,
            lock: 0,
            slide: 0,
            open: 0,
            alm_iterations: 0,
            open_close_iterations: 0,
            cuts: 0,
            kinetic_energy: 0.0,
            penalty_min: f64::NAN,
            penalty_mean: f64::NAN,
            penalty_max: f64::NAN,
        }
    }

    /// The rockfall after `steps` steps, as the panel sees it.
    fn rockfall_state(steps: usize) -> (UiState, Frame) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join("rock_column_rockfall.toml");
        let scene = crate::scene::load(&path).unwrap();
        let mut solver = crate::solver::Solver::new(scene.model.clone(), scene.params.clone());
        for _ in 0..steps {
            solver.step().unwrap();
        }
        let snap = solver.snapshot();
        let state = UiState::new(&scene, &snap, "test".into());
        let frame = Frame {
            seq: 1,
            applied: 0,
            generation: 0,
            snapshot: Arc::new(snap),
            params: solver.params.clone(),
            state: RunState::Paused,
            speed: Speed::Max,
            error: None,
            steps_per_second: 0.0,
            seconds_per_step: 0.0,
            running_seconds: 0.0,
            totals: solver.totals.clone(),
            max_step_penetration: solver.max_step_penetration(),
        };
        (state, frame)
    }

    #[test]
    fn display_options_shape_the_scene() {
        let (mut st, frame) = rockfall_state(3);
        assert!(
            !frame.snapshot.contacts.is_empty(),
            "the column rests on contacts"
        );
        st.update(Some(Arc::new(frame)), &mut Vec::new());
        st.build_scene();
        let full = st.scene.clone().unwrap();
        assert!(!full.solids.is_empty() && !full.arrows.is_empty());
        let scale = full.force_scale.expect("force arrows have a scale");

        st.display.wireframe = true;
        st.build_scene();
        let wire = st.scene.clone().unwrap();
        assert!(wire.solids.is_empty(), "wireframe draws no faces");
        assert!(wire.lines.len() >= full.lines.len(), "but all the edges");

        st.display.wireframe = false;
        st.display.forces = false;
        st.build_scene();
        assert!(st.scene.as_ref().unwrap().arrows.is_empty(), "no arrows");
        st.display.normals = true;
        st.build_scene();
        assert!(
            !st.scene.as_ref().unwrap().arrows.is_empty(),
            "normal glyphs"
        );

        // The automatic arrow scale is fixed by the first frame with contacts.
        st.display.forces = true;
        st.build_scene();
        assert_eq!(st.scene.as_ref().unwrap().force_scale, Some(scale));
        st.display.auto_force_scale = false;
        st.display.force_scale = 1234.0;
        st.build_scene();
        assert_eq!(st.scene.as_ref().unwrap().force_scale, Some(1234.0));
    }

    #[test]
    fn stale_frames_do_not_overwrite_an_edit_in_flight() {
        let (mut st, frame) = rockfall_state(0);
        st.update(Some(Arc::new(frame.clone())), &mut Vec::new());
        st.edit.contact.alpha = 5.0;
        let sent = st.param_change().expect("an edit to send");
        assert_eq!(sent.contact.alpha, 5.0);
        assert!(st.param_change().is_none(), "sent once");
        st.params_sent(7);
        // A frame published before the sim thread took command 7 still has α = 10.
        let stale = Frame {
            applied: 6,
            seq: 2,
            ..frame.clone()
        };
        st.update(Some(Arc::new(stale)), &mut Vec::new());
        assert_eq!(st.edit.contact.alpha, 5.0, "the widget keeps the edit");
        let mut fresh = Frame {
            applied: 7,
            seq: 3,
            ..frame
        };
        fresh.params.contact.alpha = 5.0;
        fresh.params.duration = 4.0; // changed by the sim thread (play past the end)
        st.update(Some(Arc::new(fresh)), &mut Vec::new());
        assert_eq!(st.edit.duration, 4.0, "the widgets follow the solver again");
        assert!(st.param_change().is_none(), "nothing to send back");
    }

    #[test]
    fn records_of_an_old_run_are_dropped_on_reset() {
        let (mut st, frame) = rockfall_state(0);
        let mut recs: Vec<StepRecord> = (1..=3).map(|k| rec(k, 0.0)).collect();
        st.update(Some(Arc::new(frame.clone())), &mut recs);
        assert_eq!(st.history.records.len(), 3);
        assert!(recs.is_empty(), "drained");
        let reset = Frame {
            generation: 1,
            ..frame
        };
        let mut old = vec![rec(4, 0.0)]; // generation 0, arrived late
        st.update(Some(Arc::new(reset)), &mut old);
        assert!(st.history.records.is_empty());
    }

    #[test]
    fn downsampling_keeps_spikes() {
        let mut r: Vec<StepRecord> = (0..10_000).map(|k| rec(k, 1.0)).collect();
        r[5_001].max_penetration = 50.0;
        let s = series(&r, |r| r.max_penetration, f64::max);
        assert!(s.len() <= PLOT_POINTS);
        assert!(s.iter().any(|p| p[1] == 50.0), "the spike survives");
        // Non-finite values (no contacts) are skipped, not plotted as zero.
        let s = series(&r, |r| r.penalty_min, f64::min);
        assert!(s.is_empty());
    }

    #[test]
    fn numbers_read_well() {
        assert_eq!(num(2.0e8), "2e8");
        assert_eq!(num(0.25), "0.25");
        assert_eq!(num(35.0), "35");
        assert_eq!(num(1.234e-5), "1.23e-5");
        assert_eq!(length(0.0004), "400 µm");
        assert_eq!(length(0.05), "50 mm");
        assert_eq!(length(2.5), "2.5 m");
        assert_eq!(seconds(0.01), "10 ms");
        assert_eq!(seconds(2.0), "2 s");
    }
}
