//! Plain-data pictures of the solver state, published after each completed step.
//!
//! Data flows one way: scene → solver → [`Snapshot`] → renderer / output files. Nothing in here
//! refers back to the solver, so the renderer and the CSV writers depend only on this module.

// Deserialize too: a checkpoint (`crate::solver::checkpoint`) saves some of these as they are.
use serde::{Deserialize, Serialize};

/// How a contact was entered (paper Fig. 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ContactMode {
    /// A vertex of block i against a face of block j.
    VertexFace,
    /// An edge of block i against an edge of block j.
    EdgeEdge,
}

impl ContactMode {
    /// The name used in `contacts.csv`.
    pub fn as_str(self) -> &'static str {
        match self {
            ContactMode::VertexFace => "vertex-face",
            ContactMode::EdgeEdge => "edge-edge",
        }
    }
}

/// Mohr–Coulomb state of a contact (reference §6.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ContactState {
    Open,
    /// Closed, tangentially held by the shear spring.
    Lock,
    /// Closed, sliding with friction N tan φ (+ cohesion).
    Slide,
}

impl ContactState {
    /// The name used in `contacts.csv`.
    pub fn as_str(self) -> &'static str {
        match self {
            ContactState::Open => "open",
            ContactState::Lock => "lock",
            ContactState::Slide => "slide",
        }
    }

    pub fn is_closed(self) -> bool {
        self != ContactState::Open
    }
}

/// One block at the end of a step.
#[derive(Clone, Debug, Serialize)]
pub struct BlockSnapshot {
    pub name: String,
    /// Held by vertex springs (drawn in a muted colour).
    pub fixed: bool,
    /// Current vertex positions, m.
    pub vertices: Vec<[f64; 3]>,
    /// Faces as vertex indices, counter-clockwise seen from outside (outward normal by the
    /// right-hand rule). The topology never changes during a run.
    pub faces: Vec<Vec<u32>>,
    /// Centroid, m.
    pub centroid: [f64; 3],
    /// Centroid velocity, m/s.
    pub velocity: [f64; 3],
    /// Centroid displacement since t = 0, m.
    pub displacement: [f64; 3],
    /// The rock mass the block was cut from (an index of [`Snapshot::rock_masses`]) and the
    /// region of its domain; `None` for a hand-made block.
    pub rock_mass: Option<(u16, u16)>,
    /// Stress σx, σy, σz, τxy, τyz, τzx, Pa (tension positive).
    pub stress: [f64; 6],
    /// Volume, m³, as the solver holds it.
    pub volume: f64,
}

/// The solver's stress `[σx, σy, σz, τyz, τzx, τxy]` (the order of the strains in T, reference
/// (1.1)) in the snapshot's order `[σx, σy, σz, τxy, τyz, τzx]`, which is VTK's for a
/// symmetric tensor (XX, YY, ZZ, XY, YZ, XZ), so that ParaView's tensor filters read it right.
/// Copied as it was, the snapshot (and the `.vtu` files) gave τyz as τxy, τzx as τyz and τxy
/// as τzx.
pub fn stress_in_output_order(s: &[f64; 6]) -> [f64; 6] {
    [s[0], s[1], s[2], s[5], s[3], s[4]]
}

#[cfg(test)]
mod stress_order_tests {
    use super::stress_in_output_order;
    use crate::physics::mechanics::rotate_stress;
    use nalgebra::{Matrix3, Vector6};

    /// A uniaxial stress along x turned by 30° about z has τxy and no τyz, τzx; about x, τyz
    /// alone; about y, τzx alone: each lands in its named slot.
    #[test]
    fn each_shear_lands_in_its_named_slot() {
        let uniaxial = Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let along_z = Vector6::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0);
        let (s, c) = 30f64.to_radians().sin_cos();
        let about_z = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let about_x = Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c);
        let about_y = Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c);
        let out = |v: Vector6<f64>| stress_in_output_order(&v.into());
        let xy = out(rotate_stress(&uniaxial, &about_z));
        assert!(
            (xy[3] - s * c).abs() < 1e-15 && xy[4] == 0.0 && xy[5] == 0.0,
            "{xy:?}"
        );
        let yz = out(rotate_stress(&along_z, &about_x));
        assert!(
            (yz[4] + s * c).abs() < 1e-15 && yz[3] == 0.0 && yz[5] == 0.0,
            "{yz:?}"
        );
        let zx = out(rotate_stress(&uniaxial, &about_y));
        assert!(
            (zx[5] + s * c).abs() < 1e-15 && zx[3] == 0.0 && zx[4] == 0.0,
            "{zx:?}"
        );
    }
}

#[cfg(test)]
impl BlockSnapshot {
    /// Test fixture: an axis-aligned cube of edge `size` with its lowest corner at `at`, at rest.
    pub(crate) fn test_cube(name: &str, at: [f64; 3], size: f64) -> Self {
        let vertices = (0..8)
            .map(|i| {
                [
                    at[0] + size * (i & 1) as f64,
                    at[1] + size * ((i >> 1) & 1) as f64,
                    at[2] + size * ((i >> 2) & 1) as f64,
                ]
            })
            .collect();
        let faces = vec![
            vec![0, 2, 3, 1],
            vec![4, 5, 7, 6],
            vec![0, 1, 5, 4],
            vec![1, 3, 7, 5],
            vec![3, 2, 6, 7],
            vec![2, 0, 4, 6],
        ];
        BlockSnapshot {
            name: name.into(),
            fixed: false,
            vertices,
            faces,
            centroid: at.map(|x| x + size / 2.0),
            velocity: [0.0; 3],
            displacement: [0.0; 3],
            rock_mass: None,
            stress: [0.0; 6],
            volume: size * size * size,
        }
    }
}

