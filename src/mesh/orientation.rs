//! Fibre directions on a curved or pre-shaped blank: a reference direction projected onto
//! each triangle's plane (what `element::MembraneElement` does), and the triangles where that
//! projection is ill-conditioned, so that a user is warned before the run rather than surprised
//! by the fibre angles after it.

use super::Mesh;
use nalgebra::{Rotation3, Vector3};

/// A projection is called poor when the reference direction lies more than this many degrees
/// out of the triangle's plane **(choice)**: its in-plane part is then shorter than half of it,
/// and a small error in the direction or the surface turns the projected warp by as much
/// again. At 90° the projection has no direction at all and the model refuses the triangle.
pub const POOR_PROJECTION_DEG: f64 = 60.0;

/// A triangle whose reference direction projects poorly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoorProjection {
    pub triangle: usize,
    /// Angle between the reference direction and the triangle's plane (degrees).
    pub out_of_plane_deg: f64,
}

/// The reference warp direction of the scenario: `reference` (global) turned by `ply_angle_deg`
/// about the stroke axis z.
pub fn reference_warp(reference: Vector3<f64>, ply_angle_deg: f64) -> Vector3<f64> {
    Rotation3::from_axis_angle(&Vector3::z_axis(), ply_angle_deg.to_radians()) * reference
}

/// Angle (degrees) between `direction` and the plane of element `t`.
pub fn out_of_plane_angle(mesh: &Mesh, t: usize, direction: &Vector3<f64>) -> f64 {
    let normal = mesh.cells[t].area_vector(&mesh.nodes);
    let sine = (normal.dot(direction) / (normal.norm() * direction.norm())).abs();
    sine.min(1.0).asin().to_degrees()
}

/// The triangles of `mesh` whose warp direction (the mesh's own where it has them, `reference`
/// otherwise) lies more than [`POOR_PROJECTION_DEG`] out of their plane, worst first.
pub fn poor_projections(mesh: &Mesh, reference: &Vector3<f64>) -> Vec<PoorProjection> {
    let mut poor: Vec<PoorProjection> = (0..mesh.cells.len())
        .filter_map(|t| {
            let direction = mesh.warp_directions.as_ref().map_or(*reference, |d| d[t]);
            let angle = out_of_plane_angle(mesh, t, &direction);
            (angle.is_nan() || angle > POOR_PROJECTION_DEG).then_some(PoorProjection {
                triangle: t,
                out_of_plane_deg: angle,
            })
        })
        .collect();
    poor.sort_by(|a, b| b.out_of_plane_deg.total_cmp(&a.out_of_plane_deg));
    poor
}

/// One line for the user about `poor` (empty: nothing to say): how many triangles, the worst
/// ones with their angles.
pub fn describe_poor_projections(poor: &[PoorProjection], triangles: usize) -> Option<String> {
    let worst: Vec<String> = poor
        .iter()
        .take(5)
        .map(|p| format!("{} ({:.1}°)", p.triangle, p.out_of_plane_deg))
        .collect();
    (!poor.is_empty()).then(|| {
        format!(
            "the warp direction lies more than {POOR_PROJECTION_DEG}° out of the plane of {} of \
             {triangles} triangles, where its projection is ill-conditioned (worst, by triangle \
             index: {}); check the reference direction or the mesh's orientations",
            poor.len(),
            worst.join(", ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{rectangle, DiagonalPattern};

    /// The unit-square mesh folded about the line x = 0.5 by `fold` degrees.
    fn folded(fold: f64) -> Mesh {
        let mut mesh = rectangle(2.0, 1.0, 2, 1, DiagonalPattern::Right);
        let (s, c) = fold.to_radians().sin_cos();
        for x in &mut mesh.nodes {
            if x.x > 0.0 {
                *x = Vector3::new(x.x * c, x.y, x.x * s);
            }
        }
        mesh
    }

    #[test]
    fn out_of_plane_angle_is_the_fold_angle_for_a_direction_across_the_fold() {
        let mesh = folded(70.0);
        let x = Vector3::x();
        let angles: Vec<f64> = (0..mesh.cells.len())
            .map(|t| out_of_plane_angle(&mesh, t, &x))
            .collect();
        for (t, &a) in angles.iter().enumerate() {
            let on_fold = mesh.centroid(t).x > 0.0;
            let expected = if on_fold { 70.0 } else { 0.0 };
            assert!((a - expected).abs() < 1e-9, "triangle {t}: {a}");
        }
        // along the fold line the projection is perfect on both sides
        assert!((0..mesh.cells.len()).all(|t| out_of_plane_angle(&mesh, t, &Vector3::y()) < 1e-9));
    }

    #[test]
    fn steep_triangles_are_reported_worst_first() {
        let mesh = folded(70.0);
        let poor = poor_projections(&mesh, &Vector3::x());
        assert_eq!(poor.len(), 2);
        assert!(poor.iter().all(|p| mesh.centroid(p.triangle).x > 0.0));
        assert!(poor_projections(&folded(50.0), &Vector3::x()).is_empty());
        let line = describe_poor_projections(&poor, mesh.cells.len()).unwrap();
        assert!(
            line.contains("2 of 4 triangles") && line.contains("70.0°"),
            "{line}"
        );
        assert!(describe_poor_projections(&[], 4).is_none());
    }

    #[test]
    fn the_mesh_s_own_directions_take_precedence() {
        let mut mesh = folded(70.0);
        mesh.warp_directions = Some(vec![Vector3::y(); mesh.cells.len()]);
        assert!(poor_projections(&mesh, &Vector3::x()).is_empty());
    }

    #[test]
    fn ply_angle_turns_the_reference_about_z() {
        let w = reference_warp(Vector3::x(), 90.0);
        assert!((w - Vector3::y()).norm() < 1e-15);
    }
}
