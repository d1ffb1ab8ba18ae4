//! From the formed part back to the flat blank: through the kinematic drape's net (each cell a
//! bilinear patch between its flat square and its formed image) for the first guess, and
//! through a forming run's formed mesh (each cell cut in triangles, barycentric coordinates)
//! for the iterations. A trim point is found in space, or in plan (seen from above, +z) for a
//! trim line given by its plan view.

use super::polygon::Polygon;
use crate::drape::DrapeResult;
use crate::forming::drape_preview::Generators;
use crate::mesh::Cell;
use nalgebra::{Matrix2, Vector2, Vector3};

/// Point of the bilinear patch of corners `c` (at (u, v) = (0, 0), (1, 0), (1, 1), (0, 1)).
pub fn bilinear(c: &[Vector3<f64>; 4], u: f64, v: f64) -> Vector3<f64> {
    c[0] * ((1.0 - u) * (1.0 - v))
        + c[1] * (u * (1.0 - v))
        + c[2] * (u * v)
        + c[3] * ((1.0 - u) * v)
}

/// The parameters (u, v) of `p` on the bilinear patch of corners `c`: the exact inverse where
/// `p` lies on the patch (always so in plan, z = 0), otherwise those of the patch's point
/// nearest `p` (Gauss–Newton on the squared distance, from the middle). Unbounded: (u, v)
/// outside [0, 1]² places `p` beyond the cell.
pub fn invert_bilinear(c: &[Vector3<f64>; 4], p: &Vector3<f64>) -> (f64, f64) {
    let (mut u, mut v) = (0.5, 0.5);
    for _ in 0..30 {
        let r = p - bilinear(c, u, v);
        let du = (c[1] - c[0]) * (1.0 - v) + (c[2] - c[3]) * v;
        let dv = (c[3] - c[0]) * (1.0 - u) + (c[2] - c[1]) * u;
        let gram = Matrix2::new(du.dot(&du), du.dot(&dv), du.dot(&dv), dv.dot(&dv));
        let Some(step) = gram
            .try_inverse()
            .map(|g| g * Vector2::new(du.dot(&r), dv.dot(&r)))
        else {
            break; // a degenerate cell: keep the guess
        };
        u += step.x;
        v += step.y;
        if step.norm() < 1e-12 {
            break;
        }
    }
    (u, v)
}

/// Flat position (mm, in plan) of node (i, j) of the net: the start point plus i cells along
/// the warp and j along the weft (+90°), as the fabric lay before draping.
pub fn flat_node(cell: f64, g: &Generators, i: f64, j: f64) -> Vector2<f64> {
    let a = g.warp_angle.to_radians();
    let warp = Vector2::new(a.cos(), a.sin());
    let weft = Vector2::new(-a.sin(), a.cos());
    Vector2::new(g.start.0, g.start.1) + warp * (i * cell) + weft * (j * cell)
}

/// The trim points `points` (in the net's frame) mapped to the flat blank through the draped
/// net `net` laid from `g`: inside the net, the cell whose formed image holds the point, its
/// bilinear map inverted; beyond the net (the drape covers only the punch's cap, not the wall
/// and the flange), the nearest node in plan, the rest of the way taken as flat, neither drawn
/// in nor sheared.
pub fn flat_from_drape(
    net: &DrapeResult,
    g: &Generators,
    points: &[Vector3<f64>],
    in_plan: bool,
) -> Polygon {
    let cells = net_cells(net);
    points
        .iter()
        .map(|p| {
            let found = if in_plan {
                cell_in_plan(&cells, p)
            } else {
                cell_in_space(&cells, p, net.cell())
            };
            match found {
                Some((i, j, u, v)) => flat_node(net.cell(), g, i as f64 + u, j as f64 + v),
                None => beyond_net(net, g, p),
            }
        })
        .collect()
}

