//! Structured mesh of a rectangular blank centred on the origin in the x–y plane.

use super::{Cell, Mesh};
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// How each rectangular cell is meshed: kept whole, or cut into triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DiagonalPattern {
    /// No diagonal: one 4-node quadrilateral per cell, edges along x and y. Free of the
    /// preferred fold lines of the triangles (docs/model.md §4).
    Quad,
    /// One diagonal per cell, all the same way (`/`): cheap, but has a preferred direction.
    Right,
    /// One diagonal per cell, alternating like a chessboard (`/\`, union-jack pattern).
    Alternating,
    /// Both diagonals with a node at the cell centre: four triangles per cell, no preferred
    /// direction, and edges along ±45° (the yarns of a bias test).
    Crossed,
}

/// A `width` (x) by `length` (y) rectangle centred on the origin, `nx` by `ny` cells.
///
/// Node sets: `bottom` (y = -length/2), `top` (y = +length/2), `left` (x = -width/2),
/// `right` (x = +width/2), and `all`.
pub fn rectangle(width: f64, length: f64, nx: usize, ny: usize, pattern: DiagonalPattern) -> Mesh {
    let nx = nx.max(1);
    let ny = ny.max(1);
    let grid = |i: usize, j: usize| j * (nx + 1) + i;
    let (dx, dy) = (width / nx as f64, length / ny as f64);
    let mut nodes: Vec<Vector3<f64>> = (0..=ny)
        .flat_map(|j| (0..=nx).map(move |i| (i, j)))
        .map(|(i, j)| {
            Vector3::new(
                -0.5 * width + i as f64 * dx,
                -0.5 * length + j as f64 * dy,
                0.0,
            )
        })
        .collect();
    let mut cells = Vec::with_capacity(4 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (
                grid(i, j),
                grid(i + 1, j),
                grid(i + 1, j + 1),
                grid(i, j + 1),
            );
            let triangles: Vec<[usize; 3]> = match pattern {
                DiagonalPattern::Quad => {
                    cells.push(Cell::Quad([a, b, c, d]));
                    Vec::new()
                }
                DiagonalPattern::Right => vec![[a, b, c], [a, c, d]],
                DiagonalPattern::Alternating if (i + j) % 2 == 1 => vec![[a, b, d], [b, c, d]],
                DiagonalPattern::Alternating => vec![[a, b, c], [a, c, d]],
                DiagonalPattern::Crossed => {
                    let centre = nodes.len();
                    nodes.push((nodes[a] + nodes[c]) * 0.5);
                    vec![
                        [a, b, centre],
                        [b, c, centre],
                        [c, d, centre],
                        [d, a, centre],
                    ]
                }
            };
            cells.extend(triangles.into_iter().map(Cell::Triangle));
        }
    }
    let row = |j: usize| (0..=nx).map(|i| grid(i, j)).collect::<Vec<_>>();
    let column = |i: usize| (0..=ny).map(|j| grid(i, j)).collect::<Vec<_>>();
    let node_sets = BTreeMap::from([
        ("bottom".to_string(), row(0)),
        ("top".to_string(), row(ny)),
        ("left".to_string(), column(0)),
        ("right".to_string(), column(nx)),
        ("all".to_string(), (0..nodes.len()).collect()),
    ]);
    Mesh {
        nodes,
        cells,
        node_sets,
        element_sets: BTreeMap::new(),
        warp_directions: None,
    }
}

impl DiagonalPattern {
    /// Elements and nodes of a rectangle of `nx` by `ny` cells with this pattern (as `f64`:
    /// for size estimates of meshes that are too large to build).
    pub fn counts(self, nx: f64, ny: f64) -> (f64, f64) {
        let corners = (nx + 1.0) * (ny + 1.0);
        match self {
            DiagonalPattern::Quad => (nx * ny, corners),
            DiagonalPattern::Right | DiagonalPattern::Alternating => (2.0 * nx * ny, corners),
            DiagonalPattern::Crossed => (4.0 * nx * ny, corners + nx * ny),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pattern_tiles_the_rectangle_exactly() {
        for pattern in [
            DiagonalPattern::Quad,
            DiagonalPattern::Right,
            DiagonalPattern::Alternating,
            DiagonalPattern::Crossed,
        ] {
            let mesh = rectangle(150.0, 450.0, 6, 18, pattern);
            mesh.validate().unwrap();
            let total: f64 = (0..mesh.cells.len()).map(|t| mesh.area(t)).sum();
            assert!((total - 150.0 * 450.0).abs() < 1e-8, "{pattern:?}: {total}");
            assert!(
                (mesh.element_size() - 25.0).abs() < 1e-9 || pattern == DiagonalPattern::Crossed
            );
            // counter-clockwise about +z
            for t in &mesh.cells {
                assert!(t.area_vector(&mesh.nodes).z > 0.0, "{pattern:?}");
            }
            let (elements, nodes) = pattern.counts(6.0, 18.0);
            assert_eq!(
                (elements, nodes),
                (mesh.cells.len() as f64, mesh.nodes.len() as f64)
            );
            assert_eq!(mesh.node_set("top").unwrap().len(), 7);
            assert!(mesh
                .node_set("top")
                .unwrap()
                .iter()
                .all(|&n| (mesh.nodes[n].y - 225.0).abs() < 1e-12));
        }
    }

    #[test]
    fn unknown_set_names_the_available_ones() {
        let mesh = rectangle(1.0, 1.0, 1, 1, DiagonalPattern::Right);
        let e = mesh.node_set("clamp").unwrap_err().to_string();
        assert!(e.contains("'clamp'") && e.contains("bottom"), "{e}");
    }
}
