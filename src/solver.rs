//! The DDA-3a / DDA-3p time-stepping solver: assembly, the open–close iteration with the inner
//! augmented-Lagrangian loop (paper Fig. 3), the adaptive penalty (P21), the convergence tests
//! (P22)–(P24) and time-step control (reference §6.3, §8).

use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use nalgebra::{Matrix6, Vector6};

use crate::contact::{
    Candidate, ContactForces, ContactKey, ContactState, ContactStiffness, DetectionParams,
    NormalKinematics, Shape, add_friction, add_normal_force, add_normal_stiffness,
    add_shear_spring_force, add_shear_spring_stiffness, broad_phase, detect_pair,
    normal_kinematics, planar_hull_area,
};
use crate::geometry::{
    MassProperties, Topology, Vec3, bounding_box, mass_properties, newell_normal,
};
use crate::linear::{BlockMatrix, SparseCholesky};
use crate::mechanics::{
    BlockStepInput, Mat3x12, Mat12, Material, StepMap, Vec12, block_terms, displacement_matrix,
    elasticity_matrix, mass_matrix, rotate_stress,
};
use crate::params::{Method, Mode, SolverParams};
use crate::snapshot::{BlockSnapshot, ContactSnapshot, Snapshot, StepStats};

/// One deformable block and its state carried between steps.
#[derive(Clone, Debug)]
pub struct Block {
    pub name: String,
    pub material: Material,
    /// Held at every vertex by springs of `fixed_spring_factor · E`.
    pub fixed: bool,
    pub vertices: Vec<Vec3>,
    pub topo: Arc<Topology>,
    /// Unit outward normals, refreshed with the vertices.
    pub face_normals: Vec<Vec3>,
    pub mp: MassProperties,
    /// Constant mass; the density follows the volume so that mass is conserved (§1.3).
    pub mass: f64,
    pub density: f64,
    pub mass_matrix: Mat12,
    pub elasticity: Matrix6<f64>,
    /// 12-vector of DOF rates carried between steps (§3.2).
    pub velocity: Vec12,
    /// Accumulated stress [σx, σy, σz, τyz, τzx, τxy], Pa.
    pub stress: Vector6<f64>,
    pub strain: Vector6<f64>,
    /// Spring anchors of a fixed block: the initial vertex positions.
    pub anchors: Vec<Vec3>,
    /// Point loads: (material point, force N).
    pub loads: Vec<(Vec3, Vec3)>,
    pub initial_centroid: Vec3,
    pub lo: Vec3,
    pub hi: Vec3,
}

impl Block {
    /// A block from its hull; `velocity` is the initial centroid velocity and `spin` the initial
    /// angular velocity (rad/s).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        name: String,
        material: Material,
        fixed: bool,
        vertices: Vec<Vec3>,
        topo: Topology,
        velocity: Vec3,
        spin: Vec3,
        loads: Vec<(Vec3, Vec3)>,
    ) -> Self {
        let mp = mass_properties(&vertices, &topo.faces);
        let mut v = Vec12::zeros();
        v.fixed_rows_mut::<3>(0).copy_from(&velocity);
        v.fixed_rows_mut::<3>(3).copy_from(&spin);
        let mut b = Block {
            name,
            material,
            fixed,
            anchors: if fixed { vertices.clone() } else { Vec::new() },
            vertices,
            topo: Arc::new(topo),
            face_normals: Vec::new(),
            mp,
            mass: material.density * mp.volume,
            density: material.density,
            mass_matrix: Mat12::zeros(),
            elasticity: elasticity_matrix(material.young_modulus, material.poisson_ratio),
            velocity: v,
            stress: Vector6::zeros(),
            strain: Vector6::zeros(),
            loads,
            initial_centroid: mp.centroid,
            lo: Vec3::zeros(),
            hi: Vec3::zeros(),
        };
        b.refresh();
        b
    }

    /// Recomputes everything derived from the vertex positions.
    fn refresh(&mut self) {
        self.face_normals = self
            .topo
            .faces
            .iter()
            .map(|f| newell_normal(&self.vertices, f).normalize())
            .collect();
        self.mp = mass_properties(&self.vertices, &self.topo.faces);
        self.density = self.mass / self.mp.volume;
        self.mass_matrix = mass_matrix(self.density, &self.mp);
        let (lo, hi) = bounding_box(&self.vertices);
        self.lo = lo;
        self.hi = hi;
    }

    fn shape(&self) -> Shape<'_> {
        Shape {
            vertices: &self.vertices,
            topo: &self.topo,
            face_normals: &self.face_normals,
            centroid: self.mp.centroid,
            lo: self.lo,
            hi: self.hi,
            fixed: self.fixed,
        }
    }

    /// ½ vᵀ M v.
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * (self.velocity.transpose() * self.mass_matrix * self.velocity)[0]
    }

    /// Largest distance from the centroid to a vertex.
    fn radius(&self) -> f64 {
        self.vertices
            .iter()
            .map(|v| (v - self.mp.centroid).norm())
            .fold(0.0, f64::max)
    }
}

/// The blocks of a scene.
#[derive(Clone, Debug)]
pub struct Model {
    pub name: String,
    pub blocks: Vec<Block>,
}

/// What a contact carries from one step to the next (reference §4.5).
#[derive(Clone, Copy, Debug)]
struct Record {
    state: ContactState,
    /// λ, N (ALM only).
    lambda: f64,
    /// p_n, N/m.
    penalty: f64,
    /// Last normal force λ + p_n d_n (ALM) or p_n d_n (penalty), N.
    normal_force: f64,
    shear_force: f64,
    penetration: f64,
    /// Reference point P_b of a locked contact, moved with block j.
    reference: Vec3,
    /// Sliding direction of a relative to b.
    tau: Vec3,
    normal: Vec3,
    /// Closed since the start and never opened or slid: still has cohesion.
    intact: bool,
    /// Joint area attributed to the contact for cohesion, m².
    cohesion_area: f64,
    /// Overlap the contact was first seen with, m, taken out of d0 so that the contact stops
    /// further penetration without pushing the blocks apart (see `activate`).
    overlap: f64,
}

/// A contact inside a step: its frozen geometry and the working values of the iterations.
struct Active {
    cand: Candidate,
    kin: NormalKinematics,
    rec: Record,
    /// Record at the start of the step, restored when an attempt is redone.
    start: Record,
    ta: Mat3x12,
    pair: usize,
    young: f64,
    dn: f64,
    force: f64,
    dn_prev: Option<f64>,
    /// Friction magnitude of a sliding contact whose slip reversed in this pass, held (see
    /// `iterate`).
    friction_cap: Option<f64>,
    /// State changes of this contact in the current attempt (to stop open–close cycles).
    flips: u8,
    /// Settled after cycling: no more state changes in this attempt.
    frozen: bool,
    /// Changed state in the last open–close pass.
    changed: bool,
    /// N(Δ + Δu_ab) of a locked contact after the last solve.
    shear: Vec3,
    /// Δu_ab projected on the tangent plane after the last solve.
    slip: Vec3,
}

