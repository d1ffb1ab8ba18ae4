//! Total-Lagrangian membrane elements carrying the laminate (docs/model.md §1, §4): the 3-node
//! triangle and the 4-node quadrilateral with one integration point and hourglass control.
//!
//! Both are evaluated at one point: `F = sum_a x_a (x) grad0 N_a` (3x2, from local reference
//! coordinates of the element's tangent plane to current 3D positions), and the internal nodal
//! forces are `f_a = A0 F N grad0 N_a` with `N` the laminate's membrane resultant. For the
//! triangle `grad0 N_a` is exact (constant strain); for the quadrilateral it is the bilinear
//! shape functions' gradient at the centre, `A0 = 4 det J(0)` its exact area, and the one point
//! sees two yarn constraints per element, as many as the element has in-plane degrees of
//! freedom: yarns at any angle to the edges do not lock it (docs/model.md §4, "Element
//! technology"). What the one point does not see, the in-plane hourglass mode, is held by the
//! stiffness [`Hourglass`]; the out-of-plane one (the cell folding across a diagonal) is left
//! to the bending.

use crate::material::FibreDirections;
use crate::mesh::Cell;
use nalgebra::{Matrix2, Matrix3, Matrix3x2, Vector2, Vector3};

/// Reference geometry of one element, computed once.
#[derive(Clone, Debug, PartialEq)]
pub struct MembraneElement {
    pub cell: Cell,
    /// Reference area `A0` (mm^2).
    pub area: f64,
    /// Gradients of the shape functions (at the centre for a quadrilateral) in the local
    /// reference basis `(e1, e2)`; the fourth is zero for a triangle.
    pub shape_gradients: [Vector2<f64>; 4],
    /// Warp and weft in the local basis.
    pub fibres: FibreDirections,
    /// The length that sets the element's stable time step (mm): the smallest altitude of a
    /// triangle, the area over the longer diagonal for a quadrilateral (the same for the
    /// square cell of two right triangles).
    pub altitude: f64,
    /// The local reference basis `(e1, e2)` as columns, in global coordinates.
    pub basis: Matrix3x2<f64>,
    /// Hourglass control of a quadrilateral; `None` for a triangle.
    pub hourglass: Option<Hourglass>,
}

/// The in-plane hourglass mode of a one-point quadrilateral (Flanagan & Belytschko 1981):
/// `q = sum_a gamma_a x_a`, with `gamma_a = (h_a - (h . X) grad0 N_a) / 4` and
/// `h = (1, -1, 1, -1)`, vanishes for every linear field (rigid motion and uniform strain), so
/// it takes nothing from the one-point response; `q` is the amplitude of the bilinear
/// displacement `u = q xi eta`. It is held by two energies (docs/model.md §4):
///
/// - shear: `1/2 k_s |q_t|^2`, `q_t` its part in the current tangent plane,
///   `k_s = (2/3) G t0 A0 sum_a |grad0 N_a|^2` with `G t0` the laminate's in-plane shear
///   stiffness at rest: what a fully integrated bilinear element gives the mode through shear;
/// - yarns, where they run along the cell's edges (within [`ALIGNED`]):
///   `1/2 sum_y E t0 Y_y (y . q)^2` over warp and weft, `y` the current yarn direction. The
///   mode stretches a yarn by `(y . q)(eta (a . grad xi) + xi (a . grad eta))`, which varies
///   across the yarn (a neighbouring parallel yarn, here the opposite edge, stretched more):
///   `Y_y = c_y^2 I_y`, `c_y = (a . grad xi)(n . grad eta) + (a . grad eta)(n . grad xi)`,
///   `I_y = int ((X - Xc) . n)^2 dA`, `a` the reference yarn, `n` normal to it in the plane:
///   the fully integrated element's yarn energy (the edges are yarns, as in the pin-jointed
///   net). Yarns that cross the edges get none: there the same constraint is not shared with
///   the neighbours and locks the element.
#[derive(Clone, Debug, PartialEq)]
pub struct Hourglass {
    pub gamma: [f64; 4],
    /// `(2/3) A0 sum_a |grad0 N_a|^2`: `k_s = G t0 x this`.
    pub shear_factor: f64,
    /// `Y_y` of the warp and of the weft (dimensionless: `E t0 Y_y` is in N/mm).
    pub yarn_factors: [f64; 2],
}

/// What holds the hourglass mode, per unit reference width (N/mm): the laminate's in-plane
/// shear stiffness `G t0` and its yarns' tension stiffness `E t0`, both at rest.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HourglassModuli {
    pub shear: f64,
    pub yarn: f64,
}

/// Sine of the largest angle between a yarn and the cell's edge directions for the yarn to be
/// taken as running along the edges (0.06°) **(choice)**: then the edges are yarns, as in the
/// pin-jointed net, and the hourglass's variation across the yarn is real; across the edges
/// any share of it locks the element (measured: with `Y` scaled by `cos^2(2 theta)`, a 30° ply
/// on the hemisphere sheared 20.4° against 27.9° for 0/90 and 26.9° for 45°).
const ALIGNED: f64 = 1e-3;

