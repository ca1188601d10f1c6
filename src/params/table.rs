//! One entry per scene-file key of [`SolverParams`]: its label, unit, valid range, the range of
//! the viewer's widget, default and description.
//!
//! [`SolverParams::validate`] checks the ranges, the viewer's panel takes its slider ranges,
//! labels and tooltips from here, and [`markdown_rows`] writes the README's scene table rows. The
//! tests of [`crate::params`] check the table against the structs: a key for every field, the
//! same defaults.

use std::ops::RangeInclusive;

use super::{SolverParams, step_rules};

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

    /// What a value must do to lie in the interval, for messages: "be positive", "lie in (0, 1)".
    fn requirement(&self) -> String {
        match (self.lo, self.hi) {
            (Bound::Unbounded, Bound::Unbounded) => "be a number".into(),
            (Bound::Open(0.0), Bound::Unbounded) => "be positive".into(),
            (Bound::Closed(0.0), Bound::Unbounded) => "not be negative".into(),
            (Bound::Open(lo), Bound::Unbounded) => format!("be > {lo}"),
            (Bound::Closed(lo), Bound::Unbounded) => format!("be at least {lo}"),
            (lo, hi) => {
                let (open, lo) = match lo {
                    Bound::Unbounded => ("(", "-∞".to_owned()),
                    Bound::Open(v) => ("(", v.to_string()),
                    Bound::Closed(v) => ("[", v.to_string()),
                };
                let (hi, close) = match hi {
                    Bound::Unbounded => ("∞".to_owned(), ")"),
                    Bound::Open(v) => (v.to_string(), ")"),
                    Bound::Closed(v) => (v.to_string(), "]"),
                };
                format!("lie in {open}{lo}, {hi}{close}")
            }
        }
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
    /// The values [`SolverParams::validate`] accepts, for numbers.
    pub valid: Interval,
    /// The panel's widget, for numbers it edits with a slider or drag value.
    pub widget: Option<Widget>,
}

impl Param {
    /// The scene-file key without its table: `beta`.
    pub fn name(&self) -> &'static str {
        self.key.rsplit('.').next().unwrap_or(self.key)
    }

    /// The scene-file table that holds the key: `solver.contact`.
    pub fn table(&self) -> &'static str {
        self.key.rsplit_once('.').map_or("", |(t, _)| t)
    }

    /// The description, with the step-control rules written out from [`step_rules`].
    pub fn doc(&self) -> String {
        self.doc
            .replace("{DT_CUT}", &step_rules::DT_CUT.to_string())
            .replace("{DT_GROWTH}", &step_rules::DT_GROWTH.to_string())
            .replace(
                "{SETTLE_PERCENT}",
                &(step_rules::SETTLE_FRACTION * 100.0).to_string(),
            )
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
            Some(v) => Err(format!("{} must be a finite number, got {v}", self.key)),
            None => Ok(()),
        }
    }

    /// An error when a number of this key lies outside [`Param::valid`].
    pub fn check_range(&self, params: &SolverParams) -> Result<(), String> {
        let v = match (self.get)(params) {
            Value::Real(v) => v,
            Value::Count(n) => f64::from(n),
            Value::Vector(_) | Value::Flag(_) | Value::Choice(_) => return Ok(()),
        };
        if self.valid.contains(v) {
            Ok(())
        } else {
            Err(format!(
                "{} must {}, got {v}{}",
                self.key,
                self.valid.requirement(),
                self.suffix()
            ))
        }
    }
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

pub const METHOD: Param = Param {
    key: "solver.method",
    label: "Method",
    unit: "",
    doc: "How normal contacts are enforced.\n\
          DDA-3a: augmented Lagrangian — multipliers λ absorb the contact force, so penetration \
          falls below ε1·d_n,max without a huge penalty; p_n grows only where convergence is \
          slow (P21).\n\
          DDA-3p: classic fixed penalty p_n = p_n,1; penetration ≈ N / p_n.",
    default: Value::Choice("alm"),
    get: |p| Value::Choice(p.method.as_str()),
    valid: Interval::ANY,
    widget: None,
};

pub const MODE: Param = Param {
    key: "solver.mode",
    label: "Mode",
    unit: "",
    doc: "Dynamic: velocities carry over between steps.\n\
          Static: velocities reset to zero every step, so the system creeps into equilibrium \
          (for stability checks).",
    default: Value::Choice("dynamic"),
    get: |p| Value::Choice(p.mode.as_str()),
    valid: Interval::ANY,
    widget: None,
};

