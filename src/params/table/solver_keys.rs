//! The `[solver]` keys of the parameter table (see [`super`]).

use super::{Bound, Interval, Param, Value, absolute, assign};

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
    set: |p, text| assign(text, &mut p.method),
    valid: Interval::ANY,
    valid_why: "",
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
    set: |p, text| assign(text, &mut p.mode),
    valid: Interval::ANY,
    valid_why: "",
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
    set: |p, text| assign(text, &mut p.spectral_radius),
    valid: Interval::new(Bound::Closed(1.0 / 3.0), Bound::Closed(1.0)),
    valid_why: "",
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
    set: |p, text| assign(text, &mut p.duration),
    valid: Interval::new(Bound::Closed(1e-7), Bound::Closed(1e7)),
    valid_why: "at least the shortest Δt_max, so that every run takes a step (the solver counts a \
          run within 10⁻⁹·Δt_max of its end as finished: 10⁻¹² s \"completed\"with none); at most \
          10⁷ steps of the longest Δt_max. Within it, duration / Δt_max must stay at most 10⁷ \
          steps.",
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
    set: |p, text| assign(text, &mut p.max_time_step),
    valid: Interval::new(Bound::Closed(1e-7), Bound::Closed(1.0)),
    valid_why: "a P-wave crosses a millimetre of rock in 2·10⁻⁷ s, and the constant-strain blocks \
          of DDA resolve nothing faster; the step control cuts down to Δt_max / 100, which up to \
          1 s still reaches the paper's 0.01 s (above it, a model that moves at all diverges at \
          the floor).",
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
    set: |p, text| assign(text, &mut p.max_displacement_ratio),
    valid: Interval::new(Bound::Closed(1e-7), Bound::Closed(0.1)),
    valid_why: "Shi advises 0.001–0.01. Above 0.1 a step may move a vertex a tenth of w0 and \
          contacts are searched 2·δ·w0 away, a tenth of the model's extent; below 10⁻⁷ a whole \
          step moves less than the open–close hysteresis f0 = 2·10⁻⁷ w0.",
    widget: absolute(1e-4, 0.1, true),
};

pub const GRAVITY: Param = Param {
    key: "solver.gravity",
    label: "g",
    unit: "m/s²",
    doc: "Gravity; z is up.",
    default: Value::Vector([0.0, 0.0, -9.8]),
    get: |p| Value::Vector(p.gravity),
    set: |p, text| assign(text, &mut p.gravity),
    valid: Interval::new(Bound::Closed(0.0), Bound::Closed(1e4)),
    valid_why: "its magnitude: a geotechnical centrifuge spins models at up to a few hundred g, \
                and 10⁴ m/s² is a thousand; at 1e300 the first solve was not finite and the \
                input was reported as a divergence (exit 1).",
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
    set: |p, text| assign(text, &mut p.fixed_spring_factor),
    valid: Interval::new(Bound::Closed(1.0), Bound::Closed(1e6)),
    valid_why: "below E a fixed block sinks under its load (at 1e-300 E the ground fell 4.9 m \
          in a second and the run completed), above 10⁶ E its springs swamp K (at 1e300 the \
          first solve was not finite).",
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
    set: |p, text| assign(text, &mut p.max_displacement_overshoot),
    valid: Interval::new(Bound::Closed(1.0), Bound::Closed(2.0)),
    valid_why: "beyond 2 a step may move a vertex past the contact window 2·δ·w0 of (P22), \
                through a face it never touched (1e300 was accepted).",
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
    set: |p, text| assign(text, &mut p.rotate_stress),
    valid: Interval::ANY,
    valid_why: "",
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
    set: |p, text| assign(text, &mut p.initial_equilibrium),
    valid: Interval::ANY,
    valid_why: "",
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
    set: |p, text| assign(text, &mut p.equilibrium_tolerance),
    valid: Interval::new(Bound::Open(0.0), Bound::Open(1.0)),
    valid_why: "",
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
    set: |p, text| assign(text, &mut p.equilibrium_max_steps),
    valid: Interval::new(Bound::Closed(1.0), Bound::Closed(1e6)),
    valid_why: "10⁶ static steps cost as much as a run of 10⁴ s at the paper's Δt; a stage that \
          has not settled by then has a mechanism (a block that slides), not a slow start.",
    widget: None,
};

pub const SLEEP_VELOCITY: Param = Param {
    key: "solver.sleep_velocity",
    label: "v_sleep",
    unit: "m/s",
    doc: "A block is still while its fastest vertex moves slower than this. An island of blocks \
          (blocks within contact search distance of each other, fixed blocks not linking them) \
          sleeps once all its blocks have been still for sleep_time: it is held exactly where \
          it is, its contacts keep their forces, and it costs nothing until a moving block comes \
          within search distance of it. A block accelerating from rest at a is stopped only if \
          a · sleep_time < sleep_velocity (10⁻⁴ m/s² at the defaults). 0: no block ever sleeps.",
    default: Value::Real(1e-5),
    get: |p| Value::Real(p.sleep_velocity),
    set: |p, text| assign(text, &mut p.sleep_velocity),
    valid: Interval::new(Bound::Closed(0.0), Bound::Closed(0.01)),
    valid_why: "1 cm/s is a block in motion, not one at rest.",
    widget: absolute(1e-7, 1e-3, true),
};

pub const SLEEP_TIME: Param = Param {
    key: "solver.sleep_time",
    label: "t_sleep",
    unit: "s",
    doc: "How long every block of an island must have been still (see sleep_velocity) before \
          the island sleeps. Longer: only blocks settled for longer sleep, and a slowly \
          accelerating block is told apart from one at rest down to a smaller acceleration.",
    default: Value::Real(0.1),
    get: |p| Value::Real(p.sleep_time),
    set: |p, text| assign(text, &mut p.sleep_time),
    valid: Interval::new(Bound::Open(0.0), Bound::Closed(1e7)),
    valid_why: "the longest run (`duration`): no block waits longer (1e300 was accepted).",
    widget: absolute(0.01, 10.0, true),
};
