//! The linear solve of a Newton iteration, `K d = -r`, for the symmetric positive definite
//! tangent `K` (docs/solver.md, "Implicit"): a sparse Cholesky factorisation (faer), whose
//! fill-reducing ordering and symbolic analysis are made once per sparsity pattern and reused
//! by every factorisation on it.
//!
//! The numeric factorisation of a supernodal structure is this crate's own (`supernodal.rs`):
//! faer's, in the same layout, but with independent subtrees of the elimination tree factorised
//! side by side; its splits are fixed by the structure, so its sums come in the same order on
//! any number of threads and results do not depend on the thread count. faer's simplicial
//! factorisation, for the small or very sparse matrices it chooses it for, runs on one thread.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use super::supernodal::{self, Supernodal};

/// The lower triangle of a symmetric sparsity pattern, compressed by columns, rows sorted,
/// stored in an elimination order chosen for it: the unknown `i` is row and column
/// `position(i)` of the stored matrix `P K P^T`, so that the factorisation takes the matrix as
/// stored, without permuting it first (that permutation was a third of each factorisation's
/// time on the hemisphere).
#[derive(Clone, Debug)]
pub struct Pattern {
    symbolic: SymbolicSparseColMat<usize>,
    /// Where each unknown is stored, and which unknown each place holds.
    position: Vec<usize>,
    unknown: Vec<usize>,
}

