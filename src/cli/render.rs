//! `dda3d render`: simulates headless and writes PNG frames (and optionally an animated GIF)
//! through the capture pipeline of [`crate::render`], plus render_summary.json.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;

use super::exit::{self, Failure, Signal};
use super::{CliError, Progress, SolverOverrides, load_scene};
use crate::compare::CompareSpec;
use crate::output::{slug, write_atomically};
use crate::render::{
    ArrowMode, CameraOverride, CaptureOptions, CaptureReport, Coloring, FrameCapture, Framing,
    RenderError,
};
use crate::solver::{Solver, SolverError};
use crate::text::short;

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML). Left out with --resume, whose checkpoint holds the scene.
    #[arg(required_unless_present = "resume")]
    pub scene: Option<PathBuf>,
    /// Output directory for frame_00000.png …, frames.csv (default: out/<scene name>/frames,
    /// and out/<scene name>-resumed/frames with --resume).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub overrides: SolverOverrides,
    /// Render from the state saved in CHECKPOINT (a checkpoint_<t>.ckpt file of `run
    /// --checkpoint-every` or the viewer's Save state), in place of SCENE: a large rock mass's
    /// equilibrium stage is then computed once, not for every render. The first frame is the
    /// checkpoint's state at its time t, the next ones fall on the multiples of 1/fps after it;
    /// the solver settings are the checkpoint's, and --duration is the new end time (from
    /// t = 0, as in the scene). With --compare, both runs start from the checkpoint.
    #[arg(
        long,
        value_name = "CHECKPOINT",
        conflicts_with_all = ["scene", "method", "mode", "spectral_radius", "max_time_step", "initial_equilibrium", "sleep_velocity"]
    )]
    pub resume: Option<PathBuf>,
    /// Frames per second of simulated time.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
    pub fps: f64,
    #[arg(long, default_value_t = 1280, allow_negative_numbers = true)]
    pub width: u32,
    #[arg(long, default_value_t = 720, allow_negative_numbers = true)]
    pub height: u32,
    /// Camera azimuth and elevation in degrees, and optionally distance in m: `az,el[,dist]`.
    #[arg(long, allow_hyphen_values = true)]
    pub camera: Option<String>,
    /// Point the camera looks at, m: `x,y,z` (default: the centre of the framed box).
    #[arg(long, allow_hyphen_values = true, value_delimiter = ',', num_args = 1)]
    pub target: Option<Vec<f64>>,
    /// Block colours: block (one colour per block), velocity, displacement, rock-mass (a colour
    /// per rock mass, shaded per region and block).
    #[arg(long, default_value = "block")]
    pub color: String,
    /// Force arrow scale in N per metre of arrow (default: automatic, fixed after frame 0).
    #[arg(long, allow_negative_numbers = true)]
    pub force_scale: Option<f64>,
    /// Draw contact normals as well as the force arrows.
    #[arg(long, conflicts_with = "no_arrows")]
    pub normals: bool,
    /// Draw no contact arrows: the blocks alone (a rock mass of thousands of contacts).
    #[arg(long)]
    pub no_arrows: bool,
    /// Arrows at the N contacts with the largest normal force only, or `all` (default: the
    /// strongest 500; the legend says when some are left out).
    #[arg(long, value_name = "N|all", allow_negative_numbers = true)]
    pub arrows: Option<String>,
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
    #[arg(long, default_value_t = 4, allow_negative_numbers = true)]
    pub msaa: u32,
    /// No progress bar and no final line.
    #[arg(long, short)]
    pub quiet: bool,
    /// Compare: also run the scene with the contact method METHOD (alm or penalty) as run B,
    /// the scene's settings being run A; each frame shows A left and B right at one time.
    #[arg(long, value_name = "METHOD")]
    pub compare: Option<String>,
    /// Compare: run B's settings as changes to A's, any scene-file key of [solver],
    /// [solver.contact] and [joint] (e.g. initial_penalty=2e9,eps1=0.001); with or without
    /// --compare.
    #[arg(long, value_name = "KEY=VALUE,...")]
    pub compare_set: Option<String>,
}

impl RenderArgs {
    /// The file the render comes from, for messages: the scene, or the checkpoint resumed.
    pub(super) fn source(&self) -> &Path {
        let from = self.resume.as_deref().or(self.scene.as_deref());
        from.unwrap_or(Path::new("-"))
    }
}

