//! Rotation-free bending of the sheet (docs/model.md §4, bending), in the family of the
//! rotation-free shell triangles of Phaal & Calladine 1992 and Oñate & Zárate 2000: the
//! curvature of each element is read off the positions of the nodes around it.
//!
//! A quadrilateral's curvature is the mean of the interpolating patches of the four triangles
//! its corners make **(choice)**, see `BendingPatch::quadrilateral`: it reproduces any
//! quadratic surface exactly, sees the cell's own warp (a fold across either diagonal) as
//! twist, and has no preferred diagonal. The rest of this page is the triangle's.
//!
//! The heights of six nodes above a triangle's current plane, `w_i = (x_i - x_0) . n`, are
//! interpolated by a quadratic in the triangle's reference in-plane coordinates `(X, Y)`, and
//! the quadratic's second derivatives are the triangle's curvature,
//! `kappa = (w_XX, w_YY, w_XY) = G w`, `G` fixed by the reference geometry. The six nodes are
//! the triangle's corners and the three nodes of its 1-ring (the nodes of the triangles that
//! touch it) that interpolate best: the largest smallest singular value of the interpolation
//! matrix, over the ring's nearest eight nodes **(choice)**. The classical choice, the corners
//! opposite its edges, fails on crossed cells: five of those six points lie on the two cell
//! diagonals. Any quadratic surface is reproduced exactly, on the boundary too, where the
//! choice is one-sided.
//!
//! Known limitation, measured in `tests/bending.rs`: on meshes with valence-4 nodes (crossed and
//! alternating cells) the patches leave a soft pattern (the cell centres moving against the
//! corners) into which a buckling strip relaxes: its Euler load comes out at 0.56 (crossed) and
//! 0.90 (alternating) of the exact one, against 0.96–1.03 on single-diagonal cells and on a
//! static rolled sheet within `0.5 (h/R)^2` on all three. Mesh blanks that bend with single
//! diagonals (or unstructured triangles, whose nodes have valence about 6).
//!
//! In the fibre frame `(a0, b0)` of the triangle the energy per unit reference area is
//! orthotropic, without warp–weft coupling:
//!
//! `W = 1/2 (B_warp k_aa^2 + B_weft k_bb^2 + 2 B_twist k_ab^2)`, `k = kappa - kappa0`,
//!
//! with `kappa0` the curvature of the reference mesh and `B_twist = (B_warp + B_weft) / 2`
//! **(choice)** (an isotropic card is then the plate without Poisson coupling). `B` is a
//! bending rigidity per unit width (N·mm), as measured by cantilever (Peirce) tests; for
//! prepregs it is far below `E t^3 / 12` because the yarns slide in the molten matrix.
//! Forces are `dW/dx` of the patch nodes, including the turn of the triangle's normal.

use super::MembraneElement;
use crate::mesh::Mesh;
use nalgebra::{DMatrix, Matrix2, Matrix3, Matrix6, Vector2, Vector3};
use rayon::prelude::*;
use std::collections::HashMap;

/// Bending rigidities per unit width (N·mm) for curvature along the warp and along the weft.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BendingRigidity {
    pub warp: f64,
    pub weft: f64,
}

impl BendingRigidity {
    /// `B_twist`, see the module documentation.
    pub fn twist(&self) -> f64 {
        0.5 * (self.warp + self.weft)
    }

    /// Checks that both are finite and not negative.
    pub fn validate(&self) -> Result<(), BendingError> {
        for (name, value) in [("warp", self.warp), ("weft", self.weft)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(BendingError::Rigidity { name, value });
            }
        }
        Ok(())
    }
}

/// Why the bending of a mesh cannot be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BendingError {
    #[error(
        "triangles {first} and {second} run their shared edge {a}-{b} the same way: the mesh \
         is not consistently oriented"
    )]
    Orientation {
        first: usize,
        second: usize,
        a: usize,
        b: usize,
    },
    #[error("edge {a}-{b} is shared by more than two triangles")]
    NonManifold { a: usize, b: usize },
    #[error("bending rigidity {name} = {value} must be a finite number >= 0 (N·mm)")]
    Rigidity { name: &'static str, value: f64 },
    #[error(
        "element {0}: the nodes around it cannot carry a quadratic (fewer than six, or all on \
         a conic)"
    )]
    SingularPatch(usize),
}

