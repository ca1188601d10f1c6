//! The global system K D = F: a symmetric block-sparse matrix of 12×12 blocks, factorized by
//! faer's supernodal sparse Cholesky in a fill-reducing (AMD) order of the blocks.
//!
//! The sparsity pattern is the block graph of the detected contacts. It is fixed for a whole
//! step (open contacts keep their place in the pattern), so the symbolic analysis is done once a
//! step — and reused across steps while the contact graph does not change. Iterations that change
//! only F (ALM multiplier updates) reuse the numeric factorization too.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::linalg::{SupernodalThreshold, amd};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use crate::physics::mechanics::Mat12;

/// Lower block triangle of K: diagonal blocks plus one 12×12 block K[hi][lo] per block pair.
#[derive(Clone, Debug)]
pub struct BlockMatrix {
    pub diag: Vec<Mat12>,
    /// Pairs (hi, lo) with hi > lo, sorted by (lo, hi): the pattern.
    pub pairs: Vec<(usize, usize)>,
    pub off: Vec<Mat12>,
}

impl BlockMatrix {
    pub fn new(n_blocks: usize, mut pairs: Vec<(usize, usize)>) -> Self {
        for p in &mut pairs {
            *p = (p.0.max(p.1), p.0.min(p.1));
        }
        pairs.sort_by_key(|&(hi, lo)| (lo, hi));
        pairs.dedup();
        let off = vec![Mat12::zeros(); pairs.len()];
        BlockMatrix {
            diag: vec![Mat12::zeros(); n_blocks],
            pairs,
            off,
        }
    }

    /// Index of the pair {a, b} in `pairs`.
    pub fn pair_index(&self, a: usize, b: usize) -> Option<usize> {
        let key = (a.max(b), a.min(b));
        self.pairs
            .binary_search_by_key(&(key.1, key.0), |&(hi, lo)| (lo, hi))
            .ok()
    }

    /// Adds K_ab (and implicitly K_ba = K_abᵀ) for a ≠ b at pair index `p`.
    pub fn add_off(&mut self, p: usize, a: usize, b: usize, k_ab: &Mat12) {
        if a > b {
            self.off[p] += k_ab;
        } else {
            self.off[p] += k_ab.transpose();
        }
    }

    /// y = K x for a stacked vector (used by tests and residual checks).
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        let seg = |v: &[f64], i: usize| {
            nalgebra::SVector::<f64, 12>::from_column_slice(&v[12 * i..12 * i + 12])
        };
        for (i, d) in self.diag.iter().enumerate() {
            let r = d * seg(x, i);
            for a in 0..12 {
                y[12 * i + a] += r[a];
            }
        }
        for (p, &(hi, lo)) in self.pairs.iter().enumerate() {
            let r1 = self.off[p] * seg(x, lo);
            let r2 = self.off[p].transpose() * seg(x, hi);
            for a in 0..12 {
                y[12 * hi + a] += r1[a];
                y[12 * lo + a] += r2[a];
            }
        }
        y
    }
}

/// Why a solve failed. K is SPD by construction (reference §7), so this means a NaN or a
/// degenerate block, and the step is redone with a smaller Δt.
#[derive(Debug, Clone, thiserror::Error)]
pub enum SolveError {
    #[error("the global stiffness matrix is not positive definite")]
    NotPositiveDefinite,
    #[error("sparse symbolic analysis failed")]
    Symbolic,
}

/// Sparse LLᵀ of a [`BlockMatrix`] with cached symbolic analysis.
///
/// The fill-reducing order is computed on the block graph (AMD over blocks, not over the 12×
/// larger scalar graph), and the matrix is scattered straight into that order, so faer's numeric
/// factorization gets it unpermuted and skips its own permutation of A, which took an eighth of a
/// 1000-block run. The factorization is supernodal: K is made of dense 12×12 blocks, so its
/// supernodes are at least 12 wide, and dense kernels on them beat the simplicial (column by
/// column) factorization that faer's scalar flop heuristic picks for these matrices — 3.5× on a
/// 100-block wall.
#[derive(Default)]
pub struct SparseCholesky {
    n_blocks: usize,
    pairs: Vec<(usize, usize)>,
    /// New position of each block in the elimination order.
    position: Vec<usize>,
    /// Lower CSC structure of the permuted scalar matrix.
    structure: Option<SymbolicSparseColMat<usize>>,
    symbolic: Option<SymbolicCholesky<usize>>,
    /// Where each pair's block goes: its column block in the elimination order, its slot among
    /// that column block's off-diagonal row blocks, and whether the stored block K[hi][lo] lands
    /// transposed (as K[lo][hi]) in the lower triangle of the permuted matrix.
    pair_slot: Vec<PairSlot>,
    col_ptr: Vec<usize>,
    values: Vec<f64>,
    l_values: Vec<f64>,
    /// Right-hand side in the elimination order.
    work: Vec<f64>,
    mem: Option<MemBuffer>,
    factorized: bool,
    /// Threads of faer's factorization: the rayon pool's where the dense fronts are wide enough
    /// for its parallel kernels to pay (fixed with the pattern, as is the scratch sized for it).
    threads: usize,
    /// Symbolic analyses performed (for statistics).
    pub symbolic_count: u64,
}

