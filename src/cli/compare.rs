//! `dda3d run SCENE --compare alm|penalty [--compare-set key=value,...]`: two runs of one scene
//! side by side, A with the scene's settings (and the command line's overrides) and B with
//! the spec's changes ([`crate::compare::spec`]). Each writes what a plain `run` writes, into
//! `DIR/A` and `DIR/B`, byte for byte the same rows as `run` with its settings: each side takes
//! its own steps, untouched. The two go in lock-step of simulated time, to every multiple of
//! the comparison interval (`--compare-interval`, else the scene's `[output] interval`, else
//! 0.01 s), where they are compared between their own steps ([`crate::compare::sample`]);
//! `DIR/compare.json` gets the comparison and, for a slope with a closed form, the paper's
//! tables ([`crate::compare::report`]).
//!
//! `--vtk`, `--output-interval` and `--checkpoint-every` apply to each side (in `DIR/A` and
//! `DIR/B`); `--resume` takes one run's checkpoint and cannot start two runs: clap rejects
//! the combination (exit status 2). A side that diverges stops there and the other runs on to
//! its end, as its plain run would; a stop signal stops both.

use std::path::{Path, PathBuf};

use clap::Args;

use super::exit::{self, Failure};
use super::load_scene;
use super::run::{End, Progress, Record, RunArgs, output_flags, output_settings, settle};
use crate::compare::report::{Recorder, Report, RunReport};
use crate::compare::{CompareSpec, Sample, labels, slope};
use crate::output::{OutputError, slug, write_atomically};
use crate::solver::Solver;
use crate::text::short;

/// The comparison's flags of `dda3d run`.
#[derive(Args, Debug, Clone, Default)]
pub struct CompareArgs {
    /// Also run the scene with the contact method METHOD (alm or penalty) as run B, the scene's
    /// own settings being run A; write DIR/A, DIR/B and DIR/compare.json.
    #[arg(long, value_name = "METHOD", conflicts_with = "resume")]
    pub compare: Option<String>,
    /// Run B's settings as changes to A's, any scene-file key of [solver], [solver.contact]
    /// and [joint] by its name (e.g. initial_penalty=2e9,eps1=0.001; gravity=[0,0,-9.81]);
    /// with or without --compare.
    #[arg(long, value_name = "KEY=VALUE,...", conflicts_with = "resume")]
    pub compare_set: Option<String>,
    /// Simulated time between the comparisons in compare.json, s (default: the scene's
    /// [output] interval, else 0.01).
    #[arg(
        long,
        value_name = "T",
        allow_negative_numbers = true,
        conflicts_with = "resume"
    )]
    pub compare_interval: Option<f64>,
}

/// The most comparison times: compare.json stays a file one can read (at 0.01 s, 1000 s).
const MAX_COMPARISONS: f64 = 1e5;

/// The spec the flags give, if any.
pub(super) fn spec(args: &CompareArgs) -> Result<Option<CompareSpec>, Failure> {
    let spec = CompareSpec::parse(args.compare.as_deref(), args.compare_set.as_deref())
        .map_err(|e| Failure::Input(e.to_string()))?;
    if spec.is_none() && args.compare_interval.is_some() {
        return Err(Failure::Input(
            "--compare-interval sets the interval of a comparison: add --compare or \
             --compare-set"
                .into(),
        ));
    }
    Ok(spec)
}

/// The time between comparisons over a run of `duration`: the flag's, checked, or the
/// default, lengthened to stay within [`MAX_COMPARISONS`].
fn interval(given: Option<f64>, scene: Option<f64>, duration: f64) -> Result<f64, Failure> {
    if let Some(t) = given {
        if !(t.is_finite() && t > 0.0) {
            return Err(Failure::Input(format!(
                "--compare-interval must be a positive number of seconds, got {}",
                short(t)
            )));
        }
        if duration / t > MAX_COMPARISONS {
            return Err(Failure::Input(format!(
                "--compare-interval {} s over {} s makes more than {} comparisons: give a \
                 longer interval",
                short(t),
                short(duration),
                short(MAX_COMPARISONS)
            )));
        }
        return Ok(t);
    }
    Ok(scene.unwrap_or(0.01).max(duration / MAX_COMPARISONS))
}

/// One of the two runs.
struct Side {
    name: &'static str,
    solver: Solver,
    rec: Record,
    /// How the run ended, once it has.
    end: Option<End>,
    /// The state after the step before the last, and after the last.
    prev: Sample,
    now: Sample,
}

impl Side {
    fn new(name: &'static str, solver: Solver, rec: Record) -> Self {
        let now = Sample::of(&solver.snapshot());
        Side {
            name,
            solver,
            rec,
            end: None,
            prev: now.clone(),
            now,
        }
    }

    fn running(&self) -> bool {
        self.end.is_none()
    }