pub const SPECTRAL_RADIUS: Param = Param {
    key: "solver.spectral_radius",
    label: "ρ∞",
    unit: "",
    doc: "Numerical dissipation of the dynamic step: the fraction of a mode far too stiff for Δt \
          (contact and fixed-point springs) that survives one step.\n\
          1 is Shi's step (3.2), which leaves those modes ringing: contact forces alternate step \
          by step for as long as a run lasts. Lower values damp them (⅓ is the strongest); slow \
          modes keep Shi's damping (Newmark γ = 1, β = (1 + 3ρ∞)/(2(1 + ρ∞)²)). Static mode \
          ignores it.",
    default: Value::Real(0.5),
    get: |p| Value::Real(p.spectral_radius),
    valid: Interval::new(Bound::Closed(1.0 / 3.0), Bound::Closed(1.0)),
    widget: absolute(1.0 / 3.0, 1.0, false),
};

pub const DURATION: Param = Param {
    key: "solver.duration",
    label: "End time",
    unit: "s",
    doc: "Simulated time to run. The viewer pauses when simulated time reaches it; Play \
          continues past it.",
    default: Value::Real(2.0),
    get: |p| Value::Real(p.duration),
    valid: Interval::POSITIVE,
    widget: absolute(1e-3, 1e6, false),
};

pub const MAX_TIME_STEP: Param = Param {
    key: "solver.max_time_step",
    label: "Δt_max",
    unit: "s",
    doc: "Largest time step. Steps start at Δt_max, are cut when a step moves too far or \
          open–close does not converge, and grow back by ≤ {DT_GROWTH}× per step. Paper: 0.01 s.",
    default: Value::Real(0.01),
    get: |p| Value::Real(p.max_time_step),
    valid: Interval::POSITIVE,
    widget: absolute(1e-5, 0.1, true),
};

pub const MAX_DISPLACEMENT_RATIO: Param = Param {
    key: "solver.max_displacement_ratio",
    label: "δ",
    unit: "",
    doc: "Maximum displacement ratio: the largest vertex displacement allowed in one step, as a \
          fraction of w0 (half the model's largest extent). A step that moves further is redone \
          with a smaller Δt. It also sets d_n,max = 2·δ·w0 (P22). Paper: 0.01.",
    default: Value::Real(0.01),
    get: |p| Value::Real(p.max_displacement_ratio),
    valid: Interval::POSITIVE,
    widget: absolute(1e-4, 0.1, true),
};

pub const GRAVITY: Param = Param {
    key: "solver.gravity",
    label: "g",
    unit: "m/s²",
    doc: "Gravity; z is up.",
    default: Value::Vector([0.0, 0.0, -9.8]),
    get: |p| Value::Vector(p.gravity),
    valid: Interval::ANY,
    widget: None,
};

pub const FIXED_SPRING_FACTOR: Param = Param {
    key: "solver.fixed_spring_factor",
    label: "Fixed springs",
    unit: "E",
    doc: "Stiffness of the vertex springs of fixed blocks, as a multiple of the block's E (the \
          paper uses 100 E).",
    default: Value::Real(100.0),
    get: |p| Value::Real(p.fixed_spring_factor),
    valid: Interval::POSITIVE,
    widget: None,
};

pub const MAX_DISPLACEMENT_OVERSHOOT: Param = Param {
    key: "solver.max_displacement_overshoot",
    label: "Overshoot",
    unit: "",
    doc: "A step is redone with a smaller Δt when its largest vertex displacement exceeds this \
          × δ·w0. 1 keeps every step within δ·w0, which is what the bound d_n,max = 2·δ·w0 of \
          (P22) assumes.",
    default: Value::Real(1.0),
    get: |p| Value::Real(p.max_displacement_overshoot),
    valid: Interval::new(Bound::Closed(1.0), Bound::Unbounded),
    widget: None,
};

pub const ROTATE_STRESS: Param = Param {
    key: "solver.rotate_stress",
    label: "Rotate stress",
    unit: "",
    doc: "Rotate the carried stress with the block (objective update, reference §1.3). Classic \
          DDA does not.",
    default: Value::Flag(false),
    get: |p| Value::Flag(p.rotate_stress),
    valid: Interval::ANY,
    widget: None,
};

pub const INITIAL_EQUILIBRIUM: Param = Param {
    key: "solver.initial_equilibrium",
    label: "Initial equilibrium",
    unit: "",
    doc: "Before the run, bring the model to rest under gravity with static steps, then start at \
          t = 0 with the contact forces in place and displacements measured from there (as \
          3DEC's model solve before a dynamic stage). Without it gravity is switched on at t = 0 \
          on unloaded contacts, a suddenly applied load that overshoots statics. Blocks with an \
          initial velocity are held where they are during the stage.",
    default: Value::Flag(false),
    get: |p| Value::Flag(p.initial_equilibrium),
    valid: Interval::ANY,
    widget: None,
};

