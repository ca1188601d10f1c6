//! The open–close check (reference §6.1): after each ALM loop, every contact is classified by
//! the contact law ([`crate::contact::law`]) from the solution, and the pass is repeated until
//! no contact changes state. Contacts that keep cycling are settled; at the pass limit the
//! stragglers are settled or the attempt is redone.

use std::collections::{BTreeMap, BTreeSet};

use rayon::prelude::*;

use super::PAR_CONTACTS;
use super::active::Active;
use super::counters::{Counters, debug_log};
use super::step_control::{Retry, stop_within};
use crate::contact::ContactState;
use crate::contact::law::{self, LawParams, Observation, Transition};
use crate::model::Block;
use crate::params::step_rules::SETTLE_FRACTION;
use crate::params::{Method, SolverParams};
use crate::physics::geometry::Vec3;

/// State changes a contact may make in one attempt before it is settled (DDA-3a). Settling is
/// the last resort against a cycle, and it has a price: a contact settled locked holds whatever
/// shear its spring has for the rest of the attempt, beyond its Mohr–Coulomb strength too. At 2
/// the shipped jointed slope settled 8659 contacts in its first second, and locked contacts on
/// J1 (φ 25°) held up to 20 kN of shear on 0.7 kN of normal force: its free blocks travelled a
/// median 0.835 m by 1 s (the least 0.63 m) against Coulomb's 0.95 m. At 6 they travel
/// 0.938 m (the least 0.93 m), with fewer passes and solves.
const MAX_FLIPS: u8 = 6;

/// The same for DDA-3p, the baseline, kept as it was: at 6 the rockfall under DDA-3p took 56
/// Δt cuts instead of 2, and its soft penalties jam a jointed slope either way (the small
/// slope's free blocks: a median 0.15 m by 1 s at 6, 0.14 m at 2).
const MAX_FLIPS_PENALTY: u8 = 2;

/// A contact that began to slide in this step and whose friction direction τ turned by more
/// than this in a pass, degrees, counts as changed (DDA-3a, outside the equilibrium stage): the
/// pass is solved again with the turned τ. At the onset τ is the direction of the spring's
/// extension, which the blocks' elastic response sets a few degrees off the direction they
/// then slide in, and the friction's lateral stiffness k⊥ (about p_τ while the slip is small)
/// held the block across it; with τ turned only between steps, a sliding wedge took steps to
/// line its friction up, and started a step late: 8.6 % short of Hoek–Bray's travel at 0.5 s
/// (2.8 % now; F = 0.905, the reference's wedge cut with a tension crack).
const ONSET_TURN: f64 = 3.0;

/// A contact that began to slide in this step and whose friction's lateral stiffness k⊥ fell
/// by more than this factor in a pass counts as changed in the same way (DDA-3a, outside the
/// equilibrium stage). k⊥ is the friction over the slip (its Newton tangent), and at the onset
/// the slip is the locked pass's, next to nothing: k⊥ starts at p_τ, and with τ a few degrees
/// off the slide, the corners' k⊥ held a small block across the slide for its first step
/// (10 cm blocks 1–17 % short at 1 s, F 0.5–0.95 on 10–60°; within 0.01 % now). Solved again
/// with the k⊥ of the slip it made, the block slides; a handful of passes in its first step.
/// Only where p_τ is far too stiff for the contact ([`softens`]).
const ONSET_SOFTENING: f64 = 2.0;

