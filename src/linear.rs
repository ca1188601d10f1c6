//! The global system K D = F: a symmetric block-sparse matrix of 12×12 blocks, factorized by
//! faer's sparse Cholesky with a fill-reducing (AMD) ordering.
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
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use crate::mechanics::Mat12;

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
#[derive(Default)]
pub struct SparseCholesky {
    n_blocks: usize,
    pairs: Vec<(usize, usize)>,
    /// Lower CSC structure of the scalar matrix.
    structure: Option<SymbolicSparseColMat<usize>>,
    symbolic: Option<SymbolicCholesky<usize>>,
    /// For each pair, its slot among the off-diagonal row blocks of its column block.
    slot: Vec<usize>,
    col_ptr: Vec<usize>,
    values: Vec<f64>,
    l_values: Vec<f64>,
    mem: Option<MemBuffer>,
    factorized: bool,
    /// Symbolic analyses performed (for statistics).
    pub symbolic_count: u64,
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
        // Off-diagonal row blocks of each column block, in ascending row order.
        let mut rows_of: Vec<Vec<usize>> = vec![Vec::new(); nb];
        let mut slot = Vec::with_capacity(k.pairs.len());
        for &(hi, lo) in &k.pairs {
            slot.push(rows_of[lo].len());
            rows_of[lo].push(hi);
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for (j, rows) in rows_of.iter().enumerate() {
            for c in 0..12 {
                for r in c..12 {
                    row_idx.push(12 * j + r);
                }
                for &i in rows {
                    for r in 0..12 {
                        row_idx.push(12 * i + r);
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let structure = SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            structure.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|_| SolveError::Symbolic)?;
        let req = symbolic
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        self.mem = Some(MemBuffer::new(req));
        self.values = vec![0.0; col_ptr[n]];
        self.l_values = vec![0.0; symbolic.len_val()];
        self.col_ptr = col_ptr;
        self.slot = slot;
        self.structure = Some(structure);
        self.symbolic = Some(symbolic);
        self.n_blocks = nb;
        self.pairs = k.pairs.clone();
        self.factorized = false;
        self.symbolic_count += 1;
        Ok(())
    }

    /// Numeric factorization of `k`.
    pub fn factorize(&mut self, k: &BlockMatrix) -> Result<(), SolveError> {
        self.ensure_pattern(k)?;
        self.factorized = false;
        // Scatter the blocks into the CSC values.
        let cp = &self.col_ptr;
        for (j, d) in k.diag.iter().enumerate() {
            for c in 0..12 {
                let base = cp[12 * j + c];
                for r in c..12 {
                    self.values[base + r - c] = d[(r, c)];
                }
            }
        }
        for (p, &(_, lo)) in k.pairs.iter().enumerate() {
            let blk = &k.off[p];
            for c in 0..12 {
                let base = cp[12 * lo + c] + (12 - c) + 12 * self.slot[p];
                for r in 0..12 {
                    self.values[base + r] = blk[(r, c)];
                }
            }
        }
        if self.values.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::NotPositiveDefinite);
        }
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
                Par::Seq,
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
        let symbolic = self.symbolic.as_ref().expect("pattern set");
        let llt = faer::sparse::linalg::cholesky::LltRef::new(symbolic, &self.l_values);
        let n = b.len();
        let rhs = MatMut::from_column_major_slice_mut(b, n, 1);
        let stack = MemStack::new(self.mem.as_mut().expect("pattern set"));
        llt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let err: f64 = b
            .iter()
            .zip(&x_true)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-12, "{err}");
        // Same pattern: no new symbolic analysis.
        k.diag[2] *= 2.0;
        chol.factorize(&k).unwrap();
        assert_eq!(chol.symbolic_count, 1);
        let mut b = k.mul(&x_true);
        chol.solve_in_place(&mut b);
        let err: f64 = b
            .iter()
            .zip(&x_true)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-12, "{err}");
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
}
