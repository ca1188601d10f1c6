//! `dda3d study`: runs the cases of a parameter study (see [`crate::study`]) in parallel on the
//! local cores, one record file per finished case, `study.csv` rewritten as they finish, and
//! the tables and plots at the end. A second run with the same `--out` resumes: it skips every
//! case with a record. `--case K` runs one case alone (a Slurm array's task) and prints its row.
//! SIGINT or SIGTERM stops starting cases, abandons those in flight and writes the table of what
//! finished.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::exit::{self, Failure};
use crate::study::{CaseRecord, Study, StudyError, default_out, run_task_until, table};
use crate::text::short;

#[derive(Args, Debug)]
pub struct StudyArgs {
    /// Study file (TOML): the base scene, the keys varied, the outcomes.
    pub study: PathBuf,
    /// Cases run at once (default: the available cores).
    #[arg(long, short = 'j', value_name = "N", allow_negative_numbers = true)]
    pub jobs: Option<usize>,
    /// Output directory (default: out/<study file name as a slug>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run case K (0-based) alone, write its record and print its row; exit status 1 if it
    /// failed. The next full run assembles it.
    #[arg(long, value_name = "K", allow_negative_numbers = true)]
    pub case: Option<usize>,
    /// With --case K: write case K's scene (the base scene with its values set) to FILE and
    /// run nothing, to watch or rerun the case with `dda3d view FILE` / `dda3d run FILE`.
    #[arg(long, value_name = "FILE", requires = "case")]
    pub write_scene: Option<PathBuf>,
    /// Run again the cases whose record says they failed (resuming skips them otherwise).
    #[arg(long)]
    pub retry_failed: bool,
    /// No progress bar and no final line.
    #[arg(long, short)]
    pub quiet: bool,
}

fn failure(e: StudyError) -> Failure {
    if e.is_io() {
        Failure::Io(e.to_string())
    } else {
        Failure::Input(e.to_string())
    }
}

/// How often, in wall time, a running study rewrites study.csv.
const TABLE_EVERY: Duration = Duration::from_secs(1);

/// `dda3d study`, with its failures as [`Failure`]s (their exit statuses).
pub(super) fn execute(args: &StudyArgs) -> Result<(), Failure> {
    if args.jobs == Some(0) {
        return Err(Failure::Input("--jobs 0: give at least one".into()));
    }
    let study = Study::load(&args.study).map_err(failure)?;
    if let (Some(k), Some(file)) = (args.case, &args.write_scene) {
        let task = study.task(k).map_err(failure)?;
        let cannot = |e: String| Failure::Io(format!("{}: cannot write: {e}", file.display()));
        // Its directory is made as `--out`'s is, and a file in the way is named (the system's
        // "Not a directory" named nothing).
        if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty()) {
            if dir.exists() && !dir.is_dir() {
                return Err(cannot(format!(
                    "{} is a file, not a directory",
                    dir.display()
                )));
            }
            crate::files::create_dir_clearly(dir).map_err(cannot)?;
        }
        return crate::output::write_atomically(file, task.scene_text.as_bytes())
            .map_err(|e| cannot(e.to_string()));
    }
    let out = args.out.clone().unwrap_or_else(|| default_out(&args.study));
    // Also refuses another study's directory before anything is written, --case included.
    let (mut records, todo) = study.pending(&out, args.retry_failed).map_err(failure)?;
    if let Some(k) = args.case {
        return one_case(&study, &out, k);
    }
    exit::catch_stop_signals()?;
    // study.json first: it marks the directory as this study's, even if killed at once.
    table::write_tables(&study, &out, &records).map_err(failure)?;
    let start = Instant::now();
    let jobs = args.jobs.unwrap_or_else(cores).max(1);
    let bar = progress(&study, records.len(), args.quiet);
    let run = run_cases(&study, &out, &todo, jobs, &mut records, &bar);
    bar.finish_and_clear();
    run?;
    study.assemble(&out, &records).map_err(failure)?;
    conclude(
        &study,
        &out,
        &records,
        start.elapsed().as_secs_f64(),
        args.quiet,
    )
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, usize::from)
}

fn progress(study: &Study, done: usize, quiet: bool) -> ProgressBar {
    let target = if quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(Some(study.len() as u64), target);
    bar.set_style(
        ProgressStyle::with_template(
            "[{elapsed_precise}] {bar:40} {pos}/{len} cases{msg} (eta {eta})",
        )
        .expect("valid template"),
    );
    bar.set_position(done as u64);
    bar
}

