//! A coarse level for the conjugate gradients on the membrane's stencil (docs/solver.md,
//! "A coarse level of rigid aggregates"): the sheet's nodes grouped into small aggregates, each
//! moving rigidly (three translations, three rotations), and the tangent projected onto those
//! motions (Galerkin, `K_c = P^T K P`). The membrane-stencil factorisation misses the bending
//! patches' farther couplings and so is too stiff for the smooth out-of-plane motions of a
//! free sheet, the more so the finer the mesh; the coarse level solves those motions with the
//! full tangent. Added to the fine preconditioner (additive two-level Schwarz):
//! `M^-1 = M_f^-1 + P K_c^-1 P^T`, symmetric positive definite as both terms are.

use nalgebra::Vector3;

use super::linear::{minimum_degree, Cholesky, NotPositiveDefinite, Pattern};

/// Rigid motions of an aggregate: three translations, then three rotations about its centre.
const MODES: usize = 6;

/// The coarse level of a sheet: its aggregates' rigid motions, and the tangent projected onto
/// them.
pub struct Coarse {
    /// Per unknown of the tangent: the rigid modes that move it, as (coarse unknown, weight),
    /// its translation first; none where the unknown is held or is not a node's.
    rows: Vec<Vec<(usize, f64)>>,
    /// Per stored place of the tangent: its unknowns `(i, j)`, the 6 x 6 block of aggregates
    /// its entry adds to, and whether `i`'s aggregate is the block's column (the pair taken
    /// the other way); no block where an unknown is not a node's.
    blocks: Vec<(u32, u32, u32, bool)>,
    /// Per block: the stored places of the coarse matrix of its 36 entries (row-major, the
    /// first aggregate's mode by row), `usize::MAX` for the upper half of a diagonal block.
    places: Vec<[usize; MODES * MODES]>,
    /// Per block: its aggregates (the larger first).
    pairs: Vec<(usize, usize)>,
    pattern: Pattern,
    cholesky: Cholesky,
    /// Buffers: the blocks' sums, the coarse matrix's values.
    sums: Vec<[f64; MODES * MODES]>,
    values: Vec<f64>,
}

impl Coarse {
    /// The coarse level of the tangent on `pattern`, whose first `3 n` unknowns are the
    /// coordinates of the `n` nodes at `points` (reference positions), coupled by `cells`
    /// (membrane elements), `held` those prescribed.
    pub fn new(
        points: &[Vector3<f64>],
        cells: &[Vec<usize>],
        pattern: &Pattern,
        held: &[bool],
    ) -> Result<Self, String> {
        let nodes = points.len();
        let neighbours = node_neighbours(nodes, cells);
        let aggregate = aggregates(&neighbours);
        let count = aggregate.iter().max().map_or(0, |m| m + 1);
        let rows = rigid_rows(points, &aggregate, count, held, pattern.size());
        // the aggregates coupled by the tangent, and the block of each stored place
        let node_of = |i: usize| (i < 3 * nodes).then_some(i / 3);
        let mut index = std::collections::HashMap::new();
        let mut pairs = Vec::new();
        let mut blocks = Vec::with_capacity(pattern.entries());
        for (i, j) in pattern.stored_pairs() {
            let (Some(a), Some(b)) = (node_of(i), node_of(j)) else {
                blocks.push((i as u32, j as u32, u32::MAX, false));
                continue;
            };
            let (g, h) = (aggregate[a], aggregate[b]);
            let key = (g.max(h), g.min(h));
            let next = pairs.len() as u32;
            let block = *index.entry(key).or_insert_with(|| {
                pairs.push(key);
                next
            });
            blocks.push((i as u32, j as u32, block, g < h));
        }
        let mut around = vec![Vec::new(); count];
        for &(g, h) in &pairs {
            if g != h {
                around[g].push(h);
                around[h].push(g);
            }
        }
        let order: Vec<usize> = minimum_degree(&around)?
            .into_iter()
            .flat_map(|g| (0..MODES).map(move |m| MODES * g + m))
            .collect();
        let groups: Vec<Vec<usize>> = pairs
            .iter()
            .map(|&(g, h)| {
                (0..MODES)
                    .flat_map(|m| [MODES * g + m, MODES * h + m])
                    .collect()
            })
            .collect();
        let coarse =
            Pattern::from_groups_in_order(MODES * count, groups.iter().map(|g| &g[..]), order);
        let places = pairs
            .iter()
            .map(|&(g, h)| {
                let mut p = [usize::MAX; MODES * MODES];
                for r in 0..MODES {
                    for s in 0..MODES {
                        if g != h || r >= s {
                            p[MODES * r + s] = coarse
                                .place(MODES * g + r, MODES * h + s)
                                .expect("a coarse coupling");
                        }
                    }
                }
                p
            })
            .collect();
        Ok(Self {
            rows,
            sums: vec![[0.0; MODES * MODES]; pairs.len()],
            blocks,
            places,
            pairs,
            cholesky: Cholesky::analyse(&coarse)?,
            values: vec![0.0; coarse.entries()],
            pattern: coarse,
        })
    }