impl Pattern {
    /// The pattern of `n` unknowns in which every two unknowns of one group are coupled (and
    /// every unknown with itself), in their own order.
    pub fn from_groups<'a>(n: usize, groups: impl Iterator<Item = &'a [usize]>) -> Self {
        Self::from_groups_in_order(n, groups, (0..n).collect())
    }

    /// [`Self::from_groups`] stored in the elimination order `order` (`order[k]` the unknown
    /// eliminated `k`-th).
    pub fn from_groups_in_order<'a>(
        n: usize,
        groups: impl Iterator<Item = &'a [usize]>,
        order: Vec<usize>,
    ) -> Self {
        let mut position = vec![0; n];
        for (k, &i) in order.iter().enumerate() {
            position[i] = k;
        }
        let mut rows: Vec<Vec<usize>> = (0..n).map(|j| vec![j]).collect();
        for group in groups {
            for &i in group {
                for &j in group {
                    let (pi, pj) = (position[i], position[j]);
                    if pi > pj {
                        rows[pj].push(pi);
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
            position,
            unknown: order,
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

    /// Where unknown `i` is stored (its row and column in the stored matrix).
    pub fn position(&self, i: usize) -> usize {
        self.position[i]
    }

    /// Where the entry `(i, j)` of the symmetric matrix is stored; `None` outside the
    /// pattern.
    pub fn place(&self, i: usize, j: usize) -> Option<usize> {
        let (pi, pj) = (self.position[i], self.position[j]);
        let (row, column) = if pi >= pj { (pi, pj) } else { (pj, pi) };
        let start = self.symbolic.col_ptr()[column];
        let stored = &self.symbolic.row_idx()[start..self.symbolic.col_ptr()[column + 1]];
        stored.binary_search(&row).ok().map(|k| start + k)
    }

    /// The first stored place of the column before which half the stored entries lie: the
    /// values split there into two parts, each holding whole columns.
    pub fn halfway(&self) -> usize {
        let col_ptr = self.symbolic.col_ptr();
        let half = self.entries() / 2;
        col_ptr[col_ptr
            .partition_point(|&p| p < half)
            .min(col_ptr.len() - 1)]
    }

    /// `y = K x` for the symmetric matrix whose lower triangle is stored in `values`: the
    /// stored columns before [`Self::halfway`] on one thread and the others on another, each
    /// into a vector of its own, the two summed after; the same sums in the same order on any
    /// number of threads.
    pub fn multiply(&self, values: &[f64], x: &[f64]) -> Vec<f64> {
        let n = x.len();
        let split = self
            .symbolic
            .col_ptr()
            .partition_point(|&p| p < self.halfway())
            .min(n);
        let (mut low, high) = rayon::join(
            || self.multiply_columns(values, x, 0..split),
            || self.multiply_columns(values, x, split..n),
        );
        low.iter_mut().zip(&high).for_each(|(a, b)| *a += b);
        low
    }

    /// `K x` of the stored columns `columns` alone (their entries and their mirrors).
    fn multiply_columns(
        &self,
        values: &[f64],
        x: &[f64],
        columns: std::ops::Range<usize>,
    ) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        for pj in columns {
            let j = self.unknown[pj];
            for k in col_ptr[pj]..col_ptr[pj + 1] {
                let i = self.unknown[row_idx[k]];
                y[i] += values[k] * x[j];
                if i != j {
                    y[j] += values[k] * x[i];
                }
            }
        }
        y
    }

    /// The unknowns `(i, j)` of the entry at each stored place, in the places' order.
    pub fn stored_pairs(&self) -> Vec<(usize, usize)> {
        let (col_ptr, row_idx) = (self.symbolic.col_ptr(), self.symbolic.row_idx());
        let mut pairs = Vec::with_capacity(row_idx.len());
        for pj in 0..self.size() {
            for &pi in &row_idx[col_ptr[pj]..col_ptr[pj + 1]] {
                pairs.push((self.unknown[pi], self.unknown[pj]));
            }
        }
        pairs
    }

    /// Entries of the Cholesky factor of a matrix of this pattern, fill-in included.
    pub fn factor_entries(&self) -> Result<usize, String> {
        Ok(symbolic_factorisation(self, SupernodalThreshold::AUTO)?.len_val())
    }
}

/// The symbolic Cholesky factorisation of the stored matrix, in its stored order. faer reads
/// the upper triangle when it is given no ordering, so the structure is handed over
/// transposed; the numeric factorisation takes the lower triangle as stored. `supernodal`
/// says when the factorisation is supernodal (faer's choice by default).
fn symbolic_factorisation(
    pattern: &Pattern,
    supernodal: SupernodalThreshold,
) -> Result<SymbolicCholesky<usize>, String> {
    let n = pattern.size();
    let (col_ptr, row_idx) = (pattern.symbolic.col_ptr(), pattern.symbolic.row_idx());
    let mut upper: Vec<Vec<usize>> = vec![Vec::new(); n];
    for j in 0..n {
        for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
            upper[i].push(j);
        }
    }
    let mut upper_ptr = Vec::with_capacity(n + 1);
    upper_ptr.push(0);
    let mut upper_idx = Vec::with_capacity(row_idx.len());
    for column in upper {
        upper_idx.extend(column);
        upper_ptr.push(upper_idx.len());
    }
    let upper = SymbolicSparseColMat::new_checked(n, n, upper_ptr, None, upper_idx);
    factorize_symbolic_cholesky(
        upper.as_ref(),
        Side::Upper,
        SymmetricOrdering::Identity,
        CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: supernodal,
            ..Default::default()
        },
    )
    .map_err(|e| format!("symbolic factorisation of the tangent: {e:?}"))
}

/// Approximate minimum degree (faer) of a graph given by each vertex's neighbours: the
/// vertices in elimination order.
pub fn minimum_degree(neighbours: &[Vec<usize>]) -> Result<Vec<usize>, String> {
    let n = neighbours.len();
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0);
    for (j, around) in neighbours.iter().enumerate() {
        let mut column: Vec<usize> = around.iter().copied().filter(|&i| i < j).collect();
        column.push(j);
        column.sort_unstable();
        column.dedup();
        row_idx.extend(column);
        col_ptr.push(row_idx.len());
    }
    let upper = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    let (mut perm, mut perm_inv) = (vec![0usize; n], vec![0usize; n]);
    let mut buffer = MemBuffer::new(amd::order_scratch::<usize>(n, upper.row_idx().len()));
    amd::order(
        &mut perm,
        &mut perm_inv,
        upper.as_ref(),
        Default::default(),
        MemStack::new(&mut buffer),
    )
    .map_err(|e| format!("minimum-degree ordering of the tangent: {e:?}"))?;
    Ok(perm)
}

