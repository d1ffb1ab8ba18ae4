//! Heat conduction in the plane of the blank (docs/model.md Eq. (H2)), with a conductivity
//! that follows the yarns of the woven fabric as they shear.
//!
//! The fibres carry the heat: in its current tangent plane a cell conducts with
//! `K = k_warp â⊗â + k_weft b̂⊗b̂`, `â`, `b̂` the CURRENT unit yarn directions (`a = F a0`,
//! `b = F b0`, normalised). Unsheared, this is the usual orthotropic tensor with principal
//! values `k_warp`, `k_weft`; sheared, each yarn family still conducts along itself, so the
//! two principal directions close up with the yarns instead of staying at 90°.
//!
//! Linear finite elements on the current (deformed, 3D) surface: for one through-thickness
//! level of thickness `dz`, the heat flowing into the nodes is `-(k_warp dz M_warp +
//! k_weft dz M_weft) T` with `M_warp = ∫ (∇N·â)(∇N·â)^T dA` and `M_weft` the same with `b̂`,
//! gradients taken in the cell's own plane. Each matrix is symmetric positive semi-definite
//! with zero row sums: a uniform temperature exchanges no heat and what leaves one node enters
//! the others. The matrices hold the geometry only, so the conductivities (functions of
//! temperature and of the level) are applied at each evaluation.
//!
//! Units: conductivity in N/(s·K) (numerically W/(m·K)), `k dz` in N·mm/(s·K), capacities in
//! N·mm/K, temperatures in °C, heat rates in N·mm/s.

use nalgebra::Vector3;

/// The area below which a triangle is taken as degenerate, relative to its longest edge
/// squared: such a cell conducts nothing rather than divide by a vanishing area.
const DEGENERATE_AREA: f64 = 1e-12;

/// The in-plane length below which a yarn is taken as normal to the cell, relative to its
/// length: its direction in the plane is then undefined and it conducts nothing there.
const NORMAL_YARN: f64 = 1e-9;

/// Conductance matrices of one cell per unit conductivity and unit thickness (mm^0: the
/// entries are `∫ (∇N_a·ŷ)(∇N_b·ŷ) dA`, dimensionless), for its warp and its weft
/// (docs/model.md Eq. (H2)).
///
/// A quadrilateral `a-b-c-d` is taken as the two linear triangles `a-b-c` and `a-c-d`, each
/// with its own area, plane and projected yarns **(choice)**: linear fields stay exact (the
/// patch test holds on any mesh), a warped quadrilateral is handled without a mean plane, and
/// the matrices are those of the triangle mesh got by splitting every cell the same way. The
/// split is along `a-c`, so it depends on which corner is first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellConduction {
    /// Corner nodes; only the first `count` are used.
    pub nodes: [usize; 4],
    /// 3 for a triangle, 4 for a quadrilateral.
    pub count: usize,
    /// `M_warp`, corners in order; rows and columns past `count` are zero.
    pub warp: [[f64; 4]; 4],
    /// `M_weft`, corners in order; rows and columns past `count` are zero.
    pub weft: [[f64; 4]; 4],
}

/// Why a cell's conduction cannot be built (bad node lists; bad geometry gives zero matrices).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConductionError {
    #[error("a conducting cell has 3 or 4 corners, not {0}")]
    CornerCount(usize),
    #[error("corner node {node} is not among the {nodes} nodes")]
    UnknownNode { node: usize, nodes: usize },
}

/// One linear triangle on the current surface: its area and its shape functions' gradients
/// in its own plane (3D vectors normal to `normal`).
struct Triangle {
    normal: Vector3<f64>,
    area: f64,
    gradients: [Vector3<f64>; 3],
}

impl Triangle {
    /// The triangle `x`, or `None` when it is degenerate (collinear or coincident corners, or
    /// positions that are not finite). `∇N_i = n × (x_{i+2} - x_{i+1}) / (2A)`: normal to the
    /// opposite edge, of length one over the altitude.
    fn new(x: &[Vector3<f64>; 3]) -> Option<Self> {
        let area_vector = (x[1] - x[0]).cross(&(x[2] - x[0]));
        let twice_area = area_vector.norm();
        let longest = (0..3)
            .map(|i| (x[(i + 1) % 3] - x[i]).norm_squared())
            .fold(0.0, f64::max);
        let sound = twice_area.is_finite() && twice_area > DEGENERATE_AREA * longest;
        if !sound {
            return None;
        }
        let normal = area_vector / twice_area;
        let gradients =
            [0, 1, 2].map(|i| normal.cross(&(x[(i + 2) % 3] - x[(i + 1) % 3])) / twice_area);
        Some(Self {
            normal,
            area: 0.5 * twice_area,
            gradients,
        })
    }

    /// The unit direction of `yarn` in the triangle's plane, or `None` when the yarn is zero,
    /// not finite or normal to the plane.
    fn in_plane(&self, yarn: &Vector3<f64>) -> Option<Vector3<f64>> {
        let projected = yarn - self.normal * self.normal.dot(yarn);
        let length = projected.norm();
        (length.is_finite() && length > NORMAL_YARN * yarn.norm()).then(|| projected / length)
    }

    /// `A (∇N_a·ŷ)(∇N_b·ŷ)` added to `matrix` at the places `corners` of the cell, off the
    /// diagonal only: each product is added to both `(a, b)` and `(b, a)`, so the matrix is
    /// exactly symmetric; the diagonal follows from the zero row sums.
    fn add_along(&self, direction: &Vector3<f64>, corners: [usize; 3], matrix: &mut [[f64; 4]; 4]) {
        let along = self.gradients.map(|g| g.dot(direction));
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            let product = self.area * along[a] * along[b];
            matrix[corners[a]][corners[b]] += product;
            matrix[corners[b]][corners[a]] += product;
        }
    }
}