    /// Unknowns of the coarse level.
    pub fn size(&self) -> usize {
        self.pattern.size()
    }

    /// Projects the tangent with lower triangle `values` (on the pattern this level was made
    /// for) onto the aggregates' rigid motions and factorises it.
    pub fn factorise(&mut self, values: &[f64]) -> Result<(), NotPositiveDefinite> {
        self.sums.iter_mut().for_each(|s| *s = [0.0; MODES * MODES]);
        for (&v, &(i, j, block, swapped)) in values.iter().zip(&self.blocks) {
            let (i, j) = (i as usize, j as usize);
            if block == u32::MAX || v == 0.0 {
                continue;
            }
            let sum = &mut self.sums[block as usize];
            let (first, second) = if swapped {
                (&self.rows[j], &self.rows[i])
            } else {
                (&self.rows[i], &self.rows[j])
            };
            // each stored entry stands for K_ij and K_ji: within one aggregate both add to a
            // mode's own entry, each to one of a pair of modes' two (summed below)
            let own = self.pairs[block as usize].0 == self.pairs[block as usize].1;
            if i == j {
                for (k, &(r, wr)) in first.iter().enumerate() {
                    for &(s, ws) in &first[k..] {
                        sum[MODES * (r % MODES) + s % MODES] += v * wr * ws;
                    }
                }
            } else {
                for &(r, wr) in first {
                    for &(s, ws) in second {
                        let (r, s) = (r % MODES, s % MODES);
                        let twice = if own && r == s { 2.0 } else { 1.0 };
                        sum[MODES * r + s] += twice * v * wr * ws;
                    }
                }
            }
        }
        self.values.iter_mut().for_each(|v| *v = 0.0);
        for ((sum, places), &(g, h)) in self.sums.iter().zip(&self.places).zip(&self.pairs) {
            for r in 0..MODES {
                for s in 0..MODES {
                    let k = MODES * r + s;
                    if g == h && r < s {
                        // an aggregate's own entry (r, s) above the diagonal: to (s, r)
                        self.values[places[MODES * s + r]] += sum[k];
                    } else {
                        self.values[places[k]] += sum[k];
                    }
                }
            }
        }
        // rigid modes no free unknown carries (an aggregate held in full) have no stiffness:
        // a floor far below the others' keeps the factorisation positive definite
        let floor = 1e-12
            * (0..self.size())
                .map(|c| self.values[self.pattern.place(c, c).expect("a diagonal")])
                .fold(0.0f64, f64::max);
        for c in 0..self.size() {
            self.values[self.pattern.place(c, c).expect("a diagonal")] += floor;
        }
        self.cholesky.factorise(&self.pattern, &self.values)
    }

    /// Adds `P K_c^-1 P^T r` to `z`.
    pub fn correct(&mut self, r: &[f64], z: &mut [f64]) {
        let mut y = vec![0.0; self.size()];
        for (row, ri) in self.rows.iter().zip(r) {
            for &(c, w) in row {
                y[c] += w * ri;
            }
        }
        self.cholesky.solve(&mut y);
        for (row, zi) in self.rows.iter().zip(z.iter_mut()) {
            for &(c, w) in row {
                *zi += w * y[c];
            }
        }
    }
}

/// Each node's neighbours: the other nodes of its cells, sorted.
fn node_neighbours(nodes: usize, cells: &[Vec<usize>]) -> Vec<Vec<usize>> {
    let mut neighbours = vec![Vec::new(); nodes];
    for cell in cells {
        for &a in cell {
            neighbours[a].extend(cell.iter().copied().filter(|&b| b != a));
        }
    }
    for around in &mut neighbours {
        around.sort_unstable();
        around.dedup();
    }
    neighbours
}

/// The aggregate of each node (greedy, in the nodes' order): a node whose neighbours are all
/// free starts an aggregate of itself and them (3 x 3 nodes on a grid of quadrilaterals); a
/// node left over joins the aggregate of its first aggregated neighbour, or starts its own.
fn aggregates(neighbours: &[Vec<usize>]) -> Vec<usize> {
    let mut aggregate = vec![usize::MAX; neighbours.len()];
    let mut count = 0;
    for (a, around) in neighbours.iter().enumerate() {
        if aggregate[a] == usize::MAX && around.iter().all(|&b| aggregate[b] == usize::MAX) {
            aggregate[a] = count;
            around.iter().for_each(|&b| aggregate[b] = count);
            count += 1;
        }
    }
    for (a, around) in neighbours.iter().enumerate() {
        if aggregate[a] == usize::MAX {
            aggregate[a] = around
                .iter()
                .map(|&b| aggregate[b])
                .find(|&g| g != usize::MAX && g < count)
                .unwrap_or_else(|| {
                    count += 1;
                    count - 1
                });
        }
    }
    aggregate
}