/// The bending patch of one element.
#[derive(Clone, Debug, PartialEq)]
pub struct BendingPatch {
    /// Patch nodes: the element's corners first, then its 1-ring.
    pub nodes: Vec<usize>,
    /// Column `i` of `G`: what the height of patch node `i` adds to `(w_XX, w_YY, w_XY)`.
    pub curvature_operator: Vec<Vector3<f64>>,
    /// Reference curvature `(kappa_XX, kappa_YY, kappa_XY)` (1/mm).
    pub rest_curvature: Vector3<f64>,
    /// Warp and weft in the local reference basis `(X, Y)`.
    pub warp: Vector2<f64>,
    pub weft: Vector2<f64>,
    /// Reference area (mm^2) and smallest altitude (mm).
    pub area: f64,
    pub altitude: f64,
    /// The rigidity of the element's ply.
    pub rigidity: BendingRigidity,
}

/// The bending stiffness of a sheet: one patch per element.
#[derive(Clone, Debug, PartialEq)]
pub struct Bending {
    pub patches: Vec<BendingPatch>,
}

impl Bending {
    /// The bending of `mesh`, whose membrane triangles are `elements` (local bases and fibre
    /// directions) with rigidities `rigidity[k]`, with the reference curvature of the mesh as
    /// rest state.
    pub fn new(
        mesh: &Mesh,
        elements: &[MembraneElement],
        rigidity: &[BendingRigidity],
    ) -> Result<Self, BendingError> {
        for r in rigidity {
            r.validate()?;
        }
        check_manifold(mesh)?;
        let around = elements_around_nodes(mesh);
        let patches: Vec<Option<BendingPatch>> = elements
            .par_iter()
            .enumerate()
            .map(|(k, e)| BendingPatch::new(mesh, e, patch_nodes(mesh, &around, k), rigidity[k]))
            .collect();
        // in order, so that of several singular patches the same one is named on any thread
        // count
        let patches = patches
            .into_iter()
            .enumerate()
            .map(|(k, t)| t.ok_or(BendingError::SingularPatch(k)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { patches })
    }

    /// Bending energy of triangle `t` (N·mm) and its forces `dW/dx` on its patch nodes,
    /// written to `forces` (as many as the patch has nodes).
    pub fn forces(&self, t: &BendingPatch, x: &[Vector3<f64>], forces: &mut [Vector3<f64>]) -> f64 {
        self.forces_with(t, &t.rigidity, x, forces)
    }

    /// [`Self::forces`] with the rigidity `b` instead of the patch's own: that of the ply at
    /// its current temperature in a non-isothermal run (docs/model.md §9).
    pub fn forces_with(
        &self,
        t: &BendingPatch,
        b: &BendingRigidity,
        x: &[Vector3<f64>],
        forces: &mut [Vector3<f64>],
    ) -> f64 {
        let frame = CurrentPlane::of(t, x);
        let k = t.curvature(&frame, x) - t.rest_curvature;
        let (energy, dw_dk) = self.energy_and_moments(t, b, &k);
        forces.fill(Vector3::zeros());
        let mut lever = Vector3::zeros();
        // the corners' heights are zero whatever they do: only the 1-ring's count
        for i in 3..t.nodes.len() {
            let dw = t.curvature_operator[i].dot(&dw_dk);
            forces[i] += frame.normal * dw;
            forces[0] -= frame.normal * dw;
            lever += (x[t.nodes[i]] - frame.origin) * dw;
        }
        for (f, g) in forces.iter_mut().zip(frame.normal_gradient(&lever)) {
            *f += g;
        }
        energy
    }

    /// Tangent stiffness of patch `t` at `x`, `d forces / dx` over its nodes (3 rows and
    /// columns per node, in patch order): its Gauss–Newton part `J^T H J`, `J = dk/dx` the
    /// curvature's Jacobian (the normal's turn included) and `H = d^2 W / dk^2`, positive
    /// semi-definite; with `exact`, plus the moments times the curvature's second derivative,
    /// which the Gauss–Newton part leaves out (small next to it while the heights over the
    /// patch are small against its size, docs/solver.md).
    pub fn stiffness(&self, t: &BendingPatch, x: &[Vector3<f64>], exact: bool) -> DMatrix<f64> {
        self.stiffness_with(t, &t.rigidity, x, exact)
    }

    /// [`Self::stiffness`] with the rigidity `b` instead of the patch's own.
    pub fn stiffness_with(
        &self,
        t: &BendingPatch,
        b: &BendingRigidity,
        x: &[Vector3<f64>],
        exact: bool,
    ) -> DMatrix<f64> {
        let size = 3 * t.nodes.len();
        let frame = CurrentPlane::of(t, x);
        // J: row m the gradient of curvature component m
        let mut jacobian = DMatrix::<f64>::zeros(3, size);
        for m in 0..3 {
            let mut lever = Vector3::zeros();
            for i in 3..t.nodes.len() {
                let g = t.curvature_operator[i][m];
                for d in 0..3 {
                    jacobian[(m, 3 * i + d)] += g * frame.normal[d];
                    jacobian[(m, d)] -= g * frame.normal[d];
                }
                lever += (x[t.nodes[i]] - frame.origin) * g;
            }
            for (c, g) in frame.normal_gradient(&lever).iter().enumerate() {
                for d in 0..3 {
                    jacobian[(m, 3 * c + d)] += g[d];
                }
            }
        }
        let h = self.curvature_hessian(t, b);
        let mut stiffness = jacobian.transpose() * h * jacobian;
        if exact {
            let k = t.curvature(&frame, x) - t.rest_curvature;
            let moments = self.energy_and_moments(t, b, &k).1;
            add_moment_stiffness(t, x, &frame, &moments, &mut stiffness);
        }
        stiffness
    }

    /// `d^2 (A W) / dk^2`, constant: the energy is quadratic in the curvature change.
    fn curvature_hessian(&self, t: &BendingPatch, b: &BendingRigidity) -> Matrix3<f64> {
        let mut h = Matrix3::zeros();
        for m in 0..3 {
            let mut unit = Vector3::zeros();
            unit[m] = 1.0;
            h.set_column(m, &self.energy_and_moments(t, b, &unit).1);
        }
        h
    }

    /// Bending energy of triangle `t` (N·mm).
    pub fn energy(&self, t: &BendingPatch, x: &[Vector3<f64>]) -> f64 {
        self.energy_with(t, &t.rigidity, x)
    }

    /// [`Self::energy`] with the rigidity `b` instead of the patch's own.
    pub fn energy_with(&self, t: &BendingPatch, b: &BendingRigidity, x: &[Vector3<f64>]) -> f64 {
        let frame = CurrentPlane::of(t, x);
        let k = t.curvature(&frame, x) - t.rest_curvature;
        self.energy_and_moments(t, b, &k).0
    }

    /// `A W(k)` and `A dW/dk` for the curvature change `k = (k_XX, k_YY, k_XY)` with the
    /// rigidity `b`.
    fn energy_and_moments(
        &self,
        t: &BendingPatch,
        b: &BendingRigidity,
        k: &Vector3<f64>,
    ) -> (f64, Vector3<f64>) {
        let kappa = Matrix2::new(k.x, k.z, k.z, k.y);
        let (aa, bb, ab) = (
            t.warp.dot(&(kappa * t.warp)),
            t.weft.dot(&(kappa * t.weft)),
            t.warp.dot(&(kappa * t.weft)),
        );
        let energy =
            0.5 * t.area * (b.warp * aa * aa + b.weft * bb * bb + 2.0 * b.twist() * ab * ab);
        // d(a.kappa.a)/dk = (a_X^2, a_Y^2, 2 a_X a_Y), d(a.kappa.b)/dk = (aX bX, aY bY, aX bY + aY bX)
        let (a, c) = (&t.warp, &t.weft);
        let d_aa = Vector3::new(a.x * a.x, a.y * a.y, 2.0 * a.x * a.y);
        let d_bb = Vector3::new(c.x * c.x, c.y * c.y, 2.0 * c.x * c.y);
        let d_ab = Vector3::new(a.x * c.x, a.y * c.y, a.x * c.y + a.y * c.x);
        let moments =
            (d_aa * (b.warp * aa) + d_bb * (b.weft * bb) + d_ab * (2.0 * b.twist() * ab)) * t.area;
        (energy, moments)
    }

    /// A bound of the stable step of the bending modes of triangle `t` on a mass per unit area
    /// `m`: a patch node moved by `u` curves the triangle by about `|G| u ~ 4 u / h^2` (`h` the
    /// smallest altitude); about six patches share a node, so its stiffness is at most about
    /// `6 x 16 B A / h^4` on a lumped mass of at least `m A / 3`: `omega^2 <= 288 B / (m h^4)`,
    /// `dt = 2 / omega` (the buckling test runs with it at a safety of 0.9).
    pub fn stable_step(&self, t: &BendingPatch, mass_per_area: f64) -> f64 {
        self.stable_step_with(t, &t.rigidity, mass_per_area)
    }

    /// [`Self::stable_step`] with the rigidity `rigidity` instead of the patch's own.
    pub fn stable_step_with(
        &self,
        t: &BendingPatch,
        rigidity: &BendingRigidity,
        mass_per_area: f64,
    ) -> f64 {
        let b = rigidity.warp.max(rigidity.weft);
        let omega_sq = 288.0 * b / (mass_per_area * t.altitude.powi(4));
        if omega_sq > 0.0 {
            2.0 / omega_sq.sqrt()
        } else {
            f64::INFINITY
        }
    }
}

impl BendingPatch {
    /// The patch of membrane triangle `e` on `nodes` (its corners first); `None` when the
    /// patch admits no unique quadratic (fewer than six nodes, or all on a conic).
    fn new(
        mesh: &Mesh,
        e: &MembraneElement,
        ring: Vec<usize>,
        rigidity: BendingRigidity,
    ) -> Option<Self> {
        if e.cell.is_quad() {
            return Self::quadrilateral(mesh, e, ring, rigidity);
        }
        // the corners stay among the candidates (never chosen: they would repeat a point), as
        // the interpolation was first measured
        let candidates: Vec<usize> = e.nodes().iter().copied().chain(ring).collect();
        let corners = [e.nodes()[0], e.nodes()[1], e.nodes()[2]];
        let (nodes, curvature_operator) = interpolation(mesh, e, corners, &candidates)?;
        Some(Self::at_rest(
            mesh,
            e,
            (nodes, curvature_operator),
            rigidity,
        ))
    }