pub const EQUILIBRIUM_TOLERANCE: Param = Param {
    key: "solver.equilibrium_tolerance",
    label: "R_max",
    unit: "",
    doc: "The equilibrium stage ends when the largest unbalanced force of a block, over its \
          weight plus its contact forces, falls below this (moments over those forces times the \
          block's radius). 1e-5 is the usual equilibrium ratio of 3DEC and PFC.",
    default: Value::Real(1e-5),
    get: |p| Value::Real(p.equilibrium_tolerance),
    valid: Interval::new(Bound::Open(0.0), Bound::Open(1.0)),
    widget: None,
};

pub const EQUILIBRIUM_MAX_STEPS: Param = Param {
    key: "solver.equilibrium_max_steps",
    label: "Stage steps",
    unit: "",
    doc: "The equilibrium stage ends after this many static steps even if R_max is still above \
          its tolerance (a mechanism: a block whose driving force exceeds its friction), and \
          summary.json reports it unconverged.",
    default: Value::Count(2000),
    get: |p| Value::Count(p.equilibrium_max_steps),
    valid: Interval::new(Bound::Closed(1.0), Bound::Closed(1e6)),
    widget: None,
};

pub const INITIAL_PENALTY: Param = Param {
    key: "solver.contact.initial_penalty",
    label: "p_n,1",
    unit: "N/m",
    doc: "Initial normal penalty of a new contact (ALM), and the fixed penalty in penalty mode. \
          The paper uses p_n,1 = 0.01 E (the same as DDA-3p) and warns it should not be too \
          small.",
    default: Value::Real(2.0e8),
    get: |p| Value::Real(p.contact.initial_penalty),
    valid: Interval::POSITIVE,
    widget: Some(Widget {
        range: WidgetRange::TimesYoung(1e-6, 100.0),
        logarithmic: true,
    }),
};

pub const ALPHA: Param = Param {
    key: "solver.contact.alpha",
    label: "α",
    unit: "",
    doc: "(P21) Penalty growth factor: p_n,k = α·p_n,k−1 when |d_n,k| > β·|d_n,k−1| (a contact \
          whose penetration does not shrink fast enough). Paper: α = 10.",
    default: Value::Real(10.0),
    get: |p| Value::Real(p.contact.alpha),
    valid: Interval::new(Bound::Open(1.0), Bound::Unbounded),
    widget: absolute(1.01, 1000.0, true),
};

pub const BETA: Param = Param {
    key: "solver.contact.beta",
    label: "β",
    unit: "",
    doc: "(P21) Convergence-rate threshold in (0, 1): the penalty of a contact grows when \
          |d_n,k| > β·|d_n,k−1|. Paper: β = 0.25.",
    default: Value::Real(0.25),
    get: |p| Value::Real(p.contact.beta),
    valid: Interval::new(Bound::Open(0.0), Bound::Open(1.0)),
    widget: absolute(0.01, 0.99, false),
};

pub const GAMMA: Param = Param {
    key: "solver.contact.gamma",
    label: "γ",
    unit: "E",
    doc: "(P21b) Penalty cap: p_n ≤ γ·E. The paper advises γ ≤ 100 (the condition number grows \
          like p·Δt²/m).",
    default: Value::Real(100.0),
    get: |p| Value::Real(p.contact.gamma),
    valid: Interval::POSITIVE,
    widget: absolute(0.01, 1000.0, true),
};

pub const EPS1: Param = Param {
    key: "solver.contact.eps1",
    label: "ε1",
    unit: "",
    doc: "(P22)–(P23) Penetration tolerance: ALM iterations stop when every closed contact's \
          |d_n| ≤ ε1·d_n,max, with d_n,max = 2·δ·w0. The paper recommends 0.01 < ε1 < 0.1 and \
          uses 0.01.",
    default: Value::Real(0.01),
    get: |p| Value::Real(p.contact.eps1),
    valid: Interval::POSITIVE,
    widget: absolute(1e-4, 0.5, true),
};

pub const EPS2: Param = Param {
    key: "solver.contact.eps2",
    label: "ε2",
    unit: "",
    doc: "(P24) Force tolerance: ALM iterations also require |λ_k − λ_k−1| / |λ_k−1| < ε2 \
          (relative change of the normal contact forces). The paper recommends 0 < ε2 < 0.1 and \
          uses 0.01.",
    default: Value::Real(0.01),
    get: |p| Value::Real(p.contact.eps2),
    valid: Interval::POSITIVE,
    widget: absolute(1e-4, 0.5, true),
};

