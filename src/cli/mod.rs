//! The `dda3d` binary's front end: parses the command line, checks the options, loads the scene
//! and hands over to the library, then turns any failure into one line on stderr and an exit
//! status ([`exit`] has the table: 1 only for a diverged run, 2 for bad input, 74 for I/O).
//!
//! One file per subcommand, each with its clap arguments and its entry function:
//! [`run`](run()) (headless simulation), [`render`](render()) (PNG frames), [`generate`](generate())
//! (scene files), [`cut`](cut()) (rock masses to blocks), [`study`](study()) (parameter studies),
//! [`bench`](bench()) and [`view`](view()) (the interactive viewer). [`RunSession`] is `run`
//! driven a step at a time by another program (the Python package). The command
//! line is a contract: flags, defaults, help texts and exit statuses stay as they are.

mod bench;
mod compare;
mod cut;
pub mod exit;
mod generate;
mod render;
mod render_compare;
mod resume;
mod run;
mod session;
mod study;
mod view;

use std::ffi::OsString;
use std::path::Path;
use std::process::ExitCode;

use clap::error::ErrorKind;
use clap::{Args, Parser};

use crate::params::{Method, Mode, table};
use crate::scene::{self, Scene, SceneError};
use crate::text::short;

pub use bench::{BenchArgs, bench};
pub use cut::{CutArgs, cut};
pub use generate::{GenerateArgs, GeneratedKind, generate};
pub use render::{RenderArgs, render};
pub use run::{Progress, RunArgs, run};
pub use session::RunSession;
pub use study::{StudyArgs, study};
pub use view::{ViewArgs, view};

#[derive(Parser, Debug)]
#[command(
    name = "dda3d",
    version,
    about = "3-D Discontinuous Deformation Analysis of jointed rock (DDA-3a)"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: CliCommand,
}

#[derive(clap::Subcommand, Debug)]
pub enum CliCommand {
    /// Simulate a scene without any window or GPU; write blocks.csv, contacts.csv, summary.json.
    Run(RunArgs),
    /// Simulate headless and write PNG frames (and optionally an animated GIF) for reports.
    Render(RenderArgs),
    /// Write a generated scene file (for measuring cost as the model grows).
    Generate(GenerateArgs),
    /// Cut the scene's rock masses into blocks: write the scene with explicit [[blocks]] and
    /// print the blocks, volumes and slivers of each.
    Cut(CutArgs),
    /// Time the rockfall scene with both methods, and the scaling on generated walls.
    Bench(BenchArgs),
    /// Run a parameter study: a scene's keys varied over a grid or at random, the cases in
    /// parallel; write study.csv, study.json and plots of each outcome against each key.
    Study(StudyArgs),
    /// Open the interactive viewer (`dda3d SCENE.toml` is short for `dda3d view SCENE.toml`).
    View(ViewArgs),
}

/// Overrides of the scene's `[solver]` table, shared by the commands that simulate. The numbers
/// take a leading minus as a value (`--duration -1`), which [`load_scene`] then rejects with
/// the range of the parameter table, as in a scene file.
#[derive(Args, Debug, Clone, Default)]
pub struct SolverOverrides {
    /// Contact method: alm (DDA-3a) or penalty (DDA-3p).
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Time integration: dynamic or static.
    #[arg(long, value_enum)]
    pub mode: Option<Mode>,
    /// Numerical dissipation ρ∞ of the dynamic step, in [1/3, 1] (1: Shi's step).
    #[arg(long, allow_negative_numbers = true)]
    pub spectral_radius: Option<f64>,
    /// Simulated time, s.
    #[arg(long, allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Largest time step Δt_max, s (the scene's `max_time_step`).
    #[arg(long, allow_negative_numbers = true)]
    pub max_time_step: Option<f64>,
    /// Bring the model to rest under gravity before the run starts (the scene's
    /// `initial_equilibrium = true`).
    #[arg(long)]
    pub initial_equilibrium: bool,
    /// A block is still below this speed, m/s, and an island of still blocks sleeps (the
    /// scene's `sleep_velocity`; 0: no block sleeps).
    #[arg(long, allow_negative_numbers = true)]
    pub sleep_velocity: Option<f64>,
}