/// Runs the cases `todo` on `jobs` threads, each with its share of the cores for the solver's
/// own parallel loops; records each as it finishes. Stops starting cases on a signal.
fn run_cases(
    study: &Study,
    out: &std::path::Path,
    todo: &[usize],
    jobs: usize,
    records: &mut Vec<CaseRecord>,
    bar: &ProgressBar,
) -> Result<(), Failure> {
    let next = AtomicUsize::new(0);
    let threads_per_case = (cores() / jobs).max(1);
    let (send, receive) = mpsc::channel::<CaseRecord>();
    let stop = || exit::interrupted().is_some();
    std::thread::scope(|scope| {
        for _ in 0..jobs.min(todo.len()) {
            let send = send.clone();
            let next = &next;
            scope.spawn(move || {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads_per_case)
                    .build();
                while !stop() {
                    let Some(&case) = todo.get(next.fetch_add(1, Ordering::SeqCst)) else {
                        break;
                    };
                    let record = match (study.task(case), &pool) {
                        (Ok(task), Ok(pool)) => pool.install(|| run_task_until(&task, &stop)),
                        (Ok(task), Err(_)) => run_task_until(&task, &stop),
                        (Err(e), _) => Some(failed_task(study, case, &e)),
                    };
                    // None: stopped by a signal. A closed channel: the main thread gave up.
                    if record.is_none_or(|r| send.send(r).is_err()) {
                        break;
                    }
                }
            });
        }
        drop(send);
        collect(study, out, receive, records, bar)
    })
}

/// A case whose scene text could not be made (a key checked at load cannot fail later, but a
/// case must never stop the study).
fn failed_task(study: &Study, case: usize, e: &StudyError) -> CaseRecord {
    CaseRecord {
        case,
        values: Vec::new(),
        outcomes: vec![None; study.outcomes().len()],
        status: "failed".into(),
        error: Some(e.to_string()),
        wall_seconds: 0.0,
        fingerprint: study.fingerprint().to_string(),
    }
}

/// The main thread's part: each finished case's record written, the bar moved, study.csv
/// rewritten at most every [`TABLE_EVERY`].
fn collect(
    study: &Study,
    out: &std::path::Path,
    receive: mpsc::Receiver<CaseRecord>,
    records: &mut Vec<CaseRecord>,
    bar: &ProgressBar,
) -> Result<(), Failure> {
    let mut last_table = Instant::now();
    let mut failed = records.iter().filter(|r| !r.is_ok()).count();
    for record in receive {
        table::write_record(out, &record).map_err(failure)?;
        failed += usize::from(!record.is_ok());
        records.retain(|r| r.case != record.case);
        records.push(record);
        bar.inc(1);
        if failed > 0 {
            bar.set_message(format!(", {failed} failed"));
        }
        if last_table.elapsed() >= TABLE_EVERY {
            table::write_tables(study, out, records).map_err(failure)?;
            last_table = Instant::now();
        }
    }
    Ok(())
}

/// The final line, and the exit status: interrupted, some case failed, or all ok.
fn conclude(
    study: &Study,
    out: &std::path::Path,
    records: &[CaseRecord],
    wall: f64,
    quiet: bool,
) -> Result<(), Failure> {
    let ok = records.iter().filter(|r| r.is_ok()).count();
    let failed = records.len() - ok;
    let line = format!(
        "{} cases: {ok} ok, {failed} failed, wall {} s; study.csv in {}",
        records.len(),
        short(wall),
        out.display()
    );
    if let Some(signal) = exit::interrupted() {
        return Err(Failure::Interrupted(
            signal,
            format!(
                "{} of {} cases finished; {line}",
                records.len(),
                study.len()
            ),
        ));
    }
    if !quiet {
        eprintln!("{line}");
    }
    if failed > 0 {
        return Err(Failure::Diverged(format!(
            "{failed} of {} cases failed (their errors are in {})",
            records.len(),
            out.join("study.csv").display()
        )));
    }
    Ok(())
}

/// `--case K`: the case alone, its record written and its row printed (header first).
fn one_case(study: &Study, out: &std::path::Path, case: usize) -> Result<(), Failure> {
    let task = study.task(case).map_err(failure)?;
    let record = run_task_until(&task, &|| false)
        .ok_or_else(|| Failure::Failed("the case was stopped".into()))?;
    table::write_record(out, &record).map_err(failure)?;
    let text = table::csv_text(&table::header(study), &[table::row(&record)]).map_err(failure)?;
    print!("{}", String::from_utf8_lossy(&text));
    match record.error {
        None => Ok(()),
        Some(e) => Err(Failure::Diverged(format!("case {case} failed: {e}"))),
    }
}

/// `dda3d study`.
pub fn study(args: &StudyArgs) -> Result<(), super::CliError> {
    execute(args).map_err(super::CliError::from)
}