/// A contact that starts to slide (DDA-3a, outside the equilibrium stage) and whose p_τ is far
/// too stiff for it ([`softens`]: a small or light block against the model's slip tolerance)
/// takes as its sliding direction its block pair's resultant locked shear, in its tangent plane,
/// where that lies within this many degrees of its own spring's extension. The corners of a
/// block under its own weight spread elastically, and their springs' extensions fan out by
/// 15–25° on a 10 cm block of soft rock (E = 1 GPa): each corner's k⊥ then held the block
/// across its neighbours' directions, and slips below f0·w0 do not turn τ, so it stood for three
/// steps (5.8 % short at 1 s, F = 0.9 on 20°; exact now). The resultant is the direction in which
/// the pair slides as a whole; a contact of a block that turns on the pair (its own extension far
/// from the resultant) keeps its own. Applied to every onset contact, it cost the shipped
/// jointed slope 11 % more open–close passes for no change in its travel.
const ONSET_RESULTANT: f64 = 45.0;

/// What the check of one pass reads.
pub(crate) struct CheckInputs<'a> {
    pub params: &'a SolverParams,
    pub blocks: &'a [Block],
    /// Warm start in effect (ALM with `warm_start`): a contact closed at the start of the step
    /// and reopened in an earlier pass keeps its adapted penalty when it closes again.
    pub warm: bool,
    /// For the debug log.
    pub time: f64,
    pub dt: f64,
    pub pass: u32,
    /// The friction of contacts that began to slide in the step is iterated to its direction
    /// ([`ONSET_TURN`]), and that of any sliding contact while it pushes across its direction
    /// beyond its strength ([`pushed_beyond_friction`]): DDA-3a, outside the equilibrium stage.
    pub onset_turns: bool,
    /// Steps carry velocity, and a sliding contact that speeds up does not stop
    /// ([`law::speeds_up`]): dynamic steps outside the equilibrium stage. (For DDA-3a only
    /// until a 10 cm block on 30° at Δt_max = 1 ms, sliding less than the slip tolerance a
    /// step, stopped every step under DDA-3p: 9·10⁻⁶ m of Coulomb's 0.47 m in 1 s.)
    pub carries: bool,
    /// A contact sliding since the step began records when its motion stopped ([`stop_within`]):
    /// dynamic steps outside the equilibrium stage, above the Δt floor, not already cut for a
    /// stop.
    pub stop_cuts: bool,
    /// Block pairs whose intact cohesive joint holds as a whole ([`holding_joints`]); filled
    /// by [`check`] itself.
    pub holding: &'a BTreeSet<(usize, usize)>,
    /// DDA-3p: the free blocks with a sliding contact ([`sliding_blocks`]); filled by [`check`]
    /// itself.
    pub sliding_blocks: &'a BTreeSet<usize>,
    /// The resultant shear force of each block pair's locked springs, on the lower-numbered
    /// block ([`pair_shears`]); filled by [`check`] itself.
    pub pair_shear: &'a BTreeMap<(usize, usize), Vec3>,
}

/// The block pairs whose intact, cohesive, locked contacts together carry less shear than their
/// joint's strength Σ(N tan φ + c·A): none of those contacts slides on its own. Cohesion is lost
/// at a contact's first slip, so contact by contact the least pressed corners of a block (the
/// uphill ones) failed first and took the joint with them: a 1 × 1 × 0.5 m block on 30° with
/// φ = 20° slid at 1.43 times the cohesion limit equilibrium needs. The joint is judged whole,
/// as limit equilibrium does; once it fails, its contacts are judged one by one again.
fn holding_joints(inp: &CheckInputs, d: &[f64], active: &[Active]) -> BTreeSet<(usize, usize)> {
    let mut sums: BTreeMap<(usize, usize), (Vec3, f64)> = BTreeMap::new();
    for c in active {
        let cohesion = c.cohesion(inp.params);
        if c.frozen || c.rec.state != ContactState::Lock || cohesion <= 0.0 {
            continue;
        }
        let strength = c.force.max(0.0) * c.tan_phi(inp.params) + cohesion;
        let sum = sums.entry(pair_key(c)).or_insert((Vec3::zeros(), 0.0));
        *sum = (sum.0 + spring_force_on_lower(inp, d, c), sum.1 + strength);
    }
    sums.into_iter()
        .filter(|(_, (shear, strength))| shear.norm() <= *strength)
        .map(|(pair, _)| pair)
        .collect()
}

