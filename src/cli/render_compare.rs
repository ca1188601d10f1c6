//! `dda3d render SCENE --compare METHOD` (or `--compare-set`): runs A (the scene's settings)
//! and B (derived) to every frame time in turn, each with its own steps shortened to land on
//! the frame time, and hands both snapshots to the capture as one side-by-side frame: A left,
//! B right, one camera, each half captioned with its side and the settings that differ.
//! frames.csv lists both sides' times and steps.

use std::path::PathBuf;
use std::time::Instant;

use super::Progress;
use super::exit::{self, Failure};
use super::render::{
    RenderArgs, Simulated, capture_failure, capture_options, conclude, frame_numbers, write_summary,
};
use crate::compare::{CompareSpec, caption, labels};
use crate::output::slug;
use crate::render::{FrameCapture, RenderError};
use crate::scene::Scene;
use crate::solver::{Solver, checkpoint};

/// `render --compare`: as `render`, with two runs in each frame.
pub(super) fn execute(args: &RenderArgs, scene: Scene, spec: &CompareSpec) -> Result<(), Failure> {
    let params_b = spec
        .derive(&scene.params)
        .map_err(|e| Failure::Input(e.to_string()))?;
    let out = PathBuf::from("out").join(slug(&scene.name));
    let a = Solver::new(scene.model.clone(), scene.params);
    let b = Solver::new(scene.model, params_b);
    render_pair(args, a, b, out)
}

/// `render --resume CHECKPOINT --compare METHOD`: both runs start from the checkpoint's state
/// `a`, B given its own settings (derived from the checkpoint's) as a comparison started from
/// a checkpoint in the window is ([`Solver::set_params`]).
pub(super) fn execute_from(
    args: &RenderArgs,
    a: Solver,
    spec: &CompareSpec,
    out: PathBuf,
) -> Result<(), Failure> {
    let params_b = spec
        .derive(&a.params)
        .map_err(|e| Failure::Input(e.to_string()))?;
    let mut b = checkpoint::decode(&checkpoint::encode(&a))
        .map_err(|e| Failure::Failed(format!("the checkpoint's copy for B: {e}")))?;
    b.set_params(params_b);
    render_pair(args, a, b, out)
}

/// Renders A and B side by side into `--out`, or `default_out/frames`.
fn render_pair(
    args: &RenderArgs,
    mut a: Solver,
    mut b: Solver,
    default_out: PathBuf,
) -> Result<(), Failure> {
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| default_out.join("frames"));
    let mut opts = capture_options(args, &out)?;
    let (la, lb) = labels(&a.params, &b.params);
    opts.sides = Some([caption("A", &a.params, &la), caption("B", &b.params, &lb)]);
    let name = a.model.name.clone();
    exit::catch_stop_signals()?;
    let capture = FrameCapture::start(opts).map_err(|e| capture_failure(&out, e))?;
    let start = Instant::now();
    let simulated =
        simulate_pairs(&mut a, &mut b, &capture, args).map_err(|e| capture_failure(&out, e))?;
    let report = capture.finish().map_err(|e| capture_failure(&out, e))?;
    let wall = start.elapsed().as_secs_f64();
    write_summary(&out, &name, args, &report, &simulated, wall)?;
    conclude(
        args,
        (&name, &out),
        &report,
        &simulated,
        wall,
        (
            a.time.min(b.time),
            "side-by-side frames",
            "simulation of A and B",
        ),
    )
}

/// Steps both solvers to each frame time in turn and submits the pair there, the first frame
/// (t = 0, or the checkpoint's time) included. Either run's failure ends both early (a half
/// with nothing to show would not compare); a capture failure is the error.
fn simulate_pairs(
    a: &mut Solver,
    b: &mut Solver,
    capture: &FrameCapture,
    args: &RenderArgs,
) -> Result<Simulated, RenderError> {
    let mut simulated = Simulated::new();
    let frame_dt = 1.0 / args.fps;
    let duration = a.params.duration.min(b.params.duration);
    let (first, last) = frame_numbers(a.time, duration, args.fps);
    let mut progress = Progress::new(duration, args.quiet);
    capture.submit_pair(a.snapshot(), b.snapshot())?;
    for k in first..=last {
        let t = k as f64 * frame_dt;
        if !(simulated.step_to(a, t, frame_dt) && simulated.step_to(b, t, frame_dt)) {
            break;
        }
        capture.submit_pair(a.snapshot(), b.snapshot())?;
        progress.update(a.time);
    }
    progress.finish();
    Ok(simulated)
}
