//! Meshes of the blank: reference node positions, cells (3-node triangles and 4-node
//! quadrilaterals), named node and element sets, and where a mesh file gives them, reference
//! warp directions per cell.

pub mod abaqus;
pub mod cell;
pub mod conformity;
pub mod file;
pub mod gmsh;
pub mod orientation;
pub mod outline;
pub mod rectangle;

pub use cell::Cell;

pub use file::{read_mesh_file, At, MeshFileError, MeshImport, Origin, Place};
pub use rectangle::{rectangle, DiagonalPattern};

use nalgebra::Vector3;
use std::collections::BTreeMap;

/// A meshed sheet in its reference configuration.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Reference positions (mm).
    pub nodes: Vec<Vector3<f64>>,
    /// The cells (triangles and quadrilaterals), corners counter-clockwise about the sheet
    /// normal.
    pub cells: Vec<Cell>,
    /// Named groups of nodes for boundary conditions and reactions.
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Named groups of cells (Abaqus `*ELSET`, Gmsh physical groups).
    pub element_sets: BTreeMap<String, Vec<usize>>,
    /// Reference direction of the warp per cell, where the mesh file gives one (Abaqus
    /// `*ORIENTATION`); it is projected onto each cell's plane. `None`: the scenario's ply
    /// angle decides.
    pub warp_directions: Option<Vec<Vector3<f64>>>,
}

/// What is wrong with a folded quadrilateral, after "element <label>" (the readers name the
/// file's label).
pub const FOLDED: &str = "is a quadrilateral that is not convex (a corner turns against the \
    others, two edges cross or two corners coincide: check its nodes and their order)";

/// What is wrong with a mesh.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("the mesh has no cells")]
    Empty,
    #[error("element {triangle} refers to node {node}, but the mesh has {nodes} nodes")]
    NodeOutOfRange {
        triangle: usize,
        node: usize,
        nodes: usize,
    },
    #[error("element {triangle} is degenerate (area {} mm^2)", six_digits(*area))]
    Degenerate { triangle: usize, area: f64 },
    /// A quadrilateral that is not convex ([`Cell::is_folded`]).
    #[error("element {element} {FOLDED}")]
    Folded { element: usize },
    #[error("node {node} has a non-finite coordinate")]
    NonFinite { node: usize },
    #[error("no set named '{name}' (the mesh has: {available})")]
    UnknownSet { name: String, available: String },
    #[error("{kind} set '{name}' refers to {kind} {index}, but the mesh has {count}")]
    SetOutOfRange {
        kind: &'static str,
        name: String,
        index: usize,
        count: usize,
    },
    #[error("{count} warp directions for {triangles} elements")]
    WarpDirectionCount { count: usize, triangles: usize },
    #[error("element {triangle} has a zero or non-finite warp direction")]
    BadWarpDirection { triangle: usize },
}

impl Mesh {
    /// Adds `other`'s nodes and cells after this mesh's (its node and cell numbers shifted by
    /// this mesh's counts), its sets under `prefix` + their names. Per-cell warp directions stay
    /// where both meshes have them or neither does; where only one has them, the cells of the
    /// other take none and the mesh keeps none (the caller projects its own direction first).
    pub fn append(&mut self, other: Mesh, prefix: &str) {
        let (nodes, cells) = (self.nodes.len(), self.cells.len());
        self.warp_directions = match (self.warp_directions.take(), other.warp_directions) {
            (Some(mut mine), Some(theirs)) => {
                mine.extend(theirs);
                Some(mine)
            }
            (None, Some(theirs)) if cells == 0 => Some(theirs),
            _ => None,
        };
        self.nodes.extend(other.nodes);
        self.cells
            .extend(other.cells.iter().map(|c| c.map(|n| n + nodes)));
        for (name, set) in other.node_sets {
            let shifted = set.into_iter().map(|n| n + nodes).collect();
            self.node_sets.insert(format!("{prefix}{name}"), shifted);
        }
        for (name, set) in other.element_sets {
            let shifted = set.into_iter().map(|c| c + cells).collect();
            self.element_sets.insert(format!("{prefix}{name}"), shifted);
        }
    }