/// How a command failed, and with which exit status.
#[derive(Debug)]
pub enum CliError {
    /// Bad input: exit status 2.
    Input(String),
    /// The run failed: exit status 1 here; `main_entry` gets the finer status (diverged 1,
    /// I/O 74, other failures 70) from `run` and `render` themselves (see [`exit`]).
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

/// Loads a scene and applies the command-line overrides, which the parameter table checks as it
/// checks the scene file: a failure names the flag that set the value.
pub fn load_scene(path: &Path, o: &SolverOverrides) -> Result<Scene, CliError> {
    // Δt_max against the heaviest block is checked at parse, unless a flag changes what it
    // depends on: then once the flags are applied (below).
    let changed = o.max_time_step.is_some() || o.method.is_some() || o.mode.is_some();
    let mut s = if changed {
        scene::load_deferring_inertia_check(path)?
    } else {
        scene::load(path)?
    };
    if let Some(m) = o.method {
        s.params.method = m;
    }
    if let Some(m) = o.mode {
        s.params.mode = m;
    }
    if o.initial_equilibrium {
        s.params.initial_equilibrium = true;
    }
    if let Some(d) = o.duration
        && !(d.is_finite() && d > 0.0)
    {
        return Err(CliError::Input(format!(
            "--duration must be a positive number of seconds, got {}",
            short(d)
        )));
    }
    // (flag, key) of every number set from the command line.
    let mut set = Vec::new();
    let p = &mut s.params;
    for (flag, param, value, field) in [
        (
            "--spectral-radius",
            &table::SPECTRAL_RADIUS,
            o.spectral_radius,
            &mut p.spectral_radius,
        ),
        ("--duration", &table::DURATION, o.duration, &mut p.duration),
        (
            "--max-time-step",
            &table::MAX_TIME_STEP,
            o.max_time_step,
            &mut p.max_time_step,
        ),
        (
            "--sleep-velocity",
            &table::SLEEP_VELOCITY,
            o.sleep_velocity,
            &mut p.sleep_velocity,
        ),
    ] {
        if let Some(v) = value {
            *field = v;
            set.push((flag, param.key));
        }
    }
    s.params.check().map_err(|e| {
        // The scene file alone was valid, so a flag set one of the keys the failure concerns.
        let flag = e
            .keys
            .iter()
            .find_map(|k| set.iter().find(|(_, key)| key == k))
            .map_or_else(|| path.display().to_string(), |(f, _)| f.to_string());
        CliError::Input(format!("{flag}: {}", e.message))
    })?;
    // Δt_max against the heaviest block, where a flag changed what it depends on.
    if changed {
        crate::scene::check_inertia_scale(&s.model.blocks, &s.params).map_err(|m| {
            let flag = if o.max_time_step.is_some() {
                "--max-time-step".to_string()
            } else {
                path.display().to_string()
            };
            CliError::Input(format!("{flag}: {m}"))
        })?;
    }
    Ok(s)
}

/// Runs the subcommand the command line asked for.
pub fn dispatch(cli: &Cli) -> Result<(), CliError> {
    match &cli.command {
        CliCommand::Run(args) => run(args),
        CliCommand::Render(args) => render(args),
        CliCommand::Generate(args) => generate(args),
        CliCommand::Cut(args) => cut(args),
        CliCommand::Bench(args) => bench(args),
        CliCommand::Study(args) => study(args),
        CliCommand::View(args) => view(args),
    }
}

/// The whole binary: parses the process's arguments, runs the subcommand and reports a failure
/// as one line on stderr with its exit status ([`exit`] has the table). Call it first thing in
/// `main`, before any other thread starts (it may set an environment variable).
pub fn main_entry() -> ExitCode {
    exit::exit_on_failed_prints();
    quiet_mesa_runtime_dir();
    let cli = parse_command_line();
    // `run` and `render` say which kind of failure ended them. Of the others, `generate` can
    // only fail to write its file, the viewer's window or GPU can fail (a solver error stays in
    // the window), and `bench` fails when one of its runs does.
    let result = match &cli.command {
        CliCommand::Run(args) => run::execute(args),
        CliCommand::Render(args) => render::execute(args),
        CliCommand::Study(args) => study::execute(args),
        CliCommand::Generate(_) | CliCommand::Cut(_) => {
            dispatch(&cli).map_err(|e| exit::Failure::from_cli(e, exit::Failure::Io))
        }
        CliCommand::View(_) => {
            dispatch(&cli).map_err(|e| exit::Failure::from_cli(e, exit::Failure::Failed))
        }
        CliCommand::Bench(_) => dispatch(&cli).map_err(exit::Failure::from),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("{}", f.line());
            ExitCode::from(f.status().code())
        }
    }
}

