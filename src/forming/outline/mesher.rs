//! The flat blank cut to an outline, meshed as an O-grid of quadrilaterals: a square of
//! cells in the middle and, from each node of the square's edge, a ray out to the outline cut
//! in equal steps, then evened out by Laplacian smoothing of the nodes inside. The blank's edge
//! is then the outline itself (its nodes on it), with no staircase of whole cells to spoil the
//! margin measured against it; it needs an outline that every ray from its centroid crosses
//! once (star-shaped), as a blank around a drawn part is.

use super::polygon::{self, Polygon};
use super::trim::at;
use crate::mesh::{Cell, Mesh};
use nalgebra::{Vector2, Vector3};

/// The inner square's half side, as a fraction of the distance from the centre to the nearest
/// point of the outline: the rays then cross at most about as far as the square is wide.
const SQUARE_FRACTION: f64 = 0.5;

/// A blank meshed to its outline.
#[derive(Clone, Debug)]
pub struct OutlineMesh {
    pub mesh: Mesh,
    /// The nodes on the outline, counter-clockwise: the blank's edge.
    pub edge: Vec<usize>,
}

impl OutlineMesh {
    /// The blank's edge as a polygon of its flat node positions.
    pub fn edge_polygon(&self) -> Polygon {
        self.edge.iter().map(|&n| self.mesh.nodes[n].xy()).collect()
    }
}

/// Meshes the counter-clockwise `outline` with quadrilaterals of about `size` (mm), flat in
/// z = 0. Errors (one line) where the outline is not star-shaped about its centroid.
pub fn mesh_outline(outline: &[Vector2<f64>], size: f64) -> Result<OutlineMesh, String> {
    let centre = polygon::centroid(outline);
    if !polygon::star_shaped_about(outline, &centre) {
        return Err(format!(
            "the outline is not star-shaped about its centroid {}: some ray from there crosses \
             it more than once, and the blank's mesher (an O-grid) needs every ray to cross it \
             once; a smaller --margin, or a trim line without deep notches, gives one",
            at(&centre)
        ));
    }
    let nearest = polygon::boundary_distance(outline, &centre);
    let half = SQUARE_FRACTION * nearest;
    // cells along a side: between the square's own size and the outline's length shared by
    // its four sides, so that neither the middle nor the rim is much coarser than `size`
    let along_square = 2.0 * half / size;
    let along_rim = polygon::perimeter(outline) / (4.0 * size);
    let n = (0.5 * (along_square + along_rim)).round().max(2.0) as usize;
    let ring = square_ring(n, half);
    let exits: Vec<Vector2<f64>> = ring
        .iter()
        .map(|s| {
            let direction = s.normalize();
            let t = polygon::ray_exit(outline, &centre, &direction).unwrap_or(s.norm());
            centre + direction * t
        })
        .collect();
    let mean_reach = ring
        .iter()
        .zip(&exits)
        .map(|(s, q)| (q - (centre + s)).norm())
        .sum::<f64>()
        / ring.len() as f64;
    let layers = (mean_reach / size).round().max(1.0) as usize;
    let mut blank = assemble(n, half, centre, &ring, &exits, layers);
    smooth(&mut blank);
    Ok(blank)
}

/// Laplacian sweeps that move each node inside the blank towards the mean of its neighbours
/// (the edge's stay on the outline).
const SMOOTHING_SWEEPS: usize = 30;

/// Evens out the O-grid's cells: the rays cut in equal steps leave thin cells where the
/// outline comes near the square and long ones where it is far (an elongated outline), and
/// the bending patches of thin cells can be too ill-conditioned to build. Sweeps that would
/// fold or turn a cell are not kept.
fn smooth(blank: &mut OutlineMesh) {
    let mesh = &mut blank.mesh;
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); mesh.nodes.len()];
    for cell in &mesh.cells {
        for (a, b) in cell.edges() {
            neighbours[a].push(b);
            neighbours[b].push(a);
        }
    }
    let mut fixed = vec![false; mesh.nodes.len()];
    for &e in &blank.edge {
        fixed[e] = true;
    }
    for _ in 0..SMOOTHING_SWEEPS {
        let moved: Vec<Vector3<f64>> = (0..mesh.nodes.len())
            .map(|n| {
                if fixed[n] || neighbours[n].is_empty() {
                    return mesh.nodes[n];
                }
                // each edge is listed from both of its cells: the mean is the same
                let sum: Vector3<f64> = neighbours[n].iter().map(|&m| mesh.nodes[m]).sum();
                sum / neighbours[n].len() as f64
            })
            .collect();
        let sound = mesh
            .cells
            .iter()
            .all(|c| c.area_vector(&moved).z > 0.0 && !c.is_folded(&moved));
        if !sound {
            break;
        }
        mesh.nodes = moved;
    }
}

