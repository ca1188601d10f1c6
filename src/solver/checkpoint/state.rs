//! The payload of a checkpoint: the solver's state as plain serde data. The solver's own types
//! hold nalgebra vectors and matrices (whose serde support would rebuild half the dependency
//! tree) and an `Arc`ed topology, so they are mirrored here with arrays. Every conversion
//! destructures the type it mirrors, so a field added to the solver, a block, a record or the
//! parameters does not compile until the format says what becomes of it (and [`super::VERSION`]
//! is raised).
//!
//! What is not saved is what a step recomputes from what is: a block's face normals, mass
//! properties, density, mass and elasticity matrices and bounding box ([`Block::refresh`], the
//! only place they are set), the factorization (its symbolic analysis is redone from the saved
//! pattern on loading, its numbers at the next step as at every step), and the run's wall-clock
//! timings, which are not state and would make every file different.

mod finite;

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::super::equilibrium::{Phase, Stage};
use super::super::sleep::Sleep;
use super::super::watchdog::EnergyWatch;
use super::super::{LinearCache, Solver};
use crate::contact::ContactKey;
use crate::contact::record::ContactRecord;
use crate::model::{Block, JointFace, Model, RockMassOf};
use crate::params::{ContactParams, JointParams, JointSetParams, Method, Mode, SolverParams};
use crate::physics::geometry::{Edge, MassProperties, Topology, Vec3};
use crate::physics::linear::{BlockMatrix, SparseCholesky};
use crate::physics::mechanics::{Material, Vec12, elasticity_matrix};
use crate::snapshot::{
    ContactSnapshot, ContactState, EquilibriumReport, RunTotals, StepStats, Timings,
};

type V3 = [f64; 3];

/// The whole solver, in the order the fields are encoded.
#[derive(Serialize, Deserialize)]
pub(super) struct SavedSolver {
    params: SavedParams,
    model_name: String,
    rock_masses: Vec<String>,
    blocks: Vec<SavedBlock>,
    time: f64,
    step: u64,
    dt: f64,
    w0: f64,
    initial_boxes: Vec<(V3, V3)>,
    /// Sorted by key: a `HashMap`'s order changes from process to process, the file must not.
    records: Vec<(ContactKey, SavedRecord)>,
    /// The last step's sparsity pattern: the next step's pattern starts from it.
    pattern: Vec<(usize, usize)>,
    /// Whether the factorization held a symbolic analysis (of `pattern`), and how many it has
    /// made: the restored one makes it again, uncounted.
    analysed: bool,
    symbolic_analyses: u64,
    contacts: Vec<ContactSnapshot>,
    last: StepStats,
    totals: RunTotals,
    contact_sum: u64,
    stage: Option<SavedStage>,
    equilibrium: Option<EquilibriumReport>,
    accelerations: bool,
    energy: Option<EnergyWatch>,
    /// Each block's still time, s, whether it sleeps, and the Δt of a model asleep throughout.
    still: Vec<f64>,
    asleep: Vec<bool>,
    resting: Option<f64>,
}

/// [`SolverParams`] with every field, the ones a scene file does not hold too (its own serde
/// form skips them, and reads gravity in a way only a self-describing format can).
#[derive(Serialize, Deserialize)]
struct SavedParams {
    method: Method,
    mode: Mode,
    spectral_radius: f64,
    duration: f64,
    max_time_step: f64,
    max_displacement_ratio: f64,
    gravity: V3,
    fixed_spring_factor: f64,
    max_displacement_overshoot: f64,
    rotate_stress: bool,
    initial_equilibrium: bool,
    equilibrium_tolerance: f64,
    equilibrium_max_steps: u32,
    sleep_velocity: f64,
    sleep_time: f64,
    contact: ContactParams,
    joint: JointParams,
    joint_sets: Vec<JointSetParams>,
    joints_held: bool,
}

