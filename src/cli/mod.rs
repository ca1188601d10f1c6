//! Command-line interface: `dda3d run`, and the shared option handling.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::output::{RunWriter, Summary, slug};
use crate::params::{Method, Mode};
use crate::scene::{self, Scene, SceneError};
use crate::solver::{Solver, SolverError};

#[derive(Parser, Debug)]
#[command(
    name = "dda3d",
    version,
    about = "3-D Discontinuous Deformation Analysis of jointed rock (DDA-3a)"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Simulate a scene without any window or GPU; write blocks.csv, contacts.csv, summary.json.
    Run(RunArgs),
    /// Simulate headless and write PNG frames (and optionally an animated GIF) for reports.
    Render(RenderArgs),
    /// Write a generated scene file (for measuring cost as the model grows).
    Generate(GenerateArgs),
    /// Time the rockfall scene with both methods, and the scaling on generated walls.
    Bench(BenchArgs),
    /// Open the interactive viewer (`dda3d SCENE.toml` is short for `dda3d view SCENE.toml`).
    View(crate::ui::ViewArgs),
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Output directory for frame_00000.png …, frames.csv (default: out/<scene name>/frames).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub overrides: SolverOverrides,
    /// Frames per second of simulated time.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Camera azimuth and elevation in degrees, and optionally distance in m: `az,el[,dist]`.
    #[arg(long, allow_hyphen_values = true)]
    pub camera: Option<String>,
    /// Point the camera looks at, m: `x,y,z` (default: the centre of the framed box).
    #[arg(long, allow_hyphen_values = true, value_delimiter = ',', num_args = 1)]
    pub target: Option<Vec<f64>>,
    /// Block colours: block (one colour per block), velocity, displacement.
    #[arg(long, default_value = "block")]
    pub color: String,
    /// Force arrow scale in N per metre of arrow (default: automatic, fixed after frame 0).
    #[arg(long)]
    pub force_scale: Option<f64>,
    /// Draw contact normals as well as the force arrows.
    #[arg(long)]
    pub normals: bool,
    /// Transparent background.
    #[arg(long)]
    pub transparent: bool,
    /// Re-frame the camera on every frame instead of keeping the first frame's view.
    #[arg(long)]
    pub follow: bool,
    /// Also write an animated GIF, animation.gif.
    #[arg(long)]
    pub gif: bool,
    /// Antialiasing samples (1 or 4).
    #[arg(long, default_value_t = 4)]
    pub msaa: u32,
    #[arg(long, short)]
    pub quiet: bool,
}

/// Kinds of generated scenes.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum GeneratedKind {
    /// A jointed wall of columns of stacked blocks, struck by a rock.
    Column,
}

#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// What to generate.
    #[arg(value_enum)]
    pub kind: GeneratedKind,
    /// Number of jointed blocks (not counting the ground slab and the rock).
    #[arg(long, default_value_t = 5)]
    pub blocks: usize,
    /// Blocks per column.
    #[arg(long, default_value_t = 5)]
    pub layers: usize,
    /// Leave out the rock: a standing wall (to measure the cost of the machinery alone).
    #[arg(long)]
    pub no_rock: bool,
    /// Output scene file (default: out/column_<N>.toml).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// The rockfall scene to time.
    #[arg(long, default_value = "scenes/rock_column_rockfall.toml")]
    pub scene: PathBuf,
    /// Generated wall sizes for the scaling study with the rockfall (comma separated).
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "10,100")]
    pub sizes: Vec<usize>,
    /// Generated wall sizes for the scaling study of a standing wall (no rock).
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "10,100,1000")]
    pub standing_sizes: Vec<usize>,
    /// Runs per measurement; the fastest is reported.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Simulated time of the scaling runs, s.
    #[arg(long, default_value_t = 2.0)]
    pub scaling_duration: f64,
}