impl Active {
    /// The settled state of a contact whose open–close state does not converge (see
    /// `iterate`): closed and locked where the last solve left it touching or penetrating (with
    /// a fresh shear spring if it was not locked), open where it left a gap. A contact closed
    /// across a gap is a spring stretched by that gap: with an adapted penalty of up to γE it
    /// pulled a 12 mm gap shut within one step and gave a 40-block wall 0.1 MJ.
    fn settle(&mut self, close_tol: f64) {
        if self.dn < -close_tol {
            self.rec.state = ContactState::Open;
            self.rec.lambda = 0.0;
        } else if self.rec.state != ContactState::Lock {
            self.rec.state = ContactState::Lock;
            self.rec.reference = self.cand.xb;
        }
    }

    /// What this contact's stiffness depends on within an attempt (its kinematics are frozen):
    /// nothing if open; p_n if sliding; p_n and the reference point of the shear spring if locked.
    fn stiffness_key(&self) -> Option<StiffnessKey> {
        match self.rec.state {
            ContactState::Open => None,
            ContactState::Slide => Some(StiffnessKey {
                lock: false,
                penalty: self.rec.penalty,
                reference: Vec3::zeros(),
            }),
            ContactState::Lock => Some(StiffnessKey {
                lock: true,
                penalty: self.rec.penalty,
                reference: self.rec.reference,
            }),
        }
    }

    /// Δu_ab = T_a D_i − T_b D_j (reference §6.1) for the solution `d`.
    fn relative_displacement(&self, d: &[f64], blocks: &[Block]) -> Vec3 {
        let (i, j) = (self.cand.key.i as usize, self.cand.key.j as usize);
        let di = Vec12::from_column_slice(&d[12 * i..12 * i + 12]);
        let dj = Vec12::from_column_slice(&d[12 * j..12 * j + 12]);
        self.ta * di - self.tb(blocks) * dj
    }

    fn tb(&self, blocks: &[Block]) -> Mat3x12 {
        let xb = match self.rec.state {
            ContactState::Lock => self.rec.reference,
            _ => self.cand.xb,
        };
        self.tb_at(&xb, blocks)
    }

    /// T_b at the point `xb` of block j.
    fn tb_at(&self, xb: &Vec3, blocks: &[Block]) -> Mat3x12 {
        displacement_matrix(&(xb - blocks[self.cand.key.j as usize].mp.centroid))
    }
}

/// See [`Active::stiffness_key`].
#[derive(Clone, Copy, Debug, PartialEq)]
struct StiffnessKey {
    lock: bool,
    penalty: f64,
    reference: Vec3,
}

/// A run that cannot go on.
#[derive(Debug, Clone, thiserror::Error)]
pub enum SolverError {
    #[error("diverged at t = {time:.6} s: {reason}")]
    Diverged { time: f64, reason: String },
}

/// Wall time spent in the phases of the solver.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Timings {
    pub detection: f64,
    pub assembly: f64,
    pub factorization: f64,
    pub solve: f64,
    pub bookkeeping: f64,
}

/// Totals over a run, for `summary.json` and the benchmark.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RunTotals {
    pub steps: u64,
    pub open_close_iterations: u64,
    pub alm_iterations: u64,
    pub time_step_cuts: u64,
    pub factorizations: u64,
    pub symbolic_analyses: u64,
    pub max_penetration: f64,
    /// Largest kept overlap (see `StepStats::max_overlap`), m.
    pub max_overlap: f64,
    /// Steps whose open–close iteration did not converge within its pass limit and was settled
    /// (the contacts still changing closed and locked for one more solve): at the Δt floor, or
    /// with at most `SETTLE_FRACTION` of the contacts still changing.
    pub unconverged_steps: u64,
    /// ALM loops that hit the iteration cap.
    pub alm_cap_hits: u64,
    /// Contacts settled closed and locked: after cycling between states within one attempt, or
    /// still changing at the open–close pass limit (see `unconverged_steps`).
    pub frozen_contacts: u64,
    pub contacts_per_step: f64,
    pub timings: Timings,
}

/// `DDA3D_DEBUG=1` logs every state change and every Δt cut to stderr (for tuning).
fn debug_log() -> bool {
    static ON: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ON.get_or_init(|| std::env::var_os("DDA3D_DEBUG").is_some_and(|v| v != "0"))
}

/// Iterations of an ALM loop (after the first) at which (P21) may raise penalties. Each raise
/// means a new factorization; later iterations only update λ and reuse it (back-substitutions).
const PENALTY_ROUNDS: u32 = 2;

/// Penetrations below this fraction of the ALM tolerance ε1·d_n,max do not raise the penalty.
const PENALTY_FLOOR: f64 = 0.01;

/// Fraction of a kept overlap released each step (see `activate`).
const OVERLAP_RELEASE: f64 = 0.1;

/// State changes a contact may make in one attempt before it is settled (see `iterate`).
const MAX_FLIPS: u8 = 2;

/// At the open–close pass limit, a step whose last pass changed at most this fraction of its
/// contacts is settled (those contacts closed and locked, as at the Δt floor) instead of redone
/// with a shorter step. In a struck wall of 1000 blocks the last passes each changed 2 to 9 of
/// 11 500 contacts, scattered along the wall; each redo threw away 30 global passes and shortened
/// the following steps (9 redos in its first second). A small model, where one contact is more
/// than 1 %, keeps Shi's rule.
const SETTLE_FRACTION: f64 = 0.01;

/// The solution of one attempt at a step.
struct Solved {
    d: Vec<f64>,
    oc_passes: u32,
    solves: u32,
    /// The open–close iteration hit its limit and was settled.
    settled: bool,
}

enum Retry {
    OpenClose,
    Displacement(f64),
    Penetration(f64),
    NotFinite,
}

/// Steps a [`Model`] through time.
pub struct Solver {
    pub params: SolverParams,
    pub model: Model,
    pub time: f64,
    pub step: u64,
    dt: f64,
    /// Half the largest extent of the initial model (Shi's w0).
    w0: f64,
    records: HashMap<ContactKey, Record>,
    /// Block pairs of the last step's sparsity pattern (a < b).
    pattern: Vec<(usize, usize)>,
    chol: SparseCholesky,
    contacts: Vec<ContactSnapshot>,
    pub last: StepStats,
    pub totals: RunTotals,
    contact_sum: u64,
}

impl Solver {
    pub fn new(model: Model, params: SolverParams) -> Self {
        let all: Vec<Vec3> = model
            .blocks
            .iter()
            .flat_map(|b| b.vertices.iter().copied())
            .collect();
        let (lo, hi) = bounding_box(&all);
        let w0 = 0.5 * (hi - lo).max();
        let mut s = Solver {
            dt: params.max_time_step,
            params,
            model,
            time: 0.0,
            step: 0,
            w0,
            records: HashMap::new(),
            pattern: Vec::new(),
            chol: SparseCholesky::default(),
            contacts: Vec::new(),
            last: StepStats::default(),
            totals: RunTotals::default(),
            contact_sum: 0,
        };
        s.last = s.energy_stats(StepStats::default());
        s
    }

    pub fn w0(&self) -> f64 {
        self.w0
    }

    /// d_n,max = 2 δ w0 of (P22).
    pub fn max_step_penetration(&self) -> f64 {
        2.0 * self.params.max_displacement_ratio * self.w0
    }

    pub fn finished(&self) -> bool {
        self.time >= self.params.duration - 1e-9 * self.params.max_time_step
    }

    fn detection_params(&self) -> DetectionParams {
        DetectionParams::new(self.w0, self.params.max_displacement_ratio)
    }

