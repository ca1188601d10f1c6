//! The `[solver.contact]` and `[joint]` keys of the parameter table (see [`super`]).

use super::{Bound, Interval, Param, Value, Widget, WidgetRange, absolute, assign};

pub const INITIAL_PENALTY: Param = Param {
    key: "solver.contact.initial_penalty",
    label: "p_n,1",
    unit: "N/m",
    doc: "Initial normal penalty of a new contact (ALM), and the fixed penalty in penalty mode. \
          The paper uses p_n,1 = 0.01 E (the same as DDA-3p) and warns it should not be too \
          small.",
    default: Value::Real(2.0e8),
    get: |p| Value::Real(p.contact.initial_penalty),
    set: |p, text| assign(text, &mut p.contact.initial_penalty),
    valid: Interval::new(Bound::Closed(1.0), Bound::Closed(1e16)),
    valid_why: "outside it the penalty is no contact spring for any material dda3d takes \
          (E in [1e2, 1e13] Pa): at 1e30 or 1e300 N/m the first solve was not finite; the scene \
          also holds it within [1e-6, γ] times its stiffest material's E (a scene that does \
          not set it and whose rock is too soft or too stiff for the default is told so, with \
          the paper's 0.01 E for its rock).",
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
    set: |p, text| assign(text, &mut p.contact.alpha),
    valid: Interval::new(Bound::Open(1.0), Bound::Closed(1e3)),
    valid_why: "at 10³ two growths already take the paper's p_n,1 = 0.01·E past its cap γ·E = \
                100·E, so a larger α only jumps to the cap sooner (1e300 was accepted and \
                changed the run).",
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
    set: |p, text| assign(text, &mut p.contact.beta),
    valid: Interval::new(Bound::Open(0.0), Bound::Open(1.0)),
    valid_why: "",
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
    set: |p, text| assign(text, &mut p.contact.gamma),
    valid: Interval::new(Bound::Open(0.0), Bound::Closed(1e6)),
    valid_why: "a cap above 10⁶ E lets a contact's stiffness swamp its blocks' in K beyond what \
          f64 solves (at 1e300 the solution was not finite).",
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
    set: |p, text| assign(text, &mut p.contact.eps1),
    valid: Interval::new(Bound::Open(0.0), Bound::Open(1.0)),
    valid_why: "ε1 ≥ 1 would accept a penetration as deep as the whole contact window d_n,max, \
          beyond which a contact is not found at all.",
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
    set: |p, text| assign(text, &mut p.contact.eps2),
    valid: Interval::new(Bound::Open(0.0), Bound::Open(1.0)),
    valid_why: "ε2 ≥ 1 would take a 100 % change of the contact forces between two iterations for \
          convergence.",
    widget: absolute(1e-4, 0.5, true),
};

pub const PENALTY_FLOOR: Param = Param {
    key: "solver.contact.penalty_floor",
    label: "(P21) floor",
    unit: "ε1·d_n,max",
    doc: "(P21) raises a contact's penalty only where its penetration exceeds this fraction of \
          the tolerance ε1·d_n,max. 0.01 keeps the penalties of a sliding jointed mass low: \
          raised, they jam its blocks at their edges (the shipped jointed slope's free blocks \
          travel a median 0.76 m by 1 s at 0, one of them not at all, and 0.94 m at 0.01; \
          Coulomb 0.94 m). 0 lets (P21) stiffen the contacts of stacked blocks at short time \
          steps, where each ALM iteration shrinks their penetration by a few per cent: a column \
          of four 1.2 × 1.2 × 2 m blocks on a fixed one at Δt = 2 ms rocks at 4 cm/s at 0.01, \
          still at 0 (at 10 ms it is still at both). Set 0 for walls and columns without a \
          sliding mass run at short steps. Static mode has no floor, so that the contacts whose \
          forces compatibility alone fixes converge (a column in a rigid shaft takes \
          σh = ν/(1−ν)·σv); the equilibrium stage keeps it. The paper has no floor.",
    default: Value::Real(0.01),
    get: |p| Value::Real(p.contact.penalty_floor),
    set: |p, text| assign(text, &mut p.contact.penalty_floor),
    valid: Interval::new(Bound::Closed(0.0), Bound::Closed(1.0)),
    valid_why: "above 1 a contact's penetration would have to exceed its whole tolerance \
          ε1·d_n,max before its penalty could grow, and the ALM loop would end first.",
    widget: absolute(0.0, 0.05, false),
};