/// DDA-3p: the free blocks that slide on one of their contacts. A contact of such a block that
/// closes while its blocks move past each other closes sliding (`law::closes_sliding`): the
/// block slides, and the corner it brings onto a face slides with it. Elsewhere it closes
/// locked, as in Shi's DDA: a block rocking on its soft springs (5 m on 30°, φ 60°, without the
/// equilibrium stage) landed on sliding corners, walked down the slope and crept 66 mm in 9 s
/// (0.3 mm locked).
fn sliding_blocks(params: &SolverParams, blocks: &[Block], active: &[Active]) -> BTreeSet<usize> {
    if params.method != Method::Penalty {
        return BTreeSet::new();
    }
    active
        .iter()
        .filter(|c| c.rec.state == ContactState::Slide)
        .flat_map(|c| {
            let (i, j) = c.blocks();
            [i, j]
        })
        .filter(|&k| !blocks[k].fixed)
        .collect()
}

/// The contact law's thresholds for `c`, with DDA-3p's closing rule ([`sliding_blocks`]).
fn law_of(params: &SolverParams, c: &Active, sliding: &BTreeSet<usize>) -> LawParams {
    let mut law = c.law(params);
    if params.method == Method::Penalty {
        let (i, j) = c.blocks();
        law.close_sliding = sliding.contains(&i) || sliding.contains(&j);
    }
    law
}

/// A contact's block pair, the lower-numbered block first.
fn pair_key(c: &Active) -> (usize, usize) {
    let (i, j) = c.blocks();
    (i.min(j), i.max(j))
}

/// 1 where the contact's block i is its pair's lower-numbered block, −1 otherwise: the sign
/// that turns the contact's tangential quantities (of i against j) into the pair's.
fn lower_sign(c: &Active) -> f64 {
    let (i, j) = c.blocks();
    if i < j { 1.0 } else { -1.0 }
}

/// A locked contact's shear spring force p_τ·N(Δ + Δu_ab) in the solution `d`, on its pair's
/// lower-numbered block, N.
fn spring_force_on_lower(inp: &CheckInputs, d: &[f64], c: &Active) -> Vec3 {
    let extension = c.spring_extension(&c.relative_displacement(d, inp.blocks));
    extension * (inp.params.contact.shear_penalty(c.rec.penalty, c.inertia) * lower_sign(c))
}

/// Classifies every contact from the solution `d` and applies the verdicts. Returns whether a
/// contact changed state (another pass is needed).
pub(crate) fn check(
    inp: &CheckInputs,
    d: &[f64],
    active: &mut [Active],
    counters: &mut Counters,
) -> bool {
    let holding = holding_joints(inp, d, active);
    let sliding_blocks = sliding_blocks(inp.params, inp.blocks, active);
    let pair_shear = if inp.onset_turns {
        pair_shears(inp, d, active)
    } else {
        BTreeMap::new()
    };
    let inp = &CheckInputs {
        holding: &holding,
        sliding_blocks: &sliding_blocks,
        pair_shear: &pair_shear,
        ..*inp
    };
    // Each contact's verdict depends on its own record and the solution alone, so contacts are
    // checked in parallel (in order when the debug log is on, so that its lines keep their
    // order); `any` and the count of settled contacts do not depend on the order.
    let one = |c: &mut Active| check_one(inp, d, c);
    let (changed, frozen) = if debug_log() {
        active
            .iter_mut()
            .map(one)
            .fold((false, 0), |(a, n), (b, m)| (a || b, n + m))
    } else {
        active
            .par_iter_mut()
            .with_min_len(PAR_CONTACTS)
            .map(one)
            .reduce(|| (false, 0), |(a, n), (b, m)| (a || b, n + m))
    };
    counters.totals.frozen_contacts += frozen;
    changed
}

