//! The numeric supernodal Cholesky factorisation `K = L L^T` of the implicit solver's tangent
//! (docs/solver.md, "Implicit"), parallel over the elimination tree.
//!
//! faer's supernodal factorisation is left-looking and runs its supernodes one after the
//! other; it only parallelises inside the dense kernels, which on the hemisphere's tangents
//! are too small for that to pay (two threads were slower than one). This one follows the
//! same algorithm on faer's symbolic structure and writes the factor in faer's layout, so that
//! faer's solve takes it as it is, but it factorises independent subtrees of the elimination
//! tree side by side (`rayon::join`), sums the many descendant updates of a big supernode
//! near the root in two groups at once, and factorises the dense block of such a supernode in
//! panels whose updates and triangular solves are split in two. (On the hemisphere's 2.26 mm
//! mesh the root supernode alone, 973 columns, took a third of the flops: its updates from
//! the rest of the tree.)
//!
//! The tree is walked in a postorder of its supernodes, in which each subtree is a range that
//! its task borrows whole; faer's numbering of the supernodes need not be one.
//!
//! Every split is fixed by the structure (the estimated flops of a subtree, never the number
//! of threads), and every sum is made in a fixed order: a task gives the same bits whichever
//! thread runs it, so the factor is the same on any number of threads.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::sparse::SymbolicSparseColMatRef;
use faer::{Accum, MatMut, MatRef, Par};
use std::ops::Range;
use std::sync::Mutex;

/// Estimated flops of a task below which it runs on one thread: a `rayon::join` costs some
/// microseconds, a few hundred kiloflops' worth.
pub(super) const PARALLEL_FLOPS: f64 = 4e6;

/// A pivot of the factorisation was not positive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct NonPositivePivot;

/// The update of supernode `s` by one of its descendants `d`: `L_s -= L_d[rows >= s] L_d[rows
/// in s]^T`, the rows of `L_d` from the `start`-th of its pattern on, the first `mid` of them
/// in `s`'s columns.
#[derive(Clone, Copy, Debug)]
struct Update {
    d: usize,
    start: usize,
    mid: usize,
    /// Where the rows of `L_d` from `start` on lie in `L_s`'s block: `relative[at..]`.
    at: usize,
    /// The runs of those rows that lie next to each other in `L_s`'s block too:
    /// `runs[runs_at..runs_end]`.
    runs_at: usize,
    runs_end: usize,
}

/// Rows of an update, from its `first` on, that go to `length` consecutive rows of its
/// supernode's block: subtracted as one slice, which the compiler vectorises.
#[derive(Clone, Copy, Debug)]
struct Run {
    first: usize,
    length: usize,
}

/// How a range of supernodes, places in the postorder of the tree, is factorised, fixed at
/// analysis.
#[derive(Debug)]
enum Task {
    /// The supernodes one after the other, on one thread.
    Sequence(Range<usize>),
    /// Two independent forests, the supernodes before `mid` and those from `mid` on, side by
    /// side.
    Fork(Box<Task>, Box<Task>, usize),
    /// The forest of the descendants of the supernode at place `at` (when it has any), then
    /// that supernode, whose updates are summed in two groups side by side, those before
    /// `split` into a zeroed buffer, the others into its block, where `split` is given.
    Node {
        forest: Option<Box<Task>>,
        at: usize,
        split: Option<usize>,
    },
}

/// A task's scratch: the dense product of an update, faer's workspace of the dense Cholesky.
struct Workspace {
    product: Vec<f64>,
    stack: MemBuffer,
}

