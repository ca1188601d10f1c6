//! Every tunable of a run in one place, with the paper's defaults.
//!
//! The same struct is filled from the scene file (`[solver]`, `[solver.contact]`, `[joint]`),
//! overridden from the command line, and edited live by the viewer's panel. Field names match the
//! scene-file keys.

use serde::{Deserialize, Serialize};

/// Shi's step-control rules (reference §6.3, §8). They are part of the method, not tunables; the
/// solver's step control, the parameter docs and the viewer's tooltips all read them from here.
pub mod step_rules {
    /// A step whose open–close iteration does not converge, or whose solution is not finite or
    /// penetrates beyond the contact window, is redone with `DT_CUT · Δt`.
    pub const DT_CUT: f64 = 0.3;
    /// A step redone for too large a displacement (r times δ·w0) is retried with
    /// `Δt / √r · DISPLACEMENT_CUT_SAFETY`: the displacement of a step grows as Δt².
    pub const DISPLACEMENT_CUT_SAFETY: f64 = 0.95;
    /// After a step, Δt grows back by at most this factor (Shi), up to Δt_max.
    pub const DT_GROWTH: f64 = 1.3;
    /// The smallest step is `Δt_max / DT_FLOOR_DIVISOR`; a step that fails there diverges.
    pub const DT_FLOOR_DIVISOR: f64 = 100.0;
    /// The predicted Δt keeps the fastest vertex within this fraction of δ·w0.
    pub const PREDICT_SAFETY: f64 = 0.9;
    /// At the open–close pass limit, a step whose last pass changed at most this fraction of its
    /// contacts is settled (those contacts closed and locked, as at the Δt floor) instead of
    /// redone with a shorter step. In a struck wall of 1000 blocks the last passes each changed
    /// 2 to 9 of 11 500 contacts, scattered along the wall; each redo threw away 30 global passes
    /// and shortened the following steps (9 redos in its first second). A small model, where one
    /// contact is more than 1 %, keeps Shi's rule.
    pub const SETTLE_FRACTION: f64 = 0.01;
}

/// How normal contacts are enforced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// DDA-3a: augmented Lagrangian multipliers with an adaptive penalty (paper §1–2).
    Alm,
    /// DDA-3p: classic fixed penalty, the paper's baseline.
    Penalty,
}

/// Time integration mode (reference §3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Velocity carried between steps.
    Dynamic,
    /// Velocity reset to zero before every step: the system creeps into equilibrium.
    Static,
}

impl Method {
    pub fn as_str(self) -> &'static str {
        match self {
            Method::Alm => "alm",
            Method::Penalty => "penalty",
        }
    }
}

impl Mode {
    pub fn as_str(self) -> &'static str {
        match self {
            Mode::Dynamic => "dynamic",
            Mode::Static => "static",
        }
    }
}

/// Contact-law parameters (`[solver.contact]` in a scene file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ContactParams {
    /// p_n,1, N/m: the first normal penalty of a new contact in ALM mode, and the fixed
    /// penalty in penalty mode. The paper uses 0.01 E.
    pub initial_penalty: f64,
    /// α > 1 of (P21): factor by which a slowly converging contact's penalty grows.
    pub alpha: f64,
    /// β ∈ (0, 1) of (P21): the penalty grows when |d_n,k| > β |d_n,k−1|.
    pub beta: f64,
    /// γ of (P21b): penalties are capped at γ E (the paper advises γ ≤ 100).
    pub gamma: f64,
    /// ε1 of (P22)–(P23): penetration tolerance as a fraction of d_n,max = 2 δ w0.
    pub eps1: f64,
    /// ε2 of (P24): relative change of the contact forces between ALM iterations.
    pub eps2: f64,
    /// p_τ / p_n,1: the shear spring of locked contacts (the paper does not give p_τ; Shi's
    /// code uses p_n / 2.5).
    pub shear_penalty_ratio: f64,
    /// Cap on ALM iterations per open–close pass (reference §6.2).
    pub max_alm_iterations: u32,
    /// Open–close passes before the step is redone with 0.3 Δt (reference §6.3). Shi's code
    /// uses 6 + 2; in a wall of many blocks, lightly loaded joints need 10–25 passes at the
    /// impact, and a pass costs far less than the steps a cut adds. Where at most 1 % of the
    /// contacts still change at the limit, they are settled closed and locked instead of the
    /// step being redone (see the solver's `SETTLE_FRACTION`).
    pub max_open_close_iterations: u32,
    /// Carry λ and p_n of persisting contacts from one step to the next. The paper is silent;
    /// both converge to the same forces, warm starting needs fewer iterations and keeps the
    /// friction force of a sliding contact exact from the first iteration.
    pub warm_start: bool,
    /// An open contact closes when its penetration exceeds this fraction of w0 (hysteresis
    /// against open–close chatter: the role of Shi's s0). Shi's value, 2e-4, lets an open
    /// contact sink 1.8 mm into a face in the rockfall, the whole ALM tolerance ε1·d_n,max; on a
    /// struck wall it saved 20 % of the passes but let overlaps of centimetres build up and
    /// gave single steps of +58 kJ, so the default is f0's 2e-7.
    pub close_threshold: f64,
    /// A closed contact opens when its gap exceeds this fraction of w0 (tension beyond
    /// p_n · f0 · w0), and tangential displacements below it are not counted as slip or as a
    /// reversal of slip (Shi's f0; hysteresis for contacts that carry no load).
    pub open_threshold: f64,
}