/// The resultant of each block pair's locked shear springs, p_τ·N(Δ + Δu_ab) summed over its
/// locked contacts, as a force on the pair's lower-numbered block ([`ONSET_RESULTANT`]).
fn pair_shears(inp: &CheckInputs, d: &[f64], active: &[Active]) -> BTreeMap<(usize, usize), Vec3> {
    let locked = |c: &&Active| !c.frozen && c.rec.state == ContactState::Lock;
    // Only the pairs with a contact the rule may apply to: none in most rock masses.
    let wanted: BTreeSet<(usize, usize)> = active
        .iter()
        .filter(locked)
        .filter(|c| softens(inp, c))
        .map(pair_key)
        .collect();
    let mut sums: BTreeMap<(usize, usize), Vec3> = BTreeMap::new();
    if wanted.is_empty() {
        return sums;
    }
    for c in active.iter().filter(locked) {
        if !wanted.contains(&pair_key(c)) {
            continue;
        }
        *sums.entry(pair_key(c)).or_insert_with(Vec3::zeros) += spring_force_on_lower(inp, d, c);
    }
    sums
}

/// The sliding direction of a contact that starts to slide along `own` (its spring's
/// extension): the direction of its block pair's resultant shear in its tangent plane, where
/// that lies within [`ONSET_RESULTANT`] of `own`.
fn onset_direction(inp: &CheckInputs, c: &Active, own: Vec3) -> Vec3 {
    let Some(r) = inp.pair_shear.get(&pair_key(c)) else {
        return own;
    };
    let r = r * lower_sign(c);
    let n = c.cand.normal;
    let t = r - n * n.dot(&r);
    if t.norm() > 0.0 && t.normalize().dot(&own) > ONSET_RESULTANT.to_radians().cos() {
        t.normalize()
    } else {
        own
    }
}

/// Whether a sliding contact's friction, of stiffness k⊥ across the τ it was solved with, pushed
/// across that τ by more than the friction F itself (k⊥·|slip⊥| > F): it then resisted the slip
/// beyond Mohr–Coulomb, and the pass is solved again with the τ it turned to. Ended there, the
/// base's friction on a struck block exceeded Mohr–Coulomb by up to 15 % in the impact's step
/// (3.4 % now, `tests/collisions.rs`): its corners had just begun to slide, τ a degree off their
/// slip and k⊥ still p_τ. A slip across τ within the slip tolerance f0·w0 is no turn of the
/// slip: counted, the struck wall of 80 in `tests/rockfall.rs` settled 50 of its 280 steps at
/// the pass limit (4 of 234 without the rule), re-solving contacts that pushed a few newtons or
/// less across τ, most on no normal force.
fn pushed_beyond_friction(
    slip: &Vec3,
    tau_before: &Vec3,
    lateral_before: f64,
    friction: f64,
    slip_tolerance: f64,
) -> bool {
    let across = (slip - tau_before * tau_before.dot(slip)).norm();
    across > slip_tolerance && lateral_before * across > friction
}