/// faer's supernodal structure, the descendant updates of each supernode with where their
/// rows go, and the parallel plan.
pub(super) struct Supernodal {
    /// Supernode `s` holds the columns `begin[s]..begin[s + 1]`, its block of `L` (its
    /// columns, then the rows of its pattern below them, column-major) the values
    /// `values[s]..values[s + 1]` of the factor.
    begin: Vec<usize>,
    values: Vec<usize>,
    /// Rows of each supernode's block.
    rows: Vec<usize>,
    /// The updates of supernode `s`, their descendants in increasing order:
    /// `updates[update_ptr[s]..update_ptr[s + 1]]`.
    update_ptr: Vec<usize>,
    updates: Vec<Update>,
    /// The rows of each update's block in its supernode's block (see [`Update::at`]).
    relative: Vec<usize>,
    runs: Vec<Run>,
    /// Where each stored entry of the matrix lies in its supernode's block.
    scatter: Vec<usize>,
    /// The stored entries of supernode `s`'s columns: `matrix_ptr[s]..matrix_ptr[s + 1]`.
    matrix_ptr: Vec<usize>,
    /// The supernodes in a postorder of the elimination tree, and the place of each in it.
    postorder: Vec<usize>,
    place: Vec<usize>,
    plan: Task,
    /// Estimated flops of a task below which it runs on one thread.
    parallel_flops: f64,
    /// faer's workspace of the dense Cholesky of any supernode.
    scratch: StackReq,
    /// Workspaces and update buffers, kept from one factorisation to the next rather than
    /// allocated anew each time (the root's buffer alone is 7 MB on the 2.26 mm mesh).
    workspaces: Mutex<Vec<Workspace>>,
    buffers: Mutex<Vec<Vec<f64>>>,
}

impl Supernodal {
    /// The updates and plan of the factorisation of matrices with lower triangle `matrix` (its
    /// structure, in the factor's order) over faer's supernodal structure `symbolic`; tasks
    /// under `parallel_flops` estimated flops run on one thread.
    pub(super) fn new(
        symbolic: &SymbolicSupernodalCholesky<usize>,
        matrix: SymbolicSparseColMatRef<'_, usize>,
        parallel_flops: f64,
    ) -> Self {
        let count = symbolic.n_supernodes();
        let n = symbolic.nrows();
        let mut begin = symbolic.supernode_begin().to_vec();
        begin.push(*symbolic.supernode_end().last().unwrap_or(&0));
        let values = symbolic.col_ptr_for_val().to_vec();
        let pattern = |s: usize| symbolic.supernode(s).pattern();
        let columns = |s: usize| begin[s + 1] - begin[s];
        let rows: Vec<usize> = (0..count).map(|s| columns(s) + pattern(s).len()).collect();
        let mut owner = vec![0; n];
        for s in 0..count {
            owner[begin[s]..begin[s + 1]].fill(s);
        }

        // each descendant's updates, by the supernode its pattern rows fall in
        let mut of: Vec<Vec<Update>> = vec![Vec::new(); count];
        let mut parent = vec![usize::MAX; count];
        for (d, up) in parent.iter_mut().enumerate() {
            let rows_d = pattern(d);
            *up = rows_d.first().map_or(usize::MAX, |&i| owner[i]);
            let mut start = 0;
            while start < rows_d.len() {
                let s = owner[rows_d[start]];
                let mid = rows_d[start..].partition_point(|&i| i < begin[s + 1]);
                of[s].push(Update {
                    d,
                    start,
                    mid,
                    at: 0,
                    runs_at: 0,
                    runs_end: 0,
                });
                start += mid;
            }
        }
        let mut local = vec![usize::MAX; n];
        let (mut update_ptr, mut updates, mut relative) = (vec![0], Vec::new(), Vec::new());
        let mut runs = Vec::new();
        let (mut scatter, mut matrix_ptr) = (vec![0; matrix.row_idx().len()], vec![]);
        let (col_ptr, row_idx) = (matrix.col_ptr(), matrix.row_idx());
        for s in 0..count {
            for (k, i) in (begin[s]..begin[s + 1])
                .chain(pattern(s).iter().copied())
                .enumerate()
            {
                local[i] = k;
            }
            for mut update in of[s].drain(..) {
                update.at = relative.len();
                relative.extend(pattern(update.d)[update.start..].iter().map(|&i| {
                    assert!(local[i] != usize::MAX, "an update outside its supernode");
                    local[i]
                }));
                update.runs_at = runs.len();
                runs.extend(consecutive_runs(&relative[update.at..]));
                update.runs_end = runs.len();
                updates.push(update);
            }
            update_ptr.push(updates.len());
            matrix_ptr.push(col_ptr[begin[s]]);
            for j in begin[s]..begin[s + 1] {
                for k in col_ptr[j]..col_ptr[j + 1] {
                    scatter[k] = (j - begin[s]) * rows[s] + local[row_idx[k]];
                }
            }
            for i in (begin[s]..begin[s + 1]).chain(pattern(s).iter().copied()) {
                local[i] = usize::MAX;
            }
        }
        matrix_ptr.push(col_ptr[n]);

        let mut factorisation = Self {
            begin,
            values,
            rows,
            update_ptr,
            updates,
            relative,
            runs,
            scatter,
            matrix_ptr,
            postorder: postorder(&parent),
            place: vec![0; count],
            plan: Task::Sequence(0..count),
            parallel_flops,
            scratch: StackReq::EMPTY,
            workspaces: Mutex::new(Vec::new()),
            buffers: Mutex::new(Vec::new()),
        };
        factorisation.scratch = StackReq::any_of(
            &(0..count)
                .map(|s| {
                    cholesky_in_place_scratch::<f64>(
                        factorisation.columns(s),
                        Par::Seq,
                        Default::default(),
                    )
                })
                .collect::<Vec<_>>(),
        );
        for (k, &s) in factorisation.postorder.iter().enumerate() {
            factorisation.place[s] = k;
        }
        factorisation.plan = Planner::new(&factorisation, &parent, parallel_flops).forest(0, count);
        factorisation
    }

