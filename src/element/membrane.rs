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
/// it takes nothing from the one-point response. Its part in the current tangent plane, `q_t`,
/// is held by the energy `1/2 k q_t . q_t` with
/// `k = HOURGLASS_FRACTION (2/3) G t0 A0 sum_a |grad0 N_a|^2`, `G t0` the laminate's in-plane
/// shear stiffness at rest: the energy a fully integrated bilinear element gives the mode
/// through shear, `(4/3) G t0` for a square (docs/model.md §4).
#[derive(Clone, Debug, PartialEq)]
pub struct Hourglass {
    pub gamma: [f64; 4],
    /// `(2/3) A0 sum_a |grad0 N_a|^2`: `k = HOURGLASS_FRACTION G t0 x this`.
    pub stiffness_factor: f64,
}

/// Fraction of the shear energy of a fully integrated element given to the hourglass mode
/// **(choice)**: all of it, which is physical (the mode shears the cell), far below the yarns'
/// stiffness (the yarns' share of the mode would lock the element when they cross its edges),
/// and, measured on the hemisphere (docs/model.md §4), enough to keep the mode out of the
/// formed parts: ten and a thousand times more change the largest shear by 1.3 and 1.6°.
pub const HOURGLASS_FRACTION: f64 = 1.0;

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
        let (area, shape_gradients, altitude, hourglass) = match cell {
            Cell::Triangle(_) => triangle_geometry(&local),
            Cell::Quad(_) => quad_geometry(&local),
        };
        Ok(Self {
            cell,
            area,
            shape_gradients,
            fibres: FibreDirections::in_plane(in_plane.y.atan2(in_plane.x)),
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

    /// The hourglass forces `k gamma_a q_t` of a quadrilateral at the positions `x`, added to
    /// `forces`, for the in-plane shear stiffness `shear_stiffness = G t0` (N/mm); returns the
    /// mode's energy `1/2 k q_t . q_t`. Nothing for a triangle.
    pub fn hourglass_forces(
        &self,
        x: &[Vector3<f64>],
        shear_stiffness: f64,
        forces: &mut [Vector3<f64>; 4],
    ) -> f64 {
        let Some(hourglass) = &self.hourglass else {
            return 0.0;
        };
        let (k, q_t) = self.hourglass_mode(hourglass, x, shear_stiffness);
        for (f, g) in forces.iter_mut().zip(hourglass.gamma) {
            *f += q_t * (k * g);
        }
        0.5 * k * q_t.norm_squared()
    }

    /// Energy of the hourglass mode at `x` (N·mm); zero for a triangle.
    pub fn hourglass_energy(&self, x: &[Vector3<f64>], shear_stiffness: f64) -> f64 {
        self.hourglass.as_ref().map_or(0.0, |hourglass| {
            let (k, q_t) = self.hourglass_mode(hourglass, x, shear_stiffness);
            0.5 * k * q_t.norm_squared()
        })
    }

    /// `k` and the mode's part `q_t` in the current tangent plane (normal along the cross
    /// product of the current diagonals).
    fn hourglass_mode(
        &self,
        hourglass: &Hourglass,
        x: &[Vector3<f64>],
        shear_stiffness: f64,
    ) -> (f64, Vector3<f64>) {
        let q: Vector3<f64> = self
            .nodes()
            .iter()
            .zip(hourglass.gamma)
            .map(|(&n, g)| x[n] * g)
            .sum();
        let normal = self.cell.area_vector(x);
        let q_t = match normal.try_normalize(0.0) {
            Some(n) => q - n * n.dot(&q),
            None => q,
        };
        let k = std::env::var("HGF")
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(HOURGLASS_FRACTION)
            * shear_stiffness
            * hourglass.stiffness_factor;
        (k, q_t)
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
/// quadrilateral with corners `p` (local, about the centroid).
fn quad_geometry(p: &[Vector2<f64>]) -> Geometry {
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
    let hourglass = Hourglass {
        gamma,
        stiffness_factor: 2.0 / 3.0 * area * sum_squares,
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
            assert!(e.hourglass_energy(&x, 1.0) < 1e-28);
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
        assert!(e.hourglass_energy(&in_plane, 1.0) > 1e-6);
        assert!(e.hourglass_energy(&folded, 1.0) < 1e-12 * e.hourglass_energy(&in_plane, 1.0));
        // nor does the one point see the in-plane pattern: only the hourglass control does
        let f = e.gradient(&in_plane);
        assert!((f - e.gradient(&x0)).amax() < 1e-12);
    }

    #[test]
    fn hourglass_forces_are_the_gradient_of_its_energy_in_the_plane_and_balance() {
        let x0 = distorted_quad();
        let e = quad();
        let x: Vec<_> = x0
            .iter()
            .enumerate()
            .map(|(a, p)| {
                p + Vector3::new(0.03 * (a as f64).sin(), 0.05 * (1.7 * a as f64).cos(), 0.0)
            })
            .collect();
        let mut forces = [Vector3::zeros(); 4];
        e.hourglass_forces(&x, 2.0, &mut forces);
        let total: Vector3<f64> = forces.iter().sum();
        assert!(total.norm() < 1e-14, "{total}");
        let step = 1e-6;
        for a in 0..4 {
            for axis in 0..2 {
                let (mut plus, mut minus) = (x.clone(), x.clone());
                plus[a][axis] += step;
                minus[a][axis] -= step;
                let fd = (e.hourglass_energy(&plus, 2.0) - e.hourglass_energy(&minus, 2.0))
                    / (2.0 * step);
                assert!(
                    (fd - forces[a][axis]).abs() < 1e-7,
                    "{a} {axis}: {fd} vs {}",
                    forces[a][axis]
                );
            }
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
}
