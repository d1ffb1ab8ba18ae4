//! Grippers (docs/model.md §10, Eq. (S4)): a node set held to where it was gripped, carried by
//! a tool or standing still, until it lets go at a time or when the force it holds reaches a
//! limit. The hold is a stiff zero-length spring per node (the tools' contact stiffness), so
//! that letting go changes no unknown of the solvers.

use super::anchor_now;
use super::spring::spring_node;
use nalgebra::{Matrix3, Vector3};

/// When a gripper lets go: at a time, or when the force it holds reaches a limit, whichever
/// comes first; never if neither is given.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Release {
    /// Process time (s).
    pub time: Option<f64>,
    /// Magnitude of the resultant it holds (N).
    pub force: Option<f64>,
}

impl Release {
    /// Whether it is due at `time` with the gripper holding `force`.
    pub fn due(&self, time: f64, force: f64) -> bool {
        self.time.is_some_and(|t| time >= t) || self.force.is_some_and(|f| force >= f)
    }
}

/// A gripper: its nodes and where each was gripped.
#[derive(Clone, Debug, PartialEq)]
pub struct GripperSet {
    pub name: String,
    pub nodes: Vec<usize>,
    /// Where each node was gripped (mm), in the order of `nodes`.
    pub anchors: Vec<Vector3<f64>>,
    /// Stiffness of the hold at each node (N/mm).
    pub stiffness: f64,
    /// The tool whose translation carries it; `None`: it stands still.
    pub carrier: Option<usize>,
    pub release: Release,
}

impl GripperSet {
    /// Adds the hold's force on each node; returns the resultant on the blank (N) and its
    /// energy (N·mm).
    pub fn add_forces(
        &self,
        positions: &[Vector3<f64>],
        translations: &[Vector3<f64>],
        forces: &mut [Vector3<f64>],
    ) -> (Vector3<f64>, f64) {
        let mut resultant = Vector3::zeros();
        let mut energy = 0.0;
        for (&node, start) in self.nodes.iter().zip(&self.anchors) {
            let anchor = anchor_now(start, self.carrier, translations);
            let (f, e) = spring_node(&positions[node], &anchor, self.stiffness, 0.0);
            forces[node] += f;
            resultant += f;
            energy += e;
        }
        (resultant, energy)
    }

    /// Pushes each node's `-df/dx = k I`.
    pub fn add_stiffness(&self, blocks: &mut Vec<(usize, Matrix3<f64>)>) {
        for &node in &self.nodes {
            blocks.push((node, Matrix3::identity() * self.stiffness));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn release_comes_at_the_time_or_the_force_whichever_first() {
        let r = Release {
            time: Some(2.0),
            force: Some(10.0),
        };
        assert!(!r.due(1.0, 5.0));
        assert!(r.due(2.0, 0.0));
        assert!(r.due(1.0, 10.0));
        assert!(!Release::default().due(1e9, 1e9));
    }

    #[test]
    fn a_carried_gripper_pulls_its_nodes_after_its_tool() {
        let gripper = GripperSet {
            name: "g".into(),
            nodes: vec![0],
            anchors: vec![Vector3::zeros()],
            stiffness: 100.0,
            carrier: Some(1),
            release: Release::default(),
        };
        let mut forces = vec![Vector3::zeros()];
        let translations = [Vector3::zeros(), Vector3::new(0.0, 0.0, 0.5)];
        let (resultant, energy) =
            gripper.add_forces(&[Vector3::zeros()], &translations, &mut forces);
        assert!((resultant - Vector3::new(0.0, 0.0, 50.0)).norm() < 1e-12);
        assert!((energy - 12.5).abs() < 1e-12);
    }
}
