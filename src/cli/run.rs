//! `dda3d run`: simulates a scene headless and writes blocks.csv, contacts.csv and summary.json,
//! with a progress bar for long runs (also used by `dda3d render`).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::{CliError, SolverOverrides, load_scene};
use crate::output::{RunWriter, Summary, slug};
use crate::solver::{Solver, SolverError};

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

/// Runs the initial equilibrium stage, if the scene has one, and says how it ended: an
/// unconverged stage is a warning (a block the stage could not bring to rest), not an error.
fn settle(solver: &mut Solver, scene: &Path, quiet: bool) -> Result<(), SolverError> {
    while solver.in_equilibrium_stage() {
        solver.step()?;
    }
    match solver.equilibrium() {
        Some(r) if !r.converged => eprintln!(
            "{}: warning: the initial equilibrium stage did not converge: R_max = {:.2e} after {} \
             steps (tolerance {:.0e}); a block may be unstable under gravity, or raise \
             equilibrium_max_steps",
            scene.display(),
            r.residual,
            r.steps,
            r.tolerance
        ),
        Some(r) if !quiet => eprintln!(
            "initial equilibrium: R_max = {:.2e} after {} static steps",
            r.residual, r.steps
        ),
        _ => {}
    }
    Ok(())
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
    let mut failure = settle(&mut solver, &args.scene, args.quiet).err();
    writer.write(&solver.snapshot()).map_err(io)?;
    while failure.is_none() && !solver.finished() {
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
    summary.equilibrium = solver.equilibrium();
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