/// Why an element cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElementError {
    #[error("element is degenerate (area {area:e} mm^2)")]
    Degenerate { area: f64 },
    #[error("quadrilateral is not convex (a corner turns inwards, or the cell crosses itself)")]
    Folded,
    #[error(
        "the reference warp direction is normal to the element: it cannot be projected onto \
         the sheet"
    )]
    WarpNormalToSheet,
}

impl MembraneElement {
    /// An element on the cell `cell` of the reference nodes `x0`, with the warp along the
    /// projection of `warp_direction` (global) onto its plane and the weft at +90° about its
    /// normal.
    pub fn new(
        cell: Cell,
        x0: &[Vector3<f64>],
        warp_direction: &Vector3<f64>,
    ) -> Result<Self, ElementError> {
        let corners = cell.positions(x0);
        let area_vector = cell.area_vector(x0);
        let scale = (corners[1] - corners[0])
            .norm_squared()
            .max((corners[2] - corners[0]).norm_squared());
        let projected = area_vector.norm();
        if projected.is_nan() || projected <= 1e-12 * scale {
            return Err(ElementError::Degenerate { area: projected });
        }
        if cell.is_folded(x0) {
            return Err(ElementError::Folded);
        }
        let n = area_vector / projected;
        let e1 = (corners[1] - corners[0]).normalize();
        let e1 = (e1 - n * n.dot(&e1)).normalize();
        let e2 = n.cross(&e1);
        let centre = cell.centroid(x0);
        let local: Vec<Vector2<f64>> = corners
            .iter()
            .map(|x| Vector2::new((x - centre).dot(&e1), (x - centre).dot(&e2)))
            .collect();
        let in_plane = Vector2::new(warp_direction.dot(&e1), warp_direction.dot(&e2));
        if in_plane.norm() < 1e-6 * warp_direction.norm() {
            return Err(ElementError::WarpNormalToSheet);
        }
        let fibres = FibreDirections::in_plane(in_plane.y.atan2(in_plane.x));
        let (area, shape_gradients, altitude, hourglass) = match cell {
            Cell::Triangle(_) => triangle_geometry(&local),
            Cell::Quad(_) => quad_geometry(&local, &fibres),
        };
        Ok(Self {
            cell,
            area,
            shape_gradients,
            fibres,
            altitude,
            basis: Matrix3x2::from_columns(&[e1, e2]),
            hourglass,
        })
    }

    /// The corner nodes.
    pub fn nodes(&self) -> &[usize] {
        self.cell.nodes()
    }

    /// `F = sum_a x_a (x) grad0 N_a`; with velocities in place of positions, `Fdot`.
    pub fn gradient(&self, field: &[Vector3<f64>]) -> Matrix3x2<f64> {
        self.nodes()
            .iter()
            .zip(&self.shape_gradients)
            .fold(Matrix3x2::zeros(), |f, (&node, g)| {
                f + field[node] * g.transpose()
            })
    }

    /// Internal nodal forces `f_a = A0 F N grad0 N_a` (docs/model.md §4), in the order of the
    /// corners; the fourth is zero for a triangle.
    pub fn internal_forces(&self, f: &Matrix3x2<f64>, n: &Matrix2<f64>) -> [Vector3<f64>; 4] {
        let fn_area = f * n * self.area;
        self.shape_gradients.map(|g| fn_area * g)
    }

    /// Tangent stiffness `K_ab = d f_a / d x_b` of the one-point membrane forces
    /// (docs/solver.md, "Implicit", element tangent): `K_ab = A0 (B_a^T D B_b + (g_a . N g_b) I)`
    /// with `B_a` the map from `x_a` to the Green strain `(E11, E22, 2 E12)`,
    /// `B_a = [g_a1 F1^T; g_a2 F2^T; g_a1 F2^T + g_a2 F1^T]` (`F1`, `F2` the columns of `F`),
    /// `D = dN/dE` the laminate's tangent in the same order, and the second term the
    /// geometric stiffness of the resultant `N`. Blocks for the corners in order; the fourth
    /// row and column are zero for a triangle.
    pub fn stiffness(
        &self,
        f: &Matrix3x2<f64>,
        n: &Matrix2<f64>,
        d: &Matrix3<f64>,
    ) -> [[Matrix3<f64>; 4]; 4] {
        let (f1, f2) = (f.column(0).into_owned(), f.column(1).into_owned());
        let b: [Matrix3<f64>; 4] = self.shape_gradients.map(|g| {
            Matrix3::from_rows(&[
                (f1 * g.x).transpose(),
                (f2 * g.y).transpose(),
                (f2 * g.x + f1 * g.y).transpose(),
            ])
        });
        let corners = self.nodes().len();
        let mut k = [[Matrix3::zeros(); 4]; 4];
        for a in 0..corners {
            let bt_d = b[a].transpose() * d * self.area;
            for c in 0..corners {
                let geometric = self.shape_gradients[a].dot(&(n * self.shape_gradients[c]));
                k[a][c] = bt_d * b[c] + Matrix3::identity() * (geometric * self.area);
            }
        }
        k
    }