/// A [`Block`]'s state: what a step reads and is not derived from the vertex positions.
#[derive(Serialize, Deserialize)]
struct SavedBlock {
    name: String,
    material: Material,
    fixed: bool,
    vertices: Vec<V3>,
    faces: Vec<Vec<usize>>,
    /// Each edge: its vertices and its two faces.
    edges: Vec<([usize; 2], [usize; 2])>,
    vertex_edges: Vec<Vec<usize>>,
    mass: f64,
    velocity: [f64; 12],
    acceleration: [f64; 12],
    stress: [f64; 6],
    strain: [f64; 6],
    anchors: Vec<V3>,
    loads: Vec<(V3, V3)>,
    initial_centroid: V3,
    /// (set, plane) of each face's joint.
    face_joints: Vec<Option<(u16, u32)>>,
    /// (rock mass, region).
    rock_mass: Option<(u16, u16)>,
}

/// A [`ContactRecord`], field for field.
#[derive(Serialize, Deserialize)]
struct SavedRecord {
    state: ContactState,
    lambda: f64,
    penalty: f64,
    normal_force: f64,
    shear_force: f64,
    penetration: f64,
    reference: V3,
    tau: V3,
    normal: V3,
    intact: bool,
    cohesion_area: f64,
    overlap: f64,
}

/// An equilibrium [`Stage`] under way.
#[derive(Serialize, Deserialize)]
struct SavedStage {
    held: Vec<(usize, [f64; 12])>,
    report: EquilibriumReport,
    phase: Phase,
    sliding: u64,
    last_force: f64,
    best: (f64, u64),
}

fn v3(v: &Vec3) -> V3 {
    [v.x, v.y, v.z]
}

fn v12(v: &Vec12) -> [f64; 12] {
    let mut a = [0.0; 12];
    a.copy_from_slice(v.as_slice());
    a
}

impl SavedSolver {
    pub(super) fn of(s: &Solver) -> Self {
        let Solver {
            params,
            model,
            time,
            step,
            dt,
            w0,
            initial_boxes,
            records,
            // K's storage is not state: every attempt sets its values afresh.
            linear:
                LinearCache {
                    pattern,
                    chol,
                    matrix: _,
                },
            contacts,
            last,
            totals,
            contact_sum,
            stage,
            equilibrium,
            accelerations,
            energy,
            sleep,
        } = s;
        let mut records: Vec<_> = records
            .iter()
            .map(|(k, r)| (*k, SavedRecord::of(r)))
            .collect();
        records.sort_unstable_by_key(|(k, _)| *k);
        let (still, asleep, resting) = sleep.parts();
        SavedSolver {
            params: SavedParams::of(params),
            model_name: model.name.clone(),
            rock_masses: model.rock_masses.clone(),
            blocks: model.blocks.iter().map(SavedBlock::of).collect(),
            time: *time,
            step: *step,
            dt: *dt,
            w0: *w0,
            initial_boxes: initial_boxes.iter().map(|(a, b)| (v3(a), v3(b))).collect(),
            records,
            pattern: pattern.clone(),
            analysed: chol.analysed(),
            symbolic_analyses: chol.symbolic_count,
            contacts: contacts.clone(),
            last: last.clone(),
            // Wall-clock times are not state, and would make every file different.
            totals: RunTotals {
                timings: Timings::default(),
                ..totals.clone()
            },
            contact_sum: *contact_sum,
            stage: stage.as_ref().map(SavedStage::of),
            equilibrium: *equilibrium,
            accelerations: *accelerations,
            energy: energy.clone(),
            still: still.to_vec(),
            asleep: asleep.to_vec(),
            resting,
        }
    }

