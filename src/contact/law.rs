//! The contact law as a pure state classification (reference §6.1): given what the last solve
//! says of one contact, does it stay, close, open, start to slide, stick again, or slide on in a
//! new direction? The solver applies the answer to the contact's record; nothing here touches
//! the solver's state, so every rule is unit-tested on its own below.
//!
//! The rules:
//! - an open contact closes when it penetrates beyond a small threshold (hysteresis against
//!   open–close chatter: the role of Shi's s0): locked, or sliding where its blocks move past
//!   each other in the solve;
//! - a closed contact opens under tension beyond p_n,1·f0·w0 (Shi's gap test f0·w0, as a force,
//!   with the initial penalty so that a stiffened contact cannot hold tension);
//! - a locked contact slides when its shear spring force exceeds N tan φ + c·A (Mohr–Coulomb;
//!   cohesion only while the joint is intact), and, unless it carries load or its spring pulls
//!   with a load's force, only when the spring's shear displacement exceeds f0·w0 (hysteresis
//!   for contacts that carry no load);
//! - a sliding contact sticks again when its slip reverses, or stops (if it was sliding when the
//!   step began, and is not speeding up, [`speeds_up`]); otherwise its friction turns toward
//!   the slip, by the trial force (Cundall's incremental friction, [`turned`]), for slips beyond
//!   f0·w0 or, at a small block's onset, any slip ([`fine_onset`]).

use super::ContactState;
use crate::physics::geometry::Vec3;

/// The law's thresholds for one step.
#[derive(Clone, Copy, Debug)]
pub struct LawParams {
    /// An open contact closes when it penetrates beyond this, m (`close_threshold · w0`).
    pub close_penetration: f64,
    /// A closed contact opens under a tension beyond this, N (p_n,1 · `open_threshold` · w0).
    pub open_tension: f64,
    /// Tangential displacements below this are neither slip nor a reversal of slip, m
    /// (`open_threshold · w0`, Shi's f0·w0).
    pub slip_tolerance: f64,
    /// A closed contact pressed by at least this normal force carries load, N: it slides by
    /// Mohr–Coulomb alone, whatever its spring's extension against `slip_tolerance` (see
    /// [`LOADED_FRACTION`]); so does one whose shear spring pulls with this force or more,
    /// loaded or not. Infinite where no weight gives the scale (no gravity).
    pub loaded_force: f64,
    /// tan φ of the joint.
    pub tan_phi: f64,
    /// Joints held against sliding (the equilibrium stage's first phase): a locked contact
    /// stays locked whatever its shear; it can still open.
    pub held: bool,
    /// A contact that closes while its blocks move past each other closes sliding; otherwise
    /// locked, as in Shi's DDA. Always under DDA-3a; under DDA-3p where one of its free blocks
    /// already slides on another contact (`crate::solver::open_close`).
    pub close_sliding: bool,
}

/// The share of the lighter free block's weight from which a contact counts as carrying load
/// ([`LawParams::loaded_force`]). The slip tolerance f0·w0 keeps a contact that carries no
/// load from sliding on the noise of its spring; but f0·w0 scales with the model (w0 is half
/// the extent of the contact group), while a loaded spring's extension N tan φ / p_τ scales
/// with the block's weight. Held to f0·w0, a 10 cm block on a 7.8 m slope could not slide
/// even without friction: each corner's spring, 1.1 N of shear at p_τ = 8·10⁷ N/m, stretched
/// 1.4·10⁻⁸ m against f0·w0 = 7.8·10⁻⁷ m, and blocks up to about 40 kg stood on any slope. A
/// block resting on four corners presses each with about a quarter of its weight; a contact
/// grazing it, with next to nothing. The same fraction bounds the tension that opens a contact
/// ([`LawParams::open_tension`], set in `crate::solver::active`), for the same reason: a block
/// that should topple stood on corners held by p_n,1·f0·w0 of tension. And the same force
/// bounds the shear an unloaded spring may hold below f0·w0: p_τ·f0·w0 grows with the model and
/// the rock's stiffness, and four unloaded corners of a crack behind a 0.2 m wedge (16 N each
/// allowed, against the wedge's 15 N weight) hung it from the crack.
pub const LOADED_FRACTION: f64 = 0.01;