/// One active (non-open) contact at the end of a step.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ContactSnapshot {
    /// Index of the block that owns the vertex (V–F) or the first edge (E–E).
    pub block_i: usize,
    /// Index of the block that owns the face (V–F) or the second edge (E–E).
    pub block_j: usize,
    pub mode: ContactMode,
    pub state: ContactState,
    /// Contact point on the surface of block j, m.
    pub point: [f64; 3],
    /// Unit contact normal, pointing out of block j toward block i.
    pub normal: [f64; 3],
    /// Normal force, N, positive when compressive.
    pub normal_force: f64,
    /// Magnitude of the tangential (shear) force, N.
    pub shear_force: f64,
    /// The tangential force on block i, N: the shear spring's pull of a locked contact, the
    /// friction against the slip of a sliding one (its length is `shear_force`).
    pub shear: [f64; 3],
    /// Penetration, m, positive when the blocks overlap.
    pub penetration: f64,
    /// Normal penalty in effect, N/m.
    pub penalty: f64,
    /// Lagrange multiplier (0 in penalty mode), N.
    pub lambda: f64,
    /// The joint set the contact lies on, an index of [`Snapshot::joint_sets`] (`None`: the
    /// scene's `[joint]`).
    pub joint: Option<u16>,
}

/// Per-step statistics.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct StepStats {
    /// Length of the accepted step, s.
    pub time_step: f64,
    /// Open–close passes in the accepted attempt.
    pub open_close_iterations: u32,
    /// Linear solves (ALM iterations, or one per open–close pass in penalty mode) in the
    /// accepted attempt.
    pub alm_iterations: u32,
    /// Attempts discarded before this step was accepted (displacement or penetration limit).
    pub time_step_cuts: u32,
    /// Numeric factorizations in this step, all attempts.
    pub factorizations: u32,
    /// Largest penetration of a closed contact at the end of the step, m, beyond the overlap it
    /// keeps (what the ALM tolerance ε1·d_n,max controls).
    pub max_penetration: f64,
    /// Largest overlap kept by a closed contact, m: a contact first seen already deeper than
    /// ε1·d_n,max (missed by detection or by the linearised step) keeps that overlap instead of
    /// having it pushed out at once, and releases 10 % of it a step.
    pub max_overlap: f64,
    /// Closed contacts in the lock state.
    pub contacts_lock: u32,
    /// Closed contacts in the slide state.
    pub contacts_slide: u32,
    /// Detected but open contacts.
    pub contacts_open: u32,
    /// Blocks asleep in this step (held still; see `solver.sleep_velocity`).
    #[serde(default)]
    pub blocks_asleep: u32,
    /// Kinetic energy ½ vᵀMv over all blocks, J.
    pub kinetic_energy: f64,
    /// Gravitational potential energy Σ m g·(−x_c) relative to the origin, J.
    pub potential_energy: f64,
    /// Elastic strain energy Σ ½ V σ·ε of the blocks, J.
    pub elastic_energy: f64,
}

/// The initial equilibrium stage (`[solver] initial_equilibrium`), while it runs and after.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EquilibriumReport {
    /// Static steps taken.
    pub steps: u64,
    /// R_max after the last step: the largest unbalanced force of a free block over the forces
    /// it carries (its weight plus its contact forces), or moment over those forces times its
    /// radius (rock-mass reference (R5.1)).
    pub residual: f64,
    pub tolerance: f64,
    /// R_max fell below the tolerance; otherwise the step limit ended the stage (a mechanism, or
    /// too few steps for the model's softest mode).
    pub converged: bool,
    /// The stage is still under way (time stands at 0).
    pub running: bool,
}

/// The state of a run at the end of a completed step (step 0 is the initial state).
#[derive(Clone, Debug, Serialize)]
pub struct Snapshot {
    pub scene_name: String,
    /// Simulated time, s.
    pub time: f64,
    /// Completed steps.
    pub step: u64,
    pub blocks: Vec<BlockSnapshot>,
    /// Closed contacts only.
    pub contacts: Vec<ContactSnapshot>,
    pub stats: StepStats,
    /// The initial equilibrium stage, if the scene asked for one.
    pub equilibrium: Option<EquilibriumReport>,
    /// The names of the rock masses ([`BlockSnapshot::rock_mass`]).
    pub rock_masses: Vec<String>,
    /// The names of the joint sets ([`ContactSnapshot::joint`]).
    pub joint_sets: Vec<String>,
}

/// Wall time spent in the phases of the solver, s.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Timings {
    /// Contact detection, the contact groups, and the step's predicted Δt (whose range queries
    /// read the groups).
    pub detection: f64,
    /// K and F, the ALM's per-contact updates and the open–close checks.
    pub assembly: f64,
    pub factorization: f64,
    pub solve: f64,
    /// The checks of a solved attempt (displacement, penetration, energy) and the commit.
    pub bookkeeping: f64,
}

/// Totals over a run, for `summary.json` and the benchmark.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
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
    /// with at most [`crate::params::step_rules::SETTLE_FRACTION`] of the contacts still changing.
    pub unconverged_steps: u64,
    /// ALM loops that hit the iteration cap.
    pub alm_cap_hits: u64,
    /// Contacts settled closed and locked: after cycling between states within one attempt, or
    /// still changing at the open–close pass limit (see `unconverged_steps`).
    pub frozen_contacts: u64,
    /// Steps in which at least one block slept (see `solver.sleep_velocity`).
    #[serde(default)]
    pub sleeping_steps: u64,
    pub contacts_per_step: f64,
    pub timings: Timings,
}
