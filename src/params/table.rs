//! One entry per scene-file key of [`SolverParams`]: its label, unit, valid range and why it ends
//! where it does, the range of the viewer's widget, default and description. The entries live in
//! [`solver_keys`] (`[solver]`) and [`contact_keys`] (`[solver.contact]`, `[joint]`); [`ALL`]
//! lists them in the scene file's order.
//!
//! [`SolverParams::validate`] checks the ranges and the number of steps a run takes
//! ([`MAX_STEPS`]), for the scene file and the command line alike; the viewer's panel takes its
//! slider ranges, labels and tooltips from here; [`markdown_rows`] writes the README's scene
//! table rows and [`markdown_limits`] its input limits. The tests of [`crate::params`] check the
//! table against the structs (a key for every field, the same defaults) and the README.

use std::ops::RangeInclusive;

use super::{SolverParams, step_rules};
use crate::text::short;

pub mod contact_keys;
pub mod solver_keys;
pub mod text;

pub use contact_keys::*;
pub use solver_keys::*;
pub use text::{FromText, assign};

/// A value of any kind of tunable, as read from [`SolverParams`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Real(f64),
    Count(u32),
    Vector([f64; 3]),
    Flag(bool),
    /// An enum, as its scene-file spelling.
    Choice(&'static str),
}

/// One end of an [`Interval`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    Unbounded,
    /// The end itself is excluded.
    Open(f64),
    /// The end itself is allowed.
    Closed(f64),
}

/// The values a number may take.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: Bound,
    pub hi: Bound,
}

impl Interval {
    /// Any value (finite, for a real number).
    pub const ANY: Interval = Interval::new(Bound::Unbounded, Bound::Unbounded);
    pub const POSITIVE: Interval = Interval::new(Bound::Open(0.0), Bound::Unbounded);
    pub const NON_NEGATIVE: Interval = Interval::new(Bound::Closed(0.0), Bound::Unbounded);

    pub const fn new(lo: Bound, hi: Bound) -> Interval {
        Interval { lo, hi }
    }

    pub fn contains(&self, v: f64) -> bool {
        let above = match self.lo {
            Bound::Unbounded => true,
            Bound::Open(lo) => v > lo,
            Bound::Closed(lo) => v >= lo,
        };
        let below = match self.hi {
            Bound::Unbounded => true,
            Bound::Open(hi) => v < hi,
            Bound::Closed(hi) => v <= hi,
        };
        above && below
    }

    /// What a value must do to lie in the interval, for messages, with the unit's suffix:
    /// "be positive", "lie in (0, 1)", "lie in [1e-7, 1] s".
    fn requirement(&self, suffix: &str) -> String {
        match (self.lo, self.hi) {
            (Bound::Unbounded, Bound::Unbounded) => "be a number".into(),
            (Bound::Open(0.0), Bound::Unbounded) => "be positive".into(),
            (Bound::Closed(0.0), Bound::Unbounded) => "not be negative".into(),
            (Bound::Open(lo), Bound::Unbounded) => format!("be > {}{suffix}", bound_text(lo)),
            (Bound::Closed(lo), Bound::Unbounded) => {
                format!("be at least {}{suffix}", bound_text(lo))
            }
            _ => format!("lie in {}{suffix}", self.text()),
        }
    }

    /// The interval in mathematical notation: `[1e-7, 1]`, `(0, 1)`, `[1, ∞)`.
    pub fn text(&self) -> String {
        let (open, lo) = match self.lo {
            Bound::Unbounded => ("(", "-∞".to_owned()),
            Bound::Open(v) => ("(", bound_text(v)),
            Bound::Closed(v) => ("[", bound_text(v)),
        };
        let (hi, close) = match self.hi {
            Bound::Unbounded => ("∞".to_owned(), ")"),
            Bound::Open(v) => (bound_text(v), ")"),
            Bound::Closed(v) => (bound_text(v), "]"),
        };
        format!("{open}{lo}, {hi}{close}")
    }
}

/// A bound as messages print it: short (`1e-7`, not `0.0000001`), except ⅓, whose four digits
/// (0.3333) would look like a value that lies outside it.
fn bound_text(x: f64) -> String {
    if x == 1.0 / 3.0 {
        "1/3".into()
    } else {
        short(x)
    }
}

