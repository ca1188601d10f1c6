//! A contact inside a step: its geometry frozen at the start of the step, the record it carries,
//! and the working values of the iterations (d_n, N, the flips of the open–close check).

use super::step_control::max_step_penetration;
use crate::contact::kinematics::NormalKinematics;
use crate::contact::law::{self, LawParams, Settled};
use crate::contact::record::ContactRecord;
use crate::contact::{Candidate, ContactState};
use crate::model::Block;
use crate::params::{ContactParams, Method, SolverParams};
use crate::physics::geometry::Vec3;
use crate::physics::mechanics::{Mat3x12, Vec12, displacement_matrix};

/// How far beyond the joint's strength [`Active::cap_shear`] lets a locked contact's spring
/// pull within the ALM loop.
const SHEAR_CAP: f64 = 2.0;

/// A kept overlap is given back with this time constant, s ([`Active::release_overlap`]).
const OVERLAP_RELEASE_TIME: f64 = 0.1;

/// ... and never faster than this, m/s: the blocks it separates leave at about twice this
/// speed, a kinetic energy of 2v² = 5 mJ/kg (a fall of half a millimetre).
const OVERLAP_RELEASE_SPEED: f64 = 0.05;

/// The depth a contact first seen overlapping may have pushed out within a dynamic step of
/// `dt`, m: what [`Active::release_overlap`] gives back at its speed limit. Deeper, the overlap
/// is kept. Pushed out within the step, a depth d leaves the blocks at about 2d/Δt (Newmark
/// γ = 1): in a cube of 5 cm slabs a corner of a 0.39 kg fragment first seen 0.18 mm inside
/// its neighbour left at 2 m/s in a step of 0.1 ms, 1.5 J the fall had never given, and the
/// cuts for that energy gain made it worse (the depth stays, Δt shrinks).
pub(crate) fn pushed_out_within(dt: f64) -> f64 {
    OVERLAP_RELEASE_SPEED * dt
}

/// A contact inside a step.
pub(crate) struct Active {
    pub cand: Candidate,
    pub kin: NormalKinematics,
    /// The normal kinematics of each of `cand.alternatives`, in order.
    pub alt_kin: Vec<NormalKinematics>,
    pub rec: ContactRecord,
    /// Record at the start of the step, restored when an attempt is redone.
    pub start: ContactRecord,
    /// Index of the block pair in the global matrix's pattern.
    pub pair: usize,
    /// The smaller Young's modulus of the two blocks: the cap γE of (P21b).
    pub young: f64,
    /// The weight of the lighter free block of the two, N: the scale of a shear spring's
    /// force below which [`Active::cap_shear`] leaves it alone.
    pub weight: f64,
    /// 2m/Δt_max² of that block in dynamic mode (0 in static mode, or both fixed), N/m: where
    /// it exceeds α·p_n,1, p_τ may follow p_n up to it ([`ContactParams::shear_penalty`]).
    pub inertia: f64,
    /// The joint set the contact lies on (`None`: `[joint]`); see [`SolverParams::joint_of`].
    pub joint: Option<u16>,
    /// Shi's w0 of the contact's group (`crate::contact::groups`), m: the length its
    /// thresholds and ALM tolerances scale with.
    pub w0: f64,
    /// d_n after the last solve (5.4), m.
    pub dn: f64,
    /// N after the last solve (5.6), N.
    pub force: f64,
    /// d_n of the previous ALM iteration, for (P21).
    pub dn_prev: Option<f64>,
    /// The normal force a sliding contact's friction takes (5.8), N: that of the previous
    /// iterate, max(0, N), which at a step's first solve is the force the last step ended with.
    /// The warm start carries a different multiplier ([`Active::lambda_solved`]), so friction
    /// cannot take λ there: λ_{k−1} lacks the penalty's share p_n·d_n of the force, and a block
    /// sliding on a 30° slope took 0.12 % too far by 0.8 s (Table 2: 0.003 %).
    pub friction_normal: f64,
    /// The multiplier the last solve was made with, λ_{k−1} of the last ALM iteration: what
    /// the step carries into the next one (see `commit::commit_contact`).
    pub lambda_solved: Option<f64>,
    /// Friction magnitude of a sliding contact whose slip reversed in this pass, held (see the
    /// ALM loop).
    pub friction_cap: Option<f64>,
    /// State changes of this contact in the current attempt (to stop open–close cycles).
    pub flips: u8,
    /// Settled after cycling: no more state changes in this attempt.
    pub frozen: bool,
    /// Stopped by the contact law in this attempt ([`law::Observation::restarted`]).
    pub stopped: bool,
    /// The slip expected over the step of a contact that began to slide from rest in this
    /// attempt, m: its k⊥ is taken over no less (`crate::solver::open_close`, `onset_slip`); 0
    /// otherwise.
    pub onset_slip: f64,
    /// The share of Δt at which this contact's sliding stopped, where its slip reversed within
    /// the attempt while it was sliding fast ([`super::step_control::stop_within`]).
    pub stop_fraction: Option<f64>,
    /// Changed state in the last open–close pass.
    pub changed: bool,
    /// N(Δ + Δu_ab) of a locked contact after the last solve.
    pub shear: Vec3,
    /// Δu_ab projected on the tangent plane after the last solve.
    pub slip: Vec3,
    /// Δu_ab = T_a D_i − T_b D_j of a closed contact in the ALM loop's last solve, taken once
    /// and read by the stick and friction updates of that iteration (they would each take it
    /// again from the same D and the same points).
    pub du: Vec3,
    /// k⊥ of a sliding contact (DDA-3a): the stiffness of its friction's direction across the
    /// slip ([`crate::contact::kinematics::add_friction_tangent`]), N/m; 0 otherwise.
    pub lateral: f64,
    /// The part of the start-of-step kept overlap given back in `kin.d0` by the current
    /// attempt ([`Active::release_overlap`]), m.
    pub released: f64,
    /// The depth of a contact first seen overlapping that activation left to be pushed out
    /// (shallower than [`pushed_out_within`] the step's Δt), m; 0 otherwise. An attempt cut
    /// shorter keeps it ([`Active::release_overlap`]).
    pub fresh_depth: f64,
    /// The face the contact had before an attempt of this step moved it to another
    /// ([`Active::reconsider_face`]), for [`Active::restart`]; `None` while it has not moved.
    pub face_at_start: Option<Box<FaceAtStart>>,
}