#[derive(Clone, Copy, Debug, Default)]
struct PairSlot {
    column: usize,
    slot: usize,
    transposed: bool,
}

/// AMD order of the block graph with `nb` nodes and edges `pairs`: `order[k]` is the block
/// eliminated k-th.
fn block_order(nb: usize, pairs: &[(usize, usize)]) -> Result<Vec<usize>, SolveError> {
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); nb];
    for &(a, b) in pairs {
        adj[a].push(b);
        adj[b].push(a);
    }
    let mut col_ptr = Vec::with_capacity(nb + 1);
    let mut rows = Vec::with_capacity(2 * pairs.len());
    col_ptr.push(0);
    for a in &mut adj {
        a.sort_unstable();
        a.dedup();
        rows.extend_from_slice(a);
        col_ptr.push(rows.len());
    }
    let graph = SymbolicSparseColMat::new_checked(nb, nb, col_ptr, None, rows);
    let mut order = vec![0usize; nb];
    let mut inverse = vec![0usize; nb];
    let mut mem = MemBuffer::new(amd::order_scratch::<usize>(nb, graph.compute_nnz()));
    amd::order(
        &mut order,
        &mut inverse,
        graph.as_ref(),
        amd::Control::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|_| SolveError::Symbolic)?;
    Ok(order)
}

/// The flop-weighted mean front height from which the factorization runs on the whole rayon pool.
///
/// faer's parallel supernodal factorization splits the dense work inside each supernode, so it
/// pays only where the fronts are wide. Measured on this project's 2-core machine: the walls of
/// 100 and 1000 blocks (fronts about 95 rows high) factorize 10–20 % slower on two threads, the
/// shipped jointed slope (482) about 20 % faster and the jointed mass of 1000 (1114) 1.35×
/// faster (the scene run for one step, 42 factorizations: 4.9 s against 6.8 s on one thread).
/// The factor came out the same to the bit on 1, 2 and 3 threads there, and
/// `tests/thread_count.rs` holds that on the jointed slope (fronts 482 high).
const PARALLEL_FRONT_HEIGHT: f64 = 256.0;

/// Flop-weighted mean height of the supernodes' fronts (the rows of each dense panel): the
/// width of the dense kernels that carry most of a factorization's work.
fn front_height(symbolic: &SymbolicCholesky<usize>) -> f64 {
    use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
    let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
        return 0.0;
    };
    let (mut flops, mut weighted) = (0.0, 0.0);
    for i in 0..s.n_supernodes() {
        let w = (s.supernode_end()[i] - s.supernode_begin()[i]) as f64;
        let h = w + s.supernode(i).pattern().len() as f64;
        // Σ_{c<w} (h − c)²: each eliminated column updates the rest of its front.
        let f = w * (h * h - h * (w - 1.0) + (w - 1.0) * (2.0 * w - 1.0) / 6.0);
        flops += f;
        weighted += f * h;
    }
    weighted / flops.max(1.0)
}