/// Every complete cell of the net: its first corner's (i, j) and its four formed corners.
fn net_cells(net: &DrapeResult) -> Vec<(i64, i64, [Vector3<f64>; 4])> {
    let n = net.max_cells() as i64;
    let node = |i, j| net.node(i, j).map(Vector3::from);
    (-n..n)
        .flat_map(|i| (-n..n).map(move |j| (i, j)))
        .filter_map(|(i, j)| {
            Some((
                i,
                j,
                [
                    node(i, j)?,
                    node(i + 1, j)?,
                    node(i + 1, j + 1)?,
                    node(i, j + 1)?,
                ],
            ))
        })
        .collect()
}

/// The cell over `p` in plan, the highest where several are: (i, j, u, v).
fn cell_in_plan(
    cells: &[(i64, i64, [Vector3<f64>; 4])],
    p: &Vector3<f64>,
) -> Option<(i64, i64, f64, f64)> {
    let flat = |c: &Vector3<f64>| Vector3::new(c.x, c.y, 0.0);
    let q = flat(p);
    let inside = |t: f64| (-1e-9..=1.0 + 1e-9).contains(&t);
    cells
        .iter()
        .filter(|(_, _, c)| {
            let (lo, hi) = plan_bounds(c);
            q.x >= lo.x && q.x <= hi.x && q.y >= lo.y && q.y <= hi.y
        })
        .filter_map(|(i, j, c)| {
            let (u, v) = invert_bilinear(&c.map(|x| flat(&x)), &q);
            (inside(u) && inside(v)).then(|| (*i, *j, u, v, bilinear(c, u, v).z))
        })
        .max_by(|a, b| a.4.total_cmp(&b.4))
        .map(|(i, j, u, v, _)| (i, j, u, v))
}

