//! The last stage of a step: accept the solution. The contacts' records move with block j into
//! the next step and the closed ones are published; the blocks take their new velocities (3.2),
//! stresses and strains, and their vertices move by the finite-rotation update (1.3).

use nalgebra::Vector6;
use rayon::prelude::*;

use super::active::Active;
use super::sleep::is_held;
use super::{PAR_BLOCKS, PAR_CONTACTS};
use crate::contact::record::{ContactRecord, RecordMap};
use crate::contact::{ContactKey, ContactState};
use crate::model::Block;
use crate::params::{Method, SolverParams};
use crate::physics::geometry::Vec3;
use crate::physics::integrator::Scheme;
use crate::physics::mechanics::{StepMap, Vec12, rotate_stress};
use crate::snapshot::{ContactSnapshot, StepStats};

/// The end-of-step map of every block's material points for the solution `d`.
pub(crate) fn step_maps(blocks: &[Block], d: &[f64]) -> Vec<StepMap> {
    blocks
        .par_iter()
        .with_min_len(PAR_BLOCKS)
        .enumerate()
        .map(|(i, b)| {
            let di = Vec12::from_column_slice(&d[12 * i..12 * i + 12]);
            StepMap::new(b.mp.centroid, &di)
        })
        .collect()
}

/// The records every contact carries into the next step, and the closed contacts as published.
/// Contact outputs use the start-of-step geometry moved by the step.
pub(crate) fn commit_contacts(
    p: &SolverParams,
    maps: &[StepMap],
    active: &[Active],
) -> (RecordMap, Vec<ContactSnapshot>) {
    // Each contact's record and snapshot in parallel, gathered in the contacts' order.
    let committed: Vec<(ContactKey, ContactRecord, Option<ContactSnapshot>)> = active
        .par_iter()
        .with_min_len(PAR_CONTACTS)
        .map(|c| commit_contact(p, maps, c))
        .collect();
    let mut contacts = Vec::new();
    let mut records = RecordMap::with_capacity_and_hasher(active.len(), Default::default());
    for (key, rec, snap) in committed {
        contacts.extend(snap);
        records.insert(key, rec);
    }
    (records, contacts)
}

/// One contact's record for the next step and, if closed, its snapshot.
fn commit_contact(
    p: &SolverParams,
    maps: &[StepMap],
    c: &Active,
) -> (ContactKey, ContactRecord, Option<ContactSnapshot>) {
    let mut rec = c.rec;
    let closed = rec.state.is_closed();
    rec.penetration = c.dn + rec.overlap;
    // The tangential force on block i: the spring pulls a locked contact back toward its
    // reference, friction acts against a sliding one's slip τ.
    let mut shear = Vec3::zeros();
    if closed {
        rec.normal_force = c.force;
        let (magnitude, direction) = match rec.state {
            ContactState::Lock => (
                p.contact.shear_penalty(rec.penalty, c.inertia) * c.shear.norm(),
                -c.shear.try_normalize(0.0).unwrap_or_else(Vec3::zeros),
            ),
            _ => {
                let n_prev = if p.method == Method::Alm {
                    rec.lambda
                } else {
                    rec.normal_force.max(0.0)
                };
                (n_prev * c.tan_phi(p), -rec.tau)
            }
        };
        rec.shear_force = magnitude;
        shear = direction * magnitude;
    } else {
        rec.normal_force = 0.0;
        rec.shear_force = 0.0;
    }
    let mj = &maps[c.cand.key.j as usize];
    rec.reference = mj.apply(&rec.reference);
    rec.tau = mj.rotation() * rec.tau;
    let snap = closed.then(|| ContactSnapshot {
        block_i: c.cand.key.i as usize,
        block_j: c.cand.key.j as usize,
        mode: c.cand.mode(),
        state: rec.state,
        point: mj.apply(&c.cand.xb).into(),
        normal: (mj.rotation() * c.cand.normal).into(),
        normal_force: rec.normal_force,
        shear_force: rec.shear_force,
        shear: (mj.rotation() * shear).into(),
        penetration: c.dn + rec.overlap,
        penalty: rec.penalty,
        joint: c.joint,
        lambda: if p.method == Method::Alm {
            rec.lambda
        } else {
            0.0
        },
    });
    // The warm start (reference §6.2) carries the multiplier the accepted solution was solved
    // with, λ_{k−1}, not λ_k = λ_{k−1} + p_n d_n (P1). The force of the next step's first solve,
    // λ + p_n d_n, then starts from the force this step ended with. Carrying λ_k counted the
    // penetration left at the step's end twice, once in λ_k and again in d_n, so wherever the
    // loop stopped before d_n reached zero the carried force was an integral of the penetration
    // over the steps and lagged the motion: a column of four blocks on a fixed one rocked at
    // 2.7 mm/s for as long as a run lasted, a generated wall of 1000 at up to 7 mm/s
    // (`tests/stable_dynamics.rs`, the stacked columns). A model of one block on one contact,
    // scripted apart, shows the same: its motion grew without bound at p_n ≪ m/Δt² with λ_k
    // carried, and died out at every p_n with λ_{k−1}. The loop's own iterations still update
    // λ as (P1) has it, and friction takes the force, not this λ ([`Active::friction_normal`]).
    if closed && let Some(lambda) = c.lambda_solved {
        rec.lambda = lambda;
    }
    (c.cand.key, rec, snap)
}

