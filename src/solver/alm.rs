//! The augmented Lagrangian loop of one open–close pass (paper Fig. 3): with the contact states
//! fixed, solve, update every multiplier (P1), raise the penalty of slowly converging contacts
//! (P21), until both convergence tests (P23) and (P24) hold. In penalty mode (DDA-3p) the loop
//! is a single solve.

use rayon::prelude::*;

use super::PAR_CONTACTS;
use super::active::Active;
use super::assemble::{StiffnessSync, hold, load_vector};
use super::counters::{Counters, Stopwatch};
use super::step_control::Retry;
use crate::contact::{ContactState, law};
use crate::model::Block;
use crate::params::{Method, Mode, SolverParams};
use crate::physics::linear::{BlockMatrix, SparseCholesky};
use crate::physics::mechanics::{Mat12, Vec12};

/// Iterations of an ALM loop (after the first) at which (P21) may raise penalties. Each raise
/// means a new factorization; later iterations only update λ and reuse it (back-substitutions).
const PENALTY_ROUNDS: u32 = 2;

/// What an ALM loop reads and does not change.
pub(crate) struct AlmInputs<'a> {
    pub params: &'a SolverParams,
    pub blocks: &'a [Block],
    /// K0 and F0 of the attempt.
    pub k0: &'a [Mat12],
    pub f0: &'a [Vec12],
    /// The first step of the run: locked contacts are stuck at a looser tolerance
    /// ([`Active::stick_tolerance`]).
    pub first_step: bool,
    /// The last pass of a non-converging open–close iteration: no more friction holds.
    pub settling: bool,
    /// The sleeping blocks, held where they are (empty: none).
    pub held: &'a [bool],
}

/// The global system of an attempt: K kept in step with the contacts, and its factorization.
pub(crate) struct System<'a> {
    pub kmat: &'a mut BlockMatrix,
    pub sync: &'a mut StiffnessSync,
    pub chol: &'a mut SparseCholesky,
}

/// The result of one ALM loop.
pub(crate) struct AlmOutcome {
    /// The displacement increments D of the last solve.
    pub d: Vec<f64>,
    pub solves: u32,
    /// Both tests held before the iteration cap.
    pub converged: bool,
}

/// Runs the ALM loop of one open–close pass.
pub(crate) fn alm_loop(
    inp: &AlmInputs,
    sys: &mut System,
    active: &mut [Active],
    counters: &mut Counters,
) -> Result<AlmOutcome, Retry> {
    let p = inp.params;
    let cp = &p.contact;
    let mut k_dirty = true;
    for c in active.iter_mut() {
        c.dn_prev = None;
        c.lambda_solved = None;
        c.friction_cap = None;
    }
    for alm_k in 1..=cp.max_alm_iterations {
        // One linear solve an iteration.
        let solves = alm_k;
        let d = solve(inp, sys, active, counters, k_dirty)?;
        let watch = Stopwatch::start();
        let tests = measure(inp, &d, active);
        if p.method == Method::Penalty {
            counters.assembly += watch.elapsed();
            return Ok(AlmOutcome {
                d,
                solves,
                converged: true,
            });
        }
        let converged = tests.penetration && tests.multipliers && tests.stuck;
        // K changes only where (P21) raised a penalty.
        k_dirty = update_contacts(inp, &d, alm_k, converged, active);
        counters.assembly += watch.elapsed();
        if converged || alm_k == cp.max_alm_iterations {
            return Ok(AlmOutcome {
                d,
                solves,
                converged,
            });
        }
    }
    unreachable!("max_alm_iterations is at least 1 (validated)")
}

/// One linear solve: K brought up to date and refactorized if it changed, F assembled, D = K⁻¹F.
fn solve(
    inp: &AlmInputs,
    sys: &mut System,
    active: &[Active],
    counters: &mut Counters,
    k_dirty: bool,
) -> Result<Vec<f64>, Retry> {
    let watch = Stopwatch::start();
    if k_dirty {
        sys.sync
            .update(sys.kmat, inp.k0, &inp.params.contact, inp.blocks, active);
    }
    let mut f = load_vector(inp.params, inp.blocks, inp.f0, active);
    hold(sys.kmat, &mut f, inp.held);
    counters.assembly += watch.elapsed();
    if k_dirty {
        let watch = Stopwatch::start();
        let ok = sys.chol.factorize(sys.kmat);
        counters.totals.timings.factorization += watch.seconds();
        counters.factorizations += 1;
        if ok.is_err() {
            return Err(Retry::NotFinite);
        }
    }
    let watch = Stopwatch::start();
    sys.chol.solve_in_place(&mut f);
    counters.totals.timings.solve += watch.seconds();
    if f.iter().any(|x| !x.is_finite()) {
        return Err(Retry::NotFinite);
    }
    Ok(f)
}