/// The nodes of the square's edge (offsets from the centre), counter-clockwise from the
/// corner (−half, −half), n cells a side.
fn square_ring(n: usize, half: f64) -> Vec<Vector2<f64>> {
    let step = 2.0 * half / n as f64;
    let grid = |i: usize, j: usize| Vector2::new(-half + i as f64 * step, -half + j as f64 * step);
    let mut ring = Vec::with_capacity(4 * n);
    ring.extend((0..n).map(|i| grid(i, 0)));
    ring.extend((0..n).map(|j| grid(n, j)));
    ring.extend((0..n).map(|i| grid(n - i, n)));
    ring.extend((0..n).map(|j| grid(0, n - j)));
    ring
}

/// The square's (n + 1)² nodes and n² cells, then `layers` rings of nodes from the square's
/// edge out to the exits, and the cells between them.
fn assemble(
    n: usize,
    half: f64,
    centre: Vector2<f64>,
    ring: &[Vector2<f64>],
    exits: &[Vector2<f64>],
    layers: usize,
) -> OutlineMesh {
    let step = 2.0 * half / n as f64;
    let at3 = |p: Vector2<f64>| Vector3::new(p.x, p.y, 0.0);
    let grid = |i: usize, j: usize| j * (n + 1) + i;
    let mut nodes: Vec<Vector3<f64>> = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| (i, j)))
        .map(|(i, j)| at3(centre + Vector2::new(-half + i as f64 * step, -half + j as f64 * step)))
        .collect();
    let mut cells = Vec::new();
    for j in 0..n {
        for i in 0..n {
            cells.push(Cell::Quad([
                grid(i, j),
                grid(i + 1, j),
                grid(i + 1, j + 1),
                grid(i, j + 1),
            ]));
        }
    }
    // the square's edge nodes in the ring's order
    let mut rim: Vec<usize> = Vec::with_capacity(4 * n);
    rim.extend((0..n).map(|i| grid(i, 0)));
    rim.extend((0..n).map(|j| grid(n, j)));
    rim.extend((0..n).map(|i| grid(n - i, n)));
    rim.extend((0..n).map(|j| grid(0, n - j)));
    let m = ring.len();
    for layer in 1..=layers {
        let f = layer as f64 / layers as f64;
        let next: Vec<usize> = (0..m)
            .map(|k| {
                let start = centre + ring[k];
                nodes.push(at3(start + (exits[k] - start) * f));
                nodes.len() - 1
            })
            .collect();
        for k in 0..m {
            let k1 = (k + 1) % m;
            // counter-clockwise: out, along the ring, back in, back along it
            cells.push(Cell::Quad([rim[k], next[k], next[k1], rim[k1]]));
        }
        rim = next;
    }
    OutlineMesh {
        mesh: Mesh {
            nodes,
            cells,
            ..Mesh::default()
        },
        edge: rim,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(r: f64, n: usize) -> Polygon {
        (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                Vector2::new(r * t.cos(), r * t.sin())
            })
            .collect()
    }

    #[test]
    fn a_disc_is_meshed_to_its_edge_with_cells_of_about_the_size() {
        let disc = circle(60.0, 360);
        let blank = mesh_outline(&disc, 8.0).unwrap();
        blank.mesh.validate().unwrap();
        let area = blank.mesh.total_area();
        assert!(
            (area - polygon::signed_area(&disc)).abs() < 0.01 * area,
            "{area}"
        );
        for &e in &blank.edge {
            assert!((blank.mesh.nodes[e].norm() - 60.0).abs() < 0.01);
        }
        for t in 0..blank.mesh.cells.len() {
            assert!(
                blank.mesh.cells[t].area_vector(&blank.mesh.nodes).z > 0.0,
                "cell {t} turned"
            );
        }
        let size = blank.mesh.element_size();
        assert!(size > 5.0 && size < 10.0, "{size}");
    }

    #[test]
    fn an_elongated_outline_is_meshed_with_sound_cells() {
        let ellipse: Polygon = circle(1.0, 240)
            .iter()
            .map(|p| Vector2::new(90.0 * p.x, 40.0 * p.y))
            .collect();
        let blank = mesh_outline(&ellipse, 4.0).unwrap();
        let x = &blank.mesh.nodes;
        for c in &blank.mesh.cells {
            assert!(c.area_vector(x).z > 0.0 && !c.is_folded(x));
        }
        // the smoothing evens the cells out: none much thinner than the size asked for
        let smallest = (0..blank.mesh.cells.len())
            .map(|t| blank.mesh.area(t))
            .fold(f64::INFINITY, f64::min);
        assert!(smallest > 0.1 * 16.0, "{smallest}");
    }

    #[test]
    fn an_outline_with_a_deep_notch_is_refused() {
        let notch = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(10.0, 0.0),
            Vector2::new(10.0, 10.0),
            Vector2::new(5.0, 1.0),
            Vector2::new(0.0, 10.0),
        ];
        assert!(mesh_outline(&notch, 1.0)
            .unwrap_err()
            .contains("star-shaped"));
    }
}
