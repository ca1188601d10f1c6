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
//!   cohesion only while the joint is intact), and, unless it carries load, only when the
//!   spring's shear displacement exceeds f0·w0 (hysteresis for contacts that carry no load);
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
    /// [`LOADED_FRACTION`]). Infinite where no weight gives the scale (no gravity).
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
/// that should topple stood on corners held by p_n,1·f0·w0 of tension.
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
            let beyond_noise = extension > p.slip_tolerance || o.normal_force >= p.loaded_force;
            if beyond_noise && o.shear_stiffness * extension > strength {
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
mod tests {
    use super::*;

    fn law() -> LawParams {
        LawParams {
            close_penetration: 1e-6,
            open_tension: 100.0,
            slip_tolerance: 1e-6,
            loaded_force: f64::INFINITY,
            tan_phi: 35f64.to_radians().tan(),
            held: false,
            close_sliding: true,
        }
    }

    fn seen(state: ContactState) -> Observation {
        Observation {
            state,
            penetration: 0.0,
            normal_force: 1e4,
            shear: Vec3::zeros(),
            shear_stiffness: 1e8,
            cohesion: 0.0,
            slip: Vec3::zeros(),
            tau: Vec3::x(),
            lambda: 1e4,
            slid_before: true,
            restarted: false,
            carried: None,
        }
    }

    /// Held joints (the equilibrium stage): a locked contact does not slide under any shear,
    /// but still opens in tension.
    #[test]
    fn held_joints_do_not_slide_but_open() {
        let p = LawParams {
            held: true,
            ..law()
        };
        let mut o = seen(ContactState::Lock);
        for n in [0.0, 1e2, 1e6] {
            o.normal_force = n;
            o.shear = Vec3::new(1.0, 0.0, 0.0);
            assert_eq!(classify(&o, &p), Transition::Keep, "N = {n}");
            assert!(matches!(classify(&o, &law()), Transition::Slide { .. }));
        }
        o.normal_force = -1e3;
        assert_eq!(classify(&o, &p), Transition::Open);
    }

    #[test]
    fn an_open_contact_closes_only_beyond_the_threshold() {
        let p = law();
        let mut o = seen(ContactState::Open);
        for (dn, want) in [
            (-1e-3, Transition::Keep),
            (0.0, Transition::Keep),
            (0.5e-6, Transition::Keep),
            (2e-6, Transition::Close),
        ] {
            o.penetration = dn;
            assert_eq!(classify(&o, &p), want, "d_n = {dn}");
        }
    }

    #[test]
    fn a_closed_contact_opens_only_under_tension_beyond_the_threshold() {
        let p = law();
        for state in [ContactState::Lock, ContactState::Slide] {
            let mut o = seen(state);
            o.slip = Vec3::new(1e-3, 0.0, 0.0);
            o.normal_force = -50.0;
            assert_ne!(
                classify(&o, &p),
                Transition::Open,
                "{state:?}: slight tension"
            );
            o.normal_force = -150.0;
            assert_eq!(classify(&o, &p), Transition::Open, "{state:?}");
        }
    }

    /// Mohr–Coulomb over a family of normal forces and friction angles: the contact slides
    /// exactly when p_τ·|shear| > N tan φ.
    #[test]
    fn a_locked_contact_slides_beyond_its_friction_strength() {
        for phi in [10.0f64, 30.0, 45.0] {
            let p = LawParams {
                tan_phi: phi.to_radians().tan(),
                ..law()
            };
            for n in [1e2, 1e4, 1e6] {
                let limit = n * p.tan_phi / 1e8; // extension at the strength, m
                let mut o = seen(ContactState::Lock);
                o.normal_force = n;
                o.shear = Vec3::new(0.0, -0.99 * limit.max(2e-6), 0.0);
                if 0.99 * limit > p.slip_tolerance {
                    assert_eq!(classify(&o, &p), Transition::Keep, "φ {phi}, N {n}");
                }
                o.shear = Vec3::new(0.0, -1.01 * limit.max(2e-6), 0.0);
                assert_eq!(
                    classify(&o, &p),
                    Transition::Slide { tau: -Vec3::y() },
                    "φ {phi}, N {n}"
                );
            }
        }
    }

    /// A contact carrying load slides by Mohr–Coulomb alone, however short its spring; one
    /// carrying less than `loaded_force` (or no weight to scale it: infinite) keeps the slip
    /// tolerance's hysteresis. Over a family of normal forces and friction angles.
    #[test]
    fn a_loaded_contact_slides_below_the_slip_tolerance() {
        for phi in [0.0f64, 10.0, 30.0] {
            for n in [1.0, 10.0, 50.0] {
                let p = LawParams {
                    tan_phi: phi.to_radians().tan(),
                    loaded_force: 0.5 * n,
                    ..law()
                };
                let mut o = seen(ContactState::Lock);
                o.normal_force = n;
                // 10 % beyond the strength (1 µN without friction), well below f0·w0 = 1 µm.
                let extension = (1.1 * n * p.tan_phi).max(1e-6) / o.shear_stiffness;
                assert!(extension < p.slip_tolerance, "φ {phi}, N {n}");
                o.shear = Vec3::new(0.0, extension, 0.0);
                let slide = Transition::Slide { tau: Vec3::y() };
                assert_eq!(classify(&o, &p), slide, "loaded: φ {phi}, N {n}");
                let unloaded = LawParams {
                    loaded_force: 2.0 * n,
                    ..p
                };
                assert_eq!(classify(&o, &unloaded), Transition::Keep, "φ {phi}, N {n}");
                assert_eq!(classify(&o, &law_at(p.tan_phi)), Transition::Keep);
                // Within its strength it stays locked, loaded or not.
                if phi > 0.0 {
                    o.shear = Vec3::new(0.0, 0.9 * n * p.tan_phi / o.shear_stiffness, 0.0);
                    assert_eq!(classify(&o, &p), Transition::Keep, "φ {phi}, N {n}");
                }
            }
        }
    }

    fn law_at(tan_phi: f64) -> LawParams {
        LawParams { tan_phi, ..law() }
    }

    #[test]
    fn cohesion_adds_to_the_strength_of_an_intact_joint() {
        let p = law();
        let mut o = seen(ContactState::Lock);
        let friction = o.normal_force * p.tan_phi;
        o.shear = Vec3::x() * (1.1 * friction / o.shear_stiffness);
        assert!(matches!(classify(&o, &p), Transition::Slide { .. }));
        o.cohesion = 0.2 * friction;
        assert_eq!(
            classify(&o, &p),
            Transition::Keep,
            "10 % reserve from cohesion"
        );
    }

    /// Hysteresis: a contact carrying no normal force does not flip to sliding for a shear
    /// displacement below f0·w0.
    #[test]
    fn tiny_shear_of_an_unloaded_contact_is_not_slip() {
        let p = law();
        let mut o = seen(ContactState::Lock);
        o.normal_force = 0.0;
        o.shear = Vec3::x() * 0.5e-6;
        assert_eq!(classify(&o, &p), Transition::Keep);
        o.shear = Vec3::x() * 2e-6;
        assert!(matches!(classify(&o, &p), Transition::Slide { .. }));
    }

    #[test]
    fn a_sliding_contact_sticks_when_its_slip_reverses_or_stops() {
        let p = law();
        let mut o = seen(ContactState::Slide);
        o.slip = Vec3::new(-2e-6, 0.0, 0.0);
        assert_eq!(classify(&o, &p), Transition::Stick, "reversed");
        o.slip = Vec3::new(0.0, 0.5e-6, 0.0);
        assert_eq!(classify(&o, &p), Transition::Stop, "stopped");
        // Once stopped in this attempt and sliding again, it does not stop a second time.
        o.restarted = true;
        assert_eq!(classify(&o, &p), Transition::Keep, "restarted");
        o.slip = Vec3::new(-2e-6, 0.0, 0.0);
        assert_eq!(classify(&o, &p), Transition::Stick, "restarted, reversed");
        o.restarted = false;
        o.slip = Vec3::new(0.0, 0.5e-6, 0.0);
        // One that began to slide in this step, held still in this pass, slides on.
        o.slid_before = false;
        assert_eq!(
            classify(&o, &p),
            Transition::Keep,
            "held still by its neighbours"
        );
        o.slid_before = true;
        // A slip far beyond the spring's elastic range N tan φ / p_τ = 70 µm: friction follows
        // the slip (the trial force is 7 kN along τ plus 141 kN along the slip).
        o.slip = Vec3::new(1e-3, 1e-3, 0.0);
        let want = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!((turn(&o, &p) - want).norm() < 0.05, "follows the slip");
    }

    fn turn(o: &Observation, p: &LawParams) -> Vec3 {
        match classify(o, p) {
            Transition::Turn { tau } => {
                assert!((tau.norm() - 1.0).abs() < 1e-12);
                tau
            }
            t => panic!("{t:?}"),
        }
    }

    /// A small block's onset (its spring's elastic range N tan φ / p_τ far below the slip
    /// tolerance): friction turns by a slip below the tolerance, by the trial force; a contact
    /// that was already sliding, an unloaded one, or one whose range is not that fine, keeps
    /// the tolerance.
    #[test]
    fn a_fine_contact_turns_by_any_slip_at_its_onset() {
        // A 10 cm block's corner on a 40 m slope: N = 3 N, p_τ = 8·10⁷ N/m, f0·w0 = 4 µm.
        let p = LawParams {
            slip_tolerance: 4e-6,
            loaded_force: 0.1,
            tan_phi: 0.18,
            ..law()
        };
        let mut o = seen(ContactState::Slide);
        o.normal_force = 3.0;
        o.lambda = 3.0;
        o.shear_stiffness = 8e7;
        o.slid_before = false;
        // A micrometre of slip 5° off τ: far beyond the range (6.8 nm), τ follows the slip.
        let off = 5f64.to_radians();
        o.slip = Vec3::new(off.cos(), off.sin(), 0.0) * 1e-6;
        assert!(fine_onset(&o, &p));
        let tau = turn(&o, &p);
        assert!(tau.y.atan2(tau.x) > 0.99 * off, "{tau}");
        o.slid_before = true;
        // Already sliding when the step began: a slip below the tolerance is a stop.
        assert_eq!(classify(&o, &p), Transition::Stop, "already sliding");
        o.slid_before = false;
        let unloaded = LawParams {
            loaded_force: 10.0,
            ..p
        };
        assert_eq!(classify(&o, &unloaded), Transition::Keep, "unloaded");
        // 1.4 kN: its range, 3.2 µm, is not below 1 % of the tolerance.
        o.normal_force = 1.4e3;
        assert!(!fine_onset(&o, &p));
        assert_eq!(classify(&o, &p), Transition::Keep, "a wide range");
        assert!(
            fine_range(1.4e3, 8e7, &p, 1.0),
            "within the tolerance itself"
        );
        assert!(!fine_range(1.0e4, 8e7, &p, 1.0));
    }

    /// A sliding contact that slips less than the tolerance stops, unless its blocks' velocities
    /// carry it forward (beyond a tenth of the tolerance) and it slips at least that far (it
    /// speeds up); without the carried motion (static steps, the stage) the tolerance
    /// alone decides.
    #[test]
    fn a_slow_contact_that_speeds_up_does_not_stop() {
        let p = law();
        let mut o = seen(ContactState::Slide);
        o.slip = Vec3::x() * 5e-7;
        assert_eq!(classify(&o, &p), Transition::Stop, "no carried motion");
        o.carried = Some(Vec3::x() * 0.5 * CARRIED_SHARE * p.slip_tolerance);
        assert_eq!(classify(&o, &p), Transition::Stop, "carried too little");
        o.carried = Some(Vec3::x() * 4e-7);
        assert!(speeds_up(&o, &p));
        assert_eq!(classify(&o, &p), Transition::Keep, "speeding up");
        o.carried = Some(Vec3::x() * 6e-7);
        assert_eq!(classify(&o, &p), Transition::Stop, "slowing down");
        // Across τ, the carried motion does not count.
        o.carried = Some(Vec3::new(4e-7, 9e-7, 0.0));
        assert_eq!(classify(&o, &p), Transition::Keep);
    }

    /// Cundall's incremental friction: τ turns to the trial force N tan φ·τ + p_τ·slip. A slip
    /// of 3 µm across τ at N tan φ = 7 kN and p_τ = 10⁸ N/m turns it by atan(300/7003) = 2.45°,
    /// where taking the slip's direction turned it by 90°; the same slip with the contact in
    /// tension (no friction to hold) is followed whole.
    #[test]
    fn micro_slip_across_the_sliding_direction_turns_it_a_little() {
        let p = law();
        let mut o = seen(ContactState::Slide);
        o.slip = Vec3::new(0.0, 3e-6, 0.0);
        let tau = turn(&o, &p);
        let held = o.normal_force * p.tan_phi;
        let want = (300.0 / held).atan();
        assert!((tau.y.atan2(tau.x) - want).abs() < 1e-12, "{tau}");
        assert!(want.to_degrees() > 2.4 && want.to_degrees() < 2.5);
        o.normal_force = -50.0;
        assert!((turn(&o, &p) - Vec3::y()).norm() < 1e-15);
        // A forward slip keeps τ whatever its size.
        o.normal_force = 1e4;
        o.slip = Vec3::new(5e-6, 0.0, 0.0);
        assert!((turn(&o, &p) - Vec3::x()).norm() < 1e-15);
    }

    /// An open contact that closes while its blocks move past each other closes sliding along
    /// that motion, whatever the motion's direction; one that closes at rest closes locked; and
    /// held joints (the equilibrium stage) and Shi's rule (DDA-3p where no block slides) close
    /// locked.
    #[test]
    fn a_contact_closing_in_motion_closes_sliding() {
        let p = law();
        let mut o = seen(ContactState::Open);
        o.penetration = 2e-6;
        for slip in [
            Vec3::new(1e-3, 0.0, 0.0),
            Vec3::new(0.0, -3e-6, 0.0),
            Vec3::new(2e-6, 2e-6, 0.0),
        ] {
            o.slip = slip;
            assert_eq!(
                classify(&o, &p),
                Transition::CloseSliding {
                    tau: slip.normalize()
                },
                "slip {slip}"
            );
            let held = LawParams { held: true, ..p };
            assert_eq!(classify(&o, &held), Transition::Close, "held, slip {slip}");
            let shi = LawParams {
                close_sliding: false,
                ..p
            };
            assert_eq!(
                classify(&o, &shi),
                Transition::Close,
                "Shi's rule, slip {slip}"
            );
        }
        o.slip = Vec3::new(0.5e-6, 0.0, 0.0);
        assert_eq!(classify(&o, &p), Transition::Close, "below the tolerance");
        o.penetration = 0.5e-6;
        o.slip = Vec3::new(1e-3, 0.0, 0.0);
        assert_eq!(classify(&o, &p), Transition::Keep, "not yet closed");
    }

    #[test]
    fn settling_closes_and_locks_unless_a_gap_is_left() {
        let c = 1e-6;
        assert_eq!(settle(ContactState::Slide, -2e-6, c, false), Settled::Open);
        assert_eq!(settle(ContactState::Lock, -2e-6, c, false), Settled::Open);
        assert_eq!(
            settle(ContactState::Slide, -0.5e-6, c, false),
            Settled::Lock { fresh_spring: true }
        );
        assert_eq!(
            settle(ContactState::Open, 1e-4, c, false),
            Settled::Lock { fresh_spring: true }
        );
        assert_eq!(
            settle(ContactState::Lock, 1e-4, c, false),
            Settled::Lock {
                fresh_spring: false
            }
        );
    }

    /// A frictionless contact settles closed and sliding wherever it would lock, and open
    /// across a gap as any other.
    #[test]
    fn a_frictionless_contact_settles_sliding() {
        let c = 1e-6;
        for state in [ContactState::Open, ContactState::Lock, ContactState::Slide] {
            assert_eq!(settle(state, -2e-6, c, true), Settled::Open);
            assert_eq!(settle(state, -0.5e-6, c, true), Settled::Slide);
            assert_eq!(settle(state, 1e-4, c, true), Settled::Slide);
        }
    }
}
