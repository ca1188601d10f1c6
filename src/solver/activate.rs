//! The first stage of a step: detect the contacts and attach each to the record it carried from
//! the last step, or to a new one (reference §4.5), with its normal kinematics frozen for the
//! step.

use std::collections::HashMap;

use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::active::{Active, initial_friction_normal, pushed_out_within};
use super::counters::debug_log;
use super::step_control::max_step_penetration;
use super::{PAR_BLOCKS, PAR_CONTACTS, PAR_PAIRS};
use crate::contact::detection::detect_pair;
use crate::contact::groups::{Bounds, ContactGroups};
use crate::contact::joint::joint_set;
use crate::contact::kinematics::normal_kinematics;
use crate::contact::law;
use crate::contact::record::{ContactRecord, RecordMap};
use crate::contact::{Candidate, ContactKey, ContactState, DetectionParams, Shape};
use crate::model::Block;
use crate::params::{Method, Mode, SolverParams};
use crate::physics::geometry::{Vec3, planar_hull_area};

/// What activation reads.
pub(crate) struct ActivationInputs<'a> {
    pub params: &'a SolverParams,
    pub blocks: &'a [Block],
    pub records: &'a RecordMap,
    /// The step about to be taken (0 for the first) and its start time.
    pub step: u64,
    pub time: f64,
    /// Δt of the step about to be taken (before any cut), s.
    pub dt: f64,
    /// The step belongs to the initial equilibrium stage, whose end takes every velocity away.
    pub in_stage: bool,
}

/// The broad phase: the contact groups with their w0 and the block pairs near each other
/// (sorted).
pub(crate) fn contact_groups(
    p: &SolverParams,
    blocks: &[Block],
    initial_boxes: &[(Vec3, Vec3)],
) -> ContactGroups {
    let bounds = blocks
        .iter()
        .zip(initial_boxes)
        .map(|(b, &home)| Bounds::of(b, home))
        .collect();
    ContactGroups::find(bounds, p.max_displacement_ratio)
}

/// This step's contacts and the contact groups ([`contact_groups`], from each block's
/// `initial_boxes`), every block awake.
#[cfg(test)]
pub(crate) fn activate(
    inp: &ActivationInputs,
    initial_boxes: &[(Vec3, Vec3)],
) -> (Vec<Active>, ContactGroups) {
    let groups = contact_groups(inp.params, inp.blocks, initial_boxes);
    let active = activate_awake(inp, &groups, &groups.pairs);
    (active, groups)
}

/// This step's contacts between the block pairs `pairs` of `groups` (all its pairs, or those
/// with an awake block: two sleeping blocks are not searched).
pub(crate) fn activate_awake(
    inp: &ActivationInputs,
    groups: &ContactGroups,
    pairs: &[(usize, usize)],
) -> Vec<Active> {
    let p = inp.params;
    // The shapes of the blocks some pair searches.
    let mut needed = vec![false; inp.blocks.len()];
    for &(a, b) in pairs {
        needed[a] = true;
        needed[b] = true;
    }
    let shapes: Vec<Option<Shape>> = inp
        .blocks
        .par_iter()
        .zip(&needed)
        .with_min_len(PAR_BLOCKS)
        .map(|(b, &n)| n.then(|| Shape::of(b)))
        .collect();
    let shape = |i: usize| {
        shapes[i]
            .as_ref()
            .expect("a shape for every searched block")
    };
    let known = |k: &ContactKey| inp.records.contains_key(k);
    // The narrow phase, pair by pair in parallel; collected in the order of the pairs.
    let cands: Vec<Candidate> = pairs
        .par_iter()
        .with_min_len(PAR_PAIRS)
        .flat_map_iter(|&(a, b)| {
            let dp = DetectionParams {
                check_crossing_depth: p.method == Method::Alm,
                ..DetectionParams::new(groups.pair_w0(a, b), p.max_displacement_ratio)
            };
            detect_pair(a, shape(a), b, shape(b), &dp, &known)
        })
        .collect();
    // Contact transfer: a vertex that slid onto an adjacent, almost coplanar face of the same
    // block keeps its history.
    let mut by_vertex: FxHashMap<(u32, u32, u32), ContactKey> = FxHashMap::default();
    for k in inp.records.keys() {
        if k.mode == 0 {
            by_vertex.insert((k.i, k.j, k.feature_i), *k);
        }
    }
    let (mut active, new): (Vec<Active>, Vec<bool>) = cands
        .into_par_iter()
        .with_min_len(PAR_CONTACTS)
        .map(|cand| {
            let w0 = groups.group_w0(cand.key.i as usize);
            activate_one(inp, &by_vertex, cand, w0)
        })
        .unzip();
    slide_if_moving(&mut active, &new, inp);
    if inp.step == 0 && active.iter().any(|c| p.joint_of(c.joint).cohesion > 0.0) {
        assign_cohesion_areas(&mut active);
    }
    active
}

