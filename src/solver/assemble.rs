//! Assembly of the global system K D = F (reference §3, §5): the block terms (K0, F0) of an
//! attempt, each closed contact's stiffness and forces, the sparsity pattern of a step, and K
//! kept up to date contact by contact as states and penalties change.

use rayon::prelude::*;

use super::active::{Active, StiffnessKey};
use super::sleep::is_held;
use super::{PAR_BLOCKS, PAR_CONTACTS};
use crate::contact::ContactState;
use crate::contact::kinematics::{
    ContactForces, ContactStiffness, StiffnessBlock, add_friction, add_friction_tangent_block,
    add_normal_force, add_normal_stiffness_block, add_shear_spring_force,
    add_shear_spring_stiffness_block,
};
use crate::model::Block;
use crate::params::{ContactParams, Method, SolverParams};
use crate::physics::geometry::Vec3;
use crate::physics::integrator::Scheme;
use crate::physics::linear::BlockMatrix;
use crate::physics::mechanics::{
    BlockStepInput, BlockTerms, Mat3x12, Mat12, Vec12, block_terms as block_step_terms,
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

/// (K0, F0): the block terms of §3 for a step of length `dt`, fixed for an attempt. A `held`
/// block's are zero: [`hold`] gives it its own equation.
pub(crate) fn block_terms(
    p: &SolverParams,
    blocks: &[Block],
    held: &[bool],
    scheme: &Scheme,
    dt: f64,
) -> (Vec<Mat12>, Vec<Vec12>) {
    blocks
        .par_iter()
        .enumerate()
        .with_min_len(PAR_BLOCKS)
        .map(|(i, b)| {
            if is_held(held, i) {
                return (Mat12::zeros(), Vec12::zeros());
            }
            let t = one_block(p, b, scheme, &b.kinematics(), dt);
            (t.k, t.f)
        })
        .unzip()
}

/// Holds the `held` blocks where they are: each one's equation becomes I·d = 0, and its
/// coupling to every other block is dropped. A contact between a held block and a free one
/// then acts on the free one alone, as a contact with an immovable block would; its solution
/// is exactly 0 for the held block. K's other blocks and F's other rows are untouched, so
/// [`StiffnessSync`] may go on adding to and taking from them (and from the held blocks'
/// diagonal, which this resets each time).
pub(crate) fn hold(kmat: &mut BlockMatrix, f: &mut [f64], held: &[bool]) {
    if held.is_empty() {
        return;
    }
    for (i, _) in held.iter().enumerate().filter(|(_, h)| **h) {
        kmat.diag[i] = Mat12::identity();
        f[12 * i..12 * i + 12].fill(0.0);
    }
    let BlockMatrix { pairs, off, .. } = kmat;
    for (&(a, b), m) in pairs.iter().zip(off.iter_mut()) {
        if held[a] || held[b] {
            *m = Mat12::zeros();
        }
    }
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
    add_contact_stiffness(t.blocks_mut(), cp, blocks, c, key);
    t
}

/// The block `which` of [`contact_stiffness`], the same to the bit.
fn contact_stiffness_block(
    cp: &ContactParams,
    blocks: &[Block],
    c: &Active,
    key: &StiffnessKey,
    which: StiffnessBlock,
) -> Mat12 {
    let mut m = Mat12::zeros();
    add_contact_stiffness([(&mut m, which)], cp, blocks, c, key);
    m
}

/// Adds to each of `targets` its block of the contact's stiffness (see [`contact_stiffness`]):
/// the normal part, then the tangential one, each block by the same operations however many
/// are asked for.
fn add_contact_stiffness<'m>(
    targets: impl IntoIterator<Item = (&'m mut Mat12, StiffnessBlock)>,
    cp: &ContactParams,
    blocks: &[Block],
    c: &Active,
    key: &StiffnessKey,
) {
    // The tangential part, with T_b taken once for all the blocks asked for.
    enum Tangential {
        None,
        /// A locked contact's shear spring.
        Spring(Mat3x12),
        /// A sliding contact's friction turning with the slip (k⊥ > 0).
        Friction(Mat3x12),
    }
    let tangential = if key.lock {
        Tangential::Spring(c.tb_at(&key.reference, blocks))
    } else if key.lateral > 0.0 {
        Tangential::Friction(c.tb_at(&c.cand.xb, blocks))
    } else {
        Tangential::None
    };
    let (n, ta) = (&c.cand.normal, c.ta(blocks));
    for (m, which) in targets {
        add_normal_stiffness_block(m, which, &c.kin, key.penalty);
        match &tangential {
            Tangential::Spring(tb) => {
                let p_tau = cp.shear_penalty(key.penalty, c.inertia);
                add_shear_spring_stiffness_block(m, which, &ta, tb, n, p_tau);
            }
            Tangential::Friction(tb) => {
                add_friction_tangent_block(m, which, &ta, tb, n, &key.tau, key.lateral);
            }
            Tangential::None => {}
        }
    }
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
            let p_tau = p.contact.shear_penalty(c.rec.penalty, c.inertia);
            add_shear_spring_force(&mut t, &c.ta(blocks), &tb, &c.cand.normal, &delta, p_tau);
        }
        ContactState::Slide => {
            add_friction(
                &mut t,
                &c.ta(blocks),
                &tb,
                &c.rec.tau,
                c.sliding_friction(p),
            );
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

/// Takes contact `c`'s stiffness in the state `old` out of K and puts it in in its present
/// state: one contact's part of [`StiffnessSync::update`].
pub(crate) fn restate_stiffness(
    kmat: &mut BlockMatrix,
    cp: &ContactParams,
    blocks: &[Block],
    c: &Active,
    old: Option<&StiffnessKey>,
) {
    if let Some(old) = old {
        apply_stiffness(kmat, cp, blocks, c, old, -1.0);
    }
    if let Some(new) = &c.stiffness_key() {
        apply_stiffness(kmat, cp, blocks, c, new, 1.0);
    }
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
        let changed: Vec<usize> = (0..active.len())
            .filter(|&k| self.in_k[k] != active[k].stiffness_key())
            .collect();
        if changed.len() >= PAR_CONTACTS {
            update_by_block(kmat, cp, blocks, active, &self.in_k, &changed);
        } else {
            for &k in &changed {
                restate_stiffness(kmat, cp, blocks, &active[k], self.in_k[k].as_ref());
            }
        }
        for &k in &changed {
            self.in_k[k] = active[k].stiffness_key();
        }
    }
}

/// [`StiffnessSync::update`] for many changed contacts (every contact at a step's first
/// assembly: a fifth of a standing wall's step, on one thread): each of K's blocks on the pool,
/// taking from each changed contact touching it, in the contacts' order, the block of the old
/// stiffness out and the new one in. Every block of K gets the very additions, in the very
/// order, of the contact-by-contact update, so K is the same to the bit on any thread count.
/// (Each contact's three blocks computed on the pool and added in turn was slower than one
/// thread: 3.5 kB a contact through a buffer.)
fn update_by_block(
    kmat: &mut BlockMatrix,
    cp: &ContactParams,
    blocks: &[Block],
    active: &[Active],
    in_k: &[Option<StiffnessKey>],
    changed: &[usize],
) {
    let by_block = Rows::of(kmat.diag.len(), changed, |k| {
        let (i, j) = active[k].blocks();
        [(i, StiffnessBlock::Ii), (j, StiffnessBlock::Jj)]
    });
    let by_pair = Rows::of(kmat.off.len(), changed, |k| {
        [(active[k].pair, StiffnessBlock::Ij)]
    });
    // Contact k's block `which` in its old state out, in its new state in.
    let swap = |m: &mut Mat12, k: usize, which: StiffnessBlock, place: &dyn Fn(&Mat12) -> Mat12| {
        let c = &active[k];
        for (key, sign) in [(in_k[k], -1.0), (c.stiffness_key(), 1.0)] {
            if let Some(key) = key {
                *m += place(&(contact_stiffness_block(cp, blocks, c, &key, which) * sign));
            }
        }
    };
    let (diag, off) = (&mut kmat.diag, &mut kmat.off);
    rayon::join(
        || {
            diag.par_iter_mut()
                .enumerate()
                .with_min_len(PAR_BLOCKS / 16)
                .for_each(|(b, m)| {
                    for &(k, which) in by_block.row(b) {
                        swap(m, k, which, &|t| *t);
                    }
                })
        },
        || {
            off.par_iter_mut()
                .enumerate()
                .with_min_len(PAR_BLOCKS / 4)
                .for_each(|(p, m)| {
                    for &(k, which) in by_pair.row(p) {
                        // `BlockMatrix::add_off`: K_ij is stored as is where i > j.
                        let (i, j) = active[k].blocks();
                        swap(m, k, which, &|t| if i > j { *t } else { t.transpose() });
                    }
                })
        },
    );
}

/// The changed contacts of each of K's blocks (a row per block or per pair), in the contacts'
/// order.
struct Rows {
    start: Vec<usize>,
    items: Vec<(usize, StiffnessBlock)>,
}

impl Rows {
    fn of<const N: usize>(
        rows: usize,
        changed: &[usize],
        targets: impl Fn(usize) -> [(usize, StiffnessBlock); N],
    ) -> Rows {
        let mut start = vec![0usize; rows + 1];
        for &k in changed {
            for (row, _) in targets(k) {
                start[row + 1] += 1;
            }
        }
        for r in 0..rows {
            start[r + 1] += start[r];
        }
        let mut fill = start.clone();
        let mut items = vec![(0, StiffnessBlock::Ii); start[rows]];
        for &k in changed {
            for (row, which) in targets(k) {
                items[fill[row]] = (k, which);
                fill[row] += 1;
            }
        }
        Rows { start, items }
    }

    fn row(&self, r: usize) -> &[(usize, StiffnessBlock)] {
        &self.items[self.start[r]..self.start[r + 1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::ContactMode;
    use crate::physics::linear::SparseCholesky;
    use crate::solver::Solver;

    /// The rockfall column run into the impact (from 0.25 s on, to the first step where both
    /// vertex–face and edge–edge contacts are active): the solver, its contacts for the next
    /// step (each pointing at its pair in a matrix laid out on the pairs), and their block pairs.
    fn at_impact() -> (Solver, Vec<Active>, Vec<(usize, usize)>) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes/rock_column_rockfall.toml");
        let s = crate::scene::load(&path).unwrap();
        let mut solver = Solver::new(s.model, s.params);
        let mut active = loop {
            solver.step().unwrap();
            let active = solver.next_contacts();
            let has = |m| active.iter().any(|c| c.cand.mode() == m);
            if solver.time >= 0.25 && has(ContactMode::EdgeEdge) && has(ContactMode::VertexFace) {
                break active;
            }
            assert!(solver.time < 2.0, "no edge–edge contact by 2 s");
        };
        let pairs: Vec<_> = active
            .iter()
            .map(|c| (c.cand.key.i as usize, c.cand.key.j as usize))
            .collect();
        let pattern = BlockMatrix::new(solver.model.blocks.len(), pairs.clone());
        for c in &mut active {
            c.pair = pattern
                .pair_index(c.cand.key.i as usize, c.cand.key.j as usize)
                .unwrap();
        }
        (solver, active, pairs)
    }

    /// Changes every contact: opened, set sliding, stiffened ×1000, or its spring re-anchored.
    fn change_every_contact(active: &mut [Active]) {
        for (n, c) in active.iter_mut().enumerate() {
            match n % 4 {
                0 => c.rec.state = ContactState::Open,
                1 => c.rec.state = ContactState::Slide,
                2 => c.rec.penalty *= 1000.0,
                _ => c.rec.reference += Vec3::new(1e-3, -2e-3, 5e-4),
            }
        }
    }

    /// K assembled afresh for a step of 0.01 s: the block terms and every closed contact.
    fn assemble_fresh(solver: &Solver, active: &[Active], k: &mut BlockMatrix) {
        let (k0, _) = block_terms(
            &solver.params,
            &solver.model.blocks,
            &[],
            &Scheme::SHI,
            0.01,
        );
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
            c.rec.state = if n % 2 == 0 {
                ContactState::Lock
            } else {
                ContactState::Slide
            };
            c.rec.penalty *= [1.0, 10.0, 100.0][n % 3];
            c.rec.lambda = 1e4;
            c.friction_normal = 1e4;
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

    /// K updated block by block on the pool ([`update_by_block`]) is K updated contact by
    /// contact, to the bit: every contact in, then every contact changed (opened, set sliding
    /// with and without k⊥, stiffened, re-anchored), on pools of 1, 2 and 3 threads.
    #[test]
    fn block_by_block_update_is_the_contact_by_contact_update_to_the_bit() {
        let (solver, mut active, pairs) = at_impact();
        let (cp, blocks) = (&solver.params.contact, &solver.model.blocks);
        for (n, c) in active.iter_mut().enumerate() {
            c.rec.state = if n % 2 == 0 {
                ContactState::Lock
            } else {
                ContactState::Slide
            };
            c.rec.tau = Vec3::new(0.6, -0.8, 0.0);
            c.lateral = [0.0, 1e7][n % 2];
        }
        let all: Vec<usize> = (0..active.len()).collect();
        let none = vec![None; active.len()];
        let serial = |from: &[Option<StiffnessKey>], to: &[Active], k: &mut BlockMatrix| {
            for (c, old) in to.iter().zip(from) {
                restate_stiffness(k, cp, blocks, c, old.as_ref());
            }
        };
        let pools: Vec<_> = (1..=3)
            .map(|n| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .unwrap()
            })
            .collect();
        let fresh = || BlockMatrix::new(blocks.len(), pairs.clone());
        let mut want = fresh();
        let mut got: Vec<BlockMatrix> = pools.iter().map(|_| fresh()).collect();
        serial(&none, &active, &mut want);
        for (pool, k) in pools.iter().zip(&mut got) {
            pool.install(|| update_by_block(k, cp, blocks, &active, &none, &all));
        }
        let first: Vec<_> = active.iter().map(|c| c.stiffness_key()).collect();
        change_every_contact(&mut active);
        serial(&first, &active, &mut want);
        for (threads, (pool, k)) in pools.iter().zip(&mut got).enumerate() {
            pool.install(|| update_by_block(k, cp, blocks, &active, &first, &all));
            let same = k.diag == want.diag && k.off == want.off;
            assert!(same, "{} threads", threads + 1);
        }
        assert!(want.diag.iter().any(|m| m.abs().max() > 0.0));
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
        for c in active.iter_mut() {
            c.rec.state = ContactState::Lock;
        }
        let mut k = fresh(&active);
        let keys: Vec<_> = active.iter().map(|c| c.stiffness_key()).collect();
        change_every_contact(&mut active);
        for (c, old) in active.iter().zip(&keys) {
            assert_ne!(&c.stiffness_key(), old);
            let (cp, blocks) = (&solver.params.contact, &solver.model.blocks);
            restate_stiffness(&mut k, cp, blocks, c, old.as_ref());
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
