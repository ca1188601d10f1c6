//! `dda3d run`: simulates a scene headless and writes blocks.csv, contacts.csv and summary.json,
//! with a progress bar for long runs (also used by `dda3d render`). A run stopped by SIGINT or
//! SIGTERM finishes its step and writes everything; a checkpoint every second keeps the files
//! usable even after a kill -9 (see [`crate::output`]). `--checkpoint-every` saves the solver's
//! whole state as the run goes, and `--resume` goes on from such a file (see [`super::resume`]).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::compare::{self, CompareArgs};
use super::exit::{self, Failure, Signal};
use super::resume::{self, Checkpoints};
use super::{CliError, SolverOverrides, load_scene};
use crate::output::vtk::VtkWriter;
use crate::output::{OutputError, RunWriter, Schedule, Summary, slug};
use crate::params::{Method, Mode};
use crate::rockmass::report::RockMassReport;
use crate::scene::OutputSettings;
use crate::snapshot::{EquilibriumReport, Snapshot};
use crate::solver::{Solver, SolverError};
use crate::text::short;

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scene file (TOML). Left out with --resume, whose checkpoint holds the scene.
    #[arg(required_unless_present = "resume")]
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub overrides: SolverOverrides,
    /// Output directory (default: out/<scene name as a slug>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// No progress bar and no final line.
    #[arg(long, short)]
    pub quiet: bool,
    /// Save the solver's complete state to OUT/checkpoint_<t>.ckpt at the end of the first step
    /// at or after each multiple of T seconds of simulated time (t: that step's time, to the
    /// microsecond). Saving does not change the run.
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub checkpoint_every: Option<f64>,
    /// Go on with the run saved in CHECKPOINT (a checkpoint_<t>.ckpt file), in place of SCENE:
    /// from t on it writes the rows the uninterrupted run wrote, byte for byte, starting with
    /// the row at t. The solver settings are the checkpoint's; --duration is the new end time
    /// (total simulated time from t = 0, as in the scene); --out defaults to
    /// out/<scene name>-resumed, so the run it continues is kept.
    #[arg(
        long,
        value_name = "CHECKPOINT",
        conflicts_with_all = ["scene", "method", "mode", "spectral_radius", "max_time_step", "initial_equilibrium", "sleep_velocity"]
    )]
    pub resume: Option<PathBuf>,
    #[command(flatten)]
    pub compare: CompareArgs,
    /// Also write the ParaView series into OUT/vtk/ (blocks as polyhedra, contacts as points,
    /// .pvd collections with simulated time); the scene's `[output] vtk = true`
    #[arg(long)]
    pub vtk: bool,
    /// Simulated time between outputs, s: the CSV rows and the VTK series (the scene's
    /// `[output] interval`; default: every step). The first state, the first step at or past
    /// each multiple, and the final state are written
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub output_interval: Option<f64>,
}

impl RunArgs {
    /// The file the run comes from, for messages: the scene, or the checkpoint resumed.
    fn source(&self) -> &Path {
        let from = self.resume.as_deref().or(self.scene.as_deref());
        from.unwrap_or(Path::new("-"))
    }
}

/// A progress bar that appears only once a run has taken more than a second: the simulated
/// time, or the equilibrium stage's static steps ([`Progress::stage`]).
pub struct Progress {
    bar: ProgressBar,
    start: Instant,
    shown: bool,
    quiet: bool,
}

impl Progress {
    pub fn new(total_seconds: f64, quiet: bool) -> Self {
        let len = (total_seconds * 1000.0).round() as u64;
        Progress::styled(len, "{bar:40} t = {msg} s (eta {eta})", quiet)
    }

    /// The equilibrium stage's bar: its static steps against `equilibrium_max_steps`, R_max
    /// against its tolerance ([`Progress::update_stage`]). A large rock mass's stage runs for
    /// minutes before the first simulated second (the jointed mass of 1000: about 200 s), and
    /// the time bar shows nothing meanwhile.
    fn stage(max_steps: u32, quiet: bool) -> Self {
        let template = "equilibrium stage {bar:40} step {pos}/{len}, {msg}";
        Progress::styled(max_steps.into(), template, quiet)
    }

