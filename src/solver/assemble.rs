//! Assembly of the global system K D = F (reference §3, §5): the block terms (K0, F0) of an
//! attempt, each closed contact's stiffness and forces, the sparsity pattern of a step, and K
//! kept up to date contact by contact as states and penalties change.

use rayon::prelude::*;

use super::active::{Active, StiffnessKey};
use super::{PAR_BLOCKS, PAR_CONTACTS};
use crate::contact::ContactState;
use crate::contact::kinematics::{
    ContactForces, ContactStiffness, add_friction, add_friction_tangent, add_normal_force,
    add_normal_stiffness, add_shear_spring_force, add_shear_spring_stiffness,
};
use crate::model::Block;
use crate::params::{ContactParams, Method, SolverParams};
use crate::physics::geometry::Vec3;
use crate::physics::integrator::Scheme;
use crate::physics::linear::BlockMatrix;
use crate::physics::mechanics::{
    BlockStepInput, BlockTerms, Mat12, Vec12, block_terms as block_step_terms,
};

/// The sparsity pattern of a step: block pairs with a contact now, plus pairs of the last
/// pattern that are still `near` each other. Keeping those (as zero blocks) makes the pattern,
/// and with it the symbolic analysis, stable while contacts come and go between neighbours.
pub(crate) fn sparsity_pattern(
    active: &[Active],
    last: &[(usize, usize)],
    near: &[(usize, usize)],
) -> Vec<(usize, usize)> {
    let mut p: Vec<(usize, usize)> = active
        .iter()
        .map(|c| {
            let (i, j) = c.blocks();
            (i.min(j), i.max(j))
        })
        .chain(
            last.iter()
                .copied()
                .filter(|q| near.binary_search(q).is_ok()),
        )
        .collect();
    p.sort_unstable();
    p.dedup();
    p
}

/// (K0, F0): the block terms of §3 for a step of length `dt`, fixed for an attempt.
pub(crate) fn block_terms(
    p: &SolverParams,
    blocks: &[Block],
    scheme: &Scheme,
    dt: f64,
) -> (Vec<Mat12>, Vec<Vec12>) {
    blocks
        .par_iter()
        .with_min_len(PAR_BLOCKS)
        .map(|b| {
            let t = one_block(p, b, scheme, &b.kinematics(), dt);
            (t.k, t.f)
        })
        .unzip()
}

fn one_block(
    p: &SolverParams,
    b: &Block,
    scheme: &Scheme,
    kin: &crate::physics::integrator::Kinematics,
    dt: f64,
) -> BlockTerms {
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
    block_step_terms(
        &BlockStepInput {
            mass_matrix: &b.mass_matrix,
            mp: &b.mp,
            density: b.density,
            elasticity: &b.elasticity,
            stress: &b.stress,
            kinematics: kin,
            scheme,
            gravity: &Vec3::from(p.gravity),
            loads: &b.loads,
            springs: &springs,
        },
        dt,
    )
}

/// The stiffness of one closed contact in the state `key`: normal (P10), and the shear spring
/// (P15)/(5.7) if locked, or the tangent of sliding friction's direction if sliding (friction
/// (P20) itself is a load).
pub(crate) fn contact_stiffness(
    cp: &ContactParams,
    blocks: &[Block],
    c: &Active,
    key: &StiffnessKey,
) -> ContactStiffness {
    let mut t = ContactStiffness::default();
    add_normal_stiffness(&mut t, &c.kin, key.penalty);
    if key.lock {
        let tb = c.tb_at(&key.reference, blocks);
        let p_tau = cp.shear_penalty(key.penalty);
        add_shear_spring_stiffness(&mut t, &c.ta, &tb, &c.cand.normal, p_tau);
    } else if key.lateral > 0.0 {
        let tb = c.tb_at(&c.cand.xb, blocks);
        add_friction_tangent(&mut t, &c.ta, &tb, &c.cand.normal, &key.tau, key.lateral);
    }
    t
}

/// Adds (`sign` = 1) or removes (−1) the stiffness of contact `c` in the state `key`.
pub(crate) fn apply_stiffness(
    kmat: &mut BlockMatrix,
    cp: &ContactParams,
    blocks: &[Block],
    c: &Active,
    key: &StiffnessKey,
    sign: f64,
) {
    let t = contact_stiffness(cp, blocks, c, key);
    let (i, j) = c.blocks();
    kmat.diag[i] += t.k_ii * sign;
    kmat.diag[j] += t.k_jj * sign;
    kmat.add_off(c.pair, i, j, &(t.k_ij * sign));
}

/// The force terms of one closed contact in its current state: normal (P10), locked shear
/// spring (P15)/(5.7), or sliding friction (P20).
pub(crate) fn contact_forces(p: &SolverParams, blocks: &[Block], c: &Active) -> ContactForces {
    let mut t = ContactForces::default();
    let alm = p.method == Method::Alm;
    add_normal_force(
        &mut t,
        &c.kin,
        c.rec.penalty,
        if alm { c.rec.lambda } else { 0.0 },
    );
    let tb = c.tb(blocks);
    match c.rec.state {
        ContactState::Lock => {
            let delta = c.cand.xa - c.rec.reference;
            let p_tau = p.contact.shear_penalty(c.rec.penalty);
            add_shear_spring_force(&mut t, &c.ta, &tb, &c.cand.normal, &delta, p_tau);
        }
        ContactState::Slide => {
            add_friction(&mut t, &c.ta, &tb, &c.rec.tau, c.sliding_friction(p));
        }
        ContactState::Open => {}
    }
    t
}