/// What the simulation side of a render did.
pub(super) struct Simulated {
    /// Wall time spent in the solver (both solvers of a comparison), s.
    pub seconds: f64,
    /// The solver error that ended the run early, if any.
    pub failure: Option<SolverError>,
    /// The stop signal that ended the run early, if any.
    pub interrupted: Option<Signal>,
}

impl Simulated {
    pub(super) fn new() -> Self {
        Simulated {
            seconds: 0.0,
            failure: None,
            interrupted: None,
        }
    }

    /// Steps `solver` up to the frame time `t` (to within round-off of the frame spacing
    /// `frame_dt`), counting its wall time; false when a stop signal (checked between steps: a
    /// frame cut short is not submitted) or a solver failure ends the run, with the reason kept.
    pub(super) fn step_to(&mut self, solver: &mut Solver, t: f64, frame_dt: f64) -> bool {
        while solver.time < t - 1e-9 * frame_dt {
            self.interrupted = exit::interrupted();
            if self.interrupted.is_some() {
                return false;
            }
            let ts = Instant::now();
            let r = solver.step_until(t);
            self.seconds += ts.elapsed().as_secs_f64();
            if let Err(e) = r {
                self.failure = Some(e);
                return false;
            }
        }
        true
    }
}

/// A capture failure with its exit status: a file that cannot be written is an I/O error, a
/// missing GPU or bad options bad input, and the rest (the device, a worker) a failure of
/// neither.
pub(super) fn capture_failure(out: &Path, e: RenderError) -> Failure {
    match e {
        RenderError::NoAdapter | RenderError::InvalidOptions(_) => Failure::Input(e.to_string()),
        // The encoders' errors are the PNG writer's, that is the file's.
        RenderError::Io { .. } | RenderError::Encode(_) => Failure::Io(e.to_string()),
        other => Failure::Failed(format!("{}: {other}", out.display())),
    }
}

/// `dda3d render`: the solver runs on this thread and hands a snapshot to the capture pipeline
/// (its own render thread and PNG encoder threads) at every frame time, so rendering and encoding
/// overlap with the simulation. Frames come from the solver's own steps, which are shortened to
/// land exactly on the frame times, not from re-simulation. SIGINT or SIGTERM ends the
/// simulation after its step; the frames already handed over are still written.
pub(super) fn execute(args: &RenderArgs) -> Result<(), Failure> {
    let (mut solver, default_out) = match &args.resume {
        Some(path) => {
            let solver = super::resume::resume(path, &args.overrides)?;
            check_image_options(args)?;
            let out = super::resume::default_out(&solver);
            if let Some(spec) = compare_spec(args)? {
                check_frame_count(solver.params.duration - solver.time, args.fps)?;
                return super::render_compare::execute_from(args, solver, &spec, out);
            }
            (solver, out)
        }
        None => {
            let scene = load_scene(args.source(), &args.overrides)?;
            check_image_options(args)?;
            if let Some(spec) = compare_spec(args)? {
                check_frame_count(scene.params.duration, args.fps)?;
                return super::render_compare::execute(args, scene, &spec);
            }
            let out = PathBuf::from("out").join(slug(&scene.name));
            (Solver::new(scene.model, scene.params), out)
        }
    };
    check_frame_count(solver.params.duration - solver.time, args.fps)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| default_out.join("frames"));
    let opts = capture_options(args, &out)?;
    let name = solver.model.name.clone();
    exit::catch_stop_signals()?;
    let capture = FrameCapture::start(opts).map_err(|e| capture_failure(&out, e))?;
    let start = Instant::now();
    let simulated =
        simulate_frames(&mut solver, &capture, args).map_err(|e| capture_failure(&out, e))?;
    let report = capture.finish().map_err(|e| capture_failure(&out, e))?;
    let wall = start.elapsed().as_secs_f64();
    write_summary(&out, &name, args, &report, &simulated, wall)?;
    conclude(
        args,
        (&name, &out),
        &report,
        &simulated,
        wall,
        (solver.time, "frames", "simulation"),
    )
}

/// `--compare`/`--compare-set` read, if given.
fn compare_spec(args: &RenderArgs) -> Result<Option<CompareSpec>, Failure> {
    CompareSpec::parse(args.compare.as_deref(), args.compare_set.as_deref())
        .map_err(|e| Failure::Input(e.to_string()))
}

