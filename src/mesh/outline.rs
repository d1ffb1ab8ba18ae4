//! Where a flat sheet lies seen along z: whether a point of the x-y plane is over one of its
//! cells, looked up in a uniform grid of the cells' bounding boxes.

use super::Mesh;
use nalgebra::Vector2;
use std::collections::HashMap;

/// A mesh's cells projected on the x-y plane.
#[derive(Clone, Debug)]
pub struct Outline {
    /// Each cell's corners in order.
    cells: Vec<Vec<Vector2<f64>>>,
    /// Cells by the grid squares their bounding boxes touch.
    grid: HashMap<(i64, i64), Vec<usize>>,
    /// The grid's square (mm) and the tolerance of the edges (mm).
    square: f64,
    tolerance: f64,
}

impl Outline {
    /// The outline of `mesh`'s cells seen along z.
    pub fn of(mesh: &Mesh) -> Self {
        let cells: Vec<Vec<Vector2<f64>>> = mesh
            .cells
            .iter()
            .map(|c| c.nodes().iter().map(|&n| mesh.nodes[n].xy()).collect())
            .collect();
        let square = mesh.element_size().max(f64::MIN_POSITIVE);
        let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for (c, corners) in cells.iter().enumerate() {
            let (low, high) = bounds(corners);
            let (i0, j0) = Self::square_of(square, &low);
            let (i1, j1) = Self::square_of(square, &high);
            for i in i0..=i1 {
                for j in j0..=j1 {
                    grid.entry((i, j)).or_default().push(c);
                }
            }
        }
        Self {
            cells,
            grid,
            square,
            tolerance: 1e-6 * square,
        }
    }

    fn square_of(square: f64, p: &Vector2<f64>) -> (i64, i64) {
        ((p.x / square).floor() as i64, (p.y / square).floor() as i64)
    }

    /// Whether `p` lies over a cell, its edges included.
    pub fn contains(&self, p: &Vector2<f64>) -> bool {
        let key = Self::square_of(self.square, p);
        self.grid
            .get(&key)
            .is_some_and(|cells| cells.iter().any(|&c| self.in_cell(c, p)))
    }

    /// `p` inside the convex cell `c` (either winding), within the tolerance.
    fn in_cell(&self, c: usize, p: &Vector2<f64>) -> bool {
        let corners = &self.cells[c];
        let sides = corners.iter().zip(corners.iter().cycle().skip(1));
        let (mut left, mut right) = (true, true);
        for (a, b) in sides {
            let edge = b - a;
            let length = edge.norm().max(f64::MIN_POSITIVE);
            let distance = (edge.x * (p.y - a.y) - edge.y * (p.x - a.x)) / length;
            left &= distance >= -self.tolerance;
            right &= distance <= self.tolerance;
        }
        left || right
    }
}

fn bounds(points: &[Vector2<f64>]) -> (Vector2<f64>, Vector2<f64>) {
    points.iter().fold(
        (
            Vector2::repeat(f64::INFINITY),
            Vector2::repeat(f64::NEG_INFINITY),
        ),
        |(low, high), p| (low.inf(p), high.sup(p)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{rectangle, DiagonalPattern};

    /// A 40 x 20 mm rectangle contains its inside and its edges, not what lies beyond them,
    /// on quadrilaterals and on triangles.
    #[test]
    fn a_rectangle_contains_its_inside_and_edges_only() {
        for pattern in [DiagonalPattern::Quad, DiagonalPattern::Crossed] {
            let outline = Outline::of(&rectangle(40.0, 20.0, 8, 4, pattern));
            for (x, y, inside) in [
                (0.0, 0.0, true),
                (19.9, 9.9, true),
                (20.0, 10.0, true),
                (-20.0, 3.3, true),
                (20.01, 0.0, false),
                (0.0, -10.01, false),
                (25.0, 25.0, false),
            ] {
                assert_eq!(
                    outline.contains(&Vector2::new(x, y)),
                    inside,
                    "{pattern:?} ({x}, {y})"
                );
            }
        }
    }
}