/// Checks one contact: whether it changed state, and whether it was settled in another state.
fn check_one(inp: &CheckInputs, d: &[f64], c: &mut Active) -> (bool, u64) {
    c.changed = false;
    let clear = !c.frozen && c.reconsider_face(inp.params, d);
    let n = c.cand.normal;
    let du = c.relative_displacement(d, inp.blocks);
    c.slip = du - n * n.dot(&du);
    if c.frozen {
        c.rec.normal_force = c.force;
        return (false, 0);
    }
    // DDA-3p's friction takes the normal force of the previous solve, so a contact that closed
    // sliding in the last check slid without friction in this solve: it is solved once more
    // with its force. Ended there, a 1 m block launched at 2 m/s along a flat base went 5.6 %
    // beyond Coulomb's stopping distance (0.15 % now).
    let unloaded = inp.params.method == Method::Penalty
        && c.rec.state == ContactState::Slide
        && c.rec.normal_force == 0.0
        && c.force > 0.0;
    let (verdict, shear) = if clear {
        // The vertex has left block j through another face: it is no longer in contact.
        c.rec.normal_force = c.force;
        (Transition::Open, Vec3::zeros())
    } else {
        classify(inp, c, &du)
    };
    let before = c.rec.state;
    let (tau_before, lateral_before) = (c.rec.tau, c.lateral);
    // A contact that slid through this solve, as it did when the step began: did its friction
    // outlast its motion? (Read from the solve it slid in; one that sticks keeps the verdict of
    // the solve it stuck after.)
    if inp.stop_cuts && before == ContactState::Slide && c.start.state == ContactState::Slide {
        let sliding_on = matches!(
            verdict,
            Transition::Keep | Transition::Turn { .. } | Transition::Stick
        );
        c.stop_fraction = sliding_on
            .then(|| {
                let carried = c.carried(inp.blocks, inp.dt).dot(&c.rec.tau);
                stop_within(
                    carried,
                    c.slip.dot(&c.rec.tau),
                    c.slip_tolerance(inp.params),
                )
            })
            .flatten();
    }
    apply(inp, c, verdict, shear);
    if c.rec.state == before {
        // A contact that began to slide in this step and whose friction turned by more than
        // ONSET_TURN, or softened across τ by more than ONSET_SOFTENING, is solved again.
        let onset = inp.onset_turns
            && before == ContactState::Slide
            && c.start.state != ContactState::Slide;
        let again = onset
            && (tau_before.dot(&c.rec.tau) < ONSET_TURN.to_radians().cos()
                || (c.lateral * ONSET_SOFTENING < lateral_before && softens(inp, c)));
        let again = again
            || (inp.onset_turns
                && c.rec.state == ContactState::Slide
                && pushed_beyond_friction(
                    &c.slip,
                    &tau_before,
                    lateral_before,
                    c.sliding_friction(inp.params),
                    c.slip_tolerance(inp.params),
                ));
        // Not `changed`: at the pass limit a turning (or unloaded) contact is not a straggler
        // to settle.
        return (again || unloaded, 0);
    }
    c.changed = true;
    c.flips += 1;
    if debug_log() {
        log_change(inp, c, before, &tau_before);
    }
    let mut frozen = 0;
    let max_flips = match inp.params.method {
        Method::Alm => MAX_FLIPS,
        Method::Penalty => MAX_FLIPS_PENALTY,
    };
    if c.flips > max_flips {
        // A contact that keeps cycling (typically an edge–edge and a vertex–face contact of one
        // block pair taking the load in turn) is settled for the rest of the attempt (see
        // `law::Settled`); one whose spring has just exceeded its Mohr–Coulomb strength stays
        // sliding, with its friction at capacity along that shear. Settled locked beyond its
        // strength, it held blocks free to slide on their joint: the front blocks of a jointed
        // slope, at a factor of safety of 0.67, stood for 2 s.
        if !matches!(verdict, Transition::Slide { .. }) {
            c.settle(inp.params);
        }
        frozen = (before != c.rec.state) as u64;
        c.flips = 0;
        c.frozen = true;
    }
    (true, frozen)
}

/// Whether a contact's k⊥ may be iterated at its onset ([`ONSET_SOFTENING`]): its spring's
/// elastic range N tan φ / p_τ is below the slip tolerance, so that any slip the law can see is
/// beyond it and k⊥ = p_τ is far too stiff. A heavily loaded contact's range is wider (10⁻⁴ m on
/// the shipped jointed slope, against f0·w0 = 5·10⁻⁶ m) and p_τ is of the right order there:
/// iterated too, the slice of that slope in `tests/joint_sets.rs` let a block of its stable
/// mass move 17 mm in 1 s (0.13 mm as it is) and a free block fall 9 % short.
fn softens(inp: &CheckInputs, c: &Active) -> bool {
    let p_tau = inp.params.contact.shear_penalty(c.rec.penalty, c.inertia);
    law::fine_range(c.force, p_tau, &c.law(inp.params), 1.0)
}