/// Sets the diagonal to minus the sum of the row's other entries: the row sums (and, the
/// matrix being symmetric, the column sums) are then zero by construction, which is what
/// `A (∇N_a·ŷ)^2` gives up to rounding since `sum_a ∇N_a = 0`.
fn zero_row_sums(matrix: &mut [[f64; 4]; 4], count: usize) {
    for (a, row) in matrix.iter_mut().enumerate().take(count) {
        let others: f64 = row[..count]
            .iter()
            .enumerate()
            .filter(|&(b, _)| b != a)
            .map(|(_, entry)| entry)
            .sum();
        row[a] = -others;
    }
}

/// The triangles a cell of `count` corners is taken as, by place: see [`CellConduction`].
fn triangles(count: usize) -> &'static [[usize; 3]] {
    if count == 4 {
        &[[0, 1, 2], [0, 2, 3]]
    } else {
        &[[0, 1, 2]]
    }
}

impl CellConduction {
    /// The conductance matrices of the cell on `nodes` (3 or 4 corners) at the current
    /// `positions`, with `warp` and `weft` the current yarn vectors (`F a0`, `F b0`): they
    /// need be neither unit nor exactly in the cell's plane, as each triangle projects them
    /// onto its plane and normalises them. A degenerate triangle, or a yarn that is zero or
    /// normal to it, conducts nothing (zero matrices, never NaN).
    pub fn new(
        nodes: &[usize],
        positions: &[Vector3<f64>],
        warp: &Vector3<f64>,
        weft: &Vector3<f64>,
    ) -> Result<Self, ConductionError> {
        let count = nodes.len();
        if !(3..=4).contains(&count) {
            return Err(ConductionError::CornerCount(count));
        }
        if let Some(&node) = nodes.iter().find(|&&n| n >= positions.len()) {
            return Err(ConductionError::UnknownNode {
                node,
                nodes: positions.len(),
            });
        }
        let mut cell = Self {
            nodes: [0; 4],
            count,
            warp: [[0.0; 4]; 4],
            weft: [[0.0; 4]; 4],
        };
        cell.nodes[..count].copy_from_slice(nodes);
        for &corners in triangles(count) {
            let Some(triangle) = Triangle::new(&corners.map(|c| positions[nodes[c]])) else {
                continue;
            };
            if let Some(a) = triangle.in_plane(warp) {
                triangle.add_along(&a, corners, &mut cell.warp);
            }
            if let Some(b) = triangle.in_plane(weft) {
                triangle.add_along(&b, corners, &mut cell.weft);
            }
        }
        zero_row_sums(&mut cell.warp, count);
        zero_row_sums(&mut cell.weft, count);
        Ok(cell)
    }

    /// The corner nodes in use.
    pub fn corners(&self) -> &[usize] {
        &self.nodes[..self.count]
    }

    /// `K = k_warp dz M_warp + k_weft dz M_weft` (N·mm/(s·K)), from the two conductances
    /// `k dz` of one level (docs/model.md Eq. (H2)).
    pub fn conductance(&self, warp: f64, weft: f64) -> [[f64; 4]; 4] {
        let mut k = [[0.0; 4]; 4];
        for (a, row) in k.iter_mut().enumerate() {
            for (b, entry) in row.iter_mut().enumerate() {
                *entry = warp * self.warp[a][b] + weft * self.weft[a][b];
            }
        }
        k
    }

    /// Adds the heat flowing into the cell's corners, `-K T`, to `rates`. Written with the
    /// zero row sums as exchanges between pairs of corners, `-K_ab (T_b - T_a)` into `a` and
    /// its opposite into `b`: a uniform field gives exactly zero, a small difference on a
    /// large temperature loses no digits, and what one corner gains the other loses, to the
    /// bit.
    fn add_heat_rates(&self, warp: f64, weft: f64, temperatures: &[f64], rates: &mut [f64]) {
        let corners = self.corners();
        for a in 0..self.count {
            for b in a + 1..self.count {
                let k = warp * self.warp[a][b] + weft * self.weft[a][b];
                let flow = k * (temperatures[corners[b]] - temperatures[corners[a]]);
                rates[corners[a]] -= flow;
                rates[corners[b]] += flow;
            }
        }
    }

    /// Gershgorin's bound on the cell's share of a row of `K`: `K_aa + sum_{b != a} |K_ab|`.
    fn row_bound(&self, warp: f64, weft: f64, a: usize) -> f64 {
        let k = self.conductance(warp, weft);
        k[a][a]
            + (0..self.count)
                .filter(|&b| b != a)
                .map(|b| k[a][b].abs())
                .sum::<f64>()
    }
}

/// Adds the heat flowing into each node of one through-thickness level, `-K T` (N·mm/s), to
/// `rates` (docs/model.md Eq. (H2)), with `conductivity(cell)` the cell's `(k_warp dz,
/// k_weft dz)` (N·mm/(s·K)) at that level, `temperatures` per node (°C).
///
/// Serial, cell by cell, so the sums are the same bits on any number of threads: the work is
/// six pair exchanges per quadrilateral, measured 0.8–1.0 ms for 5,000 quadrilaterals x 12
/// levels (`opt-level = 2`, a shared machine at a load of 4.6), about 15 ns a cell and level
/// against about 1.2 µs for a cell's membrane forces (docs/performance.md); the heat's
/// stable step, seconds, is also far above the explicit solver's, so it need not run every
/// step.
///
/// Panics if a cell's node is past the end of `temperatures` or `rates`.
pub fn add_heat_rates(
    cells: &[CellConduction],
    conductivity: impl Fn(usize) -> (f64, f64),
    temperatures: &[f64],
    rates: &mut [f64],
) {
    for (index, cell) in cells.iter().enumerate() {
        let (warp, weft) = conductivity(index);
        cell.add_heat_rates(warp, weft, temperatures, rates);
    }
}