    /// `factor` with the strict upper triangles of its diagonal blocks zero: what faer's
    /// dense Cholesky leaves there (and the solve never reads) depends on how it was blocked.
    #[cfg(test)]
    pub(super) fn lower(&self, factor: &[f64]) -> Vec<f64> {
        let mut lower = factor.to_vec();
        for s in 0..self.rows.len() {
            for j in 0..self.columns(s) {
                let column = self.values[s] + j * self.rows[s];
                lower[column..column + j].fill(0.0);
            }
        }
        lower
    }

    /// The parallel plan, written out.
    #[cfg(test)]
    pub(super) fn plan(&self) -> String {
        format!("{:?}", self.plan)
    }

    fn columns(&self, s: usize) -> usize {
        self.begin[s + 1] - self.begin[s]
    }

    fn update_flops(&self, update: &Update) -> f64 {
        let below = (self.rows[update.d] - self.columns(update.d) - update.start) as f64;
        let mid = update.mid as f64;
        (mid * (mid + 1.0) + 2.0 * (below - mid) * mid) * self.columns(update.d) as f64
    }

    fn own_flops(&self, s: usize) -> f64 {
        let (c, r) = (self.columns(s) as f64, self.rows[s] as f64);
        c * c * c / 3.0 + c * c * (r - c)
    }

    /// Factorises into `factor` (faer's layout of `L`) the matrix whose stored lower triangle
    /// has the values `matrix`.
    pub(super) fn factorise(
        &self,
        factor: &mut [f64],
        matrix: &[f64],
    ) -> Result<(), NonPositivePivot> {
        // each supernode's block, in the postorder: there a subtree's blocks are a range, which
        // its task borrows whole
        let mut natural: Vec<Option<&mut [f64]>> = Vec::with_capacity(self.rows.len());
        let mut rest = factor;
        for s in 0..self.rows.len() {
            let (block, after) = rest.split_at_mut(self.values[s + 1] - self.values[s]);
            natural.push(Some(block));
            rest = after;
        }
        let mut blocks: Vec<&mut [f64]> = self
            .postorder
            .iter()
            .map(|&s| natural[s].take().expect("a postorder"))
            .collect();
        self.run(&self.plan, &mut blocks, 0, matrix)
    }