    /// Tangent stiffness of the hourglass forces ([`Self::hourglass_forces`]) at `x`: exact
    /// (`exact`; docs/solver.md, "Hourglass tangent"), or its Gauss–Newton part, positive
    /// semi-definite: `k_s gamma_a gamma_b (I - n n^T)` for the shear and
    /// `k_y (d(y.q)/dx_a) (d(y.q)/dx_b)^T` for the yarns, the turn of the normal and of the
    /// yarn left out. The yarns' exact part adds `k_y (y.q) d2(y.q)/dx_a dx_b`, with
    /// `y.q = (u.q)/|u|`, `u = F a0 = sum_a c_a x_a`, whose second derivatives are
    /// `(3 phi y y^T - phi I - q y^T - y q^T) / |u|^2` in `(u, u)` and `(I - y y^T) / |u|` in
    /// `(u, q)`. Zero for a triangle.
    pub fn hourglass_stiffness(
        &self,
        x: &[Vector3<f64>],
        moduli: &HourglassModuli,
        exact: bool,
    ) -> [[Matrix3<f64>; 4]; 4] {
        let mut k = [[Matrix3::zeros(); 4]; 4];
        let Some(hourglass) = &self.hourglass else {
            return k;
        };
        let corners: [Vector3<f64>; 4] = std::array::from_fn(|a| x[self.nodes()[a]]);
        let local = Self {
            cell: Cell::Quad([0, 1, 2, 3]),
            ..self.clone()
        };
        let q: Vector3<f64> = corners
            .iter()
            .zip(hourglass.gamma)
            .map(|(x, g)| x * g)
            .sum();
        let k_s = moduli.shear * hourglass.shear_factor;
        if exact {
            self.add_exact_shear_hessian(hourglass, &corners, &q, k_s, &mut k);
        } else {
            let area_vector = 0.5 * (corners[2] - corners[0]).cross(&(corners[3] - corners[1]));
            let n = area_vector
                .try_normalize(0.0)
                .unwrap_or_else(Vector3::zeros);
            let tangential = Matrix3::identity() - n * n.transpose();
            for (row, gamma_a) in k.iter_mut().zip(hourglass.gamma) {
                for (block, gamma_c) in row.iter_mut().zip(hourglass.gamma) {
                    *block = tangential * (k_s * gamma_a * gamma_c);
                }
            }
        }
        let f_centre = local.gradient(&corners);
        for (k_y, fibre, y, length) in self.hourglass_yarns(hourglass, &f_centre, moduli) {
            let y_q = y.dot(&q);
            let across = (q - y * y_q) / length;
            let c: [f64; 4] = std::array::from_fn(|a| self.shape_gradients[a].dot(&fibre.xy()));
            let d: [Vector3<f64>; 4] =
                std::array::from_fn(|a| y * hourglass.gamma[a] + across * c[a]);
            // phi = y . q = (u . q) / |u| with u = F a0 = sum_a c_a x_a: its second
            // derivatives in (u, u) and (u, q); none in (q, q)
            let (uu, uq) = if exact {
                let projector = Matrix3::identity() - y * y.transpose();
                let uu = (-(q * y.transpose() + y * q.transpose()) - Matrix3::identity() * y_q
                    + y * y.transpose() * (3.0 * y_q))
                    / (length * length);
                (uu, projector / length)
            } else {
                (Matrix3::zeros(), Matrix3::zeros())
            };
            for a in 0..4 {
                for b in 0..4 {
                    let curvature = uu * (c[a] * c[b])
                        + uq * (c[a] * hourglass.gamma[b] + hourglass.gamma[a] * c[b]);
                    k[a][b] += (d[a] * d[b].transpose() + curvature * y_q) * k_y;
                }
            }
        }
        k
    }