/// The largest forward-Euler step (s) that keeps the explicit update `C dT/dt = -K T` of one
/// level stable, `capacities` per node (`rho c dz` times the nodal area, N·mm/K).
///
/// `K` is symmetric positive semi-definite, so `C^-1 K` (similar to `C^-1/2 K C^-1/2`) has
/// real eigenvalues `0 <= λ`, and `T <- (I - dt C^-1 K) T` does not grow while
/// `dt <= 2 / λ_max`. Gershgorin's theorem on the rows of `C^-1 K` bounds
/// `λ_max <= max_i (K_ii + sum_{j != i} |K_ij|) / C_i`; the row sums are taken cell by cell
/// (`|sum_c K^c_ij| <= sum_c |K^c_ij|`), which only lowers the step, so
/// `dt = min_i 2 C_i / sum_c (K^c_ii + sum_{j != i} |K^c_ij|)`. At that step the fastest mode
/// may just oscillate without growing; take a fraction of it.
///
/// `+inf` when nothing conducts; 0 when a conducting node has no positive capacity or a
/// conductivity is negative or not finite (no step is stable). Panics if a cell's node is
/// past the end of `capacities`.
pub fn stable_step(
    cells: &[CellConduction],
    conductivity: impl Fn(usize) -> (f64, f64),
    capacities: &[f64],
) -> f64 {
    let mut bounds = vec![0.0; capacities.len()];
    for (index, cell) in cells.iter().enumerate() {
        let (warp, weft) = conductivity(index);
        if !(physical(warp) && physical(weft)) {
            return 0.0;
        }
        for (a, &node) in cell.corners().iter().enumerate() {
            bounds[node] += cell.row_bound(warp, weft, a);
        }
    }
    bounds
        .iter()
        .zip(capacities)
        .filter(|&(&bound, _)| bound != 0.0)
        .map(|(&bound, &capacity)| node_step(capacity, bound))
        .fold(f64::INFINITY, f64::min)
}

/// A conductance `k dz` that conducts heat down the gradient: finite and not negative. A
/// negative one makes `K` indefinite and forward Euler unstable at any step.
fn physical(conductance: f64) -> bool {
    conductance.is_finite() && conductance >= 0.0
}