/// Per unknown of `size`, the rigid modes of its node's aggregate that move it: the
/// translation along its coordinate, and the two rotations `theta x (x - c)` that move it,
/// the arm `x - c` from the aggregate's centre in units of the aggregate's radius.
fn rigid_rows(
    points: &[Vector3<f64>],
    aggregate: &[usize],
    count: usize,
    held: &[bool],
    size: usize,
) -> Vec<Vec<(usize, f64)>> {
    let mut centre = vec![Vector3::zeros(); count];
    let mut members = vec![0usize; count];
    for (p, &g) in points.iter().zip(aggregate) {
        centre[g] += p;
        members[g] += 1;
    }
    for (c, &m) in centre.iter_mut().zip(&members) {
        *c /= m as f64;
    }
    let mut radius = vec![0.0f64; count];
    for (p, &g) in points.iter().zip(aggregate) {
        radius[g] = radius[g].max((p - centre[g]).norm());
    }
    let mut rows = vec![Vec::new(); size];
    for (a, (p, &g)) in points.iter().zip(aggregate).enumerate() {
        let arm = (p - centre[g]) / radius[g].max(f64::MIN_POSITIVE);
        let mode = |m: usize| MODES * g + m;
        // u = t + theta x arm: u_x = t_x + arm_z theta_y - arm_y theta_z, and cyclically
        let row = |d: usize| {
            let (e, f) = ((d + 1) % 3, (d + 2) % 3);
            vec![
                (mode(d), 1.0),
                (mode(3 + e), arm[f]),
                (mode(3 + f), -arm[e]),
            ]
        };
        for d in 0..3 {
            if !held[3 * a + d] {
                rows[3 * a + d] = row(d);
            }
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `side` x `side` sheet of unit quadrilaterals in the plane z = 0, three unknowns a
    /// node and one more (a tool's travel) coupled with all: the cells, the points, and a
    /// random symmetric matrix on the pattern of the cells' and their neighbours' couplings.
    fn sheet(side: usize, seed: u64) -> (Vec<Vector3<f64>>, Vec<Vec<usize>>, Pattern, Vec<f64>) {
        let node = |i: usize, j: usize| i * side + j;
        let points = (0..side * side)
            .map(|k| Vector3::new((k / side) as f64, (k % side) as f64 * 1.1, 0.0))
            .collect();
        let cells: Vec<Vec<usize>> = (0..side - 1)
            .flat_map(|i| {
                (0..side - 1).map(move |j| {
                    vec![node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)]
                })
            })
            .collect();
        let n = 3 * side * side + 1;
        let mut groups: Vec<Vec<usize>> = cells
            .iter()
            .map(|c| c.iter().flat_map(|&a| [3 * a, 3 * a + 1, 3 * a + 2]).collect())
            .collect();
        groups.push(vec![0, 1, 2, n - 1]);
        let pattern = Pattern::from_groups(n, groups.iter().map(|g| &g[..]));
        let mut state = seed;
        let values = (0..pattern.entries())
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            })
            .collect();
        (points, cells, pattern, values)
    }

    /// The coarse matrix is `P^T K P`, `P` the aggregates' rigid motions, as a dense product
    /// makes it; a held unknown moves with no mode.
    #[test]
    fn the_coarse_matrix_is_the_tangent_projected_onto_the_rigid_motions() {
        let (points, cells, pattern, values) = sheet(7, 3);
        let n = pattern.size();
        let mut held = vec![false; n];
        held[3 * 10 + 2] = true;
        let mut coarse = Coarse::new(&points, &cells, &pattern, &held).unwrap();
        assert!(coarse.rows[3 * 10 + 2].is_empty() && coarse.rows[n - 1].is_empty());
        let _ = coarse.factorise(&values);
        let m = coarse.size();
        let mut k = vec![vec![0.0; n]; n];
        for ((i, j), v) in pattern.stored_pairs().into_iter().zip(&values) {
            k[i][j] = *v;
            k[j][i] = *v;
        }
        let mut p = vec![vec![0.0; m]; n];
        for (i, row) in coarse.rows.iter().enumerate() {
            for &(c, w) in row {
                p[i][c] = w;
            }
        }
        let floor = 1e-12
            * (0..m)
                .map(|c| coarse.values[coarse.pattern.place(c, c).unwrap()])
                .fold(0.0f64, f64::max);
        for a in 0..m {
            for b in 0..=a {
                let expected: f64 = (0..n)
                    .flat_map(|i| (0..n).map(move |j| (i, j)))
                    .map(|(i, j)| p[i][a] * k[i][j] * p[j][b])
                    .sum::<f64>()
                    + if a == b { floor } else { 0.0 };
                let got = coarse
                    .pattern
                    .place(a, b)
                    .map_or(0.0, |q| coarse.values[q]);
                assert!((got - expected).abs() < 1e-9, "({a}, {b}): {got} against {expected}");
            }
        }
    }
}