    /// The solver again, after checking that every index points where it may (a file that
    /// decodes but does not hold together is refused, not stepped into a panic).
    pub(super) fn into_solver(self) -> Result<Solver, String> {
        self.check()?;
        let params = self.params.into_params();
        params
            .check()
            .map_err(|e| format!("parameters out of range: {}", e.message))?;
        let blocks = self
            .blocks
            .into_iter()
            .map(SavedBlock::into_block)
            .collect::<Result<Vec<_>, _>>()?;
        let mut chol = SparseCholesky::default();
        if self.analysed {
            let k = BlockMatrix::new(blocks.len(), self.pattern.clone());
            chol.analyse_ahead(&k)
                .map_err(|e| format!("the sparsity pattern cannot be analysed: {e}"))?;
        }
        chol.symbolic_count = self.symbolic_analyses;
        Ok(Solver {
            params,
            model: Model {
                name: self.model_name,
                blocks,
                rock_masses: self.rock_masses,
            },
            time: self.time,
            step: self.step,
            dt: self.dt,
            w0: self.w0,
            initial_boxes: self
                .initial_boxes
                .iter()
                .map(|(a, b)| (Vec3::from(*a), Vec3::from(*b)))
                .collect(),
            records: self
                .records
                .into_iter()
                .map(|(k, r)| (k, r.into_record()))
                .collect(),
            linear: LinearCache {
                pattern: self.pattern,
                chol,
                matrix: None,
            },
            contacts: self.contacts,
            last: self.last,
            totals: self.totals,
            contact_sum: self.contact_sum,
            stage: self.stage.map(SavedStage::into_stage),
            equilibrium: self.equilibrium,
            accelerations: self.accelerations,
            energy: self.energy,
            sleep: Sleep::from_parts(self.still, self.asleep, self.resting)
                .ok_or("the sleep state does not match the blocks")?,
        })
    }

    /// The indices that the solver follows without checking: blocks of records, contacts,
    /// pattern pairs and held blocks.
    fn check(&self) -> Result<(), String> {
        let n = self.blocks.len();
        if self.initial_boxes.len() != n {
            return Err(format!(
                "{} initial boxes for {n} blocks",
                self.initial_boxes.len()
            ));
        }
        if self.still.len() != n || self.asleep.len() != n {
            return Err(format!(
                "sleep state of {} and {} blocks for {n} blocks",
                self.still.len(),
                self.asleep.len()
            ));
        }
        let block = |i: usize, what: &str| {
            (i < n)
                .then_some(())
                .ok_or_else(|| format!("{what} names block {i} of {n}"))
        };
        for (k, _) in &self.records {
            block(k.i as usize, "a contact record")?;
            block(k.j as usize, "a contact record")?;
        }
        for c in &self.contacts {
            block(c.block_i, "a contact")?;
            block(c.block_j, "a contact")?;
        }
        for &(a, b) in &self.pattern {
            block(a.max(b), "the sparsity pattern")?;
        }
        for (i, _) in self.stage.iter().flat_map(|s| &s.held) {
            block(*i, "the equilibrium stage")?;
        }
        if self.records.windows(2).any(|w| w[0].0 >= w[1].0) {
            return Err("contact records out of order".into());
        }
        self.check_finite()
    }
}

impl SavedParams {
    fn of(p: &SolverParams) -> Self {
        let SolverParams {
            method,
            mode,
            spectral_radius,
            duration,
            max_time_step,
            max_displacement_ratio,
            gravity,
            fixed_spring_factor,
            max_displacement_overshoot,
            rotate_stress,
            initial_equilibrium,
            equilibrium_tolerance,
            equilibrium_max_steps,
            sleep_velocity,
            sleep_time,
            contact,
            joint,
            joint_sets,
            joints_held,
        } = p.clone();
        SavedParams {
            method,
            mode,
            spectral_radius,
            duration,
            max_time_step,
            max_displacement_ratio,
            gravity,
            fixed_spring_factor,
            max_displacement_overshoot,
            rotate_stress,
            initial_equilibrium,
            equilibrium_tolerance,
            equilibrium_max_steps,
            sleep_velocity,
            sleep_time,
            contact,
            joint,
            joint_sets,
            joints_held,
        }
    }