/// `2 C / R` for one node, or 0 where that is not a positive number (NaN included).
fn node_step(capacity: f64, bound: f64) -> f64 {
    let step = 2.0 * capacity / bound;
    if step > 0.0 {
        step
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, Matrix2, Matrix3, Rotation3, Unit, Vector2};

    const RHO_C: f64 = 1.872;
    const K_WARP: f64 = 5.0;
    const K_WEFT: f64 = 1.0;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// A small deterministic generator of numbers in [-1, 1) (no test depends on its stream).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }

        fn vector(&mut self) -> Vector3<f64> {
            v(self.next(), self.next(), self.next())
        }
    }

    /// Nodes and cells of a surface mesh.
    struct Mesh {
        positions: Vec<Vector3<f64>>,
        cells: Vec<Vec<usize>>,
    }

    /// An `nx` x `ny` grid on `[0, lx] x [0, ly]` in the plane z = 0, of quadrilaterals or of
    /// triangles with alternating diagonals.
    fn grid(nx: usize, ny: usize, lx: f64, ly: f64, quads: bool) -> Mesh {
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let positions = (0..=ny)
            .flat_map(|j| {
                (0..=nx).map(move |i| v(lx * i as f64 / nx as f64, ly * j as f64 / ny as f64, 0.0))
            })
            .collect();
        let mut cells = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let corners = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                push_cell(&mut cells, corners, quads, (i + j) % 2 == 0);
            }
        }
        Mesh { positions, cells }
    }

    /// The quadrilateral `[a, b, c, d]`, or its two triangles cut along `ac` (`even`) or `bd`.
    fn push_cell(cells: &mut Vec<Vec<usize>>, [a, b, c, d]: [usize; 4], quads: bool, even: bool) {
        if quads {
            cells.push(vec![a, b, c, d]);
        } else if even {
            cells.extend([vec![a, b, c], vec![a, c, d]]);
        } else {
            cells.extend([vec![a, b, d], vec![b, c, d]]);
        }
    }

    /// A tube of `nx` x `around` cells along x, radius `radius`: a strip periodic across its
    /// width, so a field `T(x)` meets no side edge. The cells' tangent across the strip.
    fn tube(nx: usize, around: usize, length: f64, radius: f64, quads: bool) -> Mesh {
        let id = |i: usize, j: usize| i * around + j % around;
        let positions = (0..=nx)
            .flat_map(|i| {
                (0..around).map(move |j| {
                    let theta = std::f64::consts::TAU * j as f64 / around as f64;
                    v(
                        length * i as f64 / nx as f64,
                        radius * theta.cos(),
                        radius * theta.sin(),
                    )
                })
            })
            .collect();
        let mut cells = Vec::new();
        for i in 0..nx {
            for j in 0..around {
                let corners = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                push_cell(&mut cells, corners, quads, (i + j) % 2 == 0);
            }
        }
        Mesh { positions, cells }
    }

    /// The unit warp at `phi` from `along` towards `across`, and the weft at 90° to it.
    fn ply(phi: f64, along: Vector3<f64>, across: Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        (
            along * phi.cos() + across * phi.sin(),
            -along * phi.sin() + across * phi.cos(),
        )
    }

    fn area(corners: &[Vector3<f64>]) -> f64 {
        (1..corners.len() - 1)
            .map(|k| {
                0.5 * (corners[k] - corners[0])
                    .cross(&(corners[k + 1] - corners[0]))
                    .norm()
            })
            .sum()
    }

    /// Lumped capacities `rho c dz` x nodal area (each corner a share of its cell's area).
    fn capacities(mesh: &Mesh, rho_c_dz: f64) -> Vec<f64> {
        let mut c = vec![0.0; mesh.positions.len()];
        for cell in &mesh.cells {
            let corners: Vec<_> = cell.iter().map(|&n| mesh.positions[n]).collect();
            let share = rho_c_dz * area(&corners) / cell.len() as f64;
            for &n in cell {
                c[n] += share;
            }
        }
        c
    }

    fn conduction(
        mesh: &Mesh,
        yarns: impl Fn(usize) -> (Vector3<f64>, Vector3<f64>),
    ) -> Vec<CellConduction> {
        mesh.cells
            .iter()
            .enumerate()
            .map(|(index, cell)| {
                let (warp, weft) = yarns(index);
                CellConduction::new(cell, &mesh.positions, &warp, &weft).expect("a sound cell")
            })
            .collect()
    }

    fn rates(cells: &[CellConduction], k: (f64, f64), temperatures: &[f64]) -> Vec<f64> {
        let mut rates = vec![0.0; temperatures.len()];
        add_heat_rates(cells, |_| k, temperatures, &mut rates);
        rates
    }

    fn largest(matrix: &[[f64; 4]; 4]) -> f64 {
        matrix.iter().flatten().fold(0.0, |m, x| m.max(x.abs()))
    }

    /// `∫ (∇N·ŷ)(∇N·ŷ)^T dA` of one triangle computed another way: in a 2D basis of its
    /// plane, the gradients from the inverse of the Jacobian `[x1 - x0, x2 - x0]`.
    fn reference_triangle(x: [Vector3<f64>; 3], yarn: &Vector3<f64>) -> [[f64; 3]; 3] {
        let normal = (x[1] - x[0]).cross(&(x[2] - x[0])).normalize();
        let e1 = (x[1] - x[0]).normalize();
        let e2 = normal.cross(&e1);
        let local = |w: Vector3<f64>| Vector2::new(w.dot(&e1), w.dot(&e2));
        let jacobian = Matrix2::from_columns(&[local(x[1] - x[0]), local(x[2] - x[0])]);
        let inverse = jacobian.try_inverse().expect("a sound triangle");
        let g1 = inverse.row(0).transpose();
        let g2 = inverse.row(1).transpose();
        let g = [-g1 - g2, g1, g2];
        let y = local(*yarn).normalize();
        let a = 0.5 * jacobian.determinant().abs();
        let d = g.map(|g| g.dot(&y));
        let mut m = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = a * d[i] * d[j];
            }
        }
        m
    }

    #[test]
    fn matrices_are_symmetric_with_zero_row_sums_and_those_of_their_triangles() {
        let mut random = Lcg(7);
        for trial in 0..200 {
            let count = 3 + trial % 2;
            let positions: Vec<_> = (0..count).map(|_| random.vector() * 10.0).collect();
            let (warp, weft) = (random.vector(), random.vector());
            let nodes: Vec<usize> = (0..count).collect();
            let cell = CellConduction::new(&nodes, &positions, &warp, &weft).expect("4 nodes");
            for m in [&cell.warp, &cell.weft] {
                let scale = largest(m);
                assert!(scale > 0.0, "trial {trial}: a random cell conducts");
                for (a, row) in m.iter().enumerate() {
                    let sum: f64 = row.iter().sum();
                    assert!(sum.abs() <= 1e-14 * scale, "trial {trial}: row sum {sum:e}");
                    for (b, entry) in row.iter().enumerate() {
                        assert_eq!(*entry, m[b][a], "trial {trial}: symmetric");
                    }
                }
                // Positive semi-definite: heat flows from hot to cold.
                for _ in 0..5 {
                    let t = [random.next(), random.next(), random.next(), random.next()];
                    let q: f64 = (0..4)
                        .flat_map(|a| (0..4).map(move |b| (a, b)))
                        .map(|(a, b)| t[a] * m[a][b] * t[b])
                        .sum();
                    assert!(q >= -1e-13 * scale, "trial {trial}: T^T M T = {q:e}");
                }
            }
            // The sum of the independently computed triangles a-b-c (and a-c-d).
            for (yarn, m) in [(warp, &cell.warp), (weft, &cell.weft)] {
                let mut expected = [[0.0; 4]; 4];
                for corners in triangles(count) {
                    let r = reference_triangle(corners.map(|c| positions[c]), &yarn);
                    for i in 0..3 {
                        for j in 0..3 {
                            expected[corners[i]][corners[j]] += r[i][j];
                        }
                    }
                }
                let scale = largest(&expected);
                for a in 0..4 {
                    for b in 0..4 {
                        let error = (m[a][b] - expected[a][b]).abs();
                        assert!(
                            error <= 1e-11 * scale,
                            "trial {trial}: ({a}, {b}) off by {error:e}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn bad_geometry_or_yarns_conduct_nothing_and_bad_node_lists_are_refused() {
        let square = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(0.0, 1.0, 0.0),
        ];
        let line = [v(0.0, 0.0, 0.0), v(1.0, 1.0, 1.0), v(2.0, 2.0, 2.0)];
        let point = [v(3.0, 1.0, 2.0); 3];
        let broken = [v(0.0, 0.0, 0.0), v(f64::NAN, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        let far = [
            v(0.0, 0.0, 0.0),
            v(f64::INFINITY, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
        ];
        let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
        let nan = v(f64::NAN, 1.0, 0.0);
        let zero_and_finite = |cell: &CellConduction, warp_zero: bool, weft_zero: bool| {
            for (m, zero) in [(&cell.warp, warp_zero), (&cell.weft, weft_zero)] {
                assert!(m.iter().flatten().all(|e| e.is_finite()), "{cell:?}");
                assert_eq!(largest(m) == 0.0, zero, "{cell:?}");
            }
        };
        for corners in [&line[..], &point[..], &broken[..], &far[..]] {
            let cell = CellConduction::new(&[0, 1, 2], corners, &x, &y).expect("3 nodes");
            zero_and_finite(&cell, true, true);
        }
        // A quadrilateral with a collapsed half keeps the other half.
        let collapsed = [square[0], square[1], square[2], square[2]];
        let cell = CellConduction::new(&[0, 1, 2, 3], &collapsed, &x, &y).expect("4 nodes");
        zero_and_finite(&cell, false, false);
        for (warp, weft, warp_zero, weft_zero) in [
            (z, y, true, false),
            (x, -z * 3.0, false, true),
            (Vector3::zeros(), y, true, false),
            (x, nan, false, true),
            (z * 1e300, z * 1e-300, true, true),
        ] {
            let cell = CellConduction::new(&[0, 1, 2, 3], &square, &warp, &weft).expect("4 nodes");
            zero_and_finite(&cell, warp_zero, weft_zero);
        }
        assert_eq!(
            CellConduction::new(&[0, 1], &square, &x, &y),
            Err(ConductionError::CornerCount(2))
        );
        assert_eq!(
            CellConduction::new(&[0, 1, 2, 3, 0], &square, &x, &y),
            Err(ConductionError::CornerCount(5))
        );
        assert_eq!(
            CellConduction::new(&[0, 1, 4], &square, &x, &y),
            Err(ConductionError::UnknownNode { node: 4, nodes: 4 })
        );
    }

    /// `k_warp â⊗â + k_weft b̂⊗b̂` (3D, global).
    fn tensor(k: (f64, f64), warp: &Vector3<f64>, weft: &Vector3<f64>) -> Matrix3<f64> {
        let (a, b) = (warp.normalize(), weft.normalize());
        a * a.transpose() * k.0 + b * b.transpose() * k.1
    }

    /// An irregular `nx` x `ny` mesh of `[0, lx] x [0, ly]`: interior nodes moved at random,
    /// edge nodes along their edge, corners kept.
    fn irregular(nx: usize, ny: usize, lx: f64, ly: f64, quads: bool, seed: u64) -> Mesh {
        let mut mesh = grid(nx, ny, lx, ly, quads);
        let mut random = Lcg(seed);
        let (hx, hy) = (lx / nx as f64, ly / ny as f64);
        for p in &mut mesh.positions {
            let (dx, dy) = (0.3 * hx * random.next(), 0.3 * hy * random.next());
            if p.x > 0.0 && p.x < lx {
                p.x += dx;
            }
            if p.y > 0.0 && p.y < ly {
                p.y += dy;
            }
        }
        mesh
    }

    /// The heat a uniform `K ∇T` takes out of each node of the rectangle `[0, lx] x [0, ly]`
    /// through its boundary: `rate_i = -∮ N_i (K ∇T)·n ds` (integrating `-∫ ∇N_i·K∇T dA` by
    /// parts), each boundary edge sharing `(K ∇T)·n |e|` equally between its two nodes.
    fn boundary_rates(mesh: &Mesh, lx: f64, ly: f64, flux: &Vector3<f64>) -> Vec<f64> {
        let mut rates = vec![0.0; mesh.positions.len()];
        let sides = [
            (Vector3::x(), -1.0, 0.0),
            (Vector3::x(), 1.0, lx),
            (Vector3::y(), -1.0, 0.0),
            (Vector3::y(), 1.0, ly),
        ];
        for cell in &mesh.cells {
            for (k, &i) in cell.iter().enumerate() {
                let j = cell[(k + 1) % cell.len()];
                let (pi, pj) = (mesh.positions[i], mesh.positions[j]);
                for (axis, sign, at) in sides {
                    if pi.dot(&axis) == at && pj.dot(&axis) == at {
                        let out = flux.dot(&axis) * sign * (pj - pi).norm();
                        rates[i] -= 0.5 * out;
                        rates[j] -= 0.5 * out;
                    }
                }
            }
        }
        rates
    }

    #[test]
    fn a_linear_field_gives_no_heat_inside_and_its_boundary_flux_at_the_edges() {
        let (lx, ly) = (12.0, 10.0);
        let gradient = v(0.7, -0.4, 0.0);
        let rotation = Rotation3::from_axis_angle(&Unit::new_normalize(v(1.0, 2.0, 3.0)), 0.7);
        let orthotropic = ply(30f64.to_radians(), Vector3::x(), Vector3::y());
        let sheared = (v(1.0, 0.2, 0.0), v(0.5, 0.9, 0.0) * 3.0);
        for quads in [false, true] {
            for (seed, (warp, weft)) in [(1, orthotropic), (2, sheared)] {
                let mesh = irregular(6, 5, lx, ly, quads, seed);
                let k = (K_WARP * 0.5, K_WEFT * 0.5);
                let flux = tensor(k, &warp, &weft) * gradient;
                let expected = boundary_rates(&mesh, lx, ly, &flux);
                let temperatures: Vec<f64> = mesh
                    .positions
                    .iter()
                    .map(|p| 200.0 + gradient.dot(p))
                    .collect();
                // The same mesh, yarns and field turned rigidly into 3D.
                let turned = Mesh {
                    positions: mesh.positions.iter().map(|p| rotation * p).collect(),
                    cells: mesh.cells.clone(),
                };
                let planes = [
                    conduction(&mesh, |_| (warp, weft)),
                    conduction(&turned, |_| (rotation * warp, rotation * weft)),
                ];
                for cells in planes {
                    let got = rates(&cells, k, &temperatures);
                    let scale = expected.iter().fold(0.0, |m: f64, r| m.max(r.abs()));
                    for (node, (g, e)) in got.iter().zip(&expected).enumerate() {
                        let error = (g - e).abs();
                        assert!(
                            error <= 1e-11 * scale,
                            "quads {quads}, seed {seed}, node {node}: {g} against {e}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_heat_across_a_column_of_cells_is_k_grad_t_times_its_length() {
        let h = 1.5;
        let left = [0.0, 1.3, 2.1, 3.7, 5.0];
        let right = [0.0, 0.8, 2.5, 3.1, 5.0];
        let positions: Vec<_> = left
            .iter()
            .map(|&y| v(0.0, y, 0.0))
            .chain(right.iter().map(|&y| v(h, y, 0.0)))
            .collect();
        let r = left.len();
        let quads: Vec<Vec<usize>> = (0..r - 1)
            .map(|i| vec![i, r + i, r + i + 1, i + 1])
            .collect();
        let triangles: Vec<Vec<usize>> = quads
            .iter()
            .flat_map(|q| [vec![q[0], q[1], q[2]], vec![q[0], q[2], q[3]]])
            .collect();
        let gradient = v(0.7, -0.4, 0.0);
        let dz = 0.5;
        let k = (K_WARP * dz, K_WEFT * dz);
        for phi in [0.0, 30.0, 90.0] {
            let (warp, weft) = ply(f64::to_radians(phi), Vector3::x(), Vector3::y());
            // Heat crossing the cut x = h/2 from right to left: -q_x H = (K ∇T)_x H dz.
            let across = (tensor((K_WARP, K_WEFT), &warp, &weft) * gradient).x * 5.0 * dz;
            for cells in [quads.clone(), triangles.clone()] {
                let mesh = Mesh {
                    positions: positions.clone(),
                    cells,
                };
                let temperatures: Vec<f64> =
                    positions.iter().map(|p| 20.0 + gradient.dot(p)).collect();
                let got = rates(&conduction(&mesh, |_| (warp, weft)), k, &temperatures);
                let into_left: f64 = got[..r].iter().sum();
                let into_right: f64 = got[r..].iter().sum();
                assert!(
                    (into_left - across).abs() <= 1e-12 * across.abs(),
                    "{phi}°: {into_left} against {across}"
                );
                assert!(
                    (into_right + across).abs() <= 1e-12 * across.abs(),
                    "{phi}°: {into_right}"
                );
            }
        }
    }

    /// The amplitude of `cos(π x / L)` in `temperatures`, weighted by the capacities, `x` the
    /// reference coordinate along the strip.
    fn amplitude(temperatures: &[f64], along: &[f64], capacities: &[f64], length: f64) -> f64 {
        let total: f64 = capacities.iter().sum();
        let mean = temperatures
            .iter()
            .zip(capacities)
            .map(|(t, c)| t * c)
            .sum::<f64>()
            / total;
        let mode = |x: f64| (std::f64::consts::PI * x / length).cos();
        let projection: f64 = (0..temperatures.len())
            .map(|i| capacities[i] * (temperatures[i] - mean) * mode(along[i]))
            .sum();
        let norm: f64 = (0..temperatures.len())
            .map(|i| capacities[i] * mode(along[i]).powi(2))
            .sum();
        projection / norm
    }

    /// The amplitude ratio after `time` of forward Euler from `T0 + A cos(π x / L)` with
    /// lumped capacities, at half the stable step.
    fn decay(mesh: &Mesh, cells: &[CellConduction], along: &[f64], length: f64, time: f64) -> f64 {
        let dz = 0.5;
        let k = (K_WARP * dz, K_WEFT * dz);
        let capacities = capacities(mesh, RHO_C * dz);
        let mut temperatures: Vec<f64> = along
            .iter()
            .map(|&x| 180.0 + 20.0 * (std::f64::consts::PI * x / length).cos())
            .collect();
        let start = amplitude(&temperatures, along, &capacities, length);
        let limit = stable_step(cells, |_| k, &capacities);
        let steps = (time / (0.5 * limit)).ceil();
        let dt = time / steps;
        let mut rates = vec![0.0; temperatures.len()];
        for _ in 0..steps as usize {
            rates.fill(0.0);
            add_heat_rates(cells, |_| k, &temperatures, &mut rates);
            for ((t, r), c) in temperatures.iter_mut().zip(&rates).zip(&capacities) {
                *t += dt * r / c;
            }
        }
        amplitude(&temperatures, along, &capacities, length) / start
    }

    /// Runs [`decay`] over the time the analytic amplitude `exp(-α (π/L)^2 t)` halves, for
    /// the mesh as given and turned rigidly into 3D; returns the relative errors.
    fn strip_errors(
        mesh: &Mesh,
        yarns: &[(Vector3<f64>, Vector3<f64>)],
        conductivity: f64,
    ) -> [f64; 2] {
        let length = 100.0;
        let rate = conductivity / RHO_C * (std::f64::consts::PI / length).powi(2);
        let time = std::f64::consts::LN_2 / rate;
        let analytic = (-rate * time).exp();
        let along: Vec<f64> = mesh.positions.iter().map(|p| p.x).collect();
        let rotation = Rotation3::from_axis_angle(&Unit::new_normalize(v(-1.0, 2.0, 0.5)), 2.1);
        let turned = Mesh {
            positions: mesh.positions.iter().map(|p| rotation * p).collect(),
            cells: mesh.cells.clone(),
        };
        let flat = decay(mesh, &conduction(mesh, |c| yarns[c]), &along, length, time);
        let rotated = decay(
            &turned,
            &conduction(&turned, |c| (rotation * yarns[c].0, rotation * yarns[c].1)),
            &along,
            length,
            time,
        );
        [flat, rotated].map(|ratio| ratio / analytic - 1.0)
    }

    /// THE STRIP CHECK. A strip of length 100 mm with insulated ends, from
    /// `T0 + A cos(π x / L)`, decays as `exp(-α (π/L)^2 t)`, `α = k / (rho c)`:
    ///
    /// - on a tube along x (a strip closed on itself across its width), `T(x)` meets no side
    ///   edge and `k = k_xx = k_warp cos²φ + k_weft sin²φ`;
    /// - on a flat strip with insulated side edges, `q_y = 0` there, so the field turns to
    ///   `T_y = -(k_xy / k_yy) T_x`, which leaves `k = k_xx - k_xy² / k_yy =
    ///   k_warp k_weft / (k_warp sin²φ + k_weft cos²φ)` (exactly: `cos(p x + s y)` with
    ///   `s = -p k_xy / k_yy` meets the side conditions on any width); for φ = 0 or 90° the
    ///   two agree.
    #[test]
    fn a_cosine_along_a_strip_decays_at_the_conductivity_along_it() {
        let mut worst: f64 = 0.0;
        for phi_degrees in [0.0, 30.0, 90.0] {
            let phi = f64::to_radians(phi_degrees);
            let (c2, s2) = (phi.cos().powi(2), phi.sin().powi(2));
            let k_xx = K_WARP * c2 + K_WEFT * s2;
            let k_strip = K_WARP * K_WEFT / (K_WARP * s2 + K_WEFT * c2);
            for quads in [false, true] {
                let strip = grid(50, 2, 100.0, 4.0, quads);
                let yarns = vec![ply(phi, Vector3::x(), Vector3::y()); strip.cells.len()];
                let strip_error = strip_errors(&strip, &yarns, k_strip);
                let around = 6;
                let closed = tube(50, around, 100.0, 2.0, quads);
                let yarns: Vec<_> = closed
                    .cells
                    .iter()
                    .map(|cell| {
                        let (p, q) = (
                            closed.positions[cell[0]],
                            closed.positions[cell[cell.len() - 1]],
                        );
                        let across = v(0.0, q.y - p.y, q.z - p.z).normalize();
                        ply(phi, Vector3::x(), across)
                    })
                    .collect();
                let tube_error = strip_errors(&closed, &yarns, k_xx);
                println!(
                    "φ = {phi_degrees}°, quads {quads}: strip error {:+.2e} (turned {:+.2e}), \
                     tube error {:+.2e} (turned {:+.2e})",
                    strip_error[0], strip_error[1], tube_error[0], tube_error[1]
                );
                for error in strip_error.into_iter().chain(tube_error) {
                    assert!(
                        error.abs() < 0.01,
                        "φ = {phi_degrees}°, quads {quads}: {error:e}"
                    );
                }
                assert!((strip_error[0] - strip_error[1]).abs() < 1e-9);
                assert!((tube_error[0] - tube_error[1]).abs() < 1e-9);
                worst = worst.max(strip_error[0].abs()).max(tube_error[0].abs());
            }
        }
        println!("worst relative error {worst:.2e}");
    }

    /// Cells sheared so that the yarns make 60°, with the weft not conducting, conduct along
    /// the warp's current direction only: a field constant along it exchanges no heat, while
    /// one varying along it does. The same holds for the weft alone, on a tilted plane too.
    #[test]
    fn sheared_yarns_conduct_along_their_current_directions() {
        let shear = 60f64.to_radians();
        // F maps the reference yarns x and y onto â = x and b̂ at 60° from it.
        let f = Matrix3::new(1.0, shear.cos(), 0.0, 0.0, shear.sin(), 0.0, 0.0, 0.0, 1.0);
        let tilt = Rotation3::from_axis_angle(&Unit::new_normalize(v(0.3, -1.0, 0.8)), 0.9);
        for quads in [false, true] {
            let reference = grid(3, 3, 3.0, 3.0, quads);
            for turn in [Rotation3::identity(), tilt] {
                let mesh = Mesh {
                    positions: reference.positions.iter().map(|p| turn * f * p).collect(),
                    cells: reference.cells.clone(),
                };
                let normal = turn * Vector3::z();
                let (warp, weft) = (turn * f * Vector3::x(), turn * f * Vector3::y());
                let angle = warp.angle(&weft).to_degrees();
                assert!((angle - 60.0).abs() < 1e-9, "{angle}");
                // Yarn vectors a little out of the plane and not unit: projected, normalised.
                let cells = conduction(&mesh, |_| (warp * 2.0 + normal * 0.3, weft * 0.5 - normal));
                for (yarn, other, k) in [(warp, weft, (2.0, 0.0)), (weft, warp, (0.0, 2.0))] {
                    let across = normal.cross(&yarn).normalize();
                    let constant_along: Vec<f64> = mesh
                        .positions
                        .iter()
                        .map(|p| 50.0 + 7.0 * across.dot(p))
                        .collect();
                    let varying_along: Vec<f64> = mesh
                        .positions
                        .iter()
                        .map(|p| 50.0 + 7.0 * yarn.normalize().dot(p))
                        .collect();
                    let still = rates(&cells, k, &constant_along);
                    let moving = rates(&cells, k, &varying_along);
                    let scale = moving.iter().fold(0.0, |m: f64, r| m.max(r.abs()));
                    assert!(scale > 1.0, "a gradient along the yarn moves heat: {scale}");
                    for rate in still {
                        assert!(rate.abs() <= 1e-12 * scale, "{rate:e} across {other:?}");
                    }
                }
            }
        }
    }

    /// Dense `K` of a mesh, for checks.
    fn assembled(cells: &[CellConduction], k: (f64, f64), nodes: usize) -> DMatrix<f64> {
        let mut global = DMatrix::zeros(nodes, nodes);
        for cell in cells {
            let local = cell.conductance(k.0, k.1);
            for (a, &i) in cell.corners().iter().enumerate() {
                for (b, &j) in cell.corners().iter().enumerate() {
                    global[(i, j)] += local[a][b];
                }
            }
        }
        global
    }

    #[test]
    fn the_stable_step_bounds_the_fastest_mode() {
        let k = (K_WARP * 0.5, K_WEFT * 0.5);
        for quads in [false, true] {
            for (seed, phi) in [(3, 0.0), (4, 30.0), (5, 75.0)] {
                let mesh = irregular(5, 4, 10.0, 6.0, quads, seed);
                let (warp, weft) = ply(f64::to_radians(phi), Vector3::x(), Vector3::y());
                let cells = conduction(&mesh, |_| (warp, weft));
                let capacities = capacities(&mesh, RHO_C * 0.5);
                let dt = stable_step(&cells, |_| k, &capacities);
                // λ_max of C^-1 K, from the symmetric C^-1/2 K C^-1/2.
                let n = capacities.len();
                let scaling = DMatrix::from_fn(n, n, |i, j| {
                    if i == j {
                        1.0 / capacities[i].sqrt()
                    } else {
                        0.0
                    }
                });
                let symmetric = &scaling * assembled(&cells, k, n) * &scaling;
                let eigen = symmetric.symmetric_eigenvalues();
                let fastest = eigen.iter().fold(0.0, |m: f64, &e| m.max(e));
                let slowest = eigen.iter().fold(f64::INFINITY, |m: f64, &e| m.min(e));
                assert!(
                    slowest > -1e-12 * fastest,
                    "K is positive semi-definite: {slowest:e}"
                );
                let limit = 2.0 / fastest;
                println!(
                    "quads {quads}, φ {phi}°: stable_step / (2 / λ_max) = {:.3}",
                    dt / limit
                );
                assert!(dt <= limit * (1.0 + 1e-12), "{dt} above {limit}");
                assert!(dt >= 0.25 * limit, "{dt} far below {limit}");
            }
        }
    }

    #[test]
    fn the_stable_step_without_conduction_is_unbounded_and_without_capacity_zero() {
        let mesh = grid(2, 2, 2.0, 2.0, true);
        let cells = conduction(&mesh, |_| (Vector3::x(), Vector3::y()));
        let mut capacities = capacities(&mesh, RHO_C);
        assert_eq!(
            stable_step(&cells, |_| (0.0, 0.0), &capacities),
            f64::INFINITY
        );
        assert_eq!(stable_step(&[], |_| (1.0, 1.0), &capacities), f64::INFINITY);
        assert!(stable_step(&cells, |_| (1.0, 0.0), &capacities) > 0.0);
        assert_eq!(stable_step(&cells, |_| (-1.0, 0.0), &capacities), 0.0);
        assert_eq!(stable_step(&cells, |_| (f64::NAN, 0.0), &capacities), 0.0);
        capacities[4] = 0.0;
        assert_eq!(stable_step(&cells, |_| (1.0, 0.0), &capacities), 0.0);
    }

    #[test]
    fn heat_rates_are_minus_k_t_and_add_up_to_nothing() {
        let mesh = irregular(4, 3, 8.0, 6.0, true, 9);
        let mut random = Lcg(11);
        let yarns: Vec<_> = mesh
            .cells
            .iter()
            .map(|_| (random.vector(), random.vector()))
            .collect();
        let cells = conduction(&mesh, |c| yarns[c]);
        let temperatures: Vec<f64> = mesh
            .positions
            .iter()
            .map(|_| 150.0 + 30.0 * random.next())
            .collect();
        let k = (2.5, 0.5);
        let got = rates(&cells, k, &temperatures);
        let expected = -assembled(&cells, k, temperatures.len())
            * DMatrix::from_column_slice(temperatures.len(), 1, &temperatures);
        let scale = got.iter().fold(0.0, |m: f64, r| m.max(r.abs()));
        for (g, e) in got.iter().zip(expected.iter()) {
            assert!((g - e).abs() <= 1e-10 * scale, "{g} against {e}");
        }
        let total: f64 = got.iter().sum();
        assert!(
            total.abs() <= 1e-13 * scale,
            "heat made from nothing: {total:e}"
        );
        let uniform = rates(&cells, k, &vec![180.0; temperatures.len()]);
        assert!(uniform.iter().all(|&r| r == 0.0));
    }
}