/// What the last solve says of one contact.
#[derive(Clone, Copy, Debug)]
pub struct Observation {
    pub state: ContactState,
    /// d_n, m, positive when penetrating.
    pub penetration: f64,
    /// N = λ + p_n d_n (ALM) or p_n d_n (penalty), N, positive in compression.
    pub normal_force: f64,
    /// Locked: the shear spring's extension N(Δ + Δu_ab), m, tangential. Ignored otherwise.
    pub shear: Vec3,
    /// p_τ of the contact's shear spring, N/m (a sliding contact's too: it weighs the slip
    /// that turns its friction).
    pub shear_stiffness: f64,
    /// Cohesive strength c·A of an intact joint, N (0 once it has opened or slid).
    pub cohesion: f64,
    /// The tangential part of the relative displacement Δu_ab, m.
    pub slip: Vec3,
    /// Sliding direction of a sliding contact.
    pub tau: Vec3,
    /// λ, N.
    pub lambda: f64,
    /// The contact was already sliding when the step began (not only since an earlier pass).
    pub slid_before: bool,
    /// The contact stopped ([`Transition::Stop`]) in an earlier pass of this attempt and has
    /// slid again since: its spring went beyond its strength, so the stop was wrong, and the
    /// stop rule does not apply to it again in this attempt (a reversal still sticks it).
    pub restarted: bool,
    /// The tangential motion the blocks' velocities at the step's start give the contact over
    /// the step, m, where the step carries velocity and the stop rule reads it (dynamic steps
    /// outside the equilibrium stage); `None` elsewhere.
    pub carried: Option<Vec3>,
}

/// The law's verdict on one contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transition {
    /// Stays as it is.
    Keep,
    /// An open contact closes, locked with a fresh shear spring.
    Close,
    /// An open contact closes while its blocks slide past each other (its tangential motion in
    /// the solve beyond the slip tolerance): it closes sliding along `tau`, with kinetic
    /// friction, as Coulomb's law has it. Closed locked, it held its block for a pass while
    /// every other contact of the block read as stopped (a wedge sliding on ten contacts stuck
    /// each time one of its corners reached a neighbour's face); if friction can stop the
    /// motion, the next pass sticks it.
    CloseSliding { tau: Vec3 },
    /// A closed contact opens (and loses its cohesion).
    Open,
    /// A locked contact starts to slide along `tau` (and loses its cohesion).
    Slide { tau: Vec3 },
    /// A sliding contact whose slip reversed sticks: locked with a fresh shear spring.
    Stick,
    /// A sliding contact that stopped (slipped less than the slip tolerance, and was sliding
    /// when the step began) sticks, as [`Transition::Stick`].
    Stop,
    /// A sliding contact slides on along the new direction `tau`.
    Turn { tau: Vec3 },
}

/// A closed contact under a tension beyond `open_tension` opens: [`classify`]'s first test.
pub fn pulls_open(normal_force: f64, p: &LawParams) -> bool {
    normal_force < -p.open_tension
}

/// Classifies one contact from the last solve.
pub fn classify(o: &Observation, p: &LawParams) -> Transition {
    match o.state {
        ContactState::Open => {
            if o.penetration <= p.close_penetration {
                Transition::Keep
            } else if let Some(tau) = closes_sliding(&o.slip, p) {
                Transition::CloseSliding { tau }
            } else {
                Transition::Close
            }
        }
        _ if pulls_open(o.normal_force, p) => Transition::Open,
        ContactState::Lock if p.held => Transition::Keep,
        ContactState::Lock => {
            let extension = o.shear.norm();
            let strength = o.normal_force * p.tan_phi + o.cohesion;
            let force = o.shear_stiffness * extension;
            let beyond_noise = extension > p.slip_tolerance
                || o.normal_force >= p.loaded_force
                || force >= p.loaded_force;
            if beyond_noise && force > strength {
                Transition::Slide {
                    tau: o.shear.normalize(),
                }
            } else {
                Transition::Keep
            }
        }
        ContactState::Slide => {
            // The slip reversed, or stopped: the contact sticks again. (A contact whose friction
            // the ALM loop held below its capacity λ tan φ, after its slip reversed in an early
            // iteration, used to stick too; but λ is still converging then, and on a joint near
            // its friction angle (35° at φ 33°) the corners stuck, slid and stuck again until
            // they were settled locked: the block started 15 steps late.)
            // A stop counts only for a contact that was sliding when the step began. One that
            // began to slide in an earlier pass of this step is held still in this pass by its
            // neighbours' locked (stuck) contacts: sticking it then made the corners of a pushed
            // block take turns, lock against slide, and the block stood for two steps.
            // A stop counts once in an attempt ([`Observation::restarted`]): a contact at its
            // friction limit that slides slower than the tolerance stopped, its spring went a
            // hair beyond its strength, it slid again, and so on, a pass each, until it was
            // settled. In a struck wall of 300 blocks these cycles were 7196 of the 19 000 state
            // changes from the eighth pass of a step on.
            let stopped = o.slid_before
                && !o.restarted
                && o.slip.norm() < p.slip_tolerance
                && !speeds_up(o, p);
            if reversed(&o.slip, &o.tau, p.slip_tolerance) {
                Transition::Stick
            } else if stopped {
                Transition::Stop
            } else if o.slip.norm() > p.slip_tolerance || fine_onset(o, p) {
                // Friction follows the slip; it has not reversed here, so friction along the old
                // direction still did negative work.
                Transition::Turn { tau: turned(o, p) }
            } else {
                Transition::Keep
            }
        }
    }
}