/// A V–F contact's face as activation gave it, with what [`Active::reconsider_face`] changes
/// when it moves the contact to another face.
#[derive(Clone, Debug)]
pub(crate) struct FaceAtStart {
    cand: Candidate,
    kin: NormalKinematics,
    alt_kin: Vec<NormalKinematics>,
    overlap: f64,
    released: f64,
}

/// What a contact's stiffness depends on within an attempt (its kinematics are frozen): nothing
/// if open; p_n, τ and k⊥ if sliding; p_n and the reference point of the shear spring if locked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StiffnessKey {
    pub lock: bool,
    pub penalty: f64,
    pub reference: Vec3,
    pub tau: Vec3,
    pub lateral: f64,
}

impl Active {
    /// The block indices (i, j).
    pub fn blocks(&self) -> (usize, usize) {
        (self.cand.key.i as usize, self.cand.key.j as usize)
    }

    /// The contact law's thresholds at this contact's w0.
    pub fn law(&self, p: &SolverParams) -> LawParams {
        let cp = &p.contact;
        // A vertex on an edge of block j (`Candidate::tied`) closes only beyond the ALM's own
        // tolerance ε1·d_n,max: below it, the few micrometres its blocks settle under load
        // push it behind both faces at the edge, and closed on one of them, it would stop a
        // slide along the other (see `reconsider_face`).
        let close_penetration = if self.cand.tied {
            (cp.close_threshold * self.w0).max(cp.eps1 * self.dn_max(p))
        } else {
            cp.close_threshold * self.w0
        };
        LawParams {
            close_penetration,
            // Like the slip tolerance, p_n,1·f0·w0 scales with the contact group, not the
            // block: held to it, a 0.3 × 0.3 × 1 m block on a 20 m slope that should topple
            // (its corners under 120 N of tension against 400 N) stood. A block's own weight
            // bounds it too (`law::LOADED_FRACTION` of the lighter block's).
            open_tension: (cp.initial_penalty * (cp.open_threshold * self.w0)).min(
                if self.weight > 0.0 {
                    law::LOADED_FRACTION * self.weight
                } else {
                    f64::INFINITY
                },
            ),
            slip_tolerance: cp.open_threshold * self.w0,
            loaded_force: if self.weight > 0.0 {
                law::LOADED_FRACTION * self.weight
            } else {
                f64::INFINITY
            },
            tan_phi: self.tan_phi(p),
            held: p.joints_held,
            close_sliding: true,
        }
    }