    /// The patch of quadrilateral `e`: the mean of the interpolating patches of the four
    /// triangles its corners make (`abc`, `bcd`, `cda`, `dab`), each on its three corners and
    /// the three points of the quadrilateral's 1-ring (the fourth corner included) that
    /// interpolate best. Each reproduces any quadratic, so their mean does; taking all four
    /// keeps either diagonal from being preferred. A least-squares quadratic over the 1-ring
    /// was tried first and fails: it is blind to a zigzag `w = (-1)^i` along a row of cells
    /// (the four columns of a patch fit it with no quadratic part), into which a compressed
    /// strip relaxes at 0.16 of the Euler load.
    fn quadrilateral(
        mesh: &Mesh,
        e: &MembraneElement,
        ring: Vec<usize>,
        rigidity: BendingRigidity,
    ) -> Option<Self> {
        let q = e.nodes();
        let nodes: Vec<usize> = q.iter().copied().chain(ring.iter().copied()).collect();
        let mut operator = vec![Vector3::zeros(); nodes.len()];
        for k in 0..4 {
            let corners = [q[k], q[(k + 1) % 4], q[(k + 2) % 4]];
            let (patch, columns) = interpolation(mesh, e, corners, &nodes)?;
            for (node, column) in patch.iter().zip(columns) {
                let place = nodes.iter().position(|n| n == node)?;
                operator[place] += column / 4.0;
            }
        }
        // ring nodes no sub-triangle chose carry nothing
        let (nodes, operator): (Vec<usize>, Vec<Vector3<f64>>) = nodes
            .into_iter()
            .zip(operator)
            .enumerate()
            .filter(|(i, (_, g))| *i < 4 || g.norm() > 0.0)
            .map(|(_, kept)| kept)
            .unzip();
        Some(Self::at_rest(mesh, e, (nodes, operator), rigidity))
    }