/// The end of a render (plain or compared): an early stop reported with the frames that were
/// written (up to `reached`, the simulated time), else the one-line summary unless `--quiet`.
/// `frames` names the frames ("frames", "side-by-side frames"), `solver` the simulation time's
/// label.
pub(super) fn conclude(
    args: &RenderArgs,
    (name, out): (&str, &Path),
    report: &CaptureReport,
    simulated: &Simulated,
    wall: f64,
    (reached, frames, solver): (f64, &str, &str),
) -> Result<(), Failure> {
    let reached = format!(
        "{} {frames} up to t = {} s are in {}",
        report.frames,
        short(reached),
        out.display()
    );
    if let Some(e) = &simulated.failure {
        return Err(Failure::Diverged(format!(
            "{}: {e}; {reached}",
            args.source().display()
        )));
    }
    if let Some(signal) = simulated.interrupted {
        return Err(Failure::Interrupted(
            signal,
            format!("{}; {reached}", signal.name()),
        ));
    }
    if !args.quiet {
        eprintln!(
            "{name}: {} {frames} in {} s ({} frames/s; {solver} {} s, render+readback {} ms/frame, PNG {} ms/frame on {}); frames in {}",
            report.frames,
            short(wall),
            short(report.frames as f64 / wall),
            short(simulated.seconds),
            short(report.render_ms_per_frame()),
            short(report.encode_ms_per_frame()),
            report.adapter,
            out.display()
        );
    }
    Ok(())
}

/// `dda3d render`.
pub fn render(args: &RenderArgs) -> Result<(), CliError> {
    execute(args).map_err(CliError::from)
}

/// The most frames a render writes (`--duration` × `--fps`): a day's worth at 1 s a frame
/// on a software rasterizer, 100 GB of 1280×720 PNG. `--fps 1e9` over 0.05 s asked for 5·10⁷
/// frames and wrote 200 MB a minute.
pub(super) const MAX_FRAMES: f64 = 100_000.0;

/// The frame count `duration` × `fps` (+1 for frame 0) is within [`MAX_FRAMES`].
pub(super) fn check_frame_count(duration: f64, fps: f64) -> Result<(), CliError> {
    let frames = duration * fps + 1.0;
    if frames > MAX_FRAMES {
        return Err(CliError::Input(format!(
            "{} s at --fps {} would be {} frames, more than {}: lower --fps or --duration",
            crate::text::short(duration),
            crate::text::short(fps),
            crate::text::short(frames.floor()),
            crate::text::short(MAX_FRAMES)
        )));
    }
    Ok(())
}

/// The checks of `--fps`, `--width`/`--height` and `--msaa` that need no GPU.
pub(super) fn check_image_options(args: &RenderArgs) -> Result<(), CliError> {
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
    Ok(())
}

/// The capture pipeline's options from the command line: size, camera, style and framing.
pub(super) fn capture_options(args: &RenderArgs, out: &Path) -> Result<CaptureOptions, CliError> {
    let mut opts = CaptureOptions::new(out);
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
    if let Some(a) = &args.arrows {
        opts.style.arrow_limit = match a.as_str() {
            "all" => None,
            n => Some(n.parse::<usize>().ok().filter(|&n| n > 0).ok_or_else(|| {
                CliError::Input(format!(
                    "--arrows takes a positive count or `all`, got {a:?}"
                ))
            })?),
        };
    }
    if args.normals {
        opts.style.arrows = ArrowMode::Both;
    }
    if args.no_arrows {
        opts.style.arrows = ArrowMode::None;
    }
    opts.style.transparent = args.transparent;
    if args.follow {
        opts.framing = Framing::EachFrame;
    }
    Ok(opts)
}

/// Steps the solver to each frame time in turn and submits a snapshot there, the first frame
/// being the solver's state as it is (t = 0, or a resumed checkpoint's time), the others at the
/// multiples of 1/fps after it. A solver failure ends the run early and is returned in
/// [`Simulated::failure`]; a capture failure is the error.
fn simulate_frames(
    solver: &mut Solver,
    capture: &FrameCapture,
    args: &RenderArgs,
) -> Result<Simulated, RenderError> {
    let mut simulated = Simulated::new();
    let frame_dt = 1.0 / args.fps;
    let (first, last) = frame_numbers(solver.time, solver.params.duration, args.fps);
    let mut progress = Progress::new(solver.params.duration, args.quiet);
    capture.submit(solver.snapshot())?;
    for k in first..=last {
        if !simulated.step_to(solver, k as f64 * frame_dt, frame_dt) {
            break;
        }
        capture.submit(solver.snapshot())?;
        progress.update(solver.time);
    }
    progress.finish();
    Ok(simulated)
}

