//! Total-Lagrangian 3-node membrane triangle carrying the laminate (docs/model.md §1, §4).
//!
//! Constant strain: `F = sum_a x_a (x) grad0 N_a` (3x2, from local reference coordinates of the
//! element's tangent plane to current 3D positions), and the internal nodal forces are
//! `f_a = A0 F N grad0 N_a` with `N` the laminate's membrane resultant.

use crate::material::FibreDirections;
use nalgebra::{Matrix2, Matrix3, Matrix3x2, Vector2, Vector3};

/// Reference geometry of one triangle, computed once.
#[derive(Clone, Debug, PartialEq)]
pub struct MembraneTriangle {
    pub nodes: [usize; 3],
    /// Reference area `A0` (mm^2).
    pub area: f64,
    /// Gradients of the shape functions in the local reference basis `(e1, e2)`.
    pub shape_gradients: [Vector2<f64>; 3],
    /// Warp and weft in the local basis.
    pub fibres: FibreDirections,
    /// Smallest altitude (mm): the length that sets the element's stable time step.
    pub altitude: f64,
    /// The local reference basis `(e1, e2)` as columns, in global coordinates.
    pub basis: Matrix3x2<f64>,
}

/// Why a triangle cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElementError {
    #[error("triangle is degenerate (area {area:e} mm^2)")]
    Degenerate { area: f64 },
    #[error(
        "the reference warp direction is normal to the element: it cannot be projected onto \
         the sheet"
    )]
    WarpNormalToSheet,
}

impl MembraneTriangle {
    /// A triangle on the reference nodes `x0`, with the warp along the projection of
    /// `warp_direction` (global) onto its plane and the weft at +90° about its normal.
    pub fn new(
        nodes: [usize; 3],
        x0: [Vector3<f64>; 3],
        warp_direction: &Vector3<f64>,
    ) -> Result<Self, ElementError> {
        let edge1 = x0[1] - x0[0];
        let edge2 = x0[2] - x0[0];
        let normal = edge1.cross(&edge2);
        let area = 0.5 * normal.norm();
        if area.is_nan() || area <= 1e-12 * edge1.norm_squared().max(edge2.norm_squared()) {
            return Err(ElementError::Degenerate { area });
        }
        let n = normal / (2.0 * area);
        let e1 = edge1.normalize();
        let e2 = n.cross(&e1);
        let local = x0.map(|x| Vector2::new((x - x0[0]).dot(&e1), (x - x0[0]).dot(&e2)));
        let shape_gradients = std::array::from_fn(|a| {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            Vector2::new(local[b].y - local[c].y, local[c].x - local[b].x) / (2.0 * area)
        });
        let in_plane = Vector2::new(warp_direction.dot(&e1), warp_direction.dot(&e2));
        if in_plane.norm() < 1e-6 * warp_direction.norm() {
            return Err(ElementError::WarpNormalToSheet);
        }
        let longest_edge = [edge1, edge2, x0[2] - x0[1]]
            .iter()
            .map(|e| e.norm())
            .fold(0.0, f64::max);
        Ok(Self {
            nodes,
            area,
            shape_gradients,
            fibres: FibreDirections::in_plane(in_plane.y.atan2(in_plane.x)),
            altitude: 2.0 * area / longest_edge,
            basis: Matrix3x2::from_columns(&[e1, e2]),
        })
    }

    /// `F = sum_a x_a (x) grad0 N_a`; with velocities in place of positions, `Fdot`.
    pub fn gradient(&self, field: &[Vector3<f64>]) -> Matrix3x2<f64> {
        self.nodes
            .iter()
            .zip(&self.shape_gradients)
            .fold(Matrix3x2::zeros(), |f, (&node, g)| {
                f + field[node] * g.transpose()
            })
    }

    /// Internal nodal forces `f_a = A0 F N grad0 N_a` (docs/model.md §4).
    pub fn internal_forces(&self, f: &Matrix3x2<f64>, n: &Matrix2<f64>) -> [Vector3<f64>; 3] {
        let fn_area = f * n * self.area;
        self.shape_gradients.map(|g| fn_area * g)
    }

    /// A tensor given in the local basis (like the membrane resultant `N`) in global
    /// reference coordinates: `B T B^T`.
    pub fn to_global(&self, local: &Matrix2<f64>) -> Matrix3<f64> {
        self.basis * local * self.basis.transpose()
    }

    /// Centroid of the current positions.
    /// Shear angle of the fabric (radians, signed) at the current positions `x`: the change of
    /// the angle between warp and weft (docs/model.md §3, `I10 = sin^2 gamma`).
    pub fn shear_angle(&self, x: &[Vector3<f64>]) -> f64 {
        let f = self.gradient(x);
        let mut c = Matrix3::identity();
        c.fixed_view_mut::<2, 2>(0, 0)
            .copy_from(&(f.transpose() * f));
        crate::material::fabric::shear_angle(&c, &self.fibres)
    }

    pub fn centroid(&self, x: &[Vector3<f64>]) -> Vector3<f64> {
        self.nodes.iter().map(|&n| x[n]).sum::<Vector3<f64>>() / 3.0
    }
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
        let t = MembraneTriangle::new([0, 1, 2], x0, &Vector3::x()).unwrap();
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
        let t = MembraneTriangle::new([0, 1, 2], x0, &Vector3::x()).unwrap();
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
        let t = MembraneTriangle::new([0, 1, 2], flat, &diagonal).unwrap();
        assert!((t.fibres.warp - Vector3::new(1.0, 1.0, 0.0).normalize()).norm() < 1e-12);
        assert!((t.fibres.weft - Vector3::new(-1.0, 1.0, 0.0).normalize()).norm() < 1e-12);
        assert_eq!(
            MembraneTriangle::new([0, 1, 2], flat, &Vector3::z()).unwrap_err(),
            ElementError::WarpNormalToSheet
        );
    }
}