    /// What a plain run does before its first step: a first summary.json, the equilibrium
    /// stage, the rows of the state it starts from.
    fn start(&mut self, scene: &Path, quiet: bool) {
        if let Err(e) = self.rec.checkpoint(&self.solver) {
            self.end = Some(End::Io(e));
            return;
        }
        let settled = settle(&mut self.solver, scene, quiet);
        if let Ok(Some(signal)) = settled {
            self.end = Some(End::Interrupted(signal));
            return;
        }
        // A failed equilibrium stage still writes the state it reached, as a plain run does.
        let s = self.solver.snapshot();
        if let Err(e) = self.rec.write(&s) {
            self.end = Some(End::Io(e));
            return;
        }
        self.now = Sample::of(&s);
        self.prev = self.now.clone();
        if let Err(e) = settled {
            self.end = Some(End::Diverged(e));
        }
    }

    /// One step of the plain run, its rows, and its sample.
    fn step(&mut self) {
        if self.solver.finished() {
            self.end = Some(End::Completed);
            return;
        }
        if let Some(signal) = exit::interrupted() {
            self.end = Some(End::Interrupted(signal));
            return;
        }
        if let Err(e) = self.solver.step() {
            self.end = Some(End::Diverged(e));
            return;
        }
        let s = self.solver.snapshot();
        if let Err(e) = self.rec.step_with(&self.solver, &s) {
            self.end = Some(End::Io(e));
            return;
        }
        self.prev = std::mem::replace(&mut self.now, Sample::of(&s));
        if self.solver.finished() {
            self.end = Some(End::Completed);
        }
    }

    /// Steps until the run reaches `t` (a rounding error short counting as on it), and its
    /// state at `t`; `None` if it ended before.
    fn reach(&mut self, t: f64, tol: f64) -> Option<Sample> {
        while self.running() && self.now.time < t - tol {
            self.step();
        }
        (self.now.time >= t - tol).then(|| self.prev.at(&self.now, t))
    }

    /// The last rows and summary.json; how the run ended after all, and whether its summary
    /// was written.
    fn close(&mut self) -> (End, Result<(), OutputError>) {
        let end = self.end.take().unwrap_or(End::Completed);
        self.rec.close(&self.solver, end)
    }

    /// The run in compare.json, as it ended.
    fn report(&self, end: &End, labels: Vec<String>) -> RunReport {
        let (status, error) = end.status();
        RunReport {
            dir: self.name.into(),
            labels,
            method: self.solver.params.method.as_str().into(),
            mode: self.solver.params.mode.as_str().into(),
            status: status.into(),
            error,
            time: self.solver.time,
            steps: self.solver.totals.steps,
            max_penetration: self.solver.totals.max_penetration,
        }
    }
}

/// `dda3d run SCENE --compare ...`.
pub(super) fn execute(args: &RunArgs, spec: &CompareSpec) -> Result<(), Failure> {
    let every = output_flags(args)?;
    let path = args.scene.as_deref().unwrap_or(Path::new("-"));
    let scene = load_scene(path, &args.overrides).map_err(Failure::from)?;
    let params_b = spec
        .derive(&scene.params)
        .map_err(|e| Failure::Input(e.to_string()))?;
    let duration = scene.params.duration.max(params_b.duration);
    let every_cmp = interval(
        args.compare.compare_interval,
        scene.output.interval,
        duration,
    )?;
    let out = (args.out.clone()).unwrap_or_else(|| PathBuf::from("out").join(slug(&scene.name)));
    let output = output_settings(args, &scene.output);
    exit::catch_stop_signals()?;
    let (labels_a, labels_b) = labels(&scene.params, &params_b);
    let solver_a = Solver::new(scene.model.clone(), scene.params.clone());
    let solver_b = Solver::new(scene.model, params_b);
    let mut recorder = Recorder::new(
        solver_a
            .snapshot()
            .blocks
            .into_iter()
            .map(|b| b.name)
            .collect(),
        slope::of_solver(&solver_a),
        slope::of_solver(&solver_b),
    );
    let name = scene.name;
    let record = |dir: &str, solver: &Solver| {
        let masses = scene.rock_masses.clone();
        Record::create(&out.join(dir), solver, &name, masses, output, every)
    };
    let rec_a = record("A", &solver_a)?;
    let rec_b = record("B", &solver_b)?;
    let mut sides = [
        Side::new("A", solver_a, rec_a),
        Side::new("B", solver_b, rec_b),
    ];
    lock_step(&mut sides, &mut recorder, every_cmp, args);
    let [a, b] = &mut sides;
    let (end_a, end_b) = (a.close(), b.close());
    let runs = [a.report(&end_a.0, labels_a), b.report(&end_b.0, labels_b)];
    let last = [a.solver.snapshot(), b.solver.snapshot()];
    let report = recorder.finish(name.clone(), every_cmp, runs, [&last[0], &last[1]]);
    let written = write_report(&out, &report);
    outcome(&report, [end_a, end_b], written, &out, args.quiet)
}