impl ContactParams {
    /// p_τ of a locked contact whose normal penalty is `p_n`: `shear_penalty_ratio · p_n`, with
    /// p_n capped at α·p_n,1. Following p_n keeps the shear spring stiffer than the block's
    /// inertia term once the normal penalty has been raised (with p_n,1 alone the paper's sliding
    /// block stays half-locked at its first step). The cap stops a contact stiffened to γE by
    /// (P21) from welding its neighbours together in shear.
    pub fn shear_penalty(&self, p_n: f64) -> f64 {
        self.shear_penalty_ratio * p_n.min(self.alpha * self.initial_penalty)
    }
}

impl Default for ContactParams {
    fn default() -> Self {
        // Paper §3.1: p_n,1 = 0.01 E with E = 2e10 Pa, α = 10, β = 0.25, γ = 100, ε1 = ε2 = 0.01.
        ContactParams {
            initial_penalty: 2.0e8,
            alpha: 10.0,
            beta: 0.25,
            gamma: 100.0,
            eps1: 0.01,
            eps2: 0.01,
            shear_penalty_ratio: 1.0 / 2.5,
            max_alm_iterations: 20,
            max_open_close_iterations: 30,
            warm_start: true,
            close_threshold: 2.0e-7,
            open_threshold: 2.0e-7,
        }
    }
}

/// Joint (interface) properties between blocks (`[joint]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct JointParams {
    /// φ, degrees.
    pub friction_angle: f64,
    /// c, Pa. Acts only on contacts that were closed at the start and have never opened or
    /// slid (Shi's rule): once a joint has broken it keeps only friction.
    pub cohesion: f64,
}

impl Default for JointParams {
    fn default() -> Self {
        JointParams {
            friction_angle: 35.0,
            cohesion: 0.0,
        }
    }
}

/// All tunables of a run. The scene file's `[solver]` table, plus `[solver.contact]` and
/// `[joint]` which live in their own tables.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverParams {
    pub method: Method,
    pub mode: Mode,
    /// Simulated time to run, s.
    pub duration: f64,
    /// Δt_max, s.
    pub max_time_step: f64,
    /// δ: the largest vertex displacement allowed in one step, as a fraction of w0 (half the
    /// largest extent of the model's bounding box).
    pub max_displacement_ratio: f64,
    /// Gravity, m/s²; z is up.
    pub gravity: [f64; 3],
    /// Stiffness of the vertex springs of fixed blocks, as a multiple of the block's E
    /// (the paper uses 100 E).
    pub fixed_spring_factor: f64,
    /// A step is redone with a smaller Δt when its largest vertex displacement exceeds
    /// `max_displacement_overshoot · δ · w0`. 1 keeps every step within δ w0, which is what
    /// the bound d_n,max = 2 δ w0 of (P22) assumes.
    pub max_displacement_overshoot: f64,
    /// Rotate the carried stress with the block (objective update, reference §1.3). Classic DDA
    /// does not.
    pub rotate_stress: bool,
    /// `[solver.contact]`.
    pub contact: ContactParams,
    /// The scene's top-level `[joint]` table (not part of `[solver]`).
    #[serde(skip)]
    pub joint: JointParams,
}