/// The cell nearest `p` in space, if within half a cell of it: (i, j, u, v).
fn cell_in_space(
    cells: &[(i64, i64, [Vector3<f64>; 4])],
    p: &Vector3<f64>,
    size: f64,
) -> Option<(i64, i64, f64, f64)> {
    cells
        .iter()
        .filter(|(_, _, c)| (c.iter().sum::<Vector3<f64>>() / 4.0 - p).norm() < 2.0 * size)
        .map(|(i, j, c)| {
            let (u, v) = invert_bilinear(c, p);
            let foot = bilinear(c, u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
            (*i, *j, u, v, (foot - p).norm())
        })
        .min_by(|a, b| a.4.total_cmp(&b.4))
        .filter(|m| m.4 <= 0.5 * size)
        .map(|(i, j, u, v, _)| (i, j, u, v))
}

/// A point the net does not reach: the nearest placed node in plan, then straight on in plan.
fn beyond_net(net: &DrapeResult, g: &Generators, p: &Vector3<f64>) -> Vector2<f64> {
    let n = net.max_cells() as i64;
    let nearest = (-n..=n)
        .flat_map(|i| (-n..=n).map(move |j| (i, j)))
        .filter_map(|(i, j)| net.node(i, j).map(|x| (i, j, Vector3::from(x))))
        .min_by(|a, b| (a.2 - p).xy().norm().total_cmp(&(b.2 - p).xy().norm()));
    match nearest {
        Some((i, j, x)) => flat_node(net.cell(), g, i as f64, j as f64) + (p - x).xy(),
        None => p.xy(),
    }
}

fn plan_bounds(c: &[Vector3<f64>]) -> (Vector2<f64>, Vector2<f64>) {
    c.iter().fold(
        (
            Vector2::repeat(f64::INFINITY),
            Vector2::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), x| (lo.inf(&x.xy()), hi.sup(&x.xy())),
    )
}

/// The cells cut in triangles (a quadrilateral a b c d into a b c and a c d).
pub fn triangles(cells: &[Cell]) -> Vec<[usize; 3]> {
    cells
        .iter()
        .flat_map(|c| match *c {
            Cell::Triangle(t) => vec![t],
            Cell::Quad([a, b, c, d]) => vec![[a, b, c], [a, c, d]],
        })
        .collect()
}

/// The trim points mapped to the flat blank through a formed mesh: `reference` the flat
/// positions of its nodes, `formed` their formed ones. Each point goes to the triangle
/// holding it in plan (the highest where several do), or in space to the nearest triangle;
/// its barycentric coordinates there (of its foot on the triangle's plane) combine the
/// corners' flat positions. A point off the formed blank takes the nearest triangle's
/// coordinates unbounded: it maps outside the flat blank, by about as far as it is off the
/// part.
pub fn flat_from_formed(
    reference: &[Vector3<f64>],
    formed: &[Vector3<f64>],
    cells: &[Cell],
    points: &[Vector3<f64>],
    in_plan: bool,
) -> Polygon {
    let triangles = triangles(cells);
    points
        .iter()
        .map(|p| {
            let (t, w) = if in_plan {
                in_plan_triangle(formed, &triangles, p)
            } else {
                nearest_triangle(formed, &triangles, p)
            };
            let [a, b, c] = triangles[t];
            (reference[a] * w[0] + reference[b] * w[1] + reference[c] * w[2]).xy()
        })
        .collect()
}

/// Barycentric coordinates of `p` in the plan triangle `a b c` (unbounded); `None` for a
/// triangle seen edge-on (a vertical wall), which holds no point in plan.
fn barycentric_2d(
    a: &Vector2<f64>,
    b: &Vector2<f64>,
    c: &Vector2<f64>,
    p: &Vector2<f64>,
) -> Option<[f64; 3]> {
    let area = (b - a).perp(&(c - a));
    let scale = (b - a).norm_squared().max((c - a).norm_squared());
    if area.abs() <= 1e-9 * scale || scale == 0.0 {
        return None;
    }
    let wb = (p - a).perp(&(c - a)) / area;
    let wc = (b - a).perp(&(p - a)) / area;
    Some([1.0 - wb - wc, wb, wc])
}

/// The triangle over `p` in plan (the highest at `p` where several are), or the nearest one in
/// plan; and `p`'s barycentric coordinates in it.
fn in_plan_triangle(
    x: &[Vector3<f64>],
    triangles: &[[usize; 3]],
    p: &Vector3<f64>,
) -> (usize, [f64; 3]) {
    let q = p.xy();
    let mut over: Option<(usize, [f64; 3], f64)> = None;
    let mut nearest: Option<(usize, [f64; 3], f64)> = None;
    for (t, &[a, b, c]) in triangles.iter().enumerate() {
        let (pa, pb, pc) = (x[a].xy(), x[b].xy(), x[c].xy());
        let Some(w) = barycentric_2d(&pa, &pb, &pc, &q) else {
            continue;
        };
        if w.iter().all(|&wi| wi >= -1e-9) {
            let z = w[0] * x[a].z + w[1] * x[b].z + w[2] * x[c].z;
            if over.is_none_or(|o| z > o.2) {
                over = Some((t, w, z));
            }
        } else if over.is_none() {
            let d = [(pa, pb), (pb, pc), (pc, pa)]
                .iter()
                .map(|(s, e)| super::polygon::segment_distance(&q, s, e))
                .fold(f64::INFINITY, f64::min);
            if nearest.is_none_or(|n| d < n.2) {
                nearest = Some((t, w, d));
            }
        }
    }
    over.or(nearest)
        .map_or((0, [1.0, 0.0, 0.0]), |(t, w, _)| (t, w))
}

/// The triangle nearest `p` in space and the barycentric coordinates of `p`'s foot on its
/// plane.
fn nearest_triangle(
    x: &[Vector3<f64>],
    triangles: &[[usize; 3]],
    p: &Vector3<f64>,
) -> (usize, [f64; 3]) {
    let mut best = (0, [1.0, 0.0, 0.0], f64::INFINITY);
    for (t, &[a, b, c]) in triangles.iter().enumerate() {
        let (e1, e2, r) = (x[b] - x[a], x[c] - x[a], p - x[a]);
        let gram = Matrix2::new(e1.dot(&e1), e1.dot(&e2), e1.dot(&e2), e2.dot(&e2));
        let Some(st) = gram
            .try_inverse()
            .map(|g| g * Vector2::new(e1.dot(&r), e2.dot(&r)))
        else {
            continue;
        };
        let w = [1.0 - st.x - st.y, st.x, st.y];
        let d = if w.iter().all(|&wi| wi >= 0.0) {
            (x[a] + e1 * st.x + e2 * st.y - p).norm()
        } else {
            [(a, b), (b, c), (c, a)]
                .iter()
                .map(|&(s, e)| segment_distance_3d(p, &x[s], &x[e]))
                .fold(f64::INFINITY, f64::min)
        };
        if d < best.2 {
            best = (t, w, d);
        }
    }
    (best.0, best.1)
}

fn segment_distance_3d(q: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let t = if ab.norm_squared() > 0.0 {
        ((q - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (q - (a + ab * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn patch() -> [Vector3<f64>; 4] {
        [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(10.0, 1.0, 2.0),
            Vector3::new(12.0, 9.0, 3.0),
            Vector3::new(-1.0, 11.0, 1.0),
        ]
    }

    #[test]
    fn the_bilinear_map_inverts_in_space_and_in_plan() {
        let c = patch();
        for (u, v) in [(0.3, 0.7), (0.0, 1.0), (0.9, 0.05), (1.2, -0.1)] {
            let (a, b) = invert_bilinear(&c, &bilinear(&c, u, v));
            assert!(
                (a - u).abs() < 1e-10 && (b - v).abs() < 1e-10,
                "{u},{v}: {a},{b}"
            );
            let plan = c.map(|x| Vector3::new(x.x, x.y, 0.0));
            let (a, b) = invert_bilinear(&plan, &bilinear(&plan, u, v));
            assert!((a - u).abs() < 1e-10 && (b - v).abs() < 1e-10);
        }
        // a point off the patch goes to its foot: along the normal of a flat patch
        let flat = patch().map(|x| Vector3::new(x.x, x.y, 0.0));
        let p = bilinear(&flat, 0.4, 0.6) + Vector3::new(0.0, 0.0, 5.0);
        let (a, b) = invert_bilinear(&flat, &p);
        assert!((a - 0.4).abs() < 1e-10 && (b - 0.6).abs() < 1e-10);
    }

    #[test]
    fn a_formed_square_maps_back_through_its_triangles() {
        // a unit square turned up 90° about x = 1 (an L-shaped fold): the points on the
        // standing part map to the flat strip beyond x = 1
        let reference = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(2.0, 1.0, 0.0),
        ];
        let mut formed = reference.clone();
        formed[2] = Vector3::new(1.0, 0.0, 1.0);
        formed[5] = Vector3::new(1.0, 1.0, 1.0);
        let cells = [Cell::Quad([0, 1, 4, 3]), Cell::Quad([1, 2, 5, 4])];
        let points = [Vector3::new(1.0, 0.5, 0.25), Vector3::new(0.5, 0.5, 0.0)];
        let flat = flat_from_formed(&reference, &formed, &cells, &points, false);
        assert!(
            (flat[0] - Vector2::new(1.25, 0.5)).norm() < 1e-12,
            "{}",
            flat[0]
        );
        assert!((flat[1] - Vector2::new(0.5, 0.5)).norm() < 1e-12);
        // in plan, off the part by 0.5 mm: outside the flat blank by as much
        let off = [Vector3::new(-0.5, 0.5, 0.0)];
        let flat = flat_from_formed(&reference, &formed, &cells, &off, true);
        assert!((flat[0] - Vector2::new(-0.5, 0.5)).norm() < 1e-12);
    }
}