/// Overrides of the scene's `[solver]` table, shared by the commands that simulate.
#[derive(Args, Debug, Clone, Default)]
pub struct SolverOverrides {
    /// Contact method: alm (DDA-3a) or penalty (DDA-3p).
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Time integration: dynamic or static.
    #[arg(long, value_enum)]
    pub mode: Option<Mode>,
    /// Simulated time, s.
    #[arg(long)]
    pub duration: Option<f64>,
}

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    #[command(flatten)]
    pub overrides: SolverOverrides,
    /// Output directory (default: out/<scene name as a slug>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// No progress bar and no final line.
    #[arg(long, short)]
    pub quiet: bool,
}

/// How a command failed, and with which exit status.
#[derive(Debug)]
pub enum CliError {
    /// Bad input: exit status 2.
    Input(String),
    /// The run failed (diverged, I/O): exit status 1.
    Run(String),
}

impl CliError {
    pub fn exit_code(&self) -> i32 {
        match self {
            CliError::Input(_) => 2,
            CliError::Run(_) => 1,
        }
    }
    pub fn message(&self) -> &str {
        match self {
            CliError::Input(m) | CliError::Run(m) => m,
        }
    }
}

impl From<SceneError> for CliError {
    fn from(e: SceneError) -> Self {
        CliError::Input(e.to_string())
    }
}

/// Loads a scene and applies the command-line overrides.
pub fn load_scene(path: &Path, o: &SolverOverrides) -> Result<Scene, CliError> {
    let mut s = scene::load(path)?;
    if let Some(m) = o.method {
        s.params.method = m;
    }
    if let Some(m) = o.mode {
        s.params.mode = m;
    }
    if let Some(d) = o.duration {
        if !(d.is_finite() && d > 0.0) {
            return Err(CliError::Input(format!(
                "--duration must be a positive number of seconds, got {d}"
            )));
        }
        s.params.duration = d;
    }
    Ok(s)
}

/// A progress bar that appears only once a run has taken more than a second.
pub struct Progress {
    bar: ProgressBar,
    start: Instant,
    shown: bool,
    quiet: bool,
}

impl Progress {
    pub fn new(total_seconds: f64, quiet: bool) -> Self {
        let bar = ProgressBar::with_draw_target(
            Some((total_seconds * 1000.0).round() as u64),
            ProgressDrawTarget::hidden(),
        );
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:40} t = {msg} s (eta {eta})",
            )
            .expect("valid template"),
        );
        Progress {
            bar,
            start: Instant::now(),
            shown: false,
            quiet,
        }
    }

    pub fn update(&mut self, time: f64) {
        if self.quiet {
            return;
        }
        if !self.shown && self.start.elapsed() > Duration::from_secs(1) {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown = true;
        }
        self.bar.set_position((time * 1000.0).round() as u64);
        self.bar.set_message(format!("{time:.3}"));
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// `dda3d run`.
pub fn run(args: &RunArgs) -> Result<(), CliError> {
    let scene = load_scene(&args.scene, &args.overrides)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(slug(&scene.name)));
    let io = |e: std::io::Error| CliError::Run(format!("{}: {e}", out.display()));
    let mut writer = RunWriter::create(&out).map_err(io)?;
    let name = scene.name.clone();
    let (method, mode) = (scene.params.method, scene.params.mode);
    let mut solver = Solver::new(scene.model, scene.params);
    let start = Instant::now();
    let mut progress = Progress::new(solver.params.duration, args.quiet);
    writer.write(&solver.snapshot()).map_err(io)?;
    let mut failure: Option<SolverError> = None;
    while !solver.finished() {
        if let Err(e) = solver.step() {
            failure = Some(e);
            break;
        }
        writer.write(&solver.snapshot()).map_err(io)?;
        progress.update(solver.time);
    }
    progress.finish();
    writer.flush().map_err(io)?;
    let wall = start.elapsed().as_secs_f64();
    let mut summary = Summary::new(
        &name,
        method.as_str(),
        mode.as_str(),
        solver.time,
        wall,
        &solver.totals,
    );
    if let Some(e) = &failure {
        summary.status = "diverged".into();
        summary.error = Some(e.to_string());
    }
    summary.write(&out).map_err(io)?;
    if let Some(e) = failure {
        return Err(CliError::Run(format!(
            "{}: {e}; results up to t = {:.6} s are in {}",
            args.scene.display(),
            solver.time,
            out.display()
        )));
    }
    if !args.quiet {
        eprintln!(
            "{}: {} steps to t = {:.3} s in {:.2} s wall; max penetration {:.3e} m; results in {}",
            name,
            solver.totals.steps,
            solver.time,
            wall,
            solver.totals.max_penetration,
            out.display()
        );
    }
    Ok(())
}

