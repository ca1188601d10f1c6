//! The interactive viewer: `dda3d view SCENE.toml` (or just `dda3d SCENE.toml`).
//!
//! - [`sim`]: the simulation thread and its command/frame protocol;
//! - [`view`]: camera controls and picking (pure logic);
//! - [`state`]: what the viewer remembers between frames;
//! - [`compare_ui`]: what it remembers of run B in a comparison (`view --compare`);
//! - [`panels`]: the egui panels (toolbar, parameters, display, selection, plots, 3-D view), one
//!   file each;
//! - `app/`: the winit application and the frame loop, with its parts: the window and its
//!   surface, the 3-D view's texture, screenshots and recordings, and frame pacing;
//! - [`painter`]: draws egui's meshes with wgpu (fast on software rasterizers).
//!
//! The viewer knows nothing of the command line: it takes [`ViewerOptions`] and reports
//! [`ViewerError`]; `crate::cli` reads the flags and maps the error to an exit status.

mod app;
pub mod compare_ui;
pub mod painter;
pub mod panels;
pub mod sim;
pub mod state;
pub mod view;

use std::path::PathBuf;

use crate::render::RenderError;
use crate::scene::Scene;
use sim::Speed;

pub use app::run_viewer;

/// What the viewer is to show, and how.
pub struct ViewerOptions {
    pub scene: Scene,
    /// Initial window size in pixels.
    pub size: (u32, u32),
    pub speed: Speed,
    /// Start running (false: paused at t = 0).
    pub play: bool,
    /// Write the whole window to this PNG on the last frame (with `exit_after_frames`).
    pub screenshot: Option<PathBuf>,
    /// Draw this many frames, print the frame-time report and close.
    pub exit_after_frames: Option<u64>,
    /// MSAA samples of the 3-D view (None: 4 on a GPU, 1 on a software rasterizer).
    pub msaa: Option<u32>,
    /// Directory for the screenshot button and recordings.
    pub out_dir: PathBuf,
    /// `--compare`/`--compare-set`: run B's settings (the scene's are run A's); None: one run.
    pub compare: Option<crate::params::SolverParams>,
    /// Open a comparison in one pane, B as a ghost over A.
    pub ghost: bool,
    /// The block selected at start (`--select`).
    pub selected: Option<usize>,
    /// `--resume`: the checkpoint (encoded) the run starts from and Reset goes back to, of
    /// `scene`'s blocks; `None`: the scene at t = 0.
    pub origin: Option<sim::Origin>,
}

/// Why the viewer could not run or stopped, as one line.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    /// No GPU adapter at all: a driver is missing (the message says which to install).
    #[error("{}", RenderError::NoAdapter)]
    NoAdapter,
    /// The window, the GPU, the simulation thread or the `--screenshot` file failed.
    #[error("{0}")]
    Failed(String),
}