/// Both runs to every common time, compared there; then each on to its own end (a stop
/// signal ends both).
fn lock_step(sides: &mut [Side; 2], recorder: &mut Recorder, interval: f64, args: &RunArgs) {
    let scene = args.scene.as_deref().unwrap_or(Path::new("-"));
    let end = sides[0]
        .solver
        .params
        .duration
        .min(sides[1].solver.params.duration);
    let longest = sides[0]
        .solver
        .params
        .duration
        .max(sides[1].solver.params.duration);
    let mut progress = Progress::new(longest, args.quiet);
    for side in sides.iter_mut() {
        side.start(scene, args.quiet);
    }
    let tol = 1e-9 * interval;
    let mut k = 0u64;
    loop {
        let t = (k as f64 * interval).min(end);
        let [a, b] = sides;
        let (Some(sa), Some(sb)) = (a.reach(t, tol), b.reach(t, tol)) else {
            break;
        };
        recorder.add(&sa, &sb);
        progress.update(t);
        if t >= end - tol {
            break;
        }
        k += 1;
    }
    let signal = sides.iter().find_map(|s| match s.end {
        Some(End::Interrupted(signal)) => Some(signal),
        _ => None,
    });
    for side in sides.iter_mut() {
        match signal {
            Some(signal) if side.running() => side.end = Some(End::Interrupted(signal)),
            _ => {
                while side.running() {
                    side.step();
                    progress.update(side.solver.time);
                }
            }
        }
    }
    progress.finish();
}

fn write_report(out: &Path, report: &Report) -> Result<(), String> {
    let path = out.join("compare.json");
    let mut bytes = serde_json::to_vec_pretty(report).map_err(|e| e.to_string())?;
    bytes.push(b'\n');
    write_atomically(&path, &bytes).map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

/// The exit status and its one line: an I/O failure first, then a stop signal, then a
/// divergence; a completed comparison says what it found unless `quiet`.
fn outcome(
    report: &Report,
    ends: [(End, Result<(), OutputError>); 2],
    written: Result<(), String>,
    out: &Path,
    quiet: bool,
) -> Result<(), Failure> {
    let dir = out.display();
    let mut io = Vec::new();
    for (name, (end, saved)) in ["A", "B"].iter().zip(&ends) {
        if let End::Io(e) = end {
            io.push(format!("{name}: {e}"));
        }
        if let Err(e) = saved {
            io.push(format!("{name}: {e}"));
        }
    }
    io.extend(written.err());
    if !io.is_empty() {
        return Err(Failure::Io(format!("{}; results in {dir}", io.join("; "))));
    }
    let runs = [&report.a, &report.b];
    let line = |r: &RunReport| {
        format!(
            "{} ({}) {} at t = {} s",
            r.dir,
            r.method,
            r.status,
            short(r.time)
        )
    };
    let both = format!("{}, {}", line(runs[0]), line(runs[1]));
    for (end, _) in &ends {
        if let End::Interrupted(signal) = end {
            return Err(Failure::Interrupted(
                *signal,
                format!("{}: {both}; results in {dir}", signal.name()),
            ));
        }
    }
    for (r, (end, _)) in runs.iter().zip(&ends) {
        if let End::Diverged(e) = end {
            return Err(Failure::Diverged(format!(
                "run {} diverged: {e}; {both}; results in {dir}",
                r.dir
            )));
        }
    }
    if !quiet {
        let largest = report
            .largest_difference
            .as_ref()
            .map_or(String::new(), |c| {
                format!(
                    "; largest displacement difference {} m ({}) at t = {} s",
                    short(c.max_displacement_difference),
                    c.block.as_deref().unwrap_or("-"),
                    short(c.time)
                )
            });
        eprintln!(
            "{}: A [{}] {} steps, B [{}] {} steps to t = {} s{largest}; results in {dir}",
            report.scene,
            report.a.labels.join(", "),
            report.a.steps,
            report.b.labels.join(", "),
            report.b.steps,
            short(report.a.time.min(report.b.time)),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::SolverParams;

    #[test]
    fn the_interval_defaults_and_stays_within_its_bound() {
        assert_eq!(interval(None, None, 2.0).unwrap(), 0.01);
        assert_eq!(interval(None, Some(0.2), 2.0).unwrap(), 0.2);
        assert_eq!(interval(Some(0.05), Some(0.2), 2.0).unwrap(), 0.05);
        assert_eq!(interval(None, None, 1e4).unwrap(), 0.1);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(interval(Some(bad), None, 2.0).is_err(), "{bad}");
        }
        let e = interval(Some(1e-6), None, 2.0).unwrap_err();
        assert!(e.message().contains("more than 100000"), "{}", e.message());
    }

    #[test]
    fn the_interval_needs_a_comparison() {
        let args = CompareArgs {
            compare_interval: Some(0.1),
            ..CompareArgs::default()
        };
        assert!(spec(&args).is_err());
        assert!(spec(&CompareArgs::default()).unwrap().is_none());
    }

    /// B's settings are A's plus the spec: the function the command calls.
    #[test]
    fn b_is_derived_from_a() {
        let spec = CompareSpec::parse(Some("penalty"), None).unwrap().unwrap();
        let b = spec.derive(&SolverParams::default()).unwrap();
        assert_eq!(b.method, crate::params::Method::Penalty);
    }
}