/// Geometric nested dissection of a sheet's nodes (George 1973): the nodes split at the median
/// of their longer extent, the nodes of one half that touch the other half set apart as the
/// separator and eliminated after both halves, each half dissected again down to small
/// leaves. Returns the nodes in elimination order.
pub fn nested_dissection(points: &[[f64; 3]], neighbours: &[Vec<usize>]) -> Vec<usize> {
    const LEAF: usize = 16;
    let n = points.len();
    let mut side = vec![u32::MAX; n];
    let mut order = Vec::with_capacity(n);
    let mut stack: Vec<(Vec<usize>, Vec<usize>)> = vec![((0..n).collect(), Vec::new())];
    // each entry: nodes to dissect, then separators to append once they are done; a task with
    // no nodes left only appends its separator
    let mut tag = 0u32;
    while let Some((nodes, separator)) = stack.pop() {
        if nodes.len() <= LEAF {
            order.extend(nodes);
            order.extend(separator);
            continue;
        }
        let extent = |d: usize| {
            let (lo, hi) = nodes
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(points[v][d]), hi.max(points[v][d]))
                });
            hi - lo
        };
        let axis = (0..3)
            .max_by(|&a, &b| extent(a).total_cmp(&extent(b)))
            .unwrap_or(0);
        let mut sorted = nodes;
        sorted.sort_by(|&a, &b| points[a][axis].total_cmp(&points[b][axis]).then(a.cmp(&b)));
        let half = sorted.len() / 2;
        tag += 1;
        let (left_tag, right_tag) = (2 * tag, 2 * tag + 1);
        for (k, &v) in sorted.iter().enumerate() {
            side[v] = if k < half { left_tag } else { right_tag };
        }
        let touches = |v: usize, other: u32| neighbours[v].iter().any(|&u| side[u] == other);
        let left_sep: Vec<usize> = sorted[..half]
            .iter()
            .copied()
            .filter(|&v| touches(v, right_tag))
            .collect();
        let right_sep: Vec<usize> = sorted[half..]
            .iter()
            .copied()
            .filter(|&v| touches(v, left_tag))
            .collect();
        let cut = if left_sep.len() <= right_sep.len() {
            left_sep
        } else {
            right_sep
        };
        for &v in &cut {
            side[v] = u32::MAX;
        }
        let left: Vec<usize> = sorted[..half]
            .iter()
            .copied()
            .filter(|&v| side[v] == left_tag)
            .collect();
        let right: Vec<usize> = sorted[half..]
            .iter()
            .copied()
            .filter(|&v| side[v] == right_tag)
            .collect();
        // the parent's separator after this one's, after both halves
        stack.push((Vec::new(), separator));
        stack.push((Vec::new(), cut));
        stack.push((right, Vec::new()));
        stack.push((left, Vec::new()));
    }
    order
}

/// The tangent is not positive definite: a pivot of the factorisation was not positive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NotPositiveDefinite;

/// A Cholesky factorisation `K = L L^T` on a fixed [`Pattern`], in its stored order.
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    factor: Vec<f64>,
    factored: bool,
    /// faer's workspace of the factorisation and the solve, kept: made anew at every
    /// factorisation it was a page-faulted allocation each time.
    scratch: MemBuffer,
    /// Where each unknown is stored (the pattern's order).
    position: Vec<usize>,
    /// The tree-parallel numeric factorisation, where faer chose a supernodal one; faer's
    /// simplicial factorisation (of small or very sparse matrices) otherwise.
    supernodal: Option<Supernodal>,
}

