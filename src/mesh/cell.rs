//! One cell of the sheet: a 3-node triangle or a 4-node quadrilateral.

use nalgebra::Vector3;

/// The corners of a cell, counter-clockwise about the sheet normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cell {
    Triangle([usize; 3]),
    /// Four corners in order around the cell (an Abaqus S4 / Gmsh quadrangle).
    Quad([usize; 4]),
}

impl Cell {
    /// The corner nodes, in order.
    pub fn nodes(&self) -> &[usize] {
        match self {
            Cell::Triangle(n) => n,
            Cell::Quad(n) => n,
        }
    }

    pub fn is_quad(&self) -> bool {
        matches!(self, Cell::Quad(_))
    }

    /// The same cell on renumbered nodes.
    pub fn map(&self, mut f: impl FnMut(usize) -> usize) -> Cell {
        match *self {
            Cell::Triangle(n) => Cell::Triangle(n.map(&mut f)),
            Cell::Quad(n) => Cell::Quad(n.map(&mut f)),
        }
    }

    /// The same cell numbered the other way round (its normal reversed), from the same first
    /// corner.
    pub fn reversed(&self) -> Cell {
        match *self {
            Cell::Triangle([a, b, c]) => Cell::Triangle([a, c, b]),
            Cell::Quad([a, b, c, d]) => Cell::Quad([a, d, c, b]),
        }
    }

    /// The positions of the corners in `x`.
    pub fn positions(&self, x: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        self.nodes().iter().map(|&n| x[n]).collect()
    }

    /// The edges `(a, b)` in order around the cell.
    pub fn edges(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let n = self.nodes();
        (0..n.len()).map(move |k| (n[k], n[(k + 1) % n.len()]))
    }

    /// Area vector: the normal times the area, `(b - a) x (c - a) / 2` for a triangle and
    /// `(c - a) x (d - b) / 2` (the diagonals) for a quadrilateral, whose area it is when the
    /// corners lie in a plane and the projected area otherwise.
    pub fn area_vector(&self, x: &[Vector3<f64>]) -> Vector3<f64> {
        match *self {
            Cell::Triangle([a, b, c]) => 0.5 * (x[b] - x[a]).cross(&(x[c] - x[a])),
            Cell::Quad([a, b, c, d]) => 0.5 * (x[c] - x[a]).cross(&(x[d] - x[b])),
        }
    }

    pub fn area(&self, x: &[Vector3<f64>]) -> f64 {
        self.area_vector(x).norm()
    }

    /// Mean of the corners.
    pub fn centroid(&self, x: &[Vector3<f64>]) -> Vector3<f64> {
        let n = self.nodes();
        n.iter().map(|&k| x[k]).sum::<Vector3<f64>>() / n.len() as f64
    }

    /// A quadrilateral that is not convex (a corner turns against the others, or the cell
    /// crosses itself); never a triangle.
    pub fn is_folded(&self, x: &[Vector3<f64>]) -> bool {
        let Cell::Quad(q) = *self else {
            return false;
        };
        let normal = self.area_vector(x);
        (0..4).any(|k| {
            let (prev, at, next) = (x[q[(k + 3) % 4]], x[q[k]], x[q[(k + 1) % 4]]);
            (next - at).cross(&(prev - at)).dot(&normal) <= 0.0
        })
    }

    /// The two triangles of a quadrilateral cut along its diagonal from the first corner (the
    /// cell itself for a triangle): for readers and writers that know triangles only.
    pub fn triangles(&self) -> Vec<[usize; 3]> {
        match *self {
            Cell::Triangle(t) => vec![t],
            Cell::Quad([a, b, c, d]) => vec![[a, b, c], [a, c, d]],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<Vector3<f64>> {
        vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(2.0, 1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ]
    }

    #[test]
    fn a_quadrilateral_has_the_area_of_its_two_triangles() {
        let x = square();
        let q = Cell::Quad([0, 1, 2, 3]);
        let sum: f64 = q
            .triangles()
            .iter()
            .map(|&t| Cell::Triangle(t).area(&x))
            .sum();
        assert!((q.area(&x) - 2.0).abs() < 1e-14 && (sum - 2.0).abs() < 1e-14);
        assert!(q.area_vector(&x).z > 0.0, "counter-clockwise about +z");
        assert_eq!(q.reversed().area_vector(&x), -q.area_vector(&x));
        assert_eq!(q.reversed(), Cell::Quad([0, 3, 2, 1]));
        assert_eq!(
            Cell::Triangle([0, 1, 2]).reversed(),
            Cell::Triangle([0, 2, 1])
        );
        assert_eq!(q.centroid(&x), Vector3::new(1.0, 0.5, 0.0));
        assert_eq!(
            q.edges().collect::<Vec<_>>(),
            [(0, 1), (1, 2), (2, 3), (3, 0)]
        );
    }

    #[test]
    fn a_non_convex_or_crossed_quadrilateral_is_folded() {
        let mut x = square();
        assert!(!Cell::Quad([0, 1, 2, 3]).is_folded(&x));
        assert!(Cell::Quad([0, 2, 1, 3]).is_folded(&x), "crossed");
        x[2] = Vector3::new(0.5, 0.4, 0.0);
        assert!(Cell::Quad([0, 1, 2, 3]).is_folded(&x), "re-entrant corner");
        assert!(!Cell::Triangle([0, 1, 2]).is_folded(&x));
    }
}