    /// A hidden bar of `len` units drawn by `template` after the spinner and the elapsed time.
    fn styled(len: u64, template: &str, quiet: bool) -> Self {
        let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template(&format!("{{spinner}} [{{elapsed_precise}}] {template}"))
                .expect("valid template"),
        );
        Progress {
            bar,
            start: Instant::now(),
            shown: false,
            quiet,
        }
    }

    /// Whether to update the bar; shows it on stderr once the run has taken a second.
    fn reveal(&mut self) -> bool {
        if self.quiet {
            return false;
        }
        if !self.shown && self.start.elapsed() > Duration::from_secs(1) {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown = true;
        }
        true
    }

    pub fn update(&mut self, time: f64) {
        if self.reveal() {
            self.bar.set_position((time * 1000.0).round() as u64);
            self.bar.set_message(format!("{time:.3}"));
        }
    }

    /// The stage's bar ([`Progress::stage`]) after its latest static step.
    fn update_stage(&mut self, report: Option<EquilibriumReport>) {
        if let Some(r) = report
            && self.reveal()
        {
            self.bar.set_position(r.steps);
            self.bar.set_message(format!(
                "R_max {} (tolerance {})",
                short(r.residual),
                short(r.tolerance)
            ));
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Runs the initial equilibrium stage, if the scene has one, and says how it ended: an
/// unconverged stage is a warning (a block the stage could not bring to rest), not an error.
/// A stop signal ends the stage early (`Ok(Some(signal))`).
pub(super) fn settle(
    solver: &mut Solver,
    scene: &Path,
    quiet: bool,
) -> Result<Option<Signal>, SolverError> {
    // A run resumed after its stage said how the stage ended the first time.
    if !solver.in_equilibrium_stage() && solver.time > 0.0 {
        return Ok(None);
    }
    let mut bar = Progress::stage(solver.params.equilibrium_max_steps, quiet);
    while solver.in_equilibrium_stage() {
        if let Some(signal) = exit::interrupted() {
            bar.finish();
            return Ok(Some(signal));
        }
        let stepped = solver.step().map(|_| ());
        bar.update_stage(solver.equilibrium());
        if let Err(e) = stepped {
            bar.finish();
            return Err(e);
        }
    }
    bar.finish();
    match solver.equilibrium() {
        Some(r) if !r.converged => eprintln!(
            "{}: warning: {}",
            scene.display(),
            unconverged_stage(&r, solver.params.equilibrium_max_steps)
        ),
        Some(r) if !quiet => eprintln!(
            "initial equilibrium: R_max = {} after {} static steps",
            short(r.residual),
            r.steps
        ),
        _ => {}
    }
    Ok(None)
}

impl End {
    /// summary.json's `status` and `error`.
    pub(super) fn status(&self) -> (&'static str, Option<String>) {
        match self {
            End::Completed => ("completed", None),
            End::Diverged(e) => ("diverged", Some(e.to_string())),
            End::Interrupted(s) => ("interrupted", Some(format!("stopped by {}", s.name()))),
            End::Io(e) => ("io_error", Some(e.to_string())),
            End::Stopped(time) => (
                "interrupted",
                Some(format!("stopped by the caller at t = {} s", short(*time))),
            ),
        }
    }
}

/// How often, in wall time, a run commits its CSV rows and rewrites summary.json as
/// "running": what a kill -9 can lose.
const CHECKPOINT: Duration = Duration::from_secs(1);

/// How a run ended.
pub(super) enum End {
    Completed,
    Diverged(SolverError),
    Interrupted(Signal),
    Io(OutputError),
    /// Closed before its end by the program driving it ([`super::RunSession::close`]), at
    /// this simulated time.
    Stopped(f64),
}

/// The outputs of a run as it goes: rows every step, and at every [`CHECKPOINT`] both CSV
/// files committed to the same step and summary.json rewritten as "running".
pub(super) struct Record {
    writer: RunWriter,
    /// The ParaView series, if asked for.
    vtk: Option<VtkWriter>,
    /// When the CSV rows are written (every step without an interval).
    rows: Schedule,
    scene: String,
    method: Method,
    mode: Mode,
    start: Instant,
    last_checkpoint: Instant,
    rock_masses: Vec<RockMassReport>,
    /// The solver's state saved every `--checkpoint-every`.
    states: Checkpoints,
}

impl Record {
    /// The outputs of `solver`'s run in `out`: the CSV files and, when `output.vtk` says so,
    /// the VTK series, both at `output.interval` (every step without one); the checkpoints
    /// every `every`.
    pub(super) fn create(
        out: &Path,
        solver: &Solver,
        scene: &str,
        rock_masses: Vec<RockMassReport>,
        output: OutputSettings,
        every: Option<f64>,
    ) -> Result<Self, Failure> {
        let writer = RunWriter::create(out).map_err(|e| Failure::Io(e.to_string()))?;
        let vtk = output
            .vtk
            .then(|| VtkWriter::create(out, output.interval))
            .transpose()
            .map_err(|e| Failure::Io(e.to_string()))?;
        Ok(Record {
            writer,
            vtk,
            rows: Schedule::new(output.interval),
            scene: scene.to_string(),
            rock_masses,
            method: solver.params.method,
            mode: solver.params.mode,
            start: Instant::now(),
            last_checkpoint: Instant::now(),
            states: Checkpoints::new(every, solver.time),
        })
    }

    fn summary(&self, solver: &Solver, status: &str) -> Summary {
        let wall = self.start.elapsed().as_secs_f64();
        let (method, mode) = (self.method.as_str(), self.mode.as_str());
        let mut s = Summary::new(&self.scene, method, mode, solver.time, wall, &solver.totals);
        s.status = status.into();
        s.written_time = self.writer.written_time();
        s.equilibrium = solver.equilibrium();
        s.rock_masses = self.rock_masses.clone();
        s
    }

    /// Rows of the step just completed when they are due, and a checkpoint when one is due.
    /// The snapshot is taken only for an output.
    pub(super) fn step(&mut self, solver: &Solver) -> Result<(), OutputError> {
        if self.due(solver.time) {
            self.step_with(solver, &solver.snapshot())
        } else {
            self.after_step(solver)
        }
    }

    /// [`Record::step`] with the solver's snapshot taken already.
    pub(super) fn step_with(&mut self, solver: &Solver, s: &Snapshot) -> Result<(), OutputError> {
        self.write(s)?;
        self.after_step(solver)
    }

    /// The checkpoints due after a step.
    fn after_step(&mut self, solver: &Solver) -> Result<(), OutputError> {
        self.states.after_step(solver, self.writer.dir())?;
        if self.last_checkpoint.elapsed() >= CHECKPOINT {
            self.checkpoint(solver)?;
        }
        Ok(())
    }

    /// Whether a state at `time` is written: its rows, or its VTK files.
    fn due(&self, time: f64) -> bool {
        self.rows.due(time) || self.vtk.as_ref().is_some_and(|v| v.due(time))
    }

    /// The rows of a state and its VTK files, each when due.
    pub(super) fn write(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        if self.rows.due(s.time) {
            self.writer.write(s)?;
            self.rows.wrote(s.time);
        }
        match &mut self.vtk {
            Some(vtk) => vtk.step(s),
            None => Ok(()),
        }
    }

    pub(super) fn checkpoint(&mut self, solver: &Solver) -> Result<(), OutputError> {
        self.writer.commit()?;
        self.summary(solver, "running").write(self.writer.dir())?;
        self.last_checkpoint = Instant::now();
        Ok(())
    }

    /// The last rows (and VTK files), then the final summary.json. If the rows cannot be
    /// written, that is what the summary reports: the files stop short of the state the run
    /// reached. Returns how the run ended after all, and whether the summary was written.
    pub(super) fn close(
        &mut self,
        solver: &Solver,
        mut end: End,
    ) -> (End, Result<(), OutputError>) {
        if !matches!(end, End::Io(_)) {
            // The state the run ended in is always written, whatever the interval.
            let s = solver.snapshot();
            let rows = if self.rows.final_due(s.time) {
                self.writer.write(&s)
            } else {
                Ok(())
            };
            let last = self.vtk.as_mut().map(|v| v.finish(&s));
            if let Err(e) = rows
                .and_then(|_| self.writer.commit())
                .and(last.unwrap_or(Ok(())))
            {
                end = End::Io(e);
            }
        }
        let saved = self.finish(solver, &end);
        (end, saved)
    }

    /// The final summary.json (the rows are committed by then).
    fn finish(&mut self, solver: &Solver, end: &End) -> Result<(), OutputError> {
        let (status, error) = end.status();
        let mut summary = self.summary(solver, status);
        summary.error = error;
        summary.write(self.writer.dir()).map(|_| ())
    }
}

/// The start of a run, before its first step: a first summary.json at once (so even a run
/// killed in its first second says so), the initial equilibrium stage, and the rows of the
/// state the run starts from. `Some(end)` when the run ended there.
pub(super) fn begin(
    solver: &mut Solver,
    rec: &mut Record,
    scene: &Path,
    quiet: bool,
) -> Result<Option<End>, OutputError> {
    rec.checkpoint(solver)?;
    let settled = settle(solver, scene, quiet);
    if let Ok(Some(signal)) = settled {
        return Ok(Some(End::Interrupted(signal)));
    }
    // A failed equilibrium stage still writes the state it reached, as a diverged step does.
    rec.write(&solver.snapshot())?;
    Ok(settled.err().map(End::Diverged))
}

/// Steps the run to its end, a divergence, a stop signal or a failed write. A signal that
/// arrives during a step lets the step finish and its rows be written.
fn advance(solver: &mut Solver, rec: &mut Record, args: &RunArgs) -> End {
    let mut progress = Progress::new(solver.params.duration, args.quiet);
    let end = (|| {
        if let Some(end) = begin(solver, rec, args.source(), args.quiet)? {
            return Ok(end);
        }
        while !solver.finished() {
            if let Some(signal) = exit::interrupted() {
                return Ok(End::Interrupted(signal));
            }
            if let Err(e) = solver.step() {
                return Ok(End::Diverged(e));
            }
            rec.step(solver)?;
            progress.update(solver.time);
        }
        Ok::<End, OutputError>(End::Completed)
    })();
    progress.finish();
    end.unwrap_or_else(End::Io)
}

/// The flags of the outputs that can be checked before the scene is read: the interval of
/// `--checkpoint-every`, which it returns, and of `--output-interval`.
pub(super) fn output_flags(args: &RunArgs) -> Result<Option<f64>, Failure> {
    let every = resume::interval(args.checkpoint_every)?;
    if let Some(dt) = args.output_interval {
        OutputSettings::check_interval(dt)
            .map_err(|m| Failure::Input(format!("--output-interval: {m}")))?;
    }
    Ok(every)
}

/// What a run writes besides the CSV files, and how often: `--vtk` or the scene's
/// `[output] vtk`, and `--output-interval` over the scene's `[output] interval` (for the CSV
/// rows and the VTK series alike; every step without one).
pub(super) fn output_settings(args: &RunArgs, output: &OutputSettings) -> OutputSettings {
    OutputSettings {
        vtk: args.vtk || output.vtk,
        interval: args.output_interval.or(output.interval),
    }
}

/// `dda3d run`, with its failures as [`Failure`]s (their exit statuses). Bad input is
/// reported before any file is created.
pub(super) fn execute(args: &RunArgs) -> Result<(), Failure> {
    if let Some(spec) = compare::spec(&args.compare)? {
        return compare::execute(args, &spec);
    }
    let every = output_flags(args)?;
    let (mut solver, rock_masses, output, default_out) = start(args)?;
    let out = args.out.clone().unwrap_or(default_out);
    let output = output_settings(args, &output);
    exit::catch_stop_signals()?;
    let name = solver.model.name.clone();
    let mut rec = Record::create(&out, &solver, &name, rock_masses, output, every)?;
    let end = advance(&mut solver, &mut rec, args);
    let (end, saved) = rec.close(&solver, end);
    report(&solver, &rec, end, saved, (args.source(), args.quiet))
}

/// What a run starts from: the solver (the scene's, or the checkpoint's), the rock masses cut
/// for summary.json (a resumed run has none: the cut was the first run's), the scene's
/// `[output]` table (a resumed run writes VTK only with `--vtk`), and the default output
/// directory.
type Start = (Solver, Vec<RockMassReport>, OutputSettings, PathBuf);

fn start(args: &RunArgs) -> Result<Start, Failure> {
    if let Some(path) = &args.resume {
        let solver = resume::resume(path, &args.overrides)?;
        let out = resume::default_out(&solver);
        return Ok((solver, Vec::new(), OutputSettings::default(), out));
    }
    let scene = load_scene(args.source(), &args.overrides)?;
    let out = PathBuf::from("out").join(slug(&scene.name));
    Ok((
        Solver::new(scene.model, scene.params),
        scene.rock_masses,
        scene.output,
        out,
    ))
}

/// The outcome as one line on stderr (or none, when `quiet`) and an exit status; `scene` is
/// the file the run came from, for messages.
pub(super) fn report(
    solver: &Solver,
    rec: &Record,
    end: End,
    saved: Result<(), OutputError>,
    (scene, quiet): (&Path, bool),
) -> Result<(), Failure> {
    let out = rec.writer.dir().display();
    let kept = match rec.writer.written_time() {
        Some(t) => format!("complete rows up to t = {} s are in {out}", short(t)),
        None => format!("no rows were written to {out}"),
    };
    match (end, saved) {
        (End::Io(e), saved) => {
            let also = saved.err().map(|s| format!("; {s}")).unwrap_or_default();
            Err(Failure::Io(format!("{e}; {kept}{also}")))
        }
        (_, Err(e)) => Err(Failure::Io(format!("{e}; {kept}"))),
        (End::Diverged(e), Ok(())) => Err(Failure::Diverged(format!(
            "{}: {e}; results up to t = {} s are in {out}",
            scene.display(),
            short(solver.time)
        ))),
        (End::Interrupted(signal), Ok(())) => Err(Failure::Interrupted(
            signal,
            format!(
                "{} at t = {} s after {} steps; {kept}",
                signal.name(),
                short(solver.time),
                solver.totals.steps
            ),
        )),
        (End::Stopped(_), Ok(())) => Ok(()),
        (End::Completed, Ok(())) => {
            if !quiet {
                let t = &solver.totals;
                eprintln!(
                    "{}: {} steps to t = {} s in {} s wall; max penetration {} m{}; results in {out}",
                    rec.scene,
                    t.steps,
                    short(solver.time),
                    short(rec.start.elapsed().as_secs_f64()),
                    short(t.max_penetration),
                    settled_note(t.unconverged_steps, t.steps),
                );
            }
            Ok(())
        }
    }
}

/// `dda3d run`.
pub fn run(args: &RunArgs) -> Result<(), CliError> {
    execute(args).map_err(CliError::from)
}

/// The final line's note of the steps whose open–close iteration was settled at its pass limit
/// rather than converged: those steps' contact states are the solver's best guess, which the
/// engineer should know of without opening summary.json. Empty when every step converged.
fn settled_note(settled: u64, steps: u64) -> String {
    if settled == 0 {
        String::new()
    } else {
        format!("; {settled} of {steps} steps settled at the open–close pass limit")
    }
}

/// The warning for an equilibrium stage that ended unconverged, saying what ended it: its step
/// limit, where more steps may settle the model, or before the limit the solver's test for a
/// mechanism (R_max growing for 20 steps in a row, a block sliding away, or no longer falling
/// for 200: `solver::equilibrium`), where more steps would not help.
fn unconverged_stage(r: &EquilibriumReport, max_steps: u32) -> String {
    let head = format!(
        "the initial equilibrium stage did not converge: R_max = {} after {} of its {max_steps} \
         steps (tolerance {})",
        short(r.residual),
        r.steps,
        short(r.tolerance)
    );
    if r.steps < u64::from(max_steps) {
        format!(
            "{head}; it stopped early because R_max kept growing or stopped falling: a block \
             moves under gravity (it slides or topples), and more steps would not bring it to \
             rest"
        )
    } else {
        format!("{head}; a block may be unstable under gravity, or raise equilibrium_max_steps")
    }
}

#[cfg(test)]
mod tests {
    use super::{settled_note, unconverged_stage};
    use crate::snapshot::EquilibriumReport;

    /// A stage that ended before its step limit does not advise raising the limit: it says
    /// the mechanism test ended it (the jointed slope's stopped at 49 of 60 steps, its block
    /// sliding, and was told to raise equilibrium_max_steps).
    #[test]
    fn an_unconverged_stage_says_what_ended_it() {
        let report = |steps| EquilibriumReport {
            steps,
            residual: 3.689,
            tolerance: 1e-3,
            converged: false,
            running: false,
        };
        let early = unconverged_stage(&report(49), 60);
        assert!(
            early.starts_with(
                "the initial equilibrium stage did not converge: R_max = 3.689 \
                 after 49 of its 60 steps (tolerance 0.001); it stopped early because"
            ),
            "{early}"
        );
        assert!(!early.contains("raise"), "{early}");
        let limit = unconverged_stage(&report(60), 60);
        assert!(
            limit.ends_with(
                "; a block may be unstable under gravity, or raise \
                 equilibrium_max_steps"
            ),
            "{limit}"
        );
    }

    #[test]
    fn the_final_line_names_settled_steps_only_when_there_are_some() {
        assert_eq!(settled_note(0, 390), "");
        assert_eq!(
            settled_note(78, 126),
            "; 78 of 126 steps settled at the open–close pass limit"
        );
    }
}