    /// Gives back part of a kept overlap (`crate::solver::activate`) for an attempt of `dt`:
    /// a share dt/τ of it, at most v·dt. Per unit time, not per step: a share per step would
    /// push the blocks apart faster the more Δt is cut, and a step cut for creating energy
    /// would create more. Called at the start of each attempt, after `rec` was reset to
    /// `start`.
    pub fn release_overlap(&mut self, dt: f64) {
        if self.fresh_depth > pushed_out_within(dt) && self.start.overlap == 0.0 {
            // Too deep for this shorter attempt: kept, as activation would have at this Δt.
            self.kin.d0 -= self.fresh_depth;
            self.start.overlap = self.fresh_depth;
            self.rec.overlap = self.fresh_depth;
        }
        let kept = self.rec.overlap;
        let r = (kept * (dt / OVERLAP_RELEASE_TIME).min(1.0)).min(pushed_out_within(dt));
        self.kin.d0 += r - self.released;
        self.released = r;
        self.rec.overlap = kept - r;
    }

    /// d_n,max = 2 δ w0 of (P22) at this contact's w0, m.
    pub fn dn_max(&self, p: &SolverParams) -> f64 {
        max_step_penetration(p, self.w0)
    }

    /// f0·w0: slip below this is not a reversal, m.
    pub fn slip_tolerance(&self, p: &SolverParams) -> f64 {
        p.contact.open_threshold * self.w0
    }

    /// A locked contact is stuck when its slip in a solve is below this, m: ε1·d_n,max, or
    /// f0·w0 in the first step of a run (see `alm::absorb_stick_slip`).
    pub fn stick_tolerance(&self, p: &SolverParams, first_step: bool) -> f64 {
        if first_step {
            self.slip_tolerance(p)
        } else {
            p.contact.eps1 * self.dn_max(p)
        }
    }

    /// Applies the settled state of [`law::settle`] to a contact whose open–close state does
    /// not converge.
    pub fn settle(&mut self, p: &SolverParams) {
        let close_tol = p.contact.close_threshold * self.w0;
        // Not in the stage's steps with the joints held, where no contact slides.
        let frictionless = !p.joints_held && self.tan_phi(p) == 0.0 && self.cohesion(p) == 0.0;
        match law::settle(self.rec.state, self.dn, close_tol, frictionless) {
            Settled::Open => {
                self.rec.state = ContactState::Open;
                self.clear_normal_force();
            }
            Settled::Slide => {
                self.rec.state = ContactState::Slide;
                self.rec.intact = false;
            }
            // A sliding contact settled locked keeps its friction, as one that sticks does: a
            // fresh spring dropped it, and a block whose corner sat at its friction limit,
            // flipping between lock and slide until it was settled, crept 0.5 mm in 10 s.
            Settled::Lock { fresh_spring: true } if self.rec.state == ContactState::Slide => {
                self.stick(p);
            }
            Settled::Lock { fresh_spring: true } => {
                self.rec.state = ContactState::Lock;
                self.rec.reference = self.cand.xb;
            }
            Settled::Lock {
                fresh_spring: false,
            } => {}
        }
        if self.rec.state.is_closed() && self.force < 0.0 {
            self.release_tension(p);
        }
    }

    /// A contact settled closed across a small gap (below the closing threshold) holds the
    /// blocks together by p_n·d_n. At an adapted penalty of up to γE that was a glue: after
    /// the equilibrium stage of a jointed slope, 118 settled contacts held up to 0.6 MN of
    /// tension each, and blocks free to slide on their joint stood for seconds. Back at p_n,1,
    /// the tension it can hold is at most p_n,1 · `close_threshold` · w0 (its gap is below the
    /// closing threshold), the size of the open test's threshold.
    fn release_tension(&mut self, p: &SolverParams) {
        if self.rec.penalty > p.contact.initial_penalty {
            self.set_penalty(p.contact.initial_penalty, &p.contact);
            self.clear_normal_force();
        }
    }