/// The range of the viewer's widget for a number: often narrower than the valid range (a slider
/// cannot span 0 to ∞), and for a penalty relative to the model's E.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WidgetRange {
    Absolute(f64, f64),
    /// Multiples of E (the smallest Young's modulus of the scene).
    TimesYoung(f64, f64),
}

/// How the viewer's panel edits a number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Widget {
    pub range: WidgetRange,
    /// A slider over decades (for values that span orders of magnitude).
    pub logarithmic: bool,
}

/// One tunable: a scene-file key and everything said about it.
pub struct Param {
    /// The key with its table, as in messages: `solver.contact.beta`.
    pub key: &'static str,
    /// The symbol or short name the panel shows.
    pub label: &'static str,
    /// Unit as written after a number ("" for a pure number).
    pub unit: &'static str,
    /// The description; `{DT_CUT}`, `{DT_GROWTH}` and `{SETTLE_PERCENT}` stand for the
    /// [`step_rules`] (see [`Param::doc`]).
    doc: &'static str,
    pub default: Value,
    pub get: fn(&SolverParams) -> Value,
    /// Sets the key from text (`2e9`, `true`, `penalty`, `[0, 0, -9.8]`; see [`text`]): an
    /// error says what kind of value was expected. The range is not checked here: that is
    /// [`SolverParams::check`]'s, as for the scene file.
    pub set: fn(&mut SolverParams, &str) -> Result<(), String>,
    /// The values [`SolverParams::validate`] accepts, for numbers.
    pub valid: Interval,
    /// Why the valid range ends where it does, for a range narrower than the sign alone ("" for
    /// none): the end of the description, the viewer's tooltip and the README's input limits.
    pub valid_why: &'static str,
    /// The panel's widget, for numbers it edits with a slider or drag value.
    pub widget: Option<Widget>,
}

/// A key is its entry: shown and compared by its key alone (the entry holds functions).
impl std::fmt::Debug for Param {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("Param").field(&self.key).finish()
    }
}

impl PartialEq for Param {
    fn eq(&self, other: &Self) -> bool {
        self.key == other.key
    }
}