pub const SHEAR_PENALTY_RATIO: Param = Param {
    key: "solver.contact.shear_penalty_ratio",
    label: "p_τ / p_n,1",
    unit: "",
    doc: "Shear spring of locked contacts relative to p_n,1. The paper does not give p_τ; Shi's \
          code uses p_n / 2.5.",
    default: Value::Real(1.0 / 2.5),
    get: |p| Value::Real(p.contact.shear_penalty_ratio),
    set: |p, text| assign(text, &mut p.contact.shear_penalty_ratio),
    valid: Interval::new(Bound::Closed(1e-4), Bound::Closed(100.0)),
    valid_why: "below 10⁻⁴ a locked contact holds nothing in shear, above 100 its shear spring \
          swamps the normal one (at 1e300 the first solve was not finite).",
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
    set: |p, text| assign(text, &mut p.contact.max_alm_iterations),
    valid: Interval::new(Bound::Closed(1.0), Bound::Closed(1000.0)),
    valid_why: "each iteration is a linear solve and the paper's ALM converges in a few; the cap \
          bounds the cost of a pass that does not converge.",
    widget: absolute(1.0, 100.0, false),
};

pub const MAX_OPEN_CLOSE_ITERATIONS: Param = Param {
    key: "solver.contact.max_open_close_iterations",
    label: "Open–close passes",
    unit: "",
    doc: "Open–close passes before the step is redone with {DT_CUT}·Δt (Shi: 6 + 2; walls of many \
          blocks need 10–25 at an impact). If at most {SETTLE_PERCENT} % of the contacts still \
          change then, they are settled closed and locked instead; contacts the solve after \
          leaves in tension are opened and solved again, and the step is redone shorter if it \
          still pulls after three.",
    default: Value::Count(30),
    get: |p| Value::Count(p.contact.max_open_close_iterations),
    set: |p, text| assign(text, &mut p.contact.max_open_close_iterations),
    valid: Interval::new(Bound::Closed(1.0), Bound::Closed(1000.0)),
    valid_why: "each pass solves at least once; Shi uses 8, a struck wall 25, and a step still \
          changing after 1000 is redone with a shorter Δt anyway.",
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
    set: |p, text| assign(text, &mut p.contact.warm_start),
    valid: Interval::ANY,
    valid_why: "",
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
    set: |p, text| assign(text, &mut p.contact.close_threshold),
    valid: Interval::new(Bound::Closed(0.0), Bound::Closed(0.01)),
    valid_why: "Shi's s0 is 2·10⁻⁴; at 0.01 (the paper's δ) a contact would move as far as a \
          whole step may before its state changes.",
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
    set: |p, text| assign(text, &mut p.contact.open_threshold),
    valid: Interval::new(Bound::Closed(0.0), Bound::Closed(0.01)),
    valid_why: "Shi's s0 is 2·10⁻⁴; at 0.01 (the paper's δ) a contact would move as far as a \
          whole step may before its state changes.",
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
    set: |p, text| assign(text, &mut p.joint.friction_angle),
    valid: Interval::new(Bound::Closed(0.0), Bound::Open(90.0)),
    valid_why: "",
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
    set: |p, text| assign(text, &mut p.joint.cohesion),
    valid: Interval::new(Bound::Closed(0.0), Bound::Closed(1e9)),
    valid_why: "intact rock's own cohesion is some tens of MPa: a joint of more is welded, not a \
                joint (1e308 was accepted).",
    widget: absolute(0.0, 1e8, true),
};