    /// Runs `task` on `blocks`, the blocks of the supernodes at the places `base..` of the
    /// postorder.
    fn run(
        &self,
        task: &Task,
        blocks: &mut [&mut [f64]],
        base: usize,
        matrix: &[f64],
    ) -> Result<(), NonPositivePivot> {
        match task {
            Task::Sequence(range) => {
                let mut workspace = self.workspace();
                let mut result = Ok(());
                for k in range.clone() {
                    let s = self.postorder[k];
                    let (below, block) = blocks.split_at_mut(k - base);
                    let block = &mut *block[0];
                    self.assemble(s, block, matrix);
                    let updates = self.update_ptr[s]..self.update_ptr[s + 1];
                    self.accumulate(s, updates, below, base, block, &mut workspace.product);
                    result = self.finish(s, block, &mut workspace, false);
                    if result.is_err() {
                        break;
                    }
                }
                self.workspaces.lock().unwrap().push(workspace);
                result
            }
            Task::Fork(first, second, mid) => {
                let (one, two) = blocks.split_at_mut(mid - base);
                let (a, b) = rayon::join(
                    || self.run(first, one, base, matrix),
                    || self.run(second, two, *mid, matrix),
                );
                a.and(b)
            }
            Task::Node { forest, at, split } => {
                let s = self.postorder[*at];
                let (below, block) = blocks.split_at_mut(at - base);
                let block = &mut *block[0];
                if let Some(forest) = forest {
                    self.run(forest, below, base, matrix)?;
                }
                let below = &*below;
                let updates = self.update_ptr[s]..self.update_ptr[s + 1];
                self.assemble(s, block, matrix);
                match split {
                    None => {
                        let mut workspace = self.workspace();
                        self.accumulate(s, updates, below, base, block, &mut workspace.product);
                        self.workspaces.lock().unwrap().push(workspace);
                    }
                    Some(split) => {
                        // the first group summed apart, then added: the same sums in the same
                        // order whether the two groups run on one thread or two
                        let mut buffer = self.buffers.lock().unwrap().pop().unwrap_or_default();
                        buffer.clear();
                        buffer.resize(block.len(), 0.0);
                        let group = |updates: Range<usize>, block: &mut [f64]| {
                            let mut workspace = self.workspace();
                            self.accumulate(s, updates, below, base, block, &mut workspace.product);
                            self.workspaces.lock().unwrap().push(workspace);
                        };
                        rayon::join(
                            || group(updates.start..*split, &mut buffer),
                            || group(*split..updates.end, &mut *block),
                        );
                        for (x, y) in block.iter_mut().zip(&buffer) {
                            *x += y;
                        }
                        self.buffers.lock().unwrap().push(buffer);
                    }
                }
                let mut workspace = self.workspace();
                let split = self.own_flops(s) >= self.parallel_flops;
                let result = self.finish(s, block, &mut workspace, split);
                self.workspaces.lock().unwrap().push(workspace);
                result
            }
        }
    }

    fn workspace(&self) -> Workspace {
        self.workspaces
            .lock()
            .unwrap()
            .pop()
            .unwrap_or_else(|| Workspace {
                product: Vec::new(),
                stack: MemBuffer::new(self.scratch),
            })
    }

    /// `L_s`'s block set to the matrix's entries in its columns, zero elsewhere.
    fn assemble(&self, s: usize, block: &mut [f64], matrix: &[f64]) {
        block.fill(0.0);
        let entries = self.matrix_ptr[s]..self.matrix_ptr[s + 1];
        for (&at, &value) in self.scatter[entries.clone()].iter().zip(&matrix[entries]) {
            block[at] += value;
        }
    }

    /// `block -= L_d[rows >= s] L_d[rows in s]^T` for the updates `updates` of `s`, in
    /// their order, the blocks of the supernodes at the places `base..` of the postorder in
    /// `below`. Each product
    /// is made dense in `product`, its lower part only, and subtracted where its rows go.
    fn accumulate(
        &self,
        s: usize,
        updates: Range<usize>,
        below: &[&mut [f64]],
        base: usize,
        block: &mut [f64],
        product: &mut Vec<f64>,
    ) {
        let rows_s = self.rows[s];
        for update in &self.updates[updates] {
            let d = update.d;
            let (columns_d, rows_d) = (self.columns(d), self.rows[d]);
            let l_d =
                MatRef::from_column_major_slice(&*below[self.place[d] - base], rows_d, columns_d);
            let from = l_d.subrows(columns_d + update.start, rows_d - columns_d - update.start);
            let (mid, count) = (update.mid, from.nrows());
            let in_s = from.subrows(0, mid);
            // every entry read below is written by the products: no zeroing
            if product.len() < count * mid {
                product.resize(count * mid, 0.0);
            }
            let product = &mut product[..count * mid];
            let mut w = MatMut::from_column_major_slice_mut(product, count, mid);
            let (w_top, w_bottom) = w.rb_mut().split_at_row_mut(mid);
            triangular::matmul(
                w_top,
                BlockStructure::TriangularLower,
                Accum::Replace,
                in_s,
                BlockStructure::Rectangular,
                in_s.transpose(),
                BlockStructure::Rectangular,
                1.0,
                Par::Seq,
            );
            matmul(
                w_bottom,
                Accum::Replace,
                from.subrows(mid, count - mid),
                in_s.transpose(),
                1.0,
                Par::Seq,
            );
            let relative = &self.relative[update.at..update.at + count];
            let runs = &self.runs[update.runs_at..update.runs_end];
            for (c, &column) in relative[..mid].iter().enumerate() {
                let target = &mut block[column * rows_s..(column + 1) * rows_s];
                let source = &product[c * count..(c + 1) * count];
                for run in runs {
                    let end = run.first + run.length;
                    if end <= c {
                        continue;
                    }
                    let first = run.first.max(c);
                    let at = relative[first];
                    let target = &mut target[at..at + end - first];
                    for (t, s) in target.iter_mut().zip(&source[first..end]) {
                        *t -= s;
                    }
                }
            }
        }
    }