impl Param {
    /// The scene-file key without its table: `beta`.
    pub fn name(&self) -> &'static str {
        self.key.rsplit('.').next().unwrap_or(self.key)
    }

    /// Whether `name` names this key: its scene-file name (`eps1`), the key with its table
    /// (`solver.contact.eps1`), or the name with dashes as a flag writes it
    /// (`max-time-step`).
    pub fn is_named(&self, name: &str) -> bool {
        let name = name.replace('-', "_");
        name == self.name() || name == self.key
    }

    /// The value as text that [`Param::set`] reads back to the same value: numbers in their
    /// short form where that is exact (`2e9`, `0.01`), else in full.
    pub fn text(&self, params: &SolverParams) -> String {
        let real = |x: f64| {
            let s = short(x);
            if s.parse() == Ok(x) {
                s
            } else {
                format!("{x:e}")
            }
        };
        match (self.get)(params) {
            Value::Real(x) => real(x),
            Value::Count(n) => n.to_string(),
            Value::Vector(v) => format!("[{}]", v.map(real).join(", ")),
            Value::Flag(b) => b.to_string(),
            Value::Choice(s) => s.to_owned(),
        }
    }

    /// The scene-file table that holds the key: `solver.contact`.
    pub fn table(&self) -> &'static str {
        self.key.rsplit_once('.').map_or("", |(t, _)| t)
    }

    /// The description, with the step-control rules written out from [`step_rules`], and the
    /// valid range with its reason where it has one.
    pub fn doc(&self) -> String {
        let doc = self
            .doc
            .replace("{DT_CUT}", &step_rules::DT_CUT.to_string())
            .replace("{DT_GROWTH}", &step_rules::DT_GROWTH.to_string())
            .replace(
                "{SETTLE_PERCENT}",
                &(step_rules::SETTLE_FRACTION * 100.0).to_string(),
            );
        if self.valid_why.is_empty() {
            doc
        } else {
            format!("{doc}\nValid: {}: {}", self.valid_range(), self.valid_why)
        }
    }

    /// The valid range with its unit, as the README's input limits write it: `[1e-7, 1] s`.
    pub fn valid_range(&self) -> String {
        format!("{}{}", self.valid.text(), self.suffix())
    }

    /// The first sentence of the description (the README's "meaning" column).
    pub fn summary(&self) -> String {
        let doc = self.doc();
        let end = [doc.find(". "), doc.find('\n')]
            .into_iter()
            .flatten()
            .min()
            .unwrap_or(doc.len());
        doc[..end].trim_end_matches('.').to_owned()
    }

    /// The unit as a suffix of a shown number: " N/m", "°", or "".
    pub fn suffix(&self) -> String {
        match self.unit {
            "" | "°" => self.unit.to_owned(),
            unit => format!(" {unit}"),
        }
    }

    /// The range of the panel's widget, in the parameter's unit; E is the model's Young's modulus.
    /// Panics for a parameter the panel does not edit with a number widget (a programming error).
    pub fn widget_range(&self, young: f64) -> RangeInclusive<f64> {
        match self.widget.map(|w| w.range) {
            Some(WidgetRange::Absolute(lo, hi)) => lo..=hi,
            Some(WidgetRange::TimesYoung(lo, hi)) => young * lo..=young * hi,
            None => panic!("{} has no widget range", self.key),
        }
    }

    /// Whether the panel's slider is logarithmic.
    pub fn logarithmic(&self) -> bool {
        self.widget.is_some_and(|w| w.logarithmic)
    }

    /// An error when a real number of this key is NaN or infinite.
    pub fn check_finite(&self, params: &SolverParams) -> Result<(), String> {
        let bad = match (self.get)(params) {
            Value::Real(v) => Some(v).filter(|v| !v.is_finite()),
            Value::Vector(v) => v.into_iter().find(|v| !v.is_finite()),
            Value::Count(_) | Value::Flag(_) | Value::Choice(_) => None,
        };
        match bad {
            Some(v) => Err(format!(
                "{} must be a finite number, got {}",
                self.key,
                short(v)
            )),
            None => Ok(()),
        }
    }

    /// An error when a number of this key lies outside [`Param::valid`].
    pub fn check_range(&self, params: &SolverParams) -> Result<(), String> {
        let (v, mut shown) = match (self.get)(params) {
            Value::Real(v) => (v, short(v)),
            Value::Count(n) => (f64::from(n), n.to_string()),
            // A vector's range is that of its magnitude.
            Value::Vector(x) => {
                // Scaled, so that 1e300 does not square to infinity.
                let big = x.iter().fold(0.0f64, |m, c| m.max(c.abs()));
                let norm = if big > 0.0 {
                    big * x.iter().map(|c| (c / big).powi(2)).sum::<f64>().sqrt()
                } else {
                    0.0
                };
                if self.valid.contains(norm) {
                    return Ok(());
                }
                return Err(format!(
                    "{}'s magnitude must {}, got {}{}",
                    self.key,
                    self.valid.requirement(&self.suffix()),
                    short(norm),
                    self.suffix()
                ));
            }
            Value::Flag(_) | Value::Choice(_) => return Ok(()),
        };
        if self.valid.contains(v) {
            return Ok(());
        }
        // Short, unless rounding to four digits would show a value inside the range or on one
        // of its ends (1.000000001 as 1, for a range that ends at 1).
        let ends = [self.valid.lo, self.valid.hi].map(|b| match b {
            Bound::Open(x) | Bound::Closed(x) => x,
            Bound::Unbounded => f64::NAN,
        });
        if shown
            .parse()
            .is_ok_and(|r: f64| r != v && (self.valid.contains(r) || ends.contains(&r)))
        {
            shown = format!("{v:?}");
        }
        Err(format!(
            "{} must {}, got {shown}{}",
            self.key,
            self.valid.requirement(&self.suffix()),
            self.suffix()
        ))
    }
}

/// The most steps a run may take: `duration / max_time_step` (before any cut of Δt) at most
/// this. At the paper's Δt_max = 0.01 s that is 10⁵ s of simulated time; a single block steps
/// some 10⁴–10⁵ times a second and writes a row per block per step to blocks.csv, so a run of
/// 10⁷ steps already takes minutes to hours and gigabytes of output. Beyond it a run that only
/// looks finished would never end (`--duration 1e308`, Δt_max = 1e-15 writing 18 MB/s of CSV).
pub const MAX_STEPS: f64 = 1e7;

