//! Every tunable of a run in one place, with the paper's defaults.
//!
//! The same struct is filled from the scene file (`[solver]`, `[solver.contact]`, `[joint]`),
//! overridden from the command line, and edited live by the viewer's panel. Field names match the
//! scene-file keys. [`table`] describes every key once (label, unit, valid range, the panel's
//! slider range, default, description): `validate`, the panel's sliders and tooltips, and the
//! README's scene table read it.

use serde::{Deserialize, Serialize};

pub mod numbers;
pub mod table;

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
    /// contact is more than this fraction, keeps Shi's rule.
    pub const SETTLE_FRACTION: f64 = 0.01;
    /// A step in which a free block stopped on all its sliding contacts is redone to end at the
    /// stop (`solver::step_control::stop_within`) only where the contacts slid faster than this
    /// many slip tolerances f0·w0 a step: slower ones are the micro-slips of blocks at rest.
    pub const STOP_CUT_SPEED: f64 = 10.0;
    /// ... and only where the stop fell within this share of the step: nearer its end the step
    /// is nearly right, nearer its start the speed lost is small.
    pub const STOP_CUT_RANGE: (f64, f64) = (0.1, 0.9);
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

/// Contact-law parameters (`[solver.contact]` in a scene file). The field docs name the symbol
/// and say why a value is what it is; users' descriptions, ranges and defaults are in [`table`].
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
    /// Penetrations below this fraction of ε1·d_n,max do not raise the penalty by (P21). The
    /// paper has no such floor; 0.01 keeps a sliding jointed mass free (raised penalties jam it
    /// at block edges), 0 lets (P21) stiffen the contacts of stacked blocks, which otherwise
    /// self-excite (see `crate::solver`'s ALM loop, `update_multipliers`). Static mode has none
    /// (`alm::penalty_floor`).
    pub penalty_floor: f64,
    /// p_τ / p_n,1: the shear spring of locked contacts (the paper does not give p_τ; Shi's
    /// code uses p_n / 2.5).
    pub shear_penalty_ratio: f64,
    /// Cap on ALM iterations per open–close pass (reference §6.2).
    pub max_alm_iterations: u32,
    /// Open–close passes before the step is redone with [`step_rules::DT_CUT`] · Δt (reference
    /// §6.3). Shi's code uses 6 + 2; in a wall of many blocks, lightly loaded joints need 10–25
    /// passes at the impact, and a pass costs far less than the steps a cut adds. Where at most
    /// [`step_rules::SETTLE_FRACTION`] of the contacts still change at the limit, they are settled
    /// closed and locked instead of the step being redone.
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
    ///
    /// `inertia` is the stiffness of the lighter block's inertia at Δt_max, 2m/Δt_max² (0 in
    /// static mode, or where both blocks are fixed): where it exceeds α·p_n,1, the cap rises to
    /// it. A spring much softer than its block's inertia takes many steps to take up the load,
    /// and the block slides freely meanwhile: a 20 × 20 × 10 m block released on 20° at a factor
    /// of safety of 0.8 (2m/Δt² = 2·10¹¹ N/m at 10 ms, α·p_n,1 = 2·10⁹) went 15 % too far in
    /// 1 s and, at a factor of safety of 1.5, rattled at centimetres a second for as long as it
    /// ran; with the cap at its inertia, 0.2 % too far, and the stable one's start-up jolt dies
    /// out, below 0.1 mm/s by 0.15 s. A cap no higher than the inertia still stops the welding: K holds that
    /// stiffness already.
    pub fn shear_penalty(&self, p_n: f64, inertia: f64) -> f64 {
        self.shear_penalty_ratio * p_n.min((self.alpha * self.initial_penalty).max(inertia))
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
            penalty_floor: 0.01,
            shear_penalty_ratio: 1.0 / 2.5,
            max_alm_iterations: 20,
            max_open_close_iterations: 30,
            warm_start: true,
            close_threshold: 2.0e-7,
            open_threshold: 2.0e-7,
        }
    }
}

/// Joint (interface) properties between blocks (`[joint]`); see [`table`] for their ranges.
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

/// The properties of one joint set of a rock mass (`[[rock_masses.joint_sets]]`): contacts
/// between two faces cut by the same plane of the set take these instead of `[joint]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointSetParams {
    /// The set's name, as `contacts.csv` writes it.
    pub name: String,
    /// The rock mass it cuts (set names repeat across rock masses).
    pub rock_mass: String,
    pub joint: JointParams,
}