impl Cholesky {
    /// The symbolic factorisation of `pattern`.
    pub fn analyse(pattern: &Pattern) -> Result<Self, String> {
        Self::analyse_with(
            pattern,
            SupernodalThreshold::AUTO,
            supernodal::PARALLEL_FLOPS,
        )
    }

    /// [`Self::analyse`], supernodal as `supernodal` says, whose tasks under `parallel_flops`
    /// estimated flops run on one thread.
    fn analyse_with(
        pattern: &Pattern,
        supernodal: SupernodalThreshold,
        parallel_flops: f64,
    ) -> Result<Self, String> {
        let symbolic = symbolic_factorisation(pattern, supernodal)?;
        let supernodal = match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(structure) => Some(Supernodal::new(
                structure,
                pattern.symbolic.as_ref(),
                parallel_flops,
            )),
            SymbolicCholeskyRaw::Simplicial(_) => None,
        };
        let factor = vec![0.0; symbolic.len_val()];
        let scratch = MemBuffer::new(StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]));
        Ok(Self {
            symbolic,
            factor,
            factored: false,
            scratch,
            position: pattern.position.clone(),
            supernodal,
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
        if let Some(supernodal) = &self.supernodal {
            supernodal
                .factorise(&mut self.factor, values)
                .map_err(|_| NotPositiveDefinite)?;
            self.factored = true;
            return Ok(());
        }
        let matrix = SparseColMatRef::new(pattern.symbolic.as_ref(), values);
        self.symbolic
            .factorize_numeric_llt(
                &mut self.factor,
                matrix,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut self.scratch),
                Default::default(),
            )
            .map_err(|_| NotPositiveDefinite)?;
        self.factored = true;
        Ok(())
    }

    /// Solves `K x = rhs` in place with the last factorisation.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        assert!(self.factored, "solve before a successful factorisation");
        let n = rhs.len();
        let mut stored = vec![0.0; n];
        for (i, &p) in self.position.iter().enumerate() {
            stored[p] = rhs[i];
        }
        LltRef::new(&self.symbolic, &self.factor).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut stored, n, 1),
            Par::Seq,
            MemStack::new(&mut self.scratch),
        );
        for (i, &p) in self.position.iter().enumerate() {
            rhs[i] = stored[p];
        }
    }
}

/// A sparser pattern that a matrix's entries are moved onto (docs/solver.md, "Linear solve"):
/// an entry the sparser pattern holds is kept, a coupling `a_ij` it does not hold is dropped
/// and `|a_ij|` added to both diagonals `a_ii` and `a_jj`. What was added is
/// `|a| (e_i e_i^T + e_j e_j^T) - a (e_i e_j^T + e_j e_i^T)`, positive semi-definite, so the
/// sparser matrix is at least the full one: positive definite where that is, and its
/// factorisation a preconditioner whose `M^-1 K` has its eigenvalues in `(0, 1]`.
pub struct Sparsified {
    pub pattern: Pattern,
    /// Per stored place of the full pattern: its place in the sparser one, or the places of
    /// the two diagonals a dropped coupling goes to.
    places: Vec<Result<usize, (usize, usize)>>,
}

impl Sparsified {
    /// `full`'s entries onto `sparse`, which holds every diagonal entry.
    pub fn new(full: &Pattern, sparse: Pattern) -> Self {
        let diagonal = |i: usize| sparse.place(i, i).expect("a diagonal entry");
        let places = full
            .stored_pairs()
            .into_iter()
            .map(|(i, j)| sparse.place(i, j).ok_or_else(|| (diagonal(i), diagonal(j))))
            .collect();
        Self {
            pattern: sparse,
            places,
        }
    }

    /// The sparser matrix's values (its lower triangle) from the full one's, `values`.
    pub fn values(&self, values: &[f64], into: &mut Vec<f64>) {
        into.clear();
        into.resize(self.pattern.entries(), 0.0);
        for (v, place) in values.iter().zip(&self.places) {
            match *place {
                Ok(p) => into[p] += v,
                Err((a, b)) => {
                    into[a] += v.abs();
                    into[b] += v.abs();
                }
            }
        }
    }
}