/// The contact law's verdict on one contact, and the shear spring's extension N(Δ + Δu_ab) of
/// a locked one.
fn classify(inp: &CheckInputs, c: &mut Active, du: &Vec3) -> (Transition, Vec3) {
    let cp = &inp.params.contact;
    let closed = c.rec.state.is_closed();
    if closed {
        c.rec.normal_force = c.force;
    }
    let shear = if c.rec.state == ContactState::Lock {
        c.spring_extension(du)
    } else {
        Vec3::zeros()
    };
    let seen = Observation {
        state: c.rec.state,
        penetration: c.dn,
        normal_force: c.force,
        shear,
        shear_stiffness: cp.shear_penalty(c.rec.penalty, c.inertia),
        cohesion: if c.rec.intact && inp.holding.contains(&pair_key(c)) {
            f64::INFINITY
        } else {
            c.cohesion(inp.params)
        },
        slip: c.slip,
        tau: c.rec.tau,
        lambda: c.rec.lambda,
        slid_before: c.start.state == ContactState::Slide,
        restarted: c.stopped,
        carried: (inp.carries && c.rec.state == ContactState::Slide)
            .then(|| c.carried(inp.blocks, inp.dt)),
    };
    let law = law_of(inp.params, c, inp.sliding_blocks);
    (law::classify(&seen, &law), shear)
}

/// Applies the law's verdict to the contact's record.
fn apply(inp: &CheckInputs, c: &mut Active, verdict: Transition, shear: Vec3) {
    if c.rec.state == ContactState::Lock && verdict != Transition::Open {
        c.shear = shear;
    }
    match verdict {
        Transition::Keep => {}
        Transition::Close => close(inp, c),
        Transition::CloseSliding { tau } => {
            close(inp, c);
            c.rec.state = ContactState::Slide;
            c.rec.tau = tau;
        }
        Transition::Open => c.open(),
        Transition::Slide { tau } => {
            c.rec.state = ContactState::Slide;
            c.rec.tau = if softens(inp, c) {
                onset_direction(inp, c, tau)
            } else {
                tau
            };
            c.rec.intact = false;
        }
        // The contact carries on with the friction it had (see [`Active::stick`]).
        Transition::Stick => c.stick(inp.params),
        Transition::Stop => {
            c.stick(inp.params);
            c.stopped = true;
        }
        Transition::Turn { tau } => c.rec.tau = tau,
    }
    // k⊥ follows the slip this solve gave (a contact that has just begun to slide from
    // locked has next to none: it starts as stiff across τ as its spring was), or, in the step
    // a light contact began to slide from rest, the slip it is expected to make ([`onset_slip`]).
    if c.rec.state == ContactState::Slide {
        let onset = matches!(verdict, Transition::Slide { .. })
            && c.start.state != ContactState::Slide
            && inp.onset_turns
            && softens(inp, c);
        if onset {
            c.onset_slip = c.onset_slip.max(onset_slip(inp, c, &shear));
        }
        c.set_lateral(inp.params, c.slip.norm().max(c.onset_slip));
    }
}

/// At the open–close pass limit: if more than [`SETTLE_FRACTION`] of the contacts still changed
/// in the last pass (and the step is above the Δt floor), the attempt is redone with a shorter
/// step (Shi). Otherwise, and always at the floor, the contacts that still changed are settled
/// closed and locked for one more solve (checked for tension, [`open_pulling`]), and the step
/// is accepted.
pub(crate) fn settle_stragglers(
    active: &mut [Active],
    params: &SolverParams,
    at_floor: bool,
    counters: &mut Counters,
) -> Result<(), Retry> {
    let stragglers = active.iter().filter(|c| c.changed).count() as f64;
    if !at_floor && stragglers > SETTLE_FRACTION * active.len() as f64 {
        return Err(Retry::OpenClose);
    }
    for c in active.iter_mut().filter(|c| c.changed) {
        c.settle(params);
        counters.totals.frozen_contacts += 1;
    }
    Ok(())
}