impl Default for SolverParams {
    fn default() -> Self {
        SolverParams {
            method: Method::Alm,
            mode: Mode::Dynamic,
            duration: 2.0,
            max_time_step: 0.01,
            max_displacement_ratio: 0.01,
            gravity: [0.0, 0.0, -9.8],
            fixed_spring_factor: 100.0,
            max_displacement_overshoot: 1.0,
            rotate_stress: false,
            contact: ContactParams::default(),
            joint: JointParams::default(),
        }
    }
}

impl SolverParams {
    /// Checks ranges; returns a message naming the offending key.
    pub fn validate(&self) -> Result<(), String> {
        let c = &self.contact;
        let finite = [
            ("solver.duration", self.duration),
            ("solver.max_time_step", self.max_time_step),
            ("solver.max_displacement_ratio", self.max_displacement_ratio),
            ("solver.gravity", self.gravity[0]),
            ("solver.gravity", self.gravity[1]),
            ("solver.gravity", self.gravity[2]),
            ("solver.fixed_spring_factor", self.fixed_spring_factor),
            (
                "solver.max_displacement_overshoot",
                self.max_displacement_overshoot,
            ),
            ("solver.contact.initial_penalty", c.initial_penalty),
            ("solver.contact.alpha", c.alpha),
            ("solver.contact.beta", c.beta),
            ("solver.contact.gamma", c.gamma),
            ("solver.contact.eps1", c.eps1),
            ("solver.contact.eps2", c.eps2),
            ("solver.contact.shear_penalty_ratio", c.shear_penalty_ratio),
            ("solver.contact.close_threshold", c.close_threshold),
            ("solver.contact.open_threshold", c.open_threshold),
            ("joint.friction_angle", self.joint.friction_angle),
            ("joint.cohesion", self.joint.cohesion),
        ];
        for (key, v) in finite {
            if !v.is_finite() {
                return Err(format!("{key} must be a finite number, got {v}"));
            }
        }
        let positive = [
            ("solver.duration", self.duration),
            ("solver.max_time_step", self.max_time_step),
            ("solver.max_displacement_ratio", self.max_displacement_ratio),
            ("solver.fixed_spring_factor", self.fixed_spring_factor),
            ("solver.contact.initial_penalty", c.initial_penalty),
            ("solver.contact.gamma", c.gamma),
            ("solver.contact.eps1", c.eps1),
            ("solver.contact.eps2", c.eps2),
            ("solver.contact.shear_penalty_ratio", c.shear_penalty_ratio),
        ];
        for (key, v) in positive {
            if v <= 0.0 {
                return Err(format!("{key} must be positive, got {v}"));
            }
        }
        if c.alpha <= 1.0 {
            return Err(format!("solver.contact.alpha must be > 1, got {}", c.alpha));
        }
        if !(c.beta > 0.0 && c.beta < 1.0) {
            return Err(format!(
                "solver.contact.beta must lie in (0, 1), got {}",
                c.beta
            ));
        }
        if self.max_displacement_overshoot < 1.0 {
            return Err(format!(
                "solver.max_displacement_overshoot must be at least 1, got {}",
                self.max_displacement_overshoot
            ));
        }
        if c.close_threshold < 0.0 || c.open_threshold < 0.0 {
            return Err(
                "solver.contact.close_threshold and open_threshold must not be negative".into(),
            );
        }
        if c.max_alm_iterations == 0 || c.max_open_close_iterations == 0 {
            return Err("solver.contact iteration limits must be at least 1".into());
        }
        if !(0.0..90.0).contains(&self.joint.friction_angle) {
            return Err(format!(
                "joint.friction_angle must lie in [0, 90) degrees, got {}",
                self.joint.friction_angle
            ));
        }
        if self.joint.cohesion < 0.0 {
            return Err("joint.cohesion must not be negative".into());
        }
        Ok(())
    }
}