    /// Advances one step, never past `duration`.
    pub fn step(&mut self) -> Result<&StepStats, SolverError> {
        self.step_until(self.params.duration)
    }

    /// Advances one step without passing `limit` (so that outputs land on requested times).
    pub fn step_until(&mut self, limit: f64) -> Result<&StepStats, SolverError> {
        let limit = limit.min(self.params.duration);
        let t_detect = Instant::now();
        if self.params.mode == Mode::Static {
            for b in &mut self.model.blocks {
                b.velocity = Vec12::zeros();
            }
        }
        let (mut active, near) = self.activate();
        // The sparsity pattern: block pairs with a contact now, plus pairs of the last pattern
        // that are still near each other. Keeping those (as zero blocks) makes the pattern, and
        // with it the symbolic analysis, stable while contacts come and go between neighbours.
        let pairs: Vec<(usize, usize)> = {
            let mut p: Vec<(usize, usize)> = active
                .iter()
                .map(|c| {
                    let (i, j) = (c.cand.key.i as usize, c.cand.key.j as usize);
                    (i.min(j), i.max(j))
                })
                .chain(
                    self.pattern
                        .iter()
                        .copied()
                        .filter(|q| near.binary_search(q).is_ok()),
                )
                .collect();
            p.sort_unstable();
            p.dedup();
            p
        };
        self.pattern = pairs.clone();
        let mut kmat = BlockMatrix::new(self.model.blocks.len(), pairs);
        for c in &mut active {
            c.pair = kmat
                .pair_index(c.cand.key.i as usize, c.cand.key.j as usize)
                .expect("pattern holds every contact pair");
        }
        self.totals.timings.detection += t_detect.elapsed().as_secs_f64();

        let dt_floor = self.params.max_time_step / 100.0;
        let remaining = limit - self.time;
        let base = self.dt.min(self.predict_dt());
        let mut dt = base;
        if remaining <= dt * (1.0 + 1e-9) {
            dt = remaining;
        } else if remaining < 2.0 * dt {
            dt = remaining / 2.0; // avoid a sliver of a step before the target time
        }
        let mut cuts = 0u32;
        let mut factorizations = 0u32;
        let (d, oc, alm) = loop {
            let at_floor = dt <= dt_floor * (1.0 + 1e-9);
            match self.iterate(&mut active, &mut kmat, dt, at_floor, &mut factorizations) {
                Ok(r) => {
                    self.totals.unconverged_steps += r.settled as u64;
                    break (r.d, r.oc_passes, r.solves);
                }
                Err(reason) => {
                    if at_floor {
                        match reason {
                            Retry::OpenClose => unreachable!("settled at the floor"),
                            Retry::NotFinite => {
                                return Err(self.diverged("the solution is not finite"));
                            }
                            Retry::Penetration(p) => {
                                return Err(self.diverged(&format!(
                                    "penetration {p:.3e} m exceeds the contact window at the minimum time step"
                                )));
                            }
                            Retry::Displacement(r) => {
                                return Err(self.diverged(&format!(
                                    "vertex displacement {r:.1} times the allowed δ·w0 at the minimum time step"
                                )));
                            }
                        }
                    }
                    if debug_log() {
                        let why = match &reason {
                            Retry::OpenClose => "open-close".to_string(),
                            Retry::Displacement(r) => format!("displacement r={r:.2}"),
                            Retry::Penetration(p) => format!("penetration {p:.2e}"),
                            Retry::NotFinite => "not finite".to_string(),
                        };
                        eprintln!("cut at t={:.4} dt={dt:.2e}: {why}", self.time);
                    }
                    dt = match reason {
                        Retry::Displacement(r) => dt / r.sqrt() * 0.95,
                        _ => dt * 0.3,
                    }
                    .max(dt_floor);
                    cuts += 1;
                    for c in &mut active {
                        c.rec = c.start;
                    }
                }
            }
        };
        let t_book = Instant::now();
        self.commit(&d, dt, &active);
        self.totals.timings.bookkeeping += t_book.elapsed().as_secs_f64();

        let stats = StepStats {
            time_step: dt,
            open_close_iterations: oc,
            alm_iterations: alm,
            time_step_cuts: cuts,
            factorizations,
            max_penetration: active
                .iter()
                .filter(|c| c.rec.state.is_closed())
                .map(|c| c.dn)
                .fold(0.0, f64::max),
            max_overlap: active
                .iter()
                .filter(|c| c.rec.state.is_closed())
                .map(|c| c.rec.overlap)
                .fold(0.0, f64::max),
            contacts_lock: self
                .contacts
                .iter()
                .filter(|c| c.state == ContactState::Lock)
                .count() as u32,
            contacts_slide: self
                .contacts
                .iter()
                .filter(|c| c.state == ContactState::Slide)
                .count() as u32,
            contacts_open: (active.len() - self.contacts.len()) as u32,
            ..Default::default()
        };
        self.totals.steps += 1;
        self.totals.open_close_iterations += oc as u64;
        self.totals.alm_iterations += alm as u64;
        self.totals.time_step_cuts += cuts as u64;
        self.totals.factorizations += factorizations as u64;
        self.totals.symbolic_analyses = self.chol.symbolic_count;
        self.totals.max_penetration = self.totals.max_penetration.max(stats.max_penetration);
        self.totals.max_overlap = self.totals.max_overlap.max(stats.max_overlap);
        self.contact_sum += active.len() as u64;
        self.totals.contacts_per_step = self.contact_sum as f64 / self.totals.steps as f64;
        self.last = self.energy_stats(stats);
        if debug_log() {
            let l = &self.last;
            eprintln!(
                "step t={:.4} dt={dt:.2e} kinetic={:.4e} potential={:.6e} elastic={:.4e} passes={oc} factorizations={factorizations}",
                self.time, l.kinetic_energy, l.potential_energy, l.elastic_energy
            );
        }
        // The step grows back by at most 1.3× a step (Shi); a step shortened only to land on
        // `limit` does not hold the next one back.
        let grown_from = if cuts > 0 { dt } else { base };
        self.dt = (grown_from * 1.3).min(self.params.max_time_step);
        Ok(&self.last)
    }

    fn diverged(&self, reason: &str) -> SolverError {
        SolverError::Diverged {
            time: self.time,
            reason: reason.to_string(),
        }
    }

    fn energy_stats(&self, mut s: StepStats) -> StepStats {
        let g = Vec3::from(self.params.gravity);
        s.kinetic_energy = self
            .model
            .blocks
            .iter()
            .filter(|b| !b.fixed)
            .map(Block::kinetic_energy)
            .sum();
        s.potential_energy = self
            .model
            .blocks
            .iter()
            .filter(|b| !b.fixed)
            .map(|b| -b.mass * g.dot(&b.mp.centroid))
            .sum();
        s.elastic_energy = self
            .model
            .blocks
            .iter()
            .map(|b| 0.5 * b.mp.volume * b.stress.dot(&b.strain))
            .sum();
        s
    }

