//! The linear solve of a Newton iteration, `K d = -r`, for the symmetric positive definite
//! tangent `K` (docs/solver.md, "Implicit"): a sparse Cholesky factorisation (faer), whose
//! fill-reducing ordering and symbolic analysis are made once per sparsity pattern and reused
//! by every factorisation on it.
//!
//! The factorisation runs on one thread: its sums then come in the same order on any machine,
//! so results do not depend on the thread count; the element loops around it run in parallel.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

/// The lower triangle of a symmetric sparsity pattern, compressed by columns, rows sorted.
#[derive(Clone, Debug)]
pub struct Pattern {
    symbolic: SymbolicSparseColMat<usize>,
}

impl Pattern {
    /// The pattern of `n` unknowns in which every two unknowns of one group are coupled (and
    /// every unknown with itself).
    pub fn from_groups<'a>(n: usize, groups: impl Iterator<Item = &'a [usize]>) -> Self {
        let mut rows: Vec<Vec<usize>> = (0..n).map(|j| vec![j]).collect();
        for group in groups {
            for &i in group {
                for &j in group {
                    if i > j {
                        rows[j].push(i);
                    }
                }
            }
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for mut column in rows {
            column.sort_unstable();
            column.dedup();
            row_idx.extend(column);
            col_ptr.push(row_idx.len());
        }
        Self {
            symbolic: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
        }
    }

    /// Number of unknowns.
    pub fn size(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Number of stored entries (the lower triangle).
    pub fn entries(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// Where the entry `(i, j)` of the lower triangle (`i >= j`) is stored; `None` outside the
    /// pattern.
    pub fn place(&self, i: usize, j: usize) -> Option<usize> {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        let start = self.symbolic.col_ptr()[j];
        let column = &self.symbolic.row_idx()[start..self.symbolic.col_ptr()[j + 1]];
        column.binary_search(&i).ok().map(|k| start + k)
    }

    /// `y = K x` for the symmetric matrix whose lower triangle is `values`.
    pub fn multiply(&self, values: &[f64], x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        for j in 0..x.len() {
            for k in col_ptr[j]..col_ptr[j + 1] {
                let i = row_idx[k];
                y[i] += values[k] * x[j];
                if i != j {
                    y[j] += values[k] * x[i];
                }
            }
        }
        y
    }
}

/// The tangent is not positive definite: a pivot of the factorisation was not positive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NotPositiveDefinite;

/// A Cholesky factorisation `K = L L^T` on a fixed [`Pattern`].
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    factor: Vec<f64>,
    factored: bool,
}

impl Cholesky {
    /// The ordering and symbolic factorisation of `pattern`.
    pub fn analyse(pattern: &Pattern) -> Result<Self, String> {
        let symbolic = factorize_symbolic_cholesky(
            pattern.symbolic.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| format!("symbolic factorisation of the tangent: {e:?}"))?;
        let factor = vec![0.0; symbolic.len_val()];
        Ok(Self {
            symbolic,
            factor,
            factored: false,
        })
    }

    /// Entries of the factor `L` (its fill-in included).
    pub fn factor_entries(&self) -> usize {
        self.factor.len()
    }

    /// Factorises the matrix with lower triangle `values` on `pattern`.
    pub fn factorise(
        &mut self,
        pattern: &Pattern,
        values: &[f64],
    ) -> Result<(), NotPositiveDefinite> {
        self.factored = false;
        let matrix = SparseColMatRef::new(pattern.symbolic.as_ref(), values);
        let scratch = self
            .symbolic
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        let mut buffer = MemBuffer::new(scratch);
        self.symbolic
            .factorize_numeric_llt(
                &mut self.factor,
                matrix,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut buffer),
                Default::default(),
            )
            .map_err(|_| NotPositiveDefinite)?;
        self.factored = true;
        Ok(())
    }

    /// Solves `K x = rhs` in place with the last factorisation.
    pub fn solve(&self, rhs: &mut [f64]) {
        assert!(self.factored, "solve before a successful factorisation");
        let n = rhs.len();
        let scratch = self.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq);
        let mut buffer = MemBuffer::new(scratch);
        LltRef::new(&self.symbolic, &self.factor).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            MemStack::new(&mut buffer),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of springs held at one end: `K` tridiagonal with 2 on the diagonal (1 at the
    /// free end) and -1 off it, whose solution for a unit load at the free end is `x_i = i + 1`.
    #[test]
    fn solves_a_spring_chain_and_refuses_an_indefinite_matrix() {
        let n = 50;
        let pairs: Vec<[usize; 2]> = (0..n - 1).map(|i| [i, i + 1]).collect();
        let pattern = Pattern::from_groups(n, pairs.iter().map(|p| &p[..]));
        let mut values = vec![0.0; pattern.entries()];
        for i in 0..n {
            values[pattern.place(i, i).unwrap()] = if i == n - 1 { 1.0 } else { 2.0 };
            if i + 1 < n {
                values[pattern.place(i + 1, i).unwrap()] = -1.0;
            }
        }
        assert_eq!(pattern.place(0, 2), None);
        let mut cholesky = Cholesky::analyse(&pattern).unwrap();
        cholesky.factorise(&pattern, &values).unwrap();
        let mut x = vec![0.0; n];
        x[n - 1] = 1.0;
        cholesky.solve(&mut x);
        for (i, xi) in x.iter().enumerate() {
            assert!((xi - (i + 1) as f64).abs() < 1e-9, "{i}: {xi}");
        }
        let back = pattern.multiply(&values, &x);
        assert!((back[n - 1] - 1.0).abs() < 1e-9 && back[0].abs() < 1e-9);
        values[pattern.place(n - 1, n - 1).unwrap()] = 0.5;
        assert_eq!(
            cholesky.factorise(&pattern, &values),
            Err(NotPositiveDefinite)
        );
    }
}