/// The sliding direction of a contact that closes with the tangential motion `slip` (its slip in
/// the solve, or the motion its blocks' velocities give over the step for a contact seen for
/// the first time): `None` (it closes locked) below the slip tolerance, while joints are held,
/// or without [`LawParams::close_sliding`]. DDA-3p closed every contact locked, as Shi's DDA
/// does: a Hoek–Bray wedge whose corners reached a neighbour's face each step was held by their
/// fresh springs (7 mm of 0.18 m in 0.5 s), and a block launched along a flat base stopped after
/// 27 % of its Coulomb distance (see `crate::solver::open_close`, where DDA-3p's friction then
/// takes the contact's force).
pub fn closes_sliding(slip: &Vec3, p: &LawParams) -> Option<Vec3> {
    (p.close_sliding && slip.norm() > p.slip_tolerance && !p.held).then(|| slip.normalize())
}

/// The new sliding direction of a sliding contact that slipped by `o.slip` (not reversed):
/// Cundall's incremental friction, the direction of the trial force N tan φ·τ + p_τ·slip, i.e.
/// the friction it had plus what a locked spring would have added over the slip. A slip large
/// against the spring's elastic range N tan φ / p_τ turns τ into the slip's direction (as
/// taking the slip's own direction did); micrometre slips across τ, which rocking blocks give
/// their corners pass after pass, turn it a little. Taken straight from such slips, τ swung by
/// up to 90° a pass at the corners of three cross-cut slabs standing at 84 % of their friction
/// (45° under φ 50°): the friction left the downslope load unresisted in turn, the contacts were
/// settled in arbitrary states (60 a step), and the stack crept faster and faster (2.9 mm in
/// 1.5 s).
pub fn turned(o: &Observation, p: &LawParams) -> Vec3 {
    let held = (o.normal_force * p.tan_phi).max(0.0);
    let trial = o.tau * held + o.slip * o.shear_stiffness;
    let n = trial.norm();
    if n > 0.0 && n.is_finite() {
        trial / n
    } else {
        o.slip.normalize()
    }
}

/// The share of the slip tolerance its blocks' velocities must carry a sliding contact along τ
/// over the step for [`speeds_up`] to read it as moving.
pub const CARRIED_SHARE: f64 = 0.1;

/// A sliding contact that its blocks' velocities at the step's start carry forward along τ by
/// at least [`CARRIED_SHARE`] of the slip tolerance ([`Observation::carried`]), and that slips
/// at least that far in the solve, is speeding up, not stopping, however short the slip. A
/// block just past its friction limit gains speed slowly: 1 m on 10° at F = 0.99 slips
/// 2·10⁻⁶ m in its second step, under f0·w0 = 5·10⁻⁶ m, and the stop rule alone stuck it again
/// each step (it stood; Coulomb has it slide 8.5 mm in 1 s). The share keeps the rule off the
/// micro-motions of blocks at rest: without it, a column standing on a slab shaken by an impact
/// beside it kept sliding contacts that should stick, and moved 6 times further from its run
/// without sleeping than before (`tests/sleeping.rs`).
pub fn speeds_up(o: &Observation, p: &LawParams) -> bool {
    o.carried.is_some_and(|carried| {
        let along = carried.dot(&o.tau);
        along > CARRIED_SHARE * p.slip_tolerance && o.slip.dot(&o.tau) >= along
    })
}