    /// Δt such that the fastest vertex moves at most δ·w0 under its current velocity and gravity
    /// (Shi's prediction from ½ a Δt² + v Δt = δ w0).
    fn predict_dt(&self) -> f64 {
        let allowed = self.params.max_displacement_ratio * self.w0 * 0.9;
        let a = Vec3::from(self.params.gravity).norm().max(1e-12);
        let mut dt = self.params.max_time_step;
        if self.params.mode == Mode::Static {
            return dt;
        }
        let search = self.detection_params().search_distance;
        for (i, b) in self
            .model
            .blocks
            .iter()
            .enumerate()
            .filter(|(_, b)| !b.fixed)
        {
            let v = &b.velocity;
            let r = b.radius();
            let speed = Vec3::new(v[0], v[1], v[2]).norm()
                + Vec3::new(v[3], v[4], v[5]).norm() * r
                + v.fixed_rows::<6>(6).norm() * r;
            let t = (-speed + (speed * speed + 2.0 * a * allowed).sqrt()) / a;
            if t < dt {
                let dt_max = self.params.max_time_step;
                let reach = speed * dt_max + 0.5 * a * dt_max * dt_max + search;
                if self.isolated(i, reach) {
                    continue;
                }
                dt = t;
            }
        }
        dt.max(self.params.max_time_step / 100.0)
    }

    /// True when no other block comes within `reach` of block `i`'s bounding box: a block in
    /// free flight. The constant-acceleration step integrates its motion exactly, and δ·w0,
    /// which keeps the contact linearisation and the detection window valid, need not limit
    /// its step. (A rock that bounced off the ground slab's edge fell for 90 s at the Δt floor
    /// and was then reported as diverged.)
    fn isolated(&self, i: usize, reach: f64) -> bool {
        let b = &self.model.blocks[i];
        let (lo, hi) = (b.lo - Vec3::repeat(reach), b.hi + Vec3::repeat(reach));
        self.model
            .blocks
            .iter()
            .enumerate()
            .all(|(k, o)| k == i || (0..3).any(|d| o.hi[d] < lo[d] || o.lo[d] > hi[d]))
    }

    /// Detects this step's contacts and attaches each to its record from the last step, or to a
    /// new one (reference §4.5).
    fn activate(&mut self) -> (Vec<Active>, Vec<(usize, usize)>) {
        let dp = self.detection_params();
        let blocks = &self.model.blocks;
        let shapes: Vec<Shape> = blocks.iter().map(Block::shape).collect();
        let pairs = broad_phase(&shapes, dp.search_distance);
        let near = pairs.clone();
        let records = &self.records;
        let known = |k: &ContactKey| records.contains_key(k);
        let mut cands: Vec<Candidate> = Vec::new();
        for &(a, b) in &pairs {
            cands.extend(detect_pair(a, &shapes[a], b, &shapes[b], &dp, &known));
        }
        // Contact transfer: a vertex that slid onto an adjacent, almost coplanar face of the same
        // block keeps its history.
        let mut by_vertex: HashMap<(u32, u32, u32), ContactKey> = HashMap::new();
        for k in self.records.keys() {
            if k.mode == 0 {
                by_vertex.insert((k.i, k.j, k.feature_i), *k);
            }
        }
        let p = &self.params;
        let first_step = self.step == 0;
        let close_tol = p.contact.close_threshold * self.w0;
        let overlap_tol = p.contact.eps1 * self.max_step_penetration();
        let mut active: Vec<Active> = cands
            .into_iter()
            .map(|cand| {
                let (bi, bj) = (&blocks[cand.key.i as usize], &blocks[cand.key.j as usize]);
                let mut kin = normal_kinematics(
                    cand.mode(),
                    &cand.points,
                    &cand.normal,
                    &bi.mp.centroid,
                    &bj.mp.centroid,
                );
                let old = self.records.get(&cand.key).copied().or_else(|| {
                    if cand.key.mode != 0 {
                        return None;
                    }
                    let k = by_vertex.get(&(cand.key.i, cand.key.j, cand.key.feature_i))?;
                    let r = self.records.get(k)?;
                    (r.normal.dot(&cand.normal) > 3f64.to_radians().cos()).then_some(*r)
                });
                let mut rec = match old {
                    Some(mut r) => {
                        // Warm start: λ and the adapted p_n carry over. Resetting p_n to p_n,1
                        // every step was tried: with ε2 = 0.01 the multiplier then lags by up to
                        // 1 % a step, and a standing column slowly rocks itself apart.
                        if !p.contact.warm_start || p.method == Method::Penalty {
                            r.lambda = 0.0;
                            r.penalty = p.contact.initial_penalty;
                        }
                        r.normal = cand.normal;
                        r
                    }
                    None => {
                        // A new contact touching or overlapping at the start is closed (locked);
                        // one across a gap starts open.
                        let touching = -cand.gap > -close_tol;
                        Record {
                            state: if touching {
                                ContactState::Lock
                            } else {
                                ContactState::Open
                            },
                            lambda: 0.0,
                            penalty: p.contact.initial_penalty,
                            normal_force: 0.0,
                            shear_force: 0.0,
                            penetration: -cand.gap,
                            reference: cand.xb,
                            tau: Vec3::zeros(),
                            normal: cand.normal,
                            intact: first_step && touching,
                            cohesion_area: 0.0,
                            overlap: 0.0,
                        }
                    }
                };
                if p.method == Method::Penalty {
                    rec.penalty = p.contact.initial_penalty;
                }
                // A contact seen for the first time already deeper than the ALM tolerance (a
                // corner that slipped past detection, or an open contact whose linearised gap
                // was wrong) keeps that overlap instead of having it pushed out in one step:
                // resolved within one step, an overlap of millimetres takes meganewtons and comes
                // back as kinetic energy the system never had. The overlap is taken out of d0; it
                // shrinks as the blocks separate and by OVERLAP_RELEASE of itself a step.
                let unseen = old.is_none_or(|r| r.state == ContactState::Open);
                rec.overlap = (rec.overlap * (1.0 - OVERLAP_RELEASE)).min(kin.d0.max(0.0));
                if unseen && kin.d0 > overlap_tol {
                    rec.overlap = kin.d0;
                    if debug_log() {
                        eprintln!(
                            "t={:.4}: contact {:?} first seen {:.3e} m deep; the overlap is kept",
                            self.time, cand.key, kin.d0
                        );
                    }
                }
                kin.d0 -= rec.overlap;
                let ta = displacement_matrix(&(cand.xa - bi.mp.centroid));
                Active {
                    kin,
                    ta,
                    young: bi.material.young_modulus.min(bj.material.young_modulus),
                    start: rec,
                    rec,
                    cand,
                    pair: 0,
                    dn: 0.0,
                    force: 0.0,
                    dn_prev: None,
                    friction_cap: None,
                    flips: 0,
                    frozen: false,
                    changed: false,
                    shear: Vec3::zeros(),
                    slip: Vec3::zeros(),
                }
            })
            .collect();
        if first_step && p.joint.cohesion > 0.0 {
            assign_cohesion_areas(&mut active);
        }
        (active, near)
    }