    /// The exact Hessian of the hourglass shear energy `1/2 k_s (|q|^2 - psi^2)`,
    /// `psi = n . q = (N . q) / |N|`, `N = (x2 - x0) x (x3 - x1) / 2` (docs/solver.md,
    /// "Hourglass tangent"): `k_s (gamma_a gamma_b I - dpsi_a dpsi_b^T - psi d2psi_ab)`, with
    /// `dpsi_a = gamma_a n + A_a^T v` (`A_a = dN/dx_a`, `v = (I - n n^T) q / |N|`) and
    /// `d2psi_ab = gamma_a P A_b / |N| + A_a^T P gamma_b / |N| + A_a^T H_NN A_b + v . d2N_ab`,
    /// `H_NN = (3 psi n n^T - psi I - q n^T - n q^T) / |N|^2`.
    fn add_exact_shear_hessian(
        &self,
        hourglass: &Hourglass,
        corners: &[Vector3<f64>; 4],
        q: &Vector3<f64>,
        k_s: f64,
        k: &mut [[Matrix3<f64>; 4]; 4],
    ) {
        let gamma = hourglass.gamma;
        let (d1, d2) = (corners[2] - corners[0], corners[3] - corners[1]);
        let area_vector = 0.5 * d1.cross(&d2);
        let size = area_vector.norm();
        let Some(n) = area_vector.try_normalize(0.0) else {
            for a in 0..4 {
                for b in 0..4 {
                    k[a][b] += Matrix3::identity() * (k_s * gamma[a] * gamma[b]);
                }
            }
            return;
        };
        let psi = n.dot(q);
        let projector = Matrix3::identity() - n * n.transpose();
        let v = projector * q / size;
        // dN/dx_a: d1 = x2 - x0, d2 = x3 - x1, dN = (dd1 x d2 + d1 x dd2) / 2
        let half_d1 = d1.cross_matrix() * 0.5;
        let half_d2 = d2.cross_matrix() * 0.5;
        let a_of = [half_d2, -half_d1, -half_d2, half_d1];
        let h_nn = (n * n.transpose() * (3.0 * psi)
            - Matrix3::identity() * psi
            - q * n.transpose()
            - n * q.transpose())
            / (size * size);
        // v . d2N / dd1 dd2 = -[v]x / 2, and its transpose for (d2, d1)
        let m12 = -v.cross_matrix() * 0.5;
        let (s1, s2) = ([-1.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 1.0]);
        let dpsi: [Vector3<f64>; 4] =
            std::array::from_fn(|a| n * gamma[a] + a_of[a].transpose() * v);
        let p_over = projector / size;
        for a in 0..4 {
            for b in 0..4 {
                let d2psi = p_over * a_of[b] * gamma[a]
                    + a_of[a].transpose() * p_over * gamma[b]
                    + a_of[a].transpose() * h_nn * a_of[b]
                    + m12 * (s1[a] * s2[b])
                    + m12.transpose() * (s2[a] * s1[b]);
                k[a][b] += (Matrix3::identity() * (gamma[a] * gamma[b])
                    - dpsi[a] * dpsi[b].transpose()
                    - d2psi * psi)
                    * k_s;
            }
        }
    }

    pub fn hourglass_forces(
        &self,
        x: &[Vector3<f64>],
        f: &Matrix3x2<f64>,
        moduli: &HourglassModuli,
        forces: &mut [Vector3<f64>; 4],
    ) -> f64 {
        match &self.hourglass {
            Some(hourglass) => self.hourglass_mode(hourglass, x, f, moduli, Some(forces)),
            None => 0.0,
        }
    }

    /// Energy of the hourglass mode at `x` (N·mm); zero for a triangle.
    pub fn hourglass_energy(&self, x: &[Vector3<f64>], moduli: &HourglassModuli) -> f64 {
        self.hourglass.as_ref().map_or(0.0, |hourglass| {
            self.hourglass_mode(hourglass, x, &self.gradient(x), moduli, None)
        })
    }

    /// The mode's energy, and where `forces` is given its gradient added to them.
    fn hourglass_mode(
        &self,
        hourglass: &Hourglass,
        x: &[Vector3<f64>],
        f_centre: &Matrix3x2<f64>,
        moduli: &HourglassModuli,
        mut forces: Option<&mut [Vector3<f64>; 4]>,
    ) -> f64 {
        let corners: [Vector3<f64>; 4] = std::array::from_fn(|a| x[self.nodes()[a]]);
        let q: Vector3<f64> = corners
            .iter()
            .zip(hourglass.gamma)
            .map(|(x, g)| x * g)
            .sum();
        let mut energy = 0.0;
        // shear: 1/2 k_s (|q|^2 - (n . q)^2), n the unit normal of N = (x2 - x0) x (x3 - x1) / 2
        let k_s = moduli.shear * hourglass.shear_factor;
        let (d1, d2) = (corners[2] - corners[0], corners[3] - corners[1]);
        let area_vector = 0.5 * d1.cross(&d2);
        let (n, n_q, size) = match area_vector.try_normalize(0.0) {
            Some(n) => (n, n.dot(&q), area_vector.norm()),
            None => (Vector3::zeros(), 0.0, 1.0),
        };
        energy += 0.5 * k_s * (q.norm_squared() - n_q * n_q);
        if let Some(f) = forces.as_deref_mut() {
            let q_t = q - n * n_q;
            // d(n . q)/dx through n: v . dN, v = (I - n n^T) q / |N|
            let v = q_t / size;
            let (dn_d1, dn_d2) = (0.5 * d2.cross(&v), 0.5 * v.cross(&d1));
            let turn = [-dn_d1, -dn_d2, dn_d1, dn_d2];
            for a in 0..4 {
                f[a] += q_t * (k_s * hourglass.gamma[a]) - turn[a] * (k_s * n_q);
            }
        }
        // yarns: 1/2 k_y (y . q)^2, y = F a0 / |F a0|
        for (k_y, fibre, y, length) in self.hourglass_yarns(hourglass, f_centre, moduli) {
            let y_q = y.dot(&q);
            energy += 0.5 * k_y * y_q * y_q;
            if let Some(f) = forces.as_deref_mut() {
                // d(y . q)/dx_a = gamma_a y + (grad0 N_a . a0) (I - y y^T) q / |F a0|
                let across = (q - y * y_q) / length;
                let terms = self.shape_gradients.iter().zip(hourglass.gamma);
                for (f_a, (g, gamma)) in f.iter_mut().zip(terms) {
                    *f_a += (y * gamma + across * g.dot(&fibre.xy())) * (k_y * y_q);
                }
            }
        }
        energy
    }

