//! Grippers (docs/model.md §10, Eq. (S4)): a node set held to where it was gripped, carried by
//! a tool or standing still, until it lets go at a time or when the force it holds reaches a
//! limit. The hold is a stiff zero-length spring per node (the tools' contact stiffness), so
//! that letting go changes no unknown of the solvers.

use super::spring::{SpringNode, SpringSet};
use nalgebra::Vector3;

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

/// A gripper: the zero-length springs that hold its nodes where they were gripped.
#[derive(Clone, Debug, PartialEq)]
pub struct GripperSet {
    pub name: String,
    /// Each node tied to where it was gripped, free length 0, the hold's stiffness (N/mm),
    /// carried by a tool or standing still.
    pub hold: SpringSet,
    pub release: Release,
}

impl GripperSet {
    /// A gripper on `nodes` at `positions` (mm), holding each with `stiffness` (N/mm),
    /// carried by tool `carrier` (none: fixed).
    pub fn new(
        name: String,
        (nodes, positions): (&[usize], &[Vector3<f64>]),
        stiffness: f64,
        carrier: Option<usize>,
        release: Release,
    ) -> Self {
        let nodes = nodes
            .iter()
            .map(|&node| SpringNode {
                node,
                anchor: positions[node],
            })
            .collect();
        Self {
            hold: SpringSet {
                name: name.clone(),
                nodes,
                stiffness,
                free_length: 0.0,
                carrier,
            },
            name,
            release,
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
        let at = [Vector3::zeros()];
        let gripper = GripperSet::new("g".into(), (&[0], &at), 100.0, Some(1), Release::default());
        let mut forces = vec![Vector3::zeros()];
        let translations = [Vector3::zeros(), Vector3::new(0.0, 0.0, 0.5)];
        let (resultant, energy) = gripper.hold.add_forces(&at, &translations, &mut forces);
        assert!((resultant - Vector3::new(0.0, 0.0, 50.0)).norm() < 1e-12);
        assert!((energy - 12.5).abs() < 1e-12);
    }
}