    /// (K0, F0): the block terms of §3 for a step of length `dt`, fixed for an attempt.
    fn block_terms(&self, dt: f64) -> (Vec<Mat12>, Vec<Vec12>) {
        let p = &self.params;
        let g = Vec3::from(p.gravity);
        let mut k0 = Vec::with_capacity(self.model.blocks.len());
        let mut f0 = Vec::with_capacity(self.model.blocks.len());
        for b in &self.model.blocks {
            let springs: Vec<(Vec3, Vec3, f64)> = if b.fixed {
                let k = p.fixed_spring_factor * b.material.young_modulus;
                b.vertices
                    .iter()
                    .zip(&b.anchors)
                    .map(|(x, a)| (*x, *a, k))
                    .collect()
            } else {
                Vec::new()
            };
            let terms = block_terms(
                &BlockStepInput {
                    mass_matrix: &b.mass_matrix,
                    mp: &b.mp,
                    density: b.density,
                    elasticity: &b.elasticity,
                    stress: &b.stress,
                    velocity: &b.velocity,
                    gravity: &g,
                    loads: &b.loads,
                    springs: &springs,
                },
                dt,
            );
            k0.push(terms.k);
            f0.push(terms.f);
        }
        (k0, f0)
    }

    /// The stiffness of one closed contact in the state `key`: normal (P10), and the shear spring
    /// (P15)/(5.7) if locked (sliding friction (P20) adds loads only).
    fn contact_stiffness(&self, c: &Active, key: &StiffnessKey) -> ContactStiffness {
        let mut t = ContactStiffness::default();
        add_normal_stiffness(&mut t, &c.kin, key.penalty);
        if key.lock {
            let tb = c.tb_at(&key.reference, &self.model.blocks);
            let p_tau = self.params.contact.shear_penalty(key.penalty);
            add_shear_spring_stiffness(&mut t, &c.ta, &tb, &c.cand.normal, p_tau);
        }
        t
    }

    /// Adds (`sign` = 1) or removes (−1) the stiffness of contact `c` in the state `key`.
    fn apply_stiffness(&self, kmat: &mut BlockMatrix, c: &Active, key: &StiffnessKey, sign: f64) {
        let t = self.contact_stiffness(c, key);
        let (i, j) = (c.cand.key.i as usize, c.cand.key.j as usize);
        kmat.diag[i] += t.k_ii * sign;
        kmat.diag[j] += t.k_jj * sign;
        kmat.add_off(c.pair, i, j, &(t.k_ij * sign));
    }

    /// The force terms of one closed contact in its current state: normal (P10), locked shear
    /// spring (P15)/(5.7), or sliding friction (P20).
    fn contact_forces(&self, c: &Active) -> ContactForces {
        let p = &self.params;
        let mut t = ContactForces::default();
        let alm = p.method == Method::Alm;
        add_normal_force(
            &mut t,
            &c.kin,
            c.rec.penalty,
            if alm { c.rec.lambda } else { 0.0 },
        );
        let tb = c.tb(&self.model.blocks);
        match c.rec.state {
            ContactState::Lock => {
                let delta = c.cand.xa - c.rec.reference;
                let p_tau = p.contact.shear_penalty(c.rec.penalty);
                add_shear_spring_force(&mut t, &c.ta, &tb, &c.cand.normal, &delta, p_tau);
            }
            ContactState::Slide => {
                // Friction from the previous iterate's normal force: λ_{k−1} (ALM), p_n d_n
                // (penalty); held for the rest of the ALM loop once the slip has reversed (see
                // `iterate`).
                let n_prev = if alm {
                    c.rec.lambda.min(c.friction_cap.unwrap_or(f64::INFINITY))
                } else {
                    c.rec.normal_force.max(0.0)
                };
                let tan_phi = p.joint.friction_angle.to_radians().tan();
                add_friction(&mut t, &c.ta, &tb, &c.rec.tau, n_prev * tan_phi);
            }
            ContactState::Open => {}
        }
        t
    }

