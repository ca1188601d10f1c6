//! The exit statuses of `dda3d`, in one place, and the signals that end a run early.
//!
//! | status | meaning | `summary.json` `status` |
//! |---|---|---|
//! | 0 | the command completed | `completed` |
//! | 1 | the run diverged: a NaN, a runaway penetration at the smallest Δt, or the energy watchdog; everything written up to then is kept | `diverged` |
//! | 2 | bad input or usage: the scene file, a flag, or no GPU adapter for `render` / `view` | none written |
//! | 70 | a failure that is neither the run nor its input nor a file: the GPU device, the window, a worker thread | — |
//! | 74 | an I/O error (sysexits' `EX_IOERR`): the output directory cannot be created, or a write fails (disk full; stdout or stderr included); complete rows are kept | `io_error` |
//! | 101 | a bug (a Rust panic); the last checkpoint stays | `running` |
//! | 130 | SIGINT (Ctrl-C): the step in progress was finished and everything written | `interrupted` |
//! | 143 | SIGTERM: as SIGINT | `interrupted` |
//!
//! 130 and 143 are 128 + the signal's number, what a shell reports for a process the signal
//! killed, so a script sees the same status whether dda3d stopped cleanly or was killed. A second
//! SIGINT or SIGTERM while the first is being handled exits at once with the same status,
//! leaving the outputs as of the last checkpoint (`"status": "running"`).

use std::io::Write;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use signal_hook::consts::signal::{SIGINT, SIGTERM};

use super::CliError;

/// An exit status of `dda3d` (the table in the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Completed,
    Diverged,
    BadInput,
    /// The GPU device, the window or a worker thread failed.
    Failed,
    Io,
    Interrupted(Signal),
}

impl Status {
    pub const fn code(self) -> u8 {
        match self {
            Status::Completed => 0,
            Status::Diverged => 1,
            Status::BadInput => 2,
            Status::Failed => 70,
            Status::Io => 74,
            Status::Interrupted(s) => s.code(),
        }
    }
}

/// Makes a failed write to stdout or stderr an I/O error: `println!` and `eprintln!` panic when
/// the stream cannot be written (`cut SCENE > /dev/full`, a closed pipe, stderr on a full
/// disk), and such a panic now ends the process with [`Status::Io`] and one line on stderr,
/// where stderr still takes it, instead of a bug's report and status 101. Every other panic
/// keeps Rust's report. Set once, first thing in `main`.
pub fn exit_on_failed_prints() {
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info.payload_as_str().unwrap_or("");
        if message.starts_with("failed printing to std") {
            let _ = writeln!(std::io::stderr(), "error: {message}");
            std::process::exit(i32::from(Status::Io.code()));
        }
        report(info);
    }));
}

/// A signal that asks a run to stop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signal {
    Int,
    Term,
}

impl Signal {
    pub const fn name(self) -> &'static str {
        match self {
            Signal::Int => "SIGINT",
            Signal::Term => "SIGTERM",
        }
    }

    /// 128 + the signal number, as a shell reports a process the signal killed.
    pub const fn code(self) -> u8 {
        match self {
            Signal::Int => 130,
            Signal::Term => 143,
        }
    }

    fn number(self) -> i32 {
        match self {
            Signal::Int => SIGINT,
            Signal::Term => SIGTERM,
        }
    }
}

/// How a command failed. Each kind has its exit status; the message is one line.
#[derive(Clone, Debug)]
pub enum Failure {
    Input(String),
    Diverged(String),
    Io(String),
    /// Neither the run nor its input nor a file (exit status 70).
    Failed(String),
    Interrupted(Signal, String),
}

impl Failure {
    pub fn status(&self) -> Status {
        match self {
            Failure::Input(_) => Status::BadInput,
            Failure::Diverged(_) => Status::Diverged,
            Failure::Io(_) => Status::Io,
            Failure::Failed(_) => Status::Failed,
            Failure::Interrupted(s, _) => Status::Interrupted(*s),
        }
    }

    pub fn message(&self) -> &str {
        match self {
            Failure::Input(m)
            | Failure::Diverged(m)
            | Failure::Io(m)
            | Failure::Failed(m)
            | Failure::Interrupted(_, m) => m,
        }
    }

    /// The line for stderr: an interruption was asked for, so it is not called an error.
    pub fn line(&self) -> String {
        match self {
            Failure::Interrupted(..) => format!("interrupted: {}", self.message()),
            _ => format!("error: {}", self.message()),
        }
    }

    /// A [`CliError`] of a command that does not say more: bad input stays bad input, and its
    /// `Run` failure becomes what `run_failure` says that command's failures are.
    pub fn from_cli(e: CliError, run_failure: fn(String) -> Failure) -> Failure {
        match e {
            CliError::Input(m) => Failure::Input(m),
            CliError::Run(m) => run_failure(m),
        }
    }
}

impl From<CliError> for Failure {
    fn from(e: CliError) -> Self {
        Failure::from_cli(e, Failure::Diverged)
    }
}

/// For the library's [`run`](super::run())/[`render`](super::render()), whose `CliError` has
/// only two kinds: anything but bad input is a failed run.
impl From<Failure> for CliError {
    fn from(f: Failure) -> Self {
        match f {
            Failure::Input(m) => CliError::Input(m),
            other => CliError::Run(other.message().to_string()),
        }
    }
}

/// The last stop signal received (its number), 0 for none. Statics, because signal handlers
/// can only reach memory that lives for the whole process.
static RECEIVED: AtomicUsize = AtomicUsize::new(0);
/// Set by the first stop signal, so a second one exits at once.
static ARMED: AtomicBool = AtomicBool::new(false);
static INSTALLED: OnceLock<Result<(), String>> = OnceLock::new();

/// From now on SIGINT and SIGTERM only raise a flag that the run checks between steps
/// ([`interrupted`]); a second one exits at once with its status. Installed once per process
/// (signal-hook cannot restore the default action afterwards, so it is never removed).
pub fn catch_stop_signals() -> Result<(), Failure> {
    INSTALLED
        .get_or_init(|| {
            for s in [Signal::Int, Signal::Term] {
                let n = s.number();
                // The shutdown goes first: signal-hook runs actions in order, so it sees ARMED
                // as the previous signal left it.
                signal_hook::flag::register_conditional_shutdown(n, s.code().into(), &ARMED)
                    .and_then(|_| signal_hook::flag::register(n, &ARMED))
                    .and_then(|_| signal_hook::flag::register_usize(n, &RECEIVED, n as usize))
                    .map_err(|e| format!("cannot catch {}: {e}", s.name()))?;
            }
            Ok(())
        })
        .clone()
        .map_err(Failure::Failed)
}

/// The stop signal received since [`catch_stop_signals`], if any.
pub fn interrupted() -> Option<Signal> {
    match RECEIVED.load(Ordering::SeqCst) {
        0 => None,
        n if n == SIGINT as usize => Some(Signal::Int),
        _ => Some(Signal::Term),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statuses_are_distinct_and_signals_follow_the_shell() {
        let all = [
            Status::Completed,
            Status::Diverged,
            Status::BadInput,
            Status::Failed,
            Status::Io,
            Status::Interrupted(Signal::Int),
            Status::Interrupted(Signal::Term),
        ];
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                assert_ne!(a.code(), b.code(), "{a:?} and {b:?}");
            }
        }
        for s in [Signal::Int, Signal::Term] {
            assert_eq!(i32::from(s.code()), 128 + s.number());
        }
    }
}