/// One detected contact with its record and frozen kinematics; `w0` is its group's.
fn activate_one(
    inp: &ActivationInputs,
    by_vertex: &FxHashMap<(u32, u32, u32), ContactKey>,
    cand: Candidate,
    w0: f64,
) -> (Active, bool) {
    let p = inp.params;
    let blocks = inp.blocks;
    let (bi, bj) = (&blocks[cand.key.i as usize], &blocks[cand.key.j as usize]);
    let mut kin = normal_kinematics(
        cand.mode(),
        &cand.points,
        &cand.normal,
        &bi.mp.centroid,
        &bj.mp.centroid,
    );
    let alt_kin = cand
        .alternatives
        .iter()
        .map(|a| {
            let points = [cand.xa, a.corners[0], a.corners[1], a.corners[2]];
            normal_kinematics(
                cand.mode(),
                &points,
                &a.normal,
                &bi.mp.centroid,
                &bj.mp.centroid,
            )
        })
        .collect();
    let old = inp.records.get(&cand.key).copied().or_else(|| {
        if cand.key.mode != 0 {
            return None;
        }
        let k = by_vertex.get(&(cand.key.i, cand.key.j, cand.key.feature_i))?;
        let r = inp.records.get(k)?;
        (r.normal.dot(&cand.normal) > 3f64.to_radians().cos()).then_some(*r)
    });
    let mut rec = match old {
        Some(mut r) => {
            // Warm start: λ and the adapted p_n carry over. Resetting p_n to p_n,1 every step
            // was tried: with ε2 = 0.01 the multiplier then lags by up to 1 % a step, and a
            // standing column slowly rocks itself apart.
            if !p.contact.warm_start || p.method == Method::Penalty {
                r.lambda = 0.0;
                r.penalty = p.contact.initial_penalty;
            }
            r.normal = cand.normal;
            r
        }
        None => new_record(inp, &cand, w0),
    };
    // A vertex first seen on an edge of block j starts open: closed on one of the faces at that
    // edge, it would hold the blocks against any motion across that face's plane, which may be
    // the motion the other face allows. The open–close check closes it on the face the solution
    // leaves it least deep behind, if it is behind all of them (`Active::reconsider_face`).
    if old.is_none() && cand.tied && rec.state == ContactState::Lock {
        rec.state = ContactState::Open;
        rec.intact = false;
    }
    if p.method == Method::Penalty {
        rec.penalty = p.contact.initial_penalty;
    }
    let unseen = old.is_none_or(|r| r.state == ContactState::Open);
    let fresh_depth = keep_overlap(inp, &cand, &mut rec, &mut kin.d0, unseen, w0);
    // The force the last step ended with, under the warm start (a new record's is 0).
    let friction_normal = initial_friction_normal(p, &rec);
    let mass = lighter_mass(bi, bj);
    let active = Active {
        joint: joint_set(&cand.key, bi, bj),
        kin,
        alt_kin,
        young: bi.material.young_modulus.min(bj.material.young_modulus),
        weight: lighter_weight(bi, bj, p),
        inertia: if p.mode == Mode::Dynamic && mass.is_finite() {
            2.0 * mass / (p.max_time_step * p.max_time_step)
        } else {
            0.0
        },
        w0,
        start: rec,
        rec,
        cand,
        pair: 0,
        dn: 0.0,
        force: 0.0,
        dn_prev: None,
        friction_normal,
        lambda_solved: None,
        friction_cap: None,
        flips: 0,
        frozen: false,
        stopped: false,
        onset_slip: 0.0,
        stop_fraction: None,
        changed: false,
        shear: Vec3::zeros(),
        slip: Vec3::zeros(),
        du: Vec3::zeros(),
        lateral: 0.0,
        released: 0.0,
        fresh_depth,
        face_at_start: None,
    };
    (active, old.is_none())
}