    /// One attempt at the step with length `dt`: the open–close loop around the ALM loop.
    fn iterate(
        &mut self,
        active: &mut [Active],
        kmat: &mut BlockMatrix,
        dt: f64,
        at_floor: bool,
        factorizations: &mut u32,
    ) -> Result<Solved, Retry> {
        let p = self.params.clone();
        let cp = &p.contact;
        let nb = self.model.blocks.len();
        let t_asm = Instant::now();
        // (K0, F0): the block terms of §3, fixed for the attempt.
        let (k0, f0) = self.block_terms(dt);
        let mut timings = Duration::ZERO;
        timings += t_asm.elapsed();

        let tan_phi = p.joint.friction_angle.to_radians().tan();
        let dn_max = self.max_step_penetration();
        let close_tol = cp.close_threshold * self.w0;
        let state_tol = cp.open_threshold * self.w0;
        let warm = cp.warm_start && p.method == Method::Alm;
        let mut d = vec![0.0; 12 * nb];
        let mut oc_passes = 0u32;
        let mut solves = 0u32;
        for c in active.iter_mut() {
            c.flips = 0;
            c.frozen = false;
        }
        // If the open–close iteration has not converged after its pass limit, the attempt is
        // redone with 0.3 Δt (Shi). At the Δt floor, the last resort: one more solve with the
        // contacts that still changed settled closed and locked, and the step is accepted. So
        // also where the stragglers are few (see `SETTLE_FRACTION`).
        let mut settling = false;
        // The state each contact's stiffness is in K with; empty until K is first assembled.
        let mut in_k: Vec<Option<StiffnessKey>> = Vec::new();
        for oc_idx in 0..=cp.max_open_close_iterations {
            if oc_idx == cp.max_open_close_iterations {
                let stragglers = active.iter().filter(|c| c.changed).count() as f64;
                if !at_floor && stragglers > SETTLE_FRACTION * active.len() as f64 {
                    self.totals.timings.assembly += timings.as_secs_f64();
                    return Err(Retry::OpenClose);
                }
                for c in active.iter_mut().filter(|c| c.changed) {
                    c.settle(close_tol);
                    self.totals.frozen_contacts += 1;
                }
                settling = true;
            }
            oc_passes += 1;
            let mut k_dirty = true;
            for c in active.iter_mut() {
                c.dn_prev = None;
                c.friction_cap = None;
            }
            let mut alm_converged = false;
            for alm_k in 1..=cp.max_alm_iterations {
                let t0 = Instant::now();
                if k_dirty {
                    // K is updated, not rebuilt: only the contacts whose state, penalty or
                    // shear-spring reference changed since the last assembly swap their old
                    // stiffness for the new one. Rebuilding all of them at every state change
                    // or penalty raise took a fifth of a struck 100-block wall's run.
                    if in_k.is_empty() {
                        for (kd, k) in kmat.diag.iter_mut().zip(&k0) {
                            *kd = *k;
                        }
                        for o in kmat.off.iter_mut() {
                            *o = Mat12::zeros();
                        }
                        in_k = vec![None; active.len()];
                    }
                    for (c, slot) in active.iter().zip(in_k.iter_mut()) {
                        let want = c.stiffness_key();
                        if *slot == want {
                            continue;
                        }
                        if let Some(old) = slot {
                            self.apply_stiffness(kmat, c, old, -1.0);
                        }
                        if let Some(new) = &want {
                            self.apply_stiffness(kmat, c, new, 1.0);
                        }
                        *slot = want;
                    }
                }
                let mut f: Vec<f64> = f0.iter().flat_map(|v| v.iter().copied()).collect();
                for c in active.iter() {
                    if c.rec.state == ContactState::Open {
                        continue;
                    }
                    let (i, j) = (c.cand.key.i as usize, c.cand.key.j as usize);
                    let t = self.contact_forces(c);
                    for a in 0..12 {
                        f[12 * i + a] += t.f_i[a];
                        f[12 * j + a] += t.f_j[a];
                    }
                }
                timings += t0.elapsed();
                if k_dirty {
                    let tf = Instant::now();
                    let ok = self.chol.factorize(kmat);
                    self.totals.timings.factorization += tf.elapsed().as_secs_f64();
                    *factorizations += 1;
                    if ok.is_err() {
                        self.totals.timings.assembly += timings.as_secs_f64();
                        return Err(Retry::NotFinite);
                    }
                    k_dirty = false;
                }
                let ts = Instant::now();
                self.chol.solve_in_place(&mut f);
                self.totals.timings.solve += ts.elapsed().as_secs_f64();
                solves += 1;
                d = f;
                if d.iter().any(|x| !x.is_finite()) {
                    self.totals.timings.assembly += timings.as_secs_f64();
                    return Err(Retry::NotFinite);
                }
                let t1 = Instant::now();
                // d_n and N of every closed contact (5.4), (5.6).
                let mut max_dn: f64 = 0.0;
                let (mut dl2, mut l2) = (0.0, 0.0);
                for c in active.iter_mut() {
                    let (i, j) = (c.cand.key.i as usize, c.cand.key.j as usize);
                    let di = Vec12::from_column_slice(&d[12 * i..12 * i + 12]);
                    let dj = Vec12::from_column_slice(&d[12 * j..12 * j + 12]);
                    c.dn = c.kin.d0 + c.kin.g_i.dot(&di) + c.kin.g_j.dot(&dj);
                    if c.rec.state == ContactState::Open {
                        continue;
                    }
                    let lambda = if p.method == Method::Alm {
                        c.rec.lambda
                    } else {
                        0.0
                    };
                    c.force = lambda + c.rec.penalty * c.dn;
                    max_dn = max_dn.max(c.dn.abs());
                    if p.method == Method::Alm {
                        let new = c.force.max(0.0);
                        dl2 += (new - c.rec.lambda).powi(2);
                        l2 += c.rec.lambda.powi(2);
                    }
                }
                if p.method == Method::Penalty {
                    timings += t1.elapsed();
                    alm_converged = true;
                    break;
                }
                // (P23) and (P24); an unchanged zero force vector counts as converged.
                let conv1 = max_dn <= cp.eps1 * dn_max;
                let conv2 = dl2 == 0.0 || dl2.sqrt() < cp.eps2 * l2.sqrt();
                for c in active.iter_mut() {
                    if c.rec.state == ContactState::Open {
                        continue;
                    }
                    // (P1): λ_k = λ_{k−1} + p_n d_n, kept non-negative.
                    c.rec.lambda = c.force.max(0.0);
                    // (P21): raise the penalty where the penetration does not fall fast enough.
                    // Not for a contact whose penetration is already negligible against the
                    // tolerance ε1·d_n,max: there the ratio test only sees round-off, and over
                    // many steps it ratcheted every penalty of a standing wall up to γE, a
                    // stiffness that turned a 4 µm motion into meganewtons at the next impact.
                    if let Some(prev) = c.dn_prev
                        && alm_k <= PENALTY_ROUNDS + 1
                        && !(conv1 && conv2)
                        && c.dn.abs() > cp.beta * prev.abs()
                        && c.dn.abs() > PENALTY_FLOOR * cp.eps1 * dn_max
                    {
                        let capped = (c.rec.penalty * cp.alpha).min(cp.gamma * c.young);
                        if capped > c.rec.penalty {
                            // Keep the shear spring's force as its stiffness (p_τ ∝ p_n) grows:
                            // shorten the spring instead, so that no energy is created.
                            let shrink = cp.shear_penalty(c.rec.penalty) / cp.shear_penalty(capped);
                            let delta = c.cand.xa - c.rec.reference;
                            c.rec.reference = c.cand.xa - delta * shrink;
                            c.rec.penalty = capped;
                            k_dirty = true;
                        }
                    }
                    c.dn_prev = Some(c.dn);
                }
                // A sliding contact whose slip has reversed is in the wrong state, and its
                // friction, from λ_{k−1} (5.8), can feed back: where friction presses blocks into
                // other contacts (a wedge) the loop λ → friction → λ grew ×1.4 an iteration in a
                // struck wall, reaching metres of displacement within 20 iterations, and the
                // open–close check then classified every contact from that solution. The
                // friction of such a contact is held at its present value for the rest of the
                // pass (a change of F only: no refactorization); the open–close check locks it.
                if !settling {
                    for c in active.iter_mut() {
                        if c.rec.state != ContactState::Slide
                            || c.frozen
                            || c.friction_cap.is_some()
                        {
                            continue;
                        }
                        let du = c.relative_displacement(&d, &self.model.blocks);
                        if du.dot(&c.rec.tau) < -state_tol {
                            c.friction_cap = Some(c.rec.lambda);
                        }
                    }
                }
                timings += t1.elapsed();
                if conv1 && conv2 {
                    alm_converged = true;
                    break;
                }
            }
            if !alm_converged {
                self.totals.alm_cap_hits += 1;
            }
            if settling {
                break;
            }
            // Open–close check (reference §6.1).
            let t2 = Instant::now();
            let mut changed = false;
            for c in active.iter_mut() {
                c.changed = false;
                let n = c.cand.normal;
                let du = c.relative_displacement(&d, &self.model.blocks);
                c.slip = du - n * n.dot(&du);
                if c.frozen {
                    c.rec.normal_force = c.force;
                    continue;
                }
                let before = c.rec.state;
                'classify: {
                    match c.rec.state {
                        ContactState::Open => {
                            if c.dn > close_tol {
                                c.rec.state = ContactState::Lock;
                                c.rec.reference = c.cand.xb;
                                c.rec.lambda = 0.0;
                                // A new contact starts at p_n,1 (§6.1). One that was closed at
                                // the start of the step and only opened in an earlier pass is
                                // not new: it keeps its adapted penalty, which spares the
                                // (P21) rounds, and their factorizations, of raising it again.
                                c.rec.penalty = if c.start.state.is_closed() && warm {
                                    c.start.penalty
                                } else {
                                    cp.initial_penalty
                                };
                                c.rec.normal_force = 0.0;
                                changed = true;
                            }
                        }
                        ContactState::Lock | ContactState::Slide => {
                            c.rec.normal_force = c.force;
                            // Shi's opening test, a gap beyond f0·w0, as a force: tension beyond
                            // p_n,1·f0·w0. The initial penalty, not the adapted one, so that a stiffened
                            // contact cannot hold tension.
                            if c.force < -cp.initial_penalty * state_tol {
                                c.rec.state = ContactState::Open;
                                c.rec.lambda = 0.0;
                                c.rec.intact = false;
                                changed = true;
                                break 'classify;
                            }
                            if c.rec.state == ContactState::Lock {
                                let delta = c.cand.xa - c.rec.reference;
                                let r = delta + du;
                                c.shear = r - n * n.dot(&r);
                                let shear = cp.shear_penalty(c.rec.penalty) * c.shear.norm();
                                let cohesion = if c.rec.intact {
                                    p.joint.cohesion * c.rec.cohesion_area
                                } else {
                                    0.0
                                };
                                // Hysteresis: shear displacements below f0·w0 are not slip, so a
                                // contact that carries no normal force does not flip lock ↔ slide.
                                if c.shear.norm() > state_tol
                                    && shear > c.force * tan_phi + cohesion
                                {
                                    c.rec.state = ContactState::Slide;
                                    c.rec.tau = c.shear.normalize();
                                    c.rec.intact = false;
                                    changed = true;
                                }
                            } else if c.slip.dot(&c.rec.tau) < -state_tol
                                || c.slip.norm() < state_tol
                                || c.friction_cap
                                    .is_some_and(|cap| cap < (1.0 - cp.eps2) * c.rec.lambda)
                            {
                                // The slip reversed, or stopped: the contact sticks again. So
                                // does a contact whose friction was held (see the ALM loop) below
                                // its capacity λ tan φ: the slip reversed under a smaller friction
                                // and goes forward under the held one, so a friction within the
                                // capacity stops it.
                                c.rec.state = ContactState::Lock;
                                c.rec.reference = c.cand.xb;
                                changed = true;
                            } else if c.slip.norm() > state_tol {
                                // Friction follows the slip direction; it has not reversed here, so
                                // friction along the old direction still did negative work.
                                c.rec.tau = c.slip.normalize();
                            }
                        }
                    }
                }
                if c.rec.state != before && debug_log() {
                    eprintln!(
                        "t={:.4} dt={dt:.2e} pass {oc_passes}: {:?}->{:?} mode={} N={:.2e} dn={:.2e} p={:.0e} shear={:.2e} slip={:.2e} pair={}-{}",
                        self.time,
                        before,
                        c.rec.state,
                        c.cand.key.mode,
                        c.force,
                        c.dn,
                        c.rec.penalty,
                        c.shear.norm(),
                        c.slip.norm(),
                        c.cand.key.i,
                        c.cand.key.j
                    );
                }
                if c.rec.state != before {
                    c.changed = true;
                    c.flips += 1;
                    if c.flips > MAX_FLIPS {
                        // A contact that keeps cycling (typically an edge–edge and a vertex–face
                        // contact of one block pair taking the load in turn) is settled for the
                        // rest of the attempt, closed and locked: closed so that nothing passes
                        // through it, locked because a spring stores energy and gives it back,
                        // whereas sliding friction along a guessed direction can push the slip
                        // it should resist (settling as sliding fed a 100-block wall energy).
                        c.settle(close_tol);
                        self.totals.frozen_contacts += (before != c.rec.state) as u64;
                        changed |= before != c.rec.state;
                        c.flips = 0;
                        c.frozen = true;
                    }
                }
            }
            timings += t2.elapsed();
            if !changed {
                break;
            }
        }
        self.totals.timings.assembly += timings.as_secs_f64();
        // Step size checks on the converged solution.
        let allowed = p.max_displacement_ratio * self.w0;
        let search = self.detection_params().search_distance;
        let mut max_u: f64 = 0.0;
        for (i, b) in self.model.blocks.iter().enumerate() {
            let di = Vec12::from_column_slice(&d[12 * i..12 * i + 12]);
            let u = b
                .vertices
                .iter()
                .map(|v| (displacement_matrix(&(v - b.mp.centroid)) * di).norm())
                .fold(0.0, f64::max);
            // A block in free flight may move further (see `isolated`).
            if u > allowed && self.isolated(i, u + search) {
                continue;
            }
            max_u = max_u.max(u);
        }
        let r = max_u / allowed;
        if r > p.max_displacement_overshoot {
            return Err(Retry::Displacement(r));
        }
        let dpen = self.detection_params().max_penetration;
        let worst = active
            .iter()
            .filter(|c| c.rec.state.is_closed())
            .map(|c| c.dn)
            .fold(0.0, f64::max);
        if worst > dpen {
            return Err(Retry::Penetration(worst));
        }
        Ok(Solved {
            d,
            oc_passes,
            solves,
            settled: settling,
        })
    }

    /// Accepts the step: velocities, stresses, the finite-rotation vertex update (1.3), and the
    /// contact records for the next step.
    fn commit(&mut self, d: &[f64], dt: f64, active: &[Active]) {
        let p = &self.params;
        let tan_phi = p.joint.friction_angle.to_radians().tan();
        // Contact outputs use the start-of-step geometry moved by the step.
        let mut maps = Vec::with_capacity(self.model.blocks.len());
        for (i, b) in self.model.blocks.iter().enumerate() {
            let di = Vec12::from_column_slice(&d[12 * i..12 * i + 12]);
            maps.push(StepMap::new(b.mp.centroid, &di));
        }
        self.contacts.clear();
        let mut records = HashMap::with_capacity(active.len());
        for c in active {
            let mut rec = c.rec;
            let closed = rec.state.is_closed();
            rec.penetration = c.dn + rec.overlap;
            if closed {
                rec.normal_force = c.force;
                rec.shear_force = match rec.state {
                    ContactState::Lock => p.contact.shear_penalty(rec.penalty) * c.shear.norm(),
                    _ => {
                        let n_prev = if p.method == Method::Alm {
                            rec.lambda
                        } else {
                            rec.normal_force.max(0.0)
                        };
                        n_prev * tan_phi
                    }
                };
            } else {
                rec.normal_force = 0.0;
                rec.shear_force = 0.0;
            }
            let mj = &maps[c.cand.key.j as usize];
            rec.reference = mj.apply(&rec.reference);
            rec.tau = mj.rotation() * rec.tau;
            if closed {
                let point = mj.apply(&c.cand.xb);
                self.contacts.push(ContactSnapshot {
                    block_i: c.cand.key.i as usize,
                    block_j: c.cand.key.j as usize,
                    mode: c.cand.mode(),
                    state: rec.state,
                    point: point.into(),
                    normal: (mj.rotation() * c.cand.normal).into(),
                    normal_force: rec.normal_force,
                    shear_force: rec.shear_force,
                    penetration: c.dn + rec.overlap,
                    penalty: rec.penalty,
                    lambda: if p.method == Method::Alm {
                        rec.lambda
                    } else {
                        0.0
                    },
                });
            }
            records.insert(c.cand.key, rec);
        }
        self.records = records;

        for (i, b) in self.model.blocks.iter_mut().enumerate() {
            let di = Vec12::from_column_slice(&d[12 * i..12 * i + 12]);
            // (3.2): v1 = 2D/Δt − v0.
            b.velocity = di * (2.0 / dt) - b.velocity;
            let de = di.fixed_rows::<6>(6).into_owned();
            let map = &maps[i];
            if p.rotate_stress {
                b.stress = rotate_stress(&b.stress, map.rotation());
            }
            b.stress += b.elasticity * de;
            b.strain += de;
            for v in &mut b.vertices {
                *v = map.apply(v);
            }
            // Point loads are dead loads: the point moves with the block, the force keeps its
            // direction in space (as in Shi's code).
            for (pt, _) in &mut b.loads {
                *pt = map.apply(pt);
            }
            b.refresh();
        }
        self.time += dt;
        self.step += 1;
    }

    /// The state now, as plain data.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            scene_name: self.model.name.clone(),
            time: self.time,
            step: self.step,
            blocks: self
                .model
                .blocks
                .iter()
                .map(|b| BlockSnapshot {
                    name: b.name.clone(),
                    fixed: b.fixed,
                    vertices: b.vertices.iter().map(|v| (*v).into()).collect(),
                    faces: b
                        .topo
                        .faces
                        .iter()
                        .map(|f| f.iter().map(|&k| k as u32).collect())
                        .collect(),
                    centroid: b.mp.centroid.into(),
                    velocity: [b.velocity[0], b.velocity[1], b.velocity[2]],
                    displacement: (b.mp.centroid - b.initial_centroid).into(),
                })
                .collect(),
            contacts: self.contacts.clone(),
            stats: self.last.clone(),
        }
    }

    /// Closed contacts after the last step.
    pub fn contacts(&self) -> &[ContactSnapshot] {
        &self.contacts
    }
}