/// All tunables of a run. The scene file's `[solver]` table, plus `[solver.contact]` and
/// `[joint]` which live in their own tables.
///
/// Each key's description, valid range and default, as users see them: [`table`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverParams {
    pub method: Method,
    pub mode: Mode,
    /// ρ∞ ∈ [⅓, 1]: the per-step amplification of modes with ωΔt → ∞ (Newmark γ = 1,
    /// β = (1 + 3ρ∞)/(2(1 + ρ∞)²); 1 is Shi's step). See [`crate::physics::integrator`].
    pub spectral_radius: f64,
    /// Simulated time to run, s.
    pub duration: f64,
    /// Δt_max, s.
    pub max_time_step: f64,
    /// δ: the largest vertex displacement allowed in one step, as a fraction of w0 (half the
    /// largest extent of the model's bounding box).
    pub max_displacement_ratio: f64,
    /// Gravity, m/s²; z is up.
    #[serde(deserialize_with = "numbers::exact")]
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
    /// Bring the model to rest under gravity with static steps before the run starts
    /// (rock-mass reference §5); see [`crate::solver`]'s equilibrium stage.
    pub initial_equilibrium: bool,
    /// The stage ends when R_max (R5.1) falls below this.
    pub equilibrium_tolerance: f64,
    /// The stage ends after this many static steps even if R_max has not fallen.
    pub equilibrium_max_steps: u32,
    /// A block is still while its fastest vertex is slower than this, m/s; 0: no block ever
    /// sleeps. See [`crate::solver`]'s sleeping islands.
    pub sleep_velocity: f64,
    /// An island of blocks sleeps once all of them have been still this long, s.
    pub sleep_time: f64,
    /// `[solver.contact]`.
    pub contact: ContactParams,
    /// The scene's top-level `[joint]` table (not part of `[solver]`).
    #[serde(skip)]
    pub joint: JointParams,
    /// The joint sets of the scene's rock masses, by the index a contact carries
    /// ([`SolverParams::joint_of`]).
    #[serde(skip)]
    pub joint_sets: Vec<JointSetParams>,
    /// Every joint held against sliding: set by the solver for the first phase of the
    /// equilibrium stage, never by a scene.
    #[serde(skip)]
    pub joints_held: bool,
}

impl Default for SolverParams {
    fn default() -> Self {
        SolverParams {
            method: Method::Alm,
            mode: Mode::Dynamic,
            spectral_radius: 0.5,
            duration: 2.0,
            max_time_step: 0.01,
            max_displacement_ratio: 0.01,
            gravity: [0.0, 0.0, -9.8],
            fixed_spring_factor: 100.0,
            max_displacement_overshoot: 1.0,
            rotate_stress: false,
            initial_equilibrium: false,
            equilibrium_tolerance: 1e-5,
            equilibrium_max_steps: 2000,
            sleep_velocity: 1e-5,
            sleep_time: 0.1,
            contact: ContactParams::default(),
            joint: JointParams::default(),
            joint_sets: Vec::new(),
            joints_held: false,
        }
    }
}

/// A value [`SolverParams::check`] rejects: the message, and the scene-file keys it concerns,
/// the one to point at first (the message's line, the flag that set it) first.
#[derive(Clone, Debug, PartialEq)]
pub struct Invalid {
    pub keys: &'static [&'static str],
    pub message: String,
}

impl SolverParams {
    /// The joint properties of a contact: its joint set's (`Some(index)`), or `[joint]`.
    pub fn joint_of(&self, set: Option<u16>) -> &JointParams {
        set.and_then(|k| self.joint_sets.get(usize::from(k)))
            .map_or(&self.joint, |s| &s.joint)
    }

    /// Checks every value against the range of its [`table`] entry, then the number of steps the
    /// run would take ([`table::MAX_STEPS`]); returns a message naming the offending key. Every
    /// number is first checked to be finite, then each against its range, both in the table's
    /// (the scene file's) order.
    pub fn validate(&self) -> Result<(), String> {
        self.check().map_err(|e| e.message)
    }