/// After the settled solve at the pass limit: opens every closed contact that solve left
/// pulling beyond the law's opening tension ([`law::pulls_open`]), and returns how many it
/// opened.
pub(crate) fn open_pulling(active: &mut [Active], params: &SolverParams) -> usize {
    let mut opened = 0;
    for c in active.iter_mut() {
        if c.rec.state.is_closed() && law::pulls_open(c.force, &c.law(params)) {
            if debug_log() {
                let (i, j) = c.blocks();
                eprintln!(
                    "settled solve: pair={i}-{j} pulls {:.3e} N ({:.2e} of the lighter weight), opened",
                    -c.force,
                    -c.force / c.weight
                );
            }
            c.open();
            opened += 1;
        }
    }
    opened
}

/// The slip a contact that starts to slide from rest ([`Transition::Slide`], its blocks' relative
/// motion at the step's start within the slip tolerance) is expected to make over the step, m:
/// what the force its spring pulls with beyond its strength, N tan φ, gives the lighter block
/// over Δt (½ (excess / m) Δt²); 0 without gravity, which gives no block's mass here. Its k⊥,
/// friction over slip, is taken over no less than this slip for the rest of the attempt. From
/// the slip of the locked pass alone, 10⁻¹⁰ m, k⊥ stayed p_τ, and with τ a few degrees off the
/// slide (the springs' extensions fan out on a block under its weight, and on a wedge each
/// plane's shear lies off the line of intersection) the corners held the block across it below
/// the slip tolerance, where no rule sees a slip: at the default Δt = 10 ms a third of the
/// light Hoek–Bray wedges of `tests/wedges.rs` (10–40 cm slopes) started one to six steps
/// late, and three that a zero friction cap let go took a kick instead (+43 % of ½ a t²). A
/// moving pair (a struck block) keeps the k⊥ of its slip: predicted there too, the struck wall
/// of 100 took a fifth more open–close passes.
fn onset_slip(inp: &CheckInputs, c: &Active, shear: &Vec3) -> f64 {
    let g = Vec3::from(inp.params.gravity).norm();
    let tolerance = c.slip_tolerance(inp.params);
    if g == 0.0 || c.weight <= 0.0 || c.carried(inp.blocks, inp.dt).norm() > tolerance {
        return 0.0;
    }
    let p_tau = inp.params.contact.shear_penalty(c.rec.penalty, c.inertia);
    let excess = p_tau * shear.norm() - c.force.max(0.0) * c.tan_phi(inp.params);
    0.5 * excess.max(0.0) / (c.weight / g) * inp.dt * inp.dt
}

/// Closes an open contact, locked with a fresh shear spring.
fn close(inp: &CheckInputs, c: &mut Active) {
    let cp = &inp.params.contact;
    c.rec.state = ContactState::Lock;
    c.rec.reference = c.cand.xb;
    c.clear_normal_force();
    // A new contact starts at p_n,1 (§6.1). One that was closed at the start of the
    // step and only opened in an earlier pass is not new: it keeps its adapted penalty,
    // which spares the (P21) rounds, and their factorizations, of raising it again.
    c.rec.penalty = if c.start.state.is_closed() && inp.warm {
        c.start.penalty
    } else {
        cp.initial_penalty
    };
    c.rec.normal_force = 0.0;
}

