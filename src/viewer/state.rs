//! What the viewer remembers between frames: the scene file's facts, the parameter edit in
//! flight, display options, plot history, frame timings, messages, and the 3-D scene built for
//! the frame. No widgets here: [`super::panels`] draws them from this state.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use egui::Rect;
use glam::DVec3;

use super::sim::{Command, Frame, RunState, Speed, StepRecord};
use super::view::ViewControls;
use crate::params::SolverParams;
use crate::render::scene::DEFAULT_ARROW_LIMIT;
use crate::render::{ArrowMode, Coloring, RenderScene, SceneFrame, SceneStyle};
use crate::scene::Scene as SceneFile;
use crate::snapshot::Snapshot;

/// What the panel asks the app to do after the frame's UI pass.
#[derive(Debug)]
pub enum Action {
    Sim(Command),
    /// Write the 3-D view at window size to a PNG.
    Screenshot,
    /// Start or stop writing PNG frames.
    ToggleRecord,
    /// Start a comparison with run B's settings (both runs from t = 0, paused), or end it
    /// (`None`: run A alone from t = 0).
    Compare(Option<Box<SolverParams>>),
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
    /// Arrows for the strongest `arrow_limit` contacts only (else for all of them).
    pub strongest_only: bool,
    pub arrow_limit: usize,
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
            strongest_only: true,
            arrow_limit: DEFAULT_ARROW_LIMIT,
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

/// Facts from the scene file, fixed for the session.
pub struct SceneFileInfo {
    pub name: String,
    /// The scene file's parameters ("scene values" button).
    pub params: SolverParams,
    /// E used to express penalties (the smallest Young's modulus of the scene: contacts use
    /// min(E_i, E_j)), Pa.
    pub young: f64,
    pub blocks: Vec<BlockInfo>,
}

impl SceneFileInfo {
    fn of(scene: &SceneFile) -> SceneFileInfo {
        let young = scene
            .model
            .blocks
            .iter()
            .map(|b| b.material.young_modulus)
            .filter(|e| e.is_finite() && *e > 0.0)
            .fold(f64::INFINITY, f64::min);
        SceneFileInfo {
            name: scene.name.clone(),
            params: scene.params.clone(),
            young: if young.is_finite() { young } else { 1.0 },
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
        }
    }
}

/// The parameter widgets' values, and what the solver was last sent.
pub struct ParamEdit {
    /// What the parameter widgets show and edit.
    pub edit: SolverParams,
    /// Id of the last SetParams sent; frames before it are stale for the widgets.
    sent_id: u64,
    last_sent: SolverParams,
}

/// Scales fixed by the run's first frames, so that arrow lengths and colours compare between
/// frames. Cleared on reset.
#[derive(Default)]
pub struct RunScales {
    /// Newtons per metre of force arrow, chosen from the first frame with contacts.
    pub(super) force: Option<f64>,
    /// The top of the colour range of the speed or displacement field (grow-only).
    pub(super) field_max: f64,
}

/// Everything the panel remembers between frames.
pub struct UiState {
    pub scene_file: SceneFileInfo,
    pub frame: Option<Arc<Frame>>,
    pub params: ParamEdit,
    pub speed: Speed,
    pub display: Display,
    pub history: History,
    pub selected: Option<usize>,
    pub view: ViewControls,
    /// Grid and render origin: the initial blocks (fixed, so nothing jumps while blocks move).
    pub scene_frame: SceneFrame,
    /// The scene drawn this frame (built in the UI pass, drawn by the app).
    pub scene: Option<RenderScene>,
    /// Bumped whenever `scene` is rebuilt, so the app can skip redrawing an unchanged view.
    pub scene_version: u64,
    /// What `scene` was built from: (frame seq, style, wireframe).
    scene_key: Option<(u64, SceneStyle, bool)>,
    pub(super) scales: RunScales,
    /// The 3-D view's rectangle in points.
    pub view_rect: Rect,
    pub message: Option<Message>,
    pub recording: Option<RecordingInfo>,
    pub perf: Perf,
    pub show_plots: bool,
    /// "name (backend, type), N× MSAA".
    pub adapter: String,
    /// Where Save state writes and Load state looks (the viewer's `--out`).
    pub out_dir: std::path::PathBuf,
    /// The command id of the last sim notice shown ([`Frame::notice`]).
    last_notice: u64,
    /// Run B of `view --compare` (None: one run).
    pub compare: Option<Box<super::compare_ui::CompareUi>>,
    /// The time of the checkpoint the run started from (`view --resume`), where Reset goes
    /// back to: its equilibrium stage, if any, is behind it.
    pub resumed_from: Option<f64>,
}

impl UiState {
    pub fn new(scene: &SceneFile, first: &Snapshot, adapter: String) -> UiState {
        let frame = SceneFrame::of_snapshot(first);
        UiState {
            scene_file: SceneFileInfo::of(scene),
            frame: None,
            params: ParamEdit {
                edit: scene.params.clone(),
                sent_id: 0,
                last_sent: scene.params.clone(),
            },
            speed: Speed::default(),
            display: Display::default(),
            history: History::default(),
            selected: None,
            view: ViewControls::new(frame.lo, frame.hi, 16.0 / 9.0),
            scene_frame: frame,
            scene: None,
            scene_version: 0,
            scene_key: None,
            scales: RunScales::default(),
            view_rect: Rect::NOTHING,
            message: None,
            recording: None,
            perf: Perf::default(),
            show_plots: true,
            adapter,
            out_dir: std::path::PathBuf::from("out"),
            last_notice: 0,
            compare: None,
            resumed_from: None,
        }
    }