    /// Back to the start of the step for another attempt: its record, its face (where an attempt
    /// moved it, see [`FaceAtStart`]), and the normal force its friction takes, as activation
    /// set them. (The record alone was restored: an attempt redone
    /// after an ALM loop had run away began with that loop's friction, 10²¹⁷ N, and every
    /// shorter Δt failed in its first solve until the run was declared diverged.)
    pub fn restart(&mut self, p: &SolverParams) {
        if let Some(face) = self.face_at_start.take() {
            let FaceAtStart {
                cand,
                kin,
                alt_kin,
                overlap,
                released,
            } = *face;
            (self.cand, self.kin, self.alt_kin) = (cand, kin, alt_kin);
            self.start.overlap = overlap;
            self.released = released;
        }
        self.rec = self.start;
        self.friction_normal = initial_friction_normal(p, &self.start);
    }

    /// Opens the contact: no normal force, and no cohesion once it has opened.
    pub fn open(&mut self) {
        self.rec.state = ContactState::Open;
        self.clear_normal_force();
        self.rec.intact = false;
    }

    /// Drops the contact's normal force: its multiplier λ, the force its friction takes and
    /// the multiplier it would carry into the next step (a contact that opens, closes afresh,
    /// or lets go of a tension it cannot hold).
    pub fn clear_normal_force(&mut self) {
        self.rec.lambda = 0.0;
        self.friction_normal = 0.0;
        self.lambda_solved = None;
    }

    /// Sets p_n, keeping the shear spring's force: its stiffness p_τ is proportional to p_n, so
    /// its extension is scaled by the inverse ratio (shortened as (P21) raises p_n, stretched as
    /// [`Active::release_tension`] lowers it), and no energy is created.
    pub fn set_penalty(&mut self, penalty: f64, cp: &ContactParams) {
        let ratio = cp.shear_penalty(self.rec.penalty, self.inertia)
            / cp.shear_penalty(penalty, self.inertia);
        let delta = self.cand.xa - self.rec.reference;
        self.rec.reference = self.cand.xa - delta * ratio;
        self.rec.penalty = penalty;
    }

    /// Locks a sliding contact with the friction it had: its new shear spring starts stretched
    /// along τ so that p_τ·|Δ| equals that friction. A spring started at zero dropped the shear
    /// the contact carried; the other contacts took it and slipped, and a stable block ratcheted
    /// downhill step by step (issue #12).
    pub fn stick(&mut self, p: &SolverParams) {
        let friction = self.sliding_friction(p);
        let p_tau = p.contact.shear_penalty(self.rec.penalty, self.inertia);
        self.rec.state = ContactState::Lock;
        self.rec.reference = self.cand.xb - self.rec.tau * (friction / p_tau);
    }

    /// Shortens a locked contact's shear spring to [`SHEAR_CAP`] times what the joint can hold,
    /// N tan φ (+ cohesion while intact), N the larger of the last solve's and λ: the stick
    /// update of the ALM loop ([`super::alm`]) moves the reference point by every slip the
    /// contact makes, and where the contacts around it are in the wrong states, so that it
    /// keeps slipping, the spring's force grew without bound within the loop: 3 GN at contacts
    /// of 1 MN blocks of a jointed slope, which the step then turned into 100 MJ of kinetic
    /// energy at any Δt. The open–close check lets a contact whose spring is beyond the strength
    /// slide. (Capped at the strength itself, λ still converging, the corners of the struck wall
    /// in `tests/rockfall.rs` slipped and its rock stuck instead of rebounding.)
    pub fn cap_shear(&mut self, p: &SolverParams) {
        let n = self.cand.normal;
        let r = self.cand.xa - self.rec.reference;
        let along = r - n * n.dot(&r);
        let p_tau = p.contact.shear_penalty(self.rec.penalty, self.inertia);
        let strength = (SHEAR_CAP
            * (self.force.max(self.rec.lambda).max(0.0) * self.tan_phi(p) + self.cohesion(p)))
        .max(self.weight);
        let force = p_tau * along.norm();
        if force > strength {
            self.rec.reference += along * (1.0 - strength / force);
        }
    }