/// The process's command line, parsed. A usage error is one line on stderr (clap's message,
/// its tip in brackets, without the usage block) and exit status 2, as is a first argument that
/// is no subcommand but a path (a scene file's name mistyped in `dda3d SCENE.toml`); `--help`
/// and `--version` print as clap prints them, and a failure to print them is an I/O error
/// (status 74), as it is for every other command.
fn parse_command_line() -> Cli {
    let args = expand_scene_shorthand(std::env::args_os().collect());
    match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        Err(e) if e.kind() == ErrorKind::InvalidSubcommand => {
            let line = args.get(1).and_then(|a| not_a_scene(a));
            let line = line.unwrap_or_else(|| one_line_usage_error(&e.render().to_string()));
            eprintln!("{line}");
            std::process::exit(e.exit_code());
        }
        Err(e)
            if e.use_stderr()
                && e.kind() != ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand =>
        {
            eprintln!("{}", one_line_usage_error(&e.render().to_string()));
            std::process::exit(e.exit_code());
        }
        Err(e) => print_help_or_version(&e),
    }
}

/// Prints clap's help or version text and exits with clap's status; where the stream cannot
/// be written (`dda3d --help > /dev/full`), exits with [`exit::Status::Io`] and the line the
/// other commands give (clap's own `exit` ignores the failure and exits 0).
fn print_help_or_version(e: &clap::Error) -> ! {
    use std::io::Write;
    let (stream, printed) = if e.use_stderr() {
        ("stderr", e.print().and_then(|()| std::io::stderr().flush()))
    } else {
        ("stdout", e.print().and_then(|()| std::io::stdout().flush()))
    };
    if let Err(w) = printed {
        let _ = writeln!(std::io::stderr(), "error: failed printing to {stream}: {w}");
        std::process::exit(i32::from(exit::Status::Io.code()));
    }
    std::process::exit(e.exit_code());
}

/// The error for a first argument that is no subcommand but looks like a path (a `/` or a `.`
/// in it): a scene file whose name was mistyped in the shorthand `dda3d SCENE.toml`, which
/// clap called an unrecognized subcommand. None for anything else.
fn not_a_scene(arg: &std::ffi::OsStr) -> Option<String> {
    let text = arg.to_string_lossy();
    if !(text.contains('/') || text.contains('.')) {
        return None;
    }
    Some(match std::fs::metadata(arg) {
        Err(_) => format!("error: {text}: no such scene file"),
        Ok(m) if !m.is_file() => format!("error: {text}: not a file"),
        Ok(_) => format!(
            "error: {text}: not a scene file (a scene file's name ends in .toml; `dda3d view \
             {text}` opens it as one)"
        ),
    })
}

/// clap's rendered error as one line: the lines before `Usage:`, joined, with a `tip:` in
/// brackets.
fn one_line_usage_error(rendered: &str) -> String {
    let mut line = String::new();
    for part in rendered
        .lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .filter(|l| !l.is_empty())
    {
        if line.is_empty() {
            line = part.to_string();
        } else if part.starts_with("tip:") {
            line += &format!(" ({part})");
        } else {
            line += &format!(" {part}");
        }
    }
    line
}

/// Mesa's drivers warn on every start when XDG_RUNTIME_DIR is unset (common over SSH and in CI);
/// points it at a private temporary directory before any thread or GPU library starts.
fn quiet_mesa_runtime_dir() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        let dir = std::env::temp_dir().join("dda3d-xdg-runtime");
        if std::fs::create_dir_all(&dir).is_ok() {
            // SAFETY: called from `main_entry` before any other thread exists; nothing reads the
            // environment concurrently.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}

/// `dda3d SCENE.toml` is short for `dda3d view SCENE.toml`.
fn expand_scene_shorthand(mut args: Vec<OsString>) -> Vec<OsString> {
    if args
        .get(1)
        .is_some_and(|a| a.to_string_lossy().ends_with(".toml"))
    {
        args.insert(1, "view".into());
    }
    args
}
