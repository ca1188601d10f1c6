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
    RenderArgs, Simulated, capture_failure, capture_options, conclude, write_summary,
};
use crate::compare::{CompareSpec, caption, labels};
use crate::output::slug;
use crate::render::{FrameCapture, RenderError};
use crate::scene::Scene;
use crate::solver::Solver;

/// `render --compare`: as `render`, with two runs in each frame.
pub(super) fn execute(args: &RenderArgs, scene: Scene, spec: &CompareSpec) -> Result<(), Failure> {
    let params_b = spec
        .derive(&scene.params)
        .map_err(|e| Failure::Input(e.to_string()))?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(slug(&scene.name)).join("frames"));
    let mut opts = capture_options(args, &out)?;
    let (la, lb) = labels(&scene.params, &params_b);
    opts.sides = Some([
        caption("A", &scene.params, &la),
        caption("B", &params_b, &lb),
    ]);
    let name = scene.name.clone();
    let mut a = Solver::new(scene.model.clone(), scene.params);
    let mut b = Solver::new(scene.model, params_b);
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

/// Steps both solvers to each frame time in turn and submits the pair there, frame 0
/// included. Either run's failure ends both early (a half with nothing to show would not
/// compare); a capture failure is the error.
fn simulate_pairs(
    a: &mut Solver,
    b: &mut Solver,
    capture: &FrameCapture,
    args: &RenderArgs,
) -> Result<Simulated, RenderError> {
    let mut simulated = Simulated::new();
    let frame_dt = 1.0 / args.fps;
    let duration = a.params.duration.min(b.params.duration);
    let total_frames = (duration * args.fps + 1e-9).floor() as u64 + 1;
    let mut progress = Progress::new(duration, args.quiet);
    capture.submit_pair(a.snapshot(), b.snapshot())?;
    for k in 1..total_frames {
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