/// Moves every block by its solution: velocity (3.2) v1 = 2D/Δt − v0 or its generalized-α form
/// (R4.4), stress and strain, and the vertices and load points by the finite-rotation map (1.3).
/// A `held` (sleeping) block stays exactly as it is.
pub(crate) fn commit_blocks(
    p: &SolverParams,
    blocks: &mut [Block],
    (maps, held): (&[StepMap], &[bool]),
    d: &[f64],
    dt: f64,
    scheme: &Scheme,
) {
    blocks
        .par_iter_mut()
        .with_min_len(PAR_BLOCKS)
        .enumerate()
        .filter(|&(i, _)| !is_held(held, i))
        .for_each(|(i, b)| {
            let di = Vec12::from_column_slice(&d[12 * i..12 * i + 12]);
            b.set_kinematics(scheme.advance(&b.kinematics(), &di, dt));
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
        });
}

/// The step's statistics from its contacts: the largest penetration and kept overlap of a
/// closed contact, and the contacts by state.
pub(crate) fn contact_stats(active: &[Active], closed: &[ContactSnapshot]) -> StepStats {
    let (contacts_lock, contacts_slide) = lock_and_slide(closed);
    StepStats {
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
        contacts_lock,
        contacts_slide,
        contacts_open: (active.len() - closed.len()) as u32,
        ..Default::default()
    }
}

/// How many of the closed contacts `closed` are locked, and how many slide.
pub(crate) fn lock_and_slide(closed: &[ContactSnapshot]) -> (u32, u32) {
    let count = |s: ContactState| closed.iter().filter(|c| c.state == s).count() as u32;
    (count(ContactState::Lock), count(ContactState::Slide))
}

/// The kinetic, gravitational and elastic energy the blocks would have after the solution `d`
/// of a step of `dt`, and the work the point loads would do over it, J: what
/// [`commit_blocks`] then [`with_energy`] give, without moving anything (the mass matrices
/// and volumes of the start of the step, the stress unrotated: a check's accuracy).
pub(crate) fn energy_after(
    blocks: &[Block],
    d: &[f64],
    dt: f64,
    scheme: &Scheme,
    gravity: [f64; 3],
) -> ([f64; 3], f64) {
    let g = Vec3::from(gravity);
    let (mut energy, mut work) = ([0.0; 3], 0.0);
    for (i, b) in blocks.iter().enumerate() {
        let di = Vec12::from_column_slice(&d[12 * i..12 * i + 12]);
        let de = di.fixed_rows::<6>(6).into_owned();
        energy[2] += elastic_energy(b, &(b.stress + b.elasticity * de), &(b.strain + de));
        if b.fixed {
            continue;
        }
        let v = scheme.advance(&b.kinematics(), &di, dt).velocity;
        energy[0] += b.kinetic_energy_at(&v);
        // The centroid moves by the step's translation (1.3).
        energy[1] += potential_energy(b, &(b.mp.centroid + di.fixed_rows::<3>(0)), &g);
        if !b.loads.is_empty() {
            let map = StepMap::new(b.mp.centroid, &di);
            work += b
                .loads
                .iter()
                .map(|(pt, f)| f.dot(&(map.apply(pt) - pt)))
                .sum::<f64>();
        }
    }
    (energy, work)
}

/// Kinetic, gravitational and elastic energy of the model, into `s`.
pub(crate) fn with_energy(mut s: StepStats, blocks: &[Block], gravity: [f64; 3]) -> StepStats {
    let g = Vec3::from(gravity);
    s.kinetic_energy = blocks
        .iter()
        .filter(|b| !b.fixed)
        .map(Block::kinetic_energy)
        .sum();
    s.potential_energy = blocks
        .iter()
        .filter(|b| !b.fixed)
        .map(|b| potential_energy(b, &b.mp.centroid, &g))
        .sum();
    s.elastic_energy = blocks
        .iter()
        .map(|b| elastic_energy(b, &b.stress, &b.strain))
        .sum();
    s
}

/// −m g·c: the gravitational energy of block `b` with its centroid at `centroid`, J.
fn potential_energy(b: &Block, centroid: &Vec3, g: &Vec3) -> f64 {
    -b.mass * g.dot(centroid)
}

/// ½ V σ·ε: the strain energy of block `b` at this stress and strain, J.
fn elastic_energy(b: &Block, stress: &Vector6<f64>, strain: &Vector6<f64>) -> f64 {
    0.5 * b.mp.volume * stress.dot(strain)
}