/// `dda3d generate`.
pub fn generate(args: &GenerateArgs) -> Result<(), CliError> {
    if args.blocks == 0 || args.blocks > 1_000_000 {
        return Err(CliError::Input(format!(
            "--blocks must lie in 1..=1000000, got {}",
            args.blocks
        )));
    }
    if args.layers == 0 {
        return Err(CliError::Input("--layers must be at least 1".into()));
    }
    let text = match args.kind {
        GeneratedKind::Column => {
            crate::generate::column_wall(args.blocks, args.layers, !args.no_rock)
        }
    };
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("column_{}.toml", args.blocks)));
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::Run(format!("{}: {e}", dir.display())))?;
    }
    std::fs::write(&out, text).map_err(|e| CliError::Run(format!("{}: {e}", out.display())))?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

/// `dda3d bench`.
pub fn bench(args: &BenchArgs) -> Result<(), CliError> {
    if !args.scene.exists() {
        return Err(CliError::Input(format!(
            "{}: no such scene file",
            args.scene.display()
        )));
    }
    if !(args.scaling_duration.is_finite() && args.scaling_duration > 0.0) {
        return Err(CliError::Input(
            "--scaling-duration must be positive".into(),
        ));
    }
    crate::bench::run(
        &args.scene,
        &args.sizes,
        &args.standing_sizes,
        args.repeat,
        args.scaling_duration,
    )
    .map_err(CliError::Run)
}