/// The convergence tests of one ALM iteration.
struct Tests {
    /// (P23): every closed contact's |d_n| within ε1·d_n,max of its group.
    penetration: bool,
    /// (P24): ‖λ_k − λ_{k−1}‖ < ε2‖λ_{k−1}‖ (an unchanged zero force vector counts as converged);
    /// for a sliding contact the change is the larger of λ's and that of the normal force its
    /// friction took ([`Active::friction_normal`]).
    multipliers: bool,
    /// Every locked contact is stuck: its tangential displacement in the solve is within its
    /// stick tolerance ([`Active::stick_tolerance`]).
    stuck: bool,
}

/// d_n and N of every contact (5.4), (5.6) for the solution `d`, and the convergence tests,
/// each contact against its own group's d_n,max. One pass over the contacts: at 10 000 of
/// them their records span megabytes, and the tests were three passes.
fn measure(inp: &AlmInputs, d: &[f64], active: &mut [Active]) -> Tests {
    let (p, blocks) = (inp.params, inp.blocks);
    // Per contact in parallel; the sums of (P24) are then formed in the contacts' order, so
    // they do not depend on the thread count.
    let terms: Vec<(bool, f64, f64, bool)> = active
        .par_iter_mut()
        .with_min_len(PAR_CONTACTS)
        .map(|c| {
            let (di, dj) = c.increments(d);
            c.dn = c.kin.penetration(&di, &dj);
            if c.rec.state == ContactState::Open {
                return (true, 0.0, 0.0, true);
            }
            let alm = p.method == Method::Alm;
            if alm {
                c.du = c.ta(blocks) * di - c.tb(blocks) * dj;
            }
            let lambda = if alm { c.rec.lambda } else { 0.0 };
            c.force = lambda + c.rec.penalty * c.dn;
            let within = c.dn.abs() <= p.contact.eps1 * c.dn_max(p);
            if !alm {
                return (within, 0.0, 0.0, true);
            }
            let stuck = c.rec.state != ContactState::Lock
                || tangential_slip(c).norm() <= c.stick_tolerance(p, inp.first_step);
            let new = c.force.max(0.0);
            // A sliding contact's friction came from `friction_normal`, which the warm start
            // does not carry as λ: its change counts too, so that friction has caught up with
            // the normal force when the loop ends.
            let change = if c.rec.state == ContactState::Slide {
                (new - c.rec.lambda)
                    .abs()
                    .max((new - c.friction_normal).abs())
            } else {
                (new - c.rec.lambda).abs()
            };
            (within, change.powi(2), c.rec.lambda.powi(2), stuck)
        })
        .collect();
    let mut t = Tests {
        penetration: true,
        multipliers: false,
        stuck: true,
    };
    let (mut dl2, mut l2) = (0.0, 0.0);
    for (within, a, b, stuck) in terms {
        t.penetration &= within;
        t.stuck &= stuck;
        dl2 += a;
        l2 += b;
    }
    t.multipliers = dl2 == 0.0 || dl2.sqrt() < p.contact.eps2 * l2.sqrt();
    t
}

/// Every contact's updates after the tests of ALM iteration `alm_k`, in one pass: its
/// multiplier and penalty ([`update_multipliers`]), then, if the loop goes on, its stick update
/// ([`absorb_stick_slip`]), and the hold of a reversed friction ([`hold_reversed_friction`]).
/// Each reads and writes the contact's own record only, so doing all three to one contact
/// before the next is the same as doing each to every contact in turn. Returns whether a
/// penalty changed (K must be refactorized).
fn update_contacts(
    inp: &AlmInputs,
    d: &[f64],
    alm_k: u32,
    converged: bool,
    active: &mut [Active],
) -> bool {
    let p = inp.params;
    let goes_on = !converged && alm_k < p.contact.max_alm_iterations;
    active
        .par_iter_mut()
        .with_min_len(PAR_CONTACTS)
        .map(|c| {
            let raised = update_multipliers(p, (inp.blocks, d), alm_k, converged, c);
            if goes_on {
                absorb_stick_slip(inp, c);
            }
            if !inp.settling {
                hold_reversed_friction(inp, c);
            }
            raised
        })
        .reduce(|| false, |a, b| a || b)
}