    /// Takes in the newest frame and the step records since the last call.
    pub fn update(&mut self, frame: Option<Arc<Frame>>, records: &mut Vec<StepRecord>) {
        if let Some(f) = frame {
            if f.generation != self.history.generation {
                self.history.generation = f.generation;
                self.history.records.clear();
                self.scales = RunScales::default();
            }
            // Only a frame that has seen the last edit may overwrite the widgets; older ones
            // would make a slider jump back while it is being dragged.
            if f.applied >= self.params.sent_id && self.edit_follows_a() {
                self.params.edit = f.params.clone();
                self.params.last_sent = f.params.clone();
                self.speed = f.speed;
            }
            if let Some((id, text)) = &f.notice
                && *id > self.last_notice
            {
                self.last_notice = *id;
                self.info(text.clone());
            }
            // A scene with rock masses opens coloured by rock mass (the user may change it).
            if self.frame.is_none()
                && !f.snapshot.rock_masses.is_empty()
                && self.display.coloring == Coloring::PerBlock
            {
                self.display.coloring = Coloring::RockMass;
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
        self.param_edit().map(|(_, new)| new)
    }

    /// As [`UiState::param_change`], with the settings last sent before it: (old, new).
    pub fn param_edit(&mut self) -> Option<(SolverParams, SolverParams)> {
        let p = &mut self.params;
        if p.edit == p.last_sent {
            return None;
        }
        let old = std::mem::replace(&mut p.last_sent, p.edit.clone());
        Some((old, p.edit.clone()))
    }

    /// The widgets show (and count as sent) these settings: a run's newest.
    pub(super) fn follow_edit(&mut self, params: &SolverParams) {
        self.params.edit = params.clone();
        self.params.last_sent = params.clone();
    }

    /// Call after the app sent a SetParams or SetSpeed, so that frames published before the
    /// sim thread took it do not reset the widgets.
    pub fn params_sent(&mut self, id: u64) {
        self.params.sent_id = id;
    }

    /// Whether the simulation is running (Space pauses it).
    pub fn running(&self) -> bool {
        self.frame
            .as_ref()
            .is_some_and(|f| f.state == RunState::Running)
    }

    /// The style of the 3-D view (the same look the `render` command gives).
    pub fn style(&self) -> SceneStyle {
        let d = &self.display;
        SceneStyle {
            coloring: d.coloring,
            field_range: (self.scales.field_max > 0.0).then_some((0.0, self.scales.field_max)),
            arrows: match (d.forces, d.normals) {
                (true, true) => ArrowMode::Both,
                (true, false) => ArrowMode::Forces,
                (false, true) => ArrowMode::Normals,
                (false, false) => ArrowMode::None,
            },
            force_scale: if d.auto_force_scale {
                self.scales.force
            } else {
                Some(d.force_scale)
            },
            arrow_limit: d.strongest_only.then_some(d.arrow_limit),
            transparent: false,
            grid: d.grid,
            edges: d.edges || d.wireframe,
            overlay: d.overlay,
        }
    }

    /// Builds this frame's scene from the newest snapshot.
    pub(super) fn build_scene(&mut self) {
        let Some(frame) = self.frame.clone() else {
            self.scene = None;
            return;
        };
        let snap = &frame.snapshot;
        let key = (frame.seq, self.style(), self.display.wireframe);
        if self.scene.is_some() && self.scene_key.as_ref() == Some(&key) {
            return; // same snapshot, same look: a large model is not rebuilt every frame
        }
        if !matches!(
            self.display.coloring,
            Coloring::PerBlock | Coloring::RockMass
        ) {
            // Grow-only colour range, so a colour means the same speed all run long.
            let m = snap
                .blocks
                .iter()
                .filter(|b| !b.fixed)
                .map(|b| match self.display.coloring {
                    Coloring::Velocity => DVec3::from_array(b.velocity).length(),
                    Coloring::Displacement => DVec3::from_array(b.displacement).length(),
                    Coloring::PerBlock | Coloring::RockMass => 0.0,
                })
                .filter(|v| v.is_finite())
                .fold(0.0, f64::max);
            self.scales.field_max = self.scales.field_max.max(m);
        }
        match RenderScene::build(snap, &self.style(), &self.scene_frame) {
            Ok(mut scene) => {
                if self.display.auto_force_scale && self.scales.force.is_none() {
                    self.scales.force = scene.force_scale;
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

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A step record with penetration `pen` (the plots' tests use it too).
    pub(in crate::viewer) fn rec(step: u64, pen: f64) -> StepRecord {
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
            stage: None,
        }
    }

    /// The rockfall after `steps` steps, as the panel sees it (the comparison's tests too).
    pub(crate) fn rockfall_state(steps: usize) -> (UiState, Frame) {
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
            notice: None,
            steps_per_second: 0.0,
            seconds_per_step: 0.0,
            running_seconds: 0.0,
            steps_run: 0,
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
        st.params.edit.contact.alpha = 5.0;
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
        assert_eq!(
            st.params.edit.contact.alpha, 5.0,
            "the widget keeps the edit"
        );
        let mut fresh = Frame {
            applied: 7,
            seq: 3,
            ..frame
        };
        fresh.params.contact.alpha = 5.0;
        fresh.params.duration = 4.0; // changed by the sim thread (play past the end)
        st.update(Some(Arc::new(fresh)), &mut Vec::new());
        assert_eq!(
            st.params.edit.duration, 4.0,
            "the widgets follow the solver again"
        );
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
}