    /// The patch on `nodes` with the operator `G`, its rest curvature that of the reference
    /// mesh.
    fn at_rest(
        mesh: &Mesh,
        e: &MembraneElement,
        (nodes, curvature_operator): (Vec<usize>, Vec<Vector3<f64>>),
        rigidity: BendingRigidity,
    ) -> Self {
        let mut patch = Self {
            nodes,
            curvature_operator,
            rest_curvature: Vector3::zeros(),
            warp: Vector2::new(e.fibres.warp.x, e.fibres.warp.y),
            weft: Vector2::new(e.fibres.weft.x, e.fibres.weft.y),
            area: e.area,
            altitude: e.altitude,
            rigidity,
        };
        let frame = CurrentPlane::of(&patch, &mesh.nodes);
        patch.rest_curvature = patch.curvature(&frame, &mesh.nodes);
        patch
    }

    /// `G w` for the heights above `frame`.
    fn curvature(&self, frame: &CurrentPlane, x: &[Vector3<f64>]) -> Vector3<f64> {
        self.nodes
            .iter()
            .zip(&self.curvature_operator)
            .skip(3)
            .map(|(&n, g)| g * (x[n] - frame.origin).dot(&frame.normal))
            .sum()
    }
}

/// The current plane of a triangle: a corner, the unit normal, and what the normal's
/// derivative needs.
struct CurrentPlane {
    origin: Vector3<f64>,
    normal: Vector3<f64>,
    /// `x1 - x0`, `x2 - x0` and `|N|`, `N = (x1 - x0) x (x2 - x0)`.
    edges: [Vector3<f64>; 2],
    norm: f64,
}

impl CurrentPlane {
    fn of(t: &BendingPatch, x: &[Vector3<f64>]) -> Self {
        let (x0, x1, x2) = (x[t.nodes[0]], x[t.nodes[1]], x[t.nodes[2]]);
        let edges = [x1 - x0, x2 - x0];
        let n = edges[0].cross(&edges[1]);
        let norm = n.norm();
        Self {
            origin: x0,
            normal: n / norm,
            edges,
            norm,
        }
    }