/// Why conjugate gradients gave no solution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NotSolved {
    /// `p^T K p <= 0` along a search direction: `K` is not positive definite.
    NotPositiveDefinite,
    /// The residual was not within the tolerance after the iterations allowed.
    Slow,
}

impl Cholesky {
    /// Solves `K x = rhs`, `K` the matrix with lower triangle `values` on `pattern`, by
    /// conjugate gradients preconditioned with this factorisation (of an approximation of
    /// `K`, e.g. a [`Sparsified`] one), from `x = 0` until `|K x - rhs| <= tolerance |rhs|`,
    /// within `max_iterations`: the solution and the iterations it took, or why not and after
    /// how many. Every sum runs in a fixed order: the same bits on any number of threads.
    pub fn conjugate_gradients(
        &mut self,
        pattern: &Pattern,
        values: &[f64],
        rhs: &[f64],
        tolerance: f64,
        max_iterations: usize,
    ) -> Result<(Vec<f64>, usize), (NotSolved, usize)> {
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
        let target = tolerance * dot(rhs, rhs).sqrt();
        let mut x = vec![0.0; rhs.len()];
        let mut r = rhs.to_vec();
        let mut z = r.clone();
        self.solve(&mut z);
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        for iteration in 1..=max_iterations {
            let q = pattern.multiply(values, &p);
            let curvature = dot(&p, &q);
            if curvature <= 0.0 || !curvature.is_finite() {
                return Err((NotSolved::NotPositiveDefinite, iteration));
            }
            let alpha = rz / curvature;
            x.iter_mut().zip(&p).for_each(|(x, p)| *x += alpha * p);
            r.iter_mut().zip(&q).for_each(|(r, q)| *r -= alpha * q);
            if dot(&r, &r).sqrt() <= target {
                return Ok((x, iteration));
            }
            z.copy_from_slice(&r);
            self.solve(&mut z);
            let next = dot(&r, &z);
            let beta = next / rz;
            rz = next;
            p.iter_mut().zip(&z).for_each(|(p, z)| *p = z + beta * *p);
        }
        Err((NotSolved::Slow, max_iterations))
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
        // the same chain through the supernodal factorisation, one supernode a task
        let mut forced =
            Cholesky::analyse_with(&pattern, SupernodalThreshold::FORCE_SUPERNODAL, 0.0).unwrap();
        assert!(forced.supernodal.is_some());
        forced.factorise(&pattern, &values).unwrap();
        let reference = faer_factor(&mut forced, &pattern, &values);
        assert_close(&forced, &forced.factor, &reference);
        let mut y = vec![0.0; n];
        y[n - 1] = 1.0;
        forced.solve(&mut y);
        assert!(y.iter().zip(&x).all(|(a, b)| (a - b).abs() < 1e-9));
        values[pattern.place(n - 1, n - 1).unwrap()] = 0.5;
        assert_eq!(
            cholesky.factorise(&pattern, &values),
            Err(NotPositiveDefinite)
        );
        assert_eq!(
            forced.factorise(&pattern, &values),
            Err(NotPositiveDefinite)
        );
    }