/// `penalty_floor` of the step: none in static mode. The floor is there for motion: penalties
/// ratcheted up to γE by a standing wall's micrometre rocking meet the next impact, and raised
/// penalties jam a sliding jointed mass. Static mode has neither, and there the floor kept
/// (P21) from converging the contacts whose forces compatibility alone fixes: the confinement
/// of a column in a rigid shaft (σ_h = ν/(1−ν)·σ_v) came out at 79–95 % of its value, at 100 %
/// without it (`tests/confinement.rs`). The equilibrium stage's static steps (the joints held)
/// keep it: without it the stage of `scenes/jointed_mass_1000.toml` took 1010 s instead of
/// about 220, and a confined column comes out of the stage at 19–71 % of its σ_h.
fn penalty_floor(p: &SolverParams) -> f64 {
    match p.mode {
        Mode::Static if !p.joints_held => 0.0,
        _ => p.contact.penalty_floor,
    }
}

/// (P1) λ_k = λ_{k−1} + p_n d_n, kept non-negative, for a closed contact; and (P21): its penalty
/// is raised if its penetration does not fall fast enough. Returns whether the penalty changed.
fn update_multipliers(
    p: &SolverParams,
    (blocks, d): (&[Block], &[f64]),
    alm_k: u32,
    converged: bool,
    c: &mut Active,
) -> bool {
    let cp = &p.contact;
    if c.rec.state == ContactState::Open {
        return false;
    }
    let mut raised = false;
    let lambda_before = c.rec.lambda;
    c.lambda_solved = Some(c.rec.lambda);
    c.rec.lambda = c.force.max(0.0);
    c.friction_normal = c.rec.lambda;
    // Not for a contact whose penetration is below `penalty_floor` of the tolerance
    // ε1·d_n,max (0.01 by default): over many steps the ratio test ratcheted every penalty of
    // a standing wall up to γE, a stiffness that turned a 4 µm motion into meganewtons at the
    // next impact, and raised penalties jam a sliding jointed mass at its blocks' edges. The
    // floor has a price in stacked blocks at short steps: where 2M/Δt² dwarfs p_n,1 (Δt = 2 ms
    // for a column of 1.2 × 1.2 × 2 m blocks) each iteration shrinks a stack's penetration by
    // a few per cent, the loop ends at its cap with λ still moving, and the column rocks at
    // centimetres a second; with the floor at 0, (P21) stiffens its contacts and it stays
    // still (`penalty_floor`'s table entry, `tests/stable_dynamics.rs`). Nor for a closed
    // contact the solve pulls apart (d_n < 0): a stiffer penalty only lets it hold more
    // tension, and the open–close check, not the penalty, deals with it. Slabs sliding
    // together rock on their joints by micrometres; raised there a hundredfold, the penalties
    // swung their forces by 10⁵ N and the iteration settled on states that stopped the slabs
    // within a step.
    if let Some(prev) = c.dn_prev
        && alm_k <= PENALTY_ROUNDS + 1
        && !converged
        && (c.dn > 0.0 || -c.dn > cp.eps1 * c.dn_max(p))
        && c.dn.abs() > cp.beta * prev.abs()
        && c.dn.abs() > penalty_floor(p) * cp.eps1 * c.dn_max(p)
    {
        raised = raise_penalty(
            c,
            (c.rec.penalty * cp.alpha).min(cp.gamma * c.young),
            p,
            (blocks, d),
        );
    }
    // A loop that ends at its cap with this contact's λ still moving by more than ε2 of itself,
    // where its penalty is below its lighter block's inertia 2m/Δt_max²: each (P1) update moves
    // λ by p_n·d_n, and where the inertia dwarfs p_n the solve answers with a d_n only a few
    // per cent smaller, so λ crept by 4 % an iteration and every loop ended at its cap for a
    // 2 m block sliding on 30° at Δt_max = 1 ms, which then went 3.5 % too far in 1 s (8.5 %
    // at 0.5 ms). The floor above keeps (P21) away from such small penetrations, and rightly
    // in a standing wall; here the penalty goes to the inertia (K holds that stiffness
    // already) for the next pass and, by the warm start, the next steps. Only where d_n
    // creeps (the same sign, shrinking too slowly for the cap): raised at every loop that ended
    // at its cap, penalties jammed the shipped jointed slope's sliding slabs, the least-moved of
    // its free blocks going 0.69 m in 1 s instead of 0.93 (Coulomb: 0.95).
    if !converged
        && alm_k == cp.max_alm_iterations
        && c.force > 0.0
        && (c.rec.lambda - lambda_before).abs() > cp.eps2 * c.rec.lambda
        && c.rec.penalty < c.inertia
        && creeping(c, cp)
    {
        raised |= raise_penalty(c, c.inertia.min(cp.gamma * c.young), p, (blocks, d));
    }
    c.dn_prev = Some(c.dn);
    raised
}