    /// The dense Cholesky factorisation of `L_s`'s diagonal block, then the triangular solve
    /// of the rows below it; in halves side by side where `split` (a big supernode near the
    /// root, which runs alone).
    fn finish(
        &self,
        s: usize,
        block: &mut [f64],
        workspace: &mut Workspace,
        split: bool,
    ) -> Result<(), NonPositivePivot> {
        let columns = self.columns(s);
        let l_s = MatMut::from_column_major_slice_mut(block, self.rows[s], columns);
        let (mut top, bottom) = l_s.split_at_row_mut(columns);
        dense_cholesky(top.rb_mut(), MemStack::new(&mut workspace.stack), split)?;
        solve_below(top.rb(), bottom, split);
        Ok(())
    }
}

/// The runs of consecutive values in `relative`, by their first index and length.
fn consecutive_runs(relative: &[usize]) -> Vec<Run> {
    let mut runs: Vec<Run> = Vec::new();
    for (r, &at) in relative.iter().enumerate() {
        match runs.last_mut() {
            Some(run) if relative[run.first] + run.length == at => run.length += 1,
            _ => runs.push(Run {
                first: r,
                length: 1,
            }),
        }
    }
    runs
}

/// Columns of a panel of the blocked dense Cholesky factorisation of a big diagonal block
/// (small in the tests, whose matrices are small, so that they go through it).
const PANEL: usize = if cfg!(test) { 8 } else { 128 };

/// `a = L L^T` in place (its lower triangle), in panels of [`PANEL`] columns whose trailing
/// updates and triangular solves run in two halves side by side where `split`; with faer's
/// dense kernel otherwise. The halves are fixed by the size, so the sums are the same
/// whichever threads run them.
fn dense_cholesky(
    mut a: MatMut<'_, f64>,
    stack: &mut MemStack,
    split: bool,
) -> Result<(), NonPositivePivot> {
    let n = a.nrows();
    if !split || n <= 2 * PANEL {
        return cholesky_in_place(a, Default::default(), Par::Seq, stack, Default::default())
            .map(|_| ())
            .map_err(|_| NonPositivePivot);
    }
    let mut k = 0;
    while k < n {
        let width = PANEL.min(n - k);
        let rest = a.rb_mut().submatrix_mut(k, k, n - k, n - k);
        let (mut diagonal, _, panel, trailing) = rest.split_at_mut(width, width);
        cholesky_in_place(
            diagonal.rb_mut(),
            Default::default(),
            Par::Seq,
            stack,
            Default::default(),
        )
        .map_err(|_| NonPositivePivot)?;
        if k + width == n {
            break;
        }
        let mut panel = panel;
        solve_below(diagonal.rb(), panel.rb_mut(), true);
        // trailing -= panel panel^T, lower triangle: its columns in two groups of about
        // equal area, the first a triangle with the rectangle below it, the second a triangle
        let m = trailing.ncols();
        let first = m - ((m as f64) / std::f64::consts::SQRT_2).round() as usize;
        let (t11, _, t21, t22) = trailing.split_at_mut(first, first);
        let (p1, p2) = panel.rb().split_at_row(first);
        rayon::join(
            || {
                triangular::matmul(
                    t11,
                    BlockStructure::TriangularLower,
                    Accum::Add,
                    p1,
                    BlockStructure::Rectangular,
                    p1.transpose(),
                    BlockStructure::Rectangular,
                    -1.0,
                    Par::Seq,
                );
                matmul(t21, Accum::Add, p2, p1.transpose(), -1.0, Par::Seq);
            },
            || {
                triangular::matmul(
                    t22,
                    BlockStructure::TriangularLower,
                    Accum::Add,
                    p2,
                    BlockStructure::Rectangular,
                    p2.transpose(),
                    BlockStructure::Rectangular,
                    -1.0,
                    Par::Seq,
                )
            },
        );
        k += width;
    }
    Ok(())
}