    fn into_params(self) -> SolverParams {
        let SavedParams {
            method,
            mode,
            spectral_radius,
            duration,
            max_time_step,
            max_displacement_ratio,
            gravity,
            fixed_spring_factor,
            max_displacement_overshoot,
            rotate_stress,
            initial_equilibrium,
            equilibrium_tolerance,
            equilibrium_max_steps,
            sleep_velocity,
            sleep_time,
            contact,
            joint,
            joint_sets,
            joints_held,
        } = self;
        SolverParams {
            method,
            mode,
            spectral_radius,
            duration,
            max_time_step,
            max_displacement_ratio,
            gravity,
            fixed_spring_factor,
            max_displacement_overshoot,
            rotate_stress,
            initial_equilibrium,
            equilibrium_tolerance,
            equilibrium_max_steps,
            sleep_velocity,
            sleep_time,
            contact,
            joint,
            joint_sets,
            joints_held,
        }
    }
}

impl SavedBlock {
    fn of(b: &Block) -> Self {
        let Block {
            name,
            material,
            fixed,
            vertices,
            topo,
            face_normals: _,
            mp: _,
            mass,
            density: _,
            mass_matrix: _,
            elasticity: _,
            velocity,
            acceleration,
            stress,
            strain,
            anchors,
            loads,
            initial_centroid,
            lo: _,
            hi: _,
            face_joints,
            rock_mass,
        } = b;
        let six = |v: &nalgebra::Vector6<f64>| {
            let mut a = [0.0; 6];
            a.copy_from_slice(v.as_slice());
            a
        };
        SavedBlock {
            name: name.clone(),
            material: *material,
            fixed: *fixed,
            vertices: vertices.iter().map(v3).collect(),
            faces: topo.faces.clone(),
            edges: topo.edges.iter().map(|e| (e.v, e.faces)).collect(),
            vertex_edges: topo.vertex_edges.clone(),
            mass: *mass,
            velocity: v12(velocity),
            acceleration: v12(acceleration),
            stress: six(stress),
            strain: six(strain),
            anchors: anchors.iter().map(v3).collect(),
            loads: loads.iter().map(|(p, f)| (v3(p), v3(f))).collect(),
            initial_centroid: v3(initial_centroid),
            face_joints: face_joints
                .iter()
                .map(|j| j.map(|j| (j.set, j.plane)))
                .collect(),
            rock_mass: rock_mass.map(|r| (r.mass, r.region)),
        }
    }

    /// The block, its derived quantities recomputed as a step recomputes them.
    fn into_block(self) -> Result<Block, String> {
        self.check()?;
        let p = |a: &V3| Vec3::from(*a);
        let mut b = Block {
            name: self.name,
            material: self.material,
            fixed: self.fixed,
            vertices: self.vertices.iter().map(p).collect(),
            topo: Arc::new(Topology {
                faces: self.faces,
                edges: self
                    .edges
                    .into_iter()
                    .map(|(v, faces)| Edge { v, faces })
                    .collect(),
                vertex_edges: self.vertex_edges,
            }),
            face_normals: Vec::new(),
            mp: MassProperties {
                volume: 0.0,
                centroid: Vec3::zeros(),
                second_moments: Default::default(),
            },
            mass: self.mass,
            density: 0.0,
            mass_matrix: Default::default(),
            elasticity: elasticity_matrix(self.material.young_modulus, self.material.poisson_ratio),
            velocity: Vec12::from(self.velocity),
            acceleration: Vec12::from(self.acceleration),
            stress: self.stress.into(),
            strain: self.strain.into(),
            anchors: self.anchors.iter().map(p).collect(),
            loads: self.loads.iter().map(|(a, f)| (p(a), p(f))).collect(),
            initial_centroid: p(&self.initial_centroid),
            lo: Vec3::zeros(),
            hi: Vec3::zeros(),
            face_joints: self
                .face_joints
                .into_iter()
                .map(|j| j.map(|(set, plane)| JointFace { set, plane }))
                .collect(),
            rock_mass: self
                .rock_mass
                .map(|(mass, region)| RockMassOf { mass, region }),
        };
        b.refresh();
        Ok(b)
    }