/// Raises a contact's penalty to `target` if that is higher; returns whether it did.
fn raise_penalty(
    c: &mut Active,
    target: f64,
    p: &SolverParams,
    (blocks, d): (&[Block], &[f64]),
) -> bool {
    if target > c.rec.penalty {
        c.set_penalty(target, &p.contact);
        // The spring's reference moved with p_τ, and T_b with it.
        c.du = c.relative_displacement(d, blocks);
        true
    } else {
        false
    }
}

/// d_n shrinking steadily and too slowly for the loop's cap: the same sign as in the previous
/// iteration, and at most a factor ε2^(1/cap) smaller (0.79 by default).
fn creeping(c: &Active, cp: &crate::params::ContactParams) -> bool {
    let Some(prev) = c.dn_prev else {
        return false;
    };
    let slow = cp.eps2.powf(1.0 / f64::from(cp.max_alm_iterations));
    prev * c.dn > 0.0 && c.dn.abs() <= prev.abs() && c.dn.abs() > slow * prev.abs()
}

/// The tangential part of a closed contact's relative displacement in the last solve, m.
fn tangential_slip(c: &Active) -> crate::physics::geometry::Vec3 {
    let n = c.cand.normal;
    c.du - n * n.dot(&c.du)
}

/// The augmented Lagrangian update of a locked contact's shear, as (P1) is of its normal force:
/// a locked contact is stuck, so the tangential displacement the last solve gave it goes into
/// the spring's reference point (its multiplier, λ_τ = p_τ·(x_a − reference)), and the loop
/// iterates until that displacement falls below ε1·d_n,max. With the shear spring alone
/// (p_τ = 0.4 p_n,1) a new contact stayed locked below its capacity while its block moved: a
/// block pushed by 1.5 μmg travelled 0.6 % too far in 1 s, one at a factor of safety of 0.9 on
/// 30° 3 % too far in 2 s, all of it gained in the first steps. The paper enforces only the
/// normal constraint this way; its shear is a penalty spring.
///
/// The tolerance ([`Active::stick_tolerance`]) is the normal one, ε1·d_n,max, except in the first
/// step of a run, where every contact takes up its load at once: there it is f0·w0, the slip
/// the contact law does not count. With ε1·d_n,max there too, 5 × 10 m blocks took up their load
/// with 0.12 mm of slip; with f0·w0 in every step, a struck wall of 100 blocks needed 158 solves
/// a step instead of 99 (57 with no stick update).
fn absorb_stick_slip(inp: &AlmInputs, c: &mut Active) {
    if c.rec.state == ContactState::Lock {
        let slip = tangential_slip(c);
        c.rec.reference -= slip;
        if !inp.params.joints_held && !inp.first_step {
            c.cap_shear(inp.params);
        }
    }
}

/// A sliding contact whose slip has reversed is in the wrong state, and its friction, from
/// λ_{k−1} (5.8), can feed back: where friction presses blocks into other contacts (a wedge) the
/// loop λ → friction → λ grew ×1.4 an iteration in a struck wall, reaching metres of
/// displacement within 20 iterations, and the open–close check then classified every contact
/// from that solution. The friction of such a contact is held at its present value for the rest
/// of the pass (a change of F only: no refactorization); the open–close check locks it.
fn hold_reversed_friction(inp: &AlmInputs, c: &mut Active) {
    if c.rec.state != ContactState::Slide || c.frozen || c.friction_cap.is_some() {
        return;
    }
    if law::reversed(&c.du, &c.rec.tau, c.slip_tolerance(inp.params)) {
        c.friction_cap = Some(c.rec.lambda);
    }
}