/// `below = below L^-T` for the factor `l` of a diagonal block: its rows in two halves side by
/// side where `split` (each row is solved apart, the halves fixed by the size).
fn solve_below(l: MatRef<'_, f64>, below: MatMut<'_, f64>, split: bool) {
    if split && below.nrows() >= 2 * PANEL {
        let half = below.nrows() / 2;
        let (one, two) = below.split_at_row_mut(half);
        rayon::join(
            || solve_lower_triangular_in_place(l, one.transpose_mut(), Par::Seq),
            || solve_lower_triangular_in_place(l, two.transpose_mut(), Par::Seq),
        );
    } else {
        solve_lower_triangular_in_place(l, below.transpose_mut(), Par::Seq);
    }
}

/// The parallel plan of a factorisation: which subtrees of the elimination tree run side by
/// side.
struct Planner<'a> {
    factorisation: &'a Supernodal,
    /// The place in the postorder of the first supernode of the subtree of the supernode at
    /// each place: the subtree is the places `first[k]..=k`.
    first: Vec<usize>,
    /// Estimated flops of the subtree of the supernode at each place.
    subtree: Vec<f64>,
    parallel_flops: f64,
}

/// A postorder of the tree of supernodes with parents `parent` (`usize::MAX` for a root): its
/// children in increasing order before each supernode, each subtree whole.
fn postorder(parent: &[usize]) -> Vec<usize> {
    let count = parent.len();
    let mut children = vec![Vec::new(); count];
    let mut roots = Vec::new();
    for (s, &p) in parent.iter().enumerate() {
        if p == usize::MAX {
            roots.push(s);
        } else {
            children[p].push(s);
        }
    }
    let mut order = Vec::with_capacity(count);
    // (supernode, how many of its children are done)
    let mut stack: Vec<(usize, usize)> = roots.iter().rev().map(|&r| (r, 0)).collect();
    while let Some((s, done)) = stack.pop() {
        if done < children[s].len() {
            stack.push((s, done + 1));
            stack.push((children[s][done], 0));
        } else {
            order.push(s);
        }
    }
    order
}

impl<'a> Planner<'a> {
    /// The planner over `factorisation`'s postorder, whose tree has the parents `parent`.
    fn new(factorisation: &'a Supernodal, parent: &[usize], parallel_flops: f64) -> Self {
        let f = factorisation;
        let count = parent.len();
        let mut first: Vec<usize> = (0..count).collect();
        let mut subtree = vec![0.0; count];
        for (k, &s) in f.postorder.iter().enumerate() {
            let updates = &f.updates[f.update_ptr[s]..f.update_ptr[s + 1]];
            subtree[k] += f.own_flops(s) + updates.iter().map(|u| f.update_flops(u)).sum::<f64>();
            if parent[s] != usize::MAX {
                let p = f.place[parent[s]];
                first[p] = first[p].min(first[k]);
                subtree[p] += subtree[k];
            }
        }
        Self {
            factorisation,
            first,
            subtree,
            parallel_flops,
        }
    }