    /// The yarns that hold the hourglass mode: per yarn along the edges, `k_y = E t0 Y_y`, its
    /// reference direction, its current unit direction `y = F a0 / |F a0|` and `|F a0|`.
    fn hourglass_yarns(
        &self,
        hourglass: &Hourglass,
        f_centre: &Matrix3x2<f64>,
        moduli: &HourglassModuli,
    ) -> Vec<(f64, Vector3<f64>, Vector3<f64>, f64)> {
        [self.fibres.warp, self.fibres.weft]
            .into_iter()
            .zip(hourglass.yarn_factors)
            .filter_map(|(fibre, factor)| {
                let k_y = moduli.yarn * factor;
                let along = f_centre * fibre.xy();
                let length = along.norm();
                (k_y != 0.0 && length != 0.0).then(|| (k_y, fibre, along / length, length))
            })
            .collect()
    }

    /// A tensor given in the local basis (like the membrane resultant `N`) in global
    /// reference coordinates: `B T B^T`.
    pub fn to_global(&self, local: &Matrix2<f64>) -> Matrix3<f64> {
        self.basis * local * self.basis.transpose()
    }

    /// Shear angle of the fabric (radians, signed) at the current positions `x`: the change of
    /// the angle between warp and weft (docs/model.md §3, `I10 = sin^2 gamma`).
    pub fn shear_angle(&self, x: &[Vector3<f64>]) -> f64 {
        let f = self.gradient(x);
        let mut c = Matrix3::identity();
        c.fixed_view_mut::<2, 2>(0, 0)
            .copy_from(&(f.transpose() * f));
        crate::material::fabric::shear_angle(&c, &self.fibres)
    }

    /// Centroid of the current positions.
    pub fn centroid(&self, x: &[Vector3<f64>]) -> Vector3<f64> {
        self.cell.centroid(x)
    }
}

type Geometry = (f64, [Vector2<f64>; 4], f64, Option<Hourglass>);

/// Area, exact gradients and smallest altitude of a triangle with corners `p` (local).
fn triangle_geometry(p: &[Vector2<f64>]) -> Geometry {
    let area = 0.5 * cross(&(p[1] - p[0]), &(p[2] - p[0]));
    let mut gradients = [Vector2::zeros(); 4];
    for (a, g) in gradients.iter_mut().take(3).enumerate() {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        *g = Vector2::new(p[b].y - p[c].y, p[c].x - p[b].x) / (2.0 * area);
    }
    let longest_edge = (0..3)
        .map(|a| (p[(a + 1) % 3] - p[a]).norm())
        .fold(0.0, f64::max);
    (area, gradients, 2.0 * area / longest_edge, None)
}

