//! `dda3d view` (and its shorthand `dda3d SCENE.toml`): reads the viewer's flags, loads the
//! scene, and opens the viewer of [`crate::viewer`] with them.

use std::path::{Path, PathBuf};

use clap::Args;

use super::{CliError, SolverOverrides, load_scene};
use crate::compare::CompareSpec;
use crate::output::slug;
use crate::scene::{OutputSettings, Scene};
use crate::solver::checkpoint;
use crate::viewer::sim::{Origin, Speed};
use crate::viewer::{ViewerError, ViewerOptions, run_viewer};

#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// Scene file (TOML). Left out with --resume, whose checkpoint holds the scene.
    #[arg(required_unless_present = "resume")]
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub overrides: SolverOverrides,
    /// Open at the state saved in CHECKPOINT (a checkpoint_<t>.ckpt file of `run
    /// --checkpoint-every` or of Save state), in place of SCENE: a large rock mass's
    /// equilibrium stage is computed once, headless, and watched from there as often as
    /// wanted. Reset goes back to it. The solver settings are the checkpoint's; --duration is
    /// the end time (from t = 0, as in the scene).
    #[arg(
        long,
        value_name = "CHECKPOINT",
        conflicts_with_all = ["scene", "method", "mode", "spectral_radius", "max_time_step", "initial_equilibrium", "sleep_velocity"]
    )]
    pub resume: Option<PathBuf>,
    /// Initial window size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Simulation speed: a real-time factor (1 = real time, 0.1 = slow motion) or `max`.
    #[arg(long, default_value = "1", value_parser = parse_speed, allow_negative_numbers = true)]
    pub speed: Speed,
    /// Open paused at t = 0 instead of running.
    #[arg(long)]
    pub paused: bool,
    /// Write the whole window (3-D view and panels) to this PNG, then exit (after
    /// --exit-after-frames frames, default 10).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Render this many frames, then exit with status 0 (with --screenshot: write it first).
    /// Prints the frame time and solver speed on exit.
    #[arg(long, allow_negative_numbers = true)]
    pub exit_after_frames: Option<u64>,
    /// MSAA samples of the 3-D view (1 or 4). Default: 4 on a GPU, 1 on a software
    /// rasterizer, where 4× costs about three times as much per frame.
    #[arg(long, allow_negative_numbers = true)]
    pub msaa: Option<u32>,
    /// Directory for the screenshot button and recordings (default: out/<scene name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Compare: also run the scene with the contact method METHOD (alm or penalty) as run B,
    /// the scene's own settings being run A, side by side in lock-step of simulated time.
    #[arg(long, value_name = "METHOD")]
    pub compare: Option<String>,
    /// Compare: run B's settings as changes to A's, any scene-file key of [solver],
    /// [solver.contact] and [joint] (e.g. initial_penalty=2e9,eps1=0.001); with or without
    /// --compare.
    #[arg(long, value_name = "KEY=VALUE,...")]
    pub compare_set: Option<String>,
    /// Compare: open in one pane, run B drawn as a translucent ghost over run A (the toggle
    /// above the solver panel switches back to two panes).
    #[arg(long)]
    pub ghost: bool,
    /// Open with this block selected (its name, as in blocks.csv): its card and contacts show
    /// from the first frame, in both runs of a comparison.
    #[arg(long, value_name = "BLOCK")]
    pub select: Option<String>,
}

/// Frames rendered before `--screenshot` is taken when `--exit-after-frames` is not given:
/// enough for egui to settle its layout.
const DEFAULT_SCREENSHOT_FRAMES: u64 = 10;

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got {s:?}"))?;
    let num = |t: &str| {
        t.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (64..=16384).contains(v))
            .ok_or_else(|| format!("window size {s:?}: each side must be 64..=16384 pixels"))
    };
    Ok((num(w)?, num(h)?))
}

fn parse_speed(s: &str) -> Result<Speed, String> {
    let t = s.trim().to_ascii_lowercase();
    if t == "max" || t == "fast" {
        return Ok(Speed::Max);
    }
    let t = t.trim_end_matches(['x', '×']);
    match t.parse::<f64>() {
        Ok(f) if f.is_finite() && f > 0.0 && f <= 1e6 => Ok(Speed::RealTime(f)),
        _ => Err(format!(
            "--speed expects a positive real-time factor (e.g. 1, 0.25) or `max`, got {s:?}"
        )),
    }
}