    /// Checks indices, coordinates and areas.
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.cells.is_empty() {
            return Err(MeshError::Empty);
        }
        if let Some(node) = self
            .nodes
            .iter()
            .position(|x| !x.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFinite { node });
        }
        for (triangle, t) in self.cells.iter().enumerate() {
            if let Some(&node) = t.nodes().iter().find(|&&n| n >= self.nodes.len()) {
                return Err(MeshError::NodeOutOfRange {
                    triangle,
                    node,
                    nodes: self.nodes.len(),
                });
            }
            let area = self.area(triangle);
            let scale = (self.nodes[t.nodes()[1]] - self.nodes[t.nodes()[0]]).norm_squared();
            if area.is_nan() || area <= 1e-12 * scale {
                return Err(MeshError::Degenerate { triangle, area });
            }
            if t.is_folded(&self.nodes) {
                return Err(MeshError::Folded { element: triangle });
            }
        }
        check_sets("node", &self.node_sets, self.nodes.len())?;
        check_sets("element", &self.element_sets, self.cells.len())?;
        if let Some(directions) = &self.warp_directions {
            if directions.len() != self.cells.len() {
                return Err(MeshError::WarpDirectionCount {
                    count: directions.len(),
                    triangles: self.cells.len(),
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

    /// Reference area of cell `t` (mm^2).
    pub fn area(&self, t: usize) -> f64 {
        self.cells[t].area(&self.nodes)
    }

    /// Centroid of cell `t` in the reference configuration.
    pub fn centroid(&self, t: usize) -> Vector3<f64> {
        self.cells[t].centroid(&self.nodes)
    }

    /// Whether any cell is a quadrilateral.
    pub fn has_quads(&self) -> bool {
        self.cells.iter().any(Cell::is_quad)
    }

    /// Total reference area (mm^2).
    pub fn total_area(&self) -> f64 {
        (0..self.cells.len()).map(|t| self.area(t)).sum()
    }

    /// Element size of a mesh made elsewhere (mm): the mean over the cells of the side of the
    /// square cell they make, `sqrt(A)` for a quadrilateral, `sqrt(2 A)` for a triangle (two of
    /// them make the square: the rectangle's `element_size` for every pattern but crossed;
    /// 0.93 of the side of an equilateral triangle).
    pub fn element_size(&self) -> f64 {
        let sum: f64 = (0..self.cells.len())
            .map(|t| {
                let triangles_per_square = if self.cells[t].is_quad() { 1.0 } else { 2.0 };
                (triangles_per_square * self.area(t)).sqrt()
            })
            .sum();
        sum / self.cells.len().max(1) as f64
    }

    /// The cells of the element set `name`.
    pub fn element_set(&self, name: &str) -> Result<&[usize], MeshError> {
        self.element_sets
            .get(name)
            .map(Vec::as_slice)
            .ok_or_else(|| MeshError::UnknownSet {
                name: name.to_string(),
                available: self.set_names(),
            })
    }

    /// The nodes of the cells of the element set `name`, in increasing order.
    pub fn nodes_of_element_set(&self, name: &str) -> Result<Vec<usize>, MeshError> {
        let mut nodes: Vec<usize> = self
            .element_set(name)?
            .iter()
            .flat_map(|&t| self.cells[t].nodes().to_vec())
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        Ok(nodes)
    }

    /// The mesh of the element set `name` alone: its cells and their nodes, renumbered in
    /// order, with the sets and warp directions restricted to them. Also returns, for each
    /// cell kept, its index in `self`.
    pub fn restricted_to(&self, name: &str) -> Result<(Mesh, Vec<usize>), MeshError> {
        let kept = self.element_set(name)?.to_vec();
        let mut new_node = vec![None; self.nodes.len()];
        let mut nodes = Vec::new();
        let cells: Vec<Cell> = kept
            .iter()
            .map(|&t| {
                self.cells[t].map(|n| {
                    *new_node[n].get_or_insert_with(|| {
                        nodes.push(self.nodes[n]);
                        nodes.len() - 1
                    })
                })
            })
            .collect();
        let mut new_triangle = vec![None; self.cells.len()];
        for (i, &t) in kept.iter().enumerate() {
            new_triangle[t] = Some(i);
        }
        let renumber = |members: &[usize], map: &[Option<usize>]| -> Vec<usize> {
            members.iter().filter_map(|&m| map[m]).collect()
        };
        let node_sets = self
            .node_sets
            .iter()
            .map(|(k, v)| (k.clone(), renumber(v, &new_node)))
            .filter(|(_, v)| !v.is_empty())
            .collect();
        let element_sets = self
            .element_sets
            .iter()
            .map(|(k, v)| (k.clone(), renumber(v, &new_triangle)))
            .filter(|(_, v)| !v.is_empty())
            .collect();
        let warp_directions = self
            .warp_directions
            .as_ref()
            .map(|d| kept.iter().map(|&t| d[t]).collect());
        let mesh = Mesh {
            nodes,
            cells,
            node_sets,
            element_sets,
            warp_directions,
        };
        Ok((mesh, kept))
    }

    fn set_names(&self) -> String {
        self.node_sets
            .keys()
            .chain(self.element_sets.keys())
            .cloned()
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The nodes of the set `name`.
    pub fn node_set(&self, name: &str) -> Result<&[usize], MeshError> {
        self.node_sets
            .get(name)
            .map(Vec::as_slice)
            .ok_or_else(|| MeshError::UnknownSet {
                name: name.to_string(),
                available: self.set_names(),
            })
    }
}

/// `v` to 6 significant digits, for messages: `0.3`, `1e200`, `1.23457e-7`.
fn six_digits(v: f64) -> String {
    let rounded: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    if rounded == 0.0 || (1e-4..1e6).contains(&rounded.abs()) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn element_size_of_single_diagonal_cells_is_the_cell_side() {
        let mesh = rectangle(160.0, 80.0, 16, 8, DiagonalPattern::Right);
        assert!((mesh.element_size() - 10.0).abs() < 1e-12);
        assert!((mesh.total_area() - 160.0 * 80.0).abs() < 1e-9);
    }

    #[test]
    fn a_mesh_restricted_to_an_element_set_keeps_its_nodes_sets_and_directions() {
        let mut mesh = rectangle(2.0, 1.0, 2, 1, DiagonalPattern::Right);
        mesh.element_sets.insert("right".into(), vec![2, 3]);
        mesh.warp_directions = Some((0..4).map(|t| Vector3::new(1.0, t as f64, 0.0)).collect());
        let (sub, kept) = mesh.restricted_to("right").unwrap();
        sub.validate().unwrap();
        assert_eq!(kept, vec![2, 3]);
        assert_eq!(sub.cells.len(), 2);
        assert_eq!(sub.nodes.len(), 4);
        for (t, &old) in kept.iter().enumerate() {
            let a = sub.cells[t].positions(&sub.nodes);
            let b = mesh.cells[old].positions(&mesh.nodes);
            assert_eq!(a, b);
        }
        assert_eq!(sub.warp_directions.unwrap()[1], Vector3::new(1.0, 3.0, 0.0));
        assert_eq!(sub.node_sets["right"].len(), 2);
        assert!(!sub.node_sets.contains_key("left"));
        assert_eq!(sub.element_sets["right"], vec![0, 1]);
        assert_eq!(
            mesh.nodes_of_element_set("right").unwrap(),
            vec![1, 2, 4, 5]
        );
        let e = mesh.restricted_to("nothing").unwrap_err().to_string();
        assert!(
            e.contains("no set named 'nothing'") && e.contains("right"),
            "{e}"
        );
    }
}
