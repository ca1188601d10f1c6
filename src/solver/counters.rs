//! What the solver counts and times, kept apart from the maths (as rapier's `counters`): a
//! stopwatch, the counters of the step in progress, and the `DDA3D_DEBUG` switch. The totals
//! themselves ([`RunTotals`], [`crate::snapshot::Timings`]) are plain data in the snapshot module,
//! since `summary.json` and the benchmark read them.

use std::time::{Duration, Instant};

use crate::snapshot::RunTotals;

/// Measures one phase of the solver.
pub(crate) struct Stopwatch(Instant);

impl Stopwatch {
    pub fn start() -> Self {
        Stopwatch(Instant::now())
    }

    pub fn elapsed(&self) -> Duration {
        self.0.elapsed()
    }

    pub fn seconds(&self) -> f64 {
        self.0.elapsed().as_secs_f64()
    }
}

/// The counters of the step in progress, and the run's totals they add to.
pub(crate) struct Counters<'a> {
    pub totals: &'a mut RunTotals,
    /// Numeric factorizations in this step, all attempts.
    pub factorizations: u32,
    /// Time spent assembling and checking, added to `totals.timings.assembly` by
    /// [`Counters::flush`].
    pub assembly: Duration,
}

impl<'a> Counters<'a> {
    pub fn new(totals: &'a mut RunTotals) -> Self {
        Counters {
            totals,
            factorizations: 0,
            assembly: Duration::ZERO,
        }
    }

    /// Adds the accumulated assembly time to the totals.
    pub fn flush(&mut self) {
        self.totals.timings.assembly += self.assembly.as_secs_f64();
        self.assembly = Duration::ZERO;
    }
}

/// `DDA3D_DEBUG=1` logs every state change and every Δt cut to stderr (for tuning).
pub(crate) fn debug_log() -> bool {
    static ON: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ON.get_or_init(|| std::env::var_os("DDA3D_DEBUG").is_some_and(|v| v != "0"))
}