    /// The plan of the forest of the supernodes at places `lo..hi` (whole subtrees).
    fn forest(&self, lo: usize, hi: usize) -> Task {
        let mut roots = Vec::new();
        let mut r = hi;
        while r > lo {
            roots.push(r - 1);
            r = self.first[r - 1];
        }
        roots.reverse();
        let flops: Vec<f64> = roots.iter().map(|&r| self.subtree[r]).collect();
        let total: f64 = flops.iter().sum();
        if total < self.parallel_flops || roots.is_empty() {
            return Task::Sequence(lo..hi);
        }
        if roots.len() == 1 {
            return self.tree(roots[0]);
        }
        // the split nearest to halving the flops
        let (mut best, mut best_gap, mut sum) = (1, f64::INFINITY, 0.0);
        for (k, f) in flops.iter().enumerate().take(roots.len() - 1) {
            sum += f;
            let gap = (2.0 * sum - total).abs();
            if gap < best_gap {
                (best, best_gap) = (k + 1, gap);
            }
        }
        let mid = self.first[roots[best]];
        Task::Fork(
            Box::new(self.forest(lo, mid)),
            Box::new(self.forest(mid, hi)),
            mid,
        )
    }

    /// The plan of the subtree of the supernode at place `at`.
    fn tree(&self, at: usize) -> Task {
        let f = self.factorisation;
        let s = f.postorder[at];
        let forest = (self.first[at] < at).then(|| Box::new(self.forest(self.first[at], at)));
        let updates = &f.updates[f.update_ptr[s]..f.update_ptr[s + 1]];
        let flops: Vec<f64> = updates.iter().map(|u| f.update_flops(u)).collect();
        let total: f64 = flops.iter().sum();
        // the first group the updates up to the one that makes half the flops
        let split = (total >= self.parallel_flops && updates.len() >= 2).then(|| {
            let mut sum = 0.0;
            let k = flops
                .iter()
                .position(|&x| {
                    sum += x;
                    2.0 * sum >= total
                })
                .unwrap_or(0);
            f.update_ptr[s] + k.min(updates.len() - 2) + 1
        });
        Task::Node { forest, at, split }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An update's rows are cut into runs where their places in the supernode's block stop
    /// being consecutive, and the runs cover every row once, in order.
    #[test]
    fn runs_split_where_the_rows_stop_being_consecutive() {
        let runs = consecutive_runs(&[3, 4, 5, 9, 10, 2, 7]);
        let cut: Vec<(usize, usize)> = runs.iter().map(|r| (r.first, r.length)).collect();
        assert_eq!(cut, [(0, 3), (3, 2), (5, 1), (6, 1)]);
        assert!(consecutive_runs(&[]).is_empty());
    }

    /// The blocked dense factorisation of a supernode's block, in halves, agrees with faer's
    /// (in their lower triangles: faer's leaves rounding noise above the diagonal), on sizes
    /// over a few panels and between whole panels.
    #[test]
    fn blocked_dense_factorisation_agrees_with_faers() {
        for n in [17, 24, 45, 100, 203] {
            let r = n + 30;
            let mut a = vec![0.0; r * n];
            for i in 0..r {
                for j in 0..n {
                    a[i + j * r] = if i == j {
                        n as f64
                    } else {
                        1.0 / (1.0 + (i + j) as f64)
                    };
                }
            }
            let mut b = a.clone();
            let mut stack = MemBuffer::new(cholesky_in_place_scratch::<f64>(
                n,
                Par::Seq,
                Default::default(),
            ));
            for (x, split) in [(&mut a, true), (&mut b, false)] {
                let m = MatMut::from_column_major_slice_mut(x, r, n);
                let (mut top, bottom) = m.split_at_row_mut(n);
                dense_cholesky(top.rb_mut(), MemStack::new(&mut stack), split).unwrap();
                solve_below(top.rb(), bottom, split);
            }
            // a negative pivot in the last panel refused
            let mut c = vec![0.0; r * n];
            for i in 0..n {
                c[i + i * r] = if i == n - 1 { -1.0 } else { 1.0 };
            }
            let m = MatMut::from_column_major_slice_mut(&mut c, r, n);
            let (top, _) = m.split_at_row_mut(n);
            assert_eq!(
                dense_cholesky(top, MemStack::new(&mut stack), true),
                Err(NonPositivePivot)
            );
            for j in 0..n {
                for i in j..r {
                    assert!(
                        (a[i + j * r] - b[i + j * r]).abs() < 1e-12,
                        "{n}: {i} {j}: {} {}",
                        a[i + j * r],
                        b[i + j * r]
                    );
                }
            }
        }
    }
}