pub const SHEAR_PENALTY_RATIO: Param = Param {
    key: "solver.contact.shear_penalty_ratio",
    label: "p_τ / p_n,1",
    unit: "",
    doc: "Shear spring of locked contacts relative to p_n,1. The paper does not give p_τ; Shi's \
          code uses p_n / 2.5.",
    default: Value::Real(1.0 / 2.5),
    get: |p| Value::Real(p.contact.shear_penalty_ratio),
    valid: Interval::POSITIVE,
    widget: absolute(0.01, 10.0, true),
};

pub const MAX_ALM_ITERATIONS: Param = Param {
    key: "solver.contact.max_alm_iterations",
    label: "ALM iterations",
    unit: "",
    doc: "Cap on ALM iterations per open–close pass (the paper's loop has none; 20 is the \
          reference notes' suggestion).",
    default: Value::Count(20),
    get: |p| Value::Count(p.contact.max_alm_iterations),
    valid: Interval::new(Bound::Closed(1.0), Bound::Unbounded),
    widget: absolute(1.0, 100.0, false),
};

pub const MAX_OPEN_CLOSE_ITERATIONS: Param = Param {
    key: "solver.contact.max_open_close_iterations",
    label: "Open–close passes",
    unit: "",
    doc: "Open–close passes before the step is redone with {DT_CUT}·Δt (Shi: 6 + 2; walls of many \
          blocks need 10–25 at an impact). If at most {SETTLE_PERCENT} % of the contacts still \
          change then, they are settled closed and locked instead.",
    default: Value::Count(30),
    get: |p| Value::Count(p.contact.max_open_close_iterations),
    valid: Interval::new(Bound::Closed(1.0), Bound::Unbounded),
    widget: absolute(1.0, 50.0, false),
};

pub const WARM_START: Param = Param {
    key: "solver.contact.warm_start",
    label: "Warm start",
    unit: "",
    doc: "Carry λ and p_n of persisting contacts from one step to the next. The paper is silent; \
          both converge to the same forces, warm starting in fewer iterations.",
    default: Value::Flag(true),
    get: |p| Value::Flag(p.contact.warm_start),
    valid: Interval::ANY,
    widget: None,
};

pub const CLOSE_THRESHOLD: Param = Param {
    key: "solver.contact.close_threshold",
    label: "Close threshold",
    unit: "",
    doc: "Penetration that closes an open contact, as a fraction of w0 (hysteresis against \
          open–close chatter: the role of Shi's s0).",
    default: Value::Real(2.0e-7),
    get: |p| Value::Real(p.contact.close_threshold),
    valid: Interval::NON_NEGATIVE,
    widget: None,
};

pub const OPEN_THRESHOLD: Param = Param {
    key: "solver.contact.open_threshold",
    label: "Open threshold",
    unit: "",
    doc: "Gap that opens a closed contact, as a fraction of w0 (tension beyond p_n · f0 · w0); \
          tangential displacements below it are not counted as slip or as a reversal of slip \
          (Shi's f0; hysteresis for contacts that carry no load).",
    default: Value::Real(2.0e-7),
    get: |p| Value::Real(p.contact.open_threshold),
    valid: Interval::NON_NEGATIVE,
    widget: None,
};

pub const FRICTION_ANGLE: Param = Param {
    key: "joint.friction_angle",
    label: "φ",
    unit: "°",
    doc: "Joint friction angle (Mohr–Coulomb): a closed contact slides when its shear force \
          exceeds N·tan φ (+ cohesion). The paper's examples use 35°.",
    default: Value::Real(35.0),
    get: |p| Value::Real(p.joint.friction_angle),
    valid: Interval::new(Bound::Closed(0.0), Bound::Open(90.0)),
    widget: absolute(0.0, 89.0, false),
};

pub const COHESION: Param = Param {
    key: "joint.cohesion",
    label: "c",
    unit: "Pa",
    doc: "Joint cohesion. Acts only on joints closed from the start that have never opened or \
          slid (Shi's rule): once broken a joint keeps only friction.",
    default: Value::Real(0.0),
    get: |p| Value::Real(p.joint.cohesion),
    valid: Interval::NON_NEGATIVE,
    widget: absolute(0.0, 1e8, true),
};

/// Every key, in the scene file's order (`[solver]`, `[solver.contact]`, `[joint]`).
pub const ALL: [&Param; 27] = [
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
    &INITIAL_PENALTY,
    &ALPHA,
    &BETA,
    &GAMMA,
    &EPS1,
    &EPS2,
    &SHEAR_PENALTY_RATIO,
    &MAX_ALM_ITERATIONS,
    &MAX_OPEN_CLOSE_ITERATIONS,
    &WARM_START,
    &CLOSE_THRESHOLD,
    &OPEN_THRESHOLD,
    &FRICTION_ANGLE,
    &COHESION,
];