/// F: the block loads `f0` plus the forces of every closed contact.
pub(crate) fn load_vector(
    p: &SolverParams,
    blocks: &[Block],
    f0: &[Vec12],
    active: &[Active],
) -> Vec<f64> {
    let mut f: Vec<f64> = f0.iter().flat_map(|v| v.iter().copied()).collect();
    // Each contact's forces in parallel; summed afterwards in the contacts' order, so that F
    // does not depend on the thread count.
    let terms: Vec<Option<ContactForces>> = active
        .par_iter()
        .with_min_len(PAR_CONTACTS)
        .map(|c| (c.rec.state != ContactState::Open).then(|| contact_forces(p, blocks, c)))
        .collect();
    for (c, t) in active.iter().zip(terms) {
        let Some(t) = t else { continue };
        let (i, j) = c.blocks();
        for a in 0..12 {
            f[12 * i + a] += t.f_i[a];
            f[12 * j + a] += t.f_j[a];
        }
    }
    f
}

/// K kept in step with the contacts of an attempt. K is updated, not rebuilt: only the contacts
/// whose state, penalty or shear-spring reference changed since the last assembly swap their old
/// stiffness for the new one. Rebuilding all of them at every state change or penalty raise
/// took a fifth of a struck 100-block wall's run.
#[derive(Default)]
pub(crate) struct StiffnessSync {
    /// The state each contact's stiffness is in K with; empty until K is first assembled.
    in_k: Vec<Option<StiffnessKey>>,
}

impl StiffnessSync {
    /// Brings `kmat` up to date with the contacts' current states (K0 from `k0` the first time).
    pub fn update(
        &mut self,
        kmat: &mut BlockMatrix,
        k0: &[Mat12],
        cp: &ContactParams,
        blocks: &[Block],
        active: &[Active],
    ) {
        if self.in_k.is_empty() {
            for (kd, k) in kmat.diag.iter_mut().zip(k0) {
                *kd = *k;
            }
            for o in kmat.off.iter_mut() {
                *o = Mat12::zeros();
            }
            self.in_k = vec![None; active.len()];
        }
        for (c, slot) in active.iter().zip(self.in_k.iter_mut()) {
            let want = c.stiffness_key();
            if *slot == want {
                continue;
            }
            if let Some(old) = slot {
                apply_stiffness(kmat, cp, blocks, c, old, -1.0);
            }
            if let Some(new) = &want {
                apply_stiffness(kmat, cp, blocks, c, new, 1.0);
            }
            *slot = want;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::ContactMode;
    use crate::physics::linear::SparseCholesky;
    use crate::solver::Solver;
    use crate::solver::activate::{ActivationInputs, activate};

    /// The rockfall column run into the impact (from 0.25 s on, to the first step where both
    /// vertex–face and edge–edge contacts are active): the solver, its contacts for the next
    /// step, and their block pairs.
    fn at_impact() -> (Solver, Vec<Active>, Vec<(usize, usize)>) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes/rock_column_rockfall.toml");
        let s = crate::scene::load(&path).unwrap();
        let mut solver = Solver::new(s.model, s.params);
        let active = loop {
            solver.step().unwrap();
            let (active, _) = activate(&ActivationInputs {
                params: &solver.params,
                blocks: &solver.model.blocks,
                records: &solver.records,
                initial_boxes: &solver.initial_boxes,
                step: solver.step,
                time: solver.time,
                dt: solver.dt,
            });
            let has = |m| active.iter().any(|c| c.cand.mode() == m);
            if solver.time >= 0.25 && has(ContactMode::EdgeEdge) && has(ContactMode::VertexFace) {
                break active;
            }
            assert!(solver.time < 2.0, "no edge–edge contact by 2 s");
        };
        let pairs = active
            .iter()
            .map(|c| (c.cand.key.i as usize, c.cand.key.j as usize))
            .collect();
        (solver, active, pairs)
    }

    /// K assembled afresh for a step of 0.01 s: the block terms and every closed contact.
    fn assemble_fresh(solver: &Solver, active: &[Active], k: &mut BlockMatrix) {
        let (k0, _) = block_terms(&solver.params, &solver.model.blocks, &Scheme::SHI, 0.01);
        k.diag.copy_from_slice(&k0);
        for c in active {
            if let Some(key) = c.stiffness_key() {
                let (cp, blocks) = (&solver.params.contact, &solver.model.blocks);
                apply_stiffness(k, cp, blocks, c, &key, 1.0);
            }
        }
    }

    /// The assembled global matrix — block terms, fixed-point springs, and contacts in all three
    /// closed configurations (normal + shear spring, normal + friction with and without its
    /// direction's tangent) of both entrance modes —
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
            // Sliding with and without the tangent of friction's direction.
            c.lateral = [0.0, 1e7, 1e9][n % 3];
        }
        assemble_fresh(&solver, &active, &mut k);
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
    /// in, as the ALM loop does after state changes and penalty raises) equals K assembled afresh.
    #[test]
    fn updated_matrix_equals_fresh_assembly() {
        let (solver, mut active, pairs) = at_impact();
        let fresh = |active: &[Active]| {
            let mut k = BlockMatrix::new(solver.model.blocks.len(), pairs.clone());
            assemble_fresh(&solver, active, &mut k);
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
                apply_stiffness(
                    &mut k,
                    &solver.params.contact,
                    &solver.model.blocks,
                    c,
                    old,
                    -1.0,
                );
            }
            if let Some(new) = &new {
                apply_stiffness(
                    &mut k,
                    &solver.params.contact,
                    &solver.model.blocks,
                    c,
                    new,
                    1.0,
                );
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
