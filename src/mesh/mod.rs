//! Meshes of the blank: reference node positions, 3-node triangles and named node sets.

pub mod rectangle;

pub use rectangle::{rectangle, DiagonalPattern};

use nalgebra::Vector3;
use std::collections::BTreeMap;

/// A triangulated sheet in its reference configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Reference positions (mm).
    pub nodes: Vec<Vector3<f64>>,
    /// Node indices of each triangle, counter-clockwise about the sheet normal.
    pub triangles: Vec<[usize; 3]>,
    /// Named groups of nodes for boundary conditions and reactions.
    pub node_sets: BTreeMap<String, Vec<usize>>,
}

/// What is wrong with a mesh.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("the mesh has no triangles")]
    Empty,
    #[error("triangle {triangle} refers to node {node}, but the mesh has {nodes} nodes")]
    NodeOutOfRange {
        triangle: usize,
        node: usize,
        nodes: usize,
    },
    #[error("triangle {triangle} is degenerate (area {area:e} mm^2)")]
    Degenerate { triangle: usize, area: f64 },
    #[error("node {node} has a non-finite coordinate")]
    NonFinite { node: usize },
    #[error("no node set named '{name}' (the mesh has: {available})")]
    UnknownSet { name: String, available: String },
}

impl Mesh {
    /// Checks indices, coordinates and areas.
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if let Some(node) = self
            .nodes
            .iter()
            .position(|x| !x.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFinite { node });
        }
        for (triangle, t) in self.triangles.iter().enumerate() {
            if let Some(&node) = t.iter().find(|&&n| n >= self.nodes.len()) {
                return Err(MeshError::NodeOutOfRange {
                    triangle,
                    node,
                    nodes: self.nodes.len(),
                });
            }
            let area = self.area(triangle);
            let scale = (self.nodes[t[1]] - self.nodes[t[0]]).norm_squared();
            if area.is_nan() || area <= 1e-12 * scale {
                return Err(MeshError::Degenerate { triangle, area });
            }
        }
        Ok(())
    }

    /// Reference area of triangle `t` (mm^2).
    pub fn area(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangles[t].map(|n| self.nodes[n]);
        0.5 * (b - a).cross(&(c - a)).norm()
    }

    /// Centroid of triangle `t` in the reference configuration.
    pub fn centroid(&self, t: usize) -> Vector3<f64> {
        let [a, b, c] = self.triangles[t].map(|n| self.nodes[n]);
        (a + b + c) / 3.0
    }

    /// The nodes of the set `name`.
    pub fn node_set(&self, name: &str) -> Result<&[usize], MeshError> {
        self.node_sets
            .get(name)
            .map(Vec::as_slice)
            .ok_or_else(|| MeshError::UnknownSet {
                name: name.to_string(),
                available: self
                    .node_sets
                    .keys()
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }
}