    /// [`SolverParams::validate`], with the keys the failure concerns.
    pub fn check(&self) -> Result<(), Invalid> {
        let invalid = |p: &'static table::Param| {
            move |message| Invalid {
                keys: std::slice::from_ref(&p.key),
                message,
            }
        };
        for p in table::ALL {
            p.check_finite(self).map_err(invalid(p))?;
        }
        for p in table::ALL {
            p.check_range(self).map_err(invalid(p))?;
        }
        table::check_steps(self).map_err(|message| Invalid {
            keys: &[table::DURATION.key, table::MAX_TIME_STEP.key],
            message,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::table::*;
    use super::*;

    /// The scene file's keys of every field, from serde, so that a new field cannot be missed.
    fn scene_keys() -> Vec<String> {
        let mut keys = Vec::new();
        let solver = serde_json::to_value(SolverParams::default()).unwrap();
        for (name, v) in solver.as_object().unwrap() {
            match v.as_object() {
                Some(table) => keys.extend(table.keys().map(|k| format!("solver.{name}.{k}"))),
                None => keys.push(format!("solver.{name}")),
            }
        }
        let joint = serde_json::to_value(JointParams::default()).unwrap();
        keys.extend(
            joint
                .as_object()
                .unwrap()
                .keys()
                .map(|k| format!("joint.{k}")),
        );
        keys
    }

    #[test]
    fn every_field_has_one_entry() {
        let mut keys = scene_keys();
        let mut table: Vec<String> = ALL.iter().map(|p| p.key.to_owned()).collect();
        keys.sort();
        table.sort();
        assert_eq!(table, keys);
    }

    #[test]
    fn defaults_match_the_structs_and_are_valid() {
        let d = SolverParams::default();
        for p in ALL {
            assert_eq!(p.default, (p.get)(&d), "{}", p.key);
        }
        assert_eq!(d.validate(), Ok(()));
    }

    /// A scene that sets `key` to the TOML literal `value`.
    fn scene_with(p: &Param, value: &str) -> String {
        format!(
            "[materials.rock]\ndensity = 2750.0\nyoung_modulus = 2.0e10\npoisson_ratio = 0.25\n\
             [[blocks]]\nname = \"a\"\nmaterial = \"rock\"\n\
             box = {{ size = [1, 1, 1], center = [0, 0, 0.5] }}\n\
             [{}]\n{} = {value}\n",
            p.table(),
            p.name()
        )
    }

    /// Values just outside an interval, below and above.
    fn outside(i: Interval) -> Vec<f64> {
        let nudge = |x: f64| 1e-9 * x.abs().max(1.0);
        let mut v = Vec::new();
        match i.lo {
            Bound::Unbounded => {}
            Bound::Open(x) => v.push(x),
            Bound::Closed(x) => v.push(x - nudge(x)),
        }
        match i.hi {
            Bound::Unbounded => {}
            Bound::Open(x) => v.push(x),
            Bound::Closed(x) => v.push(x + nudge(x)),
        }
        v
    }

    #[test]
    fn values_outside_a_range_are_rejected_naming_the_key() {
        let mut checked = 0;
        for p in ALL {
            let values: Vec<String> = match p.default {
                Value::Real(_) => outside(p.valid).iter().map(|x| format!("{x:?}")).collect(),
                // The whole number beyond the bound: below the lower one, above the upper one.
                Value::Count(d) => outside(p.valid)
                    .iter()
                    .map(|x| {
                        let whole = if *x < f64::from(d) {
                            x.floor()
                        } else {
                            x.ceil()
                        };
                        whole.to_string()
                    })
                    .collect(),
                _ => continue,
            };
            for value in values {
                let text = scene_with(p, &value);
                let e = crate::scene::parse(&text, "s.toml", "s").expect_err(&text);
                assert!(e.message.contains(p.key), "{}: {e}", p.key);
                checked += 1;
            }
            if let Value::Real(_) = p.default {
                let e = crate::scene::parse(&scene_with(p, "nan"), "s.toml", "s").unwrap_err();
                assert!(
                    e.message.contains(p.key) && e.message.contains("finite"),
                    "{e}"
                );
            }
            // The default, written into a scene, is accepted.
            if let Value::Real(x) = p.default {
                crate::scene::parse(&scene_with(p, &format!("{x:?}")), "s.toml", "s").unwrap();
            }
        }
        assert!(checked >= 18, "every bounded number is checked ({checked})");
        let mut bad = SolverParams::default();
        bad.contact.beta = 1.5;
        assert_eq!(
            bad.validate(),
            Err("solver.contact.beta must lie in (0, 1), got 1.5".into())
        );
        bad.contact.beta = f64::NAN;
        assert_eq!(
            bad.validate(),
            Err("solver.contact.beta must be a finite number, got NaN".into())
        );
    }

    #[test]
    fn widget_ranges_lie_within_the_valid_ranges() {
        let young = 2.0e10;
        for p in ALL.iter().filter(|p| p.widget.is_some()) {
            let r = p.widget_range(young);
            assert!(r.start() < r.end(), "{}", p.key);
            assert!(
                p.valid.contains(*r.start()) && p.valid.contains(*r.end()),
                "{}",
                p.key
            );
            if let Value::Real(d) = p.default {
                assert!(r.contains(&d), "{}: the default is on the slider", p.key);
            }
        }
    }

    #[test]
    fn docs_write_out_the_step_rules() {
        for p in ALL {
            assert!(!p.doc().contains('{'), "{}: {}", p.key, p.doc());
        }
        let passes = MAX_OPEN_CLOSE_ITERATIONS.doc();
        assert!(
            passes.contains("0.3·Δt") && passes.contains("at most 1 %"),
            "{passes}"
        );
        assert!(MAX_TIME_STEP.doc().contains("≤ 1.3×"));
    }

    /// The README's input limits list every bounded key with the table's range and reason.
    #[test]
    fn the_readme_lists_the_bounds_of_the_table() {
        let readme = include_str!("../../README.md");
        let limits = readme
            .split("### Input limits")
            .nth(1)
            .expect("README has ### Input limits");
        for row in markdown_limits().lines() {
            assert!(limits.contains(row), "README lacks the row\n{row}");
        }
        assert!(limits.contains("10⁷ steps"), "the step limit");
        assert_eq!(MAX_STEPS, 1e7);
    }

    /// Every bounded key says why, the bounds print short, and the shipped defaults lie inside.
    #[test]
    fn bounds_have_reasons_and_read_short() {
        for p in [
            &DURATION,
            &MAX_TIME_STEP,
            &MAX_DISPLACEMENT_RATIO,
            &EPS1,
            &EPS2,
            &PENALTY_FLOOR,
            &MAX_ALM_ITERATIONS,
            &MAX_OPEN_CLOSE_ITERATIONS,
            &CLOSE_THRESHOLD,
            &OPEN_THRESHOLD,
        ] {
            assert!(!p.valid_why.is_empty(), "{}", p.key);
            assert!(p.doc().contains("Valid: "), "{}", p.key);
            assert!(p.valid.lo != Bound::Unbounded && p.valid.hi != Bound::Unbounded);
        }
        assert_eq!(MAX_TIME_STEP.valid_range(), "[1e-7, 1] s");
        assert_eq!(DURATION.valid_range(), "[1e-7, 1e7] s");
        assert_eq!(MAX_DISPLACEMENT_RATIO.valid_range(), "[1e-7, 0.1]");
        assert_eq!(SPECTRAL_RADIUS.valid_range(), "[1/3, 1]");
        // The longest run the ranges allow is the step limit at the longest step.
        let longest = |b: Bound| match b {
            Bound::Closed(x) | Bound::Open(x) => x,
            Bound::Unbounded => f64::INFINITY,
        };
        assert_eq!(
            longest(DURATION.valid.hi) / longest(MAX_TIME_STEP.valid.hi),
            MAX_STEPS
        );
        // The shortest run takes a step at the longest Δt_max (the solver ends a run within
        // 1e-9·Δt_max of its end).
        let (Bound::Closed(shortest), Bound::Closed(dt_max)) =
            (DURATION.valid.lo, MAX_TIME_STEP.valid.hi)
        else {
            panic!("closed bounds")
        };
        assert!(shortest > 1e-9 * dt_max);
    }

    /// Families of absurd time controls, each rejected naming its key with the number short;
    /// the step limit names both keys.
    #[test]
    fn absurd_time_controls_are_rejected() {
        let with = |f: &dyn Fn(&mut SolverParams)| {
            let mut p = SolverParams::default();
            f(&mut p);
            p.check()
        };
        for dt in [0.0, -1.0, 1e-15, 9.9e-8, 1.01, 2.0, 1e9, 3e9, 1e308] {
            let e = with(&|p| p.max_time_step = dt).unwrap_err();
            assert_eq!(e.keys, [MAX_TIME_STEP.key]);
            assert!(e.message.contains("[1e-7, 1] s"), "{}", e.message);
            assert!(e.message.len() < 100, "short: {}", e.message);
        }
        for d in [0.0, -1.0, 1e-300, 1e-12, 9e-8, 1.1e7, 1e308] {
            let e = with(&|p| p.duration = d).unwrap_err();
            assert_eq!(e.keys, [DURATION.key], "{d}");
            assert!(e.message.len() < 100, "short: {}", e.message);
        }
        for r in [0.0, 1e-9, 0.11, 1.0, 1e300] {
            let e = with(&|p| p.max_displacement_ratio = r).unwrap_err();
            assert_eq!(e.keys, [MAX_DISPLACEMENT_RATIO.key]);
        }
        for (d, dt) in [(1e6, 0.01), (2.0, 1e-7), (1e7, 0.5), (100.0, 9e-6)] {
            let e = with(&|p| {
                p.duration = d;
                p.max_time_step = dt;
            })
            .unwrap_err();
            assert_eq!(e.keys, [DURATION.key, MAX_TIME_STEP.key]);
            assert!(
                e.message.contains("more than the limit of 1e7"),
                "{}",
                e.message
            );
        }
        // At the limit and inside it.
        for (d, dt) in [
            (1e5, 0.01),
            (1e7, 1.0),
            (1.0, 1e-7),
            (1e-7, 1.0),
            (2.0, 1e-6),
        ] {
            with(&|p| {
                p.duration = d;
                p.max_time_step = dt;
            })
            .unwrap_or_else(|e| panic!("{d} s at {dt} s: {}", e.message));
        }
        for n in [0, 1001, u32::MAX] {
            assert!(with(&|p| p.contact.max_alm_iterations = n).is_err());
            assert!(with(&|p| p.contact.max_open_close_iterations = n).is_err());
        }
        for eps in [1.0, 10.0, 1e300] {
            assert!(with(&|p| p.contact.eps1 = eps).is_err());
            assert!(with(&|p| p.contact.eps2 = eps).is_err());
        }
        for f in [0.011, 1.0, 1e300] {
            assert!(with(&|p| p.contact.close_threshold = f).is_err());
            assert!(with(&|p| p.contact.open_threshold = f).is_err());
        }
        let e = with(&|p| p.contact.beta = 1.000_000_001).unwrap_err();
        assert_eq!(
            e.message, "solver.contact.beta must lie in (0, 1), got 1.000000001",
            "a value rounded into the range prints in full"
        );
    }

    /// Every key reads back the text it writes (as `--compare-set` and the labels of a
    /// comparison use them), and is found by its name, its key and its flag spelling.
    #[test]
    fn every_key_reads_back_its_own_text() {
        let mut p = SolverParams {
            method: Method::Penalty,
            ..SolverParams::default()
        };
        p.contact.eps1 = 0.012_345_678_9;
        p.spectral_radius = 1.0 / 3.0;
        p.gravity = [0.1, 0.0, -9.81];
        p.contact.warm_start = false;
        p.contact.max_alm_iterations = 7;
        p.contact.initial_penalty = 2e9;
        for k in ALL {
            let text = k.text(&p);
            let mut q = SolverParams::default();
            (k.set)(&mut q, &text).unwrap_or_else(|e| panic!("{}: {text}: {e}", k.key));
            assert_eq!((k.get)(&q), (k.get)(&p), "{}: {text}", k.key);
            assert_eq!(find(k.name()).map(|f| f.key), Some(k.key));
            assert_eq!(find(k.key).map(|f| f.key), Some(k.key));
            assert_eq!(
                find(&k.name().replace('_', "-")).map(|f| f.key),
                Some(k.key)
            );
        }
        assert_eq!(INITIAL_PENALTY.text(&p), "2e9");
        assert_eq!(EPS1.text(&p), "1.23456789e-2");
        assert!(find("nonsense").is_none());
    }

    /// Keys the README's scene table does not have yet.
    #[test]
    fn the_readme_documents_every_key() {
        let readme = include_str!("../../README.md");
        let rows = markdown_rows();
        assert_eq!(rows.lines().count(), ALL.len());
        for row in rows.lines() {
            let cells = row.replace("\\|", "").matches('|').count() - 1;
            assert_eq!(cells, 4, "{row}");
        }
        for p in ALL {
            assert!(rows.contains(&format!("`{}`", p.name())), "{}", p.key);
            assert!(
                readme.contains(&format!("`{}`", p.name())),
                "README lacks {}",
                p.key
            );
        }
    }
}