    /// faer's own supernodal factorisation of `values` on `cholesky`'s structure.
    fn faer_factor(cholesky: &mut Cholesky, pattern: &Pattern, values: &[f64]) -> Vec<f64> {
        let mut factor = vec![0.0; cholesky.factor.len()];
        cholesky
            .symbolic
            .factorize_numeric_llt(
                &mut factor,
                SparseColMatRef::new(pattern.symbolic.as_ref(), values),
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut cholesky.scratch),
                Default::default(),
            )
            .unwrap();
        factor
    }

    /// The factor `a` equals `b` to 1e-12 of `b`'s largest entry (their lower triangles).
    fn assert_close(cholesky: &Cholesky, a: &[f64], b: &[f64]) {
        let lower = |f| cholesky.supernodal.as_ref().unwrap().lower(f);
        let (a, b) = (&lower(a), &lower(b));
        let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let error = a
            .iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert_eq!(a.len(), b.len());
        assert!(error <= 1e-12 * scale, "{error:e} of {scale:e}");
    }

    /// The out-of-plane stiffness of a `side` x `side` plate of unit cells, one unknown (the
    /// deflection) per node: a tension `t` between the nodes of each cell, the bending of a
    /// patch of 3 x 3 nodes around each inner node (its second differences along both axes
    /// and its twist, `B = 1`), and a ground spring `g` per node. The cells' pattern and the
    /// full one (with the patches), the full matrix's values, in their natural order.
    fn plate(side: usize, t: f64, g: f64) -> (Pattern, Pattern, Vec<f64>) {
        let node = |i: usize, j: usize| i * side + j;
        let cells: Vec<Vec<usize>> = (0..side - 1)
            .flat_map(|i| {
                (0..side - 1).map(move |j| {
                    vec![
                        node(i, j),
                        node(i + 1, j),
                        node(i, j + 1),
                        node(i + 1, j + 1),
                    ]
                })
            })
            .collect();
        let patches: Vec<Vec<usize>> = (1..side - 1)
            .flat_map(|i| {
                (1..side - 1)
                    .map(move |j| (0..9).map(|k| node(i + k / 3 - 1, j + k % 3 - 1)).collect())
            })
            .collect();
        let n = side * side;
        let narrow = Pattern::from_groups(n, cells.iter().map(|c| &c[..]));
        let full = Pattern::from_groups(n, cells.iter().chain(&patches).map(|c| &c[..]));
        let mut values = vec![0.0; full.entries()];
        let mut add = |nodes: &[usize], c: &[f64], scale: f64| {
            for (a, ca) in nodes.iter().zip(c) {
                for (b, cb) in nodes.iter().zip(c) {
                    if a >= b {
                        values[full.place(*a, *b).unwrap()] += scale * ca * cb;
                    }
                }
            }
        };
        for cell in &cells {
            for (a, b) in [(0, 1), (0, 2), (1, 3), (2, 3)] {
                add(&[cell[a], cell[b]], &[1.0, -1.0], t);
            }
        }
        for patch in &patches {
            // the 3 x 3 patch, row by row: w_xx, w_yy and the twist
            add(&[patch[3], patch[4], patch[5]], &[1.0, -2.0, 1.0], 1.0);
            add(&[patch[1], patch[4], patch[7]], &[1.0, -2.0, 1.0], 1.0);
            add(
                &[patch[0], patch[2], patch[6], patch[8]],
                &[0.5, -0.5, -0.5, 0.5],
                2.0,
            );
        }
        for a in 0..n {
            add(&[a], &[1.0], g);
        }
        (narrow, full, values)
    }

    /// The plate's matrix moved onto the cells' stencil keeps every entry that stencil holds
    /// and lies above the full matrix (`x^T (K_s - K) x >= 0`, here for the deflections of
    /// single nodes, of pairs and of random fields), so that it factorises.
    #[test]
    fn a_sparsified_plate_keeps_its_stencil_and_lies_above_the_full_one() {
        let (narrow, full, values) = plate(7, 0.01, 1e-3);
        let sparsified = Sparsified::new(&full, narrow.clone());
        let mut sparse = Vec::new();
        sparsified.values(&values, &mut sparse);
        let n = full.size();
        for i in 0..n {
            for j in 0..=i {
                if let (Some(p), Some(q)) = (narrow.place(i, j), full.place(i, j)) {
                    if i != j {
                        assert_eq!(sparse[p], values[q], "({i}, {j})");
                    }
                }
            }
        }
        let mut state = 7u64;
        let mut random = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
        let mut fields: Vec<Vec<f64>> = (0..20)
            .map(|_| (0..n).map(|_| random()).collect())
            .collect();
        fields.push((0..n).map(|k| if k == 24 { 1.0 } else { 0.0 }).collect());
        fields.push((0..n).map(|k| [8, 10].contains(&k) as u8 as f64).collect());
        for x in &fields {
            let above = dot(x, &narrow.multiply(&sparse, x)) - dot(x, &full.multiply(&values, x));
            assert!(above >= -1e-12 * dot(x, x), "{above:e}");
        }
        let mut cholesky = Cholesky::analyse(&narrow).unwrap();
        cholesky.factorise(&narrow, &sparse).unwrap();
    }

    /// Conjugate gradients on the full plate, preconditioned with the factorisation on the
    /// cells' stencil, reach the direct solution; with the factorisation of the full matrix
    /// itself, in one iteration; and they stop where the matrix is not positive definite.
    #[test]
    fn conjugate_gradients_preconditioned_on_the_narrow_stencil_solve_the_plate() {
        let (narrow, full, values) = plate(12, 0.01, 1e-3);
        let n = full.size();
        let load: Vec<f64> = (0..n).map(|k| ((k * 7) % 5) as f64 - 2.0).collect();
        let mut direct = Cholesky::analyse(&full).unwrap();
        direct.factorise(&full, &values).unwrap();
        let mut exact = load.clone();
        direct.solve(&mut exact);
        let sparsified = Sparsified::new(&full, narrow);
        let mut sparse = Vec::new();
        sparsified.values(&values, &mut sparse);
        let mut preconditioner = Cholesky::analyse(&sparsified.pattern).unwrap();
        preconditioner
            .factorise(&sparsified.pattern, &sparse)
            .unwrap();
        let (x, iterations) = preconditioner
            .conjugate_gradients(&full, &values, &load, 1e-12, n)
            .unwrap();
        let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let error = x
            .iter()
            .zip(&exact)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(error <= 1e-9 * scale, "{error:e} of {scale:e}");
        // the preconditioner misses the bending's farther couplings: more than one iteration,
        // far fewer than the unknowns
        assert!(iterations > 1 && iterations < n / 2, "{iterations} of {n}");
        let (y, once) = direct
            .conjugate_gradients(&full, &values, &load, 1e-10, n)
            .unwrap();
        assert_eq!(once, 1);
        assert!(y
            .iter()
            .zip(&exact)
            .all(|(a, b)| (a - b).abs() <= 1e-9 * scale));
        // a negative stiffness where the load pushes: the first search direction finds it
        let mut indefinite = values.clone();
        let centre = full.place(66, 66).unwrap();
        indefinite[centre] -= 1e3;
        let point: Vec<f64> = (0..n).map(|k| (k == 66) as u8 as f64).collect();
        let stopped = direct.conjugate_gradients(&full, &indefinite, &point, 1e-10, n);
        assert_eq!(
            stopped.map(|_| ()),
            Err((NotSolved::NotPositiveDefinite, 1))
        );
    }

    /// A `side` x `side` grid whose nodes are coupled within two steps (the patches of 3 x 3
    /// nodes of quadratic elements), in nested dissection order, with random couplings and a
    /// dominant diagonal: symmetric positive definite. Its lower triangle as stored.
    fn grid(side: usize, seed: u64) -> (Pattern, Vec<f64>) {
        let node = |i: usize, j: usize| i * side + j;
        let mut patches = Vec::new();
        for i in 0..side - 2 {
            for j in 0..side - 2 {
                patches.push(
                    (0..9)
                        .map(|k| node(i + k / 3, j + k % 3))
                        .collect::<Vec<_>>(),
                );
            }
        }
        let points: Vec<[f64; 3]> = (0..side * side)
            .map(|k| [(k / side) as f64, (k % side) as f64, 0.0])
            .collect();
        let mut neighbours = vec![Vec::new(); side * side];
        for patch in &patches {
            for &a in patch {
                neighbours[a].extend(patch.iter().copied().filter(|&b| b != a));
            }
        }
        let order = nested_dissection(&points, &neighbours);
        let pattern =
            Pattern::from_groups_in_order(side * side, patches.iter().map(|p| &p[..]), order);
        let mut state = seed;
        let mut random = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut values = vec![0.0; pattern.entries()];
        let mut diagonal = vec![1.0; side * side];
        for a in 0..side * side {
            for &b in &neighbours[a] {
                if a < b && values[pattern.place(a, b).unwrap()] == 0.0 {
                    let v = random();
                    values[pattern.place(a, b).unwrap()] = v;
                    diagonal[a] += v.abs();
                    diagonal[b] += v.abs();
                }
            }
        }
        for (a, d) in diagonal.iter().enumerate() {
            values[pattern.place(a, a).unwrap()] = *d;
        }
        (pattern, values)
    }

    /// The product with the symmetric matrix, its stored halves on two threads, is the dense
    /// product's to rounding, and the same bits on one thread and on two.
    #[test]
    fn the_product_with_the_matrix_is_the_dense_one_on_any_number_of_threads() {
        let (pattern, values) = grid(20, 5);
        let n = pattern.size();
        let x: Vec<f64> = (0..n).map(|k| ((k * 13) % 7) as f64 - 3.0).collect();
        let mut dense = vec![0.0; n];
        for ((i, j), v) in pattern.stored_pairs().into_iter().zip(&values) {
            dense[i] += v * x[j];
            if i != j {
                dense[j] += v * x[i];
            }
        }
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| pattern.multiply(&values, &x))
        };
        let (one, two) = (on(1), on(2));
        assert_eq!(one, two);
        let scale = dense.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(one
            .iter()
            .zip(&dense)
            .all(|(a, b)| (a - b).abs() <= 1e-12 * scale));
    }

    /// The tree-parallel factor equals faer's, is the same to the bit on one thread and on
    /// two, whatever the plan, and an indefinite matrix is refused.
    #[test]
    fn factorises_as_faer_does_and_alike_on_any_number_of_threads() {
        let (pattern, mut values) = grid(48, 7);
        let on = |threads: usize, cholesky: &mut Cholesky, values: &[f64]| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    cholesky
                        .factorise(&pattern, values)
                        .map(|_| cholesky.factor.clone())
                })
        };
        // every subtree over 20 kflop a task of its own; then the default plan
        for parallel_flops in [2e4, supernodal::PARALLEL_FLOPS] {
            let mut cholesky = Cholesky::analyse_with(
                &pattern,
                SupernodalThreshold::FORCE_SUPERNODAL,
                parallel_flops,
            )
            .unwrap();
            let text = cholesky.supernodal.as_ref().unwrap().plan();
            assert!(text.contains("Fork") && text.contains("Some("), "{text}");
            let one = on(1, &mut cholesky, &values).unwrap();
            let two = on(2, &mut cholesky, &values).unwrap();
            let bits = |f: &[f64]| f.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&one), bits(&two));
            let reference = faer_factor(&mut cholesky, &pattern, &values);
            assert_close(&cholesky, &one, &reference);
            let mut x: Vec<f64> = (0..pattern.size()).map(|i| (i % 7) as f64 - 3.0).collect();
            let rhs = pattern.multiply(&values, &x);
            let mut solved = rhs.clone();
            cholesky.solve(&mut solved);
            for (a, b) in solved.iter().zip(&mut x) {
                assert!((a - *b).abs() < 1e-9, "{a} {b}");
            }
            // a negative pivot deep in the tree (the first unknown eliminated) and at its
            // root (the last)
            for place in [0, pattern.size() - 1] {
                let unknown = pattern.unknown[place];
                let at = pattern.place(unknown, unknown).unwrap();
                let kept = values[at];
                values[at] = -1.0;
                for threads in [1, 2] {
                    assert_eq!(
                        on(threads, &mut cholesky, &values),
                        Err(NotPositiveDefinite)
                    );
                }
                values[at] = kept;
            }
        }
    }
}
