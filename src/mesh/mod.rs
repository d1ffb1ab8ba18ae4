//! Meshes of the blank: reference node positions, 3-node triangles, named node and element
//! sets, and where a mesh file gives them, reference warp directions per triangle.

pub mod abaqus;
pub mod file;
pub mod gmsh;
pub mod orientation;
pub mod rectangle;

pub use file::{MeshFileError, MeshImport};
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
    /// Named groups of triangles (Abaqus `*ELSET`, Gmsh physical groups).
    pub element_sets: BTreeMap<String, Vec<usize>>,
    /// Reference direction of the warp per triangle, where the mesh file gives one (Abaqus
    /// `*ORIENTATION`); it is projected onto each triangle's plane. `None`: the scenario's ply
    /// angle decides.
    pub warp_directions: Option<Vec<Vector3<f64>>>,
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
    #[error("{kind} set '{name}' refers to {kind} {index}, but the mesh has {count}")]
    SetOutOfRange {
        kind: &'static str,
        name: String,
        index: usize,
        count: usize,
    },
    #[error("{count} warp directions for {triangles} triangles")]
    WarpDirectionCount { count: usize, triangles: usize },
    #[error("triangle {triangle} has a zero or non-finite warp direction")]
    BadWarpDirection { triangle: usize },
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
        check_sets("node", &self.node_sets, self.nodes.len())?;
        check_sets("element", &self.element_sets, self.triangles.len())?;
        if let Some(directions) = &self.warp_directions {
            if directions.len() != self.triangles.len() {
                return Err(MeshError::WarpDirectionCount {
                    count: directions.len(),
                    triangles: self.triangles.len(),
                });
            }
            if let Some(triangle) = directions
                .iter()
                .position(|d| !(d.iter().all(|c| c.is_finite()) && d.norm() > 0.0))
            {
                return Err(MeshError::BadWarpDirection { triangle });
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

/// Every index of every set below `count`.
fn check_sets(
    kind: &'static str,
    sets: &BTreeMap<String, Vec<usize>>,
    count: usize,
) -> Result<(), MeshError> {
    for (name, members) in sets {
        if let Some(&index) = members.iter().find(|&&i| i >= count) {
            return Err(MeshError::SetOutOfRange {
                kind,
                name: name.clone(),
                index,
                count,
            });
        }
    }
    Ok(())
}