/// The share of the slip tolerance f0·w0 below which a loaded contact's elastic range
/// N tan φ / p_τ makes the tolerance too coarse to judge whether its friction turns
/// ([`fine_onset`]).
pub const FINE_RANGE: f64 = 0.01;

/// A contact that began to slide in this step, carries load and whose spring's elastic range is
/// below [`FINE_RANGE`] of the slip tolerance (a small block in a large model) turns its friction
/// by whatever slip it makes, not only by slips beyond f0·w0. Its first τ is the direction of
/// its spring's extension, which the block's elastic spreading under its own weight sets a few
/// degrees off the slide (5 % of a 10 cm block's corner extension); a 2 cm block on a 40 m
/// slope slides a whole step below f0·w0 = 4·10⁻⁶ m, so τ never turned, the four corners'
/// friction pulled apart and the block stood (at F ≥ 0.8 on 10–60°). [`turned`] weighs the slip
/// by p_τ against the friction held, so a slip within the spring's elastic range turns τ only
/// a little. Contacts that were already sliding, or whose range is not that fine (a rock mass's
/// blocks of a metre: 10⁻⁴ m against 5·10⁻⁶ m), keep the tolerance: turning the shipped jointed
/// slope's onset contacts by their micro-slips cost it 22 % more open–close passes, and at
/// [`FINE_RANGE`] = 1 still 16 %, with its least-moved free block 2 % shorter.
pub fn fine_onset(o: &Observation, p: &LawParams) -> bool {
    !o.slid_before
        && o.slip.norm() > 0.0
        && fine_range(o.normal_force, o.shear_stiffness, p, FINE_RANGE)
}

/// True when a contact pressed by `normal_force` carries load ([`LawParams::loaded_force`]) and
/// its spring's elastic range N tan φ / p_τ is below `share` of the slip tolerance.
pub fn fine_range(normal_force: f64, shear_stiffness: f64, p: &LawParams, share: f64) -> bool {
    normal_force >= p.loaded_force
        && normal_force * p.tan_phi < share * p.slip_tolerance * shear_stiffness
}

/// True when `motion` goes back against the sliding direction `tau` by more than `tolerance`.
pub fn reversed(motion: &Vec3, tau: &Vec3, tolerance: f64) -> bool {
    motion.dot(tau) < -tolerance
}

/// The settled state of a contact whose open–close state does not converge: closed and locked
/// where the last solve left it touching or penetrating, open where it left a gap beyond the
/// closing threshold. A contact closed across a gap is a spring stretched by that gap: with an
/// adapted penalty of up to γE it pulled a 12 mm gap shut within one step and gave a 40-block
/// wall 0.1 MJ. Locked rather than sliding because a spring stores energy and gives it back,
/// whereas sliding friction along a guessed direction can push the slip it should resist
/// (settling as sliding fed a 100-block wall energy). The exception is the solver's: a contact
/// whose last verdict was [`Transition::Slide`] (its spring beyond its strength, so the
/// direction is its shear's, not a guess) stays sliding. A frictionless contact (no friction
/// and no cohesion) settles sliding too: it carries no shear along any direction, so there is
/// no guess to make, and locked it held what its spring took. Under DDA-3p, which settles a
/// contact after its second change, a block struck on a frictionless base was held by its
/// settled corners for the impact step and lost its momentum to the base (32 of 64 frictionless
/// collisions lost 3–124 % of their horizontal momentum, `tests/collisions.rs`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Settled {
    Open,
    /// Closed and sliding, with no friction to carry.
    Slide,
    /// Locked; `fresh_spring` when it was not locked before (its spring starts here).
    Lock {
        fresh_spring: bool,
    },
}

/// See [`Settled`]. `frictionless`: the contact's joint has no friction and the contact no
/// cohesion.
pub fn settle(
    state: ContactState,
    penetration: f64,
    close_penetration: f64,
    frictionless: bool,
) -> Settled {
    if penetration < -close_penetration {
        Settled::Open
    } else if frictionless {
        Settled::Slide
    } else {
        Settled::Lock {
            fresh_spring: state != ContactState::Lock,
        }
    }
}

#[cfg(test)]
mod tests;