    /// Sets k⊥ of a sliding contact whose slip over the step is (or is expected to be) `slip`
    /// long: its friction over that slip (the derivative of friction's direction), at most the
    /// shear spring's p_τ, since a contact sliding is no stiffer across its slip than it is
    /// locked. DDA-3p keeps Shi's friction, a load alone.
    pub fn set_lateral(&mut self, p: &SolverParams, slip: f64) {
        // A frictionless joint has nothing to be stiff with (at no slip k⊥ would be p_τ).
        self.lateral = if p.method == Method::Alm
            && self.rec.state == ContactState::Slide
            && self.tan_phi(p) > 0.0
        {
            let p_tau = p.contact.shear_penalty(self.rec.penalty, self.inertia);
            let friction = self.sliding_friction(p);
            if friction < p_tau * slip {
                friction / slip
            } else {
                p_tau
            }
        } else {
            0.0
        };
    }

    /// k⊥ at the start of an attempt of length `dt`: the slip expected over the step is what
    /// the blocks' relative tangential velocity gives.
    pub fn predict_lateral(&mut self, p: &SolverParams, blocks: &[Block], dt: f64) {
        self.set_lateral(p, self.carried(blocks, dt).norm());
    }

    /// The tangential motion the blocks' velocities at the step's start give the contact over
    /// `dt`, m ([`crate::contact::law::Observation::carried`]).
    pub fn carried(&self, blocks: &[Block], dt: f64) -> Vec3 {
        let v = self.relative_velocity(blocks);
        let n = self.cand.normal;
        (v - n * n.dot(&v)) * dt
    }

    /// The locked shear spring's extension N(Δ + Δu_ab) for the relative displacement `du` of a
    /// solve, m: tangential.
    pub fn spring_extension(&self, du: &Vec3) -> Vec3 {
        let n = self.cand.normal;
        let r = (self.cand.xa - self.rec.reference) + du;
        r - n * n.dot(&r)
    }

