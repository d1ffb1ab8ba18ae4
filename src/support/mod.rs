//! What holds and loads the blank besides the tools (docs/model.md §10): gravity, springs to
//! anchors and grippers. Each acts on single nodes, with a potential, so that both solvers take
//! its force and the implicit one its stiffness too.
//!
//! Anchors stand still or move with a tool (`carrier`): a frame of springs carried by the upper
//! die, grippers on a transfer arm carried by the holder.

pub mod gravity;
pub mod gripper;
pub mod spring;

pub use gravity::Gravity;
pub use gripper::{GripperSet, Release};
pub use spring::{spring_node, SpringNode, SpringSet};

use nalgebra::{Matrix3, Vector3};

/// Everything that holds or loads the blank at single nodes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Supports {
    pub gravity: Option<Gravity>,
    pub springs: Vec<SpringSet>,
    pub grippers: Vec<GripperSet>,
}

/// Where the supports stand at one instant: the tools' translations (for the anchors they
/// carry), the time (for the grippers' release) and which grippers have let go.
#[derive(Clone, Copy, Debug)]
pub struct SupportsAt<'a> {
    pub translations: &'a [Vector3<f64>],
    pub released: &'a [bool],
}

/// The supports' forces on the blank at one configuration.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SupportLoads {
    /// Force on each node (N).
    pub forces: Vec<Vector3<f64>>,
    /// Their potential `V` (N·mm): minus the work they would do; the force is `-dV/dx`.
    pub potential: f64,
    /// The resultant each spring set and each gripper puts on the blank (N).
    pub springs: Vec<Vector3<f64>>,
    pub grippers: Vec<Vector3<f64>>,
    /// Gravity's resultant on the blank (N).
    pub weight: Vector3<f64>,
}

/// What a run keeps of the supports between steps.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SupportState {
    /// Whether each gripper has let go.
    pub released: Vec<bool>,
    /// The last step's loads.
    pub loads: SupportLoads,
}

impl Supports {
    /// Whether anything is there.
    pub fn is_empty(&self) -> bool {
        self.gravity.is_none() && self.springs.is_empty() && self.grippers.is_empty()
    }

    /// Whether the blank hangs on springs or grippers.
    pub fn holds_the_blank(&self) -> bool {
        !self.springs.is_empty() || !self.grippers.is_empty()
    }

    /// The state at the start: no gripper released.
    pub fn start(&self, nodes: usize) -> SupportState {
        SupportState {
            released: vec![false; self.grippers.len()],
            loads: SupportLoads {
                forces: vec![Vector3::zeros(); nodes],
                springs: vec![Vector3::zeros(); self.springs.len()],
                grippers: vec![Vector3::zeros(); self.grippers.len()],
                ..SupportLoads::default()
            },
        }
    }

    /// The forces at `positions`, gravity on the `masses` (physical, tonne).
    pub fn loads(
        &self,
        positions: &[Vector3<f64>],
        masses: &[f64],
        at: SupportsAt,
    ) -> SupportLoads {
        let mut loads = SupportLoads {
            forces: vec![Vector3::zeros(); positions.len()],
            ..SupportLoads::default()
        };
        if let Some(g) = &self.gravity {
            let (weight, potential) = g.add_forces(positions, masses, &mut loads.forces);
            loads.weight = weight;
            loads.potential += potential;
        }
        for set in &self.springs {
            let (resultant, potential) =
                set.add_forces(positions, at.translations, &mut loads.forces);
            loads.springs.push(resultant);
            loads.potential += potential;
        }
        for (g, gripper) in self.grippers.iter().enumerate() {
            let (resultant, potential) = match at.released.get(g) {
                Some(true) => (Vector3::zeros(), 0.0),
                _ => gripper
                    .hold
                    .add_forces(positions, at.translations, &mut loads.forces),
            };
            loads.grippers.push(resultant);
            loads.potential += potential;
        }
        loads
    }

    /// `-df/dx` of each node that a spring or gripper holds (gravity's is zero): the 3x3
    /// block the implicit tangent adds on the node's diagonal.
    pub fn stiffness(
        &self,
        positions: &[Vector3<f64>],
        at: SupportsAt,
    ) -> Vec<(usize, Matrix3<f64>)> {
        let mut blocks = Vec::new();
        for set in &self.springs {
            set.add_stiffness(positions, at.translations, &mut blocks);
        }
        for (g, gripper) in self.grippers.iter().enumerate() {
            if !at.released.get(g).copied().unwrap_or(false) {
                gripper
                    .hold
                    .add_stiffness(positions, at.translations, &mut blocks);
            }
        }
        blocks
    }

    /// The largest explicit step (s) the springs and grippers allow on nodes of `masses`:
    /// `2 sqrt(m / k)` of the stiffest node, infinite without them.
    pub fn stable_step(&self, masses: &[f64]) -> f64 {
        let mut stiffness = vec![0.0; masses.len()];
        let grippers = self.grippers.iter().map(|g| &g.hold);
        for set in self.springs.iter().chain(grippers) {
            for node in &set.nodes {
                stiffness[node.node] += set.stiffness;
            }
        }
        stiffness
            .iter()
            .zip(masses)
            .filter(|(k, _)| **k > 0.0)
            .map(|(k, m)| 2.0 * (m / k).sqrt())
            .fold(f64::INFINITY, f64::min)
    }

    /// The grippers that let go after a step that ended at `time` with `loads`: those whose
    /// release time has come, or whose force has reached their release force.
    pub fn release(&self, time: f64, loads: &SupportLoads, released: &mut [bool]) {
        for (g, gripper) in self.grippers.iter().enumerate() {
            let force = loads.grippers.get(g).map_or(0.0, |f| f.norm());
            if gripper.release.due(time, force) {
                released[g] = true;
            }
        }
    }
}

/// Where an anchor carried by tool `carrier` (none: fixed) stands, from where it stood at the
/// start.
pub(crate) fn anchor_now(
    start: &Vector3<f64>,
    carrier: Option<usize>,
    translations: &[Vector3<f64>],
) -> Vector3<f64> {
    match carrier.and_then(|k| translations.get(k)) {
        Some(t) => start + t,
        None => *start,
    }
}
