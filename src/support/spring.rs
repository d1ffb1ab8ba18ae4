//! Springs from nodes of the blank to anchors (docs/model.md §10, Eqs. (S2)–(S3)): a linear
//! spring of stiffness `k` and free length `l0` between a node at `x` and its anchor at `a`,
//!
//! `f = k (l - l0) e`, `e = (a - x) / l`, `l = |a - x|`, `V = 1/2 k (l - l0)^2`,
//!
//! and its stiffness `-df/dx = k e e^T + (k (l - l0) / l) (I - e e^T)`. A spring set spreads one
//! physical spring over the nodes it is attached to: each node gets `k / n` and the same
//! anchor offset, so that the set pulls with `k (l - l0)` in all when they move together.

use super::anchor_now;
use nalgebra::{Matrix3, Vector3};

/// One node's spring: the node and where its anchor stands at the start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpringNode {
    pub node: usize,
    pub anchor: Vector3<f64>,
}

/// The springs of one attachment: every node of a set tied to its own anchor, all with the
/// same stiffness and free length.
#[derive(Clone, Debug, PartialEq)]
pub struct SpringSet {
    pub name: String,
    pub nodes: Vec<SpringNode>,
    /// Stiffness of each node's spring (N/mm): the set's divided among its nodes.
    pub stiffness: f64,
    /// Free length (mm).
    pub free_length: f64,
    /// The tool whose translation carries the anchors; `None`: they stand still.
    pub carrier: Option<usize>,
}

/// The spring of the node at `x` whose anchor is at `anchor`: its force on the node and energy,
/// Eq. (S2).
pub fn spring_node(
    x: &Vector3<f64>,
    anchor: &Vector3<f64>,
    k: f64,
    l0: f64,
) -> (Vector3<f64>, f64) {
    let d = anchor - x;
    let l = d.norm();
    if l == 0.0 {
        return (Vector3::zeros(), 0.5 * k * l0 * l0);
    }
    let stretch = l - l0;
    (d * (k * stretch / l), 0.5 * k * stretch * stretch)
}

/// `-df/dx` of [`spring_node`], Eq. (S3); the geometric part only where the spring pulls
/// (a compressed spring's is not positive, and Newton's method needs a positive tangent).
fn spring_stiffness(x: &Vector3<f64>, anchor: &Vector3<f64>, k: f64, l0: f64) -> Matrix3<f64> {
    let d = anchor - x;
    let l = d.norm();
    if l == 0.0 {
        return Matrix3::identity() * k;
    }
    let e = d / l;
    let along = e * e.transpose();
    let geometric = (k * (l - l0) / l).max(0.0);
    along * k + (Matrix3::identity() - along) * geometric
}

impl SpringSet {
    /// Adds each node's spring force; returns the set's resultant on the blank (N) and its
    /// energy (N·mm).
    pub fn add_forces(
        &self,
        positions: &[Vector3<f64>],
        translations: &[Vector3<f64>],
        forces: &mut [Vector3<f64>],
    ) -> (Vector3<f64>, f64) {
        let mut resultant = Vector3::zeros();
        let mut energy = 0.0;
        for s in &self.nodes {
            let anchor = anchor_now(&s.anchor, self.carrier, translations);
            let (f, e) = spring_node(
                &positions[s.node],
                &anchor,
                self.stiffness,
                self.free_length,
            );
            forces[s.node] += f;
            resultant += f;
            energy += e;
        }
        (resultant, energy)
    }

    /// Pushes each node's `-df/dx`.
    pub fn add_stiffness(
        &self,
        positions: &[Vector3<f64>],
        translations: &[Vector3<f64>],
        blocks: &mut Vec<(usize, Matrix3<f64>)>,
    ) {
        for s in &self.nodes {
            let anchor = anchor_now(&s.anchor, self.carrier, translations);
            let k = spring_stiffness(
                &positions[s.node],
                &anchor,
                self.stiffness,
                self.free_length,
            );
            blocks.push((s.node, k));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn energy(x: &Vector3<f64>) -> f64 {
        spring_node(x, &Vector3::new(3.0, -1.0, 2.0), 7.0, 1.5).1
    }

    #[test]
    fn force_is_minus_the_gradient_of_the_energy() {
        let x = Vector3::new(0.3, 0.2, -0.4);
        let (f, _) = spring_node(&x, &Vector3::new(3.0, -1.0, 2.0), 7.0, 1.5);
        let h = 1e-6;
        for d in 0..3 {
            let mut plus = x;
            let mut minus = x;
            plus[d] += h;
            minus[d] -= h;
            let slope = (energy(&plus) - energy(&minus)) / (2.0 * h);
            assert!(
                (f[d] + slope).abs() < 1e-6 * f.norm(),
                "{d}: {} vs {}",
                f[d],
                -slope
            );
        }
    }

    #[test]
    fn stiffness_is_minus_the_derivative_of_the_force_where_the_spring_pulls() {
        let anchor = Vector3::new(3.0, -1.0, 2.0);
        let x = Vector3::new(0.3, 0.2, -0.4);
        let k = spring_stiffness(&x, &anchor, 7.0, 1.5);
        let h = 1e-6;
        for d in 0..3 {
            let mut plus = x;
            let mut minus = x;
            plus[d] += h;
            minus[d] -= h;
            let df = (spring_node(&plus, &anchor, 7.0, 1.5).0
                - spring_node(&minus, &anchor, 7.0, 1.5).0)
                / (2.0 * h);
            for r in 0..3 {
                assert!((k[(r, d)] + df[r]).abs() < 1e-6 * 7.0, "({r},{d})");
            }
        }
    }

    #[test]
    fn a_spring_at_its_free_length_pulls_nothing() {
        let (f, e) = spring_node(&Vector3::zeros(), &Vector3::new(0.0, 2.0, 0.0), 5.0, 2.0);
        assert_eq!(f, Vector3::zeros());
        assert_eq!(e, 0.0);
    }
}