impl SparseCholesky {
    /// Makes sure the symbolic analysis matches the pattern of `k`; recomputes it only when the
    /// block graph changed.
    fn ensure_pattern(&mut self, k: &BlockMatrix) -> Result<(), SolveError> {
        let nb = k.diag.len();
        if self.symbolic.is_some() && self.n_blocks == nb && self.pairs == k.pairs {
            return Ok(());
        }
        let n = 12 * nb;
        let order = block_order(nb, &k.pairs)?;
        let mut position = vec![0usize; nb];
        for (new, &old) in order.iter().enumerate() {
            position[old] = new;
        }
        // Off-diagonal row blocks of each (permuted) column block, in ascending row order.
        let mut rows_of: Vec<Vec<(usize, usize)>> = vec![Vec::new(); nb];
        for (p, &(hi, lo)) in k.pairs.iter().enumerate() {
            let (a, b) = (position[hi], position[lo]);
            rows_of[a.min(b)].push((a.max(b), p));
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut pair_slot = vec![PairSlot::default(); k.pairs.len()];
        col_ptr.push(0);
        for (j, rows) in rows_of.iter_mut().enumerate() {
            rows.sort_unstable();
            for (slot, &(i, p)) in rows.iter().enumerate() {
                // The stored K[hi][lo] is the lower block when hi comes later in the order.
                let (hi, _) = k.pairs[p];
                pair_slot[p] = PairSlot {
                    column: j,
                    slot,
                    transposed: position[hi] != i,
                };
            }
            for c in 0..12 {
                for r in c..12 {
                    row_idx.push(12 * j + r);
                }
                for &(i, _) in rows.iter() {
                    for r in 0..12 {
                        row_idx.push(12 * i + r);
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        // The symbolic analysis in the identity order reads the upper triangle; the pattern is
        // symmetric, so that is the transpose of the lower one.
        let mut up_ptr = vec![0usize; n + 1];
        for &r in &row_idx {
            up_ptr[r + 1] += 1;
        }
        for c in 0..n {
            up_ptr[c + 1] += up_ptr[c];
        }
        let mut next = up_ptr.clone();
        let mut up_idx = vec![0usize; row_idx.len()];
        for c in 0..n {
            for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                up_idx[next[r]] = c;
                next[r] += 1;
            }
        }
        let upper = SymbolicSparseColMat::new_checked(n, n, up_ptr, None, up_idx);
        let structure = SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            upper.as_ref(),
            Side::Upper,
            SymmetricOrdering::Identity,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|_| SolveError::Symbolic)?;
        self.threads = if front_height(&symbolic) >= PARALLEL_FRONT_HEIGHT {
            rayon::current_num_threads()
        } else {
            1
        };
        let req = symbolic
            .factorize_numeric_llt_scratch::<f64>(self.par(), Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, self.par()));
        self.mem = Some(MemBuffer::new(req));
        self.values = vec![0.0; col_ptr[n]];
        self.l_values = vec![0.0; symbolic.len_val()];
        self.work = vec![0.0; n];
        self.col_ptr = col_ptr;
        self.pair_slot = pair_slot;
        self.position = position;
        self.structure = Some(structure);
        self.symbolic = Some(symbolic);
        self.n_blocks = nb;
        self.pairs = k.pairs.clone();
        self.factorized = false;
        self.symbolic_count += 1;
        Ok(())
    }

    /// faer's parallelism for this pattern.
    fn par(&self) -> Par {
        if self.threads > 1 {
            Par::rayon(self.threads)
        } else {
            Par::Seq
        }
    }

    /// Whether a symbolic analysis is kept (for the next factorization to reuse).
    pub fn analysed(&self) -> bool {
        self.symbolic.is_some()
    }

    /// Performs `k`'s symbolic analysis now, uncounted: a solver restored from a checkpoint
    /// (which does not save the factorization) starts with the analysis the uninterrupted run
    /// kept, and so counts its analyses as that run does.
    pub fn analyse_ahead(&mut self, k: &BlockMatrix) -> Result<(), SolveError> {
        let count = self.symbolic_count;
        self.ensure_pattern(k)?;
        self.symbolic_count = count;
        Ok(())
    }

    /// Numeric factorization of `k`.
    pub fn factorize(&mut self, k: &BlockMatrix) -> Result<(), SolveError> {
        self.ensure_pattern(k)?;
        self.factorized = false;
        // Scatter the blocks into the CSC values, in the elimination order. Column c of a
        // column block starts with its diagonal entries, rows c..12 (12 − c of them), followed
        // by the 12 rows of each off-diagonal block.
        let cp = &self.col_ptr;
        // Column c of a 12×12 block is the contiguous slice [12c, 12c + 12) of its
        // column-major storage, so the lower part of a diagonal block and an untransposed
        // off-diagonal block go over column by column as slices.
        for (old, d) in k.diag.iter().enumerate() {
            let j = self.position[old];
            let ds = d.as_slice();
            for c in 0..12 {
                let base = cp[12 * j + c];
                self.values[base..base + 12 - c].copy_from_slice(&ds[13 * c..12 * c + 12]);
            }
        }
        for (blk, at) in k.off.iter().zip(&self.pair_slot) {
            let bs = blk.as_slice();
            for c in 0..12 {
                let base = cp[12 * at.column + c] + (12 - c) + 12 * at.slot;
                let column = &mut self.values[base..base + 12];
                if at.transposed {
                    for (r, v) in column.iter_mut().enumerate() {
                        *v = bs[12 * r + c];
                    }
                } else {
                    column.copy_from_slice(&bs[12 * c..12 * c + 12]);
                }
            }
        }
        // Without a short cut, so that the test runs over the values in wide lanes.
        let not_finite = self
            .values
            .iter()
            .fold(false, |bad, v| bad | !v.is_finite());
        if not_finite {
            return Err(SolveError::NotPositiveDefinite);
        }
        let par = self.par();
        let structure = self.structure.as_ref().expect("pattern set");
        let symbolic = self.symbolic.as_ref().expect("pattern set");
        let a = SparseColMatRef::new(structure.as_ref(), &self.values);
        let stack = MemStack::new(self.mem.as_mut().expect("pattern set"));
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.l_values,
                a,
                Side::Lower,
                LltRegularization::default(),
                par,
                stack,
                Default::default(),
            )
            .map_err(|_| SolveError::NotPositiveDefinite)?;
        self.factorized = true;
        Ok(())
    }

    /// Solves K x = b in place with the last factorization.
    pub fn solve_in_place(&mut self, b: &mut [f64]) {
        assert!(self.factorized, "solve before factorize");
        for (old, &new) in self.position.iter().enumerate() {
            self.work[12 * new..12 * new + 12].copy_from_slice(&b[12 * old..12 * old + 12]);
        }
        let symbolic = self.symbolic.as_ref().expect("pattern set");
        let llt = faer::sparse::linalg::cholesky::LltRef::new(symbolic, &self.l_values);
        let n = self.work.len();
        let rhs = MatMut::from_column_major_slice_mut(&mut self.work, n, 1);
        let stack = MemStack::new(self.mem.as_mut().expect("pattern set"));
        // The solves stay serial: on the jointed mass of 1000 a parallel solve was no faster,
        // and its sums, split by thread, changed the last bits of the results.
        llt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
        for (old, &new) in self.position.iter().enumerate() {
            b[12 * old..12 * old + 12].copy_from_slice(&self.work[12 * new..12 * new + 12]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    }

    fn spd_block(seed: usize) -> Mat12 {
        let a = Mat12::from_fn(|r, c| ((r * 13 + c * 7 + seed * 3) % 11) as f64 / 11.0 - 0.5);
        a * a.transpose() + Mat12::identity() * 12.0
    }

    #[test]
    fn solves_a_block_sparse_spd_system() {
        // A chain 0-1-2-3 plus a link 0-3, block sizes 12.
        let mut k = BlockMatrix::new(4, vec![(0, 1), (2, 1), (2, 3), (3, 0)]);
        for (i, d) in k.diag.iter_mut().enumerate() {
            *d = spd_block(i);
        }
        for p in 0..k.pairs.len() {
            k.off[p] = Mat12::from_fn(|r, c| (((r + 2 * c + p) % 5) as f64 - 2.0) * 0.1);
        }
        let x_true: Vec<f64> = (0..48).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut b = k.mul(&x_true);
        let mut chol = SparseCholesky::default();
        chol.factorize(&k).unwrap();
        chol.solve_in_place(&mut b);
        let err = max_abs_diff(&b, &x_true);
        assert!(err < 1e-12, "{err}");
        // Same pattern: no new symbolic analysis.
        k.diag[2] *= 2.0;
        chol.factorize(&k).unwrap();
        assert_eq!(chol.symbolic_count, 1);
        let mut b = k.mul(&x_true);
        chol.solve_in_place(&mut b);
        let err = max_abs_diff(&b, &x_true);
        assert!(err < 1e-12, "{err}");
    }

    #[test]
    fn solves_a_wall_with_a_hub_block_in_its_reordered_form() {
        // A wall of 4 × 6 blocks (neighbours across and diagonally) plus a hub block touching
        // the whole bottom row, as the ground slab does: AMD reorders it, so blocks land
        // transposed in the lower triangle.
        let (w, h) = (6, 4);
        let id = |x: usize, z: usize| 1 + z * w + x;
        let mut pairs = Vec::new();
        for z in 0..h {
            for x in 0..w {
                if x + 1 < w {
                    pairs.push((id(x, z), id(x + 1, z)));
                }
                if z + 1 < h {
                    pairs.push((id(x, z), id(x, z + 1)));
                    if x + 1 < w {
                        pairs.push((id(x + 1, z), id(x, z + 1)));
                    }
                }
            }
        }
        for x in 0..w {
            pairs.push((0, id(x, 0)));
        }
        let nb = 1 + w * h;
        let mut k = BlockMatrix::new(nb, pairs);
        for (i, d) in k.diag.iter_mut().enumerate() {
            *d = spd_block(i) * 4.0;
        }
        for p in 0..k.pairs.len() {
            k.off[p] = Mat12::from_fn(|r, c| (((3 * r + c + p) % 7) as f64 - 3.0) * 0.05);
        }
        let x_true: Vec<f64> = (0..12 * nb).map(|i| (i as f64 * 0.23).cos()).collect();
        let mut b = k.mul(&x_true);
        let mut chol = SparseCholesky::default();
        chol.factorize(&k).unwrap();
        assert!(chol.pair_slot.iter().any(|s| s.transposed));
        assert!(chol.pair_slot.iter().any(|s| !s.transposed));
        chol.solve_in_place(&mut b);
        let err = max_abs_diff(&b, &x_true);
        assert!(err < 1e-11, "{err}");
    }

    #[test]
    fn pair_lookup_and_transpose_convention() {
        let mut k = BlockMatrix::new(3, vec![(2, 0), (1, 2)]);
        let p = k.pair_index(0, 2).unwrap();
        assert_eq!(k.pair_index(2, 0), Some(p));
        assert_eq!(k.pair_index(0, 1), None);
        let m = Mat12::from_fn(|r, c| (r * 12 + c) as f64);
        k.add_off(p, 0, 2, &m); // K_02 = m → stored K_20 = mᵀ
        assert_eq!(k.off[p], m.transpose());
    }

    #[test]
    fn indefinite_matrix_is_reported() {
        let mut k = BlockMatrix::new(1, vec![]);
        k.diag[0] = -Mat12::identity();
        let mut chol = SparseCholesky::default();
        assert!(chol.factorize(&k).is_err());
    }

    /// A block graph whose every block touches every other: one front 12 n high.
    fn dense_graph(nb: usize) -> BlockMatrix {
        let pairs = (0..nb).flat_map(|a| (0..a).map(move |b| (a, b))).collect();
        let mut k = BlockMatrix::new(nb, pairs);
        for (i, d) in k.diag.iter_mut().enumerate() {
            *d = Mat12::from_fn(|r, c| ((r * 5 + c * 3 + i) % 7) as f64 * 0.01)
                + Mat12::identity() * (24.0 * nb as f64);
            *d = (*d + d.transpose()) * 0.5;
        }
        for p in 0..k.pairs.len() {
            k.off[p] = Mat12::from_fn(|r, c| (((r + 3 * c + p) % 9) as f64 - 4.0) * 0.3);
        }
        k
    }

    fn factor_and_solve(k: &BlockMatrix, threads: usize) -> (usize, Vec<f64>, Vec<f64>) {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut chol = SparseCholesky::default();
            chol.factorize(k).unwrap();
            let mut b: Vec<f64> = (0..12 * k.diag.len()).map(|i| (i as f64).sin()).collect();
            chol.solve_in_place(&mut b);
            (chol.threads, chol.l_values.clone(), b)
        })
    }

    #[test]
    fn wide_fronts_factorize_on_the_pool_to_the_same_bits() {
        let k = dense_graph(40);
        let x_true: Vec<f64> = (0..12 * 40).map(|i| (i as f64).sin()).collect();
        let (t1, l1, x1) = factor_and_solve(&k, 1);
        assert_eq!(t1, 1);
        // The solution is right (K x = b with b = sin i, so check K x).
        let kx = k.mul(&x1);
        let res = max_abs_diff(&kx, &x_true);
        assert!(res < 1e-9, "{res}");
        for threads in [2, 3, 4] {
            let (t, l, x) = factor_and_solve(&k, threads);
            assert_eq!(t, threads, "fronts of 480 rows run on the pool");
            assert!(l.iter().zip(&l1).all(|(a, b)| a.to_bits() == b.to_bits()));
            assert!(x.iter().zip(&x1).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
    }

    #[test]
    fn narrow_fronts_stay_serial() {
        // A chain of blocks: every front is two blocks (24 rows) high.
        let pairs = (1..50).map(|a| (a, a - 1)).collect();
        let mut k = BlockMatrix::new(50, pairs);
        for d in k.diag.iter_mut() {
            *d = Mat12::identity() * 10.0;
        }
        let (t, _, _) = factor_and_solve(&k, 2);
        assert_eq!(t, 1);
    }
}