/// The numbers k of the frames after the first, at k/fps, from a start at `t0` to the end at
/// `duration` (both within round-off of a frame time count as on it): 1..=⌊duration·fps⌋ from
/// t = 0.
pub(super) fn frame_numbers(t0: f64, duration: f64, fps: f64) -> (u64, u64) {
    let first = (t0 * fps + 1e-9).floor() as u64 + 1;
    let last = (duration * fps + 1e-9).floor() as u64;
    (first, last)
}

/// Writes render_summary.json (atomically): frame count, size, adapter, where the time went,
/// and how the run ended.
pub(super) fn write_summary(
    out: &Path,
    name: &str,
    args: &RenderArgs,
    report: &CaptureReport,
    simulated: &Simulated,
    wall: f64,
) -> Result<(), Failure> {
    let status = if simulated.failure.is_some() {
        "diverged"
    } else if simulated.interrupted.is_some() {
        "interrupted"
    } else {
        "completed"
    };
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
        "simulation_seconds": simulated.seconds,
        "render_seconds": report.render_seconds,
        "png_encode_seconds": report.encode_seconds,
        "gif_seconds": report.gif_seconds,
        "setup_seconds": report.setup_seconds,
        "status": status,
    });
    let path = out.join("render_summary.json");
    let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
    write_atomically(&path, text.as_bytes())
        .map_err(|e| Failure::Io(format!("{}: cannot write: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{Cli, CliCommand};
    use clap::Parser;

    fn options(extra: &[&str]) -> Result<CaptureOptions, String> {
        let mut argv = vec!["dda3d", "render", "scene.toml"];
        argv.extend_from_slice(extra);
        let cli = Cli::try_parse_from(argv).map_err(|e| e.to_string())?;
        let CliCommand::Render(args) = cli.command else {
            panic!("a render command");
        };
        capture_options(&args, Path::new("out")).map_err(|e| format!("{e:?}"))
    }

    /// Force arrows by default; `--normals` adds the normals; `--no-arrows` draws the blocks
    /// alone, and cannot be asked for with `--normals`.
    #[test]
    fn arrows_follow_the_flags() {
        assert_eq!(options(&[]).unwrap().style.arrows, ArrowMode::Forces);
        assert_eq!(
            options(&["--normals"]).unwrap().style.arrows,
            ArrowMode::Both
        );
        assert_eq!(
            options(&["--no-arrows"]).unwrap().style.arrows,
            ArrowMode::None
        );
        assert!(options(&["--normals", "--no-arrows"]).is_err());
    }

    /// A negative number is a value of its flag, which its own check answers (before: clap's
    /// tip "to pass '-3' as a value, use '-- -3'", for flags that take no such value); the
    /// camera's messages name the flag once.
    #[test]
    fn negative_numbers_and_bad_cameras_get_their_flags_message() {
        let err = options(&["--arrows", "-3"]).unwrap_err();
        assert!(
            err.contains("--arrows takes a positive count or `all`, got \\\"-3\\\""),
            "{err}"
        );
        for flag in ["--width", "--height", "--msaa"] {
            let err = options(&[flag, "-3"]).unwrap_err();
            assert!(err.contains("invalid value '-3'"), "{flag}: {err}");
            assert!(!err.contains("-- -3"), "{flag}: {err}");
        }
        let err = options(&["--camera", "30"]).unwrap_err();
        assert!(
            err.contains("\"--camera: expects az,el or az,el,dist"),
            "{err}"
        );
        assert_eq!(err.matches("--camera").count(), 1, "{err}");
        let err = options(&["--camera", "30,x"]).unwrap_err();
        assert!(
            err.contains("\"--camera: elevation \\\"x\\\" is not a number"),
            "{err}"
        );
    }

    /// From t = 0 the frames after the first are 1..=⌊duration·fps⌋, as before `--resume`;
    /// from a checkpoint they are the multiples of 1/fps after its time, one on a frame time
    /// (within round-off) included in the first frame.
    #[test]
    fn frames_follow_the_multiples_of_one_over_fps_after_the_start() {
        assert_eq!(frame_numbers(0.0, 2.0, 30.0), (1, 60));
        assert_eq!(frame_numbers(0.0, 0.05, 30.0), (1, 1));
        assert_eq!(
            frame_numbers(0.0, 0.01, 30.0),
            (1, 0),
            "no frame after the first"
        );
        assert_eq!(frame_numbers(0.5, 2.0, 30.0), (16, 60));
        assert_eq!(frame_numbers(0.5 - 1e-13, 2.0, 30.0), (16, 60));
        assert_eq!(frame_numbers(0.51, 2.0, 30.0), (16, 60));
        assert_eq!(frame_numbers(0.01, 0.1, 10.0), (1, 1));
    }
}