/// Shares each joint's contact area among its contact points (for cohesion, which acts only on
/// intact contacts of the initial state).
fn assign_cohesion_areas(active: &mut [Active]) {
    let mut groups: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (k, c) in active.iter().enumerate() {
        if c.rec.intact {
            let key = (
                c.cand.key.i.min(c.cand.key.j),
                c.cand.key.i.max(c.cand.key.j),
            );
            groups.entry(key).or_default().push(k);
        }
    }
    for idx in groups.values() {
        let pts: Vec<Vec3> = idx.iter().map(|&k| active[k].cand.xb).collect();
        let area = planar_hull_area(&pts, &active[idx[0]].cand.normal);
        for &k in idx {
            active[k].rec.cohesion_area = area / idx.len() as f64;
            active[k].start.cohesion_area = area / idx.len() as f64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::snapshot::ContactMode;

    /// The rockfall column run into the impact (0.25 s), where vertex–face and edge–edge contacts
    /// are active: the solver, its contacts for the next step, and their block pairs.
    fn at_impact() -> (Solver, Vec<Active>, Vec<(usize, usize)>) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes/rock_column_rockfall.toml");
        let s = crate::scene::load(&path).unwrap();
        let mut solver = Solver::new(s.model, s.params);
        while solver.time < 0.25 {
            solver.step().unwrap();
        }
        let (active, _) = solver.activate();
        let pairs = active
            .iter()
            .map(|c| (c.cand.key.i as usize, c.cand.key.j as usize))
            .collect();
        (solver, active, pairs)
    }

    /// The assembled global matrix — block terms, fixed-point springs, and contacts in all three
    /// closed configurations (normal + shear spring, normal + friction) of both entrance modes —
    /// is symmetric and positive definite (reference §7), so Cholesky applies.
    #[test]
    fn assembled_matrix_is_symmetric_positive_definite() {
        let (solver, mut active, pairs) = at_impact();
        assert!(
            active
                .iter()
                .any(|c| c.cand.mode() == ContactMode::EdgeEdge)
        );
        assert!(
            active
                .iter()
                .any(|c| c.cand.mode() == ContactMode::VertexFace)
        );
        let mut k = BlockMatrix::new(solver.model.blocks.len(), pairs);
        // Alternate the states so that both closed variants are assembled; raise some penalties.
        for (n, c) in active.iter_mut().enumerate() {
            c.pair = k
                .pair_index(c.cand.key.i as usize, c.cand.key.j as usize)
                .unwrap();
            c.rec.state = if n % 2 == 0 {
                ContactState::Lock
            } else {
                ContactState::Slide
            };
            c.rec.penalty *= [1.0, 10.0, 100.0][n % 3];
            c.rec.lambda = 1e4;
            c.rec.tau = c
                .cand
                .normal
                .cross(&Vec3::z())
                .try_normalize(1e-9)
                .unwrap_or(Vec3::x());
        }
        let (k0, _) = solver.block_terms(0.01);
        k.diag.copy_from_slice(&k0);
        for c in &active {
            if let Some(key) = c.stiffness_key() {
                solver.apply_stiffness(&mut k, c, &key, 1.0);
            }
        }
        let n = 12 * solver.model.blocks.len();
        let mut dense = nalgebra::DMatrix::<f64>::zeros(n, n);
        for col in 0..n {
            let mut e = vec![0.0; n];
            e[col] = 1.0;
            dense.set_column(col, &nalgebra::DVector::from_vec(k.mul(&e)));
        }
        let asym = (&dense - dense.transpose()).abs().max();
        assert!(asym <= 1e-12 * dense.abs().max(), "asymmetry {asym:e}");
        let eig = nalgebra::SymmetricEigen::new(dense.clone());
        let min = eig.eigenvalues.min();
        assert!(min > 0.0, "smallest eigenvalue {min:e}");
        // And the sparse factorization agrees with the dense solve.
        let mut chol = SparseCholesky::default();
        chol.factorize(&k).unwrap();
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let mut x = b.clone();
        chol.solve_in_place(&mut x);
        let r: Vec<f64> = k.mul(&x).iter().zip(&b).map(|(a, b)| a - b).collect();
        let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(
            rn < 1e-6 * b.iter().map(|v| v * v).sum::<f64>().sqrt(),
            "residual {rn:e}"
        );
    }

    /// K updated contact by contact (the old stiffness of each changed contact out, the new one
    /// in, as `iterate` does after state changes and penalty raises) equals K assembled afresh.
    #[test]
    fn updated_matrix_equals_fresh_assembly() {
        let (solver, mut active, pairs) = at_impact();
        let fresh = |active: &[Active]| {
            let mut k = BlockMatrix::new(solver.model.blocks.len(), pairs.clone());
            let (k0, _) = solver.block_terms(0.01);
            k.diag.copy_from_slice(&k0);
            for c in active {
                if let Some(key) = c.stiffness_key() {
                    solver.apply_stiffness(&mut k, c, &key, 1.0);
                }
            }
            k
        };
        let pattern = BlockMatrix::new(solver.model.blocks.len(), pairs.clone());
        for c in active.iter_mut() {
            c.pair = pattern
                .pair_index(c.cand.key.i as usize, c.cand.key.j as usize)
                .unwrap();
            c.rec.state = ContactState::Lock;
        }
        let mut k = fresh(&active);
        let keys: Vec<_> = active.iter().map(|c| c.stiffness_key()).collect();
        // Every contact changes: opened, set sliding, stiffened ×1000, or its spring re-anchored.
        for (n, c) in active.iter_mut().enumerate() {
            match n % 4 {
                0 => c.rec.state = ContactState::Open,
                1 => c.rec.state = ContactState::Slide,
                2 => c.rec.penalty *= 1000.0,
                _ => c.rec.reference += Vec3::new(1e-3, -2e-3, 5e-4),
            }
        }
        for (c, old) in active.iter().zip(&keys) {
            let new = c.stiffness_key();
            assert_ne!(&new, old);
            if let Some(old) = old {
                solver.apply_stiffness(&mut k, c, old, -1.0);
            }
            if let Some(new) = &new {
                solver.apply_stiffness(&mut k, c, new, 1.0);
            }
        }
        let want = fresh(&active);
        let scale = want
            .diag
            .iter()
            .chain(&want.off)
            .map(|m| m.abs().max())
            .fold(0.0, f64::max);
        for (a, b) in k
            .diag
            .iter()
            .chain(&k.off)
            .zip(want.diag.iter().chain(&want.off))
        {
            assert!(
                (a - b).abs().max() <= 1e-13 * scale,
                "{:e}",
                (a - b).abs().max()
            );
        }
    }
}