/// An error when a run of `duration` at `max_time_step` would take more than [`MAX_STEPS`]
/// steps.
pub fn check_steps(params: &SolverParams) -> Result<(), String> {
    let steps = params.duration / params.max_time_step;
    if steps <= MAX_STEPS {
        return Ok(());
    }
    Err(format!(
        "{} = {} s at {} = {} s takes {} steps, more than the limit of {} (shorten the run or \
         lengthen the step)",
        DURATION.key,
        short(params.duration),
        MAX_TIME_STEP.key,
        short(params.max_time_step),
        short(steps.ceil()),
        short(MAX_STEPS)
    ))
}

/// The README's input-limit rows of every key whose valid range has a reason
/// (`| key | valid | why |`).
pub fn markdown_limits() -> String {
    let mut rows = String::new();
    for p in ALL.iter().filter(|p| !p.valid_why.is_empty()) {
        rows += &format!(
            "| `{}` | {} | {} |\n",
            p.key,
            p.valid_range(),
            p.valid_why.replace('|', "\\|")
        );
    }
    rows
}

/// The README's scene-table rows of every key, in the README's format
/// (`| table | key | default | meaning |`): the default with its unit, and the first sentence of
/// the description.
pub fn markdown_rows() -> String {
    let mut rows = String::new();
    let mut last_table = "";
    for p in ALL {
        let table = if p.table() == last_table {
            " ".to_owned()
        } else {
            format!(" `[{}]` ", p.table())
        };
        last_table = p.table();
        rows += &format!(
            "|{table}| `{}` | {}{} | {} |\n",
            p.name(),
            markdown_value(p.default),
            p.suffix(),
            // A '|' of |d_n| would end the cell.
            p.summary().replace('|', "\\|")
        );
    }
    rows
}

fn markdown_value(v: Value) -> String {
    let real = |x: f64| {
        if x != 0.0 && !(1e-3..1e4).contains(&x.abs()) {
            format!("{x:e}")
        } else {
            format!("{x:?}")
        }
    };
    match v {
        Value::Real(x) => real(x),
        Value::Count(n) => n.to_string(),
        Value::Vector(v) => format!("[{}]", v.map(real).join(", ")),
        Value::Flag(b) => b.to_string(),
        Value::Choice(s) => format!("`\"{s}\"`"),
    }
}

const fn absolute(lo: f64, hi: f64, logarithmic: bool) -> Option<Widget> {
    Some(Widget {
        range: WidgetRange::Absolute(lo, hi),
        logarithmic,
    })
}

/// The entry `name` names (see [`Param::is_named`]).
pub fn find(name: &str) -> Option<&'static Param> {
    ALL.iter().copied().find(|p| p.is_named(name))
}

/// Every key, in the scene file's order (`[solver]`, `[solver.contact]`, `[joint]`).
pub const ALL: [&Param; 30] = [
    &METHOD,
    &MODE,
    &SPECTRAL_RADIUS,
    &DURATION,
    &MAX_TIME_STEP,
    &MAX_DISPLACEMENT_RATIO,
    &GRAVITY,
    &FIXED_SPRING_FACTOR,
    &MAX_DISPLACEMENT_OVERSHOOT,
    &ROTATE_STRESS,
    &INITIAL_EQUILIBRIUM,
    &EQUILIBRIUM_TOLERANCE,
    &EQUILIBRIUM_MAX_STEPS,
    &SLEEP_VELOCITY,
    &SLEEP_TIME,
    &INITIAL_PENALTY,
    &ALPHA,
    &BETA,
    &GAMMA,
    &EPS1,
    &EPS2,
    &PENALTY_FLOOR,
    &SHEAR_PENALTY_RATIO,
    &MAX_ALM_ITERATIONS,
    &MAX_OPEN_CLOSE_ITERATIONS,
    &WARM_START,
    &CLOSE_THRESHOLD,
    &OPEN_THRESHOLD,
    &FRICTION_ANGLE,
    &COHESION,
];