/// A viewer without a GPU driver is an installation problem, reported like bad input (exit
/// status 2) as `render` does; any other failure of the window is a failed run.
impl From<ViewerError> for CliError {
    fn from(e: ViewerError) -> Self {
        match e {
            ViewerError::NoAdapter => CliError::Input(e.to_string()),
            ViewerError::Failed(m) => CliError::Run(m),
        }
    }
}

/// The scene the viewer opens, and the checkpoint it starts from (encoded) with `--resume`: the
/// checkpoint's blocks, settings and name then make the scene.
fn open(args: &ViewArgs) -> Result<(Scene, Option<Origin>), CliError> {
    let Some(path) = &args.resume else {
        let scene = args.scene.as_deref().unwrap_or(Path::new("-"));
        return Ok((load_scene(scene, &args.overrides)?, None));
    };
    let solver = super::resume::resume(path, &args.overrides).map_err(CliError::from)?;
    let scene = Scene {
        name: solver.model.name.clone(),
        params: solver.params.clone(),
        model: solver.model.clone(),
        rock_masses: Vec::new(),
        output: OutputSettings::default(),
    };
    Ok((scene, Some(checkpoint::encode(&solver).into())))
}

/// `dda3d view`.
pub fn view(args: &ViewArgs) -> Result<(), CliError> {
    let (scene, origin) = open(args)?;
    // Checked as `run --compare` checks it: one line naming the flag and the key, exit 2.
    let compare = CompareSpec::parse(args.compare.as_deref(), args.compare_set.as_deref())
        .and_then(|spec| spec.map(|s| s.derive(&scene.params)).transpose())
        .map_err(|e| CliError::Input(e.to_string()))?;
    if args.ghost && compare.is_none() {
        return Err(CliError::Input(
            "--ghost draws run B over run A: add --compare or --compare-set".into(),
        ));
    }
    let selected = match &args.select {
        None => None,
        Some(name) => Some(
            scene
                .model
                .blocks
                .iter()
                .position(|b| &b.name == name)
                .ok_or_else(|| {
                    CliError::Input(format!("--select: the scene has no block named {name:?}"))
                })?,
        ),
    };
    if let Some(n) = args.msaa
        && !matches!(n, 1 | 4)
    {
        return Err(CliError::Input(format!("--msaa must be 1 or 4, got {n}")));
    }
    if args.exit_after_frames == Some(0) {
        return Err(CliError::Input(
            "--exit-after-frames must be at least 1".into(),
        ));
    }
    if let Some(p) = &args.screenshot
        && let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        return Err(CliError::Input(format!(
            "--screenshot {}: directory {} does not exist",
            p.display(),
            dir.display()
        )));
    }
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(slug(&scene.name)));
    let exit_after = args
        .exit_after_frames
        .or(args.screenshot.as_ref().map(|_| DEFAULT_SCREENSHOT_FRAMES));
    run_viewer(ViewerOptions {
        scene,
        size: args.size,
        speed: args.speed,
        play: !args.paused,
        screenshot: args.screenshot.clone(),
        exit_after_frames: exit_after,
        msaa: args.msaa,
        out_dir,
        ghost: args.ghost,
        compare,
        selected,
        origin,
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_speeds_parse() {
        assert_eq!(parse_size("1280x720"), Ok((1280, 720)));
        assert_eq!(parse_size("800X600"), Ok((800, 600)));
        assert!(parse_size("1280").is_err());
        assert!(parse_size("0x720").is_err());
        assert_eq!(parse_speed("max"), Ok(Speed::Max));
        assert_eq!(parse_speed("0.25"), Ok(Speed::RealTime(0.25)));
        assert_eq!(parse_speed("2x"), Ok(Speed::RealTime(2.0)));
        assert!(parse_speed("-1").is_err());
        assert!(parse_speed("fastest").is_err());
    }
}