    /// `A_c` with `dN = sum_c A_c dx_c`: `A_0 = [e2 - e1]x`, `A_1 = -[e2]x`, `A_2 = [e1]x`.
    fn cross_operators(&self) -> [Matrix3<f64>; 3] {
        let [e1, e2] = self.edges;
        [
            (e2 - e1).cross_matrix(),
            -e2.cross_matrix(),
            e1.cross_matrix(),
        ]
    }

    /// `d(v . n)/dx` for the three corners at fixed `v`: with `u = (I - n n^T) v / |N|`,
    /// `v . dn = u . dN` and `dN = dx1 x e2 + e1 x dx2 + dx0 x (e1 - e2)`.
    fn normal_gradient(&self, v: &Vector3<f64>) -> [Vector3<f64>; 3] {
        let projector = Matrix3::identity() - self.normal * self.normal.transpose();
        let u = projector * v / self.norm;
        let [e1, e2] = self.edges;
        [(e1 - e2).cross(&u), e2.cross(&u), u.cross(&e1)]
    }
}

/// Adds `sum_m M_m d^2 k_m / dx^2` to `stiffness`, `M = dW/dk` the moments: the Hessian of
/// `phi = v . n` at fixed `M`, with `v = sum_a w_a x_a`, `w_i = G_i . M` on the 1-ring,
/// `w_0 = -sum_i w_i` and `n` the unit normal of the corners. Block `(a, b)` is
/// `w_b J_a^T + w_a J_b + Q_ab`, `J_c = dn/dx_c` (zero off the corners) and `Q_ab` the second
/// derivative of `v . n` at fixed `v` over the corners (docs/solver.md, "Bending tangent").
fn add_moment_stiffness(
    t: &BendingPatch,
    x: &[Vector3<f64>],
    frame: &CurrentPlane,
    moments: &Vector3<f64>,
    stiffness: &mut DMatrix<f64>,
) {
    let nodes = t.nodes.len();
    let mut weights = vec![0.0; nodes];
    let mut lever = Vector3::zeros();
    for i in 3..nodes {
        weights[i] = t.curvature_operator[i].dot(moments);
        weights[0] -= weights[i];
        lever += (x[t.nodes[i]] - frame.origin) * weights[i];
    }
    let mut add = |a: usize, b: usize, block: &Matrix3<f64>| {
        let mut view = stiffness.fixed_view_mut::<3, 3>(3 * a, 3 * b);
        view += block;
    };
    let cross = frame.cross_operators();
    let projector = Matrix3::identity() - frame.normal * frame.normal.transpose();
    let normal_jacobians = cross.map(|a| projector * a / frame.norm);
    for (c, jc) in normal_jacobians.iter().enumerate() {
        for (m, &w) in weights.iter().enumerate() {
            if w != 0.0 {
                add(c, m, &(jc.transpose() * w));
                add(m, c, &(jc * w));
            }
        }
    }
    let pv = projector * lever;
    // u = P v / |N| as in `normal_gradient`, and du = du_dn dN
    let du_dn = -(pv * frame.normal.transpose()
        + frame.normal * pv.transpose()
        + projector * frame.normal.dot(&lever))
        / (frame.norm * frame.norm);
    let u = pv / frame.norm;
    let s = u.cross_matrix();
    // u . d^2N over (x_a, x_b) for N = (x1 - x0) x (x2 - x0)
    let second = [
        [Matrix3::zeros(), -s, s],
        [s, Matrix3::zeros(), -s],
        [-s, s, Matrix3::zeros()],
    ];
    for a in 0..3 {
        for b in 0..3 {
            add(
                a,
                b,
                &(second[a][b] + cross[a].transpose() * du_dn * cross[b]),
            );
        }
    }
}

/// The interpolating quadratic of the triangle on `corners` and the three of `candidates`
/// that interpolate best, in the local basis of `e`: the six nodes and the column of `G` of
/// each (what its height adds to `(w_XX, w_YY, w_XY)`, 1/mm).
fn interpolation(
    mesh: &Mesh,
    e: &MembraneElement,
    corners: [usize; 3],
    candidates: &[usize],
) -> Option<(Vec<usize>, Vec<Vector3<f64>>)> {
    let origin = mesh.nodes[corners[0]];
    // lengths scaled by the altitude, so that the interpolation matrix is of order one
    let scale = e.altitude;
    let local = |n: usize| {
        let d = mesh.nodes[n] - origin;
        Vector2::new(d.dot(&e.basis.column(0)), d.dot(&e.basis.column(1))) / scale
    };
    let corner_points = corners.map(local);
    let candidate_points: Vec<Vector2<f64>> = candidates.iter().map(|&n| local(n)).collect();
    let chosen = best_interpolation_points(&corner_points, &candidate_points)?;
    let points: [Vector2<f64>; 6] = std::array::from_fn(|i| {
        if i < 3 {
            corner_points[i]
        } else {
            candidate_points[chosen[i - 3]]
        }
    });
    let inverse = quadratic_basis(&points).try_inverse()?;
    // w_XX = 2 c3, w_YY = 2 c5, w_XY = c4, back in mm
    let s2 = scale * scale;
    let columns = (0..6)
        .map(|i| {
            Vector3::new(
                2.0 * inverse[(3, i)],
                2.0 * inverse[(5, i)],
                inverse[(4, i)],
            ) / s2
        })
        .collect();
    let nodes = corners
        .into_iter()
        .chain(chosen.iter().map(|&c| candidates[c]))
        .collect();
    Some((nodes, columns))
}

/// Rows `(1, X, Y, X^2, XY, Y^2)` of six points.
fn quadratic_basis(points: &[Vector2<f64>; 6]) -> Matrix6<f64> {
    Matrix6::from_fn(|i, j| {
        let p = points[i];
        [1.0, p.x, p.y, p.x * p.x, p.x * p.y, p.y * p.y][j]
    })
}

/// The three ring points that, with the corners, interpolate a quadratic best: the largest
/// smallest singular value of the interpolation matrix, over the triples of the nearest
/// [`RING_CANDIDATES`] ring points. `None` when every triple is singular.
fn best_interpolation_points(
    corners: &[Vector2<f64>; 3],
    ring: &[Vector2<f64>],
) -> Option<[usize; 3]> {
    let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
    let mut order: Vec<usize> = (0..ring.len()).collect();
    order.sort_by(|&a, &b| {
        (ring[a] - centroid)
            .norm()
            .total_cmp(&(ring[b] - centroid).norm())
    });
    order.truncate(RING_CANDIDATES);
    let mut best: Option<([usize; 3], f64)> = None;
    for (i, &a) in order.iter().enumerate() {
        for (j, &b) in order.iter().enumerate().skip(i + 1) {
            for &c in order.iter().skip(j + 1) {
                let points = [
                    corners[0], corners[1], corners[2], ring[a], ring[b], ring[c],
                ];
                let sigma = quadratic_basis(&points)
                    .singular_values()
                    .iter()
                    .fold(f64::INFINITY, |m, &v| m.min(v));
                if sigma > best.map_or(SINGULAR, |b| b.1) {
                    best = Some(([a, b, c], sigma));
                }
            }
        }
    }
    best.map(|b| b.0)
}

/// Ring points tried for the interpolation (the nearest ones to the triangle).
const RING_CANDIDATES: usize = 8;

/// Smallest singular value below which six (altitude-scaled) points are taken as on a conic.
const SINGULAR: f64 = 1e-6;

/// Refuses edges shared by more than two triangles, and neighbours that run their shared edge
/// the same way (the heights need one normal side for the whole sheet).
fn check_manifold(mesh: &Mesh) -> Result<(), BendingError> {
    let mut runs: HashMap<(usize, usize), usize> = HashMap::new();
    let mut uses: HashMap<(usize, usize), usize> = HashMap::new();
    for (t, cell) in mesh.cells.iter().enumerate() {
        for (a, b) in cell.edges() {
            let count = uses.entry((a.min(b), a.max(b))).or_default();
            *count += 1;
            if *count > 2 {
                return Err(BendingError::NonManifold { a, b });
            }
            if let Some(&first) = runs.get(&(a, b)) {
                return Err(BendingError::Orientation {
                    first,
                    second: t,
                    a,
                    b,
                });
            }
            runs.insert((a, b), t);
        }
    }
    Ok(())
}

/// The elements around each node.
fn elements_around_nodes(mesh: &Mesh) -> Vec<Vec<usize>> {
    let mut around = vec![Vec::new(); mesh.nodes.len()];
    for (t, cell) in mesh.cells.iter().enumerate() {
        for &n in cell.nodes() {
            around[n].push(t);
        }
    }
    around
}

/// The other nodes of every element that touches element `k`'s corners, sorted.
fn patch_nodes(mesh: &Mesh, around: &[Vec<usize>], k: usize) -> Vec<usize> {
    let corners = mesh.cells[k].nodes();
    let mut ring: Vec<usize> = corners
        .iter()
        .flat_map(|&c| {
            around[c]
                .iter()
                .flat_map(|&t| mesh.cells[t].nodes().to_vec())
        })
        .filter(|n| !corners.contains(n))
        .collect();
    ring.sort_unstable();
    ring.dedup();
    ring
}
