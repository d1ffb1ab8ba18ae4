//! Gravity: the body force `m g` on every node, `m` its physical mass (never the mass added
//! by mass scaling), Eq. (S1) of docs/model.md §10.

use nalgebra::Vector3;

/// Standard gravity (mm/s^2).
pub const STANDARD_GRAVITY: f64 = 9806.65;

/// A uniform acceleration field (mm/s^2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gravity {
    pub acceleration: Vector3<f64>,
}

impl Gravity {
    /// Standard gravity along `-z`, the stroke axis pointing up.
    pub fn standard() -> Self {
        Self {
            acceleration: Vector3::new(0.0, 0.0, -STANDARD_GRAVITY),
        }
    }

    /// Adds `m_a g` to each node's force; returns the resultant (the weight, N) and the
    /// potential `-sum m_a g . x_a` (N·mm).
    pub fn add_forces(
        &self,
        positions: &[Vector3<f64>],
        masses: &[f64],
        forces: &mut [Vector3<f64>],
    ) -> (Vector3<f64>, f64) {
        let mut weight = Vector3::zeros();
        let mut potential = 0.0;
        for ((x, m), f) in positions.iter().zip(masses).zip(forces) {
            let w = self.acceleration * *m;
            *f += w;
            weight += w;
            potential -= w.dot(x);
        }
        (weight, potential)
    }
}