/// The weight of the lighter of two blocks, a fixed block not counted, N.
fn lighter_weight(bi: &Block, bj: &Block, p: &SolverParams) -> f64 {
    let g = Vec3::from(p.gravity).norm();
    let m = lighter_mass(bi, bj);
    if m.is_finite() { m * g } else { 0.0 }
}

/// The mass of the lighter free block of the two, kg; infinite where both are fixed.
fn lighter_mass(bi: &Block, bj: &Block) -> f64 {
    let mass = |b: &Block| if b.fixed { f64::INFINITY } else { b.mass };
    mass(bi).min(mass(bj))
}

/// The record of a contact seen for the first time: closed (locked) if it is touching or
/// overlapping, open across a gap. Only contacts closed at t = 0 are intact (have cohesion).
fn new_record(inp: &ActivationInputs, cand: &Candidate, w0: f64) -> ContactRecord {
    let p = inp.params;
    let close_tol = p.contact.close_threshold * w0;
    let touching = -cand.gap > -close_tol;
    ContactRecord {
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
        intact: inp.step == 0 && touching,
        cohesion_area: 0.0,
        overlap: 0.0,
    }
}

/// A contact seen for the first time already deeper than the ALM tolerance (a corner that
/// slipped past detection, or an open contact whose linearised gap was wrong), or in a dynamic
/// step deeper than [`pushed_out_within`] its Δt, keeps that overlap instead of having it
/// pushed out in one step: resolved within one step, an overlap of millimetres takes
/// meganewtons and comes back as kinetic energy the system never had. The overlap is taken out
/// of d0; it shrinks as the blocks separate, and each attempt gives back a part of it in
/// proportion to its Δt ([`Active::release_overlap`]). Returns the depth of a contact first
/// seen overlapping that is left to be pushed out (0 if none), which a shorter attempt keeps.
fn keep_overlap(
    inp: &ActivationInputs,
    cand: &Candidate,
    rec: &mut ContactRecord,
    d0: &mut f64,
    unseen: bool,
    w0: f64,
) -> f64 {
    let p = inp.params;
    let mut overlap_tol = p.contact.eps1 * max_step_penetration(p, w0);
    // In the stage a depth pushed out costs nothing (the stage ends at rest), and a cut mass
    // kept 21 overlaps of 0.5 mm from it that its run then gave back: a block of the jointed
    // slope's stable mass moved 1.5 mm instead of 0.5.
    let carries = p.mode == Mode::Dynamic && !inp.in_stage;
    if carries {
        overlap_tol = overlap_tol.min(pushed_out_within(inp.dt));
    }
    rec.overlap = rec.overlap.min(d0.max(0.0));
    if unseen && *d0 > overlap_tol {
        rec.overlap = *d0;
        if debug_log() {
            eprintln!(
                "t={:.4}: contact {:?} first seen {:.3e} m deep; the overlap is kept",
                inp.time, cand.key, d0
            );
        }
    }
    *d0 -= rec.overlap;
    if unseen && carries && rec.overlap == 0.0 {
        d0.max(0.0)
    } else {
        0.0
    }
}

/// A contact first seen touching starts locked (Shi), unless its blocks move past each other:
/// then it starts sliding along that motion (see [`law::closes_sliding`]), as one that closes
/// in the open–close check does. Started locked, a vertex reaching the face of a block it slid
/// along held its block for a pass while every other contact of the block read as stopped: a
/// Hoek–Bray wedge sliding on ten contacts stuck each time one of its corners passed a
/// neighbour's corner, and bounced back. Both methods (DDA-3p's closing in the open–close
/// check asks more, see `open_close::sliding_blocks`).
fn slide_if_moving(active: &mut [Active], new: &[bool], inp: &ActivationInputs) {
    for (c, &new) in active.iter_mut().zip(new) {
        if !new || c.rec.state != ContactState::Lock {
            continue;
        }
        let v = c.relative_velocity(inp.blocks);
        let n = c.cand.normal;
        let motion = (v - n * n.dot(&v)) * inp.dt;
        if let Some(tau) = law::closes_sliding(&motion, &c.law(inp.params)) {
            c.rec.state = ContactState::Slide;
            c.rec.tau = tau;
            c.rec.intact = false;
            c.start = c.rec;
        }
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