    /// The common-plane rule on the solution `d` for a V–F contact with alternative faces: the
    /// vertex is outside block j when it is outside any one face, so the face that matters is
    /// the one it ends least deep behind. An open contact takes that face (it closes on it if
    /// even that one is penetrated); a closed one is clear, and returns true, when the vertex
    /// ends beyond the closing threshold outside another face. Only an open contact changes
    /// face: it has no stiffness in K, which is kept in step with each contact's geometry.
    pub fn reconsider_face(&mut self, p: &SolverParams, d: &[f64]) -> bool {
        let (di, dj) = self.increments(d);
        let deepest = self
            .alt_kin
            .iter()
            .map(|k| k.penetration(&di, &dj))
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1));
        let Some((k, dn)) = deepest else {
            return false;
        };
        if self.rec.state.is_closed() {
            return dn < -p.contact.close_threshold * self.w0;
        }
        if dn < self.dn {
            if self.face_at_start.is_none() {
                self.face_at_start = Some(Box::new(FaceAtStart {
                    cand: self.cand.clone(),
                    kin: self.kin,
                    alt_kin: self.alt_kin.clone(),
                    overlap: self.start.overlap,
                    released: self.released,
                }));
            }
            // A kept overlap belongs to the face it was measured on.
            self.kin.d0 += self.rec.overlap;
            self.rec.overlap = 0.0;
            self.start.overlap = 0.0;
            self.released = 0.0;
            self.cand.switch_face(k);
            std::mem::swap(&mut self.kin, &mut self.alt_kin[k]);
            self.rec.normal = self.cand.normal;
            self.dn = dn;
        }
        false
    }

    /// See [`StiffnessKey`].
    pub fn stiffness_key(&self) -> Option<StiffnessKey> {
        match self.rec.state {
            ContactState::Open => None,
            ContactState::Slide => Some(StiffnessKey {
                lock: false,
                penalty: self.rec.penalty,
                reference: Vec3::zeros(),
                tau: self.rec.tau,
                lateral: self.lateral,
            }),
            ContactState::Lock => Some(StiffnessKey {
                lock: true,
                penalty: self.rec.penalty,
                reference: self.rec.reference,
                tau: Vec3::zeros(),
                lateral: 0.0,
            }),
        }
    }

    /// The velocity of block i at the contact point against block j's at its point, m/s.
    pub fn relative_velocity(&self, blocks: &[Block]) -> Vec3 {
        let (i, j) = self.blocks();
        self.ta(blocks) * blocks[i].velocity
            - self.tb_at(&self.cand.xb, blocks) * blocks[j].velocity
    }

    /// Δu_ab = T_a D_i − T_b D_j (reference §6.1) for the solution `d`.
    pub fn relative_displacement(&self, d: &[f64], blocks: &[Block]) -> Vec3 {
        let (di, dj) = self.increments(d);
        self.ta(blocks) * di - self.tb(blocks) * dj
    }

    /// The displacement increments D_i, D_j of the contact's two blocks in the solution `d`.
    pub fn increments(&self, d: &[f64]) -> (Vec12, Vec12) {
        let (i, j) = self.blocks();
        (
            Vec12::from_column_slice(&d[12 * i..12 * i + 12]),
            Vec12::from_column_slice(&d[12 * j..12 * j + 12]),
        )
    }

    /// The friction of a sliding contact from the previous iterate's normal force (5.8):
    /// λ_{k−1} tan φ (ALM), held once the slip has reversed (see the ALM loop), or p_n d_n tan φ
    /// (penalty), N.
    pub fn sliding_friction(&self, p: &SolverParams) -> f64 {
        let n_prev = if p.method == Method::Alm {
            self.friction_normal
                .min(self.friction_cap.unwrap_or(f64::INFINITY))
        } else {
            self.rec.normal_force.max(0.0)
        };
        n_prev * self.tan_phi(p)
    }

    /// The cohesive force the contact holds, N: its joint's cohesion over its share of the
    /// joint's area while it is intact (closed since t = 0), none once it has opened or slid.
    pub fn cohesion(&self, p: &SolverParams) -> f64 {
        if self.rec.intact {
            p.joint_of(self.joint).cohesion * self.rec.cohesion_area
        } else {
            0.0
        }
    }

    /// tan φ of the contact's joint.
    pub fn tan_phi(&self, p: &SolverParams) -> f64 {
        p.joint_of(self.joint).friction_angle.to_radians().tan()
    }

    /// T_a at the contact point of block i. Taken when needed, as T_b is, rather than kept: it
    /// was a quarter of each contact's 1.2 kB, read through in every sweep over the contacts.
    pub fn ta(&self, blocks: &[Block]) -> Mat3x12 {
        displacement_matrix(&(self.cand.xa - blocks[self.cand.key.i as usize].mp.centroid))
    }

    /// T_b at the contact's point of block j: the spring's reference point if locked.
    pub fn tb(&self, blocks: &[Block]) -> Mat3x12 {
        let xb = match self.rec.state {
            ContactState::Lock => self.rec.reference,
            _ => self.cand.xb,
        };
        self.tb_at(&xb, blocks)
    }

    /// T_b at the point `xb` of block j.
    pub fn tb_at(&self, xb: &Vec3, blocks: &[Block]) -> Mat3x12 {
        displacement_matrix(&(xb - blocks[self.cand.key.j as usize].mp.centroid))
    }
}