/// `dda3d render`: the solver runs on this thread and hands a snapshot to the capture pipeline
/// (its own render thread and PNG encoder threads) at every frame time, so rendering and encoding
/// overlap with the simulation. Frames come from the solver's own steps, which are shortened to
/// land exactly on the frame times, not from re-simulation.
pub fn render(args: &RenderArgs) -> Result<(), CliError> {
    use crate::render::{
        ArrowMode, CameraOverride, CaptureOptions, Coloring, FrameCapture, Framing, RenderError,
    };
    let scene = load_scene(&args.scene, &args.overrides)?;
    if !(args.fps.is_finite() && args.fps > 0.0) {
        return Err(CliError::Input(format!(
            "--fps must be positive, got {}",
            args.fps
        )));
    }
    if args.width == 0 || args.height == 0 || args.width > 16384 || args.height > 16384 {
        return Err(CliError::Input(format!(
            "--width/--height must lie in 1..=16384, got {}x{}",
            args.width, args.height
        )));
    }
    if args.msaa != 1 && args.msaa != 4 {
        return Err(CliError::Input(format!(
            "--msaa must be 1 or 4, got {}",
            args.msaa
        )));
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(slug(&scene.name)).join("frames"));
    let mut opts = CaptureOptions::new(&out);
    opts.width = args.width;
    opts.height = args.height;
    opts.fps = args.fps;
    opts.gif = args.gif;
    opts.max_msaa_samples = args.msaa;
    if let Some(c) = &args.camera {
        opts.camera =
            CameraOverride::parse(c).map_err(|e| CliError::Input(format!("--camera: {e}")))?;
    }
    if let Some(t) = &args.target {
        if t.len() != 3 || t.iter().any(|v| !v.is_finite()) {
            return Err(CliError::Input(
                "--target needs three finite numbers x,y,z".into(),
            ));
        }
        opts.camera.target = Some([t[0], t[1], t[2]]);
    }
    opts.style.coloring =
        Coloring::parse(&args.color).map_err(|e| CliError::Input(format!("--color: {e}")))?;
    if let Some(f) = args.force_scale {
        if !(f.is_finite() && f > 0.0) {
            return Err(CliError::Input(format!(
                "--force-scale must be positive, got {f}"
            )));
        }
        opts.style.force_scale = Some(f);
    }
    if args.normals {
        opts.style.arrows = ArrowMode::Both;
    }
    opts.style.transparent = args.transparent;
    if args.follow {
        opts.framing = Framing::EachFrame;
    }
    let name = scene.name.clone();
    let mut solver = Solver::new(scene.model, scene.params);
    let capture = FrameCapture::start(opts).map_err(|e| match e {
        RenderError::NoAdapter | RenderError::InvalidOptions(_) => CliError::Input(e.to_string()),
        other => CliError::Run(other.to_string()),
    })?;
    let render_err = |e: RenderError| CliError::Run(format!("{}: {e}", out.display()));
    let start = Instant::now();
    let mut sim_seconds = 0.0;
    let frame_dt = 1.0 / args.fps;
    let total_frames = (solver.params.duration * args.fps + 1e-9).floor() as u64 + 1;
    let mut progress = Progress::new(solver.params.duration, args.quiet);
    capture.submit(solver.snapshot()).map_err(render_err)?;
    let mut failure = None;
    'frames: for k in 1..total_frames {
        let t = k as f64 * frame_dt;
        while solver.time < t - 1e-9 * frame_dt {
            let ts = Instant::now();
            let r = solver.step_until(t);
            sim_seconds += ts.elapsed().as_secs_f64();
            if let Err(e) = r {
                failure = Some(e);
                break 'frames;
            }
        }
        capture.submit(solver.snapshot()).map_err(render_err)?;
        progress.update(solver.time);
    }
    progress.finish();
    let report = capture.finish().map_err(render_err)?;
    let wall = start.elapsed().as_secs_f64();
    let summary = serde_json::json!({
        "scene": name,
        "frames": report.frames,
        "fps_of_simulated_time": args.fps,
        "width": args.width,
        "height": args.height,
        "adapter": report.adapter,
        "msaa_samples": report.msaa_samples,
        "wall_seconds": wall,
        "frames_per_wall_second": report.frames as f64 / wall,
        "simulation_seconds": sim_seconds,
        "render_seconds": report.render_seconds,
        "png_encode_seconds": report.encode_seconds,
        "gif_seconds": report.gif_seconds,
        "setup_seconds": report.setup_seconds,
        "status": if failure.is_some() { "diverged" } else { "completed" },
    });
    std::fs::write(
        out.join("render_summary.json"),
        serde_json::to_string_pretty(&summary).unwrap_or_default(),
    )
    .map_err(|e| CliError::Run(format!("{}: {e}", out.display())))?;
    if let Some(e) = failure {
        return Err(CliError::Run(format!(
            "{}: {e}; {} frames up to t = {:.6} s are in {}",
            args.scene.display(),
            report.frames,
            solver.time,
            out.display()
        )));
    }
    if !args.quiet {
        eprintln!(
            "{name}: {} frames in {:.2} s ({:.1} frames/s; simulation {:.2} s, render+readback {:.1} ms/frame, PNG {:.1} ms/frame on {}); frames in {}",
            report.frames,
            wall,
            report.frames as f64 / wall,
            sim_seconds,
            report.render_ms_per_frame(),
            report.encode_ms_per_frame(),
            report.adapter,
            out.display()
        );
    }
    Ok(())
}