/// Area `4 det J(0)`, centre gradients, stable-step length and hourglass vectors of a
/// quadrilateral with corners `p` (local, about the centroid) and yarns `fibres`.
fn quad_geometry(p: &[Vector2<f64>], fibres: &FibreDirections) -> Geometry {
    const XI: [f64; 4] = [-1.0, 1.0, 1.0, -1.0];
    const ETA: [f64; 4] = [-1.0, -1.0, 1.0, 1.0];
    const H: [f64; 4] = [1.0, -1.0, 1.0, -1.0];
    // J(0) = sum_a X_a (x) (xi_a, eta_a) / 4, columns dX/dxi, dX/deta
    let j = (0..4).fold(Matrix2::zeros(), |j, a| {
        j + p[a] * Vector2::new(XI[a], ETA[a]).transpose() / 4.0
    });
    let det = j.determinant();
    let j_inv_t = Matrix2::new(j[(1, 1)], -j[(1, 0)], -j[(0, 1)], j[(0, 0)]) / det;
    let gradients: [Vector2<f64>; 4] =
        std::array::from_fn(|a| j_inv_t * Vector2::new(XI[a], ETA[a]) / 4.0);
    let area = 4.0 * det;
    let h_dot_x: Vector2<f64> = (0..4).map(|a| p[a] * H[a]).sum();
    let gamma = std::array::from_fn(|a| (H[a] - h_dot_x.dot(&gradients[a])) / 4.0);
    let sum_squares: f64 = gradients.iter().map(|g| g.norm_squared()).sum();
    let longer_diagonal = (p[2] - p[0]).norm().max((p[3] - p[1]).norm());
    // rows of J0^-1: grad xi and grad eta
    let (grad_xi, grad_eta) = (
        j_inv_t.column(0).into_owned(),
        j_inv_t.column(1).into_owned(),
    );
    let yarn_factor = |a: Vector2<f64>| {
        let along_an_edge = [j.column(0), j.column(1)]
            .iter()
            .any(|edge| cross(&a, &edge.normalize()).abs() < ALIGNED);
        if !along_an_edge {
            return 0.0;
        }
        let n = Vector2::new(-a.y, a.x);
        let c = a.dot(&grad_xi) * n.dot(&grad_eta) + a.dot(&grad_eta) * n.dot(&grad_xi);
        // int ((X - Xc) . n)^2 dA of the parallelogram X - Xc = J0 (xi, eta)
        let second_moment =
            area / 3.0 * (n.dot(&j.column(0)).powi(2) + n.dot(&j.column(1)).powi(2));
        c * c * second_moment
    };
    let hourglass = Hourglass {
        gamma,
        shear_factor: 2.0 / 3.0 * area * sum_squares,
        yarn_factors: [yarn_factor(fibres.warp.xy()), yarn_factor(fibres.weft.xy())],
    };
    (area, gradients, area / longer_diagonal, Some(hourglass))
}

fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn sample() -> [Vector3<f64>; 3] {
        [
            Vector3::new(0.3, -0.2, 0.1),
            Vector3::new(2.1, 0.4, 0.5),
            Vector3::new(0.7, 1.9, -0.2),
        ]
    }

    #[test]
    fn reference_gradient_is_the_identity_on_the_tangent_plane() {
        let x0 = sample();
        let t = MembraneElement::new(Cell::Triangle([0, 1, 2]), &x0, &Vector3::x()).unwrap();
        let f = t.gradient(&x0);
        // F maps local coordinates to 3D: its columns are the orthonormal e1, e2
        let ftf = f.transpose() * f;
        assert!((ftf - Matrix2::identity()).amax() < 1e-12, "{ftf}");
        let sum: Vector2<f64> = t.shape_gradients.iter().sum();
        assert!(sum.norm() < 1e-12, "partition of unity");
    }

    #[test]
    fn rigid_motion_gives_no_strain_and_forces_balance() {
        let x0 = sample();
        let t = MembraneElement::new(Cell::Triangle([0, 1, 2]), &x0, &Vector3::x()).unwrap();
        let q = Rotation3::new(Vector3::new(0.4, -1.1, 0.7));
        let moved = x0.map(|x| q * x + Vector3::new(5.0, -2.0, 1.0));
        let f = t.gradient(&moved);
        assert!((f.transpose() * f - Matrix2::identity()).amax() < 1e-12);
        let forces = t.internal_forces(&f, &Matrix2::new(1.0, 0.3, 0.3, -2.0));
        let total: Vector3<f64> = forces.iter().sum();
        assert!(
            total.norm() < 1e-12,
            "a single element is in equilibrium: {total}"
        );
        // and in moment equilibrium
        let moment: Vector3<f64> = forces.iter().zip(&moved).map(|(f, x)| x.cross(f)).sum();
        assert!(moment.norm() < 1e-10, "{moment}");
    }

    #[test]
    fn warp_follows_the_projected_direction() {
        let flat = [
            Vector3::zeros(),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let diagonal = Vector3::new(1.0, 1.0, 0.0);
        let t = MembraneElement::new(Cell::Triangle([0, 1, 2]), &flat, &diagonal).unwrap();
        assert!((t.fibres.warp - Vector3::new(1.0, 1.0, 0.0).normalize()).norm() < 1e-12);
        assert!((t.fibres.weft - Vector3::new(-1.0, 1.0, 0.0).normalize()).norm() < 1e-12);
        assert_eq!(
            MembraneElement::new(Cell::Triangle([0, 1, 2]), &flat, &Vector3::z()).unwrap_err(),
            ElementError::WarpNormalToSheet
        );
    }

    const MODULI: HourglassModuli = HourglassModuli {
        shear: 2.0,
        yarn: 30.0,
    };

    fn distorted_quad() -> Vec<Vector3<f64>> {
        vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.3, 0.2, 0.0),
            Vector3::new(1.0, 1.1, 0.0),
            Vector3::new(-0.2, 0.8, 0.0),
        ]
    }

    fn quad() -> MembraneElement {
        MembraneElement::new(Cell::Quad([0, 1, 2, 3]), &distorted_quad(), &Vector3::x()).unwrap()
    }

    #[test]
    fn quadrilateral_area_is_that_of_its_polygon_and_its_gradient_is_exact_for_linear_fields() {
        let x0 = distorted_quad();
        let e = quad();
        let shoelace: f64 = (0..4)
            .map(|a| {
                let (p, q) = (x0[a], x0[(a + 1) % 4]);
                0.5 * (p.x * q.y - q.x * p.y)
            })
            .sum();
        assert!(
            (e.area - shoelace).abs() < 1e-14,
            "{} vs {shoelace}",
            e.area
        );
        let g = Matrix3::new(1.1, 0.3, 0.0, -0.2, 0.9, 0.0, 0.4, 0.1, 0.0);
        let moved: Vec<Vector3<f64>> = x0
            .iter()
            .map(|x| g * x + Vector3::new(1.0, 2.0, 3.0))
            .collect();
        let f = e.gradient(&moved);
        assert!((f - g * e.basis).amax() < 1e-12, "{f} vs {}", g * e.basis);
    }

    #[test]
    fn the_hourglass_mode_is_blind_to_rigid_motion_and_uniform_strain_and_holds_the_hourglass() {
        let x0 = distorted_quad();
        let e = quad();
        let q = Rotation3::new(Vector3::new(0.4, -1.1, 0.7));
        let g = Matrix3::new(1.1, 0.3, 0.0, -0.2, 0.9, 0.0, 0.0, 0.0, 1.0);
        for x in [
            x0.iter()
                .map(|x| q * x + Vector3::new(5.0, -2.0, 1.0))
                .collect::<Vec<_>>(),
            x0.iter().map(|x| g * x).collect(),
        ] {
            assert!(e.hourglass_energy(&x, &MODULI) < 1e-28);
        }
        // the hourglass pattern h = (1, -1, 1, -1) in the plane: held; out of the plane (the
        // cell folding across a diagonal): left to the bending
        let h = [1.0, -1.0, 1.0, -1.0];
        let in_plane: Vec<_> = x0
            .iter()
            .zip(h)
            .map(|(x, s)| x + Vector3::x() * 0.01 * s)
            .collect();
        let folded: Vec<_> = x0
            .iter()
            .zip(h)
            .map(|(x, s)| x + Vector3::z() * 0.01 * s)
            .collect();
        assert!(e.hourglass_energy(&in_plane, &MODULI) > 1e-6);
        assert!(
            e.hourglass_energy(&folded, &MODULI) < 1e-12 * e.hourglass_energy(&in_plane, &MODULI)
        );
        // nor does the one point see the in-plane pattern: only the hourglass control does
        let f = e.gradient(&in_plane);
        assert!((f - e.gradient(&x0)).amax() < 1e-12);
    }

    #[test]
    fn hourglass_forces_are_the_gradient_of_its_energy_and_balance() {
        let x0 = distorted_quad();
        let e = quad();
        let x: Vec<_> = x0
            .iter()
            .enumerate()
            .map(|(a, p)| {
                let s = a as f64;
                p + Vector3::new(
                    0.03 * s.sin(),
                    0.05 * (1.7 * s).cos(),
                    0.04 * (2.3 * s).sin(),
                )
            })
            .collect();
        let mut forces = [Vector3::zeros(); 4];
        e.hourglass_forces(&x, &e.gradient(&x), &MODULI, &mut forces);
        let total: Vector3<f64> = forces.iter().sum();
        assert!(total.norm() < 1e-13, "{total}");
        let moment: Vector3<f64> = forces.iter().zip(&x).map(|(f, p)| p.cross(f)).sum();
        assert!(moment.norm() < 1e-12, "{moment}");
        let step = 1e-6;
        for a in 0..4 {
            for axis in 0..3 {
                let (mut plus, mut minus) = (x.clone(), x.clone());
                plus[a][axis] += step;
                minus[a][axis] -= step;
                let fd = (e.hourglass_energy(&plus, &MODULI) - e.hourglass_energy(&minus, &MODULI))
                    / (2.0 * step);
                assert!(
                    (fd - forces[a][axis]).abs() < 1e-7,
                    "{a} {axis}: {fd} vs {}",
                    forces[a][axis]
                );
            }
        }
    }

    /// The exact hourglass tangent is the derivative of the hourglass forces (central
    /// differences): on a square with the yarns along its edges (shear and yarns) and on a
    /// distorted cell with the yarns at 30° (shear only), each moved out of shape, warped and
    /// given a large hourglass; its Gauss–Newton part is not.
    #[test]
    fn exact_hourglass_stiffness_is_the_derivative_of_the_forces() {
        let square = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(2.0, 2.0, 0.0),
            Vector3::new(0.0, 2.0, 0.0),
        ];
        for (x0, warp) in [
            (square, Vector3::x()),
            (distorted_quad(), Vector3::new(0.866, 0.5, 0.0)),
        ] {
            let e = MembraneElement::new(Cell::Quad([0, 1, 2, 3]), &x0, &warp).unwrap();
            let x: Vec<_> = x0
                .iter()
                .enumerate()
                .map(|(a, p)| {
                    let s = a as f64;
                    // the hourglass pattern (1, -1, 1, -1) in the plane, and more
                    let hourglass = if a % 2 == 0 { 0.3 } else { -0.3 };
                    p + Vector3::new(
                        hourglass + 0.3 * s.sin(),
                        0.2 * (1.7 * s).cos() - hourglass,
                        0.4 * (2.3 * s).sin(),
                    )
                })
                .collect();
            let exact = e.hourglass_stiffness(&x, &MODULI, true);
            let gauss_newton = e.hourglass_stiffness(&x, &MODULI, false);
            let h = 1e-6;
            let (mut largest, mut error, mut gn_error) = (0.0f64, 0.0f64, 0.0f64);
            for c in 0..4 {
                for dir in 0..3 {
                    let force_at = |sign: f64| {
                        let mut y = x.clone();
                        y[c][dir] += sign * h;
                        let mut f = [Vector3::zeros(); 4];
                        e.hourglass_forces(&y, &e.gradient(&y), &MODULI, &mut f);
                        f
                    };
                    let (plus, minus) = (force_at(1.0), force_at(-1.0));
                    for a in 0..4 {
                        let column = (plus[a] - minus[a]) / (2.0 * h);
                        largest = largest.max(column.amax());
                        error = error.max((column - exact[a][c].column(dir)).amax());
                        gn_error = gn_error.max((column - gauss_newton[a][c].column(dir)).amax());
                    }
                }
            }
            assert!(error < 1e-7 * largest, "{warp}: {error} of {largest}");
            assert!(
                gn_error > 1e-2 * largest,
                "{warp}: Gauss-Newton off by {gn_error}"
            );
        }
    }

    #[test]
    fn a_square_quadrilateral_has_the_time_step_length_of_its_two_right_triangles() {
        let square = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(2.0, 2.0, 0.0),
            Vector3::new(0.0, 2.0, 0.0),
        ];
        let q = MembraneElement::new(Cell::Quad([0, 1, 2, 3]), &square, &Vector3::x()).unwrap();
        let t = MembraneElement::new(Cell::Triangle([0, 1, 2]), &square, &Vector3::x()).unwrap();
        assert!((q.altitude - t.altitude).abs() < 1e-14);
        assert!((q.area - 4.0).abs() < 1e-14);
        let folded = [square[0], square[1], Vector3::new(0.5, 0.4, 0.0), square[3]];
        assert_eq!(
            MembraneElement::new(Cell::Quad([0, 1, 2, 3]), &folded, &Vector3::x()).unwrap_err(),
            ElementError::Folded
        );
    }

    #[test]
    fn yarns_along_the_edges_hold_the_hourglass_as_full_integration_and_crossing_yarns_not() {
        let square = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(2.0, 2.0, 0.0),
            Vector3::new(0.0, 2.0, 0.0),
        ];
        let quad = |warp: Vector3<f64>| {
            MembraneElement::new(Cell::Quad([0, 1, 2, 3]), &square, &warp)
                .unwrap()
                .hourglass
                .unwrap()
        };
        // a fully integrated bilinear square gives the mode u = s xi eta e_x the yarn energy
        // 1/2 E t (4/3) s^2 (the yarn along x stretched by s eta (2/h))
        let aligned = quad(Vector3::x());
        assert!(
            (aligned.yarn_factors[0] - 4.0 / 3.0).abs() < 1e-12,
            "{aligned:?}"
        );
        assert!(
            (aligned.yarn_factors[1] - 4.0 / 3.0).abs() < 1e-12,
            "{aligned:?}"
        );
        assert!(
            (aligned.shear_factor - 4.0 / 3.0).abs() < 1e-12,
            "{aligned:?}"
        );
        let diagonal = quad(Vector3::new(1.0, 1.0, 0.0));
        assert!(
            diagonal.yarn_factors.iter().all(|y| y.abs() < 1e-12),
            "{diagonal:?}"
        );
        // nor do yarns at any other angle to the edges
        let thirty = quad(Vector3::new(
            30f64.to_radians().cos(),
            30f64.to_radians().sin(),
            0.0,
        ));
        assert!(thirty.yarn_factors == [0.0, 0.0], "{thirty:?}");
        // and the energy is E t Y (y . q)^2 / 2: the pattern h moved along x by s
        let s = 0.01;
        let h = [1.0, -1.0, 1.0, -1.0];
        let moved: Vec<_> = square
            .iter()
            .zip(h)
            .map(|(x, k)| x + Vector3::x() * s * k)
            .collect();
        let e = MembraneElement::new(Cell::Quad([0, 1, 2, 3]), &square, &Vector3::x()).unwrap();
        let yarns = HourglassModuli {
            shear: 0.0,
            yarn: 3.0,
        };
        let energy = e.hourglass_energy(&moved, &yarns);
        assert!(
            (energy - 0.5 * 3.0 * 4.0 / 3.0 * s * s).abs() < 1e-12 * energy.max(1e-30),
            "{energy}"
        );
    }
}