/// The normal force a contact's friction takes at the start of a step: the force the last step
/// ended with under the ALM's warm start (its λ carries less: `commit::commit_contact`), else 0.
pub(crate) fn initial_friction_normal(p: &SolverParams, start: &ContactRecord) -> f64 {
    if p.contact.warm_start && p.method == Method::Alm {
        start.normal_force.max(0.0)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::Solver;

    /// A cube resting on a slab after a few steps: its contacts for the next step, each with the
    /// normal force the last step ended with.
    fn resting_cube() -> (Solver, Vec<Active>) {
        let s = crate::scene::parse(crate::solver::CUBE_ON_SLAB, "cube.toml", "cube")
            .expect("scene parses");
        let mut solver = Solver::new(s.model, s.params);
        for _ in 0..3 {
            solver.step().expect("steps");
        }
        let active = solver.next_contacts();
        (solver, active)
    }

    /// A redone attempt starts from the step's start: the record and the normal force friction
    /// takes, whatever the failed attempt left in them.
    #[test]
    fn a_restarted_contact_takes_up_its_friction_from_the_start_of_the_step() {
        let (solver, mut active) = resting_cube();
        let p = &solver.params;
        assert!(
            active.iter().any(|c| c.friction_normal > 0.0),
            "the cube bears on the slab"
        );
        let before: Vec<f64> = active.iter().map(|c| c.friction_normal).collect();
        for c in active.iter_mut() {
            c.rec.lambda = 1e217;
            c.rec.state = ContactState::Slide;
            c.friction_normal = 1e217;
        }
        for (c, &n0) in active.iter_mut().zip(&before) {
            c.restart(p);
            assert_eq!(c.rec.state, c.start.state);
            assert_eq!(c.rec.lambda, c.start.lambda);
            assert_eq!(c.friction_normal, n0);
            assert_eq!(n0, initial_friction_normal(p, &c.start));
        }
    }

    /// A redone attempt also starts on the face the contact had at the start of the step. A
    /// failed attempt could move an open vertex–face contact to another face of block j; kept
    /// there, a corner of a sliver in a collapsing jointed cube started the shorter attempts
    /// 0.55 mm behind the plane of a face it had not touched, and the step that pushed it out
    /// raised the kinetic energy from 0.15 to 1.5 kJ.
    #[test]
    fn a_restarted_contact_is_back_on_its_face_of_the_start_of_the_step() {
        // The cube's corners at x = 0.5 stand on the top edge of a slab that ends there, tied
        // between its top and its side (such a contact starts open).
        let scene = crate::solver::CUBE_ON_SLAB
            .replace(
                "size = [4.0, 4.0, 1.0], center = [0.0, 0.0, -0.5]",
                "size = [1.0, 4.0, 1.0], center = [0.0, 0.0, -0.5]",
            )
            .replace("center = [0.0, 0.0, 0.5]", "center = [1.0, 0.0, 0.5]");
        let s = crate::scene::parse(&scene, "cubes.toml", "cubes").expect("scene parses");
        let solver = Solver::new(s.model, s.params);
        let p = &solver.params;
        let mut active = solver.next_contacts();
        let c = active
            .iter_mut()
            .find(|c| !c.cand.alternatives.is_empty() && c.rec.state == ContactState::Open)
            .expect("a corner tied between faces");
        let (key, normal, d0) = (c.cand.key, c.cand.normal, c.kin.d0);
        let faces: Vec<u32> = c.cand.alternatives.iter().map(|a| a.face).collect();
        // As if a solve had left the vertex deep behind its face: the check moves it.
        c.dn = 1.0;
        c.reconsider_face(p, &[0.0; 24]);
        assert_ne!(
            c.cand.key, key,
            "the failed attempt moved the contact to another face"
        );
        c.restart(p);
        assert_eq!(c.cand.key, key);
        assert_eq!(c.cand.normal, normal);
        assert_eq!(c.kin.d0, d0);
        assert_eq!(c.rec.normal, normal);
        let after: Vec<u32> = c.cand.alternatives.iter().map(|a| a.face).collect();
        assert_eq!(after, faces);
        assert!(c.face_at_start.is_none());
    }

    /// A contact first seen overlapping by a depth the step's Δt could push out is kept once an
    /// attempt is cut so short that it could not ([`pushed_out_within`]), and only once however
    /// often the step is redone.
    #[test]
    fn a_shorter_attempt_keeps_a_fresh_overlap_once() {
        let (solver, mut active) = resting_cube();
        let p = &solver.params;
        let c = &mut active[0];
        let (d0, depth) = (c.kin.d0, 1e-4);
        c.fresh_depth = depth;
        c.release_overlap(1e-2);
        assert_eq!(
            (c.kin.d0, c.rec.overlap),
            (d0, 0.0),
            "pushed out within 10 ms"
        );
        let given_back = (depth * 1e-3 / OVERLAP_RELEASE_TIME).min(OVERLAP_RELEASE_SPEED * 1e-3);
        for _ in 0..2 {
            c.restart(p);
            c.release_overlap(1e-3);
            assert_eq!(c.start.overlap, depth);
            assert!((c.rec.overlap - (depth - given_back)).abs() < 1e-15);
            assert!((c.kin.d0 - (d0 - depth + given_back)).abs() < 1e-15);
        }
    }
}