    /// Indices within the block, so that [`Block::refresh`] and detection cannot index out of
    /// range.
    fn check(&self) -> Result<(), String> {
        let (nv, nf) = (self.vertices.len(), self.faces.len());
        let bad = |what: &str| Err(format!("block '{}': {what}", self.name));
        if nv < 4 || nf < 4 || self.faces.iter().any(|f| f.len() < 3) {
            return bad("not a polyhedron");
        }
        let vertex_ok = |v: &usize| *v < nv;
        if !self.faces.iter().flatten().all(vertex_ok)
            || !self
                .edges
                .iter()
                .all(|(v, f)| v.iter().all(vertex_ok) && f.iter().all(|f| *f < nf))
            || self.vertex_edges.len() != nv
            || !self
                .vertex_edges
                .iter()
                .flatten()
                .all(|e| *e < self.edges.len())
        {
            return bad("an index out of range");
        }
        if self.face_joints.len() != nf {
            return bad("face joints do not match the faces");
        }
        if self.fixed && self.anchors.len() != nv {
            return bad("anchors do not match the vertices");
        }
        Ok(())
    }
}

impl SavedRecord {
    fn of(r: &ContactRecord) -> Self {
        let ContactRecord {
            state,
            lambda,
            penalty,
            normal_force,
            shear_force,
            penetration,
            reference,
            tau,
            normal,
            intact,
            cohesion_area,
            overlap,
        } = *r;
        SavedRecord {
            state,
            lambda,
            penalty,
            normal_force,
            shear_force,
            penetration,
            reference: v3(&reference),
            tau: v3(&tau),
            normal: v3(&normal),
            intact,
            cohesion_area,
            overlap,
        }
    }

    fn into_record(self) -> ContactRecord {
        ContactRecord {
            state: self.state,
            lambda: self.lambda,
            penalty: self.penalty,
            normal_force: self.normal_force,
            shear_force: self.shear_force,
            penetration: self.penetration,
            reference: self.reference.into(),
            tau: self.tau.into(),
            normal: self.normal.into(),
            intact: self.intact,
            cohesion_area: self.cohesion_area,
            overlap: self.overlap,
        }
    }
}

impl SavedStage {
    fn of(s: &Stage) -> Self {
        let Stage {
            held,
            report,
            phase,
            sliding,
            last_force,
            best,
        } = s;
        SavedStage {
            held: held.iter().map(|(i, v)| (*i, v12(v))).collect(),
            report: *report,
            phase: *phase,
            sliding: *sliding,
            last_force: *last_force,
            best: *best,
        }
    }

    fn into_stage(self) -> Stage {
        Stage {
            held: self
                .held
                .into_iter()
                .map(|(i, v)| (i, Vec12::from(v)))
                .collect(),
            report: self.report,
            phase: self.phase,
            sliding: self.sliding,
            last_force: self.last_force,
            best: self.best,
        }
    }
}

#[cfg(test)]
impl SavedSolver {
    /// Points a contact record at a block the model does not have.
    /// Puts `value` into block 1's first velocity component (a test of the finiteness check).
    pub(super) fn poison_for_tests(&mut self, value: f64) {
        self.blocks[1].velocity[0] = value;
    }

    pub(super) fn break_a_record_for_tests(&mut self) {
        let key = ContactKey {
            i: self.blocks.len() as u32,
            j: 0,
            mode: 0,
            feature_i: 0,
            feature_j: 0,
        };
        let record = SavedRecord::of(&ContactRecord {
            state: ContactState::Open,
            lambda: 0.0,
            penalty: 0.0,
            normal_force: 0.0,
            shear_force: 0.0,
            penetration: 0.0,
            reference: Vec3::zeros(),
            tau: Vec3::zeros(),
            normal: Vec3::zeros(),
            intact: false,
            cohesion_area: 0.0,
            overlap: 0.0,
        });
        self.records.push((key, record));
    }
}