/// `DDA3D_DEBUG=1`: one line per state change: the pass, the change, the contact's values from
/// the solve (its slip also along the τ it had before the change, against the slip tolerance),
/// its changes so far in the attempt (`flips`, this one included), its state when the step
/// began, and its features, which with its pair and mode name the contact
/// (`scripts/open-close-tail.py` reads them).
fn log_change(inp: &CheckInputs, c: &Active, before: ContactState, tau_before: &Vec3) {
    let k = &c.cand.key;
    eprintln!(
        "t={:.4} dt={:.2e} pass {}: {:?}->{:?} mode={} N={:.2e} dn={:.2e} p={:.0e} shear={:.2e} slip={:.2e} along={:.2e} tol={:.1e} pair={}-{} flips={} started={:?} features={}-{}",
        inp.time,
        inp.dt,
        inp.pass,
        before,
        c.rec.state,
        k.mode,
        c.force,
        c.dn,
        c.rec.penalty,
        c.shear.norm(),
        c.slip.norm(),
        c.slip.dot(tau_before),
        c.slip_tolerance(inp.params),
        k.i,
        k.j,
        c.flips,
        c.start.state,
        k.feature_i,
        k.feature_j
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule that solves a pass again: friction F = 10 kN, k⊥ = 10⁸ N/m, f0·w0 = 5 µm.
    #[test]
    fn friction_pushing_across_its_direction_beyond_its_strength_is_solved_again() {
        let tau = Vec3::x();
        let beyond = |slip: Vec3| pushed_beyond_friction(&slip, &tau, 1e8, 1e4, 5e-6);
        // Along τ, however far: no force across.
        assert!(!beyond(Vec3::new(1.0, 0.0, 0.0)));
        // 50 µm across: 5 kN, within the friction.
        assert!(!beyond(Vec3::new(1e-2, 5e-5, 0.0)));
        // 200 µm across: 20 kN, twice the friction.
        assert!(beyond(Vec3::new(1e-2, 2e-4, 0.0)));
        assert!(beyond(Vec3::new(1e-2, 0.0, -2e-4)));
        // Within the slip tolerance the slip has not turned, whatever k⊥ and F.
        assert!(!pushed_beyond_friction(
            &Vec3::new(1e-2, 4e-6, 0.0),
            &tau,
            1e12,
            0.0,
            5e-6
        ));
        assert!(pushed_beyond_friction(
            &Vec3::new(1e-2, 6e-6, 0.0),
            &tau,
            1e12,
            0.0,
            5e-6
        ));
    }

    /// After a settled solve, only the closed contacts pulling beyond the law's opening tension
    /// are opened (and lose their force and cohesion); open ones and lighter tensions stay.
    #[test]
    fn a_settled_solve_opens_only_the_contacts_pulling_beyond_the_opening_tension() {
        let s = crate::scene::parse(crate::solver::CUBE_ON_SLAB, "cube.toml", "cube").unwrap();
        let solver = crate::solver::Solver::new(s.model, s.params);
        let p = solver.params.clone();
        let mut active = solver.next_contacts();
        assert!(active.len() >= 4, "{} contacts", active.len());
        let limit = active[0].law(&p).open_tension;
        assert!(limit > 0.0 && limit.is_finite());
        // Pulling at 2 and 0.5 times the limit, and open though pulling.
        let cases = [
            (ContactState::Lock, -2.0, true),
            (ContactState::Slide, -2.0, true),
            (ContactState::Lock, -0.5, false),
            (ContactState::Open, -2.0, false),
        ];
        for (c, (state, force, _)) in active.iter_mut().zip(cases) {
            c.rec.state = state;
            c.rec.lambda = 1.0;
            c.rec.intact = true;
            c.force = force * limit;
        }
        let opened = open_pulling(&mut active, &p);
        assert_eq!(opened, 2);
        for (c, (state, _, opens)) in active.iter().zip(cases) {
            let want = if opens { ContactState::Open } else { state };
            assert_eq!(c.rec.state, want);
            assert_eq!(c.rec.lambda == 0.0, opens);
            assert_eq!(c.rec.intact, !opens);
        }
    }
}
